"""The compiled chain core: FABRIK (Aristidou & Lasenby 2011), CCD (Wang & Chen 1991) and damped least squares
(Wampler 1986; Buss 2004) on the scalars of one chain of ``n + 1`` joints ``p`` (n + 1, 3), metres.

Every solver lives once, here; ``_solve_rows`` runs it over some rows of a batch (without the GIL, so the batch
driver in :mod:`~kernels.fabrik.api` runs chunks of a batch on several threads), ``_solve_one`` for one chain. A 2D
chain has z = 0 and ``dim = 2`` where the perpendicular and the rotations differ. See :mod:`kernels.fabrik` for the
model, the statuses and the stopping rules.
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from kernels._jit import compiled
from kernels.fabrik.geometry import (
    _OFF,
    _TINY,
    _TOUCH,
    Obstacles,
    _deflect,
    _inside_live,
    _mark_live,
    _perpendicular,
    _segment_cuts,
    _unit,
)
from kernels.fabrik.limits import _bend_within, _constrain, _forward_limits, _holding_hinge, _inside_limit, _joint_ok

Status = Literal["reached", "unreachable", "max_iterations", "blocked", "limited", "infeasible"]
"""Why a solve stopped:

* ``"reached"``: the end effector is within the tolerance of the target (error ≤ tolerance, exactly: no slack);
* ``"unreachable"``: the target lies outside the reach annulus, farther than the tolerance from the closest pose
  (the closest admissible pose seen is returned; with no limits or obstacles, within the tolerance of the closest
  pose, unless the iterates stalled);
* ``"blocked"``: a reachable target not reached, with the returned pose resting against an obstacle (within 0.1 %
  of its radius) or the target inside one;
* ``"limited"``: a reachable target not reached, the iterates stalled under joint limits (or obstacles, not
  touched) at a fixed point of the method: the error stopped changing, or the best error stopped improving (see
  Stopping). It does not prove the limits keep the chain from the target; another start may reach it;
* ``"max_iterations"``: the iteration cap came first, still converging: a reachable target, or one out of reach
  whose closest pose a chain with no limits or obstacles is still farther than the tolerance from;
* ``"infeasible"``: no pose the solver saw (neither the start nor any iterate) keeps every limit and clears every
  obstacle; the last iterate is returned, and it is not admissible.
"""
STATUSES: tuple[Status, ...] = ("reached", "unreachable", "max_iterations", "blocked", "limited", "infeasible")
_REACHED, _UNREACHABLE, _MAX_ITERATIONS, _BLOCKED, _LIMITED, _INFEASIBLE = range(6)

Solver = Literal["fabrik", "ccd", "jacobian_dls"]
"""The iterative methods; they share arguments, constraints and result."""
_FABRIK, _CCD, _DLS = range(3)
_SOLVER_IDS: dict[str, int] = {"fabrik": _FABRIK, "ccd": _CCD, "jacobian_dls": _DLS}

_STALL = 1e-3
"""A chain whose end-effector error changed by less than this fraction of the tolerance in an iteration is at a
fixed point (caliko's "minimum change" rule)."""
_PATIENCE = 10
"""A constrained chain whose best admissible error has improved by less than :data:`_PROGRESS` of the tolerance in
this many iterations has stopped making progress (it creeps toward, or circles, a fixed point the limits or
obstacles impose)."""
_PROGRESS = 0.1
"""See :data:`_PATIENCE`: 1 % of the tolerance per iteration, a pace at which the cap would come first anyway."""
_EXTRAPOLATION_CAP = 8.0
"""Most last-steps a FABRIK iterate is moved on by: enough for an error ratio of 0.89."""
_EXTRAPOLATION_MIN_RATIO = 0.5
"""Error ratio per iteration below which FABRIK iterates are left as they are."""
_DLS_DAMPING = 0.1
"""Damping of the DLS step, times the mean link length (Buss 2004 suggests λ of the order of the link size)."""
_POLISH_STARTS = 5
"""Starts of the polish of a FABRIK chain under hinges that stalls or creeps: the best pose, then two mirrored pairs
of admissible poses."""
_POLISH_STEPS = 50
"""Most damped-least-squares steps of the polish from each start (not ``max_iterations``: a longer run must repeat
a shorter one's polish)."""
_CREEP = 0.5
"""A chain under hinges whose best error has not halved in :data:`_PATIENCE` iterations creeps (FABRIK under
one-sided ranges can close in as slowly as 1/k): it is polished."""
_GOLDEN = 0.6180339887498949, 0.7548776662466927, 0.5698402909980532
"""Steps of the additive recurrences (golden ratio; plastic number) that spread the admissible starts' joint angles
evenly and deterministically: the same starts in every call, every thread."""


@compiled(error_model="numpy")
def _forward_pass(
    p: NDArray[np.float64],
    target: NDArray[np.float64],
    lengths: NDArray[np.float64],
    tiny: float,
    rest: NDArray[np.float64],
    limits: tuple[bool, NDArray[np.float64]],
    obstacles: Obstacles,
    has_zero: bool,
    dim: int,
) -> None:
    """End on the target, each joint back toward its old place at its link's length (the root is left)."""
    has_limits, table = limits
    n = lengths.shape[0]
    p[n, 0], p[n, 1], p[n, 2] = target[0], target[1], target[2]
    qx, qy, qz, _ = _unit(p[0, 0] - p[n, 0], p[0, 1] - p[n, 1], p[0, 2] - p[n, 2], -rest[0], -rest[1], -rest[2], tiny)
    x, y, z = p[n, 0], p[n, 1], p[n, 2]  # the anchor, carried in registers from joint to joint
    for i in range(n - 1, 0, -1):
        dx, dy, dz, _ = _unit(p[i, 0] - x, p[i, 1] - y, p[i, 2] - z, qx, qy, qz, tiny)
        if obstacles[1].shape[0] > 0:  # any obstacle at all
            dx, dy, dz, _ = _deflect(x, y, z, dx, dy, dz, lengths[i], obstacles, tiny, dim)
        if has_limits:
            dx, dy, dz = _forward_limits(p, i, n, dx, dy, dz, qx, qy, qz, table, rest, tiny, dim)
        length = lengths[i]
        x, y, z = x + length * dx, y + length * dy, z + length * dz
        p[i, 0], p[i, 1], p[i, 2] = x, y, z
        if not has_zero or length > tiny:
            qx, qy, qz = dx, dy, dz


@compiled(error_model="numpy")
def _backward_step(
    x: float,
    y: float,
    z: float,
    px: float,
    py: float,
    pz: float,
    qx: float,
    qy: float,
    qz: float,
    length: float,
    row: int,
    rest: NDArray[np.float64],
    limits: tuple[bool, NDArray[np.float64]],
    obstacles: Obstacles,
    tiny: float,
    dim: int,
) -> tuple[float, float, float]:
    """Backward reaching's rule for one segment, shared by chains and trees: the unit direction from its placed
    anchor (x, y, z) toward its joint's current place (px, py, pz), clamped into the limit of table row ``row``
    about the previous segment's direction q, turned clear of live obstacles at ``length``, and clamped again where
    that turned it."""
    has_limits, table = limits
    dx, dy, dz, _ = _unit(px - x, py - y, pz - z, qx, qy, qz, tiny)
    if has_limits:
        dx, dy, dz = _constrain(dx, dy, dz, qx, qy, qz, table, row, rest, tiny, dim)
    if obstacles[1].shape[0] > 0:  # any obstacle at all
        dx, dy, dz, turned = _deflect(x, y, z, dx, dy, dz, length, obstacles, tiny, dim)
        if turned and has_limits:
            dx, dy, dz = _constrain(dx, dy, dz, qx, qy, qz, table, row, rest, tiny, dim)
    return dx, dy, dz


@compiled(error_model="numpy")
def _backward_pass(
    p: NDArray[np.float64],
    lengths: NDArray[np.float64],
    tiny: float,
    rest: NDArray[np.float64],
    limits: tuple[bool, NDArray[np.float64]],
    obstacles: Obstacles,
    has_zero: bool,
    dim: int,
) -> None:
    """Root back on its place, each joint outward toward its current place; limits and obstacles enforced."""
    qx, qy, qz = rest[0], rest[1], rest[2]
    x, y, z = p[0, 0], p[0, 1], p[0, 2]  # the anchor, carried in registers from joint to joint
    for i in range(1, lengths.shape[0] + 1):
        length = lengths[i - 1]
        dx, dy, dz = _backward_step(
            x, y, z, p[i, 0], p[i, 1], p[i, 2], qx, qy, qz, length, i - 1, rest, limits, obstacles, tiny, dim
        )
        x, y, z = x + length * dx, y + length * dy, z + length * dz
        p[i, 0], p[i, 1], p[i, 2] = x, y, z
        if not has_zero or length > tiny:
            qx, qy, qz = dx, dy, dz


@compiled(error_model="numpy")
def _ccd_sweep(
    p: NDArray[np.float64], target: NDArray[np.float64], tiny: float, rest: NDArray[np.float64], dim: int
) -> None:
    """One CCD sweep (Wang & Chen 1991): each joint, end to root, turns what lies beyond it about
    ``to_end × to_target`` (Rodrigues' formula) so that the end points at the target."""
    n = p.shape[0] - 1
    for i in range(n - 1, -1, -1):
        ox, oy, oz = p[i, 0], p[i, 1], p[i, 2]
        ex, ey, ez, end_norm = _unit(p[n, 0] - ox, p[n, 1] - oy, p[n, 2] - oz, rest[0], rest[1], rest[2], tiny)
        tx, ty, tz, target_norm = _unit(target[0] - ox, target[1] - oy, target[2] - oz, ex, ey, ez, tiny)
        if not (end_norm > tiny and target_norm > tiny):
            continue
        cos_a = min(max(ex * tx + ey * ty + ez * tz, -1.0), 1.0)
        kx, ky, kz = ey * tz - ez * ty, ez * tx - ex * tz, ex * ty - ey * tx
        sin_a = math.sqrt(kx * kx + ky * ky + kz * kz)
        # (In the plane the axis is ±z; end and target antiparallel turn about z, or in 3D any perpendicular.)
        kx, ky, kz, _ = _unit(kx, ky, kz, 0.0, 0.0, 1.0, 1e-12)
        if sin_a <= 1e-12 and dim == 3:
            kx, ky, kz = _perpendicular(ex, ey, ez, dim)
        for j in range(i + 1, n + 1):
            # Rodrigues: v cos a + (k × v) sin a + k (k·v)(1 − cos a)
            vx, vy, vz = p[j, 0] - ox, p[j, 1] - oy, p[j, 2] - oz
            dot = (kx * vx + ky * vy + kz * vz) * (1.0 - cos_a)
            p[j, 0] = ox + vx * cos_a + (ky * vz - kz * vy) * sin_a + kx * dot
            p[j, 1] = oy + vy * cos_a + (kz * vx - kx * vz) * sin_a + ky * dot
            p[j, 2] = oz + vz * cos_a + (kx * vy - ky * vx) * sin_a + kz * dot


@compiled(error_model="numpy")
def _dls_step(
    p: NDArray[np.float64],
    target: NDArray[np.float64],
    lengths: NDArray[np.float64],
    tiny: float,
    turns: NDArray[np.float64],
) -> None:
    """One damped-least-squares step on joint angles (Wampler 1986; Buss 2004): ``Δθ = Jᵀ(JJᵀ + λ²I)⁻¹e``.

    Ball joints: ``J_i = −[l_i]×`` with ``l_i = p_n − p_i``, so ``JJᵀ = Σ |l_i|²I − l_i l_iᵀ`` and
    ``Δθ_i = l_i × y`` for ``y = (JJᵀ + λ²I)⁻¹e``. In the plane (z = 0) every ``Δθ_i`` is along z and the step is the
    planar one of hinges, ``J_i = perp(l_i)``. The error is clamped to the mean link length and
    ``λ = 0.1 × mean link length`` (Buss 2004). Segment j turns by ``R(Δθ_0) … R(Δθ_j)``, the rotations of the
    joints' rotation vectors (in the plane: by their summed angle). ``turns`` is (n + 1, 3) scratch.
    """
    n = lengths.shape[0]
    endx, endy, endz = p[n, 0], p[n, 1], p[n, 2]
    total = 0.0  # a loop: np.sum compiles an overload of its own (and adds in this order too)
    for i in range(n):
        total += lengths[i]
    cap = max(total / n, tiny)
    ex, ey, ez = target[0] - endx, target[1] - endy, target[2] - endz
    shrink = min(1.0, cap / max(math.sqrt(ex * ex + ey * ey + ez * ez), tiny))
    ex, ey, ez = ex * shrink, ey * shrink, ez * shrink
    # JJᵀ + λ²I, symmetric: a00 a01 a02 / a11 a12 / a22
    a00 = a11 = a22 = (_DLS_DAMPING * cap) ** 2
    a01 = a02 = a12 = 0.0
    for i in range(n):
        lx, ly, lz = endx - p[i, 0], endy - p[i, 1], endz - p[i, 2]
        l2 = lx * lx + ly * ly + lz * lz
        a00, a11, a22 = a00 + l2 - lx * lx, a11 + l2 - ly * ly, a22 + l2 - lz * lz
        a01, a02, a12 = a01 - lx * ly, a02 - lx * lz, a12 - ly * lz
    # Cramer's rule on the symmetric positive-definite 3 × 3 matrix
    c00, c01, c02 = a11 * a22 - a12 * a12, a02 * a12 - a01 * a22, a01 * a12 - a02 * a11
    c11, c12, c22 = a00 * a22 - a02 * a02, a01 * a02 - a00 * a12, a00 * a11 - a01 * a01
    det = a00 * c00 + a01 * c01 + a02 * c02
    yx = (c00 * ex + c01 * ey + c02 * ez) / det
    yy = (c01 * ex + c11 * ey + c12 * ez) / det
    yz = (c02 * ex + c12 * ey + c22 * ez) / det
    for i in range(n):  # Δθ_i = J_iᵀ y = l_i × y
        lx, ly, lz = endx - p[i, 0], endy - p[i, 1], endz - p[i, 2]
        turns[i, 0], turns[i, 1], turns[i, 2] = (ly * yz - lz * yy, lz * yx - lx * yz, lx * yy - ly * yx)
    # Turn every segment by the joints up to it and re-chain from the root: ``turn`` (t00 … t22, row by row) is
    # the product of the joints' rotations so far, on scalars (3 × 3 arrays compiled for seconds more).
    t00, t01, t02, t10, t11, t12, t20, t21, t22 = 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0
    ox, oy, oz = p[0, 0], p[0, 1], p[0, 2]
    for i in range(n):
        sx, sy, sz = p[i + 1, 0] - ox, p[i + 1, 1] - oy, p[i + 1, 2] - oz
        ox, oy, oz = p[i + 1, 0], p[i + 1, 1], p[i + 1, 2]
        wx, wy, wz = turns[i, 0], turns[i, 1], turns[i, 2]
        theta = math.sqrt(wx**2 + wy**2 + wz**2)
        if theta > 1e-15:
            kx, ky, kz = wx / theta, wy / theta, wz / theta
            s, c = math.sin(theta), math.cos(theta)
            # Rodrigues: R = cos θ I + sin θ [k]× + (1 − cos θ) k kᵀ, with k kᵀ as w wᵀ / θ²
            theta2, versine = theta * theta, 1.0 - c
            r00, r11, r22 = (
                versine * wx * wx / theta2 + c,
                versine * wy * wy / theta2 + c,
                versine * wz * wz / theta2 + c,
            )
            r01, r02, r12 = (
                versine * wx * wy / theta2 - s * kz,
                versine * wx * wz / theta2 + s * ky,
                versine * wy * wz / theta2 - s * kx,
            )
            r10, r20, r21 = (
                versine * wy * wx / theta2 + s * kz,
                versine * wz * wx / theta2 - s * ky,
                versine * wz * wy / theta2 + s * kx,
            )
            t00, t01, t02, t10, t11, t12, t20, t21, t22 = (
                t00 * r00 + t01 * r10 + t02 * r20,
                t00 * r01 + t01 * r11 + t02 * r21,
                t00 * r02 + t01 * r12 + t02 * r22,
                t10 * r00 + t11 * r10 + t12 * r20,
                t10 * r01 + t11 * r11 + t12 * r21,
                t10 * r02 + t11 * r12 + t12 * r22,
                t20 * r00 + t21 * r10 + t22 * r20,
                t20 * r01 + t21 * r11 + t22 * r21,
                t20 * r02 + t21 * r12 + t22 * r22,
            )
        p[i + 1, 0] = p[i, 0] + t00 * sx + t01 * sy + t02 * sz
        p[i + 1, 1] = p[i, 1] + t10 * sx + t11 * sy + t12 * sz
        p[i + 1, 2] = p[i, 2] + t20 * sx + t21 * sy + t22 * sz


@compiled(error_model="numpy")
def _colliding(p: NDArray[np.float64], obstacles: Obstacles, inflate: float) -> bool:
    """Whether any segment passes within ``inflate`` × radius of a live obstacle's centre."""
    for i in range(p.shape[0] - 1):
        if _segment_cuts(p, i, i + 1, obstacles, inflate):
            return True
    return False


@compiled(error_model="numpy")
def _admissible(
    p: NDArray[np.float64],
    tiny: float,
    rest: NDArray[np.float64],
    has_limits: bool,
    table: NDArray[np.float64],
    obstacles: Obstacles,
) -> bool:
    """Whether the pose keeps every joint's cone or hinge (zero-length segments have none and are skipped) and cuts
    no live obstacle."""
    if has_limits:
        qx, qy, qz = rest[0], rest[1], rest[2]
        for i in range(p.shape[0] - 1):
            dx, dy, dz, norm = _unit(
                p[i + 1, 0] - p[i, 0], p[i + 1, 1] - p[i, 1], p[i + 1, 2] - p[i, 2], qx, qy, qz, tiny
            )
            if norm <= tiny:
                continue
            if not _joint_ok(dx, dy, dz, qx, qy, qz, table, i, rest, tiny):
                return False
            qx, qy, qz = dx, dy, dz
    return not _colliding(p, obstacles, 1.0)


@compiled(error_model="numpy")
def _copy(source: NDArray[np.float64], destination: NDArray[np.float64]) -> None:
    for i in range(source.shape[0]):
        destination[i, 0], destination[i, 1], destination[i, 2] = (source[i, 0], source[i, 1], source[i, 2])


@compiled(error_model="numpy")
def _end_error(p: NDArray[np.float64], target: NDArray[np.float64]) -> float:
    n = p.shape[0] - 1
    x, y, z = p[n, 0] - target[0], p[n, 1] - target[1], p[n, 2] - target[2]
    return math.sqrt(x * x + y * y + z * z)


@compiled(error_model="numpy")
def _place_on_line(
    pose: NDArray[np.float64],
    root: NDArray[np.float64],
    lengths: NDArray[np.float64],
    ux: float,
    uy: float,
    uz: float,
    fold: bool,
) -> None:
    """The chain along the unit direction u from the root: straight, or (``fold``) with its longest link toward u
    and the others folded back, so the end rests on the inner boundary of the reach."""
    longest = 0  # the first longest link (np.argmax compiles an overload of its own)
    for i in range(1, lengths.shape[0]):
        if lengths[i] > lengths[longest]:
            longest = i
    reach = 0.0
    pose[0, 0], pose[0, 1], pose[0, 2] = root[0], root[1], root[2]
    for i in range(lengths.shape[0]):
        reach += lengths[i] if not fold or i == longest else -lengths[i]
        pose[i + 1, 0], pose[i + 1, 1], pose[i + 1, 2] = (
            root[0] + reach * ux,
            root[1] + reach * uy,
            root[2] + reach * uz,
        )


@compiled(error_model="numpy")
def _unbend(
    p: NDArray[np.float64],
    target: NDArray[np.float64],
    lengths: NDArray[np.float64],
    tiny: float,
    rest: NDArray[np.float64],
    limits: tuple[bool, NDArray[np.float64]],
    cos_phi: float,
    dim: int,
) -> None:
    """Bend a straight chain whose target lies on its own line into a gentle arc centred on that line, so the
    passes can bend it (every interior joint leaves the line; an arc starting along it would leave p_1 on it).

    Each joint bends by the same step, at most half the tightest cone, and a hinge about the arc's normal toward
    the inside of its range (:func:`~kernels.fabrik.limits._bend_within`): a bend past a one-sided range's end,
    or any bend of a zero range, would be clamped straight again, leaving the chain rotated off its line."""
    has_limits, table = limits
    n = p.shape[0] - 1
    ax, ay, az = rest[0], rest[1], rest[2]
    for i in range(n):  # the axis: the first segment with a direction
        dx, dy, dz = p[i + 1, 0] - p[i, 0], p[i + 1, 1] - p[i, 1], p[i + 1, 2] - p[i, 2]
        ux, uy, uz, norm = _unit(dx, dy, dz, ax, ay, az, tiny)
        if norm > tiny:
            ax, ay, az = ux, uy, uz
            break
    for i in range(n):
        dx, dy, dz = p[i + 1, 0] - p[i, 0], p[i + 1, 1] - p[i, 1], p[i + 1, 2] - p[i, 2]
        along = dx * ax + dy * ay + dz * az
        ox, oy, oz = dx - along * ax, dy - along * ay, dz - along * az
        if math.sqrt(ox * ox + oy * oy + oz * oz) > 1e-9 * max(lengths[i], tiny):
            return  # not straight
    tx, ty, tz = target[0] - p[0, 0], target[1] - p[0, 1], target[2] - p[0, 2]
    along = tx * ax + ty * ay + tz * az
    ox, oy, oz = tx - along * ax, ty - along * ay, tz - along * az
    distance = math.sqrt(tx * tx + ty * ty + tz * tz)
    if math.sqrt(ox * ox + oy * oy + oz * oz) > 1e-9 * max(distance, tiny):
        return  # the target is off the chain's line: the passes bend it
    step = 0.1 if not has_limits else min(0.1, 0.5 * math.acos(cos_phi))
    if step <= 0.0:
        return
    sx, sy, sz = _perpendicular(ax, ay, az, dim)
    nx, ny, nz = ay * sz - az * sy, az * sx - ax * sz, ax * sy - ay * sx
    # The arc turns by each joint's bend; centred, its first and last segments straddle the line.
    turn, bent = 0.0, False
    for i in range(1, n):
        bend = step if not has_limits else _bend_within(table, i, ax, ay, az, nx, ny, nz, rest, step)
        bent = bent or bend != 0.0
        turn += bend
    if not bent:
        return
    angle = -0.5 * turn
    for i in range(n):
        if i > 0:
            angle += step if not has_limits else _bend_within(table, i, ax, ay, az, nx, ny, nz, rest, step)
        c, s = math.cos(angle) * lengths[i], math.sin(angle) * lengths[i]
        p[i + 1, 0] = p[i, 0] + c * ax + s * sx
        p[i + 1, 1] = p[i, 1] + c * ay + s * sy
        p[i + 1, 2] = p[i, 2] + c * az + s * sz


@compiled(error_model="numpy")
def _extrapolate(
    p: NDArray[np.float64], previous: NDArray[np.float64], error: float, previous_error: float, allowed: bool
) -> bool:
    """Move the joints on along their last step, in place, by the rest of a geometric series; ``previous`` (the
    pose before the last step) becomes the pose before this move.

    Where the end-effector error shrank by a ratio ``r`` in [0.5, 1) in the last iteration, FABRIK converges
    linearly at about that ratio, and the steps still to come sum to ``r / (1 − r)`` times the last one (Aitken's
    Δ² extrapolation of a linearly converging sequence), capped at 8 steps. Only the next passes' starting guess
    moves: they still place every joint at its link's length, inside its cone and clear of obstacles. Nothing moves
    unless ``allowed``. Returns whether it moved the joints.
    """
    ratio = error / previous_error if previous_error > 0.0 else 0.0  # scale-free: no absolute floor
    slow = allowed and _EXTRAPOLATION_MIN_RATIO <= ratio < 1.0
    if not slow:  # (``previous`` is not yet set on the first call: only copy into it)
        _copy(p, previous)
        return False
    weight = ratio / max(1.0 - ratio, ratio / _EXTRAPOLATION_CAP)
    for i in range(p.shape[0]):
        for c in range(3):
            now = p[i, c]
            p[i, c] = now + weight * (now - previous[i, c])
            previous[i, c] = now
    return True


@compiled(error_model="numpy")
def _admissible_start(
    p: NDArray[np.float64],
    lengths: NDArray[np.float64],
    tiny: float,
    rest: NDArray[np.float64],
    table: NDArray[np.float64],
    has_zero: bool,
    start: int,
    dim: int,
) -> None:
    """Rebuild ``p`` from its root as the ``start``-th admissible pose: every joint at an angle inside its limit
    (:func:`~kernels.fabrik.limits._inside_limit`), the fractions taken from additive recurrences over the start
    and the joint, kept off a range's ends (a one-sided range's end is often a fixed point). Starts come in
    mirrored pairs (fractions u and 1 − u: each joint's angle reflected within its range), so a chain and its
    mirror image try the same poses, mirrored."""
    pair = (start + 1) // 2
    qx, qy, qz = rest[0], rest[1], rest[2]
    for i in range(lengths.shape[0]):
        u = 0.1 + 0.8 * ((0.5 + pair * _GOLDEN[0] + i * _GOLDEN[1]) % 1.0)
        if start % 2 == 0:
            u = 1.0 - u
        v = (pair * _GOLDEN[2] + i * _GOLDEN[1]) % 1.0
        dx, dy, dz = _inside_limit(qx, qy, qz, table, i, rest, u, v, dim)
        length = lengths[i]
        p[i + 1, 0], p[i + 1, 1], p[i + 1, 2] = (p[i, 0] + length * dx, p[i, 1] + length * dy, p[i, 2] + length * dz)
        if not has_zero or length > tiny:
            qx, qy, qz = dx, dy, dz


@compiled(error_model="numpy")
def _polish(
    p: NDArray[np.float64],
    best: NDArray[np.float64],
    best_error: float,
    target: NDArray[np.float64],
    tolerance: float,
    budget: int,
    lengths: NDArray[np.float64],
    tiny: float,
    rest: NDArray[np.float64],
    limits: tuple[bool, NDArray[np.float64]],
    obstacles: Obstacles,
    has_zero: bool,
    dim: int,
    turns: NDArray[np.float64],
) -> float:
    """Damped least squares (:func:`_dls_step`, each iterate projected by the constrained backward pass) from the
    best pose, then from admissible poses (:func:`_admissible_start`), once FABRIK under hinges stalls or creeps
    short of a reachable target. FABRIK's fixed points under one-sided or narrow hinge ranges are many (a joint resting
    at a range's end, a near-rigid chain pulled along a line), and its outcome there depended on which side a tie fell
    (a chain and its mirror image missed 1 % and 24 % of reachable targets); joint-space steps from a few
    admissible starts leave those basins. Each start runs up to ``budget`` steps and stops once its error has not
    improved by :data:`_PROGRESS` of the tolerance in :data:`_PATIENCE` steps; the first iterate within the
    tolerance ends it. Updates ``best`` (n + 1, 3) in place and returns its error; ``p`` and ``turns`` (n + 1, 3)
    are scratch."""
    has_limits, table = limits
    progress = _PROGRESS * tolerance + tiny
    for start in range(_POLISH_STARTS):
        if start == 0:
            _copy(best, p)
        else:
            _admissible_start(p, lengths, tiny, rest, table, has_zero, start, dim)
        # Iteration 0 is the start itself (projected, unless it is the best pose), then the steps from it.
        mark_iteration, mark_error = 0, 0.0
        for iteration in range(budget + 1):
            if iteration > 0:
                _dls_step(p, target, lengths, tiny, turns)
            if iteration > 0 or start > 0:
                _backward_pass(p, lengths, tiny, rest, limits, obstacles, has_zero, dim)
            error = _end_error(p, target)
            if error < best_error and _admissible(p, tiny, rest, has_limits, table, obstacles):
                _copy(p, best)
                best_error = error
                if error <= tolerance:
                    return best_error
            if iteration == 0 or error < mark_error - progress:
                mark_iteration, mark_error = iteration, error
            elif iteration - mark_iteration >= _PATIENCE:
                break
    return best_error


@compiled(error_model="numpy")
def _solve_chain(
    p: NDArray[np.float64],
    target: NDArray[np.float64],
    tolerance: float,
    params: NDArray[np.float64],
    flags: NDArray[np.int64],
    rest: NDArray[np.float64],
    centres: NDArray[np.float64],
    radii: NDArray[np.float64],
    lengths: NDArray[np.float64],
    live: NDArray[np.bool_],
    best: NDArray[np.float64],
    previous: NDArray[np.float64],
    before: NDArray[np.float64],
    out_p: NDArray[np.float64],
    history: NDArray[np.float64],
    table: NDArray[np.float64],
) -> tuple[int, int, float]:
    """Solve one chain, starting from ``p`` (n + 1, 3), which it works on in place.

    Writes the returned pose to ``out_p`` and the iterates' errors to ``history`` (max_iterations + 1,), which it
    leaves NaN past the last iteration; ``lengths`` (n,), ``live`` (K,), ``best``, ``previous`` and ``before``
    (n + 1, 3) are scratch. Returns (iterations, status, error of the returned pose).
    """
    cos_phi = params[1]  # the tolerance comes on its own, in the units the chain is solved in
    max_iterations, dim, solver = flags[0], flags[1], flags[2]
    extrapolate = flags[3] != 0 and solver == _FABRIK
    has_limits = flags[4] != 0
    limits = (has_limits, table)
    n = p.shape[0] - 1
    for k in range(history.shape[0]):  # a loop: a slice assignment compiles an overload of its own
        history[k] = np.nan

    total = 0.0
    for i in range(n):
        dx, dy, dz = p[i + 1, 0] - p[i, 0], p[i + 1, 1] - p[i, 1], p[i + 1, 2] - p[i, 2]
        lengths[i] = math.sqrt(dx * dx + dy * dy + dz * dz)
        total += lengths[i]
    ox, oy, oz = target[0] - p[0, 0], target[1] - p[0, 1], target[2] - p[0, 2]
    distance = math.sqrt(ox * ox + oy * oy + oz * oz)
    # relative only: the core gives the same bits at any power-of-2 scale
    tiny = _TINY * max(total, distance)
    shortest, longest = lengths[0], lengths[0]  # a loop: np.min and np.max compile overloads of their own
    for i in range(1, lengths.shape[0]):
        shortest, longest = min(shortest, lengths[i]), max(longest, lengths[i])
    has_zero = bool(shortest <= tiny)  # a bool, never the literal False (which compiled every pass twice)
    inner = max(0.0, 2.0 * longest - total)
    beyond = distance > total + tiny
    fold = distance < inner - tiny
    out_of_reach = beyond or fold
    # Within tolerance of the inner radius the folded pose is as good a candidate as the straight one at full reach.
    near_inner = inner > 0.0 and distance <= inner + tolerance + tiny
    fold = fold or (near_inner and distance - inner < total - distance)
    any_live = _mark_live(centres, radii, live, p[0, 0], p[0, 1], p[0, 2])
    obstacles = (centres, radii, live)
    constrained = (has_limits and flags[5] != 0) or any_live

    error = _end_error(p, target)
    history[0] = error
    _copy(p, best)
    best_error = np.inf
    if _admissible(p, tiny, rest, has_limits, table, obstacles):
        best_error = error
        if error <= tolerance:
            _copy(p, out_p)
            return 0, _REACHED, error

    if solver == _FABRIK and (out_of_reach or near_inner or distance >= total - tolerance - tiny):
        # The closest pose to a target out of reach; the straight pose toward one within tolerance of full reach.
        ux, uy, uz, _ = _unit(ox, oy, oz, rest[0], rest[1], rest[2], tiny)
        _place_on_line(before, p[0], lengths, ux, uy, uz, fold)
        candidate = _end_error(before, target)
        # "reached" means error ≤ tolerance, with no slack: a candidate short of it by rounding iterates on.
        if _admissible(before, tiny, rest, has_limits, table, obstacles):
            if candidate <= tolerance or out_of_reach:
                _copy(before, out_p)
                history[1] = candidate
                return 1, _REACHED if candidate <= tolerance else _UNREACHABLE, candidate

    _unbend(p, target, lengths, tiny, rest, limits, cos_phi, dim)
    # DLS steps toward ``aim``: for a free chain and a target out of reach, the nearest point of the reach annulus
    # (the target clamped to the workspace). Stepped toward the target itself, the clamped error's component that no
    # pose can remove spun the near-straight chain back and forth: 94 % of such solves stopped bent, 13 mm (median)
    # worse than the straight pose. It converges as slowly as DLS does at a singular pose, and its error can stand
    # still for an iteration as the chain swings round: it stops only within the tolerance of ``aim``, or at the cap.
    aim = np.empty(3)
    aimed = solver == _DLS and out_of_reach and not constrained
    if aimed:
        ux, uy, uz, _ = _unit(ox, oy, oz, rest[0], rest[1], rest[2], tiny)
        radius = total if beyond else inner
        aim[0], aim[1], aim[2] = p[0, 0] + radius * ux, p[0, 1] + radius * uy, p[0, 2] + radius * uz
    else:
        aim[0], aim[1], aim[2] = target[0], target[1], target[2]
    # The extrapolation's first call moves by 0 × (p − previous): never 0 × uninitialised memory (NaN).
    _copy(p, previous)
    stall = _STALL * tolerance + tiny
    progress = _PROGRESS * tolerance + tiny
    stall_applies = constrained or out_of_reach
    trusted, moved, reached, stalled = True, False, False, False
    count, mark_iteration, mark_error = 0, 0, best_error
    # Extrapolated FABRIK under limits, within reach, restarts once where it stalls (see below) at ``restart``
    retry, restart = extrapolate and (has_limits or any_live) and not out_of_reach, 0
    # ... and under hinges, or beside obstacles with no limits (FABRIK's turn past an obstacle has fixed points of
    # its own: 5 of 1,485 random targets that CCD or DLS reached clear), polishes once where it stalls after that
    # or creeps (see _polish), at ``creep_iteration``
    polish = retry and (_holding_hinge(table) or (any_live and not has_limits))
    creep_iteration, creep_error, creeping = 0, best_error, False
    for iteration in range(1, max_iterations + 1):
        count = iteration
        last_error = history[iteration - 1]
        if extrapolate and iteration >= restart + 2:  # from the third iteration on, and while trusted
            allowed = iteration >= restart + 3 and trusted
            moved = _extrapolate(p, previous, last_error, history[iteration - 2], allowed)
        if solver != _DLS:
            # A pass can fold the chain onto the target's line (a target on the line of the first link): a fixed
            # point of both FABRIK and CCD, which no longer bend it. Bent off the line, the passes go on.
            _unbend(p, target, lengths, tiny, rest, limits, cos_phi, dim)
        if solver == _FABRIK:
            _forward_pass(p, target, lengths, tiny, rest, limits, obstacles, has_zero, dim)
        elif solver == _CCD:
            _ccd_sweep(p, target, tiny, rest, dim)
        else:
            _dls_step(p, aim, lengths, tiny, before)
        _backward_pass(p, lengths, tiny, rest, limits, obstacles, has_zero, dim)
        error = _end_error(p, target)
        history[iteration] = error
        # A chain whose extrapolation made its error grow (a target the limits keep away, r → 1) is left to plain
        # FABRIK from then on, which settles at its fixed point.
        trusted = trusted and not (moved and error > last_error)
        if (error < best_error or error <= tolerance) and (
            not constrained or _admissible(p, tiny, rest, has_limits, table, obstacles)
        ):
            if error < best_error:
                _copy(p, best)
                best_error = error
            reached = error <= tolerance
        if best_error < mark_error - progress:
            mark_iteration, mark_error = iteration, best_error
        if aimed:  # the closest pose within the tolerance: nothing nearer to come
            stalled = _end_error(p, aim) <= tolerance
        else:
            stalled = stall_applies and (abs(last_error - error) < stall or iteration - mark_iteration >= _PATIENCE)
        if polish and not reached and iteration - creep_iteration >= _PATIENCE:
            creeping = best_error > _CREEP * creep_error
            creep_iteration, creep_error = iteration, best_error
        if (stalled or creeping) and not reached and retry:
            # A stall under limits is a fixed point of this start, not proof that the limits keep the target
            # away: go on once from the straight pose toward the target, clamped into the cones (another basin).
            # A creep (see _CREEP) restarts too, before any polish: an iterate that circles the optimum closes in by
            # less than _PROGRESS some iterations and more in others, and never stalls.
            retry, stalled, creeping, restart, trusted, mark_iteration = False, False, False, iteration, True, iteration
            ux, uy, uz, _ = _unit(ox, oy, oz, rest[0], rest[1], rest[2], tiny)
            _place_on_line(p, best[0], lengths, ux, uy, uz, bool(_OFF))
            _unbend(p, target, lengths, tiny, rest, limits, cos_phi, dim)  # a straight chain never bends
            _backward_pass(p, lengths, tiny, rest, limits, obstacles, has_zero, dim)
            # The restart pose is a candidate too: where the limits leave the chain nearly rigid, the passes from
            # it may move away from the best pose it already is.
            error = _end_error(p, target)
            if error < best_error and _admissible(p, tiny, rest, has_limits, table, obstacles):
                _copy(p, best)
                best_error = error
                reached = error <= tolerance
                if reached:
                    break
            continue
        if polish and not reached:
            if (stalled and not retry) or creeping:
                # Decided by the iterates alone, which a longer run repeats: more iterations are never worse.
                polish = False
                best_error = _polish(
                    out_p,
                    best,
                    best_error,
                    target,
                    tolerance,
                    int(_POLISH_STEPS),  # an int, not the literal 50: one compiled _polish
                    lengths,
                    tiny,
                    rest,
                    limits,
                    obstacles,
                    has_zero,
                    dim,
                    before,
                )
                if best_error <= tolerance:
                    reached = True
                    _copy(best, p)
        if reached or stalled:
            break

    if reached or best_error == np.inf:  # reached: this iterate is the best; none admissible: the last
        _copy(p, out_p)
    else:
        _copy(best, out_p)
    final_error = _end_error(out_p, target)
    if reached:
        return count, _REACHED, final_error
    # neither the start nor any iterate kept every limit and cleared every obstacle
    if best_error == np.inf:
        return count, _INFEASIBLE, final_error
    if out_of_reach:
        # A free chain's closest pose is known (straight, or folded in the hole): one left farther than the tolerance
        # from it by the cap is still converging (CCD and DLS close in slowly; DLS stopped 0.29 m short in 50).
        closest = distance - total if beyond else inner - distance
        if not constrained and not stalled and count == max_iterations and final_error > closest + tolerance:
            return count, _MAX_ITERATIONS, final_error
        return count, _UNREACHABLE, final_error
    if any_live and (
        _inside_live(obstacles, target[0], target[1], target[2]) or _colliding(out_p, obstacles, 1.0 + _TOUCH)
    ):
        return count, _BLOCKED, final_error
    return count, _LIMITED if stalled else _MAX_ITERATIONS, final_error


@compiled(from_python=True, error_model="numpy", nogil=True)
def _solve_rows(
    lo: int,
    hi: int,
    p: NDArray[np.float64],
    target: NDArray[np.float64],
    params: NDArray[np.float64],
    flags: NDArray[np.int64],
    rest: NDArray[np.float64],
    centres: NDArray[np.float64],
    radii: NDArray[np.float64],
    out_p: NDArray[np.float64],
    history: NDArray[np.float64],
    iterations: NDArray[np.int64],
    status: NDArray[np.int64],
    error: NDArray[np.float64],
    table: NDArray[np.float64],
) -> None:
    """Solve rows ``lo`` to ``hi`` of a batch (p (B, n + 1, 3), target (B, 3)) with one set of scratch arrays, each
    about its own root (:func:`_about_root`: ``p``, ``target`` and a row's obstacles are moved there, the result back).
    """
    count = p.shape[1]
    lengths = np.empty(count - 1)
    live = np.empty(radii.shape[0], dtype=np.bool_)
    best, previous, before = np.empty((count, 3)), np.empty((count, 3)), np.empty((count, 3))
    local, root = np.empty((radii.shape[0], 3)), np.empty(3)
    for b in range(lo, hi):
        _about_root(p[b], target[b], centres, local, root)
        iterations[b], status[b], error[b] = _solve_chain(
            p[b],
            target[b],
            params[0],
            params,
            flags,
            rest,
            local,
            radii,
            lengths,
            live,
            best,
            previous,
            before,
            out_p[b],
            history[b],
            table,
        )
        for i in range(count):
            for c in range(3):
                out_p[b, i, c] += root[c]


@compiled(error_model="numpy")
def _about_root(
    p: NDArray[np.float64],
    target: NDArray[np.float64],
    centres: NDArray[np.float64],
    local: NDArray[np.float64],
    root: NDArray[np.float64],
) -> None:
    """Move the chain ``p`` (n + 1, 3) and its ``target`` (3,), in place, and the obstacles' ``centres`` (K, 3), into
    ``local``, so that the root is at the origin; its old place into ``root``.

    The core's tests are relative to the chain's size, but a coordinate far from the origin rounds to a share of its
    own size: a 3 cm chain 1100 m out left its cones by 1e-12 in cos to rounding, and the solve returned its start
    (0.039 m off where an iterate was 0.0037 m off). About its root the rounding is the chain's own."""
    for c in range(3):
        root[c] = p[0, c]
    for i in range(p.shape[0]):
        for c in range(3):
            p[i, c] -= root[c]
    for c in range(3):
        target[c] -= root[c]
    for k in range(centres.shape[0]):
        for c in range(3):
            local[k, c] = centres[k, c] - root[c]


_UNSCALED = 2.0**-16, 2.0**16
"""Extents (m) solved as they are; outside, a problem is divided by a power of 2 near its extent first."""
_BAD_JOINTS, _BAD_TARGET, _FAR_TARGET = 1, 2, 3
"""What :func:`_solve_one` found wrong with its input (0: nothing); the caller raises the error that names it."""
_FARTHEST = 1e12
"""Most times its chain's length (ΣL > 0) that a target may lie from the root. Beyond it the links are smaller
than the rounding of the problem's scale: FABRIK collapsed a chain to its root (a target 1e200 m from a 0.5 m
chain), CCD and DLS stopped turning it, and in a batch one such row rescaled every other row. Also the most times
its chain's length that a chain may lie from the origin (1e15 m out, rounding changed a 0.5 m link by 8 %)."""
_SPAN = 1e40
"""Most times one chain of a batch may be larger than another (targets included): the batch is solved in units of
a power of 2 near its largest, and DLS lost a chain 1e60 times smaller (its 3 × 3 determinant underflows)."""


@compiled(error_model="numpy")
def _within(values: NDArray[np.float64], bound: float) -> bool:
    """Whether every value is finite and of magnitude ≤ ``bound`` (NaN fails)."""
    for value in values.flat:
        if not abs(value) <= bound:
            return False
    return True


@compiled(error_model="numpy")
def _norm_of_difference(a: NDArray[np.float64], b: NDArray[np.float64], dim: int) -> float:
    """|a − b| over the first ``dim`` components, scaled by its largest component first so that no square
    overflows or underflows (a 0.25 m link beside a target 1e200 m away)."""
    largest = 0.0
    for c in range(dim):
        largest = max(largest, abs(a[c] - b[c]))
    if largest == 0.0:
        return 0.0
    sum_sq = 0.0
    for c in range(dim):
        sum_sq += ((a[c] - b[c]) / largest) ** 2
    return largest * math.sqrt(sum_sq)


@compiled(from_python=True, error_model="numpy")
def _solve_one(
    joints: NDArray[np.float64],
    target: NDArray[np.float64],
    bound: float,
    params: NDArray[np.float64],
    flags: NDArray[np.int64],
    rest: NDArray[np.float64],
    centres: NDArray[np.float64],
    radii: NDArray[np.float64],
    table: NDArray[np.float64],
) -> tuple[int, NDArray[np.float64], NDArray[np.float64], int, int, float]:
    """One chain from shape-checked ``joints`` (n + 1, d) and ``target`` (d,), d = 2 or 3 (m): the whole single
    solve in one compiled call, so a small chain spends little time outside the core.

    Scans the input (finite, magnitude ≤ ``bound``), pads it to 3D, divides it by a power of 2 near its extent
    where that lies outside :data:`_UNSCALED` (exact; see ``api._to_unit_scale``, the batch's same rule), solves it
    with :func:`_solve_chain` and scales back. Returns (input code: 0, :data:`_BAD_JOINTS` or :data:`_BAD_TARGET`;
    joints (n + 1, d); error history (iterations + 1,); iterations; status; error); on a bad input the rest is empty.
    """
    count, dim = joints.shape[0], joints.shape[1]
    if not _within(joints, bound):
        return _BAD_JOINTS, np.empty((0, dim)), np.empty(0), 0, 0, 0.0
    if not _within(target.reshape((1, dim)), bound):  # as a 2D array, like the joints: one compiled _within
        return _BAD_TARGET, np.empty((0, dim)), np.empty(0), 0, 0, 0.0
    extent, origin = 0.0, 0.0
    for c in range(dim):
        for i in range(count):
            extent = max(extent, abs(joints[i, c] - joints[0, c]))
            origin = max(origin, abs(joints[i, c]))
        extent = max(extent, abs(target[c] - joints[0, c]))
        origin = max(origin, abs(target[c]))
    if extent > 0.0:  # the target within _FARTHEST chain lengths, the chain within them of the origin
        total = 0.0
        for i in range(1, count):
            total += _norm_of_difference(joints[i], joints[i - 1], dim)
        reach = _norm_of_difference(target, joints[0], dim)  # one signature: rows and the target are (d,)
        if total > 0.0 and (reach / _FARTHEST > total or origin / _FARTHEST > total):
            return _FAR_TARGET, np.empty((0, dim)), np.empty(0), 0, 0, 0.0
    scale = 1.0
    if extent != 0.0 and not _UNSCALED[0] <= extent <= _UNSCALED[1]:
        scale = math.ldexp(1.0, math.frexp(extent)[1])  # ≥ extent, exact; division by it is exact
    # Padded to 3D, moved about the root (see _about_root) and divided by the scale (by 1.0: the same bits) in loops:
    # array arithmetic compiles a ufunc loop for each expression.
    p, goal = np.zeros((count, 3)), np.zeros(3)
    for c in range(dim):
        for i in range(count):
            p[i, c] = (joints[i, c] - joints[0, c]) / scale
        goal[c] = (target[c] - joints[0, c]) / scale
    if radii.shape[0] > 0:
        moved_centres, moved_radii = np.empty((radii.shape[0], 3)), np.empty(radii.shape[0])
        for k in range(radii.shape[0]):
            moved_radii[k] = radii[k] / scale
            for c in range(3):
                moved_centres[k, c] = (centres[k, c] - (joints[0, c] if c < dim else 0.0)) / scale
        centres, radii = moved_centres, moved_radii
    history = np.empty(flags[0] + 1)
    out_p = np.empty((count, 3))
    lengths = np.empty(count - 1)
    live = np.empty(radii.shape[0], dtype=np.bool_)
    best, previous, before = np.empty((count, 3)), np.empty((count, 3)), np.empty((count, 3))
    tol = params[0] / scale
    iterations, status, error = _solve_chain(
        p, goal, tol, params, flags, rest, centres, radii, lengths, live, best, previous, before, out_p, history, table
    )
    # A start returned as it stands (no iteration) is its own coordinates, not their round trip about the root.
    out = np.empty((count, dim))
    for i in range(count):
        for c in range(dim):
            out[i, c] = joints[i, c] if iterations == 0 else out_p[i, c] * scale + joints[0, c]
    history = history[: iterations + 1]
    for k in range(iterations + 1):
        history[k] *= scale
    return 0, out, history, iterations, status, error * scale
