"""A real browser: Chromium ticks the course mode and its chart's tick labels stay inside its canvas, at 1600×1000 and
1280×720, before and after more power; the group on its road is framed large left of the panel, and the air controls'
labels and values read whole. (Uploading a GPX and playing it is in ``test_interactions_browser.py``.)"""

from __future__ import annotations

import numpy as np
import pytest
from helpers.browser import (
    ScenePage,
    assert_chart_shows_its_data,
    assert_in_view,
    assert_seen,
    assert_tick_labels_inside,
    changed_mask,
    control_row,
    panel_rect,
    scene_page_fixture,
    screenshot,
    set_number,
    settle,
    wait_chart_data,
    wait_frames,
    with_nodes_hidden,
)
from helpers.waiting import wait_until

from scenes.peloton import PelotonScene
from scenes.peloton.course import CHART_TITLE, CourseMode

pytestmark = pytest.mark.browser


shown = scene_page_fixture("peloton")


def test_the_course_chart_tick_labels_stay_inside_its_canvas(shown: ScenePage) -> None:
    title = CHART_TITLE
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
    # Three y axes leave the route room: the plot at least half the chart's width (it was 104 px of 324).
    plot, whole = shown.page.evaluate(PLOT_AND_CHART_WIDTH, title)
    assert plot >= 0.5 * whole, (plot, whole)
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


PLOT_AND_CHART_WIDTH = """
title => {
  const chart = [...document.querySelectorAll('.uplot')].find(u => u.querySelector('.u-title')?.textContent === title);
  return [chart.querySelector('.u-over').getBoundingClientRect().width, chart.getBoundingClientRect().width];
}
"""
"""The width (px) of a uPlot chart's plot area and of the whole chart, by its title."""

RIDER_HEIGHT_M = 1.45
"""Height of a drawn rider in the drops, wheels to helmet (m, :func:`scenes.peloton.meshes.rider_meshes`)."""

ONE_LINE = """
text => {
  const hits = [...document.querySelectorAll('label, p, span, div')].filter(e => e.childElementCount === 0
      && e.textContent.trim() === text && e.getClientRects().length > 0);
  return hits.map(e => { const s = getComputedStyle(e); const line = parseFloat(s.lineHeight)
      || 1.3 * parseFloat(s.fontSize); return e.getBoundingClientRect().height / line; });
}
"""
"""How many lines each element showing ``text`` takes (a label broken over two reads 2)."""

VALUE_FITS = """
label => {
  const rows = [...document.querySelectorAll('label')].filter(e => e.textContent.trim() === label);
  return rows.map(l => { let row = l; while (row && !row.querySelector('input')) row = row.parentElement;
      const input = row.querySelector('input:not([type=hidden])');
      return [input.value, input.scrollWidth <= input.clientWidth + 1]; });
}
"""


@pytest.mark.parametrize(
    ("formation", "riders", "least_px"), [("Single file", 4, 75.0), ("Bunch (peloton)", 121, 14.0)]
)
def test_the_course_frames_every_rider_of_the_group_large_on_its_road(
    shown: ScenePage, formation: str, riders: int, least_px: float
) -> None:
    """Course mode draws the whole group as it rides (121 rider instances for a bunch of 121) and frames it left of
    the panel, riders tall enough to see: a line of four 75 px and more, the bunch's nearest rows ≥ 45 px (the
    course drew riders 10-20 px tall before), its farthest rows still ≥ 14 px; the road under them shows."""
    scene = shown.scene
    assert isinstance(scene, PelotonScene)
    with scene._lock:
        scene.controls["formation"].value = formation
        scene.controls["n_riders"].value = riders
    mode = course_on(shown)
    settle(shown)
    with scene._lock:
        feet = np.asarray(mode.course_riders["body"].batched_positions, np.float64)
        drawn = int(np.count_nonzero(np.asarray(mode.course_riders["body"].batched_scales)[:, 0]))
    assert drawn == riders
    feet = feet[:riders]
    heads = feet + [0.0, 0.0, RIDER_HEIGHT_M]
    frame = mode.frame.name
    xy = assert_in_view(shown, frame, np.vstack([feet, heads]), f"{riders} riders")
    heights = np.linalg.norm(xy[riders:] - xy[:riders], axis=1)
    assert heights.min() >= least_px, (heights.min(), np.median(heights))
    if riders > 1:
        assert heights.max() >= 45.0, heights.max()  # the nearest riders read as riders, not specks
    # The group fills a good part of the free view left of the panel.
    left, _, _, _ = panel_rect(shown.page)
    width = np.ptp(xy[:, 0])
    assert width >= 0.4 * left, (width, left)
    # A person sees them: hiding the riders changes the picture where they are; hiding the road changes it too.
    names = [node.name for node in mode.course_riders.values()]
    # Software WebGL may draw the 121 instances a few frames after the scene has settled (a CI run saw none yet).
    for attempt in range(20):
        image = screenshot(shown.page)
        try:
            assert_seen(shown, image, names, xy, f"{riders} riders", max_outside=0.35, without_labels=True)
            break
        except AssertionError:
            if attempt == 19:
                raise
            wait_frames(shown.page, 10)
    road_changed = changed_mask(image, with_nodes_hidden(shown.page, [mode.road.name]))
    assert road_changed.sum() > 5000


def test_the_course_panel_labels_read_whole(shown: ScenePage) -> None:
    """No label of the course's air controls breaks inside a word ("Temperatur / e"), and the "Pressure from" and
    "Air" values show whole in their boxes."""
    mode = course_on(shown)
    with shown.scene._lock:
        mode.controls["air"].value = "Weather reading"
    wait_until(lambda: mode.params.air == "weather", "weather air", timeout_s=15.0)
    control_row(shown.page, "Pressure from").scroll_into_view_if_needed()
    wait_frames(shown.page, 3)
    for label in ("Temp (°C)", "Air"):  # two-word labels may wrap between words, as the panel does
        lines = shown.page.evaluate(ONE_LINE, label)
        assert lines and max(lines) < 1.5, (label, lines)
    for label in ("Pressure from", "Air"):
        fits = shown.page.evaluate(VALUE_FITS, label)
        assert fits and all(ok for _, ok in fits), (label, fits)


def test_find_the_power_says_in_view_when_the_target_is_out_of_reach(shown: ScenePage) -> None:
    """A 1 min target at the sample climb is beyond any power at the safe speed: after a click of 'Find the
    power for this time' the page says so where the eye is (the note stood at the top of the course's folder,
    scrolled out of view by the time the button is reached)."""
    mode = course_on(shown)
    set_number(shown.page, "Target time (min)", 1)
    wait_until(lambda: mode.params.target_min == 1.0, "the target time", timeout_s=15.0)
    button = shown.page.get_by_role("button", name="Find the power for this time")
    button.scroll_into_view_if_needed()
    button.click()
    wait_until(lambda: mode.params.power_w == 2000.0, "the power found", timeout_s=15.0)
    settle(shown)
    note = shown.page.get_by_text("A 1 min finish is out of reach", exact=False)
    wait_until(lambda: note.count() > 0, "the out-of-reach note on the page", timeout_s=10.0)
    # Where the eye is after the click: in the panel's view as it stands, not scrolled to.
    box, viewport = note.first.bounding_box(), shown.page.viewport_size
    assert box is not None and viewport is not None
    _, top, _, bottom = panel_rect(shown.page)
    assert top <= box["y"] and box["y"] + box["height"] <= min(bottom, viewport["height"]), (box, (top, bottom))


def course_on(shown: ScenePage) -> CourseMode:
    """Tick the peloton's course mode (if it is not on already) and wait for its first ride."""
    scene = shown.scene
    assert isinstance(scene, PelotonScene)
    mode = scene.course_mode
    with scene._lock:
        if not mode.enabled:
            mode.enable.value = True
    wait_until(lambda: mode.enabled and mode.state is not None, "course mode on", timeout_s=15.0)
    return mode
