"""Physics for animation: mass–spring systems 质点弹簧系统, a grid cloth, and rigid bodies 刚体.

scipy (the implicit step's sparse solve) is imported only when a step needs it::

    from course.physics import grid_cloth, simulate
    cloth = grid_cloth(20, 20)
    run = simulate(cloth.system, cloth.positions, 0 * cloth.positions, h=1 / 60, n_steps=60)

A rigid body (numpy only; ``docs/physics.md``)::

    from course.physics import Ground, box, simulate_rigid
    body = box(1.0, [0.1, 0.05, 0.075])
    run = simulate_rigid(body, body.state(x=[0, 0.3, 0]), h=1e-3, n_steps=2000,
                         ground=Ground(k=1e4, d=40, friction=5))

A simulated character on MuJoCo (``pip install 'course-kinematics[physics]'``; mujoco is
imported only when one of these names is first used, ``docs/physics.md``)::

    from course.physics import build_model, track
    character = build_model(motion.skeleton)
    result = track(character, motion, kp=1000, kd=6, hold_root=True)

Standing and pushed (lecture 10, ``docs/physics.md``)::

    from course.physics import Push, stand
    run = stand(character, controller="com", push=Push("Hips", (150, 0, 0), 0.5, 0.1))

Both are compositions of one simulation loop and a controller that supplies only torques
(``course.physics.simulation``, ``course.physics.controllers``)::

    from course.physics import PD, Simulation
    sim = Simulation(character, qpos, frame_time=1 / 60, h=1 / 600)
    record = sim.run(PD(qpos, kp=1000, kd=5), n_frames=61)

Lecture 11 (``docs/walking_control.md``): the linear inverted pendulum and the capture point
(numpy only), the ZMP against the support polygon, SIMBICON walking and stepping to recover
(the last three lazily, with the MuJoCo wing)::

    from course.physics import capture_point, natural_frequency, stand_and_step, walk
    run = walk(character, duration=20.0)              # run.strides, run.footsteps, run.fell
    xi = capture_point(com_xz, com_velocity_xz, natural_frequency(com_height))
"""

from typing import Any

from .cloth import BEND, SHEAR, STRUCTURAL, Cloth, grid_cloth
from .lip import (
    capture_point,
    capture_point_at,
    lip_acceleration,
    lip_state,
    natural_frequency,
    orbital_energy,
    step_to_stop,
    time_to_reach,
)
from .mass_spring import (
    GRAVITY,
    METHODS,
    Energy,
    NewtonStats,
    NotConvergedWarning,
    SpringSystem,
    StepResult,
    Trajectory,
    explicit_euler_step,
    implicit_euler_gradient,
    implicit_euler_objective,
    implicit_euler_step,
    simulate,
    step,
    symplectic_euler_step,
)
from .rigid_body import (
    INTEGRATORS,
    ROTATION_UPDATES,
    Ground,
    RigidBody,
    RigidEnergy,
    RigidState,
    RigidTrajectory,
    angular_velocity,
    box,
    box_corners,
    box_inertia,
    capsule_inertia,
    contact_forces,
    kinetic_energy,
    matrix_euler_step,
    orthonormalize,
    parallel_axis,
    point_torque,
    quat_euler_step,
    quat_exp_step,
    rigid_energy,
    simulate_rigid,
    step_rigid,
    t_handle,
    world_inertia,
)

#: Names served lazily from course.physics.character (which imports mujoco on first use).
_CHARACTER = (
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
)

#: Names served lazily from course.physics.balance (lecture 10's static balance, mujoco too).
_BALANCE = (
    "AnkleStrategy",
    "BalanceResult",
    "COMBalance",
    "largest_push",
    "stand",
    "standing_pose",
)


#: Names served lazily from course.physics.zmp (lecture 11's ZMP and support polygon; it needs
#: mujoco only for a simulated state's contacts).
_ZMP = (
    "ClipZMP",
    "KinematicZMP",
    "SegmentMasses",
    "SupportPolygons",
    "clip_zmp",
    "convex_hull",
    "in_polygon",
    "polygon_distance",
    "segment_masses",
    "support_polygons",
    "zmp_from_com",
    "zmp_from_forces",
    "zmp_from_motion",
    "zmp_from_mujoco",
    "zmp_from_points",
)

#: Names served lazily from course.physics.walking (SIMBICON) and .stepping (capture-point
#: steps). Their ``largest_push`` is reached through the module (``walking.largest_push``):
#: the package's own is the standing one.
_WALKING = ("SIMBICON", "Footstep", "Gait", "WalkResult", "neutral_pose", "walk")
_STEPPING = ("CaptureStep", "SteppingResult", "stand_and_step")

#: Names served lazily from course.physics.simulation and .controllers (the loop and the
#: controller interface; mujoco on first use too).
_SIMULATION = ("Fall", "HeldRoot", "Recording", "Simulation")
_CONTROLLERS = ("PD", "Controller", "StablePD")


def __getattr__(name: str) -> Any:
    if name in _SIMULATION:
        from . import simulation

        return getattr(simulation, name)
    if name in _CONTROLLERS:
        from . import controllers

        return getattr(controllers, name)
    if name in _CHARACTER:
        from . import character

        return getattr(character, name)
    if name in _BALANCE:
        from . import balance

        return getattr(balance, name)
    if name in _ZMP:
        from . import zmp

        return getattr(zmp, name)
    if name in _WALKING:
        from . import walking

        return getattr(walking, name)
    if name in _STEPPING:
        from . import stepping

        return getattr(stepping, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    *_CHARACTER,
    *_BALANCE,
    *_SIMULATION,
    *_CONTROLLERS,
    *_ZMP,
    *_WALKING,
    *_STEPPING,
    "BEND",
    "GRAVITY",
    "INTEGRATORS",
    "METHODS",
    "ROTATION_UPDATES",
    "SHEAR",
    "STRUCTURAL",
    "Cloth",
    "Energy",
    "Ground",
    "NewtonStats",
    "NotConvergedWarning",
    "RigidBody",
    "RigidEnergy",
    "RigidState",
    "RigidTrajectory",
    "SpringSystem",
    "StepResult",
    "Trajectory",
    "angular_velocity",
    "box",
    "box_corners",
    "box_inertia",
    "capsule_inertia",
    "capture_point",
    "capture_point_at",
    "contact_forces",
    "explicit_euler_step",
    "grid_cloth",
    "implicit_euler_gradient",
    "implicit_euler_objective",
    "implicit_euler_step",
    "kinetic_energy",
    "lip_acceleration",
    "lip_state",
    "matrix_euler_step",
    "natural_frequency",
    "orbital_energy",
    "orthonormalize",
    "parallel_axis",
    "point_torque",
    "quat_euler_step",
    "quat_exp_step",
    "rigid_energy",
    "simulate",
    "simulate_rigid",
    "step",
    "step_rigid",
    "step_to_stop",
    "symplectic_euler_step",
    "t_handle",
    "time_to_reach",
    "world_inertia",
]
