"""JupyterLab in headless Chromium: run the notebook, drag a slider, see the numbers and the
3D view change, and the kernel stay alive: with the static image view that CI executes, the
browser-rendered (vtk.js) view a student gets by default, and the server-rendered trame view
in which the IK target is a sphere to drag; in the browser-rendered view the target is dragged
on a pad in the view's plane instead. A browser-rendered view counts as drawn only when vtk.js
made WebGL draw calls in its iframe (trame's animated "Loading..." spinner also changes the
screenshots). Screenshots go to test-artifacts/. Needs the Debian package `chromium`."""

from __future__ import annotations

import os
import shutil
from contextlib import contextmanager
from pathlib import Path

import nbformat
import pytest
from labkit import (
    REPO,
    TOKEN,
    chromium,
    drawn_picture,
    kernel_alive,
    lab_server,
    launch_browser,
    new_page,
    run_all,
    webgl_drawn,
)

NOTEBOOK = Path(__file__).with_name("e2e_views.ipynb")
DRAG_NOTEBOOK = Path(__file__).with_name("e2e_drag.ipynb")
# a view, then a cell that keeps the kernel busy past trame-vtk's 20 s array cache, then a
# second view (its render is when the cache drops what is older): the first view's page,
# which could not load its arrays meanwhile, must still draw (course.viz.browser_sync)
LATE_NOTEBOOK = "e2e_late.ipynb"
LATE_CELLS = ["from course.skeleton import chain\nfrom course.viz import fk_explorer\n"
              "fk_explorer(chain([1.0, 0.8, 0.5], axes=[0, 0, 1]))",
              "import time\ntime.sleep(25)",
              "fk_explorer(chain([1.0, 0.5], axes=[0, 0, 1]))"]
ARTIFACTS = REPO / "test-artifacts"


def _chromium() -> str:
    path = chromium()
    if path is None:
        message = "chromium not found: apt-get install chromium (make e2e does it as root)"
        if os.environ.get("CI", "").lower() == "true":
            pytest.fail(message)
        pytest.skip(message)
    return path


@pytest.fixture(scope="module", params=["static", "client"])
def lab(request, tmp_path_factory):
    """JupyterLab on a free localhost port, serving a copy of the notebooks (never saved back),
    with the 3D view as an image widget (``static``, what CI executes), rendered in the
    browser (``client``, a student's default) or in the kernel (``server``)."""
    _chromium()
    root = tmp_path_factory.mktemp("lab")
    for notebook in (NOTEBOOK, DRAG_NOTEBOOK):
        shutil.copy(notebook, root / notebook.name)
    late = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(c) for c in LATE_CELLS])
    late.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3",
                                   "language": "python"}
    nbformat.write(late, root / LATE_NOTEBOOK)
    with lab_server(root, {"PYVISTA_JUPYTER_BACKEND": request.param}) as base:
        yield base, request.param


@contextmanager
def _notebook_page(base: str, notebook: Path | str, artifact: str):
    """A headless Chromium page on ``notebook`` in the served Lab, all its cells run; on a
    failure the page is saved as ``test-artifacts/<artifact>_failure.png``."""
    from playwright.sync_api import sync_playwright

    ARTIFACTS.mkdir(exist_ok=True)
    with sync_playwright() as p:
        browser = launch_browser(p)
        page = new_page(browser)  # (its probe counts the WebGL draws in the view's iframe)
        try:
            run_all(page, f"{base}/lab/tree/{Path(notebook).name}?reset&token={TOKEN}")
            yield page
        except Exception:
            page.screenshot(path=str(ARTIFACTS / f"{artifact}_failure.png"), full_page=True)
            raise
        finally:
            browser.close()


def _webgl_draws(view) -> int:
    """WebGL draw calls so far in a browser-rendered view's iframe, once it has drawn."""
    frame = view.element_handle().content_frame()
    try:
        webgl_drawn(frame)
    except Exception:
        raise AssertionError("vtk.js never drew in the view's iframe (a spinner?)") from None
    return frame.evaluate("() => window.__webgl")


def test_slider_moves_the_skeleton_in_jupyterlab(lab):
    base, backend = lab
    with _notebook_page(base, NOTEBOOK, f"e2e_{backend}") as page:
        view = page.locator(".widget-image" if backend == "static" else "iframe").first
        view.wait_for(state="visible", timeout=60_000)
        readout = page.locator(".widget-html-content").filter(has_text="Qj =").last
        page.wait_for_function(
            "[...document.querySelectorAll('.widget-html-content')]"
            ".some(e => e.innerText.includes('Qj ='))", timeout=30_000)
        widget_area = page.locator(".jp-OutputArea-output").last
        widget_area.scroll_into_view_if_needed()
        page.wait_for_timeout(500 if backend == "static" else 6000)
        draws_before = _webgl_draws(view) if backend == "client" else 0
        text_before = readout.inner_text()
        image_before = drawn_picture(view, ARTIFACTS / f"e2e_{backend}_view_before.png")
        widget_area.screenshot(path=str(ARTIFACTS / f"e2e_{backend}_widget_before.png"))

        handle = page.locator(".widget-slider .noUi-handle").first
        handle.scroll_into_view_if_needed()
        box = handle.bounding_box()
        x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
        page.mouse.move(x, y)
        page.mouse.down()
        page.mouse.move(x + 60, y, steps=8)
        page.mouse.up()

        page.wait_for_function(
            "([t]) => ![...document.querySelectorAll('.widget-html-content')]"
            ".some(e => e.innerText === t)", arg=[text_before], timeout=20_000)
        page.wait_for_timeout(800 if backend == "static" else 4000)  # the last frame
        widget_area.scroll_into_view_if_needed()
        text_after = readout.inner_text()
        image_after = drawn_picture(view, ARTIFACTS / f"e2e_{backend}_view_after.png")
        widget_area.screenshot(path=str(ARTIFACTS / f"e2e_{backend}_widget_after.png"))
        draws_after = _webgl_draws(view) if backend == "client" else 0
        alive = kernel_alive(page)
    assert alive, "the kernel died while the slider moved"
    assert text_after != text_before
    assert image_after != image_before, "the 3D view did not change"
    if backend == "client":
        assert draws_after > draws_before, "vtk.js drew nothing after the slider moved"


@pytest.mark.parametrize("lab", ["server"], indirect=True)
def test_dragging_the_target_sphere_solves_ik_again(lab):
    """In the interactive view the target is a sphere to drag: the sliders follow it."""
    base, _ = lab
    with _notebook_page(base, DRAG_NOTEBOOK, "e2e_drag") as page:
        stream = page.locator(".jp-OutputArea-output").filter(has_text="target handle at")
        stream.wait_for(state="visible", timeout=60_000)
        u, v = (float(x) for x in stream.inner_text().split()[3:5])
        view = page.locator("iframe").first
        view.wait_for(state="visible", timeout=60_000)
        view.scroll_into_view_if_needed()
        page.wait_for_timeout(6000)  # trame's first frame
        readouts = page.locator(".widget-slider .widget-readout")
        before = [readouts.nth(k).inner_text() for k in range(2)]
        view.screenshot(path=str(ARTIFACTS / "e2e_drag_before.png"))
        box = view.bounding_box()
        x, y = box["x"] + u * box["width"], box["y"] + v * box["height"]
        page.mouse.move(x, y)
        page.mouse.down()
        page.mouse.move(x - 70, y - 50, steps=12)
        page.mouse.up()
        page.wait_for_function(
            "([t]) => [...document.querySelectorAll('.widget-slider .widget-readout')]"
            ".slice(0, 2).map(e => e.innerText).join() !== t", arg=[",".join(before)],
            timeout=20_000)
        page.wait_for_timeout(3000)
        after = [readouts.nth(k).inner_text() for k in range(2)]
        view.screenshot(path=str(ARTIFACTS / "e2e_drag_after.png"))
        alive = kernel_alive(page)
    assert alive, "the kernel died while the target was dragged"
    assert after != before, "dragging the sphere did not move the target sliders"


@pytest.mark.parametrize("lab", ["client"], indirect=True)
def test_dragging_the_pad_moves_the_target_in_the_client_view(lab):
    """vtk.js sends no picks to the kernel: the pad beside the view drags the target."""
    from playwright.sync_api import TimeoutError as PlaywrightTimeout

    base, _ = lab
    with _notebook_page(base, DRAG_NOTEBOOK, "e2e_pad") as page:
        dot = page.locator(".course-drag-pad .course-drag-dot")
        dot.wait_for(state="visible", timeout=60_000)
        view = page.locator("iframe").first
        view.wait_for(state="visible", timeout=60_000)
        dot.scroll_into_view_if_needed()
        page.wait_for_timeout(5000)  # the view's first frame
        draws_before = _webgl_draws(view)
        readouts = page.locator(".widget-slider .widget-readout")
        before = [readouts.nth(k).inner_text() for k in range(3)]
        image_before = drawn_picture(view, ARTIFACTS / "e2e_pad_before.png")
        # (the screenshot scrolled to the view; hovering brings the mouse back to the page.
        # Synthetic mouse events right after a screenshot of the view's iframe are sometimes
        # lost, so the drag is tried up to three times; one of them must move the target)
        moved = False
        for attempt in range(3):
            dot.hover()
            pad = page.locator(".course-drag-pad svg").first.bounding_box()
            # press inside the pad (a press anywhere on it takes the dot there), then drag
            page.mouse.move(pad["x"] + 0.8 * pad["width"], pad["y"] + 0.5 * pad["height"])
            page.mouse.down()
            page.mouse.move(pad["x"] + (0.25 + 0.1 * attempt) * pad["width"],
                            pad["y"] + 0.3 * pad["height"], steps=10)
            page.mouse.up()
            try:
                page.wait_for_function(
                    "([t]) => [...document.querySelectorAll('.widget-slider .widget-readout')]"
                    ".slice(0, 3).map(e => e.innerText).join() !== t", arg=[",".join(before)],
                    timeout=10_000)
                moved = True
                break
            except PlaywrightTimeout:
                page.screenshot(path=str(ARTIFACTS / f"e2e_pad_attempt{attempt}.png"))
        assert moved, "three drags on the pad did not move the target sliders"
        page.wait_for_timeout(3000)
        after = [readouts.nth(k).inner_text() for k in range(3)]
        image_after = drawn_picture(view, ARTIFACTS / "e2e_pad_after.png")
        draws_after = _webgl_draws(view)
        alive = kernel_alive(page)
    assert alive, "the kernel died while the target was dragged"
    assert after != before, "dragging the pad did not move the target sliders"
    assert image_after != image_before, "the 3D view did not change"
    assert draws_after > draws_before, "vtk.js drew nothing after the target moved"


@pytest.mark.parametrize("lab", ["client"], indirect=True)
def test_a_view_shown_before_a_long_cell_still_draws(lab):
    """Run All: a view's page cannot fetch its scene while the kernel runs the next cells;
    once they end (25 s later, beyond the 20 s trame-vtk keeps arrays) it still draws."""
    base, _ = lab
    with _notebook_page(base, LATE_NOTEBOOK, "e2e_late") as page:
        frames = page.locator(".course-view iframe")
        frames.nth(1).wait_for(state="attached", timeout=60_000)
        for k in range(2):
            view = frames.nth(k)
            view.scroll_into_view_if_needed()
            try:
                webgl_drawn(view.element_handle().content_frame(), 30_000)
            except Exception:
                view.screenshot(path=str(ARTIFACTS / f"e2e_late_view{k}_never_drawn.png"))
                raise AssertionError(f"view {k} never drew: its page found its arrays gone"
                                     ) from None
