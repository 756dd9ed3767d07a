"""The bookkeeping every iterative solver shares: residuals, iterations, stalls and reasons,
for one problem in floats or a batch in arrays (:mod:`course.ik._engine.ops`)."""

from __future__ import annotations

from typing import Any

from .ops import ARRAYS, FLOATS, Ops


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
