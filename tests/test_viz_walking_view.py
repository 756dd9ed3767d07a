"""Notebook 15's live walking view: a SIMBICON walk of the CMU character simulated and drawn
frame by frame, its footprints and capture point on the ground, sliders acting on the walk."""

from __future__ import annotations

import copy

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")
pytest.importorskip("ipywidgets")
pytest.importorskip("pyvista")

from course import data  # noqa: E402
from course.physics.character import build_model  # noqa: E402
from course.physics.lip import capture_point, natural_frequency  # noqa: E402
from course.physics.model import motion_from_qpos  # noqa: E402
from course.physics.walking import Gait, walk  # noqa: E402
from course.viz.walking_view import WINDOW, WalkingSimulator, walking_simulator  # noqa: E402


@pytest.fixture(scope="module")
def character():
    return build_model(data.load("cmu_12_01_walk")[1:].skeleton)


@pytest.fixture
def view(character):
    v = walking_simulator(character)
    yield v
    v.close()


def _y_up(v):
    return np.array([v[0], v[2], -v[1]])


def test_play_simulates_and_draws_each_tick(view, character):
    assert view.time == 0.0 and view.scene.footprints == []
    png = view.scene._image.value
    for k in range(1, 6):  # the play widget's ticks, as the browser sends them
        view.play.value = k
    assert view.time > 0.0
    assert view.scene._image.value != png  # the static picture was drawn again
    view.advance(150)
    assert view.sim.frame == round(view.time / view.frame_time)
    # the drawn walker is the simulation's last frame
    pose = motion_from_qpos(character, view.sim.data.qpos[None], view.frame_time)
    np.testing.assert_allclose(view.scene.joint_positions, pose.forward_kinematics()[0][0])
    # the camera followed the root
    root = view.scene.joint_positions[0]
    focal = np.array(view.scene.plotter.camera.focal_point)
    assert abs(focal[2] - root[2]) < 0.5 / character.scale
    assert "strides walked" in view.readout.value


def test_footprints_are_the_touch_downs(view, character):
    view.advance(180)  # 3 s from rest
    steps = view.footsteps
    prints = view.scene.footprints
    assert len(steps) >= 6 and len(prints) == len(steps)
    for step, (side, p) in zip(steps, prints, strict=True):
        assert side == step.side
        np.testing.assert_allclose(p[[0, 2]], step.position[[0, 2]] / character.scale)
    left = sum(s.side == "left" for s in steps)
    assert view.scene.footprint_corners("left").shape == (4 * left, 3)
    assert view.scene.footprint_corners("right").shape == (4 * (len(steps) - left), 3)
    # drawn on the floor, which is the simulated floor (z = -foot radius in MuJoCo)
    floor = float(character.model.geom("floor").pos[2])
    assert view.ground_height == pytest.approx(floor)
    corners = view.scene.footprint_corners("left")
    assert np.all(np.abs(corners[:, 1] * character.scale - floor) < 0.01)
    view.reset()
    assert view.time == 0.0 and view.scene.footprints == []
    assert view.scene.footprint_corners("left").shape == (0, 3)


def test_capture_point_is_the_lip_capture_point_of_the_state(view, character):
    view.advance(100)
    # the state from MuJoCo directly, the velocity by another route (mj_subtreeVel on a copy)
    d = copy.copy(view.sim.data)
    mujoco.mj_comVel(view.sim.model, d)
    mujoco.mj_subtreeVel(view.sim.model, d)
    root = character.bodies[0]
    c, v = _y_up(d.subtree_com[root]), _y_up(d.subtree_linvel[root])
    floor = float(character.model.geom("floor").pos[2])
    xi = capture_point(c[[0, 2]], v[[0, 2]], natural_frequency(c[1] - floor))
    np.testing.assert_allclose(view.com, c, atol=1e-12)
    np.testing.assert_allclose(view.com_velocity, v, atol=1e-9)
    np.testing.assert_allclose(view.capture_point, xi, atol=1e-9)
    # drawn there, on the ground, and the COM's marker under the COM
    np.testing.assert_allclose(view.scene.capture_marker[[0, 2]], xi / character.scale,
                               atol=1e-9)
    np.testing.assert_allclose(view.scene.com_marker[[0, 2]], c[[0, 2]] / character.scale)
    assert view.scene.capture_marker[1] == pytest.approx(view.scene.com_marker[1])
    assert abs(view.scene.capture_marker[1] * character.scale - floor) < 0.02
    assert np.linalg.norm(xi - c[[0, 2]]) > 0.01  # it walks: ξ is not under the COM


def test_the_walk_is_walks_own(character):
    """With the sliders' gait and speed, the view simulates what walk() does, bit for bit."""
    view = WalkingSimulator(character, speed=0.2)
    view.sliders["c_v"].value = 0.5  # before it walks: reset takes it
    view.reset()
    view.advance(120)
    run = walk(character, duration=2.0, gait=Gait(c_v=0.5), speed=0.2)
    np.testing.assert_array_equal(view.com, run.com[-1])
    assert len(view.footsteps) == len(run.footsteps)
    view.close()


def test_sliders_act_on_the_walk_as_it_goes(character):
    views = [WalkingSimulator(character), WalkingSimulator(character)]
    for v in views:
        v.advance(60)
    changed = views[1]
    changed.sliders["speed"].value = 0.3
    changed.sliders["c_d"].value = 0.5
    changed.sliders["c_v"].value = 0.6
    changed.sliders["swing_hip_lift"].value = 0.5
    changed.sliders["swing_hip_down"].value = 0.4
    assert changed.time == pytest.approx(1.0)  # the walk goes on, not restarted
    g = changed.controller.gait
    assert (g.c_d, g.c_v, g.swing_hip) == (0.5, 0.6, (0.5, 0.4))
    assert changed.controller.speed == 0.3
    changed.sliders["speed"].value = 0.0
    assert changed.controller.speed is None  # 0: SIMBICON's own c_v v
    np.testing.assert_array_equal(views[0].com, changed.com)  # nothing simulated yet
    for v in views:
        v.advance(30)
    assert np.linalg.norm(views[0].com - changed.com) > 1e-3
    g0, default = views[0].controller.gait, Gait()  # the other walk kept its gait
    assert (g0.c_d, g0.c_v, g0.swing_hip) == (default.c_d, default.c_v, default.swing_hip)
    for v in views:
        v.close()


def test_push_shoves_the_root_for_its_duration(character):
    views = [WalkingSimulator(character), WalkingSimulator(character, push=300.0,
                                                          push_direction=90.0)]
    for v in views:
        v.advance(90)
    pushed = views[1]
    force = pushed.push_force()
    np.testing.assert_allclose(force, [300.0, 0.0, 0.0], atol=1e-9)  # 90 degrees: left, +x
    pushed.push_button.click()
    assert pushed.pushed.start == pytest.approx(1.5)
    np.testing.assert_allclose(pushed.pushed.force, force)
    root = character.bodies[0]
    applied = []  # the push on the root as each frame is simulated
    step = pushed.sim.step

    def recording(controller):
        applied.append(pushed.sim.data.xfrc_applied[root, :3].copy())
        return step(controller)

    pushed.sim.step = recording
    pushed.advance(3)
    assert pushed.scene.push_shown and "acting now" in pushed.readout.value
    pushed.advance(9)
    views[0].advance(12)
    assert not pushed.scene.push_shown and "ended at 1.60 s" in pushed.readout.value
    on = [np.any(f) for f in applied]
    assert on == [True] * 6 + [False] * 6  # 0.1 s: six frames of 1/60 s
    np.testing.assert_allclose(applied[0], [300.0, 0.0, 0.0], atol=1e-9)  # z up: the same
    assert not np.any(pushed.sim.data.xfrc_applied)
    # 30 N s to the left on 37 kg: the COM moves left faster than without the push
    dv = pushed.com_velocity[0] - views[0].com_velocity[0]
    assert dv > 0.3
    for v in views:
        v.close()


def test_a_fall_stops_the_walk_and_is_reported(character):
    view = WalkingSimulator(character, push=800.0, push_direction=180.0)
    view.advance(60)
    view.push()
    view.play.playing = True
    view.advance(240)
    assert view.fall_time is not None and view.fall_time < 5.0
    assert view.stopped and not view.play.playing
    t = view.time
    view.advance(10)
    assert view.time == t  # nothing more is simulated
    assert f"fell at {view.fall_time:.2f} s" in view.readout.value
    view.reset()
    assert view.fall_time is None and not view.stopped
    view.close()


def test_layout_fits_a_1366_window(view):
    panel, box = view.widget.children
    assert panel.layout.width == f"{view.PANEL_WIDTH}px"
    assert box.layout.width == f"{WINDOW[0]}px"
    assert view.PANEL_WIDTH + 12 + WINDOW[0] < 1366 - 300  # beside a narrow notebook margin
    assert view.scene.plotter.window_size == list(WINDOW)
    assert all(s.continuous_update is False for s in view.sliders.values())


def test_play_keeps_the_walk_at_real_time(view, monkeypatch):
    times = [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.9]  # ticks every 100 ms, then one 300 ms late
    clock = iter(times)
    monkeypatch.setattr("course.viz.walking_view.time.monotonic", lambda: next(clock))
    view.tick()
    assert view.time == pytest.approx(view.steps_per_tick * view.frame_time)  # 3 frames
    before = view.time
    view.tick()  # 100 ms later: 6 frames, not the 3 of a 50 ms tick
    assert view.time - before == pytest.approx(0.1)
    for _ in range(5):
        view.tick()
    assert view.measured_speed == pytest.approx(1.0)
    before = view.time
    view.tick()  # 300 ms: 18 frames wanted, 10 taken (the cap)
    assert view.time - before == pytest.approx(10 * view.frame_time)
