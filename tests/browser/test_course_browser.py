"""A real browser: Chromium ticks the course mode and its chart's tick labels stay inside its canvas, at 1600×1000 and
1280×720, before and after more power. (Uploading a GPX and playing it is in ``test_interactions_browser.py``.)"""

from __future__ import annotations

import numpy as np
import pytest
from helpers.browser import (
    ScenePage,
    assert_chart_shows_its_data,
    assert_tick_labels_inside,
    scene_page_fixture,
    set_number,
    wait_chart_data,
)
from helpers.waiting import wait_until

from scenes.peloton import PelotonScene

pytestmark = pytest.mark.browser


shown = scene_page_fixture("peloton")


def test_the_course_chart_tick_labels_stay_inside_its_canvas(shown: ScenePage) -> None:
    title = "Elevation, speed and power along the course"
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
