"""The pitch's geometry: the goal's size, the wall's distance, and the wall and goal mouth as vertical panels.

World frame as in :mod:`kernels.ball`: x from the ball toward the goal, y to the left, z up; metres. A
:class:`Panel` stands on the ground; :func:`panel_rows` packs the wall and the goal as the compiled cores' (2, 6)
rows. Sizes are FIFA's Laws of the Game (goal 7.32 m × 2.44 m, wall 9.15 m from the ball).
"""

from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import ArrayLike, NDArray

from kernels import _checks
from kernels.ball import play
from kernels.ball.config import checked_vector

GOAL_WIDTH_M = 7.32
"""Between the inside edges of the posts."""
GOAL_HEIGHT_M = 2.44
"""Ground to the underside of the crossbar."""
WALL_DISTANCE_M = 9.15
"""FIFA distance of the defensive wall from the ball."""
MAX_PANEL_M = 1000.0
"""Largest width or height of a wall or goal (m): several times the longest pitch (120 m)."""


@dataclasses.dataclass(frozen=True)
class Panel:
    """A vertical rectangle standing on the ground: the wall, or the goal mouth."""

    centre_xy: tuple[float, float]
    """Foot of the panel's centre line (m)."""
    normal_xy: tuple[float, float]
    """Horizontal direction the ball must travel to pass through it (normalised on use)."""
    width_m: float
    """Full width (m)."""
    height_m: float
    """Height of the top edge above the ground (m)."""


def free_kick_panels(
    ball_xy: ArrayLike,
    goal_centre_xy: ArrayLike = (0.0, 0.0),
    goal_normal_xy: ArrayLike | None = None,
    *,
    wall_width_m: float = 2.0,
    wall_height_m: float = 1.8,
    wall_offset_m: float = 0.0,
) -> tuple[Panel, Panel]:
    """The wall (9.15 m from the ball, square to the line from ball to goal centre) and the goal mouth.

    Args:
        ball_xy: (2,) ball position on the ground (m).
        goal_centre_xy: (2,) centre of the goal line (m).
        goal_normal_xy: (2,) direction from the pitch into the net; None: along x, away from the ball (the goal
            line across the x axis, as the scene lays the pitch out). It must point away from the ball: a goal
            facing the kick the wrong way round is refused.
        wall_width_m: wall width (m), about 0.5 m a defender.
        wall_height_m: height of the defenders' heads (m), more when they jump.
        wall_offset_m: shift of the wall's centre to the left of the ball-to-goal line (m).

    Returns:
        ``(wall, goal)``.
    """
    ball = checked_vector("ball_xy", ball_xy, 2)
    centre = checked_vector("goal_centre_xy", goal_centre_xy, 2)
    if goal_normal_xy is None:
        goal_normal_xy = (1.0 if centre[0] >= ball[0] else -1.0, 0.0)
    normal = checked_vector("goal_normal_xy", goal_normal_xy, 2)
    if not normal.any():
        raise ValueError("goal_normal_xy must not be zero")
    if float((centre - ball) @ normal) <= 0.0:
        raise ValueError(
            "goal_normal_xy points from the pitch into the net, away from the ball; "
            f"{_checks.shown(tuple(normal.tolist()))} points from the goal at {_checks.shown(tuple(centre.tolist()))} "
            f"toward the ball at {_checks.shown(tuple(ball.tolist()))}"
        )
    aim = centre - ball
    distance = float(np.hypot(*aim))
    if distance <= WALL_DISTANCE_M:
        raise ValueError(f"ball_xy must be more than {WALL_DISTANCE_M} m from the goal, got {distance:.2f} m")
    aim /= distance
    left = np.array([-aim[1], aim[0]])
    wall_foot = ball + WALL_DISTANCE_M * aim + _checks.finite_number("wall_offset_m", wall_offset_m) * left
    wall = Panel(
        (float(wall_foot[0]), float(wall_foot[1])),
        (float(aim[0]), float(aim[1])),
        _panel_size("wall_width_m", wall_width_m),
        _panel_size("wall_height_m", wall_height_m),
    )
    goal = Panel(
        (float(centre[0]), float(centre[1])), (float(normal[0]), float(normal[1])), GOAL_WIDTH_M, GOAL_HEIGHT_M
    )
    return wall, goal


def _panel_size(name: str, value: object) -> float:
    """A size in (0, :data:`MAX_PANEL_M`] m, else ``ValueError`` naming it."""
    size = _checks.positive(name, value)
    if size > MAX_PANEL_M:
        raise ValueError(f"{name} must be at most {MAX_PANEL_M:g} m, got {_checks.shown(value)}")
    return size


def panel_rows(wall: Panel, goal: Panel) -> NDArray[np.float64]:
    """The wall and the goal as the compiled cores' (2, 6) rows: centre x, y, unit normal x, y, width, height."""
    return np.array([panel_row("wall", wall), panel_row("goal", goal)])


def panel_row(name: str, panel: Panel, *, standing: bool = False) -> NDArray[np.float64]:
    """One panel as a compiled core's (6,) row: centre x, y, unit normal x, y, width, height; ``standing`` asks for a
    height above the turf (> 0). ``ValueError`` naming ``name`` and the field."""
    _checks.instance(name, panel, Panel)
    normal = checked_vector(f"{name}.normal_xy", panel.normal_xy, 2)
    length = float(np.hypot(*normal))
    if length == 0.0:
        raise ValueError(f"{name}.normal_xy must not be zero")
    row = np.empty(6)
    row[0:2], row[2:4] = checked_vector(f"{name}.centre_xy", panel.centre_xy, 2), normal / length
    row[4] = _checks.positive(f"{name}.width_m", panel.width_m)
    check = _checks.positive if standing else _checks.finite_number
    row[5] = check(f"{name}.height_m", panel.height_m)
    # Bounded by a pitch's size, many times over: a wall 1e300 m high let a shot through (its top overflowed).
    for slot, field in ((4, "width_m"), (5, "height_m")):
        if row[slot] > MAX_PANEL_M:
            raise ValueError(
                f"{name}.{field} must be at most {MAX_PANEL_M:g} m, got {_checks.shown(getattr(panel, field))}"
            )
    return row


# --------------------------------------------------------------------------------------------- the pitch
@dataclasses.dataclass(frozen=True)
class Surface:
    """How the ball meets a surface: Cross's grip–slip impulse coefficients (see :func:`kernels.ball.bounce`) and,
    for turf, its rolling resistance."""

    restitution: float = 0.6
    """e_n, normal coefficient of restitution (0–1)."""
    friction: float = 0.6
    """μ, sliding friction (≥ 0)."""
    tangential_restitution: float = 0.1
    """e_t, the share of the contact point's tangential velocity returned reversed on grip (0–1)."""
    rolling_deceleration_ms2: float = 0.8
    """Rolling resistance (m/s², ≥ 0); the air's drag adds to it."""


DRY_TURF = Surface()
"""Dry turf: e_n 0.6 (a 2 m drop rebounds 0.72 m, inside FIFA Quality Pro's 0.60–0.85 m), μ 0.6, e_t 0.1 (Cross
2002's grip–slip values for a ball that grips), rolling resistance 0.8 m/s² (FIFA's ball-roll band: a ball leaving
the ramp at ~3.2 m/s rolls 4–10 m)."""
WET_TURF = Surface(friction=0.25)
"""Wet turf: as dry but μ 0.25 (0.2–0.3 wet): the ball skids on."""
FRAME = Surface(restitution=0.75, friction=0.3, tangential_restitution=0.1, rolling_deceleration_ms2=0.0)
"""Posts and bar (aluminium): e_n 0.75, μ 0.3. Assumed from FIFA's drop test onto steel (2 m → 1.35–1.55 m, e 0.82–
0.88 at 6.3 m/s), lowered because e falls at shot speeds; μ 0.3 is a guess for a ball sliding on painted metal."""
BODY = Surface(restitution=0.4, friction=0.5, tangential_restitution=0.0, rolling_deceleration_ms2=0.0)
"""The wall's players: e_n 0.4, μ 0.5, e_t 0: a guess (a body is soft and absorbs much of the impact); no
published value was found."""


MAX_POST_RADIUS_M = 0.5
"""The thickest post or bar a pitch takes (m, radius; Law 1 allows at most 0.06): a 5 m post was refused as a net too
shallow for it."""
PITCH_WIDTH_M = 68.0
"""A pitch's width between the touchlines (m; 68 m for international matches, Law 1: 64–75 m)."""
PENALTY_AREA_DEPTH_M = 16.5
"""How far the penalty area reaches out from the goal line (m; Law 1: 16.5 m, 18 yd)."""
PENALTY_AREA_HALF_WIDTH_M = 20.16
"""Half the penalty area's width, from the goal's centre (m; Law 1: 16.5 m beyond each post, 7.32 m apart)."""


@dataclasses.dataclass(frozen=True)
class Keeper:
    """A goalkeeper: a stick of radius ``body_radius_m`` from feet to fingertips through the centre of mass.

    He stands (upright, fingertips at ``com_height_m + hand_reach_m``) on the bisector of the angle the two posts
    make at the ball, ``depth_m`` off his line (shifted ``shift_m`` to his left, looking out), until a reaction time
    after the ball passes the wall (after the kick without a wall). Then he reads where the ball, flying straight on
    under gravity, will cross the goal line, again each step until that is within 1.5 s and within his hands' reach
    of the goal (a slow roll, a ball going away or far wide or over draws no dive), and dives for that point
    (brought within the goal): his centre of mass accelerates uniformly
    for ``push_off_s`` to ``dive_speed_ms``, then keeps it, along the straight line that puts his fingertips there,
    while the stick turns from upright to point at it over ``turn_s``. A ball that touches him is saved.

    Numbers: dive speed 3.9 m/s, the horizontal centre-of-mass speed at take-off of elite keepers diving to balls
    from a ball cannon (Ibrahim et al. 2019, J. Sports Sci. 37:313: 2.7 + 1.2 m/s from the two legs); reaction
    0.25 s (simple visual reaction is 0.2–0.3 s); push-off 0.3 s and turn 0.3 s are estimates of the dive's
    duration to take-off, body sizes a 1.90 m keeper's. Spratford et al. 2009 (J. Sports Sci.) was not available
    to check against.
    """

    position_xy: tuple[float, float] | None = None
    """Where he stands (m), in his penalty area (:data:`PENALTY_AREA_DEPTH_M` off the goal line, at most
    :data:`PENALTY_AREA_HALF_WIDTH_M` either side of the goal's centre); None places him by the angle, from the
    ball's spot (the first kick's for a batch)."""
    depth_m: float = 1.0
    """Off the goal line toward the ball, along the bisector (m, 0 to :data:`PENALTY_AREA_DEPTH_M`), when placed by
    the angle."""
    shift_m: float = 0.0
    """Sideways shift from the bisector (m, + to the left looking from the goal toward the ball; at most
    :data:`PENALTY_AREA_HALF_WIDTH_M` either way), when placed."""
    reaction_s: float = 0.25
    """From the ball passing the wall (or the kick) to the start of the dive (s)."""
    push_off_s: float = 0.3
    """Time to reach the dive speed (s, > 0)."""
    dive_speed_ms: float = 3.9
    """Centre-of-mass speed in the dive (m/s)."""
    turn_s: float = 0.3
    """Time for the body to turn from upright to point at the ball (s, > 0)."""
    com_height_m: float = 1.0
    """Centre of mass above the turf, standing (m)."""
    hand_reach_m: float = 1.3
    """Centre of mass to fingertips, arms stretched (m)."""
    foot_reach_m: float = 1.0
    """Centre of mass to the soles (m)."""
    body_radius_m: float = 0.15
    """Half the body's thickness (m)."""

    def placed(self, ball_xy: ArrayLike, goal: Panel) -> tuple[float, float]:
        """Where he stands for a ball at ``ball_xy``: ``position_xy``, or on the bisector of the posts' angle.

        Raises ``ValueError`` naming the field where he would stand outside his penalty area: behind his goal line
        (in the net, where a touch would save a ball already in), or so far out that he plays no part.
        """
        row = panel_row("goal", goal, standing=True)
        centre, normal = row[0:2], row[2:4]
        along = np.array([-normal[1], normal[0]])
        if self.position_xy is not None:
            spot = checked_vector("keeper.position_xy", self.position_xy, 2)
            _refuse_outside_area("keeper.position_xy", spot, centre, normal)
            return float(spot[0]), float(spot[1])
        depth = _checks.finite_number("keeper.depth_m", self.depth_m)
        if not 0.0 <= depth <= PENALTY_AREA_DEPTH_M:
            raise ValueError(
                f"keeper.depth_m must be in [0, {PENALTY_AREA_DEPTH_M:g}] m, got {_checks.shown(self.depth_m)}"
            )
        shift = _checks.finite_number("keeper.shift_m", self.shift_m)
        if abs(shift) > PENALTY_AREA_HALF_WIDTH_M:
            raise ValueError(
                f"keeper.shift_m must be within ±{PENALTY_AREA_HALF_WIDTH_M:g} m, got {_checks.shown(self.shift_m)}"
            )
        ball = _checks.bounded_array("ball_xy", checked_vector("ball_xy", ball_xy, 2), 1e300)  # no hypot overflows
        # The bisector of the angle at the ball runs from the ball through the point that splits the goal line in
        # the ratio of the ball's distances to the posts; the keeper stands on it, depth_m out from the line.
        d_right = float(np.hypot(*(ball - (centre - 0.5 * goal.width_m * along))))
        d_left = float(np.hypot(*(ball - (centre + 0.5 * goal.width_m * along))))
        split = centre + (-0.5 + d_right / (d_right + d_left)) * goal.width_m * along
        towards_ball = ball - split
        length = float(np.hypot(*towards_ball))
        unit = towards_ball / length if length > 0 else -normal
        left = np.array([-unit[1], unit[0]])
        spot = split + depth * unit - shift * left
        # A shift across a wide angle's bisector can still take him behind his line (2 m from a spot 20 m wide of
        # the goal put him 1.7 m into the net) or out of the area's side.
        _refuse_outside_area("keeper.depth_m and keeper.shift_m", spot, centre, normal)
        return float(spot[0]), float(spot[1])


def _refuse_outside_area(
    name: str, spot: NDArray[np.float64], centre: NDArray[np.float64], normal: NDArray[np.float64]
) -> None:
    """``ValueError`` naming ``name`` where ``spot`` (the keeper's place, (2,) m) lies outside the penalty area of the
    goal at ``centre`` whose unit ``normal`` points into the net."""
    out = float(-(spot - centre) @ normal)
    across = float((spot - centre) @ np.array([-normal[1], normal[0]]))
    if not (0.0 <= out <= PENALTY_AREA_DEPTH_M and abs(across) <= PENALTY_AREA_HALF_WIDTH_M):
        raise ValueError(
            f"{name} must put the keeper in his penalty area: 0 to {PENALTY_AREA_DEPTH_M:g} m out from the goal line "
            f"and within {PENALTY_AREA_HALF_WIDTH_M:g} m of the goal's centre across it; he would stand at "
            f"{_checks.shown(tuple(round(float(v), 6) for v in spot))} m, {out:.3g} m out and {across:.3g} m across"
        )


@dataclasses.dataclass(frozen=True)
class Pitch:
    """The goal (its posts, bar and net), the wall and the keeper, for a flight that goes on after it lands.

    Heights stand on the turf, at ``ground_m − radius_m`` of the flight's config (z = 0 for a ball whose centre
    touches at its radius, as the scene flies it). Posts and bar are cylinders (capsules) of ``post_radius_m`` (Law 1:
    at most 12 cm wide), the posts centred on the goal line ``goal.width_m`` apart at their inside edges, the bar's
    underside ``goal.height_m`` up; the net a box ``net_depth_m`` deep behind the line that stops the ball. The
    wall's players stand side by side as upright capsules of radius ``wall.width_m/(2·players)``, their heads at
    ``wall.height_m`` (give a jumping wall's height for a jump). A ball wholly over the goal line off the goal, or over
    a touchline (``pitch_width_m`` wide, centred on the goal), leaves the pitch.
    """

    goal: Panel
    wall: Panel | None = None
    keeper: Keeper | None = None
    post_radius_m: float = 0.06
    surface: Surface = DRY_TURF
    frame: Surface = FRAME
    body: Surface = BODY
    net_depth_m: float = 2.0
    wall_players: int | None = None
    """Players in the wall; None: one per 0.5 m of its width."""
    pitch_width_m: float = PITCH_WIDTH_M
    roll_speed_ms: float = 0.5
    """A ground bounce leaving less than this upward (a hop under 1.3 cm) starts the roll (m/s)."""

    def __post_init__(self) -> None:
        # Its parts' types now, so a wrong one is named here and not met later as an AttributeError; their values
        # are checked where the flight reads them (pitch_vector), with the spot that places the keeper.
        _checks.instance("pitch.goal", self.goal, Panel)
        for name, kind in (("wall", Panel), ("keeper", Keeper)):
            if getattr(self, name) is not None:
                _checks.instance(f"pitch.{name}", getattr(self, name), kind, f"None or a {kind.__name__}")
        for name in ("surface", "frame", "body"):
            _checks.instance(f"pitch.{name}", getattr(self, name), Surface)


def _surface_slots(name: str, surface: Surface, radius: float) -> list[float]:
    e_n, e_t = surface.restitution, surface.tangential_restitution
    for label, value in (("restitution", e_n), ("tangential_restitution", e_t)):
        number = _checks.finite_number(f"{name}.{label}", value)
        if not 0.0 <= number <= 1.0:
            raise ValueError(f"{name}.{label} must be in [0, 1], got {_checks.shown(value)}")
    mu = _checks.non_negative(f"{name}.friction", surface.friction)
    _checks.non_negative(f"{name}.rolling_deceleration_ms2", surface.rolling_deceleration_ms2)
    return [float(e_n), float(e_t), mu, radius, 2.0 / 3.0]


def pitch_vector(pitch: Pitch, ball_xy: ArrayLike, ground_m: float, radius_m: float) -> NDArray[np.float64]:
    """The compiled flight's (N_PITCH,) pitch vector (slots in :mod:`kernels.ball.play`), checked (``ValueError``
    naming the field). ``ball_xy`` places a keeper without a position."""
    _checks.instance("pitch", pitch, Pitch)
    for name in ("surface", "frame", "body"):
        _checks.instance(f"pitch.{name}", getattr(pitch, name), Surface)
    vector = np.zeros(play.N_PITCH)
    vector[play.GX : play.GH + 1] = panel_row("pitch.goal", pitch.goal, standing=True)
    post_radius = vector[play.POST_R] = _within("pitch.post_radius_m", pitch.post_radius_m, MAX_POST_RADIUS_M)
    vector[play.NET_DEPTH] = _checks.positive("pitch.net_depth_m", pitch.net_depth_m)
    if vector[play.NET_DEPTH] <= 2.0 * radius_m + post_radius:  # room for the whole ball over the line (a goal)
        raise ValueError(
            f"pitch.net_depth_m must be more than the ball's diameter and the post's radius "
            f"({2.0 * radius_m + post_radius:g} m), got {_checks.shown(pitch.net_depth_m)}"
        )
    vector[play.TURF] = ground_m - radius_m
    vector[play.HALF_WIDTH] = 0.5 * _within("pitch.pitch_width_m", pitch.pitch_width_m, MAX_PANEL_M)
    least = vector[play.GW] + 4.0 * post_radius  # the goal and both posts stand on the pitch
    if vector[play.HALF_WIDTH] * 2.0 <= least:
        raise ValueError(
            f"pitch.pitch_width_m must be more than the goal's width and its posts ({least:g} m), "
            f"got {_checks.shown(pitch.pitch_width_m)}"
        )
    vector[play.ROLL_DECEL] = _checks.non_negative(
        "pitch.surface.rolling_deceleration_ms2", pitch.surface.rolling_deceleration_ms2
    )
    vector[play.ROLL_SPEED] = _checks.non_negative("pitch.roll_speed_ms", pitch.roll_speed_ms)
    for slot, name, surface in (
        (play.TURF_SURFACE, "pitch.surface", pitch.surface),
        (play.FRAME_SURFACE, "pitch.frame", pitch.frame),
        (play.BODY_SURFACE, "pitch.body", pitch.body),
    ):
        vector[slot : slot + 5] = _surface_slots(name, surface, radius_m)
    if pitch.wall is not None:
        wall_row = panel_row("pitch.wall", pitch.wall, standing=True)
        players = pitch.wall_players
        if players is None:
            players = max(1, round(wall_row[4] / 0.5))
            if players > 16:
                raise ValueError(
                    f"pitch.wall.width_m is {wall_row[4]:g} m, {players} players at 0.5 m each; a wall has at most "
                    f"16 (8 m): give pitch.wall_players, or a narrower wall"
                )
        if isinstance(players, bool) or not isinstance(players, (int, np.integer)) or not 1 <= players <= 16:
            raise ValueError(f"pitch.wall_players must be None or an integer in [1, 16], got {_checks.shown(players)}")
        vector[play.WALL_ON] = 1.0
        vector[play.WX : play.WH + 1] = wall_row
        vector[play.N_PLAYERS] = players
        vector[play.PLAYER_R] = wall_row[4] / (2.0 * players)
    keeper = pitch.keeper
    if keeper is not None:
        _checks.instance("pitch.keeper", keeper, Keeper)
        keeper_slots(vector, keeper, keeper.placed(ball_xy, pitch.goal))
    return vector


def keeper_slots(vector: NDArray[np.float64], keeper: Keeper, position_xy: tuple[float, float]) -> None:
    """Write ``keeper``, standing at ``position_xy``, into a pitch vector's keeper slots, checked (``ValueError``
    naming the field)."""
    kx, ky = position_xy
    vector[play.KEEPER_ON] = 1.0
    vector[play.KX], vector[play.KY] = kx, ky
    # Bounded by a human's size and speed, several times over (a keeper 10³⁰⁰ m tall overflowed his own box).
    vector[play.K_RADIUS] = _within("keeper.body_radius_m", keeper.body_radius_m, 1.0)
    vector[play.K_COM] = _within("keeper.com_height_m", keeper.com_height_m, 5.0)
    vector[play.K_HANDS] = _within("keeper.hand_reach_m", keeper.hand_reach_m, 5.0)
    vector[play.K_FEET] = _within("keeper.foot_reach_m", keeper.foot_reach_m, 5.0)
    vector[play.K_REACT] = _within("keeper.reaction_s", keeper.reaction_s, 10.0, zero=True)
    vector[play.K_PUSH] = _within("keeper.push_off_s", keeper.push_off_s, 10.0)
    vector[play.K_SPEED] = _within("keeper.dive_speed_ms", keeper.dive_speed_ms, 20.0, zero=True)
    vector[play.K_TURN] = _within("keeper.turn_s", keeper.turn_s, 10.0)


def _within(name: str, value: object, most: float, *, zero: bool = False) -> float:
    """A number in (0, ``most``] (``zero``: [0, ``most``]), else ``ValueError`` naming it."""
    number = _checks.non_negative(name, value) if zero else _checks.positive(name, value)
    if number > most:
        raise ValueError(f"{name} must be at most {most:g}, got {_checks.shown(value)}")
    return number
