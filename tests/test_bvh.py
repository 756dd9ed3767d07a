"""Reading and writing BVH: real files, format variants, FK against an independent reader."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from course.bvh import (
    BVHWarning,
    format_bvh,
    format_bvh_channels,
    joint_type,
    load_bvh,
    parse_bvh,
    save_bvh,
)
from course.motion import Motion
from course.rotations import matrix_from_quat, quat_from_axis_angle
from course.skeleton import Ball, Fixed, Hinge, Skeleton, Universal

# file (relative to the shared folder): joints, End Sites, channels, frames, frame time
EXPECTED = {
    "cmu_12_01_walk.bvh": (38, 7, 96, 524, 0.0083333),
    "01_01.bvh": (38, 7, 96, 2752, 0.0083333),
    "01_03.bvh": (38, 7, 96, 4511, 0.0083333),
    "01_03_reach_excerpt.bvh": (38, 7, 96, 780, 0.0083333),
    "edge_cases/fairmotion_sinusoidal.bvh": (4, 0, 15, 120, 1 / 60),
    "edge_cases/fairmotion_pfnn_hierarchy.bvh": (38, 7, 96, 60, 0.0333333),
    "edge_cases/pybvh_rotation_first_root.bvh": (6, 2, 15, 4, 0.04),
}
SMALL = [
    "cmu_12_01_walk.bvh",
    "edge_cases/fairmotion_sinusoidal.bvh",
    "edge_cases/fairmotion_pfnn_hierarchy.bvh",
    "edge_cases/pybvh_rotation_first_root.bvh",
]


# -- an independent reader and FK: line by line, scipy rotations, one joint at a time ------


def reference_read(text: str) -> tuple:
    """names, parents, offsets (J, 3), channels, frame values (F, C) of a well-formed file."""
    lines = text.splitlines()
    names, parents, offsets, channels, stack = [], [], [], [], []
    last = -1
    motion = next(i for i, line in enumerate(lines) if line.strip() == "MOTION")
    for line in lines[:motion]:
        words = line.split()
        if not words:
            continue
        if words[0] in ("ROOT", "JOINT") or words[0] == "End":
            name = words[1] if words[0] != "End" else names[stack[-1]] + "_end"
            names.append(name)
            parents.append(stack[-1] if stack else -1)
            channels.append([])
            last = len(names) - 1
        elif words[0] == "{":
            stack.append(last)
        elif words[0] == "}":
            stack.pop()
        elif words[0] == "OFFSET":
            offsets.append([float(w) for w in words[1:4]])
        elif words[0] == "CHANNELS":
            channels[last] = words[2:]
    rows = [line.split() for line in lines[motion + 3 :] if line.split()]
    return names, parents, np.array(offsets), channels, np.array(rows, dtype=float)


def reference_fk(text: str, frames: list[int]) -> tuple[np.ndarray, np.ndarray]:
    """World positions (len(frames), J, 3) and rotation matrices (len(frames), J, 3, 3)."""
    names, parents, offsets, channels, values = reference_read(text)
    positions = np.zeros((len(frames), len(names), 3))
    matrices = np.zeros((len(frames), len(names), 3, 3))
    for n, f in enumerate(frames):
        column = 0
        for j in range(len(names)):
            local_r, bone = np.eye(3), offsets[j].copy()
            for channel in channels[j]:
                axis, value = channel[0].lower(), values[f, column]
                column += 1
                if channel.endswith("rotation"):  # intrinsic: multiply on the right
                    local_r = local_r @ Rotation.from_euler(axis, value, degrees=True).as_matrix()
                else:
                    bone["xyz".index(axis)] = value
            if parents[j] < 0:
                matrices[n, j], positions[n, j] = local_r, bone
            else:
                p = parents[j]
                matrices[n, j] = matrices[n, p] @ local_r
                positions[n, j] = positions[n, p] + matrices[n, p] @ bone
    return positions, matrices


# -- the real files ------------------------------------------------------------------------


def test_every_shared_file_is_covered(shared_bvh_dir):
    found = {p.relative_to(shared_bvh_dir).as_posix() for p in shared_bvh_dir.rglob("*.bvh")}
    assert found == set(EXPECTED)


@pytest.mark.parametrize("name", EXPECTED)
def test_real_files_load(shared_bvh_dir, name):
    n_joints, n_end_sites, n_channels, n_frames, frame_time = EXPECTED[name]
    motion = load_bvh(shared_bvh_dir / name)
    assert motion.n_joints == n_joints
    end_sites = [n for n, c in zip(motion.skeleton.names, motion.channels, strict=True) if not c]
    assert len(end_sites) == n_end_sites and all(n.endswith("_end") for n in end_sites)
    assert sum(len(c) for c in motion.channels) == n_channels
    # one rotational degree of freedom per rotation channel: End Sites are fixed joints
    rotation_channels = sum(c.endswith("rotation") for cs in motion.channels for c in cs)
    assert motion.skeleton.dof == rotation_channels
    assert motion.n_frames == n_frames
    assert motion.frame_time == pytest.approx(frame_time)
    assert motion.local_rotations.shape == (n_frames, n_joints, 4)
    assert motion.root_positions.shape == (n_frames, 3)
    assert np.allclose(np.linalg.norm(motion.local_rotations, axis=-1), 1.0)
    assert motion.translations is None  # no position channels below the root in these files
    assert motion.source == str(shared_bvh_dir / name)
    assert motion.name == Path(name).stem


def test_walk_structure(shared_bvh_dir):
    motion = load_bvh(shared_bvh_dir / "cmu_12_01_walk.bvh")
    names = motion.skeleton.names
    assert names[:3] == ("Hips", "LHipJoint", "LeftUpLeg")
    assert names[6] == "LeftToeBase_end" and motion.channels[6] == ()
    assert motion.skeleton.parents[6] == names.index("LeftToeBase")
    assert motion.channels[0] == (
        "Xposition", "Yposition", "Zposition", "Zrotation", "Yrotation", "Xrotation"
    )
    assert set(motion.euler_orders) == {"ZYX", None}
    assert motion.fps == pytest.approx(120.0, rel=1e-4)
    assert motion.duration == pytest.approx(524 * 0.0083333)
    # The first frame's root position, straight from the file.
    assert np.allclose(motion.root_positions[0], [0.0265, 16.2134, -25.4911])


def test_rotation_first_root_and_mixed_orders(shared_bvh_dir):
    motion = load_bvh(shared_bvh_dir / "edge_cases/pybvh_rotation_first_root.bvh")
    assert motion.channels[0][:3] == ("Zrotation", "Xrotation", "Yrotation")
    assert motion.euler_orders == ("ZXY", "ZXY", "ZYX", None, "XYZ", None)
    assert np.allclose(motion.root_positions[:, 0], [10, 11, 12, 13])  # after the rotations
    expected = Rotation.from_euler("ZXY", [5, -3, 0], degrees=True).as_matrix()
    assert np.allclose(matrix_from_quat(motion.local_rotations[0, 0]), expected, atol=1e-12)


def test_leaf_joints_with_channels_and_no_final_newline(shared_bvh_dir):
    path = shared_bvh_dir / "edge_cases/fairmotion_sinusoidal.bvh"
    assert not path.read_bytes().endswith(b"\n")
    motion = load_bvh(path)
    assert motion.skeleton.names == ("base", "child1", "child2", "child3")
    assert motion.channels[3] == ("Xrotation", "Yrotation", "Zrotation")  # a leaf, no End Site
    last = np.array(path.read_text().splitlines()[-1].split(), dtype=float)
    assert np.allclose(motion.root_positions[-1], last[:3])
    angles = Rotation.from_quat(motion.local_rotations[-1, 1], scalar_first=True).as_euler(
        "XYZ", degrees=True
    )
    assert np.allclose(angles, last[6:9], atol=1e-9)


@pytest.mark.parametrize("name", SMALL)
def test_fk_matches_independent_scipy_fk(shared_bvh_dir, name):
    path = shared_bvh_dir / name
    motion = load_bvh(path)
    frames = sorted({0, 1, motion.n_frames // 2, motion.n_frames - 1})
    ref_positions, ref_matrices = reference_fk(path.read_text(), frames)
    positions, orientations = motion.forward_kinematics()
    assert np.allclose(positions[frames], ref_positions, rtol=0, atol=1e-9)
    assert np.allclose(matrix_from_quat(orientations[frames]), ref_matrices, rtol=0, atol=1e-9)


# -- what real files contain ---------------------------------------------------------------

BASE = """HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation
  JOINT Chest
  {
    OFFSET 0 5 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    End Site
    {
      OFFSET 0 2 0
    }
  }
}
MOTION
Frames: 3
Frame Time: 0.5
1 2 3 10 20 30 40 -50 60
4 5 6 11 21 31 41 -51 61
7 8 9 12 22 32 42 -52 62
"""


def assert_same_motion(a: Motion, b: Motion, atol: float = 0.0) -> None:
    assert a.skeleton.names == b.skeleton.names
    assert np.array_equal(a.skeleton.parents, b.skeleton.parents)
    assert np.allclose(a.skeleton.offsets, b.skeleton.offsets, rtol=0, atol=atol)
    assert a.channels == b.channels
    assert a.frame_time == pytest.approx(b.frame_time)
    assert np.allclose(a.root_positions, b.root_positions, rtol=0, atol=atol)
    assert np.allclose(a.local_rotations, b.local_rotations, rtol=0, atol=atol)


VARIANTS = {
    "crlf": lambda t: t.replace("\n", "\r\n"),
    "mixed endings": lambda t: "".join(
        line + ("\r\n" if i % 2 else "\n") for i, line in enumerate(t.splitlines())
    ),
    "old mac endings": lambda t: t.replace("\n", "\r"),
    "tabs and repeated spaces": lambda t: t.replace("  ", "\t").replace(" ", " \t  "),
    "blank lines": lambda t: t.replace("\n", "\n\n  \n"),
    "no final newline": lambda t: t.rstrip("\n"),
    "frame time spacing": lambda t: t.replace("Frame Time: 0.5", "Frame   Time:\t.5"),
    "frames without space": lambda t: t.replace("Frames: 3", "Frames:3").replace(
        "Frame Time: 0.5", "Frame Time:0.5"
    ),
    "lowercase keywords": lambda t: t.replace("End Site", "End site").replace(
        "Xposition", "XPOSITION"
    ),
    "brace on the joint line": lambda t: t.replace("JOINT Chest\n  {", "JOINT Chest {"),
    "leading tab on frame lines": lambda t: re.sub(r"^(\d)", "\t\\1", t, flags=re.M),
    "byte order mark and trailing spaces": lambda t: "\ufeff" + t.replace("\n", "  \n"),
}


@pytest.mark.parametrize("variant", VARIANTS)
def test_format_variants_parse_alike(variant, tmp_path):
    reference = parse_bvh(BASE)
    text = VARIANTS[variant](BASE)
    file = tmp_path / "variant.bvh"
    file.write_bytes(text.encode("utf-8"))
    assert_same_motion(load_bvh(file), reference)


def test_parse_string_values():
    motion = parse_bvh(BASE, source="<base>", name="base")
    assert (motion.name, motion.source) == ("base", "<base>")
    assert motion.skeleton.names == ("Hips", "Chest", "Chest_end")
    assert motion.channels[1] == ("Zrotation", "Xrotation", "Yrotation")
    assert np.allclose(motion.root_positions, [[1, 2, 3], [4, 5, 6], [7, 8, 9]])
    expected = Rotation.from_euler("ZXY", [42, -52, 62], degrees=True).as_matrix()
    assert np.allclose(matrix_from_quat(motion.local_rotations[2, 1]), expected, atol=1e-12)
    assert np.allclose(motion.local_rotations[:, 2], [1, 0, 0, 0])  # End Site: identity


PARTIAL = """HIERARCHY
ROOT Root
{
  OFFSET 1 2 3
  CHANNELS 3 Yrotation Xposition Zposition
  JOINT Slider
  {
    OFFSET 0 4 0
    CHANNELS 2 Yposition Zrotation
    JOINT Fixed
    {
      OFFSET 1 0 0
      CHANNELS 0
      JOINT Hinge
      {
        OFFSET 0 0 2
        CHANNELS 2 Xrotation Zrotation
        End Site
        {
          OFFSET 0 1 0
        }
      }
    }
  }
}
MOTION
Frames: 2
Frame Time: 0.1
30 5 6 7 45 10 20
-30 -5 -6 9 -45 80 -20
"""


def test_partial_channels_positions_below_root_and_no_channels(tmp_path):
    file = tmp_path / "partial.bvh"
    file.write_text(PARTIAL)
    motion = load_bvh(file)
    assert motion.euler_orders == ("YXZ", "ZXY", None, "XZY", None)
    # The root's Y position comes from its OFFSET (no Yposition channel).
    assert np.allclose(motion.root_positions, [[5, 2, 6], [-5, 2, -6]])
    # Per-frame bones: Slider's Y replaced by its channel, the others are the offsets.
    assert motion.translations is not None
    assert np.allclose(motion.translations[:, 1], [[0, 7, 0], [0, 9, 0]])
    assert np.allclose(motion.translations[:, 2], [1, 0, 0])
    assert np.allclose(motion.local_rotations[:, 2], [1, 0, 0, 0])
    positions, orientations = motion.forward_kinematics()
    ref_positions, ref_matrices = reference_fk(PARTIAL, [0, 1])
    assert np.allclose(positions, ref_positions, atol=1e-12)
    assert np.allclose(matrix_from_quat(orientations), ref_matrices, atol=1e-12)


def test_more_frame_lines_than_declared_warns_and_loads_the_declared_count(tmp_path):
    file = tmp_path / "extra.bvh"
    text = BASE.replace("Frames: 3", "Frames: 2")
    file.write_text(text)
    with pytest.warns(BVHWarning, match=r"extra\.bvh.*Frames: says 2, the file has 3") as caught:
        motion = load_bvh(file)
    assert motion.n_frames == 2
    assert np.allclose(motion.root_positions[-1], [4, 5, 6])
    # The warning points at the line that called load_bvh (here), not inside course/bvh.py.
    assert [Path(w.filename).name for w in caught] == [Path(__file__).name]
    with pytest.warns(BVHWarning, match="Frames: says 2") as caught:
        parse_bvh(text, source="extra")
    assert [Path(w.filename).name for w in caught] == [Path(__file__).name]


# One joint for each number of rotation channels: a ball root, a 1-channel hinge (knee), a
# 2-channel universal joint (wrist) turning about Z then X, and a joint with positions only.
JOINT_TYPES = """HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Yrotation Xrotation Zrotation
  JOINT Knee
  {
    OFFSET 0 -4 0
    CHANNELS 1 Xrotation
    JOINT Wrist
    {
      OFFSET 0 -4 0
      CHANNELS 2 Zrotation Xrotation
      JOINT Slide
      {
        OFFSET 1 0 0
        CHANNELS 3 Xposition Yposition Zposition
        End Site
        {
          OFFSET 0 0 1
        }
      }
    }
  }
}
MOTION
Frames: 2
Frame Time: 0.1
0 1 2 10 20 30 45 30 -60 1 0.5 0
3 4 5 -10 -20 -30 -90 120 15 2 0 0.25
"""


def test_joint_types_follow_the_rotation_channels(tmp_path):
    file = tmp_path / "types.bvh"
    file.write_text(JOINT_TYPES)
    motion = load_bvh(file)
    skeleton = motion.skeleton
    X, Y, Z = np.eye(3)
    assert skeleton.joint_types == (
        Ball(), Hinge(tuple(X)), Universal((tuple(Z), tuple(X))), Fixed(), Fixed()
    )
    # Every rotation channel is one rotational degree of freedom: 3 + 1 + 2 + 0 + 0.
    assert skeleton.dof == 6 == sum(c.endswith("rotation") for cs in motion.channels for c in cs)
    # The hinge turns about its axis, the universal joint about Z then X (R = R_Z R_X).
    knee = quat_from_axis_angle(X, [45, -90], degrees=True)
    assert np.allclose(motion.local_rotations[:, 1], knee, atol=1e-15)
    expected = Rotation.from_euler("ZX", [[30, -60], [120, 15]], degrees=True).as_matrix()
    assert np.allclose(matrix_from_quat(motion.local_rotations[:, 2]), expected, atol=1e-12)
    positions, orientations = motion.forward_kinematics()
    ref_positions, ref_matrices = reference_fk(JOINT_TYPES, [0, 1])
    assert np.allclose(positions, ref_positions, atol=1e-12)
    assert np.allclose(matrix_from_quat(orientations), ref_matrices, atol=1e-12)
    # Written and read back, the joints keep their channels and so their types.
    again = parse_bvh(format_bvh(motion))
    assert again.skeleton.joint_types == skeleton.joint_types
    assert_same_fk(motion, again, atol=1e-9)


@pytest.mark.parametrize(
    ("channels", "expected"),
    [
        ((), Fixed()),
        (("Xposition", "Yposition", "Zposition"), Fixed()),
        (("Yrotation",), Hinge((0.0, 1.0, 0.0))),
        (("Zposition", "Zrotation"), Hinge((0.0, 0.0, 1.0))),
        (("Yrotation", "Xposition", "Zrotation"), Universal(((0, 1, 0), (0, 0, 1)))),
        (("Xrotation", "Yrotation"), Universal(((1, 0, 0), (0, 1, 0)))),
        (("Xrotation", "Zrotation", "Yrotation"), Ball()),
    ],
)
def test_joint_type_of_channels(channels, expected):
    assert joint_type(channels) == expected
    assert joint_type(channels).dof == sum(c.endswith("rotation") for c in channels)


def test_no_frames():
    motion = parse_bvh(BASE.split("Frames:")[0] + "Frames: 0\nFrame Time: 0.5\n")
    assert motion.n_frames == 0
    assert motion.local_rotations.shape == (0, 3, 4)


# -- writing -------------------------------------------------------------------------------


def fk_by_name(motion: Motion) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    positions, orientations = motion.forward_kinematics()
    matrices = matrix_from_quat(orientations)
    return {n: (positions[:, j], matrices[:, j]) for j, n in enumerate(motion.skeleton.names)}


def assert_same_fk(a: Motion, b: Motion, atol: float) -> None:
    fa, fb = fk_by_name(a), fk_by_name(b)
    assert fa.keys() == fb.keys()
    for name in fa:
        assert np.allclose(fa[name][0], fb[name][0], rtol=0, atol=atol), name
        assert np.allclose(fa[name][1], fb[name][1], rtol=0, atol=atol), name


@pytest.mark.parametrize("name", SMALL)
def test_save_load_round_trip(shared_bvh_dir, tmp_path, name):
    motion = load_bvh(shared_bvh_dir / name)
    save_bvh(motion, tmp_path / "copy.bvh")
    again = load_bvh(tmp_path / "copy.bvh")
    assert again.skeleton.names == motion.skeleton.names
    assert again.channels == motion.channels
    assert again.frame_time == motion.frame_time
    assert np.allclose(again.skeleton.offsets, motion.skeleton.offsets, rtol=0, atol=1e-12)
    assert_same_fk(motion, again, atol=1e-6)


def test_round_trip_keeps_partial_channels_and_translations():
    motion = parse_bvh(PARTIAL)
    again = parse_bvh(format_bvh(motion))
    assert again.channels == motion.channels
    assert np.allclose(again.translations, motion.translations)
    assert_same_fk(motion, again, atol=1e-9)


@pytest.mark.parametrize("orders", ["XYZ", {"Chest": "YZX", "Hips": "XZY"}])
def test_save_with_other_orders(orders):
    motion = parse_bvh(BASE)
    again = parse_bvh(format_bvh(motion, orders))
    wanted = {"Hips": "XYZ", "Chest": "XYZ"} if orders == "XYZ" else orders
    assert again.euler_orders == (wanted["Hips"], wanted["Chest"], None)
    assert again.channels[0][:3] == ("Xposition", "Yposition", "Zposition")
    assert_same_fk(motion, again, atol=1e-9)


def test_save_with_orders_keeps_rotation_first_layout(shared_bvh_dir):
    motion = load_bvh(shared_bvh_dir / "edge_cases/pybvh_rotation_first_root.bvh")
    again = parse_bvh(format_bvh(motion, "YXZ"))
    assert again.channels[0] == (
        "Yrotation", "Xrotation", "Zrotation", "Xposition", "Yposition", "Zposition"
    )
    assert_same_fk(motion, again, atol=1e-9)


def test_save_walk_with_another_order(shared_bvh_dir):
    motion = load_bvh(shared_bvh_dir / "cmu_12_01_walk.bvh")[::8]
    again = parse_bvh(format_bvh(motion, "XYZ"))
    assert set(again.euler_orders) == {"XYZ", None}
    assert again.frame_time == motion.frame_time == 8 * 0.0083333
    assert_same_fk(motion, again, atol=1e-6)


@pytest.mark.parametrize(
    ("orders", "phrase"),
    [
        ("xyz", "intrinsic: use uppercase"),
        ("XXY", "not an intrinsic order"),
        ({"Nope": "XYZ"}, "no joint named 'Nope'"),
        (3, "expected a string or a mapping"),
    ],
)
def test_bad_orders(orders, phrase):
    with pytest.raises(ValueError, match=phrase):
        format_bvh(parse_bvh(BASE), orders)


def test_refuses_what_the_channels_cannot_carry():
    motion = parse_bvh(BASE)
    tilted = motion.local_rotations.copy()
    tilted[:, 2] = [np.cos(0.1), np.sin(0.1), 0, 0]  # rotate the End Site
    with pytest.raises(ValueError, match="'Chest_end' rotates but has no rotation channels"):
        format_bvh(Motion(motion.skeleton, tilted, motion.root_positions, 0.5, motion.channels))
    # Writing a rotation channel for it fixes that.
    fixed = Motion(motion.skeleton, tilted, motion.root_positions, 0.5, motion.channels)
    again = parse_bvh(format_bvh(fixed, {"Chest_end": "ZYX"}))
    assert_same_fk(fixed, again, atol=1e-9)

    partial = parse_bvh(PARTIAL)
    turned = partial.local_rotations.copy()
    turned[:, 1] = [np.cos(0.2), 0, np.sin(0.2), 0]  # about Y; Slider only has Zrotation
    with pytest.raises(ValueError, match="'Slider' rotates about axes its channels"):
        format_bvh(Motion(partial.skeleton, turned, partial.root_positions, 0.1, partial.channels,
                          partial.translations))
    lifted = partial.root_positions + [0, 1, 0]  # the root has no Yposition channel
    with pytest.raises(ValueError, match="root position of joint 'Root' moves along Y"):
        format_bvh(Motion(partial.skeleton, partial.local_rotations, lifted, 0.1,
                          partial.channels, partial.translations))


def test_motion_built_in_code_is_written_depth_first():
    # Breadth-first joint order: the file lists Root, A, A2, B; names keep their bones.
    skeleton = Skeleton(["Root", "A", "B", "A2"], [-1, 0, 0, 1],
                        [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    rng = np.random.default_rng(7)
    rotations = rng.normal(size=(5, 4, 4))
    rotations /= np.linalg.norm(rotations, axis=-1, keepdims=True)
    motion = Motion(skeleton, rotations, rng.normal(size=(5, 3)), 1 / 30)
    assert motion.channels[0][:3] == ("Xposition", "Yposition", "Zposition")
    again = parse_bvh(format_bvh(motion))
    assert again.skeleton.names == ("Root", "A", "A2", "B")
    assert_same_fk(motion, again, atol=1e-9)


def test_digits_and_file_text(tmp_path):
    motion = parse_bvh(BASE)
    save_bvh(motion, tmp_path / "out.bvh", digits=6)
    raw = (tmp_path / "out.bvh").read_bytes()
    assert b"\r" not in raw and raw.endswith(b"\n")
    text = raw.decode()
    assert "\tJOINT Chest\n" in text and "\t\tEnd Site\n" in text
    assert "Frames: 3\nFrame Time: 0.5\n" in text
    assert text.splitlines()[-1].split()[:3] == ["7", "8", "9"]
    with pytest.raises(ValueError, match="digits"):
        format_bvh(motion, digits=0)


# -- any layout: random trees, channel orders and subsets ----------------------------------


def axes() -> st.SearchStrategy[str]:
    """Some of the axes X, Y, Z in any order."""
    return st.permutations("XYZ").flatmap(
        lambda p: st.integers(0, 3).map(lambda k: "".join(p[:k]))
    )


@st.composite
def layouts(draw) -> tuple[list[int], list[tuple[str, ...]]]:
    """A random joint tree, listed depth first, and random channels for every joint: any
    subset and order of rotation axes and of position axes, rotations first or last."""
    parents, path = [-1], [0]
    for j in range(1, draw(st.integers(1, 6))):
        k = draw(st.integers(0, len(path) - 1))  # the parent lies on the path to joint j - 1
        parents.append(path[k])
        path = path[: k + 1] + [j]
    channels = []
    for _ in parents:
        rotations = [f"{a}rotation" for a in draw(axes())]
        positions = [f"{a}position" for a in draw(axes())]
        first = draw(st.booleans())
        channels.append(tuple(rotations + positions if first else positions + rotations))
    return parents, channels


@settings(max_examples=40, derandomize=True, deadline=None)
@given(layouts(), st.integers(0, 2**32 - 1))
def test_any_layout_reads_like_the_reference_and_round_trips(layout, seed):
    parents, channels = layout
    rng = np.random.default_rng(seed)
    n_frames = 3
    skeleton = Skeleton([f"J{j}" for j in range(len(parents))], parents,
                        rng.normal(size=(len(parents), 3)))
    values = np.concatenate(
        [rng.uniform(-180, 180, size=(n_frames, 1)) if c.endswith("rotation")
         else rng.normal(scale=10, size=(n_frames, 1))
         for joint in channels for c in joint] or [np.zeros((n_frames, 0))],
        axis=1,
    )
    text = format_bvh_channels(skeleton, channels, values, 0.1, fmt="%.17g")
    motion = parse_bvh(text)
    assert motion.channels == tuple(channels)
    positions, orientations = motion.forward_kinematics()
    ref_positions, ref_matrices = reference_fk(text, list(range(n_frames)))
    assert np.allclose(positions, ref_positions, rtol=0, atol=1e-9)
    assert np.allclose(matrix_from_quat(orientations), ref_matrices, rtol=0, atol=1e-12)
    again = parse_bvh(format_bvh(motion))
    assert again.channels == motion.channels
    assert_same_fk(motion, again, atol=1e-9)
