"""course.keyframes.motion and .blend: keyframed clips, alignment, cross-fades (their foot
sliding: tests/test_foot_sliding.py)."""

from __future__ import annotations

import numpy as np
import pytest
from rotation_asserts import assert_quat_equal

from course import data
from course import keyframes as kf
from course import rotations as rot
from course.bvh import load_bvh
from course.motion import Motion


@pytest.fixture(scope="module")
def walk(shared_bvh_dir):
    return load_bvh(shared_bvh_dir / "cmu_12_01_walk.bvh")[1:]  # frame 0 is a T-pose


@pytest.fixture(scope="module")
def wave():
    return data.load("wave")


# --------------------------------------------------------------------------- keyframing
def test_key_frames_include_the_last():
    assert kf.key_frames(10, 3).tolist() == [0, 3, 6, 9]
    assert kf.key_frames(11, 3).tolist() == [0, 3, 6, 9, 10]
    assert kf.key_frames(5, 1).tolist() == [0, 1, 2, 3, 4]
    with pytest.raises(ValueError, match="every: expected a positive"):
        kf.key_frames(10, 0)


@pytest.mark.parametrize(("positions", "rotations"),
                         [("linear", "slerp"), ("cubic", "squad"), ("catmull_rom", "squad")])
def test_keyframed_reproduces_keys_and_every_1_is_the_clip(wave, positions, rotations):
    again = kf.keyframed(wave, 1, positions=positions, rotations=rotations)
    assert np.allclose(again.root_positions, wave.root_positions, atol=1e-12)
    assert_quat_equal(again.local_rotations, wave.local_rotations, atol=1e-12)
    sparse = kf.keyframed(wave, 7, positions=positions, rotations=rotations)
    keys = kf.key_frames(wave.n_frames, 7)
    assert sparse.n_frames == wave.n_frames and sparse.frame_time == wave.frame_time
    assert np.allclose(sparse.root_positions[keys], wave.root_positions[keys], atol=1e-12)
    assert_quat_equal(sparse.local_rotations[keys], wave.local_rotations[keys], atol=1e-12)
    assert np.all(kf.joint_position_error(sparse, wave)[keys] < 1e-9)


def test_error_grows_with_k_and_smooth_schemes_beat_linear(walk):
    errors = {}
    for every in (5, 10, 20, 40):
        for pos, r in [("linear", "slerp"), ("catmull_rom", "squad"), ("cubic", "squad")]:
            errors[every, pos] = kf.joint_position_error(
                kf.keyframed(walk, every, positions=pos, rotations=r), walk).mean()
    for pos in ("linear", "catmull_rom", "cubic"):
        assert errors[5, pos] < errors[10, pos] < errors[20, pos] < errors[40, pos]
    for every in (10, 20, 40):
        assert errors[every, "catmull_rom"] < 0.9 * errors[every, "linear"]
        assert errors[every, "cubic"] < 0.9 * errors[every, "linear"]
    assert errors[10, "catmull_rom"] < 0.5  # cm: keys every 1/12 s hold a walk well


def test_joint_position_error_in_cm_of_a_known_shift(wave):
    moved = Motion(wave.skeleton, wave.local_rotations, wave.root_positions + [0.0, 0.0, 2.0],
                   wave.frame_time)
    assert np.allclose(kf.joint_position_error(moved, wave), 2.0 * kf.CMU_CM_PER_UNIT)
    assert np.allclose(kf.joint_position_error(moved, wave, unit_cm=1.0), 2.0)


def test_keyframing_errors(wave, walk):
    with pytest.raises(ValueError, match="positions: expected one of"):
        kf.keyframed(wave, 4, positions="bezier")
    with pytest.raises(ValueError, match="rotations: expected one of"):
        kf.keyframed(wave, 4, rotations="nlerp")
    with pytest.raises(ValueError, match="reference: has a different skeleton"):
        kf.joint_position_error(wave, walk)
    with pytest.raises(ValueError, match="reference: has 10 frames, motion has 120"):
        kf.joint_position_error(wave, wave[:10])


# --------------------------------------------------------------------------- blending
def test_aligned_moves_and_turns_on_the_ground_only(walk):
    target, yaw = np.array([3.0, 99.0, -4.0]), 1.2
    out = kf.aligned(walk, target, yaw)
    assert np.isclose(kf.facing_yaw(out.local_rotations[0, 0]), yaw)
    assert np.allclose(out.root_positions[0], [3.0, walk.root_positions[0, 1], -4.0])
    assert np.allclose(out.root_positions[:, 1], walk.root_positions[:, 1])  # heights kept
    # the clip moves rigidly: distances along the path are kept
    assert np.allclose(np.linalg.norm(np.diff(out.root_positions, axis=0), axis=1),
                       np.linalg.norm(np.diff(walk.root_positions, axis=0), axis=1))
    # joints below the root are untouched; the root only gained a turn about y
    assert_quat_equal(out.local_rotations[:, 1:], walk.local_rotations[:, 1:])
    turn = rot.quat_mul(out.local_rotations[:, 0], rot.quat_conjugate(walk.local_rotations[:, 0]))
    axis, angle = rot.axis_angle_from_quat(turn)
    assert np.allclose(np.abs(axis[angle > 1e-9, 1]), 1.0)


def test_concatenate_aligns_the_second_clip_at_the_transition(walk):
    a, b = walk[:300], walk[129:]
    for n in (0, 20):
        out = kf.concatenate(a, b, n)
        assert out.n_frames == a.n_frames + b.n_frames - n
        anchor = a.n_frames - max(n, 1)
        yaw_a = kf.facing_yaw(a.local_rotations[anchor, 0])
        # the last frame is pure B: it faces as B's last frame does, turned by the alignment
        turn = yaw_a - kf.facing_yaw(b.local_rotations[0, 0])
        expected = kf.facing_yaw(rot.quat_mul(rot.quat_from_axis_angle([0, 1, 0], turn),
                                              b.local_rotations[-1, 0]))
        assert np.isclose(kf.facing_yaw(out.local_rotations[-1, 0]), expected)
        if n:
            # B's first frame sits on A's frame at the start of the transition, so the blend
            # there is between two roots at one ground point
            start = out.root_positions[anchor]
            assert np.allclose(start[[0, 2]], a.root_positions[anchor, [0, 2]], atol=1e-9)
        assert np.allclose(out.root_positions[:a.n_frames - n], a.root_positions[:a.n_frames - n])


def test_concatenate_of_a_turned_clip_aligns_its_facing(walk):
    """Turn B by 90 degrees and move it far away: after alignment the seam carries on in A's
    direction, as if B had not been turned."""
    a, b = walk[:300], walk[129:]
    q_turn = rot.quat_from_axis_angle([0.0, 1.0, 0.0], np.pi / 2)
    local = b.local_rotations.copy()
    local[:, 0] = rot.quat_mul(q_turn, local[:, 0])
    turned = Motion(b.skeleton, local, rot.quat_rotate(q_turn, b.root_positions) + [50, 0, -80],
                    b.frame_time, channels=b.channels)
    plain, rotated = kf.concatenate(a, b, 20), kf.concatenate(a, turned, 20)
    assert np.allclose(plain.root_positions, rotated.root_positions, atol=1e-9)
    assert_quat_equal(plain.local_rotations, rotated.local_rotations, atol=1e-9)


def test_blended_seam_is_continuous_where_a_cut_jumps(walk):
    """Per-frame joint steps across a matched 20-frame cross-fade stay within the largest
    step of the clip itself; a hard cut between mismatched poses jumps beyond it."""
    p, _ = walk.forward_kinematics()
    largest = np.linalg.norm(np.diff(p, axis=0), axis=-1).max()

    def seam_step(out, n):
        q, _ = out.forward_kinematics()
        steps = np.linalg.norm(np.diff(q, axis=0), axis=-1).max(axis=1)
        seam = 300 - max(n, 1)
        return steps[seam - 3:seam + n + 3].max()

    assert seam_step(kf.concatenate(walk[:300], walk[129:], 20), 20) < largest
    assert seam_step(kf.concatenate(walk[:300], walk[150:], 0), 0) > 1.5 * largest


def test_concatenate_weights_and_errors(walk, wave):
    w = kf.smoothstep(5)
    assert np.all((w > 0) & (w < 1)) and np.all(np.diff(w) > 0)
    assert np.allclose(w + w[::-1], 1.0)  # symmetric about the middle
    with pytest.raises(ValueError, match="second: has a different skeleton"):
        kf.concatenate(walk, wave, 5)
    with pytest.raises(ValueError, match="second: frame time"):
        kf.concatenate(walk, walk[::2], 5)
    with pytest.raises(ValueError, match="blend_frames: expected an integer from 0 to 10"):
        kf.concatenate(walk, walk[:10], 11)
