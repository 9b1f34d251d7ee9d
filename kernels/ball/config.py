"""The ball, the air and the integrator: constants, :class:`FlightConfig`, and the checks on every kick's input.

SI units (m, s, kg, rad/s). :class:`FlightConfig` is validated once and carries the compiled cores' (15,) settings
vector, whose slots are :data:`Q` … :data:`RE_CRISIS`; :func:`launch_rows` turns K validated kicks into the cores'
(K, 13) launch rows (position, velocity, spin, knuckle angles and flag). Every check raises ``ValueError`` naming the
argument. The constants' sources are in :mod:`kernels.ball`'s docstring.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from typing import Any, Literal

import numpy as np
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
KNUCKLE_COEFFICIENT = 0.10
"""Side-force coefficient C_K of the knuckleball model (see :mod:`kernels.ball`)."""
KNUCKLE_WAVELENGTH_M = 15.0
"""Flight distance of one zig-zag (Cohen et al. 2012)."""
KNUCKLE_SPIN_LIMIT = 0.05
"""Launch spin parameter S₀ at and above which the knuckle force is off."""
DRAG_CRISIS_RE = 1.815e5
"""Centre of the measured model's drag crisis (Reynolds number): Goff & Carré 2010's no-spin fit to the Teamgeist
(0.155 + 0.346/(1 + exp((v − 12.19 m/s)/1.309 m/s)), in Re for a 0.22 m ball in air of 1.225 kg/m³)."""
DRAG_CRISIS_RE_BY_BALL = {"Teamgeist": 1.815e5}
"""Documented centres of the drag crisis per ball, for :attr:`FlightConfig.drag_crisis_re`. Only the Teamgeist's
(Goff & Carré 2010) is a fitted centre; wind-tunnel studies place other balls' crises elsewhere (32-panel balls
nearer 2.2–3.0·10⁵ in a compilation we have not checked against the papers; the Brazuca's critical speed below the
Jabulani's, Goff, Asai & Hong 2014), so set the centre from the ball's own measurement."""

Method = Literal["euler", "rk4"]
Model = Literal["constant", "measured"]

MAX_STEPS = 1_000_000
"""The most steps a flight takes: ``dt`` is at least ``t_max / MAX_STEPS``."""


def _step_count(duration: float, step: float) -> int:
    """Steps of ``step`` in a flight of ``duration`` (s): the last one shortened to end on it. A quotient over a
    whole number by rounding (0.514/5.14e-7 is 1000000.0000000001) is that whole number. More than
    :data:`MAX_STEPS` reads as ``MAX_STEPS + 1``: a quotient that overflows to inf has no whole number."""
    quotient = duration / step - 1e-9
    return max(1, math.ceil(quotient)) if quotient <= MAX_STEPS else MAX_STEPS + 1


# The compiled cores read their settings from one float64 vector; these are its slots.
MAX_BALL_RADIUS_M = 1.0
"""The largest ball a flight takes (m; a football's radius is 0.11 m): a 1e9 m ball was refused as a shallow net."""
Q, GRAVITY, RADIUS, RE_PER_SPEED, C_D, C_L, MASS, DT, GROUND, X_STOP = range(10)
N_STEPS, RK4, MEASURED, T_MAX, RE_CRISIS = 10, 11, 12, 13, 14

SPIN_PARAMETER_LIMIT = 1e3
"""Largest spin parameter S = r·|ω|/max(|v|, :data:`SLOW_SPEED_MS`) the measured model accepts (a kick's launch,
:func:`kernels.ball.coefficients`' input); its fits stop at S ≈ 0.3 (held constant beyond) and no kick comes near
10 (S = 1e3 is ~2·10⁵ rev/s at 25 m/s)."""
SLOW_SPEED_MS = 1.0
"""Speed (m/s) below which the measured model's coefficients are held at their value at this speed: its spin
parameter is S = r·|ω|/max(|v|, 1 m/s), so a ball at rest has a finite S (a launch from rest is checked, and its
C_D stays that of a slow ball, not the fit's extrapolation to S → ∞). The force, ∝ C·|v|², still goes to zero."""
MAX_DT_S = 0.1
"""The longest step a flight takes (s), for accuracy: over 3,768 kicks across the free-kick scene's controls (5–40
m/s, −5–50°, 0–15 rev/s about any axis, both models, some knuckling), RK4's landing point strays at most 5 mm from
a 0.1 ms RK4 reference at 0.1 s, but 13 mm at 0.11 s and 16 mm at 0.15 s (its p99 is 1.3 mm at 0.1 s). Euler, of
first order, is further off at any step (10–16 mm at 1 ms); the scene steps RK4 by 10 ms and Euler by 1 ms. RK4 in
a vacuum is exempt: it is exact for the parabola at any step (the crossing tests use steps longer than a flight)."""


# --------------------------------------------------------------------------------------------- validation
def checked_vector(name: str, value: ArrayLike, size: int) -> NDArray[np.float64]:
    """:func:`kernels._checks.vector`, saying in the ball's words when a boolean is inside
    (:func:`kernels._checks.holds_booleans`)."""
    if _checks.holds_booleans(value):
        raise ValueError(f"{name} must be numbers, not booleans, got {_checks.shown(value)}")
    return _checks.vector(name, value, size)


def checked_rows(name: str, value: ArrayLike) -> NDArray[np.float64]:
    """:func:`kernels._checks.points` with the same boolean guard as :func:`checked_vector`."""
    if _checks.holds_booleans(value):
        raise ValueError(f"{name} must be numbers, not booleans")
    return _checks.points(name, value, 3)


def fast_floats(value: object) -> list[float] | None:
    """The three finite floats of a tuple, list or float64 (3,) array, or None for anything else (then checked in
    full by :func:`checked_vector`): the common case of a single kick, at a fraction of a microsecond."""
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


def checked_seed(name: str, value: object) -> int | None:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0:
        raise ValueError(f"{name} must be None or an integer >= 0, got {_checks.shown(value)}")
    return int(value)


MAX_GRAVITY = 1000.0
"""Largest |gravity| a flight takes (m/s²): past the Sun's surface, and far from where a step limit in air or the
flight's energy bound would overflow (1e300 was refused naming dt)."""


@dataclasses.dataclass(frozen=True)
class FlightConfig:
    """Settings shared by every kick of a flight or a batch: the ball, the air, the integrator and the end.

    Validated once, here (``ValueError`` naming the field); :func:`simulate`, :func:`simulate_batch` and
    :func:`simulate_outcomes` then reuse it without checking again, so build one and pass it to many calls.
    """

    dt: float = 1e-3
    """Fixed step (s, > 0), at least ``t_max``/10⁶ and, for accuracy, at most :data:`MAX_DT_S` (0.1 s) but for RK4
    in a vacuum (``air_density`` 0), which follows the parabola exactly at any step."""
    method: Method = "euler"
    """``"euler"`` (semi-implicit: v += a·dt, then x += v·dt) or ``"rk4"``."""
    model: Model = "constant"
    """``"constant"`` coefficients or ``"measured"`` spin- and Reynolds-dependent fits (:mod:`kernels.ball`)."""
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
    drag_crisis_re: float = DRAG_CRISIS_RE
    """Centre of the measured model's drag crisis (Reynolds number, > 0): 1.815·10⁵ for the Teamgeist that Goff &
    Carré 2010 measured (the default); see :data:`DRAG_CRISIS_RE_BY_BALL`."""
    settings: NDArray[np.float64] = dataclasses.field(init=False, repr=False, compare=False)
    """(15,) the compiled cores' settings vector (slots ``Q`` … ``RE_CRISIS``), read-only; derived, not an argument."""

    def __post_init__(self) -> None:
        step = _checks.positive("dt", self.dt)
        duration = _checks.positive("t_max", self.t_max)
        density = _checks.non_negative("air_density", self.air_density)
        exact = density == 0.0 and self.method == "rk4"  # a vacuum's parabola, exact at any step
        if duration > MAX_STEPS * MAX_DT_S and not exact:
            raise ValueError(
                f"t_max must be at most {MAX_STEPS * MAX_DT_S:g} s ({MAX_STEPS} steps of at most {MAX_DT_S:g} s), "
                f"got {_checks.shown(self.t_max)}"
            )
        if _step_count(duration, step) > MAX_STEPS:
            raise ValueError(
                f"dt must be at least t_max/{MAX_STEPS} = {duration / MAX_STEPS:g} s, got {_checks.shown(step)}"
            )
        _checks.choice("method", self.method, ("euler", "rk4"))
        _checks.choice("model", self.model, ("constant", "measured"))
        c_d = _checks.non_negative("drag_coefficient", self.drag_coefficient)
        c_l = _checks.non_negative("lift_coefficient", self.lift_coefficient)
        mass = _checks.positive("mass_kg", self.mass_kg)
        radius = _checks.positive("radius_m", self.radius_m)
        if radius > MAX_BALL_RADIUS_M:
            raise ValueError(
                f"radius_m must be at most {MAX_BALL_RADIUS_M:g} m (a ball), got {_checks.shown(self.radius_m)}"
            )
        if step > MAX_DT_S and not exact:
            raise ValueError(
                f"dt must be at most {MAX_DT_S:g} s for accuracy (beyond it RK4's landing point strays more than 1 cm "
                f"on a free kick; only RK4 in a vacuum, exact at any step, takes more), got {_checks.shown(self.dt)}"
            )
        g = _checks.finite_number("gravity", self.gravity)
        if abs(g) > MAX_GRAVITY:
            raise ValueError(f"gravity must be within ±{MAX_GRAVITY:g} m/s² (the Sun's is 274), got {_checks.shown(g)}")
        stop = math.inf if self.x_stop is None else _checks.finite_number("x_stop", self.x_stop)
        ground = _checks.finite_number("ground_m", self.ground_m)
        crisis = _checks.positive("drag_crisis_re", self.drag_crisis_re)
        # In slot order: Q (½ρA/m, 1/m), GRAVITY, RADIUS, RE_PER_SPEED, C_D, C_L, MASS, DT, GROUND,
        # X_STOP, N_STEPS, RK4, MEASURED, T_MAX, RE_CRISIS.
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
                _step_count(duration, step),
                self.method == "rk4",
                self.model == "measured",
                duration,
                crisis,
            ]
        )
        settings.setflags(write=False)
        object.__setattr__(self, "settings", settings)


_DEFAULT_CONFIG = FlightConfig()

_CONFIGS: dict[object, FlightConfig] = {}
"""Configs already built from keyword options, keyed by (name, type, value) of each: a caller that passes the same
options on every call validates them once."""
_CONFIGS_MAX = 256


def flight_config(config: FlightConfig | None, options: dict[str, Any]) -> FlightConfig:
    """``config``, or one built from ``options`` (:class:`FlightConfig` fields; both together is refused)."""
    if not options:
        if config is None:
            return _DEFAULT_CONFIG
        if type(config) is not FlightConfig:
            raise ValueError(f"config must be a FlightConfig, got {type(config).__name__}")
        return config
    if config is not None:
        raise ValueError(f"pass either config or its fields as keywords, not both: {sorted(options)}")
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


def launch_rows(
    positions: NDArray[np.float64],
    velocities: NDArray[np.float64],
    spins: NDArray[np.float64],
    seeds: Sequence[int | None],
) -> NDArray[np.float64]:
    """(K, 13) launch rows of the compiled cores: position, velocity, spin, knuckle angles θ φ₁ φ₂, knuckle flag.

    ``numpy.random.default_rng(seed)`` draws the angles here in Python, so a seed gives the same flight as it always
    has; the compiled :func:`fill_kick` derives the rest of each kick's constants.
    """
    launches = np.concatenate((positions, velocities, spins, np.zeros((len(positions), 4))), axis=1)
    for k, seed in enumerate(seeds):
        if seed is not None:
            launches[k, 9:12] = np.random.default_rng(seed).uniform(0.0, 2.0 * np.pi, size=3)
            launches[k, 12] = 1.0
    return launches


def kick_rows(
    positions: ArrayLike, velocities: ArrayLike, spins: ArrayLike, knuckle_seeds: Sequence[int | None] | None
) -> NDArray[np.float64]:
    """Validated kicks of a batch as (K, 13) launch rows (see :func:`launch_rows`)."""
    p0, v0, w0 = (
        checked_rows("positions", positions),
        checked_rows("velocities", velocities),
        checked_rows("spins", spins),
    )
    k = len(p0)
    if len(v0) != k or len(w0) != k:
        raise ValueError(f"positions, velocities and spins must have the same length, got {k}, {len(v0)}, {len(w0)}")
    if knuckle_seeds is None:
        seeds: list[int | None] = [None] * k
    else:
        if isinstance(knuckle_seeds, (str, bytes)) or not isinstance(knuckle_seeds, (Sequence, np.ndarray)):
            raise ValueError(f"knuckle_seeds must be None or a sequence of K seeds, got {_checks.shown(knuckle_seeds)}")
        seeds = [checked_seed("knuckle_seeds", seed) for seed in knuckle_seeds]
        if len(seeds) != k:
            raise ValueError(f"knuckle_seeds must have {k} entries, got {len(seeds)}")
    return launch_rows(p0, v0, w0, seeds)


def _safe_norms(rows: NDArray[np.float64]) -> NDArray[np.float64]:
    """|row| of each row of a (K, 3) array without overflow or underflow in the squares."""
    scale = np.abs(rows).max(axis=1, initial=0.0)
    safe = np.where(scale > 0.0, scale, 1.0)
    return scale * np.sqrt(((rows / safe[:, None]) ** 2).sum(axis=1))


def check_launches(
    launches: NDArray[np.float64], config: NDArray[np.float64], batch: bool, strikes: bool = False
) -> None:
    """Refuse a launch below the ground and, in the measured model, a spin far beyond its fits; named as the kick's
    ``position`` and ``spin``, a batch's ``positions[k]`` and ``spins[k]``, or (``strikes``: strikes scattered
    about one intended kick) that kick's ``position`` and ``spin_rads``."""
    if not batch and not config[MEASURED] and launches[0, 2] >= config[GROUND]:
        return  # one kick in the constant model, above the ground: the common case, without array work
    low = np.flatnonzero(launches[:, 2] < config[GROUND])
    if low.size:
        which = f"positions[{low[0]}]" if batch and not strikes else "position"
        raise ValueError(
            f"{which} starts below the ground: z = {_checks.shown(float(launches[low[0], 2]))} m < ground_m = "
            f"{_checks.shown(float(config[GROUND]))} m"
        )
    if config[MEASURED]:
        refuse_fast_spin(
            float(config[RADIUS]),
            _safe_norms(launches[:, 3:6]),
            _safe_norms(launches[:, 6:9]),
            lambda k: "spin_rads" if strikes else f"spins[{k}]" if batch else "spin",
        )


def refuse_fast_spin(
    radius: float, speeds: NDArray[np.float64], rates: NDArray[np.float64], name: Callable[[int], str]
) -> None:
    """``ValueError`` naming ``name(k)`` for the first k whose spin parameter r·|ω|/max(|v|, :data:`SLOW_SPEED_MS`)
    exceeds :data:`SPIN_PARAMETER_LIMIT`: the measured model's one range check, for a kick's launch (``speeds`` and
    ``rates`` its (K,) |v| in m/s and |ω| in rad/s) and for :func:`kernels.ball.coefficients` alike."""
    spin_parameter = radius * rates / np.maximum(speeds, SLOW_SPEED_MS)
    bad = np.flatnonzero(spin_parameter > SPIN_PARAMETER_LIMIT)
    if bad.size:
        k = int(bad[0])
        raise ValueError(
            f"{name(k)} is too fast for the measured model: spin parameter S = r·|ω|/max(|v|, {SLOW_SPEED_MS:g} m/s)"
            f" = {spin_parameter[k]:.3g} > {SPIN_PARAMETER_LIMIT:g} (its fits stop at S ≈ 0.3)"
        )
