"""course.viz.rotation_plots: notebook 01's figures draw the rotations, singular values and
interpolation speeds they are given, checked against SciPy and closed forms."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import base64  # noqa: E402
import re  # noqa: E402

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from scipy.spatial.transform import Rotation, Slerp  # noqa: E402

from course.viz import rotation_plots  # noqa: E402
from course.viz.figures import AXIS_RGB, GimbalFigure  # noqa: E402


def _world(line) -> np.ndarray:
    """A 3D line's points back in world (x, y, z) from matplotlib's (z, x, y)."""
    X, Y, Z = line.get_data_3d()
    return np.column_stack([Y, Z, X])


def test_frame_steps_draws_each_matrix_columns_over_the_world_frame():
    Rx = Rotation.from_euler("x", 90, degrees=True).as_matrix()
    Rz = Rotation.from_euler("z", 90, degrees=True).as_matrix()
    rows = {"R_z R_x: x first": [np.eye(3), Rx, Rz @ Rx],
            "R_x R_z: z first": [np.eye(3), Rz, Rx @ Rz]}
    fig = rotation_plots.frame_steps(rows, title="order matters")
    assert len(fig.axes) == 6 and fig.get_suptitle() == "order matters"
    for ax, R in zip(fig.axes, [R for seq in rows.values() for R in seq], strict=True):
        world, frame = ax.lines[:3], ax.lines[3:]
        for a in range(3):
            np.testing.assert_allclose(_world(world[a])[1], np.eye(3)[:, a], atol=1e-12)
            np.testing.assert_allclose(_world(frame[a])[1], R[:, a], atol=1e-12)
            assert frame[a].get_color() == AXIS_RGB[a] and world[a].get_alpha() < 0.5
    titles = [ax.get_title() for ax in fig.axes]
    assert titles == ["start", "after turn 1", "after both: R_z R_x",
                      "start", "after turn 1", "after both: R_x R_z"]
    # the picture's point: the two orders end in different frames
    assert not np.allclose(_world(fig.axes[2].lines[4])[1], _world(fig.axes[5].lines[4])[1])


def test_frame_steps_rejects_ragged_rows_and_wrong_labels():
    with pytest.raises(ValueError, match="rows"):
        rotation_plots.frame_steps({"a": [np.eye(3)], "b": [np.eye(3), np.eye(3)]})
    with pytest.raises(ValueError, match="labels"):
        rotation_plots.frame_steps({"a": [np.eye(3), np.eye(3)]}, labels=["only one"])


def test_gimbal_panels_show_the_gimbal_figure_of_each_pose():
    poses = {(30, 40, 20): "free", (30, 90, 20): "locked"}
    html = rotation_plots.gimbal_panels("XYZ", poses).data
    images = re.findall(r"base64,([A-Za-z0-9+/=]+)'", html)
    assert len(images) == 2
    for (abc, caption), data in zip(poses.items(), images, strict=True):
        assert f"(a, b, c) = {abc}°, {caption}" in html
        assert base64.b64decode(data) == GimbalFigure("XYZ", np.radians(abc)).png()


def _smallest_singular_value(order: str, abc: np.ndarray, h: float = 1e-6) -> float:
    # Independent of the library: SciPy's matrices, central differences.
    cols = []
    for k in range(3):
        d = np.zeros(3)
        d[k] = h
        dR = Rotation.from_euler(order, abc + d).as_matrix() - \
            Rotation.from_euler(order, abc - d).as_matrix()
        cols.append(dR.ravel() / (2 * h))
    return float(np.linalg.svd(np.stack(cols, axis=1), compute_uv=False)[-1])


def test_gimbal_lock_curves_theory_matches_measured_singular_values_and_marks_the_locks():
    b = np.radians(np.linspace(-180, 180, 73))
    measured = {order: [_smallest_singular_value(order, np.array([0.5, bi, -0.3])) for bi in b]
                for order in ("XYZ", "ZYZ")}
    fig = rotation_plots.gimbal_lock_curves(b, measured)
    (ax,) = fig.axes
    thick = [ln for ln in ax.lines if ln.get_linewidth() == 4]
    dotted = [ln for ln in ax.lines if ln.get_linewidth() == 1 and len(ln.get_xdata())]
    assert [ln.get_label() for ln in thick] == ["XYZ (measured)", "ZYZ (measured)"]
    for line, order in zip(thick, measured, strict=True):
        np.testing.assert_allclose(line.get_ydata(), measured[order])
        np.testing.assert_allclose(line.get_xdata(), np.degrees(b))
    for line, order in zip(dotted, measured, strict=True):  # the formula is the measurement
        np.testing.assert_allclose(line.get_ydata(), measured[order], atol=1e-5)
    locks = sorted(t.xy[0] for t in ax.texts if t.get_text() == "lock")
    assert locks == [-90.0, 0.0, 90.0]  # ±180 (ZYZ) are the ends of the range, not marked
    assert "omega" in ax.get_legend().get_texts()[-1].get_text()  # the theory's label


def _wxyz(r: Rotation) -> np.ndarray:
    q = r.as_quat()
    return np.column_stack([q[..., 3], q[..., :3]]) if q.ndim > 1 else np.r_[q[3], q[:3]]


def test_interpolation_speed_slerp_flat_nlerp_humped_lerp_length():
    r0 = Rotation.from_euler("XYZ", [10, -20, 5], degrees=True)
    r1 = Rotation.from_rotvec(np.radians(150) * np.array([0.3, 1, 0.2]) / np.linalg.norm(
        [0.3, 1, 0.2])) * r0
    t = np.linspace(0, 1, 1001)
    slerp = _wxyz(Slerp([0, 1], Rotation.concatenate([r0, r1]))(t))
    q0, q1 = _wxyz(r0), _wxyz(r1)
    q1 = q1 if q0 @ q1 >= 0 else -q1
    lerp = (1 - t)[:, None] * q0 + t[:, None] * q1
    nlerp = lerp / np.linalg.norm(lerp, axis=1, keepdims=True)
    fig = rotation_plots.interpolation_speed(t, {"NLERP": nlerp, "SLERP": slerp}, lerp)
    ahead, speed, length = fig.axes
    (n_ahead, s_ahead), (n_speed, s_speed) = ahead.lines, speed.lines
    np.testing.assert_allclose(s_ahead.get_ydata(), 0, atol=1e-9)
    np.testing.assert_allclose(s_speed.get_ydata(), 150, atol=1e-6)  # degrees per unit t
    omega = np.radians(150) / 2
    # NLERP: mid-way speed-up 1/cos²(Ω/2) over the start, the hump at t = 1/2
    v = n_speed.get_ydata()
    assert v.max() / v[0] == pytest.approx(1 / np.cos(omega / 2) ** 2, rel=2e-3)
    assert n_speed.get_xdata()[np.argmax(v)] == pytest.approx(0.5, abs=0.01)
    np.testing.assert_allclose(n_ahead.get_ydata()[[0, -1]], 0, atol=1e-9)
    assert length.lines[0].get_ydata().min() == pytest.approx(np.cos(omega / 2), rel=1e-4)
    assert [t.get_text() for t in ahead.get_legend().get_texts()] == ["NLERP", "SLERP"]
    assert n_ahead.get_linewidth() > s_ahead.get_linewidth()  # the first path drawn thickest
    assert len(rotation_plots.interpolation_speed(t, {"SLERP": slerp}).axes) == 2
