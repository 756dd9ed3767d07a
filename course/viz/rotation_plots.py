r"""Still figures of notebook 01 (rotations): frames turned step by step, the gimbal rings, the
smallest singular value of the Euler-angle Jacobian, and the speed of LERP / NLERP / SLERP.

Each function takes what the lecture computed (matrices, singular values, quaternion paths)
and only draws it; the maths stays in the notebook cell that calls it. The figures are built
outside pyplot, in the notebooks' style (:func:`course.viz.chain_plots.panels`), and show in a
notebook cell through their PNG repr.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .. import rotations as rot
from .._typing import Array
from .chain_plots import ChainFigure, panels, snapshot_row
from .figures import METHOD_COLORS, GimbalFigure, draw_frame

INTERPOLATION_COLORS = ("#f08c3a", "#8e6bd8", "#2bb673")  # LERP, NLERP, SLERP in the notebook


def frame_steps(rows: Mapping[str, Sequence[ArrayLike]], *, title: str = "",
                labels: Sequence[str] | None = None) -> ChainFigure:
    """Coordinate frames after each turn of a sequence, one row per sequence.

    Parameters
    ----------
    rows : name -> the rotation matrices ``(3, 3)`` after 0, 1, ... turns (the same count in
        every row). A panel draws the frame's axes (x red, y green, z blue, y up) over the
        faint world frame.
    title : the figure's title.
    labels : one panel title per column; default "start", "after turn k", and for the last
        column "after both: <name>" (or "after all", for more than two turns; the name up
        to a colon).

    Returns
    -------
    The ``Figure``; its axes are ``fig.axes`` in row-major order.
    """
    mats = {name: [np.asarray(R, dtype=np.float64) for R in seq] for name, seq in rows.items()}
    n_cols = {len(seq) for seq in mats.values()}
    if len(n_cols) != 1:
        raise ValueError(f"rows: every row needs the same number of frames, got {sorted(n_cols)}")
    (n,) = n_cols
    if labels is not None and len(labels) != n:
        raise ValueError(f"labels: expected {n} column titles, got {len(labels)}")
    fig, axs = panels(n, nrows=len(mats), figsize=(3.0 * n, 2.8 * len(mats)), projection="3d")
    for r, (name, seq) in enumerate(mats.items()):
        default = ["start"] + [f"after turn {k}" for k in range(1, n - 1)] + \
                  [f"after {'both' if n == 3 else 'all'}: {name.split(':')[0]}"]
        for c, R in enumerate(seq):
            ax = axs[r * n + c]
            draw_frame(ax, np.eye(3), alpha=0.22, lw=1.5, labels=())  # the world frame, faint
            draw_frame(ax, R)
            ax.set(xlim=(-0.75, 0.75), ylim=(-0.75, 0.75), zlim=(-0.75, 0.75))
            ax.set_axis_off()
            ax.view_init(elev=20, azim=35)
            ax.set_title((labels or default)[c], fontsize=10)
    if title:
        fig.suptitle(title, fontsize=12)
    return fig


def gimbal_panels(order: str, poses: Mapping[tuple[float, float, float], str], *,
                  width: int = 340) -> Any:
    """The gimbal rings of Euler ``order`` for a few poses, side by side with captions.

    Parameters
    ----------
    order : an Euler order string (``"XYZ"``, ...).
    poses : (a, b, c) in **degrees** -> caption; each panel is a still :class:`GimbalFigure`.
    width : pixel width of each picture.

    Returns
    -------
    An ``IPython.display.HTML`` row of figures (captioned "(a, b, c) = ...°, <caption>"), by
    :func:`course.viz.chain_plots.snapshot_row`.
    """
    return snapshot_row([(f"(a, b, c) = {tuple(abc)}°, {caption}",
                          GimbalFigure(order, np.radians(abc)).png())
                         for abc, caption in poses.items()], width=width)


def _is_proper_euler(order: str) -> bool:
    return order[0].lower() == order[2].lower()


def gimbal_lock_curves(b: ArrayLike, smallest: Mapping[str, ArrayLike]) -> ChainFigure:
    r"""The smallest singular value of the Euler-angle Jacobian against the middle angle.

    Parameters
    ----------
    b : (N,) middle angles in radians.
    smallest : Euler order -> (N,) measured smallest singular value of
        :math:`J = \partial\,\mathrm{vec}(R)/\partial(a, b, c)` at each ``b``.

    Draws each measured curve (thick), the theory :math:`\sqrt{2(1-|\omega_1\cdot\omega_3|)}`
    dotted on top (:math:`|\sin b|` for Tait-Bryan orders, :math:`|\cos b|` for proper Euler
    orders such as ``"ZYZ"``), and an arrow "lock" at each zero inside the range.

    Returns
    -------
    The ``Figure`` (one axes; x in degrees).
    """
    b = np.asarray(b, dtype=np.float64)
    deg = np.degrees(b)
    fig, (ax,) = panels(1, figsize=(8, 3.4))
    dotted = {"color": "#2b3440", "lw": 1, "ls": (0, (2, 3))}
    for k, (order, values) in enumerate(smallest.items()):
        color = METHOD_COLORS[k % len(METHOD_COLORS)]
        cos_13 = np.abs(np.cos(b)) if _is_proper_euler(order) else np.abs(np.sin(b))
        ax.plot(deg, np.asarray(values, dtype=np.float64), color=color, lw=4, alpha=0.75,
                label=f"{order} (measured)")
        ax.plot(deg, np.sqrt(2 * (1 - cos_13)), **dotted)
        locks = (0.0, -180.0, 180.0) if _is_proper_euler(order) else (-90.0, 90.0)
        for lock in locks:
            if deg.min() < lock < deg.max():
                ax.annotate("lock", (lock, 0), (lock, 0.22), ha="center", color=color,
                            arrowprops={"arrowstyle": "->", "color": color})
    ax.plot([], [], **dotted, label=r"$\sqrt{2(1-|\omega_1\cdot\omega_3|)}$")
    ax.set(xlabel="middle angle b (degrees)", ylabel=r"smallest singular value of $J$",
           xticks=range(-180, 181, 45), title="Gimbal lock: the Jacobian loses rank "
           "(Tait-Bryan at ±90°, proper Euler at 0°, ±180°)")
    ax.legend(frameon=False, loc="upper right")
    return fig


def interpolation_speed(t: ArrayLike, paths: Mapping[str, ArrayLike],
                        lerp: ArrayLike | None = None) -> ChainFigure:
    r"""How three interpolations of one turn :math:`q_0 \to q_1` progress over ``t``.

    Parameters
    ----------
    t : (N,) increasing parameters, from 0 to 1.
    paths : name -> (N, 4) unit quaternions along the path (``path[0]`` = :math:`q_0`,
        ``path[-1]`` = :math:`q_1`). The first path is drawn thickest, so a path that
        coincides with it (LERP as a rotation = NLERP) stays visible under the next.
    lerp : optional (N, 4) raw LERP quaternions: a third panel shows their length
        :math:`|q(t)|` against the unit sphere.

    Draws the angle turned minus :math:`t` times the total (ahead of or behind constant speed)
    and the angular speed (step angle over step in ``t``, at the middle of each step).

    Returns
    -------
    The ``Figure`` (2 or 3 axes, in that order).
    """
    t = np.asarray(t, dtype=np.float64)
    fig, axs = panels(2 if lerp is None else 3, figsize=(8, 3.6) if lerp is None else (12, 3.6))
    for k, (name, p) in enumerate(paths.items()):
        q = np.asarray(p, dtype=np.float64)
        color, lw = INTERPOLATION_COLORS[k % 3], 5 if k == 0 else 2.5
        total = rot.quat_angle(q[0], q[-1])
        axs[0].plot(t, np.degrees(rot.quat_angle(q[0], q) - t * total), color=color, lw=lw,
                    label=name)
        steps = rot.quat_angle(q[:-1], q[1:]) / np.diff(t)
        axs[1].plot((t[1:] + t[:-1]) / 2, np.degrees(steps), color=color, lw=lw, label=name)
    axs[0].set(xlabel="t", ylabel="angle turned − t × total (deg)",
               title="Ahead of (+) or behind (−) constant speed")
    axs[1].set(xlabel="t", ylabel="angular speed (deg per unit t)", title="How fast")
    axs[0].legend(frameon=False)
    if lerp is not None:
        norm: Array = np.linalg.norm(np.asarray(lerp, dtype=np.float64), axis=-1)
        axs[2].plot(t, norm, color=INTERPOLATION_COLORS[0], lw=2.5)
        axs[2].axhline(1, color="k", lw=0.9, ls="--")
        axs[2].set(xlabel="t", ylabel="|q(t)|", title="LERP leaves the unit sphere",
                   ylim=(min(0.5, norm.min() - 0.05), 1.05))
    return fig


__all__ = ["frame_steps", "gimbal_lock_curves", "gimbal_panels", "interpolation_speed"]
