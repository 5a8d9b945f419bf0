"""Demo of the project's main job (run by `cargo xtask demo`).

1. The standard estimation case end to end: the RailVehicle FMU (20 s at 20 m/s on a German
   low-disturbance track with vertical irregularities and sensor noise) feeds the
   AlignmentEstimator FMU through a plain Python co-simulation master over fmpy (tests/cosim.py),
   and the accuracy in each EN 13848 band is printed beside the paper's Table.
2. The estimator on data from its own simplified model (tests/sm_reference.py), which shows the
   filter itself at work without model error.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import cosim
import evaluation as ev
import sm_reference as sm
from project import MODEL_IDENTIFIER, REPO, fmu_dir

#: The paper's standard case (railway.md section 1): J [mm] / Jrel per band.
PAPER = {"whole": (0.36, 0.25), "D1": (0.21, 0.48), "D2": (0.22, 0.26), "D3": (0.18, 0.15)}


def parse_args() -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--fmu", type=Path, default=fmu_dir() / f"{MODEL_IDENTIFIER}.fmu", help="the packaged FMU")
    p.add_argument("--seed", type=int, default=1, help="seed of the alignment (the noise uses seed + 100)")
    p.add_argument("--speed", type=float, default=20.0, help="vehicle speed [m/s] (default 20, the paper's)")
    p.add_argument("--duration", type=float, default=20.0, help="simulated time [s] (default 20, the paper's)")
    p.add_argument("--no-noise", action="store_true", help="noise-free sensors")
    p.add_argument("--results", type=Path, help="results.csv of `orchestrator run` for the standard case (else a Python master runs it)")
    return p.parse_args()


def shown(path: Path) -> str:
    try:
        return str(path.resolve().relative_to(REPO))
    except ValueError:
        return str(path)


def standard_case(args: argparse.Namespace) -> None:
    vehicle = args.fmu.parent / "RailVehicle.fmu"
    print("Standard case, end to end: RailVehicle.fmu -> AlignmentEstimator.fmu")
    print("===================================================================")
    print(f"vehicle  ML95-like metro car, {args.speed:g} m/s for {args.duration:g} s on a German low-disturbance track")
    print("         (alignment, vertical profile, cross-level; seed 1), sensor noise 0.01 m/s2, 0.0005 rad/s")
    t0 = time.perf_counter()
    if args.results is not None:
        print(f"master   the orchestrator (Gauss-Seidel, 1 ms steps): {shown(args.results)}")
        table = np.genfromtxt(args.results, delimiter=",", names=True, deletechars="")
        r = cosim.Result(table["time"][1:], table["vehicle.distance"][1:], table["vehicle.alignment"][1:],
                         table["estimator.alignment"][1:], table["estimator.alignment_std"][1:])
    else:
        print("master   Python over fmpy's FMU2Slave, Gauss-Seidel, 1 ms steps (tests/cosim.py)")
        r = cosim.run_standard_case(vehicle, args.fmu, stop=args.duration, speed=args.speed)
    wall = time.perf_counter() - t0
    ds = args.speed * 1e-3
    print()
    print(f"  {'band':8} {'ours J [mm] / Jrel':>20}   {'paper J / Jrel':>15}")
    for name, band in ev.BANDS.items():
        a = ev.accuracy(r.estimate, r.truth, ds, band)
        pj, pr = PAPER[name]
        print(f"  {name:8} {a.J * 1e3:10.2f} / {a.Jrel:5.2f}   {pj:9.2f} / {pr:4.2f}")
    print()
    if args.results is None:
        print(f"wall-clock {wall:.2f} s for {args.duration:g} s simulated (two FMUs, Python master loop included)")
    print("NOTE: the estimator still runs with the paper's Table 2 equivalents and an uncalibrated")
    print("diagonal noise model. Identifying its parameters against this vehicle and calibrating Q")
    print("and R (the paper's procedure) is the estimation study's job; until then these figures are")
    print("far from the paper's.")
    print()


def main() -> None:
    args = parse_args()
    standard_case(args)
    step = 1e-3
    t0 = time.perf_counter()
    alignment = sm.alignment_harmonics(np.random.default_rng(args.seed))
    noise = None if args.no_noise else np.random.default_rng(args.seed + 100)
    run = sm.synthetic_run(alignment, speed=args.speed, duration=args.duration, step=step, noise_rng=noise)
    t_data = time.perf_counter() - t0
    length = args.speed * args.duration

    print("The estimator on data from its own simplified model")
    print("===================================================")
    print("The data come from the estimator's OWN simplified model (tests/sm_reference.py), not from")
    print("the vehicle model. Without that model error these numbers are NOT comparable with the")
    print("paper's (paper: J = 0.36 mm, Jrel = 0.25).")
    print()
    print(f"track    {length:.0f} m straight, German low-disturbance alignment, wavelengths 1-250 m,")
    print(f"         seed {args.seed}: {np.std(run.xi) * 1e3:.2f} mm rms")
    sigmas = ", ".join(f"{v:g}" for v in sm.SENSOR_SIGMAS.values())
    print(f"vehicle  {args.speed:g} m/s for {args.duration:g} s; sensor noise {'none' if noise is None else sigmas + ' (m/s2, rad/s, m/s2)'}")
    print(f"FMU      {shown(args.fmu)}, fmpy.simulate_fmu, step {step * 1e3:g} ms ({run.t.size - 1} steps)")
    print()

    cases = [("FMU defaults (not yet calibrated)", {}), ("noise model matched to SM data", ev.SM_TUNING)]
    print("accuracy after a zero-phase 4th-order Butterworth band-pass, first and last 10 m trimmed")
    print(f"  {'':34} {'whole 3-200 m':>15}   {'Jrel per band':>22}")
    print(f"  {'':34} {'J [mm]':>7} {'Jrel':>7}   {'D1':>6} {'D2':>6} {'D3':>6}")
    seconds = []
    for label, start_values in cases:
        t1 = time.perf_counter()
        result = ev.simulate(args.fmu, run, start_values=start_values)
        seconds.append(time.perf_counter() - t1)
        acc = ev.score(result, run)
        w = acc["whole"]
        print(f"  {label:34} {w.J * 1e3:7.3f} {w.Jrel:7.3f}   {acc['D1'].Jrel:6.3f} {acc['D2'].Jrel:6.3f} {acc['D3'].Jrel:6.3f}")
    print()
    runs = " and ".join(f"{s:.2f} s" for s in seconds)
    print(f"wall-clock  FMU runs {runs} for {args.duration:g} s simulated, fmpy's Python loop included")
    print(f"            ({args.duration / max(seconds):.0f}x faster than real time); synthetic data {t_data:.2f} s;")
    print(f"            total {time.perf_counter() - t0:.2f} s")
    print()
    print("The matched noise model is a test setting for simplified-model data (tests/evaluation.py),")
    print("not a calibration; the calibration study will replace the FMU's default noise model.")


if __name__ == "__main__":
    main()
