"""The chart fitting's label widths and layout, without a browser (the browser tests look at the pixels)."""

from __future__ import annotations

import numpy as np
import viser.uplot

from scenes._charts import (
    AXIS_SIZE_PX,
    EDGE_PAD_PX,
    fit_layout,
    fit_x_scale,
    format_label,
    label_px,
    widest_linear_label,
    widest_log_label,
)


def test_labels_are_no_narrower_than_uplot_writes_them() -> None:
    assert format_label(20_000.0, 0) == "20,000"
    assert format_label(0.25, 2) == "0.25"
    assert format_label(1e-6, 6) == "0.000"  # Intl.NumberFormat keeps at most 3 decimals
    # DejaVu Sans 12 px (Debian's system-ui) measures "20,000" 41.4 px wide in Chromium: the bound is above it.
    assert 41.4 <= label_px("20,000") <= 45.0


def test_the_widest_label_of_the_cut_charts() -> None:
    assert widest_linear_label(0.0, 19_700.0, 20, 0.1) == "30,000"  # same width as uPlot's "20,000"
    assert widest_linear_label(-4_900.0, 2_100.0, 20, 0.1).startswith("-")
    assert (
        widest_linear_label(0.0, 1.3, 20, 0.1) == "2.0"
    )  # steps of 0.1 at the finest (uPlot writes "2", "1.5"…: never wider)
    assert widest_log_label(0.004, 2_300.0) == "10,000"
    assert widest_log_label(0.004, 0.9) == "0.001"


def test_layout_widens_the_axis_and_pads_the_top() -> None:
    x = np.linspace(0.0, 80.0, 20)
    series = (viser.uplot.Series(label="x"), viser.uplot.Series(label="y"))
    scales = {"x": viser.uplot.Scale(auto=True), "y": viser.uplot.Scale(auto=True)}
    axes, padding = fit_layout((x, x * 10.0), series, scales, None)
    assert axes[1].get("size") == AXIS_SIZE_PX and padding[0] == EDGE_PAD_PX
    axes, _ = fit_layout((x, x * 250.0), series, scales, None)
    assert float(axes[1].get("size", 0.0)) >= label_px("20,000") + 15


def test_the_x_range_is_pinned_to_the_data() -> None:
    # viser's client keeps an auto x window relative to the data, and can open a rebuilt chart zoomed into the
    # old extent: a pinned range (auto off, the data's extent) is rebuilt on the new one.
    x = np.linspace(2.0, 80.0, 20)
    scales = {"x": viser.uplot.Scale(time=False, auto=True), "y": viser.uplot.Scale(auto=True)}
    pinned = fit_x_scale((x, x), scales)
    assert pinned["x"] == {"time": False, "auto": False, "range": (2.0, 80.0)}
    # The caller's scales are left as they were.
    assert pinned["y"] == scales["y"] and scales["x"].get("auto") is True
    with_gaps = np.array([np.nan, 3.0, -np.inf, 5.0])
    assert fit_x_scale((with_gaps, with_gaps), scales)["x"].get("range") == (3.0, 5.0)


def test_a_flat_or_empty_x_range_is_widened_or_left_alone() -> None:
    scales = {"x": viser.uplot.Scale(auto=True), "y": viser.uplot.Scale(auto=True)}
    # a flat whole-number x (one iteration) gets one whole step, lo..lo + 1, so its ticks are whole numbers
    assert fit_x_scale((np.full(3, 0.0), np.zeros(3)), scales)["x"].get("range") == (0.0, 1.0)
    assert fit_x_scale((np.full(3, 0.25), np.zeros(3)), scales)["x"].get("range") == (-0.25, 0.75)
    assert fit_x_scale((np.full(3, 1e308), np.zeros(3)), scales)["x"].get("range") == (1e308 - 1e306, 1e308 + 1e306)
    assert fit_x_scale((np.full(3, np.nan), np.zeros(3)), scales) == scales
    log = {"x": viser.uplot.Scale(distr=3, auto=True)}
    assert fit_x_scale((np.full(3, 10.0), np.zeros(3)), log)["x"].get("range") == (5.0, 20.0)
    assert fit_x_scale((np.array([-1.0, 0.0]), np.zeros(2)), log) == log
    assert fit_x_scale((np.full(2, 1.7e308), np.zeros(2)), log) == log  # 2 × 1.7e308 overflows
    own = {"x": viser.uplot.Scale(auto=False, range=(0.0, 1.0))}
    assert fit_x_scale((np.arange(5.0), np.zeros(5)), own) == own
    ordinal = {"x": viser.uplot.Scale(distr=2)}
    assert fit_x_scale((np.arange(5.0), np.zeros(5)), ordinal) == ordinal
