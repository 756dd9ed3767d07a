"""course.viz.simulation_view: the simulated character drawn beside its clip while it runs."""

from __future__ import annotations

import os

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")

from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pytest  # noqa: E402

pytest.importorskip("mujoco", reason="MuJoCo is not installed")

from course.bvh import load_bvh  # noqa: E402
from course.physics.character import build_model, track  # noqa: E402
from course.viz.simulation_view import SimulationView, simulation_view  # noqa: E402

SAMPLE = Path(__file__).resolve().parents[1] / "course" / "data" / "samples" / "wave.bvh"


pytestmark = pytest.mark.usefixtures("mujoco_log_elsewhere")


@pytest.fixture(scope="module")
def wave():
    return load_bvh(SAMPLE)


@pytest.fixture(scope="module")
def waver(wave):
    return build_model(wave.skeleton)


def _drawn(view: SimulationView, name: str) -> np.ndarray:
    return np.asarray(view.scene.skeleton(name).positions)


def _check_final(view: SimulationView) -> None:
    r = view.result
    assert r is not None, view.readout.value
    last = r.motion.n_frames - 1
    sim, _ = r.motion.forward_kinematics()
    clip, _ = view.clip.forward_kinematics()
    np.testing.assert_allclose(_drawn(view, "simulated"), sim[last] + view.offset, atol=1e-9)
    np.testing.assert_allclose(_drawn(view, "captured"), clip[last], atol=1e-9)
    assert ("stayed up" in view.readout.value) != r.fell


def test_blocking_run_draws_frames_as_they_come_and_ends_on_the_last(wave, waver):
    view = simulation_view(waver, wave, n_frames=30, hold_root=True, blocking=True,
                           display_fps=1e6)
    try:
        assert view.frames_drawn == 30  # frames 1..29 while simulating, then the final one
        _check_final(view)
        again = track(waver, wave, n_frames=30, **view.settings())  # deterministic
        np.testing.assert_array_equal(again.error_cm, view.result.error_cm)
    finally:
        view.close()


def test_a_slider_change_reruns_with_the_new_gain(wave, waver):
    view = simulation_view(waver, wave, n_frames=20, hold_root=True, blocking=True)
    try:
        first = view.result
        view.sliders["kp"].value = 10.0  # a weak joint lags the clip
        assert view.result is not first and view.settings()["kp"] == pytest.approx(10.0)
        assert view.result.error_cm.mean() > first.error_cm.mean()
        view.sliders["push"].value = 200.0
        assert view.settings()["push"].force[2] == 200.0
    finally:
        view.close()


def test_threaded_run_is_drawn_by_the_loop_and_a_new_run_stops_the_old(wave, waver):
    queue: list = []
    view = SimulationView(waver, wave, n_frames=40, hold_root=True,
                          call_later=lambda delay, fn: queue.append(fn))
    try:
        view.simulate()
        view.simulate()  # the first run is stopped at its next frame; only the second shows
        view.wait()
        assert view._thread is not None and not view._thread.is_alive()
        while queue:
            queue.pop(0)()
        _check_final(view)
        assert view.frames_drawn >= 1
    finally:
        view.close()


def test_bad_settings_are_named(wave, waver):
    with pytest.raises(ValueError, match="h: one of"):
        SimulationView(waver, wave, h=0.003)
    with pytest.raises(ValueError, match="n_frames"):
        SimulationView(waver, wave, n_frames=1)


@pytest.mark.parametrize("fps", [120.0, 30.0])
def test_every_step_offered_divides_the_frame_and_runs(wave, waver, fps):
    """The menu offers only steps the simulation accepts (1/300 s is 2.5 steps of a 120 fps
    frame: refused, so not offered); each one simulates a short clip to its end."""
    from dataclasses import replace

    from course.physics.simulation import substeps
    from course.viz.simulation_view import STEP_RANGE, steps

    clip = replace(wave, frame_time=1.0 / fps)
    offered = steps(clip.frame_time)
    assert offered and all(STEP_RANGE[0] * 0.999 <= h <= STEP_RANGE[1] * 1.001 for h in offered)
    assert [substeps(clip.frame_time, h) * h for h in offered] == pytest.approx(
        [clip.frame_time] * len(offered))
    view = SimulationView(waver, clip, n_frames=3, hold_root=True, blocking=True)
    try:
        assert [v for _, v in view.sliders["h"].options] == offered
        for h in offered:  # run, not refused (a coarse step may go unstable: said so)
            view.sliders["h"].value = h
            assert view.error is None and view.result is not None, view.readout.value
            assert view.result.h == pytest.approx(h)
            assert f"(h = 1/{round(1 / h)} s)" in view.readout.value
    finally:
        view.close()
