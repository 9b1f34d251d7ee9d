"""A step too long for the drag is refused by the method's stability limit, before the flight.

Reference: scipy's DOP853 (rtol 1e-10) on the same drag law, written here. Drag alone on a ball with speed |v| has
the velocity Jacobian eigenvalues −k|v| (across the motion) and −2k|v| (along it), k = ½ρA·C_D/m; forward Euler is
stable while 2k|v|·dt ≤ 2 (k|v|·dt ≤ 1: a step never reverses the velocity), classical RK4 while 2k|v|·dt ≤ 2.7853
(Hairer & Wanner, Solving ODEs II, §IV.2).
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from helpers.properties import examples
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from kernels import ball
from kernels.ball.api import _round_down
from scenes.freekick.model import BAND_STEP_S, INTEGRATOR_STEP_S

C_D = 0.25  # FlightConfig's default constant drag coefficient


def _drag_factor(density: float) -> float:
    """k = ½ρA·C_D/m (1/m) of the default ball."""
    return 0.5 * density * math.pi * ball.BALL_RADIUS_M**2 * C_D / ball.BALL_MASS_KG


def _reference_landing(density: float, velocity: np.ndarray, height: float) -> tuple[float, float]:
    """(x where the centre reaches z = 0 (m), time of flight (s)) by DOP853 at rtol 1e-10, no spin."""
    k = _drag_factor(density)

    def rate(_t: float, y: np.ndarray) -> np.ndarray:
        v = y[3:]
        a = -k * np.linalg.norm(v) * v
        a[2] -= ball.G
        return np.concatenate((v, a))

    def ground(_t: float, y: np.ndarray) -> float:
        return y[2]

    ground.terminal = True  # type: ignore[attr-defined]
    ground.direction = -1  # type: ignore[attr-defined]
    start = np.array([0.0, 0.0, height, *velocity])
    solution = solve_ivp(rate, (0.0, 10.0), start, method="DOP853", rtol=1e-10, atol=1e-12, events=ground)
    return float(solution.y_events[0][0][0]), float(solution.t_events[0][0])


def _limit_named(error: ValueError) -> float:
    """The longest dt (s) a refusal names."""
    found = re.search(r"at most ([0-9.e+-]+) s for (euler|rk4)", str(error))
    assert found is not None, str(error)
    return float(found.group(1))


def _refusal(density: float, velocity: np.ndarray, height: float, dt: float, method: ball.Method) -> ValueError:
    with pytest.raises(ValueError, match=r"^dt = ") as caught:
        ball.simulate((0.0, 0.0, height), velocity, (0.0, 0.0, 0.0), air_density=density, dt=dt, method=method)
    return caught.value


# --------------------------------------------------------------------------------------------- the public inputs
@pytest.mark.parametrize(
    ("density", "velocity", "dt"),
    [(1000.0, (10.0, 0.0, 2.0), 0.01), (100.0, (25.0, 0.0, 5.0), 0.05)],
)
def test_the_reported_long_euler_steps_are_refused_with_their_limit(
    density: float, velocity: tuple[float, float, float], dt: float
) -> None:
    v0 = np.array(velocity)
    error = _refusal(density, v0, 1.0, dt, "euler")
    assert str(error).startswith(f"dt = {dt:g} s is too long for this drag: at most ")
    # The flight never goes faster than |v0| here (terminal speed √(g/k) is below it), so the limit is 1/(k·|v0|).
    expected = 1.0 / (_drag_factor(density) * float(np.linalg.norm(v0)))
    assert _limit_named(error) == pytest.approx(expected, rel=1e-2)
    assert _limit_named(error) <= expected
    # Just under the limit the flight is drawn, and lands ahead of the kick, as DOP853's does.
    flight = ball.simulate((0.0, 0.0, 1.0), v0, (0.0, 0.0, 0.0), air_density=density, dt=0.99 * expected)
    x_ref, _ = _reference_landing(density, v0, 1.0)
    assert x_ref > 0.0 and flight.position[-1, 0] > 0.0


def test_rk4_allows_its_longer_stability_interval() -> None:
    v0 = np.array([10.0, 0.0, 2.0])
    euler, rk4 = (_limit_named(_refusal(1000.0, v0, 1.0, 1.0, m)) for m in ("euler", "rk4"))
    assert rk4 / euler == pytest.approx(2.785293563405289 / 2.0, rel=2e-2)


def test_batches_refuse_the_same_kick_the_single_call_refuses() -> None:
    positions, velocities, spins = (
        [[0.0, 0.0, 1.0]] * 2,
        [[5.0, 0.0, 1.0], [25.0, 0.0, 5.0]],
        [[0.0, 0.0, 0.0]] * 2,
    )
    with pytest.raises(ValueError, match=r"^dt = 0.05 s is too long for this drag of kicks \[1\]"):
        ball.simulate_batch(positions, velocities, spins, air_density=100.0, dt=0.05)
    wall, goal = ball.free_kick_panels((0.0, 0.0), (20.0, 0.0), (1.0, 0.0))
    with pytest.raises(ValueError, match=r"^dt = 0.05 s is too long for this drag of kicks \[1\]"):
        ball.simulate_outcomes(positions, velocities, spins, wall, goal, air_density=100.0, dt=0.05)


# --------------------------------------------------------------------------------------------- the family
@given(
    density=st.floats(0.0, math.log(1000.0)).map(math.exp),
    speed=st.floats(1.0, 40.0),
    elevation=st.floats(-0.2, 1.3),
    height=st.floats(0.05, 2.0),
    dt=st.floats(math.log(1e-4), math.log(0.1)).map(math.exp),
    method=st.sampled_from(("euler", "rk4")),
)
@settings(max_examples=examples(60), deadline=None)
def test_a_flight_is_refused_naming_dt_or_lands_ahead_as_the_reference_does(
    density: float, speed: float, elevation: float, height: float, dt: float, method: ball.Method
) -> None:
    v0 = speed * np.array([math.cos(elevation), 0.0, math.sin(elevation)])
    start = (0.0, 0.0, height)
    k = _drag_factor(density)
    try:
        flight = ball.simulate(start, v0, (0.0, 0.0, 0.0), air_density=density, dt=dt, method=method, t_max=10.0)
    except ValueError as error:
        limit = _limit_named(error)
        assert str(error).startswith(f"dt = {dt:g} s is too long for this drag") and limit < dt
        # Not more cautious than the plain bound: the speed never passes √(|v0|² + 2g·z0) (energy), so a step
        # within the method's interval at that speed is stable.
        fastest = math.sqrt(speed**2 + 2.0 * ball.G * height)
        beta = 2.0 if method == "euler" else 2.785293563405289
        assert limit >= 0.99 * beta / (2.0 * k * fastest)
        return
    x_ref, t_ref = _reference_landing(density, v0, height)
    assert flight.ended == "ground"
    x = float(flight.position[-1, 0])
    assert x_ref > 0.0 and x > 0.0  # drag never turns the ball back: nor may a step
    # Tolerance: u = dt / (the kernel's limit) ≤ 1. Each step's drag changes the speed by a factor within about
    # u² of the exact one (Euler: 1 − h against 1/(1 + h), h = k|v|dt ≤ u), over about 1/h steps of fast decay, so
    # the landing moves by up to about u·x_ref; gravity and the end of the flight add the first-order term
    # dt·(|v0| + g·T). RK4 stays far inside the same bound.
    u = dt / _limit_named(_refusal(density, v0, height, 1e3, method))
    assert abs(x - x_ref) <= u * x_ref + dt * (speed + ball.G * t_ref) + 1e-9


# --------------------------------------------------------------------------------------------- the scene
@pytest.mark.parametrize("model", ["constant", "measured"])
@pytest.mark.parametrize("knuckle", [None, 3])
def test_the_free_kick_scene_never_meets_the_limit(model: ball.Model, knuckle: int | None) -> None:
    """The scene's air is sea level (it has no density control); its speeds are 5..40 m/s, spin 0..15 rev/s."""
    steps = [(m, dt) for m, dt in INTEGRATOR_STEP_S.items()] + [("rk4", BAND_STEP_S)]
    for method, dt in steps:
        for speed in (5.0, 40.0):
            for spin_rev_s in (0.0, 15.0):
                for elevation in (-5.0, 50.0):
                    v0 = ball.launch_velocity(speed, math.radians(elevation), 0.0)
                    w0 = ball.spin_vector(spin_rev_s * 1.1, (0.0, 0.0, 1.0))
                    ball.simulate(
                        (0.0, 0.0, ball.BALL_RADIUS_M),
                        v0,
                        w0,
                        method=method,
                        dt=dt,
                        model=model,
                        t_max=4.0,
                        ground_m=ball.BALL_RADIUS_M,
                        knuckle_seed=knuckle,
                    )
                    # A margin of ten: even ten times the step would be accepted.
                    ball.simulate(
                        (0.0, 0.0, ball.BALL_RADIUS_M),
                        v0,
                        w0,
                        method=method,
                        dt=10.0 * dt,
                        model=model,
                        t_max=4.0,
                        ground_m=ball.BALL_RADIUS_M,
                        knuckle_seed=knuckle,
                    )


@pytest.mark.parametrize(("value", "cut"), [(0.0123456, 0.0123), (987.6, 987.0), (5e-324, 5e-324), (1e-320, 1e-320)])
def test_a_printed_limit_is_cut_to_three_digits_even_when_subnormal(value: float, cut: float) -> None:
    # The family of the chart axis's fault: a power of ten under a subnormal value underflows to zero.
    assert _round_down(value) == pytest.approx(cut, rel=1e-12, abs=0.0)
