r"""Assignment a3: inverse kinematics, from two bones to any chain.

Implement the functions below with **numpy only** (no ``course``, no ``scipy``: the
autograder refuses those imports). A chain is given by its joint **positions**
``(n, 3)``: ``positions[0]`` is the root, which never moves, and ``positions[-1]`` the end
effector :math:`e`; bone :math:`i` joins points :math:`i` and :math:`i + 1` and keeps its
length :math:`d_i = \lVert p_{i+1} - p_i\rVert`.

IK has many right answers, so the autograder does not compare your pose with one reference
pose: it checks that the root stayed, that every bone kept its length, and that the end
effector reached the target within ``tol`` (for a target out of reach: that the chain is
stretched straight towards it), and that your solver stops after ``max_iter`` iterations.

Check your work with

    python -m autograder check a3

or run the last cell of ``a3_inverse_kinematics.ipynb``.
"""

import numpy as np


def two_link_ik(
    root: np.ndarray, mid: np.ndarray, end: np.ndarray, target: np.ndarray, pole: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    r"""Analytic two-bone IK (hip-knee-ankle): new positions of the middle and end joints.

    With :math:`l_1 = \lVert mid - root\rVert`, :math:`l_2 = \lVert end - mid\rVert`,
    :math:`d = \lVert target - root\rVert` and :math:`u = (target - root)/d`, the law of cosines
    gives the angle :math:`\alpha` between :math:`u` and the first bone:

    .. math::
        \cos\alpha = \frac{l_1^2 + d^2 - l_2^2}{2\,l_1\,d}.

    That puts the middle joint on a circle about :math:`u`; the **pole** (a point the middle
    joint bends towards, like a knee's) picks the point: with :math:`n` the direction
    ``pole - root`` made perpendicular to :math:`u` and normalised,

    .. math::
        mid' = root + l_1(\cos\alpha\,u + \sin\alpha\,n),\qquad end' = root + d\,u .

    Out of reach (:math:`d > l_1 + l_2`) the limb points straight at the target; closer
    than :math:`|l_1 - l_2|` it folds as far as it can (clamp :math:`d` to
    :math:`[|l_1 - l_2|, l_1 + l_2]` in both formulas).

    Parameters
    ----------
    root, mid, end, target, pole : ndarray, shape (3,)
        The pole is never on the line through root and target.

    Returns
    -------
    mid, end : ndarray, shape (3,)
        The new positions (the root stays).
    """
    raise NotImplementedError("two_link_ik")


def ccd(positions: np.ndarray, target: np.ndarray, tol: float, max_iter: int) -> np.ndarray:
    r"""Cyclic Coordinate Descent on a chain of ball joints.

    One *sweep* visits the joints from the one before the end effector down to the root.
    At joint :math:`i` (position :math:`r_i`) take the rotation :math:`R` (shortest arc) that
    turns :math:`e - r_i` onto :math:`t - r_i`: axis :math:`(e - r_i)\times(t - r_i)`,
    angle between them; then turn everything beyond the joint **about the joint**:

    .. math::
        p_k \leftarrow r_i + R\,(p_k - r_i)\qquad (k > i).

    When :math:`e - r_i` and :math:`t - r_i` point in opposite directions their cross product
    is zero, yet the turn is a half turn (angle :math:`\pi`), not none: use any axis
    perpendicular to :math:`e - r_i`. (With :math:`e` or :math:`t` on the joint itself there is
    no direction to turn to: skip the joint.)

    Sweep until :math:`\lVert e - t\rVert \le tol`, at most ``max_iter`` sweeps.

    Parameters
    ----------
    positions : ndarray, shape (n, 3)
        Joint positions, root first, end effector last (n >= 2).
    target : ndarray, shape (3,)
    tol : float
        Stop when the end effector is this close to the target.
    max_iter : int
        At most this many sweeps (``tol`` may be 0: then exactly ``max_iter``).

    Returns
    -------
    ndarray, shape (n, 3)
        The new positions: same root, same bone lengths.
    """
    raise NotImplementedError("ccd")


def fabrik(positions: np.ndarray, target: np.ndarray, tol: float, max_iter: int) -> np.ndarray:
    r"""FABRIK (Forward And Backward Reaching IK) on a chain of ball joints.

    With the bone lengths :math:`d_i = \lVert p_{i+1} - p_i\rVert` of the input chain and its
    root :math:`b = p_0`, one iteration is

    * forward reaching: :math:`p_{n-1} \leftarrow t`, then for :math:`i = n-2, \dots, 0`:
      :math:`p_i \leftarrow p_{i+1} + d_i\,\frac{p_i - p_{i+1}}{\lVert p_i - p_{i+1}\rVert}`;
    * backward reaching: :math:`p_0 \leftarrow b`, then for :math:`i = 0, \dots, n-2`:
      :math:`p_{i+1} \leftarrow p_i + d_i\,\frac{p_{i+1} - p_i}{\lVert p_{i+1} - p_i\rVert}`.

    Iterate until :math:`\lVert e - t\rVert \le tol`, at most ``max_iter`` times. A target
    farther than :math:`\sum d_i` from the root is out of reach: return the chain stretched
    straight from the root towards it.

    Parameters, returns: as for :func:`ccd`.
    """
    raise NotImplementedError("fabrik")


def jacobian(positions: np.ndarray, axes: np.ndarray) -> np.ndarray:
    r"""The positional Jacobian of a chain of hinge joints.

    Turning hinge :math:`i` (at :math:`r_i`, world axis :math:`a_i`) by :math:`d\theta_i`
    swings everything beyond it, so the end effector moves by :math:`a_i\times(e - r_i)\,
    d\theta_i`:

    .. math::
        J = \big[\,a_0\times(e - r_0)\;\; a_1\times(e - r_1)\;\cdots\;
        a_{n-1}\times(e - r_{n-1})\,\big].

    Parameters
    ----------
    positions : ndarray, shape (n + 1, 3)
        The n joints :math:`r_0 \dots r_{n-1}`, then the end effector :math:`e` last.
    axes : ndarray, shape (n, 3)
        Each joint's unit rotation axis :math:`a_i` in **world** coordinates.

    Returns
    -------
    ndarray, shape (3, n)
        Column :math:`i` is :math:`\partial e / \partial\theta_i`.
    """
    raise NotImplementedError("jacobian")


def dls_step(J: np.ndarray, error: np.ndarray, damping: float) -> np.ndarray:
    r"""One damped-least-squares (Levenberg-Marquardt) step.

    :math:`\Delta\theta` minimises :math:`\lVert J\Delta\theta - e\rVert^2 +
    \lambda^2\lVert\Delta\theta\rVert^2`:

    .. math::
        \Delta\theta = J^T\,(J J^T + \lambda^2 I)^{-1}\, e
        \;=\; (J^T J + \lambda^2 I)^{-1} J^T e .

    ``damping`` is :math:`\lambda` itself: square it. Solve the linear system
    (``np.linalg.solve``) rather than inverting. With :math:`\lambda > 0` the step stays
    bounded even at a singular pose (a stretched arm), where :math:`JJ^T` cannot be
    inverted; with :math:`\lambda = 0` it is the pseudo-inverse step :math:`J^+e` only
    when :math:`J` has full row rank (otherwise :math:`JJ^T` is singular and the formula
    has no answer).

    Parameters
    ----------
    J : ndarray, shape (m, n)
    error : ndarray, shape (m,)
        :math:`e`, e.g. target minus end effector.
    damping : float
        :math:`\lambda \ge 0`.

    Returns
    -------
    ndarray, shape (n,)
    """
    raise NotImplementedError("dls_step")


def trace_curve(positions: np.ndarray, curve: np.ndarray, tol: float,
                max_iter: int) -> np.ndarray:
    r"""Bonus: follow a curve with the end effector.

    For each point of ``curve`` in turn, solve IK (any of your solvers) starting from the
    previous pose, so the chain moves smoothly along.

    Parameters
    ----------
    positions : ndarray, shape (n, 3)
        The starting chain (root first).
    curve : ndarray, shape (K, 3)
        Points to visit, all within reach.
    tol, max_iter :
        Passed on to your solver, per point.

    Returns
    -------
    ndarray, shape (K, n, 3)
        The pose at each curve point: same root and bone lengths, end effector on the point.
    """
    raise NotImplementedError("trace_curve")
