"""The free kick's props as plain geometry: goal frame, net, pitch markings, a defender, force arrows, dashed and
polyline segments, the spin band's strip, and the colours they are drawn in. No viser: trimesh meshes and (S, 2, 3)
segment arrays in the pitch's world frame (m).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import trimesh
from numpy.typing import NDArray

from kernels import ball
from scenes.freekick.model import DEFENDER_HEIGHT_M

ARROW_POINTS = 4
"""Places along the path where force arrows are drawn (few enough that neighbouring arrows never overlap)."""
METRES_PER_NEWTON = 0.3
"""Force-arrow length scale."""
FORCE_COLOURS = {"drag": (230, 40, 40), "magnus": (40, 90, 240), "gravity": (120, 50, 170)}
"""Arrow and chart colours: red, blue and purple read on grass, sky and the white net alike."""
KNUCKLE_COLOUR = (240, 150, 20)
PATH_COLOUR = (255, 140, 0)
"""The kick as set: a thick orange line."""
GHOST_COLOUR = (40, 40, 40)
AFTER_COLOUR = (255, 215, 150)
"""The kick played on after its first contact (pale orange, beside the kick's own orange)."""
"""The no-spin ghost: thin, dark and dashed, so it never reads as the kick itself."""


def dashed(segments: NDArray[np.float32]) -> NDArray[np.float32]:
    """(S, 2, 3) the same segments with every other one shrunk to a point: a dashed line of the same node."""
    out = segments.copy()
    out[1::2, 1] = out[1::2, 0]
    return out


def _cylinder(a: NDArray[np.float64], b: NDArray[np.float64], radius: float) -> trimesh.Trimesh:
    return trimesh.creation.cylinder(radius=radius, segment=np.array([a, b]), sections=12)


def goal_frame_mesh() -> trimesh.Trimesh:
    """Posts and crossbar, 12 cm thick, inner edges on the goal mouth."""
    r, half, h = 0.06, 0.5 * ball.GOAL_WIDTH_M, ball.GOAL_HEIGHT_M
    parts = [
        _cylinder(np.array([r, side * (half + r), 0.0]), np.array([r, side * (half + r), h + r]), r)
        for side in (-1.0, 1.0)
    ]
    parts.append(_cylinder(np.array([r, -(half + 2 * r), h + r]), np.array([r, half + 2 * r, h + r]), r))
    mesh = trimesh.util.concatenate(parts)
    assert isinstance(mesh, trimesh.Trimesh)
    return mesh


def net_segments(depth: float = 2.0, spacing: float = 0.3) -> NDArray[np.float64]:
    """(S, 2, 3) net lines: back, roof and sides of a box behind the goal."""
    half, h = 0.5 * ball.GOAL_WIDTH_M, ball.GOAL_HEIGHT_M
    segs: list[list[list[float]]] = []
    for y in np.arange(-half, half + 1e-6, spacing):
        segs.append([[depth, y, 0.0], [depth, y, h]])  # back, vertical
        segs.append([[0.0, y, h], [depth, y, h]])  # roof, front to back
    for z in np.arange(0.0, h + 1e-6, spacing):
        segs.append([[depth, -half, z], [depth, half, z]])  # back, horizontal
        for side in (-half, half):
            segs.append([[0.0, side, z], [depth, side, z]])  # sides
    for x in np.arange(0.0, depth + 1e-6, spacing):
        segs.append([[x, -half, h], [x, half, h]])  # roof, across
        for side in (-half, half):
            segs.append([[x, side, 0.0], [x, side, h]])
    return np.array(segs)


def pitch_markings() -> NDArray[np.float64]:
    """(S, 2, 3) white lines near the penalty area: goal line, 6-yard box, penalty area, spot and arc."""
    z = 0.005
    segs: list[tuple[tuple[float, float, float], tuple[float, float, float]]] = []

    def box(depth: float, half_width: float) -> None:
        corners = [(0.0, -half_width), (-depth, -half_width), (-depth, half_width), (0.0, half_width)]
        for (x0, y0), (x1, y1) in itertools.pairwise(corners):
            segs.append(((x0, y0, z), (x1, y1, z)))

    segs.append(((0.0, -34.0, z), (0.0, 34.0, z)))  # goal line
    box(5.5, 9.16)  # goal area: 5.5 m from each post
    box(16.5, 20.16)  # penalty area: 16.5 m from each post
    spot = -11.0
    for a in np.linspace(0.0, 2 * math.pi, 9)[:-1]:
        b = a + 2 * math.pi / 8
        segs.append(
            ((spot + 0.11 * math.cos(a), 0.11 * math.sin(a), z), (spot + 0.11 * math.cos(b), 0.11 * math.sin(b), z))
        )
    # The arc: the part of the 9.15 m circle round the spot that lies outside the area.
    half_angle = math.acos(5.5 / 9.15)
    angles = np.linspace(math.pi - half_angle, math.pi + half_angle, 24)
    arc = [(spot + 9.15 * math.cos(a), 9.15 * math.sin(a), z) for a in angles]
    segs += list(itertools.pairwise(arc))
    return np.array(segs, dtype=np.float64)


def defender_mesh() -> trimesh.Trimesh:
    """One defender standing on z = 0: legs, body and head, 1.8 m tall."""
    body = trimesh.creation.capsule(height=0.75, radius=0.2, count=[10, 10])
    body.apply_translation((0.0, 0.0, 1.15))
    head = trimesh.creation.icosphere(subdivisions=2, radius=0.11)
    head.apply_translation((0.0, 0.0, DEFENDER_HEIGHT_M - 0.11))
    legs = [_cylinder(np.array([0.0, s, 0.0]), np.array([0.0, s, 0.85]), 0.08) for s in (-0.1, 0.1)]
    mesh = trimesh.util.concatenate([body, head, *legs])
    assert isinstance(mesh, trimesh.Trimesh)
    return mesh


def arrow_segments(
    origins: NDArray[np.float64], vectors: NDArray[np.float64], head: float = 0.3
) -> NDArray[np.float64]:
    """(3K, 2, 3): a shaft and two barbs for each of K arrows."""
    tips = origins + vectors
    length = np.linalg.norm(vectors, axis=1, keepdims=True)
    direction = vectors / np.where(length > 1e-9, length, 1.0)
    side = np.cross(direction, np.array([0.0, 0.0, 1.0]))
    side_norm = np.linalg.norm(side, axis=1, keepdims=True)
    side = np.where(side_norm > 1e-6, side / np.where(side_norm > 1e-6, side_norm, 1.0), [0.0, 1.0, 0.0])
    barb = np.minimum(head, 0.4 * length)
    left = tips - barb * direction + 0.5 * barb * side
    right = tips - barb * direction - 0.5 * barb * side
    return np.concatenate(
        [np.stack([origins, tips], axis=1), np.stack([left, tips], axis=1), np.stack([right, tips], axis=1)]
    )


def polyline_segments(points: NDArray[np.float64]) -> NDArray[np.float32]:
    """(N - 1, 2, 3) float32 segments joining consecutive points of an (N, 3) polyline."""
    return np.stack([points[:-1], points[1:]], axis=1).astype(np.float32)


def axis_angle_wxyz(axis: NDArray[np.float64], angle_rad: float) -> tuple[float, float, float, float]:
    """The wxyz quaternion turning ``angle_rad`` about (3,) ``axis`` (any length; zero gives no turn)."""
    norm = float(np.linalg.norm(axis))
    if norm == 0.0:
        return (1.0, 0.0, 0.0, 0.0)
    u = axis / norm * math.sin(angle_rad / 2)
    return (math.cos(angle_rad / 2), float(u[0]), float(u[1]), float(u[2]))


def strip_faces(n: int) -> NDArray[np.uint32]:
    """(2 (n - 1), 3) triangles of a strip between two n-point edges whose vertices interleave (a0, b0, a1, b1...)."""
    faces: list[list[int]] = []
    for i in range(n - 1):
        a, b = 2 * i, 2 * i + 1
        faces += [[a, b, a + 2], [b, b + 2, a + 2]]
    return np.array(faces, np.uint32)
