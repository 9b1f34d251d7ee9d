"""A real strike's odds: the same kick struck N times with a player's scatter, each played out on the pitch.

:class:`StrikeSpread` holds the scatter (standard deviations of speed, direction, elevation, spin rate and spin
axis); :func:`strike_odds` draws N strikes around one kick and counts how each ended (:func:`kernels.ball
.simulate_outcomes` on a :class:`~kernels.ball.pitch.Pitch`, one compiled pass); :func:`odds_map` does it for every
spot of a distance × angle grid, the strike set relative to the line from the spot to the goal's centre. Draws are
numpy's ``default_rng(draw)``: the same draw number, the same strikes. No compiled code of its own.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from kernels import _checks
from kernels.ball import play
from kernels.ball.api import pitch_outcomes, pitch_strike_outcomes
from kernels.ball.config import GROUND, RADIUS, check_launches, checked_seed, checked_vector, flight_config
from kernels.ball.core import RESULTS
from kernels.ball.pitch import (
    PENALTY_AREA_DEPTH_M,
    PENALTY_AREA_HALF_WIDTH_M,
    PITCH_WIDTH_M,
    WALL_DISTANCE_M,
    Keeper,
    Pitch,
    Surface,
    free_kick_panels,
    pitch_vector,
)

MAX_STRIKES = 1_000_000
"""Most strikes one call flies (:func:`odds_map`: spots × ``n``): a million take about 17 s on 2 cores."""
MAX_STRIKE_SPEED_MS = 100.0
"""The fastest strike the odds take (m/s; the fastest recorded shots are about 60 m/s): 1e9 m/s was blamed on dt."""
MAX_DISTANCE_M = 120.0
"""The farthest spot of :func:`odds_map`: the longest pitch Law 1 allows."""


@dataclasses.dataclass(frozen=True)
class StrikeSpread:
    """How much one player's strikes of the same kick scatter: standard deviations of a normal draw each.

    The defaults are a stated guess for a skilled free-kick taker, not a measurement: about 4 % of a 25 m/s strike's
    speed (within-player ball-speed variation in instep kicking is a few per cent), 1.5° of direction and 1° of
    elevation (about 0.5 m at the goal from 20 m), 10 % of an 8 rev/s spin rate, and 8° of spin-axis tilt.
    """

    speed_ms: float = 1.0
    direction_deg: float = 1.5
    elevation_deg: float = 1.0
    spin_rate_rev_s: float = 0.8
    spin_axis_deg: float = 8.0

    def checked(self) -> StrikeSpread:
        """This spread, each deviation a number in [0, :data:`SPREAD_LIMITS`]; ``ValueError`` naming one that is not."""
        for field in dataclasses.fields(self):
            name = f"spread.{field.name}"
            value = _checks.non_negative(name, getattr(self, field.name))
            if value > SPREAD_LIMITS[field.name]:
                raise ValueError(f"{name} must be at most {SPREAD_LIMITS[field.name]:g}, got {_checks.shown(value)}")
        return self


SPREAD_LIMITS = {
    "speed_ms": 50.0,
    "direction_deg": 180.0,
    "elevation_deg": 90.0,
    "spin_rate_rev_s": 50.0,
    "spin_axis_deg": 180.0,
}
"""The largest deviation of each :class:`StrikeSpread` field: a half turn of direction or axis, a right angle of
elevation (wider draws only wrap round), and a speed or spin rate beyond any foot (the hardest strikes reach about
35 m/s and 15 rev/s). A spin spread of 1e300 rev/s was played."""


@dataclasses.dataclass(frozen=True)
class Odds:
    """How N strikes of one kick ended."""

    counts: dict[str, int]
    """Strikes per result (all eight results, zeros included)."""
    n: int
    """Strikes drawn."""

    def probability(self, result: str) -> float:
        """Share of the strikes that ended as ``result`` (0–1)."""
        if result not in self.counts:
            raise ValueError(f"result must be one of {sorted(self.counts)}, got {_checks.shown(result)}")
        return self.counts[result] / self.n if self.n else 0.0


def draw_strikes(
    speed_ms: float,
    elevation_rad: float,
    azimuth_rad: float,
    spin_rads: ArrayLike,
    spread: StrikeSpread,
    n: int,
    draw: int = 0,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """N strikes around one kick: (N, 3) launch velocities (m/s) and (N, 3) spins (rad/s).

    Speed, elevation and azimuth get normal scatter; the spin rate too (clipped at 0), and its axis is tilted by a
    normal angle in a uniformly drawn direction. The first strike is always the kick itself.
    """
    speed_ms = _checks.non_negative("speed_ms", speed_ms)
    if speed_ms > MAX_STRIKE_SPEED_MS:
        raise ValueError(
            f"speed_ms must be at most {MAX_STRIKE_SPEED_MS:g} m/s (a strike), got {_checks.shown(speed_ms)}"
        )
    elevation_rad = _checks.finite_number("elevation_rad", elevation_rad)
    azimuth_rad = _checks.finite_number("azimuth_rad", azimuth_rad)
    spin = checked_vector("spin_rads", spin_rads, 3)
    scale = float(np.abs(spin).max())
    rate = scale * float(np.linalg.norm(spin / scale)) if scale > 0.0 else 0.0  # |ω| without overflowing its square
    if not math.isfinite(rate):
        raise ValueError(f"spin_rads must have a finite magnitude, got {_checks.shown(spin_rads)}")
    spread = _checks.instance("spread", spread, StrikeSpread).checked()
    count = _strike_count("n", n, 1)
    rng = np.random.default_rng(checked_seed("draw", draw))
    normal = rng.standard_normal((count, 5))
    normal[0] = 0.0
    speed = np.maximum(speed_ms + spread.speed_ms * normal[:, 0], 0.0)
    elevation = elevation_rad + math.radians(spread.elevation_deg) * normal[:, 1]
    azimuth = azimuth_rad + math.radians(spread.direction_deg) * normal[:, 2]
    velocities = speed[:, None] * np.stack(
        (np.cos(elevation) * np.cos(azimuth), np.cos(elevation) * np.sin(azimuth), np.sin(elevation)), axis=1
    )
    rates = np.maximum(rate + 2.0 * math.pi * spread.spin_rate_rev_s * normal[:, 3], 0.0)
    axis = spin / rate if rate > 0.0 else np.array([0.0, 0.0, 1.0])
    # Tilt the axis by a normal angle about a random direction perpendicular to it (Rodrigues' rotation).
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(axis, helper)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(axis, e1)
    turn = rng.uniform(0.0, 2.0 * math.pi, count)
    tilt = math.radians(spread.spin_axis_deg) * normal[:, 4]
    about = np.cos(turn)[:, None] * e1 + np.sin(turn)[:, None] * e2
    tilted = np.cos(tilt)[:, None] * axis + np.sin(tilt)[:, None] * np.cross(about, axis)
    spins = rates[:, None] * tilted
    spins[0] = spin
    velocities[0] = speed_ms * np.array(
        [
            math.cos(elevation_rad) * math.cos(azimuth_rad),
            math.cos(elevation_rad) * math.sin(azimuth_rad),
            math.sin(elevation_rad),
        ]
    )
    return velocities, spins


def strike_odds(
    position: ArrayLike,
    speed_ms: float,
    elevation_rad: float,
    azimuth_rad: float,
    spin_rads: ArrayLike,
    pitch: Pitch,
    *,
    spread: StrikeSpread | None = None,
    n: int = 1000,
    draw: int = 0,
    **options: Any,
) -> Odds:
    """The odds of one kick struck ``n`` times with ``spread``'s scatter, each played out on ``pitch``.

    Args:
        position: (3,) the ball's spot (m).
        speed_ms, elevation_rad, azimuth_rad: the intended kick (m/s, rad above the ground, rad to the left of +x).
        spin_rads: (3,) its intended spin (rad/s).
        pitch: the goal, wall and keeper.
        spread: the scatter (default :class:`StrikeSpread`).
        n: strikes (≥ 1); the first is the intended kick.
        draw: which random draw (the same number gives the same strikes).
        **options: :class:`~kernels.ball.FlightConfig` fields, as for :func:`kernels.ball.simulate`.

    Returns:
        :class:`Odds`.
    """
    start = checked_vector("position", position, 3)
    _checks.instance("pitch", pitch, Pitch)
    velocities, spins = draw_strikes(
        speed_ms, elevation_rad, azimuth_rad, spin_rads, StrikeSpread() if spread is None else spread, n, draw
    )
    starts = np.broadcast_to(start, velocities.shape)
    judged = pitch_strike_outcomes(starts, velocities, spins, pitch, options)
    return Odds(judged.counts(), len(velocities))


def odds_map(
    distances_m: ArrayLike,
    angles_rad: ArrayLike,
    speed_ms: float,
    elevation_rad: float,
    aim_rad: float,
    spin_rads: ArrayLike,
    *,
    keeper: Keeper | None = None,
    wall: bool = True,
    wall_height_m: float = 1.8,
    surface: Surface | None = None,
    spread: StrikeSpread | None = None,
    n: int = 64,
    draw: int = 0,
    progress: Callable[[float], object] | None = None,
    chunks: int = 8,
    **options: Any,
) -> dict[str, NDArray[np.float64]]:
    """Each result's probability at every spot of a grid around a goal at the origin (the goal line x = 0, the
    pitch toward −x): for D distances and A angles (+ to the left, seen from the goal), (D, A) arrays per result.

    The strike at each spot is the same kick turned to that spot: ``aim_rad`` is its azimuth from the line to the
    goal's centre (+ left), spin in the ball's frame (x toward the goal's centre); every spot gets the same n
    strikes' scatter (one draw). The wall (if any) stands 9.15 m out, square to that line; the keeper is placed by
    the angle. All spots' strikes fly in ``chunks`` parallel calls (each spot on its own pitch); ``progress`` is
    called with the share done after each.
    """
    distances = _checks.finite_array("distances_m", distances_m)
    angles = _checks.finite_array("angles_rad", angles_rad)
    for name, array in (("distances_m", distances), ("angles_rad", angles)):
        if array.ndim != 1 or len(array) == 0:
            raise ValueError(f"{name} must be a non-empty 1-D array, got shape {array.shape}")
    if not ((distances > WALL_DISTANCE_M) & (distances <= MAX_DISTANCE_M)).all():
        raise ValueError(
            f"distances_m must be in ({WALL_DISTANCE_M}, {MAX_DISTANCE_M:g}] m (beyond the wall's distance, on a "
            f"pitch), got {_checks.shown(distances_m)}"
        )
    if not (np.abs(angles) < 0.5 * math.pi).all():
        raise ValueError(
            f"angles_rad must be in (−π/2, π/2) (in front of the goal line), got {_checks.shown(angles_rad)}"
        )
    half_width = 0.5 * PITCH_WIDTH_M
    across = np.abs(np.outer(distances, np.sin(angles)))
    if (across > half_width).any():
        i, j = np.unravel_index(int(np.argmax(across)), across.shape)
        raise ValueError(
            f"distances_m and angles_rad must put every spot on the pitch: {distances[i]:g} m at {angles[j]:g} rad is "
            f"{across[i, j]:.4g} m from the goal's centre line, beyond the touchline at {half_width:g} m"
        )
    _checks.finite_number("aim_rad", aim_rad)
    _checks.integer("n", n, 1)
    _strike_count("n", n * len(distances) * len(angles), len(distances) * len(angles), "n × spots")
    _checks.integer("chunks", chunks, 1)
    if progress is not None and not callable(progress):
        raise ValueError(f"progress must be None or a function of the share done, got {_checks.shown(progress)}")
    if not isinstance(wall, bool):
        raise ValueError(f"wall must be True or False, got {_checks.shown(wall)}")
    if keeper is not None:
        _checks.instance("keeper", keeper, Keeper)
    if surface is not None:
        _checks.instance("surface", surface, Surface)
    settings = flight_config(None, options).settings
    ground, radius = float(settings[GROUND]), float(settings[RADIUS])
    # One scatter, drawn along +x, turned to each spot.
    velocities, spins = draw_strikes(
        speed_ms, elevation_rad, aim_rad, spin_rads, StrikeSpread() if spread is None else spread, n, draw
    )
    spots = np.array(
        [[-d * math.cos(a), d * math.sin(a)] for d in distances for a in angles], dtype=np.float64
    ).reshape(-1, 2)
    vectors = spot_vectors(spots, keeper, wall, wall_height_m, surface, ground, radius)
    launches = np.zeros((len(spots) * len(velocities), 13))
    for s, spot in enumerate(spots):
        heading = math.atan2(-spot[1], -spot[0])  # toward the goal's centre
        c, si = math.cos(heading), math.sin(heading)
        turn = np.array([[c, -si, 0.0], [si, c, 0.0], [0.0, 0.0, 1.0]])
        rows = launches[s * len(velocities) : (s + 1) * len(velocities)]
        rows[:, 0:2], rows[:, 2] = spot, ground
        rows[:, 3:6], rows[:, 6:9] = velocities @ turn.T, spins @ turn.T
    check_launches(launches, settings, batch=True, strikes=True)
    which = np.repeat(np.arange(len(spots)), len(velocities))
    codes = np.empty(len(launches), dtype=np.int64)
    bounds = np.linspace(0, len(spots), min(chunks, max(len(spots), 1)) + 1).astype(int)
    for lo, hi in itertools.pairwise(bounds.tolist()):
        a, b = lo * len(velocities), hi * len(velocities)
        codes[a:b] = pitch_outcomes(launches[a:b], settings, vectors[lo:hi], which[a:b] - lo, strikes=True)
        if progress is not None:
            progress(hi / len(spots))
    per_spot = codes.reshape(len(spots), len(velocities))
    return {
        name: (per_spot == code).mean(axis=1).reshape(len(distances), len(angles)) for code, name in enumerate(RESULTS)
    }


def spot_vectors(
    spots: NDArray[np.float64],
    keeper: Keeper | None,
    wall: bool,
    wall_height_m: float,
    surface: Surface | None,
    ground: float,
    radius: float,
) -> NDArray[np.float64]:
    """(S, N_PITCH) pitch vectors of :func:`odds_map`'s (S, 2) spots: each the :func:`~kernels.ball.pitch
    .pitch_vector` of the spot's free kick (:func:`~kernels.ball.pitch.free_kick_panels` toward a goal at the origin,
    the wall if ``wall``, ``keeper`` placed for the spot), the same numbers bit for bit.

    The first spot's pitch is built and checked in full; the others differ only in the wall's foot and normal and
    where an unplaced keeper stands, computed for all spots at once by the same operations as
    ``free_kick_panels``, ``panel_row`` and :meth:`~kernels.ball.pitch.Keeper.placed` (a pitch built per spot cost
    about 0.1 s of a 1271-spot map's 1.3 s, all of it in Python).
    """
    wall_panel, goal = free_kick_panels(spots[0], (0.0, 0.0), (1.0, 0.0), wall_height_m=wall_height_m)
    pitch = Pitch(goal, wall_panel if wall else None, keeper, surface=surface or Pitch(goal).surface)
    vectors = np.tile(pitch_vector(pitch, spots[0], ground, radius), (len(spots), 1))
    centre = np.zeros(2)
    balls_x, balls_y = spots[:, 0], spots[:, 1]
    if wall:
        aim_x, aim_y = centre[0] - balls_x, centre[1] - balls_y
        distance = np.hypot(aim_x, aim_y)
        aim_x, aim_y = aim_x / distance, aim_y / distance
        foot_x = balls_x + WALL_DISTANCE_M * aim_x + 0.0 * -aim_y  # free_kick_panels' zero wall_offset_m
        foot_y = balls_y + WALL_DISTANCE_M * aim_y + 0.0 * aim_x
        length = np.hypot(aim_x, aim_y)  # panel_row normalises the normal it is given
        vectors[:, play.WX], vectors[:, play.WY] = foot_x, foot_y
        vectors[:, play.WNX], vectors[:, play.WNY] = aim_x / length, aim_y / length
    if keeper is not None and keeper.position_xy is None:
        normal = np.array(goal.normal_xy) / float(np.hypot(*goal.normal_xy))
        along = np.array([-normal[1], normal[0]])
        right = centre - 0.5 * goal.width_m * along
        left_post = centre + 0.5 * goal.width_m * along
        d_right = np.hypot(balls_x - right[0], balls_y - right[1])
        d_left = np.hypot(balls_x - left_post[0], balls_y - left_post[1])
        share = (-0.5 + d_right / (d_right + d_left)) * goal.width_m
        split_x, split_y = centre[0] + share * along[0], centre[1] + share * along[1]
        towards_x, towards_y = balls_x - split_x, balls_y - split_y
        length = np.hypot(towards_x, towards_y)
        away = length > 0
        safe = np.where(away, length, 1.0)
        unit_x = np.where(away, towards_x / safe, -normal[0])
        unit_y = np.where(away, towards_y / safe, -normal[1])
        depth, shift = float(keeper.depth_m), float(keeper.shift_m)
        vectors[:, play.KX] = split_x + depth * unit_x - shift * -unit_y
        vectors[:, play.KY] = split_y + depth * unit_y - shift * unit_x
        # Every spot's keeper in his penalty area, as Keeper.placed holds him (refused there, by name, otherwise).
        out = -(vectors[:, play.KX] * normal[0] + vectors[:, play.KY] * normal[1])
        across = vectors[:, play.KX] * along[0] + vectors[:, play.KY] * along[1]
        outside = np.flatnonzero(
            (out < 0.0) | (out > PENALTY_AREA_DEPTH_M) | (np.abs(across) > PENALTY_AREA_HALF_WIDTH_M)
        )
        if outside.size:
            keeper.placed(spots[int(outside[0])], goal)  # raises, naming depth_m and shift_m
    return vectors


def _strike_count(name: str, value: object, minimum: int, what: str = "") -> int:
    """An integer in [``minimum``, :data:`MAX_STRIKES`], else ``ValueError`` naming it (``what``: the product it
    is part of)."""
    count = _checks.integer(name, value, minimum)
    if count > MAX_STRIKES:
        raise ValueError(f"{what or name} must be at most {MAX_STRIKES:,} strikes in one call, got {count:,}")
    return count
