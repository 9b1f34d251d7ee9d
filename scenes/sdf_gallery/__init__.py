"""The SDF gallery: primitives blended with smooth-min, or a field written in GLSL, meshed and ray-marched.

Modules: :mod:`~scenes.sdf_gallery.params` (the parameters, each control declared on its field, and pure helpers),
:mod:`~scenes.sdf_gallery.editor` (the GLSL editor's field, the editing switch and source checks),
:mod:`~scenes.sdf_gallery.export` (the mesh as GLB for the view and as files to download),
:mod:`~scenes.sdf_gallery.compare` (how mesh and ray-march agree) and :mod:`~scenes.sdf_gallery.scene` (the scene).

The package exports the scene and its parameters; everything else is imported from the module it lives in.
"""

from __future__ import annotations

from scenes.sdf_gallery.params import SdfGalleryParams
from scenes.sdf_gallery.scene import SdfGalleryScene

__all__ = ["SdfGalleryParams", "SdfGalleryScene"]
