"""Input validation shared by the rotation functions.

Every public function converts its inputs here, so a bad argument fails early with a
message that names the argument and says what is wrong with it.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

# How far R^T R may be from I before a matrix is rejected as "not a rotation". Loose enough
# for matrices that went through float32 or a long chain of products, tight enough to catch
# scaled, sheared or transposed-by-mistake input.
ROTATION_MATRIX_TOL = 1e-5


def as_array(x: ArrayLike, name: str, last: tuple[int, ...] = ()) -> NDArray[np.float64]:
    """Return ``x`` as a finite float64 array whose trailing shape is ``last``.

    Raises
    ------
    ValueError
        If ``x`` is not numeric, the trailing shape is wrong, or any entry is NaN or
        infinite; the message names ``name``.
    """
    if x is None:
        raise ValueError(f"{name}: expected numbers, got None")
    try:
        a = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name}: expected numbers, got {type(x).__name__} ({exc})") from None
    if a.ndim < len(last) or a.shape[a.ndim - len(last):] != last:
        want = "(..., " + ", ".join(map(str, last)) + ")"
        raise ValueError(f"{name}: expected shape {want}, got {a.shape}")
    finite = np.isfinite(a)
    if not finite.all():
        if a.ndim == 0:
            raise ValueError(f"{name}: is {float(a)}; expected a finite number")
        raise ValueError(f"{name}: contains NaN or infinity (the first{_index(~finite)})")
    return a


def _index(mask: NDArray[np.bool_]) -> str:
    """`` at index (i, j)`` of the first True entry of ``mask``, or ``""`` for a scalar."""
    if np.ndim(mask) == 0:
        return ""
    return f" at index {tuple(int(i) for i in np.argwhere(mask)[0])}"


def broadcast_leading(where: str, *args: tuple[str, NDArray[np.float64], int]) -> tuple[int, ...]:
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


def nonzero_norm(
    x: NDArray[np.float64], name: str, why: str = "a direction needs a non-zero vector",
    eps: float = 1e-12,
) -> NDArray[np.float64]:
    """Norm of the last axis of ``x``; a ``ValueError`` naming ``name`` and ``why`` if any is ~0."""
    n = np.linalg.norm(x, axis=-1)
    small = n < eps
    if np.any(small):
        raise ValueError(f"{name}: has zero length{_index(small)}; {why}")
    return n


ZERO_QUAT = "the zero quaternion is no rotation"


def as_quat(q: ArrayLike, name: str) -> NDArray[np.float64]:
    """``q`` checked by :func:`as_array` (shape (..., 4)) and refused if any is the zero
    quaternion (norm below 1e-12), which no rotation has."""
    a = as_array(q, name, (4,))
    nonzero_norm(a, name, ZERO_QUAT)
    return a


def as_unit(
    x: ArrayLike, name: str, size: int = 3, why: str = "a direction needs a non-zero vector"
) -> NDArray[np.float64]:
    """``x`` checked by :func:`as_array` (trailing size ``size``) and scaled to unit length."""
    a = as_array(x, name, (size,))
    return a / nonzero_norm(a, name, why)[..., None]


def _dot(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.einsum("...i,...i->...", a, b)


def as_rotation_matrix(R: ArrayLike, name: str = "R") -> NDArray[np.float64]:
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
