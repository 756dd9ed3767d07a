r"""Forward kinematics on joint trees, batched over frames.

Joint ``j`` has a parent ``parents[j]`` (``-1`` for the root, joint 0), a bone ``l_j``
(``offsets[j]``, its position in the parent's frame) and a local rotation ``R_j``. The
lecture's recursion gives every joint's global orientation and position:

.. math::
    Q_0 = R_0,\quad p_0 = \text{root position};\qquad
    Q_i = Q_{p(i)} R_i,\quad p_i = p_{p(i)} + Q_{p(i)}\, l_i .

Any joint ``k`` can serve as the root instead ("the root at the foot"): ``k`` is placed at
the given position and orientation and the tree is walked outward from ``k``. Down an edge
``p -> c`` the recursion is the one above; up an edge ``c -> p`` it is inverted,

.. math::
    Q_p = Q_c R_c^{-1},\qquad p_p = p_c - Q_p\, l_c .

How it is computed: frames are the fast axis. Orientations and positions are stored
component-major, ``(7, J, F)``, so each step of the walk is a few dozen in-place elementwise
operations on contiguous arrays of all ``F`` frames, instead of gathering ``(F, 4)`` slices of
frame-major arrays (about 5x slower) or looping over frames in Python (about 3000x slower);
``benchmarks/fk.py`` measures this. The results are returned as views of that storage: the
usual shapes ``(..., J, 3)`` and ``(..., J, 4)``, with frames-fastest strides. Every numpy
operation treats them as usual; ``np.ascontiguousarray`` makes a C-ordered copy if some code
needs one (it would cost about half as much again as the kinematics). A few frames (up to
``FLOAT_FRAMES``, e.g. the single poses of an IK solver) are computed in Python floats
instead, which is much cheaper than numpy calls on tiny arrays.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache
from typing import Generic, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._typing import Array
from ._validate import as_array, broadcast_leading
from .rotations import _kernels
from .rotations._kernels import Quat, q_mul

# How far |q|^2 may be from 1 before a rotation is rejected as not a unit quaternion: loose
# enough for quaternions stored in float32, tight enough to catch unnormalised input, which
# would silently stretch the bones.
UNIT_TOL = 1e-5

# Up to this many frames are computed one by one in Python floats (see _FloatWalk).
FLOAT_FRAMES = 8

# One step of the walk: (joint computed, joint it is computed from, going up the tree?).
Step = tuple[int, int, bool]


# --------------------------------------------------------------------------- tree checks
def joint_label(j: int, names: Sequence[str] | None = None) -> str:
    """``"joint 'LeftLeg' (index 3)"``, or ``"joint 3"`` without names, for messages."""
    return f"joint {names[j]!r} (index {j})" if names is not None else f"joint {j}"


def check_parents(parents: ArrayLike, names: Sequence[str] | None = None) -> NDArray[np.intp]:
    """``parents`` as a read-only integer array, checked to describe a joint tree.

    Parameters
    ----------
    parents : array_like of int, shape (J,)
        Parent index of every joint; ``parents[0] == -1`` and ``parents[j] < j`` for the
        others (parents before children), so joint 0 is the one root.
    names : sequence of str, optional
        Joint names, used only to name the offending joint in error messages.

    Raises
    ------
    ValueError
        Naming the joint (and its name if given) and what is wrong with its parent.
    """
    p = np.asarray(parents)
    if p.ndim != 1 or p.size == 0:
        raise ValueError(f"parents: expected a non-empty 1-D sequence, got shape {p.shape}")
    if p.dtype.kind not in "iu":
        if p.dtype.kind != "f" or not np.all(np.isfinite(p)) or np.any(p != np.round(p)):
            raise ValueError(f"parents: expected integer joint indices, got {p.dtype} {p}")
        p = p.astype(np.intp)
    out = _checked_parents(tuple(p.tolist()))
    if isinstance(out, tuple):
        j, message = out
        raise ValueError(message.format(joint=joint_label(j, names)))
    return out


@lru_cache(maxsize=256)
def _checked_parents(parents: tuple[int, ...]) -> NDArray[np.intp] | tuple[int, str]:
    # Cached, since forward kinematics checks its parents on every call. An error comes back
    # as (joint, message template) so that the caller can fill in the joint's name.
    if parents[0] != -1:
        return 0, (
            f"parents: {{joint}} must be the root with parent -1, got parent {parents[0]} "
            "(joints are listed parent-before-child, so the root comes first)"
        )
    for j, p in enumerate(parents[1:], start=1):
        if p == -1:
            return j, (
                "parents: {joint} has parent -1, but a skeleton has exactly one root "
                "and it must be joint 0"
            )
        if not 0 <= p < len(parents):
            return j, f"parents: {{joint}} has parent {p}, which is not a joint index"
        if p >= j:
            return j, (
                f"parents: {{joint}} has parent {p}, which does not come before it; "
                "list joints parent-before-child (parents[j] < j)"
            )
    out = np.array(parents, dtype=np.intp)
    out.flags.writeable = False
    return out


def tree_path(parents: NDArray[np.intp], a: int, b: int) -> list[int]:
    """Joint indices from ``a`` to ``b`` (both included) through their lowest common ancestor."""
    up_a = _ancestors(parents, a)
    up_b = _ancestors(parents, b)
    on_b = set(up_b)
    top = next(j for j in up_a if j in on_b)
    return up_a[: up_a.index(top) + 1] + up_b[: up_b.index(top)][::-1]


def _ancestors(parents: NDArray[np.intp], j: int) -> list[int]:
    """``[j, parent(j), ..., 0]``."""
    out = [j]
    while parents[out[-1]] >= 0:
        out.append(int(parents[out[-1]]))
    return out


@lru_cache(maxsize=256)
def _walk(parents: tuple[int, ...], root: int) -> tuple[Step, ...]:
    """Steps that reach every joint from ``root``, each from a joint already reached."""
    if root == 0:
        return tuple((j, p, False) for j, p in enumerate(parents) if p >= 0)
    neighbours: list[list[tuple[int, bool]]] = [[] for _ in parents]
    for c, p in enumerate(parents):
        if p >= 0:
            neighbours[p].append((c, False))
            neighbours[c].append((p, True))
    steps: list[Step] = []
    queue = [root]
    seen = {root}
    for src in queue:
        for j, up in neighbours[src]:
            if j not in seen:
                seen.add(j)
                steps.append((j, src, up))
                queue.append(j)
    return tuple(steps)


def _path_steps(parents: NDArray[np.intp], a: int, b: int) -> tuple[Step, ...]:
    """Steps along the tree path from ``a`` to ``b``."""
    path = tree_path(parents, a, b)
    return tuple((y, x, bool(parents[x] == y)) for x, y in zip(path, path[1:], strict=False))


# --------------------------------------------------------------------------- kernel
_Table = tuple[tuple[tuple[int, int, int], ...], ...]  # per component: (sign, i, k) terms


def _hamilton_tables() -> tuple[_Table, ...]:
    # (a b)_c = sum of sign * a_i * b_k; the second table is a b^* (b's vector part negated).
    # Terms are ordered positive first, so each component starts with a plain product.
    terms = (
        ((1, 0, 0), (-1, 1, 1), (-1, 2, 2), (-1, 3, 3)),
        ((1, 0, 1), (1, 1, 0), (1, 2, 3), (-1, 3, 2)),
        ((1, 0, 2), (-1, 1, 3), (1, 2, 0), (1, 3, 1)),
        ((1, 0, 3), (1, 1, 2), (-1, 2, 1), (1, 3, 0)),
    )
    conj = tuple(tuple((s if k == 0 else -s, i, k) for s, i, k in row) for row in terms)
    return tuple(
        tuple(tuple(sorted(row, key=lambda t: -t[0])) for row in table)
        for table in (terms, conj)
    )


_HAMILTON, _HAMILTON_CONJ = _hamilton_tables()
_CROSS = ((1, 2), (2, 0), (0, 1))  # (a x b)_i = a_j b_k - a_k b_j for (j, k) = _CROSS[i]


# How a walk holds one quaternion or vector: Python floats (_FloatWalk) or rows (_ArrayWalk).
V = TypeVar("V")


class _Walk(Generic[V]):
    """The walk over the tree; subclasses store ``Q_j``, ``p_j`` and do the arithmetic."""

    def rotation(self, j: int) -> V:
        raise NotImplementedError

    def product(self, j: int, src: int, r: V, conjugate: bool) -> None:
        raise NotImplementedError

    def rotate_add(self, j: int, src: int, x: int, bone: int, sign: int) -> None:
        raise NotImplementedError

    def set_orientation(self, j: int, q: V) -> None:
        raise NotImplementedError

    def set_position(self, j: int, p: V) -> None:
        raise NotImplementedError

    def walk(self, parents: NDArray[np.intp], root: int, q0: V | None, p0: V) -> None:
        """Place joint ``root`` at ``p0`` with orientation ``q0`` (by default the one from
        ordinary FK) and reach every other joint from it; ``q0``, ``p0`` as stored."""
        if q0 is None:
            self.set_orientation(0, self.rotation(0))
            if root != 0:  # default Q_k: ordinary FK orientations along the path 0 -> k
                self.run(_path_steps(parents, 0, root), positions=False)
        else:
            self.set_orientation(root, q0)
        self.set_position(root, p0)
        self.run(_walk(tuple(parents.tolist()), root))

    def run(self, steps: Sequence[Step], positions: bool = True) -> None:
        for j, src, up in steps:
            bone = src if up else j  # an edge's local rotation and bone belong to the child
            r = self.rotation(bone)
            if up:  # Q_p = Q_c R_c^-1, p_p = p_c - Q_p l_c
                self.product(j, src, r, conjugate=True)
                if positions:
                    self.rotate_add(j, src, j, bone, -1)
            else:  # Q_c = Q_p R_c, p_c = p_p + Q_p l_c
                self.product(j, src, r, conjugate=False)
                if positions:
                    self.rotate_add(j, src, src, bone, 1)


class _FloatWalk(_Walk[Sequence[float]]):
    """One frame in Python floats: for a single pose (an IK solver calls this thousands of
    times) plain float arithmetic costs far less than numpy calls on length-1 arrays."""

    def __init__(self, R: Array, L: Array):
        self.R: list[list[float]] = R.tolist()
        self.L: list[list[float]] = L.tolist()
        # Empty until the walk fills them, each before it is read.
        self.Q: list[Quat] = [(1.0, 0.0, 0.0, 0.0)] * len(self.R)
        self.P: list[Sequence[float]] = [[]] * len(self.R)

    def set_orientation(self, j: int, q: Sequence[float]) -> None:
        w, x, y, z = q
        self.Q[j] = (w, x, y, z)

    def set_position(self, j: int, p: Sequence[float]) -> None:
        self.P[j] = p

    def rotation(self, j: int) -> Sequence[float]:
        return self.R[j]

    def product(self, j: int, src: int, r: Sequence[float], conjugate: bool) -> None:
        """``Q_j = Q_src r`` (or ``Q_src r^*``): the kernel's Hamilton product."""
        w, x, y, z = r
        self.Q[j] = q_mul(self.Q[src], (w, -x, -y, -z) if conjugate else (w, x, y, z))

    def rotate_add(self, j: int, src: int, x: int, bone: int, sign: int) -> None:
        """``p_j = p_src + sign * Q_x l_bone`` as ``v + 2w (u x v) + u x (2 u x v)``."""
        (w, *u), v, p = self.Q[x], self.L[bone], self.P[src]
        t = [2 * (u[a] * v[b] - u[b] * v[a]) for a, b in _CROSS]
        self.P[j] = [
            p[i] + sign * (v[i] + w * t[i] + u[a] * t[b] - u[b] * t[a])
            for i, (a, b) in enumerate(_CROSS)
        ]


class _ArrayWalk(_Walk[Array]):
    """All frames at once on component-major storage ``work (7, J, F)``: ``Q_j`` in
    ``work[0:4, j]`` and ``p_j`` in ``work[4:7, j]``, each component a contiguous row.

    ``R`` are the local rotations ``(F, J, 4)`` and ``L`` the bones, either ``(J, 3)``
    constants or per-frame ``(F, J, 3)``. Each step copies the one local rotation (and bone)
    it needs into contiguous scratch rows and updates one joint with in-place ufuncs.
    """

    def __init__(
        self, R: Array, L: Array, work: Array, batch: tuple[int, ...],
        names: Sequence[str] | None = None,
    ):
        n = work.shape[-1]
        self.R, self.L, self.batch, self.names = R, L, batch, names
        self.Q, self.P = work[:4].transpose(1, 0, 2), work[4:].transpose(1, 0, 2)
        self.r = np.empty((4, n))
        self.l = np.empty((3, n)) if L.ndim == 3 else None
        self.t = np.empty((3, n))
        self.s = np.empty(n)

    def set_orientation(self, j: int, q: Array) -> None:
        np.copyto(self.Q[j], q)

    def set_position(self, j: int, p: Array) -> None:
        np.copyto(self.P[j], p)

    def rotation(self, j: int) -> Array:
        """``R_j`` copied into contiguous rows, checked to be unit in every frame."""
        r, s = self.r, self.s
        np.copyto(r, self.R[:, j].T)
        np.einsum("cf,cf->f", r, r, out=s)
        # NaN fails both comparisons, so this also rejects NaN.
        if s.size and not (s.max() <= 1.0 + UNIT_TOL and s.min() >= 1.0 - UNIT_TOL):
            bad = self.R[:, j : j + 1].reshape(self.batch + (1, 4))
            check_unit(bad, "local_rotations", self.names, joint=j)
        return r

    def _bone(self, j: int) -> Array | tuple[float, float, float]:
        if self.l is None:
            x, y, z = self.L[j]
            return float(x), float(y), float(z)
        np.copyto(self.l, self.L[:, j].T)
        return self.l

    def product(self, j: int, src: int, r: Array, conjugate: bool) -> None:
        """``Q_j = Q_src r`` (or ``Q_src r^*``) by the sign tables, one ufunc per term."""
        s, out, a = self.s, self.Q[j], self.Q[src]
        for c, ((_, i0, k0), *rest) in enumerate(_HAMILTON_CONJ if conjugate else _HAMILTON):
            o = out[c]
            np.multiply(a[i0], r[k0], out=o)
            for sign, i, k in rest:
                np.multiply(a[i], r[k], out=s)
                (np.add if sign > 0 else np.subtract)(o, s, out=o)

    def rotate_add(self, j: int, src: int, x: int, bone: int, sign: int) -> None:
        """``p_j = p_src + sign * Q_x l_bone`` as ``v + 2w (u x v) + u x (2 u x v)``.

        With constant bones, terms with a zero bone component are skipped (bones along an
        axis are common), so those cost a third of the work.
        """
        out, p, q, v = self.P[j], self.P[src], self.Q[x], self._bone(bone)
        s, w, u = self.s, q[0], q[1:]
        const = isinstance(v, tuple)
        if const and not any(v):
            np.copyto(out, p)
            return
        # t = 2 u x v, or None where that component is identically zero.
        t: list[Array | None] = []
        for i, (a, b) in enumerate(_CROSS):
            terms = [(u[a], 2 * v[b]), (u[b], -2 * v[a])]
            if const:
                terms = [(x, c) for x, c in terms if c != 0]
            if not terms:
                t.append(None)
                continue
            ti = self.t[i]
            np.multiply(*terms[0], out=ti)
            for x, c in terms[1:]:
                np.multiply(x, c, out=s)
                np.add(ti, s, out=ti)
            t.append(ti)
        add, sub = (np.add, np.subtract) if sign > 0 else (np.subtract, np.add)
        for i, (a, b) in enumerate(_CROSS):
            o = out[i]
            add(p[i], v[i], out=o)
            for x, y, op in ((w, t[i], add), (u[a], t[b], add), (u[b], t[a], sub)):
                if y is not None:
                    np.multiply(x, y, out=s)
                    op(o, s, out=o)


# --------------------------------------------------------------------------- public API
def check_unit(
    q: Array, name: str, names: Sequence[str] | None = None, joint: int = 0
) -> None:
    """Raise a ValueError naming the first entry of ``q (..., J, 4)`` that is not unit.

    ``q[..., i, :]`` belongs to joint ``joint + i``.
    """
    n2 = np.einsum("...i,...i->...", q, q)
    bad = ~(np.abs(n2 - 1.0) <= UNIT_TOL)  # also catches NaN
    if np.any(bad):
        where = tuple(int(i) for i in np.argwhere(bad)[0])
        value = q[where]
        what = (
            "is NaN or infinite" if not np.all(np.isfinite(value))
            else f"has norm {np.sqrt(n2[where]):.6g}, not 1; normalise it (quat_normalize)"
        )
        where = where[:-1] + (where[-1] + joint,)
        raise ValueError(
            f"{name}: the quaternion of {joint_label(where[-1], names)} at index {where} "
            f"{what}"
        )


def _local_rotations(local_rotations: ArrayLike, n: int, names: Sequence[str] | None) -> Array:
    try:
        R = np.asarray(local_rotations, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"local_rotations: expected numbers ({exc})") from None
    if R.ndim < 2 or R.shape[-2:] != (n, 4):
        raise ValueError(
            f"local_rotations: expected shape (..., {n}, 4) for {n} joints, got {R.shape}"
        )
    return R


def _offsets(offsets: ArrayLike, n: int) -> Array:
    L = as_array(offsets, "offsets", (3,))
    if L.ndim < 2 or L.shape[-2] != n:
        raise ValueError(f"offsets: expected shape ({n}, 3) or (..., {n}, 3), got {L.shape}")
    if all(d == 1 for d in L.shape[:-2]):
        L = L.reshape(n, 3)
    return L


def _check_root(root: int, n: int) -> int:
    if isinstance(root, bool) or not isinstance(root, int | np.integer) or not 0 <= root < n:
        raise ValueError(f"root: expected a joint index in [0, {n}), got {root!r}")
    return int(root)


def forward_kinematics(
    parents: ArrayLike,
    offsets: ArrayLike,
    local_rotations: ArrayLike,
    root_position: ArrayLike | None = None,
    *,
    root: int = 0,
    root_orientation: ArrayLike | None = None,
    names: Sequence[str] | None = None,
) -> tuple[Array, Array]:
    r"""Global joint positions and orientations from local rotations.

    .. math::
        Q_i = Q_{p(i)} R_i,\qquad p_i = p_{p(i)} + Q_{p(i)}\, l_i

    With ``root=k`` the walk starts at joint ``k``, placed at ``root_position`` with global
    orientation ``root_orientation``, and goes outward: down an edge as above, up an edge
    ``c -> p`` as :math:`Q_p = Q_c R_c^{-1}`, :math:`p_p = p_c - Q_p l_c`. Joint 0's own local
    rotation is then unused (it only ties joint 0 to the world, which is now done from ``k``).

    Parameters
    ----------
    parents : array_like of int, shape (J,)
        ``parents[0] == -1``, ``parents[j] < j``.
    offsets : array_like, shape (J, 3) or (..., J, 3)
        Bones ``l_j``: joint j's position in its parent's frame. Per-frame offsets (for joints
        with position channels) broadcast against the frames.
    local_rotations : array_like, shape (..., J, 4)
        Unit quaternions ``R_j`` (w, x, y, z).
    root_position : array_like, shape (..., 3), optional
        World position of the root joint (joint ``root``); the origin if omitted.
    root : int, default 0
        The joint the walk starts from.
    root_orientation : array_like, shape (..., 4), optional
        Global orientation ``Q_root`` of the root joint. Default: the orientation that joint
        has in ordinary forward kinematics of the same local rotations, ``R_0 R_1 ... R_k``
        along the path from joint 0 (so for ``root=0`` it is ``R_0``). Then every joint's
        orientation is the same for any choice of ``root``, and ``root`` only chooses which
        joint stays at ``root_position``. To keep joint k fixed in orientation too (a planted
        foot) pass its orientation, e.g. from :meth:`course.skeleton.Skeleton.pin`.
    names : sequence of str, optional
        Joint names, used in error messages.

    Returns
    -------
    positions : ndarray, shape (..., J, 3)
    orientations : ndarray, shape (..., J, 4)
        The leading shape is the broadcast of the inputs' leading shapes. For more than
        ``FLOAT_FRAMES`` frames these are views with frames-fastest strides (see the module
        notes); they do not share memory with each other or with the inputs.

    Raises
    ------
    ValueError
        Naming the argument (and joint) at fault: a bad tree, wrong shapes, NaN, or local
        rotations that are not unit quaternions (``| |q|^2 - 1 | > 1e-5``).
    """
    par = check_parents(parents, names)
    n = len(par)
    root = _check_root(root, n)
    L = _offsets(offsets, n)
    R = _local_rotations(local_rotations, n, names)
    p0 = np.zeros(3) if root_position is None else as_array(root_position, "root_position", (3,))
    q0 = None
    if root_orientation is not None:
        q0 = as_array(root_orientation, "root_orientation", (4,))
        check_unit(q0[..., None, :], "root_orientation", names, joint=root)

    args = [("local_rotations", R, 2), ("root_position", p0, 1), ("offsets", L, 2)]
    broadcast_leading(
        "forward_kinematics", *args, *([] if q0 is None else [("root_orientation", q0, 1)])
    )
    if np.prod(np.broadcast_shapes(R.shape[:-2], p0.shape[:-1], L.shape[:-2])) <= FLOAT_FRAMES:
        check_unit(R, "local_rotations", names)
    return forward_kernel(par, L, R, p0, root=root, root_orientation=q0, names=names)


def forward_kernel(
    parents: NDArray[np.intp],
    offsets: Array,
    local_rotations: Array,
    root_position: Array,
    *,
    root: int = 0,
    root_orientation: Array | None = None,
    names: Sequence[str] | None = None,
) -> tuple[Array, Array]:
    r""":func:`forward_kinematics` without its checks (正向运动学内核), for inner loops.

    The caller has checked what :func:`forward_kinematics` checks: ``parents`` an int array
    (:func:`check_parents`), ``offsets`` (J, 3) or (..., J, 3), ``local_rotations``
    (..., J, 4) unit quaternions, ``root_position`` (..., 3), ``root_orientation`` (..., 4)
    or None, leading shapes that broadcast. The same walk, so the same numbers bit for bit.
    (For more than ``FLOAT_FRAMES`` frames the walk still meets each rotation's norm as it
    copies its rows, and says so naming the joint, by ``names`` if given.)

    Returns
    -------
    positions : ndarray, shape (..., J, 3)
    orientations : ndarray, shape (..., J, 4)
    """
    par, L, R, p0, q0 = parents, offsets, local_rotations, root_position, root_orientation
    n = len(par)
    batch = np.broadcast_shapes(
        R.shape[:-2], p0.shape[:-1], L.shape[:-2], *([] if q0 is None else [q0.shape[:-1]])
    )
    F = int(np.prod(batch))

    def frames(a: Array, tail: tuple[int, ...]) -> Array:
        return np.broadcast_to(a, batch + tail).reshape((F,) + tail)

    R = frames(R, (n, 4))
    per_frame = L.ndim == 3 or L.shape != (n, 3)
    if per_frame:
        L = frames(L, (n, 3))
    p0 = frames(p0, (3,))
    q0 = None if q0 is None else frames(q0, (4,))
    if F <= FLOAT_FRAMES:
        walks = [_FloatWalk(R[f], L[f] if per_frame else L) for f in range(F)]
        for f, w in enumerate(walks):
            w.walk(par, root, None if q0 is None else q0[f].tolist(), p0[f].tolist())
        positions = np.array([w.P for w in walks]).reshape(batch + (n, 3))
        orientations = np.array([w.Q for w in walks]).reshape(batch + (n, 4))
        return positions, orientations
    work = np.empty((7, n, F))
    _ArrayWalk(R, L, work, batch, names).walk(par, root, None if q0 is None else q0.T, p0.T)
    # The results are views of this storage: the usual shapes, frames-fastest strides.
    frames_last = work.reshape((7, n) + batch)
    positions = np.moveaxis(frames_last[4:], (0, 1), (-1, -2))
    orientations = np.moveaxis(frames_last[:4], (0, 1), (-1, -2))
    return positions, orientations


def local_from_global(
    parents: ArrayLike, orientations: ArrayLike, names: Sequence[str] | None = None
) -> Array:
    r"""Local rotations from global orientations.

    .. math::
        R_0 = Q_0,\qquad R_i = Q_{p(i)}^{-1} Q_i

    The inverse of the orientation part of :func:`forward_kinematics`.

    Parameters
    ----------
    parents : array_like of int, shape (J,)
    orientations : array_like, shape (..., J, 4)
        Unit quaternions ``Q_j``.
    names : sequence of str, optional
        Joint names, used in error messages.

    Returns
    -------
    ndarray, shape (..., J, 4)
    """
    par = check_parents(parents, names)
    Q = np.asarray(orientations, dtype=np.float64) if orientations is not None else None
    if Q is None or Q.ndim < 2 or Q.shape[-2:] != (len(par), 4):
        got = None if Q is None else Q.shape
        raise ValueError(f"orientations: expected shape (..., {len(par)}, 4), got {got}")
    check_unit(Q, "orientations", names)
    inv_parent = Q[..., par[1:], :] * np.array([1.0, -1.0, -1.0, -1.0])
    return np.concatenate([Q[..., :1, :], _kernels.quat_mul(inv_parent, Q[..., 1:, :])], axis=-2)
