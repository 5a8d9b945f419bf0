"""The orchestrator's standard case (vehicle -> estimator) against a plain Python master over
fmpy's FMU2Slave that makes the same FMI calls in the same order (tests/orchestrator_pymaster.py):
Gauss-Seidel and Jacobi must give the same numbers to 1e-12 relative (in fact bit for bit, since
both call the same FMUs with the same arguments), and Jacobi must differ from Gauss-Seidel exactly
by the estimator seeing the sensor samples one step late.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

import orchestrator_cli as oc
import orchestrator_pymaster as pm

SENSORS = ("vehicle.ws_acc_y", "vehicle.ws_yaw_rate", "vehicle.frame_acc_y")


@pytest.fixture(scope="module")
def gs_2s(tmp_path_factory):
    """The orchestrator's standard case, 2 s at the default step (1 ms), every output recorded."""
    out = tmp_path_factory.mktemp("gs2")
    oc.run("run", "--stop", "2", "--out", out, "--quiet", *oc.standard_case_args())
    return oc.read_results(out)


@pytest.fixture(scope="module")
def jacobi_2s(tmp_path_factory):
    out = tmp_path_factory.mktemp("jacobi2")
    oc.run("run", "--stop", "2", "--jacobi", "--out", out, "--quiet", *oc.standard_case_args())
    return oc.read_results(out)


def _compare(orch: oc.Results, py: dict, label: str) -> dict[str, float]:
    np.testing.assert_array_equal(orch.time, py["time"], err_msg=f"{label}: time column")
    diffs = {}
    for name in pm.COMPARED:
        diffs[name] = oc.assert_close(orch[name], py[name], rtol=1e-12, atol=1e-300, what=f"{label}: {name}")
    print(f"\n{label}: max relative difference per variable: " + ", ".join(f"{k} {v:.3g}" for k, v in diffs.items()))
    return diffs


def test_time_axis_is_integer_ticks(gs_2s):
    assert gs_2s.columns[0] == "time"
    n = len(gs_2s.time)
    assert n == 2001, "one row at t = 0 after initialization, then one per 1 ms step to 2 s"
    np.testing.assert_array_equal(gs_2s.time, np.arange(n) * 1e-3)
    assert gs_2s.time[-1] == 2.0


def test_gauss_seidel_matches_python_master_2s(gs_2s):
    f = oc.fmus()
    py = pm.standard_case(f["RailVehicle"], f["AlignmentEstimator"], stop=2.0, step=1e-3)
    diffs = _compare(gs_2s, py, "standard case 2 s, Gauss-Seidel")
    # The same FMUs called in the same order with the same arguments: bit-identical.
    assert max(diffs.values()) == 0.0, diffs
    # and the run is not trivial
    assert np.std(gs_2s["vehicle.ws_acc_y"]) > 0 and np.std(gs_2s["estimator.alignment"]) > 0


def test_gauss_seidel_matches_python_master_20s(tmp_path):
    """The full standard run (20 s at 1 ms, the built-in default), recording only the compared
    variables (--record)."""
    started = time.perf_counter()
    oc.run("run", "--out", tmp_path, "--quiet", "--record", ",".join(pm.COMPARED), *oc.standard_case_args())
    wall = time.perf_counter() - started
    orch = oc.read_results(tmp_path)
    assert orch.columns == ["time", *pm.COMPARED]
    assert len(orch.time) == 20001 and orch.time[-1] == 20.0
    f = oc.fmus()
    started = time.perf_counter()
    py = pm.standard_case(f["RailVehicle"], f["AlignmentEstimator"], stop=20.0, step=1e-3)
    py_wall = time.perf_counter() - started
    print(f"\n20 s standard case: orchestrator {wall:.2f} s (process), Python master {py_wall:.2f} s")
    diffs = _compare(orch, py, "standard case 20 s, Gauss-Seidel")
    assert max(diffs.values()) == 0.0, diffs
    assert wall < 5.0, f"the 20 s standard case took {wall:.1f} s in the orchestrator"


def test_jacobi_matches_python_jacobi_master(jacobi_2s):
    f = oc.fmus()
    py = pm.standard_case(f["RailVehicle"], f["AlignmentEstimator"], stop=2.0, step=1e-3, algorithm="jacobi")
    diffs = _compare(jacobi_2s, py, "standard case 2 s, Jacobi")
    assert max(diffs.values()) == 0.0, diffs


def test_jacobi_delays_the_sensors_by_one_step(gs_2s, jacobi_2s):
    """The vehicle has no connected input, so Jacobi leaves it unchanged; the estimator then sees
    the sample of t_k in the step from t_k (Jacobi) instead of that of t_{k+1} (Gauss-Seidel).
    Shown exactly by driving a lone estimator with the recorded sensor columns, shifted or not."""
    assert gs_2s.columns == jacobi_2s.columns
    for c in gs_2s.columns:
        if c.startswith("vehicle."):
            np.testing.assert_array_equal(jacobi_2s[c], gs_2s[c], err_msg=c)
    d = oc.rel_diff(jacobi_2s["estimator.alignment"], gs_2s["estimator.alignment"])
    assert d.max() > 1e-6, "Jacobi should change the estimate"

    f = oc.fmus()
    sensors = np.column_stack([gs_2s[s] for s in SENSORS])
    speed = gs_2s["vehicle.forward_speed"]
    n = len(gs_2s.time) - 1
    # Jacobi: step k gets row k (the outputs at t_k; row 0 = after initialization).
    late = pm.estimator_alone(f["AlignmentEstimator"], sensors[:n], speed[:n], stop=2.0, step=1e-3)
    # Gauss-Seidel: step k gets row k + 1 (the vehicle already stepped to t_{k+1}).
    on_time = pm.estimator_alone(f["AlignmentEstimator"], sensors[1:], speed[1:], stop=2.0, step=1e-3)
    for name in ("alignment", "alignment_std"):
        # Row 0 (after initialization) does not depend on the samples.
        np.testing.assert_array_equal(late[name][1:], jacobi_2s[f"estimator.{name}"][1:],
                                      err_msg=f"Jacobi estimator.{name} vs samples of t_k")
        np.testing.assert_array_equal(on_time[name][1:], gs_2s[f"estimator.{name}"][1:],
                                      err_msg=f"Gauss-Seidel estimator.{name} vs samples of t_k+1")
