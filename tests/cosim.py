"""A plain Python co-simulation master over fmpy's FMU2Slave: the vehicle FMU feeds the
estimator FMU, Gauss-Seidel (vehicle first), fixed step. It is the reference the orchestrator will
be checked against (the orchestrator reproduces it bit for bit, tests/test_orchestrator_standard.py).

Order within one communication step from t to t + h: vehicle.doStep(t, h); read its sensors
(samples at t + h); set them and the speed on the estimator; estimator.doStep(t, h); read the
estimate at t + h. So estimate and truth of the same row refer to the same track position.
"""

from __future__ import annotations

import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path

import fmpy
import numpy as np
from fmpy.fmi2 import FMU2Slave

SENSORS = ("ws_acc_y", "ws_yaw_rate", "frame_acc_y")


@dataclass
class Component:
    fmu: FMU2Slave
    vr: dict[str, int]
    path: str

    @classmethod
    def load(cls, fmu_path: Path | str, name: str) -> "Component":
        md = fmpy.read_model_description(str(fmu_path))
        unzip = fmpy.extract(str(fmu_path), unzipdir=tempfile.mkdtemp(prefix=f"{name}-"))
        fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzip, modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
        return cls(fmu, {v.name: v.valueReference for v in md.modelVariables}, unzip)

    def setup(self, start_values: dict, stop: float) -> None:
        self.fmu.instantiate()
        self.fmu.setupExperiment(startTime=0.0, stopTime=stop)
        for name, value in start_values.items():
            if isinstance(value, bool):
                self.fmu.setBoolean([self.vr[name]], [value])
            elif isinstance(value, int):
                self.fmu.setInteger([self.vr[name]], [value])
            elif isinstance(value, str):
                self.fmu.setString([self.vr[name]], [value])
            else:
                self.fmu.setReal([self.vr[name]], [float(value)])
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()

    def close(self) -> None:
        self.fmu.terminate()
        self.fmu.freeInstance()
        shutil.rmtree(self.path, ignore_errors=True)


@dataclass
class Result:
    time: np.ndarray
    distance: np.ndarray
    truth: np.ndarray
    estimate: np.ndarray
    std: np.ndarray


def run_standard_case(vehicle_fmu, estimator_fmu, stop: float = 20.0, step: float = 1e-3, speed: float = 20.0,
                      vehicle_params: dict | None = None, estimator_params: dict | None = None) -> Result:
    vehicle = Component.load(vehicle_fmu, "vehicle")
    estimator = Component.load(estimator_fmu, "estimator")
    try:
        vehicle.setup({"speed": speed, **(vehicle_params or {})}, stop)
        estimator.setup({"speed": speed, **(estimator_params or {})}, stop)
        n = int(round(stop / step))
        out_vr = [vehicle.vr[s] for s in SENSORS] + [vehicle.vr["distance"], vehicle.vr["alignment"]]
        in_vr = [estimator.vr[s] for s in SENSORS] + [estimator.vr["speed"]]
        est_vr = [estimator.vr["alignment"], estimator.vr["alignment_std"]]
        rows = np.empty((n, 4))
        for k in range(n):
            t = k * step
            vehicle.fmu.setReal([vehicle.vr["speed"]], [speed])
            vehicle.fmu.doStep(t, step)
            a, b, c, d, xi = vehicle.fmu.getReal(out_vr)
            estimator.fmu.setReal(in_vr, [a, b, c, speed])
            estimator.fmu.doStep(t, step)
            e, s = estimator.fmu.getReal(est_vr)
            rows[k] = (d, xi, e, s)
        return Result(np.arange(1, n + 1) * step, rows[:, 0], rows[:, 1], rows[:, 2], rows[:, 3])
    finally:
        vehicle.close()
        estimator.close()
