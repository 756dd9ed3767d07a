"""Comparisons for rotation tests, independent of the code under test (scipy does the maths).

q and -q are the same rotation, and Euler triples are compared through their matrices.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation


def random_quats(rng: np.random.Generator, shape: tuple[int, ...] = ()) -> np.ndarray:
    """Uniformly distributed unit quaternions (w, x, y, z) of shape ``shape + (4,)``."""
    q = rng.normal(size=(*shape, 4))
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def scipy_rotation(q: np.ndarray) -> Rotation:
    """A scipy ``Rotation`` from our scalar-first quaternions (scipy's default is x, y, z, w)."""
    return Rotation.from_quat(np.reshape(q, (-1, 4)), scalar_first=True)


def scipy_quat(r: Rotation, shape: tuple[int, ...] = ()) -> np.ndarray:
    """Scalar-first quaternions of a scipy ``Rotation``, reshaped to ``shape + (4,)``."""
    return r.as_quat(scalar_first=True).reshape(*shape, 4)


def assert_quat_equal(a, b, atol: float = 1e-12) -> None:
    """``a`` and ``b`` are the same rotations entry by entry: equal up to sign (q ~ -q)."""
    a, b = np.broadcast_arrays(np.asarray(a, float), np.asarray(b, float))
    err = np.minimum(np.abs(a - b).max(axis=-1), np.abs(a + b).max(axis=-1))
    worst = int(np.argmax(err)) if err.ndim else 0
    assert np.all(err <= atol), (
        f"quaternions differ (up to sign) by {float(np.max(err)):.3g} > {atol:g}; first bad at "
        f"flat index {worst}: {a.reshape(-1, 4)[worst]} vs {b.reshape(-1, 4)[worst]}"
    )


def assert_same_rotation(a, b, atol: float = 1e-12) -> None:
    """``a`` and ``b`` (quaternions (..., 4) or matrices (..., 3, 3)) are the same rotations."""
    np.testing.assert_allclose(_matrix(a), _matrix(b), rtol=0, atol=atol)


def _matrix(x) -> np.ndarray:
    x = np.asarray(x, float)
    if x.shape[-1] == 4:
        return scipy_rotation(x).as_matrix().reshape(*x.shape[:-1], 3, 3)
    assert x.shape[-2:] == (3, 3), f"not a quaternion or matrix: shape {x.shape}"
    return x


def rotation_angle(q) -> np.ndarray:
    """Angle in [0, pi] of quaternions (via scipy's rotation-vector magnitude)."""
    q = np.asarray(q, float)
    return scipy_rotation(q).magnitude().reshape(q.shape[:-1])


def relative_angle(q0, q1) -> np.ndarray:
    """Angle of the rotation from ``q0`` to ``q1`` (of q0^-1 q1), in [0, pi], via scipy."""
    q0, q1 = np.broadcast_arrays(np.asarray(q0, float), np.asarray(q1, float))
    rel = scipy_rotation(q0).inv() * scipy_rotation(q1)
    return rel.magnitude().reshape(q0.shape[:-1])
