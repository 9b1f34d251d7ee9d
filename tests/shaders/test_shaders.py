"""The GLSL against kernels/sdf: distances at points, ray-marched depth, mesh vs ray-march, and the shading terms.

These need an OpenGL 3.3 context (moderngl, EGL: Mesa llvmpipe without a GPU). Outside CI a missing context skips
with the renderer's reason; under CI=true it fails.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
import trimesh
from scipy import ndimage

from kernels import sdf
from shaders import renderer as gl_renderer
from shaders.renderer import Camera, GLUnavailableError, Renderer, Shading

FLAT = (math.cos(math.pi / 4), math.sin(math.pi / 4), 0.0, 0.0)  # local y → world z
NO_SHADOWS = Shading(shadows=False, occlusion=False)


def smooth_scene(blend: sdf.BlendForm = "poly") -> sdf.Scene:
    """Four primitives, smoothly united: rounded shapes and one small tilted box."""
    return sdf.Scene(
        (
            sdf.Primitive("sphere", (0, 0, 0.5), (0.45,), color=(0.9, 0.3, 0.3)),
            sdf.Primitive("capsule", (0.6, 0, 0.3), (0.3, 0.2), color=(0.3, 0.6, 0.9)),
            sdf.Primitive("torus", (0, 0, 0.1), (0.6, 0.12), rotation=FLAT, color=(0.9, 0.8, 0.3)),
            sdf.Primitive("box", (-0.5, 0.2, 0.5), (0.2, 0.2, 0.2), rotation=(0.9, 0.2, 0.3, 0.1)),
        ),
        k=0.3,
        blend=blend,
    )


def every_op_scene() -> sdf.Scene:
    return sdf.Scene(
        (
            sdf.Primitive("box", (0.1, 0, 0), (0.6, 0.5, 0.4), rotation=(0.8, 0.1, 0.5, 0.2), color=(1, 0, 0)),
            sdf.Primitive("sphere", (0.5, 0.2, 0.1), (0.4,), op="subtract", color=(0, 1, 0)),
            sdf.Primitive("torus", (0, 0, 0), (0.5, 0.2), rotation=FLAT, op="intersect", color=(0, 0, 1)),
            sdf.Primitive("capsule", (-0.4, 0, 0.3), (0.4, 0.15), rotation=(0.7, 0.7, 0, 0), color=(1, 1, 0)),
        ),
        k=0.2,
        blend="exp",
    )


CAMERAS = [
    Camera((3.0, -2.5, 2.0), (0, 0, 0.3), fov_y_rad=math.radians(40)),
    Camera((-2.0, -3.0, 0.8), (0, 0, 0.3), fov_y_rad=math.radians(40)),
    Camera((0.5, 0.8, 4.0), (0, 0, 0.3), up=(0, 1, 0), fov_y_rad=math.radians(40)),
]


def view_depth(camera: Camera, t: np.ndarray, directions: np.ndarray) -> np.ndarray:
    forward, _, _ = camera.basis()
    return t * (directions @ forward)


# ------------------------------------------------------------------------------------------ GLSL == numpy
def test_glsl_mirrors_the_kernel_name_for_name() -> None:
    source = (gl_renderer.SHADER_DIR / "sdf.glsl").read_text()
    glsl_functions = set(re.findall(r"^(?:float|vec2|vec3|vec4) (\w+)\(", source, flags=re.MULTILINE))
    public = {
        "sd_sphere",
        "sd_box",
        "sd_torus",
        "sd_capsule",
        "smin_poly",
        "smin_exp",
        "op_union",
        "op_subtract",
        "op_intersect",
        "smooth_union",
        "smooth_subtract",
        "smooth_intersect",
        "scene_distance",
        "scene_color",
    }
    assert public <= glsl_functions
    assert all(callable(getattr(sdf, name)) for name in public)


ALONE_SIZES: dict[sdf.PrimitiveKind, tuple[float, ...]] = {
    "sphere": (0.7,),
    "box": (0.3, 0.5, 0.7),
    "torus": (0.6, 0.2),
    "capsule": (0.5, 0.3),
    "cylinder": (0.5, 0.3),
    "round_box": (0.3, 0.5, 0.7),
    "octahedron": (0.7,),
    "cone": (0.5, 0.9),
    "hex_prism": (0.4, 0.6),
    "ellipsoid": (0.3, 0.5, 0.7),
}
"""Sizes of each built-in kind for a scene of that one primitive, tilted and off the origin."""


def test_every_built_in_kind_is_probed_alone() -> None:
    assert tuple(ALONE_SIZES) == sdf.BUILT_IN_KINDS


@pytest.mark.gl
@pytest.mark.parametrize(
    "scene",
    [
        pytest.param(sdf.default_scene(), id="default"),
        pytest.param(smooth_scene("exp"), id="smooth-exp"),
        pytest.param(every_op_scene(), id="every-op"),
        pytest.param(sdf.Scene(every_op_scene().primitives, k=0.0), id="hard"),
        *(
            pytest.param(
                sdf.Scene((sdf.Primitive(kind, (0.1, -0.2, 0.3), size, rotation=(0.6, 0.3, -0.5, 0.4)),)), id=kind
            )
            for kind, size in ALONE_SIZES.items()
        ),
        pytest.param("catalogue", id="catalogue"),
    ],
)
def test_glsl_scene_distance_and_color_match_numpy(gl: Renderer, scene: sdf.Scene | str) -> None:
    if scene == "catalogue":
        scene = catalogue_scene()
    assert isinstance(scene, sdf.Scene)
    points = np.random.default_rng(7).uniform(-1.6, 1.6, (5000, 3))
    distance, color = gl.probe(scene, points)
    np.testing.assert_allclose(distance, sdf.scene_distance(scene, points), atol=1e-5, rtol=0)
    np.testing.assert_allclose(color, sdf.scene_color(scene, points), atol=1e-5, rtol=0)


def catalogue_scene() -> sdf.Scene:
    """Four of the catalogue's kinds, smoothly combined (each op once)."""
    return sdf.Scene(
        (
            sdf.Primitive("round_box", (0, 0, 0.3), (0.5, 0.4, 0.3), color=(0.9, 0.3, 0.3)),
            sdf.Primitive("cylinder", (0.5, 0, 0.5), (0.4, 0.2), rotation=FLAT, op="subtract"),
            sdf.Primitive("octahedron", (-0.5, 0.1, 0.4), (0.45,), color=(0.2, 0.8, 0.3)),
            sdf.Primitive("cone", (0, -0.4, 0.7), (0.3, 0.6), rotation=FLAT, color=(0.2, 0.3, 0.9)),
        ),
        k=0.15,
    )


@pytest.mark.gl
@pytest.mark.parametrize(
    "scene", [sdf.default_scene(), every_op_scene(), "catalogue"], ids=["default", "every-op", "catalogue"]
)
def test_raymarched_depth_matches_numpy_sphere_tracer(gl: Renderer, scene: sdf.Scene | str) -> None:
    if scene == "catalogue":
        scene = catalogue_scene()
    assert isinstance(scene, sdf.Scene)
    camera = CAMERAS[0]
    _, depth = gl.render(scene, camera, 64, 64, NO_SHADOWS)
    origins, directions = gl_renderer.camera_rays(camera, 64, 64)
    t = sdf.sphere_trace(scene, origins, directions)
    expected = view_depth(camera, t, directions).reshape(64, 64)
    gl_hit, np_hit = np.isfinite(depth), np.isfinite(expected)
    assert gl_hit.sum() > 200  # the scene covers hundreds of pixels
    assert (gl_hit != np_hit).sum() <= 2  # at most a grazing ray or two differ in float32
    both = gl_hit & np_hit
    np.testing.assert_allclose(depth[both], expected[both], atol=2e-3)
    assert np.median(np.abs(depth[both] - expected[both])) < 2e-4


@pytest.mark.gl
def test_image_rows_start_at_the_top_and_x_points_right(gl: Renderer) -> None:
    camera = Camera((0, -5, 0), (0, 0, 0), up=(0, 0, 1), fov_y_rad=math.radians(40))
    scene = sdf.Scene(
        (
            sdf.Primitive("sphere", (1.0, 0, 0), (0.3,), color=(1, 0, 0)),  # right of the image
            sdf.Primitive("sphere", (0, 0, 1.0), (0.3,), color=(0, 0, 1)),  # top of the image
        ),
        k=0.0,
    )
    rgb, depth = gl.render(scene, camera, 64, 64, NO_SHADOWS)
    rows, cols = np.nonzero(np.isfinite(depth))
    red = rgb[rows, cols, 0] > rgb[rows, cols, 2]
    assert cols[red].mean() > 40 and abs(rows[red].mean() - 31.5) < 3
    assert rows[~red].mean() < 24 and abs(cols[~red].mean() - 31.5) < 3
    assert depth[rows, cols].min() == pytest.approx(5.0 - 0.3, abs=2e-3)


@pytest.mark.gl
@pytest.mark.parametrize(
    "camera",
    [
        Camera((0, -3, 0.3), (0, -10, 0.3)),  # the scene wholly behind the eye
        Camera((0, -1.0, 0.3), (0, -10, 0.3)),  # eye inside the bounding sphere, looking out
        Camera((0, -200, 0.3), (0, 0, 0.3), fov_y_rad=math.radians(2)),  # far away: a few pixels
    ],
    ids=["behind", "looking-out", "far"],
)
def test_off_screen_and_distant_scenes(gl: Renderer, camera: Camera) -> None:
    scene = sdf.default_scene()
    rgb, depth = gl.render(scene, camera, 48, 32, NO_SHADOWS)
    origins, directions = gl_renderer.camera_rays(camera, 48, 32)
    expected = view_depth(camera, sdf.sphere_trace(scene, origins, directions), directions).reshape(32, 48)
    np.testing.assert_array_equal(np.isfinite(depth), np.isfinite(expected))
    background = np.round(np.array(NO_SHADOWS.background) * 255)
    assert np.all(rgb[~np.isfinite(depth)] == background)


# ------------------------------------------------------------------------------------------ mesh vs ray-march
@pytest.mark.gl
@pytest.mark.parametrize("camera", CAMERAS, ids=["front", "side", "top"])
def test_mesh_agrees_with_raymarch(gl: Renderer, camera: Camera) -> None:
    """Silhouette IoU ≥ 0.99 at 64³ and mean depth difference ≤ 0.1 voxel away from silhouette edges."""
    scene = smooth_scene()
    vertices, faces, colors = sdf.mesh(scene, 64)
    voxel = sdf.make_grid(scene, 64).spacing
    _, marched = gl.render(scene, camera, 256, 256, NO_SHADOWS)
    _, rasterised = gl.render_mesh(vertices, faces, colors, camera, 256, 256)
    a, b = np.isfinite(marched), np.isfinite(rasterised)
    iou = (a & b).sum() / (a | b).sum()
    assert iou >= 0.99
    inner = np.asarray(ndimage.binary_erosion(a & b, iterations=1), dtype=bool)
    assert inner.sum() > 5000
    difference = np.abs(np.subtract(marched[inner], rasterised[inner], dtype=np.float64))
    assert difference.mean() <= 0.1 * voxel


@pytest.mark.gl
def test_edges_drawn_over_the_march_show_in_front_and_hide_behind_its_surface(gl: Renderer) -> None:
    # A box meshed coarsely, seen from above a corner: each edge's midpoint is classified by an independent pinhole
    # projection against the march's own depth at its pixel.
    scene = sdf.Scene((sdf.Primitive("box", (0.0, 0.0, 0.0), (0.5, 0.4, 0.3), color=(0.9, 0.8, 0.2)),))
    camera = Camera((1.8, -2.2, 1.6), (0.0, 0.0, 0.0), fov_y_rad=math.radians(45))
    width, height = 320, 240
    vertices, faces, _ = sdf.mesh(scene, 16)
    edges = trimesh.Trimesh(vertices, faces, process=False).edges_unique
    tolerance = 0.02
    marched, depth = gl.render(scene, camera, width, height, NO_SHADOWS)
    drawn = gl.draw_edges(vertices, edges, camera, width, height, tolerance_m=tolerance, color=(255, 0, 255))
    forward, right, up = camera.basis()
    tan = math.tan(camera.fov_y_rad / 2)

    def project(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Pixel column, row and depth along the view axis (m) of world points, by the pinhole camera."""
        rel = points - np.asarray(camera.position)
        z = rel @ forward
        col = np.floor(((rel @ right) / (z * tan * width / height) + 1.0) / 2.0 * width).astype(int)
        row = np.floor((1.0 - (rel @ up) / (z * tan)) / 2.0 * height).astype(int)
        return col, row, z

    col, row, z = project(0.5 * (vertices[edges[:, 0]] + vertices[edges[:, 1]]))
    surface = depth[row, col]
    magenta = (drawn[..., 0] > 200) & (drawn[..., 1] < 60) & (drawn[..., 2] > 200)
    near_line = np.asarray(ndimage.binary_dilation(magenta, iterations=1), dtype=bool)
    front = z <= surface + 0.5 * tolerance
    behind = z > surface + 0.1  # the far faces: a box's depth is 0.6-1.0 m through
    assert front.sum() > 100 and behind.sum() > 100
    assert near_line[row[front], col[front]].mean() > 0.95, "edges on the seen faces are not drawn"
    # Off the lines the picture is the march's, pixel for pixel.
    np.testing.assert_array_equal(drawn[~near_line], marched[~near_line])
    # The far faces' edges alone, away from the outline (whose edges a person does see), leave no pixel drawn.
    inside = np.asarray(ndimage.binary_erosion(np.isfinite(depth), iterations=3), dtype=bool)
    ends = [project(vertices[edges[:, k]]) for k in (0, 1)]
    hidden = behind & inside[row, col] & inside[ends[0][1], ends[0][0]] & inside[ends[1][1], ends[1][0]]
    assert hidden.sum() > 50
    gl.render(scene, camera, width, height, NO_SHADOWS)
    far_only = gl.draw_edges(vertices, edges[hidden], camera, width, height, tolerance_m=tolerance, color=(255, 0, 255))
    np.testing.assert_array_equal(far_only, marched)
    # A march of another size must come first; malformed edges are refused by name.
    with pytest.raises(ValueError, match="draw_edges needs a march of 100x100"):
        gl.draw_edges(vertices, edges, camera, 100, 100, tolerance_m=tolerance)
    with pytest.raises(ValueError, match="edges"):
        gl.draw_edges(vertices, edges + len(vertices), camera, width, height, tolerance_m=tolerance)
    with pytest.raises(ValueError, match="tolerance_m"):
        gl.draw_edges(vertices, edges, camera, width, height, tolerance_m=math.nan)


# ------------------------------------------------------------------------------------------ shading
def sphere_scene(color: tuple[float, float, float] = (0.8, 0.5, 0.2)) -> sdf.Scene:
    return sdf.Scene((sdf.Primitive("sphere", (0, 0, 0), (1.0,), color=color),))


@pytest.mark.gl
def test_phong_terms_match_the_analytic_sphere(gl: Renderer) -> None:
    camera = Camera((0, -4, 1), (0, 0, 0), fov_y_rad=math.radians(45))
    shading = Shading(ambient=0.15, diffuse=0.6, specular=0.4, shininess=20.0, shadows=False, occlusion=False)
    albedo = np.array([0.8, 0.5, 0.2])
    rgb, depth = gl.render(sphere_scene(tuple(albedo)), camera, 96, 96, shading)
    origins, directions = gl_renderer.camera_rays(camera, 96, 96)
    hit = np.isfinite(depth).ravel()
    # Analytic hit points and normals of the unit sphere, then the Phong sum.
    b = np.einsum("ij,ij->i", origins, directions)
    c = np.einsum("ij,ij->i", origins, origins) - 1.0
    t = -b - np.sqrt(np.maximum(b * b - c, 0.0))
    n = origins + t[:, None] * directions
    light = np.array(shading.light_direction) / np.linalg.norm(shading.light_direction)
    n_dot_l = np.maximum(n @ light, 0.0)
    r = 2 * (n @ light)[:, None] * n - light
    spec = np.where(n_dot_l > 0, np.maximum(np.einsum("ij,ij->i", r, -directions), 0.0) ** 20.0, 0.0)
    expected = 0.15 * albedo + 0.6 * albedo * n_dot_l[:, None] + 0.4 * spec[:, None]
    expected = np.clip(expected, 0, 1).reshape(96, 96, 3)
    got = rgb.astype(float) / 255
    inner = np.asarray(ndimage.binary_erosion(hit.reshape(96, 96), iterations=2), dtype=bool)
    assert inner.sum() > 2000
    assert np.abs(got[inner] - expected[inner]).max() < 4 / 255
    assert np.all(rgb[~hit.reshape(96, 96)] == np.round(np.array(shading.background) * 255))


@pytest.mark.gl
def test_soft_shadow_darkens_what_the_light_cannot_see(gl: Renderer) -> None:
    """A sphere hangs between the light (straight above) and a slab: the slab under it falls to ambient only."""
    scene = sdf.Scene(
        (
            sdf.Primitive("box", (0, 0, 0), (1.5, 1.5, 0.1), color=(0.7, 0.7, 0.7)),
            sdf.Primitive("sphere", (0, 0, 0.8), (0.35,), color=(0.7, 0.7, 0.7)),
        ),
        k=0.0,
    )
    camera = Camera((0, -3, 3), (0, 0, 0), fov_y_rad=math.radians(45))
    base = Shading(ambient=0.2, diffuse=0.8, specular=0.0, light_direction=(0, 0, 1), occlusion=False)
    lit, _ = gl.render(scene, camera, 96, 96, dataclass_replace(base, shadows=False))
    shadowed, depth = gl.render(scene, camera, 96, 96, base)
    origins, directions = gl_renderer.camera_rays(camera, 96, 96)
    forward, _, _ = camera.basis()
    points = origins + (depth.ravel() / (directions @ forward))[:, None] * directions
    on_slab = np.isfinite(depth.ravel()) & (np.abs(points[:, 2] - 0.1) < 0.01)
    radial = np.hypot(points[:, 0], points[:, 1])
    umbra = (on_slab & (radial < 0.2)).reshape(96, 96)
    open_slab = (on_slab & (radial > 0.9) & (radial < 1.3)).reshape(96, 96)
    assert umbra.sum() > 10 and open_slab.sum() > 50
    ambient_only = round(0.2 * 0.7 * 255)
    np.testing.assert_allclose(shadowed[umbra].astype(float), ambient_only, atol=3)
    np.testing.assert_allclose(lit[umbra].astype(float), round(1.0 * 0.7 * 255), atol=3)
    # Far from the sphere the shadow term is 1: shadows change nothing there.
    assert np.abs(shadowed[open_slab].astype(int) - lit[open_slab].astype(int)).max() <= 2


@pytest.mark.gl
def test_ambient_occlusion_darkens_creases_only(gl: Renderer) -> None:
    """AO scales the ambient term: unchanged on an open convex sphere, darker where a sphere meets a slab."""
    camera = Camera((0, -3.5, 1.2), (0, 0, 0.3), fov_y_rad=math.radians(45))
    ambient_only = Shading(ambient=1.0, diffuse=0.0, specular=0.0, shadows=False, occlusion=False)
    with_ao = dataclass_replace(ambient_only, occlusion=True)
    convex_plain, _ = gl.render(sphere_scene(), camera, 64, 64, ambient_only)
    convex_ao, hit_depth = gl.render(sphere_scene(), camera, 64, 64, with_ao)
    inner = np.asarray(ndimage.binary_erosion(np.isfinite(hit_depth), iterations=2), dtype=bool)
    assert np.abs(convex_ao[inner].astype(int) - convex_plain[inner].astype(int)).max() <= 1
    crease = sdf.Scene(
        (
            sdf.Primitive("box", (0, 0, 0), (1.5, 1.5, 0.1), color=(0.8, 0.8, 0.8)),
            sdf.Primitive("sphere", (0, 0, 0.55), (0.45,), color=(0.8, 0.8, 0.8)),
        ),
        k=0.0,
    )
    plain, depth = gl.render(crease, camera, 96, 96, ambient_only)
    occluded, _ = gl.render(crease, camera, 96, 96, with_ao)
    origins, directions = gl_renderer.camera_rays(camera, 96, 96)
    forward, _, _ = camera.basis()
    points = origins + (depth.ravel() / (directions @ forward))[:, None] * directions
    radial = np.hypot(points[:, 0], points[:, 1]).reshape(96, 96)
    near_contact = np.isfinite(depth) & (np.abs(points[:, 2].reshape(96, 96) - 0.1) < 0.01) & (radial < 0.25)
    assert near_contact.sum() > 5
    assert (occluded[near_contact].astype(int) - plain[near_contact].astype(int)).mean() < -40


def dataclass_replace(shading: Shading, **changes: object) -> Shading:
    import dataclasses

    return dataclasses.replace(shading, **changes)  # type: ignore[arg-type]


# ------------------------------------------------------------------------------------------ renderer edges
@pytest.mark.gl
def test_scene_changes_reuse_the_compiled_programs(gl: Renderer) -> None:
    # Each variant compiles on first use.
    gl.render(sdf.default_scene(), CAMERAS[0], 8, 8, NO_SHADOWS)
    gl.render(every_op_scene(), CAMERAS[0], 8, 8, NO_SHADOWS)
    programs = dict(gl._raymarch)
    first, _ = gl.render(sdf.default_scene(), CAMERAS[0], 32, 32, NO_SHADOWS)
    second, _ = gl.render(every_op_scene(), CAMERAS[0], 32, 32, NO_SHADOWS)
    assert not np.array_equal(first, second)
    assert gl._raymarch == programs


def test_missing_gl_context_says_why(monkeypatch: pytest.MonkeyPatch) -> None:
    import moderngl

    def refuse(**_kwargs: object) -> None:
        raise RuntimeError("eglInitialize failed")

    monkeypatch.setattr(moderngl, "create_standalone_context", refuse)
    with pytest.raises(GLUnavailableError, match=r"EGL.*eglInitialize failed.*mesh view works without it"):
        Renderer()


@pytest.mark.parametrize(
    ("make", "name"),
    [
        (lambda: Camera((0, 0, 0), (0, 0, 0)), "look_at"),
        (lambda: Camera((0, 0, 0), (0, 0, 1), up=(0, 0, 1)), "up"),
        (lambda: Camera((0, 0, float("nan")), (0, 0, 1)), "position"),
        (lambda: Camera((0, 0, 0), (1, 0, 0), fov_y_rad=3.5), "fov_y_rad"),
        (lambda: Shading(ambient=-1.0), "ambient"),
        (lambda: Shading(shininess=0.0), "shininess"),
        (lambda: Shading(light_direction=(0, 0, 0)), "light_direction"),
        (lambda: gl_renderer.camera_rays(CAMERAS[0], 0, 10), "width"),
    ],
)
def test_invalid_camera_and_shading(make, name: str) -> None:
    with pytest.raises(ValueError, match=name):
        make()
