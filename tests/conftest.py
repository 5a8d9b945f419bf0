"""Shared fixtures: the packaged FMU, its model description and extracted files, instances that
are freed after each test, and synthetic runs of the simplified model.

The FMU is the one `cargo xtask fmu` packaged (project.fmu_dir()). When it is missing, it is
built once per session, so `pytest tests` also works by itself.
"""

from __future__ import annotations

from pathlib import Path

import fmpy
import numpy as np
import pytest

import sm_reference as sm
from fmi_harness import slave_factory
from project import MODEL_IDENTIFIER, packaged_fmus


@pytest.fixture(scope="session")
def fmu_path() -> Path:
    """Path of the packaged AlignmentEstimator.fmu (built with `cargo xtask fmu` if missing)."""
    return packaged_fmus()[MODEL_IDENTIFIER]


@pytest.fixture(scope="session")
def model_description(fmu_path):
    return fmpy.read_model_description(str(fmu_path))


@pytest.fixture(scope="session")
def unzip_dir(fmu_path, tmp_path_factory) -> Path:
    """The FMU extracted once per session (every low-level instance loads its library from here)."""
    return Path(fmpy.extract(str(fmu_path), unzipdir=str(tmp_path_factory.mktemp("fmu"))))


@pytest.fixture
def make_slave(model_description, unzip_dir):
    """Factory of instances (`make_slave(name)`), all freed when the test ends."""
    yield from slave_factory(model_description, unzip_dir, "instance")


@pytest.fixture(scope="session")
def noisy_run() -> sm.SyntheticRun:
    """20 s at 20 m/s on a low-disturbance alignment, with the paper's sensor noise (seeded)."""
    return sm.synthetic_run(
        sm.alignment_harmonics(np.random.default_rng(1)), speed=20.0, duration=20.0, noise_rng=np.random.default_rng(101)
    )


@pytest.fixture(scope="session")
def short_runs() -> list[sm.SyntheticRun]:
    """Two different noisy 2 s runs, for tests that drive instances step by step."""
    return [
        sm.synthetic_run(sm.alignment_harmonics(np.random.default_rng(seed)), duration=2.0, noise_rng=np.random.default_rng(seed + 100))
        for seed in (7, 8)
    ]
