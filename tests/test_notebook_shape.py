"""A lecture notebook reads like a lecture: short code cells showing the lecture's math, and at
least as much prose as code (issue "students do, not only read").

Measured in characters of non-blank text, so re-wrapping lines changes nothing; plotting and
widget plumbing belong in `course.viz` (documented, tested), not in the cells a student reads.
A predict-then-run question (`quiz(...)`) is a code cell that shows only its question, choices
and explanation, so it counts as prose.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
LECTURES = sorted(REPO.glob("notebooks/[0-9][0-9]_*.ipynb"))
MAX_CELL_LINES = 25


def _cells(path: Path) -> list[tuple[str, str]]:
    cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
    return [(c["cell_type"], "".join(c["source"])) for c in cells]


def _text(source: str) -> str:
    return "".join(line.strip() for line in source.splitlines())


@pytest.mark.parametrize("path", LECTURES, ids=lambda p: p.name)
def test_no_long_code_cell(path):
    long = [(i, len(src.splitlines())) for i, (kind, src) in enumerate(_cells(path))
            if kind == "code" and len(src.splitlines()) > MAX_CELL_LINES]
    assert not long, f"{path.name}: code cells (index, lines) over {MAX_CELL_LINES} lines: {long}"


@pytest.mark.parametrize("path", LECTURES, ids=lambda p: p.name)
def test_prose_at_least_as_long_as_code(path):
    cells = _cells(path)
    def is_prose(kind: str, src: str) -> bool:
        return kind == "markdown" or src.lstrip().startswith("quiz(")

    code = sum(len(_text(src)) for kind, src in cells if not is_prose(kind, src))
    prose = sum(len(_text(src)) for kind, src in cells if is_prose(kind, src))
    assert prose >= code, f"{path.name}: {prose} characters of prose for {code} of code"
