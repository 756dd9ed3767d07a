r"""Unchecked rotation kernels for inner loops (forward kinematics, IK solvers, conversions).

Each is the computation behind the public function of the same name, without the checks:
the caller has validated its arrays already (and, for :func:`quat_rotate`, normalised ``q``).
Library modules import them from here; students and notebooks use the checked functions of
:mod:`course.rotations`.
"""

from __future__ import annotations

import numpy as np

from course._typing import Array


def quat_mul(a: Array, b: Array) -> Array:
    """Hamilton product :math:`ab` of quaternions (..., 4), broadcast over leading axes."""
    aw, ax, ay, az = np.moveaxis(a, -1, 0)
    bw, bx, by, bz = np.moveaxis(b, -1, 0)
    return np.stack(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ],
        axis=-1,
    )


def quat_canonical(q: Array) -> Array:
    """``q`` or ``-q``, whichever has its first non-zero component positive (so ``w == 0``,
    a half turn, gets a sign too)."""
    nz = np.abs(q) > 1e-15
    first = np.argmax(nz, axis=-1)
    lead = np.take_along_axis(q, first[..., None], axis=-1)
    return np.where(lead < 0, -q, q)


def quat_rotate(q: Array, v: Array) -> Array:
    r""":math:`v' = v + w t + u\times t`, :math:`t = 2u\times v`, for unit ``q`` (..., 4)."""
    u = q[..., 1:]
    t = 2.0 * np.cross(u, v)
    return v + q[..., :1] * t + np.cross(u, t)


def skew(v: Array) -> Array:
    r"""The cross-product matrices :math:`[v]_\times` (..., 3, 3) of vectors (..., 3)."""
    x, y, z = np.moveaxis(v, -1, 0)
    o = np.zeros_like(x)
    return np.stack(
        [np.stack([o, -z, y], -1), np.stack([z, o, -x], -1), np.stack([-y, x, o], -1)], axis=-2
    )
