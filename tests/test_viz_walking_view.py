"""Notebook 15's walking view: a short SIMBICON walk re-simulated by its sliders, drawn from
above with the footsteps and the capture point."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("mujoco")
pytest.importorskip("ipywidgets")

from course import data  # noqa: E402
from course.physics.character import build_model  # noqa: E402
from course.viz.walking_view import capture_points, walking_view  # noqa: E402


@pytest.fixture(scope="module")
def character():
    return build_model(data.load("cmu_12_01_walk")[1:].skeleton)


def test_capture_point_of_a_path_at_rest_and_moving():
    com = np.column_stack([np.zeros(5), np.full(5, 0.981), 0.1 * np.arange(5)])  # 1 m/s in z
    xi = capture_points(com, 0.1)
    np.testing.assert_allclose(xi[:, 0], 0.0)
    np.testing.assert_allclose(xi[:, 1], com[:, 2] + 1.0 / np.sqrt(9.81 / 0.981))


def test_the_sliders_re_simulate_and_the_figure_is_drawn(character):
    view = walking_view(character, duration=1.5, push_start=0.8)
    first = view.result
    assert first is not None and not first.fell and len(first.footsteps) >= 2
    png = view.image.value
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    assert "strides" in view.readout.value
    view.sliders["c_d"].value = 0.0
    assert view.result is not first and view.settings()["gait"].c_d == 0.0
    view.sliders["push"].value = 100.0
    assert view.settings()["push"].force[2] == pytest.approx(100.0)
    assert view.image.value != png
    view.close()
