"""course.viz's ipywidgets views: drive every control from code and check the scene and readouts."""

from __future__ import annotations

import os

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")

import matplotlib  # noqa: E402

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from scipy.spatial.transform import Rotation  # noqa: E402

from course import viz  # noqa: E402
from course.viz import panel  # noqa: E402
from course.viz.scene import GHOST, PALETTE  # noqa: E402


def _same_rotation(q, ref: Rotation) -> None:
    np.testing.assert_allclose(Rotation.from_quat(q, scalar_first=True).as_matrix(),
                               ref.as_matrix(), atol=1e-9)


def test_rotation_explorer_warns_at_gimbal_lock_and_matches_scipy():
    ex = viz.rotation_explorer("XYZ", (0.0, np.pi / 2, 0.0))
    try:
        assert ex.gimbal_lock and "Gimbal lock" in ex.warning.value
        ex.sliders["angle0"].value = 30.0
        ex.sliders["angle1"].value = 40.0
        ex.sliders["angle2"].value = -70.0
        assert not ex.gimbal_lock and ex.warning.value == ""
        ref = Rotation.from_euler("XYZ", [30, 40, -70], degrees=True)
        np.testing.assert_allclose(ex.matrix, ref.as_matrix(), atol=1e-12)
        _same_rotation(ex.quaternion, ref)
        np.testing.assert_allclose(ex.scene.rotations[0], ref.as_matrix(), atol=1e-12)
        ex.order.value = "zxz"  # proper Euler, extrinsic: locked when the middle angle is 0
        ex.sliders["angle1"].value = 0.0
        assert ex.gimbal_lock
        _same_rotation(ex.quaternion, Rotation.from_euler("zxz", [30, 0, -70], degrees=True))
        assert "+0.000" in ex.readout.value or "-0.000" in ex.readout.value
        assert ex.gimbal_image.value[:4] == b"\x89PNG"
    finally:
        ex.close()


def test_slerp_explorer_lerp_shrinks_and_slerp_moves_evenly():
    ex = viz.slerp_explorer((0, 0, 0), (0, 120, 0), t=0.25)
    try:
        q = ex.quaternions
        assert np.linalg.norm(q["LERP"]) < 1 - 1e-3
        np.testing.assert_allclose(np.linalg.norm(q["SLERP"]), 1)
        _same_rotation(q["SLERP"], Rotation.from_euler("Y", 30, degrees=True))
        # the LERP frame is scaled by |q|^2, the others are rotations
        np.testing.assert_allclose(np.linalg.det(ex.scene.rotations[0]),
                                   np.linalg.norm(q["LERP"]) ** 6, rtol=1e-9)
        np.testing.assert_allclose(np.linalg.det(ex.scene.rotations[1:]), 1)
        ex.sliders["t"].value = 0.5
        _same_rotation(ex.quaternions["SLERP"], Rotation.from_euler("Y", 60, degrees=True))
        assert "SLERP" in ex.readout.value
    finally:
        ex.close()


def test_fk_explorer_slider_moves_children_by_the_fk_result():
    from course.skeleton import chain

    arm = chain([1.0, 0.8, 0.5], axes=[0, 0, 1])
    ex = viz.fk_explorer(arm)
    try:
        before = ex.scene.joint_positions
        np.testing.assert_allclose(before[:, 0], [0, 1, 1.8, 2.3])
        ex.sliders[f"{arm.names[1]}.0"].value = 90.0  # the elbow turns about +z
        after = ex.scene.joint_positions
        np.testing.assert_allclose(after[:2], before[:2], atol=1e-12)  # parents stay
        elbow = before[1]
        R = Rotation.from_euler("z", 90, degrees=True)
        np.testing.assert_allclose(after[2:], elbow + R.apply(before[2:] - elbow), atol=1e-9)
        assert arm.names[1] in ex.readout.value
        ex.reset()
        np.testing.assert_allclose(ex.scene.joint_positions, before, atol=1e-12)
        assert all(s.value == 0 for s in ex.sliders.values())
    finally:
        ex.close()


@pytest.fixture(scope="module")
def sample_motion():
    from course import data

    return data.load("wave")


def test_bvh_player_shows_the_precomputed_frame(sample_motion):
    player = viz.bvh_player(sample_motion, camera="iso")
    try:
        positions, _ = sample_motion.forward_kinematics()
        player.sliders["frame"].value = 37
        np.testing.assert_allclose(player.scene.joint_positions, positions[37])
        assert "frame 37" in player.readout.value
        player.sliders["speed"].value = 2.0
        assert player.pacer.rate == pytest.approx(2 / sample_motion.frame_time)
        # the root's path lies on the floor, under every frame's root
        path = player.scene.trail.points[:sample_motion.n_frames]
        np.testing.assert_allclose(path[:, [0, 2]], positions[:, 0, [0, 2]])
        assert np.all(path[:, 1] <= positions[..., 1].min() + 1e-9)
    finally:
        player.close()


def test_bvh_player_draws_other_clips_beside_it_frame_by_frame(sample_motion):
    positions, _ = sample_motion.forward_kinematics()
    beside = positions + [15.0, 0.0, 0.0]
    player = viz.bvh_player(sample_motion, name="reference", others={"you": beside})
    try:
        assert [n for n, _ in player.scene.legend_entries()] == ["reference", "you"]
        player.sliders["frame"].value = 21
        np.testing.assert_allclose(player.scene.skeleton("reference").positions, positions[21])
        np.testing.assert_allclose(player.scene.skeleton("you").positions, beside[21])
        # framed on both clips: every frame of both lies in view at every frame
        for f in (0, sample_motion.n_frames - 1):
            player.sliders["frame"].value = f
            for pts in (positions[f], beside[f]):
                xy = player.scene.project(pts)
                w, h = player.scene.plotter.window_size
                assert np.all((xy >= 0) & (xy <= [w, h])), f
    finally:
        player.close()
    with pytest.raises(ValueError, match=r"others\['you'\] must have the clip's shape"):
        viz.bvh_player(sample_motion, others={"you": positions[:-1]})
    bad = beside.copy()
    bad[7, 3, 1] = np.nan
    with pytest.raises(ValueError, match=r"others\['you'\] is not finite at frame 7"):
        viz.bvh_player(sample_motion, others={"you": bad})


def test_bvh_player_draws_the_targets_of_each_frame(sample_motion):
    positions, _ = sample_motion.forward_kinematics()
    targets = positions[:, -1] + [0.0, 2.0, 0.0]  # one per frame, above the last joint
    player = viz.bvh_player(sample_motion, targets=targets)
    try:
        for f in (0, 17, sample_motion.n_frames - 1):
            player.sliders["frame"].value = f
            np.testing.assert_allclose(player.scene.target_positions, targets[f][None])
    finally:
        player.close()
    with pytest.raises(ValueError, match=r"targets must have shape \(\d+, 3\)"):
        viz.bvh_player(sample_motion, targets=targets[:-1])
    bad = np.repeat(targets[:, None], 2, axis=1)
    bad[4, 1, 0] = np.inf
    with pytest.raises(ValueError, match="targets is not finite at frame 4"):
        viz.bvh_player(sample_motion, targets=bad)


class FakeLoop:
    """A clock and ``call_later`` for playback: time moves only when the loop runs a callback
    (to its due time) or a picture is drawn (``cost`` seconds each)."""

    def __init__(self) -> None:
        self.now = 0.0
        self.queue: list[tuple[float, int, object]] = []
        self.calls = 0

    def clock(self) -> float:
        return self.now

    def call_later(self, delay: float, fn) -> None:
        assert delay >= 0
        self.calls += 1
        self.queue.append((self.now + delay, self.calls, fn))

    def run(self, seconds: float) -> None:
        end = self.now + seconds
        while self.queue:
            self.queue.sort(key=lambda e: e[:2])
            due, _, fn = self.queue[0]
            if due > end:
                break
            self.queue.pop(0)
            self.now = max(self.now, due)
            fn()
        self.now = max(self.now, end)


def _paced_player(motion, loop: FakeLoop, cost: list[float], **kwargs):
    """A player whose every picture costs ``cost[0]`` seconds of the fake clock; returns it
    and the list of frames it drew (in order)."""
    player = viz.bvh_player(motion, camera="iso", clock=loop.clock,
                                 call_later=loop.call_later, **kwargs)
    shown: list[int] = []
    draw = player.show_frame

    def timed(frame: int) -> None:
        draw(frame)
        loop.now += cost[0]
        shown.append(int(frame))

    player.show_frame = timed
    return player, shown


def test_playback_skips_frames_by_the_measured_picture_cost(sample_motion):
    import math

    loop, cost = FakeLoop(), [0.05]  # 20 pictures/s at most
    player, shown = _paced_player(sample_motion, loop, cost)
    fps = 1 / sample_motion.frame_time
    try:
        player.play.value = True
        assert player.play.description == "pause"
        loop.run(1.0)
        skip = math.ceil(fps * 0.05 - 1e-9)  # frames of clip per picture
        assert player.pacer.skip == skip
        steps = np.diff(shown)
        assert np.all(steps[steps > 0] == skip)  # honest: every skip-th frame, no more
        assert f"every {skip}" in player.readout.value or (skip == 1 and "every frame" in
                                                            player.readout.value)
        # the clip keeps its speed: about fps frames of clip per second of clock
        assert abs(shown[-1] - fps * 1.0) <= 2 * skip
        # pictures got cheaper (a quieter machine): the skip falls to the display's cap
        cost[0] = 0.001
        loop.run(2.0)
        assert player.pacer.skip == max(1, math.ceil(fps / 30 - 1e-9))
        assert player.sliders["frame"].value == player.frame == shown[-1]
        np.testing.assert_allclose(player.scene.joint_positions, player.positions[shown[-1]])
    finally:
        player.close()


def test_playback_waits_for_the_picture_in_flight_and_pause_stops_at_once(
        sample_motion, monkeypatch):
    loop, cost = FakeLoop(), [0.01]
    player, shown = _paced_player(sample_motion, loop, cost)
    in_flight = [0]
    monkeypatch.setattr(player.scene, "pictures_in_flight", lambda: in_flight[0])
    try:
        player.play.value = True
        loop.run(0.2)
        drawn = len(shown)
        assert drawn >= 2
        in_flight[0] = 1  # the last picture is not sent yet: no next one is drawn
        loop.run(0.5)
        assert len(shown) in (drawn, drawn + 1)  # at most the one already asked for
        drawn = len(shown)
        loop.run(0.3)
        assert len(shown) == drawn
        in_flight[0] = 0
        loop.run(0.2)
        assert len(shown) > drawn
        player.play.value = False
        assert player.play.description == "play" and "showing" not in player.readout.value
        drawn = len(shown)
        loop.run(2.0)
        assert len(shown) == drawn and not loop.queue  # nothing after pause, nothing pending
        # pause and play again while a picture is pending: still one picture at a time
        player.play.value = True
        loop.run(0.3)
        player.play.value = False
        player.play.value = True
        start, t0 = len(shown), loop.now
        loop.run(1.0)
        assert len(shown) - start <= (loop.now - t0) / player.pacer.interval + 1
    finally:
        player.close()


def test_playback_without_loop_stops_on_the_last_frame(sample_motion):
    loop, cost = FakeLoop(), [0.02]
    player, shown = _paced_player(sample_motion, loop, cost)
    last = sample_motion.n_frames - 1
    try:
        player.sliders["loop"].value = False
        player.sliders["frame"].value = last - 5
        player.play.value = True
        loop.run(5.0)
        assert shown[-1] == last and not player.playing and not loop.queue
        player.play.value = True  # from the end: starts again at 0
        assert shown[-1] in (0, player.pacer.skip)
    finally:
        player.close()


def test_playback_needs_a_kernel_loop_without_call_later(sample_motion):
    player = viz.bvh_player(sample_motion)
    try:
        with pytest.raises(RuntimeError, match="kernel"):
            player.play.value = True
    finally:
        player.close()


def test_bvh_player_curves_follow_the_frame(sample_motion):
    n = sample_motion.n_frames
    curves = {"root height": sample_motion.root_positions[:, 1] / 100, "zero": np.zeros(n)}
    player = viz.bvh_player(sample_motion, curves=curves)
    try:
        before = player.curves_image.value
        player.sliders["frame"].value = n // 2
        t = (n // 2) * sample_motion.frame_time
        np.testing.assert_allclose(player.curves.cursor.get_xdata(), [t, t])
        assert player.curves_image.value != before and player.curves_image.value[:4] == b"\x89PNG"
    finally:
        player.close()


@pytest.mark.parametrize("camera", ["front", "side", "top", "iso"])
def test_bvh_player_keeps_every_frame_in_view(sample_motion, camera):
    player = viz.bvh_player(sample_motion, camera=camera)
    try:
        w, h = player.scene.plotter.window_size
        uv = player.scene.project(player.positions.reshape(-1, 3))
        assert uv[:, 0].min() >= 0 and uv[:, 0].max() <= w
        assert uv[:, 1].min() >= 0 and uv[:, 1].max() <= h
        # and the clip fills the view along one side at least (not a speck in the middle)
        assert max(np.ptp(uv[:, 0]) / w, np.ptp(uv[:, 1]) / h) > 0.5
    finally:
        player.close()


def test_bvh_player_follow_camera_frames_every_pose_large():
    """follow: the clip's largest pose about the root, wherever the root walks; every frame
    lies in the view and spans at least a quarter of its shorter side."""
    from course import data

    walk = data.load("cmu_12_01_walk")
    player = viz.bvh_player(walk, camera="follow")
    try:
        w, h = player.scene.plotter.window_size
        for f in range(0, walk.n_frames, 7):
            player.sliders["frame"].value = f
            uv = player.scene.project(player.positions[f])
            assert uv.min() >= 0 and uv[:, 0].max() <= w and uv[:, 1].max() <= h, f
            assert max(np.ptp(uv[:, 0]), np.ptp(uv[:, 1])) >= 0.25 * min(w, h), f
    finally:
        player.close()


def test_ik_playground_solves_and_replays():
    from course.skeleton import chain

    arm = chain([1.0] * 7, axes=[0, 0, 1])
    pg = viz.ik_playground(arm, methods=["ccd"])
    try:
        pg.sliders["x"].value, pg.sliders["y"].value, pg.sliders["z"].value = 3.0, 4.0, 0.0
        target = pg.target
        r = pg.result
        fk, _ = arm.forward_kinematics(r.local_rotations, np.zeros(3))
        np.testing.assert_allclose(fk[-1], r.positions[-1], atol=1e-9)
        assert r.converged and np.linalg.norm(fk[-1] - target) <= pg.sliders["tol"].value
        np.testing.assert_allclose(pg.scene.target_positions[0], target)
        pg.sliders["iteration"].value = 0
        np.testing.assert_allclose(pg.scene.skeleton("solution").positions, pg.frames[0])
        assert "iteration 0" in pg.readout.value
        # the solution is drawn in colour, the start pose as a grey ghost
        assert pg.scene.skeleton("solution").bone_color == PALETTE[0][0]
        assert pg.scene.skeleton("start").bone_color == GHOST[0]
    finally:
        pg.close()


def test_ik_playground_says_when_a_solve_started_from_the_reach_start():
    from course.skeleton import chain

    arm = chain([1.0] * 4, axes=[0, 0, 1])
    pg = viz.ik_playground(arm, methods=["ccd"])
    try:
        pg._dragged(np.array([2.0, 1.0, 0.0]))  # 0.56 of the reach: the given start
        assert pg.result.start == "" and "near full reach" not in pg.readout.value
        pg._dragged(np.array([3.996, 0.0, 0.0]))  # 0.999 of the reach
        assert pg.result.start == "reach" and pg.result.converged
        assert "started bent evenly: the target is near full reach" in pg.readout.value
        pg._dragged(np.array([3.0, 3.0, 0.0]))  # beyond the reach of 4
        assert pg.result.reason == "unreachable"
        assert "out of reach: the chain is stretched towards the target" in pg.readout.value
    finally:
        pg.close()


def test_dragging_the_target_moves_the_sliders_and_solves_once(monkeypatch):
    from course.skeleton import chain

    arm = chain([1.0] * 5, axes=[0, 0, 1])
    pg = viz.ik_playground(arm, methods=["dls"])
    try:
        solves = []
        solve = pg.solve
        monkeypatch.setattr(pg, "solve", lambda **kw: (solves.append(1), solve(**kw)))
        pg._dragged(np.array([2.0, 3.0, 0.0]))
        assert len(solves) == 1, "three sliders moved but the target should be solved once"
        np.testing.assert_allclose(pg.target, [2.0, 3.0, 0.0])
        assert pg.result.converged
        np.testing.assert_allclose(pg.result.positions[-1], [2.0, 3.0, 0.0], atol=1e-4)
        pg._dragged(np.array([99.0, 0.0, 0.0]))  # beyond the sliders: clipped to their range
        assert pg.target[0] == pg.sliders["x"].max
    finally:
        pg.close()


def _browser_snap(slider, value):
    """What the browser's slider sends back for ``value``: the nearest ``min + n step``."""
    return slider.min + round((value - slider.min) / slider.step) * slider.step


def test_the_browser_rounding_a_target_slider_to_its_steps_moves_nothing(monkeypatch):
    from course.skeleton import chain

    target = np.array([-0.6037, 1.7013, 0.0])  # between the sliders' steps
    pg = viz.ik_playground(chain([1.0, 0.8, 0.6, 0.4], axes=[0, 0, 1]), methods=["ccd"],
                                target=target)
    try:
        first = pg.result
        solves = []
        monkeypatch.setattr(pg, "solve", lambda **_kw: solves.append(1))
        for c in "xy":  # as the browser does when it first shows the sliders
            snapped = _browser_snap(pg.sliders[c], pg.sliders[c].value)
            assert snapped != pg.sliders[c].value
            pg.sliders[c].value = snapped
        assert not solves and pg.result is first, "a rounding is not a move: no new solve"
        np.testing.assert_array_equal(pg.target, target)  # the notebook's target, exactly
        pg.sliders["x"].value = _browser_snap(pg.sliders["x"], target[0]) + pg.sliders["x"].step
        assert solves == [1], "one step of the slider is a move"
        assert pg.target[0] == pg.sliders["x"].value
    finally:
        pg.close()


def test_full_body_targets_ignore_the_browser_rounding_their_sliders(sample_motion):
    fb = viz.full_body_ik(sample_motion)
    try:
        name = fb.sliders["edit"].value
        before, iterations = fb.targets[name].copy(), fb.result.iterations
        for c in "xyz":
            fb.sliders[c].value = _browser_snap(fb.sliders[c], fb.sliders[c].value)
        np.testing.assert_array_equal(fb.targets[name], before)
        assert fb.result.iterations == iterations
        fb.sliders["y"].value = fb.sliders["y"].value + 5 * fb.sliders["y"].step
        assert fb.targets[name][1] == pytest.approx(fb.root_position[1] + fb.sliders["y"].value)
    finally:
        fb.close()


def test_ik_playground_convergence_plot_updates_in_place():
    from course.skeleton import chain

    pg = viz.ik_playground(chain([1.0] * 7, axes=[0, 0, 1]), methods=["dls", "ccd"])
    try:
        figure = pg.convergence.figure
        pg.sliders["y"].value = pg.sliders["y"].value + 0.2
        assert pg.convergence.figure is figure
        np.testing.assert_allclose(pg.convergence.curve.get_ydata(),
                                   np.maximum(pg.result.residuals, np.finfo(float).eps))
        pg.sliders["method"].value = "ccd"
        assert pg.convergence.label.get_text().startswith("ccd")
    finally:
        pg.close()


def test_full_body_ik_reaches_the_moved_target(sample_motion):
    fb = viz.full_body_ik(sample_motion, 10)
    try:
        name = fb.sliders["edit"].value
        fb.sliders["y"].value = fb.sliders["y"].value + 3.0
        j = fb.skeleton.index(name)
        drawn = fb.scene.skeleton("IK").positions
        assert np.linalg.norm(drawn[j] - fb.targets[name]) < np.linalg.norm(
            fb.positions[j] - fb.targets[name])
    finally:
        fb.close()


def test_full_body_ik_drag_moves_the_edited_target(sample_motion):
    fb = viz.full_body_ik(sample_motion, 10)
    try:
        name = fb.sliders["edit"].value
        goal = fb.targets[name] + [1.0, 2.0, 0.5]
        fb._dragged(goal)
        np.testing.assert_allclose(fb.targets[name], goal, atol=1e-9)
        j = fb.skeleton.index(name)
        assert np.linalg.norm(fb.scene.skeleton("IK").positions[j] - goal) < 1e-3
    finally:
        fb.close()


def test_full_body_ik_shows_a_long_solve_at_once_then_its_end(shared_bvh_dir, monkeypatch):
    """A press answers at once with the pose after PREVIEW_ITERATIONS; once the kernel has
    sent that picture the same solve runs to its end (the uninterrupted solve's pose, to the
    bit); a newer press makes the unfinished one moot, and reading ``result`` finishes it."""
    import course.ik
    from course.viz import full_body_ik_view

    later: list = []
    monkeypatch.setattr(full_body_ik_view, "soon", later.append)
    from course.bvh import load_bvh

    walk = load_bvh(shared_bvh_dir / "cmu_12_01_walk.bvh")  # notebook 06's view
    fb = viz.full_body_ik(walk, 0, root="LowerBack", method="fabrik",
                          effectors=["LeftHandIndex1_end", "RightHandIndex1_end"])
    try:
        later.clear()
        fb._finish()
        name = fb.sliders["edit"].value
        y = fb.sliders["y"]
        y.value = y.value + 16 * y.step  # 16 presses up: near the arm's reach, FABRIK crawls
        assert len(later) == 1 and "solving" in fb.readout.value, fb.readout.value
        preview = fb._result
        assert preview.iterations == fb.PREVIEW_ITERATIONS and not preview.converged
        np.testing.assert_array_equal(fb.scene.skeleton("IK").positions, preview.positions)
        later.pop()()  # the kernel sent the preview: the solve runs to its end
        full = course.ik.solve(fb.skeleton, fb.local, fb.root_position,
                               {e: fb.targets[e] for e in fb.sliders["effectors"].value},
                               method="fabrik", root="LowerBack")
        assert full.iterations > fb.PREVIEW_ITERATIONS
        np.testing.assert_array_equal(fb.result.positions, full.positions)
        np.testing.assert_array_equal(fb.scene.skeleton("IK").positions, full.positions)
        assert "solving" not in fb.readout.value and "residual" in fb.readout.value

        y.value = y.value + y.step
        stale = later.pop()
        y.value = y.value + y.step  # latest wins
        stale()  # the older press's remainder: nothing runs, nothing is drawn
        assert "solving" in fb.readout.value
        final = fb.result  # reading the result finishes the newest solve
        assert "solving" not in fb.readout.value
        assert np.linalg.norm(final.positions[fb.skeleton.index(name)] - fb.targets[name]) < 0.1
    finally:
        fb.close()


def test_full_body_ik_pulls_an_inner_joint(sample_motion):
    """Not only tips: the hand (not the hand's End Site) can be an effector, rooted at a foot."""
    fb = viz.full_body_ik(sample_motion, 10, root="LeftFoot", effectors=["LeftHand"])
    try:
        fb.sliders["x"].value = fb.sliders["x"].value + 2.0
        j, foot = fb.skeleton.index("LeftHand"), fb.skeleton.index("LeftFoot")
        drawn = fb.scene.skeleton("IK").positions
        assert fb.result.converged, fb.readout.value
        assert np.linalg.norm(drawn[j] - fb.targets["LeftHand"]) < 1e-3
        np.testing.assert_allclose(drawn[foot], fb.positions[foot], atol=1e-9)
    finally:
        fb.close()


# -- true starting states: the first picture is what the sliders and readouts say -------------


@pytest.fixture
def draggable_views(monkeypatch):
    """Controls built as in a server-rendered live view (a target handle to drag), without
    starting a trame server: the view widget is a placeholder."""
    import ipywidgets as widgets

    from course.viz import scene

    monkeypatch.setenv("PYVISTA_JUPYTER_BACKEND", "server")
    monkeypatch.setattr(scene.SkeletonScene, "widget", lambda self: widgets.HTML())


def test_full_body_ik_opens_on_the_captured_pose_with_its_targets(sample_motion,
                                                                  draggable_views):
    fb = viz.full_body_ik(sample_motion, 10)
    try:
        assert fb.handle is not None
        name = fb.sliders["edit"].value
        j = fb.skeleton.index(name)
        # the sliders say where the edited effector is (relative to the root), not 0/0/0
        sliders = [fb.sliders[c].value for c in "xyz"]
        np.testing.assert_allclose(sliders, fb.positions[j] - fb.root_position,
                                   atol=fb.sliders["x"].step)
        # nothing was pulled: the IK pose is the captured one, the handle on the effector
        np.testing.assert_allclose(fb.scene.skeleton("IK").positions, fb.positions, atol=1e-6)
        np.testing.assert_allclose(fb.handle.GetCenter(), fb.positions[j], atol=1e-9)
        fb._dragged(np.array(fb.handle.GetCenter()))  # a click that does not move it
        np.testing.assert_allclose(fb.scene.skeleton("IK").positions, fb.positions, atol=1e-6)
    finally:
        fb.close()


def test_ik_playground_handle_starts_on_the_target_and_a_click_moves_nothing(draggable_views):
    from course.skeleton import chain

    pg = viz.ik_playground(chain([1.0] * 5, axes=[0, 0, 1]), methods=["dls"])
    try:
        np.testing.assert_allclose(pg.handle.GetCenter(), pg.target, atol=1e-12)
        before = pg.scene.skeleton("solution").positions
        result = pg.result
        pg._dragged(np.array(pg.handle.GetCenter()))
        assert pg.result is result, "a callback without a move must not solve again"
        np.testing.assert_allclose(pg.scene.skeleton("solution").positions, before)
    finally:
        pg.close()


def test_ik_playground_opens_on_the_first_method_listed():
    from course.skeleton import chain

    leg = chain([1.0, 1.0], axes=[0, 0, 1])
    pg = viz.ik_playground(leg, methods=["two_link", "ccd", "dls"])
    try:
        assert pg.sliders["method"].value == "two_link"
        assert pg.readout.value.startswith("<b>two_link</b>"), pg.readout.value
    finally:
        pg.close()
    with pytest.raises(ValueError, match="method"):
        viz.ik_playground(leg, methods=["ccd"], method="dls")


# -- stable layout: readouts and warnings have their room before they have their text ----------


def test_the_lock_warning_has_reserved_room_and_the_panel_a_fixed_width():
    ex = viz.rotation_explorer("XYZ", (30.0, 20.0, 10.0), degrees=True)
    try:
        box = ex.widget.children[0]
        room = (ex.warning.layout.height, ex.readout.layout.height, box.layout.width)
        assert ex.warning.value == "" and ex.warning.layout.height is not None
        ex.sliders["angle1"].value = 90.0  # gimbal lock: the warning appears ...
        assert ex.gimbal_lock and "Gimbal lock" in ex.warning.value
        # ... in the room it had: nothing beside or below it moves
        assert (ex.warning.layout.height, ex.readout.layout.height, box.layout.width) == room
        assert ex.widget.layout.flex_flow == "row wrap", "views wrap instead of leaving"
    finally:
        ex.close()


def test_a_long_joint_list_keeps_its_readout_and_reset_button_in_sight(sample_motion):
    ex = viz.fk_explorer(sample_motion.skeleton)
    try:
        panel = ex.widget.children[0]
        assert panel.children[:3] == (ex.reset_button, ex.readout, ex.accordion)
        assert ex.reset_button.layout.min_height is not None  # never squashed to 0 px
        assert ex.accordion.layout.overflow == "auto"  # the joints scroll, not the readout
    finally:
        ex.close()


def test_ik_playground_frames_its_first_target_even_out_of_reach():
    from course.skeleton import chain

    arm = chain([1.0] * 6, axes=[0, 0, 1])
    goal = np.array([-2.0, 5.5, 2.0])  # beyond the chain's reach of 6
    pg = viz.ik_playground(arm, methods=["fabrik"], target=goal)
    try:
        w, h = pg.scene.plotter.window_size
        points = np.vstack([pg.scene.skeleton("solution").positions, goal])
        uv = pg.scene.project(points)
        assert np.all((uv > 0) & (uv < [w, h])), uv
    finally:
        pg.close()


def test_readouts_never_print_minus_zero_nor_one_iterations():
    assert panel.number(-1e-17) == "+0.000" and panel.number(-0.0004) == "+0.000"
    assert panel.number(-0.0006) == "-0.001" and panel.number(-1e-9, ".2f") == "0.00"
    assert panel.vec([-1e-12, 1.0]) == "(+0.000, +1.000)"
    assert "-0.000" not in panel.matrix_html(np.array([[1.0, -1e-17], [-2e-16, 1.0]]))
    assert panel.iterations(1) == "1 iteration" and panel.iterations(0) == "0 iterations"


def _px(length: str) -> float:
    assert length.endswith("px"), length
    return float(length[:-2])


def test_full_body_panel_and_view_fit_side_by_side_beside_the_file_browser(sample_motion):
    """Issue 28: at 1366 px with JupyterLab's file browser open the notebook is ~1000 px wide
    (less its gutter): the panel and the view must share one line there."""
    fb = viz.full_body_ik(sample_motion)
    try:
        panel, view = fb.widget.children
        assert fb.widget.layout.flex_flow == "row wrap"
        # the panel: a fixed width that holds its widest children (sliders, readout, pad)
        width = _px(panel.layout.width)
        assert panel.layout.min_width == panel.layout.width and panel.layout.flex == "0 0 auto"
        assert _px(fb.readout.layout.width) <= width
        for c in "xyz":
            assert _px(fb.sliders[c].layout.width) <= width
        pad = fb.drag.pad
        assert pad.size <= 140 and _px(pad.layout.margin.split()[3]) + pad.size + 2 <= width
        # the view: its flex basis is what the line needs; it grows and shrinks from there
        grow, shrink, basis = view.layout.flex.split()
        assert (grow, shrink) == ("1", "1")
        margin = _px(panel.layout.margin.split()[1])
        assert width + margin + _px(basis) <= 900  # ~1000 px less the prompt gutter
        assert _px(view.layout.min_width) <= _px(basis)
        assert view.layout.width is None and "640px" in view.layout.max_width
    finally:
        fb.close()


def test_full_body_view_is_marked_stale_while_a_solve_fails(sample_motion):
    fb = viz.full_body_ik(sample_motion, 10)
    try:
        ik = fb.scene.skeleton("IK")
        assert not fb.stale and all(a.prop.opacity == 1.0 for a in ik.actors)
        drawn = ik.positions
        fb.sliders["method"].value = "two_link"  # two effectors: two_link cannot solve it
        assert fb.stale
        assert "two_link" in fb.readout.value or "2-bone" in fb.readout.value \
            or "chain" in fb.readout.value
        assert "last solved pose" in fb.readout.value
        assert all(a.prop.opacity == fb.STALE_OPACITY for a in ik.actors)
        np.testing.assert_array_equal(ik.positions, drawn)  # the old pose, kept but dimmed
        fb.sliders["method"].value = "dls"  # a good solve clears the mark
        assert not fb.stale and "last solved pose" not in fb.readout.value
        assert all(a.prop.opacity == 1.0 for a in ik.actors)
    finally:
        fb.close()
