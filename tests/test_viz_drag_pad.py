"""course.viz.drag_pad: the pad drags an IK target in the plane the view's camera faces."""

from __future__ import annotations

import os

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")

from types import SimpleNamespace  # noqa: E402

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from hypothesis import assume, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from course.viz import controls  # noqa: E402
from course.viz.drag_pad import ViewPlaneDrag  # noqa: E402

finite = st.floats(-3.0, 3.0)


@settings(derandomize=True, max_examples=60)
@given(direction=st.tuples(finite, finite, finite).filter(
           lambda d: np.linalg.norm(d) > 0.1 and np.linalg.norm(np.cross(d, [0, 1, 0])) > 0.1),
       start=st.tuples(finite, finite, finite), uv=st.tuples(st.floats(-1, 1), st.floats(-1, 1)))
def test_the_pad_moves_in_the_view_plane_and_keeps_the_depth(direction, start, uv):
    camera = SimpleNamespace(position=tuple(np.add(direction, 1.0)), focal_point=(1.0, 1.0, 1.0),
                             up=(0.0, 1.0, 0.0))
    moved = []
    drag = ViewPlaneDrag(camera, center=(0.5, 0.0, 0.0), half=2.0, position=start,
                         on_drag=moved.append)
    axes = np.stack([drag.right, drag.up, drag.depth_axis])
    np.testing.assert_allclose(axes @ axes.T, np.eye(3), atol=1e-12)  # orthonormal
    # the screen's right is the camera's: right x up points at the camera
    np.testing.assert_allclose(np.cross(drag.right, drag.up), drag.depth_axis, atol=1e-12)
    assume(drag.pad.uv != list(uv))  # (the same value is no change: no event)
    drag.pad.uv = list(uv)  # as the browser sends it
    assert len(moved) == 1
    p = moved[0]
    rel = p - np.array([0.5, 0.0, 0.0])
    np.testing.assert_allclose([rel @ drag.right, rel @ drag.up], np.multiply(uv, 2.0),
                               atol=1e-9)
    # the depth along the view is the start's
    np.testing.assert_allclose(rel @ drag.depth_axis,
                               (np.subtract(start, [0.5, 0, 0])) @ drag.depth_axis, atol=1e-9)
    drag.show(p)  # the dot goes back where it was, and that sends no drag
    np.testing.assert_allclose(drag.pad.uv, uv, atol=1e-9)
    assert len(moved) == 1


def test_bad_half_is_named():
    camera = SimpleNamespace(position=(0, 0, 5), focal_point=(0, 0, 0), up=(0, 1, 0))
    with pytest.raises(ValueError, match="half"):
        ViewPlaneDrag(camera, (0, 0, 0), 0.0, (0, 0, 0), lambda p: None)


def test_ik_playground_target_follows_the_pad_and_the_pad_the_sliders():
    from course.skeleton import chain

    pg = controls.ik_playground(chain([1.0] * 4, axes=[0, 0, 1]), methods=["dls"])
    try:
        assert pg.handle is None and pg.drag is not None  # a static view takes no mouse
        pg.drag.pad.uv = [0.4, -0.3]
        expected = pg.drag.position([0.4, -0.3])
        for k, c in enumerate("xyz"):  # the sliders hold the target (within their ranges)
            s = pg.sliders[c]
            assert pg.sliders[c].value == pytest.approx(np.clip(expected[k], s.min, s.max))
        np.testing.assert_allclose(pg.scene.target_positions[0], pg.target)
        assert pg.result.frames  # solved again, for the dragged target
        pg.sliders["x"].value = pg.sliders["x"].value + 0.5
        rel = pg.target - pg.drag.center
        np.testing.assert_allclose(pg.drag.pad.uv, np.clip(
            [rel @ pg.drag.right / pg.drag.half, rel @ pg.drag.up / pg.drag.half], -1, 1),
            atol=1e-9)
    finally:
        pg.close()


def test_full_body_ik_pad_drags_the_edited_effector():
    from course import data

    fb = controls.full_body_ik(data.load("wave"))
    try:
        name = fb.sliders["edit"].value
        uv = np.array(fb.drag.pad.uv) * 0.5 + [0.2, 0.1]
        fb.drag.pad.uv = list(uv)
        target = fb.drag.position(uv)
        lo = np.array([fb.sliders[c].min for c in "xyz"]) + fb.root_position
        hi = np.array([fb.sliders[c].max for c in "xyz"]) + fb.root_position
        np.testing.assert_allclose(fb.targets[name], np.clip(target, lo, hi), atol=1e-9)
        assert any(np.allclose(t, fb.targets[name]) for t in fb.scene.target_positions)
    finally:
        fb.close()
