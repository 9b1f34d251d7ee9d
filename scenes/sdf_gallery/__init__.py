"""The SDF gallery: primitives blended with smooth-min, or a field written in GLSL, meshed and ray-marched.

Modules: :mod:`~scenes.sdf_gallery.params` (the parameters, each control declared on its field, and pure helpers),
:mod:`~scenes.sdf_gallery.editor` (the GLSL editor's field, the editing switch and source checks),
:mod:`~scenes.sdf_gallery.export` (the mesh as GLB for the view and as files to download),
:mod:`~scenes.sdf_gallery.compare` (how mesh and ray-march agree) and :mod:`~scenes.sdf_gallery.scene` (the scene).
The names callers use are re-exported here.
"""

from scenes.sdf_gallery.compare import Agreement
from scenes.sdf_gallery.editor import (
    COMPILE_LIMIT_S,
    EDITOR_KEEP_CHARS,
    EXAMPLES,
    FRAME_LIMIT_S,
    EditorField,
    editing_allowed,
    set_editing_allowed,
)
from scenes.sdf_gallery.params import (
    CAMERA_REST_S,
    GIZMO_MARGIN_M,
    KIND_LABELS,
    PREVIEW_RESOLUTION,
    RESOLUTION_LABEL,
    SIZES_USED,
    PrimitiveParams,
    SdfGalleryParams,
    rest_size,
)
from scenes.sdf_gallery.scene import SdfGalleryScene
from shaders.renderer import MAX_SOURCE_CHARS

__all__ = [
    "CAMERA_REST_S",
    "COMPILE_LIMIT_S",
    "EDITOR_KEEP_CHARS",
    "EXAMPLES",
    "FRAME_LIMIT_S",
    "GIZMO_MARGIN_M",
    "KIND_LABELS",
    "MAX_SOURCE_CHARS",
    "PREVIEW_RESOLUTION",
    "RESOLUTION_LABEL",
    "SIZES_USED",
    "Agreement",
    "EditorField",
    "PrimitiveParams",
    "SdfGalleryParams",
    "SdfGalleryScene",
    "editing_allowed",
    "rest_size",
    "set_editing_allowed",
]
