"""The SDF gallery's parameters, each control declared once on its field, and pure helpers from them.

:class:`SdfGalleryParams` is what the user set (the gallery shows a function of it); :class:`PrimitiveParams` is one
of its four primitive slots, whose controls the scene builds once per slot from the declarations here (labels are
formatted with ``slot``, 1 to 4, and ``axis``, a to c). :class:`Viewer` is what the latest camera message said. The
helpers size frames and gizmos and convert a viser camera; nothing here makes or reads a viser handle.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import field
from typing import Any, Literal

import numpy as np

from kernels import sdf
from scenes._controls import checkbox, dropdown, dropdown_from_labels, rgb, slider, text
from scenes.sdf_gallery.editor import EDITOR_HALF_SIZE_M, EDITOR_KEEP_CHARS, EXAMPLES, OWN_CODE, EditorField
from shaders.renderer import Camera, Shading

BOX_M = 1.5
"""Gizmos stay inside the cube [−BOX_M, BOX_M]³ (m)."""
BOX_LO: tuple[float, float, float] = (-BOX_M, -BOX_M, -BOX_M)
BOX_HI: tuple[float, float, float] = (BOX_M, BOX_M, BOX_M)
SIZE_RANGE_M = (0.05, 1.0)


def kind_labels() -> dict[str, sdf.PrimitiveKind]:
    """The kind menu's labels and kinds, read from the primitive registry now (a kind registered after this module
    was imported is in the menus of the scenes built since)."""
    return {spec.label: spec.kind for spec in sdf.PRIMITIVES.values()}


def sizes_used(kind: sdf.PrimitiveKind) -> int:
    """How many of the sliders a, b, c a kind reads."""
    return sdf.primitive_spec(kind).size_count


def size_meaning() -> str:
    """The note under the slots: what each kind's sizes a, b, c are, from the registry."""
    return "**Sizes (m).** " + " ".join(f"{s.label}: {s.size_meaning}." for s in sdf.PRIMITIVES.values())


OP_LABELS: dict[str, sdf.BooleanOp] = {"Union": "union", "Subtract": "subtract", "Intersect": "intersect"}
BlendChoice = Literal["hard", "poly", "exp"]
"""Hard booleans, or a smooth minimum in one of its two forms."""
BLEND_LABELS: dict[str, BlendChoice] = {"Hard": "hard", "Smooth (polynomial)": "poly", "Smooth (exponential)": "exp"}
ReferenceMode = Literal["stopped", "live"]
MODE_LABELS: dict[str, ReferenceMode] = {"When the camera stops": "stopped", "Live": "live"}
ViewMode = Literal["mesh", "raymarch", "both"]
VIEW_LABELS: dict[str, ViewMode] = {"Mesh": "mesh", "Ray-marched": "raymarch", "Both": "both"}
ShapeSource = Literal["primitives", "editor"]
SOURCE_LABELS: dict[str, ShapeSource] = {"Primitives (panels below)": "primitives", "GLSL editor": "editor"}
RESOLUTION_LABEL = "Mesh resolution (samples per side)"
"""Marching-cubes samples along the longest side of the scene's bounds."""
GIZMO_MARGIN_M = 0.12
"""How far a gizmo's arrows reach beyond its primitive's surface (m): each gizmo is sized to its own primitive."""
GIZMO_MARKER_RADIUS_M = 0.035
"""Radius of the ball in the primitive's colour at the tip of each gizmo's z arrow (m)."""
VIEW_WIDTH_PX = 640
"""Narrowest ray-marched main view once the camera rests (px); its height follows the viewer's aspect."""
MAX_VIEW_SIZE_PX = (1600, 1000)
"""Largest rest frame (px): at rest the main view is drawn at the viewer's canvas width, within this box."""
REST_FRAME_BUDGET_S = 0.6
"""A rest frame is made smaller (not below VIEW_WIDTH_PX wide) when the last one's time per pixel says the
viewer's full size would take longer than this (s)."""
MOVING_WIDTH_PX = 320
"""Width while the camera or a gizmo moves: a quarter of the pixels, and no shadows or AO, so the view keeps up."""
CAMERA_REST_S = 0.25
"""The camera (and the scene) count as stopped after this long without an update (s)."""
PREVIEW_RESOLUTION = 32
"""Mesh resolution (samples per side) while a burst of scene inputs keeps arriving (a drag): a 32³ mesh takes about
a fifth of a 64³ one, so eight tabs dragging at once keep up on two cores; the full resolution follows once the
inputs have rested CAMERA_REST_S."""

Shape = sdf.Scene | EditorField
"""What the gallery shows: the primitives' scene or the editor's field."""

REFERENCE_FOLDER = "Reference (GLSL ray-march)"
"""The folder of the reference image, its note and the shading controls."""
SHADING_FIELDS = (
    "reference_mode",
    "reference_width",
    "ambient",
    "diffuse",
    "specular",
    "shininess",
    "shadows",
    "shadow_sharpness",
    "occlusion",
    "occlusion_strength",
    "light_elevation_deg",
    "light_azimuth_deg",
)
"""The fields of the "Reference (GLSL ray-march)" folder's controls, in order."""
SCENE_FIELDS = ("blend", "k", "resolution")
"""The fields of the "Blend and mesh" folder's controls."""


def light_angles_deg(direction: tuple[float, float, float]) -> tuple[float, float]:
    """Elevation and azimuth (°, rounded to whole degrees) of a light direction (any length)."""
    x, y, z = np.asarray(direction, dtype=np.float64) / np.linalg.norm(direction)
    return float(round(math.degrees(math.asin(z)))), float(round(math.degrees(math.atan2(y, x))))


_SHADING = Shading()
_LIGHT_ELEVATION_DEG, _LIGHT_AZIMUTH_DEG = light_angles_deg(_SHADING.light_direction)


@dataclasses.dataclass(frozen=True)
class PrimitiveParams:
    """One primitive slot of the gallery; its controls go in the folder "Primitive {slot}" (the first slot has no
    "on" checkbox, and its "combine" is greyed out)."""

    enabled: bool = field(metadata=checkbox("P{slot} on", folder="Primitive {slot}"))
    """Whether it is part of the scene (the first always is)."""
    kind: sdf.PrimitiveKind = field(
        metadata=dropdown_from_labels("P{slot} kind", kind_labels, folder="Primitive {slot}")
    )
    """One of the kernel's kinds (sphere, box, torus, capsule and the catalogue's six)."""
    op: sdf.BooleanOp = field(metadata=dropdown_from_labels("P{slot} combine", OP_LABELS, folder="Primitive {slot}"))
    """How it combines with the primitives before it."""
    size: tuple[float, float, float] = field(
        metadata=slider("P{slot} size {axis} (m)", *SIZE_RANGE_M, 0.01, folder="Primitive {slot}")
    )
    """Sizes a, b, c (m); which ones count depends on the kind (see :func:`size_meaning`)."""
    color: tuple[int, int, int] = field(metadata=rgb("P{slot} colour", folder="Primitive {slot}"))
    """8-bit RGB."""
    position: tuple[float, float, float]
    """Centre (m), where its gizmo is."""
    wxyz: tuple[float, float, float, float]
    """Orientation, the gizmo's."""

    def primitive(self) -> sdf.Primitive:
        size = self.size[: sizes_used(self.kind)]
        return sdf.Primitive(
            self.kind,
            self.position,
            size,
            rotation=self.wxyz,
            color=(self.color[0] / 255, self.color[1] / 255, self.color[2] / 255),
            op=self.op,
        )


def _default_primitives() -> tuple[PrimitiveParams, ...]:
    out = []
    for prim in sdf.default_scene().primitives:
        size = (*prim.size, *([0.3] * (3 - len(prim.size))))
        out.append(
            PrimitiveParams(
                enabled=True,
                kind=prim.kind,
                op=prim.op,
                size=(size[0], size[1], size[2]),
                color=(round(prim.color[0] * 255), round(prim.color[1] * 255), round(prim.color[2] * 255)),
                position=prim.center,
                wxyz=prim.rotation,
            )
        )
    return tuple(out)


def _first_example() -> EditorField:
    return EditorField(next(iter(EXAMPLES.values())), EDITOR_HALF_SIZE_M)


@dataclasses.dataclass(frozen=True)
class SdfGalleryParams:
    """Everything the gallery shows is a function of these; defaults are the opening state.

    The controls go in four folders, in this order: "Shape and view", "GLSL editor" (shown with Shape = GLSL
    editor), "Blend and mesh" and "Reference (GLSL ray-march)"; the primitive slots' folders follow
    (:class:`PrimitiveParams`, shown with Shape = primitives).
    """

    view_mode: ViewMode = field(
        default="mesh", metadata=dropdown_from_labels("View", VIEW_LABELS, folder="Shape and view")
    )
    """The main 3D view: the mesh, the GLSL ray-march (background image with depth), or both (mesh as wireframe)."""
    shape_source: ShapeSource = field(
        default="primitives", metadata=dropdown_from_labels("Shape", SOURCE_LABELS, folder="Shape and view")
    )
    """Show the primitives' scene or the editor's field."""
    rings: bool = field(default=False, metadata=checkbox("Rotation rings on the gizmos", folder="Shape and view"))
    """Whether the gizmos show their rotation rings (turn a primitive); off, only the arrows (move it) clutter the
    shape."""
    example: str = field(
        default=next(iter(EXAMPLES)), metadata=dropdown("Example", (*EXAMPLES, OWN_CODE), folder="GLSL editor")
    )
    """The title of the example last picked (picking one puts its source in the editor and applies it), or
    :data:`OWN_CODE` once the editor's text is no example's."""
    editor_text: str = field(
        default=next(iter(EXAMPLES.values())),
        metadata=text("sdf(p) in GLSL", multiline=True, max_chars=EDITOR_KEEP_CHARS, folder="GLSL editor"),
    )
    """The editor's text as last kept (at most EDITOR_KEEP_CHARS; Apply compiles it)."""
    editor_half_size: float = field(
        default=EDITOR_HALF_SIZE_M, metadata=slider("Editor bounds half size (m)", 0.5, 3.0, 0.1, folder="GLSL editor")
    )
    """Half the side of the cube the editor's field is meshed and ray-marched in, for the next mesh (m)."""
    blend: BlendChoice = field(
        default="poly", metadata=dropdown_from_labels("Blend", BLEND_LABELS, folder="Blend and mesh")
    )
    """Hard booleans (k is not used), or the polynomial or exponential smooth minimum of width k."""
    k: float = field(default=0.25, metadata=slider("Blend width k (m)", 0.0, 1.0, 0.01, folder="Blend and mesh"))
    """Blend width (m); 0 is a hard boolean."""
    resolution: int = field(
        default=64, metadata=slider(RESOLUTION_LABEL, 32, 256, 16, folder="Blend and mesh", costly=True)
    )
    """Marching-cubes samples along the longest side of the bounds (32–256); a change remeshes (up to seconds)."""
    reference_mode: ReferenceMode = field(
        default="stopped", metadata=dropdown_from_labels("Re-render", MODE_LABELS, folder=REFERENCE_FOLDER)
    )
    """Render the reference when the camera stops, or live while it moves."""
    reference_width: int = field(
        default=320, metadata=slider("Reference width (px)", 128, 640, 32, folder=REFERENCE_FOLDER)
    )
    """Width of the reference image (px); its height follows the viewer's aspect."""
    ambient: float = field(
        default=_SHADING.ambient, metadata=slider("Ambient k_a", 0.0, 1.0, 0.01, folder=REFERENCE_FOLDER)
    )
    """k_a, ambient reflection."""
    diffuse: float = field(
        default=_SHADING.diffuse, metadata=slider("Diffuse k_d", 0.0, 1.0, 0.01, folder=REFERENCE_FOLDER)
    )
    """k_d, diffuse reflection."""
    specular: float = field(
        default=_SHADING.specular, metadata=slider("Specular k_s", 0.0, 1.0, 0.01, folder=REFERENCE_FOLDER)
    )
    """k_s, specular reflection."""
    shininess: float = field(
        default=_SHADING.shininess, metadata=slider("Shininess α", 1.0, 128.0, 1.0, folder=REFERENCE_FOLDER)
    )
    """α, the Phong exponent."""
    shadows: bool = field(default=_SHADING.shadows, metadata=checkbox("Soft shadows", folder=REFERENCE_FOLDER))
    """Soft shadows (Quilez's improved technique)."""
    shadow_sharpness: float = field(
        default=_SHADING.shadow_sharpness,
        metadata=slider("Shadow sharpness k", 1.0, 64.0, 1.0, folder=REFERENCE_FOLDER),
    )
    """k of the soft shadow: penumbra width ∝ 1/k."""
    occlusion: bool = field(default=_SHADING.occlusion, metadata=checkbox("Ambient occlusion", folder=REFERENCE_FOLDER))
    """Ambient occlusion along the normal."""
    occlusion_strength: float = field(
        default=_SHADING.occlusion_strength, metadata=slider("AO strength", 0.0, 6.0, 0.1, folder=REFERENCE_FOLDER)
    )
    """How strongly occluded samples darken the ambient term."""
    light_elevation_deg: float = field(
        default=_LIGHT_ELEVATION_DEG, metadata=slider("Light elevation (°)", 5.0, 90.0, 1.0, folder=REFERENCE_FOLDER)
    )
    """The light's elevation above the ground plane (°)."""
    light_azimuth_deg: float = field(
        default=_LIGHT_AZIMUTH_DEG, metadata=slider("Light azimuth (°)", -180.0, 180.0, 1.0, folder=REFERENCE_FOLDER)
    )
    """The light's azimuth from +x toward +y (°)."""
    primitives: tuple[PrimitiveParams, ...] = field(default_factory=_default_primitives)
    """The four primitive slots."""
    shading: Shading = field(default_factory=Shading)
    """The ray-march's shading: Shading's own defaults at first (its exact light direction), then
    :meth:`shading_from_controls` once any control of the reference folder changes."""
    editor: EditorField = field(default_factory=_first_example)
    """The last editor source that compiled, checked and meshed (the first example at first)."""

    def shape(self) -> Shape:
        return self.scene() if self.shape_source == "primitives" else self.editor

    def scene(self) -> sdf.Scene:
        return sdf.Scene(
            tuple(p.primitive() for p in self.primitives if p.enabled),
            k=0.0 if self.blend == "hard" else self.k,
            blend="poly" if self.blend == "hard" else self.blend,
        )

    def shading_from_controls(self) -> Shading:
        """:attr:`shading` with the reference folder's terms and the light from its two angles."""
        elevation = math.radians(self.light_elevation_deg)
        azimuth = math.radians(self.light_azimuth_deg)
        return dataclasses.replace(
            self.shading,
            ambient=self.ambient,
            diffuse=self.diffuse,
            specular=self.specular,
            shininess=self.shininess,
            shadows=self.shadows,
            shadow_sharpness=self.shadow_sharpness,
            occlusion=self.occlusion,
            occlusion_strength=self.occlusion_strength,
            light_direction=(
                math.cos(elevation) * math.cos(azimuth),
                math.cos(elevation) * math.sin(azimuth),
                math.sin(elevation),
            ),
        )


@dataclasses.dataclass(frozen=True)
class Viewer:
    """What the latest usable camera message of a viewer said."""

    camera: Camera | None = None
    """Where it looks from; None before the first message."""
    aspect: float = 4 / 3
    """Its canvas's width / height, within [0.5, 2.5]."""
    width_px: int = VIEW_WIDTH_PX
    """Its canvas's width (px): the rest frame is drawn at it, within limits."""
    moved_at: float = 0.0
    """``time.monotonic()`` of the message (s)."""


def camera_from_viser(camera: Any) -> Camera | None:
    """The renderer's camera from a viser client camera; None if the browser sent something unusable."""
    try:
        position = tuple(float(v) for v in camera.position)
        look_at = tuple(float(v) for v in camera.look_at)
        up = tuple(float(v) for v in camera.up_direction)
        return Camera(position, look_at, up, float(camera.fov))  # type: ignore[arg-type]
    except (ValueError, TypeError, AttributeError):
        return None


def viewer_size(camera: Any) -> tuple[int, int] | None:
    """The viewer's canvas (width, height) in px from a viser camera, or None if it sent something unusable (NaN,
    zero, negative, absurd or not a number)."""
    try:
        width, height = float(camera.image_width), float(camera.image_height)
    except (TypeError, ValueError, AttributeError, OverflowError):
        return None
    if not (math.isfinite(width) and math.isfinite(height) and 1 <= width <= 2e4 and 1 <= height <= 2e4):
        return None
    return round(width), round(height)


def rest_size(viewer_width: int, aspect: float, s_per_pixel: float | None) -> tuple[int, int]:
    """The rest frame's (width, height) in px: the viewer's width (at least VIEW_WIDTH_PX) at ``aspect`` (width /
    height), made smaller (not below VIEW_WIDTH_PX) if ``s_per_pixel`` says it would take longer than
    REST_FRAME_BUDGET_S, and always within MAX_VIEW_SIZE_PX."""
    max_w, max_h = MAX_VIEW_SIZE_PX
    width = float(min(max(viewer_width, VIEW_WIDTH_PX), max_w))
    if s_per_pixel is not None and s_per_pixel > 0.0:
        affordable = REST_FRAME_BUDGET_S / s_per_pixel
        if width * width / aspect > affordable:
            width = max(math.sqrt(affordable * aspect), float(VIEW_WIDTH_PX))
    if width / aspect > max_h:  # a tall canvas: the height is the limit
        width = max_h * aspect
    return round(width), max(16, round(width / aspect))


def moving_shading(shading: Shading) -> Shading:
    """The shading of frames drawn while something moves: no soft shadows or ambient occlusion (a smaller program,
    several times cheaper a frame under llvmpipe); the full shading returns when the view rests."""
    return dataclasses.replace(shading, shadows=False, occlusion=False)


def gizmo_reach(slot: PrimitiveParams) -> float:
    """A gizmo's arrow length for ``slot`` (m): the farthest its primitive's surface lies from its centre along the
    six local axis directions, plus GIZMO_MARGIN_M, so the arrow tips poke out of the primitive and no further.

    It does not depend on where the primitive is, so it is computed once per kind, size and orientation (every
    scene input re-checks all four gizmos: 5 ms a time uncached, most of a gizmo drag's callback)."""
    return _reach(slot.kind, slot.size[: sizes_used(slot.kind)], slot.wxyz)


@functools.lru_cache(maxsize=256)
def _reach(kind: sdf.PrimitiveKind, size: tuple[float, ...], wxyz: tuple[float, float, float, float]) -> float:
    try:
        prim = sdf.Primitive(kind, (0.0, 0.0, 0.0), size, rotation=wxyz)
    except ValueError:
        return 0.5
    t = np.linspace(0.0, 3.0, 301)
    axes = sdf.rotation_matrix(wxyz).T  # rows: the local axes in the world frame
    reach = 0.0
    for axis in (*axes, *(-axes)):
        inside = prim.distance(t[:, None] * axis) <= 0.0
        if inside.any():
            reach = max(reach, float(t[np.nonzero(inside)[0].max()]))
    return round(max(reach + GIZMO_MARGIN_M, 0.2), 3)


def gizmo_label(index: int, slot: PrimitiveParams) -> str:
    """The name shown by the gizmo of slot ``index`` (from 0): "P1 sphere", "P2 round box", the kind's menu label
    in lower case without its note ("Ellipsoid (bound)" is "ellipsoid")."""
    return f"P{index + 1} {sdf.PRIMITIVES[slot.kind].label.split(' (')[0].lower()}"


def gizmo_tips(reach: float) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """Where a gizmo of arrow length ``reach`` (m) puts its marker ball and its label (its local frame, m)."""
    return (0.0, 0.0, reach), (0.0, 0.0, reach + 2.5 * GIZMO_MARKER_RADIUS_M)
