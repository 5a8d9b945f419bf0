"""Shared fixtures: the packaged FMU, its model description and extracted files, instances that
are freed after each test, and synthetic runs of the simplified model.

The FMU is the one `cargo xtask fmu` packaged (project.fmu_dir()). When it is missing, it is
built once per session, so `pytest tests` also works by itself.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import fmpy
import numpy as np
import pytest

import sm_reference as sm
from fmi_harness import Slave
from project import MODEL_IDENTIFIER, REPO, fmu_dir


@pytest.fixture(scope="session")
def fmu_path() -> Path:
    """Path of the packaged AlignmentEstimator.fmu (built with `cargo xtask fmu` if missing)."""
    path = fmu_dir() / f"{MODEL_IDENTIFIER}.fmu"
    if not path.exists():
        subprocess.run(["cargo", "xtask", "fmu"], cwd=REPO, check=True)
    assert path.exists(), f"`cargo xtask fmu` did not produce {path}"
    return path


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
    slaves: list[Slave] = []

    def make(name: str = "instance", logging_on: bool = False) -> Slave:
        s = Slave(model_description, unzip_dir, name=name, logging_on=logging_on)
        slaves.append(s)
        return s

    yield make
    for s in slaves:
        s.free()


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
