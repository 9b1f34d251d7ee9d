"""The arm's error chart after a solve of zero iterations (Tolerance 1 → 2 mm after the opening solve): whole
iteration ticks, no label cut at the canvas's edge, at 1280×720."""

from __future__ import annotations

import pytest
from helpers.browser import (
    ScenePage,
    assert_tick_labels_inside,
    scene_page_fixture,
    set_number,
    tick_label_boxes,
    wait_chart_data,
)
from helpers.waiting import wait_until

from scenes.arm import ArmScene

pytestmark = pytest.mark.browser

CHART = "Error after each iteration (log scale)"


shown = scene_page_fixture("arm", [(1280, 720)])


def test_zero_iterations_show_whole_ticks_and_no_cut_label(shown: ScenePage) -> None:
    scene = shown.scene
    assert isinstance(scene, ArmScene)
    set_number(shown.page, "Tolerance (mm)", 2.0)
    wait_until(lambda: scene.params.tolerance_mm == 2.0, "tolerance set")
    with scene._lock:
        data = scene.plot.data
    assert len(data[0]) == 1  # the opening solve is already within 2 mm: one point, iteration 0
    wait_chart_data(shown.page, CHART, data)
    layout = tick_label_boxes(shown.page, CHART)
    x_labels = [box["text"] for box in layout["boxes"] if box["axis"] == 0]
    assert x_labels == ["0", "1"], x_labels
    y_labels = [box["text"] for box in layout["boxes"] if box["axis"] == 1]
    assert y_labels and "0" not in y_labels, y_labels
    assert_tick_labels_inside(shown.page, CHART)
