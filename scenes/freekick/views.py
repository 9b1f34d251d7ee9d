"""Where each view of the free kick puts its camera: the points it keeps in frame and the pose that frames them for
one browser's lens (the goalkeeper's view looks over the goal and past the wall). No viser.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from kernels import ball
from scenes._framing import Lens, View, box_corners, frame_clear_of_notice, project_points
from scenes.freekick.model import (
    DEFENDER_WIDTH_M,
    DEFENDERS,
    KEEPER,
    FreeKickParams,
    KickState,
    ViewName,
    ball_spot,
    resample,
    wall_axes,
)

VIEW_MIN_DEPTH_M: dict[ViewName, float] = {"broadcast": 3.0, "behind": 4.0, "side": 3.0, "goal": 1.0, "above": 3.0}
"""How far in front of each view's camera everything stays (m): behind the ball means a few steps back."""
VIEW_TILTS: dict[ViewName, tuple[float, ...]] = {
    "broadcast": (1.5,),
    "behind": (0.45, 0.6, 0.8, 1.0),
    "side": (0.15,),
    "goal": (0.3, 0.4, 0.5, 0.65, 0.8, 1.0, 1.3),
    "above": (1.0,),
}
"""Downward tilts each view tries (the down part of its look for its horizontal part: see :func:`view_direction`). The
goalkeeper's view takes the flattest from which it sees the ball and the keeper over the goal and the ball past the
wall; the others the one that shows the goal widest (the first on a tie). The raised view keeps one: steeper, it drew
the goal at most 0.01 of the width wider and the flight narrower across the screen."""
GOAL_CLEAR_M = 0.3
"""How far above the crossbar and the net's roof (m) the goalkeeper's view sees the ball and the keeper's head."""
KEEPER_BOX_M = 0.5
"""Half the width of the box (m) kept in frame around where the keeper stands: his body and arms."""


def view_direction(p: FreeKickParams, view: ViewName, tilt: float | None = None) -> NDArray[np.float64]:
    """(3,) direction a camera looks in for ``view`` of the kick ``p`` (not unit): its horizontal look plus
    ``tilt`` times straight down (default: the view's first of :data:`VIEW_TILTS`)."""
    spot = ball_spot(p)
    forward = np.array([-spot[0], -spot[1], 0.0]) / max(math.hypot(spot[0], spot[1]), 1e-9)
    left = np.array([-forward[1], forward[0], 0.0])
    down = np.array([0.0, 0.0, -1.0])
    match view:
        case "broadcast":
            # Raised over the kicker's left shoulder, looking down the flight: a sideways curl runs across the
            # screen instead of along the line of sight, and the goal is in front, not far off to one side.
            look = forward - 0.8 * left
        case "behind":
            look = forward
        case "side":  # from the kicker's right: the ball flies left to right across the screen
            look = left
        case "goal":  # the goalkeeper's: from behind the goal, over his shoulder, back at the ball and the wall
            look = -forward
        case "above":
            look = 0.35 * forward
    k = VIEW_TILTS[view][0] if tilt is None else tilt
    return look + k * down


def view_points(
    p: FreeKickParams, state: KickState, view: ViewName, also: NDArray[np.float64] | None = None
) -> NDArray[np.float64]:
    """(N, 3) what ``view`` keeps in frame (m): the ball on its spot (its whole sphere), the flight and its
    no-spin ghost (the played-on flight after its first contact may roll away out of frame), the wall, the goal with its
    net and the keeper standing in it (his box to his raised hands). ``view`` is for the callers' symmetry: every view
    keeps the same points. ``also``: (M, 3) more points the view from above keeps in frame (the odds map's tiles,
    when it is shown).
    """
    half, h = 0.5 * ball.GOAL_WIDTH_M, ball.GOAL_HEIGHT_M
    goal = np.array([[x, y, z] for x in (0.0, 2.0) for y in (-half, half) for z in (0.0, h)])
    keeper = np.empty((0, 3))
    if state.keeper_xy is not None:
        kx, ky = state.keeper_xy
        top = KEEPER.com_height_m + KEEPER.hand_reach_m
        keeper = box_corners((kx - KEEPER_BOX_M, ky - KEEPER_BOX_M, 0.0), (kx + KEEPER_BOX_M, ky + KEEPER_BOX_M, top))
    wall = state.wall
    _normal, along = wall_axes(wall)
    centre, width = np.array(wall.centre_xy), 0.5 * DEFENDERS * DEFENDER_WIDTH_M
    wall_pts = np.array([[*(centre + side * width * along), z] for side in (-1.0, 1.0) for z in (0.0, wall.height_m)])
    paths = [resample(state.flight, PATH_FRAME_POINTS), resample(state.ghost, PATH_FRAME_POINTS)]
    spot = ball_spot(p)
    sphere = spot + ball.BALL_RADIUS_M * np.vstack([np.eye(3), -np.eye(3)])
    extra = [also] if (view == "above" and also is not None) else []
    return np.vstack([goal, keeper, wall_pts, *paths, sphere, *extra])


PATH_FRAME_POINTS = 48
"""Samples of each drawn path kept in frame."""


def wall_hides(state: KickState, eye: NDArray[np.float64], target: NDArray[np.float64]) -> bool:
    """Whether the wall (with a ball's radius of margin) stands on the straight line from ``eye`` to ``target`` (m)."""
    wall = state.wall
    normal_xy, along_xy = wall_axes(wall)
    normal, along = np.array([*normal_xy, 0.0]), np.array([*along_xy, 0.0])
    centre = np.array([*wall.centre_xy, 0.0])
    a, b = float((eye - centre) @ normal), float((target - centre) @ normal)
    if a * b > 0.0:  # both on one side of the wall's plane
        return False
    hit = eye + (a / (a - b)) * (target - eye)
    half = 0.5 * DEFENDERS * DEFENDER_WIDTH_M + ball.BALL_RADIUS_M
    return abs(float((hit - centre) @ along)) <= half and hit[2] <= wall.height_m + ball.BALL_RADIUS_M


def goal_hides(eye: NDArray[np.float64], target: NDArray[np.float64], clear_m: float = GOAL_CLEAR_M) -> bool:
    """Whether the straight line from ``eye`` to ``target`` (m) passes through the goal (its mouth, net and frame,
    the box from the goal line to the back of the net, up to ``clear_m`` over the crossbar) on its way."""
    half = 0.5 * ball.GOAL_WIDTH_M + 0.12
    top = ball.GOAL_HEIGHT_M + 0.12 + clear_m
    x, y, z = (eye + np.linspace(0.0, 1.0, 65)[:, None] * (target - eye)).T
    return bool(np.any((x >= -0.12) & (x <= 2.0) & (np.abs(y) <= half) & (z <= top)))


def keeper_head(state: KickState) -> NDArray[np.float64] | None:
    """(3,) top of the standing keeper's raised hands (m), None without a keeper."""
    if state.keeper_xy is None:
        return None
    return np.array([*state.keeper_xy, KEEPER.com_height_m + KEEPER.hand_reach_m])


def tilt_chosen(p: FreeKickParams, state: KickState, view: ViewName, framed: View) -> bool:
    """Whether the goalkeeper's ``framed`` pose sees the ball over the goal and past the wall, and the keeper's
    raised hands over the goal (always true for the other views)."""
    if view != "goal":
        return True
    eye = np.array(framed.position)
    spot = ball_spot(p)
    head = keeper_head(state)
    if goal_hides(eye, spot) or wall_hides(state, eye, spot):
        return False
    return head is None or not goal_hides(eye, head, 0.0)


def goal_width_px(view: View, lens: Lens) -> float:
    """Width (px) the goal mouth's corners span on the canvas of ``lens`` seen from ``view``."""
    half, h = 0.5 * ball.GOAL_WIDTH_M, ball.GOAL_HEIGHT_M
    corners = np.array([[0.0, y, z] for y in (-half, half) for z in (0.0, h)])
    return float(np.ptp(project_points(view, lens, corners)[:, 0]))


def frame_view(
    p: FreeKickParams, state: KickState, view: ViewName, lens: Lens, also: NDArray[np.float64] | None = None
) -> View:
    """The camera pose of ``view`` for one browser's ``lens``: :func:`view_points` (with ``also``) in frame, left of
    the panel and clear of viser's software-WebGL notice at the top left (:func:`frame_clear_of_notice`).

    Each view tries its tilts (:data:`VIEW_TILTS`). The goalkeeper's view takes the flattest whose camera sees the
    ball and the keeper over the goal and the ball past the wall (:func:`tilt_chosen`), else the steepest; the
    others take the one that draws the goal widest.
    """
    points = view_points(p, state, view, also)
    best: tuple[float, View] | None = None
    framed: View | None = None
    for tilt in VIEW_TILTS[view]:
        d = view_direction(p, view, tilt)
        framed = frame_clear_of_notice(
            points, (float(d[0]), float(d[1]), float(d[2])), lens, min_depth=VIEW_MIN_DEPTH_M[view]
        )
        if view == "goal":
            if tilt_chosen(p, state, view, framed):
                return framed
            continue
        width = goal_width_px(framed, lens)
        if best is None or width > best[0] + 0.5:
            best = (width, framed)
    if best is not None:
        return best[1]
    assert framed is not None
    return framed
