"""course.viz.cloth: the cloth mesh is updated in place, and the controls drive the simulation."""

from __future__ import annotations

import os

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

pytest.importorskip("pyvista")

from course.physics import grid_cloth, simulate  # noqa: E402
from course.viz import ClothScene, cloth_simulator  # noqa: E402


def _cloth_pixels(img: np.ndarray) -> np.ndarray:
    """(row, column) of the pixels shaded in the cloth's blue (lit or in shadow): blue
    clearly above red, unlike the grey-blue sky."""
    rgb = img[..., :3].astype(float)
    return np.argwhere((rgb[..., 2] - rgb[..., 0] > 60) & (rgb[..., 1] < 170))


def test_scene_updates_the_same_mesh_in_place_and_the_picture_follows():
    cloth = grid_cloth(12, 12)
    scene = ClothScene(cloth, window_size=(320, 240))
    mesh, points = scene.mesh, scene.mesh.GetPoints()
    before = _cloth_pixels(scene.image())
    fallen = simulate(cloth.system, cloth.positions, np.zeros_like(cloth.positions), 1 / 60,
                      30).positions[-1]
    scene.set_positions(fallen)
    after = _cloth_pixels(scene.image())
    assert scene.mesh is mesh and scene.mesh.GetPoints() is points  # nothing re-created
    assert np.allclose(scene.positions, fallen)
    assert len(before) > 200 and len(after) > 200
    assert after[:, 0].mean() > before[:, 0].mean() + 10  # the cloth fell: lower in the image
    scene.close()


def test_scene_rejects_bad_positions():
    scene = ClothScene(grid_cloth(3, 3), window_size=(160, 120))
    with pytest.raises(ValueError, match=r"positions must have shape \(9, 3\)"):
        scene.set_positions(np.zeros((8, 3)))
    with pytest.raises(ValueError, match="positions contains NaN"):
        scene.set_positions(np.full((9, 3), np.nan))
    scene.close()


def test_simulator_controls_drive_the_simulation():
    sim = cloth_simulator(grid_cloth(8, 8), window_size=(240, 180))
    sim.step_button.click()
    assert sim.steps == 1 and sim.last.converged
    assert sim.time == pytest.approx(sim.sliders["h"].value)
    assert np.allclose(sim.scene.positions, sim.x)
    assert "Newton" in sim.readout.value
    sim.sliders["stiffness"].value = 100.0
    assert np.allclose(sim.cloth.system.k.max(), 100.0)
    sim.play.value += 1  # a tick of play: 40 ms of simulated time at h = 1/60 s, 2 steps
    assert sim.steps_per_tick == 2 and sim.steps == 3
    sim.reset_button.click()
    assert sim.steps == 0 and np.allclose(sim.scene.positions, sim.cloth.positions)
    sim.close()


def test_simulator_stops_when_explicit_euler_explodes():
    sim = cloth_simulator(grid_cloth(8, 8), window_size=(240, 180))
    sim.sliders["method"].value = "explicit"
    sim.advance(60)
    assert sim.exploded and sim.steps < 60
    assert "exploded" in sim.readout.value
    assert np.all(np.isfinite(sim.scene.positions))  # the last drawable state stays shown
    steps = sim.steps
    sim.advance()
    assert sim.steps == steps  # nothing more until a reset
    sim.reset()
    assert not sim.exploded
    with pytest.raises(ValueError, match="^method: "):
        cloth_simulator(grid_cloth(3, 3), method="rk4")
    sim.close()


def test_the_energy_readout_shows_every_part_and_they_add_up_to_e():
    import re

    sim = cloth_simulator(grid_cloth(8, 8), window_size=(240, 180))
    try:
        for _ in range(3):  # at rest, then falling: kinetic, spring and gravity all non-zero
            sim.advance(10)
            line = next(s for s in sim.readout.value.split("<br>") if s.startswith("energy"))
            m = re.fullmatch(r"energy E = ([-+]\d+\.\d{4}) J = kinetic (\d+\.\d{4}) "
                             r"\+ spring (\d+\.\d{4}) \+ gravity \(([-+]\d+\.\d{4})\)", line)
            assert m, line
            total, kinetic, spring, gravity = map(float, m.groups())
            e = sim.cloth.system.energy(sim.x, sim.v)  # recomputed: E = T + U - sum m g.x
            mg = -np.sum(sim.cloth.system.masses * (sim.x @ sim.cloth.system.gravity))
            np.testing.assert_allclose([kinetic, spring, gravity, total],
                                       [e.kinetic, e.spring, mg, e.kinetic + e.spring + mg],
                                       atol=5e-5)
            assert abs(kinetic + spring + gravity - total) <= 1.5e-4  # up to printed rounding
            assert gravity < 0 < kinetic and spring > 0
        sim.reset()
        assert "-0.0000" not in sim.readout.value  # at rest: no negative zero
    finally:
        sim.close()


def test_play_advances_in_simulated_time_and_says_how_fast():
    sim = cloth_simulator(grid_cloth(6, 6), window_size=(240, 180))
    try:
        h = sim.sliders["h"]
        h.value = 0.01  # 40 ms per tick at real time: 4 steps
        assert sim.steps_per_tick == 4 and sim.playback_speed == pytest.approx(1.0)
        sim.play.value += 1
        assert sim.steps == 4 and sim.time == pytest.approx(0.04)
        assert "4 steps of h per tick, 1× real time" in sim.readout.value
        h.value = 1e-4  # real time would need 400 steps per tick: capped, and said so
        assert sim.steps_per_tick == sim.max_steps_per_tick == 10
        assert sim.playback_speed == pytest.approx(0.025)
        assert "10 steps of h per tick, 0.025× real time (capped" in sim.readout.value
        sim.play.value += 1
        assert sim.steps == 14 and "simulated" in sim.readout.value
        sim.step_button.click()  # one step is one step
        assert sim.steps == 15
    finally:
        sim.close()
    slow = cloth_simulator(grid_cloth(4, 4), window_size=(160, 120), speed=0.25, h=0.005)
    try:
        assert slow.steps_per_tick == 2 and "0.25× real time" in slow.readout.value
        assert "capped" not in slow.readout.value
    finally:
        slow.close()


def test_the_view_keeps_its_size_when_the_readout_grows():
    sim = cloth_simulator(grid_cloth(6, 6), window_size=(640, 480))
    try:
        panel, view = sim.widget.children
        assert panel is sim.panel and view is sim.scene.widget()
        # the panel and the readout have a fixed width, so the readout's long lines wrap
        for w in (panel, sim.readout):
            assert w.layout.width == w.layout.min_width == f"{sim.PANEL_WIDTH}px"
        assert panel.layout.flex == "0 0 auto"
        # the view neither shrinks nor grows: its own fixed width, no flex
        assert view.layout.width == view.layout.min_width == "640px"
        assert view.layout.flex == "0 0 auto"
        sim.sliders["method"].value = "explicit"
        sim.advance(80)  # long lines: the exploded warning
        assert sim.exploded
        assert view.layout.width == "640px" and panel.layout.width == f"{sim.PANEL_WIDTH}px"
    finally:
        sim.close()
