"""LERP / NLERP / SLERP, the angle between rotations, and the shortest arc between vectors."""

from __future__ import annotations

import numpy as np
import pytest
from rotation_asserts import (
    assert_quat_equal,
    random_quats,
    relative_angle,
    rotation_angle,
    scipy_rotation,
)
from scipy.spatial.transform import Rotation, Slerp

from course.rotations import (
    lerp,
    nlerp,
    quat_angle,
    quat_between,
    quat_from_axis_angle,
    quat_rotate,
    slerp,
)


@pytest.fixture
def rng():
    return np.random.default_rng(105)


def test_slerp_matches_scipy(rng):
    q0, q1 = random_quats(rng), random_quats(rng)
    t = np.linspace(0, 1, 11)
    expected = Slerp([0, 1], scipy_rotation(np.stack([q0, q1])))(t).as_quat(scalar_first=True)
    out = slerp(q0, q1, t)
    assert out.shape == (11, 4)
    assert_quat_equal(out, expected, atol=1e-14)


def test_slerp_has_constant_angular_speed(rng):
    q0, q1 = random_quats(rng, (20,)), random_quats(rng, (20,))
    t = np.linspace(0, 1, 9)[:, None]
    path = slerp(q0, q1, t)  # (9, 20, 4)
    steps = relative_angle(path[:-1], path[1:])
    total = relative_angle(q0, q1)
    np.testing.assert_allclose(steps, np.broadcast_to(total / 8, steps.shape), atol=1e-9)
    # It also rotates about one fixed axis: the angle from q0 grows linearly with t.
    np.testing.assert_allclose(relative_angle(q0, path), t * total, atol=1e-9)


def test_nlerp_is_not_constant_speed_but_same_path(rng):
    q0 = np.array([1.0, 0, 0, 0])
    q1 = quat_from_axis_angle([0, 0, 1], 2.5)
    t = np.linspace(0, 1, 11)
    steps = relative_angle(nlerp(q0, q1, t)[:-1], nlerp(q0, q1, t)[1:])
    assert steps.max() - steps.min() > 0.05, "nlerp should be faster in the middle"
    assert steps[5] > steps[0]
    # Same great arc as slerp: also a turn about z, reaching the same orientation at the ends.
    q = nlerp(q0, q1, t)
    np.testing.assert_allclose(q[:, 1:3], 0, atol=1e-15)
    assert_quat_equal(q[[0, -1]], [q0, q1], atol=1e-15)


@pytest.mark.parametrize("interp", [slerp, nlerp])
def test_shortest_path_and_endpoints(interp, rng):
    q0, q1 = random_quats(rng, (50,)), random_quats(rng, (50,))
    q1 = np.where((q0 * q1).sum(-1, keepdims=True) > 0, -q1, q1)  # all on the long way round
    np.testing.assert_allclose(interp(q0, q1, 0.0), q0, atol=1e-15)
    assert_quat_equal(interp(q0, q1, 1.0), q1, atol=1e-15)
    mid = interp(q0, q1, 0.5)
    np.testing.assert_allclose(np.linalg.norm(mid, axis=-1), 1, atol=1e-15)
    # Half-way is half the (shortest) rotation angle from each end, never more than pi / 2.
    total = relative_angle(q0, q1)
    np.testing.assert_allclose(relative_angle(q0, mid), total / 2, atol=1e-12)
    np.testing.assert_allclose(relative_angle(mid, q1), total / 2, atol=1e-12)
    assert np.all(relative_angle(q0, mid) <= np.pi / 2 + 1e-12)


def test_t_broadcasts_against_leading_dimensions(rng):
    q0, q1 = random_quats(rng, (5,)), random_quats(rng, (5,))
    t = rng.uniform(0, 1, 5)
    for f in (slerp, nlerp, lerp):
        out = f(q0, q1, t)
        assert out.shape == (5, 4)
        np.testing.assert_allclose(out[2], f(q0[2], q1[2], t[2]), atol=1e-15)
    assert slerp(q0, q1, np.zeros((7, 1))).shape == (7, 5, 4)
    assert slerp(q0[0], q1, 0.5).shape == (5, 4)
    with pytest.raises(ValueError):
        slerp(q0, q1, np.zeros(3))  # (3,) does not broadcast against (5,)


def test_slerp_is_stable_for_nearly_equal_quaternions(rng):
    q0 = random_quats(rng)
    for eps in (0.0, 1e-17, 1e-13, 1e-9):
        q1 = q0 + eps * random_quats(rng)
        out = slerp(q0, q1, np.linspace(0, 1, 5))
        assert np.all(np.isfinite(out))
        np.testing.assert_allclose(np.linalg.norm(out, axis=-1), 1, atol=1e-15)
        np.testing.assert_allclose(out, nlerp(q0, q1, np.linspace(0, 1, 5)), atol=1e-15)
    np.testing.assert_allclose(slerp(q0, q0, 0.3), q0, rtol=0, atol=1e-15)


def test_slerp_extrapolates_at_the_same_speed():
    q0, q1 = np.array([1.0, 0, 0, 0]), quat_from_axis_angle([1, 0, 0], 0.4)
    assert_quat_equal(slerp(q0, q1, 2.5), quat_from_axis_angle([1, 0, 0], 1.0), atol=1e-15)
    assert_quat_equal(slerp(q0, q1, -1.0), quat_from_axis_angle([1, 0, 0], -0.4), atol=1e-15)


def test_lerp_is_linear_and_not_unit(rng):
    a, b = rng.normal(size=(3,)), rng.normal(size=(3,))
    t = np.array([0.0, 0.25, 1.0])
    out = lerp(a, b, t)
    np.testing.assert_array_equal(out[0], a)
    np.testing.assert_array_equal(out[2], b)
    np.testing.assert_allclose(out[1], 0.75 * a + 0.25 * b, atol=1e-15)
    q0, q1 = np.array([1.0, 0, 0, 0]), quat_from_axis_angle([0, 1, 0], 2.0)
    assert np.linalg.norm(lerp(q0, q1, 0.5)) < 0.99


def test_quat_angle_matches_scipy(rng):
    q0, q1 = random_quats(rng, (100,)), random_quats(rng, (100,))
    np.testing.assert_allclose(quat_angle(q0, q1), relative_angle(q0, q1), atol=1e-14)
    np.testing.assert_allclose(quat_angle(q0, -q0), 0, atol=1e-15)
    np.testing.assert_allclose(quat_angle([1, 0, 0, 0], [0, 0, 0, 1]), np.pi)
    # Tiny angles keep their relative accuracy (an arccos of the dot product would not).
    small = quat_from_axis_angle([0, 1, 0], 1e-9)
    assert quat_angle([1, 0, 0, 0], small) == pytest.approx(1e-9, rel=1e-12)


# --- quat_between -----------------------------------------------------------------------


def _angle_between(u, v):
    u = u / np.linalg.norm(u, axis=-1, keepdims=True)
    v = v / np.linalg.norm(v, axis=-1, keepdims=True)
    return np.arctan2(np.linalg.norm(np.cross(u, v), axis=-1), (u * v).sum(-1))


def test_quat_between_is_the_shortest_arc(rng):
    u, v = rng.normal(size=(100, 3)), 3 * rng.normal(size=(100, 3))
    q = quat_between(u, v)
    unit_v = v / np.linalg.norm(v, axis=-1, keepdims=True)
    np.testing.assert_allclose(quat_rotate(q, u / np.linalg.norm(u, axis=-1, keepdims=True)),
                               unit_v, atol=1e-14)
    # Shortest: the turn angle is the angle between u and v, about an axis normal to both.
    np.testing.assert_allclose(rotation_angle(q), _angle_between(u, v), atol=1e-14)
    rotvec = scipy_rotation(q).as_rotvec()
    np.testing.assert_allclose((rotvec * u).sum(-1), 0, atol=1e-13)
    np.testing.assert_allclose((rotvec * v).sum(-1), 0, atol=1e-13)
    # Scipy's align_vectors with one pair is the same (shortest-arc) rotation.
    for n in range(5):
        ref, _ = Rotation.align_vectors(v[n:n + 1], u[n:n + 1])
        assert_quat_equal(q[n], ref.as_quat(scalar_first=True), atol=1e-12)


def test_quat_between_parallel_is_identity(rng):
    u = rng.normal(size=(10, 3))
    assert_quat_equal(quat_between(u, 2.5 * u), np.tile([1.0, 0, 0, 0], (10, 1)), atol=1e-15)


def test_quat_between_antiparallel_is_a_deterministic_half_turn(rng):
    u = np.vstack([np.eye(3), -np.eye(3), rng.normal(size=(10, 3))])
    q = quat_between(u, -0.5 * u)
    np.testing.assert_allclose(rotation_angle(q), np.pi, atol=1e-15)
    np.testing.assert_allclose(q[:, 0], 0, atol=1e-15)
    np.testing.assert_allclose((q[:, 1:] * u).sum(-1), 0, atol=1e-15)  # axis normal to u
    unit_u = u / np.linalg.norm(u, axis=-1, keepdims=True)
    np.testing.assert_allclose(quat_rotate(q, unit_u), -unit_u, atol=1e-15)
    np.testing.assert_array_equal(quat_between(u, -u), q)  # depends on u only
    np.testing.assert_allclose(quat_between([1, 0, 0], [-1, 0, 0]), [0, 0, 0, 1], atol=1e-16)


def test_quat_between_nearly_antiparallel_is_accurate():
    u = np.array([0.3, -0.5, 0.8])
    u /= np.linalg.norm(u)
    for eps in (1e-4, 1e-8, 1e-11):
        v = -u + eps * np.cross(u, [0.0, 0.0, 1.0])
        q = quat_between(u, v)
        np.testing.assert_allclose(quat_rotate(q, u), v / np.linalg.norm(v), atol=1e-14)
        np.testing.assert_allclose(rotation_angle(q), _angle_between(u, v), atol=1e-14)


def test_quat_between_broadcasts():
    q = quat_between([1.0, 0, 0], [[0, 1, 0], [0, 0, 1], [1, 0, 0], [-1, 0, 0]])
    assert q.shape == (4, 4)
    np.testing.assert_allclose(quat_rotate(q, [1.0, 0, 0]),
                               [[0, 1, 0], [0, 0, 1], [1, 0, 0], [-1, 0, 0]], atol=1e-15)


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: slerp([0, 0, 0, 0], [1, 0, 0, 0], 0.5), r"^q0: has zero length.*zero quaternion"),
        (lambda: nlerp([1, 0, 0, 0], np.zeros((2, 4)), 0.5), r"^q1: has zero length at index"),
        (lambda: slerp([1, 0, 0, 0], [1, 0, 0], 0.5), r"^q1: expected shape \(\.\.\., 4\)"),
        (lambda: slerp([1, 0, 0, 0], [1, 0, 0, 0], np.nan), r"^t: is nan; expected a finite"),
        (lambda: nlerp([1, 0, 0, 0], [1, 0, 0, 0], [0.5, np.inf]),
         r"^t: contains NaN or infinity \(the first at index \(1,\)\)$"),
        # Shapes that do not broadcast: the function and every argument with its shape.
        (lambda: slerp(np.ones((2, 4)), np.ones((2, 4)), np.ones(5)),
         r"^slerp: q0, q1 and t do not broadcast together: q0 has shape \(2, 4\) "
         r"\(leading \(2,\)\), q1 has shape \(2, 4\) \(leading \(2,\)\), t has shape \(5,\);"),
        (lambda: slerp(np.ones((2, 4)), np.ones((3, 4)), 0.5),
         r"^slerp: q0, q1 and t do not broadcast.*q1 has shape \(3, 4\)"),
        (lambda: nlerp(np.ones((2, 4)), np.ones((2, 4)), np.ones(5)),
         r"^nlerp: q0, q1 and t do not broadcast together"),
        (lambda: lerp(np.ones((2, 3)), np.ones((4, 3)), 0.5),
         r"^lerp: x0, x1 and t do not broadcast together: x0 has shape \(2, 3\)"),
        (lambda: quat_angle(np.ones((2, 4)), np.ones((3, 4))),
         r"^quat_angle: q0 and q1 do not broadcast together"),
        (lambda: quat_between(np.ones((2, 3)), np.ones((3, 3))),
         r"^quat_between: u and v do not broadcast together: u has shape \(2, 3\)"),
        (lambda: lerp([1, 2], [1, 2, 3], 0.5), r"^x1: expected shape \(\.\.\., 2\)"),
        (lambda: lerp(1.0, 2.0, 0.5), r"^x0: expected shape \(\.\.\., n\)"),
        (lambda: quat_angle([1, 0, 0, 0], [0, 0, 0, 0]), r"^q1: has zero length"),
        (lambda: quat_between([0, 0, 0], [1, 0, 0]), r"^u: has zero length"),
        (lambda: quat_between([1, 0, 0], [[1, 0, 0], [0, 0, 0]]),
         r"^v: has zero length at index \(1,\)"),
        (lambda: quat_between([1, 0, np.inf], [1, 0, 0]), r"^u: contains NaN or infinity"),
    ],
)
def test_bad_input_names_the_argument(call, message):
    with pytest.raises(ValueError, match=message):
        call()
