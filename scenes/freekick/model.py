"""The free kick as numbers: its parameters (each one's GUI control declared on it), presets, and the pure functions
from parameters to a kick state (spot, launch, spin axis, wall and goal panels, flights, outcome map, aim). No viser.

Physics comes from :mod:`kernels.ball`. The world frame is the pitch's: the goal line is x = 0 with the goal centred
on y = 0 and its net toward +x, the ball sits on the pitch (x < 0), y is to the kicker's left when facing the goal,
z is up. Paths are resampled to a fixed number of points so every redraw writes arrays of the same shapes.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import field
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from kernels import ball
from scenes._controls import checkbox, dropdown, number, slider

PATH_POINTS = 160
"""Samples per drawn path (trajectory, ghost, band edges)."""
JUMP_M = 0.35
"""How much higher a jumping wall reaches (m)."""
DEFENDER_HEIGHT_M = 1.8
"""Top of a standing defender's head (m)."""
DEFENDERS = 4
DEFENDER_WIDTH_M = 0.5

KNUCKLE_SPIN_REV_S = 0.0
"""Spin the Knuckleball checkbox sets when it is ticked: a knuckleball is struck with almost none, and any real spin
(a launch spin parameter of 0.05, about 2 rev/s at 25 m/s) steadies the wake that makes it wobble."""

SpinAxis = Literal["left", "right", "top", "back", "custom"]
SPIN_AXIS_LABELS: dict[SpinAxis, str] = {
    "left": "Sidespin, curls left",
    "right": "Sidespin, curls right",
    "top": "Topspin (dips)",
    "back": "Backspin (floats)",
    "custom": "Custom (two angles)",
}
MODEL_LABELS: dict[ball.Model, str] = {
    "measured": "Measured C_D(Re, S), C_L(S)",
    "constant": "Constant C_D = C_L = 0.25 (textbook)",
}
Integrator = Literal["rk4", "euler"]
INTEGRATOR_LABELS: dict[Integrator, str] = {"rk4": "RK4, 10 ms", "euler": "Euler, 1 ms (textbook)"}
INTEGRATOR_STEP_S: dict[Integrator, float] = {"rk4": 1e-2, "euler": 1e-3}
PLAY_T_MAX_S = 10.0
"""How long the kick is played on after it lands (s)."""
FLIGHT_T_MAX_S = 8.0
"""How long every free flight (the kick, its ghost and band, the outcome map's, the aim search's) is followed (s):
the longest flight the controls allow lasts 5.94 s (40 m/s at 50° from 40 m out with 15 rev/s of backspin, constant
coefficients), so each lands, or reaches the net, within it. At 4 s such a kick was still 19 m up and read "Lands
after 4.00 s"."""
BAND_STEP_S = 2e-2
"""Step of the ±10 % spin band's flights (RK4): they are drawn, not measured, and must not slow a redraw."""

ViewName = Literal["broadcast", "behind", "side", "goal", "above"]
VIEW_LABELS: dict[ViewName, str] = {
    "broadcast": "Raised, behind and to the side",
    "behind": "Behind the ball",
    "side": "Side-on",
    "goal": "From the goal",
    "above": "From above",
}

RESULT_COLOURS: dict[str, tuple[int, int, int]] = {
    "goal": (40, 180, 70),
    "wall": (210, 50, 50),
    "over": (245, 150, 40),
    "wide": (240, 215, 60),
    "short": (140, 140, 140),
}

MAP_SPEEDS_MS = np.linspace(15.0, 35.0, 41)
"""Outcome-map columns: launch speed (m/s)."""
MAP_SPINS_REV_S = np.linspace(0.0, 15.0, 31)
"""Outcome-map rows: spin rate (rev/s), bottom to top."""
MAP_CELL_PX = 6
MAP_QUIET_S = 0.25
"""The outcome map is recomputed once the settings have been still this long (s), not on every slider step."""


@dataclasses.dataclass(frozen=True)
class FreeKickParams:
    """Everything the scene shows is a function of these; defaults are the opening state (a curler).

    Each field is also its GUI control, declared once (:mod:`scenes._controls`), in the order and folder shown; the
    view's dropdown stands above the folders, under the Kick button.
    """

    distance_m: float = field(
        default=22.0, metadata=slider("Distance to goal (m)", 12.0, 40.0, 0.5, folder="Ball spot")
    )
    """Distance from the ball to the centre of the goal line (m)."""
    angle_deg: float = field(
        default=0.0, metadata=slider("Spot angle (°, + = left)", -45.0, 45.0, 1.0, folder="Ball spot")
    )
    """Where the spot is, seen from the goal: angle off the pitch's centre line, + toward the kicker's left (°)."""
    speed_ms: float = field(default=25.0, metadata=slider("Launch speed (m/s)", 5.0, 40.0, 0.5, folder="Strike"))
    """Launch speed (m/s)."""
    elevation_deg: float = field(default=17.0, metadata=slider("Elevation (°)", -5.0, 50.0, 0.5, folder="Strike"))
    """Launch angle above the ground (°)."""
    azimuth_deg: float = field(
        default=-9.0, metadata=slider("Azimuth (°, + = left)", -30.0, 30.0, 0.5, folder="Strike")
    )
    """Launch direction relative to the line from ball to goal centre, + to the left (°)."""
    spin_rev_s: float = field(default=8.0, metadata=slider("Spin rate (rev/s)", 0.0, 15.0, 0.1, folder="Strike"))
    """Spin rate (rev/s)."""
    spin_axis: SpinAxis = field(
        default="left",
        metadata=dropdown("Spin axis", tuple(SPIN_AXIS_LABELS), tuple(SPIN_AXIS_LABELS.values()), folder="Strike"),
    )
    """Spin axis: sidespin either way, topspin, backspin, or custom."""
    axis_tilt_deg: float = field(
        default=0.0, metadata=slider("Axis tilt from vertical (°)", -180.0, 180.0, 1.0, folder="Strike", disabled=True)
    )
    """Custom axis: tilt from vertical toward the kicker's left (°); 0 is sidespin left, 90 topspin. Its control is
    greyed out unless the spin axis is custom."""
    axis_turn_deg: float = field(
        default=0.0, metadata=slider("Axis turn toward the kick (°)", -90.0, 90.0, 1.0, folder="Strike", disabled=True)
    )
    """Custom axis: turn of the tilted part toward the kick direction (°); 90 with tilt 90 is rifle spin. Greyed out
    unless the spin axis is custom."""
    model: ball.Model = field(
        default="measured",
        metadata=dropdown("Model", tuple(MODEL_LABELS), tuple(MODEL_LABELS.values()), folder="Physics"),
    )
    """Coefficient model: the measured one, under which the spin rate changes the flight; the original brief's constant
    one curls every spinning kick alike."""
    integrator: Integrator = field(
        default="rk4",
        metadata=dropdown("Integrator", tuple(INTEGRATOR_LABELS), tuple(INTEGRATOR_LABELS.values()), folder="Physics"),
    )
    """Integrator and its step."""
    knuckle: bool = field(default=False, metadata=checkbox("Knuckleball", folder="Physics"))
    """Unsteady knuckleball side force (only acts with near-zero spin)."""
    knuckle_seed: int = field(default=1, metadata=number("Random draw", 0, 9999, 1, folder="Physics", disabled=True))
    """Random draw of the knuckleball's side force: the same number, the same flight. Greyed out without the
    knuckleball."""
    spin_before_knuckle_rev_s: float | None = None
    """The spin rate (rev/s) that ticking Knuckleball replaced with :data:`KNUCKLE_SPIN_REV_S`, kept while the kick
    still has that spin: unticking the box brings it back. None once the spin is the user's (set by them after the
    tick, or by a preset or an aim). No control of its own: the checkbox sets it (:func:`knuckle_toggled`)."""
    wall_jumps: bool = field(default=False, metadata=checkbox("Wall jumps", folder="Physics"))
    """Whether the wall jumps (its top rises by 0.35 m)."""
    keeper: bool = field(default=True, metadata=checkbox("Goalkeeper", folder="Physics"))
    """Whether a goalkeeper (:data:`KEEPER`) stands in goal, reads the kick and dives for it."""
    show_forces: bool = field(default=True, metadata=checkbox("Force arrows", folder="Physics"))
    """Whether the force arrows are drawn along the path (how the kick is shown, not what it is)."""
    view: ViewName = field(
        default="broadcast", metadata=dropdown("View", tuple(VIEW_LABELS), tuple(VIEW_LABELS.values()))
    )
    """Where each browser's camera frames the kick from (how the kick is shown, not what it is)."""

    def shown_as(self, shown: FreeKickParams) -> FreeKickParams:
        """This kick, shown as ``shown`` is (its force arrows and view): what a preset or an aim changes."""
        return dataclasses.replace(self, show_forces=shown.show_forces, view=shown.view)


@dataclasses.dataclass(frozen=True)
class Preset:
    label: str
    """Button text."""
    params: FreeKickParams
    """The kick, from the default spot unless it names another."""


PRESETS: tuple[Preset, ...] = (
    Preset("Curler round the wall, saved", FreeKickParams()),
    Preset(
        "Top corner past the keeper",
        FreeKickParams(speed_ms=28.0, elevation_deg=16.0, azimuth_deg=-14.0, spin_rev_s=8.0),
    ),
    Preset(
        "Low curler: bounces, saved",
        FreeKickParams(speed_ms=25.0, elevation_deg=12.0, azimuth_deg=-10.0, spin_rev_s=8.0),
    ),
    Preset(
        "Driven, off the post", FreeKickParams(speed_ms=28.0, elevation_deg=12.0, azimuth_deg=-10.0, spin_rev_s=0.0)
    ),
    Preset(
        "Dipping topspin",
        FreeKickParams(speed_ms=28.0, elevation_deg=21.0, azimuth_deg=0.0, spin_rev_s=8.0, spin_axis="top"),
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


def goal_heading_rad(p: FreeKickParams) -> float:
    """Heading (rad, from +x toward +y) of the line from the ball to the centre of the goal line."""
    spot = ball_spot(p)
    return math.atan2(-spot[1], -spot[0])


def aim_heading_rad(p: FreeKickParams) -> float:
    """Heading (rad, from +x toward +y) of the launch direction."""
    return goal_heading_rad(p) + math.radians(p.azimuth_deg)


def launch_velocity(p: FreeKickParams, speed_ms: float | None = None) -> NDArray[np.float64]:
    return ball.launch_velocity(
        p.speed_ms if speed_ms is None else speed_ms, math.radians(p.elevation_deg), aim_heading_rad(p)
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
            return math.cos(tilt) * up + math.sin(tilt) * (math.cos(turn) * left + math.sin(turn) * forward)


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
        spot[:2], (0.0, 0.0), (1.0, 0.0), wall_width_m=width, wall_height_m=height, wall_offset_m=offset
    )


KEEPER = ball.Keeper()
"""The scene's goalkeeper: the kernel's defaults (a 1.90 m keeper 1 m off his line on the bisector of the posts'
angle, reacting 0.25 s after the ball passes the wall, diving at 3.9 m/s)."""


def pitch(p: FreeKickParams) -> ball.Pitch:
    """The pitch the kick is played on: the goal (posts, bar, net), the wall's players and the keeper if ``p`` has
    one."""
    wall, goal = panels(p)
    return ball.Pitch(goal, wall, KEEPER if p.keeper else None)


def play_options(p: FreeKickParams) -> dict[str, Any]:
    """How a kick is played on :func:`pitch`, the kick shown and the strikes of its odds alike: ``p``'s integrator
    and model for :data:`PLAY_T_MAX_S`, the ball's centre a radius above the turf (:class:`kernels.ball.FlightConfig`
    fields)."""
    return {
        "dt": INTEGRATOR_STEP_S[p.integrator],
        "method": p.integrator,
        "model": p.model,
        "t_max": PLAY_T_MAX_S,
        "ground_m": ball.BALL_RADIUS_M,
    }


def keeper_gap_m(
    pose: ball.KeeperPath, points: NDArray[np.float64], keeper: ball.Keeper = KEEPER
) -> NDArray[np.float64]:
    """(T,) distance (m) from each ball centre of (T, 3) ``points`` to the keeper's body at the same instant
    (the kernel's capsule, :attr:`kernels.ball.KeeperPath.capsule`), less the ball's radius and half the body's
    thickness: ≤ 0 where the ball touches him."""
    soles, tips = pose.capsule[:, 0], pose.capsule[:, 1]
    axis = tips - soles
    s = np.clip(np.einsum("ij,ij->i", points - soles, axis) / np.einsum("ij,ij->i", axis, axis), 0.0, 1.0)
    nearest = soles + s[:, None] * axis
    return np.linalg.norm(points - nearest, axis=1) - keeper.body_radius_m - ball.BALL_RADIUS_M


KEEPER_STEP_S = 2e-3
"""Time step (s) at which the keeper's reach is searched for the readout's "reached it … early"."""


def margin_words(margin_s: float, apart: str, together: str) -> str:
    """A time margin (s) as the readouts say it: ``apart`` with ``{s}`` replaced by the margin to two decimals
    ("reaches it {s} s early" reads "reaches it 0.26 s early"), or ``together`` ("just reaches it") where that would
    read 0.00 s: "0.00 s early" contradicts itself. A negative margin counts as none."""
    shown = f"{max(margin_s, 0.0):.2f}"
    return together if shown == "0.00" else apart.format(s=shown)


def save_margin_s(state: KickState) -> float | None:
    """How much earlier (s) the keeper's body could have touched the ball where he met it than it arrived there;
    None unless he saved it. The kernel's keeper (:func:`kernels.ball.keeper_path`) searched every
    :data:`KEEPER_STEP_S`."""
    played, spot = state.played, state.keeper_xy
    if played is None or spot is None or played.keeper_dive is None:
        return None
    saved = next((event for event in played.events if event.kind == "keeper"), None)
    if saved is None:
        return None
    times = np.arange(played.keeper_dive.t, saved.t + KEEPER_STEP_S, KEEPER_STEP_S)
    point = np.tile(saved.position, (len(times), 1))
    reach = keeper_gap_m(ball.keeper_path(KEEPER, spot, played.keeper_dive, times), point) <= 1e-3
    first = float(times[int(np.argmax(reach))]) if reach.any() else saved.t
    return max(saved.t - first, 0.0)


KEEPER_NEAR_M = 2.0
"""Farthest (m) the keeper's body may stay from a ball that got past him for the readout to say how near he came:
from farther away the number says nothing about the save."""


def dive_words(dive: ball.KeeperDive, spot: tuple[float, float]) -> str:
    """Which way the keeper standing at ``spot`` (m) goes, in football words: "jumps" (straight up, for a ball
    read at him), else "dives to his right (your left)" or "dives to his left (your right)": he faces the kicker, so
    his right is the kicker's left, the side every other readout calls left."""
    across = dive.target[1] - spot[1]  # + toward the kicker's left
    if abs(across) < 0.3:
        return "jumps"
    return "dives to his right (your left)" if across > 0 else "dives to his left (your right)"


def keeper_words(state: KickState) -> str:
    """What the keeper did, in words: "dives to his left (your right) 0.67 s after the kick, reaches it 0.26 s
    early" (or "just reaches it"), "... the ball beats him by 0.42 m" or "never dives"; how near he came only when it
    was within :data:`KEEPER_NEAR_M`. Empty without a keeper."""
    played, spot = state.played, state.keeper_xy
    if played is None or spot is None:
        return ""
    dive = played.keeper_dive
    if dive is None:
        return _why_no_dive(state, played)
    dived = f"{dive_words(dive, spot)} {dive.t:.2f} s after the kick"
    margin = save_margin_s(state)
    if margin is not None:
        return f"{dived}, {margin_words(margin, 'reaches it {s} s early', 'just reaches it')}"
    # The ball got past: how close his body came to it over the flight.
    gap = keeper_gap_m(ball.keeper_path(KEEPER, spot, dive, played.t), played.position)
    nearest = max(float(gap.min()), 0.0)
    beaten = "; the ball beats him" if played.result == "goal" else ""
    if round(nearest, 2) >= KEEPER_NEAR_M:  # as shown: "within 2.00 m" is not near
        return f"{dived}{beaten}"
    if beaten:
        return f"{dived}{beaten} by {nearest:.2f} m"
    return f"{dived}; gets within {nearest:.2f} m of the ball"


def wall_passed_s(state: KickState, played: ball.Trajectory) -> float | None:
    """When (s) the played-on ball first crosses the wall's plane toward the goal (the keeper's first clear sight
    of it), None if it never does."""
    return _plane_crossed_s(state.wall, played)


def wall_height_words(state: KickState) -> str:
    """The ball's height where it meets the wall's plane, for the readout: the kick's own line (the free flight), or
    the played-on ball's (the pale line) where that bounced first or the free flight lands short of the wall."""
    o, played = state.outcome, state.played
    bounced = played is not None and any(
        e.kind == "ground" and (o.wall_time is None or e.t < o.wall_time) for e in played.events
    )
    if o.wall_point is not None and not bounced:
        point = o.wall_point
        return f"{point[2]:.2f} m{_clipping_words(state.wall, point)}{_beside_words(state.wall, point)}"
    if played is None or not bounced:
        return "never reaches the wall"
    struck = next((e for e in played.events if e.kind == "wall"), None)
    if struck is not None:
        return f"{struck.position[2]:.2f} m, after bouncing, into a defender (pale line)"
    crossed = wall_passed_s(state, played)
    if crossed is not None:
        point = position_at(played, crossed)
        return f"{point[2]:.2f} m{_beside_words(state.wall, point)}, after bouncing (pale line)"
    return "never reaches the wall"


def _clipping_words(wall: ball.Panel, point: NDArray[np.float64]) -> str:
    """ ", its underside 0.02 m below the wall's top" where the ball's centre at ``point`` (m) passes over the top
    but the ball does not (an outside tester read "1.89 m (wall top 1.80 m)" beside "Blocked by the wall")."""
    below = wall.height_m - (float(point[2]) - ball.BALL_RADIUS_M)
    if float(point[2]) <= wall.height_m or below <= 0.0:
        return ""
    return f", its underside {max(below, 0.005):.2f} m below the wall's top"


def _beside_words(wall: ball.Panel, point: NDArray[np.float64]) -> str:
    """ ", beside the wall, 0.45 m right of its end" where the ball's centre at ``point`` (m), in the wall's plane,
    passes clear of the wall's span (by more than the ball's radius); "" where it is over or in front of it."""
    _normal, along = wall_axes(wall)
    lateral = float((np.asarray(point[:2]) - np.array(wall.centre_xy)) @ along)
    clear = abs(lateral) - 0.5 * wall.width_m
    if clear <= ball.BALL_RADIUS_M:
        return ""
    return f", beside the wall, {clear:.2f} m {'left' if lateral > 0 else 'right'} of its end"


def landing_words(state: KickState) -> str:
    """Where a kick that never reaches the goal line first comes down: on a pitch that is the played ball's first
    bounce, unless something (the wall) touched it first; then it is where the kick's own line would land."""
    t, short = float(state.flight.t[-1]), -float(state.flight.position[-1, 0])
    played = state.played
    first = played.events[0] if played is not None and played.events else None
    if first is not None and first.kind == "ground" and abs(first.t - t) < 1e-3:
        return f"First bounce after **{t:.2f} s**, {short:.1f} m short of the goal line"
    if first is not None and first.t < t:
        return f"In free flight it would land after **{t:.2f} s**, {short:.1f} m short"
    return f"Lands after **{t:.2f} s**, {short:.1f} m short"  # nothing touched it before (or no pitch)


def _plane_crossed_s(panel: ball.Panel, played: ball.Trajectory) -> float | None:
    """When (s) the played-on ball's centre first crosses ``panel``'s plane along its normal, None if never."""
    normal, _along = wall_axes(panel)
    side = (played.position[:, :2] - np.array(panel.centre_xy)) @ normal
    past = np.flatnonzero((side[:-1] < 0.0) & (side[1:] >= 0.0))
    if not len(past):
        return None
    i = int(past[0])
    f = -side[i] / (side[i + 1] - side[i])
    return float(played.t[i] + f * (played.t[i + 1] - played.t[i]))


def _why_no_dive(state: KickState, played: ball.Trajectory) -> str:
    """Why the keeper never set off, as what happened to the ball says: it never got past the wall (only when it hit
    the wall), it never reached it, the play was over before his reaction time was up, or the ball never came at his
    goal (he dives only for a ball on his line within 1.5 s, within his reach of the goal)."""
    passed = wall_passed_s(state, played)
    if passed is None:
        if any(event.kind == "wall" for event in played.events):
            return "never dives (the ball never gets past the wall)"
        return "never dives (the ball never reaches the wall)"
    # Over for him when it crosses his line, strikes the frame, or stops, whichever is first.
    ends = [float(played.t[-1]), *(event.t for event in played.events if event.kind in ("post", "bar"))]
    line = _plane_crossed_s(state.goal, played)
    over = min(ends if line is None else [*ends, line]) - passed
    what = {
        "goal": "it is in the goal",
        "post": "it hits the post",
        "bar": "it hits the bar",
        "wide": "it is past the post",
        "over": "it is over the bar",
    }.get(str(played.result), "the play is over")
    step = float(played.t[1] - played.t[0]) if len(played.t) > 1 else 0.0  # he reads at a step's start
    if over < KEEPER.reaction_s + step:
        when = margin_words(over, "{s} s after it passes the wall", "as it passes the wall")
        return f"never dives: {what} {when}, within his reaction time ({KEEPER.reaction_s:.2f} s)"
    return "never dives: the ball never comes at his goal"


VERDICT_WORDS: dict[str, str] = {
    "goal": "GOAL",
    "wall": "Blocked by the wall",
    "over": "Over the bar",
    "wide": "Wide of the post",
    "short": "Lands short of the goal",
    "post": "Hits the post",
    "bar": "Hits the bar",
    "saved": "Saved",
}
"""The readout's headline for each of the kernel's verdicts."""


def verdict_words(result: str, crossing: NDArray[np.float64] | None) -> str:
    """The headline for the kernel's ``result``; ``crossing`` is the (3,) ball centre (m) where it crossed the goal
    line, or None. The kernel calls every ball outside the posts wide, however high: one that was also above the
    bar (where, between the posts, it would be over) reads "Wide and over the bar"."""
    if result == "wide" and crossing is not None and crossing[2] > ball.GOAL_HEIGHT_M - ball.BALL_RADIUS_M:
        return "Wide and over the bar"
    return VERDICT_WORDS[result]


def free_flight_result(state: KickState) -> str:
    """The free flight's verdict where it crosses the goal's plane, with the goal's frame in it: the kernel's free
    flight has no posts or bar and calls a ball not wholly inside the goal mouth wide or over, but one whose centre
    crosses within a ball's and a post's radius of a post's axis, or of the bar's, meets the frame there ("post",
    "bar"; a ball centred 2 cm inside the post was "wide")."""
    o, post = state.outcome, ball.Pitch.post_radius_m
    if o.result not in ("wide", "over") or o.goal_point is None:
        return str(o.result)
    y, z = abs(float(o.goal_point[1])), float(o.goal_point[2])
    reach = ball.BALL_RADIUS_M + post
    post_y, bar_z = 0.5 * ball.GOAL_WIDTH_M + post, ball.GOAL_HEIGHT_M + post
    if (z < bar_z and abs(y - post_y) < reach) or math.hypot(y - post_y, z - bar_z) < reach:  # a post, or its corner
        return "post"
    if y < post_y and abs(z - bar_z) < reach:
        return "bar"
    if y < post_y and z > bar_z:  # clear over the bar between the posts' axes: over, though not wholly inside
        return "over"
    return str(o.result)


def goal_line_reached(state: KickState) -> bool:
    """Whether the ball as played on reaches the goal line where its free flight (:attr:`KickState.outcome`)
    crosses it: the free flight crosses the goal's plane and the played ball touched nothing but the goal's frame
    before then (up to its first contact the played flight is the free one). A ball the wall or the keeper stopped,
    or that bounced first, never got to that crossing."""
    crossed = state.outcome.goal_time
    if crossed is None:
        return False
    if state.played is None:
        return True
    return all(event.t >= crossed or event.kind in ("post", "bar") for event in state.played.events)


def keeper_show_time(state: KickState) -> float:
    """The instant (s) the still picture shows the keeper at: when he touches the ball, else when the ball reaches
    the goal line (or the flight's end, if it never does)."""
    played = state.played
    if played is None:
        return 0.0
    saved = next((event.t for event in played.events if event.kind == "keeper"), None)
    if saved is not None:
        return saved
    over = np.flatnonzero(played.position[:, 0] >= 0.0)
    return float(played.t[over[0]] if len(over) else played.t[-1])


LIMBS = ("left leg", "right leg", "body", "left arm", "right arm", "head")
"""The keeper figure's parts, each drawn as one rod from a start to an end point."""
LIMB_RADII_M = np.array([0.08, 0.08, 0.16, 0.06, 0.06, 0.11])
"""Each part's half-thickness (m): the body a little thicker than the kernel's stick (0.15 m)."""


def keeper_limbs(
    pose: ball.KeeperPath, facing_xy: NDArray[np.float64], keeper: ball.Keeper = KEEPER
) -> NDArray[np.float64]:
    """(T, 6, 2, 3) start and end of each of :data:`LIMBS` (m) for a simple articulated figure on the kernel's
    stick: legs from the hips to the soles (feet apart), the body from the hips to the shoulders, arms from the
    shoulders to the fingertips (hands apart, up the stick as the kernel's reach has them) and the head. ``facing_xy``
    is the (2,) direction he faces (toward the ball); the figure spreads its limbs across it."""
    up, com = pose.up, pose.com
    soles, tips = com - keeper.foot_reach_m * up, com + keeper.hand_reach_m * up
    facing = np.array([facing_xy[0], facing_xy[1], 0.0])
    side = np.cross(facing, up)  # across the body, in the plane he dives in
    norm = np.linalg.norm(side, axis=1, keepdims=True)
    side = np.where(norm > 1e-6, side / np.maximum(norm, 1e-9), np.array([0.0, 1.0, 0.0]))
    hips = com - 0.05 * up
    shoulders = com + 0.5 * up
    head = com + 0.72 * up
    legs = [(hips + k * 0.1 * side, soles + k * 0.18 * side) for k in (1.0, -1.0)]
    arms = [(shoulders + k * 0.2 * side, tips + k * 0.15 * side - 0.05 * up) for k in (1.0, -1.0)]
    parts = [*legs, (hips, shoulders), *arms, (head - 0.06 * up, head + 0.06 * up)]
    return np.stack([np.stack(part, axis=1) for part in parts], axis=1)


def play_words(played: ball.Trajectory | None) -> str:
    """What the kick did once it touched something, in words: "hits the left post at 1.8 m, goes in"; contacts that
    read alike in a row are said once, counted ("hits a defender at 0.3 m twice"), and two defenders met at one
    instant (the ball between them) as such."""
    if played is None or not played.events:
        return ""
    phrases: list[str] = []
    bounces, repeats, last_t = 0, 1, math.nan
    for event in played.events:
        _, y, z = event.position
        if event.kind == "ground":
            bounces += 1
            continue
        if bounces:
            phrases.append("bounces" if bounces == 1 else f"bounces {bounces}×")
            bounces = 0
        side = "left" if y > 0 else "right"
        phrase = {
            "post": f"hits the {side} post at {z:.1f} m",
            "bar": f"hits the bar {abs(y):.1f} m {side} of centre",
            "wall": f"hits a defender at {z:.1f} m",
        }.get(event.kind)
        if phrase is None:
            continue
        if event.kind == "wall" and event.t == last_t and phrases and phrases[-1] == phrase:
            phrases[-1] = f"hits two defenders at {z:.1f} m"  # at once: the ball between them
            continue
        last_t = event.t
        repeats = repeats + 1 if phrases and phrases[-1].startswith(phrase) else 1
        if repeats > 1:
            phrases[-1] = f"{phrase} twice" if repeats == 2 else f"{phrase} {repeats}×"
        else:
            phrases.append(phrase)
    ending = {
        "net": "ends in the net",
        "out": "goes out of play",
        "stopped": f"rolls to a stop {max(-played.position[-1, 0], 0.0):.1f} m out",
        "saved": "into the keeper's hands",
        "contacts": f"still bouncing after {len(played.events)} contacts",
    }.get(played.ended, f"still rolling after {PLAY_T_MAX_S:g} s")
    if bounces:
        phrases.append("bounces" if bounces == 1 else f"bounces {bounces}×")
    if played.result == "goal" and played.ended != "net":
        ending = "goes in"
    phrases.append(ending)
    text = ", ".join(phrases)
    return text[0].upper() + text[1:]


def knuckle_toggled(before: FreeKickParams, after: FreeKickParams) -> FreeKickParams:
    """``after`` (the controls as read; ``before`` the kick shown) with the spin the Knuckleball checkbox implies.

    Ticked with spin enough to steady the wake, the spin becomes :data:`KNUCKLE_SPIN_REV_S` (a knuckleball, not a
    curler with a dead checkbox) and the spin it replaced is kept; unticked while the kick still has that spin, the
    kept spin comes back (the kick it was). A spin the user sets meanwhile is theirs: nothing is kept, and
    unticking leaves it.
    """
    if after.knuckle and not before.knuckle:
        replaced = after.spin_rev_s if after.spin_rev_s != KNUCKLE_SPIN_REV_S else None
        return dataclasses.replace(after, spin_rev_s=KNUCKLE_SPIN_REV_S, spin_before_knuckle_rev_s=replaced)
    kept = after.spin_before_knuckle_rev_s
    if kept is None:
        return after
    if after.spin_rev_s != before.spin_rev_s:
        return dataclasses.replace(after, spin_before_knuckle_rev_s=None)
    if not after.knuckle:
        return dataclasses.replace(after, spin_rev_s=kept, spin_before_knuckle_rev_s=None)
    return after


def knuckle_wobble_m(p: FreeKickParams, state: KickState) -> float | None:
    """Largest distance (m) of the kick from its spinless ghost across the line of flight (sideways and up or down),
    up to the played ball's first contact, where the kick carries a knuckle force; None without one."""
    found = _knuckle_across(p, state)
    if found is None:
        return None
    _, sideways, rise = found
    return float(np.hypot(sideways, rise).max())


WOBBLE_SCALE = 10.0
"""How much the knuckleball's drawn wobble magnifies its difference from the spinless path: a ball's width over
25 m is too little to see from the stands, ten times it is not."""


def _knuckle_difference(state: KickState, n: int) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
    """(n, 3) the spinless ghost and (n, 3) the kick's difference from it (m), at n times over both flights, up to
    the played ball's first contact (the knuckle force ends there, and past it the ball goes where the contact sends
    it, not where the free flight would); None without a knuckle force."""
    flight, ghost = state.flight, state.ghost
    if not np.any(flight.knuckle):
        return None
    end = min(float(flight.t[-1]), float(ghost.t[-1]))
    played = state.played
    if played is not None and played.events:
        end = min(end, played.events[0].t)
    times = np.linspace(0.0, end, n)
    base = sample_rows(times, ghost.t, ghost.position)
    return base, sample_rows(times, flight.t, flight.position) - base


def _knuckle_across(
    p: FreeKickParams, state: KickState, n: int = 400
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]] | None:
    """(n, 3) the spinless ghost, and (n,) the kick's sideways (m, + to the kicker's left, square to the launch
    heading, along which the ghost flies) and upward differences from it, as :func:`_knuckle_difference`."""
    found = _knuckle_difference(state, n)
    if found is None:
        return None
    base, diff = found
    heading = aim_heading_rad(p)
    return base, diff @ np.array([-math.sin(heading), math.cos(heading), 0.0]), diff[:, 2]


def wobble_path(state: KickState, n: int = PATH_POINTS) -> NDArray[np.float64] | None:
    """(n, 3) the knuckleball's path drawn with its difference from the spinless path magnified
    :data:`WOBBLE_SCALE` times; None without a knuckle force."""
    found = _knuckle_difference(state, n)
    return None if found is None else found[0] + WOBBLE_SCALE * found[1]


def knuckle_swerves(p: FreeKickParams, state: KickState) -> list[tuple[float, float]]:
    """Where the knuckleball swerves furthest each way: for each stretch of flight on one side of the spinless path
    (by at least 2 cm), its furthest point as (distance from the spot along the ground (m), sideways offset (m, + to
    the kicker's left)), in flight order. Empty without a knuckle force."""
    found = _knuckle_across(p, state)
    if found is None:
        return []
    base, sideways, _ = found
    spot = ball_spot(p)
    along = np.hypot(base[:, 0] - spot[0], base[:, 1] - spot[1])
    side = np.where(np.abs(sideways) >= 0.02, np.sign(sideways), 0.0)
    swerves: list[tuple[float, float]] = []
    start = None
    for i in range(len(side) + 1):
        if i < len(side) and side[i] != 0.0 and (start is None or side[i] == side[start]):
            start = i if start is None else start
            continue
        if start is not None:
            far = start + int(np.argmax(np.abs(sideways[start:i])))
            swerves.append((float(along[far]), float(sideways[far])))
            start = i if i < len(side) and side[i] != 0.0 else None
    return swerves


def wobble_words(p: FreeKickParams, state: KickState) -> str:
    """The knuckleball's swerves in words: "swerves 0.12 m left at 8 m, then 0.33 m right at 21 m; 0.10 m lower at
    most"; empty without a knuckle force."""
    found = _knuckle_across(p, state)
    if found is None:
        return ""
    said = [
        f"{abs(side):.2f} m {'left' if side > 0 else 'right'} at {at:.0f} m" for at, side in knuckle_swerves(p, state)
    ]
    words = "swerves " + ", then ".join(said) if said else "keeps within 2 cm sideways"
    rise = found[2]
    far = int(np.argmax(np.abs(rise)))
    if abs(rise[far]) >= 0.02:
        words += f"; {abs(rise[far]):.2f} m {'higher' if rise[far] > 0 else 'lower'} at most"
    return words


def wall_axes(wall: ball.Panel) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(2,) unit normal of the wall (toward the goal) and (2,) unit direction along it, + to the kicker's left."""
    normal = np.array(wall.normal_xy) / np.hypot(*wall.normal_xy)
    return normal, np.array([-normal[1], normal[0]])


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
    played: ball.Trajectory | None = None
    """The same kick played on after it first touches anything: it bounces, rolls, strikes the posts, the bar and
    the wall's players and the keeper, and stops in the net or his hands (the kernel's flight on a pitch)."""
    keeper_xy: tuple[float, float] | None = None
    """Where the keeper stands (m), None without one."""


def _fly(p: FreeKickParams, spin_scale: float, *, knuckle: bool, band: bool = False) -> ball.Trajectory:
    """One flight; ``band`` flights (only drawn, never measured) use RK4 at 20 ms, well under a millimetre off."""
    return ball.simulate(
        ball_spot(p),
        launch_velocity(p),
        spin_vector(p, spin_scale),
        dt=BAND_STEP_S if band else INTEGRATOR_STEP_S[p.integrator],
        method="rk4" if band else p.integrator,
        model=p.model,
        t_max=FLIGHT_T_MAX_S,
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
    played = ball.simulate(
        ball_spot(p),
        launch_velocity(p),
        spin_vector(p),
        knuckle_seed=p.knuckle_seed if p.knuckle else None,
        pitch=pitch(p),
        **play_options(p),
    )
    return KickState(
        flight=flight,
        ghost=ghost,
        less_spin=_fly(p, 0.9, knuckle=True, band=True),
        more_spin=_fly(p, 1.1, knuckle=True, band=True),
        outcome=ball.outcome(flight, wall, goal),
        ghost_outcome=ghost_outcome,
        wall=wall,
        goal=goal,
        played=played,
        keeper_xy=KEEPER.placed(ball_spot(p)[:2], goal) if p.keeper else None,
    )


def _without_spin(p: FreeKickParams) -> FreeKickParams:
    """``p`` with its spin, knuckleball and display settings at their defaults: all its no-spin ghost depends on."""
    plain = FreeKickParams()
    return dataclasses.replace(
        p,
        spin_rev_s=0.0,
        spin_axis=plain.spin_axis,
        axis_tilt_deg=plain.axis_tilt_deg,
        axis_turn_deg=plain.axis_turn_deg,
        knuckle=False,
        knuckle_seed=plain.knuckle_seed,
        spin_before_knuckle_rev_s=plain.spin_before_knuckle_rev_s,
        keeper=plain.keeper,
        show_forces=plain.show_forces,
        view=plain.view,
    )


@functools.lru_cache(maxsize=8)
def _ghost_kick(p: FreeKickParams) -> tuple[ball.Trajectory, ball.Outcome]:
    """The kick ``p`` with no spin and its outcome, kept for the last few launches (its arrays are read-only)."""
    wall, goal = panels(p)
    ghost = _fly(p, 0.0, knuckle=False)
    # Shared by every state of this launch: a write would corrupt them all, so refuse it.
    for member in dataclasses.fields(ghost):
        value = getattr(ghost, member.name)
        if isinstance(value, np.ndarray):
            value.flags.writeable = False
    return ghost, ball.outcome(ghost, wall, goal)


def sample_rows(times: NDArray[np.float64], t: NDArray[np.float64], values: NDArray[np.float64]) -> NDArray[np.float64]:
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


def after_contact(played: ball.Trajectory | None, n: int = PATH_POINTS) -> NDArray[np.float64] | None:
    """(n, 3) the played-on flight from its first contact to its end, at n evenly spaced times; None if it touched
    nothing (or ended at the touch)."""
    if played is None or not played.events or played.events[0].t >= float(played.t[-1]):
        return None
    return sample_rows(np.linspace(played.events[0].t, float(played.t[-1]), n), played.t, played.position)


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
        t_max=FLIGHT_T_MAX_S,
        x_stop=0.5,
        ground_m=ball.BALL_RADIUS_M,
        knuckle_seeds=[p.knuckle_seed] * k if p.knuckle else None,
    )
    return judged.result.reshape(spins.shape)


def _off_map(value: float, axis: NDArray[np.float64]) -> int:
    """−1 or +1 where ``value`` lies more than half a cell below or above the map's ``axis`` (evenly spaced), else 0."""
    half = 0.5 * (axis[1] - axis[0])
    return -1 if value < axis[0] - half else 1 if value > axis[-1] + half else 0


def map_marker_words(p: FreeKickParams) -> str:
    """Where the current kick lies when the outcome map cannot show it ("" when it can): its speed (or spin) beyond
    the map's range, marked by an arrow on the map's edge (:func:`outcome_map_image`)."""
    for value, axis, unit, sides in (
        (p.speed_ms, MAP_SPEEDS_MS, "m/s", ("left of", "right of")),
        (p.spin_rev_s, MAP_SPINS_REV_S, "rev/s", ("below", "above")),
    ):
        side = _off_map(value, axis)
        if side:
            return (
                f"This kick's {value:g} {unit} lies {sides[side > 0]} the map ({axis[0]:g}–{axis[-1]:g} {unit}): the "
                "white arrow on its edge points toward it."
            )
    return ""


def outcome_map_image(results: NDArray[np.str_], p: FreeKickParams) -> NDArray[np.uint8]:
    """RGB image of an outcome map, speed left to right, spin bottom to top, the current kick marked in white: a cross
    on its cell, or, where its speed or spin lies off the map, an arrowhead on that edge pointing out toward it."""
    rows, cols = results.shape
    image = np.zeros((rows, cols, 3), np.uint8)
    for name, colour in RESULT_COLOURS.items():
        image[results == name] = colour
    image = image[::-1]  # spin grows upward
    image = np.repeat(np.repeat(image, MAP_CELL_PX, axis=0), MAP_CELL_PX, axis=1)
    col = int(np.argmin(np.abs(MAP_SPEEDS_MS - p.speed_ms)))
    row = rows - 1 - int(np.argmin(np.abs(MAP_SPINS_REV_S - p.spin_rev_s)))
    cy, cx = row * MAP_CELL_PX + MAP_CELL_PX // 2, col * MAP_CELL_PX + MAP_CELL_PX // 2
    across, up = _off_map(p.speed_ms, MAP_SPEEDS_MS), _off_map(p.spin_rev_s, MAP_SPINS_REV_S)
    height, width = image.shape[:2]
    if across:  # tip on the left or right edge, 7 px deep and 13 px tall at its base
        for depth in range(7):
            x = depth if across < 0 else width - 1 - depth
            image[max(cy - depth, 0) : cy + depth + 1, x] = 255
    elif up:  # tip on the top or bottom edge (spin grows upward)
        for depth in range(7):
            y = depth if up > 0 else height - 1 - depth
            image[y, max(cx - depth, 0) : cx + depth + 1] = 255
    else:
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
    heading = goal_heading_rad(p) + np.radians(a)
    elevation = np.radians(e)
    velocities = p.speed_ms * np.stack(
        [np.cos(elevation) * np.cos(heading), np.cos(elevation) * np.sin(heading), np.sin(elevation)], axis=1
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
        t_max=FLIGHT_T_MAX_S,
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
        spin_before_knuckle_rev_s=None,
    )

    def crossing(k: FreeKickParams, *, goal_only: bool = False) -> NDArray[np.float64] | None:
        """(y, z) where ``k`` crosses the goal line (m), or None (also when ``goal_only`` and it is no goal)."""
        judged = ball.outcome(_fly(k, 1.0, knuckle=False), wall, goal)
        if judged.goal_point is None or (goal_only and judged.result != "goal"):
            return None
        return judged.goal_point[1:]

    here = crossing(kick, goal_only=True)
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
        # Backtrack: halve a step that leaves the goal or does not get closer.
        for _halving in range(6):
            trial = dataclasses.replace(
                kick,
                elevation_deg=float(np.clip(kick.elevation_deg + step[0], -5.0, 50.0)),
                azimuth_deg=float(np.clip(kick.azimuth_deg + step[1], -30.0, 30.0)),
            )
            there = crossing(trial, goal_only=True)
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
