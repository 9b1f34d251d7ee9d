"""Issue 8, item 1: ``cycling.speed_for_power`` at its edges (P = 0, tangencies, tiny powers), against a reference
written here: a dense scan of ``cycling.power`` for the last sign change, refined by scipy's brentq."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest
import viser
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq
from wsclient import BrowserClient

from kernels import cycling
from scenes.peloton import PelotonScene
from scenes.switcher import SceneSwitcher

# m/s: every input drawn below needs more than its power here (the reference checks it).
V_MAX = 200.0


def bracketed_root(f: Callable[[float], float], lo: float, hi: float) -> float:
    root, info = brentq(f, lo, hi, xtol=1e-14, maxiter=1000, full_output=True)
    assert info.converged
    return float(root)


def largest_root_reference(power_w: float, **args: float) -> float:
    """Largest v in [0, V_MAX] with power(v) = power_w, by scanning and brentq; independent of the kernel's solver."""

    def f(v: float) -> float:
        return float(cycling.power(v, **args).total) - power_w

    speeds = np.linspace(0.0, V_MAX, 40_001)
    values = cycling.power(speeds, **args).total - power_w
    assert values[-1] > 0.0, "V_MAX too small for this input"
    at_or_below = np.flatnonzero(values <= 0.0)
    if at_or_below.size == 0:
        return 0.0  # cannot happen for P ≥ 0 (power(0) = 0), kept for clarity
    i = int(at_or_below[-1])
    if values[i] == 0.0:
        lo = float(speeds[i])
        # An exact zero on the grid: it is the largest root unless another lies inside the next cell.
        return (
            lo
            if f(lo + 1e-12) > 0.0 or i + 1 == len(speeds)
            else bracketed_root(f, lo + 1e-12, float(speeds[i + 1]))
        )
    return bracketed_root(f, float(speeds[i]), float(speeds[i + 1]))


def assert_is_the_largest_root(v: float, power_w: float, **args: float) -> None:
    assert math.isfinite(v) and v >= 0.0
    back = float(cycling.power(v, **args).total)
    assert abs(back - power_w) <= max(1e-9 * power_w, 1e-9), (v, back, power_w)
    reference = largest_root_reference(power_w, **args)
    # Near a tangency every v within about sqrt(rounding) of the root gives power_w to rounding: 1e-6 m/s of slack.
    assert v == pytest.approx(reference, rel=1e-6, abs=1e-6), (v, reference)


# Inputs from the issue plus their whole family: rolling that cancels the grade exactly (Crr = −grade, or Crr 0 on
# the flat), grades a hair either side of it, tailwinds, zero, subnormal and tiny powers.
crrs = st.one_of(st.sampled_from([0.0, 0.004, 0.005, 0.012]), st.floats(0.0, 0.02))
tiny_powers = st.sampled_from([0.0, 5e-324, 1e-300, 1e-15, 1e-12, 1e-9, 1e-6, 1e-3])
powers = st.one_of(tiny_powers, st.floats(0.0, 1500.0))


@st.composite
def courses(draw: st.DrawFn) -> dict[str, float]:
    crr = draw(crrs)
    grade = draw(
        st.one_of(
            st.just(-crr),  # rolling cancels the grade: a double root of the cubic at v = −w
            st.builds(lambda d: -crr + d, st.sampled_from([-1e-12, 1e-12, -1e-6, 1e-6])),
            st.floats(-0.15, 0.2),
        )
    )
    return dict(
        cda_m2=draw(st.floats(0.1, 0.8)),
        mass_kg=draw(st.floats(40.0, 150.0)),
        crr=crr,
        grade=grade,
        altitude_m=draw(st.sampled_from([0.0, 2000.0])),
        headwind_ms=draw(
            st.one_of(st.sampled_from([0.0, -1.0, -2.0, -13.5, -15.0]), st.floats(-15.0, 15.0))
        ),
        drivetrain_efficiency=draw(st.sampled_from([1.0, 0.976, 0.8])),
    )


@given(power_w=powers, course=courses())
@settings(max_examples=300, deadline=None)
def test_speed_for_power_is_the_largest_root_everywhere(
    power_w: float, course: dict[str, float]
) -> None:
    v = float(cycling.speed_for_power(power_w, **course))
    assert_is_the_largest_root(v, power_w, **course)


@given(course=courses(), fraction=st.sampled_from([0.5, 1e-3, 1e-9]))
@settings(max_examples=150, deadline=None)
def test_speed_for_power_is_continuous_as_power_goes_to_zero(
    course: dict[str, float], fraction: float
) -> None:
    """ε-δ: for δ > 0 every power below power(v(0) + δ) gives a speed within δ above v(0), and never below it."""
    v_zero = float(cycling.speed_for_power(0.0, **course))
    for delta in (1e-2, 1e-4, 1e-6):
        limit = float(cycling.power(v_zero + delta, **course).total)
        assert limit > 0.0  # beyond the largest root more speed costs more power
        v = float(cycling.speed_for_power(fraction * limit, **course))
        assert v_zero <= v <= v_zero + delta


def test_vectorised_call_equals_one_value_at_a_time() -> None:
    rng = np.random.default_rng(3)
    crr = rng.choice([0.0, 0.005], 400)
    grade = np.where(rng.random(400) < 0.5, -crr, rng.uniform(-0.1, 0.1, 400))
    wind = rng.choice([-13.5, -2.0, -1.0, 0.0, 4.0], 400)
    p = rng.choice([0.0, 1e-9, 50.0, 300.0], 400)
    batch = cycling.speed_for_power(p, 0.32, 80.0, crr, grade=grade, headwind_ms=wind)
    single = [
        float(
            cycling.speed_for_power(p[i], 0.32, 80.0, crr[i], grade=grade[i], headwind_ms=wind[i])
        )
        for i in range(400)
    ]
    np.testing.assert_array_equal(batch, single)


# ------------------------------------------------------------------------------------------------ the inputs
def test_rolling_cancelling_the_grade_carries_the_rider_at_the_tailwind_speed() -> None:
    # Issue 8: returned 0.0 m/s, while 1e-9 W returned 2.00005 m/s.
    v = float(cycling.speed_for_power(0.0, 0.32, 80.0, 0.005, grade=-0.005, headwind_ms=-2.0))
    assert v == 2.0
    near = float(cycling.speed_for_power(1e-9, 0.32, 80.0, 0.005, grade=-0.005, headwind_ms=-2.0))
    assert 2.0 < near < 2.0001


@pytest.mark.parametrize("tailwind_ms", [1.0, 13.5])
def test_no_rolling_on_the_flat_carries_the_rider_at_the_tailwind_speed(tailwind_ms: float) -> None:
    v = float(cycling.speed_for_power(0.0, 0.32, 80.0, 0.0, grade=0.0, headwind_ms=-tailwind_ms))
    assert v == tailwind_ms


def test_standing_still_needs_no_power_without_a_push() -> None:
    assert float(cycling.speed_for_power(0.0, 0.32, 80.0, 0.004)) == 0.0
    assert float(cycling.speed_for_power(0.0, 0.32, 80.0, 0.0)) == 0.0
    assert (
        float(cycling.speed_for_power(0.0, 0.32, 80.0, 0.004, headwind_ms=-1.0)) == 0.0
    )  # rolling holds
    # Flat, no rolling, no wind: P = a·v³, so v = ∛(P/a) for the smallest powers too.
    a = 0.5 * 1.225 * 0.32
    for p in (1e-300, 1e-9, 1.0):
        v = float(cycling.speed_for_power(p, 0.32, 80.0, 0.0))
        assert v == pytest.approx((p / a) ** (1 / 3), rel=1e-12)


# ------------------------------------------------------------------------------------------------ the scene's readout
def test_peloton_readout_at_zero_watts_on_a_cancelling_grade(server: viser.ViserServer) -> None:
    """Crr 0.005, grade −0.5 %, headwind −2 m/s, 0 W: the rider is carried at 7.2 km/h (it read 0.0 km/h)."""
    switcher = SceneSwitcher(server, "peloton")
    try:
        scene = switcher.scene
        assert isinstance(scene, PelotonScene)
        with BrowserClient(server.get_port()) as client:
            client.wait_for_gui("Power (W)")
            for label, value in (
                ("Crr", 0.005),
                ("Grade (%)", -0.5),
                ("Headwind (m/s, − = tailwind)", -2.0),
                ("Power (W)", 0.0),
            ):
                client.set_value(label, value)
            client.wait_for(
                lambda: (
                    (scene.params.crr, scene.params.grade_pct, scene.params.headwind_ms)
                    == (0.005, -0.5, -2.0)
                    and scene.params.target_power_w == 0.0
                ),
                what="the server to apply the course",
            )
            client.wait_for(
                lambda: any(
                    "holds **7.2 km/h**" in str(e["props"].get("_markdown", ""))
                    for e in client.gui.values()
                ),
                what="the client to receive 7.2 km/h",
            )
            assert "**0.0 km/h**" not in scene.speed_out.content
    finally:
        switcher.close()
