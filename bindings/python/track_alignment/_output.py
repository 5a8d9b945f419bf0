"""The output policy of the Python commands (``track-alignment-fleet``,
``track-alignment-montecarlo``, ``python -m track_alignment.synthetic``), the Rust commands' own:
a typo in ``--out`` must not cost a recording or hours of computing.

| rule | how |
|---|---|
| checked before any work | :meth:`OutputDir.check` and :func:`check_file` run before Dask starts or a vehicle runs |
| never replace an input | an output that is the same file as an input is refused |
| never replace a file the command did not write | in a directory: an existing file of an output's name is replaced only when the directory's ``manifest.json`` (written by the same command) lists it; a single file: only with the command's ``--force`` |
| never a special file | an output that is a symlink, FIFO, device or directory is refused, never replaced |
| no half-written file | each file is written as ``.NAME.tmp-PID`` in the same directory and renamed once all are complete |
| no empty directory left behind | a new directory is created only when the results are written |

Errors are :class:`OutputError` (the commands' exit code 1), one line naming the path.
"""

from __future__ import annotations

import json
import os
import stat
from pathlib import Path
from typing import Callable, Iterable, Sequence

MANIFEST = "manifest.json"


class OutputError(Exception):
    """An output that cannot or must not be written; the message names it."""


def _same(a: Path, b: Path) -> bool:
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def _writable_dir(d: Path, what: str) -> None:
    if not d.is_dir():
        raise OutputError(f"{what} {d}: not a directory")
    if not os.access(d, os.W_OK | os.X_OK):
        raise OutputError(f"{what} {d}: the directory is not writable")


def _refuse_special(path: Path, inputs: Iterable[str | Path]) -> bool:
    """Refuses ``path`` when it is a symlink or not a regular file, or is an input; True when a
    regular file exists there."""
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return False
    except OSError as e:
        raise OutputError(f"{path}: cannot be examined ({e.strerror})") from e
    if stat.S_ISLNK(st.st_mode):
        raise OutputError(f"{path}: is a symbolic link; refused, never replaced")
    if not stat.S_ISREG(st.st_mode):
        kind = "a directory" if stat.S_ISDIR(st.st_mode) else "a FIFO" if stat.S_ISFIFO(st.st_mode) else "not a regular file"
        raise OutputError(f"{path}: is {kind}; refused, never replaced")
    for i in inputs:
        if _same(path, Path(i)):
            raise OutputError(f"{path}: is an input of this command; refused, never replaced")
    return True


def _existing_ancestor(path: Path) -> Path:
    """The nearest ancestor of ``path`` that exists."""
    for d in path.absolute().parents:
        if d.exists():
            return d
    return Path("/")


def check_file(path: str | Path, inputs: Sequence[str | Path] = (), force: bool = False) -> Path:
    """A single output file, before any work: refused when it exists (unless ``force``, and
    then never an input, a symlink, a FIFO or a directory), or its directory is not writable."""
    path = Path(path)
    exists = _refuse_special(path, inputs)
    if exists and not force:
        raise OutputError(f"{path}: exists; give --force to replace it")
    _writable_dir(path.parent if str(path.parent) else Path("."), "the output's directory")
    return path


def write_file(path: Path, write: Callable[[Path], None]) -> None:
    """``write(tmp)`` into a temporary file beside ``path``, then renamed over it."""
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    try:
        write(tmp)
        _sync(tmp)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def _sync(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


class OutputDir:
    """A command's output directory: ``names`` are the files it writes there (other files in
    it are left alone)."""

    def __init__(self, path: str | Path, command: str):
        self.path = Path(path)
        self.command = command
        self._staged: list[tuple[Path, Path]] = []
        #: The existing ancestor below which this run created directories (None: created none).
        self._created: Path | None = None

    def _listed(self) -> list[str]:
        """The files the directory's manifest says this command wrote ([] without one)."""
        m = self.path / MANIFEST
        try:
            if not m.is_file() or m.is_symlink():
                return []
            data = json.loads(m.read_text())
        except (OSError, ValueError):
            return []
        if not isinstance(data, dict) or data.get("command") != self.command:
            return []
        files = data.get("files", [])
        return [f for f in files if isinstance(f, str) and "/" not in f and f not in ("", ".", "..")]

    def check(self, names: Sequence[str], inputs: Sequence[str | Path] = ()) -> None:
        """Before any work: the directory can take ``names`` without replacing anything the
        command did not write."""
        p = self.path
        if p.is_symlink():
            raise OutputError(f"--out {p}: is a symbolic link; give the directory itself")
        if p.exists():
            if not p.is_dir():
                raise OutputError(f"--out {p}: exists and is not a directory")
            _writable_dir(p, "--out")
        else:
            _writable_dir(_existing_ancestor(p), f"--out {p}: its nearest existing parent")
        ours = set(self._listed())
        for name in [*names, MANIFEST]:
            f = p / name
            if _refuse_special(f, inputs) and name != MANIFEST and name not in ours:
                raise OutputError(f"{f}: exists and was not written by {self.command}; refused, never replaced")
        m = p / MANIFEST
        if m.exists() and not ours and self._foreign_manifest():
            raise OutputError(f"{m}: exists and was not written by {self.command}; refused, never replaced")

    def _foreign_manifest(self) -> bool:
        try:
            data = json.loads((self.path / MANIFEST).read_text())
        except (OSError, ValueError):
            return True
        return not (isinstance(data, dict) and data.get("command") == self.command)

    def stage(self, name: str, write: Callable[[Path], None]) -> None:
        """``write(tmp)`` into a temporary file for ``name``, renamed into place by :meth:`commit`;
        a write error (a full disk) removes what was staged and raises :class:`OutputError`."""
        if not self._staged and not self.path.exists():
            self._created = _existing_ancestor(self.path)
        tmp = self.path / f".{name}.tmp-{os.getpid()}"
        try:
            self.path.mkdir(parents=True, exist_ok=True)
            self._staged.append((tmp, self.path / name))
            write(tmp)
            _sync(tmp)
        except BaseException as e:
            self.abort()
            if isinstance(e, OSError):
                raise OutputError(f"{self.path / name}: cannot be written ({e.strerror or e}); "
                                  "the directory's files are as they were") from e
            raise

    def abort(self) -> None:
        """Removes the staged temporary files, and the directory if this run created it: the
        directory is as it was found."""
        for tmp, _ in self._staged:
            tmp.unlink(missing_ok=True)
        self._staged = []
        if self._created is not None:
            d = self.path.absolute()
            while d != self._created:
                try:
                    d.rmdir()
                except OSError:
                    break
                d = d.parent
            self._created = None

    def commit(self, manifest: dict) -> None:
        """The manifest (listing the staged files) and the staged files renamed into place,
        then the files the previous manifest listed that this run did not write removed (no
        stale pass beside new ones)."""
        names = [final.name for _, final in self._staged]
        previous = self._listed()
        self.stage(MANIFEST, lambda tmp: tmp.write_text(
            json.dumps({"command": self.command, **manifest, "files": names}, indent=1) + "\n"))
        try:
            for tmp, final in self._staged:
                os.replace(tmp, final)
        except OSError as e:
            self.abort()
            raise OutputError(f"{self.path}: cannot be written ({e.strerror or e})") from e
        self._staged = []
        for stale in set(previous) - set(names):
            f = self.path / stale
            if f.is_file() and not f.is_symlink():
                f.unlink()
