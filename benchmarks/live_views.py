"""From a key press to the new 3D frame in the browser: the live views as a student feels them.

JupyterLab runs in headless Chromium (Debian's ``chromium``); for the FK explorer, the IK
playground and BVH playback, the script focuses a slider, presses the right arrow key 30
times and, for each press, takes the time from the key event to the first new picture of the
3D view, both measured in the page (a key listener; an ``<img>`` load or a WebGL draw call,
see ``tests/e2e/labkit.py``), never by polling screenshots. Each view is measured with every
backend asked for, in the same run: ``static`` (PNG images), ``server`` (trame, rendered in
the kernel) and ``default`` (what a student gets without configuring anything). Holding the key for
2 s (a press every 33 ms, like a fast drag) gives the pictures per second drawn and the lag
from the last press to the last picture of the drag, where a backlog would show. BVH playback
also reports the pictures per second while playing, the frame skip the player chose (its
readout), and the pictures still arriving in the 3 s after pause (a backlog).

    .venv/bin/python benchmarks/live_views.py [--steps 30] [--backends static,server,default]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import nbformat
import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tests" / "e2e"))

import labkit  # noqa: E402

VIEWS = {
    "fk_explorer": ("3-bone chain", """
from course.skeleton import chain
from course.viz import fk_explorer
view = fk_explorer(chain([1.0, 0.8, 0.5], axes=[0, 0, 1]))
view""", "z"),
    "ik_playground": ("5-bone chain, dls", """
from course.skeleton import chain
from course.viz import ik_playground
view = ik_playground(chain([1.0] * 5, axes=[0, 0, 1]), methods=["dls"])
view""", "target y"),
    "full_body_ik": ("CMU 12_01 walk, 2 hands, fabrik (notebook 06)", """
from course import data
from course.viz import full_body_ik
view = full_body_ik(data.load("cmu_12_01_walk"), 0, root="LowerBack",
                    effectors=["LeftHandIndex1_end", "RightHandIndex1_end"], method="fabrik")
view""", "target y"),
    "bvh_player": ("CMU 12_01 walk", """
from course import data
from course.viz import bvh_player
view = bvh_player(data.load("cmu_12_01_walk"))
view""", "frame"),
}


def _notebook(backend: str, code: str) -> nbformat.NotebookNode:
    setup = ("import os\n" + (f"os.environ['PYVISTA_JUPYTER_BACKEND'] = {backend!r}"
                              if backend != "default"
                              else "os.environ.pop('PYVISTA_JUPYTER_BACKEND', None)"))
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell(setup), nbformat.v4.new_code_cell(code.strip())]
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3",
                                 "language": "python"}
    return nb


def _now(page) -> float:
    return page.evaluate("performance.timeOrigin + performance.now()")


def _settle(page, quiet_ms: float = 400.0, limit_s: float = 15.0) -> None:
    """Wait until no new picture arrived for ``quiet_ms``."""
    start = time.monotonic()
    last = _now(page)
    while time.monotonic() - start < limit_s:
        time.sleep(0.1)
        newer = labkit.frames_after(page, last)
        if newer:
            last = newer[-1]
        elif _now(page) - last > quiet_ms:
            return


def _steps(page, label: str, steps: int) -> tuple[list[float], list[float]]:
    """Press the right arrow ``steps`` times on the slider ``label``, each once the view is
    still (trame's whole-scene refresh, 1 s after a change, included): per press the time
    to the first new picture, and to the last one of its burst (a view that shows a long
    solve's pose at once and its end later settles there; pictures 0.4 s apart or more
    are another burst)."""
    handle = page.locator(f".widget-slider:has(.widget-label:text-is('{label}')) .noUi-handle")
    handle = handle.first
    handle.scroll_into_view_if_needed()
    handle.focus()
    first, settled = [], []
    for _ in range(steps):
        _settle(page, quiet_ms=1200)
        n_keys = page.evaluate("window.__keys.length")
        page.keyboard.press("ArrowRight")
        page.wait_for_function(f"window.__keys.length > {n_keys}", timeout=5000)
        key = page.evaluate("window.__keys[window.__keys.length - 1]")
        deadline = time.monotonic() + 10
        frames: list[float] = []
        while not frames and time.monotonic() < deadline:
            time.sleep(0.005)
            frames = labkit.frames_after(page, key)
        if not frames:
            first.append(float("nan"))
            settled.append(float("nan"))
            continue
        _settle(page, quiet_ms=400)
        burst = [frames[0]]
        for t in labkit.frames_after(page, frames[0]):
            if t - burst[-1] >= 400:
                break
            burst.append(t)
        first.append(frames[0] - key)
        settled.append(burst[-1] - key)
    return first, settled


def _hold(page, label: str, seconds: float = 2.0, every_s: float = 0.033) -> tuple[float, float]:
    """Hold the right arrow key on a slider (a key press every ``every_s``, as a key's
    auto-repeat or a fast drag sends): the pictures per second drawn meanwhile, and the lag
    from the last press to the last picture (a backlog shows as a long lag)."""
    handle = page.locator(f".widget-slider:has(.widget-label:text-is('{label}')) .noUi-handle")
    handle.first.focus()
    _settle(page)
    t0 = _now(page)
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        page.keyboard.press("ArrowRight")
        time.sleep(every_s)
    t1 = page.evaluate("window.__keys[window.__keys.length - 1]")
    _settle(page, quiet_ms=1500, limit_s=30)
    frames = _pictures(labkit.frames_after(page, t0))
    during = [t for t in frames if t <= t1]
    last = t1  # the pictures still coming after the last press, ~1 s apart from trame's
    for t in frames[len(during):]:  # whole-scene refresh of the same state, not counted
        if t - last > 500:
            break
        last = t
    return len(during) / ((t1 - t0) / 1000), last - t1


def _pictures(times: list[float], gap_ms: float = 20.0) -> list[float]:
    """Draw marks closer than ``gap_ms`` are one picture (a render may draw in two passes)."""
    out: list[float] = []
    for t in times:
        if not out or t - out[-1] > gap_ms:
            out.append(t)
    return out


def _playback(page, seconds: float = 4.0) -> tuple[float, str, int, int]:
    """Pictures per second while playing, the frame skip the readout names, and the pictures
    in the 3 s after pause: within 0.6 s (already on their way when pause was pressed; a
    backlog would show as many more) and later (trame's whole-scene refresh, one second
    after the last change, redraws the same frame)."""
    play = page.locator(".course-play")
    older = not play.count()  # an older checkout: the browser-side Play widget
    if older:
        play = page.locator(".widget-play button")
    _settle(page)
    play.first.click()
    t0 = _now(page)
    time.sleep(seconds)
    skip = page.locator(".widget-html-content").filter(has_text="frame ").last.inner_text()
    (play.nth(1) if older else play.first).click()
    t1 = _now(page)
    time.sleep(3.0)
    frames = _pictures(labkit.frames_after(page, t0))
    during = [t for t in frames if t <= t1]
    soon = [t for t in frames if t1 < t <= t1 + 600]
    skip = skip.split("showing ")[-1] if "showing " in skip else "not shown"
    return (len(during) / ((t1 - t0) / 1000), skip, len(soon),
            len(frames) - len(during) - len(soon))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--steps", type=int, default=30)
    parser.add_argument("--backends", default="static,server,default")
    parser.add_argument("--views", default=",".join(VIEWS))
    parser.add_argument("--course", help="measure the `course` package in this folder "
                        "(e.g. an older checkout) instead of this one")
    args = parser.parse_args()
    if labkit.chromium() is None:
        sys.exit("needs chromium (apt-get install chromium)")
    from playwright.sync_api import sync_playwright

    backends = args.backends.split(",")
    views = args.views.split(",")
    results: dict[tuple[str, str], list[float]] = {}
    settled: dict[tuple[str, str], list[float]] = {}
    playback: dict[str, tuple[float, str, int, int]] = {}
    held: dict[tuple[str, str], tuple[float, float]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        for b in backends:
            for v in views:
                nbformat.write(_notebook(b, VIEWS[v][1]), root / f"{v}_{b}.ipynb")
        env = {}
        if args.course:
            env = {"PYTHONPATH": str(Path(args.course).resolve()),
                   "COURSE_DATA_DIR": str(REPO.parent / "shared" / "data" / "bvh")}
        with labkit.lab_server(root, env) as base, sync_playwright() as p:
            browser = labkit.launch_browser(p)
            for v in views:
                for b in backends:
                    page = labkit.open_notebook(browser, base, f"{v}_{b}.ipynb")
                    try:
                        errors = page.locator(".jp-OutputArea-output[data-mime-type="
                                              "'application/vnd.jupyter.stderr']")
                        if errors.count():
                            print(errors.first.inner_text()[-2000:])
                        page.locator(".course-view, .jp-OutputArea-output iframe, "
                                     ".jp-OutputArea-output .widget-image").first.wait_for(
                                         timeout=60_000)
                        time.sleep(3.0)  # the first picture of a live view
                        results[v, b], settled[v, b] = _steps(page, VIEWS[v][2], args.steps)
                        held[v, b] = _hold(page, VIEWS[v][2])
                        if v == "bvh_player":
                            playback[b] = _playback(page)
                    finally:
                        labkit.shutdown_kernel(page)
                        page.context.close()
                    lat = np.array(results[v, b])
                    print(f"  {v:<14} {b:<8} median {np.nanmedian(lat):7.1f} ms   "
                          f"p90 {np.nanpercentile(lat, 90):7.1f} ms   "
                          f"(missed {int(np.isnan(lat).sum())})", flush=True)
            browser.close()

    print(f"\nkey press -> new 3D frame in the browser, {args.steps} steps "
          "(ratio: against static in this run)")
    for v in views:
        print(f"{v} ({VIEWS[v][0]})")
        ref = np.nanmedian(results[v, "static"]) if (v, "static") in results else None
        for b in backends:
            lat = np.array(results[v, b])
            med = float(np.nanmedian(lat))
            ratio = f"  x{med / ref:5.2f} of static" if ref else ""
            done = np.array(settled[v, b])
            print(f"  {b:<8} median {med:7.1f} ms   p90 {np.nanpercentile(lat, 90):7.1f} ms"
                  f"{ratio}   settled: median {np.nanmedian(done):7.1f} ms   "
                  f"p90 {np.nanpercentile(done, 90):7.1f} ms")
    print("\nthe right arrow held for 2 s (a press every 33 ms): pictures/s drawn, and the lag "
          "from the last press to the last picture")
    for (v, b), (rate, lag) in held.items():
        print(f"  {v:<14} {b:<8} {rate:5.1f} pictures/s   last picture {lag:7.1f} ms after")
    if playback:
        print("\nbvh_player playback (at most 30 pictures/s asked for, the skip adapted)")
        for b, (pictures, skip, soon, later) in playback.items():
            print(f"  {b:<8} {pictures:5.1f} pictures/s shown ({skip}); after pause: "
                  f"{soon} within 0.6 s, {later} later")


if __name__ == "__main__":
    main()
