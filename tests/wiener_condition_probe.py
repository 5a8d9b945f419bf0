"""What the three sensors allow at one wheel condition, beside the bank over conicities: the
non-causal Wiener estimate of `tests/wiener_bound.py` (its method, nothing from the estimator)
with the vehicle at a given conicity and Kalker scale, against `learned-conicity.taps` told the
conicity and told nothing on the same records (`alignment`, causal), and told the conicity at
its fixed lag (`alignment_lagged`, 10 m behind). The second formulation behind the conicity
sweep's "told" limits in docs/accuracy.md.

Per condition: noise-free runs of the training seeds (`--duration` s each at 20 m/s) give the
cross-spectra; the paper's sensor noise; the stationary bound, and the two-sided FIR run over the
standard case's records of the held-out seeds (20 s, the paper's noise, `noise_seed` = seed +
1000), judged by the project's metric. Whole / D1 / D2 / D3 Jrel, mean over the seeds.

    XTASK_FMU_DIR=target/fmu .venv/bin/python tests/wiener_condition_probe.py \\
        [--conditions 0.05/0.5,0.1/1] [--train-seeds 101-112] [--seeds 1-5] [--duration 300]

About 30 s per condition on 2 cores."""

from __future__ import annotations

import argparse
import os

import numpy as np

from project import packaged_fmus, seed_list
from wiener_bound import (BANDS, CHANNELS, DECIMATION, GRADES, SHAPE, SPEED, STEP, back_to_target, bound, check_runs,
                          decimate, noise_parameters, noisy_record, shape, spectra, wiener_fir, wiener_metrics)

SENSORS = (0, 1, 2)
PAPER = GRADES["paper's sensors"]


def condition(text: str) -> tuple[float, float]:
    """`conicity/kalker`, both positive."""
    try:
        c, k = (float(v) for v in text.split("/"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}': a condition is CONICITY/KALKER, e.g. 0.05/0.5") from None
    if not (0.0 < c < 1.0 and 0.0 < k <= 2.0):
        raise argparse.ArgumentTypeError(f"'{text}': conicity in (0, 1), Kalker scale in (0, 2]")
    return c, k


def main() -> None:
    import track_alignment as ta

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--conditions", type=lambda s: [condition(t) for t in s.split(",")],
                    default=[(0.05, 0.5), (0.06, 0.5), (0.1, 1.0), (0.3, 1.0)])
    ap.add_argument("--train-seeds", type=seed_list, default=seed_list("101-112"))
    ap.add_argument("--seeds", type=seed_list, default=seed_list("1-5"))
    ap.add_argument("--duration", type=float, default=300.0, help="each training run [s]")
    ap.add_argument("--segment", type=float, default=1638.4, help="Welch segment [m]")
    a = ap.parse_args()
    check_runs(ap, a)
    vehicle = packaged_fmus()["RailVehicle"]
    fs = 1.0 / (STEP * np.prod(DECIMATION))
    nperseg = int(round(a.segment / SPEED * fs))
    fmt = lambda d: " / ".join(f"{d[k]:.3f}" for k in BANDS)  # noqa: E731
    mean = lambda ms: {k: float(np.mean([m[k]["Jrel"] for m in ms])) for k in BANDS}  # noqa: E731
    print(f"Training: seeds {a.train_seeds[0]}-{a.train_seeds[-1]}, {a.duration:g} s each at {SPEED:g} m/s; "
          f"held out: {a.seeds}; the paper's sensor noise, three sensors. Jrel whole / D1 / D2 / D3.\n")
    print(f"| conicity / Kalker | Wiener bound (stationary) | Wiener FIR, non-causal, on the records "
          f"| bank over conicities told the conicity "
          f"| told nothing | told the conicity, fixed lag |")
    print("|---|---|---|---|---|---|")
    for c, k in a.conditions:
        wheels = {"conicity": c, "kalker_scale": k}
        runs = []
        for seed in a.train_seeds:
            out = ta.simulate(vehicle, a.duration, step=STEP,
                              parameters={"track_seed": seed, "sensor_noise": False, **wheels},
                              variables=[*CHANNELS, "alignment"])
            x = decimate(np.array([out[ch][1:] for ch in (*CHANNELS, "alignment")]))
            x = np.array([shape(xi, order, fs) for xi, order in zip(x, SHAPE)])
            runs.append(x[:, int(20.0 * fs):])  # the run-in ramp left out
        f, s = spectra(runs, fs, nperseg)
        target = len(CHANNELS)
        syy = s[target, target].real * np.abs(back_to_target(SHAPE[target], f, fs, SPEED)) ** 2
        h, err = wiener_fir(s, f, fs, nperseg, PAPER, SENSORS)
        records = [noisy_record(ta, vehicle, seed, 20.0, {**noise_parameters(PAPER), **wheels}, seed + 1000)
                   for seed in a.seeds]
        applied = [wiener_metrics(ta, h, r, SENSORS, fs) for r in records]

        def learned(settings: dict, lagged: bool = False) -> dict:
            ms = []
            for r in records:
                o = ta.estimate(r["forward_speed"], r["ws_acc_y"], r["ws_yaw_rate"], r["frame_acc_y"], step=STEP,
                                settings={"tap_file": "learned-conicity.taps", **settings})
                d, e = ("distance_lagged", "alignment_lagged") if lagged else ("distance", "alignment")
                ms.append(ta.band_metrics(o[d], o[e], r["distance"], r["alignment"], trim=10.0))
            return mean(ms)

        print(f"| {c:g} / {k:g} | {fmt(bound(err, syy, f, fs, SPEED))} | {fmt(mean(applied))} "
              f"| {fmt(learned({'conicity': c}))} | {fmt(learned({}))} | {fmt(learned({'conicity': c}, True))} |",
              flush=True)


if __name__ == "__main__":
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    main()
