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

Counts stay whole and small values stay readable. An x whose data are all whole numbers (iterations) gets whole
tick steps (``incrs`` 1, 2, 5, 10, …), and a single point a range of one unit from it (0..1: ticks "0" and "1")
instead of half a unit either side (fractional ticks, and a "0.5" cut at the canvas's edge). A log axis whose data
reach below 10⁻³ (a clamped zero, say) would be labelled "0" by uPlot's three-decimal format; it gets its decades
as fixed ``splits`` with their own labels ("1e-6", "0.001", "1"), at most :data:`LOG_TICKS_MAX` of them, on a range
pinned to those decades (:func:`log_ticks`).
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
WHOLE_INCRS = tuple(float(m * 10**k) for k in range(16) for m in (1, 2, 5))
"""Tick steps of an axis of whole numbers: 1, 2, 5, 10, 20, 50, … (uPlot takes the first that leaves its spacing)."""
LOG_TICKS_MAX = 6
"""A log axis with labelled decades gets at most this many (30 px apart on the smallest chart's ~180 px plot)."""
LOG_DECIMALS_MIN = -MAX_DECIMALS
"""The smallest decade uPlot's own labels can write ("0.001"); below it they read "0"."""


def number_scales(*y: str, log: Sequence[str] = ()) -> dict[str, viser.uplot.Scale]:
    """uPlot scales for a chart of numbers: x on a number line (uPlot's x is time unless told) and each of the
    ``y`` scale keys, all fitted to the data; the keys also in ``log`` on a log₁₀ axis (uPlot's ``distr=3``)."""
    scales = {"x": viser.uplot.Scale(time=False, auto=True)}
    for key in y:
        scales[key] = viser.uplot.Scale(distr=3, auto=True) if key in log else viser.uplot.Scale(auto=True)
    return scales


class AddUplot(Protocol):
    """The ``add_uplot`` of viser's GUI API (or of the scenes' facade over it)."""

    def add_uplot(self, *args: Any, **kwargs: Any) -> viser.GuiUplotHandle: ...


# --------------------------------------------------------------------------------------------- label widths
TINY = 1e-300
"""Least magnitude the label arithmetic works with: far below the 3 decimals a label shows, far above the subnormals."""


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
    # Below TINY a power of ten underflows to 0 (subnormal data): such values print as "0.000" whatever they are.
    extent = max(extent, TINY)
    lead = 10.0 ** math.floor(math.log10(extent))
    # The extent rounded up at its leading digit.
    top = math.ceil(extent / lead * (1.0 - 1e-12)) * lead
    decimals = _decimals_of_step(max(span / ticks_max, TINY))
    sign = "-" if lo < 0.0 else ""
    return sign + format_label(top, decimals)


def decade_label(exponent: int) -> str:
    """The label of 10^exponent: as uPlot writes it ("0.001", "1", "1,000"), or "1e-6" where uPlot would write "0"."""
    if exponent < LOG_DECIMALS_MIN:
        return f"1e{exponent}"
    return format_label(10.0**exponent, max(0, -exponent))


def widest_log_label(lo: float, hi: float) -> str:
    """The widest tick label a base-10 log axis over positive data ``lo``..``hi`` can show.

    uPlot widens a log range to whole decades and labels powers of ten and their multiples; decades below 10⁻³ are
    labelled by :func:`log_ticks` ("1e-6").
    """
    low, high = math.floor(math.log10(lo)), math.ceil(math.log10(hi))
    labels = [decade_label(e) for e in range(low, high + 1)]
    return max(labels, key=label_px)


def log_ticks(lo: float, hi: float) -> tuple[tuple[float, ...], tuple[str, ...]] | None:
    """Fixed decade ticks (values, labels) for a log axis over positive data ``lo``..``hi``, or None where uPlot's
    own labels read right (no decade below 10⁻³).

    Every ``step``-th decade from the one at or below ``lo`` to the first at or above ``hi``, with ``step`` the
    least that keeps them to :data:`LOG_TICKS_MAX`; the axis's range is pinned to the first and last.
    """
    low, high = math.floor(math.log10(lo)), math.ceil(math.log10(hi))
    if low >= LOG_DECIMALS_MIN:
        return None
    high = max(high, low + 1)
    step = max(1, math.ceil((high - low) / (LOG_TICKS_MAX - 1)))
    exponents = range(low, low + step * math.ceil((high - low) / step) + 1, step)
    return tuple(10.0**e for e in exponents), tuple(decade_label(e) for e in exponents)


def whole_numbers(values: np.ndarray) -> bool:
    """Whether the finite values of a 1-D array are all whole numbers (and there is at least one)."""
    finite = values[np.isfinite(values)]
    return bool(finite.size) and bool(np.all(finite == np.round(finite))) and bool(np.abs(finite).max() < 2**53)


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


def _pinned(scale: Mapping[str, Any], lo: float, hi: float) -> viser.uplot.Scale:
    """A copy of ``scale`` fixed to [lo, hi] (uPlot's ``auto`` off, so it does not rescale to the data)."""
    pinned = viser.uplot.Scale(**scale)  # type: ignore[typeddict-item]
    pinned["auto"] = False
    pinned["range"] = (lo, hi)
    return pinned


def fit_x_scale(data: Sequence[np.ndarray], scales: Mapping[str, Mapping[str, Any]]) -> dict[str, viser.uplot.Scale]:
    """``scales`` with the x scale pinned to the finite extent of ``data[0]`` (see the module's note).

    A flat x (one value) is widened to the next whole number when it is one (0 → 0..1, an iteration count), else
    by half a unit or 1 % of its size, whichever is more. The x scale is left as given when it has a range of its
    own, is ordinal, has no finite value (positive, on a log scale), or would be widened past the largest float.
    Other scales are returned as they are.
    """
    out = {key: viser.uplot.Scale(**scale) for key, scale in scales.items()}  # type: ignore[typeddict-item]
    x_scale = out.get("x", viser.uplot.Scale())
    if "range" in x_scale or x_scale.get("distr") == 2:  # the caller's own range; ordinal x (index units)
        return out
    found = _range([np.asarray(data[0], dtype=np.float64)], x_scale.get("distr") == 3)
    if found is None:
        return out
    lo, hi = found
    if hi <= lo and x_scale.get("distr") == 3:
        lo, hi = lo / 2.0, lo * 2.0
    elif hi <= lo and lo == round(lo) and abs(lo) < 2**53:
        hi = lo + 1.0
    elif hi <= lo:
        half = max(0.5, 0.01 * abs(lo))
        lo, hi = lo - half, hi + half
    if not (math.isfinite(lo) and math.isfinite(hi)):  # widened past the largest float
        return out
    out["x"] = _pinned(x_scale, lo, hi)
    return out


def fit_scales(
    data: Sequence[np.ndarray], series: Sequence[Mapping[str, Any]], scales: Mapping[str, Mapping[str, Any]]
) -> dict[str, viser.uplot.Scale]:
    """:func:`fit_x_scale`, and each log y scale whose data reach below 10⁻³ pinned to its decade ticks'
    range (:func:`log_ticks`), so the fixed ticks :func:`fit_layout` gives its axis span the plot."""
    out = fit_x_scale(data, scales)
    y_scales = _series_scales(series)
    for key, scale in out.items():
        if key == "x" or scale.get("distr") != 3 or "range" in scales.get(key, {}):
            continue
        found = _range([d for d, s in zip(data[1:], y_scales, strict=True) if s == key], True)
        ticks = log_ticks(*found) if found is not None else None
        if ticks is not None:
            out[key] = _pinned(scale, ticks[0][0], ticks[0][-1])
    return out


def fit_layout(
    data: Sequence[np.ndarray],
    series: Sequence[Mapping[str, Any]],
    scales: Mapping[str, Mapping[str, Any]],
    axes: Sequence[Mapping[str, Any]] | None,
) -> tuple[tuple[viser.uplot.Axis, ...], tuple[int, int, int, int]]:
    """Axes and padding (top, right, bottom, left; CSS px) that keep every tick label of this chart in its canvas.

    Each vertical axis gets a width for its widest label (at least its own ``size``, else uPlot's 50 px); a side with
    no axis is padded
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
        values = [data[0]] if key == "x" else [d for d, s in zip(data[1:], y_scales, strict=True) if s == key]
        found = _range(values, log)
        whole = not log and bool(values) and all(whole_numbers(np.asarray(v, dtype=np.float64)) for v in values)
        if whole and "incrs" not in axis and "splits" not in axis:
            out["incrs"] = WHOLE_INCRS
        ticks = log_ticks(*found) if log and found is not None else None
        if ticks is not None and "splits" not in axis and "values" not in axis:
            out["splits"], out["values"] = ticks
        if found is not None:
            vertical_axis = side in (1, 3)
            if ticks is not None and "values" not in axis:
                widest = max(ticks[1], key=label_px)
            elif log:
                widest = widest_log_label(*found)
            elif whole and not vertical_axis:  # whole ticks over the pinned range, a unit past one point
                widest = ("-" if found[0] < 0.0 else "") + format_label(max(abs(found[0]), abs(found[1]) + 1.0), 0)
            else:
                ticks_max, pad = (Y_TICKS_MAX, 0.1) if vertical_axis else (X_TICKS_MAX, 0.0)
                widest = widest_linear_label(*found, ticks_max, pad)
            if vertical_axis:
                need = label_px(widest) + TICK_PX + GAP_PX + MARGIN_PX
                least = float(axis.get("size", AXIS_SIZE_PX))  # an axis's own size is its least width
                out["size"] = max(least, SIZE_STEP_PX * math.ceil(need / SIZE_STEP_PX))
            else:
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
    """A uPlot chart in the GUI whose axes and ranges are refitted (:func:`fit_layout`, :func:`fit_scales`)
    whenever its data are set."""

    def __init__(
        self,
        gui: AddUplot,
        data: tuple[np.ndarray, ...],
        series: tuple[viser.uplot.Series, ...],
        *,
        scales: dict[str, viser.uplot.Scale] | None = None,
        axes: tuple[viser.uplot.Axis, ...] | None = None,
        **kwargs: Any,
    ) -> None:
        """Add the chart to ``gui``; the other keyword arguments go to ``add_uplot`` as they are (not padding).

        ``scales`` defaults to a plain number line on x (not uPlot's default of time) and y, both fitted to the data.
        """
        assert "padding" not in kwargs, "the padding is fitted"
        if scales is None:
            scales = number_scales("y")
        self._series, self._scales, self._axes = series, scales, axes
        fitted, padding = fit_layout(data, series, scales, axes)
        self.handle = gui.add_uplot(
            data=data, series=series, scales=fit_scales(data, series, scales), axes=fitted, padding=padding, **kwargs
        )
        """The viser handle underneath."""

    @property
    def data(self) -> tuple[np.ndarray, ...]:
        """The chart's (x, y1, …) arrays; setting them refits the axes first when the labels need it."""
        return self.handle.data

    @data.setter
    def data(self, data: tuple[np.ndarray, ...]) -> None:
        fitted, padding = fit_layout(data, self._series, self._scales, self._axes)
        pinned = fit_scales(data, self._series, self._scales)
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
