"""The golden files (tests/golden/README.md): each packaged FMU, run on its `_in.csv` with the
parameters of its case, reproduces its `_ref.csv` column by column, through fmpy and through
our own master (`orchestrator simulate`), so that two importers agree with the reference; the
estimator's references also through the Python bindings' offline path (`estimate`).

Oracle: the references on disk, written by tests/golden/regenerate.py from an earlier build;
a change of any output fails here until the references are regenerated on purpose.

Tolerance (tests/golden_cases.py, where each figure is derived): a Real value passes when
`|run - ref| <= 1e-9 |ref| + 1e-9 max|ref column|`. The FMUs are deterministic, so fmpy on the
same build reproduces the reference bit for bit; the slack covers another machine's libm (an
ulp in sin, cos or exp) and what the filters make of it, and it is 100 times below the
smallest change the test must catch (a tap bank refitted to the last f32 digit moves
`alignment` by 1.2e-7 of its largest value). Integer and Boolean outputs must be equal. Our
master's clock passes the step as `h` where fmpy passes `(k + 1) h - k h`, so between the two
importers the FMUs see steps an ulp apart; the comparisons through the master and the
bindings (which also step by `h`) allow the measured effect of that, per FMU
(golden_cases.MASTER_ATOL_OF_SCALE: 1e-8 of a column's largest value for the estimator, 2e-5
for the vehicle).
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
import pytest

import golden_cases as g
import orchestrator_cli as oc
from project import packaged_fmus

CASES = g.cases()


@functools.lru_cache(maxsize=None)
def fmpy_run(name: str) -> g.Table:
    """The case through fmpy, every step (shared by the tests below)."""
    case = next(c for c in CASES if c.name == name)
    return g.run_fmpy(case, packaged_fmus()[case.fmu], every_step=True)


def decimated(case: g.Case, run: g.Table) -> g.Table:
    return g.Table(run.names, run.values[:: case.every])


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_the_reference_holds_every_output_at_every_interval(case):
    names, _ = g.outputs(packaged_fmus()[case.fmu])
    ref = g.read_table(case.ref)
    assert ref.names == ["time", *names], (
        f"{case.ref} has the columns {ref.names}, the FMU's outputs are {names}: "
        "regenerate it (tests/golden/README.md)"
    )
    expected = np.arange(case.steps // case.every + 1) * case.interval
    assert np.allclose(ref.column("time"), expected, rtol=0, atol=1e-12), f"{case.ref}: times are not 0, {case.interval}, ... {case.stop}"


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_fmpy_reproduces_the_reference(case):
    _, discrete = g.outputs(packaged_fmus()[case.fmu])
    bad = g.failures(g.compare(g.read_table(case.ref), decimated(case, fmpy_run(case.name)), discrete))
    assert not bad, f"{case.name} ({case.about}) differs from {case.ref}:\n" + "\n".join(bad)


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_our_master_agrees_with_fmpy_and_the_reference(case, tmp_path):
    fmu = packaged_fmus()[case.fmu]
    _, discrete = g.outputs(fmu)
    oc.run(*g.orchestrator_args(case, fmu, tmp_path / "out"))
    ours = g.orchestrator_table(case, fmu, oc.read_results(tmp_path / "out"))
    atol = g.MASTER_ATOL_OF_SCALE[case.fmu]
    bad = g.failures(g.compare(fmpy_run(case.name), ours, discrete, atol))
    assert not bad, f"{case.name}: orchestrator simulate against fmpy, every step:\n" + "\n".join(bad)
    bad = g.failures(g.compare(g.read_table(case.ref), decimated(case, ours), discrete, atol))
    assert not bad, f"{case.name}: orchestrator simulate against {case.ref}:\n" + "\n".join(bad)


def test_the_comparison_flags_changes_the_size_of_a_refitted_tap_bank():
    """The comparison itself: a reference moved by 1e-7 of its column's largest value (a tap
    bank refitted to the last f32 digit moves `alignment` by 1.2e-7), an active estimator
    changed, or a NaN is flagged, each in its own column; a move of 1e-12 relative (rounding)
    is not."""
    case = next(c for c in CASES if c.name == "AlignmentEstimator")
    _, discrete = g.outputs(packaged_fmus()[case.fmu])
    ref = g.read_table(case.ref)
    assert not g.failures(g.compare(ref, ref, discrete))

    def changed(column: str, row: int, value) -> list[str]:
        run = dataclasses.replace(ref, values=ref.values.copy())
        run.values[row, ref.names.index(column)] = value(run.values[row, ref.names.index(column)])
        return g.failures(g.compare(ref, run, discrete))

    row = len(ref.values) - 1
    scale = np.max(np.abs(ref.column("alignment")))
    bad = changed("alignment", row, lambda x: x + 1e-7 * scale)
    assert len(bad) == 1 and bad[0].startswith("alignment: 1 value(s)"), bad
    assert not changed("alignment", row, lambda x: x * (1 + 1e-12))
    assert len(changed("active_estimator", row, lambda x: 3 - x)) == 1
    assert len(changed("contact_scale", row, lambda x: np.nan)) == 1


ESTIMATOR_CASES = [c for c in CASES if c.fmu == "AlignmentEstimator"]


@pytest.mark.parametrize("case", ESTIMATOR_CASES, ids=[c.name for c in ESTIMATOR_CASES])
def test_the_bindings_offline_path_agrees_with_the_references(case):
    """A third path: the Python bindings' `estimate` (the estimator's offline code, stepped by
    exactly `step` as our master steps) on the same input. Its sample `k` is the input's row
    `k` (read for the step ending at `(k + 1) h`), so the reference's row at `j * interval`
    is its sample `j * every - 1`; row 0, before any step, has no sample."""
    native = pytest.importorskip("track_alignment._native", reason="the bindings are built into .venv by `cargo xtask test`")
    _, discrete = g.outputs(packaged_fmus()[case.fmu])
    inp = g.read_table(case.input)
    col = {n: np.ascontiguousarray(inp.column(n)) for n in inp.names}
    out = native.estimate(col["speed"], col["ws_acc_y"], col["ws_yaw_rate"], col["frame_acc_y"], step=case.step,
                          ws_roll_rate=col["ws_roll_rate"], settings=dict(case.parameters))
    ref = g.read_table(case.ref)
    names = [n for n in ref.names[1:] if isinstance(out.get(n), np.ndarray)]
    assert {"alignment", "alignment_lagged", "alignment_kalman", "active_estimator", "contact_scale"} <= set(names), names
    rows = np.arange(1, len(ref.values)) * case.every - 1
    ours = g.Table(names, np.column_stack([np.asarray(out[n], dtype=np.float64)[rows] for n in names]))
    theirs = g.Table(names, np.column_stack([ref.column(n)[1:] for n in names]))
    bad = g.failures(g.compare(theirs, ours, discrete, g.MASTER_ATOL_OF_SCALE[case.fmu]))
    assert not bad, f"{case.name}: the bindings' estimate against {case.ref}:\n" + "\n".join(bad)
