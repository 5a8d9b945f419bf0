"""Low-level access to the estimator FMU for tests of the FMI contract.

Why not only fmpy's high-level API: fmpy raises on any status above fmi2Warning, so a test that
must see the status number (fmi2Error = 3, fmi2Warning = 1) calls the C functions directly
through `Slave.raw(name)`: the ctypes function objects fmpy loaded, argument types set.

Logging: the FMU calls the importer's variadic C logger with the format "%s". ctypes cannot
receive variadic arguments, so fmpy ships a native proxy (fmpy/logging) that formats the
message and forwards it to ONE Python function kept in a C static. We therefore install one
router for the whole process; it dispatches each message by the componentEnvironment pointer
to the LogSink of the instance, and hands messages of any other instance (componentEnvironment
NULL, as fmpy.simulate_fmu passes) to fmpy's default printer, so fmpy behaves as before.
"""

from __future__ import annotations

import itertools
import threading
from ctypes import byref, c_char_p, c_double, c_int, c_uint
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fmpy import calloc, free
from fmpy.fmi1 import printLogMessage
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)
from fmpy.logging import addLoggerProxy
from fmpy.model_description import ModelDescription

OK, WARNING, DISCARD, ERROR, FATAL = 0, 1, 2, 3, 4


@dataclass(frozen=True)
class LogRecord:
    instance_name: str | None
    status: int
    category: str | None
    message: str


@dataclass
class LogSink:
    """The messages one instance sent to its logger."""

    key: int
    records: list[LogRecord] = field(default_factory=list)

    def messages(self, min_status: int = OK) -> list[str]:
        return [r.message for r in self.records if r.status >= min_status]

    def clear(self) -> None:
        self.records.clear()


_sinks: dict[int, LogSink] = {}
_keys = itertools.count(1)
_lock = threading.Lock()


def _decode(b: bytes | None) -> str | None:
    return None if b is None else b.decode("utf-8", errors="replace")


def _route(env, instance_name, status, category, message):
    sink = _sinks.get(env or 0)
    if sink is None:
        printLogMessage(env, instance_name, status, category, message)
    else:
        sink.records.append(LogRecord(_decode(instance_name), status, _decode(category), _decode(message) or ""))


_route_c = fmi2CallbackLoggerTYPE(_route)
_calloc_c = fmi2CallbackAllocateMemoryTYPE(calloc)
_free_c = fmi2CallbackFreeMemoryTYPE(free)


def callbacks() -> tuple[fmi2CallbackFunctions, LogSink]:
    """A callback structure whose messages land in a fresh LogSink (keyed by the
    componentEnvironment value, which the FMU must hand back unchanged)."""
    with _lock:
        key = next(_keys)
        sink = LogSink(key)
        _sinks[key] = sink
    cb = fmi2CallbackFunctions()
    cb.logger = _route_c
    cb.allocateMemory = _calloc_c
    cb.freeMemory = _free_c
    cb.componentEnvironment = key
    addLoggerProxy(byref(cb))  # replaces cb.logger by the native formatter, which calls _route
    return cb, sink


class Slave:
    """One FMU instance: an fmpy FMU2Slave with its own log sink, plus raw calls."""

    def __init__(self, md: ModelDescription, unzip_dir: Path, name: str = "instance", logging_on: bool = False):
        self.md = md
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.fmu = FMU2Slave(
            guid=md.guid, unzipDirectory=str(unzip_dir), modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name
        )
        self.callbacks, self.log = callbacks()
        self.fmu.instantiate(callbacks=self.callbacks, loggingOn=logging_on)

    # --- the usual sequence -------------------------------------------------------------------

    def initialize(self, start_values: dict[str, float] | None = None, strings: dict[str, str] | None = None) -> int:
        """setupExperiment, parameters (each set by its type in the model description: a Boolean
        or Integer parameter takes True or 1), enter and exit initialization; returns the raw status
        of fmi2ExitInitializationMode (so a test can see an error)."""
        self.fmu.setupExperiment(startTime=0.0)
        types = {v.name: v.type for v in self.md.modelVariables}
        for name, value in (start_values or {}).items():
            if types[name] == "Boolean":
                self.fmu.setBoolean([self.vr[name]], [bool(value)])
            elif types[name] == "Integer":
                self.fmu.setInteger([self.vr[name]], [int(value)])
            else:
                self.set_real(name, value)
        for name, value in (strings or {}).items():
            self.fmu.setString([self.vr[name]], [value])
        self.fmu.enterInitializationMode()
        return self.call("fmi2ExitInitializationMode")

    def set_real(self, name: str, value: float) -> None:
        self.fmu.setReal([self.vr[name]], [value])

    def get_reals(self, names: list[str]) -> list[float]:
        return self.fmu.getReal([self.vr[n] for n in names])

    def get_integer(self, name: str) -> int:
        return self.fmu.getInteger([self.vr[name]])[0]

    def step(self, t: float, h: float) -> int:
        """fmi2DoStep, returning the status instead of raising."""
        return self.call("fmi2DoStep", c_double(t), c_double(h), c_int(1))

    # --- raw C calls --------------------------------------------------------------------------

    def raw(self, name: str):
        """The ctypes function `name` of the loaded library (fmpy has set its argument types)."""
        return getattr(self.fmu.dll, name)

    def call(self, name: str, *args) -> int:
        """Calls `name(component, *args)` and returns the status number."""
        return self.raw(name)(self.fmu.component, *args)

    def get_real_status(self, vrs: list[int], values=None) -> int:
        """fmi2GetReal with raw value references (unknown ones allowed); returns the status."""
        arr = (c_uint * len(vrs))(*vrs)
        if values is None:
            values = (c_double * len(vrs))()
        return self.raw("fmi2GetReal")(self.fmu.component, arr, len(vrs), values)

    def set_real_status(self, vrs: list[int], values: list[float]) -> int:
        arr = (c_uint * len(vrs))(*vrs)
        vals = (c_double * len(values))(*values)
        return self.raw("fmi2SetReal")(self.fmu.component, arr, len(vrs), vals)

    def free(self) -> None:
        """Frees the instance (the library stays loaded while other Slaves use it)."""
        if self.fmu.component is not None:
            self.fmu.fmi2FreeInstance(self.fmu.component)
            self.fmu.component = None
        with _lock:
            _sinks.pop(self.log.key, None)
        self.fmu.freeLibrary()


def instantiate_raw(slave: Slave, guid: str, name: str = "raw", resources: bool = True) -> int | None:
    """fmi2Instantiate with an arbitrary GUID through `slave`'s library, with the FMU's resources
    location or (`resources` False) a NULL one; the new component pointer, or None for NULL."""
    cb = slave.callbacks
    uri = (Path(slave.fmu.unzipDirectory) / "resources").as_uri().encode() if resources else None
    f = slave.raw("fmi2Instantiate")
    return f(c_char_p(name.encode()), c_int(1), c_char_p(guid.encode()), c_char_p(uri), byref(cb), c_int(0), c_int(0))


SENSORS = ("ws_acc_y", "ws_yaw_rate", "frame_acc_y")
OUTPUTS = ("alignment", "alignment_std", "distance", "est_y", "est_psi", "est_y_f", "est_vy", "est_psi_rate", "est_vy_f", "nis")


def run_steps(slave: Slave, samples: np.ndarray, t0: float, h: float, speed: float = 20.0) -> np.ndarray:
    """Steps `slave` once per row of `samples` (n x 3: the sensor values at the END of each
    step, see evaluation.input_table) at constant speed; returns the outputs OUTPUTS after each
    step (n x len(OUTPUTS)). Raises if a step returns more than fmi2Warning."""
    in_vr = [slave.vr[n] for n in SENSORS] + [slave.vr["speed"]]
    out_vr = [slave.vr[n] for n in OUTPUTS]
    out = np.empty((samples.shape[0], len(OUTPUTS)))
    for k, row in enumerate(samples):
        slave.fmu.setReal(in_vr, [row[0], row[1], row[2], speed])
        t = t0 + k * h
        status = slave.step(t, h)
        if status > WARNING:
            raise RuntimeError(f"fmi2DoStep({t}, {h}) returned {status}: {slave.log.messages(WARNING)}")
        out[k] = slave.fmu.getReal(out_vr)
    return out


def assert_another_builds_state_is_refused(slave: Slave) -> None:
    """Serializes the slave's current state and checks that a copy whose state-layout
    fingerprint differs (another build) is refused with a message naming the layout. The header
    is RTGS3, the GUID and the build's fingerprint (16 hex digits), each NUL-terminated."""
    state = slave.fmu.getFMUstate()
    blob = slave.fmu.serializeFMUstate(state)
    slave.fmu.freeFMUstate(state)
    magic, _guid, layout = blob.split(b"\0")[:3]
    assert magic == b"RTGS3" and len(layout) == 16
    int(layout, 16)
    changed = layout[:-1] + (b"0" if layout[-1:] != b"0" else b"1")
    other = blob.replace(b"\0" + layout + b"\0", b"\0" + changed + b"\0", 1)
    assert other != blob
    try:
        slave.fmu.deSerializeFMUstate(other)
    except Exception:
        pass
    else:
        raise AssertionError("a state with another layout fingerprint was accepted")
    assert "state layout" in slave.log.messages(ERROR)[-1]


def step_samples(signals: dict[str, np.ndarray]) -> np.ndarray:
    """The n - 1 rows of sensor samples for stepping through a run sampled at n instants: row k
    holds the samples at t_(k+1), the end of step k."""
    return np.column_stack([signals[name][1:] for name in SENSORS])


def slave_factory(model_description, unzip_dir, default_name: str):
    """A fixture body: yields `make(name)` creating instances, and frees them all at the end."""
    slaves: list[Slave] = []

    def make(name: str = default_name, logging_on: bool = False) -> Slave:
        s = Slave(model_description, unzip_dir, name=name, logging_on=logging_on)
        slaves.append(s)
        return s

    yield make
    for s in slaves:
        s.free()
