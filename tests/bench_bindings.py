"""Throughput of the Python bindings and wall time of the fleet pipeline (issue 16). Prints:

- samples per second through ``track_alignment.estimate`` on one core (the call runs on one
  thread), for the estimators a user picks, at constant and at variable speed, median of 3 runs
  over 2 million samples;
- the fleet pipeline's wall time on a LocalCluster with 1 and 2 workers over a synthetic fleet
  (``--passes`` passes of 1 km, generated first; generation not timed).

Run, after ``cargo xtask fmu``: ``VIRTUAL_ENV=.venv .venv/bin/maturin develop --release
--manifest-path bindings/Cargo.toml`` (``cargo xtask test`` installs a dev-profile build), then
``.venv/bin/python tests/bench_bindings.py``. Figures are only comparable within one run on a quiet
machine."""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

import track_alignment as ta
from project import packaged_fmus

CASES = {
    "default (learned, causal + 10 m lag; Kalman channel: steady-state gain scheduled on speed)": {},
    "learned, causal only (lag 0)": {"lag": 0.0},
    "learned with the Kalman channel's time-varying gain (gain 1)": {"gain": 1},
    "paper's Kalman filter alone (time-varying gain)": {"estimator": 1},
    "paper's Kalman filter alone (steady-state gain)": {"estimator": 1, "gain": 2},
}


def throughput(n: int) -> None:
    rng = np.random.default_rng(0)
    t = np.arange(n) * 1e-3
    speeds = {
        "constant 20 m/s": np.full(n, 20.0),
        # A measured speed: a new value every sample (18-22 m/s over 63 s, plus 0.05 m/s noise).
        "variable 18-22 m/s": 20.0 + 2.0 * np.sin(0.1 * t) + 0.05 * rng.standard_normal(n),
    }
    a, y, f = (s * rng.standard_normal(n) for s in (0.1, 1e-3, 0.05))
    for speed_label, speed in speeds.items():
        print(f"track_alignment.estimate, {n:,} samples at 1 kHz, speed {speed_label}, one core:")
        for label, settings in CASES.items():
            runs = []
            for _ in range(3):
                start = time.perf_counter()
                ta.estimate(speed, a, y, f, step=1e-3, settings=settings)
                runs.append(time.perf_counter() - start)
            dt = statistics.median(runs)
            print(f"  {n / dt / 1e6:6.2f} M samples/s  ({dt / n * 1e6:.3f} us/sample)  {label}")


def pipeline(passes: int) -> None:
    from dask.distributed import Client, LocalCluster
    from track_alignment import fleet, synthetic

    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp) / "fleet"
        synthetic.synthesize(d, packaged_fmus()["RailVehicle"], passes=passes, length=1000.0)
        samples = sum(len(fleet.read_recording(p)[0]["time"]) for p in fleet.expand([d]))
        print(f"fleet pipeline, {passes} passes of 1 km ({samples:,} samples):")
        for workers in (1, 2):
            with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0") as c, \
                    Client(c) as client:
                t = time.perf_counter()
                fleet.run([d], Path(tmp) / f"out{workers}", client=client, plot=False)
                dt = time.perf_counter() - t
            print(f"  {workers} worker(s): {dt:6.2f} s  ({samples / dt / 1e6:.2f} M samples/s)")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--samples", type=int, default=2_000_000)
    p.add_argument("--passes", type=int, default=50)
    a = p.parse_args()
    throughput(a.samples)
    pipeline(a.passes)


if __name__ == "__main__":
    main()
