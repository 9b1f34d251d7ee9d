"""Chart axes: whole-number x axes get whole ticks and a one-point series a one-unit range; a log axis whose data
reach below 10⁻³ (a clamped zero) gets decade ticks labelled with their values, never "0"."""

from __future__ import annotations

import math

import numpy as np
import pytest
import viser.uplot
from helpers.properties import examples
from hypothesis import given, settings
from hypothesis import strategies as st

from scenes._charts import (
    LOG_TICKS_MAX,
    WHOLE_INCRS,
    decade_label,
    fit_layout,
    fit_scales,
    label_px,
    log_ticks,
    number_scales,
    whole_numbers,
    widest_linear_label,
)

SERIES = (viser.uplot.Series(label="Iteration"), viser.uplot.Series(label="Error (mm)"))
ARM_SCALES = number_scales("y", log=("y",))
LINEAR_SCALES = number_scales("y")


def _x_axis(data: tuple[np.ndarray, ...], scales: dict[str, viser.uplot.Scale]) -> viser.uplot.Axis:
    axes, _ = fit_layout(data, SERIES, scales, None)
    return axes[0]


def _whole_ticks(lo: float, hi: float, incrs: tuple[float, ...], px: float, space: float = 50.0) -> list[float]:
    """uPlot's linear splits: the first increment at least ``space`` px apart, multiples of it in [lo, hi]."""
    incr = next(i for i in incrs if i * px / (hi - lo) >= space)
    first = math.ceil(lo / incr) * incr
    return [first + k * incr for k in range(int((hi - first) / incr + 1e-9) + 1)]


# --------------------------------------------------------------------------------------------- the arm's chart
def test_the_arm_chart_after_zero_iterations_spans_zero_to_one_with_whole_ticks() -> None:
    data = (np.zeros(1), np.array([0.4]))
    scale = fit_scales(data, SERIES, ARM_SCALES)["x"]
    assert scale.get("range") == (0.0, 1.0) and scale.get("auto") is False
    axis = _x_axis(data, ARM_SCALES)
    assert axis.get("incrs") == WHOLE_INCRS
    # Over a ~300 px plot, uPlot's first whole step 50 px apart is 1: ticks 0 and 1, nothing at 0.5.
    assert _whole_ticks(0.0, 1.0, WHOLE_INCRS, 300.0) == [0.0, 1.0]
    # The padding right of the plot holds half of the widest label ("1") and a margin.
    _, padding = fit_layout(data, SERIES, ARM_SCALES, None)
    assert padding[1] >= label_px("1") / 2.0 + 3


def test_an_error_of_zero_clamped_to_a_floor_is_labelled_by_its_value() -> None:
    data = (np.arange(4.0), np.array([120.0, 3.0, 0.02, 1e-6]))
    axes, _ = fit_layout(data, SERIES, ARM_SCALES, None)
    y = axes[1]
    assert y.get("splits") == (1e-6, 1e-4, 1e-2, 1.0, 1e2, 1e4)
    assert y.get("values") == ("1e-6", "1e-4", "0.01", "1", "100", "10,000")
    assert "0" not in (y.get("values") or ())
    assert fit_scales(data, SERIES, ARM_SCALES)["y"].get("range") == (1e-6, 1e4)
    assert y.get("size", 0) >= label_px("10,000") + 10 + 5


# --------------------------------------------------------------------------------------------- families
whole_x = st.lists(st.integers(-1000, 10**6), min_size=1, max_size=40).map(
    lambda v: np.array(sorted(v), dtype=np.float64)
)


@given(x=whole_x)
@settings(max_examples=examples(200), deadline=None)
def test_whole_number_x_gets_whole_ticks_and_at_least_a_unit_of_range(x: np.ndarray) -> None:
    data = (x, np.ones_like(x))
    axis = _x_axis(data, LINEAR_SCALES)
    assert axis.get("incrs") == WHOLE_INCRS and all(i == round(i) and i >= 1 for i in WHOLE_INCRS)
    pinned = fit_scales(data, SERIES, LINEAR_SCALES)["x"].get("range")
    assert isinstance(pinned, tuple)
    lo, hi = float(pinned[0] or 0.0), float(pinned[1] or 0.0)
    assert lo == x.min() and hi == max(x.max(), x.min() + 1.0)
    for px in (160.0, 300.0, 800.0):
        ticks = _whole_ticks(lo, hi, WHOLE_INCRS, px)
        assert ticks and all(t == round(t) and lo <= t <= hi for t in ticks)
    # The label at the right end fits in the padding right of the plot (half a label and a margin; the y axis
    # holds the left end's).
    _, padding = fit_layout(data, SERIES, LINEAR_SCALES, None)
    assert padding[1] >= max(label_px(f"{lo:,.0f}"), label_px(f"{hi:,.0f}")) / 2.0 + 3


@given(
    x=st.lists(st.floats(-1e6, 1e6, allow_nan=False), min_size=1, max_size=20).filter(
        lambda v: any(value != round(value) for value in v)
    )
)
@settings(max_examples=examples(100), deadline=None)
def test_fractional_x_keeps_uplot_s_own_ticks(x: list[float]) -> None:
    data = (np.array(sorted(x)), np.ones(len(x)))
    assert "incrs" not in _x_axis(data, LINEAR_SCALES)


@pytest.mark.parametrize(
    ("x", "widest"),
    [([5e-324], "0.000"), ([-5e-324, 5e-324], "-0.000"), ([0.0, 1e-310], "0.000"), ([1e-320, 2e-320, 0.5], "0.50")],
)
def test_subnormal_x_gets_a_label_width_and_uplot_s_own_ticks(x: list[float], widest: str) -> None:
    # Found with fresh examples: a lone x of 5e-324 was divided by a power of ten that underflowed to zero. Values
    # that small print as uPlot's 3-decimal zero.
    data = (np.array(x), np.ones(len(x)))
    assert "incrs" not in _x_axis(data, LINEAR_SCALES)
    assert widest_linear_label(min(x), max(x), 16, 0.0) == widest


@given(
    values=st.lists(st.one_of(st.just(0.0), st.floats(1e-300, 1e300)), min_size=1, max_size=30),
    floor_exponent=st.integers(-12, -1),
)
@settings(max_examples=examples(300), deadline=None)
def test_a_log_axis_never_labels_a_tick_zero(values: list[float], floor_exponent: int) -> None:
    """Zeros clamped to a floor (as the arm does), huge and tiny values: every label is its decade's value."""
    y = np.maximum(np.array(values), 10.0**floor_exponent)
    data = (np.arange(float(len(y))), y)
    axes, _ = fit_layout(data, SERIES, ARM_SCALES, None)
    scale = fit_scales(data, SERIES, ARM_SCALES)["y"]
    low = math.floor(math.log10(y.min()))
    splits, found_labels = axes[1].get("splits"), axes[1].get("values")
    labels = [str(label) for label in found_labels] if isinstance(found_labels, tuple) else None
    if low >= -3:  # uPlot's own labels read right down to "0.001"
        assert splits is None and labels is None and "range" not in scale
        return
    assert splits is not None and labels is not None
    assert 2 <= len(splits) <= LOG_TICKS_MAX and len(labels) == len(splits)
    for value, label in zip(splits, labels, strict=True):
        assert label != "0" and float(label.replace(",", "")) == value
    assert scale.get("range") == (splits[0], splits[-1]) and scale.get("auto") is False
    assert splits[0] <= y.min() and splits[-1] >= y.max()  # every point is inside the pinned range
    assert axes[1].get("size", 0) >= max(label_px(label) for label in labels) + 10 + 5


def test_all_zeros_and_one_point_are_handled() -> None:
    zeros = (np.zeros(5), np.zeros(5))
    assert fit_scales(zeros, SERIES, LINEAR_SCALES)["x"].get("range") == (0.0, 1.0)
    assert whole_numbers(np.array([np.nan, 2.0])) and not whole_numbers(np.array([np.nan]))
    assert log_ticks(1e-6, 1e-6) == ((1e-6, 1e-5), ("1e-6", "1e-5"))
    assert log_ticks(0.001, 10.0) is None
    assert decade_label(-3) == "0.001" and decade_label(-4) == "1e-4" and decade_label(3) == "1,000"
    # A caller's own ticks are kept.
    axes = (viser.uplot.Axis(scale="x", incrs=(0.5,)), viser.uplot.Axis(scale="y", splits=(1.0,)))
    fitted, _ = fit_layout((np.arange(3.0), np.array([0.0, 1e-9, 1.0])), SERIES, ARM_SCALES, axes)
    assert fitted[0].get("incrs") == (0.5,) and fitted[1].get("splits") == (1.0,)
