r"""Assignment a6: a rigid-body step, a PD torque with limits and a balance torque.

Implement the functions below with **numpy only** (no ``course``, no ``scipy``: the
autograder refuses those imports). Quaternions are scalar first, ``(w, x, y, z)``, Hamilton
product, body to world; :math:`q` and :math:`-q` are the same rotation (the grader accepts
either).

Check your work with

    python -m autograder check a6

or run the last cell of ``a6_physics.ipynb``.
"""

import numpy as np


def rigid_body_step(x: np.ndarray, v: np.ndarray, q: np.ndarray, L: np.ndarray, mass: float,
                    inertia_body: np.ndarray, force: np.ndarray, torque: np.ndarray, h: float
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    r"""One semi-implicit (symplectic) Euler step of a rigid body, angular-momentum form.

    With :math:`R` the rotation matrix of :math:`q` at the **start** of the step:

    .. math::
        v^+ = v + h\,f/m,\qquad x^+ = x + h\,v^+,\qquad L^+ = L + h\,\tau,

        \omega = R\,I_0^{-1}R^T L^+,\qquad
        q^+ = \frac{q + \frac h2\,[0, \omega]\otimes q}{\lVert q + \frac h2\,[0, \omega]
        \otimes q\rVert}.

    :math:`L`, :math:`\tau`, :math:`f` and :math:`\omega` are in the world frame;
    :math:`I_0` in the body frame (the world inertia is :math:`I = R I_0 R^T`).

    Parameters
    ----------
    x, v : ndarray, shape (3,)
        Centre-of-mass position and velocity.
    q : ndarray, shape (4,)
        Unit quaternion, body to world.
    L : ndarray, shape (3,)
        Angular momentum about the centre of mass.
    mass : float
    inertia_body : ndarray, shape (3, 3)
        :math:`I_0` (symmetric positive definite, maybe not diagonal).
    force, torque : ndarray, shape (3,)
        The total force, and the torque about the centre of mass, over the step.
    h : float
        The time step.

    Returns
    -------
    x, v, q, L : ndarray, shapes (3,), (3,), (4,), (3,)
    """
    raise NotImplementedError("rigid_body_step")


def pd_torque(q: np.ndarray, q_bar: np.ndarray, omega: np.ndarray, kp: float, kd: float,
              limit: float) -> np.ndarray:
    r"""PD torques of ball joints driving each joint's rotation ``q`` to its target ``q_bar``.

    The error is the turn from :math:`q` to :math:`\bar q` in the joint's own frame,
    :math:`d = q^{-1}\bar q`, taken the short way (:math:`\bar q` and :math:`-\bar q` are
    one target: flip :math:`d \leftarrow -d` when its :math:`w < 0`), as a rotation vector
    :math:`r = 2\log d = 2\,\mathrm{atan2}(\lVert v\rVert, w)\,v/\lVert v\rVert` for
    :math:`d = (w, v)` (:math:`r = 0` when :math:`v = 0`). Then

    .. math:: \tau = \mathrm{clip}(k_p\,r - k_d\,\omega,\ -\mathrm{limit},\ \mathrm{limit})

    component by component, :math:`\omega` being the joint's angular velocity in its own
    frame (the frame of :math:`r`).

    Parameters
    ----------
    q, q_bar : ndarray, shape (J, 4)
        Current and target unit quaternions, one per joint.
    omega : ndarray, shape (J, 3)
    kp, kd, limit : float
        Gains (> 0) and the largest torque a component may have.

    Returns
    -------
    ndarray, shape (J, 3)
    """
    raise NotImplementedError("pd_torque")


def balance_torque(joint_angles: np.ndarray, lengths: np.ndarray, masses: np.ndarray,
                   com_ratios: np.ndarray, com_target: np.ndarray, com_velocity: np.ndarray,
                   kp: float, kd: float) -> np.ndarray:
    r"""Jacobian-transpose balance torques of a planar chain standing on a fixed foot.

    The chain lies in the x-y plane (y up), its foot (joint 0) at the origin. Link
    :math:`i` starts at joint :math:`i` and points along
    :math:`u_i = (-\sin\varphi_i, \cos\varphi_i)`, :math:`\varphi_i = \theta_0 + \dots +
    \theta_i` (the joint angles are relative, counter-clockwise; all zero is straight up):
    :math:`p_{i+1} = p_i + l_i u_i`. Its centre of mass is :math:`c_i = p_i + \rho_i l_i u_i`
    and the body's is :math:`c = \sum_i m_i c_i / M`, :math:`M = \sum_i m_i`.

    The Jacobian of a point :math:`p` carried by link :math:`i` has the columns
    :math:`\partial p/\partial\theta_j = \hat z\times(p - p_j) = (-(p - p_j)_y,\ (p - p_j)_x)`
    for :math:`j \le i` (0 for the joints above it). The COM's is the mass-weighted
    :math:`J_c = \sum_i m_i J_{c_i} / M`, shape (2, n). A virtual force at the COM,

    .. math:: f = k_p(\bar c - c) - k_d\,\dot c,

    is made by the joint torques :math:`\tau = J_c^T f`. (No gravity compensation here:
    :math:`\tau` is the balance feedback alone.)

    Parameters
    ----------
    joint_angles, lengths, masses, com_ratios : ndarray, shape (n,)
        :math:`\theta_i`, :math:`l_i`, :math:`m_i` and :math:`\rho_i` (the COM's place along
        its link, 0 at its start, 1 at its end).
    com_target, com_velocity : ndarray, shape (2,)
        :math:`\bar c` and :math:`\dot c`.
    kp, kd : float

    Returns
    -------
    ndarray, shape (n,)
    """
    raise NotImplementedError("balance_torque")
