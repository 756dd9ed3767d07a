"""The judging core: a call's outcome validated, compared with the reference's answer and
explained by the catalogue of known mistakes.

The grader judges what its sandbox sent back (:mod:`autograder.runner`); the notebooks'
self-checks (:mod:`course.exercises`) judge calls made in the student's own kernel. Both use
this module, which, like everything it imports (:mod:`autograder.spec`,
:mod:`autograder.checks`, :mod:`autograder.catalogue`, :mod:`autograder.results`,
:mod:`autograder.protocol`), starts no process and loads no sandbox.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np

from .protocol import Value
from .results import CaseResult
from .spec import Assignment, Case, Function, Misconception, Test, case_rng


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


def judge(fn: Function, case: Case, expected: Any, out: Outcome, memory_mb: int | None,
          locate: Callable[[int], str], catalogue: tuple[Misconception, ...]) -> CaseResult:
    """One case's verdict from what the call gave (``out``): validated, compared, an error
    explained by the ``catalogue`` if it can be (public: the notebooks' self-checks,
    :mod:`course.exercises`, judge their calls with it too)."""
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
