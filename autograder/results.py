"""What grading one submission found: per case, per test, per submission.

Plain data with the scores derived from it: :mod:`autograder.runner` (or a notebook's
self-check) fills it in; the views (the text and HTML report, Gradescope's results.json, the
class summary, the CSV and LMS exports) import it and say it. It imports no view.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .spec import Assignment, Case, Function, Misconception, Test


@dataclass
class CaseResult:
    """One case: passed or not, why not (one line), and the output if it had the right shape.

    ``kind`` is ``"pass"``, ``"wrong"`` (a valid answer that differs), ``"invalid"`` (wrong
    type, shape, NaN...), ``"error"`` (``error`` holds its type and message),
    ``"not_implemented"``, ``"timeout"``, ``"crash"``, ``"garbage"`` or ``"skipped"``.
    """

    case: Case
    kind: str
    reason: str = ""
    got: Any = None
    expected: Any = None
    error: dict[str, Any] | None = None

    @property
    def passed(self) -> bool:
        return self.kind == "pass"


@dataclass
class TestResult:
    """A test's cases, its score (points times the fraction passed) and its diagnosis."""

    test: Test
    function: Function
    cases: list[CaseResult] = field(default_factory=list)
    misconception: Misconception | None = None
    note: str = ""  # why the test did not run at all (rejected, missing function, ...)
    elapsed: float = 0.0  # seconds its cases took, in the sandbox and in the comparison

    @property
    def n_passed(self) -> int:
        return sum(c.passed for c in self.cases)

    @property
    def score(self) -> float:
        return self.test.points * self.n_passed / len(self.cases) if self.cases else 0.0

    @property
    def status(self) -> str:
        if self.note or not self.cases:
            return "not_run"
        if self.n_passed == len(self.cases):
            return "passed"
        if all(c.kind == "not_implemented" for c in self.cases):
            return "not_implemented"
        return "partial" if self.n_passed else "failed"

    @property
    def first_failure(self) -> CaseResult | None:
        return next((c for c in self.cases if not c.passed), None)


@dataclass
class Result:
    """The outcome of grading one submission."""

    assignment: Assignment
    submission: Path
    tests: list[TestResult]
    hidden_run: bool
    problems: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    output: str = ""
    elapsed: float = 0.0
    isolation: str = ""
    #: why the submission could not be graded, the machine's fault or the grader's (the
    #: sandbox could not start, a worker was lost, a bug of ours): then it has no score, and
    #: every view says "not graded" instead of a number
    not_graded: str = ""

    @property
    def score(self) -> float:
        return sum(t.score for t in self.tests)

    @property
    def max_score(self) -> float:
        """The points of all but the bonus tests."""
        return sum(t.test.points for t in self.tests if not t.test.bonus)

    @property
    def bonus_score(self) -> float:
        return sum(t.score for t in self.tests if t.test.bonus)
