"""Compiled vector primitives shared by the chain and tree solvers: unit vectors, rotations, and the obstacle rule.

Vectors are passed as scalars ``(x, y, z)`` in metres (a 2D problem has z = 0 and ``dim = 2``); obstacles are
``centres`` (K, 3) m and ``radii`` (K,) m, circles in 2D and spheres in 3D; the passes take them as one
:data:`Obstacles` tuple with ``live`` (K,), those the root stands outside of. A segment is ``a + t·v``,
``t ∈ [0, length]``. Whenever a pass would place a segment through an obstacle, it is turned about its anchor by the
least angle until it only touches it (tangent, or its far end on the surface).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from kernels._jit import compiled

_TINY = 1e-12
"""Relative length below which a vector has no direction, and the rounding slack of the reach tests (times the
chain's scale, ``max(ΣL, |target − root|)``; never added to the tolerance)."""
_LARGEST = 1e300
"""Largest magnitude accepted for a coordinate, length or radius (m): sums and differences stay finite."""
_CLEARANCE = 1e-6
"""Segments are turned to clear an obstacle by this fraction of its radius, so rounding never leaves them inside."""
_TOUCH = 1e-3
"""A pose within this fraction of an obstacle's radius of it rests against it ("blocked")."""

Obstacles = tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]]
"""``(centres, radii, live)``: centres (K, 3) m, radii (K,) m, and which of them count (K,): an obstacle the root
stands inside of is ignored."""


_DIM_3D, _ROW_0, _OFF = 3, 0, False
"""Passed by compiled callers as ``int(_DIM_3D)``, ``int(_ROW_0)``, ``bool(_OFF)``: numba types a bare ``3``, ``0`` or
``False`` as a literal and compiles the callee once more for it; an int or bool argument shares the one variant."""


@compiled(error_model="numpy")
def _unit(
    x: float, y: float, z: float, fx: float, fy: float, fz: float, tiny: float
) -> tuple[float, float, float, float]:
    """``(x, y, z) / |(x, y, z)|`` and the norm; the fallback direction where the norm is ≤ ``tiny``."""
    norm = math.sqrt(x * x + y * y + z * z)
    if norm > tiny:
        inverse = 1.0 / norm
        return x * inverse, y * inverse, z * inverse, norm
    return fx, fy, fz, norm


@compiled(from_python=True, error_model="numpy")
def _perpendicular(x: float, y: float, z: float, dim: int) -> tuple[float, float, float]:
    """A fixed unit vector perpendicular to the unit vector (x, y, z): in the plane for d = 2."""
    if dim == 2:
        return -y, x, 0.0
    # the cross product with the coordinate axis least aligned with the vector
    ex, ey = (0.0, 1.0) if abs(x) > 0.9 else (1.0, 0.0)
    cx, cy, cz = -z * ey, z * ex, x * ey - y * ex
    norm = math.sqrt(cx * cx + cy * cy + cz * cz)
    return cx / norm, cy / norm, cz / norm


_HALF_TURN = 0.5e-16
"""1 + s·t (= δ²/2) below which :func:`_turn_shortest` turns by half a turn: δ < 10⁻⁸ rad from t = −s."""


@compiled(error_model="numpy")
def _turn_shortest(
    vx: float, vy: float, vz: float, s: NDArray[np.float64], tx: float, ty: float, tz: float
) -> tuple[float, float, float]:
    """v turned by the shortest rotation taking unit s onto unit t (π about a perpendicular where t = −s).

    ``R v = v + c × v + c × (c × v) / (1 + s·t)`` with ``c = s × t`` (Rodrigues' formula without the angle).

    Within δ of t = −s the formula's rounding grows as ε/δ (c = s × t cancels) and the half turn's error as δ, so
    the half turn takes over at δ = 10⁻⁸ ≈ √ε: each is then within about 10⁻⁸. (At 1.4·10⁻⁶, where it took over
    before, a zero-range local hinge after a segment that far from −s bent by as much.) 1 + s·t is taken as
    ``|s + t|² / 2``, which keeps its digits there."""
    cx, cy, cz = s[1] * tz - s[2] * ty, s[2] * tx - s[0] * tz, s[0] * ty - s[1] * tx
    hx, hy, hz = s[0] + tx, s[1] + ty, s[2] + tz
    one_plus_dot = 0.5 * (hx * hx + hy * hy + hz * hz)
    if one_plus_dot < _HALF_TURN:
        kx, ky, kz = _perpendicular(s[0], s[1], s[2], int(_DIM_3D))
        along = 2.0 * (kx * vx + ky * vy + kz * vz)
        return along * kx - vx, along * ky - vy, along * kz - vz
    wx, wy, wz = cy * vz - cz * vy, cz * vx - cx * vz, cx * vy - cy * vx
    k = 1.0 / one_plus_dot
    ux, uy, uz = cy * wz - cz * wy, cz * wx - cx * wz, cx * wy - cy * wx
    return vx + wx + k * ux, vy + wy + k * uy, vz + wz + k * uz


@compiled(error_model="numpy")
def _rotate(
    vx: float, vy: float, vz: float, ax: float, ay: float, az: float, angle: float
) -> tuple[float, float, float]:
    """v turned by ``angle`` (rad) about the unit axis a (Rodrigues' formula)."""
    c, s = math.cos(angle), math.sin(angle)
    dot = (ax * vx + ay * vy + az * vz) * (1.0 - c)
    return (
        vx * c + (ay * vz - az * vy) * s + ax * dot,
        vy * c + (az * vx - ax * vz) * s + ay * dot,
        vz * c + (ax * vy - ay * vx) * s + az * dot,
    )


@compiled(error_model="numpy")
def _wrap(angle: float) -> float:
    """``angle`` (rad) brought into [−π, π)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


@compiled(error_model="numpy")
def _turn_clear(
    ax: float,
    ay: float,
    az: float,
    vx: float,
    vy: float,
    vz: float,
    length: float,
    centre: NDArray[np.float64],
    radius: float,
    tiny: float,
    dim: int,
) -> tuple[float, float, float]:
    """The direction nearest v whose segment of ``length`` from anchor ``a`` just clears one obstacle: tangent to
    it if the segment is long enough to reach the tangent point, else with its far end on the surface."""
    clear = radius * (1.0 + _CLEARANCE)
    cx, cy, cz, distance = _unit(centre[0] - ax, centre[1] - ay, centre[2] - az, -vx, -vy, -vz, tiny)
    if distance <= radius:  # an anchor inside: leave straight away from the centre
        return -cx, -cy, -cz
    if length * length >= distance * distance - clear * clear:
        sin_t = min(max(clear / max(distance, tiny), 0.0), 1.0)
        cos_t = math.sqrt(1.0 - sin_t * sin_t)
    else:
        cos_t = (length * length + distance * distance - clear * clear) / (
            2.0 * max(length, tiny) * max(distance, tiny)
        )
        cos_t = min(max(cos_t, -1.0), 1.0)
        sin_t = math.sqrt(1.0 - cos_t * cos_t)
    along = vx * cx + vy * cy + vz * cz
    sx, sy, sz, side = _unit(vx - along * cx, vy - along * cy, vz - along * cz, 0.0, 0.0, 0.0, 1e-9)
    if side <= 1e-9:  # v through the centre: turn to any side
        sx, sy, sz = _perpendicular(cx, cy, cz, dim)
    tx, ty, tz = cos_t * cx + sin_t * sx, cos_t * cy + sin_t * sy, cos_t * cz + sin_t * sz
    norm = math.sqrt(tx * tx + ty * ty + tz * tz)
    return tx / norm, ty / norm, tz / norm


@compiled(error_model="numpy")
def _deflect(
    ax: float,
    ay: float,
    az: float,
    vx: float,
    vy: float,
    vz: float,
    length: float,
    obstacles: Obstacles,
    tiny: float,
    dim: int,
) -> tuple[float, float, float, bool]:
    """Turn the segment ``a + t·v, t ∈ [0, length]`` by the least angle until no live obstacle cuts it; returns
    the new unit direction and whether it was turned."""
    centres, radii, live = obstacles
    turned = False
    for _ in range(3):  # turning around one obstacle can push into another: a few rounds settle it
        hit = False
        for k in range(radii.shape[0]):
            if not live[k]:
                continue
            rx, ry, rz = centres[k, 0] - ax, centres[k, 1] - ay, centres[k, 2] - az
            rel2 = rx * rx + ry * ry + rz * rz
            reach = length + radii[k]
            if rel2 >= reach * reach:  # too far for the segment to touch: most pairs stop here
                continue
            along = rx * vx + ry * vy + rz * vz
            t = min(max(along, 0.0), length)
            if rel2 - 2.0 * t * along + t * t < radii[k] * radii[k]:
                hit = True
                vx, vy, vz = _turn_clear(ax, ay, az, vx, vy, vz, length, centres[k], radii[k], tiny, dim)
        if not hit:
            return vx, vy, vz, turned
        turned = True
    return vx, vy, vz, turned


@compiled(error_model="numpy")
def _segment_cuts(p: NDArray[np.float64], a: int, b: int, obstacles: Obstacles, inflate: float) -> bool:
    """Whether the segment from joint ``a`` to joint ``b`` of ``p`` (J, 3) passes within ``inflate`` × radius of a
    live obstacle's centre. A zero-length segment is its one point (the closest-point parameter is not divided by
    its zero squared length). The chain and the tree both test their poses with it."""
    centres, radii, live = obstacles
    x, y, z = p[a, 0], p[a, 1], p[a, 2]
    sx, sy, sz = p[b, 0] - x, p[b, 1] - y, p[b, 2] - z
    seg2 = sx * sx + sy * sy + sz * sz
    for k in range(radii.shape[0]):
        if not live[k]:
            continue
        rx, ry, rz = centres[k, 0] - x, centres[k, 1] - y, centres[k, 2] - z
        grown = radii[k] * inflate
        # |c − a| ≥ |s| + r, so no point of the segment is within r: (|s| + r)² ≤ 2(|s|² + r²)
        if rx * rx + ry * ry + rz * rz >= 2.0 * (seg2 + grown * grown):
            continue
        t = min(max((rx * sx + ry * sy + rz * sz) / (seg2 if seg2 > 0.0 else 1.0), 0.0), 1.0)
        gx, gy, gz = rx - t * sx, ry - t * sy, rz - t * sz
        if gx * gx + gy * gy + gz * gz < grown * grown:
            return True
    return False


@compiled(error_model="numpy")
def _mark_live(
    centres: NDArray[np.float64], radii: NDArray[np.float64], live: NDArray[np.bool_], x: float, y: float, z: float
) -> bool:
    """Mark in ``live`` (K,) each obstacle the root ``(x, y, z)`` stands outside of (one it stands inside could never
    be cleared, so it is ignored); whether any is live."""
    any_live = False
    for k in range(radii.shape[0]):
        rx, ry, rz = centres[k, 0] - x, centres[k, 1] - y, centres[k, 2] - z
        live[k] = rx * rx + ry * ry + rz * rz > radii[k] * radii[k]
        any_live = any_live or live[k]
    return any_live


@compiled(error_model="numpy")
def _inside_live(obstacles: Obstacles, x: float, y: float, z: float) -> bool:
    """Whether the point ``(x, y, z)`` (a target) lies inside a live obstacle."""
    centres, radii, live = obstacles
    for k in range(radii.shape[0]):
        rx, ry, rz = centres[k, 0] - x, centres[k, 1] - y, centres[k, 2] - z
        if live[k] and rx * rx + ry * ry + rz * rz < radii[k] * radii[k]:
            return True
    return False
