"""kernels.ball.odds: strike scatter drawn as specified, and the odds of a kick on the pitch."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from kernels import ball
from kernels.ball import odds
from kernels.ball.pitch import pitch_vector

R = ball.BALL_RADIUS_M
OPTIONS = {"dt": 1e-2, "method": "rk4", "model": "measured", "ground_m": R, "t_max": 4.0}
SPIN = ball.spin_vector(9.0, (0.0, 0.0, 1.0))


def test_strikes_scatter_with_the_spreads_asked_for() -> None:
    spread = odds.StrikeSpread(
        speed_ms=1.0, direction_deg=1.5, elevation_deg=1.0, spin_rate_rev_s=0.8, spin_axis_deg=8.0
    )
    velocities, spins = odds.draw_strikes(25.0, math.radians(15.0), math.radians(-5.0), SPIN, spread, 40_000, 7)
    np.testing.assert_allclose(velocities[0], ball.launch_velocity(25.0, math.radians(15.0), math.radians(-5.0)))
    np.testing.assert_array_equal(spins[0], SPIN)
    speed = np.linalg.norm(velocities, axis=1)
    elevation = np.degrees(np.arcsin(velocities[:, 2] / speed))
    azimuth = np.degrees(np.arctan2(velocities[:, 1], velocities[:, 0]))
    # Standard errors of a sample SD over 40 000 draws are ~0.35 %: 3 % is far outside chance.
    assert np.std(speed) == pytest.approx(1.0, rel=0.03)
    assert np.std(elevation) == pytest.approx(1.0, rel=0.03)
    assert np.std(azimuth) == pytest.approx(1.5, rel=0.03)
    rates = np.linalg.norm(spins, axis=1) / (2 * math.pi)
    assert np.std(rates) == pytest.approx(0.8, rel=0.03)
    tilt = np.degrees(np.arccos(np.clip(spins[:, 2] / np.linalg.norm(spins, axis=1), -1.0, 1.0)))
    assert math.sqrt(np.mean(tilt**2)) == pytest.approx(8.0, rel=0.03)  # |normal| tilt: RMS is the SD
    again, _ = odds.draw_strikes(25.0, math.radians(15.0), math.radians(-5.0), SPIN, spread, 40_000, 7)
    np.testing.assert_array_equal(again, velocities)  # the same draw, the same strikes


def test_without_scatter_every_strike_is_the_kick_and_its_result_is_certain() -> None:
    wall, goal = ball.free_kick_panels((-22.0, 0.0), (0.0, 0.0), (1.0, 0.0))
    pitch = ball.Pitch(goal, wall, ball.Keeper())
    speed, elevation, azimuth = 26.0, math.radians(17.0), math.radians(-6.0)
    alone = ball.simulate(
        (-22.0, 0.0, R), ball.launch_velocity(speed, elevation, azimuth), SPIN, pitch=pitch, **OPTIONS
    )
    none = odds.StrikeSpread(0.0, 0.0, 0.0, 0.0, 0.0)
    certain = odds.strike_odds((-22.0, 0.0, R), speed, elevation, azimuth, SPIN, pitch, spread=none, n=50, **OPTIONS)
    assert alone.result is not None
    assert certain.probability(alone.result) == 1.0
    scattered = odds.strike_odds((-22.0, 0.0, R), speed, elevation, azimuth, SPIN, pitch, n=2000, **OPTIONS)
    assert sum(scattered.counts.values()) == 2000
    assert 0.0 < scattered.probability(alone.result) < 1.0  # a real strike's scatter spreads the outcomes
    with pytest.raises(ValueError, match="result"):
        scattered.probability("bicycle kick")


def test_the_odds_map_reports_progress_and_its_shares_sum_to_one() -> None:
    seen: list[float] = []
    maps = odds.odds_map(
        [18.0, 25.0],
        np.radians([-20.0, 0.0, 20.0]),
        26.0,
        math.radians(17.0),
        0.0,
        SPIN,
        keeper=ball.Keeper(),
        n=16,
        progress=seen.append,
        **OPTIONS,
    )
    assert seen == pytest.approx([i / 6 for i in range(1, 7)])
    total = sum(maps.values())
    np.testing.assert_allclose(total, 1.0)
    assert maps["goal"].shape == (2, 3)
    # The map's spot straight in front (angle 0) strikes the same n kicks as strike_odds from there: same shares.
    wall, goal = ball.free_kick_panels((-25.0, 0.0), (0.0, 0.0), (1.0, 0.0))
    alone = odds.strike_odds(
        (-25.0, 0.0, R), 26.0, math.radians(17.0), 0.0, SPIN, ball.Pitch(goal, wall, ball.Keeper()), n=16, **OPTIONS
    )
    for name in alone.counts:
        assert maps[name][1, 1] == pytest.approx(alone.probability(name)), name


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"n": 0}, "n"),
        ({"draw": -1}, "draw"),
        ({"spread": odds.StrikeSpread(speed_ms=-1.0)}, "speed_ms"),
        ({"spread": odds.StrikeSpread(spin_rate_rev_s=1e300)}, "spread.spin_rate_rev_s must be at most 50"),
        ({"spread": odds.StrikeSpread(direction_deg=180.5)}, "spread.direction_deg must be at most 180"),
        ({"spread": odds.StrikeSpread(elevation_deg=math.inf)}, "spread.elevation_deg"),
        ({"spread": odds.StrikeSpread(spin_axis_deg=181.0)}, "spread.spin_axis_deg must be at most 180"),
        ({"spread": odds.StrikeSpread(speed_ms=50.01)}, "spread.speed_ms must be at most 50"),
        ({"spread": "s"}, "spread must be a StrikeSpread"),
    ],
)
def test_bad_odds_input_raises_naming_it(kwargs, name) -> None:
    wall, goal = ball.free_kick_panels((-22.0, 0.0), (0.0, 0.0), (1.0, 0.0))
    with pytest.raises(ValueError, match=name):
        odds.strike_odds((-22.0, 0.0, R), 25.0, 0.3, 0.0, SPIN, ball.Pitch(goal, wall), **kwargs, **OPTIONS)


@pytest.mark.parametrize("name", sorted(odds.SPREAD_LIMITS))
def test_a_spread_at_its_limit_still_gives_odds(name: str) -> None:
    wall, goal = ball.free_kick_panels((-22.0, 0.0), (0.0, 0.0), (1.0, 0.0))
    spread = odds.StrikeSpread(**{name: odds.SPREAD_LIMITS[name]})  # type: ignore[arg-type]
    result = odds.strike_odds(
        (-22.0, 0.0, R), 25.0, 0.3, 0.0, SPIN, ball.Pitch(goal, wall), spread=spread, n=32, **OPTIONS
    )
    assert sum(result.counts.values()) == result.n == 32


def test_strike_odds_wants_a_pitch() -> None:
    with pytest.raises(ValueError, match="pitch must be a Pitch"):
        odds.strike_odds((-22.0, 0.0, R), 25.0, 0.3, 0.0, SPIN, None, **OPTIONS)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"wall": "yes"}, "wall must be True or False"),
        ({"keeper": "keeper"}, "keeper must be a Keeper"),
        ({"surface": 1.0}, "surface must be a Surface"),
        ({"distances_m": [[20.0, 21.0]]}, "distances_m must be a non-empty 1-D array"),
        ({"angles_rad": []}, "angles_rad must be a non-empty 1-D array"),
        ({"spread": "s"}, "spread must be a StrikeSpread"),
    ],
)
def test_bad_odds_map_input_raises_naming_it(kwargs, name) -> None:
    arguments = {"distances_m": [20.0], "angles_rad": [0.0], **kwargs}
    with pytest.raises(ValueError, match=name):
        odds.odds_map(speed_ms=25.0, elevation_rad=0.3, aim_rad=0.0, spin_rads=SPIN, n=2, **arguments, **OPTIONS)


# The intended kick's numbers, each bad in every way a caller can get one wrong. They reached numpy unchecked: a
# string or None raised numpy's TypeError, inf and NaN gave NaN velocities, a negative speed was flown backwards.
BAD_NUMBERS = ["25", None, math.inf, -math.inf, math.nan, True, 1j, [25.0], np.array([25.0, 1.0])]


def _kick_arguments(function: str) -> tuple[dict[str, object], dict[str, object]]:
    """The kick's scalar arguments by name, and the rest of a valid call, for one of the three odds functions."""
    kick: dict[str, object] = {"speed_ms": 25.0, "elevation_rad": 0.3}
    if function == "odds_map":
        kick["aim_rad"] = 0.0
        rest = {"distances_m": [20.0], "angles_rad": [0.0], "spin_rads": SPIN, "n": 2, **OPTIONS}
    else:
        kick["azimuth_rad"] = 0.0
        rest = {"spin_rads": SPIN, "n": 2}
        if function == "strike_odds":
            wall, goal = ball.free_kick_panels((-22.0, 0.0), (0.0, 0.0), (1.0, 0.0))
            rest.update(position=(-22.0, 0.0, R), pitch=ball.Pitch(goal, wall), **OPTIONS)
        else:
            rest["spread"] = odds.StrikeSpread()
    return kick, rest


@pytest.mark.parametrize("function", ["draw_strikes", "strike_odds", "odds_map"])
@pytest.mark.parametrize("argument", ["speed_ms", "elevation_rad", "direction"])
@pytest.mark.parametrize("bad", [*BAD_NUMBERS, -5.0], ids=repr)
def test_a_bad_kick_number_raises_naming_it(function: str, argument: str, bad: object) -> None:
    kick, rest = _kick_arguments(function)
    if argument == "direction":
        argument = "aim_rad" if function == "odds_map" else "azimuth_rad"
    if type(bad) is float and bad == -5.0 and argument != "speed_ms":
        getattr(odds, function)(**{**kick, argument: bad}, **rest)  # a negative angle is an angle
        return
    with pytest.raises(ValueError, match=f"^{argument} must be"):
        getattr(odds, function)(**{**kick, argument: bad}, **rest)


def test_a_huge_spin_keeps_its_axis_and_one_too_large_to_measure_is_refused() -> None:
    # |ω|² of 1e200 rad/s overflowed to inf, and the axis came out NaN.
    still = odds.StrikeSpread(0.0, 0.0, 0.0, 0.0, 0.0)
    _, spins = odds.draw_strikes(25.0, 0.3, 0.0, (0.0, 3e200, 4e200), still, 3)
    np.testing.assert_allclose(spins, [[0.0, 3e200, 4e200]] * 3, rtol=1e-15)
    _, spins = odds.draw_strikes(25.0, 0.3, 0.0, (0.0, 3e-200, 4e-200), still, 3)
    np.testing.assert_allclose(spins, [[0.0, 3e-200, 4e-200]] * 3, rtol=1e-15)
    with pytest.raises(ValueError, match="spin_rads must have a finite magnitude"):
        odds.draw_strikes(25.0, 0.3, 0.0, (1.5e308, 1.5e308, 1.5e308), still, 3)  # |ω| = 2.6e308


def test_strike_counts_are_capped_before_anything_is_allocated() -> None:
    # n = 10¹² asked numpy for 36 TiB and raised MemoryError.
    velocities, _ = odds.draw_strikes(25.0, 0.3, 0.0, SPIN, odds.StrikeSpread(), odds.MAX_STRIKES)
    assert velocities.shape == (odds.MAX_STRIKES, 3)
    for n in (odds.MAX_STRIKES + 1, 10**12):
        with pytest.raises(ValueError, match=r"^n must be at most 1,000,000 strikes"):
            odds.draw_strikes(25.0, 0.3, 0.0, SPIN, odds.StrikeSpread(), n)
    with pytest.raises(ValueError, match=r"^n × spots must be at most 1,000,000 strikes in one call, got 1,000,020"):
        odds.odds_map([20.0, 25.0], [0.0, 0.1], 25.0, 0.3, 0.0, SPIN, n=250_005, **OPTIONS)


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        # A spot too close was blamed on "ball_xy", an argument odds_map does not have.
        ({"distances_m": [5.0]}, "distances_m must be in"),
        ({"distances_m": [9.15]}, "distances_m must be in"),
        ({"distances_m": [20.0, -20.0]}, "distances_m must be in"),
        ({"distances_m": [120.5]}, "distances_m must be in"),
        # 10³⁰⁰ m out: "the ball starts inside a post".
        ({"distances_m": [1e300]}, "distances_m must be in"),
        # Behind the goal line: every strike "short", a map of nothing.
        ({"angles_rad": [3.0]}, "angles_rad must be in"),
        ({"angles_rad": [0.0, -math.pi / 2]}, "angles_rad must be in"),
        # progress=1 raised TypeError once the first chunk was flown.
        ({"progress": 1}, "progress must be None or a function"),
        ({"progress": "bar"}, "progress must be None or a function"),
    ],
)
def test_a_bad_odds_map_grid_or_progress_raises_naming_it(kwargs, name) -> None:
    arguments = {"distances_m": [20.0], "angles_rad": [0.0], **kwargs}
    with pytest.raises(ValueError, match=f"^{name}"):
        odds.odds_map(speed_ms=25.0, elevation_rad=0.3, aim_rad=0.0, spin_rads=SPIN, n=2, **arguments, **OPTIONS)


def test_the_odds_maps_edges_are_accepted() -> None:
    # The farthest spot straight out, and the widest angle as far out as the touchline (34 m from the centre line)
    # allows; a spot beyond the touchline is refused (120 m at 1.5 rad had been played 120 m off the pitch).
    for distances, angles in (([9.2, 120.0], [0.0]), ([9.2, 34.0 / math.sin(1.5)], [-1.5, 1.5])):
        edges = odds.odds_map(distances, angles, 25.0, 0.3, 0.0, SPIN, n=2, progress=lambda share: None, **OPTIONS)
        assert edges["goal"].shape == (2, len(angles))
        np.testing.assert_allclose(sum(edges.values()), 1.0)
    for distances, angles in (([120.0], [1.5]), ([34.01 / math.sin(0.5)], [-0.5])):
        with pytest.raises(ValueError, match=r"distances_m and angles_rad must put every spot on the pitch"):
            odds.odds_map(distances, angles, 25.0, 0.3, 0.0, SPIN, n=2, **OPTIONS)


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"n": None}, r"^n must be an integer"),  # TypeError multiplying None
        ({"n": 2.0}, r"^n must be an integer"),
        ({"wall_height_m": 1e300}, r"^wall_height_m must be at most 1000 m"),  # the wall let the shot through
        ({"wall_height_m": 1000.5}, r"^wall_height_m must be at most 1000 m"),
    ],
)
def test_a_second_reviews_odds_map_inputs_are_refused_by_name(kwargs, name) -> None:
    arguments = {"distances_m": [20.0], "angles_rad": [0.2], "n": 2, **kwargs}
    with pytest.raises(ValueError, match=name):
        odds.odds_map(speed_ms=25.0, elevation_rad=0.2, aim_rad=0.0, spin_rads=(0.0, 0.0, 0.0), **arguments, **OPTIONS)


def test_a_tall_wall_blocks_a_low_shot_up_to_the_largest_height_accepted() -> None:
    for height in (1.8, 10.0, 1000.0):
        shares = odds.odds_map([20.0], [0.2], 25.0, 0.2, 0.0, (0.0, 0.0, 0.0), wall_height_m=height, n=2, **OPTIONS)
        assert shares["wall"][0, 0] == 1.0, height


def test_a_keeper_placed_for_a_ball_beyond_1e300_m_is_refused_not_nan() -> None:
    _, goal = ball.free_kick_panels((-20.0, 0.0), (0.0, 0.0), (1.0, 0.0))
    with pytest.raises(ValueError, match=r"^ball_xy must be of magnitude"):
        ball.Keeper().placed((1.7e308, 1.7e308), goal)
    x, y = ball.Keeper().placed((-1e300, 0.0), goal)
    assert math.isfinite(x) and math.isfinite(y)
    with pytest.raises(ValueError, match=r"^pitch\.goal\.height_m must be at most 1000 m"):
        ball.simulate(
            (-20.0, 0.0, R),
            (25.0, 0.0, 3.0),
            (0.0, 0.0, 0.0),
            ground_m=R,
            pitch=ball.Pitch(ball.Panel((0, 0), (1, 0), 7.32, 1e300)),
        )


@pytest.mark.parametrize(
    ("keeper", "wall", "surface"),
    [
        (ball.Keeper(), True, None),
        (ball.Keeper(depth_m=2.5, shift_m=-0.7), False, ball.WET_TURF),
        (ball.Keeper(position_xy=(-1.0, 0.5)), True, None),
        (None, True, ball.WET_TURF),
        (None, False, None),
    ],
)
def test_the_odds_maps_pitches_are_each_spots_own_pitch_bit_for_bit(keeper, wall, surface) -> None:
    # The map builds its spots' pitch vectors all at once: each must be the one pitch_vector gives the spot's own
    # free kick (its wall 9.15 m out toward the goal, the keeper placed for it), to the last bit.
    distances = np.array([9.2, 16.0, 22.5, 36.0, 119.0])
    angles = np.radians([-89.0, -40.0, -7.3, 0.0, 12.0, 40.0, 89.0])
    spots = np.array([[-d * math.cos(a), d * math.sin(a)] for d in distances for a in angles])
    # Where the keeper's depth and shift would put him out of his penalty area at a spot (the bisector of a wide
    # angle), pitch_vector refuses it; the map refuses the first such spot the same way, and builds the others.
    expected, refusals = [], []
    for spot in spots:
        wall_panel, goal = ball.free_kick_panels(spot, (0.0, 0.0), (1.0, 0.0), wall_height_m=1.9)
        pitch = ball.Pitch(goal, wall_panel if wall else None, keeper, surface=surface or ball.Pitch(goal).surface)
        try:
            expected.append(pitch_vector(pitch, spot, R, R))
        except ValueError as error:
            expected.append(None)
            refusals.append(str(error))
    if refusals:
        with pytest.raises(ValueError, match=re.escape(refusals[0])):
            odds.spot_vectors(spots, keeper, wall, 1.9, surface, R, R)
    kept = [i for i, vector in enumerate(expected) if vector is not None]
    assert len(kept) >= 25
    vectors = odds.spot_vectors(spots[kept], keeper, wall, 1.9, surface, R, R)
    for i, vector in zip(kept, vectors, strict=True):
        np.testing.assert_array_equal(vector, expected[i])
