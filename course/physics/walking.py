r"""Walking 行走 on the simulated character (lecture 11): SIMBICON (Yin, Loken and van de
Panne 2007) on the MuJoCo character :func:`~course.physics.model.build_model` makes of a
skeleton (the CMU one: ball joints, capsule feet), driven only by joint torques (the root gets
none, ever).

:class:`SIMBICON` is a :class:`~course.physics.simulation.Controller` on the one simulation
loop :func:`course.physics.character.track` and :func:`course.physics.balance.stand` use:

* **a state machine**, four states per stride, two per leg: swing-lift for
  :attr:`Gait.lift_time`, then swing-down until the swing foot touches the ground (or
  :attr:`Gait.max_swing_time`); the touch-down swaps the legs (:class:`Footstep`);
* **PD targets per state**: knees and the stance ankle in joint space, the swing foot's pitch
  in the world frame (it lands flat), everything else held at :func:`neutral_pose`;
* **the torso and the swing hip in the world frame**: the root's orientation is pulled to an
  upright target along the heading, :math:`\tau_{torso} = k_p \log(R_d R^\top) - k_d\omega`,
  the swing thigh to its target, :math:`\tau_{swing} = k_p\log(R_d R^\top)`, and the stance
  hip takes :math:`\tau_{stance} = -\tau_{torso} - \tau_{swing}`, so the hips' torques on
  the pelvis sum to the torso's; both hip torques are also applied through the pelvis bone
  (CMU's ``LHipJoint``) so they reach the root whole;
* **balance feedback on the swing hip**: :math:`\theta_d = \theta_{d0} + c_d d + c_v (v -
  \bar v)` forward and :math:`\phi_d = \phi_{d0} + c_{d,c} d_c + c_{v,c} v_c` outward, with
  :math:`d, v` the COM's offset from the stance ankle and its velocity along the heading
  (coronal: towards the swing side), :math:`\bar v` the speed input;
* **a speed and a heading input** (:attr:`SIMBICON.speed`, :attr:`SIMBICON.heading`,
  radians about the vertical, positive to the left; both may change between frames);
* simplifications from the literature, each in ``docs/walking_control.md``: joint damping is
  MuJoCo's implicit joint damping (stable PD's, Tan et al. 2011), gravity compensation of the
  swing leg (Coros et al. 2010), a stiff stance ankle, a reduced yaw gain (line feet), and a
  per-group gain table (:data:`DEFAULT_GAINS`).

:func:`walk` runs it, :func:`largest_push` bisects the push it survives while walking.
MuJoCo is imported only when something here runs.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._typing import Array
from .._validate import as_positive
from ..motion import Motion
from ..rotations._kernels import quat_between, quat_conjugate, quat_from_rotvec, quat_mul
from ..skeleton import Skeleton
from .balance import bisect_push, foot_chains, push_direction
from .model import Y_TO_Z_MATRIX, Character, import_mujoco, motion_from_qpos, qpos_from_motion
from .simulation import Controller, Fall, Push, Simulation

_GRAVITY = 9.81


# -- the body: legs, torso, arms ---------------------------------------------------------------


@dataclass(frozen=True)
class Leg:
    """One leg of the character: skeleton joints, MuJoCo bodies and DOF addresses.

    ``pelvis`` is the joint between the root and the hip (CMU's ``LHipJoint``, a bone of the
    pelvis), -1 when the hip is a child of the root.
    """

    side: str
    pelvis: int
    hip: int
    knee: int
    ankle: int
    toe: int
    bodies: tuple[int, ...]  # pelvis (if any), thigh, shin, foot, toe bodies
    thigh: int
    shin: int
    foot: int
    toe_body: int
    pelvis_body: int
    hip_dof: int
    knee_dof: int
    ankle_dof: int
    toe_dof: int
    pelvis_dof: int


@dataclass(frozen=True)
class Body:
    """The parts of a character that walking needs (:func:`body_parts`)."""

    left: Leg
    right: Leg
    arms: tuple[int, ...]  # skeleton joints of the upper arms (turned down in the neutral pose)

    def legs(self) -> tuple[Leg, Leg]:
        return self.left, self.right


def _leg(character: Character, chain: tuple[int, ...], side: str) -> Leg:
    skel = character.skeleton
    model = character.model
    ankle, toe = chain[0], chain[1]
    knee = skel.parents[ankle]
    hip = skel.parents[knee]
    pelvis = skel.parents[hip]
    if knee <= 0 or hip <= 0:
        raise ValueError(f"skeleton {skel.names[0]!r}: the foot {skel.names[ankle]!r} needs a "
                         "knee and a hip above it")
    if pelvis == 0:
        pelvis = -1
    b = character.bodies

    def dof(j: int) -> int:
        return int(model.jnt_dofadr[model.body_jntadr[b[j]]]) if j >= 0 else -1

    return Leg(side=side, pelvis=pelvis, hip=hip, knee=knee, ankle=ankle, toe=toe,
               bodies=tuple(b[j] for j in (pelvis, hip, knee, ankle, toe) if j >= 0),
               thigh=b[hip], shin=b[knee], foot=b[ankle], toe_body=b[toe],
               pelvis_body=b[pelvis] if pelvis >= 0 else -1,
               hip_dof=dof(hip), knee_dof=dof(knee), ankle_dof=dof(ankle), toe_dof=dof(toe),
               pelvis_dof=dof(pelvis))


def body_parts(character: Character) -> Body:
    """The character's legs (left and right: the left foot is the one at larger rest x, the
    y-up skeleton's left) and upper arms (per lateral branch of the upper body, its longest
    sideways bone: CMU's ``LeftArm``, ``RightArm``)."""
    skel = character.skeleton
    chains = foot_chains(character)
    rest = skel.rest_positions()
    a, b = chains[0], chains[1]
    left, right = (a, b) if rest[a[0], 0] > rest[b[0], 0] else (b, a)
    legs = {j for c in (left, right) for j in _path_to_root(skel, c[-1])}
    arms = []
    for j in range(1, skel.n_joints):
        if j in legs or character.bodies[j] < 0:
            continue
        kids = [c for c in skel.children(j) if np.linalg.norm(skel.offsets[c]) > 1e-9]
        if not kids:
            continue
        d = skel.offsets[kids[0]]
        if abs(d[0]) < 0.9 * np.linalg.norm(d):
            continue
        # the longest sideways bone of this branch: compare with the parent's and the child's
        longest = True
        for k in (skel.parents[j], kids[0]):
            kk = [c for c in skel.children(k) if np.linalg.norm(skel.offsets[c]) > 1e-9]
            if kk and np.linalg.norm(skel.offsets[kk[0]]) > np.linalg.norm(d) and abs(
                    skel.offsets[kk[0]][0]) > 0.9 * np.linalg.norm(skel.offsets[kk[0]]):
                longest = False
        if longest:
            arms.append(j)
    return Body(_leg(character, left, "left"), _leg(character, right, "right"), tuple(arms))


def _path_to_root(skel: Skeleton, j: int) -> list[int]:
    out = []
    while j > 0:
        out.append(j)
        j = skel.parents[j]
    return out


# -- the neutral pose ---------------------------------------------------------------------------

_DOWN = np.array([0.0, -1.0, 0.0])  # y-up


def neutral_pose(character: Character, *, arm_angle: float = 0.15,
                 spine_lean: float = 0.15) -> Motion:
    """A 1-frame pose to walk from (y-up, frame time 1/60 s).

    The pelvis (the root) level and facing +z, the torso bent forward by ``spine_lean``
    radians at its lowest joint (CMU's ``LowerBack``; the walk clip bends it 8 degrees), the
    upper arms (:func:`body_parts`) turned down beside the body ``arm_angle`` radians out from
    vertical, everything else above the hips as in the rest pose; each leg straight, in the
    sagittal plane below its hip, the feet flat and pointing forward, both legs pitched back
    by one angle until the COM is above the centre of the feet (the CMU skeleton's hips are
    6 cm in front of its spine: with vertical legs its COM is 10 cm behind the feet). The root
    is placed so the lowest foot joint is at height 0 (the clip ground), the feet's centre
    under the origin.
    """
    mujoco = import_mujoco()
    skel = character.skeleton
    parts = body_parts(character)
    n = skel.n_joints
    data = mujoco.MjData(character.model)
    feet = [j for leg in parts.legs() for j in (leg.ankle, leg.toe)]
    legs = {j for leg in parts.legs() for j in (leg.pelvis, leg.hip)}
    spine = [c for c in skel.children(0) if c not in legs]

    def make(back: float, roll: float) -> tuple[Motion, Array]:
        local = np.zeros((1, n, 4))
        local[..., 0] = 1.0
        g_root = quat_from_rotvec(np.array([0.0, 0.0, roll]))  # about forward (+z)
        local[0, 0] = g_root
        for c in spine:  # the roll is for the legs: the spine undoes it
            local[0, c] = quat_mul(quat_conjugate(g_root),
                                   quat_from_rotvec(np.array([spine_lean, 0.0, 0.0])))
        pitch = quat_from_rotvec(np.array([-back, 0.0, 0.0]))  # the feet move back
        for leg in parts.legs():
            g_thigh = quat_mul(pitch, quat_between(skel.offsets[leg.knee], _DOWN))
            g_shin = quat_mul(pitch, quat_between(skel.offsets[leg.ankle], _DOWN))
            g_foot = _flat(skel.offsets[leg.toe])
            tips = [c for c in skel.children(leg.toe) if np.linalg.norm(skel.offsets[c]) > 1e-9]
            g_toe = _flat(skel.offsets[tips[0]]) if tips else g_foot
            g_parent = _global(skel, local[0], skel.parents[leg.hip])
            local[0, leg.hip] = quat_mul(quat_conjugate(g_parent), g_thigh)
            local[0, leg.knee] = quat_mul(quat_conjugate(g_thigh), g_shin)
            local[0, leg.ankle] = quat_mul(quat_conjugate(g_shin), g_foot)
            local[0, leg.toe] = quat_mul(quat_conjugate(g_foot), g_toe)
        for arm in parts.arms:
            kid = [c for c in skel.children(arm) if np.linalg.norm(skel.offsets[c]) > 1e-9][0]
            d = skel.offsets[kid]
            want = np.array([math.sin(arm_angle) * np.sign(d[0]), -math.cos(arm_angle), 0.0])
            g_parent = _global(skel, local[0], skel.parents[arm])  # bent with the spine
            local[0, arm] = quat_mul(quat_conjugate(g_parent), quat_between(d, want))
        motion = Motion(skel, local, np.zeros((1, 3)), 1.0 / 60.0, name="neutral")
        positions, _ = motion.forward_kinematics()
        root = np.zeros(3)
        root[1] = -float(positions[0, feet, 1].min())
        centre = positions[0, feet].mean(axis=0)
        root[0], root[2] = -centre[0], -centre[2]
        motion = Motion(skel, local, root[None], 1.0 / 60.0, name="neutral")
        data.qpos[:] = qpos_from_motion(character, motion)[0]
        mujoco.mj_kinematics(character.model, data)
        mujoco.mj_comPos(character.model, data)
        com = Y_TO_Z_MATRIX.T @ data.subtree_com[character.bodies[0]] / character.scale
        ankles = positions[0, [parts.left.ankle, parts.right.ankle], 1]
        # the COM's forward offset from the feet's centre; the ankles' height difference
        return motion, np.array([float(com[2]), float(ankles[0] - ankles[1])])

    # Newton on (leg pitch, pelvis roll) with a finite-difference Jacobian
    params = np.array([0.1, 0.0])
    for _ in range(8):
        r = make(*params)[1]
        if np.abs(r).max() < 1e-6:
            break
        jac = np.empty((2, 2))
        for k in range(2):
            e = np.zeros(2)
            e[k] = 1e-6
            jac[:, k] = (make(*(params + e))[1] - r) / 1e-6
        params = params - np.linalg.solve(jac, r)
    return make(*params)[0]


def _global(skel: Skeleton, local: Array, j: int) -> Array:
    """Global rotation of joint ``j`` from the local rotations ``local`` (J, 4)."""
    q: Array = local[0]
    for k in reversed(_path_to_root(skel, j)):
        q = quat_mul(q, local[k])
    return q


def _flat(d: Array) -> Array:
    """The smallest rotation that makes the bone ``d`` (y-up) horizontal."""
    flat = d * np.array([1.0, 0.0, 1.0])
    if np.linalg.norm(flat) < 1e-9:
        return np.array([1.0, 0.0, 0.0, 0.0])
    out: Array = quat_between(d, flat)
    return out


# -- small rotation helpers (z-up MuJoCo frames) ------------------------------------------------
# Scalar versions of one 3x3 each, not course.rotations' batched kernels (matrix_from_rotvec,
# rotvec_from_matrix): those cost 15-35 us per single matrix from Python, these 1.5-2 us, and
# the torque law calls them about five times a step, 600 steps per simulated second.

_LEFT = np.array([1.0, 0.0, 0.0])  # z-up: the character's left at heading 0
_FORWARD = np.array([0.0, -1.0, 0.0])  # z-up: where the feet point at heading 0


def _axis_angle(axis: Array, angle: float) -> Array:
    """Rotation matrix of ``angle`` radians about the unit ``axis``."""
    x, y, z = float(axis[0]), float(axis[1]), float(axis[2])
    c, s = math.cos(angle), math.sin(angle)
    C = 1.0 - c
    return np.array([[c + x * x * C, x * y * C - z * s, x * z * C + y * s],
                     [y * x * C + z * s, c + y * y * C, y * z * C - x * s],
                     [z * x * C - y * s, z * y * C + x * s, c + z * z * C]])


def _axis_angle_vector(r: Array) -> Array:
    """Rotation matrix of the rotation vector ``r``."""
    angle = math.sqrt(float(r @ r))
    if angle < 1e-12:
        return np.eye(3)
    return _axis_angle(r / angle, angle)


def _log(R: Array) -> Array:
    """The rotation vector of the rotation matrix ``R`` (angle in [0, pi])."""
    cos = max(-1.0, min(1.0, 0.5 * (R[0, 0] + R[1, 1] + R[2, 2] - 1.0)))
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    angle = math.acos(cos)
    s = math.sin(angle)
    if s > 1e-6:
        return w * (0.5 * angle / s)
    if cos > 0:  # near the identity
        return 0.5 * w
    # near pi: R = 2 a a^T - I, the axis from the largest column of (R + I) / 2
    B = 0.5 * (R + np.eye(3))
    k = int(np.argmax(np.diag(B)))
    axis = B[:, k] / math.sqrt(max(float(B[k, k]), 1e-12))
    out: Array = axis / np.linalg.norm(axis) * angle
    return out


def _quat(R: Array) -> Array:
    """The unit quaternion (w, x, y, z) of a rotation matrix (MuJoCo's ``mju_mat2Quat``)."""
    q = np.zeros(4)
    import_mujoco().mju_mat2Quat(q, np.ascontiguousarray(R).ravel())
    return q


# -- SIMBICON -----------------------------------------------------------------------------------

#: Gain groups of :class:`Gait` ``gains``: per group ``(kp, kd)``, N m/rad and N m s/rad.
#: ``torso`` and ``hip`` are world-frame laws (the root, the swing thigh), the rest joint PD.
DEFAULT_GAINS: dict[str, tuple[float, float]] = {
    "torso": (300.0, 30.0),
    "hip": (300.0, 30.0),
    "pelvis": (1000.0, 30.0),
    "knee": (300.0, 15.0),
    "ankle": (300.0, 10.0),
    "toe": (100.0, 3.0),
    "spine": (500.0, 30.0),
    "neck": (100.0, 5.0),
    "arm": (100.0, 5.0),
    "hand": (30.0, 1.0),
}


#: The default gains of :class:`Gait`: :data:`DEFAULT_GAINS` with a stiffer ankle, swing hip
#: and torso, tuned with :class:`Gait`'s defaults for the CMU character (what they achieve is
#: measured in ``docs/walking_control.md``).
GAIT_GAINS: dict[str, tuple[float, float]] = {
    **DEFAULT_GAINS, "ankle": (888.0, 29.6), "hip": (357.0, 35.7), "torso": (388.0, 38.8)}


@dataclass(frozen=True, eq=False)
class Gait:
    r"""SIMBICON's parameters: the state machine's timing, the PD targets of each state, the
    balance feedback and the gains. Angles in radians; ``(lift, down)`` pairs give a target
    for each of the two states of a step.

    Attributes
    ----------
    lift_time : float
        Seconds of swing-lift (state 0 and 2 of SIMBICON's four).
    first_lift_time : float
        Seconds of the first swing-lift, from rest.
    max_swing_time : float
        Swing-down ends at the swing foot's contact, or after this many seconds of the step.
    swing_hip : (float, float)
        :math:`\theta_{d0}`: the swing thigh's forward angle in the world frame, from the
        neutral pose's (:func:`neutral_pose`), before feedback.
    swing_knee, stance_knee : (float, float)
        Knee flexion targets (joint PD).
    swing_ankle : (float, float)
        The swing foot's pitch in the world frame (toe down positive; 0: flat), so it lands
        flat (Coros et al. 2010 control the swing foot's orientation in the world too).
    stance_ankle : (float, float)
        The stance ankle's flexion from the neutral pose (joint PD).
    swing_hip_out : (float, float)
        :math:`\phi_{d0}`: the swing thigh's outward (coronal) angle, before feedback.
    torso_lean : float
        The torso's (the root's) forward lean, world frame.
    c_d, c_v : float
        Sagittal feedback :math:`\theta_d = \theta_{d0} + c_d d + c_v (v - \bar v)`.
    c_d_coronal, c_v_coronal : float
        Coronal feedback :math:`\phi_d = \phi_{d0} + c_{d,c} d_c + c_{v,c} v_c`.
    gravity_compensation : bool
        Add :math:`J^\top m g` of the swing leg's bodies to its joints (Coros et al. 2010).
    yaw_gain : float
        Fraction of the world-frame torque about the vertical kept (torso and swing hip): the
        character's feet are lines of capsules, whose torsional friction is small, and the
        full yaw torque spins the stance foot.
    hip_range, hip_out_range : (float, float)
        Clamps of :math:`\theta_d` and :math:`\phi_d`.
    ramp_time : float
        Seconds over which the swing thigh's target turns from its orientation at a state's
        start to the state's target (0: at once).
    gains : dict
        ``(kp, kd)`` per group of :data:`DEFAULT_GAINS`; missing groups take the default.
    """

    lift_time: float = 0.276
    first_lift_time: float = 0.276
    max_swing_time: float = 1.0
    swing_hip: tuple[float, float] = (0.356, 0.268)
    swing_knee: tuple[float, float] = (0.706, 0.1)
    swing_ankle: tuple[float, float] = (-0.040, 0.010)
    stance_knee: tuple[float, float] = (0.052, 0.052)
    stance_ankle: tuple[float, float] = (-0.049, -0.049)
    swing_hip_out: tuple[float, float] = (0.0, 0.0)
    torso_lean: float = -0.030
    c_d: float = 0.777
    c_v: float = 0.312
    c_d_coronal: float = 1.614
    c_v_coronal: float = 0.195
    gravity_compensation: bool = True
    yaw_gain: float = 0.277
    hip_range: tuple[float, float] = (-0.4, 1.0)
    hip_out_range: tuple[float, float] = (-0.2, 0.407)
    ramp_time: float = 0.0
    gains: dict[str, tuple[float, float]] = field(default_factory=lambda: dict(GAIT_GAINS))

    def __post_init__(self) -> None:
        for name in ("lift_time", "first_lift_time", "max_swing_time"):
            as_positive(getattr(self, name), f"Gait.{name}")
        as_positive(self.ramp_time, "Gait.ramp_time", allow_zero=True)
        as_positive(self.yaw_gain, "Gait.yaw_gain", allow_zero=True)
        unknown = set(self.gains) - set(DEFAULT_GAINS)
        if unknown:
            raise ValueError(f"Gait.gains: unknown groups {sorted(unknown)}; the groups are "
                             f"{sorted(DEFAULT_GAINS)}")
        for group, pair in self.gains.items():
            if len(pair) != 2 or min(pair) < 0 or not all(math.isfinite(x) for x in pair):
                raise ValueError(f"Gait.gains: {group!r} needs (kp, kd) >= 0, got {pair!r}")


@dataclass(frozen=True)
class Footstep:
    """A swing foot's touch-down: ``time`` (s), the new stance ``side``, and where its ankle
    landed (y-up meters)."""

    time: float
    side: str
    position: Array
    com_velocity: Array


class SIMBICON(Controller):
    """The SIMBICON walking controller (module docstring).

    Parameters
    ----------
    character : Character
        Built by :func:`~course.physics.model.build_model` from a skeleton with two feet
        (:func:`body_parts`).
    gait : Gait, optional
        Timing, targets, feedback and gains; default ``Gait()`` (tuned for the CMU skeleton).
    speed : float, optional
        Desired forward speed (m/s) in the sagittal feedback; ``None``: SIMBICON's own,
        :math:`c_v v`.
    heading : float
        Walking direction, radians about the vertical from the neutral pose's forward
        (positive: to the left).
    stance : {"left", "right"}
        The first stance leg.
    turn_rate : float
        rad/s: the heading the controller uses turns towards :attr:`heading` at most this
        fast (a new heading all at once would twist the stance foot off the ground).
    feedback : callable, optional
        The sagittal feedback in place of the built-in law: ``feedback(theta_d0, c_d, c_v,
        com, com_velocity, stance_ankle, heading) -> theta_d`` with the COM, its velocity
        (less the speed input along the heading, if any) and the stance ankle as y-up
        meters ``(3,)`` and the heading in use (radians), as assignment a7's
        ``swing_hip_target`` (:meth:`placement` clamps what it returns). ``None``: the law
        of :meth:`placement`.

    Attributes
    ----------
    footsteps : list of Footstep
        Every touch-down of the run so far.
    stance, phase : str
        The state: the stance leg and ``"lift"`` or ``"down"``.
    phase_start : float
        When the state began (s).
    forward_axis, left_axis : ndarray, shape (3,)
        The heading in use as z-up world directions (set with each state's targets).
    """

    def __init__(self, character: Character, gait: Gait | None = None, *,
                 speed: float | None = None, heading: float = 0.0,
                 stance: str = "left", turn_rate: float = 0.4,
                 feedback: Callable[[float, float, float, Array, Array, Array, float], float]
                 | None = None) -> None:
        self.character = character
        self.feedback = feedback
        self.gait = Gait() if gait is None else gait
        if not isinstance(self.gait, Gait):
            raise ValueError(f"gait: a Gait, got {type(gait).__name__}")
        if speed is not None and not math.isfinite(float(speed)):
            raise ValueError(f"speed: a finite number of m/s or None, got {speed!r}")
        if not math.isfinite(float(heading)):
            raise ValueError(f"heading: a finite angle in radians, got {heading!r}")
        self.speed = None if speed is None else float(speed)
        self.heading = float(heading)
        self.turn_rate = as_positive(turn_rate, "turn_rate")
        if stance not in ("left", "right"):
            raise ValueError(f"stance: 'left' or 'right', got {stance!r}")
        self.first_stance = stance
        self.parts = body_parts(character)
        self.pose = neutral_pose(character)
        self.neutral = qpos_from_motion(character, self.pose)[0]

    # -- setup ------------------------------------------------------------------------------

    def reset(self, sim: Simulation) -> None:
        """The gains (implicit joint damping: the ``implicitfast`` integrator and
        ``dof_damping`` on ``sim.model``), the neutral pose's body frames, the first state."""
        if sim.character is not self.character and sim.model.nv != self.character.model.nv:
            raise ValueError("sim: a simulation of another character")
        self._mj = mj = import_mujoco()
        model = sim.model
        nv = model.nv
        self._err = np.zeros(nv)
        self._tau = np.zeros(nv)
        self._target = self.neutral.copy()
        self._kp, self._kd = self._gain_vectors(model)
        gains = {**DEFAULT_GAINS, **self.gait.gains}
        self._kp_torso, self._kd_torso = gains["torso"]
        self._kp_hip = gains["hip"][0]
        self._cached: tuple[str, str, float] | None = None
        self._ramp_from: Array | None = None
        self._heading = 0.0  # the heading in use: it turns towards self.heading
        # joint damping: MuJoCo's, implicit (as StablePD): explicit damping of the light
        # axial DOFs (armature only, 0.01 kg m^2) would need h kd / I < 2
        model.opt.integrator = mj.mjtIntegrator.mjINT_IMPLICITFAST
        model.dof_damping[6:] = self._kd[6:]
        # the neutral pose's body orientations (heading 0)
        d0 = mj.MjData(model)
        d0.qpos[:] = self.neutral
        mj.mj_kinematics(model, d0)
        self._N = d0.xmat.reshape(-1, 3, 3).copy()
        self._root = self.character.bodies[0]
        self.stance = self.first_stance
        self.phase = "lift"
        self.phase_start = 0.0
        self.footsteps: list[Footstep] = []
        self._geom_body = np.asarray(model.geom_bodyid)
        self._jacp = np.zeros((3, nv))
        self._g = np.array([0.0, 0.0, _GRAVITY])
        mass = np.asarray(model.body_mass)
        self._leg_mass = {leg.side: [(b, float(mass[b])) for b in
                                     (leg.thigh, leg.shin, leg.foot, leg.toe_body)]
                          for leg in self.parts.legs()}
        self._leg_dofs = {leg.side: np.arange(leg.hip_dof, leg.hip_dof + 12)
                          for leg in self.parts.legs()}
        for leg in self.parts.legs():  # hip, knee, ankle, toe: 12 consecutive DOFs
            if not (leg.knee_dof == leg.hip_dof + 3 and leg.toe_dof == leg.hip_dof + 9):
                raise ValueError(f"character: the {leg.side} leg's joints are not one chain "
                                 "hip, knee, ankle, toe")

    def _gain_vectors(self, model: Any) -> tuple[Array, Array]:
        gains = {**DEFAULT_GAINS, **self.gait.gains}
        kp = np.zeros(model.nv)
        kd = np.zeros(model.nv)
        for j, group in self._groups().items():
            adr = self.character.dof_address[j]
            kp[adr:adr + 3], kd[adr:adr + 3] = gains[group]
        return kp, kd

    def _groups(self) -> dict[int, str]:
        skel, parts = self.character.skeleton, self.parts
        groups: dict[int, str] = {}
        for leg in parts.legs():
            if leg.pelvis >= 0:
                groups[leg.pelvis] = "pelvis"
            groups[leg.hip], groups[leg.knee] = "hip", "knee"
            groups[leg.ankle], groups[leg.toe] = "ankle", "toe"
        spine = {k for a in parts.arms for k in _path_to_root(skel, skel.parents[a])}
        for j in range(1, skel.n_joints):
            if j in groups or self.character.bodies[j] < 0:
                continue
            path = _path_to_root(skel, j)
            arm = [a for a in parts.arms if a in path]
            if arm:
                depth = path.index(arm[0])
                groups[j] = "arm" if depth <= 1 else "hand"
            else:
                groups[j] = "spine" if j in spine else "neck"
        return groups

    # -- the state machine ------------------------------------------------------------------

    def legs(self) -> tuple[Leg, Leg]:
        """The legs as ``(stance, swing)``."""
        p = self.parts
        return (p.left, p.right) if self.stance == "left" else (p.right, p.left)

    def _touching(self, data: Any, leg: Leg) -> bool:
        n = int(data.ncon)
        if n == 0:
            return False
        b = self._geom_body[data.contact.geom[:n]]
        feet = (b == leg.foot) | (b == leg.toe_body)
        return bool(np.any((feet[:, 0] & (b[:, 1] == 0)) | (feet[:, 1] & (b[:, 0] == 0))))

    def advance(self, sim: Simulation, t: float) -> None:
        """The state machine's step at ``t``: swing-lift for its time, then swing-down until
        the swing foot touches (or ``max_swing_time``), the touch-down swapping the legs and
        recording a :class:`Footstep`. A subclass may override it (stepping's recovery step
        lifts until the foot is above its target)."""
        g = self.gait
        if self.phase == "lift":
            if t - self.phase_start >= (g.lift_time if self.footsteps else g.first_lift_time):
                self.phase = "down"
            return
        _, swing = self.legs()
        if self._touching(sim.data, swing) or t - self.phase_start >= g.max_swing_time:
            self.stance = swing.side
            self.phase = "lift"
            self.phase_start = t
            p = sim.data.xpos[swing.foot]
            self._mj.mj_subtreeVel(sim.model, sim.data)
            v = sim.data.subtree_linvel[self._root]
            self.footsteps.append(Footstep(t, swing.side, np.array([p[0], p[2], -p[1]]),
                                           np.array([v[0], v[2], -v[1]])))

    def start_step(self, stance: str, t: float) -> None:
        """Begin a step at ``t`` on the ``stance`` leg (``"left"`` or ``"right"``): swing-lift
        of the other, the state's targets recomputed on the next step."""
        if stance not in ("left", "right"):
            raise ValueError(f"stance: 'left' or 'right', got {stance!r}")
        self.stance, self.phase, self.phase_start = stance, "lift", t
        self._cached = None

    # -- torques ----------------------------------------------------------------------------

    def _state_targets(self) -> None:
        """What is constant within a state: the knee and stance-ankle targets, the heading
        frame, the torso's target orientation and the swing foot's (world)."""
        g, N, addr = self.gait, self._N, self.character.qpos_address
        stance, swing = self.legs()
        k = 0 if self.phase == "lift" else 1
        tgt = self._target
        for leg, knee in ((stance, g.stance_knee[k]), (swing, g.swing_knee[k])):
            a = addr[leg.knee]
            tgt[a:a + 4] = _quat(N[leg.thigh].T @ _axis_angle(_LEFT, knee) @ N[leg.shin])
        a = addr[stance.ankle]
        tgt[a:a + 4] = _quat(N[stance.shin].T @ _axis_angle(_LEFT, g.stance_ankle[k])
                             @ N[stance.foot])
        for leg in (stance, swing):  # the swing ankle's is set every step
            a = addr[leg.toe]
            tgt[a:a + 4] = self.neutral[a:a + 4]
        c, s = math.cos(self._heading), math.sin(self._heading)
        H = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        self._H = H
        self.forward_axis, self.left_axis = H @ _FORWARD, H @ _LEFT
        self._torso_goal = H @ _axis_angle(_LEFT, g.torso_lean) @ N[self._root]
        self._foot_goal = H @ _axis_angle(_LEFT, g.swing_ankle[k]) @ N[swing.foot]
        self._k = k
        self._cached = (self.stance, self.phase, self._heading)
        if self.phase == "lift":
            self._ramp_from = None

    def placement(self, sim: Simulation, stance: Leg, swing: Leg) -> tuple[float, float]:
        r"""SIMBICON's foot placement: the swing thigh's target angles (radians, world frame,
        from the neutral pose) forward, :math:`\theta = \theta_0 + c_d d + c_v (v - \bar v)`,
        and outward, :math:`\phi = \phi_0 + c_{d,c} d_c + c_{v,c} v_c`, each clamped to its
        range; ``d`` and ``v`` are the COM's offset from the stance ankle and its velocity
        along the heading (``d_c``, ``v_c`` towards the swing side), ``\bar v`` the speed.
        ``sim.data.subtree_linvel`` is current."""
        g, data, k = self.gait, sim.data, self._k
        com = data.subtree_com[self._root]
        vel = data.subtree_linvel[self._root]
        rel = com - data.xpos[stance.foot]
        out = self.left_axis if swing.side == "left" else -self.left_axis
        v_fwd = float(vel @ self.forward_axis) - (self.speed if self.speed is not None else 0.0)
        if self.feedback is None:
            theta = g.swing_hip[k] + g.c_d * float(rel @ self.forward_axis) + g.c_v * v_fwd
        else:  # in the course's y-up frame: (x, z, -y) of MuJoCo's z-up (x, y, z)
            lag = vel - (self.speed or 0.0) * self.forward_axis
            to_y = Y_TO_Z_MATRIX.T
            theta = float(self.feedback(
                g.swing_hip[k], g.c_d, g.c_v, to_y @ com, to_y @ lag,
                to_y @ data.xpos[stance.foot], self._heading))
        phi = g.swing_hip_out[k] + g.c_d_coronal * float(rel @ out) + g.c_v_coronal * float(
            vel @ out)
        theta = min(max(theta, g.hip_range[0]), g.hip_range[1])
        phi = min(max(phi, g.hip_out_range[0]), g.hip_out_range[1])
        return theta, phi

    def torques(self, sim: Simulation, t: float) -> Array:
        """The state machine's step, then the joint PD, the world-frame torso and swing hip,
        the stance hip and the swing leg's gravity compensation (module docstring)."""
        mj, model, data, g = self._mj, sim.model, sim.data, self.gait
        self.advance(sim, t)
        turn = math.remainder(self.heading - self._heading, math.tau)
        if turn != 0.0:
            limit = self.turn_rate * sim.h
            self._heading += min(max(turn, -limit), limit)
        if self._cached != (self.stance, self.phase, self._heading):
            self._state_targets()
        stance, swing = self.legs()
        H, fwd, N = self._H, self.forward_axis, self._N
        xmat = data.xmat
        mj.mj_subtreeVel(model, data)
        theta, phi = self.placement(sim, stance, swing)
        # joint PD (the damping is MuJoCo's, implicit)
        tgt = self._target
        a = self.character.qpos_address[swing.ankle]
        tgt[a:a + 4] = _quat(xmat[swing.shin].reshape(3, 3).T @ self._foot_goal)
        mj.mj_differentiatePos(model, self._err, 1.0, data.qpos, tgt)
        tau = self._tau
        np.multiply(self._kp, self._err, out=tau)
        # the torso (the root) and the swing thigh in the world frame
        R_root = xmat[self._root].reshape(3, 3)
        tau_torso = self._kp_torso * _log(self._torso_goal @ R_root.T) - (
            self._kd_torso * data.cvel[self._root, :3])
        tau_torso[2] *= g.yaw_gain
        R_th = xmat[swing.thigh].reshape(3, 3)
        R_d = H @ _axis_angle(_LEFT, -theta) @ _axis_angle(fwd if swing.side == "left" else
                                                            -fwd, phi) @ N[swing.thigh]
        if g.ramp_time > 0.0:  # from the thigh's orientation at the state's start
            if self._ramp_from is None:
                self._ramp_from = R_th.copy()
            share = min(1.0, (t - self.phase_start) / g.ramp_time)
            if share < 1.0:
                R0 = self._ramp_from
                R_d = _axis_angle_vector(share * _log(R_d @ R0.T)) @ R0
        tau_swing = self._kp_hip * _log(R_d @ R_th.T)
        tau_swing[2] *= g.yaw_gain
        tau_stance = -tau_torso - tau_swing
        self.last = (theta, phi)
        for leg, tw in ((swing, tau_swing), (stance, tau_stance)):
            h = leg.hip_dof
            tau[h:h + 3] = xmat[leg.thigh].reshape(3, 3).T @ tw
            if leg.pelvis_dof >= 0:  # pass it through the pelvis bone to the root
                p = leg.pelvis_dof
                tau[p:p + 3] += xmat[leg.pelvis_body].reshape(3, 3).T @ tw
        if g.gravity_compensation:
            dofs = self._leg_dofs[swing.side]
            jac = self._jacp
            for b, m in self._leg_mass[swing.side]:
                mj.mj_jacBodyCom(model, data, jac, None, b)
                tau[dofs] += jac[:, dofs].T @ (m * self._g)
        return tau


# -- runs ---------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class WalkResult:
    """What :func:`walk` returns.

    Attributes
    ----------
    motion : Motion
        The simulated motion, one frame per control frame (y-up, skeleton units).
    fell : bool
        Whether the COM went below ``fall_fraction`` of its initial height.
    fall_time : float or None
    footsteps : list of Footstep
        Every touch-down (time, new stance side, ankle position and COM velocity, y-up).
    com : ndarray, shape (F, 3)
        COM per frame, y-up meters.
    torques : ndarray, shape (F, nv)
        The applied generalized forces (``qfrc_applied``) of each frame's last step, the
        root's six included (always zero: no hand of God).
    sim_time, wall_time : float
    """

    motion: Motion
    fell: bool
    fall_time: float | None
    footsteps: list[Footstep] = field(repr=False)
    com: Array = field(repr=False)
    torques: Array = field(repr=False)
    sim_time: float
    wall_time: float

    @property
    def strides(self) -> int:
        """Whole strides walked (a stride is two steps)."""
        return len(self.footsteps) // 2

    @property
    def distance(self) -> float:
        """Horizontal distance (m) the COM travelled from the first frame to the last."""
        d = self.com[-1] - self.com[0]
        return float(math.hypot(d[0], d[2]))

    @property
    def rate(self) -> float:
        """Simulated seconds per wall-clock second (the real-time factor)."""
        return self.sim_time / self.wall_time if self.wall_time > 0 else math.inf


def walk(character: Character, *, duration: float = 20.0, gait: Gait | None = None,
         speed: float | None = None, heading: float = 0.0, turn_rate: float = 0.4,
         push: Push | None = None, h: float = 1.0 / 600.0, frame_time: float = 1.0 / 60.0,
         torque_limit: float = 400.0,
         fall_fraction: float = 0.6, stop_when_fallen: bool = True,
         on_frame: Callable[[int, Motion], None] | None = None) -> WalkResult:
    """Simulate ``character`` walking from :func:`neutral_pose` at rest under
    :class:`SIMBICON`.

    Parameters
    ----------
    character : Character
    duration : float
        Simulated seconds.
    gait, speed, heading, turn_rate
        As :class:`SIMBICON`.
    push : Push, optional
        A shove during the walk.
    h, frame_time : float
        The step and the control frame (``h`` must divide it).
    torque_limit : float
        Per-component torque limit (N m).
    fall_fraction : float
        Fallen when the COM is below this fraction of its initial height.
    stop_when_fallen : bool
        End the run at the first fallen frame.
    on_frame : callable, optional
        ``on_frame(i, frame)`` after each frame, as :class:`~course.physics.simulation.
        Simulation`.

    Returns
    -------
    WalkResult
    """
    duration = as_positive(duration, "duration")
    frame_time = as_positive(frame_time, "frame_time")
    fall_fraction = as_positive(fall_fraction, "fall_fraction")
    controller = SIMBICON(character, gait, speed=speed, heading=heading, turn_rate=turn_rate)
    n = max(2, round(duration / frame_time) + 1)
    sim = Simulation(character, controller.neutral, frame_time=frame_time, h=h,
                     torque_limit=torque_limit, push=push,
                     fall=Fall("com", fraction=fall_fraction, stop=stop_when_fallen),
                     on_frame=on_frame, name="walk")
    record = sim.run(controller, n)
    return WalkResult(
        motion=motion_from_qpos(character, record.qpos, frame_time, name="walk"),
        fell=record.fall_time is not None, fall_time=record.fall_time,
        footsteps=list(controller.footsteps), com=record.com @ Y_TO_Z_MATRIX,
        torques=record.torques, sim_time=record.sim_time, wall_time=record.wall_time)


def largest_push(character: Character, *, direction: Sequence[float] | Array = (0.0, 0.0, 1.0),
                 start: float | Sequence[float] = 5.0, duration: float = 0.1,
                 settle: float = 5.0, joint: str | None = None, tol: float = 5.0,
                 max_force: float = 1e4, **walk_options: Any) -> float:
    """The largest push (N) the walker survives, by bisection over the force.

    The push acts on ``joint`` (default the root) along ``direction`` (y-up, normalized; +z
    is the walking direction at heading 0, +x the character's left) for ``duration`` s from
    ``start`` (5 s: some 17 steps into the walk); survived when :func:`walk` has not fallen
    ``settle`` s after it ends. ``start`` may be several times (e.g. eight spread over one
    stride): a force is then survived only if it is at every one of them. The search is
    :func:`~course.physics.balance.bisect_push` (doubling from 100 N, then bisection to
    ``tol`` N); the survived end is returned (its impulse is that times ``duration``).

    Deterministic on one build, but a walking push is a chaotic experiment: survival is not
    monotonic in the force (a push at one instant of the stride can be survived at 800 N and
    fall at 500 N), so one ``start`` can return an isolated survivor; several starts give
    the figure the walker holds whenever in its stride the push comes.
    """
    d = push_direction(direction)
    as_positive(duration, "duration")
    as_positive(settle, "settle")
    starts = [float(start)] if isinstance(start, (int, float)) else [float(s) for s in start]
    if not starts or not all(math.isfinite(s) and s >= 0.0 for s in starts):
        raise ValueError(f"start: one time >= 0 s or several, got {start!r}")
    name = character.skeleton.names[0] if joint is None else joint

    def survives(force: Array) -> bool:
        return all(not walk(character, duration=s + duration + settle,
                            push=Push(name, force, s, duration), stop_when_fallen=True,
                            **walk_options).fell for s in starts)

    return bisect_push(survives, d, tol=tol, max_force=max_force)


__all__ = [
    "DEFAULT_GAINS",
    "GAIT_GAINS",
    "SIMBICON",
    "Body",
    "Footstep",
    "Gait",
    "Leg",
    "WalkResult",
    "body_parts",
    "largest_push",
    "neutral_pose",
    "walk",
]
