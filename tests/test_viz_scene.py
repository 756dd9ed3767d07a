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
        floor_y = 5.0 - 0.022 * sc.framing.scale
        for point in ([35.0, floor_y, -30.0], [35.0, floor_y, -60.0]):
            c, r = np.round(sc.project(np.array([point]))[0]).astype(int)
            assert 0 <= r < img.shape[0], "the floor behind the feet is out of view"
            floor = img[r, c, :3].astype(int)
            assert np.ptp(floor) < 18, f"the floor tiles are neutral grey, got {floor}"
        sky = img[5, 5, :3].astype(int)
        assert np.ptp(sky) > 20, f"the sky is bluish, got {sky}"
    finally:
        sc.close()


@pytest.mark.parametrize("ghost_first", [True, False])
def test_a_faint_ghost_under_a_coincident_pose_leaves_its_joints_clean(ghost_first):
    """Where IK leaves joints in place the solid pose covers its ghost: no speckle of the
    ghost's grey inside a joint's sphere or a bone's tube (z-fighting)."""
    from course.viz.scene import GHOST

    def render(ghost: bool):
        sc = SkeletonScene(window_size=(480, 400), ground=False, camera="iso")
        try:
            if ghost and ghost_first:
                sc.add_skeleton(PARENTS, POSE, name="start", color=GHOST, opacity=0.55)
            sc.add_skeleton(PARENTS, POSE, name="IK", color=PALETTE[0])
            if ghost and not ghost_first:
                sc.add_skeleton(PARENTS, POSE, name="start", color=GHOST, opacity=0.55)
            sc.plotter.remove_legend(render=False)  # the legend is not the point here
            cam = sc.plotter.camera
            towards = np.subtract(cam.position, cam.focal_point)
            right = np.cross(cam.up, towards / np.linalg.norm(towards))
            right /= np.linalg.norm(right)
            uv = sc.project(POSE)
            joint = 0.022 * sc.framing.scale * right
            radius = np.linalg.norm(sc.project(POSE + joint) - uv, axis=1)
            return sc.screenshot().astype(int), uv, radius
        finally:
            sc.close()

    alone, uv, radius = render(ghost=False)
    both, _, _ = render(ghost=True)
    assert radius.min() > 4  # joints big enough to have an inside
    rows, cols = np.mgrid[:alone.shape[0], :alone.shape[1]]
    inside = np.zeros(alone.shape[:2], bool)
    for (c, r), rad in zip(uv, radius, strict=True):  # each sphere's disc, its rim left out
        inside |= (cols - c) ** 2 + (rows - r) ** 2 < (rad - 1.5) ** 2
    mids = np.round((uv[1:] + uv[PARENTS[1:]]) / 2).astype(int)  # the middle of each bone
    diff = np.abs(both - alone).max(axis=2)
    assert inside.sum() > 500
    assert diff[inside].max() <= 8, "the ghost shows through the solid pose's joints"
    assert diff[mids[:, 1], mids[:, 0]].max() <= 8, "the ghost shows through the bones"


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
    np.testing.assert_allclose(np.asarray(scene.trail.points)[:, 0], [2, 3, 4, 5])
    scene.clear_trail()


def test_the_pole_is_a_violet_sphere_apart_from_the_red_target_and_in_the_legend():
    from course.viz.scene import GHOST, POLE_COLOR, TARGET_COLOR

    sc = SkeletonScene(window_size=(480, 400), ground=False, camera="front")
    try:
        sc.add_skeleton(PARENTS, POSE, name="start", color=GHOST, opacity=0.5)
        sc.add_skeleton(PARENTS, POSE, name="two-link IK")
        assert sc.pole_position is None and [n for n, _ in sc.legend_entries()] == [
            "start", "two-link IK"]
        target, pole = np.array([[40.0, 20.0, 0.0]]), np.array([-40.0, 20.0, 0.0])
        sc.set_targets(target, render=False)
        sc.set_pole(pole + 5.0, render=False)
        mesh = sc._pole
        sc.set_pole(pole)
        assert sc._pole is mesh  # moved in place
        np.testing.assert_allclose(sc.pole_position, pole)
        assert sc.legend_entries()[-2:] == [("target", TARGET_COLOR), ("pole", POLE_COLOR)]
        img = sc.screenshot().astype(int)
        (tc, tr), (pc, pr) = np.round(sc.project(np.vstack([target, pole]))).astype(int)
        sky_t, sky_p = img[tr, 0], img[pr, 0]
        t_px, p_px = img[tr, tc], img[pr, pc]
        # over the same sky: the target turns it red (r up, b down), the pole violet (r and g
        # down, b kept); one is redder than blue, the other bluer than red
        assert t_px[0] - t_px[2] > sky_t[0] - sky_t[2] + 40
        assert p_px[2] - p_px[1] > sky_p[2] - sky_p[1] + 40 and p_px[0] < sky_p[0] - 40
        assert t_px[0] > t_px[2] + 20 and p_px[2] > p_px[0] + 20
        with pytest.raises(ValueError, match="position"):
            sc.set_pole([np.nan, 0.0, 0.0])
    finally:
        sc.close()


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
    monkeypatch.setenv("PYVISTA_JUPYTER_BACKEND", "client")
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
    radius = 0.022 * browser_scene.framing.scale
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


class _FakeLoop:
    """A clock and ``call_later`` that run only when told."""

    def __init__(self):
        self.now, self.timers = 0.0, []

    def call_later(self, delay, fn):
        self.timers.append((self.now + delay, fn))

    def advance(self, seconds):
        self.now += seconds
        while due := [t for t in self.timers if t[0] <= self.now]:  # (and timers they set)
            self.timers = [t for t in self.timers if t[0] > self.now]
            for _, fn in due:
                fn()


def test_a_browser_view_publishes_changes_at_once_and_the_whole_scene_when_still():
    from course.viz.browser_sync import BrowserDraws, send_changes_only

    published, full = [], []

    class Helper:
        def scene(self, window, new_state, widgets, orientation_axis):
            return {"window": window, "new": new_state}

    class View:
        module = Helper()

        @staticmethod
        def get_widgets():
            return []

        class server:  # noqa: N801 (trame's attribute name)
            class protocol:  # noqa: N801
                @staticmethod
                def publish(topic, state):
                    published.append((topic, state))

        def update(self, **_kwargs):
            full.append(1)

    loop = _FakeLoop()
    view = View()
    draws = BrowserDraws(clock=lambda: loop.now, call_later=loop.call_later)
    send_changes_only(view, "window", draws)
    view.update()  # no page has shown the scene: it will load the whole state, kept current
    assert full == [1] and not published
    draws.drawn()  # a page shows it: from now on it takes changes
    for _ in range(5):  # a drag
        view.update()
        draws.drawn()
        loop.advance(0.05)
    assert full == [1], "the whole scene must wait until the view is still"
    assert published == [("trame.vtk.delta", {"window": "window", "new": False})] * 5
    loop.advance(0.9)
    assert full == [1], "not before a second has passed since the last change"
    loop.advance(0.1)  # a second after the last change, once
    assert full == [1, 1]
    loop.advance(5.0)
    assert full == [1, 1]


def test_browser_draws_hold_back_all_but_the_newest_change_until_the_last_is_drawn():
    from course.viz.browser_sync import BrowserDraws

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
    from course.viz.browser_sync import BrowserDraws

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
    from course.viz.browser_sync import BrowserDraws, send_changes_only

    published = []

    class View:
        class module:  # noqa: N801 (trame's attribute name)
            @staticmethod
            def scene(window, new_state, widgets, orientation_axis):
                return {"state": state[0]}

        @staticmethod
        def get_widgets():
            return []

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
    send_changes_only(view, "window", draws)
    for k in range(1, 6):  # five renders while the browser draws the first
        state[0] = k
        view.update()
    assert published == [1]
    draws.drawn()
    assert published == [1, 5], "the browser gets the newest state, not a backlog"


def _turn(axis, degrees):
    return Rotation.from_rotvec(np.radians(degrees) * np.asarray(axis, float)).as_matrix()


def test_frame_scene_draws_equal_lengths_equally_in_every_frame():
    """A parallel projection: the same axis is as long on screen in each frame, and the
    frames stand on one row (LERP's shorter frame is shorter, not farther away)."""
    from course.viz.frame_scene import FrameScene

    sc = FrameScene(3, labels=["LERP", "NLERP", "SLERP"], window_size=(780, 300))
    try:
        assert sc.plotter.camera.parallel_projection
        origins = np.array(sc.offsets)
        px = [sc.project(np.vstack([o, o + np.eye(3)])) for o in origins]
        lengths = np.array([np.linalg.norm(p[1:] - p[0], axis=1) for p in px])  # (frame, axis)
        np.testing.assert_allclose(lengths, np.broadcast_to(lengths[0], lengths.shape), atol=1e-6)
        assert lengths.min() > 20
        np.testing.assert_allclose([p[0, 1] for p in px], px[0][0, 1], atol=1e-6)  # one row
        # and in the picture: the red (x) arrows, turned alike, are equally long
        sc.set_rotations([_turn([0, 1, 0], 30)] * 3)
        img = sc.screenshot().astype(int)
        red = (img[..., 0] > 150) & (img[..., 1] < 110) & (img[..., 2] < 120)
        spans = []
        for p in px:
            lo, hi = int(p[0, 0] - 5), int(p[0, 0] + 1.2 * lengths[0, 0])
            cols = np.nonzero(red[:, lo:hi].any(axis=0))[0]
            spans.append(cols.max() - cols.min())
        assert max(spans) - min(spans) <= 2, spans
    finally:
        sc.close()


ROTATION_SETS = {
    "a1 v0": [np.zeros((3, 3)), Rotation.from_rotvec(np.pi * np.array([1, 2, 2]) / 3).as_matrix()],
    "a1 v3": [np.zeros((3, 3)), _turn([1, 0, 0], 90) @ _turn([0, 0, 1], 90),
              _turn([0, 0, 1], 90) @ _turn([1, 0, 0], 90)],
    "down": [_turn([1, 0, 0], 90), _turn([0, 0, 1], -90), _turn([1, 0, 0], 180)],  # axes to -y
    "random": list(Rotation.random(3, random_state=7).as_matrix()),
}


@pytest.mark.parametrize("case, labels, size", [
    ("a1 v0", ["yours: not implemented yet", "reference"], None),
    ("a1 v0", ["yours: not implemented yet", "reference"], (420, 380)),  # a narrow window
    ("a1 v3", ["yours: not implemented yet", "reference", "b a (the other order)"], None),
    ("a1 v3", ["yours: not implemented yet", "reference", "b a (the other order)"],
     (1200, 380)),
    ("down", ["LERP", "NLERP", "SLERP"], (780, 300)),
    ("random", ["LERP", "NLERP", "SLERP"], (780, 300)),
])
def test_frame_scene_captions_sit_under_their_own_frame_clear_of_every_arrow(case, labels, size):
    from course.viz.frame_scene import FrameScene

    rotations = ROTATION_SETS[case][:len(labels)]
    sc = FrameScene(len(labels), labels=labels, window_size=size)
    try:
        sc.set_rotations(rotations, render=False)
        arrows = sc.plotter.renderer.GetActors()

        def picture(show_arrows: bool, captions: list[int]) -> np.ndarray:
            for k, actor in enumerate(sc.label_actors):
                actor.SetVisibility(k in captions)
            for actor in arrows:
                actor.SetVisibility(show_arrows)
            return sc.screenshot().astype(int)

        sky = picture(False, [])
        drawn = np.abs(picture(True, []) - sky).max(axis=2) > 12  # arrows and world axes
        assert drawn.sum() > 300
        drawn |= np.roll(drawn, 2, 0) | np.roll(drawn, -2, 0)  # 2 px clear of them
        drawn |= np.roll(drawn, 2, 1) | np.roll(drawn, -2, 1)
        h, w = sky.shape[:2]
        origins = sc.project(np.array(sc.offsets))
        texts = []
        for k in range(len(labels)):
            text = np.abs(picture(False, [k]) - sky).max(axis=2) > 40
            rows, cols = np.nonzero(text)
            assert len(rows) > 30, f"caption {labels[k]!r} is not drawn"
            assert not (text & drawn).any(), f"an arrow crosses {labels[k]!r}"
            # whole, in the window, centred under its own frame, below its arrows' reach
            assert rows.min() > 1 and rows.max() < h - 2 and cols.min() > 1 and cols.max() < w - 2
            assert abs((cols.min() + cols.max()) / 2 - origins[k, 0]) < 12
            assert rows.min() > origins[k, 1] + sc.REACH * sc.pixels_per_unit
            texts.append(text)
        for a in range(len(texts)):
            for b in range(a + 1, len(texts)):
                assert not (texts[a] & texts[b]).any(), "two captions overlap"
        for actor in sc.label_actors:
            actor.SetVisibility(True)
        for actor in arrows:
            actor.SetVisibility(True)
    finally:
        sc.close()
    with pytest.raises(ValueError, match="labels"):
        FrameScene(2, labels=["one"])
