"""Reports of a graded submission: text (terminal), HTML (notebook), CSV.

They, and Gradescope's results.json (:mod:`autograder.gradescope_json`), say the same
things, shortly: per test, the points, how many cases passed, the known mistake the failures
match (with the lecture's formula), and the first failing case with its inputs, what came
back and what was expected.

What they say of each test and of the submission comes from :mod:`autograder.findings`,
which bounds every string that may come from the submission; :mod:`autograder.output`
writes the files.
"""

from __future__ import annotations

import html as _html
import textwrap
from dataclasses import fields
from typing import TYPE_CHECKING, Any

from .findings import bounded, header, points, scored, test_lines, utf8
from .results import Result

if TYPE_CHECKING:
    from .results import TestResult

BADGE = {"passed": "PASS", "partial": "PART", "failed": "FAIL", "not_implemented": "TODO",
         "not_run": "----"}
COLOURS = {"passed": "#1a7f37", "partial": "#b35900", "failed": "#cf222e",
           "not_implemented": "#6e7781", "not_run": "#6e7781"}


def _score(t: TestResult) -> str:
    """``0.5/1``, or ``n/m`` cases for an unscored test."""
    if not t.test.points:
        return f"{t.n_passed}/{len(t.cases)} cases"
    return f"{points(t.score)}/{points(t.test.points)}"


def _scope(result: Result) -> str:
    scope = "all tests" if result.hidden_run else "visible tests"
    if result.bonus_score:
        scope += f", including {points(result.bonus_score)} bonus points"
    return scope


def _shown(result: Result) -> list[TestResult]:
    """The tests a report lists: none for a submission not graded (none ran)."""
    return [] if result.not_graded else result.tests


def _total(result: Result) -> str:
    """``Score: 18 / 24 (all tests)``, or that it was not graded."""
    if result.not_graded:
        return f"Not graded: no score (of {points(result.max_score)} points)"
    return (f"Score: {points(result.score)} / {points(result.max_score)} "
            f"({_scope(result)})")


def text(result: Result, width: int = 100) -> str:
    """The terminal report."""
    out = header(result) + [""]
    name_w = max((len(t.test.name) for t in result.tests), default=10)
    for t in _shown(result):
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
    out += ["", f"{_total(result)}, checked in {result.elapsed:.1f} s"]
    if result.output.strip():
        shown = result.output.strip().splitlines()[:8]
        out += ["", "Your code printed (the grader ignores it):"] + [f"  | {s}" for s in shown]
    return utf8("\n".join(out))


def html(result: Result) -> str:
    """The notebook report, with a picture of the first failing rotation."""
    esc = _html.escape
    rows = []
    for t in _shown(result):
        colour = COLOURS[t.status]
        detail = "" if t.status == "passed" else "<br>".join(esc(s) for s in test_lines(t))
        rows.append(
            f"<tr><td style='color:{colour};font-weight:bold'>{BADGE[t.status]}</td>"
            f"<td>{esc(t.test.name)}</td><td style='text-align:right'>{_score(t)}</td>"
            f"<td style='text-align:left;font-size:90%'>{detail}</td></tr>")
    head = "<br>".join(esc(s) for s in header(result))
    picture = ""
    from .figures import first_failure_png

    png = first_failure_png(result)
    if png:
        picture = (f"<p>{esc(png[0])}</p><img src='data:image/png;base64,{png[1]}' "
                   "style='max-width:560px'>")
    return utf8(
        f"<div><p>{head}</p><table><tr><th></th><th>test</th><th>points</th><th>why</th></tr>"
        + "".join(rows)
        + f"</table><p><b>{esc(_total(result))}</b></p>{picture}</div>"
    )


class Report(Result):
    """A :class:`Result` that shows itself, as :func:`autograder.check` returns it:
    ``str(report)`` is the text report and a notebook shows the HTML one."""

    @classmethod
    def of(cls, result: Result) -> Report:
        return cls(**{f.name: getattr(result, f.name) for f in fields(Result)})

    def __str__(self) -> str:
        return text(self)

    def _repr_html_(self) -> str:
        return html(self)


CSV_FIXED = ["submission", "score", "max_score", "status", "reason", "misconceptions",
             "seconds", "isolation"]


def csv_header(result: Result) -> list[str]:
    return CSV_FIXED + [t.test.name for t in scored(result)]


NOT_GRADED = "not graded"  # a row's status when the machine or the grader failed: no score


def csv_row(name: str, result: Result) -> dict[str, Any]:
    """A row of ``grades.csv``; ``reason`` says why a refused submission was, or why one
    was not graded (one line): such a row's score and test columns are empty, never 0."""
    status = NOT_GRADED if result.not_graded else "refused" if result.problems else "graded"
    found = sorted({f"{t.test.function}:{t.misconception.key}" for t in scored(result)
                    if t.misconception})
    reason = bounded(" ".join((result.not_graded or "; ".join(result.problems)).split()))
    row: dict[str, Any] = {
        "submission": name, "score": "" if result.not_graded else round(result.score, 4),
        "max_score": result.max_score, "status": status, "reason": reason,
        "misconceptions": " ".join(found), "seconds": round(result.elapsed, 2),
        "isolation": str(result.isolation),
    }
    row.update({t.test.name: "" if result.not_graded else round(t.score, 4)
                for t in scored(result)})
    return row
