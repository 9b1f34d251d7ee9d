"""The free kick's odds over a player's scatter: the current strike's chances (each result's share over imperfect
strikes from this spot) and the goal-chance map (the same strike from every spot of a grid over the pitch), their
colours and their words. No viser; physics from :func:`kernels.ball.strike_odds` and :func:`kernels.ball.odds_map`.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from kernels import ball
from scenes.freekick.model import (
    DEFENDER_HEIGHT_M,
    INTEGRATOR_STEP_S,
    JUMP_M,
    KEEPER,
    PLAY_T_MAX_S,
    FreeKickParams,
    aim_heading_rad,
    ball_spot,
    pitch,
    play_options,
    spin_vector,
)

STRIKES = 200
"""Strikes of the current kick played out for its odds (a player's scatter, :class:`kernels.ball.StrikeSpread`)."""


def strike_chances(p: FreeKickParams, n: int = STRIKES) -> ball.Odds:
    """The current kick struck ``n`` times with a skilled player's scatter (:class:`kernels.ball.StrikeSpread`'s
    defaults), each played on over the scene's pitch (wall, posts, bar, net and the keeper if there is one), without
    the knuckle force."""
    return ball.strike_odds(
        ball_spot(p),
        p.speed_ms,
        math.radians(p.elevation_deg),
        aim_heading_rad(p),
        spin_vector(p),
        pitch(p),
        n=n,
        **play_options(p),
    )


ODDS_MAP_DISTANCES_M = np.linspace(16.0, 36.0, 21)
"""The odds map's rows: distance from the spot to the goal's centre (m), every metre."""
ODDS_MAP_ANGLES_DEG = np.linspace(-40.0, 40.0, 17)
"""The odds map's columns: the spot's angle off the centre line (°, + to the kicker's left), every 5°."""
ODDS_MAP_STRIKES = 32
"""Strikes per spot of the odds map (21 × 17 spots × 32 = 11,424 kicks played out)."""


def odds_map_settings(p: FreeKickParams) -> FreeKickParams:
    """What the odds map of ``p`` depends on: ``p`` without its spot, its display settings, its integrator (the map
    flies RK4 at its step whatever the Integrator says) and the spin a Knuckleball tick keeps (the map is the same
    strike from every spot)."""
    plain = FreeKickParams()
    return dataclasses.replace(
        p,
        distance_m=plain.distance_m,
        angle_deg=plain.angle_deg,
        show_forces=plain.show_forces,
        view=plain.view,
        integrator=plain.integrator,
        spin_before_knuckle_rev_s=plain.spin_before_knuckle_rev_s,
    )


def spot_odds_map(p: FreeKickParams, progress: Callable[[float], object] | None = None) -> NDArray[np.float64]:
    """(D, A) the chance of a goal from each spot of :data:`ODDS_MAP_DISTANCES_M` × :data:`ODDS_MAP_ANGLES_DEG` for
    the current strike (its speed, elevation, azimuth and spin, turned to face the goal from each spot), struck
    :data:`ODDS_MAP_STRIKES` times with a skilled player's scatter over a 4-man wall square to the line to the goal
    (jumping if ``p``'s does) and the keeper if ``p`` has one (:func:`kernels.ball.odds_map`, no knuckle force).
    ``progress`` is called with the share done (0–1) as the spots' batches finish."""
    straight = dataclasses.replace(p, angle_deg=0.0)  # from the centre line the world's axes are the ball's
    chances = ball.odds_map(
        ODDS_MAP_DISTANCES_M,
        np.radians(ODDS_MAP_ANGLES_DEG),
        p.speed_ms,
        math.radians(p.elevation_deg),
        math.radians(p.azimuth_deg),
        spin_vector(straight),
        keeper=KEEPER if p.keeper else None,
        wall_height_m=DEFENDER_HEIGHT_M + (JUMP_M if p.wall_jumps else 0.0),
        n=ODDS_MAP_STRIKES,
        progress=progress,
        chunks=17,
        dt=INTEGRATOR_STEP_S["rk4"],
        method="rk4",
        model=p.model,
        t_max=PLAY_T_MAX_S,  # each strike played as long as the scene plays its kick: 5 spots' goals came after 4 s
        ground_m=ball.BALL_RADIUS_M,
    )
    return chances["goal"]


HEAT_STOPS = np.array([[0.0, 20, 20, 110], [0.35, 170, 20, 150], [0.7, 240, 80, 20], [1.0, 255, 240, 40]])
"""The heat map's colour ramp: (share, R, G, B) stops from no goals (dark blue) through magenta and orange to every
strike a goal (yellow), as docs/freekick.md says; every stop stands out from the grass."""


def heat_colours(chance: NDArray[np.float64]) -> NDArray[np.uint8]:
    """(..., 3) RGB of each chance (0–1) on :data:`HEAT_STOPS`."""
    c = np.clip(np.asarray(chance, dtype=np.float64), 0.0, 1.0)
    rgb = [np.interp(c, HEAT_STOPS[:, 0], HEAT_STOPS[:, k]) for k in (1, 2, 3)]
    return np.stack(rgb, axis=-1).round().astype(np.uint8)


def heat_cells(p: FreeKickParams | None = None) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """The odds map's cells on the turf, row-major as :func:`spot_odds_map`'s (D, A): (D·A, 3) centres (m, just
    above the grass), (D·A,) headings (rad, from +x: the line from the spot to the goal) and (D·A, 2) sizes (m,
    along and across that line: a metre by the arc of 5°)."""
    d, a = np.meshgrid(ODDS_MAP_DISTANCES_M, np.radians(ODDS_MAP_ANGLES_DEG), indexing="ij")
    d, a = d.ravel(), a.ravel()
    centres = np.column_stack([-d * np.cos(a), d * np.sin(a), np.full(d.size, 0.012)])
    headings = np.arctan2(-centres[:, 1], -centres[:, 0])
    step_d = float(ODDS_MAP_DISTANCES_M[1] - ODDS_MAP_DISTANCES_M[0])
    step_a = math.radians(float(ODDS_MAP_ANGLES_DEG[1] - ODDS_MAP_ANGLES_DEG[0]))
    sizes = np.column_stack([np.full(d.size, 0.96 * step_d), 0.96 * d * step_a])
    return centres, headings, sizes


ODDS_MAP_CAVEAT = (
    "The keeper dives on his first read of each ball, as if it flew straight on, so from far out, where it dips "
    "and curls more after he reads it, the map scores higher than a real keeper would let it."
)
"""Said under the map with a keeper in goal: far-out spots (30–36 m) score more than near ones (docs/freekick.md)."""


def odds_map_words(chance: NDArray[np.float64], p: FreeKickParams) -> str:
    """The map in words: the best spot and its chance, the chance from the spot nearest the ball's and, with a keeper,
    :data:`ODDS_MAP_CAVEAT`; or that no spot scores."""
    if not np.any(chance > 0.0):
        return "**No spot on the map scores with this strike.**"
    caveat = f"  \n{ODDS_MAP_CAVEAT}" if p.keeper else ""
    best = np.unravel_index(int(np.argmax(chance)), chance.shape)
    d, a = ODDS_MAP_DISTANCES_M[best[0]], ODDS_MAP_ANGLES_DEG[best[1]]
    side = "on the centre line" if a == 0 else f"{abs(a):g}° {'left' if a > 0 else 'right'}"
    text = f"Best spot: **{d:g} m, {side}: goal {100 * chance[best]:.0f} %**"
    i = int(np.argmin(np.abs(ODDS_MAP_DISTANCES_M - p.distance_m)))
    j = int(np.argmin(np.abs(ODDS_MAP_ANGLES_DEG - p.angle_deg)))
    if abs(ODDS_MAP_DISTANCES_M[i] - p.distance_m) <= 0.5 and abs(ODDS_MAP_ANGLES_DEG[j] - p.angle_deg) <= 2.5:
        text += f"; from this spot: **{100 * chance[i, j]:.0f} %**"
    return text + caveat


def chances_words(odds: ball.Odds) -> str:
    """ "Struck 200 times with a player's scatter: goal 62 %, wall 9 %, …" (results that happened, largest first)."""
    shares = sorted(((odds.probability(name), name) for name in odds.counts if odds.counts[name]), reverse=True)
    listed = ", ".join(f"{name} {100 * share:.0f} %" for share, name in shares)
    return f"Struck {odds.n} times with a player's scatter: **{listed}**"
