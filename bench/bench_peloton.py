"""Benchmark the cycling kernel and the peloton scene's slider-to-screen latency.

    python bench/bench_peloton.py           # everything
    python bench/bench_peloton.py course    # only the course kernel

Prints a table: kernel times for ``power`` on 10⁶ speeds and ``speed_for_power`` (against a plain Python loop
run in the same process), and, through the websocket test client, the time from a slider message to the
redrawn scene arriving back (p50, p95), with the server-side handling time on its own. The course rows ride a
synthetic 100 km route at 10 m steps (10 000 segments of rolling hills and turns): ``ride`` (goal ≤ 50 ms),
``power_for_time`` (goal ≤ 0.5 s) and ``paced_ride``.
"""

from __future__ import annotations

import os
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

import viser  # noqa: E402
from helpers.wsclient import BrowserClient  # noqa: E402

from bench._timing import row as timing_row  # noqa: E402
from bench._timing import time_handling, timings  # noqa: E402
from kernels import course, cycling  # noqa: E402
from scenes.peloton import PelotonScene  # noqa: E402
from server.switcher import SceneSwitcher  # noqa: E402


def python_loop_power(speeds: list[float]) -> list[float]:
    """The baseline: the same formula one speed at a time."""
    rho = 1.225
    out = []
    for v in speeds:
        out.append((0.5 * rho * 0.3 * v * abs(v) * v + 0.004 * 80 * 9.81 * v) / 0.976)
    return out


def row(name: str, values: list[float], unit: float, unit_name: str, note: str = "") -> None:
    timing_row(name, values, unit, unit_name, note, width=44)


def hundred_km() -> course.Course:
    """100 km at 10 m steps: rolling hills up to ±6 %, a heading that wanders, 10 001 points."""
    s = np.arange(0.0, 100_000.0 + 5.0, 10.0)
    heading = 0.8 * np.sin(2 * np.pi * s / 7000.0) + 0.3 * np.sin(2 * np.pi * s / 1300.0)
    east = np.concatenate(([0.0], np.cumsum(10.0 * np.sin(heading[:-1]))))
    north = np.concatenate(([0.0], np.cumsum(10.0 * np.cos(heading[:-1]))))
    z = 300.0 + 60.0 * np.sin(2 * np.pi * s / 5000.0) + 15.0 * np.sin(2 * np.pi * s / 900.0)
    return course.course_from_xy(east, north, z, name="100 km")


def course_rows() -> None:
    start = time.perf_counter()
    course.warm_up()
    row("course.warm_up (compile or load the cache)", [time.perf_counter() - start], 1e-3, "ms")
    route = hundred_km()
    rider = course.Rider()
    air = course.Air("weather", temperature_c=22.0, pressure_hpa=980.0, relative_humidity=0.5)
    rides = timings(lambda: course.ride(route, 250.0, rider, 4.0, 225.0, air), 30)
    target = course.ride(route, 250.0, rider, 4.0, 225.0, air).time_s
    inverse = timings(lambda: course.power_for_time(route, target * 0.95, rider, 4.0, 225.0, air), 10)
    paced = timings(lambda: course.paced_ride(route, 250.0, rider, 0.15, 4.0, 225.0, air), 5)
    row("course.ride, 100 km at 10 m (10^4 segments)", rides, 1e-3, "ms", "goal <= 50 ms")
    row("course.power_for_time, 100 km", inverse, 1e-3, "ms", "goal <= 0.5 s")
    row("course.paced_ride, 100 km (constant + paced)", paced, 1e-3, "ms")


def header() -> None:
    print("| measurement                                  |     median |        p95 | unit | note")
    print("|----------------------------------------------|-----------:|-----------:|------|-----")


def main() -> None:
    header()
    if sys.argv[1:] == ["course"]:
        course_rows()
        machine()
        return
    course_rows()
    rng = np.random.default_rng(0)
    speeds = rng.uniform(0.0, 20.0, 1_000_000)
    kernel = timings(lambda: cycling.power(speeds, 0.3, 80.0, 0.004, drivetrain_efficiency=0.976), 15)
    sample = speeds[:100_000].tolist()
    loop = timings(lambda: python_loop_power(sample), 5)
    loop_per_million = [t * 10 for t in loop]
    row(
        "power, 10^6 speeds",
        kernel,
        1e-3,
        "ms",
        f"{statistics.median(loop_per_million) / statistics.median(kernel):.0f}x a Python loop",
    )
    row("power, Python loop (10^5, scaled to 10^6)", loop_per_million, 1e-3, "ms", "baseline")

    powers = rng.uniform(0.0, 800.0, 100_000)
    grades = rng.uniform(-0.1, 0.15, 100_000)
    winds = rng.uniform(-10.0, 10.0, 100_000)
    inverse = timings(lambda: cycling.speed_for_power(powers, 0.3, 80.0, 0.004, grade=grades, headwind_ms=winds), 7)
    row(
        "speed_for_power, 10^5 (grade, wind mixed)",
        inverse,
        1e-3,
        "ms",
        f"{statistics.median(inverse) / 1e5 * 1e9:.0f} ns each",
    )
    single = timings(lambda: cycling.speed_for_power(250.0, 0.3, 80.0, 0.004), 200)
    row("speed_for_power, one value", single, 1e-6, "us")

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    switcher = SceneSwitcher(server, "peloton")
    scene = switcher.scene
    assert isinstance(scene, PelotonScene)
    handling = time_handling(scene, ("speed_kmh",))

    round_trips = speed_round_trips(server, paceline_leader_watts)
    switcher.close()
    server.stop()
    row("slider -> callback -> redraw (server side)", handling, 1e-3, "ms", "goal p95 <= 5 ms")
    row("slider message -> redraw back at client", round_trips, 1e-3, "ms", "goal p95 <= 20 ms")
    machine()


def paceline_leader_watts(speed_kmh: float) -> str:
    """The opening paceline's leader's power as the table shows it (bold whole watts)."""
    power = cycling.paceline(4, 0.5, speed_kmh / 3.6, 0.32, 80.0, 0.004, drivetrain_efficiency=0.976, model="measured")
    return f"**{float(power.total[0]):.0f}**"


def speed_round_trips(server: viser.ViserServer, leader_watts: Callable[[float], str]) -> list[float]:
    """Send 120 speed changes (20 to 69 km/h) from a websocket client, timing each from the slider message until a
    markdown holding ``leader_watts(speed)`` arrives back (s)."""
    round_trips: list[float] = []
    with BrowserClient(server.get_port()) as client:
        client.wait_for_gui("Speed (km/h)")
        time.sleep(0.5)
        for i in range(120):
            speed = 20.0 + (i % 50)
            expected = leader_watts(speed)
            start = time.perf_counter()
            client.set_value("Speed (km/h)", speed)
            client.wait_for(
                lambda expected=expected: any(
                    expected in str(e["props"].get("_markdown", "")) for e in client.gui.values()
                ),
                what="redrawn table",
            )
            round_trips.append(time.perf_counter() - start)
            time.sleep(0.02)
    return round_trips


def machine() -> None:
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    import numba

    print(
        f"\nmachine: {sys.platform}, {_cpus()} CPUs, load {load:.1f}, Python {sys.version.split()[0]}, "
        f"numpy {np.__version__}, numba {numba.__version__} "
        f"({numba.get_num_threads()} threads; the ride loop is serial)"
    )


def _cpus() -> int:
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 0


if __name__ == "__main__":
    main()
