"""A real browser on a HiDPI screen, and one whose drawing resolution drops: framing works in CSS pixels.

viser 1.1.1's client reports its canvas in device pixels (``canvas.width``): twice the CSS size at a device pixel
ratio of 2, and 0.75–1 of it while its adaptive resolution drops on a slow machine. The control panel is a fixed
CSS width, so framing in device pixels put the peloton under the panel on a HiDPI screen (it framed for a window
twice as wide), and each resolution change moved the camera. The app sends each tab a script
(:data:`server.gate.CSS_CAMERA_JS`) that makes its camera report the CSS size. viser's "Reset View" puts the tab
back at the server's opening camera; the scene then frames it again.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
import viser
from helpers.browser import assert_in_view, close_notifications, served_scene, settle
from helpers.waiting import wait_until

from scenes.peloton import PelotonScene

pytestmark = pytest.mark.browser

VIEWPORT = (1280, 720)


def _canvas(page: Any) -> tuple[int, int]:
    """(device px width, CSS px width) of viser's canvas."""
    width, css = page.evaluate("() => [window.__viserMutable.canvas.width, window.__viserMutable.canvas.clientWidth]")
    return int(width), int(css)


@pytest.mark.parametrize("ratio", [1.0, 2.0])
def test_the_camera_reports_css_pixels_and_the_line_is_framed_clear_of_the_panel(
    server: viser.ViserServer, browser_page: Any, ratio: float
) -> None:
    page = browser_page
    cdp = page.context.new_cdp_session(page)
    cdp.send(
        "Emulation.setDeviceMetricsOverride",
        {"width": VIEWPORT[0], "height": VIEWPORT[1], "deviceScaleFactor": ratio, "mobile": False},
    )
    with served_scene(server, page, "peloton", viewport=VIEWPORT) as shown:
        scene = shown.scene
        assert isinstance(scene, PelotonScene)
        # The longest line: the last rider is the first to go under the panel.
        scene.controls["n_riders"].value = 8
        shown.open("/peloton")
        close_notifications(page)
        settle(shown)
        device, css = _canvas(page)
        assert css == VIEWPORT[0]
        assert device >= 0.7 * ratio * css  # the screen really is HiDPI (viser may draw at 0.75 of it)
        camera = shown.client_camera
        assert (camera.image_width, camera.image_height) == VIEWPORT
        with scene._lock:
            points = scene.line_points()
        assert_in_view(shown, "/peloton", points, f"the line at a pixel ratio of {ratio}")

        # viser's client drops its resolution while it draws slowly: the camera stays where it was framed.
        frames, position = scene.framing.frames, np.asarray(camera.position).copy()
        page.evaluate("() => window.__viserTestpoints.devSettings.set({ fixedDpr: 0.6 })")
        page.wait_for_function(
            f"() => Math.abs(window.__viserMutable.canvas.width - 0.6 * {VIEWPORT[0]}) <= 2", timeout=30_000
        )
        stamp = camera.update_timestamp
        page.evaluate("() => window.__viserMutable.sendCamera()")
        wait_until(lambda: camera.update_timestamp > stamp, "the camera report after the change")
        assert (camera.image_width, camera.image_height) == VIEWPORT
        assert scene.framing.frames == frames
        np.testing.assert_allclose(camera.position, position, atol=1e-6)

        # viser's own "Reset View" flies the tab to the server's opening camera: the scene frames it again.
        page.evaluate("() => window.__viserMutable.resetCameraPose(true)")
        wait_until(lambda: scene.framing.frames > frames, "the reset tab to be framed again")
        settle(shown)
        np.testing.assert_allclose(camera.position, position, atol=1e-3)
