"""Frames per second each scene draws in Chromium while the camera is dragged (software WebGL when no GPU is present).

    python bench/bench_browser_fps.py                      # every case at 1280×720, each run twice
    python bench/bench_browser_fps.py --scenes arm peloton-bunch --sizes 1280x720 1600x1000 --repeats 3

For each scene the app serves, the page is opened in Debian's Chromium (the browser tests' settings), the scene
settles, and the camera is orbited by a left-button mouse drag across the canvas for ``seconds`` (one mouse move every
16 ms, as a hand moves). Every frame three.js draws is timed in the page (``scene.onAfterRender``). Printed per scene:
frames drawn, frames per second over the drag, the median and p95 interval between frames (ms), and the canvas's
drawing width (viser's client lowers its resolution while frames are slow; "held" rows keep the full resolution, as
the browser tests do). The WebGL renderer string says whether it was software (SwiftShader) or a GPU.

The cases are the scenes as they open, plus ``peloton-bunch``: the peloton with Formation set to a bunch and Riders
to 121 through the page, as a person sets them, and ``sdf-both``: the SDF gallery's View set to Both. Each case runs
``repeats`` times (a fresh page each time) and a last table gives the median frames per second of its runs: on a machine
shared with other work one run can be unlucky.
"""

from __future__ import annotations

import itertools
import os
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import tyro

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

from helpers.browser import ScenePage, control_row, panel_rect, scene_page, set_number, settle  # noqa: E402
from helpers.ci import chromium_context  # noqa: E402
from helpers.waiting import wait_until  # noqa: E402

from scenes import SCENES  # noqa: E402

COUNT_FRAMES = """
() => {
  const scene = window.__viserMutable.scene;
  window.__benchFrames = [];
  scene.onAfterRender = () => window.__benchFrames.push(performance.now());
}
"""

RENDERER = """
() => {
  const gl = document.createElement("canvas").getContext("webgl2");
  const info = gl && gl.getExtension("WEBGL_debug_renderer_info");
  return info ? gl.getParameter(info.UNMASKED_RENDERER_WEBGL) : "unknown";
}
"""


def bunch_of_121(shown: ScenePage) -> None:
    """Set the peloton to a bunch of 121 riders through its controls, as a person would, and wait for the picture."""
    page = shown.page
    control_row(page, "Formation").locator("input").first.click()
    page.get_by_role("option", name="Bunch (peloton)").click()
    set_number(page, "Riders", 121)
    wait_until(lambda: shown.scene.params.n_riders == 121 and shown.scene.params.formation == "bunch", "a bunch of 121")
    settle(shown)


def sdf_both(shown: ScenePage) -> None:
    """Set the SDF gallery's View to Both (the ray-march with the mesh's wireframe) through its dropdown."""
    page = shown.page
    control_row(page, "View").locator("input").first.click()
    page.get_by_role("option", name="Both", exact=True).click()
    wait_until(lambda: shown.scene.view_edges > 0, "the ray-march with the wireframe")
    settle(shown)


CASES: dict[str, tuple[str, Callable[[ScenePage], None] | None]] = {
    **{key: (key, None) for key in SCENES},
    "peloton-bunch": ("peloton", bunch_of_121),
    "sdf-both": ("sdf", sdf_both),
}
"""Each case: the scene it opens and what is set on its page before the camera is dragged."""


def orbit(page: Any, seconds: float) -> list[float]:
    """Drag the camera with the left mouse button across the free part of the canvas for ``seconds``; the page's
    frame times (ms) during the drag."""
    left, _top, _right, _bottom = panel_rect(page)
    size = page.viewport_size
    free_right = left if left > size["width"] / 3 else size["width"]
    x0, y = free_right * 0.35, size["height"] * 0.55
    page.evaluate(COUNT_FRAMES)
    page.mouse.move(x0, y)
    page.mouse.down()
    start = time.perf_counter()
    step = 0
    while time.perf_counter() - start < seconds:
        swing = (step % 60) / 60.0  # back and forth over a third of the free width
        x = x0 + free_right * 0.3 * (swing if (step // 60) % 2 == 0 else 1.0 - swing)
        page.mouse.move(x, y + 20.0 * ((step % 20) / 20.0))
        step += 1
        time.sleep(max(0.0, step * 0.016 - (time.perf_counter() - start)))
    page.mouse.up()
    return list(page.evaluate("() => window.__benchFrames"))


def report(key: str, size: tuple[int, int], mode: str, frames: list[float], seconds: float, width: int) -> float:
    """Print one row; return its frames per second."""
    intervals = [b - a for a, b in itertools.pairwise(frames)]
    if len(intervals) < 2:
        print(
            f"| {key} | {size[0]}×{size[1]} | {mode} | {len(frames)} | {len(frames) / seconds:.1f} | – | – | {width} |"
        )
        return len(frames) / seconds
    fps = (len(frames) - 1) / ((frames[-1] - frames[0]) / 1000.0)
    ordered = sorted(intervals)
    p95 = ordered[min(len(ordered) - 1, round(0.95 * (len(ordered) - 1)))]
    print(
        f"| {key} | {size[0]}×{size[1]} | {mode} | {len(frames)} | {fps:.1f} | {statistics.median(intervals):.0f} | "
        f"{p95:.0f} | {width} |",
        flush=True,
    )
    return fps


def main(
    scenes: tuple[str, ...] = (), sizes: tuple[str, ...] = ("1280x720",), seconds: float = 4.0, repeats: int = 2
) -> None:
    """Measure frames per second while orbiting the camera.

    Args:
        scenes: cases (scene keys, or ``peloton-bunch``); empty means all.
        sizes: window sizes, WIDTHxHEIGHT in CSS px.
        seconds: how long each drag lasts.
        repeats: runs of each case, each on a fresh page.
    """
    keys = list(scenes) or list(CASES)
    loads = [os.getloadavg()[0]]
    fps: dict[tuple[str, str, str], list[float]] = {}
    with chromium_context() as context:
        probe = context.new_page()
        renderer = probe.evaluate(RENDERER)
        probe.close()
        print(f"Chromium WebGL renderer: {renderer}; load average {loads[0]:.2f} on {os.cpu_count()} cores\n")
        print("| case | window | resolution | frames | frames/s | median ms | p95 ms | canvas px wide |")
        print("|---|---|---|---:|---:|---:|---:|---:|")
        for _run, key, text in itertools.product(range(repeats), keys, sizes):
            scene_key, prepare = CASES[key]
            width, height = (int(v) for v in text.split("x"))
            with scene_page(context, scene_key, (width, height)) as shown:
                page = shown.page
                if prepare is not None:
                    prepare(shown)
                loads.append(os.getloadavg()[0])
                frames = orbit(page, seconds)
                drawn = int(page.evaluate("() => window.__viserMutable.canvas.width"))
                fps.setdefault((key, text, "held"), []).append(
                    report(key, (width, height), "held", frames, seconds, drawn)
                )
                page.evaluate("() => window.__viserTestpoints.devSettings.set({ fixedDpr: null })")
                orbit(page, 2.0)  # let viser's client settle its own resolution
                frames = orbit(page, seconds)
                drawn = int(page.evaluate("() => window.__viserMutable.canvas.width"))
                fps.setdefault((key, text, "adaptive"), []).append(
                    report(key, (width, height), "adaptive", frames, seconds, drawn)
                )
    print(f"\nMedian over {repeats} runs; load average (1 min) {min(loads):.1f}–{max(loads):.1f} during the runs\n")
    print("| case | window | resolution | frames/s, each run | median frames/s |")
    print("|---|---|---|---|---:|")
    for (key, text, mode), values in fps.items():
        runs = ", ".join(f"{v:.1f}" for v in values)
        print(f"| {key} | {text.replace('x', '×')} | {mode} | {runs} | {statistics.median(values):.1f} |")


if __name__ == "__main__":
    tyro.cli(main)
