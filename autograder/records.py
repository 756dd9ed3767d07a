"""A submission as plain data: as it was found, as a cluster task carries it, and the result
of one that was not run, so that the local pool, the cluster, Gradescope's runner and the LMS
exports share one form (and :mod:`autograder.grading` and :mod:`autograder.cluster` need not
import each other). What the batch keeps of a graded one is :func:`autograder.batch.record`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from .judging import prepare
from .results import Result, TestResult
from .spec import Assignment


@dataclass(frozen=True)
class Submission:
    """A submission: its name (its folder in the output), its file, and why it cannot be
    graded if that was found while collecting (several candidate files, a search cut
    short); then ``path`` is the student's folder. ``folder``: the student's folder it was
    found in, if any (:mod:`autograder.lms` reads the platform's metadata there)."""

    name: str
    path: Path
    refused: str = ""
    folder: Path | None = None


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


def grader_failed(assignment: Assignment, path: Path, seed: str | None, level: str,
                  exc: BaseException) -> Result:
    """The result of a submission the grader itself failed on: not graded."""
    return not_graded(assignment, path, seed, level,
                      f"the grader failed ({type(exc).__name__}: {exc}); please report this")


def not_graded(assignment: Assignment, path: Path, seed: str | None, level: str,
               why: str) -> Result:
    """A result with no score: the machine or the grader, not the submission, failed
    (``why``). It is graded again by ``grade --resume``."""
    result = not_run(assignment, path, seed, level, "", "not run: the submission could not be "
                     "graded (see above)")
    result.problems, result.not_graded = [], why
    return result


def not_run(assignment: Assignment, path: Path, seed: str | None, level: str, problem: str,
            note: str) -> Result:
    """A result scoring 0: every test ``note``d as not run, for ``problem``."""
    tests = [TestResult(p.test, assignment.function(p.test.function), note=note)
             for p in prepare(assignment, seed)]
    return Result(assignment, path, tests, seed is not None, isolation=level,
                  problems=[problem])
