r"""Assignment a7: the capture point, SIMBICON's balance feedback and the ZMP (lecture 11).

Implement the functions below with **numpy only** (no ``course``, no ``scipy``: the
autograder refuses those imports). y is up: the ground plane is x-z and gravity is
``(0, -g, 0)``. Arrays broadcast over leading dimensions: a ``(3,)`` COM or a ``(B, 3)`` batch
of them, and so on.

Check your work with

    python -m autograder check a7

or run the last cell of ``a7_walking.ipynb``. Besides single calls, the autograder plugs your
functions into the simulated CMU character: your capture point decides when and where it
steps after a push, your feedback places its swing foot while it walks.
"""

import numpy as np


def capture_point(com: np.ndarray, com_velocity: np.ndarray, ground_height: float | np.ndarray,
                  gravity: float) -> np.ndarray:
    r"""The capture point of the linear inverted pendulum, on the ground.

    .. math::
        \xi = c + \frac{\dot c}{\omega_0}, \qquad \omega_0 = \sqrt{g / h},

    with :math:`h` the COM's height **above the ground** the foot stands on
    (``com[..., 1] - ground_height``), and :math:`c, \dot c` the COM's ground-plane position
    and velocity, their ``(x, z)``.

    Parameters
    ----------
    com, com_velocity : ndarray, shape (..., 3)
        The centre of mass and its velocity, y up (m, m/s).
    ground_height : float or ndarray, shape (...)
        The ground's y under the foot (m).
    gravity : float
        :math:`g`, gravity's magnitude (9.81 m/s² on Earth).

    Returns
    -------
    ndarray, shape (..., 2)
        :math:`\xi`'s ``(x, z)``.
    """
    raise NotImplementedError("capture_point")


def swing_hip_target(theta_d0: float, c_d: float, c_v: float, com: np.ndarray,
                     com_velocity: np.ndarray, stance_ankle: np.ndarray,
                     heading: float) -> np.ndarray:
    r"""SIMBICON's balance feedback: the swing hip's target angle (forward, in the world).

    .. math:: \theta_d = \theta_{d0} + c_d\,d + c_v\,v

    with :math:`d` the COM's horizontal offset from the stance ankle and :math:`v` the COM's
    velocity, both measured along the walking direction :math:`f = (\sin\psi, 0, \cos\psi)`
    of the heading :math:`\psi` (the world's heading frame, not the pelvis's):
    :math:`d = (c - a)\cdot f`, :math:`v = \dot c\cdot f`.

    Parameters
    ----------
    theta_d0 : float
        :math:`\theta_{d0}`, the target without feedback (rad).
    c_d, c_v : float
        The feedback gains (rad/m, rad s/m; positive).
    com, com_velocity, stance_ankle : ndarray, shape (..., 3)
        The COM, its velocity and the stance ankle, y up.
    heading : float
        :math:`\psi`, radians about +y (0: walking along +z; positive: turned to the left,
        towards +x).

    Returns
    -------
    ndarray, shape (...)
        :math:`\theta_d` (a 0-d array, or a float, for one state).
    """
    raise NotImplementedError("swing_hip_target")


def zmp_from_forces(positions: np.ndarray, forces: np.ndarray,
                    ground_height: float | np.ndarray) -> np.ndarray:
    r"""The ZMP (centre of pressure) of point contact forces on flat ground.

    The point :math:`p` of the ground plane :math:`y = p_y` about which the forces' moment
    :math:`\sum_i (r_i - p)\times f_i` has no horizontal part:

    .. math::
        p_x = \frac{\sum_i x_i f_{i,y} - (y_i - p_y) f_{i,x}}{\sum_i f_{i,y}}, \qquad
        p_z = \frac{\sum_i z_i f_{i,y} - (y_i - p_y) f_{i,z}}{\sum_i f_{i,y}}.

    Parameters
    ----------
    positions : ndarray, shape (..., k, 3)
        The contact points :math:`r_i`, y up (some may be a little above the ground).
    forces : ndarray, shape (..., k, 3)
        The force the ground exerts at each (its y part, the normal force, is positive).
    ground_height : float or ndarray, shape (...)
        :math:`p_y`.

    Returns
    -------
    ndarray, shape (..., 3)
        :math:`(p_x, p_y, p_z)`.
    """
    raise NotImplementedError("zmp_from_forces")
