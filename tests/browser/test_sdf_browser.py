"""A real browser: Chromium opens the SDF gallery, shows the mesh in view and clear of the panel with no error text at
1600×1000 and 1280×720, and shows the GLSL reference image the server made."""

from __future__ import annotations

import time
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
import viser
from helpers.browser import (
    VIEWPORTS,
    ScenePage,
    assert_in_view,
    assert_seen,
    error_text,
    node_box_corners,
    open_viser,
    save_scene_screenshot,
    scene_page,
    screenshot,
)
from helpers.ci import need_gl

from scenes.sdf_gallery import SdfGalleryScene
from server.switcher import SceneSwitcher

pytestmark = [pytest.mark.browser, pytest.mark.gl]

MESH = "/sdf/mesh"


@pytest.fixture(scope="module", params=VIEWPORTS, ids=lambda v: f"{v[0]}x{v[1]}")
def shown(request: pytest.FixtureRequest, chromium_browser: Any) -> Iterator[ScenePage]:
    need_gl()  # the process's one GL context (made here if not yet)
    with scene_page(chromium_browser, "sdf", request.param) as page:
        yield page


def test_the_mesh_is_in_view_clear_of_the_panel(shown: ScenePage) -> None:
    corners = node_box_corners(shown.page, MESH)
    assert np.all(np.isfinite(corners)), "no mesh on the page"
    image = screenshot(shown.page)
    xy = assert_in_view(shown, MESH, corners, "the mesh's bounding box")
    assert_seen(shown, image, [MESH], xy, "the mesh")
    assert error_text(shown.page) == []
    save_scene_screenshot(shown, "sdf")


READ_IMAGE = """
([w, h]) => {
    const img = [...document.querySelectorAll('img')].find(
        i => i.complete && i.naturalWidth === w && i.naturalHeight === h);
    if (!img) return null;
    const canvas = document.createElement('canvas');
    canvas.width = w; canvas.height = h;
    const ctx = canvas.getContext('2d');
    ctx.drawImage(img, 0, 0);
    return Array.from(ctx.getImageData(0, 0, w, h).data);
}
"""


def test_browser_shows_the_mesh_and_the_reference_image(server: viser.ViserServer, browser_page: Any) -> None:
    need_gl()
    switcher = SceneSwitcher(server, "sdf")
    scene = switcher.scene
    assert isinstance(scene, SdfGalleryScene)
    page = browser_page
    try:
        open_viser(page, server.get_port(), "/sdf/mesh")

        # The 3D view shows the mesh: the sphere's red and the box's blue are on the canvas (once the page has
        # drawn the full mesh: a render taken as the page opens can catch it on its way; CI saw 198 blue px).
        clients = list(server.get_clients().values())
        assert len(clients) == 1
        deadline = time.monotonic() + 60
        while True:
            render = clients[0].get_render(height=360, width=480)
            rgb = np.asarray(render)[..., :3].astype(int)
            reddish = (rgb[..., 0] > rgb[..., 2] + 60) & (rgb[..., 0] > 120)
            bluish = (rgb[..., 2] > rgb[..., 0] + 60) & (rgb[..., 2] > 120)
            if (reddish.sum() > 200 and bluish.sum() > 200) or time.monotonic() > deadline:
                break
            time.sleep(0.5)
        assert reddish.sum() > 200 and bluish.sum() > 200, (reddish.sum(), bluish.sum())

        # The reference panel shows the ray-marched image, pixel for pixel as the server rendered it.
        deadline = time.monotonic() + 60
        while scene.reference_rgb is None and time.monotonic() < deadline:
            time.sleep(0.05)
        assert scene.reference_rgb is not None
        # The browser may move its camera once more (a re-render); wait until the page and the server agree.
        shown = None
        while time.monotonic() < deadline:
            expected = scene.reference_rgb
            height, width = expected.shape[:2]
            handle = page.wait_for_function(f"({READ_IMAGE})([{width}, {height}])", timeout=30_000, polling=200)
            shown = np.asarray(handle.json_value(), dtype=np.uint8).reshape(height, width, 4)[..., :3]
            if np.array_equal(shown, scene.reference_rgb):
                break
            time.sleep(0.2)
        assert shown is not None and scene.reference_rgb is not None
        np.testing.assert_array_equal(shown, scene.reference_rgb)
        height, width = shown.shape[:2]
        object_pixels = (np.abs(shown.astype(int) - shown[0, 0].astype(int)).sum(axis=2) > 30).sum()
        assert object_pixels > 0.02 * width * height  # the object, not just background
    finally:
        switcher.close()


OCTAHEDRON = (
    "float sdf(vec3 p) {\n    return sd_octahedron(p - vec3(0.0, 0.0, 0.4), 0.7);\n}\n"
    "vec3 color(vec3 p) {\n    return vec3(0.1, 0.85, 0.2);\n}\n"
)


def green_mask(png: bytes) -> np.ndarray:
    import io

    from PIL import Image

    rgb = np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)
    # Green over red and blue by a ratio, so the shaded underside (dark green) counts too.
    green = rgb[..., 1]
    return (green > 20) & (green - np.maximum(rgb[..., 0], rgb[..., 2]) > 0.3 * green)


def wait_for_green(page: Any, pixels: int = 5000, timeout_s: float = 30.0) -> np.ndarray:
    """Screenshots until the green shape shows (the picture a person sees), its mask."""
    deadline = time.monotonic() + timeout_s
    mask = green_mask(page.screenshot())
    while mask.sum() < pixels and time.monotonic() < deadline:
        time.sleep(0.2)
        mask = green_mask(page.screenshot())
    return mask


def test_typed_shape_is_meshed_and_ray_marched_in_the_main_view(server: viser.ViserServer, browser_page: Any) -> None:
    from kernels import sdf

    need_gl()
    switcher = SceneSwitcher(server, "sdf")
    scene = switcher.scene
    assert isinstance(scene, SdfGalleryScene)
    page = browser_page
    try:
        page.set_viewport_size({"width": 1600, "height": 1000})
        open_viser(page, server.get_port(), "/sdf/mesh")
        page.locator('text="GLSL editor" >> visible=true').first.click()  # the folder, not the About text
        editor = page.locator("textarea").filter(has_text="sdf(vec3 p)").first
        editor.fill(OCTAHEDRON)
        page.get_by_role("button", name="Apply").click()
        deadline = time.monotonic() + 60
        while scene.editor_serial == 0 and time.monotonic() < deadline:
            time.sleep(0.05)
        assert scene.editor_serial == 1 and scene.params.editor.source == OCTAHEDRON.strip("\n") + "\n"
        # Meshed: every vertex on the octahedron the person typed.
        d = sdf.sd_octahedron(scene.mesh_vertices - [0.0, 0.0, 0.4], 0.7)
        assert len(d) > 500 and np.abs(d).max() < 0.02
        assert not any(g.visible for g in scene.gizmos)
        mesh_green = wait_for_green(page)
        assert mesh_green.sum() > 5000  # the green octahedron fills a good part of the view

        # Ray-marched: the same green shape, now from the shader, with the mesh hidden.
        page.locator("input[value='Mesh']").first.click()
        page.get_by_role("option", name="Ray-marched").click()
        page.wait_for_function("() => !window.__viserMutable.nodeRefFromName['/sdf/mesh'].visible", timeout=30_000)
        deadline = time.monotonic() + 60
        # The frame at rest: the canvas's width (at least 640 px; a moving frame is 320).
        while time.monotonic() < deadline and not (scene.view_rgb is not None and scene.view_rgb.shape[1] >= 640):
            time.sleep(0.05)
        assert scene.view_rgb is not None and scene.view_rgb.shape[1] >= 640
        marched_green = wait_for_green(page)
        assert marched_green.sum() > 5000
        overlap = (mesh_green & marched_green).sum() / (mesh_green | marched_green).sum()
        assert overlap > 0.8, f"mesh and ray-march silhouettes overlap {overlap:.2f}"
        page.screenshot(path="/tmp/sdf_browser_raymarched.png")
    finally:
        switcher.close()
