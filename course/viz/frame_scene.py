"""Rotated coordinate frames side by side (pyvista): what a rotation, or a blend of two,
does to the axes.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from .backend import configure_environment, jupyter_backend
from .live_view import LiveView
from .skeleton_actors import AXIS_COLORS

configure_environment()

import pyvista as pv  # noqa: E402  (after the environment is set: VTK reads it on import)
from vtkmodules.vtkRenderingCore import vtkActor2D  # noqa: E402


class FrameScene(LiveView):
    """A rotated coordinate frame (x red, y green, z blue arrows) beside the faint world frame;
    :meth:`set_rotations` moves each frame by setting its actors' transform (nothing rebuilt).

    The view is a parallel projection, so equal lengths look equal in every frame (a shorter
    arrow is a shorter axis, not a farther one). The frames stand in a row across the screen,
    each caption centred under its own frame, below every place its arrows can point.

    Parameters
    ----------
    n_frames : how many frames to show side by side (e.g. 3 for LERP / NLERP / SLERP).
    labels : a caption under each frame (wrapped to the frame's width).
    """

    #: world units between neighbouring frames, and the radius every arrow (turned any way,
    #: its tip included) and the world frame's axes (1.15 long) stay inside
    SPACING, REACH = 2.6, 1.2
    FONT_SIZE, MARGIN = 18, 8  # caption size, and pixels kept clear at the window's edges

    def __init__(
        self,
        n_frames: int = 1,
        labels: Sequence[str] | None = None,
        *,
        window_size: tuple[int, int] | None = None,
    ) -> None:
        if labels is not None and len(labels) != n_frames:
            raise ValueError(f"labels must have {n_frames} entries, got {len(labels)}")
        backend = jupyter_backend()
        size = window_size or (max(420, 300 * n_frames), 380)
        # the captions are VTK text, which vtk.js does not draw: rendered in the kernel
        super().__init__(size, backend="server" if backend == "client" else backend)
        # looking from the front, a little right and above; the frames in a row along the
        # screen's right (horizontal), so none is lower or farther than another
        d = np.array([0.45, 0.35, 1.0]) / np.linalg.norm([0.45, 0.35, 1.0])
        right = np.cross([0.0, 1.0, 0.0], d)
        right /= np.linalg.norm(right)
        up = np.cross(d, right)
        self.offsets = [self.SPACING * (i - (n_frames - 1) / 2) * right for i in range(n_frames)]
        scale, captions, caption_px = self._layout(size, n_frames, labels)
        self.pixels_per_unit = scale
        self._arrows: list[list[pv.Actor]] = []
        self.label_actors: list[vtkActor2D] = []
        arrow = [pv.Arrow(start=(0, 0, 0), direction=np.eye(3)[a], tip_length=0.22,
                          tip_radius=0.07, shaft_radius=0.028) for a in range(3)]
        gap = 6.0 / scale  # between the lowest reach of the arrows and the caption's top
        for i, off in enumerate(self.offsets):
            for a in range(3):  # the world frame, faint and thin
                ghost = pv.Line(off, off + 1.15 * np.eye(3)[a])
                self.plotter.add_mesh(ghost, color=tuple(AXIS_COLORS[a] / 255), opacity=0.35,
                                      line_width=2, reset_camera=False)
            actors = []
            for a in range(3):
                actor = self.plotter.add_mesh(arrow[a], color=tuple(AXIS_COLORS[a] / 255),
                                              smooth_shading=True, specular=0.4,
                                              reset_camera=False)
                actors.append(actor)
            self._arrows.append(actors)
            if captions:
                self.label_actors.append(self.plotter.add_point_labels(
                    [off - (self.REACH + gap) * up], [captions[i]], font_size=self.FONT_SIZE,
                    shape=None, show_points=False, text_color="#2b3440", always_visible=True,
                    justification_horizontal="center", justification_vertical="top",
                    reset_camera=False))
        self.rotations = np.tile(np.eye(3), (n_frames, 1, 1))
        # the row of frames and the captions under it, centred in the window: the frames'
        # centre row is above the window's middle by half the captions' height
        camera = self.plotter.camera
        camera.parallel_projection = True
        camera.parallel_scale = size[1] / (2 * scale)
        focal = -(caption_px + 6.0) / 2 / scale * up
        self._look_at(focal, focal + 4 * self.SPACING * max(n_frames, 2) * d, up)

    @classmethod
    def _layout(cls, size: tuple[int, int], n_frames: int, labels: Sequence[str] | None
                ) -> tuple[float, list[str], float]:
        """Pixels per world unit that fit the row of frames and the captions under it in
        ``size``; the captions wrapped to a frame's width; their height in pixels."""
        import textwrap

        w, h = size
        line = 1.25 * cls.FONT_SIZE
        captions: list[str] = []
        caption_px = 0.0
        for _ in range(2):  # the scale depends on the captions' lines, their width on the scale
            scale = min((w - 2 * cls.MARGIN) / (cls.SPACING * (n_frames - 1) + 2 * cls.REACH),
                        (h - 2 * cls.MARGIN - 6.0 - caption_px) / (2 * cls.REACH))
            if labels is None:
                break
            column = min(cls.SPACING * scale, w - 2 * cls.MARGIN) - 8  # a gap between captions
            chars = max(6, int(column / (0.55 * cls.FONT_SIZE)))  # bold sans: ~0.55 em a letter
            captions = ["\n".join(textwrap.wrap(text, chars)) or " " for text in labels]
            caption_px = line * max(c.count("\n") + 1 for c in captions)
        return float(scale), captions, caption_px

    def set_rotations(self, matrices: ArrayLike, *, render: bool = True) -> None:
        """Set each frame's linear map ``(n_frames, 3, 3)`` (a rotation, or a scaled one to
        show a non-unit quaternion); the arrows are transformed, not rebuilt."""
        R = np.asarray(matrices, dtype=np.float64).reshape(-1, 3, 3)
        if len(R) != len(self._arrows):
            raise ValueError(f"matrices must have shape ({len(self._arrows)}, 3, 3)")
        self.rotations = R.copy()
        for actors, off, Ri in zip(self._arrows, self.offsets, R, strict=True):
            T = np.eye(4)
            T[:3, :3] = Ri
            T[:3, 3] = off
            for actor in actors:
                actor.user_matrix = T
        if render:
            self.render()
