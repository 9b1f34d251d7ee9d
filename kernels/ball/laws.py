"""The ball's laws as public functions: the flight's drag and lift coefficients, and its bounce on a surface.

:func:`coefficients` returns the C_D and C_L the flight uses, from the same compiled function its force law calls
(:func:`kernels.ball.aero.drag_lift`); :func:`bounce` applies Cross's grip–slip impulse model
(:mod:`kernels.ball.contact`). Both check their arguments once (``ValueError`` naming the argument) and hand trusted
arrays to their compiled cores. The flight on a pitch applies the same compiled impact at each contact
(:mod:`kernels.ball.play`). Frame, units and the flight's model: :mod:`kernels.ball`.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from kernels import _checks
from kernels.ball import aero, contact
from kernels.ball.config import BALL_RADIUS_M, MEASURED, RADIUS, Model, checked_vector, flight_config, refuse_fast_spin
from kernels.warming import Entry

# The compiled cores called from here: plain Python while the app's first start compiles them (kernels.warming).
drag_lift_table = Entry(aero.drag_lift_table)
impacts = Entry(contact.impacts)

SHELL_INERTIA_FACTOR = 2.0 / 3.0
"""I/(m·R²) of a thin spherical shell: the largest any ball of radius R can have (its mass at most R from the
centre), and a size-5 football's usual model (Cross 2002)."""


def _real_array(name: str, value: ArrayLike, *, non_negative: bool = False) -> NDArray[np.float64]:
    """Finite float64 array (any shape) from ``value``, refusing booleans anywhere in it; ≥ 0 if asked."""
    if _checks.holds_booleans(value):
        raise ValueError(f"{name} must be numbers, not booleans, got {_checks.shown(value)}")
    return _checks.non_negative_array(name, value) if non_negative else _checks.finite_array(name, value)


def coefficients(
    speed_ms: ArrayLike, spin_rads: ArrayLike, model: Model = "measured", **options: Any
) -> tuple[Any, Any]:
    """The drag and lift coefficients (C_D, C_L) the flight uses at a speed and spin rate.

    ``"constant"``: the configured C_D and C_L (0.25 and 0.25 by default). ``"measured"``: with S = r·|ω|/|v| the
    spin parameter and Re = ρ·|v|·2r/μ,

        C_L(S)     = 0.9·min(S, 0.3)        (below Asai et al. 2007's wind-tunnel 0.21 at S = 0.18: see kernels.ball)
        C_D(Re, S) = C_D0(Re) + min(S/0.05, 1)·(C_Ds(max(S, 0.05)) − C_D0(Re))
        C_D0(Re)   = 0.155 + 0.346 / (1 + exp((Re − Re_c) / 1.949·10⁴))   (Goff & Carré 2010, Eur. J. Phys. 31)
        C_Ds(S)    = 0.4127·S^0.3056                                   (Goff & Carré 2010)

    with Re_c the crisis centre (``drag_crisis_re``, 1.815·10⁵ for the Teamgeist they measured), so a spinless
    ball's drag falls through the drag crisis (0.501 well below, 0.328 at 12.19 m/s, 0.155 well above, for the
    default ball and air) and a spinning one's grows with S. The fits were measured up to S ≈ 0.3–0.5; beyond, C_Ds
    is their extrapolation. As for :func:`simulate`, S is r·|ω|/max(|v|, 1 m/s): below 1 m/s the coefficients are
    held at their value at 1 m/s (``coefficients(0, 10)`` is C_D = 0.4127·1.1^0.3056 = 0.425, C_L = 0.27; the
    force, ∝ C·|v|², still goes to zero with the speed), and a spin with S above 10³ is refused, as :func:`simulate`
    refuses it at launch (:func:`kernels.ball.config.refuse_fast_spin`, the one check). Computed by the very
    compiled function the flight's force law calls (:func:`kernels.ball.aero.drag_lift`); details and sources in
    :mod:`kernels.ball`.

    Args:
        speed_ms: the ball's speed |v| (m/s, ≥ 0): a number or an array.
        spin_rads: its spin rate |ω| (rad/s, ≥ 0): a number or an array, broadcast against ``speed_ms``.
        model: ``"measured"`` or ``"constant"``.
        **options: any of :class:`FlightConfig`'s fields but ``model``, as for :func:`simulate`; those that matter
            here are ``radius_m``, ``air_density`` and ``drag_crisis_re`` (the measured model's S, Re and crisis
            centre) and ``drag_coefficient`` and
            ``lift_coefficient`` (the constant model's values).

    Returns:
        (C_D, C_L), dimensionless: two floats when both inputs are numbers, else two arrays of their broadcast
        shape.

    Raises:
        ValueError: naming the argument, for a non-finite, negative or boolean speed or spin, shapes that do not
            broadcast, an unknown model or an invalid option, and (measured model, as :func:`simulate` refuses at
            launch, by the same check) ``spin_rads`` for a spin parameter r·|ω|/max(|v|, 1 m/s) above 10³.
        TypeError: an unknown keyword.
    """
    settings = flight_config(None, {"model": model, **options}).settings
    speed = _real_array("speed_ms", speed_ms, non_negative=True)
    rate = _real_array("spin_rads", spin_rads, non_negative=True)
    try:
        shape = np.broadcast_shapes(speed.shape, rate.shape)
    except ValueError as error:
        raise ValueError(
            f"speed_ms and spin_rads must broadcast together, got shapes {speed.shape} and {rate.shape}"
        ) from error
    speeds = np.array(np.broadcast_to(speed, shape), dtype=np.float64, order="C").reshape(-1)
    rates = np.array(np.broadcast_to(rate, shape), dtype=np.float64, order="C").reshape(-1)
    if settings[MEASURED]:
        refuse_fast_spin(float(settings[RADIUS]), speeds, rates, lambda _: "spin_rads")
    drag, lift = np.empty(len(speeds)), np.empty(len(speeds))
    drag_lift_table(speeds, rates, settings, drag, lift)
    if not shape:
        return float(drag[0]), float(lift[0])
    return drag.reshape(shape), lift.reshape(shape)


def _impact_rows(name: str, value: ArrayLike) -> NDArray[np.float64]:
    array = _real_array(name, value)
    if array.shape != (3,) and (array.ndim != 2 or array.shape[1] != 3):
        raise ValueError(f"{name} must have shape (3,) or (K, 3), got {array.shape}")
    return array


def _fraction(name: str, value: object) -> float:
    number = _checks.finite_number(name, value)
    if not 0.0 <= number <= 1.0:
        raise ValueError(f"{name} must be in [0, 1], got {_checks.shown(value)}")
    return number


def bounce(
    velocity: ArrayLike,
    spin: ArrayLike,
    *,
    normal: ArrayLike = (0.0, 0.0, 1.0),
    restitution: float = 0.6,
    friction: float = 0.6,
    tangential_restitution: float = 0.1,
    radius_m: float = BALL_RADIUS_M,
    inertia_factor: float = SHELL_INERTIA_FACTOR,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """A ball's velocity and spin just after it strikes a surface: Cross's grip–slip impulse model.

    Cross 2002 (Am. J. Phys. 70:1093); Mencke et al. 2020 (Am. J. Phys. 88:934) use the same. With n the unit
    normal, r_c = −R·n and I = α·m·R² (α = ``inertia_factor``), per unit mass (the mass cancels)::

        J_n/m = −(1 + e_n)·(v·n)
        u_t   = v − (v·n)·n + ω × r_c                     (the contact point's tangential velocity)
        J_t/m = −(1 + e_t)·α/(1 + α)·u_t                  (grip)
        J_t/m = −μ·(J_n/m)·û_t   if that |J_t| > μ·J_n    (slide)
        v' = v + (J_n·n + J_t)/m,   ω' = ω + r_c × J_t / I

    A ball not moving into the surface (v·n ≥ 0) is returned unchanged. Kinetic energy (translational and
    rotational) never rises, and the angular momentum about the contact point is conserved. The defaults are a
    size-5 ball on dry turf: e_n = 0.6 (a 2 m drop rebounds 0.72 m, inside FIFA Quality Pro's 0.60–0.85 m), μ = 0.6,
    e_t = 0.1 (see :mod:`kernels.ball.contact`). The flight on a pitch applies the same compiled impact.

    Args:
        velocity: (3,) or (K, 3) velocity at impact (m/s).
        spin: (3,) or (K, 3) angular velocity (rad/s); a (3,) one is shared by a batch, and so is a (3,) velocity.
        normal: (3,) the surface's normal, pointing out of it (any nonzero length; normalised here).
        restitution: e_n, normal coefficient of restitution (0–1).
        friction: μ, sliding friction coefficient (≥ 0).
        tangential_restitution: e_t, the share of the contact point's tangential velocity returned reversed when
            the ball grips (0–1; 0 leaves it rolling).
        radius_m: ball radius R (m, > 0).
        inertia_factor: α = I/(m·R²), in (0, 2/3]: 2/3 a thin shell (the default), 2/5 a solid ball.

    Returns:
        (velocity, spin) after the impact, in m/s and rad/s, each of the broadcast shape of the inputs ((3,) or
        (K, 3)).

    Raises:
        ValueError: naming the argument, for non-finite, boolean or wrongly shaped input, a zero normal, a
            restitution outside [0, 1], a negative friction, a radius ≤ 0, an inertia factor outside (0, 2/3],
            batches of different lengths, or values so large that the impulse overflows.
    """
    v = _impact_rows("velocity", velocity)
    w = _impact_rows("spin", spin)
    unit = _checks.direction("normal", checked_vector("normal", normal, 3), 3)
    e_n = _fraction("restitution", restitution)
    e_t = _fraction("tangential_restitution", tangential_restitution)
    mu = _checks.non_negative("friction", friction)
    radius = _checks.positive("radius_m", radius_m)
    alpha = _checks.positive("inertia_factor", inertia_factor)
    if alpha > SHELL_INERTIA_FACTOR * (1.0 + 1e-12):
        raise ValueError(
            f"inertia_factor must be in (0, 2/3] (2/3 is a thin shell), got {_checks.shown(inertia_factor)}"
        )
    try:
        shape = np.broadcast_shapes(v.shape, w.shape)
    except ValueError as error:
        raise ValueError(f"velocity and spin must have the same length, got shapes {v.shape} and {w.shape}") from error
    rows = (1, 3) if shape == (3,) else shape
    velocities = np.array(np.broadcast_to(v, rows), dtype=np.float64, order="C")
    spins = np.array(np.broadcast_to(w, rows), dtype=np.float64, order="C")
    v_out, w_out = np.empty_like(velocities), np.empty_like(spins)
    surface = np.empty(contact.N_SURFACE)
    surface[contact.RESTITUTION], surface[contact.TANGENTIAL_RESTITUTION] = e_n, e_t
    surface[contact.FRICTION], surface[contact.RADIUS], surface[contact.INERTIA_FACTOR] = mu, radius, alpha
    surface.setflags(write=False)  # typed as the pitch's read-only surfaces: one compiled impact for both
    impacts(velocities, spins, unit, surface, v_out, w_out)
    if not (np.isfinite(v_out).all() and np.isfinite(w_out).all()):
        raise ValueError(
            "velocity, spin and radius_m are too large: the impulse overflowed "
            f"(|v| up to {np.abs(velocities).max():g} m/s, |ω| up to {np.abs(spins).max():g} rad/s)"
        )
    return v_out.reshape(shape), w_out.reshape(shape)
