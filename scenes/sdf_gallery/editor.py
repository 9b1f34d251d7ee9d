"""The gallery's GLSL editor: its field, the switch that lets browsers send GLSL, and what it checks of a source.

:class:`EditorField` is an applied source and the box it is meshed and ray-marched in. :func:`set_editing_allowed`
is the server-wide switch (app.py turns it off for a non-loopback host unless asked). :func:`kept_text_problem` and
:func:`apply_problem` say why the editor's text is not kept or not applied; :func:`trial_source` compiles and draws
a source once in a child process killed at COMPILE_LIMIT_S and FRAME_LIMIT_S; :func:`mesh_field` meshes an applied
field on the GL thread.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from kernels import sdf
from shaders import renderer as gl_renderer
from shaders.renderer import MAX_SOURCE_CHARS, Camera, ShaderCompileError, Shading
from shaders.trial import TrialTimes, trial

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
OWN_CODE = "Your own code"
"""What the Example menu shows once the editor's text is no example's: picking an example again then puts it back."""
EXAMPLE_SOURCES = frozenset(EXAMPLES.values())
EDITOR_KEEP_CHARS = 2 * MAX_SOURCE_CHARS
"""Longest text the editor keeps (characters): room to paste a little too much and trim it; beyond, the previous
text is put back at once."""
EDITOR_HELP = (
    "Write `float sdf(vec3 p)` (metres, Z up) and optionally `vec3 color(vec3 p)` (`in`, `const in` and "
    "`highp` before `vec3` are fine), using the library's "
    "`sd_*` primitives and `op_*`, `smooth_*` operators, then **Apply**: the shape is meshed and ray-marched "
    f"from the same source. At most {MAX_SOURCE_CHARS} characters; no loops, no `#` lines."
)
EDITING_OFF = (
    "**Editing is off**: this server is reachable from other machines. The examples "
    "still work; start the app with `--allow-remote-glsl` to allow typing GLSL."
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


def kept_text_problem(text: object) -> str | None:
    """Why the editor's text is not kept (None when it is: text of at most EDITOR_KEEP_CHARS, editing on); with
    editing off the answer is "" (put the kept text back without a word)."""
    if not editing_allowed():
        return ""
    if isinstance(text, str) and len(text) <= EDITOR_KEEP_CHARS:
        return None
    length = len(text) if isinstance(text, (str, bytes, list)) else None
    if length is None:
        return "The editor takes only text; the previous text is back."
    return (
        f"That text was {length} characters long; the editor keeps at most {EDITOR_KEEP_CHARS} "
        f"(and Apply takes at most {MAX_SOURCE_CHARS}), so the previous text is back."
    )


def apply_problem(text: object) -> str | None:
    """Why ``text`` is not applied before any compiling (None: it is short enough text to try)."""
    if not isinstance(text, str):
        return "The source must be text."
    if len(text) > MAX_SOURCE_CHARS:
        return (
            f"The source is {len(text)} characters long; the limit is {MAX_SOURCE_CHARS} characters. "
            f"Shorten it by {len(text) - MAX_SOURCE_CHARS} and apply again."
        )
    return None


def trial_height(width: int) -> int:
    """The height (px) of the frame :func:`trial_source` draws ``width`` wide."""
    return width * 5 // 8


def trial_source(
    text: str, shadings: list[Shading], camera: Camera, field: EditorField, width: int
) -> TrialTimes | None:
    """Compile ``text`` with each of ``shadings`` and draw one ``width`` × ``width·5/8`` frame with the first in a
    child process, killed at COMPILE_LIMIT_S plus FRAME_LIMIT_S, and return what it measured; ShaderCompileError
    says why it is refused. The server's own examples are known to compile quickly and skip it (None).

    A compiler can take minutes on a short source, and moderngl holds the GIL while it compiles, which would freeze
    every viewer: only a source that passes is compiled in this process.
    """
    if text in EXAMPLE_SOURCES:
        return None
    return trial(text, shadings, camera, field.bounds, width, trial_height(width), COMPILE_LIMIT_S, FRAME_LIMIT_S)


def _no_surface(field: EditorField, resolution: int) -> str:
    """Why a field gave no mesh, from the samples the mesher read: all on one side of the surface (0 is inside), and
    where the nearest comes within two sample spacings of a surface (in metres: the values divided by the field's
    largest gradient), that a shape or hollow may fall between samples."""
    grid = sdf.make_grid(sdf.default_scene(), resolution, field.bounds)  # the mesher's grid (the scene is unused)
    samples = gl_renderer.sample_glsl(field.source, grid)
    box = f"the ±{field.half_size:g} m box"
    lowest, highest = float(samples.min()), float(samples.max())
    if lowest == highest == 0.0:
        return f"no surface lies inside the bounds: sdf() is 0 at every sample of {box}, so there is nothing to mesh"
    side = "outside (sdf > 0)" if lowest > 0.0 else "inside (sdf ≤ 0)"
    message = f"no surface lies inside the bounds: every sample of {box} is {side}, so there is nothing to mesh"
    gradient = gl_renderer.lipschitz_estimate(samples, grid.spacing)
    nearest = (lowest if lowest > 0.0 else -highest) / (gradient if 0.0 < gradient < math.inf else 1.0)
    if nearest < 2.0 * grid.spacing:
        shape = "shape" if lowest > 0.0 else "hollow"
        return (
            f"{message}. The field comes within about {nearest:.3g} m of a surface: a {shape} smaller than the "
            f"sample spacing ({grid.spacing:.3g} m) may fall between samples; shrink the bounds or raise the mesh "
            "resolution"
        )
    return f"{message} (change sdf() or the bounds)"


def mesh_warning(field: EditorField, vertices: np.ndarray, faces: np.ndarray) -> str:
    """What to tell a person whose field meshes but not as they would want; "" for a closed shape inside its bounds.

    A field that crosses its bounds: there marching cubes leaves the mesh open (vertices on the box's faces, where
    the field is still inside). A field inside out (−sdf: negative outside its surface): its closed mesh encloses a
    negative volume (Σ v₀·(v₁ × v₂)/6 over the faces, by the divergence theorem; marching cubes winds them outward
    from sdf ≤ 0), and the ray-march, which starts outside, stops on the box."""
    lo, hi = np.asarray(field.bounds, dtype=np.float64)
    tol = 1e-6 * float(np.max(hi - lo))
    if not len(vertices):
        return ""
    if np.any((np.abs(vertices - lo) < tol) | (np.abs(vertices - hi) < tol)):
        return (
            f"⚠ The shape reaches the ±{field.half_size:g} m box and is cut there: the mesh and its downloads are "
            "open (holes), while the ray-march shows the cut face closed. Raise Editor bounds half size to take it all "
            "in, if it is finite: a plane or any other unbounded shape is always cut."
        )
    v0, v1, v2 = (vertices[faces[:, k]].astype(np.float64) for k in range(3))
    if np.einsum("ij,ij->", v0, np.cross(v1, v2)) < 0.0:
        return (
            "⚠ The field is inside out: sdf() is negative outside its surface (as −sdf is), so the mesh and its "
            "downloads face inward, and the ray-march, which starts outside, stops on the box. Negate sdf() to "
            "turn it right side out."
        )
    return ""


def mesh_field(field: EditorField, resolution: int) -> tuple[np.ndarray, ...]:
    """Mesh the editor's field at ``resolution`` on the GL thread: vertices (V, 3) (m), faces (F, 3), colours
    (V, 3) in [0, 1] and normals (V, 3). ShaderCompileError when no surface lies inside the bounds."""
    tri = gl_renderer.mesh_glsl(field.source, resolution, field.bounds)
    if len(tri.faces) == 0:
        raise ShaderCompileError(_no_surface(field, resolution), None)
    vertices = np.asarray(tri.vertices, dtype=np.float64)
    faces = np.asarray(tri.faces, dtype=np.int64)
    rgba = getattr(tri.visual, "vertex_colors", np.zeros((len(vertices), 4)))
    colors = np.asarray(rgba, dtype=np.float64)[:, :3] / 255.0
    normals = np.asarray(tri.vertex_normals) if len(faces) else np.zeros_like(vertices)
    return vertices, faces, colors, normals
