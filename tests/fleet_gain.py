"""Measures the fleet pipeline's in-band gain: for each track seed, a synthetic fleet (the test's
recipe: 1 km, 15-25 m/s, Kalker 100 and 75 %) is estimated and band-passed as the pipeline does,
and in each EN 13848 band the estimate is compared with the truth over the line (where every
pass covers it):

| column | what |
|---|---|
| `sd_ratio` | SD(estimate) / SD(truth) over the line |
| `slope` | regression slope of the estimate on the truth, `<x^, x> / <x, x>` (the in-band gain g) |
| `wiener` | `<x^, x> / <x^, x^>`: 1 if the error is orthogonal to the estimate (a Wiener estimate); then `sd_ratio` = sqrt(g) |
| `seg_err_%` | per-segment relative error of the SD (200 m segments), min and max; of single passes after the pipeline's correction (`fleet.SD_MODELS`, the settings' model), of the average before it |
| `corrected_seg_errs_%` | the average's per-segment errors after the correction |
| `error` (printed) | the error's variance over the truth's, `sd_ratio^2 - 2 slope + 1`: for the average of many passes, the part of the error the passes share (the track's, not the sensors' noise) |

for one pass (the mean over passes) and for the average of all passes.

    XTASK_FMU_DIR=target/fmu .venv/bin/python tests/fleet_gain.py --seeds 101-106 [--passes 50] \
        [--settings '{"tap_file": "learned-conicity.taps"}']

Seeds: 101 calibration, 102-106 validation, 1-5 held out (evaluate on them, choose nothing).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from project import packaged_fmus, seed_list  # noqa: E402

from track_alignment import fleet, synthetic  # noqa: E402


def on_common(a_start: int, a: np.ndarray, b_start: int, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """`a` and `b` (grids starting at the given indices) where both are finite."""
    lo, hi = max(a_start, b_start), min(a_start + len(a), b_start + len(b))
    x, y = a[lo - a_start:hi - a_start], b[lo - b_start:hi - b_start]
    ok = np.isfinite(x) & np.isfinite(y)
    return x[ok], y[ok]


def gains(est: np.ndarray, truth: np.ndarray) -> dict[str, float]:
    return {
        "sd_ratio": float(np.std(est) / np.std(truth)),
        "slope": float(est @ truth / (truth @ truth)),
        "wiener": float(est @ truth / (est @ est)),
    }


def measure(seed: int, passes: int, work: Path, options: fleet.Options) -> dict:
    d = work / f"seed{seed}"
    synthetic.synthesize(d, packaged_fmus()["RailVehicle"], passes=passes, track_seed=seed, length=1000.0, seed=seed)
    results = [fleet.estimate_pass(str(f), options) for f in fleet.expand([d])]
    coverages = [c for c, _ in results]
    first, truth = fleet.truth_bands(d / "truth.parquet", options)
    truth_sd = fleet.segment_sds(first, truth, options)
    import dask

    total = dask.compute(fleet.tree_sum(coverages))[0]
    mean = {k: np.where(total.count == passes, x / np.maximum(total.count, 1), np.nan) for k, x in total.bands.items()}
    avg_sd = fleet.segment_sds(total.start, mean, options)
    out: dict = {"seed": seed}
    for band in fleet.BANDS:
        single = [gains(*on_common(c.start, c.bands[band], first, truth[band])) for c in coverages]
        out[band] = {
            "one": {k: float(np.mean([g[k] for g in single])) for k in single[0]},
            "all": gains(*on_common(total.start, mean[band], first, truth[band])),
        }
        m = min(len(avg_sd[band]), len(truth_sd[band]))
        err = avg_sd[band][:m] / truth_sd[band][:m] - 1
        one_err = np.concatenate([s[band][:m] / truth_sd[band][:m] - 1 for _, s in results])
        out[band]["all"]["seg_err_%"] = [float(np.nanmin(err) * 100), float(np.nanmax(err) * 100)]
        out[band]["one"]["seg_err_%"] = [float(np.nanmin(one_err) * 100), float(np.nanmax(one_err) * 100)]
        out[band]["all"]["seg_errs_%"] = [round(float(e) * 100, 2) for e in err]
        fixed = fleet.corrected({band: avg_sd[band][:m]}, passes, fleet.model_of(options))[band] / truth_sd[band][:m] - 1
        out[band]["all"]["corrected_seg_errs_%"] = [round(float(e) * 100, 2) for e in fixed]
    return out


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--seeds", default="101-106")
    p.add_argument("--passes", type=int, default=50)
    p.add_argument("--settings", help="the estimator settings as JSON, e.g. {\"tap_file\": \"learned-conicity.taps\"}")
    a = p.parse_args()
    options = fleet.Options(settings=json.loads(a.settings) if a.settings else None)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for seed in seed_list(a.seeds):
            t = time.perf_counter()
            rows.append(measure(seed, a.passes, Path(tmp), options))
            print(json.dumps(rows[-1]), f"({time.perf_counter() - t:.0f} s)", flush=True)
    for band in fleet.BANDS:
        errs = np.array([e for r in rows for e in r[band]["all"]["corrected_seg_errs_%"]])
        errs = errs[np.isfinite(errs)]
        print(f"{band} average, corrected segment SD errors: {errs.size} segments, {np.sum(errs < 0)} low, "
              f"from {errs.min():.2f} to {errs.max():.2f} %, rms {np.sqrt(np.mean(errs ** 2)):.2f} %")
        for which in ("one", "all"):
            for k in ("sd_ratio", "slope", "wiener"):
                v = np.array([r[band][which][k] for r in rows])
                print(f"{band} {which:3s} {k:8s} mean {v.mean():.4f} min {v.min():.4f} max {v.max():.4f}")
            v = np.array([r[band][which]["sd_ratio"] ** 2 - 2 * r[band][which]["slope"] + 1 for r in rows])
            print(f"{band} {which:3s} error    mean {v.mean():.4f} min {v.min():.4f} max {v.max():.4f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
