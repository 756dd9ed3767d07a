"""Physics for animation: mass–spring systems 质点弹簧系统 and a grid cloth.

scipy (the implicit step's sparse solve) is imported only when a step needs it::

    from course.physics import grid_cloth, simulate
    cloth = grid_cloth(20, 20)
    run = simulate(cloth.system, cloth.positions, 0 * cloth.positions, h=1 / 60, n_steps=60)
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

__all__ = [
    "BEND",
    "GRAVITY",
    "METHODS",
    "SHEAR",
    "STRUCTURAL",
    "Cloth",
    "Energy",
    "NewtonStats",
    "NotConvergedWarning",
    "SpringSystem",
    "StepResult",
    "Trajectory",
    "explicit_euler_step",
    "grid_cloth",
    "implicit_euler_gradient",
    "implicit_euler_objective",
    "implicit_euler_step",
    "simulate",
    "step",
    "symplectic_euler_step",
]
