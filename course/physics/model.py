"""The simulated character's model 仿真角色模型 on MuJoCo, built from any
:class:`~course.skeleton.Skeleton`.

MuJoCo (``pip install 'course-kinematics[physics]'``) is imported only when a function here
runs, so ``import course`` and ``import course.physics`` stay light. This module is the bottom
of the MuJoCo wing: :mod:`course.physics.simulation` steps what is built here,
:mod:`course.physics.controllers` drives it, and :mod:`course.physics.character` (which
re-exports every name here) and :mod:`course.physics.balance` compose them.

Model (after dm_control's CMU humanoid, but generated from the skeleton, nothing downloaded):

* one MuJoCo body per skeleton joint that is not a BVH End Site; End Sites have no body and
  no joint (their bone is a capsule of the parent's body);
* per body a sphere of ``radius`` at the joint and a capsule per bone to each child, so every
  body has mass ``volume * density`` (positive);
* the root has a free joint (6 DOF, never actuated: the character can fall), every other
  body a ball joint (3 DOF). Ball joints rather than three hinges: a ball joint's ``qpos`` is
  the Motion's local quaternion itself (round trip exact, no Euler order, no gimbal lock) and
  its ``qvel`` and torque are rotation vectors in the joint's frame, which is what the PD
  law (:class:`~course.physics.controllers.PD`) needs;
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
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._typing import Array
from .._validate import as_positive
from ..motion import Motion, is_end_site
from ..rotations._kernels import quat_conjugate, quat_mul
from ..skeleton import Skeleton

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


def y_up_to_z_up_rotations(q: Array) -> Array:
    """``c q c^-1``: (..., 4) y-up quaternions as z-up quaternions."""
    c = np.broadcast_to(Y_TO_Z, q.shape)
    return quat_mul(quat_mul(c, q), quat_conjugate(c))


def z_up_to_y_up_rotations(q: Array) -> Array:
    """``c^-1 q c``: the inverse of :func:`y_up_to_z_up_rotations`."""
    c = np.broadcast_to(Y_TO_Z, q.shape)
    return quat_mul(quat_mul(quat_conjugate(c), q), c)


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
        The compiled model (z-up, meters). A :class:`~course.physics.simulation.Simulation`
        works on its own copy (:meth:`fresh_model`).
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
        The model's default step in seconds (:func:`~course.physics.character.track` sets
        its own).
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
    density = as_positive(density, "density")
    radius = as_positive(radius, "radius")
    friction = as_positive(friction, "friction", allow_zero=True)
    armature = as_positive(armature, "armature", allow_zero=True)
    timestep = as_positive(timestep, "timestep")
    mujoco = import_mujoco()
    s = guess_scale(skeleton) if scale is None else as_positive(scale, "scale")
    xml = _mjcf(skeleton, s, density=density, radius=radius, friction=friction,
                armature=armature, timestep=timestep, limit=_cone(joint_limits))
    model = mujoco.MjModel.from_xml_string(xml)
    bodies, qadr, dadr = [], [], []
    for j in range(skeleton.n_joints):
        if is_end_site(skeleton, j):
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


def _cone(joint_limits: bool | float) -> float | None:
    """:func:`build_model`'s ``joint_limits`` as a cone angle in radians, or None (no limit)."""
    if joint_limits is True:
        return JOINT_LIMIT
    if joint_limits is False:
        return None
    limit = float(joint_limits)
    if not 0.0 < limit <= math.pi:
        raise ValueError(f"joint_limits: {limit!r} rad is not in (0, pi]")
    return limit


def _mjcf(skeleton: Skeleton, s: float, *, density: float, radius: float, friction: float,
          armature: float, timestep: float, limit: float | None) -> str:
    """The MJCF of :func:`build_model` (``s`` meters per skeleton unit), as a string."""
    offsets = skeleton.offsets * s @ Y_TO_Z_MATRIX.T  # (J, 3), z-up meters
    end = [is_end_site(skeleton, j) for j in range(skeleton.n_joints)]
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
    return "\n".join(
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
    "Y_TO_Z",
    "Y_TO_Z_MATRIX",
    "Character",
    "build_model",
    "effective_inertia",
    "guess_scale",
    "import_mujoco",
    "motion_from_qpos",
    "qpos_from_motion",
    "qvel_from_motion",
    "set_state",
    "y_up_to_z_up_rotations",
    "z_up_to_y_up_rotations",
]
