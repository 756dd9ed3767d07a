"""course.viz.chain_plots: the IK notebooks' flat drawings show the chains, angles and rings
they are given, checked against forward kinematics, closed forms and the solvers."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402
from matplotlib.patches import Arc, Circle, Rectangle, Wedge  # noqa: E402

import course.rotations as rot  # noqa: E402
from course import ik  # noqa: E402
from course.skeleton import Skeleton, chain  # noqa: E402
from course.viz import chain_plots  # noqa: E402
from course.viz.figures import GHOST  # noqa: E402

Z = np.array([0.0, 0.0, 1.0])
ARM = chain([1.0, 0.8, 0.6, 0.4], axes=Z, names=["shoulder", "elbow", "wrist", "knuckle", "tip"])
R0 = rot.quat_from_axis_angle(Z, np.radians([20.0, 20.0, 20.0, 20.0, 0.0]))
P0 = ARM.forward_kinematics(R0)[0]


def _xy(line) -> np.ndarray:
    return np.column_stack(line.get_data()).astype(float)


def _arcs(ax) -> list[Arc]:
    return [p for p in ax.patches if isinstance(p, Arc)]


def _span(arc: Arc) -> float:
    return (arc.theta2 - arc.theta1) % 360.0


def _ax():
    return chain_plots.panels(1)[1][0]


def test_draw_chain_bones_and_joints_are_the_fk_positions():
    ax = _ax()
    bones, joints, end = chain_plots.draw_chain(ax, P0, end=True)
    np.testing.assert_allclose(_xy(bones), P0[:, :2])
    np.testing.assert_allclose(_xy(joints), P0[:-1, :2])
    np.testing.assert_allclose(_xy(end), P0[-1:, :2])
    assert end.get_markerfacecolor() == "white"


def test_draw_chain_of_a_tree_draws_each_bone_once_and_projects_planes():
    tree = Skeleton(["root", "a", "b", "c"], [-1, 0, 0, 2],
                    [[0, 0, 0], [1, 0, 0.5], [0, 1, 0.2], [0, 0.5, -1]])
    pos = tree.forward_kinematics(rot.quat_identity(4))[0]
    ax = _ax()
    bones, _ = chain_plots.draw_chain(ax, pos, parents=tree.parents, plane="zy")
    seg = _xy(bones).reshape(-1, 3, 2)
    assert np.isnan(seg[:, 2]).all(), "bones are separated by NaN breaks"
    for (parent_pt, child_pt), child in zip(seg[:, :2], range(1, 4), strict=True):
        np.testing.assert_allclose(parent_pt, pos[tree.parents[child]][[2, 1]])
        np.testing.assert_allclose(child_pt, pos[child][[2, 1]])


def test_draw_chain_rejects_bad_input_naming_it():
    ax = _ax()
    with pytest.raises(ValueError, match="points"):
        chain_plots.draw_chain(ax, np.zeros((4, 5)))
    with pytest.raises(ValueError, match="parents"):
        chain_plots.draw_chain(ax, P0, parents=[-1, 0])
    with pytest.raises(ValueError, match="plane"):
        chain_plots.draw_chain(ax, P0, plane="xw")


@settings(derandomize=True, max_examples=60, deadline=None)
@given(st.floats(-179.0, 179.0), st.floats(-179.0, 179.0), st.floats(0.2, 3.0))
def test_angle_arc_spans_the_smaller_angle_between_the_two_directions(a, b, radius):
    u = np.array([np.cos(np.radians(a)), np.sin(np.radians(a))])
    v = np.array([np.cos(np.radians(b)), np.sin(np.radians(b))])
    center = np.array([0.3, -0.2])
    arc, turn = chain_plots.angle_arc(_ax(), center, center + 2 * u, center + 0.5 * v, radius)
    angle = np.degrees(np.arccos(np.clip(u @ v, -1.0, 1.0)))  # independent: the dot product
    assert abs(turn) == pytest.approx(angle, abs=1e-6)
    if angle > 1e-3:
        assert np.sign(turn) == np.sign(u[0] * v[1] - u[1] * v[0])  # counter-clockwise > 0
    assert _span(arc) == pytest.approx(angle, abs=1e-6) or angle < 1e-6
    assert arc.width == pytest.approx(2 * radius) and tuple(arc.center) == pytest.approx(center)
    start = np.radians(arc.theta1)  # the arc starts at whichever ray is clockwise of the other
    assert any(np.allclose([np.cos(start), np.sin(start)], w, atol=1e-9) for w in (u, v))


def test_angle_arc_label_sits_on_the_bisector():
    ax = _ax()
    chain_plots.angle_arc(ax, (0, 0), (1, 0), (0, 1), 0.5, text="α", text_radius=1.0)
    (label,) = ax.texts
    assert label.get_text() == "α"
    np.testing.assert_allclose(label.get_position(), [np.sqrt(0.5), np.sqrt(0.5)])


def test_reach_annulus_is_the_ring_between_the_two_radii():
    ax = _ax()
    ring = chain_plots.reach_annulus(ax, 0.4, 1.6, center=(0.5, 0.0))
    assert isinstance(ring, Wedge) and ring.r == 1.6 and ring.width == pytest.approx(1.2)
    rims = sorted(p.radius for p in ax.patches if isinstance(p, Circle))
    assert rims == [0.4, 1.6]
    assert tuple(ring.center) == (0.5, 0.0) and (ring.theta1, ring.theta2) == (0, 360)
    assert all(tuple(p.center) == (0.5, 0.0) for p in ax.patches)
    disc = chain_plots.reach_annulus(_ax(), 0.0, 2.0)
    assert disc.width is None
    with pytest.raises(ValueError, match="inner"):
        chain_plots.reach_annulus(ax, 2.0, 1.0)


def test_iteration_panels_of_a_ccd_sweep_draw_each_step_and_its_angle():
    target = np.array([-0.6, 1.7, 0.0])
    poses, angles, P = [P0], [], P0
    order = [3, 2, 1, 0]
    for i in order:
        q = rot.quat_between(P[-1] - P[i], target - P[i])
        angles.append(np.degrees(rot.axis_angle_from_quat(q)[1]))
        P = P.copy()
        P[i + 1:] = P[i] + rot.quat_rotate(q, P[i + 1:] - P[i])
        poses.append(P)
    titles = ["start"] + [f"step {k}" for k in range(1, 5)]
    fig = chain_plots.iteration_panels(poses, titles, target=target, pivots=[None, *order],
                                       xlim=(-1.3, 2.6), ylim=(-0.4, 2.4))
    axes = [ax for ax in fig.axes if ax.get_visible()]
    assert [ax.get_title() for ax in axes] == titles
    for k, ax in enumerate(axes[1:], start=1):
        ghost = next(line for line in ax.lines if line.get_color() == GHOST)
        np.testing.assert_allclose(_xy(ghost), poses[k - 1][:, :2])
        np.testing.assert_allclose(_xy(ax.lines[-3]), poses[k][:, :2])  # bones, joints, end
        (arc,) = _arcs(ax)
        assert _span(arc) == pytest.approx(angles[k - 1], abs=1e-6)
        np.testing.assert_allclose(arc.center, poses[k - 1][order[k - 1], :2])
        x0, x1, y0, y1 = *ax.get_xlim(), *ax.get_ylim()
        assert (poses[k][:, 0] >= x0).all() and (poses[k][:, 0] <= x1).all()
        assert (poses[k][:, 1] >= y0).all() and (poses[k][:, 1] <= y1).all()


def test_iteration_panels_of_fabrik_passes_draw_an_arrow_per_moved_joint():
    target, base = np.array([-1.2, 0.2, 0.0]), P0[0]
    after, _, _ = ik.fabrik_positions(P0, target, max_iter=1)
    fig = chain_plots.iteration_panels([P0, after], ["start", "one iteration"], target=target,
                                       base=base, arrows=True, ncols=3)
    arrows = [t for t in fig.axes[1].texts if t.arrow_patch is not None]
    moved = np.linalg.norm(after - P0, axis=1) > 0.01 * np.ptp(np.vstack([P0, after]), 0).max()
    assert len(arrows) == moved.sum()
    for arrow, p, q in zip(arrows, P0[moved], after[moved], strict=True):
        np.testing.assert_allclose(arrow.xy, q[:2])
        np.testing.assert_allclose(arrow.xyann, p[:2])
    assert not fig.axes[2].get_visible(), "the unused panel of the row is hidden"
    with pytest.raises(ValueError, match="titles"):
        chain_plots.iteration_panels([P0, after], ["start"])


def test_overlay_panels_two_mirror_solutions_with_the_ring_and_legend():
    a, b, c = np.array([[0.0, 0, 0], [1.0, 0, 0], [1.6, 0, 0]])
    t = np.array([0.9, 0.7, 0.0])
    up = np.stack([a, *ik.two_link(a, b, c, t, pole=[0.0, 1.0, 0.0])[:2]])
    down = np.stack([a, *ik.two_link(a, b, c, t, pole=[0.0, 1.0, 0.0], flip=True)[:2]])
    fig = chain_plots.overlay_panels([{"elbow +1": up, "elbow −1": down}], [t], ["mirror"],
                                     annulus=(0.4, 1.6), root_lines=True, ghost=np.stack([a, b, c]))
    ax = fig.axes[0]
    assert [x.get_text() for x in ax.get_legend().get_texts()] == ["elbow +1", "elbow −1", "start"]
    drawn = [_xy(line) for line in ax.lines if line.get_label() in ("elbow +1", "elbow −1")]
    np.testing.assert_allclose(drawn[0], up[:, :2])
    np.testing.assert_allclose(drawn[1], down[:, :2])
    assert any(isinstance(p, Wedge) and p.r == 1.6 for p in ax.patches)
    with pytest.raises(ValueError, match="same length"):
        chain_plots.overlay_panels([{"x": up}], [t, t], ["a"])


def test_law_of_cosines_figure_arcs_are_alpha_and_beta():
    l1, l2 = 1.0, 0.6
    a, b, c = np.array([[0.0, 0, 0], [l1, 0, 0], [l1 + l2, 0, 0]])
    t = np.array([0.9, 0.7, 0.0])
    mid, end, reached = ik.two_link(a, b, c, t)
    assert reached
    fig = chain_plots.law_of_cosines_figure(a, mid, end, t)
    ax = fig.axes[0]
    d = np.linalg.norm(t)
    alpha = np.degrees(np.arccos((l1**2 + d**2 - l2**2) / (2 * l1 * d)))
    beta = np.degrees(np.arccos((l1**2 + l2**2 - d**2) / (2 * l1 * l2)))
    at_root, at_mid = _arcs(ax)
    assert _span(at_root) == pytest.approx(alpha) and _span(at_mid) == pytest.approx(beta)
    np.testing.assert_allclose(at_mid.center, mid[:2])
    labels = {text.get_text() for text in ax.texts}
    assert {"α", "β", "l₁", "l₂", "d", "t"} <= labels


def test_reachability_figure_colours_reached_and_missed_targets():
    hands = np.random.default_rng(0).uniform(-1, 1, (50, 2))
    reached_arm = np.array([[0.0, 0], [1.0, 0], [0.9, 0.7]])
    missed_arm = np.array([[0.0, 0], [0.8, 0.6], [1.2, 0.9]])
    fig = chain_plots.reachability_figure(
        0.4, 1.6, hands, [reached_arm],
        {"in": ([0.9, 0.7], reached_arm), "far": ([2.0, 1.5], missed_arm)})
    left, right = fig.axes
    np.testing.assert_allclose(_xy(left.lines[0]), hands)
    stars = [line for line in right.lines if line.get_marker() == "*"]
    assert [s.get_color() for s in stars] == [chain_plots.GREEN, chain_plots.TARGET]
    (gap,) = [line for line in right.lines if line.get_linestyle() == ":"]
    np.testing.assert_allclose(_xy(gap), [[1.2, 0.9], [2.0, 1.5]])


def test_body_views_fit_every_joint_and_widen_the_highlighted_leg():
    tree = Skeleton(["hips", "knee", "foot", "chest"], [-1, 0, 1, 0],
                    [[0, 0, 0], [0, -4, 1], [0, -4, -1], [0, 5, 0]])
    pose = tree.forward_kinematics(rot.quat_identity(4), [1.0, 8.0, -2.0])[0]
    fig = chain_plots.body_views(tree.parents, {"captured": pose, "moved": pose + [0, 0, 1]},
                                 targets=pose[2:3], markers={"pole": pose[1] + [0, 0, 2]},
                                 highlight=[1, 2], ground=-0.5, step=(-3.0, 0.0, 1.0))
    side, front = fig.axes
    for ax, cols in ((side, [2, 1]), (front, [0, 1])):
        (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
        p = pose[:, cols]
        assert (p[:, 0] >= x0).all() and (p[:, 0] <= x1).all()
        assert (p[:, 1] >= y0).all() and (p[:, 1] <= y1).all()
        widths = [line.get_linewidth() for line in ax.lines[:3]]  # the first pose's 3 bones
        assert widths == [6.0, 6.0, 4.0]
    (box,) = [p for p in side.patches if isinstance(p, Rectangle)]
    assert box.get_height() == pytest.approx(1.5) and box.get_width() == pytest.approx(3.0)
    with pytest.raises(ValueError, match="poses"):
        chain_plots.body_views(tree.parents, {"bad": pose[:3]})


def test_pole_figure_draws_each_leg_and_rejects_mismatched_poles():
    legs = np.array([[[0.0, 0, 0], [0, -0.5, 0.4], [0.1, -1.2, 0.2]]] * 2)
    poles = np.array([[0.0, -0.5, 1.0], [0.0, -0.5, -1.0]])
    fig = chain_plots.pole_figure(legs, poles, legs[0, 2], np.zeros((5, 3)))
    ax = fig.axes[0]
    leg_lines = [line for line in ax.lines if line.get_marker() == "o"]
    X, Y, Zm = leg_lines[0].get_data_3d()
    np.testing.assert_allclose(np.column_stack([Y, Zm, X]), legs[0])  # matplotlib's (z, x, y)
    with pytest.raises(ValueError, match="poles"):
        chain_plots.pole_figure(legs, poles[:1], legs[0, 2], np.zeros((5, 3)))


def test_subbase_figure_marks_the_centroid_of_the_proposals():
    parents = [-1, 0, 1, 1]
    start = np.array([[0.0, 0, 0], [0, 1, 0], [1, 1.5, 0], [-1, 1.5, 0]])
    proposals = {"a": np.array([[0.2, 1.1, 0], [1.2, 1.4, 0]]),
                 "b": np.array([[-0.1, 0.9, 0], [-1.1, 1.2, 0]])}
    centroid = np.mean([p[0] for p in proposals.values()], axis=0)
    fig = chain_plots.subbase_figure(parents, start, proposals, centroid, [start, start * 1.1],
                                     np.array([[1.2, 1.4, 0], [-1.1, 1.2, 0]]))
    (plus,) = [line for line in fig.axes[1].lines if line.get_marker() == "P"]
    np.testing.assert_allclose(_xy(plus)[0], centroid[:2])
    assert "1 iterations" in fig.axes[2].get_title()


def test_tracking_and_frame_change_plots_show_the_joint_motion():
    frames = 30
    theta = np.cumsum(np.full((frames, 4), 0.05), axis=0)
    poses = np.stack([ARM.forward_kinematics(rot.quat_from_axis_angle(Z, np.append(th, 0.0)))[0]
                      for th in theta])
    path = poses[:, -1]
    fig = chain_plots.tracking_figure(path, {"ccd": (theta, poses, frames)}, ARM.names)
    top, bottom = fig.axes
    np.testing.assert_allclose(_xy(top.lines[0]), path[:, :2])
    assert len(top.lines) == 1 + frames // 5
    np.testing.assert_allclose(bottom.lines[0].get_ydata(), np.degrees(theta[:, 0]))
    assert f"{np.degrees(0.05 * 4):.1f}°/frame" in bottom.get_title()
    change = chain_plots.frame_change_plot({"ccd": theta, "dls": theta / 2})
    ccd, dls = change.axes[0].lines
    np.testing.assert_allclose(ccd.get_ydata(), np.degrees(0.2))
    np.testing.assert_allclose(dls.get_ydata(), np.degrees(0.1))
    assert ccd.get_color() == chain_plots.METHOD_COLOR["ccd"]


def test_turn_violins_history_and_histogram():
    turns = np.random.default_rng(1).uniform(0, 180, (40, 4))
    fig = chain_plots.turn_violins({"tip to root": turns}, [range(3, -1, -1)], ARM.names)
    ticks = [t.get_text() for t in fig.axes[0].get_xticklabels()]
    assert ticks == ["1. knuckle", "2. wrist", "3. elbow", "4. shoulder"]
    with pytest.raises(ValueError, match="orders"):
        chain_plots.turn_violins({"a": turns}, [], ARM.names)

    res = ik.solve(ARM, R0, [0.0, 0.0, 0.0], {"tip": [-0.6, 1.7, 0.0]}, method="ccd",
                   tol=1e-4, record=True)
    frames = np.array([f["positions"] for f in res.frames])
    fig = chain_plots.history_figure(frames, {"ccd": res.residuals}, target=[-0.6, 1.7, 0.0])
    left, right = fig.axes
    (path,) = [line for line in left.lines if line.get_label() == "end effector path"]
    np.testing.assert_allclose(_xy(path), frames[:, -1, :2])
    np.testing.assert_allclose(right.lines[0].get_ydata(), np.maximum(res.residuals, 2e-16),
                               rtol=1e-6)

    ax = chain_plots.panels(1)[1][0]
    chain_plots.iterations_histogram(ax, {"ccd": [1, 3, 70], "fabrik": [1, 2, 2]}, clip=60)
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["CCD (median 3)",
                                                                    "FABRIK (median 2)"]
    heights = [sum(p.get_height() for p in c) for c in ax.containers]
    assert heights == [3, 3], "a count above clip is drawn at clip, not dropped"


def test_figures_show_themselves_as_png_and_snapshots_as_html():
    fig, _ = chain_plots.panels(2, xlim=(-1, 1), ylim=(-1, 1))
    assert fig._repr_png_()[:8] == b"\x89PNG\r\n\x1a\n"
    assert all(ax.get_aspect() == 1.0 for ax in fig.axes)
    html = chain_plots.snapshot_row([("a", b"x"), ("b", b"y")]).data
    assert html.count("<img") == 2 and "<figcaption" in html
    with pytest.raises(ValueError, match="ncols"):
        chain_plots.panels(0)
