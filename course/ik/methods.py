"""The IK methods :func:`course.ik.solve` offers: one record per method, read by ``solve`` (its
checks and its engines), by the views (``course.viz``'s method pickers) and by the docs.

Each :class:`Method` says what the method takes (its options, their defaults and checks), what
it can aim at (positions only, or orientations too) and which engine functions run it: the
general tree engine (:mod:`course.ik._engine.tree_solvers`, any skeleton) and, where there is
one, the serial-chain fast path (:mod:`course.ik._engine.chain_solvers`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from functools import partial
from typing import Any, Generic, TypeVar

from ._engine import chain_solvers as chain
from ._engine import tree_solvers as tree
from ._engine.request import (
    CCDOptions,
    JacobianOptions,
    JacobianStep,
    MethodOptions,
    NoOptions,
    TwoLinkOptions,
)

# The method's options record (:mod:`course.ik._engine.request`), which its solvers take.
Options = TypeVar("Options", bound=MethodOptions)


@dataclass(frozen=True)
class Option:
    """An option a method takes: its default, and the test a value must pass (None: any
    value), with what it must be for the message."""

    default: Any = None
    test: Callable[[Any], bool] | None = None
    what: str = ""


@dataclass(frozen=True)
class Method(Generic[Options]):
    """One IK method, as :func:`course.ik.solve` runs it.

    Attributes
    ----------
    name : str
    summary : str
        One line for docs and views.
    max_iter : int
        Default iteration budget.
    options : mapping name -> Option
    options_record : callable
        Builds the options record the solvers take from the checked options (every default
        filled in), by keyword.
    orientations : bool
        Takes orientation targets (else positions only).
    targets : str
        What it aims at and how it weighs several targets (:class:`~course.ik.Target`'s
        ``weight_position`` / ``weight_orientation``), for docs and errors.
    limits : str
        How joint limits are enforced (all methods take them).
    weights : bool
        Uses per-joint ``weights`` (the regulariser :math:`W`).
    iterative : bool
        Iterates (so a singular straight start is bent first); two-link is closed-form.
    tree : TreeSolver
        The general engine's solver (:data:`~course.ik._engine.tree_solvers.TreeSolver`,
        a :class:`~course.ik._engine.history.Solver` on the tree's run record).
    chain : ChainSolver or None
        The serial-chain solver (:data:`~course.ik._engine.chain_solvers.ChainSolver`);
        None: the tree engine runs every skeleton.
    batch_from : float
        Batches on the chain smaller than this run one problem at a time in floats (the
        array engine pays a numpy call per component and step, for as many iterations as
        the batch's slowest problem needs); measured on the chains of ``benchmarks/ik.py``.
    batch_from_points : float, optional
        The same for FABRIK's points-only engine (a chain of free balls, no limits).
    """

    name: str
    summary: str
    max_iter: int
    options: Mapping[str, Option]
    options_record: Callable[..., Options]
    tree: tree.TreeSolver[Options]
    chain: chain.ChainSolver[Options] | None = None
    orientations: bool = False
    targets: str = ""
    limits: str = "projected after every step"
    weights: bool = False
    iterative: bool = True
    batch_from: float = math.inf
    batch_from_points: float | None = None

    def singles_below(self, free_balls: bool, limited: bool) -> float:
        """The smallest batch the array engine solves faster than single solves."""
        if self.batch_from_points is not None and free_balls and not limited:
            return self.batch_from_points
        return self.batch_from


def _positive_angle(x: Any) -> bool:
    return bool(x > 0)


_ANGLE = "a positive angle in radians (inf: no cap)"
_JACOBIAN_OPTIONS = {
    # None: 5% of the longest path to an effector (tree_solvers.DEFAULT_DAMPING), a length.
    # Its sixth power is a determinant in the closed-form step: beyond 1e50 it overflows.
    "damping": Option(None, lambda x: 0 <= x <= 1e50, "a length in [0, 1e50]"),
    "rcond": Option(1e-6, lambda x: 0 <= x < 1, "a number in [0, 1)"),
    "max_step": Option(0.5, _positive_angle, _ANGLE),
}


_JACOBIAN_TARGETS = ("positions and orientations (the 6-row Jacobian), each target's rows "
                     "weighted by the square root of its weight")


def _jacobian(name: JacobianStep, summary: str, max_iter: int,
              batch_from: float) -> Method[JacobianOptions]:
    return Method(
        name, summary, max_iter, _JACOBIAN_OPTIONS, partial(JacobianOptions, method=name),
        tree=tree.solve_jacobian, chain=chain.solve_jacobian,
        orientations=True, targets=_JACOBIAN_TARGETS, weights=True, batch_from=batch_from)


# Iteration budgets: Jacobian transpose converges linearly and slowly near the target, and its
# slowest problems take thousands of iterations, so its batches never beat its single solves.
REGISTRY: dict[str, Method[Any]] = {m.name: m for m in (
    Method("two_link", "analytic hip-knee-ankle (law of cosines, pole, hinge knees)", 1,
           {"pole": Option(), "flip": Option(False)}, TwoLinkOptions, tree=tree.solve_two_link,
           targets="one position, two bones from the fixed joint: the law of cosines places "
                   "the joints, no orientation can be asked of them",
           limits="projected after placing the joints", iterative=False),
    Method("ccd", "cyclic coordinate descent: one joint at a time turns the end to the target",
           200, {"tip_to_root": Option(True),
                 "max_angle": Option(None, _positive_angle, _ANGLE)}, CCDOptions,
           orientations=True,
           targets="positions and orientations: each joint takes the weighted least-squares "
                   "turn of the targets below it, an orientation as its frame's three axes "
                   "(the last joint of an orientation target turns the end to it)",
           tree=tree.solve_ccd, chain=chain.solve_ccd, batch_from=256),
    Method("fabrik", "forward and backward reaching on joint positions", 200, {}, NoOptions,
           orientations=True,
           targets="positions and orientations: sub-bases reach to the weighted centroid of "
                   "their branches; after the backward pass the last joint of an orientation "
                   "target turns the end to it (by its weight's share where it moves a "
                   "position target too)",
           tree=tree.solve_fabrik, chain=chain.solve_fabrik,
           limits="projected in the backward pass", batch_from=256, batch_from_points=64),
    _jacobian("jacobian_transpose", "gradient descent, J^T e with Buss's step", 2000,
              math.inf),
    _jacobian("pseudo_inverse", "least squares, J^+ e (SVD, rcond cut)", 100, 48),
    _jacobian("dls", "damped least squares (Levenberg-Marquardt), the default", 100, 48),
)}

METHODS = tuple(REGISTRY)
DEFAULT_MAX_ITER = {m.name: m.max_iter for m in REGISTRY.values()}
