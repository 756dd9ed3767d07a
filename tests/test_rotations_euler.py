"""Euler angles in all 24 conventions against scipy, including at and near gimbal lock."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from rotation_asserts import assert_quat_equal, random_quats
from scipy.spatial.transform import Rotation

from course.rotations import (
    EULER_ORDERS,
    GIMBAL_LOCK_TOL,
    PROPER_EULER_ORDERS,
    TAIT_BRYAN_ORDERS,
    euler_from_matrix,
    euler_from_quat,
    gimbal_lock_distance,
    is_gimbal_lock,
    matrix_from_euler,
    matrix_from_quat,
    quat_from_euler,
)

N = 200


def _rng(order: str) -> np.random.Generator:
    return np.random.default_rng([EULER_ORDERS.index(order), 11])


def _is_proper(order: str) -> bool:
    return order.upper() in PROPER_EULER_ORDERS


def _lock_values(order: str) -> tuple[float, float]:
    return (0.0, np.pi) if _is_proper(order) else (np.pi / 2, -np.pi / 2)


def _scipy_euler(R: np.ndarray, order: str) -> np.ndarray:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # scipy's "Gimbal lock detected"
        return Rotation.from_matrix(R).as_euler(order)


def _wrapped_diff(a, b):
    return (np.asarray(a) - b + np.pi) % (2 * np.pi) - np.pi


def test_there_are_24_conventions():
    assert len(EULER_ORDERS) == len(set(EULER_ORDERS)) == 24
    assert set(EULER_ORDERS) == {
        o for base in TAIT_BRYAN_ORDERS + PROPER_EULER_ORDERS for o in (base, base.lower())
    }


@pytest.mark.parametrize("order", EULER_ORDERS)
def test_matrix_and_quat_from_euler_match_scipy(order):
    angles = _rng(order).uniform(-np.pi, np.pi, (N, 3))
    expected = Rotation.from_euler(order, angles)
    np.testing.assert_allclose(matrix_from_euler(angles, order), expected.as_matrix(),
                               atol=1e-15)
    q = quat_from_euler(angles, order)
    assert_quat_equal(q, expected.as_quat(scalar_first=True), atol=1e-15)
    assert np.all(q[:, 0] >= 0)


@pytest.mark.parametrize("order", EULER_ORDERS)
def test_euler_from_matrix_matches_scipy_and_round_trips(order):
    R = Rotation.random(N, random_state=EULER_ORDERS.index(order)).as_matrix()
    angles, locked = euler_from_matrix(R, order, return_gimbal_lock=True)
    assert not locked.any()
    np.testing.assert_allclose(matrix_from_euler(angles, order), R, atol=1e-14)
    # Away from lock the angles are unique in their ranges, so equal scipy's.
    np.testing.assert_allclose(_wrapped_diff(angles, _scipy_euler(R, order)), 0, atol=1e-12)
    middle = angles[:, 1]
    if _is_proper(order):
        assert np.all((middle >= 0) & (middle <= np.pi))
    else:
        assert np.all(np.abs(middle) <= np.pi / 2)
    assert np.all((angles[:, [0, 2]] >= -np.pi) & (angles[:, [0, 2]] < np.pi))
    # Through the quaternion, in either sign.
    q = Rotation.from_matrix(R).as_quat(scalar_first=True)
    np.testing.assert_allclose(euler_from_quat(q, order), angles, atol=1e-15)
    np.testing.assert_allclose(euler_from_quat(-q, order), angles, atol=1e-15)


@pytest.mark.parametrize("order", EULER_ORDERS)
def test_gimbal_lock_is_reported_and_third_angle_is_zero(order):
    rng = _rng(order)
    for lock in _lock_values(order):
        angles = rng.uniform(-np.pi, np.pi, (50, 3))
        angles[:, 1] = lock
        R = matrix_from_euler(angles, order)
        got, locked = euler_from_matrix(R, order, return_gimbal_lock=True)
        assert locked.all(), f"{order}: middle angle {lock} not reported as gimbal lock"
        np.testing.assert_array_equal(got[:, 2], 0.0)
        np.testing.assert_allclose(matrix_from_euler(got, order), R, atol=1e-14)
        # The same deterministic choice as scipy.
        np.testing.assert_allclose(_wrapped_diff(got, _scipy_euler(R, order)), 0, atol=1e-12)
        assert is_gimbal_lock(got, order).all()
        np.testing.assert_allclose(gimbal_lock_distance(angles, order), 0, atol=1e-15)


@pytest.mark.parametrize("order", EULER_ORDERS)
def test_near_gimbal_lock_reproduces_the_matrix(order):
    rng = _rng(order)
    for lock in _lock_values(order):
        for delta in (1e-7, -1e-7, 1e-9, 1e-12, -1e-13):
            angles = rng.uniform(-np.pi, np.pi, (50, 3))
            angles[:, 1] = lock + delta
            R = matrix_from_euler(angles, order)
            got, locked = euler_from_matrix(R, order, return_gimbal_lock=True)
            # Locked (only within GIMBAL_LOCK_TOL) costs at most twice the distance to lock.
            np.testing.assert_allclose(matrix_from_euler(got, order), R, rtol=0,
                                       atol=1e-14 + 2 * abs(delta) * locked.any(),
                                       err_msg=f"{order} middle angle {lock} + {delta}")
            if abs(delta) >= 1e-9:
                assert not locked.any()
                np.testing.assert_allclose(gimbal_lock_distance(got, order), abs(delta),
                                           rtol=1e-5)


@pytest.mark.parametrize("order", EULER_ORDERS)
def test_one_gimbal_lock_tolerance(order):
    """euler_from_* and is_gimbal_lock (by default) call the same rotations locked: those
    within GIMBAL_LOCK_TOL of lock, and no others."""
    rng = _rng(order)
    for lock in _lock_values(order):
        for factor, expect in ((0.0, True), (0.5, True), (2.0, False), (1e3, False)):
            for sign in (1.0, -1.0):
                delta = sign * factor * GIMBAL_LOCK_TOL
                angles = rng.uniform(-np.pi, np.pi, (50, 3))
                angles[:, 1] = lock + delta
                R = matrix_from_euler(angles, order)
                got, locked = euler_from_matrix(R, order, return_gimbal_lock=True)
                where = f"{order} middle angle {lock} + {delta:g}"
                assert (locked == expect).all(), where
                np.testing.assert_array_equal(is_gimbal_lock(got, order), locked, err_msg=where)
                np.testing.assert_array_equal(is_gimbal_lock(angles, order), locked,
                                              err_msg=where)
                np.testing.assert_array_equal(
                    is_gimbal_lock(np.degrees(got), order, degrees=True), locked, err_msg=where)
                if expect:
                    np.testing.assert_array_equal(got[:, 2], 0.0)
                np.testing.assert_allclose(matrix_from_euler(got, order), R, rtol=0,
                                           atol=1e-14 + 2 * abs(delta) * expect, err_msg=where)


@pytest.mark.parametrize("order", ["XYZ", "zyx", "ZXZ", "yzy"])
def test_degrees_option(order):
    angles = _rng(order).uniform(-180, 180, (20, 3))
    np.testing.assert_allclose(matrix_from_euler(angles, order, degrees=True),
                               Rotation.from_euler(order, angles, degrees=True).as_matrix(),
                               atol=1e-15)
    np.testing.assert_allclose(quat_from_euler(angles, order, degrees=True),
                               quat_from_euler(np.radians(angles), order), atol=1e-15)
    R = matrix_from_euler(angles, order, degrees=True)
    got = euler_from_matrix(R, order, degrees=True)
    np.testing.assert_allclose(got, np.degrees(euler_from_matrix(R, order)), atol=1e-12)
    np.testing.assert_allclose(matrix_from_euler(got, order, degrees=True), R, atol=1e-14)
    q = quat_from_euler(angles, order, degrees=True)
    np.testing.assert_allclose(euler_from_quat(q, order, degrees=True), got, atol=1e-11)


def test_intrinsic_is_extrinsic_reversed():
    a, b, c = 0.3, -1.1, 2.5
    Rx, Ry, Rz = (Rotation.from_euler(axis, angle).as_matrix()
                  for axis, angle in zip("xyz", (a, b, c), strict=True))
    np.testing.assert_allclose(matrix_from_euler([a, b, c], "XYZ"), Rx @ Ry @ Rz, atol=1e-15)
    np.testing.assert_allclose(matrix_from_euler([a, b, c], "xyz"), Rz @ Ry @ Rx, atol=1e-15)
    np.testing.assert_allclose(matrix_from_euler([c, b, a], "zyx"),
                               matrix_from_euler([a, b, c], "XYZ"), atol=1e-15)


def test_elementary_rotations_are_right_handed():
    R = matrix_from_euler([np.pi / 2, 0, 0], "ZYX")  # a quarter turn about z
    np.testing.assert_allclose(R @ [1, 0, 0], [0, 1, 0], atol=1e-15)
    np.testing.assert_allclose(matrix_from_euler([0, 0, 90], "ZYX", degrees=True) @ [0, 1, 0],
                               [0, 0, 1], atol=1e-15)


def test_batched_shapes():
    rng = np.random.default_rng(3)
    angles = rng.uniform(-1, 1, (4, 5, 3))
    R = matrix_from_euler(angles, "YXZ")
    assert R.shape == (4, 5, 3, 3)
    assert quat_from_euler(angles, "YXZ").shape == (4, 5, 4)
    got, locked = euler_from_matrix(R, "YXZ", return_gimbal_lock=True)
    assert got.shape == (4, 5, 3) and locked.shape == (4, 5) and locked.dtype == bool
    np.testing.assert_allclose(got, angles, atol=1e-14)
    q = random_quats(rng, (2, 3))
    np.testing.assert_allclose(matrix_from_euler(euler_from_quat(q, "zxz"), "zxz"),
                               matrix_from_quat(q), atol=1e-14)


def test_is_gimbal_lock_tolerance_and_degrees():
    angles = np.array([[10, 88, 5], [10, 90, 5], [10, -91, 5], [10, 30, 5], [0, 270, 0]])
    np.testing.assert_allclose(gimbal_lock_distance(angles, "ZYX", degrees=True),
                               [2, 0, 1, 60, 0], atol=1e-12)
    np.testing.assert_array_equal(is_gimbal_lock(angles, "ZYX", degrees=True, tol=1.5),
                                  [False, True, True, False, True])
    np.testing.assert_array_equal(is_gimbal_lock(np.radians(angles), "ZYX"),
                                  [False, True, False, False, True])
    proper = np.radians([[0, 179.5, 0], [0, 0.2, 0], [0, 90, 0], [0, -360, 0]])
    np.testing.assert_array_equal(is_gimbal_lock(proper, "zxz", tol=np.radians(1)),
                                  [True, True, False, True])
    with pytest.raises(ValueError, match="^tol:"):
        is_gimbal_lock(angles, "ZYX", tol=-1)


@pytest.mark.parametrize(
    ("order", "why"),
    [
        ("XYY", "turns about the same axis twice in a row"),
        ("XXZ", "turns about the same axis twice in a row"),
        ("xYz", "mixes upper and lower case"),
        ("XY", "has 2 characters"),
        ("XYZX", "has 4 characters"),
        ("XYW", "uses a letter other than x, y and z"),
        ("", "has 0 characters"),
    ],
)
def test_unknown_order_is_rejected(order, why):
    for call in (lambda: matrix_from_euler([0, 0, 0], order),
                 lambda: euler_from_matrix(np.eye(3), order),
                 lambda: quat_from_euler([0, 0, 0], order),
                 lambda: euler_from_quat([1, 0, 0, 0], order),
                 lambda: is_gimbal_lock([0, 0, 0], order)):
        with pytest.raises(ValueError, match=f"^order: {order!r} {why}"):
            call()


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: matrix_from_euler([0, 0, 0], 123), r"^order: expected a string"),
        (lambda: matrix_from_euler([0, 0], "XYZ"), r"^angles: expected shape \(\.\.\., 3\)"),
        (lambda: quat_from_euler([0, np.nan, 0], "XYZ"), r"^angles: contains NaN"),
        (lambda: euler_from_matrix(np.zeros((3, 3)), "XYZ"), r"^R: not a rotation matrix"),
        (lambda: euler_from_quat([0, 0, 0, 0], "XYZ"), r"^q: has zero length"),
        (lambda: euler_from_quat([1, 0, 0], "XYZ"), r"^q: expected shape \(\.\.\., 4\)"),
    ],
)
def test_bad_input_names_the_argument(call, message):
    with pytest.raises(ValueError, match=message):
        call()
