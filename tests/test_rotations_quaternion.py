"""Quaternion algebra against scipy and the Hamilton multiplication table."""

from __future__ import annotations

import numpy as np
import pytest
from rotation_asserts import (
    assert_quat_equal,
    assert_same_rotation,
    random_quats,
    scipy_quat,
    scipy_rotation,
)
from scipy.spatial.transform import Rotation

from course.rotations import (
    matrix_from_quat,
    quat_canonical,
    quat_conjugate,
    quat_from_matrix,
    quat_identity,
    quat_inverse,
    quat_mul,
    quat_normalize,
    quat_rotate,
)
from course.rotations._kernels import quat_mul as _mul
from course.rotations._kernels import quat_rotate as _rotate

RNG_SEED = 20240105


@pytest.fixture
def rng():
    return np.random.default_rng(RNG_SEED)


def test_identity_shapes():
    assert quat_identity().tolist() == [1, 0, 0, 0]
    assert quat_identity(5).shape == (5, 4)
    q = quat_identity((2, 3))
    assert q.shape == (2, 3, 4)
    assert np.all(q == [1, 0, 0, 0])


def test_hamilton_table():
    one, i, j, k = np.eye(4)
    assert_quat_equal(quat_mul(i, j), k, 0)
    assert_quat_equal(quat_mul(j, k), i, 0)
    assert_quat_equal(quat_mul(k, i), j, 0)
    np.testing.assert_array_equal(quat_mul(j, i), -k)
    for unit in (i, j, k):
        np.testing.assert_array_equal(quat_mul(unit, unit), -one)
    # i j k = -1, Hamilton's defining relation.
    np.testing.assert_array_equal(quat_mul(quat_mul(i, j), k), -one)


def test_mul_matches_scipy_composition(rng):
    a, b = random_quats(rng, (50,)), random_quats(rng, (50,))
    expected = scipy_quat(scipy_rotation(a) * scipy_rotation(b), (50,))
    assert_quat_equal(quat_mul(a, b), expected)
    # The product of quaternions is the quaternion of the product of matrices.
    np.testing.assert_allclose(matrix_from_quat(quat_mul(a, b)),
                               matrix_from_quat(a) @ matrix_from_quat(b), atol=1e-14)


def test_mul_broadcasts(rng):
    a, b = random_quats(rng, (3, 1)), random_quats(rng, (5,))
    ab = quat_mul(a, b)
    assert ab.shape == (3, 5, 4)
    np.testing.assert_allclose(ab[2, 4], quat_mul(a[2, 0], b[4]), atol=1e-15)


def test_private_helpers_agree_with_public(rng):
    a, b, v = random_quats(rng, (20,)), random_quats(rng, (20,)), rng.normal(size=(20, 3))
    np.testing.assert_array_equal(_mul(a, b), quat_mul(a, b))
    np.testing.assert_allclose(_rotate(a, v), quat_rotate(a, v), atol=1e-15)


def test_conjugate_and_inverse(rng):
    q = random_quats(rng, (30,))
    np.testing.assert_array_equal(quat_conjugate(q), q * [1, -1, -1, -1])
    assert_quat_equal(quat_mul(q, quat_conjugate(q)), quat_identity((30,)))
    scaled = q * rng.uniform(0.1, 10, (30, 1))  # the inverse works for non-unit too
    np.testing.assert_allclose(quat_mul(scaled, quat_inverse(scaled)), quat_identity((30,)),
                               atol=1e-14)
    np.testing.assert_allclose(quat_mul(quat_inverse(scaled), scaled), quat_identity((30,)),
                               atol=1e-14)
    assert_same_rotation(quat_inverse(q), scipy_quat(scipy_rotation(q).inv(), (30,)))


def test_algebra_takes_non_unit_quaternions(rng):
    # The sandwich q (0, v) q* of the lecture rotates v: pure quaternions are fine.
    q, v = random_quats(rng, (10,)), rng.normal(size=(10, 3))
    pure = np.concatenate([np.zeros((10, 1)), v], axis=-1)
    sandwich = quat_mul(quat_mul(q, pure), quat_conjugate(q))
    np.testing.assert_allclose(sandwich[:, 0], 0, atol=1e-15)
    np.testing.assert_allclose(sandwich[:, 1:], scipy_rotation(q).apply(v), atol=1e-14)
    # A scaled quaternion keeps its length through the product, conjugate and sign choice.
    np.testing.assert_allclose(quat_mul(3 * q, 2 * q), 6 * quat_mul(q, q), rtol=0, atol=1e-14)
    np.testing.assert_array_equal(quat_canonical(-5 * q), 5 * quat_canonical(q))


def test_normalize(rng):
    q = rng.normal(size=(10, 4)) * 7
    n = quat_normalize(q)
    np.testing.assert_allclose(np.linalg.norm(n, axis=-1), 1, atol=1e-15)
    np.testing.assert_allclose(n * np.linalg.norm(q, axis=-1, keepdims=True), q, rtol=1e-14)


def test_canonical_picks_w_nonnegative(rng):
    q = random_quats(rng, (100,))
    c = quat_canonical(q)
    assert np.all(c[:, 0] >= 0)
    assert_quat_equal(c, q)
    np.testing.assert_array_equal(quat_canonical(c), c)
    np.testing.assert_array_equal(quat_canonical(-q), c)


def test_canonical_half_turns_use_first_nonzero_component():
    np.testing.assert_array_equal(quat_canonical([0, -1, 0, 0]), [0, 1, 0, 0])
    np.testing.assert_array_equal(quat_canonical([0, 0, -0.6, 0.8]), [0, 0, 0.6, -0.8])
    np.testing.assert_array_equal(quat_canonical([0, 0, 0.6, -0.8]), [0, 0, 0.6, -0.8])


def test_rotate_matches_scipy_and_matrix(rng):
    q, v = random_quats(rng, (40,)), rng.normal(size=(40, 3))
    expected = scipy_rotation(q).apply(v)
    np.testing.assert_allclose(quat_rotate(q, v), expected, atol=1e-14)
    np.testing.assert_allclose(np.einsum("nij,nj->ni", matrix_from_quat(q), v), expected,
                               atol=1e-14)
    # A non-unit q is normalised first.
    np.testing.assert_allclose(quat_rotate(3 * q, v), expected, atol=1e-14)


def test_rotate_quarter_turn_about_z():
    q = [np.cos(np.pi / 4), 0, 0, np.sin(np.pi / 4)]
    np.testing.assert_allclose(quat_rotate(q, [1, 0, 0]), [0, 1, 0], atol=1e-15)


def test_rotate_broadcasts(rng):
    q, v = random_quats(rng, (6, 1)), rng.normal(size=(4, 3))
    out = quat_rotate(q, v)
    assert out.shape == (6, 4, 3)
    np.testing.assert_allclose(out[5, 3], quat_rotate(q[5, 0], v[3]), atol=1e-15)


def test_matrix_from_quat_matches_scipy(rng):
    q = random_quats(rng, (60,))
    R = matrix_from_quat(q)
    np.testing.assert_allclose(R, scipy_rotation(q).as_matrix(), atol=1e-15)
    np.testing.assert_allclose(np.swapaxes(R, -1, -2) @ R, np.broadcast_to(np.eye(3), R.shape),
                               atol=1e-15)
    np.testing.assert_allclose(np.linalg.det(R), 1, atol=1e-14)


def _hard_matrices(rng):
    """Identity, half turns (w = 0: the branch Shepperd's method exists for) and near them."""
    axes = np.vstack([np.eye(3), rng.normal(size=(20, 3))])
    axes /= np.linalg.norm(axes, axis=-1, keepdims=True)
    angles = np.array([0.0, 1e-9, np.pi, np.pi - 1e-9, np.pi - 1e-5, 2.0])
    rotvecs = (axes[:, None, :] * angles[None, :, None]).reshape(-1, 3)
    return Rotation.from_rotvec(rotvecs).as_matrix()


def test_quat_from_matrix_matches_scipy(rng):
    R = np.concatenate([Rotation.random(100, random_state=RNG_SEED).as_matrix(),
                        _hard_matrices(rng)])
    q = quat_from_matrix(R)
    assert_quat_equal(q, Rotation.from_matrix(R).as_quat(scalar_first=True), atol=1e-14)
    np.testing.assert_allclose(np.linalg.norm(q, axis=-1), 1, atol=1e-15)
    assert np.all(q[:, 0] >= -1e-15)  # half turns: w is rounding noise, the sign rule uses x
    np.testing.assert_allclose(matrix_from_quat(q), R, atol=1e-15)
    # Half turns come back in the canonical sign.
    np.testing.assert_array_equal(quat_canonical(q), q)


def test_quat_from_matrix_round_trip_batched(rng):
    q = quat_canonical(random_quats(rng, (4, 5)))
    np.testing.assert_allclose(quat_from_matrix(matrix_from_quat(q)), q, atol=1e-15)


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: quat_mul([1, 0, 0], [1, 0, 0, 0]), r"^a: expected shape \(\.\.\., 4\)"),
        (lambda: quat_mul([1, 0, 0, 0], np.ones((2, 3))), r"^b: expected shape"),
        (lambda: quat_normalize([0, 0, 0, 0]), r"^q: has zero length.*zero quaternion"),
        (lambda: quat_inverse(np.zeros((3, 4))), r"^q: has zero length at index \(0,\)"),
        (lambda: quat_rotate([0, 0, 0, 0], [1, 0, 0]), r"^q: has zero length"),
        (lambda: quat_rotate([1, 0, 0, 0], [1, 0]), r"^v: expected shape \(\.\.\., 3\)"),
        (lambda: matrix_from_quat([1, np.nan, 0, 0]), r"^q: contains NaN.*index \(1,\)"),
        (lambda: quat_canonical([1, 0, np.inf, 0]), r"^q: contains NaN or infinity"),
        # The zero quaternion is refused everywhere, the algebra included.
        (lambda: quat_mul([0, 0, 0, 0], [1, 0, 0, 0]), r"^a: has zero length; the zero quat"),
        (lambda: quat_mul([1, 0, 0, 0], np.zeros((2, 4))), r"^b: has zero length at index \(0,\)"),
        (lambda: quat_conjugate([[1, 0, 0, 0], [0, 0, 0, 0]]),
         r"^q: has zero length at index \(1,\); the zero quaternion is no rotation"),
        (lambda: quat_canonical(np.zeros(4)), r"^q: has zero length; the zero quaternion"),
        # Shapes that do not broadcast: the function and both arguments with their shapes.
        (lambda: quat_mul(np.ones((5, 4)), np.ones((3, 4))),
         r"^quat_mul: a and b do not broadcast together: a has shape \(5, 4\) \(leading \(5,\)\), "
         r"b has shape \(3, 4\) \(leading \(3,\)\); leading dimensions must be equal or 1$"),
        (lambda: quat_rotate(np.ones((2, 4)), np.ones((3, 3))),
         r"^quat_rotate: q and v do not broadcast together: q has shape \(2, 4\)"),
        (lambda: quat_mul("wxyz", [1, 0, 0, 0]), r"^a: expected numbers"),
        (lambda: quat_conjugate(None), r"^q: expected numbers, got None"),
        (lambda: quat_from_matrix(np.eye(4)), r"^R: expected shape \(\.\.\., 3, 3\)"),
        (lambda: quat_from_matrix(2 * np.eye(3)), r"^R: not a rotation matrix"),
        (lambda: quat_from_matrix(np.diag([1.0, 1.0, -1.0])), r"^R: has determinant -1"),
        (lambda: quat_from_matrix([np.eye(3), [[1, 1, 0], [0, 1, 0], [0, 0, 1]]]),
         r"^R: not a rotation matrix at index \(1,\)"),
    ],
)
def test_bad_input_names_the_argument(call, message):
    with pytest.raises(ValueError, match=message):
        call()
