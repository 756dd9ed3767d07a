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
"""

from .cloth import BEND, SHEAR, STRUCTURAL, Cloth, grid_cloth
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

__all__ = [
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
    "contact_forces",
    "explicit_euler_step",
    "grid_cloth",
    "implicit_euler_gradient",
    "implicit_euler_objective",
    "implicit_euler_step",
    "kinetic_energy",
    "matrix_euler_step",
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
    "symplectic_euler_step",
    "t_handle",
    "world_inertia",
]
