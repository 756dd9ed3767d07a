r"""Unchecked small linear algebra for the solvers' inner loops.

Everything here works on rotation *matrices* batched over leading dimensions and never
validates its input: the public solvers check their arguments once, then iterate with these.
Degenerate input (zero vectors) gives the identity rather than NaN, because a zero-length bone
or a target exactly on a joint must not poison a solve.
"""

from __future__ import annotations

import numpy as np

from course._typing import Array

# Below this length a direction is treated as undefined (zero bone, target on the pivot).
TINY = 1e-12


def cross(a: Array, b: Array) -> Array:
    """``a x b`` over the last axis; faster than ``np.cross`` for small arrays."""
    ax, ay, az = a[..., 0], a[..., 1], a[..., 2]
    bx, by, bz = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx], axis=-1)


def dot(a: Array, b: Array) -> Array:
    """Dot product over the last axis."""
    return np.einsum("...i,...i->...", a, b)


def norm(a: Array) -> Array:
    """Euclidean length over the last axis."""
    return np.sqrt(dot(a, a))


def matvec(M: Array, v: Array) -> Array:
    """``M v`` for stacks of 3x3 matrices and 3-vectors."""
    return (M @ v[..., None])[..., 0]


def matrix_from_rotvec(r: Array) -> Array:
    r"""Rodrigues: :math:`R = I + \frac{\sin\theta}{\theta}[r]_\times +
    \frac{1-\cos\theta}{\theta^2}[r]_\times^2` for rotation vectors ``r`` (..., 3), exact at 0."""
    theta2 = dot(r, r)
    theta = np.sqrt(theta2)
    small = theta < 1e-8
    safe = np.where(small, 1.0, theta)
    # Series for tiny angles keeps the identity exact and avoids 0/0.
    a = np.where(small, 1.0 - theta2 / 6.0, np.sin(safe) / safe)
    b = np.where(small, 0.5 - theta2 / 24.0, (1.0 - np.cos(safe)) / (safe * safe))
    x, y, z = r[..., 0], r[..., 1], r[..., 2]
    xx, yy, zz, xy, xz, yz = x * x, y * y, z * z, x * y, x * z, y * z
    return np.stack(
        [
            np.stack([1 - b * (yy + zz), b * xy - a * z, b * xz + a * y], -1),
            np.stack([b * xy + a * z, 1 - b * (xx + zz), b * yz - a * x], -1),
            np.stack([b * xz - a * y, b * yz + a * x, 1 - b * (xx + yy)], -1),
        ],
        axis=-2,
    )


def matrix_between(u: Array, v: Array) -> Array:
    r"""Shortest-arc rotation matrices turning direction ``u`` onto ``v`` (any lengths).

    Axis :math:`u\times v`, angle :math:`\mathrm{atan2}(\lVert u\times v\rVert, u\cdot v)`.
    The identity where either vector is (nearly) zero; a half turn about an axis perpendicular
    to ``u`` where they are opposite.
    """
    c = cross(u, v)
    s = norm(c)
    d = dot(u, v)
    angle = np.arctan2(s, d)
    # Normalised wherever it is not zero: the angle is exact at any length (bones of 1e-8).
    axis = c / np.where(s > 0, s, 1.0)[..., None]
    nu = norm(u)
    opposite = (s <= TINY * np.maximum(nu * norm(v), TINY)) & (d < 0)
    if np.any(opposite):
        # Any perpendicular axis: cross with the coordinate axis along u's smallest component.
        e = np.eye(3)[np.argmin(np.abs(u), axis=-1)]
        perp = cross(u, e)
        perp = perp / np.maximum(norm(perp), TINY)[..., None]
        axis = np.where(opposite[..., None], perp, axis)
        angle = np.where(opposite, np.pi, angle)
    degenerate = (nu < TINY) | (norm(v) < TINY)
    angle = np.where(degenerate, 0.0, angle)
    return matrix_from_rotvec(axis * angle[..., None])


def best_rotation(u: Array, v: Array, w: Array | None = None) -> Array:
    r"""The rotation ``R`` minimising :math:`\sum_i w_i\lVert R u_i - v_i\rVert^2` (Kabsch),
    the smallest one where that leaves a freedom.

    Kabsch maximises :math:`\mathrm{tr}(R H)`, :math:`H = \sum_i w_i u_i v_i^T = U\Sigma V^T`,
    with :math:`R = V D U^T` (:math:`D` fixing the sign of the determinant). When :math:`H`
    has rank 1 (the ``u_i`` or the ``v_i`` all on one line: a joint whose child offsets are
    collinear, or zero-length bones among them), :math:`H = \sigma_1 a b^T` and every ``R``
    with :math:`R a = b` is optimal: any twist about ``b``. The SVD would pick one at random
    (and differently in a batch than alone); here it is the shortest arc from ``a`` to ``b``,
    so the joint keeps its previous twist.

    Parameters
    ----------
    u, v : ndarray, shape (..., k, 3)
        Vectors from the pivot to the current and to the wanted points.
    w : ndarray, shape (..., k), optional
        Weights.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        For one pair (``k = 1``) this is the shortest arc :func:`matrix_between`.
    """
    if u.shape[-2] == 1:
        return matrix_between(u[..., 0, :], v[..., 0, :])
    wu = u if w is None else u * w[..., None]
    H = np.swapaxes(wu, -1, -2) @ v  # sum_i u_i v_i^T
    U, S, Vt = np.linalg.svd(H)
    d = np.sign(np.linalg.det(np.swapaxes(Vt, -1, -2) @ np.swapaxes(U, -1, -2)))
    d = np.where(d == 0, 1.0, d)
    D = np.ones(H.shape[:-1])
    D[..., -1] = d
    R = np.swapaxes(Vt, -1, -2) @ (D[..., None] * np.swapaxes(U, -1, -2))
    rank1 = S[..., 1] <= 1e-9 * S[..., 0]
    if np.any(rank1):
        R = np.where(rank1[..., None, None], matrix_between(U[..., :, 0], Vt[..., 0, :]), R)
    return R




def rotvec_from_matrix(R: Array) -> Array:
    r"""Rotation vectors :math:`\theta\,\hat a`, :math:`\theta \in [0, \pi]`, of rotation
    matrices ``R`` (..., 3, 3).

    The angle is :math:`\mathrm{atan2}(\tfrac12\lVert s\rVert,\ \tfrac12(\mathrm{tr}R - 1))`
    with :math:`s = (R_{21}-R_{12}, R_{02}-R_{20}, R_{10}-R_{01}) = 2\sin\theta\,\hat a`,
    accurate everywhere. The axis is :math:`\hat s` up to a quarter turn; beyond, where
    :math:`\sin\theta` vanishes and :math:`\hat s` with it (a half turn has
    :math:`s = 0`), it comes from the symmetric part
    :math:`B = \tfrac12(R + R^T) - \cos\theta\, I = (1 - \cos\theta)\,\hat a\hat a^T`: the
    column of its largest diagonal entry, normalised, its sign taken from :math:`s` (at an
    exact half turn either sign is the same rotation).
    """
    s = np.stack([R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0],
                  R[..., 1, 0] - R[..., 0, 1]], -1)
    n = norm(s)
    c = 0.5 * (R[..., 0, 0] + R[..., 1, 1] + R[..., 2, 2] - 1.0)
    angle = np.arctan2(0.5 * n, c)
    # theta / (2 sin theta): -> 1/2 for small angles, so s keeps its first-order accuracy.
    out = s * np.where(n > TINY, angle / np.where(n > TINY, n, 1.0), 0.5)[..., None]
    wide = c < 0.0
    if np.any(wide):
        Rw, cw, sw = R[wide], c[wide], s[wide]
        B = 0.5 * (Rw + np.swapaxes(Rw, -1, -2)) - cw[:, None, None] * np.eye(3)
        i = np.argmax(np.diagonal(B, axis1=-2, axis2=-1), axis=-1)
        col = np.take_along_axis(B, i[:, None, None], axis=-1)[..., 0]  # B[:, i]
        axis = col / np.maximum(norm(col), TINY)[:, None]
        axis = axis * np.where(dot(axis, sw) < 0, -1.0, 1.0)[:, None]
        out[wide] = axis * angle[wide][:, None]
    return out


def orthonormalize(R: Array) -> Array:
    r"""One Newton-Schulz step towards the nearest rotation, :math:`R \leftarrow \frac32 R -
    \frac12 R R^T R`. Products like :math:`M^T R M` otherwise let rounding errors grow from
    iteration to iteration; one step squares a small deviation from orthonormality."""
    return 1.5 * R - 0.5 * (R @ np.swapaxes(R, -1, -2) @ R)
