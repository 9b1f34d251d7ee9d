"""A real browser: Chromium ticks the course mode, uploads a GPX through viser's upload button and plays it."""

from __future__ import annotations

import io
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import viser
from helpers.browser import canvas_is_not_blank, open_viser
from helpers.gpx import hill_gpx
from helpers.waiting import wait_until
from PIL import Image

from scenes.peloton import PelotonScene
from server.switcher import SceneSwitcher

pytestmark = pytest.mark.browser


def render(server: viser.ViserServer) -> np.ndarray:
    clients = list(server.get_clients().values())
    assert len(clients) == 1
    return np.asarray(clients[0].get_render(height=360, width=640, transport_format="png"))


def png(image: np.ndarray) -> bytes:
    buffer = io.BytesIO()
    Image.fromarray(image).save(buffer, format="PNG")
    return buffer.getvalue()


def test_upload_a_gpx_and_play_it(server: viser.ViserServer, browser_page: Any, tmp_path: Path) -> None:
    switcher = SceneSwitcher(server, "peloton")
    scene = switcher.scene
    assert isinstance(scene, PelotonScene)
    mode = scene.course_mode
    page = browser_page
    open_viser(page, server.get_port(), "/peloton/course_mode/route")

    page.get_by_text("Ride a course", exact=True).first.click()
    wait_until(lambda: mode.enabled and mode.state is not None, "course mode on", timeout_s=15.0)

    path = tmp_path / "browser_hill.gpx"
    path.write_bytes(hill_gpx("Browser hill", 1500))
    with page.expect_file_chooser() as chooser:
        page.get_by_text("Upload GPX", exact=True).first.click()
    chooser.value.set_files(str(path))
    wait_until(lambda: mode.route.name == "Browser hill", "the uploaded course", timeout_s=20.0)
    page.get_by_text("Browser hill", exact=False).first.wait_for(timeout=15_000)

    time.sleep(1.0)  # let the new geometry reach the canvas
    before = render(server)
    assert canvas_is_not_blank(png(before))
    with scene._lock:
        start = mode.leader_distance_m()
    # Fast forward, set on the server (its on_update and cleaning run).
    mode.controls["playback"].value = 300.0
    page.get_by_role("button", name="Play").first.click()
    wait_until(lambda: mode.leader_distance_m() > start + 500.0, "the riders to ride", timeout_s=20.0)
    page.get_by_role("button", name="Pause").first.click()
    wait_until(lambda: not mode.playing, "pause", timeout_s=10.0)
    time.sleep(0.5)
    after = render(server)
    # The riders moved on screen: part of the picture changed.
    changed = np.any(np.abs(after.astype(int) - before.astype(int)) > 30, axis=2)
    assert changed.mean() > 0.0005, f"only {changed.mean():.5f} of the pixels changed"

    # The profile chart shows the elevation line (brown) and the power line (red) in its canvas.
    chart = page.locator(".uplot", has_text="Elevation, speed and power along the course").first
    chart.scroll_into_view_if_needed(timeout=10_000)
    shot = np.asarray(Image.open(io.BytesIO(chart.screenshot())).convert("RGB")).astype(int)

    def has_colour(rgb: tuple[int, int, int]) -> bool:
        return bool(np.any(np.all(np.abs(shot - np.array(rgb)) < 40, axis=2)))

    assert has_colour((120, 90, 60)) and has_colour((220, 40, 40))
    # The page tells the person where the leader is.
    page.get_by_text("Leader at", exact=False).first.wait_for(timeout=10_000)
    switcher.close()


@pytest.mark.parametrize("viewport", [(1600, 1000), (1280, 720)], ids=["1600x1000", "1280x720"])
def test_the_course_chart_tick_labels_stay_inside_its_canvas(chromium_browser: Any, viewport: tuple[int, int]) -> None:
    from helpers.browser import (
        assert_chart_shows_its_data,
        assert_tick_labels_inside,
        scene_page,
        set_number,
        wait_chart_data,
    )

    title = "Elevation, speed and power along the course"
    with scene_page(chromium_browser, "peloton", viewport) as shown:
        scene = shown.scene
        assert isinstance(scene, PelotonScene)
        mode = scene.course_mode
        shown.page.get_by_text("Ride a course", exact=True).first.click()
        wait_until(lambda: mode.enabled and mode.state is not None, "course mode on", timeout_s=15.0)
        # The sample climb tops out at 1815 m: the "2,000" tick sits at the plot's top (its label was cut).
        with scene._lock:
            data = mode.chart.data
        wait_chart_data(shown.page, title, data)
        assert_chart_shows_its_data(shown.page, title, data)
        assert_tick_labels_inside(shown.page, title)
        # More power: the speed axis on the right reaches higher.
        before = float(np.max(data[2]))
        set_number(shown.page, "Course power (W)", 2000)
        wait_until(lambda: mode.params.power_w == 2000.0, "the course power", timeout_s=15.0)
        with scene._lock:
            data = mode.chart.data
        assert float(np.max(data[2])) > before + 10.0
        wait_chart_data(shown.page, title, data)
        assert_chart_shows_its_data(shown.page, title, data)
        assert_tick_labels_inside(shown.page, title)
