"""Axis-angle, rotation vectors, Rodrigues' formula and the cross-product matrix, vs scipy."""

from __future__ import annotations

import numpy as np
import pytest
from rotation_asserts import assert_quat_equal, assert_same_rotation, random_quats
from scipy.spatial.transform import Rotation

from course.rotations import (
    DEFAULT_AXIS,
    axis_angle_from_matrix,
    axis_angle_from_quat,
    matrix_from_axis_angle,
    matrix_from_quat,
    matrix_from_rotvec,
    quat_from_axis_angle,
    quat_from_rotvec,
    rotvec_from_matrix,
    rotvec_from_quat,
    skew,
)


@pytest.fixture
def rng():
    return np.random.default_rng(7)


def _axes_angles(rng, n):
    axis = rng.normal(size=(n, 3))
    return axis / np.linalg.norm(axis, axis=-1, keepdims=True), rng.uniform(-2 * np.pi,
                                                                           2 * np.pi, n)


def test_quat_from_axis_angle_matches_scipy(rng):
    axis, angle = _axes_angles(rng, 50)
    expected = Rotation.from_rotvec(axis * angle[:, None]).as_quat(scalar_first=True)
    assert_quat_equal(quat_from_axis_angle(axis, angle), expected)
    # Any non-zero axis length, and the half-angle form q = (cos θ/2, sin θ/2 u).
    q = quat_from_axis_angle(5 * axis, angle)
    np.testing.assert_allclose(q[:, 0], np.cos(angle / 2), atol=1e-15)
    np.testing.assert_allclose(q[:, 1:], np.sin(angle / 2)[:, None] * axis, atol=1e-15)


def test_axis_angle_broadcasting_and_degrees():
    angles = np.linspace(0, np.pi, 7)
    q = quat_from_axis_angle([0, 0, 2], angles)
    assert q.shape == (7, 4)
    np.testing.assert_allclose(q[:, 3], np.sin(angles / 2))
    np.testing.assert_allclose(quat_from_axis_angle([0, 0, 1], np.degrees(angles), degrees=True),
                               q, atol=1e-15)
    R = matrix_from_axis_angle([[1, 0, 0], [0, 1, 0]], 90, degrees=True)
    np.testing.assert_allclose(R[0] @ [0, 1, 0], [0, 0, 1], atol=1e-15)
    np.testing.assert_allclose(R[1] @ [0, 0, 1], [1, 0, 0], atol=1e-15)
    axis, angle = axis_angle_from_quat(q[3], degrees=True)
    np.testing.assert_allclose(angle, 90)
    np.testing.assert_allclose(axis, [0, 0, 1])


def test_axis_angle_from_quat_round_trip(rng):
    axis, angle = _axes_angles(rng, 100)
    angle = np.abs(angle) % np.pi  # the representable range [0, pi)
    got_axis, got_angle = axis_angle_from_quat(quat_from_axis_angle(axis, angle))
    np.testing.assert_allclose(got_angle, angle, atol=1e-14)
    np.testing.assert_allclose(got_axis, axis, atol=1e-13)


def test_axis_angle_from_quat_range_and_sign(rng):
    q = random_quats(rng, (200,))
    axis, angle = axis_angle_from_quat(q)
    assert np.all((angle >= 0) & (angle <= np.pi))
    np.testing.assert_allclose(np.linalg.norm(axis, axis=-1), 1, atol=1e-15)
    neg_axis, neg_angle = axis_angle_from_quat(-q)
    np.testing.assert_array_equal(neg_angle, angle)
    np.testing.assert_array_equal(neg_axis, axis)
    assert_quat_equal(quat_from_axis_angle(axis, angle), q, atol=1e-14)
    # Scipy's rotation-vector magnitude is the same angle.
    np.testing.assert_allclose(angle, Rotation.from_quat(q, scalar_first=True).magnitude(),
                               atol=1e-14)


def test_identity_gives_angle_zero_about_default_axis():
    axis, angle = axis_angle_from_quat([1, 0, 0, 0])
    assert angle == 0
    np.testing.assert_array_equal(axis, DEFAULT_AXIS)
    np.testing.assert_array_equal(DEFAULT_AXIS, [1, 0, 0])
    axis, angle = axis_angle_from_matrix(np.eye(3))
    assert angle == 0
    np.testing.assert_array_equal(axis, [1, 0, 0])
    np.testing.assert_array_equal(rotvec_from_quat([-1, 0, 0, 0]), [0, 0, 0])


def test_half_turn_axis_has_positive_first_component():
    for sign in (1, -1):
        axis, angle = axis_angle_from_quat([0, 0, sign * 0.6, -sign * 0.8])
        assert angle == pytest.approx(np.pi)
        np.testing.assert_allclose(axis, [0, 0.6, -0.8])


def test_tiny_angles_keep_full_relative_accuracy():
    for theta in (1e-6, 1e-10, 1e-15, 1e-150):
        axis = np.array([2.0, -1.0, 2.0]) / 3
        axis_out, angle = axis_angle_from_quat(quat_from_axis_angle(axis, theta))
        assert angle == pytest.approx(theta, rel=1e-14)
        np.testing.assert_allclose(axis_out, axis, rtol=1e-14)
        np.testing.assert_allclose(rotvec_from_quat(quat_from_rotvec(theta * axis)), theta * axis,
                                   rtol=1e-14)


def _rodrigues_reference(axis, angle):
    """R = I + sin θ K + (1 - cos θ) K^2 with K built from cross products of the basis."""
    K = np.stack([np.cross(axis, e) for e in np.eye(3)], axis=-1)
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def test_rodrigues_matches_scipy_and_the_formula(rng):
    axis, angle = _axes_angles(rng, 50)
    R = matrix_from_axis_angle(axis, angle)
    np.testing.assert_allclose(R, Rotation.from_rotvec(axis * angle[:, None]).as_matrix(),
                               atol=1e-15)
    for n in range(5):
        np.testing.assert_allclose(R[n], _rodrigues_reference(axis[n], angle[n]), atol=1e-15)
    np.testing.assert_allclose(R, matrix_from_quat(quat_from_axis_angle(axis, angle)),
                               atol=1e-15)


def test_axis_angle_from_matrix_near_half_turn(rng):
    axis, _ = _axes_angles(rng, 20)
    for angle in (np.pi, np.pi - 1e-9, np.pi - 1e-5, 1e-9, 0.5):
        got_axis, got_angle = axis_angle_from_matrix(matrix_from_axis_angle(axis, angle))
        np.testing.assert_allclose(got_angle, angle, atol=1e-14)
        # At exactly pi the axis may come back as -axis (same rotation).
        assert_same_rotation(matrix_from_axis_angle(got_axis, got_angle),
                             matrix_from_axis_angle(axis, angle), atol=1e-14)


def test_rotvec_matches_scipy(rng):
    q = random_quats(rng, (100,))
    scipy_rot = Rotation.from_quat(q, scalar_first=True)
    rotvec = scipy_rot.as_rotvec()
    np.testing.assert_allclose(rotvec_from_quat(q), rotvec, atol=1e-14)
    np.testing.assert_allclose(rotvec_from_matrix(scipy_rot.as_matrix()), rotvec, atol=1e-14)
    assert_quat_equal(quat_from_rotvec(rotvec), q, atol=1e-15)
    np.testing.assert_allclose(matrix_from_rotvec(rotvec), scipy_rot.as_matrix(), atol=1e-15)
    assert np.all(np.linalg.norm(rotvec_from_quat(q), axis=-1) <= np.pi + 1e-15)
    # Degrees: the length of the vector is in degrees.
    np.testing.assert_allclose(rotvec_from_quat(q, degrees=True),
                               scipy_rot.as_rotvec(degrees=True), atol=1e-12)
    np.testing.assert_allclose(matrix_from_rotvec(np.degrees(rotvec), degrees=True),
                               scipy_rot.as_matrix(), atol=1e-15)
    # Rotation vectors longer than pi wrap around.
    long = rotvec * ((np.linalg.norm(rotvec, axis=-1) + 2 * np.pi)
                     / np.linalg.norm(rotvec, axis=-1))[:, None]
    assert_quat_equal(quat_from_rotvec(long), q, atol=1e-14)


def test_zero_rotvec_is_identity():
    np.testing.assert_array_equal(quat_from_rotvec(np.zeros((2, 3))), [[1, 0, 0, 0]] * 2)
    np.testing.assert_array_equal(matrix_from_rotvec([0, 0, 0]), np.eye(3))
    np.testing.assert_array_equal(rotvec_from_matrix(np.eye(3)), [0, 0, 0])


def test_skew_is_the_cross_product_matrix(rng):
    v, w = rng.normal(size=(10, 3)), rng.normal(size=(10, 3))
    K = skew(v)
    assert K.shape == (10, 3, 3)
    np.testing.assert_allclose(np.einsum("nij,nj->ni", K, w), np.cross(v, w), atol=1e-15)
    np.testing.assert_array_equal(np.swapaxes(K, -1, -2), -K)
    np.testing.assert_array_equal(skew([1, 2, 3]), [[0, -3, 2], [3, 0, -1], [-2, 1, 0]])


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: quat_from_axis_angle([0, 0, 0], 1.0), r"^axis: has zero length.*rotation axis"),
        (lambda: matrix_from_axis_angle([[1, 0, 0], [0, 0, 0]], 1.0),
         r"^axis: has zero length at index \(1,\)"),
        (lambda: quat_from_axis_angle([1, 0], 1.0), r"^axis: expected shape \(\.\.\., 3\)"),
        (lambda: quat_from_axis_angle([1, 0, 0], np.nan), r"^angle: is nan; expected a finite"),
        (lambda: quat_from_axis_angle([1, 0, 0], [0.0, -np.inf]),
         r"^angle: contains NaN or infinity \(the first at index \(1,\)\)$"),
        (lambda: quat_from_axis_angle([1, 0, 0], "ninety"), r"^angle: expected numbers"),
        (lambda: matrix_from_axis_angle(np.ones((2, 3)), np.ones(3)),
         r"^matrix_from_axis_angle: axis and angle do not broadcast together: axis has shape "
         r"\(2, 3\) \(leading \(2,\)\), angle has shape \(3,\);"),
        (lambda: quat_from_axis_angle(np.ones((4, 3)), np.ones(5)),
         r"^quat_from_axis_angle: axis and angle do not broadcast together.*\(5,\)"),
        (lambda: axis_angle_from_quat([0, 0, 0, 0]), r"^q: has zero length"),
        (lambda: quat_from_rotvec([1, 2]), r"^rotvec: expected shape \(\.\.\., 3\)"),
        (lambda: matrix_from_rotvec([np.inf, 0, 0]), r"^rotvec: contains NaN or infinity"),
        (lambda: rotvec_from_matrix(np.ones((3, 3))), r"^R: not a rotation matrix"),
        (lambda: skew([1, 2, 3, 4]), r"^v: expected shape \(\.\.\., 3\)"),
    ],
)
def test_bad_input_names_the_argument(call, message):
    with pytest.raises(ValueError, match=message):
        call()
