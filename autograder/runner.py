"""Grade one submission: static check, sandboxed calls, then each call judged
(:mod:`autograder.judging`: validation, comparison, diagnosis).

Everything that decides a score happens in the grading process, on plain arrays the
sandbox sent back; the submission only ever sees its inputs.
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .judging import Prepared, diagnose, error_text, judge, prepare
from .limits import DEFAULT_LIMITS, Limits
from .records import not_graded
from .results import CaseResult, Result, TestResult
from .sandbox import Sandbox, Unavailable, level_for
from .spec import Assignment, Case, Function, Misconception, Rollout, Run
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
            started_at = time.monotonic()
            fn = tr.function
            if fn.name in sandbox.missing:
                tr.note = f"{assignment.template} has no function {fn.name}()"
                continue
            catalogue = assignment.misconceptions_of(fn.name)
            if p.test.rollout is not None:
                tr.cases, wrong = roll_test(fn, p, sandbox, source.locate, catalogue)
                # the diagnosis reads, in each failing run, the first step unlike the reference's
                tr.misconception = diagnose(assignment, fn, wrong)
                tr.elapsed = time.monotonic() - started_at
                continue
            outcomes = sandbox.call(fn.name, [c.args for c in p.cases],
                                    [4 * _numbers(e) + 64 for e in p.expected])
            if any(o.status == "garbage" for o in outcomes):
                # Frames that are not the child's own void the test: none of it can be trusted.
                forged = next(o for o in outcomes if o.status == "garbage")
                outcomes = [forged] * len(outcomes)
            tr.cases = [judge(fn, c, e, o, sandbox.memory_mb, source.locate, catalogue)
                        for c, e, o in zip(p.cases, p.expected, outcomes, strict=True)]
            tr.misconception = (_callee_mistake(assignment, fn, tr.cases, sandbox)
                                or diagnose(assignment, fn, tr.cases))
            tr.elapsed = time.monotonic() - started_at
        result.output = sandbox.output()


def _numbers(x: Any) -> int:
    """How many numbers an expected answer holds (an answer may hold a few times more)."""
    if isinstance(x, (tuple, list)):
        return sum(_numbers(i) for i in x)
    return int(np.size(x)) if isinstance(x, (np.ndarray, np.generic, int, float)) else 1


def roll_test(fn: Function, prepared: Prepared, sandbox: Sandbox, locate: Callable[[int], str],
              catalogue: tuple[Misconception, ...]) -> tuple[list[CaseResult], list[CaseResult]]:
    """Every run of a rollout test (:func:`roll`), with the steps to diagnose from. As in a
    test of single calls, a frame that is not the child's own voids the whole test.

    The runs together get ``rollout.seconds`` of their own, and those still running when
    they are spent end there (the report names the test and says why: :class:`Pace`).
    Those seconds are outside the submission's budget (``Limits.budget``): while the test
    runs the sandbox's deadline is the test's own end, whatever the tests before it left,
    and the submission then has what it had left when the test began. No test can spend a
    rollout test's time, nor a rollout test the others': a submission's wall time is bounded
    by ``Limits.budget`` plus its rollout tests' ``seconds``."""
    rollout = prepared.test.rollout
    assert rollout is not None
    pace = Pace(prepared.test.name, time.monotonic(), rollout.seconds, rollout.hint)
    left = sandbox.deadline - pace.started  # the submission's budget, kept for after
    sandbox.deadline = pace.started + rollout.seconds  # a call in flight then is cut short
    try:
        results: list[CaseResult] = []
        wrong: list[CaseResult] = []
        for case, expected in zip(prepared.cases, prepared.expected, strict=True):
            result, first_wrong = roll(fn, rollout, case, expected, sandbox, locate, catalogue,
                                       pace, len(prepared.cases))
            if result.kind == "garbage":  # none of the test can be trusted
                return [CaseResult(c, "garbage", result.reason, None, e.answers[-1])
                        for c, e in zip(prepared.cases, prepared.expected, strict=True)], []
            results.append(result)
            wrong += [first_wrong] if first_wrong else []
        return results, wrong
    finally:
        sandbox.deadline = time.monotonic() + max(left, 0.0)


PACE_HINT = ("look for work your function repeats needlessly in every call (a print, a sleep, "
             "a loop far longer than its arrays)")


@dataclass
class Pace:
    """The wall-clock time of one rollout test (named ``test``): when its runs started, the
    ``seconds`` they have, the calls they made, and ``hint``, what its report adds when the
    time is spent (:data:`PACE_HINT` if empty)."""

    test: str
    started: float
    seconds: float
    hint: str = ""
    calls: int = 0

    def spent(self, rollout: Rollout, runs: int) -> str | None:
        """Why no further step may run (the test's time is spent), or None: the test, its
        calls so far, the time a step took and the time that would have run them all."""
        used = time.monotonic() - self.started
        if used < self.seconds:
            return None
        each = 1e3 * used / max(self.calls, 1)
        total = rollout.steps * runs
        fits = 1e3 * self.seconds / total
        return (f"not run: the test \"{self.test}\" ran out of its own {self.seconds:g} s "
                f"after {self.calls} of its {total} calls: a step took {each:.1f} ms here "
                f"(your function and the grader's round trip), and {fits:.1f} ms would run them"
                f" all; {self.hint or PACE_HINT}")


def roll(fn: Function, rollout: Rollout, case: Case, expected: Run, sandbox: Sandbox,
         locate: Callable[[int], str], catalogue: tuple[Misconception, ...],
         pace: Pace, runs: int) -> tuple[CaseResult, CaseResult | None]:
    """One rollout case: the student's function called ``rollout.steps`` times in the
    sandbox, the state carried between calls here, and the run judged by
    ``rollout.verdict`` against the reference's (``expected``). Also returns, if the run
    fails, its first step whose answer is unlike the reference's on the same arguments (as
    a case of its own, for the diagnosis). A call that raises, stops or answers in the wrong
    shape ends the run there (a raised error is then the step the diagnosis reads), and so
    does the end of the test's time (``pace``, shared by its ``runs`` runs), before a step
    or during one (the sandbox's deadline is then the test's: :func:`roll_test`)."""
    steps: list[Case] = []
    run = Run([], [rollout.start(case.args)])
    size = 4 * _numbers(expected.answers[0]) + 64
    last = expected.answers[-1]
    for k, want in enumerate(expected.answers):
        late = pace.spent(rollout, runs)
        if late is not None:
            return CaseResult(case, "skipped", f"step {k + 1} of {rollout.steps}: {late}",
                              None, last), None
        pace.calls += 1
        steps.append(Case(f"{case.label}, step {k + 1} of {rollout.steps}",
                          rollout.call(run.states[-1])))
        [out] = sandbox.call(fn.name, [steps[-1].args], [size])
        late = pace.spent(rollout, runs) if out.status in ("timeout", "skipped") else None
        if late is not None:  # cut short by the end of the test's time (the sandbox's deadline)
            return CaseResult(case, "skipped", f"step {k + 1} of {rollout.steps}: {late}",
                              None, last), None
        if out.status == "ok":
            assert out.value is not None
            valid = fn.check.validate(fn.name, out.value, want)
            if valid.error is None:
                run.answers.append(valid.array)
                run.states.append(rollout.advance(run.states[-1], valid.array))
                continue
        ended = judge(fn, steps[-1], want, out, sandbox.memory_mb, locate, catalogue)
        reason = ended.reason if ended.kind == "not_implemented" else (
            f"step {k + 1} of {rollout.steps}: {ended.reason}")
        # an error the catalogue explains diagnoses the run
        return (CaseResult(case, ended.kind, reason, None, last, ended.error),
                ended if ended.kind == "error" else None)
    why = rollout.verdict(run, expected, case.args)
    if why is None:
        return CaseResult(case, "pass", got=run.answers[-1], expected=last), None
    first_wrong = None
    for step, got in zip(steps, run.answers, strict=True):
        reference = fn.reference(*step.args)
        if fn.check.judge(got, reference, step.args) is not None:
            first_wrong = CaseResult(step, "wrong", got=got, expected=reference)
            break
    return CaseResult(case, "wrong", why, run.answers[-1], last), first_wrong


def _callee_mistake(assignment: Assignment, fn: Function, cases: list[CaseResult],
                    sandbox: Sandbox) -> Misconception | None:
    """The catalogued mistake ``caused_by`` a function ``fn`` uses, if the student's own
    callee, called with the arguments ``fn`` would give it on the failing cases, is wrong on
    one of them (raises, or differs from its reference)."""
    failing = [c for c in cases if not c.passed and c.kind != "not_implemented"]
    if not failing:
        return None
    for use in fn.uses:
        mistake = next((m for m in assignment.misconceptions_of(fn.name)
                        if m.caused_by == use.name), None)
        if mistake is None or use.name in sandbox.missing:
            continue
        callee = assignment.function(use.name)
        args = [use.args(*c.case.args) for c in failing]
        for a, out in zip(args, sandbox.call(use.name, args), strict=True):
            if out.status == "error":
                return mistake
            if out.status != "ok" or out.value is None:
                continue
            expected = callee.reference(*a)
            v = callee.check.validate(callee.name, out.value, expected)
            if v.error or callee.check.judge(v.array, expected, a) is not None:
                return mistake
    return None


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
