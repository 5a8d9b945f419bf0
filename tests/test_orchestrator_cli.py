"""The orchestrator's command line as a user meets it (subprocess): help, exit codes (0 success,
2 bad input, 3 an FMU failed during the run, 1 I/O), error messages that name the file, component
and variable, `info`, and `export-ssp` round trips (through the orchestrator and through fmpy).
Systems with Dahlquist/Feedthrough are .ssd files written into each test's tmp dir.
"""

from __future__ import annotations

import uuid
import zipfile

import numpy as np
import fmpy
import pytest

import orchestrator_cli as oc
import orchestrator_pymaster as pm
from orchestrator_cli import SsdComponent as C, SsdConnection as K


@pytest.mark.parametrize("sub", [None, "run", "simulate", "info", "export-ssp"])
def test_help_for_every_subcommand(sub):
    """`orchestrator [SUB] --help`, `-h` and `orchestrator help [SUB]` print the same usage."""
    args = [sub] if sub else []
    p = oc.run(*args, "--help")
    usage = f"Usage: orchestrator {sub}" if sub else "Usage: orchestrator <COMMAND>"
    assert usage in p.stdout, p.stdout
    assert p.stderr == ""
    assert oc.run(*args, "-h").stdout.startswith(p.stdout.split("\n")[0])
    assert usage in oc.run("help", *args).stdout
    if sub is None:
        for s in ("run", "simulate", "info", "export-ssp"):
            assert f"  {s} " in p.stdout
    if sub == "run":
        for option in ("--fmu", "--stop", "--step", "--out", "--record", "--set", "--jacobi"):
            assert option in p.stdout
        # The standard case's own FMU options are the studies' (`alignment-studies run`).
        s = oc.studies("run", "--help").stdout
        for option in ("--vehicle", "--estimator", "--stop", "--step", "--out", "--record", "--set", "--jacobi"):
            assert option in s


def test_no_subcommand_or_unknown_option_is_a_usage_error():
    assert oc.run(check=None).returncode == 2
    p = oc.run("run", "--no-such-option", check=2)
    assert "--no-such-option" in p.stderr


def test_version():
    assert oc.run("--version").stdout.startswith("orchestrator ")


@pytest.fixture
def corrupt_fmu(tmp_path):
    path = tmp_path / "Corrupt.fmu"
    path.write_bytes(np.random.default_rng(3).bytes(4096))
    return path


def test_corrupt_fmu_exit_2_names_the_file(corrupt_fmu, tmp_path):
    f = oc.fmus()
    for args in (["info", corrupt_fmu],
                 ["simulate", corrupt_fmu, "--stop", "1", "--step", "0.1", "--out", tmp_path / "o1"],
                 ["run", oc.STANDARD_SSD, "--fmu", f"vehicle={corrupt_fmu}", "--fmu", f"estimator={f['AlignmentEstimator']}", "--stop", "0.01", "--out", tmp_path / "o2"],
                 ["run", oc.STANDARD_SSD, "--fmu", f"vehicle={f['RailVehicle']}", "--fmu", f"estimator={corrupt_fmu}", "--stop", "0.01", "--out", tmp_path / "o3"]):
        p = oc.run(*args, check=2)
        assert "Corrupt.fmu" in p.stderr, p.stderr
        assert "Traceback" not in p.stderr and "panicked" not in p.stderr, p.stderr
    assert not (tmp_path / "o2").exists() and not (tmp_path / "o3").exists()


def test_missing_fmu_file_exit_2(tmp_path):
    p = oc.run("info", tmp_path / "Nowhere.fmu", check=2)
    assert "Nowhere.fmu" in p.stderr


def _two(tmp_path, connection: K, name="sys.ssd", **kw):
    f = oc.fmus()
    return oc.write_ssd(tmp_path / name, [C("feed", f["Feedthrough"]), C("plant", f["Dahlquist"])], [connection], **kw)


def test_unknown_variable_in_connection_exit_2(tmp_path):
    ssd = _two(tmp_path, K("plant.xx", "feed.u"))
    p = oc.run("run", ssd, "--stop", "1", "--step", "0.1", "--out", tmp_path / "o", check=2)
    assert "'plant'" in p.stderr and "'xx'" in p.stderr and "Dahlquist.fmu" in p.stderr, p.stderr
    assert not (tmp_path / "o" / "results.csv").exists()


def test_unknown_component_in_connection_exit_2(tmp_path):
    ssd = _two(tmp_path, K("plant.x", "nobody.u"))
    p = oc.run("run", ssd, "--stop", "1", "--step", "0.1", "--out", tmp_path / "o", check=2)
    assert "nobody" in p.stderr, p.stderr


def test_input_to_input_connection_exit_2(tmp_path):
    ssd = _two(tmp_path, K("plant.u", "feed.u"))
    p = oc.run("run", ssd, "--stop", "1", "--step", "0.1", "--out", tmp_path / "o", check=2)
    assert "plant.u" in p.stderr and "not an output" in p.stderr, p.stderr


def test_type_mismatch_exit_2(tmp_path):
    """Feedthrough.steps (Integer) -> Dahlquist.u (Real)."""
    ssd = _two(tmp_path, K("feed.steps", "plant.u"))
    p = oc.run("run", ssd, "--stop", "1", "--step", "0.1", "--out", tmp_path / "o", check=2)
    assert "feed.steps" in p.stderr and "plant.u" in p.stderr and "Integer" in p.stderr and "Real" in p.stderr, p.stderr


def test_algebraic_loop_exit_2_names_the_loop(tmp_path):
    """Two Feedthrough FMUs in a ring; y depends directly on u (dependencies="1")."""
    f = oc.fmus()
    ssd = oc.write_ssd(tmp_path / "ring.ssd", [C("a", f["Feedthrough"]), C("b", f["Feedthrough"])],
                       [K("a.y", "b.u"), K("b.y", "a.u")], stop=1.0)
    p = oc.run("run", ssd, "--step", "0.1", "--out", tmp_path / "o", check=2)
    assert "algebraic loop" in p.stderr, p.stderr
    for v in ("a.y", "b.u", "b.y", "a.u"):
        assert v in p.stderr, p.stderr


def test_feedback_through_a_state_is_not_a_loop(tmp_path):
    """Dahlquist's x has no direct feedthrough (dependencies=""): a ring through it is legal."""
    f = oc.fmus()
    ssd = oc.write_ssd(tmp_path / "ring.ssd", [C("plant", f["Dahlquist"]), C("feed", f["Feedthrough"], {"gain": -0.5})],
                       [K("plant.x", "feed.u"), K("feed.y", "plant.u")], stop=1.0)
    oc.run("run", ssd, "--step", "0.1", "--out", tmp_path / "o")
    r = oc.read_results(tmp_path / "o")
    np.testing.assert_array_equal(r["feed.y"], -0.5 * r["plant.x"])
    # a feedback cycle keeps the description order; Jacobi too must match the Python master
    oc.run("run", ssd, "--step", "0.1", "--out", tmp_path / "j", "--jacobi")
    j = oc.read_results(tmp_path / "j")
    for algorithm, res in (("gauss-seidel", r), ("jacobi", j)):
        py = pm.run_system([pm.Comp("plant", f["Dahlquist"]), pm.Comp("feed", f["Feedthrough"], {"gain": -0.5})],
                           [pm.Connection("plant.x", "feed.u"), pm.Connection("feed.y", "plant.u")],
                           stop=1.0, step=0.1, algorithm=algorithm, record=res.columns[1:])
        for c in res.columns:
            np.testing.assert_array_equal(res[c], py[c], err_msg=f"{algorithm}: {c}")
    assert np.any(r["plant.x"] != j["plant.x"])


@pytest.fixture
def chain(tmp_path):
    """plant (Dahlquist) -> feed (Feedthrough); feed listed first (the master orders producers first)."""
    return _two(tmp_path, K("plant.x", "feed.u"), name="chain.ssd", stop=1.0)


def test_fmu_failure_mid_run_exit_3_keeps_results(chain, tmp_path):
    out = tmp_path / "o"
    p = oc.run("run", chain, "--step", "0.1", "--out", out, "--set", "feed.fail_at=0.5", check=3)
    err = p.stderr
    assert "Feedthrough.fmu" in err and "'feed'" in err, err
    assert "fmi2DoStep" in err and "t = 0.5" in err, err
    assert "results.csv" in err, "the message says where the partial results are"
    r = oc.read_results(out)
    np.testing.assert_array_equal(r.time, np.arange(6) * 0.1)  # rows up to t = 0.5, the failing step's start
    assert r.time[-1] == 0.5
    np.testing.assert_array_equal(r["feed.steps"], np.arange(6))
    assert not (out / "results.csv.partial").exists()
    assert (out / "results.units.csv").exists()


def test_set_unknown_variable_exit_2(chain, tmp_path):
    p = oc.run("run", chain, "--step", "0.1", "--out", tmp_path / "o", "--set", "feed.nope=1", check=2)
    assert "nope" in p.stderr and "feed" in p.stderr, p.stderr
    p = oc.run("run", chain, "--step", "0.1", "--out", tmp_path / "o", "--set", "ghost.gain=1", check=2)
    assert "ghost" in p.stderr, p.stderr


@pytest.mark.parametrize("setting, words", [
    ("feed.steps=3", ["feed.steps", "causality"]),  # an output
    ("feed.gain=abc", ["feed.gain", "abc"]),  # not a number
    ("feed.gain", ["feed.gain"]),  # no '='
])
def test_bad_set_exit_2(chain, tmp_path, setting, words):
    p = oc.run("run", chain, "--step", "0.1", "--out", tmp_path / "o", "--set", setting, check=2)
    for w in words:
        assert w in p.stderr, p.stderr


def test_step_not_dividing_the_run_exit_2(chain, tmp_path):
    p = oc.run("run", chain, "--step", "0.3", "--out", tmp_path / "o", check=2)
    assert "0.3" in p.stderr, p.stderr


def test_info_on_the_estimator():
    fmu = oc.fmus()["AlignmentEstimator"]
    p = oc.run("info", fmu)
    out = p.stdout
    # The GUID is made at build time (state-layout crate); fmpy reads the one in the archive.
    guid = fmpy.read_model_description(str(fmu)).guid
    assert guid in out and uuid.UUID(guid).version == 8
    assert "model identifier AlignmentEstimator" in out
    rows = {line.split()[0]: line.split() for line in out.splitlines() if line.startswith("  ") and line.split()}
    for name, causality in (("ws_acc_y", "input"), ("ws_yaw_rate", "input"), ("frame_acc_y", "input"), ("speed", "input"),
                            ("alignment", "output"), ("alignment_std", "output"), ("nis", "output"),
                            ("sigma_acc_ws", "parameter"), ("discretization", "parameter")):
        assert name in rows and rows[name][1] == causality, f"{name}: {rows.get(name)}"
    assert rows["alignment"][3] == "Real" and "m" in rows["alignment"]
    assert rows["skipped_updates"][3] == "Integer" and rows["updated"][3] == "Boolean"
    assert "problem(s)" not in out, out


def test_info_does_not_need_a_loadable_binary(tmp_path):
    """`info` is "like fmpy info": it describes an FMU from its modelDescription.xml, which is how
    a user finds out, among other things, that the FMU has no binary for this platform. A
    Windows-only FMU (binaries/win64 only) must still be described (exit 0), not refused."""
    stripped = tmp_path / "WindowsOnly.fmu"
    with zipfile.ZipFile(oc.fmus()["Dahlquist"]) as src, zipfile.ZipFile(stripped, "w") as dst:
        for item in src.infolist():
            if not item.filename.startswith("binaries/linux64/"):
                dst.writestr(item, src.read(item.filename))
        dst.writestr("binaries/win64/Dahlquist.dll", b"MZ placeholder")
    p = oc.run("info", stripped, check=None)
    assert p.returncode == 0, f"exit code {p.returncode}; stderr: {p.stderr}"
    assert "0b7e1c52-3f2d-4a61-9e58-d1a4c2f7b903" in p.stdout
    for name in ("x", "k", "u", "x0"):
        assert any(line.split()[:1] == [name] for line in p.stdout.splitlines()), p.stdout


def test_export_ssp_round_trip(tmp_path):
    """export-ssp of the standard case, run back by the orchestrator: identical to the shipped
    .ssd's run; and fmpy's SSP reader and master (fmpy.ssp.simulation.simulate_ssp) run it too."""
    ssp = tmp_path / "standard.ssp"
    oc.run("export-ssp", ssp, "--system", *oc.standard_case_args())
    with zipfile.ZipFile(ssp) as z:
        names = set(z.namelist())
    assert {"SystemStructure.ssd", "resources/vehicle.fmu", "resources/estimator.fmu"} <= names

    oc.run("run", ssp, "--stop", "0.5", "--out", tmp_path / "from_ssp", "--quiet")
    oc.run("run", "--stop", "0.5", "--out", tmp_path / "builtin", "--quiet", *oc.standard_case_args())
    a = (tmp_path / "from_ssp" / "results.csv").read_text()
    b = (tmp_path / "builtin" / "results.csv").read_text()
    assert a == b, "the exported system runs to the same results file, byte for byte"
    assert (tmp_path / "from_ssp" / "results.units.csv").read_text() == (tmp_path / "builtin" / "results.units.csv").read_text()
    # SSP 1.0 has no step size: the export's run took the vehicle FMU's default step; it must be
    # the built-in 1 ms for the comparison above to mean something.
    assert len(a.splitlines()) == 502

    from fmpy.ssp.ssd import read_ssd
    from fmpy.ssp.simulation import simulate_ssp

    ssd = read_ssd(str(ssp))  # fmpy validates the .ssd against the SSP 1.0 schema
    assert sorted(c.name for c in ssd.system.elements) == ["estimator", "vehicle"]
    # The three sensors, the roll-rate gyroscope and the speed.
    assert len(ssd.system.connections) == 5

    res = simulate_ssp(str(ssp), stop_time=0.5, step_size=1e-3)
    orch = oc.read_results(tmp_path / "builtin")
    # fmpy's master is Jacobi with connector values starting at 0.0; its row i holds the values
    # after the step from t_i (labelled t_i), and it accumulates time with +=. The vehicle has no
    # connected input: its outputs must be those of the orchestrator's row i + 1.
    n = len(res)
    assert n in (500, 501)
    for name in ("vehicle.ws_acc_y", "vehicle.ws_yaw_rate", "vehicle.frame_acc_y", "vehicle.forward_speed"):
        np.testing.assert_array_equal(res[name][:500], orch[name][1:501], err_msg=name)
    # and what fmpy delivered to the estimator is what the vehicle produced
    np.testing.assert_array_equal(res["estimator.speed"], res["vehicle.forward_speed"])


def test_export_ssp_of_a_system_file(tmp_path):
    """export-ssp --system re-exports an .ssd with parameters and a linear transformation; the
    .ssp runs to the same results as the .ssd."""
    f = oc.fmus()
    ssd = oc.write_ssd(tmp_path / "sys.ssd",
                       [C("plant", f["Dahlquist"], {"k": 2.0, "x0": 1.5}), C("feed", f["Feedthrough"], {"gain": 3.0, "offset": -1.0})],
                       [K("plant.x", "feed.u", 0.5, 0.25)], stop=1.0)
    ssp = tmp_path / "sys.ssp"
    oc.run("export-ssp", ssp, "--system", ssd)
    oc.run("run", ssd, "--step", "0.1", "--out", tmp_path / "a")
    oc.run("run", ssp, "--step", "0.1", "--out", tmp_path / "b")
    a = oc.read_results(tmp_path / "a")
    assert (tmp_path / "a" / "results.csv").read_text() == (tmp_path / "b" / "results.csv").read_text()
    # after the first step (row 0 is the subject of test_orchestrator_results.py's initial-value tests)
    np.testing.assert_array_equal(a["feed.y"][1:], 3.0 * (0.5 * a["plant.x"][1:] + 0.25) - 1.0)
    assert a["plant.x"][0] == 1.5


def test_failure_in_the_first_step_keeps_row_0(chain, tmp_path):
    p = oc.run("run", chain, "--step", "0.1", "--out", tmp_path / "o", "--set", "feed.fail_at=0", check=3)
    assert "t = 0 s" in p.stderr, p.stderr
    r = oc.read_results(tmp_path / "o")
    np.testing.assert_array_equal(r.time, [0.0])


def test_unwritable_output_is_an_io_error_exit_1(chain, tmp_path):
    (tmp_path / "a_file").write_text("")
    p = oc.run("run", chain, "--step", "0.1", "--out", tmp_path / "a_file" / "sub", check=1)
    assert "a_file" in p.stderr, p.stderr


@pytest.mark.parametrize("args, words", [
    (["--step", "0"], ["step"]),
    (["--step=-0.1"], ["step"]),
    (["--start", "2", "--stop", "1", "--step", "0.1"], ["2", "1"]),
])
def test_bad_experiment_exit_2(chain, tmp_path, args, words):
    p = oc.run("run", chain, *args, "--out", tmp_path / "o", check=2)
    for w in words:
        assert w in p.stderr, p.stderr
    assert not (tmp_path / "o" / "results.csv").exists()


def test_malformed_or_missing_system_file_exit_2(tmp_path):
    bad = tmp_path / "broken.ssd"
    bad.write_text("<ssd:SystemStructureDescription>\n<oops")
    p = oc.run("run", bad, "--out", tmp_path / "o", check=2)
    assert "broken.ssd" in p.stderr and "line 2" in p.stderr, p.stderr
    p = oc.run("run", tmp_path / "nowhere.ssd", "--out", tmp_path / "o", check=2)
    assert "nowhere.ssd" in p.stderr, p.stderr


def test_input_fed_twice_and_transformation_on_integer_exit_2(tmp_path):
    f = oc.fmus()
    comps = [C("a", f["Feedthrough"]), C("b", f["Feedthrough"]), C("plant", f["Dahlquist"])]
    ssd = oc.write_ssd(tmp_path / "twice.ssd", comps, [K("a.y", "plant.u"), K("b.y", "plant.u")], stop=1.0)
    p = oc.run("run", ssd, "--step", "0.1", "--out", tmp_path / "o", check=2)
    assert "plant.u" in p.stderr and "a.y" in p.stderr and "b.y" in p.stderr, p.stderr
    ssd = oc.write_ssd(tmp_path / "int.ssd", comps[:2], [K("a.steps", "b.steps", 2.0, 0.0)], stop=1.0)
    p = oc.run("run", ssd, "--step", "0.1", "--out", tmp_path / "o", check=2)
    assert "a.steps" in p.stderr, p.stderr


def test_start_time_other_than_zero(chain, tmp_path):
    """--start 1: rows from t = 1 on integer ticks, the FMUs told startTime 1 (same as a Python
    master doing so)."""
    oc.run("run", chain, "--start", "1", "--stop", "1.5", "--step", "0.1", "--out", tmp_path / "o")
    r = oc.read_results(tmp_path / "o")
    np.testing.assert_array_equal(r.time, 1.0 + np.arange(6) * 0.1)
    f = oc.fmus()
    py = pm.run_system([pm.Comp("plant", f["Dahlquist"]), pm.Comp("feed", f["Feedthrough"])],
                       [pm.Connection("plant.x", "feed.u")], start=1.0, stop=1.5, step=0.1, record=r.columns[1:])
    for c in r.columns:
        np.testing.assert_array_equal(r[c], py[c], err_msg=c)


def test_an_fmu_that_ends_the_simulation_ends_the_run_as_in_fmpy(tmp_path):
    """Issue 14: fmi2Discard with fmi2Terminated ends the run with exit 0 and a last row at the
    FMU's last successful time; fmpy, the oracle, stops at the same time with the same value."""
    import fmpy

    dahlquist = oc.fmus()["Dahlquist"]
    out = tmp_path / "out"
    p = oc.run("simulate", dahlquist, "--stop", "1", "--step", "0.1", "--quiet",
               "--set", "end_at=0.55", "--out", out)
    assert "ended the simulation" in p.stderr, p.stderr
    ours = oc.read_results(out)
    theirs = fmpy.simulate_fmu(str(dahlquist), stop_time=1.0, step_size=0.1, output_interval=0.1,
                               start_values={"end_at": 0.55})
    assert theirs["time"][-1] == pytest.approx(0.55)
    assert ours["time"][-1] == pytest.approx(theirs["time"][-1])
    assert ours["Dahlquist.x"][-1] == pytest.approx(theirs["x"][-1], rel=1e-12)


def test_export_ssp_runs_in_libcosim_without_a_step_and_matches_jacobi(tmp_path):
    """Issue 14: libcosim (through libcosimpy) reads the step from the export's OSP annotation
    (it crashed without an explicit step before); its fixed-step algorithm is Jacobi, so its
    samples equal the orchestrator's --jacobi run. `run` reads the annotation back too."""
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    ssp = tmp_path / "standard.ssp"
    oc.run("export-ssp", ssp, "--system", *oc.standard_case_args())
    ssd = zipfile.ZipFile(ssp).read("SystemStructure.ssd").decode()
    assert 'osp:FixedStepAlgorithm baseStepSize="0.001"' in ssd
    assert 'oms:FixedStepMaster description="oms-ma" stepSize="0.001"' in ssd

    log_output_level(CosimLogLevel.WARNING)
    ex = CosimExecution.from_ssp_file(str(ssp))  # no step size given
    observer = CosimObserver.create_time_series()
    ex.add_observer(observer)
    names = {("vehicle", "ws_acc_y"): CosimVariableType.REAL, ("estimator", "alignment"): CosimVariableType.REAL,
             ("estimator", "rebuilds"): CosimVariableType.INTEGER}
    refs = {}
    for (component, variable), kind in names.items():
        index = ex.slave_index_from_instance_name(component)
        reference = {v.name.decode(): v.reference for v in ex.slave_variables(index)}[variable]
        refs[component, variable] = (index, reference)
        observer.start_time_series(index, reference, kind)
    assert ex.simulate_until(int(0.5e9))  # nanoseconds

    oc.run("run", ssp, "--stop", "0.5", "--jacobi", "--quiet", "--out", tmp_path / "jacobi")
    ours = oc.read_results(tmp_path / "jacobi")
    assert len(ours["time"]) == 501, "run stepped at the annotated 1 ms"
    for component, variable in [("vehicle", "ws_acc_y"), ("estimator", "alignment")]:
        times, _, values = observer.time_series_real_samples(*refs[component, variable], 0, 600)
        n = len(values)
        assert n >= 500
        np.testing.assert_array_equal(times, np.arange(n) * 1_000_000)  # ns
        # libcosim's steps are differences of a nanosecond clock (1 ms +- 1 ulp): the vehicle's
        # contact dynamics carry that rounding up to about 1e-5 of the signal's rms in 0.5 s.
        want = ours[f"{component}.{variable}"][:n]
        rms = np.sqrt(np.mean(want**2))
        np.testing.assert_allclose(values, want, rtol=0, atol=1e-4 * rms, err_msg=f"{component}.{variable}")
    _, _, rebuilds = observer.time_series_integer_samples(*refs["estimator", "rebuilds"], 0, 600)
    assert max(rebuilds) == 1, "libcosim's nanosecond clock does not rebuild the filter"


def test_an_output_directory_has_a_manifest_and_no_stale_files(chain, tmp_path):
    """Issue 14: manifest.json traces a result (command line, --set, each FMU's GUID and
    SHA-256, time, files); a later run into the same directory removes the files of the earlier
    one it would otherwise leave stale (the standard case's metrics.json beside a new results.csv).
    The standard case with its metrics is `alignment-studies run`, which writes its results
    through the master's output directory; the orchestrator's next run clears them."""
    import hashlib
    import json

    out = tmp_path / "out"
    oc.studies("run", "--stop", "5", "--quiet", "--out", out, "--set", "vehicle.track_seed=3", *oc.standard_fmu_args())
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["settings"] == ["vehicle.track_seed=3"]
    assert "--stop" in manifest["command"] and manifest["program"].startswith("alignment-studies ")
    assert manifest["time_utc"].endswith("Z") and len(manifest["time_utc"]) == 20
    assert manifest["files"] == ["results.csv", "results.units.csv", "metrics.json"]
    for record in manifest["fmus"]:
        path = oc.fmus()["RailVehicle" if record["component"] == "vehicle" else "AlignmentEstimator"]
        assert record["sha256"] == hashlib.sha256(path.read_bytes()).hexdigest()
        guid = zipfile.ZipFile(path).read("modelDescription.xml").decode().split('guid="')[1].split('"')[0]
        assert record["guid"] == guid
    assert (out / "metrics.json").exists()

    oc.run("run", chain, "--step", "0.1", "--quiet", "--out", out)
    assert not (out / "metrics.json").exists(), "the earlier run's metrics would describe another run"
    assert oc.read_results(out).columns[1:] != []
    second = json.loads((out / "manifest.json").read_text())
    assert second["files"] == ["results.csv", "results.units.csv"]
    assert second["program"].startswith("orchestrator ")


def test_a_second_run_into_a_busy_output_directory_is_refused(tmp_path):
    """Issue 14: two runs into one directory mixed their rows; the second now stops at once with
    exit 1, naming the directory, and the first finishes untouched."""
    import signal
    import subprocess
    import time

    out = tmp_path / "out"
    first = subprocess.Popen([str(oc.orchestrator_binary()), "simulate", str(oc.fmus()["Dahlquist"]),
                              # 1e8 steps: an estimated 4 GB, under the 10 GB limit.
                              "--stop", "100000", "--step", "0.001", "--quiet", "--out", str(out)],
                             stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 60
        while not (out / "results.csv.partial").exists():
            assert time.monotonic() < deadline and first.poll() is None, "the first run did not start"
            time.sleep(0.02)
        p = oc.run("simulate", oc.fmus()["Dahlquist"], "--stop", "1", "--step", "0.1", "--quiet",
                   "--out", out, check=1)
        assert "being written by another run" in p.stderr and str(out) in p.stderr, p.stderr
    finally:
        first.send_signal(signal.SIGINT)
        first.wait(timeout=60)
    assert first.returncode == 130
    rows = (out / "results.csv").read_text().splitlines()
    assert all(len(r.split(",")) == 2 for r in rows), "whole rows of the first run only"


def test_smooth_refuses_to_replace_a_symlink(tmp_path):
    """Issue 14: `smooth --out` given a symlink (or a device) refuses it instead of replacing it."""
    csv = tmp_path / "recorded.csv"
    csv.write_text("time,speed,ws_acc_y,ws_yaw_rate,frame_acc_y\n" + "".join(f"{k * 1e-3},20,0,0,0\n" for k in range(3000)))
    target = tmp_path / "target.csv"
    target.write_text("keep me\n")
    link = tmp_path / "link.csv"
    link.symlink_to(target)
    p = oc.studies("smooth", csv, "--out", link, check=None)
    assert p.returncode != 0 and "symbolic link" in p.stderr and str(link) in p.stderr, p.stderr
    assert link.is_symlink() and target.read_text() == "keep me\n"


def test_simulate_input_holds_discrete_inputs_and_takes_integers_and_booleans(tmp_path):
    """Issue 14: discrete Real, Integer and Boolean inputs are held between rows (fmpy does the
    same; they were interpolated, or refused), component-prefixed and quoted column names are
    accepted, and Integer and Boolean outputs are written as whole numbers."""
    import fmpy

    feed = oc.fmus()["Feedthrough"]
    signals = tmp_path / "signals.csv"
    signals.write_text('\ufeff"time","feed.u",ud,n_in,flag_in\n0,0,0,0,0\n1,10,10,5,true\n2,20,20,7,false\n')
    out = tmp_path / "out"
    oc.run("simulate", feed, "--input", signals, "--stop", "2", "--step", "0.25", "--quiet", "--out", out)
    r = oc.read_results(out)
    t = np.asarray(r["time"])
    # y = u (continuous: interpolated at the start of each step, feedthrough), yd = ud held.
    np.testing.assert_allclose(r["Feedthrough.y"][1:], 10 * t[:-1] + 0 * t[1:], atol=1e-12)
    held = np.floor(t[:-1] + 1e-12) * 10
    np.testing.assert_array_equal(r["Feedthrough.yd"][1:], held)
    np.testing.assert_array_equal(r["Feedthrough.n_out"][1:], np.array([0, 5, 7])[np.floor(t[:-1] + 1e-12).astype(int)])
    np.testing.assert_array_equal(r["Feedthrough.flag_out"][1:], (np.floor(t[:-1] + 1e-12) == 1).astype(float))
    rows = (out / "results.csv").read_text().splitlines()
    header = rows[0].split(",")
    last = dict(zip(header, rows[-1].split(",")))
    # The last step (from 1.75 s) read the row of t = 1.
    assert last["Feedthrough.n_out"] == "5" and last["Feedthrough.flag_out"] == "1", last

    # fmpy, the oracle, holds the discrete ones the same way.
    dtype = [("time", float), ("u", float), ("ud", float), ("n_in", np.int32), ("flag_in", np.bool_)]
    table = np.array([(0, 0, 0, 0, False), (1, 10, 10, 5, True), (2, 20, 20, 7, False)], dtype=dtype)
    theirs = fmpy.simulate_fmu(str(feed), stop_time=2.0, step_size=0.25, output_interval=0.25, input=table,
                               output=["yd", "n_out", "flag_out"])
    np.testing.assert_array_equal(theirs["yd"][1:], r["Feedthrough.yd"][1:len(theirs)])
    np.testing.assert_array_equal(theirs["n_out"][1:], r["Feedthrough.n_out"][1:len(theirs)])


def test_simulate_replay_feeds_a_record_back_in_step(tmp_path):
    """Issue 14: a recorded results.csv replayed through `simulate --input` is one step late;
    `--replay` replays it exactly: the estimator alone, fed the vehicle columns of a standard
    run, reproduces that run's alignment bit for bit."""
    run_dir = tmp_path / "run"
    oc.run("run", "--stop", "1", "--quiet", "--out", run_dir, "--set", "estimator.estimator=1",
           "--record", "vehicle.ws_acc_y,vehicle.ws_yaw_rate,vehicle.frame_acc_y,vehicle.forward_speed,estimator.alignment",
           *oc.standard_case_args())
    rec = oc.read_results(run_dir)
    signals = tmp_path / "signals.csv"
    names = ["ws_acc_y", "ws_yaw_rate", "frame_acc_y", "speed"]
    cols = [rec[f"vehicle.{n if n != 'speed' else 'forward_speed'}"] for n in names]
    lines = ["time," + ",".join(names)] + [",".join(repr(float(x)) for x in (t, *row))
                                          for t, *row in zip(rec["time"], *cols)]
    signals.write_text("\n".join(lines) + "\n")
    est = oc.fmus()["AlignmentEstimator"]
    for replay, exact in [(True, True), (False, False)]:
        out = tmp_path / f"replay_{replay}"
        args = ["simulate", est, "--input", signals, "--stop", "1", "--step", "0.001", "--quiet",
                "--set", "estimator=1", "--out", out] + (["--replay"] if replay else [])
        oc.run(*args)
        got = oc.read_results(out)["AlignmentEstimator.alignment"]
        same = np.array_equal(got, rec["estimator.alignment"])
        assert same == exact, (replay, np.max(np.abs(got - rec["estimator.alignment"])))
