"""A real browser draws charts made through :class:`scenes._charts.FittedChart`: whatever the data's range (large,
small, negative, over decades on a log axis) every tick label lies inside the chart's canvas, by uPlot's own layout
and by the pixels on the canvas's edge. The scenes' own charts are checked in their browser test files."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
import viser
import viser.uplot
from helpers.browser import (
    VIEWPORTS,
    assert_chart_shows_its_data,
    assert_tick_labels_inside,
    open_viser,
    wait_chart_data,
)
from helpers.properties import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from scenes._charts import FittedChart, number_scales

pytestmark = pytest.mark.browser

LINEAR = "Linear probe"
LOG = "Log probe"
TWO_AXES = "Two-axis probe"


class Probe:
    def __init__(self, server: viser.ViserServer, page: Any) -> None:
        self.server, self.page = server, page
        x = np.linspace(0.0, 1.0, 50)
        self.linear = FittedChart(
            server.gui,
            data=(x, x),
            series=(viser.uplot.Series(label="x"), viser.uplot.Series(label="y", stroke="red")),
            scales=number_scales("y"),
            title=LINEAR,
            aspect=1.4,
        )
        self.log = FittedChart(
            server.gui,
            data=(x, x + 1.0),
            series=(viser.uplot.Series(label="x"), viser.uplot.Series(label="y", stroke="red")),
            scales=number_scales("y", log=("y",)),
            title=LOG,
            aspect=1.6,
        )
        self.two = FittedChart(  # the course chart's layout: an axis on each side, one series without an axis
            server.gui,
            data=(x, x, x, x),
            series=(
                viser.uplot.Series(label="x"),
                viser.uplot.Series(label="a", stroke="red", scale="a"),
                viser.uplot.Series(label="b", stroke="blue", scale="b"),
                viser.uplot.Series(label="c", stroke="green", scale="c"),
            ),
            scales=number_scales("a", "b", "c"),
            axes=(
                viser.uplot.Axis(scale="x", label="x"),
                viser.uplot.Axis(scale="a", label="a", side=3),
                viser.uplot.Axis(scale="b", label="b", side=1, grid=viser.uplot.Axis_Grid(show=False)),
            ),
            title=TWO_AXES,
            aspect=1.4,
        )

    def show(self, chart: FittedChart, title: str, data: tuple[np.ndarray, ...]) -> None:
        chart.data = data
        self.server.flush()
        wait_chart_data(self.page, title, data)
        assert_chart_shows_its_data(self.page, title, data)
        assert_tick_labels_inside(self.page, title)


@pytest.fixture(scope="module", params=VIEWPORTS, ids=lambda v: f"{v[0]}x{v[1]}")
def probe(request: pytest.FixtureRequest, chromium_browser: Any) -> Iterator[Probe]:
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    server.scene.add_frame("/probe", show_axes=False)
    page = chromium_browser.new_page()
    page.set_default_timeout(90_000)
    try:
        page.set_viewport_size({"width": request.param[0], "height": request.param[1]})
        probe = Probe(server, page)
        open_viser(page, server.get_port(), "/probe")
        page.get_by_text(TWO_AXES, exact=True).first.wait_for()
        yield probe
    finally:
        page.close()
        server.stop()


def _curve(lo: float, hi: float, x_max: float) -> tuple[np.ndarray, np.ndarray]:
    x = np.linspace(0.0, x_max, 120)
    return x, lo + (hi - lo) * (x / x_max) ** 3


def test_the_wide_labels_that_were_cut(probe: Probe) -> None:
    # The peloton's chart at CdA 0.8 into a 15 m/s headwind ("20,000" W ran 7 px off the left edge), down a 15 %
    # grade ("-4,000"), and the course chart's sample climb ("2,000" m at the top tick ran 6 px off the top).
    probe.show(probe.linear, LINEAR, _curve(0.0, 19_700.0, 80.0))
    probe.show(probe.linear, LINEAR, _curve(-4_900.0, 2_100.0, 80.0))
    x, elevation = _curve(744.0, 1815.0, 13.2)
    probe.show(probe.two, TWO_AXES, (x, elevation, elevation / 90.0, elevation / 5.0))


@settings(max_examples=examples(12), deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    magnitude=st.floats(-2.5, 5.5),
    low=st.floats(-1.0, 1.0),
    x_magnitude=st.floats(-1.0, 4.0),
    right_magnitude=st.floats(-1.0, 3.5),
)
def test_labels_stay_inside_for_any_range(
    probe: Probe, magnitude: float, low: float, x_magnitude: float, right_magnitude: float
) -> None:
    hi = 10.0**magnitude
    x, y = _curve(low * hi, hi, 10.0**x_magnitude)
    probe.show(probe.linear, LINEAR, (x, y))
    right = y / hi * 10.0**right_magnitude
    probe.show(probe.two, TWO_AXES, (x, y, right, y))


@settings(max_examples=examples(8), deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(low=st.floats(-6.0, 2.0), decades=st.floats(0.3, 7.0))
def test_log_labels_stay_inside_for_any_decades(probe: Probe, low: float, decades: float) -> None:
    x = np.arange(40, dtype=np.float64)
    y = 10.0 ** (low + decades * (1.0 - x / x[-1]) ** 2)
    probe.show(probe.log, LOG, (x, y))
