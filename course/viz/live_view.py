"""The live 3D view every pyvista scene of the course is: a plotter, its camera, and its
picture in a notebook, kept in step with the browser.

A :class:`LiveView` owns a :class:`pyvista.Plotter` whose renders all run on the GL thread,
and shows it as the backend chosen for the student (:func:`~course.viz.backend.jupyter_backend`):
an ``ipywidgets.Image`` refreshed on every render (static), or trame's iframe, rendered in
the kernel (server) or by vtk.js in the browser (client; see :mod:`course.viz.browser_sync`).
The scenes (:class:`~course.viz.scene.SkeletonScene`, :class:`~course.viz.frame_scene.FrameScene`,
:class:`~course.viz.cloth.ClothScene`, :class:`~course.viz.rigid_body_view.RigidBodyScene`)
add their meshes to :attr:`LiveView.plotter` and call :meth:`LiveView.render`.
"""

from __future__ import annotations

import contextlib
import io
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._typing import Array
from .backend import (
    configure_environment,
    headless,
    in_jupyter_kernel,
    jupyter_backend,
    off_screen,
    on_gl_thread,
    png_bytes,
)
from .browser_sync import BrowserDraws, keep_scene_arrays, send_changes_only

if TYPE_CHECKING:
    import ipywidgets as widgets

configure_environment()

import pyvista as pv  # noqa: E402  (after the environment is set: VTK reads it on import)

BACKGROUND = ("#f4f6fa", "#c9d3e3")  # bottom, top: a soft sky


def new_plotter(window_size: Sequence[int]) -> pv.Plotter:
    """An off-screen-aware plotter whose every render runs on the GL thread: pyvista also
    renders from inside ``add_actor``, camera setters and ``show``, not only when we ask."""
    plotter = pv.Plotter(off_screen=off_screen(), window_size=list(window_size),
                         lighting="light kit")
    render = plotter.render
    plotter.render = lambda: on_gl_thread(render)  # type: ignore[method-assign]
    plotter.renderers.set_background(BACKGROUND[0], top=BACKGROUND[1])
    if headless():
        # VTK draws on the CPU (llvmpipe), where MSAA costs 5-8x per frame: interaction stays
        # aliased and only saved screenshots are smoothed (pyvista's theme asks for 4 samples)
        plotter.disable_anti_aliasing()
    else:  # a GPU draws: MSAA is free there
        plotter.enable_anti_aliasing("msaa")
    return plotter


def shade(actor: pv.Actor, color: str, *, specular: float = 0.35, opacity: float = 1.0) -> None:
    """The course's material: a little ambient light, a soft phong highlight."""
    prop = actor.prop
    prop.color = color
    prop.opacity = opacity
    prop.ambient = 0.18
    prop.diffuse = 0.85
    prop.specular = specular
    prop.specular_power = 30.0
    prop.interpolation = "phong"


class LiveView:
    """A pyvista plotter shown in a notebook and kept up to date there.

    Parameters
    ----------
    window_size : (width, height) in pixels.
    backend : how the view is shown (see :func:`~course.viz.backend.jupyter_backend`,
        the default): ``"static"``, ``"client"``, ``"server"`` or ``"trame"``.
    """

    def __init__(self, window_size: Sequence[int], *, backend: str | None = None) -> None:
        self.backend = backend or jupyter_backend()
        self.plotter = new_plotter(window_size)
        self._in_browser = self.backend == "client"  # vtk.js draws: no glyph mapper, no text
        self._browser_views: list[Any] = []  # the vtk.js views showing this scene
        self._live_servers: list[Any] = []  # the trame servers of live views
        self._drawn = BrowserDraws()  # pictures the vtk.js views have not drawn yet
        self._camera_moved = False  # vtk.js keeps its own camera until it is sent one
        self._image: widgets.Image | None = None  # the static picture, refreshed per render
        self._widget: widgets.DOMWidget | None = None  # what widget() returns

    def _look_at(self, focal: ArrayLike, position: ArrayLike, up: ArrayLike) -> None:
        """Place the camera; pyvista keeps it (it resets an unset camera at the first render)."""
        camera = self.plotter.camera
        camera.focal_point = tuple(np.asarray(focal, dtype=np.float64))
        camera.position = tuple(np.asarray(position, dtype=np.float64))
        camera.up = tuple(np.asarray(up, dtype=np.float64))
        self.plotter.renderer.camera_set = True

    # -- output ------------------------------------------------------------------------------

    def render(self) -> None:
        """Draw the current state (and push it to the notebook view, if one is shown)."""
        if self._image is not None:  # the static picture's capture draws: once, not twice
            self._image.value = png_bytes(self.image())
            return
        if not self._in_browser:  # vtk.js sets its own clipping range
            self.plotter.renderer.ResetCameraClippingRange()
        self.plotter.render()
        if self._camera_moved and self._browser_views:  # vtk.js keeps its camera otherwise
            for view in self._browser_views:
                view.push_camera()
            self._camera_moved = False

    def image(self) -> NDArray[np.uint8]:
        """The rendered frame as an ``(H, W, 3)`` uint8 array (row 0 at the top)."""
        return on_gl_thread(self._capture, False)

    def screenshot(self, path: str | Path | None = None) -> NDArray[np.uint8]:
        """Render and return the frame ``(H, W, 3)``; also write it as PNG to ``path``
        (a saved picture is always anti-aliased, even where interaction is not)."""
        img = on_gl_thread(self._capture, path is not None)
        if path is not None:
            Path(path).parent.mkdir(parents=True, exist_ok=True)
            Path(path).write_bytes(png_bytes(img, compress_level=6))
        return img

    def _capture(self, smooth: bool) -> NDArray[np.uint8]:
        # a view rendered in the browser suppresses VTK's own rendering: lift that for a picture
        suppressed, self.plotter.suppress_rendering = self.plotter.suppress_rendering, False
        # the depth range of what is drawn now: one set before the actors were added spans
        # 0.01 to 1000, too coarse a depth buffer to tell a joint from a ghost's just behind it
        if not self._in_browser:  # (vtk.js sets its own)
            self.plotter.renderer.ResetCameraClippingRange()
        try:
            window = self.plotter.render_window
            smooth = smooth and window is not None and not window.GetMultiSamples()
            if smooth:
                self.plotter.enable_anti_aliasing("msaa")
            self.plotter.render()
            img = np.asarray(self.plotter.screenshot(None, return_img=True), dtype=np.uint8)
            if smooth:
                self.plotter.disable_anti_aliasing()
                self.plotter.render()
        finally:
            self.plotter.suppress_rendering = suppressed
        return img

    def project(self, points: ArrayLike) -> Array:
        """Pixel coordinates ``(N, 2)`` as (column, row), row 0 at the top, of world points
        ``(N, 3)`` in the rendered image: the camera's composite projection
        ``x_clip = P V [p; 1]``, then the viewport transform."""
        w, h = self.plotter.window_size
        ren = self.plotter.renderer
        m = ren.GetActiveCamera().GetCompositeProjectionTransformMatrix(w / h, -1.0, 1.0)
        M = np.array([[m.GetElement(i, j) for j in range(4)] for i in range(4)])
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        clip = np.column_stack([p, np.ones(len(p))]) @ M.T
        ndc = clip[:, :2] / clip[:, 3:4]
        return np.column_stack([(ndc[:, 0] + 1) / 2 * w, h - (ndc[:, 1] + 1) / 2 * h])

    def widget(self) -> widgets.DOMWidget:
        """The view for a notebook layout: an ``ipywidgets.Image`` refreshed on every render
        (static backend) or the interactive trame iframe."""
        if self._widget is None:
            if self.backend == "static":
                import ipywidgets as widgets

                w, h = self.plotter.window_size
                # as wide as the window, narrower when the notebook is (aspect kept)
                self._image = widgets.Image(format="png", width=w, height=h, layout=widgets.Layout(
                    max_width="100%", height="auto", min_width="320px", flex="0 1 auto"))
                self.render()
                view = self._image
            else:
                view = on_gl_thread(self._trame_view)
            view.add_class("course-view")  # found by the browser tests
            view.add_class(f"course-view-{self.backend}")  # what they expect it to draw
            self._widget = self._framed(view)
        return self._widget

    def _framed(self, view: widgets.DOMWidget) -> widgets.DOMWidget:
        """The view as :meth:`widget` shows it; a scene adds what vtk.js cannot draw."""
        return view

    def _trame_view(self) -> widgets.DOMWidget:
        """The interactive view; trame-vtklocal's note of where it found its (unused) wasm
        bundle is kept out of the student's output."""
        from trame_pyvista.widgets import PyVistaLocalView

        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            if not self._in_browser:  # as in _capture
                self.plotter.renderer.ResetCameraClippingRange()
            self.plotter.render()
            # the toolbar collapsed to one button in the corner: it covers nothing
            view: widgets.DOMWidget = self.plotter.show(
                jupyter_backend=self.backend, return_viewer=True, auto_close=False,
                jupyter_kwargs={"collapse_menu": True},
            )
        print("".join(line for line in out.getvalue().splitlines(keepends=True)
                      if not line.startswith("Using wasm_dir:")), end="")
        viewer = getattr(view, "viewer", None)
        server = getattr(viewer, "server", None)
        if server is not None:
            self._live_servers.append(server)
        for local_view in getattr(viewer, "views", ()):
            if isinstance(local_view, PyVistaLocalView):
                keep_scene_arrays(local_view)
                send_changes_only(local_view, self.plotter.render_window, self._drawn)
                self._browser_views.append(local_view)
                # the vtk.js view says when it has drawn a change (playback waits for that)
                local_view.after_scene_loaded = self._drawn.drawn
        layout = getattr(viewer, "layout", None)
        if self._browser_views and layout is not None:
            layout.flush_content()  # before the page loads: the event is in its template
        # the iframe is as wide as its box (keeping its aspect): the window's width, narrower
        # when the notebook is, never nothing
        view.layout.width = f"{self.plotter.window_size[0]}px"
        view.layout.min_width = "320px"
        view.layout.flex = "0 1 auto"
        return view

    def pictures_in_flight(self) -> int:
        """Pictures of this scene's live views not yet shown: messages on trame's websocket
        not yet handed to the network, and pictures the browser's vtk.js view has not drawn
        (:class:`~course.viz.browser_sync.BrowserDraws`). The last picture is on screen once
        this is 0. Always 0 for a static image, which travels with its widget's own message."""
        return self._drawn.pending() + sum(
            getattr(getattr(getattr(s, "context", None), "network_monitor", None), "pending", 0)
            for s in self._live_servers)

    def show(self) -> None:
        """Display the view: in a notebook as :meth:`widget`, else in a window (blocking)."""
        if in_jupyter_kernel():
            from IPython.display import display

            display(self.widget())
        else:
            self.plotter.show(auto_close=False)

    def close(self) -> None:
        """Free the render window."""
        on_gl_thread(self.plotter.close)
