"""A real browser: Chromium opens the SDF gallery, shows the mesh in view and clear of the panel with no error text at
1600×1000 and 1280×720. (The reference image and a typed shape are in ``test_interactions_browser.py``.)"""

from __future__ import annotations

import numpy as np
import pytest
from helpers.browser import (
    ScenePage,
    assert_in_view,
    assert_seen,
    error_text,
    node_box_corners,
    save_scene_screenshot,
    scene_page_fixture,
    screenshot,
)
from helpers.waiting import wait_until

pytestmark = [pytest.mark.browser, pytest.mark.gl]

MESH = "/sdf/mesh"


shown = scene_page_fixture("sdf", gl=True)


def test_the_mesh_is_in_view_clear_of_the_panel(shown: ScenePage) -> None:
    corners = node_box_corners(shown.page, MESH)
    assert np.all(np.isfinite(corners)), "no mesh on the page"
    image = screenshot(shown.page)
    xy = assert_in_view(shown, MESH, corners, "the mesh's bounding box")
    assert_seen(shown, image, [MESH], xy, "the mesh")
    assert error_text(shown.page) == []
    save_scene_screenshot(shown, "sdf")


TITLE_WIDTHS = """
([label, titles]) => {
  const rows = [...document.querySelectorAll('label')].filter(e => e.textContent.trim() === label);
  if (rows.length !== 1) return null;
  let row = rows[0];
  while (row && !row.querySelector('input:not([type=hidden])')) row = row.parentElement;
  const input = row.querySelector('input:not([type=hidden])');
  const style = getComputedStyle(input);
  const pen = document.createElement('canvas').getContext('2d');
  pen.font = `${style.fontWeight} ${style.fontSize} ${style.fontFamily}`;
  const room = input.clientWidth - parseFloat(style.paddingLeft) - parseFloat(style.paddingRight);
  return [room, titles.map(title => pen.measureText(title).width)];
}
"""
"""The room for text in the input labelled ``label`` (CSS px) and the width each of ``titles`` takes in its font."""


def test_every_example_title_fits_its_menu(shown: ScenePage) -> None:
    """The Example menu shows the whole title of whichever example is picked: "Smooth blend: a cylinder, an
    octahedron and a cor" was cut off at both window sizes."""
    from scenes.sdf_gallery import SdfGalleryScene
    from scenes.sdf_gallery.editor import EXAMPLES

    scene = shown.scene
    assert isinstance(scene, SdfGalleryScene)
    shape = scene.view_controls["shape_source"]
    shape.value = "GLSL editor"  # the editor's folders show with it
    try:
        wait_until(lambda: shown.page.evaluate(TITLE_WIDTHS, ["Example", []]) is not None, "the Example menu")
        room, widths = shown.page.evaluate(TITLE_WIDTHS, ["Example", list(EXAMPLES)])
    finally:
        shape.value = "Primitives (panels below)"
    assert room > 100.0
    too_wide = {title: round(width) for title, width in zip(EXAMPLES, widths, strict=True) if width > room}
    assert not too_wide, (round(room), too_wide)
