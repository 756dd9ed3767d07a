"""JupyterLab in headless Chromium, shared by the browser tests and `benchmarks/live_views.py`:
one Lab server on a free localhost port, one browser, a page per notebook that runs all cells.

Every page (and every frame in it, e.g. a trame view's iframe) records when a new picture
reaches it, in ``window.__frames`` as absolute times in ms (``performance.timeOrigin +
performance.now()``, comparable across frames): an ``<img>`` that finished loading (the
static view, a server-rendered trame image) or a WebGL draw call in a new animation frame
(a view rendered in the browser by vtk.js). Key presses on the page are recorded in
``window.__keys`` the same way, and WebGL draw calls are counted in ``window.__webgl``: a
vtk.js view that drew, not trame's animated "Loading..." spinner (see :func:`webgl_drawn`).
"""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import sys
import time
import urllib.request
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[2]
TOKEN = "course-e2e"
KERNEL_IDLE = ("window.jupyterapp?.shell.currentWidget?.sessionContext?.session?.kernel"
               "?.status === 'idle'")
RUN_ALL = "() => { window.jupyterapp.commands.execute('notebook:run-all-cells'); }"  # no await
# the kernel is idle again and every code cell has run (an execution count), or one failed
# (the kernel then skips the rest)
ALL_RUN = ("() => { const w = window.jupyterapp?.shell.currentWidget;"
           " if (!w?.content) return false;"
           " const cells = w.content.widgets.filter(c => c.model.type === 'code');"
           " const failed = cells.some(c => c.model.outputs.toJSON()"
           ".some(o => o.output_type === 'error'));"
           " return w.sessionContext.session?.kernel?.status === 'idle' && (failed ||"
           " cells.every(c => c.model.executionCount !== null ||"
           " !c.model.sharedModel.getSource().trim())); }")

FRAME_PROBE = r"""
(() => {
  const now = () => performance.timeOrigin + performance.now();
  window.__frames = [];
  window.__keys = [];
  window.__webgl = 0;
  document.addEventListener('keydown', () => window.__keys.push(now()), true);
  // in the notebook itself only the 3D view's image counts (not a plot beside it)
  const top = window === window.top;
  document.addEventListener('load', (e) => {
    const el = e.target;
    // (views made before the class existed: the one wide image)
    const view = el && el.tagName === 'IMG' && (!top || el.closest('.course-view') ||
      (!document.querySelector('.course-view') && el.naturalWidth >= 600));
    if (view) {
      window.__frames.push(now());
    }
  }, true);
  let tick = -1;
  const mark = () => {  // one mark per animation frame that draws
    const t = now();
    if (t - tick > 4) { tick = t; window.__frames.push(t); }
  };
  const draw = window.CanvasRenderingContext2D?.prototype.drawImage;
  if (draw && !top) {  // a server-rendered image painted on a canvas
    CanvasRenderingContext2D.prototype.drawImage = function (...args) {
      mark(); return draw.apply(this, args);
    };
  }
  for (const proto of [window.WebGL2RenderingContext?.prototype,
                       window.WebGLRenderingContext?.prototype]) {
    if (!proto) continue;
    for (const name of ['drawElements', 'drawArrays', 'drawElementsInstanced',
                        'drawArraysInstanced']) {
      const original = proto[name];
      if (!original) continue;
      proto[name] = function (...args) {
        window.__webgl += 1; mark(); return original.apply(this, args);
      };
    }
  }
})();
"""


def chromium() -> str | None:
    return shutil.which("chromium") or shutil.which("chromium-browser")


def free_port() -> int:
    """A localhost TCP port free right now."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


# a canvas and at least one WebGL draw call in the frame (a spinner draws none)
WEBGL_DRAWN = "() => !!document.querySelector('canvas') && (window.__webgl || 0) > 0"


def webgl_drawn(frame: Any, timeout_ms: float = 60_000) -> Any:
    """Wait until ``frame`` (a client view's iframe, ``content_frame()``) has drawn with
    WebGL: vtk.js showed the scene, not a "Loading..." spinner that only changes pixels.
    Works with Playwright's sync API and, awaited, with its async one."""
    return frame.wait_for_function(WEBGL_DRAWN, timeout=timeout_ms)


def wait_until_answers(url: str, server: subprocess.Popen, log: Path,
                       timeout_s: float = 90) -> None:
    """Wait until ``url`` answers; a server that exits or stays silent raises with the end
    of its ``log``."""
    deadline = time.monotonic() + timeout_s
    while True:
        try:
            urllib.request.urlopen(url, timeout=2)
            return
        except OSError:
            if server.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError(log.read_text()[-3000:]) from None
            time.sleep(0.3)


def drawn_pixels(picture: Any) -> int:
    """Pixels drawn in colour (bones, joints, axes) in a view's picture (PNG bytes or an
    ``(H, W, 3)`` array): the background and the floor are pale grey."""
    import io

    import numpy as np
    from PIL import Image

    if isinstance(picture, bytes):
        picture = Image.open(io.BytesIO(picture)).convert("RGB")
    image = np.asarray(picture).astype(np.int16)
    return int((np.ptp(image, axis=-1) > 70).sum())


def drawn_picture(view: Any, path: Path | None = None, timeout_s: float = 30.0) -> bytes:
    """A screenshot (PNG) of ``view`` that shows a drawing, saved to ``path``. A live view's
    canvas can reach a screenshot a moment after it drew (a blank white iframe first), so
    the screenshot is taken again until at least 200 pixels are drawn in colour; a view that
    stays blank raises, saying so."""
    deadline = time.monotonic() + timeout_s
    while True:
        png = view.screenshot()
        if drawn_pixels(png) >= 200:
            break
        if time.monotonic() > deadline:
            raise AssertionError(f"the view stayed blank for {timeout_s:.0f} s")
        time.sleep(0.5)
    if path is not None:
        path.write_bytes(png)
    return png


@contextmanager
def lab_server(root: Path, env: Mapping[str, str] | None = None) -> Iterator[str]:
    """JupyterLab serving ``root`` on a free localhost port; yields its base URL."""
    port = free_port()
    # no "would you like news?" toast over the notebook
    notification = root / ".settings" / "@jupyterlab" / "apputils-extension"
    notification.mkdir(parents=True, exist_ok=True)
    (notification / "notification.jupyterlab-settings").write_text(
        '{"fetchNews": "false", "checkForUpdates": false}')
    full_env = {
        **os.environ,
        "VTK_DEFAULT_OPENGL_WINDOW": "vtkEGLRenderWindow",
        "PYVISTA_OFF_SCREEN": "true",
        "JUPYTERLAB_SETTINGS_DIR": str(root / ".settings"),
        "JUPYTERLAB_WORKSPACES_DIR": str(root / ".workspaces"),
        "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")]),
        **(env or {}),
    }
    cmd = [sys.executable, "-m", "jupyter", "lab", "--no-browser", f"--port={port}",
           "--ServerApp.ip=127.0.0.1", f"--IdentityProvider.token={TOKEN}", "--allow-root",
           f"--ServerApp.root_dir={root}", "--LabApp.expose_app_in_browser=True",
           "--LabApp.news_url=", "--LabApp.check_for_updates_class=jupyterlab.NeverCheckForUpdate",
           "--ServerApp.disable_check_xsrf=True"]
    log = open(root / "lab.log", "wb")  # noqa: SIM115 (closed below)
    server = subprocess.Popen(cmd, env=full_env, stdout=log, stderr=subprocess.STDOUT)
    base = f"http://127.0.0.1:{port}"
    try:
        wait_until_answers(f"{base}/api/status?token={TOKEN}", server, root / "lab.log")
        yield base
    finally:
        server.terminate()
        try:
            server.wait(timeout=15)
        except subprocess.TimeoutExpired:
            server.kill()
        log.close()


def launch_browser(playwright: Any) -> Any:
    """Headless Chromium (Debian's package) with software WebGL for vtk.js views."""
    return playwright.chromium.launch(
        executable_path=chromium(),
        args=["--headless", "--no-sandbox", "--disable-background-networking",
              "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
              "--disable-renderer-backgrounding", "--disable-background-timer-throttling",
              "--disable-backgrounding-occluded-windows"],
    )


def new_page(browser: Any, width: int = 1400, height: int = 1000) -> Any:
    """A page in a new browser context whose frames record key presses and pictures
    (:data:`FRAME_PROBE`). The caller closes ``page.context``."""
    context = browser.new_context(viewport={"width": width, "height": height})
    context.add_init_script(FRAME_PROBE)
    return context.new_page()


def run_all(page: Any, url: str, *, run_timeout_ms: int = 240_000) -> None:
    """Open the notebook at ``url`` in ``page``, run all its cells and wait until every one
    has run and the kernel is idle again."""
    page.goto(url)
    page.wait_for_function("window.jupyterapp && document.querySelector('.jp-Notebook')",
                           timeout=90_000)
    page.wait_for_function(KERNEL_IDLE, timeout=90_000)
    page.evaluate(RUN_ALL)
    page.wait_for_function(ALL_RUN, timeout=run_timeout_ms, polling=250)


def open_notebook(browser: Any, base: str, path: str, *, width: int = 1400,
                  height: int = 1000, run_timeout_ms: int = 240_000) -> Any:
    """A new page on the notebook ``path`` (relative to the Lab's root), all cells run and
    the kernel idle again. The caller closes ``page.context``."""
    page = new_page(browser, width, height)
    try:
        run_all(page, f"{base}/lab/tree/{path}?reset&token={TOKEN}",
                run_timeout_ms=run_timeout_ms)
    except Exception:
        page.context.close()
        raise
    return page


def shutdown_kernel(page: Any) -> None:
    """Stop the notebook's kernel (frees its memory and trame server for the next one)."""
    page.evaluate("() => window.jupyterapp.shell.currentWidget?.sessionContext?.shutdown()")


def kernel_alive(page: Any) -> bool:
    return page.evaluate("() => " + KERNEL_IDLE.replace(" === 'idle'", " !== 'dead'"))


def frames_after(page: Any, t0: float) -> list[float]:
    """Frame times (ms) after ``t0`` recorded in the page and in all its frames."""
    times: list[float] = []
    for frame in page.frames:
        try:
            times += frame.evaluate("(t) => (window.__frames || []).filter(x => x > t)", t0)
        except Exception:  # a frame that went away meanwhile
            continue
    return sorted(times)
