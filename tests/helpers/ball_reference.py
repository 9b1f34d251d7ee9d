"""A reference ball flight for the tests and the free-kick benchmark, written from the equations and not from
:mod:`kernels.ball`: scipy's ``solve_ivp`` on drag, Magnus lift and gravity, one kick at a time.

The ball and air are the kernel's defaults: a FIFA size-5 ball of 0.43 kg and radius 0.11 m in air of
1.225 kg/m³, under g = 9.81 m/s². Forces per unit mass are ``−Q·C_D·|v|·v + Q·C_L·|v|·(ω̂ × v) − g·ẑ`` with
``Q = ½ρA/m``; the coefficients are constant (0.25 and 0.25) or measured (Goff & Carré 2010 and a lift slope of 0.9, as
kernels.ball's docstring gives them).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.integrate import solve_ivp

M, R, RHO, G = 0.43, 0.11, 1.225, 9.81
"""Ball mass (kg), radius (m), air density (kg/m³) and gravity (m/s²)."""
AREA = math.pi * R**2
"""The ball's cross-section (m²)."""
Q = 0.5 * RHO * AREA / M
"""½ρA/m (1/m): force per unit mass per unit C·v²."""
START = np.array([0.0, 0.0, R])
"""(3,) a ball on the turf at the origin (m)."""


def reference_at_x(
    velocity: NDArray[np.float64],
    spin: NDArray[np.float64],
    x_line: float,
    model: str = "constant",
    *,
    method: str = "DOP853",
    rtol: float = 1e-12,
    atol: float = 1e-12,
) -> NDArray[np.float64]:
    """Ball centre where a kick from :data:`START` crosses the plane x = ``x_line``, by scipy's ``solve_ivp``.

    Args:
        velocity: (3,) launch velocity (m/s).
        spin: (3,) spin vector (rad/s); its direction is the Magnus axis, zero for no lift.
        x_line: the plane's x (m); the flight must reach it within 5 s.
        model: ``"constant"`` (C_D = C_L = 0.25) or ``"measured"`` coefficients.
        method, rtol, atol: ``solve_ivp``'s solver and tolerances (DOP853 at 1e-12 for a reference).

    Returns:
        (3,) position (m) at the crossing.
    """
    rate = float(np.linalg.norm(spin))
    axis = spin / rate if rate > 0 else np.zeros(3)

    def rhs(_t: float, y: NDArray[np.float64]) -> NDArray[np.float64]:
        v = y[3:]
        speed = float(np.linalg.norm(v))
        if model == "constant":
            c_d, c_l = 0.25, 0.25
        else:  # Goff & Carré 2010 and a lift slope of 0.9 (see kernels.ball's docstring)
            s_param = R * rate / speed
            c_l = 0.9 * min(s_param, 0.3)
            re = RHO * speed * 2 * R / 1.81e-5
            still = 0.155 + 0.346 / (1 + math.exp((re - 1.815e5) / 1.949e4))
            spinning = 0.4127 * max(s_param, 0.05) ** 0.3056
            c_d = still + min(s_param / 0.05, 1.0) * (spinning - still)
        a = -Q * c_d * speed * v + Q * c_l * speed * np.cross(axis, v) + np.array([0.0, 0.0, -G])
        return np.concatenate((v, a))

    def crossing(_t: float, y: NDArray[np.float64]) -> float:
        return float(y[0] - x_line)

    crossing.terminal = True  # type: ignore[attr-defined]
    solution = solve_ivp(
        rhs, (0.0, 5.0), np.concatenate((START, velocity)), method=method, rtol=rtol, atol=atol, events=crossing
    )
    assert solution.status == 1, "the reference flight must reach the line"
    return solution.y_events[0][0][:3]
