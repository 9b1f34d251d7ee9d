"""kernels.cycling against analytic values, the seed's own numbers, published measurements and properties."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from helpers import riders
from helpers.properties import examples
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.typing import NDArray

from kernels import cycling

RHO = 1.225
G = 9.81


# ------------------------------------------------------------------------------------------------ air and drafting
def test_air_density_matches_the_seed_formula_and_its_21_percent_claim() -> None:
    assert cycling.air_density(0.0) == pytest.approx(1.225)
    rho_2000 = float(cycling.air_density(2000.0))
    assert rho_2000 == pytest.approx(1.225 * math.exp(-2000 / 8500), rel=1e-12)
    assert rho_2000 == pytest.approx(0.968, abs=5e-4)  # physics notes
    assert 1 - rho_2000 / 1.225 == pytest.approx(0.21, abs=0.005)  # the seed's "about 21 % thinner"


@pytest.mark.parametrize(("gap_m", "reduction"), [(0.0, 0.270), (2.0, 0.153), (5.0, 0.065), (10.0, 0.016)])
def test_seed_draft_factor_gives_what_its_formula_gives(gap_m: float, reduction: float) -> None:
    # Not the seed's prose (35 %, 10 %, 4 %): the notes show the formula gives these.
    assert 1 - float(cycling.draft_factor(gap_m)) == pytest.approx(reduction, abs=6e-4)


def test_measured_model_matches_team_pursuit_drag_data_at_close_gap() -> None:
    reduction = cycling.drag_reduction(4, 0.3, "measured")
    # Barry et al. 2015 / Fitton et al. 2018: positions 1-4 save ~4-5 / 42-45 / 48-55 / 47-57 %.
    assert 0.01 <= reduction[0] <= 0.05
    assert reduction[1] == pytest.approx(0.435, abs=0.05)
    assert reduction[2] == pytest.approx(0.515, abs=0.06)
    assert reduction[3] == pytest.approx(0.52, abs=0.06)


def test_measured_model_fades_with_gap_like_swiss_side_cfd() -> None:
    # Swiss Side: one TT follower saves ~36 % at 0.1 m and ~13 % at 10 m; the leader's gain is gone by 5 m.
    near = cycling.drag_reduction(2, 0.1, "measured")
    far = cycling.drag_reduction(2, 10.0, "measured")
    assert near[1] == pytest.approx(0.36, abs=0.05)
    assert far[1] == pytest.approx(0.13, abs=0.03)
    assert cycling.drag_reduction(2, 5.0, "measured")[0] < 0.002


@given(n=st.integers(2, 12), gap=st.floats(0.0, 20.0))
@settings(max_examples=examples(60), deadline=None)
def test_measured_model_is_monotone_in_position_and_gap(n: int, gap: float) -> None:
    reduction = cycling.drag_reduction(n, gap, "measured")
    assert np.all(np.diff(reduction[1:]) >= 0.0)  # further back saves at least as much
    assert 0.0 < reduction[0] < reduction[1]  # the leader saves a little, less than the second
    wider = cycling.drag_reduction(n, gap + 0.5, "measured")
    assert np.all(wider < reduction)  # every saving fades with the gap


def test_one_rider_gets_no_draft() -> None:
    for model in ("textbook", "measured"):
        assert cycling.drag_reduction(1, 0.0, model).tolist() == [0.0]  # type: ignore[arg-type]


# ------------------------------------------------------------------------------------------------ power
def test_power_components_are_the_textbook_formulas() -> None:
    v, cda, m, crr, grade = 10.0, 0.3, 75.0, 0.005, 0.08
    p = cycling.power(v, cda, m, crr, grade=grade)
    theta = math.atan(grade)
    assert float(p.aero) == pytest.approx(0.5 * RHO * cda * v**3, rel=1e-12)
    assert float(p.rolling) == pytest.approx(crr * m * G * math.cos(theta) * v, rel=1e-12)
    assert float(p.climbing) == pytest.approx(m * G * math.sin(theta) * v, rel=1e-12)
    assert float(p.total) == pytest.approx(float(p.aero + p.rolling + p.climbing), rel=1e-12)


def test_seed_claim_about_90_percent_aero_at_40_kmh() -> None:
    # Physics notes: 88.5 % for CdA 0.32, m 80 kg, Crr 0.004; 85.8 % for CdA 0.25.
    for cda, share in ((0.32, 0.885), (0.25, 0.858)):
        p = cycling.power(40 / 3.6, cda, 80.0, 0.004)
        assert float(p.aero / p.total) == pytest.approx(share, abs=1e-3)


def test_doubling_speed_costs_eight_times_the_aero_power() -> None:
    p = cycling.power(np.array([10.0, 20.0]), 0.3, 80.0, 0.004)
    assert p.aero[1] / p.aero[0] == pytest.approx(8.0, rel=1e-12)


def test_wind_uses_air_speed_squared_with_its_sign() -> None:
    head = cycling.power(10.0, 0.3, 80.0, 0.0, headwind_ms=5.0)
    assert float(head.aero) == pytest.approx(0.5 * RHO * 0.3 * 15.0**2 * 10.0)
    tail = cycling.power(5.0, 0.3, 80.0, 0.0, headwind_ms=-10.0)  # wind faster than the rider pushes
    assert float(tail.aero) == pytest.approx(-0.5 * RHO * 0.3 * 5.0**2 * 5.0)


def test_drivetrain_loss_divides_the_wheel_power() -> None:
    wheel = cycling.power(11.0, 0.3, 80.0, 0.004)
    pedals = cycling.power(11.0, 0.3, 80.0, 0.004, drivetrain_efficiency=0.976)
    assert float(pedals.total) == pytest.approx(float(wheel.total) / 0.976)
    assert float(pedals.aero) == pytest.approx(float(wheel.aero))


def test_a_descent_surplus_is_not_scaled_by_the_drivetrain() -> None:
    p = cycling.power(10.0, 0.3, 80.0, 0.004, grade=-0.1, drivetrain_efficiency=0.9)
    wheel = float(p.aero + p.rolling + p.climbing)
    assert wheel < 0.0
    assert float(p.total) == pytest.approx(wheel)


def test_power_broadcasts_over_arrays() -> None:
    speeds = np.linspace(1.0, 20.0, 5)[:, None]
    grades = np.array([0.0, 0.05, -0.05])[None, :]
    p = cycling.power(speeds, 0.3, 80.0, 0.004, grade=grades)
    assert p.total.shape == (5, 3)
    assert float(p.climbing[2, 1]) == pytest.approx(80 * G * math.sin(math.atan(0.05)) * float(speeds[2, 0]))


# Kind: one field of a result of another type. martin_power's wheel was a numpy scalar where its six other fields
# were 0-d arrays (a sum of 0-d arrays is a scalar); every field is an array of the inputs' broadcast shape.
@pytest.mark.parametrize("speed", [10.0, np.array(10.0), np.array([8.0, 12.0]), np.full((2, 3), 9.0)])
def test_every_power_term_is_an_array_of_the_inputs_shape(speed: float | NDArray[np.float64]) -> None:
    shape = np.shape(speed)
    for result in (cycling.power(speed, 0.3, 80.0, 0.004), cycling.martin_power(speed, 0.3, 80.0, 0.004)):
        for field in dataclasses.fields(result):
            value = getattr(result, field.name)
            assert type(value) is np.ndarray and value.shape == shape, (type(result).__name__, field.name)


@given(
    v=st.floats(0.1, 30.0),
    dv=st.floats(0.01, 5.0),
    cda=riders.cda_m2,
    mass=riders.mass_kg,
    crr=riders.crr,
    grade=st.floats(0.0, 0.2),
    wind=st.floats(0.0, 15.0),
)
@settings(max_examples=examples(100), deadline=None)
def test_power_rises_with_speed(
    v: float, dv: float, cda: float, mass: float, crr: float, grade: float, wind: float
) -> None:
    slow = cycling.power(v, cda, mass, crr, grade=grade, headwind_ms=wind).total
    fast = cycling.power(v + dv, cda, mass, crr, grade=grade, headwind_ms=wind).total
    assert fast > slow


# ------------------------------------------------------------------------------------------------ inverse
def test_speed_for_power_known_flat_case() -> None:
    # With no rolling loss: P = ½ρ·CdA·v³ exactly.
    v = cycling.speed_for_power(300.0, 0.3, 80.0, 0.0)
    assert float(v) == pytest.approx((300.0 / (0.5 * RHO * 0.3)) ** (1 / 3), rel=1e-9)


@given(
    power_w=st.floats(0.0, 1500.0),
    cda=riders.cda_m2,
    mass=riders.mass_kg,
    crr=riders.crr,
    grade=st.floats(-0.15, 0.2),
    altitude=st.floats(0.0, 4000.0),
    wind=st.floats(-15.0, 15.0),
    efficiency=st.floats(0.8, 1.0),
)
@settings(max_examples=examples(200), deadline=None)
def test_speed_for_power_round_trips_to_1e_6(
    power_w: float, cda: float, mass: float, crr: float, grade: float, altitude: float, wind: float, efficiency: float
) -> None:
    args = dict(grade=grade, altitude_m=altitude, headwind_ms=wind, drivetrain_efficiency=efficiency)
    v = float(cycling.speed_for_power(power_w, cda, mass, crr, **args))
    assert v >= 0.0
    if v == 0.0:  # only possible when even standing still needs no power: P(0) = 0 = target
        assert power_w == pytest.approx(0.0, abs=1e-9)
        return
    back = float(cycling.power(v, cda, mass, crr, **args).total)
    assert back == pytest.approx(power_w, rel=1e-6, abs=1e-6)
    # The stable root: a little faster always costs more than this power.
    assert float(cycling.power(v * 1.001 + 1e-6, cda, mass, crr, **args).total) > power_w


@given(v=st.floats(0.5, 25.0), cda=riders.cda_m2, grade=st.floats(0.0, 0.2), wind=st.floats(0.0, 10.0))
@settings(max_examples=examples(100), deadline=None)
def test_speed_from_power_from_speed_is_identity_where_power_is_monotone(
    v: float, cda: float, grade: float, wind: float
) -> None:
    p = cycling.power(v, cda, 80.0, 0.004, grade=grade, headwind_ms=wind).total
    back = float(cycling.speed_for_power(p, cda, 80.0, 0.004, grade=grade, headwind_ms=wind))
    assert back == pytest.approx(v, rel=1e-6)


def test_descent_coasting_speed_is_terminal_velocity() -> None:
    # Zero power down 8 %: gravity along the slope balances drag and rolling: ½ρCdA v² = m g (sin θ − Crr cos θ).
    theta = math.atan(-0.08)
    v = float(cycling.speed_for_power(0.0, 0.3, 80.0, 0.004, grade=-0.08))
    expected = math.sqrt(80 * G * (-math.sin(theta) - 0.004 * math.cos(theta)) / (0.5 * RHO * 0.3))
    assert v == pytest.approx(expected, rel=1e-9)


def test_strong_tailwind_takes_the_largest_root() -> None:
    # 12 m/s tailwind, 50 W: the rider is pushed to near the wind speed and beyond it.
    v = float(cycling.speed_for_power(50.0, 0.4, 80.0, 0.004, headwind_ms=-12.0))
    assert float(cycling.power(v, 0.4, 80.0, 0.004, headwind_ms=-12.0).total) == pytest.approx(50.0, rel=1e-6)
    assert v > 12.0


def test_speed_for_power_broadcasts() -> None:
    v = cycling.speed_for_power(np.array([100.0, 200.0, 400.0]), 0.3, 80.0, 0.004, grade=np.array([[0.0], [0.05]]))
    assert v.shape == (2, 3)
    assert np.all(np.diff(v, axis=1) > 0)
    assert np.all(v[1] < v[0])


# ------------------------------------------------------------------------------------------------ paceline
def test_seed_paceline_gives_every_follower_the_seed_factor() -> None:
    line = cycling.paceline(4, 2.0, 12.0, 0.3, 80.0, 0.004, model="textbook")
    solo = cycling.power(12.0, 0.3, 80.0, 0.004)
    follower = cycling.power(12.0, 0.3 * float(cycling.draft_factor(2.0)), 80.0, 0.004)
    assert line.total.shape == (4,)
    assert line.total[0] == pytest.approx(float(solo.total))
    np.testing.assert_allclose(line.total[1:], float(follower.total), rtol=1e-12)


def test_measured_paceline_power_against_broker_kyle_burke() -> None:
    # Broker, Kyle & Burke 1999, 4-rider team pursuit at 60 km/h: 2nd needs ~71 %, 3rd-4th ~65 % of the leader's power.
    line = cycling.paceline(4, 0.3, 60 / 3.6, 0.21, 85.0, 0.0025, model="measured")
    ratio = line.total / line.total[0]
    assert ratio[1] == pytest.approx(0.71, abs=0.08)
    assert ratio[2] == pytest.approx(0.65, abs=0.1)
    assert ratio[3] == pytest.approx(0.65, abs=0.11)
    assert ratio[3] <= ratio[2] <= ratio[1] < 1.0


# ------------------------------------------------------------------------------------------------ bad input
@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        (dict(speed_ms=float("nan")), "speed_ms"),
        (dict(speed_ms=-1.0), "speed_ms"),
        (dict(cda_m2=0.0), "cda_m2"),
        (dict(cda_m2=float("inf")), "cda_m2"),
        (dict(mass_kg=-80.0), "mass_kg"),
        (dict(crr=-0.001), "crr"),
        (dict(grade=float("nan")), "grade"),
        (dict(altitude_m=float("inf")), "altitude_m"),
        (dict(headwind_ms=float("nan")), "headwind_ms"),
        (dict(drivetrain_efficiency=0.0), "drivetrain_efficiency"),
        (dict(drivetrain_efficiency=1.1), "drivetrain_efficiency"),
        (dict(speed_ms="fast"), "speed_ms"),
    ],
)
def test_power_rejects_bad_input_naming_the_argument(kwargs: dict[str, object], name: str) -> None:
    args: dict[str, object] = dict(speed_ms=10.0, cda_m2=0.3, mass_kg=80.0, crr=0.004)
    args.update(kwargs)
    with pytest.raises(ValueError, match=name):
        cycling.power(**args)  # type: ignore[arg-type]


def test_inverse_and_paceline_reject_bad_input() -> None:
    with pytest.raises(ValueError, match="power_w"):
        cycling.speed_for_power(-5.0, 0.3, 80.0, 0.004)
    with pytest.raises(ValueError, match="n_riders"):
        cycling.paceline(0, 1.0, 10.0, 0.3, 80.0, 0.004)
    with pytest.raises(ValueError, match="n_riders"):
        cycling.paceline(2.5, 1.0, 10.0, 0.3, 80.0, 0.004)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="gap_m"):
        cycling.paceline(3, -1.0, 10.0, 0.3, 80.0, 0.004)
    with pytest.raises(ValueError, match="model"):
        cycling.paceline(3, 1.0, 10.0, 0.3, 80.0, 0.004, model="magic")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="drivetrain_efficiency"):
        cycling.paceline(3, 1.0, 10.0, 0.3, 80.0, 0.004, drivetrain_efficiency=-0.5)
