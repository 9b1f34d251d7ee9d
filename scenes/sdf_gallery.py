"""SDF gallery: up to four primitives blended with smooth-min, meshed for the 3D view and ray-marched in GLSL.

The distance field comes from :mod:`kernels.sdf`; the mesh is its marching-cubes surface, shown with blended vertex
colours; the "Reference" panel is the same scene sphere-traced by ``shaders/raymarch.frag`` from the viewer's
camera, and the readouts say how well the two agree (silhouette IoU, mean depth difference).

Threads: GUI and gizmo callbacks only record the new state and wake one worker thread. The worker meshes the latest
scene (a burst of drags coalesces: only the newest request is meshed), then renders the reference when the camera
has stopped moving (or at once, in live mode). Refinement is progressive: while a burst of inputs keeps arriving
the worker meshes at PREVIEW_RESOLUTION, and once they rest it meshes the latest scene at full resolution (a single
change is meshed at full resolution at once). The GL work goes to :mod:`shaders.gl_service`: one context and one
thread per process, shared by every gallery (a context per build leaked ~50 MiB each).
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import io
import json
import logging
import math
import struct
import threading
import time
from typing import Any, Literal

import numpy as np
import viser
from PIL import Image

from kernels import sdf
from scenes._base import TURNS, Scene, mark_costly
from shaders import gl_service
from shaders import renderer as gl_renderer
from shaders.renderer import (
    MAX_SOURCE_CHARS,
    Camera,
    GLUnavailableError,
    Renderer,
    ShaderCompileError,
    Shading,
    check_source,
)
from shaders.trial import trial

logger = logging.getLogger(__name__)

BOX_M = 1.5
"""Gizmos stay inside the cube [−BOX_M, BOX_M]³ (m)."""
BOX_LO: tuple[float, float, float] = (-BOX_M, -BOX_M, -BOX_M)
BOX_HI: tuple[float, float, float] = (BOX_M, BOX_M, BOX_M)
SIZE_RANGE_M = (0.05, 1.0)
KIND_LABELS: dict[str, sdf.PrimitiveKind] = {s.label: s.kind for s in sdf.PRIMITIVES.values()}
SIZES_USED: dict[sdf.PrimitiveKind, int] = {s.kind: s.size_count for s in sdf.PRIMITIVES.values()}
"""How many of the sliders a, b, c each kind reads."""
OP_LABELS: dict[str, sdf.BooleanOp] = {
    "Union": "union",
    "Subtract": "subtract",
    "Intersect": "intersect",
}
BlendChoice = Literal["hard", "poly", "exp"]
"""Hard booleans, or a smooth minimum in one of its two forms."""
BLEND_LABELS: dict[str, BlendChoice] = {
    "Hard": "hard",
    "Smooth (polynomial)": "poly",
    "Smooth (exponential)": "exp",
}
ReferenceMode = Literal["stopped", "live"]
MODE_LABELS: dict[str, ReferenceMode] = {"When the camera stops": "stopped", "Live": "live"}
SIZE_MEANING = (
    "**Sizes (m).** Sphere: a = radius. Box: a, b, c = half sizes along local x, y, z. "
    "Torus: a = major radius, b = tube radius (ring in the local xz plane). "
    "Capsule: a = half length along local y, b = radius. Cylinder: a = half height along local y, b = radius. "
    "Round box: a, b, c = half sizes, edges rounded by a quarter of the smallest. Octahedron: a = centre to vertex. "
    "Cone: a = base radius, b = height, along local y. Hexagonal prism: a = centre to flat side, b = half "
    "height along local z. Ellipsoid: a, b, c = semi-axes (a distance bound, not exact)."
)
RESOLUTION_LABEL = "Mesh resolution (samples per side)"
"""Marching-cubes samples along the longest side of the scene's bounds."""
GIZMO_MARGIN_M = 0.12
"""How far a gizmo's arrows reach beyond its primitive's surface (m): each gizmo is sized to its own primitive."""
GIZMO_MARKER_RADIUS_M = 0.035
"""Radius of the ball in the primitive's colour at the tip of each gizmo's z arrow (m)."""

ViewMode = Literal["mesh", "raymarch", "both"]
VIEW_LABELS: dict[str, ViewMode] = {"Mesh": "mesh", "Ray-marched": "raymarch", "Both": "both"}
ShapeSource = Literal["primitives", "editor"]
SOURCE_LABELS: dict[str, ShapeSource] = {
    "Primitives (panels below)": "primitives",
    "GLSL editor": "editor",
}
VIEW_WIDTH_PX = 640
"""Narrowest ray-marched main view once the camera rests (px); its height follows the viewer's aspect."""
MAX_VIEW_SIZE_PX = (1600, 1000)
"""Largest rest frame (px): at rest the main view is drawn at the viewer's canvas width, within this box."""
REST_FRAME_BUDGET_S = 0.6
"""A rest frame is made smaller (not below VIEW_WIDTH_PX wide) when the last one's time per pixel says the
viewer's full size would take longer than this (s)."""
MOVING_WIDTH_PX = 320
"""Width while the camera or a gizmo moves: a quarter of the pixels, and no shadows or AO, so the view keeps up."""
COMPILE_LIMIT_S = 5.0
"""An editor source whose programs (moving and fully shaded) take longer to compile in the trial process is refused
(s); the trial process is killed at this limit plus FRAME_LIMIT_S (:mod:`shaders.trial`)."""
FRAME_LIMIT_S = 1.0
"""An editor source whose test frame (MOVING_WIDTH_PX wide, moving shading) takes longer is refused (s); the fully
shaded program at rest costs a few times more (its soft shadows and AO call sdf about twenty times a pixel more)."""
EDITOR_HALF_SIZE_M = 1.5
"""The editor's field is meshed and ray-marched inside the cube [−h, h]³ (m) by default."""
EXAMPLES = gl_renderer.examples()
"""The editor's examples, by title."""
EXAMPLE_SOURCES = frozenset(EXAMPLES.values())
EDITOR_KEEP_CHARS = 2 * MAX_SOURCE_CHARS
"""Longest text the editor keeps (characters): room to paste a little too much and trim it; beyond, the previous
text is put back at once."""
EDITOR_HELP = (
    "Write `float sdf(vec3 p)` (metres, Z up) and optionally `vec3 color(vec3 p)`, using the library's "
    "`sd_*` primitives and `op_*`, `smooth_*` operators, then **Apply**: the shape is meshed and ray-marched "
    f"from the same source. At most {MAX_SOURCE_CHARS} characters; no loops, no `#` lines."
)
_editing = {"allowed": True}


def set_editing_allowed(allowed: bool) -> None:
    """Whether browsers may send GLSL to compile (app.py turns it off for a non-loopback host unless asked)."""
    _editing["allowed"] = bool(allowed)


def editing_allowed() -> bool:
    return _editing["allowed"]


@dataclasses.dataclass(frozen=True)
class EditorField:
    """The editor's shape: a GLSL source that compiled, and the box it is meshed and ray-marched in."""

    source: str
    """Defines float sdf(vec3 p) (m) and optionally vec3 color(vec3 p)."""
    half_size: float
    """The bounds are the cube [−half_size, half_size]³ (m)."""

    @property
    def bounds(self) -> np.ndarray:
        return np.array([[-self.half_size] * 3, [self.half_size] * 3])


Shape = sdf.Scene | EditorField
"""What the gallery shows: the primitives' scene or the editor's field."""
CAMERA_REST_S = 0.25
"""The camera (and the scene) count as stopped after this long without an update (s)."""
PREVIEW_RESOLUTION = 32
"""Mesh resolution (samples per side) while a burst of scene inputs keeps arriving (a drag): a 32³ mesh takes about
a fifth of a 64³ one, so eight tabs dragging at once keep up on two cores; the full resolution follows once the
inputs have rested CAMERA_REST_S."""


@dataclasses.dataclass(frozen=True)
class PrimitiveParams:
    """One primitive slot of the gallery."""

    enabled: bool
    """Whether it is part of the scene (the first always is)."""
    kind: sdf.PrimitiveKind
    """One of the kernel's kinds (sphere, box, torus, capsule and the catalogue's six)."""
    size: tuple[float, float, float]
    """Sizes a, b, c (m); which ones count depends on the kind (see SIZE_MEANING)."""
    color: tuple[int, int, int]
    """8-bit RGB."""
    op: sdf.BooleanOp
    """How it combines with the primitives before it."""
    position: tuple[float, float, float]
    """Centre (m), where its gizmo is."""
    wxyz: tuple[float, float, float, float]
    """Orientation, the gizmo's."""

    def primitive(self) -> sdf.Primitive:
        size = self.size[: SIZES_USED[self.kind]]
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
                size=(size[0], size[1], size[2]),
                color=(
                    round(prim.color[0] * 255),
                    round(prim.color[1] * 255),
                    round(prim.color[2] * 255),
                ),
                op=prim.op,
                position=prim.center,
                wxyz=prim.rotation,
            )
        )
    return tuple(out)


@dataclasses.dataclass(frozen=True)
class SdfGalleryParams:
    """Everything the gallery shows is a function of these; defaults are the opening state."""

    primitives: tuple[PrimitiveParams, ...] = dataclasses.field(default_factory=_default_primitives)
    """The four primitive slots."""
    k: float = 0.25
    """Blend width (m); 0 is a hard boolean."""
    blend: BlendChoice = "poly"
    """Hard booleans (k is not used), or the polynomial or exponential smooth minimum of width k."""
    resolution: int = 64
    """Marching-cubes samples along the longest side of the bounds (32–256)."""
    shading: Shading = dataclasses.field(default_factory=Shading)
    """Phong terms, soft shadows and ambient occlusion of the reference image."""
    reference_mode: ReferenceMode = "stopped"
    """Render the reference when the camera stops, or live while it moves."""
    reference_width: int = 320
    """Width of the reference image (px); its height follows the viewer's aspect."""
    view_mode: ViewMode = "mesh"
    """The main 3D view: the mesh, the GLSL ray-march (background image with depth), or both (mesh as wireframe)."""
    shape_source: ShapeSource = "primitives"
    """Show the primitives' scene or the editor's field."""
    editor: EditorField = dataclasses.field(
        default_factory=lambda: EditorField(next(iter(EXAMPLES.values())), EDITOR_HALF_SIZE_M)
    )
    """The last editor source that compiled, checked and meshed (the first example at first)."""

    def shape(self) -> Shape:
        return self.scene() if self.shape_source == "primitives" else self.editor

    def scene(self) -> sdf.Scene:
        return sdf.Scene(
            tuple(p.primitive() for p in self.primitives if p.enabled),
            k=0.0 if self.blend == "hard" else self.k,
            blend="poly" if self.blend == "hard" else self.blend,
        )


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


def camera_from_viser(camera: Any) -> Camera | None:
    """The renderer's camera from a viser client camera; None if the browser sent something unusable."""
    try:
        position = tuple(float(v) for v in camera.position)
        look_at = tuple(float(v) for v in camera.look_at)
        up = tuple(float(v) for v in camera.up_direction)
        return Camera(position, look_at, up, float(camera.fov))  # type: ignore[arg-type]
    except (ValueError, TypeError, AttributeError):
        return None


def _viewer_size(camera: Any) -> tuple[int, int] | None:
    """The viewer's canvas (width, height) in px from a viser camera, or None if it sent something unusable (NaN,
    zero, negative, absurd or not a number)."""
    try:
        width, height = float(camera.image_width), float(camera.image_height)
    except (TypeError, ValueError, AttributeError, OverflowError):
        return None
    if not (
        math.isfinite(width) and math.isfinite(height) and 1 <= width <= 2e4 and 1 <= height <= 2e4
    ):
        return None
    return round(width), round(height)


def _rest_size(viewer_width: int, aspect: float, s_per_pixel: float | None) -> tuple[int, int]:
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


def gizmo_reach(slot: PrimitiveParams) -> float:
    """A gizmo's arrow length for ``slot`` (m): the farthest its primitive's surface lies from its centre along the
    six local axis directions, plus GIZMO_MARGIN_M, so the arrow tips poke out of the primitive and no further.

    It does not depend on where the primitive is, so it is computed once per kind, size and orientation (every
    scene input re-checks all four gizmos: 5 ms a time uncached, most of a gizmo drag's callback)."""
    return _reach(slot.kind, slot.size[: SIZES_USED[slot.kind]], slot.wxyz)


@functools.lru_cache(maxsize=256)
def _reach(
    kind: sdf.PrimitiveKind, size: tuple[float, ...], wxyz: tuple[float, float, float, float]
) -> float:
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


def _gizmo_label(index: int, slot: PrimitiveParams) -> str:
    return f"P{index + 1} {slot.kind}"


class SdfGalleryScene(Scene):
    key = "sdf"
    title = "SDF gallery (ray marching)"
    camera_position = (1.9, -2.1, 1.4)
    camera_look_at = (0.05, 0.0, 0.3)
    about = """
**What it shows.** A scene of up to four signed-distance primitives (sphere, box, torus, capsule and Quilez's
cylinder, round box, octahedron, cone, hexagonal prism, ellipsoid) combined by union, subtraction or intersection,
hard or with a smooth minimum; or any shape you write in GLSL in the **GLSL editor** (`float sdf(vec3 p)`, with the
same primitives and operators). The 3D view shows its marching-cubes mesh, the GLSL ray-march rendered from your
camera (**View: Ray-marched**, composited by depth with the gizmos), or both (the mesh as a wireframe over the
ray-march). The **Reference** panel shows the ray-march as an image and the readouts measure how well mesh and
ray-march agree. Drag a gizmo: the mesh follows.

**Equations.** Sphere |p| − r; box |max(q,0)| + min(max(q.x,q.y,q.z),0), q = |p| − b; torus |(|p.xz| − R, p.y)| − r;
capsule |pa − ba·h| − r. Smooth union, polynomial: h = clamp(½ + ½(b − a)/k, 0, 1),
smin = mix(b, a, h) − k·h·(1 − h); exponential: −ln(e^(−sa) + e^(−sb))/s with sharpness s = 4 ln 2 / k, so both
dip by k/4 where surfaces meet. Subtraction −smin(−a, b), intersection −smin(−a, −b). Colours blend by the same
weights. Shading: I = k_a·AO·albedo + (k_d·albedo·max(n·L, 0) + k_s·max(r·v, 0)^α)·shadow; normals by central
differences; soft shadows by Quilez's improved technique; AO from five samples along the normal.

**Assumptions.** Smooth blends are distance bounds, not exact distances (1-Lipschitz), which is all sphere tracing
and the mesher's coarse-to-fine pass need. Marching cubes bevels sharp box edges by up to about half a voxel, so
IoU is lowest when a box edge is on the silhouette.

**Sources.** I. Quilez, *distance functions*, *smooth minimum*, *soft shadows* (iquilezles.org); J. C. Hart,
*Sphere tracing* (1996); T. Lewiner et al., marching cubes (2003), via scikit-image.
"""

    def __init__(self, server: viser.ViserServer) -> None:
        super().__init__(server)
        self.params = SdfGalleryParams()
        self.mesh_vertices = np.zeros((0, 3))
        self.mesh_faces = np.zeros((0, 3), dtype=np.int64)
        self.mesh_colors = np.zeros((0, 3))
        self.mesh_scene: sdf.Scene | None = None
        """The scene the shown mesh was made from (None when it came from the editor)."""
        self.mesh_shape: Shape | None = None
        """The scene or editor field the shown mesh was made from."""
        self.view_serial = 0
        """How many ray-marched main-view frames have been sent."""
        self.view_rgb: np.ndarray | None = None
        """The latest main-view frame."""
        self.view_ms: float | None = None
        """Time to ray-march it (ms)."""
        self.editor_error: str | None = None
        """Why the latest editor source was refused (None once one is applied)."""
        self.editor_serial = 0
        """How many editor sources have been applied."""
        self.mesh_serial = 0
        """How many full-resolution meshes have been shown (``mesh_vertices`` … describe the latest)."""
        self.preview_serial = 0
        """How many preview meshes (PREVIEW_RESOLUTION, during a burst of inputs) have been shown."""
        self.shown_resolution = self.params.resolution
        """Samples per side of the mesh on screen now: PREVIEW_RESOLUTION during a drag, the slider's value after."""
        self.reference_serial = 0
        """How many reference images have been shown."""
        self.reference_mesh_serial = 0
        """The ``mesh_serial`` of the full mesh the shown reference was compared against."""
        self.reference_rgb: np.ndarray | None = None
        self.agreement = Agreement(0, 0.0, None, None, None)
        self.gl_error: str | None = None
        self._mesh_voxel = 1.0
        self._work = threading.Condition()
        self._wanted_scene: Shape | None = None
        self._wanted_source: str | None = None
        self._view_key: tuple[Any, ...] | None = None
        self._wanted_resolution = self.params.resolution
        self._wanted_preview = False
        """Whether the wanted mesh came in a burst of inputs (mesh it as a preview)."""
        self._refine: tuple[Shape, int] | None = None
        """The scene and resolution to mesh in full once the inputs rest (a preview is on screen)."""
        self._camera: Camera | None = None
        self._aspect = 4 / 3
        self._viewer_width = VIEW_WIDTH_PX
        """The viewer's canvas width (px), from its camera messages; the rest frame is drawn at it, within limits."""
        self._rest_s_per_pixel: float | None = None
        """Seconds a pixel of the last rest frame took: the next one is sized to REST_FRAME_BUDGET_S."""
        self._moving_s_per_pixel: float | None = None
        self._camera_time = 0.0
        self._scene_time = 0.0
        self._reference_due = True
        self._build_gui()
        self._build_world()
        self._sync_enabled_inputs()
        self._mesh_and_show(self.params.scene(), self.params.resolution)
        self._watch_cameras()
        worker = threading.Thread(target=self._work_forever, name="sdf-worker", daemon=True)
        self._threads.append(worker)
        worker.start()

    def close(self) -> None:
        """Wake the worker and wait for it (a reference render in flight finishes first), then remove everything."""
        self._stop.set()
        with self._work:
            self._work.notify_all()
        for thread in self._threads:
            thread.join(timeout=60.0)
        with self._lock:
            self.server.scene.set_background_image(None)
        super().close()

    # ----------------------------------------------------------------------------------------- GUI
    def _build_gui(self) -> None:
        gui = self.server.gui
        p = self.params
        self.slots: list[dict[str, Any]] = []
        with self.gui_root:
            with gui.add_folder("Shape and view"):
                self.view_mode = gui.add_dropdown(
                    "View",
                    options=list(VIEW_LABELS),
                    initial_value=_label(VIEW_LABELS, p.view_mode),
                )
                self.shape_source = gui.add_dropdown(
                    "Shape",
                    options=list(SOURCE_LABELS),
                    initial_value=_label(SOURCE_LABELS, p.shape_source),
                )
                self.view_note = gui.add_markdown("")
            with gui.add_folder("GLSL editor", expand_by_default=False):
                allowed = editing_allowed()
                self.example = gui.add_dropdown(
                    "Example", options=list(EXAMPLES), initial_value=next(iter(EXAMPLES))
                )
                self.editor = gui.add_text(
                    "sdf(p) in GLSL", p.editor.source, multiline=True, disabled=not allowed
                )
                self.editor_half_size = gui.add_slider(
                    "Editor bounds half size (m)", 0.5, 3.0, 0.1, p.editor.half_size
                )
                self.apply = mark_costly(gui.add_button("Apply"))  # compiles GLSL, remeshes
                self.editor_status = gui.add_markdown(
                    EDITOR_HELP
                    if allowed
                    else "**Editing is off**: this server is reachable from other machines. The examples "
                    "still work; start the app with `--allow-remote-glsl` to allow typing GLSL."
                )
            with gui.add_folder("Blend and mesh"):
                self.blend = gui.add_dropdown(
                    "Blend",
                    options=list(BLEND_LABELS),
                    initial_value=_label(BLEND_LABELS, p.blend),
                )
                self.k = gui.add_slider("Blend width k (m)", 0.0, 1.0, 0.01, p.k)
                self.resolution = mark_costly(  # a remesh: up to seconds at 256
                    gui.add_slider(RESOLUTION_LABEL, 32, 256, 16, p.resolution)
                )
                self.progress = gui.add_progress_bar(0.0, visible=False)
                self.readout = gui.add_markdown("")
            with gui.add_folder("Reference (GLSL ray-march)"):
                self.reference = gui.add_image(
                    np.full((120, 160, 3), 235, np.uint8), label="Reference", format="png"
                )
                self.reference_note = gui.add_markdown("")
                self.mode = gui.add_dropdown(
                    "Re-render",
                    options=list(MODE_LABELS),
                    initial_value=_label(MODE_LABELS, p.reference_mode),
                )
                self.reference_width = gui.add_slider(
                    "Reference width (px)", 128, 640, 32, p.reference_width
                )
                s = p.shading
                self.ambient = gui.add_slider("Ambient k_a", 0.0, 1.0, 0.01, s.ambient)
                self.diffuse = gui.add_slider("Diffuse k_d", 0.0, 1.0, 0.01, s.diffuse)
                self.specular = gui.add_slider("Specular k_s", 0.0, 1.0, 0.01, s.specular)
                self.shininess = gui.add_slider("Shininess α", 1.0, 128.0, 1.0, s.shininess)
                self.shadows = gui.add_checkbox("Soft shadows", s.shadows)
                self.shadow_k = gui.add_slider(
                    "Shadow sharpness k", 1.0, 64.0, 1.0, s.shadow_sharpness
                )
                self.occlusion = gui.add_checkbox("Ambient occlusion", s.occlusion)
                self.occlusion_strength = gui.add_slider(
                    "AO strength", 0.0, 6.0, 0.1, s.occlusion_strength
                )
                elevation, azimuth = _light_angles_deg(s.light_direction)
                self.light_elevation = gui.add_slider(
                    "Light elevation (°)", 5.0, 90.0, 1.0, elevation
                )
                self.light_azimuth = gui.add_slider(
                    "Light azimuth (°)", -180.0, 180.0, 1.0, azimuth
                )
            for i, slot in enumerate(p.primitives):
                n = i + 1
                with gui.add_folder(f"Primitive {n}", expand_by_default=False):
                    handles: dict[str, Any] = {}
                    if i > 0:
                        handles["enabled"] = gui.add_checkbox(f"P{n} on", slot.enabled)
                    handles["kind"] = gui.add_dropdown(
                        f"P{n} kind",
                        options=list(KIND_LABELS),
                        initial_value=_label(KIND_LABELS, slot.kind),
                    )
                    handles["op"] = gui.add_dropdown(
                        f"P{n} combine",
                        options=list(OP_LABELS),
                        initial_value=_label(OP_LABELS, slot.op),
                        disabled=i == 0,
                    )
                    for axis, value in zip("abc", slot.size, strict=True):
                        handles[f"size_{axis}"] = gui.add_slider(
                            f"P{n} size {axis} (m)", *SIZE_RANGE_M, 0.01, value
                        )
                    handles["color"] = gui.add_rgb(f"P{n} colour", slot.color)
                    self.slots.append(handles)
            gui.add_markdown(SIZE_MEANING)
            with gui.add_folder("Downloads", expand_by_default=False):
                self.downloads = {
                    "glb": gui.add_button("Download mesh (GLB)"),
                    "stl": gui.add_button("Download mesh (STL)"),
                    "obj": gui.add_button("Download mesh (OBJ)"),
                    "png": gui.add_button("Download reference (PNG)"),
                }
        scene_inputs = [self.blend, self.k, self.resolution]
        for handles in self.slots:
            scene_inputs.extend(handles.values())
        for handle in scene_inputs:
            handle.on_update(self.callback(self._on_scene_input))
        shading_inputs = [
            self.mode,
            self.reference_width,
            self.ambient,
            self.diffuse,
            self.specular,
            self.shininess,
            self.shadows,
            self.shadow_k,
            self.occlusion,
            self.occlusion_strength,
            self.light_elevation,
            self.light_azimuth,
        ]
        for handle in shading_inputs:
            handle.on_update(self.callback(self._on_shading_input))
        for fmt, button in self.downloads.items():
            button.on_click(self._download_handler(fmt))
        for handle in (self.view_mode, self.shape_source):
            handle.on_update(self.callback(self._on_view_input))
        self.example.on_update(self.callback(self._on_example))
        self._editor_text = p.editor.source
        self.editor.on_update(self.callback(self._on_editor_text))
        self.apply.on_click(self.callback(self._on_apply))

    def _build_world(self) -> None:
        scene = self.server.scene
        vertices, faces, colors = sdf.mesh(self.params.scene(), self.params.resolution)
        self.mesh_node = scene.add_mesh_trimesh(
            f"{self.root.name}/mesh", sdf.mesh_trimesh(vertices, faces, colors)
        )
        self.mesh_node.glb_data = _viewer_glb(
            vertices, faces, colors, _scene_normals(self.params.scene(), vertices)
        )
        self.wireframe_node = scene.add_mesh_simple(
            f"{self.root.name}/wireframe",
            vertices.astype(np.float32),
            faces.astype(np.uint32),
            color=(40, 40, 40),
            wireframe=True,
            visible=False,
        )
        self._wire: tuple[np.ndarray, np.ndarray] | None = None
        """The latest mesh's (vertices, faces) for the wireframe, drawn only while it shows."""
        self.gizmos = []
        self.gizmo_markers = []
        self.gizmo_labels = []
        for i, slot in enumerate(self.params.primitives):
            reach = gizmo_reach(slot)
            gizmo = scene.add_transform_controls(
                f"{self.root.name}/gizmo_{i + 1}",
                scale=reach,
                line_width=2.0,
                disable_sliders=True,  # the plane handles of four gizmos cluttered the middle; arrows and rings stay
                # Drawn over the mesh: a gizmo sits at its primitive's centre, inside the surface. Each is sized to
                # its own primitive (its arrows just poke out of it), so the four do not pile up in the middle.
                depth_test=False,
                position=slot.position,
                wxyz=slot.wxyz,
                visible=slot.enabled,
            )
            gizmo.on_update(self.callback(self._on_scene_input))
            self.gizmos.append(gizmo)
            # A ball in the primitive's colour at the tip of its local z arrow, and its name: which gizmo moves
            # which primitive, at a glance.
            self.gizmo_markers.append(
                scene.add_icosphere(
                    f"{gizmo.name}/marker",
                    radius=GIZMO_MARKER_RADIUS_M,
                    color=slot.color,
                    subdivisions=2,
                    position=(0.0, 0.0, reach),
                    cast_shadow=False,
                    receive_shadow=False,
                )
            )
            self.gizmo_labels.append(
                scene.add_label(
                    f"{gizmo.name}/label",
                    _gizmo_label(i, slot),
                    position=(0.0, 0.0, reach + 2.5 * GIZMO_MARKER_RADIUS_M),
                )
            )

    def _watch_cameras(self) -> None:
        self.watch_cameras(self._on_camera)

    # ----------------------------------------------------------------------------------------- inputs
    def read_params(self) -> SdfGalleryParams:
        """The current GUI and gizmo values, cleaned: anything unusable keeps the last good value."""
        last = self.params
        slots = []
        for i, (handles, gizmo, old) in enumerate(
            zip(self.slots, self.gizmos, last.primitives, strict=True)
        ):
            enabled = True if i == 0 else self.read_bool(handles["enabled"], old.enabled)
            kind = KIND_LABELS[
                self.read_choice(handles["kind"], list(KIND_LABELS), _label(KIND_LABELS, old.kind))
            ]
            op = OP_LABELS[
                self.read_choice(handles["op"], list(OP_LABELS), _label(OP_LABELS, old.op))
            ]
            size = tuple(
                self.read_number(handles[f"size_{axis}"], value)
                for axis, value in zip("abc", old.size, strict=True)
            )
            position = self.read_position(gizmo, old.position, BOX_LO, BOX_HI)
            slots.append(
                PrimitiveParams(
                    enabled=enabled,
                    kind=kind,
                    size=(size[0], size[1], size[2]),
                    color=self._read_rgb(handles["color"], old.color),
                    op=op,
                    position=position,
                    wxyz=self._read_wxyz(gizmo, old.wxyz),
                )
            )
        return dataclasses.replace(
            last,
            primitives=tuple(slots),
            k=self.read_number(self.k, last.k),
            blend=BLEND_LABELS[
                self.read_choice(self.blend, list(BLEND_LABELS), _label(BLEND_LABELS, last.blend))
            ],
            resolution=int(self.read_number(self.resolution, last.resolution, integer=True)),
        )

    def read_shading(self) -> tuple[Shading, ReferenceMode, int]:
        last = self.params
        s = last.shading
        elevation_deg, azimuth_deg = _light_angles_deg(s.light_direction)
        elevation = math.radians(self.read_number(self.light_elevation, elevation_deg))
        azimuth = math.radians(self.read_number(self.light_azimuth, azimuth_deg))
        shading = dataclasses.replace(
            s,
            ambient=self.read_number(self.ambient, s.ambient),
            diffuse=self.read_number(self.diffuse, s.diffuse),
            specular=self.read_number(self.specular, s.specular),
            shininess=self.read_number(self.shininess, s.shininess),
            shadows=self.read_bool(self.shadows, s.shadows),
            shadow_sharpness=self.read_number(self.shadow_k, s.shadow_sharpness),
            occlusion=self.read_bool(self.occlusion, s.occlusion),
            occlusion_strength=self.read_number(self.occlusion_strength, s.occlusion_strength),
            light_direction=(
                math.cos(elevation) * math.cos(azimuth),
                math.cos(elevation) * math.sin(azimuth),
                math.sin(elevation),
            ),
        )
        mode = MODE_LABELS[
            self.read_choice(self.mode, list(MODE_LABELS), _label(MODE_LABELS, last.reference_mode))
        ]
        width = int(self.read_number(self.reference_width, last.reference_width, integer=True))
        return shading, mode, width

    def _read_rgb(self, handle: Any, last_good: tuple[int, int, int]) -> tuple[int, int, int]:
        raw = handle.value
        try:
            values = [float(v) for v in raw]
        except (TypeError, ValueError):
            values = []
        if len(values) == 3 and all(math.isfinite(v) and 0 <= v <= 255 for v in values):
            return (round(values[0]), round(values[1]), round(values[2]))
        self._write_back(handle, last_good)
        return last_good

    def _read_wxyz(
        self, gizmo: Any, last_good: tuple[float, float, float, float]
    ) -> tuple[float, float, float, float]:
        try:
            q = np.asarray(gizmo.wxyz, dtype=np.float64).reshape(4)
        except (TypeError, ValueError):
            q = np.full(4, np.nan)
        norm = float(np.linalg.norm(q)) if np.all(np.isfinite(q)) else 0.0
        if norm < 1e-6:
            gizmo.wxyz = last_good
            return last_good
        q = q / norm
        return (float(q[0]), float(q[1]), float(q[2]), float(q[3]))

    def _on_scene_input(self) -> None:
        params = self.read_params()
        try:
            params.scene()
        except ValueError:
            logger.warning("sdf: rejected scene input; keeping the last good scene", exc_info=True)
            return
        self.params = params
        self._sync_enabled_inputs()
        self._request_mesh()

    def _on_view_input(self) -> None:
        p = self.params
        view = VIEW_LABELS[
            self.read_choice(self.view_mode, list(VIEW_LABELS), _label(VIEW_LABELS, p.view_mode))
        ]
        source = SOURCE_LABELS[
            self.read_choice(
                self.shape_source, list(SOURCE_LABELS), _label(SOURCE_LABELS, p.shape_source)
            )
        ]
        self.params = dataclasses.replace(p, view_mode=view, shape_source=source)
        self._show_view_mode()
        if source != p.shape_source:
            self._sync_enabled_inputs()
            self._request_mesh()
        with self._work:
            self._view_key = None
            self._work.notify_all()

    def _on_example(self) -> None:
        title = self.read_choice(self.example, list(EXAMPLES), next(iter(EXAMPLES)))
        self._write_back(self.editor, EXAMPLES[title])
        self._request_source(EXAMPLES[title])

    def _on_editor_text(self) -> None:
        """Keep the editor's text only if it is text of at most EDITOR_KEEP_CHARS characters (and editing is on);
        else put the last kept text back, so a huge or crafted value is not kept for every viewer and late joiner
        (viser relays an update to the other viewers before this runs; the write-back replaces it)."""
        text = self.editor.value
        if editing_allowed() and isinstance(text, str) and len(text) <= EDITOR_KEEP_CHARS:
            self._editor_text = text
            return
        self._write_back(self.editor, self._editor_text)
        if editing_allowed():
            length = len(text) if isinstance(text, (str, bytes, list)) else None
            self._show_editor_error(
                f"That text was {length} characters long; the editor keeps at most {EDITOR_KEEP_CHARS} "
                f"(and Apply takes at most {MAX_SOURCE_CHARS}), so the previous text is back."
                if length is not None
                else "The editor takes only text; the previous text is back."
            )

    def _on_apply(self) -> None:
        if not editing_allowed():
            # Only the server's own examples compile: the browser's text is not read.
            title = self.read_choice(self.example, list(EXAMPLES), next(iter(EXAMPLES)))
            self._write_back(self.editor, EXAMPLES[title])
            self._request_source(EXAMPLES[title])
            return
        text = self.editor.value
        if not isinstance(text, str):
            self._show_editor_error("The source must be text.")
            return
        if len(text) > MAX_SOURCE_CHARS:
            self._show_editor_error(
                f"The source is {len(text)} characters long; the limit is {MAX_SOURCE_CHARS} characters. "
                f"Shorten it by {len(text) - MAX_SOURCE_CHARS} and apply again."
            )
            return
        self._request_source(text)

    def _request_source(self, text: str) -> None:
        with self._work:
            self._wanted_source = text
            self._work.notify_all()

    def _show_editor_error(self, message: str) -> None:
        self.editor_error = message
        with self._lock:
            if not self.closed:
                self.editor_status.content = (
                    f"**Not applied.** {message}\n\nThe last good shape stays on screen."
                )

    def _show_view_mode(self) -> None:
        mode = self.params.view_mode
        with self.server.atomic():
            self.mesh_node.visible = mode == "mesh"
            if mode == "both":
                self._draw_wire()
            self.wireframe_node.visible = mode == "both"
            if mode == "mesh":
                self.server.scene.set_background_image(None)
            self.view_note.content = {
                "mesh": "The 3D view shows the marching-cubes mesh.",
                "raymarch": "The 3D view shows the GLSL ray-march, rendered from your camera "
                "(coarser while it moves).",
                "both": "The GLSL ray-march with the mesh as a wireframe over it: where they agree, the "
                "wireframe hugs the surface.",
            }[mode]

    def _draw_wire(self) -> None:
        """Put the latest mesh (preview or full) on the wireframe node."""
        if self._wire is not None:
            self.wireframe_node.vertices, self.wireframe_node.faces = self._wire

    def _on_shading_input(self) -> None:
        shading, mode, width = self.read_shading()
        self.params = dataclasses.replace(
            self.params, shading=shading, reference_mode=mode, reference_width=width
        )
        with self._work:
            self._reference_due = True
            self._work.notify_all()

    def _on_camera(self, camera: Any) -> None:
        if self.closed:
            return
        cam = camera_from_viser(camera)
        if cam is None:
            return
        size = _viewer_size(camera)
        if size is not None:
            with self._work:
                self._viewer_width = size[0]
        try:
            aspect = size[0] / size[1] if size is not None else float(camera.aspect)
        except (TypeError, ValueError, AttributeError, ZeroDivisionError, OverflowError):
            aspect = 4 / 3
        self._on_camera_values(cam, aspect)

    def _on_camera_values(self, cam: Camera, aspect: float) -> None:
        """Take a cleaned camera and its image aspect (width / height) and schedule a new reference."""
        with self._work:
            self._camera = cam
            self._aspect = min(max(aspect, 0.5), 2.5) if math.isfinite(aspect) else 4 / 3
            self._camera_time = time.monotonic()
            self._reference_due = True
            self._work.notify_all()

    def _sync_enabled_inputs(self) -> None:
        """Show gizmos of enabled primitives; grey out sizes the kind does not use."""
        used = SIZES_USED
        self.k.disabled = self.params.blend == "hard"
        for handles, gizmo, slot in zip(
            self.slots, self.gizmos, self.params.primitives, strict=True
        ):
            gizmo.visible = slot.enabled and self.params.shape_source == "primitives"
            for j, axis in enumerate("abc"):
                handles[f"size_{axis}"].disabled = j >= used[slot.kind] or not slot.enabled
        self._sync_gizmo_looks()

    def _sync_gizmo_looks(self) -> None:
        """Each gizmo's size, marker colour and label follow its primitive's kind, size and colour."""
        for i, (gizmo, marker, label, slot) in enumerate(
            zip(
                self.gizmos,
                self.gizmo_markers,
                self.gizmo_labels,
                self.params.primitives,
                strict=True,
            )
        ):
            reach = gizmo_reach(slot)
            if abs(gizmo.scale - reach) > 1e-6:
                gizmo.scale = reach
                marker.position = (0.0, 0.0, reach)
                label.position = (0.0, 0.0, reach + 2.5 * GIZMO_MARKER_RADIUS_M)
            if tuple(int(c) for c in marker.color) != slot.color:
                marker.color = slot.color
            text = _gizmo_label(i, slot)
            if label.text != text:
                label.text = text

    def _request_mesh(self) -> None:
        params = self.params
        half_size = self.read_number(self.editor_half_size, params.editor.half_size)
        if half_size != params.editor.half_size:
            params = dataclasses.replace(
                params, editor=dataclasses.replace(params.editor, half_size=half_size)
            )
            self.params = params
        with self._work:
            now = time.monotonic()
            # A request within CAMERA_REST_S of the one before is part of a burst (a drag): preview it.
            self._wanted_preview = now - self._scene_time < CAMERA_REST_S
            self._scene_time = now
            self._wanted_scene = params.shape()
            self._wanted_resolution = params.resolution
            self._work.notify_all()

    # ----------------------------------------------------------------------------------------- worker
    def _work_forever(self) -> None:
        while not self._stop.is_set():
            with self._work:
                if self._wanted_scene is None and self._wanted_source is None:
                    self._work.wait(
                        timeout=0.05
                    )  # a request that came during the last job is taken at once
                # A drag's preview (≤ 32³, a few ms) takes the process's turn, as callbacks do (TURNS): eight tabs'
                # workers interleaving made each mesh eight times slower, and a tab's newer pose, arriving while
                # its worker waits for the turn, replaces the one it would have meshed. Full meshes (up to seconds)
                # run outside the turn, so they never hold up other tabs' inputs.
                quick = self._quick_job()
            if self._stop.is_set():
                return
            turn = contextlib.ExitStack()
            if quick:  # the scene's lock first, then the turn: the order callbacks take them in
                turn.enter_context(self._lock)
                turn.enter_context(TURNS.turn())
            try:
                with turn:
                    with self._work:
                        # Asked again under the turn: a request that came meanwhile may be a full mesh.
                        meshed_here = quick and self._quick_job()
                        scene, resolution = self._wanted_scene, self._wanted_resolution
                        source, preview = self._wanted_source, self._wanted_preview
                        self._wanted_scene = self._wanted_source = None
                        refine = self._refine
                        rested = time.monotonic() - self._scene_time >= CAMERA_REST_S
                    if meshed_here and scene is not None:
                        self._mesh_request(scene, resolution, preview)
                if self._stop.is_set():
                    return
                if source is None and scene is not None and not meshed_here:
                    self._mesh_request(scene, resolution, preview)
                elif source is not None:
                    self._refine = None
                    self._apply_source(source, resolution)
                elif (
                    scene is None and refine is not None and rested
                ):  # the inputs rested: the full mesh of the latest scene
                    self._refine = None
                    self._mesh_and_show(*refine)
                    with self._work:
                        self._reference_due = True
                if self.gl_error is None:
                    self._render_view()
                if self.gl_error is None and self._reference_ready():
                    self._render_reference()
            except GLUnavailableError as exc:
                self._no_gl(exc)
            except ShaderCompileError as exc:  # a remesh of the editor's field found no surface
                self._show_editor_error(str(exc))
            except Exception:
                # One failed mesh or render must not stop every later one: log it and wait for new input.
                logger.exception("sdf: meshing or rendering failed; keeping the last good picture")
                with self._work:
                    self._reference_due = False

    def _quick_job(self) -> bool:
        """Whether the job wanted now (call under ``self._work``) is a drag's preview of the primitives (≤ 32³, a
        few ms): the kind that takes the process's turn. Editor fields mesh on the GL thread, which may be busy with
        other tabs' renders: they never take it."""
        return (
            self._wanted_source is None
            and isinstance(self._wanted_scene, sdf.Scene)
            and (self._wanted_preview or self._wanted_resolution <= PREVIEW_RESOLUTION)
        )

    def _mesh_request(self, scene: Shape, resolution: int, preview: bool) -> None:
        """Mesh a wanted scene: a preview at 32³ while a drag's inputs keep coming, else at ``resolution``."""
        preview = preview and resolution > PREVIEW_RESOLUTION
        self._refine = (scene, resolution) if preview else None
        self._mesh_and_show(scene, PREVIEW_RESOLUTION if preview else resolution, preview=preview)
        with self._work:
            self._reference_due = True

    def _reference_ready(self) -> bool:
        with self._work:
            if (
                not self._reference_due
                or self.mesh_shape is None
                or self._wanted_scene is not None
                or self._refine
                is not None  # the reference compares against the full mesh, not a preview
            ):
                return False
            if self.params.reference_mode == "live":
                return True
            # Wait until the camera and the primitives have both been still for a moment: a render started in
            # the middle of a drag would hold up the next mesh.
            return time.monotonic() - max(self._camera_time, self._scene_time) >= CAMERA_REST_S

    def _no_gl(self, exc: GLUnavailableError) -> None:
        self.gl_error = str(exc)
        logger.warning("sdf: %s", exc)
        with self._lock:
            if not self.closed:
                self.reference_note.content = f"**No reference image.** {exc}"

    def _apply_source(self, text: str, resolution: int) -> None:
        """Check, compile, time and mesh an editor source; show it, or say why not and keep the last good one."""
        half_size = self.params.editor.half_size
        field = EditorField(text, half_size)
        start = time.perf_counter()
        try:
            check_source(text)
            # Compile and draw it once in a child process first, killed at the limits: a compiler can take
            # minutes on a short source, and moderngl holds the GIL while it compiles, which would freeze every
            # viewer. Only a source that passes is compiled here, the moving frames' program (no shadows, no AO)
            # first: the new shape appears with it, and the fully shaded one compiles when the view next rests.
            moving_shading = _moving_shading(self.params.shading)
            camera = self._camera or Camera(self.camera_position, self.camera_look_at)
            if (
                text not in EXAMPLE_SOURCES
            ):  # the server's own examples are known to compile quickly
                trial(
                    text,
                    [moving_shading, self.params.shading],
                    camera,
                    field.bounds,
                    MOVING_WIDTH_PX,
                    MOVING_WIDTH_PX * 5 // 8,
                    COMPILE_LIMIT_S,
                    FRAME_LIMIT_S,
                )
            gl_service.run(lambda gl: gl.compile_field(text, moving_shading))
            self._mesh_and_show(field, resolution)
        except ShaderCompileError as exc:
            self._show_editor_error(str(exc))
            return
        total_ms = 1e3 * (time.perf_counter() - start)
        with self._lock:
            if self.closed:
                return
            self.params = dataclasses.replace(self.params, editor=field, shape_source="editor")
            self.editor_error = None
            self.editor_serial += 1
            self._write_back(self.shape_source, _label(SOURCE_LABELS, "editor"))
            self._sync_enabled_inputs()
            self.editor_status.content = f"**Applied** in {total_ms:.0f} ms (compile, a test frame and a {resolution}³ mesh)."
        with self._work:
            self._reference_due = True
            self._view_key = None
            self._scene_time = time.monotonic()

    def _mesh_and_show(self, scene: Shape, resolution: int, *, preview: bool = False) -> None:
        """Mesh ``scene`` at ``resolution`` and show it; a ``preview`` goes to the 3D view only (the readouts, the
        export and the reference keep the last full mesh)."""
        if isinstance(scene, EditorField):
            self._mesh_field_and_show(scene, resolution, preview=preview)
            return
        big = resolution >= 128

        def progress(fraction: float) -> None:
            if big and not self.closed:
                self.progress.value = 100.0 * fraction

        if big:
            self.progress.value = 0.0
            self.progress.visible = True
        start = time.perf_counter()
        vertices, faces, colors = sdf.mesh(scene, resolution, progress=progress)
        glb = _viewer_glb(vertices, faces, colors, _scene_normals(scene, vertices))
        mesh_ms = 1e3 * (time.perf_counter() - start)
        self._show_mesh(scene, vertices, faces, colors, glb, mesh_ms, resolution, preview=preview)

    def _mesh_field_and_show(
        self, field: EditorField, resolution: int, *, preview: bool = False
    ) -> None:
        start = time.perf_counter()
        tri = gl_renderer.mesh_glsl(field.source, resolution, field.bounds)
        if len(tri.faces) == 0:
            centre = gl_service.run(lambda gl: gl.probe_field(field.source, [[0.0, 0.0, 0.0]]))[0]
            side = "outside (sdf > 0)" if float(centre[0]) > 0.0 else "inside (sdf ≤ 0)"
            h = field.half_size
            raise ShaderCompileError(
                f"no surface lies inside the bounds: every sample of the ±{h:g} m box is {side}, so there "
                "is nothing to mesh (change sdf() or the editor's bounds)",
                None,
            )
        vertices = np.asarray(tri.vertices, dtype=np.float64)
        faces = np.asarray(tri.faces, dtype=np.int64)
        rgba = getattr(tri.visual, "vertex_colors", np.zeros((len(vertices), 4)))
        colors = np.asarray(rgba, dtype=np.float64)[:, :3] / 255.0
        normals = np.asarray(tri.vertex_normals) if len(faces) else np.zeros_like(vertices)
        glb = _viewer_glb(vertices, faces, colors, normals)
        mesh_ms = 1e3 * (time.perf_counter() - start)
        self._show_mesh(field, vertices, faces, colors, glb, mesh_ms, resolution, preview=preview)

    def _show_mesh(
        self,
        shape: Shape,
        vertices: np.ndarray,
        faces: np.ndarray,
        colors: np.ndarray,
        glb: bytes,
        mesh_ms: float,
        resolution: int,
        *,
        preview: bool = False,
    ) -> None:
        with self._lock:
            if self.closed:
                return
            with self.server.atomic():
                self.mesh_node.glb_data = glb
                # The wireframe shows only in the "Both" view: a hidden one is not sent (40 % of a preview's bytes
                # to every viewer), it is drawn from the latest mesh when it is shown.
                self._wire = (vertices.astype(np.float32), faces.astype(np.uint32))
                if self.wireframe_node.visible:
                    self._draw_wire()
                self.progress.visible = False
                self.shown_resolution = resolution
                if preview:
                    self.preview_serial += 1
                else:
                    self.mesh_vertices, self.mesh_faces, self.mesh_colors = vertices, faces, colors
                    self.mesh_shape = shape
                    self.mesh_scene = shape if isinstance(shape, sdf.Scene) else None
                    grid_scene = shape if isinstance(shape, sdf.Scene) else sdf.default_scene()
                    bounds = None if isinstance(shape, sdf.Scene) else shape.bounds
                    self._mesh_voxel = sdf.make_grid(grid_scene, resolution, bounds).spacing
                    self.mesh_serial += 1
                    self.agreement = dataclasses.replace(
                        self.agreement, triangles=len(faces), mesh_ms=mesh_ms
                    )
                    self.readout.content = self._readout_markdown()
            self.server.flush()

    def _render_reference(self) -> None:
        with self._work:
            self._reference_due = False
            camera = self._camera or Camera(self.camera_position, self.camera_look_at)
            aspect = self._aspect
        with (
            self._lock
        ):  # one consistent mesh: the worker replaces all four together under this lock
            params = self.params
            scene, vertices, faces, colors = (
                self.mesh_shape,
                self.mesh_vertices,
                self.mesh_faces,
                self.mesh_colors,
            )
            mesh_serial = self.mesh_serial
        assert scene is not None
        width = params.reference_width
        height = max(16, round(width / aspect))

        def job(renderer: Renderer) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, str]:
            start = time.perf_counter()
            rgb, depth = _march(renderer, scene, camera, width, height, params.shading)
            render_ms = 1e3 * (time.perf_counter() - start)
            _, mesh_depth = renderer.render_mesh(
                vertices, faces, colors, camera, width, height, params.shading
            )
            return rgb, depth, mesh_depth, render_ms, renderer.renderer_name

        rgb, depth, mesh_depth, render_ms, renderer_name = gl_service.run(job)
        iou, depth_diff = _compare(depth, mesh_depth)
        with self._lock:
            if self.closed:
                return
            with self.server.atomic():
                self.reference.image = rgb
                self.reference_rgb = rgb
                self.reference_serial += 1
                self.reference_mesh_serial = mesh_serial
                self.agreement = dataclasses.replace(
                    self.agreement,
                    render_ms=render_ms,
                    iou=iou,
                    depth_diff_voxels=None if depth_diff is None else depth_diff / self._mesh_voxel,
                )
                self.readout.content = self._readout_markdown()
                self.reference_note.content = f"{width}×{height} px on {renderer_name}."
            self.server.flush()

    def _render_view(self) -> None:
        """The ray-marched main view: a coarse frame while the camera or the shape moves, a full one at rest."""
        with self._work:
            params = self.params
            if params.view_mode == "mesh" or self._camera is None:
                return
            moving = time.monotonic() - max(self._camera_time, self._scene_time) < CAMERA_REST_S
            camera, aspect, viewer_width = self._camera, self._aspect, self._viewer_width
        shape = params.shape()
        if isinstance(shape, sdf.Scene) and self.mesh_shape is not None:
            try:
                shape = self.params.scene()
            except ValueError:
                return
        key = (shape, camera, aspect, viewer_width, moving, params.shading, params.view_mode)
        if key == self._view_key:
            return
        if moving:
            width, height = MOVING_WIDTH_PX, max(16, round(MOVING_WIDTH_PX / aspect))
        else:
            # Before the first rest frame, guess from the moving ones (the shadows and AO cost a few times more).
            guess = None if self._moving_s_per_pixel is None else 4.0 * self._moving_s_per_pixel
            width, height = _rest_size(viewer_width, aspect, self._rest_s_per_pixel or guess)
        shading = _moving_shading(params.shading) if moving else params.shading
        start = time.perf_counter()
        rgb, depth = gl_service.run(lambda gl: _march(gl, shape, camera, width, height, shading))
        view_ms = 1e3 * (time.perf_counter() - start)
        if moving:
            self._moving_s_per_pixel = view_ms / 1e3 / (width * height)
        else:
            self._rest_s_per_pixel = view_ms / 1e3 / (width * height)
        # viser encodes depth in fixed point up to 167 m: a miss goes to the far end.
        depth = np.where(np.isfinite(depth), depth, 1e3).astype(np.float32)
        with self._lock:
            if self.closed or self.params.view_mode == "mesh":
                return
            self.server.scene.set_background_image(rgb, format="jpeg", jpeg_quality=90, depth=depth)
            self.view_rgb, self.view_ms = rgb, view_ms
            self.view_serial += 1
            self._view_key = key
            self.server.flush()

    def _readout_markdown(self) -> str:
        a = self.agreement
        render = "–" if a.render_ms is None else f"{a.render_ms:.0f} ms"
        iou = "–" if a.iou is None else f"{a.iou:.4f}"
        depth = "–" if a.depth_diff_voxels is None else f"{a.depth_diff_voxels:.3f} voxel"
        return (
            f"| | |\n|---|---|\n| Triangles | {a.triangles:,} |\n| Time to mesh | {a.mesh_ms:.0f} ms |\n"
            f"| Time to render | {render} |\n| Silhouette IoU (mesh vs ray-march) | {iou} |\n"
            f"| Mean depth difference | {depth} |"
        )

    # ----------------------------------------------------------------------------------------- downloads
    def _download_handler(self, fmt: str) -> Any:
        def handler(event: Any) -> None:
            client = getattr(event, "client", None)
            if client is None or self.closed:
                return
            try:
                name, content = self.export(fmt)
            except Exception:
                logger.exception("sdf: export %s failed", fmt)
                return
            if content is None:
                client.add_notification(
                    "Nothing to download yet", "The reference image has not been rendered."
                )
                return
            client.send_file_download(name, content)

        return handler

    def export(self, fmt: str) -> tuple[str, bytes | None]:
        """File name and bytes of the current mesh (glb, stl, obj) or reference image (png)."""
        with (
            self._lock
        ):  # a consistent snapshot: the worker replaces these together under this lock
            reference, vertices, faces, colors = (
                self.reference_rgb,
                self.mesh_vertices,
                self.mesh_faces,
                self.mesh_colors,
            )
        if fmt == "png":
            if reference is None:
                return "sdf_reference.png", None
            buffer = io.BytesIO()
            Image.fromarray(reference).save(buffer, format="PNG")
            return "sdf_reference.png", buffer.getvalue()
        tri = sdf.mesh_trimesh(vertices, faces, colors)
        data = tri.export(file_type=fmt)
        return f"sdf_mesh.{fmt}", data.encode() if isinstance(data, str) else bytes(data)


def _compare(marched: np.ndarray, rasterised: np.ndarray) -> tuple[float | None, float | None]:
    """Silhouette IoU and mean depth difference (m) away from silhouette edges (both masks eroded a pixel)."""
    a, b = np.isfinite(marched), np.isfinite(rasterised)
    union = int((a | b).sum())
    if union == 0:
        return None, None
    iou = float((a & b).sum()) / union
    both = a & b
    inner = np.zeros_like(both)
    inner[1:-1, 1:-1] = (
        both[1:-1, 1:-1] & both[:-2, 1:-1] & both[2:, 1:-1] & both[1:-1, :-2] & both[1:-1, 2:]
    )
    if not inner.any():
        return iou, None
    return iou, float(np.mean(np.abs(marched[inner].astype(np.float64) - rasterised[inner])))


def _moving_shading(shading: Shading) -> Shading:
    """The shading of frames drawn while something moves: no soft shadows or ambient occlusion (a smaller program,
    several times cheaper a frame under llvmpipe); the full shading returns when the view rests."""
    return dataclasses.replace(shading, shadows=False, occlusion=False)


def _march(
    gl: Renderer, shape: Shape, camera: Camera, width: int, height: int, shading: Shading
) -> tuple[np.ndarray, np.ndarray]:
    """Ray-march the primitives' scene or the editor's field: RGB (H, W, 3) uint8 and depth (H, W) (m)."""
    if isinstance(shape, EditorField):
        return gl.render_field(shape.source, shape.bounds, camera, width, height, shading)
    return gl.render(shape, camera, width, height, shading)


def _scene_normals(scene: sdf.Scene, vertices: np.ndarray) -> np.ndarray:
    """(V, 3) unit normals: the field's gradient by four probes on a tetrahedron's corners (Quilez's trick)."""
    if not len(vertices):
        return np.zeros((0, 3))
    corners = np.array([[1.0, -1.0, -1.0], [-1.0, -1.0, 1.0], [-1.0, 1.0, -1.0], [1.0, 1.0, 1.0]])
    probes = (vertices[None, :, :] + 1e-4 * corners[:, None, :]).reshape(-1, 3)
    d = sdf.scene_distance(scene, probes).reshape(4, -1)
    gradient = d.T @ corners
    return gradient / np.maximum(np.linalg.norm(gradient, axis=1, keepdims=True), 1e-12)


def _viewer_glb(
    vertices: np.ndarray, faces: np.ndarray, colors: np.ndarray, normals: np.ndarray
) -> bytes:
    """A minimal GLB for the 3D view: positions, smooth normals and 8-bit vertex colours, written directly.

    Normals are the field's gradient (exact directions where the SDF is, no averaging of faces). Colours are made linear: three.js treats vertex colours as linear light, so sRGB-like values would
    look washed out. (trimesh's exporter gives the same file for downloads but costs several times as long, and
    this runs on every drag.)
    """
    v = np.asarray(vertices, dtype=np.float32)
    normals = np.asarray(normals, dtype=np.float32).reshape(-1, 3)
    rgba = np.empty((len(v), 4), np.uint8)
    rgba[:, :3] = np.round(255 * np.clip(colors, 0.0, 1.0) ** 2.2)
    rgba[:, 3] = 255
    indices = np.ascontiguousarray(faces, dtype=np.uint32).ravel()
    blobs = [indices.tobytes(), v.tobytes(), normals.tobytes(), rgba.tobytes()]
    views, offset = [], 0
    for blob, target in zip(blobs, (34963, 34962, 34962, 34962), strict=True):
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(blob), "target": target})
        offset += len(blob)  # every blob's length is a multiple of 4
    lo = v.min(axis=0).tolist() if len(v) else [0.0] * 3
    hi = v.max(axis=0).tolist() if len(v) else [0.0] * 3
    gltf = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [
            {
                "primitives": [
                    {
                        "attributes": {"POSITION": 1, "NORMAL": 2, "COLOR_0": 3},
                        "indices": 0,
                        "mode": 4,
                    }
                ]
            }
        ],
        "buffers": [{"byteLength": offset}],
        "bufferViews": views,
        "accessors": [
            {"bufferView": 0, "componentType": 5125, "count": len(indices), "type": "SCALAR"},
            {
                "bufferView": 1,
                "componentType": 5126,
                "count": len(v),
                "type": "VEC3",
                "min": lo,
                "max": hi,
            },
            {"bufferView": 2, "componentType": 5126, "count": len(v), "type": "VEC3"},
            {
                "bufferView": 3,
                "componentType": 5121,
                "normalized": True,
                "count": len(v),
                "type": "VEC4",
            },
        ],
    }
    text = json.dumps(gltf, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    body = b"".join(blobs)
    total = 12 + 8 + len(text) + 8 + len(body)
    return b"".join(
        [
            struct.pack("<4sII", b"glTF", 2, total),
            struct.pack("<I4s", len(text), b"JSON"),
            text,
            struct.pack("<I4s", len(body), b"BIN\x00"),
            body,
        ]
    )


def _label(mapping: dict[str, Any], value: Any) -> str:
    return next(label for label, v in mapping.items() if v == value)


def _light_angles_deg(direction: tuple[float, float, float]) -> tuple[float, float]:
    x, y, z = np.asarray(direction, dtype=np.float64) / np.linalg.norm(direction)
    return round(math.degrees(math.asin(z))), round(math.degrees(math.atan2(y, x)))
