"""course.physics.walking (SIMBICON) and course.physics.stepping on the CMU character.

Figures measured on this build (docs/walking_control.md, benchmarks/walking.py): 20 strides
(40 steps) and 2.5 m in 12 s from rest, every step ended by the swing foot's contact; a push
of 0.1 s on the root survived at every instant of a stride up to 125 N forward, 269 N
backward, 500 N to the left (at 5 s alone: 169, 281, 606 N; survival is not monotonic in the
force); standing, stepping survives every push of 10, 20, ... N up to 160 N backward, 290
forward, 280 left and 190 right, where the balance alone survives 80, 150, 160 and 120 N.
Contact makes every run chaotic in its last digits, so the tests assert
with margin (15 strides; walking pushes at 55-80% of the stride-wide figure, each checked to
survive from 0.8x to 1.2x of its force and at 4.9-5.1 s; the stepping push in the middle of
its window) and never compare trajectories."""

from __future__ import annotations

import math

import numpy as np
import pytest

from course.physics.balance import bisect_push, push_direction

mujoco = pytest.importorskip(
    "mujoco", reason="MuJoCo is not installed (pip install 'course-kinematics[physics]')"
)

from course.physics.character import Push, qpos_from_motion  # noqa: E402
from course.physics.stepping import CaptureStep, stand_and_step  # noqa: E402
from course.physics.walking import (  # noqa: E402
    SIMBICON,
    Gait,
    body_parts,
    largest_push,
    neutral_pose,
    walk,
)

pytestmark = pytest.mark.usefixtures("mujoco_log_elsewhere")


@pytest.fixture(scope="module")
def walked(cmu):
    return walk(cmu, duration=12.0)


def test_body_parts_find_the_cmu_legs_and_arms(cmu) -> None:
    parts = body_parts(cmu)
    names = cmu.skeleton.names
    assert [names[j] for j in (parts.left.hip, parts.left.knee, parts.left.ankle)] == [
        "LeftUpLeg", "LeftLeg", "LeftFoot"]
    assert names[parts.right.pelvis] == "RHipJoint"
    # the upper arms, and the finger bases (the hands' longest sideways bone) turned down too
    assert {names[a] for a in parts.arms} == {"LeftArm", "RightArm", "LeftFingerBase",
                                              "RightFingerBase"}


def test_neutral_pose_stands_level_with_the_com_above_the_feet(cmu) -> None:
    pose = neutral_pose(cmu)
    positions, _ = pose.forward_kinematics()
    parts = body_parts(cmu)
    feet = [j for leg in parts.legs() for j in (leg.ankle, leg.toe)]
    assert np.allclose(positions[0, feet, 1], 0.0, atol=1e-5)  # flat, level, on the ground
    data = mujoco.MjData(cmu.model)
    data.qpos[:] = qpos_from_motion(cmu, pose)[0]
    mujoco.mj_forward(cmu.model, data)
    com_forward = -data.subtree_com[cmu.bodies[0]][1]  # z-up: forward is -y
    feet_forward = -np.mean([data.xpos[cmu.bodies[j]][1] for j in feet])
    assert abs(com_forward - feet_forward) < 1e-3


def test_walks_15_strides_in_12_seconds_with_no_root_force(walked) -> None:
    assert not walked.fell
    assert walked.strides >= 15  # measured 20
    assert walked.distance > 1.5  # measured 2.5 m
    assert np.all(walked.torques[:, :6] == 0.0)  # no hand of God, ever
    assert np.abs(walked.torques[:, 6:]).max() > 1.0  # it was driven
    sides = [f.side for f in walked.footsteps]
    assert all(a != b for a, b in zip(sides, sides[1:], strict=False))  # feet alternate
    # every step ended by a touch-down, not by max_swing_time (1 s): measured 0.28-0.38 s
    times = np.diff([0.0] + [f.time for f in walked.footsteps])
    assert times.max() < 0.6
    # the COM stays up: above 85% of its start height (measured 0.63-0.71 m of 0.69)
    assert walked.com[:, 1].min() > 0.85 * walked.com[0, 1]


@pytest.mark.parametrize(("direction", "force"), [((0.0, 0.0, 1.0), 100.0),
                                                   ((0.0, 0.0, -1.0), 150.0),
                                                   ((1.0, 0.0, 0.0), 300.0)])
def test_keeps_walking_after_a_push(cmu, direction, force) -> None:
    push = Push("Hips", np.array(direction) * force, start=5.0, duration=0.1)
    run = walk(cmu, duration=8.1, push=push)
    assert not run.fell
    assert np.all(run.torques[:, :6] == 0.0)
    after = [f for f in run.footsteps if f.time > 5.1]
    assert len(after) >= 6  # it went on stepping (measured 10)


def test_speed_input_changes_the_speed(cmu) -> None:
    def pace(speed: float) -> float:
        run = walk(cmu, duration=10.0, speed=speed)
        assert not run.fell
        d = run.com[-1] - run.com[240]  # from 4 s on
        return math.hypot(d[0], d[2]) / (run.sim_time - 4.0)

    slow, fast = pace(0.15), pace(0.3)  # measured 0.15 and 0.33 m/s
    assert fast > slow + 0.08


def test_stepping_recovers_a_push_that_fells_the_balance_alone(cmu) -> None:
    push = Push("Hips", (0.0, 0.0, -95.0), start=0.25, duration=0.1)  # backward
    without = stand_and_step(cmu, stepping=False, duration=2.35, push=push,
                             stop_when_fallen=True)
    stepped = stand_and_step(cmu, stepping=True, duration=2.35, push=push,
                             stop_when_fallen=True)
    assert without.fell  # the balance alone: survives 80 N, falls from 88 N on
    assert not stepped.fell  # stepping survives every 10 N up to 160 N
    assert len(stepped.steps) >= 1 and stepped.capture_points
    t, xi = stepped.capture_points[0]
    assert 0.35 < t < 1.0 and xi[1] < -0.05  # the step starts once xi is behind the feet
    assert stepped.steps[0].position[2] < -0.1  # and lands behind them
    assert np.all(stepped.torques[:, :6] == 0.0)


@pytest.mark.parametrize(("direction", "force"), [((0.0, 0.0, -1.0), 120.0),
                                                   ((0.0, 0.0, 1.0), 220.0),
                                                   ((1.0, 0.0, 0.0), 220.0),
                                                   ((-1.0, 0.0, 0.0), 150.0)])
def test_stepping_recovers_from_every_side(cmu, direction, force) -> None:
    # the balance alone survives 80 N backward, 150 forward, 160 left, 120 right; stepping
    # every 10 N up to 160, 290, 280, 190 N (benchmarks/walking.py); 0.9x and 1.1x of these
    # forces measured to behave the same
    push = Push("Hips", np.array(direction) * force, start=0.25, duration=0.1)
    without = stand_and_step(cmu, stepping=False, duration=2.35, push=push,
                             stop_when_fallen=True)
    stepped = stand_and_step(cmu, stepping=True, duration=2.35, push=push,
                             stop_when_fallen=True)
    assert without.fell and not stepped.fell
    first = stepped.steps[0].position  # the first step lands on the push's side (3-4 steps)
    k = 0 if direction[0] else 2
    assert first[k] * (direction[0] or direction[2]) > 0.25  # measured 0.33-0.56 m
    assert np.all(stepped.torques[:, :6] == 0.0)


def test_unpushed_standing_takes_no_step(cmu) -> None:
    run = stand_and_step(cmu, duration=1.5)
    assert not run.fell and run.steps == []


def test_bisect_push_finds_a_threshold_within_tol() -> None:
    calls = []

    def survives(force: np.ndarray) -> bool:
        calls.append(force)
        return float(np.linalg.norm(force)) < 237.0

    found = bisect_push(survives, (0.0, 0.0, -2.0), tol=5.0)
    assert 232.0 <= found < 237.0
    assert all(np.allclose(f[:2], 0.0) and f[2] <= 0.0 for f in calls)  # along direction
    assert bisect_push(lambda f: False, (1.0, 0.0, 0.0)) == 0.0
    assert bisect_push(lambda f: True, (1.0, 0.0, 0.0), max_force=1000.0) == 800.0
    assert np.allclose(push_direction((0.0, 3.0, 4.0)), (0.0, 0.6, 0.8))


def test_bad_arguments_name_themselves(cmu) -> None:
    with pytest.raises(ValueError, match="duration"):
        walk(cmu, duration=-1.0)
    with pytest.raises(ValueError, match="stance"):
        SIMBICON(cmu, stance="middle")
    with pytest.raises(ValueError, match="speed"):
        SIMBICON(cmu, speed=float("nan"))
    with pytest.raises(ValueError, match="heading"):
        SIMBICON(cmu, heading=float("inf"))
    with pytest.raises(ValueError, match="turn_rate"):
        SIMBICON(cmu, turn_rate=0.0)
    with pytest.raises(ValueError, match="Gait.lift_time"):
        Gait(lift_time=0.0)
    with pytest.raises(ValueError, match="Gait.gains"):
        Gait(gains={"elbow": (1.0, 1.0)})
    with pytest.raises(ValueError, match="direction"):
        largest_push(cmu, direction=(0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="start"):
        largest_push(cmu, start=[])
    with pytest.raises(ValueError, match="tol"):
        bisect_push(lambda f: True, (1.0, 0.0, 0.0), tol=0.0)
    with pytest.raises(ValueError, match="margin"):
        CaptureStep(cmu, margin=-1.0)
    with pytest.raises(ValueError, match="max_steps"):
        CaptureStep(cmu, max_steps=1.5)  # type: ignore[arg-type]
