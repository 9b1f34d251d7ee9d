"""kernels.ball against analytic flights, a high-accuracy scipy reference, published coefficients and hand-made kicks."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.typing import NDArray
from scipy.integrate import solve_ivp

from kernels import ball

M, R, RHO, G = 0.43, 0.11, 1.225, 9.81
AREA = math.pi * R**2
Q = 0.5 * RHO * AREA / M  # ½ρA/m (1/m)
START = np.array([0.0, 0.0, R])  # ball on the turf
WALL, GOAL = ball.free_kick_panels((0.0, 0.0), (25.0, 0.0), (1.0, 0.0))


def kick(speed: float, elevation_deg: float, azimuth_deg: float = 0.0) -> NDArray[np.float64]:
    return ball.launch_velocity(speed, math.radians(elevation_deg), math.radians(azimuth_deg))


# ------------------------------------------------------------------------------------------------ reference solver
def reference_at_x(
    velocity: NDArray[np.float64],
    spin: NDArray[np.float64],
    x_line: float,
    model: str = "constant",
) -> NDArray[np.float64]:
    """Ball centre where it crosses x = x_line, by scipy's DOP853 at tight tolerances (written independently here)."""
    rate = float(np.linalg.norm(spin))
    axis = spin / rate if rate > 0 else np.zeros(3)

    def rhs(_t: float, y: NDArray[np.float64]) -> NDArray[np.float64]:
        v = y[3:]
        speed = float(np.linalg.norm(v))
        if model == "constant":
            c_d, c_l = 0.25, 0.25
        else:  # Goff & Carré 2010 and a lift slope of 0.9 (see kernels/ball.py's docstring)
            s_param = R * rate / speed
            c_l = 0.9 * min(s_param, 0.3)
            re = RHO * speed * 2 * R / 1.81e-5
            still = 0.155 + 0.346 / (1 + math.exp((re - 1.815e5) / 1.949e4))
            spinning = 0.4127 * max(s_param, 0.05) ** 0.3056
            c_d = still + min(s_param / 0.05, 1.0) * (spinning - still)
        a = -Q * c_d * speed * v + Q * c_l * speed * np.cross(axis, v) + np.array([0.0, 0.0, -G])
        return np.concatenate((v, a))

    def crossing(_t: float, y: NDArray[np.float64]) -> float:
        return float(y[0] - x_line)

    crossing.terminal = True  # type: ignore[attr-defined]
    solution = solve_ivp(
        rhs,
        (0.0, 5.0),
        np.concatenate((START, velocity)),
        method="DOP853",
        rtol=1e-12,
        atol=1e-12,
        events=crossing,
    )
    assert solution.status == 1, "the reference flight must reach the line"
    return solution.y_events[0][0][:3]


CURLER = (kick(28.0, 19.0, -8.0), ball.spin_vector(9.0, (0.0, 0.0, 1.0)))  # a 30 m curler, S ≈ 0.22


def test_seed_euler_at_1ms_is_not_within_a_centimetre_at_30m() -> None:
    velocity, spin = CURLER
    reference = reference_at_x(velocity, spin, 30.0)
    flight = ball.simulate(START, velocity, spin, dt=1e-3, method="euler", x_stop=30.0)
    error = float(np.linalg.norm(flight.position[-1] - reference))
    # The seed claims "accurate to within a centimetre over a 30 m free kick"; its own method misses by more.
    assert 0.010 < error < 0.020
    halved = ball.simulate(START, velocity, spin, dt=5e-4, method="euler", x_stop=30.0)
    # First order: halving the step halves the error.
    assert np.linalg.norm(halved.position[-1] - reference) / error == pytest.approx(0.5, abs=0.05)


@pytest.mark.parametrize("model", ["constant", "measured"])
def test_rk4_at_10ms_is_within_a_tenth_of_a_millimetre_at_30m(model: ball.Model) -> None:
    velocity, spin = CURLER
    reference = reference_at_x(velocity, spin, 30.0, model)
    flight = ball.simulate(START, velocity, spin, dt=1e-2, method="rk4", model=model, x_stop=30.0)
    assert flight.ended == "x_stop"
    assert np.linalg.norm(flight.position[-1] - reference) < 1e-4


# ------------------------------------------------------------------------------------------------ analytic flights
def test_no_air_gives_the_exact_parabola_and_the_seed_euler_its_known_offset() -> None:
    v0 = kick(20.0, 30.0, 10.0)
    spin = ball.spin_vector(8.0, (0.0, 0.0, 1.0))  # no air, so spin does nothing
    exact = ball.simulate(START, v0, spin, dt=0.05, method="rk4", air_density=0.0)
    t = exact.t
    parabola = START + v0 * t[:, None] + 0.5 * np.array([0.0, 0.0, -G]) * t[:, None] ** 2
    np.testing.assert_allclose(exact.position, parabola, atol=1e-10)
    assert exact.ended == "ground"
    assert t[-1] == pytest.approx((v0[2] + math.sqrt(v0[2] ** 2 + 2 * G * R)) / G, abs=1e-12)

    # The seed's Euler (v first, then x) lands g·dt·t/2 low at every sample: z_n = parabola − g·dt·t_n/2.
    dt = 1e-3
    euler = ball.simulate(START, v0, spin, dt=dt, method="euler", air_density=0.0)
    t = euler.t[:-1]
    np.testing.assert_allclose(
        euler.position[:-1, 2], START[2] + v0[2] * t - 0.5 * G * t**2 - 0.5 * G * dt * t, atol=1e-9
    )
    np.testing.assert_allclose(euler.position[:-1, 0], v0[0] * t, atol=1e-9)


def test_drag_alone_decays_speed_exponentially_with_distance() -> None:
    v0 = 30.0
    flight = ball.simulate(
        START, (v0, 0.0, 0.0), (0, 0, 0), dt=2e-3, method="rk4", gravity=0.0, t_max=3.0
    )
    k = RHO * AREA * 0.25 / (2 * M)
    distance = flight.position[:, 0]
    speed = np.linalg.norm(flight.velocity, axis=1)
    assert distance[-1] > 40.0
    np.testing.assert_allclose(speed, v0 * np.exp(-k * distance), rtol=1e-9)
    assert flight.ended == "t_max"


def test_constant_lift_and_drag_without_gravity_fly_a_circle() -> None:
    radius = 2 * M / (RHO * AREA * 0.25)
    assert radius == pytest.approx(73.9, abs=0.1)  # physics notes
    flight = ball.simulate(
        START,
        (30.0, 0.0, 0.0),
        ball.spin_vector(8.0, (0, 0, 1)),
        dt=2e-3,
        method="rk4",
        gravity=0.0,
        t_max=4.0,
    )
    centre = START + np.array([0.0, radius, 0.0])  # spin +z curls a +x kick to the left
    np.testing.assert_allclose(np.linalg.norm(flight.position - centre, axis=1), radius, rtol=1e-9)
    assert flight.position[-1, 1] > 5.0  # it really turned
    np.testing.assert_allclose(flight.position[:, 2], R, atol=1e-12)


@given(
    speed=st.floats(5.0, 35.0),
    elevation=st.floats(-5.0, 60.0),
    azimuth=st.floats(-40.0, 40.0),
    model=st.sampled_from(["constant", "measured"]),
)
@settings(max_examples=25, deadline=None)
def test_zero_spin_never_curls(
    speed: float, elevation: float, azimuth: float, model: ball.Model
) -> None:
    v0 = kick(speed, elevation, azimuth)
    flight = ball.simulate(START, v0, (0, 0, 0), dt=1e-2, method="rk4", model=model)
    across = np.array([-math.sin(math.radians(azimuth)), math.cos(math.radians(azimuth)), 0.0])
    np.testing.assert_allclose(flight.position @ across, 0.0, atol=1e-9)
    np.testing.assert_allclose(flight.magnus, 0.0, atol=0.0)


# ------------------------------------------------------------------------------------------------ directions and sizes
def flight_at(
    x_line: float, velocity: NDArray[np.float64], spin: NDArray[np.float64], **kw: object
):
    return ball.simulate(START, velocity, spin, dt=1e-2, method="rk4", x_stop=x_line, **kw)  # type: ignore[arg-type]


def test_sidespin_about_plus_z_curls_left_topspin_dips_backspin_floats() -> None:
    v0 = kick(25.0, 15.0)
    plain = flight_at(20.0, v0, np.zeros(3)).position[-1]
    curl = flight_at(20.0, v0, ball.spin_vector(8.0, (0, 0, 1))).position[-1]
    top = flight_at(20.0, v0, ball.spin_vector(8.0, (0, 1, 0))).position[-1]
    back = flight_at(20.0, v0, ball.spin_vector(8.0, (0, -1, 0))).position[-1]
    assert curl[1] > 2.0 and plain[1] == 0.0
    assert top[2] < plain[2] - 1.0
    assert back[2] > plain[2] + 1.0


@pytest.mark.parametrize(("speed", "rev_s"), [(25.0, 8.0), (30.0, 10.0), (27.0, 9.0)])
def test_seed_claim_of_3_to_5_m_sideways_over_25_m_holds_with_the_corrected_force(
    speed: float, rev_s: float
) -> None:
    v0 = kick(speed, 16.0)
    curl = flight_at(25.0, v0, ball.spin_vector(rev_s, (0, 0, 1)))
    assert curl.ended == "x_stop"
    assert 3.0 <= curl.position[-1, 1] <= 5.0


def test_measured_coefficients_match_goff_and_carre_and_the_lift_slope() -> None:
    speed = 25.0
    v0 = np.array([speed, 0.0, 0.0])
    dynamic = 0.5 * RHO * AREA * speed**2
    still = ball.simulate(START, v0, np.zeros(3), model="measured", t_max=0.01)
    assert np.linalg.norm(still.drag[0]) / dynamic == pytest.approx(
        0.155, abs=2e-4
    )  # supercritical, no spin
    slow = ball.simulate(START, (8.0, 0.0, 0.0), np.zeros(3), model="measured", t_max=0.01)
    assert np.linalg.norm(slow.drag[0]) / (0.5 * RHO * AREA * 64) == pytest.approx(
        0.49, abs=0.01
    )  # subcritical
    spin = ball.spin_vector(8.0, (0, 0, 1))
    s_param = R * 2 * math.pi * 8.0 / speed
    spinning = ball.simulate(START, v0, spin, model="measured", t_max=0.01)
    assert np.linalg.norm(spinning.drag[0]) / dynamic == pytest.approx(
        0.4127 * s_param**0.3056, rel=1e-9
    )
    assert np.linalg.norm(spinning.magnus[0]) / dynamic == pytest.approx(0.9 * s_param, rel=1e-9)


def test_a_tenth_more_spin_changes_the_flight_only_in_the_measured_model() -> None:
    v0 = kick(25.0, 14.0)
    base = ball.spin_vector(8.0, (0, 0, 1))
    for model, least, most in (("constant", 0.0, 1e-12), ("measured", 0.25, 1.0)):
        y = [flight_at(25.0, v0, spin, model=model).position[-1, 1] for spin in (base, 1.1 * base)]
        assert least <= abs(y[1] - y[0]) <= most, model


def test_forces_are_sampled_with_the_flight() -> None:
    flight = ball.simulate(START, kick(25.0, 15.0), ball.spin_vector(8.0, (0, 0, 1)), dt=1e-3)
    n = len(flight.t)
    assert (
        flight.position.shape
        == flight.drag.shape
        == flight.magnus.shape
        == flight.gravity.shape
        == (n, 3)
    )
    np.testing.assert_allclose(np.diff(flight.t[:-1]), 1e-3, rtol=1e-9)
    assert 0.0 < flight.t[-1] - flight.t[-2] <= 1e-3
    assert flight.ended == "ground" and flight.position[-1, 2] == 0.0
    np.testing.assert_allclose(flight.gravity, np.tile([0.0, 0.0, -M * G], (n, 1)))
    # Drag opposes the velocity; Magnus is perpendicular to it.
    unit = flight.velocity / np.linalg.norm(flight.velocity, axis=1, keepdims=True)
    np.testing.assert_allclose(np.cross(flight.drag, unit), 0.0, atol=1e-12)
    assert np.all(np.einsum("ij,ij->i", flight.drag, unit) < 0)
    np.testing.assert_allclose(np.einsum("ij,ij->i", flight.magnus, unit), 0.0, atol=1e-12)


# ------------------------------------------------------------------------------------------------ outcomes
def judge(speed: float, elevation: float, azimuth: float, rev_s: float = 0.0) -> ball.Outcome:
    spin = ball.spin_vector(rev_s, (0, 0, 1))
    flight = ball.simulate(
        START, kick(speed, elevation, azimuth), spin, dt=1e-2, method="rk4", ground_m=R
    )
    return ball.outcome(flight, WALL, GOAL)


def test_outcomes_of_hand_made_kicks() -> None:
    into_wall = judge(20.0, 8.0, 0.0)
    assert into_wall.result == "wall" and into_wall.wall_point is not None
    assert into_wall.wall_point[0] == pytest.approx(9.15) and into_wall.wall_point[2] < 1.8 + R
    over = judge(30.0, 30.0, 0.0)
    assert over.result == "over" and over.goal_point is not None and over.goal_point[2] > 2.44
    wide = judge(25.0, 17.0, 12.0)
    assert wide.result == "wide" and wide.goal_point is not None and abs(wide.goal_point[1]) > 3.66
    curler = judge(
        25.0, 17.0, -9.0, rev_s=8.0
    )  # round the wall's right end, curled back inside the near post
    assert curler.result == "goal"
    assert curler.wall_point is not None and curler.goal_point is not None
    assert curler.wall_point[2] > 1.8 + R or abs(curler.wall_point[1]) > 1.0 + R
    assert abs(curler.goal_point[1]) < 3.66 - R and curler.goal_point[2] < 2.44 - R
    assert (
        curler.goal_time is not None
        and curler.wall_time is not None
        and curler.goal_time > curler.wall_time
    )
    short = judge(12.0, 20.0, 0.0)
    assert short.result == "short" and short.goal_point is None


def test_wall_clearance_counts_the_ball_radius_and_the_jump() -> None:
    wall_point = judge(25.0, 16.0, 0.0).wall_point
    assert wall_point is not None
    clearance = wall_point[2] - R  # underside of the ball above the ground at the wall
    low_wall, _ = ball.free_kick_panels(
        (0.0, 0.0), (25.0, 0.0), (1.0, 0.0), wall_height_m=clearance - 0.01
    )
    high_wall, _ = ball.free_kick_panels(
        (0.0, 0.0), (25.0, 0.0), (1.0, 0.0), wall_height_m=clearance + 0.01
    )
    flight = ball.simulate(START, kick(25.0, 16.0), np.zeros(3), dt=1e-2, method="rk4", ground_m=R)
    assert ball.outcome(flight, low_wall, GOAL).result != "wall"
    assert ball.outcome(flight, high_wall, GOAL).result == "wall"


# ------------------------------------------------------------------------------------------------ knuckleball
def test_knuckleball_is_reproducible_by_seed_and_zig_zags_about_a_diameter() -> None:
    v0 = kick(25.0, 12.0)
    plain = flight_at(25.0, v0, np.zeros(3))
    assert np.all(plain.knuckle == 0.0)
    first = flight_at(25.0, v0, np.zeros(3), knuckle_seed=7)
    again = flight_at(25.0, v0, np.zeros(3), knuckle_seed=7)
    other = flight_at(25.0, v0, np.zeros(3), knuckle_seed=8)
    np.testing.assert_array_equal(first.position, again.position)
    assert not np.allclose(first.position[-1], other.position[-1], atol=1e-3)
    peaks = []
    for seed in range(30):
        flight = flight_at(25.0, v0, np.zeros(3), knuckle_seed=seed)
        n = min(len(flight.t), len(plain.t))
        peaks.append(np.linalg.norm(flight.position[:n, 1:] - plain.position[:n, 1:], axis=1).max())
    assert 0.11 <= float(np.median(peaks)) <= 0.44  # about one ball diameter (0.22 m)
    # An unsteady force: its lateral component changes sign during the flight.
    assert np.any(np.diff(np.sign(first.knuckle[:, 1])) != 0)


def test_knuckle_force_needs_near_zero_spin() -> None:
    v0 = kick(25.0, 12.0)
    spinning = flight_at(25.0, v0, ball.spin_vector(3.0, (0, 0, 1)), knuckle_seed=7)  # S ≈ 0.08
    assert np.all(spinning.knuckle == 0.0)
    slight = flight_at(25.0, v0, ball.spin_vector(0.5, (0, 0, 1)), knuckle_seed=7)  # S ≈ 0.014
    assert np.abs(slight.knuckle).max() > 0.1


# ------------------------------------------------------------------------------------------------ batch
@pytest.mark.parametrize(
    ("method", "dt", "model"),
    [
        ("rk4", 1e-2, "constant"),
        ("euler", 1e-3, "measured"),
        ("rk4", 5e-3, "measured"),
        ("euler", 1e-3, "constant"),
    ],
)
def test_batch_equals_single_runs(method: ball.Method, dt: float, model: ball.Model) -> None:
    velocities = np.array(
        [kick(25, 16, -9), kick(30, 30, 0), kick(12, 20, 0), kick(25, 12, 0), kick(20, 8, 2)]
    )
    spins = np.array(
        [
            ball.spin_vector(8, (0, 0, 1)),
            np.zeros(3),
            ball.spin_vector(5, (0, 1, 0)),
            np.zeros(3),
            np.zeros(3),
        ]
    )
    positions = np.tile(START, (len(velocities), 1))
    seeds = [None, None, None, 3, None]
    batch = ball.simulate_batch(
        positions,
        velocities,
        spins,
        knuckle_seeds=seeds,
        dt=dt,
        method=method,
        model=model,
        ground_m=R,
        x_stop=26.0,
    )
    judged = ball.outcome_batch(batch, WALL, GOAL)
    results = set()
    for i in range(len(velocities)):
        single = ball.simulate(
            positions[i],
            velocities[i],
            spins[i],
            knuckle_seed=seeds[i],
            dt=dt,
            method=method,
            model=model,
            ground_m=R,
            x_stop=26.0,
        )
        n = batch.n_samples[i]
        assert n == len(single.t)
        np.testing.assert_allclose(batch.t[i, :n], single.t, rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(batch.position[i, :n], single.position, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(batch.velocity[i, :n], single.velocity, rtol=1e-12, atol=1e-12)
        np.testing.assert_array_equal(
            batch.position[i, n:], np.broadcast_to(single.position[-1], (len(batch.t[i]) - n, 3))
        )
        assert batch.ended[i] == single.ended
        single_outcome = ball.outcome(single, WALL, GOAL)
        assert judged.result[i] == single_outcome.result
        results.add(single_outcome.result)
    assert {"goal", "over", "short"} <= results


# ------------------------------------------------------------------------------------------------ invalid input
@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"position": (0.0, math.nan, 0.0)}, "position"),
        ({"velocity": (1.0, 2.0)}, "velocity"),
        ({"spin": (0.0, 0.0, math.inf)}, "spin"),
        ({"dt": 0.0}, "dt"),
        ({"dt": -1e-3}, "dt"),
        ({"dt": math.nan}, "dt"),
        ({"mass_kg": 0.0}, "mass_kg"),
        ({"radius_m": -0.1}, "radius_m"),
        ({"method": "verlet"}, "method"),
        ({"model": "magic"}, "model"),
        ({"t_max": 0.0}, "t_max"),
        ({"drag_coefficient": -0.1}, "drag_coefficient"),
        ({"knuckle_seed": -1}, "knuckle_seed"),
        ({"knuckle_seed": 1.5}, "knuckle_seed"),
        ({"x_stop": math.nan}, "x_stop"),
        ({"dt": 1e-9}, "dt"),
    ],
)
def test_invalid_input_raises_naming_the_argument(kwargs: dict[str, object], name: str) -> None:
    arguments: dict[str, object] = {
        "position": START,
        "velocity": kick(25, 15),
        "spin": (0.0, 0.0, 50.0),
    }
    arguments.update(kwargs)
    with pytest.raises(ValueError, match=name):
        ball.simulate(**arguments)  # type: ignore[arg-type]


def test_batch_rejects_mismatched_rows() -> None:
    with pytest.raises(ValueError, match="velocities"):
        ball.simulate_batch(np.zeros((2, 3)), np.zeros((2, 2)), np.zeros((2, 3)))
    with pytest.raises(ValueError, match="knuckle_seeds"):
        ball.simulate_batch(np.zeros((2, 3)), np.ones((2, 3)), np.zeros((2, 3)), knuckle_seeds=[1])
