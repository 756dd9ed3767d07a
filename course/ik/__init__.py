"""Inverse kinematics: the lecture's solvers, one module per method, one entry point.

:func:`solve` runs any method on any skeleton (any fixed joint, any effectors, batched);
the modules also expose each method as a plain function the notebooks can show:
:func:`two_link`, :func:`ccd_positions`, :func:`fabrik_positions` / :func:`fabrik_batch`,
:func:`chain_jacobian`, :func:`finite_difference_jacobian` and the Jacobian steps.
"""

from .api import DEFAULT_MAX_ITER, METHODS, solve
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
from .result import IKResult, Target
from .two_link import two_link

__all__ = [
    "DEFAULT_MAX_ITER",
    "METHODS",
    "IKResult",
    "Target",
    "ccd_positions",
    "chain_jacobian",
    "dls_step",
    "fabrik_batch",
    "fabrik_positions",
    "finite_difference_jacobian",
    "pinv_step",
    "pinv_svd",
    "pinv_tall",
    "pinv_wide",
    "solve",
    "transpose_step",
    "two_link",
]
