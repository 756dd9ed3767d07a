"""Counted arithmetic (:mod:`course.opcount`): counts checked against hand counts, values against
independent references (numpy, :mod:`course.rotations`), and the counted IK iteration against
one iteration of :func:`course.ik.solve`, bit for bit."""

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
    atan2,
    count_iteration,
    count_ops,
    counted,
    cross,
    dot,
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


METHODS = ("fabrik", "ccd", "jacobian_transpose", "pseudo_inverse", "dls")


def _options(method):
    return {"damping": 0.5} if method == "dls" else {}


@pytest.mark.parametrize("method", METHODS)
def test_the_counted_iteration_is_one_iteration_of_course_ik_bit_for_bit(method):
    snake, pose, _, goal = _bent_snake()
    mine, ops = count_iteration(snake, pose, goal, method, **_options(method))
    library = ik.solve(snake, pose, np.zeros(3), {"end_effector": goal}, method=method,
                       max_iter=1, tol=1e-12, reach_start=False, **_options(method))
    assert np.linalg.norm(goal) < 0.85 * snake.bone_lengths.sum()
    assert np.array_equal(mine, library.positions)  # the library's own code, on other numbers
    assert ops > 0


@pytest.mark.parametrize("method", METHODS)
def test_an_iteration_costs_the_same_for_every_bone(method):
    # Each method visits every bone once per iteration with the same arithmetic: the count is
    # a + b n, so chains of 4, 6 and 8 bones differ by the same amount.
    counts = []
    for n in (4, 6, 8):
        snake, pose, _, goal = _bent_snake(n)
        counts.append(count_iteration(snake, pose, goal, method, **_options(method))[1])
    assert counts[2] - counts[1] == counts[1] - counts[0] > 0


@pytest.mark.parametrize("method", METHODS)
def test_no_iteration_runs_with_the_effector_on_the_target(method):
    snake, pose, P, _ = _bent_snake()
    mine, ops = count_iteration(snake, pose, P[-1], method, **_options(method))
    assert ops == 0 and np.allclose(mine, P, atol=1e-12)


def test_count_iteration_names_what_it_cannot_count():
    snake, pose, _, goal = _bent_snake()
    with pytest.raises(ValueError, match="chain solver.*'two_link'"):
        count_iteration(snake, pose, goal, "two_link")


def test_atan2_counts_one_operation_and_passes_floats():
    value, ops = count_ops(atan2, Counted(1.0), 1.0)
    assert value.value == pytest.approx(math.pi / 4) and ops == 1
    assert atan2(0.0, -1.0) == math.pi
