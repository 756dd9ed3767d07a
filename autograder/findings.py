"""What a graded submission says: one frozen record, built once from its
:class:`~autograder.results.Result`, that every view only renders.

:meth:`Findings.of` says, once, what was graded (the header: the file, the refusals, the
notes, the isolation), which tests count (:attr:`Findings.scored`) and, per test
(:class:`TestFindings`), its status, its points, the lines that explain it, its failing
cases (the first one first) and the mistake they show. The text and HTML report
(:mod:`autograder.report`, with :mod:`autograder.figures`' picture), Gradescope's
results.json (:mod:`autograder.gradescope_json`), the row of ``grades.csv``, the class
summary's facts (:mod:`autograder.summary`) and the notebooks' checks
(:mod:`course.exercises`) lay it out, each in its own medium; none reads a
:class:`~autograder.results.Result` or another view.

Part of the judging core: it imports results, never a view, and loads no sandbox. Much of
what it holds comes from the submission (file names, messages of its errors, notes on its
notebook), so every string is made printable or bounded (:mod:`autograder.safe_text`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .checks import show
from .limits import ISOLATION_NOTES
from .safe_text import bounded, printable

if TYPE_CHECKING:
    from .results import CaseResult, Result, TestResult
    from .spec import Case, Function, Misconception

STOPPED = ("timeout", "crash")  # fatal outcomes that concern one case (garbage voids a test)


# --- the words every view shares -----------------------------------------------------------

def points(x: float) -> str:
    """Points as every view writes them: ``3``, ``0.5``, ``0.33``."""
    return f"{x:.2f}".rstrip("0").rstrip(".") if x != int(x) else f"{int(x)}"


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


# --- the record --------------------------------------------------------------------------------

@dataclass(frozen=True)
class Failure:
    """A failing case: its ``case`` (label and arguments), its ``kind`` (as
    :class:`~autograder.results.CaseResult`'s), why it failed (one line), and what came
    back and what was expected (``got`` is None without an answer of the right shape)."""

    case: Case
    kind: str
    reason: str
    got: Any = None
    expected: Any = None

    @classmethod
    def of(cls, c: CaseResult) -> Failure:
        return cls(c.case, c.kind, c.reason, c.got, c.expected)


@dataclass(frozen=True)
class TestFindings:
    """What one test says: its ``name``, the ``function`` it tests (the assignment's name,
    as the CSV and results.json key its mistakes) and ``spec``, that function as the
    submission names it (its parameters, check and picture); its ``status`` (as
    :attr:`~autograder.results.TestResult.status`), ``passed`` of its ``cases``, its
    ``score`` of ``points`` (0: unscored, left out of the class's results), whether it is
    ``hidden`` or a ``bonus``; the ``lines`` that explain it, its ``failures`` in order,
    ``call``, the first one written as a call (``fn(R = ...)``, "" if none), and the
    ``mistake`` they show; and the seconds its cases took."""

    name: str
    function: str
    spec: Function
    status: str
    passed: int
    cases: int
    score: float
    points: float
    hidden: bool
    bonus: bool
    lines: tuple[str, ...]
    failures: tuple[Failure, ...]
    call: str
    mistake: Misconception | None
    elapsed: float

    @property
    def first(self) -> Failure | None:
        """The first failing case."""
        return self.failures[0] if self.failures else None

    @classmethod
    def of(cls, t: TestResult) -> TestFindings:
        failures = tuple(Failure.of(c) for c in t.cases if not c.passed)
        call = (f"{t.function.name}({describe_args(t.function, failures[0].case)})"
                if failures else "")
        return cls(name=t.test.name, function=t.test.function, spec=t.function,
                   status=t.status, passed=t.n_passed, cases=len(t.cases), score=t.score,
                   points=t.test.points, hidden=t.test.hidden, bonus=t.test.bonus,
                   lines=tuple(_lines(t, failures, call)), failures=failures, call=call,
                   mistake=t.misconception, elapsed=t.elapsed)


def _lines(t: TestResult, failures: tuple[Failure, ...], call: str) -> list[str]:
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
    if not failures:  # a test with neither cases nor a note: nothing more to say
        return lines
    first = failures[0]
    lines += [f"First failing case ({first.case.label}):", f"  {call}", f"  {first.reason}"]
    stopped = [c for c in failures[1:] if c.kind in STOPPED]
    if stopped:  # which other cases ran out of time or crashed (the first may not have)
        said = [c.case.label if c.reason == first.reason else f"{c.case.label} ({c.reason})"
                for c in stopped[:3]]
        more = f" and {len(stopped) - 3} more" if len(stopped) > 3 else ""
        same = " (the same)" if all(c.reason == first.reason for c in stopped) else ""
        lines.append(f"Also stopped the interpreter{same}: {'; '.join(said)}{more}")
    return lines


@dataclass(frozen=True)
class Findings:
    """What a graded submission says, built once (:meth:`of`) and rendered by every view.

    ``assignment`` and ``title`` name the assignment, ``path`` the file graded; ``header``
    is what every view says first (what was graded, the refusals, the notes, the isolation),
    bounded; ``refusals``, ``notes`` and ``not_graded`` (why the machine or the grader, not
    the submission, failed: then nothing is scored) are as the grading found them.
    ``tests`` are every test run, ``score`` / ``max_score`` / ``bonus_score`` the points,
    ``output`` what the submission printed and ``elapsed`` the seconds it all took."""

    assignment: str
    title: str
    path: Path
    header: tuple[str, ...]
    refusals: tuple[str, ...]
    notes: tuple[str, ...]
    not_graded: str
    hidden_run: bool
    isolation: str
    tests: tuple[TestFindings, ...]
    score: float
    max_score: float
    bonus_score: float
    output: str
    elapsed: float

    @property
    def scored(self) -> tuple[TestFindings, ...]:
        """The tests that count: unscored ones run on data only some machines have, so the
        class's results leave them out and are the same wherever they are graded."""
        return tuple(t for t in self.tests if t.points)

    @property
    def shown(self) -> tuple[TestFindings, ...]:
        """The tests a report lists: none for a submission not graded (none ran)."""
        return () if self.not_graded else self.tests

    @property
    def refused(self) -> str:
        """Every refusal, in one string ("" if none)."""
        return "; ".join(self.refusals)

    @classmethod
    def of(cls, result: Result) -> Findings:
        a = result.assignment
        return cls(assignment=a.key, title=a.title, path=result.submission,
                   header=tuple(_header(result)), refusals=tuple(result.problems),
                   notes=tuple(result.notes), not_graded=result.not_graded,
                   hidden_run=result.hidden_run, isolation=str(result.isolation),
                   tests=tuple(TestFindings.of(t) for t in result.tests), score=result.score,
                   max_score=result.max_score, bonus_score=result.bonus_score,
                   output=result.output, elapsed=result.elapsed)


def _header(result: Result) -> list[str]:
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
