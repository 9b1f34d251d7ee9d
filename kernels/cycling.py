"""Bicycle power: aerodynamic, rolling and climbing terms, its inverse, and drafting in a paceline.

All quantities are SI: speed and wind in m/s, CdA in m², mass in kg, power in W, altitude in m. Grade is rise over
run (0.05 is 5 %), so the road angle is θ = atan(grade). Every function accepts numpy arrays and broadcasts them.

Model (the textbook one, with wind made sign-correct):

    P_aero  = ½·ρ·CdA·(v + w)·|v + w|·v        w = headwind (negative for a tailwind)
    P_roll  = Crr·m·g·cos θ·v
    P_climb = m·g·sin θ·v
    P_total = (P_aero + P_roll + P_climb) / η   η = drivetrain efficiency (when the sum is positive)
    ρ(h)    = 1.225·exp(−h / 8500)

The absolute value matters: a tailwind faster than the rider pushes instead of dragging. Assumptions: steady speed
(no kinetic-energy change), no wheel-bearing or wheel-rotation losses (Martin et al. 1998 add them; they are a few
watts), yaw-free CdA.

Drafting, two models:

* ``"textbook"``: every follower gets ``CdA·(1 − 0.27·exp(−gap/3.5))``, a simple exponential fade: 27.0 %, 6.5 % and
  1.6 % less drag at 0, 5 and 10 m, whatever the place in the line.
* ``"measured"``: position-dependent drag reductions fitted to published measurements::

      reduction(position k ≥ 2, gap g) = R_k · exp(−g / 9.7 m)
      R_2 = 0.40, R_3 = 0.48, R_k≥4 = 0.50           (close-gap plateau of a tight line)
      reduction(leader, gap g) = 0.03 · exp(−g / 1.5 m)   (only when someone follows)

  The close-gap plateaus follow the 4-rider team-pursuit line of Barry et al. 2015 and Fitton et al. 2018 (2nd
  42–45 %, 3rd 48–55 %, 4th 47–57 %) and Broker, Kyle & Burke 1999 (riders 3–4 need less than rider 2). The fade
  length 9.7 m is fitted to Swiss Side's CFD (36 % at 0.1 m, 13 % at 10 m behind one rider). The leader's gain
  follows Blocken et al. 2013 (0.8–2.6 %) and Swiss Side (~4 % at 0.1 m, gone by 5 m). Riders further back save
  more than the second, the leader saves a little, and every saving fades with the gap.

Formations (:func:`formation`, :func:`formation_drag`, :func:`formation_power`): riders laid out in two dimensions
(single file, a two-abreast paceline, a bunch, an echelon) and a wake model of each rider's drag from the offsets of
the riders around it, which is the line model above in single file and is fitted to Blocken et al. 2018's 121-rider
peloton (J. Wind Eng. Ind. Aerodyn. 179:319). Plain numpy over the (N, N) offsets: about 0.7 ms for 121 riders.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import Any, Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from kernels import _checks
from kernels._jit import compiled

G = 9.81
"""Gravitational acceleration (m/s²)."""
RHO_SEA_LEVEL = 1.225
"""Air density at sea level (kg/m³)."""
SCALE_HEIGHT_M = 8500.0
"""Scale height of the textbook exponential atmosphere (m)."""

DraftModel = Literal["textbook", "measured"]
DRAFT_MODELS: tuple[DraftModel, ...] = ("textbook", "measured")

# "measured" drafting model constants (see the module docstring for the sources).
_MEASURED_PLATEAU = (0.40, 0.48, 0.50)  # positions 2, 3, 4+ at zero gap
_MEASURED_FADE_M = 9.7
_LEADER_PLATEAU = 0.03
_LEADER_FADE_M = 1.5


@dataclasses.dataclass(frozen=True)
class Power:
    """Power split in watts; each field has the broadcast shape of the inputs."""

    aero: NDArray[np.float64]
    """Power against air drag at the wheel (W)."""
    rolling: NDArray[np.float64]
    """Power against rolling resistance at the wheel (W)."""
    climbing: NDArray[np.float64]
    """Power against gravity along the road (W); negative downhill."""
    total: NDArray[np.float64]
    """Power at the pedals: (aero + rolling + climbing) / drivetrain efficiency (W); the plain sum when negative."""


# Every function here broadcasts, so its arguments are arrays of any shape: the array checks of kernels._checks.
_finite = _checks.finite_array
_positive = _checks.positive_array
_non_negative = _checks.non_negative_array


def _shape(name: str, value: ArrayLike) -> tuple[int, ...]:
    if type(value) is float or type(value) is int:  # the common case, without numpy's conversion
        return ()
    try:
        return np.shape(value)
    except ValueError as error:  # a ragged list: numpy's "inhomogeneous shape" names nothing
        raise ValueError(f"{name} must be an array of real numbers, got {_checks.shown(value)}") from error


def _broadcast(**values: ArrayLike) -> None:
    """``ValueError`` naming the first of ``values`` whose shape does not broadcast with the ones before it (numpy
    would say "operands could not be broadcast together" and name none)."""
    shapes = [(name, _shape(name, value)) for name, value in values.items()]
    if not any(here for _, here in shapes):  # all scalars, the common case: nothing to broadcast
        return
    shape: tuple[int, ...] = ()
    for name, here in shapes:
        try:
            shape = np.broadcast_shapes(shape, here)
        except ValueError as error:
            raise ValueError(
                f"{name} must broadcast with the shape {shape} of the arguments before it, got {here}"
            ) from error


def _efficiency(value: ArrayLike) -> NDArray[np.float64]:
    array = _finite("drivetrain_efficiency", value)
    if np.any((array < 1e-3) | (array > 1.0)):  # a thousandth: far below any drivetrain, and no overflow
        raise ValueError(f"drivetrain_efficiency must be in [0.001, 1], got {_checks.shown(value)}")
    return array


AIR_DENSITY_ALTITUDE_M = (-10_000.0, 30_000.0)
"""Altitudes :func:`air_density` takes (m): from 10 km below sea level (the deepest a course may reach,
:data:`kernels.course.MIN_ELEVATION_M`; 3.97 kg/m³ there) to 30 km, where :data:`MODEL_DOMAIN` stops (the
exponential atmosphere is no air above). Beyond them it gave 157 573 kg/m³ at −100 km and inf at −10³⁰⁰ m."""


def air_density(altitude_m: ArrayLike) -> NDArray[np.float64]:
    """Air density of the textbook exponential atmosphere, 1.225·exp(−h/8500).

    Args:
        altitude_m: altitude above sea level (m, −10 000 to 30 000: :data:`AIR_DENSITY_ALTITUDE_M`), any shape.

    Returns:
        Density (kg/m³), same shape.

    Raises:
        ValueError: an altitude is not a finite number or outside its range; the message names ``altitude_m``.
    """
    h = _finite("altitude_m", altitude_m)
    low, high = AIR_DENSITY_ALTITUDE_M
    if np.any((h < low) | (h > high)):
        raise ValueError(f"altitude_m must be in [{low:g}, {high:g}] m, got {_checks.shown(altitude_m)}")
    return RHO_SEA_LEVEL * np.exp(-h / SCALE_HEIGHT_M)


def draft_factor(gap_m: ArrayLike) -> NDArray[np.float64]:
    """The textbook CdA multiplier for a rider following at ``gap_m``: 1 − 0.27·exp(−gap/3.5)."""
    gap = _non_negative("gap_m", gap_m)
    return 1.0 - 0.27 * np.exp(-gap / 3.5)


def drag_reduction(n_riders: int, gap_m: float, model: DraftModel = "measured") -> NDArray[np.float64]:
    """Fractional CdA reduction of each rider in a single-file line, leader first.

    Args:
        n_riders: riders in the line (1 to :data:`MAX_FORMATION_RIDERS`, 200).
        gap_m: wheel-to-wheel gap between consecutive riders (m, ≥ 0).
        model: ``"textbook"`` or ``"measured"`` (see the module docstring).

    Returns:
        (n_riders,) reductions in [0, 1); effective CdA is ``cda·(1 − reduction)``.
    """
    _checks.integer("n_riders", n_riders, 1)
    if n_riders > MAX_FORMATION_RIDERS:  # 10¹² riders asked numpy for 7 TiB
        raise ValueError(f"n_riders must be at most {MAX_FORMATION_RIDERS}, got {_checks.shown(n_riders)}")
    gap = _checks.non_negative("gap_m", gap_m)  # one gap: an array raised numpy's TypeError
    _checks.choice("model", model, DRAFT_MODELS)  # checked for one rider too
    reduction = np.zeros(int(n_riders))
    if n_riders == 1:
        return reduction
    match model:
        case "textbook":
            reduction[1:] = 1.0 - float(draft_factor(gap))
        case "measured":
            plateau = np.array([_MEASURED_PLATEAU[min(k, len(_MEASURED_PLATEAU)) - 1] for k in range(1, n_riders)])
            reduction[1:] = plateau * np.exp(-gap / _MEASURED_FADE_M)
            reduction[0] = _LEADER_PLATEAU * np.exp(-gap / _LEADER_FADE_M)
    return reduction


# --------------------------------------------------------------------------------------------- the power law
def wheel_power_terms(v, drag, rolling_force, climbing_force, wind, b0, b1):
    """The cyclist power law, its one implementation: the power the rear wheel delivers, term by term (W).

    Returns ``(aero, rolling, bearings, climbing)`` at ground speed ``v`` (m/s, ≥ 0)::

        aero     = drag·(v + wind)·|v + wind|·v      drag = ½ρ·CdA (kg/m), wind = headwind (m/s)
        rolling  = rolling_force·v                   rolling_force = Crr·m·g·cos θ (N)
        bearings = b0·v + b1·v²                      wheel bearings (W); 0, 0 in the textbook model
        climbing = climbing_force·v                  climbing_force = m·g·sin θ (N)

    Martin et al. (1998), J. Appl. Biomech. 14:276–291, eq. 9 without its kinetic term (the ride loop of
    :mod:`kernels.course` integrates that one); their sum over the drivetrain efficiency is the pedal power.
    Inputs are trusted (checked by the callers) and broadcast; see :func:`road_forces` for the forces.

    Written with arithmetic and ``abs`` only, so one source runs on numpy arrays (in :func:`power` and
    :func:`martin_power`) and, compiled as :data:`wheel_power_terms_compiled`, on floats inside
    :mod:`kernels.course`'s compiled ride loop.
    """
    air = v + wind
    return drag * air * abs(air) * v, rolling_force * v, b0 * v + b1 * v * v, climbing_force * v


wheel_power_terms_compiled = compiled(inline="always")(wheel_power_terms)
"""The very same :func:`wheel_power_terms`, compiled by numba for scalar calls from compiled loops."""


def road_forces(
    mass_kg: ArrayLike, crr: ArrayLike, grade: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Rolling and climbing forces along the road (N): Crr·m·g·cos θ and m·g·sin θ, with θ = atan(grade).

    Args:
        mass_kg: rider plus bike (kg, > 0, at most 10⁶: :data:`MODEL_DOMAIN`).
        crr: rolling-resistance coefficient (0 to 1).
        grade: rise over run, any finite value.

    Returns:
        The two forces, with the broadcast shape of the inputs.

    Raises:
        ValueError: an argument is not finite, out of its range or of a shape that does not broadcast; the message
            names it.
    """
    mass = _positive("mass_kg", mass_kg)
    friction = _non_negative("crr", crr)
    slope = _finite("grade", grade)
    _check_domain("road_forces", MODEL_DOMAIN, mass_kg=mass, crr=friction)
    _broadcast(mass_kg=mass, crr=friction, grade=slope)
    return _road_forces(mass, friction, slope)


def _road_forces(
    mass: NDArray[np.float64], crr: NDArray[np.float64], grade: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """:func:`road_forces` of inputs its callers checked."""
    theta = np.arctan(grade)
    return crr * mass * G * np.cos(theta), mass * G * np.sin(theta)


@dataclasses.dataclass(frozen=True)
class _Resistance:
    """The validated rider and course, reduced to the coefficients both directions of the model need."""

    drag: NDArray[np.float64]
    """½ρ·CdA (kg/m): aero force is drag·(v+w)|v+w|."""
    rolling_force: NDArray[np.float64]
    """Crr·m·g·cos θ (N)."""
    climbing_force: NDArray[np.float64]
    """m·g·sin θ (N)."""
    wind: NDArray[np.float64]
    efficiency: NDArray[np.float64]


def _resistance(
    lead: tuple[str, ArrayLike],
    cda_m2: ArrayLike,
    mass_kg: ArrayLike,
    crr: ArrayLike,
    grade: ArrayLike,
    altitude_m: ArrayLike,
    headwind_ms: ArrayLike,
    drivetrain_efficiency: ArrayLike,
) -> _Resistance:
    """The coefficients of :func:`power` and :func:`speed_for_power`, their inputs' shapes first checked to broadcast
    with ``lead``'s (the speed or the power, by name)."""
    _broadcast(
        **{lead[0]: lead[1]},
        cda_m2=cda_m2,
        mass_kg=mass_kg,
        crr=crr,
        grade=grade,
        altitude_m=altitude_m,
        headwind_ms=headwind_ms,
        drivetrain_efficiency=drivetrain_efficiency,
    )
    rolling_force, climbing_force = _road_forces(
        _positive("mass_kg", mass_kg), _non_negative("crr", crr), _finite("grade", grade)
    )
    return _Resistance(
        drag=0.5 * air_density(altitude_m) * _positive("cda_m2", cda_m2),
        rolling_force=rolling_force,
        climbing_force=climbing_force,
        wind=_finite("headwind_ms", headwind_ms),
        efficiency=_efficiency(drivetrain_efficiency),
    )


def power(
    speed_ms: ArrayLike,
    cda_m2: ArrayLike,
    mass_kg: ArrayLike,
    crr: ArrayLike,
    grade: ArrayLike = 0.0,
    altitude_m: ArrayLike = 0.0,
    headwind_ms: ArrayLike = 0.0,
    drivetrain_efficiency: ArrayLike = 1.0,
) -> Power:
    """Power needed to hold ``speed_ms``, split into aero, rolling and climbing.

    Args:
        speed_ms: ground speed (m/s, ≥ 0).
        cda_m2: drag area CdA (m², > 0).
        mass_kg: rider plus bike (kg, > 0).
        crr: rolling-resistance coefficient (≥ 0).
        grade: rise over run (0.05 = 5 %).
        altitude_m: altitude (m), sets air density.
        headwind_ms: wind against the rider (m/s); negative for a tailwind.
        drivetrain_efficiency: fraction of pedal power reaching the wheel, in [0.001, 1].

    Returns:
        :class:`Power` with the broadcast shape of the inputs.
    """
    _check_model_domain(cda_m2, mass_kg, crr, altitude_m, headwind_ms, speed_ms, "power")
    return _power(speed_ms, cda_m2, mass_kg, crr, grade, altitude_m, headwind_ms, drivetrain_efficiency)


def _power(
    speed_ms: ArrayLike,
    cda_m2: ArrayLike,
    mass_kg: ArrayLike,
    crr: ArrayLike,
    grade: ArrayLike,
    altitude_m: ArrayLike,
    headwind_ms: ArrayLike,
    drivetrain_efficiency: ArrayLike,
) -> Power:
    """:func:`power` once its callers have checked the ranges (a group's CdA times its drag share may lie below
    the range a rider's CdA is checked against)."""
    v = _non_negative("speed_ms", speed_ms)
    r = _resistance(("speed_ms", v), cda_m2, mass_kg, crr, grade, altitude_m, headwind_ms, drivetrain_efficiency)

    aero, rolling, _, climbing = wheel_power_terms(v, r.drag, r.rolling_force, r.climbing_force, r.wind, 0.0, 0.0)
    aero, rolling, climbing, efficiency = np.broadcast_arrays(aero, rolling, climbing, r.efficiency)
    wheel = aero + rolling + climbing
    # The drivetrain loses a share of what the rider puts in; when the wheel needs no power (a descent),
    # nothing passes through it, so a negative surplus is not scaled.
    total = np.where(wheel > 0.0, wheel / efficiency, wheel)
    return Power(aero=aero.copy(), rolling=rolling.copy(), climbing=climbing.copy(), total=total)


def speed_for_power(
    power_w: ArrayLike,
    cda_m2: ArrayLike,
    mass_kg: ArrayLike,
    crr: ArrayLike,
    grade: ArrayLike = 0.0,
    altitude_m: ArrayLike = 0.0,
    headwind_ms: ArrayLike = 0.0,
    drivetrain_efficiency: ArrayLike = 1.0,
) -> NDArray[np.float64]:
    """Steady ground speed that ``power_w`` at the pedals sustains: the inverse of :func:`power`.

    Write the wheel power as P(v) = v·g(v) with g(v) = a·(v + w)|v + w| + c, a = ½ρ·CdA and
    c = m·g·cos θ·(Crr + grade) (rolling plus climbing, tan θ = grade). g rises with v, so it has one zero, the
    coasting speed v_c = −w + sign(−c)·√(|c|/a), where the wind and the road's pull hold the rider without
    pedalling. For P = 0 the roots are 0 and v_c, and the rider settles at the larger, max(0, v_c) (beyond it more
    speed costs more power): computed in closed form, so where rolling cancels the grade (c = 0 exactly when
    Crr = −grade) the rider is carried at the wind's speed, a double root of the cubic on that branch that rounding
    would otherwise drop. For P > 0, v·g(v) rises strictly from 0 at v₀ = max(0, v_c) and is ≤ 0 below it, so
    there is one root, inside [v₀, v₀ + 2·√(|c|/a) + ∛(P/a)]. The closed-form cubic of its branch (Cardano, or the
    trigonometric form for three real roots) gives the first guess; a safeguarded Newton iteration (the
    bracket's secant or midpoint whenever a step would leave the shrinking bracket, after ``rtsafe`` in Press et al.,
    Numerical Recipes, 2007) then polishes it to rounding level, so ``power(v) == P`` and v moves continuously
    as P → 0⁺.

    Domain: the inverse is defined on :data:`SPEED_FOR_POWER_DOMAIN` (power up to 1 MW, CdA 1 mm² to 10⁴ m²,
    mass up to 10⁶ kg, Crr up to 1, altitude −10 000 to 30 000 m as :func:`air_density`'s, |wind| up to 1 000 m/s;
    any finite grade). Far beyond any rider, and where the model still means something (the exponential atmosphere
    is no air above ~30 km; drag ∝ v² fails past the speed of sound), it also keeps every intermediate (P/a, |c|/a,
    a·w²·v, the cubic's coefficients) inside float64, so no answer is inf or silently wrong. Outside it: ValueError
    naming the argument.

    Args:
        power_w: power at the pedals (W, ≥ 0).
        Other arguments as for :func:`power`.

    Returns:
        Speed (m/s, ≥ 0) with the broadcast shape of the inputs.

    Raises:
        ValueError: an argument is not finite, out of :func:`power`'s range, or outside the domain above.
    """
    target = _non_negative("power_w", power_w)
    _check_domain(
        "speed_for_power",
        SPEED_FOR_POWER_DOMAIN,
        power_w=power_w,
        cda_m2=cda_m2,
        mass_kg=mass_kg,
        crr=crr,
        altitude_m=altitude_m,
        headwind_ms=headwind_ms,
    )
    r = _resistance(("power_w", target), cda_m2, mass_kg, crr, grade, altitude_m, headwind_ms, drivetrain_efficiency)
    # Validated above. Rolling plus climbing as m·g·cos θ·(Crr + grade), which is exactly 0 where Crr = −grade
    # (the sum of the two forces would leave rounding there, and its square root would move v_c); the ratio
    # (Crr + grade)/√(1 + grade²) is formed first, so a huge grade gives ±m·g instead of overflowing.
    slope = np.asarray(grade, dtype=np.float64)
    road = (np.asarray(crr, dtype=np.float64) + slope) / np.hypot(1.0, slope)
    broadcast = np.broadcast_arrays(
        r.drag, np.asarray(mass_kg, dtype=np.float64) * G * road, r.wind, target * r.efficiency
    )
    shape = broadcast[0].shape
    return _largest_root(_PowerBalance(*(np.array(x, dtype=np.float64).ravel() for x in broadcast))).reshape(shape)


MODEL_DOMAIN: dict[str, tuple[float, float]] = {
    "speed_ms": (0.0, 1e8),
    "cda_m2": (1e-6, 1e4),
    "mass_kg": (0.0, 1e6),
    "crr": (0.0, 1.0),
    "altitude_m": AIR_DENSITY_ALTITUDE_M,
    "headwind_ms": (-1000.0, 1000.0),
}
"""Closed ranges (SI units) on which :func:`power` (and :func:`paceline`, :func:`formation_power`,
:func:`martin_power`) is defined: far beyond any rider (the speed reaches every speed :func:`speed_for_power`
returns), and where the model still means something (no air above ~30 km). Outside them a huge but finite input
gave inf or NaN watts; now ``ValueError`` naming it."""

MARTIN_DOMAIN: dict[str, tuple[float, float]] = {
    **{name: bounds for name, bounds in MODEL_DOMAIN.items() if name != "altitude_m"},
    "air_density": (0.0, 100.0),
    "spoke_drag_m2": (0.0, 1e4),
    "wheel_inertia_kgm2": (0.0, 1e6),
    "wheel_radius_m": (1e-3, 100.0),
    "acceleration_ms2": (-1e4, 1e4),
}
"""As :data:`MODEL_DOMAIN`, for :func:`martin_power`'s own inputs (the air given as a density, up to 100 kg/m³)."""

SPEED_FOR_POWER_DOMAIN: dict[str, tuple[float, float]] = {
    "power_w": (0.0, 1e6),
    **{name: bounds for name, bounds in MODEL_DOMAIN.items() if name != "speed_ms"},
}
"""Closed ranges (SI units) on which :func:`speed_for_power` is defined; ``power``'s own checks (CdA, mass > 0,
…) still apply. Within them no intermediate of the solver overflows or underflows to a wrong answer."""


_POSITIVE = frozenset({"mass_kg", "air_density", "wheel_radius_m", "cda_m2"})
"""Arguments that must be > 0: a domain's range (closed) may start at 0 for them, and 0 itself is refused."""


def _check_domain(function: str, domain: dict[str, tuple[float, float]], **values: ArrayLike) -> None:
    """``ValueError`` naming the first of ``values`` that is not finite, not > 0 where it must be, or outside its
    ``domain`` range."""
    for name, value in values.items():
        low, high = domain[name]
        array = _finite(name, value)
        if name in _POSITIVE and np.any(array <= 0.0):  # else -80 kg was told a range [0, …] that holds 0
            raise ValueError(f"{name} must be > 0, got {_checks.shown(value)}")
        if np.any((array < low) | (array > high)):
            raise ValueError(f"{name} must be in [{low:g}, {high:g}] for {function}, got {_checks.shown(value)}")


class _PowerBalance(NamedTuple):
    """The wheel-power balance a·v·(v + w)|v + w| + c·v = p that :func:`speed_for_power` solves for v, per point."""

    a: NDArray[np.float64]
    """½ρ·CdA (kg/m), > 0."""
    c: NDArray[np.float64]
    """Rolling plus climbing, m·g·cos θ·(Crr + grade) (N)."""
    w: NDArray[np.float64]
    """Headwind (m/s)."""
    p: NDArray[np.float64]
    """Power at the wheel (W), ≥ 0."""

    def at(self, index: Any) -> _PowerBalance:
        """The balance at ``index`` of every coefficient (a subset, or a new axis to broadcast against)."""
        return _PowerBalance(self.a[index], self.c[index], self.w[index], self.p[index])


def _largest_root(balance: _PowerBalance) -> NDArray[np.float64]:
    """Largest v ≥ 0 of the ``balance``, all (N,), a > 0, p ≥ 0 (see :func:`speed_for_power`).

    Each step takes Newton's point when it stays in the bracket, else the bracket's secant point (Newton
    overshoots on the concave part of a tailwind branch, and the root may sit at the bracket's low end), else its
    midpoint; the bracket shrinks on every evaluation. It stops when f is at the rounding level of its terms or
    the bracket is one ulp wide, then keeps whichever of v and its two float neighbours gives the smallest |f|.
    """
    with np.errstate(all="ignore"):
        return _largest_root_unguarded(balance)


def _largest_root_unguarded(balance: _PowerBalance) -> NDArray[np.float64]:
    a, c, w, p = balance
    balance_air = np.sign(-c) * np.sqrt(np.abs(c) / a)  # air speed at which drag balances c: g = 0
    v0 = np.maximum(balance_air - w, 0.0)
    lo, f_lo = v0.copy(), -p  # P(v0) = 0
    hi = v0 + 2.0 * np.abs(balance_air) + np.cbrt(p / a)  # P(hi) ≥ p: see the docstring's bracket
    f_hi = np.maximum(_residual(hi, balance)[0], 0.0)
    v = np.clip(_cubic_guess(balance, v0), lo, hi)
    v = np.where(np.isfinite(v), v, 0.5 * (lo + hi))
    active = p > 0.0  # P = 0: v0 is the answer
    v = np.where(active, v, v0)
    eps = np.finfo(np.float64).eps
    idx = np.flatnonzero(active)
    for _ in range(_MAX_POLISH_STEPS):
        if idx.size == 0:
            break
        # Work on the unconverged points only: most converge in three or four steps.
        vi, balance_i = v[idx], balance.at(idx)
        f, g, g_slope, noise = _residual(vi, balance_i)
        below, above = f < 0.0, f > 0.0
        lo_i = np.where(below, vi, lo[idx])
        f_lo_i = np.where(below, f, f_lo[idx])
        hi_i = np.where(above, vi, hi[idx])
        f_hi_i = np.where(above, f, f_hi[idx])
        lo[idx], f_lo[idx], hi[idx], f_hi[idx] = lo_i, f_lo_i, hi_i, f_hi_i
        df = g + vi * g_slope
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            # v − f/df rearranged: on the bracket g ≥ 0, so no term cancels and a root near 0 keeps its digits.
            newton = (balance_i.p + vi * vi * g_slope) / df
            secant = lo_i - f_lo_i * (hi_i - lo_i) / (f_hi_i - f_lo_i)
        step = np.where(
            (newton >= lo_i) & (newton <= hi_i),
            newton,
            np.where((secant > lo_i) & (secant < hi_i), secant, 0.5 * (lo_i + hi_i)),
        )
        # Converged: f at the rounding level of its terms, a bracket one ulp wide, or no move left. (A test on
        # v's own rounding, eps·v·|df|, stopped several ulps short where |df| is large: a fast tailwind.)
        moving = (np.abs(f) > noise) & (step != vi) & (hi_i - lo_i > 2.0 * eps * np.maximum(hi_i, 0.0))
        v[idx[moving]] = step[moving]
        idx = idx[moving]
    # The nearest float: v or one of its neighbours (within the bracket [v0, ∞)).
    solved = np.flatnonzero(active)
    if solved.size:
        vs = v[solved]
        candidates = np.stack([vs, np.nextafter(vs, -np.inf), np.nextafter(vs, np.inf)], axis=1)
        candidates = np.maximum(candidates, v0[solved, None])
        f_all = np.abs(_residual(candidates, balance.at((solved, None)))[0])
        v[solved] = candidates[np.arange(solved.size), np.argmin(f_all, axis=1)]
    return v


def _residual(v: NDArray[np.float64], balance: _PowerBalance) -> tuple[NDArray[np.float64], ...]:
    """f = v·g(v) − p, g, dg/dv, and the rounding level of f's terms."""
    a, c, w, p = balance
    u = v + w
    drag = a * u * np.abs(u)
    g = drag + c
    noise = 8.0 * np.finfo(np.float64).eps * (np.abs(drag * v) + np.abs(c * v) + p)
    return v * g - p, g, 2.0 * a * np.abs(u), noise


_MAX_POLISH_STEPS = 200
"""Bound on the safeguarded Newton steps; bisection alone halves a bracket to one ulp in about 60."""


def _cubic_guess(balance: _PowerBalance, v0: NDArray[np.float64]) -> NDArray[np.float64]:
    """Closed-form root of the cubic on the branch that holds the root: the first guess for the polish.

    Branch s = +1 (v ≥ −w, air from ahead): a·v³ + 2aw·v² + (aw² + c)·v − p = 0; branch s = −1 (v < −w, a
    tailwind faster than the rider) has every coefficient but c negated. The root lies on branch −1 when v₀ < −w
    and P(−w) = −c·w ≥ p.
    """
    a, c, w, p = balance
    sign = np.where((v0 < -w) & (-c * w >= p), -1.0, 1.0)
    lead = sign * a
    roots = _cubic_real_roots(2.0 * w, (lead * w * w + c) / lead, -p / lead)
    # The largest real root inside the branch and at or beyond v0, with slack for rounding (the polish repairs it);
    # NaN where rounding leaves none there.
    slack = 1e-9 * (1.0 + np.abs(w) + v0)[:, None]
    edge = -w[:, None]
    inside = np.where(sign[:, None] > 0.0, roots >= edge - slack, roots <= edge + slack)
    inside &= roots >= v0[:, None] - slack
    best = np.where(inside, roots, -np.inf).max(axis=1)
    return np.where(np.isfinite(best), best, np.nan)


def _cubic_real_roots(b: NDArray[np.float64], c: NDArray[np.float64], d: NDArray[np.float64]) -> NDArray[np.float64]:
    """Real roots of x³ + b·x² + c·x + d = 0, batched: (N, 3), NaN where a root is complex.

    Cardano for one real root, the trigonometric form for three (no complex arithmetic, no loops).
    """
    shift = b / 3.0
    p = c - b * b / 3.0
    q = 2.0 * b**3 / 27.0 - b * c / 3.0 + d
    disc = (q / 2.0) ** 2 + (p / 3.0) ** 3
    roots = np.full(b.shape + (3,), np.nan)
    one = disc >= 0.0
    sq = np.sqrt(np.where(one, disc, 0.0))
    roots[:, 0] = np.where(one, np.cbrt(-q / 2.0 + sq) + np.cbrt(-q / 2.0 - sq) - shift, np.nan)
    three = ~one
    m = 2.0 * np.sqrt(np.where(three, -p / 3.0, 0.0))
    safe_p = np.where(three & (p != 0.0), p, -1.0)
    arg = np.clip(3.0 * q / (2.0 * safe_p) * np.sqrt(-3.0 / safe_p), -1.0, 1.0)
    phi = np.arccos(arg) / 3.0
    for k in range(3):
        roots[:, k] = np.where(three, m * np.cos(phi - 2.0 * np.pi * k / 3.0) - shift, roots[:, k])
    return roots


def paceline(
    n_riders: int,
    gap_m: float,
    speed_ms: float,
    cda_m2: float,
    mass_kg: float,
    crr: float,
    grade: float = 0.0,
    altitude_m: float = 0.0,
    headwind_ms: float = 0.0,
    drivetrain_efficiency: float = 1.0,
    model: DraftModel = "textbook",
) -> Power:
    """Power of each rider in a single-file line at one speed, leader first.

    Args:
        n_riders: riders in the line (1 to :data:`MAX_FORMATION_RIDERS`, 200).
        gap_m: wheel-to-wheel gap (m, ≥ 0).
        model: ``"textbook"`` or ``"measured"`` drafting (see the module docstring).
        Other arguments as for :func:`power`, for one rider: each one number (the riders are alike).

    Returns:
        :class:`Power` whose fields have shape (n_riders,).

    Raises:
        ValueError: an argument is not a number (an array included) or out of its range; the message names it.
    """
    return _group_power(
        "paceline",
        lambda: 1.0 - drag_reduction(n_riders, gap_m, model),
        speed_ms,
        cda_m2,
        mass_kg,
        crr,
        grade,
        altitude_m,
        headwind_ms,
        drivetrain_efficiency,
    )


def _group_power(
    function: str,
    drag_fraction: Callable[[], NDArray[np.float64]],
    speed_ms: float,
    cda_m2: float,
    mass_kg: float,
    crr: float,
    grade: float,
    altitude_m: float,
    headwind_ms: float,
    drivetrain_efficiency: float,
) -> Power:
    """:func:`power` of each rider of a group at its one speed, each rider's CdA times its ``drag_fraction()``
    ((N,) fractions of a lone rider's drag), which is called once the rider's own inputs are checked against
    :data:`MODEL_DOMAIN` (``function`` names the caller in the message)."""
    speed = _checks.non_negative("speed_ms", speed_ms)  # the group's one speed
    # One rider's numbers, each a number: an array of another length than the group raised numpy's "operands
    # could not be broadcast together", naming none of them.
    cda, mass, friction, slope, altitude, wind, efficiency = (
        _checks.finite_number(name, value)
        for name, value in (
            ("cda_m2", cda_m2),
            ("mass_kg", mass_kg),
            ("crr", crr),
            ("grade", grade),
            ("altitude_m", altitude_m),
            ("headwind_ms", headwind_ms),
            ("drivetrain_efficiency", drivetrain_efficiency),
        )
    )
    _check_model_domain(cda, mass, friction, altitude, wind, speed, function)
    drag = drag_fraction()
    return _power(
        np.full(drag.shape, speed), _positive("cda_m2", cda) * drag, mass, friction, slope, altitude, wind, efficiency
    )


# --------------------------------------------------------------------------------------------- weather air
# Real air, for the course mode: the ideal gas law for moist air, and the standard atmosphere.
R_DRY_AIR = 287.058
"""Specific gas constant of dry air (J/(kg·K)), R / 0.0289652 kg/mol (U.S. Standard Atmosphere 1976)."""
R_WATER_VAPOUR = 461.495
"""Specific gas constant of water vapour (J/(kg·K)), R / 0.018016 kg/mol."""
ISA_SEA_LEVEL_PRESSURE_HPA = 1013.25
"""Standard sea-level pressure (hPa)."""
ISA_SEA_LEVEL_TEMPERATURE_C = 15.0
"""Standard sea-level temperature (°C)."""
ISA_LAPSE_RATE_K_PER_M = 0.0065
"""Temperature lapse rate of the standard troposphere (K/m)."""
_ISA_TROPOPAUSE_M = 11_000.0
ISA_ALTITUDE_M = (-5_000.0, 20_000.0)
"""Geometric altitudes (m) the standard atmosphere functions take: from −5 km, where the U.S. Standard Atmosphere
1976 tables begin, to 20 km, the top of the isothermal layer above the tropopause that they model."""
_ISA_G0 = 9.80665
_ISA_MOLAR_MASS = 0.0289644  # kg/mol, U.S. Standard Atmosphere 1976
_ISA_R = 8.31432  # J/(mol·K), the constant the 1976 standard uses
_ISA_EXPONENT = _ISA_G0 * _ISA_MOLAR_MASS / (_ISA_R * ISA_LAPSE_RATE_K_PER_M)  # 5.25588
_KELVIN = 273.15


def saturation_vapour_pressure_hpa(temperature_c: ArrayLike) -> NDArray[np.float64]:
    """Saturation vapour pressure of water over liquid water, Buck (1981).

    e_s = 6.1121·exp(17.502·T / (240.97 + T)) hPa, T in °C: Buck, A. L. (1981), "New equations for computing
    vapor pressure and enhancement factor", J. Appl. Meteorol. 20, 1527–1532, eq. 8 (e_w, enhancement factor
    left out; within 0.05 % of the Wexler/Goff–Gratch values from −20 to +50 °C, as Buck's table 2 reports).

    Args:
        temperature_c: air temperature (°C, −60 to 60), any shape.

    Returns:
        Pressure (hPa), same shape.

    Raises:
        ValueError: a temperature is not finite or outside −60…60 °C.
    """
    t = _finite("temperature_c", temperature_c)
    if np.any((t < -60.0) | (t > 60.0)):
        raise ValueError(f"temperature_c must be in [-60, 60] °C, got {_checks.shown(temperature_c)}")
    return 6.1121 * np.exp(17.502 * t / (240.97 + t))


def air_density_weather(
    temperature_c: ArrayLike, pressure_hpa: ArrayLike, relative_humidity: ArrayLike = 0.0
) -> NDArray[np.float64]:
    """Density of moist air from a weather reading, by the ideal gas law for dry air plus water vapour.

    ρ = (p − e)/(R_d·T) + e/(R_v·T), e = RH·e_s(T), with e_s from :func:`saturation_vapour_pressure_hpa`
    (Buck 1981). Humid air is lighter than dry air at the same pressure and temperature (water's molar mass is
    18 g/mol against air's 29). The non-ideality of air (compressibility Z ≈ 0.9996 near sea level, CIPM-2007,
    Picard et al. 2008, Metrologia 45:149) is left out: 0.04 %.

    Args:
        temperature_c: air temperature (°C, −60 to 60).
        pressure_hpa: station (not sea-level-reduced) pressure (hPa, 10 to 1100).
        relative_humidity: relative humidity as a fraction in [0, 1] (0.5 is 50 %).

    Returns:
        Density (kg/m³) with the broadcast shape of the inputs.

    Raises:
        ValueError: an argument is not finite or out of its range; the message names it.
    """
    e_s = saturation_vapour_pressure_hpa(temperature_c)
    t_k = _finite("temperature_c", temperature_c) + _KELVIN
    p = _finite("pressure_hpa", pressure_hpa)
    if np.any((p < 10.0) | (p > 1100.0)):
        raise ValueError(f"pressure_hpa must be in [10, 1100] hPa, got {_checks.shown(pressure_hpa)}")
    rh = _finite("relative_humidity", relative_humidity)
    if np.any((rh < 0.0) | (rh > 1.0)):
        raise ValueError(f"relative_humidity must be a fraction in [0, 1], got {_checks.shown(relative_humidity)}")
    _broadcast(temperature_c=t_k, pressure_hpa=p, relative_humidity=rh)
    e = rh * e_s
    if np.any(e >= p):
        raise ValueError("relative_humidity: the vapour pressure would reach the total pressure")
    return 100.0 * ((p - e) / (R_DRY_AIR * t_k) + e / (R_WATER_VAPOUR * t_k))


_EARTH_RADIUS_ISA_M = 6_356_766.0  # r₀ of the geopotential conversion, U.S. Standard Atmosphere 1976


def _isa_altitude(altitude_m: ArrayLike) -> NDArray[np.float64]:
    """Geopotential altitude H = r₀·h/(r₀ + h) of the geometric altitude h (what a map or a GPS gives)."""
    h = _finite("altitude_m", altitude_m)
    low, high = ISA_ALTITUDE_M
    if np.any((h < low) | (h > high)):
        raise ValueError(f"altitude_m must be in [{low:g}, {high:g}] m, got {_checks.shown(altitude_m)}")
    return _EARTH_RADIUS_ISA_M * h / (_EARTH_RADIUS_ISA_M + h)


def isa_temperature_c(altitude_m: ArrayLike) -> NDArray[np.float64]:
    """Temperature of the International Standard Atmosphere (°C): 15 − 6.5 K/km up to 11 km, −56.5 °C above.

    Args:
        altitude_m: geometric altitude above mean sea level (m, −5000 to 20 000: :data:`ISA_ALTITUDE_M`), any shape;
            converted to geopotential altitude H = r₀·h/(r₀ + h), r₀ = 6 356 766 m, as the standard's tables are.

    Returns:
        Temperature (°C), same shape.
    """
    h = _isa_altitude(altitude_m)
    return ISA_SEA_LEVEL_TEMPERATURE_C - ISA_LAPSE_RATE_K_PER_M * np.minimum(h, _ISA_TROPOPAUSE_M)


def isa_pressure_hpa(altitude_m: ArrayLike) -> NDArray[np.float64]:
    """Pressure of the International Standard Atmosphere (ISO 2533:1975; U.S. Standard Atmosphere 1976).

    Troposphere (H ≤ 11 km): p = 1013.25·(1 − L·H/T₀)^(g₀M/(R·L)) hPa, L = 6.5 K/km, T₀ = 288.15 K, exponent
    5.25588; above, the isothermal layer at 216.65 K: p = p₁₁·exp(−g₀M·(H − 11 000)/(R·216.65)).

    Args:
        altitude_m: geometric altitude above mean sea level (m, −5000 to 20 000: :data:`ISA_ALTITUDE_M`), any shape;
            converted to geopotential altitude H = r₀·h/(r₀ + h), r₀ = 6 356 766 m, as the standard's tables are.

    Returns:
        Pressure (hPa), same shape.

    Raises:
        ValueError: an altitude is not finite or outside −5000…20 000 m.
    """
    h = _isa_altitude(altitude_m)
    t0 = ISA_SEA_LEVEL_TEMPERATURE_C + _KELVIN
    low = np.minimum(h, _ISA_TROPOPAUSE_M)
    p = ISA_SEA_LEVEL_PRESSURE_HPA * (1.0 - ISA_LAPSE_RATE_K_PER_M * low / t0) ** _ISA_EXPONENT
    t_tropopause = t0 - ISA_LAPSE_RATE_K_PER_M * _ISA_TROPOPAUSE_M
    above = np.maximum(h - _ISA_TROPOPAUSE_M, 0.0)
    return p * np.exp(-_ISA_G0 * _ISA_MOLAR_MASS * above / (_ISA_R * t_tropopause))


# --------------------------------------------------------------------------------------------- Martin et al. 1998
MARTIN_BEARING_W = (0.091, 0.0087)
"""Wheel-bearing loss V·(91 + 8.7·V)·10⁻³ W (Martin et al. 1998, from Dahn et al. 1991): (W per m/s, W per (m/s)²)."""


@dataclasses.dataclass(frozen=True)
class MartinPower:
    """Martin et al. (1998) power terms in watts; each field has the broadcast shape of the inputs."""

    aero: NDArray[np.float64]
    """½ρ·(CdA + F_w)·(v + w)|v + w|·v: air drag of rider and bike plus the spokes' drag area F_w (W)."""
    rolling: NDArray[np.float64]
    """Crr·m·g·cos θ·v (W)."""
    bearings: NDArray[np.float64]
    """Wheel-bearing friction v·(91 + 8.7·v)·10⁻³ (W)."""
    climbing: NDArray[np.float64]
    """Potential energy: m·g·sin θ·v (W); negative downhill."""
    kinetic: NDArray[np.float64]
    """Kinetic energy change (m + I/r²)·a·v, wheel inertia I about radius r (W); negative while slowing."""
    wheel: NDArray[np.float64]
    """Sum of the five terms: the power the rear wheel must deliver (W)."""
    total: NDArray[np.float64]
    """Power at the pedals: wheel / drivetrain efficiency when positive, the plain sum when not (W)."""


def martin_power(
    speed_ms: ArrayLike,
    cda_m2: ArrayLike,
    mass_kg: ArrayLike,
    crr: ArrayLike,
    grade: ArrayLike = 0.0,
    headwind_ms: ArrayLike = 0.0,
    air_density: ArrayLike = RHO_SEA_LEVEL,
    drivetrain_efficiency: ArrayLike = 0.976,
    spoke_drag_m2: ArrayLike = 0.0044,
    wheel_inertia_kgm2: ArrayLike = 0.14,
    wheel_radius_m: ArrayLike = 0.311,
    acceleration_ms2: ArrayLike = 0.0,
) -> MartinPower:
    """Power to ride at ``speed_ms``: the full model of Martin et al. (1998), J. Appl. Biomech. 14:276–291.

    P = (P_AT + P_RR + P_WB + P_PE + P_KE) / E_c, the paper's eq. 9 with

    - P_AT = ½ρ·(C_D·A + F_w)·V_A²·V_G, here with V_A² written (v + w)|v + w| so a tailwind faster than the rider
      pushes (the paper squares it);
    - P_RR = V_G·μ_rr·m_T·g·cos(atan G_R);  P_WB = V_G·(91 + 8.7·V_G)·10⁻³;
    - P_PE = V_G·m_T·g·sin(atan G_R);  P_KE = (m_T + I/r²)·a·V_G, the limit of the paper's
      ½(m_T + I/r²)(V_f² − V_i²)/(t_f − t_i) over a short interval.

    The paper's values are the defaults: E_c = 0.976, F_w = 0.0044 m², I = 0.14 kg·m² (both wheels), r = 0.311 m.
    CdA here is yaw-free (the paper measured it in the wind tunnel at the ride's yaw).

    Args:
        speed_ms: ground speed V_G (m/s, ≥ 0).
        cda_m2: drag area C_D·A of rider and bike (m², > 0).
        mass_kg: rider plus bike m_T (kg, > 0).
        crr: rolling-resistance coefficient μ_rr (≥ 0).
        grade: rise over run G_R (0.05 = 5 %).
        headwind_ms: wind against the rider (m/s); negative for a tailwind.
        air_density: ρ (kg/m³, > 0); :func:`air_density_weather` gives it from a weather reading.
        drivetrain_efficiency: E_c in [0.001, 1].
        spoke_drag_m2: F_w, drag area of the rotating spokes (m², ≥ 0).
        wheel_inertia_kgm2: I, moment of inertia of both wheels together (kg·m², ≥ 0).
        wheel_radius_m: r, outer radius of the tyre (m, > 0).
        acceleration_ms2: dV_G/dt (m/s²).

    Returns:
        :class:`MartinPower`, every field with the broadcast shape of the inputs.

    Raises:
        ValueError: an argument is not finite or out of its range; the message names it.
    """
    v = _non_negative("speed_ms", speed_ms)
    _check_domain(
        "martin_power",
        MARTIN_DOMAIN,
        speed_ms=speed_ms,
        cda_m2=cda_m2,
        mass_kg=mass_kg,
        crr=crr,
        headwind_ms=headwind_ms,
        air_density=air_density,
        spoke_drag_m2=spoke_drag_m2,
        wheel_inertia_kgm2=wheel_inertia_kgm2,
        wheel_radius_m=wheel_radius_m,
        acceleration_ms2=acceleration_ms2,
    )
    mass = _positive("mass_kg", mass_kg)
    slope = _finite("grade", grade)
    rho = _positive("air_density", air_density)
    drag_area = _positive("cda_m2", cda_m2) + _non_negative("spoke_drag_m2", spoke_drag_m2)
    wind = _finite("headwind_ms", headwind_ms)
    inertia = _non_negative("wheel_inertia_kgm2", wheel_inertia_kgm2)
    radius = _positive("wheel_radius_m", wheel_radius_m)
    acceleration = _finite("acceleration_ms2", acceleration_ms2)
    efficiency = _efficiency(drivetrain_efficiency)
    friction = _non_negative("crr", crr)
    _broadcast(
        speed_ms=v,
        cda_m2=cda_m2,
        mass_kg=mass,
        crr=friction,
        grade=slope,
        headwind_ms=wind,
        air_density=rho,
        drivetrain_efficiency=efficiency,
        spoke_drag_m2=spoke_drag_m2,
        wheel_inertia_kgm2=inertia,
        wheel_radius_m=radius,
        acceleration_ms2=acceleration,
    )

    rolling_force, climbing_force = _road_forces(mass, friction, slope)
    aero, rolling, bearings, climbing = wheel_power_terms(
        v, 0.5 * rho * drag_area, rolling_force, climbing_force, wind, *MARTIN_BEARING_W
    )
    kinetic = (mass + inertia / radius**2) * acceleration * v
    aero, rolling, bearings, climbing, kinetic, efficiency = np.broadcast_arrays(
        aero, rolling, bearings, climbing, kinetic, efficiency
    )
    wheel = np.asarray(aero + rolling + bearings + climbing + kinetic)  # 0-d sums are numpy scalars, not arrays
    total = np.where(wheel > 0.0, wheel / efficiency, wheel)
    return MartinPower(
        aero=aero.copy(),
        rolling=rolling.copy(),
        bearings=bearings.copy(),
        climbing=climbing.copy(),
        kinetic=kinetic.copy(),
        wheel=wheel,
        total=total,
    )


# --------------------------------------------------------------------------------------------- formations
FormationShape = Literal["single", "double", "bunch", "echelon"]
FORMATION_SHAPES: tuple[FormationShape, ...] = ("single", "double", "bunch", "echelon")
MAX_FORMATION_RIDERS = 200
"""Most riders :func:`formation` lays out."""
BIKE_LENGTH_M = 1.70
"""Wheel-to-wheel length of one bike (m): a gap is measured from a front wheel to the rear wheel ahead."""
BUNCH_WIDTH = 8
"""Riders abreast where a bunch stops widening (Blocken et al. 2018's peloton widens row by row behind its leader)."""
ECHELON_WIDTH = BUNCH_WIDTH
"""Riders in one echelon: it reaches across a road as wide as a bunch's widest row, and the riders who find no place
in it ride in the next echelon behind, as the groups of a race split by a crosswind do."""

# Wake-model constants of formation_drag ("measured"), fitted to Blocken et al. 2018's 121-rider map (see
# docs/peloton.md for the fit and its residuals). The single-file part reuses the line model's constants above.
WAKE_WIDTH_M = 0.4507
"""Lateral scale σ of a rider's own wake: shelter from a rider ahead falls as exp(−(Δy/σ)²) (halved at 0.38 m)."""
BUNCH_OFFSET_M = 0.4084
"""Lateral offset at which a rider ahead adds most to the bunch's shelter, (Δy/s)²·exp(−(Δy/s)²) (peak at s)."""
BUNCH_SHELTER = 0.7919
"""Strength β of the bunch's shelter: drag × exp(−β·Σ offset weights of the riders ahead)."""
BUNCH_FADE_M = 10.7038
"""Fade length of the bunch's shelter with the gap to each rider ahead (m)."""
BUNCH_PUSH = 0.1661
"""Strength γ of the push an exposed rider gets from the riders behind it, off its axis (the bunch behind a leader)."""


def formation(
    n_riders: int, shape: FormationShape, *, gap_m: float = 0.3, lateral_m: float = 0.6
) -> NDArray[np.float64]:
    """Rider positions of a group formation, leader first.

    Shapes:

    * ``"single"``: a line, each rider one bike plus ``gap_m`` behind the one ahead (what :func:`drag_reduction`
      models).
    * ``"double"``: a two-abreast paceline, pairs ``lateral_m`` apart; an odd last rider rides behind the left file.
    * ``"bunch"``: a peloton after Blocken et al. 2018 (J. Wind Eng. Ind. Aerodyn. 179:319): one leader, then rows
      one rider wider each until :data:`BUNCH_WIDTH` abreast, then rows of 8 and 7 alternately; every row is centred
      on the road, so neighbouring rows are staggered by half a rider. Rows are one bike plus ``gap_m`` apart.
    * ``"echelon"``: diagonal lines of up to :data:`ECHELON_WIDTH` riders, each rider half a bike plus ``gap_m``
      behind the one ahead and ``lateral_m`` to its right; a full echelon spans the road, so the next rider starts
      the next echelon at the leader's side, one bike plus ``gap_m`` behind the last rider of the one ahead.

    Args:
        n_riders: riders (1 to :data:`MAX_FORMATION_RIDERS`).
        shape: one of :data:`FORMATION_SHAPES`.
        gap_m: wheel-to-wheel gap between rows (m, 0 to 50).
        lateral_m: distance between the centres of riders side by side (m, 0.3 to 5).

    Returns:
        (n_riders, 2) positions (m): x forward along the road (leader at 0, the others behind at x < 0), y to the
        left of the road's axis.

    Raises:
        ValueError: an argument is out of range; the message names it.
    """
    _checks.integer("n_riders", n_riders)
    if not 1 <= n_riders <= MAX_FORMATION_RIDERS:
        raise ValueError(f"n_riders must be in [1, {MAX_FORMATION_RIDERS}], got {_checks.shown(n_riders)}")
    gap = _checks.non_negative("gap_m", gap_m)
    if gap > 50.0:
        raise ValueError(f"gap_m must be at most 50 m, got {_checks.shown(gap_m)}")
    lateral = _checks.finite_number("lateral_m", lateral_m)
    if not 0.3 <= lateral <= 5.0:
        raise ValueError(f"lateral_m must be in [0.3, 5] m, got {_checks.shown(lateral_m)}")
    _checks.choice("shape", shape, FORMATION_SHAPES)
    n = int(n_riders)
    k = np.arange(n, dtype=np.float64)
    step = BIKE_LENGTH_M + gap
    match shape:
        case "single":
            return np.stack([-k * step, np.zeros(n)], axis=1).astype(np.float64)
        case "double":
            return np.stack([-np.floor(k / 2) * step, np.where(k % 2 == 0, 0.5, -0.5) * lateral], axis=1).astype(
                np.float64
            )
        case "echelon":
            # Rider k rides in echelon k // ECHELON_WIDTH, place k % ECHELON_WIDTH: a half-bike step back along it,
            # one whole bike back from the end of one echelon to the start of the next.
            row, place = np.divmod(k, ECHELON_WIDTH)
            x = -(k - row) * (0.5 * BIKE_LENGTH_M + gap) - row * step
            return np.stack([x, -place * lateral], axis=1).astype(np.float64)
        case "bunch":
            xs: list[float] = []
            ys: list[float] = []
            row = 0
            while len(xs) < n:
                # Rows one wider each up to BUNCH_WIDTH, then BUNCH_WIDTH − 1 and BUNCH_WIDTH alternately (staggered).
                width = row + 1 if row < BUNCH_WIDTH else BUNCH_WIDTH - 1 + (row - BUNCH_WIDTH) % 2
                ys += [(j - 0.5 * (width - 1)) * lateral for j in range(width)]
                xs += [-row * step] * width
                row += 1
            return np.stack([np.array(xs[:n]), np.array(ys[:n])], axis=1)


def _plateau(depth: NDArray[np.float64]) -> NDArray[np.float64]:
    """The line model's close-gap reduction R at a (fractional) number of riders ahead: 0, R₂, R₃, R₄… joined by
    straight lines, so a whole number ``k − 1`` ahead gives position k's plateau exactly."""
    table = np.array([0.0, *_MEASURED_PLATEAU])
    return np.interp(depth, np.arange(table.size, dtype=np.float64), table)


def apparent_yaw(speed_ms: float, headwind_ms: float = 0.0, crosswind_ms: float = 0.0) -> float:
    """Yaw ψ (rad) of the air a rider meets: the angle between the direction of travel and where the apparent wind
    comes from, + from the left. ψ = atan2(crosswind, speed + headwind); 0 in still air or a pure head or tail wind.

    Args:
        speed_ms: ground speed (m/s, ≥ 0).
        headwind_ms: wind component against the direction of travel (m/s, negative for a tailwind).
        crosswind_ms: wind component across it (m/s, + blowing from the rider's left).

    Raises:
        ValueError: an argument is not a finite number (or the speed is negative); the message names it.
    """
    speed = _checks.non_negative("speed_ms", speed_ms)
    head = _checks.finite_number("headwind_ms", headwind_ms)
    cross = _checks.finite_number("crosswind_ms", crosswind_ms)
    return math.atan2(cross, speed + head) if cross != 0.0 else 0.0


def formation_drag(
    positions_xy: ArrayLike, model: DraftModel = "measured", *, yaw_rad: float = 0.0
) -> NDArray[np.float64]:
    """Each rider's air drag in a formation, as a fraction of the same rider riding alone at the same speed.

    A wake model over the (N, N) offsets: rider j rides Δx = x_j − x_i ahead of rider i and Δy = y_j − y_i to its
    side; the gap between them is g = max(Δx − L, 0), L = :data:`BIKE_LENGTH_M`, and φ = clip(Δx/L, 0, 1) says how
    far j is ahead (0 side by side, 1 from a bike length on). With a(Δy) = exp(−(Δy/σ)²) the rider's own wake and
    b(Δy) = (Δy/s)²·exp(−(Δy/s)²) the offset riders of a bunch (b(0) = 0)::

        depth_i = Σ_j a·φ                          riders ahead in i's wake (whole riders in a line)
        near_i  = max_j a·φ·exp(−g/9.7 m)          the closest shelter
        line_i  = R(depth_i)·near_i                 R: the line model's plateaus 0, 0.40, 0.48, 0.50…
        bunch_i = exp(−β·Σ_j b·φ·exp(−g/F))         the shelter of a bunch around and ahead of i
        push_i  = (1 − min(depth_i, 1))·(p + q − p·q),  p = 0.03·max_j a·φ'·exp(−g'/1.5 m),
                  q = 1 − exp(−γ·Σ_j b·φ'·exp(−g'/1.5 m))   (φ', g' for the riders behind i)
        drag_i  = (1 − push_i)·(1 − line_i)·bunch_i

    In single file every Δy is 0, so b = 0, depth is the number of riders ahead and near the gap's fade: the
    model is :func:`drag_reduction` exactly (drag = 1 − reduction). The constants σ, s, β, F and γ
    (:data:`WAKE_WIDTH_M`, :data:`BUNCH_OFFSET_M`, :data:`BUNCH_SHELTER`, :data:`BUNCH_FADE_M`, :data:`BUNCH_PUSH`)
    are fitted to Blocken et al. 2018 (J. Wind Eng. Ind. Aerodyn. 179:319, CFD of a 121-rider peloton validated in a
    wind tunnel): leader 0.88, second row 0.63, the middle of the third row 0.38, the middle of the bunch 0.05–0.10 and
    the back 0.04–0.05 of a lone rider's drag. Every term only grows with more riders, so adding a rider behind the
    group (or anywhere ahead of nobody) never raises anyone's drag, and the kernels are even in Δy, so the mirror
    image across the road's axis gives the same drags.

    Crosswind: every wake trails downwind along the apparent wind, so the offsets are measured in the wind's frame,
    the layout turned by the yaw ``yaw_rad`` (:func:`apparent_yaw`): Δx' = Δx·cos ψ + Δy·sin ψ, Δy' = −Δx·sin ψ +
    Δy·cos ψ. A line along the road then loses its shelter to the side, and an echelon angled downwind keeps it: the
    reason riders form one. Checked against the one crosswind study found (Fintelman-type CFD of five riders at
    30 km/h in a 30 km/h wind at 40°, ψ = 20°; J. Sci. Med. Sport 2022, doi 10.1016/j.jsams.2022.12.003): the
    leader of a straight line saves 0.1 % of its drag, the fourth rider of an echelon in the wind's shadow 53.6 %.
    The drag is a fraction of the same rider's alone in the same wind; how a rider's own drag grows with yaw is not
    modelled.

    ``model="textbook"``: the textbook formula for any layout, drag = 1 − 0.27·max_j a·φ·exp(−g/3.5 m) (in single file,
    :func:`draft_factor` for every follower and 1 for the leader).

    Args:
        positions_xy: (N, 2) rider positions (m), x forward along the road, y to the left, any order; N ≥ 1.
        model: ``"measured"`` (the wake model above) or ``"textbook"``.
        yaw_rad: yaw of the apparent wind (rad, + from the left, |ψ| < π/2); 0 for still air or a head wind.

    Returns:
        (N,) drag fractions in (0, 1], in the order of ``positions_xy``.

    Raises:
        ValueError: ``positions_xy`` is not a finite (N, 2) array with 1 ≤ N ≤ 2000 and |coordinates| ≤ 10⁶ m,
            ``model`` is unknown, or ``yaw_rad`` is not a finite number in (−π/2, π/2).
    """
    pos = _checks.bounded_array("positions_xy", positions_xy, 1e6)
    if pos.ndim != 2 or pos.shape[1] != 2 or not 1 <= pos.shape[0] <= 2000:
        raise ValueError(f"positions_xy must have shape (N, 2) with 1 <= N <= 2000, got {pos.shape}")
    _checks.choice("model", model, DRAFT_MODELS)
    yaw = _checks.finite_number("yaw_rad", yaw_rad)
    if not abs(yaw) < 0.5 * math.pi:
        raise ValueError(f"yaw_rad must be in (-pi/2, pi/2), got {_checks.shown(yaw_rad)}")
    x, y = pos[:, 0], pos[:, 1]
    if yaw != 0.0:  # offsets in the wind's frame: its x toward where the apparent wind comes from
        c, s = math.cos(yaw), math.sin(yaw)
        x, y = c * x + s * y, -s * x + c * y
    dx = x[None, :] - x[:, None]  # [i, j]: how far rider j rides ahead of rider i
    dy = y[None, :] - y[:, None]
    own_wake = np.exp(-((dy / WAKE_WIDTH_M) ** 2))
    ahead = np.clip(dx / BIKE_LENGTH_M, 0.0, 1.0)
    gap_ahead = np.maximum(dx - BIKE_LENGTH_M, 0.0)
    if model == "textbook":
        shelter = (own_wake * ahead * np.exp(-gap_ahead / 3.5)).max(axis=1)
        return 1.0 - 0.27 * shelter
    q = (dy / BUNCH_OFFSET_M) ** 2
    offset = q * np.exp(-q)
    behind = np.clip(-dx / BIKE_LENGTH_M, 0.0, 1.0)
    gap_behind = np.maximum(-dx - BIKE_LENGTH_M, 0.0)
    depth = (own_wake * ahead).sum(axis=1)
    near = (own_wake * ahead * np.exp(-gap_ahead / _MEASURED_FADE_M)).max(axis=1)
    line = _plateau(depth) * near
    bunch = np.exp(-BUNCH_SHELTER * (offset * ahead * np.exp(-gap_ahead / BUNCH_FADE_M)).sum(axis=1))
    fade_behind = behind * np.exp(-gap_behind / _LEADER_FADE_M)
    push_line = _LEADER_PLATEAU * (own_wake * fade_behind).max(axis=1)
    push_bunch = 1.0 - np.exp(-BUNCH_PUSH * (offset * fade_behind).sum(axis=1))
    push = (1.0 - np.minimum(depth, 1.0)) * (push_line + push_bunch - push_line * push_bunch)
    return (1.0 - push) * (1.0 - line) * bunch


def formation_power(
    positions_xy: ArrayLike,
    speed_ms: float,
    cda_m2: float,
    mass_kg: float,
    crr: float,
    grade: float = 0.0,
    altitude_m: float = 0.0,
    headwind_ms: float = 0.0,
    drivetrain_efficiency: float = 1.0,
    model: DraftModel = "measured",
) -> Power:
    """Power of each rider of a formation at the group's speed: :func:`power` at CdA·:func:`formation_drag`.

    Args:
        positions_xy: (N, 2) rider positions (m), as for :func:`formation_drag`.
        model: ``"measured"`` or ``"textbook"`` (see :func:`formation_drag`).
        Other arguments as for :func:`power`, for one rider riding alone: each one number (the riders are alike).

    Returns:
        :class:`Power` whose fields have shape (N,), in the order of ``positions_xy``.

    Raises:
        ValueError: an argument is not a number (an array included) or out of its range; the message names it.
    """
    return _group_power(
        "formation_power",
        lambda: formation_drag(positions_xy, model),
        speed_ms,
        cda_m2,
        mass_kg,
        crr,
        grade,
        altitude_m,
        headwind_ms,
        drivetrain_efficiency,
    )


def _check_model_domain(
    cda_m2: ArrayLike,
    mass_kg: ArrayLike,
    crr: ArrayLike,
    altitude_m: ArrayLike,
    headwind_ms: ArrayLike,
    speed_ms: ArrayLike,
    function: str,
) -> None:
    """:data:`MODEL_DOMAIN` for one rider's inputs (for a group, the rider's CdA before drafting shrinks it: a CdA
    at the range's floor drafted below it and was refused, quoting values the caller never passed)."""
    _check_domain(
        function,
        MODEL_DOMAIN,
        speed_ms=speed_ms,
        cda_m2=cda_m2,
        mass_kg=mass_kg,
        crr=crr,
        altitude_m=altitude_m,
        headwind_ms=headwind_ms,
    )
