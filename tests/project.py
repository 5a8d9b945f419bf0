"""Where the harness finds the project: the repository root and the packaged FMU."""

from __future__ import annotations

import functools
import os
import subprocess
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
MODEL_IDENTIFIER = "AlignmentEstimator"


def fmu_dir() -> Path:
    """Where `cargo xtask fmu` put the FMUs: `$XTASK_FMU_DIR` (set by `cargo xtask test`, which
    knows cargo's target directory) or `<repo>/target/fmu`."""
    return Path(os.environ.get("XTASK_FMU_DIR", REPO / "target" / "fmu"))


#: The FMUs `cargo xtask fmu` packages.
PACKAGED = ("AlignmentEstimator", "RailVehicle", "Dahlquist", "Feedthrough")


@functools.lru_cache(maxsize=None)
def packaged_fmus() -> dict[str, Path]:
    """The packaged FMUs by model identifier, built once with `cargo xtask fmu` if one is missing."""
    paths = {n: fmu_dir() / f"{n}.fmu" for n in PACKAGED}
    if not all(p.is_file() for p in paths.values()):
        subprocess.run(["cargo", "xtask", "fmu"], cwd=REPO, check=True)
    missing = [str(p) for p in paths.values() if not p.is_file()]
    assert not missing, f"`cargo xtask fmu` did not produce {missing}"
    return {n: p.resolve() for n, p in paths.items()}


def seed_list(text: str) -> list[int]:
    """Track seeds from a command line: `1-5`, `101,103-106`."""
    out = []
    for part in text.split(","):
        lo, _, hi = part.partition("-")
        out.extend(range(int(lo), int(hi or lo) + 1))
    return out
