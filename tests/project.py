"""Where the harness finds the project: the repository root and the packaged FMU."""

from __future__ import annotations

import os
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
MODEL_IDENTIFIER = "AlignmentEstimator"


def fmu_dir() -> Path:
    """Where `cargo xtask fmu` put the FMUs: `$XTASK_FMU_DIR` (set by `cargo xtask test`, which
    knows cargo's target directory) or `<repo>/target/fmu`."""
    return Path(os.environ.get("XTASK_FMU_DIR", REPO / "target" / "fmu"))
