"""Input validation shared by the rotation functions.

Every public function converts its inputs here, so a bad argument fails early with a
message that names the argument and says what is wrong with it.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray


def as_array(x: ArrayLike, name: str, last: tuple[int, ...] = ()) -> NDArray[np.float64]:
    """Return ``x`` as a finite float64 array whose trailing shape is ``last``.

    Raises
    ------
    ValueError
        If the trailing shape is wrong or any entry is NaN or infinite; the message names
        ``name``.
    """
    try:
        a = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name}: expected numbers, got {type(x).__name__} ({exc})") from None
    if a.ndim < len(last) or a.shape[a.ndim - len(last):] != last:
        want = "(..., " + ", ".join(map(str, last)) + ")"
        raise ValueError(f"{name}: expected shape {want}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        bad = np.argwhere(~np.isfinite(a))[0]
        raise ValueError(
            f"{name}: contains NaN or infinity (first at index {tuple(int(i) for i in bad)})"
        )
    return a


def nonzero_norm(
    x: NDArray[np.float64], name: str, why: str = "a direction needs a non-zero vector",
    eps: float = 1e-12,
) -> NDArray[np.float64]:
    """Norm of the last axis of ``x``; a ``ValueError`` naming ``name`` and ``why`` if any is ~0."""
    n = np.linalg.norm(x, axis=-1)
    if np.any(n < eps):
        where = np.argwhere(np.atleast_1d(n) < eps)[0]
        at = f" at index {tuple(int(i) for i in where)}" if np.ndim(n) else ""
        raise ValueError(f"{name}: has zero length{at}; {why}")
    return n
