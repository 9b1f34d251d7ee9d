"""Benchmark of the arm scene's solvers: FABRIK against CCD and DLS, single-solve latency, and batch throughput.

Run ``.venv/bin/python bench/bench_arm.py``. It prints three tables:

1. The FABRIK paper's setup (Aristidou & Lasenby 2011, Table 1): a 10-link chain, reachable random targets, mean
   iterations and time per solve for FABRIK, CCD and DLS at the same tolerance, side by side with the paper's
   figures (MATLAB, 2011 hardware; only the ratios compare). Goals: FABRIK ≤ 15.5 mean iterations, ≥ 10× faster than
   our CCD and ≥ 100× faster than our DLS.
2. One 12-link solve with 30° joint limits and 4 obstacles, p95 latency (goal ≤ 1 ms): while a target is dragged
   (each solve starts from the last pose, as in the scene) and from a fixed rest pose to random targets.
3. ``solve_batch`` with 12 links and B = 10 000 (goal ≥ 50 000 chain solves per second), against a per-chain
   Python loop of :func:`kernels.fabrik.solve` timed in the same process.

Every time is the fastest of three runs (see :data:`REPEATS`).
"""

from __future__ import annotations

import argparse
import functools
import math
import time
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from kernels import fabrik

PAPER = {
    "fabrik": (15.5, 13.3),
    "fabrik, plain (no extrapolation)": (15.5, 13.3),
    "ccd": (26.3, 123.6),
    "jacobian_dls": (999.0, 10480.0),
}
"""Aristidou & Lasenby 2011 Table 1: mean iterations and ms per solve (10 joints, 20 runs, MATLAB)."""


def arc_chain(n: int, link: float, d: int = 3, turn: float = 0.15) -> NDArray[np.float64]:
    """A rest pose: n links of length ``link`` (m) bending gently away from +z by ``turn`` rad per joint."""
    angles = turn * np.arange(n)
    directions = np.zeros((n, d))
    directions[:, 0] = np.sin(angles)
    directions[:, -1] = np.cos(angles)
    return np.vstack([np.zeros(d), np.cumsum(link * directions, axis=0)])


def random_targets(
    rng: np.random.Generator, count: int, radius: float, d: int = 3
) -> NDArray[np.float64]:
    """Uniform in a ball of ``radius`` (m)."""
    v = rng.normal(size=(count, d))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    return v * radius * rng.uniform(0.0, 1.0, (count, 1)) ** (1.0 / d)


REPEATS = 3
"""Each solve is timed this many times and the fastest kept: the machine is shared, and another process taking the
core mid-solve says nothing about the solver (timeit's rule)."""


def timed(call: Callable[[], fabrik.Solution]) -> tuple[float, fabrik.Solution]:
    best = math.inf
    for _ in range(REPEATS):
        start = time.perf_counter()
        result = call()
        best = min(best, time.perf_counter() - start)
    return best, result


def paper_setup(runs: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    joints = arc_chain(10, 1.0)
    targets = random_targets(rng, runs, 0.9 * 10.0)
    tolerance = 0.01
    solvers = {
        "fabrik": fabrik.solve,
        "fabrik, plain (no extrapolation)": functools.partial(fabrik.solve, extrapolate=False),
        "ccd": fabrik.ccd,
        "jacobian_dls": fabrik.jacobian_dls,
    }
    rows = {}
    for name, solver in solvers.items():
        times, iterations, reached = [], [], 0
        for target in targets:
            elapsed, result = timed(
                lambda solver=solver, target=target: solver(
                    joints, target, tolerance=tolerance, max_iterations=5000
                )
            )
            times.append(elapsed)
            iterations.append(result.iterations)
            reached += result.status == "reached"
        rows[name] = (np.mean(iterations), np.mean(times) * 1e3, np.median(times) * 1e3, reached)
    base = rows["fabrik"][1]
    print(
        f"\n## Paper setup: 10 links of 1 m, 3D, {runs} reachable random targets, tolerance {tolerance} m"
    )
    print(
        "| solver | mean iterations | mean ms/solve | median ms | reached | time / FABRIK | paper iterations | paper ms |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for name, (its, mean_ms, median_ms, reached) in rows.items():
        paper_its, paper_ms = PAPER[name]
        print(
            f"| {name} | {its:.1f} | {mean_ms:.3f} | {median_ms:.3f} | {reached}/{runs} | "
            f"{mean_ms / base:.1f}× | {paper_its:g} | {paper_ms:g} |"
        )


def single_latency(frames: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    link = 0.1
    joints = arc_chain(12, link)
    reach = 12 * link
    phi = math.radians(30.0)
    obstacles = [
        (np.array([0.35, 0.0, 0.55]), 0.08),
        (np.array([-0.3, 0.1, 0.6]), 0.1),
        (np.array([0.0, 0.35, 0.8]), 0.07),
        (np.array([0.3, 0.3, 0.25]), 0.09),
    ]
    kwargs = {"cone_half_angle_rad": phi, "obstacles": obstacles}
    print(
        f"\n## One 12-link solve, 30° limits, 4 obstacles, tolerance 1 mm, max 50 iterations ({frames} solves)"
    )
    print("| case | median ms | p95 ms | max ms | mean iterations | p95 iterations | statuses |")
    print("|---|---|---|---|---|---|---|")
    # Drag: the target moves 60 Hz-style along a figure-eight, each solve warm-started from the last pose.
    pose = joints
    times, iterations, statuses = [], [], []
    for k in range(frames):
        s = 2.0 * math.pi * k / frames
        target = np.array([0.45 * math.sin(s), 0.25 * math.sin(2 * s), 0.75 + 0.2 * math.cos(s)])
        elapsed, result = timed(
            lambda target=target, pose=pose: fabrik.solve(pose, target, **kwargs)
        )
        pose = result.joints
        times.append(elapsed)
        iterations.append(result.iterations)
        statuses.append(result.status)
    print(row("drag (warm start)", times, iterations, statuses))
    times, iterations, statuses = [], [], []
    for target in random_targets(rng, frames, 0.9 * reach):
        elapsed, result = timed(lambda target=target: fabrik.solve(joints, target, **kwargs))
        times.append(elapsed)
        iterations.append(result.iterations)
        statuses.append(result.status)
    print(row("random target from rest", times, iterations, statuses))
    times, iterations, statuses = [], [], []
    for target in random_targets(rng, frames, 0.9 * reach):
        elapsed, result = timed(lambda target=target: fabrik.solve(joints, target))
        times.append(elapsed)
        iterations.append(result.iterations)
        statuses.append(result.status)
    print(row("same, no limits or obstacles", times, iterations, statuses))


def row(label: str, times: list[float], iterations: list[int], statuses: list[str]) -> str:
    ms = np.array(times) * 1e3
    names, counts = np.unique(statuses, return_counts=True)
    mix = ", ".join(f"{name} {count}" for name, count in zip(names, counts, strict=True))
    return (
        f"| {label} | {np.median(ms):.3f} | {np.percentile(ms, 95):.3f} | {ms.max():.3f} | "
        f"{np.mean(iterations):.1f} | {np.percentile(iterations, 95):.0f} | {mix} |"
    )


def batch_throughput(batch: int, loop_sample: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    rest = arc_chain(12, 0.1)
    joints = np.broadcast_to(rest, (batch, *rest.shape)).copy()
    targets = random_targets(rng, batch, 0.9 * 1.2)
    print(f"\n## solve_batch, 12 links, B = {batch}, tolerance 1 mm, max 50 iterations")
    print("| case | batch s | chains/s | per-chain loop chains/s | batch / loop | reached |")
    print("|---|---|---|---|---|---|")
    cases = {
        "no limits": {},
        "30° limits + 4 obstacles": {
            "cone_half_angle_rad": math.radians(30.0),
            "obstacles": [
                (np.array([0.35, 0.0, 0.55]), 0.08),
                (np.array([-0.3, 0.1, 0.6]), 0.1),
                (np.array([0.0, 0.35, 0.8]), 0.07),
                (np.array([0.3, 0.3, 0.25]), 0.09),
            ],
        },
    }
    for label, kwargs in cases.items():
        batch_s, loop_s = math.inf, math.inf
        for _ in range(REPEATS):  # fastest of three, as for single solves
            start = time.perf_counter()
            result = fabrik.solve_batch(joints, targets, **kwargs)
            batch_s = min(batch_s, time.perf_counter() - start)
            start = time.perf_counter()
            for i in range(loop_sample):
                fabrik.solve(joints[i], targets[i], **kwargs)
            loop_s = min(loop_s, time.perf_counter() - start)
        loop_rate = loop_sample / loop_s
        rate = batch / batch_s
        reached = int(np.sum(result.status == "reached"))
        print(
            f"| {label} | {batch_s:.3f} | {rate:,.0f} | {loop_rate:,.0f} | {rate / loop_rate:.0f}× | "
            f"{reached}/{batch} |"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description="Benchmark the arm scene's IK solvers.")
    parser.add_argument("--runs", type=int, default=100, help="targets in the paper setup (≥ 20)")
    parser.add_argument("--frames", type=int, default=500, help="solves in the latency cases")
    parser.add_argument("--batch", type=int, default=10_000)
    parser.add_argument(
        "--loop-sample", type=int, default=300, help="chains timed in the per-chain loop"
    )
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    paper_setup(args.runs, args.seed)
    single_latency(args.frames, args.seed)
    batch_throughput(args.batch, args.loop_sample, args.seed)


if __name__ == "__main__":
    main()
