"""course.viz.character_plots: what each figure draws (the artists' data), not only that it runs."""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.colors import to_hex

from course.foot_sliding import foot_sliding
from course.motion import Motion
from course.skeleton import Skeleton
from course.viz import character_plots as cp
from course.viz.figures import bone_xy

ARM = Skeleton(["root", "a", "b", "c"], [-1, 0, 1, 1],
               [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 2.0]])


def xy(line):
    return np.column_stack(line.get_data()).astype(float)


def legend_texts(ax):
    return [t.get_text() for t in ax.get_legend().get_texts()]


def walker(frames=40, dt=0.1):
    """A hip over two feet, dragged along x at 1 unit/s after frame 9 (see test_foot_sliding)."""
    skel = Skeleton(["Hips", "L", "R"], [-1, 0, 0],
                    [[0.0, 0.0, 0.0], [1.0, -10.0, 0.0], [-1.0, -10.0, 0.0]])
    x = dt * np.maximum(0, np.arange(frames) - 9)
    root = np.column_stack([x, np.full(frames, 10.0), np.zeros(frames)])
    return Motion(skel, np.tile([1.0, 0, 0, 0], (frames, 3, 1)), root, dt)


# --------------------------------------------------------------------------- 10
def test_pose_panels_draw_each_layer_as_its_bones_in_the_plane():
    rest = ARM.rest_positions()
    moved = rest + [0.5, 0.0, -1.0]
    fig = cp.pose_panels({"one": [(ARM, rest), (ARM, moved)], "two": [(ARM, moved), (ARM, rest)]},
                         labels=["wanted", "made"], plane="zy", xlim=(-5.0, 5.0))
    assert [ax.get_title() for ax in fig.axes] == ["one", "two"]
    ghost, made = fig.axes[0].lines
    np.testing.assert_array_equal(xy(ghost), bone_xy(ARM.parents, rest[:, [2, 1]]))
    np.testing.assert_array_equal(xy(made), bone_xy(ARM.parents, moved[:, [2, 1]]))
    assert to_hex(ghost.get_color()) == cp.GHOST and ghost.get_linewidth() == 6.0
    assert to_hex(made.get_color()) == cp.BONE and made.get_linewidth() == 2.5
    assert legend_texts(fig.axes[0]) == ["wanted", "made"] and fig.axes[1].get_legend() is None
    assert fig.axes[0].get_xlabel() == "z" and fig.axes[0].get_ylabel() == "y (up)"
    assert all(ax.get_xlim() == (-5.0, 5.0) for ax in fig.axes)
    assert fig._repr_png_()[:4] == b"\x89PNG"


def test_pose_panels_one_layer_is_blue_and_fits_the_pose():
    fig = cp.pose_panels({"rest": [(ARM, ARM.rest_positions())]})
    (line,) = fig.axes[0].lines
    assert to_hex(line.get_color()) == cp.BONE and line.get_linewidth() == 3.0
    (x0, x1), (y0, y1) = fig.axes[0].get_xlim(), fig.axes[0].get_ylim()
    assert x0 <= 0.0 and x1 >= 1.0 and y0 <= 0.0 and y1 >= 1.0  # the whole pose is in view


def test_pose_panels_refuse_bad_input():
    rest = ARM.rest_positions()
    with pytest.raises(ValueError, match="same number"):
        cp.pose_panels({"a": [(ARM, rest)], "b": [(ARM, rest), (ARM, rest)]})
    with pytest.raises(ValueError, match="labels: expected one per layer"):
        cp.pose_panels({"a": [(ARM, rest)]}, labels=["x", "y"])
    with pytest.raises(ValueError, match="plane"):
        cp.pose_panels({"a": [(ARM, rest)]}, plane="yz")
    with pytest.raises(ValueError, match=r"panels_\['a'\]\[0\]: expected positions of shape"):
        cp.pose_panels({"a": [(ARM, rest[:3])]})


def test_sliding_speeds_draw_the_speeds_during_contacts():
    clip = walker()
    runs = {"own": foot_sliding(clip, ["L", "R"], cm_per_unit=1.0),
            "all": foot_sliding(clip, ["L", "R"], contacts=np.ones((40, 2), bool),
                                cm_per_unit=1.0)}
    fig = cp.sliding_speeds(runs, foot=1)
    own, every = fig.axes[0].lines
    t = np.arange(1, 40) * 0.1
    np.testing.assert_allclose(xy(own)[:, 0], t)
    np.testing.assert_array_equal(xy(own)[:, 1], runs["own"].speed_cm_per_s[:, 1])
    np.testing.assert_allclose(xy(every)[9:, 1], 1.0)  # dragged at 1 unit/s = 1 cm/s here
    assert legend_texts(fig.axes[0]) == ["own", "all"]
    assert fig.axes[0].get_title().startswith("R:")


# --------------------------------------------------------------------------- 09
def test_planted_foot_task_draws_the_paths_from_above():
    s = np.linspace(0, 2 * np.pi, 50)
    target = np.column_stack([np.cos(s), np.zeros(50), np.sin(s)])
    hips = 0.1 * target + [3.0, 10.0, 0.0]
    foot = np.array([3.0, 0.0, 0.5])
    fig = cp.planted_foot_task(hips, target, target, foot,
                               {"cold": np.full(50, 5), "warm": np.ones(50)}, title="above")
    top, its = fig.axes
    h, e, t, f = top.lines
    np.testing.assert_array_equal(xy(h), hips[:, [0, 2]])
    np.testing.assert_array_equal(xy(t), target[:, [0, 2]])
    np.testing.assert_array_equal(xy(f), [foot[[0, 2]]])
    assert top.get_title() == "above" and top.get_aspect() == 1.0
    cold, warm = its.lines
    np.testing.assert_array_equal(xy(warm)[:, 1], 1.0)
    assert to_hex(warm.get_color()) == cp.BONE and to_hex(cold.get_color()) == cp.GHOST
    with pytest.raises(ValueError, match="hips, hand, target"):
        cp.planted_foot_task(hips, target[:10], target, foot, {})


# --------------------------------------------------------------------------- 11
def test_knots_figure_draws_velocities_keys_and_paths():
    t = np.linspace(0, 3, 31)
    v = {"time": np.sin(t), "uniform": np.cos(t)}
    pts = np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 0.0]])
    paths = {"centripetal": np.column_stack([t, t**2])}
    fig = cp.knots_figure(t, v, [0.0, 1.5, 3.0], paths, pts)
    left, right = fig.axes
    time_line, uniform_line = left.lines[:2]
    np.testing.assert_array_equal(xy(time_line), np.column_stack([t, np.sin(t)]))
    assert to_hex(time_line.get_color()) == cp.KNOT_COLORS["time"]
    assert len(left.lines) == 2 + 3  # two curves and a dotted line per key
    assert legend_texts(left) == ['knots="time"', 'knots="uniform"']
    np.testing.assert_array_equal(xy(right.lines[0]), paths["centripetal"])
    np.testing.assert_array_equal(xy(right.lines[1]), pts)


def test_angular_speeds_are_drawn_at_the_midpoints():
    times = np.array([0.0, 1.0, 3.0, 4.0])
    fig = cp.angular_speeds(times, {"capture": [1.0, 2.0, 3.0], "slerp": [2.0, 2.0, 2.0]},
                            [0.0, 4.0], title="hip", xlim=(0.0, 2.0))
    (ax,) = fig.axes
    capture, slerp = ax.lines[:2]
    np.testing.assert_array_equal(xy(capture), [[0.5, 1.0], [2.0, 2.0], [3.5, 3.0]])
    assert capture.get_linewidth() == 3 and slerp.get_linewidth() == 1.6
    assert ax.get_xlim() == (0.0, 2.0) and ax.get_title() == "hip" and len(ax.lines) == 4


def test_keyframe_errors_log_log_and_keys_on_the_time_axis():
    ks = [2, 5, 10]
    errors = {"linear + SLERP": [0.1, 0.5, 2.0], "cubic + SQUAD": [0.05, 0.3, 1.0]}
    times = np.arange(11) * 0.1
    over = {"linear + SLERP": np.abs(np.sin(times))}
    fig = cp.keyframe_errors(ks, errors, times, over, times[::5], 5)
    left, right = fig.axes
    np.testing.assert_array_equal(xy(left.lines[1]), np.column_stack([ks, errors["cubic + SQUAD"]]))
    assert left.get_xscale() == left.get_yscale() == "log"
    keys = right.lines[-1]
    np.testing.assert_array_equal(xy(keys), np.column_stack([times[::5], np.zeros(3)]))
    assert "k = 5" in right.get_title() and legend_texts(right)[-1] == "keys"


def test_blend_figure_draws_the_toe_and_the_summed_sliding():
    clip = walker()
    contacts = np.ones((40, 2), bool)
    contacts[30:, 1] = False
    contacts[35:] = False
    sliding = foot_sliding(clip, ["L", "R"], contacts=contacts, cm_per_unit=100.0)
    fig = cp.blend_figure({"run": (clip, sliding)}, "L", fade=(10, 20), window=(5, 39),
                          cm_per_unit=100.0)
    left, right = fig.axes
    toe = clip.forward_kinematics()[0][:, 1]  # metres at 100 cm per unit
    np.testing.assert_allclose(xy(left.lines[0]), toe[:, [2, 0]])
    np.testing.assert_allclose(xy(left.lines[1]), toe[10:20][:, [2, 0]])
    assert left.lines[1].get_linewidth() == 4
    summed = xy(right.lines[0])
    np.testing.assert_array_equal(summed[:, 0], np.arange(5, 39))
    steps = np.arange(5, 39)
    expected = np.where(steps < 9, 0.0, np.where(steps < 29, 200.0, 100.0))  # cm/s
    expected[steps >= 34] = np.nan  # no foot on the ground from step 34 -> 35 on
    np.testing.assert_allclose(summed[:, 1], expected)
    assert legend_texts(right) == ["run", "cross-fade"]
