"""course.keyframes.rotations: SLERP keys and SQUAD against scipy and numerical derivatives."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from rotation_asserts import assert_quat_equal, random_quats, scipy_quat, scipy_rotation
from scipy.spatial.transform import Rotation, Slerp

from course import keyframes as kf
from course import rotations as rot

TIMES = np.array([0.0, 0.5, 0.8, 1.6, 2.0])  # uneven


def keys_along_a_path(rng, n=5, step_deg=50.0):
    """Rotation keys that each turn up to ``step_deg`` from the previous one, signs random
    (q and -q stored at random, as a file may)."""
    steps = rot.quat_from_rotvec(rng.normal(size=(n - 1, 3)) * np.radians(step_deg) / 2)
    q = [random_quats(rng)]
    for s in steps:
        q.append(rot.quat_mul(s, q[-1]))
    return np.array(q) * rng.choice([-1.0, 1.0], size=(n, 1))


def speed_jumps(f, times):
    return np.array([kf.angular_velocity_jump(f, x) for x in times[1:-1]])


def test_slerp_keys_matches_scipy_slerp():
    rng = np.random.default_rng(0)
    q = keys_along_a_path(rng)
    t = np.linspace(0, 2, 101)
    ref = Slerp(TIMES, scipy_rotation(kf.same_hemisphere(q)))(t)
    assert_quat_equal(kf.slerp_keys(q, TIMES, t), scipy_quat(ref, (101,)), atol=1e-12)


def test_slerp_keys_turns_at_constant_angular_velocity_per_segment():
    rng = np.random.default_rng(1)
    q = keys_along_a_path(rng)
    for i in range(len(TIMES) - 1):
        t = np.linspace(TIMES[i], TIMES[i + 1], 41)
        w = kf.angular_velocity(kf.slerp_keys(q, TIMES, t), t)
        expected = rot.quat_angle(q[i], q[i + 1]) / (TIMES[i + 1] - TIMES[i])
        assert np.allclose(np.linalg.norm(w, axis=-1), expected, rtol=1e-9)
        assert np.allclose(w, w[0], atol=1e-9)  # fixed axis too


def test_same_hemisphere_keeps_rotations_and_makes_dots_nonnegative():
    rng = np.random.default_rng(2)
    q = random_quats(rng, (30, 4))
    out = kf.same_hemisphere(q)
    assert_quat_equal(out, q)
    assert np.all(np.sum(out[1:] * out[:-1], axis=-1) >= 0)


@pytest.mark.parametrize("scheme", [kf.slerp_keys, kf.squad])
def test_shortest_path_with_a_negated_key(scheme):
    """Negating a key changes nothing: the curve still takes the short way (the turn between
    neighbouring keys of 40 degrees is never the long 320)."""
    q = rot.quat_from_axis_angle([0.0, 1.0, 0.0], np.radians([0.0, 40.0, 80.0, 120.0]))
    flipped = q * np.array([1, -1, 1, -1])[:, None]
    times = np.arange(4.0)
    t = np.linspace(0, 3, 301)
    a, b = scheme(q, times, t), scheme(flipped, times, t)
    assert_quat_equal(a, b, atol=1e-12)
    angle = np.degrees(rot.quat_angle(q[0], b))  # monotone 0 -> 120 about y: no detour
    assert np.all(np.diff(angle) > 0) and np.isclose(angle[-1], 120)


@pytest.mark.parametrize("scheme", [kf.slerp_keys, kf.squad])
def test_unit_norm_and_keys_passed(scheme):
    rng = np.random.default_rng(3)
    q = keys_along_a_path(rng)
    t = np.linspace(0, 2, 203)
    out = scheme(q, TIMES, t)
    assert np.allclose(np.linalg.norm(out, axis=-1), 1.0, atol=1e-12)
    assert_quat_equal(scheme(q, TIMES, TIMES), q, atol=1e-12)


def test_squad_is_c1_where_slerp_is_not():
    rng = np.random.default_rng(4)
    q = keys_along_a_path(rng)
    slerp_jumps = speed_jumps(lambda t: kf.slerp_keys(q, TIMES, t), TIMES)
    squad_jumps = speed_jumps(lambda t: kf.squad(q, TIMES, t), TIMES)
    assert squad_jumps.max() < 1e-5, squad_jumps
    assert slerp_jumps.min() > 0.1, slerp_jumps


@pytest.mark.parametrize(("w0", "w1"), [(1.0, 1.0), (0.5, 2.0), (-1.0, 3.0)])
def test_angular_velocity_jump_closed_form(w0, w1):
    """A turn about one axis at w0 rad/s before t = 1 and w1 after: the jump is |w1 - w0|."""
    axis = np.array([1.0, 2.0, 2.0]) / 3.0

    def q_of_t(t):
        angle = np.where(t < 1.0, w0 * (t - 1.0), w1 * (t - 1.0))
        return rot.quat_from_axis_angle(axis, angle)

    assert kf.angular_velocity_jump(q_of_t, 1.0) == pytest.approx(abs(w1 - w0), abs=1e-7)
    with pytest.raises(ValueError, match="h: expected > 0"):
        kf.angular_velocity_jump(q_of_t, 1.0, h=-1.0)


def test_squad_is_shoemakes_formula_with_course_slerp():
    """The batched log/exp evaluation against the formula written with course.rotations.slerp."""
    rng = np.random.default_rng(9)
    q = keys_along_a_path(rng)
    t = np.linspace(0, 2, 77)
    qa, s = kf.same_hemisphere(q), kf.squad_controls(q, TIMES)
    i = np.clip(np.searchsorted(TIMES, t, side="right") - 1, 0, len(TIMES) - 2)
    u = ((t - TIMES[i]) / (TIMES[i + 1] - TIMES[i]))[:, None]
    ref = rot.slerp(rot.slerp(qa[i], qa[i + 1], u[:, 0]), rot.slerp(s[i], s[i + 1], u[:, 0]),
                    (2 * u * (1 - u))[:, 0])
    assert_quat_equal(kf.squad(q, TIMES, t), ref, atol=1e-12)


def test_squad_with_equal_spacing_uses_shoemakes_controls():
    rng = np.random.default_rng(5)
    q = kf.same_hemisphere(keys_along_a_path(rng))
    times = np.arange(len(q)) * 0.25
    s = kf.squad_controls(q, times)
    for i in range(1, len(q) - 1):
        inv = rot.quat_conjugate(q[i])
        log_sum = (kf.quat_log(rot.quat_mul(inv, q[i + 1]))
                   + kf.quat_log(rot.quat_mul(inv, q[i - 1])))
        assert_quat_equal(s[i], rot.quat_mul(q[i], kf.quat_exp(-log_sum / 4)))
    assert_quat_equal(s[[0, -1]], q[[0, -1]])


def test_squad_on_a_single_axis_matches_the_catmull_rom_of_its_angle():
    """About one fixed axis rotations commute and squad is a curve in the angle alone; with
    the time-weighted controls its angular speed at an interior key is the Catmull-Rom
    tangent of the angle, (theta_{i+1} - theta_{i-1}) / (t_{i+1} - t_{i-1})."""
    angles = np.radians([0.0, 30.0, 45.0, 100.0, 110.0])
    q = rot.quat_from_axis_angle([0.0, 0.0, 1.0], angles)
    h = 1e-6
    x = TIMES[1:-1]
    w = kf.angular_velocity(kf.squad(q, TIMES, np.stack([x - h, x + h], axis=1)).swapaxes(0, 1),
                            np.array([0.0, 2 * h]))[0, :, 2]
    assert np.allclose(w, kf.catmull_rom(angles, TIMES, x, derivative=1), rtol=1e-5)


def test_angular_velocity_matches_scipy_rotvec_of_the_step():
    rng = np.random.default_rng(6)
    q = random_quats(rng, (10, 3))
    times = np.cumsum(rng.uniform(0.1, 0.3, size=10))
    w = kf.angular_velocity(q, times)
    r = scipy_rotation(q[1:]) * scipy_rotation(q[:-1]).inv()
    expected = r.as_rotvec().reshape(9, 3, 3) / np.diff(times)[:, None, None]
    assert np.allclose(w, expected, atol=1e-12)


def test_batched_joints_and_times():
    rng = np.random.default_rng(7)
    q = random_quats(rng, (len(TIMES), 6))
    t = np.linspace(0, 2, 12).reshape(3, 4)
    for scheme in (kf.slerp_keys, kf.squad):
        out = scheme(q, TIMES, t)
        assert out.shape == (3, 4, 6, 4)
        single = scheme(q[:, 2], TIMES, t)
        assert np.allclose(out[..., 2, :], single, atol=1e-12)


def test_log_exp_round_trip():
    rng = np.random.default_rng(8)
    q = rot.quat_canonical(random_quats(rng, (100,)))
    assert_quat_equal(kf.quat_exp(kf.quat_log(q)), q)
    assert np.allclose(kf.quat_log(q), Rotation.from_quat(q, scalar_first=True).as_rotvec() / 2)


@pytest.mark.parametrize(("args", "match"), [
    ((np.zeros((5, 4)), TIMES, 1.0), "q_keys: has zero length"),
    ((np.ones((5, 3)), TIMES, 1.0), r"q_keys: expected shape \(\.\.\., 4\)"),
    ((np.ones((4, 4)), TIMES, 1.0), r"q_keys: expected one key per time, shape \(5, \.\.\.\)"),
    ((np.ones((5, 4)), TIMES[::-1], 1.0), "times: must be strictly increasing"),
    ((np.ones((5, 4)), TIMES, 2.5), "t: 2.5 is outside the key times"),
    ((np.ones(4), TIMES[:1], 0.0), "times: need at least 2 keys"),
])
def test_bad_input_names_the_argument(args, match):
    for scheme in (kf.slerp_keys, kf.squad):
        with pytest.raises(ValueError, match=match):
            scheme(*args)


@settings(derandomize=True, max_examples=40, deadline=None)
@given(st.integers(2, 7), st.integers(0, 2**31 - 1), st.floats(5.0, 170.0))
def test_property_squad_hits_keys_unit_and_short(n, seed, step):
    rng = np.random.default_rng(seed)
    q = keys_along_a_path(rng, n, step)
    times = np.cumsum(rng.uniform(0.1, 1.0, size=n))
    t = np.linspace(times[0], times[-1], 97)
    out = kf.squad(q, times, t)
    assert np.allclose(np.linalg.norm(out, axis=-1), 1.0, atol=1e-12)
    assert_quat_equal(kf.squad(q, times, times), q, atol=1e-10)
    # Never farther from the segment's keys than the keys are from each other plus the
    # controls' detour (at most 90 degrees of rotation): no long way round.
    i = np.clip(np.searchsorted(times, t, side="right") - 1, 0, n - 2)
    off = rot.quat_angle(out, q[i]) - rot.quat_angle(q[i], q[i + 1])
    assert np.all(off <= np.pi / 2 + 1e-9)


def keys_turning_by(rng, angles_deg):
    """Keys from a random start, each turning by exactly ``angles_deg[i]`` (< 180) about a
    random axis from the one before, stored with random signs."""
    axes = rng.normal(size=(len(angles_deg), 3))
    steps = rot.quat_from_axis_angle(axes, np.radians(angles_deg))
    q = [random_quats(rng)]
    for s in steps:
        q.append(rot.quat_mul(s, q[-1]))
    return np.array(q) * rng.choice([-1.0, 1.0], size=(len(q), 1))


@pytest.mark.parametrize("apart", [118.0, 122.0, 170.0])
def test_squad_through_keys_far_apart_turns_straight_there_and_is_c1(apart):
    """Keys 0, apart, 0 degrees about z: the first segment climbs monotonically to the peak,
    with zero angular velocity there (Catmull-Rom tangent (0 - 0) / 2). Before the inner
    SLERP followed the stored controls, above ~120 degrees it went 0, 2.5, -13.8, 7.4, 122
    and the angular velocity jumped by 4 pi rad/s at the key."""
    q = rot.quat_from_axis_angle([0.0, 0.0, 1.0], np.radians([0.0, apart, 0.0]))
    times = np.array([0.0, 1.0, 2.0])
    t = np.linspace(0.0, 1.0, 201)
    angle = np.degrees(np.unwrap(2 * np.arctan2(*kf.squad(q, times, t)[:, [3, 0]].T)))
    assert np.all(np.diff(angle) > 0) and np.isclose(angle[-1], apart)
    assert kf.angular_velocity_jump(lambda x: kf.squad(q, times, x), 1.0) < 1e-5


@settings(derandomize=True, max_examples=60, deadline=None)
@given(st.integers(3, 6), st.integers(0, 2**31 - 1), st.floats(90.0, 179.0))
def test_property_squad_c1_and_through_the_keys_for_wide_turns(n, seed, widest):
    """C¹ at every interior key and through every key, for uneven times and turns between
    neighbouring keys up to 179 degrees (the old inner SLERP jumped by up to 60 rad/s)."""
    rng = np.random.default_rng(seed)
    q = keys_turning_by(rng, rng.uniform(0.0, widest, size=n - 1))
    times = np.cumsum(rng.uniform(0.2, 1.0, size=n))
    assert_quat_equal(kf.squad(q, times, times), q, atol=1e-10)
    jumps = speed_jumps(lambda t: kf.squad(q, times, t), times)
    assert jumps.max() < 1e-4, jumps


@settings(derandomize=True, max_examples=40, deadline=None)
@given(st.integers(2, 6), st.integers(0, 2**31 - 1), st.floats(-3.1, 3.1))
def test_property_squad_is_slerp_at_constant_angular_velocity(n, seed, speed):
    """Keys on one great circle, turning about one axis at one rate (turn_i = speed * h_i, up
    to 178 degrees): every control is its key and squad is SLERP, here scipy's Slerp."""
    rng = np.random.default_rng(seed)
    times = np.concatenate([[0.0], np.cumsum(rng.uniform(0.1, 1.0, size=n - 1))])
    q = rot.quat_mul(random_quats(rng), rot.quat_from_axis_angle(rng.normal(size=3),
                                                                 speed * times))
    q *= rng.choice([-1.0, 1.0], size=(n, 1))
    t = np.linspace(0.0, times[-1], 157)
    ref = Slerp(times, scipy_rotation(kf.same_hemisphere(q)))(t)
    assert_quat_equal(kf.squad(q, times, t), scipy_quat(ref, (157,)), atol=1e-10)


@settings(derandomize=True, max_examples=40, deadline=None)
@given(st.integers(0, 2**31 - 1))
def test_property_squad_of_two_keys_is_slerp(seed):
    """With two keys both controls are their keys and squad is SLERP, however far apart."""
    rng = np.random.default_rng(seed)
    q, times = random_quats(rng, (2,)), np.sort(rng.uniform(-2.0, 2.0, size=2))
    t = np.linspace(*times, 57)
    ref = Slerp(times, scipy_rotation(kf.same_hemisphere(q)))(t)
    assert_quat_equal(kf.squad(q, times, t), scipy_quat(ref, (57,)), atol=1e-10)


@settings(derandomize=True, max_examples=40, deadline=None)
@given(st.integers(2, 7), st.integers(0, 2**31 - 1), st.sampled_from([-1.0, 1.0]))
def test_property_squad_about_one_axis_is_monotone(n, seed, sense):
    """About one axis squad is the cubic Hermite spline of the angle with Catmull-Rom
    tangents; for equally spaced times and turns of one sense within a factor 5 of each other
    (30 to 150 degrees) the tangent-to-secant ratios stay in [0, 3], so by Fritsch and
    Carlson's criterion the angle never turns back, however far apart the keys are."""
    rng = np.random.default_rng(seed)
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    angles = sense * np.radians(np.concatenate([[0.0], np.cumsum(rng.uniform(30, 150, n - 1))]))
    q = rot.quat_from_axis_angle(axis, angles)
    t = np.linspace(0.0, n - 1.0, 100 * n)
    w = kf.angular_velocity(kf.squad(q, np.arange(float(n)), t), t)
    assert np.allclose(np.cross(w, axis), 0.0, atol=1e-9)  # about the axis only
    assert np.all(sense * w @ axis > -1e-9)
