"""Screen-space geometry the free-kick view tests share: how far apart two drawn polylines are, and the goal's box."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from kernels import ball

GOAL_CORNERS = np.array(
    [
        [x, y, z]
        for x in (0.0, 2.0)
        for y in (-0.5 * ball.GOAL_WIDTH_M, 0.5 * ball.GOAL_WIDTH_M)
        for z in (0.0, ball.GOAL_HEIGHT_M)
    ]
)
"""(8, 3) corners of the goal mouth and its net, 2 m deep (world frame, m)."""


def polyline_gap(points: NDArray[np.float64], polyline: NDArray[np.float64]) -> NDArray[np.float64]:
    """(N,) distance from each of ``points`` (N, 2) to the nearest point of the polyline through ``polyline`` (M, 2).

    On the screen, that is how far from the other line a person sees each point of one line (px in, px out).
    """
    a, b = polyline[:-1], polyline[1:]
    ab = b - a
    rel = points[:, None, :] - a[None, :, :]
    t = np.clip((rel * ab).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-12), 0.0, 1.0)
    nearest = a[None] + t[..., None] * ab[None]
    return np.linalg.norm(points[:, None, :] - nearest, axis=-1).min(axis=1)
