"""course.physics.simulation and .controllers: one loop, controllers that supply only torques.

On the bundled sample (``wave.bvh``, 30 fps): ``track`` and ``stand`` are compositions of a
:class:`Simulation` and a controller, so a controller written here plugs into the same loop and
gives the same numbers bit for bit.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from course.bvh import load_bvh

mujoco = pytest.importorskip(
    "mujoco", reason="MuJoCo is not installed (pip install 'course-kinematics[physics]')"
)

from course.physics.balance import stand, standing_pose  # noqa: E402
from course.physics.character import (  # noqa: E402
    Y_TO_Z_MATRIX,
    Push,
    build_model,
    motion_from_qpos,
    qpos_from_motion,
    qvel_from_motion,
    track,
)
from course.physics.controllers import PD, Controller, StablePD  # noqa: E402
from course.physics.simulation import (  # noqa: E402
    STEP_RTOL,
    Fall,
    HeldRoot,
    Simulation,
    substeps,
)

SAMPLE = Path(__file__).resolve().parents[1] / "course" / "data" / "samples" / "wave.bvh"


pytestmark = pytest.mark.usefixtures("mujoco_log_elsewhere")


@pytest.fixture(scope="module")
def wave():
    return load_bvh(SAMPLE)


@pytest.fixture(scope="module")
def waver(wave):
    return build_model(wave.skeleton)


@pytest.fixture(scope="module")
def pose(waver):
    return standing_pose(waver)


class Zero(Controller):
    """No torques, through the interface."""

    def torques(self, sim, t):
        return np.zeros(sim.model.nv)


class HoldPose(Controller):
    """Joint PD to one pose written out here: what ``stand(controller="none")`` runs."""

    def __init__(self, target, kp, kd):
        self.target, self.kp, self.kd = target, kp, kd

    def reset(self, sim):
        self.err = np.zeros(sim.model.nv)

    def torques(self, sim, t):
        mujoco.mj_differentiatePos(sim.model, self.err, 1.0, sim.data.qpos, self.target)
        tau = self.err * self.kp
        tau -= self.kd * sim.data.qvel
        return tau


class Counting(Zero):
    """Zero torques; remembers every call."""

    def __init__(self):
        self.resets, self.calls = 0, []

    def reset(self, sim):
        self.resets += 1

    def torques(self, sim, t):
        self.calls.append((sim.frame, t, sim.data.xfrc_applied.copy()))
        return super().torques(sim, t)


# -- the step ---------------------------------------------------------------------------------


@pytest.mark.parametrize(("frame_time", "h", "n"), [
    (1 / 30, 1 / 600, 20), (1 / 60, 1 / 600, 10), (0.0083333, 1 / 600, 5),  # BVH-rounded 1/120
    (1 / 120, 1 / 120, 1), (1 / 120, 1 / 1200, 10)])
def test_a_step_that_divides_the_frame_gives_its_count(frame_time, h, n) -> None:
    assert substeps(frame_time, h) == n
    assert abs(frame_time / n - h) <= STEP_RTOL * h


@pytest.mark.parametrize(("frame_time", "h"), [
    (1 / 120, 1 / 300), (1 / 120, 1 / 60), (1 / 60, 1 / 500), (1 / 120, 1e-3)])
def test_a_step_that_does_not_divide_the_frame_is_refused_naming_h(frame_time, h) -> None:
    with pytest.raises(ValueError, match=r"^h: .*does not divide the frame time") as err:
        substeps(frame_time, h)
    assert f"{frame_time:.6g} s" in str(err.value)  # the frame time, and steps that divide it
    assert "h = frame_time / n" in str(err.value)


def test_track_and_stand_refuse_a_step_that_does_not_divide_their_frame(wave, waver, pose):
    with pytest.raises(ValueError, match=r"^h: .*0\.0333333 s"):  # 1/70 in a 1/30 s frame
        track(waver, wave, kp=100.0, kd=2.0, n_frames=3, h=1 / 70)
    with pytest.raises(ValueError, match=r"^h: .*0\.0166667 s"):  # 1/500 in a 1/60 s frame
        stand(waver, pose, duration=0.1, h=1 / 500)
    with pytest.raises(ValueError, match="^h: the time step must be a positive"):
        stand(waver, pose, duration=0.1, h=0.0)


def test_bad_arguments_are_named(waver, pose) -> None:
    qpos = qpos_from_motion(waver, pose)[0]
    with pytest.raises(ValueError, match="^frame_time"):
        Simulation(waver, qpos, frame_time=-1.0)
    with pytest.raises(ValueError, match="^torque_limit"):
        Simulation(waver, qpos, frame_time=1 / 60, torque_limit=-1.0)
    with pytest.raises(ValueError, match="^qpos"):
        Simulation(waver, qpos[:-1], frame_time=1 / 60)
    with pytest.raises(ValueError, match="^kp"):
        PD(qpos, kp=-1.0, kd=0.0)
    with pytest.raises(ValueError, match="^duration"):
        stand(waver, pose, duration=0.0)
    with pytest.raises(ValueError, match="^Fall.measure"):
        Fall("knee")
    sim = Simulation(waver, qpos, frame_time=1 / 60)
    for n_frames in (0, 2.0, True):
        with pytest.raises(ValueError, match="^n_frames: a whole number"):
            sim.run(None, n_frames)
    held = HeldRoot(np.tile(qpos[:7], (3, 1)), np.zeros((3, 6)))
    with pytest.raises(ValueError, match="^n_frames: 4 frames, but the held root has 3"):
        Simulation(waver, qpos, frame_time=1 / 60, held_root=held).run(None, 4)


# -- controllers plug in ------------------------------------------------------------------------


def test_a_custom_controller_gives_what_stand_none_gives(waver, pose) -> None:
    target = qpos_from_motion(waver, pose)[0]
    push = Push(waver.skeleton.names[0], (0.0, 0.0, 80.0), 0.2, 0.1)
    ref = stand(waver, pose, controller="none", duration=0.5, kp=1000.0, kd=5.0,
                torque_limit=400.0, push=push)
    sim = Simulation(waver, target, frame_time=1 / 60, h=1 / 600, torque_limit=400.0,
                     push=push)
    record = sim.run(HoldPose(target, 1000.0, 5.0), n_frames=ref.motion.n_frames)
    again = stand(waver, pose, controller="none", duration=0.5, push=push)
    assert np.array_equal(record.torques[:, 6:], ref.torques)
    assert np.array_equal(record.com @ Y_TO_Z_MATRIX, ref.com)
    assert np.array_equal(again.motion.local_rotations, ref.motion.local_rotations)
    # the built-in PD controller is the same law
    pd = Simulation(waver, target, frame_time=1 / 60, torque_limit=400.0, push=push).run(
        PD(target, 1000.0, 5.0), n_frames=ref.motion.n_frames)
    assert np.array_equal(pd.qpos, record.qpos)


def test_zero_torques_are_the_passive_ragdoll(waver, pose) -> None:
    ref = stand(waver, pose, controller="none", duration=0.5, torques=False)
    target = qpos_from_motion(waver, pose)[0]
    zero = Simulation(waver, target, frame_time=1 / 60).run(Zero(), ref.motion.n_frames)
    none = Simulation(waver, target, frame_time=1 / 60).run(None, ref.motion.n_frames)
    assert np.array_equal(zero.qpos, none.qpos)
    assert np.array_equal(none.com @ Y_TO_Z_MATRIX, ref.com)
    assert not zero.torques.any()


def test_track_is_pd_on_the_clip_with_the_root_held(wave, waver) -> None:
    clip = wave[:10]
    qref, vref = qpos_from_motion(waver, clip), qvel_from_motion(waver, clip)
    ref = track(waver, wave, kp=300.0, kd=3.5, n_frames=10, hold_root=True, stable_pd=True)
    record = Simulation(waver, qref[0], vref[0], frame_time=wave.frame_time,
                        held_root=HeldRoot(qref[:, :7], vref[:, :6])).run(
        StablePD(qref, 300.0, 3.5), n_frames=10)
    assert np.array_equal(record.qpos[:, 2], ref.root_height)
    assert np.array_equal(record.qpos[:, :7], qref[:, :7])  # the root on the clip


def test_the_root_is_never_actuated_and_torques_are_clipped(waver, pose) -> None:
    class Huge(Controller):
        def torques(self, sim, t):
            return np.full(sim.model.nv, 1e6)

    target = qpos_from_motion(waver, pose)[0]
    record = Simulation(waver, target, frame_time=1 / 60, torque_limit=7.5).run(Huge(), 3)
    assert not record.torques[:, :6].any()
    assert np.all(record.torques[1:, 6:] == 7.5)


def test_a_controller_of_the_wrong_shape_is_named(waver, pose) -> None:
    class Short(Controller):
        def torques(self, sim, t):
            return np.zeros(3)

    target = qpos_from_motion(waver, pose)[0]
    with pytest.raises(ValueError, match="^controller: torques of shape"):
        Simulation(waver, target, frame_time=1 / 60).run(Short(), 3)


# -- the frame: recording, on_frame, pushes -------------------------------------------------


def test_on_frame_and_the_controller_are_called_once_per_frame_and_step(waver, pose) -> None:
    target = qpos_from_motion(waver, pose)[0]
    root = waver.skeleton.names[0]
    push = Push(root, (0.0, 0.0, 50.0), start=0.1, duration=0.05)
    seen = []
    sim = Simulation(waver, target, frame_time=1 / 60, h=1 / 300, push=push,
                     on_frame=lambda i, frame: seen.append((i, frame)), name="probe")
    law = Counting()
    record = sim.run(law, n_frames=13)
    assert sim.substeps == 5 and record.h == pytest.approx(1 / 300)
    assert law.resets == 1 and len(law.calls) == 12 * 5
    assert [i for i, _ in seen] == list(range(1, 13)) and record.n_frames == 13
    for i, frame in seen:  # frame i as a Motion, the recording's row i
        assert frame.n_frames == 1 and frame.name == "probe"
        row = motion_from_qpos(waver, record.qpos[i : i + 1], 1 / 60)
        assert np.array_equal(frame.local_rotations, row.local_rotations)
        assert np.array_equal(frame.root_positions, row.root_positions)
    frames = [f for f, _, _ in law.calls]
    assert frames == [i for i in range(1, 13) for _ in range(5)]  # the frame being stepped to
    times = np.array([t for _, t, _ in law.calls])
    assert np.allclose(times, np.arange(60) / 300, atol=1e-15)
    body = waver.bodies[0]
    pushed = np.array([np.any(x[body, :3] != 0) for _, _, x in law.calls])
    mids = times + 0.5 / 300
    assert np.array_equal(pushed, (mids >= 0.1) & (mids < 0.15)) and pushed.sum() == 15
    assert record.sim_time == pytest.approx(12 / 60) and record.reason == "end"


def test_before_frame_is_called_once_per_frame_before_its_steps(waver, pose) -> None:
    class Log(Zero):
        def __init__(self):
            self.log = []

        def before_frame(self, sim):
            self.log.append(("frame", sim.frame, sim.data.qpos.copy()))

        def torques(self, sim, t):
            self.log.append(("step", sim.frame, None))
            return super().torques(sim, t)

    target = qpos_from_motion(waver, pose)[0]
    law = Log()
    record = Simulation(waver, target, frame_time=1 / 60, h=1 / 300).run(law, n_frames=4)
    assert [(kind, i) for kind, i, _ in law.log] == [
        (kind, i) for i in (1, 2, 3) for kind in ("frame", *["step"] * 5)]
    for _, i, qpos in (entry for entry in law.log if entry[0] == "frame"):
        assert np.array_equal(qpos, record.qpos[i - 1])  # the state the last frame ended in


def test_step_by_step_is_run(waver, pose) -> None:
    target = qpos_from_motion(waver, pose)[0]
    law = PD(target, 500.0, 5.0)
    sim = Simulation(waver, target, frame_time=1 / 60)
    law.reset(sim)
    for _ in range(6):
        assert sim.step(law) is None
    assert sim.frame == 6 and sim.time == pytest.approx(0.1)
    whole = Simulation(waver, target, frame_time=1 / 60).run(PD(target, 500.0, 5.0), 7)
    assert np.array_equal(sim.recording().qpos, whole.qpos)


# -- stop reasons ---------------------------------------------------------------------------


def test_a_fall_stops_the_run_when_asked(waver, pose) -> None:
    target = qpos_from_motion(waver, pose)[0]
    go_on = Simulation(waver, target, frame_time=1 / 60, fall=Fall("com", fraction=0.9)).run(
        None, 61)
    assert go_on.reason == "end" and go_on.n_frames == 61 and go_on.fall_time is not None
    sim = Simulation(waver, target, frame_time=1 / 60, fall=Fall("com", fraction=0.9, stop=True))
    stopped = sim.run(None, 61)
    assert stopped.reason == "fell" and stopped.fall_time == go_on.fall_time
    assert stopped.n_frames - 1 == round(stopped.fall_time * 60)  # ends at the fallen frame
    assert stopped.com[-1, 2] < 0.9 * stopped.com[0, 2] <= stopped.com[-2, 2]
    assert np.array_equal(stopped.qpos, go_on.qpos[: stopped.n_frames])
    with pytest.raises(RuntimeError, match="stopped"):
        sim.step(None)
    root = Simulation(waver, target, frame_time=1 / 60, fall=Fall("root", height=10.0)).run(
        None, 3)
    assert root.fall_time == pytest.approx(1 / 60)  # below 10 m at once


def test_divergence_is_flagged_and_stops_when_asked(wave, waver) -> None:
    clip = wave[:31]
    qref, vref = qpos_from_motion(waver, clip), qvel_from_motion(waver, clip)
    held = HeldRoot(qref[:, :7], vref[:, :6])

    def sim(stop: bool) -> Simulation:
        return Simulation(waver, qref[0], vref[0], frame_time=wave.frame_time, h=1 / 600,
                          held_root=held, stop_when_diverged=stop)

    go_on = sim(False).run(PD(qref, 1e6, 0.0), 31)  # kp h^2 / I_min ~ 300, far beyond 4
    stopped = sim(True).run(PD(qref, 1e6, 0.0), 31)
    assert go_on.unstable and go_on.reason == "end" and go_on.n_frames == 31
    assert stopped.unstable and stopped.reason == "diverged" and stopped.n_frames < 31
    calm = sim(True).run(PD(qref, 100.0, 2.0), 31)
    assert not calm.unstable and calm.reason == "end"
