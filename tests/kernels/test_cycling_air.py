"""Weather air density, the standard atmosphere and the full Martin et al. (1998) model, against published numbers
and the paper's equations written out here independently."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import riders
from hypothesis import given
from hypothesis import strategies as st

from kernels import cycling

# U.S. Standard Atmosphere 1976 tables, by geometric altitude: (altitude m, pressure hPa, density kg/m³).
US_STANDARD_ATMOSPHERE_1976 = [
    (0.0, 1013.25, 1.2250),
    (1000.0, 898.76, 1.1117),
    (2000.0, 795.01, 1.0066),
    (3000.0, 701.21, 0.90925),
    (5000.0, 540.48, 0.73643),
    (10000.0, 265.00, 0.41351),
    (15000.0, 121.11, 0.19476),
]
# Saturation vapour pressure over water, CRC Handbook of Chemistry and Physics (kPa → hPa).
CRC_SATURATION_HPA = [(0.0, 6.1129), (10.0, 12.282), (20.0, 23.393), (30.0, 42.470), (40.0, 73.849)]


@pytest.mark.parametrize(("altitude", "pressure", "density"), US_STANDARD_ATMOSPHERE_1976)
def test_standard_atmosphere_matches_the_1976_tables(altitude: float, pressure: float, density: float) -> None:
    assert float(cycling.isa_pressure_hpa(altitude)) == pytest.approx(pressure, rel=1e-4)
    rho = cycling.air_density_weather(cycling.isa_temperature_c(altitude), cycling.isa_pressure_hpa(altitude))
    assert float(rho) == pytest.approx(density, rel=2e-4)


def test_isa_temperature_at_the_tropopause_and_above() -> None:
    # 11 km geopotential is 11 019 m geometric: −56.5 °C there and above.
    assert float(cycling.isa_temperature_c(11_019.1)) == pytest.approx(-56.5, abs=1e-3)
    assert float(cycling.isa_temperature_c(18_000.0)) == -56.5
    assert float(cycling.isa_temperature_c(0.0)) == 15.0


def test_the_issue_figures_at_2500_m() -> None:
    """The textbook exponential gives 0.913 kg/m³ at 2 500 m where the standard atmosphere gives 0.957."""
    assert float(cycling.air_density(2500.0)) == pytest.approx(0.913, abs=5e-4)
    isa = cycling.air_density_weather(cycling.isa_temperature_c(2500.0), cycling.isa_pressure_hpa(2500.0))
    assert float(isa) == pytest.approx(0.957, abs=5e-4)


@pytest.mark.parametrize(("temperature", "pressure"), CRC_SATURATION_HPA)
def test_saturation_pressure_against_the_crc_table(temperature: float, pressure: float) -> None:
    assert float(cycling.saturation_vapour_pressure_hpa(temperature)) == pytest.approx(pressure, rel=1e-3)


def mole_fraction_density(t_c: float, p_hpa: float, rh: float) -> float:
    """Moist-air density written the CIPM way, ρ = p·M_a/(R·T)·(1 − x_v·(1 − M_v/M_a)), with Z = 1 and
    the CRC-table-interpolated vapour pressure: an independent route to the same physics."""
    r, m_a, m_v = 8.314462618, 0.0289652, 0.01801528
    table = np.array(CRC_SATURATION_HPA)
    e_s = float(np.interp(t_c, table[:, 0], table[:, 1]))
    x_v = rh * e_s / p_hpa
    return 100.0 * p_hpa * m_a / (r * (t_c + 273.15)) * (1.0 - x_v * (1.0 - m_v / m_a))


@pytest.mark.parametrize(
    ("t_c", "p_hpa", "rh"),
    [(20.0, 1013.25, 0.5), (30.0, 1013.25, 1.0), (0.0, 1013.25, 0.8), (10.0, 850.0, 0.3), (40.0, 950.0, 0.9)],
)
def test_moist_air_density_against_the_mole_fraction_form(t_c: float, p_hpa: float, rh: float) -> None:
    assert float(cycling.air_density_weather(t_c, p_hpa, rh)) == pytest.approx(
        mole_fraction_density(t_c, p_hpa, rh), rel=3e-4
    )


def test_humid_air_is_lighter_by_the_expected_amount() -> None:
    """At 30 °C, saturated air is about 1.5 % lighter than dry air (e ≈ 42.4 hPa, (1 − 0.622)·e/p ≈ 1.6 %)."""
    dry = float(cycling.air_density_weather(30.0, 1013.25, 0.0))
    wet = float(cycling.air_density_weather(30.0, 1013.25, 1.0))
    e = float(cycling.saturation_vapour_pressure_hpa(30.0))
    assert 1.0 - wet / dry == pytest.approx(e / 1013.25 * (1.0 - cycling.R_DRY_AIR / cycling.R_WATER_VAPOUR))
    assert 0.014 < 1.0 - wet / dry < 0.017


@given(
    t=st.floats(-60.0, 60.0),
    p=st.floats(10.0, 1100.0),
    rh=st.floats(0.0, 1.0),
    dt=st.floats(0.1, 10.0),
    drh=st.floats(0.01, 0.5),
)
def test_density_falls_with_heat_and_humidity_and_rises_with_pressure(
    t: float, p: float, rh: float, dt: float, drh: float
) -> None:
    e_max = float(cycling.saturation_vapour_pressure_hpa(60.0))
    if e_max >= p:  # saturated hot air at very low pressure is not air
        rh = min(rh, 0.9 * p / e_max)
    base = float(cycling.air_density_weather(t, p, rh))
    assert base > 0.0 and math.isfinite(base)
    if t + dt <= 60.0:
        assert float(cycling.air_density_weather(t + dt, p, rh)) < base
    if p * 1.01 <= 1100.0:
        assert float(cycling.air_density_weather(t, p * 1.01, rh)) > base
    if rh + drh <= 1.0 and float(cycling.saturation_vapour_pressure_hpa(t)) * (rh + drh) < p:
        assert float(cycling.air_density_weather(t, p, rh + drh)) <= base


@given(h=st.floats(-5000.0, 19_990.0), dh=st.floats(1.0, 10.0))
def test_isa_pressure_falls_with_altitude(h: float, dh: float) -> None:
    assert float(cycling.isa_pressure_hpa(h + dh)) < float(cycling.isa_pressure_hpa(h))


def test_range_edges_are_accepted_and_beyond_them_rejected() -> None:
    for t in (-60.0, 60.0):
        assert math.isfinite(float(cycling.air_density_weather(t, 1013.25, 1.0)))
    for h in (-5000.0, 20_000.0):
        assert math.isfinite(float(cycling.isa_pressure_hpa(h)))
    cases = [
        (lambda: cycling.air_density_weather(60.001, 1013.25), "temperature_c"),
        (lambda: cycling.air_density_weather(float("nan"), 1013.25), "temperature_c"),
        (lambda: cycling.air_density_weather(15.0, 9.99), "pressure_hpa"),
        (lambda: cycling.air_density_weather(15.0, float("inf")), "pressure_hpa"),
        (lambda: cycling.air_density_weather(15.0, 1013.25, 1.0001), "relative_humidity"),
        (lambda: cycling.air_density_weather(15.0, 1013.25, -1e-300), "relative_humidity"),
        (lambda: cycling.air_density_weather(60.0, 100.0, 1.0), "relative_humidity"),
        (lambda: cycling.isa_pressure_hpa(20_000.5), "altitude_m"),
        (lambda: cycling.isa_pressure_hpa(-5000.5), "altitude_m"),
        (lambda: cycling.isa_pressure_hpa("high"), "altitude_m"),
    ]
    for call, name in cases:
        with pytest.raises(ValueError, match=name):
            call()


# ------------------------------------------------------------------------------------------------ Martin et al. 1998
def paper_power(
    v_g: float,
    cda: float,
    m_t: float,
    mu: float,
    g_r: float,
    w: float,
    rho: float,
    e_c: float,
    f_w: float,
    inertia: float,
    r: float,
    v_i: float,
    v_f: float,
    dt: float,
) -> dict[str, float]:
    """Martin et al. (1998), eqs. 2–9 written from the paper, air speed from ahead (V_A = V_G + w ≥ 0)."""
    v_a = v_g + w
    p_at = 0.5 * rho * (cda + f_w) * v_a**2 * v_g
    p_rr = v_g * mu * m_t * 9.81 * math.cos(math.atan(g_r))
    p_wb = v_g * (91.0 + 8.7 * v_g) * 1e-3
    p_pe = v_g * m_t * 9.81 * math.sin(math.atan(g_r))
    p_ke = 0.5 * (m_t + inertia / r**2) * (v_f**2 - v_i**2) / dt
    net = p_at + p_rr + p_wb + p_pe + p_ke
    return {"aero": p_at, "rolling": p_rr, "bearings": p_wb, "climbing": p_pe, "kinetic": p_ke, "total": net / e_c}


@given(
    v=st.floats(0.0, 25.0),
    cda=riders.cda_m2,
    m=riders.mass_kg,
    crr=st.floats(0.0, 0.015),
    grade=st.floats(-0.05, 0.25),
    w=st.floats(0.0, 15.0),
    rho=st.floats(0.6, 1.4),
    a=st.floats(-1.0, 1.5),
)
def test_martin_power_matches_the_paper_term_by_term(
    v: float, cda: float, m: float, crr: float, grade: float, w: float, rho: float, a: float
) -> None:
    dt = 0.5  # the paper's finite-difference kinetic term over [t − dt/2, t + dt/2] at constant acceleration
    ref = paper_power(v, cda, m, crr, grade, w, rho, 0.976, 0.0044, 0.14, 0.311, v - a * dt / 2, v + a * dt / 2, dt)
    got = cycling.martin_power(v, cda, m, crr, grade, w, rho, acceleration_ms2=a)
    for term in ("aero", "rolling", "bearings", "climbing", "kinetic"):
        assert float(getattr(got, term)) == pytest.approx(ref[term], rel=1e-9, abs=1e-9), term
    net = sum(ref[t] for t in ("aero", "rolling", "bearings", "climbing", "kinetic"))
    assert float(got.wheel) == pytest.approx(net, rel=1e-9, abs=1e-9)
    if net > 0:
        assert float(got.total) == pytest.approx(ref["total"], rel=1e-9)
    else:  # nothing passes through the drivetrain when the wheel needs no power
        assert float(got.total) == pytest.approx(net, rel=1e-9, abs=1e-9)


def test_martin_paper_defaults_and_a_hand_number() -> None:
    """10 m/s, CdA 0.30, 80 kg, Crr 0.004, still sea-level air: aero ½·1.225·0.3044·100·10 = 186.4 W,
    rolling 31.39 W, bearings 10·(91 + 87)·10⁻³ = 1.78 W, total 219.6/0.976 = 225.0 W."""
    p = cycling.martin_power(10.0, 0.30, 80.0, 0.004)
    assert float(p.aero) == pytest.approx(186.445, abs=1e-3)
    assert float(p.rolling) == pytest.approx(31.392, abs=1e-3)
    assert float(p.bearings) == pytest.approx(1.78, abs=1e-9)
    assert float(p.total) == pytest.approx((186.445 + 31.392 + 1.78) / 0.976, abs=2e-3)
    # The seed model is Martin's without spokes, bearings and drivetrain: set those off and they agree.
    bare = cycling.martin_power(10.0, 0.30, 80.0, 0.004, drivetrain_efficiency=1.0, spoke_drag_m2=0.0)
    seed = cycling.power(10.0, 0.30, 80.0, 0.004)
    assert float(bare.total) - float(bare.bearings) == pytest.approx(float(seed.total), rel=1e-12)


def test_martin_tailwind_faster_than_the_rider_pushes() -> None:
    p = cycling.martin_power(5.0, 0.3, 80.0, 0.004, headwind_ms=-8.0, spoke_drag_m2=0.0)
    assert float(p.aero) == pytest.approx(-0.5 * 1.225 * 0.3 * 9.0 * 5.0)


def test_martin_broadcasts_and_rejects_bad_arguments() -> None:
    p = cycling.martin_power(np.linspace(0, 20, 5), 0.3, 80.0, 0.004, grade=np.array([[0.0], [0.1]]))
    assert p.total.shape == (2, 5) and p.kinetic.shape == (2, 5)
    for kwargs, name in [
        ({"speed_ms": -1.0}, "speed_ms"),
        ({"air_density": 0.0}, "air_density"),
        ({"wheel_radius_m": 0.0}, "wheel_radius_m"),
        ({"wheel_inertia_kgm2": -0.1}, "wheel_inertia_kgm2"),
        ({"spoke_drag_m2": float("nan")}, "spoke_drag_m2"),
        ({"acceleration_ms2": float("inf")}, "acceleration_ms2"),
        ({"drivetrain_efficiency": 1.2}, "drivetrain_efficiency"),
    ]:
        args = {"speed_ms": 10.0, "cda_m2": 0.3, "mass_kg": 80.0, "crr": 0.004, **kwargs}
        with pytest.raises(ValueError, match=name):
            cycling.martin_power(**args)


def test_the_standard_atmosphere_reaches_down_to_where_its_1976_tables_begin() -> None:
    # The tables (and the troposphere's formula) begin at −5 km; −1000 m was refused. Written out here: geopotential
    # H = r₀h/(r₀ + h), T = 288.15 − 0.0065·H K, p = 1013.25·(T/288.15)^5.25588 hPa.
    h = -5000.0
    geopotential = 6_356_766.0 * h / (6_356_766.0 + h)
    kelvin = 288.15 - 0.0065 * geopotential
    assert kelvin == pytest.approx(320.68, abs=0.01)
    assert float(cycling.isa_temperature_c(h)) == pytest.approx(kelvin - 273.15, abs=1e-9)
    assert float(cycling.isa_pressure_hpa(h)) == pytest.approx(1013.25 * (kelvin / 288.15) ** 5.25588, rel=1e-5)
