"""course.viz.keyframe_plots: the notebook's explorers update from code and draw what they claim."""

from __future__ import annotations

import numpy as np

from course.keyframes import catmull_rom, cubic, polynomial
from course.viz.keyframe_plots import RungeExplorer, SplineExplorer, spline_family


def test_runge_explorer_follows_its_slider():
    explorer = RungeExplorer(n=5)
    first = explorer.canvas.image.value
    explorer.slider.value = 13
    assert explorer.canvas.image.value != first  # redrawn (blitted) into a new PNG
    keys_x, keys_y = explorer.keys.get_data()
    assert len(keys_x) == 13
    assert np.allclose(explorer.poly.get_data()[1], polynomial(keys_y, keys_x, explorer.x))
    poly_err, spline_err = explorer.errors(13)
    assert poly_err > 3 > 0.01 > spline_err


def test_spline_explorer_redraws_every_scheme_from_the_key_sliders():
    times = np.array([0.0, 0.5, 1.2, 1.6, 2.4, 3.0])
    explorer = SplineExplorer([0.0, 0.8, 0.7, 0.5, 1.0, -0.6], times)
    explorer.sliders[2].value = -0.5
    keys = explorer.keys
    assert keys[2] == -0.5
    position, velocity, _ = explorer.lines
    assert np.allclose(position["Catmull–Rom"].get_data()[1],
                       catmull_rom(keys, times, explorer.t))
    assert np.allclose(velocity["cubic (natural)"].get_data()[1],
                       cubic(keys, times, explorer.t, derivative=1))
    assert np.allclose(explorer.markers.get_data()[1], keys)


def test_bezier_of_the_family_starts_and_ends_at_the_end_keys_only():
    times, keys = np.array([0.0, 1.0, 2.5, 3.0]), np.array([0.0, 1.0, -1.0, 0.5])
    bez = spline_family(keys, times, times)["Bézier (keys as control points)"]
    assert np.allclose(bez[[0, -1]], keys[[0, -1]])
    assert not np.allclose(bez[1:-1], keys[1:-1])
