"""A real browser looks at the peloton: the line in view and clear of the panel, the chart's curves drawn, no error
text, at 1600×1000 and 1280×720; a typed rider count and speed change the picture where they should. (The mouse
drag on the speed slider is in ``test_interactions_browser.py``.)"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from helpers.browser import (
    NumberChange,
    ScenePage,
    assert_chart_draws,
    assert_chart_fits_after,
    assert_in_view,
    assert_seen,
    chart_image,
    error_text,
    line_mask,
    panel_rect,
    save_scene_screenshot,
    scene_page_fixture,
    screenshot,
    set_number,
    settle,
    with_labels_hidden,
)
from helpers.waiting import wait_until

from scenes.peloton import COMPONENT_COLOURS, LABEL_PX, PelotonScene

pytestmark = pytest.mark.browser

RIDERS = [f"/peloton/course/riders_{part}" for part in ("body", "bike", "head")]
BARS = [f"/peloton/course/bars_{c}" for c in COMPONENT_COLOURS]
CHART = "Solo power vs speed (cube law)"
NOW_RED = (220, 30, 30)
CHART_COLOURS = {
    "aero": COMPONENT_COLOURS["aero"],
    "rolling": COMPONENT_COLOURS["rolling"],
    "climbing": COMPONENT_COLOURS["climbing"],
    "total": (0, 0, 0),
    "solo now": NOW_RED,
}


shown = scene_page_fixture("peloton")


def _look_at_the_line(shown: ScenePage) -> None:
    scene = shown.scene
    assert isinstance(scene, PelotonScene)
    image = screenshot(shown.page)
    with scene._lock:
        points = scene.line_points()
        n = scene.params.n_riders
    xy = assert_in_view(shown, "/peloton", points, f"the line of {n} riders, bars and labels")
    assert_seen(
        shown,
        with_labels_hidden(shown.page),
        RIDERS + BARS,
        xy,
        f"{n} riders and their bars",
        without_labels=True,
    )
    # Every label (drawn at its anchor, extending right and up) lies inside the page and left of the panel, and
    # there is dark text there.
    with scene._lock:
        anchors = np.array([scene.labels[i].position for i in range(n)], dtype=np.float64)
    corners = assert_in_view(shown, "/peloton/course", anchors, "label anchors")
    reach_x, reach_y = LABEL_PX
    left, _, _, _ = panel_rect(shown.page)
    assert corners[:, 0].max() + reach_x <= left and corners[:, 1].min() - reach_y >= 0, corners
    # No two labels' boxes overlap where the page's own camera puts them.
    for i in range(n):
        for j in range(i + 1, n):
            (xi, yi), (xj, yj) = corners[i], corners[j]
            assert abs(xi - xj) >= reach_x or abs(yi - yj) >= reach_y, (
                f"labels {i} and {j} overlap at ({xi:.0f}, {yi:.0f}) and ({xj:.0f}, {yj:.0f})"
            )
    for x, y in corners:
        box = image[max(int(y) - 40, 0) : int(y) + 10, int(x) - 10 : int(x + reach_x)]
        assert np.count_nonzero(box.max(axis=-1) < 120) > 10, f"no label text near ({x:.0f}, {y:.0f})"


def test_the_line_is_in_view_clear_of_the_panel(shown: ScenePage) -> None:
    _look_at_the_line(shown)
    save_scene_screenshot(shown, "peloton")


def test_the_chart_draws_every_curve(shown: ScenePage) -> None:
    assert_chart_draws(shown.page, CHART, CHART_COLOURS)


def test_no_error_text_on_the_page(shown: ScenePage) -> None:
    assert error_text(shown.page) == []


def test_eight_riders_far_apart_stay_in_view(shown: ScenePage) -> None:
    scene = shown.scene
    set_number(shown.page, "Riders", 8)
    set_number(shown.page, "Gap (m)", 6)
    wait_until(lambda: scene.params.n_riders == 8 and scene.params.gap_m == 6.0, "8 riders, 6 m apart")
    settle(shown)
    _look_at_the_line(shown)
    assert error_text(shown.page) == []


def test_more_speed_lifts_the_now_line_and_the_bars(shown: ScenePage) -> None:
    scene = shown.scene

    def red_row() -> float:
        rows = np.nonzero(line_mask(chart_image(shown.page, CHART), NOW_RED))[0]
        assert len(rows) > 20
        return float(np.median(rows))

    before_row = red_row()
    with scene._lock:
        top_before = scene.line_points()[:, 2].max()
    frames = scene.framing.frames
    set_number(shown.page, "Speed (km/h)", 55)
    wait_until(lambda: scene.params.speed_kmh == 55.0, "the speed to reach the scene")
    # The taller bars outgrow the view, so the scene frames the camera again: wait for that, then for the page.
    wait_until(lambda: scene.framing.frames > frames, "the camera to be framed for the taller bars")
    settle(shown)
    # The solo power's level line rose (screen y grows downward) and the bars grew: still all in view.
    assert red_row() < before_row - 5
    with scene._lock:
        assert scene.line_points()[:, 2].max() > top_before
    _look_at_the_line(shown)
    assert_chart_draws(shown.page, CHART, CHART_COLOURS)


def test_the_chart_tick_labels_stay_inside_its_canvas(shown: ScenePage) -> None:
    assert isinstance(shown.scene, PelotonScene)

    def over_ten_kilowatts(data: Any) -> None:
        assert max(float(np.max(series)) for series in data[1:]) > 10_000.0

    # A bigger rider into a gale: the power axis reaches "20,000" W (it ran 7 px off the canvas's left edge).
    assert_chart_fits_after(
        shown,
        CHART,
        [
            NumberChange("CdA (m²)", "cda_m2", 0.8, 0.32),
            NumberChange("Headwind (m/s, − = tailwind)", "headwind_ms", 15.0, 0.0),
        ],
        lambda scene: scene.chart.data,
        over_ten_kilowatts,
    )
