"""Swing-twist decomposition and the cone + twist-range projection, checked against scipy."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from rotation_asserts import assert_quat_equal, random_quats, relative_angle, scipy_rotation

from course.rotations import (
    clamp_swing_twist,
    quat_from_axis_angle,
    quat_mul,
    quat_rotate,
    swing_angle,
    swing_twist,
    twist_angle,
)

PROPERTY = settings(max_examples=80, derandomize=True, deadline=None, database=None,
                    suppress_health_check=[HealthCheck.too_slow])

coord = st.floats(-1.0, 1.0, allow_nan=False, allow_infinity=False)
axes = st.tuples(coord, coord, coord).map(np.array).filter(lambda v: np.linalg.norm(v) > 1e-2)
quats = st.tuples(coord, coord, coord, coord).map(np.array).filter(
    lambda q: np.linalg.norm(q) > 1e-2).map(lambda q: q / np.linalg.norm(q))
limits = st.tuples(st.floats(0.0, np.pi), st.floats(-np.pi, np.pi), st.floats(-np.pi, np.pi))


def _unit(v):
    return np.asarray(v, float) / np.linalg.norm(v, axis=-1, keepdims=True)


def _apart(a, b):
    """How far apart angles ``a`` and ``b`` are round the circle, in [0, pi]."""
    d = abs(a - b) % (2 * np.pi)
    return min(d, 2 * np.pi - d)


def _off_range(theta, lo, hi):
    """How far round the circle ``theta`` is from the arc [lo, hi]: 0 on it (as theta, or as
    theta +- 2 pi), else the distance to the nearer bound."""
    if any(lo <= theta + k * 2 * np.pi <= hi for k in (-1, 0, 1)):
        return 0.0
    return min(_apart(theta, lo), _apart(theta, hi))


@PROPERTY
@given(quats, axes)
def test_recomposes_twist_about_axis_swing_perpendicular(q, axis):
    swing, twist = swing_twist(q, axis)
    a = _unit(axis)
    assert_quat_equal(quat_mul(swing, twist), q, atol=1e-12)
    # The twist keeps the axis; its rotation vector (scipy) is parallel to it.
    np.testing.assert_allclose(quat_rotate(twist, a), a, atol=1e-12)
    rv = scipy_rotation(twist).as_rotvec()[0]
    assert np.linalg.norm(np.cross(rv, a)) < 1e-9
    # The swing's axis is perpendicular to the twist axis, and it moves a where q does.
    assert abs(np.dot(swing[1:], a)) < 1e-12
    np.testing.assert_allclose(quat_rotate(swing, a), quat_rotate(q, a), atol=1e-12)
    assert swing[0] >= 0 and twist[0] >= 0


@PROPERTY
@given(quats, axes)
def test_angles_match_scipy(q, axis):
    swing, twist = swing_twist(q, axis)
    a = _unit(axis)
    # Swing angle is the angle between a and q a; the two angles are those of the parts.
    qa = quat_rotate(q, a)
    expected_swing = np.arctan2(np.linalg.norm(np.cross(a, qa)), np.dot(a, qa))
    assert abs(swing_angle(q, axis) - expected_swing) < 1e-7
    assert abs(swing_angle(q, axis) - scipy_rotation(swing).magnitude()[0]) < 1e-7
    theta = twist_angle(q, axis)
    assert -np.pi <= theta <= np.pi
    assert_quat_equal(quat_from_axis_angle(a, theta), twist, atol=1e-12)


def test_batched_and_broadcast_against_scalar_calls():
    rng = np.random.default_rng(15)
    q = random_quats(rng, (5, 3))
    axis = _unit(rng.normal(size=(3, 3)))
    swing, twist = swing_twist(q, axis)
    assert swing.shape == twist.shape == (5, 3, 4)
    assert twist_angle(q, axis).shape == swing_angle(q, axis).shape == (5, 3)
    for i in range(5):
        for j in range(3):
            s, t = swing_twist(q[i, j], axis[j])
            np.testing.assert_allclose(swing[i, j], s, atol=1e-15)
            np.testing.assert_allclose(twist[i, j], t, atol=1e-15)


def test_pure_swing_and_pure_twist():
    a = np.array([0.0, 1.0, 0.0])
    pure_twist = quat_from_axis_angle(a, 1.1)
    s, t = swing_twist(pure_twist, a)
    assert_quat_equal(s, [1, 0, 0, 0])
    assert_quat_equal(t, pure_twist)
    pure_swing = quat_from_axis_angle([1.0, 0.0, 0.0], 0.7)
    s, t = swing_twist(pure_swing, a)
    assert_quat_equal(s, pure_swing)
    assert_quat_equal(t, [1, 0, 0, 0])
    assert twist_angle(-pure_twist, a) == pytest.approx(1.1)  # q and -q agree


@pytest.mark.parametrize("twist", [0.0, 0.4, -2.0, np.pi])
def test_half_turn_swing_singularity_gives_identity_twist(twist):
    a = np.array([0.0, 0.0, 1.0])
    # A half-turn swing about x followed by any twist about z: w and v.a are both 0 when the
    # twist is 0; otherwise the decomposition is still exact.
    q = quat_mul(quat_from_axis_angle([1.0, 0.0, 0.0], np.pi), quat_from_axis_angle(a, twist))
    s, t = swing_twist(q, a)
    assert_quat_equal(quat_mul(s, t), q, atol=1e-12)
    assert swing_angle(q, a) == pytest.approx(np.pi)
    np.testing.assert_allclose(quat_rotate(s, a), -a, atol=1e-12)
    exact = quat_mul(quat_from_axis_angle([1.0, 0.0, 0.0], np.pi), [1.0, 0.0, 0.0, 0.0])
    s0, t0 = swing_twist(exact, a)
    assert_quat_equal(t0, [1, 0, 0, 0], atol=0)
    assert twist_angle(exact, a) == 0.0
    assert np.all(np.isfinite(s0))


@PROPERTY
@given(quats, axes, limits)
def test_clamp_is_within_limits_idempotent_and_keeps_allowed(q, axis, lim):
    cone, t0, t1 = lim
    lo, hi = min(t0, t1), max(t0, t1)
    c = clamp_swing_twist(q, axis, cone, (lo, hi))
    assert abs(np.linalg.norm(c) - 1) < 1e-12
    assert swing_angle(c, axis) <= cone + 1e-9
    assert _off_range(twist_angle(c, axis), lo, hi) < 1e-9 or swing_angle(c, axis) > np.pi - 1e-6
    assert_quat_equal(clamp_swing_twist(c, axis, cone, (lo, hi)), c, atol=1e-9)
    allowed = (swing_angle(q, axis) <= cone) and _off_range(twist_angle(q, axis), lo, hi) == 0
    if allowed:
        assert_quat_equal(c, q, atol=1e-12)


@PROPERTY
@given(quats, axes, limits)
def test_clamp_picks_the_nearest_swing_and_twist(q, axis, lim):
    cone, t0, t1 = lim
    lo, hi = min(t0, t1), max(t0, t1)
    c = clamp_swing_twist(q, axis, cone, (lo, hi))
    a = _unit(axis)
    # The bone direction is pulled straight towards the axis: same plane, angle min(., cone).
    qa, ca = quat_rotate(q, a), quat_rotate(c, a)
    if np.linalg.norm(np.cross(a, qa)) > 1e-6:
        assert abs(np.dot(np.cross(a, qa), ca)) < 1e-9
    assert swing_angle(c, axis) == pytest.approx(min(swing_angle(q, axis), cone), abs=1e-9)
    if swing_angle(q, axis) < np.pi - 1e-6:  # the nearest allowed twist, round the circle
        theta = twist_angle(q, axis)
        assert _off_range(twist_angle(c, axis), lo, hi) < 1e-9
        assert _apart(twist_angle(c, axis), theta) == pytest.approx(_off_range(theta, lo, hi),
                                                                    abs=1e-9)


@pytest.mark.parametrize(("theta", "twist_range", "expected"), [
    (-3.0, (-0.5, 3.0), 3.0),  # 0.28 round through -pi; -0.5 is 2.5 away
    (-2.0, (-0.5, 3.0), 3.0),  # 1.28 against 1.5
    (-1.5, (-0.5, 3.0), -0.5),  # 1.0 against 1.78
    (np.pi, (-np.pi, -3.0), np.pi),  # pi is -pi, on the arc: unchanged
    (2.9, (-np.pi, -3.0), -np.pi),  # 0.24 to -pi, through pi
])
def test_clamp_twist_goes_to_the_nearer_bound_round_the_circle(theta, twist_range, expected):
    a = np.array([0.3, -0.4, 1.2])
    swing = quat_from_axis_angle(np.cross(a, [1.0, 0.0, 0.0]), 0.4)  # inside the cone
    q = quat_mul(swing, quat_from_axis_angle(a, theta))
    c = clamp_swing_twist(q, a, 1.0, twist_range)
    assert_quat_equal(c, quat_mul(swing, quat_from_axis_angle(a, expected)), atol=1e-12)


def test_clamp_example_shoulder_cone():
    a = np.array([1.0, 0.0, 0.0])  # an arm along +x
    q = quat_mul(quat_from_axis_angle([0, 0, 1], np.radians(120)),
                 quat_from_axis_angle(a, np.radians(80)))
    c = clamp_swing_twist(q, a, np.radians(90), (np.radians(-45), np.radians(45)))
    expected = quat_mul(quat_from_axis_angle([0, 0, 1], np.radians(90)),
                        quat_from_axis_angle(a, np.radians(45)))
    assert_quat_equal(c, expected, atol=1e-12)
    assert float(relative_angle(c, q)) > 0


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        (dict(max_swing=-0.1, twist_range=(0, 1)), "max_swing"),
        (dict(max_swing=4.0, twist_range=(0, 1)), "max_swing"),
        (dict(max_swing=1.0, twist_range=(1, 0)), "twist_range"),
        (dict(max_swing=1.0, twist_range=(-4, 0)), "twist_range"),
        (dict(max_swing=1.0, twist_range=0.5), "twist_range"),
        (dict(max_swing=np.nan, twist_range=(0, 1)), "max_swing"),
    ],
)
def test_clamp_rejects_bad_limits(kwargs, message):
    with pytest.raises(ValueError, match=message):
        clamp_swing_twist([1, 0, 0, 0], [1, 0, 0], **kwargs)


def test_bad_inputs_name_the_argument():
    with pytest.raises(ValueError, match="axis"):
        swing_twist([1, 0, 0, 0], [0, 0, 0])
    with pytest.raises(ValueError, match="q"):
        swing_twist([0, 0, 0, 0], [1, 0, 0])
    with pytest.raises(ValueError, match="q.*axis|axis.*q"):
        swing_twist(np.tile([1.0, 0, 0, 0], (3, 1)), np.ones((2, 3)))
