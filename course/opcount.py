r"""Counted arithmetic: numbers that count the operations done with them.

A wall-clock time measured in Python mostly measures Python; the arithmetic an algorithm does
can be *counted* instead. A :class:`Counted` number adds one to a running count for every
:math:`+, -, \times, \div`, :math:`\sqrt{\ }`, :math:`\sin` and :math:`\cos` (a sign flip is
free). numpy arrays of them (``dtype=object``, see :func:`counted`) run unchanged numpy code
element by element, so a formula written with ``+``, ``@`` or ``np.sqrt`` on them is counted
exactly (``np.linalg`` does not take them: :func:`solve3` below does)::

    >>> from course.opcount import count_ops, counted, norm
    >>> value, ops = count_ops(norm, counted([3.0, 4.0, 0.0]))
    >>> value.value, ops             # 3 products, 2 sums, 1 square root
    (5.0, 6)

The vector and quaternion helpers below (:func:`dot`, :func:`cross`, :func:`qmul`,
:func:`qrot`, :func:`solve3`) are written with plain arithmetic so that every operation is
seen; they also work on floats. :func:`ccd_sweep` and :func:`jacobian_iteration` are one
iteration of CCD and of the Jacobian methods written out from the formulas of notebooks 02 and
05–07, for counting (notebook 08 checks each against one iteration of :mod:`course.ik`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

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


def ccd_sweep(P: Numbers, t: Numbers) -> np.ndarray:
    """One CCD sweep, tip to root, on joint positions ``P (n + 1, 3)`` towards target ``t (3,)``.

    Each joint turns ``e - r_i`` onto ``t - r_i`` by the shortest arc (notebook 05). Written
    the economical way: during the sweep only the end effector is turned; the chain is rebuilt
    once at the end. A joint with the effector or the target on its pivot has no direction to
    turn to and stays (as in :func:`course.ik.ccd_positions`). Returns the new joint positions
    ``(n + 1, 3)``.
    """
    e, turns = P[-1], list[np.ndarray]()
    identity = np.array([1.0, 0.0, 0.0, 0.0])
    for i in range(len(P) - 2, -1, -1):
        u, v = e - P[i], t - P[i]
        nu, nv = norm(u), norm(v)
        if min(_value(nu), _value(nv)) < 1e-12:
            turns.insert(0, identity)
            continue
        q = np.r_[nu * nv + dot(u, v), cross(u, v)]
        q = q / np.sqrt(q[0] * q[0] + dot(q[1:], q[1:]))
        e = P[i] + qrot(q, u)
        turns.insert(0, q)
    # Bone j was turned by q_j first, then by q_(j-1), ..., q_0: by the product q_0 ... q_j.
    out, total = [P[0]], None
    for j, q in enumerate(turns):
        total = q if total is None else qmul(total, q)
        out.append(out[-1] + qrot(total, P[j + 1] - P[j]))
    return np.array(out)


def _skew_columns(w: Numbers) -> np.ndarray:
    """The three Jacobian columns ``x × w, y × w, z × w`` of a ball joint with lever arm ``w``."""
    zero = 0.0
    return np.array([[zero, w[2], -w[1]], [-w[2], zero, w[0]], [w[1], -w[0], zero]])


def jacobian_iteration(R: Numbers, offsets: Numbers, t: Numbers, method: str,
                       damping: float = 0.0) -> np.ndarray:
    r"""One Jacobian iteration on a chain of ball joints, root at the origin.

    Parameters
    ----------
    R : (n + 1, 4) local rotations; the last (the end effector) is carried unchanged.
    offsets : (n + 1, 3) bone offsets :math:`l_i`.
    t : (3,) the target.
    method : ``"jacobian_transpose"`` (:math:`\alpha J^T\Delta e` with Buss's
        :math:`\alpha = \langle\Delta e, JJ^T\Delta e\rangle / \lVert JJ^T\Delta e\rVert^2`),
        ``"pseudo_inverse"`` or ``"dls"`` (:math:`J^T(JJ^T + \lambda^2 I)^{-1}\Delta e`; the
        pseudo-inverse of a full-row-rank :math:`J` is :math:`\lambda = 0`).
    damping : :math:`\lambda` for ``"dls"``.

    Returns
    -------
    (n + 1, 4) the new local rotations,
    :math:`R_i \leftarrow \exp(Q_{parent}^{-1}\Delta\theta_i)\,R_i`; a joint whose step is
    zero (the effector already on the target) keeps its rotation, and a transpose step whose
    :math:`JJ^T\Delta e` vanishes is zero (:math:`\alpha = 0`, as :mod:`course.ik` takes it).
    """
    if method not in ("jacobian_transpose", "pseudo_inverse", "dls"):
        raise ValueError(f"method: expected 'jacobian_transpose', 'pseudo_inverse' or 'dls', "
                         f"got {method!r}")
    # FK (02): Q_i = Q_parent R_i, p_i = p_parent + Q_parent l_i, joint 0 at the origin.
    Q, p = [R[0]], [offsets[0]]
    for i in range(1, len(R)):
        p.append(p[-1] + qrot(Q[-1], offsets[i]))
        Q.append(qmul(Q[-1], R[i]))
    de = t - p[-1]
    # J (07): a ball joint's three columns are the world axes x, y, z crossed with e - r_i.
    J = np.hstack([_skew_columns(p[-1] - r) for r in p[:-1]])
    if method == "jacobian_transpose":
        g = J.T @ de
        Jg = J @ g
        den = dot(Jg, Jg)
        step = dot(de, Jg) / den * g if _value(den) > 0 else np.zeros(len(g))
    else:
        A = J @ J.T
        if method == "dls" and damping:
            for k in range(3):
                A[k, k] = A[k, k] + damping**2
        step = J.T @ solve3(A, de)
    # R_i <- exp(Q_parent^-1 dtheta_i) R_i: joint i's turn, taken into its parent's frame.
    new = []
    for i in range(len(R) - 1):
        turn = step[3 * i:3 * i + 3]
        if i > 0:
            turn = qrot(np.r_[Q[i - 1][0], -Q[i - 1][1:]], turn)
        angle = norm(turn)
        if _value(angle) == 0:  # no step: exp(0) R_i = R_i (sin(angle/2)/angle would be 0/0)
            new.append(np.asarray(R[i]))
            continue
        new.append(qmul(np.r_[np.cos(angle / 2), np.sin(angle / 2) / angle * turn], R[i]))
    return np.array([*new, R[-1]])


__all__ = [
    "Counted",
    "ccd_sweep",
    "count_ops",
    "counted",
    "cross",
    "dot",
    "jacobian_iteration",
    "norm",
    "qmul",
    "qrot",
    "solve3",
    "values",
]
