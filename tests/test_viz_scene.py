"""course.viz.scene: render known poses off-screen and check the pixels, not just the file."""

from __future__ import annotations

import os

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from scipy.spatial.transform import Rotation  # noqa: E402

pytest.importorskip("pyvista")

from course.viz.scene import PALETTE, SkeletonScene, show_skeletons  # noqa: E402

# A small figure, y up: hips, spine, head, two arms, two legs (units ~ cm).
PARENTS = np.array([-1, 0, 1, 2, 2, 4, 2, 6, 0, 8, 0, 10])
POSE = np.array([
    [0, 90, 0], [0, 120, 0], [0, 150, 0], [0, 165, 0],
    [22, 140, 0], [45, 125, 0], [-22, 140, 0], [-45, 125, 0],
    [10, 50, 0], [10, 5, 0], [-10, 50, 0], [-10, 5, 0],
], dtype=float)
JOINT_RGB = np.array([int(PALETTE[0][1][i:i + 2], 16) for i in (1, 3, 5)])


def _rgb(hex_color: str) -> np.ndarray:
    return np.array([int(hex_color[i:i + 2], 16) for i in (1, 3, 5)])


def _near(img: np.ndarray, uv: np.ndarray, color: np.ndarray, tol: float = 70.0) -> np.ndarray:
    """For each pixel position, whether some pixel within 1 px has ``color`` (shaded: tol)."""
    out = []
    for c, r in np.round(uv).astype(int):
        patch = img[r - 1:r + 2, c - 1:c + 2, :3].reshape(-1, 3).astype(float)
        out.append(np.linalg.norm(patch - color, axis=1).min() < tol)
    return np.array(out)


def _distance_to_segments(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Pixel distance of each point p (N, 2) to the nearest segment a-b (S, 2)."""
    ab = b - a
    t = np.clip(np.einsum("nsk,sk->ns", p[:, None] - a, ab) / np.sum(ab * ab, axis=1), 0, 1)
    closest = a + t[..., None] * ab
    return np.linalg.norm(p[:, None] - closest, axis=2).min(axis=1)


@pytest.fixture(scope="module")
def scene():
    sc = SkeletonScene(window_size=(480, 400), ground=False, camera="front")
    sc.add_skeleton(PARENTS, POSE, name="student")
    yield sc
    sc.close()


def test_each_joint_is_drawn_at_its_projection_and_background_elsewhere(scene):
    scene.set_pose(POSE)
    img = scene.screenshot()
    assert img.shape == (400, 480, 3)
    uv = scene.project(POSE)
    assert np.all(_near(img, uv, JOINT_RGB)), "a joint is not covered by the joint colour"
    # pixels far (> 25 px) from every bone and joint show the sky gradient: per row, the colour
    # of the left border column
    rng = np.random.default_rng(0)
    samples = rng.uniform([5, 5], [475, 395], size=(400, 2))
    far = _distance_to_segments(samples, uv[PARENTS[1:]], uv[1:]) > 25
    assert far.sum() > 200
    cols, rows = np.round(samples[far]).astype(int).T
    diff = np.abs(img[rows, cols].astype(int) - img[rows, 0].astype(int)).max()
    assert diff <= 3


def test_front_camera_looks_down_minus_z_with_y_up(scene):
    scene.set_camera("front")
    u = scene.project(np.array([[0, 100, 0], [30, 100, 0], [0, 130, 0]]))
    assert u[1, 0] > u[0, 0] + 10 and abs(u[1, 1] - u[0, 1]) < 3  # +x to the right
    assert u[2, 1] < u[0, 1] - 10  # +y up (rows grow downwards)
    scene.set_camera("top")
    u = scene.project(np.array([[0, 100, 0], [30, 100, 0], [0, 100, 30]]))
    assert u[1, 0] > u[0, 0] + 10 and u[2, 1] > u[0, 1] + 10  # +x right, +z down
    scene.set_camera("side")
    u = scene.project(np.array([[0, 100, 0], [0, 100, -30]]))
    assert u[1, 0] > u[0, 0] + 10  # looking down -x: -z to the right
    scene.set_camera("front")


def test_set_pose_moves_points_in_place(scene):
    skel = scene.skeleton()
    meshes = (id(skel.points), id(skel.bones), skel.points.GetPoints())
    raised = POSE.copy()
    raised[4:6] = [[22, 150, 0], [40, 172, 0]]  # the left arm up
    scene.set_pose(raised)
    assert (id(skel.points), id(skel.bones), skel.points.GetPoints()) == meshes
    np.testing.assert_allclose(scene.joint_positions, raised)
    np.testing.assert_allclose(np.asarray(skel.bones.points), raised)  # shared vtkPoints
    img = scene.screenshot()
    assert np.all(_near(img, scene.project(raised), JOINT_RGB))
    old_hand = scene.project(POSE[5:6])  # where the hand was: now background
    c, r = np.round(old_hand[0]).astype(int)
    assert np.abs(img[r, c].astype(int) - img[r, 0].astype(int)).max() <= 3
    scene.set_pose(POSE)


def test_axis_triads_follow_the_orientations():
    rot = Rotation.from_euler("ZYX", [[0.3 * j, 0.2, -0.1 * j] for j in range(len(PARENTS))])
    quats = rot.as_quat(scalar_first=True)
    sc = SkeletonScene(window_size=(320, 280), ground=False)
    try:
        skel = sc.add_skeleton(PARENTS, POSE, quats, axes=True)
        tips = np.asarray(skel.triads.points).reshape(-1, 3, 2, 3)
        np.testing.assert_allclose(tips[:, :, 0], np.repeat(POSE[:, None], 3, axis=1))
        expected = POSE[:, None] + skel.axis_length * np.swapaxes(rot.as_matrix(), 1, 2)
        np.testing.assert_allclose(tips[:, :, 1], expected, atol=1e-9)
        img = sc.screenshot()
        x_tip = sc.project(tips[0, 0, 1])  # the root's x axis tip is red
        assert _near(img, x_tip, np.array([230, 57, 70]), tol=90)[0]
        with pytest.raises(ValueError, match="orientations"):
            sc.set_pose(POSE)
    finally:
        sc.close()


def test_two_skeletons_have_distinct_colours_a_legend_and_a_ground(tmp_path):
    shifted = POSE + [70, 0, 0]
    sc = show_skeletons(PARENTS, [POSE, shifted], names=["reference", "student"],
                        window_size=(560, 400), camera="front")
    try:
        assert list(sc.skeletons) == ["reference", "student"]
        assert sc.skeletons["reference"].joint_color != sc.skeletons["student"].joint_color
        assert sc.plotter.legend is not None
        img = sc.screenshot(tmp_path / "two.png")
        assert (tmp_path / "two.png").stat().st_size > 5000
        ref = _near(img, sc.project(POSE[1:3]), _rgb(PALETTE[0][1]))
        stu = _near(img, sc.project(shifted[1:3]), _rgb(PALETTE[1][1]))
        assert ref.all() and stu.all()
        # the floor sits just under the lowest joint (y = 5), behind and between the feet
        floor_y = 5.0 - 0.022 * sc._scale
        for point in ([35.0, floor_y, -30.0], [35.0, floor_y, -60.0]):
            c, r = np.round(sc.project(np.array([point]))[0]).astype(int)
            assert 0 <= r < img.shape[0], "the floor behind the feet is out of view"
            floor = img[r, c, :3].astype(int)
            assert np.ptp(floor) < 18, f"the floor tiles are neutral grey, got {floor}"
        sky = img[5, 5, :3].astype(int)
        assert np.ptp(sky) > 20, f"the sky is bluish, got {sky}"
    finally:
        sc.close()


def test_targets_and_trail_update_in_place(scene):
    scene.set_targets([[40, 160, 0], [-40, 160, 0]])
    np.testing.assert_allclose(scene.target_positions, [[40, 160, 0], [-40, 160, 0]])
    mesh = scene._targets
    scene.set_targets([[30, 150, 0], [-30, 150, 0]])
    assert scene._targets is mesh
    img = scene.screenshot()
    c, r = np.round(scene.project([[30, 150, 0]])[0]).astype(int)
    pixel, sky = img[r, c].astype(int), img[r, 0].astype(int)
    assert pixel[0] - pixel[2] > sky[0] - sky[2] + 40  # translucent red over the sky
    scene.add_trail(capacity=4)
    for k in range(6):
        scene.push_trail([k, 0, 0])
    np.testing.assert_allclose(np.asarray(scene._trail.points)[:, 0], [2, 3, 4, 5])
    scene.clear_trail()


def test_bad_input_names_the_argument(scene):
    with pytest.raises(ValueError, match="positions"):
        scene.set_pose(POSE[:3])
    with pytest.raises(ValueError, match="parents"):
        SkeletonScene.add_skeleton(scene, [0, 0], POSE[:2])
    with pytest.raises(ValueError, match="camera"):
        SkeletonScene(camera="diagonal")
    with pytest.raises(ValueError, match="already used"):
        scene.add_skeleton(PARENTS, POSE, name="student")


def test_the_target_handle_reports_where_it_is_dragged(scene):
    moved = []
    handle = scene.add_target_handle([40, 160, 0], moved.append)
    handle.SetCenter(10.0, 150.0, 5.0)  # what a mouse drag does, then VTK's event
    handle.InvokeEvent("InteractionEvent")
    np.testing.assert_allclose(moved[-1], [10.0, 150.0, 5.0])
    scene.move_target_handle([0.0, 170.0, 0.0])
    np.testing.assert_allclose(handle.GetCenter(), [0.0, 170.0, 0.0])
    handle.Off()


# -- the view rendered in the browser (vtk.js): what it is sent ----------------------------------


@pytest.fixture
def browser_scene(monkeypatch):
    """A scene built as for the client (vtk.js) view, without a trame server."""
    from course.viz import scene

    monkeypatch.setattr(scene, "jupyter_backend", lambda: "client")
    s = SkeletonScene(window_size=(320, 240))
    s.add_skeleton(PARENTS, POSE, name="a")
    s.add_skeleton(PARENTS, POSE + [60, 0, 0], name="b")
    yield s
    s.close()


def test_a_browser_view_gets_joints_as_a_mesh_that_follows_the_pose(browser_scene):
    from vtkmodules.vtkRenderingCore import vtkPolyDataMapper

    joints = browser_scene.skeleton("a").actors[1]
    # vtk.js has no glyph mapper: the spheres are a plain mesh it can draw
    assert type(joints.mapper) is vtkPolyDataMapper or joints.mapper.IsA("vtkPolyDataMapper")
    assert not joints.mapper.IsA("vtkGlyph3DMapper")
    moved = POSE + [0, 0, 30]
    browser_scene.set_pose(moved, name="a")
    joints.mapper.GetInputAlgorithm().Update()
    mesh = joints.mapper.GetInput()
    lo, hi = np.array(mesh.GetBounds()).reshape(3, 2).T
    radius = 0.022 * browser_scene._scale
    np.testing.assert_allclose(lo, moved.min(axis=0) - radius, atol=0.05 * radius)
    np.testing.assert_allclose(hi, moved.max(axis=0) + radius, atol=0.05 * radius)
    # the legend, which vtk.js would not draw, is HTML naming both skeletons in their colours
    html = browser_scene._legend_html()
    for name, color in browser_scene.legend_entries():
        assert name in html and color in html


def test_a_browser_view_is_sent_the_camera_only_when_it_moved(browser_scene):
    class View:
        pushes = 0

        def push_camera(self):
            View.pushes += 1

    browser_scene._browser_views.append(View())
    browser_scene.render()  # the framing made at build time reaches the browser once
    assert View.pushes == 1
    browser_scene.set_pose(POSE + 1.0, name="a")
    assert View.pushes == 1, "a pose change must not resend the camera"
    browser_scene.set_camera("follow", render=True)
    browser_scene.set_pose(POSE + [5.0, 0, 0], name="a")  # the camera follows the root
    assert View.pushes == 3


def test_a_browser_view_publishes_changes_at_once_and_the_whole_scene_when_still():
    import asyncio

    from course.viz.scene import _send_changes_only

    published, full = [], []

    class Helper:
        def scene(self, window, new_state, widgets, orientation_axis):
            return {"window": window, "new": new_state}

    class View:
        _VtkLocalView__view = "window"
        _helper = Helper()
        _widgets: list = []

        class server:  # noqa: N801 (trame's attribute name)
            class protocol:  # noqa: N801
                @staticmethod
                def publish(topic, state):
                    published.append((topic, state))

        def update(self, **_kwargs):
            full.append(1)

    view = View()
    assert _send_changes_only(view)

    async def drag():
        for _ in range(5):
            view.update()
            await asyncio.sleep(0.05)
        assert not full, "the whole scene must wait until the view is still"
        await asyncio.sleep(1.3)

    asyncio.run(drag())
    assert published == [("trame.vtk.delta", {"window": "window", "new": False})] * 5
    assert full == [1]
    assert not _send_changes_only(object()), "a view of another kind is left as it is"


class _FakeLoop:
    """A clock and ``call_later`` that run only when told."""

    def __init__(self):
        self.now, self.timers = 0.0, []

    def call_later(self, delay, fn):
        self.timers.append((self.now + delay, fn))

    def advance(self, seconds):
        self.now += seconds
        due = [t for t in self.timers if t[0] <= self.now]
        self.timers = [t for t in self.timers if t[0] > self.now]
        for _, fn in due:
            fn()


def test_browser_draws_hold_back_all_but_the_newest_change_until_the_last_is_drawn():
    from course.viz.scene import BrowserDraws

    loop = _FakeLoop()
    draws = BrowserDraws(clock=lambda: loop.now, call_later=loop.call_later)
    sent = []
    draws.send_or_wait(lambda: sent.append(0))
    assert sent == [0] and draws.pending() == 0, "a view that never answered is not waited for"
    draws.drawn()  # now it answers: from here each change waits for the last one's picture
    draws.send_or_wait(lambda: sent.append(1))
    assert draws.pending() == 1
    for k in (2, 3, 4):  # a fast drag while the browser draws change 1
        draws.send_or_wait(lambda k=k: sent.append(k))
    assert sent == [0, 1], "nothing is sent while the browser still draws"
    draws.drawn()  # change 1 drawn: the newest (4) goes, 2 and 3 never
    assert sent == [0, 1, 4] and draws.pending() == 1
    draws.drawn()
    assert draws.pending() == 0 and draws.count == 3
    loop.advance(5.0)
    assert sent == [0, 1, 4], "no timer sends a change twice"


def test_browser_draws_stop_waiting_for_a_browser_that_went_quiet():
    from course.viz.scene import BrowserDraws

    loop = _FakeLoop()
    draws = BrowserDraws(patience=1.0, clock=lambda: loop.now, call_later=loop.call_later)
    sent = []
    draws.drawn()
    draws.send_or_wait(lambda: sent.append(1))
    draws.send_or_wait(lambda: sent.append(2))  # held: 1 is not drawn
    loop.advance(0.5)
    assert sent == [1] and draws.pending() == 1
    loop.advance(0.6)  # the tab was closed: 1 is forgotten and the held change goes
    assert sent == [1, 2]
    loop.advance(1.1)
    assert draws.pending() == 0


def test_a_browser_view_sends_a_drag_at_the_pace_the_browser_draws():
    from course.viz.scene import BrowserDraws, _send_changes_only

    published = []

    class View:
        _VtkLocalView__view = "window"
        _widgets: list = []

        class _helper:  # noqa: N801
            @staticmethod
            def scene(window, new_state, widgets, orientation_axis):
                return {"state": state[0]}

        class server:  # noqa: N801 (trame's attribute name)
            class protocol:  # noqa: N801
                @staticmethod
                def publish(topic, delta):
                    published.append(delta["state"])

        def update(self, **_kwargs):
            pass

    loop = _FakeLoop()
    draws = BrowserDraws(clock=lambda: loop.now, call_later=loop.call_later)
    draws.drawn()  # the browser answers
    view, state = View(), [0]
    assert _send_changes_only(view, draws)
    for k in range(1, 6):  # five renders while the browser draws the first
        state[0] = k
        view.update()
    assert published == [1]
    draws.drawn()
    assert published == [1, 5], "the browser gets the newest state, not a backlog"
