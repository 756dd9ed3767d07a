"""Skeleton structure, validation, joint types and the chain constructor."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from course.skeleton import Ball, Fixed, Hinge, Skeleton, Universal, chain

#        hips
#      /  |   \
#  lknee rknee spine
#    |     |     |
#  lfoot rfoot  head
NAMES = ["hips", "lknee", "lfoot", "rknee", "rfoot", "spine", "head"]
PARENTS = [-1, 0, 1, 0, 3, 0, 5]
OFFSETS = [[0, 0, 0], [1, -4, 0], [0, -4, 0], [-1, -4, 0], [0, -4, 0], [0, 3, 0], [0, 2, 0]]


@pytest.fixture
def body() -> Skeleton:
    return Skeleton(NAMES, PARENTS, OFFSETS)


def test_structure(body):
    assert body.n_joints == len(body) == 7
    assert body.index("rfoot") == 4 and body.index(4) == 4
    assert body.children("hips") == [1, 3, 5] and body.children(2) == []
    assert [body.depth(j) for j in range(7)] == [0, 1, 2, 1, 2, 1, 2]
    assert body.end_effectors == body.leaves == (2, 4, 6)
    assert body.parents.dtype.kind == "i" and list(body.parents) == PARENTS
    np.testing.assert_allclose(body.bone_lengths[2], 4.0)


@pytest.mark.parametrize(
    ("a", "b", "path"),
    [
        ("lfoot", "rfoot", [2, 1, 0, 3, 4]),
        ("head", "lknee", [6, 5, 0, 1]),
        (0, "head", [0, 5, 6]),
        ("rfoot", 0, [4, 3, 0]),
        ("lknee", "lfoot", [1, 2]),
        (3, 3, [3]),
    ],
)
def test_path(body, a, b, path):
    assert body.path(a, b) == path


def test_arrays_are_read_only(body):
    with pytest.raises(ValueError):
        body.offsets[0, 0] = 1.0
    with pytest.raises(ValueError):
        body.parents[1] = 0


def test_unknown_joint_suggests_close_names(body):
    with pytest.raises(KeyError, match="did you mean 'lfoot'"):
        body.index("lfot")
    with pytest.raises(ValueError, match=r"index 9 is not in \[0, 7\)"):
        body.index(9)


@pytest.mark.parametrize(
    ("names", "parents", "offsets", "message"),
    [
        (["a", "b", "a"], [-1, 0, 1], np.zeros((3, 3)), r"'a' \(index 2\).*same name as joint 0"),
        (["a", "", "c"], [-1, 0, 1], np.zeros((3, 3)), "joint 1 has name ''"),
        (["a", "b", "c"], [0, 0, 1], np.zeros((3, 3)), r"'a' \(index 0\) must be the root"),
        (["a", "b", "c"], [-1, 0, -1], np.zeros((3, 3)), r"'c' \(index 2\).*exactly one root"),
        (["a", "b", "c"], [-1, 2, 0], np.zeros((3, 3)), r"'b' \(index 1\).*parent-before-child"),
        (["a", "b", "c"], [-1, 0, 7], np.zeros((3, 3)), r"'c' \(index 2\).*not a joint index"),
        (["a", "b", "c"], [-1, 0], np.zeros((3, 3)), "parents: expected one parent per joint"),
        (["a", "b", "c"], [-1, 0, 1], np.zeros((2, 3)), r"offsets: expected shape \(3, 3\)"),
        (["a", "b", "c"], [-1, 0, 1], [[0, 0, 0], [0, np.nan, 0], [0, 0, 0]],
         r"'b' \(index 1\) has a NaN"),
    ],
)
def test_validation_names_the_joint(names, parents, offsets, message):
    with pytest.raises(ValueError, match=message):
        Skeleton(names, parents, offsets)


def test_joint_types():
    assert Hinge((0, 0, 2)).axis == (0.0, 0.0, 1.0) and Hinge((0, 0, 1)).dof == 1
    assert Universal(((1, 0, 0), (0, 1, 0))).dof == 2 and Ball().dof == 3 and Fixed().dof == 0
    assert Hinge((0, 0, 2)) == Hinge((0, 0, 1))  # compared by value, hashable
    assert len({Hinge((1, 0, 0)), Hinge((2, 0, 0)), Ball(), Ball()}) == 2
    with pytest.raises(ValueError, match="zero length"):
        Hinge((0, 0, 0))
    with pytest.raises(ValueError, match="parallel"):
        Universal(((1, 0, 0), (2, 0, 0)))
    skel = Skeleton(NAMES, PARENTS, OFFSETS, joint_types={"lknee": Hinge((1, 0, 0))})
    assert skel.joint_types[1] == Hinge((1, 0, 0)) and skel.joint_types[0] == Ball()
    assert skel.dof == 6 * 3 + 1
    with pytest.raises(ValueError, match=r"joint 'hips' \(index 0\) has 'ball'"):
        Skeleton(NAMES, PARENTS, OFFSETS, joint_types=["ball"] * 7)
    with pytest.raises(ValueError, match="no joints named"):
        Skeleton(NAMES, PARENTS, OFFSETS, joint_types={"knee": Ball()})


def test_chain_from_lengths_with_hinges():
    arm = chain([1.0, 2.0, 0.5, 1, 1, 1, 1], axes=[0, 0, 1])
    assert arm.n_joints == 8 and arm.dof == 7
    assert arm.names[0] == "joint0" and arm.names[-1] == "end_effector"
    assert arm.end_effectors == (7,)
    assert all(t == Hinge((0, 0, 1)) for t in arm.joint_types[:-1])
    assert arm.joint_types[-1] == Fixed()
    np.testing.assert_allclose(arm.rest_positions()[:, 0], np.cumsum([0, 1, 2, 0.5, 1, 1, 1, 1]))
    # Turning the first hinge by 90 degrees about z swings the straight arm onto +y.
    local = np.tile([1.0, 0, 0, 0], (8, 1))
    local[0] = [np.cos(np.pi / 4), 0, 0, np.sin(np.pi / 4)]
    P, _ = arm.forward_kinematics(local)
    np.testing.assert_allclose(P[-1], [0, 7.5, 0], atol=1e-12)


def test_chain_from_offsets_and_names():
    bones = [[0, 1, 0], [0, 1, 1]]
    c = chain(bones, names=["a", "b", "tip"], axes=[[1, 0, 0], [0, 1, 0]])
    np.testing.assert_allclose(c.offsets, [[0, 0, 0], [0, 1, 0], [0, 1, 1]])
    assert c.joint_types[1] == Hinge((0, 1, 0)) and c.dof == 2
    assert chain([1.0, 1.0]).joint_types == (Ball(), Ball(), Fixed())
    with pytest.raises(ValueError, match="positive"):
        chain([1.0, -1.0])
    with pytest.raises(ValueError, match="2 bones make 3 joints"):
        chain([1.0, 1.0], names=["a", "b"])
    with pytest.raises(ValueError, match=r"axes: expected shape \(3,\) or \(2, 3\)"):
        chain([1.0, 1.0], axes=np.eye(3))


def test_display(body):
    assert repr(body).startswith("Skeleton(7 joints") and "root 'hips'" in repr(body)
    lines = str(body).splitlines()
    assert lines[1].startswith("hips [0] ball")
    assert any(line.startswith("│   └── lfoot [2]") for line in lines)
    assert lines[-1].startswith("    └── head [6]")


def test_local_from_global_and_pin(body):
    rng = np.random.default_rng(3)
    q = rng.normal(size=(2, 7, 4))
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    P, Q = body.forward_kinematics(q, [0, 10, 0])
    np.testing.assert_allclose(body.forward_kinematics(body.local_from_global(Q))[1], Q, atol=1e-12)
    p, o = body.pin("rfoot", q, [0, 10, 0])
    np.testing.assert_allclose(p, P[:, 4])
    np.testing.assert_allclose(o, Q[:, 4])
    P2, _ = body.forward_kinematics(q, p, root="rfoot", root_orientation=o)
    np.testing.assert_allclose(P2, P, atol=1e-12)


def test_modules_import_without_scipy():
    code = "import sys, course.skeleton, course.fk; print('scipy' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
