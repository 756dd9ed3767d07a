"""Inverse kinematics: the lecture's solvers, one module per method, one entry point.

:func:`solve` runs any method on any skeleton (any fixed joint, any effectors, batched),
:func:`solve_motion` a target per frame over a clip (a new :class:`~course.motion.Motion`;
:func:`hand_targets` makes its demo targets for a CMU clip's hands);
the modules also expose each method as a plain function the notebooks can show:
:func:`two_link`, :func:`ccd_positions`, :func:`fabrik_positions` / :func:`fabrik_batch`,
:func:`chain_jacobian`, :func:`finite_difference_jacobian` and the Jacobian steps.
:mod:`course.ik.methods` lists the methods (:data:`METHODS`), and ``course.ik._engine`` holds
the engines ``solve`` runs them on (see ``docs/architecture.md``).
"""

from .api import solve
from .ccd import ccd_positions
from .fabrik import fabrik_batch, fabrik_positions
from .jacobian import (
    chain_jacobian,
    dls_step,
    finite_difference_jacobian,
    pinv_step,
    pinv_svd,
    pinv_tall,
    pinv_wide,
    transpose_step,
)
from .methods import DEFAULT_MAX_ITER, METHODS
from .motion import MotionIK, hand_targets, solve_motion
from .result import IKResult, SwingTwist, Target
from .two_link import two_link

__all__ = [
    "DEFAULT_MAX_ITER",
    "METHODS",
    "MotionIK",
    "IKResult",
    "SwingTwist",
    "Target",
    "ccd_positions",
    "chain_jacobian",
    "dls_step",
    "fabrik_batch",
    "fabrik_positions",
    "finite_difference_jacobian",
    "hand_targets",
    "pinv_step",
    "pinv_svd",
    "pinv_tall",
    "pinv_wide",
    "solve",
    "solve_motion",
    "transpose_step",
    "two_link",
]
