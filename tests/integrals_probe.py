"""What straight track gives the estimator's in-motion checks (fmu-estimator/src/integrals.rs):
the yaw gyroscope's heading and the accelerometers' difference (`ws_acc_y - frame_acc_y`)
integrated over a trailing 500 m window, read every 10 m, as the FMU's `heading_change` and
`relative_velocity_change` are. Vehicle FMU runs of 10 km on validation seeds, nothing told,
the biases left out (the check is for what is not removed); per condition and seed the rms
and the largest absolute value over the run, which the checks' levels must stay above.

    XTASK_FMU_DIR=target/fmu .venv/bin/python tests/integrals_probe.py [--seeds 102,103]

About 4 min on 2 cores. The window is computed here from the raw sensors (the oracle for the
FMU's own outputs is in tests/test_curves.py and tests/test_sensors.py).
"""

from __future__ import annotations

import argparse

import numpy as np

from project import packaged_fmus, seed_list
from wiener_bound import STEP, noisy_record

ta = __import__("track_alignment")

WINDOW, CELL = 500.0, 10.0
DISTANCE = 10_000.0
#: A sensor error parameter left at 0 takes the preset's value: a negligible bias removes it.
NO_BIAS = {"ws_yaw_rate_bias": 1e-12, "ws_acc_y_bias": 1e-12, "frame_acc_y_bias": 1e-12}
#: (name, vehicle parameters, speed [m/s]).
CONDITIONS = [
    ("German low (training), 10 m/s", {}, 10.0),
    ("German low (training), 20 m/s", {}, 20.0),
    ("German low (training), 30 m/s", {}, 30.0),
    ("German high, 20 m/s", {"spectrum": 2}, 20.0),
    ("FRA class 6, 20 m/s", {"spectrum": 4}, 20.0),
    ("FRA class 5, 20 m/s", {"spectrum": 3}, 20.0),
    ("FRA class 5, 30 m/s", {"spectrum": 3}, 30.0),
    ("conicity 0.05, Kalker 50 %", {"conicity": 0.05, "kalker_scale": 0.5}, 20.0),
    ("conicity 0.4", {"conicity": 0.4}, 20.0),
    ("Manchester Benchmark vehicle", {"vehicle": "manchester.toml"}, 20.0),
    ("tactical preset, turn-on biases removed", {"sensor_grade": 1, **NO_BIAS}, 20.0),
    ("MEMS preset, turn-on biases removed", {"sensor_grade": 2, **NO_BIAS}, 20.0),
]


def record(seed: int, parameters: dict, speed: float) -> dict[str, np.ndarray]:
    return noisy_record(ta, packaged_fmus()["RailVehicle"], seed, float(round(DISTANCE / speed) + 1),
                        {"speed": speed, **parameters}, seed + 1000)


def window_changes(r: dict[str, np.ndarray]) -> np.ndarray:
    """|change| of the heading and of the relative velocity over the trailing window, at every
    cell end: from the cell end at or before WINDOW metres back (the run's start before)."""
    moving = r["forward_speed"] > 0.01
    rates = np.array([r["ws_yaw_rate"], r["ws_acc_y"] - r["frame_acc_y"]])
    integral = np.cumsum(np.where(moving, rates, 0.0) * STEP, axis=1)
    s = np.cumsum(np.where(moving, r["forward_speed"], 0.0) * STEP)
    ends = np.arange(CELL, s[-1], CELL)
    at = integral[:, np.minimum(np.searchsorted(s, ends), len(s) - 1)]
    back = int(round(WINDOW / CELL))
    start = np.concatenate([np.zeros((2, back)), at[:, :-back]], axis=1)
    return np.abs(at - start)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=seed_list, default=[102, 103])
    a = ap.parse_args()
    print("| condition | seeds | heading: rms / largest (mrad) | relative velocity: rms / largest (mm/s) |")
    print("|---|---|---|---|")
    for name, parameters, speed in CONDITIONS:
        runs = [window_changes(record(seed, parameters, speed)) for seed in a.seeds]
        rms = [max(np.sqrt(np.mean(c[i] ** 2)) for c in runs) for i in range(2)]
        top = [max(c[i].max() for c in runs) for i in range(2)]
        print(f"| {name} | {','.join(map(str, a.seeds))} | {1e3 * rms[0]:.1f} / {1e3 * top[0]:.1f} | "
              f"{1e3 * rms[1]:.1f} / {1e3 * top[1]:.1f} |", flush=True)


if __name__ == "__main__":
    main()
