"""Batched meshes as every scene draws them: one mesh, a fixed number of instances placed later.

A scene makes as many instances as it can ever show, all upright and hidden (scaled to zero and parked far below
the ground, unless told otherwise), and afterwards only writes their ``batched_positions``, ``batched_wxyzs`` and
``batched_scales``: changing how many show never re-adds a node. Level of detail is off, since instances are few and
small.

A hidden instance is parked, not only scaled to zero (:func:`park_hidden`): viser's client culls each instance
against the view, and an instance scaled to zero at the origin is in view, so its vertices are still transformed
every frame. Parked, it is culled: the peloton's four riders among 121 instances drew 7.3 → 14.7 frames/s in
Chromium's software WebGL at 1280×720 (docs/performance.md).
"""

from __future__ import annotations

import numpy as np
import trimesh
import viser
from numpy.typing import NDArray

PARKED_AT_M = (0.0, 0.0, -1.0e5)
"""Where hidden instances wait (m): far below the ground, outside every view."""


def park_hidden(positions: NDArray[np.floating], scales: NDArray[np.floating]) -> NDArray[np.float32]:
    """(N, 3) float32 instance positions (m) with every instance of zero scale ((N, 3) or (N,) ``scales``) moved to
    :data:`PARKED_AT_M`; the others as given."""
    placed = np.array(positions, dtype=np.float32, copy=True).reshape(-1, 3)
    hidden = ~np.any(np.asarray(scales).reshape(len(placed), -1) != 0.0, axis=1)
    placed[hidden] = PARKED_AT_M
    return placed


def add_instances(
    scene: viser.SceneApi,
    name: str,
    mesh: trimesh.Trimesh,
    count: int,
    colors: tuple[int, int, int] | NDArray[np.uint8],
    *,
    scale: float | None = 0.0,
    opacity: float | None = None,
    cast_shadow: bool = True,
    visible: bool = True,
) -> viser.BatchedMeshHandle:
    """``count`` instances of ``mesh`` at the origin, upright, each scaled by ``scale`` (None: viser's default, 1).

    Args:
        scene: where to add the node.
        name: the node's name.
        mesh: the mesh every instance shows (float32 vertices and uint32 faces are sent).
        count: how many instances.
        colors: one RGB colour for all, or (count, 3) uint8 per instance.
        scale: every instance's scale at first; 0 hides them until they are placed.
        opacity: the mesh's opacity, or None for opaque.
        cast_shadow: whether the instances cast shadows.
        visible: whether the node shows at first.
    """
    return scene.add_batched_meshes_simple(
        name,
        vertices=mesh.vertices.astype(np.float32),
        faces=mesh.faces.astype(np.uint32),
        batched_wxyzs=np.tile([1.0, 0.0, 0.0, 0.0], (count, 1)),
        batched_positions=np.tile(np.array(PARKED_AT_M if scale == 0.0 else (0.0, 0.0, 0.0)), (count, 1)),
        batched_scales=None if scale is None else np.full((count, 3), scale),
        batched_colors=colors,
        opacity=opacity,
        lod="off",
        cast_shadow=cast_shadow,
        visible=visible,
    )
