"""A picture of the first failing case, for the HTML report.

A rotation (a1) is drawn as the axis triad it turns the world axes into (x red, y green,
z blue), the student's beside the expected one, with the world axes faint behind. A joint
tree (a2's skeletons, a3's chains) is drawn twice, in 3D and seen from the front (x right,
y up, as in BVH): yours solid, the expected one dashed, the pose the call started from faint,
and the targets marked. matplotlib is imported only here, only when a report is drawn, and
draws off screen (the Agg canvas), so it works headless and in a kernel alike; the class
summary draws its charts with the same :func:`figure` and :func:`png`.
"""

from __future__ import annotations

import base64
import io
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from .findings import Failure, Findings, TestFindings
    from .spec import Picture

AXIS_COLOURS = ("#d62728", "#2ca02c", "#1f77b4")
YOURS, EXPECTED, START = "#e8710a", "#1f6fd1", "#b8c0c8"
MARKERS = ("#cf222e", "#8250df", "#1a7f37", "#6e7781")


def first_failure_png(f: Findings) -> tuple[str, str] | None:
    """(caption, base64 PNG) of the first failing case that can be pictured, if any."""
    for t in f.tests:
        for c in t.failures:
            if c.got is None:
                continue
            drawn = _draw(t, c)
            if drawn:
                return drawn
    return None


def _draw(t: TestFindings, c: Failure) -> tuple[str, str] | None:
    fn = t.spec
    where = f"{t.name}, {c.case.label}"
    if fn.picture is not None:
        try:
            with np.errstate(all="ignore"):
                picture = fn.picture(c.got, c.expected, c.case.args)
        except (ValueError, IndexError, TypeError):  # an answer too broken to draw
            picture = None
        if picture is not None and _finite(picture):
            return f"{where}: {picture.what}", _trees_png(picture)
        return None
    got, want = fn.check.rotation(c.got), fn.check.rotation(c.expected)
    if got is not None and want is not None:
        return f"{where}: your rotation and the expected one", _triads_png(got, want)
    return None


def _finite(p: Picture) -> bool:
    arrays = [p.yours, p.expected, *(a for _, a in p.points)]
    return all(a is not None and np.all(np.isfinite(a)) for a in arrays)


def figure(size: tuple[float, float]) -> Figure:
    from matplotlib.figure import Figure  # the Agg canvas: no display needed

    return Figure(figsize=size, dpi=80)


def png(fig: Figure) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", bbox_inches="tight")
    return base64.b64encode(buf.getvalue()).decode()


def _triads_png(got: np.ndarray, want: np.ndarray) -> str:
    fig = figure((7, 3.4))
    for k, (R, title) in enumerate(((got, "yours"), (want, "expected"))):
        ax = fig.add_subplot(1, 2, k + 1, projection="3d")
        for i, colour in enumerate(AXIS_COLOURS):
            ax.quiver(0, 0, 0, *np.eye(3)[i], color=colour, alpha=0.15, linewidth=1)
            ax.quiver(0, 0, 0, *R[:, i], color=colour, linewidth=2.5)
            ax.text(*(1.12 * R[:, i]), "xyz"[i], color=colour)
        ax.set(xlim=(-1, 1), ylim=(-1, 1), zlim=(-1, 1), xlabel="x", ylabel="y", zlabel="z",
               title=title)
        ax.set_box_aspect((1, 1, 1))
    return png(fig)


def _bones(
    parents: np.ndarray, positions: np.ndarray
) -> list[tuple[np.ndarray, np.ndarray]]:
    """(start, end) of every bone, as pairs of points."""
    return [(positions[p], positions[j]) for j, p in enumerate(parents) if 0 <= p < j]


def _trees_png(p: Picture) -> str:
    """3D view (y drawn up) and front view (x, y) of the trees and markers of ``p``."""
    fig = figure((8, 3.8))
    ax3 = fig.add_subplot(1, 2, 1, projection="3d")
    ax2 = fig.add_subplot(1, 2, 2)
    trees = [(p.yours, p.parents, YOURS, "-", 2.5, "yours"),
             (p.expected, p.parents if p.expected_parents is None else p.expected_parents,
              EXPECTED, "--", 2.0, "expected")]
    if p.start is not None:
        trees.insert(0, (p.start, p.parents if p.expected_parents is None
                         else p.expected_parents, START, "-", 1.5, "start"))
    for positions, parents, colour, style, width, label in trees:
        for k, (a, b) in enumerate(_bones(parents, positions)):
            name = label if k == 0 else None
            ax3.plot([a[0], b[0]], [a[2], b[2]], [a[1], b[1]], style, color=colour, lw=width,
                     label=name)
            ax2.plot([a[0], b[0]], [a[1], b[1]], style, color=colour, lw=width, label=name)
        ax3.scatter(positions[:, 0], positions[:, 2], positions[:, 1], color=colour, s=8)
        ax2.plot(positions[:, 0], positions[:, 1], ".", color=colour, ms=4)
    for (label, pts), colour in zip(p.points, MARKERS, strict=False):
        pts = np.atleast_2d(pts)
        marker, size = ("x", 60) if len(pts) == 1 else (".", 10)
        ax3.scatter(pts[:, 0], pts[:, 2], pts[:, 1], color=colour, label=label, marker=marker,
                    s=size)
        ax2.scatter(pts[:, 0], pts[:, 1], color=colour, label=label, marker=marker, s=size)
    everything = np.vstack([t[0] for t in trees] + [np.atleast_2d(a) for _, a in p.points])
    lo, hi = everything.min(axis=0), everything.max(axis=0)
    centre, half = (lo + hi) / 2, max(float(np.max(hi - lo)) / 2, 1e-3) * 1.1
    ax3.set(xlim=(centre[0] - half, centre[0] + half), ylim=(centre[2] - half, centre[2] + half),
            zlim=(centre[1] - half, centre[1] + half), xlabel="x", ylabel="z", zlabel="y",
            title="3D (y up)")
    ax3.set_box_aspect((1, 1, 1))
    ax2.set(aspect="equal", xlabel="x", ylabel="y", title="front view")
    ax2.legend(fontsize=7, loc="best", frameon=False)
    return png(fig)
