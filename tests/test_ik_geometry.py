"""Chain-level IK building blocks: two-link geometry, Jacobians, pseudo-inverses, FABRIK and
CCD on points. Checked against the law of cosines, finite differences and numpy.linalg.pinv."""

from __future__ import annotations

import numpy as np
import pytest

from course.ik import (
    ccd_positions,
    chain_jacobian,
    dls_step,
    fabrik_batch,
    fabrik_positions,
    finite_difference_jacobian,
    pinv_step,
    pinv_svd,
    pinv_tall,
    pinv_wide,
    transpose_step,
    two_link,
)
from course.ik._engine.tree import build_model
from course.rotations import matrix_from_quat, quat_from_rotvec


def _bones(P: np.ndarray) -> np.ndarray:
    return np.linalg.norm(np.diff(P, axis=-2), axis=-1)


# --------------------------------------------------------------------------- two-link
def test_two_link_law_of_cosines_and_pole_plane():
    rng = np.random.default_rng(1)
    for _ in range(50):
        a, b, c = rng.normal(size=(3, 3))
        l1, l2 = np.linalg.norm(b - a), np.linalg.norm(c - b)
        d = rng.uniform(abs(l1 - l2) + 1e-3, l1 + l2 - 1e-3)
        u = rng.normal(size=3)
        u /= np.linalg.norm(u)
        t = a + d * u
        pole = rng.normal(size=3) * 3
        nb, nc, ok = two_link(a, b, c, t, pole)
        assert ok
        np.testing.assert_allclose(nc, t, atol=1e-12)
        np.testing.assert_allclose([np.linalg.norm(nb - a), np.linalg.norm(nc - nb)], [l1, l2])
        # The middle joint's inner angle follows the law of cosines.
        cos_beta = np.dot(a - nb, nc - nb) / (l1 * l2)
        np.testing.assert_allclose(cos_beta, (l1**2 + l2**2 - d**2) / (2 * l1 * l2), atol=1e-12)
        # It lies in the plane of the root-target axis and the pole, on the pole's side.
        n = np.cross(t - a, pole - a)
        assert abs(np.dot(nb - a, n)) < 1e-9 * np.linalg.norm(n)
        perp = (pole - a) - np.dot(pole - a, u) * u
        assert np.dot(nb - a, perp) > 0
        fb, fc, _ = two_link(a, b, c, t, pole, flip=True)  # the mirror solution
        np.testing.assert_allclose(fc, t, atol=1e-12)
        assert np.dot(fb - a, perp) < 0
        n_hat = perp / np.linalg.norm(perp)
        mirrored = nb - 2 * np.dot(nb - a, n_hat) * n_hat
        np.testing.assert_allclose(fb, mirrored, atol=1e-9)


def test_two_link_unreachable_straight_or_folded_and_degenerate():
    a, b, c = np.zeros(3), np.array([2.0, 0, 0]), np.array([2.0, 1.0, 0])
    nb, nc, ok = two_link(a, b, c, [10.0, 5.0, 0])
    assert not ok
    u = np.array([10.0, 5.0, 0]) / np.linalg.norm([10.0, 5.0, 0])
    np.testing.assert_allclose(nb, 2 * u, atol=1e-12)
    np.testing.assert_allclose(nc, 3 * u, atol=1e-12)
    nb, nc, ok = two_link(a, b, c, [0.2, 0, 0])  # closer than |l1 - l2| = 1: folded
    assert not ok
    np.testing.assert_allclose(np.linalg.norm(nc - a), 1.0)
    np.testing.assert_allclose(np.linalg.norm(nb - nc), 1.0)
    for t in (a, [2.0, 0, 0], [3.0, 0, 0]):  # on the root, on the straight chain's line
        nb, nc, _ = two_link(a, b, [4.0, 0, 0], t)
        assert np.all(np.isfinite(nb)) and np.all(np.isfinite(nc))
        np.testing.assert_allclose([np.linalg.norm(nb), np.linalg.norm(nc - nb)], [2.0, 2.0])


# --------------------------------------------------------------------------- Jacobians
def _hinge_chain_fk(theta, axes, bones):
    """Independent reference: matrices by scipy, positions p_i = p_{i-1} + Q_{i-1} l_i."""
    from scipy.spatial.transform import Rotation

    Q = np.eye(3)
    p = [np.zeros(3)]
    for a, th, bone in zip(axes, theta, bones, strict=True):
        Q = Q @ Rotation.from_rotvec(np.asarray(a) * th).as_matrix()
        p.append(p[-1] + Q @ bone)
    return np.array(p)


def test_chain_jacobian_matches_finite_differences():
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(2)
    axes = np.array([[0, 1, 0], [0, 0, 1], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    bones = rng.normal(size=(5, 3))
    theta = rng.uniform(-2, 2, 5)
    P = _hinge_chain_fk(theta, axes, bones)
    # World axes after the preceding rotations: a_i^w = Q_{i-1} R_i a_i = Q_{i-1} a_i.
    Q, world = np.eye(3), []
    for a, th in zip(axes, theta, strict=True):
        world.append(Q @ a)
        Q = Q @ Rotation.from_rotvec(a * th).as_matrix()
    J = chain_jacobian(P[:-1], np.array(world), P[-1])
    Jfd = finite_difference_jacobian(lambda t: _hinge_chain_fk(t, axes, bones)[-1], theta)
    np.testing.assert_allclose(J, Jfd, atol=1e-6)


@pytest.mark.parametrize("root_name", ["Hips", "LeftFoot", "RightArm"])
def test_model_jacobian_matches_finite_differences_rerooted(shared_bvh_dir, root_name):
    """Ball columns a x (e - r_i) on a re-rooted CMU skeleton, up and down edges, with an
    orientation target: the analytic Jacobian against central differences of the step."""
    from course.bvh import load_bvh
    from course.rotations import matrix_from_quat

    motion = load_bvh(shared_bvh_dir / "cmu_12_01_walk.bvh")
    sk = motion.skeleton
    k = sk.index(root_name)
    eff = [sk.index("LeftHand"), sk.index("RightToeBase")]
    eff = [e for e in eff if e != k]
    model = build_model(sk.parents, sk.offsets, [None] * sk.n_joints, k, eff,
                        [sk.index("LeftHand")])
    local = motion.local_rotations[100]
    Rn = np.broadcast_to(np.eye(3), (1, model.n_nodes, 3, 3)).copy()
    has = model.edge_joint >= 0
    Rn[0, has] = matrix_from_quat(local[model.edge_joint[has]])
    base = matrix_from_quat(quat_from_rotvec([0.3, -0.2, 0.5]))[None]
    p0 = np.array([[1.0, 2.0, 3.0]])
    M, p = model.forward(Rn, base, p0)
    J = model.jacobian(M, p, base)

    def effect(delta):
        M2, p2 = model.forward(model.step(Rn, M, base, delta[None]), base, p0)
        rot = M2[0, model.rot_effectors] @ np.swapaxes(M[0, model.rot_effectors], -1, -2)
        from course.rotations._kernels import rotvec_from_matrix

        return np.concatenate([p2[0, model.effectors].ravel(), rotvec_from_matrix(rot).ravel()])

    Jfd = finite_difference_jacobian(effect, np.zeros(model.n_cols))
    np.testing.assert_allclose(J[0], Jfd, atol=1e-6 * max(1.0, np.abs(J).max()))


# --------------------------------------------------------------------------- pseudo-inverse
def test_pseudo_inverse_forms_match_numpy():
    rng = np.random.default_rng(3)
    wide = rng.normal(size=(4, 3, 7))
    tall = rng.normal(size=(4, 9, 5))
    np.testing.assert_allclose(pinv_wide(wide), np.linalg.pinv(wide), atol=1e-10)
    np.testing.assert_allclose(pinv_tall(tall), np.linalg.pinv(tall), atol=1e-10)
    np.testing.assert_allclose(pinv_svd(wide), np.linalg.pinv(wide), atol=1e-10)
    np.testing.assert_allclose(pinv_svd(tall), np.linalg.pinv(tall), atol=1e-10)
    rank1 = np.outer([1.0, 2, 3], [1.0, 0, 1, 0])
    np.testing.assert_allclose(pinv_svd(rank1), np.linalg.pinv(rank1, rcond=1e-6), atol=1e-12)
    # Ill-conditioned (singular values 1, 1e-3, 1e-7): both forms are computed from the SVD,
    # not by inverting JJ^T or J^TJ (whose condition number, 1e14, costs ~5e-3 relative here).
    U = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    V = np.linalg.qr(rng.normal(size=(7, 7)))[0][:, :3]
    J = U @ np.diag([1.0, 1e-3, 1e-7]) @ V.T
    for form, A in ((pinv_wide, J), (pinv_tall, J.T)):
        ref = np.linalg.pinv(A, rcond=1e-15)
        assert np.abs(form(A) - ref).max() < 1e-7 * np.abs(ref).max()
    e = rng.normal(size=(4, 3))
    np.testing.assert_allclose(pinv_step(wide, e), np.einsum("bij,bj->bi", np.linalg.pinv(wide), e),
                               atol=1e-10)


def test_dls_and_transpose_steps():
    rng = np.random.default_rng(4)
    J, e = rng.normal(size=(3, 6)), rng.normal(size=3)
    lam, W = 0.3, rng.uniform(0.5, 2.0, 6)
    # DLS minimises |J x - e|^2 + lam^2 |W x|^2: normal equations (J^T J + lam^2 W^2) x = J^T e.
    x = dls_step(J, e, lam, W)
    np.testing.assert_allclose((J.T @ J + lam**2 * np.diag(W**2)) @ x, J.T @ e, atol=1e-10)
    np.testing.assert_allclose(dls_step(J, e, 1e-9), np.linalg.pinv(J) @ e, atol=1e-6)
    heavy = dls_step(J, e, lam, np.where(np.arange(6) == 2, 100.0, 1.0))
    assert abs(heavy[2]) < 1e-2 * np.abs(heavy).max()
    step = transpose_step(J, e)  # Buss's alpha: the exact line search along g = J^T e
    g = J.T @ e
    alpha = step @ g / (g @ g)
    np.testing.assert_allclose(step, alpha * g, atol=1e-12)
    np.testing.assert_allclose((e - J @ step) @ (J @ g), 0.0, atol=1e-12)  # stationary in alpha
    assert np.linalg.norm(e - J @ step) < np.linalg.norm(e)


def test_dls_bounded_near_singularity_where_pinv_explodes():
    # A straight 3-bone planar chain along x: no joint moves the tip along x.
    P = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]]) + [[0, 0, 0]] * 4
    P[2, 1] = 1e-6  # almost straight
    axes = np.tile([0.0, 0, 1], (3, 1))
    J = chain_jacobian(P[:-1], axes, P[-1])[:2]  # planar rows x, y
    e = np.array([0.5, 0.0])  # ask the tip to move along the chain
    plain = np.linalg.pinv(J) @ e
    damped = dls_step(J, e, 0.1)
    assert np.abs(plain).max() > 1e4
    assert np.abs(damped).max() < 10.0


# --------------------------------------------------------------------------- FABRIK / CCD on points
def test_fabrik_positions_reach_keep_bones_and_root():
    rng = np.random.default_rng(5)
    n = 10
    P0 = np.cumsum(np.vstack([np.zeros(3), rng.normal(size=(n - 1, 3))]), axis=0)
    reach = _bones(P0).sum()
    dirs = rng.normal(size=(200, 3))
    targets = P0[0] + dirs / np.linalg.norm(dirs, axis=1, keepdims=True) * rng.uniform(
        0.1, 0.9, (200, 1)) * reach
    P, its, err = fabrik_batch(P0, targets)
    assert P.shape == (200, n, 3)
    assert (err < 1e-4).mean() >= 0.99
    np.testing.assert_allclose(_bones(P), np.broadcast_to(_bones(P0), (200, n - 1)), atol=1e-9)
    np.testing.assert_allclose(P[:, 0], np.broadcast_to(P0[0], (200, 3)), atol=1e-12)
    one, _, e1 = fabrik_positions(P0, targets[0])
    np.testing.assert_allclose(one, P[0], atol=1e-12)


def test_fabrik_unreachable_one_pass_straight():
    P0 = np.array([[0.0, 0, 0], [1, 0, 0], [1, 2, 0], [1, 2, 2]])
    t = np.array([0.0, 0, 10.0])
    P, its, err = fabrik_positions(P0, t)
    assert its == 1
    np.testing.assert_allclose(P, [[0, 0, 0], [0, 0, 1], [0, 0, 3], [0, 0, 5]], atol=1e-12)
    np.testing.assert_allclose(err, 5.0)


def test_fabrik_and_ccd_degenerate_no_nan():
    straight = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0], [2, 0, 0], [3, 0, 0]])  # zero bone
    for t in ([0.0, 0, 0], [1.5, 0, 0], [-1.0, 0, 0], [2.0, 1.0, 0]):
        P, _, _ = fabrik_positions(straight, t)
        assert np.all(np.isfinite(P))
        np.testing.assert_allclose(_bones(P), _bones(straight), atol=1e-9)
        Q, _, _ = ccd_positions(straight, t, max_iter=20)
        assert np.all(np.isfinite(Q))
        np.testing.assert_allclose(_bones(Q), _bones(straight), atol=1e-9)


def test_ccd_positions_reach():
    rng = np.random.default_rng(6)
    P0 = np.vstack([np.zeros(3), np.cumsum(np.tile([1.0, 0, 0], (5, 1)), 0)])
    reached = 0
    for _ in range(20):
        d = rng.normal(size=3)
        t = d / np.linalg.norm(d) * rng.uniform(0.5, 4.5)
        P, sweeps, err = ccd_positions(P0, t, max_iter=500)
        reached += err < 1e-4
        np.testing.assert_allclose(_bones(P), 1.0, atol=1e-9)
    assert reached >= 18  # CCD can crawl near full extension; see test_ik_solvers for rates


def test_ccd_and_fabrik_batches_are_their_single_solves():
    """The lecture loops are batched: each row of a batch (chains of different shapes, a zero
    bone, a target on the root, out of reach, one already reached) is exactly the single
    solve of that chain, sweeps/iterations and errors included, and keeps its bones."""
    rng = np.random.default_rng(8)
    P = np.cumsum(rng.normal(size=(12, 5, 3)), axis=1)
    P[3, 2] = P[3, 1]
    t = rng.normal(size=(12, 3)) * 3
    t[5], t[6], t[7] = P[5, 0], P[6, -1], P[7, 0] + 50.0
    for solver in (ccd_positions, fabrik_positions):
        Pb, its, err = solver(P, t, 1e-6, 40)
        assert Pb.shape == P.shape and its.shape == err.shape == (12,)
        np.testing.assert_allclose(_bones(Pb), _bones(P), atol=1e-9)
        for i in range(12):
            one = solver(P[i], t[i], 1e-6, 40)
            np.testing.assert_array_equal(Pb[i], one[0])
            assert its[i] == one[1] and err[i] == one[2]
    assert ccd_positions(P[0], t[0])[1].__class__ is int


def test_quat_between_matches_matrix_between_including_opposite_and_zero():
    """The serial path's shortest arc (quaternion components, floats and arrays) is the general
    path's matrix_between: generic pairs, exactly opposite pairs (a half turn about the same
    perpendicular axis) and a zero vector (the identity)."""
    from course.ik._engine.components import quat_between
    from course.ik._engine.ops import ARRAYS, FLOATS
    from course.rotations._kernels import matrix_between

    rng = np.random.default_rng(21)
    u = rng.normal(size=(12, 3))
    v = rng.normal(size=(12, 3))
    v[:4] = -2.5 * u[:4]  # opposite, u in every orientation
    u[4] = [3.0, 0.1, -0.2]
    v[4] = -u[4]  # opposite along x
    u[5] = 0.0
    v[6] = 0.0
    want = matrix_between(u, v)
    q = np.stack(quat_between(tuple(u.T), tuple(v.T), ARRAYS), -1)
    np.testing.assert_allclose(np.linalg.norm(q, axis=-1), 1.0, atol=1e-12)
    np.testing.assert_allclose(matrix_from_quat(q), want, atol=1e-9)
    for i in range(len(u)):
        one = quat_between(tuple(u[i].tolist()), tuple(v[i].tolist()), FLOATS)
        np.testing.assert_allclose(one, q[i], atol=1e-12)
