"""kernels.ball.odds: strike scatter drawn as specified, and the odds of a kick on the pitch."""

from __future__ import annotations

import math

import numpy as np
import pytest

from kernels import ball
from kernels.ball import odds

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
        ({"spread": "s"}, "spread must be a StrikeSpread"),
    ],
)
def test_bad_odds_input_raises_naming_it(kwargs, name) -> None:
    wall, goal = ball.free_kick_panels((-22.0, 0.0), (0.0, 0.0), (1.0, 0.0))
    with pytest.raises(ValueError, match=name):
        odds.strike_odds((-22.0, 0.0, R), 25.0, 0.3, 0.0, SPIN, ball.Pitch(goal, wall), **kwargs, **OPTIONS)


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
