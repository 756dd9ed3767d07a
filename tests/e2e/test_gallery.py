"""The gallery: every notebook and assignment notebook as a student sees it.

Each notebook (found by glob, so new ones join by themselves) is opened in one live
JupyterLab in headless Chromium with the default 3D view, all cells run, and for every
interactive view at 1366x768 and again at 1920x1080, each time with the notebook alone (the
file browser collapsed) and beside JupyterLab's file browser (how Lab opens, ~250 px less
for the notebook):

- the view and its controls lie inside the output area and inside the window's width, and
  no box around the view that clips (``overflow`` not visible) cuts it,
- with the notebook alone, the whole output (view, sliders, readouts, plots under it) is no
  taller than the part of the notebook the window shows, so a student sees all of it at
  once (beside the file browser a view may wrap under its panel: it stays whole),
- no visible button has zero height,
- the picture is not blank; in a 3D view what is drawn in colour (the skeleton, its joints,
  the target, the frames' arrows) keeps clear of the view's edges and spans at least a
  quarter of its shorter side; a view drawn in the browser has made WebGL draw calls, and
  one rendered in the kernel has shown a streamed image (trame's animated "Loading..."
  spinner changes pixels too, but is neither);

then, at 1366x768 with the notebook alone, the first slider of the view is moved to both ends
(Home, End) and all of it is checked again (every view is shot at its start at both sizes,
in both layouts, before anything moves).
An interactive view is a 3D view (``.course-view``) or, in an output with a slider or a play
button and no 3D view, its largest image: a matplotlib explorer (11's Runge and spline
explorers), found without any class so that a new one cannot be missed. A gimbal explorer
(01) is also set to Y = 90 degrees: the lock warning shows, and the view, the rings picture
and the controls stay inside the output where they were. Some shots must exist
(``REQUIRED``: 04's pole scene at both ends of its slider, the a2 walk at its first and last
frame, 11's two explorers), so a view that stops answering its slider cannot drop out
unnoticed. Every screenshot goes into ``tests/e2e/artifacts/gallery.html``, one page to
scan. Notebooks run a few at a time in one browser; ``GALLERY_ONLY=01_,a2`` runs those whose
path contains one of the comma-separated parts (a quick look at what you changed).
"""

from __future__ import annotations

import asyncio
import html
import io
import json
import os
import re
import shutil
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest
from labkit import (
    ALL_RUN,
    FRAME_PROBE,
    KERNEL_IDLE,
    REPO,
    RUN_ALL,
    TOKEN,
    chromium,
    lab_server,
    webgl_drawn,
)

ARTIFACTS = Path(__file__).resolve().parent / "artifacts"
ONLY = [part for part in os.environ.get("GALLERY_ONLY", "").split(",") if part]
NOTEBOOKS = sorted(
    nb for nb in
    [p.relative_to(REPO).as_posix() for p in (REPO / "notebooks").glob("[0-9]*.ipynb")]
    + [p.relative_to(REPO).as_posix() for p in (REPO / "assignments").glob("*.ipynb")]
    if not ONLY or any(part in nb for part in ONLY)
)
# shots that must be taken (prefixes of a shot's state), by notebook
REQUIRED = {
    "notebooks/01_rotations.ipynb": ("Y=90",),
    "notebooks/04_two_link_ik.ipynb": ("min (pole angle", "max (pole angle"),
    "assignments/a2_forward_kinematics.ipynb": ("min (frame", "max (frame"),
    "notebooks/11_keyframes.ipynb": ("min (keys n", "min (p0"),
    "notebooks/13_rigid_bodies.ipynb": ("min (time step h", "max (time step h"),
    "notebooks/15_walking.ipynb": ("min (speed", "max (speed"),
    "notebooks/16_optimal_control.ipynb": ("min (Q COM", "max (Q COM"),
}
SIZES = ((1366, 768), (1920, 1080))
# the notebook alone, then beside the file browser (``.shell`` calls; the state a shot names)
LAYOUTS = (("collapseLeft", ""), ("expandLeft", ", beside the file browser"))
PARALLEL = int(os.environ.get("GALLERY_PARALLEL", "3"))
SETTLE_S = 2.0  # after a change: the kernel answers, the browser draws
FIT_MARGIN = 8  # px the output must leave of the notebook's visible height
# seconds per notebook: opening and Run All, then the shots (in gallery.html: where time goes)
TIMES: dict[str, tuple[float, float]] = {}

# The interactive views, marked ``data-gallery-view="k"`` for the locators: every 3D view, and
# in an output with a slider or a play button but no 3D view its largest image (a figure drawn
# by matplotlib). Returns their kinds in that order, "scene" or "plot".
FIND_VIEWS = """() => {
  const views = [];
  const area = (e) => { const r = e.getBoundingClientRect(); return r.width * r.height; };
  for (const out of document.querySelectorAll('.jp-OutputArea-output')) {
    const scenes = [...out.querySelectorAll('.course-view')];
    const images = [...out.querySelectorAll('.widget-image')];
    if (scenes.length) {
      views.push(...scenes.map(e => [e, 'scene']));
    } else if (images.length && out.querySelector('.widget-slider, .widget-play')) {
      views.push([images.reduce((a, b) => area(b) > area(a) ? b : a), 'plot']);
    }
  }
  views.forEach(([e], k) => e.setAttribute('data-gallery-view', String(k)));
  return views.map(([, kind]) => kind);
}"""

# Geometry of every view's output, from the DOM: the output area, the view, its controls.
GEOMETRY = """(view) => {
  const out = view.closest('.jp-OutputArea-output') || view.parentElement;
  const box = (e) => { const r = e.getBoundingClientRect();
    return {left: r.left, right: r.right, top: r.top, bottom: r.bottom,
            width: r.width, height: r.height}; };
  const shown = (e) => e.offsetParent !== null && getComputedStyle(e).visibility !== 'hidden';
  const controls = [...out.querySelectorAll(
      '.widget-slider, .widget-dropdown, .widget-button, button, .widget-play, .widget-html,'
      + ' .widget-image, .widget-checkbox, .widget-select-multiple, .course-view')].filter(shown);
  // the part of the notebook the window shows (under the toolbar, above the status bar)
  const panel = view.closest('.jp-WindowedPanel-outer') || view.closest('.jp-Notebook');
  // the boxes between the view and the output area that clip what sticks out of them
  const clips = [];
  for (let e = view.parentElement; e && e !== out.parentElement; e = e.parentElement) {
    const style = getComputedStyle(e);
    if (style.overflowX !== 'visible' || style.overflowY !== 'visible') {
      clips.push({cls: e.className.toString().slice(0, 60), ...box(e)});
    }
  }
  return {out: box(out), view: box(view), window: window.innerWidth,
          visible: panel ? panel.clientHeight : window.innerHeight, clips,
          controls: controls.map(e => ({cls: e.className.toString().slice(0, 60), ...box(e)})),
          buttons: [...out.querySelectorAll('button')].filter(shown).map(box)};
}"""


@dataclass
class Shot:
    notebook: str
    size: tuple[int, int]
    view: int
    state: str
    png: str
    problems: list[str] = field(default_factory=list)


def _drawn_box(image: np.ndarray) -> tuple[int, int, int, int] | None:
    """Bounding box (x0, y0, x1, y1) of what is drawn: saturated pixels (skeleton, joints,
    targets, arrows) and dark ones (a grey "before" pose, captions), which the pale
    background and floor never are. Left out: the magenta root path on the floor (a clip's
    whole walk may run out of view) and the corner where a live view keeps its menu button."""
    rgb = image[..., :3].astype(np.int16)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    drawn = ((rgb.max(axis=-1) - rgb.min(axis=-1)) > 70) | (rgb.mean(axis=-1) < 150)
    drawn &= ~((r > g + 60) & (b > g + 30) & (r > b))  # the trail, #d1347a, shaded
    drawn[:70, :70] = False  # the collapsed toolbar button
    ys, xs = np.nonzero(drawn)
    if xs.size < 30:
        return None
    return int(xs.min()), int(ys.min()), int(xs.max()), int(ys.max())


def _check_picture(png: bytes, kind: str) -> list[str]:
    """A plot is not blank; a 3D view also shows a skeleton inside it, large enough."""
    from PIL import Image

    image = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))
    h, w = image.shape[:2]
    if image.std() < 4:
        return ["the picture is blank"]
    if kind == "plot":  # axes, ticks and labels reach its edges by design
        return []
    box = _drawn_box(image)
    if box is None:
        return ["nothing drawn in colour (no skeleton)"]
    x0, y0, x1, y1 = box
    problems = []
    margin = 2
    if x0 < margin or y0 < margin or x1 > w - 1 - margin or y1 > h - 1 - margin:
        problems.append(f"the drawing touches the view's edge (box {box} in {w}x{h})")
    if max(x1 - x0, y1 - y0) < 0.25 * min(w, h):
        problems.append(f"the drawing is small: {max(x1 - x0, y1 - y0)} px "
                        f"< a quarter of {min(w, h)} px")
    return problems


def _check_geometry(g: dict, *, seen_at_once: bool = True) -> list[str]:
    """The view and its controls inside the output area and the window, the view cut by no
    box around it; with ``seen_at_once``, the whole output no taller than the notebook shows."""
    problems = []
    out, tol = g["out"], 1.5
    for c in g["controls"]:
        if c["right"] > g["window"] + tol:
            problems.append(f"{c['cls'] or 'a control'} ends at x={c['right']:.0f}, "
                            f"past the window ({g['window']})")
        elif c["left"] < out["left"] - tol or c["right"] > out["right"] + tol:
            problems.append(f"{c['cls'] or 'a control'} [{c['left']:.0f}, {c['right']:.0f}] "
                            f"leaves the output area [{out['left']:.0f}, {out['right']:.0f}] "
                            f"by {max(out['left'] - c['left'], c['right'] - out['right']):.0f} px")
    v = g["view"]
    for c in g["clips"]:
        if (v["left"] < c["left"] - tol or v["right"] > c["right"] + tol
                or v["top"] < c["top"] - tol or v["bottom"] > c["bottom"] + tol):
            problems.append(f"the view [{v['left']:.0f}, {v['right']:.0f}] x [{v['top']:.0f}, "
                            f"{v['bottom']:.0f}] is cut by its container {c['cls'] or '(a box)'} "
                            f"[{c['left']:.0f}, {c['right']:.0f}] x [{c['top']:.0f}, "
                            f"{c['bottom']:.0f}]")
    if seen_at_once and out["height"] > g["visible"] - FIT_MARGIN:
        problems.append(f"the output is {out['height']:.0f} px tall, the notebook shows "
                        f"{g['visible']} px: it cannot be seen at once")
    if any(b["height"] < 1 for b in g["buttons"]):
        problems.append("a button has zero height")
    if v["width"] < 50 or v["height"] < 50:
        problems.append(f"the view is {v['width']:.0f}x{v['height']:.0f} px")
    return problems


async def _wait_settled(page, seconds: float = SETTLE_S) -> None:
    await page.wait_for_function(KERNEL_IDLE, timeout=60_000)
    await asyncio.sleep(seconds)


async def _first_picture(view, timeout_s: float = 30.0) -> None:
    """Wait until the view shows something (a live view draws a moment after its cell)."""
    from PIL import Image

    deadline = asyncio.get_running_loop().time() + timeout_s
    while asyncio.get_running_loop().time() < deadline:
        image = np.asarray(Image.open(io.BytesIO(await view.screenshot())).convert("RGB"))
        if image.std() >= 4 and _drawn_box(image) is not None:
            return
        await asyncio.sleep(0.5)


def _output(view):
    return view.locator("xpath=ancestor::div[contains(@class, 'jp-OutputArea-output')][1]")


# a picture the kernel rendered reached the iframe (an image loaded or painted, see labkit)
STREAM_SHOWN = "() => (window.__frames || []).length > 0"


async def _live_problems(view) -> list[str]:
    """A live view's iframe shows a picture, not trame's "Loading..." spinner: one the kernel
    chose to draw in the browser (``.course-view-client``) has made WebGL draw calls, one it
    renders itself (``.course-view-server``, e.g. 01's frames with their captions) has shown
    a streamed image."""
    iframe = view.locator("iframe")
    if await iframe.count() == 0:
        return []
    frame = await (await iframe.first.element_handle()).content_frame()
    client = await view.evaluate("e => e.classList.contains('course-view-client')")
    try:
        if client:
            await webgl_drawn(frame, 60_000)
        else:
            await frame.wait_for_function(STREAM_SHOWN, timeout=60_000)
    except Exception:
        return [("vtk.js never drew in the view's iframe (a spinner is not a picture)" if client
                 else "no rendered image reached the view's iframe (a spinner is not a picture)")
                + f"; the iframe: {await _frame_state(frame)}"]
    return []


# what a view's iframe holds when it shows no picture: enough to tell a page that never
# loaded from a scene that never arrived or a canvas with no size
FRAME_STATE = """() => {
  const c = document.querySelector('canvas');
  return {url: location.href, ready: document.readyState, canvases:
          document.querySelectorAll('canvas').length,
          canvas: c ? [c.width, c.height, c.clientWidth, c.clientHeight] : null,
          window: [innerWidth, innerHeight], webgl: window.__webgl ?? null,
          frames: (window.__frames || []).length,
          text: (document.body?.innerText || '').trim().slice(0, 160)};
}"""


async def _frame_state(frame) -> str:
    try:
        return json.dumps(await frame.evaluate(FRAME_STATE))
    except Exception as exc:  # a detached or crashed frame says so
        return f"unreadable ({type(exc).__name__}: {str(exc)[:160]})"


async def _shoot(page, view, shots: list[Shot], notebook: str, size, k: int,
                 state: str, kind: str, *, seen_at_once: bool = True) -> None:
    await view.scroll_into_view_if_needed()
    problems = []
    if state == "start":
        problems += await _live_problems(view)
        await _first_picture(view)
    slug = re.sub(r"[^A-Za-z0-9=]+", "_", state).strip("_")
    name = f"{notebook.replace('/', '_').removesuffix('.ipynb')}_{size[0]}_v{k}_{slug}.png"
    await _output(view).screenshot(path=str(ARTIFACTS / name))
    problems += _check_geometry(await view.evaluate(GEOMETRY), seen_at_once=seen_at_once)
    problems += _check_picture(await view.screenshot(), kind)
    shots.append(Shot(notebook, size, k, state, name, problems))


async def _slider_end(page, view, key: str) -> str | None:
    """Press ``key`` on the output's first slider; its label, or None when it has none."""
    sliders = _output(view).locator(".widget-slider")
    if await sliders.count() == 0:
        return None
    handle = sliders.first.locator(".noUi-handle")
    if not await handle.is_visible():
        return None
    await handle.focus()
    await page.keyboard.press(key)
    return (await sliders.first.locator(".widget-label").inner_text()).strip()


async def _type_into_slider(page, slider, value: str) -> None:
    """Type ``value`` into a slider's editable readout (what a student can do too)."""
    readout = slider.locator(".widget-readout")
    await readout.click()
    await page.keyboard.press("Control+A")
    await page.keyboard.type(value)
    await page.keyboard.press("Enter")
    await readout.evaluate("e => e.blur()")  # no focus ring in the next shot


# where the view, the rings picture and the warning are in their output area, from the DOM
# (relative to it: a scroll of the notebook between two readings moves nothing)
BOXES = """(view) => {
  const out = view.closest('.jp-OutputArea-output');
  const o = out.getBoundingClientRect();
  const r = (e) => { const b = e.getBoundingClientRect();
    return [b.left - o.left, b.top - o.top, b.width, b.height].map(Math.round); };
  const rings = [...out.querySelectorAll('.widget-image')].filter(e => !e.closest('.course-view'));
  const warning = [...out.querySelectorAll('.widget-html')].find(
    e => e.innerText.includes('Gimbal lock'));
  return {view: r(view), rings: rings.map(r), warning: warning ? r(warning) : null,
          out: r(out), ringsLoaded: rings.every(e => e.naturalWidth > 0)};
}"""


async def _gimbal_lock(page, view, shots: list[Shot], notebook: str, size, k: int) -> None:
    """A gimbal explorer (a slider "Y (#2)" and a rings picture) at Y = 90 degrees: the
    warning shows; the view, the rings and the controls stay inside the output, unmoved."""
    slider = _output(view).locator(".widget-slider").filter(
        has=page.locator(".widget-label", has_text="(#2)"))
    if await slider.count() == 0:
        return
    slider = slider.first
    start = (await slider.locator(".widget-readout").inner_text()).strip()
    before = await view.evaluate(BOXES)
    await _type_into_slider(page, slider, "90")
    await _wait_settled(page)
    await _shoot(page, view, shots, notebook, size, k, "Y=90", "scene")
    after = await view.evaluate(BOXES)
    problems = shots[-1].problems
    if after["warning"] is None:
        problems.append("no gimbal-lock warning at Y = 90")
    if not after["rings"] or not after["ringsLoaded"]:
        problems.append("the rings picture is not shown")
    for name in ("view", "rings"):
        if before[name] != after[name]:
            problems.append(f"the {name} moved at Y = 90: {before[name]} -> {after[name]}")
    out = after["out"]
    for box in [*after["rings"], *([after["warning"]] if after["warning"] else [])]:
        if box[0] < out[0] - 1 or box[0] + box[2] > out[0] + out[2] + 1:
            problems.append(f"the rings or the warning {box} leave the output {out}")
    await _type_into_slider(page, slider, start)  # back where it was, for the next size
    await _wait_settled(page, 1.0)


async def _layout(page, shell_call: str) -> None:
    """The notebook alone (``collapseLeft``) or beside the file browser (``expandLeft``);
    the views settle into their new width (a vtk.js view draws again at its new size)."""
    await page.evaluate(f"() => window.jupyterapp.shell.{shell_call}?.()")
    await asyncio.sleep(1.5)


async def _shoot_views(page, kinds: list[str], shots: list[Shot], notebook: str) -> None:
    """Every view at its start at every size and in both layouts first, before anything
    moves (a start typed back into a slider is only as exact as its readout: a re-solve,
    other numbers); then the moves, with the notebook alone: Y = 90 at every size, the
    slider's ends at the small one, where space is tight. The layouts alternate from one
    size to the next, so each size starts in the layout the last one ended in and the
    moves start with the notebook alone: two layout changes, not one per layout and size."""
    if not kinds:  # nothing to shoot: no layout or viewport to wait for
        return
    layouts = LAYOUTS
    for size in SIZES:
        await page.set_viewport_size({"width": size[0], "height": size[1]})
        await asyncio.sleep(1.0)
        for j, (shell_call, where) in enumerate(layouts):
            if j:  # the first is the one the page is in (it opens with the notebook alone)
                await _layout(page, shell_call)
            for k, kind in enumerate(kinds):
                view = page.locator(f"[data-gallery-view='{k}']")
                # beside the file browser a view may wrap under its panel: whole, not at once
                await _shoot(page, view, shots, notebook, size, k, "start" + where, kind,
                             seen_at_once=not where)
        layouts = layouts[::-1]
    if layouts[0] != LAYOUTS[0]:  # an odd number of sizes ends beside the file browser
        await _layout(page, LAYOUTS[0][0])
    for size in reversed(SIZES):
        await page.set_viewport_size({"width": size[0], "height": size[1]})
        await asyncio.sleep(1.0)
        for k, kind in enumerate(kinds):
            view = page.locator(f"[data-gallery-view='{k}']")
            await view.scroll_into_view_if_needed()  # where its start was shot
            await _gimbal_lock(page, view, shots, notebook, size, k)
            if size != SIZES[0]:
                continue
            for key, state in (("Home", "min"), ("End", "max")):
                label = await _slider_end(page, view, key)
                if label is None:
                    break
                await _wait_settled(page)
                await _shoot(page, view, shots, notebook, size, k, f"{state} ({label})", kind)


async def _gallery_of(browser, base: str, notebook: str) -> list[Shot]:
    shots: list[Shot] = []
    context = await browser.new_context(viewport=dict(zip(("width", "height"), SIZES[0],
                                                          strict=True)))
    await context.add_init_script(FRAME_PROBE)
    page = await context.new_page()
    clock = asyncio.get_running_loop().time
    start = ran = clock()
    try:
        await page.goto(f"{base}/lab/tree/{notebook}?reset&token={TOKEN}")
        for attempt in range(3):  # on a busy machine a kernel can miss its start: reload
            try:
                await page.wait_for_function(
                    "window.jupyterapp && document.querySelector('.jp-Notebook')",
                    timeout=120_000)
                await page.wait_for_function(KERNEL_IDLE, timeout=120_000)
                break
            except Exception:
                if attempt == 2:
                    raise
                await page.reload()
        # one column for the notebook: no file browser beside it
        await page.evaluate("() => window.jupyterapp.shell.collapseLeft?.()")
        await page.evaluate(RUN_ALL)
        await page.wait_for_function(ALL_RUN, timeout=300_000, polling=500)
        await _wait_settled(page, 4.0)
        tracebacks = await page.locator(".jp-OutputArea-output[data-mime-type="
                                        "'application/vnd.jupyter.error']").all_inner_texts()
        if tracebacks:
            shots.append(Shot(notebook, SIZES[0], -1, "run", "", [
                f"a cell failed: {tracebacks[0][-300:]}"]))
        ran = clock()
        kinds = await page.evaluate(FIND_VIEWS)
        await _shoot_views(page, kinds, shots, notebook)
        missing = [s for s in REQUIRED.get(notebook, ())
                   if not any(shot.state.startswith(s) for shot in shots)]
        if missing:
            shots.append(Shot(notebook, SIZES[0], -1, "required", "", [
                f"no shot of {', '.join(missing)} (is the view or its slider gone?)"]))
    except Exception as exc:  # recorded, so one notebook does not hide the others
        name = f"{notebook.replace('/', '_').removesuffix('.ipynb')}_failure.png"
        try:
            await page.screenshot(path=str(ARTIFACTS / name), full_page=True)
        except Exception:
            name = ""
        shots.append(Shot(notebook, SIZES[0], -1, "failure", name, [f"{type(exc).__name__}: {exc}"
                                                                    [:400]]))
    finally:
        try:
            await page.evaluate(
                "() => window.jupyterapp.shell.currentWidget?.sessionContext?.shutdown()")
        except Exception:
            pass
        await context.close()
        TIMES[notebook] = (ran - start, clock() - ran)
    return shots


async def _run_all(base: str) -> dict[str, list[Shot]]:
    from playwright.async_api import async_playwright

    limit = asyncio.Semaphore(PARALLEL)
    async with async_playwright() as p:
        browser = await p.chromium.launch(
            executable_path=chromium(),
            args=["--headless", "--no-sandbox", "--disable-background-networking",
                  "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                  "--disable-renderer-backgrounding", "--disable-background-timer-throttling",
                  "--disable-backgrounding-occluded-windows"])

        async def one(nb: str) -> list[Shot]:
            async with limit:
                return await _gallery_of(browser, base, nb)

        results = await asyncio.gather(*(one(nb) for nb in NOTEBOOKS))
        await browser.close()
    return dict(zip(NOTEBOOKS, results, strict=True))


def _write_gallery(results: dict[str, list[Shot]]) -> Path:
    rows = []
    for notebook, shots in results.items():
        cells = []
        for s in shots:
            verdict = ("<span class=ok>ok</span>" if not s.problems else
                       "<span class=bad>" + "<br>".join(html.escape(p) for p in s.problems)
                       + "</span>")
            image = f"<a href='{s.png}'><img src='{s.png}'></a>" if s.png else ""
            cells.append(f"<figure>{image}<figcaption>{s.size[0]}&times;{s.size[1]} view "
                         f"{s.view} {s.state}: {verdict}</figcaption></figure>")
        if not shots:
            cells.append("<p>no interactive view</p>")
        run, shoot = TIMES.get(notebook, (0.0, 0.0))
        rows.append(f"<section><h2>{html.escape(notebook)}</h2><p>opened and run in {run:.0f} s,"
                    f" shot in {shoot:.0f} s</p>{''.join(cells)}</section>")
    page = ("<!doctype html><meta charset=utf-8><title>course-kinematics: the live views</title>"
            "<style>body{font:14px sans-serif;margin:16px}section{margin-bottom:18px}"
            "figure{display:inline-block;margin:4px;vertical-align:top;max-width:460px}"
            "img{max-width:460px;max-height:300px;border:1px solid #ccd}"
            ".ok{color:#1a7f37}.bad{color:#b42318;font-weight:bold}</style>"
            "<h1>The live views, as a student sees them</h1>"
            f"<p>{len(results)} notebooks, window sizes "
            f"{', '.join(f'{w}x{h}' for w, h in SIZES)}; each view at its start (both sizes, "
            "the notebook alone and beside the file browser, before anything moves), and "
            f"with its first slider at both ends ({SIZES[0][0]}, the notebook alone).</p>"
            + "".join(rows))
    path = ARTIFACTS / "gallery.html"
    path.write_text(page)
    (ARTIFACTS / "times.json").write_text(json.dumps(TIMES, indent=1))
    return path


@pytest.fixture(scope="module")
def gallery(tmp_path_factory):
    if chromium() is None:
        message = "chromium not found: apt-get install chromium (make e2e does it as root)"
        if os.environ.get("CI", "").lower() == "true":
            pytest.fail(message)
        pytest.skip(message)
    root = tmp_path_factory.mktemp("gallery")
    for folder in ("notebooks", "assignments"):
        shutil.copytree(REPO / folder, root / folder,
                        ignore=shutil.ignore_patterns(".ipynb_checkpoints", "__pycache__"))
    shutil.rmtree(ARTIFACTS, ignore_errors=True)
    ARTIFACTS.mkdir(parents=True)
    (ARTIFACTS / ".gitignore").write_text("*\n")
    # the view a student gets: no backend forced (the Makefile's static is for nbval)
    with lab_server(root, {"PYVISTA_JUPYTER_BACKEND": ""}) as base:
        results = asyncio.run(_run_all(base))
    _write_gallery(results)
    return results


@pytest.mark.parametrize("notebook", NOTEBOOKS)
def test_every_view_is_framed_unclipped_and_drawn(gallery, notebook):
    problems = [f"{s.size[0]}x{s.size[1]} view {s.view} ({s.state}): {p}"
                for s in gallery[notebook] for p in s.problems]
    assert not problems, "\n".join(problems) + f"\n(see {ARTIFACTS / 'gallery.html'})"
