"""``solve``: one entry point for every IK method, on any skeleton, rooted at any joint.

A solve is two steps (:mod:`course.ik._pipeline`): :func:`~course.ik._pipeline.validate`
checks every argument against the method's record (:mod:`course.ik.methods`) and builds a
:class:`~course.ik._engine.request.Request`, :func:`~course.ik._pipeline.run` hands it to an
engine (the serial-chain fast path where the paths are one chain, else the general tree
engine) and builds the :class:`IKResult`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from numpy.typing import ArrayLike

from course.skeleton import Skeleton

from ._pipeline import Engine, run, validate
from .result import IKResult

__all__ = ["Engine", "solve"]


def solve(
    skeleton: Skeleton,
    local_rotations: ArrayLike,
    root_position: ArrayLike,
    targets: Mapping[str | int, Any],
    method: str = "dls",
    root: str | int | None = None,
    tol: float = 1e-4,
    max_iter: int | None = None,
    weights: Mapping[str | int, float] | None = None,
    limits: Mapping[str | int, Any] | None = None,
    record: bool = False,
    reach_start: bool = True,
    *,
    engine: Engine = "auto",
    **options: Any,
) -> IKResult:
    r"""Move a skeleton's joints so that the end effectors reach their targets.

    Only the local rotations on the paths from the fixed joint ``root`` to the effectors
    change; every other joint keeps its local rotation (and so moves rigidly with its parent).
    With ``root`` other than joint 0 the skeleton is re-rooted there (the lecture's root at
    the foot, :math:`Q_p = Q_c R_c^{-1},\ p_p = p_c - Q_p l_c`): that joint keeps its position
    and, if any path leaves it upwards, its global orientation; the rest of the body, joint 0
    included, moves around it. If all effectors lie below ``root``, its parent frame is held
    and ``R_root`` is a variable (as for an ordinary chain rooted at joint 0).

    A straight path whose target lies on its own line is a singular pose for every iterative
    method (no Jacobian column points along the line; FABRIK and CCD stay on it): the
    iterative methods first bend it by a small deterministic turn of each joint
    (:func:`course.ik._engine.tree.bend_increment`, 0.05 rad), so ``frames[0]`` and
    ``residuals[0]`` are those of the bent start. Near the stretched pose they all crawl
    (the distance to the root changes with the square of the bend): a serial chain of ball
    joints, or of hinges about one axis, whose target lies at 0.9 or more of its full reach
    starts bent evenly to the target's distance and aimed at it
    (:mod:`course.ik._engine.reach`), and says so in ``result.start`` (``reach_start=False``
    leaves the method alone from the given pose).

    Parameters
    ----------
    skeleton : course.skeleton.Skeleton
        Hinge joints solve for one angle about their axis, ball (and universal) joints for a
        full rotation, fixed joints not at all.
    local_rotations : array_like, shape ([B,] J, 4)
        Starting pose (unit quaternions); a leading ``B`` solves ``B`` problems at once.
    root_position : array_like, shape ([B,] 3)
        Position of joint 0.
    targets : mapping joint (name or index) -> target
        A world position ``(3,)`` or ``(B, 3)``; a pair ``(position, quaternion)``; or a
        :class:`Target` (``Target(None, q)``: an orientation alone; ``weight_position`` and
        ``weight_orientation`` weigh competing targets). Every iterative method takes
        orientation targets (CCD and FABRIK by an end-orientation step), ``two_link`` none;
        each record's ``targets`` says how it meets and weighs them.
    method : {"two_link", "ccd", "fabrik", "jacobian_transpose", "pseudo_inverse", "dls"}
        The records of :data:`course.ik.methods.REGISTRY` (what each takes and runs on).
    root : joint name or index, optional
        The joint that stays fixed; default joint 0.
    tol : float
        Convergence: every effector within ``tol`` (orientations within ``tol`` radians).
    max_iter : int, optional
        Default per method (:data:`DEFAULT_MAX_ITER`).
    weights : mapping joint -> float, optional
        Jacobian methods: the regulariser :math:`W` (larger: the joint moves less).
    limits : mapping joint -> (lo, hi), float or SwingTwist, optional
        Hinge angle range in radians (one angle ``a``: the range ``(-a, a)``); for a ball
        joint a :class:`SwingTwist` (a cone on the swing of its bone and a twist range,
        projected by :func:`course.rotations.clamp_swing_twist`) or one largest rotation
        angle of its local rotation (swing and twist together). Enforced by projection after
        each step (CCD, Jacobian) or joint placement (FABRIK, two-link), so every iteration's
        pose is within them. Joint 0 takes none when ``root`` is a joint whose paths go up
        through it (its rotation is then the body's world orientation). A target the limits
        keep the solve from is reported ``reason="limits"`` (see :class:`IKResult`).
    record : bool
        Keep every iteration's pose in ``result.frames``.
    reach_start : bool
        Start a target at or near the full reach from the reach-aware start (above; the
        default). False: every iterative method from the given pose alone, as the lecture's
        loop runs it (near the reach it crawls, beyond it may end off the stretched pose):
        to compare with a plain implementation.
    engine : {"auto", "chain", "tree"}
        Which implementation runs the method. ``"tree"``: the general engine, which walks
        the paths of any joint tree; ``"chain"``: the serial-chain engine, which runs a whole
        batch in arrays (used only where the paths are one chain, else ``"tree"``);
        ``"auto"`` (the default) takes the chain engine for a chain, a small batch one
        problem at a time. Each engine runs the lecture tier's step (:mod:`course.ik.ccd`,
        :mod:`course.ik.fabrik`, :mod:`course.ik.jacobian`) in another layout: one iteration
        agrees to rounding and whole solves meet the same targets within ``tol``
        (``tests/test_ik_differential.py``), though rounding may settle two engines on
        different poses of the same residual. The choice is speed.
    **options
        ``damping`` (DLS :math:`\lambda`, a length in [0, 1e50]), ``rcond`` (pseudo-inverse
        cutoff, in [0, 1)), ``max_step`` (largest joint step per Jacobian iteration, radians,
        > 0), ``tip_to_root`` and ``max_angle`` (CCD: the largest turn per joint and step,
        radians, > 0), ``pole`` (a world point) and ``flip`` (two-link).

    Returns
    -------
    IKResult

    Raises
    ------
    ValueError
        Naming the argument: unknown method, joint or option; an option value, ``tol`` or
        ``max_iter`` out of range; non-finite, huge (beyond :data:`LARGEST_COORDINATE`) or
        badly shaped input, a zero quaternion; a hinge whose start rotation is off its axis;
        an effector no joint on its path can move; a two-link solve whose path is not two
        bones.
    """
    if engine not in ("auto", "chain", "tree"):
        raise ValueError(f"engine: expected 'auto', 'chain' or 'tree', got {engine!r}")
    req = validate(skeleton, local_rotations, root_position, targets, method, root, tol,
                    max_iter, weights, limits, record, options, reach_start)
    return run(req, engine)
