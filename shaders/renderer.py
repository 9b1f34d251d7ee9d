"""A small offscreen renderer: ray-marches an SDF scene in GLSL and rasterises its mesh from the same camera.

It uses moderngl's standalone context on EGL: Mesa llvmpipe on a machine without a GPU, the GPU where there is one.
Programs are compiled once per :class:`Renderer`; the scene reaches ``sdf.glsl`` as uniforms, so moving or changing
a primitive never recompiles anything.

The camera is :mod:`shaders.camera`'s pinhole (:func:`camera_rays` gives its rays in numpy); the editor's sources
are checked by :mod:`shaders.glsl_sandbox`; ``sdf.glsl`` is completed from the kernel's primitive registry by
:mod:`shaders.glsl_library`. These names are re-exported here for callers of this module. Depth is
the distance along the view axis (m), ``inf`` where nothing is hit; the rasterised mesh uses the same convention,
so the two images compare pixel for pixel.

An EGL context lives on the thread that made it: use a :class:`Renderer` on the thread that created it (the
module-level :func:`render` keeps one per thread).
"""

from __future__ import annotations

import collections
import itertools
import math
import threading

import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray

from kernels import _checks, sdf
from shaders.camera import MAX_CAMERA_COORDINATE, Camera, Shading, camera_rays, check_image_size, screen_rectangle
from shaders.glsl_library import SHADER_DIR, read_source, sdf_library, with_defines
from shaders.glsl_sandbox import (
    DEFAULT_COLOR_GLSL,
    MAX_INLINED_TOKENS,
    MAX_SOURCE_CHARS,
    ShaderCompileError,
    check_field_bounds,
    check_source,
    examples,
    inlined_sizes,
    user_glsl,
)

__all__ = [
    "BLEND_CODE",
    "DEFAULT_COLOR_GLSL",
    "MAX_INLINED_TOKENS",
    "MAX_SOURCE_CHARS",
    "OP_CODE",
    "SHADER_DIR",
    "Camera",
    "GLUnavailableError",
    "Renderer",
    "ShaderCompileError",
    "Shading",
    "camera_rays",
    "check_source",
    "create_context",
    "examples",
    "inlined_sizes",
    "mesh_glsl",
    "render",
    "renderer",
    "sample_glsl",
    "slab_planes",
    "user_glsl",
]

OP_CODE: dict[str, int] = {"union": 0, "subtract": 1, "intersect": 2}
BLEND_CODE: dict[str, int] = {"poly": 0, "exp": 1}
_MISS = -1.0
"""Depth the shaders write where no surface is hit; read back as inf."""
_PROBE_WIDTH = 256
_FIELD_CACHE = 12
"""Editor programs kept compiled (a few sources × their variants)."""
_MAX_ROWS = 8192
"""Rows of one grid-sampling draw (GL_MAX_TEXTURE_SIZE is at least this on every driver we meet)."""
_FLOAT32_MAX = float(np.finfo(np.float32).max)
"""The largest float32 (3.4e38): GL's float, and the mesher's samples."""


class GLUnavailableError(RuntimeError):
    """No OpenGL 3.3 context could be created; the mesh side of the app keeps working without one."""


def _bounding_boxes(scene: sdf.Scene) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Oriented boxes whose union holds the scene: (P, 3) centres, (P, 3, 3) local-to-world rotations, (P, 3) half
    extents (m).

    Each primitive's box in its own frame (the torus's ring lies in the local xz plane, the capsule's axis is local
    y), grown by k/4 per smooth union and 1 mm: each union's blend lies at most k/4 below the smaller distance (poly:
    k·h(1 - h) ≤ k/4; exp: ln 2 / sharpness = k/4), and subtraction and intersection only raise the distance, so
    every point inside the scene lies within that reach of some primitive. (The spheres of
    :func:`kernels.sdf.scene_bounding_spheres` grow by k, the same bound with slack.) A flat torus's box is far
    thinner than its sphere, so fewer rays march beside the shape and miss.
    """
    half = np.array([sdf.primitive_spec(p.kind).half_extents(p.size) for p in scene.primitives])
    centers = np.array([p.center for p in scene.primitives], dtype=np.float64)
    rotations = np.array([sdf.rotation_matrix(p.rotation) for p in scene.primitives])
    unions = sum(prim.op == "union" for prim in scene.primitives[1:])
    return centers, rotations, half + unions * scene.k / 4 + 1e-3


def _bounds_scissor(camera: Camera, scene: sdf.Scene, width: int, height: int) -> tuple[int, int, int, int]:
    """(x, y, w, h) pixel rectangle (GL origin bottom left) holding the screen image of the bounding boxes.

    Conservative: the rectangle bounds the boxes' projected corners, widened by a pixel; if any corner lies near or
    behind the eye it is the whole image.
    """
    centers, rotations, half = _bounding_boxes(scene)
    unit = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=np.float64)
    corners = (centers[:, None, :] + np.einsum("pij,pcj->pci", rotations, half[:, None, :] * unit[None])).reshape(-1, 3)
    return screen_rectangle(camera, corners, width, height)


def _background_levels(shading: Shading) -> tuple[int, int, int]:
    """The background colour in 8-bit levels, as the images hold it."""
    red, green, blue = (int(np.clip(round(c * 255), 0, 255)) for c in shading.background)
    return red, green, blue


def _box_scissor(camera: Camera, box: NDArray[np.float64], width: int, height: int) -> tuple[int, int, int, int]:
    """:func:`_bounds_scissor` for one axis-aligned box (the editor's bounds)."""
    corners = np.array([[box[i, 0], box[j, 1], box[k, 2]] for i in (0, 1) for j in (0, 1) for k in (0, 1)])
    return screen_rectangle(camera, corners, width, height)


def _probe_points(points: ArrayLike) -> NDArray[np.float32]:
    """Points to probe as (N, 3) float32, or ValueError unless they are (N, 3) with N ≥ 1 and finite in float32 (a
    point so far that float32 squares of it overflow has the distance inf there, as in the kernel)."""
    pts = _checks.points("points", points)
    if len(pts) == 0 or not (np.abs(pts) <= _FLOAT32_MAX).all():
        raise ValueError(
            f"points must be (N, 3) with N ≥ 1, finite in float32, got {pts.shape} "
            f"of magnitude up to {np.abs(pts).max(initial=0.0):g}"
        )
    return pts.astype(np.float32)


def _drawable_scene(scene: object) -> sdf.Scene:
    """``scene`` when it is a :class:`kernels.sdf.Scene` whose bounds lie within
    ±:data:`~shaders.camera.MAX_CAMERA_COORDINATE` (the shaders' float32), else ``ValueError`` naming it."""
    checked = _checks.instance("scene", scene, sdf.Scene)
    box = sdf.scene_bounds(checked)
    if not (np.abs(box) <= MAX_CAMERA_COORDINATE).all():
        raise ValueError(
            f"scene must lie within ±{MAX_CAMERA_COORDINATE:g} m for the float32 shaders, got bounds {box.tolist()}"
        )
    return checked


def _shading(shading: object) -> Shading:
    """``shading``, or the defaults for None; ``ValueError`` naming it for anything else."""
    return Shading() if shading is None else _checks.instance("shading", shading, Shading, "a Shading or None")


def create_context() -> object:
    """A standalone OpenGL 3.3+ context on EGL, or :class:`GLUnavailableError` saying why not."""
    try:
        import moderngl
    except ImportError as exc:  # pragma: no cover - moderngl is a dependency
        raise GLUnavailableError(f"moderngl is not installed ({exc}); the reference image needs it") from exc
    try:
        # moderngl's stub types `backend` wrongly (as a dict); the runtime takes the backend's name.
        return moderngl.create_standalone_context(backend="egl", require=330)  # pyright: ignore[reportArgumentType]
    except Exception as exc:
        raise GLUnavailableError(
            "No OpenGL 3.3 context on EGL, so the GLSL reference image cannot be rendered "
            f"({type(exc).__name__}: {exc}). Install Mesa's EGL (Debian: libegl1 libgl1-mesa-dri) or run on a "
            "machine with a GPU driver; the mesh view works without it."
        ) from exc


def _mesh_arrays(
    vertices: ArrayLike, indices: ArrayLike, name: str, corners: int
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """(V, 3) float vertices and (N, ``corners``) int indices into them, or ValueError naming what is malformed."""
    v = _checks.points("vertices", vertices)
    if not (np.abs(v) <= MAX_CAMERA_COORDINATE).all():
        raise ValueError(
            f"vertices must be within ±{MAX_CAMERA_COORDINATE:g} m for float32, got {_checks.shown(vertices)}"
        )
    return v, _checks.indices(name, indices, corners, len(v))


class Renderer:
    """Compiled programs on one EGL context; use it on the thread that created it."""

    def __init__(self, builtin: bool = True) -> None:
        """``builtin=False`` skips compiling the app's own programs (for a trial of an editor source alone)."""
        import moderngl

        ctx = create_context()
        assert isinstance(ctx, moderngl.Context)
        self.ctx = ctx
        self.ctx.includes["sdf.glsl"] = sdf_library()
        self.ctx.includes["shading.glsl"] = read_source("shading.glsl")
        fullscreen = read_source("fullscreen.vert")
        # One program per (shadows, occlusion, polynomial blend only), compiled on first use and kept: under
        # llvmpipe a term switched off by a uniform would still be paid for, and the exponential blend's exp and log
        # cost as much as the rest of the scene, so poly and hard scenes use a program without them.
        self._raymarch_source = read_source("raymarch.frag")
        self._fullscreen = read_source("fullscreen.vert")
        self._raymarch: dict[tuple[bool, bool, bool, bool], object] = {}
        self._raymarch_vao: dict[tuple[bool, bool, bool, bool], object] = {}
        self._fields: collections.OrderedDict[tuple[str, str], tuple[object, object]] = collections.OrderedDict()
        """Compiled editor programs by (source, variant), least recently used first."""
        self._field_gradients: collections.OrderedDict[tuple[str, bytes], float] = collections.OrderedDict()
        """What each editor field is divided by to march, by (source, bounds' bytes): its largest gradient where
        :func:`mesh_glsl` measured one far from 1 (a field that is not a distance), least recently used first."""
        self.renderer_name = str(self.ctx.info.get("GL_RENDERER", "unknown"))
        self._target_size: tuple[int, int] | None = None
        self._target_objects: list = []
        if not builtin:
            return
        for shadows, occlusion in ((True, True), (False, False)):  # the gallery's opening variants
            self._raymarch_program((shadows, occlusion, True, False))
        self._probe = self.ctx.program(
            vertex_shader=fullscreen, fragment_shader=with_defines(read_source("probe.frag"), EXTRA_KINDS=1)
        )
        self._mesh = self.ctx.program(vertex_shader=read_source("mesh.vert"), fragment_shader=read_source("mesh.frag"))
        self._edges = self.ctx.program(
            vertex_shader=read_source("edges.vert"), fragment_shader=read_source("edges.frag")
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
                fragment_shader=with_defines(
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
        center, size, color = (np.zeros((n, 3), np.float32), np.zeros((n, 3), np.float32), np.zeros((n, 3), np.float32))
        rotation = np.tile(np.eye(3, dtype=np.float32), (n, 1, 1))
        for i, prim in enumerate(scene.primitives):
            kind[i], op[i] = sdf.primitive_spec(prim.kind).code, OP_CODE[prim.op]
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
        self, scene: sdf.Scene, camera: Camera, width: int, height: int, shading: Shading | None = None
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

        scene = _drawable_scene(scene)
        _checks.instance("camera", camera, Camera)
        check_image_size(width, height)
        shading = _shading(shading)
        # sdf.glsl's smin_blend uses the polynomial form for hard scenes (k = 0) whatever the blend.
        variant = (
            shading.shadows,
            shading.occlusion,
            scene.blend == "poly" or scene.k == 0.0,
            any(not sdf.primitive_spec(p.kind).fused for p in scene.primitives),
        )
        prog, vao = self._raymarch_program(variant)
        self._set_scene(prog, scene)
        return self._march(prog, vao, camera, width, height, shading, _bounds_scissor(camera, scene, width, height))

    def _march(
        self,
        prog: object,
        vao: object,
        camera: Camera,
        width: int,
        height: int,
        shading: Shading,
        scissor: tuple[int, int, int, int],
    ) -> tuple[NDArray[np.uint8], NDArray[np.float32]]:
        """Draw a ray-march program (its scene or field already set) into fresh targets and read them back; only
        the pixels in ``scissor`` run the shader (llvmpipe pays for every pixel)."""
        import moderngl

        self._set_camera(prog, camera, width, height, shading)
        fbo, color, depth = self._targets(width, height, shading)
        assert isinstance(fbo, moderngl.Framebuffer)
        fbo.scissor = scissor
        self.ctx.disable(moderngl.DEPTH_TEST)
        vao.render(moderngl.TRIANGLES, vertices=3)  # pyright: ignore[reportAttributeAccessIssue]
        fbo.scissor = (0, 0, width, height)
        return self._read(color, depth, width, height)

    def _set_camera(self, prog: object, camera: Camera, width: int, height: int, shading: Shading) -> None:
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

    def _set_mesh_camera(self, prog: object, v: NDArray[np.float64], camera: Camera, width: int, height: int) -> None:
        """The projection, eye and view axis of a program that rasterises (V, 3) world points ``v`` (m): near and
        far planes that hold them all."""
        eye = np.asarray(camera.position, dtype=np.float64)
        forward, _, _ = camera.basis()
        reach = float(np.linalg.norm(v - eye, axis=1).max()) if len(v) else 1.0
        near, far = max(1e-3, 1e-3 * reach), 2.0 * reach + 1.0
        self._write(prog, "u_view_projection", camera.view_projection(width / height, near, far).T.astype("f4"))
        self._set(prog, "u_eye", tuple(float(x) for x in eye))
        self._set(prog, "u_forward", tuple(float(x) for x in forward))

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

        _checks.instance("camera", camera, Camera)
        check_image_size(width, height)
        shading = _shading(shading)
        v, f = _mesh_arrays(vertices, faces, "faces", 3)
        c = _checks.finite_array("colors", colors)
        if c.shape != v.shape:
            raise ValueError(f"colors must match vertices' shape {v.shape}, got {c.shape}")
        normals = (trimesh.Trimesh(v, f, process=False).vertex_normals if len(f) else np.zeros_like(v)).astype(
            np.float32
        )
        prog = self._mesh
        self._set_shading(prog, shading)
        self._set_mesh_camera(prog, v, camera, width, height)
        _, color, depth = self._targets(width, height, shading)
        if len(f):
            interleaved = np.concatenate([v.astype(np.float32), normals, c.astype(np.float32)], axis=1)
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

    def draw_edges(
        self,
        vertices: ArrayLike,
        edges: ArrayLike,
        camera: Camera,
        width: int,
        height: int,
        *,
        tolerance_m: float,
        color: tuple[int, int, int] = (40, 40, 40),
    ) -> NDArray[np.uint8]:
        """Draw a mesh's edges as 1 px lines over the image the last :meth:`render` or :meth:`render_field` of this
        size left, each pixel of an edge hidden where it lies more than ``tolerance_m`` behind the marched surface.

        The wireframe of the "both" view: where the mesh and the ray-march agree, the edges hug the marched surface.
        Drawn here, into the marched image, the browser draws one picture instead of ~10⁴ lines, which a software
        WebGL renderer draws at a few frames per second.

        Args:
            vertices: (V, 3) world positions (m).
            edges: (E, 2) vertex indices, each edge once.
            camera: the camera of the last march.
            width, height: its image size (px).
            tolerance_m: how far (m) an edge may lie behind the surface and still show: at least the sag of a chord
                under a curved surface, about a mesh edge's length.
            color: the lines' sRGB colour (0-255).

        Returns:
            RGB (H, W, 3) uint8, row 0 at the top: the marched image with the edges drawn over it.

        Raises:
            ValueError: ``vertices``/``edges`` malformed, ``tolerance_m`` not finite and non-negative, or no march of
                this size came before.
        """
        import moderngl

        _checks.instance("camera", camera, Camera)
        check_image_size(width, height)
        v, e = _mesh_arrays(vertices, edges, "edges", 2)
        tolerance = _checks.non_negative("tolerance_m", tolerance_m)
        levels = np.asarray(color)
        if levels.shape != (3,) or levels.dtype.kind not in "iu" or not ((levels >= 0) & (levels <= 255)).all():
            raise ValueError(f"color must be 3 integers in 0..255, got {_checks.shown(color)}")
        if self._target_size != (width, height):
            raise ValueError(f"draw_edges needs a march of {width}x{height} before it, got {self._target_size}")
        _, color_only, _, color_tex, depth_tex, _ = self._target_objects
        assert isinstance(color_only, moderngl.Framebuffer)
        assert isinstance(color_tex, moderngl.Texture) and isinstance(depth_tex, moderngl.Texture)
        if len(e):
            prog = self._edges
            self._set_mesh_camera(prog, v, camera, width, height)
            self._set(prog, "u_tolerance", tolerance)
            # sRGB levels are what the marched image holds: the lines are written as they should read.
            self._set(prog, "u_color", tuple(float(c) / 255.0 for c in color))
            self._set(prog, "u_depth", 0)
            depth_tex.use(location=0)
            vbo = self.ctx.buffer(np.ascontiguousarray(v, dtype=np.float32).tobytes())
            ibo = self.ctx.buffer(np.ascontiguousarray(e, dtype=np.int32).tobytes())
            vao = self.ctx.vertex_array(prog, [(vbo, "3f", "in_position")], index_buffer=ibo)
            color_only.use()
            self.ctx.disable(moderngl.DEPTH_TEST)
            vao.render(moderngl.LINES)
            for obj in (vao, vbo, ibo):
                obj.release()
        return np.frombuffer(color_tex.read(), np.uint8).reshape(height, width, 3)[::-1].copy()

    def probe(self, scene: sdf.Scene, points: ArrayLike) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
        """Evaluate ``scene_distance`` and ``scene_color`` of ``sdf.glsl`` at points (via a float texture).

        Args:
            scene: the scene.
            points: (N, 3) world points (m).

        Returns:
            (N,) distances (m) and (N, 3) colours, float32, computed by the GLSL.
        """
        pts = _probe_points(points)
        self._set_scene(self._probe, _drawable_scene(scene))
        return self._draw_probe(self._probe, self._probe_vao, pts)

    def _draw_probe(
        self, prog: object, vao: object, pts: NDArray[np.float32]
    ) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
        """Draw a probing program (its scene or source already set) once per point, read from a float texture:
        (N,) distances and (N, 3) colours, float32."""
        import moderngl

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
        source.use(location=0)
        self._set(prog, "u_points", 0)
        fbo.use()
        vao.render(moderngl.TRIANGLES, vertices=3)  # pyright: ignore[reportAttributeAccessIssue]
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
            template = read_source("field_sample.frag")
        else:
            _, shadows, occlusion = variant.split(":")
            template = with_defines(
                self._raymarch_source, USER_FIELD=1, SHADOWS=int(shadows), OCCLUSION=int(occlusion), POLY_BLEND_ONLY=1
            )
        try:
            prog = self.ctx.program(vertex_shader=self._fullscreen, fragment_shader=template + user_glsl(source))
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

    def remember_field_gradient(self, source: str, bounds: NDArray[np.float64], gradient: float) -> None:
        """Keep what :meth:`render_field` divides ``source``'s field by in ``bounds`` (see there): the shader divides
        by its square root twice, so a slope over float32's range (a ±3e38 step) is kept whole."""
        key = (source, np.asarray(bounds, dtype=np.float64).tobytes())
        self._field_gradients[key] = gradient
        self._field_gradients.move_to_end(key)
        while len(self._field_gradients) > _FIELD_CACHE:
            self._field_gradients.popitem(last=False)

    def compile_field(self, source: str, shading: Shading | None = None) -> None:
        """Check and compile an editor source (its sampling programs and the ray-march for ``shading``'s shadow and
        occlusion switches), or raise ValueError saying why and where."""
        check_source(source)
        shading = _shading(shading)
        self._field_program(source, "sample")
        self._field_program(source, f"march:{int(shading.shadows)}:{int(shading.occlusion)}")

    def probe_field(self, source: str, points: ArrayLike) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
        """The editor's ``sdf`` and ``color`` at (N, 3) points: (N,) distances and (N, 3) colours, float32."""
        check_source(source)
        pts = _probe_points(points)
        prog, vao = self._field_program(source, "sample")
        self._set(prog, "u_sample_points", 1)
        return self._draw_probe(prog, vao, pts)

    def sample_field(self, source: str, grid: sdf.Grid, planes: tuple[int, int] | None = None) -> NDArray[np.float32]:
        """The editor's ``sdf`` at every sample of ``grid``, or of its z planes ``planes`` = (first, end): (nx, ny, n)
        float32 (m), n the planes sampled, in GLSL.

        The samples are drawn as images of nx × (ny·slices) pixels, as many z slices a draw as fit in 8192 rows
        (:func:`slab_planes`).
        """
        import moderngl

        check_source(source)
        prog, vao = self._field_program(source, "sample")
        self._set(prog, "u_sample_points", 0)
        nx, ny, nz = grid.shape
        first, end = (0, nz) if planes is None else planes
        if not 0 <= first < end <= nz:
            raise ValueError(f"planes must lie within the grid's {nz} z planes, got {planes!r}")
        slices = slab_planes(grid)
        distance = self.ctx.texture((nx, ny * slices), 1, dtype="f4")
        color = self.ctx.texture((nx, ny * slices), 4, dtype="f1")  # a quarter of the points pass's bytes
        fbo = self.ctx.framebuffer(color_attachments=[distance, color])
        fbo.use()
        self._set(prog, "u_origin", tuple(float(v) for v in grid.origin))
        self._set(prog, "u_spacing", float(grid.spacing))
        self._set(prog, "u_ny", ny)
        out = np.empty((end - first, ny, nx), np.float32)
        try:
            for z0 in range(first, end, slices):
                count = min(slices, end - z0)
                self._set(prog, "u_z0", z0)
                fbo.scissor = (0, 0, nx, ny * count)
                vao.render(moderngl.TRIANGLES, vertices=3)  # pyright: ignore[reportAttributeAccessIssue]
                block = np.frombuffer(distance.read(), np.float32).reshape(ny * slices, nx)
                out[z0 - first : z0 - first + count] = block[: ny * count].reshape(count, ny, nx)
        finally:
            for obj in (fbo, distance, color):
                obj.release()
        return np.ascontiguousarray(out.transpose(2, 1, 0))

    def render_field(
        self, source: str, bounds: ArrayLike, camera: Camera, width: int, height: int, shading: Shading | None = None
    ) -> tuple[NDArray[np.uint8], NDArray[np.float32]]:
        """Ray-march the editor's field inside ``bounds`` ((2, 3) min and max corners, m), as :meth:`render` does.

        A field :func:`mesh_glsl` has meshed in these bounds and found far from a distance (its largest gradient
        outside [0.5, 1.5], e.g. 1e30·sdf or 1e-6·sdf) is marched divided by that gradient, as it is meshed: a
        sphere tracer's steps are the field's values, so 1e30·sdf overshot every surface and 1e-6·sdf stopped short.

        Returns:
            RGB (H, W, 3) uint8 and depth along the view axis (H, W) float32 (m), inf where a ray misses.
        """

        _checks.instance("camera", camera, Camera)
        check_image_size(width, height)
        check_source(source)
        box = check_field_bounds(bounds)
        shading = _shading(shading)
        prog, vao = self._field_program(source, f"march:{int(shading.shadows)}:{int(shading.occlusion)}")
        self._set(prog, "u_field_lo", tuple(float(v) for v in box[0]))
        self._set(prog, "u_field_hi", tuple(float(v) for v in box[1]))
        self._set(prog, "u_field_root", math.sqrt(self._field_gradients.get((source, box.tobytes()), 1.0)))
        return self._march(prog, vao, camera, width, height, shading, _box_scissor(camera, box, width, height))


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
    # Checked before the renderer is made, so a bad argument is named even where GL is missing.
    _drawable_scene(scene)
    _checks.instance("camera", camera, Camera)
    check_image_size(width, height)
    _shading(shading)
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
            compiler reject, with the compiler's message and the source line, or whose ``sdf`` is not finite
            inside the bounds or ``color`` not finite on the surface.
        GLUnavailableError: no OpenGL context on this machine.
    """
    from shaders import gl_service

    check_source(source)
    box = check_field_bounds(bounds)
    grid = sdf.make_grid(sdf.default_scene(), resolution, box)  # the scene is unused when bounds are given
    field = sample_glsl(source, grid)
    if not np.all(np.isfinite(field)):
        raise ShaderCompileError("sdf() returned NaN or infinity inside the bounds", None)
    outside = field > 0.0
    if not outside.any() or outside.all():  # one side everywhere (0 is inside; 0 everywhere was meshed as a blob)
        return sdf.mesh_trimesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64), np.zeros((0, 3)))
    # Marching cubes places vertices from the corners' values by linear interpolation, so a positive scale of the
    # field changes nothing but the kernel's level nudge (a thousandth of a voxel, in metres): a field steeper than a
    # distance outside its shape (the march would overshoot), or far flatter (0.001·sdf: it would crawl), is scaled
    # to one first, so K·sdf meshes and marches as sdf does. An exact distance measures 1.01–1.06 (the differences'
    # error), and is divided by that: a few per cent more steps.
    lipschitz = lipschitz_estimate(field, grid.spacing)
    far = math.isfinite(lipschitz) and (lipschitz > 1.0 or 0.0 < lipschitz < 0.5)
    if far and lipschitz <= _FLOAT32_MAX:
        field = (field / np.float32(lipschitz)).astype(np.float32)
    elif far:  # over float32's range (3e38·sdf; a ±3e38 step): in two steps, as its cast overflowed to a field of ±0
        root = np.float32(math.sqrt(lipschitz))
        field = (field / root / root).astype(np.float32)
    gradient = lipschitz if far else 1.0
    gl_service.run(lambda gl: gl.remember_field_gradient(source, box, gradient))
    try:  # on the caller's thread: the GL thread serves other callers meanwhile
        # Cell centres beside samples on the zero level are read from the source itself (whether the solid has
        # volume there); the field's positive scale above changes no sign.
        def distance_at(points: NDArray[np.float64]) -> NDArray[np.float32]:
            return gl_service.run(lambda gl: gl.probe_field(source, points)[0])

        vertices, faces = sdf.mesh_samples(grid, field, _near_surface_mask(field, grid.spacing), distance_at)
    except RuntimeError:  # scikit-image's "No surface found at the given iso value"
        vertices, faces = np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
    colors = gl_service.run(lambda gl: gl.probe_field(source, vertices)[1]) if len(vertices) else np.zeros((0, 3))
    if not np.all(np.isfinite(colors)):
        raise ShaderCompileError("color() returned NaN or infinity on the surface", None)
    return sdf.mesh_trimesh(vertices, faces, np.clip(colors.astype(np.float64), 0.0, 1.0))


def slab_planes(grid: sdf.Grid) -> int:
    """How many z planes of ``grid`` one sampling draw covers: as many as fit in 8192 rows of ny each."""
    _nx, ny, nz = grid.shape
    return max(1, min(nz, _MAX_ROWS // ny))


def sample_glsl(source: str, grid: sdf.Grid) -> NDArray[np.float32]:
    """An editor source's ``sdf`` at every sample of ``grid``: (nx, ny, nz) float32 (m), sampled in GLSL on the
    process's one GL thread (:mod:`shaders.gl_service`) one draw's slab of z planes (:func:`slab_planes`) at a time.

    Other callers' GL work (another gallery tab's frame) runs between the slabs: a field that is costly to evaluate,
    sampled whole, held every other tab's frames for as long as it took (4.6 s for a nine-level chain at 256³).
    """
    from shaders import gl_service

    nz, step = grid.shape[2], slab_planes(grid)
    slabs = [
        gl_service.run(lambda gl, first=first: gl.sample_field(source, grid, (first, min(first + step, nz))))
        for first in range(0, nz, step)
    ]
    return np.concatenate(slabs, axis=2)


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


JUMP_RATIO = 1.3
"""A cell's difference quotient over this times its parent's (at twice the spacing) is a jump's, not a slope's."""


def lipschitz_estimate(field: NDArray[np.float32], spacing: float) -> float:
    """The steepest slope of ``field`` outside its shape (field units per m): the largest gradient norm by forward
    differences over the grid's cells with a corner outside (``field > 0``), leaving out jumps.

    Only the outside counts: a march runs there, and meshing only scales by it. Inside, a bound may be steep without
    harm (Quilez's ellipsoid bound is singular at its centre: its quotient grew from 3.8 to 12 as the grid went from
    48 to 160 samples a side, and the Elongation example was marched up to 12 times too slowly).

    A jump (the value steps between two neighbouring samples: ``p.x > 1.2 ? 0.2 : length(p) - 1.0``) is not a slope:
    its quotient doubles each time the spacing halves, and dividing the field by it made a valid distance bound march
    short everywhere (a sphere drawn at 74 % of its area). A cell whose quotient is over :data:`JUMP_RATIO` times its
    parent's, the cell of the grid at twice the spacing that holds it, is left out; a slope, seen at both spacings, is
    not. Where no cell is left, the largest over jumps and inside. Computed in slabs of float64 (no overflow for huge
    fields, a bounded extra memory).
    """
    slope = _steepest(field, leave_out_jumps=True)
    return (slope if slope > 0.0 else _steepest(field, leave_out_jumps=False)) / spacing


def _steepest(field: NDArray[np.float32], *, leave_out_jumps: bool) -> float:
    """The largest forward-difference norm of ``field`` per sample spacing: over its cells with a corner outside,
    jumps left out (see :func:`lipschitz_estimate`), or over every cell."""
    largest = 0.0
    for x0 in range(0, field.shape[0] - 1, 32):  # even starts: a slab's every other sample is the coarse grid's
        slab = field[x0 : x0 + 33].astype(np.float64)
        fine = _difference_norms(slab)
        if not leave_out_jumps:
            largest = max(largest, float(fine.max(initial=0.0)))
            continue
        coarse = 0.5 * _difference_norms(slab[::2, ::2, ::2])  # per fine spacing
        if coarse.size:  # an even grid's last cells have no whole parent: they take their neighbours' (edge padding)
            coarse = np.pad(coarse, [(0, 1)] * 3, mode="edge")
        else:  # a slab of one cell (or a grid of two samples a side): no coarser grid to tell a jump by
            coarse = np.full((1, 1, 1), np.inf)
        counted = _any_corner(slab > 0.0)
        for parity in itertools.product((0, 1), repeat=3):  # the fine cells of each parity have one parent each
            cells = tuple(slice(start, None, 2) for start in parity)
            mine = fine[cells]
            parent = coarse[: mine.shape[0], : mine.shape[1], : mine.shape[2]]
            counted[cells] &= mine <= JUMP_RATIO * np.broadcast_to(parent, mine.shape)
        largest = max(largest, float(np.max(fine, where=counted, initial=0.0)))
    return largest


def _any_corner(samples: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """(nx − 1, ny − 1, nz − 1) whether any of each cell's eight corner samples is true."""
    for axis in range(3):
        head, tail = [slice(None)] * 3, [slice(None)] * 3
        head[axis], tail[axis] = slice(None, -1), slice(1, None)
        samples = samples[tuple(head)] | samples[tuple(tail)]
    return samples


def _difference_norms(samples: NDArray[np.float64]) -> NDArray[np.float64]:
    """(nx − 1, ny − 1, nz − 1) the norm of each cell's forward differences of ``samples`` (value per spacing)."""
    dx = np.diff(samples, axis=0)[:, :-1, :-1]
    dy = np.diff(samples, axis=1)[:-1, :, :-1]
    dz = np.diff(samples, axis=2)[:-1, :-1, :]
    return np.sqrt(dx * dx + dy * dy + dz * dz)
