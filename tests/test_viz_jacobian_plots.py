"""course.viz.jacobian_plots: the figures of notebooks 07 and 08 draw what they were given
(FK positions, Jacobian columns, steps, iteration counts), checked on the artists' data."""

from __future__ import annotations

import os

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

import course.ik as ik  # noqa: E402
import course.rotations as rot  # noqa: E402
from course.skeleton import chain  # noqa: E402
from course.viz import jacobian_plots as plots  # noqa: E402
from course.viz.figures import METHOD_COLORS, mpl3  # noqa: E402

Z = np.array([0.0, 0.0, 1.0])


def _planar(angles_deg, lengths=(1.0, 0.8, 0.6)):
    arm = chain(list(lengths), axes=Z, names=["shoulder", "elbow", "wrist", "hand"])
    pose = np.tile(rot.quat_identity(), (len(lengths) + 1, 1))
    pose[:-1] = rot.quat_from_axis_angle(Z, np.radians(angles_deg))
    p, Q = arm.forward_kinematics(pose)
    J = ik.chain_jacobian(p[:-1], rot.quat_rotate(Q[:-1], Z), p[-1])
    return arm, pose, p, J


def _inside(ax, points):
    (x0, x1), (y0, y1) = sorted(ax.get_xlim()), sorted(ax.get_ylim())
    p = np.asarray(points)[..., :2].reshape(-1, 2)
    return bool(np.all((p[:, 0] >= x0) & (p[:, 0] <= x1) & (p[:, 1] >= y0) & (p[:, 1] <= y1)))


def _line_xy(line):
    return np.column_stack([line.get_xdata(), line.get_ydata()]).astype(float)


def test_jacobian_columns_are_arrows_from_the_hand():
    arm, _, p, J = _planar([30.0, 40.0, 30.0])
    fig = plots.jacobian_columns(p, J, arm.names, scale=0.45)
    ax = fig.axes[0]
    arrows = [t for t in ax.texts if hasattr(t, "xyann") and t.get_text() == ""]
    assert len(arrows) == 3
    for i, arrow in enumerate(arrows):
        assert np.allclose(arrow.xyann, p[-1, :2])                      # from the hand
        assert np.allclose(arrow.xy, p[-1, :2] + 0.45 * J[:2, i])       # along J_i
        lever = p[-1, :2] - p[i, :2]
        assert abs(np.dot(np.subtract(arrow.xy, arrow.xyann), lever)) < 1e-9  # planar: ⟂
    labels = [t.get_text() for t in ax.texts if t.get_text()]
    assert labels == ["$J_0$ (shoulder)", "$J_1$ (elbow)", "$J_2$ (wrist)"]
    chain_line = _line_xy(ax.lines[0])
    assert np.allclose(chain_line, p[:, :2])                             # the FK positions
    dotted = [_line_xy(ln) for ln in ax.lines if ln.get_linestyle() == ":"]
    assert all(np.allclose(d, [p[i, :2], p[-1, :2]]) for i, d in enumerate(dotted))
    assert _inside(ax, p) and _inside(ax, [a.xy for a in arrows])
    assert fig._repr_png_().startswith(b"\x89PNG")


def test_jacobian_columns_refuses_mismatched_shapes():
    arm, _, p, J = _planar([30.0, 40.0, 30.0])
    with pytest.raises(ValueError, match="J"):
        plots.jacobian_columns(p, J[:, :2], arm.names)


def test_solve_paths_draws_each_solve():
    arm = chain([1.0, 0.9, 0.8, 0.7], axes=Z)
    start = np.tile(rot.quat_identity(), (5, 1))
    start[:-1] = rot.quat_from_axis_angle(Z, np.radians(20.0))
    target = np.array([1.0, 2.0, 0.0])
    solves = {m: ik.solve(arm, start, np.zeros(3), {"end_effector": target}, method=m,
                          tol=1e-4, record=True) for m in ("jacobian_transpose", "dls")}
    p_start = arm.forward_kinematics(start)[0]
    fig = plots.solve_paths(p_start, solves, target, tol=1e-4)
    left, right = fig.axes
    assert left.get_yscale() == "log"
    for k, (m, r) in enumerate(solves.items()):
        path = next(ln for ln in right.lines if ln.get_label() == f"{m}: {r.iterations} steps")
        assert np.allclose(_line_xy(path)[-1], r.positions[-1, :2])     # ends on the hand
        assert path.get_color() == METHOD_COLORS[k]
        assert _inside(right, r.positions)
    assert np.allclose(_line_xy(right.lines[0]), p_start[:, :2])
    assert right.get_legend() is not None


def test_singular_sweep_plots_the_steps_against_sigma():
    sigma = np.geomspace(0.5, 1e-3, 6)
    pinv, dls = 0.1 / sigma, 0.1 * sigma / (sigma**2 + 0.01)
    poses = [np.array([[0, 0, 0], [1, 0, 0], [1 + np.cos(b), np.sin(b), 0]])
             for b in np.linspace(1.0, 0.0, 6)]
    delta_e = np.array([-0.1, 0.05, 0.0])
    fig = plots.singular_sweep(poses, delta_e, sigma, pinv, dls, 0.1, every=2)
    arm_ax, ax = fig.axes
    assert len(arm_ax.lines) == 4                                      # poses 0, 2, 4 and the last
    curves = [ln for ln in ax.lines if len(ln.get_xdata()) == len(sigma)]
    assert np.allclose(_line_xy(curves[0]), np.c_[sigma, pinv])
    assert np.allclose(_line_xy(curves[1]), np.c_[sigma, dls])
    bound = [ln for ln in ax.lines if ln.get_linestyle() == "--"][0]
    assert np.allclose(bound.get_ydata(), np.linalg.norm(delta_e) / 0.2)  # |Δe| / 2λ
    assert ax.xaxis_inverted() and ax.get_xscale() == "log"


def test_weighted_solves_labels_each_joint_turn():
    arm, _, p, _ = _planar([10.0, 10.0, 10.0])
    _, _, q, _ = _planar([40.0, 20.0, 5.0])
    fig = plots.weighted_solves(p, {"a": (q, [30.0, 10.0, 5.0]), "b": (p, [0.0, 0.0, 0.0])},
                                q[-1])
    a_ax, b_ax = fig.axes
    assert [t.get_text() for t in a_ax.texts] == ["30°", "10°", "5°"]
    assert np.allclose(_line_xy(a_ax.lines[1]), q[:, :2])
    assert a_ax.get_title() == "a" and _inside(a_ax, np.vstack([p, q]))


def test_least_squares_plane_returns_the_projection():
    rng = np.random.default_rng(3)
    J, de = rng.normal(size=(3, 2)), rng.normal(size=3)
    from matplotlib.figure import Figure

    ax = Figure().add_subplot(projection="3d")
    hit = plots.least_squares_plane(ax, J, de)
    assert np.allclose(hit, J @ np.linalg.pinv(J) @ de)                # the least-squares shadow
    assert np.allclose(J.T @ (de - hit), 0)                            # the miss ⟂ the columns
    labels = ax.get_legend_handles_labels()[1]
    assert "Δe" in labels and "the miss, perpendicular" in labels
    with pytest.raises(ValueError, match="J"):
        plots.least_squares_plane(ax, rng.normal(size=(3, 3)), de)


def test_null_space_lengths_has_its_minimum_at_the_pseudo_inverse_step():
    from matplotlib.figure import Figure

    rng = np.random.default_rng(4)
    J = rng.normal(size=(3, 5))
    step = np.linalg.pinv(J) @ rng.normal(size=3)
    null = np.linalg.svd(J)[2][3:].T
    ax = Figure().add_subplot()
    filled = plots.null_space_lengths(ax, step, null, extent=1.0)
    assert filled.levels[0] <= np.linalg.norm(step) + 1e-12             # no shorter exact step
    corner = np.linalg.norm(step + null @ [1.0, 1.0])
    assert filled.levels[-1] >= corner - 1e-12
    assert np.allclose(_line_xy(ax.lines[0]), [[0.0, 0.0]])            # the star at z = 0
    with pytest.raises(ValueError, match="null"):
        plots.null_space_lengths(ax, step, null[:4])


def test_wide_and_tall_has_three_panels():
    rng = np.random.default_rng(5)
    J_tall, de, J = rng.normal(size=(3, 2)), rng.normal(size=3), rng.normal(size=(3, 5))
    step = np.linalg.pinv(J) @ de
    fig = plots.wide_and_tall(J_tall, de, step, np.linalg.svd(J)[2][3:].T,
                              {"wide": [1.0, 0.1, 1e-5], "tall": [0.5, 0.3, 0.3]}, 0.3, tol=1e-4)
    three_d = [ax for ax in fig.axes if ax.name == "3d"]
    assert len(three_d) == 1
    errors = next(ax for ax in fig.axes if ax.get_yscale() == "log")
    assert any(np.allclose(ln.get_ydata(), 0.3) for ln in errors.lines
               if ln.get_label() == "closest the tall arm can get")


def test_root_choices_renders_one_panel_per_root():
    pytest.importorskip("pyvista")
    skel = chain([1.0, 1.0, 1.0])
    before = skel.forward_kinematics(np.tile(rot.quat_identity(), (4, 1)))[0]
    after = before.copy()
    after[2:] += [0.5, 0.0, 0.0]
    fig = plots.root_choices(skel.parents, before, {"base": after, "top": before},
                             {"base": before[0], "top": before[-1]}, after[-1], radius=0.05)
    assert [ax.get_title() for ax in fig.axes] == ["rooted at the base: 2 joints moved",
                                                   "rooted at the top: 0 joints moved"]
    assert all(len(ax.images) == 1 and ax.images[0].get_array().shape[:2] == (520, 420)
               for ax in fig.axes)


def test_race_figure_marks_mean_and_percentile():
    its = {"fabrik": np.array([1, 2, 3, 40]), "ccd": np.array([5, 6, 7, 300])}
    fig = plots.race_figure(its, {"fabrik": [1.0, 1e-3], "ccd": [1.0, 0.1, 1e-5]}, tol=0.01,
                            one_tol=1e-4, title="race")
    box_ax, one_ax = fig.axes
    means = next(ln for ln in box_ax.lines if ln.get_label() == "mean")
    assert np.allclose(means.get_ydata(), [11.5, 79.5])
    tails = next(ln for ln in box_ax.lines if ln.get_label() == "90th percentile")
    assert np.allclose(tails.get_ydata(), [np.percentile(v, 90) for v in its.values()])
    assert [t.get_text() for t in box_ax.get_xticklabels()] == ["fabrik", "ccd"]
    assert box_ax.get_yscale() == "log" and one_ax.get_title() == "One target, to tol = 0.0001"


def test_word_figure_traces_the_end_effector():
    word = [[-1.0, 2.0], [-1.0, 1.0], [0.5, 2.0]]
    frames = np.random.default_rng(6).normal(size=(30, 4, 3))
    fig = plots.word_figure(word, {1}, {"dls": frames, "ccd": frames + 0.1},
                            {"dls": np.full(30, 2), "ccd": np.full(30, 4)}, every=10)
    assert len(fig.axes) == 2
    ax = fig.axes[0]
    traced = next(ln for ln in ax.lines if ln.get_color() == METHOD_COLORS[0])
    assert np.allclose(np.array(traced.get_data_3d()), np.array(mpl3(frames[:, -1])))
    assert ax.get_title() == "dls\n2.0 iterations / frame"
    strokes = [ln for ln in ax.lines if ln.get_linestyle() in ("-", ":") and ln.get_lw() != 1.5]
    assert [ln.get_linestyle() for ln in strokes[:2]] == ["-", ":"]     # pen lifted on 1
    z0, z1 = ax.get_xlim()
    assert z0 <= min(frames[..., 2].min(), 2.0) and z1 >= max(frames[..., 2].max(), 2.0)


def test_smoothness_figure_bars_and_curves_share_colours():
    jerk = {"fabrik": 2e-4, "ccd": 3e-4, "dls": 1e-5}
    fig = plots.smoothness_figure(jerk, {"ccd": np.arange(5.0), "dls": np.ones(5)})
    bars_ax, curves_ax = fig.axes
    heights = [b.get_height() for b in bars_ax.patches]
    assert np.allclose(heights, list(jerk.values()))
    from matplotlib.colors import to_hex

    assert to_hex(bars_ax.patches[1].get_facecolor()) == curves_ax.lines[0].get_color()
    assert np.allclose(curves_ax.lines[0].get_ydata(), np.arange(5.0))
