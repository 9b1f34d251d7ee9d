"""Joint types (:class:`Cone`, :class:`Hinge`), the limit table the compiled solvers read, and the compiled joint rules.

A chain's table has one row per segment (segment i is joints i to i + 1), or one row for every segment (the uniform
cone); a tree's has one row per joint, for the segment from its parent. Directions are unit vectors; angles are
radians. The cone is Aristidou & Lasenby 2011's joint limit (symmetric), the hinge caliko's (Lansley 2016), both
applied inside the passes so every iterate keeps every limit.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from kernels import _checks
from kernels._checks import bounded_array, finite_number
from kernels._jit import compiled
from kernels.fabrik.geometry import _DIM_3D, _LARGEST, _TINY, _perpendicular, _rotate, _turn_shortest, _unit, _wrap


# ================================================================================================ joint types
@dataclasses.dataclass(frozen=True)
class Cone:
    """A ball joint: the segment stays within ``half_angle_rad`` of the previous segment's direction (the first
    segment of the root direction), as ``cone_half_angle_rad`` does for every joint at once."""

    half_angle_rad: float
    """Half-angle of the cone (rad), in [0, π]; π leaves the joint free."""

    def __post_init__(self) -> None:
        phi = finite_number("half_angle_rad", self.half_angle_rad)
        if not 0.0 <= phi <= math.pi:
            raise ValueError(f"half_angle_rad must be in [0, π], got {_checks.shown(self.half_angle_rad)}")
        object.__setattr__(self, "half_angle_rad", phi)


HingeFrame = Literal["global", "local"]
"""Where a hinge's axes are given: fixed in the world, or in the frame of the previous segment."""


@dataclasses.dataclass(frozen=True)
class Hinge:
    """A hinge joint: the segment turns only about ``axis``, within an angle range (caliko's hinge, 2016).

    The segment's direction is kept in the plane through its inner joint perpendicular to the axis; its signed angle
    about the axis (right-handed), measured from the reference direction, stays in ``[min_angle_rad,
    max_angle_rad]``. The reference direction is ``reference_axis`` (its part perpendicular to the axis), or, when
    None, the previous segment's direction (the root direction for the first segment) projected onto that plane: the
    angle is then the joint angle a robot's encoder reads, 0 for a straight joint.

    ``frame="global"``: ``axis`` and ``reference_axis`` are fixed in the world (caliko's GLOBAL_HINGE).
    ``frame="local"``: they are given for a chain at rest along the root direction and turn with the previous
    segment, by the shortest rotation taking the root direction onto it (caliko's LOCAL_HINGE builds the previous
    bone's frame from a fixed up vector instead; the two agree about the bone's axis and differ in twist, which
    positions alone do not fix). For the first segment both frames are the world.

    Where ours differs from caliko: a range need not contain 0 (caliko's clockwise/anticlockwise limits do); a
    direction outside the range goes to the nearer end around the circle (caliko clamps to the end on its side);
    the forward pass only keeps each segment in its hinge plane and the backward pass imposes the range, as caliko
    does, so every returned pose keeps every hinge.
    """

    axis: ArrayLike
    """(3,) rotation axis (any length > 0; unit once built). In 2D it must be ±z, the plane's normal."""
    min_angle_rad: float = -math.pi
    """Lower end of the range (rad), in [−π, π]."""
    max_angle_rad: float = math.pi
    """Upper end of the range (rad), in [min_angle_rad, π]."""
    reference_axis: ArrayLike | None = None
    """(3,) direction angle 0 is measured from (its part perpendicular to ``axis``); None: the previous segment."""
    frame: HingeFrame = "global"
    """"global" or "local"; see the class docstring."""

    def __post_init__(self) -> None:
        axis = bounded_array("axis", self.axis, _LARGEST)
        if axis.shape != (3,) or not float(np.linalg.norm(axis)) > _TINY:
            raise ValueError(f"axis must be a non-zero (3,) vector, got {_checks.shown(self.axis)}")
        axis = axis / float(np.linalg.norm(axis))
        low = finite_number("min_angle_rad", self.min_angle_rad)
        high = finite_number("max_angle_rad", self.max_angle_rad)
        if not -math.pi <= low <= math.pi:
            raise ValueError(f"min_angle_rad must be in [−π, π], got {_checks.shown(self.min_angle_rad)}")
        if not low <= high <= math.pi:
            raise ValueError(
                f"max_angle_rad must be in [min_angle_rad, π] = [{low}, π], got {_checks.shown(self.max_angle_rad)}"
            )
        reference = None
        if self.reference_axis is not None:
            raw = bounded_array("reference_axis", self.reference_axis, _LARGEST)
            if raw.shape != (3,):
                raise ValueError(f"reference_axis must be a (3,) vector, got {_checks.shown(self.reference_axis)}")
            off = raw - float(raw @ axis) * axis
            if not float(np.linalg.norm(off)) > 1e-9 * max(float(np.linalg.norm(raw)), _TINY):
                raise ValueError(
                    f"reference_axis must not be parallel to axis, got {_checks.shown(self.reference_axis)}"
                )
            reference = tuple(float(v) for v in off / float(np.linalg.norm(off)))
        match self.frame:
            case "global" | "local":
                pass
            case _:
                raise ValueError(f"frame must be 'global' or 'local', got {_checks.shown(self.frame)}")
        object.__setattr__(self, "axis", tuple(float(v) for v in axis))
        object.__setattr__(self, "min_angle_rad", low)
        object.__setattr__(self, "max_angle_rad", high)
        object.__setattr__(self, "reference_axis", reference)


Constraint = Cone | Hinge | None
"""One segment's joint: a cone, a hinge, or None (free)."""

_TABLE_WIDTH = 13
"""Columns of a limit table row: kind, cos φ, sin φ, axis (3), reference (3), min, max, local, has reference."""
_KIND_FREE, _KIND_CONE, _KIND_HINGE = 0.0, 1.0, 2.0
_FREE_TABLE = np.zeros((1, _TABLE_WIDTH))
_CONE_SLACK = 1e-12
"""Rounding allowed when checking ``cos(angle) ≥ cos φ``."""
_HINGE_SLACK = 1e-9
"""Rounding allowed when checking a hinge: out of its plane by this much (of a unit direction), or past its range
by this many radians."""


def _limit_table(
    constraints: Sequence[Constraint], count: int, dim: int, name: str, *, segment_offset: int
) -> NDArray[np.float64]:
    """(count, 13) rows the compiled core reads, one per segment, from checked constraints.

    ``segment_offset`` rows are left free at the start (the root of a tree has no segment)."""
    if isinstance(constraints, (str, bytes)) or not isinstance(constraints, Sequence):
        raise ValueError(f"{name} must be a sequence of Cone, Hinge or None, got {_checks.shown(constraints)}")
    if len(constraints) != count:
        raise ValueError(f"{name} must have one entry per segment ({count}), got {len(constraints)}")
    table = np.zeros((count, _TABLE_WIDTH))
    for i, item in enumerate(constraints):
        if i < segment_offset and item is not None:
            raise ValueError(f"{name}[{i}] must be None (the root has no segment), got {_checks.shown(item)}")
        match item:
            case None:
                pass
            case Cone(half_angle_rad=phi):
                if phi < math.pi:
                    table[i, :3] = _KIND_CONE, math.cos(phi), math.sin(phi)
            case Hinge():
                axis = np.asarray(item.axis)
                if dim == 2 and abs(axis[2]) < 1.0 - 1e-12:
                    raise ValueError(f"{name}[{i}].axis must be ±z for a 2D chain, got {_checks.shown(item.axis)}")
                table[i, 0] = _KIND_HINGE
                table[i, 3:6] = axis
                if item.reference_axis is not None:
                    table[i, 6:9] = item.reference_axis
                    table[i, 12] = 1.0
                table[i, 9], table[i, 10] = item.min_angle_rad, item.max_angle_rad
                table[i, 11] = 1.0 if item.frame == "local" else 0.0
            case _:
                raise ValueError(f"{name}[{i}] must be a Cone, a Hinge or None, got {_checks.shown(item)}")
    return table


@compiled(error_model="numpy")
def _clamp_cone(
    vx: float, vy: float, vz: float, ax: float, ay: float, az: float, cos_phi: float, sin_phi: float, dim: int
) -> tuple[float, float, float]:
    """The unit direction v turned, by the least angle, into the cone of half-angle φ around the unit ``a``."""
    cos_v = vx * ax + vy * ay + vz * az
    if not cos_v < cos_phi:
        return vx, vy, vz
    sx, sy, sz, side = _unit(vx - cos_v * ax, vy - cos_v * ay, vz - cos_v * az, 0.0, 0.0, 0.0, 1e-9)
    if side <= 1e-9:  # v (anti)parallel to the axis: any side will do
        sx, sy, sz = _perpendicular(ax, ay, az, dim)
    # A nearly (anti)parallel v leaves the side only roughly perpendicular (v − (v·a)a cancels: its direction is off
    # by 1e-16/|side|, and a chain folded on its root left its cone by 2.5e-9 in cos): made square to a once more.
    along = sx * ax + sy * ay + sz * az
    sx, sy, sz, _ = _unit(sx - along * ax, sy - along * ay, sz - along * az, sx, sy, sz, 0.5)
    # Renormalised so lengths stay exact.
    cx, cy, cz = (cos_phi * ax + sin_phi * sx, cos_phi * ay + sin_phi * sy, cos_phi * az + sin_phi * sz)
    norm = math.sqrt(cx * cx + cy * cy + cz * cz)
    return cx / norm, cy / norm, cz / norm


@compiled(error_model="numpy")
def _row(table: NDArray[np.float64], i: int) -> int:
    return i if table.shape[0] > 1 else 0


@compiled(error_model="numpy")
def _hinge_axes(
    table: NDArray[np.float64], row: int, qx: float, qy: float, qz: float, rest: NDArray[np.float64]
) -> tuple[float, float, float, float, float, float]:
    """The hinge's world axis a and unit reference r ⊥ a, for a previous-segment direction q (unit)."""
    ax, ay, az = table[row, 3], table[row, 4], table[row, 5]
    rx, ry, rz = table[row, 6], table[row, 7], table[row, 8]
    if table[row, 11] != 0.0:  # local: turn with the previous segment
        ax, ay, az = _turn_shortest(ax, ay, az, rest, qx, qy, qz)
        if table[row, 12] != 0.0:
            rx, ry, rz = _turn_shortest(rx, ry, rz, rest, qx, qy, qz)
    if table[row, 12] == 0.0:
        rx, ry, rz = qx, qy, qz
    along = rx * ax + ry * ay + rz * az
    px, py, pz = _perpendicular(ax, ay, az, int(_DIM_3D))
    rx, ry, rz, _ = _unit(rx - along * ax, ry - along * ay, rz - along * az, px, py, pz, 1e-9)
    return ax, ay, az, rx, ry, rz


@compiled(error_model="numpy")
def _hinge_angle(
    vx: float,
    vy: float,
    vz: float,
    ax: float,
    ay: float,
    az: float,
    rx: float,
    ry: float,
    rz: float,
    low: float,
    high: float,
) -> float:
    """Signed angle of v about a from r (rad), as the representative in [low − 2π, high + 2π] nearest the range."""
    bx, by, bz = ay * rz - az * ry, az * rx - ax * rz, ax * ry - ay * rx
    theta = math.atan2(vx * bx + vy * by + vz * bz, vx * rx + vy * ry + vz * rz)
    if theta < low and theta + 2.0 * math.pi <= high + _HINGE_SLACK:
        theta += 2.0 * math.pi
    elif theta > high and theta - 2.0 * math.pi >= low - _HINGE_SLACK:
        theta -= 2.0 * math.pi
    return theta


@compiled(error_model="numpy")
def _clamp_hinge(
    vx: float,
    vy: float,
    vz: float,
    qx: float,
    qy: float,
    qz: float,
    table: NDArray[np.float64],
    row: int,
    rest: NDArray[np.float64],
) -> tuple[float, float, float]:
    """The unit direction v brought onto the hinge: projected onto its plane (the nearest direction there), then,
    outside the range, onto the nearer end around the circle."""
    ax, ay, az, rx, ry, rz = _hinge_axes(table, row, qx, qy, qz, rest)
    along = vx * ax + vy * ay + vz * az
    ux, uy, uz, _ = _unit(vx - along * ax, vy - along * ay, vz - along * az, rx, ry, rz, 1e-12)
    low, high = table[row, 9], table[row, 10]
    theta = _hinge_angle(ux, uy, uz, ax, ay, az, rx, ry, rz, low, high)
    if low <= theta <= high:
        return ux, uy, uz
    end = low if abs(_wrap(theta - low)) <= abs(_wrap(theta - high)) else high
    bx, by, bz = ay * rz - az * ry, az * rx - ax * rz, ax * ry - ay * rx
    c, s = math.cos(end), math.sin(end)
    return c * rx + s * bx, c * ry + s * by, c * rz + s * bz


@compiled(error_model="numpy")
def _constrain(
    vx: float,
    vy: float,
    vz: float,
    qx: float,
    qy: float,
    qz: float,
    table: NDArray[np.float64],
    i: int,
    rest: NDArray[np.float64],
    tiny: float,
    dim: int,
) -> tuple[float, float, float]:
    """Segment i's unit direction v brought inside its joint's limit, q (unit) the previous segment's direction."""
    row = _row(table, i)
    kind = table[row, 0]
    if kind == _KIND_CONE:
        return _clamp_cone(vx, vy, vz, qx, qy, qz, table[row, 1], table[row, 2], dim)
    if kind == _KIND_HINGE:
        return _clamp_hinge(vx, vy, vz, qx, qy, qz, table, row, rest)
    return vx, vy, vz


@compiled(error_model="numpy")
def _hold_by_next(
    dx: float,
    dy: float,
    dz: float,
    qx: float,
    qy: float,
    qz: float,
    table: NDArray[np.float64],
    row: int,
    rest: NDArray[np.float64],
    dim: int,
) -> tuple[float, float, float]:
    """A forward pass's rule for the joint ``row`` beyond a segment: the segment's reversed unit direction d is
    held by the next segment's (reversed, unit q) through that joint.

    A cone holds them together (it is symmetric); a hinge measured from the previous segment turns d about its axis
    until the next segment's angle from it is in range, as the cone does by symmetry. Chain and tree share it."""
    if table[row, 0] == _KIND_CONE:
        return _clamp_cone(dx, dy, dz, qx, qy, qz, table[row, 1], table[row, 2], dim)
    if table[row, 0] == _KIND_HINGE and table[row, 12] == 0.0:
        ax, ay, az, rx, ry, rz = _hinge_axes(table, row, -dx, -dy, -dz, rest)
        low, high = table[row, 9], table[row, 10]
        theta = _hinge_angle(-qx, -qy, -qz, ax, ay, az, rx, ry, rz, low, high)
        if not low <= theta <= high:
            end = low if abs(_wrap(theta - low)) <= abs(_wrap(theta - high)) else high
            return _rotate(dx, dy, dz, ax, ay, az, theta - end)
    return dx, dy, dz


@compiled(error_model="numpy")
def _into_hinge_plane(
    dx: float,
    dy: float,
    dz: float,
    sx: float,
    sy: float,
    sz: float,
    table: NDArray[np.float64],
    row: int,
    rest: NDArray[np.float64],
) -> tuple[float, float, float]:
    """A forward pass's rule for a segment's own joint ``row``: a hinge keeps the segment's reversed unit direction
    d in its plane, the plane taken from the previous segment's unit direction s as it stands (caliko's forward
    pass; the range waits for the backward pass). Other joints leave d. Chain and tree share it."""
    if table[row, 0] != _KIND_HINGE:
        return dx, dy, dz
    ax, ay, az, rx, ry, rz = _hinge_axes(table, row, sx, sy, sz, rest)
    along = dx * ax + dy * ay + dz * az
    dx, dy, dz, _ = _unit(dx - along * ax, dy - along * ay, dz - along * az, -rx, -ry, -rz, 1e-12)
    return dx, dy, dz


@compiled(error_model="numpy")
def _forward_limits(
    p: NDArray[np.float64],
    i: int,
    n: int,
    dx: float,
    dy: float,
    dz: float,
    qx: float,
    qy: float,
    qz: float,
    table: NDArray[np.float64],
    rest: NDArray[np.float64],
    tiny: float,
    dim: int,
) -> tuple[float, float, float]:
    """The chain's forward-pass limits on segment i, whose reversed unit direction is d (q: segment i + 1's,
    reversed): held by the joint to segment i + 1, then kept in its own hinge's plane."""
    if i < n - 1:
        dx, dy, dz = _hold_by_next(dx, dy, dz, qx, qy, qz, table, _row(table, i + 1), rest, dim)
    row = _row(table, i)
    if table[row, 0] == _KIND_HINGE:
        sx, sy, sz, _ = _unit(
            p[i, 0] - p[i - 1, 0], p[i, 1] - p[i - 1, 1], p[i, 2] - p[i - 1, 2], rest[0], rest[1], rest[2], tiny
        )
        dx, dy, dz = _into_hinge_plane(dx, dy, dz, sx, sy, sz, table, row, rest)
    return dx, dy, dz


@compiled(error_model="numpy")
def _holds(table: NDArray[np.float64], row: int) -> bool:
    """Whether joint ``row`` can hold a chain at a fixed point: a cone, or a hinge with less than the full turn
    (a free hinge only keeps its segment in its plane, where it moves as freely as without it)."""
    kind = table[row, 0]
    if kind == _KIND_FREE:
        return False
    return not (kind == _KIND_HINGE and table[row, 10] - table[row, 9] >= 2.0 * math.pi)


@compiled(from_python=True, error_model="numpy")
def _limit_flags(table: NDArray[np.float64]) -> tuple[bool, bool]:
    """(any limit at all, any limit that can hold a chain or tree at a fixed point; see :func:`_holds`)."""
    has_limits, holding = False, False
    for row in range(table.shape[0]):
        has_limits = has_limits or table[row, 0] != _KIND_FREE
        holding = holding or _holds(table, row)
    return has_limits, holding


@compiled(error_model="numpy")
def _joint_ok(
    dx: float,
    dy: float,
    dz: float,
    qx: float,
    qy: float,
    qz: float,
    table: NDArray[np.float64],
    i: int,
    rest: NDArray[np.float64],
    tiny: float,
) -> bool:
    """Whether segment i's unit direction d keeps its joint's limit, q the previous segment's unit direction."""
    row = _row(table, i)
    kind = table[row, 0]
    if kind == _KIND_CONE:
        return dx * qx + dy * qy + dz * qz >= table[row, 1] - _CONE_SLACK
    if kind == _KIND_HINGE:
        ax, ay, az, rx, ry, rz = _hinge_axes(table, row, qx, qy, qz, rest)
        if abs(dx * ax + dy * ay + dz * az) > _HINGE_SLACK:
            return False
        low, high = table[row, 9], table[row, 10]
        theta = _hinge_angle(dx, dy, dz, ax, ay, az, rx, ry, rz, low, high)
        return low - _HINGE_SLACK <= theta <= high + _HINGE_SLACK
    return True


@compiled(from_python=True, error_model="numpy")
def _usage(
    p: NDArray[np.float64], table: NDArray[np.float64], rest: NDArray[np.float64], tiny: float
) -> NDArray[np.float64]:
    """(n,) share of each segment's limit used (see :func:`limit_usage`)."""
    n = p.shape[0] - 1
    share = np.zeros(n)
    qx, qy, qz = rest[0], rest[1], rest[2]
    for i in range(n):
        dx, dy, dz, norm = _unit(p[i + 1, 0] - p[i, 0], p[i + 1, 1] - p[i, 1], p[i + 1, 2] - p[i, 2], qx, qy, qz, tiny)
        if norm <= tiny:
            continue
        row = _row(table, i)
        kind = table[row, 0]
        if kind == _KIND_CONE:
            phi = math.atan2(table[row, 2], table[row, 1])
            angle = math.acos(min(max(dx * qx + dy * qy + dz * qz, -1.0), 1.0))
            share[i] = 1.0 if phi <= 0.0 else min(angle / phi, 1.0)
        elif kind == _KIND_HINGE:
            ax, ay, az, rx, ry, rz = _hinge_axes(table, row, qx, qy, qz, rest)
            low, high = table[row, 9], table[row, 10]
            theta = _hinge_angle(dx, dy, dz, ax, ay, az, rx, ry, rz, low, high)
            half = 0.5 * (high - low)
            gap = min(theta - low, high - theta)
            share[i] = 1.0 if half <= 0.0 else min(max(1.0 - gap / half, 0.0), 1.0)
        qx, qy, qz = dx, dy, dz
    return share


@compiled(error_model="numpy")
def _inside_limit(
    qx: float,
    qy: float,
    qz: float,
    table: NDArray[np.float64],
    i: int,
    rest: NDArray[np.float64],
    u: float,
    v: float,
    dim: int,
) -> tuple[float, float, float]:
    """A unit direction for segment i that keeps its joint's limit, q (unit) the previous segment's direction, picked
    by two numbers u, v in [0, 1): a hinge's angle at the fraction u of its range; a cone's (or a free joint's,
    the cone of π) angle from q at ``(2u − 1) φ`` in the plane, or at ``u φ`` with azimuth ``2π v`` in 3D.

    The chain's restarts from admissible poses build their poses with it, segment by segment from the root."""
    row = _row(table, i)
    kind = table[row, 0]
    if kind == _KIND_HINGE:
        ax, ay, az, rx, ry, rz = _hinge_axes(table, row, qx, qy, qz, rest)
        low, high = table[row, 9], table[row, 10]
        angle = low + u * (high - low)
        bx, by, bz = ay * rz - az * ry, az * rx - ax * rz, ax * ry - ay * rx
        c, s = math.cos(angle), math.sin(angle)
        return c * rx + s * bx, c * ry + s * by, c * rz + s * bz
    phi = math.atan2(table[row, 2], table[row, 1]) if kind == _KIND_CONE else math.pi
    sx, sy, sz = _perpendicular(qx, qy, qz, dim)
    if dim == 2:
        angle = (2.0 * u - 1.0) * phi
    else:
        angle = u * phi
        tx, ty, tz = qy * sz - qz * sy, qz * sx - qx * sz, qx * sy - qy * sx
        c, s = math.cos(2.0 * math.pi * v), math.sin(2.0 * math.pi * v)
        sx, sy, sz = c * sx + s * tx, c * sy + s * ty, c * sz + s * tz
    c, s = math.cos(angle), math.sin(angle)
    dx, dy, dz = c * qx + s * sx, c * qy + s * sy, c * qz + s * sz
    norm = math.sqrt(dx * dx + dy * dy + dz * dz)
    return dx / norm, dy / norm, dz / norm


@compiled(error_model="numpy")
def _holding_hinge(table: NDArray[np.float64]) -> bool:
    """Whether some joint is a hinge with less than the full turn (see :func:`_holds`)."""
    for row in range(table.shape[0]):
        if table[row, 0] == _KIND_HINGE and _holds(table, row):
            return True
    return False


@compiled(error_model="numpy")
def _bend_within(
    table: NDArray[np.float64],
    i: int,
    qx: float,
    qy: float,
    qz: float,
    nx: float,
    ny: float,
    nz: float,
    rest: NDArray[np.float64],
    step: float,
) -> float:
    """The signed bend (rad, right-handed about the unit normal n) that segment i takes from the straight
    continuation q (unit) of the segment before it when a straight chain is bent into an arc: ``step`` toward the
    centre of a hinge's range about ±n, at most half way to that side's end (0 for a zero range, the feasible side
    of a one-sided range); ``step`` for other joints (a cone bounds ``step`` itself), and for a hinge about another
    axis (the backward pass brings the bend into its plane) at most half its range's larger side."""
    row = _row(table, i)
    if table[row, 0] != _KIND_HINGE:
        return step
    ax, ay, az, rx, ry, rz = _hinge_axes(table, row, qx, qy, qz, rest)
    along = ax * nx + ay * ny + az * nz
    low, high = table[row, 9], table[row, 10]
    straight = _hinge_angle(qx, qy, qz, ax, ay, az, rx, ry, rz, low, high)
    low, high = low - straight, high - straight
    # About another axis, the backward pass turns the bend into the hinge's plane: keep it that small.
    if abs(along) < 1.0 - 1e-9:
        return min(step, max(max(0.5 * high, -0.5 * low), 0.0))  # max of two: one compiled max
    if along < 0.0:
        low, high = -high, -low
    if low + high >= 0.0:
        return min(step, max(0.5 * high, 0.0))
    return max(-step, min(0.5 * low, 0.0))
