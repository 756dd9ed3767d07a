"""A drag pad: move an IK target with the mouse where the 3D view cannot send the mouse back.

The browser-rendered view (vtk.js) and the static image send no picks to the kernel, so
their target cannot be dragged in 3D. The pad is a square in the plane that faces the
view's camera: dragging its red dot moves the target along the camera's right and up
axes, ``p = c + h (u r + v s) + ((p_0 - c) . d) d``, keeping its depth ``d``. For a chain
of hinges about one axis ``n`` (a planar arm) the plane is the one across ``n``, the only
one its end can reach: ``d = n``. It is an
anywidget (a few lines of JavaScript), so it works wherever ipywidgets do: JupyterLab,
Notebook, VS Code, Colab.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import anywidget
import numpy as np
import traitlets
from numpy.typing import ArrayLike

from .._typing import Array

_ESM = r"""
function render({ model, el }) {
  const size = model.get("size"), r = model.get("dot_radius"), border = 1;
  // uv in [-1, 1]^2 spans the drawing inset by the dot's radius (and a pixel): at the
  // pad's edge the whole dot stays visible
  const inset = r + 1, span = size - 2 * inset;
  const ns = "http://www.w3.org/2000/svg";
  const svg = document.createElementNS(ns, "svg");
  svg.setAttribute("width", size);
  svg.setAttribute("height", size);
  svg.style.cssText = `background:#f4f6fa;border:${border}px solid #c9d3e3;border-radius:4px;` +
    "cursor:crosshair;touch-action:none;display:block";
  for (const [x1, y1, x2, y2] of [[size / 2, 0, size / 2, size], [0, size / 2, size, size / 2]]) {
    const line = document.createElementNS(ns, "line");
    const attributes = { x1, y1, x2, y2, stroke: "#d5dae0" };
    Object.entries(attributes).forEach(([k, v]) => line.setAttribute(k, v));
    svg.appendChild(line);
  }
  const dot = document.createElementNS(ns, "circle");
  dot.setAttribute("r", r);
  dot.setAttribute("fill", "#e5484d");
  dot.setAttribute("class", "course-drag-dot");
  svg.appendChild(dot);
  const place = ([u, v]) => {
    dot.setAttribute("cx", inset + (u + 1) / 2 * span);
    dot.setAttribute("cy", inset + (1 - v) / 2 * span);
  };
  let dragging = false, pending = null;
  const clip = (x) => Math.max(-1, Math.min(1, x));
  const send = () => {  // at most one message per animation frame
    if (pending) { model.set("uv", pending); model.save_changes(); pending = null; }
  };
  const move = (e) => {
    const box = svg.getBoundingClientRect();  // the border's box, maybe scaled by CSS
    const x = (e.clientX - box.left) * (size + 2 * border) / box.width - border;
    const y = (e.clientY - box.top) * (size + 2 * border) / box.height - border;
    const uv = [clip((x - inset) / span * 2 - 1), clip(1 - (y - inset) / span * 2)];
    place(uv);
    if (!pending) requestAnimationFrame(send);
    pending = uv;
  };
  svg.addEventListener("pointerdown", (e) => {
    dragging = true; svg.setPointerCapture(e.pointerId); move(e);
  });
  svg.addEventListener("pointermove", (e) => { if (dragging) move(e); });
  svg.addEventListener("pointerup", () => { dragging = false; });
  model.on("change:uv", () => { if (!dragging) place(model.get("uv")); });
  place(model.get("uv"));
  el.appendChild(svg);
}
export default { render };
"""


class DragPad(anywidget.AnyWidget):
    """The square pad of side ``size`` pixels; ``uv`` is the dot's centre in ``[-1, 1]^2``
    (right, up), which spans the pad inset by the dot's radius (so the dot is never cut)."""

    _esm = _ESM
    uv = traitlets.List(traitlets.Float(), default_value=[0.0, 0.0]).tag(sync=True)
    size = traitlets.Int(180).tag(sync=True)
    dot_radius = traitlets.Int(9).tag(sync=True)


class ViewPlaneDrag:
    """Map a :class:`DragPad` to target positions in the plane facing ``camera``, or in the
    plane across ``normal``.

    Parameters
    ----------
    camera : a pyvista camera (its position, focal point and up at this moment).
    center : (3,) the point under the pad's centre (e.g. the middle of the target's range).
    half : half the pad's side in world units.
    position : (3,) the target now.
    on_drag : called with each new target position ``(3,)`` while the dot is dragged.
    normal : (3,) the pad's plane is across this axis instead of facing the camera: a chain
        of hinges about one axis reaches only a plane across it, so the pad stays in that
        plane (the camera's right and up, projected into it, keep the pad's directions).
    box : (3,) half-extents of an axis-aligned box around ``center`` (e.g. the ranges of
        x/y/z sliders): instead of ``half``, the pad spans the largest rectangle in its plane
        inside that box, in the proportions of the box's outline (:func:`fit_in_box`), so
        that the pad's corners reach the box's faces and no point of the pad leaves it.
    """

    def __init__(self, camera: Any, center: ArrayLike, half: float | None, position: ArrayLike,
                 on_drag: Callable[[Array], None], *, size: int = 180,
                 normal: ArrayLike | None = None, box: ArrayLike | None = None) -> None:
        from .backend import latest_on_gl_thread

        if box is None and not (half is not None and half > 0):
            raise ValueError(f"half must be positive, got {half!r}")
        d = np.subtract(camera.position, camera.focal_point)
        towards_camera = d / np.linalg.norm(d)
        self.depth_axis = towards_camera
        if normal is not None:
            n = np.asarray(normal, dtype=np.float64).reshape(3)
            if not np.linalg.norm(n) > 0:
                raise ValueError(f"normal must be a non-zero vector, got {normal!r}")
            n = n / np.linalg.norm(n)
            # facing the camera's side; a plane seen edge-on gets the camera's up for its up
            self.depth_axis = n if n @ towards_camera >= 0 else -n
        right = np.cross(camera.up, towards_camera)
        right -= (right @ self.depth_axis) * self.depth_axis
        if np.linalg.norm(right) < 1e-6:  # looking along the plane's up: any right will do
            right = np.cross(self.depth_axis, np.eye(3)[np.argmin(np.abs(self.depth_axis))])
        self.right = right / np.linalg.norm(right)
        self.up = np.cross(self.depth_axis, self.right)
        self.center = np.asarray(center, dtype=np.float64).reshape(3)
        if box is not None:
            self.half_uv = fit_in_box(self.right, self.up, box)
        else:
            self.half_uv = np.full(2, float(half))  # type: ignore[arg-type]
        self.half = float(self.half_uv.max())
        self._depth = 0.0
        self._quiet = False
        self.pad = DragPad(size=size)
        self.pad.add_class("course-drag-pad")
        self.show(position)
        self._on_drag = on_drag
        self.pad.observe(latest_on_gl_thread(self._moved), names="uv")

    def position(self, uv: ArrayLike) -> Array:
        """The target at pad point ``uv (2,)``: in the view plane, at the kept depth."""
        u, v = np.clip(np.asarray(uv, dtype=np.float64).reshape(2), -1.0, 1.0)
        hu, hv = self.half_uv
        p: Array = (self.center + hu * u * self.right + hv * v * self.up
                    + self._depth * self.depth_axis)
        return p

    def show(self, position: ArrayLike) -> None:
        """Put the dot where ``position (3,)`` lies (clipped to the pad); keep its depth."""
        rel = np.asarray(position, dtype=np.float64).reshape(3) - self.center
        self._depth = float(rel @ self.depth_axis)
        uv = np.clip([rel @ self.right / self.half_uv[0], rel @ self.up / self.half_uv[1]],
                     -1.0, 1.0)
        self._quiet = True
        try:
            self.pad.uv = [float(uv[0]), float(uv[1])]
        finally:
            self._quiet = False

    def _moved(self, change: dict[str, Any]) -> None:
        if not self._quiet:
            self._on_drag(self.position(change["new"]))


def fit_in_box(right: ArrayLike, up: ArrayLike, box: ArrayLike) -> Array:
    """Half-sides ``(a, b)`` of the largest rectangle ``c + a u right + b v up`` (``|u|, |v|
    <= 1``) inside the box ``c ± box`` that keeps the proportions of the box's outline seen
    along ``right x up``: a corner of the pad reaches a face of the box (a slider's limit),
    and its middle is the box's middle. Seen along a world axis, it is the box's face."""
    r, s = (np.abs(np.asarray(a, dtype=np.float64).reshape(3)) for a in (right, up))
    b = np.asarray(box, dtype=np.float64).reshape(3)
    if not np.all(b > 0):
        raise ValueError(f"box must have positive half-extents, got {box!r}")
    outline = np.array([r @ b, s @ b])  # the box's outline in the pad's plane
    reach = outline[0] * r + outline[1] * s  # how far its corners go along each axis
    scale = min(1.0, float(np.min(b[reach > 1e-12] / reach[reach > 1e-12])))
    out: Array = scale * outline
    return out
