"""Code, tests and README describe the product, not the work that made it.

A reader needs what a thing does, why, and the current measured number with the command that
measures it; which work round or tracker entry changed it belongs in the commit messages. So no
file of lfdfuse/, tests/ or the README names a round ("stop" and a number) or a tracker entry
("issue" and a number).
"""

from __future__ import annotations

import re
from pathlib import Path

from tests.conftest import ROOT

#: a work round or a tracker entry by number (one, several, or a range of rounds); the words are
#: split so this file does not match itself
ROUND, ENTRY = "st" + "op", "iss" + "ue"
HISTORY = re.compile(
    rf"\b({ROUND} [0-9]{{2}}|{ROUND}s [0-9]{{2}}[-–][0-9]{{2}}|{ENTRY}s? [0-9]{{1,2}})\b", re.IGNORECASE
)
#: text files a reader opens
SUFFIXES = {".py", ".md", ".yaml", ".yml", ".json", ".toml", ".txt", ".cfg"}


def _documents() -> list[Path]:
    files = [ROOT / "README.md"]
    for top in ("lfdfuse", "tests"):
        files += [
            p
            for p in sorted((ROOT / top).rglob("*"))
            if p.is_file() and p.suffix in SUFFIXES and "__pycache__" not in p.parts
        ]
    return files


def history_lines(text: str) -> list[tuple[int, str]]:
    """The lines of ``text`` (numbered from 1) that cite a work round or a tracker entry."""
    return [(i, line.strip()) for i, line in enumerate(text.splitlines(), 1) if HISTORY.search(line)]


def test_the_pattern_finds_rounds_and_tracker_entries_and_nothing_else() -> None:
    cited = [
        "St" + "op 28 chose on tuning seeds",
        "developed in st" + "ops 26-27",
        "as iss" + "ue 21 asks",
        "(ISS" + "UE 9)",
        "(iss" + "ues 15, 21)",
    ]
    assert all(history_lines(s) for s in cited)
    innocent = [
        "the robot stops 20 cm short",
        "a stop 5 s long",
        "an issue tracker",
        "tissue 12",
        "nonstop 12",
    ]
    assert not any(history_lines(s) for s in innocent)


def test_no_document_tells_its_history() -> None:
    files = _documents()
    assert len(files) > 100  # the package, the tests and the README are all read
    hits = [
        f"{path.relative_to(ROOT)}:{i}: {line}"
        for path in files
        for i, line in history_lines(path.read_text(errors="replace"))
    ]
    assert not hits, "history belongs in commit messages:\n  " + "\n  ".join(hits)
