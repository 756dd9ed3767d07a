"""A simulated character 仿真角色 on MuJoCo, built from any :class:`~course.skeleton.Skeleton`.

MuJoCo (``pip install 'course-kinematics[physics]'``) is imported only when a function here
runs, so ``import course`` and ``import course.physics`` stay light.

Model (after dm_control's CMU humanoid, but generated from the skeleton, nothing downloaded):

* one MuJoCo body per skeleton joint that is not a BVH End Site; End Sites have no body and
  no joint (their bone is a capsule of the parent's body);
* per body a sphere of ``radius`` at the joint and a capsule per bone to each child, so every
  body has mass ``volume * density`` (positive);
* the root has a free joint (6 DOF, never actuated: the character can fall), every other
  body a ball joint (3 DOF). Ball joints rather than three hinges: a ball joint's ``qpos`` is
  the Motion's local quaternion itself (round trip exact, no Euler order, no gimbal lock) and
  its ``qvel`` and torque are rotation vectors in the joint's frame, which is what the PD
  law below needs;
* a ground plane at height ``-radius`` (so a foot capsule whose axis is at the clip's
  ground, height 0, touches it) colliding with every body geom (feet included); body geoms do
  not collide with each other.

Axes: the course is y-up, MuJoCo z-up. A y-up point ``p`` (in skeleton units) is the z-up
point ``C p * scale`` with ``C`` the rotation of +90 degrees about x, ``(x, y, z) -> (x, -z, y)``,
quaternion ``c = (cos 45deg, sin 45deg, 0, 0)``. Rotations are conjugated,
``q_z = c q_y c^-1`` (local and global alike), because every body frame is at rest aligned
with the world in both conventions.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..motion import Motion, is_end_site
from ..skeleton import Skeleton

Array = NDArray[np.float64]

#: Meters per unit of the CMU BVH clips (dm_control's ``CMU_SCALE`` for the CMU ASF/AMC).
CMU_SCALE = 0.056444
#: Default ball-joint cone (radians) of :func:`build_model`: 135 degrees, see its docstring.
JOINT_LIMIT = 0.75 * math.pi
_S = math.sqrt(0.5)
#: y-up -> z-up, as a quaternion (w, x, y, z): +90 degrees about x.
Y_TO_Z = np.array([_S, _S, 0.0, 0.0])
#: y-up -> z-up, as a matrix: (x, y, z) -> (x, -z, y).
Y_TO_Z_MATRIX = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


def import_mujoco() -> Any:
    """The ``mujoco`` module, imported on first use (``course.physics`` loads without it);
    an ImportError that says how to install it."""
    try:
        import mujoco  # type: ignore[import-untyped]  # (no stubs shipped)
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise ImportError(
            "course.physics.character needs MuJoCo: pip install 'course-kinematics[physics]' "
            "(or pip install 'mujoco>=3.1')"
        ) from exc
    return mujoco


def _qmul(a: Array, b: Array) -> Array:
    """Hamilton product of (..., 4) quaternions, scalar first."""
    aw, ax, ay, az = np.moveaxis(a, -1, 0)
    bw, bx, by, bz = np.moveaxis(b, -1, 0)
    out: Array = np.stack(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ],
        axis=-1,
    )
    return out


def _conj(q: Array) -> Array:
    out: Array = q * np.array([1.0, -1.0, -1.0, -1.0])
    return out


def y_up_to_z_up_rotations(q: Array) -> Array:
    """``c q c^-1``: (..., 4) y-up quaternions as z-up quaternions."""
    c = np.broadcast_to(Y_TO_Z, q.shape)
    return _qmul(_qmul(c, q), _conj(c))


def z_up_to_y_up_rotations(q: Array) -> Array:
    """``c^-1 q c``: the inverse of :func:`y_up_to_z_up_rotations`."""
    c = np.broadcast_to(Y_TO_Z, q.shape)
    return _qmul(_qmul(_conj(c), q), c)


def guess_scale(skeleton: Skeleton) -> float:
    """Meters per skeleton unit, guessed from the rest pose's height ``H`` (in units).

    ``H < 3``: meters (1.0); ``H < 60``: CMU units (:data:`CMU_SCALE`); otherwise
    centimeters (0.01).
    """
    rest = skeleton.rest_positions()
    height = float(np.ptp(rest[:, 1])) if len(rest) > 1 else 0.0
    if height < 3.0:
        return 1.0
    return CMU_SCALE if height < 60.0 else 0.01


@dataclass(frozen=True, eq=False)
class Character:
    """A compiled MuJoCo character and how its joints map to the skeleton's.

    Attributes
    ----------
    model : mujoco.MjModel
        The compiled model (z-up, meters). :func:`track` works on its own copy.
    xml : str
        The MJCF it was compiled from.
    skeleton : Skeleton
        The skeleton it was built from (``J`` joints, End Sites included).
    scale : float
        Meters per skeleton unit.
    bodies : tuple of int, length J
        MuJoCo body id of each skeleton joint; -1 for End Sites (no body).
    qpos_address : tuple of int, length J
        Start of the joint's ``qpos`` slice (7 for the free root: position then quaternion;
        4 for a ball joint: its quaternion); -1 for End Sites.
    dof_address : tuple of int, length J
        Start of the joint's ``qvel`` slice (6 for the root, 3 for a ball joint); -1 for End
        Sites.
    """

    model: Any
    xml: str
    skeleton: Skeleton
    scale: float
    bodies: tuple[int, ...]
    qpos_address: tuple[int, ...]
    dof_address: tuple[int, ...]

    @property
    def simulated_joints(self) -> tuple[int, ...]:
        """Skeleton indices that have a MuJoCo body and joint (all but the End Sites)."""
        return tuple(j for j, b in enumerate(self.bodies) if b >= 0)

    @property
    def total_mass(self) -> float:
        """Kilograms."""
        return float(np.sum(self.model.body_mass))

    def fresh_model(self) -> Any:
        """A new ``MjModel`` compiled from :attr:`xml` (safe to modify)."""
        return import_mujoco().MjModel.from_xml_string(self.xml)


def _fmt(v: Array) -> str:
    return " ".join(f"{x:.9g}" for x in v)


def build_model(
    skeleton: Skeleton,
    *,
    density: float = 1000.0,
    radius: float = 0.04,
    scale: float | None = None,
    friction: float = 1.0,
    armature: float = 0.01,
    timestep: float = 1.0 / 600.0,
    joint_limits: bool | float = True,
) -> Character:
    """Build and compile a MuJoCo character from ``skeleton``.

    Parameters
    ----------
    skeleton : Skeleton
        ``J`` joints, y-up; End Sites (:func:`course.motion.is_end_site`) get no body.
    density : float
        kg/m^3 of every geom (water: 1000); masses are volume times density.
    radius : float
        Capsule and joint-sphere radius in meters.
    scale : float, optional
        Meters per skeleton unit; default :func:`guess_scale`.
    friction : float
        Sliding friction of the ground.
    armature : float
        Rotor inertia (kg m^2) added to every ball joint's DOFs, as dm_control's humanoid
        does: it keeps the light hand and finger bodies from forcing tiny steps.
    timestep : float
        The model's default step in seconds (:func:`track` sets its own).
    joint_limits : bool or float
        A cone limit on every ball joint: its rotation from the rest pose (the angle of its
        local quaternion) stays below the given angle in radians (MuJoCo ``limited="true"
        range="0 angle"``, a constraint the solver enforces, so a limit can be exceeded
        slightly while it pushes back). ``True`` is :data:`JOINT_LIMIT`, 135 degrees: the
        CMU walk's largest joint rotation is 97 degrees (the arms, lowered from the T-pose
        rest), so the limit never binds while a clip is tracked, and 135 degrees is about a
        knee's anatomical flexion, so a push cannot fold a joint through the body. The limit
        is stiffened (``solreflimit="0.005 1"``, a 5 ms time constant instead of MuJoCo's
        20 ms): a 1500 N push on the sample's head then overshoots a 30 degree cone by
        3.4 degrees instead of 12.7. ``False``: no limits.

    Returns
    -------
    Character
    """
    if density <= 0 or radius <= 0:
        raise ValueError("density and radius must be positive")
    mujoco = import_mujoco()
    s = guess_scale(skeleton) if scale is None else float(scale)
    offsets = skeleton.offsets * s @ Y_TO_Z_MATRIX.T  # (J, 3), z-up meters
    end = [is_end_site(skeleton, j) for j in range(skeleton.n_joints)]
    if joint_limits is True:
        limit: float | None = JOINT_LIMIT
    elif joint_limits is False:
        limit = None
    else:
        limit = float(joint_limits)
        if not 0.0 < limit <= math.pi:
            raise ValueError(f"joint_limits: {limit!r} rad is not in (0, pi]")
    rest_min = float(np.min((skeleton.rest_positions() * s @ Y_TO_Z_MATRIX.T)[:, 2]))
    lines: list[str] = []

    def body(j: int, indent: str) -> None:
        name = skeleton.names[j]
        pos = np.zeros(3) if j == 0 else offsets[j]
        if j == 0:
            pos = np.array([0.0, 0.0, -rest_min])
        lines.append(f'{indent}<body name="{name}" pos="{_fmt(pos)}">')
        kind = "free" if j == 0 else "ball"
        extra = "" if j == 0 else f' armature="{armature:.9g}"'
        if j > 0 and limit is not None:
            extra += f' limited="true" range="0 {limit:.9g}" solreflimit="0.005 1"'
        lines.append(f'{indent}  <joint name="{name}" type="{kind}"{extra}/>')
        lines.append(f'{indent}  <geom name="{name}" type="sphere" size="{radius:.9g}"/>')
        for c in skeleton.children(j):
            if np.linalg.norm(offsets[c]) > 1e-6:
                lines.append(
                    f'{indent}  <geom name="{skeleton.names[c]}_bone" type="capsule" '
                    f'size="{radius:.9g}" fromto="0 0 0 {_fmt(offsets[c])}"/>'
                )
        for c in skeleton.children(j):
            if not end[c]:
                body(c, indent + "  ")
        lines.append(f"{indent}</body>")

    body(0, "    ")
    xml = "\n".join(
        [
            f'<mujoco model="{skeleton.names[0]}_character">',
            '  <compiler angle="radian"/>',
            f'  <option timestep="{timestep:.9g}" gravity="0 0 -9.81"/>',
            "  <default>",
            f'    <geom density="{density:.9g}" contype="2" conaffinity="1" '
            f'friction="{friction:.9g} 0.005 0.0001"/>',
            "  </default>",
            "  <worldbody>",
            f'    <geom name="floor" type="plane" size="0 0 1" pos="0 0 {-radius:.9g}" '
            'contype="1" conaffinity="2"/>',
            *lines,
            "  </worldbody>",
            "</mujoco>",
        ]
    )
    model = mujoco.MjModel.from_xml_string(xml)
    bodies, qadr, dadr = [], [], []
    for j in range(skeleton.n_joints):
        if end[j]:
            bodies.append(-1)
            qadr.append(-1)
            dadr.append(-1)
            continue
        b = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, skeleton.names[j])
        jid = int(model.body_jntadr[b])
        bodies.append(int(b))
        qadr.append(int(model.jnt_qposadr[jid]))
        dadr.append(int(model.jnt_dofadr[jid]))
    return Character(model, xml, skeleton, s, tuple(bodies), tuple(qadr), tuple(dadr))


# -- state conversion ------------------------------------------------------------------------


def qpos_from_motion(character: Character, motion: Motion) -> Array:
    """MuJoCo ``qpos`` of every frame, shape (F, nq).

    The root's position is converted to z-up meters, every local rotation conjugated to z-up
    (module docstring). ``motion.translations`` (animated bones) are not simulated.
    """
    qpos = np.zeros((motion.n_frames, character.model.nq))
    rot = y_up_to_z_up_rotations(motion.local_rotations)
    qpos_root = motion.root_positions * character.scale @ Y_TO_Z_MATRIX.T
    for j, a in enumerate(character.qpos_address):
        if a < 0:
            continue
        if j == 0:
            qpos[:, 0:3] = qpos_root
            qpos[:, 3:7] = rot[:, 0]
        else:
            qpos[:, a : a + 4] = rot[:, j]
    return qpos


def qvel_from_motion(character: Character, motion: Motion) -> Array:
    """MuJoCo ``qvel`` of every frame by finite differences, shape (F, nv).

    Frame ``i`` gets ``(qpos[i+1] ⊖ qpos[i]) / frame_time`` (the last frame repeats the one
    before), computed by ``mj_differentiatePos`` (angular velocities in the joint's frame).
    """
    mujoco = import_mujoco()
    qpos = qpos_from_motion(character, motion)
    qvel = np.zeros((motion.n_frames, character.model.nv))
    for i in range(motion.n_frames - 1):
        mujoco.mj_differentiatePos(
            character.model, qvel[i], motion.frame_time, qpos[i], qpos[i + 1]
        )
    if motion.n_frames > 1:
        qvel[-1] = qvel[-2]
    return qvel


def set_state(character: Character, data: Any, motion: Motion, frame: int = 0) -> None:
    """Set ``data.qpos``/``data.qvel`` from frame ``frame`` of ``motion`` and run mj_forward."""
    mujoco = import_mujoco()
    clip = motion[max(0, frame - 1) : frame + 2] if motion.n_frames > 1 else motion
    k = min(frame, 1) if motion.n_frames > 1 else 0
    data.qpos[:] = qpos_from_motion(character, clip)[k]
    data.qvel[:] = qvel_from_motion(character, clip)[k]
    mujoco.mj_forward(character.model, data)


def motion_from_qpos(
    character: Character, qpos: Array, frame_time: float, *, name: str = "simulated"
) -> Motion:
    """The simulated states ``qpos`` (F, nq) as a :class:`~course.motion.Motion` (y-up, skeleton
    units); End Sites get the identity rotation (they are leaves: FK positions unaffected)."""
    qpos = np.atleast_2d(np.asarray(qpos, dtype=float))
    n = qpos.shape[0]
    local = np.zeros((n, character.skeleton.n_joints, 4))
    local[..., 0] = 1.0
    for j, a in enumerate(character.qpos_address):
        if a < 0:
            continue
        q = qpos[:, 3:7] if j == 0 else qpos[:, a : a + 4]
        local[:, j] = q / np.linalg.norm(q, axis=-1, keepdims=True)
    local = z_up_to_y_up_rotations(local)
    root = qpos[:, 0:3] @ Y_TO_Z_MATRIX / character.scale  # C^-1 = C^T
    return Motion(character.skeleton, local, root, frame_time, name=name)


# -- pushes ---------------------------------------------------------------------------------


@dataclass(frozen=True)
class Push:
    """An external force 外力 on one body for a while: a shove.

    Attributes
    ----------
    joint : str
        Name of the skeleton joint whose body is pushed (the force acts at that body's centre
        of mass), e.g. the root or a spine joint. Checked against a character by
        :meth:`body`.
    force : array_like, shape (3,)
        Newtons, y-up world frame; stored as a float ndarray.
    start : float
        Seconds after the start of the simulation.
    duration : float
        Seconds; positive.

    The force is applied on every step whose midpoint ``(k + 1/2) h`` lies in
    ``[start, start + duration)``, through MuJoCo's ``xfrc_applied``.
    """

    joint: str
    force: tuple[float, float, float] | Array
    start: float
    duration: float

    def __post_init__(self) -> None:
        if not isinstance(self.joint, str):
            raise TypeError(f"Push.joint: a joint name (str), got {type(self.joint).__name__}")
        force = np.array(self.force, dtype=float)
        if force.shape != (3,) or not np.all(np.isfinite(force)):
            raise ValueError(f"Push.force: 3 finite newtons (y-up), got {self.force!r}")
        if not (math.isfinite(self.start) and self.start >= 0.0):
            raise ValueError(f"Push.start: a time >= 0 s, got {self.start!r}")
        if not (math.isfinite(self.duration) and self.duration > 0.0):
            raise ValueError(f"Push.duration: a positive time in s, got {self.duration!r}")
        force.flags.writeable = False
        object.__setattr__(self, "force", force)
        object.__setattr__(self, "start", float(self.start))
        object.__setattr__(self, "duration", float(self.duration))

    @property
    def impulse(self) -> float:
        """``|force| * duration`` in N s."""
        return float(np.linalg.norm(self.force)) * self.duration

    def body(self, character: Character) -> int:
        """MuJoCo body id of :attr:`joint` in ``character``; ValueError if it has none."""
        names = character.skeleton.names
        if self.joint not in names:
            some = ", ".join(repr(n) for n in names[:6])
            raise ValueError(
                f"Push.joint: {self.joint!r} is not a joint of the skeleton "
                f"({len(names)} joints: {some}, ...)"
            )
        b = character.bodies[names.index(self.joint)]
        if b < 0:
            raise ValueError(
                f"Push.joint: {self.joint!r} is an End Site, it has no body; push its parent"
            )
        return b

    def active(self, t: float, h: float) -> bool:
        """Whether the step ``[t, t + h)`` pushes (its midpoint is in the push's interval)."""
        mid = t + 0.5 * h
        return self.start <= mid < self.start + self.duration

    def force_z_up(self) -> Array:
        """The force in MuJoCo's z-up world frame (N)."""
        out: Array = Y_TO_Z_MATRIX @ np.asarray(self.force)
        return out


# -- PD tracking -----------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class TrackingResult:
    """What :func:`track` returns.

    Attributes
    ----------
    motion : Motion
        The simulated motion, one frame per clip frame (frame 0 is the initial state).
    error_cm : ndarray, shape (F,)
        Per frame, mean over joints of the distance between simulated and clip joint
        positions (FK), in centimeters.
    fell : bool
        Whether the root went below ``fall_height``.
    fall_time : float or None
        Simulated seconds at the first such step.
    sim_time : float
        Simulated seconds.
    wall_time : float
        Wall-clock seconds of the simulation loop.
    h : float
        The step actually used (``frame_time / steps_per_frame``).
    unstable : bool
        Whether MuJoCo reported a numerical blow-up (bad qacc) or the state went non-finite.
    root_height : ndarray, shape (F,)
        Simulated root height in meters per frame.
    """

    motion: Motion
    error_cm: Array
    fell: bool
    fall_time: float | None
    sim_time: float
    wall_time: float
    h: float
    unstable: bool
    root_height: Array = field(repr=False)

    @property
    def rate(self) -> float:
        """Simulated seconds per wall-clock second."""
        return self.sim_time / self.wall_time if self.wall_time > 0 else math.inf


def tracking_error_cm(character: Character, simulated: Motion, clip: Motion) -> Array:
    """Per frame, the mean joint-position distance (FK) in centimeters, shape (F,)."""
    n = min(simulated.n_frames, clip.n_frames)
    p_sim, _ = simulated[:n].forward_kinematics()
    p_ref, _ = clip[:n].forward_kinematics()
    dist = np.linalg.norm(p_sim - p_ref, axis=-1) * character.scale * 100.0
    return np.asarray(dist.mean(axis=1), dtype=float)


def track(
    character: Character,
    motion: Motion,
    *,
    kp: float,
    kd: float,
    torque_limit: float = math.inf,
    h: float = 1.0 / 600.0,
    n_frames: int | None = None,
    stable_pd: bool = False,
    hold_root: bool = False,
    fall_height: float | None = None,
    gravity: bool = True,
    torques: bool = True,
    push: Push | None = None,
    on_frame: Callable[[int, Motion], None] | None = None,
) -> TrackingResult:
    r"""Simulate ``character`` tracking ``motion`` with joint PD control.

    Per ball joint :math:`\tau = k_p\,(\bar q \ominus q) - k_d\,\dot q`, where
    :math:`\bar q \ominus q = \log(q^{-1}\bar q)` is the rotation vector from the current to
    the target local rotation in the joint's own frame (``mj_differentiatePos``), the target
    being the clip's *next* frame (zero-order hold between frames); each component is clipped
    to ``±torque_limit`` (N m) and applied through ``data.qfrc_applied``. The root is never
    actuated.

    Parameters
    ----------
    character : Character
    motion : Motion
        The clip to follow (same skeleton); frame 0 is the initial state.
    kp, kd : float
        Gains, N m/rad and N m s/rad, the same for every joint.
    torque_limit : float
        Per-component torque limit.
    h : float
        Requested step; rounded so a whole number of steps fits a frame (see ``result.h``).
    n_frames : int, optional
        Frames to simulate (default: the whole clip).
    stable_pd : bool
        Stable PD (Tan, Liu and Turk 2011): :math:`\tau = k_p(\bar q \ominus (q + h\dot q))
        - k_d(\dot q + h\ddot q)`. The position term is evaluated at ``q + h q̇``
        (``mj_integratePos``); the damping term at the next velocity is MuJoCo's own
        implicit joint damping (``dof_damping = kd`` with the ``implicitfast`` integrator),
        which is exactly ``-kd q̇_{n+1}``, so no mass-matrix solve is written here.
    hold_root : bool
        "Hand of God": before each step the root's position and velocity are set to the
        clip's, so only the joints are simulated.
    fall_height : float, optional
        Root height (m) below which the character has fallen; default half the initial.
    gravity, torques : bool
        Switch gravity or the PD torques off (``torques=False``: a passive ragdoll).
    push : Push, optional
        An external force during the run (its time counts from frame 0).
    on_frame : callable, optional
        ``on_frame(i, frame)`` is called after each simulated clip frame ``i = 1 .. F-1``
        with that frame as a 1-frame :class:`~course.motion.Motion` (equal to
        ``result.motion[i]``), so a view can play while the simulation runs. Its time is
        counted in ``wall_time``.

    Returns
    -------
    TrackingResult
    """
    mujoco = import_mujoco()
    if motion.skeleton.n_joints != character.skeleton.n_joints:
        raise ValueError("motion: its skeleton does not match the character's")
    n = motion.n_frames if n_frames is None else min(int(n_frames), motion.n_frames)
    steps = max(1, round(motion.frame_time / h))
    h_used = motion.frame_time / steps
    model = character.fresh_model()
    model.opt.timestep = h_used
    if not gravity:
        model.opt.gravity[:] = 0.0
    actuated = np.ones(model.nv, dtype=bool)
    actuated[:6] = False  # the free root
    if stable_pd:
        model.opt.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
        model.dof_damping[actuated] = kd
    data = mujoco.MjData(model)
    clip = motion[:n]
    qref = qpos_from_motion(character, clip)
    vref = qvel_from_motion(character, clip)
    data.qpos[:] = qref[0]
    data.qvel[:] = vref[0]
    mujoco.mj_forward(model, data)
    threshold = 0.5 * float(data.qpos[2]) if fall_height is None else fall_height
    out = np.empty((n, model.nq))
    out[0] = data.qpos
    err = np.zeros(model.nv)
    q_pred = np.zeros(model.nq)
    tau = np.zeros(model.nv)
    fall_time: float | None = None
    unstable = False
    kd_explicit = 0.0 if stable_pd else kd
    push_body = push.body(character) if push is not None else -1
    push_force = push.force_z_up() if push is not None else np.zeros(3)
    start = time.perf_counter()
    for i in range(1, n):
        target = qref[i]
        for k in range(steps):
            if push is not None:
                t = ((i - 1) * steps + k) * h_used
                data.xfrc_applied[push_body, :3] = push_force if push.active(t, h_used) else 0.0
            if hold_root:
                alpha = (k + 1) / steps
                data.qpos[:3] = (1 - alpha) * qref[i - 1, :3] + alpha * target[:3]
                data.qpos[3:7] = target[3:7]
                data.qvel[:6] = vref[i - 1, :6]
            if torques:
                if stable_pd:
                    q_pred[:] = data.qpos
                    mujoco.mj_integratePos(model, q_pred, data.qvel, h_used)
                    mujoco.mj_differentiatePos(model, err, 1.0, q_pred, target)
                else:
                    mujoco.mj_differentiatePos(model, err, 1.0, data.qpos, target)
                np.multiply(err, kp, out=tau)
                tau -= kd_explicit * data.qvel
                tau[~actuated] = 0.0
                np.clip(tau, -torque_limit, torque_limit, out=tau)
                data.qfrc_applied[:] = tau
            mujoco.mj_step(model, data)
        if hold_root:  # the step moved the root by h v: put it back on the clip
            data.qpos[:7] = target[:7]
        if data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number > 0 or not np.all(
            np.isfinite(data.qpos)
        ):
            unstable = True
        if fall_time is None and data.qpos[2] < threshold:
            fall_time = i * motion.frame_time
        out[i] = data.qpos
        if on_frame is not None:
            on_frame(i, motion_from_qpos(character, out[i : i + 1], motion.frame_time,
                                         name=f"{motion.name} (sim)"))
    wall = time.perf_counter() - start
    simulated = motion_from_qpos(character, out, motion.frame_time, name=f"{motion.name} (sim)")
    return TrackingResult(
        motion=simulated,
        error_cm=tracking_error_cm(character, simulated, clip),
        fell=fall_time is not None,
        fall_time=fall_time,
        sim_time=(n - 1) * motion.frame_time,
        wall_time=wall,
        h=h_used,
        unstable=unstable,
        root_height=out[:, 2].copy(),
    )


def effective_inertia(character: Character, motion: Motion | None = None) -> Array:
    """Diagonal of the joint-space mass matrix for the actuated DOFs (kg m^2), shape (nv-6,),
    at frame 0 of ``motion`` (or the rest pose). ``sqrt(kp / I)`` is a joint's PD frequency."""
    mujoco = import_mujoco()
    model = character.model
    data = mujoco.MjData(model)
    if motion is not None:
        data.qpos[:] = qpos_from_motion(character, motion[:1])[0]
    else:
        data.qpos[3] = 1.0
        for a in character.qpos_address[1:]:
            if a >= 0:
                data.qpos[a] = 1.0
    mujoco.mj_forward(model, data)
    full = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, full)
    return np.asarray(np.diag(full)[6:], dtype=float)


__all__ = [
    "CMU_SCALE",
    "JOINT_LIMIT",
    "Character",
    "Push",
    "TrackingResult",
    "build_model",
    "effective_inertia",
    "guess_scale",
    "motion_from_qpos",
    "qpos_from_motion",
    "qvel_from_motion",
    "set_state",
    "track",
    "tracking_error_cm",
    "y_up_to_z_up_rotations",
    "z_up_to_y_up_rotations",
]
