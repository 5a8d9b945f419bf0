"""A probe for the next step of the learned filter: a long-wave stage after the default. At
constant speed, each sensor and the default's own causal estimate pass a causal band-pass
(second-order Butterworth high-pass at 400 m and low-pass at 40 m); an FIR over the last 600 m
of them (taps every 10 m) is fitted by ridge least squares to the default's residual, both in
the metric's whole band (3-200 m), and added to the default's estimate. With the default's
estimate among the regressors the stage can replace its long waves, not only correct them
(`--without-estimate` leaves it out, for comparison).

Training seeds 101-108 (300 s runs, samples past 800 m, where the window is full), the ridge
chosen on 109-112 (150 s runs, 200 m trimmed: its column is the choosing score, so a little
optimistic), then the standard case on the held-out seeds 1-5 (20 s, 10 m trimmed), for three
and four sensors (the roll gyro) with the paper's sensors or the tactical preset's noise. On
the 400 m standard records the window never fills (its lags before the start are zeros): the
stage is judged there in a start-up it was not fitted on.

    XTASK_FMU_DIR=target/fmu .venv/bin/python tests/long_stage_probe.py [--grade tactical] \
        [--without-estimate]

About 6 min per grade on 2 cores. Nothing in the shipped estimator uses this; see
docs/accuracy.md ("Real sensors").
"""

from __future__ import annotations

import argparse

import numpy as np
from scipy import signal

from wiener_bound import CHANNELS, GRADES, SPEED, STEP, default_estimate, lagged, noise_parameters, noisy_record

# The paper's sensors as the vehicle FMU's default per-sample sigmas; the tactical preset's noise.
NOISE = {"paper": {}, "tactical": noise_parameters(GRADES["tactical (HG1700)"])}
EVERY = int(round(10.0 / (SPEED * STEP)))  # samples between taps: 10 m
LAGS = range(0, 61)  # 600 m
HIGH = signal.butter(2, SPEED / 400.0, btype="high", fs=1 / STEP, output="sos")
LOW = signal.butter(2, SPEED / 40.0, btype="low", fs=1 / STEP, output="sos")


def low(order: int, cut: float = 40.0):
    return signal.butter(order, SPEED / cut, btype="low", fs=1 / STEP, output="sos")
RIDGES = (1e-8, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2)
BANDS = ("whole", "D1", "D2", "D3")


def record(ta, vehicle, seed: int, duration: float, grade: str, sensors: int, estimate: bool) -> dict:
    """One run of the vehicle FMU, the default's estimate of it, and the stage's inputs."""
    r = noisy_record(ta, vehicle, seed, duration, NOISE[grade], seed + 1000)
    o = default_estimate(ta, r, sensors)
    r["estimate"], r["estimate_distance"] = o["alignment"], o["distance"]
    inputs = [r[c] for c in CHANNELS[:sensors]] + ([o["alignment"]] if estimate else [])
    r["inputs"] = np.array([signal.sosfilt(LOW, signal.sosfilt(HIGH, x)) for x in inputs])
    return r


def delayed(inputs: np.ndarray) -> np.ndarray:
    """Each input delayed by each of LAGS x EVERY samples (the past only), zero before the start:
    one row per input and lag."""
    return lagged(inputs, [lag * EVERY for lag in LAGS]).T


def main() -> None:
    import track_alignment as ta
    from project import packaged_fmus

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grade", choices=sorted(NOISE), default="paper")
    ap.add_argument("--without-estimate", action="store_true", help="the sensors only as the stage's inputs")
    ap.add_argument("--sensors", type=int, nargs="+", choices=(3, 4), default=[3, 4])
    ap.add_argument("--low-order", type=int, default=2, help="the low-pass's order")
    ap.add_argument("--low-cut", type=float, default=40.0, help="the low-pass's cut-off [m]")
    ap.add_argument("--d3-weight", type=float, default=0.0, help="the D3 residual's extra weight in the fit")
    ap.add_argument("--per-seed", action="store_true", help="also each standard-case seed's D3")
    a = ap.parse_args()
    global LOW
    LOW = low(a.low_order, a.low_cut)
    d3 = lambda x: ta.bandpass(np.ascontiguousarray(x), SPEED * STEP, 70.0, 200.0)  # noqa: E731
    vehicle = packaged_fmus()["RailVehicle"]
    whole = lambda x: ta.bandpass(np.ascontiguousarray(x), SPEED * STEP, 3.0, 200.0)  # noqa: E731
    fmt = lambda ms: " / ".join(f"{np.mean([m[k]['Jrel'] for m in ms]):.3f}" for k in BANDS)  # noqa: E731
    inputs = "the sensors" if a.without_estimate else "the sensors and the default's estimate"
    print(f"The stage's inputs: {inputs}. Jrel whole / D1 / D2 / D3.\n")
    print("| noise | sensors | ridge (chosen on 109-112) | seeds 109-112: default | with the stage | seeds 1-5, standard case: default | with the stage |")
    print("|---|---|---|---|---|---|---|")
    for sensors in a.sensors:
        rows, target = [], []
        for seed in range(101, 109):
            r = record(ta, vehicle, seed, 300.0, a.grade, sensors, not a.without_estimate)
            keep = slice(int(800.0 / (SPEED * STEP)), None, int(2.0 / (SPEED * STEP)))  # past 800 m, every 2 m
            rows.append(np.array([whole(x)[keep] for x in delayed(r["inputs"])]).T)
            target.append(whole(r["alignment"] - r["estimate"])[keep])
            if a.d3_weight > 0:
                rows.append(np.sqrt(a.d3_weight) * np.array([d3(x)[keep] for x in delayed(r["inputs"])]).T)
                target.append(np.sqrt(a.d3_weight) * d3(r["alignment"] - r["estimate"])[keep])
        x, y = np.concatenate(rows), np.concatenate(target)
        gram = x.T @ x

        cache = {}

        def judged(w, seeds, duration, trim):
            before, after = [], []
            for seed in seeds:
                if seed not in cache:
                    cache[seed] = record(ta, vehicle, seed, duration, a.grade, sensors, not a.without_estimate)
                r = cache[seed]
                stage = np.ascontiguousarray(r["estimate"] + w @ delayed(r["inputs"]))
                before.append(ta.band_metrics(r["estimate_distance"], r["estimate"], r["distance"], r["alignment"], trim=trim))
                after.append(ta.band_metrics(r["estimate_distance"], stage, r["distance"], r["alignment"], trim=trim))
            return before, after

        fits = {}
        for ridge in RIDGES:
            w = np.linalg.solve(gram + ridge * np.trace(gram) / len(gram) * np.eye(len(gram)), x.T @ y)
            fits[ridge] = (w, judged(w, range(109, 113), 150.0, 200.0))
        ridge = min(fits, key=lambda k: np.mean([m["whole"]["Jrel"] for m in fits[k][1][1]]))
        w, (v0, v1) = fits[ridge]
        s0, s1 = judged(w, range(1, 6), 20.0, 10.0)
        print(f"| {a.grade} | {sensors} | {ridge:g} | {fmt(v0)} | {fmt(v1)} | {fmt(s0)} | {fmt(s1)} |", flush=True)
        if a.per_seed:
            for k in BANDS:
                each = lambda ms: " ".join(f"{m[k]['Jrel']:.3f}" for m in ms)  # noqa: E731
                print(f"  seeds 1-5 {k}: default {each(s0)}; with the stage {each(s1)}", flush=True)


if __name__ == "__main__":
    main()
