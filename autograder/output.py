"""The files a grading writes (results.json, grades.csv, the LMS exports, summary.html), written
safely: nothing through a link or into a FIFO planted where they go, and no CSV cell that a
spreadsheet would run as a formula (:func:`csv_cell`)."""

from __future__ import annotations

import csv
import os
import stat
from pathlib import Path
from typing import Any, TextIO

from .safe_text import MAX_FIELD, bounded, printable

FORMULA = ("=", "+", "-", "@", "\t", "\r")  # what starts a formula in a spreadsheet (OWASP)
# O_NOFOLLOW: a link planted where a result goes is not written through; O_NONBLOCK: a FIFO
# there fails at once instead of blocking until someone reads it; O_BINARY: Windows writes
# the newlines it is given.
WRITE_FLAGS = (os.O_WRONLY | os.O_CREAT | os.O_TRUNC | getattr(os, "O_NOFOLLOW", 0)
               | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0))


def csv_cell(value: Any) -> Any:
    """A text cell that would start a formula, quoted with ``'`` (OWASP's advice) so that a
    spreadsheet shows it as text; numbers as they are."""
    if isinstance(value, str):
        value = bounded(value, MAX_FIELD)
        return "'" + value if value.startswith(FORMULA) else value
    return value


def write_csv(path: Path, header_: list[str], rows: list[dict[str, Any]]) -> None:
    with create(path) as f:
        w = csv.writer(f)
        w.writerow([csv_cell(h) for h in header_])
        w.writerows([csv_cell(row.get(h, "")) for h in header_] for row in rows)


def create(path: Path) -> TextIO:
    """``path`` opened to be written as UTF-8 text (from the start), if it is a regular file
    or new; a link or special file there is an ``OSError``, and is left as it is."""
    fd = os.open(path, WRITE_FLAGS, 0o644)
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise OSError(f"{printable(path)} is not a regular file")
    except BaseException:
        os.close(fd)
        raise
    return open(fd, "w", encoding="utf-8", errors="backslashreplace", newline="")
