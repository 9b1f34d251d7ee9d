"""Benchmark of the arm scene's solvers against the scene's speed goals, with a plain numpy FABRIK as the baseline.

Run ``.venv/bin/python bench/bench_arm.py`` (``--quick`` for a shorter run). It prints the machine (CPU, cores,
numba's threads and threading layer, the load average before and after), then:

1. The FABRIK paper's setup (Aristidou & Lasenby 2011, Table 1): 10 links of 1 m in 3D, reachable random targets,
   tolerance 0.01 m: mean iterations and µs per solve for FABRIK, CCD and DLS, beside the paper's figures (MATLAB,
   2011 hardware: only the ratios compare). Goal: FABRIK mean ≤ 10 µs.
2. One 12-link solve with 30° joint limits and 4 obstacles while a target is dragged (each solve warm-started from
   the last pose, as in the scene). Goal: p95 ≤ 50 µs.
3. ``solve_batch`` with 12 links and B = 10 000, without limits (goal ≥ 1.5 M chains/s on 2 cores) and with 30°
   limits and 4 obstacles (goal ≥ 300 k chains/s).
4. Cold start: compiling every core in a fresh process with an empty cache, and loading them from the cache.
5. The Python around the core: for chains of 2, 4, 8 and 16 links, the median and p95 of the compiled single-chain
   entry alone (``kernels.fabrik.api.compiled_single_solve``: the compiled call on prepared arguments, numba's dispatch
   included) and of a full public ``solve`` call on the same chain and target, and their ratio. Goal: ``solve`` within
   2× of the core.
6. The goal table.

The baseline is ``tests/helpers/ik_reference.py``'s FABRIK: Aristidou & Lasenby's Algorithm 1 in plain numpy, one joint
at a time, with the same cone limits (it has no obstacles), iterated to the same tolerance and cap in the same process;
``× baseline`` is its time over ours. Every single-solve time is the fastest of three runs (timeit's rule: another
process taking the core mid-solve says nothing about the solver). The machine may be shared: read the figures with
the load printed beside them.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

import numba  # noqa: E402
from helpers import ik_reference  # noqa: E402

from kernels import fabrik  # noqa: E402

PAPER = {"fabrik": (15.5, 13.3), "ccd": (26.3, 123.6), "jacobian_dls": (999.0, 10480.0)}
"""Aristidou & Lasenby 2011 Table 1: mean iterations and ms per solve (10 joints, 20 runs, MATLAB)."""
OBSTACLES = [
    (np.array([0.35, 0.0, 0.55]), 0.08),
    (np.array([-0.3, 0.1, 0.6]), 0.1),
    (np.array([0.0, 0.35, 0.8]), 0.07),
    (np.array([0.3, 0.3, 0.25]), 0.09),
]
"""Four spheres around the 12 × 0.1 m chain's workspace (m)."""
LIMITS = math.radians(30.0)
REPEATS = 3
Array = NDArray[np.float64]


def arc_chain(n: int, link: float, d: int = 3, turn: float = 0.15) -> Array:
    """A rest pose: n links of length ``link`` (m) bending gently away from +z by ``turn`` rad per joint."""
    angles = turn * np.arange(n)
    directions = np.zeros((n, d))
    directions[:, 0] = np.sin(angles)
    directions[:, -1] = np.cos(angles)
    return np.vstack([np.zeros(d), np.cumsum(link * directions, axis=0)])


def random_targets(rng: np.random.Generator, count: int, radius: float, d: int = 3) -> Array:
    """Uniform in a ball of ``radius`` (m)."""
    v = rng.normal(size=(count, d))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    return v * radius * rng.uniform(0.0, 1.0, (count, 1)) ** (1.0 / d)


def drag_targets(frames: int) -> Array:
    """A figure-eight the scene's drag follows, one target a frame (m)."""
    s = 2.0 * math.pi * np.arange(frames) / frames
    return np.stack([0.45 * np.sin(s), 0.25 * np.sin(2 * s), 0.75 + 0.2 * np.cos(s)], axis=1)


def fastest(call: Callable[[], object]) -> tuple[float, object]:
    best, result = math.inf, None
    for _ in range(REPEATS):
        start = time.perf_counter()
        result = call()
        best = min(best, time.perf_counter() - start)
    return best, result


def baseline_solve(
    joints: Array, target: Array, tolerance: float, max_iterations: int, phi: float | None = None
) -> Array:
    """The plain numpy FABRIK, one iteration at a time until the tolerance or the cap."""
    pose = joints
    for _ in range(max_iterations):
        pose = ik_reference.fabrik(pose, target, 1, phi)[-1]
        if np.linalg.norm(pose[-1] - target) < tolerance:
            break
    return pose


def load() -> str:
    one, five, _ = os.getloadavg()
    return f"load {one:.1f} (1 min), {five:.1f} (5 min)"


def machine() -> None:
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    print(
        f"Machine: {cpu}, {os.cpu_count()} cores; Python {platform.python_version()}, numpy {np.__version__}, "
        f"numba {numba.__version__}, {numba.get_num_threads()} numba threads, threading layer "
        f"{numba.threading_layer()}; {load()}"
    )


def paper_setup(runs: int, seed: int, baseline_runs: int) -> dict[str, float]:
    rng = np.random.default_rng(seed)
    joints = arc_chain(10, 1.0)
    targets = random_targets(rng, runs, 0.9 * 10.0)
    tolerance = 0.01
    solvers = {
        "fabrik": lambda t: fabrik.solve(joints, t, tolerance=tolerance, max_iterations=5000),
        "fabrik, plain (no extrapolation)": lambda t: fabrik.solve(
            joints, t, tolerance=tolerance, max_iterations=5000, extrapolate=False
        ),
        "ccd": lambda t: fabrik.ccd(joints, t, tolerance=tolerance, max_iterations=5000),
        "jacobian_dls": lambda t: fabrik.jacobian_dls(joints, t, tolerance=tolerance, max_iterations=5000),
    }
    base_s = np.mean(
        [fastest(lambda t=t: baseline_solve(joints, t, tolerance, 5000))[0] for t in targets[:baseline_runs]]
    )
    rows = {}
    for name, solver in solvers.items():
        times, iterations, reached = [], [], 0
        for target in targets:
            elapsed, result = fastest(lambda solver=solver, target=target: solver(target))
            assert isinstance(result, fabrik.Solution)
            times.append(elapsed)
            iterations.append(result.iterations)
            reached += result.status == "reached"
        rows[name] = (np.mean(iterations), np.mean(times) * 1e6, np.median(times) * 1e6, reached)
    print(f"\n## Paper setup: 10 links of 1 m, 3D, {runs} reachable random targets, tolerance {tolerance} m ({load()})")
    print(
        "| solver | mean iterations | mean µs/solve | median µs | reached | × baseline | paper iterations | paper ms |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for name, (its, mean_us, median_us, reached) in rows.items():
        paper_its, paper_ms = PAPER[name.split(",")[0]]
        print(
            f"| {name} | {its:.1f} | {mean_us:.1f} | {median_us:.1f} | {reached}/{runs} | "
            f"{base_s * 1e6 / mean_us:.0f}× | {paper_its:g} | {paper_ms:g} |"
        )
    print(f"| baseline: plain numpy FABRIK ({baseline_runs} targets) | | {base_s * 1e6:.0f} | | | 1× | | |")
    return {"paper_mean_us": rows["fabrik"][1], "paper_ratio": base_s * 1e6 / rows["fabrik"][1]}


def drag_row(label: str, times: list[float], iterations: list[int], statuses: list[str]) -> float:
    """Print one drag's table row (times in s) and return its p95 (µs)."""
    us = np.array(times) * 1e6
    names, counts = np.unique(statuses, return_counts=True)
    mix = ", ".join(f"{name} {count}" for name, count in zip(names, counts, strict=True))
    print(
        f"| {label} | {np.median(us):.1f} | {np.percentile(us, 95):.1f} | {us.max():.1f} | "
        f"{np.mean(iterations):.1f} | {np.percentile(iterations, 95):.0f} | {mix} |"
    )
    return float(np.percentile(us, 95))


def drag_latency(frames: int, baseline_frames: int) -> dict[str, float]:
    kwargs = {"cone_half_angle_rad": LIMITS, "obstacles": OBSTACLES}
    print(
        f"\n## One 12-link solve, 30° limits, 4 obstacles, tolerance 1 mm, max 50 iterations, dragged "
        f"({frames} frames, each warm-started from the last pose; {load()})"
    )
    print("| case | median µs | p95 µs | max µs | mean iterations | p95 iterations | statuses |")
    print("|---|---:|---:|---:|---:|---:|---|")
    figures = {}
    for label, extra in (("drag, limits + obstacles", kwargs), ("drag, nothing", {})):
        pose = arc_chain(12, 0.1)
        times, iterations, statuses = [], [], []
        for target in drag_targets(frames):
            elapsed, result = fastest(lambda target=target, pose=pose, extra=extra: fabrik.solve(pose, target, **extra))
            assert isinstance(result, fabrik.Solution)
            pose = result.joints
            times.append(elapsed)
            iterations.append(result.iterations)
            statuses.append(result.status)
        figures.setdefault("drag_p95_us", drag_row(label, times, iterations, statuses))
    # The baseline follows the same drag with the same limits (it knows no obstacles).
    pose, times = arc_chain(12, 0.1), []
    for target in drag_targets(frames)[:baseline_frames]:
        elapsed, pose = fastest(lambda target=target, pose=pose: baseline_solve(pose, target, 1e-3, 50, LIMITS))
        times.append(elapsed)
    us = np.array(times) * 1e6
    print(
        f"| baseline: plain numpy FABRIK, limits only ({baseline_frames} frames) | "
        f"{np.median(us):.0f} | {np.percentile(us, 95):.0f} | {us.max():.0f} | | | |"
    )
    figures["drag_ratio"] = float(np.percentile(us, 95)) / figures["drag_p95_us"]
    return figures


def batch_throughput(batch: int, baseline_chains: int, seed: int) -> dict[str, float]:
    rng = np.random.default_rng(seed)
    rest = arc_chain(12, 0.1)
    joints = np.repeat(rest[None], batch, axis=0)
    targets = random_targets(rng, batch, 0.9 * 1.2)
    print(
        f"\n## solve_batch, 12 links of 0.1 m, B = {batch} random targets from rest, tolerance 1 mm, max 50 "
        f"iterations, {numba.get_num_threads()} threads ({load()})"
    )
    print(
        "| case | batch s (fastest of 3) | chains/s | CPU s / wall s | chains per CPU-second, 1 thread "
        "| mean iterations | statuses | baseline chains/s | × baseline |"
    )
    print("|---|---:|---:|---:|---:|---:|---|---:|---:|")
    figures = {}
    cases = {
        "no limits": ({}, None),
        "30° limits + 4 obstacles": ({"cone_half_angle_rad": LIMITS, "obstacles": OBSTACLES}, LIMITS),
    }
    for label, (kwargs, phi) in cases.items():
        best, cpu, result = math.inf, math.nan, None
        for _ in range(REPEATS):
            start, start_cpu = time.perf_counter(), time.process_time()
            result = fabrik.solve_batch(joints, targets, **kwargs)
            wall = time.perf_counter() - start
            if wall < best:
                best, cpu = wall, (time.process_time() - start_cpu) / wall
        assert result is not None
        # One thread's CPU time: what a core does, whatever else the shared machine runs.
        threads = numba.get_num_threads()
        numba.set_num_threads(1)
        one_core = math.inf
        for _ in range(REPEATS):
            start_cpu = time.process_time()
            fabrik.solve_batch(joints, targets, **kwargs)
            one_core = min(one_core, time.process_time() - start_cpu)
        numba.set_num_threads(threads)
        base = time.perf_counter()
        for i in range(baseline_chains):
            baseline_solve(joints[i], targets[i], 1e-3, 50, phi)
        base_rate = baseline_chains / (time.perf_counter() - base)
        rate = batch / best
        names, counts = np.unique(result.status, return_counts=True)
        mix = ", ".join(f"{name} {count}" for name, count in zip(names, counts, strict=True))
        print(
            f"| {label} | {best:.4f} | {rate:,.0f} | {cpu:.2f} | {batch / one_core:,.0f} | "
            f"{result.iterations.mean():.1f} | {mix} | "
            f"{base_rate:,.0f} | {rate / base_rate:,.0f}× |"
        )
        figures[label] = rate
        figures[label + ", per core"] = batch / one_core
    return figures


def tree_30() -> tuple[list[int], Array, list[fabrik.Constraint]]:
    """30 joints: a root, a trunk of 4 links to a sub-base, and 5 branches of 5 links (0.1 m each, 60° cones)."""
    parents = [-1, 0, 1, 2, 3]
    for _ in range(5):
        parents.append(4)
        parents.extend(range(len(parents) - 1, len(parents) + 3))
    joints = np.zeros((30, 3))
    for j in range(1, 5):
        joints[j] = joints[j - 1] + (0.0, 0.0, 0.1)
    for b in range(5):
        angle = 2 * math.pi * b / 5
        direction = np.array([0.6 * math.cos(angle), 0.6 * math.sin(angle), 0.8])
        for k in range(5):
            j = 5 + 5 * b + k
            joints[j] = joints[parents[j]] + 0.1 * direction
    constraints: list[fabrik.Constraint] = [None, *[fabrik.Cone(math.radians(60.0))] * 29]
    return parents, joints, constraints


def skeletons(frames: int) -> dict[str, float]:
    """The arm scene's hand preset with every fingertip target moving, and a 30-joint tree."""
    print(
        f"\n## Skeletons (solve_tree), tolerance 1 mm, max 50 iterations, {frames} frames, each warm-started "
        f"from the last pose ({load()})"
    )
    print("| case | median µs | p95 µs | max µs | mean iterations | p95 iterations | statuses |")
    print("|---|---:|---:|---:|---:|---:|---|")
    from scenes._skeletons import hand

    figures = {}
    rest = hand()
    phase = np.linspace(0.0, 2 * math.pi, frames)
    # Every fingertip target moves every frame: each finger curls and opens on a cycle of its own.
    curls = [hand(target_curl_rad=0.2 + 0.4 * (1 + math.sin(t))).targets for t in phase]
    finger_phase = [hand(target_curl_rad=0.2 + 0.4 * (1 + math.cos(1.7 * t))).targets for t in phase]
    tree = tree_30()
    cases = {
        "hand: 5 fingers × 3 hinges (+ welded palm), all 5 targets moving": (
            list(rest.parents),
            rest.joints,
            list(rest.constraints),
            list(rest.effectors),
            [np.where(np.arange(5)[:, None] % 2 == 0, a, b) for a, b in zip(curls, finger_phase, strict=True)],
        ),
        "30-joint tree, 5 effectors, 60° cones, all 5 targets moving": (
            tree[0],
            tree[1],
            tree[2],
            [9, 14, 19, 24, 29],
            [
                tree[1][[9, 14, 19, 24, 29]]
                + 0.15
                * np.stack(
                    [np.sin(t + np.arange(5)), np.cos(1.3 * t + np.arange(5)), np.full(5, -abs(math.sin(t)))], axis=1
                )
                for t in phase
            ],
        ),
    }
    for label, (parents, joints, constraints, effectors, targets) in cases.items():
        pose, times, iterations, statuses = joints.copy(), [], [], []
        for frame in targets:
            goal = {e: frame[k] for k, e in enumerate(effectors)}
            elapsed, result = fastest(
                lambda pose=pose, goal=goal, parents=parents, constraints=constraints: fabrik.solve_tree(
                    parents, pose, goal, constraints=constraints
                )
            )
            assert isinstance(result, fabrik.TreeSolution)
            pose = result.joints
            times.append(elapsed)
            iterations.append(result.iterations)
            statuses.extend(result.status)
        figures[label.split(":")[0].split(",")[0]] = drag_row(label, times, iterations, statuses)
    return figures


def overhead(calls: int) -> dict[str, float]:
    """Median and p95 of the compiled single-chain entry alone and of a full ``solve`` call, same chain and target."""
    from kernels.fabrik.api import compiled_single_solve

    print(
        f"\n## Python around the core: one solve, links of 0.1 m, 3D, no limits, {calls} calls each, "
        f"interleaved ({load()})"
    )
    print("| links | core median µs | core p95 µs | solve median µs | solve p95 µs | ratio (median) |")
    print("|---:|---:|---:|---:|---:|---:|")
    figures = {}
    for n in (2, 4, 8, 16):
        joints = arc_chain(n, 0.1)
        target = np.array([0.05, 0.02, 0.07 * n])
        solve_core, args = compiled_single_solve(joints, target)
        core, full = np.empty(calls), np.empty(calls)
        for i in range(calls):  # interleaved, so a busy moment on the shared machine hits both
            start = time.perf_counter()
            solve_core(*args)
            middle = time.perf_counter()
            fabrik.solve(joints, target)
            core[i], full[i] = middle - start, time.perf_counter() - middle
        core_us, full_us = core * 1e6, full * 1e6
        ratio = float(np.median(full_us) / np.median(core_us))
        print(
            f"| {n} | {np.median(core_us):.1f} | {np.percentile(core_us, 95):.1f} | "
            f"{np.median(full_us):.1f} | {np.percentile(full_us, 95):.1f} | {ratio:.2f} |"
        )
        figures[f"ratio {n}"] = ratio
    return figures


def cold_start() -> dict[str, float]:
    """Compile every core in a fresh process with an empty cache, then load them from that cache."""
    code = (
        "import time; t = time.perf_counter(); from kernels import fabrik; fabrik.warm_up(); "
        "print(time.perf_counter() - t)"
    )
    figures = {}
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache, "PYTHONPATH": str(ROOT)}
        for label in ("cold (empty cache: compile)", "warm (cache present: load)"):
            out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
            figures[label] = float(out.stdout.split()[-1])
    print(f"\n## Start-up: import kernels.fabrik + warm_up() in a fresh process ({load()})")
    print("| case | s |")
    print("|---|---:|")
    for label, seconds in figures.items():
        print(f"| {label} | {seconds:.2f} |")
    return figures


def main() -> None:
    parser = argparse.ArgumentParser(description="Benchmark the arm scene's IK solvers.")
    parser.add_argument("--runs", type=int, default=100, help="targets in the paper setup")
    parser.add_argument("--frames", type=int, default=500, help="frames of the drag")
    parser.add_argument("--batch", type=int, default=10_000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--quick", action="store_true", help="fewer solves, for a smoke run")
    parser.add_argument("--overhead", action="store_true", help="only the Python-around-the-core table")
    args = parser.parse_args()
    if args.quick:
        args.runs, args.frames, args.batch = 20, 100, 2000
    fabrik.warm_up()
    machine()
    if args.overhead:
        overhead(20_000)
        return
    paper = paper_setup(args.runs, args.seed, baseline_runs=max(5, args.runs // 10))
    drag = drag_latency(args.frames, baseline_frames=max(10, args.frames // 10))
    batch = batch_throughput(args.batch, baseline_chains=100, seed=args.seed)
    trees = skeletons(args.frames)
    around = overhead(2000 if args.quick else 20_000)
    start = cold_start()
    threads = numba.get_num_threads()
    print(f"\n## Goals ({threads} threads; {load()})")
    print("| measure | goal | measured | × baseline | met |")
    print("|---|---|---:|---:|---|")
    rows = [
        (
            "FABRIK, 12 links, 30° limits, 4 obstacles, drag p95",
            "≤ 50 µs",
            f"{drag['drag_p95_us']:.1f} µs",
            f"{drag['drag_ratio']:.0f}×",
            drag["drag_p95_us"] <= 50,
        ),
        (
            "FABRIK, paper setup, mean per solve",
            "≤ 10 µs",
            f"{paper['paper_mean_us']:.1f} µs",
            f"{paper['paper_ratio']:.0f}×",
            paper["paper_mean_us"] <= 10,
        ),
        (
            "solve_batch, 12 links, no limits",
            "≥ 1.5 M chains/s on 2 cores",
            f"{batch['no limits']:,.0f}/s ({batch['no limits, per core']:,.0f}/s per core)",
            "",
            batch["no limits"] >= 1.5e6,
        ),
        (
            "solve_batch, 12 links, limits + 4 obstacles",
            "≥ 300 k chains/s",
            f"{batch['30° limits + 4 obstacles']:,.0f}/s "
            f"({batch['30° limits + 4 obstacles, per core']:,.0f}/s per core)",
            "",
            batch["30° limits + 4 obstacles"] >= 3e5,
        ),
        ("cold start: compile every core", "report it", f"{start['cold (empty cache: compile)']:.1f} s", "", True),
        (
            "warm start: load every core from the cache",
            "(part of app start ≤ 3 s)",
            f"{start['warm (cache present: load)']:.2f} s",
            "",
            start["warm (cache present: load)"] <= 3,
        ),
        (
            "hand, 5 fingers × 3 hinges, all targets moving, p95",
            "≤ 100 µs",
            f"{trees['hand']:.1f} µs",
            "",
            trees["hand"] <= 100,
        ),
        (
            "30-joint tree, 5 effectors, p95",
            "≤ 1 ms",
            f"{trees['30-joint tree']:.1f} µs",
            "",
            trees["30-joint tree"] <= 1000,
        ),
        (
            "one solve over its compiled core, 2–16 links, median",
            "≤ 2×",
            f"{max(around.values()):.2f}× (worst)",
            "",
            max(around.values()) <= 2.0,
        ),
    ]
    for measure, goal, measured, ratio, met in rows:
        print(f"| {measure} | {goal} | {measured} | {ratio} | {'met' if met else 'NOT met'} |")


if __name__ == "__main__":
    main()
