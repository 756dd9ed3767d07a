r"""Assignment a1: rotations.

Implement the six functions below with **numpy only** (no ``course``, no ``scipy``: the
autograder refuses those imports). Conventions, as in the lecture:

* quaternions are scalar first, ``q = (w, x, y, z)``, unit length, Hamilton product;
  ``q`` and ``-q`` are the same rotation (the autograder accepts either);
* rotations are active: ``v' = R v = q v q*``;
* Euler order strings are intrinsic, uppercase ``"XYZ"``: ``R = R_X(a) R_Y(b) R_Z(c)``;
* angles are in radians.

Each function takes and returns **one** rotation (no batching needed). Check your work with

    python -m autograder check a1

or run the last cell of ``a1_rotations.ipynb``.
"""

import numpy as np


def quat_from_matrix(R: np.ndarray) -> np.ndarray:
    r"""The unit quaternion of a rotation matrix.

    From :math:`R = \begin{pmatrix} 1-2(y^2+z^2) & 2(xy-wz) & 2(xz+wy)\\ 2(xy+wz) &
    1-2(x^2+z^2) & 2(yz-wx)\\ 2(xz-wy) & 2(yz+wx) & 1-2(x^2+y^2)\end{pmatrix}`:

    .. math::
        4w^2 = 1 + \mathrm{tr}\,R,\quad 4x^2 = 1 + R_{00} - R_{11} - R_{22},\quad
        4y^2 = 1 - R_{00} + R_{11} - R_{22},\quad 4z^2 = 1 - R_{00} - R_{11} + R_{22}

    and :math:`4wx = R_{21} - R_{12}`, :math:`4wy = R_{02} - R_{20}`,
    :math:`4wz = R_{10} - R_{01}`, :math:`4xy = R_{01} + R_{10}`,
    :math:`4xz = R_{02} + R_{20}`, :math:`4yz = R_{12} + R_{21}`.

    Careful: for a half turn (180°) :math:`w = 0`. Solve first for the **largest** of
    :math:`w, x, y, z`, then get the others by dividing by it.

    Parameters
    ----------
    R : ndarray, shape (3, 3)
        A rotation matrix.

    Returns
    -------
    ndarray, shape (4,)
        ``(w, x, y, z)`` with :math:`w^2 + x^2 + y^2 + z^2 = 1` (either sign).
    """
    raise NotImplementedError("quat_from_matrix")


def matrix_from_quat(q: np.ndarray) -> np.ndarray:
    r"""The rotation matrix of a unit quaternion ``q = (w, x, y, z)``.

    .. math::
        R = \begin{pmatrix} 1-2(y^2+z^2) & 2(xy-wz) & 2(xz+wy)\\
        2(xy+wz) & 1-2(x^2+z^2) & 2(yz-wx)\\
        2(xz-wy) & 2(yz+wx) & 1-2(x^2+y^2) \end{pmatrix}

    Parameters
    ----------
    q : ndarray, shape (4,)
        A unit quaternion.

    Returns
    -------
    ndarray, shape (3, 3)
    """
    raise NotImplementedError("matrix_from_quat")


def quat_from_axis_angle(axis: np.ndarray, angle: float) -> np.ndarray:
    r"""The quaternion of a right-handed turn by ``angle`` about ``axis``.

    .. math::
        q = \left(\cos\frac\theta2,\ \sin\frac\theta2\,u\right),\qquad u = \frac{a}{\lVert a\rVert}

    Parameters
    ----------
    axis : ndarray, shape (3,)
        The rotation axis :math:`a`; any non-zero length (normalise it).
    angle : float
        The angle :math:`\theta` in radians (any value, negative too).

    Returns
    -------
    ndarray, shape (4,)
    """
    raise NotImplementedError("quat_from_axis_angle")


def matrix_from_euler(angles: np.ndarray, order: str) -> np.ndarray:
    r"""The rotation matrix of intrinsic Euler angles.

    For ``order = "XYZ"`` and ``angles = (a, b, c)``: :math:`R = R_X(a)\,R_Y(b)\,R_Z(c)`,
    a turn about x, then about the *new* y, then about the newest z. Any of the 12
    intrinsic orders may be asked for: ``"XYZ" "XZY" "YXZ" "YZX" "ZXY" "ZYX"`` and
    ``"XYX" "XZX" "YXY" "YZY" "ZXZ" "ZYZ"``. The elementary rotations are

    .. math::
        R_X(\theta) = \begin{pmatrix}1&0&0\\0&\cos\theta&-\sin\theta\\0&\sin\theta&\cos\theta
        \end{pmatrix},\;
        R_Y(\theta) = \begin{pmatrix}\cos\theta&0&\sin\theta\\0&1&0\\-\sin\theta&0&\cos\theta
        \end{pmatrix},\;
        R_Z(\theta) = \begin{pmatrix}\cos\theta&-\sin\theta&0\\\sin\theta&\cos\theta&0\\0&0&1
        \end{pmatrix}.

    Parameters
    ----------
    angles : ndarray, shape (3,)
        The three angles in radians, in the order of the letters of ``order``.
    order : str
        Three uppercase axis letters.

    Returns
    -------
    ndarray, shape (3, 3)
    """
    raise NotImplementedError("matrix_from_euler")


def quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    r"""The Hamilton product :math:`a\,b`: the rotation by ``b`` first, then by ``a``.

    .. math::
        a\,b = (w_a w_b - \mathbf v_a\cdot\mathbf v_b,\;
               w_a \mathbf v_b + w_b \mathbf v_a + \mathbf v_a \times \mathbf v_b)

    Parameters
    ----------
    a, b : ndarray, shape (4,)
        Quaternions ``(w, x, y, z)``.

    Returns
    -------
    ndarray, shape (4,)
    """
    raise NotImplementedError("quat_mul")


def slerp(q0: np.ndarray, q1: np.ndarray, t: float) -> np.ndarray:
    r"""Spherical linear interpolation from ``q0`` (at ``t = 0``) to ``q1`` (at ``t = 1``).

    .. math::
        \mathrm{slerp}(q_0, q_1, t) = \frac{\sin((1-t)\Omega)}{\sin\Omega}\,q_0
        + \frac{\sin(t\Omega)}{\sin\Omega}\,q_1,\qquad \cos\Omega = q_0\cdot q_1

    Take the **shortest path**: if :math:`q_0\cdot q_1 < 0`, use :math:`-q_1` instead of
    :math:`q_1` (the same rotation). When :math:`\Omega` is tiny, :math:`\sin\Omega \approx 0`:
    fall back to normalised linear interpolation there.

    Parameters
    ----------
    q0, q1 : ndarray, shape (4,)
        Unit quaternions.
    t : float
        In [0, 1].

    Returns
    -------
    ndarray, shape (4,)
        A unit quaternion.
    """
    raise NotImplementedError("slerp")
