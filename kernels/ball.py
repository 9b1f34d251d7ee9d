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
direction, ``½·ρ·A·|v|²·C_K·w·(cos θ·sin(Ωt + φ₁)·n₁ + sin θ·sin(Ωt + φ₂)·n₂)``, with Ω = 2π·|v₀|/15 m, n₁ = ẑ × v̂₀
normalised (horizontal, to the left; +y for a vertical kick) and n₂ = v̂₀ × n₁, and θ, φ₁, φ₂ drawn in that order by
``numpy.random.default_rng(knuckle_seed).uniform(0, 2π, 3)`` so a seed always gives the same flight.
w = max(0, 1 − S₀/0.05) fades the effect out as launch spin grows (S₀ the launch spin parameter): any real spin
steadies the wake. With C_K = 0.10 the median (over seeds) peak deviation from the spinless flight of a 25 m/s
kick at 12° over 25 m is 0.18 m for seeds 0–29 and 0.21 m for seeds 0–199 (RK4, 10 ms): a little under the "about
one ball diameter" (0.22 m) those papers report.

Assumptions: spin is constant in flight (spin decay over a 1–2 s free kick is a few percent); still air; the ball is
rigid and stops at the first touch of the ground (no bounce or roll); a ball that touches the wall or the frame does
not rebound. Integrators: ``"euler"`` is the seed's fixed-step method (v += a·dt, then x += v·dt; first order),
``"rk4"`` the classical fourth-order Runge–Kutta. The last sample of a flight is placed on the ground (or on the
``x_stop`` plane) by cubic Hermite interpolation of the last step, which keeps RK4's accuracy: the first root of
that cubic in the step, bracketed between its turning points (a ball may rise, peak and land within one long step).
Wall and goal crossings are found the same way. Every step is ``dt`` but the last, which is shortened to end exactly
on ``t_max``. Planes are closed on the start side: a ball launched on the ``x_stop``, wall or goal plane and moving
through it crosses at t = 0; one launched on the ground (``z = ground_m``) and not moving up lands at t = 0; one
launched below it is refused. The measured model refuses a launch spin parameter r·|ω|/max(|v|, 1 m/s) above 10³
(its fits stop at S ≈ 0.3; 10³ is ~2·10⁵ rev/s at 25 m/s) with a ``ValueError`` naming the spin.

Implementation: every numeric core (force law, Euler and RK4 steps, the Hermite end of a flight, plane crossings and
the verdict) is written once, on scalars, and compiled by numba (``@njit(cache=True)``). One kick and a batch run the
same compiled flight; a batch runs its kicks in parallel (``prange``, :func:`numba.get_num_threads` threads). The
Python functions below only validate (``ValueError`` naming the argument) and package arrays. Compiled code is cached
in ``__pycache__`` beside this file, or, where that is read-only (an installed package), in numba's user-wide cache
(``~/.cache/numba``; ``NUMBA_CACHE_DIR`` overrides both; with neither writable, no disk cache). :func:`warm_up`
compiles (or loads) every core. A flight whose steps overshoot the drag, so that |v|² + 2gz grows far past its launch
value (or overflows), raises ``ValueError`` naming ``dt`` rather than returning an absurd path.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import threading
from collections.abc import Callable, Sequence
from typing import Any, Literal

import numpy as np
from numba import njit, prange
from numpy.typing import ArrayLike, NDArray

from kernels import _checks

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
# Codes of the compiled flight's ending (3, diverged, raises) and of its verdict.
_ENDINGS: tuple[Ending, ...] = ("ground", "x_stop", "t_max")
_RESULTS: tuple[Result, ...] = ("goal", "wall", "over", "wide", "short")

# Goff & Carré 2010 no-spin drag fit, in Reynolds number (see the module docstring).
_RE_CRISIS = 1.815e5
_RE_WIDTH = 1.949e4

# The compiled cores read their settings from one float64 vector; these are its slots.
_Q, _GRAVITY, _RADIUS, _RE_PER_SPEED, _C_D, _C_L, _MASS, _DT, _GROUND, _X_STOP = range(10)
_N_STEPS, _RK4, _MEASURED, _T_MAX = 10, 11, 12, 13
# ... and each kick's constants from one row of 14: ω̂, |ω|, knuckle gain ½ρA·C_K·w/m, rate Ω, phases φ₁ φ₂,
# cos θ·n₁ and sin θ·n₂.
_AXIS, _RATE, _GAIN, _OMEGA, _PHASE, _N1, _N2 = 0, 3, 4, 5, 6, 8, 11
_N_KICK = 14

_SPIN_PARAMETER_LIMIT = 1e3
"""Largest spin parameter S = r·|ω|/|v| the measured model accepts at launch; its fits stop at S ≈ 0.3 (held
constant beyond) and no kick comes near 10 (S = 1e3 is ~2·10⁵ rev/s at 25 m/s)."""

_RESERVE_BYTES = 2**31
"""Largest time-major reservation :func:`simulate_batch` makes before it counts the samples first (bytes)."""
# numba's workqueue threading layer (the fallback where neither TBB nor OpenMP is present) must not launch two
# parallel kernels at once; the scene's workers and the app's warm-up may call from different threads.
_PARALLEL = threading.Lock()


_UNCACHED: list[str] = []
"""Compiled cores that run without numba's disk cache (none where a cache directory is writable)."""


def _compiled(**options: Any) -> Callable[[Callable[..., object]], Any]:
    """``numba.njit(cache=True, **options)``; without the disk cache where numba finds no writable directory.

    numba caches beside the module, else in ``~/.cache/numba`` (or ``NUMBA_CACHE_DIR``); where none of those is
    writable it refuses ``cache=True`` outright, which would make this module fail to import.
    """

    def decorate(function: Callable[..., object]) -> Any:
        try:
            return njit(cache=True, **options)(function)
        except RuntimeError as error:
            if "no locator available" not in str(error):
                raise
            if not _UNCACHED:
                logging.getLogger(__name__).warning(
                    "no writable numba cache directory: the ball kernels compile at every start"
                )
            _UNCACHED.append(function.__name__)
            return njit(**options)(function)

    return decorate


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
    """:class:`Outcome` for each kick of a batch; crossings are NaN where there was none."""

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
    if not normal.any():
        raise ValueError("goal_normal_xy must not be zero")
    aim = centre - ball
    distance = float(np.hypot(*aim))
    if distance <= WALL_DISTANCE_M:
        raise ValueError(
            f"ball_xy must be more than {WALL_DISTANCE_M} m from the goal, got {distance:.2f} m"
        )
    aim /= distance
    left = np.array([-aim[1], aim[0]])
    wall_foot = (
        ball + WALL_DISTANCE_M * aim + _checks.finite_number("wall_offset_m", wall_offset_m) * left
    )
    wall = Panel(
        (float(wall_foot[0]), float(wall_foot[1])),
        (float(aim[0]), float(aim[1])),
        _checks.positive("wall_width_m", wall_width_m),
        _checks.positive("wall_height_m", wall_height_m),
    )
    goal = Panel(
        (float(centre[0]), float(centre[1])),
        (float(normal[0]), float(normal[1])),
        GOAL_WIDTH_M,
        GOAL_HEIGHT_M,
    )
    return wall, goal


# --------------------------------------------------------------------------------------------- validation
def _booleans(value: object) -> bool:
    """Whether ``value`` is a boolean array or a sequence holding booleans (refused like a bool scalar)."""
    if isinstance(value, np.ndarray):
        return value.dtype == np.bool_
    if isinstance(value, (list, tuple)):
        for item in value:  # a plain loop: this runs on every kick's three vectors
            kind = type(item)
            if kind is bool or kind is np.bool_:
                return True
            if (kind is list or kind is tuple or kind is np.ndarray) and _booleans(item):
                return True
        return False
    return isinstance(value, (bool, np.bool_))


def _vector(name: str, value: ArrayLike, size: int) -> NDArray[np.float64]:
    """:func:`kernels._checks.vector`, and no boolean anywhere inside (special to this kernel: numpy turns a
    ``[1.0, True, 2.0]`` into floats, and a flag where a coordinate belongs is a caller's bug)."""
    if _booleans(value):
        raise ValueError(f"{name} must be numbers, not booleans, got {value!r}")
    return _checks.vector(name, value, size)


def _rows(name: str, value: ArrayLike) -> NDArray[np.float64]:
    """:func:`kernels._checks.points` with the same boolean guard as :func:`_vector`."""
    if _booleans(value):
        raise ValueError(f"{name} must be numbers, not booleans")
    return _checks.points(name, value, 3)


def _fast_floats(value: object) -> list[float] | None:
    """The three finite floats of a tuple, list or float64 (3,) array, or None for anything else (then checked in
    full by :func:`_vector`): the common case of a single kick, at a fraction of a microsecond."""
    kind = type(value)
    if kind is np.ndarray:
        array: Any = value
        if array.dtype != np.float64 or array.shape != (3,):
            return None
        items = array.tolist()
    elif kind is tuple or kind is list:
        items: Any = value
        if len(items) != 3:
            return None
    else:
        return None
    x, y, z = items
    if type(x) is float and type(y) is float and type(z) is float and math.isfinite(x + y + z):
        return [x, y, z]
    return None


def _seed(name: str, value: object) -> int | None:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0:
        raise ValueError(f"{name} must be None or an integer >= 0, got {value!r}")
    return int(value)


@dataclasses.dataclass(frozen=True)
class FlightConfig:
    """Settings shared by every kick of a flight or a batch: the ball, the air, the integrator and the end.

    Validated once, here (``ValueError`` naming the field); :func:`simulate`, :func:`simulate_batch` and
    :func:`simulate_outcomes` then reuse it without checking again, so build one and pass it to many calls.
    """

    dt: float = 1e-3
    """Fixed step (s, > 0), at least ``t_max``/10⁶."""
    method: Method = "euler"
    """``"euler"`` (the seed's: v += a·dt, then x += v·dt) or ``"rk4"``."""
    model: Model = "constant"
    """``"constant"`` coefficients or ``"measured"`` spin- and Reynolds-dependent fits (module docstring)."""
    drag_coefficient: float = 0.25
    """C_D of the constant model (dimensionless, ≥ 0)."""
    lift_coefficient: float = 0.25
    """C_L of the constant model (dimensionless, ≥ 0)."""
    mass_kg: float = BALL_MASS_KG
    """Ball mass (kg, > 0)."""
    radius_m: float = BALL_RADIUS_M
    """Ball radius (m, > 0)."""
    air_density: float = AIR_DENSITY
    """ρ (kg/m³, ≥ 0; 0 is a vacuum)."""
    gravity: float = G
    """g (m/s², downward when positive)."""
    t_max: float = 5.0
    """Longest flight to integrate (s, > 0)."""
    x_stop: float | None = None
    """Optional plane x = x_stop (m) that ends a flight when crossed in +x."""
    ground_m: float = 0.0
    """Height of the ball's centre at which it touches the ground (m); the radius for a ball whose underside
    meets the turf at z = 0."""
    settings: NDArray[np.float64] = dataclasses.field(init=False, repr=False, compare=False)
    """(14,) the compiled cores' settings vector (slots ``_Q`` … ``_T_MAX``), read-only; derived, not an argument."""

    def __post_init__(self) -> None:
        step = _checks.positive("dt", self.dt)
        duration = _checks.positive("t_max", self.t_max)
        if duration / step > _MAX_STEPS:
            raise ValueError(
                f"dt must be at least t_max/{_MAX_STEPS} = {duration / _MAX_STEPS:g} s, got {step:g}"
            )
        if self.method not in ("euler", "rk4"):
            raise ValueError(f"method must be 'euler' or 'rk4', got {self.method!r}")
        if self.model not in ("constant", "measured"):
            raise ValueError(f"model must be 'constant' or 'measured', got {self.model!r}")
        c_d = _checks.non_negative("drag_coefficient", self.drag_coefficient)
        c_l = _checks.non_negative("lift_coefficient", self.lift_coefficient)
        mass = _checks.positive("mass_kg", self.mass_kg)
        radius = _checks.positive("radius_m", self.radius_m)
        density = _checks.non_negative("air_density", self.air_density)
        g = _checks.finite_number("gravity", self.gravity)
        stop = math.inf if self.x_stop is None else _checks.finite_number("x_stop", self.x_stop)
        ground = _checks.finite_number("ground_m", self.ground_m)
        # In slot order: _Q (½ρA/m, 1/m), _GRAVITY, _RADIUS, _RE_PER_SPEED, _C_D, _C_L, _MASS, _DT, _GROUND,
        # _X_STOP, _N_STEPS, _RK4, _MEASURED, _T_MAX.
        settings = np.array(
            [
                0.5 * density * math.pi * radius**2 / mass,
                g,
                radius,
                density * 2.0 * radius / AIR_VISCOSITY,
                c_d,
                c_l,
                mass,
                step,
                ground,
                stop,
                max(1, math.ceil(duration / step - 1e-9)),
                self.method == "rk4",
                self.model == "measured",
                duration,
            ]
        )
        settings.setflags(write=False)
        object.__setattr__(self, "settings", settings)


_DEFAULT_CONFIG = FlightConfig()

_CONFIGS: dict[object, FlightConfig] = {}
"""Configs already built from keyword options, keyed by (name, type, value) of each: a caller that passes the same
options on every call validates them once."""
_CONFIGS_MAX = 256


def _flight_config(config: FlightConfig | None, options: dict[str, Any]) -> FlightConfig:
    """``config``, or one built from ``options`` (:class:`FlightConfig` fields; both together is refused)."""
    if not options:
        if config is None:
            return _DEFAULT_CONFIG
        if type(config) is not FlightConfig:
            raise ValueError(f"config must be a FlightConfig, got {type(config).__name__}")
        return config
    if config is not None:
        raise ValueError(
            f"pass either config or its fields as keywords, not both: {sorted(options)}"
        )
    try:
        key: object = tuple((name, type(value), value) for name, value in options.items())
        hash(key)
    except TypeError:  # an unhashable value (an array): validated below, never cached
        key = None
    if key is not None:
        cached = _CONFIGS.get(key)
        if cached is not None:
            return cached
    built = FlightConfig(**options)  # an unknown keyword is a TypeError, as for any function
    if key is not None:
        if len(_CONFIGS) >= _CONFIGS_MAX:
            _CONFIGS.clear()
        _CONFIGS[key] = built
    return built


def _launches(
    positions: NDArray[np.float64],
    velocities: NDArray[np.float64],
    spins: NDArray[np.float64],
    seeds: Sequence[int | None],
) -> NDArray[np.float64]:
    """(K, 13) launch rows of the compiled cores: position, velocity, spin, knuckle angles θ φ₁ φ₂, knuckle flag.

    ``numpy.random.default_rng(seed)`` draws the angles here in Python, so a seed gives the same flight as it always
    has; the compiled :func:`_fill_kick` derives the rest of each kick's constants.
    """
    launches = np.concatenate((positions, velocities, spins, np.zeros((len(positions), 4))), axis=1)
    for k, seed in enumerate(seeds):
        if seed is not None:
            launches[k, 9:12] = np.random.default_rng(seed).uniform(0.0, 2.0 * np.pi, size=3)
            launches[k, 12] = 1.0
    return launches


# --------------------------------------------------------------------------------------------- force law
@_compiled(inline="always")
def _norm(v):
    """|v| of a (3,) vector without overflow or underflow in the squares (a spin of 1e200 rad/s still has an axis)."""
    scale = max(abs(v[0]), abs(v[1]), abs(v[2]))
    if scale == 0.0 or not math.isfinite(scale):
        return scale
    return scale * math.sqrt((v[0] / scale) ** 2 + (v[1] / scale) ** 2 + (v[2] / scale) ** 2)


@_compiled()
def _fill_kick(launch, config, kick):
    """One kick's (14,) constants (see the slots above) from its (13,) launch row."""
    velocity, spin, angles = launch[3:6], launch[6:9], launch[9:12]
    rate = _norm(spin)
    kick[:] = 0.0
    if rate > 0.0:
        for i in range(3):
            kick[_AXIS + i] = spin[i] / rate
    kick[_RATE] = rate
    speed = _norm(velocity)
    if launch[12] == 0.0 or speed == 0.0:
        return
    weight = max(0.0, 1.0 - config[_RADIUS] * rate / speed / KNUCKLE_SPIN_LIMIT)
    ux, uy, uz = velocity[0] / speed, velocity[1] / speed, velocity[2] / speed
    hx, hy = -uy, ux  # horizontal normal to the launch direction
    length = math.sqrt(hx * hx + hy * hy)
    if length < 1e-9:  # kicked straight up: any horizontal direction will do
        hx, hy, length = 0.0, 1.0, 1.0
    hx, hy = hx / length, hy / length
    vertical = (-uz * hy, uz * hx, ux * hy - uy * hx)  # u × h
    theta = angles[0]
    kick[_GAIN] = config[_Q] * KNUCKLE_COEFFICIENT * weight
    kick[_OMEGA] = 2.0 * math.pi * speed / KNUCKLE_WAVELENGTH_M
    kick[_PHASE], kick[_PHASE + 1] = angles[1], angles[2]
    kick[_N1], kick[_N1 + 1] = math.cos(theta) * hx, math.cos(theta) * hy
    for i in range(3):
        kick[_N2 + i] = math.sin(theta) * vertical[i]


@_compiled(inline="always")
def _factors(speed, kick, config):
    """(−½ρA·C_D·|v|/m, ½ρA·C_L·|v|/m) at this speed: drag and lift per unit velocity and mass (1/s)."""
    q = config[_Q]
    if config[_MEASURED] == 0.0:
        return -q * config[_C_D] * speed, q * config[_C_L] * speed
    spin_parameter = config[_RADIUS] * kick[_RATE] / max(speed, 1e-9)
    lift = 0.9 * min(spin_parameter, 0.3)  # Asai et al. 2007
    arg = min((config[_RE_PER_SPEED] * speed - _RE_CRISIS) / _RE_WIDTH, 50.0)
    still = 0.155 + 0.346 / (1.0 + math.exp(arg))  # Goff & Carré 2010
    spinning = 0.4127 * max(spin_parameter, 0.05) ** 0.3056
    drag = still + min(spin_parameter / 0.05, 1.0) * (spinning - still)
    return -q * drag * speed, q * lift * speed


@_compiled(inline="always")
def _knuckle(speed, t, kick):
    """Knuckle side force per unit mass (m/s², 3 values); zero when the kick has none."""
    gain = kick[_GAIN]
    if gain == 0.0:
        return 0.0, 0.0, 0.0
    kk = gain * speed * speed
    s1 = kk * math.sin(kick[_OMEGA] * t + kick[_PHASE])
    s2 = kk * math.sin(kick[_OMEGA] * t + kick[_PHASE + 1])
    return (
        s1 * kick[_N1] + s2 * kick[_N2],
        s1 * kick[_N1 + 1] + s2 * kick[_N2 + 1],
        s1 * kick[_N1 + 2] + s2 * kick[_N2 + 2],
    )


@_compiled(inline="always")
def _acceleration(vx, vy, vz, t, kick, config):
    """Total acceleration (m/s²): drag, Magnus (ω̂ × v), knuckle and gravity."""
    speed = math.sqrt(vx * vx + vy * vy + vz * vz)
    kd, kl = _factors(speed, kick, config)
    wx, wy, wz = kick[_AXIS], kick[_AXIS + 1], kick[_AXIS + 2]
    sx, sy, sz = _knuckle(speed, t, kick)
    return (
        kd * vx + kl * (wy * vz - wz * vy) + sx,
        kd * vy + kl * (wz * vx - wx * vz) + sy,
        kd * vz + kl * (wx * vy - wy * vx) + sz - config[_GRAVITY],
    )


@_compiled()
def _forces(t, state, kick, config, forces):
    """Drag, Magnus, gravity and knuckle forces (N) at each sample: ``forces`` (N, 12) from ``state`` (N, 6)."""
    m = config[_MASS]
    wx, wy, wz = kick[_AXIS], kick[_AXIS + 1], kick[_AXIS + 2]
    for i in range(len(t)):
        vx, vy, vz = state[i, 3], state[i, 4], state[i, 5]
        speed = math.sqrt(vx * vx + vy * vy + vz * vz)
        kd, kl = _factors(speed, kick, config)
        sx, sy, sz = _knuckle(speed, t[i], kick)
        forces[i, 0], forces[i, 1], forces[i, 2] = m * kd * vx, m * kd * vy, m * kd * vz
        forces[i, 3] = m * kl * (wy * vz - wz * vy)
        forces[i, 4] = m * kl * (wz * vx - wx * vz)
        forces[i, 5] = m * kl * (wx * vy - wy * vx)
        forces[i, 6], forces[i, 7], forces[i, 8] = 0.0, 0.0, -m * config[_GRAVITY]
        forces[i, 9], forces[i, 10], forces[i, 11] = m * sx, m * sy, m * sz


# --------------------------------------------------------------------------------------------- flight
@_compiled(inline="always")
def _step(x, y, z, vx, vy, vz, t, dt, kick, config):
    """One step of length ``dt`` of the configured method: (x, y, z, vx, vy, vz) after it."""
    if config[_RK4] == 0.0:  # the seed's Euler: velocity first, then position with the new velocity
        ax, ay, az = _acceleration(vx, vy, vz, t, kick, config)
        vx1, vy1, vz1 = vx + ax * dt, vy + ay * dt, vz + az * dt
        return x + vx1 * dt, y + vy1 * dt, z + vz1 * dt, vx1, vy1, vz1
    half, sixth = 0.5 * dt, dt / 6.0
    # The acceleration does not depend on position, so each stage's position slope is its velocity.
    a1x, a1y, a1z = _acceleration(vx, vy, vz, t, kick, config)
    v2x, v2y, v2z = vx + half * a1x, vy + half * a1y, vz + half * a1z
    a2x, a2y, a2z = _acceleration(v2x, v2y, v2z, t + half, kick, config)
    v3x, v3y, v3z = vx + half * a2x, vy + half * a2y, vz + half * a2z
    a3x, a3y, a3z = _acceleration(v3x, v3y, v3z, t + half, kick, config)
    v4x, v4y, v4z = vx + dt * a3x, vy + dt * a3y, vz + dt * a3z
    a4x, a4y, a4z = _acceleration(v4x, v4y, v4z, t + dt, kick, config)
    return (
        x + sixth * (vx + 2.0 * (v2x + v3x) + v4x),
        y + sixth * (vy + 2.0 * (v2y + v3y) + v4y),
        z + sixth * (vz + 2.0 * (v2z + v3z) + v4z),
        vx + sixth * (a1x + 2.0 * (a2x + a3x) + a4x),
        vy + sixth * (a1y + 2.0 * (a2y + a3y) + a4y),
        vz + sixth * (a1z + 2.0 * (a2z + a3z) + a4z),
    )


@_compiled(inline="always")
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
        (6 * s2 - 6 * s) * p0
        + (3 * s2 - 4 * s + 1) * h * v0
        + (6 * s - 6 * s2) * p1
        + (3 * s2 - 2 * s) * h * v1
    ) / h
    return value, slope


@_compiled(inline="always")
def _cubic_value(d0, dd0, d1, dd1, h, s):
    value, _ = _hermite(d0, dd0, d1, dd1, h, s)
    return value


@_compiled(inline="always")
def _crossing_fraction(d0, dd0, d1, dd1, h):
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


@_compiled()
def _fly(launch, kick, config, t_out, state_out):
    """Step one kick (its (13,) launch row and (14,) constants) until it lands, passes ``x_stop`` or runs out of time.

    Writes each sample's time to ``t_out`` (T,) and position then velocity to ``state_out`` (T, 6), T ≥ n_steps + 1;
    with T = 0 it only counts.

    Returns:
        (samples written, ending code: 0 ground, 1 x_stop, 2 t_max, 3 diverged: gained energy, or inf/NaN).
    """
    store = len(t_out) > 0
    dt, ground, x_stop = config[_DT], config[_GROUND], config[_X_STOP]
    n_steps = int(config[_N_STEPS])
    x, y, z, vx, vy, vz = launch[0], launch[1], launch[2], launch[3], launch[4], launch[5]
    # Drag dissipates and Magnus does no work, so |v|² + 2gz never grows but for the knuckle force's small push;
    # a step that overshoots the drag makes it grow without bound. Stop that flight (ending 3) rather than draw it.
    g = config[_GRAVITY]
    energy_limit = vx * vx + vy * vy + vz * vz + 2.0 * g * z
    energy_limit += 3.0 * (vx * vx + vy * vy + vz * vz + 2.0 * abs(g) * (abs(z) + 1.0)) + 100.0
    if store:
        t_out[0] = 0.0
        state_out[0, 0], state_out[0, 1], state_out[0, 2] = x, y, z
        state_out[0, 3], state_out[0, 4], state_out[0, 5] = vx, vy, vz
    t_max = config[_T_MAX]
    for n in range(n_steps):
        # Every step is dt but the last, which ends exactly on t_max.
        h = dt if n < n_steps - 1 else t_max - (n_steps - 1) * dt
        x1, y1, z1, vx1, vy1, vz1 = _step(x, y, z, vx, vy, vz, n * dt, h, kick, config)
        if vx1 * vx1 + vy1 * vy1 + vz1 * vz1 + 2.0 * g * z1 > energy_limit:
            return n + 1, 3
        # The stop plane is closed on the start side: a kick launched on it, moving on, stops at t = 0.
        hit_ground = z1 <= ground
        hit_stop = x < x_stop <= x1 or (n == 0 and x == x_stop and x1 > x)
        if hit_ground or hit_stop:
            # End on whichever of the ground and the stop plane the cubic through this step reaches first.
            f_ground = (
                _crossing_fraction(z - ground, vz, z1 - ground, vz1, h) if hit_ground else np.inf
            )
            f_stop = (
                _crossing_fraction(x_stop - x, -vx, x_stop - x1, -vx1, h) if hit_stop else np.inf
            )
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
                t_out[n + 1] = n * dt + f * h
                state_out[n + 1, 0], state_out[n + 1, 1], state_out[n + 1, 2] = ex, ey, ez
                state_out[n + 1, 3], state_out[n + 1, 4], state_out[n + 1, 5] = evx, evy, evz
            return n + 2, ending
        x, y, z, vx, vy, vz = x1, y1, z1, vx1, vy1, vz1
        if store:
            t_out[n + 1] = (n + 1) * dt if n < n_steps - 1 else t_max
            state_out[n + 1, 0], state_out[n + 1, 1], state_out[n + 1, 2] = x, y, z
            state_out[n + 1, 3], state_out[n + 1, 4], state_out[n + 1, 5] = vx, vy, vz
    # A state that overflowed stays inf or NaN to the end (NaN fails the ground test, so it runs to t_max).
    return n_steps + 1, 2 if math.isfinite(x + y + z + vx + vy + vz) else 3


@_compiled()
def _simulate_one(launch, config, t_out, state_out, forces_out):
    """:func:`simulate`'s compiled part: the kick's constants, its flight and the forces along it."""
    kick = np.empty(_N_KICK)
    _fill_kick(launch, config, kick)
    n, ending = _fly(launch, kick, config, t_out, state_out)
    _forces(t_out[:n], state_out[:n], kick, config, forces_out[:n])
    if not np.isfinite(
        forces_out[:n]
    ).all():  # a finite flight with an infinite force: a 1e-300 kg ball
        ending = 3
    return n, ending


@_compiled(parallel=True)
def _fly_batch(launches, config, t_out, state_out, n_samples, endings):
    """Every kick's flight into column k of ``t_out`` (T, K) and ``state_out`` (T, K, 6), in parallel.

    T must hold each flight (n_steps + 1 always does); with T = 0 it only counts the samples.
    """
    for k in prange(len(launches)):
        kick = np.empty(_N_KICK)
        _fill_kick(launches[k], config, kick)
        n_samples[k], endings[k] = _fly(launches[k], kick, config, t_out[:, k], state_out[:, k])


@_compiled(parallel=True)
def _pad(t, state, n_samples):
    """Repeat each flight's last sample to the end of ``t`` (T, K) and ``state`` (T, K, 6)."""
    for k in prange(len(n_samples)):
        last = n_samples[k] - 1
        for i in range(last + 1, t.shape[0]):
            t[i, k] = t[last, k]
            state[i, k, :] = state[last, k, :]


# --------------------------------------------------------------------------------------------- outcome
@_compiled()
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
            s = _crossing_fraction(-d0, -dd0, -d1, -dd1, h)
            crossing[0] = t[i] + s * h
            for c in range(3):
                p0, v0, p1, v1 = (
                    position[i, c],
                    velocity[i, c],
                    position[i + 1, c],
                    velocity[i + 1, c],
                )
                crossing[1 + c], _ = _hermite(p0, v0, p1, v1, h, s)
            return


@_compiled()
def _judge(t, position, velocity, n, panels, radius, crossings):
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


@_compiled(parallel=True)
def _judge_batch(t, position, velocity, n_samples, panels, radius, results, crossings):
    """:func:`_judge` for every flight of a (K, T) batch, in parallel."""
    for k in prange(len(n_samples)):
        results[k] = _judge(
            t[k], position[k], velocity[k], n_samples[k], panels, radius, crossings[k]
        )


@_compiled(parallel=True)
def _fly_and_judge(launches, config, panels, results, crossings, endings):
    """Fly each kick into its own scratch buffer and judge it at once (ball radius from ``config``): nothing kept."""
    rows = int(config[_N_STEPS]) + 1
    for k in prange(len(launches)):
        kick, t, state = np.empty(_N_KICK), np.empty(rows), np.empty((rows, 6))
        _fill_kick(launches[k], config, kick)
        n, endings[k] = _fly(launches[k], kick, config, t, state)
        results[k] = _judge(t, state[:, :3], state[:, 3:], n, panels, config[_RADIUS], crossings[k])


# --------------------------------------------------------------------------------------------- public API
def _kick_rows(
    positions: ArrayLike,
    velocities: ArrayLike,
    spins: ArrayLike,
    knuckle_seeds: Sequence[int | None] | None,
) -> NDArray[np.float64]:
    """Validated kicks of a batch as (K, 13) launch rows (see :func:`_launches`)."""
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
        if isinstance(knuckle_seeds, (str, bytes)) or not isinstance(
            knuckle_seeds, (Sequence, np.ndarray)
        ):
            raise ValueError(
                f"knuckle_seeds must be None or a sequence of K seeds, got {knuckle_seeds!r}"
            )
        seeds = [_seed("knuckle_seeds", seed) for seed in knuckle_seeds]
        if len(seeds) != k:
            raise ValueError(f"knuckle_seeds must have {k} entries, got {len(seeds)}")
    return _launches(p0, v0, w0, seeds)


def _safe_norms(rows: NDArray[np.float64]) -> NDArray[np.float64]:
    """|row| of each row of a (K, 3) array without overflow or underflow in the squares."""
    scale = np.abs(rows).max(axis=1, initial=0.0)
    safe = np.where(scale > 0.0, scale, 1.0)
    return scale * np.sqrt(((rows / safe[:, None]) ** 2).sum(axis=1))


def _check_launches(
    launches: NDArray[np.float64], config: NDArray[np.float64], batch: bool
) -> None:
    """Refuse a launch below the ground and, in the measured model, a spin far beyond its fits."""
    if not batch and not config[_MEASURED] and launches[0, 2] >= config[_GROUND]:
        return  # one kick in the constant model, above the ground: the common case, without array work
    low = np.flatnonzero(launches[:, 2] < config[_GROUND])
    if low.size:
        which = f"positions[{low[0]}]" if batch else "position"
        raise ValueError(
            f"{which} starts below the ground: z = {launches[low[0], 2]:g} m < ground_m = {config[_GROUND]:g} m"
        )
    if config[_MEASURED]:
        speeds = np.maximum(_safe_norms(launches[:, 3:6]), 1.0)
        spin_parameter = config[_RADIUS] * _safe_norms(launches[:, 6:9]) / speeds
        bad = np.flatnonzero(spin_parameter > _SPIN_PARAMETER_LIMIT)
        if bad.size:
            which = f"spins[{bad[0]}]" if batch else "spin"
            raise ValueError(
                f"{which} is too fast for the measured model: spin parameter S = r·|ω|/max(|v|, 1 m/s) = "
                f"{spin_parameter[bad[0]]:.3g} > {_SPIN_PARAMETER_LIMIT:g} (its fits stop at S ≈ 0.3)"
            )


def _refuse_overflow(endings: NDArray[np.int64], config: NDArray[np.float64]) -> None:
    """Raise where a flight overflowed to inf or NaN: an explicit step too long for its drag, or absurd input."""
    bad = np.flatnonzero(endings == 3)
    if bad.size:
        which = "the flight" if len(endings) == 1 else f"kicks {bad[:5].tolist()}"
        raise ValueError(
            f"dt = {config[_DT]:g} s is too long for {which}: each step overshoots the drag, so the ball gains "
            "energy until it overflows; use a smaller dt (or a smaller air_density or a larger mass_kg)"
        )


def simulate(
    position: ArrayLike,
    velocity: ArrayLike,
    spin: ArrayLike,
    config: FlightConfig | None = None,
    *,
    knuckle_seed: int | None = None,
    **options: Any,
) -> Trajectory:
    """Integrate one kick until the ball's centre reaches ``ground_m``, passes ``x_stop``, or ``t_max`` runs out.

    Args:
        position: (3,) launch position of the ball's centre (m).
        velocity: (3,) launch velocity (m/s).
        spin: (3,) angular velocity (rad/s); +z curls a ball kicked along +x to the left (+y), +y is topspin.
        config: the ball, air, integrator and end of the flight (:class:`FlightConfig`, validated once); default
            ``FlightConfig()``.
        knuckle_seed: turn on the knuckleball side force (near-zero spin only), drawn from this seed.
        **options: instead of ``config``, any of :class:`FlightConfig`'s fields as keywords (``dt=1e-2,
            method="rk4"``); the config built from them is cached, so repeating the same options costs no
            validation.

    Returns:
        :class:`Trajectory`, sampled every ``dt`` plus the interpolated end.

    Raises:
        ValueError: naming the argument, for non-finite, boolean or wrongly shaped input, an invalid
            :class:`FlightConfig` field, a position below ``ground_m``, a spin beyond the measured model's range
            (see the module docstring); naming dt when the steps overshoot the drag and the ball gains energy
            without bound (a step far too long for this speed, density and mass).
        TypeError: an unknown keyword.
    """
    flight = _flight_config(config, options)
    settings = flight.settings
    p0, v0, w0 = _fast_floats(position), _fast_floats(velocity), _fast_floats(spin)
    if p0 is None or v0 is None or w0 is None or knuckle_seed is not None:
        launch = _launches(
            _vector("position", position, 3)[None],
            _vector("velocity", velocity, 3)[None],
            _vector("spin", spin, 3)[None],
            [_seed("knuckle_seed", knuckle_seed)],
        )
        _check_launches(launch, settings, batch=False)
        launch = launch[0]
    else:  # three plain vectors and no knuckle: the launch row at once
        launch = np.array(p0 + v0 + w0 + _NO_KNUCKLE)
        if settings[_MEASURED] or p0[2] < settings[_GROUND]:
            _check_launches(launch[None], settings, batch=False)
    rows = int(settings[_N_STEPS]) + 1
    t, state, forces = np.empty(rows), np.empty((rows, 6)), np.empty((rows, 12))
    n, ending = _simulate_one(launch, settings, t, state, forces)
    if ending == 3:
        _refuse_overflow(np.array([ending]), settings)
    state, forces = state[:n], forces[:n]
    return Trajectory(
        t=t[:n],
        position=state[:, :3],
        velocity=state[:, 3:],
        drag=forces[:, 0:3],
        magnus=forces[:, 3:6],
        gravity=forces[:, 6:9],
        knuckle=forces[:, 9:12],
        ended=_ENDINGS[ending],
    )


_NO_KNUCKLE = [0.0, 0.0, 0.0, 0.0]
"""Knuckle angles θ φ₁ φ₂ and flag of a launch row without the knuckle force."""


def simulate_batch(
    positions: ArrayLike,
    velocities: ArrayLike,
    spins: ArrayLike,
    config: FlightConfig | None = None,
    *,
    knuckle_seeds: Sequence[int | None] | None = None,
    **options: Any,
) -> BatchTrajectory:
    """Integrate K kicks, in parallel over the kicks; each flight is :func:`simulate`'s, bit for bit.

    Memory is K·T·7 floats (T the longest flight's samples): 10 000 kicks of 1.9 s at RK4 10 ms take ~110 MB, at
    Euler 1 ms ten times that; use ``x_stop`` and a coarser ``dt`` for large sweeps, or :func:`simulate_outcomes`
    when only the verdicts matter. Forces are not stored; run :func:`simulate` on a kick of interest for them.

    Args:
        positions: (K, 3) launch positions (m).
        velocities: (K, 3) launch velocities (m/s).
        spins: (K, 3) angular velocities (rad/s).
        knuckle_seeds: None, or K seeds (each None or an int) as :func:`simulate`'s ``knuckle_seed``.
        config, options: as for :func:`simulate`, shared by every kick.

    Returns:
        :class:`BatchTrajectory`.
    """
    settings = _flight_config(config, options).settings
    launches = _kick_rows(positions, velocities, spins, knuckle_seeds)
    _check_launches(launches, settings, batch=True)
    k = len(launches)
    rows = int(settings[_N_STEPS]) + 1
    n_samples, endings = np.ones(k, dtype=np.int64), np.full(k, 2, dtype=np.int64)
    with _PARALLEL:
        # Time-major (T, K) storage with room for the longest flight t_max allows: rows past this batch's longest
        # flight are never touched, so they never become memory. Where even that reservation is too large, count
        # the samples first.
        if rows * k * 56 > _RESERVE_BYTES:
            _fly_batch(
                launches, settings, np.empty((0, k)), np.empty((0, k, 6)), n_samples, endings
            )
            rows = int(n_samples.max())
        t, state = np.empty((rows, k)), np.empty((rows, k, 6))
        _fly_batch(launches, settings, t, state, n_samples, endings)
        width = int(n_samples.max()) if k else 1
        t, state = t[:width], state[:width]
        _pad(t, state, n_samples)
    _refuse_overflow(endings, settings)
    state = state.transpose(1, 0, 2)  # (K, T, 6) view, no copy
    return BatchTrajectory(
        t=t.T,
        position=state[:, :, :3],
        velocity=state[:, :, 3:],
        n_samples=n_samples,
        ended=np.array(_ENDINGS, dtype="<U6")[endings],
    )


def _panels(wall: Panel, goal: Panel) -> NDArray[np.float64]:
    """The wall and the goal as the compiled cores' (2, 6) rows: centre x, y, unit normal x, y, width, height."""
    rows = np.empty((2, 6))
    for row, (name, panel) in zip(rows, (("wall", wall), ("goal", goal)), strict=True):
        normal = _vector(f"{name}.normal_xy", panel.normal_xy, 2)
        length = float(np.hypot(*normal))
        if length == 0.0:
            raise ValueError(f"{name}.normal_xy must not be zero")
        row[0:2], row[2:4] = _vector(f"{name}.centre_xy", panel.centre_xy, 2), normal / length
        row[4] = _checks.positive(f"{name}.width_m", panel.width_m)
        row[5] = _checks.finite_number(f"{name}.height_m", panel.height_m)
    return rows


def outcome(
    trajectory: Trajectory, wall: Panel, goal: Panel, *, radius_m: float = BALL_RADIUS_M
) -> Outcome:
    """Judge one flight against the wall and the goal.

    The ball hits the wall when its centre crosses the wall's plane within a radius of the defenders' outline
    (width × height). Otherwise, where its centre crosses the goal's plane decides: the whole ball inside the posts
    and under the bar is a goal; outside a post is wide; inside the posts but touching or above the bar is over. A
    flight that ends (lands, or reaches ``t_max``) before the goal's plane is short. Posts and bar do not rebound.
    Each crossing is the root of the cubic Hermite interpolant of the step that crosses the plane.

    Args:
        trajectory: from :func:`simulate`.
        wall: the wall, e.g. from :func:`free_kick_panels`.
        goal: the goal mouth.
        radius_m: ball radius (m).

    Returns:
        :class:`Outcome`.
    """
    radius = _checks.positive("radius_m", radius_m)
    if not isinstance(trajectory, Trajectory):
        raise ValueError(
            f"trajectory must be a Trajectory from simulate(), got {type(trajectory).__name__}"
        )
    crossings = np.empty((2, 4))
    t, position, velocity = trajectory.t, trajectory.position, trajectory.velocity
    code = _judge(t, position, velocity, len(t), _panels(wall, goal), radius, crossings)
    wall_ok, goal_ok = not math.isnan(crossings[0, 0]), not math.isnan(crossings[1, 0])
    return Outcome(
        result=_RESULTS[code],
        wall_point=crossings[0, 1:] if wall_ok else None,
        goal_point=crossings[1, 1:] if goal_ok else None,
        wall_time=float(crossings[0, 0]) if wall_ok else None,
        goal_time=float(crossings[1, 0]) if goal_ok else None,
    )


def outcome_batch(
    batch: BatchTrajectory, wall: Panel, goal: Panel, *, radius_m: float = BALL_RADIUS_M
) -> BatchOutcome:
    """:func:`outcome` for every kick of a batch, in parallel.

    Args:
        batch: from :func:`simulate_batch`.
        wall: the wall.
        goal: the goal mouth.
        radius_m: ball radius (m).

    Returns:
        :class:`BatchOutcome`.
    """
    radius = _checks.positive("radius_m", radius_m)
    if not isinstance(batch, BatchTrajectory):
        raise ValueError(
            f"batch must be a BatchTrajectory from simulate_batch(), got {type(batch).__name__}"
        )
    k = len(batch.n_samples)
    results, crossings, panels = (
        np.empty(k, dtype=np.int64),
        np.empty((k, 2, 4)),
        _panels(wall, goal),
    )
    with _PARALLEL:
        _judge_batch(
            batch.t,
            batch.position,
            batch.velocity,
            batch.n_samples,
            panels,
            radius,
            results,
            crossings,
        )
    return _batch_outcome(results, crossings)


def _batch_outcome(results: NDArray[np.int64], crossings: NDArray[np.float64]) -> BatchOutcome:
    return BatchOutcome(
        result=np.array(_RESULTS, dtype="<U5")[results],
        wall_point=crossings[:, 0, 1:],
        goal_point=crossings[:, 1, 1:],
    )


def simulate_outcomes(
    positions: ArrayLike,
    velocities: ArrayLike,
    spins: ArrayLike,
    wall: Panel,
    goal: Panel,
    config: FlightConfig | None = None,
    *,
    knuckle_seeds: Sequence[int | None] | None = None,
    **options: Any,
) -> BatchOutcome:
    """``outcome_batch(simulate_batch(...), wall, goal)`` without keeping the flights: the same verdicts and crossings.

    Each kick flies into a scratch buffer of its own and is judged at once, in parallel over the kicks, so memory
    stays K·(a few floats) however long the flights. This is what a sweep (an outcome map, an aiming search) wants.

    Args:
        positions, velocities, spins, knuckle_seeds: the K kicks, as for :func:`simulate_batch`.
        wall: the wall.
        goal: the goal mouth.
        config, options: as for :func:`simulate`, shared by every kick; its ``radius_m`` also sizes the ball
            for the verdict.

    Returns:
        :class:`BatchOutcome`.
    """
    settings = _flight_config(config, options).settings
    launches = _kick_rows(positions, velocities, spins, knuckle_seeds)
    _check_launches(launches, settings, batch=True)
    k, panels = len(launches), _panels(wall, goal)
    results, crossings, endings = np.empty(k, np.int64), np.empty((k, 2, 4)), np.empty(k, np.int64)
    with _PARALLEL:
        _fly_and_judge(launches, settings, panels, results, crossings, endings)
    _refuse_overflow(endings, settings)
    return _batch_outcome(results, crossings)


def spin_vector(rate_rev_s: float, axis: ArrayLike) -> NDArray[np.float64]:
    """Angular velocity (rad/s) from a spin rate in rev/s about ``axis`` (any length, normalised here).

    Args:
        rate_rev_s: spin rate (rev/s, ≥ 0).
        axis: (3,) spin axis; +z is sidespin curling a ball kicked along +x to the left.

    Returns:
        (3,) ω (rad/s).
    """
    rate = _checks.non_negative("rate_rev_s", rate_rev_s)
    direction = _vector("axis", axis, 3)
    scale = float(np.abs(direction).max())
    if scale == 0.0:
        raise ValueError("axis must not be zero")
    direction = (
        direction / scale
    )  # largest component ±1 first: neither overflows nor underflows when squared
    return 2.0 * math.pi * rate * direction / float(np.linalg.norm(direction))


def launch_velocity(
    speed_ms: float, elevation_rad: float, azimuth_rad: float
) -> NDArray[np.float64]:
    """Velocity (3,) in m/s from speed, elevation above the ground and azimuth to the left of +x."""
    speed = _checks.non_negative("speed_ms", speed_ms)
    elevation = _checks.finite_number("elevation_rad", elevation_rad)
    azimuth = _checks.finite_number("azimuth_rad", azimuth_rad)
    return speed * np.array(
        [
            math.cos(elevation) * math.cos(azimuth),
            math.cos(elevation) * math.sin(azimuth),
            math.sin(elevation),
        ]
    )


def warm_up() -> None:
    """Compile, or load from the cache, every compiled core, on tiny inputs (both models, both methods, a knuckle).

    Call once at start-up, off the thread that serves users: the first kick then runs at full speed. A cold compile
    takes several seconds; a warm cache loads in well under one.
    """
    wall, goal = free_kick_panels((0.0, 0.0), (12.0, 0.0), (1.0, 0.0))
    start, velocity, spin = (0.0, 0.0, BALL_RADIUS_M), (20.0, 0.0, 4.0), (0.0, 0.0, 30.0)
    flight = simulate(
        start, velocity, spin, dt=0.05, method="rk4", model="measured", knuckle_seed=0
    )
    outcome(flight, wall, goal)
    rows = np.array([start, start])
    batch = simulate_batch(rows, [velocity, velocity], [spin, spin], dt=0.05, t_max=0.2)
    outcome_batch(batch, wall, goal)
    simulate_outcomes(rows, [velocity, velocity], [spin, spin], wall, goal, dt=0.05, x_stop=13.0)
