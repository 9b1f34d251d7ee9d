"""Benchmark the free kick on a pitch: one kick with collisions, 10 000 strikes' outcomes, and the odds map.

    python bench/bench_ball_pitch.py

Prints median and p95 (and the machine, numba's thread count and the load average) of:

* one RK4 kick (10 ms) on a pitch with wall, keeper, posts, bar and net, 26 m/s curler from 22 m that hits the turf
  in the net: (a) the compiled core alone on prepared buffers, (b) the public ``ball.simulate(..., pitch=...)``;
* 10 000 scattered strikes of that kick judged on the pitch (``simulate_outcomes(..., pitch=...)``, RK4 10 ms,
  wall and keeper), in parallel over the kicks;
* the odds map, 41 distances × 31 angles × 64 strikes (``kernels.ball.odds.odds_map``).

The two batches are also timed on one thread in CPU time (``time.thread_time``): on a machine shared with other
work their wall-clock times swing with its load, the CPU time of one thread far less, so a before/after pair taken
under load compares in it.
"""

from __future__ import annotations

import math
import os
import platform
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numba  # noqa: E402

from kernels import ball  # noqa: E402
from kernels.ball import odds, play  # noqa: E402
from kernels.ball.config import N_STEPS  # noqa: E402
from kernels.ball.core import simulate_one  # noqa: E402
from kernels.ball.pitch import pitch_vector  # noqa: E402

R = ball.BALL_RADIUS_M
START = np.array([-22.0, 0.0, R])
VELOCITY = ball.launch_velocity(26.0, math.radians(17.0), math.radians(-6.0))
SPIN = ball.spin_vector(9.0, (0.0, 0.0, 1.0))
OPTIONS = {"dt": 1e-2, "method": "rk4", "model": "measured", "ground_m": R, "t_max": 4.0}


def timings(call: Callable[[], object], repeats: int) -> tuple[float, float]:
    """(median, p95) of ``repeats`` calls, in seconds."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    times.sort()
    return statistics.median(times), times[min(len(times) - 1, int(0.95 * len(times)))]


def cpu_timings(call: Callable[[], object], repeats: int) -> tuple[float, float]:
    """(median, p95) CPU seconds of ``repeats`` calls on this thread alone (numba's thread count set to 1 for
    them): the work itself, which other jobs on a shared machine slow far less than the wall clock."""
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        times = []
        for _ in range(repeats):
            start = time.thread_time()
            call()
            times.append(time.thread_time() - start)
    finally:
        numba.set_num_threads(threads)
    times.sort()
    return statistics.median(times), times[min(len(times) - 1, int(0.95 * len(times)))]


def main() -> None:
    ball.warm_up()
    wall, goal = ball.free_kick_panels(START[:2], (0.0, 0.0), (1.0, 0.0))
    pitch = ball.Pitch(goal, wall, ball.Keeper())
    config = ball.FlightConfig(**OPTIONS)  # type: ignore[arg-type]
    print(
        f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, numba threads "
        f"{numba.get_num_threads()}, load {os.getloadavg()[0]:.2f}"
    )
    flight = ball.simulate(START, VELOCITY, SPIN, config, pitch=pitch)
    print(
        f"the kick: {flight.result}, ended {flight.ended}, {len(flight.t)} samples, "
        f"events {[e.kind for e in flight.events]}"
    )

    settings = config.settings
    launch = np.concatenate((START, VELOCITY, SPIN, np.zeros(4)))
    vector = pitch_vector(pitch, START[:2], R, R)
    vector.setflags(write=False)  # as the public functions pass it
    rows = int(settings[N_STEPS]) + 1 + play.EXTRA_ROWS
    buffers = (
        np.empty((1, rows)),
        np.empty((1, rows, 6)),
        np.empty((1, rows, 3)),
        np.empty((1, rows, 12)),
        np.empty((1, play.MAX_EVENTS, 5)),
        np.empty((1, play.N_INFO)),
        np.empty(1, dtype=np.int64),
        np.empty(1, dtype=np.int64),
    )
    core, first = play.play_rows, np.zeros(1, dtype=np.int64)
    median, p95 = timings(lambda: core(0, 1, launch[None], settings, vector[None], first, *buffers), 2000)
    print(f"| one RK4 kick with collisions, compiled core | {median * 1e6:.1f} µs | p95 {p95 * 1e6:.1f} µs |")
    free_rows = int(settings[N_STEPS]) + 1
    free = (np.empty(free_rows), np.empty((free_rows, 6)), np.empty((free_rows, 12)))
    stopped = ball.FlightConfig(**OPTIONS, x_stop=2.0).settings  # type: ignore[arg-type]
    median_free, _ = timings(lambda: simulate_one(launch, stopped, *free), 2000)
    print(
        f"| the same kick without a pitch to x = 2 m, compiled core (reference) | {median_free * 1e6:.1f} µs | "
        f"pitch/free {median / median_free:.2f} |"
    )
    median, p95 = timings(lambda: ball.simulate(START, VELOCITY, SPIN, config, pitch=pitch), 2000)
    print(
        f"| one RK4 kick with collisions, ball.simulate(pitch=...) | {median * 1e6:.1f} µs | p95 {p95 * 1e6:.1f} µs |"
    )

    velocities, spins = odds.draw_strikes(
        26.0, math.radians(17.0), math.radians(-6.0), SPIN, odds.StrikeSpread(), 10_000, 0
    )
    starts = np.broadcast_to(START, velocities.shape)
    median, p95 = timings(lambda: ball.simulate_outcomes(starts, velocities, spins, config=config, pitch=pitch), 15)
    counts = ball.simulate_outcomes(starts, velocities, spins, config=config, pitch=pitch).counts()
    print(f"| 10 000 strikes' outcomes with collisions and a keeper | {median * 1e3:.1f} ms | p95 {p95 * 1e3:.1f} ms |")
    print(f"  their results: {counts}")
    median, p95 = cpu_timings(lambda: ball.simulate_outcomes(starts, velocities, spins, config=config, pitch=pitch), 7)
    print(f"| the same, one thread, CPU time | {median * 1e3:.1f} ms | p95 {p95 * 1e3:.1f} ms |")

    distances = np.linspace(16.0, 36.0, 41)
    angles = np.radians(np.linspace(-40.0, 40.0, 31))
    median, p95 = timings(
        lambda: odds.odds_map(
            distances, angles, 26.0, math.radians(17.0), math.radians(-6.0), SPIN, keeper=ball.Keeper(), n=64, **OPTIONS
        ),
        3,
    )
    print(f"| odds map 41 × 31 spots × 64 strikes | {median:.2f} s | p95 {p95:.2f} s |")
    median, p95 = cpu_timings(
        lambda: odds.odds_map(
            distances, angles, 26.0, math.radians(17.0), math.radians(-6.0), SPIN, keeper=ball.Keeper(), n=64, **OPTIONS
        ),
        3,
    )
    print(f"| the same, one thread, CPU time | {median:.2f} s | p95 {p95:.2f} s |")


if __name__ == "__main__":
    main()
