"""uPlot charts whose tick labels stay inside their canvas: every scene's chart is made and fed through here.

uPlot (1.6.32 in viser 1.1.1's client) draws tick labels on its canvas. A vertical axis gets a fixed width (50 CSS px
by default) and viser's client pads the plot by (0, 24, 0, 0) px, so a label wider than the axis runs off the left
edge ("20,000" W, "-4,000" W), and the label of a tick at the very top of the plot runs off the top edge (the course
chart's "2,000" m). A chart cannot send uPlot a sizing function (only JSON crosses the websocket), so the width is
fitted here, from the data, to the widest label uPlot can write for that data, and it is fitted again whenever the
data change (:meth:`FittedChart.data`).

The widths are an upper bound for uPlot's labels with its default axis font (12 px system-ui, DejaVu Sans on
Debian): uPlot pads an auto y range by 10 % of the span, rounds it to "nice" values, formats with
``Intl.NumberFormat`` (grouping commas, at most 3 decimals), and spaces ticks at least 30 px (y) / 50 px (x) apart.
A y range narrowed by drag-zooming into a small part of the x range can call for more decimals than the full data
do; those labels can still overrun.

The x range is pinned to the data's (:func:`fit_x_scale`). viser 1.1.1's client keeps an auto x scale's window
*relative* to the data across updates, in a React effect that also runs when the chart is rebuilt (any change of
axes or padding rebuilds it). When a rebuild and a new x extent arrive together, that effect can read the old
chart's window before uPlot has committed the new one, and the new chart opens zoomed into the old extent: the
labels' chart opened on x 0..1 of 0..80 and showed y "-4,899.999" to "-4,899.996" for data from -4,900 to 2,100.
A pinned range (``auto: false``, a ``range`` tuple) skips that effect; a new x extent sends new scales, which
rebuild the chart on the new range. Drag-zoom still works and a double click returns to the whole range.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any, Protocol

import numpy as np
import viser
import viser.uplot

AXIS_SIZE_PX = 50
"""uPlot's default width of a vertical axis (tick, gap and labels, without the axis title), CSS px."""
TICK_PX, GAP_PX = 10, 5
"""uPlot's default tick length and gap between tick and label, CSS px."""
MARGIN_PX = 3
"""Room left between a label and the canvas edge, CSS px."""
SIZE_STEP_PX = 4
"""Axis widths are rounded up to a multiple of this, so small changes in the data do not rebuild the chart."""
EDGE_PAD_PX = 12
"""Padding above (below) the plot when no axis is there: half a 12 px label over the top tick, and a margin."""
CHAR_PX = {",": 4.0, ".": 4.0, "-": 4.6}
"""Advance widths of a 12 px label's characters (DejaVu Sans 12 px measures 7.63 px a digit, 3.81 a comma or point,
4.33 a hyphen); digits take :data:`DIGIT_PX`."""
DIGIT_PX = 7.8
MAX_DECIMALS = 3
"""uPlot 1.6's labels come from ``Intl.NumberFormat().format``: at most 3 fraction digits."""
Y_TICKS_MAX = 20
"""A y axis has at most this many ticks (30 px apart over at most 600 px of plot, the expanded view's height)."""
FAINT_TICKS = "rgba(0,0,0,0.07)"
"""uPlot's default tick colour (its grid's)."""
X_TICKS_MAX = 16
"""An x axis has at most this many ticks (50 px apart over at most 800 px)."""


class AddUplot(Protocol):
    """The ``add_uplot`` of viser's GUI API (or of the scenes' facade over it)."""

    def add_uplot(self, *args: Any, **kwargs: Any) -> viser.GuiUplotHandle: ...


# --------------------------------------------------------------------------------------------- label widths
def label_px(text: str) -> float:
    """Width in CSS px of tick label ``text`` in uPlot's 12 px axis font (an upper bound)."""
    return sum(DIGIT_PX if c.isdigit() else CHAR_PX.get(c, DIGIT_PX) for c in text)


def format_label(value: float, decimals: int) -> str:
    """``value`` as uPlot writes a tick label: grouped thousands, ``decimals`` fraction digits (at most 3)."""
    return f"{value:,.{min(decimals, MAX_DECIMALS)}f}"


def _decimals_of_step(step: float) -> int:
    """Fraction digits of the smallest "nice" tick step (1, 2, 2.5 or 5 × 10^k) at least ``step``."""
    k = math.floor(math.log10(step))
    for mantissa in (1.0, 2.0, 2.5, 5.0, 10.0):
        if mantissa * 10.0**k >= step * (1.0 - 1e-9):
            break
    if mantissa == 10.0:
        mantissa, k = 1.0, k + 1
    return max(0, -k) + (1 if mantissa == 2.5 else 0)


def widest_linear_label(lo: float, hi: float, ticks_max: int, pad: float) -> str:
    """The widest tick label uPlot can write on a linear axis over data ``lo``..``hi``.

    Args:
        lo, hi: the data's range on this axis (finite, any units).
        ticks_max: the most ticks the axis can hold (its longest plot side over its tick spacing).
        pad: fraction of the span uPlot adds beyond the data (0.1 for an auto y range, 0 for x).
    """
    span = hi - lo
    if span <= 0.0:
        span = abs(hi) if hi != 0.0 else 1.0
    extent = max(abs(lo), abs(hi)) + pad * span
    if extent <= 0.0:
        return "0"
    lead = 10.0 ** math.floor(math.log10(extent))
    # The extent rounded up at its leading digit.
    top = math.ceil(extent / lead * (1.0 - 1e-12)) * lead
    decimals = _decimals_of_step(span / ticks_max)
    sign = "-" if lo < 0.0 else ""
    return sign + format_label(top, decimals)


def widest_log_label(lo: float, hi: float) -> str:
    """The widest tick label uPlot can write on a base-10 log axis over positive data ``lo``..``hi``.

    uPlot widens a log range to whole decades and labels powers of ten and their multiples.
    """
    low, high = math.floor(math.log10(lo)), math.ceil(math.log10(hi))
    labels = [format_label(10.0**e, max(0, -e)) for e in range(low, high + 1)]
    return max(labels, key=label_px)


# --------------------------------------------------------------------------------------------- fitting
def _series_scales(series: Sequence[Mapping[str, Any]]) -> list[str]:
    """Scale key of each y series (uPlot's default is "y")."""
    return [str(s.get("scale", "y")) for s in series[1:]]


def _range(values: Sequence[np.ndarray], log: bool) -> tuple[float, float] | None:
    finite = [v[np.isfinite(v) & ((v > 0.0) if log else True)] for v in values]
    finite = [v for v in finite if v.size]
    if not finite:
        return None
    return float(min(v.min() for v in finite)), float(max(v.max() for v in finite))


def fit_x_scale(
    data: Sequence[np.ndarray], scales: Mapping[str, Mapping[str, Any]]
) -> dict[str, viser.uplot.Scale]:
    """``scales`` with the x scale pinned to the finite extent of ``data[0]`` (see the module's note).

    A flat x (one value) is widened by half a unit or 1 % of its size, whichever is more. The x scale is left as
    given when it has a range of its own, is ordinal, has no finite value (positive, on a log scale), or would be
    widened past the largest float. Other scales are returned as they are.
    """
    out = {key: viser.uplot.Scale(**scale) for key, scale in scales.items()}  # type: ignore[typeddict-item]
    x_scale = out.get("x", viser.uplot.Scale())
    if (
        "range" in x_scale or x_scale.get("distr") == 2
    ):  # the caller's own range; ordinal x (index units)
        return out
    found = _range([np.asarray(data[0], dtype=np.float64)], x_scale.get("distr") == 3)
    if found is None:
        return out
    lo, hi = found
    if hi <= lo:
        half = max(0.5, 0.01 * abs(lo))
        lo, hi = (lo / 2.0, lo * 2.0) if x_scale.get("distr") == 3 else (lo - half, hi + half)
    if not (math.isfinite(lo) and math.isfinite(hi)):  # widened past the largest float
        return out
    x_scale = viser.uplot.Scale(**x_scale)  # type: ignore[typeddict-item]
    x_scale["auto"] = False
    x_scale["range"] = (lo, hi)
    out["x"] = x_scale
    return out


def fit_layout(
    data: Sequence[np.ndarray],
    series: Sequence[Mapping[str, Any]],
    scales: Mapping[str, Mapping[str, Any]],
    axes: Sequence[Mapping[str, Any]] | None,
) -> tuple[tuple[viser.uplot.Axis, ...], tuple[int, int, int, int]]:
    """Axes and padding (top, right, bottom, left; CSS px) that keep every tick label of this chart in its canvas.

    Each vertical axis gets a width for its widest label (at least uPlot's 50 px); a side with no axis is padded
    for half a label: above and below the plot for the y labels at its top and bottom ticks, left and right for
    the x labels at its ends.

    Args:
        data: (x, y1, y2, …) 1-D arrays, as given to ``add_uplot``.
        series: the chart's series; each y series' ``scale`` names its scale (default "y").
        scales: the chart's scales; ``distr=3`` is a log scale.
        axes: the chart's axes, or None for uPlot's default (x below, the first y series' scale on the left).
    """
    y_scales = _series_scales(series)
    if axes is None:
        # uPlot's own faint ticks: viser's client darkens the ticks of axes given explicitly.
        ticks = viser.uplot.Axis_Ticks(stroke=FAINT_TICKS)
        axes = (
            viser.uplot.Axis(scale="x", ticks=ticks),
            viser.uplot.Axis(scale=y_scales[0] if y_scales else "y", ticks=ticks),
        )
    fitted: list[viser.uplot.Axis] = []
    sides: set[int] = set()
    x_label_px = 0.0
    for k, axis in enumerate(axes):
        out = viser.uplot.Axis(**axis)  # type: ignore[typeddict-item]
        side = int(axis.get("side", 2 if k == 0 else 3))
        if axis.get("show", True):
            sides.add(side)
        key = str(axis.get("scale", "x" if k == 0 else "y"))
        log = scales.get(key, {}).get("distr") == 3
        values = (
            [data[0]]
            if key == "x"
            else [d for d, s in zip(data[1:], y_scales, strict=True) if s == key]
        )
        found = _range(values, log)
        if found is not None and side in (1, 3):
            widest = (
                widest_log_label(*found) if log else widest_linear_label(*found, Y_TICKS_MAX, 0.1)
            )
            need = label_px(widest) + TICK_PX + GAP_PX + MARGIN_PX
            out["size"] = max(AXIS_SIZE_PX, SIZE_STEP_PX * math.ceil(need / SIZE_STEP_PX))
        elif found is not None:
            widest = (
                widest_log_label(*found) if log else widest_linear_label(*found, X_TICKS_MAX, 0.0)
            )
            x_label_px = max(x_label_px, label_px(widest))
        fitted.append(out)
    vertical = bool(sides & {1, 3})
    horizontal = bool(sides & {0, 2})
    end_pad = math.ceil(x_label_px / 2.0) + MARGIN_PX + 1 if horizontal else 4
    padding = (
        0 if 0 in sides else (EDGE_PAD_PX if vertical else 4),
        0 if 1 in sides else end_pad,
        0 if 2 in sides else (EDGE_PAD_PX if vertical else 4),
        0 if 3 in sides else end_pad,
    )
    return tuple(fitted), padding


class FittedChart:
    """A uPlot chart in the GUI whose axes and x range are refitted (:func:`fit_layout`, :func:`fit_x_scale`)
    whenever its data are set."""

    def __init__(
        self,
        gui: AddUplot,
        data: tuple[np.ndarray, ...],
        series: tuple[viser.uplot.Series, ...],
        *,
        scales: dict[str, viser.uplot.Scale],
        axes: tuple[viser.uplot.Axis, ...] | None = None,
        **kwargs: Any,
    ) -> None:
        """Add the chart to ``gui``; the other keyword arguments go to ``add_uplot`` as they are (not padding)."""
        assert "padding" not in kwargs, "the padding is fitted"
        self._series, self._scales, self._axes = series, scales, axes
        fitted, padding = fit_layout(data, series, scales, axes)
        self.handle = gui.add_uplot(
            data=data,
            series=series,
            scales=fit_x_scale(data, scales),
            axes=fitted,
            padding=padding,
            **kwargs,
        )
        """The viser handle underneath."""

    @property
    def data(self) -> tuple[np.ndarray, ...]:
        """The chart's (x, y1, …) arrays; setting them refits the axes first when the labels need it."""
        return self.handle.data

    @data.setter
    def data(self, data: tuple[np.ndarray, ...]) -> None:
        fitted, padding = fit_layout(data, self._series, self._scales, self._axes)
        pinned = fit_x_scale(data, self._scales)
        if pinned != self.handle.scales:
            self.handle.scales = pinned
        if fitted != self.handle.axes:
            self.handle.axes = fitted
        if padding != self.handle.padding:
            self.handle.padding = padding
        self.handle.data = data

    @property
    def visible(self) -> bool:
        return self.handle.visible

    @visible.setter
    def visible(self, visible: bool) -> None:
        self.handle.visible = visible

    def remove(self) -> None:
        self.handle.remove()
