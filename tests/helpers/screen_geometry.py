"""Screen-space geometry the view tests share: a pinhole camera written out apart from the scenes', how far apart
two drawn polylines are, and the goal's box."""

from __future__ import annotations

import math

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


def pinhole_ndc(
    points: NDArray[np.float64],
    position: NDArray[np.float64],
    look_at: NDArray[np.float64],
    fov_rad: float,
    aspect: float,
) -> NDArray[np.float64]:
    """Pinhole projection with z up, written out apart from the scenes' own: (N, 3) NDC x, y and depth (m) of
    (N, 3) world points (m), for a camera at ``position`` looking at ``look_at`` with vertical field of view
    ``fov_rad`` and width/height ``aspect``."""
    d = (look_at - position) / np.linalg.norm(look_at - position)
    right = np.cross(d, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, d)
    rel = points - position
    depth = rel @ d
    tan_y = math.tan(fov_rad / 2)
    return np.stack([(rel @ right) / (depth * tan_y * aspect), (rel @ up) / (depth * tan_y), depth], axis=1)
