"""Edge cases of ``course.ik``: half-turn orientation errors, option validation, honest
reasons. Answers are checked by forward-kinematics residuals against independent references
(scipy's rotation vectors, quaternion distances), never by joint angles."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from course.ik import Target, solve
from course.ik._engine.small import rotvec_from_matrix
from course.rotations import quat_from_rotvec, quat_mul
from course.skeleton import chain

BALL = chain([1.0] * 7)
IDENT = np.tile([1.0, 0, 0, 0], (8, 1))
PLANAR = chain([1.0] * 7, axes=[0, 0, 1])

PROPERTY = settings(max_examples=60, derandomize=True, deadline=None, database=None)


def _angle_between(q1: np.ndarray, q2: np.ndarray) -> float:
    """Rotation angle of q1 q2^-1 (an independent measure: quaternion inner product)."""
    return float(2 * np.arccos(min(1.0, abs(np.dot(q1, q2)))))


# --------------------------------------------------------------------------- rotation vectors
def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


axes = st.tuples(*[st.floats(-1, 1)] * 3).map(np.array).filter(lambda v: np.linalg.norm(v) > .1)


@PROPERTY
@given(axes, st.sampled_from([np.pi, np.pi - 1e-12, np.pi - 1e-9, np.pi - 1e-6, np.pi - 1e-3,
                              3.0, 2.0, np.pi / 2, 1.0, 1e-3, 1e-9, 0.0]))
def test_rotvec_from_matrix_matches_scipy_including_half_turns(axis, angle):
    """Against scipy's as_rotvec on every angle in [0, pi], the exact half turn included (up to
    the sign of the axis, the one ambiguity there: +-pi a are the same rotation)."""
    from scipy.spatial.transform import Rotation

    a = _unit(axis)
    R = Rotation.from_rotvec(angle * a).as_matrix()
    if angle == np.pi:  # exactly: R = 2 a a^T - I, whose antisymmetric part is zero
        R = 2 * np.outer(a, a) - np.eye(3)
    got = rotvec_from_matrix(R[None])[0]
    ref = Rotation.from_matrix(R).as_rotvec()
    if np.pi - angle < 1e-6:
        err = min(np.abs(got - ref).max(), np.abs(got + ref).max())
    else:
        err = np.abs(got - ref).max()
    assert err < 1e-9
    np.testing.assert_allclose(np.linalg.norm(got), angle, atol=1e-9)
    # And it is the rotation itself: Rodrigues of the result gives R back.
    np.testing.assert_allclose(Rotation.from_rotvec(got).as_matrix(), R, atol=1e-12)


def test_rotvec_from_matrix_batched_half_turns_about_random_axes():
    rng = np.random.default_rng(3)
    a = rng.normal(size=(500, 3))
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    R = 2 * a[:, :, None] * a[:, None, :] - np.eye(3)
    got = rotvec_from_matrix(R)
    np.testing.assert_allclose(np.linalg.norm(got, axis=1), np.pi, atol=1e-12)
    np.testing.assert_allclose(np.abs(np.einsum("bi,bi->b", got / np.pi, a)), 1.0, atol=1e-12)


# --------------------------------------------------------------------------- half-turn targets
@pytest.mark.parametrize("method", ["dls", "pseudo_inverse"])
def test_half_turn_orientation_target_is_not_a_false_success(method):
    """The audit's cases: joint2 aimed at a position with a half-turn orientation, and the
    identity pose asked for a half turn. The returned pose must really reach the orientation
    (measured by quaternions, independently of the solver's own error)."""
    for position, q in (([1.0, 1.0, 0.0], [0.0, 1.0, 0.0, 0.0]),
                        ([1.5, 0.5, 0.3], [0.0, 0.0, 1.0, 0.0])):
        r = solve(BALL, IDENT, np.zeros(3), {"joint2": Target(position, q)}, method=method)
        _, ori = BALL.forward_kinematics(r.local_rotations)
        real = _angle_between(ori[2], np.array(q))
        assert r.converged == (real < 1e-4 and np.linalg.norm(r.positions[2] - position) < 1e-4)
        assert r.converged, (r.reason, real)


def test_half_turn_from_start_about_random_axes():
    """Start exactly a half turn away (about a random axis) from a reachable orientation: the
    first residual is pi, and the solve ends on the orientation."""
    rng = np.random.default_rng(4)
    for _ in range(5):
        q = np.tile(IDENT, (1, 1))
        q[:7] = quat_from_rotvec(rng.normal(scale=0.4, size=(7, 3)))
        pos, ori = BALL.forward_kinematics(q)
        start = q.copy()
        axis = _unit(rng.normal(size=3))
        start[4] = quat_mul(start[4], np.r_[0.0, axis])  # joint4's orientation: half a turn off
        r = solve(BALL, start, np.zeros(3), {"joint4": Target(pos[4], ori[4])}, method="dls")
        np.testing.assert_allclose(r.residuals[0], np.pi, atol=1e-9)
        _, got = BALL.forward_kinematics(r.local_rotations)
        assert r.converged and _angle_between(got[4], ori[4]) < 1e-4
        assert np.linalg.norm(r.positions[4] - pos[4]) < 1e-4


@pytest.mark.parametrize("method", ["dls", "pseudo_inverse", "jacobian_transpose"])
def test_orientation_only_target(method):
    for q in ([0.0, 1.0, 0.0, 0.0], [0.5, 0.5, 0.5, 0.5]):
        r = solve(BALL, IDENT, np.zeros(3), {"joint3": Target(None, q)}, method=method)
        _, ori = BALL.forward_kinematics(r.local_rotations)
        assert r.converged and _angle_between(ori[3], np.array(q)) < 1e-4
        np.testing.assert_allclose(r.positions[0], 0.0, atol=1e-12)


# --------------------------------------------------------------------------- option validation
T = np.array([2.0, 3.0, 1.0])


@pytest.mark.parametrize("method, option, value", [
    ("dls", "damping", np.nan), ("dls", "damping", np.inf), ("dls", "damping", -0.1),
    ("pseudo_inverse", "rcond", np.nan), ("pseudo_inverse", "rcond", 2.0),
    ("dls", "max_step", np.nan), ("jacobian_transpose", "max_step", -1.0),
    ("dls", "max_step", 0.0), ("ccd", "max_angle", np.nan), ("ccd", "max_angle", -1.0),
    ("dls", "max_iter", np.nan), ("fabrik", "max_iter", -3), ("ccd", "max_iter", 2.5),
    ("dls", "max_iter", True), ("dls", "tol", np.nan), ("dls", "damping", "big"),
])
def test_bad_option_values_name_the_option(method, option, value):
    with pytest.raises(ValueError, match=option):
        solve(BALL, IDENT, np.zeros(3), {"end_effector": T}, method=method, **{option: value})


def test_edge_option_values_that_are_meaningful():
    """No cap (inf), no damping (0: the undamped step, from a bent pose where it is defined),
    zero iterations, numpy integers."""
    bent = IDENT.copy()
    bent[:7] = quat_from_rotvec(np.tile([0.1, 0.2, 0.3], (7, 1)))
    for method, kwargs in (("dls", {"max_step": np.inf}), ("dls", {"damping": 0.0}),
                           ("ccd", {"max_angle": np.inf}), ("dls", {"max_iter": np.int64(50)})):
        r = solve(BALL, bent, np.zeros(3), {"end_effector": T}, method=method, **kwargs)
        assert r.converged and np.linalg.norm(r.positions[-1] - T) < 1e-4, (method, kwargs)
    r = solve(BALL, IDENT, np.zeros(3), {"end_effector": T}, method="fabrik", max_iter=0)
    assert r.iterations == 0 and r.reason == "max_iterations"


def test_zero_orientation_quaternion_names_the_target():
    with pytest.raises(ValueError, match=r"targets\['joint3'\] orientation"):
        solve(BALL, IDENT, np.zeros(3), {"joint3": Target([1.0, 1.0, 0.0], [0, 0, 0, 0])})


# --------------------------------------------------------------------------- reasons
@pytest.mark.parametrize("method", ["dls", "pseudo_inverse"])
def test_iteration_cap_reports_max_iterations_not_singular(method):
    """A planar arm's Jacobian always has rank 2 (no column moves out of the plane), yet an
    in-plane target is reached: stopped by the cap it was still progressing, so the reason is
    the cap. An out-of-plane target at a reachable distance stalls there: singular."""
    t = np.array([3.0, 4.0, 0.0])
    full = solve(PLANAR, IDENT, np.zeros(3), {"end_effector": t}, method=method)
    assert full.converged and full.iterations > 2
    capped = solve(PLANAR, IDENT, np.zeros(3), {"end_effector": t}, method=method, max_iter=2)
    assert not capped.converged and capped.reason == "max_iterations"
    off = solve(PLANAR, IDENT, np.zeros(3), {"end_effector": [3.0, 2.0, 2.0]}, method=method)
    assert not off.converged and off.reason == "singular"


# --------------------------------------------------------------------------- rank-1 fits
def test_best_rotation_rank_one_is_the_shortest_arc():
    """Collinear offsets (and zero-length ones among them) leave a twist free; the fit takes
    the shortest arc, which keeps the previous twist, alone or in a batch."""
    from course.ik._engine.small import best_rotation, matrix_between

    rng = np.random.default_rng(5)
    B = 12
    a = rng.normal(size=(B, 3))
    b = rng.normal(size=(B, 3))
    scales_u = np.stack([np.ones(B), np.zeros(B), rng.uniform(0.5, 2, B)], 1)  # a zero bone
    u = scales_u[..., None] * a[:, None]
    v = scales_u[..., None] * b[:, None] / np.linalg.norm(b, axis=1)[:, None, None] * \
        np.linalg.norm(a, axis=1)[:, None, None]
    R = best_rotation(u, v)
    np.testing.assert_allclose(R, matrix_between(a, b), atol=1e-12)
    for i in (0, 5):
        np.testing.assert_allclose(best_rotation(u[i:i + 1], v[i:i + 1])[0], R[i], atol=1e-12)
    # A full-rank fit is still Kabsch: it recovers an exact rotation.
    Rt = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    Rt *= np.sign(np.linalg.det(Rt))
    pts = rng.normal(size=(5, 3))
    np.testing.assert_allclose(best_rotation(pts[None], (pts @ Rt.T)[None])[0], Rt, atol=1e-12)


@pytest.fixture(scope="module")
def walk(shared_bvh_dir):
    from course.bvh import load_bvh

    return load_bvh(shared_bvh_dir / "cmu_12_01_walk.bvh")


@pytest.mark.parametrize("root_name, hand", [("LeftFoot", "LeftHand"), ("RightFoot", "RightHand"),
                                             ("LeftFoot", "RightHand")])
def test_cmu_fabrik_batched_equals_single(walk, root_name, hand):
    """The CMU skeleton has ten zero-length bones (LHipJoint, LowerBack, Neck, ...): fits at
    those joints are rank 1. A batch of 9 reaches gives the same poses as 9 single solves, and
    the leg hanging from the hips stays nearly put for a reach of 2 units."""
    sk = walk.skeleton
    local, root = walk.local_rotations[100], walk.root_positions[100]
    pos0, _ = sk.forward_kinematics(local, root)
    rng = np.random.default_rng(6)
    d = rng.normal(size=(9, 3))
    ts = pos0[sk.index(hand)] + 2.0 * d / np.linalg.norm(d, axis=1, keepdims=True)
    batch = solve(sk, local, root, {hand: ts}, method="fabrik", root=root_name)
    other_foot = sk.index("RightFoot" if root_name == "LeftFoot" else "LeftFoot")
    for i, t in enumerate(ts):
        one = solve(sk, local, root, {hand: t}, method="fabrik", root=root_name)
        np.testing.assert_allclose(batch.positions[i], one.positions, atol=1e-9)
        assert one.converged and batch.converged[i]
        pos, _ = sk.forward_kinematics(one.local_rotations, one.root_position)
        np.testing.assert_allclose(pos, one.positions, atol=1e-9)
        assert np.linalg.norm(pos[sk.index(hand)] - t) < 1e-4
        assert np.linalg.norm(pos[other_foot] - pos0[other_foot]) < 2.0


def test_cmu_jacobian_transpose_with_two_effectors(walk):
    """Rooted at the right foot, the left hand and the head pulled at once. Backtracking on
    the summed error (the objective the transpose step descends), not on the largest one,
    lets a step trade a little of one effector's error for much of the other's. Measured: 6 of
    6 within 1e-3 (before: 0 of 6, all 'stalled')."""
    sk = walk.skeleton
    local, root = walk.local_rotations[100], walk.root_positions[100]
    pos0, _ = sk.forward_kinematics(local, root)
    rng = np.random.default_rng(7)
    hits = 0
    for _ in range(6):
        targets = {"LeftHand": pos0[sk.index("LeftHand")] + rng.normal(scale=2, size=3),
                   "Head": pos0[sk.index("Head")] + rng.normal(scale=1, size=3)}
        r = solve(sk, local, root, targets, method="jacobian_transpose", root="RightFoot",
                  tol=1e-3)
        pos, _ = sk.forward_kinematics(r.local_rotations, r.root_position)
        np.testing.assert_allclose(pos[sk.index("RightFoot")], pos0[sk.index("RightFoot")],
                                   atol=1e-9)
        errs = [np.linalg.norm(pos[sk.index(n)] - t) for n, t in targets.items()]
        np.testing.assert_allclose(max(errs), r.error, atol=1e-9)
        assert r.converged == (max(errs) < 1e-3)
        assert r.converged or r.reason == "max_iterations"
        hits += r.converged
    assert hits >= 5


# --------------------------------------------------------------------------- two-link, hinge knee
def test_two_link_hinge_knee_out_of_its_plane():
    """A ball hip and a hinge knee, the knee bent in the yz plane, targets anywhere in reach:
    the leg's plane is chosen from the knee axis (or through the pole), the hip turns the knee
    axis onto its normal, and the analytic answer lands exactly (before: 'max_iterations'
    whenever the target left the knee's current plane)."""
    from course.skeleton import Ball, Fixed, Hinge, Skeleton

    leg = Skeleton(["hip", "knee", "ankle"], [-1, 0, 1], [[0, 0, 0], [0, -4, 0], [0, -3, 0]],
                   {"hip": Ball(), "knee": Hinge((1, 0, 0)), "ankle": Fixed()})
    start = np.tile([1.0, 0, 0, 0], (3, 1))
    start[1] = [np.cos(0.3), np.sin(0.3), 0, 0]  # knee bent by 0.6 rad about x
    rng = np.random.default_rng(9)
    d = rng.normal(size=(40, 3))
    targets = d / np.linalg.norm(d, axis=1, keepdims=True) * rng.uniform(1.2, 6.8, (40, 1))
    for pole in (None, [0.0, -4.0, 5.0]):
        for flip in (False, True):
            batch = solve(leg, start, np.zeros(3), {"ankle": targets}, method="two_link",
                          pole=pole, flip=flip)
            assert batch.converged.all()
            pos, _ = leg.forward_kinematics(batch.local_rotations)
            np.testing.assert_allclose(pos, batch.positions, atol=1e-9)
            np.testing.assert_allclose(pos[:, 2], targets, atol=1e-9)
            np.testing.assert_allclose(np.linalg.norm(pos[:, 1], axis=1), 4.0, atol=1e-9)
            # The knee turns about its own axis only.
            np.testing.assert_allclose(batch.local_rotations[:, 1, 2:], 0.0, atol=1e-12)
            if pole is not None:  # the knee lies in the plane of the hip, target and pole
                n = np.cross(targets, pole)
                np.testing.assert_allclose(np.einsum("bi,bi->b", pos[:, 1], n), 0.0,
                                           atol=1e-9 * np.linalg.norm(n, axis=1).max())
            one = solve(leg, start, np.zeros(3), {"ankle": targets[5]}, method="two_link",
                        pole=pole, flip=flip)
            np.testing.assert_allclose(one.positions, batch.positions[5], atol=1e-9)
