"""``cycling.speed_for_power`` at its edges (P = 0, tangencies, tiny powers), against a reference
written here: a dense scan of ``cycling.power`` for the last sign change, refined by scipy's brentq."""

from __future__ import annotations

import itertools
import math
import warnings
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
import viser
from helpers import riders
from helpers.properties import examples
from helpers.wsclient import BrowserClient
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

from kernels import cycling
from scenes.peloton import PelotonScene
from server.switcher import SceneSwitcher

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
            lo if f(lo + 1e-12) > 0.0 or i + 1 == len(speeds) else bracketed_root(f, lo + 1e-12, float(speeds[i + 1]))
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
        cda_m2=draw(riders.cda_m2),
        mass_kg=draw(riders.mass_kg),
        crr=crr,
        grade=grade,
        altitude_m=draw(st.sampled_from([0.0, 2000.0])),
        headwind_ms=draw(st.one_of(st.sampled_from([0.0, -1.0, -2.0, -13.5, -15.0]), st.floats(-15.0, 15.0))),
        drivetrain_efficiency=draw(st.sampled_from([1.0, 0.976, 0.8])),
    )


@given(power_w=powers, course=courses())
@settings(max_examples=examples(300), deadline=None)
def test_speed_for_power_is_the_largest_root_everywhere(power_w: float, course: dict[str, float]) -> None:
    v = float(cycling.speed_for_power(power_w, **course))
    assert_is_the_largest_root(v, power_w, **course)


@given(course=courses(), fraction=st.sampled_from([0.5, 1e-3, 1e-9]))
@settings(max_examples=examples(150), deadline=None)
def test_speed_for_power_is_continuous_as_power_goes_to_zero(course: dict[str, float], fraction: float) -> None:
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
        float(cycling.speed_for_power(p[i], 0.32, 80.0, crr[i], grade=grade[i], headwind_ms=wind[i]))
        for i in range(400)
    ]
    np.testing.assert_array_equal(batch, single)


# ------------------------------------------------------------------------------------------------ public inputs
def test_rolling_cancelling_the_grade_carries_the_rider_at_the_tailwind_speed() -> None:
    # Once: returned 0.0 m/s, while 1e-9 W returned 2.00005 m/s.
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
    assert float(cycling.speed_for_power(0.0, 0.32, 80.0, 0.004, headwind_ms=-1.0)) == 0.0  # rolling holds
    # Flat, no rolling, no wind: P = a·v³, so v = ∛(P/a) for the smallest powers too.
    a = 0.5 * 1.225 * 0.32
    for p in (1e-300, 1e-9, 1.0):
        v = float(cycling.speed_for_power(p, 0.32, 80.0, 0.0))
        assert v == pytest.approx((p / a) ** (1 / 3), rel=1e-12)


# ------------------------------------------------------------------------ the domain: overflow, underflow, last ulps
# The kind: finite accepted inputs whose intermediates (P/a, |c|/a, w², m·g·(Crr + grade),
# ρ(h)) overflow or underflow, giving inf or a wrong finite speed, and a stopping rule that quit several ulps short
# where dP/dv is large. Family: every argument at and beyond the ends of SPEED_FOR_POWER_DOMAIN, any finite grade.
DOMAIN = cycling.SPEED_FOR_POWER_DOMAIN
BASE = dict(power_w=100.0, cda_m2=0.32, mass_kg=80.0, crr=0.005, headwind_ms=0.0, altitude_m=0.0)


def solve_without_warnings(**args: float) -> float:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return float(cycling.speed_for_power(**args))


def assert_solves_to_the_nearest_float(v: float, **args: float) -> None:
    """power(v) = P to rounding: 1e-9 relative, 1e-9 W, or the rounding of the sum (1e-13 of its terms' magnitude,
    which the drivetrain efficiency divides) plus two ulps of v."""
    assert math.isfinite(v) and v >= 0.0, v
    target = args.pop("power_w")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        parts = cycling.power(np.array([max(np.nextafter(v, -1.0), 0.0), v, np.nextafter(v, np.inf)]), **args)
    miss = np.abs(parts.total - target)
    scale = np.abs(parts.aero[1]) + np.abs(parts.rolling[1]) + np.abs(parts.climbing[1])
    per_ulp = 0.5 * abs(parts.total[2] - parts.total[0])  # where one ulp of v moves P by more than 1e-9 W
    # The total is the terms' sum over the efficiency: where terms of 10⁹ W cancel to 1 W at η = 0.01, power() itself
    # rounds by 1e-13 of 10¹¹ W, and the root lies within two ulps of v of that (once these were a max, not a sum).
    rounding = 1e-13 * scale / float(args.get("drivetrain_efficiency", 1.0))
    assert miss[1] <= max(1e-9 * target, 1e-9, rounding + 2.0 * per_ulp), (v, parts.total[1], target)
    # (The speed is the root to a few ulps; the nearest float is not promised: near v the float power() rounds
    # by about an ulp of v itself.)


def edge(name: str) -> st.SearchStrategy[float]:
    low, high = DOMAIN[name]
    inside = st.floats(low, high) | st.sampled_from([low, high, 0.5 * (low + high)])
    return inside.filter(lambda x: name not in ("cda_m2", "mass_kg") or x > 0.0)


@given(
    power_w=edge("power_w") | tiny_powers,
    cda_m2=edge("cda_m2"),
    mass_kg=edge("mass_kg") | st.sampled_from([5e-324, 1e-300, 80.0]),
    crr=edge("crr"),
    grade=st.floats(allow_nan=False, allow_infinity=False) | st.sampled_from([-1.7e308, 1.7e308, -1e10, 0.0]),
    altitude_m=edge("altitude_m"),
    headwind_ms=edge("headwind_ms") | st.sampled_from([-300.0, -1000.0, 1000.0]),
    drivetrain_efficiency=st.sampled_from([1.0, 0.9, 0.01]),
)
@settings(max_examples=examples(400), deadline=None)
def test_speed_for_power_is_finite_and_exact_over_its_whole_domain(**args: float) -> None:
    v = solve_without_warnings(**args)
    assert_solves_to_the_nearest_float(v, **args)


@given(
    name=st.sampled_from(sorted(DOMAIN)),
    side=st.sampled_from([-1.0, 1.0]),
    beyond=st.floats(1e-9, 1.0) | st.sampled_from([1e3, 1e150, 1e300]),
)
@settings(max_examples=examples(200), deadline=None)
def test_speed_for_power_rejects_values_outside_its_domain_by_name(name: str, side: float, beyond: float) -> None:
    low, high = DOMAIN[name]
    end = high if side > 0.0 else low
    value = end + side * max(beyond * max(abs(end), 1.0), 1e-300)
    if side < 0.0 and name in ("cda_m2", "mass_kg"):
        value = min(value, low * (1.0 - 1e-9)) if low > 0.0 else -beyond
    args = dict(BASE, **{name: value})
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError, match=name):
            cycling.speed_for_power(**args)


# The reviewer's inputs (args 0.32 m², 80 kg, Crr 0.005 unless shown), each with its right value.
@pytest.mark.parametrize(
    "name, value",
    [
        ("headwind_ms", 1e155),  # returned 8.47 m/s, the no-wind speed
        ("headwind_ms", 1e200),
        ("headwind_ms", 1.7e308),
        ("headwind_ms", -1.7e308),  # returned inf
        ("power_w", 1.7e308),  # returned inf (P/a overflowed)
        ("altitude_m", 1e300),  # returned inf (density underflowed to 0)
        ("altitude_m", -1e300),  # returned 0.0 (density overflowed)
        ("cda_m2", 5e-324),  # returned inf
        ("cda_m2", 1e-300),  # warned
    ],
)
def test_absurd_inputs_are_refused_by_name(name: str, value: float) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError, match=name):
            cycling.speed_for_power(**dict(BASE, **{name: value}))


@pytest.mark.parametrize("grade", [-1.7e308, -1e300, -1e10])
def test_a_vertical_descent_falls_at_terminal_velocity(grade: float) -> None:
    # m·g·(Crr + grade) overflowed to −inf (returned inf). A vertical road: gravity m·g against drag a·v², so
    # at 0 W v = √(m·g / a) = 63.278 m/s, and at 100 W the root of v·(a·v² − m·g) = 100.
    a = 0.5 * 1.225 * 0.32
    v0 = solve_without_warnings(**dict(BASE, power_w=0.0, grade=grade))
    assert v0 == pytest.approx(math.sqrt(80.0 * 9.81 / a), rel=1e-12)
    assert v0 == pytest.approx(63.27781312, rel=1e-9)
    v = solve_without_warnings(**dict(BASE, grade=grade))
    root = brentq(lambda x: x * (a * x * x - 80.0 * 9.81) - 100.0, 63.0, 64.0, xtol=1e-13)
    assert v == pytest.approx(root, rel=1e-12)


def test_an_efficiency_below_a_thousandth_is_refused_and_a_thousandth_solves() -> None:
    # A subnormal η: P·η underflowed to nothing in the inverse, and power() overflowed dividing by it.
    for efficiency in (5e-324, 1e-300, 9.99e-4, 0.0):
        with pytest.raises(ValueError, match=r"^drivetrain_efficiency must be in \[0.001, 1\]"):
            cycling.speed_for_power(**dict(BASE, drivetrain_efficiency=efficiency))
        with pytest.raises(ValueError, match=r"^drivetrain_efficiency must be in \[0.001, 1\]"):
            cycling.power(**POWER_BASE, drivetrain_efficiency=efficiency)
    args = dict(BASE, drivetrain_efficiency=1e-3)
    assert_solves_to_the_nearest_float(solve_without_warnings(**args), **args)


@pytest.mark.parametrize(
    "args",
    [
        # Stopped 15 ulps early: power(v) missed 0.001 W by 1.2e-8 W (one ulp of v is 1.5e-9 W here).
        dict(
            power_w=0.001,
            cda_m2=0.3,
            mass_kg=80.0,
            crr=0.008023272163568376,
            grade=0.0749270873968717,
            headwind_ms=-1000.0,
        ),
        # An explore run's case: a 300 m/s tailwind, CdA 4334 m² and 270 t on a grade of 7 at η = 0.01 cancel to
        # 1 W (v = 243.4275 m/s); the check allowed for power()'s rounding before the division by η.
        dict(
            power_w=1.0,
            cda_m2=4334.125,
            mass_kg=269838.0,
            crr=0.0,
            grade=7.0,
            altitude_m=9998.0,
            headwind_ms=-300.0,
            drivetrain_efficiency=0.01,
        ),
    ],
    ids=["a fast tailwind", "huge terms cancelling at a low efficiency"],
)
def test_drawn_cases_solve_to_rounding(args: dict[str, float]) -> None:
    v = solve_without_warnings(**args)
    assert_solves_to_the_nearest_float(v, **dict(args))


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
                    (scene.params.crr, scene.params.grade_pct, scene.params.headwind_ms) == (0.005, -0.5, -2.0)
                    and scene.params.target_power_w == 0.0
                ),
                what="the server to apply the course",
            )
            client.wait_for(
                lambda: any("holds **7.2 km/h**" in str(e["props"].get("_markdown", "")) for e in client.gui.values()),
                what="the client to receive 7.2 km/h",
            )
            assert "**0.0 km/h**" not in scene.speed_out.content
    finally:
        switcher.close()


# ------------------------------------------------------------------------ power and martin_power over their domains
# The kind: a huge but finite input to the forward model (mass 1e308, speed or wind 1e300, altitude −1e6 m, CdA
# 1e200) gave NaN or inf watts, or 10⁵³ W, with only numpy's RuntimeWarning. Family: every corner of each domain,
# any finite grade, gives finite watts without a warning; every argument past either end is refused by name.
POWER_BASE = dict(speed_ms=10.0, cda_m2=0.3, mass_kg=80.0, crr=0.004)
FORWARD = [(cycling.power, cycling.MODEL_DOMAIN), (cycling.martin_power, cycling.MARTIN_DOMAIN)]


@pytest.mark.parametrize(
    ("argument", "value"),
    [
        ("mass_kg", 1e308),
        ("speed_ms", 1e300),
        ("headwind_ms", 1e300),
        ("altitude_m", -1e6),
        ("cda_m2", 1e200),
        ("drivetrain_efficiency", 5e-324),
    ],
)
def test_power_refuses_the_huge_inputs_that_gave_nan_or_inf(argument: str, value: float) -> None:
    with pytest.raises(ValueError, match=f"^{argument} must be in"):
        cycling.power(**{**POWER_BASE, argument: value})


@pytest.mark.parametrize(("function", "domain"), FORWARD, ids=["power", "martin_power"])
@pytest.mark.parametrize("grade", [0.0, 0.3, -1.7e308, 1.7e308])
def test_power_is_finite_at_every_corner_of_its_domain(function: Callable[..., Any], domain: dict, grade: float):
    names = sorted(domain)
    for corner in itertools.product(*[domain[name] for name in names]):
        args = dict(zip(names, corner, strict=True))
        for name in ("mass_kg", "air_density", "wheel_radius_m", "cda_m2"):  # > 0 where the range starts at 0
            if args.get(name) == 0.0:
                args[name] = 5e-324
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            total = function(grade=grade, drivetrain_efficiency=1e-3, **args).total
        assert np.isfinite(total).all(), args


@pytest.mark.parametrize(("function", "domain"), FORWARD, ids=["power", "martin_power"])
@pytest.mark.parametrize("side", [-1.0, 1.0])
@pytest.mark.parametrize("beyond", [1e-6, 1.0, 1e150, 1e300])
def test_power_refuses_every_argument_past_its_domain_by_name(
    function: Callable[..., Any], domain: dict, side: float, beyond: float
) -> None:
    for name, (low, high) in domain.items():
        edge_value = high if side > 0 else low
        value = edge_value + side * max(abs(edge_value), 1.0) * beyond
        with pytest.raises(ValueError, match=f"^{name} must be"):
            function(**{**POWER_BASE, name: value})


# Kind: a refusal that tells a range holding the refused value. −80 kg was told "in [0, 1e+06]" while 0 kg is
# refused ("must be > 0"): every argument that must be > 0 says so for any value ≤ 0, in every function.
@pytest.mark.parametrize(("function", "domain"), FORWARD, ids=["power", "martin_power"])
@pytest.mark.parametrize("value", [0.0, -0.0, -5e-324, -80.0, -1.7e308])
def test_an_argument_that_must_be_positive_says_so_for_any_value_not_above_zero(
    function: Callable[..., Any], domain: dict, value: float
) -> None:
    positive = [name for name in domain if name in ("mass_kg", "cda_m2", "air_density", "wheel_radius_m")]
    assert "mass_kg" in positive and "cda_m2" in positive
    for name in positive:
        with pytest.raises(ValueError, match=rf"^{name} must be > 0, got "):
            function(**{**POWER_BASE, name: value})
    for name in ("mass_kg", "cda_m2"):
        with pytest.raises(ValueError, match=rf"^{name} must be > 0, got "):
            cycling.speed_for_power(250.0, **{**{k: POWER_BASE[k] for k in ("cda_m2", "mass_kg", "crr")}, name: value})


@pytest.mark.parametrize(
    ("call", "message"),
    [
        # One speed or gap for the group: an array raised numpy's "only 0-dimensional arrays" TypeError.
        (lambda: cycling.paceline(3, 1.0, [10.0, 11.0], 0.3, 80.0, 0.004), "^speed_ms must be a finite number"),  # type: ignore[arg-type]
        (lambda: cycling.formation_power([[0, 0], [-2, 0]], [10.0, 11.0], 0.3, 80, 0.004), "^speed_ms must be"),  # type: ignore[arg-type]
        (lambda: cycling.paceline(2, [1.0, 2.0], 10.0, 0.3, 80.0, 0.004), "^gap_m must be a finite number"),  # type: ignore[arg-type]
        # 10¹² riders asked for 7 TiB.
        (lambda: cycling.paceline(10**12, 1.0, 10.0, 0.3, 80.0, 0.004), "^n_riders must be at most 200"),
        (lambda: cycling.drag_reduction(201, 1.0), "^n_riders must be at most 200"),
        # The model was checked only from two riders up.
        (lambda: cycling.paceline(1, 1.0, 10.0, 0.3, 80.0, 0.004, model=None), "^model must be"),  # type: ignore[arg-type]
        (lambda: cycling.drag_reduction(1, 1.0, model="bogus"), "^model must be"),  # type: ignore[arg-type]
    ],
)
def test_a_groups_bad_input_is_refused_by_name(call: Callable[[], object], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        call()


def test_a_group_at_the_cda_floor_is_accepted_though_drafting_takes_it_below() -> None:
    # CdA 1e-6 m² (the range's floor), drafted to 5e-7: refused as "cda_m2 ... got array([9.7e-07, 6.0e-07, ...])".
    line = cycling.paceline(3, 0.0, 10.0, 1e-6, 80.0, 0.004, model="measured")
    alone = cycling.power(10.0, 1e-6, 80.0, 0.004)
    assert np.all(line.total < alone.total) and np.all(np.isfinite(line.total))
    # 2,000 riders packed tight: the drag share falls to 7e-13 of the leader's; the power is rolling alone, finite.
    x = -0.01 * np.arange(2000)
    y = np.where(np.arange(2000) % 2, 0.41, -0.41)
    group = cycling.formation_power(np.column_stack([x, y]), 10.0, 0.3, 80.0, 0.004)
    rolling = float(cycling.power(10.0, 0.3, 80.0, 0.004).rolling)
    assert np.all(group.total >= rolling) and np.all(np.isfinite(group.total))


# Kind: an array for one rider's number in a group leaked numpy's "operands could not be broadcast together".
GROUP_ARGUMENTS = ["cda_m2", "mass_kg", "crr", "grade", "altitude_m", "headwind_ms", "drivetrain_efficiency"]
GROUP_BASE = {"speed_ms": 10.0, "cda_m2": 0.3, "mass_kg": 80.0, "crr": 0.004}
BAD_NUMBERS: list[Any] = [None, "1", True, object(), 1 + 2j, 10**400, math.nan, math.inf, -math.inf]


@pytest.mark.parametrize("value", [[0.3, 0.3, 0.3, 0.3], np.array([0.1, 0.2]), *BAD_NUMBERS])
@pytest.mark.parametrize("name", GROUP_ARGUMENTS)
def test_a_groups_rider_numbers_are_one_number_each(name: str, value: Any) -> None:
    with pytest.raises(ValueError, match=f"^{name} must"):
        cycling.paceline(3, 1.0, **{**GROUP_BASE, name: value})
    with pytest.raises(ValueError, match=f"^{name} must"):
        cycling.formation_power([[0.0, 0.0], [-2.0, 0.0], [-4.0, 0.0]], **{**GROUP_BASE, name: value})


@pytest.mark.parametrize("name", ["cda_m2", "mass_kg", "crr", "grade", "altitude_m", "headwind_ms"])
def test_power_names_the_argument_whose_shape_does_not_broadcast(name: str) -> None:
    # The first argument whose shape does not fit those before it (speed_ms, (3,)) is named.
    args: dict[str, Any] = {**GROUP_BASE, "speed_ms": [8.0, 9.0, 10.0]}
    args[name] = [1.0, 1.0, 1.0, 1.0] if name != "crr" else [0.004] * 4
    with pytest.raises(ValueError, match=f"^{name} must broadcast"):
        cycling.power(**args)


def test_speed_for_power_and_martin_power_name_a_shape_that_does_not_broadcast() -> None:
    with pytest.raises(ValueError, match=r"^mass_kg must broadcast"):
        cycling.speed_for_power([100.0, 200.0, 300.0], 0.3, [80.0, 81.0], 0.004)
    with pytest.raises(ValueError, match=r"^air_density must broadcast"):
        cycling.martin_power([8.0, 9.0, 10.0], 0.3, 80.0, 0.004, air_density=[1.2, 1.1])
    with pytest.raises(ValueError, match=r"^relative_humidity must broadcast"):
        cycling.air_density_weather([10.0, 20.0, 30.0], 1000.0, [0.1, 0.2])


# Kind: an array or a non-string as a string choice raised "truth value of an array is ambiguous".
@pytest.mark.parametrize(
    "value", [None, math.nan, object(), 1, np.array(["textbook", "textbook"]), np.array("textbook")]
)
def test_a_model_or_shape_must_be_one_of_its_strings(value: Any) -> None:
    with pytest.raises(ValueError, match=r"^model must be one of 'textbook', 'measured'"):
        cycling.paceline(3, 1.0, 10.0, 0.3, 80.0, 0.004, model=value)
    with pytest.raises(ValueError, match=r"^model must be one of"):
        cycling.drag_reduction(3, 1.0, model=value)
    with pytest.raises(ValueError, match=r"^model must be one of"):
        cycling.formation_drag([[0.0, 0.0], [-2.0, 0.0]], model=value)
    with pytest.raises(ValueError, match=r"^model must be one of"):
        cycling.formation_power([[0.0, 0.0], [-2.0, 0.0]], 10.0, 0.3, 80.0, 0.004, model=value)
    with pytest.raises(ValueError, match=r"^shape must be one of"):
        cycling.formation(3, value)


# Kind: the exponential atmosphere beyond any air (157 573 kg/m³ at −100 km, inf at −10³⁰⁰ m).
@pytest.mark.parametrize("altitude_m", [-1e300, -1e5, -10_000.001, 30_000.001, 1e300, [0.0, -1e5], *BAD_NUMBERS])
def test_air_density_refuses_an_altitude_off_its_range_by_name(altitude_m: Any) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError, match=r"^altitude_m must"):
            cycling.air_density(altitude_m)


@pytest.mark.parametrize(("altitude_m", "density"), [(-10_000.0, 1.225 * math.exp(10 / 8.5)), (0.0, 1.225)])
def test_air_density_at_the_ends_of_its_range(altitude_m: float, density: float) -> None:
    assert float(cycling.air_density(altitude_m)) == pytest.approx(density, rel=1e-15)
    assert float(cycling.air_density(30_000.0)) == pytest.approx(1.225 * math.exp(-30 / 8.5), rel=1e-15)


def test_an_air_density_message_shows_a_few_values_not_the_array() -> None:
    with pytest.raises(ValueError, match=r"^altitude_m must be in") as refused:
        cycling.air_density(np.full(5000, -1e5))
    assert len(str(refused.value)) < 200


# Kind: road_forces is public and trusted its inputs ((nan, nan) for None, "1", True).
@pytest.mark.parametrize(
    ("mass_kg", "crr", "grade", "name"),
    [
        (None, 0.004, 0.0, "mass_kg"),
        ("80", 0.004, 0.0, "mass_kg"),
        (-80.0, 0.004, 0.0, "mass_kg"),
        (1e300, 0.004, 0.0, "mass_kg"),
        (80.0, "1", 0.0, "crr"),
        (80.0, -0.1, 0.0, "crr"),
        (80.0, 2.0, 0.0, "crr"),
        (80.0, 0.004, True, "grade"),
        (80.0, 0.004, math.nan, "grade"),
        (80.0, 0.004, [0.0, 0.1, 0.2], "grade"),
    ],
)
def test_road_forces_refuse_bad_input_by_name(mass_kg: Any, crr: Any, grade: Any, name: str) -> None:
    with pytest.raises(ValueError, match=f"^{name} must"):
        cycling.road_forces([80.0, 90.0] if name == "grade" and np.ndim(grade) else mass_kg, crr, grade)


def test_road_forces_on_a_slope() -> None:
    rolling, climbing = cycling.road_forces(80.0, 0.004, 0.75)  # a 3-4-5 triangle: cos 0.8, sin 0.6
    assert float(rolling) == pytest.approx(0.004 * 80.0 * cycling.G * 0.8)
    assert float(climbing) == pytest.approx(80.0 * cycling.G * 0.6)


@pytest.mark.parametrize("argument", ["speed_ms", "grade", "drivetrain_efficiency"])
def test_a_ragged_list_is_refused_naming_it_not_as_numpy_s_inhomogeneous_shape(argument: str) -> None:
    values: dict[str, object] = {"speed_ms": 10.0, "cda_m2": 0.32, "mass_kg": 80.0, "crr": 0.004}
    values[argument] = [[1.0, 0.5], [0.5]]
    with pytest.raises(ValueError, match=rf"^{argument} must be an array of real numbers"):
        cycling.power(**values)  # type: ignore[arg-type]


# Kind: one quantity with a different range in each function that takes it. power() refused altitudes below
# −500 m that air_density (down to −10 km, the deepest a course may reach) and the course took.
@pytest.mark.parametrize(
    "call",
    [
        lambda h: cycling.air_density(h),
        lambda h: cycling.power(10.0, 0.3, 80.0, 0.004, altitude_m=h),
        lambda h: cycling.speed_for_power(250.0, 0.3, 80.0, 0.004, altitude_m=h),
        lambda h: cycling.paceline(4, 1.0, 10.0, 0.3, 80.0, 0.004, altitude_m=h),
    ],
    ids=["air_density", "power", "speed_for_power", "paceline"],
)
def test_the_textbook_model_takes_one_altitude_range(call: Callable[[float], object]) -> None:
    low, high = cycling.AIR_DENSITY_ALTITUDE_M
    assert cycling.MODEL_DOMAIN["altitude_m"] == (low, high) == (-10_000.0, 30_000.0)
    for h in (low, -1000.0, high):
        call(h)
    for h in (np.nextafter(low, -math.inf), np.nextafter(high, math.inf)):
        with pytest.raises(ValueError, match=r"altitude_m"):
            call(float(h))


def test_power_at_1000_m_below_sea_level_is_the_formula_with_its_air() -> None:
    rho = 1.225 * math.exp(1000.0 / 8500.0)
    v = 10.0
    expected = 0.5 * rho * 0.3 * v**3 + 0.004 * 80.0 * 9.81 * v  # level road, no wind, efficiency 1 (the default)
    got = float(cycling.power(v, 0.3, 80.0, 0.004, altitude_m=-1000.0).total)
    assert got == pytest.approx(expected, rel=1e-12)
