"""A real browser: Chromium opens the app, the scene renders, and a mouse drag on the speed slider changes power."""

from __future__ import annotations

import io
import time
from typing import Any

import pytest
import viser
from browser import canvas_is_not_blank, open_viser
from PIL import Image

from scenes.peloton import PelotonScene
from scenes.switcher import SceneSwitcher

pytestmark = pytest.mark.browser


def test_drag_speed_slider_with_the_mouse(server: viser.ViserServer, browser_page: Any) -> None:
    switcher = SceneSwitcher(server, "peloton")
    scene = switcher.scene
    assert isinstance(scene, PelotonScene)
    page = browser_page
    open_viser(page, server.get_port(), "/peloton/course/riders_body")

    # The canvas shows the scene, not a blank page.
    clients = list(server.get_clients().values())
    assert len(clients) == 1
    render = clients[0].get_render(height=360, width=640, transport_format="png")
    buffer = io.BytesIO()
    Image.fromarray(render).save(buffer, format="PNG")
    assert canvas_is_not_blank(buffer.getvalue())

    before_speed = scene.params.speed_kmh
    before_power = float(scene.state.power.total[0])
    label = page.get_by_text("Speed (km/h)", exact=True).first
    row = label.locator("xpath=ancestor::*[.//*[@role='slider']][1]")
    thumb = row.locator("[role='slider']").first
    box = thumb.bounding_box()
    assert box is not None
    x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    page.mouse.move(x, y)
    page.mouse.down()
    for step in range(1, 11):
        page.mouse.move(x + 4 * step, y)
    page.mouse.up()

    # Wait until the drag's messages have all been handled: the speed has moved and then held still.
    end = time.monotonic() + 15.0
    last, still_since = before_speed, time.monotonic()
    while time.monotonic() < end:
        with scene._lock:
            speed = scene.params.speed_kmh
        if speed != last:
            last, still_since = speed, time.monotonic()
        elif speed != before_speed and time.monotonic() - still_since > 0.5:
            break
        time.sleep(0.05)
    with scene._lock:
        final_speed = scene.params.speed_kmh
        final_power = float(scene.state.power.total[0])
    assert final_speed > before_speed
    assert final_power > before_power
    # The page shows the server's new value in the slider's number box.
    page.wait_for_function(
        "v => [...document.querySelectorAll('[role=slider]')].some(e => Number(e.getAttribute('aria-valuenow')) === v)",
        arg=final_speed,
        timeout=10_000,
        polling=100,
    )
    switcher.close()
