"""Grade one submission: static check, then each test's cases called in a sandbox and
judged by the judging core's loop (:func:`autograder.judging.run_test`: validation,
comparison, diagnosis), the sandbox its executor.

Everything that decides a score happens in the grading process, on plain arrays the
sandbox sent back; the submission only ever sees its inputs.
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

from .judging import Prepared, error_text, prepare, run_test
from .limits import DEFAULT_LIMITS, Limits
from .records import not_graded
from .results import Result, TestResult
from .sandbox import Sandbox, Unavailable, level_for
from .spec import Assignment
from .submission import Source, SubmissionError, import_problems, read_regular, read_source

ASSIGNMENTS_DIR = Path(__file__).resolve().parents[1] / "assignments"


def default_submission(assignment: Assignment) -> Path:
    """The template file in the current directory if there is one, else in ``assignments/``."""
    here = Path.cwd() / assignment.template
    return here if here.exists() else ASSIGNMENTS_DIR / assignment.template


MACHINE_ATTEMPTS = 3  # gradings of one submission that the machine may fail before "not graded"
MACHINE_PAUSE = 1.0  # seconds before the second attempt, twice that before the third


def run(assignment: Assignment, submission: Path, seed: str | None = None,
        limits: Limits = DEFAULT_LIMITS, level: str | None = None) -> Result:
    """Grade ``submission`` (a ``.py`` or ``.ipynb``) against ``assignment``, in a sandbox
    of isolation ``level`` (default: the strongest here; see :mod:`autograder.sandbox`).

    A grading the machine fails (the sandbox could not start or be prepared:
    :class:`~autograder.sandbox.Unavailable`) is done again from the start, with a fresh
    sandbox and budget, :data:`MACHINE_ATTEMPTS` times in all; if it never succeeds the
    result is *not graded* (:attr:`Result.not_graded` says why) and has no score."""
    start = time.monotonic()
    for attempt in range(MACHINE_ATTEMPTS):
        if attempt:
            time.sleep(MACHINE_PAUSE * attempt)
        try:
            result = _graded(assignment, submission, seed or None, limits, level)
            break
        except Unavailable as exc:
            why = str(exc)
    else:
        result = not_graded(assignment, submission, seed or None, level_for(level),
                            f"{why} on each of {MACHINE_ATTEMPTS} attempts")
    result.elapsed = time.monotonic() - start
    return result


def _graded(assignment: Assignment, submission: Path, seed: str | None, limits: Limits,
            level: str | None) -> Result:
    prepared = prepare(assignment, seed)
    tests = [TestResult(p.test, assignment.function(p.test.function)) for p in prepared]
    result = Result(assignment, submission, tests, hidden_run=seed is not None,
                    isolation=level_for(level))
    names = frozenset(f.name for f in assignment.functions)
    try:
        source = read_source(submission, assignment.allowed_imports, assignment.template, names)
        result.notes = list(source.notes)
        result.problems = import_problems(source, assignment.allowed_imports, submission.name)
    except SubmissionError as exc:
        result.problems = [str(exc)]
    if result.problems:
        _skip_all(result, "not run: the submission was refused (see above)")
    else:
        _run_tests(assignment, source, prepared, result, limits)
    return result


def _skip_all(result: Result, note: str) -> None:
    for t in result.tests:
        t.note = note


def _run_tests(assignment: Assignment, source: Source, prepared: tuple[Prepared, ...],
               result: Result, limits: Limits) -> None:
    """Every test's cases called in one sandbox, each test judged by the judging core's own
    loop (:func:`autograder.judging.run_test`: the sandbox is its executor)."""
    names = [f.name for f in assignment.functions]
    total = sum(len(p.cases) * (p.test.rollout.steps if p.test.rollout else 1)
                for p in prepared)
    with Sandbox(source.text, names, limits, assignment.allowed_imports, total,
                 level=result.isolation) as sandbox:
        started = sandbox.start()
        if started.status != "ok":
            why = (error_text(started.error, source.locate) if started.status == "error"
                   else started.message)
            result.problems = [f"your file could not be loaded: {why}"]
            _skip_all(result, "not run: the file could not be loaded (see above)")
            return
        for p, tr in zip(prepared, result.tests, strict=True):
            run_test(assignment, p, tr, sandbox, source.locate)
        result.output = sandbox.output()


def seed_from_env(seed: str | None) -> str | None:
    """``seed`` if given, else ``$AUTOGRADER_SEED`` (empty counts as none)."""
    return seed or os.environ.get("AUTOGRADER_SEED") or None


MAX_SEED = 4096  # bytes of a seed file


def read_seed(path: str) -> str:
    """The secret seed from the first line of the file ``path`` (``-``: standard input),
    which, unlike a command line, no other process of the machine can read. ValueError
    names what is wrong."""
    if path == "-":
        text = sys.stdin.read(MAX_SEED + 1)
        if len(text) > MAX_SEED:
            raise ValueError(f"--seed-file -: more than {MAX_SEED} characters on standard "
                             "input")
    else:
        try:
            text = read_regular(Path(path), limit=MAX_SEED)
        except SubmissionError as exc:
            raise ValueError(f"--seed-file: {exc}") from None
    lines = text.strip().splitlines()
    if not lines or not lines[0].strip().isprintable():
        raise ValueError(f"--seed-file {path}: its first line must be the seed (printable "
                         "text)")
    return lines[0].strip()
