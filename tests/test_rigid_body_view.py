"""course.viz.rigid_body_view: the body's boxes move in place, and the controls drive the
simulation (a push turns the body as well as moving it)."""

from __future__ import annotations

import os

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

pytest.importorskip("pyvista")

from course.physics.rigid_body import (  # noqa: E402
    Ground,
    RigidBody,
    box,
    point_torque,
    simulate_rigid,
    t_handle,
)
from course.rotations import matrix_from_quat, quat_from_axis_angle  # noqa: E402
from course.viz.rigid_body_view import RigidBodyScene, rigid_body_simulator  # noqa: E402


def _body_pixels(img: np.ndarray) -> np.ndarray:
    """(row, column) of the pixels in the body's blue: blue clearly above red."""
    rgb = img[..., :3].astype(float)
    return np.argwhere((rgb[..., 2] - rgb[..., 0] > 60) & (rgb[..., 1] < 170))


def test_scene_moves_the_same_mesh_and_the_picture_follows():
    cube = box(1.0, (0.1, 0.1, 0.1))
    scene = RigidBodyScene(cube, window_size=(320, 240))
    mesh, points = scene.mesh, scene.mesh.GetPoints()
    scene.set_state((0.0, 0.5, 0.0), (1.0, 0.0, 0.0, 0.0))
    high = _body_pixels(scene.image())
    q = quat_from_axis_angle(np.array([0.3, 1.0, 0.2]), 0.7)
    scene.set_state((0.0, 0.1, 0.0), q)
    low = _body_pixels(scene.image())
    assert scene.mesh is mesh and scene.mesh.GetPoints() is points  # nothing re-created
    expected = np.array([0.0, 0.1, 0.0]) + cube.points @ np.asarray(matrix_from_quat(q)).T
    assert np.allclose(scene.positions, expected)
    assert len(high) > 100 and len(low) > 100
    assert low[:, 0].mean() > high[:, 0].mean() + 10  # lower in the world, lower in the image
    scene.close()


def test_scene_draws_one_box_per_eight_corners_and_rejects_bad_input():
    scene = RigidBodyScene(t_handle(), floor=False, center=(0, 0, 0), radius=0.12,
                           window_size=(160, 120))
    assert scene.mesh.n_points == 16 and scene.mesh.n_cells == 12
    with pytest.raises(ValueError, match=r"x, q: expected shapes"):
        scene.set_state(np.zeros(2), (1.0, 0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="NaN"):
        scene.set_state(np.full(3, np.nan), (1.0, 0.0, 0.0, 0.0))
    scene.close()
    odd = RigidBody(mass=1.0, inertia=np.eye(3), points=np.zeros((5, 3)))
    with pytest.raises(ValueError, match="8 per box"):
        RigidBodyScene(odd)


def test_simulator_steps_as_simulate_rigid_and_the_sliders_reach_the_step():
    sim = rigid_body_simulator("box", window_size=(240, 180))
    sim.sliders["h"].value = 1e-3
    sim.sliders["k"].value = 2e4
    sim.advance(50)
    ground = Ground(k=2e4, d=0.3 * np.sqrt(2e4), friction=1.0)
    ref = simulate_rigid(sim.body, sim.start, 1e-3, 50, ground=ground)
    assert sim.steps == 50 and sim.time == pytest.approx(0.05)
    assert np.allclose(sim.state.x, ref.x[-1]) and np.allclose(sim.state.q, ref.q[-1])
    assert np.allclose(sim.scene.positions.mean(axis=0),
                       sim.state.x + np.asarray(matrix_from_quat(sim.state.q)) @
                       sim.body.points.mean(axis=0))
    assert "energy" in sim.readout.value
    sim.play.value += 1  # one tick: 40 ms at h = 1 ms, 40 steps
    assert sim.steps == 90
    sim.reset_button.click()
    assert sim.steps == 0 and np.allclose(sim.state.x, sim.start.x)
    sim.close()


def test_push_is_an_impulse_at_the_highest_corner():
    sim = rigid_body_simulator("box", window_size=(160, 120))
    before = sim.state
    top = sim.scene.positions[np.argmax(sim.scene.positions[:, 1])]
    sim.sliders["push"].value = 2.0
    sim.push_button.click()
    dp = np.array([2.0, 0.0, 0.0])
    assert np.allclose(sim.state.v, before.v + dp)
    assert np.allclose(sim.state.L, before.L + point_torque(top, before.x, dp))
    assert np.linalg.norm(sim.state.L) > 0.01  # it turns, not only moves
    sim.close()


def test_an_unstable_step_stops_play_and_says_so():
    sim = rigid_body_simulator("box", window_size=(160, 120))
    sim.sliders["h"].value = 0.05
    sim.sliders["k"].value = 1e6
    sim.advance(200)
    assert sim.exploded and "exploded" in sim.readout.value
    steps = sim.steps
    sim.advance(5)
    assert sim.steps == steps  # a blown-up state is not stepped further
    sim.close()


def test_t_handle_flips_in_the_live_view():
    sim = rigid_body_simulator("t_handle", window_size=(160, 120))
    for _ in range(50):  # 50 ticks of 40 steps of 1 ms: 2 s, past the flip at 1.57 s
        sim.tick()
    assert sim.time == pytest.approx(2.0)
    bar = np.asarray(matrix_from_quat(sim.state.q))[:, 0]  # the bar's axis in the world
    assert bar[0] < 0  # turned over
    assert np.allclose(sim.state.L, sim.start.L)  # a free body: L kept exactly
    with pytest.raises(ValueError, match="kind"):
        rigid_body_simulator("sphere")
    sim.close()
