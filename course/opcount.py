r"""Counted arithmetic: numbers that count the operations done with them.

A wall-clock time measured in Python mostly measures Python; the arithmetic an algorithm does
can be *counted* instead. A :class:`Counted` number adds one to a running count for every
:math:`+, -, \times, \div`, :math:`\sqrt{\ }`, :math:`\sin`, :math:`\cos` and
:math:`\operatorname{atan2}` (a sign flip, an absolute value and a comparison are free).
numpy arrays of them (``dtype=object``, see :func:`counted`) run unchanged numpy code element
by element, so a formula written with ``+``, ``@`` or ``np.sqrt`` on them is counted exactly
(``np.linalg`` does not take them: :func:`solve3` below does)::

    >>> from course.opcount import count_ops, counted, norm
    >>> value, ops = count_ops(norm, counted([3.0, 4.0, 0.0]))
    >>> value.value, ops             # 3 products, 2 sums, 1 square root
    (5.0, 6)

:func:`count_iteration` counts what :func:`course.ik.solve` itself does: it runs the solver
that every solve of one serial chain runs (the chain engine, one problem in Python numbers)
on counted numbers instead of floats, so the count is that of the library's own code, not of
a rewrite. The vector and quaternion helpers (:func:`dot`, :func:`cross`, :func:`qmul`,
:func:`qrot`, :func:`solve3`) are there to count formulas of your own.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from course import rotations as rot
from course.ik._engine.chain import as_quat, as_vec
from course.ik._engine.chain_solvers import ChainRun
from course.ik._engine.ops import Floats
from course.ik._pipeline import validate
from course.ik.methods import REGISTRY
from course.skeleton import Skeleton

#: An array of :class:`Counted` (``dtype=object``), or of floats: the helpers take either.
Numbers = Any


class Counted:
    """A float that counts the arithmetic done with it in :attr:`Counted.ops` (shared by all
    counted numbers; :func:`count_ops` resets and reads it)."""

    __slots__ = ("value",)
    ops: ClassVar[int] = 0

    def __init__(self, value: float) -> None:
        self.value = float(value)

    def __repr__(self) -> str:
        return f"Counted({self.value!r})"

    def _apply(self, other: object, f: Callable[[float, float], float]) -> Counted:
        if isinstance(other, Counted):
            b = other.value
        elif isinstance(other, (int, float, np.number)):
            b = float(other)
        else:  # an ndarray: numpy then applies the operation element by element
            return NotImplemented  # type: ignore[no-any-return]  # (typeshed: Any)
        Counted.ops += 1
        return Counted(f(self.value, b))

    def _unary(self, f: Callable[[float], float]) -> Counted:
        Counted.ops += 1
        return Counted(f(self.value))

    def __add__(self, other: object) -> Counted:
        return self._apply(other, lambda a, b: a + b)

    def __radd__(self, other: object) -> Counted:
        return self._apply(other, lambda a, b: b + a)

    def __sub__(self, other: object) -> Counted:
        return self._apply(other, lambda a, b: a - b)

    def __rsub__(self, other: object) -> Counted:
        return self._apply(other, lambda a, b: b - a)

    def __mul__(self, other: object) -> Counted:
        return self._apply(other, lambda a, b: a * b)

    def __rmul__(self, other: object) -> Counted:
        return self._apply(other, lambda a, b: b * a)

    def __truediv__(self, other: object) -> Counted:
        return self._apply(other, lambda a, b: a / b)

    def __rtruediv__(self, other: object) -> Counted:
        return self._apply(other, lambda a, b: b / a)

    def __neg__(self) -> Counted:  # a sign flip: free
        return Counted(-self.value)

    def __abs__(self) -> Counted:  # free, as a sign flip
        return Counted(abs(self.value))

    def __float__(self) -> float:  # reading the value back: free
        return self.value

    # Comparisons decide branches and cost no arithmetic.
    def __lt__(self, other: object) -> bool:
        return self.value < _value(other)

    def __le__(self, other: object) -> bool:
        return self.value <= _value(other)

    def __gt__(self, other: object) -> bool:
        return self.value > _value(other)

    def __ge__(self, other: object) -> bool:
        return self.value >= _value(other)

    # np.sqrt, np.sin and np.cos of an object array call these methods of each element.
    def sqrt(self) -> Counted:
        return self._unary(math.sqrt)

    def sin(self) -> Counted:
        return self._unary(math.sin)

    def cos(self) -> Counted:
        return self._unary(math.cos)


def counted(a: ArrayLike) -> np.ndarray:
    """The array ``a`` (any shape) as counted numbers: an object array of :class:`Counted`."""
    x = np.asarray(a, dtype=np.float64)
    out = np.empty(x.shape, dtype=object)
    out.flat[:] = [Counted(v) for v in x.flat]
    return out


def values(a: Numbers) -> np.ndarray:
    """The float values of counted numbers (floats pass through), as a float array."""
    x = np.asarray(a, dtype=object)
    return np.array([v.value if isinstance(v, Counted) else float(v) for v in x.flat],
                    dtype=np.float64).reshape(x.shape)


def count_ops(f: Callable[..., Any], *args: Any, **kwargs: Any) -> tuple[Any, int]:
    """Run ``f(*args, **kwargs)`` and return ``(its result, the operations it counted)``."""
    Counted.ops = 0
    result = f(*args, **kwargs)
    return result, Counted.ops


def dot(u: Numbers, v: Numbers) -> Any:
    """``u · v`` of 3-vectors: 3 products, 2 sums."""
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]


def norm(u: Numbers) -> Any:
    """``|u|`` of a 3-vector: a dot product and a square root."""
    return np.sqrt(dot(u, u))


def cross(u: Numbers, v: Numbers) -> np.ndarray:
    """``u × v`` of 3-vectors: 6 products, 3 differences."""
    return np.array([u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                     u[0] * v[1] - u[1] * v[0]])


def qmul(a: Numbers, b: Numbers) -> np.ndarray:
    """The Hamilton product ``a b`` of quaternions ``(w, x, y, z)``."""
    return np.asarray(np.r_[a[0] * b[0] - dot(a[1:], b[1:]),
                            a[0] * b[1:] + b[0] * a[1:] + cross(a[1:], b[1:])])


def qrot(q: Numbers, v: Numbers) -> np.ndarray:
    r"""``q v q*`` for a unit quaternion ``q (4,)`` and ``v (3,)``, as
    :math:`v + w\,t + q_v \times t` with :math:`t = 2\,q_v \times v`."""
    t = 2 * cross(q[1:], v)
    return np.asarray(v + q[0] * t + cross(q[1:], t))


def _det3(M: Numbers) -> Any:
    return (M[0, 0] * (M[1, 1] * M[2, 2] - M[1, 2] * M[2, 1])
            - M[0, 1] * (M[1, 0] * M[2, 2] - M[1, 2] * M[2, 0])
            + M[0, 2] * (M[1, 0] * M[2, 1] - M[1, 1] * M[2, 0]))


def solve3(A: Numbers, b: Numbers) -> np.ndarray:
    """``x`` with ``A x = b`` for a 3 × 3 ``A``, by Cramer's rule (one division, then products)."""
    inverse = 1 / _det3(A)
    columns = [np.array(A, dtype=object) for _ in range(3)]
    for k, M in enumerate(columns):
        M[:, k] = b
    return np.array([_det3(M) * inverse for M in columns])


def _value(x: Any) -> float:
    """The float value of a counted number or a float (a test that costs no operation)."""
    return x.value if isinstance(x, Counted) else float(x)


def atan2(y: Any, x: Any) -> Any:
    r""":math:`\operatorname{atan2}(y, x)`: one operation if either is counted."""
    if isinstance(y, Counted) or isinstance(x, Counted):
        Counted.ops += 1
        return Counted(math.atan2(_value(y), _value(x)))
    return math.atan2(y, x)


class CountedOps(Floats):
    """The chain engine's operations (:mod:`course.ik._engine.ops`) on one problem whose
    numbers are :class:`Counted`: the engine's own code then counts what it does."""

    @staticmethod
    def sqrt(x: Any) -> Any:
        return x.sqrt() if isinstance(x, Counted) else math.sqrt(x)

    @staticmethod
    def sin(x: Any) -> Any:
        return x.sin() if isinstance(x, Counted) else math.sin(x)

    @staticmethod
    def cos(x: Any) -> Any:
        return x.cos() if isinstance(x, Counted) else math.cos(x)

    atan2 = staticmethod(atan2)

    @staticmethod
    def dist(a: tuple[Any, ...], b: tuple[Any, ...]) -> Any:
        """``|a - b|`` of two points: 3 differences, 3 squares, 2 sums, a square root."""
        x, y, z = a[0] - b[0], a[1] - b[1], a[2] - b[2]
        return CountedOps.sqrt(x * x + y * y + z * z)


COUNTED = CountedOps()


def count_iteration(skeleton: Skeleton, local_rotations: ArrayLike, target: ArrayLike,
                    method: str, **options: Any) -> tuple[np.ndarray, int]:
    r"""One iteration of :func:`course.ik.solve` on a serial chain, counted.

    The chain engine's solver for ``method`` (what ``solve`` runs on one chain to one
    position target) runs on :class:`Counted` numbers. It runs twice, for one iteration and
    for two; the difference is the operations of one iteration (the set-up, forward
    kinematics of the start and the bookkeeping, cancels). No reach-aware start, no limits.

    Parameters
    ----------
    skeleton : Skeleton
        A serial chain (:func:`course.skeleton.chain`); its last joint is the end effector,
        joint 0 sits at the origin.
    local_rotations : array_like, shape (J, 4)
        The starting pose.
    target : array_like, shape (3,)
    method : str
        A method of :data:`course.ik.METHODS` with a chain solver.
    **options
        The method's options, as :func:`course.ik.solve` takes them.

    Returns
    -------
    positions : ndarray, shape (J, 3)
        The joint positions after one iteration (those of ``solve(..., max_iter=1)``).
    ops : int
        The operations of one iteration.
    """
    (positions, one), (_, two) = (_counted_solve(skeleton, local_rotations, target, method,
                                                 n, options) for n in (1, 2))
    return positions, two - one


def _counted_solve(skeleton: Skeleton, local_rotations: ArrayLike, target: ArrayLike,
                   method: str, max_iter: int, options: dict[str, Any]
                   ) -> tuple[np.ndarray, int]:
    req = validate(skeleton, local_rotations, np.zeros(3), {skeleton.n_joints - 1: target},
                   method, None, 1e-12, max_iter, None, None, False, options,
                   reach_start=False)
    spec = REGISTRY[method]
    if req.serial is None or spec.chain is None or req.batched:
        raise ValueError(f"count_iteration: expected one serial chain and a method with a "
                         f"chain solver, got {skeleton.n_joints} joints and {method!r}")
    chain = req.serial

    def numbers(x: Any) -> tuple[Counted, ...]:
        return tuple(Counted(v) for v in np.asarray(x, float).tolist())

    inv_w2 = tuple((1.0 / req.col_weight**2).tolist()) if spec.weights else ()
    run = ChainRun(chain, [as_quat(numbers(req.local[j])) for j in chain.joints],
                   as_quat(numbers(rot.quat_identity())), as_vec(numbers(req.root_pos)),
                   as_vec(numbers(req.pos_t[skeleton.n_joints - 1])), req.tol, max_iter,
                   False, [], COUNTED, False, inv_w2)
    solved, ops = count_ops(spec.chain, run, req.options)
    return values(np.array([tuple(p) for p in solved.P], dtype=object)), ops


__all__ = [
    "COUNTED",
    "Counted",
    "CountedOps",
    "atan2",
    "count_iteration",
    "count_ops",
    "counted",
    "cross",
    "dot",
    "norm",
    "qmul",
    "qrot",
    "solve3",
    "values",
]
