"""Differential tests: the lecture tier (:mod:`course.ik.ccd`, :mod:`course.ik.fabrik`,
:mod:`course.ik.jacobian`) and both engines of :func:`course.ik.solve` (the serial chain on
components, the tree on rotation matrices) on the same seeded problems.

The three are the same algorithms in different layouts (points batched over B, quaternion
components, matrices), so they agree to rounding, not bit for bit. Claims:

* one iteration from the same pose: the same positions within 1e-9 (CCD and FABRIK on ball
  chains; every Jacobian method on a 3D hinge chain and, via the lecture steps, on balls);
* whole solves (positions, joint limits, hinges, orientation targets): the chain and tree
  engines reach the same answer by FK residual (each within ``tol``, the same convergence
  flag), and every pose they return satisfies its limits.

A fix to one copy that misses another makes one of these fail.
"""

from __future__ import annotations

import numpy as np
import pytest

import course.rotations as rot
from course import ik
from course.ik import SwingTwist, Target
from course.ik.jacobian import chain_jacobian, dls_step, pinv_step, transpose_step
from course.skeleton import chain

SEEDS = range(5)
ENGINES = ("chain", "tree")
AXES = np.array([[0, 1, 0], [0, 0, 1]] * 3 + [[0, 1, 0]], float)


def _bent(n: int, seed: int, hinge_axes: np.ndarray | None = None):
    """A chain bent well inside its reach (so no reach-aware start), its pose, positions and a
    target near the effector."""
    rng = np.random.default_rng(seed)
    sk = chain([1.0] * n) if hinge_axes is None else chain([1.0] * n, axes=hinge_axes)
    while True:  # seeded draws until one is bent well inside the reach
        if hinge_axes is None:
            pose = rot.quat_from_axis_angle(rng.normal(size=(n + 1, 3)), 1.2)
        else:
            pose = rot.quat_from_axis_angle(np.vstack([hinge_axes, [1.0, 0, 0]]),
                                            rng.uniform(-1.2, 1.2, n + 1))
        pose[-1] = rot.quat_identity()
        P, _ = sk.forward_kinematics(pose)
        goal = P[-1] + rng.uniform(-0.3, 0.3, 3)
        if np.linalg.norm(goal - P[0]) < 0.85 * n:
            return sk, pose, P, goal


def _one(sk, pose, goal, method, engine, **options):
    return ik.solve(sk, pose, np.zeros(3), {sk.n_joints - 1: goal}, method, max_iter=1,
                    tol=1e-12, reach_start=False, engine=engine, **options)


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("engine", ENGINES)
def test_one_ccd_sweep_lecture_equals_engines(seed, engine):
    sk, pose, P, goal = _bent(6, seed)
    lecture = ik.ccd_positions(P, goal, max_iter=1)[0]
    assert np.allclose(_one(sk, pose, goal, "ccd", engine).positions, lecture, atol=1e-9)


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("engine", ENGINES)
def test_one_fabrik_iteration_lecture_equals_engines(seed, engine):
    sk, pose, P, goal = _bent(6, seed)
    lecture = ik.fabrik_positions(P, goal, max_iter=1)[0]
    assert np.allclose(_one(sk, pose, goal, "fabrik", engine).positions, lecture, atol=1e-9)


def _lecture_step(method, J, e):
    if method == "dls":
        return dls_step(J, e, 0.5)
    if method == "pseudo_inverse":
        return pinv_step(J, e)
    return transpose_step(J, e)


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("method", ["jacobian_transpose", "pseudo_inverse", "dls"])
def test_one_jacobian_step_on_hinges_lecture_equals_engines(seed, engine, method):
    # A hinge chain: theta <- theta + step(J, t - e), J_i = a_i x (e - r_i) (course.ik.jacobian).
    sk, pose, P, goal = _bent(7, seed, AXES)
    angles = 2.0 * np.arctan2(np.einsum("ji,ji->j", pose[:-1, 1:], AXES), pose[:-1, 0])
    _, Q = sk.forward_kinematics(pose)
    parents_q = np.vstack([rot.quat_identity(), Q[:-2]])  # Q of each hinge's parent
    world_axes = rot.quat_rotate(parents_q, AXES)
    J = chain_jacobian(P[:-1], world_axes, P[-1])
    new = angles + _lecture_step(method, J, goal - P[-1])
    lecture_pose = pose.copy()
    lecture_pose[:-1] = rot.quat_from_axis_angle(AXES, new)
    lecture = sk.forward_kinematics(lecture_pose)[0]
    options = {"damping": 0.5} if method == "dls" else {}
    solved = _one(sk, pose, goal, method, engine, **options)
    assert np.max(np.abs(new - angles)) < 0.5  # below max_step: no cap, one plain step
    assert np.allclose(solved.positions, lecture, atol=1e-9)


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("method", ["jacobian_transpose", "pseudo_inverse", "dls"])
def test_one_jacobian_step_on_balls_chain_equals_tree(seed, method):
    sk, pose, _, goal = _bent(6, seed)
    options = {"damping": 0.5} if method == "dls" else {}
    a, b = (_one(sk, pose, goal, method, e, **options) for e in ENGINES)
    assert np.allclose(a.positions, b.positions, atol=1e-9)


def _problems():
    """(name, skeleton, targets, limits) of whole solves: positions, limits, hinges."""
    hinge, ball = chain([1.0] * 7, axes=AXES), chain([1.0] * 7)
    rng = np.random.default_rng(26)
    out = []
    for sk, name in ((hinge, "hinge"), (ball, "ball")):
        for k in range(4):
            q = rot.quat_from_axis_angle(np.vstack([AXES, [1.0, 0, 0]]) if name == "hinge"
                                         else rng.normal(size=(8, 3)), rng.uniform(-1, 1, 8))
            goal = sk.forward_kinematics(q)[0][-1]
            out.append((f"{name}{k}", sk, {7: goal}, None))
            limits = ({0: (-0.6, 0.6), 2: 0.5} if name == "hinge"
                      else {0: 0.7, 1: SwingTwist(0.6, (-0.3, 0.3))})
            out.append((f"{name}{k}-limits", sk, {7: goal}, limits))
    return out


PROBLEMS = _problems()


def _within_limits(sk, local, limits):
    for j, lim in (limits or {}).items():
        q = local[j]
        if isinstance(lim, SwingTwist):
            axis = sk.offsets[j + 1] / np.linalg.norm(sk.offsets[j + 1])
            assert rot.swing_angle(q, axis) <= lim.max_swing + 1e-9
            assert lim.twist[0] - 1e-9 <= rot.twist_angle(q, axis) <= lim.twist[1] + 1e-9
        elif np.ndim(lim) == 0 and sk.joint_types[j].__class__.__name__ == "Ball":
            assert 2 * np.arctan2(np.linalg.norm(q[1:]), abs(q[0])) <= lim + 1e-9
        else:
            lo, hi = (-lim, lim) if np.ndim(lim) == 0 else lim
            axis = AXES[j]
            angle = 2 * np.arctan2(q[1:] @ axis, q[0])
            assert lo - 1e-9 <= angle <= hi + 1e-9


@pytest.mark.parametrize("method", ["ccd", "fabrik", "jacobian_transpose", "pseudo_inverse",
                                    "dls"])
@pytest.mark.parametrize("problem", PROBLEMS, ids=[p[0] for p in PROBLEMS])
def test_whole_solves_chain_and_tree_agree(problem, method):
    _, sk, targets, limits = problem
    tol = 1e-4
    pose = np.tile(rot.quat_identity(), (sk.n_joints, 1))
    results = [ik.solve(sk, pose, np.zeros(3), targets, method, tol=tol, limits=limits,
                        engine=e) for e in ENGINES]
    goal = targets[7]
    for r in results:
        residual = np.linalg.norm(sk.forward_kinematics(r.local_rotations)[0][-1] - goal)
        assert np.allclose(sk.forward_kinematics(r.local_rotations)[0], r.positions, atol=1e-9)
        if r.converged:
            assert residual < tol
        _within_limits(sk, r.local_rotations, limits)
    if limits is None:  # free, reachable targets: both engines reach them
        assert all(r.converged for r in results), [r.reason for r in results]
    else:
        assert results[0].converged == results[1].converged, [r.reason for r in results]


@pytest.mark.parametrize("method", ["ccd", "fabrik", "jacobian_transpose", "pseudo_inverse",
                                    "dls"])
@pytest.mark.parametrize("seed", range(3))
def test_orientation_targets_reached_on_tree_and_auto(seed, method):
    sk = chain([1.0] * 5)
    rng = np.random.default_rng(seed)
    q = rot.quat_from_axis_angle(rng.normal(size=(6, 3)), rng.uniform(-0.8, 0.8, 6))
    pos, ori = sk.forward_kinematics(q)
    pose = np.tile(rot.quat_identity(), (6, 1))
    for engine in ("tree", "auto"):
        r = ik.solve(sk, pose, np.zeros(3), {5: Target(pos[5], ori[4])}, method, tol=1e-4,
                     max_iter=2000, engine=engine)
        p, Q = sk.forward_kinematics(r.local_rotations)
        assert r.converged, (engine, r.reason)
        assert np.linalg.norm(p[5] - pos[5]) < 1e-4
        assert 2 * np.arccos(min(1.0, abs(float(Q[5] @ ori[4])))) < 1e-3
