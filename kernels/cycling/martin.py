"""The full cycling power model of Martin et al. (1998), J. Appl. Biomech. 14:276–291: the textbook terms of
:mod:`kernels.cycling.power_law` plus wheel-bearing losses, the spokes' drag and the kinetic energy of rider, bike and
wheels (:func:`martin_power`), and the domain it is defined on (:data:`MARTIN_DOMAIN`).
"""

from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import ArrayLike, NDArray

from kernels.cycling._arrays import _broadcast, _check_domain, _efficiency, _finite, _non_negative, _positive
from kernels.cycling.air import RHO_SEA_LEVEL
from kernels.cycling.power_law import MODEL_DOMAIN, _road_forces, wheel_power_terms

MARTIN_BEARING_W = (0.091, 0.0087)
"""Wheel-bearing loss V·(91 + 8.7·V)·10⁻³ W (Martin et al. 1998, from Dahn et al. 1991): (W per m/s, W per (m/s)²)."""

MARTIN_DOMAIN: dict[str, tuple[float, float]] = {
    **{name: bounds for name, bounds in MODEL_DOMAIN.items() if name != "altitude_m"},
    "air_density": (0.0, 100.0),
    "spoke_drag_m2": (0.0, 1e4),
    "wheel_inertia_kgm2": (0.0, 1e6),
    "wheel_radius_m": (1e-3, 100.0),
    "acceleration_ms2": (-1e4, 1e4),
}
"""As :data:`MODEL_DOMAIN`, for :func:`martin_power`'s own inputs (the air given as a density, up to 100 kg/m³)."""


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
        air_density: ρ (kg/m³, > 0); :func:`kernels.cycling.air_density_weather` gives it from a weather reading.
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
