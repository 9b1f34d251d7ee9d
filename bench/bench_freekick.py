"""Benchmark the ball-flight kernel, the app's start and the free-kick scene's slider-to-screen latency.

    python bench/bench_freekick.py            # goal table, accuracy table, scene table
    python bench/bench_freekick.py --goals    # goal table only (a minute)
    python bench/bench_freekick.py --overhead # single-kick overhead: compiled core vs public simulate

Prints:

* the goal table: one 30 m curler (28 m/s, 19°, 9 rev/s sidespin, constant coefficients) at RK4 10 ms
  and at Euler 1 ms; ``simulate_batch`` on 10 000 kicks (RK4 10 ms); the 41 × 31 outcome map; the app's
  start to serving its page with numba's cache warm and cold (a fresh ``NUMBA_CACHE_DIR``), and when its background
  warm-up finished. Each kernel row has a ratio against a plain numpy implementation of the same equations run in
  this process (:func:`numpy_flight`, :func:`numpy_batch`); the machine's CPU, numba's thread count and the load
  average are printed with it;
* accuracy and time of the curler for Euler 1 ms, RK4 10 ms and scipy's own solvers, the error being the distance
  at the plane x = 30 m from a DOP853 solution at rtol = atol = 1e-12;
* the single kick's overhead: median and p95 of the compiled core alone and of a full public ``simulate`` call
  (with a reused ``FlightConfig`` and with keyword options) for a typical free kick, and their ratio;
* the scene: a spin-slider change recomputed and redrawn on the server (goal p95 ≤ 16 ms) for each model and
  integrator, a speed-slider change, and a spin change from a websocket client's message to the new path arriving
  back; the outcome map and aiming on the scene's worker thread.
"""

from __future__ import annotations

import contextlib
import math
import os
import platform
import statistics
import sys
import tempfile
import time
import urllib.request
from collections.abc import Callable
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

import numba  # noqa: E402
import viser  # noqa: E402
from helpers.ball_reference import START, G, Q, R, reference_at_x  # noqa: E402
from helpers.processes import AppProcess  # noqa: E402
from helpers.waiting import wait_until  # noqa: E402
from helpers.wsclient import BrowserClient  # noqa: E402

from bench._timing import row, time_handling, timings  # noqa: E402
from kernels import ball  # noqa: E402
from kernels.ball.config import N_STEPS  # noqa: E402
from kernels.ball.core import simulate_one  # noqa: E402
from scenes.freekick import FreeKickParams, FreeKickScene  # noqa: E402
from scenes.freekick.model import MAP_QUIET_S, outcome_map  # noqa: E402
from server.switcher import SceneSwitcher  # noqa: E402

VELOCITY = ball.launch_velocity(28.0, math.radians(19.0), math.radians(-8.0))
SPIN = ball.spin_vector(9.0, (0.0, 0.0, 1.0))
LINE_M = 30.0
MAP_SPEEDS = np.linspace(15.0, 35.0, 41)
MAP_SPINS = np.linspace(0.0, 15.0, 31)


def scipy_flight(method: str, rtol: float, atol: float) -> NDArray[np.float64]:
    """Ball centre at x = 30 m by scipy's ``solve_ivp`` (constant coefficients, the tests' independent reference)."""
    return reference_at_x(VELOCITY, SPIN, LINE_M, method=method, rtol=rtol, atol=atol)


def kernel_rows() -> None:
    reference = scipy_flight("DOP853", 1e-12, 1e-12)
    cases: list[tuple[str, Callable[[], NDArray[np.float64]], int]] = [
        (
            "Euler 1 ms, one 30 m flight",
            lambda: ball.simulate(START, VELOCITY, SPIN, dt=1e-3, method="euler", x_stop=LINE_M).position[-1],
            30,
        ),
        (
            "RK4 10 ms, one 30 m flight",
            lambda: ball.simulate(START, VELOCITY, SPIN, dt=1e-2, method="rk4", x_stop=LINE_M).position[-1],
            200,
        ),
        (
            "RK4 10 ms, measured model",
            lambda: ball.simulate(
                START, VELOCITY, SPIN, dt=1e-2, method="rk4", model="measured", x_stop=LINE_M
            ).position[-1],
            200,
        ),
        ("scipy DOP853 rtol=atol=1e-12 (reference)", lambda: scipy_flight("DOP853", 1e-12, 1e-12), 10),
        ("scipy RK45 default tolerances", lambda: scipy_flight("RK45", 1e-3, 1e-6), 30),
        ("scipy DOP853 rtol=1e-8, atol=1e-10", lambda: scipy_flight("DOP853", 1e-8, 1e-10), 30),
    ]
    for name, run, repeat in cases:
        end = run()
        if "measured" in name:
            note = "(error not comparable: other model)"
        else:
            note = f"error at 30 m {np.linalg.norm(end - reference) * 1e3:.4g} mm"
        if name.startswith("Euler"):
            note += "; < 10 mm asked of it"
        if name.startswith("RK4 10 ms, one"):
            note += "; goal <= 0.1 mm in <= 1 ms"
        row(name, timings(run, repeat), 1e-3, "ms", note)


def scene_rows() -> None:
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    switcher = SceneSwitcher(server, "freekick")
    scene = switcher.scene
    assert isinstance(scene, FreeKickScene)
    scene.wait_idle()
    handling = time_handling(scene, ("spin_rev_s", "speed_ms"))

    with BrowserClient(server.get_port()) as client:
        client.wait_for_gui("Spin rate (rev/s)")
        client.wait_for_node("/freekick/path")
        for i in range(120):  # constant model: the path does not move with the rate; time the server only
            done = len(handling)
            client.set_value("Spin rate (rev/s)", 4.0 + 0.1 * (i % 80))
            client.wait_for(lambda done=done: len(handling) > done, what="the callback")
            time.sleep(0.02)
        constant = handling[:]
        scene.controls["model"].value = "Measured C_D(Re, S), C_L(S)"
        scene.wait_idle()
        round_trips: list[float] = []
        for i in range(120):
            before = np.array(client.nodes["/freekick/path"]["props"]["points"]).copy()
            start = time.perf_counter()
            client.set_value("Spin rate (rev/s)", 4.0 + 0.1 * (i % 80) + 0.05)
            client.wait_for(
                lambda before=before: (
                    not np.array_equal(np.asarray(client.nodes["/freekick/path"]["props"]["points"]), before)
                ),
                what="redrawn path",
            )
            round_trips.append(time.perf_counter() - start)
            time.sleep(0.02)
        measured = handling[len(constant) :]
        scene.controls["integrator"].value = "Euler, 1 ms (textbook)"
        scene.wait_idle()
        for i in range(120):
            done = len(handling)
            client.set_value("Spin rate (rev/s)", 4.0 + 0.1 * (i % 80))
            client.wait_for(lambda done=done: len(handling) > done, what="the callback")
            time.sleep(0.02)
        euler = handling[len(constant) + len(measured) :]
        # A new launch speed: the no-spin ghost is flown again too, which a spin change reuses.
        for i in range(120):
            done = len(handling)
            client.set_value("Launch speed (m/s)", 20.0 + 0.5 * (i % 24))
            client.wait_for(lambda done=done: len(handling) > done, what="the callback")
            time.sleep(0.02)
        euler_speed = handling[len(constant) + len(measured) + len(euler) :]
    row("spin slider -> recompute + redraw (server)", constant, 1e-3, "ms", "constant model; goal p95 <= 16 ms")
    row("  same, measured model", measured, 1e-3, "ms", "goal p95 <= 16 ms")
    row("  same, measured model, Euler 1 ms", euler, 1e-3, "ms", "goal p95 <= 16 ms")
    row("speed slider, measured model, Euler 1 ms", euler_speed, 1e-3, "ms", "ghost re-flown too; goal p95 <= 16 ms")
    row("spin slider message -> new path at client", round_trips, 1e-3, "ms", "measured model, websocket client")

    map_times = timings(lambda: (scene.request_outcome_map(), scene.wait_idle()), 3)
    row(
        "outcome map, 41 x 31 kicks (worker thread)",
        map_times,
        1e-3,
        "ms",
        f"includes the scene's {MAP_QUIET_S:g} s wait for the settings to be still",
    )
    aim_times = timings(lambda: (scene.aim_at_point(-2.5, 1.9), scene.wait_idle()), 3)
    row(
        "aim at a clicked point (worker thread)",
        aim_times,
        1e-3,
        "ms",
        "includes the new kick's outcome map; " + scene.aim_message[:40],
    )
    switcher.close()
    server.stop()


# --------------------------------------------------------------------------------------------- plain numpy
def numpy_acceleration(v: NDArray[np.float64], axis: NDArray[np.float64]) -> NDArray[np.float64]:
    """Constant-coefficient drag + Magnus + gravity (m/s²) for velocities (..., 3), plain numpy."""
    speed = np.linalg.norm(v, axis=-1, keepdims=True)
    a = -Q * 0.25 * speed * v + Q * 0.25 * speed * np.cross(axis, v)
    a[..., 2] -= G
    return a


def numpy_rk4_step(
    p: NDArray[np.float64], v: NDArray[np.float64], axis: NDArray[np.float64], dt: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """One classical RK4 step of positions and velocities (..., 3) over ``dt`` (s), plain numpy."""
    k1 = numpy_acceleration(v, axis)
    k2 = numpy_acceleration(v + 0.5 * dt * k1, axis)
    k3 = numpy_acceleration(v + 0.5 * dt * k2, axis)
    k4 = numpy_acceleration(v + dt * k3, axis)
    p_next = p + dt / 6 * (v + 2 * (v + 0.5 * dt * k1) + 2 * (v + 0.5 * dt * k2) + (v + dt * k3))
    return p_next, v + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)


def numpy_flight(method: str, dt: float, x_stop: float) -> NDArray[np.float64]:
    """The curler in plain numpy, one 3-vector step at a time, until it passes x_stop or lands: (N, 6) states."""
    axis = SPIN / np.linalg.norm(SPIN)
    p, v = START.copy(), VELOCITY.copy()
    states = [np.concatenate((p, v))]
    for _ in range(round(5.0 / dt)):
        if method == "euler":
            v = v + dt * numpy_acceleration(v, axis)
            p = p + dt * v
        else:
            p, v = numpy_rk4_step(p, v, axis, dt)
        states.append(np.concatenate((p, v)))
        if p[2] <= 0.0 or p[0] >= x_stop:
            break
    return np.array(states)


def numpy_batch(
    starts: NDArray[np.float64], velocities: NDArray[np.float64], spins: NDArray[np.float64], x_stop: float
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """RK4 10 ms over all kicks at once in plain numpy until each lands or passes x_stop: (T, K, 6), samples."""
    dt = 1e-2
    rates = np.linalg.norm(spins, axis=1, keepdims=True)
    axis = spins / np.where(rates > 0, rates, 1.0)
    p, v = starts.copy(), velocities.copy()
    flying = np.ones(len(p), dtype=bool)
    n = np.ones(len(p), dtype=np.int64)
    frames = [np.concatenate((p, v), axis=1)]
    for _ in range(400):
        p_new, v_new = numpy_rk4_step(p, v, axis, dt)
        p = np.where(flying[:, None], p_new, p)
        v = np.where(flying[:, None], v_new, v)
        n += flying
        frames.append(np.concatenate((p, v), axis=1))
        flying &= (p[:, 2] > R) & (p[:, 0] < x_stop)
        if not flying.any():
            break
    return np.stack(frames), n


def numpy_outcomes(states: NDArray[np.float64], wall: ball.Panel, goal: ball.Panel) -> NDArray[np.str_]:
    """Results of :func:`numpy_batch` flights (linear interpolation at each plane: the cheap reference)."""
    result = np.full(states.shape[1], "short", dtype="<U5")
    crossings = []
    for panel in (wall, goal):
        normal = np.array([*panel.normal_xy]) / np.hypot(*panel.normal_xy)
        d = (states[:, :, :2] - np.array(panel.centre_xy)) @ normal  # (T, K)
        crosses = (d[:-1] < 0) & (d[1:] >= 0)
        found = crosses.any(axis=0)
        i = np.argmax(crosses, axis=0)
        k = np.arange(states.shape[1])
        s = -d[i, k] / np.where(found, d[i + 1, k] - d[i, k], 1.0)
        point = states[i, k, :3] + s[:, None] * (states[i + 1, k, :3] - states[i, k, :3])
        lateral = (point[:, :2] - np.array(panel.centre_xy)) @ np.array([-normal[1], normal[0]])
        crossings.append((found, point, lateral))
    (wall_found, wall_point, wall_lateral), (goal_found, goal_point, goal_lateral) = crossings
    inside = np.abs(goal_lateral) <= 0.5 * goal.width_m - R
    under = goal_point[:, 2] <= goal.height_m - R
    result[goal_found & inside & under] = "goal"
    result[goal_found & inside & ~under] = "over"
    result[goal_found & ~inside] = "wide"
    hit = wall_found & (np.abs(wall_lateral) <= 0.5 * wall.width_m + R) & (wall_point[:, 2] <= wall.height_m + R)
    result[hit] = "wall"
    return result


# --------------------------------------------------------------------------------------------- goals
def batch_kicks(k: int = 10_000) -> tuple[NDArray[np.float64], ...]:
    rng = np.random.default_rng(0)
    speeds = rng.uniform(15.0, 35.0, k)
    elevations = np.radians(rng.uniform(5.0, 30.0, k))
    azimuths = np.radians(rng.uniform(-15.0, 15.0, k))
    velocities = np.stack(
        [
            speeds * np.cos(elevations) * np.cos(azimuths),
            speeds * np.cos(elevations) * np.sin(azimuths),
            speeds * np.sin(elevations),
        ],
        axis=1,
    )
    spins = np.zeros((k, 3))
    spins[:, 2] = 2 * math.pi * rng.uniform(-12.0, 12.0, k)
    return np.tile([-25.0, 0.0, R], (k, 1)), velocities, spins


def app_start(cache_dir: str | None) -> tuple[float, float | None]:
    """Seconds from launching ``app.py`` to its page answering, and to its log saying the kernels are warm (None if
    they were not within 300 s)."""
    env = dict(os.environ)
    if cache_dir is not None:
        env["NUMBA_CACHE_DIR"] = cache_dir
    start = time.perf_counter()
    app = AppProcess(env=env, timeout_s=300.0)
    try:
        served: list[float] = []

        def page_answers() -> bool:
            with (
                contextlib.suppress(OSError),
                urllib.request.urlopen(f"http://127.0.0.1:{app.port}/", timeout=5) as page,
            ):
                if page.status == 200:
                    served.append(time.perf_counter() - start)
            return bool(served)

        wait_until(page_answers, "the app's page to answer", 300.0)
        try:
            app.wait_compiled(max(0.0, 300.0 - (time.perf_counter() - start)))
        except AssertionError:
            return served[0], None
        return served[0], time.perf_counter() - start
    finally:
        app.close()


def goal_row(name: str, values: list[float], unit: float, unit_name: str, goal: float | None, note: str) -> None:
    """One row: median, p95 and best (the best is what an idle machine gives; this one is shared)."""
    median, p95 = statistics.median(values) / unit, float(np.percentile(values, 95)) / unit
    best = min(values) / unit
    verdict = "" if goal is None else ("met" if median <= goal else "NOT met")
    goal_text = "" if goal is None else f"<= {goal:g} {unit_name}"
    print(
        f"| {name:<44} | {median:>9.3f} | {p95:>9.3f} | {best:>9.3f} | {unit_name:<4} | {goal_text:<11} "
        f"| {verdict:<7} | {note}"
    )


def goal_rows() -> None:
    load_before = os.getloadavg()
    cpu = platform.processor() or platform.machine()
    with open("/proc/cpuinfo") as info:
        models = [line.split(":", 1)[1].strip() for line in info if line.startswith("model name")]
    cpu = models[0] if models else cpu
    ball.warm_up()
    print(
        "| goal                                         |    median |       p95 |      best | unit | goal        "
        "| verdict | note"
    )
    print(
        "|----------------------------------------------|----------:|----------:|----------:|------|-------------"
        "|---------|-----"
    )
    kicks: tuple[tuple[ball.Method, float, float, int, str], ...] = (
        ("rk4", 1e-2, 20.0, 3000, "one 30 m kick, RK4 10 ms"),
        ("euler", 1e-3, 100.0, 1000, "one 30 m kick, Euler 1 ms"),
    )
    for method, dt, goal, repeat, label in kicks:
        compiled = timings(
            lambda method=method, dt=dt: ball.simulate(START, VELOCITY, SPIN, dt=dt, method=method, x_stop=LINE_M),
            repeat,
        )
        plain = timings(lambda method=method, dt=dt: numpy_flight(method, dt, LINE_M), 20)
        ratio = statistics.median(plain) / statistics.median(compiled)
        goal_row(
            label, compiled, 1e-6, "µs", goal, f"{ratio:.0f}x plain numpy ({statistics.median(plain) * 1e3:.1f} ms)"
        )

    starts, velocities, spins = batch_kicks()
    options = {"dt": 1e-2, "method": "rk4", "t_max": 4.0, "x_stop": 0.5, "ground_m": R}
    batch = timings(lambda: ball.simulate_batch(starts, velocities, spins, **options), 9)  # type: ignore[arg-type]
    plain = timings(lambda: numpy_batch(starts, velocities, spins, 0.5), 3)
    ratio = statistics.median(plain) / statistics.median(batch)
    goal_row(
        "simulate_batch, 10 000 kicks, RK4 10 ms",
        batch,
        1e-3,
        "ms",
        60.0,
        f"{ratio:.1f}x plain numpy over the kicks ({statistics.median(plain) * 1e3:.0f} ms)",
    )
    wall, goal = ball.free_kick_panels((-25.0, 0.0), (0.0, 0.0), (1.0, 0.0))
    fused = timings(lambda: ball.simulate_outcomes(starts, velocities, spins, wall, goal, **options), 9)  # type: ignore[arg-type]
    goal_row("  simulate_outcomes, same kicks (no storage)", fused, 1e-3, "ms", None, "verdicts only")

    params = FreeKickParams()
    grid = timings(lambda: outcome_map(params), 15)
    speeds, rates = np.meshgrid(MAP_SPEEDS, MAP_SPINS)
    heading = math.atan2(0.0, 22.0) + math.radians(params.azimuth_deg)
    direction = ball.launch_velocity(1.0, math.radians(params.elevation_deg), heading)
    map_starts = np.tile([-22.0, 0.0, R], (speeds.size, 1))
    map_velocities = speeds.reshape(-1, 1) * direction
    map_spins = 2 * math.pi * rates.reshape(-1, 1) * np.array([0.0, 0.0, 1.0])
    map_wall, map_goal = ball.free_kick_panels((-22.0, 0.0), (0.0, 0.0), (1.0, 0.0), wall_width_m=2.0)

    def plain_map() -> NDArray[np.str_]:
        states, _ = numpy_batch(map_starts, map_velocities, map_spins, 0.5)
        return numpy_outcomes(states, map_wall, map_goal)

    plain = timings(plain_map, 5)
    agree = float(np.mean(plain_map().reshape(speeds.shape) == outcome_map(params)))
    ratio = statistics.median(plain) / statistics.median(grid)
    goal_row(
        "outcome map 41 x 31 (scene's outcome_map)",
        grid,
        1e-3,
        "ms",
        20.0,
        f"{ratio:.0f}x plain numpy ({statistics.median(plain) * 1e3:.0f} ms, {agree:.1%} same cells)",
    )

    warm = [app_start(None) for _ in range(3)]
    goal_row(
        "app start to serving, warm cache",
        [w[0] for w in warm],
        1.0,
        "s",
        3.0,
        f"kernels warm after {statistics.median([w[1] or math.nan for w in warm]):.2f} s",
    )
    with tempfile.TemporaryDirectory() as empty:
        serving, warmed = app_start(empty)
    goal_row(
        "app start to serving, cold cache",
        [serving],
        1.0,
        "s",
        None,
        f"kernels compiled after {warmed or math.nan:.1f} s (background thread)",
    )
    load_after = os.getloadavg()
    print(
        f"\nCPU: {cpu}, {os.cpu_count()} logical CPUs; numba {numba.__version__}, {numba.get_num_threads()} threads "
        f"({numba.threading_layer()} layer); load average (1 min) {load_before[0]:.2f} before, "
        f"{load_after[0]:.2f} after\n"
    )


def overhead_rows(calls: int = 20_000) -> None:
    """The Python around one kick: the compiled core alone against a full public ``simulate`` call, in turns.

    A typical free kick: the scene's RK4 at 10 ms, a 30 m curler to the plane x = 30 m, t_max 4 s, the ball's
    underside on the turf. (a) is :func:`kernels.ball.core.simulate_one` on a prepared launch row and preallocated
    buffers; (b) is ``ball.simulate`` with a reused :class:`kernels.ball.FlightConfig`, (c) with the same settings as
    keywords. Each call is timed on its own; the three alternate, so a neighbour's load falls on all of them alike.
    """
    config = ball.FlightConfig(dt=1e-2, method="rk4", t_max=4.0, x_stop=LINE_M, ground_m=R)
    options = {"dt": 1e-2, "method": "rk4", "t_max": 4.0, "x_stop": LINE_M, "ground_m": R}
    settings = config.settings
    launch = np.concatenate((START, VELOCITY, SPIN, np.zeros(4)))
    rows = int(settings[N_STEPS]) + 1
    t, state, forces = np.empty(rows), np.empty((rows, 6)), np.empty((rows, 12))
    ball.simulate(START, VELOCITY, SPIN, config)  # compiled already; warm the caches
    ball.simulate(START, VELOCITY, SPIN, **options)
    core_s, public_s, keywords_s = [], [], []
    clock = time.perf_counter_ns
    for _ in range(calls):
        start = clock()
        simulate_one(launch, settings, t, state, forces)
        middle = clock()
        ball.simulate(START, VELOCITY, SPIN, config)
        end = clock()
        ball.simulate(START, VELOCITY, SPIN, **options)
        last = clock()
        core_s.append((middle - start) * 1e-9)
        public_s.append((end - middle) * 1e-9)
        keywords_s.append((last - end) * 1e-9)
    core = statistics.median(core_s)
    print("| measurement                                    |     median |        p95 | unit | note")
    print("|------------------------------------------------|-----------:|-----------:|------|-----")
    row("(a) compiled core alone, RK4 10 ms, 30 m", core_s, 1e-6, "us", f"{calls} calls")
    row(
        "(b) simulate(..., config)",
        public_s,
        1e-6,
        "us",
        f"{statistics.median(public_s) / core:.2f}x the core (goal <= 2x)",
    )
    row(
        "(c) simulate(..., dt=..., method=...)",
        keywords_s,
        1e-6,
        "us",
        f"{statistics.median(keywords_s) / core:.2f}x the core",
    )
    print(f"load average (1 min) {os.getloadavg()[0]:.2f}\n")


def main() -> None:
    if "--overhead" in sys.argv:
        overhead_rows()
        return
    goal_rows()
    overhead_rows()
    if "--goals" in sys.argv:
        return
    print("| measurement                                    |     median |        p95 | unit | note")
    print("|------------------------------------------------|-----------:|-----------:|------|-----")
    kernel_rows()
    scene_rows()
    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    print(f"\nmachine: {sys.platform}, {cpus} CPUs, Python {sys.version.split()[0]}, numpy {np.__version__}")


if __name__ == "__main__":
    main()
