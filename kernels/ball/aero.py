"""The force law, compiled: drag and Magnus lift (constant or measured coefficients), the knuckleball's side force,
and gravity.

Scalar cores on the (14,) settings vector of :class:`kernels.ball.config.FlightConfig` and each kick's (14,)
constants (slots :data:`AXIS` … :data:`N2`: ω̂, |ω|, knuckle gain, rate, phases, directions). Accelerations are per
unit mass (m/s²), forces in N. Coefficients: constant C_D and C_L, or the measured model: C_L(S) = 0.9·min(S, 0.3)
(below Asai et al. 2007's wind-tunnel values, Sports Eng. 10) and C_D(Re, S) of Goff & Carré 2010 (Eur. J. Phys. 31),
its drag crisis centred at the configured Reynolds number (1.815·10⁵, their Teamgeist fit); knuckle force after Cohen et al. 2012 and
Texier et al. 2016 (New J. Phys. 18). The model, its assumptions and its sources in full: :mod:`kernels.ball`.
"""

from __future__ import annotations

import math

from kernels.ball.config import (
    C_D,
    C_L,
    GRAVITY,
    GROUND,
    KNUCKLE_COEFFICIENT,
    KNUCKLE_SPIN_LIMIT,
    KNUCKLE_WAVELENGTH_M,
    MASS,
    MEASURED,
    RADIUS,
    RE_CRISIS,
    RE_PER_SPEED,
    RK4,
    T_MAX,
    Q,
)
from kernels.ball.jit import compiled

# Width of the Goff & Carré 2010 no-spin drag fit's crisis, in Reynolds number (its centre is a setting: see
# :data:`kernels.ball.config.DRAG_CRISIS_RE`).
_RE_WIDTH = 1.949e4

# Bounds of the measured fits below (Goff & Carré 2010, Asai et al. 2007): C_D0 lies in (0.155, 0.501), the spinning
# C_D is 0.4127·S^0.3056 (0.165 at S = 0.05, growing with S), C_L at most 0.9·0.3.
_MEASURED_DRAG_MIN = 0.155
_MEASURED_STILL_DRAG_MAX = 0.501
_MEASURED_LIFT_MAX = 0.27
_SPINNING_AT_BLEND = 0.4127 * 0.05**0.3056
"""The spinning C_D at S = 0.05, where the blend from the still fit reaches it (a constant: no power per call)."""

EULER_STABILITY = 2.0
"""Forward Euler's stability interval on the negative real axis, |1 + z| ≤ 1 for z ∈ [−2, 0]."""
RK4_STABILITY = 2.785293563405289
"""Classical RK4's: |1 + z + z²/2 + z³/6 + z⁴/24| ≤ 1 for z ∈ [−2.7853, 0], the real root of z³ + 4z² + 12z + 24
(Hairer & Wanner, Solving ODEs II, 2nd ed. 1996, §IV.2, Fig. 2.1)."""

# Each kick's constants are one row of 14 (beside the settings vector of FlightConfig): ω̂, |ω|, knuckle gain ½ρA·C_K·w/m, rate Ω, phases φ₁ φ₂,
# cos θ·n₁ and sin θ·n₂.
AXIS, RATE, GAIN, OMEGA, PHASE, N1, N2 = 0, 3, 4, 5, 6, 8, 11
N_KICK = 14


# --------------------------------------------------------------------------------------------- force law
@compiled()
def _norm(v):
    """|v| of a (3,) vector without overflow or underflow in the squares (a spin of 1e200 rad/s still has an axis)."""
    scale = max(abs(v[0]), abs(v[1]), abs(v[2]))
    if scale == 0.0 or not math.isfinite(scale):
        return scale
    return scale * math.sqrt((v[0] / scale) ** 2 + (v[1] / scale) ** 2 + (v[2] / scale) ** 2)


@compiled()
def fill_kick(launch, config, kick):
    """One kick's (14,) constants (see the slots above) from its (13,) launch row."""
    velocity, spin, angles = launch[3:6], launch[6:9], launch[9:12]
    rate = _norm(spin)
    kick[:] = 0.0
    if rate > 0.0:
        for i in range(3):
            kick[AXIS + i] = spin[i] / rate
    kick[RATE] = rate
    speed = _norm(velocity)
    if launch[12] == 0.0 or speed == 0.0:
        return
    weight = max(0.0, 1.0 - config[RADIUS] * rate / speed / KNUCKLE_SPIN_LIMIT)
    ux, uy, uz = velocity[0] / speed, velocity[1] / speed, velocity[2] / speed
    hx, hy = -uy, ux  # horizontal normal to the launch direction
    length = math.sqrt(hx * hx + hy * hy)
    if length < 1e-9:  # kicked straight up: any horizontal direction will do
        hx, hy, length = 0.0, 1.0, 1.0
    hx, hy = hx / length, hy / length
    vertical = (-uz * hy, uz * hx, ux * hy - uy * hx)  # u × h
    theta = angles[0]
    kick[GAIN] = config[Q] * KNUCKLE_COEFFICIENT * weight
    kick[OMEGA] = 2.0 * math.pi * speed / KNUCKLE_WAVELENGTH_M
    kick[PHASE], kick[PHASE + 1] = angles[1], angles[2]
    kick[N1], kick[N1 + 1] = math.cos(theta) * hx, math.cos(theta) * hy
    for i in range(3):
        kick[N2 + i] = math.sin(theta) * vertical[i]


@compiled()
def max_stable_step(launch, kick, config):
    """(longest stable dt (s), fastest speed bound (m/s)) of one kick: its launch row, constants and the settings.

    The acceleration's velocity-dependent part a(v) = |v|·(−k_D·v + k_L·ω̂ × v + knuckle), k = ½ρA·C/m, has the
    Jacobian ∂a/∂v; for drag alone its eigenvalues are −k_D|v| (twice, across the motion) and −2k_D|v| (along it).
    A fixed-step method stays stable while every λ·dt lies in its stability region; on the negative real axis that
    is z ∈ [−β, 0] with β = 2 for forward Euler and 2.7853 for RK4 (:data:`EULER_STABILITY`, :data:`RK4_STABILITY`).
    So dt ≤ β / (2·k·|v|), with k the sum of the drag, lift and knuckle factors' bounds (the lift's and knuckle's
    magnitudes rotate the velocity but add to ‖∂a/∂v‖ ≤ 2k|v|). For Euler and drag alone this is k_D·|v|·dt ≤ 1: a
    step never reverses the velocity (v·(1 − k_D|v|dt)); past 2 the error grows every step. With C_L ≤ (1 + √2)·C_D
    (both models' defaults) the bound also keeps Euler's Magnus pair −k_D|v| ± i·k_L|v| in |1 + z| ≤ 1.

    |v| is the fastest the ball can fly: drag and Magnus do no positive work, so with damping c = k_D,min − k_K > 0
    the speed never passes max(|v₀|, √(|g|/c)) (d|v|²/dt ≤ 2|v|(|g| − c|v|²)) nor, under downward gravity,
    √(|v₀|² + 2g·(z₀ − ground)) (|v|² + 2gz never grows); and never |v₀| + |g|·t_max. The measured C_D's bound at
    that speed is max(0.501, 0.4127·max(S, 0.05)^0.3056), S = r|ω|/|v| (C_D·|v| grows with |v| under both fits).
    """
    q, g = config[Q], config[GRAVITY]
    speed = _norm(launch[3:6])
    knuckle = kick[GAIN]  # ½ρA·C_K·w/m, zero without the knuckle force
    if config[MEASURED] == 0.0:
        damping = q * config[C_D] - knuckle
    else:
        damping = q * _MEASURED_DRAG_MIN - knuckle
    fastest = speed + abs(g) * config[T_MAX]
    if damping > 0.0:
        fastest = min(fastest, max(speed, math.sqrt(abs(g) / damping)))
        if g > 0.0:
            height = max(launch[2] - config[GROUND], 0.0)
            fastest = min(fastest, math.sqrt(speed * speed + 2.0 * g * height))
    if config[MEASURED] == 0.0:
        drag, lift = config[C_D], config[C_L]
    else:
        spin_parameter = config[RADIUS] * kick[RATE] / max(fastest, 1e-9)
        drag = max(_MEASURED_STILL_DRAG_MAX, 0.4127 * max(spin_parameter, 0.05) ** 0.3056)
        lift = _MEASURED_LIFT_MAX
    if kick[RATE] == 0.0:
        lift = 0.0  # no spin, no Magnus force
    rate = (q * (drag + lift) + knuckle) * fastest  # 1/s, ≥ ‖∂a/∂v‖ / 2
    beta = RK4_STABILITY if config[RK4] != 0.0 else EULER_STABILITY
    return (beta / (2.0 * rate) if rate > 0.0 else math.inf), fastest


@compiled()
def drag_lift(speed, rate, measured, constant_drag, constant_lift, radius, re_per_speed, re_crisis):
    """(C_D, C_L) of a ball at ``speed`` (m/s, ≥ 0) spinning at ``rate`` = |ω| (rad/s, ≥ 0): ``constant_drag`` and
    ``constant_lift`` when ``measured`` is 0, else the measured fits C_D(Re, S) of Goff & Carré 2010 (Eur. J. Phys. 31),
    its drag crisis centred at Re = ``re_crisis``, and C_L(S) = 0.9·min(S, 0.3), with S = ``radius``·|ω|/max(|v|,
    10⁻⁹ m/s) and Re = ``re_per_speed``·|v| (ρ·2r/μ). The flight's force law and the public :func:`kernels.ball.coefficients` both
    call this one function. Plain scalars, not the settings vector: an array argument costs the flight's every force
    evaluation a reference-count increment and decrement."""
    if measured == 0.0:
        return constant_drag, constant_lift
    spin_parameter = radius * rate / max(speed, 1e-9)
    lift = 0.9 * min(spin_parameter, 0.3)  # below Asai et al. 2007's wind-tunnel values: see kernels.ball
    if spin_parameter >= 0.05:  # the spinning fit alone (the blend's weight is 1): no exponential to evaluate
        return 0.4127 * spin_parameter**0.3056, lift  # Goff & Carré 2010
    arg = min((re_per_speed * speed - re_crisis) / _RE_WIDTH, 50.0)
    still = 0.155 + 0.346 / (1.0 + math.exp(arg))  # Goff & Carré 2010
    return still + (spin_parameter / 0.05) * (_SPINNING_AT_BLEND - still), lift


@compiled()
def drag_lift_table(speeds, rates, config, drag, lift):
    """:func:`drag_lift` at each of the (N,) ``speeds`` and ``rates`` under the (14,) settings' model, into the (N,)
    ``drag`` and ``lift``."""
    measured, c_d, c_l = config[MEASURED], config[C_D], config[C_L]
    radius, re_per_speed, re_crisis = config[RADIUS], config[RE_PER_SPEED], config[RE_CRISIS]
    for i in range(len(speeds)):
        drag[i], lift[i] = drag_lift(speeds[i], rates[i], measured, c_d, c_l, radius, re_per_speed, re_crisis)


@compiled(inline="always")
def configured_drag_lift(speed, rate, config):
    """:func:`drag_lift` under the (14,) settings' model: the force law's and the rolling ball's coefficients.

    Inlined into its callers, so reading the settings here costs what reading them there did.
    """
    return drag_lift(
        speed,
        rate,
        config[MEASURED],
        config[C_D],
        config[C_L],
        config[RADIUS],
        config[RE_PER_SPEED],
        config[RE_CRISIS],
    )


@compiled()
def _factors(speed, kick, config):
    """(−½ρA·C_D·|v|/m, ½ρA·C_L·|v|/m) at this speed: drag and lift per unit velocity and mass (1/s)."""
    q = config[Q]
    drag, lift = configured_drag_lift(speed, kick[RATE], config)
    return -q * drag * speed, q * lift * speed


@compiled()
def _knuckle(speed, t, kick):
    """Knuckle side force per unit mass (m/s², 3 values); zero when the kick has none."""
    gain = kick[GAIN]
    if gain == 0.0:
        return 0.0, 0.0, 0.0
    kk = gain * speed * speed
    s1 = kk * math.sin(kick[OMEGA] * t + kick[PHASE])
    s2 = kk * math.sin(kick[OMEGA] * t + kick[PHASE + 1])
    return (
        s1 * kick[N1] + s2 * kick[N2],
        s1 * kick[N1 + 1] + s2 * kick[N2 + 1],
        s1 * kick[N1 + 2] + s2 * kick[N2 + 2],
    )


@compiled()
def acceleration(vx, vy, vz, t, kick, config):
    """Total acceleration (m/s²): drag, Magnus (ω̂ × v), knuckle and gravity."""
    speed = math.sqrt(vx * vx + vy * vy + vz * vz)
    kd, kl = _factors(speed, kick, config)
    wx, wy, wz = kick[AXIS], kick[AXIS + 1], kick[AXIS + 2]
    sx, sy, sz = _knuckle(speed, t, kick)
    return (
        kd * vx + kl * (wy * vz - wz * vy) + sx,
        kd * vy + kl * (wz * vx - wx * vz) + sy,
        kd * vz + kl * (wx * vy - wy * vx) + sz - config[GRAVITY],
    )


@compiled()
def sample_forces(t, state, kick, config, forces):
    """Drag, Magnus, gravity and knuckle forces (N) at each sample: ``forces`` (N, 12) from ``state`` (N, 6)."""
    m = config[MASS]
    wx, wy, wz = kick[AXIS], kick[AXIS + 1], kick[AXIS + 2]
    for i in range(len(t)):
        vx, vy, vz = state[i, 3], state[i, 4], state[i, 5]
        speed = math.sqrt(vx * vx + vy * vy + vz * vz)
        kd, kl = _factors(speed, kick, config)
        sx, sy, sz = _knuckle(speed, t[i], kick)
        forces[i, 0], forces[i, 1], forces[i, 2] = m * kd * vx, m * kd * vy, m * kd * vz
        forces[i, 3] = m * kl * (wy * vz - wz * vy)
        forces[i, 4] = m * kl * (wz * vx - wx * vz)
        forces[i, 5] = m * kl * (wx * vy - wy * vx)
        forces[i, 6], forces[i, 7], forces[i, 8] = 0.0, 0.0, -m * config[GRAVITY]
        forces[i, 9], forces[i, 10], forces[i, 11] = m * sx, m * sy, m * sz
