r"""Still figures of notebooks 07 (Jacobian IK) and 08 (the IK race).

Each function takes what the notebook computed (FK positions, Jacobians, solves, iteration
counts) and only draws it; the lecture's maths stays in the cell that calls it. Chains are drawn
with :mod:`course.viz.chain_plots`; every figure is a
:class:`~course.viz.chain_plots.ChainFigure` (outside pyplot, shown once as a PNG when it
ends a notebook cell). A method's colour is its position in the mapping given, as in
:func:`course.viz.figures.convergence_plot`, so the lines of one figure match.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from numpy.typing import ArrayLike

from .._typing import Array
from .chain_plots import GREEN, ChainFigure, draw_chain, draw_target, panels
from .figures import BONE, JOINT, METHOD_COLORS, TARGET, convergence_plot, mpl3

START = "#c3cad3"    # a start or captured pose, underneath
MUTED = "#5b6b7c"
DIM = "#8f9aa6"
PURPLE = "#8e6bd8"


def _color(k: int) -> str:
    return METHOD_COLORS[k % len(METHOD_COLORS)]


def _fit(ax: Any, points: ArrayLike, pad: float, *, square: bool = False) -> None:
    """Equal-aspect limits that contain ``points (N, 2)`` with a margin ``pad`` (``square``:
    both axes as wide as the wider one, around the points' middle)."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    lo, hi = p.min(axis=0) - pad, p.max(axis=0) + pad
    if square:
        middle, half = (lo + hi) / 2, (hi - lo).max() / 2
        lo, hi = middle - half, middle + half
    ax.set(aspect="equal", xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]))


def jacobian_columns(positions: ArrayLike, J: ArrayLike, names: Sequence[str], *,
                     scale: float = 0.45) -> ChainFigure:
    r"""A planar chain (every hinge axis along z) and the columns of its Jacobian drawn at the
    end effector; the title says what holds in that case: each column is perpendicular to its
    lever arm and as long as it.

    Parameters
    ----------
    positions : (n + 1, 3) joint positions :math:`r_0 \dots r_{n-1}`, then the end effector
        :math:`e`; the xy plane is drawn.
    J : (3, n) the Jacobian; column :math:`J_i` is drawn as an arrow from :math:`e`, ``scale``
        times its length, with the dotted lever arm :math:`e - r_i` in the same colour.
    names : n joint names, for the labels :math:`J_i` (name).

    Returns
    -------
    The figure; ``fig.axes[0]`` holds the chain, the lever arms and the arrows.
    """
    p = np.asarray(positions, dtype=np.float64)
    jac = np.asarray(J, dtype=np.float64)
    if p.ndim != 2 or jac.shape != (3, len(p) - 1) or len(names) < jac.shape[1]:
        raise ValueError(f"need positions (n + 1, 3), J (3, n) and n names; got positions "
                         f"{p.shape}, J {jac.shape}, {len(names)} names")
    fig, (ax,) = panels(1, figsize=(6.4, 4.6))
    draw_chain(ax, p, lw=6)
    e = p[-1, :2]
    tips = e + scale * jac[:2].T
    for i, tip in enumerate(tips):
        color = _color(i + 1)
        ax.plot(*np.stack([p[i, :2], e]).T, ls=":", color=color, lw=1.5)
        ax.annotate("", tip, e, arrowprops={"arrowstyle": "-|>", "color": color, "lw": 2.5})
        out = (tip - e) / max(float(np.linalg.norm(tip - e)), 1e-12)  # label beyond the tip
        ax.text(*(tip + 0.06 * out), f"$J_{i}$ ({names[i]})", color=color, fontsize=10,
                va="center", ha="right" if out[0] < 0 else "left")
    _fit(ax, np.vstack([p[:, :2], tips]), 0.3, square=True)
    ax.set(xlabel="x", ylabel="y",
           title="Columns of J: the hand's velocity when one joint turns\n"
                 f"(perpendicular to the dotted lever arm e − r_i, as long as it; drawn at "
                 f"{scale:g}×)")
    return fig


def solve_paths(start: ArrayLike, solves: Mapping[str, Any], target: ArrayLike, *,
                tol: float) -> ChainFigure:
    """Several solves of one target: their residuals per iteration (left, log scale) and the
    end effector's path through the iterations with each final pose (right, xy plane).

    Parameters
    ----------
    start : (J, 3) the starting pose's joint positions, drawn grey.
    solves : method -> the result of ``ik.solve(..., record=True)`` (its ``residuals``,
        ``frames``, ``positions`` and ``iterations``).
    target : (3,) the target, a star.
    tol : the tolerance, a dashed line on the left.
    """
    fig, (ax0, ax1) = panels(2, figsize=(11.5, 4.4), width_ratios=(1.25, 1))
    convergence_plot({m: r.residuals for m, r in solves.items()}, tol=tol, ax=ax0,
                     title="Residual per iteration (log scale)")
    s = np.asarray(start, dtype=np.float64)
    ax1.plot(s[:, 0], s[:, 1], "-o", color=START, lw=4, ms=5, label="start")
    drawn = [s[:, :2]]
    for k, (method, r) in enumerate(solves.items()):
        path = np.array([f["positions"][-1] for f in r.frames])
        ax1.plot(path[:, 0], path[:, 1], ".-", color=_color(k), lw=1, ms=3,
                 label=f"{method}: {r.iterations} steps")
        ax1.plot(r.positions[:, 0], r.positions[:, 1], "-", color=_color(k), lw=2.5, alpha=0.8)
        drawn += [path[:, :2], r.positions[:, :2]]
    draw_target(ax1, target)
    _fit(ax1, np.vstack(drawn), 0.6)
    x0, x1 = ax1.get_xlim()
    ax1.set_xlim(x0, x1 + 0.5 * (x1 - x0))  # room on the right for the legend
    ax1.set(xlabel="x", ylabel="y", title="End-effector path and final poses")
    ax1.legend(frameon=False, fontsize=8, loc="upper right")
    return fig


def singular_sweep(poses: Sequence[ArrayLike], delta_e: ArrayLike, sigma_min: ArrayLike,
                   step_pinv: ArrayLike, step_dls: ArrayLike, damping: float, *,
                   every: int = 6) -> ChainFigure:
    r"""A two-link arm straightening, and the length of the pseudo-inverse and DLS steps for
    the same :math:`\Delta e` against its smallest singular value.

    Parameters
    ----------
    poses : K poses (3, 3) of the arm (base, elbow, hand), from bent to straight; every
        ``every``-th one and the last are drawn (viridis, in order), with :math:`\Delta e`
        (×6) at the last hand.
    delta_e : (2,) or (3,) the error asked for.
    sigma_min, step_pinv, step_dls : (K,) :math:`\sigma_{min}` and
        :math:`\lVert\Delta\theta\rVert` of each step, drawn log-log, :math:`\sigma` decreasing
        to the right; the bound :math:`\lVert\Delta e\rVert / 2\lambda` dashed and
        :math:`\sigma = \lambda` dotted.
    damping : :math:`\lambda`.
    """
    from matplotlib import colormaps

    fig, (ax0, ax1) = panels(2, figsize=(11.5, 4.3), width_ratios=(1, 1.35))
    shown = [*poses[::every], poses[-1]]
    for k, pose in enumerate(shown):
        p = np.asarray(pose, dtype=np.float64)
        ax0.plot(p[:, 0], p[:, 1], "-o", color=colormaps["viridis"](k / len(shown)), lw=3,
                 ms=6, alpha=0.85)
    de = np.asarray(delta_e, dtype=np.float64)[:2]
    hand = np.asarray(poses[-1], dtype=np.float64)[-1, :2]
    ax0.annotate("", hand + 6 * de, hand,
                 arrowprops={"arrowstyle": "-|>", "color": TARGET, "lw": 2.5})
    ax0.text(*(hand + 6 * de + [0.05, 0.05]), "Δe (×6)", color=TARGET)
    _fit(ax0, np.vstack([np.asarray(p, dtype=np.float64)[:, :2] for p in shown]
                        + [hand + 6 * de]), 0.2)
    ax0.set(xlabel="x", ylabel="y", title="Elbow bent → straight")
    bound = np.linalg.norm(delta_e) / (2 * damping)
    ax1.loglog(sigma_min, step_pinv, "o-", ms=3, color=_color(1),
               label="pseudo-inverse  $|J^+ Δe|$")
    ax1.loglog(sigma_min, step_dls, "o-", ms=3, color=_color(2), label=f"DLS  λ = {damping:g}")
    ax1.axhline(bound, color=_color(2), ls="--", lw=1, label="DLS bound |Δe| / 2λ")
    ax1.axvline(damping, color=DIM, ls=":", lw=1)
    ax1.text(damping * 1.1, 2e-2, "σ = λ", color="#4a5561")
    ax1.invert_xaxis()
    ax1.set(xlabel="smallest singular value σ_min (→ straight arm)",
            ylabel="step size |Δθ| (rad)", title="Near a singular pose: explosion vs. damping")
    ax1.legend(frameon=False, fontsize=9, loc="upper left")
    return fig


def weighted_solves(start: ArrayLike, solves: Mapping[str, tuple[ArrayLike, ArrayLike]],
                    target: ArrayLike) -> ChainFigure:
    """One panel per solve of the same target: the start (grey), the solution, and how far
    each joint turned, in degrees, next to it.

    Parameters
    ----------
    start : (J, 3) the starting joint positions.
    solves : panel title -> (the solution's positions (J, 3), each joint's turn (J - 1,) in
        degrees).
    target : (3,) the target, a star.
    """
    s = np.asarray(start, dtype=np.float64)
    fig, axes = panels(len(solves), figsize=(5.25 * len(solves), 4.2), sharey=True)
    drawn = [s[:, :2], np.asarray(target, dtype=np.float64)[None, :2]]
    for ax, (title, (positions, turned)) in zip(axes, solves.items(), strict=True):
        p = np.asarray(positions, dtype=np.float64)
        ax.plot(s[:, 0], s[:, 1], "-o", color=START, lw=4, ms=5, label="start")
        ax.plot(p[:, 0], p[:, 1], "-o", color=BONE, lw=4, ms=7, mfc=JOINT, mec="#7a5600",
                label="DLS solution")
        draw_target(ax, target)
        for j, angle in enumerate(np.asarray(turned, dtype=np.float64)):
            ax.text(*(p[j, :2] + [0.12, -0.05]), f"{angle:.0f}°", fontsize=8, color="#4a5561")
        drawn.append(p[:, :2])
        ax.set(title=title, xlabel="x")
    for ax in axes:
        _fit(ax, np.vstack(drawn), 0.5)
    axes[0].set_ylabel("y")
    axes[0].legend(frameon=False, fontsize=8, loc="lower left")
    fig.suptitle("Labels: how far each joint turned. The heavy joint barely moves.", fontsize=10)
    return fig


def least_squares_plane(ax: Any, J: ArrayLike, de: ArrayLike) -> Array:
    r"""On a 3D axes: the plane of the two columns of a tall ``J (3, 2)``, the columns,
    :math:`\Delta e (3,)` and its least-squares shadow :math:`J\Delta\theta` on the plane, and
    the miss between them (dotted, perpendicular to the plane). Drawn in the plane's own frame
    (the shadow along the first axis, :math:`\Delta e` above). Returns the shadow ``(3,)``
    in world coordinates."""
    jac = np.asarray(J, dtype=np.float64)
    d = np.asarray(de, dtype=np.float64)
    if jac.shape != (3, 2) or d.shape != (3,):
        raise ValueError(f"need J (3, 2) and de (3,), got {jac.shape} and {d.shape}")
    hit = jac @ np.linalg.lstsq(jac, d, rcond=None)[0]
    normal = np.cross(jac[:, 0], jac[:, 1])
    up = normal / np.linalg.norm(normal) * (np.sign(d @ normal) or 1.0)
    along = hit / np.linalg.norm(hit)
    basis = np.stack([along, np.cross(up, along), up])   # rows: the plane's frame
    r = 1.1 * max(np.abs(basis @ v).max() for v in (*jac.T, d))
    s = np.linspace(-r, r, 2)
    ax.plot_surface(*np.meshgrid(s, s), np.zeros((2, 2)), color=BONE, alpha=0.15, lw=0)
    for v, c, label in [(jac[:, 0], MUTED, "the columns of J"), (jac[:, 1], MUTED, None),
                        (d, TARGET, "Δe"), (hit, GREEN, "J Δθ, least squares")]:
        ax.quiver(0, 0, 0, *(basis @ v), color=c, lw=2.2, arrow_length_ratio=0.1, label=label)
    ax.plot(*np.stack([basis @ hit, basis @ d]).T, ":", color=TARGET, lw=1.8,
            label="the miss, perpendicular")
    ax.set(xlim=(-r, r), ylim=(-r, r), zlim=(-0.2 * r, r), xticklabels=[], yticklabels=[],
           zticklabels=[], title="tall 3×2: J Δθ cannot leave the plane")
    ax.set_box_aspect((1, 1, 0.6))
    ax.view_init(elev=8, azim=-75)
    ax.legend(frameon=False, fontsize=7, loc="upper left")
    return hit


def null_space_lengths(ax: Any, step: ArrayLike, null: ArrayLike, *,
                       extent: float = 2.0) -> Any:
    r"""Filled contours of :math:`\lVert J^+\Delta e + N z\rVert` over the null-space
    coordinates :math:`z \in [-extent, extent]^2`, with :math:`z = 0` (the pseudo-inverse
    step) starred. ``step (n,)``, ``null (n, 2)``. Returns the contour set."""
    n = np.asarray(null, dtype=np.float64)
    st = np.asarray(step, dtype=np.float64)
    if n.ndim != 2 or n.shape != (st.shape[0], 2):
        raise ValueError(f"null must have shape ({st.shape[0]}, 2), got {n.shape}")
    g = np.linspace(-extent, extent, 201)
    Z1, Z2 = np.meshgrid(g, g)
    lengths = np.linalg.norm(st + np.stack([Z1, Z2], -1) @ n.T, axis=-1)
    filled = ax.contourf(Z1, Z2, lengths, levels=12, cmap="Greens_r")
    ax.figure.colorbar(filled, ax=ax, label="|Δθ| (rad)")
    ax.plot(0, 0, "*", ms=15, color=TARGET, mec="white")
    ax.annotate("J⁺Δe: the shortest", (0, 0), (0.2, 0.35), fontsize=9)
    ax.set(aspect="equal", xlabel="z₁", ylabel="z₂",
           title="wide 3×5: every Δθ = J⁺Δe + N z is exact")
    return filled


def wide_and_tall(J_tall: ArrayLike, de: ArrayLike, step_wide: ArrayLike, null: ArrayLike,
                  residuals: Mapping[str, ArrayLike], closest: float, *,
                  tol: float) -> ChainFigure:
    r"""Three panels: :func:`least_squares_plane` of ``J_tall (3, 2)`` and ``de (3,)``;
    :func:`null_space_lengths` of the wide step ``step_wide (n,)`` and ``null (n, 2)``; and
    the residuals per iteration of whole solves (name -> (K,)), with the ``closest`` distance
    the tall arm can get dotted."""
    fig, axes = panels(3, figsize=(13, 4.3))
    ax0 = fig.add_subplot(axes[0].get_subplotspec(), projection="3d")
    axes[0].remove()
    least_squares_plane(ax0, J_tall, de)
    null_space_lengths(axes[1], step_wide, null)
    convergence_plot(residuals, tol=tol, ax=axes[2],
                     title="pseudo-inverse solves: error per iteration")
    axes[2].axhline(closest, color=PURPLE, ls=":", lw=1.5, label="closest the tall arm can get")
    axes[2].legend(frameon=False, fontsize=8)
    return fig


def root_choices(parents: ArrayLike, captured: ArrayLike, solved: Mapping[str, ArrayLike],
                 fixed: Mapping[str, ArrayLike], target: ArrayLike, *,
                 radius: float = 1.0) -> ChainFigure:
    """Full-body IK answers in 3D (pyvista, side camera), one panel per choice of fixed joint:
    the captured pose grey and translucent, the answer blue, the target a red ball and the
    joint that stays put a green ball (of ``radius``, in file units).

    Parameters
    ----------
    parents : (J,) parent indices.
    captured : (J, 3) the pose before IK.
    solved : label -> (J, 3) the IK answer; each panel is titled with how many joints moved.
    fixed : label -> (3,) the fixed joint's position.
    target : (3,) the effector's target.
    """
    import pyvista as pv

    from .scene import SkeletonScene

    before = np.asarray(captured, dtype=np.float64)
    fig, axes = panels(len(solved), figsize=(4.0 * len(solved), 5.2))
    for ax, (label, positions) in zip(axes, solved.items(), strict=True):
        after = np.asarray(positions, dtype=np.float64)
        scene = SkeletonScene(window_size=(420, 520), camera="side")
        scene.add_skeleton(parents, before, name="captured", color=(START, "#9aa5b1"),
                           opacity=0.5, frame_points=np.stack([before, after]))
        scene.add_skeleton(parents, after, name="IK", color=(BONE, JOINT))
        scene.set_targets(np.asarray(target, dtype=np.float64)[None], render=False)
        scene.plotter.add_mesh(pv.Sphere(radius=radius, center=np.asarray(fixed[label])),
                               color=GREEN)
        ax.imshow(scene.screenshot())
        scene.close()
        ax.set_axis_off()
        moved = int((np.linalg.norm(after - before, axis=1) > 1e-6).sum())
        ax.set_title(f"rooted at the {label}: {moved} joints moved", fontsize=10)
    return fig


def race_figure(iterations: Mapping[str, ArrayLike], residuals: Mapping[str, ArrayLike], *,
                tol: float, one_tol: float, title: str) -> ChainFigure:
    """The race: each method's iteration counts over the targets (left: box plot, log scale,
    with the mean ◆ and the 90th percentile —), and one target's residual per iteration
    (right, solved to ``one_tol``).

    Parameters
    ----------
    iterations : method -> (N,) iterations to ``tol`` for each target.
    residuals : method -> (K,) one solve's residuals.
    title : the left panel's title.
    """
    fig, (ax0, ax1) = panels(2, figsize=(12, 4.3))
    methods = list(iterations)
    counts = [np.asarray(iterations[m], dtype=np.float64) for m in methods]
    parts = ax0.boxplot(counts, tick_labels=methods, patch_artist=True, widths=0.55,
                        medianprops={"color": "k"})
    for k, patch in enumerate(parts["boxes"]):
        patch.set(facecolor=_color(k), alpha=0.75)
    at = range(1, len(methods) + 1)
    ax0.plot(at, [c.mean() for c in counts], "D", color="k", ms=6, label="mean")
    ax0.plot(at, [np.percentile(c, 90) for c in counts], "_", color=MUTED, ms=22, mew=2.5,
             label="90th percentile")
    ax0.set_yscale("log")
    ax0.set(ylabel=f"iterations to tol = {tol:g}", title=title)
    ax0.tick_params(axis="x", labelsize=8)
    ax0.legend(frameon=False)
    convergence_plot(residuals, tol=one_tol, ax=ax1, title=f"One target, to tol = {one_tol:g}")
    return fig


def word_figure(word: ArrayLike, pen_up: Sequence[int], positions: Mapping[str, ArrayLike],
                iterations: Mapping[str, ArrayLike], *, plane_z: float = 2.0,
                every: int = 14) -> ChainFigure:
    """A chain writing a word in the plane ``z = plane_z``, one 3D panel per method: the word's
    strokes (grey; dotted where the pen is lifted), every ``every``-th pose (viridis, in time)
    and the traced path in the method's colour.

    Parameters
    ----------
    word : (S, 2) the stroke corners (x, y).
    pen_up : indices of the segments travelled with the pen lifted.
    positions : method -> (F, J, 3) the joint positions of every frame.
    iterations : method -> (F,) iterations per frame (their mean is in the panel's title).
    """
    from matplotlib import colormaps

    w = np.asarray(word, dtype=np.float64)
    strokes = np.c_[w, np.full(len(w), plane_z)]
    every_point = np.vstack([strokes, *(np.reshape(f, (-1, 3)) for f in positions.values())])
    lo, hi = every_point.min(axis=0) - 0.5, every_point.max(axis=0) + 0.5
    # 3D panels edge to edge, without constrained layout (it shrinks them)
    fig = ChainFigure(figsize=(2.6 * len(positions), 4.3), dpi=110)
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, len(positions), squeeze=False, subplot_kw={"projection": "3d"})[0]
    fig.subplots_adjust(left=0, right=1, bottom=0, top=0.86, wspace=0)
    for k, (ax, (method, frames)) in enumerate(zip(axes, positions.items(), strict=True)):
        P = np.asarray(frames, dtype=np.float64)
        for s in range(len(w) - 1):
            ax.plot(*mpl3(strokes[s:s + 2]), color=START, lw=1 if s in pen_up else 5,
                    ls=":" if s in pen_up else "-")
        for f in range(0, len(P), every):
            ax.plot(*mpl3(P[f]), "-o", color=colormaps["viridis"](f / len(P)), lw=1.5, ms=2.5,
                    alpha=0.7)
        ax.plot(*mpl3(P[:, -1]), color=_color(k), lw=2)
        ax.set(xlim=(lo[2], hi[2]), ylim=(lo[0], hi[0]), zlim=(lo[1], hi[1]), xticklabels=[],
               yticklabels=[], zticklabels=[])
        ax.set_box_aspect(mpl3(hi - lo), zoom=1.3)
        ax.view_init(elev=10, azim=-68)
        mean = np.asarray(iterations[method], dtype=np.float64).mean()
        ax.set_title(f"{method}\n{mean:.1f} iterations / frame", fontsize=9)
    fig.suptitle(f"The end effector writes the word (grey strokes, dotted: pen lifted); "
                 f"coloured: the traced path; chains: every {every}th frame", fontsize=10)
    return fig


def smoothness_figure(jerk: Mapping[str, float],
                      largest_turn: Mapping[str, ArrayLike]) -> ChainFigure:
    """Left: each method's jerkiness (mean squared second difference of the joint turns,
    rad², a bar); right: the largest joint turn of every frame (degrees) for the methods in
    ``largest_turn`` (method -> (F - 1,)), coloured as in the bars."""
    fig, (ax0, ax1) = panels(2, figsize=(12, 4.0), width_ratios=(1, 1.6))
    methods = list(jerk)
    bars = ax0.bar(range(len(methods)), [jerk[m] for m in methods],
                   color=[_color(k) for k in range(len(methods))])
    ax0.bar_label(bars, fmt="%.1e", fontsize=8)
    ax0.set_xticks(range(len(methods)), methods, rotation=20, fontsize=8)
    ax0.set(ylabel="mean squared 2nd difference (rad²)",
            title="Jerkiness of the joints (lower: smoother)")
    for m, turn in largest_turn.items():
        ax1.plot(np.asarray(turn, dtype=np.float64), color=_color(methods.index(m)), lw=1.6,
                 label=m)
    ax1.set(xlabel="frame", ylabel="largest joint turn in the frame (°)",
            title="Frame to frame: the Jacobian step spreads the motion evenly")
    ax1.legend(frameon=False, fontsize=8)
    return fig


__all__ = [
    "jacobian_columns",
    "least_squares_plane",
    "null_space_lengths",
    "race_figure",
    "root_choices",
    "singular_sweep",
    "smoothness_figure",
    "solve_paths",
    "weighted_solves",
    "wide_and_tall",
    "word_figure",
]
