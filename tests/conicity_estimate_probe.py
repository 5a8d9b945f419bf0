"""The bank over conicities' conicity estimate and accuracy on 400 m records, told nothing: the
figures of docs/learned-filter.md ("What the sensors tell of the conicity", the table of the
estimator) and of the constants `SHARE`, `DISAGREEMENT`, `FIT_LEVEL` and `EVERY_FULL` in
fmu-estimator/src/learned/spectral.rs.

Records: the standard case (20 s at 20 m/s, the paper's noise, `noise_seed` = seed + 1000) at
conicity 0.06, 0.075, 0.1, 0.125, 0.2, 0.3 x Kalker 100 and 50 %. Prints per bank the
`ln(conicity_estimate / conicity)` rms error (mean) at 30-390 m over all records, and the whole
Jrel per condition (mean over the seeds), their mean and worst. About 20 s per bank.

    XTASK_FMU_DIR=target/fmu .venv/bin/python tests/conicity_estimate_probe.py \\
        [--seeds 102-106] [--conicities 0.06,0.075,0.1,0.125,0.2,0.3] [--duration 20] \\
        [--vehicles DIR] [--bank learned-conicity.taps] [--bank OTHER.taps]

`--vehicles DIR` runs, in place of the conditions, the vehicle files in DIR at their own wheels
(the validation vehicles: `cargo run --release -p alignment-studies --example
validation_vehicles -- DIR`), and prints the whole Jrel per file and per stem (`kind`, `family`:
mean / worst over the files). SHARE's table: the conditions with `--conicities
0.05,0.06,0.075,0.1,0.15,0.2,0.3,0.4`; the vehicles with `--seeds 102-104`, and `--seeds
102-103 --duration 100` (2 km) for the `kind` files.

A bank of another commit (the features' estimate alone: `git show 40f735e:fmu-estimator/
resources/learned-conicity.taps > /tmp/old.taps`) is given by its absolute path."""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np

from project import packaged_fmus, seed_list
from wiener_bound import STEP, noisy_record

CHANNELS = ("ws_acc_y", "ws_yaw_rate", "frame_acc_y")
CONICITIES = "0.06,0.075,0.1,0.125,0.2,0.3"
AT = (30.0, 50.0, 100.0, 150.0, 200.0, 300.0, 390.0)


def main() -> None:
    import track_alignment as ta

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=seed_list, default=seed_list("102-106"), help="track seeds")
    ap.add_argument("--conicities", default=CONICITIES, help="the conditions' conicities (each at Kalker 100 and 50 %%)")
    ap.add_argument("--duration", type=float, default=20.0, help="seconds per record at 20 m/s")
    ap.add_argument("--vehicles", type=Path, help="a directory of vehicle files, run in place of the conditions")
    ap.add_argument("--bank", action="append", help="tap_file (repeatable; default learned-conicity.taps)")
    a = ap.parse_args()
    banks = a.bank or ["learned-conicity.taps"]
    if not a.duration * 20.0 > max(AT):
        ap.error(f"--duration {a.duration}: the record must reach {max(AT)} m at 20 m/s")
    vehicle = packaged_fmus()["RailVehicle"]
    if a.vehicles:
        files = sorted(a.vehicles.glob("*.toml"))
        if not files:
            ap.error(f"--vehicles {a.vehicles}: no vehicle files (*.toml)")
        try:
            runs = {f.stem: ({"vehicle": str(f.resolve())}, vehicle_conicity(f)) for f in files}
        except ValueError as e:
            ap.error(str(e))
    else:
        try:
            conicities = [float(c) for c in a.conicities.split(",")]
        except ValueError:
            ap.error(f"--conicities {a.conicities!r}: not a list of numbers")
        if not all(0.0 < c < 1.0 for c in conicities):
            ap.error(f"--conicities {a.conicities}: each must lie in (0, 1)")
        runs = {f"{c} / {k:g}": ({"conicity": c, "kalker_scale": k}, c) for c in conicities for k in (1.0, 0.5)}
    records = {(name, s): noisy_record(ta, vehicle, s, a.duration, p, s + 1000)
               for name, (p, _) in runs.items() for s in a.seeds}
    for bank in banks:
        errors, whole = [], {}
        for (name, _), r in records.items():
            c = runs[name][1]
            o = ta.estimate(r["forward_speed"], *(r[ch] for ch in CHANNELS), step=STEP, settings={"tap_file": bank})
            errors.append(np.log(np.interp(AT, o["distance"], o["conicity_estimate"]) / c))
            m = ta.band_metrics(o["distance"], o["alignment"], r["distance"], r["alignment"], trim=10.0)
            whole.setdefault(name, []).append(m["whole"]["Jrel"])
        e = np.array(errors)
        means = {key: float(np.mean(v)) for key, v in whole.items()}
        print(f"{bank}, seeds {a.seeds}, {a.duration:g} s:")
        print("  ln(conicity) rms (mean): " + ", ".join(
            f"{d:g} m {np.sqrt(np.mean(e[:, i] ** 2)):.3f} ({np.mean(e[:, i]):+.3f})" for i, d in enumerate(AT)))
        print(f"  whole Jrel: mean {np.mean(list(means.values())):.4f}, worst {max(means.values()):.3f}")
        print("  " + ", ".join(f"{name}: {v:.3f}" for name, v in means.items()))
        if a.vehicles:
            for stem in sorted({n.rstrip("0123456789") for n in means}):
                v = [x for n, x in means.items() if n.rstrip("0123456789") == stem]
                print(f"  {stem}: mean {np.mean(v):.4f}, worst {max(v):.3f} ({len(v)} files)")


def vehicle_conicity(file: Path) -> float:
    """The tread conicity a vehicle file gives its wheelsets; `ValueError` naming the file if it
    has none."""
    import tomllib

    try:
        with file.open("rb") as f:
            return float(tomllib.load(f)["wheelset"]["conicity"])
    except (OSError, tomllib.TOMLDecodeError, KeyError, TypeError, ValueError) as e:
        raise ValueError(f"{file}: no wheelset.conicity ({type(e).__name__}: {e})") from None


if __name__ == "__main__":
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    main()
