"""Flat 2-D drawings of chains for the IK notebooks: bones and joints from FK positions, the
target and the base, angle arcs, the reach annulus, a traced path, and panels of iterations.

Every drawer takes joint positions ``(J, 2)`` or ``(J, 3)``; 3-D points are projected onto a
``plane`` (``"xy"``: front view, default; ``"zy"``: side; ``"xz"``: top), y up. A chain without
``parents`` is the polyline through its joints in order; with ``parents`` it is a tree. The
figure functions return a :class:`ChainFigure`: a matplotlib figure outside pyplot (no double
display, no leak in loops) that shows itself as a PNG when it ends a notebook cell.
"""

from __future__ import annotations

import io
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Arc, Circle, Rectangle, Wedge
from numpy.typing import ArrayLike

from .._typing import Array
from .figures import BONE, GHOST, JOINT, METHOD_COLORS, PLANES, TARGET, TRAIL, bone_xy, mpl3

GREEN = "#2bb673"
ORANGE = "#f08c3a"
INK = "#2b3440"
MUTED = "#5b6b7c"
ACCENT = "#8e3bd1"
RING = "#dcebfa"
JOINT_EDGE = "#7a5600"
# One colour per IK method, the same in every notebook (05's tracking, 06's race, 08's tables).
# A matplotlib colour: a name or hex string, or an RGB(A) tuple (a colormap's output).
Color = str | tuple[float, ...]
METHOD_COLOR = {"ccd": TARGET, "fabrik": BONE, "dls": GREEN, "two_link": ACCENT}


class ChainFigure(Figure):
    """A figure drawn by Agg outside pyplot that a notebook cell displays as its PNG."""

    def _repr_png_(self) -> bytes:
        buffer = io.BytesIO()
        self.savefig(buffer, format="png")
        return buffer.getvalue()


def style_axes(ax: Any) -> None:
    ax.grid(True, color="#e3e7ec", lw=0.8)
    ax.set_axisbelow(True)
    for side in ("top", "right"):
        ax.spines[side].set_visible(False)


def panels(
    ncols: int = 1,
    *,
    nrows: int = 1,
    figsize: tuple[float, float] | None = None,
    xlim: tuple[float, float] | None = None,
    ylim: tuple[float, float] | None = None,
    sharey: bool = False,
    width_ratios: Sequence[float] | None = None,
    projection: str | None = None,
) -> tuple[ChainFigure, list[Any]]:
    """A figure of ``nrows x ncols`` axes, styled like the notebooks (light grid, no top and
    right spines). With ``xlim`` and ``ylim`` every axes gets those limits and an equal aspect
    (a chain's angles look like angles). Returns the figure and its axes, row by row."""
    if ncols < 1 or nrows < 1:
        raise ValueError(f"ncols and nrows must be at least 1, got {ncols} and {nrows}")
    size = figsize if figsize is not None else (4.4 * ncols, 4.0 * nrows)
    fig = ChainFigure(figsize=size, dpi=110, layout="constrained")
    FigureCanvasAgg(fig)
    axes: list[Any] = []
    grid = fig.add_gridspec(nrows, ncols, width_ratios=width_ratios)
    for k in range(nrows * ncols):
        share = axes[0] if sharey and axes else None
        ax = fig.add_subplot(grid[k // ncols, k % ncols], projection=projection, sharey=share)
        if projection is None:
            style_axes(ax)
            if xlim is not None and ylim is not None:
                ax.set(aspect="equal", xlim=xlim, ylim=ylim)
        axes.append(ax)
    return fig, axes


def _xy(points: ArrayLike, plane: str = "xy", name: str = "points") -> Array:
    """Points ``(..., 2)`` or ``(..., 3)`` as plane coordinates ``(..., 2)``."""
    if plane not in PLANES:
        raise ValueError(f"plane must be one of {tuple(PLANES)}, got {plane!r}")
    p = np.asarray(points, dtype=np.float64)
    if p.ndim == 0 or p.shape[-1] not in (2, 3):
        raise ValueError(f"{name} must have shape (..., 2) or (..., 3), got {p.shape}")
    return p if p.shape[-1] == 2 else p[..., list(PLANES[plane])]


def draw_chain(
    ax: Any,
    points: ArrayLike,
    *,
    parents: ArrayLike | None = None,
    plane: str = "xy",
    color: Color = BONE,
    lw: float = 4.0,
    alpha: float = 1.0,
    label: str | None = None,
    joints: bool = True,
    end: bool = False,
) -> list[Any]:
    """Bones as thick lines and joints as amber dots.

    Parameters
    ----------
    points : (J, 2) or (J, 3) joint positions, root first.
    parents : (J,) parent indices for a tree; None: a chain, joint j's parent is j - 1.
    joints : draw the joints; ``end=True`` draws the last one (the end effector) as a white
        dot ringed in the bone colour.

    Returns the bone line, then the joint markers.
    """
    p = _xy(points, plane)
    if p.ndim != 2:
        raise ValueError(f"points must have shape (J, 2) or (J, 3), got {p.shape}")
    if parents is None:
        bones = p
    else:
        par = np.asarray(parents, dtype=np.intp)
        if par.shape != (len(p),):
            raise ValueError(f"parents must have shape ({len(p)},), got {par.shape}")
        bones = bone_xy(par, p)
    lines = ax.plot(bones[:, 0], bones[:, 1], "-", color=color, lw=lw, alpha=alpha,
                    solid_capstyle="round", label=label, zorder=3)
    if joints:
        body = p[:-1] if end else p
        lines += ax.plot(body[:, 0], body[:, 1], "o", ms=lw + 3, mfc=JOINT, mec=JOINT_EDGE,
                         alpha=alpha, zorder=4)
        if end:
            lines += ax.plot(p[-1, 0], p[-1, 1], "o", ms=lw + 2, mfc="white", mec=color, mew=2,
                             alpha=alpha, zorder=4)
    return list(lines)


def draw_target(
    ax: Any, target: ArrayLike, *, plane: str = "xy", color: str = TARGET,
    label: str | None = None,
) -> Any:
    """The target as a star. Returns its line."""
    t = _xy(target, plane, "target").reshape(-1, 2)
    return ax.plot(t[:, 0], t[:, 1], "*", ms=17, color=color, mec="white", mew=0.8, ls="none",
                   label=label, zorder=5)[0]


def draw_base(ax: Any, base: ArrayLike, *, plane: str = "xy") -> Any:
    """The fixed root (the base) as a dark triangle. Returns its line."""
    b = _xy(base, plane, "base")
    return ax.plot(b[0], b[1], "^", ms=13, color=INK, zorder=2)[0]


def draw_path(ax: Any, points: ArrayLike, *, plane: str = "xy", **style: Any) -> Any:
    """A traced path (e.g. the end effector's, iteration after iteration): a dashed line
    through ``points (K, 2|3)``. Returns the line."""
    p = _xy(points, plane).reshape(-1, 2)
    kw = {"color": TRAIL, "lw": 1.2, "ls": "--"} | style
    return ax.plot(p[:, 0], p[:, 1], **kw)[0]


def _direction_deg(v: Array) -> float:
    return float(np.degrees(np.arctan2(v[1], v[0])))


def angle_arc(
    ax: Any,
    center: ArrayLike,
    start: ArrayLike,
    end: ArrayLike,
    radius: float,
    *,
    color: str = ACCENT,
    text: str | None = None,
    text_radius: float | None = None,
    plane: str = "xy",
) -> tuple[Arc, float]:
    """The arc of the angle at ``center`` from the direction to ``start`` to the direction to
    ``end`` (points, not directions), the smaller way round, with an optional label on its
    bisector (at ``text_radius``, default 1.4 ``radius``).

    Returns the arc and the signed angle in degrees, counter-clockwise positive, in (-180, 180].
    """
    c = _xy(center, plane, "center")
    a0 = _direction_deg(_xy(start, plane, "start") - c)
    turn = (_direction_deg(_xy(end, plane, "end") - c) - a0 + 180.0) % 360.0 - 180.0
    if turn == -180.0:
        turn = 180.0
    lo = a0 if turn >= 0 else a0 + turn  # matplotlib draws an arc counter-clockwise
    arc = Arc(tuple(c), 2 * radius, 2 * radius, theta1=lo, theta2=lo + abs(turn), color=color,
              lw=2)
    ax.add_patch(arc)
    if text:
        mid = np.radians(a0 + turn / 2)
        r = 1.4 * radius if text_radius is None else text_radius
        ax.text(c[0] + r * np.cos(mid), c[1] + r * np.sin(mid), text, color=color, fontsize=12,
                ha="center", va="center")
    return arc, float(turn)


def reach_annulus(
    ax: Any, inner: float, outer: float, *, center: ArrayLike = (0.0, 0.0),
    color: str = RING, edges: bool = True,
) -> Wedge:
    """The reachable ring ``inner <= |p - center| <= outer`` shaded (a disc for ``inner = 0``),
    its rims dashed. Returns the shaded wedge."""
    if not 0 <= inner <= outer:
        raise ValueError(f"need 0 <= inner <= outer, got inner={inner}, outer={outer}")
    c = tuple(_xy(center, name="center"))
    ring = Wedge(c, outer, 0, 360, width=outer - inner if inner > 0 else None, color=color,
                 zorder=0)
    ax.add_patch(ring)
    if edges:
        for r in (inner, outer):
            if r > 0:
                ax.add_patch(Circle(c, r, fill=False, ec=BONE, lw=1.2, ls="--", zorder=1))
    return ring


def draw_history(
    ax: Any,
    poses: ArrayLike,
    *,
    parents: ArrayLike | None = None,
    target: ArrayLike | None = None,
    plane: str = "xy",
    label: str = "iterations 0, 1, ...",
    final_label: str | None = None,
    path: bool = True,
) -> None:
    """Every pose of a solve ``(K, J, 2|3)`` faded from light to dark blue, the last one in
    full, and (``path``) the end effector's path through them."""
    p = np.asarray(poses, dtype=np.float64)
    if p.ndim != 3 or len(p) < 1:
        raise ValueError(f"poses must have shape (K, J, 2) or (K, J, 3), got {p.shape}")
    from matplotlib import colormaps

    blues = colormaps["Blues"]
    for k, pose in enumerate(p[:-1]):
        draw_chain(ax, pose, parents=parents, plane=plane, color=blues(0.25 + 0.6 * k / len(p)),
                   lw=2.5, alpha=0.8, joints=False, label=label if k == 0 else None)
    draw_chain(ax, p[-1], parents=parents, plane=plane, end=parents is None,
               label=final_label or f"after {len(p) - 1}")
    if path:
        draw_path(ax, p[:, -1], plane=plane, label="end effector path")
    if target is not None:
        for t in np.asarray(target, dtype=np.float64).reshape(-1, np.shape(target)[-1]):
            draw_target(ax, t, plane=plane)


def iteration_panels(
    poses: Sequence[ArrayLike],
    titles: Sequence[str],
    *,
    target: ArrayLike | None = None,
    base: ArrayLike | None = None,
    pivots: Sequence[int | None] | None = None,
    arrows: bool = False,
    colors: Sequence[str] | None = None,
    ncols: int | None = None,
    xlim: tuple[float, float] = (-2.0, 2.0),
    ylim: tuple[float, float] = (-2.0, 2.0),
    suptitle: str | None = None,
    figsize: tuple[float, float] | None = None,
) -> ChainFigure:
    """A row (or grid) of panels, one per step of an iterative solver: panel 0 the start, each
    later panel the pose before the step (grey) and after it.

    Parameters
    ----------
    poses : K poses (J, 2|3), the start first.
    titles : K panel titles.
    pivots : per panel, the joint that turned (a CCD step): its rays to the old end effector
        (dotted) and to the target (dashed), the arc between them, and a ring on the joint;
        None for no pivot.
    arrows : arrows from each joint's old to its new position (a FABRIK pass).
    colors : per panel, the colour of the new pose (default: the bone blue).
    """
    if len(titles) != len(poses):
        raise ValueError(f"titles must have one entry per pose ({len(poses)}), got {len(titles)}")
    ncols = ncols or len(poses)
    nrows = -(-len(poses) // ncols)
    fig, axes = panels(ncols, nrows=nrows, xlim=xlim, ylim=ylim, figsize=figsize or
                       (3.0 * ncols + 0.4, 3.0 * nrows + 0.9), sharey=True)
    for k, (ax, title) in enumerate(zip(axes, titles, strict=False)):
        ax.set_title(title, fontsize=10)
        if target is not None:
            draw_target(ax, target)
        if base is not None:
            draw_base(ax, base)
        after = _xy(poses[k])
        if k == 0:
            draw_chain(ax, after, end=pivots is not None)
            continue
        before = _xy(poses[k - 1])
        draw_chain(ax, before, color=GHOST, lw=3, alpha=0.7, joints=False)
        pivot = pivots[k] if pivots is not None else None
        if pivot is not None and target is not None:
            r, t = before[pivot], _xy(target)
            ax.plot(*np.stack([r, before[-1]]).T, ":", color=ACCENT, lw=1.3)
            ax.plot(*np.stack([r, t]).T, "--", color=ACCENT, lw=1.3)
            angle_arc(ax, r, before[-1], t, 0.35)
            ax.plot(*r, "o", ms=13, mfc="none", mec=ACCENT, mew=2)
        color = colors[k] if colors is not None else BONE
        if arrows:
            scale = np.ptp(np.concatenate([before, after]), axis=0).max()
            for p, q in zip(before, after, strict=True):
                if np.linalg.norm(q - p) > 0.01 * scale:
                    ax.annotate("", q, p, arrowprops={"arrowstyle": "-|>", "color": color,
                                                      "lw": 1.3, "alpha": 0.8})
        draw_chain(ax, after, color=color, end=pivots is not None)
    for ax in axes[len(poses):]:
        ax.set_visible(False)
    if suptitle:
        fig.suptitle(suptitle, fontsize=10)
    return fig


def overlay_panels(
    cases: Sequence[Mapping[str, ArrayLike]],
    targets: Sequence[ArrayLike],
    titles: Sequence[str],
    *,
    colors: Mapping[str, str] | None = None,
    ghost: ArrayLike | None = None,
    ghost_label: str = "start",
    annulus: tuple[float, float] | None = None,
    root_lines: bool = False,
    base: ArrayLike | None = None,
    xlim: tuple[float, float] = (-2.0, 2.0),
    ylim: tuple[float, float] = (-2.0, 2.0),
    suptitle: str | None = None,
    figsize: tuple[float, float] | None = None,
) -> ChainFigure:
    """One panel per case, several answers to the same target overlaid (e.g. the two mirror
    solutions, or two sweep orders).

    Parameters
    ----------
    cases : per panel, label -> pose (J, 2|3); the labels are the legend of panel 0.
    targets : per panel, the target (2|3,).
    colors : label -> colour (default: the method colours in order).
    ghost : a pose (J, 2|3) drawn faintly under every panel (e.g. the start).
    annulus : (inner, outer) radii of the reachable ring, shaded under every panel.
    root_lines : a dashed line from the root (``base``, default the origin) through each target.
    base : the fixed root (2|3,), drawn as a triangle.
    """
    if not len(cases) == len(targets) == len(titles):
        raise ValueError("cases, targets and titles must have the same length, got "
                         f"{len(cases)}, {len(targets)} and {len(titles)}")
    size = figsize or ((3.5 * len(cases), 4.0) if len(cases) > 1 else (6.0, 4.6))
    fig, axes = panels(len(cases), xlim=xlim, ylim=ylim, sharey=True, figsize=size)
    for ax, case, target, title in zip(axes, cases, targets, titles, strict=True):
        if annulus is not None:
            reach_annulus(ax, *annulus, center=(0.0, 0.0) if base is None else base,
                          color="#eef4fb", edges=False)
        t = _xy(target, name="target")
        root = (0.0, 0.0) if base is None else tuple(_xy(base, name="base"))
        if root_lines:
            ax.axline(root, tuple(t), color=MUTED, ls="--", lw=1)
        if base is not None:
            draw_base(ax, base)
        for k, (label, pose) in enumerate(case.items()):
            color = (colors or {}).get(label, METHOD_COLORS[k % len(METHOD_COLORS)])
            draw_chain(ax, pose, color=color, lw=3.5, alpha=0.9, label=label)
        if ghost is not None:
            draw_chain(ax, ghost, color=GHOST, lw=2, alpha=0.6, joints=False, label=ghost_label)
        draw_target(ax, t)
        ax.set_title(title, fontsize=10)
    axes[0].legend(frameon=False, fontsize=8, loc="lower left")
    if suptitle:
        fig.suptitle(suptitle, fontsize=10)
    return fig


def reachability_figure(
    inner: float,
    outer: float,
    hands: ArrayLike,
    arms: Sequence[ArrayLike],
    solved: Mapping[str, tuple[ArrayLike, ArrayLike]],
    *,
    offsets: Mapping[str, tuple[float, float]] | None = None,
) -> ChainFigure:
    """A two-link arm's reachable ring, two panels.

    Left: the ring with sampled hand positions ``hands (N, 2|3)`` and a few example arms
    ``(3, 2|3)``, the rims annotated (stretched, folded). Right: name -> (target, solved arm);
    a reached target is green on a blue arm, a missed one red on a grey arm with a dotted gap.
    ``offsets``: name -> label offset in points.
    """
    from matplotlib import colormaps

    lim = (-1.2 * outer, 1.2 * outer)
    fig, (left, right) = panels(2, xlim=lim, ylim=lim, figsize=(11, 5.2))
    for ax in (left, right):
        reach_annulus(ax, inner, outer)
        ax.set(xlabel="x", ylabel="y")
    h = _xy(hands, name="hands")
    left.plot(h[:, 0], h[:, 1], ".", ms=1.5, color=MUTED, alpha=0.5, zorder=1)
    for k, arm in enumerate(arms):
        draw_chain(left, arm, color=colormaps["viridis"](0.15 + 0.22 * k), lw=4)
    corner = np.array([-np.sqrt(0.5), -np.sqrt(0.5)])  # 225°: the lower-left of the ring
    for r, text, at in [(outer, f"outer rim: stretched\nd = l₁ + l₂ = {outer:.1f}", -0.97),
                        (inner, f"inner rim: folded\nd = |l₁ − l₂| = {inner:.1f}", 0.84)]:
        left.annotate(text, r * corner, (lim[0] * 0.97, lim[1] * at), fontsize=8,
                      arrowprops={"arrowstyle": "-", "color": MUTED})
    left.set_title(f"The hands of {len(h):,} random poses fill the ring", fontsize=10)
    for name, (target, arm) in solved.items():
        t, a = _xy(target, name="target"), _xy(arm, name="arm")
        ok = bool(np.linalg.norm(a[-1] - t) < 1e-9)
        draw_chain(right, a, color=BONE if ok else "#8f9aa6", lw=4)
        draw_target(right, t, color=GREEN if ok else TARGET)
        if not ok:
            right.plot(*np.stack([a[-1], t]).T, ":", color=TARGET, lw=1.5)
        right.annotate(name, tuple(t), xytext=(offsets or {}).get(name, (8, 4)),
                       textcoords="offset points", fontsize=8,
                       color="#1f7a4d" if ok else "#a4161a")
    right.set_title("Solved: green targets are reached; red ones get the closest pose",
                    fontsize=10)
    return fig


def law_of_cosines_figure(
    root: ArrayLike, mid: ArrayLike, end: ArrayLike, target: ArrayLike,
) -> ChainFigure:
    """The triangle of a solved two-link arm: sides l₁ (root-mid), l₂ (mid-end) and d
    (root-target) labelled, the triangle shaded, the angle α at the root (between the line to
    the target and the first bone) and the inner angle β at the middle joint drawn as arcs."""
    a, b, c, t = (_xy(p, name=n) for p, n in
                  ((root, "root"), (mid, "mid"), (end, "end"), (target, "target")))
    fig, (ax,) = panels(1, figsize=(6.4, 4.8))
    ax.fill(*np.stack([a, b, t]).T, color=RING, zorder=0)
    ax.plot(*np.stack([a, t]).T, "--", color=MUTED, lw=1.3)
    draw_chain(ax, np.stack([a, b, c]), lw=5)
    draw_target(ax, t)
    size = float(np.linalg.norm(t - a))
    angle_arc(ax, a, t, b, 0.3 * size, text="α")
    angle_arc(ax, b, a, c, 0.18 * size, color=TRAIL, text="β")
    for p, q, text in ((a, b, "l₁"), (b, c, "l₂"), (a, t, "d")):
        side = q - p
        normal = np.array([-side[1], side[0]]) / np.linalg.norm(side)
        inward = np.sign(normal @ ((a + b + t) / 3 - (p + q) / 2)) or 1.0
        ax.text(*((p + q) / 2 - 0.09 * size * inward * normal), text, fontsize=13, color=INK,
                ha="center", va="center")
    ax.text(*(a - 0.08 * size), "a (root)", fontsize=9, ha="right")
    ax.text(*(b + [0.04 * size, -0.1 * size]), "b", fontsize=11)
    ax.text(*(t + 0.05 * size), "t", fontsize=11, color=TARGET)
    points = np.stack([a, b, c, t])
    lo, hi = points.min(axis=0) - 0.3 * size, points.max(axis=0) + 0.25 * size
    ax.set(aspect="equal", xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), xlabel="x", ylabel="y",
           title="Sides l₁, l₂, d fix the angles: d² = l₁² + l₂² − 2 l₁ l₂ cos β")
    return fig


def pole_figure(
    legs: ArrayLike,
    poles: ArrayLike,
    target: ArrayLike,
    circle: ArrayLike,
    *,
    lim: float = 1.0,
    height: tuple[float, float] = (-1.8, 0.2),
) -> ChainFigure:
    """Two-link solutions for several poles, in 3D, twice: from the side, and looking down the
    root-target axis. Each leg ``legs[k] (3, 3)`` and its pole ``poles[k] (3,)`` (a diamond,
    joined to the knee) share a colour; the grey circle ``circle (M, 3)`` holds every solution's
    middle joint."""
    from matplotlib import colormaps

    legs_, poles_ = np.asarray(legs, dtype=np.float64), np.asarray(poles, dtype=np.float64)
    if legs_.ndim != 3 or legs_.shape[1:] != (3, 3) or poles_.shape != (len(legs_), 3):
        raise ValueError(f"legs must be (K, 3, 3) and poles (K, 3), got {legs_.shape} and "
                         f"{poles_.shape}")
    t = np.asarray(target, dtype=np.float64)
    axis = t - legs_[0, 0]
    view = np.stack(mpl3(-axis / np.linalg.norm(axis)))  # down the root -> target axis
    down = (float(np.degrees(np.arcsin(view[2]))), float(np.degrees(np.arctan2(view[1], view[0]))))
    fig, axes = panels(2, figsize=(11, 5.4), projection="3d")
    tab10 = colormaps["tab10"]
    for ax, (elev, azim), title in zip(axes, [(14.0, -60.0), down],
                                       [f"{len(legs_)} poles, {len(legs_)} knees",
                                        "looking down the hip–target axis"], strict=True):
        ax.plot(*mpl3(circle), color=GHOST, lw=1.5, ls="--")
        ax.plot(*mpl3(np.stack([legs_[0, 0], t])), color=MUTED, lw=1, ls=":")
        for k, (leg, pole) in enumerate(zip(legs_, poles_, strict=True)):
            color = tab10(k if k < 7 else k + 1)  # skip tab10's grey
            ax.plot(*mpl3(leg), "-o", color=color, lw=3.5, ms=5, mfc=JOINT, mec=JOINT_EDGE)
            ax.plot(*mpl3(pole), "D", color=color, ms=6)
            ax.plot(*mpl3(np.stack([leg[1], pole])), color=color, lw=0.8, ls="--")
        ax.plot(*mpl3(t), "*", color=TARGET, ms=16)
        ax.set(xlabel="z", ylabel="x", zlabel="y", title=title, xticklabels=[], yticklabels=[],
               zticklabels=[], xlim=(-lim, lim), ylim=(-lim, lim), zlim=height)
        ax.set_box_aspect((1, 1, 1))
        ax.view_init(elev=elev, azim=azim)
    fig.suptitle("The knee (amber) turns to its pole (◆ of the same colour); the grey circle "
                 "holds every solution", fontsize=10)
    return fig


def body_views(
    parents: ArrayLike,
    poses: Mapping[str, ArrayLike],
    *,
    targets: ArrayLike | None = None,
    markers: Mapping[str, ArrayLike] | None = None,
    highlight: Sequence[int] = (),
    ground: float | None = None,
    step: tuple[float, float, float] | None = None,
    half_width: float | None = None,
    ylim: tuple[float, float] | None = None,
    titles: tuple[str, str] = ("side view", "front view"),
) -> ChainFigure:
    """A skeleton from the side (z forward, y up) and from the front (x, y up), several poses
    overlaid: the first pose thick and light grey (e.g. the captured one), the others blue.

    Parameters
    ----------
    parents : (J,) parent indices.
    poses : label -> (J, 3) joint positions.
    targets : (T, 3) targets, drawn as stars.
    markers : label -> (3,) point, drawn in turn as a diamond (e.g. a pole), a plus, a square
        and a cross.
    highlight : joints whose bone (to the parent) is drawn 1.5x wider.
    ground : the floor's height (a line); ``step = (z from, z to, top)`` a box on it (side).
    half_width : each view spans the first pose's root ± this (default: fit the poses).
    """
    fig, axes = panels(2, figsize=(10, 5.8), width_ratios=(1.25, 1))
    wide = set(highlight)
    par = np.asarray(parents, dtype=np.intp)
    for ax, plane, title in zip(axes, ("zy", "xy"), titles, strict=True):
        for k, (label, pose) in enumerate(poses.items()):
            color, lw = ("#c3cad3", 4.0) if k == 0 else (METHOD_COLORS[k - 1], 2.4)
            p = _xy(pose, plane, label)
            if p.shape != (len(par), 2):
                raise ValueError(f"poses[{label!r}] must have shape ({len(par)}, 3), "
                                 f"got {np.shape(pose)}")
            for child in range(1, len(par)):
                seg = p[[par[child], child]]
                ax.plot(seg[:, 0], seg[:, 1], color=color, solid_capstyle="round",
                        lw=lw * (1.5 if child in wide else 1), label=label if child == 1 else None)
        if targets is not None:
            draw_target(ax, targets, plane=plane, label="target")
        for k, (label, point) in enumerate((markers or {}).items()):
            q = _xy(point, plane, label)
            ax.plot(q[0], q[1], "DPsX"[k % 4], color=ACCENT, ms=9, ls="none", label=label,
                    zorder=6)
        if ground is not None:
            ax.axhline(ground, color="#8f9aa6", lw=1)
            if step is not None and plane == "zy":
                ax.add_patch(Rectangle((step[0], ground), step[1] - step[0], step[2] - ground,
                                       color="#d5dae0", zorder=0))
        ax.set(aspect="equal", xlabel="z (forward)" if plane == "zy" else "x (sideways)",
               ylabel="y (up)", title=title)
        ax.title.set_fontsize(10)
        if half_width is not None:
            center = _xy(next(iter(poses.values())), plane)[0, 0]
            ax.set_xlim(center - half_width, center + half_width)
        if ylim is not None:
            ax.set_ylim(*ylim)
    axes[1].legend(frameon=False, fontsize=8, loc="upper right")
    return fig


def subbase_figure(
    parents: ArrayLike,
    start: ArrayLike,
    proposals: Mapping[str, ArrayLike],
    centroid: ArrayLike,
    frames: Sequence[ArrayLike],
    targets: ArrayLike,
    *,
    xlim: tuple[float, float] = (-2.6, 2.6),
    ylim: tuple[float, float] = (-0.4, 3.6),
) -> ChainFigure:
    """Multi-effector FABRIK on a tree, three panels: the start with its targets; each branch's
    forward pass (``proposals``: name -> branch positions, sub-base first), its proposed
    sub-base (□) and their ``centroid`` (+); and the solve, ``frames`` faded, the last in full.
    """
    fig, axes = panels(3, xlim=xlim, ylim=ylim, figsize=(14, 4.9), sharey=True)
    s = np.asarray(start, dtype=np.float64)
    for ax in axes:
        draw_target(ax, targets)
        draw_base(ax, s[0])
    draw_chain(axes[0], s, parents=parents)
    axes[0].set_title("start: one trunk, two arms, two targets", fontsize=10)
    draw_chain(axes[1], s, parents=parents, color=GHOST, lw=3, alpha=0.6)
    for k, (name, reached) in enumerate(proposals.items()):
        r, color = _xy(reached, name=name), (TARGET, ORANGE, GREEN, BONE)[k % 4]
        draw_chain(axes[1], r, color=color, lw=3, label=f"{name} branch, forward")
        axes[1].plot(*r[0], "s", ms=10, mfc="white", mec=color, mew=2, zorder=6)
    axes[1].plot(*_xy(centroid, name="centroid"), "P", ms=14, color=ACCENT, zorder=7,
                 label="centroid: new sub-base")
    axes[1].legend(frameon=False, fontsize=8, loc="lower left")
    axes[1].set_title("each branch proposes a sub-base (□); it takes the centroid", fontsize=10)
    draw_history(axes[2], np.asarray(frames, dtype=np.float64), parents=parents, path=False,
                 label="iterations", final_label="solved")
    axes[2].set_title(f"solved in {len(frames) - 1} iterations (faded), both hands on target",
                      fontsize=10)
    return fig


def _method_color(method: str, k: int) -> str:
    return METHOD_COLOR.get(method.lower(), METHOD_COLORS[k % len(METHOD_COLORS)])


def tracking_figure(
    path: ArrayLike,
    tracks: Mapping[str, Sequence[Any]],
    names: Sequence[str],
    *,
    every: int = 5,
    xlim: tuple[float, float] = (-1.2, 2.6),
    ylim: tuple[float, float] = (-1.6, 1.9),
    suptitle: str = "Warm-started IK on a target moving along a figure eight (dashed)",
) -> ChainFigure:
    """IK following a moving target, one column per method. Top: the target's ``path (F, 3)``
    and every ``every``-th solved pose; bottom: each joint's angle (degrees) against the frame,
    titled with the mean joint change per frame and the widest range a joint swept.

    ``tracks``: method -> (angles (F, J) in radians, unwrapped; poses (F, J + 1, 3); anything
    after these two is ignored).
    """
    fig = ChainFigure(figsize=(4.3 * len(tracks), 7.6), dpi=110, layout="constrained")
    FigureCanvasAgg(fig)
    grid = fig.add_gridspec(2, len(tracks), height_ratios=[1, 1.05])
    for k, (method, track) in enumerate(tracks.items()):
        th, poses = np.degrees(np.asarray(track[0], dtype=np.float64)), track[1]
        color = _method_color(method, k)
        top = fig.add_subplot(grid[0, k])
        style_axes(top)
        draw_path(top, path, color=MUTED, lw=1)
        for pose in np.asarray(poses, dtype=np.float64)[::every]:
            top.plot(*_xy(pose).T, "-", color=color, lw=1.2, alpha=0.35)
        top.set(aspect="equal", xlim=xlim, ylim=ylim, title=f"{method.upper()}: every "
                f"{every}th frame")
        bottom = fig.add_subplot(grid[1, k])
        style_axes(bottom)
        for j in range(th.shape[1]):
            bottom.plot(th[:, j], lw=1.6, label=names[j])
        change = np.abs(np.diff(th, axis=0)).sum(1).mean()
        bottom.set(xlabel="frame", ylabel="joint angle (°)" if k == 0 else None)
        bottom.set_title(f"joint angles: mean change {change:.1f}°/frame, widest range "
                         f"{np.ptp(th, axis=0).max():.0f}°", fontsize=9)
        if k == 0:
            bottom.legend(frameon=False, fontsize=8, ncol=2)
    fig.suptitle(suptitle, fontsize=11)
    return fig


def frame_change_plot(tracks: Mapping[str, ArrayLike]) -> ChainFigure:
    """Σ_j |Δθ_j| per frame (degrees) for each method; ``tracks``: method -> (F, J) angles in
    radians, unwrapped."""
    fig, (ax,) = panels(1, figsize=(9, 3.4))
    for k, (method, theta) in enumerate(tracks.items()):
        change = np.degrees(np.abs(np.diff(np.asarray(theta, dtype=np.float64), axis=0)).sum(1))
        ax.plot(np.arange(1, len(change) + 1), change, color=_method_color(method, k), lw=1.6,
                label=method.upper())
        ax.set_xlim(0, len(change) + 1)
    ax.set(xlabel="frame", ylabel="Σ |Δθ| per frame (°)",
           title="Frame-to-frame joint change for the same smooth target motion")
    ax.legend(frameon=False)
    return fig


def turn_violins(
    turns: Mapping[str, ArrayLike],
    orders: Sequence[Sequence[int]],
    names: Sequence[str],
    *,
    suptitle: str | None = None,
) -> ChainFigure:
    """How much each joint turned, one panel per sweep order, the joints in the order the
    sweep visits them and the first one visited in red; a violin per joint shows the spread
    over many targets, its median marked.

    Parameters
    ----------
    turns : panel title -> (N, J) angles in degrees, one column per joint (root first).
    orders : per panel, the joint indices in the order the sweep visits them.
    names : the joints' names (root first).
    """
    if len(orders) != len(turns):
        raise ValueError(f"orders must have one entry per panel ({len(turns)}), got {len(orders)}")
    fig, axes = panels(len(turns), figsize=(5.5 * len(turns), 3.8), sharey=True)
    for ax, (title, angles), order in zip(axes, turns.items(), orders, strict=True):
        a = np.asarray(angles, dtype=np.float64)[:, list(order)]
        parts = ax.violinplot([a[:, j] for j in range(a.shape[1])], showmedians=True,
                              widths=0.8)
        for k, body in enumerate(parts["bodies"]):
            body.set_facecolor(TARGET if k == 0 else BONE)
            body.set_alpha(0.55)
        ax.set_xticks(range(1, a.shape[1] + 1),
                      [f"{k + 1}. {names[j]}" for k, j in enumerate(order)])
        ax.set(xlabel="joints in the order the sweep visits them", ylim=(0, 185), title=title)
    axes[0].set_ylabel("rotation in the first sweep (°)")
    if suptitle:
        fig.suptitle(suptitle, fontsize=10)
    return fig


def history_figure(
    poses: ArrayLike,
    residuals: Mapping[str, ArrayLike],
    *,
    target: ArrayLike,
    tol: float | None = None,
    xlim: tuple[float, float] = (-2.0, 2.0),
    ylim: tuple[float, float] = (-2.0, 2.0),
    title: str = "record=True: every iteration",
    label: str = "iterations 0, 1, ...",
) -> ChainFigure:
    """One solve, two panels: left, every recorded pose ``(K, J, 2|3)`` (see
    :func:`draw_history`) with the end effector's path; right, the residual per iteration
    (:func:`course.viz.figures.convergence_plot` of ``residuals``: method -> (K,))."""
    from .figures import convergence_plot

    fig, (left, right) = panels(2, figsize=(11, 4.3), width_ratios=(1.1, 1))
    draw_history(left, poses, target=target, label=label)
    left.set(aspect="equal", xlim=xlim, ylim=ylim, title=title)
    left.legend(frameon=False, fontsize=8, loc="lower left")
    convergence_plot(residuals, tol=tol, ax=right, title="error per iteration")
    return fig


def iterations_histogram(
    ax: Any, iterations: Mapping[str, ArrayLike], *, clip: int = 60, width: int = 2,
    tol: float | None = None,
) -> Any:
    """Histogram of the iterations each method needed, one colour per method, the medians in
    the legend; counts above ``clip`` are drawn at ``clip``. Returns ``ax``."""
    bins = np.arange(0, clip + 1, width)
    for k, (method, its) in enumerate(iterations.items()):
        n = np.asarray(its)
        ax.hist(np.minimum(n, clip), bins=bins, color=_method_color(method, k), alpha=0.6,
                label=f"{method.upper()} (median {np.median(n):.0f})")
    reach = f"|e − t| < {tol:g}" if tol is not None else "the tolerance"
    ax.set(xlabel=f"iterations to reach {reach} (clipped at {clip})", ylabel="targets")
    ax.legend(frameon=False)
    return ax


def snapshot_row(snapshots: Sequence[tuple[str, bytes]], *, width: int = 210) -> Any:
    """PNG snapshots (caption, PNG bytes) side by side, wrapping, as an ``IPython HTML``."""
    from base64 import b64encode

    from IPython.display import HTML

    html: Any = HTML  # IPython is untyped
    cells = "".join(
        f"<figure style='margin:0'><img width='{width}' src='data:image/png;base64,"
        f"{b64encode(png).decode()}'><figcaption style='text-align:center;font-size:11px'>"
        f"{caption}</figcaption></figure>" for caption, png in snapshots)
    return html(f"<div style='display:flex;flex-wrap:wrap;gap:6px'>{cells}</div>")


__all__ = [
    "METHOD_COLOR",
    "ChainFigure",
    "angle_arc",
    "body_views",
    "draw_base",
    "draw_chain",
    "draw_history",
    "draw_path",
    "draw_target",
    "frame_change_plot",
    "history_figure",
    "iteration_panels",
    "iterations_histogram",
    "law_of_cosines_figure",
    "overlay_panels",
    "panels",
    "pole_figure",
    "reach_annulus",
    "reachability_figure",
    "snapshot_row",
    "subbase_figure",
    "tracking_figure",
    "turn_violins",
]
