"""What a graded submission says, in the words every view shares.

The text and HTML report (:mod:`autograder.report`), Gradescope's results.json
(:mod:`autograder.gradescope_json`) and the class summary (:mod:`autograder.summary`) say
the same things of a :class:`~autograder.results.Result`: its header (what was graded, what
was refused, the notes), per test the lines that explain it, points written alike. They take
them from here, so no view reads another.

Much of what they say comes from the submission (file names, messages of its errors, notes
on its notebook), so every string is bounded (:func:`bounded`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .checks import show
from .sandbox import ISOLATION_NOTES
from .submission import printable

if TYPE_CHECKING:
    from .results import Result, TestResult
    from .spec import Case, Function

STOPPED = ("timeout", "crash")  # fatal outcomes that concern one case (garbage voids a test)
MAX_LINE = 2000  # characters of one problem, note or reason: far more than ours ever say
MAX_FIELD = 20_000  # characters of one field of results.json (a test's output, the header)


def bounded(text: str, limit: int = MAX_LINE) -> str:
    """``text`` cut to ``limit`` characters, saying how many were cut; characters that
    cannot be written as UTF-8 (lone surrogates) escaped."""
    if len(text) > limit:
        text = f"{text[:limit]} [... {len(text) - limit} characters cut]"
    return utf8(text)


def utf8(text: str) -> str:
    """``text`` with lone surrogates (which a forged JSON message can hold) escaped: print()
    and UTF-8 files would fail on them."""
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:
        return text.encode("utf-8", "backslashreplace").decode("utf-8")
    return text


def points(x: float) -> str:
    """Points as every view writes them: ``3``, ``0.5``, ``0.33``."""
    return f"{x:.2f}".rstrip("0").rstrip(".") if x != int(x) else f"{int(x)}"


def scored(result: Result) -> list[TestResult]:
    """The tests that count: unscored ones run on data only some machines have, so the
    class's results leave them out and are the same wherever they are graded."""
    return [t for t in result.tests if t.test.points]


def describe_args(fn: Function, case: Case) -> str:
    """``R = [[...]], t = 0.25`` for messages."""
    parts = []
    for name, a in zip(fn.params, case.args, strict=True):
        shown = show(a) if isinstance(a, np.ndarray) else f"{a:.4g}" if isinstance(a, float) else (
            _short_text(str(a)) if isinstance(a, str) else repr(a))
        parts.append(f"{name} = {shown}")
    return ", ".join(parts)


def _short_text(s: str, limit: int = 60) -> str:
    """A long string argument (a BVH hierarchy) as its start and its number of lines."""
    if len(s) <= limit:
        return repr(s)
    return f"{s[:limit]!r}... (a text of {len(s.splitlines())} lines)"


def test_lines(t: TestResult) -> list[str]:
    """What a test's report says, one item per line (without the header)."""
    if t.note:
        return [t.note]
    n = len(t.cases)
    if t.status == "passed":
        return [f"all {n} cases pass"]
    if t.status == "not_implemented":
        return ["not implemented yet"]
    lines = [f"{t.n_passed} of {n} cases pass."]
    if t.misconception:
        m = t.misconception
        lines.append(f"Likely mistake, {m.title}: {m.explanation}")
    first = t.first_failure
    assert first is not None
    lines += [f"First failing case ({first.case.label}):",
              f"  {t.function.name}({describe_args(t.function, first.case)})",
              f"  {first.reason}"]
    stopped = [c for c in t.cases if c.kind in STOPPED and c is not first]
    if stopped:  # which other cases ran out of time or crashed (the first may not have)
        said = [c.case.label if c.reason == first.reason else f"{c.case.label} ({c.reason})"
                for c in stopped[:3]]
        more = f" and {len(stopped) - 3} more" if len(stopped) > 3 else ""
        same = " (the same)" if all(c.reason == first.reason for c in stopped) else ""
        lines.append(f"Also stopped the interpreter{same}: {'; '.join(said)}{more}")
    return lines


def header(result: Result) -> list[str]:
    a = result.assignment
    lines = [f"{a.key} · {a.title} · {printable(result.submission)}"]
    if not result.hidden_run:
        lines.append("Visible tests only: hidden tests run when your instructor grades "
                     "(with a secret seed).")
    if result.not_graded:
        lines.append(f"Not graded: {bounded(result.not_graded)}. This is the grading machine's "
                     "fault, not your code's; nothing was scored, so grading it again is safe.")
    lines += [f"Refused: {bounded(p)}" for p in result.problems]
    lines += [f"Note: {bounded(n)}" for n in result.notes]
    if ISOLATION_NOTES.get(result.isolation):
        lines.append(ISOLATION_NOTES[result.isolation])
    return lines
