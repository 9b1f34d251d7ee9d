"""A small offscreen renderer: ray-marches an SDF scene in GLSL and rasterises its mesh from the same camera.

It uses moderngl's standalone context on EGL: Mesa llvmpipe on a machine without a GPU, the GPU where there is one.
Programs are compiled once per :class:`Renderer`; the scene reaches ``sdf.glsl`` as uniforms, so moving or changing
a primitive never recompiles anything.

Camera model: a pinhole at ``position`` looking at ``look_at`` with ``up`` and a vertical field of view. Pixel
``(row, col)`` (row 0 at the top) looks along ``forward + x·tan(fov/2)·aspect·right + y·tan(fov/2)·up`` with
``x = 2(col + ½)/W − 1`` and ``y = 1 − 2(row + ½)/H``; :func:`camera_rays` gives the same rays in numpy. Depth is
the distance along the view axis (m), ``inf`` where nothing is hit; the rasterised mesh uses the same convention,
so the two images compare pixel for pixel.

An EGL context lives on the thread that made it: use a :class:`Renderer` on the thread that created it (the
module-level :func:`render` keeps one per thread).
"""

from __future__ import annotations

import collections
import dataclasses
import math
import re
import threading
from pathlib import Path

import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray

from kernels import sdf

KIND_CODE: dict[str, int] = {
    "sphere": 0,
    "box": 1,
    "torus": 2,
    "capsule": 3,
    "cylinder": 4,
    "round_box": 5,
    "octahedron": 6,
    "cone": 7,
    "hex_prism": 8,
    "ellipsoid": 9,
}
BASIC_KINDS = frozenset({"sphere", "box", "torus", "capsule"})
"""Kinds the fast single-formula path of sdf.glsl's primitive_distance handles; others need EXTRA_KINDS."""
OP_CODE: dict[str, int] = {"union": 0, "subtract": 1, "intersect": 2}
BLEND_CODE: dict[str, int] = {"poly": 0, "exp": 1}
_MISS = -1.0
"""Depth the shaders write where no surface is hit; read back as inf."""
_PROBE_WIDTH = 256


class GLUnavailableError(RuntimeError):
    """No OpenGL 3.3 context could be created; the mesh side of the app keeps working without one."""


@dataclasses.dataclass(frozen=True)
class Camera:
    """A pinhole camera in the world frame (Z up)."""

    position: tuple[float, float, float]
    """Eye position (m)."""
    look_at: tuple[float, float, float]
    """Point the view axis passes through (m)."""
    up: tuple[float, float, float] = (0.0, 0.0, 1.0)
    """Approximate up direction; made orthogonal to the view axis."""
    fov_y_rad: float = math.radians(50.0)
    """Vertical field of view (rad), in (0, π)."""

    def __post_init__(self) -> None:
        eye, target, up = (
            np.asarray(v, dtype=np.float64) for v in (self.position, self.look_at, self.up)
        )
        for name, v in (("position", eye), ("look_at", target), ("up", up)):
            if v.shape != (3,) or not np.all(np.isfinite(v)):
                raise ValueError(f"{name} must be 3 finite numbers, got {v.tolist()}")
        forward = target - eye
        if np.linalg.norm(forward) < 1e-9:
            raise ValueError("look_at must differ from position")
        if np.linalg.norm(np.cross(forward, up)) < 1e-9 * np.linalg.norm(forward) * max(
            np.linalg.norm(up), 1e-30
        ):
            raise ValueError("up must not be parallel to the view axis")
        if not (math.isfinite(self.fov_y_rad) and 0.0 < self.fov_y_rad < math.pi):
            raise ValueError(f"fov_y_rad must be in (0, π), got {self.fov_y_rad}")

    def basis(self) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """Unit (forward, right, up) vectors of the image."""
        forward = np.subtract(self.look_at, self.position).astype(np.float64)
        forward /= np.linalg.norm(forward)
        right = np.cross(forward, self.up)
        right /= np.linalg.norm(right)
        return forward, right, np.cross(right, forward)

    def view_projection(self, aspect: float, near: float, far: float) -> NDArray[np.float64]:
        """(4, 4) OpenGL clip-from-world matrix for this camera."""
        forward, right, up = self.basis()
        eye = np.asarray(self.position, dtype=np.float64)
        view = np.eye(4)
        view[0, :3], view[1, :3], view[2, :3] = right, up, -forward
        view[:3, 3] = -view[:3, :3] @ eye
        f = 1.0 / math.tan(self.fov_y_rad / 2)
        proj = np.zeros((4, 4))
        proj[0, 0], proj[1, 1] = f / aspect, f
        proj[2, 2], proj[2, 3] = (far + near) / (near - far), 2 * far * near / (near - far)
        proj[3, 2] = -1.0
        return proj @ view


@dataclasses.dataclass(frozen=True)
class Shading:
    """Lighting and marching parameters of the reference image; defaults are the gallery's opening values."""

    ambient: float = 0.2
    """k_a, ambient reflection."""
    diffuse: float = 0.75
    """k_d, diffuse reflection."""
    specular: float = 0.3
    """k_s, specular reflection."""
    shininess: float = 32.0
    """α, Phong exponent."""
    light_direction: tuple[float, float, float] = (0.45, -0.35, 0.82)
    """Direction toward the light (world), normalised on use."""
    shadows: bool = True
    """Soft shadows (Quilez's improved technique)."""
    shadow_sharpness: float = 8.0
    """k of the soft shadow: penumbra width ∝ 1/k."""
    occlusion: bool = True
    """Ambient occlusion along the normal."""
    occlusion_strength: float = 3.0
    """How strongly occluded samples darken the ambient term."""
    occlusion_step: float = 0.04
    """Distance between the five AO samples (m)."""
    background: tuple[float, float, float] = (0.93, 0.94, 0.96)
    """Linear RGB where no surface is hit."""
    max_steps: int = 256
    """Sphere-tracing steps before a ray counts as a miss."""
    hit_epsilon: float = 1e-4
    """Hit threshold (m at t ≤ 1, relative beyond)."""
    max_distance: float = 100.0
    """Rays longer than this miss (m)."""
    normal_epsilon: float = 1e-3
    """Central-difference step for normals (m)."""

    def __post_init__(self) -> None:
        for name in ("ambient", "diffuse", "specular", "occlusion_strength"):
            value = getattr(self, name)
            if not (math.isfinite(value) and 0.0 <= value <= 10.0):
                raise ValueError(f"{name} must be in [0, 10], got {value}")
        for name in (
            "shininess",
            "shadow_sharpness",
            "occlusion_step",
            "hit_epsilon",
            "max_distance",
        ):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"{name} must be finite and positive, got {value}")
        if not (math.isfinite(self.normal_epsilon) and self.normal_epsilon > 0.0):
            raise ValueError(
                f"normal_epsilon must be finite and positive, got {self.normal_epsilon}"
            )
        light = np.asarray(self.light_direction, dtype=np.float64)
        if light.shape != (3,) or not np.all(np.isfinite(light)) or np.linalg.norm(light) < 1e-9:
            raise ValueError(
                f"light_direction must be a finite non-zero 3-vector, got {light.tolist()}"
            )
        if not 1 <= self.max_steps <= 4096:
            raise ValueError(f"max_steps must be in 1..4096, got {self.max_steps}")


def camera_rays(
    camera: Camera, width: int, height: int
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The renderer's rays in numpy: origins and unit directions, (H·W, 3) each, row-major from the top row."""
    _check_size(width, height)
    forward, right, up = camera.basis()
    tan_half = math.tan(camera.fov_y_rad / 2)
    x = (2 * (np.arange(width) + 0.5) / width - 1) * tan_half * width / height
    y = (1 - 2 * (np.arange(height) + 0.5) / height) * tan_half
    dirs = forward + x[None, :, None] * right + y[:, None, None] * up
    dirs = dirs.reshape(-1, 3)
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    origins = np.broadcast_to(np.asarray(camera.position, dtype=np.float64), dirs.shape).copy()
    return origins, dirs


def _bounding_boxes(
    scene: sdf.Scene,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Oriented boxes whose union holds the scene: (P, 3) centres, (P, 3, 3) local-to-world rotations, (P, 3) half
    extents (m).

    Each primitive's box in its own frame (the torus's ring lies in the local xz plane, the capsule's axis is local
    y), grown by k/4 per smooth union and 1 mm: each union's blend lies at most k/4 below the smaller distance (poly:
    k·h(1 - h) ≤ k/4; exp: ln 2 / sharpness = k/4), and subtraction and intersection only raise the distance, so
    every point inside the scene lies within that reach of some primitive. (The spheres of
    :func:`kernels.sdf.scene_bounding_spheres` grow by k, the same bound with slack.) A flat torus's box is far
    thinner than its sphere, so fewer rays march beside the shape and miss.
    """
    half = np.zeros((len(scene.primitives), 3))
    for i, prim in enumerate(scene.primitives):
        s = prim.size
        match prim.kind:
            case "sphere":
                half[i] = (s[0], s[0], s[0])
            case "box":
                half[i] = s[:3]
            case "torus":
                half[i] = (s[0] + s[1], s[1], s[0] + s[1])
            case "capsule":
                half[i] = (s[1], s[0] + s[1], s[1])
            case "cylinder" | "cone":
                radius, half_height = (s[1], s[0]) if prim.kind == "cylinder" else (s[0], s[1] / 2)
                half[i] = (radius, half_height, radius)
            case "round_box" | "ellipsoid":
                half[i] = s[:3]
            case "octahedron":
                half[i] = (s[0], s[0], s[0])
            case "hex_prism":
                half[i] = (2 * s[0] / math.sqrt(3.0), s[0], s[1])
    centers = np.array([p.center for p in scene.primitives], dtype=np.float64)
    rotations = np.array([sdf.rotation_matrix(p.rotation) for p in scene.primitives])
    unions = sum(prim.op == "union" for prim in scene.primitives[1:])
    return centers, rotations, half + unions * scene.k / 4 + 1e-3


def _bounds_scissor(
    camera: Camera, scene: sdf.Scene, width: int, height: int
) -> tuple[int, int, int, int]:
    """(x, y, w, h) pixel rectangle (GL origin bottom left) holding the screen image of the bounding boxes.

    Conservative: the rectangle bounds the boxes' projected corners, widened by a pixel; if any corner lies near or
    behind the eye it is the whole image.
    """
    centers, rotations, half = _bounding_boxes(scene)
    unit = np.array(
        [[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=np.float64
    )
    corners = (
        centers[:, None, :] + np.einsum("pij,pcj->pci", rotations, half[:, None, :] * unit[None])
    ).reshape(-1, 3)
    forward, right, up = camera.basis()
    rel = corners - np.asarray(camera.position)
    z = rel @ forward
    if np.all(z <= 0.0):
        return (0, 0, 0, 0)  # wholly behind the eye: nothing to draw
    if np.any(z < 1e-3):
        return (0, 0, width, height)
    tan_half = math.tan(camera.fov_y_rad / 2)
    x_ndc = (rel @ right) / (z * tan_half * width / height)
    y_ndc = (rel @ up) / (z * tan_half)
    x0 = int(np.clip(math.floor((x_ndc.min() + 1) / 2 * width) - 1, 0, width))
    x1 = int(np.clip(math.ceil((x_ndc.max() + 1) / 2 * width) + 1, 0, width))
    y0 = int(np.clip(math.floor((y_ndc.min() + 1) / 2 * height) - 1, 0, height))
    y1 = int(np.clip(math.ceil((y_ndc.max() + 1) / 2 * height) + 1, 0, height))
    return (x0, y0, max(x1 - x0, 0), max(y1 - y0, 0))


def _background_levels(shading: Shading) -> tuple[int, int, int]:
    """The background colour in 8-bit levels, as the images hold it."""
    red, green, blue = (int(np.clip(round(c * 255), 0, 255)) for c in shading.background)
    return red, green, blue


def _check_size(width: int, height: int) -> None:
    for name, value in (("width", width), ("height", height)):
        if (
            isinstance(value, bool)
            or not isinstance(value, (int, np.integer))
            or not 1 <= value <= 8192
        ):
            raise ValueError(f"{name} must be an integer in 1..8192, got {value!r}")


SHADER_DIR = Path(__file__).resolve().parent
"""Where the GLSL files live (installed as package data next to this module)."""


def _source(name: str) -> str:
    return (SHADER_DIR / name).read_text(encoding="utf-8")


def _with_defines(source: str, **defines: int) -> str:
    """``source`` with ``#define NAME value`` lines after its ``#version`` line."""
    version, rest = source.split("\n", 1)
    assert version.startswith("#version")
    return "\n".join([version, *(f"#define {k} {v}" for k, v in defines.items()), rest])


# ------------------------------------------------------------------------------------------ the editor's source
MAX_SOURCE_CHARS = 8000
"""Longest editor source accepted (characters)."""
_FIELD_CACHE = 12
"""Editor programs kept compiled (a few sources × their variants)."""
_MAX_ROWS = 8192
"""Rows of one grid-sampling draw (GL_MAX_TEXTURE_SIZE is at least this on every driver we meet)."""
DEFAULT_COLOR_GLSL = "vec3 color(vec3 p) {\n    return vec3(0.85, 0.55, 0.35);\n}\n"
"""The colour an editor source gets when it defines no ``color``."""
_FORBIDDEN = {
    "for": "loops are not allowed (a loop could run forever and stall every viewer); use op_repeat_finite",
    "while": "loops are not allowed (a loop could run forever and stall every viewer)",
    "do": "loops are not allowed (a loop could run forever and stall every viewer)",
    "discard": "discard is not allowed in sdf() or color()",
    "uniform": "declaring uniforms is not allowed",
    "main": "main() is the app's; write float sdf(vec3 p) and optionally vec3 color(vec3 p)",
}


MAX_INLINED_TOKENS = 20000
"""Largest ``sdf`` + ``color`` accepted once every call is inlined (tokens, the library's functions counted too).
GLSL compilers inline every call, so a chain of functions each calling the one before twice doubles the code at
each link: ten links of 679 characters took Mesa 76 s to compile. The examples count at most about 1600."""
_DEFINITION = re.compile(r"\b([A-Za-z_]\w*)\s+([A-Za-z_]\w*)\s*\(([^()]*)\)\s*\{")
_TOKEN = re.compile(r"\w+|[^\w\s]")
_NOT_NAMES = frozenset({"if", "else", "return", "for", "while", "do", "switch"})


def inlined_sizes(code: str, known: dict[str, int] | None = None) -> dict[str, int]:
    """Tokens of each function defined in ``code`` (comments already removed) with every call to a function
    defined before it (or in ``known``) replaced by that function's own inlined size, by name.

    A call to a function not yet defined counts nothing (GLSL needs a declaration first and forbids recursion, so
    the compiler refuses such a source anyway)."""
    sizes = dict(known or {})
    for match in _DEFINITION.finditer(code):
        name = match.group(2)
        if match.group(1) in _NOT_NAMES or name in _NOT_NAMES:
            continue
        depth, end = 1, match.end()
        while end < len(code) and depth:
            depth += {"{": 1, "}": -1}.get(code[end], 0)
            end += 1
        tokens = _TOKEN.findall(code[match.end() : end])
        size = len(tokens)
        for i, token in enumerate(tokens[:-1]):
            if token != name and tokens[i + 1] == "(" and token in sizes:
                size += sizes[token]
        sizes[name] = size
    return sizes


_library_sizes: dict[str, int] = {}


def _without_comments(source: str) -> str:
    return "\n".join(line.split("//", 1)[0] for line in source.split("\n"))


class ShaderCompileError(ValueError):
    """An editor source the checks or the GLSL compiler reject; ``line`` is 1-based in that source (or None)."""

    def __init__(self, message: str, line: int | None) -> None:
        super().__init__(message if line is None else f"line {line}: {message}")
        self.line = line
        self.reason = message

    @classmethod
    def from_compiler(cls, log: str, source: str) -> ShaderCompileError:
        """The first error of a compiler log (Mesa "0:LINE(COL): error: …"; NVIDIA "0(LINE) : error …")."""
        lines = source.count("\n") + 1
        for match in re.finditer(
            r"^\s*\d+[:(](\d+)\)?(?:\(\d+\))?\s*:\s*error\s*:?\s*(.+)$", log, re.M
        ):
            line, message = int(match.group(1)), match.group(2).strip()
            return cls(message, line if 1 <= line <= lines else None)
        text = (
            " ".join(log.replace("GLSL Compiler failed", "").split())
            or "the shader did not compile"
        )
        return cls(text, None)


def check_source(source: object) -> str:
    """The editor source if the app will compile it, else :class:`ShaderCompileError` saying why and where.

    Untrusted text: at most :data:`MAX_SOURCE_CHARS` printable ASCII characters (tabs and newlines too; no
    backslash, which would join lines, and no carriage return, which Mesa takes as a line end); no ``#``, so no
    preprocessor lines (no ``#include``, ``#extension``, macros); no loops (``for``, ``while``, ``do``): without
    them, and without recursion (which GLSL forbids), every call of ``sdf`` ends, and its cost grows with the
    source's length, which :data:`MAX_INLINED_TOKENS` bounds once calls are inlined; no ``uniform`` declarations,
    ``discard`` or ``main``. It must define
    ``float sdf(vec3 p)``; ``vec3 color(vec3 p)`` is optional.
    """
    if not isinstance(source, str):
        raise ShaderCompileError("the source must be text", None)
    if len(source) > MAX_SOURCE_CHARS:
        raise ShaderCompileError(
            f"the source is {len(source)} characters; the limit is {MAX_SOURCE_CHARS}", None
        )
    # Check the text the compiler will see. A backslash before a newline splices two lines into one (so
    # "fo\<newline>r" is the word for) and Mesa ends a // comment at a lone carriage return (so a loop after one is
    # code): neither has a use in sdf() text, so both are refused outright, and every line below is a line the
    # compiler reads as one.
    for number, line in enumerate(source.split("\n"), start=1):
        bad = next((c for c in line if not (" " <= c <= "~" or c == "\t")), None)
        if bad == "\r":
            raise ShaderCompileError(
                "carriage returns are not allowed (end lines with a plain newline)", number
            )
        if bad is not None:
            raise ShaderCompileError(
                f"character {bad!r} is not allowed (printable ASCII only)", number
            )
        if "\\" in line:
            raise ShaderCompileError(
                "backslashes are not allowed (a backslash at a line's end joins it to the next)",
                number,
            )
        code = line.split("//", 1)[0]
        if "#" in code:
            raise ShaderCompileError("preprocessor lines (#…) are not allowed", number)
        for word in re.findall(r"[A-Za-z_]\w*", code):
            if word in _FORBIDDEN:
                raise ShaderCompileError(_FORBIDDEN[word], number)
            if word.startswith("gl_"):
                raise ShaderCompileError(f"{word} is not available here", number)
    if "/*" in source:
        raise ShaderCompileError("block comments (/* */) are not allowed; use //", None)
    if not re.search(r"\bfloat\s+sdf\s*\(\s*vec3\s+\w+\s*\)", source):
        raise ShaderCompileError("define float sdf(vec3 p), the signed distance (m)", None)
    if not _library_sizes:
        _library_sizes.update(inlined_sizes(_without_comments(_source("sdf.glsl"))))
    sizes = inlined_sizes(_without_comments(source), _library_sizes)
    inlined = sizes.get("sdf", 0) + sizes.get("color", 0)
    if inlined > MAX_INLINED_TOKENS:
        raise ShaderCompileError(
            f"sdf() and color() come to about {inlined} tokens once every call is inlined (a function that "
            f"calls another several times multiplies its size); the limit is {MAX_INLINED_TOKENS}",
            None,
        )
    return source


def user_glsl(source: str) -> str:
    """What a template gets appended: ``#line 1`` so compiler lines count from the source's first line, the
    source, and the default ``color`` if it defines none."""
    has_color = re.search(r"\bvec3\s+color\s*\(\s*vec3\s+\w+\s*\)", source) is not None
    return "\n#line 1\n" + source + "\n" + ("" if has_color else DEFAULT_COLOR_GLSL)


def _check_bounds(bounds: ArrayLike) -> NDArray[np.float64]:
    box = np.asarray(bounds, dtype=np.float64)
    if box.shape != (2, 3) or not np.all(np.isfinite(box)) or np.any(box[1] <= box[0]):
        raise ValueError(
            f"bounds must be finite (2, 3) min and max corners with max > min, got {box.tolist()}"
        )
    if np.any(np.abs(box) > 1e3):
        raise ValueError("bounds must lie within ±1000 m")
    return box


def _box_scissor(
    camera: Camera, box: NDArray[np.float64], width: int, height: int
) -> tuple[int, int, int, int]:
    """:func:`_bounds_scissor` for one axis-aligned box (the editor's bounds)."""
    corners = np.array(
        [[box[i, 0], box[j, 1], box[k, 2]] for i in (0, 1) for j in (0, 1) for k in (0, 1)]
    )
    forward, right, up = camera.basis()
    rel = corners - np.asarray(camera.position)
    z = rel @ forward
    if np.all(z <= 0.0):
        return (0, 0, 0, 0)
    if np.any(z < 1e-3):
        return (0, 0, width, height)
    tan_half = math.tan(camera.fov_y_rad / 2)
    x_ndc = (rel @ right) / (z * tan_half * width / height)
    y_ndc = (rel @ up) / (z * tan_half)
    x0 = int(np.clip(math.floor((x_ndc.min() + 1) / 2 * width) - 1, 0, width))
    x1 = int(np.clip(math.ceil((x_ndc.max() + 1) / 2 * width) + 1, 0, width))
    y0 = int(np.clip(math.floor((y_ndc.min() + 1) / 2 * height) - 1, 0, height))
    y1 = int(np.clip(math.ceil((y_ndc.max() + 1) / 2 * height) + 1, 0, height))
    return (x0, y0, max(x1 - x0, 0), max(y1 - y0, 0))


def create_context() -> object:
    """A standalone OpenGL 3.3+ context on EGL, or :class:`GLUnavailableError` saying why not."""
    try:
        import moderngl
    except ImportError as exc:  # pragma: no cover - moderngl is a dependency
        raise GLUnavailableError(
            f"moderngl is not installed ({exc}); the reference image needs it"
        ) from exc
    try:
        # moderngl's stub types `backend` wrongly (as a dict); the runtime takes the backend's name.
        return moderngl.create_standalone_context(backend="egl", require=330)  # pyright: ignore[reportArgumentType]
    except Exception as exc:
        raise GLUnavailableError(
            "No OpenGL 3.3 context on EGL, so the GLSL reference image cannot be rendered "
            f"({type(exc).__name__}: {exc}). Install Mesa's EGL (Debian: libegl1 libgl1-mesa-dri) or run on a "
            "machine with a GPU driver; the mesh view works without it."
        ) from exc


class Renderer:
    """Compiled programs on one EGL context; use it on the thread that created it."""

    def __init__(self, builtin: bool = True) -> None:
        """``builtin=False`` skips compiling the app's own programs (for a trial of an editor source alone)."""
        import moderngl

        ctx = create_context()
        assert isinstance(ctx, moderngl.Context)
        self.ctx = ctx
        self.ctx.includes["sdf.glsl"] = _source("sdf.glsl")
        self.ctx.includes["shading.glsl"] = _source("shading.glsl")
        fullscreen = _source("fullscreen.vert")
        # One program per (shadows, occlusion, polynomial blend only), compiled on first use and kept: under
        # llvmpipe a term switched off by a uniform would still be paid for, and the exponential blend's exp and log
        # cost as much as the rest of the scene, so poly and hard scenes use a program without them.
        self._raymarch_source = _source("raymarch.frag")
        self._fullscreen = _source("fullscreen.vert")
        self._raymarch: dict[tuple[bool, bool, bool, bool], object] = {}
        self._raymarch_vao: dict[tuple[bool, bool, bool, bool], object] = {}
        self._fields: collections.OrderedDict[tuple[str, str], tuple[object, object]] = (
            collections.OrderedDict()
        )
        """Compiled editor programs by (source, variant), least recently used first."""
        self.renderer_name = str(self.ctx.info.get("GL_RENDERER", "unknown"))
        self._target_size: tuple[int, int] | None = None
        self._target_objects: list = []
        if not builtin:
            return
        for shadows, occlusion in ((True, True), (False, False)):  # the gallery's opening variants
            self._raymarch_program((shadows, occlusion, True, False))
        self._probe = self.ctx.program(
            vertex_shader=fullscreen,
            fragment_shader=_with_defines(_source("probe.frag"), EXTRA_KINDS=1),
        )
        self._mesh = self.ctx.program(
            vertex_shader=_source("mesh.vert"), fragment_shader=_source("mesh.frag")
        )
        self._probe_vao = self.ctx.vertex_array(self._probe, [])

    def release(self) -> None:
        self.ctx.release()

    def _raymarch_program(self, variant: tuple[bool, bool, bool, bool]) -> tuple[object, object]:
        """The ray-march program for (shadows, occlusion, polynomial blend only, catalogue kinds), compiled once."""
        if variant not in self._raymarch:
            shadows, occlusion, poly_only, extra = variant
            prog = self.ctx.program(
                vertex_shader=self._fullscreen,
                fragment_shader=_with_defines(
                    self._raymarch_source,
                    SHADOWS=int(shadows),
                    OCCLUSION=int(occlusion),
                    POLY_BLEND_ONLY=int(poly_only),
                    EXTRA_KINDS=int(extra),
                ),
            )
            self._raymarch[variant] = prog
            self._raymarch_vao[variant] = self.ctx.vertex_array(prog, [])
        return self._raymarch[variant], self._raymarch_vao[variant]

    # ------------------------------------------------------------------------------------- uniforms
    def _set(self, program: object, name: str, value: object) -> None:
        import moderngl

        assert isinstance(program, moderngl.Program)
        if name in program:  # the GLSL compiler drops uniforms a program does not use
            uniform = program[name]
            assert isinstance(uniform, moderngl.Uniform)
            uniform.value = value

    def _write(self, program: object, name: str, data: NDArray[np.generic]) -> None:
        import moderngl

        assert isinstance(program, moderngl.Program)
        if name in program:
            uniform = program[name]
            assert isinstance(uniform, moderngl.Uniform)
            uniform.write(np.ascontiguousarray(data).tobytes())

    def _set_scene(self, program: object, scene: sdf.Scene) -> None:
        n = sdf.MAX_PRIMITIVES
        kind, op = np.zeros(n, np.int32), np.zeros(n, np.int32)
        center, size, color = (
            np.zeros((n, 3), np.float32),
            np.zeros((n, 3), np.float32),
            np.zeros((n, 3), np.float32),
        )
        rotation = np.tile(np.eye(3, dtype=np.float32), (n, 1, 1))
        for i, prim in enumerate(scene.primitives):
            kind[i], op[i] = KIND_CODE[prim.kind], OP_CODE[prim.op]
            center[i], color[i] = prim.center, prim.color
            size[i, : len(prim.size)] = prim.size
            # GLSL mat3 is column-major: writing R row by row gives the matrix Rᵀ (world to local).
            rotation[i] = sdf.rotation_matrix(prim.rotation)
        self._set(program, "u_count", len(scene.primitives))
        self._write(program, "u_kind", kind)
        self._write(program, "u_op", op)
        self._write(program, "u_center", center)
        self._write(program, "u_size", size)
        self._write(program, "u_world_to_local", rotation)
        self._write(program, "u_color", color)
        self._set(program, "u_k", float(scene.k))
        self._set(program, "u_blend", BLEND_CODE[scene.blend])
        centers, radii = sdf.scene_bounding_spheres(scene)
        bounds = np.zeros((n, 4), np.float32)
        bounds[: len(radii), :3], bounds[: len(radii), 3] = centers, radii
        self._write(program, "u_bounds", bounds)
        boxes = np.zeros((n, 3), np.float32)
        boxes[: len(radii)] = _bounding_boxes(scene)[2]
        self._write(program, "u_box_half", boxes)

    def _set_shading(self, program: object, shading: Shading) -> None:
        light = np.asarray(shading.light_direction, dtype=np.float64)
        self._set(program, "u_ambient", shading.ambient)
        self._set(program, "u_diffuse", shading.diffuse)
        self._set(program, "u_specular", shading.specular)
        self._set(program, "u_shininess", shading.shininess)
        self._set(program, "u_light_direction", tuple(light / np.linalg.norm(light)))

    def _targets(self, width: int, height: int, shading: Shading) -> tuple[object, object, object]:
        """Colour (RGB8), depth (R32F) and z-buffer of this size, kept between calls (new ones cost a draw), cleared.

        The colour is cleared to the background and the depth to the miss value, each through a framebuffer of its
        own, so reading back needs no masking (that masking cost more than the readback itself). Returns the
        framebuffer of all three, bound, with the colour and depth textures.
        """
        import moderngl

        if self._target_size != (width, height):
            for obj in self._target_objects:
                obj.release()
            color = self.ctx.texture((width, height), 3, dtype="f1")
            depth = self.ctx.texture((width, height), 1, dtype="f4")
            zbuffer = self.ctx.depth_renderbuffer((width, height))
            fbo = self.ctx.framebuffer(color_attachments=[color, depth], depth_attachment=zbuffer)
            color_only = self.ctx.framebuffer(color_attachments=[color])
            depth_only = self.ctx.framebuffer(color_attachments=[depth], depth_attachment=zbuffer)
            self._target_objects = [fbo, color_only, depth_only, color, depth, zbuffer]
            self._target_size = (width, height)
        fbo, color_only, depth_only, color, depth, _ = self._target_objects
        assert isinstance(fbo, moderngl.Framebuffer)
        assert isinstance(color_only, moderngl.Framebuffer)
        assert isinstance(depth_only, moderngl.Framebuffer)
        # Whole 8-bit levels: GL turns c/255 back into c exactly.
        red, green, blue = (float(c) / 255.0 for c in _background_levels(shading))
        color_only.use()
        color_only.clear(red, green, blue, 1.0)
        depth_only.use()
        depth_only.clear(_MISS, _MISS, _MISS, 0.0, depth=1.0)
        fbo.use()
        return fbo, color, depth

    def _read(
        self, color: object, depth: object, width: int, height: int
    ) -> tuple[NDArray[np.uint8], NDArray[np.float32]]:
        import moderngl

        assert isinstance(color, moderngl.Texture) and isinstance(depth, moderngl.Texture)
        rgb = np.frombuffer(color.read(), np.uint8).reshape(height, width, 3)[::-1].copy()
        z = np.frombuffer(depth.read(), np.float32).reshape(height, width)[::-1].copy()
        z[z == _MISS] = np.inf
        return rgb, z

    # ------------------------------------------------------------------------------------- passes
    def render(
        self,
        scene: sdf.Scene,
        camera: Camera,
        width: int,
        height: int,
        shading: Shading | None = None,
    ) -> tuple[NDArray[np.uint8], NDArray[np.float32]]:
        """Ray-march the scene.

        Args:
            scene: the SDF scene.
            camera: where it is seen from.
            width: image width (px).
            height: image height (px).
            shading: lighting and marching parameters (defaults if None).

        Returns:
            RGB (H, W, 3) uint8 (row 0 at the top) and depth along the view axis (H, W) float32 in metres, inf
            where a ray misses.
        """
        import moderngl

        _check_size(width, height)
        shading = shading or Shading()
        # sdf.glsl's smin_blend uses the polynomial form for hard scenes (k = 0) whatever the blend.
        variant = (
            shading.shadows,
            shading.occlusion,
            scene.blend == "poly" or scene.k == 0.0,
            any(p.kind not in BASIC_KINDS for p in scene.primitives),
        )
        prog, vao = self._raymarch_program(variant)
        self._set_scene(prog, scene)
        self._set_camera(prog, camera, width, height, shading)
        fbo, color, depth = self._targets(width, height, shading)
        assert isinstance(fbo, moderngl.Framebuffer)
        # Only pixels whose rays can meet a bounding box run the shader (llvmpipe pays for every pixel).
        fbo.scissor = _bounds_scissor(camera, scene, width, height)
        self.ctx.disable(moderngl.DEPTH_TEST)
        vao.render(moderngl.TRIANGLES, vertices=3)  # pyright: ignore[reportAttributeAccessIssue]
        fbo.scissor = (0, 0, width, height)
        return self._read(color, depth, width, height)

    def _set_camera(
        self, prog: object, camera: Camera, width: int, height: int, shading: Shading
    ) -> None:
        """The camera, marching and shading uniforms of a ray-march program."""
        self._set_shading(prog, shading)
        forward, right, up = camera.basis()
        self._set(prog, "u_resolution", (float(width), float(height)))
        self._set(prog, "u_eye", tuple(float(v) for v in camera.position))
        self._set(prog, "u_forward", tuple(forward))
        self._set(prog, "u_right", tuple(right))
        self._set(prog, "u_up", tuple(up))
        self._set(prog, "u_tan_half_fov", math.tan(camera.fov_y_rad / 2))
        self._set(prog, "u_max_steps", int(shading.max_steps))
        self._set(prog, "u_hit_epsilon", shading.hit_epsilon)
        self._set(prog, "u_max_distance", shading.max_distance)
        self._set(prog, "u_normal_epsilon", shading.normal_epsilon)
        self._set(prog, "u_shadow_sharpness", shading.shadow_sharpness)
        self._set(prog, "u_occlusion_strength", shading.occlusion_strength)
        self._set(prog, "u_occlusion_step", shading.occlusion_step)

    def render_mesh(
        self,
        vertices: ArrayLike,
        faces: ArrayLike,
        colors: ArrayLike,
        camera: Camera,
        width: int,
        height: int,
        shading: Shading | None = None,
    ) -> tuple[NDArray[np.uint8], NDArray[np.float32]]:
        """Rasterise a triangle mesh (e.g. :func:`kernels.sdf.mesh`'s) with the same camera and Phong terms.

        Args:
            vertices: (V, 3) world positions (m).
            faces: (F, 3) vertex indices.
            colors: (V, 3) linear RGB in [0, 1].
            camera: where it is seen from.
            width: image width (px).
            height: image height (px).
            shading: lighting (its shadows and AO are not used here).

        Returns:
            RGB (H, W, 3) uint8 and depth along the view axis (H, W) float32 (m), inf where no triangle covers
            the pixel centre.
        """
        import moderngl

        _check_size(width, height)
        shading = shading or Shading()
        v = np.asarray(vertices, dtype=np.float64)
        f = np.asarray(faces, dtype=np.int64)
        c = np.asarray(colors, dtype=np.float64)
        if v.ndim != 2 or v.shape[1] != 3 or not np.all(np.isfinite(v)):
            raise ValueError(f"vertices must be finite (V, 3), got {v.shape}")
        if f.ndim != 2 or f.shape[1] != 3 or (f.size and (f.min() < 0 or f.max() >= len(v))):
            raise ValueError(f"faces must be (F, 3) indices into vertices, got {f.shape}")
        if c.shape != v.shape:
            raise ValueError(f"colors must match vertices' shape {v.shape}, got {c.shape}")
        normals = (
            trimesh.Trimesh(v, f, process=False).vertex_normals if len(f) else np.zeros_like(v)
        ).astype(np.float32)
        eye = np.asarray(camera.position, dtype=np.float64)
        forward, _, _ = camera.basis()
        reach = np.linalg.norm(v - eye, axis=1).max() if len(v) else 1.0
        near, far = max(1e-3, 1e-3 * reach), 2.0 * reach + 1.0
        prog = self._mesh
        self._set_shading(prog, shading)
        self._write(
            prog,
            "u_view_projection",
            camera.view_projection(width / height, near, far).T.astype("f4"),
        )
        self._set(prog, "u_eye", tuple(float(x) for x in eye))
        self._set(prog, "u_forward", tuple(forward))
        _, color, depth = self._targets(width, height, shading)
        if len(f):
            interleaved = np.concatenate(
                [v.astype(np.float32), normals, c.astype(np.float32)], axis=1
            )
            vbo = self.ctx.buffer(np.ascontiguousarray(interleaved).tobytes())
            ibo = self.ctx.buffer(np.ascontiguousarray(f, dtype=np.int32).tobytes())
            vao = self.ctx.vertex_array(
                prog, [(vbo, "3f 3f 3f", "in_position", "in_normal", "in_color")], index_buffer=ibo
            )
            self.ctx.enable(moderngl.DEPTH_TEST)
            vao.render(moderngl.TRIANGLES)
            self.ctx.disable(moderngl.DEPTH_TEST)
            for obj in (vao, vbo, ibo):
                obj.release()
        return self._read(color, depth, width, height)

    def probe(
        self, scene: sdf.Scene, points: ArrayLike
    ) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
        """Evaluate ``scene_distance`` and ``scene_color`` of ``sdf.glsl`` at points (via a float texture).

        Args:
            scene: the scene.
            points: (N, 3) world points (m).

        Returns:
            (N,) distances (m) and (N, 3) colours, float32, computed by the GLSL.
        """
        import moderngl

        pts = np.asarray(points, dtype=np.float32)
        if pts.ndim != 2 or pts.shape[1] != 3 or not np.all(np.isfinite(pts)) or len(pts) == 0:
            raise ValueError(f"points must be finite (N, 3) with N ≥ 1, got {pts.shape}")
        n = len(pts)
        width = min(n, _PROBE_WIDTH)
        height = -(-n // width)
        padded = np.zeros((width * height, 3), np.float32)
        padded[:n] = pts
        source = self.ctx.texture((width, height), 3, padded.tobytes(), dtype="f4")
        source.filter = (moderngl.NEAREST, moderngl.NEAREST)
        distance = self.ctx.texture((width, height), 1, dtype="f4")
        color = self.ctx.texture((width, height), 4, dtype="f4")
        fbo = self.ctx.framebuffer(color_attachments=[distance, color])
        self._set_scene(self._probe, scene)
        source.use(location=0)
        self._set(self._probe, "u_points", 0)
        fbo.use()
        self._probe_vao.render(moderngl.TRIANGLES, vertices=3)
        d = np.frombuffer(distance.read(), np.float32)[:n].copy()
        rgb = np.frombuffer(color.read(), np.float32).reshape(-1, 4)[:n, :3].copy()
        for obj in (fbo, source, distance, color):
            obj.release()
        return d, rgb

    # ------------------------------------------------------------------------------------- the editor's fields
    def _field_program(self, source: str, variant: str) -> tuple[object, object]:
        """The compiled program of an editor source for one variant ("sample", or "march:S:O" with the shadow and
        occlusion flags), cached; :class:`ShaderCompileError` for a source the compiler rejects.

        A new program is drawn once into one pixel: llvmpipe compiles (JITs) a program at its first draw, which
        costs more than most frames; drawing here keeps that cost in the compile time, not the first frame.
        """
        import moderngl

        key = (source, variant)
        cached = self._fields.get(key)
        if cached is not None:
            self._fields.move_to_end(key)
            return cached
        if variant == "sample":
            template = _source("field_sample.frag")
        else:
            _, shadows, occlusion = variant.split(":")
            template = _with_defines(
                self._raymarch_source,
                USER_FIELD=1,
                SHADOWS=int(shadows),
                OCCLUSION=int(occlusion),
                POLY_BLEND_ONLY=1,
            )
        try:
            prog = self.ctx.program(
                vertex_shader=self._fullscreen, fragment_shader=template + user_glsl(source)
            )
        except moderngl.Error as exc:
            raise ShaderCompileError.from_compiler(str(exc), source) from None
        vao = self.ctx.vertex_array(prog, [])
        # llvmpipe compiles a variant per framebuffer layout: warm with each layout the real draws use (the grid
        # pass's and the points pass's, or the ray-march's).
        layouts = [("f1", 4), ("f4", 4)] if variant == "sample" else [("f4", 1)]
        self.ctx.disable(moderngl.DEPTH_TEST)
        for second_dtype, second_components in layouts:
            first = (
                self.ctx.texture((1, 1), 1, dtype="f4")
                if variant == "sample"
                else self.ctx.texture((1, 1), 3, dtype="f1")
            )
            second = self.ctx.texture((1, 1), second_components, dtype=second_dtype)
            zbuffer = None if variant == "sample" else self.ctx.depth_renderbuffer((1, 1))
            warm = self.ctx.framebuffer(color_attachments=[first, second], depth_attachment=zbuffer)
            warm.use()
            vao.render(moderngl.TRIANGLES, vertices=3)
            warm.read(components=1, dtype="f4")  # wait for it
            for obj in (warm, first, second, *([] if zbuffer is None else [zbuffer])):
                obj.release()
        self._fields[key] = (prog, vao)
        while len(self._fields) > _FIELD_CACHE:
            _, (old_prog, old_vao) = self._fields.popitem(last=False)
            old_vao.release()  # pyright: ignore[reportAttributeAccessIssue]
            old_prog.release()  # pyright: ignore[reportAttributeAccessIssue]
        return prog, vao

    def compile_field(self, source: str, shading: Shading | None = None) -> None:
        """Check and compile an editor source (its sampling programs and the ray-march for ``shading``'s shadow and
        occlusion switches), or raise ValueError saying why and where."""
        check_source(source)
        shading = shading or Shading()
        self._field_program(source, "sample")
        self._field_program(source, f"march:{int(shading.shadows)}:{int(shading.occlusion)}")

    def probe_field(
        self, source: str, points: ArrayLike
    ) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
        """The editor's ``sdf`` and ``color`` at (N, 3) points: (N,) distances and (N, 3) colours, float32."""
        import moderngl

        check_source(source)
        pts = np.asarray(points, dtype=np.float32)
        if pts.ndim != 2 or pts.shape[1] != 3 or not np.all(np.isfinite(pts)) or len(pts) == 0:
            raise ValueError(f"points must be finite (N, 3) with N ≥ 1, got {pts.shape}")
        prog, vao = self._field_program(source, "sample")
        self._set(prog, "u_sample_points", 1)
        n = len(pts)
        width = min(n, _PROBE_WIDTH)
        height = -(-n // width)
        padded = np.zeros((width * height, 3), np.float32)
        padded[:n] = pts
        texture = self.ctx.texture((width, height), 3, padded.tobytes(), dtype="f4")
        texture.filter = (moderngl.NEAREST, moderngl.NEAREST)
        distance = self.ctx.texture((width, height), 1, dtype="f4")
        color = self.ctx.texture((width, height), 4, dtype="f4")
        fbo = self.ctx.framebuffer(color_attachments=[distance, color])
        texture.use(location=0)
        self._set(prog, "u_points", 0)
        fbo.use()
        vao.render(moderngl.TRIANGLES, vertices=3)  # pyright: ignore[reportAttributeAccessIssue]
        d = np.frombuffer(distance.read(), np.float32)[:n].copy()
        rgb = np.frombuffer(color.read(), np.float32).reshape(-1, 4)[:n, :3].copy()
        for obj in (fbo, texture, distance, color):
            obj.release()
        return d, rgb

    def sample_field(self, source: str, grid: sdf.Grid) -> NDArray[np.float32]:
        """The editor's ``sdf`` at every sample of ``grid``: (nx, ny, nz) float32 (m), sampled in GLSL.

        The samples are drawn as images of nx × (ny·slices) pixels, as many z slices a draw as fit in 8192 rows.
        """
        import moderngl

        check_source(source)
        prog, vao = self._field_program(source, "sample")
        self._set(prog, "u_sample_points", 0)
        nx, ny, nz = grid.shape
        slices = max(1, min(nz, _MAX_ROWS // ny))
        distance = self.ctx.texture((nx, ny * slices), 1, dtype="f4")
        color = self.ctx.texture(
            (nx, ny * slices), 4, dtype="f1"
        )  # a quarter of the points pass's bytes
        fbo = self.ctx.framebuffer(color_attachments=[distance, color])
        fbo.use()
        self._set(prog, "u_origin", tuple(float(v) for v in grid.origin))
        self._set(prog, "u_spacing", float(grid.spacing))
        self._set(prog, "u_ny", ny)
        out = np.empty((nz, ny, nx), np.float32)
        try:
            for z0 in range(0, nz, slices):
                count = min(slices, nz - z0)
                self._set(prog, "u_z0", z0)
                fbo.scissor = (0, 0, nx, ny * count)
                vao.render(moderngl.TRIANGLES, vertices=3)  # pyright: ignore[reportAttributeAccessIssue]
                block = np.frombuffer(distance.read(), np.float32).reshape(ny * slices, nx)
                out[z0 : z0 + count] = block[: ny * count].reshape(count, ny, nx)
        finally:
            for obj in (fbo, distance, color):
                obj.release()
        return np.ascontiguousarray(out.transpose(2, 1, 0))

    def render_field(
        self,
        source: str,
        bounds: ArrayLike,
        camera: Camera,
        width: int,
        height: int,
        shading: Shading | None = None,
    ) -> tuple[NDArray[np.uint8], NDArray[np.float32]]:
        """Ray-march the editor's field inside ``bounds`` ((2, 3) min and max corners, m), as :meth:`render` does.

        Returns:
            RGB (H, W, 3) uint8 and depth along the view axis (H, W) float32 (m), inf where a ray misses.
        """
        import moderngl

        _check_size(width, height)
        check_source(source)
        box = _check_bounds(bounds)
        shading = shading or Shading()
        prog, vao = self._field_program(
            source, f"march:{int(shading.shadows)}:{int(shading.occlusion)}"
        )
        self._set(prog, "u_field_lo", tuple(float(v) for v in box[0]))
        self._set(prog, "u_field_hi", tuple(float(v) for v in box[1]))
        self._set_camera(prog, camera, width, height, shading)
        fbo, color, depth = self._targets(width, height, shading)
        assert isinstance(fbo, moderngl.Framebuffer)
        fbo.scissor = _box_scissor(camera, box, width, height)
        self.ctx.disable(moderngl.DEPTH_TEST)
        vao.render(moderngl.TRIANGLES, vertices=3)  # pyright: ignore[reportAttributeAccessIssue]
        fbo.scissor = (0, 0, width, height)
        return self._read(color, depth, width, height)


_local = threading.local()


def renderer() -> Renderer:
    """This thread's renderer, created on first use (raises :class:`GLUnavailableError` without GL)."""
    existing = getattr(_local, "renderer", None)
    if existing is None:
        existing = Renderer()
        _local.renderer = existing
    return existing


def render(
    scene: sdf.Scene, camera: Camera, width: int, height: int, shading: Shading | None = None
) -> tuple[NDArray[np.uint8], NDArray[np.float32]]:
    """Ray-march ``scene`` with this thread's :class:`Renderer`: RGB (H, W, 3) uint8 and depth (H, W) float32."""
    return renderer().render(scene, camera, width, height, shading)


def mesh_glsl(source: str, resolution: int, bounds: ArrayLike) -> trimesh.Trimesh:
    """Mesh an editor source: its ``sdf`` sampled in GLSL on the marching-cubes grid, then marching cubes.

    The same text the ray-march runs, so what a person types appears meshed and ray-marched from one source.
    Runs on the process's one GL thread (:mod:`shaders.gl_service`).

    Args:
        source: GLSL defining ``float sdf(vec3 p)`` (m) and optionally ``vec3 color(vec3 p)`` (linear RGB), using
            ``sdf.glsl``'s primitives and operators; see :func:`check_source` for what is allowed.
        resolution: samples along the longest side of ``bounds``, 16..512.
        bounds: (2, 3) min and max corners (m).

    Returns:
        The zero level set with vertex colours from ``color`` (empty if no surface crosses the bounds).

    Raises:
        ValueError: a bad resolution or bounds, or (:class:`ShaderCompileError`) a source the checks or the
            compiler reject, with the compiler's message and the source line.
        GLUnavailableError: no OpenGL context on this machine.
    """
    from shaders import gl_service

    check_source(source)
    box = _check_bounds(bounds)
    grid = sdf.make_grid(
        sdf.default_scene(), resolution, box
    )  # the scene is unused when bounds are given

    def job(gl: Renderer) -> trimesh.Trimesh:
        field = gl.sample_field(source, grid)
        if not np.all(np.isfinite(field)):
            raise ShaderCompileError("sdf() returned NaN or infinity inside the bounds", None)
        # Marching cubes places vertices from the corners' values by linear interpolation, so a positive scale of
        # the field changes nothing but the kernel's level nudge (a thousandth of a voxel, in metres): a field far
        # from a distance (|∇d| not near 1, e.g. 100·sdf or 0.001·sdf) is scaled to one first, so K·sdf meshes as
        # sdf does.
        lipschitz = _lipschitz_estimate(field, grid.spacing)
        if math.isfinite(lipschitz) and (lipschitz > 1.5 or 0.0 < lipschitz < 0.5):
            field = (field / np.float32(lipschitz)).astype(np.float32)
        try:
            vertices, faces = sdf.mesh_samples(grid, field, _near_surface_mask(field, grid.spacing))
        except RuntimeError:  # scikit-image's "No surface found at the given iso value"
            vertices, faces = np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
        colors = gl.probe_field(source, vertices)[1] if len(vertices) else np.zeros((0, 3))
        return sdf.mesh_trimesh(vertices, faces, np.clip(colors.astype(np.float64), 0.0, 1.0))

    return gl_service.run(job)


def _near_surface_mask(field: NDArray[np.float32], spacing: float) -> NDArray[np.bool_]:
    """(nx, ny, nz) samples marking the cells marching cubes must visit: every cell whose eight corners change
    sign (or come within the kernel's level nudge of zero, which may move them across).

    Only the corners' signs are used, never how far they are from zero: a typed ``sdf`` need not be a distance
    bound (``3.0 * (length(p) - 1.0)`` grows three times as fast), and a threshold on |d| that assumed |∇d| ≤ 1
    skipped cells the surface crosses, leaving holes. scikit-image 0.2x reads a cell's flag at its upper corner
    (measured: flags at the lower corner lost half the faces); both corners are marked, so the mask does not hang
    on that detail.
    """
    eps = np.float32(sdf.ISO_NUDGE_VOXELS * spacing)
    lo = field
    hi = field
    for axis in range(3):
        head = [slice(None)] * 3
        tail = [slice(None)] * 3
        head[axis] = slice(None, -1)
        tail[axis] = slice(1, None)
        lo = np.minimum(lo[tuple(head)], lo[tuple(tail)])
        hi = np.maximum(hi[tuple(head)], hi[tuple(tail)])
    crossing = (lo < eps) & (hi > -eps)  # (nx-1, ny-1, nz-1) cells
    mask = np.zeros(field.shape, dtype=np.bool_)
    mask[:-1, :-1, :-1] = crossing
    mask[1:, 1:, 1:] |= crossing
    return mask


def _lipschitz_estimate(field: NDArray[np.float32], spacing: float) -> float:
    """The largest gradient norm of ``field`` by forward differences over its grid (field units per m), in slabs of
    float64 (no overflow for huge fields, a bounded extra memory)."""
    nx = field.shape[0]
    largest = 0.0
    for x0 in range(0, nx - 1, 32):
        x1 = min(nx, x0 + 33)
        slab = field[x0:x1].astype(np.float64)
        dx = np.diff(slab, axis=0)[:, :-1, :-1]
        dy = np.diff(slab, axis=1)[:-1, :, :-1]
        dz = np.diff(slab, axis=2)[:-1, :-1, :]
        largest = max(largest, float(np.sqrt(dx * dx + dy * dy + dz * dz).max(initial=0.0)))
    return largest / spacing


def examples() -> dict[str, str]:
    """The editor's example sources (``shaders/example_*.glsl``) by title (each file's first comment line)."""
    out: dict[str, str] = {}
    for path in sorted(SHADER_DIR.glob("example_*.glsl")):
        source = path.read_text(encoding="utf-8")
        title = source.split("\n", 1)[0].removeprefix("//").strip()
        out[title] = source
    return out
