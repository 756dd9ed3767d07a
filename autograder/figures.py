"""A picture of the first failing case: the student's rotation beside the expected one.

Each rotation is drawn as the axis triad it turns the world axes into (x red, y green,
z blue), with the world axes faint behind it. matplotlib is imported only here, and only
when a report is drawn.
"""

from __future__ import annotations

import base64
import io

import numpy as np

from .runner import Result

AXIS_COLOURS = ("#d62728", "#2ca02c", "#1f77b4")


def first_failure_png(result: Result) -> tuple[str, str] | None:
    """(caption, base64 PNG) of the first failing case whose output is a rotation, if any."""
    for t in result.tests:
        for c in t.cases:
            if c.passed or c.got is None:
                continue
            check = t.function.check
            got, want = check.rotation(c.got), check.rotation(c.expected)
            if got is not None and want is not None:
                caption = f"{t.test.name}, {c.case.label}: your rotation and the expected one"
                return caption, _triads_png(got, want)
    return None


def _triads_png(got: np.ndarray, want: np.ndarray) -> str:
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7, 3.4), dpi=80)
    for k, (R, title) in enumerate(((got, "yours"), (want, "expected"))):
        ax = fig.add_subplot(1, 2, k + 1, projection="3d")
        for i, colour in enumerate(AXIS_COLOURS):
            ax.quiver(0, 0, 0, *np.eye(3)[i], color=colour, alpha=0.15, linewidth=1)
            ax.quiver(0, 0, 0, *R[:, i], color=colour, linewidth=2.5)
            ax.text(*(1.12 * R[:, i]), "xyz"[i], color=colour)
        ax.set(xlim=(-1, 1), ylim=(-1, 1), zlim=(-1, 1), xlabel="x", ylabel="y", zlabel="z",
               title=title)
        ax.set_box_aspect((1, 1, 1))
    buf = io.BytesIO()
    fig.savefig(buf, format="png", bbox_inches="tight")
    return base64.b64encode(buf.getvalue()).decode()
