"""PD tracking 跟踪 of a clip by the simulated character, on MuJoCo.

:func:`track` is a composition: a :class:`~course.physics.simulation.Simulation` of the
character from the clip's first frame, driven by a :class:`~course.physics.controllers.PD`
(or :class:`~course.physics.controllers.StablePD`) controller aiming at the clip's next frame.
The model it simulates (how a :class:`~course.skeleton.Skeleton` becomes a MuJoCo body tree,
the y-up/z-up axes, the state conversions) is :mod:`course.physics.model`, and its names are
re-exported here, as :class:`~course.physics.simulation.Push` is: ``from
course.physics.character import build_model, Push, track`` keeps working.

MuJoCo (``pip install 'course-kinematics[physics]'``) is imported only when a function here
runs, so ``import course`` and ``import course.physics`` stay light.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from .._typing import Array
from .._validate import as_count
from ..motion import Motion
from .controllers import PD, StablePD
from .model import (
    CMU_SCALE,
    JOINT_LIMIT,
    Y_TO_Z,
    Y_TO_Z_MATRIX,
    Character,
    build_model,
    effective_inertia,
    guess_scale,
    import_mujoco,
    motion_from_qpos,
    qpos_from_motion,
    qvel_from_motion,
    set_state,
    y_up_to_z_up_rotations,
    z_up_to_y_up_rotations,
)
from .simulation import Fall, HeldRoot, Push, Simulation


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
        The step; it must divide the clip's frame time (a ValueError names ``h`` otherwise,
        :func:`~course.physics.simulation.substeps`); ``result.h`` is ``frame_time / n``.
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
    if motion.skeleton.n_joints != character.skeleton.n_joints:
        raise ValueError("motion: its skeleton does not match the character's")
    n = motion.n_frames if n_frames is None else min(as_count(n_frames, "n_frames"),
                                                       motion.n_frames)
    clip = motion[:n]
    qref = qpos_from_motion(character, clip)
    vref = qvel_from_motion(character, clip)
    name = f"{motion.name} (sim)"
    sim = Simulation(
        character, qref[0], vref[0], frame_time=motion.frame_time, h=h, gravity=gravity,
        torque_limit=torque_limit, push=push,
        held_root=HeldRoot(qref[:, :7], vref[:, :6]) if hold_root else None,
        fall=Fall("root", height=fall_height),
        on_frame=on_frame, name=name)
    law = StablePD if stable_pd else PD
    record = sim.run(law(qref, kp, kd) if torques else None, n)
    simulated = motion_from_qpos(character, record.qpos, motion.frame_time, name=name)
    return TrackingResult(
        motion=simulated,
        error_cm=tracking_error_cm(character, simulated, clip),
        fell=record.fall_time is not None,
        fall_time=record.fall_time,
        sim_time=record.sim_time,
        wall_time=record.wall_time,
        h=record.h,
        unstable=record.unstable,
        root_height=record.qpos[:, 2].copy(),
    )


__all__ = [
    "CMU_SCALE",
    "JOINT_LIMIT",
    "Y_TO_Z",
    "Y_TO_Z_MATRIX",
    "Character",
    "Push",
    "TrackingResult",
    "build_model",
    "effective_inertia",
    "guess_scale",
    "import_mujoco",
    "motion_from_qpos",
    "qpos_from_motion",
    "qvel_from_motion",
    "set_state",
    "track",
    "tracking_error_cm",
    "y_up_to_z_up_rotations",
    "z_up_to_y_up_rotations",
]
