"""Playback pacing: which frames of a clip to show so that it keeps its speed, at the rate
the pictures actually reach the student.

A clip of ``fps`` frames a second played at ``speed`` asks for ``r = fps * speed`` frames a
second. Each picture costs ``c`` seconds (draw, serialize, send) on this machine, measured
while playing; so at most ``1 / c`` pictures a second (and never more than
``max_pictures_per_s``) can be shown, and the player shows every ``k``-th frame,
``k = ceil(r * max(c, 1 / max_pictures_per_s))``, one picture every ``k / r`` seconds. The
next picture is asked for only once the previous one has been sent, so nothing queues up
and a pause stops the pictures at once.
"""

from __future__ import annotations

import math


def _ordinal(k: int) -> str:
    suffix = "th" if 10 <= k % 100 <= 20 else {1: "st", 2: "nd", 3: "rd"}.get(k % 10, "th")
    return f"{k}{suffix}"


class PlaybackPacer:
    """The frame skip of a playing clip, adapted to the measured cost of a picture.

    Parameters
    ----------
    fps : the clip's frames per second (``1 / frame_time``).
    max_pictures_per_s : the most pictures a second worth asking for (a display's rate).
    smoothing : weight of the newest cost in its running mean, in (0, 1]: lower is steadier.
    """

    def __init__(self, fps: float, *, max_pictures_per_s: float = 30.0,
                 smoothing: float = 0.3) -> None:
        for name, value in (("fps", fps), ("max_pictures_per_s", max_pictures_per_s)):
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a positive number, got {value!r}")
        if not 0 < smoothing <= 1:
            raise ValueError(f"smoothing must lie in (0, 1], got {smoothing!r}")
        self.fps = float(fps)
        self.max_pictures_per_s = float(max_pictures_per_s)
        self.smoothing = float(smoothing)
        self.speed = 1.0
        self.cost: float | None = None  # seconds per picture, running mean (None: not measured)

    @property
    def rate(self) -> float:
        """Clip frames per second asked for: ``fps * speed``."""
        return self.fps * self.speed

    def delivered(self, seconds: float) -> None:
        """One picture took ``seconds`` from being asked for to being sent."""
        if not (math.isfinite(seconds) and seconds >= 0):
            raise ValueError(f"seconds must be a finite number >= 0, got {seconds!r}")
        self.cost = seconds if self.cost is None else (
            (1 - self.smoothing) * self.cost + self.smoothing * seconds)

    @property
    def pictures_per_s(self) -> float:
        """How many pictures a second this machine delivers (capped by the display's rate)."""
        floor = 1.0 / self.max_pictures_per_s
        return 1.0 / max(self.cost or 0.0, floor)

    @property
    def skip(self) -> int:
        """Show every ``skip``-th frame (1: every frame)."""
        return max(1, math.ceil(self.rate / self.pictures_per_s - 1e-9))

    @property
    def interval(self) -> float:
        """Seconds between pictures that keep the clip's speed: ``skip / rate``."""
        return self.skip / self.rate

    def next_frame(self, frame: int, n_frames: int, loop: bool) -> int | None:
        """The frame to show after ``frame``: ``skip`` on, wrapping to 0 when ``loop``; None at
        the end of a clip that does not loop."""
        nxt = frame + self.skip
        if nxt < n_frames:
            return nxt
        if not loop:
            return None if frame >= n_frames - 1 else n_frames - 1  # the last frame, once
        return 0

    def describe(self) -> str:
        """What the student sees, e.g. ``"showing every 2nd frame — 15 of 30 fps"``."""
        if self.skip == 1:
            return f"showing every frame — {self.rate:.0f} fps"
        return (f"showing every {_ordinal(self.skip)} frame — {self.rate / self.skip:.0f} "
                f"of {self.rate:.0f} fps")
