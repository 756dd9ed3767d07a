"""What every solver returns, and the bookkeeping the iterative solvers share."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Target:
    """A goal for one joint: a world position and, optionally, a global orientation.

    Parameters
    ----------
    position : array_like, shape (3,) or (B, 3)
    orientation : array_like, shape (4,) or (B, 4), optional
        Unit quaternion (w, x, y, z) the joint's global orientation ``Q_j`` should reach.
    """

    position: ArrayLike
    orientation: ArrayLike | None = None


@dataclass
class IKResult:
    """The outcome of an IK solve (one problem, or a batch with a leading ``B`` axis).

    Attributes
    ----------
    local_rotations : ndarray, shape ([B,] J, 4)
        Solved local rotations ``R_j``; joints off the paths from the fixed joint to the
        effectors keep theirs.
    root_position : ndarray, shape ([B,] 3)
        Position of joint 0 (moves only when the fixed joint is not joint 0).
    positions : ndarray, shape ([B,] J, 3)
        Global joint positions of the solved pose (forward kinematics of the above).
    converged : bool or ndarray of bool, shape (B,)
        Every effector within ``tol`` of its target (orientations within ``tol`` radians).
    iterations : int or ndarray, shape (B,)
    residuals : ndarray, shape (iterations + 1,) or (T, B)
        Largest effector error before the first and after every iteration.
    reason : str or ndarray of str, shape (B,)
        ``""`` when converged, else ``"unreachable"`` (no pose reaches: the best, stretched
        pose is returned), ``"singular"`` (a Jacobian method stalled where the Jacobian has
        lost rank, so no step can reduce the remaining error), ``"max_iterations"`` (still
        making progress when the iteration cap was hit) or ``"stalled"`` (no more progress:
        a local minimum or a constrained chain).
    frames : list of dict, optional
        With ``record=True``: the pose before the first and after every iteration, each a
        dict with ``"positions"`` ``([B,] J, 3)`` and ``"local_rotations"`` ``([B,] J, 4)``.
    method : str
    """

    local_rotations: Array
    root_position: Array
    positions: Array
    converged: bool | NDArray[np.bool_]
    iterations: int | NDArray[np.int_]
    residuals: Array
    reason: str | NDArray[np.str_]
    method: str = ""
    frames: list[dict[str, Array]] | None = field(default=None, repr=False)

    @property
    def error(self) -> float | Array:
        """The final residual (largest effector error)."""
        return self.residuals[-1]


class History:
    """Per-problem convergence bookkeeping for a batch of ``B`` problems.

    ``update(err)`` records the largest effector error of every problem and returns the mask
    of problems still running (not converged, not stalled, below ``max_iter``).
    """

    # A problem has stalled when its error (or the objective it minimises) fell by less than
    # this fraction of the tolerance over the last ``window`` iterations.
    window = 8

    def __init__(self, err: Array, tol: float, max_iter: int, progress: Array | None = None):
        """``progress`` (B,), if given, is the starting objective the stall test then watches
        (see :meth:`update`)."""
        self.tol, self.max_iter = tol, max_iter
        self.residuals = [err.copy()]
        self._progress: list[Array] = [] if progress is None else [progress.copy()]
        self.iterations = np.zeros(err.shape, dtype=int)
        self.stalled = np.zeros(err.shape, dtype=bool)
        self.active = err >= tol if max_iter > 0 else self.stalled.copy()
        # Set by the Jacobian methods: the final Jacobian has lost rank.
        self.singular = self.stalled.copy()

    def update(self, err: Array, progress: Array | None = None) -> Array:
        """Record ``err`` (B,); ``progress`` (B,), if given, is the objective the solver
        reduces (a length), which the stall test watches instead of ``err``."""
        prev = self.residuals[-1]
        err = np.where(self.active, err, prev)
        self.iterations += self.active
        self.residuals.append(err)
        watched = self.residuals
        if progress is not None:
            self._progress.append(progress)
            watched = self._progress
        if len(watched) > self.window:
            old, new = watched[-1 - self.window], watched[-1]
            self.stalled |= self.active & (old - new < 1e-3 * self.tol)
        self.active = (err >= self.tol) & ~self.stalled & (self.iterations < self.max_iter)
        return self.active

    @property
    def error(self) -> Array:
        return self.residuals[-1]

    @property
    def converged(self) -> Array:
        return self.error < self.tol

    def reasons(self, unreachable: Array) -> NDArray[np.str_]:
        """Why each problem stopped: ``""`` converged, else the most informative reason."""
        converged = self.converged
        if converged.all():
            return np.zeros(converged.shape, dtype="<U14")  # all ""
        out = np.full(converged.shape, "max_iterations", dtype="<U14")
        out[self.stalled] = "stalled"
        # Singular only where the solve stalled on a lost-rank Jacobian: one that merely ran
        # out of iterations was still making progress, whatever its last Jacobian.
        out[self.stalled & self.singular] = "singular"
        out[unreachable & ~converged] = "unreachable"
        out[converged] = ""
        return out
