r"""Assignment a5: keyframe splines and an implicit Euler step.

Implement the functions below with **numpy only** (no ``course``, no ``scipy``: the
autograder refuses those imports; solve linear systems with ``np.linalg.solve``).

Keys are values at strictly increasing times :math:`t_0 < \dots < t_{K-1}`. A time ``t``
lies in segment :math:`i` when :math:`t_i \le t < t_{i+1}`; the last key :math:`t_{K-1}` is the
end of the last segment (:math:`i = K - 2`, :math:`u = 1`); inside it
:math:`u = (t - t_i)/h_i` with :math:`h_i = t_{i+1} - t_i`. The times to evaluate at lie
inside :math:`[t_0, t_{K-1}]`, the key times among them.

The implicit Euler step has one right answer, the minimiser of the step's objective, and the
autograder checks what makes it right: the fixed points held, the gradient of the objective
≈ 0 at your positions (it computes it itself), :math:`v^+ = (x^+ - x)/h`, and your positions
close to the reference's.

Check your work with

    python -m autograder check a5

or run the last cell of ``a5_animation.ipynb``.
"""

import numpy as np


def catmull_rom(keys: np.ndarray, times: np.ndarray, t: np.ndarray) -> np.ndarray:
    r"""The Catmull–Rom spline through position keys, at times ``t``.

    The tangent (a velocity :math:`dp/dt`) at an interior key is the central difference over
    the time between its **two neighbours**, one-sided at the end keys:

    .. math::
        m_i = \frac{p_{i+1} - p_{i-1}}{t_{i+1} - t_{i-1}},\qquad
        m_0 = \frac{p_1 - p_0}{t_1 - t_0},\qquad
        m_{K-1} = \frac{p_{K-1} - p_{K-2}}{t_{K-1} - t_{K-2}}.

    On segment :math:`i` the curve is the cubic Hermite segment, tangents per unit :math:`u`
    being :math:`h_i m_i` and :math:`h_i m_{i+1}`:

    .. math::
        p(u) = (2u^3 - 3u^2 + 1)\,p_i + (u^3 - 2u^2 + u)\,h_i m_i
             + (-2u^3 + 3u^2)\,p_{i+1} + (u^3 - u^2)\,h_i m_{i+1}.

    Parameters
    ----------
    keys : ndarray, shape (K, D)
        Key values (K >= 2; D = 1, 2 or 3 channels).
    times : ndarray, shape (K,)
        Strictly increasing, not evenly spaced in general.
    t : ndarray, shape (T,)
        Times in ``[times[0], times[-1]]``.

    Returns
    -------
    ndarray, shape (T, D)
    """
    raise NotImplementedError("catmull_rom")


def squad(q_keys: np.ndarray, times: np.ndarray, t: np.ndarray) -> np.ndarray:
    r"""SQUAD: a smooth spline through rotation keys (unit quaternions ``(w, x, y, z)``).

    First put the keys in one hemisphere: :math:`q` and :math:`-q` are one rotation, so
    flip :math:`q_i \leftarrow -q_i` whenever :math:`q_i \cdot q_{i-1} < 0` (going down the
    keys): every turn between neighbours is then the short one. With
    :math:`\log q = \operatorname{atan2}(\lVert v\rVert, w)\,v/\lVert v\rVert` for
    :math:`q = (w, v)`, :math:`\exp v = (\cos\lVert v\rVert, \sin\lVert v\rVert\,v/\lVert v\rVert)`,
    and :math:`\mathrm{slerp}(a, b, u) = a\exp(u\log(a^{-1}b))`, the control of interior
    key :math:`i` is

    .. math::
        s_i = q_i \exp\!\left(-\frac{h_{i-1}\log(q_i^{-1}q_{i+1}) + h_i\log(q_i^{-1}q_{i-1})}
                                    {2\,(h_{i-1} + h_i)}\right),

    (Shoemake's :math:`-(\dots + \dots)/4` when the keys are evenly spaced), and
    :math:`s_0 = q_0`, :math:`s_{K-1} = q_{K-1}`. On segment :math:`i`:

    .. math::
        \mathrm{squad}(u) = \mathrm{slerp}\big(\mathrm{slerp}(q_i, q_{i+1}, u),\
        \mathrm{slerp}(s_i, s_{i+1}, u),\ 2u(1 - u)\big).

    The keys are in one hemisphere, so :math:`\mathrm{slerp}(q_i, q_{i+1}, u)` is the short
    way. Take the other two slerps **as they are** (:math:`a^{-1}b` with the signs the
    controls and the outer terms have, no flip to :math:`-b`): the inner
    :math:`\mathrm{slerp}(s_i, s_{i+1}, u)` must follow the arc the controls were built on,
    or the curve jumps where the controls' signs happen to differ.

    Parameters
    ----------
    q_keys : ndarray, shape (K, 4)
        Unit quaternion keys, some possibly stored as :math:`-q`.
    times : ndarray, shape (K,)
        Strictly increasing.
    t : ndarray, shape (T,)
        Times in ``[times[0], times[-1]]``.

    Returns
    -------
    ndarray, shape (T, 4)
        Unit quaternions (the grader accepts :math:`q` or :math:`-q`).
    """
    raise NotImplementedError("squad")


def implicit_euler_step(x: np.ndarray, v: np.ndarray, masses: np.ndarray, springs: np.ndarray,
                        rest: np.ndarray, k: np.ndarray, h: float, fixed: np.ndarray,
                        gravity: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r"""One implicit Euler step of a mass–spring system, solved by Newton's method.

    Implicit Euler takes the force at the **end** of the step, :math:`x^+ = x + h v^+`,
    :math:`v^+ = v + h M^{-1} f(x^+)`. That is the minimum of

    .. math::
        E(z) = \frac{1}{2h^2}(z - y)^T M (z - y) + U(z),\qquad y = x + h v + h^2 g,\qquad
        U(z) = \sum_s \tfrac12 k_s (\lVert d_s\rVert - L_s)^2,

    with :math:`d_s = z_i - z_j` for spring :math:`s = (i, j)`. Newton's method repeats
    :math:`z \leftarrow z + \alpha\,\Delta z` (start at :math:`z = y`) with

    .. math::
        \nabla^2E\,\Delta z = -\nabla E,\qquad
        \nabla E = \frac{M(z - y)}{h^2} + \nabla U,\qquad
        \nabla^2 E = \frac{M}{h^2} + \sum_s H_s,

    where spring :math:`s` adds :math:`k_s(1 - L_s/\lVert d_s\rVert)\,d_s` to
    :math:`\partial U/\partial z_i` (the opposite to :math:`z_j`) and the 3×3 block

    .. math::
        H_s = k_s\left[\Big(1 - \frac{L_s}{\lVert d_s\rVert}\Big) I
              + \frac{L_s}{\lVert d_s\rVert}\,\hat d_s\hat d_s^T\right]

    at :math:`(i, i)` and :math:`(j, j)`, :math:`-H_s` at :math:`(i, j)` and :math:`(j, i)`.
    Keep the :math:`(1 - L/\lVert d\rVert)` term: it is negative for a compressed spring.
    a5 wants this **true** Hessian, not the projected one of notebook 12 (each compressed
    block's coefficient clamped at 0): the true Hessian gives Newton's fast (quadratic)
    convergence near the answer, where :math:`\nabla^2 E` is positive definite; the projected
    one converges only linearly there and may not reach the tolerance within the 50
    iterations. Where the true Hessian is indefinite (compressed springs outweigh
    :math:`M/h^2`) its Newton direction may go uphill: if
    :math:`\nabla E\cdot\Delta z \ge 0`, use :math:`\Delta z = -\nabla E` instead.
    **Fixed** particles are not unknowns: drop their rows and columns and keep them where
    they are.

    Line search (needed: from a start far from the answer, a big :math:`h`, the full
    Newton step can overshoot and never settle): start with :math:`\alpha = 1` and halve it
    until

    .. math::
        E(z + \alpha\Delta z) \le E(z) + 10^{-4}\alpha\,\nabla E\cdot\Delta z
                                 + 10^{-14}\,\lvert E(z)\rvert ,

    or until :math:`\alpha < 2^{-30}` (then take that step anyway). The
    :math:`10^{-14}\lvert E\rvert` slack and the :math:`\alpha` floor matter: near the
    minimum the decrease is smaller than the rounding in :math:`E`, and without them the
    halving never ends.

    Stop when :math:`\lVert\nabla E\rVert` (over the free particles) is at most
    :math:`\tau = \max\big(10^{-9} f,\ 100\,\varepsilon\,s\,(\lVert m\rVert/h^2
    + \lVert k\rVert)\big)`, where :math:`f = \max(\lVert m\rVert\,\lVert g\rVert,\
    \lVert\nabla E(z_0)\rVert)` is the force scale (the free particles' weight, or the
    first gradient), :math:`\varepsilon` = ``np.finfo(float).eps``, :math:`s` the largest
    :math:`\lvert\cdot\rvert` of the entries of :math:`x` and :math:`y` and
    :math:`\lVert m\rVert`, :math:`\lVert k\rVert` the norms of the free masses and the
    stiffnesses (the second term is what rounding lets :math:`\lVert\nabla E\rVert` reach),
    **or after 50 Newton iterations**, whichever comes first. The grader accepts any
    :math:`x^+` with :math:`\lVert\nabla E\rVert \le 10^{-6}` times the force scale and
    :math:`E(x^+)` no higher than at its own minimiser. Then :math:`v^+ = (x^+ - x)/h`.

    Parameters
    ----------
    x, v : ndarray, shape (N, 3)
        Positions and velocities at the start of the step (N <= 36 here: a dense
        ``np.linalg.solve`` of size 3N is fine).
    masses : ndarray, shape (N,)
    springs : ndarray of int, shape (S, 2)
        Particle index pairs :math:`(i, j)`.
    rest : ndarray, shape (S,)
        Rest lengths :math:`L_s`.
    k : ndarray, shape (S,)
        Stiffness :math:`k_s`.
    h : float
        The time step.
    fixed : ndarray of int, shape (F,)
        Indices of the particles that do not move (maybe none).
    gravity : ndarray, shape (3,)
        :math:`g`, e.g. ``(0, -9.81, 0)``.

    Returns
    -------
    x, v : ndarray, shape (N, 3)
        Positions and velocities at the end of the step.
    """
    raise NotImplementedError("implicit_euler_step")
