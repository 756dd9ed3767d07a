"""What an assignment is, as data: functions, tests with case generators, known mistakes.

An assignment module (``autograder/assignments/a1.py``) builds one :class:`Assignment`:

* a :class:`Function` per function the student writes, with its reference implementation
  and a :class:`~autograder.checks.Check` that validates and compares its output;
* :class:`Test` s, each a named group of cases worth some points (partial credit is the
  fraction of cases passed); a test's ``cases(rng)`` builds its inputs, from a fixed seed
  for visible tests and from the instructor's secret seed for hidden ones;
* a catalogue of :class:`Misconception` s: each a known-wrong variant of one function,
  written as a function of the reference, which the diagnosis compares failing outputs to,
  or, where a mistake has no single wrong output (an iterative solver), a *symptom*: a
  predicate on the failing output and the call's arguments; a mistake that makes some
  inputs raise (an inverse of a singular matrix) may also *explain* those errors; a
  mistake *caused by* another function the template asks this one to call (:class:`Uses`)
  is found by calling the student's own callee on the failing cases' arguments;
* optionally, per function, a :class:`Picture` of a failing case (skeletons, chains);
* for a function that steps a simulation, tests whose cases are whole runs
  (:class:`Rollout`), judged by what the run achieves rather than call by call.

Nothing here runs student code; the runner does, in a sandbox.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .checks import Check


@dataclass(frozen=True)
class Case:
    """One call: positional ``args`` (arrays, floats, strings) and a short human ``label``."""

    label: str
    args: tuple[Any, ...]


@dataclass(frozen=True)
class Picture:
    """A failing case drawn as joint trees (the HTML report's figure): ``yours`` and
    ``expected`` are joint positions ``(J, 3)`` with their ``parents`` (``expected_parents``
    if they differ), ``start`` the pose the call started from (drawn faint), ``points``
    labelled markers such as ``("target", (k, 3))``, and ``what`` names the picture."""

    what: str
    parents: np.ndarray
    yours: np.ndarray
    expected: np.ndarray
    expected_parents: np.ndarray | None = None
    start: np.ndarray | None = None
    points: tuple[tuple[str, np.ndarray], ...] = ()


@dataclass(frozen=True)
class Uses:
    """The template asks a function to call the student's ``name``, with the arguments
    ``args(*case_args)`` built from its own (``ik_local`` walks ``path_to(parents, fixed,
    effector)``): a wrong callee explains the caller's failures."""

    name: str
    args: Callable[..., tuple[Any, ...]]


@dataclass(frozen=True)
class Function:
    """A function the student implements.

    ``params`` are the argument names, in order (for messages); ``reference`` computes the
    expected output from the same arguments; ``check`` validates and compares outputs;
    ``picture(got, expected, args)`` draws a failing case, or returns None; ``timeout_hint``
    is added to the message of a case that ran out of time (the likely cause, and the fix);
    ``uses`` names the student's functions it is meant to call.
    """

    name: str
    params: tuple[str, ...]
    reference: Callable[..., Any]
    check: Check
    picture: Callable[..., Picture | None] | None = None
    timeout_hint: str | None = None
    uses: tuple[Uses, ...] = ()


def _same(x: Any) -> Any:
    return x


@dataclass(frozen=True)
class Run:
    """A rollout's ``answers``, call by call, and the ``states`` it went through (one more
    than the answers: the first comes from the case's arguments)."""

    answers: list[Any]
    states: list[Any]


@dataclass(frozen=True)
class Rollout:
    """Cases judged by what many calls in a row achieve: a simulation the student's function
    steps. Each case's arguments start it (``start(args)``: the simulation's state, by
    default the arguments themselves); the grader, never the submission, carries the state
    from one call to the next: a call gets ``call(state)`` and ``advance(state, answer)``
    is the next state. After ``steps`` calls ``verdict(yours, reference, args)`` compares
    the :class:`Run` with the reference function's by what they do (a rotation stays a
    rotation, a joint settles, a pushed body stands): None if it achieves what it should,
    else one sentence on what it did.

    All runs of one test together have ``seconds`` of wall-clock time of their own
    (thousands of calls), outside the submission's ``Limits.budget``: no other test can
    spend them, and they spend nothing of the others' (a submission's wall time is at most
    its budget plus its rollout tests' seconds). The runs still going when they are spent
    end there, and the report names the test, the time a step took and the time that would
    have run them all, then ``hint``: what a step fast enough is, and what to look for."""

    steps: int
    advance: Callable[[Any, Any], Any]
    verdict: Callable[[Run, Run, tuple[Any, ...]], str | None]
    start: Callable[[tuple[Any, ...]], Any] = _same
    call: Callable[[Any], tuple[Any, ...]] = _same
    seconds: float = 20.0
    hint: str = ""

    def run(self, step: Callable[..., Any], args: tuple[Any, ...]) -> Run:
        """The whole rollout from ``args`` with ``step`` (the reference) answering."""
        run = Run([], [self.start(args)])
        for _ in range(self.steps):
            run.answers.append(step(*self.call(run.states[-1])))
            run.states.append(self.advance(run.states[-1], run.answers[-1]))
        return run


@dataclass(frozen=True)
class Test:
    """A named group of cases of one function, worth ``points``.

    ``hidden`` tests draw their cases from the secret seed and are shown to students only
    after grades are published. ``bonus`` points add to the score but not to the maximum.
    A test with a ``rollout`` runs each case as a simulation (:class:`Rollout`).
    """

    name: str
    function: str
    points: float
    cases: Callable[[np.random.Generator], Sequence[Case]]
    hidden: bool = False
    bonus: bool = False
    rollout: Rollout | None = None


#: a test's case generator: the cases drawn from a seeded generator
Cases = Callable[[np.random.Generator], Sequence[Case]]


def random_edge_hidden(fn: str, random: Cases, edges: Cases, hidden: Cases,
                       points: tuple[float, float, float] = (1.0, 1.0, 2.0)
                       ) -> tuple[Test, Test, Test]:
    """A function's usual three tests: seeded random cases, edge cases, and hidden cases drawn
    from the secret seed, worth ``points`` in that order."""
    return (Test(f"{fn}: random cases", fn, points[0], random),
            Test(f"{fn}: edge cases", fn, points[1], edges),
            Test(f"{fn}: hidden cases", fn, points[2], hidden, hidden=True))


@dataclass(frozen=True)
class Misconception:
    """A known-wrong way to implement ``function``.

    ``wrong`` takes the same arguments as the function and returns what the mistaken
    implementation would; ``explanation`` is one sentence with the lecture's formula. When
    the mistaken output is not one definite answer, ``symptom(got, *args) -> bool`` instead
    recognises it (the root moved, the bone lengths came out reversed, ...). A mistake that
    makes some inputs raise may say so: ``explains(error, *args)`` returns, for the error a
    case raised (type, message), a sentence on what happened, or None if this mistake does
    not explain it. ``caused_by`` names instead a function of :attr:`Function.uses` whose
    wrong answers, on the failing cases' own arguments, explain this function's failures.
    ``undefined(*args) -> bool`` marks the cases where the mistaken method has no definite
    answer (it does not converge, its iterates are chaos that rounding decides): there a
    failing output neither confirms nor refutes the mistake, and the mistake is named only
    if the failing cases outside them confirm it (at least one).
    """

    key: str
    function: str
    title: str
    explanation: str
    wrong: Callable[..., Any] | None = None
    symptom: Callable[..., bool] | None = None
    explains: Callable[..., str | None] | None = None
    caused_by: str | None = None
    undefined: Callable[..., bool] | None = None

    def __post_init__(self) -> None:
        given = [x is not None for x in (self.wrong, self.symptom, self.caused_by)]
        if sum(given) != 1:
            raise ValueError(f"misconception {self.key!r}: give exactly one of wrong, "
                             "symptom, caused_by")


@dataclass(frozen=True)
class Assignment:
    """An assignment: its template file, functions, tests, allowed imports and catalogue
    (its own ``misconceptions`` and the ``shared`` ones of every assignment)."""

    key: str
    title: str
    template: str
    functions: tuple[Function, ...]
    tests: tuple[Test, ...]
    misconceptions: tuple[Misconception, ...] = ()
    allowed_imports: frozenset[str] = field(default_factory=lambda: frozenset({"numpy"}))
    #: the mistakes every assignment can show (:mod:`autograder.catalogue`), added on loading
    shared: tuple[Misconception, ...] = ()

    def function(self, name: str) -> Function:
        for f in self.functions:
            if f.name == name:
                return f
        raise KeyError(name)

    def misconceptions_of(self, name: str) -> tuple[Misconception, ...]:
        """The mistakes known for function ``name``: the assignment's own first, then the
        shared ones it does not name more specifically (the same key)."""
        own = tuple(m for m in self.misconceptions if m.function == name)
        keys = {m.key for m in own}
        return own + tuple(m for m in self.shared if m.function == name and m.key not in keys)

    @property
    def catalogue(self) -> tuple[Misconception, ...]:
        """Every mistake the diagnosis can name, function by function."""
        return tuple(m for f in self.functions for m in self.misconceptions_of(f.name))


def case_rng(test: Test, seed: str | None) -> np.random.Generator:
    """The generator of a test's cases: fixed for visible tests, from ``seed`` for hidden ones.

    Hashing the test name in keeps each test's cases independent of the others, so adding
    a test does not change the cases of existing ones.
    """
    if test.hidden and not seed:
        raise ValueError(f"test {test.name!r} is hidden and needs the secret seed")
    material = f"{test.name}\0{seed if test.hidden else 'visible'}".encode()
    digest = hashlib.sha256(material).digest()
    return np.random.default_rng(list(np.frombuffer(digest, dtype=np.uint32)))
