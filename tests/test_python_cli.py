"""The Python commands against hostile input (issue 25): `track-alignment-fleet`,
`track-alignment-montecarlo` and `python -m track_alignment.synthetic`, run as a user runs them
(subprocesses). Each argument is checked before any work; the output never replaces an input or
a file the command did not write, a FIFO, a symlink or a directory; a write error leaves the
directory as it was; the user sees one `error:` line and a documented exit code, never a
traceback. Oracles: the files' bytes before and after, the exit codes of docs/python.md."""

from __future__ import annotations

import json
import os
import resource
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from project import packaged_fmus

pytest.importorskip("track_alignment.fleet", reason="the bindings are built into .venv by `cargo xtask test`")
from track_alignment import recordings  # noqa: E402

TIMEOUT = 300


def command(module: str, *args, limit_bytes: int | None = None, unprivileged: bool = False, inject: str = "",
            timeout: float = TIMEOUT) -> subprocess.CompletedProcess:
    """`python -m track_alignment.MODULE ARGS...`; `limit_bytes` caps the size of any file it
    writes (RLIMIT_FSIZE: a write past it fails as on a full disk); `unprivileged` runs it, when
    this is root, without the capability to write where the permissions forbid it (setpriv);
    `inject` is Python run first in the process (a simulated write error where the command also
    unpacks an FMU, which a file size limit would stop first)."""

    def limits():
        if limit_bytes is not None:
            resource.setrlimit(resource.RLIMIT_FSIZE, (limit_bytes, limit_bytes))

    run = ["-m", f"track_alignment.{module}"]
    if inject:
        run = ["-c", f"{inject}\nimport runpy, sys\nsys.argv[0] = {module!r}\n"
                     f"runpy.run_module('track_alignment.{module}', run_name='__main__')"]
    prefix = []
    if unprivileged and os.geteuid() == 0:
        if shutil.which("setpriv") is None:
            pytest.skip("root writes into a read-only directory, and setpriv is missing to drop that")
        prefix = ["setpriv", "--bounding-set=-dac_override,-dac_read_search", "--"]
    p = subprocess.run([*prefix, sys.executable, *run, *map(str, args)], capture_output=True, text=True,
                       timeout=timeout, preexec_fn=limits)
    assert "Traceback" not in p.stderr, p.stderr
    return p


def disk_full(module: str, owner: str, attr: str, n: int, path_arg: int) -> str:
    """Python that makes the `n`-th call of `owner.attr` (in `module`) write half a file at its
    argument `path_arg` and fail as a full disk does (ENOSPC)."""
    return f"""
import errno, {module}
_owner = {owner}
_real, _calls = getattr(_owner, {attr!r}), [0]
def _failing(*a, **k):
    _calls[0] += 1
    if _calls[0] == {n}:
        open(a[{path_arg}], "wb").write(b"PAR1 half")
        raise OSError(errno.ENOSPC, "No space left on device")
    return _real(*a, **k)
setattr(_owner, {attr!r}, _failing)
"""


def one_error(p: subprocess.CompletedProcess, code: int, *needles: str) -> None:
    """Exit `code` with one `error:` line on stderr holding every needle."""
    lines = [line for line in p.stderr.splitlines() if line.strip()]
    assert p.returncode == code, (p.returncode, p.stderr)
    errors = [line for line in lines if line.startswith("error:") or ": error:" in line]
    assert len(errors) == 1, p.stderr
    for n in needles:
        assert n in errors[0], (n, p.stderr)


def snapshot(d: Path) -> dict[str, bytes]:
    """Every regular file under `d` (names relative to it) with its bytes."""
    return {str(p.relative_to(d)): p.read_bytes() for p in sorted(d.rglob("*")) if p.is_file() and not p.is_symlink()}


@pytest.fixture(scope="module")
def passes(tmp_path_factory) -> Path:
    """Three passes of 400 m (long enough for the D2 band), through the synthetic command."""
    d = tmp_path_factory.mktemp("fleet") / "passes"
    p = command("synthetic", "--vehicle-fmu", packaged_fmus()["RailVehicle"], "--out", d, "--passes", "3",
                "--length", "400")
    assert p.returncode == 0, p.stderr
    return d


# --- track-alignment-fleet ---

def fleet_args(passes: Path, out: Path, *more) -> list:
    return [passes, "--out", out, "--workers", "1", "--no-plot", *more]


@pytest.mark.parametrize("workers", ["0", "-1", "two"])
def test_fleet_refuses_workers_that_are_not_positive(passes, tmp_path, workers):
    """`--workers 0` hung: argparse refuses it now, before anything starts."""
    p = command("fleet", passes, "--out", tmp_path / "o", "--workers", workers, timeout=60)
    one_error(p, 2, "--workers")
    assert not (tmp_path / "o").exists()


def test_fleet_refuses_a_bad_setting_in_one_line_before_dask(passes, tmp_path):
    start = time.monotonic()
    p = command("fleet", *fleet_args(passes, tmp_path / "o", "--set", "lag=abc"), timeout=60)
    one_error(p, 2, "--set lag=abc", "lag")
    p = command("fleet", *fleet_args(passes, tmp_path / "o", "--set", "no_such_parameter=1"), timeout=60)
    one_error(p, 2, "no_such_parameter")
    assert time.monotonic() - start < 60
    assert not (tmp_path / "o").exists()


def test_fleet_refuses_an_existing_file_as_out_before_any_work(passes, tmp_path):
    """`--out existing.txt` failed with "[Errno 17]" after all the computing: now at once, exit 1."""
    existing = tmp_path / "existing.txt"
    existing.write_text("keep me\n")
    p = command("fleet", *fleet_args(passes, existing), timeout=60)
    one_error(p, 1, str(existing), "not a directory")
    assert existing.read_text() == "keep me\n"


def test_fleet_never_replaces_an_input(passes, tmp_path):
    """A recording named like an output, in the directory given as --out: it is an input."""
    d = tmp_path / "rec"
    d.mkdir()
    shutil.copy(passes / "pass_0000.parquet", d / "segments.parquet")
    before = snapshot(d)
    p = command("fleet", *fleet_args(d, d), timeout=60)
    one_error(p, 1, "segments.parquet", "is an input")
    assert snapshot(d) == before
    # The recording itself as --out.
    p = command("fleet", *fleet_args(d / "segments.parquet", d / "segments.parquet"), timeout=60)
    one_error(p, 1, "not a directory")
    assert snapshot(d) == before


def test_fleet_never_replaces_a_file_it_did_not_write(passes, tmp_path):
    out = tmp_path / "o"
    out.mkdir()
    (out / "passes.parquet").write_bytes(b"someone else's table")
    (out / "notes.txt").write_text("mine\n")
    before = snapshot(out)
    p = command("fleet", *fleet_args(passes, out), timeout=60)
    one_error(p, 1, "passes.parquet", "not written by track-alignment-fleet")
    assert snapshot(out) == before


def test_fleet_refuses_a_fifo_and_a_symlink_in_place_of_an_output(passes, tmp_path):
    out = tmp_path / "o"
    out.mkdir()
    os.mkfifo(out / "segments.parquet")
    p = command("fleet", *fleet_args(passes, out), timeout=60)
    one_error(p, 1, "segments.parquet", "FIFO")
    os.unlink(out / "segments.parquet")
    target = tmp_path / "target.txt"
    target.write_text("target\n")
    (out / "passes.parquet").symlink_to(target)
    p = command("fleet", *fleet_args(passes, out), timeout=60)
    one_error(p, 1, "passes.parquet", "symbolic link")
    assert target.read_text() == "target\n" and (out / "passes.parquet").is_symlink()


def test_fleet_writes_reruns_and_survives_a_write_error(passes, tmp_path):
    """A run writes its files and a manifest; a rerun replaces them; a rerun that cannot write
    (file size limit: the write fails as on a full disk) leaves the first results intact, no
    temporary file, exit 1."""
    out = tmp_path / "o"
    (tmp_path / "o").mkdir()
    (out / "notes.txt").write_text("mine\n")
    p = command("fleet", *fleet_args(passes, out))
    assert p.returncode == 0, p.stderr
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["command"] == "track-alignment-fleet"
    assert manifest["files"] == ["segments.parquet", "passes.parquet"]
    p = command("fleet", *fleet_args(passes, out))
    assert p.returncode == 0, p.stderr
    before = snapshot(out)
    p = command("fleet", *fleet_args(passes, out, "--segment", "100"), limit_bytes=2000)
    one_error(p, 1, "cannot be written")
    assert snapshot(out) == before
    assert sorted(x.name for x in out.iterdir()) == ["manifest.json", "notes.txt", "passes.parquet", "segments.parquet"]


def test_fleet_refuses_a_read_only_directory(passes, tmp_path):
    out = tmp_path / "ro"
    out.mkdir()
    out.chmod(0o555)
    try:
        p = command("fleet", *fleet_args(passes, out), unprivileged=True, timeout=60)
        one_error(p, 1, str(out), "not writable")
        p = command("fleet", *fleet_args(passes, out / "new"), unprivileged=True, timeout=60)
        one_error(p, 1, str(out), "not writable")
        assert list(out.iterdir()) == []
    finally:
        out.chmod(0o755)


# --- python -m track_alignment.synthetic ---

def test_synthetic_seed_sets_the_noise_seeds_and_speeds(tmp_path):
    """`--seed S`: pass i has noise seed 1000 + 100000 S + i (seed 0: 1000 + i, as before), and
    its own speeds."""
    fmu = packaged_fmus()["RailVehicle"]
    runs = {}
    for seed in (0, 7):
        out = tmp_path / f"s{seed}"
        p = command("synthetic", "--vehicle-fmu", fmu, "--out", out, "--passes", "2", "--length", "10",
                    "--track-seed", "4", "--seed", seed)
        assert p.returncode == 0, p.stderr
        runs[seed] = [recordings.read_table(out / f"pass_{i:04d}.parquet")[1]["parameters"] for i in range(2)]
    assert [r["noise_seed"] for r in runs[0]] == [1000, 1001]
    assert [r["noise_seed"] for r in runs[7]] == [701000, 701001]
    assert all(r["track_seed"] == 4 for rs in runs.values() for r in rs)
    assert runs[0][0]["speed"] != runs[7][0]["speed"]


@pytest.mark.parametrize("args, needle", [
    (["--passes", "0"], "--passes"), (["--length", "nan"], "--length"), (["--length", "-5"], "--length"),
    (["--seed", "-1"], "--seed"), (["--seed", "x"], "--seed"),
])
def test_synthetic_refuses_bad_arguments(tmp_path, args, needle):
    p = command("synthetic", "--vehicle-fmu", packaged_fmus()["RailVehicle"], "--out", tmp_path / "o", *args,
                timeout=60)
    one_error(p, 2, needle)
    assert not (tmp_path / "o").exists()


def test_synthetic_output_policy(tmp_path):
    fmu = packaged_fmus()["RailVehicle"]
    base = ["--vehicle-fmu", fmu, "--passes", "3", "--length", "10"]
    out = tmp_path / "o"
    # An unrelated file of an output's name, a FIFO, the FMU (an input) as --out.
    out.mkdir()
    (out / "truth.parquet").write_text("not mine\n")
    p = command("synthetic", *base, "--out", out, timeout=60)
    one_error(p, 1, "truth.parquet", "not written by")
    assert (out / "truth.parquet").read_text() == "not mine\n"
    os.unlink(out / "truth.parquet")
    os.mkfifo(out / "pass_0001.parquet")
    p = command("synthetic", *base, "--out", out, timeout=60)
    one_error(p, 1, "pass_0001.parquet", "FIFO")
    os.unlink(out / "pass_0001.parquet")
    p = command("synthetic", *base, "--out", fmu, timeout=60)
    one_error(p, 1, "not a directory")
    # A full disk at the third file: no new directory, nothing half-written.
    fresh = tmp_path / "fresh"
    full = disk_full("track_alignment.recordings", "track_alignment.recordings", "write_parquet", 3, 0)
    p = command("synthetic", *base, "--out", fresh, inject=full)
    one_error(p, 1, "cannot be written", "No space left on device")
    assert not fresh.exists()
    # Written; rerun with fewer passes: the earlier run's third pass is removed, the rest kept.
    p = command("synthetic", *base, "--out", out)
    assert p.returncode == 0, p.stderr
    (out / "notes.txt").write_text("mine\n")
    p = command("synthetic", *base[:2], "--passes", "2", "--length", "10", "--out", out)
    assert p.returncode == 0, p.stderr
    assert sorted(x.name for x in out.iterdir()) == [
        "manifest.json", "notes.txt", "pass_0000.parquet", "pass_0001.parquet", "truth.parquet"]


def test_synthetic_refuses_a_read_only_directory(tmp_path):
    out = tmp_path / "ro"
    out.mkdir()
    out.chmod(0o555)
    try:
        p = command("synthetic", "--vehicle-fmu", packaged_fmus()["RailVehicle"], "--out", out, "--passes", "1",
                    "--length", "10", unprivileged=True, timeout=60)
        one_error(p, 1, "not writable")
        assert list(out.iterdir()) == []
    finally:
        out.chmod(0o755)


# --- track-alignment-montecarlo ---

def montecarlo_args(out: Path, *more) -> list:
    return ["--vehicle-fmu", packaged_fmus()["RailVehicle"], "--seeds", "1", "--stop", "12", "--workers", "1",
            "--out", out, *more]


@pytest.mark.parametrize("args, needle", [
    (["--workers", "0"], "--workers"), (["--stop", "-1"], "--stop"), (["--stop", "inf"], "--stop"),
])
def test_montecarlo_refuses_bad_arguments(tmp_path, args, needle):
    p = command("montecarlo", *montecarlo_args(tmp_path / "r.parquet"), *args, timeout=60)
    one_error(p, 2, needle)
    assert not (tmp_path / "r.parquet").exists()


def test_montecarlo_output_policy(tmp_path):
    existing = tmp_path / "r.parquet"
    existing.write_text("keep me\n")
    p = command("montecarlo", *montecarlo_args(existing), timeout=60)
    one_error(p, 1, "exists", "--force")
    # The input as the output: an FMU named vehicle.csv, given as both.
    fmu_copy = tmp_path / "vehicle.csv"
    shutil.copy(packaged_fmus()["RailVehicle"], fmu_copy)
    want = fmu_copy.read_bytes()
    args = ["--vehicle-fmu", fmu_copy, "--seeds", "1", "--stop", "12", "--workers", "1", "--force"]
    p = command("montecarlo", *args, "--out", fmu_copy, timeout=60)
    one_error(p, 1, "is an input")
    assert fmu_copy.read_bytes() == want
    link = tmp_path / "link.csv"
    link.symlink_to(existing)
    p = command("montecarlo", *args, "--out", link, timeout=60)
    one_error(p, 1, "symbolic link")
    fifo = tmp_path / "fifo.csv"
    os.mkfifo(fifo)
    p = command("montecarlo", *args, "--out", fifo, timeout=60)
    one_error(p, 1, "FIFO")
    # A read-only directory.
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        p = command("montecarlo", *montecarlo_args(ro / "r.parquet"), unprivileged=True, timeout=60)
        one_error(p, 1, "not writable")
        assert list(ro.iterdir()) == []
    finally:
        ro.chmod(0o755)
    # A full disk after the sweep: the old file kept, no temporary file.
    full = disk_full("pandas", "pandas.DataFrame", "to_parquet", 1, 1)
    p = command("montecarlo", *montecarlo_args(existing, "--force"), inject=full)
    one_error(p, 1, "cannot be written")
    assert existing.read_text() == "keep me\n"
    assert not [x for x in tmp_path.iterdir() if x.name.startswith(".")]
    p = command("montecarlo", *montecarlo_args(existing, "--force"))
    assert p.returncode == 0, p.stderr
    assert existing.read_bytes()[:4] == b"PAR1"
