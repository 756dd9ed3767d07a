"""A validated solve: what :func:`course.ik.solve` checked, in the form the engines read."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, replace
from typing import Any, NamedTuple

from course._typing import Array

from .chain import SerialChain
from .components import Limit
from .history import History
from .tree import TreeModel


@dataclass(frozen=True, kw_only=True)
class Request:
    """One solve (``batched`` False: arrays without a batch axis) or a batch of ``B``; frozen,
    built by keyword (:func:`course.ik._pipeline.validate`) and varied with
    :func:`dataclasses.replace`.

    ``pos_t`` and ``rot_t`` map effector joints to their position ``([B,] 3)`` and orientation
    ``([B,] 4)`` targets; ``limits`` holds each variable's :class:`~.components.Limit` (None:
    free) and ``limited`` whether any limits were given at all;
    ``options`` are the method's options with every default filled in; ``pos_weight`` (E,)
    and ``rot_weight`` (E_r,) the targets' relative weights (largest 1); ``reach_start``
    whether a target near the full reach starts from the reach-aware start (:mod:`.reach`).
    """

    skeleton: Any
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
    options: dict[str, Any]
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
    unreachable: Any
    frames: list[tuple[Array, Array]] | None
    reach_start: Any = False
