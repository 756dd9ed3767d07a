"""course.physics.lqr_balance: MuJoCo's LQR tutorial on the standing CMU character.

Deterministic (the simulation has no randomness): the equilibrium, the linearisation's ``B``
against a finite-difference rollout of the character's own model (torques through
``qfrc_applied``), the solver-tolerance pitfall that zeroes ``B`` in contact, and a push the
LQR balance survives with no force or torque on the root on any step. Figures in
docs/control.md ("LQR balance of the character").
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from course.bvh import load_bvh

mujoco = pytest.importorskip(
    "mujoco", reason="MuJoCo is not installed (pip install 'course-kinematics[physics]')"
)

from course.control.linearization import linearize  # noqa: E402
from course.physics.character import build_model  # noqa: E402
from course.physics.lqr_balance import (  # noqa: E402
    LQRBalance,
    balance_dofs,
    design,
    lqr_stand,
    motor_model,
    survived,
)
from course.physics.simulation import Push  # noqa: E402


@pytest.fixture(autouse=True)
def _mujoco_log_elsewhere(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)


@pytest.fixture(scope="module")
def cmu(shared_bvh_dir: Path):
    return build_model(load_bvh(shared_bvh_dir / "cmu_12_01_walk.bvh").skeleton)


@pytest.fixture(scope="module")
def lqr(cmu):
    return design(cmu)


def test_equilibrium_needs_nothing_at_the_root(cmu, lqr) -> None:
    eq = lqr.equilibrium
    assert np.abs(eq.root_force).max() < 1e-6
    # the tutorial's height search alone leaves moments on the root no joint can supply
    assert np.abs(eq.tutorial_root_force[3:]).max() > 1.0
    assert -1e-3 < eq.height < 0 and np.abs(eq.tilt).max() < 0.01
    model = motor_model(cmu)
    data = mujoco.MjData(model)
    data.qpos[:] = eq.qpos
    data.ctrl[:] = eq.ctrl
    for _ in range(60):  # 0.1 s from rest: it stays, with the root unactuated
        mujoco.mj_step(model, data)
    assert np.abs(data.qvel).max() < 1e-6


def test_motor_control_is_the_torque_the_simulation_applies(cmu, lqr) -> None:
    motors, plain = motor_model(cmu, tolerance=None), cmu.fresh_model()
    rng = np.random.default_rng(3)
    u = lqr.equilibrium.ctrl + rng.normal(0.0, 5.0, motors.nu)
    a, b = mujoco.MjData(motors), mujoco.MjData(plain)
    for d in (a, b):
        d.qpos[:] = lqr.equilibrium.qpos
    a.ctrl[:] = u
    b.qfrc_applied[6:] = u
    for _ in range(5):
        mujoco.mj_step(motors, a)
        mujoco.mj_step(plain, b)
    assert np.abs(a.qvel - b.qvel).max() < 1e-9
    assert motors.nu == plain.nv - 6


def test_B_is_a_finite_difference_rollout_of_the_torques(cmu, lqr) -> None:
    """Columns of B against one step of the character's own model (no actuators), a torque
    component nudged both ways through qfrc_applied, the solver run to its end."""
    plain = cmu.fresh_model()
    plain.opt.tolerance = 0.0
    nv, eps = plain.nv, 1e-4

    def step(u):
        data = mujoco.MjData(plain)
        data.qpos[:] = lqr.equilibrium.qpos
        data.qfrc_applied[6:] = u
        mujoco.mj_step(plain, data)
        dq = np.zeros(nv)
        mujoco.mj_differentiatePos(plain, dq, 1.0, lqr.equilibrium.qpos, data.qpos)
        return np.concatenate([dq, data.qvel])

    for column in (balance_dofs(cmu)[0] - 6, 40, 75):  # a hip, an arm, a hand
        e = np.zeros(nv - 6)
        e[column] = eps
        fd = (step(lqr.equilibrium.ctrl + e) - step(lqr.equilibrium.ctrl - e)) / (2 * eps)
        assert np.abs(lqr.B[:, column] - fd).max() < 1e-6 * max(1.0, np.abs(fd).max())
        assert np.abs(fd).max() > 1e-3


def test_the_default_solver_tolerance_zeroes_B_in_contact(cmu, lqr) -> None:
    """The pitfall: warm-started at the unperturbed solution, the solver stops at once."""
    model = motor_model(cmu, tolerance=None)
    lin = linearize(model, lqr.equilibrium.qpos, None, lqr.equilibrium.ctrl)
    assert np.abs(lin.B).max() == 0.0
    assert np.abs(lqr.B).max() > 0.01


def test_lqr_survives_a_push_with_nothing_on_the_root(cmu, lqr) -> None:
    push = Push(cmu.skeleton.names[0], (0.0, 0.0, 30.0), start=0.25, duration=0.1)
    run = lqr_stand(cmu, lqr, duration=1.85, push=push)
    assert survived(run)
    assert not run.torques[:, :6].any()  # every recorded step: the root gets nothing
    assert LQRBalance(lqr).K.shape == (cmu.model.nv - 6, 2 * cmu.model.nv)
    # the gain is what holds it: ctrl0 alone (K = 0) falls under the same push
    open_loop = dataclasses.replace(lqr, K=np.zeros_like(lqr.K))
    assert not survived(lqr_stand(cmu, open_loop, duration=1.85, push=push))
    unpushed = lqr_stand(cmu, lqr, duration=1.0)
    assert survived(unpushed)
    assert np.linalg.norm(unpushed.com[-1] - unpushed.com[0]) < 1e-6
