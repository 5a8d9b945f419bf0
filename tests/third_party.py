"""FMUs from an independent producer: PythonFMU (PyPI `pythonfmu`, pinned in requirements.txt)
packages a Python class as an FMI 2.0 co-simulation FMU whose binary embeds the Python
interpreter. Two tiny slaves: a first-order lag (a parameter, an input, an output) and a sine
source (parameters, an output).

Loading them outside a Python process: PythonFMU's Linux binary (0.7.0) is not linked against
libpython (PythonFMU PR #187: "on Linux it should not be linked at all as symbols are loaded
through the interpreter"), so it only loads into a process that already has the Python C API
loaded globally: fmpy in a Python interpreter works, a native host such as the orchestrator gets
`undefined symbol: _Py_NoneStruct` from dlopen (the same failure as the FMU Compliance Checker,
PythonFMU issue #202). The remedy for a native host is to preload this interpreter's shared
libpython (LD_PRELOAD); the embedded interpreter then starts from that library's prefix and finds
its standard library (the slaves below need nothing else).
"""

from __future__ import annotations

import os
import subprocess
import sys
import sysconfig
from pathlib import Path

PYTHONFMU_VERSION = "0.7.0"

LAG_SOURCE = '''\
import math

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real


class Lag(Fmi2Slave):
    author = "railway track-geometry toolkit tests"
    description = "first-order lag y' = (gain * u - y) / tau, exact per step with u held"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.tau = 0.5
        self.gain = 1.0
        self.u = 0.0
        self.y = 0.0
        self.register_variable(Real("tau", causality=Fmi2Causality.parameter, variability=Fmi2Variability.tunable))
        self.register_variable(Real("gain", causality=Fmi2Causality.parameter, variability=Fmi2Variability.tunable))
        self.register_variable(Real("u", causality=Fmi2Causality.input))
        self.register_variable(Real("y", causality=Fmi2Causality.output))

    def do_step(self, current_time, step_size):
        e = math.exp(-step_size / self.tau)
        self.y = self.y * e + self.gain * self.u * (1.0 - e)
        return True
'''

SINE_SOURCE = '''\
import math

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real


class Sine(Fmi2Slave):
    author = "railway track-geometry toolkit tests"
    description = "y = offset + amplitude * sin(2 pi frequency t) at the end of each step"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.amplitude = 1.0
        self.frequency = 1.0
        self.offset = 0.0
        self.y = 0.0
        self.register_variable(Real("amplitude", causality=Fmi2Causality.parameter, variability=Fmi2Variability.tunable))
        self.register_variable(Real("frequency", causality=Fmi2Causality.parameter, variability=Fmi2Variability.tunable))
        self.register_variable(Real("offset", causality=Fmi2Causality.parameter, variability=Fmi2Variability.tunable))
        self.register_variable(Real("y", causality=Fmi2Causality.output))

    def exit_initialization_mode(self):
        self.y = self.offset

    def do_step(self, current_time, step_size):
        t = current_time + step_size
        self.y = self.offset + self.amplitude * math.sin(2.0 * math.pi * self.frequency * t)
        return True
'''


def libpython() -> Path | None:
    """This interpreter's shared libpython, or None when it is built without one."""
    if not sysconfig.get_config_var("Py_ENABLE_SHARED"):
        return None
    for name in (sysconfig.get_config_var("INSTSONAME"), sysconfig.get_config_var("LDLIBRARY")):
        if name:
            path = Path(sysconfig.get_config_var("LIBDIR")) / name
            if path.is_file():
                return path
    return None


def native_host_env() -> dict[str, str]:
    """Environment for a native (non-Python) host process loading PythonFMU FMUs."""
    lib = libpython()
    if lib is None:
        raise RuntimeError(
            f"{sys.executable} has no shared libpython (Py_ENABLE_SHARED={sysconfig.get_config_var('Py_ENABLE_SHARED')}): "
            "PythonFMU FMUs cannot be loaded by a native host such as the orchestrator on this machine"
        )
    preload = os.environ.get("LD_PRELOAD", "")
    return {"LD_PRELOAD": f"{lib}:{preload}" if preload else str(lib)}


def pythonfmu_command() -> list[str]:
    return [sys.executable, "-m", "pythonfmu"]


def build_fmus(work: Path) -> dict[str, Path]:
    """Builds Lag.fmu and Sine.fmu in `work` with `pythonfmu build -f FILE -d DIR`."""
    import pythonfmu

    assert pythonfmu.__version__ == PYTHONFMU_VERSION, (
        f"pythonfmu {pythonfmu.__version__} installed, the tests pin {PYTHONFMU_VERSION} (tests/requirements.txt)"
    )
    work = Path(work)
    out = {}
    for name, text in (("Lag", LAG_SOURCE), ("Sine", SINE_SOURCE)):
        script = work / f"{name}.py"
        script.write_text(text)
        p = subprocess.run([*pythonfmu_command(), "build", "-f", str(script), "-d", str(work)],
                           capture_output=True, text=True, timeout=120, cwd=work)
        fmu = work / f"{name}.fmu"
        assert p.returncode == 0 and fmu.is_file(), (
            f"pythonfmu build -f {script} failed (exit {p.returncode}):\n{p.stdout}\n{p.stderr}"
        )
        out[name] = fmu
    return out
