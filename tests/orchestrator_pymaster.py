"""A plain Python co-simulation master over fmpy's FMU2Slave that follows the orchestrator's
documented algorithm (orchestrator/src/master.rs) call for call, as the independent reference the
orchestrator's results are compared with:

- instantiate every component (instance name = component name), fmi2SetupExperiment(start, stop),
  set the parameters, fmi2EnterInitializationMode for all;
- initial values through the connections: n times over the components in Gauss-Seidel order,
  set each component's connected inputs from the values last read, then read its connected
  outputs; fmi2ExitInitializationMode in that order; read every component's connected outputs;
- record a row at t = start;
- step k from t_k = start + k*h (integer ticks, no accumulation):
  Gauss-Seidel: per component in order, set inputs, doStep(t_k, h), read outputs;
  Jacobi: set every component's inputs, step every component, read every component's outputs;
- record a row at t_{k+1}.

A connection's LinearTransformation is applied as factor * x + offset. The module also drives a
single FMU from input signals, both as `orchestrator simulate` and as fmpy.simulate_fmu do, to
explain the differences between those two exactly.

"""

from __future__ import annotations

import shutil
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import fmpy
import numpy as np
from fmpy.fmi2 import FMU2Slave


@dataclass
class Connection:
    start: str  # component.variable (an output)
    end: str  # component.variable (an input)
    factor: float | None = None
    offset: float | None = None

    def apply(self, x):
        if self.factor is None and self.offset is None:
            return x
        f = 1.0 if self.factor is None else self.factor
        o = 0.0 if self.offset is None else self.offset
        return f * x + o


@dataclass
class Comp:
    name: str
    path: Path
    parameters: dict = field(default_factory=dict)
    # filled by load()
    fmu: FMU2Slave | None = None
    variables: dict = field(default_factory=dict)
    unzip: str = ""

    def load(self) -> None:
        md = fmpy.read_model_description(str(self.path), validate=False)
        self.variables = {v.name: v for v in md.modelVariables}
        self.unzip = fmpy.extract(str(self.path), unzipdir=tempfile.mkdtemp(prefix=f"pymaster-{self.name}-"))
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=self.unzip,
                             modelIdentifier=md.coSimulation.modelIdentifier, instanceName=self.name)

    def get(self, name: str):
        v = self.variables[name]
        if v.type == "Real":
            return self.fmu.getReal([v.valueReference])[0]
        if v.type in ("Integer", "Enumeration"):
            return self.fmu.getInteger([v.valueReference])[0]
        if v.type == "Boolean":
            return bool(self.fmu.getBoolean([v.valueReference])[0])
        raise TypeError(f"{self.name}.{name}: {v.type}")

    def set(self, name: str, value) -> None:
        v = self.variables[name]
        if v.type == "Real":
            self.fmu.setReal([v.valueReference], [float(value)])
        elif v.type in ("Integer", "Enumeration"):
            self.fmu.setInteger([v.valueReference], [int(value)])
        elif v.type == "Boolean":
            self.fmu.setBoolean([v.valueReference], [bool(value)])
        else:
            self.fmu.setString([v.valueReference], [str(value)])

    def outputs(self) -> list[str]:
        return [n for n, v in self.variables.items() if v.causality == "output" and v.type != "String"]

    def close(self) -> None:
        if self.fmu is not None:
            try:
                self.fmu.terminate()
            finally:
                self.fmu.freeInstance()
                self.fmu = None
        shutil.rmtree(self.unzip, ignore_errors=True)


def run_system(components: list[Comp], connections: list[Connection], stop: float, step: float,
               start: float = 0.0, algorithm: str = "gauss-seidel", record: list[str] | None = None) -> dict[str, np.ndarray]:
    """Runs the system; `components` must be in the Gauss-Seidel order (producers first).

    record: `component.variable` names (default: every non-String output, as the orchestrator).
    Returns a dict with "time" and one array per recorded variable (rows at start and after
    every step).
    """
    by_name = {c.name: c for c in components}
    n_steps = int(round((stop - start) / step))
    slots: dict[str, float] = {}
    into: dict[str, list[Connection]] = {c.name: [] for c in components}
    for k in connections:
        into[k.end.split(".", 1)[0]].append(k)
    produced: dict[str, list[str]] = {c.name: [] for c in components}
    for k in connections:
        comp, var = k.start.split(".", 1)
        if var not in produced[comp]:
            produced[comp].append(var)

    def write_inputs(c: Comp) -> None:
        for k in into[c.name]:
            c.set(k.end.split(".", 1)[1], k.apply(slots.get(k.start, 0.0)))

    def read_outputs(c: Comp) -> None:
        for var in produced[c.name]:
            slots[f"{c.name}.{var}"] = c.get(var)

    if record is None:
        record = []
    rows: list[list[float]] = []
    try:
        for c in components:
            c.load()
        if not record:
            record = [f"{c.name}.{v}" for c in components for v in c.outputs()]

        def sample(t: float) -> None:
            row = [t]
            for r in record:
                comp, var = r.split(".", 1)
                row.append(float(by_name[comp].get(var)))
            rows.append(row)

        for c in components:
            c.fmu.instantiate()
            c.fmu.setupExperiment(startTime=start, stopTime=stop)
        for c in components:
            for name, value in c.parameters.items():
                c.set(name, value)
        for c in components:
            c.fmu.enterInitializationMode()
        for _ in components:
            for c in components:
                write_inputs(c)
                read_outputs(c)
        for c in components:
            c.fmu.exitInitializationMode()
        for c in components:
            read_outputs(c)
        sample(start)

        for k in range(n_steps):
            t = start + k * step
            if algorithm == "gauss-seidel":
                for c in components:
                    write_inputs(c)
                    c.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=step)
                    read_outputs(c)
            elif algorithm == "jacobi":
                for c in components:
                    write_inputs(c)
                for c in components:
                    c.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=step)
                for c in components:
                    read_outputs(c)
            else:
                raise ValueError(algorithm)
            sample(start + (k + 1) * step)
    finally:
        for c in components:
            c.close()
    data = np.array(rows, dtype=np.float64)
    out = {"time": data[:, 0]}
    for i, r in enumerate(record):
        out[r] = data[:, i + 1]
    return out


# ---- the standard case (studies/standard.ssd) -------------------------------------------------

STANDARD_CONNECTIONS = [
    Connection("vehicle.ws_acc_y", "estimator.ws_acc_y"),
    Connection("vehicle.ws_yaw_rate", "estimator.ws_yaw_rate"),
    Connection("vehicle.frame_acc_y", "estimator.frame_acc_y"),
    Connection("vehicle.forward_speed", "estimator.speed"),
]

COMPARED = ("estimator.alignment", "estimator.alignment_std", "vehicle.ws_acc_y", "vehicle.ws_y")


def standard_case(vehicle_fmu: Path, estimator_fmu: Path, stop: float, step: float = 1e-3,
                  algorithm: str = "gauss-seidel", record=COMPARED, **kwargs) -> dict[str, np.ndarray]:
    return run_system([Comp("vehicle", Path(vehicle_fmu)), Comp("estimator", Path(estimator_fmu))],
                      STANDARD_CONNECTIONS, stop=stop, step=step, algorithm=algorithm, record=list(record), **kwargs)


def estimator_alone(estimator_fmu: Path, inputs: np.ndarray, speed: np.ndarray, stop: float, step: float,
                    record=("alignment", "alignment_std")) -> dict[str, np.ndarray]:
    """The estimator by itself: before the step from t_k it gets inputs[k] (ws_acc_y, ws_yaw_rate,
    frame_acc_y) and speed[k]; during initialization inputs[0] and speed[0]."""
    c = Comp("estimator", Path(estimator_fmu))
    names = ("ws_acc_y", "ws_yaw_rate", "frame_acc_y")
    n = int(round(stop / step))
    rows = []
    try:
        c.load()
        c.fmu.instantiate()
        c.fmu.setupExperiment(startTime=0.0, stopTime=stop)
        c.fmu.enterInitializationMode()
        for j, name in enumerate(names):
            c.set(name, inputs[0, j])
        c.set("speed", speed[0])
        c.fmu.exitInitializationMode()
        rows.append([c.get(r) for r in record])
        for k in range(n):
            for j, name in enumerate(names):
                c.set(name, inputs[k, j])
            c.set("speed", speed[k])
            c.fmu.doStep(currentCommunicationPoint=k * step, communicationStepSize=step)
            rows.append([c.get(r) for r in record])
    finally:
        c.close()
    data = np.array(rows, dtype=np.float64)
    return {r: data[:, i] for i, r in enumerate(record)}


# ---- one FMU driven by input signals (`orchestrator simulate` and fmpy.simulate_fmu) ----------

def orchestrator_interpolation(times: np.ndarray, values: np.ndarray, t: float) -> float:
    """orchestrator/src/simulate.rs Signals::at, operation for operation."""
    import bisect

    ts, xs = list(times), list(values)
    if t <= ts[0]:
        return xs[0]
    if t >= ts[-1]:
        return xs[-1]
    i = bisect.bisect_right(ts, t) - 1
    t0, t1 = ts[i], ts[i + 1]
    if t1 == t0:
        return xs[i + 1]
    return xs[i] + (xs[i + 1] - xs[i]) * (t - t0) / (t1 - t0)


def fmpy_interpolation(times: np.ndarray, values: np.ndarray, t: float) -> float:
    """fmpy 0.3.32's own Input.interpolate, as simulate_fmu calls it in co-simulation (after_event=True)."""
    from fmpy.simulation import Input

    v, _ = Input.interpolate(time=t, t=np.asarray(times, dtype=np.float64),
                             table=np.asarray(values, dtype=np.float64).reshape(1, -1), discrete=False, after_event=True)
    return float(np.asarray(v).ravel()[0])


def simulate_single(path: Path, name: str, inputs: dict[str, tuple[np.ndarray, np.ndarray]], stop: float, step: float,
                    parameters: dict | None = None, interpolation=orchestrator_interpolation,
                    step_size: str = "constant", record: list[str] | None = None) -> dict[str, np.ndarray]:
    """One FMU with input signals {input: (times, values)}: before the step from t_k = k*h every
    input is set to interpolation(times, values, t_k); also once in initialization mode at t = 0.
    step_size "constant": doStep(t_k, h) (the orchestrator); "difference": doStep(t_k, t_{k+1} - t_k)
    (fmpy.simulate_fmu, whose next communication point is start + (n + 1) * output_interval)."""
    c = Comp(name, Path(path), dict(parameters or {}))
    n = int(round(stop / step))
    rows = []
    try:
        c.load()
        record = record or c.outputs()

        def set_inputs(t: float) -> None:
            for var, (ts, xs) in inputs.items():
                c.set(var, interpolation(ts, xs, t))

        c.fmu.instantiate()
        c.fmu.setupExperiment(startTime=0.0, stopTime=stop)
        for k, v in c.parameters.items():
            c.set(k, v)
        c.fmu.enterInitializationMode()
        set_inputs(0.0)
        c.fmu.exitInitializationMode()
        rows.append([0.0] + [float(c.get(r)) for r in record])
        for k in range(n):
            t = k * step
            t_next = (k + 1) * step
            set_inputs(t)
            c.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=step if step_size == "constant" else t_next - t)
            rows.append([t_next] + [float(c.get(r)) for r in record])
    finally:
        c.close()
    data = np.array(rows, dtype=np.float64)
    out = {"time": data[:, 0]}
    for i, r in enumerate(record):
        out[r] = data[:, i + 1]
    return out
