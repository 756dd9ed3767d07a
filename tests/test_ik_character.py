"""``course.ik`` on a whole character: swing–twist joint limits in every iterative method,
``reason="limits"``, orientation targets for CCD and FABRIK, and IK written into a motion.
Answers are judged by forward-kinematics residuals and by the constraints (limits, planted
joints, untouched joints), never by comparing joint angles."""

from __future__ import annotations

import functools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from course.ik import SwingTwist, Target, hand_targets, solve
from course.ik._engine.components import clamp_swing_twist as clamp_components
from course.ik._engine.ops import ARRAYS, FLOATS
from course.rotations import (
    clamp_swing_twist,
    quat_conjugate,
    quat_from_axis_angle,
    quat_from_rotvec,
    quat_mul,
    swing_angle,
    twist_angle,
)
from course.skeleton import Ball, Hinge, Skeleton, chain

PROPERTY = settings(max_examples=25, derandomize=True, deadline=None, database=None)
ITERATIVE = ("ccd", "fabrik", "dls", "pseudo_inverse", "jacobian_transpose")
SLACK = 1e-7  # rounding of a projected rotation through matrices and back


# --------------------------------------------------------------------------- the kernel
@PROPERTY
@given(st.integers(0, 2**32 - 1))
def test_component_clamp_is_the_checked_clamp(seed):
    """The engines' swing–twist projection (components, floats and arrays) is
    ``course.rotations.clamp_swing_twist``: the same rotations, half turns included."""
    rng = np.random.default_rng(seed)
    q = rng.normal(size=(16, 4))
    q[0] = [0.0, 1.0, 0.0, 0.0]  # a half-turn swing of the y axis: the singular split
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    axis = np.array([0.0, 1.0, 0.0]) if seed % 2 else rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    cone = rng.uniform(0, np.pi)
    lo, hi = np.sort(rng.uniform(-np.pi, np.pi, 2))
    want = clamp_swing_twist(q, axis, cone, (lo, hi))
    a = tuple(axis.tolist())
    batch = np.stack(clamp_components(tuple(q.T), a, cone, lo, hi, ARRAYS), -1)
    single = np.array([clamp_components(tuple(row), a, cone, lo, hi, FLOATS)
                       for row in q.tolist()])
    for got in (batch, single):
        np.testing.assert_allclose(np.abs(np.einsum("bi,bi->b", got, want)), 1.0, atol=1e-12)


@pytest.mark.parametrize("ops", [FLOATS, ARRAYS], ids=["floats", "arrays"])
def test_component_clamp_takes_the_twist_to_the_nearer_bound_round_the_circle(ops):
    """-3.0 with the range [-0.5, 3.0] goes to 3.0 (0.28 away through -pi), not -0.5."""
    q = quat_from_axis_angle([0.0, 0.0, 1.0], -3.0)
    got = clamp_components(tuple(q.tolist()), (0.0, 0.0, 1.0), 1.0, -0.5, 3.0, ops)
    assert float(twist_angle(np.array(got, float), [0.0, 0.0, 1.0])) == pytest.approx(3.0)


# --------------------------------------------------------------------------- random trees
@st.composite
def limited_trees(draw):
    """A random tree of 4-8 joints (balls with swing–twist cones or caps, hinges with ranges),
    a start pose inside the limits, a fixed joint and one or two effectors with targets."""
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    n = int(rng.integers(4, 9))
    parents = [-1] + [int(rng.integers(max(0, j - 3), j)) for j in range(1, n)]
    offsets = rng.normal(size=(n, 3))
    offsets[0] = 0.0
    types, limits, start = [], {}, np.tile([1.0, 0, 0, 0], (n, 1))
    for j in range(n):
        name = f"j{j}"
        if rng.random() < 0.3:
            axis = rng.normal(size=3)
            axis /= np.linalg.norm(axis)
            types.append(Hinge(tuple(axis)))
            lo, hi = np.sort(rng.uniform(-2.0, 2.0, 2))
            limits[name] = (lo, hi)
            start[j] = quat_from_axis_angle(axis, rng.uniform(lo, hi))
            continue
        types.append(Ball())
        q = quat_from_rotvec(rng.normal(scale=0.8, size=3))
        if rng.random() < 0.25:  # the plain cap: swing and twist together
            limits[name] = float(rng.uniform(0.2, 1.5))
            start[j] = quat_from_rotvec(rng.normal(scale=0.05, size=3))
            continue
        cone = float(rng.uniform(0.2, 2.0))
        twist = tuple(float(t) for t in np.sort(rng.uniform(-2.0, 2.0, 2)))
        leaf = j not in parents  # no rest bone: its axis must be given
        axis = None if rng.random() < 0.5 and not leaf else tuple(rng.normal(size=3))
        limits[name] = SwingTwist(cone, twist, axis)
        start[j] = clamp_swing_twist(q, _twist_axis(offsets, parents, j, axis), cone, twist)
    sk = Skeleton([f"j{j}" for j in range(n)], parents, offsets, types)
    leaves = [j for j in range(1, n) if j not in parents]
    effectors = [int(e) for e in rng.choice(leaves, size=min(2, len(leaves)), replace=False)]
    # The fixed joint: joint 0 or any other that is not an effector's parent (which could
    # only turn that effector in place).
    below = {parents[e] for e in effectors} | set(effectors)
    root = int(rng.choice([0, *[j for j in range(1, n) if j not in below]]))
    if root:  # joint 0's rotation is then the body's orientation, not a joint's: no limit
        limits.pop("j0")
    pos, _ = sk.forward_kinematics(start, np.zeros(3))
    targets = {f"j{e}": pos[e] + rng.normal(size=3) for e in effectors}
    return sk, start, limits, f"j{root}", targets


def _twist_axis(offsets, parents, j, axis):
    """The twist axis a SwingTwist means: given, or the joint's rest bone direction."""
    if axis is None:
        axis = offsets[[c for c in range(len(parents)) if parents[c] == j]].sum(axis=0)
    axis = np.asarray(axis, float)
    return axis / np.linalg.norm(axis) if np.linalg.norm(axis) > 1e-12 else np.array([0, 1.0, 0])


def _violation(sk, local, limits):
    """The largest amount by which any joint of a pose leaves its limit (radians)."""
    worst = 0.0
    for name, lim in limits.items():
        j = sk.index(name)
        q = local[..., j, :]
        axis = getattr(sk.joint_types[j], "axis", None)
        if axis is not None:
            angle = 2 * np.arctan2(q[..., 1:] @ np.asarray(axis), q[..., 0])
            angle = (angle + np.pi) % (2 * np.pi) - np.pi
            worst = max(worst, np.max(lim[0] - angle), np.max(angle - lim[1]))
        elif isinstance(lim, SwingTwist):
            a = _twist_axis(np.asarray(sk.offsets), sk.parents, j, lim.axis)
            worst = max(worst, np.max(swing_angle(q, a) - lim.max_swing))
            t = twist_angle(q, a)
            worst = max(worst, np.max(lim.twist[0] - t), np.max(t - lim.twist[1]))
        else:
            angle = 2 * np.arctan2(np.linalg.norm(q[..., 1:], axis=-1), np.abs(q[..., 0]))
            worst = max(worst, np.max(angle - lim))
    return worst


@PROPERTY
@given(limited_trees(), st.sampled_from(ITERATIVE), st.sampled_from(["auto", "tree"]))
def test_every_limit_holds_at_every_iteration(tree, method, engine):
    sk, start, limits, root, targets = tree
    r = solve(sk, start, np.zeros(3), targets, method=method, root=root, limits=limits,
              record=True, max_iter=25, engine=engine)
    assert len(r.frames) == r.iterations + 1
    for frame in r.frames:
        assert _violation(sk, frame["local_rotations"], limits) <= SLACK
    pos, _ = sk.forward_kinematics(r.local_rotations, r.root_position)
    np.testing.assert_allclose(pos, r.positions, atol=1e-9)
    err = max(np.linalg.norm(pos[sk.index(n)] - t) for n, t in targets.items())
    np.testing.assert_allclose(err, r.error, atol=1e-9)  # the residual is the pose's own


ARM = chain([1.0] * 5)
ARM_START = np.tile([1.0, 0, 0, 0], (6, 1))
CONES = {f"joint{i}": SwingTwist(0.5, (-0.3, 0.3)) for i in range(5)}


@pytest.mark.parametrize("method", ["ccd", "fabrik", "dls", "pseudo_inverse"])
def test_swing_twist_fast_path_agrees_with_general_model(method):
    """The differential contract with cones: the serial-chain fast path (one problem in
    floats, a batch in arrays) and the tree engine reach the same poses."""
    rng = np.random.default_rng(5)
    targets = rng.normal(size=(5, 3)) * 2.0 + [2.5, 0, 0]
    run = {e: functools.partial(solve, ARM, ARM_START, np.zeros(3), method=method,
                                limits=CONES, max_iter=40, engine=e) for e in ("chain", "tree")}
    batch = run["chain"]({"end_effector": targets})
    for i, t in enumerate(targets):
        f, g = run["chain"]({"end_effector": t}), run["tree"]({"end_effector": t})
        assert f.iterations == g.iterations and f.reason == g.reason
        np.testing.assert_allclose(f.residuals, g.residuals, atol=1e-8)
        np.testing.assert_allclose(f.positions, g.positions, atol=1e-7)
        np.testing.assert_allclose(batch.positions[i], f.positions, atol=1e-9)
        assert _violation(ARM, f.local_rotations, CONES) <= SLACK


def test_swing_twist_limit_errors_name_the_joint():
    sk = chain([1.0, 1.0], axes=[0, 0, 1])
    start = np.tile([1.0, 0, 0, 0], (3, 1))
    with pytest.raises(ValueError, match=r"limits\['joint0'\]: joint 'joint0' is a hinge"):
        solve(sk, start, np.zeros(3), {"end_effector": [1, 1, 0]},
              limits={"joint0": SwingTwist(0.5)})
    with pytest.raises(ValueError, match=r"limits\['joint1'\]: max_swing must be"):
        solve(ARM, ARM_START, np.zeros(3), {"end_effector": [1, 1, 0]},
              limits={"joint1": SwingTwist(4.0)})
    with pytest.raises(ValueError, match=r"limits\['joint1'\]: twist must be a range"):
        solve(ARM, ARM_START, np.zeros(3), {"end_effector": [1, 1, 0]},
              limits={"joint1": SwingTwist(1.0, (0.5, -0.5))})
    with pytest.raises(ValueError, match=r"limits\['joint0'\]: rooted at 'joint2', joint "
                                         r"'joint0'"):
        solve(ARM, ARM_START, np.zeros(3), {"joint0": [0.5, 0.5, 0]}, root="joint2",
              limits={"joint0": SwingTwist(1.0)})


# --------------------------------------------------------------------------- reason="limits"
BEHIND = [-2.0, 0.5, 0.0]  # behind the base: five cones of 0.3 rad bend 1.5 rad at most


@pytest.mark.parametrize("method", ITERATIVE)
def test_target_the_limits_forbid_is_reported_limits(method):
    cones = {f"joint{i}": SwingTwist(0.3, (-0.2, 0.2)) for i in range(5)}
    free = solve(ARM, ARM_START, np.zeros(3), {"end_effector": BEHIND}, method=method)
    assert free.converged  # reachable without the limits
    r = solve(ARM, ARM_START, np.zeros(3), {"end_effector": BEHIND}, method=method,
              limits=cones)
    assert not r.converged and r.reason == "limits"
    assert _violation(ARM, r.local_rotations, cones) <= SLACK
    # In a batch, only the problem the limits forbid is blamed on them.
    inside = ARM_START.copy()
    inside[:5] = quat_from_axis_angle([0, 0, 1], 0.2)  # a pose within the cones
    within = ARM.forward_kinematics(inside)[0][-1]
    batch = solve(ARM, ARM_START, np.zeros(3), {"end_effector": [BEHIND, within, [9.0, 0, 0]]},
                  method=method, limits=cones)
    assert batch.reason.tolist() == ["limits", "", "unreachable"]


@pytest.mark.parametrize("method", ITERATIVE)
def test_limits_reason_is_honest_on_random_targets(method):
    """Over random targets: every miss blamed on the limits is reached without them, and no
    target reached without the limits is missed silently (as ``max_iterations``/``stalled``)."""
    rng = np.random.default_rng(21)
    targets = rng.uniform(-5, 5, (40, 3))
    run = functools.partial(solve, ARM, ARM_START, np.zeros(3), method=method, max_iter=60)
    free = run({"end_effector": targets})
    limited = run({"end_effector": targets}, limits=CONES)
    missed = ~limited.converged & free.converged
    assert np.all(limited.reason[missed] == "limits")
    assert np.all(free.converged[limited.reason == "limits"])
    assert np.any(limited.reason == "limits")


# --------------------------------------------------------------------------- orientation targets
BALL = chain([1.0] * 7)
BALL_START = np.tile([1.0, 0, 0, 0], (8, 1))


def _orientation_error(q1, q2):
    """Angle of the rotation between two orientations (radians)."""
    d = quat_mul(quat_conjugate(q1), q2)
    return 2 * np.arctan2(np.linalg.norm(d[1:]), abs(d[0]))


@pytest.mark.parametrize("method", ["ccd", "fabrik"])
@pytest.mark.parametrize("end", ["joint6", "end_effector"])  # own rotation free / a fixed end
def test_ccd_and_fabrik_reach_orientation_targets(method, end):
    for seed in range(5):
        rng = np.random.default_rng(seed)
        pose = BALL_START.copy()
        pose[:7] = quat_from_rotvec(rng.normal(scale=0.4, size=(7, 3)))
        pos, ori = BALL.forward_kinematics(pose)
        j = BALL.index(end)
        r = solve(BALL, BALL_START, np.zeros(3), {end: Target(pos[j], ori[j])}, method=method,
                  max_iter=1000)  # CCD trades position and orientation joint by joint: slow
        assert r.converged, (seed, r.reason, r.error)
        got_pos, got_ori = BALL.forward_kinematics(r.local_rotations)
        assert np.linalg.norm(got_pos[j] - pos[j]) < 1e-4
        assert _orientation_error(got_ori[j], ori[j]) < 1e-4


@pytest.mark.parametrize("method", ["ccd", "fabrik", "dls"])
def test_hands_with_orientation_from_a_planted_foot(walk, method):
    sk = walk.skeleton
    local, root = walk.local_rotations[60], walk.root_positions[60]
    pos0, ori0 = sk.forward_kinematics(local, root)
    lh, rh, foot = sk.index("LeftHand"), sk.index("RightHand"), sk.index("LeftFoot")
    turn = quat_from_rotvec([0.5, 0.3, 0.2])
    targets = {"LeftHand": Target(pos0[lh] + [3.0, 4.0, 2.0], turn),
               "RightHand": Target(None, ori0[rh])}  # an orientation alone: keep it
    r = solve(sk, local, root, targets, method=method, root="LeftFoot", tol=1e-3)
    assert r.converged, (r.reason, r.error)
    pos, ori = sk.forward_kinematics(r.local_rotations, r.root_position)
    assert np.linalg.norm(pos[lh] - targets["LeftHand"].position) < 1e-3
    assert _orientation_error(ori[lh], turn) < 1e-3
    assert _orientation_error(ori[rh], ori0[rh]) < 1e-3
    np.testing.assert_allclose(pos[foot], pos0[foot], atol=1e-9)
    assert _orientation_error(ori[foot], ori0[foot]) < 1e-9


@pytest.mark.parametrize("method", ITERATIVE)
def test_target_weights_trade_competing_targets(walk, method):
    """Both hands pulled far apart (no pose meets either): the spine leans towards the
    heavier target, which ends nearer; the other ends farther."""
    sk = walk.skeleton
    local, root = walk.local_rotations[60], walk.root_positions[60]
    pos0, _ = sk.forward_kinematics(local, root)
    lh, rh = sk.index("LeftHand"), sk.index("RightHand")
    left, right = pos0[lh] + [0.0, 25.0, -10.0], pos0[rh] + [0.0, -25.0, 10.0]

    def errors(weight):
        r = solve(sk, local, root, {"LeftHand": Target(left, weight_position=weight),
                                    "RightHand": right}, method=method, tol=1e-3)
        return np.linalg.norm(r.positions[lh] - left), np.linalg.norm(r.positions[rh] - right)

    light, heavy = errors(0.2), errors(5.0)
    assert heavy[0] < light[0] - 1.0 and heavy[1] > light[1] + 1.0


def test_two_link_says_it_takes_no_orientation():
    arm = chain([1.0, 1.0])
    with pytest.raises(ValueError, match=r"method 'two_link' takes no orientation targets "
                                         r"\(one position, two bones"):
        solve(arm, np.tile([1.0, 0, 0, 0], (3, 1)), np.zeros(3),
              {"end_effector": Target([1.0, 1.0, 0], [1.0, 0, 0, 0])}, method="two_link")
    with pytest.raises(ValueError, match=r"targets\['end_effector'\] weight_orientation"):
        solve(arm, np.tile([1.0, 0, 0, 0], (3, 1)), np.zeros(3),
              {"end_effector": Target([1.0, 1.0, 0], [1.0, 0, 0, 0], weight_orientation=0)})


@pytest.fixture(scope="module")
def walk(shared_bvh_dir):
    from course.bvh import load_bvh

    return load_bvh(shared_bvh_dir / "cmu_12_01_walk.bvh")


# --------------------------------------------------------------------------- IK over a clip
@pytest.fixture(scope="module")
def planted(walk):
    """The whole walk solved with the left foot planted, DLS, warm-started."""
    from course.ik import solve_motion

    return solve_motion(walk, hand_targets(walk), method="dls", root="LeftFoot", tol=1e-3)


def test_solve_motion_plants_the_foot_and_reaches(walk, planted):
    sk = walk.skeleton
    pos, ori = planted.motion.forward_kinematics()
    foot = sk.index("LeftFoot")
    assert np.abs(np.diff(pos[:, foot], axis=0)).max() < 1e-6  # planted: < 1e-6 per frame
    assert max(_orientation_error(ori[0, foot], o) for o in ori[:, foot]) < 1e-9
    np.testing.assert_allclose(pos[0, foot], walk.forward_kinematics()[0][0, foot], atol=1e-9)
    assert planted.converged.all(), np.unique(planted.reasons)
    for name, t in hand_targets(walk).items():
        err = np.linalg.norm(pos[:, sk.index(name)] - t, axis=-1)
        np.testing.assert_allclose(err.max(), planted.residuals.max(), atol=1e-3)
        assert err.max() < 1e-3
    # The hips moved over the foot (root channels rewritten), consistently with FK above.
    assert np.linalg.norm(planted.motion.root_positions - walk.root_positions, axis=1).max() > 1


def test_solve_motion_leaves_joints_off_the_path_untouched(walk, planted):
    sk = walk.skeleton
    on_path = set(planted.joints)
    assert {sk.index(n) for n in ("LeftForeArm", "RightArm", "LeftLeg", "Hips")} <= on_path
    off = [j for j in range(sk.n_joints) if j not in on_path]
    assert sk.index("RightUpLeg") in off and sk.index("Head") in off
    assert np.array_equal(planted.motion.local_rotations[:, off], walk.local_rotations[:, off])
    # Rooted at the hips, the root's channels are the clip's, bit for bit.
    from course.ik import solve_motion

    short = walk[:40]
    hips = solve_motion(short, {"LeftHand": hand_targets(short)["LeftHand"]}, method="ccd",
                        tol=1e-3)
    assert np.array_equal(hips.motion.root_positions, short.root_positions)
    untouched = [j for j in range(sk.n_joints) if j not in hips.joints]
    assert np.array_equal(hips.motion.local_rotations[:, untouched],
                          short.local_rotations[:, untouched])


def test_solved_motion_saves_as_bvh(walk, planted, tmp_path):
    from course.bvh import load_bvh

    path = tmp_path / "planted.bvh"
    planted.motion.save(path)
    back = load_bvh(path)
    names = walk.skeleton.names
    order = [back.skeleton.index(n) for n in names]
    np.testing.assert_allclose(back.forward_kinematics()[0][:, order],
                               planted.motion.forward_kinematics()[0], atol=1e-6)


def test_solve_motion_names_bad_targets(walk):
    from course.ik import solve_motion

    with pytest.raises(ValueError, match=r"targets_per_frame\['LeftHand'\] position: 3 frames"):
        solve_motion(walk[:5], {"LeftHand": np.zeros((3, 3))})
    with pytest.raises(ValueError, match=r"targets\['Nose'\]|Nose"):
        solve_motion(walk[:5], {"Nose": np.zeros((5, 3))})


def test_cold_frames_keep_the_foot_planted_too(walk):
    """``warm_start=False`` solves every frame alone from the clip's pose, moved rigidly onto
    the planted foot: the foot still stays put, and the answers reach as the warm ones."""
    from course.ik import solve_motion

    short = walk[:30]
    cold = solve_motion(short, hand_targets(short), root="LeftFoot", tol=1e-3,
                        warm_start=False)
    pos, _ = cold.motion.forward_kinematics()
    foot = walk.skeleton.index("LeftFoot")
    assert np.abs(pos[:, foot] - pos[0, foot]).max() < 1e-6
    assert cold.converged.all() and cold.residuals.max() < 1e-3


def test_solve_motion_holds_swing_twist_limits_and_says_limits(walk):
    """A shoulder cone over a short clip: every written frame within it, and the frames whose
    target only the cone forbids are reported ``"limits"``."""
    from course.ik import solve_motion

    short = walk[:20]
    sk = short.skeleton
    pos, _ = short.forward_kinematics()
    shoulder = {"LeftArm": SwingTwist(0.4, (-0.3, 0.3))}
    arm, hand = pos[0, sk.index("LeftArm")], pos[0, sk.index("LeftHand")]
    up = arm + [0.0, 0.9 * np.linalg.norm(hand - arm), 0.0]  # the arm raised: a 90° swing
    reach = {"LeftHand": up}
    out = solve_motion(short, reach, root="LeftArm", tol=1e-3, limits=shoulder)
    assert _violation(sk, out.motion.local_rotations, shoulder) <= SLACK
    free = solve_motion(short, reach, root="LeftArm", tol=1e-3)
    assert free.converged.all() and not out.converged.any()
    assert set(out.reasons) == {"limits"}
