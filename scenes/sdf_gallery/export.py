"""The gallery's mesh as bytes: the GLB the 3D view gets on every remesh, and the downloads (GLB, STL, OBJ, PNG).

Meshes are vertices (V, 3) float (m, world frame), faces (F, 3) int and vertex colours (V, 3) in [0, 1] (sRGB-like,
as :mod:`kernels.sdf` gives them). Every download follows one rule (:func:`download`): with nothing to export (a
mesh of no triangles, no reference image yet) there is no file, and the answer says why.
"""

from __future__ import annotations

import dataclasses
import io
from typing import Literal

import numpy as np
from PIL import Image

from kernels import sdf
from scenes._look import mesh_glb

MeshFormat = Literal["glb", "stl", "obj"]
"""The mesh's download formats."""
DownloadFormat = MeshFormat | Literal["png"]
"""The gallery's downloads: the mesh in three formats, the reference image as PNG."""
NOTHING_TO_DOWNLOAD = "Nothing to download yet"
"""The title of the notification a download button gives when there is nothing to export."""


@dataclasses.dataclass(frozen=True)
class Download:
    """What a download button gives: a file, or why there is none."""

    name: str
    """The file's name."""
    content: bytes | None
    """The file's bytes; None when there is nothing to export."""
    why_not: str = ""
    """Why there is no file (the notification's text), when ``content`` is None."""


def download(
    fmt: DownloadFormat, vertices: np.ndarray, faces: np.ndarray, colors: np.ndarray, reference: np.ndarray | None
) -> Download:
    """The download of format ``fmt``: the mesh (vertices (V, 3) m, faces (F, 3), colours (V, 3) in [0, 1]) as GLB,
    STL or OBJ, or the reference image ((H, W, 3) uint8, None before one is rendered) as PNG; no file when there is
    nothing to export."""
    match fmt:
        case "png":
            if reference is None or reference.size == 0:
                return Download("sdf_ref.png", None, "The reference image has not been rendered.")
            return Download("sdf_ref.png", png_bytes(reference))
        case "glb" | "stl" | "obj":
            name = f"sdf_mesh.{fmt}"
            if len(faces) == 0:
                return Download(name, None, "The shape is empty (0 triangles): there is no surface to export.")
            return Download(name, mesh_file(fmt, vertices, faces, colors))


Z_UP_TO_Y_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
"""The rotation (a quarter turn about x) from the scene's frame, z up, to y up: (x, y, z) → (x, z, −y)."""
Y_UP_FORMATS: frozenset[MeshFormat] = frozenset({"glb", "obj"})
"""The formats written y up: glTF 2.0 defines +y as up, and OBJ readers (Blender's among them) take +y as up. STL
stays z up, as slicers for 3D printing read it."""


def mesh_file(fmt: MeshFormat, vertices: np.ndarray, faces: np.ndarray, colors: np.ndarray) -> bytes:
    """The mesh as a file of format ``fmt``, with its colours where the format has them, in the format's own up
    direction (:data:`Y_UP_FORMATS`); ValueError for a mesh of no triangles (its files would be broken: an OBJ of
    bare ``v``/``f`` lines, a GLB node with no mesh)."""
    if len(faces) == 0:
        raise ValueError("a mesh of no triangles has no file")
    if fmt in Y_UP_FORMATS:  # a rotation: the winding, hence the outward side, is kept
        vertices = np.asarray(vertices, dtype=np.float64) @ Z_UP_TO_Y_UP.T
    data = sdf.mesh_trimesh(vertices, faces, colors).export(file_type=fmt)
    return data.encode() if isinstance(data, str) else bytes(data)


def png_bytes(rgb: np.ndarray) -> bytes:
    """An (H, W, 3) uint8 image as PNG bytes."""
    buffer = io.BytesIO()
    Image.fromarray(rgb).save(buffer, format="PNG")
    return buffer.getvalue()


def scene_normals(scene: sdf.Scene, vertices: np.ndarray) -> np.ndarray:
    """(V, 3) unit normals: the field's gradient by four probes on a tetrahedron's corners (Quilez's trick)."""
    if not len(vertices):
        return np.zeros((0, 3))
    corners = np.array([[1.0, -1.0, -1.0], [-1.0, -1.0, 1.0], [-1.0, 1.0, -1.0], [1.0, 1.0, 1.0]])
    probes = (vertices[None, :, :] + 1e-4 * corners[:, None, :]).reshape(-1, 3)
    d = sdf.scene_distance(scene, probes).reshape(4, -1)
    gradient = d.T @ corners
    return gradient / np.maximum(np.linalg.norm(gradient, axis=1, keepdims=True), 1e-12)


def viewer_glb(vertices: np.ndarray, faces: np.ndarray, colors: np.ndarray, normals: np.ndarray) -> bytes:
    """The GLB the 3D view gets: positions, the field's gradient as normals (exact directions where the SDF is, no
    averaging of faces) and the vertex colours, with the project's matte material (:func:`scenes._look.mesh_glb`)."""
    return mesh_glb(vertices, faces, normals=normals, vertex_colors=colors)
