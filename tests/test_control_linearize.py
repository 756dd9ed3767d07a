"""Linearisation of a MuJoCo model (course.control.linearize): A, B against a
finite-difference rollout of mj_step, against the hand-written models of
course.control.systems (the same pendulum and cart-pole as inline XML, y up), on a free
body whose position lives in the tangent space, and LQR on the result balancing the
MuJoCo cart-pole. Needs mujoco (the dev extra)."""

from __future__ import annotations

import numpy as np
import pytest

from course.control import (
    CartPole,
    Pendulum,
    linearize,
    lqr_infinite_horizon,
    state_difference,
)

mujoco = pytest.importorskip("mujoco")

# A point mass of 1 kg on a 1 m massless rod, hinged about z; y up, upright at qpos = 0.
PENDULUM_XML = """
<mujoco model="pendulum">
  <option timestep="0.02" gravity="0 -9.81 0" integrator="Euler">
    <flag contact="disable"/>
  </option>
  <worldbody>
    <body name="pole">
      <joint name="hinge" type="hinge" axis="0 0 1"/>
      <inertial pos="0 1 0" mass="1" diaginertia="1e-8 1e-8 1e-8"/>
      <geom type="capsule" fromto="0 0 0 0 1 0" size="0.02" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
  <actuator><motor joint="hinge" gear="1"/></actuator>
</mujoco>
"""

# CartPole's defaults: 1 kg cart on a slider along x, 0.1 kg point mass 0.5 m up a massless
# pole; the hinge axis -z so that positive angles lean the pole towards +x.
CART_POLE_XML = """
<mujoco model="cart-pole">
  <option timestep="0.02" gravity="0 -9.81 0" integrator="Euler">
    <flag contact="disable"/>
  </option>
  <worldbody>
    <body name="cart">
      <joint name="slide" type="slide" axis="1 0 0"/>
      <inertial pos="0 0 0" mass="1" diaginertia="1e-3 1e-3 1e-3"/>
      <body name="pole">
        <joint name="hinge" type="hinge" axis="0 0 -1"/>
        <inertial pos="0 0.5 0" mass="0.1" diaginertia="1e-9 1e-9 1e-9"/>
      </body>
    </body>
  </worldbody>
  <actuator><motor joint="slide" gear="1"/></actuator>
</mujoco>
"""

# A free box with a motor on nothing but a hinge to a flap: quaternion positions (nq != nv).
FREE_XML = """
<mujoco model="free">
  <option timestep="0.005" gravity="0 -9.81 0"><flag contact="disable"/></option>
  <worldbody>
    <body name="box">
      <freejoint/>
      <geom type="box" size="0.2 0.1 0.05" mass="2"/>
      <body name="flap" pos="0.2 0 0">
        <joint name="flap" type="hinge" axis="0 1 0" damping="0.1"/>
        <geom type="box" pos="0.1 0 0" size="0.1 0.02 0.02" mass="0.3"/>
      </body>
    </body>
  </worldbody>
  <actuator><motor joint="flap" gear="2"/></actuator>
</mujoco>
"""


def model(xml: str) -> object:
    return mujoco.MjModel.from_xml_string(xml)


def step_state(m: object, qpos: np.ndarray, qvel: np.ndarray, ctrl: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
    d = mujoco.MjData(m)
    d.qpos[:], d.qvel[:], d.ctrl[:] = qpos, qvel, ctrl
    mujoco.mj_step(m, d)
    return d.qpos.copy(), d.qvel.copy()


def perturbed(m: object, qpos: np.ndarray, dx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The state ``(qpos, 0) ⊕ dx``: positions moved in the tangent space."""
    q = qpos.copy()
    mujoco.mj_integratePos(m, q, dx[: m.nv], 1.0)
    return q, dx[m.nv:]


def rollout_jacobians(m: object, qpos: np.ndarray, qvel: np.ndarray, ctrl: np.ndarray,
                      h: float = 1e-5) -> tuple[np.ndarray, np.ndarray]:
    """A, B by central differences of our own: each state coordinate (tangent space for
    positions) and each control moved by ±h, one mj_step each, the results differenced."""
    nv, nu = m.nv, m.nu
    q1, v1 = step_state(m, qpos, qvel, ctrl)

    def after(dx: np.ndarray, du: np.ndarray) -> np.ndarray:
        q, dv = perturbed(m, qpos, dx)
        q2, v2 = step_state(m, q, qvel + dv, ctrl + du)
        return state_difference(m, q2, v2, q1, v1)

    A = np.empty((2 * nv, 2 * nv))
    B = np.empty((2 * nv, nu))
    for j in range(2 * nv):
        e = np.zeros(2 * nv)
        e[j] = h
        A[:, j] = (after(e, np.zeros(nu)) - after(-e, np.zeros(nu))) / (2 * h)
    for j in range(nu):
        e = np.zeros(nu)
        e[j] = h
        B[:, j] = (after(np.zeros(2 * nv), e) - after(np.zeros(2 * nv), -e)) / (2 * h)
    return A, B


def a_state(m: object, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    qpos = m.qpos0.copy()
    if m.nq != m.nv:  # a free body: some orientation, not the identity, and a flap angle
        qpos[3:7] = np.array([0.9, 0.1, -0.3, 0.2]) / np.linalg.norm([0.9, 0.1, -0.3, 0.2])
        qpos[7] = 0.4
    else:
        qpos = 0.3 * rng.standard_normal(m.nq)
    return qpos, 0.5 * rng.standard_normal(m.nv), rng.standard_normal(m.nu)


@pytest.mark.parametrize("xml", [PENDULUM_XML, CART_POLE_XML, FREE_XML],
                         ids=["pendulum", "cart-pole", "free body"])
def test_A_B_are_a_finite_difference_rollout(xml: str) -> None:
    m = model(xml)
    qpos, qvel, ctrl = a_state(m, 0)
    lin = linearize(m, qpos, qvel, ctrl)
    assert lin.A.shape == (2 * m.nv, 2 * m.nv) and lin.B.shape == (2 * m.nv, m.nu)
    A, B = rollout_jacobians(m, qpos, qvel, ctrl)
    np.testing.assert_allclose(lin.A, A, atol=1e-6 * max(1.0, np.max(np.abs(A))))
    np.testing.assert_allclose(lin.B, B, atol=1e-6 * max(1.0, np.max(np.abs(B))))


@pytest.mark.parametrize("xml", [PENDULUM_XML, CART_POLE_XML, FREE_XML],
                         ids=["pendulum", "cart-pole", "free body"])
def test_A_B_predict_a_perturbed_step(xml: str) -> None:
    """One step from a perturbed state and control, simulated, against ``A δx + B δu``."""
    m = model(xml)
    qpos, qvel, ctrl = a_state(m, 1)
    lin = linearize(m, qpos, qvel, ctrl)
    q1, v1 = step_state(m, qpos, qvel, ctrl)
    rng = np.random.default_rng(2)
    dx = 1e-3 * rng.standard_normal(2 * m.nv)
    du = 1e-3 * rng.standard_normal(m.nu)
    q_start, dv = perturbed(m, qpos, dx)
    q2, v2 = step_state(m, q_start, qvel + dv, ctrl + du)
    actual = state_difference(m, q2, v2, q1, v1)
    predicted = lin.A @ dx + lin.B @ du
    assert np.max(np.abs(actual - predicted)) < 1e-3 * np.max(np.abs(predicted))


def test_the_mujoco_pendulum_is_the_hand_written_one() -> None:
    m = model(PENDULUM_XML)
    pendulum = Pendulum(dt=0.02)
    for theta, omega, torque in [(0.0, 0.0, 0.0), (0.7, 0.3, 0.2), (3.0, -2.0, 1.0)]:
        lin = linearize(m, [theta], [omega], [torque])
        A, B = pendulum.jacobians([theta, omega], [torque])
        np.testing.assert_allclose(lin.A, A, atol=1e-7)
        np.testing.assert_allclose(lin.B, B, atol=1e-8)
        q, v = step_state(m, np.array([theta]), np.array([omega]), np.array([torque]))
        np.testing.assert_allclose(np.r_[q, v], pendulum.step([theta, omega], [torque]),
                                   atol=1e-7)


def test_the_mujoco_cart_pole_is_the_hand_written_one() -> None:
    m = model(CART_POLE_XML)
    cart_pole = CartPole(dt=0.02)
    for x in ([0.0, 0.0, 0.0, 0.0], [0.3, 0.4, -0.2, 0.5]):
        lin = linearize(m, x[:2], x[2:], [0.5])
        A, B = cart_pole.jacobians(x, [0.5])
        np.testing.assert_allclose(lin.A, A, atol=1e-6)
        np.testing.assert_allclose(lin.B, B, atol=1e-7)


def test_lqr_on_the_linearisation_balances_the_mujoco_cart_pole() -> None:
    m = model(CART_POLE_XML)
    lin = linearize(m, [0.0, 0.0])
    lqr = lqr_infinite_horizon(lin.A, lin.B, np.diag([1.0, 10.0, 0.1, 0.1]), [[0.1]])
    assert lqr.converged and lqr.spectral_radius < 1
    d = mujoco.MjData(m)
    d.qpos[:] = [0.2, 0.15]  # 0.2 m off and leaning 8.6 degrees
    for _ in range(500):  # 10 s
        x = state_difference(m, d.qpos, d.qvel, np.zeros(2), np.zeros(2))
        d.ctrl[:] = -lqr.K @ x
        mujoco.mj_step(m, d)
    assert np.max(np.abs(np.r_[d.qpos, d.qvel])) < 1e-3
    # Without it, it falls.
    d = mujoco.MjData(m)
    d.qpos[:] = [0.2, 0.15]
    for _ in range(100):
        mujoco.mj_step(m, d)
    assert abs(d.qpos[1]) > 1.0


def test_forward_differences_and_the_callers_data_untouched() -> None:
    m = model(CART_POLE_XML)
    central = linearize(m, [0.1, 0.2], [0.0, 0.1])
    forward = linearize(m, [0.1, 0.2], [0.0, 0.1], centered=False, eps=1e-7)
    np.testing.assert_allclose(forward.A, central.A, atol=1e-5)
    assert not forward.centered and forward.eps == 1e-7 and central.dt == 0.02
    assert (central.nv, central.na, central.nu, central.n_states) == (2, 0, 1, 4)


def test_state_difference_in_the_tangent_space() -> None:
    m = model(FREE_XML)
    q_ref = m.qpos0.copy()
    dx = np.array([0.1, -0.2, 0.3, 0.05, -0.02, 0.01, 0.4])  # 3 linear, 3 angular, the hinge
    q = q_ref.copy()
    mujoco.mj_integratePos(m, q, dx, 1.0)
    v = np.arange(7.0)
    np.testing.assert_allclose(state_difference(m, q, v, q_ref, np.zeros(7)), np.r_[dx, v],
                               atol=1e-12)


def test_bad_arguments_are_named() -> None:
    m = model(CART_POLE_XML)
    with pytest.raises(ValueError, match=r"qpos: expected shape \(2,\) for this model"):
        linearize(m, [0.0])
    with pytest.raises(ValueError, match=r"ctrl: expected shape \(1,\) for this model"):
        linearize(m, [0.0, 0.0], ctrl=[1.0, 2.0])
    with pytest.raises(ValueError, match="model: expected a mujoco.MjModel, got str"):
        linearize("cart-pole", [0.0, 0.0])
    with pytest.raises(ValueError, match="eps: must be a positive number"):
        linearize(m, [0.0, 0.0], eps=0.0)
    with pytest.raises(ValueError, match="qvel: contains NaN"):
        linearize(m, [0.0, 0.0], [np.nan, 0.0])
