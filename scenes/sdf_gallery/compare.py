"""How the gallery's mesh and its ray-march agree: the :class:`Agreement` readout and the comparison behind it.

:func:`compare` takes two depth images of one camera, (H, W) float (m, +inf where a ray misses): the sphere-traced
field and the rasterised mesh. :func:`readout_markdown` is the table the "Blend and mesh" folder shows. :class:`Wire`
is the mesh's edges the "both" view draws over the ray-march, where a person sees the two agree.
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
import trimesh


@dataclasses.dataclass(frozen=True)
class Agreement:
    """How the latest reference image and mesh compare, and what they cost."""

    triangles: int
    """Faces in the mesh."""
    mesh_ms: float
    """Time to mesh (ms)."""
    render_ms: float | None
    """Time to ray-march the reference (ms); None before the first."""
    iou: float | None
    """Silhouette intersection over union of mesh raster and ray-march."""
    depth_diff_voxels: float | None
    """Mean |depth difference| away from silhouette edges, in voxels of the mesh grid."""


def compare(marched: np.ndarray, rasterised: np.ndarray) -> tuple[float | None, float | None]:
    """Silhouette IoU and mean depth difference (m) away from silhouette edges (both masks eroded a pixel).

    Args:
        marched: (H, W) depth of the ray-march (m), +inf where a ray misses.
        rasterised: (H, W) depth of the mesh (m), +inf where no face is drawn.

    Returns:
        The IoU (None when neither shows anything) and the mean |difference| (None when no pixel is inside both).
    """
    a, b = np.isfinite(marched), np.isfinite(rasterised)
    union = int((a | b).sum())
    if union == 0:
        return None, None
    iou = float((a & b).sum()) / union
    both = a & b
    inner = np.zeros_like(both)
    inner[1:-1, 1:-1] = both[1:-1, 1:-1] & both[:-2, 1:-1] & both[2:, 1:-1] & both[1:-1, :-2] & both[1:-1, 2:]
    if not inner.any():
        return iou, None
    return iou, float(np.mean(np.abs(marched[inner].astype(np.float64) - rasterised[inner])))


def readout_markdown(a: Agreement) -> str:
    """The readout table of ``a``: triangles, times, IoU and depth difference ("–" for what is not known yet)."""
    render = "–" if a.render_ms is None else f"{a.render_ms:.0f} ms"
    iou = "–" if a.iou is None else f"{a.iou:.4f}"
    depth = "–" if a.depth_diff_voxels is None else f"{a.depth_diff_voxels:.3f} voxel"
    table = (
        f"| | |\n|---|---|\n| Triangles | {a.triangles:,} |\n| Time to mesh | {a.mesh_ms:.0f} ms |\n"
        f"| Time to render | {render} |\n| Silhouette IoU (mesh vs ray-march) | {iou} |\n"
        f"| Mean depth difference | {depth} |"
    )
    if a.triangles == 0:  # an outside tester: an empty view and "Triangles 0", with no word of why
        return f"{table}\n\n{EMPTY_MESH}"
    return table


EMPTY_MESH = (
    "**The mesh is empty:** nothing is left inside the bounds at this resolution. A subtraction or an intersection "
    "may remove every part, or what is left may be finer than the mesh resolution."
)
"""Said under the readout when a mesh has no triangles."""


class Wire:
    """A mesh's edges for the wireframe of the "both" view, found once per mesh and only if that view draws it."""

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, *, serial: int) -> None:
        self.vertices, self.faces, self.serial = vertices, faces, serial

    @functools.cached_property
    def edges(self) -> np.ndarray:
        """(E, 2) vertex indices of the mesh's edges, each once."""
        if len(self.faces) == 0:
            return np.zeros((0, 2), np.int64)
        return trimesh.Trimesh(self.vertices, self.faces, process=False).edges_unique

    @functools.cached_property
    def tolerance_m(self) -> float:
        """How far behind the marched surface an edge still shows (m): its mean length, which bounds the sag of a
        chord under a curved surface."""
        if len(self.edges) == 0:
            return 0.0
        return float(np.linalg.norm(self.vertices[self.edges[:, 0]] - self.vertices[self.edges[:, 1]], axis=1).mean())
