"""course.viz.playback: the frame skip follows the measured cost of a picture."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from course.viz.playback import PlaybackPacer


def test_skip_starts_at_the_display_rate_and_follows_the_cost():
    pacer = PlaybackPacer(120.0, max_pictures_per_s=30.0)
    assert pacer.cost is None and pacer.skip == 4 and pacer.interval == pytest.approx(4 / 120)
    assert pacer.describe() == "showing every 4th frame — 30 of 120 fps"
    for _ in range(40):
        pacer.delivered(1 / 14)  # 14 pictures a second get through
    assert pacer.cost == pytest.approx(1 / 14)
    assert pacer.skip == 9  # ceil(120 / 14)
    pacer.speed = 0.25
    assert pacer.skip == 3 and pacer.describe() == "showing every 3rd frame — 10 of 30 fps"
    slow = PlaybackPacer(30.0)
    assert slow.skip == 1 and slow.describe() == "showing every frame — 30 fps"
    slow.delivered(1 / 15)
    assert slow.describe() == "showing every 2nd frame — 15 of 30 fps"


def test_running_mean_weights_the_newest_cost():
    pacer = PlaybackPacer(30.0, smoothing=0.5)
    pacer.delivered(0.1)
    pacer.delivered(0.3)
    assert pacer.cost == pytest.approx(0.2)


@settings(derandomize=True, max_examples=200)
@given(fps=st.floats(1.0, 240.0), speed=st.sampled_from([0.25, 0.5, 1.0, 2.0]),
       cost=st.floats(0.0, 1.0), cap=st.floats(5.0, 120.0))
def test_skip_is_the_smallest_that_keeps_the_clip_speed(fps, speed, cost, cap):
    pacer = PlaybackPacer(fps, max_pictures_per_s=cap)
    pacer.speed = speed
    pacer.delivered(cost)
    per_picture = max(cost, 1 / cap)
    k = pacer.skip
    # k frames per picture keep up with the clip; k - 1 would not
    assert k / pacer.rate >= per_picture * (1 - 1e-9)
    assert k == 1 or (k - 1) / pacer.rate < per_picture * (1 + 1e-9)
    assert pacer.interval == pytest.approx(k / (fps * speed))


def test_next_frame_wraps_or_stops_on_the_last():
    pacer = PlaybackPacer(120.0)  # skip 4
    assert pacer.next_frame(0, 10, loop=True) == 4
    assert pacer.next_frame(8, 10, loop=True) == 0
    assert pacer.next_frame(8, 10, loop=False) == 9  # the last frame is shown once
    assert pacer.next_frame(9, 10, loop=False) is None


@pytest.mark.parametrize("kwargs, message", [
    ({"fps": 0.0}, "fps"), ({"fps": math.nan}, "fps"),
    ({"fps": 30.0, "max_pictures_per_s": -1.0}, "max_pictures_per_s"),
    ({"fps": 30.0, "smoothing": 0.0}, "smoothing"),
])
def test_bad_arguments_are_named(kwargs, message):
    with pytest.raises(ValueError, match=message):
        PlaybackPacer(**kwargs)
    with pytest.raises(ValueError, match="seconds"):
        PlaybackPacer(30.0).delivered(-1.0)
