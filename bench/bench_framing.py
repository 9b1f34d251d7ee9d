"""Benchmark camera framing: ``frame_points`` against the nested bisections it replaced (run in the same process).

    python bench/bench_framing.py

Prints median and p95 milliseconds per call for the peloton's framing (the line's 8 box corners, fov 1.3 rad, aspect
1.6, the rectangle left of the panel and the labels in a 1600 × 1000 canvas) and for a 200-point cloud, for the
closed-form ``frame_points`` and for the former implementation (copied below as the baseline: a 60-step bisection on
the distance, each step running two 60-step bisections of the centring shift), with their ratio and the largest
difference between the two views (m).
"""

from __future__ import annotations

import math
import statistics
import sys
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench._timing import p95, timings  # noqa: E402
from scenes._framing import FULL_NDC, NEAR_M, Lens, Sight, View, box_corners, frame_points  # noqa: E402


def baseline_frame_points(
    sight: Sight, ndc: tuple[float, float, float, float] = FULL_NDC, min_depth: float = 0.0
) -> View:
    """``scenes._framing.frame_points`` as it was before the closed form (commit 3b41d9e), from the same
    :class:`~scenes._framing.Sight` of the points."""
    x0, x1, y0, y1 = ndc
    u, v, w = sight.offsets
    tan_x, tan_y, depth_extent, size = sight.tan_x, sight.tan_y, sight.depth_extent, sight.size

    def shift(coord: NDArray[np.float64], scale: NDArray[np.float64], lo: float, hi: float) -> float:
        reach = size + 1.0 + float(np.max(scale)) * (abs(lo) + abs(hi) + 1.0)
        a, b = -reach, reach
        for _ in range(60):
            s = 0.5 * (a + b)
            p = (coord - s) / scale
            if 0.5 * (p.min() + p.max()) > 0.5 * (lo + hi):
                a = s
            else:
                b = s
        return 0.5 * (a + b)

    least_depth = max(min_depth, NEAR_M) if math.isfinite(min_depth) else NEAR_M

    def fits(distance: float) -> tuple[bool, float, float]:
        depth = distance + w
        if np.any(depth < least_depth):
            return False, 0.0, 0.0
        sx = shift(u, depth * tan_x, x0, x1)
        sy = shift(v, depth * tan_y, y0, y1)
        px, py = (u - sx) / (depth * tan_x), (v - sy) / (depth * tan_y)
        ok = px.min() >= x0 and px.max() <= x1 and py.min() >= y0 and py.max() <= y1
        return bool(ok), sx, sy

    near = depth_extent + NEAR_M
    far = depth_extent + least_depth + 1000.0 * (size + 1.0)
    for _ in range(60):
        mid = 0.5 * (near + far)
        if fits(mid)[0]:
            far = mid
        else:
            near = mid
    ok, sx, sy = fits(far)
    if not ok:
        if ndc != FULL_NDC:
            return baseline_frame_points(sight, FULL_NDC, min_depth)
    return sight.view(far, sx, sy)


def main() -> None:
    lens = Lens(1.3, 1600, 1000)
    peloton = box_corners((-54.75, -1.1, 0.0), (0.85, 1.1, 4.26))
    cloud = np.random.default_rng(0).normal(0.0, 5.0, (200, 3))
    cases: list[tuple[str, NDArray[np.float64], tuple[float, float, float, float]]] = [
        ("peloton line, 8 corners", peloton, lens.usable_ndc(right_px=190.0, top_px=30.0)),
        ("200-point cloud", cloud, lens.usable_ndc()),
    ]
    direction = (-1.2, 7.5, -1.8)
    print(
        f"{'case':<26} {'new median':>11} {'new p95':>9} {'old median':>11} {'old p95':>9} {'ratio':>7} {'Δ view':>9}"
    )
    for name, pts, ndc in cases:

        def new(pts: NDArray[np.float64] = pts, ndc: tuple[float, float, float, float] = ndc) -> View:
            return frame_points(pts, direction, fov_rad=lens.fov_rad, aspect=lens.aspect, ndc=ndc)

        def old(pts: NDArray[np.float64] = pts, ndc: tuple[float, float, float, float] = ndc) -> View:
            return baseline_frame_points(Sight.of(pts, direction, fov_rad=lens.fov_rad, aspect=lens.aspect), ndc)

        fast, slow = timings(new, 2000, warmup=1, scale=1e3), timings(old, 40, warmup=1, scale=1e3)
        a, b = new(), old()
        diff = max(
            float(np.abs(np.subtract(a.position, b.position)).max()),
            float(np.abs(np.subtract(a.look_at, b.look_at)).max()),
        )
        ratio = statistics.median(slow) / statistics.median(fast)
        print(
            f"{name:<26} {statistics.median(fast):>8.3f} ms {p95(fast):>6.3f} ms "
            f"{statistics.median(slow):>8.2f} ms {p95(slow):>6.2f} ms {ratio:>6.0f}× {diff:>9.1e}"
        )


if __name__ == "__main__":
    main()
