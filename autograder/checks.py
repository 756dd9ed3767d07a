"""Validate what a student's function returned, then compare it with the reference.

Validation comes first and in order, each with its own message: the type (an array, not
``None`` or some object), the dtype (numbers), the shape, then finiteness. Only a valid
output is compared, in the way the mathematics allows: ``q`` and ``-q`` are one rotation.

All of this runs in the grading process on plain arrays decoded from the sandbox's JSON;
no student object ever reaches it.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .protocol import Value

Array = NDArray[np.float64]


def show(x: Array, digits: int = 3) -> str:
    """An array on one short line, ``digits`` decimals, trailing zeros dropped:
    ``[0.5, -1, 0]``. An array whose every entry would print as 0 (a T-handle's inertia,
    2.4e-4 kg m²) gets the decimals that keep ``digits`` significant ones of its largest."""
    a = np.asarray(x, dtype=float)
    if a.size > 24:
        return f"<array of shape {a.shape}>"
    finite = np.abs(a[np.isfinite(a)])
    largest = float(finite.max()) if finite.size else 0.0
    style = "f"
    if 0 < largest < 0.5 * 10.0**-digits:
        style, digits = ("f", digits - 1 - int(np.floor(np.log10(largest)))) if (
            largest >= 1e-5) else ("g", digits)
    return _show(a, digits, style)


def _show(a: np.ndarray, digits: int, style: str) -> str:
    if a.ndim == 0:
        if not np.isfinite(a):
            return str(a)
        v = f"{a:.{digits}{style}}"
        v = v.rstrip("0").rstrip(".") if style == "f" else v
        return "0" if v in ("-0", "-0.0") else v
    return "[" + ", ".join(_show(v, digits, style) for v in a) + "]"


@dataclass(frozen=True)
class Validated:
    """An output of the right type and shape (``array``), and what is wrong with it if
    anything (``error``: NaN/inf, or a wrong type/shape, in which case ``array`` is None)."""

    array: Any
    error: str | None = None


class Check:
    """How one function's output is validated, compared and pictured (base: one array).

    ``shape`` None means "the reference's shape" (a skeleton's ``(J, 3)``, say); an entry
    may differ from the reference's by ``atol + rtol * |reference|``.
    """

    def __init__(self, shape: tuple[int, ...] | None, atol: float = 1e-6, noun: str = "array",
                 rtol: float = 0.0):
        self.shape = shape
        self.atol = atol
        self.rtol = rtol
        self.noun = noun

    def shape_of(self, expected: Any = None) -> tuple[int, ...]:
        return self.shape if self.shape is not None else tuple(np.shape(expected))

    def expected_text(self, expected: Any = None) -> str:
        return f"a numpy array of shape {self.shape_of(expected)}"

    @property
    def expected(self) -> str:
        return self.expected_text()

    def validate(self, fn: str, value: Value, expected: Any = None) -> Validated:
        """Type, dtype, shape, finiteness: the first problem found, in that order."""
        want = self.expected_text(expected)
        if value.kind == "none":
            return Validated(None, f"{fn} returned None; did you forget a `return`?")
        if value.kind == "seq":
            return Validated(
                None, f"{fn} returned a {value.type_name} of {len(value.items)} items, "
                f"expected {want}",
            )
        if value.kind != "array":
            return Validated(None, f"{fn} returned an object of type {value.type_name}, "
                                   f"expected {want}")
        if value.dtype == "bool":
            return Validated(None, f"{fn} returned booleans, expected numbers")
        a = value.array
        assert a is not None
        shape = self.shape_of(expected)
        if a.shape != shape:
            # Against the reference's shape (a skeleton's J), a wrong length is a wrong answer
            # that the catalogue may still recognise (End Sites dropped): keep the array.
            keep = self.shape is None and a.ndim == len(shape) and a.shape[1:] == shape[1:]
            return Validated(a if keep else None,
                             f"{fn} returned shape {a.shape}, expected {shape}")
        if not np.all(np.isfinite(a)):
            return Validated(a, f"{fn} returned NaN or infinity: {show(a)}")
        return Validated(a)

    def judge(self, got: Any, expected: Any, args: tuple[Any, ...]) -> str | None:
        """None if ``got`` is a right answer to the call ``args``, else a short reason.

        By default: the same as the reference's answer (:meth:`compare`). Checks of
        functions with many right answers (inverse kinematics) look at ``args`` instead.
        """
        return self.compare(got, expected)

    def _tolerance(self, expected: Array) -> Array | float:
        return self.atol + self.rtol * np.abs(expected) if self.rtol else self.atol

    def compare(self, got: Array, expected: Array) -> str | None:
        """None if ``got`` is right, else a short reason."""
        diff = np.abs(got - expected)
        if np.all(diff <= self._tolerance(expected)):
            return None
        return f"off by up to {float(np.max(diff)):.2g}"

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
        return bool(np.all(np.abs(a[fa] - b[fb]) <= self._tolerance(b[fb])))

    def difference(self, got: Any, expected: Any) -> float:
        """The largest entry of |got - expected| (for :meth:`decimals`)."""
        return float(np.max(np.abs(np.subtract(got, expected))))

    def decimals(self, got: Any, expected: Any) -> int:
        """How many decimals show where ``got`` and ``expected`` differ: 3, or more when they
        agree to 3 decimals (up to 12)."""
        try:
            diff = self.difference(got, expected)
        except (TypeError, ValueError):  # names, or shapes that differ
            return 3
        if not np.isfinite(diff) or diff <= 0:
            return 3
        return int(np.clip(np.ceil(-np.log10(diff)) + 1, 3, 12))

    def show_value(self, x: Array, digits: int = 3) -> str:
        """``x`` for a message, with ``digits`` decimals."""
        return show(x, digits)

    def show_expected(self, expected: Array, digits: int = 3) -> str:
        return show(expected, digits)

    def rotation(self, x: Array) -> Array | None:
        """A 3x3 rotation to picture ``x`` by, or None if the output is not a rotation."""
        return None


class QuatCheck(Check):
    """A unit quaternion (w, x, y, z), or one per joint (``shape`` (J, 4), None: the
    reference's); ``q`` and ``-q`` are the same rotation."""

    def __init__(self, atol: float = 1e-6, shape: tuple[int, ...] | None = (4,),
                 row: str = "joint"):
        super().__init__(shape, atol, "quaternion")
        self.row = row

    def expected_text(self, expected: Any = None) -> str:
        shape = self.shape_of(expected)
        what = "a quaternion (w, x, y, z)" if len(shape) == 1 else f"a quaternion per {self.row}"
        return f"a numpy array of shape {shape}: {what}"

    def compare(self, got: Array, expected: Array,
                name: Callable[[int], str] | None = None) -> str | None:
        g, e = np.reshape(got, (-1, 4)), np.reshape(expected, (-1, 4))
        where: Callable[[int], str] = (
            (lambda i: "") if np.ndim(got) == 1 else
            (lambda i: f"{name(i)} ") if name else (lambda i: f"{self.row} {i} "))
        norms = np.linalg.norm(g, axis=-1)
        bad = np.flatnonzero(np.abs(norms - 1.0) > self.atol)
        if bad.size:
            i = int(bad[0])
            return (f"{where(i)}is not a unit quaternion (|q| = {norms[i]:.4g}); rotations need "
                    "|q| = 1")
        err = np.minimum(np.max(np.abs(g - e), axis=-1), np.max(np.abs(g + e), axis=-1))
        bad = np.flatnonzero(err > self.atol)
        if not bad.size:
            return None
        i = int(bad[0])
        others = f" ({bad.size} {self.row}s in all)" if bad.size > 1 else ""
        return (f"{where(i)}is a different rotation (off by up to {err[i]:.2g}, even allowing "
                f"for q ~ -q){others}")

    def close(self, a: Array, b: Array) -> bool:
        a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
        if a.shape != b.shape:
            return False
        rows = zip(np.reshape(a, (-1, 4)), np.reshape(b, (-1, 4)), strict=True)
        return all(Check.close(self, x, y) or Check.close(self, x, -y) for x, y in rows)

    def difference(self, got: Any, expected: Any) -> float:
        """Up to sign: q and -q print differently but are one rotation."""
        return min(super().difference(got, expected), super().difference(got, -expected))

    def show_expected(self, expected: Array, digits: int = 3) -> str:
        return ("±" if np.ndim(expected) == 1 else "") + show(expected, digits)

    def rotation(self, x: Array) -> Array | None:
        if np.ndim(x) != 1:
            return None
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

    def rotation(self, x: Array) -> Array | None:
        return np.asarray(x) if np.all(np.isfinite(x)) else None


class PointsCheck(Check):
    """One point per row (joint positions ``(J, 3)``), named by row in messages."""

    def __init__(self, atol: float = 1e-6, row: str = "joint",
                 shape: tuple[int, ...] | None = None):
        super().__init__(shape, atol, "points")
        self.row = row

    def compare(self, got: Array, expected: Array,
                name: Callable[[int], str] | None = None) -> str | None:
        """``name(i)`` names row ``i`` (default ``"joint 3"``); the row is shown with enough
        decimals to see where it differs."""
        err = np.max(np.abs(np.reshape(got, (len(got), -1)) - np.reshape(expected,
                                                                         (len(got), -1))), axis=1)
        bad = np.flatnonzero(err > self.atol)
        if not bad.size:
            return None
        i = int(bad[0])
        others = f"; {bad.size} of {len(err)} {self.row}s are off" if bad.size > 1 else ""
        digits = self.decimals(got[i], expected[i])
        where = name(i) if name else f"{self.row} {i}"
        return (f"{where} is at {show(got[i], digits)}, expected {show(expected[i], digits)}"
                f"{others}")


class IndexCheck(Check):
    """Integer indices (a skeleton's ``parents``), which must match exactly."""

    def __init__(self, shape: tuple[int, ...] | None = None, noun: str = "index"):
        super().__init__(shape, 0.0, noun)

    def expected_text(self, expected: Any = None) -> str:
        return f"a numpy array of {len(np.ravel(expected))} integers" if self.shape is None \
            else super().expected_text(expected)

    def compare(self, got: Array, expected: Array) -> str | None:
        wrong = np.flatnonzero(np.ravel(got) != np.ravel(expected))
        if not wrong.size:
            return None
        i = int(wrong[0])
        return (f"entry {i} is {show(np.ravel(got)[i])}, expected {show(np.ravel(expected)[i])}"
                + (f" ({wrong.size} entries differ)" if wrong.size > 1 else ""))


class StringsCheck(Check):
    """A list of strings (joint names), compared exactly and in order."""

    def __init__(self, noun: str = "name"):
        super().__init__(None, 0.0, noun)

    def expected_text(self, expected: Any = None) -> str:
        n = "" if expected is None else f"{len(expected)} "
        return f"a list of {n}strings"

    def validate(self, fn: str, value: Value, expected: Any = None) -> Validated:
        if value.kind != "seq" or any(i.kind != "str" for i in value.items):
            got = {"none": "None", "array": "numbers", "str": "one string"}.get(
                value.kind, f"a {value.type_name}")
            if value.kind == "seq":
                got = f"a {value.type_name} holding {_kinds(value.items)}"
            return Validated(None, f"{fn} returned {got}, expected "
                                   f"{self.expected_text(expected)}")
        return Validated(tuple(i.text for i in value.items))

    # A StringsCheck is only handed the names its own validate() returned, never arrays.
    def compare(  # type: ignore[override]
        self, got: Sequence[str], expected: Sequence[str]
    ) -> str | None:
        if len(got) != len(expected):
            missing = [n for n in expected if n not in got][:3]
            extra = [n for n in got if n not in expected][:3]
            detail = ", ".join(filter(None, (f"missing {missing}" if missing else "",
                                             f"unexpected {extra}" if extra else "")))
            return f"has {len(got)} {self.noun}s, expected {len(expected)}" + (
                f" ({detail})" if detail else "")
        for i, (g, e) in enumerate(zip(got, expected, strict=True)):
            if g != e:
                return f"{self.noun} {i} is {g!r}, expected {e!r}"
        return None

    def close(self, a: Sequence[str], b: Sequence[str]) -> bool:  # type: ignore[override]
        return tuple(a) == tuple(b)

    def show_value(self, x: Sequence[str], digits: int = 3) -> str:  # type: ignore[override]
        return _show_names(x)

    def show_expected(  # type: ignore[override]
        self, expected: Sequence[str], digits: int = 3
    ) -> str:
        return _show_names(expected)


def _kinds(items: tuple[Value, ...]) -> str:
    kinds = sorted({"strings" if i.kind == "str" else i.type_name or i.kind for i in items})
    return " and ".join(kinds) or "nothing"


def _show_names(seq: Sequence[str]) -> str:
    names = list(seq)
    shown = ", ".join(repr(n) for n in names[:6])
    return f"[{shown}{', ...' if len(names) > 6 else ''}] ({len(names)})"


class TupleCheck(Check):
    """A tuple of outputs, e.g. forward kinematics' ``(positions, orientations)``.

    Each item is validated and compared by its own check; ``names`` say which is which.
    """

    def __init__(self, items: tuple[Check, ...], names: tuple[str, ...]):
        super().__init__((len(items),), noun="tuple")
        self.items = items
        self.names = names

    def expected_text(self, expected: Any = None) -> str:
        return f"a tuple ({', '.join(self.names)})"

    def validate(self, fn: str, value: Value, expected: Any = None) -> Validated:
        if value.kind == "array" and value.array is not None and value.array.ndim > 1 \
                and len(value.array) == len(self.items):
            # (mid, end) of equal shapes crosses the wire as one stacked array: unstack it
            value = Value("seq", value.type_name, items=tuple(
                Value("array", value.type_name, a, value.dtype) for a in value.array))
        if value.kind != "seq" or len(value.items) != len(self.items):
            got = {"none": "None", "array": "one array"}.get(value.kind, value.type_name)
            if value.kind == "seq":
                got = f"a {value.type_name} of {len(value.items)} items"
            return Validated(None, f"{fn} returned {got}, expected {self.expected}")
        arrays, errors = [], []
        parts = expected if expected is not None else (None,) * len(self.items)
        for check, name, item, e in zip(self.items, self.names, value.items, parts, strict=True):
            v = check.validate(f"{fn}'s {name}", item, e)
            if v.array is None:
                return v
            arrays.append(v.array)
            if v.error:
                errors.append(v.error)
        return Validated(tuple(arrays), errors[0] if errors else None)

    # A TupleCheck is only handed the tuples its own validate() returned, one item per check.
    def compare(  # type: ignore[override]
        self, got: tuple[Any, ...], expected: tuple[Any, ...]
    ) -> str | None:
        for check, name, g, e in zip(self.items, self.names, got, expected, strict=True):
            why = check.compare(g, e)
            if why:
                return f"{name} {why}"
        return None

    def close(self, a: tuple[Any, ...], b: tuple[Any, ...]) -> bool:  # type: ignore[override]
        return all(c.close(x, y) for c, x, y in zip(self.items, a, b, strict=True))

    def difference(self, got: tuple[Any, ...], expected: tuple[Any, ...]) -> float:
        return max(c.difference(g, e) for c, g, e in zip(self.items, got, expected, strict=True))

    def show_value(  # type: ignore[override]
        self, x: tuple[Any, ...], digits: int = 3
    ) -> str:
        return "(" + ", ".join(c.show_value(v, digits) for c, v in zip(self.items, x,
                                                                       strict=True)) + ")"

    def show_expected(  # type: ignore[override]
        self, expected: tuple[Any, ...], digits: int = 3
    ) -> str:
        return "(" + ", ".join(c.show_expected(e, digits) for c, e in zip(self.items, expected,
                                                                          strict=True)) + ")"
