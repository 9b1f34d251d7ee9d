"""Free kick: a spinning ball's 3D flight over a wall, with its forces, a no-spin ghost, a ±10 % spin band and the
knuckleball.

- :mod:`~scenes.freekick.model`: the parameters (each one's control declared on it), presets and the pure functions
  from parameters to a kick state, the outcome map and the aim search (no viser).
- :mod:`~scenes.freekick.views`: where each view puts its camera.
- :mod:`~scenes.freekick.props`: goal, net, pitch markings, defender and arrow geometry, and the colours.
- :mod:`~scenes.freekick.scene`: :class:`FreeKickScene`, which draws it all on viser.

This module re-exports what callers use, so ``from scenes.freekick import ...`` does not depend on the split.
"""

from __future__ import annotations

from scenes.freekick.model import (
    AIM_TOLERANCE_M,
    JUMP_M,
    MAP_QUIET_S,
    MAP_SPEEDS_MS,
    MAP_SPINS_REV_S,
    PATH_POINTS,
    PRESETS,
    RESULT_COLOURS,
    VIEW_LABELS,
    FreeKickParams,
    KickState,
    Preset,
    ViewName,
    aim_at,
    ball_spot,
    compute_kick,
    outcome_map,
    resample,
    sample_rows,
    spin_words,
)
from scenes.freekick.props import (
    ARROW_POINTS,
    FORCE_COLOURS,
    KNUCKLE_COLOUR,
    PATH_COLOUR,
    polyline_segments,
)
from scenes.freekick.scene import FreeKickScene
from scenes.freekick.views import (
    VIEW_MIN_DEPTH_M,
    VIEW_TILTS,
    frame_view,
    goal_hides,
    view_points,
    wall_hides,
)

_segments = polyline_segments
"""The older name of :func:`~scenes.freekick.props.polyline_segments`, which tests/test_coalescing.py imports."""

__all__ = [
    "AIM_TOLERANCE_M",
    "ARROW_POINTS",
    "FORCE_COLOURS",
    "JUMP_M",
    "KNUCKLE_COLOUR",
    "MAP_QUIET_S",
    "MAP_SPEEDS_MS",
    "MAP_SPINS_REV_S",
    "PATH_COLOUR",
    "PATH_POINTS",
    "PRESETS",
    "RESULT_COLOURS",
    "VIEW_LABELS",
    "VIEW_MIN_DEPTH_M",
    "VIEW_TILTS",
    "FreeKickParams",
    "FreeKickScene",
    "KickState",
    "Preset",
    "ViewName",
    "aim_at",
    "ball_spot",
    "compute_kick",
    "frame_view",
    "goal_hides",
    "outcome_map",
    "polyline_segments",
    "resample",
    "sample_rows",
    "spin_words",
    "view_points",
    "wall_hides",
]
