"""Where things sit and how they project: rider slots, the tilted course frame, and label layout in pixels.

Points are (N, 3) world metres, z up; screen points are (N, 2) pixels, x right and y down, for a pinhole camera
(:class:`~scenes._framing.View` and :class:`~scenes._framing.Lens`). No viser handles: pure numpy.
"""

from __future__ import annotations

import math

import numpy as np

from scenes._framing import Lens, View, in_notice
from scenes.peloton.model import BIKE_LENGTH_M, MAX_RIDERS

LABEL_PX = (190.0, 30.0)
"""Room a rider's label needs right of and above its anchor (px): framing keeps it clear of the panel."""


def slot_offsets(n_riders: int, gap_m: float) -> np.ndarray:
    """(MAX_RIDERS,) x positions of the slots, leader at 0 and each slot one bike plus one gap behind."""
    return -np.arange(MAX_RIDERS) * (BIKE_LENGTH_M + gap_m)


LABEL_PAD_PX = 4.0
"""Clear space kept between two riders' labels (px)."""


def under_notice(points_px: np.ndarray, anchors_px: np.ndarray) -> bool:
    """Whether any of the (N, 2) ``points_px`` or any label drawn right of and above its (M, 2) anchor
    (:data:`LABEL_PX`) would lie under :data:`NOTICE_PX`."""
    label_bottoms = np.asarray(anchors_px, dtype=np.float64) - (0.0, LABEL_PX[1])
    return bool(in_notice(points_px).any() or in_notice(label_bottoms).any())


def course_to_world(points: np.ndarray, grade_pct: float) -> np.ndarray:
    """(N, 3) points of the course frame (m) in the world: the course frame turns by −atan(grade) about y."""
    theta = math.atan(grade_pct / 100.0)
    c, s = math.cos(theta), math.sin(theta)
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    return np.stack([c * pts[:, 0] - s * pts[:, 2], pts[:, 1], s * pts[:, 0] + c * pts[:, 2]], axis=1)


def label_lifts_px(
    anchors_px: np.ndarray,
    label_px: tuple[float, float] = LABEL_PX,
    *,
    text_px: float | None = None,
    stem_px: float = 0.0,
) -> np.ndarray:
    """(N,) how far (px, upward) to lift each label so no two overlap, leader first: each takes the lowest free place.

    Each label hangs on a leader line, straight down from its anchor to its rider ``stem_px`` below the unlifted
    anchor; with ``text_px`` no label's text (that wide, right of its anchor) crosses another label's line either.

    Args:
        anchors_px: (N, 2) screen x, y (px, y down) of each label's anchor; its box spans ``label_px`` right of and
            above it.
        label_px: (width, height) of a label's box (px).
        text_px: width of a label's text (px), at most ``label_px[0]``; None: lines are not looked at.
        stem_px: length (px) of a leader line below its unlifted anchor.
    """
    width, height = label_px[0] + LABEL_PAD_PX, label_px[1] + LABEL_PAD_PX
    text = None if text_px is None else min(text_px, label_px[0]) + LABEL_PAD_PX
    anchors = np.asarray(anchors_px, dtype=np.float64)
    lifts = np.zeros(len(anchors))
    for i, (x, y) in enumerate(anchors):
        # Label j, placed, forbids lifts in (low, high): where the two boxes would share rows.
        blocked = [
            (y - yj + lifts[j] - height, y - yj + lifts[j] + height)
            for j, (xj, yj) in enumerate(anchors[:i])
            if abs(x - xj) < width
        ]
        if text is not None:
            for j, (xj, yj) in enumerate(anchors[:i]):
                if (
                    x - LABEL_PAD_PX < xj < x + text
                ):  # this label's text would cross j's line (yj - lift_j to yj + stem)
                    blocked.append((y - yj - stem_px - height, y - yj + lifts[j] + LABEL_PAD_PX))
                if xj - LABEL_PAD_PX < x < xj + text:  # this label's line would rise through j's text
                    top = y - yj + lifts[j]  # this lift puts the label level with j's
                    if y + stem_px > yj - lifts[j] - height:
                        blocked.append((top - LABEL_PAD_PX, np.inf))
        for lift in sorted({0.0, *(high for _, high in blocked if np.isfinite(high))}):
            if lift >= 0.0 and not any(low < lift < high for low, high in blocked):
                lifts[i] = lift
                break
        else:  # no free place: above every other label
            lifts[i] = max((high for _, high in blocked if np.isfinite(high)), default=0.0)
    return lifts


def camera_basis(view: View) -> tuple[np.ndarray, ...]:
    """The camera's position and its (3,) unit forward, right and up vectors in the world, z up."""
    position, look_at = np.asarray(view.position), np.asarray(view.look_at)
    d = (look_at - position) / np.linalg.norm(look_at - position)
    right = np.cross(d, (0.0, 0.0, 1.0))
    right /= np.linalg.norm(right)
    return position, d, right, np.cross(right, d)


def project_px(points_world: np.ndarray, view: View, lens: Lens) -> np.ndarray:
    """(N, 2) screen x, y (px, y down) of world points (m) seen from ``view`` through ``lens`` (pinhole, z up)."""
    position, d, right, up = camera_basis(view)
    rel = np.asarray(points_world, dtype=np.float64) - position
    depth = rel @ d
    tan_y = math.tan(0.5 * lens.fov_rad)
    x = (rel @ right) / (depth * tan_y * lens.aspect)
    y = (rel @ up) / (depth * tan_y)
    return np.stack([(x + 1.0) / 2.0 * lens.width_px, (1.0 - y) / 2.0 * lens.height_px], axis=1)


def lift_to_metres(
    anchors_world: np.ndarray, lifts_px: np.ndarray, up_world: np.ndarray, view: View, lens: Lens
) -> np.ndarray:
    """(N,) distances (m) along ``up_world`` that raise each anchor by its lift (px) in ``lens`` from ``view``.

    Exact for the pinhole camera: the screen height of a point moved along a line is a ratio of linear functions
    of the distance, solved for the target height.
    """
    position, d, _right, up = camera_basis(view)
    tan_y = math.tan(0.5 * lens.fov_rad)
    rel = np.asarray(anchors_world, dtype=np.float64) - position
    a, b = rel @ up, float(up_world @ up)
    c, e = (rel @ d) * tan_y, float(up_world @ d) * tan_y
    target = a / c + 2.0 * np.asarray(lifts_px, dtype=np.float64) / max(lens.height_px, 1)
    return np.maximum((target * c - a) / (b - target * e), 0.0)
