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
from course.rotations._checks import as_array, broadcast_leading

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
from ._small import (
    TINY,
    best_rotation,
    cross,
    dot,
    matvec,
    norm,
    orthonormalize,
    rotvec_matrix,
)
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
        Hinge angle range in radians (one angle ``a``: the range ``(-a, a)``), or the
        largest rotation angle of a ball joint's local
        rotation (swing and twist together: the bone stays in a cone of that half-angle about
        its rest direction, and its twist is capped as well). Enforced by projection after
        each step (CCD, Jacobian) or joint placement (FABRIK, two-link).
    record : bool
        Keep every iteration's pose in ``result.frames``.
    **options
        ``damping`` (DLS :math:`\lambda`, a length in [0, 1e50]), ``rcond`` (pseudo-inverse
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
        ``max_iter`` out of range; non-finite, huge (beyond :data:`LARGEST_COORDINATE`) or
        badly shaped input, a zero quaternion; a hinge whose start rotation is off its axis;
        an effector no joint on its path can move; a two-link solve whose path is not two
        bones.
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
    if not all(hasattr(skeleton, a) for a in ("n_joints", "parents", "offsets", "joint_types",
                                                "index")):
        raise ValueError(f"skeleton: expected a course.skeleton.Skeleton, got "
                         f"{type(skeleton).__name__}")
    J = skeleton.n_joints
    local = as_array(local_rotations, "local_rotations", (4,))
    if local.ndim not in (2, 3) or local.shape[-2] != J:
        raise ValueError(f"local_rotations: expected shape ([B,] {J}, 4), got {local.shape}")
    big = np.abs(local).max(-1, keepdims=True)  # scaled first: the squares of 1e155 overflow
    qn = big * np.linalg.norm(local / np.where(big > 0, big, 1.0), axis=-1, keepdims=True)
    if qn.min() < 1e-12:
        raise ValueError("local_rotations: contains a zero quaternion, which is no rotation")
    local = local / qn
    root_pos = _position(root_position, "root_position")
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
        if position is None and orientation is None:
            raise ValueError(f"{name}: expected a position (3,) or ([B,] 3), a pair (position, "
                             f"quaternion) or a Target, got {value!r}")
        if position is not None:
            pos_t[j] = _position(position, f"{name} position")
        if orientation is not None:
            q = as_array(orientation, f"{name} orientation", (4,))
            if np.min(np.einsum("...i,...i->...", q, q)) < 1e-24:
                raise ValueError(f"{name} orientation: the zero quaternion is no rotation")
            rot_t[j] = q
    if rot_t and method not in jacobian.METHODS:
        raise ValueError(f"targets: orientation targets need a Jacobian method, not {method!r}")
    if k in pos_t or k in rot_t:
        raise ValueError(f"root: joint {skeleton.names[k]!r} is fixed, it cannot also be a target")

    shape = broadcast_leading(
        "targets", ("local_rotations", local, 2), ("root_position", root_pos, 1),
        *((f"targets[{skeleton.names[j]!r}] position", a, 1) for j, a in pos_t.items()),
        *((f"targets[{skeleton.names[j]!r}] orientation", a, 1) for j, a in rot_t.items()))
    if len(shape) > 1:
        raise ValueError(f"targets: leading shapes {shape} do not broadcast to one batch axis")
    batched = len(shape) == 1
    B = shape[0] if batched else 1

    model, serial = _model(skeleton, k, tuple(pos_t), tuple(rot_t))
    _check_movable(skeleton, model, k)
    _check_hinges(skeleton, model, local)
    col_weight = _weights(skeleton, model, weights)
    max_iter = int(max_iter)
    if _FAST_PATH and serial is not None and method != "two_link":
        (target,) = pos_t.values()
        lims = serial.limits(*_limits(skeleton, model, limits)) if limits else []
        if not batched or B >= _batch_from(method, serial, lims):
            return _result(*_solve_serial(
                skeleton, serial, model, local, root_pos, k, target, B, batched, method, tol,
                max_iter, col_weight, lims, record, **options), method)
        # A small batch: one problem at a time in floats is faster (see _BATCH_FROM).
        rows = zip(np.broadcast_to(local, (B, J, 4)), np.broadcast_to(root_pos, (B, 3)),
                   np.broadcast_to(target, (B, 3)), strict=True)
        return _stack([_result(*_solve_serial(
            skeleton, serial, model, q, r, k, t, 1, False, method, tol, max_iter, col_weight,
            lims, record, **options), method) for q, r, t in rows])
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
        if serial is not None and serial.free_balls and not limits:
            problem.Rn = problem.stretch_if_far(problem.Rn, tol)
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


# Batches on the serial fast path smaller than this solve one problem at a time in Python
# floats: the array engine pays a numpy call per component and step (~1 us, against ~50 ns
# for a float), and for as many iterations as the batch's slowest problem needs. Crossovers
# measured on the 7-bone chains of benchmarks/ik.py; the transpose method's slowest problems
# take thousands of iterations, so its batches are never faster than its single solves.
_BATCH_FROM = {"ccd": 256, "fabrik": 256, "fabrik_points": 64, "jacobian_transpose": math.inf,
               "pseudo_inverse": 48, "dls": 48}


def _batch_from(method: str, serial: SerialChain, limits: list) -> float:
    """The smallest batch the array engine solves faster than a loop of single solves
    (FABRIK on free balls iterates on points alone, a cheaper engine)."""
    if method == "fabrik" and serial.free_balls and not limits:
        return _BATCH_FROM["fabrik_points"]
    return _BATCH_FROM[method]


def _stack(results: list[IKResult]) -> IKResult:
    """One batch result from single ones: arrays (B, ...), residuals (T, B) and frames with
    every problem held at its last entry once it has stopped (as the array engine does)."""
    residuals = np.empty((max(len(r.residuals) for r in results), len(results)))
    for i, r in enumerate(results):
        residuals[:len(r.residuals), i] = r.residuals
        residuals[len(r.residuals):, i] = r.error
    frames = None
    if results[0].frames is not None:
        F = max(len(r.frames) for r in results)
        frames = [{key: np.stack([r.frames[min(t, len(r.frames) - 1)][key] for r in results])
                   for key in ("positions", "local_rotations")} for t in range(F)]
    return IKResult(
        local_rotations=np.stack([r.local_rotations for r in results]),
        root_position=np.stack([r.root_position for r in results]),
        positions=np.stack([r.positions for r in results]),
        converged=np.array([r.converged for r in results]),
        iterations=np.array([r.iterations for r in results]),
        residuals=residuals,
        reason=np.array([r.reason for r in results], dtype="<U14"),
        method=results[0].method,
        frames=frames,
    )


# The options each method takes, and the values they accept: (test, what it must be).
OPTIONS: dict[str, dict[str, tuple[Any, str]]] = {
    "two_link": {"pole": (None, ""), "flip": (None, "")},
    "ccd": {"tip_to_root": (None, ""),
            "max_angle": (lambda x: x > 0, "a positive angle in radians (inf: no cap)")},
    "fabrik": {},
    **dict.fromkeys(jacobian.METHODS, {
        # Its sixth power is a determinant in the closed-form step: beyond 1e50 it overflows.
        "damping": (lambda x: 0 <= x <= 1e50, "a length in [0, 1e50]"),
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


def _check_movable(skeleton: Any, model: ChainModel, root: int) -> None:
    """``ValueError`` naming an effector that no joint between it and the fixed joint can
    move (all fixed, or only its own rotation free, which turns it in place)."""
    stuck = [e for nodes, mask in ((model.effectors, model.pos_mask),
                                   (model.rot_effectors, model.rot_mask))
             for e, row in zip(nodes, mask, strict=True) if not row.any()]
    if stuck:
        name = skeleton.names[int(model.joints[stuck[0]])]
        raise ValueError(
            f"targets[{name!r}]: no joint between it and the fixed joint "
            f"{skeleton.names[root]!r} can move it (they are Fixed, or turn it in place); "
            "free one of them or choose another root")


# Positions beyond this size cannot be solved in double precision: squared distances and the
# solvers' products of errors overflow (a target of 1e155 gave an infinite residual).
LARGEST_COORDINATE = 1e100


def _position(x: Any, name: str) -> Array:
    """A position ``([B,] 3)`` checked by ``as_array`` and refused beyond
    :data:`LARGEST_COORDINATE`."""
    a = as_array(x, name, (3,))
    if a.size and np.abs(a).max() > LARGEST_COORDINATE:
        raise ValueError(f"{name}: coordinates up to {LARGEST_COORDINATE:g} can be solved "
                         f"(their squares must not overflow), got {np.abs(a).max():g}")
    return a


def _check_hinges(skeleton: Any, model: ChainModel, local: Array) -> None:
    """``ValueError`` naming a hinge the solve moves whose start rotation is not a turn about
    its own axis (a hinge solve keeps the off-axis part, so the answer would depend on how
    the problem was batched)."""
    for v in np.flatnonzero(model.hinge):
        j = int(model.edge_joint[model.var_nodes[v]])
        axis = np.asarray(skeleton.joint_types[j].axis)
        vec = local[..., j, 1:]
        off = np.linalg.norm(vec - (vec @ axis)[..., None] * axis, axis=-1)
        if off.max() > 1e-6:
            where = f" (problem {int(np.argmax(off))})" if off.ndim else ""
            raise ValueError(
                f"local_rotations: joint {skeleton.names[j]!r} is a hinge about {axis.tolist()} "
                f"but its start rotation{where} turns "
                f"{2 * np.arcsin(min(1.0, float(off.max()))):.3g} rad about another axis; "
                "give a turn about the hinge axis (quat_from_axis_angle(axis, angle))")


def _weights(skeleton: Any, model: ChainModel, weights: Mapping | None) -> Array:
    if not weights:
        return model.unit_weights
    w = np.ones(model.n_cols)
    for key, value in (weights or {}).items():
        j = skeleton.index(key)
        if not (_is_number(value) and math.isfinite(value) and value > 0):
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
        a = np.asarray(value) if not isinstance(value, str) else None
        ok = a is not None and a.dtype.kind in "iuf" and not np.isnan(a).any()
        if hinge:
            if not (ok and a.shape in ((), (2,))):
                raise ValueError(f"limits[{key!r}]: a hinge takes a range (lo, hi) or one angle "
                                 f"a >= 0 for (-a, a), radians, got {value!r}")
            lo, hi = (-float(a), float(a)) if a.ndim == 0 else (float(a[0]), float(a[1]))
            if not lo <= hi:
                raise ValueError(f"limits[{key!r}]: a hinge range needs lo <= hi (one angle: "
                                 f">= 0), got {value!r}")
            hinge_limits[v] = (lo, hi)
        else:
            if not (ok and a.ndim == 0 and a >= 0):
                raise ValueError(f"limits[{key!r}]: a ball joint takes one largest angle "
                                 f"(radians, >= 0), got {value!r}")
            ball_limit[v] = float(a)
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
    """The analytic two-bone solve; a start already within ``tol`` is kept (0 iterations),
    and a target the joints cannot reach (out of reach, off a hinge's plane) ends in their
    closest pose, reported ``"unreachable"`` or ``"stalled"`` (never ``"max_iterations"``:
    there is nothing to iterate)."""
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
    axes = problem._axes()
    both = bool(not m.up.any() and len(hip) and len(knee))
    if both and m.hinge[hip[0]]:
        Rn = _two_link_hinge_hip(problem, p, t, axes[hip[0]],
                                 axes[knee[0]] if m.hinge[knee[0]] else None, pole, flip)
        b = problem.forward(Rn)[1][:, 1]
    elif both and m.hinge[knee[0]]:
        Rn, b, _ = _two_link_hinge_knee(problem, M, p, t, axes[knee[0]], pole, flip)
    else:
        Rn = problem.Rn
        b, _, _ = two_link(p[:, 0], p[:, 1], p[:, 2], t, pole, flip)
    # With both joints free each aims at its own point (exact: no least-squares compromise).
    Rn = problem.fit(Rn, np.stack([p[:, 0], b, t], 1), subtree=not both)
    if not history.active.any():  # every start within tolerance already: nothing to do
        return problem.Rn, history, [problem.Rn] if record else []
    Rn = np.where(history.active[:, None, None, None], Rn, problem.Rn)
    history.update(problem.error(*problem.forward(Rn))[1])
    history.stalled = ~history.converged
    return Rn, history, [problem.Rn, Rn] if record else []


def _two_link_hinge_hip(problem: Problem, p: Array, t: Array, hip_axis: Array,
                        knee_axis: Array | None, pole: ArrayLike | None,
                        flip: bool) -> Array:
    r"""Two-link with a hinge root (the textbook arm): the hip can only swing the knee on the
    circle :math:`b(\theta) = a + \exp(\theta[\hat a]_\times)(b_0 - a)` about its world axis
    :math:`\hat a`, so the law of cosines becomes one equation in :math:`\theta`. With
    :math:`v = b(\theta) - a` and :math:`w = t - a`, :math:`\lVert t - b\rVert = l_2` reads
    :math:`v\cdot w = (l_1^2 + d^2 - l_2^2)/2`, and
    :math:`v\cdot w = C + A\cos\theta + B\sin\theta` (:math:`C` the part along the axis), so
    :math:`\theta = \varphi \pm \arccos\frac{K - C}{\sqrt{A^2 + B^2}}`,
    :math:`\varphi = \mathrm{atan2}(B, A)`. When the knee is a hinge parallel to the hip (a
    planar arm) the same holds in the plane: the parts along the axis drop out, so a target
    off the plane gets the pose reaching its projection. Of the two roots (the elbow on
    either side of the line to the target) the one nearer the pole, else the one bending as
    the knee bends now (the smaller turn from a straight start); ``flip`` takes the other.
    Out of reach the cosine is clipped: the arm stretches (or folds) towards the target.

    Returns the edge rotations with the hip turned (and projected into its limits).
    """
    a, b0, c0 = p[:, 0], p[:, 1], p[:, 2]
    ax = matvec(problem.base, hip_axis)
    v, w, bone2 = b0 - a, t - a, c0 - b0
    va, wa = dot(v, ax), dot(w, ax)
    v_perp = v - va[:, None] * ax
    side = cross(ax, v_perp)
    K = 0.5 * (dot(v, v) + dot(w, w) - dot(bone2, bone2)) - va * wa
    if knee_axis is not None and norm(cross(np.asarray(knee_axis), hip_axis)) < 1e-9:
        h = dot(bone2, ax)  # a planar arm: solve in the plane (the axial parts drop out)
        K = K - 0.5 * ((va - wa) ** 2 - h * h)
    A, Bs = dot(v_perp, w), dot(side, w)
    radius = np.hypot(A, Bs)
    scale = problem.model.length_scale
    cos = np.where(radius > 1e-12 * scale * scale, K / np.where(radius > 0, radius, 1.0), 1.0)
    phi = np.arctan2(Bs, A)
    half = np.arccos(np.clip(cos, -1.0, 1.0))
    roots = np.stack([phi - half, phi + half], 1)  # (B, 2)
    roots = (roots + np.pi) % (2 * np.pi) - np.pi
    knees = (a[:, None] + np.cos(roots)[..., None] * v_perp[:, None]
             + np.sin(roots)[..., None] * side[:, None] + va[:, None, None] * ax[:, None])
    if pole is not None:
        pole_pt = np.broadcast_to(as_array(pole, "pole", (3,)), a.shape)
        first = norm(knees[:, 0] - pole_pt) <= norm(knees[:, 1] - pole_pt)
    else:
        now = dot(ax, cross(v, c0 - a))  # which way the knee bends now, about the hip axis
        bend = dot(ax[:, None], cross(knees - a[:, None], w[:, None]))
        straight = np.abs(now) <= 1e-9 * scale * scale
        first = np.where(straight, np.abs(roots[:, 0]) <= np.abs(roots[:, 1]),
                         bend[:, 0] * now >= bend[:, 1] * now)
    theta = np.where(first != flip, roots[:, 0], roots[:, 1])
    Rn = problem.Rn.copy()
    Rn[:, 0] = rotvec_matrix(hip_axis * theta[:, None]) @ Rn[:, 0]
    return problem.project(Rn)


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
    elif chain.free_balls:  # at or beyond the reach: the stretched pose (see stretch_if_far)
        R = chain.stretch_if_far(R, base, p0, target, tol, ops)
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
