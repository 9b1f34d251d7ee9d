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
    menu_test,
    node_box_corners,
    save_scene_screenshot,
    scene_page_fixture,
    screenshot,
)

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


# The failing input (an outside tester): "Smooth blend: a cylinder, an octahedron and a cor", 257 px of title in
# the Example menu's 223 px, at both window sizes.
test_every_menu_option_fits_its_menu = menu_test()
