"""Reports of a graded submission: text (terminal), HTML (notebook), CSV.

They, and Gradescope's results.json (:mod:`autograder.gradescope_json`), say the same
things, shortly: per test, the points, how many cases passed, the known mistake the failures
match (with the lecture's formula), and the first failing case with its inputs, what came
back and what was expected.

They render a submission's :class:`~autograder.findings.Findings`, built once from its
result, which has every line already said and every string from the submission bounded;
:mod:`autograder.output` writes the files.
"""

from __future__ import annotations

import html as _html
import textwrap
from dataclasses import fields
from functools import cached_property
from typing import Any

from .findings import Findings, TestFindings, points
from .results import Result
from .safe_text import one_line, utf8

BADGE = {"passed": "PASS", "partial": "PART", "failed": "FAIL", "not_implemented": "TODO",
         "not_run": "----"}
COLOURS = {"passed": "#1a7f37", "partial": "#b35900", "failed": "#cf222e",
           "not_implemented": "#6e7781", "not_run": "#6e7781"}


def _score(t: TestFindings) -> str:
    """``0.5/1``, or ``n/m`` cases for an unscored test."""
    if not t.points:
        return f"{t.passed}/{t.cases} cases"
    return f"{points(t.score)}/{points(t.points)}"


def _scope(f: Findings) -> str:
    scope = "all tests" if f.hidden_run else "visible tests"
    if f.bonus_score:
        scope += f", including {points(f.bonus_score)} bonus points"
    return scope


def _total(f: Findings) -> str:
    """``Score: 18 / 24 (all tests)``, or that it was not graded."""
    if f.not_graded:
        return f"Not graded: no score (of {points(f.max_score)} points)"
    return f"Score: {points(f.score)} / {points(f.max_score)} ({_scope(f)})"


def text(f: Findings, width: int = 100) -> str:
    """The terminal report."""
    out = [*f.header, ""]
    name_w = max((len(t.name) for t in f.tests), default=10)
    for t in f.shown:
        out.append(f"  {BADGE[t.status]}  {t.name:<{name_w}}  {_score(t):>7}")
        if t.status == "passed":
            continue
        if len(t.lines) == 1 and len(t.lines[0]) < 60:
            out[-1] += f"   {t.lines[0]}"
            continue
        for line in t.lines:
            indent = " " * (8 + len(line) - len(line.lstrip()))
            out += textwrap.wrap(line.strip(), width, initial_indent=indent,
                                 subsequent_indent=indent + "  ")
    out += ["", f"{_total(f)}, checked in {f.elapsed:.1f} s"]
    if f.output.strip():
        shown = f.output.strip().splitlines()[:8]
        out += ["", "Your code printed (the grader ignores it):"] + [f"  | {s}" for s in shown]
    return utf8("\n".join(out))


def html(f: Findings) -> str:
    """The notebook report, with a picture of the first failing rotation."""
    esc = _html.escape
    rows = []
    for t in f.shown:
        colour = COLOURS[t.status]
        detail = "" if t.status == "passed" else "<br>".join(esc(s) for s in t.lines)
        rows.append(
            f"<tr><td style='color:{colour};font-weight:bold'>{BADGE[t.status]}</td>"
            f"<td>{esc(t.name)}</td><td style='text-align:right'>{_score(t)}</td>"
            f"<td style='text-align:left;font-size:90%'>{detail}</td></tr>")
    head = "<br>".join(esc(s) for s in f.header)
    picture = ""
    from .figures import first_failure_png

    png = first_failure_png(f)
    if png:
        picture = (f"<p>{esc(png[0])}</p><img src='data:image/png;base64,{png[1]}' "
                   "style='max-width:560px'>")
    return utf8(
        f"<div><p>{head}</p><table><tr><th></th><th>test</th><th>points</th><th>why</th></tr>"
        + "".join(rows)
        + f"</table><p><b>{esc(_total(f))}</b></p>{picture}</div>"
    )


class Report(Result):
    """A :class:`Result` that shows itself, as :func:`autograder.check` returns it:
    ``str(report)`` is the text report and a notebook shows the HTML one, both rendered from
    its :attr:`findings`."""

    @classmethod
    def of(cls, result: Result) -> Report:
        return cls(**{f.name: getattr(result, f.name) for f in fields(Result)})

    @cached_property
    def findings(self) -> Findings:
        """What it says, built on first use."""
        return Findings.of(self)

    def __str__(self) -> str:
        return text(self.findings)

    def _repr_html_(self) -> str:
        return html(self.findings)


CSV_FIXED = ["submission", "score", "max_score", "status", "reason", "misconceptions",
             "seconds", "isolation"]


def csv_header(f: Findings) -> list[str]:
    return CSV_FIXED + [t.name for t in f.scored]


NOT_GRADED = "not graded"  # a row's status when the machine or the grader failed: no score


def csv_row(name: str, f: Findings) -> dict[str, Any]:
    """A row of ``grades.csv``; ``reason`` says why a refused submission was, or why one
    was not graded (one line): such a row's score and test columns are empty, never 0."""
    status = NOT_GRADED if f.not_graded else "refused" if f.refusals else "graded"
    found = sorted({f"{t.function}:{t.mistake.key}" for t in f.scored if t.mistake})
    row: dict[str, Any] = {
        "submission": name, "score": "" if f.not_graded else round(f.score, 4),
        "max_score": f.max_score, "status": status,
        "reason": one_line(f.not_graded or f.refused),
        "misconceptions": " ".join(found), "seconds": round(f.elapsed, 2),
        "isolation": f.isolation,
    }
    row.update({t.name: "" if f.not_graded else round(t.score, 4) for t in f.scored})
    return row
