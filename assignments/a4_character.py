r"""Assignment a4: IK on a whole character, written back as local rotations, and rest poses.

Implement the functions below with **numpy only** (no ``course``, no ``scipy``: the
autograder refuses those imports). A skeleton is given as in a2: ``parents`` ``(J,)``
(``parents[0] == -1``, parents before children), bones ``offsets`` ``(J, 3)`` (:math:`l_i`,
joint :math:`i` in its parent's frame), local rotations ``local_quats`` ``(J, 4)``
(:math:`R_i`, unit quaternions ``(w, x, y, z)``) and ``root_position`` (3,), with the
lecture's forward kinematics

.. math::
    Q_i = Q_{p(i)} R_i,\qquad p_i = p_{p(i)} + Q_{p(i)}\, l_i,\qquad
    R_i = Q_{p(i)}^{-1} Q_i .

IK has many right answers, so the autograder never compares your angles with one reference
pose: it runs forward kinematics on your rotations and checks what they achieve (the end
effector on the target, the fixed joint unmoved, the joints off the path unchanged).

Check your work with

    python -m autograder check a4

or run the last cell of ``a4_character.ipynb``.
"""

import numpy as np


def path_to(parents: np.ndarray, start: int, end: int) -> np.ndarray:
    r"""The joints from the fixed joint ``start`` to the end effector ``end``, through the tree.

    The path goes **up** from ``start`` to the lowest common ancestor of the two joints, then
    **down** to ``end``: from the left foot to the right hand it is ``LeftFoot, LeftLeg,
    LeftUpLeg, Hips, Spine, Chest, RightArm, RightForeArm, RightHand``. (Walk up from both
    joints to the root; the first joint the two walks share is the common ancestor.)

    Parameters
    ----------
    parents : ndarray of int, shape (J,)
    start, end : int
        Joint indices (they may be equal: a path of one joint).

    Returns
    -------
    ndarray of int, shape (n,)
        ``start`` first, ``end`` last; consecutive joints are parent and child.
    """
    raise NotImplementedError("path_to")


def ik_local(
    parents: np.ndarray,
    offsets: np.ndarray,
    local_quats: np.ndarray,
    root_position: np.ndarray,
    fixed: int,
    effector: int,
    target: np.ndarray,
    iterations: int,
) -> np.ndarray:
    r"""Whole-body IK (全身IK): the fixed joint (固定关节) stays, the end effector (末端执行器)
    reaches the target; the answer is new **local** rotations.

    Only the joints on ``path_to(parents, fixed, effector)`` turn. Any method will do; CCD on
    world quantities is the shortest way: compute :math:`p_i, Q_i` by forward kinematics,
    then, sweeping the path from the effector back to the fixed joint, at each joint :math:`a`
    of the path take the shortest arc :math:`D` turning :math:`e - p_a` onto
    :math:`t - p_a` and turn the part of the body **beyond** :math:`a` (seen from the fixed
    joint) about :math:`p_a`:

    .. math::
        p_k \leftarrow p_a + D\,(p_k - p_a),\qquad Q_k \leftarrow D\,Q_k .

    Going **down** the path (the next joint is a child of :math:`a`), what turns is the
    subtree of :math:`a`, :math:`a` included (its own :math:`Q_a` changes). Going **up** (the
    next joint is :math:`a`'s parent), it is everything *outside* :math:`a`'s subtree: joint 0,
    the other leg, the arms, the head. :math:`a` keeps its frame, so a planted foot neither
    slides nor turns. (The common ancestor, entered from below, has no turn of its own: its
    edges up and down are one rigid body.)

    Finally read the local rotations off the world orientations,
    :math:`R_i = Q_{p(i)}^{-1} Q_i` (and :math:`R_0 = Q_0`). A turn :math:`D` found in world
    coordinates is **not** a local rotation: :math:`D R_i` is wrong (the lab report's bug).

    Parameters
    ----------
    parents, offsets, local_quats, root_position :
        The skeleton and its pose, as in the module's notes.
    fixed : int
        The fixed joint: it keeps its world position, and its world orientation whenever the
        path leaves it upwards. In every case the path either starts at an ancestor of the
        effector or passes through joint 0.
    effector : int
    target : ndarray, shape (3,)
        A reachable world position for the effector.
    iterations : int
        At most this many sweeps (or iterations of your method); stop earlier once the
        effector is on the target (say within 1e-5 × the path's length).

    Returns
    -------
    ndarray, shape (J, 4)
        New local rotations, unit quaternions. Joints off the path keep theirs. No root
        position: joint 0 goes wherever keeps the fixed joint in place. The autograder
        accepts an effector within 1e-3 × the path's length of the target.
    """
    raise NotImplementedError("ik_local")


def retarget_rest(
    parents: np.ndarray, offsets_from: np.ndarray, offsets_to: np.ndarray,
    local_quats: np.ndarray,
) -> np.ndarray:
    r"""Local rotations for another rest pose of the same hierarchy (T pose ↔ A pose).

    Copying :math:`R_i` from one skeleton to the other is wrong by the rest-pose difference.
    Let :math:`C_i` turn the **target**'s rest bones below joint :math:`i` onto the
    **source**'s: :math:`C_i\,\hat l^{\,to}_c = \hat l^{\,from}_c` for the children
    :math:`c` of :math:`i` (:math:`\hat l` = offset / its length). Asking every bone of the
    target to point where the source's does, :math:`Q'_i = Q_i C_i`, gives

    .. math::
        R'_i = C_{p(i)}^{-1}\, R_i\, C_i ,\qquad R'_0 = R_0\, C_0 .

    :math:`C_i`: with one child bone (or all along one line), the shortest arc from
    :math:`\hat l^{\,to}_c` to :math:`\hat l^{\,from}_c`; with child bones in two directions,
    the rotation taking both (an orthonormal frame from two of them in each skeleton,
    :math:`C = F_{from} F_{to}^T`); a leaf (no child) keeps its parent's :math:`C`. Every bone
    has a length.

    Parameters
    ----------
    parents : ndarray of int, shape (J,)
    offsets_from, offsets_to : ndarray, shape (J, 3)
        The bones of the skeleton ``local_quats`` are for, and of the target skeleton.
    local_quats : ndarray, shape (J, 4)

    Returns
    -------
    ndarray, shape (J, 4)
        Graded by the global bone directions they give the target skeleton.
    """
    raise NotImplementedError("retarget_rest")
