"""course.viz.skeleton_plots: the figures of notebooks 02 and 03 draw the poses, layouts,
contacts and angles they are given (artists' data against FK and closed forms)."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402
from matplotlib.text import Annotation  # noqa: E402
from scipy.spatial.transform import Rotation  # noqa: E402

import course.rotations as rot  # noqa: E402
from course.skeleton import Skeleton, chain  # noqa: E402
from course.viz import skeleton_plots  # noqa: E402
from course.viz.chain_plots import panels  # noqa: E402
from course.viz.figures import AXIS_RGB  # noqa: E402

Z = np.array([0.0, 0.0, 1.0])


def _segments(line) -> np.ndarray:
    """The (start, end) pairs of a NaN-separated bone polyline, or of a plain polyline."""
    xy = np.column_stack([line.get_xdata(), line.get_ydata()])
    if np.isnan(xy).any():
        return xy.reshape(-1, 3, 2)[:, :2]
    return np.stack([xy[:-1], xy[1:]], axis=1)


def _star() -> Skeleton:
    """A root with three limbs (a hub), one of them branching once more."""
    names = ["root", "a", "a_end", "b", "b_end", "c", "c1", "c1_end", "c2_end"]
    parents = [-1, 0, 1, 0, 3, 0, 5, 6, 6]
    offsets = [[0, 0, 0], [1, 0, 0], [1, 0, 0], [-1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, 1, 0],
               [1, 1, 0], [-1, 1, 0]]
    return Skeleton(names, parents, offsets)


def test_arm_panels_draw_the_fk_pose_its_frames_and_global_turns():
    arm = chain([1.0, 0.8, 0.5], axes=Z, names=["shoulder", "elbow", "wrist", "hand"])
    theta = np.radians([30.0, 45.0, -60.0])
    p, Q = arm.forward_kinematics(rot.quat_from_axis_angle(Z, np.r_[theta, 0.0]))
    sweep = [arm.forward_kinematics(rot.quat_from_axis_angle(Z, [theta[0], e, theta[2], 0.0]))
             for e in np.radians([-90, 0, 90])]
    fig = skeleton_plots.arm_panels({"one": [(p, Q)], "sweep": sweep}, names=arm.names)
    one, many = fig.axes
    bones = one.lines[0]
    np.testing.assert_allclose(np.column_stack(bones.get_data()), p[:, :2])
    # closed form of the planar arm: the angles add up along the chain
    cum = np.cumsum(theta)
    tips = np.cumsum([[0, 0]] + [[ln * np.cos(a), ln * np.sin(a)]
                                 for ln, a in zip([1.0, 0.8, 0.5], cum, strict=True)], axis=0)
    np.testing.assert_allclose(np.column_stack(bones.get_data()), tips, atol=1e-12)
    arrows = [t for t in one.texts if isinstance(t, Annotation)]
    assert len(arrows) == 2 * len(p)
    M = Rotation.from_quat(Q[:, [1, 2, 3, 0]]).as_matrix()
    for k, arrow in enumerate(arrows):
        j, axis = divmod(k, 2)
        np.testing.assert_allclose(arrow.xyann, p[j, :2])
        np.testing.assert_allclose(arrow.xy, p[j, :2] + 0.28 * M[j, :2, axis])
        assert arrow.arrow_patch.get_edgecolor() == matplotlib.colors.to_rgba(AXIS_RGB[axis])
    labels = [t.get_text() for t in one.texts if not isinstance(t, Annotation)]
    assert labels == ["shoulder\nQ: 30°", "elbow\nQ: 75°", "wrist\nQ: 15°", "hand\nQ: 15°"]
    # the sweep: three poses, no frames, the shoulder and the elbow never move
    chains = [ln for ln in many.lines if ln.get_linestyle() == "-"]
    assert len(chains) == 3 and not [t for t in many.texts if isinstance(t, Annotation)]
    for line in chains:
        np.testing.assert_allclose(np.column_stack(line.get_data())[:2], p[:2, :2])
    for ax in (one, many):  # every pose inside the same limits
        x0, x1 = ax.get_xlim()
        y0, y1 = ax.get_ylim()
        pts = np.concatenate([p[:, :2]] + [s[0][:, :2] for s in sweep])
        assert (pts[:, 0] > x0).all() and (pts[:, 0] < x1).all()
        assert (pts[:, 1] > y0).all() and (pts[:, 1] < y1).all()


def test_planar_arm_rejects_orientations_of_another_chain():
    _, (ax,) = panels(1)
    with pytest.raises(ValueError, match="orientations"):
        skeleton_plots.planar_arm(ax, np.zeros((3, 3)), np.tile([1.0, 0, 0, 0], (2, 1)))


def test_tree_layout_parents_centred_on_children_and_limbs_from_the_hub():
    skel = _star()
    x, y = skeleton_plots.tree_layout(skel)
    np.testing.assert_array_equal(x, [skel.depth(j) for j in range(skel.n_joints)])
    leaves = list(skel.end_effectors)
    np.testing.assert_array_equal(-y[leaves], np.arange(len(leaves)))  # one row per leaf
    for j in range(skel.n_joints):
        if skel.children(j):
            assert y[j] == pytest.approx(np.mean(y[skel.children(j)]))
    limb, hubs = skeleton_plots.limbs(skel)
    assert hubs == [0]
    np.testing.assert_array_equal(limb, [0, 1, 1, 3, 3, 5, 5, 5, 5])


def test_hierarchy_figure_rest_pose_bones_and_tree_edges():
    skel = _star()
    fig = skeleton_plots.hierarchy_figure(skel, landmarks=("root", "c1", "not a joint"))
    tree, rest_ax = fig.axes
    rest = skel.rest_positions()
    bones = [ln for ln in rest_ax.lines if ln.get_linestyle() == "-"]
    assert len(bones) == skel.n_joints - 1
    for j, line in enumerate(bones, start=1):
        np.testing.assert_allclose(np.column_stack(line.get_data()),
                                   rest[[skel.parents[j], j]][:, :2])
    # the same limb, the same colour; different limbs, different colours
    assert bones[0].get_color() == bones[1].get_color() != bones[2].get_color()
    x, y = skeleton_plots.tree_layout(skel)
    edges = [ln for ln in tree.lines if len(ln.get_xdata()) == 3]
    for j, line in enumerate(edges, start=1):  # an elbow from the parent down to the child
        p = skel.parents[j]
        np.testing.assert_allclose(line.get_xdata(), [x[p], x[p], x[j]])
        np.testing.assert_allclose(line.get_ydata(), [y[p], y[j], y[j]])
    assert [t.get_text() for t in tree.texts] == list(skel.names)
    assert sorted(t.get_text() for t in rest_ax.texts) == ["c1", "root"]


def _fk(skel, R, root_position, **kw):
    return skel.forward_kinematics(R, root_position, **kw)[0]


def test_root_views_mark_the_root_and_arrow_the_mover():
    leg = Skeleton(["hips", "knee", "foot"], [-1, 0, 1], [[0, 0, 0], [0, -4, 0], [0, -4, 0]])
    R0 = np.tile(rot.quat_identity(), (3, 1))
    root0 = np.array([0.0, 8.0, 0.0])
    R1 = R0.copy()
    R1[1] = rot.quat_from_axis_angle([1.0, 0, 0], np.radians(60))
    before = _fk(leg, R0, root0)
    hips_root = _fk(leg, R1, root0)
    pos, ori = leg.pin("foot", R0, root0)
    foot_root = _fk(leg, R1, pos, root="foot", root_orientation=ori)
    fig = skeleton_plots.root_views(leg, before, {"hips": (hips_root, "hips", "foot"),
                                                  "foot": (foot_root, 2, 0)},
                                    highlight=[0, 1, 2], label="bent")
    for ax, (after, root, mover) in zip(fig.axes, [(hips_root, 0, 2), (foot_root, 2, 0)],
                                        strict=True):
        (mark,) = [ln for ln in ax.lines if ln.get_marker() == "v"]
        np.testing.assert_allclose(np.column_stack(mark.get_data())[0], before[root, [2, 1]])
        (arrow,) = [t for t in ax.texts if isinstance(t, Annotation)]
        np.testing.assert_allclose(arrow.xyann, before[mover, [2, 1]])
        np.testing.assert_allclose(arrow.xy, after[mover, [2, 1]])
        shift = np.linalg.norm(after[mover] - before[mover])
        assert f"moves {shift:.2f}" in [t for t in ax.texts if t is not arrow][0].get_text()
        blue = [ln for ln in ax.lines if ln.get_label() == "bent"][0]
        np.testing.assert_allclose(_segments(blue)[:, 1], after[1:, [2, 1]])
        z0, z1 = ax.get_xlim()
        assert z0 < min(before[:, 2].min(), after[:, 2].min()) < max(
            before[:, 2].max(), after[:, 2].max()) < z1
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert labels == ["before", "bent", "the root stays here"]
    with pytest.raises(ValueError, match="before"):
        skeleton_plots.root_views(leg, before[:2], {})


def test_strobe_draws_every_nth_pose_and_the_traced_paths():
    leg = Skeleton(["hips", "knee", "foot"], [-1, 0, 1], [[0, 0, 0], [0, -4, 0], [0, -4, 0]])
    frames = 10
    R = np.tile(rot.quat_identity(), (frames, 3, 1))
    roots = np.column_stack([np.zeros(frames), np.full(frames, 8.0), np.arange(frames) * 2.0])
    P = leg.forward_kinematics(R, roots)[0]
    fig = skeleton_plots.strobe(leg, P, every=4, traces=["foot"], frame_time=0.1, title="walk")
    (ax,) = fig.axes
    poses = [ln for ln in ax.lines if np.isnan(ln.get_xdata()).any()]
    assert len(poses) == 3  # frames 0, 4, 8
    for line, f in zip(poses, (0, 4, 8), strict=True):
        np.testing.assert_allclose(_segments(line)[:, 1], P[f, 1:][:, [2, 1]])
    (trace,) = [ln for ln in ax.lines if ln.get_label() == "foot path"]
    np.testing.assert_allclose(np.column_stack(trace.get_data()), P[:, 2][:, [2, 1]])
    assert ax.get_title() == "walk, every 0.4 s (dark = early, light = late)"
    with pytest.raises(ValueError, match="positions"):
        skeleton_plots.strobe(leg, P[:, :2], every=4)
    with pytest.raises(ValueError, match="every"):
        skeleton_plots.strobe(leg, P, every=0)


def test_gait_figure_heights_swings_contacts_and_knees():
    t = np.linspace(0, 2, 201)
    heights = {"Left": 1 + np.maximum(np.sin(2 * np.pi * t), 0),
               "Right": 1 + np.maximum(-np.sin(2 * np.pi * t), 0)}
    swings = {"Left": np.array([25, 125]), "Right": np.array([75, 175])}
    contact = {side: h < 1.05 for side, h in heights.items()}
    knee = {side: np.radians(60) * (h - 1) for side, h in heights.items()}
    fig = skeleton_plots.gait_figure(t, heights, swings, contact, knee)
    top, bottom = fig.axes
    assert bottom.get_shared_x_axes().joined(top, bottom)
    for side in heights:
        (curve,) = [ln for ln in top.lines if ln.get_label() == f"{side}Foot (ankle) height"]
        np.testing.assert_allclose(curve.get_ydata(), heights[side])
        marks = [ln for ln in top.lines if ln.get_marker() == "v"
                 and ln.get_color() == curve.get_color()]
        np.testing.assert_allclose(marks[0].get_xdata(), t[swings[side]])
        (flex,) = [ln for ln in bottom.lines if ln.get_label() == f"{side}Leg (knee)"]
        np.testing.assert_allclose(flex.get_ydata(), np.degrees(knee[side]))
        dotted = [ln for ln in bottom.lines if ln.get_linestyle() == ":"
                  and ln.get_color() == curve.get_color()]
        np.testing.assert_allclose([ln.get_xdata()[0] for ln in dotted], t[swings[side]])
    bars = [c for c in top.collections if isinstance(c, PolyCollection)]
    assert [b.get_label() for b in bars] == ["Left foot in contact", "Right foot in contact"]
    for bar, side in zip(bars, heights, strict=True):  # one box per run of contact frames
        edges = np.flatnonzero(np.diff(np.r_[0, contact[side].astype(int), 0]))
        runs = [(t[a], t[b - 1]) for a, b in zip(edges[::2], edges[1::2], strict=True)]
        spans = [(p.vertices[:, 0].min(), p.vertices[:, 0].max()) for p in bar.get_paths()]
        np.testing.assert_allclose(spans, runs)


def test_bone_elevation_closed_forms():
    skel = Skeleton(["a", "b"], [-1, 0], [[0, 0, 0], [1, 1, 0]])
    pose = np.array([[0.0, 0, 0], [1, 1, 0]])
    assert skeleton_plots.bone_elevation(skel, pose, "a", "b") == pytest.approx(45)
    assert skeleton_plots.bone_elevation(skel, [[0, 0, 0], [0, -2, 0]], 0, 1) == \
        pytest.approx(-90)
    assert skeleton_plots.bone_elevation(skel, [[0, 0, 0], [0, 0, 3]], "a", "b") == \
        pytest.approx(0)
    with pytest.raises(ValueError, match="length 0"):
        skeleton_plots.bone_elevation(skel, np.zeros((2, 3)), "a", "b")


def test_front_views_label_each_bone_with_its_elevation():
    skel = _star()
    rest = skel.rest_positions()
    tilted = rest.copy()
    tilted[2] = tilted[1] + [np.cos(np.radians(-8)), np.sin(np.radians(-8)), 0]
    fig = skeleton_plots.front_views(skel, {"rest": rest, "tilted": tilted}, [("a", "a_end")],
                                     level="a", title="front")
    assert fig.get_suptitle() == "front"
    for ax, pose, want in zip(fig.axes, (rest, tilted), ("0°", "-8°"), strict=True):
        assert [t.get_text() for t in ax.texts] == [want]
        (level,) = [ln for ln in ax.lines if ln.get_linestyle() == "--"]
        assert level.get_ydata()[0] == pytest.approx(pose[1, 1])
        bones = ax.lines[0]
        np.testing.assert_allclose(_segments(bones)[:, 1], pose[1:, :2])
    with pytest.raises(ValueError, match="poses"):
        skeleton_plots.front_views(skel, {"bad": rest[:3]})
