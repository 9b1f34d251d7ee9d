"""Frames per second each scene draws in Chromium while the camera is dragged (software WebGL when no GPU is present).

    python bench/bench_browser_fps.py                      # every scene at 1280×720
    python bench/bench_browser_fps.py --scenes arm --sizes 1280x720 1600x1000

For each scene the app serves, the page is opened in Debian's Chromium (the browser tests' settings), the scene
settles, and the camera is orbited by a left-button mouse drag across the canvas for ``seconds`` (one mouse move every
16 ms, as a hand moves). Every frame three.js draws is timed in the page (``scene.onAfterRender``). Printed per scene:
frames drawn, frames per second over the drag, the median and p95 interval between frames (ms), and the canvas's
drawing width (viser's client lowers its resolution while frames are slow; "held" rows keep the full resolution, as
the browser tests do). The WebGL renderer string says whether it was software (SwiftShader) or a GPU.
"""

from __future__ import annotations

import itertools
import os
import statistics
import sys
import time
from pathlib import Path
from typing import Any

import tyro

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

from helpers.browser import panel_rect, scene_page  # noqa: E402
from helpers.ci import chromium_context  # noqa: E402

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


def report(key: str, size: tuple[int, int], mode: str, frames: list[float], seconds: float, width: int) -> None:
    intervals = [b - a for a, b in itertools.pairwise(frames)]
    if len(intervals) < 2:
        print(
            f"| {key} | {size[0]}×{size[1]} | {mode} | {len(frames)} | {len(frames) / seconds:.1f} | – | – | {width} |"
        )
        return
    fps = (len(frames) - 1) / ((frames[-1] - frames[0]) / 1000.0)
    ordered = sorted(intervals)
    p95 = ordered[min(len(ordered) - 1, round(0.95 * (len(ordered) - 1)))]
    print(
        f"| {key} | {size[0]}×{size[1]} | {mode} | {len(frames)} | {fps:.1f} | {statistics.median(intervals):.0f} | "
        f"{p95:.0f} | {width} |"
    )


def main(scenes: tuple[str, ...] = (), sizes: tuple[str, ...] = ("1280x720",), seconds: float = 4.0) -> None:
    """Measure frames per second while orbiting the camera.

    Args:
        scenes: scene keys; empty means all.
        sizes: window sizes, WIDTHxHEIGHT in CSS px.
        seconds: how long each drag lasts.
    """
    keys = list(scenes) or list(SCENES)
    load = os.getloadavg()[0]
    with chromium_context() as context:
        probe = context.new_page()
        renderer = probe.evaluate(RENDERER)
        probe.close()
        print(f"Chromium WebGL renderer: {renderer}; load average {load:.2f} on {os.cpu_count()} cores\n")
        print("| scene | window | resolution | frames | frames/s | median ms | p95 ms | canvas px wide |")
        print("|---|---|---|---:|---:|---:|---:|---:|")
        for key in keys:
            for text in sizes:
                width, height = (int(v) for v in text.split("x"))
                with scene_page(context, key, (width, height)) as shown:
                    page = shown.page
                    frames = orbit(page, seconds)
                    drawn = int(page.evaluate("() => window.__viserMutable.canvas.width"))
                    report(key, (width, height), "held", frames, seconds, drawn)
                    page.evaluate("() => window.__viserTestpoints.devSettings.set({ fixedDpr: null })")
                    orbit(page, 2.0)  # let viser's client settle its own resolution
                    frames = orbit(page, seconds)
                    drawn = int(page.evaluate("() => window.__viserMutable.canvas.width"))
                    report(key, (width, height), "adaptive", frames, seconds, drawn)


if __name__ == "__main__":
    tyro.cli(main)
