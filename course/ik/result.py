"""What :func:`course.ik.solve` takes as a target and returns."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from course._typing import Array


@dataclass(frozen=True)
class Target:
    """A goal for one joint: a world position and, optionally, a global orientation.

    Parameters
    ----------
    position : array_like, shape (3,) or (B, 3), or None
        None: an orientation alone.
    orientation : array_like, shape (4,) or (B, 4), optional
        Unit quaternion (w, x, y, z) the joint's global orientation ``Q_j`` should reach.
    weight_position, weight_orientation : float
        How much this target's position and orientation errors count against the other
        targets' (relative: a solve divides them by the largest; each method's record in
        :data:`course.ik.methods.REGISTRY` says how it weighs them). They matter where
        targets compete (a pose that cannot meet them all), not for one target alone.
    """

    position: ArrayLike | None
    orientation: ArrayLike | None = None
    weight_position: float = 1.0
    weight_orientation: float = 1.0


@dataclass(frozen=True)
class SwingTwist:
    r"""A ball joint's limit as a cone on the swing and a range on the twist (shoulders, hips).

    The local rotation splits as :math:`R = s\otimes t`
    (:func:`course.rotations.swing_twist`): the swing :math:`s` may turn the bone axis by at
    most ``max_swing`` from its rest direction, the twist :math:`t` about it lies in ``twist``.
    Solvers project with :func:`course.rotations.clamp_swing_twist`.

    Parameters
    ----------
    max_swing : float
        Half-angle of the cone, radians in :math:`[0, \pi]`.
    twist : (lo, hi)
        Twist range, radians, :math:`-\pi \le lo \le hi \le \pi`; default free.
    axis : array_like, shape (3,), optional
        Twist axis in the joint's local frame; default the joint's rest bone direction (its
        child's offset; several children: the direction of their offsets' sum).
    """

    max_swing: float
    twist: tuple[float, float] = (-np.pi, np.pi)
    axis: ArrayLike | None = None


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
        making progress when the iteration cap was hit), ``"stalled"`` (no more progress:
        a local minimum) or ``"limits"`` (the joint limits keep it from the target: the same
        method from the same start, with the same ``tol`` and ``max_iter``, reaches it
        without them).
    frames : list of dict, optional
        With ``record=True``: the pose before the first and after every iteration, each a
        dict with ``"positions"`` ``([B,] J, 3)`` and ``"local_rotations"`` ``([B,] J, 4)``.
    method : str
    start : str or ndarray of str, shape (B,)
        Where the iterations started: ``""`` from the given pose (projected into the limits;
        a straight chain aimed along its own line bent a little first; always with
        ``solve(..., reach_start=False)``), ``"reach"`` from the reach-aware start: a serial
        chain of ball joints, or of hinges about one axis, whose target lies at 0.9 or more
        of its full reach is first bent evenly in a plane so that its end reaches the
        target's distance, aimed at it (stretched straight at or beyond the reach); near the
        stretched pose every iterative method otherwise crawls. ``frames[0]`` and
        ``residuals[0]`` are then that pose's.
    """

    local_rotations: Array
    root_position: Array
    positions: Array
    converged: bool | NDArray[np.bool_]
    iterations: int | NDArray[np.int_]
    residuals: Array
    reason: str | NDArray[np.str_]
    method: str = ""
    start: str | NDArray[np.str_] = ""
    frames: list[dict[str, Array]] | None = field(default=None, repr=False)

    @property
    def error(self) -> float | Array:
        """The final residual (largest effector error)."""
        last: float | Array = self.residuals[-1]
        return last
