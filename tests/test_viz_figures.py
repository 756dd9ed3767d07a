"""course.viz.figures: the pixels of the matplotlib figures, and the math they draw."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from mpl_toolkits.mplot3d import proj3d  # noqa: E402
from scipy.spatial.transform import Rotation, Slerp  # noqa: E402

from course.viz.figures import (  # noqa: E402
    JOINT,
    ChainPlot,
    ConvergenceFigure,
    GimbalFigure,
    JointAngleFigure,
    SlerpArcFigure,
    convergence_plot,
    slerp_arc_figure,
)

PARENTS = np.array([-1, 0, 1, 2])
ARM = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0.5, 0], [2.5, 1.3, 0]])
JOINT_RGB = np.array([int(JOINT[i:i + 2], 16) for i in (1, 3, 5)])


def _joint_coloured(img: np.ndarray, uv: np.ndarray, tol: float = 40.0) -> np.ndarray:
    ok = []
    for c, r in np.round(uv).astype(int):
        patch = img[r - 2:r + 3, c - 2:c + 3, :3].reshape(-1, 3).astype(float)
        ok.append(np.linalg.norm(patch - JOINT_RGB, axis=1).min() < tol)
    return np.array(ok)


def test_chain_2d_joints_in_joint_colour_and_blitted_updates(monkeypatch):
    plot = ChainPlot(PARENTS, ARM)
    img = plot.image()
    assert _joint_coloured(img, plot.data_to_pixels(ARM[:, :2])).all()
    corner = plot.data_to_pixels([[-2.5, -2.5]])[0]  # inside the axes, far from the arm
    c, r = np.round(corner).astype(int)
    assert (img[r, c, :3] == 255).all()

    def no_full_draw() -> None:
        raise AssertionError("update() must blit, not redraw the figure")

    monkeypatch.setattr(plot.figure.canvas, "draw", no_full_draw)
    bent = np.array([[0.0, 0, 0], [0, 1, 0], [-0.7, 1.7, 0], [-1.5, 2.0, 0]])
    plot.update(bent, target=[1.5, 2.0, 0], trail=True)
    img2 = plot.image()
    assert _joint_coloured(img2, plot.data_to_pixels(bent[:, :2])).all()
    c, r = np.round(plot.data_to_pixels(ARM[3:, :2])[0]).astype(int)
    assert (img2[r, c, :3] == 255).all(), "the old end effector was not erased"
    assert plot.png()[:8] == b"\x89PNG\r\n\x1a\n"


def test_chain_3d_joints_at_their_projection():
    pose = np.array([[0.0, 0, 0], [0, 1, 0], [0.6, 1.6, 0.3], [1.2, 2.0, 0.9]])
    plot = ChainPlot(PARENTS, pose, dims=3)
    ax = plot.ax
    # stored as matplotlib (X, Y, Z) = (z, x, y): right-handed, y up
    xs, ys, zs = pose[:, 2], pose[:, 0], pose[:, 1]
    px, py, _ = proj3d.proj_transform(xs, ys, zs, ax.get_proj())
    disp = ax.transData.transform(np.column_stack([px, py]))
    uv = np.column_stack([disp[:, 0], plot.figure.bbox.height - disp[:, 1]])
    assert _joint_coloured(plot.image(), uv).all()
    moved = pose + [0.5, 0, 0]

    def no_full_draw() -> None:
        raise AssertionError("update() must blit in 3D too: the view does not move")

    draw, plot.figure.canvas.draw = plot.figure.canvas.draw, no_full_draw
    plot.update(moved)
    plot.figure.canvas.draw = draw
    np.testing.assert_allclose(np.column_stack(plot.joints.get_data_3d()), moved[:, [2, 0, 1]])
    px, py, _ = proj3d.proj_transform(moved[:, 2], moved[:, 0], moved[:, 1], ax.get_proj())
    disp = ax.transData.transform(np.column_stack([px, py]))
    uv = np.column_stack([disp[:, 0], plot.figure.bbox.height - disp[:, 1]])
    assert _joint_coloured(plot.image(), uv).all(), "the blitted joints are not where they project"


def test_chain_plot_rejects_bad_shapes():
    with pytest.raises(ValueError, match="positions"):
        ChainPlot(PARENTS, ARM[:2])
    with pytest.raises(ValueError, match="plane"):
        ChainPlot(PARENTS, ARM, plane="yy")


def test_convergence_plot_one_log_line_per_method():
    res = {"ccd": 0.5 ** np.arange(12), "dls": 10.0 ** -np.arange(5.0)}
    ax = convergence_plot(res, tol=1e-4)
    assert ax.get_yscale() == "log"
    lines = [ln for ln in ax.get_lines() if ln.get_label().split()[0] in res]
    assert len(lines) == 2
    np.testing.assert_allclose(lines[0].get_ydata(), res["ccd"])
    np.testing.assert_array_equal(lines[1].get_xdata(), np.arange(5))


def _ring_normal(line) -> np.ndarray:
    x, y, z = line.get_data_3d()
    pts = np.column_stack([y, z, x])  # back to world (x, y, z)
    n = np.cross(pts[5] - pts[0], pts[30] - pts[0])
    return n / np.linalg.norm(n)


def test_gimbal_rings_coplanar_exactly_at_lock():
    fig = GimbalFigure("XYZ", (0.4, np.pi / 2, -0.3))
    outer, inner = (_ring_normal(fig.rings[k]) for k in (0, 2))
    assert abs(abs(outer @ inner) - 1) < 1e-9
    fig.update((0.4, 0.5, -0.3), "XYZ")
    outer, middle, inner = (_ring_normal(r) for r in fig.rings)
    assert abs(outer @ inner) < 0.99
    # ring k's normal is R_1..R_k applied to its axis: the middle ring turns with the outer
    R = Rotation.from_euler("XYZ", [0.4, 0.5, -0.3])
    np.testing.assert_allclose(abs(middle @ Rotation.from_euler("X", 0.4).apply([0, 1, 0])), 1,
                               atol=1e-9)
    np.testing.assert_allclose(abs(inner @ R.apply([0, 0, 1])), 1, atol=1e-9)
    # the inner ring's frame is the rotated frame of R
    frame = np.array([np.array(ln.get_data_3d())[:, 1] for ln in fig.frame])[:, [1, 2, 0]]
    np.testing.assert_allclose(frame / 0.55, R.as_matrix().T, atol=1e-9)


def test_slerp_ticks_evenly_spaced_nlerp_not():
    q0 = Rotation.identity()
    q1 = Rotation.from_euler("XYZ", [0.3, 2.4, 0.5])
    fig = slerp_arc_figure(q0.as_quat(scalar_first=True), q1.as_quat(scalar_first=True), n=9)
    ax = fig.axes[0]
    marks = [ln for ln in ax.get_lines() if ln.get_marker() == "o"]
    nlerp, slerp = (np.column_stack(ln.get_data_3d())[:, [1, 2, 0]] for ln in marks)
    ref = Slerp([0, 1], Rotation.concatenate([q0, q1]))(np.linspace(0, 1, 9)).apply([0, 0, 1])
    np.testing.assert_allclose(slerp, ref, atol=1e-9)
    steps = lambda p: np.arccos(np.clip(np.sum(p[1:] * p[:-1], axis=1), -1, 1))  # noqa: E731
    assert np.ptp(steps(slerp)) < 1e-6
    assert np.ptp(steps(nlerp)) > 1e-3


def test_joint_angle_cursor_moves_to_the_frame():
    t = np.linspace(0, 2 * np.pi, 50)
    fig = JointAngleFigure(np.column_stack([np.sin(t), np.cos(t)]), 0.1, ["knee", "hip"])
    fig.set_frame(20)
    np.testing.assert_allclose(fig.cursor.get_xdata(), [2.0, 2.0])
    with pytest.raises(ValueError, match="angles"):
        JointAngleFigure(np.zeros((5, 3)), 0.1, ["a"])


def test_joint_angle_legend_covers_no_curve_and_no_cursor():
    t = np.linspace(0, 4, 400)
    knees = np.radians(np.column_stack([60 * np.sin(3 * t) ** 2, 60 * np.cos(3 * t) ** 2]))
    fig = JointAngleFigure(knees, 0.01, ["LeftLeg (knee) flexion", "RightLeg (knee) flexion"],
                           figsize=(7.2, 2.4))
    renderer = fig.figure.canvas.get_renderer()
    legends = fig.figure.legends + [fig.ax.get_legend()] * (fig.ax.get_legend() is not None)
    assert len(legends) == 1 and len(legends[0].get_texts()) == 2
    box = legends[0].get_window_extent(renderer)
    # the curves and the cursor (at any frame) are drawn inside the axes: the legend is not
    assert not box.overlaps(fig.ax.get_window_extent(renderer))
    assert box.y0 >= fig.ax.get_window_extent(renderer).y1
    assert fig.figure.bbox.contains(box.x0, box.y0) and fig.figure.bbox.contains(box.x1, box.y1)


def _no_full_draw(figure) -> None:
    def refuse() -> None:
        raise AssertionError("this update must blit, not redraw the figure")

    figure.canvas.draw = refuse


def test_slerp_arc_moves_by_blitting_and_marks_t():
    q0 = Rotation.identity()
    q1 = Rotation.from_euler("XYZ", [0.3, 2.4, 0.5])
    arc = SlerpArcFigure(q0.as_quat(scalar_first=True), q1.as_quat(scalar_first=True), t=0.25)
    before = np.asarray(arc.figure.canvas.buffer_rgba()).copy()
    _no_full_draw(arc.figure)
    arc.set_t(0.75)
    slerp_marker = np.column_stack(arc.current[1].get_data_3d())[:, [1, 2, 0]]
    ref = Slerp([0, 1], Rotation.concatenate([q0, q1]))([0.75]).apply([0, 0, 1])
    np.testing.assert_allclose(slerp_marker, ref, atol=1e-9)
    q2 = Rotation.from_euler("XYZ", [1.0, -0.4, 0.2])
    arc.set_rotations(q0.as_quat(scalar_first=True), q2.as_quat(scalar_first=True))
    end = np.column_stack(arc.marks[1].get_data_3d())[-1, [1, 2, 0]]
    np.testing.assert_allclose(end, q2.apply([0, 0, 1]), atol=1e-9)
    assert not np.array_equal(before, np.asarray(arc.figure.canvas.buffer_rgba()))


def test_gimbal_update_blits_unless_the_order_changes():
    fig = GimbalFigure("XYZ", (0.1, 0.2, 0.3))
    before = np.asarray(fig.figure.canvas.buffer_rgba()).copy()
    draw = fig.figure.canvas.draw
    _no_full_draw(fig.figure)
    fig.update((0.9, 0.2, 0.3), "XYZ")
    assert not np.array_equal(before, np.asarray(fig.figure.canvas.buffer_rgba()))
    fig.figure.canvas.draw = draw
    fig.update((0.9, 0.2, 0.3), "zxz")  # a new title: one full redraw
    assert "zxz" in fig.ax.get_title()


def test_convergence_figure_blits_within_its_limits_and_rescales_beyond():
    fig = ConvergenceFigure()
    fig.update(10.0 ** -np.arange(6.0), 1e-4, "dls: 5 iterations")
    assert fig.ax.get_yscale() == "log"
    assert fig.limits == (10.0, 1e-7, 1.0)
    np.testing.assert_allclose(fig.curve.get_ydata(), 10.0 ** -np.arange(6.0))
    draw = fig.figure.canvas.draw
    _no_full_draw(fig.figure)
    fig.update(0.5 * 10.0 ** -np.arange(7.0), 1e-4, "dls: 6 iterations")  # same limits
    assert fig.label.get_text() == "dls: 6 iterations"
    fig.figure.canvas.draw = draw
    fig.update(0.9 ** np.arange(40.0), 1e-4, "ccd: 39 iterations")  # more iterations
    assert fig.limits[0] == 50.0
    np.testing.assert_allclose(fig.tol_line.get_ydata(), [1e-4, 1e-4])
    assert fig.png()[:4] == b"\x89PNG"
