"""Argument checks shared by course.control: matrices of the shapes the lecture's symbols
have, errors that name the argument, the shape expected and the shape given."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .._typing import Array
from .._validate import as_array

# How far a matrix may be from its transpose, relative to its largest entry, and still be
# taken as the symmetric cost matrix it is meant to be (rounding of a product such as
# K^T R K stays far below this; a transposed or mistyped matrix does not).
SYMMETRY_TOL = 1e-9


def as_matrix(value: ArrayLike, name: str, rows: int | None = None,
              cols: int | None = None) -> Array:
    """``value`` as a finite float64 matrix ``(rows, cols)`` (``None``: any size)."""
    a = as_array(value, name)
    if a.ndim != 2 or (rows is not None and a.shape[0] != rows) or (
            cols is not None and a.shape[1] != cols):
        want = f"({'n' if rows is None else rows}, {'m' if cols is None else cols})"
        raise ValueError(f"{name}: expected a matrix of shape {want}, got shape {a.shape}")
    return a


def as_gain(value: ArrayLike, name: str, m: int, n: int) -> Array:
    """A feedback gain ``K (m, n)`` of ``u = -K x``; the message says which way round."""
    a = as_array(value, name)
    if a.shape != (m, n):
        raise ValueError(f"{name}: expected a gain of shape ({m}, {n}) (u = -K x, {m} "
                         f"control(s) by {n} states), got shape {a.shape}")
    return a


def as_vector(value: ArrayLike, name: str, size: int) -> Array:
    """``value`` as a finite float64 vector ``(size,)``."""
    a = as_array(value, name)
    if a.shape != (size,):
        raise ValueError(f"{name}: expected a vector of shape ({size},), got shape {a.shape}")
    return a


def as_square(value: ArrayLike, name: str, size: int | None = None) -> Array:
    a = as_matrix(value, name, size, size)
    if a.shape[0] != a.shape[1]:
        raise ValueError(f"{name}: expected a square matrix, got shape {a.shape}")
    return a


def as_cost_matrix(value: ArrayLike, name: str, size: int, *, definite: bool) -> Array:
    """A symmetric cost matrix ``(size, size)``: positive semi-definite (``Q``), or positive
    definite (``R``, whose inverse the gain needs) when ``definite``."""
    a = as_square(value, name, size)
    scale = max(float(np.max(np.abs(a))), 1e-300)
    if np.max(np.abs(a - a.T)) > SYMMETRY_TOL * scale:
        raise ValueError(f"{name}: a cost matrix must be symmetric ({name} == {name}.T)")
    lowest = float(np.linalg.eigvalsh(a)[0]) if size else 0.0
    if definite and lowest <= 0:
        raise ValueError(f"{name}: must be positive definite (its smallest eigenvalue is "
                         f"{lowest:.3g}); the gain needs (R + B^T P B)^-1")
    if not definite and lowest < -1e-12 * scale:
        raise ValueError(f"{name}: must be positive semi-definite (its smallest eigenvalue is "
                         f"{lowest:.3g})")
    return np.asarray(0.5 * (a + a.T))


def as_count(value: int, name: str, *, minimum: int = 1) -> int:
    """``value`` as an int of at least ``minimum`` (a bool or float is refused)."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise ValueError(f"{name}: expected an integer >= {minimum}, got {value!r}")
    return int(value)


def as_fraction(value: float, name: str, *, allow_one: bool = True) -> float:
    """A discount factor, in (0, 1] (or (0, 1))."""
    ok = isinstance(value, (int, float, np.floating)) and not isinstance(value, bool)
    v = float(value) if ok else float("nan")
    if not (0 < v < 1 or (allow_one and v == 1)):
        want = "(0, 1]" if allow_one else "(0, 1)"
        raise ValueError(f"{name}: expected a number in {want}, got {value!r}")
    return v


def system_shapes(A: ArrayLike, B: ArrayLike) -> tuple[Array, Array]:
    """``A (n, n)`` and ``B (n, m)`` of ``x_{t+1} = A x_t + B u_t``, checked together."""
    a = as_square(A, "A")
    b = as_array(B, "B")
    n = a.shape[0]
    if b.ndim != 2 or b.shape[0] != n:
        raise ValueError(f"B: expected shape ({n}, m) to match A of shape {a.shape} "
                         f"(x_next = A x + B u), got shape {b.shape}")
    return a, b
