"""The judging core: a test's cases called on an executor, each call's outcome validated,
compared with the reference's answer and explained by the catalogue of known mistakes.

One loop over a test's cases (:func:`run_test`) serves both graders: the autograder's, whose
executor is its sandbox (:mod:`autograder.runner`), and the notebooks' self-checks
(:mod:`course.exercises`), whose executor calls the student's function in their own kernel.
So a notebook's check judges and diagnoses exactly as the grader does. This module, like
everything it imports (:mod:`autograder.spec`, :mod:`autograder.checks`,
:mod:`autograder.catalogue`, :mod:`autograder.results`, :mod:`autograder.protocol`), starts
no process and loads no sandbox.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Collection
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any, Protocol

import numpy as np

from .protocol import Value
from .results import CaseResult, TestResult
from .spec import Assignment, Case, Function, Misconception, Rollout, Run, Test, case_rng


@dataclass
class Outcome:
    """What became of one case: ``status`` is ``ok`` (``value`` holds the return value),
    ``error`` (the function raised; ``error`` has type, message, line), or a fatal
    ``timeout``, ``crash`` or ``garbage`` (``message`` says what happened), or ``skipped``."""

    status: str
    value: Value | None = None
    error: dict[str, Any] = field(default_factory=dict)
    message: str = ""


@dataclass(frozen=True)
class Prepared:
    """A test with its cases and the reference's answers (a rollout's: its :class:`Run`),
    computed once per seed."""

    test: Test
    cases: tuple[Case, ...]
    expected: tuple[Any, ...]


@lru_cache(maxsize=16)
def prepare(assignment: Assignment, seed: str | None) -> tuple[Prepared, ...]:
    """The tests to run: all visible ones, and the hidden ones when there is a seed (a test
    without cases here, such as one on data this machine lacks, is left out)."""
    out = []
    for test in assignment.tests:
        if test.hidden and not seed:
            continue
        fn = assignment.function(test.function)
        cases = tuple(test.cases(case_rng(test, seed)))
        if cases:
            expected = (fn.reference(*c.args) if test.rollout is None
                        else test.rollout.run(fn.reference, c.args) for c in cases)
            out.append(Prepared(test, cases, tuple(expected)))
    return tuple(out)


class Executor(Protocol):
    """Where a submission's functions are called: the grader's sandbox
    (:class:`autograder.sandbox.Sandbox`) or, for a notebook's check, the student's own
    kernel. ``call`` gives one :class:`Outcome` per argument tuple (``sizes[i]``: the most
    numbers case ``i`` may return); ``missing`` names the functions the submission lacks,
    ``memory_mb`` its memory limit (None: none), and ``deadline`` (monotonic seconds) is when
    its time ends, which a rollout test moves to its own end while it runs."""

    deadline: float

    @property
    def missing(self) -> Collection[str]: ...

    @property
    def memory_mb(self) -> int | None: ...

    def call(self, fn: str, cases: list[tuple[Any, ...]],
             sizes: list[int] | None = None) -> list[Outcome]: ...


def run_test(assignment: Assignment, prepared: Prepared, tr: TestResult, executor: Executor,
             locate: Callable[[int], str]) -> None:
    """Fill ``tr`` in: the test's cases called on ``executor``, each judged (:func:`judge`),
    and the mistake they show diagnosed (:func:`diagnose`, or a callee's: a function the
    submission was to call). ``tr.function`` is the function as the submission names it
    (the messages say that name); ``locate`` says where a line of the submission is."""
    started_at = time.monotonic()
    fn = assignment.function(prepared.test.function)
    if fn.name in executor.missing:
        tr.note = f"{assignment.template} has no function {fn.name}()"
        return
    catalogue = assignment.misconceptions_of(fn.name)
    if prepared.test.rollout is not None:
        tr.cases, wrong = roll_test(tr.function, prepared, executor, locate, catalogue)
        # the diagnosis reads, in each failing run, the first step unlike the reference's
        tr.misconception = diagnose(assignment, fn, wrong)
        tr.elapsed = time.monotonic() - started_at
        return
    outcomes = executor.call(fn.name, [c.args for c in prepared.cases],
                             [4 * _numbers(e) + 64 for e in prepared.expected])
    if any(o.status == "garbage" for o in outcomes):
        # Frames that are not the child's own void the test: none of it can be trusted.
        forged = next(o for o in outcomes if o.status == "garbage")
        outcomes = [forged] * len(outcomes)
    tr.cases = [judge(tr.function, c, e, o, executor.memory_mb, locate, catalogue)
                for c, e, o in zip(prepared.cases, prepared.expected, outcomes, strict=True)]
    tr.misconception = (_callee_mistake(assignment, fn, tr.cases, executor)
                        or diagnose(assignment, fn, tr.cases))
    tr.elapsed = time.monotonic() - started_at


def _numbers(x: Any) -> int:
    """How many numbers an expected answer holds (an answer may hold a few times more)."""
    if isinstance(x, (tuple, list)):
        return sum(_numbers(i) for i in x)
    return int(np.size(x)) if isinstance(x, (np.ndarray, np.generic, int, float)) else 1


def roll_test(fn: Function, prepared: Prepared, executor: Executor,
              locate: Callable[[int], str], catalogue: tuple[Misconception, ...]
              ) -> tuple[list[CaseResult], list[CaseResult]]:
    """Every run of a rollout test (:func:`roll`), with the steps to diagnose from. As in a
    test of single calls, a frame that is not the child's own voids the whole test.

    The runs together get ``rollout.seconds`` of their own, and those still running when
    they are spent end there (the report names the test and says why: :class:`Pace`).
    Those seconds are outside the submission's budget (``Limits.budget``): while the test
    runs the executor's deadline is the test's own end, whatever the tests before it left,
    and the submission then has what it had left when the test began. No test can spend a
    rollout test's time, nor a rollout test the others': a submission's wall time is bounded
    by ``Limits.budget`` plus its rollout tests' ``seconds``."""
    rollout = prepared.test.rollout
    assert rollout is not None
    pace = Pace(prepared.test.name, time.monotonic(), rollout.seconds, rollout.hint)
    left = executor.deadline - pace.started  # the submission's budget, kept for after
    executor.deadline = pace.started + rollout.seconds  # a call in flight then is cut short
    try:
        results: list[CaseResult] = []
        wrong: list[CaseResult] = []
        for case, expected in zip(prepared.cases, prepared.expected, strict=True):
            result, first_wrong = roll(fn, prepared.test.function, rollout, case, expected,
                                       executor, locate, catalogue, pace, len(prepared.cases))
            if result.kind == "garbage":  # none of the test can be trusted
                return [CaseResult(c, "garbage", result.reason, None, e.answers[-1])
                        for c, e in zip(prepared.cases, prepared.expected, strict=True)], []
            results.append(result)
            wrong += [first_wrong] if first_wrong else []
        return results, wrong
    finally:
        executor.deadline = time.monotonic() + max(left, 0.0)


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


def roll(fn: Function, name: str, rollout: Rollout, case: Case, expected: Run,
         executor: Executor, locate: Callable[[int], str],
         catalogue: tuple[Misconception, ...], pace: Pace,
         runs: int) -> tuple[CaseResult, CaseResult | None]:
    """One rollout case: the submission's function ``name`` called ``rollout.steps`` times
    on the executor, the state carried between calls here, and the run judged by
    ``rollout.verdict`` against the reference's (``expected``); ``fn`` is the function as
    the submission names it. Also returns, if the run fails, its first step whose answer is
    unlike the reference's on the same arguments (as a case of its own, for the diagnosis).
    A call that raises, stops or answers in the wrong shape ends the run there (a raised
    error is then the step the diagnosis reads), and so does the end of the test's time
    (``pace``, shared by its ``runs`` runs), before a step or during one (the executor's
    deadline is then the test's: :func:`roll_test`)."""
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
        [out] = executor.call(name, [steps[-1].args], [size])
        late = pace.spent(rollout, runs) if out.status in ("timeout", "skipped") else None
        if late is not None:  # cut short by the end of the test's time (the executor's deadline)
            return CaseResult(case, "skipped", f"step {k + 1} of {rollout.steps}: {late}",
                              None, last), None
        if out.status == "ok":
            assert out.value is not None
            valid = fn.check.validate(fn.name, out.value, want)
            if valid.error is None:
                run.answers.append(valid.array)
                run.states.append(rollout.advance(run.states[-1], valid.array))
                continue
        ended = judge(fn, steps[-1], want, out, executor.memory_mb, locate, catalogue)
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
                    executor: Executor) -> Misconception | None:
    """The catalogued mistake ``caused_by`` a function ``fn`` uses, if the submission's own
    callee, called with the arguments ``fn`` would give it on the failing cases, is wrong on
    one of them (raises, or differs from its reference)."""
    failing = [c for c in cases if not c.passed and c.kind != "not_implemented"]
    if not failing:
        return None
    for use in fn.uses:
        mistake = next((m for m in assignment.misconceptions_of(fn.name)
                        if m.caused_by == use.name), None)
        if mistake is None or use.name in executor.missing:
            continue
        callee = assignment.function(use.name)
        args = [use.args(*c.case.args) for c in failing]
        for a, out in zip(args, executor.call(use.name, args), strict=True):
            if out.status == "error":
                return mistake
            if out.status != "ok" or out.value is None:
                continue
            expected = callee.reference(*a)
            v = callee.check.validate(callee.name, out.value, expected)
            if v.error or callee.check.judge(v.array, expected, a) is not None:
                return mistake
    return None


def judge(fn: Function, case: Case, expected: Any, out: Outcome, memory_mb: int | None,
          locate: Callable[[int], str], catalogue: tuple[Misconception, ...]) -> CaseResult:
    """One case's verdict from what the call gave (``out``): validated, compared, an error
    explained by the ``catalogue`` if it can be (what :func:`run_test` does with each
    call, in the sandbox or in a notebook's kernel alike)."""
    if out.status == "ok":
        assert out.value is not None
        v = fn.check.validate(fn.name, out.value, expected)
        if v.error:
            return CaseResult(case, "invalid", v.error, v.array, expected)
        why = fn.check.judge(v.array, expected, case.args)
        if why is None:
            return CaseResult(case, "pass", got=v.array, expected=expected)
        digits = fn.check.decimals(v.array, expected)
        return CaseResult(case, "wrong", f"{fn.name} returned "
                          f"{fn.check.show_value(v.array, digits)}, expected "
                          f"{fn.check.show_expected(expected, digits)}: {why}", v.array, expected)
    if out.status == "error":
        if out.error.get("type") == "NotImplementedError":
            return CaseResult(case, "not_implemented", "not implemented yet", None, expected)
        text = error_text(out.error, locate)
        if out.error.get("type") == "MemoryError" and memory_mb is not None:
            text += f" (the memory limit is {memory_mb} MB)"
        for m in catalogue:
            hint = _explained(m, out.error, case)
            if hint:
                text += f": {hint}"
                break
        return CaseResult(case, "error", f"{fn.name} raised {text}", None, expected,
                          error=out.error)
    message = out.message
    if out.status == "timeout" and fn.timeout_hint:
        message = f"{message}: {fn.timeout_hint}"
    return CaseResult(case, out.status, message, None, expected)


def diagnose(assignment: Assignment, fn: Function,
             cases: list[CaseResult]) -> Misconception | None:
    """The first catalogued mistake that reproduces (or shows the symptom of) every failing
    case of a test, if any; the cases where it has no definite answer
    (:attr:`Misconception.undefined`) aside, as long as one is left.

    Only outputs of the right shape can be compared, and errors only by a mistake that
    explains them; a test with a timeout or a wrong shape among its failures gets no
    diagnosis.
    """
    failing = [c for c in cases if not c.passed]
    if not failing or any(c.got is None and c.error is None for c in failing):
        return None
    for m in assignment.misconceptions_of(fn.name):
        evidence = [c for c in failing if not _undefined(m, c.case)]
        if evidence and all(_reproduces(m, fn, c) for c in evidence):
            return m
    return None


def _undefined(m: Misconception, case: Case) -> bool:
    """Whether ``m`` has no definite answer on ``case`` (:attr:`Misconception.undefined`)."""
    if m.undefined is None:
        return False
    try:
        with np.errstate(all="ignore"):
            return bool(m.undefined(*case.args))
    except Exception:  # a test undefined on this input leaves the case as evidence
        return False


def _reproduces(m: Misconception, fn: Function, c: CaseResult) -> bool:
    if m.caused_by is not None:  # found by calling the callee (_callee_mistake), not here
        return False
    if c.got is None:
        return c.error is not None and _explained(m, c.error, c.case) is not None
    try:
        with np.errstate(all="ignore"):
            if m.symptom is not None:
                return bool(m.symptom(c.got, *c.case.args))
            assert m.wrong is not None  # Misconception holds one of wrong, symptom, caused_by
            wrong = m.wrong(*c.case.args)
    except Exception:  # a variant undefined on this input reproduces nothing
        return False
    return fn.check.close(c.got, wrong)


def _explained(m: Misconception, error: dict[str, Any], case: Case) -> str | None:
    """What ``m`` says about the error a case raised, if it explains it."""
    if m.explains is None:
        return None
    try:
        return m.explains(error, *case.args)
    except Exception:  # an explanation undefined on this input explains nothing
        return None


def error_text(error: dict[str, Any], locate: Callable[[int], str]) -> str:
    text: str = error.get("type", "Exception")
    if error.get("message"):
        text += f": {error['message']}"
    where = error.get("where")
    if where:
        text += f" ({locate(where['line'])}: {where['code'].strip()})"
    return text
