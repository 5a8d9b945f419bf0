"""What the FMU hands the importer's logger (docs/references.md section 7.7, items 4): our componentEnvironment
back (the router in fmi_harness finds the instance's sink by it), the instance name, a declared
non-NULL category, and the message text intact even when it contains '%' (the FMU must pass it
as an argument of a "%s" format, never as the format)."""

from __future__ import annotations

from fmi_harness import ERROR, OK, WARNING

TRICKY = "does%snot%dexist.toml"


def test_an_error_names_a_missing_calibration_file_with_percent_signs_intact(make_slave, model_description):
    s = make_slave("logger%s#1")
    status = s.initialize(strings={"calibration_file": TRICKY})
    # Issue 14: a calibration file the user named must exist (it was a warning before, and the
    # run went on with another noise model).
    assert status == ERROR
    errors = [r for r in s.log.records if r.status == ERROR]
    assert any(TRICKY in r.message and "calibration_file" in r.message for r in errors), s.log.records
    categories = {c.name for c in model_description.logCategories}
    for r in s.log.records:
        assert r.instance_name == "logger%s#1"
        assert r.category is not None and r.category in categories, r
    s.fmu.reset()  # Reset recovers; the default calibration works
    assert s.initialize() == OK
    assert s.step(0.0, 1e-3) == OK


def test_error_messages_reach_the_right_instance(make_slave):
    quiet, noisy = make_slave("quiet"), make_slave("noisy")
    assert quiet.initialize() == OK and noisy.initialize() == OK
    quiet.log.clear()
    assert noisy.step(0.0, -1.0) == ERROR
    assert quiet.log.records == []
    [record] = noisy.log.records
    assert (record.instance_name, record.status, record.category) == ("noisy", ERROR, "logStatusError")


def test_debug_categories_follow_set_debug_logging(make_slave):
    """Status categories are always on; logCalls only after fmi2SetDebugLogging switches it on."""
    s = make_slave("debug")
    assert s.initialize() == OK
    s.log.clear()
    assert s.step(0.0, 1e-3) == OK
    assert [r for r in s.log.records if r.category == "logCalls"] == []
    s.fmu.setDebugLogging(True, ["logCalls"])
    assert s.step(1e-3, 1e-3) == OK
    calls = [r for r in s.log.records if r.category == "logCalls"]
    assert any("fmi2DoStep" in r.message for r in calls), s.log.records


def test_an_unobservable_model_is_reported_by_the_pbh_test(make_slave):
    """Without lateral primary suspension the frame neither moves with the wheelset nor shows in
    any sensor: the PBH test at initialization must say so with a warning (and the FMU still runs)."""
    s = make_slave("unobservable")
    assert s.initialize({"ky": 0.0, "cy": 0.0, "estimator": 1}) == OK
    warnings = [r.message for r in s.log.records if r.status == WARNING]
    assert any("not observable" in m and "PBH rank" in m for m in warnings), s.log.records
    observable = make_slave("observable")
    assert observable.initialize() == OK
    assert not any("observable" in r.message for r in observable.log.records)
    assert s.step(0.0, 1e-3) == OK


def shipped_calibration_with(path, old: str, new: str):
    """The shipped calibration file with its first `old` replaced by `new`, written to `path`."""
    from project import REPO

    shipped = (REPO / "fmu-estimator" / "resources" / "calibration.toml").read_text()
    other = shipped.replace(old, new, 1)
    assert other != shipped
    path.write_text(other)
    return path


def test_a_calibration_file_brings_its_parameters_unless_the_importer_set_others(make_slave, tmp_path):
    """A calibration file's [parameters] are the model its Q and R were made with: naming the
    file is enough to get them where the importer left the parameters at their defaults (said
    at fmi2OK); a parameter the importer set to another value stays, with a warning; one set
    to the file's value is not flagged."""
    path = shipped_calibration_with(tmp_path / "other.toml", "m = 1.109e3", "m = 1.813e3")

    # The paper's filter alone: with the learned filter another calibration is another Kalman
    # channel than its tap bank's, an error of its own (below).
    s = make_slave("other-calibration", logging_on=True)
    assert s.initialize({"estimator": 1}, strings={"calibration_file": str(path)}) == OK
    assert not any(r.status == WARNING for r in s.log.records), s.log.records
    taken = [r.message for r in s.log.records if "model parameters from" in r.message]
    assert len(taken) == 1 and "m = 1813" in taken[0], s.log.records

    kept = make_slave("kept-parameter")
    assert kept.initialize({"m": 1500.0, "estimator": 1}, strings={"calibration_file": str(path)}) in (OK, WARNING)
    flagged = [r.message for r in kept.log.records if r.status == WARNING and "other model parameters" in r.message]
    assert len(flagged) == 1 and "m = 1813 (here 1500)" in flagged[0], kept.log.records

    matched = make_slave("matched-calibration")
    assert matched.initialize({"m": 1813.0, "estimator": 1}, strings={"calibration_file": str(path)}) == OK
    assert not any("other model parameters" in r.message for r in matched.log.records), matched.log.records


def test_the_learned_filter_with_another_kalman_channel_is_an_error_unless_allowed(make_slave, tmp_path):
    """The tap bank's contract (docs/learned-filter.md): taps fitted with the shipped calibration
    do not run on another one unless allow_other_kalman asks for approximate use."""
    path = shipped_calibration_with(tmp_path / "other-q.toml", "1.0889672112641672e-6]", "2e-6]")

    refused = make_slave("learned-other-calibration")
    assert refused.initialize(strings={"calibration_file": str(path)}) == ERROR
    errors = [r.message for r in refused.log.records if r.status == ERROR]
    assert any("another Kalman channel" in m and "Q (" in m and "allow_other_kalman" in m for m in errors), errors

    allowed = make_slave("learned-other-calibration-allowed")
    assert allowed.initialize({"allow_other_kalman": True}, strings={"calibration_file": str(path)}) == OK
    assert any("another Kalman channel" in r.message for r in allowed.log.records if r.status == WARNING)
    assert allowed.step(0.0, 1e-3) == OK


def test_the_kalman_mismatch_names_the_channels_parameters_not_the_learned_filters(make_slave):
    """The contract error lists the parameters not at their defaults that feed the Kalman
    channel (alpha here); the learned filter's own conditions (conicity, kalker_scale) do not
    change the channel and are not listed."""
    s = make_slave("learned-other-alpha")
    assert s.initialize({"alpha": 0.2, "conicity": 0.2, "kalker_scale": 0.5}) == ERROR
    errors = [r.message for r in s.log.records if r.status == ERROR]
    listed = [m.split("parameters not at their defaults:")[1] for m in errors if "parameters not at their defaults:" in m]
    assert listed and "alpha = 0.2" in listed[0], errors
    assert "kalker_scale" not in listed[0] and "conicity" not in listed[0], listed
