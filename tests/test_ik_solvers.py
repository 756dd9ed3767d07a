"""``course.ik.solve`` on chains and on the CMU skeleton, every method. Answers are checked by
forward-kinematics residual and constraints (bone lengths, fixed root, limits), never by
joint angles."""

from __future__ import annotations

import functools
import re

import numpy as np
import pytest

from course.ik import METHODS, Target, solve
from course.rotations import matrix_from_quat, quat_from_axis_angle, quat_from_rotvec
from course.skeleton import chain

AXES = np.array([[0, 1, 0], [0, 0, 1]] * 3 + [[0, 1, 0]], float)
HINGE = chain([1.0] * 7, axes=AXES)
BALL = chain([1.0] * 7)
IDENT = np.tile([1.0, 0, 0, 0], (8, 1))


def _reachable_targets(n: int, seed: int) -> np.ndarray:
    """End positions of random hinge poses: reachable by both chains."""
    rng = np.random.default_rng(seed)
    q = np.tile(IDENT, (n, 1, 1))
    q[:, :7] = quat_from_axis_angle(AXES, rng.uniform(-1.5, 1.5, (n, 7)))
    return HINGE.forward_kinematics(q)[0][:, -1]


def _check_pose(sk, result):
    """Bones kept (FK of the returned pose gives the returned positions) and root fixed."""
    pos, _ = sk.forward_kinematics(result.local_rotations, result.root_position)
    np.testing.assert_allclose(pos, result.positions, atol=1e-9)
    np.testing.assert_allclose(result.root_position, np.zeros(3), atol=1e-12)
    bones = np.linalg.norm(np.diff(result.positions, axis=-2), axis=-1)
    np.testing.assert_allclose(bones, 1.0, atol=1e-9)
    assert np.all(np.isfinite(result.local_rotations))


# Share of seeded reachable targets each method reaches to 1e-4 from the zero pose (hinge chain
# unless noted). CCD and the transpose method crawl on some targets; FABRIK runs on ball joints.
SUCCESS = {"dls": 1.0, "pseudo_inverse": 0.95, "jacobian_transpose": 0.8, "ccd": 0.9,
           "fabrik": 1.0}


@pytest.mark.parametrize("method", list(SUCCESS))
def test_methods_reach_seeded_targets(method):
    sk = BALL if method == "fabrik" else HINGE
    targets = _reachable_targets(12, seed=10)
    hits = 0
    for t in targets:
        r = solve(sk, IDENT, np.zeros(3), {"end_effector": t}, method=method)
        _check_pose(sk, r)
        err = np.linalg.norm(r.positions[-1] - t)
        np.testing.assert_allclose(err, r.residuals[-1], atol=1e-9)  # honest residual
        assert r.converged == (err < 1e-4)
        assert r.converged or r.reason in ("max_iterations", "stalled")
        hits += r.converged
    assert hits >= SUCCESS[method] * len(targets)


def test_hinge_joints_stay_hinges():
    t = _reachable_targets(1, seed=11)[0]
    for method in ("dls", "ccd", "pseudo_inverse"):
        r = solve(HINGE, IDENT, np.zeros(3), {"end_effector": t}, method=method)
        R = matrix_from_quat(r.local_rotations[:7])
        np.testing.assert_allclose(np.einsum("jab,jb->ja", R, AXES), AXES, atol=1e-9)


def test_batched_dls_and_fabrik_match_single():
    targets = _reachable_targets(16, seed=12)
    for method, sk in (("dls", HINGE), ("fabrik", BALL)):
        rb = solve(sk, IDENT, np.zeros(3), {"end_effector": targets}, method=method)
        assert rb.positions.shape == (16, 8, 3) and rb.converged.shape == (16,)
        assert rb.converged.all()
        np.testing.assert_allclose(rb.positions[:, -1], targets, atol=1e-4)
        one = solve(sk, IDENT, np.zeros(3), {"end_effector": targets[3]}, method=method)
        np.testing.assert_allclose(one.positions, rb.positions[3], atol=1e-9)


@pytest.mark.parametrize("method", ["dls", "pseudo_inverse", "ccd", "fabrik", "jacobian_transpose"])
def test_unreachable_reports_stretched_pose(method):
    t = np.array([3.0, 9.0, 2.0])
    r = solve(BALL, IDENT, np.zeros(3), {"end_effector": t}, method=method, tol=1e-4)
    assert not r.converged and r.reason == "unreachable"
    _check_pose(BALL, r)
    # Best pose: stretched straight at the target. FABRIK answers in one pass; the iterative
    # methods approach it, but near the straight pose the error is flat (it grows with the
    # square of the bend), so they stop with the error ~1e-3 off and the joints visibly bent.
    u = t / np.linalg.norm(t)
    if method == "fabrik":
        np.testing.assert_allclose(r.positions, np.arange(8)[:, None] * u, atol=1e-9)
    np.testing.assert_allclose(r.error, np.linalg.norm(t) - 7.0, atol=1e-9 if method == "fabrik"
                               else 5e-3)
    # A hinge chain whose base turns about y cannot point its first bone at t; it still
    # reports unreachable, with a pose no worse than where it started.
    h = solve(HINGE, IDENT, np.zeros(3), {"end_effector": t}, method=method if method not in
              ("fabrik", "ccd") else "dls")
    assert h.reason == "unreachable" and h.error < h.residuals[0]
    assert np.all(np.diff(h.residuals) <= 1e-12) or method in ("fabrik", "ccd")


def test_limits_respected():
    t = _reachable_targets(6, seed=13)
    lim = {f"joint{i}": (-0.4, 0.4) for i in range(7)}
    for method in ("dls", "ccd", "fabrik", "jacobian_transpose", "pseudo_inverse"):
        for target in t:
            r = solve(HINGE, IDENT, np.zeros(3), {"end_effector": target}, method=method,
                      limits=lim, max_iter=60)
            assert np.all(np.abs(_hinge_angles(r.local_rotations)) <= 0.4 + 1e-9), method
    cap = 0.3
    r = solve(BALL, IDENT, np.zeros(3), {"end_effector": [2.0, 5.0, 1.0]}, method="dls",
              limits={f"joint{i}": cap for i in range(7)})
    half = np.linalg.norm(r.local_rotations[:7, 1:], axis=1)
    assert np.all(2 * np.arcsin(np.minimum(half, 1)) <= cap + 1e-9)


def test_weights_make_a_joint_move_less():
    t = _reachable_targets(1, seed=14)[0]
    free = solve(BALL, IDENT, np.zeros(3), {"end_effector": t}, method="dls")
    held = solve(BALL, IDENT, np.zeros(3), {"end_effector": t}, method="dls",
                 weights={"joint0": 20.0})
    assert held.converged
    assert 1 - abs(held.local_rotations[0, 0]) < 0.2 * (1 - abs(free.local_rotations[0, 0]))


def test_two_link_solve_and_pole():
    sk = chain([2.0, 1.5])
    t = np.array([1.0, 2.0, 0.5])
    for pole, flip in (([0, 0, 5.0], False), ([0, 0, 5.0], True), (None, False)):
        r = solve(sk, np.tile(IDENT[0], (3, 1)), np.zeros(3), {"end_effector": t},
                  method="two_link", pole=pole, flip=flip)
        assert r.converged and r.iterations == 1
        np.testing.assert_allclose(r.positions[-1], t, atol=1e-12)
        np.testing.assert_allclose(np.linalg.norm(np.diff(r.positions, axis=0), axis=1),
                                   [2.0, 1.5], atol=1e-12)
        if pole is not None:
            side = np.dot(r.positions[1], [0, 0, 1.0])
            assert (side < 0) if flip else (side > 0)
    far = solve(sk, np.tile(IDENT[0], (3, 1)), np.zeros(3), {"end_effector": 10 * t},
                method="two_link")
    assert far.reason == "unreachable"
    np.testing.assert_allclose(far.positions[-1], 3.5 * t / np.linalg.norm(t), atol=1e-12)
    with pytest.raises(ValueError, match="two bones"):
        solve(BALL, IDENT, np.zeros(3), {"end_effector": t}, method="two_link")


def test_record_frames_replay():
    t = _reachable_targets(1, seed=15)[0]
    for method in ("ccd", "fabrik", "dls"):
        r = solve(BALL, IDENT, np.zeros(3), {"end_effector": t}, method=method, record=True)
        assert len(r.frames) == r.iterations + 1
        np.testing.assert_allclose(r.frames[-1]["positions"], r.positions, atol=1e-12)
        errs = [np.linalg.norm(f["positions"][-1] - t) for f in r.frames]
        np.testing.assert_allclose(errs, r.residuals, atol=1e-9)


@pytest.mark.parametrize("method", [m for m in METHODS if m != "two_link"])
def test_residual_history_does_not_depend_on_recording(method):
    """One residual per iteration plus the start, whether or not the poses are recorded."""
    t = _reachable_targets(1, seed=16)[0]
    runs = [solve(BALL, IDENT, np.zeros(3), {"end_effector": t}, method=method, record=record)
            for record in (False, True)]
    for r in runs:
        assert len(r.residuals) == r.iterations + 1
    np.testing.assert_allclose(runs[0].residuals, runs[1].residuals, atol=1e-9)


def test_degenerate_input_no_nan():
    zero_bone = chain(np.array([[1.0, 0, 0], [0, 0, 0], [1, 0, 0], [1, 0, 0]]))
    ident = np.tile(IDENT[0], (5, 1))
    for method in METHODS[1:]:
        for t in ([0.0, 0, 0], [1.5, 0, 0], [-2.0, 0, 0], [5.0, 0, 0], [1.0, 1.0, 0]):
            r = solve(zero_bone, ident, np.zeros(3), {"end_effector": t}, method=method,
                      max_iter=30)
            assert np.all(np.isfinite(r.positions)) and np.all(np.isfinite(r.residuals))
            bones = np.linalg.norm(np.diff(r.positions, axis=0), axis=1)
            np.testing.assert_allclose(bones, [1, 0, 1, 1], atol=1e-9)
            assert r.converged or r.reason


def test_bad_input_names_the_argument():
    t = np.array([1.0, 2.0, 0.0])
    cases = [
        (dict(targets={"end_effector": [np.nan, 0, 0]}), "targets"),
        (dict(local_rotations=np.full((8, 4), np.inf)), "local_rotations"),
        (dict(root_position=[0, np.nan, 0]), "root_position"),
        (dict(method="newton"), "method"),
        (dict(targets={"nope": t}), "nope"),
        (dict(targets={"end_effector": (t, [1, 0, 0, 0])}, method="two_link"), "targets"),
        (dict(weights={"joint1": -1.0}), "weights"),
        (dict(damping=0.1, method="ccd"), "options"),
        (dict(engine="fast"), "engine"),
    ]
    for kwargs, word in cases:
        args = dict(skeleton=BALL, local_rotations=IDENT, root_position=np.zeros(3),
                    targets={"end_effector": t}) | kwargs
        with pytest.raises(ValueError, match=word):
            solve(**args)


def test_orientation_target_with_dls():
    rng = np.random.default_rng(16)
    q = np.tile(IDENT, (1, 1))
    q[:7] = quat_from_rotvec(rng.normal(scale=0.4, size=(7, 3)))
    pos, ori = BALL.forward_kinematics(q)
    r = solve(BALL, IDENT, np.zeros(3), {"joint6": Target(pos[6], ori[6])}, method="dls")
    assert r.converged
    _, got = BALL.forward_kinematics(r.local_rotations)
    np.testing.assert_allclose(r.positions[6], pos[6], atol=1e-4)
    assert abs(abs(np.dot(got[6], ori[6])) - 1) < 1e-7


# --------------------------------------------------------------------------- CMU skeleton
@pytest.fixture(scope="module")
def walk(shared_bvh_dir):
    from course.bvh import load_bvh

    return load_bvh(shared_bvh_dir / "cmu_12_01_walk.bvh")


def _moved(before, after):
    return np.linalg.norm(after - before, axis=-1) > 1e-9


@pytest.mark.parametrize("method", ["dls", "fabrik", "ccd", "pseudo_inverse"])
def test_both_hands_from_hips(walk, method):
    sk = walk.skeleton
    local, root = walk.local_rotations[60], walk.root_positions[60]
    pos0, _ = sk.forward_kinematics(local, root)
    lh, rh = sk.index("LeftHand"), sk.index("RightHand")
    targets = {"LeftHand": pos0[lh] + [3.0, 4.0, 2.0], "RightHand": pos0[rh] + [-2.0, 5.0, 3.0]}
    r = solve(sk, local, root, targets, method=method, tol=1e-3)
    assert r.converged, (r.reason, r.error)
    pos, _ = sk.forward_kinematics(r.local_rotations, r.root_position)
    np.testing.assert_allclose(pos, r.positions, atol=1e-9)
    np.testing.assert_allclose(r.root_position, root)
    np.testing.assert_allclose(np.linalg.norm(pos - pos[sk.parents], axis=1)[1:],
                               np.linalg.norm(sk.offsets, axis=1)[1:], atol=1e-9)
    # Rooted at the hips, the hips turn (R_0 is solved, the legs swing rigidly with them);
    # rooted at the lower back, the hips' frame is held and the legs stay put.
    back = solve(sk, local, root, targets, method=method, tol=1e-3, root="LowerBack")
    assert back.converged
    for name in ("LeftToeBase", "RightFoot", "Hips"):
        j = sk.index(name)
        np.testing.assert_allclose(back.positions[j], pos0[j], atol=1e-9)
        np.testing.assert_allclose(back.local_rotations[j], local[j], atol=1e-12)
    np.testing.assert_allclose(back.positions[sk.index("LowerBack")],
                               pos0[sk.index("LowerBack")], atol=1e-9)
    off_path = [j for j in range(sk.n_joints) if j not in set(sk.path(0, lh) + sk.path(0, rh))]
    np.testing.assert_allclose(r.local_rotations[off_path], local[off_path], atol=1e-12)


@pytest.mark.parametrize("root_name", ["Hips", "LeftFoot", "RightArm"])
def test_same_reach_rooted_elsewhere(walk, root_name):
    sk = walk.skeleton
    local, root = walk.local_rotations[200], walk.root_positions[200]
    pos0, ori0 = sk.forward_kinematics(local, root)
    k = sk.index(root_name)
    t = pos0[sk.index("RightHand")] + [2.0, 3.0, -2.0]
    r = solve(sk, local, root, {"RightHand": t}, method="dls", root=root_name)
    assert r.converged
    pos, ori = sk.forward_kinematics(r.local_rotations, r.root_position)
    np.testing.assert_allclose(pos, r.positions, atol=1e-9)
    np.testing.assert_allclose(pos[sk.index("RightHand")], t, atol=1e-4)
    np.testing.assert_allclose(pos[k], pos0[k], atol=1e-9)  # the fixed joint stays
    moved = _moved(pos0, pos)
    left_foot = sk.index("LeftFoot")
    if root_name == "LeftFoot":  # planted: orientation kept, the body moves over it
        assert abs(abs(np.dot(ori[k], ori0[k])) - 1) < 1e-12
        assert moved[0] and moved[sk.index("Head")]
    elif root_name == "RightArm":  # only the arm below the shoulder moves
        assert not moved[0] and not moved[left_foot] and not moved[sk.index("Head")]
        assert not moved[sk.index("RightShoulder")]
    else:  # the hips stay and turn; the legs keep their local rotations
        assert not moved[0]
        legs = sk.path(0, sk.index("LeftToeBase"))[1:]
        np.testing.assert_allclose(r.local_rotations[legs], local[legs], atol=1e-12)


def test_rerooted_multi_effector_hand_and_foot(walk):
    sk = walk.skeleton
    local, root = walk.local_rotations[300], walk.root_positions[300]
    pos0, _ = sk.forward_kinematics(local, root)
    targets = {"LeftHand": pos0[sk.index("LeftHand")] + [0.0, 6.0, 3.0],
               "RightFoot": pos0[sk.index("RightFoot")] + [0.0, 4.0, 4.0]}
    for method in ("dls", "fabrik"):
        r = solve(sk, local, root, targets, method=method, root="LeftToeBase", tol=1e-3)
        assert r.converged, method
        pos, _ = sk.forward_kinematics(r.local_rotations, r.root_position)
        np.testing.assert_allclose(pos, r.positions, atol=1e-9)
        np.testing.assert_allclose(pos[sk.index("LeftToeBase")], pos0[sk.index("LeftToeBase")],
                                   atol=1e-9)
        for name, t in targets.items():
            assert np.linalg.norm(pos[sk.index(name)] - t) < 1e-3


HINGE_LIMITS = {f"joint{i}": (-1.2, 1.2) for i in range(7)}
BALL_LIMITS = {f"joint{i}": 0.6 for i in range(7)}


@pytest.mark.parametrize("method, sk, lim, options", [
    ("dls", HINGE, HINGE_LIMITS, {}),
    ("pseudo_inverse", HINGE, HINGE_LIMITS, {}),
    ("jacobian_transpose", HINGE, HINGE_LIMITS, {}),
    ("fabrik", BALL, None, {}),  # positions alone, rotations fitted once
    ("fabrik", HINGE, HINGE_LIMITS, {}),  # joint-space backward pass
    ("fabrik", BALL, BALL_LIMITS, {}),
    ("ccd", HINGE, HINGE_LIMITS, {}),
    # Root to tip from the straight pose, every joint after the first lies on the line to
    # the target: exact ties (opposite directions) that rounding breaks; start bent instead.
    ("ccd", HINGE, None, {"tip_to_root": False, "start": 0.3}),
    ("ccd", BALL, BALL_LIMITS, {}),
    ("ccd", BALL, None, {"max_angle": 0.3}),
], ids=lambda x: x if isinstance(x, str) else None)
def test_fast_serial_path_agrees_with_general_model(method, sk, lim, options):
    """The serial-chain fast path (floats for one problem, component arrays for a batch) and
    the general model reach the same poses: same residuals, limits and bones."""
    targets = _reachable_targets(6, seed=16)
    options = dict(options)
    start = IDENT.copy()
    start[:7] = quat_from_axis_angle(AXES, np.full(7, options.pop("start", 0.0)))
    runs = {}
    for fast in (True, False):
        run = _solver("chain" if fast else "tree")
        one = [run(sk, start, np.zeros(3), {"end_effector": t}, method=method, limits=lim,
                   max_iter=60, **options) for t in targets]
        batch = run(sk, start, np.zeros(3), {"end_effector": targets}, method=method,
                    limits=lim, max_iter=60, **options)
        runs[fast] = one, batch
    (one_f, batch_f), (one_g, _) = runs[True], runs[False]
    for i, (f, g) in enumerate(zip(one_f, one_g, strict=True)):
        _check_pose(sk, f)
        assert f.iterations == g.iterations and f.reason == g.reason
        np.testing.assert_allclose(f.residuals, g.residuals, atol=1e-8)
        np.testing.assert_allclose(f.positions, g.positions, atol=1e-7)
        np.testing.assert_allclose(batch_f.positions[i], f.positions, atol=1e-9)
        if lim is HINGE_LIMITS:
            assert np.all(np.abs(_hinge_angles(f.local_rotations)) <= 1.2 + 1e-9)
        elif lim is BALL_LIMITS:
            half = np.linalg.norm(f.local_rotations[:7, 1:], axis=1)
            assert np.all(2 * np.arcsin(np.minimum(half, 1)) <= 0.6 + 1e-9)


def _solver(engine: str):
    """``solve`` on one engine: ``"tree"`` (the general model), ``"chain"`` (the serial fast
    path, a batch of any size on the array engine, every component an ndarray (B,): small
    batches would otherwise solve one problem at a time) or ``"auto"`` (as ``solve``)."""
    return functools.partial(solve, engine=engine)


def _hinge_angles(local: np.ndarray) -> np.ndarray:
    """Angles of the HINGE chain's local rotations about their axes, in (-pi, pi]."""
    angles = 2 * np.arctan2(np.einsum("ji,ji->j", local[:7, 1:], AXES), local[:7, 0])
    return (angles + np.pi) % (2 * np.pi) - np.pi


def test_fabrik_with_hinges_converges_on_a_planar_arm():
    """Parallel hinges (the lecture's 2D arm): the backward pass turns each hinge about z onto
    the reached points of the chain below it. Seeded reachable targets in the plane: all
    reached to 1e-4 (measured: 200 of 200, median 7 iterations), single and batched, each
    pose a pure turn about z."""
    arm = chain([1.0] * 7, axes=[0, 0, 1])
    rng = np.random.default_rng(17)
    q = np.tile(IDENT, (40, 1, 1))
    q[:, :7] = quat_from_axis_angle(np.array([0.0, 0, 1]), rng.uniform(-1.5, 1.5, (40, 7)))
    targets = arm.forward_kinematics(q)[0][:, -1]
    batch = solve(arm, IDENT, np.zeros(3), {"end_effector": targets}, method="fabrik")
    assert batch.converged.all()
    np.testing.assert_allclose(batch.positions[:, -1], targets, atol=1e-4)
    np.testing.assert_allclose(batch.local_rotations[:, :7, 1:3], 0.0, atol=1e-12)
    for i in (0, 7, 23):
        one = solve(arm, IDENT, np.zeros(3), {"end_effector": targets[i]}, method="fabrik")
        _check_pose(arm, one)
        assert one.converged and one.iterations == batch.iterations[i]


def test_fabrik_with_hinges_about_different_axes():
    """The 3D hinge chain (axes y, z, y, ...): a hinge cannot aim its bone at a point off its
    plane, so each one takes the turn that brings the whole chain below it closest to the
    reached points. Measured on 200 seeded targets: 199 reached to 1e-4, median 20 iterations
    (aiming the next bone alone: none). Here 40 targets, single and batched, hinges kept."""
    targets = _reachable_targets(40, seed=18)
    batch = solve(HINGE, IDENT, np.zeros(3), {"end_effector": targets}, method="fabrik")
    assert batch.converged.mean() >= 0.95
    np.testing.assert_allclose(batch.residuals[-1], np.linalg.norm(batch.positions[:, -1] - targets,
                                                                   axis=1), atol=1e-9)
    for i in (0, 13):
        one = solve(HINGE, IDENT, np.zeros(3), {"end_effector": targets[i]}, method="fabrik")
        _check_pose(HINGE, one)
        np.testing.assert_allclose(one.positions, batch.positions[i], atol=1e-9)
        R = matrix_from_quat(one.local_rotations[:7])
        np.testing.assert_allclose(np.einsum("jab,jb->ja", R, AXES), AXES, atol=1e-9)


@pytest.mark.parametrize("method", ["pseudo_inverse", "dls", "jacobian_transpose", "ccd", "fabrik"])
@pytest.mark.parametrize("fast", [True, False])
def test_straight_chain_target_on_its_line(method, fast):
    """A straight chain and a reachable target on its line: every Jacobian column is
    perpendicular to the line (no step), FABRIK's points and CCD's turns stay on it. The
    solvers first bend the chain by a small deterministic turn and then reach, on ball and
    hinge chains, single and batched, fast path and general model alike."""
    solve = _solver("chain" if fast else "tree")
    sk = chain([1.0, 0.5, 2.0, 0.7])
    ident = np.tile(IDENT[0], (5, 1))
    targets = np.array([[2.5, 0, 0], [1.5, 0, 0], [-2.0, 0, 0], [0.8, 0, 0]])
    batch = solve(sk, ident, np.zeros(3), {"end_effector": targets}, method=method)
    for i, t in enumerate(targets):
        r = solve(sk, ident, np.zeros(3), {"end_effector": t}, method=method)
        assert r.converged, (t, r.reason, r.error)
        pos, _ = sk.forward_kinematics(r.local_rotations)
        np.testing.assert_allclose(pos, r.positions, atol=1e-9)
        np.testing.assert_allclose(np.linalg.norm(np.diff(pos, axis=0), axis=1),
                                   [1.0, 0.5, 2.0, 0.7], atol=1e-9)
        np.testing.assert_allclose(batch.positions[i], r.positions, atol=1e-9)
    if method != "fabrik":  # FABRIK's hinge support is for planar chains
        r = solve(HINGE, IDENT, np.zeros(3), {"end_effector": [5.0, 0, 0]}, method=method)
        assert r.converged and np.linalg.norm(r.positions[-1] - [5.0, 0, 0]) < 1e-4
    # Stretched at a target beyond the tip on the line: already the best pose, left straight.
    far = solve(sk, ident, np.zeros(3), {"end_effector": [6.0, 0, 0]}, method=method)
    assert far.reason == "unreachable"
    np.testing.assert_allclose(far.positions[-1], [4.2, 0, 0], atol=1e-9)


@pytest.mark.parametrize("method", ["pseudo_inverse", "dls"])
@pytest.mark.parametrize("fast", [True, False])
def test_singular_pose_reported(method, fast):
    """A planar arm (every hinge about z) and a target out of its plane at a reachable
    distance: the Jacobian has rank 2 everywhere, no step leaves the plane, so the solve
    stalls and says "singular"."""
    solve = _solver("auto" if fast else "tree")
    arm = chain([1.0] * 7, axes=[0, 0, 1])
    r = solve(arm, IDENT, np.zeros(3), {"end_effector": [3.0, 2.0, 2.0]}, method=method)
    assert not r.converged and r.reason == "singular"
    np.testing.assert_allclose(r.error, 2.0, atol=1e-6)  # the in-plane part is reached


@pytest.mark.parametrize("method", [m for m in METHODS if m != "two_link"])
@pytest.mark.parametrize("fast", [True, False])
def test_result_of_one_problem_and_of_a_batch(method, fast):
    """One problem's result holds plain values (bool, int, str, residuals (T,), arrays without a
    batch axis) whether the fast path solved it in floats or the general model as a batch of
    one; a batch's holds arrays (B,) and residuals (T, B); and each single solve is its row of
    the batch. Targets: reachable, beyond reach (stretched, one pass) and a capped solve."""
    solve = _solver("chain" if fast else "tree")
    sk = BALL if method == "fabrik" else HINGE
    targets = np.vstack([_reachable_targets(3, seed=19), [[9.0, 1.0, 0.0]]])
    kw = dict(method=method, max_iter=25)
    batch = solve(sk, IDENT, np.zeros(3), {"end_effector": targets}, **kw)
    B = len(targets)
    assert batch.converged.dtype == bool and batch.converged.shape == (B,)
    assert batch.iterations.dtype.kind == "i" and batch.reason.dtype == "<U14"
    assert batch.residuals.shape == (batch.iterations.max() + 1, B)
    assert batch.local_rotations.shape == (B, 8, 4) and batch.positions.shape == (B, 8, 3)
    assert batch.reason[-1] == "unreachable"
    for i, t in enumerate(targets):
        r = solve(sk, IDENT, np.zeros(3), {"end_effector": t}, **kw)
        assert type(r.converged) is bool and type(r.iterations) is int
        assert type(r.reason) is str
        assert r.residuals.dtype == np.float64 and r.residuals.shape == (r.iterations + 1,)
        assert r.local_rotations.shape == (8, 4) and r.positions.shape == (8, 3)
        assert r.root_position.shape == (3,)
        assert (r.converged, r.iterations, r.reason) == (
            batch.converged[i], batch.iterations[i], batch.reason[i])
        np.testing.assert_allclose(r.residuals, batch.residuals[:r.iterations + 1, i],
                                   atol=1e-9)
        np.testing.assert_allclose(r.positions, batch.positions[i], atol=1e-9)


def test_history_of_one_problem_in_floats_keeps_a_batchs_books():
    """The bookkeeping of one problem in floats (the fast path) is that of its column in a
    batch: iterations, residuals, the stall test, the iteration cap, and the reasons in their
    order of precedence (converged, unreachable, singular, stalled, max_iterations)."""
    from course.ik._engine.history import History
    from course.ik._engine.ops import ARRAYS, FLOATS

    tol, max_iter, T = 1e-3, 12, 16
    k = np.arange(T + 1)[:, None]
    errors = np.hstack([
        0.5 ** k,                           # converges at iteration 10
        np.full((T + 1, 1), 0.5),           # no progress: stalls after the window
        1.0 - 0.01 * k,                     # still falling at the cap
        np.full((T + 1, 1), 0.2),           # stalls on a lost-rank Jacobian
        np.full((T + 1, 1), 0.3),           # stalls, out of reach
        np.zeros((T + 1, 1)),               # there at the start
    ])
    singular = np.array([False, False, False, True, False, False])
    unreachable = np.array([False, False, False, False, True, False])
    want = ["", "stalled", "max_iterations", "singular", "unreachable", ""]

    batch = History(errors[0], tol, max_iter, ops=ARRAYS)
    for e in errors[1:]:
        if batch.active.any():
            batch.update(e)
    batch.singular = singular
    assert list(batch.reasons(unreachable)) == want
    for i in range(errors.shape[1]):
        one = History(float(errors[0, i]), tol, max_iter, ops=FLOATS)
        for e in errors[1:, i]:
            if one.active:
                one.update(float(e))
        one.singular = bool(singular[i])
        assert type(one.iterations) is int and type(one.converged) is bool
        assert one.iterations == batch.iterations[i] and one.converged == batch.converged[i]
        assert one.reasons(bool(unreachable[i])) == want[i]
        column = np.array(batch.residuals)[:, i]
        assert one.residuals == column[:one.iterations + 1].tolist()
        assert np.all(column[one.iterations:] == one.error)  # held once stopped
    assert batch.iterations.tolist() == [10, 8, 12, 8, 8, 0]


def test_the_one_iteration_driver_steps_only_the_problems_still_running():
    """:func:`iterate` steps while some problem runs, hands the step which ones do, keeps the
    :class:`History` and, with ``record``, every state from the start on."""
    from typing import NamedTuple

    from course.ik._engine.history import iterate
    from course.ik._engine.ops import ARRAYS

    class Run(NamedTuple):
        tol: float = 1e-3
        max_iter: int = 20
        record: bool = True
        ops: object = ARRAYS
        done: object = False

    class State(NamedTuple):
        R: np.ndarray
        P: None
        err: np.ndarray
        progress: None = None

    seen = []

    def halve(s, active):
        seen.append(active.copy())
        return State(s.R + active, None, np.where(active, s.err / 2, s.err))

    start = State(np.zeros(3), None, np.array([1.0, 1e-4, 0.01]))
    solution = iterate(Run(), start, halve)
    assert solution.history.iterations.tolist() == [10, 0, 4]
    assert solution.history.converged.all() and not solution.history.active.any()
    assert solution.R.tolist() == [10, 0, 4] and solution.frames[0] is start
    assert len(solution.frames) == len(seen) + 1 == 11
    assert [a.tolist() for a in seen[3:5]] == [[True, False, True], [True, False, False]]


def test_the_method_registry_is_what_solve_takes_and_documents():
    """One record per method: ``METHODS``, the default budgets, the options ``solve`` accepts
    (an unknown one is refused naming the ones it takes, a bad value naming what it must be)
    and ``solve``'s docstring all come from ``course.ik.methods.REGISTRY``."""
    from course.ik import DEFAULT_MAX_ITER
    from course.ik.methods import REGISTRY

    assert METHODS == tuple(REGISTRY) == ("two_link", "ccd", "fabrik", "jacobian_transpose",
                                          "pseudo_inverse", "dls")
    assert DEFAULT_MAX_ITER == {name: m.max_iter for name, m in REGISTRY.items()}
    doc = solve.__doc__
    arm = chain([1.0, 1.0])
    start = np.tile(IDENT[0], (3, 1))
    for name, m in REGISTRY.items():
        assert f'"{name}"' in doc
        with pytest.raises(ValueError, match=r"options: \['bogus'\] do not apply to method"):
            solve(arm, start, np.zeros(3), {"end_effector": [1.0, 1.0, 0]}, method=name, bogus=1)
        for option, spec in m.options.items():
            assert f"``{option}``" in doc
            if spec.test is not None:
                with pytest.raises(ValueError, match=f"^{option}: expected {re.escape(spec.what)}"):
                    solve(arm, start, np.zeros(3), {"end_effector": [1.0, 1.0, 0]}, method=name,
                          **{option: -1.0})
        # Orientation targets only where the record says so.
        target = {"end_effector": Target([1.0, 1.0, 0.0], [1.0, 0, 0, 0])}
        if m.orientations:
            solve(arm, start, np.zeros(3), target, method=name)
        else:
            with pytest.raises(ValueError, match=f"method '{name}' takes no orientation "
                                                 f"targets \\({re.escape(m.targets)}\\)"):
                solve(arm, start, np.zeros(3), target, method=name)


@pytest.mark.parametrize("engine", ["auto", "chain", "tree"])
def test_recorded_fabrik_at_exactly_full_reach(engine):
    """A free ball chain, straight, and a target exactly at its tip's full reach along its
    line: the stretched start is the answer, so nothing is iterated; recording it gave an
    IndexError on the fast path (no iteration to fit). One frame, 0 iterations, converged,
    single and batched alike."""
    run = _solver(engine)
    ident = np.tile(IDENT[0], (8, 1))
    one = run(BALL, ident, np.zeros(3), {"end_effector": [7.0, 0, 0]}, method="fabrik",
              record=True)
    assert one.converged and one.iterations == 0 and len(one.frames) == 1
    np.testing.assert_allclose(one.positions[-1], [7.0, 0, 0], atol=1e-12)
    batch = run(BALL, ident, np.zeros(3), {"end_effector": [[7.0, 0, 0], [0, 7.0, 0]]},
                method="fabrik", record=True)
    assert batch.converged.all() and batch.iterations[0] == 0
    np.testing.assert_allclose(batch.positions[:, -1], [[7.0, 0, 0], [0, 7.0, 0]], atol=1e-9)


@pytest.mark.parametrize("method", METHODS)
def test_every_solver_gets_a_frozen_run_and_its_methods_options_record(method, monkeypatch):
    """The one engine contract: every solver is called with its engine's run record (a
    :class:`ChainRun`, the tree's :class:`Problem`: each with ``tol``, ``max_iter`` and
    ``record``) and the method's own options record (frozen, every option given or
    defaulted)."""
    import dataclasses

    from course.ik._engine.chain_solvers import ChainRun
    from course.ik._engine.tree import Problem
    from course.ik.methods import REGISTRY

    spec, calls = REGISTRY[method], []

    def spy(solver):
        def run(*args):
            calls.append(args)
            return solver(*args)
        return run

    monkeypatch.setitem(REGISTRY, method, dataclasses.replace(
        spec, tree=spy(spec.tree), chain=None if spec.chain is None else spy(spec.chain)))
    arm = chain([1.0, 1.0])
    start = np.tile(IDENT[0], (3, 1))
    options = {"two_link": {"flip": True}, "ccd": {"tip_to_root": False}, "fabrik": {},
               "jacobian_transpose": {"max_step": 0.25}, "pseudo_inverse": {"max_step": 0.25},
               "dls": {"max_step": 0.25}}[method]
    for engine in ("chain", "tree"):
        solve(arm, start, np.zeros(3), {"end_effector": [1.0, 1.0, 0]}, method=method, tol=1e-3,
              engine=engine, **options)
    kinds = [type(args[0]) for args in calls]
    assert kinds == ([ChainRun, Problem] if spec.chain is not None else [Problem, Problem])
    for run, record in calls:
        assert (run.tol, run.max_iter, run.record) == (1e-3, spec.max_iter, False)
        assert dataclasses.is_dataclass(record) and all(
            getattr(record, name) == value for name, value in options.items())
        with pytest.raises(dataclasses.FrozenInstanceError):
            record.flip = None
