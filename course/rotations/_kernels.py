r"""Unchecked rotation kernels: the one copy of the arithmetic behind rotations, forward
kinematics, the IK solvers and retargeting (无检查的旋转内核).

Each is the computation behind a public function of :mod:`course.rotations` without its
checks: the caller has validated its arrays already (and normalised the quaternions where a
kernel says unit). Library modules import them from here; students and notebooks use the
checked functions. Two layouts share the formulas:

* **components** (``v_*``, ``q_*``): a vector is a tuple ``(x, y, z)``, a quaternion
  ``(w, x, y, z)``, each component a Python float (one problem) or an ndarray ``(B,)`` (a
  batch, contiguous rows); ``ops`` (:class:`ScalarOps`) supplies what differs between the two.
  The serial-chain IK engine runs on them.
* **arrays** (``quat_*``, ``matrix_*``, ...): ``(..., 4)`` quaternions, ``(..., 3)`` vectors and
  ``(..., 3, 3)`` matrices broadcast over leading axes; :func:`quat_mul`, :func:`quat_rotate`
  and :func:`quat_between` are the component kernels applied to the arrays' columns, so the
  two layouts give the same numbers bit for bit.

Degenerate input (zero vectors) gives the identity rather than NaN: a zero-length bone or a
target exactly on a joint must not poison a solve.
"""

from __future__ import annotations

import math
from typing import Any, Protocol

import numpy as np

from course._typing import Array

# Below this length a direction is treated as undefined (zero bone, target on the pivot).
TINY = 1e-12

Scalar = Any  # a float or an ndarray (B,)
Vec = tuple[Any, Any, Any]  # (x, y, z) of Scalars
Quat = tuple[Any, Any, Any, Any]  # (w, x, y, z) of Scalars


class ScalarOps(Protocol):
    """What the component kernels ask of their ``ops``: the operations that differ between
    Python floats and ndarrays ``(B,)``."""

    def sqrt(self, x: Scalar, /) -> Scalar: ...
    def sin(self, x: Scalar, /) -> Scalar: ...
    def cos(self, x: Scalar, /) -> Scalar: ...
    def atan2(self, y: Scalar, x: Scalar, /) -> Scalar: ...
    def abs(self, x: Scalar, /) -> Scalar: ...
    def where(self, c: Any, a: Any, b: Any, /) -> Any: ...
    def select(self, c: Any, a: Any, b: Any, /) -> Any: ...
    def maximum(self, a: Scalar, b: Scalar, /) -> Scalar: ...
    def minimum(self, a: Scalar, b: Scalar, /) -> Scalar: ...
    def both(self, a: Any, b: Any, /) -> Any: ...
    def invert(self, a: Any, /) -> Any: ...
    def any(self, a: Any, /) -> bool: ...
    def all(self, a: Any, /) -> bool: ...


class NumpyOps:
    """:class:`ScalarOps` on ndarrays (any shape, broadcasting): the array kernels' own."""

    sqrt, sin, cos, atan2, abs = (staticmethod(f) for f in (np.sqrt, np.sin, np.cos,
                                                            np.arctan2, np.abs))
    where, maximum, minimum = (staticmethod(f) for f in (np.where, np.maximum, np.minimum))
    both, invert = staticmethod(np.logical_and), staticmethod(np.logical_not)

    @staticmethod
    def select(c: Any, a: Any, b: Any) -> Any:
        """``np.where`` on every array of a structure (tuples and lists of arrays)."""
        if isinstance(a, tuple | list):
            return type(a)(NumpyOps.select(c, x, y) for x, y in zip(a, b, strict=True))
        return np.where(c, a, b)

    @staticmethod
    def any(a: Any) -> bool:
        return bool(np.any(a))

    @staticmethod
    def all(a: Any) -> bool:
        return bool(np.all(a))


NUMPY = NumpyOps()


def _parts(a: Array) -> tuple[Any, ...]:
    return tuple(np.moveaxis(a, -1, 0))


_CONJUGATE = np.array([1.0, -1.0, -1.0, -1.0])


# --------------------------------------------------------------------------- arrays
def quat_mul(a: Array, b: Array) -> Array:
    """Hamilton product :math:`ab` of quaternions (..., 4), broadcast over leading axes."""
    return np.stack(np.broadcast_arrays(*q_mul(_parts(a), _parts(b))), axis=-1)


def quat_rotate(q: Array, v: Array) -> Array:
    r""":math:`v' = v + w t + u\times t`, :math:`t = 2u\times v`, for unit ``q`` (..., 4)."""
    return np.stack(np.broadcast_arrays(*q_rotate(_parts(q), _parts(v))), axis=-1)


def quat_between(u: Array, v: Array) -> Array:
    """Shortest arc turning directions ``u`` onto ``v`` (..., 3) -> (..., 4): :func:`q_between`
    on arrays (the identity where either is shorter than :data:`TINY`)."""
    u, v = np.broadcast_arrays(u, v)
    return np.stack(np.broadcast_arrays(*q_between(_parts(u), _parts(v), NUMPY)), axis=-1)


def quat_conjugate(q: Array) -> Array:
    """:math:`q^* = (w, -x, -y, -z)` of quaternions (..., 4): the inverse of a unit one
    (:func:`q_conjugate` on arrays)."""
    out: Array = q * _CONJUGATE
    return out


def quat_from_rotvec(r: Array) -> Array:
    r""":math:`\exp(r)` of rotation vectors (..., 3) -> (..., 4): :func:`q_from_rotvec` on
    arrays (the identity at 0)."""
    return np.stack(np.broadcast_arrays(*q_from_rotvec(_parts(r), NUMPY)), axis=-1)


def quat_canonical(q: Array) -> Array:
    """``q`` or ``-q``, whichever has its first non-zero component positive (so ``w == 0``,
    a half turn, gets a sign too)."""
    nz = np.abs(q) > 1e-15
    first = np.argmax(nz, axis=-1)
    lead = np.take_along_axis(q, first[..., None], axis=-1)
    return np.where(lead < 0, -q, q)


def skew(v: Array) -> Array:
    r"""The cross-product matrices :math:`[v]_\times` (..., 3, 3) of vectors (..., 3)."""
    x, y, z = np.moveaxis(v, -1, 0)
    o = np.zeros_like(x)
    return np.stack(
        [np.stack([o, -z, y], -1), np.stack([z, o, -x], -1), np.stack([-y, x, o], -1)], axis=-2
    )


def cross(a: Array, b: Array) -> Array:
    """``a x b`` over the last axis; faster than ``np.cross`` for small arrays."""
    ax, ay, az = a[..., 0], a[..., 1], a[..., 2]
    bx, by, bz = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx], axis=-1)


def dot(a: Array, b: Array) -> Array:
    """Dot product over the last axis."""
    out: Array = np.einsum("...i,...i->...", a, b)
    return out


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
    R: Array = np.swapaxes(Vt, -1, -2) @ (D[..., None] * np.swapaxes(U, -1, -2))
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


# --------------------------------------------------------------------------- components


def v_add(a: Vec, b: Vec) -> Vec:
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def v_sub(a: Vec, b: Vec) -> Vec:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def v_scale(a: Vec, s: Scalar) -> Vec:
    return (a[0] * s, a[1] * s, a[2] * s)


def v_dot(a: Vec, b: Vec) -> Scalar:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def v_cross(a: Vec, b: Vec) -> Vec:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def q_mul(a: Quat, b: Quat) -> Quat:
    """Hamilton product :math:`a b` (rotate by ``b``, then ``a``)."""
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw)


def q_conjugate(q: Quat) -> Quat:
    return (q[0], -q[1], -q[2], -q[3])


def q_rotate(q: Quat, v: Vec) -> Vec:
    r""":math:`q v q^*` as :math:`v + w t + u\times t`, :math:`t = 2u\times v`,
    :math:`u = (x, y, z)` (written out: this is the innermost operation)."""
    w, x, y, z = q
    vx, vy, vz = v
    tx, ty, tz = 2.0 * (y * vz - z * vy), 2.0 * (z * vx - x * vz), 2.0 * (x * vy - y * vx)
    return (vx + w * tx + y * tz - z * ty, vy + w * ty + z * tx - x * tz,
            vz + w * tz + x * ty - y * tx)


def q_unit(q: Quat, ops: ScalarOps) -> Quat:
    """``q`` renormalised: CCD and FABRIK turn every joint hundreds of times, and rounding must
    not build up in its length."""
    qw, qx, qy, qz = q
    inv = 1.0 / ops.sqrt(qw * qw + qx * qx + qy * qy + qz * qz)
    return (qw * inv, qx * inv, qy * inv, qz * inv)


def q_units_like(qs: list[Quat], refs: list[Quat], ops: ScalarOps) -> list[Quat]:
    """The quaternions ``qs`` normalised, each with the sign of its ``refs`` entry (``q`` and
    ``-q`` are one rotation: keeping the starting quaternion's sign spares an animated solve
    its sign flips)."""
    sqrt, where, out = ops.sqrt, ops.where, []
    for (w, x, y, z), (rw, rx, ry, rz) in zip(qs, refs, strict=True):
        inv = 1.0 / sqrt(w * w + x * x + y * y + z * z)
        inv = where(w * rw + x * rx + y * ry + z * rz < 0, -inv, inv)
        out.append((w * inv, x * inv, y * inv, z * inv))
    return out


def q_from_axis_angle(axis: Vec, angle: Scalar, ops: ScalarOps) -> Quat:
    """Turn by ``angle`` about the unit ``axis`` (a constant)."""
    s = ops.sin(0.5 * angle)
    return (ops.cos(0.5 * angle), axis[0] * s, axis[1] * s, axis[2] * s)


def q_from_rotvec(r: Vec, ops: ScalarOps) -> Quat:
    r""":math:`\exp(r)`: turn by :math:`\lVert r\rVert` about :math:`\hat r` (identity at 0)."""
    theta = ops.sqrt(v_dot(r, r))
    safe = ops.where(theta > 1e-8, theta, 1.0)
    k = ops.where(theta > 1e-8, ops.sin(0.5 * safe) / safe, 0.5)
    return (ops.cos(0.5 * theta), r[0] * k, r[1] * k, r[2] * k)


def q_between(u: Vec, v: Vec, ops: ScalarOps) -> Quat:
    r"""Shortest arc taking direction ``u`` onto ``v``: :math:`(\lVert u\rVert\lVert v\rVert +
    u\cdot v,\ u\times v)` normalised; a half turn about an axis perpendicular to ``u`` when
    they are opposite; the identity when either is shorter than ``TINY`` (as
    :func:`matrix_between`). The two special cases are rare, so they are
    only worked out when some problem needs them (FABRIK fits every bone with this)."""
    (ux, uy, uz), (vx, vy, vz) = u, v
    uu, vv = ux * ux + uy * uy + uz * uz, vx * vx + vy * vy + vz * vz
    nn = ops.sqrt(uu * vv)
    w, x, y, z = (nn + ux * vx + uy * vy + uz * vz, uy * vz - uz * vy, uz * vx - ux * vz,
                  ux * vy - uy * vx)
    opposite = w <= TINY * nn
    if ops.any(opposite):
        # Turn about u x (the coordinate axis of u's smallest component), as matrix_between.
        ax, ay, az = ops.abs(u[0]), ops.abs(u[1]), ops.abs(u[2])
        use_x = ops.both(ax <= ay, ax <= az)
        use_y = ops.both(ops.invert(use_x), ay <= az)
        px, py, pz = ops.select(use_x, (0.0, u[2], -u[1]),  # u x (1, 0, 0)
                                ops.select(use_y, (-u[2], 0.0, u[0]), (u[1], -u[0], 0.0)))
        w, x, y, z = (ops.where(opposite, 0.0, w), ops.where(opposite, px, x),
                      ops.where(opposite, py, y), ops.where(opposite, pz, z))
    n = ops.sqrt(w * w + x * x + y * y + z * z)
    degenerate = ops.minimum(uu, vv) < TINY * TINY  # either vector (nearly) zero
    if not ops.any(degenerate):
        inv = 1.0 / n
        return (w * inv, x * inv, y * inv, z * inv)
    inv = 1.0 / ops.where(degenerate, 1.0, n)
    return (ops.where(degenerate, 1.0, w * inv), ops.where(degenerate, 0.0, x * inv),
            ops.where(degenerate, 0.0, y * inv), ops.where(degenerate, 0.0, z * inv))


def q_cap_angle(q: Quat, cap: float, ops: ScalarOps) -> Quat:
    r"""``q`` with its rotation angle :math:`2\,\mathrm{atan2}(\lVert v\rVert, |w|)` capped at
    ``cap``, keeping its axis."""
    w, x, y, z = q
    s = ops.sqrt(x * x + y * y + z * z)
    over = 2.0 * ops.atan2(s, ops.abs(w)) > cap
    k = math.sin(0.5 * cap) / ops.where(s > TINY, s, 1.0)
    sign = ops.where(w < 0, -1.0, 1.0)
    return (ops.where(over, sign * math.cos(0.5 * cap), w), ops.where(over, x * k, x),
            ops.where(over, y * k, y), ops.where(over, z * k, z))


def q_clamp_swing_twist(q: Quat, axis: Vec, cone: float, lo: float, hi: float,
                        ops: ScalarOps) -> Quat:
    r""":func:`course.rotations.clamp_swing_twist` on components (its own formula, which the
    tests check against the checked one): :math:`q = s\otimes t`
    (twist :math:`t \propto (w, (v\cdot a)\,a)`, the identity at the half-turn singularity),
    the swing's angle capped at ``cone`` about its own axis, the twist angle clamped to
    ``[lo, hi]`` on the circle (as ``course.rotations.swing_twist._clamp_on_circle``), and
    :math:`s'\otimes t'` returned in the sign of ``q``."""
    sign = ops.where(q[0] < 0, -1.0, 1.0)  # canonical (w >= 0), as the checked function
    w, x, y, z = q[0] * sign, q[1] * sign, q[2] * sign, q[3] * sign
    p = x * axis[0] + y * axis[1] + z * axis[2]
    n = ops.sqrt(w * w + p * p)
    singular = n < 1e-12
    inv = 1.0 / ops.where(singular, 1.0, n)
    tw, tp = ops.where(singular, 1.0, w * inv), ops.where(singular, 0.0, p * inv)
    sw, sx, sy, sz = q_mul((w, x, y, z), (tw, -tp * axis[0], -tp * axis[1], -tp * axis[2]))
    sin_half = ops.sqrt(sx * sx + sy * sy + sz * sz)
    half = 0.5 * ops.minimum(2.0 * ops.atan2(sin_half, sw), cone)
    k = ops.where(sin_half > 0, ops.sin(half) / ops.where(sin_half > 0, sin_half, 1.0), 0.0)
    twist = 2.0 * ops.atan2(tp, tw)
    off = twist - 0.5 * (lo + hi)
    off = ops.atan2(ops.sin(off), ops.cos(off))  # from the range's middle, round the circle
    theta = 0.5 * ops.where(ops.abs(off) <= 0.5 * (hi - lo), twist,
                            ops.where(off > 0, hi, lo))
    st = ops.sin(theta)
    out = q_mul((ops.cos(half), sx * k, sy * k, sz * k),
                   (ops.cos(theta), st * axis[0], st * axis[1], st * axis[2]))
    return (out[0] * sign, out[1] * sign, out[2] * sign, out[3] * sign)
