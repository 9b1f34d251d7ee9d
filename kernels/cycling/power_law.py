"""The cyclist power law: aerodynamic, rolling and climbing terms (:func:`power`, with the one implementation of the
terms, :func:`wheel_power_terms`, and its compiled twin), its inverse (:func:`speed_for_power`), single-file drafting
(:func:`drag_reduction`, :func:`paceline`) and the domains they are defined on. The model, its assumptions and the
drafting models' sources: :mod:`kernels.cycling`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any, Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from kernels import _checks
from kernels._jit import compiled
from kernels.cycling._arrays import _broadcast, _check_domain, _efficiency, _finite, _non_negative, _positive
from kernels.cycling.air import AIR_DENSITY_ALTITUDE_M, air_density

G = 9.81
"""Gravitational acceleration (m/s²)."""
MAX_FORMATION_RIDERS = 200
"""Most riders in a group: a line (:func:`drag_reduction`, :func:`paceline`) or a formation
(:func:`kernels.cycling.formation` lays out at most this many)."""

DraftModel = Literal["textbook", "measured"]
DRAFT_MODELS: tuple[DraftModel, ...] = ("textbook", "measured")

# "measured" drafting model constants (the sources: the package docstring, :mod:`kernels.cycling`); the
# formations' wake model (kernels.cycling.formations) reuses them.
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


def draft_factor(gap_m: ArrayLike) -> NDArray[np.float64]:
    """The textbook CdA multiplier for a rider following at ``gap_m``: 1 − 0.27·exp(−gap/3.5)."""
    gap = _non_negative("gap_m", gap_m)
    return 1.0 - 0.27 * np.exp(-gap / 3.5)


def drag_reduction(n_riders: int, gap_m: float, model: DraftModel = "measured") -> NDArray[np.float64]:
    """Fractional CdA reduction of each rider in a single-file line, leader first.

    Args:
        n_riders: riders in the line (1 to :data:`MAX_FORMATION_RIDERS`, 200).
        gap_m: wheel-to-wheel gap between consecutive riders (m, ≥ 0).
        model: ``"textbook"`` or ``"measured"`` (see :mod:`kernels.cycling`).

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
    :func:`kernels.cycling.martin_power`) and, compiled as :data:`wheel_power_terms_compiled`, on floats inside
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
"""Closed ranges (SI units) on which :func:`power` (and :func:`paceline`, :func:`kernels.cycling.formation_power`,
:func:`kernels.cycling.martin_power`) is defined: far beyond any rider (the speed reaches every speed
:func:`speed_for_power` returns), and where the model still means something (no air above ~30 km). Outside them a
huge but finite input gave inf or NaN watts; now ``ValueError`` naming it."""

SPEED_FOR_POWER_DOMAIN: dict[str, tuple[float, float]] = {
    "power_w": (0.0, 1e6),
    **{name: bounds for name, bounds in MODEL_DOMAIN.items() if name != "speed_ms"},
}
"""Closed ranges (SI units) on which :func:`speed_for_power` is defined; ``power``'s own checks (CdA, mass > 0,
…) still apply. Within them no intermediate of the solver overflows or underflows to a wrong answer."""


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
        model: ``"textbook"`` or ``"measured"`` drafting (see :mod:`kernels.cycling`).
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
