"""Benchmark peloton formations: the wake model, and a slider change to the 121-rider picture.

    python bench/bench_formation.py            # kernel and server rows
    python bench/bench_formation.py --browser  # also frames per second in Chromium (software WebGL), 1280×720

Prints a table of median and p95: ``formation_drag`` for 8, 121 and 200 riders (goal ≤ 1 ms at 121); the server's
handling of a speed change with a 121-rider bunch shown (callback to redraw, goal p95 ≤ 16 ms) and the round trip
from the slider message to the redrawn table arriving at a websocket client; with ``--browser``, frames per second
that Chromium draws while the mouse orbits the bunch (goal ≥ 10).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

import viser  # noqa: E402

from bench._timing import row as timing_row  # noqa: E402
from bench._timing import time_handling, timings  # noqa: E402
from bench.bench_peloton import machine, speed_round_trips  # noqa: E402
from kernels import cycling  # noqa: E402
from scenes.peloton import PelotonScene  # noqa: E402
from server.switcher import SceneSwitcher  # noqa: E402


def row(name: str, values: list[float], unit: float, unit_name: str, note: str = "") -> None:
    timing_row(name, values, unit, unit_name, note, width=48)


def kernel_rows() -> None:
    for n in (8, 121, 200):
        positions = cycling.formation(n, "bunch")
        values = timings(lambda positions=positions: cycling.formation_drag(positions), 500, warmup=20)
        row(f"formation_drag, bunch of {n}", values, 1e-3, "ms", "goal <= 1 ms at 121" if n == 121 else "")
    values = timings(lambda: cycling.formation(121, "bunch"), 500, warmup=20)
    row("formation, bunch of 121", values, 1e-3, "ms")


def bunch_scene(server: viser.ViserServer) -> tuple[SceneSwitcher, PelotonScene]:
    switcher = SceneSwitcher(server, "peloton")
    scene = switcher.scene
    assert isinstance(scene, PelotonScene)
    c = scene.controls
    c["formation"].value, c["n_riders"].value, c["gap_m"].value = "Bunch (peloton)", 121, 0.3
    return switcher, scene


def leader_watts(speed_kmh: float) -> str:
    positions = cycling.formation(121, "bunch", gap_m=0.3, lateral_m=0.6)
    power = cycling.formation_power(positions, speed_kmh / 3.6, 0.32, 80.0, 0.004, drivetrain_efficiency=0.976)
    return f"**{float(power.total[0]):.0f}**"


def server_rows() -> None:
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    switcher, scene = bunch_scene(server)
    handling = time_handling(scene, ("speed_kmh",))
    round_trips = speed_round_trips(server, leader_watts)
    switcher.close()
    server.stop()
    row("121 riders: slider -> callback -> redraw (server)", handling, 1e-3, "ms", "goal p95 <= 16 ms")
    row("121 riders: slider message -> redraw at client", round_trips, 1e-3, "ms")


def browser_rows() -> None:
    """Frames per second Chromium (software WebGL) draws at 1280×720 while the mouse orbits a 121-rider bunch."""
    from helpers.browser import scene_page
    from helpers.ci import chromium_context

    with chromium_context() as context:
        for case in ("single file of 8", "bunch of 121"):
            with scene_page(context, "peloton", (1280, 720)) as shown:
                if case == "bunch of 121":
                    c = shown.scene.controls
                    c["formation"].value, c["n_riders"].value, c["gap_m"].value = "Bunch (peloton)", 121, 0.3
                    time.sleep(2.0)
                page = shown.page
                page.evaluate(
                    "() => { window.__frames = []; const tick = (t) => { window.__frames.push(t); "
                    "requestAnimationFrame(tick); }; requestAnimationFrame(tick); }"
                )
                page.mouse.move(400, 400)
                page.mouse.down()
                start = time.perf_counter()
                step = 0
                while time.perf_counter() - start < 6.0:
                    step += 1
                    page.mouse.move(400 + 150 * np.sin(step / 10.0), 400 + 30 * np.cos(step / 10.0))
                page.mouse.up()
                stamps = np.asarray(page.evaluate("() => window.__frames"), dtype=np.float64)
                stamps = stamps[stamps >= stamps[-1] - 5000.0]  # the last 5 s of the drag
                gaps_ms = np.diff(stamps)
                fps = 1000.0 / gaps_ms
                row(f"Chromium software WebGL, {case}: frame time", list(gaps_ms * 1e-3), 1e-3, "ms")
                print(
                    f"| {'  frames per second while orbiting':<48} | {np.median(fps):>10.1f} "
                    f"| {np.percentile(fps, 5):>10.1f} | fps  | median, 5th percentile; goal >= 10"
                )


def main() -> None:
    print(f"| {'what':<48} | {'median':>10} | {'p95':>10} | unit |")
    print(f"|{'-' * 50}|{'-' * 12}|{'-' * 12}|------|")
    kernel_rows()
    server_rows()
    if "--browser" in sys.argv:
        browser_rows()
    machine()


if __name__ == "__main__":
    main()
