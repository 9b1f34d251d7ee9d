"""Operators on distances and query points after Quilez: rounding, onion, elongation, twist, bend, finite repetition
and mirror symmetry, mirrored name for name in ``shaders/sdf.glsl``.

Points are ``(N, 3)`` float arrays in metres; distances ``(N,)`` in metres. A point transform maps the query point;
the shape is then any primitive evaluated at the mapped point.

Source: I. Quilez, "distance functions" (iquilezles.org/articles/distfunctions, 2008–2024).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from kernels import _checks
from kernels.sdf.blend import distance_array
from kernels.sdf.primitives import MAX_COORDINATE, FloatArray, coordinates, length

MAX_RATE = 1e150
"""Largest twist or bend (rad/m): times a coordinate within ±MAX_COORDINATE the angle stays finite (cos and sin
of an infinite angle are NaN)."""


def _rate(value: object) -> float:
    k = _checks.finite_number("rate", value)
    if abs(k) > MAX_RATE:
        raise ValueError(f"rate must be of magnitude ≤ {MAX_RATE:g} rad/m, got {_checks.shown(value)}")
    return k


# Quilez, "distance functions": rounding, onion, and the point transforms (elongation, twist, bend, finite
# repetition, mirror symmetry). A point transform maps the query point; the shape is then any primitive evaluated
# at the mapped point. GLSL has no function arguments, so both sides are written this way, name for name.
def op_round(d: ArrayLike, radius: float) -> FloatArray:
    """d − radius: a shape grown by ``radius`` with rounded edges (Quilez, "Rounding"). Exact if d is, outside.

    Args:
        d: (N,) distances (m), ±inf allowed (±inf stays ±inf), never NaN.
        radius: rounding radius (m), in [0, :data:`~kernels.sdf.primitives.MAX_COORDINATE`].
    """
    return distance_array("d", d) - length("radius", radius, zero_ok=True)


def op_onion(d: ArrayLike, thickness: float) -> FloatArray:
    """|d| − thickness: a shell of the surface (Quilez, "Onion"). Exact if d is.

    Args:
        d: (N,) distances (m), ±inf allowed (giving +inf), never NaN.
        thickness: half the shell's wall thickness (m), in [0, :data:`~kernels.sdf.primitives.MAX_COORDINATE`].
    """
    return np.abs(distance_array("d", d)) - length("thickness", thickness, zero_ok=True)


def op_elongate(p: ArrayLike, half_length: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Stretch a shape by 2·half_length, splitting it at its centre planes (Quilez, "Elongation", exact form).

    ``q = |p| − h``; the shape is ``sd(p − clamp(p, −h, h)) + min(max(q.x, q.y, q.z), 0)``. The first part keeps
    the sign of p (Quilez writes ``max(q, 0)``, which needs a shape symmetric in every axis). Exact if sd is.

    Args:
        p: (N, 3) points (m), within ±:data:`~kernels.sdf.primitives.MAX_COORDINATE`.
        half_length: (3,) elongation along x, y, z (m), each in [0, :data:`~kernels.sdf.primitives.MAX_COORDINATE`].

    Returns:
        (N, 3) points to evaluate the shape at, and (N,) the term to add to its distance.
    """
    pts = coordinates("p", p)
    h = _checks.vector("half_length", _checks.bounded_array("half_length", half_length, MAX_COORDINATE), 3)
    if np.any(h < 0.0):
        raise ValueError(f"half_length must be non-negative, got {h.tolist()}")
    q = np.abs(pts) - h
    return pts - np.clip(pts, -h, h), np.minimum(q.max(axis=1), 0.0)


def op_twist(p: ArrayLike, rate: float) -> FloatArray:
    """Twist about local y: rotate (x, z) by the angle rate·y (Quilez, "Twist").

    Not a distance-preserving map: a shape of radius ρ from the axis needs its distance divided by
    sqrt(1 + (rate·ρ)²) to stay a bound.

    Args:
        p: (N, 3) points (m), within ±:data:`~kernels.sdf.primitives.MAX_COORDINATE`.
        rate: twist (rad/m), of magnitude ≤ :data:`MAX_RATE`.

    Returns:
        (N, 3) points: (c·x − s·z, y, s·x + c·z) with c, s = cos, sin(rate·y).
    """
    pts = coordinates("p", p)
    k = _rate(rate)
    c, s = np.cos(k * pts[:, 1]), np.sin(k * pts[:, 1])
    return np.stack([c * pts[:, 0] - s * pts[:, 2], pts[:, 1], s * pts[:, 0] + c * pts[:, 2]], axis=1)


def op_bend(p: ArrayLike, rate: float) -> FloatArray:
    """Bend in the xy plane: rotate (x, y) by the angle rate·x (Quilez, "Bend").

    Not distance-preserving either (the same bound correction as :func:`op_twist`).

    Args:
        p: (N, 3) points (m), within ±:data:`~kernels.sdf.primitives.MAX_COORDINATE`.
        rate: bend (rad/m), of magnitude ≤ :data:`MAX_RATE`.

    Returns:
        (N, 3) points: (c·x − s·y, s·x + c·y, z) with c, s = cos, sin(rate·x).
    """
    pts = coordinates("p", p)
    k = _rate(rate)
    c, s = np.cos(k * pts[:, 0]), np.sin(k * pts[:, 0])
    return np.stack([c * pts[:, 0] - s * pts[:, 1], s * pts[:, 0] + c * pts[:, 1], pts[:, 2]], axis=1)


def op_repeat_finite(p: ArrayLike, spacing: ArrayLike, limit: ArrayLike) -> FloatArray:
    """Finite repetition: copies every ``spacing`` along each axis, cell indices in [−limit, limit]
    (Quilez, "Finite Repetition").

    ``p − spacing·clamp(round(p/spacing), −limit, limit)``, rounding half up (floor(x + ½), the same in GLSL,
    whose round() leaves halves to the driver). Exact for a shape that fits in its cell and is symmetric.

    Args:
        p: (N, 3) points (m), within ±:data:`~kernels.sdf.primitives.MAX_COORDINATE`.
        spacing: (3,) cell size along x, y, z (m), each in (0, :data:`~kernels.sdf.primitives.MAX_COORDINATE`].
        limit: (3,) copies on each side of the middle one, each ≥ 0 (whole numbers, at most MAX_COORDINATE).

    Returns:
        (N, 3) points in the nearest copy's frame.
    """
    pts = coordinates("p", p)
    c = _checks.positive_vector("spacing", _checks.bounded_array("spacing", spacing, MAX_COORDINATE), 3)
    lim = _checks.vector("limit", _checks.bounded_array("limit", limit, MAX_COORDINATE), 3)
    if np.any(lim < 0.0) or np.any(lim != np.round(lim)):
        raise ValueError(f"limit must be whole numbers ≥ 0, got {lim.tolist()}")
    return pts - c * np.clip(np.floor(pts / c + 0.5), -lim, lim)


def op_symmetry(p: ArrayLike, axes: ArrayLike) -> FloatArray:
    """Mirror symmetry: the chosen coordinates replaced by their absolute values (Quilez, "Symmetry").

    Args:
        p: (N, 3) points (m), within ±:data:`~kernels.sdf.primitives.MAX_COORDINATE`.
        axes: (3,) 1 (mirror across that coordinate's plane) or 0 (leave it), for x, y, z.

    Returns:
        (N, 3) points.
    """
    pts = coordinates("p", p)
    mask = _checks.vector("axes", axes, 3)
    if not np.all((mask == 0.0) | (mask == 1.0)):
        raise ValueError(f"axes must be 0 or 1 each, got {mask.tolist()}")
    return np.where(mask > 0.0, np.abs(pts), pts)
