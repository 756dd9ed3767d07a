"""A graded submission as plain data: what the batch keeps of it, what a cluster task carries
and what a worker sends back, so that the local pool, the cluster and ``--resume`` share one
form (and :mod:`autograder.grading` and :mod:`autograder.cluster` need not import each other).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .gradescope.feedback import results_json
from .report import csv_header, csv_row
from .results import Result, TestResult
from .runner import prepare
from .spec import Assignment
from .summary import facts


@dataclass(frozen=True)
class Job:
    """A submission as a cluster task carries it: its name, the path its report shows
    (``label``), its files' bytes by name (``file`` first, then the template beside a
    notebook, which it may import) and their digest with the grading's context."""

    name: str
    label: str
    file: str
    files: dict[str, bytes]
    digest: str


def record(name: str, result: Result, digest: str = "") -> dict[str, Any]:
    """What the batch keeps of a graded submission, as plain data (a cluster's worker sends
    it back): its ``results.json``, its row and header of ``grades.csv``, the facts the
    class summary needs, and the digest of what was graded ("" for nothing to resume)."""
    return {"results": results_json(result, f"Graded {result.submission.name}."),
            "row": csv_row(name, result),
            "header": csv_header(result), "facts": facts(name, result), "digest": digest}


def grader_failed(assignment: Assignment, path: Path, seed: str | None, level: str,
                  exc: BaseException) -> Result:
    """The result of a submission the grader itself failed on."""
    return not_run(assignment, path, seed, level,
                   f"the grader failed ({type(exc).__name__}: {exc}); please report this",
                   "not run: the grader failed on this submission")


def not_run(assignment: Assignment, path: Path, seed: str | None, level: str, problem: str,
            note: str) -> Result:
    """A result scoring 0: every test ``note``d as not run, for ``problem``."""
    tests = [TestResult(p.test, assignment.function(p.test.function), note=note)
             for p in prepare(assignment, seed)]
    return Result(assignment, path, tests, seed is not None, isolation=level,
                  problems=[problem])
