r"""Assignment a8: the Riccati recursion, the infinite-horizon LQR gain and the REINFORCE
estimate of a policy's gradient (GAMES105 lecture 12).

Implement the functions below with **numpy only** (no ``course``, no ``scipy``: the
autograder refuses those imports). The course's conventions (``docs/control.md``): the
dynamics are :math:`x_{t+1} = A x_t + B u_t`, the cost has **no factor ½**,
:math:`\sum_t (x_t^\top Q x_t + u_t^\top R u_t)`, and the gain's sign is **u = -K x**,
:math:`K` of shape (m, n).

Check your work with

    python -m autograder check a8

or run the last cell of ``a8_optimal_control.ipynb``.
"""

import numpy as np


def riccati_step(P_next: np.ndarray, A: np.ndarray, B: np.ndarray, Q: np.ndarray,
                 R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r"""One step of the Riccati recursion backwards in time: :math:`(P_t, K_t)` from
    :math:`P_{t+1}`.

    Minimising :math:`x^\top Q x + u^\top R u + (Ax + Bu)^\top P_{t+1} (Ax + Bu)` over
    :math:`u` gives :math:`u = -K_t x` and the cost-to-go :math:`x^\top P_t x`, with

    .. math::
        K_t = (R + B^\top P_{t+1} B)^{-1} B^\top P_{t+1} A, \qquad
        P_t = Q + A^\top P_{t+1} (A - B K_t).

    Use ``np.linalg.solve`` rather than an inverse.

    Parameters
    ----------
    P_next : ndarray, shape (n, n)
        :math:`P_{t+1}` (symmetric).
    A, B : ndarray, shapes (n, n), (n, m)
    Q, R : ndarray, shapes (n, n), (m, m)
        Symmetric; :math:`Q` positive semi-definite, :math:`R` positive definite.

    Returns
    -------
    P : ndarray, shape (n, n)
        :math:`P_t` (symmetric: ``0.5 * (P + P.T)`` removes the rounding).
    K : ndarray, shape (m, n)
    """
    raise NotImplementedError("riccati_step")


def lqr_gain(A: np.ndarray, B: np.ndarray, Q: np.ndarray, R: np.ndarray) -> np.ndarray:
    r"""The infinite-horizon LQR gain: the Riccati recursion run backwards from :math:`P = Q`
    until :math:`P` stops changing, the gain of its fixed point.

    Stop when :math:`\max|P_{new} - P| \le 10^{-12} \max(1, \max|P_{new}|)` (a slow system
    takes thousands of steps: do not stop after a fixed number). You may call your
    ``riccati_step``.

    Parameters
    ----------
    A, B, Q, R : ndarray, shapes (n, n), (n, m), (n, n), (m, m)

    Returns
    -------
    K : ndarray, shape (m, n)
        The controller is :math:`u = -K x`.
    """
    raise NotImplementedError("lqr_gain")


def reinforce_gradient(x: np.ndarray, u: np.ndarray, cost: np.ndarray,
                       final_cost: np.ndarray, K: np.ndarray, sigma: float,
                       discount: float) -> np.ndarray:
    r"""The REINFORCE estimate of :math:`\nabla_K J` from ``N`` episodes of the policy
    :math:`u \sim \mathcal N(-K x, \sigma^2 I)`, with the leave-one-out mean baseline.

    :math:`J(K) = E[\sum_{t<T} \gamma^t c_t + \gamma^T c_T]` is the expected discounted cost.
    For each episode and step:

    * the score :math:`\nabla_K \log\pi(u_t|x_t) = -(u_t + K x_t)\, x_t^\top / \sigma^2`
      (m x n);
    * the cost-to-go discounted **from t**, :math:`G_t = c_t + \gamma c_{t+1} + \dots +
      \gamma^{T-t} c_T` (:math:`c_T` the final cost);
    * the baseline :math:`b_t`, the mean :math:`G_t` of the **other** episodes.

    The estimate is the mean over episodes of
    :math:`\sum_t \gamma^t\, \nabla_K \log\pi(u_t|x_t)\, (G_t - b_t)`.

    Parameters
    ----------
    x : ndarray, shape (N, T + 1, n)
        The states of each episode, :math:`x_0 \dots x_T`.
    u : ndarray, shape (N, T, m)
        The controls drawn.
    cost : ndarray, shape (N, T)
        The running costs :math:`c_t = x_t^\top Q x_t + u_t^\top R u_t`, not discounted.
    final_cost : ndarray, shape (N,)
        :math:`c_T`, not discounted.
    K : ndarray, shape (m, n)
    sigma : float
        :math:`\sigma > 0`.
    discount : float
        :math:`\gamma \in (0, 1]`.

    Returns
    -------
    ndarray, shape (m, n)
    """
    raise NotImplementedError("reinforce_gradient")
