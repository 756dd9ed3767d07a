"""Matplotlib figures: chains in 2D/3D, IK convergence, rotation pictures, joint-angle curves.

Figures that move (:class:`ChainPlot`, :class:`JointAngleFigure`, :class:`GimbalFigure`) are
built once and then redrawn by updating their artists. In 2D they blit: the static part
(axes, grid, ground) is rendered once and cached, and each update restores it and draws only
the moving artists (about 1 ms for 30 bones instead of about 40 ms for a full redraw).
Everything renders with any backend, including Agg without a display; :meth:`png` gives the
current picture for an ``ipywidgets.Image``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from numpy.typing import ArrayLike, NDArray

from .._typing import Array
from .backend import png_bytes

BONE = "#3d7dca"
JOINT = "#ffb000"
GHOST = "#a9b3be"
TARGET = "#e5484d"
TRAIL = "#d1347a"
AXIS_RGB = ("#e63946", "#2aaa52", "#2c6ee6")
METHOD_COLORS = ("#3d7dca", "#e5484d", "#2bb673", "#8e6bd8", "#f08c3a", "#4a5561")
PLANES = {"xy": (0, 1), "zy": (2, 1), "xz": (0, 2)}


def agg_figure(figsize: tuple[float, float], dpi: int = 100) -> Figure:
    """A figure outside pyplot (no inline double display, no leak in loops), drawn by Agg;
    it still displays in a notebook cell through its PNG repr."""
    fig = Figure(figsize=figsize, dpi=dpi, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def agg_canvas(fig: Figure) -> FigureCanvasAgg:
    """The Agg canvas of a figure made by :func:`agg_figure` (its pixel buffer, its blits)."""
    canvas = fig.canvas
    if not isinstance(canvas, FigureCanvasAgg):
        raise TypeError(f"expected a figure drawn by Agg, got {type(canvas).__name__}")
    return canvas


def figure_png(fig: Figure) -> bytes:
    """The figure's current canvas buffer as PNG bytes (no redraw)."""
    return png_bytes(np.asarray(agg_canvas(fig).buffer_rgba()))


class Blitter:
    """A figure's static part rendered once and cached; the moving artists (created with
    ``animated=True``, so a full draw skips them) are drawn over it on every update. In 3D
    this holds while the view stays put: the projection is computed by the cached draw."""

    def __init__(self, figure: Figure, artists: Sequence[Any]) -> None:
        self.figure = figure
        self.artists = list(artists)
        self._background: Any = None

    def full_redraw(self) -> None:
        """Render the static part and cache it (again after a change of limits or titles)."""
        canvas = agg_canvas(self.figure)
        canvas.draw()
        self._background = canvas.copy_from_bbox(self.figure.bbox)
        self.blit()

    def blit(self) -> None:
        canvas = agg_canvas(self.figure)
        if self._background is None:
            self.full_redraw()
            return
        canvas.restore_region(self._background)
        for artist in self.artists:
            artist.axes.draw_artist(artist)
        canvas.blit(self.figure.bbox)


def mpl3(p: ArrayLike) -> tuple[Array, Array, Array]:
    """World (x, y, z), y up, as matplotlib's (X, Y, Z), Z up: X = z, Y = x, Z = y. A cyclic
    permutation, so right-handed frames stay right-handed on screen."""
    p = np.asarray(p, dtype=np.float64)
    return p[..., 2], p[..., 0], p[..., 1]


def _label_3d(ax: Any) -> None:
    ax.set_xlabel("z")
    ax.set_ylabel("x")
    ax.set_zlabel("y")


def bone_xy(parents: NDArray[np.intp], pos: Array) -> Array:
    """Bone segments as one NaN-separated polyline: ``(3 (J-1), dims)``."""
    seg = np.full((3 * (len(parents) - 1), pos.shape[1]), np.nan)
    seg[0::3] = pos[parents[1:]]
    seg[1::3] = pos[1:]
    return seg


class ChainPlot:
    """A skeleton or chain drawn with matplotlib, redrawn by updating artists.

    Parameters
    ----------
    parents : (J,) parent indices.
    positions : (J, 3) joint positions (or (J, 2) in 2D).
    dims : 2 (a plane of the 3D positions, see ``plane``) or 3.
    plane : for ``dims=2``: ``"xy"`` (front view, default), ``"zy"`` (side) or ``"xz"`` (top).
    reach : half-width of the fixed view around the root; default: the total bone length
        (a chain can never leave it, so the view never needs a full redraw).
    ghost : draw this first pose faintly underneath (e.g. before IK).
    """

    def __init__(
        self,
        parents: ArrayLike,
        positions: ArrayLike,
        *,
        dims: int = 2,
        plane: str = "xy",
        reach: float | None = None,
        ghost: bool = False,
        figsize: tuple[float, float] = (5.0, 4.2),
        ax: Any = None,
    ) -> None:
        if dims not in (2, 3):
            raise ValueError(f"dims must be 2 or 3, got {dims}")
        if plane not in PLANES:
            raise ValueError(f"plane must be one of {tuple(PLANES)}, got {plane!r}")
        self.parents = np.asarray(parents, dtype=np.intp)
        self.dims, self.plane = dims, plane
        pos = self._project(positions)
        bones = np.linalg.norm(pos[1:] - pos[self.parents[1:]], axis=1)
        half = float(reach if reach is not None else max(bones.sum(), 1e-6)) * 1.08
        if ax is None:
            self.figure = agg_figure(figsize)
            ax = self.figure.add_subplot(projection="3d" if dims == 3 else None)
        else:
            self.figure = ax.figure
        self.ax = ax
        center = pos[0]
        if dims == 2:
            ax.set_xlim(center[0] - half, center[0] + half)
            ax.set_ylim(center[1] - half, center[1] + half)
            ax.set_aspect("equal")
            ax.grid(True, color="#e3e7ec", lw=0.8)
            ax.set_xlabel(plane[0])
            ax.set_ylabel(plane[1])
        else:  # positions are stored as matplotlib's (X, Y, Z) = (z, x, y): y stays up
            for setter, c in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), center, strict=True):
                setter(c - half, c + half)
            ax.set_box_aspect((1, 1, 1))
            _label_3d(ax)
            ax.view_init(elev=18, azim=35)
        if ghost:
            self._line(bone_xy(self.parents, pos), color=GHOST, lw=3, zorder=1)
        # the moving artists: drawn only by draw_artist (animated), never by a full draw
        self.bones = self._line(bone_xy(self.parents, pos), color=BONE, lw=3.5, animated=True,
                                solid_capstyle="round", zorder=3)
        self.joints = self._line(pos, ls="none", marker="o", ms=8, mfc=JOINT, mec="#7a5600",
                                 mew=0.8, animated=True, zorder=4)
        self.target = self._line(np.full((1, dims), np.nan), ls="none", marker="*", ms=15,
                                 color=TARGET, animated=True, zorder=5)
        self.trail = self._line(np.full((1, dims), np.nan), color=TRAIL, lw=1.5, alpha=0.8,
                                animated=True, zorder=2)
        self._trail_pts: list[Array] = []
        self.positions = pos
        self._blitter = Blitter(self.figure, (self.trail, self.bones, self.joints, self.target))
        self.full_redraw()

    def _project(self, positions: ArrayLike) -> Array:
        p = np.asarray(positions, dtype=np.float64)
        if p.ndim != 2 or p.shape[0] != self.parents.size or p.shape[1] not in (2, 3):
            raise ValueError(f"positions must have shape ({self.parents.size}, 3), got {p.shape}")
        if self.dims == 2:
            return p[:, list(PLANES[self.plane])] if p.shape[1] == 3 else p
        if p.shape[1] != 3:
            raise ValueError("positions must be 3D for dims=3")
        return p[:, [2, 0, 1]]

    def _line(self, pts: Array, **kw: Any) -> Any:
        if self.dims == 2:
            return self.ax.plot(pts[:, 0], pts[:, 1], **kw)[0]
        return self.ax.plot(pts[:, 0], pts[:, 1], pts[:, 2], **kw)[0]

    @staticmethod
    def _set(artist: Any, pts: Array) -> None:
        if pts.shape[1] == 2:
            artist.set_data(pts[:, 0], pts[:, 1])
        else:
            artist.set_data_3d(pts[:, 0], pts[:, 1], pts[:, 2])

    def full_redraw(self) -> None:
        """Render everything and cache the static background (also after a resize)."""
        self._blitter.full_redraw()

    def update(
        self,
        positions: ArrayLike,
        target: ArrayLike | None = None,
        *,
        trail: bool = False,
    ) -> None:
        """Move the chain (and the target); restore the cached background and draw only the
        moving artists, in 2D and in 3D (the view is fixed). ``trail=True`` appends the end
        effector (last joint) to the trail."""
        pos = self._project(positions)
        self.positions = pos
        self._set(self.bones, bone_xy(self.parents, pos))
        self._set(self.joints, pos)
        if target is not None:
            t = np.asarray(target, dtype=np.float64).reshape(-1, 3)
            self._set(self.target, t[:, list(PLANES[self.plane])] if self.dims == 2
                      else t[:, [2, 0, 1]])
        if trail:
            self._trail_pts.append(pos[-1])
            self._set(self.trail, np.array(self._trail_pts))
        self._blitter.blit()

    def clear_trail(self) -> None:
        self._trail_pts.clear()
        self._set(self.trail, np.full((1, self.dims), np.nan))

    def data_to_pixels(self, points: ArrayLike) -> Array:
        """Pixel (column, row) of plotted 2D points in :meth:`image`, row 0 at the top."""
        xy = self.ax.transData.transform(np.asarray(points, dtype=np.float64).reshape(-1, 2))
        return np.column_stack([xy[:, 0], self.figure.bbox.height - xy[:, 1]])

    def image(self) -> NDArray[np.uint8]:
        """The current picture ``(H, W, 4)`` uint8."""
        return np.array(agg_canvas(self.figure).buffer_rgba(), dtype=np.uint8)

    def png(self) -> bytes:
        return figure_png(self.figure)


def convergence_plot(
    residuals: Mapping[str, ArrayLike],
    *,
    tol: float | None = None,
    ax: Any = None,
    title: str = "IK convergence",
) -> Any:
    """Residual ``|e - t|`` against iteration, log scale, one line per method.

    Parameters
    ----------
    residuals : method name -> residual per iteration ``(n_k,)`` (iteration 0 = start).
    tol : draw the tolerance as a dashed line.
    """
    if ax is None:
        ax = agg_figure((5.5, 3.6)).add_subplot()
    floor = np.finfo(float).eps
    for i, (method, r) in enumerate(residuals.items()):
        r = np.asarray(r, dtype=np.float64).reshape(-1)
        ax.semilogy(np.arange(r.size), np.maximum(r, floor), marker="o", ms=3, lw=1.8,
                    color=METHOD_COLORS[i % len(METHOD_COLORS)], label=f"{method} ({r.size - 1})")
    if tol is not None:
        ax.axhline(tol, color="#4a5561", ls="--", lw=1, label=f"tol = {tol:g}")
    ax.set_xlabel("iteration")
    ax.set_ylabel("residual  |e - t|")
    ax.set_title(title)
    ax.grid(True, which="both", color="#e3e7ec", lw=0.6)
    ax.legend(frameon=False, fontsize="small")
    return ax


def _decade(x: float, up: bool, shift: int = 0) -> float:
    """The power of ten at or above (``up``) or below ``x``, times ``10**shift``."""
    exponent = np.log10(max(x, np.finfo(float).tiny))
    return float(10.0 ** (int(np.ceil(exponent) if up else np.floor(exponent)) + shift))


class ConvergenceFigure:
    """One solve's residual ``|e - t|`` against iteration (log scale) and the tolerance, for a
    control that solves again on every event.

    The axes change in coarse steps only (x: 10, 20, 50, 100 ... iterations; y: whole decades,
    from a thousandth of the tolerance up), so nearly every update just blits the curve over
    the cached axes; a change of those limits redraws the figure once.
    """

    def __init__(self, *, figsize: tuple[float, float] = (4.6, 3.0)) -> None:
        self.figure = agg_figure(figsize)
        self.ax = self.figure.add_subplot()
        self.ax.set_yscale("log")
        self.ax.set_xlabel("iteration")
        self.ax.set_ylabel("residual  |e - t|")
        self.ax.grid(True, which="both", color="#e3e7ec", lw=0.6)
        self.curve = self.ax.plot([], [], marker="o", ms=3, lw=1.8, color=METHOD_COLORS[0],
                                  animated=True)[0]
        self.tol_line = self.ax.axhline(1.0, color="#4a5561", ls="--", lw=1, animated=True)
        self.label = self.ax.text(0.97, 0.95, "", transform=self.ax.transAxes, ha="right",
                                  va="top", fontsize="small", animated=True)
        self.limits: tuple[float, float, float] | None = None  # (x max, y min, y max)
        self._blitter = Blitter(self.figure, (self.tol_line, self.curve, self.label))

    def update(self, residuals: ArrayLike, tol: float, label: str = "") -> None:
        """Show ``residuals (n,)`` (iteration 0 = the start) against the tolerance ``tol``."""
        r = np.maximum(np.asarray(residuals, dtype=np.float64).reshape(-1), np.finfo(float).eps)
        steps = max(r.size - 1, 1)
        limits = (
            next(float(m * 10**k) for k in range(1, 9) for m in (1, 2, 5) if m * 10**k >= steps),
            min(_decade(tol, up=False, shift=-3), _decade(r.min(), up=False)),
            _decade(max(r.max(), tol), up=True),
        )
        if self.limits is not None:  # limits that still fit, and are not far off, are kept
            x_max, y_min, y_max = self.limits
            limits = (x_max if limits[0] <= x_max < 5 * limits[0] else limits[0],
                      y_min if limits[1] >= y_min > 1e-4 * limits[1] else limits[1],
                      y_max if limits[2] <= y_max < 1e3 * limits[2] else limits[2])
        self.curve.set_data(np.arange(r.size), r)
        self.tol_line.set_ydata([tol, tol])
        self.label.set_text(label)
        if limits != self.limits:
            self.limits = limits
            self.ax.set_xlim(-0.02 * limits[0], limits[0])
            self.ax.set_ylim(limits[1], limits[2])
            self._blitter.full_redraw()
        else:
            self._blitter.blit()

    def png(self) -> bytes:
        return figure_png(self.figure)


def draw_frame(
    ax: Any,
    R: ArrayLike,
    origin: ArrayLike = (0.0, 0.0, 0.0),
    *,
    length: float = 1.0,
    labels: Sequence[str] = ("x", "y", "z"),
    alpha: float = 1.0,
    lw: float = 2.5,
) -> list[Any]:
    """Draw the axis triad of rotation ``R (3, 3)`` (its columns) on a 3D axes: x red, y green,
    z blue, y up (see :func:`mpl3`). Returns the three lines."""
    R = np.asarray(R, dtype=np.float64).reshape(3, 3)
    o = np.asarray(origin, dtype=np.float64)
    lines = []
    for a in range(3):
        tip = o + length * R[:, a]
        (line,) = ax.plot(*mpl3(np.stack([o, tip])), color=AXIS_RGB[a], lw=lw, alpha=alpha,
                          solid_capstyle="round")
        if labels:
            ax.text(*mpl3(1.08 * tip - 0.08 * o), labels[a], color=AXIS_RGB[a], alpha=alpha)
        lines.append(line)
    return lines


def _sphere_axes(figsize: tuple[float, float] = (4.6, 4.4)) -> Any:
    ax = agg_figure(figsize).add_subplot(projection="3d")
    for s in (ax.set_xlim, ax.set_ylim, ax.set_zlim):
        s(-1.05, 1.05)
    ax.set_box_aspect((1, 1, 1))
    _label_3d(ax)
    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
        axis.set_ticklabels([])
    ax.view_init(elev=20, azim=35)
    return ax


def _ring(axis: int, radius: float, n: int = 97) -> Array:
    """A circle of ``radius`` in the plane perpendicular to world axis ``axis``: (n, 3)."""
    s = np.linspace(0, 2 * np.pi, n)
    u, v = [a for a in range(3) if a != axis]
    pts = np.zeros((n, 3))
    pts[:, u], pts[:, v] = radius * np.cos(s), radius * np.sin(s)
    return pts


class GimbalFigure:
    """The three gimbal rings of an Euler order, nested outer to inner.

    For an intrinsic order ``"ABC"`` (``R = R_A R_B R_C``) the outer ring turns about A and
    carries the middle ring (about B), which carries the inner ring (about C): ring k is drawn
    rotated by the product of the first k elementary rotations. An extrinsic order ``"abc"``
    is the intrinsic ``"CBA"`` with the angles reversed. At gimbal lock (the middle angle
    +-90 deg for Tait-Bryan orders, 0 or 180 deg for proper Euler orders) the outer and inner
    rings lie in one plane: one degree of freedom is lost.
    """

    RADII = (1.0, 0.82, 0.64)

    def __init__(self, order: str = "XYZ", angles: ArrayLike = (0.0, 0.0, 0.0)) -> None:
        self.ax = _sphere_axes()
        self.figure = self.ax.figure
        self.rings = [self.ax.plot([], [], [], lw=4, color=AXIS_RGB[0], animated=True)[0]
                      for _ in range(3)]
        self.frame = [self.ax.plot([], [], [], lw=2.5, color=c, animated=True)[0]
                      for c in AXIS_RGB]
        self._blitter = Blitter(self.figure, (*self.rings, *self.frame))
        self._order: str | None = None
        self.update(angles, order)

    def update(self, angles: ArrayLike, order: str) -> None:
        from course.rotations import matrix_from_axis_angle

        a = np.asarray(angles, dtype=np.float64).reshape(3)
        title = order
        if order.islower():
            order, a = order[::-1].upper(), a[::-1]
        R = np.eye(3)
        for k, (letter, angle) in enumerate(zip(order, a, strict=True)):
            axis = "XYZ".index(letter)
            R = R @ matrix_from_axis_angle(np.eye(3)[axis], angle)
            ring = _ring(axis, self.RADII[k]) @ R.T
            self.rings[k].set_data_3d(*mpl3(ring))
            self.rings[k].set_color(AXIS_RGB[axis])
        for axis, line in enumerate(self.frame):
            line.set_data_3d(*mpl3(np.stack([np.zeros(3), 0.55 * R[:, axis]])))
        if title != self._order:  # the title is part of the cached background
            self._order = title
            self.ax.set_title(f"gimbal rings, order {title}", fontsize="medium")
            self._blitter.full_redraw()
        else:
            self._blitter.blit()

    def png(self) -> bytes:
        return figure_png(self.figure)


class SlerpArcFigure:
    """The path of ``R(t) v`` on the unit sphere for SLERP and NLERP between ``q0`` and ``q1``,
    with ticks at equal steps of t. SLERP's ticks are evenly spaced (constant angular speed);
    NLERP's bunch in the middle (LERP draws NLERP's path: as a rotation q/|q| is q). A diamond
    marks the current ``t``.

    Built once; :meth:`set_rotations` and :meth:`set_t` move the paths and markers by
    blitting over the cached sphere (``animated=False`` gives a plain figure for display).
    """

    INTERPOLATIONS = ("nlerp", "slerp")

    def __init__(
        self,
        q0: ArrayLike,
        q1: ArrayLike,
        *,
        vector: ArrayLike = (0.0, 0.0, 1.0),
        n: int = 9,
        methods: Sequence[str] = ("nlerp", "slerp"),
        t: float | None = None,
        animated: bool = True,
    ) -> None:
        for method in methods:
            if method not in self.INTERPOLATIONS:
                raise ValueError(f"methods must be among {self.INTERPOLATIONS}, got {method!r}")
        vec = np.asarray(vector, dtype=np.float64)
        self.vector = vec / np.linalg.norm(vec)
        self.methods = tuple(methods)
        self.ticks = np.linspace(0, 1, n)
        self.ax = _sphere_axes()
        self.figure: Figure = self.ax.figure
        u, v = np.mgrid[0 : 2 * np.pi : 25j, 0 : np.pi : 13j]
        self.ax.plot_wireframe(np.cos(u) * np.sin(v), np.sin(u) * np.sin(v), np.cos(v),
                               color="#dde2e8", lw=0.5)
        self.paths, self.marks, self.current = [], [], []
        for i, method in enumerate(self.methods):
            color = METHOD_COLORS[i]
            # earlier methods wider and hollow underneath, so coinciding paths stay visible
            self.paths.append(self.ax.plot([], [], [], color=color, lw=4.5 - 2 * i, alpha=0.9,
                                           label=method.upper(), animated=animated)[0])
            self.marks.append(self.ax.plot([], [], [], ls="none", marker="o", ms=10 - 4 * i,
                                           color=color, mfc="white" if i == 0 else color, mew=2,
                                           animated=animated)[0])
            self.current.append(self.ax.plot([], [], [], ls="none", marker="D", ms=9,
                                             color=color, animated=animated)[0])
        self.ax.legend(loc="upper left", frameon=False)
        self.ax.set_title(f"R(t) v at t = 0, 1/{n - 1}, ..., 1", fontsize="medium")
        self._blitter = (Blitter(self.figure, (*self.paths, *self.marks, *self.current))
                         if animated else None)
        self.t = t
        self.set_rotations(q0, q1)

    def _rotated(self, method: str, t: Array) -> Array:
        from course.rotations import nlerp, quat_rotate, slerp

        interp = slerp if method == "slerp" else nlerp
        return quat_rotate(interp(self.q0, self.q1, t), self.vector)

    def set_rotations(self, q0: ArrayLike, q1: ArrayLike) -> None:
        """New end rotations ``q0, q1 (4,)``: the paths and ticks move."""
        self.q0 = np.asarray(q0, dtype=np.float64)
        self.q1 = np.asarray(q1, dtype=np.float64)
        dense = np.linspace(0, 1, 121)
        for method, path, marks in zip(self.methods, self.paths, self.marks, strict=True):
            path.set_data_3d(*mpl3(self._rotated(method, dense)))
            marks.set_data_3d(*mpl3(self._rotated(method, self.ticks)))
        self.set_t(self.t)

    def set_t(self, t: float | None) -> None:
        """Mark ``R(t) v`` for each method (``None``: no marker)."""
        self.t = t
        for method, marker in zip(self.methods, self.current, strict=True):
            m = (self._rotated(method, np.array([t])) if t is not None
                 else np.full((1, 3), np.nan))
            marker.set_data_3d(*mpl3(m))
        if self._blitter is not None:
            self._blitter.blit()
        else:
            self.figure.canvas.draw()

    def png(self) -> bytes:
        return figure_png(self.figure)


def slerp_arc_figure(
    q0: ArrayLike,
    q1: ArrayLike,
    *,
    vector: ArrayLike = (0.0, 0.0, 1.0),
    n: int = 9,
    methods: Sequence[str] = ("nlerp", "slerp"),
    t: float | None = None,
) -> Figure:
    """A still :class:`SlerpArcFigure` (for a notebook cell): the figure itself."""
    return SlerpArcFigure(q0, q1, vector=vector, n=n, methods=methods, t=t,
                          animated=False).figure


class JointAngleFigure:
    """Joint-angle curves over a clip (degrees against seconds) with a moving time cursor.

    Parameters
    ----------
    angles : (F, K) angles in radians (e.g. the Euler channels of a few joints).
    frame_time : seconds per frame.
    labels : K curve labels.
    """

    def __init__(
        self,
        angles: ArrayLike,
        frame_time: float,
        labels: Sequence[str],
        *,
        figsize: tuple[float, float] = (6.0, 3.2),
    ) -> None:
        a = np.degrees(np.asarray(angles, dtype=np.float64))
        if a.ndim != 2 or a.shape[1] != len(labels):
            raise ValueError(f"angles must have shape (F, {len(labels)}), got {a.shape}")
        self.times = np.arange(a.shape[0]) * frame_time
        self.figure = agg_figure(figsize)
        self.ax = self.figure.add_subplot()
        for k, label in enumerate(labels):
            self.ax.plot(self.times, a[:, k], lw=1.4, label=label,
                         color=METHOD_COLORS[k % len(METHOD_COLORS)])
        self.ax.set_xlabel("time (s)")
        self.ax.set_ylabel("angle (deg)")
        self.ax.set_xlim(self.times[0], self.times[-1])
        self.ax.grid(True, color="#e3e7ec", lw=0.6)
        # above the axes: the curves fill their width and the cursor sweeps all of it
        self.figure.legend(loc="outside upper center", fontsize="small", frameon=False,
                           ncol=min(3, len(labels)))
        self.cursor = self.ax.axvline(0.0, color="#2b3440", lw=1.2, animated=True)
        self.figure.canvas.draw()
        self._background = agg_canvas(self.figure).copy_from_bbox(self.figure.bbox)
        self.set_frame(0)

    def set_frame(self, frame: int) -> None:
        """Move the cursor to ``frame`` (blitted)."""
        t = self.times[int(frame)]
        self.cursor.set_xdata([t, t])
        agg_canvas(self.figure).restore_region(self._background)
        self.ax.draw_artist(self.cursor)
        self.figure.canvas.blit(self.figure.bbox)

    def png(self) -> bytes:
        return figure_png(self.figure)


__all__ = [
    "ChainPlot",
    "ConvergenceFigure",
    "GimbalFigure",
    "JointAngleFigure",
    "SlerpArcFigure",
    "convergence_plot",
    "draw_frame",
    "figure_png",
    "slerp_arc_figure",
]
