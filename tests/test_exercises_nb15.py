"""Notebook 15's exercises against the package's own walking functions: the references of
15.capture_point and 15.zmp_from_forces agree with course.physics.lip and course.physics.zmp,
and 15.swing_hip_target's feedback points along the heading. (Solved by the reference and
every named mistake caught: tests/test_exercises.py, which runs every notebook's.)"""

from __future__ import annotations

import numpy as np
import pytest

from course.exercises import check, exercise, reference
from course.physics import lip, zmp

RNG = np.random.default_rng(15)


@pytest.mark.parametrize("k", range(5))
def test_capture_point_is_the_lip_one_with_the_height_above_the_ground(k):
    ground = RNG.uniform(-0.5, 0.5)
    com = np.array([RNG.uniform(-1, 1), ground + RNG.uniform(0.5, 1.0), RNG.uniform(-1, 1)])
    v = RNG.normal(size=3)
    xi = reference("15.capture_point")(com, v, ground)
    w0 = lip.natural_frequency(com[1] - ground)
    np.testing.assert_allclose(xi, lip.capture_point(com[[0, 2]], v[[0, 2]], w0), atol=1e-12)
    # a foot there: zero orbital energy on each axis, the pendulum comes to rest over it
    np.testing.assert_allclose(lip.orbital_energy(com[[0, 2]], v[[0, 2]], xi, w0), 0, atol=1e-9)


@pytest.mark.parametrize("k", range(5))
def test_zmp_from_forces_is_the_package_one(k):
    n = 4
    ground = RNG.uniform(-0.2, 0.2)
    r = np.column_stack([RNG.uniform(-0.3, 0.3, n), ground + RNG.uniform(0, 0.1, n),
                         RNG.uniform(-0.3, 0.3, n)])
    f = np.column_stack([RNG.normal(scale=30, size=n), RNG.uniform(50, 300, n),
                         RNG.normal(scale=30, size=n)])
    np.testing.assert_allclose(reference("15.zmp_from_forces")(r, f, ground),
                               zmp.zmp_from_forces(r, f, ground_height=ground), atol=1e-12)


def test_zmp_of_contacts_on_the_ground_is_the_weighted_mean():
    r = np.array([[0.0, 0.0, 0.0], [0.2, 0.0, 0.4]])
    f = np.array([[30.0, 100.0, -5.0], [0.0, 300.0, 9.0]])
    np.testing.assert_allclose(reference("15.zmp_from_forces")(r, f, 0.0), [0.15, 0.0, 0.3])


def test_swing_hip_feedback_along_the_heading():
    ref = reference("15.swing_hip_target")
    ankle = np.array([1.0, 0.0, 1.0])
    ahead_x = np.array([1.1, 0.7, 1.0])  # 10 cm along +x: ahead at heading π/2, beside at 0
    assert ref(0.3, 1.0, 0.0, ahead_x, np.zeros(3), ankle, np.pi / 2) == pytest.approx(0.4)
    assert ref(0.3, 1.0, 0.0, ahead_x, np.zeros(3), ankle, 0.0) == pytest.approx(0.3)
    # falling forward (d, v > 0) swings the leg further forward
    assert ref(0.3, 0.5, 0.2, ahead_x, np.array([0.5, 0, 0]), ankle, np.pi / 2) > 0.3


@pytest.mark.parametrize("key", ["15.capture_point", "15.swing_hip_target",
                                 "15.zmp_from_forces"])
def test_the_issue_s_named_mistakes_are_named(key):
    named = {"15.capture_point": "omega_wrong_height", "15.swing_hip_target": "feedback_signs",
             "15.zmp_from_forces": "moment_sign"}[key]
    m = next(m for m in exercise(key).mistakes if m.key == named)
    feedback = check(key, lambda *a: m.wrong(*a))
    assert feedback.status == "fail" and m.title in feedback.text, feedback.text
