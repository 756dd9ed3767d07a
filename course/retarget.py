r"""Rest poses and motion retargeting (重定向): T pose ↔ A pose, and onto another skeleton.

A skeleton's rest pose (静止姿态) is its pose with every local rotation the identity: then
every joint frame is aligned with the world and joint :math:`i`'s bones point along its
children's offsets :math:`l_c`. Two skeletons can share a hierarchy and still differ in rest
pose -- a T pose (T 姿态, arms out) and an A pose (A 姿态, arms down) -- so the same local
rotations :math:`R_i` point their bones in different directions. Copying local rotations
from one to the other is wrong by exactly the rest-pose difference.

**The correction.** Let :math:`C_i` be the rotation of joint :math:`i` that turns the
*target* skeleton's rest bone directions onto the *source*'s, :math:`C_i\,\hat l^{\,B}_c =
\hat l^{\,A}_c` for every child :math:`c` (source A, target B). Asking the target's bones to
point where the source's do in every frame,

.. math::
    Q^B_i\,\hat l^{\,B}_c = Q^A_i\,\hat l^{\,A}_c = Q^A_i C_i\,\hat l^{\,B}_c
    \quad\Longleftarrow\quad Q^B_i = Q^A_i\,C_i ,

and with the lecture's forward kinematics :math:`Q_i = Q_{p(i)} R_i`, i.e.
:math:`R_i = Q_{p(i)}^{-1} Q_i`,

.. math::
    R'_i = (Q^A_{p(i)} C_{p(i)})^{-1}\, Q^A_i C_i = C_{p(i)}^{-1}\, R_i\, C_i ,
    \qquad R'_0 = R_0\, C_0 .

The correction multiplies on the *right* of the joint's own rotation (it acts in the joint's
rest frame, before the motion) and its inverse on the *left* for the parent's; ``R C`` and
``C R`` differ. The round trip A → B → A uses :math:`C^{-1}` and gives back :math:`R_i`.

**Choosing** :math:`C_i`. One child bone fixes :math:`C_i` up to a twist about the bone; we
take the shortest arc (:func:`~course.rotations.quat_between`). Several children fix it
completely when their angles agree (the best fit otherwise, Kabsch / Wahba). Zero-length
bones carry no direction: a joint whose child bones all have zero length (CMU's ``Hips``,
``Spine1``, ``LeftHand``) looks through them to the next bones; a joint with none at all (a
leaf) keeps its parent's correction.

**Different skeletons** are matched by a name map ``{target joint: source joint}``: the
target orientation is :math:`Q^B_i = Q^A_{m(i)} C_i` for a mapped joint, and an unmapped
(extra) joint keeps its rest pose relative to its parent (:math:`R'_i = I`). The root path is
scaled by the ratio of the rest hip heights. Bones match exactly when the source has no
rotating joint between two mapped ones; :func:`bone_direction_errors` measures the rest.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import fk
from ._typing import Array
from ._validate import as_array
from .fk import check_parents, check_unit
from .motion import Motion, default_channels
from .rotations import (
    _kernels,
    quat_from_axis_angle,
    quat_from_matrix,
    quat_identity,
    quat_rotate,
)
from .skeleton import Hinge, JointNotFoundError, Skeleton, Universal

# Bones shorter than this (in skeleton units) have no direction.
_ZERO_BONE = 1e-9


# --------------------------------------------------------------------------- rest poses
def with_rest_pose(skeleton: Skeleton, local_rotations: ArrayLike) -> Skeleton:
    r"""The same hierarchy with a pose baked in as its rest pose.

    Joint frames of the new skeleton are world-aligned in the new rest pose, so each bone
    becomes :math:`l'_i = Q_{p(i)}\, l_i`, with :math:`Q` the global orientations of the pose
    (the root offset is kept). Hinge and universal axes (given in the parent's frame) turn
    with it.

    Parameters
    ----------
    skeleton : Skeleton
    local_rotations : array_like, shape (J, 4)
        The pose :math:`R_i` to become the rest pose.
    """
    R = np.asarray(local_rotations, dtype=np.float64)
    if R.shape != (skeleton.n_joints, 4):
        raise ValueError(
            f"local_rotations: expected shape ({skeleton.n_joints}, 4), one pose, got {R.shape}"
        )
    _, Q = skeleton.forward_kinematics(R)
    parents = skeleton.parents
    Qp = np.concatenate([quat_identity((1,)), Q[parents[1:]]])
    offsets = quat_rotate(Qp, skeleton.offsets)
    types = []
    for t, q in zip(skeleton.joint_types, Qp, strict=True):
        if isinstance(t, Hinge):
            t = Hinge(tuple(quat_rotate(q, t.axis)))
        elif isinstance(t, Universal):
            a0, a1 = (quat_rotate(q, a) for a in t.axes)
            t = Universal(((a0[0], a0[1], a0[2]), (a1[0], a1[1], a1[2])))
        types.append(t)
    return Skeleton(skeleton.names, parents, offsets, types)


def a_pose_from_t_pose(
    skeleton: Skeleton,
    angle: float = np.pi / 4,
    arms: Sequence[str] = ("LeftArm", "RightArm"),
) -> Skeleton:
    """An A-pose skeleton from a T-pose one: each arm turned ``angle`` radians down at the
    shoulder joints ``arms`` (the whole arm below turns with it), about the axis
    ``bone x down`` (y up), so the arm stays in its plane with the body's up axis.

    Raises
    ------
    ValueError
        Naming the arm joint if it is missing, has no bone below it, or already points down.
    """
    pose = quat_identity((skeleton.n_joints,))
    rest = skeleton.rest_positions()
    for arm in arms:
        j = _joint(skeleton, arm, "arms")
        kids = [c for c in skeleton.children(j) if np.linalg.norm(skeleton.offsets[c]) > _ZERO_BONE]
        if not kids:
            raise ValueError(f"arms: joint {arm!r} has no bone below it to turn down")
        bone = rest[kids[0]] - rest[j]
        axis = np.cross(bone, [0.0, -1.0, 0.0])
        if np.linalg.norm(axis) < 1e-9 * np.linalg.norm(bone):
            raise ValueError(f"arms: the bone below {arm!r} already points straight up or down")
        pose[j] = quat_from_axis_angle(axis, angle)
    return with_rest_pose(skeleton, pose)


def rest_height(skeleton: Skeleton) -> float:
    """Height of the root above the lowest joint in the rest pose (the hip height), > 0."""
    y = skeleton.rest_positions()[:, 1]
    h = float(y[0] - y.min())
    if h <= _ZERO_BONE:
        raise ValueError(
            f"skeleton: the root {skeleton.names[0]!r} is not above any joint in the rest pose; "
            "cannot scale the root height"
        )
    return h


# --------------------------------------------------------------------------- name maps
def _joint(skeleton: Skeleton, name: str | int, argument: str) -> int:
    try:
        return skeleton.index(name)
    except JointNotFoundError as exc:
        raise ValueError(f"{argument}: {exc}") from None


def _mapping(
    source: Skeleton, target: Skeleton, name_map: Mapping[str, str] | None
) -> NDArray[np.intp]:
    """Source index per target joint, -1 where unmapped; checked against both hierarchies."""
    if name_map is None:
        missing = [n for n in target.names if n not in source.names]
        extra = [n for n in source.names if n not in target.names]
        if missing or extra:
            raise ValueError(
                "name_map: the skeletons' joint names differ (target only: "
                f"{missing[:6]}, source only: {extra[:6]}); pass name_map={{target: source}}"
            )
        name_map = {n: n for n in target.names}
    if not isinstance(name_map, Mapping):
        raise ValueError(f"name_map: expected a mapping target joint -> source joint, got "
                         f"{type(name_map).__name__}")
    m = np.full(target.n_joints, -1)
    for t_name, s_name in name_map.items():
        m[_joint(target, t_name, "name_map (target joint)")] = _joint(
            source, s_name, f"name_map[{t_name!r}] (source joint)"
        )
    if m[0] < 0:
        raise ValueError(f"name_map: the target root {target.names[0]!r} must be mapped")
    for i in range(1, target.n_joints):
        if m[i] < 0:
            continue
        a = _mapped_ancestor(target.parents, m, i)
        if not _is_below(source.parents, int(m[i]), int(m[a])):
            raise ValueError(
                f"name_map: target joint {target.names[i]!r} (below {target.names[a]!r}) maps "
                f"to source {source.names[m[i]]!r}, which is not below "
                f"{source.names[m[a]]!r} in the source hierarchy"
            )
    return m


def _mapped_ancestor(parents: NDArray[np.intp], m: NDArray[np.intp], i: int) -> int:
    a = int(parents[i])
    while m[a] < 0:
        a = int(parents[a])
    return a


def _is_below(parents: NDArray[np.intp], j: int, ancestor: int) -> bool:
    j = int(parents[j])
    while j >= 0 and j != ancestor:
        j = int(parents[j])
    return j == ancestor


# --------------------------------------------------------------------------- corrections
def _direction_pairs(
    target: Skeleton, m: NDArray[np.intp], i: int, P_t: Array, P_s: Array
) -> tuple[list[Array], list[Array]]:
    """Rest directions (target, source) from mapped joint ``i`` to its next mapped joints.

    Unmapped joints are looked through (their local rotation stays the identity); zero-length
    bones are looked through only when no direct bone has a direction (the bones below a
    mapped joint turn with that joint, not with ``i``). ``P_t``, ``P_s``: rest positions.
    """
    direct: tuple[list[Array], list[Array]] = ([], [])
    deeper: tuple[list[Array], list[Array]] = ([], [])
    stack = [(c, False) for c in target.children(i)]
    while stack:
        k, through_zero = stack.pop()
        d_t = P_t[k] - P_t[i]
        d_s = P_s[m[k]] - P_s[m[i]] if m[k] >= 0 else None
        if d_s is not None and min(np.linalg.norm(d_t), np.linalg.norm(d_s)) > _ZERO_BONE:
            out = deeper if through_zero else direct
            out[0].append(d_t)
            out[1].append(d_s)
            continue
        stack.extend((c, through_zero or m[k] >= 0) for c in target.children(k))
    return direct if direct[0] else deeper


def _best_rotation(d_from: list[Array], d_to: list[Array]) -> Array:
    """Unit quaternion C with C d_from[k] ~ d_to[k] (directions compared, lengths ignored)."""
    a = np.array(d_from) / np.linalg.norm(d_from, axis=1, keepdims=True)
    b = np.array(d_to) / np.linalg.norm(d_to, axis=1, keepdims=True)
    # Kabsch (the shortest arc for one direction, or where they all lie on one line).
    return quat_from_matrix(_kernels.best_rotation(a, b))


def rest_corrections(
    source: Skeleton, target: Skeleton, name_map: Mapping[str, str] | None = None
) -> Array:
    r"""Per target joint, the rotation :math:`C_i` turning its rest bones onto the source's.

    :math:`C_i\,\hat l^{\,B}_c = \hat l^{\,A}_{m(c)}` for the next mapped joints :math:`c`
    below :math:`i` (see the module notes for the choice with one, several or no bones).

    Parameters
    ----------
    source, target : Skeleton
    name_map : mapping target joint name -> source joint name, optional
        Default: the same names (both skeletons must then have the same joints).

    Returns
    -------
    ndarray, shape (J_target, 4)
    """
    m = _mapping(source, target, name_map)
    return _corrections(source, target, m)


def _corrections(source: Skeleton, target: Skeleton, m: NDArray[np.intp]) -> Array:
    C = quat_identity((target.n_joints,))
    P_t, P_s = target.rest_positions(), source.rest_positions()
    for i in range(target.n_joints):
        if i > 0:
            C[i] = C[target.parents[i]]  # leaves and unmapped joints keep the parent's
        if m[i] >= 0:
            d_t, d_s = _direction_pairs(target, m, i, P_t, P_s)
            if d_t:
                C[i] = _best_rotation(d_t, d_s)
    return C


# --------------------------------------------------------------------------- retargeting
def _globals(parents: NDArray[np.intp], R: Array) -> Array:
    """Global orientations :math:`Q_i = Q_{p(i)} R_i` of checked local rotations ``R``
    (the orientation half of the forward-kinematics kernel)."""
    zero = np.zeros((len(parents), 3))
    return fk.forward_kernel(parents, zero, R, np.zeros(R.shape[:-2] + (3,)))[1]


def _retarget_rotations(
    parents_to: NDArray[np.intp], m: NDArray[np.intp], C: Array, Q_from: Array
) -> Array:
    """Local rotations of the target: Q'_i = Q_from[m(i)] C_i, or Q'_parent if unmapped."""
    Q = np.empty(Q_from.shape[:-2] + (len(m), 4))
    for i, s in enumerate(m):
        Q[..., i, :] = (_kernels.quat_mul(Q_from[..., s, :], C[i]) if s >= 0
                        else Q[..., parents_to[i], :])
    R: Array = Q.copy()
    conj = Q[..., parents_to[1:], :] * np.array([1.0, -1.0, -1.0, -1.0])
    R[..., 1:, :] = _kernels.quat_mul(conj, Q[..., 1:, :])
    # An unmapped joint keeps its rest pose exactly (R'_i = I), not as Q'_p^* Q'_p rounded
    # (numpy 1.x rounds that product to 1e-15 off the identity).
    R[..., np.flatnonzero(m[1:] < 0) + 1, :] = (1.0, 0.0, 0.0, 0.0)
    return R


def retarget_rest(
    parents: ArrayLike, offsets_from: ArrayLike, offsets_to: ArrayLike, local_quats: ArrayLike
) -> Array:
    r"""Local rotations for another rest pose of the same hierarchy: :math:`C_{p(i)}^{-1} R_i C_i`.

    Parameters
    ----------
    parents : array_like of int, shape (J,)
    offsets_from, offsets_to : array_like, shape (J, 3)
        Bones :math:`l_i` of the skeleton the rotations are for, and of the target.
    local_quats : array_like, shape (..., J, 4)

    Returns
    -------
    ndarray, shape (..., J, 4)
        Rotations under which every bone of the target points where the source's does.

    Raises
    ------
    ValueError
        Naming the argument: parents that are no tree, offsets or rotations that are not
        numbers of the right shape, or a rotation that is not a unit quaternion (with its
        joint), as forward kinematics refuses it: non-unit rotations compound down a chain
        (norm 3 at every joint gave norm 243 five joints down).
    """
    p = check_parents(parents)
    names = [f"joint{j}" for j in range(len(p))]
    source = Skeleton(names, p, _bones(offsets_from, "offsets_from", len(p)))
    target = Skeleton(names, p, _bones(offsets_to, "offsets_to", len(p)))
    R = as_array(local_quats, "local_quats", (4,))
    if R.ndim < 2 or R.shape[-2] != len(p):
        raise ValueError(f"local_quats: expected shape (..., {len(p)}, 4), got {R.shape}")
    check_unit(R, "local_quats")
    m = np.arange(len(names))
    C = _corrections(source, target, m)
    return _retarget_rotations(target.parents, m, C, _globals(source.parents, R))


def _bones(offsets: ArrayLike, name: str, n: int) -> Array:
    """``offsets`` checked to be ``n`` bones (n, 3), the error naming ``name``."""
    L = as_array(offsets, name, (3,))
    if L.shape != (n, 3):
        raise ValueError(f"{name}: expected shape ({n}, 3), one bone per joint, got {L.shape}")
    return L


def retarget(
    motion: Motion,
    skeleton: Skeleton,
    name_map: Mapping[str, str] | None = None,
    *,
    scale_root: bool = True,
    name: str | None = None,
) -> Motion:
    r"""The clip on another skeleton, every mapped bone pointing as in the source.

    Parameters
    ----------
    motion : Motion
        The source clip (skeleton A).
    skeleton : Skeleton
        The target skeleton B: the same hierarchy in another rest pose, or another skeleton.
    name_map : mapping target joint -> source joint, optional
        Default: the same names. Target joints left out keep their rest pose relative to their
        parent; source joints left out are dropped.
    scale_root : bool
        Scale the root path by ``rest_height(B) / rest_height(A)`` (shorter legs, shorter
        steps, the feet stay on the floor).

    Returns
    -------
    Motion
        Local rotations :math:`R'_i = C_{p(i)}^{-1} R_i C_i` (same hierarchy), or from
        :math:`Q'_i = Q_{m(i)} C_i` in general; the root at the scaled source root path.

    Raises
    ------
    ValueError
        Naming the joint when the map names a missing joint, leaves the root out, or does not
        follow the hierarchy; or if the clip animates bone lengths (translations).
    """
    if motion.translations is not None:
        raise ValueError("motion: has per-frame bone translations; retarget handles rotations "
                         "and the root path only")
    source = motion.skeleton
    m = _mapping(source, skeleton, name_map)
    C = _corrections(source, skeleton, m)
    positions, Q_from = source.forward_kinematics(motion.local_rotations, motion.root_positions)
    scale = rest_height(skeleton) / rest_height(source) if scale_root else 1.0
    return Motion(
        skeleton=skeleton,
        local_rotations=_retarget_rotations(skeleton.parents, m, C, np.asarray(Q_from)),
        root_positions=scale * positions[:, m[0]],
        frame_time=motion.frame_time,
        channels=default_channels(skeleton),
        name=name if name is not None else f"{motion.name}_retargeted",
        source=motion.source,
    )


def copy_local_rotations(
    motion: Motion, skeleton: Skeleton, name_map: Mapping[str, str] | None = None
) -> Motion:
    """The naive retargeting: local rotations copied joint by joint, no rest-pose correction.

    Wrong whenever the rest poses differ; shown in the notebook to measure how wrong.
    """
    m = _mapping(motion.skeleton, skeleton, name_map)
    R = np.where((m >= 0)[:, None], motion.local_rotations[:, np.maximum(m, 0)], quat_identity())
    return Motion(skeleton, R, motion.root_positions, motion.frame_time,
                  channels=default_channels(skeleton), name=f"{motion.name}_copied")


# --------------------------------------------------------------------------- comparison
@dataclass(frozen=True)
class BoneComparison:
    """One bone in both rest poses: from ``parent`` to ``joint`` (target names)."""

    joint: str
    parent: str
    source_joint: str
    direction_source: tuple[float, float, float]
    direction_target: tuple[float, float, float]
    angle_degrees: float
    length_source: float
    length_target: float


class RestComparison(tuple[BoneComparison, ...]):
    """The bones of two rest poses side by side; ``print`` it for a table."""

    def __str__(self) -> str:
        head = (f"{'bone (target)':<38} {'source joint':<18} {'dir source':>20} "
                f"{'dir target':>20} {'angle':>7} {'len source':>10} {'len target':>10}")
        lines = [head, "-" * len(head)]
        for b in self:
            # round(., 2) + 0.0: no "-0.00", the table prints the same on every machine
            ds = "({:5.2f},{:5.2f},{:5.2f})".format(*(round(v, 2) + 0.0 for v in
                                                      b.direction_source))
            dt = "({:5.2f},{:5.2f},{:5.2f})".format(*(round(v, 2) + 0.0 for v in
                                                      b.direction_target))
            lines.append(
                f"{b.parent + ' -> ' + b.joint:<38} {b.source_joint:<18} {ds:>20} {dt:>20} "
                f"{b.angle_degrees:6.1f}° {b.length_source:10.2f} {b.length_target:10.2f}"
            )
        return "\n".join(lines)


def compare_rest_poses(
    source: Skeleton, target: Skeleton, name_map: Mapping[str, str] | None = None
) -> RestComparison:
    """Each mapped, non-zero bone of ``target`` beside the source's: directions, the angle
    between them (degrees) and both lengths. Bones run from a mapped joint's nearest mapped
    ancestor to it."""
    m = _mapping(source, target, name_map)
    P_t, P_s = target.rest_positions(), source.rest_positions()
    rows = []
    for i in range(1, target.n_joints):
        if m[i] < 0:
            continue
        a = _mapped_ancestor(target.parents, m, i)
        d_t, d_s = P_t[i] - P_t[a], P_s[m[i]] - P_s[m[a]]
        n_t, n_s = float(np.linalg.norm(d_t)), float(np.linalg.norm(d_s))
        if min(n_t, n_s) <= _ZERO_BONE:
            continue
        u_t, u_s = d_t / n_t, d_s / n_s
        angle = np.degrees(np.arctan2(np.linalg.norm(np.cross(u_s, u_t)), u_s @ u_t))
        rows.append(BoneComparison(
            target.names[i], target.names[a], source.names[m[i]], tuple(u_s.round(12)),
            tuple(u_t.round(12)), float(angle), n_s, n_t,
        ))
    return RestComparison(rows)


def bone_direction_errors(
    source: Motion, target: Motion, name_map: Mapping[str, str] | None = None
) -> Array:
    """Angle in degrees, per frame and compared bone, between the two clips' global bone
    directions, shape (F, B) for the bones of :func:`compare_rest_poses` (same order).

    Raises
    ------
    ValueError
        If the clips' frame counts differ, the map is bad (as in :func:`retarget`), or no
        bone can be compared (no mapped joint below another with a non-zero bone in both).
    """
    if source.n_frames != target.n_frames:
        raise ValueError(f"target: has {target.n_frames} frames, source has {source.n_frames}")
    m = _mapping(source.skeleton, target.skeleton, name_map)
    P_s, _ = source.forward_kinematics()
    P_t, _ = target.forward_kinematics()
    pairs = [
        (i, _mapped_ancestor(target.skeleton.parents, m, i))
        for i in range(1, target.n_joints) if m[i] >= 0
    ]
    rest_t, rest_s = target.skeleton.rest_positions(), source.skeleton.rest_positions()
    pairs = [(i, a) for i, a in pairs
             if min(np.linalg.norm(rest_t[i] - rest_t[a]),
                    np.linalg.norm(rest_s[m[i]] - rest_s[m[a]])) > _ZERO_BONE]
    if not pairs:
        mapped = [target.skeleton.names[j] for j in np.flatnonzero(m >= 0)]
        raise ValueError(f"name_map: no bone to compare: no mapped target joint lies below "
                         f"another with a bone of non-zero length in both skeletons (mapped: "
                         f"{mapped})")
    i, a = (np.array(x, dtype=int) for x in zip(*pairs, strict=True))
    d_t = P_t[:, i] - P_t[:, a]
    d_s = P_s[:, m[i]] - P_s[:, m[a]]
    cross = np.linalg.norm(np.cross(d_s, d_t), axis=-1)
    angle: Array = np.degrees(np.arctan2(cross, np.einsum("...i,...i->...", d_s, d_t)))
    return angle
