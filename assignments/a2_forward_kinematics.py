r"""Assignment a2: forward kinematics on joint trees and real BVH motion capture.

Implement the functions below with **numpy only** (no ``course``, no ``scipy``: the
autograder refuses those imports). Conventions, as in the lecture:

* a skeleton is ``names`` (J,), ``parents`` (J,) ints and ``offsets`` (J, 3), joints listed
  parent before child, ``parents[0] == -1``; ``offsets[i]`` is the bone :math:`l_i`, joint
  i's position in its parent's frame;
* quaternions are scalar first, ``q = (w, x, y, z)``, unit, Hamilton product; ``q`` and
  ``-q`` are the same rotation (the autograder accepts either);
* forward kinematics: :math:`Q_0 = R_0`, :math:`p_0` = the root position, and for every other
  joint :math:`Q_i = Q_{p(i)} R_i`, :math:`p_i = p_{p(i)} + Q_{p(i)}\, l_i`;
* a BVH ``End Site`` is a joint too, named ``"<Parent>_end"``, with no channels.

Check your work with

    python -m autograder check a2

or run the last cell of ``a2_forward_kinematics.ipynb``.
"""

import numpy as np


def parse_bvh_hierarchy(text: str) -> tuple[list[str], np.ndarray, np.ndarray]:
    r"""The skeleton described by the ``HIERARCHY`` section of a BVH file.

    ``text`` is the file up to (not including) its ``MOTION`` line::

        HIERARCHY
        ROOT Hips
        {
            OFFSET 0.0 0.0 0.0
            CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation
            JOINT LeftUpLeg
            {
                OFFSET 3.9 -0.1 0.0
                CHANNELS 3 Zrotation Yrotation Xrotation
                End Site
                {
                    OFFSET 0.0 -7.1 0.0
                }
            }
        }

    Joints come in file order (a joint before its children). Careful with real files:
    tabs or spaces, Windows line endings (``\r\n``), numbers like ``1.5e-01``, a joint with
    no ``End Site`` below it, and ``CHANNELS`` lines of any order and length (skip the
    channel names: their count is the number after ``CHANNELS``).

    Parameters
    ----------
    text : str
        The hierarchy section of a BVH file.

    Returns
    -------
    names : list of str, length J
        Joint names in file order; an ``End Site`` under joint ``"Head"`` is ``"Head_end"``.
    parents : ndarray of int, shape (J,)
        ``parents[0] == -1``; ``parents[i]`` is the index of joint i's parent.
    offsets : ndarray, shape (J, 3)
        The ``OFFSET`` of each joint (the bone :math:`l_i` in the parent's frame).
    """
    raise NotImplementedError("parse_bvh_hierarchy")


def forward_kinematics(
    parents: np.ndarray, offsets: np.ndarray, local_quats: np.ndarray, root_position: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    r"""Global joint positions and orientations of one pose.

    .. math::
        Q_0 = R_0,\quad p_0 = \text{root\_position};\qquad
        Q_i = Q_{p(i)}\, R_i,\quad p_i = p_{p(i)} + Q_{p(i)}\, l_i

    The local rotation :math:`R_i` acts in the parent's frame, so it multiplies on the right;
    the bone :math:`l_i` hangs from the parent, so the *parent's* orientation turns it.
    Rotate a vector by a quaternion with :math:`q\,(0, v)\,q^*` (or its matrix).

    Parameters
    ----------
    parents : ndarray of int, shape (J,)
    offsets : ndarray, shape (J, 3)
        The bones :math:`l_i` (``offsets[0]`` is not used: the root sits at
        ``root_position``).
    local_quats : ndarray, shape (J, 4)
        Local rotations :math:`R_i` as unit quaternions (w, x, y, z).
    root_position : ndarray, shape (3,)

    Returns
    -------
    positions : ndarray, shape (J, 3)
        :math:`p_i`.
    orientations : ndarray, shape (J, 4)
        :math:`Q_i`, unit quaternions.
    """
    raise NotImplementedError("forward_kinematics")


def local_from_global(parents: np.ndarray, orientations: np.ndarray) -> np.ndarray:
    r"""Local rotations from global orientations: the inverse of the orientation part of FK.

    .. math::
        R_0 = Q_0,\qquad R_i = Q_{p(i)}^{-1}\, Q_i

    (for a unit quaternion the inverse is the conjugate :math:`(w, -x, -y, -z)`).

    Parameters
    ----------
    parents : ndarray of int, shape (J,)
    orientations : ndarray, shape (J, 4)
        Global orientations :math:`Q_i`.

    Returns
    -------
    local_quats : ndarray, shape (J, 4)
        :math:`R_i`, with ``forward_kinematics(parents, offsets, local_quats, p0)`` giving back
        ``orientations`` (up to the sign of each quaternion).
    """
    raise NotImplementedError("local_from_global")


def pose_from_frame(text: str, frame: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r"""Bonus: the root position and local rotations of one line of a BVH ``MOTION`` section.

    ``frame`` holds one number per channel, joint after joint in file order, each joint's
    channels in the order of its ``CHANNELS`` line. Rotations are in **degrees**, and a
    joint's rotation is the product of its rotation channels *in the order listed*:
    ``Zrotation Yrotation Xrotation`` is :math:`R = R_Z(z)\,R_Y(y)\,R_X(x)` (intrinsic
    ``"ZYX"``), ``Xrotation Zrotation Yrotation`` is :math:`R_X R_Z R_Y`, and so on; orders
    may differ from joint to joint, and the root may list its rotations before its positions.
    The quaternion of a turn by :math:`\theta` about axis :math:`u` is
    :math:`(\cos\frac\theta2, \sin\frac\theta2\,u)`.

    Parameters
    ----------
    text : str
        The hierarchy section of the file (as for :func:`parse_bvh_hierarchy`).
    frame : ndarray, shape (C,)
        One MOTION line: C numbers, C the total of the ``CHANNELS`` counts.

    Returns
    -------
    root_position : ndarray, shape (3,)
        The root's ``Xposition Yposition Zposition`` channels (an axis without a position
        channel keeps the root's OFFSET).
    local_quats : ndarray, shape (J, 4)
        :math:`R_i` per joint; the identity ``(1, 0, 0, 0)`` for End Sites.
    """
    raise NotImplementedError("pose_from_frame")
