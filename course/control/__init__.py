"""Optimal control and learning 最优控制与学习 (GAMES105 lecture 12): LQR, dynamic
programming, iLQR and policy gradient, on small systems and on any MuJoCo model.

Nothing is loaded until a name is first used (``import course.control`` imports neither
numpy's friends nor mujoco; scipy is never needed)::

    from course.control import double_integrator, lqr_infinite_horizon
    system = double_integrator(dt=0.1)
    lqr = lqr_infinite_horizon(system.A, system.B, Q=np.eye(2), R=[[1.0]])
    u = -lqr.K @ x                       # the sign convention everywhere: u = -K x

One module per topic, each readable beside the lecture (``docs/control.md``):

* :mod:`~course.control.lqr` — the Riccati recursion, finite and infinite horizon;
* :mod:`~course.control.systems` — double integrator, linear inverted pendulum, pendulum,
  cart-pole as discrete-time models;
* :mod:`~course.control.linearization` — ``A``, ``B`` of a MuJoCo model about a state
  (``mujoco.mjd_transitionFD``);
* :mod:`~course.control.dynamic_programming` — value iteration on the discretised pendulum;
* :mod:`~course.control.ilqr` — iLQR (Tassa, Erez and Todorov 2012), the pendulum swing-up;
* :mod:`~course.control.policy_gradient` — REINFORCE with a baseline on a linear-Gaussian
  policy, checked against the exact gradient and LQR's cost.
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .dynamic_programming import (
        PendulumGrid,
        Transitions,
        ValueIterationResult,
        bellman_backup,
        transitions,
        value_iteration,
        wrap_angle,
    )
    from .ilqr import (
        ILQRResult,
        QuadraticCost,
        backward_pass,
        pendulum_swing_up,
        rollout_open_loop,
        solve_ilqr,
    )
    from .linearization import Linearization, linearize, state_difference
    from .lqr import (
        FiniteHorizonLQR,
        LQRResult,
        gain_value_matrices,
        lqr_finite_horizon,
        lqr_infinite_horizon,
        quadratic_cost,
        riccati_step,
        rollout_linear,
    )
    from .policy_gradient import (
        LinearGaussianPolicy,
        LQTask,
        Rollouts,
        TrainingResult,
        ValueBaseline,
        reinforce_gradient,
        reinforce_terms,
        sample_rollouts,
        train_reinforce,
    )
    from .systems import (
        GRAVITY,
        CartPole,
        DiscreteSystem,
        LinearSystem,
        Pendulum,
        double_integrator,
        finite_difference_jacobians,
        linear_inverted_pendulum,
    )

#: Each public name and the submodule that defines it (loaded on first use).
_WHERE = {
    **dict.fromkeys(("FiniteHorizonLQR", "LQRResult", "gain_value_matrices",
                     "lqr_finite_horizon", "lqr_infinite_horizon", "quadratic_cost",
                     "riccati_step", "rollout_linear"), "lqr"),
    **dict.fromkeys(("GRAVITY", "CartPole", "DiscreteSystem", "LinearSystem", "Pendulum",
                     "double_integrator", "finite_difference_jacobians",
                     "linear_inverted_pendulum"), "systems"),
    **dict.fromkeys(("Linearization", "linearize", "state_difference"), "linearization"),
    **dict.fromkeys(("PendulumGrid", "Transitions", "ValueIterationResult", "bellman_backup",
                     "transitions", "value_iteration", "wrap_angle"), "dynamic_programming"),
    **dict.fromkeys(("ILQRResult", "QuadraticCost", "backward_pass", "solve_ilqr",
                     "pendulum_swing_up", "rollout_open_loop"), "ilqr"),
    **dict.fromkeys(("LQTask", "LinearGaussianPolicy", "Rollouts", "TrainingResult",
                     "ValueBaseline", "reinforce_gradient", "reinforce_terms",
                     "sample_rollouts", "train_reinforce"), "policy_gradient"),
}


def __getattr__(name: str) -> Any:
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(import_module(f"{__name__}.{module}"), name)


def __dir__() -> list[str]:
    return sorted({*globals(), *_WHERE})


__all__ = [
    # lqr
    "FiniteHorizonLQR", "LQRResult", "gain_value_matrices", "lqr_finite_horizon",
    "lqr_infinite_horizon", "quadratic_cost", "riccati_step", "rollout_linear",
    # systems
    "CartPole", "DiscreteSystem", "GRAVITY", "LinearSystem", "Pendulum", "double_integrator",
    "finite_difference_jacobians", "linear_inverted_pendulum",
    # linearization
    "Linearization", "linearize", "state_difference",
    # dynamic_programming
    "PendulumGrid", "Transitions", "ValueIterationResult", "bellman_backup", "transitions",
    "value_iteration", "wrap_angle",
    # ilqr
    "ILQRResult", "QuadraticCost", "backward_pass", "pendulum_swing_up", "rollout_open_loop",
    "solve_ilqr",
    # policy_gradient
    "LQTask", "LinearGaussianPolicy", "Rollouts", "TrainingResult", "ValueBaseline",
    "reinforce_gradient", "reinforce_terms", "sample_rollouts", "train_reinforce",
]
