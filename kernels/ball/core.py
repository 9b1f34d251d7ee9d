"""The compiled flight and its verdict: Euler or RK4 steps, the Hermite end of a flight, plane crossings, the judge.

A flight writes its samples' times (T,) and states (T, 6: position then velocity, m and m/s) into buffers the caller
gives; a batch runs its K kicks, a range of them per thread, into (T, K) and (T, K, 6) time-major buffers. Each flight
ends with a code in :data:`ENDINGS` order (3: diverged; 4: not flown, its step beyond the method's stability limit;
9: not flown, the ball starts inside a body of the pitch), each verdict with one in :data:`RESULTS` order. Crossings
are the first root of the cubic Hermite interpolant of the step (:func:`crossing_fraction`). Method and assumptions:
:mod:`kernels.ball`.
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np

from kernels._jit import compiled
from kernels.ball.aero import N_KICK, acceleration, fill_kick, force_law, max_stable_step, sample_forces
from kernels.ball.config import DT, GRAVITY, GROUND, N_STEPS, RADIUS, RK4, T_MAX, X_STOP

Ending = Literal["ground", "x_stop", "t_max", "stopped", "net", "out", "saved", "contacts"]
Result = Literal["goal", "wall", "over", "wide", "short", "post", "bar", "saved"]

# Codes of the compiled flight's ending (3 diverged, 4 refused and 9 started inside a body raise; 5–10 only on a
# pitch, kernels.ball.play) and of its verdict (5–7 only on a pitch).
ENDINGS: tuple[str, ...] = (
    "ground",
    "x_stop",
    "t_max",
    "diverged",
    "refused",
    "stopped",
    "net",
    "out",
    "saved",
    "inside",
    "contacts",
)
RESULTS: tuple[Result, ...] = ("goal", "wall", "over", "wide", "short", "post", "bar", "saved")


# --------------------------------------------------------------------------------------------- flight
@compiled(inline="always")
def _step(x, y, z, vx, vy, vz, t, dt, law, rk4):
    """One step of length ``dt``, RK4 if ``rk4`` else Euler, under the kick's force law: (x, y, z, vx, vy, vz)
    after it."""
    if not rk4:  # the textbook Euler: velocity first, then position with the new velocity
        ax, ay, az, _, _ = acceleration(vx, vy, vz, t, law, 0.0, 0.0)
        vx1, vy1, vz1 = vx + ax * dt, vy + ay * dt, vz + az * dt
        return x + vx1 * dt, y + vy1 * dt, z + vz1 * dt, vx1, vy1, vz1
    half, sixth = 0.5 * dt, dt / 6.0
    # The acceleration does not depend on position, so each stage's position slope is its velocity. The later
    # stages take the drag from the first's where their speed is near it (the same value, without exp and log).
    a1x, a1y, a1z, speed2, drag = acceleration(vx, vy, vz, t, law, 0.0, 0.0)
    inverse2 = 1.0 / speed2 if drag > 0.0 else 0.0
    v2x, v2y, v2z = vx + half * a1x, vy + half * a1y, vz + half * a1z
    a2x, a2y, a2z, _, _ = acceleration(v2x, v2y, v2z, t + half, law, inverse2, drag)
    v3x, v3y, v3z = vx + half * a2x, vy + half * a2y, vz + half * a2z
    a3x, a3y, a3z, _, _ = acceleration(v3x, v3y, v3z, t + half, law, inverse2, drag)
    v4x, v4y, v4z = vx + dt * a3x, vy + dt * a3y, vz + dt * a3z
    a4x, a4y, a4z, _, _ = acceleration(v4x, v4y, v4z, t + dt, law, inverse2, drag)
    return (
        x + sixth * (vx + 2.0 * (v2x + v3x) + v4x),
        y + sixth * (vy + 2.0 * (v2y + v3y) + v4y),
        z + sixth * (vz + 2.0 * (v2z + v3z) + v4z),
        vx + sixth * (a1x + 2.0 * (a2x + a3x) + a4x),
        vy + sixth * (a1y + 2.0 * (a2y + a3y) + a4y),
        vz + sixth * (a1z + 2.0 * (a2z + a3z) + a4z),
    )


@compiled()
def _hermite(p0, v0, p1, v1, h, s):
    """Cubic Hermite value and derivative (per unit time) at fraction ``s`` of a step of length ``h``.

    The value is written as p0 + (p1 − p0)·(3s² − 2s³) + slope terms, so a coordinate constant over the step
    (p0 = p1, no velocity) comes back exactly, whatever s; s = 0 and s = 1 give the samples exactly.
    """
    s2, s3 = s * s, s * s * s
    if s <= 0.0:
        value = p0
    elif s >= 1.0:
        value = p1
    else:
        value = p0 + (p1 - p0) * (3 * s2 - 2 * s3) + h * ((s3 - 2 * s2 + s) * v0 + (s3 - s2) * v1)
    slope = (
        (6 * s2 - 6 * s) * p0 + (3 * s2 - 4 * s + 1) * h * v0 + (6 * s - 6 * s2) * p1 + (3 * s2 - 2 * s) * h * v1
    ) / h
    return value, slope


@compiled()
def _cubic_value(d0, dd0, d1, dd1, h, s):
    value, _ = _hermite(d0, dd0, d1, dd1, h, s)
    return value


@compiled()
def crossing_fraction(d0, dd0, d1, dd1, h):
    """First fraction s ∈ [0, 1] of a step where the cubic Hermite through (d0, dd0) and (d1, dd1) reaches zero.

    Call with ``d0 ≥ 0 ≥ d1`` (the far side of the plane is negative). ``d0 < 0``, or ``d0 = 0`` moving onto the
    far side or along the plane (``dd0 ≤ 0``), gives 0; ``d0 = 0`` moving away (a kick from the ground) looks for
    the later root. The cubic's turning points split [0, 1] into monotone pieces; the first piece whose end is ≤ 0
    brackets the first root, which a safeguarded Newton iteration (bisection whenever a Newton step leaves the
    bracket) finds to rounding. A ball that rises and lands within one step so finds its landing, not the launch
    (a linear guess plus bare Newton stalled at s = 0 there).
    """
    if d0 < 0.0 or (d0 == 0.0 and dd0 <= 0.0):
        return 0.0
    m0, m1 = h * dd0, h * dd1
    # p(s) = a s³ + b s² + m0 s + d0, p'(s) = 3a s² + 2b s + m0.
    a = 2.0 * d0 + m0 - 2.0 * d1 + m1
    b = -3.0 * d0 - 2.0 * m0 + 3.0 * d1 - m1
    c1, c2 = 2.0, 2.0  # turning points in (0, 1), ascending; 2.0 means none
    qa, qb, qc = 3.0 * a, 2.0 * b, m0
    if qa != 0.0:
        disc = qb * qb - 4.0 * qa * qc
        if disc >= 0.0:
            root = math.sqrt(disc)
            q = -0.5 * (qb + math.copysign(root, qb))
            r1 = q / qa
            r2 = qc / q if q != 0.0 else r1
            lo_r, hi_r = min(r1, r2), max(r1, r2)
            if 0.0 < lo_r < 1.0:
                c1 = lo_r
            if 0.0 < hi_r < 1.0:
                if c1 == 2.0:
                    c1 = hi_r
                else:
                    c2 = hi_r
    elif qb != 0.0:
        r = -qc / qb
        if 0.0 < r < 1.0:
            c1 = r
    lo, hi = 0.0, 1.0
    for edge in (c1, c2, 1.0):
        if edge > 1.0:
            continue
        if edge == 1.0 or _cubic_value(d0, dd0, d1, dd1, h, edge) <= 0.0:
            hi = edge
            break
        lo = edge
    # p(lo) > 0 ≥ p(hi) and p is monotone on [lo, hi].
    s = 0.5 * (lo + hi)
    for _ in range(80):
        value, slope = _hermite(d0, dd0, d1, dd1, h, s)
        if value == 0.0:
            return s
        if value > 0.0:
            lo = s
        else:
            hi = s
        slope *= h  # per unit s
        trial = s - value / slope if slope != 0.0 else -1.0
        if not lo < trial < hi:
            trial = 0.5 * (lo + hi)
        if trial == s or hi - lo <= 1e-16:
            break
        s = trial
    return s


@compiled(inline="always")
def _energy_limit(vx, vy, vz, z, g):
    """Bound on |v|² + 2gz past which a flight launched at (vx, vy, vz) from height ``z`` has diverged (m²/s²).

    Drag dissipates and Magnus does no work, so |v|² + 2gz never grows but for the knuckle force's small push; a
    step that overshoots the drag makes it grow without bound. The stability limit refuses such a step before the
    flight; this guard stays for what it does not bound (Euler with much lift and little drag).
    """
    speed2 = vx * vx + vy * vy + vz * vz
    return (speed2 + 2.0 * g * z) + (3.0 * (speed2 + 2.0 * abs(g) * (abs(z) + 1.0)) + 100.0)


@compiled(inline="always")
def _write_sample(t_out, state_out, n, t, x, y, z, vx, vy, vz):
    """Sample ``n``: its time into ``t_out`` (T,), its position then velocity into ``state_out`` (T, 6)."""
    t_out[n] = t
    state_out[n, 0], state_out[n, 1], state_out[n, 2] = x, y, z
    state_out[n, 3], state_out[n, 4], state_out[n, 5] = vx, vy, vz


@compiled()
def _fly(launch, kick, config, t_out, state_out):
    """Step one kick (its (13,) launch row and (14,) constants) until it lands, passes ``x_stop`` or runs out of time.

    Writes each sample's time to ``t_out`` (T,) and position then velocity to ``state_out`` (T, 6), T ≥ n_steps + 1;
    with T = 0 it only counts.

    Returns:
        (samples written, ending code: 0 ground, 1 x_stop, 2 t_max, 3 diverged: gained energy, or inf/NaN; 4 not
        flown: dt exceeds :func:`~kernels.ball.aero.max_stable_step`, only the launch sample written).
    """
    store = len(t_out) > 0
    dt, ground, x_stop = config[DT], config[GROUND], config[X_STOP]
    refused = dt > max_stable_step(launch, kick, config, 0.0)[0]
    n_steps = int(config[N_STEPS])
    x, y, z, vx, vy, vz = launch[0], launch[1], launch[2], launch[3], launch[4], launch[5]
    g = config[GRAVITY]
    energy_limit = _energy_limit(vx, vy, vz, z, g)
    if store:
        _write_sample(t_out, state_out, 0, 0.0, x, y, z, vx, vy, vz)
    if refused:
        return 1, 4
    t_max = config[T_MAX]
    law, rk4 = force_law(kick, config), config[RK4] != 0.0
    for n in range(n_steps):
        # Every step is dt but the last, which ends exactly on t_max.
        h = dt if n < n_steps - 1 else t_max - (n_steps - 1) * dt
        x1, y1, z1, vx1, vy1, vz1 = _step(x, y, z, vx, vy, vz, n * dt, h, law, rk4)
        if vx1 * vx1 + vy1 * vy1 + vz1 * vz1 + 2.0 * g * z1 > energy_limit:
            return n + 1, 3
        # The stop plane is closed on the start side: a kick launched on it, moving on, stops at t = 0.
        hit_ground = z1 <= ground
        hit_stop = x < x_stop <= x1 or (n == 0 and x == x_stop and x1 > x)
        if hit_ground or hit_stop:
            # End on whichever of the ground and the stop plane the cubic through this step reaches first.
            f_ground = crossing_fraction(z - ground, vz, z1 - ground, vz1, h) if hit_ground else np.inf
            f_stop = crossing_fraction(x_stop - x, -vx, x_stop - x1, -vx1, h) if hit_stop else np.inf
            ending = 0 if f_ground <= f_stop else 1
            f = min(f_ground, f_stop)
            ex, evx = _hermite(x, vx, x1, vx1, h, f)
            ey, evy = _hermite(y, vy, y1, vy1, h, f)
            ez, evz = _hermite(z, vz, z1, vz1, h, f)
            if ending == 0:
                ez = ground
            else:
                ex = x_stop
            if not math.isfinite(ex + ey + ez + evx + evy + evz):  # inf or NaN (or ~1e308)
                ending = 3
            if store:
                _write_sample(t_out, state_out, n + 1, n * dt + f * h, ex, ey, ez, evx, evy, evz)
            return n + 2, ending
        x, y, z, vx, vy, vz = x1, y1, z1, vx1, vy1, vz1
        if store:
            _write_sample(t_out, state_out, n + 1, (n + 1) * dt if n < n_steps - 1 else t_max, x, y, z, vx, vy, vz)
    # A state that overflowed stays inf or NaN to the end (NaN fails the ground test, so it runs to t_max).
    return n_steps + 1, 2 if math.isfinite(x + y + z + vx + vy + vz) else 3


@compiled(from_python=True)
def simulate_one(launch, config, t_out, state_out, forces_out):
    """:func:`simulate`'s compiled part: the kick's constants, its flight and the forces along it."""
    kick = np.empty(N_KICK)
    fill_kick(launch, config, kick)
    # Strided views ([::1] types as any layout), as fly_rows hands it a batch's columns: one compiled _fly.
    n, ending = _fly(launch, kick, config, t_out[::1], state_out[::1])
    sample_forces(t_out[:n], state_out[:n], kick, config, forces_out[:n])
    # A finite flight with an infinite force (a 1e-300 kg ball) diverged; a kick not flown (ending 4: its one
    # sample's drag may overflow, |v| = 1e200 m/s) keeps its ending, as in a batch.
    if ending < 3 and not np.isfinite(forces_out[:n]).all():
        ending = 3
    return n, ending


@compiled(from_python=True)
def stable_step(launch, config, spin_inertia):
    """(longest stable dt (s), fastest speed bound (m/s)) of one kick's (13,) launch row: what ending 4 compared
    (``spin_inertia``: α·R² (m²) on a pitch, 0 in free flight; see :func:`~kernels.ball.aero.max_stable_step`)."""
    kick = np.empty(N_KICK)
    fill_kick(launch, config, kick)
    return max_stable_step(launch, kick, config, spin_inertia)


@compiled(from_python=True, nogil=True)
def fly_rows(start, stop, launches, config, t_out, state_out, n_samples, endings):
    """Kicks ``start`` to ``stop`` of a batch, each flight into column k of ``t_out`` (T, K) and ``state_out``
    (T, K, 6); without the GIL, so threads share a batch (:func:`kernels._rows.run_rows`).

    T must hold each flight (n_steps + 1 always does); with T = 0 it only counts the samples.
    """
    kick = np.empty(N_KICK)
    for k in range(start, stop):
        fill_kick(launches[k], config, kick)
        n_samples[k], endings[k] = _fly(launches[k], kick, config, t_out[:, k], state_out[:, k])


@compiled(from_python=True, nogil=True)
def pad(t, state, n_samples):
    """Repeat each flight's last sample to the end of ``t`` (T, K) and ``state`` (T, K, 6)."""
    for k in range(len(n_samples)):
        last = n_samples[k] - 1
        for i in range(last + 1, t.shape[0]):
            t[i, k] = t[last, k]
            for c in range(6):
                state[i, k, c] = state[last, k, c]


# --------------------------------------------------------------------------------------------- outcome
@compiled()
def _plane_crossing(t, position, velocity, n, panel, crossing):
    """First crossing of a panel's plane in its normal direction among the first ``n`` samples.

    ``panel`` is (6,): centre x, y, unit normal x, y, width, height. Writes (time, x, y, z) to ``crossing`` (4,),
    NaN if there is none.
    """
    cx, cy, nx, ny = panel[0], panel[1], panel[2], panel[3]
    crossing[:] = np.nan
    d1 = (position[0, 0] - cx) * nx + (position[0, 1] - cy) * ny
    for i in range(n - 1):
        d0, d1 = d1, (position[i + 1, 0] - cx) * nx + (position[i + 1, 1] - cy) * ny
        # Closed on the start side: a ball launched on the plane and moving through it crosses at t = 0.
        if d0 < 0.0 <= d1 or (i == 0 and d0 == 0.0 and d1 > 0.0):
            h = t[i + 1] - t[i]
            h = h if h > 0.0 else 1.0
            dd0 = velocity[i, 0] * nx + velocity[i, 1] * ny
            dd1 = velocity[i + 1, 0] * nx + velocity[i + 1, 1] * ny
            s = crossing_fraction(-d0, -dd0, -d1, -dd1, h)
            crossing[0] = t[i] + s * h
            for c in range(3):
                p0, v0, p1, v1 = (position[i, c], velocity[i, c], position[i + 1, c], velocity[i + 1, c])
                crossing[1 + c], _ = _hermite(p0, v0, p1, v1, h, s)
            return


@compiled(from_python=True)
def judge(t, position, velocity, n, panels, radius, crossings):
    """Result code (0 goal, 1 wall, 2 over, 3 wide, 4 short) of one flight's first ``n`` samples.

    ``panels`` (2, 6) are the wall and the goal; their crossings (time, x, y, z) go to ``crossings`` (2, 4).
    """
    for j in range(2):
        _plane_crossing(t, position, velocity, n, panels[j], crossings[j])
    # Offset of each crossing along its panel from the centre line (along = (−n_y, n_x)); NaN when none.
    wall, goal = panels[0], panels[1]
    wall_lateral = -(crossings[0, 1] - wall[0]) * wall[3] + (crossings[0, 2] - wall[1]) * wall[2]
    goal_lateral = -(crossings[1, 1] - goal[0]) * goal[3] + (crossings[1, 2] - goal[1]) * goal[2]
    # Every edge is closed (touching counts). A coordinate that stays constant over the crossing step comes out of
    # _hermite exactly, so a ball exactly on an edge gets the same verdict however its flight was sampled.
    # The ball touches the wall if its centre comes within a radius of the defenders' outline.
    if abs(wall_lateral) <= 0.5 * wall[4] + radius and crossings[0, 3] <= wall[5] + radius:
        return 1
    if np.isnan(crossings[1, 0]):
        return 4
    if abs(goal_lateral) > 0.5 * goal[4] - radius:
        return 3
    # A goal needs the whole ball inside the posts and under the bar (touching them from inside counts).
    return 0 if crossings[1, 3] <= goal[5] - radius else 2


@compiled(from_python=True, nogil=True)
def judge_rows(start, stop, t, position, velocity, n_samples, panels, radius, results, crossings):
    """:func:`judge` for flights ``start`` to ``stop`` of a (K, T) batch, without the GIL (threads share a batch)."""
    for k in range(start, stop):
        results[k] = judge(t[k], position[k], velocity[k], n_samples[k], panels, radius, crossings[k])


@compiled(from_python=True, nogil=True)
def fly_and_judge_rows(start, stop, launches, config, panels, results, crossings, endings):
    """Fly kicks ``start`` to ``stop`` each into a scratch buffer and judge it at once (ball radius from ``config``):
    nothing kept. Without the GIL (threads share a batch)."""
    rows = int(config[N_STEPS]) + 1
    kick, t, state = np.empty(N_KICK), np.empty(rows), np.empty((rows, 6))
    for k in range(start, stop):
        fill_kick(launches[k], config, kick)
        n, endings[k] = _fly(launches[k], kick, config, t[::1], state[::1])  # any layout: as simulate_one
        results[k] = judge(t[::1], state[:, :3], state[:, 3:], n, panels, config[RADIUS], crossings[k])
