"""The primitive registry: one table (kernels/sdf/primitives.py) feeds the kernel, the gallery's menus, the
renderer's codes and the GLSL dispatch; registering a kind with its two formulas is all a new primitive needs.

The GL tests need an OpenGL 3.3 context (EGL: Mesa llvmpipe without a GPU); outside CI a missing one skips.
"""

from __future__ import annotations

import math
import re
import typing
from collections.abc import Iterator

import numpy as np
import pytest
import viser
from helpers.ci import fresh_renderer
from helpers.paths import GLSL
from helpers.scenes import MakeScene
from helpers.waiting import wait_until
from helpers.wsclient import BrowserClient
from scipy import ndimage

from kernels import sdf
from scenes.sdf_gallery import params as gallery_params
from shaders import glsl_library
from shaders import renderer as gl_renderer
from shaders.renderer import Camera, Renderer, Shading

OCTAHEDRON_BOUND_GLSL = GLSL / "sd_octahedron_bound.glsl"
NO_SHADOWS = Shading(shadows=False, occlusion=False)
CAMERA = Camera((2.2, -2.6, 1.6), (0.1, 0.0, 0.1), fov_y_rad=math.radians(40))


def sd_octahedron_bound(p: np.ndarray, size: float) -> np.ndarray:
    """(|x| + |y| + |z| − size)/√3 (Quilez, "Octahedron - bound (not exact)"): a 1-Lipschitz bound."""
    return (np.abs(p).sum(axis=1) - size) / math.sqrt(3.0)


def octahedron_bound_spec() -> sdf.PrimitiveSpec:
    return sdf.PrimitiveSpec(
        kind=typing.cast(sdf.PrimitiveKind, "octahedron_bound"),
        label="Octahedron (bound)",
        code=max(s.code for s in sdf.PRIMITIVES.values()) + 1,
        sizes=(("size", "m"),),
        distance=lambda p, s: sd_octahedron_bound(p, s[0]),
        bounding_radius=lambda s: s[0],
        half_extents=lambda s: (s[0], s[0], s[0]),
        glsl_function="sd_octahedron_bound",
        glsl_arguments="p, s.x",
        glsl_file=OCTAHEDRON_BOUND_GLSL,
    )


@pytest.fixture
def octahedron_bound() -> Iterator[sdf.PrimitiveSpec]:
    spec = octahedron_bound_spec()
    sdf.register_primitive(spec)
    try:
        yield spec
    finally:
        sdf.unregister_primitive(spec.kind)


def extra_scene() -> sdf.Scene:
    kind = typing.cast(sdf.PrimitiveKind, "octahedron_bound")
    return sdf.Scene(
        (
            sdf.Primitive(kind, (0.0, 0.0, 0.1), (0.7,), rotation=(0.9, 0.1, 0.3, 0.2)),
            sdf.Primitive("sphere", (0.5, 0.0, 0.4), (0.3,), color=(0.9, 0.3, 0.3)),
        ),
        k=0.15,
    )


# ------------------------------------------------------------------------------------------ one table
def test_registry_lists_the_built_in_kinds_in_code_order() -> None:
    assert sdf.PRIMITIVE_KINDS == (
        "sphere", "box", "torus", "capsule", "cylinder", "round_box", "octahedron", "cone", "hex_prism", "ellipsoid"
    )  # fmt: skip
    assert tuple(sdf.PRIMITIVES) == sdf.PRIMITIVE_KINDS
    assert [s.code for s in sdf.PRIMITIVES.values()] == list(range(len(sdf.PRIMITIVES)))
    assert [s.kind for s in sdf.PRIMITIVES.values() if s.fused] == ["sphere", "box", "torus", "capsule"]
    for spec in sdf.PRIMITIVES.values():
        assert 1 <= spec.size_count <= 3
        assert all(unit == "m" for _, unit in spec.sizes)


def test_gallery_menus_come_from_the_registry() -> None:
    assert list(gallery_params.kind_labels().values()) == list(sdf.PRIMITIVE_KINDS)
    assert list(gallery_params.kind_labels()) == [s.label for s in sdf.PRIMITIVES.values()]
    assert [gallery_params.sizes_used(kind) for kind in sdf.PRIMITIVE_KINDS] == [1, 3, 2, 2, 2, 3, 1, 2, 2, 3]
    note = gallery_params.size_meaning()
    assert "Torus: a = major radius, b = tube radius (ring in the local xz plane)." in note
    assert "Hexagonal prism: a = centre to flat side, b = half height along local z." in note


def test_a_kind_registered_after_the_gallery_was_imported_is_in_its_menus_and_meshed(
    octahedron_bound: sdf.PrimitiveSpec, server: viser.ViserServer, show_scene: MakeScene
) -> None:
    # The gallery's kind menu was read once, when its module was imported: a kind registered afterwards never
    # reached it. It is read each time a gallery is built now, and so is the note of what each kind's sizes are.
    from scenes.sdf_gallery.scene import SdfGalleryScene

    scene = show_scene(SdfGalleryScene)
    menu = scene.slot_controls[1]["kind"]
    assert isinstance(menu, viser.GuiDropdownHandle)
    assert "Octahedron (bound)" in menu.options
    assert "Octahedron (bound): a = size." in scene.size_note.content
    with BrowserClient(server.get_port()) as client:
        client.wait_for_gui("P2 kind")
        client.set_value("P2 kind", "Octahedron (bound)")
        wait_until(
            lambda: scene.mesh_scene is not None and scene.mesh_scene.primitives[1].kind == octahedron_bound.kind,
            "a mesh with the registered kind",
        )
    assert scene.gizmo_labels[1].text == "P2 octahedron"


def test_glsl_codes_and_dispatch_match_the_registry() -> None:
    library = glsl_library.sdf_library()
    defines = dict(re.findall(r"^#define KIND_(\w+) (\d+)$", library, flags=re.MULTILINE))
    assert list(defines) == [s.kind.upper() for s in sdf.PRIMITIVES.values()]
    assert [int(c) for c in defines.values()] == [s.code for s in sdf.PRIMITIVES.values()]
    functions = set(re.findall(r"^(?:float|vec2|vec3|vec4) (\w+)\(", library, flags=re.MULTILINE))
    for spec in sdf.PRIMITIVES.values():
        assert spec.glsl_function in functions, spec.kind
        # The same sd_* in numpy: its unchecked formula, _sd_* (a scene's local points need no re-checking).
        assert spec.distance.__code__.co_names[0].removeprefix("_") == spec.glsl_function
    dispatch = re.findall(r"kind == KIND_(\w+)\) return (\w+)\(", library)
    catalogue = [s for s in sdf.PRIMITIVES.values() if not s.fused]
    assert dispatch == [(s.kind.upper(), s.glsl_function) for s in catalogue[:-1]]
    assert f"return {catalogue[-1].glsl_function}(" in library


def test_registering_checks_the_entry(octahedron_bound: sdf.PrimitiveSpec) -> None:
    with pytest.raises(ValueError, match="already registered"):
        sdf.register_primitive(octahedron_bound)
    with pytest.raises(ValueError, match="built in"):
        sdf.unregister_primitive("sphere")
    with pytest.raises(ValueError, match="kind must be one of"):
        sdf.Primitive(typing.cast(sdf.PrimitiveKind, "pyramid"), (0, 0, 0), (1.0,))


# ------------------------------------------------------------------------------------------ a new kind
def test_a_registered_kind_is_evaluated_and_meshed(octahedron_bound: sdf.PrimitiveSpec) -> None:
    kind = octahedron_bound.kind
    prim = sdf.Primitive(kind, (0.2, -0.1, 0.3), (0.5,))
    rng = np.random.default_rng(7)
    points = rng.uniform(-1.0, 1.0, (500, 3))
    np.testing.assert_allclose(prim.distance(points), sd_octahedron_bound(points - prim.center, 0.5), atol=1e-12)
    vertices, faces, _ = sdf.mesh(sdf.Scene((prim,)), 48)
    assert len(faces) > 1000
    voxel = sdf.make_grid(sdf.Scene((prim,)), 48).spacing
    assert np.abs(prim.distance(vertices)).max() < 0.05 * voxel
    assert np.abs(vertices - prim.center).sum(axis=1).max() == pytest.approx(0.5, abs=voxel)


@pytest.fixture
def gl_with_extra(octahedron_bound: sdf.PrimitiveSpec) -> Iterator[Renderer]:
    del octahedron_bound  # registered before the renderer loads sdf.glsl
    with fresh_renderer() as renderer:
        yield renderer


@pytest.mark.gl
def test_a_registered_kind_is_ray_marched_to_the_kernels_surface(gl_with_extra: Renderer) -> None:
    scene = extra_scene()
    rng = np.random.default_rng(3)
    points = rng.uniform(-1.0, 1.0, (400, 3))
    d_gl, _ = gl_with_extra.probe(scene, points)
    np.testing.assert_allclose(d_gl, sdf.scene_distance(scene, points), atol=1e-5)

    _, depth = gl_with_extra.render(scene, CAMERA, 64, 64, NO_SHADOWS)
    origins, directions = gl_renderer.camera_rays(CAMERA, 64, 64)
    forward, _, _ = CAMERA.basis()
    t = sdf.sphere_trace(scene, origins, directions)
    expected = (t * (directions @ forward)).reshape(64, 64)
    gl_hit, np_hit = np.isfinite(depth), np.isfinite(expected)
    assert gl_hit.sum() > 200
    assert (gl_hit != np_hit).sum() <= 2
    both = gl_hit & np_hit
    np.testing.assert_allclose(depth[both], expected[both], atol=2e-3)

    vertices, faces, colors = sdf.mesh(scene, 64)
    voxel = sdf.make_grid(scene, 64).spacing
    _, marched = gl_with_extra.render(scene, CAMERA, 128, 128, NO_SHADOWS)
    _, rasterised = gl_with_extra.render_mesh(vertices, faces, colors, CAMERA, 128, 128)
    a, b = np.isfinite(marched), np.isfinite(rasterised)
    assert (a & b).sum() / (a | b).sum() >= 0.98
    inner = np.asarray(ndimage.binary_erosion(a & b, iterations=1), dtype=bool)
    difference = np.abs(np.subtract(marched[inner], rasterised[inner], dtype=np.float64))
    assert difference.mean() <= 0.2 * voxel
