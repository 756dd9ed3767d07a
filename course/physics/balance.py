"""Static balance 静态平衡 of a simulated character (lecture 10): PD on the centre of mass.

A character from :func:`course.physics.character.build_model` stands on both feet in
:func:`standing_pose`. :func:`stand` simulates it for a while, optionally pushed
(:class:`~course.physics.simulation.Push`), under one of three controllers named after the
lecture:

``"none"``
    joint PD only, holding the standing pose: :math:`\\tau = k_p(\\bar q \\ominus q) - k_d\\dot q`
    per ball joint (the root is never actuated).
``"ankle"``
    the ankle strategy 踝关节策略: the same joint PD, plus a desired horizontal force on the
    centre of mass (COM) :math:`f = k_{p,c}(\\bar c - c) - k_{d,c}\\dot c` turned into torques
    at the ankles only, :math:`\\tau_{ankle} = \\tilde J_{ankle}^\\top f`.
``"com"``
    Jacobian transpose 雅可比转置 (a virtual force, as in SIMBICON and Coros et al. 2010):
    the same force turned into torques on every joint of the leg chains from the stance feet
    to the root, :math:`\\tau = \\tilde J^\\top f`, plus gravity compensation: the virtual force
    :math:`m g` upwards through the same Jacobian (each foot carries half).

Each is a :class:`~course.physics.simulation.Controller` on the one simulation loop,
:class:`~course.physics.simulation.Simulation`: ``"none"`` is
:class:`~course.physics.controllers.PD`, ``"ankle"`` and ``"com"`` are :class:`AnkleStrategy`
and :class:`COMBalance` (both a :class:`VirtualForce`), and :func:`stand` is their
composition.

:math:`\\tilde J` is the COM Jacobian with the stance foot fixed: with ``J_c`` from
``mj_jacSubtreeCom`` (the floating-base COM Jacobian, 3 x nv) and ``J_f`` from ``mj_jacBody``
(the foot body's 6 x nv Jacobian), a joint velocity ``q̇_leg`` with the foot held still needs a
root velocity ``v_root = -J_f,root^-1 J_f,leg q̇_leg``, so

.. math:: \\tilde J = J_{c,leg} - J_{c,root}\\, J_{f,root}^{-1} J_{f,leg},

which is what a torque must push against to move the COM while the foot stays on the ground.
By virtual work, :math:`\\tau = \\tilde J^\\top f` does the work :math:`f\\cdot\\delta c` of
the force. MuJoCo's frames are z-up; everything returned here is y-up meters.
"""

from __future__ import annotations

import math
from abc import abstractmethod
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._typing import Array
from .._validate import as_positive
from ..motion import Motion
from ..rotations._kernels import quat_between, quat_conjugate, quat_from_rotvec, quat_mul
from .controllers import PD
from .model import (
    Y_TO_Z_MATRIX,
    Character,
    import_mujoco,
    motion_from_qpos,
    qpos_from_motion,
)
from .simulation import Fall, Push, Simulation

#: The controllers :func:`stand` knows.
CONTROLLERS = ("none", "ankle", "com")
_GRAVITY = 9.81


# -- feet and the standing pose --------------------------------------------------------------


def foot_chains(character: Character) -> tuple[tuple[int, ...], ...]:
    """The feet: per foot, skeleton joints from the ankle down to the tip, top first.

    A foot is a chain of joints whose rest heights are all within 10% of the skeleton's
    height of its lowest point; its first joint (the ankle) has a parent above that band. On
    the CMU skeleton: ``LeftFoot, LeftToeBase, LeftToeBase_end`` and the right one.
    """
    skel = character.skeleton
    rest = skel.rest_positions()
    low = float(rest[:, 1].min())
    band = low + 0.1 * float(np.ptp(rest[:, 1]))
    chains = []
    for j in range(1, skel.n_joints):
        p = skel.parents[j]
        if rest[j, 1] > band or rest[p, 1] <= band:
            continue
        chain = [j]
        while True:
            kids = [c for c in skel.children(chain[-1]) if rest[c, 1] <= band]
            if not kids:
                break
            chain.append(kids[0])
        if len(chain) >= 2:
            chains.append(tuple(chain))
    if len(chains) < 2:
        raise ValueError(
            f"skeleton {skel.names[0]!r}: found {len(chains)} feet (chains of joints near the "
            "lowest point of the rest pose); standing needs two"
        )
    return tuple(chains)


def _com_y_up(character: Character, data: Any) -> Array:
    """Whole-body COM of ``data`` (after kinematics), y-up meters."""
    root = character.bodies[0]
    out: Array = Y_TO_Z_MATRIX.T @ data.subtree_com[root]
    return out


def support_centre(character: Character, motion: Motion, frame: int = 0) -> Array:
    """Centre of the feet, y-up meters: the mean over feet of the midpoint of ankle and tip."""
    positions, _ = motion[frame : frame + 1].forward_kinematics()
    p = positions[0] * character.scale
    mids = [(p[c[0]] + p[c[-1]]) / 2 for c in foot_chains(character)]
    out: Array = np.mean(mids, axis=0)
    return out


def standing_pose(character: Character) -> Motion:
    """A 1-frame standing pose, both feet flat on the ground, made from the skeleton.

    How it is made, from the rest pose (every local rotation the identity: for BVH skeletons a
    T-pose with straight legs):

    1. each foot bone (:func:`foot_chains`: ankle to toe to tip) is turned by the smallest
       rotation that makes it horizontal, so the whole foot lies flat;
    2. the body is tilted as a whole (the root's rotation, the ankles turned back so the feet
       stay flat) until the COM (MuJoCo's ``subtree_com``) is straight above the centre of the
       feet (:func:`support_centre`), and the legs alone are rolled sideways (the roll is
       undone at the root's other children) until both ankles are at one height (the CMU
       skeleton's legs differ by about 5 mm): Newton's method on these three angles with a
       finite-difference Jacobian, to 1e-9 m;
    3. the root is placed so the feet's centre is above the origin and the lowest foot joint
       at height 0 (the clip ground of :func:`~course.physics.character.build_model`, whose
       floor is one capsule radius lower, so the foot capsules rest on it).

    Returns
    -------
    Motion
        One frame, ``frame_time`` 1/60 s, named ``"standing"``.
    """
    mujoco = import_mujoco()
    skel = character.skeleton
    feet = foot_chains(character)
    n = skel.n_joints
    local = np.zeros((1, n, 4))
    local[..., 0] = 1.0
    level: dict[int, Array] = {}  # wanted global rotation of each foot joint
    for chain in feet:
        for j, c in zip(chain[:-1], chain[1:], strict=True):
            d = skel.offsets[c].astype(float)
            flat = d * np.array([1.0, 0.0, 1.0])
            level[j] = quat_between(d, flat) if np.linalg.norm(flat) > 1e-9 else np.array(
                [1.0, 0.0, 0.0, 0.0]
            )
    legs = {a for chain in feet for a in leg_joints(skel, chain[0])}
    upper = [c for c in skel.children(0) if c not in legs]
    data = mujoco.MjData(character.model)
    up = np.array([0.0, 1.0, 0.0])
    rest = skel.rest_positions()
    side = (rest[feet[1][0]] - rest[feet[0][0]]) * np.array([1.0, 0.0, 1.0])
    forward = np.cross(side, up) / np.linalg.norm(side)  # roll axis, horizontal

    def make(params: Array) -> tuple[Motion, Array]:
        tilt = np.array([params[0], 0.0, params[1]])
        roll = params[2] * forward
        local[0, 0] = quat_mul(quat_from_rotvec(tilt), quat_from_rotvec(roll))
        for c in upper:  # the roll is for the legs: the upper body keeps the tilt only
            local[0, c] = quat_conjugate(quat_from_rotvec(roll))
        # feet flat whatever the tilt: local = parent's global^-1 * wanted global
        bare = Motion(skel, local.copy(), np.zeros((1, 3)), 1.0 / 60.0)
        _, rotations = bare.forward_kinematics()
        for chain in feet:
            g_parent = rotations[0, skel.parents[chain[0]]]
            for j in chain[:-1]:
                local[0, j] = quat_mul(quat_conjugate(g_parent), level[j])
                g_parent = level[j]
        motion = Motion(skel, local.copy(), np.zeros((1, 3)), 1.0 / 60.0, name="standing")
        positions, _ = motion.forward_kinematics()
        foot_joints = [j for chain in feet for j in chain]
        centre = support_centre(character, motion) / character.scale  # skeleton units
        root = -centre * np.array([1.0, 0.0, 1.0])
        root[1] = -float(positions[0, foot_joints, 1].min())
        motion = Motion(skel, local.copy(), root[None], 1.0 / 60.0, name="standing")
        data.qpos[:] = qpos_from_motion(character, motion)[0]
        mujoco.mj_kinematics(character.model, data)
        mujoco.mj_comPos(character.model, data)
        offset = _com_y_up(character, data) - support_centre(character, motion)
        ankles = positions[0, [feet[0][0], feet[1][0]], 1] * character.scale
        return motion, np.array([offset[0], offset[2], ankles[1] - ankles[0]])

    # Newton on (tilt about x, tilt about z, roll) with a finite-difference Jacobian
    params = np.zeros(3)
    for _ in range(6):
        motion, r = make(params)
        if np.abs(r).max() < 1e-9:
            break
        jac = np.empty((3, 3))
        for k in range(3):
            e = np.zeros(3)
            e[k] = 1e-6
            jac[:, k] = (make(params + e)[1] - r) / 1e-6
        params = params - np.linalg.solve(jac, r)
    motion, _ = make(params)
    return motion


def leg_joints(skel: Any, j: int) -> list[int]:
    """Joint ``j`` and its ancestors up to the root (the root, joint 0, excluded): the chain a
    foot hangs from, foot first."""
    out = []
    while j > 0:
        out.append(j)
        j = skel.parents[j]
    return out


# -- Jacobians -------------------------------------------------------------------------------


def com_jacobian(character: Character, model: Any, data: Any) -> Array:
    """Floating-base COM Jacobian ``J_c`` (3, nv), z-up: ``ċ = J_c q̇`` (``mj_jacSubtreeCom``
    of the root body; ``data`` must have had ``mj_forward`` or ``mj_step``)."""
    mujoco = import_mujoco()
    jac = np.zeros((3, model.nv))
    mujoco.mj_jacSubtreeCom(model, data, jac, character.bodies[0])
    return jac


def _ancestor_dofs(character: Character, model: Any, body: int) -> NDArray[np.intp]:
    """DOF indices of ``body`` and its ancestors' ball joints (the root's excluded)."""
    dofs: list[int] = []
    b = body
    while b > 0 and b != character.bodies[0]:
        adr = int(model.body_dofadr[b])
        dofs.extend(range(adr, adr + int(model.body_dofnum[b])))
        b = int(model.body_parentid[b])
    return np.array(sorted(dofs), dtype=np.intp)


def stance_com_jacobian(character: Character, model: Any, data: Any, foot_body: int) -> Array:
    """COM Jacobian with ``foot_body`` held fixed, (3, nv), z-up (module docstring):
    ``J_c - J_c,root J_f,root^-1 J_f``; its root columns are zero."""
    mujoco = import_mujoco()
    jc = com_jacobian(character, model, data)
    jp = np.zeros((3, model.nv))
    jr = np.zeros((3, model.nv))
    mujoco.mj_jacBody(model, data, jp, jr, foot_body)
    jf = np.vstack([jp, jr])
    out: Array = jc - jc[:, :6] @ np.linalg.solve(jf[:, :6], jf)
    return out


# -- the balance controllers ------------------------------------------------------------------


class VirtualForce(PD):
    r"""Joint PD holding a pose plus a horizontal virtual force on the COM, through each
    stance foot's COM Jacobian transposed (module docstring).

    :math:`f = k_{p,c}(\bar c - c) - k_{d,c}\dot c`, its vertical part dropped, plus
    :math:`m g` upwards with ``gravity_compensation``, shared equally by the feet; per foot
    :math:`\tau = \tilde J^\top f` on the DOFs :meth:`dofs` picks. :math:`\bar c` is the COM
    when the run starts (:meth:`reset`).

    Parameters
    ----------
    character : Character
    target : ndarray, shape (nq,)
        The pose held by the joint PD.
    kp, kd : float
        Joint PD gains (N m/rad, N m s/rad).
    com_kp, com_kd : float
        COM PD gains (N/m, N s/m).
    gravity_compensation : bool
        Add :math:`\tilde J^\top (m g)`.
    """

    def __init__(self, character: Character, target: Array, *, kp: float, kd: float,
                 com_kp: float, com_kd: float, gravity_compensation: bool) -> None:
        super().__init__(target, kp, kd)
        self.character = character
        self.com_kp = as_positive(com_kp, "com_kp", allow_zero=True)
        self.com_kd = as_positive(com_kd, "com_kd", allow_zero=True)
        self.gravity_compensation = bool(gravity_compensation)

    @abstractmethod
    def dofs(self, model: Any, foot_body: int) -> NDArray[np.intp]:
        """The DOFs the force of the foot ``foot_body`` acts through."""

    def reset(self, sim: Simulation) -> None:
        r"""As :class:`~course.physics.controllers.PD`; the feet, their DOFs, the mass and the
        COM target :math:`\bar c` (the current COM)."""
        super().reset(sim)
        model = sim.model
        self._feet = [self.character.bodies[c[0]] for c in foot_chains(self.character)]
        self._dofs = [self.dofs(model, b) for b in self._feet]
        mass = float(np.sum(model.body_mass))
        self.com_target = sim.data.subtree_com[self.character.bodies[0]].copy()  # z-up
        self._weight = (np.array([0.0, 0.0, mass * _GRAVITY]) if self.gravity_compensation
                        else np.zeros(3))

    def torques(self, sim: Simulation, t: float) -> Array:
        r"""The joint PD's torques plus each foot's :math:`\tilde J^\top f`."""
        tau = super().torques(sim, t)
        model, data, character = sim.model, sim.data, self.character
        jc = com_jacobian(character, model, data)
        c = data.subtree_com[character.bodies[0]]
        cdot = jc @ data.qvel
        f = self.com_kp * (self.com_target - c) - self.com_kd * cdot
        f[2] = 0.0  # horizontal
        f = (f + self._weight) / len(self._feet)
        for b, dofs in zip(self._feet, self._dofs, strict=True):
            jt = stance_com_jacobian(character, model, data, b)
            tau[dofs] += jt[:, dofs].T @ f
        return tau


class AnkleStrategy(VirtualForce):
    """The ankle strategy 踝关节策略: the virtual force through the ankles' DOFs only
    (``stand(controller="ankle")``)."""

    def dofs(self, model: Any, foot_body: int) -> NDArray[np.intp]:
        """The ankle's three DOFs (its ball joint)."""
        adr = int(model.body_dofadr[foot_body])
        return np.arange(adr, adr + 3, dtype=np.intp)


class COMBalance(VirtualForce):
    """Jacobian transpose 雅可比转置 on the COM: the virtual force through every joint of the
    leg chain from the foot to the root (``stand(controller="com")``)."""

    def dofs(self, model: Any, foot_body: int) -> NDArray[np.intp]:
        """The ball-joint DOFs from the foot up to the root (the root's excluded)."""
        return _ancestor_dofs(self.character, model, foot_body)


#: :func:`stand`'s COM controllers by name.
BALANCE_CONTROLLERS: dict[str, type[VirtualForce]] = {"ankle": AnkleStrategy,
                                                      "com": COMBalance}


# -- standing --------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class BalanceResult:
    """What :func:`stand` returns.

    Attributes
    ----------
    motion : Motion
        The simulated motion, one frame per control frame (frame 0 the initial pose).
    fell : bool
        Whether the COM went below ``fall_fraction`` of its initial height.
    fall_time : float or None
        Simulated seconds at the first such frame.
    com : ndarray, shape (F, 3)
        COM per frame, y-up meters.
    com_target : ndarray, shape (3,)
        The COM target ``c̄``: the initial COM (above the feet's centre), y-up meters.
    support : ndarray, shape (3,)
        Centre of the feet at the start (:func:`support_centre`), y-up meters.
    torques : ndarray, shape (F, nv - 6)
        Actuated joint torques (N m, joint frames) of the last step of each frame.
    push : Push or None
    controller : str
    h, sim_time, wall_time : float
        Step, simulated seconds and wall-clock seconds of the loop.
    """

    motion: Motion
    fell: bool
    fall_time: float | None
    com: Array = field(repr=False)
    com_target: Array
    support: Array
    torques: Array = field(repr=False)
    push: Push | None
    controller: str
    h: float
    sim_time: float
    wall_time: float

    @property
    def rate(self) -> float:
        """Simulated seconds per wall-clock second."""
        return self.sim_time / self.wall_time if self.wall_time > 0 else math.inf

    @property
    def max_torque(self) -> float:
        """Largest absolute joint torque component over the run (N m)."""
        return float(np.abs(self.torques).max()) if self.torques.size else 0.0


def stand(
    character: Character,
    pose: Motion | None = None,
    *,
    duration: float = 3.0,
    h: float = 1.0 / 600.0,
    kp: float = 1000.0,
    kd: float = 5.0,
    controller: str = "com",
    com_kp: float = 1000.0,
    com_kd: float = 200.0,
    gravity_compensation: bool | None = None,
    torque_limit: float = 400.0,
    push: Push | None = None,
    on_frame: Callable[[int, Motion], None] | None = None,
    frame_time: float = 1.0 / 60.0,
    fall_fraction: float = 0.6,
    stop_when_fallen: bool = False,
    torques: bool = True,
) -> BalanceResult:
    r"""Simulate ``character`` standing in ``pose`` under a balance controller.

    Parameters
    ----------
    character : Character
    pose : Motion, optional
        Frame 0 is the pose held (and the start, at rest); default :func:`standing_pose`.
    duration : float
        Simulated seconds.
    h : float
        The step; it must divide ``frame_time`` (a ValueError names ``h`` otherwise,
        :func:`~course.physics.simulation.substeps`).
    kp, kd : float
        Joint PD gains (N m/rad, N m s/rad), every ball joint, all controllers.
    controller : {"none", "ankle", "com"}
        Module docstring.
    com_kp, com_kd : float
        COM PD gains (N/m, N s/m) of the horizontal virtual force
        :math:`f = k_{p,c}(\bar c - c) - k_{d,c}\dot c`.
    gravity_compensation : bool, optional
        Add :math:`\tilde J^\top (m g)` on the leg chains; default on for ``"com"`` only.
    torque_limit : float
        Per-component limit on the total joint torque (N m).
    push : Push, optional
        A shove during the run.
    on_frame : callable, optional
        ``on_frame(i, frame)`` after each frame ``i = 1 .. F-1`` with a 1-frame Motion.
    frame_time : float
        Seconds per recorded frame (the control frame).
    fall_fraction : float
        The character has fallen when its COM is below this fraction of its initial height.
    stop_when_fallen : bool
        End the run at the first fallen frame (``motion`` is then shorter).
    torques : bool
        ``False``: no torques at all, a passive ragdoll.

    Returns
    -------
    BalanceResult
    """
    if controller not in CONTROLLERS:
        raise ValueError(f"controller: {controller!r} is not one of {CONTROLLERS}")
    duration = as_positive(duration, "duration")
    frame_time = as_positive(frame_time, "frame_time")
    if pose is None:
        pose = standing_pose(character)
    if pose.skeleton.n_joints != character.skeleton.n_joints:
        raise ValueError("pose: its skeleton does not match the character's")
    n = max(2, round(duration / frame_time) + 1)
    target = qpos_from_motion(character, pose[:1])[0]
    sim = Simulation(character, target, frame_time=frame_time, h=h,
                     torque_limit=torque_limit, push=push,
                     fall=Fall("com", fraction=fall_fraction, stop=stop_when_fallen),
                     on_frame=on_frame, name="stand")
    law: PD | None = None
    if torques:
        comp = controller == "com" if gravity_compensation is None else bool(gravity_compensation)
        law = (PD(target, kp, kd) if controller == "none" else
               BALANCE_CONTROLLERS[controller](character, target, kp=kp, kd=kd,
                                               com_kp=com_kp, com_kd=com_kd,
                                               gravity_compensation=comp))
    record = sim.run(law, n)
    return BalanceResult(
        motion=motion_from_qpos(character, record.qpos, frame_time, name="stand"),
        fell=record.fall_time is not None,
        fall_time=record.fall_time,
        com=record.com @ Y_TO_Z_MATRIX,
        com_target=Y_TO_Z_MATRIX.T @ record.com[0],
        support=support_centre(character, pose),
        torques=record.torques[:, 6:],
        push=push,
        controller=controller,
        h=record.h,
        sim_time=record.sim_time,
        wall_time=record.wall_time,
    )


def largest_push(
    character: Character,
    pose: Motion | None = None,
    *,
    controller: str,
    direction: Sequence[float] | Array = (1.0, 0.0, 0.0),
    duration: float = 0.1,
    joint: str | None = None,
    tol: float = 5.0,
    start: float = 0.25,
    settle: float = 1.5,
    max_force: float = 1e5,
    **stand_options: Any,
) -> float:
    """The largest push (N) the character survives, by bisection over the force.

    The push acts on ``joint`` (default the root) along ``direction`` (y-up, normalized) for
    ``duration`` seconds from ``start``; the character survives it when :func:`stand` under
    ``controller`` has not fallen ``settle`` seconds after the push ends. The force doubles
    from 100 N until one fells it, then bisection narrows the bracket to ``tol`` newtons; the
    survived end is returned (its impulse is that times ``duration``). Deterministic: the
    simulation has no randomness.
    """
    d = push_direction(direction)
    if pose is None:
        pose = standing_pose(character)
    name = character.skeleton.names[0] if joint is None else joint

    def survives(force: Array) -> bool:
        push = Push(name, force, start, duration)
        run = stand(character, pose, controller=controller, duration=start + duration + settle,
                    push=push, stop_when_fallen=True, **stand_options)
        return not run.fell

    return bisect_push(survives, d, tol=tol, max_force=max_force)


def push_direction(direction: Sequence[float] | Array) -> Array:
    """``direction`` (y-up) as a unit 3-vector; ValueError naming it if it is not a nonzero
    3-vector."""
    d = np.asarray(direction, dtype=float)
    if d.shape != (3,) or not np.linalg.norm(d) > 0:
        raise ValueError(f"direction: a nonzero 3-vector (y-up), got {direction!r}")
    out: Array = d / np.linalg.norm(d)
    return out


def bisect_push(survives: Callable[[Array], bool], direction: Sequence[float] | Array, *,
                tol: float = 5.0, max_force: float = 1e5) -> float:
    """The largest push (N) along ``direction`` that ``survives(force)`` accepts, ``force``
    the push in newtons, shape (3,), y-up.

    0 if the unpushed run (zero force) falls. Otherwise the force doubles from 100 N until
    one fells it (or passes ``max_force``: the last survived is returned), then bisection
    narrows the bracket to ``tol`` newtons; the survived end is returned. Every
    ``largest_push`` of the package (standing, walking, stepping) is this search around its
    own run. It assumes survival is monotonic in the force; where it is not (contact makes
    runs chaotic: ``docs/walking_control.md`` measures cases), the figure can be an isolated
    survivor above forces that fall.
    """
    d = push_direction(direction)
    tol = as_positive(tol, "tol")
    if not survives(0.0 * d):
        return 0.0
    lo, hi = 0.0, 100.0
    while survives(hi * d):
        lo, hi = hi, 2 * hi
        if hi > max_force:
            return lo
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if survives(mid * d) else (lo, mid)
    return lo


__all__ = [
    "BALANCE_CONTROLLERS",
    "CONTROLLERS",
    "AnkleStrategy",
    "BalanceResult",
    "COMBalance",
    "VirtualForce",
    "bisect_push",
    "com_jacobian",
    "foot_chains",
    "largest_push",
    "push_direction",
    "stance_com_jacobian",
    "stand",
    "standing_pose",
    "support_centre",
]
