"""Where each view of the free kick puts its camera: the points it keeps in frame and the pose that frames them for
one browser's lens (the goalkeeper's view also looks past the wall). No viser.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from kernels import ball
from scenes._framing import Lens, View, box_corners, frame_clear_of_notice
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
KEEPER_BOX_M = 0.5
"""Half the width of the box (m) kept in frame around where the keeper stands: his body and arms."""
KEEPER_FRONT_M = 0.3
"""How far in front of the goal line (x < 0) the goalkeeper's camera stands at least (m)."""


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
        case "goal":  # the goalkeeper's: from in front of the goal line, back at the ball and the wall
            return -forward + look_aside * left + look_down * down
        case "above":
            return 0.35 * forward + down


def view_points(
    p: FreeKickParams, state: KickState, view: ViewName, also: NDArray[np.float64] | None = None
) -> NDArray[np.float64]:
    """(N, 3) what ``view`` keeps in frame (m): the ball on its spot (its whole sphere), the path and the no-spin
    ghost, the wall, the goal with its net and the keeper standing in it (his box to his raised hands); the goalkeeper's view (``"goal"``) stands in front of the goal, so it
    keeps neither the goal nor the last :data:`KEEPER_SEES_FROM_M` of the flights. ``also``: (M, 3) more points the
    view from above keeps in frame (the odds map's tiles, when it is shown).
    """
    half, h = 0.5 * ball.GOAL_WIDTH_M, ball.GOAL_HEIGHT_M
    goal = np.array([[x, y, z] for x in (0.0, 2.0) for y in (-half, half) for z in (0.0, h)])
    if state.keeper_xy is not None:
        kx, ky = state.keeper_xy
        top = KEEPER.com_height_m + KEEPER.hand_reach_m
        goal = np.vstack(
            [
                goal,
                box_corners((kx - KEEPER_BOX_M, ky - KEEPER_BOX_M, 0.0), (kx + KEEPER_BOX_M, ky + KEEPER_BOX_M, top)),
            ]
        )
    wall = state.wall
    _normal, along = wall_axes(wall)
    centre, width = np.array(wall.centre_xy), 0.5 * DEFENDERS * DEFENDER_WIDTH_M
    wall_pts = np.array([[*(centre + side * width * along), z] for side in (-1.0, 1.0) for z in (0.0, wall.height_m)])
    path, ghost = resample(state.flight, 24), resample(state.ghost, 24)
    spot = ball_spot(p)
    sphere = spot + ball.BALL_RADIUS_M * np.vstack([np.eye(3), -np.eye(3)])
    if view == "goal":
        flights = np.vstack([path, ghost])
        far_out = flights[flights[:, 0] <= -KEEPER_SEES_FROM_M]
        return np.vstack([wall_pts, far_out, sphere])
    if view == "above" and also is not None:
        return np.vstack([goal, wall_pts, path, ghost, sphere, also])
    return np.vstack([goal, wall_pts, path, ghost, sphere])


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


def frame_view(
    p: FreeKickParams, state: KickState, view: ViewName, lens: Lens, also: NDArray[np.float64] | None = None
) -> View:
    """The camera pose of ``view`` for one browser's ``lens``: :func:`view_points` (with ``also``) in frame, left of
    the panel and clear of viser's software-WebGL notice at the top left (:func:`frame_clear_of_notice`).

    The goalkeeper's view tries tilts (:data:`KEEPER_LOOK_DOWN`, flattest first) and turns
    (:data:`KEEPER_LOOK_ASIDE`) until its camera stands at least :data:`KEEPER_FRONT_M` in front of the goal line
    and sees the ball past or over the wall; failing that, the last pose in front of the line, else the last tried.
    """
    points = view_points(p, state, view, also)
    if view == "goal":
        tries = [(down, aside) for down in KEEPER_LOOK_DOWN for aside in KEEPER_LOOK_ASIDE]
    else:
        tries = [(KEEPER_LOOK_DOWN[0], KEEPER_LOOK_ASIDE[0])]
    spot = ball_spot(p)
    framed, in_front = None, None
    for down, aside in tries:
        d = view_direction(p, view, down, aside)
        framed = frame_clear_of_notice(
            points, (float(d[0]), float(d[1]), float(d[2])), lens, min_depth=VIEW_MIN_DEPTH_M[view]
        )
        if view != "goal":
            return framed
        if framed.position[0] <= -KEEPER_FRONT_M:
            in_front = framed
            if not wall_hides(state, np.array(framed.position), spot):
                return framed
    assert framed is not None
    return in_front if in_front is not None else framed
