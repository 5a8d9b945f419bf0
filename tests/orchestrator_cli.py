"""Helpers for the orchestrator's tests (tests/test_orchestrator*.py) and the studies' (the
`alignment-studies` binary): where the binaries are, how to run them, how to read their results,
how to write small SSP systems, and how to compare numbers.

The binaries are `$ORCHESTRATOR` and `$ALIGNMENT_STUDIES` (set by `cargo xtask test`), else
`<repo>/target/release/<name>`, else they are built once per process with `cargo build --release`.
"""

from __future__ import annotations

import functools
import math
import os
import subprocess
from decimal import Decimal
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from project import REPO, packaged_fmus

# A run of any test system takes well under a second; a hang must not stall the suite.
TIMEOUT = 120


def _binary(env_name: str, package: str, name: str) -> Path:
    env = os.environ.get(env_name)
    if env:
        path = Path(env)
        assert path.is_file(), f"{env_name}={env} is not a file"
        return path
    path = REPO / "target" / "release" / name
    if not path.is_file():
        subprocess.run(["cargo", "build", "--release", "-p", package], cwd=REPO, check=True)
    assert path.is_file(), f"`cargo build --release -p {package}` did not produce {path}"
    return path


@functools.lru_cache(maxsize=None)
def orchestrator_binary() -> Path:
    return _binary("ORCHESTRATOR", "orchestrator", "orchestrator")


@functools.lru_cache(maxsize=None)
def studies_binary() -> Path:
    return _binary("ALIGNMENT_STUDIES", "alignment-studies", "alignment-studies")


# The standard case (vehicle -> estimator, 20 s at 1 ms), shipped with the studies.
STANDARD_SSD = REPO / "studies" / "standard.ssd"


def fmus() -> dict[str, Path]:
    """The four packaged FMUs by model name (built with `cargo xtask fmu` once if one is missing)."""
    return packaged_fmus()


def standard_fmu_args() -> list[str]:
    """The packaged FMUs as `alignment-studies` takes them."""
    f = fmus()
    return ["--vehicle", str(f["RailVehicle"]), "--estimator", str(f["AlignmentEstimator"])]


def standard_case_args() -> list[str]:
    """The standard case as `orchestrator run` and `export-ssp --system` take it: the shipped .ssd
    with the packaged FMUs."""
    f = fmus()
    return [str(STANDARD_SSD), "--fmu", f"vehicle={f['RailVehicle']}", "--fmu", f"estimator={f['AlignmentEstimator']}"]


def studies(*args, **kwargs) -> subprocess.CompletedProcess:
    """Runs `alignment-studies ARGS...`, as [`run`] runs the orchestrator."""
    return run(*args, binary=studies_binary(), **kwargs)


def run(*args, env: dict | None = None, cwd: Path | None = None, check: int | None = 0,
        binary: Path | None = None) -> subprocess.CompletedProcess:
    """Runs `orchestrator ARGS...` (or `binary`); with `check` (default 0) asserts the exit code and
    shows stderr. `env` adds to the environment (a value None removes the variable)."""
    cmd = [str(binary or orchestrator_binary()), *map(str, args)]
    full_env = None
    if env is not None:
        full_env = dict(os.environ)
        for k, v in env.items():
            if v is None:
                full_env.pop(k, None)
            else:
                full_env[k] = v
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=TIMEOUT, env=full_env, cwd=cwd)
    if check is not None:
        assert p.returncode == check, (
            f"{' '.join(cmd)}\nexit code {p.returncode}, expected {check}\nstdout:\n{p.stdout}\nstderr:\n{p.stderr}"
        )
    return p


@dataclass
class Results:
    """results.csv as read back: the header, the raw text fields, and the values parsed with float()."""

    columns: list[str]
    fields: list[list[str]]
    values: np.ndarray  # rows x columns, float64

    def __getitem__(self, name: str) -> np.ndarray:
        return self.values[:, self.columns.index(name)]

    @property
    def time(self) -> np.ndarray:
        return self["time"]


def read_results(path: Path) -> Results:
    """Reads a results.csv (or the directory holding it) with float() on every field, which parses
    ryu's shortest round-trip representation exactly."""
    path = Path(path)
    if path.is_dir():
        path = path / "results.csv"
    lines = path.read_text().splitlines()
    columns = lines[0].split(",")
    fields = [line.split(",") for line in lines[1:]]
    for i, f in enumerate(fields):
        assert len(f) == len(columns), f"{path}: row {i + 2} has {len(f)} fields, the header {len(columns)}"
    values = np.array([[float(x) for x in f] for f in fields], dtype=np.float64).reshape(len(fields), len(columns))
    return Results(columns, fields, values)


def read_units(path: Path) -> tuple[list[str], list[str]]:
    lines = Path(path).read_text().splitlines()
    assert len(lines) == 2, f"{path}: expected a header and one row of units, got {len(lines)} lines"
    return lines[0].split(","), lines[1].split(",")


def rel_diff(a, b) -> np.ndarray:
    """|a - b| / max(|a|, |b|) elementwise (0 where both are 0; inf where one is NaN)."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    scale = np.maximum(np.abs(a), np.abs(b))
    with np.errstate(invalid="ignore", divide="ignore"):
        d = np.where(scale > 0, np.abs(a - b) / np.where(scale > 0, scale, 1.0), 0.0)
    return np.where(np.isnan(a) | np.isnan(b), np.inf, d)


def assert_close(a, b, rtol: float = 1e-12, atol: float = 1e-300, what: str = "") -> float:
    """Asserts |a-b| <= rtol*max(|a|,|b|) + atol everywhere; returns the largest relative difference."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    assert a.shape == b.shape, f"{what}: shapes {a.shape} and {b.shape}"
    bad = ~(np.abs(a - b) <= rtol * np.maximum(np.abs(a), np.abs(b)) + atol)
    if bad.any():
        i = int(np.flatnonzero(bad.ravel())[0])
        raise AssertionError(
            f"{what}: {int(bad.sum())} of {a.size} values differ by more than {rtol:g} relative; "
            f"first at index {i}: {a.ravel()[i]!r} vs {b.ravel()[i]!r}; max relative difference {rel_diff(a, b).max():.3g}"
        )
    return float(rel_diff(a, b).max()) if a.size else 0.0


# ---- SSP 1.0 system descriptions written by hand (docs/references.md section 8.3) -----------------------

SSD_HEADER = """<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription version="1.0" name={name}
    xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
    xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon"
    xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues">
"""


@dataclass
class SsdComponent:
    name: str
    source: Path
    parameters: dict | None = None  # name -> float | int | bool | str
    connectors: list[tuple[str, str, str]] | None = None  # (name, kind, type)


@dataclass
class SsdConnection:
    start: str  # component.variable
    end: str
    factor: float | None = None
    offset: float | None = None


def _ssv_value(value) -> str:
    if isinstance(value, bool):
        return f'<ssv:Boolean value="{str(value).lower()}"/>'
    if isinstance(value, int):
        return f'<ssv:Integer value="{value}"/>'
    if isinstance(value, float):
        return f'<ssv:Real value="{value!r}"/>'
    return f"<ssv:String value={quoteattr(str(value))}/>"


def write_ssd(path: Path, components: list[SsdComponent], connections: list[SsdConnection],
              stop: float | None = None, name: str = "test_system") -> Path:
    """A SystemStructure.ssd with FMU sources as absolute paths (relative references resolve
    against the .ssd's directory, so absolute paths keep the file anywhere)."""
    x = [SSD_HEADER.format(name=quoteattr(name)), '  <ssd:System name="root">\n    <ssd:Elements>\n']
    for c in components:
        x.append(f'      <ssd:Component name={quoteattr(c.name)} type="application/x-fmu-sharedlibrary" '
                 f'source={quoteattr(str(Path(c.source).resolve()))}>\n')
        if c.connectors:
            x.append("        <ssd:Connectors>\n")
            for n, kind, ty in c.connectors:
                x.append(f'          <ssd:Connector name={quoteattr(n)} kind="{kind}"><ssc:{ty}/></ssd:Connector>\n')
            x.append("        </ssd:Connectors>\n")
        if c.parameters:
            x.append("        <ssd:ParameterBindings><ssd:ParameterBinding><ssd:ParameterValues>\n")
            x.append(f"          <ssv:ParameterSet version=\"1.0\" name={quoteattr(c.name + '_parameters')}><ssv:Parameters>\n")
            for n, v in c.parameters.items():
                x.append(f"            <ssv:Parameter name={quoteattr(n)}>{_ssv_value(v)}</ssv:Parameter>\n")
            x.append("          </ssv:Parameters></ssv:ParameterSet>\n")
            x.append("        </ssd:ParameterValues></ssd:ParameterBinding></ssd:ParameterBindings>\n")
        x.append("      </ssd:Component>\n")
    x.append("    </ssd:Elements>\n")
    if connections:
        x.append("    <ssd:Connections>\n")
        for k in connections:
            sc, sv = k.start.split(".", 1)
            ec, ev = k.end.split(".", 1)
            attrs = (f"startElement={quoteattr(sc)} startConnector={quoteattr(sv)} "
                     f"endElement={quoteattr(ec)} endConnector={quoteattr(ev)}")
            if k.factor is None and k.offset is None:
                x.append(f"      <ssd:Connection {attrs}/>\n")
            else:
                x.append(f"      <ssd:Connection {attrs}>\n")
                x.append(f'        <ssc:LinearTransformation factor="{(k.factor if k.factor is not None else 1.0)!r}" '
                         f'offset="{(k.offset if k.offset is not None else 0.0)!r}"/>\n')
                x.append("      </ssd:Connection>\n")
        x.append("    </ssd:Connections>\n")
    x.append("  </ssd:System>\n")
    x.append(f'  <ssd:DefaultExperiment startTime="0"{f" stopTime={quoteattr(repr(stop))}" if stop is not None else ""}/>\n')
    x.append("</ssd:SystemStructureDescription>\n")
    path = Path(path)
    path.write_text("".join(x))
    # A hand-written system must itself be valid SSP 1.0 (fmpy ships the schema), so that what the
    # orchestrator refuses is refused for the reason the test means.
    from lxml import etree
    from fmpy.ssp.ssd import validate_tree

    validate_tree(etree.parse(str(path)).getroot(), "SystemStructureDescription.xsd")
    return path


def shortest_repr_matches(text: str) -> bool:
    """Whether a results field is the shortest round-trip decimal of its value: the same value and
    significant digits as Python's repr (which writes the exponent differently: 1e-7 vs 1e-07)."""
    x = float(text)
    if not math.isfinite(x):
        return text in ("nan", "inf", "-inf")
    return Decimal(text).normalize().as_tuple() == Decimal(repr(x)).normalize().as_tuple()
