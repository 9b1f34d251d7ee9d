"""A step too long for the drag is refused by the method's stability limit, before the flight.

Reference: scipy's DOP853 (rtol 1e-10) on the same drag law, written here. Drag alone on a ball with speed |v| has
the velocity Jacobian eigenvalues −k|v| (across the motion) and −2k|v| (along it), k = ½ρA·C_D/m; forward Euler is
stable while 2k|v|·dt ≤ 2 (k|v|·dt ≤ 1: a step never reverses the velocity), classical RK4 while 2k|v|·dt ≤ 2.7853
(Hairer & Wanner, Solving ODEs II, §IV.2).
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable

import numpy as np
import pytest
from helpers.properties import examples
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from kernels import ball
from kernels.ball.api import _round_down, stable_step
from kernels.ball.config import MAX_DT_S
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


def _stability_limit(density: float, velocity: np.ndarray, height: float, method: ball.Method) -> float:
    """The longest stable dt (s) the kernel computes for a spinless kick, as :func:`_refusal` would name it (a step
    long enough to be refused is itself refused for accuracy above 0.1 s, so it is asked for directly)."""
    config = ball.FlightConfig(air_density=density, method=method)
    launch = np.array([0.0, 0.0, height, *velocity, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    return _round_down(stable_step(launch, config.settings, 0.0)[0])


# --------------------------------------------------------------------------------------------- the public inputs
@pytest.mark.parametrize(
    ("density", "velocity", "dt"), [(1000.0, (10.0, 0.0, 2.0), 0.01), (100.0, (25.0, 0.0, 5.0), 0.05)]
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
    euler, rk4 = (_limit_named(_refusal(1000.0, v0, 1.0, 0.1, m)) for m in ("euler", "rk4"))
    assert rk4 / euler == pytest.approx(2.785293563405289 / 2.0, rel=2e-2)


def test_batches_refuse_the_same_kick_the_single_call_refuses() -> None:
    positions, velocities, spins = ([[0.0, 0.0, 1.0]] * 2, [[5.0, 0.0, 1.0], [25.0, 0.0, 5.0]], [[0.0, 0.0, 0.0]] * 2)
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
    dt=st.floats(math.log(1e-4), math.log(MAX_DT_S)).map(lambda u: min(math.exp(u), MAX_DT_S)),  # exp(log(0.1)) > 0.1
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
    u = dt / _stability_limit(density, v0, height, method)
    assert abs(x - x_ref) <= u * x_ref + dt * (speed + ball.G * t_ref) + 1e-9


# --------------------------------------------------------------------------------------------- absurd launches
# The fault's kind: a kick refused before it flies (its step beyond the limit) had its one sample's drag, |v|·v,
# overflow from |v| ≈ 1.3e154 m/s, and the single and on-pitch paths then reported a diverged flight that blamed dt
# alone, where a batch named the limit and the speed. Every path must give the one refusal, naming the velocity.
_WALL, _GOAL = ball.free_kick_panels((0.0, 0.0), (20.0, 0.0), (1.0, 0.0))
_PITCH = ball.Pitch(_GOAL, _WALL, ball.Keeper())
_ALPHA = 2.0 / 3.0  # I/(m·R²) of the ball's thin shell, the pitch's
_C_L = ball.FlightConfig().lift_coefficient


def _q(density: float) -> float:
    """½ρA/m (1/m) of the default ball."""
    return _drag_factor(density) / C_D


def _refusals(velocity: np.ndarray, method: ball.Method, dt: float) -> list[tuple[str, bool]]:
    """Each path's refusal of one kick from (0, 0, 1), and whether it flew on a pitch: alone, alone on a pitch,
    second of a batch, second of a batch judged against a wall and goal, second of a batch on a pitch."""
    start, still = (0.0, 0.0, 1.0), (0.0, 0.0, 0.0)
    pair = np.array([(5.0, 0.0, 1.0), velocity])  # a calm kick, then this one
    calls = [
        (lambda: ball.simulate(start, velocity, still, method=method, dt=dt), False),
        (lambda: ball.simulate(start, velocity, still, method=method, dt=dt, pitch=_PITCH), True),
        (lambda: ball.simulate_batch([start] * 2, pair, [still] * 2, method=method, dt=dt), False),
        (lambda: ball.simulate_outcomes([start] * 2, pair, [still] * 2, _WALL, _GOAL, method=method, dt=dt), False),
        (lambda: ball.simulate_outcomes([start] * 2, pair, [still] * 2, pitch=_PITCH, method=method, dt=dt), True),
    ]
    refusals = []
    for call, on_pitch in calls:
        with pytest.raises(ValueError) as caught:
            call()
        refusals.append((str(caught.value), on_pitch))
    return refusals


def _check_refusals(velocity: np.ndarray, method: ball.Method, dt: float) -> None:
    speed = math.hypot(*velocity)
    refusals = _refusals(velocity, method, dt)
    # The limit β/(2q·C·|v|), β = 2 for Euler and 2.7853 for RK4: the speed only falls from |v0|. C is C_D in free
    # flight without spin; on a pitch C_D + C_L, as a bounce can spin the ball up.
    beta = 2.0 if method == "euler" else 2.785293563405289
    shortest = 5.0 / 1e6  # the default t_max over the most steps a flight takes: no dt may be shorter
    for (message, on_pitch), name, which in zip(
        refusals,
        ["velocity", "velocity", "velocities[1]", "velocities[1]", "velocities[1]"],
        ["", "", " of kicks [1]", " of kicks [1]", " of kicks [1]"],
        strict=True,
    ):
        expected = beta / (2.0 * _q(ball.AIR_DENSITY) * (C_D + (_C_L if on_pitch else 0.0)) * speed)
        assert f"launched at |{name}| = {speed:.3g} m/s;" in message, message  # no spin to name
        limit = _limit_named(ValueError(message))  # cut to three digits
        assert limit == pytest.approx(expected, rel=1e-2) and limit <= expected, message
        assert message.startswith(f"dt = {dt:g} s is too long for this drag{which}: at most "), message
        if expected > 1.01 * shortest or (expected > 0.99 * shortest and f"use a smaller dt or {name}" in message):
            assert f"use a smaller dt or {name}, or" in message, message
        else:  # no step the flight takes is that short: not dt but a t_max that allows one is named
            assert f"so use a smaller {name}, a t_max of at most " in message, message
            found = re.search(r"a t_max of at most ([0-9.e+-]+) s", message)
            assert found is not None, message
            assert float(found.group(1)) == pytest.approx(1e6 * limit, rel=1e-2), message
            assert float(found.group(1)) <= 1e6 * expected, message
    assert refusals[0][0] == refusals[2][0].replace(" of kicks [1]", "").replace("velocities[1]", "velocity")
    assert refusals[2][0] == refusals[3][0]


def test_the_t_max_a_refusal_names_lets_the_kick_fly() -> None:
    # At 1e8 m/s Euler's limit is 7.38e-7 s, under the 5e-6 s a 5 s flight's million steps allow, so the refusal
    # named a dt no flight took. It now names the t_max that allows one: 0.738 s flies, 0.739 s does not.
    with pytest.raises(ValueError, match=r"so use a smaller velocity, a t_max of at most 0\.738 s, or"):
        ball.simulate((0.0, 0.0, 1.0), (1e8, 0.0, 0.0), (0.0, 0.0, 0.0), dt=1e-3)
    flight = ball.simulate((0.0, 0.0, 1.0), (1e8, 0.0, 0.0), (0.0, 0.0, 0.0), t_max=0.738, dt=0.738e-6)
    assert flight.ended == "ground" and np.isfinite(flight.position).all()
    with pytest.raises(ValueError, match=r"^dt = 7\.39e-07 s is too long for this drag: at most 7\.38e-07 s"):
        ball.simulate((0.0, 0.0, 1.0), (1e8, 0.0, 0.0), (0.0, 0.0, 0.0), t_max=0.739, dt=0.739e-6)


@given(
    log_speed=st.floats(math.log(3e7), math.log(1e150)),  # every limit under t_max/10⁶ = 5e-6 s
    method=st.sampled_from(("euler", "rk4")),
    on_pitch=st.booleans(),
)
@settings(max_examples=examples(40), deadline=None)
def test_the_dt_and_t_max_a_refusal_names_are_taken_together(log_speed: float, method: ball.Method, on_pitch: bool):
    # A review: at 1e8 m/s toward a wall (RK4) the refusal named dt 5.14e-7 s and t_max 0.514 s, and that pair was
    # refused in turn: 0.514/5.14e-7 is 1000000.0000000001 in floating point, over the million-step cap.
    velocity = (math.exp(log_speed), 0.0, 0.0)
    with pytest.raises(ValueError) as caught:
        ball.simulate((0.0, 0.0, 1.0), velocity, (0.0, 0.0, 0.0), method=method, dt=1e-3,
                      pitch=_PITCH if on_pitch else None)  # fmt: skip
    message = str(caught.value)
    found = re.search(r"a t_max of at most ([0-9.e+-]+) s", message)
    assert found is not None, message
    config = ball.FlightConfig(dt=_limit_named(caught.value), t_max=float(found.group(1)), method=method)
    assert config.settings[10] <= 1_000_000  # N_STEPS


def test_a_step_count_a_whole_number_but_for_rounding_is_that_number() -> None:
    assert ball.FlightConfig(dt=5.14e-7, t_max=0.514).settings[10] == 1_000_000
    with pytest.raises(ValueError, match=r"^dt must be at least t_max/1000000 = 5\.141e-07 s, got 5\.14e-07"):
        ball.FlightConfig(dt=5.14e-7, t_max=0.5141)


@pytest.mark.parametrize("speed", [1e6, 1.3e154, 1.4e154, 1e200, 1.7e308])
def test_an_absurd_launch_speed_is_refused_naming_the_velocity_on_every_path(speed: float) -> None:
    _check_refusals(np.array([speed, 0.0, 0.0]), "euler", 1e-3)


@given(
    log_speed=st.floats(math.log(2e6), math.log(1.7e308)),  # each method's limit under the shortest dt, 1e-4 s
    direction=st.tuples(*[st.floats(-1.0, 1.0)] * 3).filter(lambda d: math.hypot(*d) > 0.1),
    method=st.sampled_from(("euler", "rk4")),
    dt=st.floats(math.log(1e-4), math.log(0.05)).map(lambda x: min(math.exp(x), 0.05)),  # the longest on a pitch
)
@settings(max_examples=examples(40), deadline=None)
def test_every_path_refuses_a_too_fast_launch_alike(
    log_speed: float, direction: tuple[float, float, float], method: ball.Method, dt: float
) -> None:
    speed = min(math.exp(log_speed), 1.7e308)
    d = np.array(direction) / math.hypot(*direction)
    _check_refusals(speed * d, method, dt)


# --------------------------------------------------------------------------------------------- spin into speed
# The fault's kind: on a pitch a bounce turns spin into speed, which the limit did not count. A ball launched at
# 15 m/s with 1e20 rad/s of backspin left the turf at 4.4e18 m/s and flew on, its 1 ms steps 1e14 times its
# stability limit, to a verdict; at 1e300 rad/s it overflowed and the refusal blamed dt alone.
def _stable_along(flight: ball.Trajectory, dt: float, method: ball.Method) -> bool:
    """Whether every step of a constant-coefficient flight lay inside its method's interval: q(C_D + C_L)|v|·dt ≤
    β/2 at each sample's speed (the Jacobian bound of kernels.ball.aero.max_stable_step)."""
    beta = 2.0 if method == "euler" else 2.785293563405289
    speeds = np.linalg.norm(flight.velocity, axis=1)
    return bool((_q(ball.AIR_DENSITY) * (C_D + _C_L) * speeds * dt <= beta / 2.0).all())


def test_backspin_a_bounce_turns_into_speed_is_refused_naming_the_spin() -> None:
    velocity, spin = (15.0, 0.0, 3.0), (0.0, 1e20, 0.0)
    with pytest.raises(ValueError) as caught:
        ball.simulate((0.0, 0.0, 1.0), velocity, spin, dt=1e-3, pitch=_PITCH)
    message = str(caught.value)
    assert "and spinning at |spin| = 1e+20 rad/s, whose energy a bounce can turn into speed" in message
    # Its limit, about 2e-18 s, is under any step a 5 s flight takes (5e-6 s): a t_max that allows one is named.
    assert "so use a smaller velocity or spin, a t_max of at most 2.0" in message
    # The fastest is the spin's: 2·√α·R·|ω| (the launch's 15.3 m/s is 1e-38 of it in quadrature).
    fastest = 2.0 * math.sqrt(_ALPHA) * ball.BALL_RADIUS_M * 1e20
    expected = 2.0 / (2.0 * _q(ball.AIR_DENSITY) * (C_D + _C_L) * fastest)
    assert _limit_named(caught.value) == pytest.approx(expected, rel=1e-2)
    # In free flight there is nothing to bounce off: the same kick flies, its spin's axis alone mattering.
    assert ball.simulate((0.0, 0.0, 1.0), velocity, spin, dt=1e-3).ended == "ground"
    # A strike's odds and an odds map name their own arguments.
    for call in (
        lambda: ball.strike_odds((-20.0, 0.0, 0.11), 25.0, 0.3, 0.05, (0.0, 1e300, 0.0), _PITCH, n=20),
        lambda: ball.odds_map([20.0], [0.0], 25.0, 0.3, 0.05, (0.0, 1e300, 0.0), n=8),
    ):
        with pytest.raises(
            ValueError,
            match=r"of strikes \[0, 1, 2, 3, 4\]: .* so use a smaller speed_ms or spin_rads, a t_max of at most",
        ):
            call()
    # Where a shorter step would do, the step is refused.
    with pytest.raises(ValueError, match=r"of strikes \[0, 1, 2, 3, 4\]: .* use a smaller dt, speed_ms or spin_rads"):
        ball.strike_odds((-20.0, 0.0, 0.11), 25.0, 0.3, 0.05, (0.0, 1e6, 0.0), _PITCH, n=20)


@given(
    speed=st.floats(5.0, 40.0),
    elevation=st.floats(-0.1, 0.6),
    log_spin=st.floats(0.0, math.log(1e8)),
    axis=st.tuples(*[st.floats(-1.0, 1.0)] * 3).filter(lambda a: math.hypot(*a) > 0.1),
    dt=st.floats(math.log(1e-4), math.log(0.05)).map(lambda x: min(math.exp(x), 0.05)),
    method=st.sampled_from(("euler", "rk4")),
)
@settings(max_examples=examples(60), deadline=None)
def test_a_flight_on_a_pitch_is_refused_or_stays_within_its_stability_limit(
    speed: float, elevation: float, log_spin: float, axis: tuple[float, float, float], dt: float, method: ball.Method
) -> None:
    velocity = speed * np.array([math.cos(elevation), 0.0, math.sin(elevation)])
    spin = math.exp(log_spin) * np.array(axis) / math.hypot(*axis)
    try:
        flight = ball.simulate((0.0, 0.0, 0.3), velocity, spin, dt=dt, method=method, pitch=_PITCH, t_max=4.0)
    except ValueError as error:
        assert str(error).startswith(f"dt = {dt:g} s is too long for this drag: at most "), str(error)
        assert _limit_named(error) < dt
        assert f"and spinning at |spin| = {math.exp(log_spin):.3g} rad/s" in str(error)
        return
    assert _stable_along(flight, dt, method)


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
                    # A margin of ten: even ten times the step would be accepted (the band's 20 ms: five times, up
                    # to the accuracy bound MAX_DT_S).
                    ball.simulate(
                        (0.0, 0.0, ball.BALL_RADIUS_M),
                        v0,
                        w0,
                        method=method,
                        dt=min(10.0 * dt, MAX_DT_S),
                        model=model,
                        t_max=4.0,
                        ground_m=ball.BALL_RADIUS_M,
                        knuckle_seed=knuckle,
                    )


@pytest.mark.parametrize(
    ("value", "printed"),
    [
        (0.0123456, "0.0123"),
        (987.6, "987"),
        (1.4399999999999998e-09, "1.43e-09"),  # just under 1.44e-9: its quotient by 1e-11 once rounded up to 144
        (4.345484343042e-307, "4.34e-307"),  # the limit at 1.7e308 m/s; printed as 4.35e-307 once
        (1e-320, "9.99e-321"),  # subnormal: the float is 9.99988…e-321
        (5e-324, "4.94e-324"),  # the smallest float
    ],
)
def test_a_printed_limit_is_cut_to_three_digits_even_when_subnormal(value: float, printed: str) -> None:
    # The family of the chart axis's fault: a power of ten under a subnormal value underflows to zero.
    assert f"{_round_down(value):.3g}" == printed


@given(st.floats(min_value=5e-324, max_value=1.7e308))
@settings(max_examples=examples(500), deadline=None)
def test_a_printed_limit_never_exceeds_the_limit(value: float) -> None:
    """ "At most X s" must be a step the kernel accepts: X, as printed, is never above the limit, and within the
    three digits' resolution of it (coarser among the subnormals, where a float has fewer digits)."""
    printed = float(f"{_round_down(value):.3g}")
    assert printed <= value
    assert printed >= value * (1.0 - 1e-2) or value < 1e-305


# --------------------------------------------------------------------------------------------- a strike's own names
# The kind: a function that scatters one intended kick into many named the batch it built (positions[0],
# spins[0]) where its caller gave position and spin_rads.
@pytest.mark.parametrize(
    ("call", "message"),
    [
        (
            lambda: ball.strike_odds(
                (-20.0, 0.0, 0.11), 25.0, 0.3, 0.0, (0.0, 0.0, 1e20), _PITCH, n=8, model="measured"
            ),
            r"^spin_rads is too fast for the measured model",
        ),
        (
            lambda: ball.odds_map([20.0], [0.0], 25.0, 0.3, 0.0, (0.0, 0.0, 1e20), n=8, model="measured"),
            r"^spin_rads is too fast for the measured model",
        ),
        (
            lambda: ball.strike_odds((-20.0, 0.0, -1.0), 25.0, 0.3, 0.0, (0.0, 0.0, 50.0), _PITCH, n=8),
            r"^position starts below the ground",
        ),
        (
            lambda: ball.strike_odds((25.0, 0.0, 1.0), 25.0, 0.3, 0.0, (0.0, 0.0, 50.0), _PITCH, n=8),
            r"^position must be on the pitch",
        ),
    ],
)
def test_a_strikes_refusal_names_the_arguments_its_caller_gave(call: Callable[[], object], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        call()


@pytest.mark.parametrize("gravity", [1e300, -1e300, 1000.1, math.inf])
def test_an_absurd_gravity_is_refused_naming_it(gravity: float) -> None:
    # 1e300 m/s² overflowed the flight, and the refusal named dt.
    with pytest.raises(ValueError, match=r"^gravity must be"):
        ball.simulate((0.0, 0.0, 1.0), (20.0, 0.0, 5.0), (0.0, 0.0, 0.0), gravity=gravity)
    assert ball.simulate((0.0, 0.0, 1.0), (20.0, 0.0, 5.0), (0.0, 0.0, 0.0), gravity=274.0).ended == "ground"
