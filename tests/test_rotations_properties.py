"""Algebraic properties of the rotation library, checked by hypothesis (derandomised)."""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from rotation_asserts import assert_quat_equal, assert_same_rotation, relative_angle

from course.rotations import (
    EULER_ORDERS,
    GIMBAL_LOCK_TOL,
    axis_angle_from_quat,
    euler_from_matrix,
    euler_from_quat,
    matrix_from_axis_angle,
    matrix_from_euler,
    matrix_from_quat,
    quat_between,
    quat_from_axis_angle,
    quat_from_matrix,
    quat_from_rotvec,
    quat_identity,
    quat_inverse,
    quat_mul,
    quat_rotate,
    rotvec_from_quat,
    slerp,
)

PROPERTY = settings(max_examples=60, derandomize=True, deadline=None, database=None,
                    suppress_health_check=[HealthCheck.too_slow])

coord = st.floats(-1.0, 1.0, allow_nan=False, allow_infinity=False)
vectors = st.tuples(coord, coord, coord).map(np.array).filter(
    lambda v: np.linalg.norm(v) > 1e-3)
quats = st.tuples(coord, coord, coord, coord).map(np.array).filter(
    lambda q: np.linalg.norm(q) > 1e-3).map(lambda q: q / np.linalg.norm(q))
# Special angles (lock, half turns, zero) are likely, not only generic ones.
angles = st.one_of(st.floats(-2 * np.pi, 2 * np.pi),
                   st.sampled_from([0.0, np.pi / 2, -np.pi / 2, np.pi, -np.pi, 1e-8]))
ts = st.floats(0.0, 1.0)


@PROPERTY
@given(quats, quats)
def test_product_keeps_unit_norm_and_matches_matrix_product(a, b):
    ab = quat_mul(a, b)
    assert abs(np.linalg.norm(ab) - 1) < 1e-14
    np.testing.assert_allclose(matrix_from_quat(ab), matrix_from_quat(a) @ matrix_from_quat(b),
                               atol=1e-14)


@PROPERTY
@given(quats, quats, quats)
def test_product_is_associative(a, b, c):
    np.testing.assert_allclose(quat_mul(quat_mul(a, b), c), quat_mul(a, quat_mul(b, c)),
                               atol=1e-14)


@PROPERTY
@given(quats)
def test_inverse_gives_identity(q):
    np.testing.assert_allclose(quat_mul(q, quat_inverse(q)), quat_identity(), atol=1e-15)
    np.testing.assert_allclose(matrix_from_quat(quat_inverse(q)), matrix_from_quat(q).T,
                               atol=1e-15)


@PROPERTY
@given(quats, vectors)
def test_rotate_preserves_length_and_matches_matrix(q, v):
    w = quat_rotate(q, v)
    assert abs(np.linalg.norm(w) - np.linalg.norm(v)) < 1e-14
    np.testing.assert_allclose(w, matrix_from_quat(q) @ v, atol=1e-14)


@PROPERTY
@given(quats, quats, ts)
def test_slerp_stays_unit_and_between_the_ends(q0, q1, t):
    q = slerp(q0, q1, t)
    assert abs(np.linalg.norm(q) - 1) < 1e-14
    # On the shortest arc, at the fraction t of the way.
    total = relative_angle(q0, q1)
    assert abs(relative_angle(q0, q) - t * total) < 1e-12
    assert abs(relative_angle(q, q1) - (1 - t) * total) < 1e-12


@PROPERTY
@given(quats)
def test_matrix_quat_round_trip(q):
    assert_quat_equal(quat_from_matrix(matrix_from_quat(q)), q, atol=1e-14)


@PROPERTY
@given(quats)
def test_axis_angle_and_rotvec_round_trips(q):
    axis, angle = axis_angle_from_quat(q)
    assert 0 <= angle <= np.pi
    assert_quat_equal(quat_from_axis_angle(axis, angle), q, atol=1e-14)
    np.testing.assert_allclose(matrix_from_axis_angle(axis, angle), matrix_from_quat(q),
                               atol=1e-14)
    assert_quat_equal(quat_from_rotvec(rotvec_from_quat(q)), q, atol=1e-14)


@PROPERTY
@given(st.tuples(angles, angles, angles).map(np.array), st.sampled_from(EULER_ORDERS))
def test_euler_round_trip_reproduces_the_rotation(euler, order):
    R = matrix_from_euler(euler, order)
    back, locked = euler_from_matrix(R, order, return_gimbal_lock=True)
    # Exact away from lock; within GIMBAL_LOCK_TOL of it, moving the third angle into the
    # first turns the rotation by at most twice the distance to lock.
    atol = 1e-14 + (2 * GIMBAL_LOCK_TOL if locked else 0.0)
    np.testing.assert_allclose(matrix_from_euler(back, order), R, rtol=0, atol=atol)
    assert_same_rotation(matrix_from_euler(euler_from_quat(quat_from_matrix(R), order), order),
                         R, atol=atol)


@PROPERTY
@given(vectors, vectors)
def test_quat_between_turns_u_onto_v(u, v):
    q = quat_between(u, v)
    assert abs(np.linalg.norm(q) - 1) < 1e-14
    np.testing.assert_allclose(quat_rotate(q, u / np.linalg.norm(u)), v / np.linalg.norm(v),
                               atol=1e-12)
