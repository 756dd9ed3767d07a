"""course.viz.drag_pad: the pad drags an IK target in the plane the view's camera faces, or
in a planar arm's plane."""

from __future__ import annotations

import json
import os
import shutil
import subprocess

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")

from types import SimpleNamespace  # noqa: E402

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from hypothesis import assume, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from course import viz  # noqa: E402
from course.viz import panel  # noqa: E402
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


@settings(derandomize=True, max_examples=60)
@given(direction=st.tuples(finite, finite, finite).filter(lambda d: np.linalg.norm(d) > 0.1),
       normal=st.tuples(finite, finite, finite).filter(lambda n: np.linalg.norm(n) > 0.1),
       uv=st.tuples(st.floats(-1, 1), st.floats(-1, 1)))
def test_a_pad_across_a_normal_keeps_the_target_in_that_plane(direction, normal, uv):
    camera = SimpleNamespace(position=tuple(direction), focal_point=(0.0, 0.0, 0.0),
                             up=(0.0, 1.0, 0.0))
    start = np.array([0.3, -0.2, 0.7])
    moved = []
    drag = ViewPlaneDrag(camera, center=(0.0, 0.0, 0.0), half=1.5, position=start,
                         on_drag=moved.append, normal=normal)
    n = np.asarray(normal) / np.linalg.norm(normal)
    axes = np.stack([drag.right, drag.up, drag.depth_axis])
    np.testing.assert_allclose(axes @ axes.T, np.eye(3), atol=1e-9)
    np.testing.assert_allclose(abs(drag.depth_axis @ n), 1.0, atol=1e-12)
    assert drag.depth_axis @ np.asarray(direction) >= 0, "the pad faces the camera's side"
    assume(drag.pad.uv != list(uv))
    drag.pad.uv = list(uv)
    # every dragged target lies in the plane across n through the start
    assert len(moved) == 1 and moved[0] @ n == pytest.approx(start @ n, abs=1e-9)


def test_bad_half_is_named():
    camera = SimpleNamespace(position=(0, 0, 5), focal_point=(0, 0, 0), up=(0, 1, 0))
    with pytest.raises(ValueError, match="half"):
        ViewPlaneDrag(camera, (0, 0, 0), 0.0, (0, 0, 0), lambda p: None)
    with pytest.raises(ValueError, match="normal"):
        ViewPlaneDrag(camera, (0, 0, 0), 1.0, (0, 0, 0), lambda p: None, normal=(0, 0, 0))


def test_a_planar_arm_is_seen_face_on_and_dragged_in_its_plane():
    from course.skeleton import chain

    arm = chain([1.0, 0.8, 0.6, 0.4], axes=[0, 0, 1])  # hinges about z: the xy plane
    pg = viz.ik_playground(arm, methods=["dls"])
    try:
        assert pg.scene._camera == "front"
        np.testing.assert_allclose(pg.drag.depth_axis, [0.0, 0.0, 1.0])
        for uv in ([0.3, 0.5], [-0.6, 0.2], [0.9, -0.4]):
            pg.drag.pad.uv = uv
            assert pg.target[2] == pytest.approx(0.0, abs=1e-12)
            # in the plane, within reach: solved, not "singular" as off the plane
            assert pg.result.converged, (uv, pg.result.reason)
    finally:
        pg.close()
    ball = viz.ik_playground(chain([1.0, 0.8]), methods=["dls"])  # ball joints
    try:
        assert ball.scene._camera == "iso"
        cam = ball.scene.plotter.camera
        d = np.subtract(cam.position, cam.focal_point)
        np.testing.assert_allclose(ball.drag.depth_axis, d / np.linalg.norm(d))
    finally:
        ball.close()


def test_ik_playground_target_follows_the_pad_and_the_pad_the_sliders():
    from course.skeleton import chain

    pg = viz.ik_playground(chain([1.0] * 4, axes=[0, 0, 1]), methods=["dls"])
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

    fb = viz.full_body_ik(data.load("wave"))
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


def test_the_plane_normal_is_found_only_for_hinges_about_one_world_axis():
    from course.rotations import quat_from_axis_angle
    from course.skeleton import chain

    def normal(skeleton, local=None):
        n = skeleton.n_joints
        local = np.tile([1.0, 0, 0, 0], (n, 1)) if local is None else local
        _, rot = skeleton.forward_kinematics(local, np.zeros(3))
        return panel.hinge_plane_normal(skeleton, panel.ancestors(skeleton, n - 1), rot)

    np.testing.assert_allclose(normal(chain([1.0, 1.0], axes=[0, 0, 1])), [0, 0, 1])
    # a hinge's world axis is Q_j a_j: a bent start about the same axis keeps it
    local = np.tile([1.0, 0, 0, 0], (3, 1))
    local[0] = quat_from_axis_angle(np.array([0.0, 0.0, 1.0]), 0.7)
    np.testing.assert_allclose(normal(chain([1.0, 1.0], axes=[0, 0, 1]), local), [0, 0, 1],
                               atol=1e-12)
    assert normal(chain([1.0, 1.0])) is None  # ball joints
    assert normal(chain([1.0, 1.0], axes=[[0, 0, 1], [1, 0, 0]])) is None  # two axes
    assert panel.ancestors(chain([1.0, 1.0, 1.0]), 3) == [2, 1, 0]


def test_a_planar_arm_is_posed_face_on_in_the_fk_explorer():
    from course.skeleton import chain

    fk = viz.fk_explorer(chain([1.0, 0.8, 0.5], axes=[0, 0, 1]))
    try:
        assert fk.scene._camera == "front"
        w, h = fk.scene.plotter.window_size
        for value in (-180.0, 0.0, 90.0, 180.0):  # the whole swing stays in view
            fk.sliders["joint0.0"].value = value
            xy = fk.scene.project(fk.scene.skeleton().positions)
            assert np.all((xy > 0) & (xy < [w, h])), value
    finally:
        fk.close()
    assert viz.fk_explorer(chain([1.0, 0.8])).scene._camera == "iso"  # ball joints


# The pad's own JavaScript, run in node with the little of the DOM it uses: a pointer at
# (clientX, clientY) or a uv set from the kernel, and where it draws the dot / what it sends.
_PAD_HARNESS = r"""
import pad from "./pad.mjs";
const [size, r, cssScale, presses, uvs] = JSON.parse(process.argv[2]);
const element = () => ({
  attrs: {}, style: {}, children: [], handlers: {},
  setAttribute(k, v) { this.attrs[k] = Number(v) === Number(v) ? Number(v) : v; },
  appendChild(c) { this.children.push(c); },
  addEventListener(type, f) { this.handlers[type] = f; },
  setPointerCapture() {},
  getBoundingClientRect() {
    const side = (size + 2) * cssScale;  // a 1 px border each side, then CSS scaling
    return { left: 100, top: 40, width: side, height: side };
  },
});
globalThis.document = { createElementNS: () => element() };
let frame = [];
globalThis.requestAnimationFrame = (f) => frame.push(f);
const state = { size, dot_radius: r, uv: [0, 0] }, listeners = {};
const model = { get: (k) => state[k], set: (k, v) => { state[k] = v; },
                save_changes() {}, on: (e, f) => { listeners[e] = f; } };
const el = element();
pad.render({ model, el });
const svg = el.children[0], dot = svg.children.find((c) => c.attrs.class === "course-drag-dot");
const out = { pressed: [], placed: [] };
for (const [x, y] of presses) {
  svg.handlers.pointerdown({ clientX: x, clientY: y, pointerId: 1 });
  frame.forEach((f) => f()); frame = [];
  out.pressed.push({ cx: dot.attrs.cx, cy: dot.attrs.cy, r: dot.attrs.r, uv: state.uv });
  svg.handlers.pointerup({});
}
for (const p of out.pressed) {  // the kernel sends back the uv it was sent
  state.uv = p.uv; listeners["change:uv"]();
  p.again = { cx: dot.attrs.cx, cy: dot.attrs.cy };
}
for (const uv of uvs) {
  state.uv = uv; listeners["change:uv"]();
  out.placed.push({ cx: dot.attrs.cx, cy: dot.attrs.cy });
}
console.log(JSON.stringify(out));
"""


@pytest.mark.skipif(shutil.which("node") is None, reason="needs node to run the pad's script")
@pytest.mark.parametrize("css_scale", [1.0, 0.75])
def test_the_pads_dot_is_never_cut_and_stays_under_the_pointer(tmp_path, css_scale):
    from course.viz.drag_pad import DragPad

    pad = DragPad()
    size, r = pad.size, pad.dot_radius
    (tmp_path / "pad.mjs").write_text(pad._esm)
    (tmp_path / "run.mjs").write_text(_PAD_HARNESS)
    # presses in drawing pixels (inside the 1 px border): edges, corners, beyond, inside
    drawing = [(0, 0), (size, size), (-30, size / 2), (size + 30, 3), (size / 2, size / 2),
               (40, 130), (r + 1, size - r - 1), (12.5, 150.25)]
    presses = [[100 + (x + 1) * css_scale, 40 + (y + 1) * css_scale] for x, y in drawing]
    corners = [[-1, -1], [1, 1], [-1, 1], [0, 0], [0.3, -0.8]]
    run = subprocess.run(
        [shutil.which("node"), str(tmp_path / "run.mjs"),
         json.dumps([size, r, css_scale, presses, corners])],
        capture_output=True, text=True, timeout=60, cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    out = json.loads(run.stdout)
    for (x, y), got in zip(drawing, out["pressed"], strict=True):
        cx, cy = got["cx"], got["cy"]
        assert got["r"] == r
        # the whole dot inside the drawing, for any press (even outside the pad)
        assert r < cx < size - r and r < cy < size - r, (x, y, cx, cy)
        assert all(-1 <= c <= 1 for c in got["uv"])
        inner = (r + 1, size - r - 1)
        if inner[0] <= x <= inner[1] and inner[0] <= y <= inner[1]:  # the dot is where pressed
            assert (cx, cy) == (pytest.approx(x, abs=1e-9), pytest.approx(y, abs=1e-9))
        # that uv, set by the kernel, draws the dot at the same place: one mapping both ways
        assert (got["again"]["cx"], got["again"]["cy"]) == (pytest.approx(cx), pytest.approx(cy))
    centre = size / 2
    np.testing.assert_allclose([[p["cx"], p["cy"]] for p in out["placed"]],
                               [[r + 1, size - r - 1], [size - r - 1, r + 1],
                                [r + 1, r + 1], [centre, centre],
                                [centre + 0.3 * (centre - r - 1), centre + 0.8 * (centre - r - 1)]])


def test_full_body_pad_corners_are_the_target_sliders_limits():
    """Issue 28: half-way to a corner the pad drove two sliders to their limits. Now its
    corners are their limits, its middle their middles, and the third slider is kept."""
    from course import data

    fb = viz.full_body_ik(data.load("wave"))
    try:
        lo = np.array([fb.sliders[c].min for c in "xyz"])
        hi = np.array([fb.sliders[c].max for c in "xyz"])
        moved = [int(np.argmax(np.abs(fb.drag.right))), int(np.argmax(np.abs(fb.drag.up)))]
        kept = 3 - sum(moved)
        assert sorted(moved) != [0, 2] and moved[1] == 1  # a vertical face: y is up
        for u in (-1.0, -0.5, 0.0, 0.5, 1.0):
            for v in (-1.0, -0.5, 0.0, 0.5, 1.0):
                fb.drag.pad.uv = [u, v]  # as the browser sends it
                rel = (fb.drag.position([u, v]) - fb.root_position - lo) / (hi - lo)
                expected = (np.array([u, v]) * [np.sign(fb.drag.right[moved[0]]), 1] + 1) / 2
                np.testing.assert_allclose(rel[moved], expected, atol=1e-9)
                assert 0 <= rel[kept] <= 1
                name = fb.sliders["edit"].value
                target = fb.targets[name] - fb.root_position
                np.testing.assert_allclose(target, fb.drag.position([u, v]) - fb.root_position,
                                           atol=1e-9)  # nothing clipped: inside the sliders
        assert fb._pad_caption().startswith("drag target")
    finally:
        fb.close()


def test_fit_in_box_is_the_box_face_seen_along_an_axis_and_inside_it_otherwise():
    from course.viz.drag_pad import fit_in_box

    np.testing.assert_allclose(fit_in_box([1, 0, 0], [0, 1, 0], [2.0, 3.0, 5.0]), [2.0, 3.0])
    r = np.array([1.0, 0, -1]) / np.sqrt(2)
    s = np.array([0.0, 1, 0])
    box = np.array([1.0, 2.0, 3.0])
    a, b = fit_in_box(r, s, box)
    corner = np.abs(a * r) + np.abs(b * s)
    assert np.all(corner <= box + 1e-12) and np.isclose(np.max(corner / box), 1.0)
    with pytest.raises(ValueError, match="positive half-extents"):
        fit_in_box(r, s, [1.0, 0.0, 1.0])
