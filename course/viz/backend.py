"""Where the pictures go: a live 3D view in JupyterLab, PNG images without a browser.

The choice is made for the student, never hard-coded in a notebook:

- ``PYVISTA_JUPYTER_BACKEND`` wins when set: ``static`` (CI, so executed notebooks embed
  images), ``client``, ``server`` or ``trame``;
- inside a Jupyter kernel with trame installed (``pyvista[jupyter]``): ``"client"``, the
  scene rendered in the browser by vtk.js; a slider step sends only the changed points;
- in Google Colab (which cannot reach a port of the kernel), in VS Code attached to a remote
  kernel (SSH, a dev container, Codespaces: its webview reaches ports of the local machine
  only) and outside a kernel (scripts, tests): ``"static"`` images.

On a JupyterHub (``JUPYTERHUB_SERVICE_PREFIX`` set) the trame iframe reaches the kernel's
trame server through ``jupyter-server-proxy`` (installed with ``pyvista[jupyter]``; pyvista
turns the proxy on by itself there). Whether the single-user server really serves the proxy
is asked of the server itself, not of the kernel's packages (the extension can be installed
but disabled, or the kernel run from another environment): once per kernel, a request to
``$JUPYTERHUB_SERVICE_URL/proxy/...`` without credentials. An unknown route answers 404
before any login check; the proxy's route asks for a login (302, 403) or answers. Without the
proxy (or without an answer within a second or two) the view is ``"static"``.
"""

from __future__ import annotations

import functools
import io
import os
import sys
import threading
import traceback
from collections.abc import Callable
from concurrent.futures import Future
from pathlib import Path
from typing import Any, TypeVar

import numpy as np


def headless() -> bool:
    """True on Linux without an X11/Wayland display (CI containers, remote kernels)."""
    return sys.platform.startswith("linux") and not (
        os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")
    )


def _cache_dir() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "course-kinematics"


def configure_environment() -> None:
    """Set the environment before VTK/trame read it; every setting yields to the user's own.

    - ``VTK_WASM_DIR_OVERRIDE``: trame-vtklocal otherwise downloads a WebAssembly bundle from
      the internet at every server start; pointing it at an existing directory keeps a
      classroom without internet quiet (the default trame view renders in the kernel and
      does not need the bundle).
    - Without a display: off-screen rendering through EGL, so views and screenshots work in
      CI and on remote kernels.
    - ``WSLINK_WS_COMPRESS=0``: trame's websocket deflates every message by default. The
      arrays a browser-drawn view fetches per change are floats, which barely compress
      (notebook 06's 80 KB per press: 74 KB, for 2.3 ms of CPU and a thread hop per message
      on the kernel's loop), and the student waits for them.
    """
    os.environ.setdefault("WSLINK_WS_COMPRESS", "0")
    wasm_dir = _cache_dir() / "vtk-wasm"
    try:
        wasm_dir.mkdir(parents=True, exist_ok=True)
        os.environ.setdefault("VTK_WASM_DIR_OVERRIDE", str(wasm_dir))
    except OSError:  # read-only home: trame then falls back to its own cache
        pass
    if headless():
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
        os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")


def in_jupyter_kernel() -> bool:
    """True when running inside an IPython kernel (JupyterLab, nbval, nbclient)."""
    ipython = sys.modules.get("IPython")
    if ipython is None:
        return False
    shell = ipython.get_ipython()
    return shell is not None and "IPKernelApp" in getattr(shell, "config", {})


LIVE_BACKENDS = ("client", "server", "trame")


def jupyter_backend() -> str:
    """``"client"`` (rendered in the browser), ``"server"``/``"trame"`` (rendered in the
    kernel, streamed as images) or ``"static"`` (PNG), chosen as the module doc says."""
    env = os.environ.get("PYVISTA_JUPYTER_BACKEND", "").strip().lower()
    if env:
        if env in ("static", "none"):
            return "static"
        if env not in LIVE_BACKENDS:
            raise ValueError(f"PYVISTA_JUPYTER_BACKEND must be static, {', '.join(LIVE_BACKENDS)}"
                             f", got {env!r}")
        return env
    if not in_jupyter_kernel() or "google.colab" in sys.modules or _vscode_remote():
        return "static"
    try:
        import trame_pyvista  # noqa: F401
    except ImportError:
        return "static"
    if os.environ.get("JUPYTERHUB_SERVICE_PREFIX") and not hub_serves_proxy(
            os.environ.get("JUPYTERHUB_SERVICE_URL", "")):
        return "static"  # the browser cannot reach the kernel's trame port
    return "client"


# no trailing slash: Jupyter Server answers a path ending in "/" with a redirect of its own
HUB_PROXY_PROBE = "proxy/1/course-kinematics-probe"
HUB_PROBE_TIMEOUT_S = 1.5


@functools.cache
def hub_serves_proxy(service_url: str) -> bool:
    """True when the single-user server at ``service_url`` (``JUPYTERHUB_SERVICE_URL``, e.g.
    ``http://127.0.0.1:41234/user/ada/``) serves ``jupyter-server-proxy``'s routes.

    Asked once per kernel and URL (cached): a GET of :data:`HUB_PROXY_PROBE` with no
    credentials, redirects not followed, environment proxies bypassed (the server is local to
    the kernel). The proxy's handler checks the login first (302 to the hub's login, 403),
    an unknown route is a 404; no answer, or no URL (a hub older than 2.0), counts as no proxy.
    """
    import http.client
    import urllib.error
    import urllib.request

    if not service_url.startswith(("http://", "https://")):
        return False

    class NoRedirect(urllib.request.HTTPRedirectHandler):
        def redirect_request(self, *args: Any, **kwargs: Any) -> None:
            return None  # the 302 itself is the answer

    opener = urllib.request.build_opener(urllib.request.ProxyHandler({}), NoRedirect())
    url = service_url.rstrip("/") + "/" + HUB_PROXY_PROBE
    try:
        with opener.open(url, timeout=HUB_PROBE_TIMEOUT_S):
            return True
    except urllib.error.HTTPError as err:
        err.close()
        return err.code != 404 and err.code < 500
    except (OSError, ValueError, http.client.HTTPException):  # refused, timed out, garbage
        return False


def _vscode_remote() -> bool:
    """A kernel started by VS Code (its environment markers) on another machine than the
    editor: over SSH, in a dev container or a Codespace."""
    env = os.environ
    vscode = any(env.get(k) for k in ("VSCODE_PID", "VSCODE_CWD", "VSCODE_IPC_HOOK_CLI"))
    remote = (env.get("CODESPACES", "").lower() == "true" or bool(env.get("REMOTE_CONTAINERS"))
              or bool(env.get("SSH_CONNECTION")))
    return vscode and remote


def off_screen() -> bool:
    """Render without a window: in a kernel (trame renders in the kernel too) or headless."""
    flag = os.environ.get("PYVISTA_OFF_SCREEN", "").strip().lower() in ("1", "true", "yes")
    return flag or in_jupyter_kernel() or headless()


T = TypeVar("T")


def _kernel_loop() -> Any:
    """The kernel's main-thread event loop (a tornado ``IOLoop``), or None outside a kernel."""
    ipython = sys.modules.get("IPython")
    shell = ipython.get_ipython() if ipython is not None else None
    return getattr(getattr(shell, "kernel", None), "io_loop", None)


def on_gl_thread(fn: Callable[..., T], *args: Any) -> T:
    """Run ``fn(*args)`` on the thread that owns VTK's OpenGL contexts, and wait for it.

    An OpenGL (EGL) context is bound to one thread, and rendering from another crashes the
    kernel. In a kernel that thread is the main one: cells run there, and so does the trame
    server that renders the interactive view. But JupyterLab 4.6 with ipykernel 7 delivers
    widget events on a *subshell* thread, so a render asked for there is handed to the main
    thread's event loop. Elsewhere (scripts, tests) ``fn`` runs directly.
    """
    loop = None if threading.current_thread() is threading.main_thread() else _kernel_loop()
    if loop is None:
        return fn(*args)
    future: Future[T] = Future()

    def run() -> None:
        try:
            future.set_result(fn(*args))
        except BaseException as exc:  # handed to the waiting thread, which re-raises it
            future.set_exception(exc)

    loop.add_callback(run)
    return future.result()


def latest_on_gl_thread(handler: Callable[[T], None]) -> Callable[[T], None]:
    """Wrap a widget observer so that it runs on the GL thread (see :func:`on_gl_thread`).

    Called on the main thread, ``handler`` runs at once. Called from a subshell thread, it is
    queued on the main loop without waiting, and an event that arrives while one is still
    queued replaces it: a fast drag renders its latest value, never a backlog of stale ones.
    """
    pending: list[T] = []
    lock = threading.Lock()

    def run() -> None:
        with lock:
            change = pending.pop()
        try:
            handler(change)
        except Exception:  # nobody waits for this call: report instead of losing the error
            traceback.print_exc()

    def observer(change: T) -> None:
        loop = None if threading.current_thread() is threading.main_thread() else _kernel_loop()
        if loop is None:
            handler(change)
            return
        with lock:
            queued = bool(pending)
            pending[:] = [change]
        if not queued:
            loop.add_callback(run)

    return observer


def soon(fn: Callable[[], None]) -> None:
    """Run ``fn()`` once the kernel's loop has done what is already queued (e.g. sending a
    3D picture over the network) when called on the GL thread of a kernel; else at once."""
    loop = _kernel_loop() if threading.current_thread() is threading.main_thread() else None
    if loop is None:
        fn()
        return
    loop.add_callback(fn)


def in_background(work: Callable[[], T], done: Callable[[T], None],
                  failed: Callable[[Exception], None]) -> None:
    """Run ``work()`` beside the kernel and hand its result to ``done`` (its error to
    ``failed``) on the GL thread: a computation of seconds that touches no view (a gain's
    design) leaves the views and widgets answering meanwhile. Outside a kernel (scripts,
    tests) there is nothing to keep answering: ``done(work())`` at once, errors raised."""
    loop = _kernel_loop()
    if loop is None:
        done(work())
        return

    def run() -> None:
        try:
            result = work()
        except Exception as exc:  # reported where the view can say it
            loop.add_callback(lambda err=exc: failed(err))
            return
        loop.add_callback(lambda: done(result))

    threading.Thread(target=run, name="course-background", daemon=True).start()


def call_later(delay: float, fn: Callable[[], None]) -> None:
    """Run ``fn()`` on the kernel's main loop (the GL thread) in ``delay`` seconds, without
    blocking; outside a kernel there is no loop to run it (a RuntimeError says so)."""
    loop = _kernel_loop()
    if loop is None:
        raise RuntimeError("playing needs a running Jupyter kernel; from code, set the frame "
                           "slider's value (or pass call_later= to the player)")
    loop.call_later(delay, fn)


def png_bytes(image: np.ndarray, compress_level: int = 1) -> bytes:
    """Encode an ``(H, W, 3|4)`` uint8 image as PNG (fast compression: this runs per event)."""
    from PIL import Image

    buffer = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(image)).save(
        buffer, format="PNG", compress_level=compress_level
    )
    return buffer.getvalue()
