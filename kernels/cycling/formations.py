"""Drafting formations: riders laid out in two dimensions and the air drag each one meets there.

:func:`formation` lays out single file, a two-abreast paceline, a bunch or an echelon; :func:`formation_drag` is a
wake model of each rider's drag from the offsets of the riders around it, which is the line model of
:func:`kernels.cycling.drag_reduction` in single file and is fitted to Blocken et al. 2018's 121-rider peloton (J. Wind
Eng. Ind. Aerodyn. 179:319), its wakes turned by a crosswind's yaw (:func:`apparent_yaw`); :func:`formation_power`
is each rider's power there. Plain numpy over the (N, N) offsets: about 0.7 ms for 121 riders.
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from kernels import _checks
from kernels.cycling.power_law import (
    _LEADER_FADE_M,
    _LEADER_PLATEAU,
    _MEASURED_FADE_M,
    _MEASURED_PLATEAU,
    DRAFT_MODELS,
    MAX_FORMATION_RIDERS,
    DraftModel,
    Power,
    _group_power,
)

FormationShape = Literal["single", "double", "bunch", "echelon"]
FORMATION_SHAPES: tuple[FormationShape, ...] = ("single", "double", "bunch", "echelon")
BIKE_LENGTH_M = 1.70
"""Wheel-to-wheel length of one bike (m): a gap is measured from a front wheel to the rear wheel ahead."""
BUNCH_WIDTH = 8
"""Riders abreast where a bunch stops widening (Blocken et al. 2018's peloton widens row by row behind its leader)."""
ECHELON_WIDTH = BUNCH_WIDTH
"""Riders in one echelon: it reaches across a road as wide as a bunch's widest row, and the riders who find no place
in it ride in the next echelon behind, as the groups of a race split by a crosswind do."""

# Wake-model constants of formation_drag ("measured"), fitted to Blocken et al. 2018's 121-rider map (see
# docs/peloton.md for the fit and its residuals). The single-file part reuses the line model's constants
# (kernels.cycling.power_law).
WAKE_WIDTH_M = 0.4507
"""Lateral scale σ of a rider's own wake: shelter from a rider ahead falls as exp(−(Δy/σ)²) (halved at 0.38 m)."""
BUNCH_OFFSET_M = 0.4084
"""Lateral offset at which a rider ahead adds most to the bunch's shelter, (Δy/s)²·exp(−(Δy/s)²) (peak at s)."""
BUNCH_SHELTER = 0.7919
"""Strength β of the bunch's shelter: drag × exp(−β·Σ offset weights of the riders ahead)."""
BUNCH_FADE_M = 10.7038
"""Fade length of the bunch's shelter with the gap to each rider ahead (m)."""
BUNCH_PUSH = 0.1661
"""Strength γ of the push an exposed rider gets from the riders behind it, off its axis (the bunch behind a leader)."""


def formation(
    n_riders: int, shape: FormationShape, *, gap_m: float = 0.3, lateral_m: float = 0.6
) -> NDArray[np.float64]:
    """Rider positions of a group formation, leader first.

    Shapes:

    * ``"single"``: a line, each rider one bike plus ``gap_m`` behind the one ahead (what
      :func:`kernels.cycling.drag_reduction` models).
    * ``"double"``: a two-abreast paceline, pairs ``lateral_m`` apart; an odd last rider rides behind the left file.
    * ``"bunch"``: a peloton after Blocken et al. 2018 (J. Wind Eng. Ind. Aerodyn. 179:319): one leader, then rows
      one rider wider each until :data:`BUNCH_WIDTH` abreast, then rows of 8 and 7 alternately; every row is centred
      on the road, so neighbouring rows are staggered by half a rider. Rows are one bike plus ``gap_m`` apart.
    * ``"echelon"``: diagonal lines of up to :data:`ECHELON_WIDTH` riders, each rider half a bike plus ``gap_m``
      behind the one ahead and ``lateral_m`` to its right; a full echelon spans the road, so the next rider starts
      the next echelon at the leader's side, one bike plus ``gap_m`` behind the last rider of the one ahead.

    Args:
        n_riders: riders (1 to :data:`MAX_FORMATION_RIDERS`).
        shape: one of :data:`FORMATION_SHAPES`.
        gap_m: wheel-to-wheel gap between rows (m, 0 to 50).
        lateral_m: distance between the centres of riders side by side (m, 0.3 to 5).

    Returns:
        (n_riders, 2) positions (m): x forward along the road (leader at 0, the others behind at x < 0), y to the
        left of the road's axis.

    Raises:
        ValueError: an argument is out of range; the message names it.
    """
    _checks.integer("n_riders", n_riders)
    if not 1 <= n_riders <= MAX_FORMATION_RIDERS:
        raise ValueError(f"n_riders must be in [1, {MAX_FORMATION_RIDERS}], got {_checks.shown(n_riders)}")
    gap = _checks.non_negative("gap_m", gap_m)
    if gap > 50.0:
        raise ValueError(f"gap_m must be at most 50 m, got {_checks.shown(gap_m)}")
    lateral = _checks.finite_number("lateral_m", lateral_m)
    if not 0.3 <= lateral <= 5.0:
        raise ValueError(f"lateral_m must be in [0.3, 5] m, got {_checks.shown(lateral_m)}")
    _checks.choice("shape", shape, FORMATION_SHAPES)
    n = int(n_riders)
    k = np.arange(n, dtype=np.float64)
    step = BIKE_LENGTH_M + gap
    match shape:
        case "single":
            return np.stack([-k * step, np.zeros(n)], axis=1).astype(np.float64)
        case "double":
            return np.stack([-np.floor(k / 2) * step, np.where(k % 2 == 0, 0.5, -0.5) * lateral], axis=1).astype(
                np.float64
            )
        case "echelon":
            # Rider k rides in echelon k // ECHELON_WIDTH, place k % ECHELON_WIDTH: a half-bike step back along it,
            # one whole bike back from the end of one echelon to the start of the next.
            row, place = np.divmod(k, ECHELON_WIDTH)
            x = -(k - row) * (0.5 * BIKE_LENGTH_M + gap) - row * step
            return np.stack([x, -place * lateral], axis=1).astype(np.float64)
        case "bunch":
            xs: list[float] = []
            ys: list[float] = []
            row = 0
            while len(xs) < n:
                # Rows one wider each up to BUNCH_WIDTH, then BUNCH_WIDTH − 1 and BUNCH_WIDTH alternately (staggered).
                width = row + 1 if row < BUNCH_WIDTH else BUNCH_WIDTH - 1 + (row - BUNCH_WIDTH) % 2
                ys += [(j - 0.5 * (width - 1)) * lateral for j in range(width)]
                xs += [-row * step] * width
                row += 1
            return np.stack([np.array(xs[:n]), np.array(ys[:n])], axis=1)


def _plateau(depth: NDArray[np.float64]) -> NDArray[np.float64]:
    """The line model's close-gap reduction R at a (fractional) number of riders ahead: 0, R₂, R₃, R₄… joined by
    straight lines, so a whole number ``k − 1`` ahead gives position k's plateau exactly."""
    table = np.array([0.0, *_MEASURED_PLATEAU])
    return np.interp(depth, np.arange(table.size, dtype=np.float64), table)


def apparent_yaw(speed_ms: float, headwind_ms: float = 0.0, crosswind_ms: float = 0.0) -> float:
    """Yaw ψ (rad) of the air a rider meets: the angle between the direction of travel and where the apparent wind
    comes from, + from the left. ψ = atan2(crosswind, speed + headwind); 0 in still air or a pure head or tail wind.

    Args:
        speed_ms: ground speed (m/s, ≥ 0).
        headwind_ms: wind component against the direction of travel (m/s, negative for a tailwind).
        crosswind_ms: wind component across it (m/s, + blowing from the rider's left).

    Raises:
        ValueError: an argument is not a finite number (or the speed is negative); the message names it.
    """
    speed = _checks.non_negative("speed_ms", speed_ms)
    head = _checks.finite_number("headwind_ms", headwind_ms)
    cross = _checks.finite_number("crosswind_ms", crosswind_ms)
    return math.atan2(cross, speed + head) if cross != 0.0 else 0.0


def formation_drag(
    positions_xy: ArrayLike, model: DraftModel = "measured", *, yaw_rad: float = 0.0
) -> NDArray[np.float64]:
    """Each rider's air drag in a formation, as a fraction of the same rider riding alone at the same speed.

    A wake model over the (N, N) offsets: rider j rides Δx = x_j − x_i ahead of rider i and Δy = y_j − y_i to its
    side; the gap between them is g = max(Δx − L, 0), L = :data:`BIKE_LENGTH_M`, and φ = clip(Δx/L, 0, 1) says how
    far j is ahead (0 side by side, 1 from a bike length on). With a(Δy) = exp(−(Δy/σ)²) the rider's own wake and
    b(Δy) = (Δy/s)²·exp(−(Δy/s)²) the offset riders of a bunch (b(0) = 0)::

        depth_i = Σ_j a·φ                          riders ahead in i's wake (whole riders in a line)
        near_i  = max_j a·φ·exp(−g/9.7 m)          the closest shelter
        line_i  = R(depth_i)·near_i                 R: the line model's plateaus 0, 0.40, 0.48, 0.50…
        bunch_i = exp(−β·Σ_j b·φ·exp(−g/F))         the shelter of a bunch around and ahead of i
        push_i  = (1 − min(depth_i, 1))·(p + q − p·q),  p = 0.03·max_j a·φ'·exp(−g'/1.5 m),
                  q = 1 − exp(−γ·Σ_j b·φ'·exp(−g'/1.5 m))   (φ', g' for the riders behind i)
        drag_i  = (1 − push_i)·(1 − line_i)·bunch_i

    In single file every Δy is 0, so b = 0, depth is the number of riders ahead and near the gap's fade: the
    model is :func:`kernels.cycling.drag_reduction` exactly (drag = 1 − reduction). The constants σ, s, β, F and γ
    (:data:`WAKE_WIDTH_M`, :data:`BUNCH_OFFSET_M`, :data:`BUNCH_SHELTER`, :data:`BUNCH_FADE_M`, :data:`BUNCH_PUSH`)
    are fitted to Blocken et al. 2018 (J. Wind Eng. Ind. Aerodyn. 179:319, CFD of a 121-rider peloton validated in a
    wind tunnel): leader 0.88, second row 0.63, the middle of the third row 0.38, the middle of the bunch 0.05–0.10 and
    the back 0.04–0.05 of a lone rider's drag. Every term only grows with more riders, so adding a rider behind the
    group (or anywhere ahead of nobody) never raises anyone's drag, and the kernels are even in Δy, so the mirror
    image across the road's axis gives the same drags.

    Crosswind: every wake trails downwind along the apparent wind, so the offsets are measured in the wind's frame,
    the layout turned by the yaw ``yaw_rad`` (:func:`apparent_yaw`): Δx' = Δx·cos ψ + Δy·sin ψ, Δy' = −Δx·sin ψ +
    Δy·cos ψ. A line along the road then loses its shelter to the side, and an echelon angled downwind keeps it: the
    reason riders form one. Checked against the one crosswind study found (Fintelman-type CFD of five riders at
    30 km/h in a 30 km/h wind at 40°, ψ = 20°; J. Sci. Med. Sport 2022, doi 10.1016/j.jsams.2022.12.003): the
    leader of a straight line saves 0.1 % of its drag, the fourth rider of an echelon in the wind's shadow 53.6 %.
    The drag is a fraction of the same rider's alone in the same wind; how a rider's own drag grows with yaw is not
    modelled.

    ``model="textbook"``: the textbook formula for any layout, drag = 1 − 0.27·max_j a·φ·exp(−g/3.5 m) (in single file,
    :func:`kernels.cycling.draft_factor` for every follower and 1 for the leader).

    Args:
        positions_xy: (N, 2) rider positions (m), x forward along the road, y to the left, any order; N ≥ 1.
        model: ``"measured"`` (the wake model above) or ``"textbook"``.
        yaw_rad: yaw of the apparent wind (rad, + from the left, |ψ| < π/2); 0 for still air or a head wind.

    Returns:
        (N,) drag fractions in (0, 1], in the order of ``positions_xy``.

    Raises:
        ValueError: ``positions_xy`` is not a finite (N, 2) array with 1 ≤ N ≤ 2000 and |coordinates| ≤ 10⁶ m,
            ``model`` is unknown, or ``yaw_rad`` is not a finite number in (−π/2, π/2).
    """
    pos = _checks.bounded_array("positions_xy", positions_xy, 1e6)
    if pos.ndim != 2 or pos.shape[1] != 2 or not 1 <= pos.shape[0] <= 2000:
        raise ValueError(f"positions_xy must have shape (N, 2) with 1 <= N <= 2000, got {pos.shape}")
    _checks.choice("model", model, DRAFT_MODELS)
    yaw = _checks.finite_number("yaw_rad", yaw_rad)
    if not abs(yaw) < 0.5 * math.pi:
        raise ValueError(f"yaw_rad must be in (-pi/2, pi/2), got {_checks.shown(yaw_rad)}")
    x, y = pos[:, 0], pos[:, 1]
    if yaw != 0.0:  # offsets in the wind's frame: its x toward where the apparent wind comes from
        c, s = math.cos(yaw), math.sin(yaw)
        x, y = c * x + s * y, -s * x + c * y
    dx = x[None, :] - x[:, None]  # [i, j]: how far rider j rides ahead of rider i
    dy = y[None, :] - y[:, None]
    own_wake = np.exp(-((dy / WAKE_WIDTH_M) ** 2))
    ahead = np.clip(dx / BIKE_LENGTH_M, 0.0, 1.0)
    gap_ahead = np.maximum(dx - BIKE_LENGTH_M, 0.0)
    if model == "textbook":
        shelter = (own_wake * ahead * np.exp(-gap_ahead / 3.5)).max(axis=1)
        return 1.0 - 0.27 * shelter
    q = (dy / BUNCH_OFFSET_M) ** 2
    offset = q * np.exp(-q)
    behind = np.clip(-dx / BIKE_LENGTH_M, 0.0, 1.0)
    gap_behind = np.maximum(-dx - BIKE_LENGTH_M, 0.0)
    depth = (own_wake * ahead).sum(axis=1)
    near = (own_wake * ahead * np.exp(-gap_ahead / _MEASURED_FADE_M)).max(axis=1)
    line = _plateau(depth) * near
    bunch = np.exp(-BUNCH_SHELTER * (offset * ahead * np.exp(-gap_ahead / BUNCH_FADE_M)).sum(axis=1))
    fade_behind = behind * np.exp(-gap_behind / _LEADER_FADE_M)
    push_line = _LEADER_PLATEAU * (own_wake * fade_behind).max(axis=1)
    push_bunch = 1.0 - np.exp(-BUNCH_PUSH * (offset * fade_behind).sum(axis=1))
    push = (1.0 - np.minimum(depth, 1.0)) * (push_line + push_bunch - push_line * push_bunch)
    return (1.0 - push) * (1.0 - line) * bunch


def formation_power(
    positions_xy: ArrayLike,
    speed_ms: float,
    cda_m2: float,
    mass_kg: float,
    crr: float,
    grade: float = 0.0,
    altitude_m: float = 0.0,
    headwind_ms: float = 0.0,
    drivetrain_efficiency: float = 1.0,
    model: DraftModel = "measured",
) -> Power:
    """Power of each rider of a formation at the group's speed: :func:`kernels.cycling.power` at
    CdA·:func:`formation_drag`.

    Args:
        positions_xy: (N, 2) rider positions (m), as for :func:`formation_drag`.
        model: ``"measured"`` or ``"textbook"`` (see :func:`formation_drag`).
        Other arguments as for :func:`kernels.cycling.power`, for one rider riding alone: each one number (the
            riders are alike).

    Returns:
        :class:`Power` whose fields have shape (N,), in the order of ``positions_xy``.

    Raises:
        ValueError: an argument is not a number (an array included) or out of its range; the message names it.
    """
    return _group_power(
        "formation_power",
        lambda: formation_drag(positions_xy, model),
        speed_ms,
        cda_m2,
        mass_kg,
        crr,
        grade,
        altitude_m,
        headwind_ms,
        drivetrain_efficiency,
    )
