"""A validated solve: what :func:`course.ik.solve` checked, in the form the engines read: the
:class:`Request`, each method's options as a typed record (:class:`JacobianOptions`,
:class:`CCDOptions`, :class:`TwoLinkOptions`, :class:`NoOptions`), and :class:`Solved`, what
an engine hands back."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, replace
from typing import Literal, NamedTuple

from numpy.typing import ArrayLike

from course._typing import Array
from course.skeleton import Skeleton

from .chain import SerialChain
from .components import Limit
from .history import History
from .ops import Flag
from .tree import TreeModel

JacobianStep = Literal["dls", "pseudo_inverse", "jacobian_transpose"]


@dataclass(frozen=True, kw_only=True)
class JacobianOptions:
    r"""The Jacobian methods' options (:mod:`course.ik.jacobian`): which step (``method``),
    DLS's damping :math:`\lambda` (a length), the pseudo-inverse's ``rcond`` cut and the
    largest joint increment per iteration ``max_step`` (radians)."""

    method: JacobianStep
    damping: float
    rcond: float
    max_step: float


@dataclass(frozen=True, kw_only=True)
class CCDOptions:
    """CCD's options: the sweep's direction, and the largest turn of a joint per step
    (radians; None: no cap)."""

    tip_to_root: bool
    max_angle: float | None


@dataclass(frozen=True, kw_only=True)
class TwoLinkOptions:
    """The two-link solve's options: a pole point ``(3,)`` or ``(B, 3)`` the middle joint
    bends towards (None: the way it bends now), and ``flip`` for the other solution."""

    pole: ArrayLike | None
    flip: bool


@dataclass(frozen=True)
class NoOptions:
    """The options of a method that takes none (FABRIK)."""


MethodOptions = JacobianOptions | CCDOptions | TwoLinkOptions | NoOptions


@dataclass(frozen=True, kw_only=True)
class Request:
    """One solve (``batched`` False: arrays without a batch axis) or a batch of ``B``; frozen,
    built by keyword (:func:`course.ik._pipeline.validate`) and varied with
    :func:`dataclasses.replace`.

    ``pos_t`` and ``rot_t`` map effector joints to their position ``([B,] 3)`` and orientation
    ``([B,] 4)`` targets; ``limits`` holds each variable's :class:`~.components.Limit` (None:
    free) and ``limited`` whether any limits were given at all;
    ``options`` are the method's options with every default filled in (its record, as its
    solvers take it); ``pos_weight`` (E,)
    and ``rot_weight`` (E_r,) the targets' relative weights (largest 1); ``reach_start``
    whether a target near the full reach starts from the reach-aware start (:mod:`.reach`).
    """

    skeleton: Skeleton
    method: str
    local: Array  # ([B,] J, 4) unit quaternions
    root_pos: Array  # ([B,] 3)
    root: int  # the fixed joint
    pos_t: dict[int, Array]
    rot_t: dict[int, Array]
    batched: bool
    B: int
    model: TreeModel
    serial: SerialChain | None  # the model as one serial chain, if it is one
    col_weight: Array  # (C,)
    pos_weight: Array  # (E,)
    rot_weight: Array  # (E_r,)
    limits: tuple[Limit | None, ...]  # (V,)
    limited: bool
    tol: float
    max_iter: int
    record: bool
    options: MethodOptions
    reach_start: bool = True

    def rows(self) -> Iterator[Request]:
        """The batch's problems, one by one (each without a batch axis)."""
        for i in range(self.B):
            yield replace(self, local=_row(self.local, i, 3), root_pos=_row(self.root_pos, i, 2),
                          pos_t={j: _row(t, i, 2) for j, t in self.pos_t.items()}, rot_t={},
                          batched=False, B=1)


def _row(a: Array, i: int, batched_ndim: int) -> Array:
    """Problem ``i`` of ``a``: its row if ``a`` has a batch axis (of ``B``, or of 1 broadcast
    over the batch), else ``a`` itself."""
    if a.ndim < batched_ndim:
        return a
    row: Array = a[i if len(a) > 1 else 0]
    return row


class Solved(NamedTuple):
    """What an engine hands back: the pose (local rotations, root position, positions, with
    a batch's leading ``B``), its :class:`History`, whether each target is out of reach, the
    recorded ``(local rotations, positions)`` of every iteration (``record``) or None, and
    whether each problem iterated from the reach-aware start (:mod:`.reach`)."""

    local: Array
    root_pos: Array
    positions: Array
    history: History
    unreachable: Flag
    frames: list[tuple[Array, Array]] | None
    reach_start: Flag = False
