"""course.physics.lqr_balance: MuJoCo's LQR tutorial on the standing CMU character.

Deterministic (the simulation has no randomness): the equilibrium, the linearisation's ``B``
against a finite-difference rollout of the character's own model (torques through
``qfrc_applied``), the solver-tolerance pitfall that zeroes ``B`` in contact, and a push the
LQR balance survives with no force or torque on the root on any step; then the same on one
leg (the tutorial's own task): the pose, its equilibrium, and pushes survived and not, at
bounds under and over the measured largest push. Figures in docs/control.md ("LQR balance of
the character").
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

mujoco = pytest.importorskip(
    "mujoco", reason="MuJoCo is not installed (pip install 'course-kinematics[physics]')"
)

from course.control.linearization import linearize  # noqa: E402
from course.physics.balance import leg_joints  # noqa: E402
from course.physics.lqr_balance import (  # noqa: E402
    LQRBalance,
    balance_dofs,
    design,
    lqr_stand,
    motor_model,
    one_leg_pose,
    support_feet,
    survived,
)
from course.physics.model import Y_TO_Z_MATRIX, qpos_from_motion  # noqa: E402
from course.physics.simulation import Push  # noqa: E402

pytestmark = pytest.mark.usefixtures("mujoco_log_elsewhere")


@pytest.fixture(scope="module")
def lqr(cmu):
    return design(cmu)


@pytest.fixture(scope="module")
def one_leg(cmu):
    return design(cmu, stance=0)


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


def test_one_leg_pose_has_the_com_over_the_stance_foot(cmu) -> None:
    pose = one_leg_pose(cmu, stance=0)
    p = pose.forward_kinematics()[0][0] * cmu.scale  # y-up metres
    model = cmu.fresh_model()
    data = mujoco.MjData(model)
    data.qpos[:] = qpos_from_motion(cmu, pose)[0]
    mujoco.mj_forward(model, data)
    com = Y_TO_Z_MATRIX.T @ data.subtree_com[cmu.bodies[0]]
    stand, lifted = support_feet(cmu, 0)[0], support_feet(cmu, 1)[0]
    centre = (p[stand[0]] + p[stand[-1]]) / 2
    assert np.abs((com - centre)[[0, 2]]).max() < 1e-8
    assert p[list(stand), 1].min() == pytest.approx(0.0, abs=1e-9)  # flat where it stood
    assert p[list(lifted), 1].min() > 0.08  # the other foot well off the floor
    with pytest.raises(ValueError, match="stance"):
        one_leg_pose(cmu, stance=2)


def test_one_leg_equilibrium_touches_with_one_foot_and_needs_nothing_at_the_root(
        cmu, one_leg) -> None:
    eq = one_leg.equilibrium
    assert one_leg.stance == 0
    assert np.abs(eq.root_force).max() < 1e-6
    model = motor_model(cmu)
    data = mujoco.MjData(model)
    data.qpos[:] = eq.qpos
    mujoco.mj_forward(model, data)
    leg = {cmu.bodies[j] for j in leg_joints(cmu.skeleton, support_feet(cmu, 0)[0][-1])}
    touching = {int(model.geom_bodyid[g]) for c in data.contact[:data.ncon]
                for g in (c.geom1, c.geom2)} - {0}
    assert touching and touching <= leg
    data.ctrl[:] = eq.ctrl
    for _ in range(60):
        mujoco.mj_step(model, data)
    assert np.abs(data.qvel).max() < 1e-6
    # the tutorial's groups: the stance leg and the spine are the balance DOFs, not the other leg
    assert len(balance_dofs(cmu, 0)) == len(balance_dofs(cmu)) - 15


@pytest.mark.parametrize("direction,survives,falls", [
    ((0.0, 0.0, 1.0), 80.0, 200.0),    # forward: largest 96.9 N measured
    ((0.0, 0.0, -1.0), 110.0, 200.0),  # backward: 128.1 N
    ((1.0, 0.0, 0.0), 70.0, 200.0),    # sideways, towards the stance foot: 84.4 N
])
def test_one_leg_lqr_survives_pushes_with_nothing_on_the_root(cmu, one_leg, direction,
                                                              survives, falls) -> None:
    root = cmu.skeleton.names[0]

    def run(force):
        push = Push(root, tuple(force * np.array(direction)), start=0.25, duration=0.1)
        return lqr_stand(cmu, one_leg, duration=1.85, push=push)

    held = run(survives)
    assert survived(held) and not held.torques[:, :6].any()
    assert not survived(run(falls))
    if direction[2] > 0:  # the gain is what holds it: ctrl0 alone falls under 30 N
        open_loop = dataclasses.replace(one_leg, K=np.zeros_like(one_leg.K))
        assert not survived(lqr_stand(cmu, open_loop, duration=1.85, push=Push(
            root, (0.0, 0.0, 30.0), start=0.25, duration=0.1)))
