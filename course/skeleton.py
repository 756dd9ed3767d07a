r"""Joint trees: names, parents, bones and joint types, with forward kinematics.

A skeleton of ``J`` joints lists them parent-before-child: ``parents[0] == -1`` (the root)
and ``parents[j] < j``. ``offsets[j]`` is the bone :math:`l_j`, joint j's position in its
parent's frame. Forward kinematics (:mod:`course.fk`) turns local rotations :math:`R_j` into
global orientations and positions, :math:`Q_i = Q_{p(i)} R_i`,
:math:`p_i = p_{p(i)} + Q_{p(i)} l_i`.
"""

from __future__ import annotations

import difflib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import fk
from ._typing import Array
from ._validate import as_array


# --------------------------------------------------------------------------- joint types
def _unit_axis(axis: ArrayLike, name: str) -> tuple[float, float, float]:
    a = as_array(axis, name, (3,))
    if a.shape != (3,):
        raise ValueError(f"{name}: expected one 3-vector, got shape {a.shape}")
    n = float(np.linalg.norm(a))
    if n < 1e-12:
        raise ValueError(f"{name}: has zero length; a joint axis needs a direction")
    x, y, z = a / n
    return float(x), float(y), float(z)


@dataclass(frozen=True)
class Hinge:
    """A revolute joint turning about one ``axis`` (in the parent's frame); 1 degree of freedom.

    The axis is stored normalised, as a tuple so that joint types compare and hash by value.
    """

    axis: tuple[float, float, float] = (0.0, 0.0, 1.0)

    def __post_init__(self) -> None:
        object.__setattr__(self, "axis", _unit_axis(self.axis, "Hinge axis"))

    @property
    def dof(self) -> int:
        return 1


@dataclass(frozen=True)
class Universal:
    """Two hinges in series, about ``axes[0]`` then ``axes[1]`` (not parallel); 2 dof."""

    axes: tuple[tuple[float, float, float], tuple[float, float, float]] = (
        (1.0, 0.0, 0.0),
        (0.0, 1.0, 0.0),
    )

    def __post_init__(self) -> None:
        if len(self.axes) != 2:
            raise ValueError(f"Universal axes: expected two axes, got {len(self.axes)}")
        a, b = (_unit_axis(x, f"Universal axes[{i}]") for i, x in enumerate(self.axes))
        if np.linalg.norm(np.cross(a, b)) < 1e-6:
            raise ValueError(f"Universal axes: {a} and {b} are parallel; that is a hinge")
        object.__setattr__(self, "axes", (a, b))

    @property
    def dof(self) -> int:
        return 2


@dataclass(frozen=True)
class Ball:
    """A spherical joint, any rotation; 3 degrees of freedom."""

    @property
    def dof(self) -> int:
        return 3


@dataclass(frozen=True)
class Fixed:
    """No rotation of its own (an end effector or BVH End Site); 0 degrees of freedom."""

    @property
    def dof(self) -> int:
        return 0


JointType = Hinge | Universal | Ball | Fixed
_JOINT_TYPES = (Hinge, Universal, Ball, Fixed)


class JointNotFoundError(KeyError, ValueError):
    """No joint of that name or index; catch it as ``KeyError`` or ``ValueError``."""

    def __str__(self) -> str:  # KeyError would show the message in quotes
        return str(self.args[0])


# --------------------------------------------------------------------------- skeleton
class Skeleton:
    """A joint tree: names, parents (parent-before-child), bones and joint types.

    Parameters
    ----------
    names : sequence of str, length J
        Unique, non-empty joint names.
    parents : sequence of int, length J
        ``parents[0] == -1``; ``parents[j] < j`` for the others.
    offsets : array_like, shape (J, 3)
        Bone ``l_j``: joint j's position in its parent's frame (the root's is usually 0).
    joint_types : sequence of joint types, or mapping name -> joint type, optional
        :class:`Hinge`, :class:`Universal`, :class:`Ball` or :class:`Fixed` per joint;
        :class:`Ball` for every joint not given.

    Raises
    ------
    ValueError
        Naming the joint (name and index) and what is wrong with it.

    Examples
    --------
    >>> skel = Skeleton(["hip", "knee", "ankle"], [-1, 0, 1], [[0, 0, 0], [0, -4, 0], [0, -4, 0]])
    >>> skel.path("ankle", "hip")
    [2, 1, 0]
    """

    def __init__(
        self,
        names: Sequence[str],
        parents: ArrayLike,
        offsets: ArrayLike,
        joint_types: Sequence[JointType] | Mapping[str, JointType] | None = None,
    ):
        self._names = _checked_names(names)
        n = len(self._names)
        parents_arr = np.asarray(parents)
        if parents_arr.ndim != 1 or len(parents_arr) != n:
            raise ValueError(
                f"parents: expected one parent per joint ({n} names), got shape "
                f"{parents_arr.shape}"
            )
        self._parents = fk.check_parents(parents_arr, self._names)
        self._offsets = _checked_offsets(offsets, self._names)
        self._types = _checked_types(joint_types, self._names)
        self._children: tuple[tuple[int, ...], ...] = tuple(
            tuple(int(c) for c in np.flatnonzero(self._parents == j)) for j in range(n)
        )
        depth = [0] * n
        for j in range(1, n):
            depth[j] = depth[self._parents[j]] + 1
        self._depth = tuple(depth)
        self._lookup = {name: j for j, name in enumerate(self._names)}

    # ------------------------------------------------------------------ structure
    @property
    def names(self) -> tuple[str, ...]:
        return self._names

    @property
    def parents(self) -> NDArray[np.intp]:
        """Parent index per joint, shape (J,), read-only; ``-1`` for the root."""
        return self._parents

    @property
    def offsets(self) -> Array:
        """Bones ``l_j``, shape (J, 3), read-only."""
        return self._offsets

    @property
    def joint_types(self) -> tuple[JointType, ...]:
        return self._types

    @property
    def n_joints(self) -> int:
        return len(self._names)

    def __len__(self) -> int:
        return len(self._names)

    @property
    def dof(self) -> int:
        """Total degrees of freedom of the joint types."""
        return sum(t.dof for t in self._types)

    @property
    def end_effectors(self) -> tuple[int, ...]:
        """Joints without children (the leaves), in index order."""
        return tuple(j for j, c in enumerate(self._children) if not c)

    leaves = end_effectors

    @property
    def bone_lengths(self) -> Array:
        """``|l_j|`` per joint, shape (J,)."""
        lengths: Array = np.linalg.norm(self._offsets, axis=-1)
        return lengths

    def index(self, joint: str | int) -> int:
        """Index of a joint given by name (or an index, checked).

        Raises
        ------
        JointNotFoundError
            (a ``KeyError`` and a ``ValueError``) listing the closest names.
        """
        if isinstance(joint, str):
            j = self._lookup.get(joint)
            if j is not None:
                return j
            close = difflib.get_close_matches(joint, self._names, n=5, cutoff=0.5)
            if not close:
                close = [n for n in self._names if joint.lower() in n.lower()][:5]
            hint = f"; did you mean {', '.join(map(repr, close))}?" if close else ""
            raise JointNotFoundError(
                f"joint: no joint named {joint!r} among the {len(self)} joints{hint}"
            )
        if isinstance(joint, int | np.integer) and not isinstance(joint, bool):
            if 0 <= joint < len(self):
                return int(joint)
            raise JointNotFoundError(f"joint: index {joint} is not in [0, {len(self)})")
        raise JointNotFoundError(f"joint: expected a joint name or index, got {joint!r}")

    def children(self, joint: str | int) -> list[int]:
        """Indices of the joint's children."""
        return list(self._children[self.index(joint)])

    def depth(self, joint: str | int) -> int:
        """Number of bones between the root and the joint (the root has depth 0)."""
        return self._depth[self.index(joint)]

    def path(self, a: str | int, b: str | int) -> list[int]:
        """Joint indices from ``a`` to ``b`` (both included) through their common ancestor."""
        return fk.tree_path(self._parents, self.index(a), self.index(b))

    # ------------------------------------------------------------------ kinematics
    def forward_kinematics(
        self,
        local_rotations: ArrayLike,
        root_position: ArrayLike | None = None,
        *,
        root: str | int = 0,
        root_orientation: ArrayLike | None = None,
    ) -> tuple[Array, Array]:
        """Global positions ``(..., J, 3)`` and orientations ``(..., J, 4)``.

        See :func:`course.fk.forward_kinematics`; ``root`` may be a joint name.
        """
        return fk.forward_kinematics(
            self._parents, self._offsets, local_rotations, root_position,
            root=self.index(root), root_orientation=root_orientation, names=self._names,
        )

    def pin(
        self,
        joint: str | int,
        local_rotations: ArrayLike,
        root_position: ArrayLike | None = None,
        *,
        root: str | int = 0,
        root_orientation: ArrayLike | None = None,
    ) -> tuple[Array, Array]:
        """World position ``(..., 3)`` and orientation ``(..., 4)`` of one joint, to pin it.

        Pass them back as ``forward_kinematics(new_rotations, position, root=joint,
        root_orientation=orientation)`` to keep that joint where it is while the pose changes
        (the lecture's root at the foot). The arguments after ``joint`` are those of the
        forward kinematics the pose currently comes from.
        """
        positions, orientations = self.forward_kinematics(
            local_rotations, root_position, root=root, root_orientation=root_orientation
        )
        j = self.index(joint)
        return positions[..., j, :], orientations[..., j, :]

    def local_from_global(self, orientations: ArrayLike) -> Array:
        """Local rotations ``(..., J, 4)``: ``R_0 = Q_0``, ``R_i = Q_parent^-1 Q_i``."""
        return fk.local_from_global(self._parents, orientations, self._names)

    def rest_positions(self) -> Array:
        """Joint positions ``(J, 3)`` with every local rotation the identity, root at the origin."""
        rest = np.zeros((len(self), 4))
        rest[:, 0] = 1.0
        return self.forward_kinematics(rest)[0]

    # ------------------------------------------------------------------ display
    def __repr__(self) -> str:
        shown = ", ".join(map(repr, self._names[:4])) + (", ..." if len(self) > 4 else "")
        return (
            f"Skeleton({len(self)} joints [{shown}], root {self._names[0]!r}, "
            f"{len(self.end_effectors)} end effectors, dof {self.dof})"
        )

    def __str__(self) -> str:
        return self.describe()

    def describe(self) -> str:
        """The hierarchy as an indented tree: name, index, joint type and bone."""
        lines = [repr(self)]

        def visit(j: int, prefix: str, last: bool, top: bool) -> None:
            branch = "" if top else ("└── " if last else "├── ")
            x, y, z = self._offsets[j]
            lines.append(
                f"{prefix}{branch}{self._names[j]} [{j}] {_type_label(self._types[j])}  "
                f"offset ({x:.4g}, {y:.4g}, {z:.4g})"
            )
            inner = prefix + ("" if top else ("    " if last else "│   "))
            kids = self._children[j]
            for i, c in enumerate(kids):
                visit(c, inner, i == len(kids) - 1, False)

        visit(0, "", True, True)
        return "\n".join(lines)


def _type_label(t: JointType) -> str:
    if isinstance(t, Hinge):
        return "hinge({:.3g}, {:.3g}, {:.3g})".format(*t.axis)
    if isinstance(t, Universal):
        return "universal"
    return type(t).__name__.lower()


def _checked_names(names: Sequence[str]) -> tuple[str, ...]:
    if isinstance(names, str) or not isinstance(names, Sequence):
        raise ValueError(f"names: expected a sequence of joint names, got {type(names).__name__}")
    if not names:
        raise ValueError("names: a skeleton needs at least one joint")
    seen: dict[str, int] = {}
    for j, name in enumerate(names):
        if not isinstance(name, str) or not name.strip():
            raise ValueError(f"names: joint {j} has name {name!r}; names must be non-empty text")
        if name in seen:
            raise ValueError(
                f"names: joint {name!r} (index {j}) has the same name as joint {seen[name]}; "
                "names must be unique"
            )
        seen[name] = j
    return tuple(names)


def _checked_offsets(offsets: ArrayLike, names: tuple[str, ...]) -> Array:
    try:
        L = np.array(offsets, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"offsets: expected numbers, shape ({len(names)}, 3) ({exc})") from None
    if L.shape != (len(names), 3):
        raise ValueError(
            f"offsets: expected shape ({len(names)}, 3), one 3-vector per joint, got {L.shape}"
        )
    bad = ~np.isfinite(L).all(axis=1)
    if bad.any():
        j = int(np.argmax(bad))
        raise ValueError(f"offsets: {fk.joint_label(j, names)} has a NaN or infinite offset {L[j]}")
    L.flags.writeable = False
    return L


def _checked_types(
    joint_types: Sequence[JointType] | Mapping[str, JointType] | None, names: tuple[str, ...]
) -> tuple[JointType, ...]:
    if joint_types is None:
        return (Ball(),) * len(names)
    if isinstance(joint_types, Mapping):
        unknown = [k for k in joint_types if k not in names]
        if unknown:
            raise ValueError(f"joint_types: no joints named {unknown}")
        types = [joint_types.get(name, Ball()) for name in names]
    else:
        types = list(joint_types)
        if len(types) != len(names):
            raise ValueError(
                f"joint_types: expected one per joint ({len(names)}), got {len(types)}"
            )
    for j, t in enumerate(types):
        if not isinstance(t, _JOINT_TYPES):
            raise ValueError(
                f"joint_types: {fk.joint_label(j, names)} has {t!r}; expected Hinge(axis), "
                "Universal(axes), Ball() or Fixed()"
            )
    return tuple(types)


# --------------------------------------------------------------------------- constructors
def chain(
    lengths_or_offsets: ArrayLike,
    axes: ArrayLike | None = None,
    names: Sequence[str] | None = None,
) -> Skeleton:
    """A serial chain of ``K`` bones: ``K + 1`` joints, the last one the end effector.

    Parameters
    ----------
    lengths_or_offsets : array_like, shape (K,) or (K, 3)
        Positive bone lengths (bones along +x) or explicit bone vectors; bone ``i`` goes
        from joint ``i`` to joint ``i + 1``. Joint 0 sits at the root position.
    axes : array_like, shape (3,) or (K, 3), optional
        Hinge axes of joints ``0..K-1`` (one axis for all, or one each); those joints are then
        :class:`Hinge`, otherwise :class:`Ball`. The end effector is :class:`Fixed`.
    names : sequence of str, length K + 1, optional
        Default ``"joint0", ..., "joint{K-1}", "end_effector"``.

    Examples
    --------
    >>> arm = chain([1.0] * 7, axes=[0, 0, 1])
    >>> arm.n_joints, arm.dof
    (8, 7)
    """
    a = as_array(lengths_or_offsets, "lengths_or_offsets")
    if a.ndim == 1:
        if a.size == 0 or np.any(a <= 0):
            raise ValueError(
                f"lengths_or_offsets: bone lengths must be positive and at least one, got {a}"
            )
        bones = np.zeros((a.size, 3))
        bones[:, 0] = a
    elif a.ndim == 2 and a.shape[1] == 3 and a.shape[0] > 0:
        bones = a
    else:
        raise ValueError(
            f"lengths_or_offsets: expected lengths (K,) or bone vectors (K, 3), got {a.shape}"
        )
    k = len(bones)
    if names is None:
        names = [f"joint{i}" for i in range(k)] + ["end_effector"]
    elif len(names) != k + 1:
        raise ValueError(f"names: {k} bones make {k + 1} joints, got {len(names)} names")
    if axes is None:
        types: list[JointType] = [Ball() for _ in range(k)]
    else:
        ax = as_array(axes, "axes", (3,))
        if ax.shape not in ((3,), (k, 3)):
            raise ValueError(f"axes: expected shape (3,) or ({k}, 3), got {ax.shape}")
        ax = np.broadcast_to(ax, (k, 3))
        types = []
        for i, axis in enumerate(ax):
            if np.linalg.norm(axis) < 1e-12:
                raise ValueError(f"axes: the axis of joint {i} has zero length")
            types.append(Hinge(tuple(axis)))
    offsets = np.vstack([np.zeros((1, 3)), bones])
    return Skeleton(list(names), list(range(-1, k)), offsets, types + [Fixed()])
