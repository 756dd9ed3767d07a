r"""Still figures of notebooks 02 and 03: a planar arm with its joint frames, a skeleton's
hierarchy beside its rest pose, the same pose rooted at two joints, a clip as a strobe of side
views, the gait's contacts and knee angles over time, and front views with bone elevations.

Each function draws what the notebook computed (forward kinematics, contacts, peaks); the
maths stays in the cell that calls it. Chains are drawn with :mod:`course.viz.chain_plots`
(bones, amber joints, the notebooks' style), and every figure is a
:class:`~course.viz.chain_plots.ChainFigure`: it shows itself as a PNG when it ends a cell.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import rotations as rot
from .._typing import Array
from ..skeleton import Skeleton
from .chain_plots import ChainFigure, draw_chain, panels
from .figures import AXIS_RGB, METHOD_COLORS

PALETTE = ("#3d7dca", "#2bb673", "#8e6bd8", "#f08c3a", "#e5484d", "#1f9bb4")
INK = "#2b3440"
BEFORE = "#c3cad3"
GROUND = "#8f9aa6"
SIDES = {"Left": "#3d7dca", "Right": "#e5484d"}  # the two sides, as bvh_player draws them
LANDMARKS = ("Hips", "Spine1", "Head", "LeftArm", "LeftHand", "RightArm", "RightHand",
             "LeftLeg", "LeftFoot", "RightLeg", "RightFoot")


def _points(a: ArrayLike, n: int, name: str) -> Array:
    p = np.asarray(a, dtype=np.float64)
    if p.shape != (n, 3):
        raise ValueError(f"{name} must have shape ({n}, 3), got {p.shape}")
    return p


def _fit(ax: Any, points: Array, margin: float) -> None:
    lo, hi = points.min(axis=0) - margin, points.max(axis=0) + margin
    ax.set(aspect="equal", xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]))


def planar_arm(ax: Any, positions: ArrayLike, orientations: ArrayLike | None = None, *,
               color: Any = "#3d7dca", alpha: float = 1.0, frame_length: float = 0.28) -> None:
    r"""A chain in the xy plane: bones, amber joints and, with ``orientations``, each joint's
    frame as its x (red) and y (green) axes.

    Parameters
    ----------
    ax : a 2D matplotlib axes.
    positions : (J, 3) joint positions :math:`p_i` (x, y drawn), root first.
    orientations : (J, 4) global orientations :math:`Q_i` (w, x, y, z), or None (no frames).
    frame_length : the drawn length of each frame axis.
    """
    p = np.asarray(positions, dtype=np.float64)
    draw_chain(ax, p, color=color, lw=5, alpha=alpha)
    if orientations is None:
        return
    mats = rot.matrix_from_quat(np.asarray(orientations, dtype=np.float64))
    if mats.shape != (len(p), 3, 3):
        raise ValueError(f"orientations must have shape ({len(p)}, 4), got "
                         f"{np.shape(orientations)}")
    for pi, Mi in zip(p, mats, strict=True):
        for axis in (0, 1):
            tip = pi + frame_length * Mi[:, axis]
            ax.annotate("", tip[:2], pi[:2], zorder=5,  # over the bones (draw_chain: 3, 4)
                        arrowprops={"arrowstyle": "-|>", "color": AXIS_RGB[axis], "lw": 1.8})


def arm_panels(poses: Mapping[str, Sequence[tuple[ArrayLike, ArrayLike]]], *,
               names: Sequence[str] | None = None, margin: float = 0.5) -> ChainFigure:
    r"""Planar arm poses, one panel per title.

    Parameters
    ----------
    poses : panel title -> list of (positions (J, 3), orientations (J, 4)) from forward
        kinematics. A panel of one pose draws the joint frames and labels each joint with its
        name and global turn about z (from :math:`Q_i`); a panel of several overlays them,
        coloured from dark to light (viridis), without frames.
    names : J joint names, for the labels.
    margin : space around the poses; every panel shows the same region, equal aspect.

    Returns
    -------
    The :class:`ChainFigure`, one axes per panel.
    """
    from matplotlib import colormaps

    fig, axs = panels(len(poses), figsize=(5.5 * len(poses), 4.6))
    everything = np.concatenate([np.asarray(p, dtype=np.float64)[:, :2]
                                 for group in poses.values() for p, _ in group])
    for ax, (title, group) in zip(axs, poses.items(), strict=True):
        if len(group) == 1:
            p, Q = (np.asarray(a, dtype=np.float64) for a in group[0])
            planar_arm(ax, p, Q)
            turn = np.degrees(2 * np.arctan2(Q[:, 3], Q[:, 0]))  # Q is a turn about z
            for k, (pi, a) in enumerate(zip(p, (turn + 180) % 360 - 180, strict=True)):
                name = names[k] if names is not None else f"joint {k}"
                ax.text(pi[0] + 0.05, pi[1] - 0.17, f"{name}\nQ: {a:.0f}°", fontsize=8)
        else:
            for k, (pk, _) in enumerate(group):
                planar_arm(ax, pk, color=colormaps["viridis"](k / (len(group) - 1)), alpha=0.85)
        ax.set_title(title, fontsize=10)
        ax.set(xlabel="x", ylabel="y")
        _fit(ax, everything, margin)
    return fig


def tree_layout(skeleton: Skeleton) -> tuple[NDArray[np.intp], Array]:
    """Where each joint goes in a drawing of the hierarchy: x = its depth (bones below the
    root), y = minus its row: the leaves one row apart in order, a parent centred on its
    children. Returns ``(x (J,), y (J,))``."""
    y = np.zeros(skeleton.n_joints)
    row = {leaf: k for k, leaf in enumerate(skeleton.end_effectors)}
    for j in reversed(range(skeleton.n_joints)):  # children have larger indices than parents
        kids = skeleton.children(j)
        y[j] = np.mean(y[kids]) if kids else row[j]
    return np.array([skeleton.depth(j) for j in range(skeleton.n_joints)], dtype=np.intp), -y


def limbs(skeleton: Skeleton, min_children: int = 3) -> tuple[NDArray[np.intp], list[int]]:
    """The limb of each joint: the child of a *hub* (a joint with at least ``min_children``
    children) that the joint hangs from (0 for the root and the hubs above every limb).
    Returns ``(limb (J,), hubs)``."""
    hubs = [j for j in range(skeleton.n_joints) if len(skeleton.children(j)) >= min_children]
    limb = np.zeros(skeleton.n_joints, dtype=np.intp)
    for j in range(1, skeleton.n_joints):
        parent = int(skeleton.parents[j])
        limb[j] = j if parent in hubs else limb[parent]
    return limb, hubs


def hierarchy_figure(skeleton: Skeleton, *,
                     landmarks: Sequence[str] = LANDMARKS) -> ChainFigure:
    r"""A skeleton's tree beside its rest pose, coloured by limb.

    Left: the hierarchy, laid out by :func:`tree_layout` (root on the left, one column per
    bone), each joint joined to its parent by an elbow line and labelled; End Sites as hollow
    dots, hubs (three children or more) as large dots. Right: the rest pose
    :math:`p_i = p_{p(i)} + l_i` (every :math:`R_i = I`), front view (x, y), the ``landmarks``
    labelled (names not in the skeleton are skipped).

    Returns
    -------
    The :class:`ChainFigure`; its axes are (hierarchy, rest pose).
    """
    limb, hubs = limbs(skeleton)
    color = {int(k): PALETTE[i % len(PALETTE)] for i, k in enumerate(sorted(set(limb[1:])))}
    color[0] = INK
    tx, ty = tree_layout(skeleton)
    rest = skeleton.rest_positions()
    fig, (ax0, ax1) = panels(2, figsize=(13, 5.6), width_ratios=(1.7, 1))
    for j in range(1, skeleton.n_joints):
        p, c = int(skeleton.parents[j]), color[int(limb[j])]
        ax0.plot([tx[p], tx[p], tx[j]], [ty[p], ty[j], ty[j]], color=c, lw=2)
        ax1.plot(*rest[[p, j]][:, :2].T, color=c, lw=3, solid_capstyle="round")
    for j in range(skeleton.n_joints):
        tip, hub = j in skeleton.end_effectors, j in hubs
        ax0.plot(tx[j], ty[j], "o", ms=11 if hub else 7, mfc="white" if tip else "#ffb000",
                 mec=color[int(limb[j])] if tip else "#7a5600")
        ax0.text(tx[j], ty[j] + 0.18, skeleton.names[j], fontsize=7, rotation=28, va="bottom")
    ax1.plot(*rest[:, :2].T, "o", ms=4, mfc="#ffb000", mec="#7a5600", ls="none")
    ax1.plot(*rest[hubs, :2].T, "o", ms=10, mfc="#ffb000", mec="#7a5600", ls="none")
    for name in (n for n in landmarks if n in skeleton.names):
        p = rest[skeleton.index(name)]
        ax1.annotate(name, p[:2], (p[0] + 0.5, p[1] + 0.6), fontsize=7)
    ax0.set(xlabel="depth: bones between the joint and the root", yticks=[],
            xlim=(-0.3, tx.max() + 1.8), ylim=(ty.min() - 0.5, 1.3),
            title="The hierarchy: parent → children (○: End Site, large dot: three children)")
    ax0.grid(False)
    ax1.set(aspect="equal", xlabel="x (the actor's left is +x)", ylabel="y (up)",
            title="The rest pose, front view: p_i = p_parent + l_i")
    for ax in (ax0, ax1):
        ax.title.set_fontsize(10)
    return fig


def _side(skeleton: Skeleton, ax: Any, pose: Array, color: Any, lw: float,
          highlight: Sequence[int] = (), label: str | None = None) -> None:
    """A skeleton from the side (z forward to the right, y up); the ``highlight`` joints (a
    path, in order) drawn again 1.6x wider over it."""
    draw_chain(ax, pose, parents=skeleton.parents, plane="zy", color=color, lw=lw,
               joints=False, label=label)
    if len(highlight) > 1:
        draw_chain(ax, pose[list(highlight)], plane="zy", color=color, lw=1.6 * lw,
                   joints=False)


def root_views(skeleton: Skeleton, before: ArrayLike,
               cases: Mapping[str, tuple[ArrayLike, str | int, str | int]], *,
               highlight: Sequence[int] = (), label: str = "after") -> ChainFigure:
    """The same change of pose under different roots, one side view per case.

    Parameters
    ----------
    skeleton : the skeleton.
    before : (J, 3) joint positions before the change (grey, thick).
    cases : panel title -> (positions after the change (J, 3), the root joint, a joint that
        moves); the root is marked where it was (▼), the moving joint gets a green arrow from
        its old to its new place and the distance in the corner.
    highlight : a path of joints drawn wider (e.g. the leg that changed).
    label : legend entry of the changed pose.

    Returns
    -------
    The :class:`ChainFigure`, one axes per case (legend in the first).
    """
    n = skeleton.n_joints
    b = _points(before, n, "before")
    fig, axs = panels(len(cases), figsize=(4.75 * len(cases), 5.6))
    poses = [b]
    for ax, (title, (after_, root, mover)) in zip(axs, cases.items(), strict=True):
        after = _points(after_, n, f"cases[{title!r}]")
        poses.append(after)
        r, m = skeleton.index(root), skeleton.index(mover)
        _side(skeleton, ax, b, BEFORE, 4, highlight, label="before")
        _side(skeleton, ax, after, "#3d7dca", 2.2, highlight, label=label)
        ax.plot(b[r, 2], b[r, 1], marker="v", ms=14, color="#e5484d", ls="none", zorder=6,
                label="the root stays here")
        ax.annotate("", (after[m, 2], after[m, 1]), (b[m, 2], b[m, 1]), zorder=6,
                    arrowprops={"arrowstyle": "-|>", "color": "#2bb673", "lw": 2.5})
        ax.text(0.04, 0.03, f"green arrow: {skeleton.names[m]} moves "
                f"{np.linalg.norm(after[m] - b[m]):.2f}", transform=ax.transAxes,
                color="#1f7a4d", fontsize=9)
        ax.axhline(0, color=GROUND, lw=1)
        ax.set(title=title, xlabel="z (forward)", ylabel="y (up)")
    everything = np.concatenate(poses)[:, [2, 1]]
    for ax in axs:
        _fit(ax, np.vstack([everything, [[everything[:, 0].min(), 0.0]]]), 1.5)
    axs[0].legend(frameon=False, loc="upper left", fontsize=8)
    return fig


def strobe(skeleton: Skeleton, positions: ArrayLike, every: int, *,
           traces: Sequence[str] = (), frame_time: float | None = None,
           title: str = "") -> ChainFigure:
    """A clip as a strobe photograph from the side: every ``every``-th pose, dark (early) to
    light (late), and the full path of each joint in ``traces``.

    Parameters
    ----------
    positions : (F, J, 3) joint positions of every frame.
    every : frames between two drawn poses.
    traces : joint names whose path (z, y) is drawn over all frames, one colour each.
    frame_time : seconds per frame, to title the figure with the time between poses.
    title : the start of the title (e.g. the clip's name).

    Returns
    -------
    The :class:`ChainFigure` (one axes: z forward, y up, equal aspect).
    """
    from matplotlib import colormaps

    P = np.asarray(positions, dtype=np.float64)
    if P.ndim != 3 or P.shape[1:] != (skeleton.n_joints, 3):
        raise ValueError(f"positions must have shape (F, {skeleton.n_joints}, 3), got {P.shape}")
    if every < 1:
        raise ValueError(f"every must be at least 1, got {every}")
    fig, (ax,) = panels(1, figsize=(11, 3.4))
    shown = range(0, len(P), every)
    for k, f in enumerate(shown):
        draw_chain(ax, P[f], parents=skeleton.parents, plane="zy", lw=2, joints=False,
                   color=colormaps["viridis"](k / max(len(shown) - 1, 1)))
    for k, name in enumerate(traces):
        j = skeleton.index(name)
        ax.plot(P[:, j, 2], P[:, j, 1], color=METHOD_COLORS[k % len(METHOD_COLORS)], lw=1,
                alpha=0.8, label=f"{name} path")
    ax.axhline(0, color=GROUND, lw=1)
    step = f"every {every * frame_time:.1f} s" if frame_time else f"every {every} frames"
    ax.set(aspect="equal", xlabel="z (forward, file units)", ylabel="y (up)",
           title=f"{title + ', ' if title else ''}{step} (dark = early, light = late)")
    if traces:
        ax.legend(frameon=False, loc="upper left", fontsize=8)
    return fig


def gait_figure(times: ArrayLike, heights: Mapping[str, ArrayLike],
                swings: Mapping[str, ArrayLike], contact: Mapping[str, ArrayLike],
                knee: Mapping[str, ArrayLike]) -> ChainFigure:
    """The gait over time, two rows sharing the time axis, one colour per side.

    Parameters
    ----------
    times : (F,) seconds.
    heights : side ("Left", "Right") -> (F,) ankle height; swing peaks marked ▼.
    swings : side -> frame indices of the swing peaks (one step each).
    contact : side -> (F,) bool, the foot on the ground: a bar under the curves.
    knee : side -> (F,) knee flexion in radians (drawn in degrees), dotted lines at the swings.

    Returns
    -------
    The :class:`ChainFigure`; its axes are (heights, knee flexion).
    """
    t = np.asarray(times, dtype=np.float64)
    fig, (ax, ax2) = panels(1, nrows=2, figsize=(11, 5.8))
    ax2.sharex(ax)
    for k, side in enumerate(heights):
        color = SIDES.get(side, METHOD_COLORS[k % len(METHOD_COLORS)])
        h, s = np.asarray(heights[side], dtype=np.float64), np.asarray(swings[side], dtype=int)
        ax.plot(t, h, color=color, lw=2, label=f"{side}Foot (ankle) height")
        ax.plot(t[s], h[s], "v", color=color, ms=8)
        ax.fill_between(t, -0.35 - 0.35 * k, -0.05 - 0.35 * k,
                        where=np.asarray(contact[side], dtype=bool), color=color, alpha=0.55,
                        lw=0, label=f"{side} foot in contact")
        ax2.plot(t, np.degrees(np.asarray(knee[side], dtype=np.float64)), color=color, lw=2,
                 label=f"{side}Leg (knee)")
        for ts in t[s]:
            ax2.axvline(ts, color=color, lw=0.8, ls=":")
    top = max(float(np.max(h)) for h in heights.values())
    ax.set(ylabel="y (file units)", xlim=(t[0], t[-1]), ylim=(-0.35 * len(heights) - 0.1,
                                                                top * 1.25),
           title="Ankle heights: stance (flat, bar below) and swing (peak ▼ = one step)")
    ax.legend(frameon=False, ncol=4, loc="upper center", fontsize=8)
    ax2.set(xlabel="time (s)", ylabel="knee flexion (°)",
            title="Knee flexion: the peaks follow the swings (dotted: the ankle peaks ▼ above)")
    ax2.legend(frameon=False, ncol=2, loc="upper right", fontsize=8)
    return fig


def bone_elevation(skeleton: Skeleton, pose: ArrayLike, a: str | int, b: str | int) -> float:
    """Angle of the bone from joint ``a`` to joint ``b`` above the horizontal plane (y up), in
    degrees: +90 straight up, -90 straight down."""
    p = np.asarray(pose, dtype=np.float64)
    d = p[skeleton.index(b)] - p[skeleton.index(a)]
    length = np.linalg.norm(d)
    if length == 0:
        raise ValueError(f"the bone {a!r} -> {b!r} has length 0: no direction")
    return float(np.degrees(np.arcsin(d[1] / length)))


def front_views(skeleton: Skeleton, poses: Mapping[str, ArrayLike],
                bones: Sequence[tuple[str, str]] = (), *,
                level: str | None = None, title: str = "") -> ChainFigure:
    """Poses from the front (x, y up), side by side with a shared height axis, each labelled
    with the elevation (:func:`bone_elevation`) of the ``bones`` (pairs of joint names) at
    their middle; ``level`` draws a dashed line at that joint's height; ``title`` is the
    figure's title.

    Returns
    -------
    The :class:`ChainFigure`, one axes per pose.
    """
    fig, axs = panels(len(poses), figsize=(5 * len(poses), 5), sharey=True)
    for ax, (name, pose_) in zip(axs, poses.items(), strict=True):
        pose = _points(pose_, skeleton.n_joints, f"poses[{name!r}]")
        draw_chain(ax, pose, parents=skeleton.parents, lw=3, joints=False)
        ax.plot(pose[:, 0], pose[:, 1], "o", ms=4, mfc="#ffb000", mec="#7a5600", ls="none",
                zorder=4)  # over the bones, as draw_chain's joints
        if level is not None:
            ax.axhline(pose[skeleton.index(level), 1], color="#e5484d", lw=0.8, ls="--")
        for a, b in bones:
            mid = (pose[skeleton.index(a)] + pose[skeleton.index(b)]) / 2
            ax.text(mid[0], mid[1] + 0.6, f"{bone_elevation(skeleton, pose, a, b):.0f}°",
                    ha="center", fontsize=9, color="#a4161a")
        ax.set(title=name, aspect="equal", xlabel="x (the actor's left is +x)")
    axs[0].set_ylabel("y (up)")
    if title:
        fig.suptitle(title, fontsize=11)
    return fig


__all__ = [
    "arm_panels",
    "bone_elevation",
    "front_views",
    "gait_figure",
    "hierarchy_figure",
    "limbs",
    "planar_arm",
    "root_views",
    "strobe",
    "tree_layout",
]
