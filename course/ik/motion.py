r"""IK that writes a motion: solve a target per frame over a clip, warm-started, and get a new
:class:`~course.motion.Motion` whose local rotations are the solution.

This is the lab's task (the lecture's full-body IK on a BVH character): choose the fixed joint
(``root="LeftFoot"`` keeps that foot planted, the hips move over it), solve along the paths to
the effectors, and write the **local** rotations :math:`R_j` back, frame by frame. Each
frame starts from the previous frame's solution on the solved paths (a warm start: the pose
is already close, so a few iterations suffice, and the answer cannot jump to the other
branch of a redundant arm); every joint off the paths keeps the clip's own rotation.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from course._typing import Array
from course.motion import Motion
from course.rotations import quat_conjugate, quat_mul, quat_rotate

from ._engine.request import Request
from ._pipeline import run, split_target, validate
from .result import Target


@dataclass
class MotionIK:
    """What :func:`solve_motion` returns.

    Attributes
    ----------
    motion : Motion
        The solved clip: local rotations of the solved paths (and, when the fixed joint is not
        joint 0, the root's position and rotation) replaced; every other value is the input's,
        bit for bit. ``motion.save(path)`` writes it as BVH.
    residuals : ndarray, shape (F,)
        Largest effector error of each frame's solution.
    iterations : ndarray of int, shape (F,)
    converged : ndarray of bool, shape (F,)
    reasons : ndarray of str, shape (F,)
        Each frame's :attr:`course.ik.IKResult.reason` (``""`` when converged).
    joints : tuple of int
        The joints whose local rotations the solve wrote.
    """

    motion: Motion
    residuals: Array
    iterations: NDArray[np.int_]
    converged: NDArray[np.bool_]
    reasons: NDArray[np.str_]
    joints: tuple[int, ...]


def solve_motion(
    motion: Motion,
    targets_per_frame: Mapping[str | int, Any],
    method: str = "dls",
    root: str | int | None = None,
    tol: float = 1e-4,
    max_iter: int | None = None,
    weights: Mapping[str | int, float] | None = None,
    limits: Mapping[str | int, Any] | None = None,
    warm_start: bool = True,
    **options: Any,
) -> MotionIK:
    r"""Solve IK on every frame of a clip (:func:`course.ik.solve` frame by frame).

    Parameters
    ----------
    motion : Motion
        ``F`` frames; its skeleton's offsets are the bones (a clip with per-frame bone
        translations is refused).
    targets_per_frame : mapping joint (name or index) -> targets over the clip
        Per joint: positions ``(F, 3)`` (or one ``(3,)`` for every frame), a pair
        ``(positions, quaternions (F, 4))``, or a :class:`Target` of such arrays (weights
        included).
    method, root, tol, max_iter, weights, limits, **options
        As :func:`course.ik.solve`. ``root`` is the fixed joint: it stays where it is in
        frame 0 for the whole clip (a planted foot), and the rest of the body, joint 0
        included, moves around it; with ``root`` joint 0 (the default) the hips follow the
        clip and the paths below them are solved.
    warm_start : bool
        Start each frame from the previous frame's solution on the solved paths (and, with
        a planted ``root``, the previous root position and rotation), never from the
        reach-aware start of :func:`course.ik.solve` (which would jump where the target
        crosses 0.9 of the reach); False: every frame alone (cold) from the clip's own pose of
        that frame, moved rigidly so that a planted ``root`` sits where it is in frame 0.

    Returns
    -------
    MotionIK
        The new clip, and per frame the residual, iterations, convergence and reason.

    Raises
    ------
    ValueError
        As :func:`course.ik.solve`, naming the argument; ``targets_per_frame`` whose frame
        count is not the clip's; a clip with per-frame bone translations.
    """
    if not isinstance(motion, Motion):
        raise ValueError(f"motion: expected a course.motion.Motion, got {type(motion).__name__}")
    if motion.translations is not None:
        raise ValueError("motion: has per-frame bone translations (position channels below the "
                         "root); IK solves on the skeleton's constant offsets")
    F = motion.n_frames
    targets = _per_frame(targets_per_frame, F)
    # Every frame checked at once, as one batch: shapes, values, joints, limits, hinges.
    req = validate(motion.skeleton, motion.local_rotations, motion.root_positions, targets,
                    method, root, tol, max_iter, weights, limits, False, options)
    model = req.model
    moved_root = not model.anchor_parent  # joint 0 moves around a fixed joint elsewhere
    joints = sorted({int(j) for j in model.edge_joint[model.var_nodes]} | ({0} if moved_root
                                                                             else set()))
    starts, start_roots = req.local, req.root_pos
    if moved_root:
        starts, start_roots = _planted(motion, req.root, starts)
    local = motion.local_rotations.copy()
    root_pos = motion.root_positions.copy()
    out: dict[str, list[Any]] = {k: [] for k in ("residuals", "iterations", "converged",
                                                 "reasons")}
    for t in range(F):
        start, start_root = starts[t].copy(), start_roots[t]
        if warm_start and t:
            start[joints] = local[t - 1, joints]
            if moved_root:
                start_root = root_pos[t - 1]
        # A warm frame goes on from the last answer: the reach-aware start would jump to its
        # own bend wherever the target crosses 0.9 of the reach (measured: turns of 0.8-1.8
        # rad in one frame of a 4-bone arm), and from the last answer DLS needs no help.
        row = _frame(req, t, start, start_root,
                     reach_start=req.reach_start and not (warm_start and t))
        r = run(row, "auto")
        local[t, joints] = r.local_rotations[joints]
        if moved_root:
            root_pos[t] = r.root_position
        for key, value in (("residuals", r.error), ("iterations", r.iterations),
                           ("converged", r.converged), ("reasons", r.reason)):
            out[key].append(value)
    solved = Motion(motion.skeleton, local, root_pos, motion.frame_time, motion.channels,
                    name=f"{motion.name} (IK)" if motion.name else "IK",
                    source=motion.source)
    return MotionIK(solved, np.array(out["residuals"]), np.array(out["iterations"]),
                    np.array(out["converged"]), np.array(out["reasons"]), tuple(joints))


def hand_targets(motion: Motion) -> dict[str, Array]:
    """Per-frame targets (F, 3) for both hands of a CMU clip, around where they are in frame
    0: the left hand circling in towards the body (radius 2), the right hand drawn in and out
    (by up to 3), once over the clip. The clip starts with the arms straight out to the sides,
    so with the body held over a planted foot every target is in reach: the test case and
    benchmark of :func:`solve_motion` (``tests/test_ik_character.py``,
    ``benchmarks/character_ik.py``)."""
    sk = motion.skeleton
    pos, _ = motion.forward_kinematics()
    phase = np.linspace(0.0, 2 * np.pi, motion.n_frames)[:, None]
    zero = np.zeros_like(phase)
    circle = np.hstack([np.cos(phase) - 1, np.sin(phase), zero])
    sway = np.hstack([1 - np.cos(phase), zero, zero])
    return {"LeftHand": pos[0, sk.index("LeftHand")] + 2.0 * circle,
            "RightHand": pos[0, sk.index("RightHand")] + 1.5 * sway}


def _per_frame(targets: Any, F: int) -> dict[Any, Any]:
    """The targets as :func:`course.ik.solve` takes them for a batch of ``F`` frames,
    ``ValueError`` naming a joint whose targets cover another number of frames."""
    if not isinstance(targets, Mapping) or not targets:
        raise ValueError("targets_per_frame: expected a non-empty mapping joint -> targets")
    out = {}
    for key, value in targets.items():
        position, orientation = split_target(value)
        for what, a, ndim in (("position", position, 2), ("orientation", orientation, 2)):
            shape: tuple[int, ...] = np.shape(a) if a is not None else ()
            if len(shape) == ndim and shape[0] != F:
                raise ValueError(f"targets_per_frame[{key!r}] {what}: {shape[0]} frames, the "
                                 f"motion has {F}")
        out[key] = value if isinstance(value, Target) else Target(position, orientation)
    return out


def _planted(motion: Motion, k: int, local: Array) -> tuple[Array, Array]:
    r"""The clip's poses (local rotations (F, J, 4), root positions (F, 3)) moved rigidly so
    that joint ``k`` keeps its frame-0 position and orientation: the world turn
    :math:`G_t = Q_k(0)\,Q_k(t)^{-1}` applied to the root, :math:`R_0 \leftarrow G_t R_0`,
    :math:`p_0 \leftarrow p_k(0) + G_t\,(p_0 - p_k(t))`."""
    positions, orientations = motion.skeleton.forward_kinematics(local, motion.root_positions)
    G = quat_mul(orientations[:1, k], quat_conjugate(orientations[:, k]))
    local = local.copy()
    local[:, 0] = quat_mul(G, local[:, 0])
    root = positions[:1, k] + quat_rotate(G, motion.root_positions - positions[:, k])
    return local, root


def _frame(req: Request, t: int, local: Array, root_pos: Array, reach_start: bool) -> Request:
    """Frame ``t`` of a batched request over the clip, started from ``local``, ``root_pos``."""
    return replace(req, local=local, root_pos=root_pos, batched=False, B=1,
                   pos_t={j: a[t] if a.ndim == 2 else a for j, a in req.pos_t.items()},
                   rot_t={j: a[t] if a.ndim == 2 else a for j, a in req.rot_t.items()},
                   reach_start=reach_start)
