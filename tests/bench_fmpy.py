"""fmpy's cost per communication step on the benchmark system of orchestrator/benches/master.rs
(Dahlquist -> Feedthrough, Gauss-Seidel), as a hand-written FMU2Slave loop: the fastest way
fmpy users step two FMUs. Prints the median microseconds per step of 3 runs."""

from __future__ import annotations

import argparse
import shutil
import statistics
import tempfile
import time

import fmpy
from fmpy.fmi2 import FMU2Slave


def load(path: str, name: str):
    md = fmpy.read_model_description(path)
    unzip = fmpy.extract(path, unzipdir=tempfile.mkdtemp())
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzip, modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    vr = {v.name: v.valueReference for v in md.modelVariables}
    return fmu, vr, unzip


def once(dq_path: str, feed_path: str, steps: int, h: float) -> float:
    (a, av, ad), (b, bv, bd) = load(dq_path, "dq"), load(feed_path, "feed")
    x, u = [av["x"]], [bv["u"]]
    start = time.perf_counter()
    for k in range(steps):
        t = k * h
        a.doStep(t, h)
        b.setReal(u, a.getReal(x))
        b.doStep(t, h)
    elapsed = time.perf_counter() - start
    for f, d in ((a, ad), (b, bd)):
        f.terminate()
        f.freeInstance()
        shutil.rmtree(d, ignore_errors=True)
    return elapsed / steps * 1e6


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("dahlquist")
    p.add_argument("feedthrough")
    p.add_argument("--steps", type=int, default=100_000)
    p.add_argument("--step", type=float, default=1e-4)
    a = p.parse_args()
    print(statistics.median(once(a.dahlquist, a.feedthrough, a.steps, a.step) for _ in range(3)))


if __name__ == "__main__":
    main()
