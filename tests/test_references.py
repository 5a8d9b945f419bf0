"""References between the repository's files: every `docs/NAME.md` and `tests/NAME.py` path named
in the docs, the Python sources, the Rust sources and the Cargo/pyproject/requirements files
exists; every `cargo xtask CMD` named is a command of xtask's usage text; every relative
Markdown link between docs resolves. Oracle: the file system and xtask's USAGE text."""

from __future__ import annotations

import re
from pathlib import Path

from project import REPO

SKIP = {"target", ".venv", ".git", "node_modules", "__pycache__"}
SUFFIXES = {".md", ".py", ".pyi", ".rs", ".toml", ".txt"}
PATH = re.compile(r"(?<![\w/.-])((?:docs|tests)/[\w.-]+\.(?:md|py))")
XTASK = re.compile(r"cargo xtask ([a-z][\w-]*)")
LINK = re.compile(r"\]\(([\w./-]+\.md)(?:#[\w-]*)?\)")


def sources() -> list[Path]:
    """The files scanned: not build outputs, and not this file (its examples are dangling on purpose)."""
    return sorted(p for p in REPO.rglob("*") if p.suffix in SUFFIXES and p.is_file()
                  and not SKIP.intersection(p.relative_to(REPO).parts) and p != Path(__file__).resolve())


def xtask_commands() -> set[str]:
    """The commands of xtask's USAGE text, wherever in xtask/src it is defined."""
    text = next(t for t in (p.read_text() for p in sorted((REPO / "xtask" / "src").glob("*.rs")))
                if "const USAGE" in t)
    usage = text[text.index("const USAGE"):]
    usage = usage[:usage.index('";')]
    commands = set(re.findall(r"^  ([a-z][\w-]*)", usage, re.M))
    assert {"test", "demo", "fmu"} <= commands, commands
    return commands


def test_named_docs_tests_and_xtask_commands_exist():
    commands = xtask_commands()
    files = sources()
    assert len(files) > 50 and any(p.name == "python.md" for p in files)
    dangling = []
    for p in files:
        text = p.read_text(errors="replace")
        where = p.relative_to(REPO)
        dangling += [f"{where}: {m}" for m in PATH.findall(text) if not (REPO / m).is_file()]
        dangling += [f"{where}: cargo xtask {m}" for m in XTASK.findall(text) if m not in commands]
        if p.suffix == ".md":
            dangling += [f"{where}: link {m}" for m in LINK.findall(text)
                         if "://" not in m and not (p.parent / m).is_file()]
    assert not dangling, "\n".join(dangling)


def test_the_scan_finds_a_dangling_reference(tmp_path):
    """The patterns catch the forms the issue found (docs/fleet.md, tests/demo.py, `cargo xtask
    python`), so an empty result above means something."""
    text = "see docs/fleet.md and (tests/demo.py); run `cargo xtask python` or cargo xtask test"
    assert PATH.findall(text) == ["docs/fleet.md", "tests/demo.py"]
    assert XTASK.findall(text) == ["python", "test"]
    assert "python" not in xtask_commands()
