"""The 3D view on a real JupyterHub, in headless Chromium.

One hub on localhost (`hub/jupyterhub_config.py`: a shared password, single-user JupyterLab
servers of this Python as local processes, the pure-Python configurable-http-proxy, all in a
temporary folder on free ports, stopped after), two students logging in through its login
page, each running `e2e_views.ipynb` (an `fk_explorer`) in their own JupyterLab:

- ``ada``'s server has jupyter-server-proxy, as `pyvista[jupyter]` installs it: the view is
  drawn in the browser (vtk.js) in an iframe served through ``/user/ada/proxy/<port>/``;
- ``noproxy``'s server runs with the proxy's server extension disabled (its package still
  imports): the kernel asks the server, finds no proxy route and shows static images instead
  of an iframe the browser could not load.

In both, the picture must not be blank and one key press on a slider must change it.
Screenshots go to `tests/e2e/artifacts/hub_*.png`.
"""

from __future__ import annotations

import importlib.util
import io
import os
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from labkit import (
    chromium,
    drawn_picture,
    drawn_pixels,
    frames_after,
    free_port,
    kernel_alive,
    launch_browser,
    new_page,
    run_all,
    wait_until_answers,
    webgl_drawn,
)

from course.viz.backend import HUB_PROXY_PROBE

HERE = Path(__file__).resolve().parent
NOTEBOOK = HERE / "e2e_views.ipynb"
HUB_CONFIG = HERE / "hub" / "jupyterhub_config.py"
ARTIFACTS = HERE / "artifacts"
PASSWORD = "course-e2e-hub"
PROXY_USER, NO_PROXY_USER = "ada", "noproxy"  # the config disables the second one's proxy


def _missing() -> str | None:
    if chromium() is None:
        return "chromium not found: apt-get install chromium (make e2e does it as root)"
    if importlib.util.find_spec("jupyterhub") is None:
        return "jupyterhub not installed: pip install -e '.[dev]'"
    if importlib.util.find_spec("configurable_http_proxy") is None:
        return "configurable-http-proxy not installed: pip install -e '.[dev]'"
    return None


@contextmanager
def hub_server(root: Path) -> Iterator[str]:
    """A JupyterHub serving from ``root`` on free localhost ports; yields its public URL."""
    port = free_port()
    (root / "home").mkdir()
    for user in (PROXY_USER, NO_PROXY_USER):
        (root / "home" / user).mkdir()
        shutil.copy(NOTEBOOK, root / "home" / user / NOTEBOOK.name)
    # no "would you like news?" toast over the notebook
    settings = root / "settings" / "@jupyterlab" / "apputils-extension"
    settings.mkdir(parents=True)
    (settings / "notification.jupyterlab-settings").write_text(
        '{"fetchNews": "false", "checkForUpdates": false}')
    env = {
        # the student's automatic choice of view, not the Makefile's static (only the keys
        # the config passes on reach the single-user servers)
        **{k: v for k, v in os.environ.items() if k != "PYVISTA_JUPYTER_BACKEND"},
        "COURSE_HUB_ROOT": str(root),
        "COURSE_HUB_PORT": str(port),
        "COURSE_HUB_API_PORT": str(free_port()),
        "COURSE_HUB_PROXY_API_PORT": str(free_port()),
        "COURSE_HUB_PASSWORD": PASSWORD,
        "COURSE_HUB_NO_PROXY_USER": NO_PROXY_USER,
        "COURSE_HUB_PYTHON": sys.executable,
        "VTK_DEFAULT_OPENGL_WINDOW": "vtkEGLRenderWindow",
        "PYVISTA_OFF_SCREEN": "true",
        "JUPYTERLAB_SETTINGS_DIR": str(root / "settings"),
    }
    log = open(root / "hub.log", "wb")  # noqa: SIM115 (closed below)
    # its own process group: whatever the hub leaves behind is stopped with it
    hub = subprocess.Popen([sys.executable, "-m", "jupyterhub", "-f", str(HUB_CONFIG)],
                           cwd=root, env=env, stdout=log, stderr=subprocess.STDOUT,
                           start_new_session=True)
    base = f"http://127.0.0.1:{port}"
    try:
        wait_until_answers(f"{base}/hub/api", hub, root / "hub.log")
        yield base
    finally:
        hub.terminate()  # the hub stops the users' servers and its proxy
        try:
            hub.wait(timeout=30)
        except subprocess.TimeoutExpired:
            hub.kill()
        try:
            os.killpg(hub.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        log.close()


@pytest.fixture(scope="module")
def hub(tmp_path_factory):
    missing = _missing()
    if missing:
        if os.environ.get("CI", "").lower() == "true":
            pytest.fail(missing)
        pytest.skip(missing)
    ARTIFACTS.mkdir(exist_ok=True)
    if not (ARTIFACTS / ".gitignore").exists():
        (ARTIFACTS / ".gitignore").write_text("*\n")
    root = tmp_path_factory.mktemp("hub")
    started = time.monotonic()
    with hub_server(root) as base:
        print(f"\nthe hub answered after {time.monotonic() - started:.1f} s")
        yield base, root


@contextmanager
def _student_notebook(base: str, user: str) -> Iterator[Any]:
    """Chromium logged in to the hub as ``user`` (its login form), the notebook open in the
    user's JupyterLab with all cells run; on a failure the page goes to the artifacts."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = launch_browser(p)
        page = new_page(browser)
        try:
            page.goto(f"{base}/hub/login")
            page.fill("input[name=username]", user)
            page.fill("input[name=password]", PASSWORD)
            page.click("[type=submit]")
            # the spawn-pending page forwards to the user's Lab once the server is up
            page.wait_for_url(f"**/user/{user}/lab**", timeout=120_000)
            run_all(page, f"{base}/user/{user}/lab/tree/{NOTEBOOK.name}?reset")
            yield page
        except Exception:
            page.screenshot(path=str(ARTIFACTS / f"hub_{user}_failure.png"), full_page=True)
            raise
        finally:
            browser.close()


def _image(png: bytes) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(np.int16)




def _press_and_see(page: Any, view: Any, key: str = "End",
                   timeout_s: float = 30.0) -> tuple[np.ndarray, float | None]:
    """Press ``key`` on the explorer's first slider; the view's next different picture and
    the ms from the key press to the first new frame the page recorded (None if none)."""
    before = _image(view.screenshot())
    handle = page.locator(".widget-slider .noUi-handle").first
    handle.focus()
    t0 = page.evaluate("() => performance.timeOrigin + performance.now()")
    page.keyboard.press(key)
    deadline = time.monotonic() + timeout_s
    while True:
        time.sleep(0.5)
        frames = frames_after(page, t0)
        after = _image(view.screenshot())
        if (frames and np.abs(after - before).mean() > 0.5) or time.monotonic() > deadline:
            break
    time.sleep(1.0)  # the last frame of the step
    after = _image(view.screenshot())
    latency = frames_after(page, t0)[0] - t0 if frames_after(page, t0) else None
    return after, latency


def _save(image: np.ndarray, name: str) -> None:
    from PIL import Image

    Image.fromarray(image.astype(np.uint8)).save(ARTIFACTS / name)


def _check_view(page: Any, view: Any, user: str) -> None:
    """The picture is drawn; a slider key press changes it and the readout; the kernel lives."""
    view.scroll_into_view_if_needed()
    # a live view draws a moment after its cell: its first picture that is not blank
    before = _image(drawn_picture(view, ARTIFACTS / f"hub_{user}_before.png", timeout_s=60))
    readout = page.locator(".widget-html-content").filter(has_text="Qj =").last
    text_before = readout.inner_text()
    after, latency = _press_and_see(page, view)
    _save(after, f"hub_{user}_after.png")
    print(f"{user}: key press -> first new frame in the page: "
          + (f"{latency:.0f} ms" if latency is not None else "none recorded"))
    assert kernel_alive(page), "the kernel died when the slider moved"
    assert latency is not None, "no new frame reached the page after the key press"
    assert readout.inner_text() != text_before, "the readout did not follow the slider"
    assert np.abs(after - before).mean() > 0.5, "the 3D view did not change"
    assert drawn_pixels(after) >= 200, "the view is blank after the key press"


def _probes(root: Path, user: str, status: int) -> int:
    """How often the kernel's probe for the proxy got ``status`` (the single-user server's log
    goes to the hub's)."""
    return (root / "hub.log").read_text().count(f"{status} GET /user/{user}/{HUB_PROXY_PROBE}")


def test_a_hub_with_the_proxy_draws_the_view_in_the_browser(hub):
    base, root = hub
    started = time.monotonic()
    with _student_notebook(base, PROXY_USER) as page:
        view = page.locator(".course-view").first
        view.wait_for(state="visible", timeout=60_000)
        frame = view.locator("iframe")
        assert frame.count() == 1, "no iframe: the kernel did not choose the browser-drawn view"
        src = frame.get_attribute("src") or ""
        assert f"/user/{PROXY_USER}/proxy/" in src, f"the view's iframe bypasses the proxy: {src}"
        # vtk.js drew (WebGL calls in the iframe), not trame's "Loading..." that waits for its
        # websocket through the proxies
        try:
            webgl_drawn(frame.element_handle().content_frame())
        except Exception:
            _save(_image(view.screenshot()), f"hub_{PROXY_USER}_never_drawn.png")
            raise AssertionError("vtk.js never drew in the view's iframe") from None
        _check_view(page, view, PROXY_USER)
    # the kernel asked the server once (the login check's redirect: the route exists)
    assert _probes(root, PROXY_USER, 302) == 1
    print(f"{PROXY_USER}: login to checked view {time.monotonic() - started:.1f} s")


def test_a_hub_without_the_proxy_shows_static_images_not_a_dead_iframe(hub):
    base, root = hub
    started = time.monotonic()
    with _student_notebook(base, NO_PROXY_USER) as page:
        view = page.locator(".course-view").first
        view.wait_for(state="visible", timeout=60_000)
        assert page.locator(".jp-OutputArea-output iframe").count() == 0, "an iframe was shown"
        assert view.evaluate("e => e.tagName") == "IMG", "the view is not a static image"
        _check_view(page, view, NO_PROXY_USER)
    # the kernel asked the server once, and got the 404 that says there is no proxy
    assert _probes(root, NO_PROXY_USER, 404) == 1
    print(f"{NO_PROXY_USER}: login to checked view {time.monotonic() - started:.1f} s")
