r"""Analytic two-link IK (hip-knee-ankle, shoulder-elbow-wrist).

With bone lengths :math:`l_1 = \lVert b - a\rVert`, :math:`l_2 = \lVert c - b\rVert` and the
target at distance :math:`d = \lVert t - a\rVert` from the root, the law of cosines gives the
angle at the root between the root-to-target axis :math:`\hat u` and the first bone,

.. math::
    \cos\alpha = \frac{l_1^2 + d^2 - l_2^2}{2 l_1 d},

and the middle joint's inner angle :math:`\cos\beta = (l_1^2 + l_2^2 - d^2) / (2 l_1 l_2)`.
That fixes the middle joint on a circle about :math:`\hat u`; the *pole* picks the point:
the final twist about the root-to-target axis turns the middle joint into the plane of
:math:`\hat u` and the pole, :math:`b = a + l_1(\cos\alpha\,\hat u + \sin\alpha\,\hat n)`
with :math:`\hat n` the pole direction made perpendicular to :math:`\hat u`. ``flip`` takes the
mirror solution :math:`-\hat n`.

Out of reach (:math:`d > l_1 + l_2`) the chain points straight at the target; closer than
:math:`|l_1 - l_2|` it folds as far as it goes. Both are reported unreachable.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from course._typing import Array
from course._validate import as_array
from course.rotations._kernels import TINY, cross, dot, norm


def _perpendicular(u: Array) -> Array:
    """A unit vector perpendicular to unit ``u`` (crossing the axis of its smallest component)."""
    e = np.eye(3)[np.argmin(np.abs(u), axis=-1)]
    n = cross(u, e)
    return n / norm(n)[..., None]


def two_link(
    root: ArrayLike,
    mid: ArrayLike,
    end: ArrayLike,
    target: ArrayLike,
    pole: ArrayLike | None = None,
    flip: bool = False,
) -> tuple[Array, Array, NDArray[np.bool_]]:
    r"""New middle and end positions of a two-bone chain reaching for ``target``.

    Parameters
    ----------
    root, mid, end : array_like, shape (..., 3)
        Current joint positions :math:`a, b, c` (the root stays).
    target : array_like, shape (..., 3)
    pole : array_like, shape (..., 3), optional
        A point the middle joint should bend towards (a knee's pole in front of the leg).
        Default: keep the current bending plane (the current middle joint is the pole).
    flip : bool
        Take the mirror solution, bending away from the pole.

    Returns
    -------
    mid, end : ndarray, shape (..., 3)
        Same bone lengths as the input; ``end`` is on the target when reachable.
    reachable : ndarray of bool, shape (...)

    Raises
    ------
    ValueError
        If an argument has the wrong shape or is not finite.
    """
    a, b, c = (as_array(x, n, (3,)) for x, n in ((root, "root"), (mid, "mid"), (end, "end")))
    t = as_array(target, "target", (3,))
    pole_pt = b if pole is None else as_array(pole, "pole", (3,))
    l1, l2 = norm(b - a), norm(c - b)
    to_t = t - a
    d_raw = norm(to_t)
    lo, hi = np.abs(l1 - l2), l1 + l2
    # Lengths below ``eps`` count as zero: relative to the chain, so any size solves alike.
    eps = TINY * hi
    reachable = (d_raw <= hi + eps) & (d_raw >= lo - eps)
    d = np.clip(d_raw, lo, hi)
    # Target on the root: no axis to aim along; keep the current one (or any).
    cur = c - a
    u = np.where((d_raw > eps)[..., None], to_t, np.where((norm(cur) > eps)[..., None], cur,
                                                          b - a))
    u = np.where((norm(u) > eps)[..., None], u, [1.0, 0.0, 0.0])
    u = u / norm(u)[..., None]
    # Bend direction: the pole with its component along u removed.
    pv = pole_pt - a
    n = pv - dot(pv, u)[..., None] * u
    nn = norm(n)
    n = np.where((nn > TINY * norm(pv))[..., None],
                 n / np.where(nn > 0, nn, 1.0)[..., None], _perpendicular(u))
    if flip:
        n = -n
    ok = (d > eps) & (l1 > eps)
    cos_a = np.where(ok, (l1 * l1 + d * d - l2 * l2) / (2 * np.where(ok, l1 * d, 1.0)), 1.0)
    cos_a = np.clip(cos_a, -1.0, 1.0)
    sin_a = np.sqrt(1.0 - cos_a * cos_a)
    new_b = a + l1[..., None] * (cos_a[..., None] * u + sin_a[..., None] * n)
    new_c = a + d[..., None] * u
    return new_b, new_c, reachable
