"""Which file of a student's folder is graded: one policy, for the local pool, the cluster and
Gradescope alike, so the same upload is graded the same way everywhere.

A folder (a student's folder of an LMS export, Gradescope's ``submission/``) is searched
without following links, hidden entries and an archiver's or Python's folders left out, to
at most :data:`MAX_DEPTH` levels and :data:`MAX_ENTRIES` entries. Of the ``.py`` and
``.ipynb`` files found (:func:`choose`):

1. the file named like the template, the shallowest (a ``.py`` before a notebook; where
   several are equally shallow, the rule 3 among them);
2. else the only file;
3. else the one file that defines the most of the assignment's functions (at least one);
4. else none: the folder is refused with the files listed, because any pick would be a guess
   that the student cannot see coming.

Nothing is read here but the files' text (to count their ``def``); a link or special file
chosen is refused when it is read (:func:`autograder.submission.read_regular`).
"""

from __future__ import annotations

import itertools
import os
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from .safe_text import printable
from .submission import SubmissionError, read_regular

SUFFIXES = (".py", ".ipynb")
MAX_DEPTH = 32  # folder levels searched inside a student's folder
MAX_ENTRIES = 2000  # files and folders looked at inside a student's folder, in all
JUNK = frozenset({"__MACOSX", "__pycache__"})  # an archiver's or Python's, not the student's


@dataclass(frozen=True)
class Choice:
    """The file of a folder to grade and a sentence saying which and why; or no file, with
    ``refused`` saying why nothing can be graded ("" when the folder holds no file at all)."""

    path: Path | None
    said: str
    refused: str = ""


def choose(folder: Path, template: str, functions: Sequence[str], shown: str = "") -> Choice:
    """The file of ``folder`` to grade for an assignment whose template is ``template`` and
    whose functions are ``functions`` (the policy of this module's docstring). ``shown``
    names the folder in the sentences (its path by default)."""
    shown = shown or printable(folder)
    files, cut = search(folder)
    if cut:
        return Choice(None, "", f"{shown} has no {template} and could not be searched for "
                                f"one: {cut}")
    if not files:
        return Choice(None, "")

    def rel(path: Path) -> str:
        return printable(path.relative_to(folder))

    stem = Path(template).stem
    pool = files
    named = [f for f in files if f.stem == stem]
    if named:
        top = min(_depth(f, folder) for f in named)
        named = [f for f in named if _depth(f, folder) == top]
        pool = [f for f in named if f.suffix == ".py"] or named
        if len(pool) == 1:
            return Choice(pool[0], f"Graded {rel(pool[0])}" + (
                "." if len(files) == 1 else f", named like the template, of your "
                                            f"{len(files)} files."))
    if len(files) == 1:
        return Choice(files[0], f"Graded {rel(files[0])}.")
    counts = [(len(defines(f, functions)), f) for f in pool]
    most = max(n for n, _ in counts)
    leaders = [f for n, f in counts if n == most]
    if most and len(leaders) == 1:
        return Choice(leaders[0], f"Graded {rel(leaders[0])}, the one of your {len(files)} "
                                  f"files that defines the most of the assignment's functions "
                                  f"({most} of {len(functions)}).")
    listed = leaders if most else pool
    some = ", ".join(rel(f) for f in listed[:3])
    more = f" and {len(listed) - 3} more" if len(listed) > 3 else ""
    why = (f"{len(leaders)} of them define {most} of its functions each" if most
           else "none defines any of its functions")
    what = (f"{len(pool)} files named like {template} at the same depth" if named
            else f"no {template} but {len(files)} .py/.ipynb files")
    return Choice(None, "", f"{shown} has {what} ({some}{more}; {why}): cannot tell which "
                            "one to grade")


def _depth(path: Path, folder: Path) -> int:
    return len(path.relative_to(folder).parts)


def search(folder: Path) -> tuple[list[Path], str]:
    """The ``.py``/``.ipynb`` entries below ``folder`` (links too: refused when read), hidden
    ones and links to folders left out, and why the search stopped short if it did.
    Iterative, never following a link, at most :data:`MAX_DEPTH` levels and
    :data:`MAX_ENTRIES` entries."""
    found: list[Path] = []
    stack, seen = [(folder, 1)], 0
    while stack:
        here, depth = stack.pop()
        try:
            with os.scandir(here) as it:
                entries = sorted(itertools.islice(it, MAX_ENTRIES - seen + 1),
                                 key=lambda e: e.name)
        except OSError as exc:
            return found, f"a folder in it cannot be read ({exc.strerror})"
        seen += len(entries)
        if seen > MAX_ENTRIES:
            return found, f"it holds more than {MAX_ENTRIES} files and folders"
        for e in reversed(entries):  # popped in name order
            if e.name.startswith(".") or e.name in JUNK:
                continue
            if is_dir(e):
                if depth >= MAX_DEPTH:
                    return found, f"its folders nest deeper than {MAX_DEPTH} levels"
                stack.append((Path(e.path), depth + 1))
            elif Path(e.path).suffix in SUFFIXES:
                found.append(Path(e.path))
    return sorted(found), ""


def is_dir(entry: os.DirEntry[str]) -> bool:
    """A folder, not a link to one (an entry that vanished or cannot be read is not)."""
    try:
        return entry.is_dir(follow_symlinks=False)
    except OSError:
        return False


def defines(path: Path, names: Sequence[str]) -> list[str]:
    """Which of ``names`` ``path`` defines with a ``def`` (in a notebook, in a code cell's
    JSON string); read as text, so a file that does not parse still counts."""
    try:
        text = read_regular(path)
    except (SubmissionError, OSError):
        return []
    defined = set(re.findall(r'(?:^|")[ \t]*def[ \t]+(\w+)[ \t]*\(', text, re.MULTILINE))
    return [n for n in names if n in defined]
