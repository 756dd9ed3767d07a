"""Retargeting: T pose <-> A pose of one hierarchy, and onto skeletons with other proportions.

Checked by invariants independent of the implementation: global bone directions (from forward
kinematics positions), exact round trips, uniformly scaled skeletons giving scaled motion.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from rotation_asserts import assert_quat_equal, random_quats

from course.bvh import load_bvh
from course.foot_sliding import foot_contacts, foot_sliding
from course.motion import Motion
from course.retarget import (
    a_pose_from_t_pose,
    bone_direction_errors,
    compare_rest_poses,
    copy_local_rotations,
    rest_corrections,
    rest_height,
    retarget,
    retarget_rest,
    with_rest_pose,
)
from course.rotations import quat_conjugate, quat_mul, quat_rotate
from course.skeleton import Skeleton

PROPERTY = settings(max_examples=40, derandomize=True, deadline=None, database=None,
                    suppress_health_check=[HealthCheck.too_slow])
TOES = ["LeftToeBase", "RightToeBase"]
# How much faster (cm/s, mean over contact frames) a retargeted foot may slide than the source's
# scaled by the height ratio, where the pelvis shapes differ: CMU 12_01 onto the bundled
# skeleton measures +6.1 (left) and +4.2 cm/s (right) at 30 fps.
SLIDE_BOUND = 8.0


@pytest.fixture(scope="module")
def walk(shared_bvh_dir):
    # Frame 0 is the converter's T pose (a jump to frame 1); then 131 frames at 30 fps.
    return load_bvh(shared_bvh_dir / "cmu_12_01_walk.bvh")[1::4]


@pytest.fixture(scope="module")
def a_pose(walk):
    return a_pose_from_t_pose(walk.skeleton)


def bone_directions(motion: Motion) -> np.ndarray:
    """Unit vectors parent -> joint from FK positions, (F, J-1, 3); NaN for zero bones."""
    P, _ = motion.forward_kinematics()
    d = P[:, 1:] - P[:, motion.skeleton.parents[1:]]
    n = np.linalg.norm(d, axis=-1, keepdims=True)
    return np.where(n > 1e-9, d / np.where(n > 1e-9, n, 1.0), np.nan)


def angle_degrees(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return np.degrees(np.arctan2(np.linalg.norm(np.cross(u, v), axis=-1),
                                 np.einsum("...i,...i->...", u, v)))


def assert_same_bone_directions(a: Motion, b: Motion, atol_degrees: float = 1e-7) -> None:
    da, db = bone_directions(a), bone_directions(b)
    both = ~np.isnan(da[..., 0]) & ~np.isnan(db[..., 0])
    err = angle_degrees(da[both], db[both])
    assert err.size and err.max() <= atol_degrees, f"bones differ by up to {err.max():.3g} deg"


# --------------------------------------------------------------------------- A pose <-> T pose
def test_a_pose_turns_only_the_arms_down(walk, a_pose):
    table = compare_rest_poses(walk.skeleton, a_pose)
    for bone in table:
        arm = any(k in bone.joint for k in ("ForeArm", "Hand", "Thumb"))
        assert bone.length_source == pytest.approx(bone.length_target, abs=1e-12)
        if not arm:
            assert bone.angle_degrees == pytest.approx(0.0, abs=1e-9), bone
    upper = {b.joint: b for b in table}["LeftForeArm"]
    assert upper.angle_degrees == pytest.approx(45.0, abs=1e-9)
    assert upper.direction_target[1] < 0  # turned down, not up
    assert "LeftArm -> LeftForeArm" in str(table)
    assert rest_height(a_pose) == rest_height(walk.skeleton)


def test_t_to_a_and_back_is_the_identity(walk, a_pose):
    there = retarget(walk, a_pose)
    back = retarget(there, walk.skeleton)
    assert_quat_equal(back.local_rotations, walk.local_rotations, atol=1e-9)
    np.testing.assert_allclose(back.root_positions, walk.root_positions, rtol=0, atol=1e-9)
    assert_same_bone_directions(walk, there)
    assert bone_direction_errors(walk, there).max() < 1e-7
    # And the lab's direction: an A-pose clip to T and back.
    again = retarget(retarget(there, walk.skeleton), a_pose)
    assert_quat_equal(again.local_rotations, there.local_rotations, atol=1e-9)


def test_correction_formula_in_local_rotations(walk, a_pose):
    """R'_i = C_p(i)^-1 R_i C_i with C_i l_B = l_A, checked joint by joint."""
    C = rest_corrections(walk.skeleton, a_pose)
    P_t, P_a = walk.skeleton.rest_positions(), a_pose.rest_positions()
    for j in range(1, a_pose.n_joints):
        bone_a, bone_t = P_a[j] - P_a[a_pose.parents[j]], P_t[j] - P_t[a_pose.parents[j]]
        if np.linalg.norm(bone_a) > 1e-9:  # C of the parent turns the A bone onto the T bone
            np.testing.assert_allclose(quat_rotate(C[a_pose.parents[j]], bone_a), bone_t,
                                       atol=1e-12)
    parent_C = np.concatenate([[[1.0, 0, 0, 0]], C[a_pose.parents[1:]]])
    expected = quat_mul(quat_mul(quat_conjugate(parent_C), walk.local_rotations), C)
    assert_quat_equal(retarget(walk, a_pose).local_rotations, expected, atol=1e-12)
    wrong_side = quat_mul(C, quat_mul(walk.local_rotations, quat_conjugate(parent_C)))
    assert np.abs(wrong_side - expected).max() > 0.1  # R C and C R differ


def test_copying_local_rotations_points_the_arms_45_degrees_off(walk, a_pose):
    err = bone_direction_errors(walk, copy_local_rotations(walk, a_pose))
    names = [b.joint for b in compare_rest_poses(walk.skeleton, a_pose)]
    arm = [names.index(n) for n in ("LeftForeArm", "LeftHand", "RightForeArm", "RightHand")]
    np.testing.assert_allclose(err[:, arm], 45.0, atol=1e-7)
    legs = [names.index(n) for n in ("LeftLeg", "RightFoot")]
    assert err[:, legs].max() < 1e-7


def test_retarget_rest_for_the_assignment_matches_retarget(walk, a_pose):
    R = retarget_rest(walk.skeleton.parents, walk.skeleton.offsets, a_pose.offsets,
                      walk.local_rotations)
    assert_quat_equal(R, retarget(walk, a_pose).local_rotations, atol=1e-12)
    assert R.shape == walk.local_rotations.shape


# --------------------------------------------------------------------------- other skeletons
def test_uniformly_scaled_skeleton_gives_the_scaled_motion(walk):
    s = walk.skeleton
    big = Skeleton(s.names, s.parents, 1.3 * s.offsets)
    out = retarget(walk, big)
    np.testing.assert_allclose(out.root_positions, 1.3 * walk.root_positions, rtol=1e-12)
    np.testing.assert_allclose(out.forward_kinematics()[0], 1.3 * walk.forward_kinematics()[0],
                               rtol=0, atol=1e-9)
    before, after = foot_sliding(walk, TOES), foot_sliding(out, TOES)
    np.testing.assert_array_equal(after.contacts, before.contacts)
    np.testing.assert_allclose(after.total_cm, 1.3 * before.total_cm, rtol=1e-9)


def generated_skeleton(walk):
    """Other proportions (legs x1.25, arms x0.8, spine x1.1), no fingers, an extra tail."""
    s = walk.skeleton
    keep = [j for j, n in enumerate(s.names) if not any(k in n for k in ("Thumb", "Finger",
                                                                       "Index"))]
    scale = np.array([1.25 if ("Leg" in n or "Foot" in n or "Toe" in n) else
                      0.8 if ("Arm" in n or "Hand" in n) else 1.1 for n in s.names])
    new_index = {j: k for k, j in enumerate(keep)}
    names = [s.names[j] for j in keep] + ["Tail"]
    parents = [-1] + [new_index[s.parents[j]] for j in keep[1:]] + [0]
    offsets = np.vstack([s.offsets[keep] * scale[keep, None], [[0.0, -0.5, -2.0]]])
    skel = Skeleton(names, parents, offsets)
    return skel, {n: n for n in names if n != "Tail"}


def test_generated_skeleton_with_extra_and_missing_joints(walk):
    target, name_map = generated_skeleton(walk)
    out = retarget(walk, target, name_map)
    # Every mapped bone points as in the source, every frame (one rotating source joint per
    # target bone: the dropped joints are all below the hands).
    assert bone_direction_errors(walk, out, name_map).max() < 1e-7
    ratio = rest_height(target) / rest_height(walk.skeleton)
    np.testing.assert_allclose(out.root_positions, ratio * walk.root_positions, rtol=1e-12)
    # The extra joint keeps its rest pose relative to the hips.
    assert_quat_equal(out.local_rotations[:, -1], [1.0, 0, 0, 0], atol=1e-15)
    # The whole leg, hip joint to toe, is scaled by 1.25 and so is the hip height: the root
    # path and the feet scale together and the feet slide exactly 1.25 times as fast.
    assert ratio == pytest.approx(1.25, rel=1e-12)
    contacts = foot_contacts(walk, TOES)
    before = foot_sliding(walk, TOES)
    after = foot_sliding(out, TOES, contacts=contacts)
    np.testing.assert_array_equal(after.contact_frames, before.contact_frames)
    assert before.contact_frames.min() > 10
    np.testing.assert_allclose(after.mean_cm_per_s, ratio * before.mean_cm_per_s, rtol=1e-9)


def test_cmu_onto_the_bundled_skeleton(walk):
    from course import data

    wave = data.load("wave").skeleton
    name_map = {n: n for n in wave.names if n in walk.skeleton.names}
    name_map |= {"Chest": "Spine1", "Neck": "Neck1", "LeftFoot_end": "LeftToeBase",
                 "RightFoot_end": "RightToeBase"}
    out = retarget(walk, wave, name_map)
    err = bone_direction_errors(walk, out, name_map)
    names = [b.joint for b in compare_rest_poses(walk.skeleton, wave, name_map)]
    limbs = [names.index(n) for n in ("LeftLeg", "LeftFoot", "RightLeg", "RightFoot",
                                      "LeftForeArm", "LeftHand", "RightArm", "RightHand")]
    assert err[:, limbs].max() < 1e-7  # one-to-one chains match exactly
    before = foot_sliding(walk, TOES)
    after = foot_sliding(out, ["LeftFoot_end", "RightFoot_end"],
                         contacts=foot_contacts(walk, TOES))
    ratio = rest_height(wave) / rest_height(walk.skeleton)
    assert np.all(after.mean_cm_per_s <= ratio * before.mean_cm_per_s + SLIDE_BOUND), (after,
                                                                                       before)


# --------------------------------------------------------------------------- errors
@pytest.mark.parametrize(
    ("name_map", "message"),
    [
        ({"Hips": "Hips", "LeftLegg": "LeftLeg"}, "LeftLegg"),
        ({"Hips": "Hips", "LeftLeg": "LeftKnee"}, "LeftKnee"),
        ({"LeftLeg": "LeftLeg"}, "target root 'Hips' must be mapped"),
        ({"Hips": "Hips", "LeftUpLeg": "LeftUpLeg", "LeftLeg": "RightLeg"},
         "target joint 'LeftLeg' .*'LeftUpLeg'.* maps to source 'RightLeg'"),
        ({"Hips": "Hips", "LeftUpLeg": "LeftLeg", "LeftLeg": "LeftUpLeg"}, "'LeftLeg'"),
    ],
)
def test_bad_name_maps_name_the_joint(walk, name_map, message):
    with pytest.raises(ValueError, match=message):
        retarget(walk, walk.skeleton, name_map)


def test_other_errors_name_the_argument(walk):
    other = Skeleton(["root", "a"], [-1, 0], [[0, 0, 0], [0, -1, 0]])
    with pytest.raises(ValueError, match="name_map: the skeletons' joint names differ"):
        retarget(walk, other)
    with pytest.raises(ValueError, match="arms: .*'LeftArmm'"):
        a_pose_from_t_pose(walk.skeleton, arms=["LeftArmm"])
    leg = Skeleton(["h", "LeftUpLeg", "k"], [-1, 0, 1], [[0, 0, 0], [1, 0, 0], [0, -2, 0]])
    with pytest.raises(ValueError, match="arms: the bone below 'LeftUpLeg'"):
        a_pose_from_t_pose(leg, arms=["LeftUpLeg"])
    with pytest.raises(ValueError, match="arms: joint 'k' has no bone below it"):
        a_pose_from_t_pose(leg, arms=["k"])
    with pytest.raises(ValueError, match="local_rotations"):
        with_rest_pose(walk.skeleton, np.ones((3, 4)))


STICK = ([-1, 0, 1, 2], [[0, 0, 0], [0, 1, 0], [0, 1, 0], [0, 1, 0]],
         [[0, 0, 0], [1, 0, 0], [1, 0, 0], [1, 0, 0]])  # parents, a rest pose up, one along x


@pytest.mark.parametrize(("change", "message"), [
    ({3: [3.0, 0, 0, 0]}, r"local_quats: the quaternion of joint 3 at index \(3,\) has norm 3, "
                          "not 1"),
    ({1: [0.0, 0, 0, 0]}, r"local_quats: the quaternion of joint 1 .* has norm 0"),
    ({2: [np.nan, 0, 0, 0]}, "local_quats: contains NaN or infinity"),
])
def test_retarget_rest_refuses_rotations_that_are_not_unit_naming_the_joint(change, message):
    """As forward kinematics does: a norm-3 rotation was taken, and scaled the bones below it
    (3, 27, 243 ... down a chain); a zero or NaN one failed naming an internal ``a``."""
    R = np.tile([1.0, 0, 0, 0], (4, 1))
    for j, q in change.items():
        R[j] = q
    with pytest.raises(ValueError, match=message):
        retarget_rest(*STICK, R)


@pytest.mark.parametrize(("args", "message"), [
    (("abc", *STICK[1:], np.tile([1.0, 0, 0, 0], (4, 1))), "parents: expected a non-empty"),
    ((*STICK[:2], "abc", np.tile([1.0, 0, 0, 0], (4, 1))), "offsets_to: expected numbers, got "
                                                           "strings"),
    ((STICK[0], np.zeros((3, 3)), *STICK[2:], np.tile([1.0, 0, 0, 0], (4, 1))),
     r"offsets_from: expected shape \(4, 3\), one bone per joint, got \(3, 3\)"),
    ((*STICK, "1, 0, 0, 0"), "local_quats: expected numbers, got strings"),
    ((*STICK, [["1", "0", "0", "0"]] * 4), "local_quats: expected numbers, got strings"),
])
def test_retarget_rest_names_the_bad_argument(args, message):
    with pytest.raises(ValueError, match=message):
        retarget_rest(*args)


def test_bone_direction_errors_without_a_comparable_bone_says_so(walk):
    """Only the root mapped: no bone between two mapped joints (was numpy's "not enough values
    to unpack")."""
    with pytest.raises(ValueError, match=r"name_map: no bone to compare: .*\(mapped: \['Hips'\]"):
        bone_direction_errors(walk[:2], walk[:2], {"Hips": "Hips"})


# --------------------------------------------------------------------------- random trees
def random_tree(rng: np.random.Generator) -> Skeleton:
    n = int(rng.integers(2, 10))
    parents = [-1] + [int(rng.integers(0, j)) for j in range(1, n)]
    offsets = rng.normal(size=(n, 3))
    zero = rng.random(n) < 0.15  # zero-length bones, as CMU's hip and shoulder joints
    zero[:2] = False  # the root's offset is no bone; keep one bone to compare
    offsets[zero] = 0.0
    return Skeleton([f"j{j}" for j in range(n)], parents, offsets)


@PROPERTY
@given(st.integers(0, 2**32 - 1))
def test_random_trees_and_rest_poses(seed):
    rng = np.random.default_rng(seed)
    source = random_tree(rng)
    n = source.n_joints
    # Another rest pose of the same tree, with other bone lengths.
    target = with_rest_pose(source, random_quats(rng, (n,)))
    target = Skeleton(target.names, target.parents,
                      target.offsets * rng.uniform(0.5, 2.0, size=(n, 1)))
    clip = Motion(source, random_quats(rng, (4, n)), rng.normal(size=(4, 3)), 1 / 30)
    out = retarget(clip, target, scale_root=False)
    assert_same_bone_directions(clip, out)
    np.testing.assert_allclose(out.root_positions, clip.root_positions, atol=0)
    back = retarget(out, source, scale_root=False)
    assert_quat_equal(back.local_rotations, clip.local_rotations, atol=1e-9)
    assert_quat_equal(retarget_rest(source.parents, source.offsets, target.offsets,
                                    clip.local_rotations), out.local_rotations, atol=1e-12)


@PROPERTY
@given(st.integers(0, 2**32 - 1), st.floats(0.01, 10.0).filter(lambda s: abs(s - 1) > 1e-4))
def test_property_retarget_rest_names_the_first_rotation_that_is_not_unit(seed, scale):
    rng = np.random.default_rng(seed)
    source = random_tree(rng)
    n = source.n_joints
    R = random_quats(rng, (3, n))
    f, j = int(rng.integers(3)), int(rng.integers(n))
    R[f, j] *= scale
    with pytest.raises(ValueError, match=rf"local_quats: the quaternion of joint {j} at index "
                                         rf"\({f}, {j}\) has norm {scale:.6g}, not 1"):
        retarget_rest(source.parents, source.offsets, source.offsets, R)
