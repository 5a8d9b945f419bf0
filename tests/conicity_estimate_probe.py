"""The bank over conicities' conicity estimate and accuracy on 400 m records, told nothing: the
figures of docs/learned-filter.md ("What the sensors tell of the conicity", the table of the
estimator) and of the constants `SHARE`, `DISAGREEMENT`, `FIT_LEVEL` and `EVERY_FULL` in
fmu-estimator/src/learned/spectral.rs.

Records: the standard case (20 s at 20 m/s, the paper's noise, `noise_seed` = seed + 1000) at
conicity 0.06, 0.075, 0.1, 0.125, 0.2, 0.3 x Kalker 100 and 50 %. Prints per bank the
`ln(conicity_estimate / conicity)` rms error (mean) at 30-390 m over all records, and the whole
Jrel per condition (mean over the seeds), their mean and worst. About 20 s per bank.

    XTASK_FMU_DIR=target/fmu .venv/bin/python tests/conicity_estimate_probe.py \\
        [--seeds 102-106] [--bank learned-conicity.taps] [--bank OTHER.taps]

A bank of another commit (the features' estimate alone: `git show 40f735e:fmu-estimator/
resources/learned-conicity.taps > /tmp/old.taps`) is given by its absolute path."""

from __future__ import annotations

import argparse
import os

import numpy as np

from project import packaged_fmus, seed_list
from wiener_bound import STEP, noisy_record

CHANNELS = ("ws_acc_y", "ws_yaw_rate", "frame_acc_y")
RECORDS = [(c, k) for c in (0.06, 0.075, 0.1, 0.125, 0.2, 0.3) for k in (1.0, 0.5)]
AT = (30.0, 50.0, 100.0, 150.0, 200.0, 300.0, 390.0)


def main() -> None:
    import track_alignment as ta

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=seed_list, default=seed_list("102-106"), help="track seeds")
    ap.add_argument("--bank", action="append", help="tap_file (repeatable; default learned-conicity.taps)")
    a = ap.parse_args()
    banks = a.bank or ["learned-conicity.taps"]
    vehicle = packaged_fmus()["RailVehicle"]
    records = {(c, k, s): noisy_record(ta, vehicle, s, 20.0, {"conicity": c, "kalker_scale": k}, s + 1000)
               for c, k in RECORDS for s in a.seeds}
    for bank in banks:
        errors, whole = [], {}
        for (c, k, _), r in records.items():
            o = ta.estimate(r["forward_speed"], *(r[ch] for ch in CHANNELS), step=STEP, settings={"tap_file": bank})
            errors.append(np.log(np.interp(AT, o["distance"], o["conicity_estimate"]) / c))
            m = ta.band_metrics(o["distance"], o["alignment"], r["distance"], r["alignment"], trim=10.0)
            whole.setdefault((c, k), []).append(m["whole"]["Jrel"])
        e = np.array(errors)
        means = {key: float(np.mean(v)) for key, v in whole.items()}
        print(f"{bank}, seeds {a.seeds}:")
        print("  ln(conicity) rms (mean): " + ", ".join(
            f"{d:g} m {np.sqrt(np.mean(e[:, i] ** 2)):.3f} ({np.mean(e[:, i]):+.3f})" for i, d in enumerate(AT)))
        print(f"  whole Jrel: mean {np.mean(list(means.values())):.3f}, worst {max(means.values()):.3f}")
        print("  " + ", ".join(f"{c} / {k:g}: {v:.3f}" for (c, k), v in means.items()))


if __name__ == "__main__":
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    main()
