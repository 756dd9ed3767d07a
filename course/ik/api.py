"""``solve``: one entry point for every IK method, on any skeleton, rooted at any joint."""

from __future__ import annotations

import math
import weakref
from collections.abc import Mapping
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from course import fk
from course.rotations import matrix_from_quat, quat_from_matrix
from course.rotations._checks import as_array

from . import ccd, fabrik, jacobian
from ._chains import ChainModel, Problem, build_model
from ._ops import ARRAYS, FLOATS
from ._serial import (
    SerialChain,
    serial_chain,
    solve_ccd,
    solve_fabrik,
    solve_fabrik_joints,
    solve_jacobian,
    units_like,
)
from ._small import TINY, best_rotation, cross, dot, matvec, norm, orthonormalize
from .result import History, IKResult, Target
from .two_link import two_link

Array = NDArray[np.float64]

# Serial chains take the lean path of course.ik._serial (tests switch it off to compare).
_FAST_PATH = True

METHODS = ("two_link", "ccd", "fabrik", "jacobian_transpose", "pseudo_inverse", "dls")
# Iteration budgets: Jacobian transpose converges linearly and slowly near the target.
DEFAULT_MAX_ITER = {"two_link": 1, "ccd": 200, "fabrik": 200, "jacobian_transpose": 2000,
                    "pseudo_inverse": 100, "dls": 100}


def solve(
    skeleton: Any,
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
    (:func:`course.ik._chains.bend_increment`, 0.05 rad), so ``frames[0]`` and
    ``residuals[0]`` are those of the bent start.

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
        :class:`Target` (``Target(None, q)``: an orientation alone). Orientation targets need
        a Jacobian method.
    method : {"two_link", "ccd", "fabrik", "jacobian_transpose", "pseudo_inverse", "dls"}
    root : joint name or index, optional
        The joint that stays fixed; default joint 0.
    tol : float
        Convergence: every effector within ``tol`` (orientations within ``tol`` radians).
    max_iter : int, optional
        Default per method (:data:`DEFAULT_MAX_ITER`).
    weights : mapping joint -> float, optional
        Jacobian methods: the regulariser :math:`W` (larger: the joint moves less).
    limits : mapping joint -> (lo, hi) or float, optional
        Hinge angle range in radians, or the largest rotation angle of a ball joint's local
        rotation (swing and twist together: the bone stays in a cone of that half-angle about
        its rest direction, and its twist is capped as well). Enforced by projection after
        each step (CCD, Jacobian) or joint placement (FABRIK, two-link).
    record : bool
        Keep every iteration's pose in ``result.frames``.
    **options
        ``damping`` (DLS :math:`\lambda`, a finite length >= 0), ``rcond`` (pseudo-inverse
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
        ``max_iter`` out of range; non-finite or badly shaped input, a zero quaternion; a
        two-link solve whose path is not two bones.
    """
    if method not in METHODS:
        raise ValueError(f"method: expected one of {METHODS}, got {method!r}")
    _check_options(method, options)
    if options.get("max_angle") == math.inf:  # no cap
        options["max_angle"] = None
    if not (_is_number(tol) and math.isfinite(tol) and tol > 0):
        raise ValueError(f"tol: expected a positive number, got {tol!r}")
    if max_iter is None:
        max_iter = DEFAULT_MAX_ITER[method]
    elif (isinstance(max_iter, bool) or not isinstance(max_iter, int | np.integer)
          or max_iter < 0):
        raise ValueError(f"max_iter: expected a whole number >= 0, got {max_iter!r}")
    J = skeleton.n_joints
    local = as_array(local_rotations, "local_rotations", (4,))
    if local.ndim not in (2, 3) or local.shape[-2] != J:
        raise ValueError(f"local_rotations: expected shape ([B,] {J}, 4), got {local.shape}")
    qn2 = (local * local).sum(-1)
    if qn2.min() < 1e-24:
        raise ValueError("local_rotations: contains a zero quaternion, which is no rotation")
    local = local / np.sqrt(qn2)[..., None]
    root_pos = as_array(root_position, "root_position", (3,))
    if root_pos.ndim > 2:
        raise ValueError(f"root_position: expected shape ([B,] 3), got {root_pos.shape}")
    k = 0 if root is None else skeleton.index(root)

    if not isinstance(targets, Mapping) or not targets:
        raise ValueError("targets: expected a non-empty mapping joint -> target")
    pos_t, rot_t = {}, {}
    for key, value in targets.items():
        j = skeleton.index(key)
        name = f"targets[{key!r}]"
        position, orientation = _split_target(value)
        if position is not None:
            pos_t[j] = as_array(position, f"{name} position", (3,))
        if orientation is not None:
            q = as_array(orientation, f"{name} orientation", (4,))
            if np.min(np.einsum("...i,...i->...", q, q)) < 1e-24:
                raise ValueError(f"{name} orientation: the zero quaternion is no rotation")
            rot_t[j] = q
    if rot_t and method not in jacobian.METHODS:
        raise ValueError(f"targets: orientation targets need a Jacobian method, not {method!r}")
    if k in pos_t or k in rot_t:
        raise ValueError(f"root: joint {skeleton.names[k]!r} is fixed, it cannot also be a target")

    leading = [local.shape[:-2], root_pos.shape[:-1]]
    leading += [a.shape[:-1] for a in (*pos_t.values(), *rot_t.values())]
    shape = np.broadcast_shapes(*leading) if any(leading) else ()
    if len(shape) > 1:
        raise ValueError(f"targets: leading shapes {shape} do not broadcast to one batch axis")
    batched = len(shape) == 1
    B = shape[0] if batched else 1

    model, serial = _model(skeleton, k, tuple(pos_t), tuple(rot_t))
    col_weight = _weights(skeleton, model, weights)
    max_iter = int(max_iter)
    if _FAST_PATH and serial is not None and method != "two_link":
        (j,) = pos_t
        return _result(*_solve_serial(
            skeleton, serial, model, local, root_pos, k, pos_t[j], B, batched, method, tol,
            max_iter, col_weight,
            serial.limits(*_limits(skeleton, model, limits)) if limits else [], record,
            **options), method)
    hinge_limits, ball_limit = _limits(skeleton, model, limits)

    local_b = np.broadcast_to(local, (B, J, 4)).copy()
    root_b = np.broadcast_to(root_pos, (B, 3)).copy()
    if k == 0:  # the world frame is held and joint 0 sits at the root position
        base, p_k, Q_k = np.broadcast_to(np.eye(3), (B, 3, 3)), root_b, None
    else:
        positions, orientations = fk.forward_kinematics(skeleton.parents, skeleton.offsets,
                                                        local_b, root_b)
        p_k, Q_k = positions[:, k], orientations[:, k]
        base = matrix_from_quat(orientations[:, skeleton.parents[k]] if model.anchor_parent
                                else Q_k)
    Rn = np.broadcast_to(np.eye(3), (B, model.n_nodes, 3, 3)).copy()
    has = model.edge_joint >= 0
    Rn[:, has] = matrix_from_quat(local_b[:, model.edge_joint[has]])
    problem = Problem(
        model=model, Rn=Rn, base=base, p0=p_k,
        target_pos=np.stack([np.broadcast_to(pos_t[j], (B, 3)) for j in pos_t], 1)
        if pos_t else np.zeros((B, 0, 3)),
        target_rot=np.stack([matrix_from_quat(np.broadcast_to(rot_t[j], (B, 4))) for j in rot_t],
                            1) if rot_t else np.zeros((B, 0, 3, 3)),
        col_weight=col_weight, hinge_limits=hinge_limits, ball_limit=ball_limit,
    )
    problem.Rn = problem.project(problem.Rn)
    if method != "two_link":
        problem.Rn = problem.bend_if_straight(problem.Rn, tol)

    if method == "two_link":
        Rn_out, history, frames = _two_link(problem, tol, record, **options)
    elif method == "ccd":
        Rn_out, history, frames = ccd.solve_problem(problem, tol, max_iter, record=record,
                                                    **options)
    elif method == "fabrik":
        Rn_out, history, frames = fabrik.solve_problem(problem, tol, max_iter, record=record)
    else:
        Rn_out, history, frames = jacobian.solve_problem(problem, method, tol, max_iter,
                                                         record=record, **options)

    pose = _pose(skeleton, model, local_b, root_b, Q_k, p_k, Rn_out)
    recorded = []
    if record:
        T = len(frames)
        stacked = _pose(skeleton, model, np.tile(local_b, (T, 1, 1)), np.tile(root_b, (T, 1)),
                        None if Q_k is None else np.tile(Q_k, (T, 1)), np.tile(p_k, (T, 1)),
                        np.concatenate(frames, 0))
        recorded = [(stacked[0][t * B:(t + 1) * B], stacked[2][t * B:(t + 1) * B])
                    for t in range(T)]
    unreachable = problem.unreachable() if len(model.effectors) else np.zeros(B, bool)
    if not batched:  # one problem, solved as a batch of one
        pose = [a[0] for a in pose]
        recorded = [(q[0], p[0]) for q, p in recorded]
        unreachable = unreachable[0]
        history.unbatch()
    return _result(*pose, history, unreachable, recorded if record else None, method)


# The options each method takes, and the values they accept: (test, what it must be).
OPTIONS: dict[str, dict[str, tuple[Any, str]]] = {
    "two_link": {"pole": (None, ""), "flip": (None, "")},
    "ccd": {"tip_to_root": (None, ""),
            "max_angle": (lambda x: x > 0, "a positive angle in radians (inf: no cap)")},
    "fabrik": {},
    **dict.fromkeys(jacobian.METHODS, {
        "damping": (lambda x: x >= 0 and math.isfinite(x), "a finite length >= 0"),
        "rcond": (lambda x: 0 <= x < 1, "a number in [0, 1)"),
        "max_step": (lambda x: x > 0, "a positive angle in radians (inf: no cap)"),
    }),
}


_NUMBER = (int, float, np.integer, np.floating)  # a tuple: ``int | float`` is built per call


def _is_number(x: Any) -> bool:
    return isinstance(x, _NUMBER) and not isinstance(x, bool)


def _check_options(method: str, options: Mapping[str, Any]) -> None:
    """``ValueError`` naming an option the method does not take or a value it cannot use
    (NaN fails every test; ``None`` means the default)."""
    allowed = OPTIONS[method]
    unknown = set(options) - set(allowed)
    if unknown:
        raise ValueError(f"options: {sorted(unknown)} do not apply to method {method!r} "
                         f"(it takes {sorted(allowed) or 'none'})")
    for name, value in options.items():
        test, what = allowed[name]
        if test is not None and value is not None and not (_is_number(value) and test(value)):
            raise ValueError(f"{name}: expected {what}, got {value!r}")


def _result(local: Array, root_pos: Array, positions: Array, history: History,
            unreachable: Any, frames: list[tuple[Array, Array]] | None,
            method: str) -> IKResult:
    """The :class:`IKResult` of one problem (arrays without a batch axis, a history of floats)
    or of a batch (arrays (B, ...)); ``frames`` are (local, positions)."""
    return IKResult(
        local_rotations=local,
        root_position=root_pos,
        positions=positions,
        converged=history.converged,
        iterations=history.iterations,
        residuals=np.array(history.residuals),
        reason=history.reasons(unreachable),
        method=method,
        frames=None if frames is None else [{"positions": p, "local_rotations": q}
                                            for q, p in frames],
    )


def _split_target(value: Any) -> tuple[Any, Any]:
    """``(position, orientation)`` of a target given as Target, pair or position."""
    if isinstance(value, Target):
        return value.position, value.orientation
    if isinstance(value, tuple) and len(value) == 2 and np.shape(value[1])[-1:] == (4,):
        return value
    return value, None


@lru_cache(maxsize=128)
def _cached_model(parents: tuple, offsets: bytes, kinds: tuple, root: int, eff: tuple,
                  reff: tuple) -> tuple[ChainModel, SerialChain | None]:
    off = np.frombuffer(offsets).reshape(-1, 3)
    model = build_model(np.array(parents), off, list(kinds), root, list(eff), list(reff))
    return model, serial_chain(model)


# Per skeleton object (read-only: its offsets cannot be written), the models of the paths
# solved on it: a slider calls ``solve`` with the same skeleton over and over.
_MODELS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _model(skeleton: Any, root: int, eff: tuple,
           reff: tuple) -> tuple[ChainModel, SerialChain | None]:
    """The (cached) model, and its serial chain if it is one."""
    try:
        per_skeleton = _MODELS.setdefault(skeleton, {})
    except TypeError:  # not weakly referenceable: look up by value only
        per_skeleton = {}
    key = (root, eff, reff)
    if key not in per_skeleton:
        per_skeleton[key] = _model_by_value(skeleton, root, eff, reff)
    return per_skeleton[key]


def _model_by_value(skeleton: Any, root: int, eff: tuple,
                    reff: tuple) -> tuple[ChainModel, SerialChain | None]:
    kinds = []
    for t in skeleton.joint_types:
        axis = getattr(t, "axis", None)
        kinds.append(tuple(axis) if axis is not None else (False if t.dof == 0 else None))
    return _cached_model(tuple(int(p) for p in skeleton.parents),
                         np.ascontiguousarray(skeleton.offsets, float).tobytes(), tuple(kinds),
                         root, eff, reff)


def _weights(skeleton: Any, model: ChainModel, weights: Mapping | None) -> Array:
    if not weights:
        return model.unit_weights
    w = np.ones(model.n_cols)
    for key, value in (weights or {}).items():
        j = skeleton.index(key)
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"weights[{key!r}]: expected a positive number, got {value!r}")
        w[model.edge_joint[model.var_nodes[model.col_var]] == j] = value
    return w


def _limits(skeleton: Any, m: ChainModel, limits: Mapping | None) -> tuple[Array, Array]:
    """Hinge ranges (V, 2) and ball caps (V,) of the variables (``±inf`` / ``inf``: free)."""
    hinge_limits = np.full((len(m.var_nodes), 2), [-np.inf, np.inf])
    ball_limit = np.full(len(m.var_nodes), np.inf)
    var_joint = m.edge_joint[m.var_nodes]
    for key, value in (limits or {}).items():
        j = skeleton.index(key)
        hinge = getattr(skeleton.joint_types[j], "axis", None) is not None
        v = np.flatnonzero(var_joint == j)
        if hinge:
            lo, hi = (float(x) for x in np.broadcast_to(np.asarray(value, float), (2,)))
            if not lo <= hi:
                raise ValueError(f"limits[{key!r}]: a hinge range needs lo <= hi, got {value!r}")
            hinge_limits[v] = (lo, hi)
        else:
            if np.ndim(value) != 0 or not value >= 0:
                raise ValueError(f"limits[{key!r}]: a ball joint takes one largest angle "
                                 f"(radians, >= 0), got {value!r}")
            ball_limit[v] = float(value)
    return hinge_limits, ball_limit


def _pose(skeleton: Any, model: ChainModel, local: Array, root_pos: Array, Qk: Array | None,
          pk: Array, Rn: Array) -> tuple[Array, Array, Array]:
    """Local rotations, root position and global positions of solved edge rotations."""
    local = local.copy()
    joints = model.edge_joint[model.var_nodes]
    q = quat_from_matrix(Rn[:, model.var_nodes])
    # Keep the sign of the starting quaternion, so an animated solve has no sign flips.
    flip = np.einsum("bji,bji->bj", q, local[:, joints]) < 0
    local[:, joints] = np.where(flip[..., None], -q, q)
    if model.anchor_parent:
        if model.n_nodes == len(local[0]) and model.joints[0] == 0:
            # The paths cover the skeleton (a chain): the model's own FK has every position.
            _, p = model.forward(Rn, np.broadcast_to(np.eye(3), Rn.shape[:1] + (3, 3)), root_pos)
            positions = np.empty_like(p)
            positions[:, model.joints] = p
        else:
            positions, _ = fk.forward_kinematics(skeleton.parents, skeleton.offsets, local,
                                                 root_pos)
        return local, root_pos, positions
    k = int(model.joints[0])
    positions, orientations = fk.forward_kinematics(
        skeleton.parents, skeleton.offsets, local, pk, root=k, root_orientation=Qk)
    local[:, 0] = orientations[:, 0]
    return local, positions[:, 0].copy(), positions


def _two_link(problem: Problem, tol: float, record: bool, pole: ArrayLike | None = None,
              flip: bool = False) -> tuple[Array, History, list[Array]]:
    m = problem.model
    if m.n_nodes != 3 or len(m.effectors) != 1 or m.effectors[0] != 2:
        raise ValueError(
            "method: 'two_link' needs the path from root to the one effector to be two bones "
            f"(three joints), got {m.n_nodes} joints; choose root accordingly")
    M, p = problem.forward(problem.Rn)
    history = History(problem.error(M, p)[1], tol, 1)
    t = problem.target_pos[:, 0]
    hip = np.flatnonzero(m.var_nodes == 0)
    knee = np.flatnonzero(m.var_nodes == 1)
    if not m.up.any() and len(hip) and len(knee) and not m.hinge[hip[0]] and m.hinge[knee[0]]:
        Rn, b, c = _two_link_hinge_knee(problem, M, p, t, problem._axes()[knee[0]], pole, flip)
    else:
        Rn = problem.Rn
        b, c, _ = two_link(p[:, 0], p[:, 1], p[:, 2], t, pole, flip)
    Rn = problem.fit(Rn, np.stack([p[:, 0], b, c], 1))
    history.update(problem.error(*problem.forward(Rn))[1])
    return Rn, history, [problem.Rn, Rn] if record else []


def _two_link_hinge_knee(problem: Problem, M: Array, p: Array, t: Array, knee_axis: Array,
                         pole: ArrayLike | None, flip: bool) -> tuple[Array, Array, Array]:
    r"""Two-link with a ball root and a hinge middle joint (hip and knee): the leg's plane
    must be perpendicular to the knee axis, which turns with the hip. So the plane is chosen
    first: through the root-to-target axis :math:`\hat u` and the pole, or without a pole the
    plane whose normal is nearest the knee's world axis :math:`a = Q_{hip}\hat a` (its part
    perpendicular to :math:`\hat u`, bending to the side the knee bends now). The law of
    cosines places the knee in it (:func:`two_link`), and the hip turns (Kabsch on the two
    directions) so that its bone points at the new knee and the knee axis along the plane's
    normal; the knee's own turn about its axis then lands the end on the target.

    Returns the edge rotations with the hip turned, and the new knee and end positions.
    """
    a, b0, c0 = p[:, 0], p[:, 1], p[:, 2]
    axis = matvec(M[:, 0], knee_axis)
    u = np.where((norm(t - a) > TINY)[:, None], t - a, c0 - a)
    u = u / np.maximum(norm(u), TINY)[:, None]
    if pole is None:
        n = axis - dot(axis, u)[:, None] * u
        side = cross(u, n)  # a knee bent by a positive turn about n has its joint on this side
        bent = b0 - a - dot(b0 - a, u)[:, None] * u
        side = np.where((dot(bent, side) < 0)[:, None], -side, side)
        planar = norm(n) > 1e-9
        pole_pt = np.where(planar[:, None], a + side, b0)  # knee axis along u: keep the plane
    else:
        pole_pt = np.broadcast_to(as_array(pole, "pole", (3,)), a.shape)
    b, c, _ = two_link(a, b0, c0, t, pole_pt, flip)
    n = cross(b - a, c - a)
    n = np.where((norm(n) > TINY)[:, None], n, cross(u, pole_pt - a))
    n = n / np.maximum(norm(n), TINY)[:, None]
    n = np.where((dot(n, axis) < 0)[:, None], -n, n)  # the nearer of the two normals
    turn = best_rotation(np.stack([b0 - a, axis], 1), np.stack([b - a, n * norm(b0 - a)[:, None]],
                                                               1))
    Rn = problem.Rn.copy()
    Rn[:, 0] = orthonormalize(np.swapaxes(problem.base, -1, -2) @ turn @ M[:, 0])
    return problem.project(Rn), b, c


def _solve_serial(
    skeleton: Any, chain: SerialChain, model: ChainModel, local: Array, root_pos: Array, k: int,
    target: Array, B: int, batched: bool, method: str, tol: float, max_iter: int,
    col_weight: Array, limits: list[tuple], record: bool, damping: float | None = None,
    rcond: float = 1e-6, max_step: float = 0.5, tip_to_root: bool = True,
    max_angle: float | None = None,
) -> tuple[Array, Array, Array, History, Any, list[tuple[Array, Array]] | None]:
    """CCD, FABRIK or a Jacobian method on a serial chain (:mod:`course.ik._serial`): one
    problem in Python floats (``local`` (J, 4), ``root_pos`` and ``target`` (3,)), or a batch
    on component arrays. Returns local rotations, root position and positions (with a batch's
    leading ``B``), the history, whether each target is out of reach and the recorded
    (local, positions) frames."""
    ops = ARRAYS if batched else FLOATS
    joints = list(chain.joints)
    if batched:
        local = np.broadcast_to(local, (B, skeleton.n_joints, 4))
        root_pos = np.broadcast_to(root_pos, (B, 3))
    if k == 0:  # the world frame is held and joint 0 sits at the root position
        base, p0 = (1.0, 0.0, 0.0, 0.0), _components(root_pos, ops)
    else:
        positions, orientations = fk.forward_kinematics(skeleton.parents, skeleton.offsets,
                                                        local, root_pos)
        base = _components(orientations[..., skeleton.parents[k], :], ops)
        p0 = _components(positions[..., k, :], ops)
    if ops is FLOATS:
        rows = local.tolist()
        start = [tuple(rows[j]) for j in joints]
        target = tuple(target.tolist())
    else:
        start = [_components(local[:, j], ops) for j in joints]
        target = _components(np.broadcast_to(target, (B, 3)), ops)
    R = start
    if limits:
        R = chain.project(R, limits, ops)
    if method == "fabrik" and chain.free_balls and not limits:  # positions alone suffice
        R, P, history, frames = solve_fabrik(chain, R, base, p0, target, tol, max_iter, record,
                                             ops)
    elif method == "fabrik":
        R, P, history, frames = solve_fabrik_joints(chain, R, base, p0, target, tol, max_iter,
                                                    limits, record, ops)
    elif method == "ccd":
        R, P, history, frames = solve_ccd(chain, R, base, p0, target, tol, max_iter,
                                          tip_to_root=tip_to_root, max_angle=max_angle,
                                          limits=limits, record=record, ops=ops)
    else:
        if damping is None:
            damping = jacobian.DEFAULT_DAMPING * model.length_scale
        R, P, history, frames = solve_jacobian(
            chain, R, base, p0, target, method, tol, max_iter,
            inv_w2=tuple((1.0 / col_weight**2).tolist()), damping=damping, rcond=rcond,
            max_step=max_step, limits=limits, record=record, ops=ops)

    covers = chain.joints == tuple(range(skeleton.n_joints))  # a chain skeleton: its own FK

    def pose(R: list, P: list | None = None) -> tuple[Array, Array]:
        """Local rotations (unit, in the starting quaternions' signs) and positions of ``R``;
        ``P``, if given, are the chain's positions of ``R`` already computed."""
        q = ops.stack(units_like(R, start, ops), B)
        if covers:  # every joint is on the chain
            return q, ops.stack(chain.forward(R, base, p0)[1] if P is None else P, B)
        out = local.copy()
        out[..., joints, :] = q
        return out, fk.forward_kinematics(skeleton.parents, skeleton.offsets, out, root_pos)[0]

    local_out, positions = pose(R, P)
    recorded = [pose(f) for f in frames] if record else None
    unreachable = chain.unreachable(target, p0, ops)
    return local_out, root_pos.copy(), positions, history, unreachable, recorded


def _components(a: Array, ops: Any) -> tuple:
    """(c,) -> c floats for one problem; (B, c) -> c contiguous (B,) rows for a batch."""
    if ops is FLOATS:
        return tuple(a.tolist())
    return tuple(np.ascontiguousarray(a.T))
