"""Reports of a graded submission: text (terminal), HTML (notebook), Gradescope JSON, CSV.

All of them say the same things, shortly: per test, the points, how many cases passed, the
known mistake the failures match (with the lecture's formula), and the first failing case
with its inputs, what came back and what was expected.

Much of what they say comes from the submission (file names, messages of its errors, notes
on its notebook), so every string is bounded (:func:`bounded`), and CSV cells that a
spreadsheet would run as a formula are quoted (:func:`csv_cell`).
"""

from __future__ import annotations

import csv
import html as _html
import os
import stat
import textwrap
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO

import numpy as np

from .checks import show
from .sandbox import ISOLATION_NOTES
from .submission import printable

if TYPE_CHECKING:  # results.py builds its str() and HTML from here: hints only, no circle
    from .results import Result, TestResult
    from .spec import Case, Function

BADGE = {"passed": "PASS", "partial": "PART", "failed": "FAIL", "not_implemented": "TODO",
         "not_run": "----"}
STOPPED = ("timeout", "crash")  # fatal outcomes that concern one case (garbage voids a test)
COLOURS = {"passed": "#1a7f37", "partial": "#b35900", "failed": "#cf222e",
           "not_implemented": "#6e7781", "not_run": "#6e7781"}
MAX_LINE = 2000  # characters of one problem, note or reason: far more than ours ever say
MAX_FIELD = 20_000  # characters of one field of results.json (a test's output, the header)
FORMULA = ("=", "+", "-", "@", "\t", "\r")  # what starts a formula in a spreadsheet (OWASP)
# O_NOFOLLOW: a link planted where a result goes is not written through; O_NONBLOCK: a FIFO
# there fails at once instead of blocking until someone reads it; O_BINARY: Windows writes
# the newlines it is given.
WRITE_FLAGS = (os.O_WRONLY | os.O_CREAT | os.O_TRUNC | getattr(os, "O_NOFOLLOW", 0)
               | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0))


def bounded(text: str, limit: int = MAX_LINE) -> str:
    """``text`` cut to ``limit`` characters, saying how many were cut; characters that
    cannot be written as UTF-8 (lone surrogates) escaped."""
    if len(text) > limit:
        text = f"{text[:limit]} [... {len(text) - limit} characters cut]"
    return _utf8(text)


def _utf8(text: str) -> str:
    """``text`` with lone surrogates (which a forged JSON message can hold) escaped: print()
    and UTF-8 files would fail on them."""
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:
        return text.encode("utf-8", "backslashreplace").decode("utf-8")
    return text


def _points(x: float) -> str:
    return f"{x:.2f}".rstrip("0").rstrip(".") if x != int(x) else f"{int(x)}"


def _score(t: TestResult) -> str:
    """``0.5/1``, or ``n/m`` cases for an unscored test."""
    if not t.test.points:
        return f"{t.n_passed}/{len(t.cases)} cases"
    return f"{_points(t.score)}/{_points(t.test.points)}"


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
    lines += [f"Refused: {bounded(p)}" for p in result.problems]
    lines += [f"Note: {bounded(n)}" for n in result.notes]
    if ISOLATION_NOTES.get(result.isolation):
        lines.append(ISOLATION_NOTES[result.isolation])
    return lines


def _scope(result: Result) -> str:
    scope = "all tests" if result.hidden_run else "visible tests"
    if result.bonus_score:
        scope += f", including {_points(result.bonus_score)} bonus points"
    return scope


def text(result: Result, width: int = 100) -> str:
    """The terminal report."""
    out = header(result) + [""]
    name_w = max((len(t.test.name) for t in result.tests), default=10)
    for t in result.tests:
        out.append(f"  {BADGE[t.status]}  {t.test.name:<{name_w}}  {_score(t):>7}")
        if t.status == "passed":
            continue
        lines = test_lines(t)
        if len(lines) == 1 and len(lines[0]) < 60:
            out[-1] += f"   {lines[0]}"
            continue
        for line in lines:
            indent = " " * (8 + len(line) - len(line.lstrip()))
            out += textwrap.wrap(line.strip(), width, initial_indent=indent,
                                 subsequent_indent=indent + "  ")
    scope = _scope(result)
    out += ["", f"Score: {_points(result.score)} / {_points(result.max_score)} ({scope}), "
                f"checked in {result.elapsed:.1f} s"]
    if result.output.strip():
        shown = result.output.strip().splitlines()[:8]
        out += ["", "Your code printed (the grader ignores it):"] + [f"  | {s}" for s in shown]
    return _utf8("\n".join(out))


def html(result: Result) -> str:
    """The notebook report, with a picture of the first failing rotation."""
    esc = _html.escape
    rows = []
    for t in result.tests:
        colour = COLOURS[t.status]
        detail = "" if t.status == "passed" else "<br>".join(esc(s) for s in test_lines(t))
        rows.append(
            f"<tr><td style='color:{colour};font-weight:bold'>{BADGE[t.status]}</td>"
            f"<td>{esc(t.test.name)}</td><td style='text-align:right'>{_score(t)}</td>"
            f"<td style='text-align:left;font-size:90%'>{detail}</td></tr>")
    head = "<br>".join(esc(s) for s in header(result))
    scope = _scope(result)
    picture = ""
    from .figures import first_failure_png

    png = first_failure_png(result)
    if png:
        picture = (f"<p>{esc(png[0])}</p><img src='data:image/png;base64,{png[1]}' "
                   "style='max-width:560px'>")
    return _utf8(
        f"<div><p>{head}</p><table><tr><th></th><th>test</th><th>points</th><th>why</th></tr>"
        + "".join(rows)
        + f"</table><p><b>Score: {_points(result.score)} / {_points(result.max_score)}</b> "
        f"({scope})</p>{picture}</div>"
    )


def _scored(result: Result) -> list[TestResult]:
    """The tests that count: unscored ones run on data only some machines have, so the
    class's results leave them out and are the same wherever they are graded."""
    return [t for t in result.tests if t.test.points]


CSV_FIXED = ["submission", "score", "max_score", "status", "reason", "misconceptions",
             "seconds", "isolation"]


def csv_header(result: Result) -> list[str]:
    return CSV_FIXED + [t.test.name for t in _scored(result)]


def csv_row(name: str, result: Result) -> dict[str, Any]:
    """A row of ``grades.csv``; ``reason`` says why a refused submission was (one line)."""
    status = "refused" if result.problems else "graded"
    found = sorted({f"{t.test.function}:{t.misconception.key}" for t in _scored(result)
                    if t.misconception})
    reason = bounded(" ".join("; ".join(result.problems).split()))
    row: dict[str, Any] = {
        "submission": name, "score": round(result.score, 4), "max_score": result.max_score,
        "status": status, "reason": reason, "misconceptions": " ".join(found),
        "seconds": round(result.elapsed, 2), "isolation": str(result.isolation),
    }
    row.update({t.test.name: round(t.score, 4) for t in _scored(result)})
    return row


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
