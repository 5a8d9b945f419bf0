"""`alignment-studies` as a user meets it (subprocess): help for every command, and exit codes by
the master's convention (docs/orchestrator.md) through the studies' typed error: 2 for bad input
(named), 3 when an FMU fails during one of a study's runs (the master's run error is kept, not
turned into text), as `orchestrator run` exits for the same failure."""

from __future__ import annotations

import pytest

import orchestrator_cli as oc

COMMANDS = ("run", "calibrate", "standard", "robustness", "resonance", "all", "variants", "learn", "taps", "smooth")


@pytest.mark.parametrize("sub", [None, *COMMANDS])
def test_help_for_every_command(sub):
    args = [sub] if sub else []
    p = oc.studies(*args, "--help")
    usage = f"Usage: alignment-studies {sub}" if sub else "Usage: alignment-studies <COMMAND>"
    assert usage in p.stdout, p.stdout
    assert p.stderr == ""
    if sub is None:
        for s in COMMANDS:
            assert f"  {s} " in p.stdout, s


def test_version_and_usage_errors():
    assert oc.studies("--version").stdout.startswith("alignment-studies ")
    assert oc.studies(check=None).returncode == 2
    p = oc.studies("standard", "--no-such-option", check=2)
    assert "--no-such-option" in p.stderr


def test_the_calibration_seed_is_refused_as_an_evaluation_seed(tmp_path):
    p = oc.studies("standard", "--seeds", "1,101", "--quiet", "--out", tmp_path, *oc.standard_fmu_args(), check=2)
    assert "seed 101 is the calibration seed" in p.stderr, p.stderr


def test_a_corrupt_fmu_exits_2_naming_it(tmp_path):
    corrupt = tmp_path / "Corrupt.fmu"
    corrupt.write_bytes(b"not a zip archive" * 100)
    f = oc.fmus()
    p = oc.studies("run", "--vehicle", corrupt, "--estimator", f["AlignmentEstimator"], "--stop", "0.01",
                   "--out", tmp_path / "o", check=2)
    assert "Corrupt.fmu" in p.stderr, p.stderr
    assert "Traceback" not in p.stderr and "panicked" not in p.stderr, p.stderr


@pytest.mark.parametrize("command", [
    ["standard", "--seeds", "1", "--quiet"],
    ["calibrate", "--out", "{tmp}/cal.toml", "--plots", "{tmp}/plots"],
])
def test_an_fmu_failing_mid_study_exits_3(command, tmp_path):
    """A vehicle with a conicity of 5 hunts at 20 m/s and leaves the track within 0.1 s: the
    vehicle FMU returns fmi2Error from fmi2DoStep (orchestrator simulate exits 3 on it,
    tests/test_vehicle.py). The study stops with that error and exit 3, not 2 (bad input)."""
    args = [a.replace("{tmp}", str(tmp_path)) for a in command]
    out = [] if "calibrate" in command else ["--out", tmp_path / "study"]
    p = oc.studies(*args, *out, "--set", "vehicle.conicity=5", *oc.standard_fmu_args(), check=3)
    assert "derailed" in p.stderr, p.stderr
    assert "Traceback" not in p.stderr and "panicked" not in p.stderr, p.stderr
    assert not (tmp_path / "cal.toml").exists()
