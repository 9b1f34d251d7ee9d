"""Rider meshes: a low-poly bike, body and head per riding position, and the batched nodes that draw a line of them.

Meshes are in the bike frame (x forward, z up, ground at z = 0, m). :func:`add_riders` makes one batched mesh per part
with an instance per rider slot (:data:`~scenes.peloton.model.MAX_RIDERS`), so the line and the course draw their
riders the same way, and :func:`show_position` re-meshes them when the riding position changes.
"""

from __future__ import annotations

import functools
import math
from typing import Literal

import numpy as np
import trimesh
import viser

from scenes._instances import add_instances
from scenes.peloton.model import MAX_RIDERS, POSITIONS, Position

GRASS_COLOUR = (168, 205, 150)
"""The verge's grass (8-bit sRGB, drawn unlit: after viser's tone mapping it shows as the lit grass did)."""
ROAD_COLOUR = (110, 112, 127)
"""The road's asphalt (8-bit sRGB, drawn unlit, as :data:`GRASS_COLOUR`)."""
JERSEYS = np.array(
    [
        (220, 40, 40),
        (30, 110, 220),
        (250, 200, 30),
        (40, 170, 90),
        (150, 60, 200),
        (250, 130, 30),
        (30, 190, 200),
        (230, 90, 160),
    ],
    dtype=np.uint8,
)
RIDER_COLOURS = {
    "bike": np.full((MAX_RIDERS, 3), 45, np.uint8),
    "body": JERSEYS,
    "head": np.full((MAX_RIDERS, 3), 235, np.uint8),
}
"""(MAX_RIDERS, 3) uint8 colour of each part, per rider slot: bikes dark, bodies in team jerseys, heads pale."""


Detail = Literal["full", "light", "crowd"]
"""How finely a rider is meshed: ``"full"`` (1 504 triangles) for a line of a few riders seen close, ``"light"``
(412) for a group, where a rider is a few dozen pixels tall, ``"crowd"`` (186: open rods, flat wheels) for a bunch,
where most riders are a few pixels tall. Chromium's software WebGL spends its frame on the riders' triangles: a bunch
of 121 drew 4.3 → 10.0 frames/s at 1280×720 with the light mesh and more with the crowd mesh
(docs/performance.md)."""

LIGHT_ABOVE = 8
"""Riders are meshed ``"light"`` when more than this many ride."""
CROWD_ABOVE = 40
"""Riders are meshed ``"crowd"`` when more than this many ride."""

SECTIONS: dict[Detail, dict[str, int]] = {
    "full": {"rod": 8, "wheel_major": 24, "wheel_minor": 6, "capsule": 8, "head": 2, "caps": 1},
    "light": {"rod": 3, "wheel_major": 10, "wheel_minor": 3, "capsule": 4, "head": 1, "caps": 1},
    "crowd": {"rod": 3, "wheel_major": 8, "wheel_minor": 2, "capsule": 0, "head": 0, "caps": 0},
}
"""Per detail: sides of a rod, segments round a wheel and round its tyre (2: a flat ring in the wheel's plane), rings
of the torso's capsule (0: the torso is a 6-sided open rod), subdivisions of the head's icosphere, and whether rods have
end caps (an open rod's ends do not show a few pixels tall)."""


def rider_detail(n_riders: int) -> Detail:
    """The mesh detail for a group of ``n_riders``."""
    return "crowd" if n_riders > CROWD_ABOVE else "light" if n_riders > LIGHT_ABOVE else "full"


def rod(a: np.ndarray, b: np.ndarray, radius: float, sections: int = 8, caps: bool = True) -> trimesh.Trimesh:
    """A cylinder of ``sections`` sides and ``radius`` from (3,) point ``a`` to ``b`` (m); without ``caps`` only its
    sides (2·``sections`` triangles)."""
    if caps:
        return trimesh.creation.cylinder(radius=radius, segment=np.array([a, b]), sections=sections)
    axis = (b - a) / np.linalg.norm(b - a)
    side = np.cross(axis, [0.0, 0.0, 1.0] if abs(axis[2]) < 0.9 else [1.0, 0.0, 0.0])
    side /= np.linalg.norm(side)
    up = np.cross(axis, side)
    angles = 2.0 * math.pi * np.arange(sections) / sections
    ring = radius * (np.cos(angles)[:, None] * side + np.sin(angles)[:, None] * up)
    k = np.arange(sections)
    nxt = (k + 1) % sections
    faces = np.concatenate([np.stack([k, nxt, k + sections], 1), np.stack([nxt, nxt + sections, k + sections], 1)])
    return trimesh.Trimesh(np.concatenate([a + ring, b + ring]), faces, process=False)


def two_bone_knee(hip: np.ndarray, foot: np.ndarray, thigh: float, shin: float) -> np.ndarray:
    """Knee position in the xz plane by the law of cosines, bending forward (as a rider's knee does)."""
    d_vec = foot - hip
    d = float(np.clip(np.linalg.norm(d_vec), 1e-6, thigh + shin - 1e-6))
    along = (thigh**2 - shin**2 + d**2) / (2 * d)
    height = math.sqrt(max(thigh**2 - along**2, 0.0))
    u = d_vec / np.linalg.norm(d_vec)
    forward = np.array([u[2], 0.0, -u[0]])  # u rotated by −90° about y: in front of the hip–foot line
    if forward[0] < 0:
        forward = -forward
    return hip + along * u + height * forward


@functools.cache
def rider_meshes(position: Position, detail: Detail = "full") -> dict[str, trimesh.Trimesh]:
    """Low-poly bike, body and head for one rider, in the bike frame (x forward, z up, ground at z = 0), meshed at
    ``detail`` (:data:`SECTIONS`). The meshes are cached and shared: copy before changing one."""
    pose, n = POSITIONS[position], SECTIONS[detail]
    rod_n = functools.partial(rod, sections=n["rod"], caps=bool(n["caps"]))
    wheel_r = 0.34
    rear, front = np.array([-0.51, 0.0, wheel_r]), np.array([0.51, 0.0, wheel_r])
    bb = np.array([-0.04, 0.0, 0.27])
    seat = np.array([-0.20, 0.0, 0.86])
    head_top = np.array([0.40, 0.0, 0.80])
    bars = np.array([pose.hands[0] - 0.02, 0.0, pose.hands[2] - 0.02])

    bike_parts = []
    for centre in (rear, front):
        wheel = trimesh.creation.torus(
            major_radius=wheel_r - 0.015,
            minor_radius=0.018,
            major_sections=n["wheel_major"],
            minor_sections=n["wheel_minor"],
        )
        if n["wheel_minor"] == 2:  # a flat ring: its two faces must not share vertices, or their normals cancel
            wheel.unmerge_vertices()
        wheel.apply_transform(trimesh.transformations.rotation_matrix(math.pi / 2, [1, 0, 0]))
        wheel.apply_translation(centre)
        bike_parts.append(wheel)
    for a, b in ((rear, bb), (rear, seat), (bb, seat), (bb, head_top), (seat, head_top), (head_top, front)):
        bike_parts.append(rod_n(a, b, 0.016))
    bike_parts.append(rod_n(head_top, bars, 0.014))
    bike_parts.append(rod_n(bars + [0, -0.2, 0], bars + [0, 0.2, 0], 0.012))
    bike_parts.append(rod_n(seat + [-0.08, 0, 0.03], seat + [0.08, 0, 0.03], 0.03))

    theta = math.radians(pose.torso_deg)
    hip = seat + np.array([0.0, 0.0, 0.08])
    shoulder = hip + 0.58 * np.array([math.cos(theta), 0.0, math.sin(theta)])
    if n["capsule"]:
        torso = trimesh.creation.capsule(height=0.58, radius=0.12, count=[n["capsule"], n["capsule"]])
        torso.apply_transform(
            trimesh.geometry.align_vectors([0, 0, 1], shoulder - hip)  # capsule axis along the torso
        )
        torso.apply_translation((hip + shoulder) / 2)
    else:  # a 6-sided rod a little past the hips and shoulders, where the capsule's round ends reach
        along = (shoulder - hip) / np.linalg.norm(shoulder - hip)
        torso = rod(hip - 0.09 * along, shoulder + 0.09 * along, 0.12, 6, caps=False)
    body_parts = [torso]
    hands = np.array(pose.hands)
    for side in (-1.0, 1.0):
        s = shoulder + [0.0, side * 0.17, 0.0]
        h = hands * [1.0, side, 1.0]
        if position in ("tt", "hour"):  # elbows on the pads: upper arm down, forearm forward
            elbow = np.array([s[0] + 0.05, side * 0.09, hands[2] - 0.02])
            body_parts += [rod_n(s, elbow, 0.045), rod_n(elbow, h, 0.04)]
        else:
            body_parts.append(rod_n(s, h, 0.045))
        crank = np.array([side * 0.17 * 0.7, 0.0, -side * 0.17 * 0.7])
        foot = bb + crank + [0.0, side * 0.12, 0.0]
        h_side = hip + [0.0, side * 0.1, 0.0]
        knee = two_bone_knee(h_side, foot, 0.46, 0.46)
        body_parts += [rod_n(h_side, knee, 0.065), rod_n(knee, foot, 0.05)]
    head_centre = shoulder + 0.17 * np.array([math.cos(theta * 0.5), 0.0, math.sin(theta * 0.5) + 0.6])
    head = trimesh.creation.icosphere(subdivisions=n["head"], radius=0.12)
    head.apply_translation(head_centre)
    bike, body = trimesh.util.concatenate(bike_parts), trimesh.util.concatenate(body_parts)
    assert isinstance(bike, trimesh.Trimesh) and isinstance(body, trimesh.Trimesh)
    return {"bike": bike, "body": body, "head": head}


@functools.cache
def rider_head_m(position: Position) -> tuple[float, float]:
    """(ahead, up): where the top of a rider's head is in ``position``, ahead of the bike's middle and above the
    road (m)."""
    head = rider_meshes(position)["head"].vertices
    return float(0.5 * (head[:, 0].min() + head[:, 0].max())), float(head[:, 2].max())


def rider_colours(part: str, count: int) -> np.ndarray:
    """(count, 3) uint8 colours of one part for ``count`` riders: :data:`RIDER_COLOURS`, the jerseys repeating."""
    return np.resize(RIDER_COLOURS[part], (count, 3)).astype(np.uint8)


def add_riders(
    scene: viser.SceneApi,
    prefix: str,
    position: Position,
    scale: float,
    count: int = MAX_RIDERS,
    detail: Detail = "full",
) -> dict[str, viser.BatchedMeshHandle]:
    """One batched mesh per part (``<prefix>_bike``, ``_body``, ``_head``), ``count`` instances (one per rider
    slot), all at the origin and scaled by ``scale`` (0 hides them until they are placed). Three nodes whatever the
    count: 121 riders cost the browser three draw calls, as 8 do."""
    nodes: dict[str, viser.BatchedMeshHandle] = {}
    for part, mesh in rider_meshes(position, detail).items():
        nodes[part] = add_instances(scene, f"{prefix}_{part}", mesh, count, rider_colours(part, count), scale=scale)
    return nodes


def show_position(nodes: dict[str, viser.BatchedMeshHandle], position: Position, detail: Detail = "full") -> None:
    """Re-mesh the riders of :func:`add_riders` for another riding position or detail."""
    for part, mesh in rider_meshes(position, detail).items():
        nodes[part].vertices = mesh.vertices.astype(np.float32)
        nodes[part].faces = mesh.faces.astype(np.uint32)
