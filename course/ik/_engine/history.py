"""The iteration every solver runs, for one problem in floats or a batch in arrays
(:mod:`course.ik._engine.ops`): :func:`iterate`, the one driver of both engines (a method
supplies only its step), the :class:`Solution` it returns, and :class:`History`, its
bookkeeping of residuals, iterations, stalls and reasons."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Generic, Protocol, TypeVar

from .ops import ARRAYS, FLOATS, Flag, Ops

Pose_co = TypeVar("Pose_co", covariant=True)
Points_co = TypeVar("Points_co", covariant=True)
PoseT = TypeVar("PoseT")
PointsT = TypeVar("PointsT")


class State(Protocol[Pose_co, Points_co]):
    """What :func:`iterate` reads of a method's state between two steps (an engine's record,
    :class:`~.chain_solvers.ChainState` or :class:`~.tree_solvers.TreeState`)."""

    @property
    def R(self) -> Pose_co:
        """The pose (what a recorded frame keeps)."""

    @property
    def P(self) -> Points_co:
        """Its node positions."""

    @property
    def err(self) -> Any:
        """The largest effector error of every problem (a float, or (B,))."""

    @property
    def progress(self) -> Any:
        """The objective the stall test watches instead of ``err`` (None: ``err``)."""


S = TypeVar("S", bound=State[Any, Any])
S_co = TypeVar("S_co", bound=State[Any, Any], covariant=True)
RunT = TypeVar("RunT", contravariant=True)
Options = TypeVar("Options", contravariant=True)

# A method's step: the state after one iteration of every problem still running (``active``).
Step = Callable[[S, Flag], S]


class Run(Protocol):
    """What :func:`iterate` reads of a solver's run record (:class:`~.chain_solvers.ChainRun`,
    the tree's :class:`~.tree.Problem`)."""

    @property
    def tol(self) -> float: ...

    @property
    def max_iter(self) -> int: ...

    @property
    def record(self) -> bool: ...

    @property
    def ops(self) -> Ops: ...

    @property
    def done(self) -> Flag:
        """The problems whose start is already their best pose (:mod:`.reach`)."""


@dataclass(frozen=True)
class Solution(Generic[S_co]):
    """What a solver of either engine returns: its final state, the :class:`History`, and the
    states before the first and after every iteration (``record``; else empty)."""

    state: S_co
    history: History
    frames: tuple[S_co, ...] = ()

    @property
    def R(self: Solution[State[PoseT, Any]]) -> PoseT:
        """The final pose."""
        return self.state.R

    @property
    def P(self: Solution[State[Any, PointsT]]) -> PointsT:
        """The final pose's node positions."""
        return self.state.P


class Solver(Protocol[RunT, Options, S_co]):
    """A method on an engine: ``solver(run, options) -> Solution``, ``run`` the engine's run
    record, ``options`` the method's record (:mod:`course.ik._engine.request`)."""

    def __call__(self, run: RunT, options: Options, /) -> Solution[S_co]: ...


def iterate(run: Run, state: S, step: Step[S]) -> Solution[S]:
    """Iterate a method: ``state = step(state, active)`` while some problem is still running.

    Parameters
    ----------
    run : Run
        The engine's run record: ``tol``, ``max_iter``, ``record``, ``ops`` and ``done``.
    state : State
        The start (forward kinematics of the start pose, bent where the engine bends it);
        ``state.err`` a float, or (B,).
    step : callable
        One iteration of the method, ``(state, active) -> state``; ``active`` (a bool, or
        (B,)) marks the problems still running (:attr:`History.active`: not within ``tol``,
        not stalled, below ``max_iter``), and the step leaves the others as they are.

    Returns
    -------
    Solution
        The last state, the :class:`History`, and with ``run.record`` every state from the
        start on (one more than the iterations).
    """
    ops, record = run.ops, run.record
    history = History(state.err, run.tol, run.max_iter, state.progress, ops, run.done)
    frames = [state] if record else []
    while ops.any(history.active):
        state = step(state, history.active)
        history.update(state.err, state.progress)
        if record:
            frames.append(state)
    return Solution(state, history, tuple(frames))


class History:
    """Per-problem convergence bookkeeping for one problem or a batch of ``B``.

    ``update(err)`` records the largest effector error of every problem and returns the mask
    of problems still running (not converged, not stalled, below ``max_iter``). With ``ops``
    :data:`~.ops.FLOATS` (one problem on the serial fast path) errors are floats and
    flags bools, which spares a single solve a numpy call per entry; with
    :data:`~course.ik._engine.ops.ARRAYS` (the default) they are arrays (B,).
    """

    # A problem has stalled when its error (or the objective it minimises) fell by less than
    # this fraction of the tolerance over the last ``window`` iterations.
    window = 8

    def __init__(self, err: Any, tol: float, max_iter: int, progress: Any = None,
                 ops: Ops = ARRAYS, done: Any = False):
        """``progress`` (B,), if given, is the starting objective the stall test then watches
        (see :meth:`update`); ``done`` (B,) marks the problems whose start is already their
        best pose (stretched at a target beyond the reach, :mod:`.reach`): unreached, they
        stop at once, stalled."""
        self.tol, self.max_iter, self.ops = tol, max_iter, ops
        self.residuals = [ops.copy(err)]
        self._progress: list[Any] = [] if progress is None else [ops.copy(progress)]
        self.iterations = ops.full(err, 0)
        self.stalled = ops.both(ops.full(err, True), ops.both(done, err >= tol))
        self.active = (ops.both(err >= tol, ops.invert(self.stalled)) if max_iter > 0
                       else ops.full(err, False))
        # Set by the Jacobian methods: the final Jacobian has lost rank.
        self.singular = ops.full(err, False)

    @classmethod
    def of(cls, residuals: list[Any], iterations: Any, tol: float, max_iter: int,
           ops: Ops = ARRAYS) -> History:
        """The books of a solve that iterated on its own (FABRIK on points alone): its
        residuals before the first and after every iteration and its iterations (per
        problem); nothing runs any more, nothing stalled."""
        history = cls(residuals[0], tol, max_iter, ops=ops)
        history.residuals += residuals[1:]
        history.iterations = iterations
        history.active = ops.full(iterations, False)
        return history

    def update(self, err: Any, progress: Any = None) -> Any:
        """Record ``err`` (B,); ``progress`` (B,), if given, is the objective the solver
        reduces (a length), which the stall test watches instead of ``err``."""
        ops = self.ops
        prev = self.residuals[-1]
        err = ops.where(self.active, err, prev)
        self.iterations += self.active
        self.residuals.append(err)
        watched = self.residuals
        if progress is not None:
            self._progress.append(progress)
            watched = self._progress
        if len(watched) > self.window:
            old, new = watched[-1 - self.window], watched[-1]
            self.stalled |= self.active & (old - new < 1e-3 * self.tol)
        self.active = ((err >= self.tol) & ops.invert(self.stalled)
                       & (self.iterations < self.max_iter))
        return self.active

    def unbatch(self) -> None:
        """Turn the bookkeeping of a batch of one into that problem's own (floats, ints and
        bools, as with :data:`~course.ik._engine.ops.FLOATS`)."""
        self.residuals = [r.item() for r in self.residuals]
        self._progress = [p.item() for p in self._progress]
        self.iterations, self.stalled, self.active, self.singular = (
            a.item() for a in (self.iterations, self.stalled, self.active, self.singular))
        self.ops = FLOATS

    @property
    def error(self) -> Any:
        return self.residuals[-1]

    @property
    def converged(self) -> Any:
        return self.error < self.tol

    def reasons(self, unreachable: Any) -> Any:
        """Why each problem stopped: ``""`` converged, else the most informative reason
        (one problem: a str; a batch: an array of str)."""
        where = self.ops.where
        # Singular only where the solve stalled on a lost-rank Jacobian: one that merely ran
        # out of iterations was still making progress, whatever its last Jacobian.
        stopped = where(self.stalled, where(self.singular, "singular", "stalled"),
                        "max_iterations")
        return where(self.converged, "", where(unreachable, "unreachable", stopped))
