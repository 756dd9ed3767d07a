"""Notebook 13's figure and prose say what its code measures: the flip figure marks scipy's
flip where the simulated spin about the bar turns around, and the numbers the prose quotes
are the ones the cells compute."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np

NOTEBOOK = Path(__file__).resolve().parents[1] / "notebooks" / "13_rigid_bodies.ipynb"


def _cells() -> list[tuple[str, str]]:
    cells = json.loads(NOTEBOOK.read_text(encoding="utf-8"))["cells"]
    return [(c["cell_type"], "".join(c["source"])) for c in cells]


def _run(monkeypatch, *markers: str) -> dict:
    """Execute the imports and the code cells containing ``markers``, in order."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    monkeypatch.setattr(plt, "show", lambda: None)
    code = [s for kind, s in _cells() if kind == "code"]
    env: dict = {}
    exec(next(s for s in code if "COLORS = {" in s), env)
    for marker in markers:
        exec(next(s for s in code if marker in s), env)
    return env


def test_the_flip_figure_marks_the_flip_where_the_spin_turns(monkeypatch):
    import matplotlib.pyplot as plt

    env = _run(monkeypatch, "handle = t_handle()", "run = simulate_rigid(handle",
               "T-handle spun about its intermediate axis")
    ax = plt.gcf().axes[0]
    try:
        dashed = [line for line in ax.lines if line.get_linestyle() == "--"]
        assert len(dashed) == 1
        t_mark = float(np.asarray(dashed[0].get_xdata())[0])
        assert t_mark == env["t_ref"]
        simulated = next(line for line in ax.lines if str(line.get_label()) == "$\\omega_x$ (body)")
        t, w = np.asarray(simulated.get_xdata()), np.asarray(simulated.get_ydata())
        assert w[0] > 9.9 and w.min() < -9.9  # +10 to -10 rad/s: turned over
        first = t[np.argmax(w < 0)]
        assert abs(first - t_mark) <= 0.01  # within 10 steps of 1 ms of scipy's flip
    finally:
        plt.close("all")


def test_the_prose_quotes_the_measured_flip_time(monkeypatch):
    env = _run(monkeypatch, "handle = t_handle()")
    prose = " ".join(s for kind, s in _cells() if kind == "markdown")
    quiz = " ".join(s for kind, s in _cells() if 'quiz("13.flip"' in s)
    quoted = f"{env['t_ref']:.2f} s"
    assert quoted in prose and quoted in quiz.replace("about ", "")


def test_h_max_is_the_damped_rocking_bound(monkeypatch):
    """h_max in the notebook is (2/ω)(√(1 + ζ²) − ζ) of the cube's rocking mode ω = √(6k/m)
    (a cube: I_x = 2 m a²/3): it scales as 1/√k, and the damped bound is below 2/ω."""
    env = _run(monkeypatch, "def h_max(k)")
    for k in (1e3, 1e4, 1e5):
        omega = np.sqrt(6 * k / 1.0)
        assert env["h_max"](k) < 2 / omega
        zeta = 4 * 0.3 * np.sqrt(k) * 0.01 / (2 / 3 * 0.01) / (2 * omega)
        assert np.isclose(env["h_max"](k), 2 / omega * (np.sqrt(1 + zeta**2) - zeta))
    ratios = [env["h_max"](k) * np.sqrt(k) for k in (1e3, 1e4, 1e5)]
    assert np.ptp(ratios) < 1e-12
    assert re.search(r"h_\{max\} \\propto 1/\\sqrt\{k\}", " ".join(s for _, s in _cells()))
