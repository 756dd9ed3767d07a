"""The steps of a solve (求解流程, internal): :func:`validate` checks every argument of
:func:`course.ik.solve` against the method's record (:mod:`course.ik.methods`) and builds a
frozen :class:`~course.ik._engine.request.Request`; :func:`run` hands it to an engine (the
serial-chain fast path where the paths are one chain, else the general tree engine) and
builds the :class:`~course.ik.result.IKResult`. :func:`course.ik.solve` and
:func:`course.ik.motion.solve_motion` are written on them.
"""

from __future__ import annotations

import dataclasses
import math
import weakref
from collections.abc import Mapping
from functools import lru_cache
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from course._typing import Array
from course._validate import as_array, broadcast_leading
from course.skeleton import Hinge, Skeleton

from ._engine.chain import SerialChain, as_vec, serial_chain
from ._engine.chain_solvers import solve_on_chain
from ._engine.components import Limit
from ._engine.request import MethodOptions, Request, Solved
from ._engine.tree import JointAxis, TreeModel, build_model
from ._engine.tree_solvers import DEFAULT_DAMPING, solve_on_tree
from .methods import REGISTRY, Method
from .result import IKResult, SwingTwist, Target

# Which engine runs a solve: "auto" (the serial-chain fast path for a chain, small batches one
# problem at a time), "chain" (the fast path for any batch, in arrays) or "tree" (always the
# general engine): ``solve``'s ``engine`` keyword.
Engine = Literal["auto", "chain", "tree"]


def validate(skeleton: Skeleton, local_rotations: ArrayLike, root_position: ArrayLike,
              targets: Any, method: str, root: str | int | None, tol: float,
              max_iter: int | None, weights: Mapping[str | int, Any] | None,
              limits: Mapping[str | int, Any] | None, record: bool, options: Mapping[str, Any],
              reach_start: bool = True) -> Request:
    """Every argument of :func:`solve` checked (``ValueError`` naming the first bad one), as
    the :class:`Request` the engines run."""
    spec = _method(method)
    if not isinstance(reach_start, bool | np.bool_):
        raise ValueError(f"reach_start: expected True or False, got {reach_start!r}")
    checked = _options(spec, options)
    max_iter = _tol_and_max_iter(spec, tol, max_iter)
    _check_skeleton(skeleton)
    local = _start_pose(skeleton, local_rotations)
    root_pos = _position(root_position, "root_position")
    if root_pos.ndim > 2:
        raise ValueError(f"root_position: expected shape ([B,] 3), got {root_pos.shape}")
    k = 0 if root is None else skeleton.index(root)
    pos_t, rot_t, pos_w, rot_w = _targets(skeleton, targets, spec, k)
    B, batched = _batch(skeleton, local, root_pos, pos_t, rot_t)
    model, serial = _model(skeleton, k, tuple(pos_t), tuple(rot_t))
    _check_movable(skeleton, model, k)
    _check_hinges(skeleton, model, local)
    col_weight = _weights(skeleton, model, weights)
    joint_limits = _limits(skeleton, model, limits)
    if spec.weights and checked["damping"] is None:
        checked["damping"] = DEFAULT_DAMPING * model.length_scale
    method_options: MethodOptions = spec.options_record(**checked)
    return Request(skeleton=skeleton, method=method, local=local, root_pos=root_pos, root=k,
                   pos_t=pos_t, rot_t=rot_t, batched=batched, B=B, model=model, serial=serial,
                   col_weight=col_weight, pos_weight=pos_w, rot_weight=rot_w,
                   limits=joint_limits,
                   limited=bool(limits), tol=tol, max_iter=max_iter, record=record,
                   options=method_options, reach_start=bool(reach_start))


def run(req: Request, engine: Engine) -> IKResult:
    """Solve a request (:func:`run_engine`); a limited solve that missed its target is then
    told apart from one the limits made unreachable (:func:`_blame_limits`)."""
    result = run_engine(req, engine)
    if any(req.limits) and not np.all(result.converged):
        _blame_limits(req, result, engine)
    return result


def _blame_limits(req: Request, result: IKResult, engine: Engine) -> None:
    """``reason="limits"`` for every problem that missed its target with the limits and
    reaches it without them: the same method from the same start, with the same tolerance and
    budget (so the limits are what made the difference; never a silent
    ``"max_iterations"`` or ``"stalled"``)."""
    free = dataclasses.replace(req, limits=req.model.no_limits, limited=False, record=False)
    unlimited = run_engine(free, engine)
    blame = np.logical_and(np.logical_not(result.converged), unlimited.converged)
    if np.ndim(blame):
        result.reason = np.where(blame, "limits", result.reason)
    elif blame:
        result.reason = "limits"


def run_engine(req: Request, engine: Engine) -> IKResult:
    """Solve a request: on the serial-chain fast path where its paths are one chain and the
    method has a chain solver (a small batch one problem at a time in floats, which is
    faster: see :attr:`Method.batch_from`), else on the general tree engine."""
    spec = REGISTRY[req.method]
    if engine == "tree" or req.serial is None or spec.chain is None:
        return _result(solve_on_tree(req, spec.tree, spec.iterative), req.method)
    limits = req.serial.limits(req.limits) if req.limited else []
    singles_below = spec.singles_below(req.serial.free_balls, bool(limits))
    if engine == "chain" or not req.batched or req.B >= singles_below:
        return _result(solve_on_chain(req, spec.chain, limits, spec.weights), req.method)
    return _stack([_result(solve_on_chain(row, spec.chain, limits, spec.weights), req.method)
                   for row in req.rows()])


def _method(method: Any) -> Method[Any]:
    if not isinstance(method, str) or method not in REGISTRY:
        raise ValueError(f"method: expected one of {tuple(REGISTRY)}, got {method!r}")
    return REGISTRY[method]


def _options(spec: Method[Any], options: Mapping[str, Any]) -> dict[str, Any]:
    """The method's options, checked (``ValueError`` naming an option the method does not take
    or a value it cannot use; NaN fails every test), with defaults for those not given or
    None; ``max_angle=inf`` is no cap."""
    unknown = set(options) - set(spec.options)
    if unknown:
        raise ValueError(f"options: {sorted(unknown)} do not apply to method {spec.name!r} "
                         f"(it takes {sorted(spec.options) or 'none'})")
    out = {}
    for name, opt in spec.options.items():
        value = options.get(name)
        if value is None:
            value = opt.default
        elif opt.test is not None and not (_is_number(value) and opt.test(value)):
            raise ValueError(f"{name}: expected {opt.what}, got {value!r}")
        out[name] = value
    if out.get("max_angle") == math.inf:  # no cap
        out["max_angle"] = None
    return out


def _tol_and_max_iter(spec: Method[Any], tol: Any, max_iter: Any) -> int:
    """``max_iter`` (the method's default for None), after checking it and ``tol``."""
    if not (_is_number(tol) and math.isfinite(tol) and tol > 0):
        raise ValueError(f"tol: expected a positive number, got {tol!r}")
    if max_iter is None:
        return spec.max_iter
    if isinstance(max_iter, bool) or not isinstance(max_iter, int | np.integer) or max_iter < 0:
        raise ValueError(f"max_iter: expected a whole number >= 0, got {max_iter!r}")
    return int(max_iter)


def _check_skeleton(skeleton: object) -> None:
    if not all(hasattr(skeleton, a) for a in ("n_joints", "parents", "offsets", "joint_types",
                                                "index")):
        raise ValueError(f"skeleton: expected a course.skeleton.Skeleton, got "
                         f"{type(skeleton).__name__}")


def _start_pose(skeleton: Skeleton, local_rotations: ArrayLike) -> Array:
    """The starting local rotations ``([B,] J, 4)``, normalised (a zero quaternion refused)."""
    J = skeleton.n_joints
    local = as_array(local_rotations, "local_rotations", (4,))
    if local.ndim not in (2, 3) or local.shape[-2] != J:
        raise ValueError(f"local_rotations: expected shape ([B,] {J}, 4), got {local.shape}")
    big = np.abs(local).max(-1, keepdims=True)  # scaled first: the squares of 1e155 overflow
    qn = big * np.linalg.norm(local / np.where(big > 0, big, 1.0), axis=-1, keepdims=True)
    if qn.min() < 1e-12:
        raise ValueError("local_rotations: contains a zero quaternion, which is no rotation")
    unit: Array = local / qn
    return unit


def _targets(skeleton: Skeleton, targets: Any, spec: Method[Any],
             k: int) -> tuple[dict[int, Array], dict[int, Array], Array, Array]:
    """Position and orientation targets by joint index, checked, and their relative weights
    (E,) and (E_r,), the largest 1."""
    if not isinstance(targets, Mapping) or not targets:
        raise ValueError("targets: expected a non-empty mapping joint -> target")
    pos_t, rot_t, pos_w, rot_w = {}, {}, [], []
    for key, value in targets.items():
        j = skeleton.index(key)
        name = f"targets[{key!r}]"
        position, orientation = split_target(value)
        weights = _target_weights(value, name)
        if position is None and orientation is None:
            raise ValueError(f"{name}: expected a position (3,) or ([B,] 3), a pair (position, "
                             f"quaternion) or a Target, got {value!r}")
        if position is not None:
            pos_t[j] = _position(position, f"{name} position")
            pos_w.append(weights[0])
        if orientation is not None:
            q = as_array(orientation, f"{name} orientation", (4,))
            if np.min(np.einsum("...i,...i->...", q, q)) < 1e-24:
                raise ValueError(f"{name} orientation: the zero quaternion is no rotation")
            rot_t[j] = q
            rot_w.append(weights[1])
    if rot_t and not spec.orientations:
        raise ValueError(f"targets: method {spec.name!r} takes no orientation targets "
                         f"({spec.targets}); methods that do: "
                         f"{[m.name for m in REGISTRY.values() if m.orientations]}")
    if k in pos_t or k in rot_t:
        raise ValueError(f"root: joint {skeleton.names[k]!r} is fixed, it cannot also be a target")
    top = max(pos_w + rot_w)
    return pos_t, rot_t, np.array(pos_w) / top, np.array(rot_w) / top


def _target_weights(value: Any, name: str) -> tuple[float, float]:
    """A :class:`Target`'s position and orientation weights, checked (1 for other forms)."""
    if not isinstance(value, Target):
        return 1.0, 1.0
    for what in ("weight_position", "weight_orientation"):
        w = getattr(value, what)
        if not (_is_number(w) and math.isfinite(w) and w > 0):
            raise ValueError(f"{name} {what}: expected a positive number, got {w!r}")
    return float(value.weight_position), float(value.weight_orientation)


def _batch(skeleton: Skeleton, local: Array, root_pos: Array, pos_t: dict[int, Array],
           rot_t: dict[int, Array]) -> tuple[int, bool]:
    """The batch size and whether there is a batch axis at all."""
    shape = broadcast_leading(
        "targets", ("local_rotations", local, 2), ("root_position", root_pos, 1),
        *((f"targets[{skeleton.names[j]!r}] position", a, 1) for j, a in pos_t.items()),
        *((f"targets[{skeleton.names[j]!r}] orientation", a, 1) for j, a in rot_t.items()))
    if len(shape) > 1:
        raise ValueError(f"targets: leading shapes {shape} do not broadcast to one batch axis")
    return (shape[0], True) if len(shape) == 1 else (1, False)


_NUMBER = (int, float, np.integer, np.floating)  # a tuple: ``int | float`` is built per call


def _is_number(x: Any) -> bool:
    return isinstance(x, _NUMBER) and not isinstance(x, bool)


def _result(solved: Solved, method: str) -> IKResult:
    """The :class:`IKResult` of one problem (arrays without a batch axis, a history of floats)
    or of a batch (arrays (B, ...)); the engine's frames are (local, positions)."""
    history = solved.history
    return IKResult(
        local_rotations=solved.local,
        root_position=solved.root_pos,
        positions=solved.positions,
        converged=history.converged,
        iterations=history.iterations,
        residuals=np.array(history.residuals),
        reason=history.reasons(solved.unreachable),
        method=method,
        start=(np.where(solved.reach_start, "reach", "") if np.ndim(solved.reach_start)
               else "reach" if solved.reach_start else ""),
        frames=None if solved.frames is None else [{"positions": p, "local_rotations": q}
                                                   for q, p in solved.frames],
    )


def _stack(results: list[IKResult]) -> IKResult:
    """One batch result from single ones: arrays (B, ...), residuals (T, B) and frames with
    every problem held at its last entry once it has stopped (as the array engine does)."""
    if len(results) == 1:  # a batch of one: its arrays with a leading axis (a quarter the cost)
        (one,) = results
        return IKResult(
            local_rotations=one.local_rotations[None], root_position=one.root_position[None],
            positions=one.positions[None], converged=np.array([one.converged]),
            iterations=np.array([one.iterations]), residuals=one.residuals[:, None],
            reason=np.array([one.reason], dtype="<U14"), method=one.method,
            start=np.array([one.start], dtype="<U5"),
            frames=None if one.frames is None else [{k: v[None] for k, v in f.items()}
                                                    for f in one.frames])
    residuals = np.empty((max(len(r.residuals) for r in results), len(results)))
    for i, r in enumerate(results):
        residuals[:len(r.residuals), i] = r.residuals
        residuals[len(r.residuals):, i] = r.error
    runs = [r.frames for r in results if r.frames is not None]  # every problem's, or none
    frames = None
    if runs:
        F = max(len(run) for run in runs)
        frames = [{key: np.stack([run[min(t, len(run) - 1)][key] for run in runs])
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
        start=np.array([r.start for r in results], dtype="<U5"),
        frames=frames,
    )


def split_target(value: Any) -> tuple[Any, Any]:
    """``(position, orientation)`` of a target given as Target, pair or position."""
    if isinstance(value, Target):
        return value.position, value.orientation
    if isinstance(value, tuple) and len(value) == 2 and np.shape(value[1])[-1:] == (4,):
        return value
    return value, None


# A model's key beside its skeleton: the fixed joint, the effectors and the orientation ones.
ModelKey = tuple[int, tuple[int, ...], tuple[int, ...]]
Models = tuple[TreeModel, SerialChain | None]


@lru_cache(maxsize=128)
def _cached_model(parents: tuple[int, ...], offsets: bytes, kinds: tuple[JointAxis, ...],
                  root: int, eff: tuple[int, ...], reff: tuple[int, ...]) -> Models:
    off = np.frombuffer(offsets).reshape(-1, 3)
    model = build_model(np.array(parents), off, list(kinds), root, list(eff), list(reff))
    return model, serial_chain(model)


# Per skeleton object (read-only: its offsets cannot be written), the models of the paths
# solved on it: a slider calls ``solve`` with the same skeleton over and over.
_MODELS: weakref.WeakKeyDictionary[Skeleton, dict[ModelKey, Models]] = weakref.WeakKeyDictionary()


def _model(skeleton: Skeleton, root: int, eff: tuple[int, ...], reff: tuple[int, ...]) -> Models:
    """The (cached) model, and its serial chain if it is one."""
    try:
        per_skeleton = _MODELS.setdefault(skeleton, {})
    except TypeError:  # not weakly referenceable: look up by value only
        per_skeleton = {}
    key: ModelKey = (root, eff, reff)
    if key not in per_skeleton:
        per_skeleton[key] = _model_by_value(skeleton, root, eff, reff)
    return per_skeleton[key]


def _model_by_value(skeleton: Skeleton, root: int, eff: tuple[int, ...],
                    reff: tuple[int, ...]) -> Models:
    kinds: list[JointAxis] = []
    for t in skeleton.joint_types:
        axis = getattr(t, "axis", None)
        kinds.append(tuple(axis) if axis is not None else (False if t.dof == 0 else None))
    return _cached_model(tuple(int(p) for p in skeleton.parents),
                         np.ascontiguousarray(skeleton.offsets, float).tobytes(), tuple(kinds),
                         root, eff, reff)


def _check_movable(skeleton: Skeleton, model: TreeModel, root: int) -> None:
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


def _check_hinges(skeleton: Skeleton, model: TreeModel, local: Array) -> None:
    """``ValueError`` naming a hinge the solve moves whose start rotation is not a turn about
    its own axis (a hinge solve keeps the off-axis part, so the answer would depend on how
    the problem was batched)."""
    for v in np.flatnonzero(model.hinge):
        j = int(model.edge_joint[model.var_nodes[v]])
        joint = skeleton.joint_types[j]
        assert isinstance(joint, Hinge), "the model's hinges are the skeleton's"
        axis = np.asarray(joint.axis)
        vec = local[..., j, 1:]
        off = np.linalg.norm(vec - (vec @ axis)[..., None] * axis, axis=-1)
        if off.max() > 1e-6:
            where = f" (problem {int(np.argmax(off))})" if off.ndim else ""
            raise ValueError(
                f"local_rotations: joint {skeleton.names[j]!r} is a hinge about {axis.tolist()} "
                f"but its start rotation{where} turns "
                f"{2 * np.arcsin(min(1.0, float(off.max()))):.3g} rad about another axis; "
                "give a turn about the hinge axis (quat_from_axis_angle(axis, angle))")


def _weights(skeleton: Skeleton, model: TreeModel,
             weights: Mapping[str | int, Any] | None) -> Array:
    if not weights:
        return model.unit_weights
    w = np.ones(model.n_cols)
    for key, value in (weights or {}).items():
        j = skeleton.index(key)
        if not (_is_number(value) and math.isfinite(value) and value > 0):
            raise ValueError(f"weights[{key!r}]: expected a positive number, got {value!r}")
        w[model.edge_joint[model.var_nodes[model.col_var]] == j] = value
    return w


def _limits(skeleton: Skeleton, m: TreeModel,
            limits: Mapping[str | int, Any] | None) -> tuple[Limit | None, ...]:
    """Each variable's :class:`Limit` (None: free), checked."""
    if not limits:
        return m.no_limits
    out: list[Limit | None] = list(m.no_limits)
    var_joint = m.edge_joint[m.var_nodes]
    for key, value in limits.items():
        j = skeleton.index(key)
        if j == 0 and not m.anchor_parent:
            raise ValueError(
                f"limits[{key!r}]: rooted at {skeleton.names[int(m.joints[0])]!r}, joint "
                f"{skeleton.names[0]!r}'s rotation is the body's world orientation, which "
                "follows from the solve (no joint turns it); limit the joints on the way")
        lim = _joint_limit(skeleton, j, f"limits[{key!r}]", value)
        for v in np.flatnonzero(var_joint == j):
            out[v] = lim
    return tuple(out)


def _joint_limit(skeleton: Skeleton, j: int, name: str, value: Any) -> Limit | None:
    """The :class:`Limit` of joint ``j`` given as ``value`` (None: no actual limit)."""
    axis = getattr(skeleton.joint_types[j], "axis", None)
    if isinstance(value, SwingTwist):
        if axis is not None:
            raise ValueError(f"{name}: joint {skeleton.names[j]!r} is a hinge; give it a range "
                             "(lo, hi), not a SwingTwist")
        return _swing_twist(skeleton, j, name, value)
    a = np.asarray(value)
    ok = a.dtype.kind in "iuf" and not np.isnan(a).any()
    if axis is None:
        if not (ok and a.ndim == 0 and a >= 0):
            raise ValueError(f"{name}: a ball joint takes one largest angle (radians, >= 0) or "
                             f"a SwingTwist(max_swing, twist, axis), got {value!r}")
        return Limit("cap", None, 0.0, float(a)) if np.isfinite(a) else None
    if not (ok and a.shape in ((), (2,))):
        raise ValueError(f"{name}: a hinge takes a range (lo, hi) or one angle a >= 0 for "
                         f"(-a, a), radians, got {value!r}")
    lo, hi = (-float(a), float(a)) if a.ndim == 0 else (float(a[0]), float(a[1]))
    if not lo <= hi:
        raise ValueError(f"{name}: a hinge range needs lo <= hi (one angle: >= 0), got {value!r}")
    if not (math.isfinite(lo) or math.isfinite(hi)):
        return None
    return Limit("hinge", as_vec(float(c) for c in axis), lo, hi)


def _swing_twist(skeleton: Skeleton, j: int, name: str, value: SwingTwist) -> Limit:
    """A swing–twist cone checked; its axis defaults to the joint's rest bone direction."""
    cone, twist = value.max_swing, value.twist
    if not (_is_number(cone) and 0 <= cone <= math.pi):
        raise ValueError(f"{name}: max_swing must be an angle in [0, pi] radians, got {cone!r}")
    if not (isinstance(twist, tuple | list) and len(twist) == 2 and all(map(_is_number, twist))
            and -math.pi <= twist[0] <= twist[1] <= math.pi):
        raise ValueError(f"{name}: twist must be a range (lo, hi) with -pi <= lo <= hi <= pi "
                         f"radians, got {twist!r}")
    if value.axis is None:
        kids = [c for c in range(skeleton.n_joints) if skeleton.parents[c] == j]
        axis = np.asarray(skeleton.offsets)[kids].sum(axis=0)
        if not np.linalg.norm(axis) > 1e-12:
            raise ValueError(f"{name}: joint {skeleton.names[j]!r} has no rest bone to twist "
                             "about (no child offset); give SwingTwist(axis=...)")
    else:
        axis = as_array(value.axis, f"{name} axis", (3,))
        if axis.ndim != 1 or not np.linalg.norm(axis) > 1e-12:
            raise ValueError(f"{name} axis: expected a non-zero vector (3,), got {value.axis!r}")
    axis = axis / np.linalg.norm(axis)
    return Limit("swing_twist", as_vec(axis.tolist()), float(twist[0]), float(twist[1]),
                 float(cone))
