"""kernels.ball.coefficients against the flight's own forces and the published fits, and kernels.ball.bounce (Cross's
grip–slip impulse model) against FIFA's turf tests, conservation laws and symmetry."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from helpers.properties import examples
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.typing import NDArray

from kernels import ball, warming

M, R, RHO, G = 0.43, 0.11, 1.225, 9.81
AREA = math.pi * R**2
START = np.array([0.0, 0.0, R])
ALPHA = 2.0 / 3.0  # thin shell, I = ⅔·m·R²
ROOT = Path(__file__).resolve().parents[2]


# ------------------------------------------------------------------------------------------------ coefficients
FLIGHTS = {
    # dropped from rest, spinning: under 1 m/s for most of its fall, where the coefficients are held at 1 m/s's
    "measured, dropped spinning": (np.zeros(3), ball.spin_vector(5.0, (0.0, 1.0, 0.0)), {}),
    # a spinless lob that slows through the drag crisis (12.19 m/s) and speeds up again as it falls
    "measured, no spin, through the crisis": (ball.launch_velocity(16.0, math.radians(50.0), 0.0), np.zeros(3), {}),
    "measured, curler": (
        ball.launch_velocity(28.0, math.radians(19.0), math.radians(-8.0)),
        ball.spin_vector(9.0, (0.0, 0.0, 1.0)),
        {},
    ),
    "measured, slow spin (S blended below 0.05)": (
        ball.launch_velocity(20.0, math.radians(30.0), 0.0),
        ball.spin_vector(0.8, (0.0, 1.0, 1.0)),
        {"air_density": 1.1, "radius_m": 0.105},
    ),
    "constant, own values": (
        ball.launch_velocity(25.0, math.radians(15.0), 0.0),
        ball.spin_vector(8.0, (0.0, 0.0, 1.0)),
        {"drag_coefficient": 0.3, "lift_coefficient": 0.2},
    ),
}


@pytest.mark.parametrize("name", sorted(FLIGHTS))
def test_coefficients_are_those_the_flights_forces_use_at_every_sample(name: str) -> None:
    velocity, spin, options = FLIGHTS[name]
    model = "constant" if name.startswith("constant") else "measured"
    flight = ball.simulate(START, velocity, spin, dt=1e-2, method="rk4", model=model, **options)
    radius, density = options.get("radius_m", R), options.get("air_density", RHO)
    speed = np.linalg.norm(flight.velocity, axis=1)
    rate = float(np.linalg.norm(spin))
    c_d, c_l = ball.coefficients(speed, rate, model, **options)
    assert c_d.shape == c_l.shape == speed.shape
    # The force law of kernels.ball: F_drag = −½ρA·C_D·|v|·v, F_Magnus = ½ρA·C_L·|v|·(ω̂ × v).
    half_rho_area = 0.5 * density * math.pi * radius**2
    drag = -half_rho_area * (c_d * speed)[:, None] * flight.velocity
    axis = spin / rate if rate > 0 else np.zeros(3)
    magnus = half_rho_area * (c_l * speed)[:, None] * np.cross(axis, flight.velocity)
    np.testing.assert_allclose(flight.drag, drag, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(flight.magnus, magnus, rtol=1e-12, atol=1e-15)
    if name == "measured, no spin, through the crisis":
        assert speed.min() < 11.0 < 13.5 < speed.max()  # the flight samples both sides of the crisis
        assert c_d.max() - c_d.min() > 0.15


def test_spinless_drag_falls_monotonically_through_the_crisis_as_goff_and_carre_fitted() -> None:
    speed = np.linspace(0.5, 45.0, 900)
    c_d, c_l = ball.coefficients(speed, 0.0)
    assert np.all(c_l == 0.0)
    assert np.all(np.diff(c_d) <= 0.0)  # never rises with speed
    crisis = (speed > 8.0) & (speed < 16.0)
    assert np.all(np.diff(c_d[crisis]) < 0.0)  # strictly falling across the crisis
    # Goff & Carré 2010 (Eur. J. Phys. 31), the no-spin fit in speed for a 0.22 m ball in air of 1.225 kg/m³:
    # C_D = 0.155 + 0.346/(1 + exp((v − 12.19)/1.309)); the kernel's form in Re rounds the centre and the width.
    goff_carre = 0.155 + 0.346 / (1.0 + np.exp((speed - 12.19) / 1.309))
    np.testing.assert_allclose(c_d, goff_carre, atol=2e-3)
    assert ball.coefficients(3.0, 0.0)[0] == pytest.approx(0.501, abs=1e-3)  # subcritical
    assert ball.coefficients(12.19, 0.0)[0] == pytest.approx(0.155 + 0.346 / 2, abs=1e-3)  # mid-crisis
    assert ball.coefficients(30.0, 0.0)[0] == pytest.approx(0.155, abs=1e-4)  # supercritical
    # Hong & Asai 2013 measured the crisis at Re 2.2–3.3·10⁵ for 32-panel balls: by Re 3.3·10⁵ the drag is down.
    re_per_speed = RHO * 2 * R / 1.81e-5
    assert ball.coefficients(3.3e5 / re_per_speed, 0.0)[0] < 0.17


def test_spinning_coefficients_follow_the_published_fits() -> None:
    speed = 25.0
    rates = np.linspace(0.0, 150.0, 301)
    c_d, c_l = ball.coefficients(speed, rates)
    s = R * rates / speed
    np.testing.assert_allclose(c_l, 0.9 * np.minimum(s, 0.3), rtol=1e-12)  # Asai et al. 2007, held beyond S = 0.3
    spinning = s >= 0.05
    np.testing.assert_allclose(c_d[spinning], 0.4127 * s[spinning] ** 0.3056, rtol=1e-12)  # Goff & Carré 2010
    assert np.all(np.abs(np.diff(c_d)) < 0.01)  # continuous: the blend below S = 0.05 meets both fits
    assert c_l[-1] == pytest.approx(0.27)


@pytest.mark.parametrize("speed", [1e150, 1.35e154, 1e200, 1e300, 1e306])
def test_coefficients_hold_at_any_speed(speed: float) -> None:
    # The law is computed from |v|², which overflows past 1.34e154 m/s: C_D read inf there. So far past the drag
    # crisis the measured coefficients depend on S alone (C_D0 = 0.155), and the constant ones on nothing.
    s = np.array([0.0, 0.01, 0.05, 0.2, 0.3, 5.0])
    c_d, c_l = ball.coefficients(speed, s * (speed / R))
    np.testing.assert_allclose(c_l, 0.9 * np.minimum(s, 0.3), rtol=1e-12)  # Asai et al. 2007
    still = 0.155 + 0.346 / (1.0 + math.exp(50.0))  # Goff & Carré 2010, its exponent's argument capped at 50
    blend = still + s / 0.05 * (0.4127 * 0.05**0.3056 - still)
    np.testing.assert_allclose(c_d, np.where(s >= 0.05, 0.4127 * np.maximum(s, 1e-300) ** 0.3056, blend), rtol=1e-12)
    assert ball.coefficients(speed, 1.0, "constant") == (0.25, 0.25)


def test_the_constant_model_gives_its_constants_whatever_the_speed_and_spin() -> None:
    speed, rate = np.array([0.0, 5.0, 12.19, 40.0])[:, None], np.array([0.0, 10.0, 300.0])
    c_d, c_l = ball.coefficients(speed, rate, "constant")
    assert c_d.shape == c_l.shape == (4, 3)
    assert np.all(c_d == 0.25) and np.all(c_l == 0.25)
    c_d, c_l = ball.coefficients(speed, rate, "constant", drag_coefficient=0.3, lift_coefficient=0.1)
    assert np.all(c_d == 0.3) and np.all(c_l == 0.1)


def test_numbers_in_give_floats_out_and_arrays_keep_their_shape() -> None:
    c_d, c_l = ball.coefficients(25, 50)
    assert type(c_d) is float and type(c_l) is float
    c_d, c_l = ball.coefficients(np.float64(25.0), [50.0])
    assert isinstance(c_d, np.ndarray) and c_d.shape == (1,)
    c_d, _ = ball.coefficients(np.empty((0, 2)), 1.0)
    assert c_d.shape == (0, 2)


@pytest.mark.parametrize(
    ("args", "kwargs", "name"),
    [
        ((-1.0, 0.0), {}, "speed_ms"),
        ((math.nan, 0.0), {}, "speed_ms"),
        (([1.0, True], 0.0), {}, "speed_ms"),
        ((True, 0.0), {}, "speed_ms"),
        ((10.0, -1.0), {}, "spin_rads"),
        ((10.0, math.inf), {}, "spin_rads"),
        ((10.0, "fast"), {}, "spin_rads"),
        ((10.0, 1e6), {}, "spin_rads"),  # S = 0.11·10⁶/10 = 1.1·10⁴, beyond the measured model's 10³
        (([1.0, 2.0], [1.0, 2.0, 3.0]), {}, "speed_ms and spin_rads"),
        ((10.0, 1.0, "wind tunnel"), {}, "model"),
        ((10.0, 1.0), {"radius_m": 0.0}, "radius_m"),
        ((10.0, 1.0, "constant"), {"drag_coefficient": -0.1}, "drag_coefficient"),
    ],
)
def test_bad_coefficient_input_raises_naming_the_argument(args: tuple, kwargs: dict, name: str) -> None:
    with pytest.raises(ValueError, match=name):
        ball.coefficients(*args, **kwargs)


def test_a_ball_at_rest_has_a_slow_balls_coefficients_not_the_fits_extrapolation() -> None:
    # Kind: coefficients(0, 10) gave C_D = 239.16. Its range check, like simulate's, counted S = r·|ω|/max(|v|, 1 m/s)
    # = 1.1 and let it through, but the law then took |v| as 10⁻⁹ m/s: S ≈ 10⁹, far past the fits. One spin
    # parameter now, S = r·|ω|/max(|v|, 1 m/s), for the check and the law alike.
    c_d, c_l = ball.coefficients(0, 10, model="measured")
    s = R * 10.0 / 1.0
    assert c_d == pytest.approx(0.4127 * s**0.3056, rel=1e-12) and c_l == 0.27  # Goff & Carré 2010; Asai et al. 2007
    assert ball.coefficients(0.0, 10.0) == ball.coefficients(0.5, 10.0) == ball.coefficients(1.0, 10.0)
    assert ball.coefficients(np.linspace(0.0, 40.0, 41), 60.0)[0].max() < 1.0


def test_the_coefficients_refuse_a_spin_where_simulate_refuses_it() -> None:
    # The boundary is simulate's: S = r·|ω|/max(|v|, 1 m/s) up to 10³, at rest as at speed.
    for speed in (0.0, 0.5, 20.0):
        limit = 1e3 * max(speed, 1.0) / R  # rad/s
        inside, outside = limit * (1.0 - 1e-9), limit * (1.0 + 1e-9)
        c_d, _ = ball.coefficients(speed, inside)
        assert c_d == pytest.approx(0.4127 * 1e3**0.3056, rel=1e-6)  # the fit at S = 10³, finite
        with pytest.raises(ValueError, match=r"^spin_rads is too fast for the measured model: spin parameter S"):
            ball.coefficients(speed, outside)
        velocity = (speed, 0.0, 0.0)
        ball.simulate((0.0, 0.0, 1.0), velocity, (0.0, 0.0, inside), model="measured", t_max=0.05)
        with pytest.raises(ValueError, match=r"^spin is too fast for the measured model: spin parameter S"):
            ball.simulate((0.0, 0.0, 1.0), velocity, (0.0, 0.0, outside), model="measured", t_max=0.05)
    assert ball.coefficients(0.0, 1e9, "constant") == (0.25, 0.25)  # the constant model has no spin parameter


def test_an_unknown_keyword_is_a_type_error() -> None:
    with pytest.raises(TypeError):
        ball.coefficients(10.0, 1.0, wind_ms=3.0)
    with pytest.raises(TypeError):
        ball.coefficients(10.0, 1.0, "measured", model="constant")  # type: ignore[misc]


# ------------------------------------------------------------------------------------------------ bounce
def kinetic_energy(v: NDArray[np.float64], w: NDArray[np.float64], alpha: float, radius: float) -> float:
    """½m|v|² + ½·α·m·R²·|ω|² per unit mass (J/kg)."""
    return 0.5 * float(v @ v) + 0.5 * alpha * radius**2 * float(w @ w)


def angular_momentum_about_contact(
    v: NDArray[np.float64], w: NDArray[np.float64], n: NDArray[np.float64], alpha: float, radius: float
) -> NDArray[np.float64]:
    """I·ω + m·(R·n) × v per unit mass: about the contact point, R·n below the centre."""
    return alpha * radius**2 * w + np.cross(radius * n, v)


def test_fifa_quality_pro_vertical_drop_from_2_m_rebounds_inside_its_band() -> None:
    # FIFA Quality Programme for Football Turf, Handbook of Requirements (2015), vertical ball rebound: a ball
    # dropped from 2 m must rebound 0.60–0.85 m for FIFA Quality Pro. Impact speed √(2·g·2 m) = 6.26 m/s; with
    # e_n = 0.6 the rebound is e_n²·2 m = 0.72 m.
    impact = math.sqrt(2.0 * G * 2.0)
    v, w = ball.bounce((0.0, 0.0, -impact), (0.0, 0.0, 0.0))
    height = v[2] ** 2 / (2.0 * G)
    assert height == pytest.approx(0.72, rel=1e-12)
    assert 0.60 <= height <= 0.85
    np.testing.assert_array_equal(v[:2], 0.0)
    np.testing.assert_array_equal(w, 0.0)


def test_fifa_oblique_test_leaves_at_45_to_60_percent_of_its_speed() -> None:
    # FIFA's angle ball behaviour test on turf (Handbook of Test Methods, 2015): a ball projected at 50 km/h
    # (13.9 m/s) at 25° to the surface, no spin; FIFA Quality Pro asks the ball to leave with 45–60 % of its speed
    # (as compiled in the project's physics notes). By hand with the defaults (e_n 0.6, e_t 0.1, μ 0.6, α ⅔): it
    # grips (|J_t|/m = 1.1·0.4·12.60 = 5.54 < μ·J_n/m = 0.6·1.6·5.87 = 5.64), leaving at (7.05, 0, 3.52) m/s: 56.7 %.
    angle = math.radians(25.0)
    v_in = 13.9 * np.array([math.cos(angle), 0.0, -math.sin(angle)])
    v, w = ball.bounce(v_in, np.zeros(3))
    ratio = float(np.linalg.norm(v)) / 13.9
    assert 0.45 <= ratio <= 0.60
    assert ratio == pytest.approx(0.5674, abs=1e-4)
    assert w[1] > 0.0  # it leaves with topspin (+y for a ball moving along +x)


def test_a_gripping_ball_without_spin_leaves_at_one_over_one_plus_alpha_of_its_tangential_speed() -> None:
    # Cross 2002: with e_t = 0 the ball leaves rolling, v_x' = v_x/(1 + α): 3/5 for a shell, 5/7 for a solid ball.
    for alpha in (ALPHA, 0.4):
        options = {"tangential_restitution": 0.0, "friction": 10.0, "inertia_factor": alpha}
        v, w = ball.bounce((10.0, 0.0, -2.0), (0.0, 0.0, 0.0), **options)
        assert v[0] == pytest.approx(10.0 / (1.0 + alpha), rel=1e-12)
        assert w[1] * R == pytest.approx(v[0], rel=1e-12)  # rolling: ω·R = v_x


def test_a_sliding_ball_takes_exactly_mu_times_the_normal_impulse() -> None:
    # Heavy backspin against a forward ball: the grip impulse would exceed μ·J_n, so it slides.
    mu, e_n = 0.3, 0.6
    v, w = ball.bounce((10.0, 0.0, -4.0), (0.0, -200.0, 0.0), friction=mu, restitution=e_n)
    assert v[0] == pytest.approx(10.0 - mu * (1.0 + e_n) * 4.0, rel=1e-12)
    assert v[2] == pytest.approx(e_n * 4.0, rel=1e-12)
    assert w[1] == pytest.approx(-200.0 + mu * (1.0 + e_n) * 4.0 / (ALPHA * R), rel=1e-12)


def test_topspin_matching_rolling_keeps_the_tangential_velocity_and_spin() -> None:
    # u_t = v_t + ω × (−R·n) = 0 when ω = (0, v_x/R, 0) with n = ẑ: no tangential impulse at all.
    v_in, w_in = np.array([8.0, -3.0, -5.0]), np.array([3.0 / R, 8.0 / R, 7.0])
    v, w = ball.bounce(v_in, w_in)
    np.testing.assert_allclose(v[:2], v_in[:2], rtol=1e-14)
    assert v[2] == pytest.approx(0.6 * 5.0)
    np.testing.assert_allclose(w, w_in, rtol=1e-14)


@pytest.mark.parametrize("case", ["grip, rolling out", "slide"])
def test_angular_momentum_about_the_contact_point_is_conserved(case: str) -> None:
    # Both impulses act at the contact point, so they exert no moment about it (Cross 2002). With e_t = 0 the
    # ball also leaves rolling: u_t' = 0.
    n = np.array([0.3, -0.2, 1.0])
    n /= np.linalg.norm(n)
    v_in, w_in = np.array([6.0, 2.0, -7.0]), np.array([10.0, -40.0, 5.0])
    if case == "slide":
        w_in = np.array([0.0, -400.0, 0.0])
    options = {"tangential_restitution": 0.0, "friction": 5.0} if case != "slide" else {"friction": 0.2}
    v, w = ball.bounce(v_in, w_in, normal=n, **options)
    np.testing.assert_allclose(
        angular_momentum_about_contact(v, w, n, ALPHA, R),
        angular_momentum_about_contact(v_in, w_in, n, ALPHA, R),
        rtol=1e-12,
        atol=1e-12,
    )
    u_in = v_in - (v_in @ n) * n + np.cross(w_in, -R * n)
    u_out = v - (v @ n) * n + np.cross(w, -R * n)
    if case == "slide":
        assert 0.0 < np.linalg.norm(u_out) and u_out @ u_in > 0.0  # still slipping the same way
    else:
        np.testing.assert_allclose(u_out, 0.0, atol=1e-12)


vectors = st.tuples(*[st.floats(-60.0, 60.0)] * 3)
spins = st.tuples(*[st.floats(-400.0, 400.0)] * 3)
normals = st.tuples(*[st.floats(-1.0, 1.0)] * 3).filter(lambda n: math.hypot(*n) > 0.05)


@settings(max_examples=examples(2000))
@given(
    v=vectors,
    w=spins,
    n=normals,
    e_n=st.floats(0.0, 1.0),
    e_t=st.floats(0.0, 1.0),
    mu=st.floats(0.0, 2.0),
    alpha=st.floats(0.05, ALPHA),
    radius=st.floats(0.02, 0.3),
)
def test_kinetic_energy_never_rises(
    v: tuple, w: tuple, n: tuple, e_n: float, e_t: float, mu: float, alpha: float, radius: float
) -> None:
    v_in, w_in = np.array(v), np.array(w)
    unit = np.array(n) / np.linalg.norm(n)
    if v_in @ unit > 0.0:
        v_in = -v_in  # into the surface: an impact, not a ball passing by
    v_out, w_out = ball.bounce(
        v_in,
        w_in,
        normal=n,
        restitution=e_n,
        tangential_restitution=e_t,
        friction=mu,
        inertia_factor=alpha,
        radius_m=radius,
    )
    before = kinetic_energy(v_in, w_in, alpha, radius)
    after = kinetic_energy(v_out, w_out, alpha, radius)
    assert after <= before * (1.0 + 1e-12) + 1e-12
    assert v_out @ unit >= -1e-9  # never left moving into the surface
    np.testing.assert_allclose(  # and the angular momentum about the contact point stays
        angular_momentum_about_contact(v_out, w_out, unit, alpha, radius),
        angular_momentum_about_contact(v_in, w_in, unit, alpha, radius),
        rtol=1e-9,
        atol=1e-9 * (1.0 + radius * (np.abs(v_in).max() + alpha * radius * np.abs(w_in).max())),
    )


def test_mirror_images_bounce_as_mirror_images() -> None:
    # Reflecting in a plane that holds the normal maps v to M·v and the spin (an axial vector) to −M·ω.
    rng = np.random.default_rng(7)
    v_in, w_in = rng.uniform(-20, 20, (200, 3)), rng.uniform(-300, 300, (200, 3))
    v_in[:, 2] = -np.abs(v_in[:, 2])
    v, w = ball.bounce(v_in, w_in)
    for mirror in (np.diag([1.0, -1.0, 1.0]), np.diag([-1.0, 1.0, 1.0])):
        v_m, w_m = ball.bounce(v_in @ mirror, -(w_in @ mirror))
        np.testing.assert_allclose(v_m, v @ mirror, rtol=1e-13, atol=1e-12)
        np.testing.assert_allclose(w_m, -(w @ mirror), rtol=1e-13, atol=1e-12)


# Kind: a norm taken as the root of a sum of squares. From 1e154 m/s the squares overflowed, the slide's impulse
# became −μ·J_n/∞ = 0 and the ball bounced without friction (and below 1e-154 they underflowed the other way).
@pytest.mark.parametrize("power", [-1020, -600, -300, -100, 0, 100, 300, 500, 511, 1000, 1010])
def test_a_bounce_scales_with_its_velocity_and_spin_at_any_magnitude(power: int) -> None:
    """Every term of the impulse is linear in (v, ω) together: scaled by 2^k, the result is scaled by 2^k."""
    rng = np.random.default_rng(power + 2000)
    v_in, w_in = rng.uniform(-20, 20, (100, 3)), rng.uniform(-300, 300, (100, 3))
    v_in[:, 2] = -np.abs(v_in[:, 2])
    v, w = ball.bounce(v_in, w_in)
    scale = math.ldexp(1.0, power)
    v_s, w_s = ball.bounce(v_in * scale, w_in * scale)
    np.testing.assert_allclose(v_s / scale, v, rtol=1e-14, atol=0.0)
    np.testing.assert_allclose(w_s / scale, w, rtol=1e-14, atol=0.0)


# The same family, apart: a spin 10⁴⁰⁰ times the speed made −μ·J_n/|u_t| underflow to 0 (no friction again).
@pytest.mark.parametrize(
    ("speed", "spin"), [(1.0, 1e10), (1e-100, 1e200), (1e-150, 1e150), (1e-160, 1e160), (1e-300, 1e100)]
)
def test_a_ball_spinning_far_faster_than_it_moves_slides_at_any_magnitude(speed: float, spin: float) -> None:
    """The contact point's velocity is the spin's alone, so the ball slides along −û_t set by the spin: the
    velocity after is the speed's scale times one result (μ = 0.6, e_n = 0.6), and the spin barely changes."""
    v_in, w_in = np.array([3.0, 1.0, -5.0]), np.array([10.0, -20.0, 30.0]) / 0.11
    v, w = ball.bounce(speed * v_in, spin * w_in)
    u = np.cross(w_in, [0.0, 0.0, -ball.BALL_RADIUS_M])  # ω × r_c, r_c = −R·n: the contact point's velocity
    expected = v_in + 8.0 * np.array([0.0, 0.0, 1.0]) - 0.6 * 8.0 * u / np.linalg.norm(u)  # J_n/m = 1.6·5
    np.testing.assert_allclose(v / speed, expected, rtol=1e-9)  # u_t is the spin's to 1e-10 at (1, 1e10)
    np.testing.assert_allclose(w / spin, w_in, rtol=1e-8)


def test_a_tilted_surface_bounces_as_the_ground_in_a_rotated_frame() -> None:
    rng = np.random.default_rng(11)
    rotation, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    v_in, w_in = rng.uniform(-20, 20, (50, 3)), rng.uniform(-300, 300, (50, 3))
    v_in[:, 2] = -np.abs(v_in[:, 2])
    v, w = ball.bounce(v_in, w_in)
    normal = rotation @ np.array([0.0, 0.0, 1.0])
    # A proper rotation (det +1) turns axial vectors like polar ones; flip it if QR gave a reflection.
    sign = np.sign(np.linalg.det(rotation))
    v_r, w_r = ball.bounce(v_in @ rotation.T, sign * (w_in @ rotation.T), normal=3.0 * normal)
    np.testing.assert_allclose(v_r, v @ rotation.T, rtol=1e-12, atol=1e-11)
    np.testing.assert_allclose(w_r, sign * (w @ rotation.T), rtol=1e-12, atol=1e-10)


def test_a_ball_moving_away_from_or_along_the_surface_is_unchanged() -> None:
    for v_in in ((3.0, 1.0, 2.0), (5.0, 0.0, 0.0), (0.0, 0.0, 0.0)):
        v, w = ball.bounce(v_in, (1.0, 2.0, 3.0))
        np.testing.assert_array_equal(v, v_in)
        np.testing.assert_array_equal(w, (1.0, 2.0, 3.0))
    # A surface facing down (a ceiling): a falling ball moves away from it.
    v, _ = ball.bounce((0.0, 0.0, -1.0), (0.0, 0.0, 0.0), normal=(0.0, 0.0, -1.0))
    np.testing.assert_array_equal(v, (0.0, 0.0, -1.0))


def test_a_batch_equals_single_impacts_and_shares_a_single_spin() -> None:
    rng = np.random.default_rng(3)
    v_in, w_in = rng.uniform(-20, 20, (40, 3)), rng.uniform(-200, 200, (40, 3))
    options = {"normal": (0.1, 0.2, 1.0), "friction": 0.3, "tangential_restitution": 0.05, "restitution": 0.7}
    v, w = ball.bounce(v_in, w_in, **options)
    assert v.shape == w.shape == (40, 3)
    for k in range(40):
        v_k, w_k = ball.bounce(v_in[k], w_in[k], **options)
        assert v_k.shape == w_k.shape == (3,)
        np.testing.assert_array_equal(v_k, v[k])
        np.testing.assert_array_equal(w_k, w[k])
    v_shared, w_shared = ball.bounce(v_in, w_in[0], **options)
    np.testing.assert_array_equal(v_shared[5], ball.bounce(v_in[5], w_in[0], **options)[0])
    assert w_shared.shape == (40, 3)
    empty_v, empty_w = ball.bounce(np.empty((0, 3)), np.empty((0, 3)))
    assert empty_v.shape == empty_w.shape == (0, 3)


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"velocity": (1.0, math.nan, -1.0)}, "velocity"),
        ({"velocity": (1.0, -1.0)}, "velocity"),
        ({"velocity": np.zeros((2, 4))}, "velocity"),
        ({"velocity": (1.0, True, -1.0)}, "velocity"),
        ({"spin": (0.0, math.inf, 0.0)}, "spin"),
        ({"spin": "topspin"}, "spin"),
        ({"velocity": np.ones((3, 3)), "spin": np.ones((2, 3))}, "velocity and spin"),
        ({"normal": (0.0, 0.0, 0.0)}, "normal"),
        ({"normal": (0.0, 1.0)}, "normal"),
        ({"normal": (0.0, math.nan, 1.0)}, "normal"),
        ({"restitution": 1.2}, "restitution"),
        ({"restitution": -0.1}, "restitution"),
        ({"restitution": math.nan}, "restitution"),
        ({"restitution": True}, "restitution"),
        ({"tangential_restitution": 1.5}, "tangential_restitution"),
        ({"friction": -0.1}, "friction"),
        ({"friction": math.inf}, "friction"),
        ({"radius_m": 0.0}, "radius_m"),
        ({"inertia_factor": 0.0}, "inertia_factor"),
        ({"inertia_factor": 0.7}, "inertia_factor"),
        ({"velocity": (1e200, 0.0, -1e200), "spin": (0.0, 1e200, 0.0), "radius_m": 1e200}, "too large"),
    ],
)
def test_bad_bounce_input_raises_naming_the_argument(kwargs: dict, name: str) -> None:
    arguments = {"velocity": (3.0, 0.0, -2.0), "spin": (0.0, 10.0, 0.0), **kwargs}
    with pytest.raises(ValueError, match=name):
        ball.bounce(**arguments)


# ------------------------------------------------------------------------------------------------ compiled cores
def test_the_plain_python_twins_give_the_compiled_numbers(monkeypatch: pytest.MonkeyPatch) -> None:
    def both() -> list[NDArray[np.float64]]:
        c_d, c_l = ball.coefficients(np.linspace(0.0, 40.0, 41), 60.0)
        v, w = ball.bounce(np.array([[10.0, 2.0, -4.0], [3.0, 0.0, -1.0]]), (0.0, -300.0, 20.0), normal=(0, 0.2, 1))
        return [c_d, c_l, v, w]

    compiled = both()
    monkeypatch.setattr(warming.Entry, "__call__", lambda self, *a, **k: warming.python_twin(self.compiled)(*a, **k))
    for twin, expected in zip(both(), compiled, strict=True):
        np.testing.assert_allclose(twin, expected, rtol=1e-12, atol=1e-14)


WARM_CHECK = """
import numpy as np
from numba.core.registry import CPUDispatcher
from kernels import ball
from kernels.ball import aero, contact

cores = [f for m in (aero, contact) for f in vars(m).values() if isinstance(f, CPUDispatcher)]
ball.warm_up()
before = sum(len(core.signatures) for core in cores)
frozen = np.array([[3.0, 0.0, -2.0]])
frozen.setflags(write=False)
for model in ("constant", "measured"):
    ball.coefficients(12, [0, 10], model)
    ball.coefficients(np.arange(6.0).reshape(2, 3), np.float32(3.0), model, radius_m=0.1)
ball.bounce([1, 0, -2], [0, 3, 0], normal=[0, 1, 1], restitution=1, friction=0)
ball.bounce(frozen, frozen[0], normal=frozen[0])
ball.bounce(np.ones((5, 3)) - 2.0, np.zeros((5, 3), dtype=np.float32))
print(before, sum(len(core.signatures) for core in cores))
"""


def test_after_warm_up_the_coefficients_and_the_bounce_compile_nothing() -> None:
    result = subprocess.run(
        [sys.executable, "-c", WARM_CHECK], cwd=ROOT, capture_output=True, text=True, timeout=600, check=True
    )
    before, after = map(int, result.stdout.split())
    assert before > 0 and after == before
