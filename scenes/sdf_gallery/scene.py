"""The SDF gallery scene: up to four primitives blended with smooth-min, meshed for the 3D view and ray-marched in
GLSL, or a shape written in the GLSL editor.

The distance field comes from :mod:`kernels.sdf`; the mesh is its marching-cubes surface, shown with blended vertex
colours; the "Reference" panel is the same scene sphere-traced by ``shaders/raymarch.frag`` from the viewer's
camera, and the readouts say how well the two agree (:mod:`scenes.sdf_gallery.compare`).

Threads: GUI, gizmo and camera callbacks only record the new state and submit one job, :meth:`SdfGalleryScene.step`,
to the scene's :class:`~scenes._worker.LatestWorker` (a burst of drags coalesces: only the newest state is meshed).
A step meshes the wanted shape, draws the ray-marched main view and renders the reference when it is due; whatever
waits for the inputs to rest (the full-resolution mesh after a drag's previews, the main view's rest frame, the
reference once camera and primitives are still) is scheduled as a later step, CAMERA_REST_S after the last input,
so the worker sleeps between. Refinement is progressive: while a burst of inputs keeps arriving a step meshes at
PREVIEW_RESOLUTION, and once they rest it meshes the latest scene at full resolution (a single change is meshed at
full resolution at once). The GL work goes to :mod:`shaders.gl_service`: one context and one thread per process,
shared by every gallery.
"""

from __future__ import annotations

import contextlib
import dataclasses
import logging
import math
import re
import threading
import time
from typing import Any

import numpy as np
import viser

from kernels import sdf
from scenes import _controls
from scenes._base import TURNS, Scene, mark_costly, set_if_changed
from scenes._controls import build_controls
from scenes._framing import ClientFraming, Lens, View, box_corners, frame_points
from scenes._worker import LatestWorker
from scenes.sdf_gallery import editor
from scenes.sdf_gallery.compare import Agreement, Wire, compare, readout_markdown
from scenes.sdf_gallery.editor import EDITING_OFF, EDITOR_HELP, EXAMPLES, OWN_CODE, EditorField
from scenes.sdf_gallery.export import NOTHING_TO_DOWNLOAD, Download, DownloadFormat, download, scene_normals, viewer_glb
from scenes.sdf_gallery.params import (
    BOX_HI,
    BOX_LO,
    CAMERA_REST_S,
    GIZMO_MARKER_RADIUS_M,
    MOVING_WIDTH_PX,
    PREVIEW_RESOLUTION,
    REFERENCE_FOLDER,
    SCENE_FIELDS,
    SHADING_FIELDS,
    SdfGalleryParams,
    Shape,
    Viewer,
    camera_from_viser,
    gizmo_reach,
    moving_shading,
    rest_size,
    size_meaning,
    sizes_used,
    viewer_size,
)
from scenes.sdf_gallery.slots import add_slot_gizmo, build_slot_controls, read_wxyz, update_gizmo_looks
from shaders import gl_service
from shaders.renderer import Camera, GLUnavailableError, Renderer, ShaderCompileError, Shading, check_source

logger = logging.getLogger(__name__)

VIEW_NOTES = {
    "mesh": "The 3D view shows the marching-cubes mesh.",
    "raymarch": "The 3D view shows the GLSL ray-march, rendered from your camera (coarser while it moves).",
    "both": "The GLSL ray-march with the mesh as a wireframe over it: where they agree, the wireframe hugs the "
    "surface.",
}
"""What the note under the View dropdown says for each view."""


EDITOR_LINES = 18
"""Lines of GLSL the editor shows at once."""
EDITOR_STYLE = (
    f"<style>.mantine-Textarea-input {{ min-height: calc({EDITOR_LINES} * 1.55em) !important;"
    " font-family: ui-monospace, monospace; white-space: pre-wrap; overflow-wrap: anywhere; }"
    " .mantine-Flex-root:has(.mantine-Textarea-input) { flex-direction: column; align-items: stretch; }"
    " .mantine-Flex-root:has(.mantine-Textarea-input) > div { width: 100% !important; }</style>"
)
"""Drawn inside the GLSL editor's folder (and only while the gallery is shown): the editor as a code box of
EDITOR_LINES lines (viser's own text box grows from 2 to at most 6), the panel's full width under its label (viser
gives every control's label a column of its own: the box was 236 px wide, 34 characters), long lines wrapped rather
than cut off."""


_SEE_IT = "; choose GLSL editor in Shape to see it."
"""How an Apply's status ends while Shape shows another shape; dropped once the editor is chosen."""


def as_sentence(message: str) -> str:
    """A refusal as a sentence after the bold "Not applied.": a capital first (not where it opens with code,
    "sdf() returned NaN"), a full stop last."""
    said = message if re.match(r"\w+\(", message) else message[:1].upper() + message[1:]
    return said + "." if said[-1:].isalnum() or said.endswith((")", "'", '"')) else said


def _rebounded(shape: Shape, shown: Shape | None) -> bool:
    """Whether ``shape`` is the shown editor field meshed in another box."""
    return (
        isinstance(shape, EditorField)
        and isinstance(shown, EditorField)
        and shape.source == shown.source
        and shape.half_size != shown.half_size
    )


class SdfGalleryScene(Scene[SdfGalleryParams]):
    key = "sdf"
    title = "SDF gallery (ray marching)"
    opening_view = View((1.9, -2.1, 1.4), (0.05, 0.0, 0.3))
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
        self._bounds_refused = False
        """Whether ``editor_error`` is a remesh's of the applied field in new bounds (the next good one clears it),
        not a refused source's (which stands until a source is applied)."""
        self.editor_serial = 0
        """How many editor sources have been applied, counted once an apply is complete (its view framed too)."""
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
        self.reference_params: SdfGalleryParams | None = None
        self.reference_camera: Camera | None = None
        """The parameters and camera the shown reference image was rendered with (a render in flight when an input
        or the camera changes finishes with those it started with)."""
        self.agreement = Agreement(0, 0.0, None, None, None)
        self.gl_error: str | None = None
        self.viewer = Viewer()
        """What the latest usable camera message said (replaced whole, under the worker's state lock)."""
        self._mesh_voxel = 1.0
        # What the worker is asked to do, guarded by _state (taken after the scene lock and the turn, never before).
        self._state = threading.Lock()
        self._wanted_scene: Shape | None = None
        self._wanted_source: str | None = None
        self._shape_choices = 0
        """How many times the Shape menu has changed: an Apply that finishes after the menu changed leaves the shape
        the person chose."""
        self._gizmo_moves = 0
        """How many inputs have moved or turned a primitive (its gizmo). Each mesh request carries the count it was
        made at, and ``_moves_at_mesh`` is the shown full mesh's: a mesh with none since follows its shape out of
        the picture; one after a drag does not."""
        self._moves_at_mesh: int | None = None
        self._wanted_moves: int | None = None
        self._source_choice = 0
        """``_shape_choices`` when the wanted source was asked for."""
        self._wanted_resolution = self.params.resolution
        self._wanted_preview = False
        """Whether the wanted mesh came in a burst of inputs (mesh it as a preview)."""
        self._refine: tuple[Shape, int, int | None] | None = None
        """The scene, resolution and gizmo-input count of the mesh to make in full once the inputs rest (a preview
        is on screen)."""
        self._scene_time = 0.0
        self._reference_due = True
        self._view_key: tuple[Any, ...] | None = None
        self._view_moving = False
        """Whether the main view's last frame was a moving one (its rest frame is still to come)."""
        self._rest_s_per_pixel: float | None = None
        """Seconds a pixel of the last rest frame took: the next one is sized to REST_FRAME_BUDGET_S."""
        self._moving_s_per_pixel: float | None = None
        self._costs_of: Shape | None = None
        """The editor field the two costs above were measured on, or None for the primitives' scenes: another
        field's frames may cost a hundred times more, so its first rest frame is not sized by them."""
        self._trial_cost: tuple[EditorField, float] | None = None
        """The last applied field and the seconds a pixel of its trial's moving frame took (:mod:`shaders.trial`)."""
        self._download_notices: dict[tuple[int, str], tuple[viser.ClientHandle, str]] = {}
        """The download links shown, by (tab, file name): the tab and the notice's id."""
        self._sending = threading.Lock()
        """Held from a link's send to its record: a second click's handler (viser's pool runs them side by side)
        found the first link not yet recorded once its file had arrived, and left it up."""
        self._build_gui()
        self._build_world()
        self._sync_enabled_inputs()
        self.framing = ClientFraming(self._view_for, opening=self.opening_view.position)
        """Frames each tab's camera on the shape and its gizmos when it opens (and when its window is resized), and
        again when a field applied in the editor, or a shape a control changed, leaves the picture."""
        self._mesh_and_show(self.params.scene(), self.params.resolution, moves=self._gizmo_moves)
        self.worker = LatestWorker("sdf-worker")
        """Runs :meth:`step`: the meshing and ray-marching, off the callback threads."""
        self._threads.append(self.worker.thread)
        self.watch_cameras(self.on_camera)
        self.watch_cameras(self.framing.on_camera)
        self._wake()

    def _view_for(self, lens: Lens) -> View:
        """The opening view's direction, as close as the shape, its gizmos' arrows, rings and labels allow, in the
        canvas left of the panel (:func:`scenes._framing.frame_points`)."""
        return frame_points(
            self.framed_points(),
            self.opening_view.direction,
            fov_rad=lens.fov_rad,
            aspect=lens.aspect,
            ndc=lens.usable_ndc(),
        )

    def framed_points(self) -> np.ndarray:
        """(N, 3) world points (m) the camera frames: the shown mesh's bounding box and, with the primitives shown,
        each enabled gizmo's reach (arrows and rings) and its label above it."""
        vertices = self.mesh_vertices if len(self.mesh_vertices) else self._opening_vertices
        points = [box_corners(vertices.min(axis=0), vertices.max(axis=0))] if len(vertices) else []
        if self.params.shape_source == "primitives":
            for slot in self.params.primitives:
                if slot.enabled:
                    reach = gizmo_reach(slot) + 2.5 * GIZMO_MARKER_RADIUS_M  # the label sits beyond the arrow
                    centre = np.asarray(slot.position, dtype=np.float64)
                    points.append(centre + reach * np.vstack([np.eye(3), -np.eye(3)]))
        return np.vstack(points) if points else np.zeros((1, 3))

    def close(self) -> None:
        """Stop the worker and wait for it (a reference render in flight finishes first), then remove everything."""
        self._stop.set()
        self.worker.close(timeout_s=60.0)
        with self._lock:
            self.server.scene.set_background_image(None)
            notices = list(self._download_notices.values())
            self._download_notices.clear()
        for client, notice in notices:
            self.server.remove_notice(client, notice)
        super().close()

    def wait_idle(self, timeout_s: float = 60.0) -> bool:
        """Sleep until the worker has nothing waiting or running (True), or ``timeout_s`` has passed (False)."""
        return self.worker.wait_idle(timeout_s)

    # ----------------------------------------------------------------------------------------- GUI
    def _build_gui(self) -> None:
        gui = self.server.gui
        p = self.params
        allowed = editor.editing_allowed()
        with self.gui_root:
            self.view_controls = build_controls(gui, p, ("view_mode", "shape_source", "rings"))
            with self.view_controls.folders["Shape and view"]:
                self.view_note = gui.add_markdown("")
            # Shown only with Shape = GLSL editor, and open when it shows (viser opens a folder only as it is made).
            self.example_controls = build_controls(gui, p, ("example",))
            folders = self.example_controls.folders
            self.editor = build_controls(gui, p, ("editor_text",), folders_open=folders)["editor_text"]
            self.editor.disabled = not allowed
            self.half_size_controls = build_controls(gui, p, ("editor_half_size",), folders_open=folders)
            with folders["GLSL editor"]:
                # viser draws a multi-line text box 2–6 lines tall; a GLSL function wants a screenful (sdf.md).
                api: Any = getattr(gui, "api", gui)  # the session's facade records inputs only; html is not one
                api.add_html(EDITOR_STYLE)
                self.apply = mark_costly(gui.add_button("Apply"))  # compiles GLSL, remeshes
                self.editor_status = gui.add_markdown(EDITOR_HELP if allowed else EDITING_OFF)
                self.mesh_note = gui.add_markdown("", visible=False)
            self.scene_controls = build_controls(gui, p, SCENE_FIELDS)
            with self.scene_controls.folders["Blend and mesh"]:
                self.progress = gui.add_progress_bar(0.0, visible=False)
                self.readout = gui.add_markdown("")
            with gui.add_folder(REFERENCE_FOLDER) as reference_folder:
                self.reference = gui.add_image(np.full((120, 160, 3), 235, np.uint8), label="Reference", format="png")
                self.reference_note = gui.add_markdown("")
            self.shading_controls = build_controls(
                gui, p, SHADING_FIELDS, folders_open={REFERENCE_FOLDER: reference_folder}
            )
            self.slot_controls = [build_slot_controls(gui, i, slot) for i, slot in enumerate(p.primitives)]
            self.size_note = gui.add_markdown(size_meaning())
            with gui.add_folder("Downloads", expand_by_default=False):
                self.downloads: dict[DownloadFormat, viser.GuiButtonHandle] = {
                    "glb": gui.add_button("Download mesh (GLB)"),
                    "stl": gui.add_button("Download mesh (STL)"),
                    "obj": gui.add_button("Download mesh (OBJ)"),
                    "png": gui.add_button("Download reference (PNG)"),
                }
        self._on_scene = self.callback(self._on_scene_input)
        """The one handler of every scene input (controls and gizmos): a burst of them costs one read."""
        self.scene_controls.on_update(self._on_scene)
        for controls in self.slot_controls:
            controls.on_update(self._on_scene)
        self.shading_controls.on_update(self.callback(self._on_shading_input))
        for fmt, button in self.downloads.items():
            button.on_click(self._download_handler(fmt))
        self.view_controls.on_update(self.callback(self._on_view_input))
        self.example_controls.on_update(self.callback(self._on_example))
        self.editor.on_update(self.callback(self._on_editor_text))
        self.half_size_controls.on_update(self.callback(self._on_bounds_input))
        self.apply.on_click(self.callback(self._on_apply))

    def _build_world(self) -> None:
        scene = self.server.scene
        vertices, faces, colors = sdf.mesh(self.params.scene(), self.params.resolution)
        self._opening_vertices = vertices
        self.mesh_node = scene.add_mesh_trimesh(f"{self.root.name}/mesh", sdf.mesh_trimesh(vertices, faces, colors))
        self.mesh_node.glb_data = viewer_glb(vertices, faces, colors, scene_normals(self.params.scene(), vertices))
        self._wire = Wire(vertices, faces, serial=0)
        """The latest mesh (preview or full), drawn as a wireframe over the ray-march in the "both" view."""
        self.view_edges = 0
        """Mesh edges drawn over the last main-view frame (0 unless the view is "both")."""
        self.gizmos: list[viser.TransformControlsHandle] = []
        self.gizmo_markers: list[viser.IcosphereHandle] = []
        self.gizmo_labels: list[viser.LabelHandle] = []
        for i, slot in enumerate(self.params.primitives):
            gizmo, marker, label = add_slot_gizmo(
                scene, f"{self.root.name}/gizmo_{i + 1}", i, slot, rings=self.params.rings
            )
            gizmo.on_update(self._on_scene)
            self.gizmos.append(gizmo)
            self.gizmo_markers.append(marker)
            self.gizmo_labels.append(label)

    # ----------------------------------------------------------------------------------------- inputs
    def read_params(self) -> SdfGalleryParams:
        """The current scene controls' and gizmos' values, cleaned: anything unusable keeps the last good value."""
        last = self.params
        slots = []
        for i, (controls, gizmo, old) in enumerate(zip(self.slot_controls, self.gizmos, last.primitives, strict=True)):
            slot = _controls.read_controls(controls, old, write_back=self.write_back)
            slots.append(
                dataclasses.replace(
                    slot,
                    enabled=True if i == 0 else slot.enabled,
                    position=self.read_position(gizmo, old.position, BOX_LO, BOX_HI),
                    wxyz=read_wxyz(gizmo, old.wxyz),
                )
            )
        return dataclasses.replace(self.read_controls(self.scene_controls), primitives=tuple(slots))

    def _on_scene_input(self) -> None:
        params = self.read_params()
        try:
            params.scene()
        except ValueError:
            logger.warning("sdf: rejected scene input; keeping the last good scene", exc_info=True)
            return
        placed = [(slot.position, slot.wxyz) for slot in params.primitives]
        if placed != [(slot.position, slot.wxyz) for slot in self.params.primitives]:
            with self._state:
                self._gizmo_moves += 1  # a gizmo moved or turned one: the mesh it makes keeps the view
        self.params = params
        self._sync_enabled_inputs()
        self._request_mesh()

    def _on_view_input(self) -> None:
        before = self.params
        self.params = self.read_controls(self.view_controls)
        self._show_view_mode()
        if self.params.rings != before.rings:
            with self.server.atomic():
                for gizmo in self.gizmos:
                    gizmo.disable_rotations = not self.params.rings
        if self.params.shape_source != before.shape_source:
            with self._state:
                self._shape_choices += 1
            status = self.editor_status.content
            if self.params.shape_source == "editor" and status.endswith(_SEE_IT):  # it is seen now
                self._show_editor_status(status.removeprefix(f"{EDITING_OFF}\n\n").removesuffix(_SEE_IT) + ".")
            self._sync_enabled_inputs()
            self._request_mesh()
        with self._state:
            self._view_key = None
        self._wake()

    def _on_bounds_input(self) -> None:
        """The editor's bounds: the next Apply meshes and ray-marches in them, and a field on screen is meshed in
        them at once."""
        if self.params.shape_source == "editor":
            self._request_mesh()  # reads the bounds into the parameters and their field
        else:
            self.params = self.read_controls(self.half_size_controls)

    def _on_example(self) -> None:
        self.params = self.read_controls(self.example_controls)
        self._apply_example()

    def _apply_example(self) -> None:
        """Put the chosen example's source in the editor and apply it (the editor's own code stays as it is)."""
        source = EXAMPLES.get(self.params.example)
        if source is None:  # OWN_CODE: nothing to put in
            return
        self.params = dataclasses.replace(self.params, editor_text=source)  # the state first, then what it shows
        self.write_back(self.editor, source)
        self._request_source(source)

    def _on_editor_text(self) -> None:
        """Keep the editor's text only if it is text of at most EDITOR_KEEP_CHARS characters (and editing is on);
        else put the last kept text back, so a huge or crafted value is not kept for every viewer and late joiner
        (viser relays an update to the other viewers before this runs; the write-back replaces it)."""
        text = self.editor.value
        problem = editor.kept_text_problem(text)
        if problem is None:
            self.params = dataclasses.replace(self.params, editor_text=text)
            if text != EXAMPLES.get(self.params.example, text):  # no longer the example: the menu says so
                self.params = dataclasses.replace(self.params, example=OWN_CODE)
                self.write_back(self.example_controls["example"], OWN_CODE)
            return
        self.write_back(self.editor, self.params.editor_text)
        if problem:
            self._show_editor_error(problem)

    def _on_apply(self) -> None:
        if not editor.editing_allowed():
            # Only the server's own examples compile: the browser's text is not read.
            self.params = self.read_controls(self.example_controls)
            self._apply_example()
            return
        text = self.editor.value
        problem = editor.apply_problem(text)
        if problem is not None:
            self._show_editor_error(problem)
            return
        self._request_source(text)

    def _on_shading_input(self) -> None:
        params = self.read_controls(self.shading_controls)
        self.params = dataclasses.replace(params, shading=params.shading_from_controls())
        with self._state:
            self._reference_due = True
        self._wake()

    def on_camera(self, camera: Any) -> None:
        """Take a viewer's camera message (any of its fields may be crafted): unusable ones are ignored."""
        if self.closed:
            return
        cam = camera_from_viser(camera)
        if cam is None:
            return
        size = viewer_size(camera)
        try:
            aspect = size[0] / size[1] if size is not None else float(camera.aspect)
        except (TypeError, ValueError, AttributeError, ZeroDivisionError, OverflowError):
            aspect = 4 / 3
        self.on_camera_values(cam, aspect, None if size is None else size[0])

    def on_camera_values(self, cam: Camera, aspect: float, width_px: int | None = None) -> None:
        """Take a cleaned camera, its image aspect (width / height) and canvas width (px; None keeps the last) and
        ask for a new reference."""
        with self._state:
            self.viewer = Viewer(
                cam,
                min(max(aspect, 0.5), 2.5) if math.isfinite(aspect) else 4 / 3,
                self.viewer.width_px if width_px is None else width_px,
                time.monotonic(),
            )
            self._reference_due = True
        self._wake()

    def _request_mesh(self) -> None:
        params = self.params
        half_size = self.read_controls(self.half_size_controls).editor_half_size
        if half_size != params.editor.half_size:
            params = dataclasses.replace(
                params, editor_half_size=half_size, editor=dataclasses.replace(params.editor, half_size=half_size)
            )
            self.params = params
        with self._state:
            now = time.monotonic()
            # A request within CAMERA_REST_S of the one before is part of a burst (a drag): preview it.
            self._wanted_preview = now - self._scene_time < CAMERA_REST_S
            self._scene_time = now
            self._wanted_scene = params.shape()
            self._wanted_resolution = params.resolution
            self._wanted_moves = self._gizmo_moves
        self._wake()

    def _request_source(self, text: str) -> None:
        with self._state:
            self._wanted_source, self._source_choice = text, self._shape_choices
        self._wake()

    # ----------------------------------------------------------------------------------------- showing inputs
    def _show_editor_status(self, status: str) -> None:
        """Say ``status`` under the editor, after why typing is off where it is (the box stays disabled: a status
        alone would leave it unexplained)."""
        self.editor_status.content = status if editor.editing_allowed() else f"{EDITING_OFF}\n\n{status}"

    def _show_editor_error(self, message: str, *, bounds: bool = False) -> None:
        self.editor_error, self._bounds_refused = message, bounds
        with self._lock:
            if not self.closed:
                self._show_editor_status(
                    f"**Not applied.** {as_sentence(message)}\n\nThe last good shape stays on screen."
                )

    def _show_view_mode(self) -> None:
        mode = self.params.view_mode
        with self.server.atomic():
            self.mesh_node.visible = mode == "mesh"
            if mode == "mesh":
                self.server.scene.set_background_image(None)
            self.view_note.content = VIEW_NOTES[mode]

    def _sync_enabled_inputs(self) -> None:
        """Show gizmos of enabled primitives, sized and named for them; grey out sizes the kind does not use."""
        self.scene_controls["k"].disabled = self.params.blend == "hard"
        primitives = self.params.shape_source == "primitives"
        # Each shape source shows its own controls only: the primitives' panels, blend and gizmo rings, or the editor.
        for name in ("blend", "k"):
            self.scene_controls[name].visible = primitives
        self.view_controls["rings"].visible = primitives  # so do the gizmos the rings sit on
        for folder in (folder for controls in self.slot_controls for folder in controls.folders.values()):
            folder.visible = primitives
        self.size_note.visible = primitives
        self.example_controls.folders["GLSL editor"].visible = not primitives
        for controls, gizmo, slot in zip(self.slot_controls, self.gizmos, self.params.primitives, strict=True):
            gizmo.visible = slot.enabled and primitives
            for j, handle in enumerate(controls.each("size")):
                handle.disabled = j >= sizes_used(slot.kind) or not slot.enabled
        # Each gizmo's size, marker colour and label follow its primitive's kind, size and colour.
        handles = zip(self.gizmos, self.gizmo_markers, self.gizmo_labels, strict=True)
        for i, (gizmo, marker, label) in enumerate(handles):
            update_gizmo_looks(gizmo, marker, label, i, self.params.primitives[i])

    # ----------------------------------------------------------------------------------------- worker
    def _wake(self) -> None:
        """Ask for a step now (it replaces a step waiting for the inputs to rest: it will ask again)."""
        self.worker.submit(self.step)

    def step(self) -> None:
        """One worker job: mesh what is wanted, draw the main view, render the reference if it is due, then ask
        for a later step if something waits for the inputs to rest. A failure is logged (or shown, for GL and
        editor errors) and the last good picture stays."""
        if self.closed:
            return
        try:
            self._mesh_wanted()
            if self.closed:
                return
            if self.gl_error is None:
                self._render_view()
            if self.gl_error is None and self._reference_ready():
                self._render_reference()
        except GLUnavailableError as exc:
            self._no_gl(exc)
        except ShaderCompileError as exc:  # a remesh of the editor's field found no surface
            self._show_editor_error(str(exc), bounds=True)
        except Exception:
            # One failed mesh or render must not stop every later one: log it and wait for new input.
            logger.exception("sdf: meshing or rendering failed; keeping the last good picture")
            with self._state:
                self._reference_due = False
            return
        self._schedule_rest()

    def _mesh_wanted(self) -> None:
        """Mesh the wanted scene or apply the wanted editor source; or, once the inputs rest, the full mesh of the
        scene a drag's previews showed."""
        with self._state:
            # A drag's preview (≤ 32³, a few ms) takes the process's turn, as callbacks do (TURNS): eight tabs'
            # workers interleaving made each mesh eight times slower, and a tab's newer pose, arriving while its
            # worker waits for the turn, replaces the one it would have meshed. Full meshes (up to seconds) run
            # outside the turn, so they never hold up other tabs' inputs.
            quick = self._quick_job()
        turn = contextlib.ExitStack()
        if quick:  # the scene's lock first, then the turn: the order callbacks take them in
            turn.enter_context(self._lock)
            turn.enter_context(TURNS.turn())
        with turn:
            with self._state:
                # Asked again under the turn: a request that came meanwhile may be a full mesh.
                meshed_here = quick and self._quick_job()
                scene, resolution, moves = self._wanted_scene, self._wanted_resolution, self._wanted_moves
                source, preview, choice = self._wanted_source, self._wanted_preview, self._source_choice
                self._wanted_scene = self._wanted_source = None
                refine = self._refine
                rested = time.monotonic() - self._scene_time >= CAMERA_REST_S
            if meshed_here and scene is not None:
                self._mesh_request(scene, resolution, preview, moves)
        if self.closed:
            return
        if source is None and scene is not None and not meshed_here:
            self._mesh_request(scene, resolution, preview, moves)
        elif source is not None:
            self._refine = None
            self._apply_source(source, resolution, choice)
        elif scene is None and refine is not None and rested:
            self._refine = None
            self._mesh_and_show(refine[0], refine[1], moves=refine[2])
            with self._state:
                self._reference_due = True

    def _schedule_rest(self) -> None:
        """Ask for a step when the next thing waiting for the inputs to rest is due: the full mesh after a drag's
        previews, the main view's rest frame, the reference (once camera and primitives are still)."""
        with self._state:
            rest_at = max(self.viewer.moved_at, self._scene_time) + CAMERA_REST_S
            due: list[float] = []
            if self._refine is not None:
                due.append(self._scene_time + CAMERA_REST_S)
            elif self._reference_due and self.gl_error is None and self.mesh_shape is not None:
                due.append(rest_at)
            if self._view_moving and self.gl_error is None:
                due.append(rest_at)
        if due:
            self.worker.schedule(self.step, min(due) - time.monotonic())

    def _quick_job(self) -> bool:
        """Whether the job wanted now (call under ``self._state``) is a drag's preview of the primitives (≤ 32³, a
        few ms): the kind that takes the process's turn. Editor fields mesh on the GL thread, which may be busy with
        other tabs' renders: they never take it."""
        return (
            self._wanted_source is None
            and isinstance(self._wanted_scene, sdf.Scene)
            and (self._wanted_preview or self._wanted_resolution <= PREVIEW_RESOLUTION)
        )

    def _mesh_request(self, scene: Shape, resolution: int, preview: bool, moves: int | None) -> None:
        """Mesh a wanted scene (asked for when ``moves`` gizmo inputs had come): a preview at 32³ while a drag's
        inputs keep coming, else at ``resolution``."""
        preview = preview and resolution > PREVIEW_RESOLUTION
        self._refine = (scene, resolution, moves) if preview else None
        self._mesh_and_show(scene, PREVIEW_RESOLUTION if preview else resolution, preview=preview, moves=moves)
        with self._state:
            self._reference_due = True

    def _reference_ready(self) -> bool:
        with self._state:
            if (
                not self._reference_due
                or self.mesh_shape is None
                or self._wanted_scene is not None
                or self._refine is not None  # the reference compares against the full mesh, not a preview
            ):
                return False
            if self.params.reference_mode == "live":
                return True
            # Wait until the camera and the primitives have both been still for a moment: a render started in
            # the middle of a drag would hold up the next mesh.
            return time.monotonic() - max(self.viewer.moved_at, self._scene_time) >= CAMERA_REST_S

    def _no_gl(self, exc: GLUnavailableError) -> None:
        self.gl_error = str(exc)
        logger.warning("sdf: %s", exc)
        with self._lock:
            if not self.closed:
                self.reference_note.content = f"**No reference image.** {exc}"

    def _camera_or_default(self) -> Camera:
        """The latest viewer's camera, or the scene's opening one before any viewer sent one."""
        return self.viewer.camera or Camera(self.opening_view.position, self.opening_view.look_at)

    def _apply_source(self, text: str, resolution: int, choice: int) -> None:
        """Check, compile, time and mesh an editor source; show it, or say why not and keep the last good one.

        An Apply shows the editor's field (Shape turns to the editor), unless the Shape menu was turned away from
        the editor after it (``choice``: :attr:`_shape_choices` when it was asked for): the source is then applied
        to the editor, and the shape chosen last stays on screen."""
        field = EditorField(text, self.params.editor_half_size)  # the bounds on screen
        start = time.perf_counter()
        try:
            check_source(text)
            # Trial it in a child process first; then compile the moving frames' program (no shadows, no AO)
            # here: the new shape appears with it, and the fully shaded one compiles when the view next rests.
            shading = self.params.shading
            times = editor.trial_source(
                text, [moving_shading(shading), shading], self._camera_or_default(), field, MOVING_WIDTH_PX
            )
            gl_service.run(lambda gl: gl.compile_field(text, moving_shading(shading)))
            if not self._turned_away(choice):
                self._mesh_and_show(field, resolution)
        except ShaderCompileError as exc:
            self._show_editor_error(str(exc))
            return
        total_ms = 1e3 * (time.perf_counter() - start)
        with self._lock:
            if self.closed:
                return
            if self._turned_away(choice):
                self.params = dataclasses.replace(self.params, editor=field)
                self.editor_error, self._bounds_refused = None, False
                self.editor_serial += 1
                self._show_editor_status(f"**Applied** in {total_ms:.0f} ms{_SEE_IT}")
                self._request_mesh()  # the chosen shape, also where the Apply took the request that chose it
                return
            self.params = dataclasses.replace(self.params, editor=field, shape_source="editor")
            self.editor_error, self._bounds_refused = None, False
            with self._state:  # an older field asked for while this one compiled (Shape turned away and back)
                if isinstance(self._wanted_scene, EditorField):
                    self._wanted_scene = None
            source_control = self.view_controls.fields["shape_source"].control
            self.write_back(self.view_controls["shape_source"], source_control.to_gui("editor"))
            self._sync_enabled_inputs()
            self._show_editor_status(
                f"**Applied** in {total_ms:.0f} ms (compile, a test frame and a {resolution}³ mesh)."
            )
            if self.params.editor_half_size != field.half_size:  # the bounds moved while it compiled
                self._request_mesh()
            points = self.framed_points()
        # A field anywhere in its box: framed if it left the picture (the gallery frames under viser's notice)
        self.framing.keep_in_view(points, clear_of_notice=False)
        with self._state:
            self._reference_due = True
            self._view_key = None
            self._scene_time = time.monotonic()
            if times is not None:
                per_pixel = times.frame_s / (MOVING_WIDTH_PX * editor.trial_height(MOVING_WIDTH_PX))
                self._trial_cost = (field, per_pixel)
        with self._lock:
            self.editor_serial += 1

    def _turned_away(self, choice: int) -> bool:
        """Whether the Shape menu turned away from the editor since an Apply asked at ``choice`` (see
        :meth:`_apply_source`)."""
        with self._state:
            return self._shape_choices != choice and self.params.shape_source != "editor"

    def _mesh_and_show(self, scene: Shape, resolution: int, *, preview: bool = False, moves: int | None = None) -> None:
        """Mesh ``scene`` at ``resolution`` and show it; a ``preview`` goes to the 3D view only (the readouts, the
        export and the reference keep the last full mesh). ``moves``: the gizmo inputs counted when it was asked
        for (None: not a request of the primitives' controls)."""
        start = time.perf_counter()
        if isinstance(scene, EditorField):
            vertices, faces, colors, normals = editor.mesh_field(scene, resolution)
        else:
            big = resolution >= 128

            def progress(fraction: float) -> None:
                if big and not self.closed:
                    self.progress.value = 100.0 * fraction

            if big:
                self.progress.value = 0.0
                self.progress.visible = True
            vertices, faces, colors = sdf.mesh(scene, resolution, progress=progress)
            normals = scene_normals(scene, vertices)
        glb = viewer_glb(vertices, faces, colors, normals)
        mesh_ms = 1e3 * (time.perf_counter() - start)
        self._show_mesh(scene, vertices, faces, colors, glb, mesh_ms, resolution, preview=preview, moves=moves)

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
        moves: int | None = None,
    ) -> None:
        with self._lock:
            if self.closed:
                return
            # A field re-bounded in the editor may lie anywhere in its new box, primitives changed by a control
            # (a size, a kind, one turned on, the blend) may outgrow the picture, and the Shape menu turned from the
            # one to the other shows what the last view was not framed for: the view follows if it left the picture
            # (a newly applied field is followed by _apply_source, once the scene shows the editor). A gizmo's drag
            # never moves the view, here or since the last mesh: it would pull the camera.
            unmoved = moves is not None and moves == self._moves_at_mesh
            if not preview:
                self._moves_at_mesh = moves
            shown = self.mesh_shape
            switched = shown is not None and isinstance(shape, EditorField) != isinstance(shown, EditorField)
            follow = not preview and (
                switched
                or _rebounded(shape, shown)
                or (isinstance(shape, sdf.Scene) and isinstance(shown, sdf.Scene) and shape != shown and unmoved)
            )
            with self.server.atomic():
                self.mesh_node.glb_data = glb
                # The "both" view draws this mesh's edges into its ray-marched frame (never sent as lines: a
                # software-WebGL browser drew ~10⁴ of them at 4-6 frames/s).
                self._wire = Wire(vertices, faces, serial=self._wire.serial + 1)
                self.progress.visible = False
                self.shown_resolution = resolution
                if preview:
                    self.preview_serial += 1
                else:
                    self.mesh_vertices, self.mesh_faces, self.mesh_colors = vertices, faces, colors
                    self.mesh_shape = shape
                    note = editor.mesh_warning(shape, vertices, faces) if isinstance(shape, EditorField) else ""
                    if isinstance(shape, EditorField) and self._bounds_refused:  # the box that had no surface is gone
                        self.editor_error, self._bounds_refused = None, False
                        self._show_editor_status(f"**Meshed again** in the ±{shape.half_size:g} m box.")
                    set_if_changed(self.mesh_note, "content", note)
                    set_if_changed(self.mesh_note, "visible", bool(note))
                    self.mesh_scene = shape if isinstance(shape, sdf.Scene) else None
                    grid_scene = shape if isinstance(shape, sdf.Scene) else sdf.default_scene()
                    bounds = None if isinstance(shape, sdf.Scene) else shape.bounds
                    self._mesh_voxel = sdf.make_grid(grid_scene, resolution, bounds).spacing
                    self.mesh_serial += 1
                    # The comparison was of the last mesh: "–" until the reference is rendered against this one.
                    self.agreement = Agreement(len(faces), mesh_ms, None, None, None)
                    self.readout.content = readout_markdown(self.agreement)
            self.server.flush()
            points = self.framed_points() if follow else None
        if points is not None:
            self.framing.keep_in_view(points, clear_of_notice=False)

    def _render_reference(self) -> None:
        with self._state:
            self._reference_due = False
            camera, aspect = self._camera_or_default(), self.viewer.aspect
        with self._lock:  # one consistent mesh: the worker replaces all four together under this lock
            params = self.params
            scene, vertices, faces, colors = (self.mesh_shape, self.mesh_vertices, self.mesh_faces, self.mesh_colors)
            mesh_serial = self.mesh_serial
        assert scene is not None
        width = params.reference_width
        height = max(16, round(width / aspect))

        def job(renderer: Renderer) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, str]:
            start = time.perf_counter()
            rgb, depth = march(renderer, scene, camera, width, height, params.shading)
            render_ms = 1e3 * (time.perf_counter() - start)
            _, mesh_depth = renderer.render_mesh(vertices, faces, colors, camera, width, height, params.shading)
            return rgb, depth, mesh_depth, render_ms, renderer.renderer_name

        rgb, depth, mesh_depth, render_ms, renderer_name = gl_service.run(job)
        iou, depth_diff = compare(depth, mesh_depth)
        with self._lock:
            if self.closed:
                return
            with self.server.atomic():
                self.reference.image = rgb
                self.reference_rgb = rgb
                self.reference_params, self.reference_camera = params, camera
                self.reference_serial += 1
                self.reference_mesh_serial = mesh_serial
                if mesh_serial == self.mesh_serial:  # else a newer mesh is shown: this compares an older one
                    self.agreement = dataclasses.replace(
                        self.agreement,
                        render_ms=render_ms,
                        iou=iou,
                        depth_diff_voxels=None if depth_diff is None else depth_diff / self._mesh_voxel,
                    )
                    self.readout.content = readout_markdown(self.agreement)
                self.reference_note.content = f"{width}×{height} px on {renderer_name}."
            self.server.flush()

    def _render_view(self) -> None:
        """The ray-marched main view: a coarse frame while the camera or the shape moves, a full one at rest."""
        with self._state:
            params, viewer = self.params, self.viewer
            camera = viewer.camera
            if params.view_mode == "mesh" or camera is None:
                self._view_moving = False
                return
            moving = time.monotonic() - max(viewer.moved_at, self._scene_time) < CAMERA_REST_S
        shape = params.shape()
        if isinstance(shape, sdf.Scene) and self.mesh_shape is not None:
            try:
                shape = self.params.scene()
            except ValueError:
                self._view_moving = False
                return
        aspect, viewer_width = viewer.aspect, viewer.width_px
        with self._state:
            costs_of = shape if isinstance(shape, EditorField) else None
            if costs_of != self._costs_of:  # a new field: its costs, not the last one's (the trial's, if it had one)
                trial = self._trial_cost
                self._costs_of, self._rest_s_per_pixel = costs_of, None
                self._moving_s_per_pixel = trial[1] if trial is not None and trial[0] == costs_of else None
        with self._lock:
            wire = self._wire if params.view_mode == "both" else None
        key = (shape, camera, aspect, viewer_width, moving, params.shading, params.view_mode, wire and wire.serial)
        self._view_moving = moving
        if key == self._view_key:
            return
        if moving:
            width, height = MOVING_WIDTH_PX, max(16, round(MOVING_WIDTH_PX / aspect))
        else:
            # Before the first rest frame, guess from the moving ones (the shadows and AO cost a few times more).
            guess = None if self._moving_s_per_pixel is None else 4.0 * self._moving_s_per_pixel
            width, height = rest_size(viewer_width, aspect, self._rest_s_per_pixel or guess)
        shading = moving_shading(params.shading) if moving else params.shading
        start = time.perf_counter()

        def job(gl: Renderer) -> tuple[np.ndarray, np.ndarray]:
            rgb, depth = march(gl, shape, camera, width, height, shading)
            if wire is not None and len(wire.edges):
                rgb = gl.draw_edges(wire.vertices, wire.edges, camera, width, height, tolerance_m=wire.tolerance_m)
            return rgb, depth

        rgb, depth = gl_service.run(job)
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
            self.view_edges = 0 if wire is None else len(wire.edges)
            self.view_serial += 1
            self._view_key = key
            self.server.flush()

    # ----------------------------------------------------------------------------------------- downloads
    def _download_handler(self, fmt: DownloadFormat) -> Any:
        def handler(event: Any) -> None:
            client = getattr(event, "client", None)
            if client is None or self.closed:
                return
            try:
                answer = self.download(fmt)
            except Exception:
                logger.exception("sdf: export %s failed", fmt)
                self.notify(client, "The download failed", "See the server's log.", color="red")
                return
            if answer.content is None:
                self.notify(client, NOTHING_TO_DOWNLOAD, answer.why_not)
                return
            with self._sending:
                notice = self.server.send_download(client, answer.name, answer.content)
                with self._lock:
                    # One link a file and tab: the newer one replaces it (its file freed); the scene's close takes
                    # the rest down, so no link is left over another scene. A close that began while this one was
                    # sent has taken down the links it found: this one goes too.
                    older = self._download_notices.pop((client.client_id, answer.name), None)
                    stale = [] if older is None else [older]
                    if self.closed:
                        stale.append((client, notice))
                    else:
                        self._download_notices[(client.client_id, answer.name)] = (client, notice)
            for link in stale:
                self.server.remove_notice(*link)

        return handler

    def download(self, fmt: DownloadFormat) -> Download:
        """The file of a download button (the current mesh as glb, stl or obj, the reference image as png), or why
        there is none (an empty mesh, no reference yet)."""
        with self._lock:  # a consistent snapshot: the worker replaces these together under this lock
            reference, vertices, faces, colors = (
                self.reference_rgb,
                self.mesh_vertices,
                self.mesh_faces,
                self.mesh_colors,
            )
        return download(fmt, vertices, faces, colors, reference)

    def export(self, fmt: DownloadFormat) -> tuple[str, bytes | None]:
        """File name and bytes of :meth:`download` (None when there is nothing to export)."""
        answer = self.download(fmt)
        return answer.name, answer.content


def march(
    gl: Renderer, shape: Shape, camera: Camera, width: int, height: int, shading: Shading
) -> tuple[np.ndarray, np.ndarray]:
    """Ray-march the primitives' scene or the editor's field: RGB (H, W, 3) uint8 and depth (H, W) (m)."""
    if isinstance(shape, EditorField):
        return gl.render_field(shape.source, shape.bounds, camera, width, height, shading)
    return gl.render(shape, camera, width, height, shading)
