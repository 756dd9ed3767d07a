"""The two ways the serial-chain code runs (:mod:`course.ik._engine.chain`): one problem in Python
floats (:data:`FLOATS`), or a batch with every component an ndarray ``(B,)``
(:data:`ARRAYS`). Each supplies the handful of operations that differ between the two; the
solvers and their bookkeeping (:class:`course.ik.result.History`) are written once on top.
"""

from __future__ import annotations

import math
from itertools import chain
from typing import Any, Protocol

import numpy as np

from course.rotations._kernels import NumpyOps, Scalar

# A component: a Python float (FLOATS) or an ndarray (B,) (ARRAYS); a flag: a bool or a bool
# ndarray (B,). Each implementation takes only its own kind, so the protocol leaves them open.
Component = Scalar
Flag = Any
Components = tuple[Component, ...]  # a vector, quaternion or symmetric 3x3 matrix


class Ops(Protocol):
    """The switch between the two ways (:data:`FLOATS`, :data:`ARRAYS`): what the chain code
    asks of ``ops``."""

    def sqrt(self, x: Component, /) -> Component: ...
    def sin(self, x: Component, /) -> Component: ...
    def cos(self, x: Component, /) -> Component: ...
    def atan2(self, y: Component, x: Component, /) -> Component: ...
    def abs(self, x: Component, /) -> Component: ...
    def dist(self, a: Components, b: Components, /) -> Component: ...
    def where(self, c: Flag, a: Component, b: Component, /) -> Component: ...
    def select(self, c: Flag, a: Any, b: Any, /) -> Any: ...  # whole structures
    def maximum(self, a: Component, b: Component, /) -> Component: ...
    def minimum(self, a: Component, b: Component, /) -> Component: ...
    def full(self, like: Component, value: Any, /) -> Component: ...
    def flag(self, mask: np.ndarray, /) -> Flag: ...
    def symmetric(self, A: Components, /) -> np.ndarray: ...
    def vector(self, x: np.ndarray, /) -> Components: ...
    def stack(self, items: list[Components], batch: int, /) -> np.ndarray: ...
    def both(self, a: Flag, b: Flag, /) -> Flag: ...
    def invert(self, a: Flag, /) -> Flag: ...
    def any(self, a: Flag, /) -> bool: ...
    def all(self, a: Flag, /) -> bool: ...
    def take(self, x: Any, idx: Any, /) -> Any: ...
    def copy(self, x: Any, /) -> Any: ...
    def put(self, full: Any, idx: Any, part: Any, /) -> Any: ...



class Floats:
    """Component operations for one problem in Python floats."""

    sqrt, sin, cos, atan2, dist = (staticmethod(f) for f in (math.sqrt, math.sin, math.cos,
                                                             math.atan2, math.dist))
    abs = staticmethod(abs)

    @staticmethod
    def where(c: bool, a: Any, b: Any) -> Any:
        return a if c else b

    select = where  # whole structures (tuples of components) at once

    @staticmethod
    def maximum(a: float, b: float) -> float:
        return a if a > b else b

    @staticmethod
    def minimum(a: float, b: float) -> float:
        return a if a < b else b

    @staticmethod
    def full(like: Any, value: Any) -> Any:
        """``value`` for every problem (here the one)."""
        return value

    @staticmethod
    def flag(mask: np.ndarray) -> bool:
        """A (1,) mask from a numpy helper as this problem's bool."""
        return bool(mask[0])

    @staticmethod
    def symmetric(A: Components) -> np.ndarray:
        a00, a01, a02, a11, a12, a22 = A
        return np.array([[a00, a01, a02], [a01, a11, a12], [a02, a12, a22]])

    @staticmethod
    def vector(x: np.ndarray) -> Components:
        return tuple(x.tolist())

    @staticmethod
    def stack(items: list[Components], batch: int) -> np.ndarray:
        """Tuples of ``c`` floats as an array (len(items), c), with no batch axis.
        (``fromiter`` over the flat floats, told their count: a third cheaper than
        ``np.array`` of the tuples.)"""
        n, c = len(items), len(items[0])
        return np.fromiter(chain.from_iterable(items), float, n * c).reshape(n, c)

    @staticmethod
    def both(a: bool, b: bool) -> bool:
        return a and b

    @staticmethod
    def invert(a: bool) -> bool:
        return not a

    # One problem's flags are plain bools already (the builtin is the fastest identity).
    any = all = staticmethod(bool)

    @staticmethod
    def take(x: Any, idx: Any) -> Any:
        return x

    @staticmethod
    def copy(x: Any) -> Any:
        return x  # floats and tuples are immutable

    @staticmethod
    def put(full: Any, idx: Any, part: Any) -> Any:
        return part


class Arrays(NumpyOps):
    """Component operations for a batch: every component an ndarray (B,) (the rotation
    kernels' :class:`~course.rotations._kernels.NumpyOps`, and what the chain code adds)."""

    @staticmethod
    def dist(a: Components, b: Components) -> np.ndarray:
        """Distance between two points (components (B,) or floats)."""
        x, y, z = a[0] - b[0], a[1] - b[1], a[2] - b[2]
        d: np.ndarray = np.sqrt(x * x + y * y + z * z)
        return d

    @staticmethod
    def full(like: np.ndarray, value: Any) -> np.ndarray:
        """``value`` for every problem, an array shaped like ``like``."""
        return np.full(np.shape(like), value)

    @staticmethod
    def flag(mask: np.ndarray) -> np.ndarray:
        return mask

    @staticmethod
    def symmetric(A: Components) -> np.ndarray:
        a00, a01, a02, a11, a12, a22 = np.broadcast_arrays(*A)
        return np.stack([np.stack([a00, a01, a02], -1), np.stack([a01, a11, a12], -1),
                         np.stack([a02, a12, a22], -1)], -2)

    @staticmethod
    def vector(x: np.ndarray) -> Components:
        return tuple(np.moveaxis(x, -1, 0))

    @staticmethod
    def stack(items: list[Components], batch: int) -> np.ndarray:
        """Tuples of ``c`` components (B,) or floats as an array (B, len(items), c)."""
        return np.stack([np.stack([np.broadcast_to(c, (batch,)) for c in x], -1)
                         for x in items], 1)

    @staticmethod
    def take(x: Any, idx: np.ndarray) -> Any:
        """``x[idx]`` for every array in a structure (the problems still running)."""
        if isinstance(x, tuple | list):
            return type(x)(Arrays.take(c, idx) for c in x)
        return x[idx] if isinstance(x, np.ndarray) and x.ndim else x

    @staticmethod
    def copy(x: Any) -> Any:
        if isinstance(x, tuple | list):
            return type(x)(Arrays.copy(c) for c in x)
        return x.copy() if isinstance(x, np.ndarray) else x

    @staticmethod
    def put(full: Any, idx: np.ndarray, part: Any) -> Any:
        """``full[idx] = part`` for every array in a structure, in place."""
        if isinstance(full, tuple | list):
            for f, q in zip(full, part, strict=True):
                Arrays.put(f, idx, q)
        else:
            full[idx] = part
        return full


FLOATS: Ops = Floats()
ARRAYS: Ops = Arrays()
