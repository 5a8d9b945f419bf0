"""The orchestrator with FMUs it did not produce: PythonFMU (an independent FMU exporter, pinned in
tests/requirements.txt) builds FMI 2.0 co-simulation FMUs from Python classes (tests/third_party.py).

- `orchestrator info` describes them;
- `orchestrator simulate FMU --input in.csv` gives what fmpy.simulate_fmu gives with the same
  input, to 1e-12 relative; the residual (a few ulp) is explained exactly: both are reproduced
  bit for bit by a Python loop that differs only in the two documented places (how the input is
  interpolated, and which step size is passed to fmi2DoStep);
- an SSP system (written by hand) connecting a PythonFMU source to our Dahlquist FMU through a
  linear transformation runs in the orchestrator and gives the values of a Python FMU2Slave loop.

PythonFMU's Linux binary needs the host to provide libpython's symbols (see third_party.py): the
orchestrator is run with this interpreter's libpython preloaded, and a test shows the plain
failure without it.
"""

from __future__ import annotations

import fmpy
import numpy as np
import pytest

import orchestrator_cli as oc
import orchestrator_pymaster as pm
import third_party as tp

# Input signal for the lag: a ramp whose breakpoints fall between communication points, a jump
# at a communication point (two rows with t = 0.5), and a hold after the last row.
INPUT_T = np.array([0.0, 0.37, 0.5, 0.5, 1.23])
INPUT_U = np.array([0.0, 1.0, 1.0, -0.5, 0.25])
LAG_PARAMETERS = {"tau": 0.3, "gain": 2.0}
STOP, STEP = 1.5, 0.05


@pytest.fixture(scope="module")
def pyfmus(tmp_path_factory):
    return tp.build_fmus(tmp_path_factory.mktemp("pythonfmu"))


@pytest.fixture(scope="module")
def host_env():
    """LD_PRELOAD of this interpreter's libpython, without which a native host cannot load
    PythonFMU's binary (fails rather than skips when the interpreter has no shared libpython)."""
    return tp.native_host_env()


def test_pythonfmu_fmus_are_fmi2_cosimulation(pyfmus):
    for name, path in pyfmus.items():
        md = fmpy.read_model_description(str(path))
        assert md.fmiVersion == "2.0" and md.coSimulation is not None
        assert md.coSimulation.modelIdentifier == name
        assert md.generationTool == f"PythonFMU {tp.PYTHONFMU_VERSION}"


def test_native_host_without_libpython_fails_clearly(pyfmus, tmp_path):
    """What a user of the orchestrator sees with a PythonFMU FMU when libpython is not preloaded:
    exit code 2 (bad input), the FMU's file and the loader's reason."""
    env = {"LD_PRELOAD": None}
    p = oc.run("simulate", pyfmus["Lag"], "--stop", "0.1", "--step", "0.05", "--out", tmp_path, "--quiet",
               env=env, check=2)
    assert "Lag.fmu" in p.stderr and "undefined symbol" in p.stderr, p.stderr
    assert not (tmp_path / "results.csv").exists()


def test_info_describes_pythonfmu_fmus(pyfmus, host_env):
    for name, expected in (("Lag", {"tau": "parameter", "gain": "parameter", "u": "input", "y": "output"}),
                           ("Sine", {"amplitude": "parameter", "frequency": "parameter", "offset": "parameter", "y": "output"})):
        p = oc.run("info", pyfmus[name], env=host_env)
        md = fmpy.read_model_description(str(pyfmus[name]))
        assert md.guid in p.stdout
        assert f"model identifier {name}" in p.stdout
        assert f"PythonFMU {tp.PYTHONFMU_VERSION}" in p.stdout
        lines = {line.split()[0]: line.split() for line in p.stdout.splitlines()[1:] if line.startswith("  ") and line.split()}
        for var, causality in expected.items():
            assert var in lines and lines[var][1] == causality, f"{name}.{var}: {lines.get(var)}\n{p.stdout}"
        print(f"\norchestrator info {name}.fmu:\n{p.stdout}")


def _write_input(path):
    lines = ["time,u"] + [f"{float(t)!r},{float(u)!r}" for t, u in zip(INPUT_T, INPUT_U)]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_simulate_matches_fmpy_simulate_fmu(pyfmus, host_env, tmp_path):
    fmu = pyfmus["Lag"]
    inp = _write_input(tmp_path / "in.csv")
    out = tmp_path / "out"
    sets = [a for k, v in LAG_PARAMETERS.items() for a in ("--set", f"{k}={v!r}")]
    oc.run("simulate", fmu, "--input", inp, "--stop", STOP, "--step", STEP, "--out", out, "--quiet", *sets, env=host_env)
    orch = oc.read_results(out)
    assert orch.columns == ["time", "Lag.y"]

    signals = np.array(list(zip(INPUT_T, INPUT_U)), dtype=[("time", np.float64), ("u", np.float64)])
    ref = fmpy.simulate_fmu(str(fmu), input=signals, start_values=dict(LAG_PARAMETERS), stop_time=STOP,
                            output_interval=STEP, output=["y"])
    np.testing.assert_array_equal(orch.time, ref["time"])
    d_fmpy = oc.assert_close(orch["Lag.y"], ref["y"], rtol=1e-12, what="orchestrator simulate vs fmpy.simulate_fmu: y")
    y = orch["Lag.y"]
    assert y.max() > 1.0 and y.min() < 0.0, "the input's ramp, jump and hold reach the output"

    # The residual, explained: reproduce each bit for bit.
    inputs = {"u": (INPUT_T, INPUT_U)}
    as_orch = pm.simulate_single(fmu, "Lag", inputs, STOP, STEP, LAG_PARAMETERS,
                                 interpolation=pm.orchestrator_interpolation, step_size="constant", record=["y"])
    as_fmpy = pm.simulate_single(fmu, "Lag", inputs, STOP, STEP, LAG_PARAMETERS,
                                 interpolation=pm.fmpy_interpolation, step_size="difference", record=["y"])
    np.testing.assert_array_equal(orch["Lag.y"], as_orch["y"], err_msg="orchestrator vs its documented semantics")
    np.testing.assert_array_equal(ref["y"], as_fmpy["y"], err_msg="fmpy vs its semantics")
    # Where the two differ: the interpolated input (x0 + (x1 - x0) (t - t0)/(t1 - t0) against
    # w0 x0 + w1 x1) and the step size (h against t_{k+1} - t_k = (k+1) h - k h).
    t = np.arange(int(round(STOP / STEP))) * STEP
    u_orch = np.array([pm.orchestrator_interpolation(INPUT_T, INPUT_U, x) for x in t])
    u_fmpy = np.array([pm.fmpy_interpolation(INPUT_T, INPUT_U, x) for x in t])
    h_fmpy = (np.arange(1, len(t) + 1) * STEP) - t
    du = np.abs(u_orch - u_fmpy).max() / np.abs(INPUT_U).max()  # relative to the signal's scale
    dh = np.abs(h_fmpy - STEP).max() / STEP
    print(f"\nsimulate Lag.fmu vs fmpy.simulate_fmu: max relative difference in y {d_fmpy:.3g}; "
          f"inputs differ by up to {du:.3g} of the signal's range, step sizes by up to {dh:.3g} relative; "
          f"{int(np.count_nonzero(u_orch != u_fmpy))} of {len(t)} inputs and "
          f"{int(np.count_nonzero(h_fmpy != STEP))} of {len(t)} step sizes differ")
    assert du < 1e-15 and dh < 1e-14, (du, dh)
    # with the same semantics the difference would vanish: it is only these two things
    if d_fmpy != 0.0:
        assert np.any(u_orch != u_fmpy) or np.any(h_fmpy != STEP)


def test_ssp_pythonfmu_source_feeds_dahlquist(pyfmus, host_env, tmp_path):
    """Sine (PythonFMU) -> LinearTransformation -> Dahlquist.u; the consumer is listed first in
    the .ssd, so the orchestrator has to order the producer first (Gauss-Seidel)."""
    fmus = oc.fmus()
    sine_params = {"amplitude": 2.0, "frequency": 1.5, "offset": 0.25}
    plant_params = {"k": 3.0, "x0": 0.5}
    factor, offset = -1.5, 0.125
    ssd = oc.write_ssd(
        tmp_path / "SystemStructure.ssd",
        [
            oc.SsdComponent("plant", fmus["Dahlquist"], plant_params,
                            [("u", "input", "Real"), ("x", "output", "Real"), ("k", "parameter", "Real"), ("x0", "parameter", "Real")]),
            oc.SsdComponent("src", pyfmus["Sine"], sine_params,
                            [("y", "output", "Real"), ("amplitude", "parameter", "Real"),
                             ("frequency", "parameter", "Real"), ("offset", "parameter", "Real")]),
        ],
        [oc.SsdConnection("src.y", "plant.u", factor, offset)],
        stop=2.0,
    )
    out = tmp_path / "out"
    oc.run("run", ssd, "--step", "0.01", "--out", out, "--quiet", env=host_env)
    orch = oc.read_results(out)
    assert orch.columns == ["time", "plant.x", "src.y"]
    assert len(orch.time) == 201 and orch.time[-1] == 2.0

    py = pm.run_system(
        [pm.Comp("src", pyfmus["Sine"], sine_params), pm.Comp("plant", fmus["Dahlquist"], plant_params)],
        [pm.Connection("src.y", "plant.u", factor, offset)],
        stop=2.0, step=0.01, record=["plant.x", "src.y"],
    )
    np.testing.assert_array_equal(orch.time, py["time"])
    diffs = {c: oc.assert_close(orch[c], py[c], rtol=1e-12, what=c) for c in ("plant.x", "src.y")}
    print(f"\nSSP Sine (PythonFMU) -> Dahlquist: max relative difference {diffs}")
    assert max(diffs.values()) == 0.0
    # the parameters reached both FMUs and the transformation was applied
    assert orch["src.y"][0] == 0.25 and orch["plant.x"][0] == 0.5
    assert abs(orch["src.y"].max() - 2.25) < 0.01
    # x' = -k x + factor * y + offset, u held over each step: a Dahlquist step by hand
    e = np.exp(-3.0 * 0.01)
    u = factor * orch["src.y"][1:] + offset
    x_next = orch["plant.x"][:-1] * e + u / 3.0 * (1 - e)
    oc.assert_close(orch["plant.x"][1:], x_next, rtol=1e-13, what="Dahlquist step with u = transformed y at the step's end")
