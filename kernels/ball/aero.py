"""The force law, compiled: drag and Magnus lift (constant or measured coefficients), the knuckleball's side force,
and gravity.

Scalar cores on the (14,) settings vector of :class:`kernels.ball.config.FlightConfig` and each kick's (14,)
constants (slots :data:`AXIS` … :data:`N2`: ω̂, |ω|, knuckle gain, rate, phases, directions). Accelerations are per
unit mass (m/s²), forces in N. Coefficients: constant C_D and C_L, or the measured model: C_L(S) = 0.9·min(S, 0.3)
(below Asai et al. 2007's wind-tunnel values, Sports Eng. 10) and C_D(Re, S) of Goff & Carré 2010 (Eur. J. Phys. 31),
its drag crisis centred at the configured Reynolds number (1.815·10⁵, their Teamgeist fit); knuckle force after Cohen et
al. 2012 and Texier et al. 2016 (New J. Phys. 18). The model, its assumptions and its sources in full:
:mod:`kernels.ball`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from kernels._jit import compiled
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
    SLOW_SPEED_MS,
    T_MAX,
    Q,
)

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
_SLOW2 = SLOW_SPEED_MS * SLOW_SPEED_MS
"""|v|² (m²/s²) below which the measured coefficients are held at their value at :data:`SLOW_SPEED_MS`."""

EULER_STABILITY = 2.0
"""Forward Euler's stability interval on the negative real axis, |1 + z| ≤ 1 for z ∈ [−2, 0]."""
RK4_STABILITY = 2.785293563405289
"""Classical RK4's: |1 + z + z²/2 + z³/6 + z⁴/24| ≤ 1 for z ∈ [−2.7853, 0], the real root of z³ + 4z² + 12z + 24
(Hairer & Wanner, Solving ODEs II, 2nd ed. 1996, §IV.2, Fig. 2.1)."""

# Each kick's constants are one row of 14 (beside the settings vector of FlightConfig): ω̂, |ω|, knuckle gain
# ½ρA·C_K·w/m, rate Ω, phases φ₁ φ₂, cos θ·n₁ and sin θ·n₂.
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
def max_stable_step(launch, kick, config, spin_inertia):
    """(longest stable dt (s), fastest speed bound (m/s)) of one kick: its launch row, constants and the settings;
    ``spin_inertia`` α·R² (m²) of the ball on a pitch, 0 for a flight that meets nothing.

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

    On a pitch a bounce can turn the spin's energy into speed (per unit mass ½α·R²·|ω|², α·R² = ``spin_inertia``),
    and can spin up a ball launched without spin; so there the bound adds 2·√(α·R²)·|ω₀| in quadrature, the
    margin of :func:`kernels.ball.play.play`'s energy guard, and the lift counts whatever the launch spin.
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
    if spin_inertia > 0.0 and kick[RATE] > 0.0:
        fastest = math.hypot(fastest, 2.0 * math.sqrt(spin_inertia) * kick[RATE])
    if config[MEASURED] == 0.0:
        drag, lift = config[C_D], config[C_L]
    else:
        spin_parameter = config[RADIUS] * kick[RATE] / max(fastest, SLOW_SPEED_MS)
        drag = max(_MEASURED_STILL_DRAG_MAX, 0.4127 * max(spin_parameter, 0.05) ** 0.3056)
        lift = _MEASURED_LIFT_MAX
    if kick[RATE] == 0.0 and spin_inertia == 0.0:
        lift = 0.0  # no spin, no Magnus force (on a pitch a bounce may spin the ball up)
    rate = (q * (drag + lift) + knuckle) * fastest  # 1/s, ≥ ‖∂a/∂v‖ / 2
    beta = RK4_STABILITY if config[RK4] != 0.0 else EULER_STABILITY
    return (beta / (2.0 * rate) if rate > 0.0 else math.inf), fastest


@compiled()
def drag_lift_speeds(speed2, rate, measured, constant_drag, constant_lift, radius, re_per_speed, re_crisis):
    """(C_D·|v|, C_L·|v|) in m/s of a ball with squared speed ``speed2`` = |v|² (m²/s², ≥ 0) spinning at ``rate`` =
    |ω| (rad/s, ≥ 0): ``constant_drag`` and ``constant_lift`` times |v| when ``measured`` is 0, else the measured fits
    C_D(Re, S) of Goff & Carré 2010 (Eur. J. Phys. 31), its drag crisis centred at Re = ``re_crisis``, and
    C_L(S) = 0.9·min(S, 0.3), with S = ``radius``·|ω|/|v| and Re = ``re_per_speed``·|v| (ρ·2r/μ); below
    :data:`~kernels.ball.config.SLOW_SPEED_MS` (1 m/s) the measured C_D and C_L are held at their value there (so
    S = r·|ω|/max(|v|, 1 m/s), the spin parameter the launch check bounds), and C·|v| goes to zero with |v|.

    The one implementation of the law: the flight's force law (through :func:`_drag_lift_spin`, with the spin's
    logarithm taken once per :class:`ForceLaw`), the rolling ball and the public :func:`kernels.ball.coefficients`
    (through :func:`drag_lift`) all come here.
    """
    spin_speed = radius * rate  # r|ω| (m/s): S·|v|
    drag, lift, _ = _drag_lift_spin(
        speed2,
        spin_speed,
        _spin_term(spin_speed),
        measured,
        constant_drag,
        constant_lift,
        re_per_speed,
        re_crisis,
        0.0,
        0.0,
    )
    return drag, lift


@compiled()
def _spin_term(spin_speed):
    """0.3056·ln(r|ω|), the spinning C_D fit's spin factor as a logarithm (−∞ without spin, where it is unused)."""
    return 0.3056 * math.log(spin_speed) if spin_speed > 0.0 else -math.inf


_SPINNING_POWER = 0.3472
"""The spinning C_D fit's C_D·|v| = 0.4127·(r|ω|)^0.3056·(|v|²)^0.3472 grows as this power of the squared speed."""
_NEAR = 1.0 / 32.0
"""How far (relative) a squared speed may lie from a reference for :func:`_spinning_drag_near`'s series."""


def _binomial_series(power: float, terms: int) -> tuple[float, ...]:
    """The coefficients C(power, k), k = 1 … ``terms``, of (1 + r)^power = 1 + Σ C(power, k)·r^k."""
    coefficients, c = [], 1.0
    for k in range(1, terms + 1):
        c *= (power - k + 1) / k
        coefficients.append(c)
    return tuple(coefficients)


# (1 + r)^0.3472 to 9 terms: for |r| ≤ 1/32 the first term left out, |C(0.3472, 10)|·r¹⁰ ≤ 0.012·2⁻⁵⁰, is below
# 2⁻⁵³ (half an ulp), so the series is as exact as the exponential it stands for.
_S1, _S2, _S3, _S4, _S5, _S6, _S7, _S8, _S9 = _binomial_series(_SPINNING_POWER, 9)


@compiled()
def _spinning_drag_near(speed2, inverse_reference2, reference_drag):
    """The spinning fit's C_D·|v| (m/s) at squared speed ``speed2`` from its value ``reference_drag`` at a squared
    speed 1/``inverse_reference2``, where |speed2·inverse_reference2 − 1| ≤ 1/32: reference_drag·(1 + r)^0.3472 by
    its binomial series (no exponential, no logarithm; in Estrin's order, whose few dependent steps an RK4 stage
    waits on less than nine in a row). NaN where the speed lies farther out (the caller then takes the exponential).
    """
    r = speed2 * inverse_reference2 - 1.0
    if not abs(r) <= _NEAR:
        return math.nan
    r2 = r * r
    r4 = r2 * r2
    low = (1.0 + _S1 * r) + r2 * (_S2 + _S3 * r)
    high = (_S4 + _S5 * r) + r2 * (_S6 + _S7 * r)
    return reference_drag * ((low + r4 * high) + (r4 * r4) * (_S8 + _S9 * r))


@compiled()
def _drag_lift_spin(
    speed2,
    spin_speed,
    spin_term,
    measured,
    constant_drag,
    constant_lift,
    re_per_speed,
    re_crisis,
    inverse_reference2,
    reference_drag,
):
    """:func:`drag_lift_speeds` given r|ω| = ``spin_speed`` (m/s) and ``spin_term`` = :func:`_spin_term` of it, and
    a nearby state's 1/|v|² (s²/m²) and spinning-fit C_D·|v| (m/s; 0 where that state was not under the spinning
    fit, or for none): (C_D·|v|, C_L·|v|, this state's spinning-fit C_D·|v| or 0).

    Written for the force law, whose four evaluations an RK4 step makes one after another, each waiting on the
    last: with the spinning fit (S ≥ 0.05) C_D·|v| = 0.4127·(r|ω|)^0.3056·(|v|²)^0.3472
    = 0.4127·exp(``spin_term`` + 0.3472·ln |v|²), one logarithm and one exponential of |v|² with no square root or
    division before them (the spin's logarithm is the kick's, taken once); where ``reference_drag`` > 0 and |v|²
    lies within 1/32 of the reference's, the same value from the reference by :func:`_spinning_drag_near` (a step's
    later stages from its first). C_L·|v| = 0.9·min(r|ω|, 0.3·|v|), the square root taken only at S > 0.3. Plain
    scalars, not the settings vector: an array argument costs every evaluation a reference-count increment and
    decrement.
    """
    if measured == 0.0:
        speed = math.sqrt(speed2)
        return constant_drag * speed, constant_lift * speed, 0.0
    if speed2 == 0.0:
        return 0.0, 0.0, 0.0  # at rest, no force: the logarithms below need |v| > 0
    scale = 1.0
    if speed2 < _SLOW2:  # the coefficients at 1 m/s (S = r|ω|/max(|v|, 1 m/s)), times |v|; no reference from here
        scale, speed2, reference_drag = math.sqrt(speed2) / SLOW_SPEED_MS, _SLOW2, 0.0
    # Below Asai et al. 2007's wind-tunnel values: see kernels.ball.
    lift = 0.9 * spin_speed if spin_speed * spin_speed <= 0.09 * speed2 else 0.27 * math.sqrt(speed2)
    if spin_speed * spin_speed >= 0.0025 * speed2:  # S ≥ 0.05: the spinning fit alone (the blend's weight is 1)
        drag = math.nan
        if reference_drag > 0.0:
            drag = _spinning_drag_near(speed2, inverse_reference2, reference_drag)
        if math.isnan(drag):
            # 0.4127·S^0.3056·|v| (Goff & Carré 2010) as one exponential (here r|ω| > 0).
            drag = 0.4127 * math.exp(spin_term + _SPINNING_POWER * math.log(speed2))
        if scale != 1.0:
            return drag * scale, lift * scale, 0.0
        return drag, lift, drag
    speed = math.sqrt(speed2)
    arg = min((re_per_speed * speed - re_crisis) / _RE_WIDTH, 50.0)
    still = 0.155 + 0.346 / (1.0 + math.exp(arg))  # Goff & Carré 2010
    # The blend C_D0 + (S/0.05)·(C_Ds(0.05) − C_D0), times |v|: (S/0.05)·|v| = r|ω|/0.05.
    return scale * (still * speed + (spin_speed / 0.05) * (_SPINNING_AT_BLEND - still)), scale * lift, 0.0


@compiled()
def drag_lift(speed, rate, measured, constant_drag, constant_lift, radius, re_per_speed, re_crisis):
    """(C_D, C_L) of a ball at ``speed`` (m/s, ≥ 0) spinning at ``rate`` = |ω| (rad/s, ≥ 0): :func:`drag_lift_speeds`
    divided by the speed, taken as at least :data:`~kernels.ball.config.SLOW_SPEED_MS` (1 m/s), below which the
    measured coefficients are held (so a ball at rest has those of one at 1 m/s, S = r·|ω|/1 m/s)."""
    speed = max(speed, SLOW_SPEED_MS)
    if speed > 1e150:  # |v|² would overflow: so far past the drag crisis the coefficients depend on S alone
        rate, speed = rate * (1e150 / speed), 1e150
    drag, lift = drag_lift_speeds(
        speed * speed, rate, measured, constant_drag, constant_lift, radius, re_per_speed, re_crisis
    )
    return drag / speed, lift / speed


@compiled(from_python=True)
def drag_lift_table(speeds, rates, config, drag, lift):
    """:func:`drag_lift` at each of the (N,) ``speeds`` and ``rates`` under the (14,) settings' model, into the (N,)
    ``drag`` and ``lift``."""
    measured, c_d, c_l = config[MEASURED], config[C_D], config[C_L]
    radius, re_per_speed, re_crisis = config[RADIUS], config[RE_PER_SPEED], config[RE_CRISIS]
    for i in range(len(speeds)):
        drag[i], lift[i] = drag_lift(speeds[i], rates[i], measured, c_d, c_l, radius, re_per_speed, re_crisis)


class ForceLaw(NamedTuple):
    """One kick's force law as plain numbers (:func:`force_law`), handed to each force evaluation by value.

    An array handed to a compiled function costs each call an atomic reference-count increment and decrement; in
    the four evaluations of an RK4 step, one after another, those took about a fifth of the step.
    """

    q: float
    """½ρA/m (1/m): force per unit mass per unit C·|v|²."""
    gravity: float
    """g (m/s², acting along −z)."""
    measured: float
    """1.0 for the measured coefficients, 0.0 for the constant ones."""
    drag: float
    """The constant model's C_D."""
    lift: float
    """The constant model's C_L."""
    radius: float
    """Ball radius (m)."""
    re_per_speed: float
    """Reynolds number per m/s of speed (ρ·2r/μ)."""
    re_crisis: float
    """The measured C_D's drag-crisis centre (Reynolds number)."""
    axis_x: float
    """Unit spin axis ω̂ (0 without spin)."""
    axis_y: float
    axis_z: float
    rate: float
    """|ω| (rad/s)."""
    gain: float
    """Knuckle gain ½ρA·C_K·w/m (1/m); 0 without the knuckle force."""
    omega: float
    """Knuckle force's angular rate Ω (rad/s)."""
    phase_1: float
    """Phases of its two components (rad)."""
    phase_2: float
    n1_x: float
    """cos θ·n₁: the first component's direction."""
    n1_y: float
    n1_z: float
    n2_x: float
    """sin θ·n₂: the second component's direction."""
    n2_y: float
    n2_z: float
    spin_speed: float
    """r|ω| (m/s)."""
    spin_term: float
    """0.3056·ln(r|ω|), the measured C_D's spin factor as a logarithm (:func:`_spin_term`)."""


@compiled()
def force_law(kick, config):
    """The :class:`ForceLaw` of one kick's (14,) constants under the (14,) settings."""
    return ForceLaw(
        config[Q],
        config[GRAVITY],
        config[MEASURED],
        config[C_D],
        config[C_L],
        config[RADIUS],
        config[RE_PER_SPEED],
        config[RE_CRISIS],
        kick[AXIS],
        kick[AXIS + 1],
        kick[AXIS + 2],
        kick[RATE],
        kick[GAIN],
        kick[OMEGA],
        kick[PHASE],
        kick[PHASE + 1],
        kick[N1],
        kick[N1 + 1],
        kick[N1 + 2],
        kick[N2],
        kick[N2 + 1],
        kick[N2 + 2],
        config[RADIUS] * kick[RATE],
        _spin_term(config[RADIUS] * kick[RATE]),
    )


@compiled()
def _factors(speed2, law, inverse_reference2, reference_drag):
    """(−½ρA·C_D·|v|/m, ½ρA·C_L·|v|/m) at squared speed ``speed2``: drag and lift per unit velocity and mass (1/s);
    then the spinning fit's C_D·|v| (0 where not that fit), a reference for a nearby evaluation with 1/``speed2``
    (see :func:`_drag_lift_spin`; pass 0.0, 0.0 for none)."""
    drag, lift, spinning = _drag_lift_spin(
        speed2,
        law.spin_speed,
        law.spin_term,
        law.measured,
        law.drag,
        law.lift,
        law.re_per_speed,
        law.re_crisis,
        inverse_reference2,
        reference_drag,
    )
    return -law.q * drag, law.q * lift, spinning


@compiled()
def _knuckle(speed2, t, law):
    """Knuckle side force per unit mass (m/s², 3 values) at squared speed ``speed2``; zero when the kick has none."""
    if law.gain == 0.0:
        return 0.0, 0.0, 0.0
    kk = law.gain * speed2
    s1 = kk * math.sin(law.omega * t + law.phase_1)
    s2 = kk * math.sin(law.omega * t + law.phase_2)
    return s1 * law.n1_x + s2 * law.n2_x, s1 * law.n1_y + s2 * law.n2_y, s1 * law.n1_z + s2 * law.n2_z


@compiled(inline="always")
def acceleration(vx, vy, vz, t, law, inverse_reference2, reference_drag):
    """Total acceleration (m/s²) under the kick's :class:`ForceLaw`: drag, Magnus (ω̂ × v), knuckle and gravity;
    then |v|² (m²/s²) and the spinning fit's C_D·|v| (m/s, 0 where not that fit), the reference that a later
    evaluation near this one may pass back as 1/|v|² and C_D·|v| (0.0, 0.0 for none: see
    :func:`_drag_lift_spin`)."""
    speed2 = vx * vx + vy * vy + vz * vz
    kd, kl, spinning = _factors(speed2, law, inverse_reference2, reference_drag)
    wx, wy, wz = law.axis_x, law.axis_y, law.axis_z
    sx, sy, sz = _knuckle(speed2, t, law)
    return (
        kd * vx + kl * (wy * vz - wz * vy) + sx,
        kd * vy + kl * (wz * vx - wx * vz) + sy,
        kd * vz + kl * (wx * vy - wy * vx) + sz - law.gravity,
        speed2,
        spinning,
    )


@compiled()
def sample_forces(t, state, kick, config, forces):
    """Drag, Magnus, gravity and knuckle forces (N) at each sample: ``forces`` (N, 12) from ``state`` (N, 6)."""
    m = config[MASS]
    law = force_law(kick, config)
    wx, wy, wz = law.axis_x, law.axis_y, law.axis_z
    for i in range(len(t)):
        vx, vy, vz = state[i, 3], state[i, 4], state[i, 5]
        speed2 = vx * vx + vy * vy + vz * vz
        kd, kl, _ = _factors(speed2, law, 0.0, 0.0)
        sx, sy, sz = _knuckle(speed2, t[i], law)
        forces[i, 0], forces[i, 1], forces[i, 2] = m * kd * vx, m * kd * vy, m * kd * vz
        forces[i, 3] = m * kl * (wy * vz - wz * vy)
        forces[i, 4] = m * kl * (wz * vx - wx * vz)
        forces[i, 5] = m * kl * (wx * vy - wy * vx)
        forces[i, 6], forces[i, 7], forces[i, 8] = 0.0, 0.0, -m * law.gravity
        forces[i, 9], forces[i, 10], forces[i, 11] = m * sx, m * sy, m * sz
