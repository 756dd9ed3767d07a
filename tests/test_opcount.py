"""Counted arithmetic (:mod:`course.opcount`): counts checked against hand counts, values against
independent references (numpy, :mod:`course.rotations`, one iteration of :mod:`course.ik`)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import course.ik as ik
import course.rotations as rot
from course.opcount import (
    Counted,
    ccd_sweep,
    count_ops,
    counted,
    cross,
    dot,
    jacobian_iteration,
    norm,
    qmul,
    qrot,
    solve3,
    values,
)
from course.skeleton import chain

finite = st.floats(-10, 10, allow_nan=False)


def test_hand_count_of_a_small_expression():
    a, b, c = Counted(3.0), Counted(4.0), Counted(2.0)
    # (a + b) * c - a / b: +, *, /, - = 4 (a sign flip is free); then 2 squares, a sum, sqrt,
    # sin, cos, a product and a sum = 8
    result, ops = count_ops(lambda: -((a + b) * c - a / b))
    assert result.value == pytest.approx(-(7.0 * 2.0 - 0.75)) and ops == 4
    result, ops = count_ops(lambda: np.sqrt(a * a + b * b) + np.sin(c) * np.cos(c))
    assert result.value == pytest.approx(5.0 + math.sin(2) * math.cos(2)) and ops == 8


def test_plain_numbers_mix_in_from_either_side():
    a = Counted(6.0)
    for expression, expected in [(lambda: 2 * a, 12.0), (lambda: a * 2, 12.0),
                                 (lambda: 1 - a, -5.0), (lambda: a - 1, 5.0),
                                 (lambda: 3 / a, 0.5), (lambda: a / 3, 2.0),
                                 (lambda: 1.5 + a, 7.5), (lambda: np.float64(2) * a, 12.0)]:
        result, ops = count_ops(expression)
        assert (result.value, ops) == (expected, 1)


def test_an_unknown_operand_is_refused():
    with pytest.raises(TypeError):
        Counted(1.0) + "one"


def test_arrays_count_element_by_element():
    u, v = counted([1.0, 2.0, 3.0]), counted([4.0, 5.0, 6.0])
    assert count_ops(lambda: u @ v)[1] == 5          # 3 products, 2 sums
    assert count_ops(lambda: u + v)[1] == 3
    assert count_ops(dot, u, v)[1] == 5
    assert count_ops(cross, u, v)[1] == 9            # 6 products, 3 differences
    assert count_ops(norm, u)[1] == 6                # dot + sqrt
    # Hamilton product: w: 1 + 5 + 1; vector: 3 + 3 + 9 + 2 * 3 sums
    assert count_ops(qmul, counted([1, 2, 3, 4]), counted([5, 6, 7, 8]))[1] == 28
    assert values(u).dtype == np.float64 and values(u).tolist() == [1.0, 2.0, 3.0]
    assert values([Counted(1.0), 2.0]).tolist() == [1.0, 2.0]


@settings(derandomize=True, max_examples=40)
@given(st.lists(finite, min_size=6, max_size=6))
def test_vector_helpers_match_numpy(x):
    u, v = np.array(x[:3]), np.array(x[3:])
    assert np.allclose(values(cross(counted(u), counted(v))), np.cross(u, v))
    assert values(dot(counted(u), counted(v))) == pytest.approx(u @ v)
    assert values(norm(counted(u))) == pytest.approx(np.linalg.norm(u))


@settings(derandomize=True, max_examples=40)
@given(st.lists(finite, min_size=11, max_size=11))
def test_quaternion_helpers_match_course_rotations(x):
    a, b, v = np.array(x[:4]), np.array(x[4:8]), np.array(x[8:])
    if min(np.linalg.norm(a), np.linalg.norm(b)) < 1e-3:
        return
    a, b = a / np.linalg.norm(a), b / np.linalg.norm(b)
    assert np.allclose(values(qmul(counted(a), counted(b))), rot.quat_mul(a, b))
    assert np.allclose(values(qrot(counted(a), counted(v))), rot.quat_rotate(a, v))


def test_solve3_matches_numpy():
    rng = np.random.default_rng(0)
    A, b = rng.normal(size=(3, 3)) + 3 * np.eye(3), rng.normal(size=3)
    x, ops = count_ops(solve3, counted(A), counted(b))
    assert np.allclose(values(x), np.linalg.solve(A, b))
    # 4 determinants of 14 operations (9 products, 5 sums), 1 division, 3 products
    assert ops == 4 * 14 + 1 + 3


def _bent_snake(n=6, seed=1):
    # Bent well inside the reach, so that course.ik starts from this very pose (a target near
    # the full reach gets a reach-aware start: then one library iteration is not one step).
    snake = chain([1.0] * n)
    pose = rot.quat_from_axis_angle(np.random.default_rng(seed).normal(size=(n + 1, 3)), 0.8)
    pose[-1] = rot.quat_identity()
    P, _ = snake.forward_kinematics(pose)
    return snake, pose, P, P[-1] + np.array([0.3, -0.2, 0.25])


def test_ccd_sweep_is_one_iteration_of_course_ik():
    _, _, P, goal = _bent_snake()
    mine, ops = count_ops(ccd_sweep, counted(P), counted(goal))
    assert np.allclose(values(mine), ik.ccd_positions(P, goal, max_iter=1)[0], atol=1e-9)
    assert np.allclose(ccd_sweep(P, goal), values(mine))          # plain floats work too
    assert ops > 0


@pytest.mark.parametrize("method", ["jacobian_transpose", "pseudo_inverse", "dls"])
def test_jacobian_iteration_is_one_iteration_of_course_ik(method):
    snake, pose, _, goal = _bent_snake()
    damping = 0.5 if method == "dls" else 0.0
    R, ops = count_ops(jacobian_iteration, counted(pose), counted(snake.offsets),
                       counted(goal), method, damping)
    options = {"damping": damping} if method == "dls" else {}
    library = ik.solve(snake, pose, np.zeros(3), {"end_effector": goal}, method=method,
                       max_iter=1, tol=1e-12, **options)
    assert np.linalg.norm(goal) < 0.85 * snake.bone_lengths.sum()
    assert np.allclose(snake.forward_kinematics(values(R))[0], library.positions, atol=1e-9)
    assert ops > 0


def test_jacobian_iteration_names_a_bad_method():
    snake, pose, _, goal = _bent_snake()
    with pytest.raises(ValueError, match="method"):
        jacobian_iteration(pose, snake.offsets, goal, "newton")


@pytest.mark.parametrize("method", ["jacobian_transpose", "pseudo_inverse", "dls"])
def test_jacobian_iteration_with_the_effector_on_the_target_keeps_the_pose(method):
    # Every joint's step is zero: exp(0) R = R, where sin(angle/2)/angle was 0/0 (NaN).
    snake, pose, _, _ = _bent_snake()
    damping = 0.5 if method == "dls" else 0.0
    # The effector as the iteration's own forward kinematics places it (bit for bit), so the
    # error and with it every step is exactly zero.
    Q, e = pose[0], snake.offsets[0]
    for i in range(1, len(pose)):
        e, Q = e + qrot(Q, snake.offsets[i]), qmul(Q, pose[i])
    R, _ = count_ops(jacobian_iteration, counted(pose), counted(snake.offsets), counted(e),
                     method, damping)
    assert np.array_equal(values(R), pose)
    assert np.array_equal(jacobian_iteration(pose, snake.offsets, e, method, damping), pose)


def test_jacobian_iteration_zero_step_for_one_joint_only():
    # A target along the lever of the last joint's ball: its Jacobian columns see the error,
    # yet a zero-length turn on any joint must keep that joint's rotation exactly.
    snake, pose, P, goal = _bent_snake()
    R = jacobian_iteration(pose, snake.offsets, goal, "dls", 0.5)
    assert np.all(np.isfinite(R)) and np.array_equal(R[-1], pose[-1])


def test_ccd_sweep_with_the_target_on_the_effector_or_on_a_joint():
    _, _, P, _ = _bent_snake()
    assert np.allclose(values(count_ops(ccd_sweep, counted(P), counted(P[-1]))[0]), P,
                       atol=1e-12)
    # The target on joint 2's pivot: that joint has no direction and stays; the rest turn.
    mine = ccd_sweep(P, P[2])
    assert np.all(np.isfinite(mine))
    assert np.allclose(mine, ik.ccd_positions(P, P[2], max_iter=1)[0], atol=1e-9)
