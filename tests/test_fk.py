"""Forward kinematics against an independent scipy reference, re-rooting, and the inverse."""

from __future__ import annotations

import numpy as np
import pytest
from rotation_asserts import random_quats
from scipy.spatial.transform import Rotation

from course.fk import forward_kinematics, local_from_global
from course.skeleton import Skeleton


def random_tree(rng: np.random.Generator, n: int) -> tuple[list[int], np.ndarray]:
    parents = [-1] + [int(rng.integers(0, j)) for j in range(1, n)]
    offsets = rng.normal(size=(n, 3))
    offsets[rng.random(n) < 0.3, rng.integers(0, 3)] = 0.0  # bones with zero components
    offsets[rng.integers(1, n)] = 0.0  # a zero-length bone
    return parents, offsets


def matrices(q: np.ndarray) -> np.ndarray:
    return Rotation.from_quat(q.reshape(-1, 4), scalar_first=True).as_matrix().reshape(
        q.shape[:-1] + (3, 3)
    )


def reference_fk(parents, offsets, local, root_position):
    """The lecture's recursion with rotation matrices, frame by frame in plain loops."""
    Rm = matrices(local)
    L = np.broadcast_to(offsets, local.shape[:-1] + (3,))
    M = np.zeros(Rm.shape)
    P = np.zeros(local.shape[:-1] + (3,))
    M[..., 0, :, :] = Rm[..., 0, :, :]
    P[..., 0, :] = root_position
    for j in range(1, len(parents)):
        p = parents[j]
        M[..., j, :, :] = M[..., p, :, :] @ Rm[..., j, :, :]
        P[..., j, :] = P[..., p, :] + np.einsum("...ab,...b->...a", M[..., p, :, :], L[..., j, :])
    return P, M


@pytest.mark.parametrize("seed", range(6))
def test_matches_scipy_reference_on_random_trees(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 25))
    parents, offsets = random_tree(rng, n)
    local = random_quats(rng, (3, 5, n))
    root = rng.normal(size=(3, 5, 3))
    P, Q = forward_kinematics(parents, offsets, local, root)
    P_ref, M_ref = reference_fk(parents, offsets, local, root)
    assert P.shape == (3, 5, n, 3) and Q.shape == (3, 5, n, 4)
    np.testing.assert_allclose(P, P_ref, atol=1e-9)
    np.testing.assert_allclose(matrices(Q), M_ref, atol=1e-9)


def test_single_pose_per_frame_offsets_and_broadcasting():
    rng = np.random.default_rng(10)
    parents, offsets = random_tree(rng, 9)
    local = random_quats(rng, (4, 9))
    per_frame = offsets + rng.normal(scale=0.1, size=(4, 9, 3))
    P, Q = forward_kinematics(parents, per_frame, local, [1.0, 2.0, 3.0])
    P_ref, M_ref = reference_fk(parents, per_frame, local, np.array([1.0, 2.0, 3.0]))
    np.testing.assert_allclose(P, P_ref, atol=1e-9)
    np.testing.assert_allclose(matrices(Q), M_ref, atol=1e-9)
    # One pose: no leading dimensions in, none out; the root position defaults to the origin.
    P1, Q1 = forward_kinematics(parents, offsets, local[0])
    P1_ref, _ = reference_fk(parents, offsets, local[0], np.zeros(3))
    assert P1.shape == (9, 3) and Q1.shape == (9, 4)
    np.testing.assert_allclose(P1, P1_ref, atol=1e-9)


def test_local_from_global_inverts_forward_kinematics():
    rng = np.random.default_rng(11)
    parents, offsets = random_tree(rng, 15)
    local = random_quats(rng, (6, 15))
    _, Q = forward_kinematics(parents, offsets, local, np.zeros(3))
    back = local_from_global(parents, Q)
    np.testing.assert_allclose(matrices(back), matrices(local), atol=1e-12)
    _, Q2 = forward_kinematics(parents, offsets, back, np.zeros(3))
    np.testing.assert_allclose(Q2, Q, atol=1e-12)


@pytest.mark.parametrize("seed", range(4))
def test_rerooted_fk_reproduces_every_joint(seed):
    rng = np.random.default_rng(20 + seed)
    parents, offsets = random_tree(rng, 14)
    local = random_quats(rng, (5, 14))
    root = rng.normal(size=(5, 3))
    P, Q = forward_kinematics(parents, offsets, local, root)
    for k in range(14):
        Pk, Qk = forward_kinematics(
            parents, offsets, local, P[:, k], root=k, root_orientation=Q[:, k]
        )
        np.testing.assert_allclose(Pk, P, atol=1e-9)
        np.testing.assert_allclose(matrices(Qk), matrices(Q), atol=1e-9)
        # Default orientation: the one from ordinary FK of the same local rotations.
        Pd, Qd = forward_kinematics(parents, offsets, local, P[:, k], root=k)
        np.testing.assert_allclose(Pd, P, atol=1e-9)
        np.testing.assert_allclose(matrices(Qd), matrices(Q), atol=1e-9)


def test_rerooted_fk_is_a_rigid_motion_of_ordinary_fk():
    # Any root pose: ordinary FK moved rigidly so that joint k lands on (position, orientation).
    rng = np.random.default_rng(30)
    parents, offsets = random_tree(rng, 12)
    local = random_quats(rng, (4, 12))
    P, Q = forward_kinematics(parents, offsets, local, np.zeros(3))
    k = 7
    target_p, target_q = rng.normal(size=(4, 3)), random_quats(rng, (4,))
    Pk, Qk = forward_kinematics(
        parents, offsets, local, target_p, root=k, root_orientation=target_q
    )
    A = matrices(target_q) @ np.swapaxes(matrices(Q[:, k]), -1, -2)
    expect_p = np.einsum("fab,fjb->fja", A, P - P[:, k : k + 1]) + target_p[:, None]
    np.testing.assert_allclose(Pk, expect_p, atol=1e-9)
    np.testing.assert_allclose(matrices(Qk), A[:, None] @ matrices(Q), atol=1e-9)


def test_pinned_joint_stays_and_bones_keep_their_length():
    rng = np.random.default_rng(40)
    parents, offsets = random_tree(rng, 16)
    skel = Skeleton([f"j{i}" for i in range(16)], parents, offsets)
    foot = skel.end_effectors[0]
    pose = random_quats(rng, (16,))
    pin_p, pin_q = skel.pin(foot, pose, [0.0, 1.0, 0.0])
    for _ in range(5):
        new = random_quats(rng, (16,))
        P, Q = skel.forward_kinematics(new, pin_p, root=foot, root_orientation=pin_q)
        np.testing.assert_allclose(P[foot], pin_p, atol=1e-12)
        np.testing.assert_allclose(Q[foot], pin_q, atol=1e-12)
        lengths = np.linalg.norm(P[1:] - P[np.asarray(parents)[1:]], axis=-1)
        np.testing.assert_allclose(lengths, skel.bone_lengths[1:], atol=1e-9)
    # Pinning under a re-rooted pose reads that pose.
    P, _ = skel.forward_kinematics(pose, pin_p, root=foot, root_orientation=pin_q)
    p3, _ = skel.pin(3, pose, pin_p, root=foot, root_orientation=pin_q)
    np.testing.assert_allclose(p3, P[3], atol=1e-12)


@pytest.mark.parametrize("n_frames", [1, 3, 8, 9, 12])
def test_one_frame_at_a_time_and_all_frames_at_once_agree(n_frames):
    # Few frames take the Python-float path, more the component-major numpy path.
    rng = np.random.default_rng(50 + n_frames)
    parents, offsets = random_tree(rng, 10)
    local = random_quats(rng, (n_frames, 10))
    root = rng.normal(size=(n_frames, 3))
    per_frame = offsets + rng.normal(size=(n_frames, 10, 3))
    for k, q0 in [(0, None), (6, None), (6, random_quats(rng, (n_frames,)))]:
        for L in (offsets, per_frame):
            P, Q = forward_kinematics(parents, L, local, root, root=k, root_orientation=q0)
            one = [
                forward_kinematics(
                    parents, L if L.ndim == 2 else L[f], local[f], root[f], root=k,
                    root_orientation=None if q0 is None else q0[f],
                )
                for f in range(n_frames)
            ]
            np.testing.assert_allclose(P, [p for p, _ in one], atol=1e-12)
            np.testing.assert_allclose(Q, [q for _, q in one], atol=1e-12)


def test_results_are_independent_arrays_and_empty_batch_works():
    rng = np.random.default_rng(60)
    parents, offsets = random_tree(rng, 6)
    local = random_quats(rng, (7, 6))
    P, Q = forward_kinematics(parents, offsets, local, np.zeros(3))
    P2, Q2 = forward_kinematics(parents, offsets, local, np.zeros(3))
    assert not np.shares_memory(P, Q) and not np.shares_memory(P, P2)
    P[:] = 0
    np.testing.assert_array_equal(Q, Q2)
    P, Q = forward_kinematics(parents, offsets, np.zeros((0, 6, 4)), np.zeros(3))
    assert P.shape == (0, 6, 3) and Q.shape == (0, 6, 4)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"local_rotations": np.ones((2, 4, 4)) / 2}, r"rotations: expected shape \(\.\.\., 3, 4"),
        ({"local_rotations": np.tile([2.0, 0, 0, 0], (3, 1))}, r"joint 'b' \(index 0\).*norm 2"),
        ({"local_rotations": np.tile([np.nan, 0, 0, 0], (3, 1))}, "NaN"),
        ({"offsets": np.zeros((4, 3))}, r"offsets: expected shape \(3, 3\)"),
        ({"root_position": [0.0, 1.0]}, "root_position"),
        ({"root": 3}, "root: expected a joint index"),
        ({"root_orientation": [0.5, 0, 0, 0], "root": 1}, r"root_orientation.*'c' \(index 1\)"),
        ({"parents": [-1, 0, 2]}, r"joint 'd' \(index 2\).*parent-before-child"),
        ({"parents": [-1, -1, 0]}, r"joint 'c' \(index 1\).*exactly one root"),
    ],
)
def test_bad_input_names_argument_and_joint(kwargs, message):
    args = {
        "parents": [-1, 0, 1],
        "offsets": np.ones((3, 3)),
        "local_rotations": np.tile([1.0, 0, 0, 0], (3, 1)),
        "root_position": np.zeros(3),
        "names": ["b", "c", "d"],
    } | kwargs
    with pytest.raises(ValueError, match=message):
        forward_kinematics(**args)


@pytest.mark.parametrize("batch", [(2, 5), (1, 1), ()])
def test_bad_rotation_is_reported_with_its_frame(batch):
    local = np.tile([1.0, 0, 0, 0], batch + (3, 1))
    local[..., 2, :] = [1.0, 1.0, 0, 0]
    where = (0,) * len(batch) + (2,)
    with pytest.raises(ValueError, match=rf"joint 2 at index \({', '.join(map(str, where))},?\)"):
        forward_kinematics([-1, 0, 1], np.ones((3, 3)), local, np.zeros(3))
