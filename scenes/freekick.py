"""Free kick: a spinning ball's 3D flight over a wall, with its forces, a no-spin ghost, a ±10 % spin band and the
knuckleball.

Physics comes from :mod:`kernels.ball`; this module owns the viser handles. The world frame is the pitch's: the goal
line is x = 0 with the goal centred on y = 0 and its net toward +x, the ball sits on the pitch (x < 0), y is to the
kicker's left when facing the goal, z is up. Paths are resampled to a fixed number of points so every redraw writes
the same nodes' arrays (line-segment points, one band mesh's vertices) and never re-adds a node.

Two searches run on a worker thread, never on a callback: the outcome map (a speed × spin grid through
:func:`kernels.ball.simulate_batch`) and "aim at a clicked point of the goal mouth". The worker only ever runs the
latest request (one worker each); a newer request makes an older one's result be dropped, and the map waits for the
settings to be still for a moment so dragging a slider redraws at full speed.
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
import logging
import math
import threading
import time
from collections.abc import Callable
from typing import Literal

import numpy as np
import trimesh
import viser
import viser.uplot
from numpy.typing import NDArray

from kernels import ball
from scenes._base import Scene, set_if_changed
from scenes._charts import FittedChart
from scenes._framing import ClientFraming, Lens, View, frame_points

logger = logging.getLogger(__name__)

PATH_POINTS = 160
"""Samples per drawn path (trajectory, ghost, band edges)."""
ARROW_POINTS = 4
"""Places along the path where force arrows are drawn (few enough that neighbouring arrows never overlap)."""
METRES_PER_NEWTON = 0.3
"""Force-arrow length scale."""
JUMP_M = 0.35
"""How much higher a jumping wall reaches (m)."""
DEFENDER_HEIGHT_M = 1.8
"""Top of a standing defender's head (m)."""
DEFENDERS = 4
DEFENDER_WIDTH_M = 0.5

SpinAxis = Literal["left", "right", "top", "back", "custom"]
SPIN_AXIS_LABELS: dict[SpinAxis, str] = {
    "left": "Sidespin, curls left",
    "right": "Sidespin, curls right",
    "top": "Topspin (dips)",
    "back": "Backspin (floats)",
    "custom": "Custom (two angles)",
}
SPIN_AXIS_FROM_LABEL: dict[str, SpinAxis] = {label: key for key, label in SPIN_AXIS_LABELS.items()}
MODEL_LABELS: dict[ball.Model, str] = {
    "measured": "Measured C_D(Re, S), C_L(S)",
    "constant": "Constant C_D = C_L = 0.25 (seed)",
}
MODEL_FROM_LABEL: dict[str, ball.Model] = {label: key for key, label in MODEL_LABELS.items()}
Integrator = Literal["rk4", "euler"]
INTEGRATOR_LABELS: dict[Integrator, str] = {"rk4": "RK4, 10 ms", "euler": "Euler, 1 ms (seed)"}
INTEGRATOR_FROM_LABEL: dict[str, Integrator] = {
    label: key for key, label in INTEGRATOR_LABELS.items()
}
INTEGRATOR_STEP_S: dict[Integrator, float] = {"rk4": 1e-2, "euler": 1e-3}
BAND_STEP_S = 2e-2
"""Step of the ±10 % spin band's flights (RK4): they are drawn, not measured, and must not slow a redraw."""

RESULT_COLOURS: dict[str, tuple[int, int, int]] = {
    "goal": (40, 180, 70),
    "wall": (210, 50, 50),
    "over": (245, 150, 40),
    "wide": (240, 215, 60),
    "short": (140, 140, 140),
}
FORCE_COLOURS = {"drag": (230, 40, 40), "magnus": (40, 90, 240), "gravity": (120, 50, 170)}
"""Arrow and chart colours: red, blue and purple read on grass, sky and the white net alike."""
KNUCKLE_COLOUR = (240, 150, 20)
PATH_COLOUR = (255, 140, 0)
"""The kick as set: a thick orange line."""
GHOST_COLOUR = (40, 40, 40)
"""The no-spin ghost: thin, dark and dashed, so it never reads as the kick itself."""

ViewName = Literal["broadcast", "behind", "side", "goal", "above"]
VIEW_LABELS: dict[ViewName, str] = {
    "broadcast": "Raised, behind and to the side",
    "behind": "Behind the ball",
    "side": "Side-on",
    "goal": "From the goal",
    "above": "From above",
}
VIEW_FROM_LABEL: dict[str, ViewName] = {label: key for key, label in VIEW_LABELS.items()}
VIEW_MIN_DEPTH_M: dict[ViewName, float] = {
    "broadcast": 3.0,
    "behind": 4.0,
    "side": 3.0,
    "goal": 1.0,
    "above": 3.0,
}
"""How far in front of each view's camera everything stays (m): behind the ball means a few steps back."""
KEEPER_SEES_FROM_M = 5.0
"""The goalkeeper's view keeps the path in frame only while it is at least this far out from the goal line (m):
the last metres fly past the camera, as they fly past a keeper."""
KEEPER_LOOK_DOWN = (0.25, 0.5, 0.8, 1.2, 2.0, 3.0)
"""Downward tilts (per unit of horizontal look) the goalkeeper's view tries, flattest first."""
KEEPER_LOOK_ASIDE = (0.3, -0.3, 0.0)
"""Sideways turns (per unit of horizontal look, + toward the kicker's left) it tries at each tilt: a keeper steps
to one side to see the ball past the wall."""
KEEPER_FRONT_M = 0.3
"""How far in front of the goal line (x < 0) the goalkeeper's camera stands at least (m)."""

MAP_SPEEDS_MS = np.linspace(15.0, 35.0, 41)
"""Outcome-map columns: launch speed (m/s)."""
MAP_SPINS_REV_S = np.linspace(0.0, 15.0, 31)
"""Outcome-map rows: spin rate (rev/s), bottom to top."""
MAP_CELL_PX = 6
MAP_QUIET_S = 0.25
"""The outcome map is recomputed once the settings have been still this long (s), not on every slider step."""


@dataclasses.dataclass(frozen=True)
class FreeKickParams:
    """Everything the scene shows is a function of these; defaults are the opening state (a curler)."""

    distance_m: float = 22.0
    """Distance from the ball to the centre of the goal line (m)."""
    angle_deg: float = 0.0
    """Where the spot is, seen from the goal: angle off the pitch's centre line, + toward the kicker's left (°)."""
    speed_ms: float = 25.0
    """Launch speed (m/s)."""
    elevation_deg: float = 17.0
    """Launch angle above the ground (°)."""
    azimuth_deg: float = -9.0
    """Launch direction relative to the line from ball to goal centre, + to the left (°)."""
    spin_rev_s: float = 8.0
    """Spin rate (rev/s)."""
    spin_axis: SpinAxis = "left"
    """Spin axis: sidespin either way, topspin, backspin, or custom."""
    axis_tilt_deg: float = 0.0
    """Custom axis: tilt from vertical toward the kicker's left (°); 0 is sidespin left, 90 topspin."""
    axis_turn_deg: float = 0.0
    """Custom axis: turn of the tilted part toward the kick direction (°); 90 with tilt 90 is rifle spin."""
    model: ball.Model = "measured"
    """Coefficient model: the measured one, under which the spin rate changes the flight; the seed's constant one
    curls every spinning kick alike."""
    integrator: Integrator = "rk4"
    """Integrator and its step."""
    knuckle: bool = False
    """Unsteady knuckleball side force (only acts with near-zero spin)."""
    knuckle_seed: int = 1
    """Seed of the knuckleball's side force: the same seed, the same flight."""
    wall_jumps: bool = False
    """Whether the wall jumps (its top rises by 0.35 m)."""


@dataclasses.dataclass(frozen=True)
class Preset:
    label: str
    """Button text."""
    params: FreeKickParams
    """The kick, from the default spot unless it names another."""


PRESETS: tuple[Preset, ...] = (
    Preset("Curler round the wall", FreeKickParams()),
    Preset(
        "Dipping topspin",
        FreeKickParams(
            speed_ms=28.0, elevation_deg=21.0, azimuth_deg=0.0, spin_rev_s=8.0, spin_axis="top"
        ),
    ),
    Preset(
        "Knuckleball",
        FreeKickParams(
            distance_m=27.0,
            speed_ms=29.0,
            elevation_deg=15.0,
            azimuth_deg=0.0,
            spin_rev_s=0.0,
            model="measured",
            knuckle=True,
            knuckle_seed=4,
        ),
    ),
    Preset(
        "Long-range swerve",
        FreeKickParams(
            distance_m=32.0,
            angle_deg=-10.0,
            speed_ms=30.0,
            elevation_deg=18.5,
            azimuth_deg=-10.0,
            spin_rev_s=9.0,
            spin_axis="custom",
            axis_tilt_deg=8.0,
            axis_turn_deg=0.0,
        ),
    ),
)


# --------------------------------------------------------------------------------------------- kick geometry
def ball_spot(p: FreeKickParams) -> NDArray[np.float64]:
    """(3,) centre of the ball on its spot (m)."""
    a = math.radians(p.angle_deg)
    return np.array([-p.distance_m * math.cos(a), p.distance_m * math.sin(a), ball.BALL_RADIUS_M])


def aim_heading_rad(p: FreeKickParams) -> float:
    """Heading (rad, from +x toward +y) of the launch direction."""
    spot = ball_spot(p)
    return math.atan2(-spot[1], -spot[0]) + math.radians(p.azimuth_deg)


def launch_velocity(p: FreeKickParams, speed_ms: float | None = None) -> NDArray[np.float64]:
    return ball.launch_velocity(
        p.speed_ms if speed_ms is None else speed_ms,
        math.radians(p.elevation_deg),
        aim_heading_rad(p),
    )


def spin_axis(p: FreeKickParams) -> NDArray[np.float64]:
    """(3,) unit spin axis in the world, from the preset kind or the two custom angles, relative to the kick."""
    heading = aim_heading_rad(p)
    forward = np.array([math.cos(heading), math.sin(heading), 0.0])
    left = np.array([-math.sin(heading), math.cos(heading), 0.0])
    up = np.array([0.0, 0.0, 1.0])
    match p.spin_axis:
        case "left":
            return up
        case "right":
            return -up
        case "top":
            return left
        case "back":
            return -left
        case "custom":
            tilt, turn = math.radians(p.axis_tilt_deg), math.radians(p.axis_turn_deg)
            return math.cos(tilt) * up + math.sin(tilt) * (
                math.cos(turn) * left + math.sin(turn) * forward
            )


def spin_vector(p: FreeKickParams, scale: float = 1.0) -> NDArray[np.float64]:
    """(3,) ω (rad/s)."""
    return ball.spin_vector(p.spin_rev_s * scale, spin_axis(p))


def panels(p: FreeKickParams) -> tuple[ball.Panel, ball.Panel]:
    """The wall (shifted to cover the near post once the spot is off-centre) and the goal mouth."""
    spot = ball_spot(p)
    height = DEFENDER_HEIGHT_M + (JUMP_M if p.wall_jumps else 0.0)
    width = DEFENDERS * DEFENDER_WIDTH_M
    offset = 0.0
    if abs(p.angle_deg) >= 5.0:
        # The wall's outside defender stands on the line from the ball to the near post.
        near_post = np.array([0.0, math.copysign(0.5 * ball.GOAL_WIDTH_M, spot[1])])
        aim = -spot[:2] / np.linalg.norm(spot[:2])
        to_post = near_post - spot[:2]
        left = np.array([-aim[1], aim[0]])
        post_lateral = ball.WALL_DISTANCE_M * float(to_post @ left) / float(to_post @ aim)
        offset = post_lateral - math.copysign(0.5 * width - 0.5 * DEFENDER_WIDTH_M, post_lateral)
    return ball.free_kick_panels(
        spot[:2],
        (0.0, 0.0),
        (1.0, 0.0),
        wall_width_m=width,
        wall_height_m=height,
        wall_offset_m=offset,
    )


# --------------------------------------------------------------------------------------------- flight
@dataclasses.dataclass(frozen=True)
class KickState:
    """The kick, its comparisons and its verdict for one parameter set."""

    flight: ball.Trajectory
    """The kick as set."""
    ghost: ball.Trajectory
    """The same kick with no spin."""
    less_spin: ball.Trajectory
    """Spin × 0.9."""
    more_spin: ball.Trajectory
    """Spin × 1.1."""
    outcome: ball.Outcome
    """What the kick did."""
    ghost_outcome: ball.Outcome
    """What the no-spin kick did."""
    wall: ball.Panel
    goal: ball.Panel


def _fly(
    p: FreeKickParams, spin_scale: float, *, knuckle: bool, band: bool = False
) -> ball.Trajectory:
    """One flight; ``band`` flights (only drawn, never measured) use RK4 at 20 ms, well under a millimetre off."""
    return ball.simulate(
        ball_spot(p),
        launch_velocity(p),
        spin_vector(p, spin_scale),
        dt=BAND_STEP_S if band else INTEGRATOR_STEP_S[p.integrator],
        method="rk4" if band else p.integrator,
        model=p.model,
        t_max=4.0,
        x_stop=2.0,  # two metres into the net: far enough to see the ball cross the line
        ground_m=ball.BALL_RADIUS_M,
        knuckle_seed=p.knuckle_seed if (knuckle and p.knuckle) else None,
    )


def compute_kick(p: FreeKickParams) -> KickState:
    """Run the kernels for one parameter set (no viser: testable on its own).

    The no-spin ghost is flown once per launch and wall (:func:`_ghost_kick`): while only the spin or the knuckleball
    settings change, as when the spin slider is dragged, it is reused rather than flown again.
    """
    wall, goal = panels(p)
    flight = _fly(p, 1.0, knuckle=True)
    ghost, ghost_outcome = _ghost_kick(_without_spin(p))
    return KickState(
        flight=flight,
        ghost=ghost,
        less_spin=_fly(p, 0.9, knuckle=True, band=True),
        more_spin=_fly(p, 1.1, knuckle=True, band=True),
        outcome=ball.outcome(flight, wall, goal),
        ghost_outcome=ghost_outcome,
        wall=wall,
        goal=goal,
    )


def _without_spin(p: FreeKickParams) -> FreeKickParams:
    """``p`` with its spin and knuckleball settings at their defaults: all its no-spin ghost depends on."""
    plain = FreeKickParams()
    return dataclasses.replace(
        p,
        spin_rev_s=0.0,
        spin_axis=plain.spin_axis,
        axis_tilt_deg=plain.axis_tilt_deg,
        axis_turn_deg=plain.axis_turn_deg,
        knuckle=False,
        knuckle_seed=plain.knuckle_seed,
    )


@functools.lru_cache(maxsize=8)
def _ghost_kick(p: FreeKickParams) -> tuple[ball.Trajectory, ball.Outcome]:
    """The kick ``p`` with no spin and its outcome, kept for the last few launches (its arrays are read-only)."""
    wall, goal = panels(p)
    ghost = _fly(p, 0.0, knuckle=False)
    # Shared by every state of this launch: a write would corrupt them all, so refuse it.
    for field in dataclasses.fields(ghost):
        value = getattr(ghost, field.name)
        if isinstance(value, np.ndarray):
            value.flags.writeable = False
    return ghost, ball.outcome(ghost, wall, goal)


def sample_rows(
    times: NDArray[np.float64], t: NDArray[np.float64], values: NDArray[np.float64]
) -> NDArray[np.float64]:
    """(M, C) ``values`` (N, C), given at the increasing sample times ``t`` (N,), interpolated linearly at ``times``
    (M,), clamped to ``[t[0], t[-1]]``: ``np.interp`` on every column at once. One ``np.interp`` finds each time's
    fractional row (``np.interp`` clamps, and is compiled); the columns are then blended in one step (a redraw
    once called ``np.interp`` 33 times; a search and masks of our own took 59 µs a path, this 17 µs)."""
    if len(t) == 1:
        return np.repeat(values[:1], len(times), axis=0)
    row = np.interp(times, t, np.arange(len(t), dtype=np.float64))
    i = np.minimum(row.astype(np.intp), len(t) - 2)
    w = (row - i)[:, None]
    return values[i] + w * (values[i + 1] - values[i])


def resample(flight: ball.Trajectory, n: int = PATH_POINTS) -> NDArray[np.float64]:
    """(n, 3) positions at n evenly spaced times over the flight."""
    return sample_rows(np.linspace(0.0, float(flight.t[-1]), n), flight.t, flight.position)


def position_at(flight: ball.Trajectory, t: float) -> NDArray[np.float64]:
    """(3,) ball centre at time t (clamped to the flight)."""
    return sample_rows(np.array([float(t)]), flight.t, flight.position)[0]


def deflection_m(state: KickState) -> float | None:
    """Sideways distance at the goal line between the kick and its no-spin ghost (m, + = left)."""
    a, b = state.outcome.goal_point, state.ghost_outcome.goal_point
    if a is None or b is None:
        return None
    return float(a[1] - b[1])


def outcome_map(p: FreeKickParams) -> NDArray[np.str_]:
    """(spins, speeds) results over :data:`MAP_SPEEDS_MS` × :data:`MAP_SPINS_REV_S` with the other settings kept.

    With the knuckleball on, every cell flies with ``p.knuckle_seed`` (the side force fades out as the spin grows,
    so it matters in the low-spin rows only), as the kick itself does.
    """
    wall, goal = panels(p)
    speeds, spins = np.meshgrid(MAP_SPEEDS_MS, MAP_SPINS_REV_S)
    heading, elevation = aim_heading_rad(p), math.radians(p.elevation_deg)
    direction = ball.launch_velocity(1.0, elevation, heading)
    axis = spin_axis(p)
    k = speeds.size
    judged = ball.simulate_outcomes(
        np.tile(ball_spot(p), (k, 1)),
        speeds.reshape(-1, 1) * direction,
        (2.0 * math.pi * spins.reshape(-1, 1)) * axis,
        wall,
        goal,
        dt=INTEGRATOR_STEP_S["rk4"],
        method="rk4",
        model=p.model,
        t_max=4.0,
        x_stop=0.5,
        ground_m=ball.BALL_RADIUS_M,
        knuckle_seeds=[p.knuckle_seed] * k if p.knuckle else None,
    )
    return judged.result.reshape(spins.shape)


def outcome_map_image(results: NDArray[np.str_], p: FreeKickParams) -> NDArray[np.uint8]:
    """RGB image of an outcome map, speed left to right, spin bottom to top, the current kick marked in white."""
    rows, cols = results.shape
    image = np.zeros((rows, cols, 3), np.uint8)
    for name, colour in RESULT_COLOURS.items():
        image[results == name] = colour
    image = image[::-1]  # spin grows upward
    image = np.repeat(np.repeat(image, MAP_CELL_PX, axis=0), MAP_CELL_PX, axis=1)
    col = int(np.argmin(np.abs(MAP_SPEEDS_MS - p.speed_ms)))
    row = rows - 1 - int(np.argmin(np.abs(MAP_SPINS_REV_S - p.spin_rev_s)))
    cy, cx = row * MAP_CELL_PX + MAP_CELL_PX // 2, col * MAP_CELL_PX + MAP_CELL_PX // 2
    image[cy, max(cx - 6, 0) : cx + 7] = 255
    image[max(cy - 6, 0) : cy + 7, cx] = 255
    return image


AIM_TOLERANCE_M = 0.15
"""Largest miss (m) between the clicked point and the found kick's goal-line crossing; beyond it :func:`aim_at`
returns None. About 1.4 ball radii: the ball still covers the point."""


def aim_at(p: FreeKickParams, target_yz: tuple[float, float]) -> FreeKickParams | None:
    """A kick at the same speed that reaches ``target_yz`` (m) on the goal line over the wall, or None.

    Searches elevation, azimuth and sidespin on a grid with :func:`kernels.ball.simulate_outcomes`, then polishes the
    best goal-scoring candidate's elevation and azimuth by damped Newton steps on the crossing point (a step that
    leaves the goal or misses by more is halved, up to five times). Returns None when no goal is found or the best
    kick still misses the target by more than :data:`AIM_TOLERANCE_M`. A kick without spin keeps ``p``'s spin axis
    (its direction is moot; :func:`spin_words` says "no spin").
    """
    wall, goal = panels(p)
    target = np.array(target_yz, dtype=np.float64)
    elevations = np.linspace(4.0, 35.0, 16)
    azimuths = np.linspace(-25.0, 25.0, 21)
    spins = np.array([-10.0, -7.0, -4.0, 0.0, 4.0, 7.0, 10.0])  # + curls left
    e, a, s = (g.ravel() for g in np.meshgrid(elevations, azimuths, spins, indexing="ij"))
    spot = ball_spot(p)
    heading = math.atan2(-spot[1], -spot[0]) + np.radians(a)
    elevation = np.radians(e)
    velocities = p.speed_ms * np.stack(
        [
            np.cos(elevation) * np.cos(heading),
            np.cos(elevation) * np.sin(heading),
            np.sin(elevation),
        ],
        axis=1,
    )
    omegas = np.zeros((len(e), 3))
    omegas[:, 2] = 2.0 * math.pi * s
    judged = ball.simulate_outcomes(
        np.tile(spot, (len(e), 1)),
        velocities,
        omegas,
        wall,
        goal,
        dt=1e-2,
        method="rk4",
        model=p.model,
        t_max=4.0,
        x_stop=0.5,
        ground_m=ball.BALL_RADIUS_M,
    )
    miss = np.linalg.norm(judged.goal_point[:, 1:] - target, axis=1)
    miss[judged.result != "goal"] = np.inf
    if not np.isfinite(miss).any():
        return None
    best = int(np.argmin(miss))
    kick = dataclasses.replace(
        p,
        elevation_deg=float(e[best]),
        azimuth_deg=float(a[best]),
        spin_rev_s=abs(float(s[best])),
        spin_axis=p.spin_axis if s[best] == 0 else ("left" if s[best] > 0 else "right"),
        knuckle=False,
    )

    def crossing(k: FreeKickParams) -> NDArray[np.float64] | None:
        point = ball.outcome(_fly(k, 1.0, knuckle=False), wall, goal).goal_point
        return None if point is None else point[1:]

    def goal_crossing(k: FreeKickParams) -> NDArray[np.float64] | None:
        judged = ball.outcome(_fly(k, 1.0, knuckle=False), wall, goal)
        return (
            None if judged.result != "goal" or judged.goal_point is None else judged.goal_point[1:]
        )

    here = goal_crossing(kick)
    for _ in range(8):  # damped Newton on (elevation, azimuth) -> (y, z) at the goal line
        if here is None:
            break
        error = target - here
        if np.linalg.norm(error) < 0.01:
            break
        h = 0.05
        de = crossing(dataclasses.replace(kick, elevation_deg=kick.elevation_deg + h))
        da = crossing(dataclasses.replace(kick, azimuth_deg=kick.azimuth_deg + h))
        if de is None or da is None:
            break
        jacobian = np.column_stack([(de - here) / h, (da - here) / h])
        try:
            step = np.linalg.solve(jacobian, error)
        except np.linalg.LinAlgError:
            break
        step = np.clip(step, -3.0, 3.0)
        for _halving in range(
            6
        ):  # backtrack: halve a step that leaves the goal or does not get closer
            trial = dataclasses.replace(
                kick,
                elevation_deg=float(np.clip(kick.elevation_deg + step[0], -5.0, 50.0)),
                azimuth_deg=float(np.clip(kick.azimuth_deg + step[1], -30.0, 30.0)),
            )
            there = goal_crossing(trial)
            if there is not None and np.linalg.norm(target - there) < np.linalg.norm(error):
                break
            step = 0.5 * step
        else:
            break
        kick, here = trial, there
    if here is None or np.linalg.norm(target - here) > AIM_TOLERANCE_M:
        return None
    return kick


def spin_words(p: FreeKickParams) -> str:
    """The spin as a person says it: "no spin", or "8.0 rev/s sidespin, curls left"."""
    if p.spin_rev_s <= 0.0:
        return "no spin"
    return f"{p.spin_rev_s:.1f} rev/s {SPIN_AXIS_LABELS[p.spin_axis].lower()}"


def view_direction(
    p: FreeKickParams,
    view: ViewName,
    look_down: float = KEEPER_LOOK_DOWN[0],
    look_aside: float = KEEPER_LOOK_ASIDE[0],
) -> NDArray[np.float64]:
    """(3,) direction a camera looks in for ``view`` of the kick ``p`` (not unit).

    ``look_down`` and ``look_aside`` tilt and turn the goalkeeper's view (per unit of horizontal look; + aside is
    toward the kicker's left); other views ignore them.
    """
    spot = ball_spot(p)
    forward = np.array([-spot[0], -spot[1], 0.0]) / max(math.hypot(spot[0], spot[1]), 1e-9)
    left = np.array([-forward[1], forward[0], 0.0])
    down = np.array([0.0, 0.0, -1.0])
    match view:
        case "broadcast":
            # High (about 50°) over the kicker's left shoulder, looking down the flight: a sideways curl runs across
            # the screen instead of along the line of sight, and the goal is in front, not far off to one side.
            return forward - 0.8 * left + 1.5 * down
        case "behind":
            return forward + 0.12 * down
        case "side":  # from the kicker's right: the ball flies left to right across the screen
            return left + 0.15 * down
        case (
            "goal"
        ):  # the goalkeeper's: from in front of the goal line, back at the ball and the wall
            return -forward + look_aside * left + look_down * down
        case "above":
            return 0.35 * forward + down


def view_points(p: FreeKickParams, state: KickState, view: ViewName) -> NDArray[np.float64]:
    """(N, 3) what ``view`` keeps in frame (m): the ball on its spot (its whole sphere), the path and the no-spin
    ghost, the wall and the goal with its net; the goalkeeper's view (``"goal"``) stands in front of the goal, so it
    keeps neither the goal nor the last :data:`KEEPER_SEES_FROM_M` of the flights.
    """
    half, h = 0.5 * ball.GOAL_WIDTH_M, ball.GOAL_HEIGHT_M
    goal = np.array([[x, y, z] for x in (0.0, 2.0) for y in (-half, half) for z in (0.0, h)])
    wall = state.wall
    normal = np.array(wall.normal_xy) / np.hypot(*wall.normal_xy)
    along = np.array([-normal[1], normal[0]])
    centre, width = np.array(wall.centre_xy), 0.5 * DEFENDERS * DEFENDER_WIDTH_M
    wall_pts = np.array(
        [
            [*(centre + side * width * along), z]
            for side in (-1.0, 1.0)
            for z in (0.0, wall.height_m)
        ]
    )
    path, ghost = resample(state.flight, 24), resample(state.ghost, 24)
    spot = ball_spot(p)
    sphere = spot + ball.BALL_RADIUS_M * np.vstack([np.eye(3), -np.eye(3)])
    if view == "goal":
        flights = np.vstack([path, ghost])
        far_out = flights[flights[:, 0] <= -KEEPER_SEES_FROM_M]
        return np.vstack([wall_pts, far_out, sphere])
    return np.vstack([goal, wall_pts, path, ghost, sphere])


def wall_hides(state: KickState, eye: NDArray[np.float64], target: NDArray[np.float64]) -> bool:
    """Whether the wall (with a ball's radius of margin) stands on the straight line from ``eye`` to ``target`` (m)."""
    wall = state.wall
    normal = np.array([*wall.normal_xy, 0.0]) / np.hypot(*wall.normal_xy)
    centre = np.array([*wall.centre_xy, 0.0])
    a, b = float((eye - centre) @ normal), float((target - centre) @ normal)
    if a * b > 0.0:  # both on one side of the wall's plane
        return False
    hit = eye + (a / (a - b)) * (target - eye)
    along = np.array([-normal[1], normal[0], 0.0])
    half = 0.5 * DEFENDERS * DEFENDER_WIDTH_M + ball.BALL_RADIUS_M
    return (
        abs(float((hit - centre) @ along)) <= half and hit[2] <= wall.height_m + ball.BALL_RADIUS_M
    )


def frame_view(p: FreeKickParams, state: KickState, view: ViewName, lens: Lens) -> View:
    """The camera pose of ``view`` for one browser's ``lens``: :func:`view_points` in frame, left of the panel.

    The goalkeeper's view tries tilts (:data:`KEEPER_LOOK_DOWN`, flattest first) and turns
    (:data:`KEEPER_LOOK_ASIDE`) until its camera stands at least :data:`KEEPER_FRONT_M` in front of the goal line
    and sees the ball past or over the wall; failing that, the last pose in front of the line, else the last tried.
    """
    points = view_points(p, state, view)
    if view == "goal":
        tries = [(down, aside) for down in KEEPER_LOOK_DOWN for aside in KEEPER_LOOK_ASIDE]
    else:
        tries = [(KEEPER_LOOK_DOWN[0], KEEPER_LOOK_ASIDE[0])]
    spot = ball_spot(p)
    framed, in_front = None, None
    for down, aside in tries:
        d = view_direction(p, view, down, aside)
        framed = frame_points(
            points,
            (float(d[0]), float(d[1]), float(d[2])),
            fov_rad=lens.fov_rad,
            aspect=lens.aspect,
            ndc=lens.usable_ndc(),
            min_depth=VIEW_MIN_DEPTH_M[view],
        )
        if view != "goal":
            return framed
        if framed.position[0] <= -KEEPER_FRONT_M:
            in_front = framed
            if not wall_hides(state, np.array(framed.position), spot):
                return framed
    assert framed is not None
    return in_front if in_front is not None else framed


def dashed(segments: NDArray[np.float32]) -> NDArray[np.float32]:
    """(S, 2, 3) the same segments with every other one shrunk to a point: a dashed line of the same node."""
    out = segments.copy()
    out[1::2, 1] = out[1::2, 0]
    return out


# --------------------------------------------------------------------------------------------- geometry
def _cylinder(a: NDArray[np.float64], b: NDArray[np.float64], radius: float) -> trimesh.Trimesh:
    return trimesh.creation.cylinder(radius=radius, segment=np.array([a, b]), sections=12)


def goal_frame_mesh() -> trimesh.Trimesh:
    """Posts and crossbar, 12 cm thick, inner edges on the goal mouth."""
    r, half, h = 0.06, 0.5 * ball.GOAL_WIDTH_M, ball.GOAL_HEIGHT_M
    parts = [
        _cylinder(np.array([r, side * (half + r), 0.0]), np.array([r, side * (half + r), h + r]), r)
        for side in (-1.0, 1.0)
    ]
    parts.append(
        _cylinder(np.array([r, -(half + 2 * r), h + r]), np.array([r, half + 2 * r, h + r]), r)
    )
    mesh = trimesh.util.concatenate(parts)
    assert isinstance(mesh, trimesh.Trimesh)
    return mesh


def net_segments(depth: float = 2.0, spacing: float = 0.3) -> NDArray[np.float64]:
    """(S, 2, 3) net lines: back, roof and sides of a box behind the goal."""
    half, h = 0.5 * ball.GOAL_WIDTH_M, ball.GOAL_HEIGHT_M
    segs: list[list[list[float]]] = []
    for y in np.arange(-half, half + 1e-6, spacing):
        segs.append([[depth, y, 0.0], [depth, y, h]])  # back, vertical
        segs.append([[0.0, y, h], [depth, y, h]])  # roof, front to back
    for z in np.arange(0.0, h + 1e-6, spacing):
        segs.append([[depth, -half, z], [depth, half, z]])  # back, horizontal
        for side in (-half, half):
            segs.append([[0.0, side, z], [depth, side, z]])  # sides
    for x in np.arange(0.0, depth + 1e-6, spacing):
        segs.append([[x, -half, h], [x, half, h]])  # roof, across
        for side in (-half, half):
            segs.append([[x, side, 0.0], [x, side, h]])
    return np.array(segs)


def pitch_markings() -> NDArray[np.float64]:
    """(S, 2, 3) white lines near the penalty area: goal line, 6-yard box, penalty area, spot and arc."""
    z = 0.005
    segs: list[tuple[tuple[float, float, float], tuple[float, float, float]]] = []

    def box(depth: float, half_width: float) -> None:
        corners = [
            (0.0, -half_width),
            (-depth, -half_width),
            (-depth, half_width),
            (0.0, half_width),
        ]
        for (x0, y0), (x1, y1) in itertools.pairwise(corners):
            segs.append(((x0, y0, z), (x1, y1, z)))

    segs.append(((0.0, -34.0, z), (0.0, 34.0, z)))  # goal line
    box(5.5, 9.16)  # goal area: 5.5 m from each post
    box(16.5, 20.16)  # penalty area: 16.5 m from each post
    spot = -11.0
    for a in np.linspace(0.0, 2 * math.pi, 9)[:-1]:
        b = a + 2 * math.pi / 8
        segs.append(
            (
                (spot + 0.11 * math.cos(a), 0.11 * math.sin(a), z),
                (spot + 0.11 * math.cos(b), 0.11 * math.sin(b), z),
            )
        )
    # The arc: the part of the 9.15 m circle round the spot that lies outside the area.
    half_angle = math.acos(5.5 / 9.15)
    angles = np.linspace(math.pi - half_angle, math.pi + half_angle, 24)
    arc = [(spot + 9.15 * math.cos(a), 9.15 * math.sin(a), z) for a in angles]
    segs += list(itertools.pairwise(arc))
    return np.array(segs, dtype=np.float64)


def defender_mesh() -> trimesh.Trimesh:
    """One defender standing on z = 0: legs, body and head, 1.8 m tall."""
    body = trimesh.creation.capsule(height=0.75, radius=0.2, count=[10, 10])
    body.apply_translation((0.0, 0.0, 1.15))
    head = trimesh.creation.icosphere(subdivisions=2, radius=0.11)
    head.apply_translation((0.0, 0.0, DEFENDER_HEIGHT_M - 0.11))
    legs = [_cylinder(np.array([0.0, s, 0.0]), np.array([0.0, s, 0.85]), 0.08) for s in (-0.1, 0.1)]
    mesh = trimesh.util.concatenate([body, head, *legs])
    assert isinstance(mesh, trimesh.Trimesh)
    return mesh


def arrow_segments(
    origins: NDArray[np.float64], vectors: NDArray[np.float64], head: float = 0.3
) -> NDArray[np.float64]:
    """(3K, 2, 3): a shaft and two barbs for each of K arrows."""
    tips = origins + vectors
    length = np.linalg.norm(vectors, axis=1, keepdims=True)
    direction = vectors / np.where(length > 1e-9, length, 1.0)
    side = np.cross(direction, np.array([0.0, 0.0, 1.0]))
    side_norm = np.linalg.norm(side, axis=1, keepdims=True)
    side = np.where(
        side_norm > 1e-6, side / np.where(side_norm > 1e-6, side_norm, 1.0), [0.0, 1.0, 0.0]
    )
    barb = np.minimum(head, 0.4 * length)
    left = tips - barb * direction + 0.5 * barb * side
    right = tips - barb * direction - 0.5 * barb * side
    return np.concatenate(
        [
            np.stack([origins, tips], axis=1),
            np.stack([left, tips], axis=1),
            np.stack([right, tips], axis=1),
        ]
    )


def _css(rgb: tuple[int, int, int]) -> str:
    return f"rgb({rgb[0]},{rgb[1]},{rgb[2]})"


def _segments(points: NDArray[np.float64]) -> NDArray[np.float32]:
    return np.stack([points[:-1], points[1:]], axis=1).astype(np.float32)


def _quaternion(axis: NDArray[np.float64], angle_rad: float) -> tuple[float, float, float, float]:
    norm = float(np.linalg.norm(axis))
    if norm == 0.0:
        return (1.0, 0.0, 0.0, 0.0)
    u = axis / norm * math.sin(angle_rad / 2)
    return (math.cos(angle_rad / 2), float(u[0]), float(u[1]), float(u[2]))


# --------------------------------------------------------------------------------------------- worker
class _LatestWorker:
    """Runs submitted jobs on one thread, newest only: a job still waiting is replaced by a newer one.

    A job may ask to wait for a quiet spell (``quiet_s``): it starts only once that long has passed with no newer
    submission, so a slider being dragged redraws at full speed and the expensive job runs once, after.
    """

    def __init__(self, stop: threading.Event, name: str) -> None:
        self._stop = stop
        self._condition = threading.Condition()
        self._job: Callable[[], None] | None = None
        self._not_before = 0.0
        self.busy = False
        self.thread = threading.Thread(target=self._run, name=name, daemon=True)

    def submit(self, job: Callable[[], None], quiet_s: float = 0.0) -> None:
        with self._condition:
            self._job = job
            self._not_before = time.monotonic() + quiet_s
            self._condition.notify_all()

    def idle(self) -> bool:
        with self._condition:
            return self._job is None and not self.busy

    def _run(self) -> None:
        while not self._stop.is_set():
            with self._condition:
                while not self._stop.is_set():
                    wait = self._not_before - time.monotonic()
                    if self._job is not None and wait <= 0:
                        break
                    self._condition.wait(min(wait, 0.2) if self._job is not None else 0.2)
                job, self._job = self._job, None
                self.busy = job is not None
            if job is None:
                continue
            try:
                job()
            except Exception:
                logger.exception("freekick: background job failed; the last result stays on screen")
            finally:
                with self._condition:
                    self.busy = False
                    self._condition.notify_all()


# --------------------------------------------------------------------------------------------- scene
class FreeKickScene(Scene):
    key = "freekick"
    title = "Free kick: Magnus effect"
    camera_position = (-31.0, -4.0, 3.6)
    camera_look_at = (-6.0, 0.0, 1.4)
    about = """
**What it shows.** A free kick's flight in 3D over a four-man wall 9.15 m from the ball (1.8 m tall; 2.15 m when it
jumps): the kick as set (thick orange line), the same kick with no spin (dark dashed ghost), a faint band between 10 % less
and 10 % more spin, and force arrows along the path: drag (red), Magnus (blue), gravity (purple). **View** frames
the kick raised over the kicker's shoulder, from behind the ball, side-on, as the goalkeeper sees it or from above. **Kick** flies the ball, spinning,
in real time. Click a point in the goal mouth to have the scene find a kick that reaches it over the wall. The
outcome map colours each launch speed × spin rate by result: goal (green), wall (red), over (orange), wide (yellow),
short (grey); the white cross is the current kick.

**Equations** (A = πr², ω̂ = ω/|ω|): F_drag = −½ρA·C_D·|v|·v, F_Magnus = ½ρA·C_L·|v|·(ω̂ × v), F_g = −m·g·ẑ;
m = 0.43 kg, r = 0.11 m, ρ = 1.225 kg/m³. The seed's Magnus formula (C_L·ρπr²·|v×ω|/|ω|) is not a force; this form
keeps its direction and gives its 3–5 m of curl over 25 m.

**Models.** *Constant*: C_D = C_L = 0.25; the curl radius is then 2m/(ρA·C_L) ≈ 74 m whatever the spin rate, so the
spin rate changes nothing but the direction. *Measured*: C_L = 0.9·S (S = r|ω|/|v|, up to S = 0.3; Asai et al.
2007), C_D from Goff & Carré 2010 (drag crisis near Re 2–3·10⁵, 0.4127·S^0.3056 when spinning): 10 % more spin
visibly moves the ball. *Knuckleball*: with almost no spin, an unsteady side force zig-zags the ball by about a
diameter per ~15 m (Cohen, Texier, Quéré & Clanet 2012; Texier et al. 2016), drawn from a seed.

**Integrators.** RK4 at 10 ms is within a micrometre of a DOP853 reference over 30 m; the seed's Euler at 1 ms is
off by about 1.4 cm, not "within a centimetre".

**Assumptions.** Constant spin, still air, no bounce: the flight ends when the ball touches the turf; posts, bar and
wall do not deflect it. A goal needs the whole ball inside the posts and under the bar.
"""

    def __init__(self, server: viser.ViserServer) -> None:
        super().__init__(server)
        self.params = FreeKickParams()
        self.state = compute_kick(self.params)
        self._kick_time_s: float | None = None
        self._map_version = 0
        self._aim_version = 0
        self.map_results: NDArray[np.str_] | None = None
        self.map_runs = 0
        """How many outcome maps have been computed (a burst of changes computes one)."""
        self.map_params: FreeKickParams | None = None
        """The settings the shown outcome map was computed for."""
        self.last_target: tuple[float, float] | None = None
        self.aim_message = ""
        self._map_worker = _LatestWorker(self._stop, "freekick-map")
        self._aim_worker = _LatestWorker(self._stop, "freekick-aim")
        self._threads += [self._map_worker.thread, self._aim_worker.thread]
        self._view: ViewName = "broadcast"
        self._build_gui()
        self._build_world()
        self.redraw()
        self.framing = ClientFraming(self._view_for, opening=self.camera_position)
        self.watch_cameras(self.framing.on_camera)
        self._map_worker.thread.start()
        self._aim_worker.thread.start()
        self._request_map()
        self.start_loop(self._animate, 1.0 / 30.0)

    # ----------------------------------------------------------------------------------------- GUI
    def _build_gui(self) -> None:
        gui, p = self.server.gui, self.params
        with self.gui_root:
            self.kick_button = gui.add_button("Kick", color="green")
            self.view = gui.add_dropdown(
                "View", options=list(VIEW_FROM_LABEL), initial_value=VIEW_LABELS[self._view]
            )
            self.result = gui.add_markdown("")
            with gui.add_folder("Ball spot"):
                self.distance = gui.add_slider(
                    "Distance to goal (m)", min=12.0, max=40.0, step=0.5, initial_value=p.distance_m
                )
                self.angle = gui.add_slider(
                    "Spot angle (°, + = left)",
                    min=-45.0,
                    max=45.0,
                    step=1.0,
                    initial_value=p.angle_deg,
                )
            with gui.add_folder("Strike"):
                self.speed = gui.add_slider(
                    "Launch speed (m/s)", min=5.0, max=40.0, step=0.5, initial_value=p.speed_ms
                )
                self.elevation = gui.add_slider(
                    "Elevation (°)", min=-5.0, max=50.0, step=0.5, initial_value=p.elevation_deg
                )
                self.azimuth = gui.add_slider(
                    "Azimuth (°, + = left)",
                    min=-30.0,
                    max=30.0,
                    step=0.5,
                    initial_value=p.azimuth_deg,
                )
                self.spin = gui.add_slider(
                    "Spin rate (rev/s)", min=0.0, max=15.0, step=0.1, initial_value=p.spin_rev_s
                )
                self.axis = gui.add_dropdown(
                    "Spin axis",
                    options=list(SPIN_AXIS_FROM_LABEL),
                    initial_value=SPIN_AXIS_LABELS[p.spin_axis],
                )
                self.tilt = gui.add_slider(
                    "Axis tilt from vertical (°)",
                    min=-180.0,
                    max=180.0,
                    step=1.0,
                    initial_value=p.axis_tilt_deg,
                    disabled=p.spin_axis != "custom",
                )
                self.turn = gui.add_slider(
                    "Axis turn toward the kick (°)",
                    min=-90.0,
                    max=90.0,
                    step=1.0,
                    initial_value=p.axis_turn_deg,
                    disabled=p.spin_axis != "custom",
                )
            with gui.add_folder("Physics"):
                self.model = gui.add_dropdown(
                    "Model", options=list(MODEL_FROM_LABEL), initial_value=MODEL_LABELS[p.model]
                )
                self.integrator = gui.add_dropdown(
                    "Integrator",
                    options=list(INTEGRATOR_FROM_LABEL),
                    initial_value=INTEGRATOR_LABELS[p.integrator],
                )
                self.knuckle = gui.add_checkbox("Knuckleball", initial_value=p.knuckle)
                self.knuckle_seed = gui.add_number(
                    "Knuckle seed", min=0, max=9999, step=1, initial_value=p.knuckle_seed
                )
                self.jump = gui.add_checkbox("Wall jumps", initial_value=p.wall_jumps)
                self.show_forces = gui.add_checkbox("Force arrows", initial_value=True)
            with gui.add_folder("Presets"):
                self.preset_buttons = [gui.add_button(preset.label) for preset in PRESETS]
            with gui.add_folder("Forces"):
                self.chart = FittedChart(
                    gui,
                    data=self._chart_data(),
                    series=(
                        viser.uplot.Series(label="t (s)"),
                        viser.uplot.Series(
                            label="Drag (N)", stroke=_css(FORCE_COLOURS["drag"]), width=2
                        ),
                        viser.uplot.Series(
                            label="Magnus (N)", stroke=_css(FORCE_COLOURS["magnus"]), width=2
                        ),
                        viser.uplot.Series(
                            label="Gravity (N)", stroke=_css(FORCE_COLOURS["gravity"]), width=2
                        ),
                        viser.uplot.Series(
                            label="Knuckle (N)", stroke=_css(KNUCKLE_COLOUR), width=2
                        ),
                    ),
                    scales={
                        "x": viser.uplot.Scale(time=False, auto=True),
                        "y": viser.uplot.Scale(auto=True),
                    },
                    legend=viser.uplot.Legend(show=True),
                    title="Force magnitudes along the flight",
                    aspect=1.6,
                )
            with gui.add_folder("Aim at the goal mouth"):
                self.aim_help = gui.add_markdown(
                    "Click a point in the goal mouth: the scene searches elevation, azimuth and sidespin at this "
                    "launch speed for a kick that reaches it over the wall."
                )
                self.aim_status = gui.add_markdown("")
            with gui.add_folder("Outcome map"):
                self.map_legend = gui.add_markdown(
                    "Launch speed 15–35 m/s left to right, spin 0–15 rev/s bottom to top, other settings as set. "
                    "Green goal, red wall, orange over, yellow wide, grey short; white cross: this kick."
                )
                self.map_image = gui.add_image(
                    np.full(
                        (len(MAP_SPINS_REV_S) * MAP_CELL_PX, len(MAP_SPEEDS_MS) * MAP_CELL_PX, 3),
                        200,
                        np.uint8,
                    ),
                    label="Speed × spin",
                    format="png",
                )
                self.map_status = gui.add_markdown("Computing…")

        for handle in (
            self.distance, self.angle, self.speed, self.elevation, self.azimuth, self.spin, self.axis, self.tilt,
            self.turn, self.model, self.integrator, self.knuckle, self.knuckle_seed, self.jump, self.show_forces,
        ):  # fmt: skip
            handle.on_update(self.callback(self._on_input))
        self.kick_button.on_click(self.callback(self._on_kick))
        self.view.on_update(self.callback(self._on_view))
        for preset, button in zip(PRESETS, self.preset_buttons, strict=True):
            button.on_click(self.callback(lambda preset=preset: self.apply(preset.params)))

    # ----------------------------------------------------------------------------------------- world
    def _build_world(self) -> None:
        scene, root = self.server.scene, self.root.name
        grass = trimesh.creation.box(extents=(50.0, 70.0, 0.02))
        grass.apply_translation((-22.0, 0.0, -0.011))
        scene.add_mesh_simple(f"{root}/grass", grass.vertices, grass.faces, color=(70, 140, 60))
        scene.add_line_segments(
            f"{root}/markings", pitch_markings(), colors=(245, 245, 245), thickness=0.12
        )
        frame = goal_frame_mesh()
        scene.add_mesh_simple(
            f"{root}/goal_frame", frame.vertices, frame.faces, color=(250, 250, 250)
        )
        scene.add_line_segments(
            f"{root}/net", net_segments(), colors=(225, 225, 225), thickness=0.02
        )
        half, h = 0.5 * ball.GOAL_WIDTH_M, ball.GOAL_HEIGHT_M
        # A nearly invisible pane across the goal mouth: clicking it aims a kick there.
        self.goal_mouth = scene.add_mesh_simple(
            f"{root}/goal_mouth",
            np.array([[0.0, -half, 0.0], [0.0, half, 0.0], [0.0, half, h], [0.0, -half, h]]),
            np.array([[0, 1, 2], [0, 2, 3]]),
            color=(255, 255, 255),
            opacity=0.08,
            side="double",
            cast_shadow=False,
            receive_shadow=False,
        )
        self.goal_mouth.on_click(self._on_goal_click)
        self.target_marker = scene.add_icosphere(
            f"{root}/target",
            radius=0.12,
            color=(255, 60, 200),
            position=(0.0, 0.0, 1.0),
            visible=False,
        )

        defender = defender_mesh()
        self.wall_nodes = scene.add_batched_meshes_simple(
            f"{root}/wall",
            vertices=defender.vertices.astype(np.float32),
            faces=defender.faces.astype(np.uint32),
            batched_wxyzs=np.tile([1.0, 0.0, 0.0, 0.0], (DEFENDERS, 1)),
            batched_positions=np.zeros((DEFENDERS, 3)),
            batched_colors=np.tile(np.array([30, 60, 170], np.uint8), (DEFENDERS, 1)),
            lod="off",
        )

        self.ball_frame = scene.add_frame(
            f"{root}/ball", show_axes=False, position=tuple(ball_spot(self.params))
        )
        sphere = trimesh.creation.icosphere(subdivisions=3, radius=ball.BALL_RADIUS_M)
        scene.add_mesh_simple(
            f"{self.ball_frame.name}/sphere", sphere.vertices, sphere.faces, color=(250, 250, 250)
        )
        # A dark band round the ball's equator makes its spin visible.
        band = trimesh.creation.torus(
            major_radius=ball.BALL_RADIUS_M, minor_radius=0.018, major_sections=32, minor_sections=6
        )
        band.apply_transform(trimesh.transformations.rotation_matrix(math.pi / 2, [1, 0, 0]))
        scene.add_mesh_simple(
            f"{self.ball_frame.name}/band", band.vertices, band.faces, color=(20, 20, 20)
        )

        empty_path = np.zeros((PATH_POINTS - 1, 2, 3), np.float32)
        self.path = scene.add_line_segments(
            f"{root}/path", empty_path, colors=PATH_COLOUR, thickness=0.09
        )
        self.ghost = scene.add_line_segments(
            f"{root}/ghost", empty_path, colors=GHOST_COLOUR, thickness=0.04
        )
        strip_faces = []
        for i in range(PATH_POINTS - 1):
            a, b = 2 * i, 2 * i + 1
            strip_faces += [[a, b, a + 2], [b, b + 2, a + 2]]
        self.band = scene.add_mesh_simple(
            f"{root}/band",
            np.zeros((2 * PATH_POINTS, 3), np.float32),
            np.array(strip_faces, np.uint32),
            color=(255, 200, 90),
            opacity=0.35,
            side="double",
            cast_shadow=False,
            receive_shadow=False,
        )
        empty_arrows = np.zeros((3 * ARROW_POINTS, 2, 3), np.float32)
        self.arrows = {
            name: scene.add_line_segments(
                f"{root}/force_{name}", empty_arrows, colors=colour, thickness=0.07
            )
            for name, colour in FORCE_COLOURS.items()
        }

    # ----------------------------------------------------------------------------------------- inputs
    def read_params(self) -> FreeKickParams:
        """The current GUI values, cleaned: anything non-finite, out of range or unknown keeps the last good value."""
        last = self.params
        axis_label = self.read_choice(
            self.axis, list(SPIN_AXIS_FROM_LABEL), SPIN_AXIS_LABELS[last.spin_axis]
        )
        model_label = self.read_choice(self.model, list(MODEL_FROM_LABEL), MODEL_LABELS[last.model])
        integrator_label = self.read_choice(
            self.integrator, list(INTEGRATOR_FROM_LABEL), INTEGRATOR_LABELS[last.integrator]
        )
        return FreeKickParams(
            distance_m=self.read_number(self.distance, last.distance_m),
            angle_deg=self.read_number(self.angle, last.angle_deg),
            speed_ms=self.read_number(self.speed, last.speed_ms),
            elevation_deg=self.read_number(self.elevation, last.elevation_deg),
            azimuth_deg=self.read_number(self.azimuth, last.azimuth_deg),
            spin_rev_s=self.read_number(self.spin, last.spin_rev_s),
            spin_axis=SPIN_AXIS_FROM_LABEL[axis_label],
            axis_tilt_deg=self.read_number(self.tilt, last.axis_tilt_deg),
            axis_turn_deg=self.read_number(self.turn, last.axis_turn_deg),
            model=MODEL_FROM_LABEL[model_label],
            integrator=INTEGRATOR_FROM_LABEL[integrator_label],
            knuckle=self.read_bool(self.knuckle, last.knuckle),
            knuckle_seed=int(self.read_number(self.knuckle_seed, last.knuckle_seed, integer=True)),
            wall_jumps=self.read_bool(self.jump, last.wall_jumps),
        )

    def _on_input(self) -> None:
        params = self.read_params()
        self.read_bool(self.show_forces, True)
        self._set_params(params)

    def _set_params(self, params: FreeKickParams) -> None:
        state = compute_kick(
            params
        )  # raises (and keeps the last state) if the kernels refuse the input
        moved = (params.distance_m, params.angle_deg) != (
            self.params.distance_m,
            self.params.angle_deg,
        )
        self.params, self.state = params, state
        self._kick_time_s = None
        self.redraw()
        self._request_map()
        if moved:  # the ball is on another spot: every view moves with it
            self.framing.reframe()

    # ----------------------------------------------------------------------------------------- camera
    def _on_view(self) -> None:
        label = self.read_choice(self.view, list(VIEW_FROM_LABEL), VIEW_LABELS[self._view])
        self._view = VIEW_FROM_LABEL[label]
        self.framing.reframe()

    def _view_for(self, lens: Lens) -> View:
        return frame_view(self.params, self.state, self._view, lens)

    def apply(self, params: FreeKickParams) -> None:
        """Show ``params``: write every GUI control (without re-running callbacks) and redraw once."""
        writes = (
            (self.distance, params.distance_m), (self.angle, params.angle_deg), (self.speed, params.speed_ms),
            (self.elevation, params.elevation_deg), (self.azimuth, params.azimuth_deg),
            (self.spin, params.spin_rev_s), (self.axis, SPIN_AXIS_LABELS[params.spin_axis]),
            (self.tilt, params.axis_tilt_deg), (self.turn, params.axis_turn_deg),
            (self.model, MODEL_LABELS[params.model]), (self.integrator, INTEGRATOR_LABELS[params.integrator]),
            (self.knuckle, params.knuckle), (self.knuckle_seed, params.knuckle_seed), (self.jump, params.wall_jumps),
        )  # fmt: skip
        with self.server.atomic():
            for handle, value in writes:
                self._write_back(handle, value)
        self._set_params(self.read_params())

    def _on_kick(self) -> None:
        self._kick_time_s = 0.0
        self.wake_loops()

    def _on_goal_click(self, event: viser.SceneNodePointerEvent) -> None:
        origin, direction = event.ray_origin, event.ray_direction
        self.callback(lambda: self.aim_from_ray(origin, direction))(None)

    def aim_from_ray(self, ray_origin: object, ray_direction: object) -> None:
        """Intersect a click ray with the goal mouth and queue the search for a kick reaching that point."""
        try:
            o = np.asarray(ray_origin, dtype=np.float64)
            d = np.asarray(ray_direction, dtype=np.float64)
        except (TypeError, ValueError):
            return  # not a ray: a crafted message
        if (
            o.shape != (3,)
            or d.shape != (3,)
            or not (np.all(np.isfinite(o)) and np.all(np.isfinite(d)))
        ):
            return
        if abs(d[0]) < 1e-9:
            return
        s = -o[0] / d[0]
        if s <= 0:
            return
        y, z = float(o[1] + s * d[1]), float(o[2] + s * d[2])
        half, h = 0.5 * ball.GOAL_WIDTH_M, ball.GOAL_HEIGHT_M
        if not (-half <= y <= half and 0.0 <= z <= h):
            return
        self.aim_at_point(y, z)

    def aim_at_point(self, y: float, z: float) -> None:
        """Queue a search for a kick reaching (y, z) on the goal line; its result is applied when it finishes."""
        self.last_target = (y, z)
        self._aim_version += 1
        version, params = self._aim_version, self.params
        with self.server.atomic():
            self.target_marker.position = (0.0, y, z)
            self.target_marker.visible = True
            self.aim_status.content = f"Searching for a kick to y = {y:+.2f} m, z = {z:.2f} m…"

        def job() -> None:
            found = aim_at(params, (y, z))
            with self._lock:
                if self.closed or version != self._aim_version:
                    return
                if found is None:
                    self.aim_message = (
                        "No kick at this speed reaches that point over the wall; try another speed."
                    )
                    self.aim_status.content = self.aim_message
                    return
                self.apply(found)
                point = self.state.outcome.goal_point
                reached = (
                    ""
                    if point is None
                    else f" It crosses at y = {point[1]:+.2f} m, z = {point[2]:.2f} m."
                )
                self.aim_message = (
                    f"Found: elevation {found.elevation_deg:.1f}°, azimuth {found.azimuth_deg:+.1f}°, "
                    f"{spin_words(found)}.{reached}"
                )
                self.aim_status.content = self.aim_message

        self._aim_worker.submit(job)

    # ----------------------------------------------------------------------------------------- outcome map
    def _request_map(self) -> None:
        self._map_version += 1
        version, params = self._map_version, self.params

        def job() -> None:
            self.map_runs += 1
            results = outcome_map(params)
            with self._lock:
                if self.closed or version != self._map_version:
                    return
                self.map_results, self.map_params = results, params
                counts = {name: int(np.sum(results == name)) for name in RESULT_COLOURS}
                self.map_image.image = outcome_map_image(results, params)
                words = {
                    "goal": "goals",
                    "wall": "blocked by the wall",
                    "over": "over the bar",
                    "wide": "wide",
                    "short": "short",
                }
                summary = f"Of {results.size} kicks: " + ", ".join(
                    f"{n} {words[name]}" for name, n in counts.items() if n
                )
                if params.model == "constant":
                    summary += (
                        "  \nConstant C_L: any spin above zero curls the same, so the rows repeat. Pick the "
                        "measured model to see the spin rate matter."
                    )
                self.map_status.content = summary

        self._map_worker.submit(job, quiet_s=MAP_QUIET_S)

    def wait_idle(self, timeout_s: float = 30.0) -> bool:
        """Block until no background job is queued or running (for tests and benchmarks)."""
        deadline = threading.Event()
        timer = threading.Timer(timeout_s, deadline.set)
        timer.start()
        try:
            while not deadline.is_set():
                if self._map_worker.idle() and self._aim_worker.idle():
                    return True
                deadline.wait(0.02)
            return False
        finally:
            timer.cancel()

    # ----------------------------------------------------------------------------------------- drawing
    def _chart_data(self) -> tuple[NDArray[np.float64], ...]:
        f = self.state.flight
        return (
            f.t,
            np.linalg.norm(f.drag, axis=1),
            np.linalg.norm(f.magnus, axis=1),
            np.linalg.norm(f.gravity, axis=1),
            np.linalg.norm(f.knuckle, axis=1),
        )

    def redraw(self) -> None:
        """Push the current state to the path, ghost, band, arrows, wall, ball and readouts, in one atomic update."""
        p, state = self.params, self.state
        path = resample(state.flight)
        less, more = resample(state.less_spin), resample(state.more_spin)
        strip = np.empty((2 * PATH_POINTS, 3))
        strip[0::2], strip[1::2] = less, more
        flight = state.flight
        times = np.linspace(0.0, float(flight.t[-1]), ARROW_POINTS + 2)[1:-1]
        names = list(FORCE_COLOURS)
        at = sample_rows(
            times, flight.t, np.hstack([flight.position, *(getattr(flight, n) for n in names)])
        )
        origins, forces = at[:, :3], at[:, 3:].reshape(ARROW_POINTS, len(names), 3)
        # Every force's arrows in one call: (3 parts, force, arrow, 2, 3), each force's (3K, 2, 3) a slice.
        arrows = arrow_segments(
            np.tile(origins, (len(names), 1)),
            METRES_PER_NEWTON * forces.transpose(1, 0, 2).reshape(-1, 3),
        ).reshape(3, len(names), ARROW_POINTS, 2, 3)
        show = self.show_forces.value is True

        wall = state.wall
        normal = np.array(wall.normal_xy) / np.hypot(*wall.normal_xy)
        along = np.array([-normal[1], normal[0]])
        offsets = (np.arange(DEFENDERS) - 0.5 * (DEFENDERS - 1)) * DEFENDER_WIDTH_M
        feet = np.array(wall.centre_xy) + offsets[:, None] * along
        lift = JUMP_M if p.wall_jumps else 0.0
        heading = math.atan2(normal[1], normal[0])

        with self.server.atomic():
            self.path.points = _segments(path)
            self.ghost.points = dashed(_segments(resample(state.ghost)))
            self.band.vertices = strip.astype(np.float32)
            for k, name in enumerate(names):
                self.arrows[name].points = arrows[:, k].reshape(-1, 2, 3).astype(np.float32)
                set_if_changed(self.arrows[name], "visible", show)
            # Only what changed: viser casts every write through its type hints first (~0.1 ms each).
            set_if_changed(
                self.wall_nodes,
                "batched_positions",
                np.column_stack([feet, np.full(DEFENDERS, lift)]).astype(np.float32),
            )
            set_if_changed(
                self.wall_nodes,
                "batched_wxyzs",
                np.tile(
                    [math.cos(heading / 2), 0.0, 0.0, math.sin(heading / 2)], (DEFENDERS, 1)
                ).astype(np.float32),
            )
            set_if_changed(self.ball_frame, "position", tuple(ball_spot(p)))
            set_if_changed(self.ball_frame, "wxyz", (1.0, 0.0, 0.0, 0.0))
            for handle, disabled in (
                (self.tilt, p.spin_axis != "custom"),
                (self.turn, p.spin_axis != "custom"),
                (self.knuckle_seed, not p.knuckle),
            ):
                if handle.disabled != disabled:
                    handle.disabled = disabled
            self.result.content = self.readout_markdown()
            self.chart.data = self._chart_data()
        self.server.flush()

    def readout_markdown(self) -> str:
        state, p = self.state, self.params
        o = state.outcome
        verdict = {
            "goal": "GOAL",
            "wall": "Blocked by the wall",
            "over": "Over the bar",
            "wide": "Wide of the post",
            "short": "Lands short of the goal",
        }[o.result]
        wall_height = (
            "never reaches the wall" if o.wall_point is None else f"{o.wall_point[2]:.2f} m"
        )
        lines = [
            f"**{verdict}**",
            "",
            f"Height at the wall: **{wall_height}** (wall top {state.wall.height_m:.2f} m)",
        ]
        if o.goal_point is not None and o.goal_time is not None:
            lines.append(
                f"At the goal line: **y = {o.goal_point[1]:+.2f} m, z = {o.goal_point[2]:.2f} m** after "
                f"**{o.goal_time:.2f} s**"
            )
        else:
            lines.append(
                f"Lands after **{float(state.flight.t[-1]):.2f} s**, {-state.flight.position[-1, 0]:.1f} m short"
            )
        deflection = deflection_m(state)
        if deflection is not None:
            lines.append(f"Sideways against the no-spin kick: **{deflection:+.2f} m** (+ = left)")
        s_param = ball.BALL_RADIUS_M * 2 * math.pi * p.spin_rev_s / max(p.speed_ms, 1e-9)
        lines.append(f"Spin parameter S = r·ω/v = {s_param:.3f}")
        return "  \n".join(lines)

    # ----------------------------------------------------------------------------------------- animation
    def _animate(self, dt: float) -> bool:
        """One frame of the kick's replay; False (the loop sleeps) when no kick is playing."""
        if self._kick_time_s is None:
            return False
        flight = self.state.flight
        self._kick_time_s += min(dt, 0.1)
        t = min(self._kick_time_s, float(flight.t[-1]))
        angle = float(np.linalg.norm(spin_vector(self.params))) * t
        with self.server.atomic():
            self.ball_frame.position = tuple(position_at(flight, t))
            self.ball_frame.wxyz = _quaternion(spin_axis(self.params), angle)
        self.server.flush()
        if self._kick_time_s >= float(flight.t[-1]) + 1.5:
            self._kick_time_s = None  # rest a moment where it landed, then go back to the spot
            self.ball_frame.position = tuple(ball_spot(self.params))
            self.ball_frame.wxyz = (1.0, 0.0, 0.0, 0.0)
        return True
