"""A grid cloth 布料: particles on a rows × cols grid, joined by three kinds of springs.

- structural 结构弹簧: to the right and below neighbours (resist stretching);
- shear 剪切弹簧: along both diagonals of every square (resist shearing);
- bend 弯曲弹簧: to the neighbour two steps away (resist folding), optional.

Rest lengths are the initial distances, so the flat cloth starts at rest. Particle
``(r, c)`` has index ``r * cols + c``; row 0 is the edge that hangs from its pinned corners.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from .mass_spring import GRAVITY, SpringSystem

Array = NDArray[np.float64]

#: Spring kinds, as stored in :attr:`Cloth.kinds`.
STRUCTURAL, SHEAR, BEND = 0, 1, 2
PINS = ("top corners", "all corners", "none")


@dataclass(frozen=True)
class Cloth:
    """A grid cloth: its rest state, its springs and the quads to draw.

    positions : (N, 3) the flat start, at rest.
    system : the :class:`~course.physics.mass_spring.SpringSystem` (masses, springs, fixed).
    shape : (rows, cols); ``N = rows * cols``.
    kinds : (S,) ``STRUCTURAL``, ``SHEAR`` or ``BEND`` per spring.
    quads : (Q, 4) particle indices of the grid's squares, counter-clockwise.
    stiffness : the structural stiffness ``k`` (N/m); shear and bend springs have
        ``k * ratios[kind]``.
    ratios : (3,) stiffness of each kind relative to structural.
    """

    positions: Array
    system: SpringSystem
    shape: tuple[int, int]
    kinds: NDArray[np.intp]
    quads: NDArray[np.intp]
    stiffness: float
    ratios: Array

    @property
    def n_particles(self) -> int:
        return int(self.positions.shape[0])

    def with_stiffness(self, stiffness: float) -> Cloth:
        """The same cloth with structural stiffness ``stiffness`` (the ratios kept)."""
        if not np.isfinite(stiffness) or stiffness <= 0:
            raise ValueError(f"stiffness: must be a positive number, got {stiffness!r}")
        k = float(stiffness) * self.ratios[self.kinds]
        return replace(self, system=replace(self.system, k=k), stiffness=float(stiffness))


def _grid_pairs(rows: int, cols: int, dr: int, dc: int) -> NDArray[np.intp]:
    """Index pairs ``((r, c), (r + dr, c + dc))`` for every such pair inside the grid."""
    r, c = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
    ok = (r + dr < rows) & (c + dc >= 0) & (c + dc < cols)
    a = (r * cols + c)[ok]
    return np.column_stack([a, a + dr * cols + dc])


def grid_cloth(
    rows: int,
    cols: int,
    *,
    size: float = 1.0,
    mass: float = 1.0,
    stiffness: float = 1000.0,
    shear: float = 1.0,
    bend: float = 0.2,
    plane: Literal["xz", "xy"] = "xz",
    pinned: str = "top corners",
    gravity: tuple[float, float, float] = GRAVITY,
) -> Cloth:
    """A square cloth of ``rows × cols`` particles, ``size`` metres wide, total ``mass`` kg.

    Parameters
    ----------
    rows, cols : particles per side (at least 2 each).
    size : the side length along the columns (m); rows are spaced the same.
    mass : total mass (kg), shared equally by the particles.
    stiffness : structural spring stiffness ``k`` (N/m).
    shear, bend : stiffness of the shear and bend springs relative to ``stiffness``;
        ``bend=0`` leaves out the bend springs.
    plane : ``"xz"``: horizontal at height 0 (it falls and swings from its pins);
        ``"xy"``: vertical, hanging down from ``y = 0``.
    pinned : ``"top corners"`` (both ends of row 0), ``"all corners"`` or ``"none"``.
    gravity : (3,) acceleration.
    """
    for name, n in (("rows", rows), ("cols", cols)):
        if int(n) != n or n < 2:
            raise ValueError(f"{name}: a cloth needs at least 2 particles per side, got {n!r}")
    rows, cols = int(rows), int(cols)
    if plane not in ("xz", "xy"):
        raise ValueError(f"plane: must be 'xz' or 'xy', got {plane!r}")
    if pinned not in PINS:
        raise ValueError(f"pinned: must be one of {PINS}, got {pinned!r}")
    for name, value in (("size", size), ("mass", mass), ("stiffness", stiffness)):
        if not np.isfinite(value) or value <= 0:
            raise ValueError(f"{name}: must be a positive number, got {value!r}")
    for name, value in (("shear", shear), ("bend", bend)):
        if not np.isfinite(value) or value < 0:
            raise ValueError(f"{name}: must be a number >= 0, got {value!r}")
    spacing = size / (cols - 1)
    r, c = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
    across, down = (c.ravel() - (cols - 1) / 2) * spacing, r.ravel() * spacing
    zeros = np.zeros(rows * cols)
    positions = (np.column_stack([across, zeros, down]) if plane == "xz"
                 else np.column_stack([across, -down, zeros]))
    groups = [(STRUCTURAL, (0, 1)), (STRUCTURAL, (1, 0)), (SHEAR, (1, 1)), (SHEAR, (1, -1))]
    if bend > 0:
        groups += [(BEND, (0, 2)), (BEND, (2, 0))]
    if shear == 0:
        groups = [g for g in groups if g[0] != SHEAR]
    pairs = [_grid_pairs(rows, cols, *offset) for _, offset in groups]
    kinds = np.concatenate([np.full(len(p), kind) for (kind, _), p in zip(groups, pairs,
                                                                           strict=True)])
    springs = np.concatenate(pairs)
    rest = np.linalg.norm(positions[springs[:, 0]] - positions[springs[:, 1]], axis=1)
    ratios = np.array([1.0, shear, bend])
    last = rows * cols - 1
    fixed = {"top corners": [0, cols - 1], "all corners": [0, cols - 1, last - cols + 1, last],
             "none": []}[pinned]
    system = SpringSystem.create(np.full(rows * cols, mass / (rows * cols)), springs, rest,
                                 stiffness * ratios[kinds], np.array(fixed, dtype=np.intp),
                                 gravity)
    a = (r[:-1, :-1] * cols + c[:-1, :-1]).ravel()
    quads = np.column_stack([a, a + cols, a + cols + 1, a + 1])
    return Cloth(positions, system, (rows, cols), kinds, quads, float(stiffness), ratios)
