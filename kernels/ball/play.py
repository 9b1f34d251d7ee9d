"""The flight on a pitch, compiled: it bounces, rolls, strikes the posts, the bar, the wall's players and the keeper,
and ends in the net, at rest, off the pitch, in the keeper's hands or at ``t_max``.

One compiled loop, :func:`play`, steps the same force law and RK4/Euler step as the free flight
(:func:`kernels.ball.core._step`) between contacts; each contact is the first one found inside a step (the ground by
the cubic Hermite root of :func:`~kernels.ball.core.crossing_fraction`, a capsule by bisection on the Hermite
interpolant after a swept test of the step's chord, grown by how far the path can stray from it) and applies
:func:`kernels.ball.contact.impact`, Cross's grip–slip impulse (Cross 2002), with the surface's coefficients. The step
then restarts from the contact, so samples are every ``dt`` between contacts, plus one at each contact. Spin is constant
between contacts and changed by each.

Pitch geometry is one (:data:`N_PITCH`,) vector (slots below) built by :func:`kernels.ball.pitch.pitch_vector`:
the goal (posts: vertical capsules of radius r_p on the goal line at ±(w/2 + r_p); bar: a horizontal capsule with
its underside at h), the net (a box 2 m deep behind the line: reaching it stops the ball), the wall's players
(vertical capsules side by side, their tops at the wall's height) and the keeper (a capsule from feet to fingertips
that stands, then, a reaction time after the ball passes the wall, moves toward where it reads the ball will cross
the line). Rolling: once a ground bounce leaves less than :data:`ROLL_SPEED` upward, the ball rolls, held on the
turf, slowed by a constant rolling resistance and the air's drag, until it stops. Sources and numbers:
:mod:`kernels.ball.pitch`.
"""

from __future__ import annotations

import math

import numpy as np

from kernels._jit import compiled
from kernels.ball.aero import (
    AXIS,
    GAIN,
    N_KICK,
    RATE,
    drag_lift_speeds,
    fill_kick,
    force_law,
    max_stable_step,
    sample_forces,
)
from kernels.ball.config import DT, GRAVITY, GROUND, N_STEPS, RADIUS, RK4, T_MAX, X_STOP
from kernels.ball.contact import N_SURFACE, impact
from kernels.ball.core import _energy_limit, _hermite, _step, _write_sample, crossing_fraction

# Slots of the pitch vector.
GX, GY, GNX, GNY, GW, GH, POST_R, NET_DEPTH, TURF, HALF_WIDTH, ROLL_DECEL, ROLL_SPEED = range(12)
TURF_SURFACE, FRAME_SURFACE, BODY_SURFACE = 12, 17, 22  # each N_SURFACE (5) slots: e_n, e_t, μ, R, α
WALL_ON, WX, WY, WNX, WNY, WW, WH, N_PLAYERS, PLAYER_R = range(27, 36)
KEEPER_ON, KX, KY, K_RADIUS, K_COM, K_HANDS, K_FEET, K_REACT, K_PUSH, K_SPEED, K_TURN = range(36, 47)
N_PITCH = 48

MAX_EVENTS = 64
"""Contacts recorded per flight; a flight ends at its 64th, with the ending ``"contacts"`` (only a surface that
returns nearly all the ball's energy, restitution ≳ 0.97, bounces that often in a flight)."""
MAX_CAPSULES = 20
EXTRA_ROWS = 2 * MAX_EVENTS + 2
"""Samples a flight on a pitch may add to ``n_steps + 1``: one at each contact and one partial step after it."""

# Event kinds, ending codes and result codes (their names: kernels.ball.api).
GROUND_HIT, POST, BAR, WALL, KEEPER, NET = range(6)
ENDED_X_STOP, ENDED_T_MAX, DIVERGED, REFUSED, STOPPED, IN_NET, OUT, SAVED, INSIDE, CONTACTS = range(1, 11)
GOAL, WALL_RESULT, OVER, WIDE, SHORT, POST_RESULT, BAR_RESULT, SAVED_RESULT = range(8)
CONTACT_S = 0.009
"""How long a football's contact with a body lasts (s): under 10 ms for a kick's foot, filmed at 5000 Hz (Shinkai
et al. 2009, Med. Sci. Sports Exerc. 41:889). A second body within the ball's compression over it is met in the same
contact (:func:`_also_met`)."""
DIVE_HORIZON_S = 1.5
"""The keeper dives only for a ball that his read puts on his line within this time (s), within his hands' reach of
the goal; until then he stands and reads it again each step (a slow roll or a ball far over the bar draws no dive)."""

# Slots of a flight's (N_INFO,) summary.
I_RESULT, I_WALL, I_GOAL, I_EVENTS, I_DIVE, I_TARGET, I_FIRST = 0, 1, 5, 9, 10, 11, 14
N_INFO = 16


# --------------------------------------------------------------------------------------------- geometry
@compiled()
def _segment_closest(px, py, pz, dx, dy, dz, qx, qy, qz, ex, ey, ez):
    """Closest points of segments P(s) = p + s·d and Q(u) = q + u·e, s, u ∈ [0, 1]: (s, u, squared distance).

    Ericson, Real-Time Collision Detection (2005), §5.1.9.
    """
    rx, ry, rz = px - qx, py - qy, pz - qz
    a = dx * dx + dy * dy + dz * dz
    e2 = ex * ex + ey * ey + ez * ez
    f = ex * rx + ey * ry + ez * rz
    if a <= 1e-30 and e2 <= 1e-30:
        return 0.0, 0.0, rx * rx + ry * ry + rz * rz
    if a <= 1e-30:
        s, u = 0.0, min(max(f / e2, 0.0), 1.0)
    else:
        c = dx * rx + dy * ry + dz * rz
        if e2 <= 1e-30:
            u, s = 0.0, min(max(-c / a, 0.0), 1.0)
        else:
            b = dx * ex + dy * ey + dz * ez
            denom = a * e2 - b * b
            s = min(max((b * f - c * e2) / denom, 0.0), 1.0) if denom > 1e-30 else 0.0
            u = (b * s + f) / e2
            if u < 0.0:
                u, s = 0.0, min(max(-c / a, 0.0), 1.0)
            elif u > 1.0:
                u, s = 1.0, min(max((b - c) / a, 0.0), 1.0)
    wx = px + s * dx - qx - u * ex
    wy = py + s * dy - qy - u * ey
    wz = pz + s * dz - qz - u * ez
    return s, u, wx * wx + wy * wy + wz * wz


@compiled()
def _to_axis(x, y, z, cap):
    """Distance from a point to a capsule's axis segment (``cap``: ax, ay, az, bx, by, bz, …) and the unit vector
    from the axis to the point."""
    ex, ey, ez = cap[3] - cap[0], cap[4] - cap[1], cap[5] - cap[2]
    length2 = ex * ex + ey * ey + ez * ez
    u = 0.0
    if length2 > 0.0:
        u = min(max(((x - cap[0]) * ex + (y - cap[1]) * ey + (z - cap[2]) * ez) / length2, 0.0), 1.0)
    wx, wy, wz = x - cap[0] - u * ex, y - cap[1] - u * ey, z - cap[2] - u * ez
    distance = math.sqrt(wx * wx + wy * wy + wz * wz)
    if distance == 0.0:
        return 0.0, 0.0, 0.0, 1.0
    return distance, wx / distance, wy / distance, wz / distance


@compiled()
def _path_stray(x, y, z, vx, vy, vz, x1, y1, z1, vx1, vy1, vz1, h):
    """A bound on how far the step's cubic Hermite path strays from its chord (m).

    Written about the chord velocity c = (p₁ − p₀)/h, the path less the chord at fraction s is
    h·s(1 − s)·((1 − s)(v₀ − c) − s(v₁ − c)), so its length is at most h/4 · max(|v₀ − c|, |v₁ − c|); taken here
    with the sum of the components' sizes, no less than the length, so each step pays no square root. Gravity bends
    a long step's path off its chord, and drag slows the ball along it.
    """
    dx, dy, dz = x1 - x, y1 - y, z1 - z
    a = abs(h * vx - dx) + abs(h * vy - dy) + abs(h * vz - dz)
    b = abs(h * vx1 - dx) + abs(h * vy1 - dy) + abs(h * vz1 - dz)
    return 0.25 * max(a, b)


@compiled()
def _path_to_axis(x, y, z, vx, vy, vz, x1, y1, z1, vx1, vy1, vz1, h, s, cap):
    """Distance from the step's path at fraction ``s`` to the capsule's axis (m)."""
    px, _ = _hermite(x, vx, x1, vx1, h, s)
    py, _ = _hermite(y, vy, y1, vy1, h, s)
    pz, _ = _hermite(z, vz, z1, vz1, h, s)
    distance, _, _, _ = _to_axis(px, py, pz, cap)
    return distance


PATH_SAMPLES = 16
"""Points of a step's path sampled for its first touch of a capsule, where the chord's closest approach does not
bracket it."""


@compiled()
def _path_bracket(x, y, z, vx, vy, vz, x1, y1, z1, vx1, vy1, vz1, h, cap, reach):
    """Fractions (lo, hi) of the step with the path clear of the capsule at ``lo`` and touching it at ``hi``, the
    first touch between them; (0, 2) if no touch is found. The first of :data:`PATH_SAMPLES` samples that touches,
    else a golden-section search for the least distance about the nearest sample."""
    nearest, least = 1, math.inf
    for k in range(1, PATH_SAMPLES + 1):
        distance = _path_to_axis(x, y, z, vx, vy, vz, x1, y1, z1, vx1, vy1, vz1, h, k / PATH_SAMPLES, cap)
        if distance <= reach:
            return (k - 1) / PATH_SAMPLES, k / PATH_SAMPLES
        if distance < least:
            nearest, least = k, distance
    lo = (nearest - 1) / PATH_SAMPLES
    a, b = lo, min(nearest + 1, PATH_SAMPLES) / PATH_SAMPLES
    shrink = 0.5 * (math.sqrt(5.0) - 1.0)
    while b - a > 1e-13:
        c, d = b - shrink * (b - a), a + shrink * (b - a)
        at_c = _path_to_axis(x, y, z, vx, vy, vz, x1, y1, z1, vx1, vy1, vz1, h, c, cap)
        if at_c <= reach:
            return lo, c
        at_d = _path_to_axis(x, y, z, vx, vy, vz, x1, y1, z1, vx1, vy1, vz1, h, d, cap)
        if at_d <= reach:
            return lo, d
        if at_c < at_d:
            b = d
        else:
            a = c
    return 0.0, 2.0


@compiled()
def _capsule_fraction(x, y, z, vx, vy, vz, x1, y1, z1, vx1, vy1, vz1, h, cap, radius, stray):
    """First fraction of the step at which the ball (radius ``radius``) touches the capsule ``cap`` while moving
    into it, or 2.0 for none: a swept test of the chord, grown by how far the path strays from it (``stray``,
    :func:`_path_stray`), then bisection on the cubic Hermite path."""
    reach = radius + cap[6]
    # Broad phase: the step's chord and the capsule's axis, each boxed, must come within reach (most steps do not).
    margin = reach + 1e-3 + stray
    if max(x, x1) < min(cap[0], cap[3]) - margin or min(x, x1) > max(cap[0], cap[3]) + margin:
        return 2.0
    if max(y, y1) < min(cap[1], cap[4]) - margin or min(y, y1) > max(cap[1], cap[4]) + margin:
        return 2.0
    if max(z, z1) < min(cap[2], cap[5]) - margin or min(z, z1) > max(cap[2], cap[5]) + margin:
        return 2.0
    s_hi, _, d2 = _segment_closest(
        x, y, z, x1 - x, y1 - y, z1 - z, cap[0], cap[1], cap[2], cap[3] - cap[0], cap[4] - cap[1], cap[5] - cap[2]
    )
    if d2 > margin * margin:
        return 2.0
    distance, nx, ny, nz = _to_axis(x, y, z, cap)
    # Touching at the start (to rounding: the last contact leaves a ball at reach ± 1 ulp): a contact only if moving
    # into the body faster than 1 nm/s (a ball it left sliding along the body moves along it to rounding). Without
    # the tolerances such a ball met the body again at once, contact after contact with no change.
    if distance <= reach * (1.0 + 1e-12):
        return 0.0 if vx * nx + vy * ny + vz * nz < -1e-9 else 2.0
    # The chord's closest approach brackets the first touch (distance to a convex body is convex along a line) when
    # the path there touches. In a long step it may not: drag slows the ball along the step, so the path at that
    # fraction lies short of the chord's point, and gravity bends the path off the chord. Then the path's samples
    # bracket it: the first sample that touches, or the least distance about the nearest sample.
    lo, hi = 0.0, max(s_hi, 1e-12)
    if _path_to_axis(x, y, z, vx, vy, vz, x1, y1, z1, vx1, vy1, vz1, h, hi, cap) > reach:
        lo, hi = _path_bracket(x, y, z, vx, vy, vz, x1, y1, z1, vx1, vy1, vz1, h, cap, reach)
        if hi > 1.0:
            return 2.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if _path_to_axis(x, y, z, vx, vy, vz, x1, y1, z1, vx1, vy1, vz1, h, mid, cap) > reach:
            lo = mid
        else:
            hi = mid
        if hi - lo < 1e-13:
            break
    return lo


@compiled()
def _keeper_pose(pitch, dive_t, target, t):
    """The keeper at time ``t``: his centre of mass and the unit vector from it toward his fingertips, as
    (mx, my, mz, ux, uy, uz). Standing, he is upright; from ``dive_t`` the centre of mass accelerates uniformly for
    the push-off time to the dive speed, then keeps it, along the straight line to the point that puts the
    fingertips on ``target``, stopping there; the body turns from upright to point at the target over the turn
    time."""
    mx, my, mz = pitch[KX], pitch[KY], pitch[TURF] + pitch[K_COM]
    ux, uy, uz = 0.0, 0.0, 1.0
    if t > dive_t:
        tau = t - dive_t
        push, speed = pitch[K_PUSH], pitch[K_SPEED]
        travel = 0.5 * speed * tau * tau / push if tau < push else 0.5 * speed * push + speed * (tau - push)
        gx, gy, gz = target[0] - mx, target[1] - my, target[2] - mz
        span = math.sqrt(gx * gx + gy * gy + gz * gz)
        if span > 1e-9:
            gx, gy, gz = gx / span, gy / span, gz / span
            move = min(travel, max(span - pitch[K_HANDS], 0.0))
            mx, my, mz = mx + gx * move, my + gy * move, mz + gz * move
            turn = min(tau / pitch[K_TURN], 1.0)
            ux, uy, uz = turn * gx, turn * gy, (1.0 - turn) + turn * gz
            length = math.sqrt(ux * ux + uy * uy + uz * uz)
            if length > 1e-9:
                ux, uy, uz = ux / length, uy / length, uz / length
            else:
                ux, uy, uz = gx, gy, gz
    return mx, my, mz, ux, uy, uz


@compiled()
def spin_inertia_bound(pitch):
    """The largest α·R² (m²) of the ball in the pitch's surface slots (turf, frame, bodies): how much of the spin's
    energy a contact can turn into speed (:func:`~kernels.ball.aero.max_stable_step`)."""
    bound = 0.0
    for slot in (TURF_SURFACE, FRAME_SURFACE, BODY_SURFACE):
        bound = max(bound, pitch[slot + 4] * pitch[slot + 3] ** 2)
    return bound


@compiled()
def _keeper_capsule(pitch, dive_t, target, t, cap):
    """The keeper's capsule at time ``t`` into ``cap`` (8,): a stick from feet to fingertips through the centre of
    mass (:func:`_keeper_pose`), its ends pulled in by the body's radius and kept above the turf."""
    mx, my, mz, ux, uy, uz = _keeper_pose(pitch, dive_t, target, t)
    turf, feet, hands, r = pitch[TURF], pitch[K_FEET], pitch[K_HANDS], pitch[K_RADIUS]
    cap[0], cap[1], cap[2] = mx - ux * (feet - r), my - uy * (feet - r), max(mz - uz * (feet - r), turf + r)
    cap[3], cap[4], cap[5] = mx + ux * (hands - r), my + uy * (hands - r), max(mz + uz * (hands - r), turf + r)
    cap[6], cap[7] = r, KEEPER


@compiled(from_python=True)
def keeper_path(pitch, dive_t, target, times, out):
    """The keeper at each of ``times`` (T,) into ``out`` (T, 12): centre of mass (3), the unit vector toward the
    fingertips (3), and the ends of the capsule the ball is tested against (feet end 3, fingertip end 3).

    Raises:
        ValueError: ``pitch`` shorter than N_PITCH, ``target`` than 3, or ``out`` smaller than (T, 12). Of the
        compiled cores only this one shares a public function's name, so it checks the sizes it writes by.
    """
    if pitch.shape[0] < N_PITCH or target.shape[0] < 3 or out.shape[0] < times.shape[0] or out.shape[1] < 12:
        raise ValueError("keeper_path core: pitch needs N_PITCH values, target 3 and out (T, 12) for T times")
    cap = np.empty(8)
    for i in range(times.shape[0]):
        out[i, 0], out[i, 1], out[i, 2], out[i, 3], out[i, 4], out[i, 5] = _keeper_pose(pitch, dive_t, target, times[i])
        _keeper_capsule(pitch, dive_t, target, times[i], cap)
        for c in range(6):  # element by element: a slice assignment compiles numba's shape-mismatch message
            out[i, 6 + c] = cap[c]


@compiled()
def _fixed_capsules(pitch, caps):
    """Posts, bar and the wall's players as rows of ``caps`` (ax, ay, az, bx, by, bz, radius, kind); their count."""
    gx, gy, nx, ny = pitch[GX], pitch[GY], pitch[GNX], pitch[GNY]
    ax, ay = -ny, nx  # along the goal line, to the left looking into the net
    rp, turf = pitch[POST_R], pitch[TURF]
    half = 0.5 * pitch[GW] + rp
    top = turf + pitch[GH] + rp
    for i, side in enumerate((-1.0, 1.0)):
        caps[i, 0], caps[i, 1], caps[i, 2] = gx + side * half * ax, gy + side * half * ay, turf
        caps[i, 3], caps[i, 4], caps[i, 5] = caps[i, 0], caps[i, 1], top
        caps[i, 6], caps[i, 7] = rp, POST
    caps[2, 0], caps[2, 1], caps[2, 2] = gx - half * ax, gy - half * ay, top
    caps[2, 3], caps[2, 4], caps[2, 5] = gx + half * ax, gy + half * ay, top
    caps[2, 6], caps[2, 7] = rp, BAR
    count = 3
    if pitch[WALL_ON] != 0.0:
        players, r = int(pitch[N_PLAYERS]), pitch[PLAYER_R]
        wx, wy = -pitch[WNY], pitch[WNX]
        for j in range(players):
            offset = (j - 0.5 * (players - 1)) * 2.0 * r
            cx, cy = pitch[WX] + offset * wx, pitch[WY] + offset * wy
            caps[count, 0], caps[count, 1], caps[count, 2] = cx, cy, turf + r
            caps[count, 3], caps[count, 4] = cx, cy
            caps[count, 5] = max(turf + pitch[WH] - r, turf + r)
            caps[count, 6], caps[count, 7] = r, WALL
            count += 1
    return count


@compiled()
def _group_boxes(caps, n_fixed, reach, boxes):
    """Boxes (lo x y z, hi x y z) around the goal frame's capsules (rows 0–2) and the wall's (rows 3 to
    ``n_fixed``) into ``boxes`` (2, 6), grown by ``reach``: a step whose chord box misses a group's box cannot touch
    any capsule of it, so its capsules are not tested one by one. An empty group's box is empty (lo > hi)."""
    boxes[:, 0:3] = math.inf
    boxes[:, 3:6] = -math.inf
    for c in range(n_fixed):
        g = 0 if c < 3 else 1
        grow = reach + caps[c, 6]
        for k in range(3):
            boxes[g, k] = min(boxes[g, k], min(caps[c, k], caps[c, k + 3]) - grow)
            boxes[g, k + 3] = max(boxes[g, k + 3], max(caps[c, k], caps[c, k + 3]) + grow)


@compiled(inline="always")
def _box(boxes, g):
    """Row ``g`` of ``boxes`` as a tuple (lo x y z, hi x y z): what the step tests, read with no array reference.
    (Inlined: called with constant rows, it would otherwise compile once for each.)"""
    return boxes[g, 0], boxes[g, 1], boxes[g, 2], boxes[g, 3], boxes[g, 4], boxes[g, 5]


@compiled()
def _chord_meets(x, y, z, x1, y1, z1, box, grow):
    """Whether the box of the step's chord, grown by ``grow`` (m), meets ``box`` (:func:`_box`)."""
    return not (
        max(x, x1) + grow < box[0]
        or min(x, x1) - grow > box[3]
        or max(y, y1) + grow < box[1]
        or min(y, y1) - grow > box[4]
        or max(z, z1) + grow < box[2]
        or min(z, z1) - grow > box[5]
    )


@compiled()
def _keeper_box(pitch, dive_t, target, reach, boxes):
    """A box around every place the keeper's capsule can be from now on into ``boxes[2]``, grown by ``reach``: the
    segment his centre of mass moves along (:func:`_keeper_pose`), grown by his longer reach (the stick may point
    anywhere) and his body's radius."""
    x0, y0, z0, _, _, _ = _keeper_pose(pitch, dive_t, target, -1.0)  # standing: the dive starts at t ≥ 0
    late = dive_t + 1e9 if dive_t < math.inf else -1.0  # long after the dive: where he stops
    x1, y1, z1, _, _, _ = _keeper_pose(pitch, dive_t, target, late)
    grow = reach + pitch[K_RADIUS] + max(pitch[K_HANDS], pitch[K_FEET])
    boxes[2, 0], boxes[2, 1], boxes[2, 2] = min(x0, x1) - grow, min(y0, y1) - grow, min(z0, z1) - grow
    boxes[2, 3], boxes[2, 4], boxes[2, 5] = max(x0, x1) + grow, max(y0, y1) + grow, max(z0, z1) + grow


@compiled()
def _rolls_clear(x, y, z, vx, vy, pitch, boxes, dived):
    """Whether a ball rolling from (x, y, z) at (vx, vy) can no longer change its verdict: it rolls away from the
    goal (or along its line) and its roll misses the goal frame's, the wall's and the keeper's boxes (``boxes``,
    :func:`_group_boxes`, :func:`_keeper_box`). Before the keeper has ``dived`` nothing is clear: his box holds only
    where he stands, not where his dive will take him. A roll runs straight, since every force on a rolling ball
    acts against its velocity, and stops within |v|²/(2·d), d the rolling deceleration (the air's drag only
    shortens it)."""
    keeper = pitch[KEEPER_ON] != 0.0
    if vx * pitch[GNX] + vy * pitch[GNY] > 0.0 or (keeper and not dived):
        return False
    decel = pitch[ROLL_DECEL]
    if decel <= 0.0:
        return False
    reach = math.sqrt(vx * vx + vy * vy) / (2.0 * decel)  # the stop is at (x, y) + (vx, vy)·reach
    x1, y1 = x + vx * reach, y + vy * reach
    return not (
        _chord_meets(x, y, z, x1, y1, z, _box(boxes, 0), 0.0)
        or _chord_meets(x, y, z, x1, y1, z, _box(boxes, 1), 0.0)
        or (keeper and _chord_meets(x, y, z, x1, y1, z, _box(boxes, 2), 0.0))
    )


@compiled()
def _reach_boxes(pitch, reach, boxes):
    """Boxes around every place a ball that has struck the wall, a post or the bar could still change its verdict,
    grown by ``reach``: the goal mouth (a goal: the ball's centre crosses the goal line there, within a post's
    radius of the posts and the bar) into ``boxes[3]``, and every place the keeper's capsule can ever be (he stands,
    then dives to a point of the mouth: his centre of mass keeps to the box around where he stands and the mouth's
    corners, grown by his longer reach and his body's radius) into ``boxes[4]``; ``boxes[4]`` is empty (lo > hi)
    without a keeper."""
    gx, gy, ax, ay = pitch[GX], pitch[GY], -pitch[GNY], pitch[GNX]
    half, turf = 0.5 * pitch[GW] + pitch[POST_R], pitch[TURF]
    boxes[3, 0], boxes[3, 3] = gx - abs(ax) * half - reach, gx + abs(ax) * half + reach
    boxes[3, 1], boxes[3, 4] = gy - abs(ay) * half - reach, gy + abs(ay) * half + reach
    boxes[3, 2], boxes[3, 5] = turf - reach, turf + pitch[GH] + pitch[POST_R] + reach
    boxes[4, 0:3] = math.inf
    boxes[4, 3:6] = -math.inf
    if pitch[KEEPER_ON] == 0.0:
        return
    # Where he stands, and the corners of the dive targets' rectangle (play: lateral within the goal's half width,
    # height from the ball's radius above the turf to the bar's underside; the ball's radius is reach's larger part).
    grow = reach + pitch[K_RADIUS] + max(pitch[K_HANDS], pitch[K_FEET])
    lo_x, lo_y, lo_z = pitch[KX], pitch[KY], turf + pitch[K_COM]
    hi_x, hi_y, hi_z = lo_x, lo_y, lo_z
    for side in (-1.0, 1.0):
        cx, cy = gx + side * 0.5 * pitch[GW] * ax, gy + side * 0.5 * pitch[GW] * ay
        lo_x, hi_x, lo_y, hi_y = min(lo_x, cx), max(hi_x, cx), min(lo_y, cy), max(hi_y, cy)
    lo_z, hi_z = min(lo_z, turf), max(hi_z, turf + pitch[GH])
    boxes[4, 0], boxes[4, 1], boxes[4, 2] = lo_x - grow, lo_y - grow, lo_z - grow
    boxes[4, 3], boxes[4, 4], boxes[4, 5] = hi_x + grow, hi_y + grow, hi_z + grow


@compiled()
def _box_distance2(x, y, z, box):
    """Squared distance from (x, y, z) to ``box`` (:func:`_box`); 0 inside it, +inf for an empty box."""
    if box[0] > box[3]:
        return math.inf
    dx = max(box[0] - x, x - box[3], 0.0)
    dy = max(box[1] - y, y - box[4], 0.0)
    dz = max(box[2] - z, z - box[5], 0.0)
    return dx * dx + dy * dy + dz * dz


@compiled()
def _out_of_reach(x, y, z, vx, vy, vz, wx, wy, wz, t_left, g, ground, spin_inertia, mouth_box, keeper_box):
    """Whether a ball that has struck something (the knuckle force ended) can no longer reach the goal mouth nor the
    keeper (``mouth_box``, ``keeper_box``: :func:`_reach_boxes`, or the dived keeper's :func:`_keeper_box`) in the
    ``t_left`` seconds left: then nothing can change the verdict of a ball whose first body decided it.

    Its energy per unit mass, doubled, E = |v|² + 2g·(z − ground) + α·R²·|ω|² (``spin_inertia`` = α·R²), never
    grows: the drag only takes energy, the Magnus force is square to the velocity and does no work, gravity only
    trades height for speed, spin is constant in flight, every impact (Cross's model with 0 ≤ e_n, e_t ≤ 1) and the
    start of a roll take energy (:mod:`kernels.ball.contact`), and a roll slows. So |v| ≤ √E from now on, and the
    ball's path, each step's chord box included, keeps within √E·``t_left`` of here; 2 % of E and 0.01 m²/s² are
    added for the integration's and the contact roots' rounding. The bound holds whatever the spin and however the
    ball bounces off the turf, the wall or the frame.
    """
    energy = vx * vx + vy * vy + vz * vz + 2.0 * g * (z - ground) + spin_inertia * (wx * wx + wy * wy + wz * wz)
    reach2 = (1.02 * energy + 0.01) * t_left * t_left
    return _box_distance2(x, y, z, mouth_box) > reach2 and _box_distance2(x, y, z, keeper_box) > reach2


# --------------------------------------------------------------------------------------------- the flight
@compiled()
def _roll_acceleration(vx, vy, law, decel):
    """Horizontal acceleration of a rolling ball: rolling resistance ``decel`` and the air's drag (spin rate |v|/R)
    under the kick's :class:`~kernels.ball.aero.ForceLaw`."""
    speed2 = vx * vx + vy * vy
    if speed2 == 0.0:
        return 0.0, 0.0
    speed = math.sqrt(speed2)
    drag, _ = drag_lift_speeds(
        speed2, speed / law.radius, law.measured, law.drag, law.lift, law.radius, law.re_per_speed, law.re_crisis
    )  # C_D·|v|
    k = decel / speed + law.q * drag
    return -k * vx, -k * vy


@compiled()
def _set_spin(kick, wx, wy, wz):
    rate = math.sqrt(wx * wx + wy * wy + wz * wz)
    kick[RATE] = rate
    if rate > 0.0:
        kick[AXIS], kick[AXIS + 1], kick[AXIS + 2] = wx / rate, wy / rate, wz / rate
    else:
        kick[AXIS], kick[AXIS + 1], kick[AXIS + 2] = 0.0, 0.0, 0.0


@compiled(inline="always")
def _write_spin_sample(t_out, state_out, spin_out, n, t, x, y, z, vx, vy, vz, wx, wy, wz):
    """The free flight's sample ``n`` (:func:`~kernels.ball.core._write_sample`) and its spin into ``spin_out``."""
    _write_sample(t_out, state_out, n, t, x, y, z, vx, vy, vz)
    spin_out[n, 0], spin_out[n, 1], spin_out[n, 2] = wx, wy, wz


@compiled()
def _roll_step(x, y, z, vx, vy, h, law, decel):
    """One step of a roll (horizontal velocity (vx, vy) ≠ 0): RK4 on the horizontal velocity, or the exact stop
    where the speed runs out inside the step. Returns the step's end (x, y, z, vx, vy, vz), its length and whether
    the ball stopped."""
    speed = math.sqrt(vx * vx + vy * vy)
    ax0, ay0 = _roll_acceleration(vx, vy, law, decel)
    a = math.sqrt(ax0 * ax0 + ay0 * ay0)
    if speed <= a * h:  # it stops inside this step (the deceleration is nearly constant over it)
        h = speed / a
        return x + 0.5 * vx * h, y + 0.5 * vy * h, z, 0.0, 0.0, 0.0, h, True
    half = 0.5 * h
    a2x, a2y = _roll_acceleration(vx + half * ax0, vy + half * ay0, law, decel)
    a3x, a3y = _roll_acceleration(vx + half * a2x, vy + half * a2y, law, decel)
    a4x, a4y = _roll_acceleration(vx + h * a3x, vy + h * a3y, law, decel)
    x1 = x + h / 6.0 * (vx + 2.0 * (vx + half * ax0) + 2.0 * (vx + half * a2x) + vx + h * a3x)
    y1 = y + h / 6.0 * (vy + 2.0 * (vy + half * ay0) + 2.0 * (vy + half * a2y) + vy + h * a3y)
    vx1 = vx + h / 6.0 * (ax0 + 2.0 * (a2x + a3x) + a4x)
    vy1 = vy + h / 6.0 * (ay0 + 2.0 * (a2y + a3y) + a4y)
    if vx1 * vx + vy1 * vy <= 0.0:  # reversed: stop where the speed reached zero
        return x1, y1, z, 0.0, 0.0, 0.0, h, True
    return x1, y1, z, vx1, vy1, 0.0, h, False


@compiled()
def _verdict(pitch, info, radius, scored, touched_keeper, first_body):
    """The play's result code from what it met and where it crossed the goal line (``info``)."""
    if scored:
        return GOAL
    elif touched_keeper:
        return SAVED_RESULT
    elif first_body == WALL:
        return WALL_RESULT
    elif first_body == POST:
        return POST_RESULT
    elif first_body == BAR:
        return BAR_RESULT
    elif not math.isnan(info[I_GOAL]):
        lateral = -(info[I_GOAL + 1] - pitch[GX]) * pitch[GNY] + (info[I_GOAL + 2] - pitch[GY]) * pitch[GNX]
        if abs(lateral) > 0.5 * pitch[GW] - radius:
            return WIDE
        elif info[I_GOAL + 3] > pitch[TURF] + pitch[GH] - radius:
            return OVER
        else:
            return SHORT
    return SHORT


@compiled()
def _keeper_reads(pitch, x, y, z, vx, vy, vz, t, g, radius, target, info, boxes):
    """The keeper's read of the ball at time ``t``: where it will cross his goal line if it reaches it within
    :data:`DIVE_HORIZON_S` within his hands' reach of the goal, he dives for that point now (its time and target into
    ``info``, his new box into ``boxes[2]``). Returns the dive's start, ``inf`` while he waits."""
    gx, gy, gnx, gny = pitch[GX], pitch[GY], pitch[GNX], pitch[GNY]
    half_goal, turf = 0.5 * pitch[GW], pitch[TURF]
    depth = (x - gx) * gnx + (y - gy) * gny
    approach = vx * gnx + vy * gny
    lead = -depth / approach if approach > 1e-9 and depth < 0.0 else math.inf
    if not lead <= DIVE_HORIZON_S:
        return math.inf
    lateral = -(x + vx * lead - gx) * gny + (y + vy * lead - gy) * gnx
    height = z + vz * lead - 0.5 * g * lead * lead
    if not (abs(lateral) <= half_goal + pitch[K_HANDS] and height <= turf + pitch[GH] + pitch[K_HANDS]):
        return math.inf
    lateral = min(max(lateral, -half_goal), half_goal)
    height = min(max(height, turf + radius), turf + pitch[GH])
    target[0], target[1], target[2] = gx - lateral * gny, gy + lateral * gnx, height
    info[I_DIVE] = t
    info[I_TARGET], info[I_TARGET + 1], info[I_TARGET + 2] = target[0], target[1], target[2]
    _keeper_box(pitch, t, target, radius + 1e-3, boxes)
    return t


@compiled()
def _goal_mouth(
    pitch, x, y, z, vx, vy, vz, x1, y1, z1, vx1, vy1, vz1, t, h, radius, best, kind, inside, scored, crossed, info
):
    """The goal in one step: the ball crossing the goal line (into the mouth, where the crossing goes into ``info``, or
    outside the goal: out of the pitch), back out through the mouth, wholly over the line (the fraction ``crossed``)
    and stopped by the net's back, sides or roof. Returns the step's first contact (fraction ``best``, ``kind``),
    whether the ball is inside the goal, and ``crossed``."""
    gx, gy, gnx, gny = pitch[GX], pitch[GY], pitch[GNX], pitch[GNY]
    half_goal, rp, turf = 0.5 * pitch[GW], pitch[POST_R], pitch[TURF]
    depth0 = (x - gx) * gnx + (y - gy) * gny
    depth1 = (x1 - gx) * gnx + (y1 - gy) * gny
    rate0, rate1 = vx * gnx + vy * gny, vx1 * gnx + vy1 * gny
    if not inside and depth0 <= 0.0 < depth1:  # from on the line too (a kick from it flew through the net unseen)
        f = crossing_fraction(-depth0, -rate0, -depth1, -rate1, h)
        if f <= best:
            cx, _ = _hermite(x, vx, x1, vx1, h, f)
            cy, _ = _hermite(y, vy, y1, vy1, h, f)
            cz, _ = _hermite(z, vz, z1, vz1, h, f)
            if math.isnan(info[I_GOAL]):
                info[I_GOAL], info[I_GOAL + 1], info[I_GOAL + 2], info[I_GOAL + 3] = t + f * h, cx, cy, cz
            lateral = -(cx - gx) * gny + (cy - gy) * gnx
            if abs(lateral) <= half_goal + rp and cz <= turf + pitch[GH] + rp:
                inside = True
            else:
                best, kind = f, -3  # over the goal line outside the goal: it leaves the pitch
    elif inside and depth0 >= 0.0 > depth1:
        inside = False  # back out through the mouth
    if inside:
        # Wholly over the line (Law 10: a goal), then the net: back, sides and roof stop it.
        line = rp + radius
        if not scored and depth1 >= line:
            crossed = 0.0 if depth0 >= line else crossing_fraction(line - depth0, -rate0, line - depth1, -rate1, h)
        limit = pitch[NET_DEPTH] - radius
        if depth1 >= limit:
            f = crossing_fraction(limit - depth0, -rate0, limit - depth1, -rate1, h)
            if f < best:
                best, kind = f, NET
        lat0 = -(x - gx) * gny + (y - gy) * gnx
        lat1 = -(x1 - gx) * gny + (y1 - gy) * gnx
        side = half_goal + rp - radius
        if depth1 > rp and abs(lat1) >= side and abs(lat0) < side:
            sign = 1.0 if lat1 > 0.0 else -1.0
            f = crossing_fraction(
                side - sign * lat0,
                -sign * (-vx * gny + vy * gnx),
                side - sign * lat1,
                -sign * (-vx1 * gny + vy1 * gnx),
                h,
            )
            if f < best:
                best, kind = f, NET
        roof = turf + pitch[GH] + 2.0 * rp - radius
        if depth1 > rp and z1 >= roof > z:
            f = crossing_fraction(roof - z, -vz, roof - z1, -vz1, h)
            if f < best:
                best, kind = f, NET
    return best, kind, inside, crossed


@compiled()
def _also_met(caps, n_fixed, which, x, y, z, vx, vy, vz, radius):
    """The body of the frame or the wall, other than ``which``, that the ball touching ``which`` at (x, y, z) also
    meets within the same contact, and its share of the impact's normal; (-1, 0.0) for none.

    A contact lasts :data:`CONTACT_S`, over which the ball is pressed in by up to |v|·T/π (a half-sine force: 4.3 cm
    at 15 m/s). A body nearer than that, which the ball moves into, shares the impact by 1 − gap/depth: all of it
    when touched at once (a kick square into the gap between two defenders comes straight back), none at the
    depth. Met one after the other, the first body turned the ball aside, and a shift of 1e-6 m chose which way it
    rebounded (4.4 m either side)."""
    depth = math.sqrt(vx * vx + vy * vy + vz * vz) * CONTACT_S / math.pi
    nearest, share = -1, 0.0
    for c in range(n_fixed):
        if c == which:
            continue
        distance, nx, ny, nz = _to_axis(x, y, z, caps[c])
        gap = distance - (radius + caps[c, 6])
        if gap < depth and vx * nx + vy * ny + vz * nz < 0.0 and 1.0 - max(gap, 0.0) / depth > share:
            nearest, share = c, 1.0 - max(gap, 0.0) / depth
    return nearest, share


@compiled()
def _bounce(
    pitch, kind, cap, other, share, x, y, z, vx, vy, vz, wx, wy, wz, t, rolling, chatter, supported_t, ground, radius
):
    """The ball meets the turf (``kind`` GROUND_HIT) or the body ``cap`` (a post, the bar, a player of the wall) at
    time ``t``: Cross's impact (:func:`~kernels.ball.contact.impact`) on the surface's normal, the roll it starts or
    keeps, and a ball that settles on a body below it. With ``share`` > 0 it also meets the body ``other`` within
    the same contact (:func:`_also_met`): one impact on the normal n₁ + share·n₂, normalised. Returns the state after
    (z, velocity, spin), whether it rolls, the count and time of quick contacts on bodies below it, and whether it
    settled there."""
    scratch = np.empty((5, 3))
    v_in, w_in, normal, v_new, w_new = scratch[0], scratch[1], scratch[2], scratch[3], scratch[4]
    settled = False
    if kind == GROUND_HIT:
        z = ground
        normal[0], normal[1], normal[2] = 0.0, 0.0, 1.0
        surface = pitch[TURF_SURFACE : TURF_SURFACE + N_SURFACE]
    else:
        _, nx, ny, nz = _to_axis(x, y, z, cap)
        if share > 0.0:
            _, mx, my, mz = _to_axis(x, y, z, other)
            nx, ny, nz = nx + share * mx, ny + share * my, nz + share * mz
            length = math.sqrt(nx * nx + ny * ny + nz * nz)
            if length > 0.0:
                nx, ny, nz = nx / length, ny / length, nz / length
        if rolling:
            nz = 0.0
            length = math.sqrt(nx * nx + ny * ny)
            if length > 0.0:
                nx, ny = nx / length, ny / length
            else:
                speed = max(math.sqrt(vx * vx + vy * vy), 1e-300)
                nx, ny = -vx / speed, -vy / speed
        normal[0], normal[1], normal[2] = nx, ny, nz
        slot = FRAME_SURFACE if kind != WALL else BODY_SURFACE
        surface = pitch[slot : slot + N_SURFACE]
    v_in[0], v_in[1], v_in[2] = vx, vy, vz
    w_in[0], w_in[1], w_in[2] = wx, wy, wz
    impact(v_in, w_in, normal, surface, v_new, w_new)
    vx, vy, vz = v_new[0], v_new[1], v_new[2]
    wx, wy, wz = w_new[0], w_new[1], w_new[2]
    if kind == GROUND_HIT and vz < pitch[ROLL_SPEED]:
        rolling = True
    if rolling:
        # Onto the turf, rolling without slipping: a gripping tangential impulse that stops the contact
        # point (Cross's grip with e_t = 0; it conserves the angular momentum about the contact point and
        # never adds energy), then ω = (ẑ × v)/R; spin about the vertical is lost to the turf.
        vz = 0.0
        alpha = pitch[TURF_SURFACE + 4]
        share = alpha / (1.0 + alpha)
        ux, uy = vx - radius * wy, vy + radius * wx
        vx, vy = vx - share * ux, vy - share * uy
        into = vx * normal[0] + vy * normal[1]
        if kind != GROUND_HIT and into < 0.0:
            # The turf's grip can leave a ball that rolled into a post or a player still rolling into it
            # (its spin outweighs the rebound); the body stops that part and the ball rolls on along it,
            # or rests against it. Without this it struck the body again at once, contact after contact.
            vx, vy = vx - into * normal[0], vy - into * normal[1]
    elif kind != GROUND_HIT and normal[2] >= 0.5:  # on a body below it: a head, the bar, a post's top
        chatter = chatter + 1 if t - supported_t < 0.01 else 0
        supported_t = t
        if vx * vx + vy * vy + vz * vz < pitch[ROLL_SPEED] ** 2 or chatter >= 2:
            # Settled there: it leaves slower than a ground bounce that starts the roll (slow overall: a
            # fast ball grazing the bar leaves with a weak rebound too), or it is caught between two heads,
            # struck three times inside 10 ms. Each bounce would come sooner than the last, without end.
            # The ball rests there.
            vx, vy, vz, wx, wy, wz = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
            settled = True
    return z, vx, vy, vz, wx, wy, wz, rolling, chatter, supported_t, settled


@compiled()
def play(launch, kick, config, pitch, t_out, state_out, spin_out, events, info):
    """Fly one kick on the pitch. Writes samples (time, position and velocity, spin) to ``t_out`` (T,), ``state_out``
    (T, 6) and ``spin_out`` (T, 3), T ≥ n_steps + 1 + :data:`EXTRA_ROWS` (T = 0: count only); contacts (time, kind,
    x, y, z) to ``events`` (:data:`MAX_EVENTS`, 5); the verdict, the wall's and goal's plane crossings (time, x, y,
    z; NaN where none), the contact count, the keeper's dive start and target and the first contact's time to
    ``info`` (:data:`N_INFO`,). ``kick`` (from :func:`fill_kick`) is changed: spin after each contact, no knuckle
    force after the first. Returns (samples written, ending code)."""
    store = len(t_out) > 0
    info[:] = np.nan
    info[I_EVENTS] = 0.0
    dt, ground, x_stop, g, t_max = config[DT], config[GROUND], config[X_STOP], config[GRAVITY], config[T_MAX]
    radius = config[RADIUS]
    x, y, z, vx, vy, vz = launch[0], launch[1], launch[2], launch[3], launch[4], launch[5]
    wx, wy, wz = launch[6], launch[7], launch[8]
    # The spin's energy counts too (α·R²·|ω|² per unit mass, doubled as |v|² is), with the same margin: a bounce can
    # turn it into speed, and a ball rolled with heavy backspin leaves the turf faster than it came. The one α·R²
    # serves this guard, the step limit and the energy bound of _out_of_reach.
    spin_inertia = spin_inertia_bound(pitch)
    energy_limit = _energy_limit(vx, vy, vz, z, g) + 4.0 * spin_inertia * (wx * wx + wy * wy + wz * wz)
    if store:
        _write_spin_sample(t_out, state_out, spin_out, 0, 0.0, x, y, z, vx, vy, vz, wx, wy, wz)
    refused = dt > max_stable_step(launch, kick, config, spin_inertia)[0]
    if refused:
        info[I_RESULT] = SHORT
        return 1, REFUSED
    caps = np.empty((MAX_CAPSULES, 8))
    n_fixed = _fixed_capsules(pitch, caps)
    keeper = pitch[KEEPER_ON] != 0.0
    n_caps = n_fixed + 1 if keeper else n_fixed
    boxes = np.empty((5, 6))
    _group_boxes(caps, n_fixed, radius + 1e-3, boxes)  # the capsule test's own broad-phase margin
    target = np.zeros(3)
    dive_t = math.inf
    if keeper:
        _keeper_box(pitch, dive_t, target, radius + 1e-3, boxes)  # standing until he dives
    frame_box, wall_box, keeper_box = _box(boxes, 0), _box(boxes, 1), _box(boxes, 2)
    _reach_boxes(pitch, radius + 1e-3, boxes)
    mouth_box, keeper_reach = _box(boxes, 3), _box(boxes, 4)
    # The energy bound of _out_of_reach counts the spin with the ball's α and R, the same in every surface's slots
    # (pitch_vector writes the ball's); where they differ, it is not used.
    bounded = True
    for slot in (TURF_SURFACE, FRAME_SURFACE, BODY_SURFACE):
        if pitch[slot + 4] * pitch[slot + 3] ** 2 != spin_inertia:
            bounded = False
    if keeper:
        _keeper_capsule(pitch, dive_t, target, 0.0, caps[n_fixed])
    for c in range(n_caps):  # a ball that starts inside a body would leave it with no contact: not flown
        if _to_axis(x, y, z, caps[c])[0] < (caps[c, 6] + radius) * (1.0 - 1e-9):
            info[I_RESULT] = SHORT
            return 1, INSIDE
    seen_t = math.inf if pitch[WALL_ON] != 0.0 else 0.0
    gx, gy, gnx, gny = pitch[GX], pitch[GY], pitch[GNX], pitch[GNY]
    n_events, first_body, touched_keeper, scored, inside = 0, -1, False, False, False
    rolling = False
    chatter, supported_t = 0, -math.inf  # contacts in quick succession on bodies below the ball, the last one's time
    law, rk4 = force_law(kick, config), config[RK4] != 0.0
    crossed = 2.0  # fraction of this step at which the whole ball is over the goal line (2: not in this step)
    t, n, ending = 0.0, 1, ENDED_T_MAX
    max_rows = len(t_out)
    for _ in range(int(config[N_STEPS]) + EXTRA_ROWS):
        # A verdict only: a goal stays a goal; a roll away from the goal and clear of every body, or a ball whose
        # first body decided it and whose energy cannot carry it back to the mouth or the keeper, ends here.
        if not store and (
            scored
            or (rolling and not inside and _rolls_clear(x, y, z, vx, vy, pitch, boxes, dive_t < math.inf))
            or (
                bounded
                and first_body >= 0
                and not inside
                and _out_of_reach(
                    x,
                    y,
                    z,
                    vx,
                    vy,
                    vz,
                    wx,
                    wy,
                    wz,
                    t_max - t,
                    g,
                    ground,
                    spin_inertia,
                    mouth_box,
                    keeper_box if dive_t < math.inf else keeper_reach,
                )
            )
        ):
            break
        h = min(dt, t_max - t)
        if h <= 1e-12 * max(dt, 1.0):
            break
        # The keeper reads the ball a reaction time after it passes the wall (or after the kick), and again each
        # step until it will reach his line within DIVE_HORIZON_S, within his hands' reach of the goal: then he dives.
        if keeper and dive_t == math.inf and t >= seen_t + pitch[K_REACT]:
            dive_t = _keeper_reads(pitch, x, y, z, vx, vy, vz, t, g, radius, target, info, boxes)
            if dive_t < math.inf:
                keeper_box = _box(boxes, 2)
        # One step: RK4/Euler in flight; rolling, the same step on the horizontal velocity, or the exact stop.
        stop_here = False
        if rolling:
            if math.sqrt(vx * vx + vy * vy) == 0.0:
                ending = STOPPED
                break
            x1, y1, z1, vx1, vy1, vz1, h, stop_here = _roll_step(x, y, z, vx, vy, h, law, pitch[ROLL_DECEL])
        else:
            x1, y1, z1, vx1, vy1, vz1 = _step(x, y, z, vx, vy, vz, t, h, law, rk4)
        if vx1 * vx1 + vy1 * vy1 + vz1 * vz1 + 2.0 * g * z1 > energy_limit or not math.isfinite(
            x1 + y1 + z1 + vx1 + vy1 + vz1
        ):
            ending = DIVERGED
            break
        stray = _path_stray(x, y, z, vx, vy, vz, x1, y1, z1, vx1, vy1, vz1, h)
        near_keeper = keeper and _chord_meets(x, y, z, x1, y1, z1, keeper_box, stray)
        if near_keeper:
            _keeper_capsule(pitch, dive_t, target, t + 0.5 * h, caps[n_fixed])
        # The first contact in the step.
        best, kind, which = 2.0, -1, -1
        if not rolling and z1 <= ground:
            best, kind = crossing_fraction(z - ground, vz, z1 - ground, vz1, h), GROUND_HIT
        if x < x_stop <= x1 or (t == 0.0 and x == x_stop and x1 > x):
            f = crossing_fraction(x_stop - x, -vx, x_stop - x1, -vx1, h)
            if f < best:
                best, kind = f, -2
        near_frame = _chord_meets(x, y, z, x1, y1, z1, frame_box, stray)
        near_wall = _chord_meets(x, y, z, x1, y1, z1, wall_box, stray)
        for c in range(n_caps):
            if (c < 3 and not near_frame) or (3 <= c < n_fixed and not near_wall) or (c == n_fixed and not near_keeper):
                continue
            f = _capsule_fraction(x, y, z, vx, vy, vz, x1, y1, z1, vx1, vy1, vz1, h, caps[c], radius, stray)
            if f < best:
                best, kind, which = f, int(caps[c, 7]), c
        depth0, depth1 = (x - gx) * gnx + (y - gy) * gny, (x1 - gx) * gnx + (y1 - gy) * gny
        if inside or depth0 <= 0.0 < depth1:  # the goal only where the ball is in it or crosses its line
            best, kind, inside, crossed = _goal_mouth(
                pitch,
                x,
                y,
                z,
                vx,
                vy,
                vz,
                x1,
                y1,
                z1,
                vx1,
                vy1,
                vz1,
                t,
                h,
                radius,
                best,
                kind,
                inside,
                scored,
                crossed,
                info,
            )
        # The wall's plane (the keeper's first clear sight of the ball).
        if pitch[WALL_ON] != 0.0 and math.isnan(info[I_WALL]):
            d0 = (x - pitch[WX]) * pitch[WNX] + (y - pitch[WY]) * pitch[WNY]
            d1 = (x1 - pitch[WX]) * pitch[WNX] + (y1 - pitch[WY]) * pitch[WNY]
            if d0 < 0.0 <= d1:
                f = crossing_fraction(
                    -d0, -(vx * pitch[WNX] + vy * pitch[WNY]), -d1, -(vx1 * pitch[WNX] + vy1 * pitch[WNY]), h
                )
                if f <= best:
                    cx, _ = _hermite(x, vx, x1, vx1, h, f)
                    cy, _ = _hermite(y, vy, y1, vy1, h, f)
                    cz, _ = _hermite(z, vz, z1, vz1, h, f)
                    info[I_WALL], info[I_WALL + 1], info[I_WALL + 2], info[I_WALL + 3] = t + f * h, cx, cy, cz
                    seen_t = t + f * h
        if crossed <= min(best, 1.0):  # wholly over the line before any contact in this step
            scored = True
        crossed = 2.0
        lat_end = -(x1 - gx) * gny + (y1 - gy) * gnx
        if kind == -1 and abs(lat_end) > pitch[HALF_WIDTH]:
            best, kind = 1.0, -3  # over a touchline
        if kind == -1:
            x, y, z, vx, vy, vz = x1, y1, z1, vx1, vy1, vz1
            if rolling:  # rolling without slipping: ω = (ẑ × v)/R as the roll slows
                wx, wy = -vy / radius, vx / radius
            t = t + h
            if store and n < max_rows:
                _write_spin_sample(t_out, state_out, spin_out, n, t, x, y, z, vx, vy, vz, wx, wy, wz)
            n += 1
            if stop_here:
                ending = STOPPED
                break
            continue
        # Move to the contact.
        f = best
        if stop_here:  # the stop's path is uniform deceleration, not a cubic with these end slopes
            ex, ey, ez = x + vx * h * (f - 0.5 * f * f), y + vy * h * (f - 0.5 * f * f), z
            evx, evy, evz = vx * (1.0 - f), vy * (1.0 - f), 0.0
        else:
            ex, evx = _hermite(x, vx, x1, vx1, h, f)
            ey, evy = _hermite(y, vy, y1, vy1, h, f)
            ez, evz = _hermite(z, vz, z1, vz1, h, f)
        if rolling:
            ez, evz = ground, 0.0
            wx, wy = -evy / radius, evx / radius
        t = t + f * h
        x, y, z, vx, vy, vz = ex, ey, ez, evx, evy, evz
        done = False
        which2, share = -1, 0.0
        if kind == POST or kind == BAR or kind == WALL:
            which2, share = _also_met(caps, n_fixed, which, x, y, z, vx, vy, vz, radius)
        if kind == GROUND_HIT or kind == POST or kind == BAR or kind == WALL:
            z, vx, vy, vz, wx, wy, wz, rolling, chatter, supported_t, settled = _bounce(
                pitch,
                kind,
                caps[which],
                caps[max(which2, 0)],
                share,
                x,
                y,
                z,
                vx,
                vy,
                vz,
                wx,
                wy,
                wz,
                t,
                rolling,
                chatter,
                supported_t,
                ground,
                radius,
            )
            if settled:
                ending, done = STOPPED, True
            if kind != GROUND_HIT and first_body < 0:
                first_body = kind  # the wall's players, a post or the bar: the first of them decides the verdict
        elif kind == KEEPER:
            touched_keeper, ending, done = True, SAVED, True
        elif kind == NET:
            # The net lies behind the line and the ball came in through the mouth: what it stops drops inside the
            # goal. A ball angled into the side netting met it with its centre 0.06 m past the line, before the
            # whole ball was over (0.17 m), and stopped there, "short" or "post".
            vx, vy, vz, ending, done = 0.0, 0.0, 0.0, IN_NET, True
            scored = True
        elif kind == -2:
            ending, done = ENDED_X_STOP, True
        else:  # kind == -3
            ending, done = OUT, True
        if rolling:  # rolling without slipping, or stopped (by a body, the net): ω = (ẑ × v)/R
            wx, wy, wz = -vy / radius, vx / radius, 0.0
        if kind >= 0:
            for body in (kind, -1 if which2 < 0 else int(caps[which2, 7])):  # both bodies of one impact
                if body < 0:
                    continue
                if n_events < MAX_EVENTS:
                    events[n_events, 0], events[n_events, 1] = t, body
                    events[n_events, 2], events[n_events, 3], events[n_events, 4] = x, y, z
                n_events += 1
            if n_events == 1:
                info[I_FIRST] = t
            kick[GAIN] = 0.0  # the knuckle's unsteady wake is a launch effect; any contact ends it
            _set_spin(kick, wx, wy, wz)
            law = force_law(kick, config)
        if store and n < max_rows:
            _write_spin_sample(t_out, state_out, spin_out, n, t, x, y, z, vx, vy, vz, wx, wy, wz)
        n += 1
        if stop_here and kind < 0:
            ending, done = (STOPPED if not done else ending), True
        if done:
            break
        if n_events >= MAX_EVENTS:
            ending = CONTACTS
            break
        if rolling and vx == 0.0 and vy == 0.0:
            ending = STOPPED
            break
    # Whole ball over the line between the posts and under the bar, at any time (off the post, the bar, the wall
    # or the keeper too), is a goal; then the keeper; then the first of the wall and the frame it struck (a ball off
    # the bar that bounces back into the wall's backs hit the bar: the wall did not block it); then where it crossed
    # the line.
    result = _verdict(pitch, info, radius, scored, touched_keeper, first_body)
    info[I_RESULT] = result
    info[I_EVENTS] = min(n_events, MAX_EVENTS)
    return min(n, max_rows) if store else n, ending


@compiled()
def _forces_along(t_out, state_out, spin_out, n, first, kick, gain, config, forces_out):
    """The forces at each of a played flight's ``n`` samples, into ``forces_out`` (T, 12): each sample's spin, no
    Magnus force while rolling, the knuckle force (``gain``) only before the ``first`` contact (s). Returns whether
    every force is finite."""
    i = 0
    while i < n:  # one call of the force law per run of samples with one spin, on one side of the first contact
        before = t_out[i] < first
        j = i + 1
        while (
            j < n
            and (t_out[j] < first) == before
            and spin_out[j, 0] == spin_out[i, 0]
            and spin_out[j, 1] == spin_out[i, 1]
            and spin_out[j, 2] == spin_out[i, 2]
        ):
            j += 1
        _set_spin(kick, spin_out[i, 0], spin_out[i, 1], spin_out[i, 2])
        kick[GAIN] = gain if before else 0.0
        sample_forces(t_out[i:j], state_out[i:j], kick, config, forces_out[i:j])
        i = j
    for i in range(n):
        if state_out[i, 2] == config[GROUND] and state_out[i, 5] == 0.0 and t_out[i] >= first:
            forces_out[i, 3], forces_out[i, 4], forces_out[i, 5] = 0.0, 0.0, 0.0  # rolling: no lift off the turf
    return np.isfinite(forces_out[:n]).all()


@compiled(from_python=True, nogil=True)
def play_rows(
    start,
    stop,
    launches,
    config,
    pitches,
    which,
    t_out,
    state_out,
    spin_out,
    forces_out,
    events,
    info,
    n_samples,
    endings,
):
    """:func:`play` for kicks ``start`` to ``stop``, without the GIL (threads share a batch:
    :func:`kernels._rows.run_rows`), kick k on pitch ``pitches[which[k]]`` ((P, N_PITCH) and (K,)): its samples into
    row k of ``t_out`` (K, T), ``state_out`` (K, T, 6), ``spin_out`` (K, T, 3) (T = 0: verdicts only, and each flight
    ends once its verdict cannot change) and the forces at them into ``forces_out`` (K, T, 12) (where it has T rows;
    a batch passes (K, 0, 12): no forces), its contacts into ``events`` (K, MAX_EVENTS, 5) and its summary into
    ``info`` (K, N_INFO). One compiled entry serves a single kick (K = 1) and a batch, so the long flight on a pitch
    is compiled into one entry, not two."""
    kick = np.empty(N_KICK)
    with_forces = forces_out.shape[1] > 0
    for k in range(start, stop):
        fill_kick(launches[k], config, kick)
        gain = kick[GAIN]  # play() drops the knuckle force at the first contact
        n, ending = play(
            launches[k], kick, config, pitches[which[k]], t_out[k], state_out[k], spin_out[k], events[k], info[k]
        )
        # A kick not flown (refused, or starting inside a body) keeps its ending, whatever its one sample's drag.
        if with_forces and ending != REFUSED and ending != INSIDE:
            first = info[k, I_FIRST] if not math.isnan(info[k, I_FIRST]) else math.inf
            if not _forces_along(t_out[k], state_out[k], spin_out[k], n, first, kick, gain, config, forces_out[k]):
                ending = DIVERGED
        n_samples[k], endings[k] = n, ending
