"""Illegal calls return an error status (never crash the host) and leave the instance usable;
bad data degrade gracefully. Statuses are read from the raw C calls (fmi_harness), since fmpy
raises on anything above fmi2Warning."""

from __future__ import annotations

import math
from ctypes import c_uint

import numpy as np
import pytest

from fmi_harness import ERROR, OK, WARNING, Slave, instantiate_raw

H = 1e-3


def initialized(make_slave, name: str) -> Slave:
    s = make_slave(name)
    assert s.initialize() == OK
    return s


def assert_still_steps(s: Slave, t: float) -> None:
    """The instance accepts a legal step afterwards and its outputs are finite."""
    assert s.step(t, H) == OK
    assert all(math.isfinite(x) for x in s.get_reals(["alignment", "alignment_std", "distance"]))


def last_error(s: Slave) -> str:
    errors = s.log.messages(ERROR)
    assert errors, "an error status must come with a logged message"
    return errors[-1]


def test_do_step_before_initialization(make_slave):
    s = make_slave("early")
    assert s.step(0.0, H) == ERROR
    assert "fmi2DoStep" in last_error(s)
    assert s.initialize() == OK
    assert_still_steps(s, 0.0)


def test_get_real_with_an_unknown_value_reference(make_slave):
    s = initialized(make_slave, "unknown_vr")
    assert s.get_real_status([9999]) == ERROR
    assert "9999" in last_error(s)
    assert s.get_real_status([s.vr["alignment"]]) == OK
    assert_still_steps(s, 0.0)


def test_get_real_into_a_null_array(make_slave):
    s = initialized(make_slave, "null")
    vrs = (c_uint * 1)(s.vr["alignment"])
    assert s.raw("fmi2GetReal")(s.fmu.component, vrs, 1, None) == ERROR
    assert "NULL" in last_error(s)
    assert_still_steps(s, 0.0)


def test_setting_an_output_is_refused_and_changes_nothing(make_slave):
    s = initialized(make_slave, "set_output")
    assert s.step(0.0, H) == OK
    before = s.get_reals(["alignment"])
    assert s.set_real_status([s.vr["alignment"]], [0.123]) == ERROR
    assert "alignment" in last_error(s)
    assert s.get_reals(["alignment"]) == before
    assert_still_steps(s, H)


@pytest.mark.parametrize("h", [-1e-3, math.nan, 0.0, math.inf])
def test_do_step_with_a_step_size_that_is_not_positive_and_finite(make_slave, h):
    s = initialized(make_slave, "bad_h")
    assert s.step(0.0, h) == ERROR
    assert "communicationStepSize" in last_error(s)
    assert s.get_reals(["distance"]) == [0.0]  # the refused step did not advance anything
    assert_still_steps(s, 0.0)


def test_terminate_allows_reading_final_values_but_not_stepping(make_slave):
    s = initialized(make_slave, "terminated")
    s.set_real("speed", 20.0)
    for k in range(3):
        assert s.step(k * H, H) == OK
    final = s.get_reals(["alignment", "alignment_std", "distance"])
    assert s.call("fmi2Terminate") == OK
    assert s.get_real_status([s.vr["distance"]]) == OK  # FMI 2.0: GetReal is legal after Terminate
    assert s.get_reals(["alignment", "alignment_std", "distance"]) == final
    assert final[2] == pytest.approx(3 * 20.0 * H)
    assert s.step(3 * H, H) == ERROR
    assert "terminated" in last_error(s)
    s.fmu.reset()  # and Reset brings it back
    assert s.initialize() == OK
    assert_still_steps(s, 0.0)


def test_instantiate_with_a_wrong_guid_returns_null(make_slave):
    s = make_slave("guid")
    assert instantiate_raw(s, "00000000-0000-0000-0000-000000000000") is None
    assert "GUID" in s.log.messages(ERROR)[-1]


def test_without_a_resources_location_the_learned_filter_is_refused_by_name(make_slave, model_description):
    """The FMU's library builds no tap bank in (it reads its resources): an importer that gives
    no fmuResourceLocation gets fmi2Error naming tap_file and the missing location at
    initialization, not a crash; the paper's filter, which needs no file, still runs."""
    from ctypes import c_double, c_int, c_uint, c_void_p

    s = make_slave("no-resources")
    guid = model_description.guid
    estimator = next(v.valueReference for v in model_description.modelVariables if v.name == "estimator")
    for paper, expected in [(False, ERROR), (True, OK)]:
        c = instantiate_raw(s, guid, name="no-resources", resources=False)
        assert c is not None, s.log.messages(ERROR)
        comp = c_void_p(c)
        if paper:
            vr = (c_uint * 1)(estimator)
            assert s.raw("fmi2SetInteger")(comp, vr, 1, (c_int * 1)(1)) == OK
        assert s.raw("fmi2SetupExperiment")(comp, c_int(0), c_double(0.0), c_double(0.0), c_int(0), c_double(0.0)) == OK
        assert s.raw("fmi2EnterInitializationMode")(comp) == OK
        assert s.raw("fmi2ExitInitializationMode")(comp) == expected
        if not paper:
            message = last_error(s)
            assert "tap_file" in message and "fmuResourceLocation" in message, message
        s.raw("fmi2FreeInstance")(comp)


def test_nan_sample_is_skipped_with_a_warning_and_estimation_continues(make_slave, short_runs):
    s = initialized(make_slave, "nan")
    signals = short_runs[0].signals
    names = ["ws_acc_y", "ws_yaw_rate", "frame_acc_y"]

    def step(k: int, values: list[float]) -> int:
        for name, v in zip(names, values):
            s.set_real(name, v)
        return s.step(k * H, H)

    for k in range(200):
        assert step(k, [signals[n][k + 1] for n in names]) == OK
    assert s.get_integer("skipped_updates") == 0
    assert step(200, [math.nan, signals["ws_yaw_rate"][201], signals["frame_acc_y"][201]]) == WARNING
    assert any("non-finite" in m for m in s.log.messages(WARNING))
    assert s.get_integer("skipped_updates") == 1
    for k in range(201, 400):
        assert step(k, [signals[n][k + 1] for n in names]) == OK
    assert s.get_integer("skipped_updates") == 1
    values = s.get_reals(["alignment", "alignment_std", "est_y", "est_vy", "nis"])
    assert np.all(np.isfinite(values))


def test_zero_conicity_is_refused_at_initialization_naming_alpha(make_slave):
    s = make_slave("alpha")
    assert s.initialize({"alpha": 0.0}) == ERROR
    assert "alpha" in last_error(s)
    s.fmu.reset()  # Reset recovers from the error
    assert s.initialize() == OK
    assert_still_steps(s, 0.0)


@pytest.mark.parametrize("path", ["/dev/zero", "/"])
def test_a_calibration_file_that_is_not_a_regular_file_is_refused_naming_it(make_slave, path):
    """/dev/zero would be read forever and a directory is no file: both are refused by name
    instead of hanging or exhausting the importer, and Reset recovers."""
    s = make_slave("device")
    assert s.initialize(strings={"calibration_file": path}) == ERROR
    assert path in last_error(s) and "not a regular file" in last_error(s)
    s.fmu.reset()
    assert s.initialize() == OK
    assert_still_steps(s, 0.0)


@pytest.mark.parametrize("name", ["tap_file", "calibration_file"])
def test_a_missing_relative_file_is_named_in_both_places_looked_for(make_slave, name):
    """A relative tap_file or calibration_file is looked for in the FMU's resources, then in the
    working directory: when it is in neither, the error names both."""
    import os

    s = make_slave("missing-" + name)
    assert s.initialize(strings={name: "no-such-dir/fitted.file"}) == ERROR
    message = last_error(s)
    assert "resources" in message and "no-such-dir/fitted.file" in message, message
    assert os.path.join(os.getcwd(), "no-such-dir", "fitted.file") in message, message
    s.fmu.reset()
    assert s.initialize() == OK
    assert_still_steps(s, 0.0)


def test_a_negative_speed_is_an_error_naming_the_input(make_slave):
    """Issue 14: the model is for forward running; a negative speed is refused, not run."""
    s = initialized(make_slave, "reverse")
    s.set_real("speed", -3.0)
    assert s.step(0.0, H) == ERROR
    assert "'speed'" in last_error(s) and "-3" in last_error(s)


def test_an_implausible_sample_is_skipped_not_integrated(make_slave, short_runs):
    """Issue 14: one accelerometer sample of 1e300 m/s2 gave an alignment of 1e301 m; it is
    skipped like a non-finite sample (with a warning naming it), and the estimate stays sane."""
    s = initialized(make_slave, "huge")
    signals = short_runs[0].signals
    names = ["ws_acc_y", "ws_yaw_rate", "frame_acc_y"]
    for k in range(400):
        values = [signals[n][k + 1] for n in names]
        if k == 200:
            values[0] = 1e300
        for name, v in zip(names, values):
            s.set_real(name, v)
        assert s.step(k * H, H) == (WARNING if k == 200 else OK)
    assert any("implausible" in m and "ws_acc_y" in m for m in s.log.messages(WARNING))
    alignment, std = s.get_reals(["alignment", "alignment_std"])
    assert abs(alignment) < 0.1 and 0 < std < 0.1, (alignment, std)


def test_a_warning_repeated_every_step_is_logged_once_then_counted(make_slave):
    """Issue 14: 2 s of NaN samples logged 2000 warnings; now the first in full, then the 10th,
    100th and 1000th as counts, and the total at fmi2Terminate."""
    s = initialized(make_slave, "nan-storm")
    for k in range(2000):
        s.set_real("ws_acc_y", math.nan)
        assert s.step(k * H, H) == WARNING
    warnings = s.log.messages(WARNING)
    about_nan = [m for m in warnings if "non-finite sensor sample" in m]
    assert len(about_nan) == 4, about_nan
    assert s.get_integer("skipped_updates") == 2000
    s.fmu.terminate()  # fmpy raises on an error status
    assert any("2000 times in all" in m for m in s.log.messages(WARNING)), s.log.messages(WARNING)
