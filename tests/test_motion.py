"""Motion: validation, timing, frame slicing and forward kinematics."""

from __future__ import annotations

import numpy as np
import pytest

from course.motion import Motion, default_channels, euler_order
from course.rotations import quat_from_euler, quat_rotate
from course.skeleton import Skeleton


def arm() -> Skeleton:
    return Skeleton(
        ["Root", "Upper", "Lower", "Lower_end"], [-1, 0, 1, 2],
        [[0, 0, 0], [0, 2, 0], [3, 0, 0], [2, 0, 0]],
    )


def random_motion(n_frames: int = 10, seed: int = 0) -> Motion:
    rng = np.random.default_rng(seed)
    q = rng.normal(size=(n_frames, 4, 4))
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    return Motion(arm(), q, rng.normal(size=(n_frames, 3)), 0.02, name="arm")


def test_timing():
    motion = random_motion(10)
    assert (motion.n_frames, motion.n_joints, len(motion)) == (10, 4, 10)
    assert motion.fps == pytest.approx(50.0)
    assert motion.duration == pytest.approx(0.2)
    assert np.allclose(motion.times, np.arange(10) * 0.02)
    assert repr(motion) == "Motion('arm', 10 frames at 50 fps, 4 joints, 0.200 s)"


def test_default_channels_and_orders():
    motion = random_motion()
    assert motion.channels == default_channels(arm())
    assert motion.channels[0] == (
        "Xposition", "Yposition", "Zposition", "Zrotation", "Yrotation", "Xrotation"
    )
    assert motion.channels[3] == ()  # Lower_end is an End Site
    assert motion.euler_orders == ("ZYX", "ZYX", "ZYX", None)
    assert euler_order(("Xposition", "Yrotation")) == "YXZ"
    assert euler_order(("Zrotation", "Xrotation")) == "ZXY"


def test_forward_kinematics_is_the_lecture_recursion():
    # Q_i = Q_parent R_i, p_i = p_parent + Q_parent l_i, checked joint by joint.
    motion = random_motion(6, seed=3)
    positions, orientations = motion.forward_kinematics()
    assert positions.shape == (6, 4, 3) and orientations.shape == (6, 4, 4)
    assert np.allclose(positions[:, 0], motion.root_positions)
    for j in range(1, 4):
        p = motion.skeleton.parents[j]
        expected = positions[:, p] + quat_rotate(orientations[:, p], motion.skeleton.offsets[j])
        assert np.allclose(positions[:, j], expected, atol=1e-12)


def test_translations_replace_the_offsets():
    motion = random_motion(4, seed=1)
    bones = np.broadcast_to(motion.skeleton.offsets, (4, 4, 3)).copy()
    bones[:, 2] *= np.arange(1, 5)[:, None]  # the upper arm stretches
    stretched = Motion(motion.skeleton, motion.local_rotations, motion.root_positions,
                       motion.frame_time, translations=bones)
    positions, orientations = stretched.forward_kinematics()
    expected = positions[:, 1] + quat_rotate(orientations[:, 1], bones[:, 2])
    assert np.allclose(positions[:, 2], expected, atol=1e-12)
    # Same as the plain motion when the translations are the offsets.
    plain = Motion(motion.skeleton, motion.local_rotations, motion.root_positions,
                   motion.frame_time,
                   translations=np.broadcast_to(motion.skeleton.offsets, (4, 4, 3)))
    assert np.allclose(plain.forward_kinematics()[0], motion.forward_kinematics()[0])


def test_slicing():
    motion = random_motion(20, seed=2)
    positions = motion.forward_kinematics()[0]
    part = motion[5:15]
    assert part.n_frames == 10 and part.frame_time == motion.frame_time
    assert np.allclose(part.forward_kinematics()[0], positions[5:15])
    every_other = motion[::2]
    assert every_other.n_frames == 10 and every_other.frame_time == pytest.approx(0.04)
    assert np.allclose(every_other.root_positions, motion.root_positions[::2])
    one = motion[-1]
    assert one.n_frames == 1
    assert np.allclose(one.forward_kinematics()[0][0], positions[-1])
    assert motion[np.int64(3)].n_frames == 1
    part.root_positions[:] = 0  # a copy: the original is untouched
    assert not np.allclose(motion.root_positions[5:15], 0)
    assert (part.name, part.channels) == (motion.name, motion.channels)


@pytest.mark.parametrize(
    ("index", "error"), [(20, IndexError), (-21, IndexError), ("a", TypeError), (1.0, TypeError)]
)
def test_bad_frame_index(index, error):
    with pytest.raises(error):
        random_motion(20)[index]


def test_slice_step_zero():
    with pytest.raises(ValueError, match="step"):
        random_motion()[::0]


def test_euler_channels_give_the_rotations():
    # A motion from Euler angles, as a BVH file would hold them (intrinsic ZYX, degrees).
    angles = np.array([[30.0, -20.0, 10.0]])
    q = quat_from_euler(angles, "ZYX", degrees=True)
    motion = Motion(arm(), np.repeat(q[:, None], 4, axis=1), np.zeros((1, 3)), 1 / 30)
    assert np.allclose(motion.local_rotations[0, 1], q[0])


@pytest.mark.parametrize(
    ("kwargs", "phrase"),
    [
        ({"local_rotations": np.zeros((5, 3, 4))}, r"local_rotations: expected shape \(F, 4, 4\)"),
        ({"root_positions": np.zeros((4, 3))}, "root_positions: has 4 frames"),
        ({"root_positions": np.zeros((5, 2))}, r"root_positions: expected shape \(F, 3\)"),
        ({"frame_time": 0.0}, "frame_time: must be a positive"),
        ({"frame_time": float("nan")}, "frame_time: must be a positive"),
        ({"translations": np.zeros((5, 4, 2))}, "translations: expected shape"),
        ({"translations": np.zeros((6, 4, 3))}, "translations: has 6 frames"),
        ({"channels": [()] * 3}, "channels: expected one tuple"),
        ({"channels": [("Xpos",), (), (), ()]}, "unknown channel 'Xpos'"),
        ({"channels": [("Xrotation", "Xrotation"), (), (), ()]}, "repeats a channel"),
        ({"local_rotations": np.full((5, 4, 4), np.nan)}, "NaN or infinity"),
    ],
)
def test_bad_arguments(kwargs, phrase):
    args = {
        "skeleton": arm(),
        "local_rotations": np.tile([1.0, 0, 0, 0], (5, 4, 1)),
        "root_positions": np.zeros((5, 3)),
        "frame_time": 0.1,
    } | kwargs
    with pytest.raises(ValueError, match=phrase):
        Motion(**args)
