"""The orchestrator's results files: results.csv has `time` then one `component.variable` column
per recorded variable (by default every non-String output, components in system order, variables
in modelDescription order), one row at t = start after initialization and one per step (or per
--interval); results.units.csv beside it holds the same header and one row of units. Every number
is written as the shortest decimal that parses back to the same double, and equals what fmpy
reads from the same FMUs. Also: initial values through a direct-feedthrough connection (row 0).
"""

from __future__ import annotations

import math

import fmpy
import numpy as np
import pytest

import orchestrator_cli as oc
import orchestrator_pymaster as pm
from orchestrator_cli import SsdComponent as C, SsdConnection as K


def _outputs(path):
    md = fmpy.read_model_description(str(path))
    return [v for v in md.modelVariables if v.causality == "output" and v.type != "String"]


@pytest.fixture(scope="module")
def standard(tmp_path_factory):
    out = tmp_path_factory.mktemp("standard")
    oc.run("run", "--stop", "0.2", "--out", out, "--quiet", *oc.standard_case_args())
    return out


def test_header_is_time_then_every_output(standard):
    f = oc.fmus()
    r = oc.read_results(standard)
    expected = ["time"] + [f"vehicle.{v.name}" for v in _outputs(f["RailVehicle"])] + \
               [f"estimator.{v.name}" for v in _outputs(f["AlignmentEstimator"])]
    assert r.columns == expected
    assert len(r.time) == 201


def test_units_file_beside_results(standard):
    f = oc.fmus()
    header, units = oc.read_units(standard / "results.units.csv")
    assert header == (standard / "results.csv").read_text().splitlines()[0].split(",")
    expected = ["s"] + [v.unit or "" for v in _outputs(f["RailVehicle"])] + [v.unit or "" for v in _outputs(f["AlignmentEstimator"])]
    assert units == expected
    by_name = dict(zip(header, units))
    assert by_name["vehicle.ws_acc_y"] == "m/s2" and by_name["estimator.alignment"] == "m"
    assert by_name["estimator.skipped_updates"] == "" and by_name["estimator.updated"] == ""


def test_numbers_are_shortest_round_trip(standard):
    r = oc.read_results(standard)
    bad = [(i, j, x) for i, row in enumerate(r.fields) for j, x in enumerate(row) if not oc.shortest_repr_matches(x)]
    assert not bad, f"{len(bad)} fields are not the shortest round-trip decimal, e.g. {bad[:5]}"
    # and the file holds real information in full precision
    assert any(len(x) >= 17 for row in r.fields for x in row)


@pytest.fixture(scope="module")
def chain(tmp_path_factory):
    """plant (Dahlquist, k = 0.7) -> feed (Feedthrough, gain 1/3, offset -0.1); feed listed first."""
    d = tmp_path_factory.mktemp("chain")
    f = oc.fmus()
    ssd = oc.write_ssd(d / "chain.ssd",
                       [C("feed", f["Feedthrough"], {"gain": 1.0 / 3.0, "offset": -0.1, "flag_in": True}),
                        C("plant", f["Dahlquist"], {"k": 0.7})],
                       [K("plant.x", "feed.u")], stop=1.0)
    return ssd


def test_values_equal_fmpy_readings(chain, tmp_path):
    """Every recorded value, parsed back, is bit-identical to what fmpy's FMU2Slave reads from the
    same FMUs stepped the same way (Real, Integer and Boolean columns)."""
    oc.run("run", chain, "--step", "0.05", "--out", tmp_path)
    r = oc.read_results(tmp_path)
    assert r.columns == ["time", "feed.y", "feed.steps", "feed.yd", "feed.n_out", "feed.flag_out", "plant.x"]
    f = oc.fmus()
    py = pm.run_system([pm.Comp("plant", f["Dahlquist"], {"k": 0.7}),
                        pm.Comp("feed", f["Feedthrough"], {"gain": 1.0 / 3.0, "offset": -0.1, "flag_in": True})],
                       [pm.Connection("plant.x", "feed.u")], stop=1.0, step=0.05, record=r.columns[1:])
    for c in r.columns:
        np.testing.assert_array_equal(r[c], py[c], err_msg=c)
    np.testing.assert_array_equal(r["feed.steps"], np.arange(21))
    np.testing.assert_array_equal(r["feed.flag_out"], [0.0] + [1.0] * 20)  # flag_in passed through at each step
    # a few by hand: x_{k+1} = x_k exp(-k h) (libm's exp, as the FMU), y = x / 3 - 0.1
    x = 1.0
    for k in range(1, 4):
        x = x * math.exp(-0.7 * 0.05)
        assert r["plant.x"][k] == x
        assert r["feed.y"][k] == 1.0 / 3.0 * x + -0.1
    assert r.fields[1][r.columns.index("feed.y")] == repr(float(r["feed.y"][1]))


def test_record_selection_and_interval(chain, tmp_path):
    oc.run("run", chain, "--step", "0.05", "--out", tmp_path / "all")
    oc.run("run", chain, "--step", "0.05", "--out", tmp_path / "some", "--record", "plant.x,feed.y", "--interval", "0.2")
    full, some = oc.read_results(tmp_path / "all"), oc.read_results(tmp_path / "some")
    assert some.columns == ["time", "plant.x", "feed.y"]
    np.testing.assert_array_equal(some.time, full.time[::4])
    np.testing.assert_array_equal(some.time, np.arange(6) * 0.2)
    for c in ("plant.x", "feed.y"):
        np.testing.assert_array_equal(some[c], full[c][::4])
    header, units = oc.read_units(tmp_path / "some" / "results.units.csv")
    assert header == some.columns and units == ["s", "1", "1"]
    # errors in the selection
    p = oc.run("run", chain, "--step", "0.05", "--out", tmp_path / "x", "--record", "plant.nope", check=2)
    assert "plant.nope" in p.stderr
    p = oc.run("run", chain, "--step", "0.05", "--out", tmp_path / "x", "--interval", "0.07", check=2)
    assert "0.07" in p.stderr


def test_no_record_writes_nothing(chain, tmp_path):
    oc.run("run", chain, "--step", "0.05", "--out", tmp_path / "o", "--no-record")
    assert not (tmp_path / "o" / "results.csv").exists()


# ---- initial values (row 0) ----------------------------------------------------------------


def test_row0_is_consistent_through_direct_feedthrough(tmp_path):
    """Row 0 (t = start, after initialization) must show the values the FMUs start from, with
    connected inputs holding their producers' initial outputs: with plant.x0 = 1.5, feed.y(0) =
    gain * plant.x(0) + offset. The orchestrator propagates initial values in initialization mode
    (master.rs), so this holds only if each FMU reports its initial outputs there."""
    f = oc.fmus()
    ssd = oc.write_ssd(tmp_path / "chain.ssd",
                       [C("feed", f["Feedthrough"], {"gain": 2.0, "offset": 0.5}), C("plant", f["Dahlquist"], {"x0": 1.5})],
                       [K("plant.x", "feed.u")], stop=1.0)
    oc.run("run", ssd, "--step", "0.1", "--out", tmp_path / "o")
    r = oc.read_results(tmp_path / "o")
    assert r["plant.x"][0] == 1.5
    np.testing.assert_array_equal(r["feed.y"][1:], 2.0 * r["plant.x"][1:] + 0.5)
    assert r["feed.y"][0] == 2.0 * 1.5 + 0.5, (
        f"row 0: plant.x = {r['plant.x'][0]} but feed.y = {r['feed.y'][0]} = 2 * {(r['feed.y'][0] - 0.5) / 2} + 0.5: "
        "feed.u got plant.x's value in initialization mode, which is not its initial value"
    )


@pytest.mark.parametrize("fmu, parameters", [
    ("Dahlquist", {}),
    ("Dahlquist", {"x0": 1.5}),
    ("Feedthrough", {"gain": 2.0, "offset": 0.5}),
    ("RailVehicle", {}),
    ("AlignmentEstimator", {}),
])
def test_outputs_in_initialization_mode_are_the_initial_values(fmu, parameters):
    """What the orchestrator's initial-value propagation relies on (FMI 2.0: in Initialization
    Mode outputs can be read; an output declared initial="exact" has its start value as initial
    value, a calculated one is computed from the parameters): every output read in
    initialization mode equals the value read right after fmi2ExitInitializationMode (nothing
    happens in between: no step, no input change)."""
    c = pm.Comp("c", oc.fmus()[fmu], dict(parameters))
    try:
        c.load()
        c.fmu.instantiate()
        c.fmu.setupExperiment(startTime=0.0, stopTime=1.0)
        for k, v in c.parameters.items():
            c.set(k, v)
        c.fmu.enterInitializationMode()
        during = {o: c.get(o) for o in c.outputs()}
        c.fmu.exitInitializationMode()
        after = {o: c.get(o) for o in c.outputs()}
    finally:
        c.close()
    changed = {o: (during[o], after[o]) for o in during if not (during[o] == after[o] or (during[o] != during[o] and after[o] != after[o]))}
    declared = {v.name: (v.initial, v.start) for v in fmpy.read_model_description(str(oc.fmus()[fmu])).modelVariables}
    assert not changed, (
        f"{fmu} {parameters}: outputs change at fmi2ExitInitializationMode (in init mode -> after): "
        + ", ".join(f"{o}: {a!r} -> {b!r} (declared initial={declared[o][0]}, start={declared[o][1]})" for o, (a, b) in changed.items())
    )
