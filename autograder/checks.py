"""Validate what a student's function returned, then compare it with the reference.

Validation comes first and in order, each with its own message: the type (an array, not
``None`` or some object), the dtype (numbers), the shape, then finiteness. Only a valid
output is compared, in the way the mathematics allows: ``q`` and ``-q`` are one rotation.

All of this runs in the grading process on plain arrays decoded from the sandbox's JSON;
no student object ever reaches it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .protocol import Value

Array = NDArray[np.float64]


def show(x: Array) -> str:
    """An array on one short line, 3 decimals, trailing zeros dropped: ``[0.5, -1, 0]``."""
    a = np.asarray(x, dtype=float)
    if a.ndim == 0:
        v = f"{a:.3f}".rstrip("0").rstrip(".") if np.isfinite(a) else str(a)
        return "0" if v == "-0" else v
    if a.size > 24:
        return f"<array of shape {a.shape}>"
    return "[" + ", ".join(show(v) for v in a) + "]"


@dataclass(frozen=True)
class Validated:
    """An output of the right type and shape (``array``), and what is wrong with it if
    anything (``error``: NaN/inf, or a wrong type/shape, in which case ``array`` is None)."""

    array: Array | tuple[Array, ...] | None
    error: str | None = None


class Check:
    """How one function's output is validated, compared and pictured (base: one array)."""

    def __init__(self, shape: tuple[int, ...], atol: float = 1e-6, noun: str = "array"):
        self.shape = shape
        self.atol = atol
        self.noun = noun

    @property
    def expected(self) -> str:
        return f"a numpy array of shape {self.shape}"

    def validate(self, fn: str, value: Value) -> Validated:
        """Type, dtype, shape, finiteness: the first problem found, in that order."""
        if value.kind == "none":
            return Validated(None, f"{fn} returned None; did you forget a `return`?")
        if value.kind == "seq":
            return Validated(
                None, f"{fn} returned a {value.type_name} of {len(value.items)} items, "
                f"expected {self.expected}",
            )
        if value.kind != "array":
            return Validated(None, f"{fn} returned an object of type {value.type_name}, "
                                   f"expected {self.expected}")
        if value.dtype == "bool":
            return Validated(None, f"{fn} returned booleans, expected numbers")
        a = value.array
        assert a is not None
        if a.shape != self.shape:
            return Validated(None, f"{fn} returned shape {a.shape}, expected {self.shape}")
        if not np.all(np.isfinite(a)):
            return Validated(a, f"{fn} returned NaN or infinity: {show(a)}")
        return Validated(a)

    def compare(self, got: Array, expected: Array) -> str | None:
        """None if ``got`` is right, else a short reason."""
        err = float(np.max(np.abs(got - expected)))
        if err <= self.atol:
            return None
        return f"off by up to {err:.2g}"

    def close(self, a: Array, b: Array) -> bool:
        """Whether two outputs are the same answer (used to match known mistakes).

        Non-finite entries must sit in the same places; the finite ones must agree.
        """
        a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
        if a.shape != b.shape:
            return False
        fa, fb = np.isfinite(a), np.isfinite(b)
        if not np.array_equal(fa, fb):
            return False
        return bool(np.all(np.abs(a[fa] - b[fb]) <= self.atol))

    def show_value(self, x: Array) -> str:
        return show(x)

    def show_expected(self, expected: Array) -> str:
        return show(expected)

    def rotation(self, x: Array) -> Array | None:
        """A 3x3 rotation to picture ``x`` by, or None if the output is not a rotation."""
        return None


class QuatCheck(Check):
    """A unit quaternion (w, x, y, z); ``q`` and ``-q`` are the same rotation."""

    def __init__(self, atol: float = 1e-6):
        super().__init__((4,), atol, "quaternion")

    @property
    def expected(self) -> str:
        return "a numpy array of shape (4,): a quaternion (w, x, y, z)"

    def compare(self, got: Array, expected: Array) -> str | None:
        norm = float(np.linalg.norm(got))
        if abs(norm - 1.0) > self.atol:
            return f"is not a unit quaternion (|q| = {norm:.4g}); rotations need |q| = 1"
        err = min(np.max(np.abs(got - expected)), np.max(np.abs(got + expected)))
        if err <= self.atol:
            return None
        return f"is a different rotation (off by up to {err:.2g}, even allowing for q ~ -q)"

    def close(self, a: Array, b: Array) -> bool:
        return super().close(a, b) or super().close(a, -np.asarray(b))

    def show_expected(self, expected: Array) -> str:
        return "±" + show(expected)

    def rotation(self, x: Array) -> Array | None:
        n = np.linalg.norm(x)
        if not np.isfinite(n) or n < 1e-9:
            return None
        w, i, j, k = np.asarray(x) / n
        return np.array(
            [
                [1 - 2 * (j * j + k * k), 2 * (i * j - w * k), 2 * (i * k + w * j)],
                [2 * (i * j + w * k), 1 - 2 * (i * i + k * k), 2 * (j * k - w * i)],
                [2 * (i * k - w * j), 2 * (j * k + w * i), 1 - 2 * (i * i + j * j)],
            ]
        )


class MatrixCheck(Check):
    """A 3x3 rotation matrix, compared entry by entry."""

    def __init__(self, atol: float = 1e-6):
        super().__init__((3, 3), atol, "matrix")

    @property
    def expected(self) -> str:
        return "a numpy array of shape (3, 3)"

    def rotation(self, x: Array) -> Array | None:
        return np.asarray(x) if np.all(np.isfinite(x)) else None


class TupleCheck(Check):
    """A tuple of outputs, e.g. forward kinematics' ``(positions, orientations)``.

    Each item is validated and compared by its own check; ``names`` say which is which.
    """

    def __init__(self, items: tuple[Check, ...], names: tuple[str, ...]):
        super().__init__((len(items),), noun="tuple")
        self.items = items
        self.names = names

    @property
    def expected(self) -> str:
        return f"a tuple ({', '.join(self.names)})"

    def validate(self, fn: str, value: Value) -> Validated:
        if value.kind != "seq" or len(value.items) != len(self.items):
            got = {"none": "None", "array": "one array"}.get(value.kind, value.type_name)
            if value.kind == "seq":
                got = f"a {value.type_name} of {len(value.items)} items"
            return Validated(None, f"{fn} returned {got}, expected {self.expected}")
        arrays, errors = [], []
        for check, name, item in zip(self.items, self.names, value.items, strict=True):
            v = check.validate(f"{fn}'s {name}", item)
            if v.array is None:
                return v
            arrays.append(v.array)
            if v.error:
                errors.append(v.error)
        return Validated(tuple(arrays), errors[0] if errors else None)

    def compare(self, got, expected) -> str | None:  # type: ignore[override]
        for check, name, g, e in zip(self.items, self.names, got, expected, strict=True):
            why = check.compare(g, e)
            if why:
                return f"{name} {why}"
        return None

    def close(self, a, b) -> bool:  # type: ignore[override]
        return all(c.close(x, y) for c, x, y in zip(self.items, a, b, strict=True))

    def show_value(self, x) -> str:  # type: ignore[override]
        return "(" + ", ".join(c.show_value(v) for c, v in zip(self.items, x, strict=True)) + ")"

    def show_expected(self, expected) -> str:  # type: ignore[override]
        return "(" + ", ".join(c.show_expected(e) for c, e in zip(self.items, expected,
                                                                  strict=True)) + ")"
