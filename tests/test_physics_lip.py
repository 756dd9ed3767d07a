"""course.physics.lip: the linear inverted pendulum and the capture point (lecture 11).

The closed forms against numerical integration (scipy's solve_ivp, DOP853 at rtol 1e-11), the
conserved orbital energy, and the capture point's promise: a foot placed at ξ = c + ċ/ω₀
brings the pendulum to rest over it. Hypothesis properties are derandomised (seeded).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from course.physics.lip import (
    G,
    capture_point,
    capture_point_at,
    lip_acceleration,
    lip_state,
    natural_frequency,
    orbital_energy,
    step_to_stop,
    time_to_reach,
)

solve_ivp = pytest.importorskip("scipy.integrate").solve_ivp

PROPERTY = settings(max_examples=60, derandomize=True, deadline=None, database=None,
                    suppress_health_check=[HealthCheck.too_slow])

positions = st.floats(-1.0, 1.0)
speeds = st.floats(-2.0, 2.0)
heights = st.floats(0.5, 1.5)


def integrate(c0, v0, p, w, t):
    """c, ċ at times t of c̈ = ω²(c − p), by DOP853 (any dimension: the axes stacked)."""
    c0, v0 = np.atleast_1d(c0).astype(float), np.atleast_1d(v0).astype(float)
    n = len(c0)

    def rhs(_, y):
        return np.concatenate([y[n:], w**2 * (y[:n] - p)])

    sol = solve_ivp(rhs, (0.0, float(t[-1])), np.concatenate([c0, v0]), method="DOP853",
                    t_eval=t, rtol=1e-11, atol=1e-12)
    assert sol.success
    return sol.y[:n].T, sol.y[n:].T


def test_omega0_is_the_square_root_of_g_over_the_com_height():
    assert natural_frequency(1.0) == pytest.approx(math.sqrt(9.81))
    assert natural_frequency(0.9) == pytest.approx(3.3015148, rel=1e-7)  # 1/s
    # the height is above the ground, whatever the floor's y: a grader's "wrong height"
    np.testing.assert_allclose(natural_frequency([0.8, 1.0], g=G), np.sqrt(G / np.array([0.8, 1])))
    # taller pendulums are slower
    assert natural_frequency(1.2) < natural_frequency(0.8)


def test_the_com_accelerates_away_from_the_foot():
    w = natural_frequency(0.9)
    assert lip_acceleration(0.1, 0.0, w) > 0  # in front of the foot: falls forwards
    assert lip_acceleration(-0.1, 0.0, w) < 0
    assert lip_acceleration(0.3, 0.3, w) == 0
    np.testing.assert_allclose(lip_acceleration([0.1, -0.2], [0.0, 0.1], w), w**2 * np.array(
        [0.1, -0.3]))


@pytest.mark.parametrize("c0, v0, p", [(0.05, 0.4, 0.0), (-0.2, 0.9, 0.1), (0.0, 0.0, 0.0),
                                       (0.1, -0.6, -0.05)])
def test_closed_form_matches_numerical_integration_1d(c0, v0, p):
    w = natural_frequency(0.85)
    t = np.linspace(0, 1.0, 41)
    c_num, v_num = integrate(c0, v0, p, w, t)
    c, v = lip_state(t, c0, v0, p, w)
    np.testing.assert_allclose(c, c_num[:, 0], rtol=0, atol=1e-8 * max(1, np.abs(c).max()))
    np.testing.assert_allclose(v, v_num[:, 0], rtol=0, atol=1e-8 * max(1, np.abs(v).max()))


def test_closed_form_on_the_ground_plane_broadcasts_times_against_xz():
    w = natural_frequency(1.0)
    c0, v0, p = np.array([0.02, -0.1]), np.array([0.3, 0.7]), np.array([0.0, 0.05])
    t = np.linspace(0, 0.8, 17)
    c, v = lip_state(t[:, None], c0, v0, p, w)
    assert c.shape == v.shape == (17, 2)
    c_num, v_num = integrate(c0, v0, p, w, t)
    np.testing.assert_allclose(c, c_num, atol=1e-8)
    np.testing.assert_allclose(v, v_num, atol=1e-8)
    # the axes are independent: each is the 1-D pendulum
    for k in range(2):
        np.testing.assert_array_equal(lip_state(t, c0[k], v0[k], p[k], w)[0], c[:, k])
    # t = 0 gives the initial state back, and running backwards undoes running forwards
    np.testing.assert_allclose(lip_state(0.0, c0, v0, p, w), (c0, v0))
    c1, v1 = lip_state(0.5, c0, v0, p, w)
    np.testing.assert_allclose(lip_state(-0.5, c1, v1, p, w), (c0, v0), atol=1e-12)


@PROPERTY
@given(c0=positions, v0=speeds, p=positions, h=heights, t=st.floats(0.0, 2.0))
def test_orbital_energy_is_conserved_along_the_closed_form(c0, v0, p, h, t):
    w = natural_frequency(h)
    c, v = lip_state(t, c0, v0, p, w)
    e0, e1 = orbital_energy(c0, v0, p, w), orbital_energy(c, v, p, w)
    scale = 0.5 * v**2 + 0.5 * w**2 * (c - p) ** 2  # the terms that cancel
    assert abs(e1 - e0) <= 1e-12 * max(1.0, scale)


def test_orbital_energy_numbers_and_sign():
    w = 3.0
    assert orbital_energy(0.1, 0.5, 0.0, w) == pytest.approx(0.5 * 0.25 - 0.5 * 9 * 0.01)
    # E > 0 moving towards the foot: passes over it with speed sqrt(2E)
    c0, v0, p = -0.1, 0.5, 0.0
    e = orbital_energy(c0, v0, p, w)
    assert e > 0
    t = time_to_reach(c0, v0, p, w, p)
    assert np.isfinite(t)
    assert lip_state(t, c0, v0, p, w)[1] == pytest.approx(math.sqrt(2 * e))
    # E < 0: it stops short and falls back, never reaching the foot
    assert orbital_energy(-0.2, 0.5, 0.0, w) < 0
    assert time_to_reach(-0.2, 0.5, 0.0, w, 0.0) == math.inf


@PROPERTY
@given(c0=positions, v0=speeds, h=heights)
def test_stepping_to_the_capture_point_brings_the_pendulum_to_rest_over_the_foot(c0, v0, h):
    w = natural_frequency(h)
    xi = capture_point(c0, v0, w)
    # zero orbital energy about the new foot, moving towards it (or already at rest on it)
    assert abs(orbital_energy(c0, v0, xi, w)) <= 1e-12 * max(1.0, v0**2)
    # closed form: c(t) - ξ = (c0 - ξ) e^{-ω t}, ċ(t) = -ω (c0 - ξ) e^{-ω t} -> 0
    t = np.array([0.5, 1.0, 3.0, 10.0])
    c, v = lip_state(t, c0, v0, xi, w)
    decay = np.exp(-w * t)
    np.testing.assert_allclose(c - xi, (c0 - xi) * decay, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(v, -w * (c0 - xi) * decay, rtol=1e-9, atol=1e-14)
    assert abs(v[-1]) < 1e-9  # at rest after 10 s
    # any other foot does not stop it: it runs away from that foot
    for miss in (0.02, -0.02):
        c_miss, _ = lip_state(3.0, c0, v0, xi + miss, w)
        assert abs(c_miss - (xi + miss)) > 1.0


def test_capture_point_units_and_signs():
    w = natural_frequency(0.9)
    # moving forwards at 0.5 m/s over the foot: step 0.5 / 3.30 = 15 cm ahead
    assert capture_point(0.0, 0.5, w) == pytest.approx(0.5 / 3.3015148, rel=1e-7)
    assert capture_point(0.0, -0.5, w) < 0
    # divided by ω0, not multiplied: a grader's "c + ċ ω0" is ten times too far
    assert capture_point(0.0, 0.5, w) < 0.5
    # 2-D: the capture point of each ground-plane axis
    np.testing.assert_allclose(capture_point([0.1, 0.2], [0.3, -0.6], w),
                               [0.1 + 0.3 / w, 0.2 - 0.6 / w])


@PROPERTY
@given(c0=positions, v0=speeds, p=positions, h=heights, t=st.floats(0.0, 1.0))
def test_the_capture_point_diverges_from_the_foot_exponentially(c0, v0, p, h, t):
    w = natural_frequency(h)
    c, v = lip_state(t, c0, v0, p, w)
    xi_t = capture_point_at(t, c0, v0, p, w)
    assert xi_t == pytest.approx(capture_point(c, v, w), abs=1e-9 * math.exp(w * t))
    # ξ̇ = ω0 (ξ − p), by a central difference of the closed form
    dt = 1e-6
    rate = (capture_point_at(t + dt, c0, v0, p, w) - capture_point_at(t - dt, c0, v0, p, w)) / (
        2 * dt)
    assert rate == pytest.approx(w * (xi_t - p), rel=1e-5, abs=1e-6)


def test_stepping_after_a_delay_lands_where_the_capture_point_has_gone():
    w = natural_frequency(0.9)
    c0, v0, p = np.array([0.0, 0.1]), np.array([0.6, -0.2]), np.array([0.0, 0.08])
    after = 0.3
    foot = step_to_stop(c0, v0, w, p=p, after=after)
    c1, v1 = lip_state(after, c0, v0, p, w)  # still on the old foot until then
    np.testing.assert_allclose(foot, capture_point(c1, v1, w), atol=1e-12)
    # then on the new foot: comes to rest over it
    c2, v2 = lip_state(8.0, c1, v1, foot, w)
    np.testing.assert_allclose(c2, foot, atol=1e-9)
    np.testing.assert_allclose(v2, 0.0, atol=1e-9)
    # stepping now is the capture point itself
    np.testing.assert_array_equal(step_to_stop(c0, v0, w), capture_point(c0, v0, w))
    np.testing.assert_allclose(step_to_stop(c0, v0, w, p=p), capture_point(c0, v0, w))


@PROPERTY
@given(c0=positions, v0=speeds, p=positions, h=heights, target=positions)
def test_time_to_reach_is_the_first_time_the_com_is_there(c0, v0, p, h, target):
    w = natural_frequency(h)
    t = float(time_to_reach(c0, v0, p, w, target))
    assert t >= 0
    grid = np.linspace(0.0, min(t, 5.0) if np.isfinite(t) else 5.0, 400)
    c_grid, _ = lip_state(grid, c0, v0, p, w)
    side = np.sign(c0 - target)
    if np.isfinite(t):
        c_t, _ = lip_state(t, c0, v0, p, w)
        assert c_t == pytest.approx(target, abs=1e-7 * (1 + math.cosh(w * t)))
        # not there before (the COM stays on its starting side until t)
        if side != 0:
            assert np.all(side * (c_grid[:-1] - target) >= -1e-7)
    else:
        # never: on the starting side all along
        assert side != 0
        assert np.all(side * (c_grid - target) > -1e-9)


def test_time_to_reach_cases():
    w = 3.0
    assert time_to_reach(0.2, 0.0, 0.0, w, 0.2) == 0.0
    # from rest in front of the foot: c = c0 cosh(ωt), reaching 2 c0 at acosh(2)/ω
    assert time_to_reach(0.1, 0.0, 0.0, w, 0.2) == pytest.approx(math.acosh(2) / w)
    assert time_to_reach(0.1, 0.0, 0.0, w, 0.05) == math.inf  # falls away from it
    # captured exactly (ξ = p): only tends to the foot
    assert time_to_reach(-0.1, 0.3, 0.0, w, 0.0) == math.inf
    assert time_to_reach(-0.1, 0.3, 0.0, w, -0.05) == pytest.approx(math.log(2) / w)
    # vectorised over targets
    out = time_to_reach(0.1, 0.0, 0.0, w, np.array([0.1, 0.2, 0.05]))
    np.testing.assert_allclose(out, [0.0, math.acosh(2) / w, math.inf])


@pytest.mark.parametrize("call, name", [
    (lambda: natural_frequency(0.0), "height"),
    (lambda: natural_frequency(-1.0), "height"),
    (lambda: natural_frequency(1.0, g=0.0), "g"),
    (lambda: lip_state(0.1, 0.0, 0.1, 0.0, 0.0), "omega0"),
    (lambda: lip_state(0.1, 0.0, 0.1, 0.0, [3.0, -3.0]), "omega0"),
    (lambda: lip_state(float("nan"), 0.0, 0.1, 0.0, 3.0), "t"),
    (lambda: lip_state(0.1, "0.1", 0.1, 0.0, 3.0), "c0"),
    (lambda: orbital_energy(0.0, float("inf"), 0.0, 3.0), "cdot"),
    (lambda: capture_point(0.0, 0.1, np.nan), "omega0"),
    (lambda: step_to_stop(0.0, 0.1, 3.0, after=0.2), "p"),
    (lambda: step_to_stop(0.0, 0.1, 3.0, p=0.0, after=-0.2), "after"),
    (lambda: time_to_reach(0.0, 0.1, 0.0, 3.0, None), "target"),
])
def test_bad_arguments_are_refused_by_name(call, name):
    with pytest.raises(ValueError, match=rf"^{name}\b"):
        call()


def test_shapes_that_do_not_broadcast_name_every_argument():
    with pytest.raises(ValueError, match=r"lip_state: .*c0 has shape \(2,\).*cdot0 has shape "
                       r"\(3,\)"):
        lip_state(0.1, np.zeros(2), np.zeros(3), 0.0, 3.0)
