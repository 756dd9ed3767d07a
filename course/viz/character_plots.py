r"""Still figures of notebooks 09–11 (whole-body IK, retargeting, keyframes): poses side by
side, a planted-foot task from above, foot sliding, and curves over time.

Each function takes what the lecture computed (joint positions from forward kinematics,
curves from the interpolation schemes, a :class:`~course.foot_sliding.FootSliding`) and only
draws it; the maths stays in the notebook cell that calls it. The figures are built outside
pyplot, as :class:`~course.viz.chain_plots.ChainFigure`: one shows itself as a PNG when it
ends a notebook cell.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..data.registry import CMU_CM_PER_UNIT
from ..foot_sliding import FootSliding
from ..motion import Motion
from ..skeleton import Skeleton
from .chain_plots import GREEN, ChainFigure, draw_chain, panels
from .figures import BONE, GHOST, JOINT, PLANES, TARGET

HIGHLIGHT = "#ffe8a3"  # the span of a cross-fade


def pose_panels(
    panels_: Mapping[str, Sequence[tuple[Skeleton, ArrayLike]]],
    labels: Sequence[str] | None = None,
    *,
    plane: str = "xy",
    colors: Sequence[str] | None = None,
    widths: Sequence[float] | None = None,
    panel_size: tuple[float, float] = (3.0, 4.4),
    xlim: tuple[float, float] | None = None,
    legend_loc: str = "lower center",
) -> ChainFigure:
    """Poses drawn over each other, one panel per title: e.g. the wanted pose under the made one.

    Parameters
    ----------
    panels_ : title -> layers, each ``(skeleton, positions (J, 3))`` of that skeleton's
        joints; layer k of every panel is drawn in ``colors[k]``, ``widths[k]``, later layers
        on top.
    labels : one legend entry per layer, shown in the first panel; default none.
    plane : ``"xy"`` (front), ``"zy"`` (side) or ``"xz"`` (from above); the axes are labelled
        with the world axes.
    colors, widths : per layer. Default: one layer blue (3 pt); several, the first a wide
        grey ghost (6 pt) and the others thin (2.5 pt) in blue, red, amber.
    panel_size : inches per panel.
    xlim : the horizontal range of every panel; default: fit each panel's poses.
    legend_loc : where the legend goes in the first panel (matplotlib's ``loc``).

    Returns
    -------
    The :class:`~course.viz.chain_plots.ChainFigure`; ``fig.axes`` in the order of the
    panels, sharing the height axis; each pose is one line (``Axes.lines``, NaN between bones).
    """
    n_layers = {len(layers) for layers in panels_.values()}
    if len(n_layers) != 1 or 0 in n_layers:
        raise ValueError(f"panels_: expected the same number (> 0) of layers in every panel, "
                         f"got {sorted(n_layers)}")
    if plane not in PLANES:
        raise ValueError(f"plane: expected one of {sorted(PLANES)}, got {plane!r}")
    (n,) = n_layers
    if labels is not None and len(labels) != n:
        raise ValueError(f"labels: expected one per layer ({n}), got {len(labels)}")
    colors = colors or ((BONE,) if n == 1 else (GHOST, BONE, TARGET, JOINT)[:n])
    widths = widths or ((3.0,) if n == 1 else (6.0,) + (2.5,) * (n - 1))
    fig, axs = panels(len(panels_), sharey=True,
                      figsize=(panel_size[0] * len(panels_) + 1.0, panel_size[1]))
    a, b = ("xyz"[k] for k in PLANES[plane])
    for k, (ax, (title, layers)) in enumerate(zip(axs, panels_.items(), strict=True)):
        for i, (skeleton, positions) in enumerate(layers):
            p = np.asarray(positions, dtype=np.float64)
            if p.shape != (skeleton.n_joints, 3):
                raise ValueError(f"panels_[{title!r}][{i}]: expected positions of shape "
                                 f"({skeleton.n_joints}, 3), got {p.shape}")
            draw_chain(ax, p, parents=skeleton.parents, plane=plane, color=colors[i],
                       lw=widths[i], joints=False,
                       label=labels[i] if labels is not None and k == 0 else None)
        ax.set(title=title, xlabel=a, aspect="equal")
        if xlim is not None:
            ax.set_xlim(*xlim)
        ax.title.set_fontsize(10)
    axs[0].set_ylabel(f"{b} (up)" if b == "y" else b)
    if labels is not None:
        axs[0].legend(frameon=False, fontsize=8, loc=legend_loc)
    return fig


def sliding_speeds(runs: Mapping[str, FootSliding], foot: int = 0,
                   colors: Sequence[str] | None = None) -> ChainFigure:
    """A foot's sliding speed (cm/s) over time while in contact, one line per clip.

    Parameters
    ----------
    runs : label -> :func:`~course.foot_sliding.foot_sliding` of a clip.
    foot : which foot, an index into each run's ``feet``.
    colors : one per run; default grey, red, blue, amber.

    Returns
    -------
    The ``ChainFigure``: the step from frame f to f + 1 drawn at time (f + 1) dt, gaps where
    the foot is not in contact at both frames.
    """
    colors = colors or (GHOST, TARGET, BONE, JOINT)
    fig, (ax,) = panels(figsize=(10, 3.4))
    for (label, s), color in zip(runs.items(), colors, strict=False):
        t = np.arange(1, len(s.steps_cm) + 1) * s.frame_time
        ax.plot(t, s.speed_cm_per_s[:, foot], color=color, label=label)
    feet = " / ".join(dict.fromkeys(s.feet[foot] for s in runs.values()))
    ax.set(xlabel="time (s)", ylabel="cm/s", title=f"{feet}: sliding speed during contacts")
    ax.legend(frameon=False, fontsize=8)
    return fig


# --------------------------------------------------------------------------- 09: whole-body IK
def planted_foot_task(
    hips: ArrayLike,
    hand: ArrayLike,
    target: ArrayLike,
    foot: ArrayLike,
    iterations: Mapping[str, ArrayLike],
    *,
    title: str = "seen from above",
) -> ChainFigure:
    """A clip solved with one foot planted: from above, and the solver's iterations per frame.

    Parameters
    ----------
    hips, hand, target : array_like, shape (F, 3)
        Per frame: the root (hips) and the end effector after IK, and its target.
    foot : array_like, shape (3,)
        Where the planted foot stands.
    iterations : label -> (F,) iterations per frame, e.g. cold and warm starts (the last drawn
        on top, in blue; the others grey).
    title : of the left panel.

    Returns
    -------
    The ``ChainFigure``: left, x against z with an equal aspect (hips blue, hand amber, target
    dashed red, foot a green triangle); right, the iterations against the frame.
    """
    h, e, t = (np.asarray(a, dtype=np.float64) for a in (hips, hand, target))
    f = np.asarray(foot, dtype=np.float64)
    if not (h.ndim == 2 and h.shape[1] == 3 and e.shape == t.shape == h.shape and f.shape == (3,)):
        raise ValueError(f"hips, hand, target: expected (F, 3) each and foot (3,), got "
                         f"{h.shape}, {e.shape}, {t.shape}, {f.shape}")
    fig, (top, its) = panels(2, figsize=(11, 4))
    top.plot(h[:, 0], h[:, 2], color=BONE, lw=2, label="hips (IK)")
    top.plot(e[:, 0], e[:, 2], color=JOINT, lw=4, label="right hand (IK)")
    top.plot(t[:, 0], t[:, 2], "--", color=TARGET, lw=1, label="target")
    top.plot(f[0], f[2], "^", color=GREEN, ms=10, ls="none", label="planted left foot")
    top.set(xlabel="x", ylabel="z", aspect="equal", title=title)
    top.legend(fontsize=8)
    for k, (label, n) in enumerate(iterations.items()):
        last = k == len(iterations) - 1
        its.plot(np.asarray(n), color=BONE if last else GHOST, lw=1.5 if last else 1, label=label)
    its.set(xlabel="frame", ylabel="iterations", title="iterations per frame")
    its.legend()
    return fig


# --------------------------------------------------------------------------- 11: keyframes
KNOT_COLORS = {"time": TARGET, "uniform": "#4a5561", "centripetal": GREEN}
SCHEME_LINES = ("#4a5561", BONE, TARGET)  # linear + SLERP, cubic + SQUAD, Catmull-Rom + SQUAD
KEY_DOT = "#f08c3a"
# each scheme its own dash and marker too, later ones drawn thinner on top: two schemes with
# nearly the same error (cubic and Catmull-Rom) stay visible as two lines, not one
SCHEME_STYLES = (("o", "-", 2.2), ("s", "--", 1.6), ("^", ":", 1.4))


def _key_lines(ax: Any, key_times: ArrayLike) -> None:
    for x in np.asarray(key_times, dtype=np.float64):
        ax.axvline(x, color="#c9d1da", ls=":", lw=0.8)


def knots_figure(t: ArrayLike, velocities: Mapping[str, ArrayLike], key_times: ArrayLike,
                 paths: Mapping[str, ArrayLike], points: ArrayLike) -> ChainFigure:
    """Catmull–Rom with other knots: velocities over time at uneven keys, and 2D paths.

    Parameters
    ----------
    t : array_like, shape (N,)
        Times of ``velocities``.
    velocities : knots name (``"time"``, ``"uniform"``, ``"centripetal"``) -> (N,) velocity.
    key_times : array_like, shape (K,)
        Drawn as dotted verticals.
    paths : knots name -> (M, 2) points of a 2D curve through ``points`` (K2, 2) (orange dots).

    Returns
    -------
    The ``ChainFigure``, two panels; a curve's legend entry is ``knots="<name>"``.
    """
    fig, (left, right) = panels(2, figsize=(11, 3.4))
    for name, v in velocities.items():
        left.plot(t, v, color=KNOT_COLORS.get(name, BONE), label=f'knots="{name}"')
    _key_lines(left, key_times)
    left.set(xlabel="t", ylabel="velocity p'(t)", title="Catmull–Rom velocity, uneven keys")
    left.legend(frameon=False)
    for name, path in paths.items():
        xy = np.asarray(path, dtype=np.float64)
        right.plot(xy[:, 0], xy[:, 1], color=KNOT_COLORS.get(name, BONE), label=f'knots="{name}"')
    right.plot(*np.asarray(points, dtype=np.float64).T, "o", color=KEY_DOT)
    right.set(title="2D keys bunched up: a loop with uniform knots", aspect="equal")
    right.legend(frameon=False)
    return fig


def angular_speeds(times: ArrayLike, speeds: Mapping[str, ArrayLike], key_times: ArrayLike, *,
                   title: str = "", xlim: tuple[float, float] | None = None) -> ChainFigure:
    """Angular speeds over time: the first curve wide and grey (the reference, e.g. the
    capture), the others thin, in dark grey, red, blue; keys as dotted verticals.

    Parameters
    ----------
    times : array_like, shape (F,)
        Sample times; ``speeds`` are between samples (as :func:`course.keyframes.
        angular_velocity` gives them) and drawn at the midpoints.
    speeds : label -> (F - 1,) angular speed, degrees per second.
    """
    t = np.asarray(times, dtype=np.float64)
    mid = (t[1:] + t[:-1]) / 2
    fig, (ax,) = panels(figsize=(11, 3.4))
    colors = (GHOST, "#4a5561", TARGET, BONE)
    for k, (label, w) in enumerate(speeds.items()):
        ax.plot(mid, np.asarray(w), color=colors[k % len(colors)], lw=3 if k == 0 else 1.6,
                label=label)
    _key_lines(ax, key_times)
    ax.set(xlabel="t (s)", ylabel="angular speed (deg/s)", title=title)
    if xlim is not None:
        ax.set_xlim(*xlim)
    ax.legend(frameon=False, ncol=3, loc="upper right")
    return fig


def keyframe_errors(ks: Sequence[int], errors: Mapping[str, Sequence[float]], times: ArrayLike,
                    over_time: Mapping[str, ArrayLike], key_times: ArrayLike, k: int
                    ) -> ChainFigure:
    """A clip rebuilt from keys: mean error against the key spacing, and over time for one.

    Parameters
    ----------
    ks : key spacings (keep every k-th frame).
    errors : scheme -> mean error (cm) per spacing in ``ks``; drawn log-log.
    times : array_like, shape (F,)
    over_time : scheme -> (F,) error (cm) per frame at the spacing ``k``.
    key_times : the times of the keys at that spacing, marked on the time axis.
    """
    fig, (left, right) = panels(2, figsize=(11, 3.4))
    styles = list(zip(SCHEME_LINES, SCHEME_STYLES, strict=True))
    for z, ((name, e), (color, (marker, dash, lw))) in enumerate(zip(errors.items(), styles,
                                                                      strict=False)):
        left.plot(ks, e, marker=marker, ls=dash, lw=lw, color=color, label=name, zorder=2 + z,
                  ms=7 - 1.5 * z, mfc="none" if z else color)
    left.set(xlabel="k (keep every k-th frame)", ylabel="mean joint error (cm)", xscale="log",
             yscale="log", title="Error vs key spacing")
    left.set_xticks(list(ks), labels=[str(k_) for k_ in ks])
    left.minorticks_off()
    left.legend(frameon=False)
    for z, ((name, err), (color, (_, dash, lw))) in enumerate(zip(over_time.items(), styles,
                                                                   strict=False)):
        right.plot(times, err, color=color, ls=dash, lw=lw * 0.7, label=name, zorder=2 + z)
    kt = np.asarray(key_times, dtype=np.float64)
    right.plot(kt, np.zeros(len(kt)), "|", ms=12, color=KEY_DOT, label="keys")
    right.legend(frameon=False, fontsize=8)
    right.set(xlabel="t (s)", ylabel="error (cm)", title=f"k = {k}: zero at the keys, "
              "largest between")
    return fig


def blend_figure(runs: Mapping[str, tuple[Motion, FootSliding]], toe: str,
                 fade: tuple[int, int], window: tuple[int, int],
                 cm_per_unit: float = CMU_CM_PER_UNIT) -> ChainFigure:
    """Concatenated clips: one toe's path from above, and the feet's sliding near the seam.

    Parameters
    ----------
    runs : label -> (the concatenated clip, its :func:`~course.foot_sliding.foot_sliding`);
        drawn in dark grey, red, blue.
    toe : the joint whose path is drawn (metres, z against x), thick during the cross-fade.
    fade : frames [start, stop) of the cross-fade, shaded on the right.
    window : frames [start, stop) drawn on the right: the sliding speed summed over the feet
        (cm/s) per step, gaps where no foot is in contact.
    """
    fig, (left, right) = panels(2, figsize=(11, 3.6))
    frames = np.arange(*window)
    for (label, (clip, sliding)), color in zip(runs.items(), SCHEME_LINES[::2] + (BONE,),
                                               strict=False):
        p = clip.forward_kinematics()[0][:, clip.skeleton.index(toe)] * cm_per_unit / 100
        left.plot(p[:, 2], p[:, 0], color=color, lw=1.2, label=label)
        left.plot(p[fade[0]:fade[1], 2], p[fade[0]:fade[1], 0], color=color, lw=4, alpha=0.5)
        s = sliding.speed_cm_per_s[frames]
        right.plot(frames, np.where(np.isnan(s).all(axis=1), np.nan, np.nansum(s, axis=1)),
                   color=color, label=label)
    left.set(xlabel="z (m)", ylabel="x (m)", title=f"{toe} from above (thick: the cross-fade)")
    right.axvspan(*fade, color=HIGHLIGHT, alpha=0.6, label="cross-fade")
    right.set(xlabel="frame", ylabel="foot sliding (cm/s)", title="Feet in contact: sliding")
    left.legend(frameon=False)
    right.legend(frameon=False)
    return fig
