"""Notebook 16's live LQR balance view: the CMU character standing under LQR, the cost's
weights on sliders (the gain re-designed on release), a push, and a readout of what happened.

One two-foot design per module (about 4 s); every run is short (1.5 s simulated, under 0.1 s).
"""

from __future__ import annotations

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")
pytest.importorskip("ipywidgets")
pytest.importorskip("pyvista")

from course.physics.lqr_balance import (  # noqa: E402
    Weights,
    design,
    lqr_stand,
    reweigh,
    survived,
)
from course.physics.simulation import Push  # noqa: E402
from course.viz.lqr_view import MEASURED, lqr_balance_simulator  # noqa: E402

pytestmark = pytest.mark.usefixtures("mujoco_log_elsewhere")


@pytest.fixture(scope="module")
def lqr(cmu):
    return design(cmu)


@pytest.fixture
def view(cmu, lqr):
    v = lqr_balance_simulator(cmu, lqr, push=0.0, duration=1.5)
    yield v
    v.close()


def test_the_sliders_set_the_gain_it_uses(view, cmu, lqr) -> None:
    assert view.controller.K is lqr.K
    view.sliders["velocity"].value = 3.0  # released: designed again, run again, playing
    assert view.design.weights == Weights(velocity=3.0)
    expected = reweigh(cmu, lqr, Weights(velocity=3.0))
    np.testing.assert_allclose(view.controller.K, expected.K)
    assert np.abs(view.controller.K - lqr.K).max() > 10.0  # a different gain, in use
    assert view.design.equilibrium is lqr.equilibrium  # the equilibrium kept: a DARE alone
    assert view.sim.frame == 0 and view.play.playing
    assert "gain designed in" in view.readout.value
    view.sliders["torque"].value = 10.0  # R ten times: the same gain as Q a tenth
    tenth = reweigh(cmu, lqr, Weights(velocity=3.0, scale=1.0))
    np.testing.assert_allclose(view.controller.K, tenth.K, rtol=1e-6, atol=1e-6 * 983)


def test_no_push_stands_and_the_readout_says_so(view) -> None:
    assert "push: none" in view.readout.value
    view.finish()
    assert view.stopped and view.fall_time is None and not view.play.playing
    assert "stood 1.5 s" in view.readout.value
    # the floor's neutral modes (x, z, yaw) sit at |λ| = 1; every other mode decays
    line = view.readout.value.split("<br>")[3]
    assert "ρ(A − BK) = 1 on 3 neutral modes" in line
    assert float(line.rsplit("≤ ", 1)[1].split()[0]) < 1.0
    assert view.sim.frame == view.n_frames - 1 == 90


def test_a_push_past_the_measured_limit_falls(view, cmu, lqr) -> None:
    limit = MEASURED["two feet"][0]  # N forward, the default gain's (docs/control.md)
    view.sliders["push"].value = 2 * limit
    force = view.sliders["push"].value  # on the slider's 5 N steps
    assert force > 1.9 * limit
    view.push_button.click()  # runs again with the push, playing
    assert view.play.playing and view.sim.frame == 0
    view.finish()
    assert view.fall_time is not None and view.fall_time < 1.5
    assert f"fell at {view.fall_time:.2f} s" in view.readout.value
    assert f"{force:.0f} N for 0.1 s" in view.readout.value
    # the same run as lqr_stand's, up to where the view stopped it
    run = lqr_stand(cmu, lqr, duration=1.5, push=Push("Hips", (0, 0, force), 0.25, 0.1))
    assert not survived(run)
    n = view.sim.frame + 1
    np.testing.assert_array_equal(view.sim.recording().qpos[:n - 1], run.qpos[:n - 1])


def test_a_push_within_the_limit_stands(view) -> None:
    view.sliders["push"].value = 80.0
    view.sliders["push_direction"].value = 180.0
    view.push_button.click()
    view.finish()
    assert view.fall_time is None and "stood 1.5 s" in view.readout.value
    assert "com controller 159 N" in view.readout.value  # backward, beside LQR's own 131


def _com_y_up(cmu, data) -> np.ndarray:
    c = data.subtree_com[int(cmu.bodies[0])]  # MuJoCo, z up
    return np.array([c[0], c[2], -c[1]])


def test_the_push_com_and_capture_point_are_drawn_where_they_are(view, cmu) -> None:
    view.sliders["push"].value = 250.0  # forward, +z; from 0.25 s for 0.1 s
    view.push_button.click()
    view.advance(16)  # t = 0.267 s: the next frame pushes
    assert view.pushing and view.markers.push_shown
    root = view.scene.skeleton().positions[0]
    assert view.markers.push_segment[1] == pytest.approx(root)  # into the root
    assert np.all(np.diff(view.markers.push_segment[:, 2]) > 0)  # along +z
    view.advance(5)  # t = 0.35 s: the push has ended
    before = _com_y_up(cmu, view.sim.data)
    view.advance(1)
    assert not view.pushing and not view.markers.push_shown
    c = _com_y_up(cmu, view.sim.data)
    scale = cmu.scale
    floor = view.scene.floor_height
    np.testing.assert_allclose(view.markers.com_marker[[0, 2]] * scale, c[[0, 2]], atol=1e-9)
    assert view.markers.com_marker[1] == pytest.approx(floor + view.markers.lift)
    # ξ = c + ċ/ω0, ċ by a finite difference over the last frame, h over MuJoCo's floor
    v = (c - before) / view.frame_time
    w0 = np.sqrt(9.81 / (c[1] - view.ground_height))
    xi = c[[0, 2]] + v[[0, 2]] / w0
    drawn = view.markers.capture_marker[[0, 2]] * scale
    assert np.linalg.norm(xi - c[[0, 2]]) > 0.05  # pushed forward: ξ well ahead of the COM
    np.testing.assert_allclose(drawn, xi, atol=0.01)
    assert drawn[1] > c[2]  # ahead, the push's way
    assert "capture point ξ" in view.readout.value


class _KernelLoop:
    """The kernel's loop as :mod:`course.viz.backend` sees it: callbacks kept, run on demand."""

    def __init__(self) -> None:
        self.callbacks: list = []

    def add_callback(self, fn) -> None:
        self.callbacks.append(fn)


def test_a_new_stance_is_designed_beside_the_kernel_while_the_last_gain_plays(
        view, cmu, lqr, monkeypatch) -> None:
    import threading

    from course.physics import lqr_balance
    from course.viz import backend

    loop, release, asked = _KernelLoop(), threading.Event(), []

    def slow_design(character, *, stance):  # the 4 s design, held until the test says
        asked.append((threading.current_thread() is threading.main_thread(), stance))
        release.wait(30)
        return lqr

    monkeypatch.setattr(backend, "_kernel_loop", lambda: loop)
    monkeypatch.setattr(lqr_balance, "design", slow_design)
    view.sliders["stance"].value = "left foot"
    view.sliders["velocity"].value = 3.0  # asked again while designing: no second design
    assert view.designing and "designing for left foot" in view.readout.value
    assert view.controller.K is lqr.K  # the last gain plays on, the kernel free
    view.advance(5)
    assert view.sim.frame == 5 and "designing for left foot" in view.readout.value
    release.set()
    worker = next(t for t in threading.enumerate() if t.name == "course-background")
    worker.join(30)
    assert asked == [(False, 0)]  # one design, on another thread, for the stance chosen
    assert len(loop.callbacks) == 1 and view.designing  # handed back to the kernel's loop
    loop.callbacks.pop()()
    assert not view.designing and "designing" not in view.readout.value
    np.testing.assert_allclose(view.controller.K, reweigh(cmu, lqr, Weights(velocity=3.0)).K)
    assert view.sim.frame == 0 and view.play.playing  # the new gain's run, from its start
    assert "gain designed in" in view.readout.value


def test_a_failed_design_says_why_and_the_last_gain_stays(view, lqr, monkeypatch) -> None:
    import threading

    from course.physics import lqr_balance
    from course.viz import backend

    loop = _KernelLoop()

    def broken(character, *, stance):
        raise RuntimeError("no equilibrium on one leg")

    monkeypatch.setattr(backend, "_kernel_loop", lambda: loop)
    monkeypatch.setattr(lqr_balance, "design", broken)
    view.sliders["stance"].value = "left foot"
    worker = next((t for t in threading.enumerate() if t.name == "course-background"), None)
    if worker is not None:
        worker.join(30)
    loop.callbacks.pop()()
    assert not view.designing and view.controller.K is lqr.K
    assert "the design for left foot failed: RuntimeError: no equilibrium" in view.readout.value
    view.advance(1)  # the next tick keeps saying it
    assert "failed" in view.readout.value
