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
from kernels.ball.config import checked_vector

GOAL_WIDTH_M = 7.32
"""Between the inside edges of the posts."""
GOAL_HEIGHT_M = 2.44
"""Ground to the underside of the crossbar."""
WALL_DISTANCE_M = 9.15
"""FIFA distance of the defensive wall from the ball."""


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
    goal_normal_xy: ArrayLike = (-1.0, 0.0),
    *,
    wall_width_m: float = 2.0,
    wall_height_m: float = 1.8,
    wall_offset_m: float = 0.0,
) -> tuple[Panel, Panel]:
    """The wall (9.15 m from the ball, square to the line from ball to goal centre) and the goal mouth.

    Args:
        ball_xy: (2,) ball position on the ground (m).
        goal_centre_xy: (2,) centre of the goal line (m).
        goal_normal_xy: (2,) direction from the pitch into the net.
        wall_width_m: wall width (m), about 0.5 m a defender.
        wall_height_m: height of the defenders' heads (m), more when they jump.
        wall_offset_m: shift of the wall's centre to the left of the ball-to-goal line (m).

    Returns:
        ``(wall, goal)``.
    """
    ball = checked_vector("ball_xy", ball_xy, 2)
    centre = checked_vector("goal_centre_xy", goal_centre_xy, 2)
    normal = checked_vector("goal_normal_xy", goal_normal_xy, 2)
    if not normal.any():
        raise ValueError("goal_normal_xy must not be zero")
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
        _checks.positive("wall_width_m", wall_width_m),
        _checks.positive("wall_height_m", wall_height_m),
    )
    goal = Panel(
        (float(centre[0]), float(centre[1])),
        (float(normal[0]), float(normal[1])),
        GOAL_WIDTH_M,
        GOAL_HEIGHT_M,
    )
    return wall, goal


def panel_rows(wall: Panel, goal: Panel) -> NDArray[np.float64]:
    """The wall and the goal as the compiled cores' (2, 6) rows: centre x, y, unit normal x, y, width, height."""
    rows = np.empty((2, 6))
    for row, (name, panel) in zip(rows, (("wall", wall), ("goal", goal)), strict=True):
        normal = checked_vector(f"{name}.normal_xy", panel.normal_xy, 2)
        length = float(np.hypot(*normal))
        if length == 0.0:
            raise ValueError(f"{name}.normal_xy must not be zero")
        row[0:2], row[2:4] = (
            checked_vector(f"{name}.centre_xy", panel.centre_xy, 2),
            normal / length,
        )
        row[4] = _checks.positive(f"{name}.width_m", panel.width_m)
        row[5] = _checks.finite_number(f"{name}.height_m", panel.height_m)
    return rows
