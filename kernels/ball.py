"""Flight of a spinning football: drag, Magnus lift, gravity and the knuckleball's unsteady side force.

Frame and units: world frame with x from the ball toward the goal, y to the left, z up; SI throughout (m, s, kg,
rad/s). A position is the ball's centre, (3,) or (N, 3); spin ω is the angular-velocity vector in rad/s.

Model (per unit mass, A = π r², v̂ = v/|v|, ω̂ = ω/|ω|, zero when ω = 0)::

    F_drag   = −½·ρ·A·C_D·|v|·v
    F_Magnus = ½·ρ·A·C_L·|v|·(ω̂ × v)
    F_grav   = (0, 0, −m·g)

The seed writes the Magnus force as C_L·ρ·π·r²·|v×ω|/|ω|, which has units of kg/s, not newtons; the form above keeps
its direction (ω × v) and its sin-angle factor and gives the seed's "3–5 m sideways over 25 m" (about 4.4 m at
C_L = 0.25). Two coefficient models:

* ``"constant"``: C_D and C_L as given (defaults 0.25 and 0.25). The curl radius is then fixed at 2m/(ρ·A·C_L)
  ≈ 73.9 m whatever the spin rate, so spin changes nothing but the direction of the curl.
* ``"measured"``: coefficients from published fits, so the spin rate matters. With S = r·|ω|/|v| the spin parameter
  and Re = ρ·|v|·2r/μ (μ = 1.81·10⁻⁵ Pa·s):

      C_L(S) = 0.9·min(S, 0.3)
          Lift grows roughly as 0.8–1.0·S up to S ≈ 0.3 in wind-tunnel measurements (Asai et al. 2007, Sports Eng.
          10; Carré, Goff et al. 2005–2010). Beyond S = 0.3 data are sparse; the value is held at 0.27.
      C_D(Re, S) = C_D0(Re) + min(S/0.05, 1)·(C_Ds(max(S, 0.05)) − C_D0(Re))
      C_D0(Re)   = 0.155 + 0.346 / (1 + exp((Re − 1.815·10⁵) / 1.949·10⁴))
      C_Ds(S)    = 0.4127·S^0.3056
          Goff & Carré 2010 (Eur. J. Phys. 31): the non-spinning fit 0.155 + 0.346/(1 + exp((v − 12.19)/1.309)),
          re-expressed in Re for a 0.22 m ball in air of 1.225 kg/m³, puts the drag crisis at Re 2.2–3.3·10⁵ as Hong
          & Asai 2013 measured; the spinning fit (S > 0.05) is theirs too. Between S = 0 and 0.05 the two are blended
          linearly so C_D is continuous.

Knuckleball (``knuckle_seed`` set): a ball kicked with almost no spin at 24–30 m/s sheds an unsteady wake and
zig-zags by about one ball diameter, one zig-zag per ~15 m of flight (Cohen, Darbois Texier, Quéré & Clanet, APS DFD
2012; Texier et al. 2016, New J. Phys. 18). Modelled as a side force of coefficient C_K = 0.10 across the launch
direction, ``½·ρ·A·|v|²·C_K·w·(cos θ·sin(Ωt + φ₁)·n₁ + sin θ·sin(Ωt + φ₂)·n₂)``, with Ω = 2π·|v₀|/15 m, n₁ the
horizontal and n₂ the vertical normals to the launch velocity, and θ, φ₁, φ₂ drawn from ``numpy.random.default_rng(
knuckle_seed)`` so a seed always gives the same flight. w = max(0, 1 − S₀/0.05) fades the effect out as launch spin
grows (S₀ the launch spin parameter): any real spin steadies the wake. C_K is set so that the median peak lateral
deviation at 25 m/s over 25 m is about one ball diameter.

Assumptions: spin is constant in flight (spin decay over a 1–2 s free kick is a few percent); still air; the ball is
rigid and stops at the first touch of the ground (no bounce or roll); a ball that touches the wall or the frame does
not rebound. Integrators: ``"euler"`` is the seed's fixed-step method (v += a·dt, then x += v·dt; first order),
``"rk4"`` the classical fourth-order Runge–Kutta. The last sample of a flight is placed on the ground (or on the
``x_stop`` plane) by cubic Hermite interpolation of the last step, which keeps RK4's accuracy.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

G = 9.81
"""Gravitational acceleration (m/s²)."""
BALL_MASS_KG = 0.43
"""Size-5 ball (FIFA: 410–450 g)."""
BALL_RADIUS_M = 0.11
"""Size-5 ball (circumference 68–70 cm)."""
AIR_DENSITY = 1.225
"""Sea-level air density (kg/m³)."""
AIR_VISCOSITY = 1.81e-5
"""Dynamic viscosity of air at 15 °C (Pa·s), for the Reynolds number of the measured model."""
GOAL_WIDTH_M = 7.32
"""Between the inside edges of the posts."""
GOAL_HEIGHT_M = 2.44
"""Ground to the underside of the crossbar."""
WALL_DISTANCE_M = 9.15
"""FIFA distance of the defensive wall from the ball."""
KNUCKLE_COEFFICIENT = 0.10
"""Side-force coefficient C_K of the knuckleball model (see the module docstring)."""
KNUCKLE_WAVELENGTH_M = 15.0
"""Flight distance of one zig-zag (Cohen et al. 2012)."""
KNUCKLE_SPIN_LIMIT = 0.05
"""Launch spin parameter S₀ at and above which the knuckle force is off."""

Method = Literal["euler", "rk4"]
Model = Literal["constant", "measured"]
Ending = Literal["ground", "x_stop", "t_max"]
Result = Literal["goal", "wall", "over", "wide", "short"]

_MAX_STEPS = 1_000_000

# Goff & Carré 2010 no-spin drag fit, in Reynolds number (see the module docstring).
_RE_CRISIS = 1.815e5
_RE_WIDTH = 1.949e4


@dataclasses.dataclass(frozen=True)
class Trajectory:
    """One flight sampled every ``dt``; the last sample is the interpolated end (ground contact or ``x_stop``)."""

    t: NDArray[np.float64]
    """(N,) time since the kick (s)."""
    position: NDArray[np.float64]
    """(N, 3) ball centre (m)."""
    velocity: NDArray[np.float64]
    """(N, 3) ball velocity (m/s)."""
    drag: NDArray[np.float64]
    """(N, 3) drag force (N)."""
    magnus: NDArray[np.float64]
    """(N, 3) Magnus force (N)."""
    gravity: NDArray[np.float64]
    """(N, 3) weight (N)."""
    knuckle: NDArray[np.float64]
    """(N, 3) knuckleball side force (N); zero unless ``knuckle_seed`` was set and the spin is near zero."""
    ended: Ending
    """Why the flight stopped: it touched the ground, passed ``x_stop``, or reached ``t_max``."""


@dataclasses.dataclass(frozen=True)
class BatchTrajectory:
    """Many flights integrated together, padded after each one's end with its final state."""

    t: NDArray[np.float64]
    """(K, T) time of each sample (s); kick k's samples are ``[:n_samples[k]]``."""
    position: NDArray[np.float64]
    """(K, T, 3) ball centre (m)."""
    velocity: NDArray[np.float64]
    """(K, T, 3) ball velocity (m/s)."""
    n_samples: NDArray[np.int64]
    """(K,) samples that belong to each flight; the last is its interpolated end."""
    ended: NDArray[np.str_]
    """(K,) ``"ground"``, ``"x_stop"`` or ``"t_max"``."""


@dataclasses.dataclass(frozen=True)
class Panel:
    """A vertical rectangle standing on the ground: the wall, or the goal mouth."""

    centre_xy: tuple[float, float]
    """Foot of the panel's centre line (m)."""
    normal_xy: tuple[float, float]
    """Horizontal direction the ball must travel to pass through it (normalised on use)."""
    width_m: float
    """Full width (m)."""
    height_m: float
    """Height of the top edge above the ground (m)."""


@dataclasses.dataclass(frozen=True)
class Outcome:
    """What a kick did, and where it crossed the wall's and the goal's planes."""

    result: Result
    """``"goal"``, ``"wall"`` (hit it), ``"over"`` the bar, ``"wide"`` of a post, or ``"short"`` (landed first)."""
    wall_point: NDArray[np.float64] | None
    """(3,) ball centre where it crossed the wall's plane (m), None if it never got there."""
    goal_point: NDArray[np.float64] | None
    """(3,) ball centre where it crossed the goal's plane (m), None if it never got there."""
    wall_time: float | None
    """Time of the wall crossing (s)."""
    goal_time: float | None
    """Time of the goal crossing (s)."""


@dataclasses.dataclass(frozen=True)
class BatchOutcome:
    """:class:`Outcome` for each kick of a :class:`BatchTrajectory`; crossings are NaN where there was none."""

    result: NDArray[np.str_]
    """(K,) one of the five results."""
    wall_point: NDArray[np.float64]
    """(K, 3) crossing of the wall's plane (m)."""
    goal_point: NDArray[np.float64]
    """(K, 3) crossing of the goal's plane (m)."""


def free_kick_panels(
    ball_xy: ArrayLike,
    goal_centre_xy: ArrayLike = (0.0, 0.0),
    goal_normal_xy: ArrayLike = (-1.0, 0.0),
    *,
    wall_width_m: float = 2.0,
    wall_height_m: float = 1.8,
    wall_offset_m: float = 0.0,
) -> tuple[Panel, Panel]:
    """The wall (9.15 m from the ball, square to the line from ball to goal centre) and the goal mouth.

    Args:
        ball_xy: (2,) ball position on the ground (m).
        goal_centre_xy: (2,) centre of the goal line (m).
        goal_normal_xy: (2,) direction from the pitch into the net.
        wall_width_m: wall width (m), about 0.5 m a defender.
        wall_height_m: height of the defenders' heads (m), more when they jump.
        wall_offset_m: shift of the wall's centre to the left of the ball-to-goal line (m).

    Returns:
        ``(wall, goal)``.
    """
    ball = _vector("ball_xy", ball_xy, 2)
    centre = _vector("goal_centre_xy", goal_centre_xy, 2)
    normal = _vector("goal_normal_xy", goal_normal_xy, 2)
    aim = centre - ball
    distance = float(np.hypot(*aim))
    if distance <= WALL_DISTANCE_M:
        raise ValueError(
            f"ball_xy must be more than {WALL_DISTANCE_M} m from the goal, got {distance:.2f} m"
        )
    aim /= distance
    left = np.array([-aim[1], aim[0]])
    wall_foot = ball + WALL_DISTANCE_M * aim + _finite_scalar("wall_offset_m", wall_offset_m) * left
    wall = Panel(
        (float(wall_foot[0]), float(wall_foot[1])),
        (float(aim[0]), float(aim[1])),
        _positive_scalar("wall_width_m", wall_width_m),
        _positive_scalar("wall_height_m", wall_height_m),
    )
    goal = Panel(
        (float(centre[0]), float(centre[1])),
        (float(normal[0]), float(normal[1])),
        GOAL_WIDTH_M,
        GOAL_HEIGHT_M,
    )
    return wall, goal


# --------------------------------------------------------------------------------------------- validation
def _vector(name: str, value: ArrayLike, size: int) -> NDArray[np.float64]:
    try:
        array = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise ValueError(f"{name} must be {size} numbers, got {value!r}") from error
    if array.shape != (size,):
        raise ValueError(f"{name} must have shape ({size},), got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return array


def _rows(name: str, value: ArrayLike) -> NDArray[np.float64]:
    try:
        array = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise ValueError(f"{name} must be an (N, 3) array of numbers") from error
    if array.ndim != 2 or array.shape[1] != 3:
        raise ValueError(f"{name} must have shape (N, 3), got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must be finite")
    return array


def _finite_scalar(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"{name} must be a number, got {value!r}")
    number = float(value)
    if not math.isfinite(number):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return number


def _positive_scalar(name: str, value: object) -> float:
    number = _finite_scalar(name, value)
    if number <= 0.0:
        raise ValueError(f"{name} must be > 0, got {value!r}")
    return number


def _non_negative_scalar(name: str, value: object) -> float:
    number = _finite_scalar(name, value)
    if number < 0.0:
        raise ValueError(f"{name} must be >= 0, got {value!r}")
    return number


def _seed(name: str, value: object) -> int | None:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0:
        raise ValueError(f"{name} must be None or an integer >= 0, got {value!r}")
    return int(value)


@dataclasses.dataclass(frozen=True)
class _Settings:
    """Validated scalar settings shared by :func:`simulate` and :func:`simulate_batch`."""

    dt: float
    method: Method
    model: Model
    drag_coefficient: float
    lift_coefficient: float
    mass_kg: float
    radius_m: float
    air_density: float
    gravity: float
    t_max: float
    x_stop: float | None
    ground_m: float


def _settings(
    *,
    dt: object,
    method: object,
    model: object,
    drag_coefficient: object,
    lift_coefficient: object,
    mass_kg: object,
    radius_m: object,
    air_density: object,
    gravity: object,
    t_max: object,
    x_stop: object,
    ground_m: object,
) -> _Settings:
    step = _positive_scalar("dt", dt)
    duration = _positive_scalar("t_max", t_max)
    if duration / step > _MAX_STEPS:
        raise ValueError(
            f"dt must be at least t_max/{_MAX_STEPS} = {duration / _MAX_STEPS:g} s, got {step:g}"
        )
    if method not in ("euler", "rk4"):
        raise ValueError(f"method must be 'euler' or 'rk4', got {method!r}")
    if model not in ("constant", "measured"):
        raise ValueError(f"model must be 'constant' or 'measured', got {model!r}")
    return _Settings(
        dt=step,
        method=method,
        model=model,
        drag_coefficient=_non_negative_scalar("drag_coefficient", drag_coefficient),
        lift_coefficient=_non_negative_scalar("lift_coefficient", lift_coefficient),
        mass_kg=_positive_scalar("mass_kg", mass_kg),
        radius_m=_positive_scalar("radius_m", radius_m),
        air_density=_non_negative_scalar("air_density", air_density),
        gravity=_finite_scalar("gravity", gravity),
        t_max=duration,
        x_stop=None if x_stop is None else _finite_scalar("x_stop", x_stop),
        ground_m=_finite_scalar("ground_m", ground_m),
    )


# --------------------------------------------------------------------------------------------- force law
@dataclasses.dataclass(frozen=True)
class _Ops:
    """The few math functions the force law needs, for Python floats (fast single runs) or numpy arrays (batches)."""

    sqrt: Callable[[Any], Any]
    exp: Callable[[Any], Any]
    sin: Callable[[Any], Any]
    minimum: Callable[[Any, Any], Any]
    maximum: Callable[[Any, Any], Any]


_FLOAT_OPS = _Ops(math.sqrt, math.exp, math.sin, min, max)
_ARRAY_OPS = _Ops(np.sqrt, np.exp, np.sin, np.minimum, np.maximum)


@dataclasses.dataclass(frozen=True)
class _Kick:
    """Per-kick constants of the force law: floats for one kick, (K,) arrays for a batch."""

    spin_axis: tuple[Any, Any, Any]  # ω̂, zero for no spin
    spin_rate: Any  # |ω| (rad/s)
    knuckle_gain: Any  # ½ρA·C_K·w/m (1/m), zero when off
    knuckle_rate: Any  # Ω (rad/s)
    knuckle_phase: tuple[Any, Any]  # φ₁, φ₂
    knuckle_n1: tuple[Any, Any, Any]  # cos θ · n₁
    knuckle_n2: tuple[Any, Any, Any]  # sin θ · n₂


def _knuckle_draw(
    seed: int | None, velocity: NDArray[np.float64], spin: NDArray[np.float64], s: _Settings
):
    """Knuckle constants for one kick: (gain, rate, phases, cosθ·n₁, sinθ·n₂)."""
    speed = float(np.linalg.norm(velocity))
    if seed is None or speed == 0.0:
        return 0.0, 0.0, (0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    spin_parameter = s.radius_m * float(np.linalg.norm(spin)) / speed
    weight = max(0.0, 1.0 - spin_parameter / KNUCKLE_SPIN_LIMIT)
    rng = np.random.default_rng(seed)
    theta, phi1, phi2 = rng.uniform(0.0, 2.0 * np.pi, size=3)
    along = velocity / speed
    horizontal = np.array([-along[1], along[0], 0.0])
    if np.linalg.norm(horizontal) < 1e-9:  # kicked straight up: any horizontal direction will do
        horizontal = np.array([0.0, 1.0, 0.0])
    horizontal /= np.linalg.norm(horizontal)
    vertical = np.cross(along, horizontal)
    area = math.pi * s.radius_m**2
    gain = 0.5 * s.air_density * area * KNUCKLE_COEFFICIENT * weight / s.mass_kg
    n1 = math.cos(theta) * horizontal
    n2 = math.sin(theta) * vertical
    return (
        gain,
        2.0 * math.pi * speed / KNUCKLE_WAVELENGTH_M,
        (float(phi1), float(phi2)),
        (float(n1[0]), float(n1[1]), float(n1[2])),
        (float(n2[0]), float(n2[1]), float(n2[2])),
    )


def _force_law(ops: _Ops, kick: _Kick, s: _Settings):
    """Acceleration terms (m/s²) as a function of velocity components and time.

    Returns ``terms(vx, vy, vz, t) -> (drag xyz, magnus xyz, knuckle xyz)`` (9 values) and
    ``acceleration(vx, vy, vz, t) -> (ax, ay, az)`` including gravity. Works unchanged on floats and on arrays;
    :func:`simulate_batch` steps with it on (K,) arrays, while a single flight steps with
    :func:`_scalar_acceleration`, the same law written for floats.
    """
    q = 0.5 * s.air_density * math.pi * s.radius_m**2 / s.mass_kg  # ½ρA/m (1/m)
    g = s.gravity
    wx, wy, wz = kick.spin_axis
    spin_rate = kick.spin_rate
    kg, kr = kick.knuckle_gain, kick.knuckle_rate
    p1, p2 = kick.knuckle_phase
    ax1, ay1, az1 = kick.knuckle_n1
    ax2, ay2, az2 = kick.knuckle_n2
    sqrt, exp, sin, minimum, maximum = ops.sqrt, ops.exp, ops.sin, ops.minimum, ops.maximum
    r = s.radius_m
    re_per_speed = s.air_density * 2.0 * r / AIR_VISCOSITY
    c_d, c_l = s.drag_coefficient, s.lift_coefficient
    measured = s.model == "measured"

    def coefficients(speed):
        """(−½ρA·C_D·|v|/m, ½ρA·C_L·|v|/m): the drag and lift factors of the current speed."""
        if not measured:
            return -q * c_d * speed, q * c_l * speed
        spin_parameter = r * spin_rate / maximum(speed, 1e-9)
        lift = 0.9 * minimum(spin_parameter, 0.3)
        arg = minimum((re_per_speed * speed - _RE_CRISIS) / _RE_WIDTH, 50.0)
        still = 0.155 + 0.346 / (1.0 + exp(arg))
        spinning = 0.4127 * maximum(spin_parameter, 0.05) ** 0.3056
        drag = still + minimum(spin_parameter / 0.05, 1.0) * (spinning - still)
        return -q * drag * speed, q * lift * speed

    def knuckle(speed, t):
        kk = kg * speed * speed
        return kk * sin(kr * t + p1), kk * sin(kr * t + p2)

    def terms(vx, vy, vz, t):
        speed = sqrt(vx * vx + vy * vy + vz * vz)
        kd, kl = coefficients(speed)
        s1, s2 = knuckle(speed, t)
        return (
            kd * vx,
            kd * vy,
            kd * vz,
            kl * (wy * vz - wz * vy),
            kl * (wz * vx - wx * vz),
            kl * (wx * vy - wy * vx),
            s1 * ax1 + s2 * ax2,
            s1 * ay1 + s2 * ay2,
            s1 * az1 + s2 * az2,
        )

    # The batch integrator calls this every stage of every step: it repeats ``terms``' sums inline (no 9-tuple) and
    # skips the knuckle force when it is off everywhere.
    has_knuckle = bool(np.any(kg != 0.0))

    drag_factor, lift_factor = -q * c_d, q * c_l

    def acceleration(vx, vy, vz, t):
        speed = sqrt(vx * vx + vy * vy + vz * vz)
        if measured:
            kd, kl = coefficients(speed)
        else:
            kd, kl = drag_factor * speed, lift_factor * speed
        ax = kd * vx + kl * (wy * vz - wz * vy)
        ay = kd * vy + kl * (wz * vx - wx * vz)
        az = kd * vz + kl * (wx * vy - wy * vx) - g
        if has_knuckle:
            s1, s2 = knuckle(speed, t)
            ax = ax + s1 * ax1 + s2 * ax2
            ay = ay + s1 * ay1 + s2 * ay2
            az = az + s1 * az1 + s2 * az2
        return ax, ay, az

    return terms, acceleration


def _stepper(method: Method, acceleration, dt: float):
    """One fixed step ``(x, y, z, vx, vy, vz, t) -> (x, y, z, vx, vy, vz)`` on (K,) arrays (floats work too).

    :func:`_integrate_one` writes the same steps out, operation for operation, for one kick on floats.
    """
    match method:
        case "euler":

            def euler(x, y, z, vx, vy, vz, t):
                ax, ay, az = acceleration(vx, vy, vz, t)
                vx, vy, vz = vx + ax * dt, vy + ay * dt, vz + az * dt
                return x + vx * dt, y + vy * dt, z + vz * dt, vx, vy, vz

            return euler
        case "rk4":
            half, sixth = 0.5 * dt, dt / 6.0

            def rk4(x, y, z, vx, vy, vz, t):
                # The acceleration does not depend on position, so each stage's position slope is its velocity.
                a1x, a1y, a1z = acceleration(vx, vy, vz, t)
                v2x, v2y, v2z = vx + half * a1x, vy + half * a1y, vz + half * a1z
                a2x, a2y, a2z = acceleration(v2x, v2y, v2z, t + half)
                v3x, v3y, v3z = vx + half * a2x, vy + half * a2y, vz + half * a2z
                a3x, a3y, a3z = acceleration(v3x, v3y, v3z, t + half)
                v4x, v4y, v4z = vx + dt * a3x, vy + dt * a3y, vz + dt * a3z
                a4x, a4y, a4z = acceleration(v4x, v4y, v4z, t + dt)
                return (
                    x + sixth * (vx + 2.0 * (v2x + v3x) + v4x),
                    y + sixth * (vy + 2.0 * (v2y + v3y) + v4y),
                    z + sixth * (vz + 2.0 * (v2z + v3z) + v4z),
                    vx + sixth * (a1x + 2.0 * (a2x + a3x) + a4x),
                    vy + sixth * (a1y + 2.0 * (a2y + a3y) + a4y),
                    vz + sixth * (a1z + 2.0 * (a2z + a3z) + a4z),
                )

            return rk4


def _scalar_acceleration(kick: _Kick, s: _Settings) -> Callable[..., tuple[float, float, float]]:
    """``acceleration(vx, vy, vz, t) -> (ax, ay, az)`` (m/s²) for one kick on Python floats.

    The same law as :func:`_force_law`, operation for operation (so a single flight and its batch lane agree to the
    last bits), written for the single flight's inner loop: a thousand calls per Euler flight, so the measured
    coefficients are inlined with comparisons instead of ``min``/``max`` calls, and the knuckle force is skipped when
    it is off.
    """
    q = 0.5 * s.air_density * math.pi * s.radius_m**2 / s.mass_kg  # ½ρA/m (1/m)
    g = s.gravity
    wx, wy, wz = kick.spin_axis
    spin_rate = kick.spin_rate
    kg, kr = kick.knuckle_gain, kick.knuckle_rate
    p1, p2 = kick.knuckle_phase
    ax1, ay1, az1 = kick.knuckle_n1
    ax2, ay2, az2 = kick.knuckle_n2
    has_knuckle = kg != 0.0
    sqrt, exp, sin = math.sqrt, math.exp, math.sin
    r = s.radius_m
    re_per_speed = s.air_density * 2.0 * r / AIR_VISCOSITY
    drag_factor, lift_factor = -q * s.drag_coefficient, q * s.lift_coefficient
    # The law's leading products, precomputed as it evaluates them (left to right): the same bits.
    r_spin_rate, minus_q = r * spin_rate, -q

    def knuckle(ax: float, ay: float, az: float, speed: float, t: float):
        kk = kg * speed * speed
        s1, s2 = kk * sin(kr * t + p1), kk * sin(kr * t + p2)
        return ax + s1 * ax1 + s2 * ax2, ay + s1 * ay1 + s2 * ay2, az + s1 * az1 + s2 * az2

    match s.model:
        case "constant":

            def constant(vx: float, vy: float, vz: float, t: float):
                speed = sqrt(vx * vx + vy * vy + vz * vz)
                kd, kl = drag_factor * speed, lift_factor * speed
                ax = kd * vx + kl * (wy * vz - wz * vy)
                ay = kd * vy + kl * (wz * vx - wx * vz)
                az = kd * vz + kl * (wx * vy - wy * vx) - g
                return knuckle(ax, ay, az, speed, t) if has_knuckle else (ax, ay, az)

            return constant
        case "measured":

            def measured(vx: float, vy: float, vz: float, t: float):
                speed = sqrt(vx * vx + vy * vy + vz * vz)
                spin_parameter = r_spin_rate / (speed if speed > 1e-9 else 1e-9)
                lift = 0.9 * (spin_parameter if spin_parameter < 0.3 else 0.3)
                arg = (re_per_speed * speed - _RE_CRISIS) / _RE_WIDTH
                still = 0.155 + 0.346 / (1.0 + exp(arg if arg < 50.0 else 50.0))
                spinning = 0.4127 * (spin_parameter if spin_parameter > 0.05 else 0.05) ** 0.3056
                blend = spin_parameter / 0.05
                drag = still + (blend if blend < 1.0 else 1.0) * (spinning - still)
                kd, kl = minus_q * drag * speed, q * lift * speed
                ax = kd * vx + kl * (wy * vz - wz * vy)
                ay = kd * vy + kl * (wz * vx - wx * vz)
                az = kd * vz + kl * (wx * vy - wy * vx) - g
                return knuckle(ax, ay, az, speed, t) if has_knuckle else (ax, ay, az)

            return measured


# --------------------------------------------------------------------------------------------- interpolation
def _hermite(p0, v0, p1, v1, h, s):
    """Cubic Hermite value and derivative (per unit time) at fraction ``s`` of a step of length ``h``."""
    s2, s3 = s * s, s * s * s
    value = (
        (2 * s3 - 3 * s2 + 1) * p0
        + (s3 - 2 * s2 + s) * h * v0
        + (3 * s2 - 2 * s3) * p1
        + (s3 - s2) * h * v1
    )
    slope = (
        (6 * s2 - 6 * s) * p0
        + (3 * s2 - 4 * s + 1) * h * v0
        + (6 * s - 6 * s2) * p1
        + (3 * s2 - 2 * s) * h * v1
    ) / h
    return value, slope


def _crossing_fraction(ops: _Ops, d0, dd0, d1, dd1, h):
    """Fraction s ∈ [0, 1] of a step where the cubic through (d0, dd0) and (d1, dd1) reaches zero.

    Floats or (K,) arrays alike. ``d0`` and ``d1`` should bracket zero; the answer is clamped to the step. Linear
    guess, then Newton on the Hermite cubic (its error is O(h⁴), below the integrators' own).
    """
    span = d1 - d0
    s = ops.minimum(ops.maximum(-d0 / (span + (span == 0.0)), 0.0), 1.0)
    for _ in range(4):
        value, slope = _hermite(d0, dd0, d1, dd1, h, s)
        slope = slope * h  # per unit s
        s = ops.minimum(ops.maximum(s - value / (slope + (slope == 0.0)), 0.0), 1.0)
    return s


# --------------------------------------------------------------------------------------------- simulate
def _check_kick(position: ArrayLike, velocity: ArrayLike, spin: ArrayLike):
    return (
        _vector("position", position, 3),
        _vector("velocity", velocity, 3),
        _vector("spin", spin, 3),
    )


def _kick_constants(
    velocities: NDArray[np.float64],
    spins: NDArray[np.float64],
    seeds: Sequence[int | None],
    s: _Settings,
) -> _Kick:
    """(K,)-array kick constants."""
    rates = np.linalg.norm(spins, axis=1)
    axes = spins / np.where(rates > 0.0, rates, 1.0)[:, None]
    off = _knuckle_draw(None, velocities[0], spins[0], s)
    draws = [
        off if seed is None else _knuckle_draw(seed, v, w, s)
        for seed, v, w in zip(seeds, velocities, spins, strict=True)
    ]
    gain = np.array([d[0] for d in draws])
    rate = np.array([d[1] for d in draws])
    phase = np.array([d[2] for d in draws]).reshape(-1, 2)
    n1 = np.array([d[3] for d in draws]).reshape(-1, 3)
    n2 = np.array([d[4] for d in draws]).reshape(-1, 3)
    return _Kick(
        spin_axis=(axes[:, 0], axes[:, 1], axes[:, 2]),
        spin_rate=rates,
        knuckle_gain=gain,
        knuckle_rate=rate,
        knuckle_phase=(phase[:, 0], phase[:, 1]),
        knuckle_n1=(n1[:, 0], n1[:, 1], n1[:, 2]),
        knuckle_n2=(n2[:, 0], n2[:, 1], n2[:, 2]),
    )


def _scalar_kick(kick: _Kick) -> _Kick:
    """The only kick of a (1,)-array :class:`_Kick`, as Python floats."""

    def f(value: Any) -> Any:
        return tuple(float(v[0]) for v in value) if isinstance(value, tuple) else float(value[0])

    return _Kick(*(f(getattr(kick, field.name)) for field in dataclasses.fields(kick)))


def _finish(
    p_old: NDArray[np.float64],
    v_old: NDArray[np.float64],
    p_new: NDArray[np.float64],
    v_new: NDArray[np.float64],
    t_old: NDArray[np.float64] | float,
    dt: float,
    s: _Settings,
) -> tuple[
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.bool_],
    NDArray[np.bool_],
]:
    """End states of flights whose last step (K rows, (K, 3) arrays) crossed the ground or the ``x_stop`` plane.

    Returns:
        (position (K, 3), velocity (K, 3), t (K,), hit_ground (K,), hit_x_stop (K,)).
    """
    ground = p_new[:, 2] <= s.ground_m
    s_ground = np.where(
        ground,
        _crossing_fraction(
            _ARRAY_OPS,
            p_old[:, 2] - s.ground_m,
            v_old[:, 2],
            p_new[:, 2] - s.ground_m,
            v_new[:, 2],
            dt,
        ),
        np.inf,
    )
    if s.x_stop is not None:
        stop = (p_old[:, 0] < s.x_stop) & (p_new[:, 0] >= s.x_stop)
        s_stop = np.where(
            stop,
            _crossing_fraction(
                _ARRAY_OPS,
                p_old[:, 0] - s.x_stop,
                v_old[:, 0],
                p_new[:, 0] - s.x_stop,
                v_new[:, 0],
                dt,
            ),
            np.inf,
        )
    else:
        stop = np.zeros_like(ground)
        s_stop = np.full_like(s_ground, np.inf)
    first_ground = ground & (s_ground <= s_stop)
    first_stop = stop & ~first_ground
    frac = np.minimum(s_ground, s_stop)
    frac = np.where(np.isfinite(frac), frac, 1.0)[:, None]
    position, velocity = _hermite(p_old, v_old, p_new, v_new, dt, frac)
    position[first_ground, 2] = s.ground_m
    if s.x_stop is not None:
        position[first_stop, 0] = s.x_stop
    return position, velocity, t_old + frac[:, 0] * dt, first_ground, first_stop


def _integrate_one(
    p0: NDArray[np.float64],
    v0: NDArray[np.float64],
    acceleration: Callable[..., tuple[float, float, float]],
    s: _Settings,
) -> tuple[NDArray[np.float64], float, Ending]:
    """Step one kick on Python floats until it lands, passes ``x_stop`` or runs out of time.

    Each method's step is written out in its own loop (the same arithmetic as :func:`_stepper`), and the samples
    go to one flat list: no per-step call or tuple beyond the acceleration's, which a 1 ms Euler flight of a
    thousand steps feels.

    Returns:
        (samples (N, 6): position (m) then velocity (m/s), end time (s), why it ended).
    """
    dt = s.dt
    n_steps = math.ceil(s.t_max / dt - 1e-9)
    ground, x_stop_at = s.ground_m, math.inf if s.x_stop is None else s.x_stop
    x, y, z = (float(c) for c in p0)
    vx, vy, vz = (float(c) for c in v0)
    x1, y1, z1, vx1, vy1, vz1 = x, y, z, vx, vy, vz
    samples = [x, y, z, vx, vy, vz]
    extend = samples.extend
    n = 0
    match s.method:
        case "euler":
            for n in range(n_steps):
                ax, ay, az = acceleration(vx, vy, vz, n * dt)
                vx1, vy1, vz1 = vx + ax * dt, vy + ay * dt, vz + az * dt
                x1, y1, z1 = x + vx1 * dt, y + vy1 * dt, z + vz1 * dt
                if z1 <= ground or x < x_stop_at <= x1:
                    break
                extend((x1, y1, z1, vx1, vy1, vz1))
                x, y, z, vx, vy, vz = x1, y1, z1, vx1, vy1, vz1
            else:
                return _rows_of_six(samples), n_steps * dt, "t_max"
        case "rk4":
            half, sixth = 0.5 * dt, dt / 6.0
            for n in range(n_steps):
                t = n * dt
                # The acceleration does not depend on position, so each stage's position slope is its velocity.
                a1x, a1y, a1z = acceleration(vx, vy, vz, t)
                v2x, v2y, v2z = vx + half * a1x, vy + half * a1y, vz + half * a1z
                a2x, a2y, a2z = acceleration(v2x, v2y, v2z, t + half)
                v3x, v3y, v3z = vx + half * a2x, vy + half * a2y, vz + half * a2z
                a3x, a3y, a3z = acceleration(v3x, v3y, v3z, t + half)
                v4x, v4y, v4z = vx + dt * a3x, vy + dt * a3y, vz + dt * a3z
                a4x, a4y, a4z = acceleration(v4x, v4y, v4z, t + dt)
                x1 = x + sixth * (vx + 2.0 * (v2x + v3x) + v4x)
                y1 = y + sixth * (vy + 2.0 * (v2y + v3y) + v4y)
                z1 = z + sixth * (vz + 2.0 * (v2z + v3z) + v4z)
                vx1 = vx + sixth * (a1x + 2.0 * (a2x + a3x) + a4x)
                vy1 = vy + sixth * (a1y + 2.0 * (a2y + a3y) + a4y)
                vz1 = vz + sixth * (a1z + 2.0 * (a2z + a3z) + a4z)
                if z1 <= ground or x < x_stop_at <= x1:
                    break
                extend((x1, y1, z1, vx1, vy1, vz1))
                x, y, z, vx, vy, vz = x1, y1, z1, vx1, vy1, vz1
            else:
                return _rows_of_six(samples), n_steps * dt, "t_max"

    # The last step crossed the ground or the stop plane: end on whichever the cubic through it reaches first.
    hit_ground, hit_stop = z1 <= ground, x < x_stop_at <= x1
    fraction_ground = (
        _crossing_fraction(_FLOAT_OPS, z - ground, vz, z1 - ground, vz1, dt)
        if hit_ground
        else math.inf
    )
    fraction_stop = (
        _crossing_fraction(_FLOAT_OPS, x - x_stop_at, vx, x1 - x_stop_at, vx1, dt)
        if hit_stop
        else math.inf
    )
    ended: Ending = "ground" if fraction_ground <= fraction_stop else "x_stop"
    f = min(fraction_ground, fraction_stop)
    (x1, vx1), (y1, vy1), (z1, vz1) = (
        _hermite(a, va, b, vb, dt, f)
        for a, va, b, vb in ((x, vx, x1, vx1), (y, vy, y1, vy1), (z, vz, z1, vz1))
    )
    if ended == "ground":
        z1 = ground
    else:
        x1 = x_stop_at
    extend((x1, y1, z1, vx1, vy1, vz1))
    return _rows_of_six(samples), (n + f) * dt, ended


def _rows_of_six(samples: list[float]) -> NDArray[np.float64]:
    """(N, 6) array of a flat list of floats (``fromiter`` reads a list of floats faster than ``array``)."""
    return np.fromiter(samples, np.float64, len(samples)).reshape(-1, 6)


def simulate(
    position: ArrayLike,
    velocity: ArrayLike,
    spin: ArrayLike,
    *,
    dt: float = 1e-3,
    method: Method = "euler",
    model: Model = "constant",
    drag_coefficient: float = 0.25,
    lift_coefficient: float = 0.25,
    mass_kg: float = BALL_MASS_KG,
    radius_m: float = BALL_RADIUS_M,
    air_density: float = AIR_DENSITY,
    gravity: float = G,
    t_max: float = 5.0,
    x_stop: float | None = None,
    ground_m: float = 0.0,
    knuckle_seed: int | None = None,
) -> Trajectory:
    """Integrate one kick until the ball's centre reaches ``ground_m``, passes ``x_stop``, or ``t_max`` runs out.

    Args:
        position: (3,) launch position of the ball's centre (m).
        velocity: (3,) launch velocity (m/s).
        spin: (3,) angular velocity (rad/s); +z curls a ball kicked along +x to the left (+y), +y is topspin.
        dt: fixed step (s, > 0).
        method: ``"euler"`` (the seed's: v += a·dt, then x += v·dt) or ``"rk4"``.
        model: ``"constant"`` coefficients or ``"measured"`` spin- and Reynolds-dependent fits.
        drag_coefficient: C_D of the constant model (≥ 0).
        lift_coefficient: C_L of the constant model (≥ 0).
        mass_kg: ball mass (kg, > 0).
        radius_m: ball radius (m, > 0).
        air_density: ρ (kg/m³, ≥ 0; 0 is a vacuum).
        gravity: g (m/s², downward when positive).
        t_max: longest flight to integrate (s, > 0).
        x_stop: optional plane x = x_stop (m) that ends the flight when crossed in +x.
        ground_m: height of the ball's centre at which it touches the ground (m); pass the radius for a ball
            whose underside meets the turf at z = 0.
        knuckle_seed: turn on the knuckleball side force (near-zero spin only), drawn from this seed.

    Returns:
        :class:`Trajectory`, sampled every ``dt`` plus the interpolated end.

    Raises:
        ValueError: naming the argument, for non-finite or wrongly shaped input, dt ≤ 0, mass or radius ≤ 0, an
            unknown method or model.
    """
    p0, v0, w0 = _check_kick(position, velocity, spin)
    s = _settings(
        dt=dt,
        method=method,
        model=model,
        drag_coefficient=drag_coefficient,
        lift_coefficient=lift_coefficient,
        mass_kg=mass_kg,
        radius_m=radius_m,
        air_density=air_density,
        gravity=gravity,
        t_max=t_max,
        x_stop=x_stop,
        ground_m=ground_m,
    )
    seed = _seed("knuckle_seed", knuckle_seed)
    kick_array = _kick_constants(v0[None], w0[None], [seed], s)
    samples, t_end, ended = _integrate_one(
        p0, v0, _scalar_acceleration(_scalar_kick(kick_array), s), s
    )
    t = np.arange(len(samples), dtype=np.float64) * s.dt
    t[-1] = t_end
    return _with_forces(t, samples[:, :3], samples[:, 3:], kick_array, s, ended)


def _with_forces(
    t: NDArray[np.float64],
    position: NDArray[np.float64],
    velocity: NDArray[np.float64],
    kick: _Kick,
    s: _Settings,
    ended: Ending,
) -> Trajectory:
    """Attach the forces at every sample, evaluated once, vectorised over the samples."""
    terms, _ = _force_law(_ARRAY_OPS, kick, s)
    dx, dy, dz, mx, my, mz, kx, ky, kz = terms(velocity[:, 0], velocity[:, 1], velocity[:, 2], t)
    m = s.mass_kg
    n = len(t)

    def stack(a: Any, b: Any, c: Any) -> NDArray[np.float64]:
        """(n, 3) force from three acceleration components, each (n,) or a scalar (broadcast)."""
        force = np.empty((n, 3))
        force[:, 0], force[:, 1], force[:, 2] = a, b, c
        force *= m
        return force

    gravity = np.zeros((n, 3))
    gravity[:, 2] = -m * s.gravity
    return Trajectory(
        t=t,
        position=position,
        velocity=velocity,
        drag=stack(dx, dy, dz),
        magnus=stack(mx, my, mz),
        gravity=gravity,
        knuckle=stack(kx, ky, kz),
        ended=ended,
    )


def simulate_batch(
    positions: ArrayLike,
    velocities: ArrayLike,
    spins: ArrayLike,
    *,
    dt: float = 1e-3,
    method: Method = "euler",
    model: Model = "constant",
    drag_coefficient: float = 0.25,
    lift_coefficient: float = 0.25,
    mass_kg: float = BALL_MASS_KG,
    radius_m: float = BALL_RADIUS_M,
    air_density: float = AIR_DENSITY,
    gravity: float = G,
    t_max: float = 5.0,
    x_stop: float | None = None,
    ground_m: float = 0.0,
    knuckle_seeds: Sequence[int | None] | None = None,
) -> BatchTrajectory:
    """Integrate K kicks at once, vectorised over the kicks; each flight matches :func:`simulate`'s.

    Memory is K·T·6 floats (T the longest flight's samples): 10 000 kicks of 1.2 s at RK4 10 ms take ~60 MB, at
    Euler 1 ms ten times that; use ``x_stop`` and a coarser ``dt`` for large sweeps. Forces are not stored; run
    :func:`simulate` on a kick of interest for them.

    Args:
        positions: (K, 3) launch positions (m).
        velocities: (K, 3) launch velocities (m/s).
        spins: (K, 3) angular velocities (rad/s).
        knuckle_seeds: None, or K seeds (each None or an int) as :func:`simulate`'s ``knuckle_seed``.
        dt, method, model, drag_coefficient, lift_coefficient, mass_kg, radius_m, air_density, gravity, t_max,
            x_stop, ground_m: as for :func:`simulate`, shared by every kick.

    Returns:
        :class:`BatchTrajectory`.
    """
    p0, v0, w0 = (
        _rows("positions", positions),
        _rows("velocities", velocities),
        _rows("spins", spins),
    )
    k = len(p0)
    if len(v0) != k or len(w0) != k:
        raise ValueError(
            f"positions, velocities and spins must have the same length, got {k}, {len(v0)}, {len(w0)}"
        )
    if knuckle_seeds is None:
        seeds: list[int | None] = [None] * k
    else:
        seeds = [_seed("knuckle_seeds", seed) for seed in knuckle_seeds]
        if len(seeds) != k:
            raise ValueError(f"knuckle_seeds must have {k} entries, got {len(seeds)}")
    s = _settings(
        dt=dt,
        method=method,
        model=model,
        drag_coefficient=drag_coefficient,
        lift_coefficient=lift_coefficient,
        mass_kg=mass_kg,
        radius_m=radius_m,
        air_density=air_density,
        gravity=gravity,
        t_max=t_max,
        x_stop=x_stop,
        ground_m=ground_m,
    )
    kick = _kick_constants(v0, w0, seeds, s)

    def stepper_for(lanes: NDArray[np.intp]):
        """The step function for the kicks ``lanes`` only."""
        sub = _Kick(
            *(
                tuple(part[lanes] for part in value) if isinstance(value, tuple) else value[lanes]
                for value in (getattr(kick, field.name) for field in dataclasses.fields(kick))
            )
        )
        return _stepper(s.method, _force_law(_ARRAY_OPS, sub, s)[1], s.dt)

    state = np.concatenate(
        (p0, v0), axis=1
    ).T.copy()  # (6, K); finished kicks keep their final state
    t_last = np.zeros(k)
    frames = [state.T.copy()]  # (K, 6) per sample
    times = [t_last.copy()]
    lanes = np.arange(k)  # the kicks being stepped; compacted as they land
    flying = np.ones(k, dtype=bool)  # which of ``lanes`` are still in the air
    step = stepper_for(lanes)
    n_samples = np.ones(k, dtype=np.int64)
    ended = np.full(k, "t_max", dtype="<U6")
    x_stop_at = np.inf if s.x_stop is None else s.x_stop
    n_steps = math.ceil(s.t_max / s.dt - 1e-9)
    for n in range(n_steps):
        if not flying.any():
            break
        old = state[:, lanes]
        x, y, z, vx, vy, vz = old
        new = np.array(step(x, y, z, vx, vy, vz, n * s.dt))
        t_new = np.full(lanes.size, (n + 1) * s.dt)
        done = flying & ((new[2] <= s.ground_m) | ((old[0] < x_stop_at) & (new[0] >= x_stop_at)))
        if done.any():
            end_p, end_v, end_t, hit_ground, _ = _finish(
                old[:3, done].T,
                old[3:, done].T,
                new[:3, done].T,
                new[3:, done].T,
                n * s.dt,
                s.dt,
                s,
            )
            new[:3, done] = end_p.T
            new[3:, done] = end_v.T
            t_new[done] = end_t
            ended[lanes[done]] = np.where(hit_ground, "ground", "x_stop")
        moving = lanes[
            flying
        ]  # landed kicks in ``lanes`` are stepped but never written: they are padding
        state[:, moving] = new[:, flying]
        t_last[moving] = t_new[flying]
        n_samples[moving] += 1
        frames.append(state.T.copy())
        times.append(t_last.copy())
        flying &= ~done
        if (
            flying.sum() < 0.75 * lanes.size
        ):  # rebuilding the force law for fewer lanes pays from here
            lanes = lanes[flying]
            flying = np.ones(lanes.size, dtype=bool)
            step = stepper_for(lanes)

    # (T, K, 6) stacks fast; the fields are (K, T, ·) views of it, no transposing copy.
    stacked = np.stack(frames).transpose(1, 0, 2)
    return BatchTrajectory(
        t=np.stack(times).T,
        position=stacked[:, :, :3],
        velocity=stacked[:, :, 3:],
        n_samples=n_samples,
        ended=ended,
    )


# --------------------------------------------------------------------------------------------- outcome
def _plane_crossing(
    t: NDArray[np.float64],
    position: NDArray[np.float64],
    velocity: NDArray[np.float64],
    n_samples: NDArray[np.int64],
    panel: Panel,
) -> tuple[NDArray[np.bool_], NDArray[np.float64], NDArray[np.float64]]:
    """First crossing of ``panel``'s plane in its normal direction, per flight; (K,), (K, 3), (K,)."""
    normal = _vector("normal_xy", panel.normal_xy, 2)
    length = float(np.hypot(*normal))
    if length == 0.0:
        raise ValueError("normal_xy must not be zero")
    n3 = np.array([normal[0], normal[1], 0.0]) / length
    c3 = np.array([panel.centre_xy[0], panel.centre_xy[1], 0.0])
    d = (position - c3) @ n3  # (K, T)
    dd = velocity @ n3
    index = np.arange(d.shape[1])
    valid = index[None, 1:] < n_samples[:, None]
    crosses = (d[:, :-1] < 0.0) & (d[:, 1:] >= 0.0) & valid
    found = crosses.any(axis=1)
    k = np.argmax(crosses, axis=1)
    rows = np.arange(len(d))
    h = t[rows, k + 1] - t[rows, k]
    h = np.where(h > 0.0, h, 1.0)
    ends = (d[rows, k], dd[rows, k], d[rows, k + 1], dd[rows, k + 1], h)
    # One flight (``outcome``): the Newton steps cost far less on floats than on (1,) arrays; same arithmetic.
    if len(d) == 1:
        frac = np.array([_crossing_fraction(_FLOAT_OPS, *(float(end[0]) for end in ends))])
    else:
        frac = _crossing_fraction(_ARRAY_OPS, *ends)
    point, _ = _hermite(
        position[rows, k],
        velocity[rows, k],
        position[rows, k + 1],
        velocity[rows, k + 1],
        h[:, None],
        frac[:, None],
    )
    when = t[rows, k] + frac * h
    point[~found] = np.nan
    when[~found] = np.nan
    return found, point, when


def _lateral(point: NDArray[np.float64], panel: Panel) -> NDArray[np.float64]:
    """Signed offset of points (K, 3) from the panel's centre line, along the panel (m)."""
    normal = np.asarray(panel.normal_xy, dtype=np.float64)
    normal = normal / np.hypot(*normal)
    along = np.array([-normal[1], normal[0]])
    return (point[:, :2] - np.asarray(panel.centre_xy)) @ along


def _classify(
    t: NDArray[np.float64],
    position: NDArray[np.float64],
    velocity: NDArray[np.float64],
    n_samples: NDArray[np.int64],
    wall: Panel,
    goal: Panel,
    radius_m: float,
):
    wall_found, wall_point, wall_time = _plane_crossing(t, position, velocity, n_samples, wall)
    goal_found, goal_point, goal_time = _plane_crossing(t, position, velocity, n_samples, goal)
    # The ball touches the wall if its centre comes within a radius of the defenders' outline.
    in_wall = (
        wall_found
        & (np.abs(_lateral(wall_point, wall)) <= 0.5 * wall.width_m + radius_m)
        & (wall_point[:, 2] <= wall.height_m + radius_m)
    )
    # A goal needs the whole ball inside the posts and under the bar.
    inside = np.abs(_lateral(goal_point, goal)) <= 0.5 * goal.width_m - radius_m
    under = goal_point[:, 2] <= goal.height_m - radius_m
    result = np.full(len(t), "short", dtype="<U5")
    result[goal_found & inside & under] = "goal"
    result[goal_found & inside & ~under] = "over"
    result[goal_found & ~inside] = "wide"
    result[in_wall] = "wall"
    return result, wall_point, goal_point, wall_time, goal_time


def outcome(
    trajectory: Trajectory, wall: Panel, goal: Panel, *, radius_m: float = BALL_RADIUS_M
) -> Outcome:
    """Judge one flight against the wall and the goal.

    The ball hits the wall when its centre crosses the wall's plane within a radius of the defenders' outline
    (width × height). Otherwise, where its centre crosses the goal's plane decides: the whole ball inside the posts
    and under the bar is a goal; outside a post is wide; inside the posts but touching or above the bar is over. A
    flight that ends (lands, or reaches ``t_max``) before the goal's plane is short. Posts and bar do not rebound.

    Args:
        trajectory: from :func:`simulate`.
        wall: the wall, e.g. from :func:`free_kick_panels`.
        goal: the goal mouth.
        radius_m: ball radius (m).

    Returns:
        :class:`Outcome`.
    """
    radius = _positive_scalar("radius_m", radius_m)
    n = np.array([len(trajectory.t)], dtype=np.int64)
    result, wall_point, goal_point, wall_time, goal_time = _classify(
        trajectory.t[None],
        trajectory.position[None],
        trajectory.velocity[None],
        n,
        wall,
        goal,
        radius,
    )
    wall_ok, goal_ok = bool(np.isfinite(wall_time[0])), bool(np.isfinite(goal_time[0]))
    return Outcome(
        result=str(result[0]),  # type: ignore[arg-type]
        wall_point=wall_point[0] if wall_ok else None,
        goal_point=goal_point[0] if goal_ok else None,
        wall_time=float(wall_time[0]) if wall_ok else None,
        goal_time=float(goal_time[0]) if goal_ok else None,
    )


def outcome_batch(
    batch: BatchTrajectory, wall: Panel, goal: Panel, *, radius_m: float = BALL_RADIUS_M
) -> BatchOutcome:
    """:func:`outcome` for every kick of a batch, vectorised.

    Args:
        batch: from :func:`simulate_batch`.
        wall: the wall.
        goal: the goal mouth.
        radius_m: ball radius (m).

    Returns:
        :class:`BatchOutcome`.
    """
    radius = _positive_scalar("radius_m", radius_m)
    result, wall_point, goal_point, _, _ = _classify(
        batch.t, batch.position, batch.velocity, batch.n_samples, wall, goal, radius
    )
    return BatchOutcome(result=result, wall_point=wall_point, goal_point=goal_point)


def spin_vector(rate_rev_s: float, axis: ArrayLike) -> NDArray[np.float64]:
    """Angular velocity (rad/s) from a spin rate in rev/s about ``axis`` (any length, normalised here).

    Args:
        rate_rev_s: spin rate (rev/s, ≥ 0).
        axis: (3,) spin axis; +z is sidespin curling a ball kicked along +x to the left.

    Returns:
        (3,) ω (rad/s).
    """
    rate = _non_negative_scalar("rate_rev_s", rate_rev_s)
    direction = _vector("axis", axis, 3)
    length = float(np.linalg.norm(direction))
    if length == 0.0:
        raise ValueError("axis must not be zero")
    return 2.0 * math.pi * rate * direction / length


def launch_velocity(
    speed_ms: float, elevation_rad: float, azimuth_rad: float
) -> NDArray[np.float64]:
    """Velocity (3,) in m/s from speed, elevation above the ground and azimuth to the left of +x."""
    speed = _non_negative_scalar("speed_ms", speed_ms)
    elevation = _finite_scalar("elevation_rad", elevation_rad)
    azimuth = _finite_scalar("azimuth_rad", azimuth_rad)
    return speed * np.array(
        [
            math.cos(elevation) * math.cos(azimuth),
            math.cos(elevation) * math.sin(azimuth),
            math.sin(elevation),
        ]
    )
