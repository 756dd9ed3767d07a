"""Notebook 12 §3: the energy figure's "explicit" marker stands where its curve leaves the
chart, and the caption says both when that is and when `simulate` calls it exploded."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np

NOTEBOOK = Path(__file__).resolve().parents[1] / "notebooks" / "12_mass_spring.ipynb"


def _cells() -> list[tuple[str, str]]:
    nb = json.loads(NOTEBOOK.read_text(encoding="utf-8"))
    return [(c["cell_type"], "".join(c["source"])) for c in nb["cells"]]


def test_the_explicit_marker_is_where_the_curve_leaves_the_chart(monkeypatch):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cells = _cells()
    code = [s for kind, s in cells if kind == "code"]
    imports = next(s for s in code if "COLORS = {" in s)
    drift = next(s for s in code if "drift = {m:" in s)
    i = next(i for i, (kind, s) in enumerate(cells) if "Energy of a falling" in s)
    figure, caption = cells[i][1], cells[i + 1][1]
    monkeypatch.setattr(plt, "show", lambda: None)
    env: dict = {}
    exec(imports.replace("from course.viz import cloth_simulator", ""), env)
    exec("small = grid_cloth(8, 8)", env)
    exec(drift, env)
    exec(figure, env)
    ax = plt.gcf().axes[0]
    try:
        top = ax.get_ylim()[1]
        explicit = next(line for line in ax.lines if line.get_label() == "explicit")
        t, e = np.asarray(explicit.get_xdata()), np.asarray(explicit.get_ydata())
        leaves = t[np.argmax(e > top)]  # the first time the curve is above the chart
        assert e.max() > top
        dotted = [line for line in ax.lines if line.get_linestyle() == ":"]
        assert len(dotted) == 1
        x = float(np.asarray(dotted[0].get_xdata())[0])
        assert abs(x - leaves) <= env["h"] * 1000 + 1e-9  # within one step
        blown = env["energy"]["explicit"].exploded_at * env["h"] * 1000
        assert blown - x > 50  # the two are far apart: the caption must tell them apart
        assert f"{leaves:.0f} ms" in caption.replace("about ", "")
        assert f"{blown:.0f} ms" in caption
        assert re.search(r"leaves the chart", caption)
    finally:
        plt.close("all")
