"""Input validation shared by the whole library (rotations, skeletons, FK, IK, motion).

Every public function converts its inputs here, so a bad argument fails early with a
message that names the argument and says what is wrong with it.
"""

from __future__ import annotations

import math
import numbers

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._typing import Array

# How far R^T R may be from I before a matrix is rejected as "not a rotation". Loose enough
# for matrices that went through float32 or a long chain of products, tight enough to catch
# scaled, sheared or transposed-by-mistake input.
ROTATION_MATRIX_TOL = 1e-5


def as_array(x: ArrayLike, name: str, last: tuple[int, ...] = ()) -> Array:
    """Return ``x`` as a finite float64 array whose trailing shape is ``last``.

    Raises
    ------
    ValueError
        If ``x`` is not real numbers (complex numbers, strings, even ``"1.5"``, dates and
        other objects are refused rather than cast), the trailing shape is wrong, or any entry
        is NaN or infinite; the message names ``name``.
    """
    if x is None:
        raise ValueError(f"{name}: expected numbers, got None")
    try:
        a = np.asarray(x)
    except (TypeError, ValueError) as exc:  # e.g. ragged nesting
        raise ValueError(f"{name}: expected numbers, got {type(x).__name__} ({exc})") from None
    # Checked before the cast, which would drop imaginary parts with only a warning and read
    # "1.5" or a date as a number.
    if a.dtype.kind == "O":
        a = _real_objects(a, name)
    elif a.dtype.kind not in "biuf":
        kind = _NOT_REAL.get(a.dtype.kind, f"dtype {a.dtype}")
        raise ValueError(f"{name}: expected numbers, got {kind}")
    a = a.astype(np.float64, copy=False)
    if a.ndim < len(last) or a.shape[a.ndim - len(last):] != last:
        want = "(..., " + ", ".join(map(str, last)) + ")"
        raise ValueError(f"{name}: expected shape {want}, got {a.shape}")
    finite = np.isfinite(a)
    if not finite.all():
        if a.ndim == 0:
            raise ValueError(f"{name}: is {float(a)}; expected a finite number")
        raise ValueError(f"{name}: contains NaN or infinity (the first{_index(~finite)})")
    return a


# The dtype kinds that are not real numbers, as a message says them.
_NOT_REAL = {
    "c": "complex values (only real numbers; pass x.real if the imaginary parts are 0)",
    "U": "strings (numbers written as text are not numbers)",
    "S": "bytes",
    "M": "dates (datetime64)",
    "m": "time spans (timedelta64)",
    "V": "structured records",
}


def _real_objects(a: NDArray[np.object_], name: str) -> Array:
    """An array of Python objects as float64 if every entry is a real number (big ints and
    fractions are); otherwise a ``ValueError`` naming ``name`` and the first bad index."""
    for i, v in enumerate(a.flat):
        if not isinstance(v, (numbers.Real, np.bool_)):
            at = f" at index {tuple(map(int, np.unravel_index(i, a.shape)))}" if a.ndim else ""
            raise ValueError(f"{name}: expected numbers, got {type(v).__name__}{at}")
    try:
        return a.astype(np.float64)
    except OverflowError:
        raise ValueError(f"{name}: has a number too large for a float") from None


def _index(mask: NDArray[np.bool_]) -> str:
    """`` at index (i, j)`` of the first True entry of ``mask``, or ``""`` for a scalar."""
    if np.ndim(mask) == 0:
        return ""
    return f" at index {tuple(int(i) for i in np.argwhere(mask)[0])}"


def as_time_step(h: float) -> float:
    """A simulation's time step ``h`` as a float; a ValueError unless a positive finite
    number."""
    scalar: bool = np.isscalar(h)  # kept a bool: numpy's TypeGuard would widen h's type
    if not scalar or not np.isfinite(h) or h <= 0:
        raise ValueError(f"h: the time step must be a positive finite number, got {h!r}")
    return float(h)


def as_positive(value: float, name: str, *, allow_zero: bool = False,
                allow_inf: bool = False) -> float:
    """``value`` as a float; a ValueError naming ``name`` unless it is one real number above
    zero (or at least zero with ``allow_zero``), finite (or ``+inf`` with ``allow_inf``, e.g. a
    limit that is off)."""
    if allow_inf and isinstance(value, numbers.Real) and value == math.inf:
        return math.inf
    a = as_array(value, name)
    if a.ndim != 0 or not (a >= 0 if allow_zero else a > 0):
        want = "non-negative" if allow_zero else "positive"
        raise ValueError(f"{name}: must be a {want} number, got {value!r}")
    return float(a)


def as_count(value: int, name: str, minimum: int = 1) -> int:
    """``value`` as an int of at least ``minimum``; a ValueError naming ``name`` unless it is a
    whole number (an int or a numpy integer; not a bool, not a float such as ``10.0``)."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < minimum:
        raise ValueError(f"{name}: a whole number, at least {minimum}, got {value!r}")
    return int(value)


def as_radians(angle: Array, degrees: bool) -> Array:
    """``angle`` in radians: converted when the caller's ``degrees=True`` says it is in
    degrees."""
    return np.radians(angle) if degrees else angle


def broadcast_leading(where: str, *args: tuple[str, Array, int]) -> tuple[int, ...]:
    """The broadcast of the arguments' leading shapes, each without its trailing axes.

    Parameters
    ----------
    where : str
        The function, named first in the message.
    *args : (name, array, n_trailing)
        Each argument's name, its (checked) array and how many trailing axes are its own
        (1 for a quaternion (..., 4), 2 for a matrix (..., 3, 3), 0 for a scalar per item).

    Raises
    ------
    ValueError
        If the leading shapes do not broadcast; the message names every argument with its
        shape, instead of numpy's anonymous "operands could not be broadcast".
    """
    leading = [a.shape[: a.ndim - n] for _, a, n in args]
    try:
        return np.broadcast_shapes(*leading)
    except ValueError:
        names = [name for name, _, _ in args]
        listing = ", ".join(
            f"{name} has shape {a.shape}" + (f" (leading {lead})" if n else "")
            for (name, a, n), lead in zip(args, leading, strict=True)
        )
        raise ValueError(
            f"{where}: {', '.join(names[:-1])} and {names[-1]} do not broadcast together: "
            f"{listing}; leading dimensions must be equal or 1"
        ) from None


def as_point_chains(positions: ArrayLike, target: ArrayLike
                    ) -> tuple[Array, Array, tuple[int, ...]]:
    """Chains of joint positions and their targets, flattened over their broadcast batch.

    Parameters
    ----------
    positions : array_like, shape (..., n, 3)
        Joint positions, ``n >= 2``.
    target : array_like, shape (..., 3)
        A target per chain; its leading dimensions broadcast against those of ``positions``.

    Returns
    -------
    chains : ndarray, shape (B, n, 3)
        A writable copy, ``B`` the size of the batch.
    targets : ndarray, shape (B, 3)
    batch : tuple of int
        The broadcast leading shape (``()`` for one chain): the results' shape.

    Raises
    ------
    ValueError
        If an argument has the wrong shape or is not finite.
    """
    P = as_array(positions, "positions", (3,))
    t = as_array(target, "target", (3,))
    if P.ndim < 2 or P.shape[-2] < 2:
        raise ValueError(f"positions: expected shape (..., n, 3) with n >= 2, got {P.shape}")
    batch = np.broadcast_shapes(P.shape[:-2], t.shape[:-1])
    n = P.shape[-2]
    chains = np.broadcast_to(P, batch + (n, 3)).reshape(-1, n, 3).copy()
    return chains, np.broadcast_to(t, batch + (3,)).reshape(-1, 3), batch


# Between these, |x|^2 neither overflows nor underflows, so np.linalg.norm (which squares the
# components) is exact and used as it is; outside, the components are scaled first.
_PLAIN_NORM = (1e-140, 1e140)


def norm(x: Array) -> Array:
    """Euclidean norm of the last axis of ``x``, exact for any finite ``x``: where
    ``np.linalg.norm`` would overflow (above ~1e154) or underflow (below ~1e-154, which gave a
    3e-162 rad rotation an axis of length 0.71), the components are divided by the largest
    first."""
    return _norms(x)[0]


def unit(x: Array) -> Array:
    """Non-zero rows of ``x`` (last axis) scaled to unit length, however large or small."""
    n, plain = _norms(x)
    if np.all(plain):
        return x / n[..., None]
    s = x / np.max(np.abs(x), axis=-1, keepdims=True)
    scaled = s / np.linalg.norm(s, axis=-1, keepdims=True)
    return np.where(plain[..., None], x / np.where(plain, n, 1.0)[..., None], scaled)


def _norms(x: Array) -> tuple[Array, NDArray[np.bool_]]:
    """:func:`norm` and where ``np.linalg.norm`` alone was exact."""
    with np.errstate(over="ignore", under="ignore"):  # those entries are recomputed
        n = np.linalg.norm(x, axis=-1)
    plain = (n > _PLAIN_NORM[0]) & (n < _PLAIN_NORM[1])
    if np.all(plain):
        return n, plain
    m = np.max(np.abs(x), axis=-1)
    with np.errstate(over="ignore"):  # only for a length beyond the largest float: inf
        scaled = m * np.linalg.norm(x / np.where(m > 0, m, 1.0)[..., None], axis=-1)
    return np.where(plain, n, scaled), plain


def nonzero_norm(
    x: Array, name: str, why: str = "a direction needs a non-zero vector",
    eps: float = 1e-12,
) -> Array:
    """Norm of the last axis of ``x``; a ``ValueError`` naming ``name`` and ``why`` if any is ~0."""
    n = norm(x)
    small = n < eps
    if np.any(small):
        raise ValueError(f"{name}: has zero length{_index(small)}; {why}")
    return n


ZERO_QUAT = "the zero quaternion is no rotation"


def as_quat(q: ArrayLike, name: str) -> Array:
    """``q`` checked by :func:`as_array` (shape (..., 4)) and refused if any is the zero
    quaternion (norm below 1e-12), which no rotation has."""
    a = as_array(q, name, (4,))
    nonzero_norm(a, name, ZERO_QUAT)
    return a


def as_unit(
    x: ArrayLike, name: str, size: int = 3, why: str = "a direction needs a non-zero vector"
) -> Array:
    """``x`` checked by :func:`as_array` (trailing size ``size``) and scaled to unit length."""
    a = as_array(x, name, (size,))
    nonzero_norm(a, name, why)
    return unit(a)


def _dot(a: Array, b: Array) -> Array:
    d: Array = np.einsum("...i,...i->...", a, b)
    return d


def as_rotation_matrix(R: ArrayLike, name: str = "R") -> Array:
    r"""``R`` checked to be a stack of rotation matrices, shape ``(..., 3, 3)``.

    A rotation matrix is orthonormal, :math:`R^T R = I`, with :math:`\det R = +1`.

    Raises
    ------
    ValueError
        If ``R`` has the wrong shape or non-finite entries, is not orthonormal to within
        ``ROTATION_MATRIX_TOL``, or is a reflection (``det R = -1``).
    """
    R = as_array(R, name, (3, 3))
    c0, c1, c2 = R[..., 0], R[..., 1], R[..., 2]  # columns
    # The six distinct entries of R^T R - I, one dot product each (faster than a batched
    # 3x3 matmul).
    err = np.abs([_dot(c0, c0) - 1, _dot(c1, c1) - 1, _dot(c2, c2) - 1,
                  _dot(c0, c1), _dot(c0, c2), _dot(c1, c2)]).max(axis=0)
    bad = err > ROTATION_MATRIX_TOL
    if np.any(bad):
        worst = float(np.max(err))
        raise ValueError(
            f"{name}: not a rotation matrix{_index(bad)} (R^T R differs from I by up to "
            f"{worst:.3g}); the columns must be orthonormal"
        )
    flipped = _dot(c0, np.cross(c1, c2)) < 0  # det R
    if np.any(flipped):
        raise ValueError(
            f"{name}: has determinant -1{_index(flipped)}; that is a reflection, not a rotation"
        )
    return R
