"""A ball's impact on a surface, compiled: Cross's grip–slip impulse model.

Cross 2002 (R. Cross, "Grip-slip behavior of a bouncing ball", Am. J. Phys. 70:1093), as Mencke et al. 2020
(Am. J. Phys. 88:934) use it for footballs. The impact is instantaneous and the surface rigid and fixed; n is the
unit normal out of the surface, R the ball's radius, I = α·m·R² its moment of inertia (α = 2/3 for a thin shell, 2/5
for a solid ball), r_c = −R·n the contact point from the centre. Per unit mass (the mass cancels)::

    J_n/m = −(1 + e_n)·(v·n)                                 normal impulse (e_n: normal restitution)
    u_t   = v − (v·n)·n + ω × r_c                            the contact point's tangential velocity
    J_t/m = −(1 + e_t)·α/(1 + α)·u_t                         grip: u_t leaves reversed to −e_t·u_t
    J_t/m = −μ·(J_n/m)·û_t      where |J_t| > μ·J_n          slide: Coulomb friction μ caps the tangential impulse
    v' = v + (J_n·n + J_t)/m
    ω' = ω + r_c × J_t / I = ω − n × (J_t/m) / (α·R)

A ball that is not moving into the surface (v·n ≥ 0) leaves unchanged. Kinetic energy never rises (for
0 ≤ e_n, e_t ≤ 1 and μ ≥ 0), and both impulses act at the contact point, so the angular momentum about it,
I·ω + m·(R·n) × v, is conserved by every impact.

Scalar cores on (3,) rows and a (5,) surface vector (e_n, e_t, μ, R, α in the slots :data:`RESTITUTION` …
:data:`INERTIA_FACTOR`), compiled by numba like the flight (:mod:`kernels._jit`); :func:`impacts` runs a batch
through the single :func:`impact`. The public, checked function is :func:`kernels.ball.bounce`.
"""

from __future__ import annotations

import math

from kernels._jit import compiled

# The surface and ball of an impact are one (5,) vector; these are its slots.
RESTITUTION, TANGENTIAL_RESTITUTION, FRICTION, RADIUS, INERTIA_FACTOR = range(5)
N_SURFACE = 5


@compiled()
def impact(velocity, spin, normal, surface, v_out, w_out):
    """One impact: the (3,) ``velocity`` (m/s) and ``spin`` (rad/s) after it, into the (3,) ``v_out`` and ``w_out``.

    ``normal`` is the surface's (3,) unit normal; ``surface`` holds e_n and e_t (0–1), μ (≥ 0), R (m, > 0) and
    α = I/(m·R²) in the slots above, trusted (see the module's formulas and sources). Returns whether the ball struck
    the surface (v·n < 0).
    """
    vx, vy, vz = velocity[0], velocity[1], velocity[2]
    wx, wy, wz = spin[0], spin[1], spin[2]
    nx, ny, nz = normal[0], normal[1], normal[2]
    approach = vx * nx + vy * ny + vz * nz
    if approach >= 0.0:
        v_out[0], v_out[1], v_out[2] = vx, vy, vz
        w_out[0], w_out[1], w_out[2] = wx, wy, wz
        return False
    radius, alpha = surface[RADIUS], surface[INERTIA_FACTOR]
    jn = -(1.0 + surface[RESTITUTION]) * approach  # J_n/m > 0
    # u_t = v_t + ω × (−R·n) = v − (v·n)·n − R·(ω × n)
    ux = vx - approach * nx - radius * (wy * nz - wz * ny)
    uy = vy - approach * ny - radius * (wz * nx - wx * nz)
    uz = vz - approach * nz - radius * (wx * ny - wy * nx)
    grip = -(1.0 + surface[TANGENTIAL_RESTITUTION]) * alpha / (1.0 + alpha)
    jx, jy, jz = grip * ux, grip * uy, grip * uz  # J_t/m when the ball grips
    limit = surface[FRICTION] * jn
    # hypot, not the root of a sum of squares: those overflow from 1e154 m/s, and the slide lost its friction
    if math.hypot(math.hypot(jx, jy), jz) > limit:  # it slides: J_t = −μ·J_n·û_t
        # û_t first: −μ·J_n/|u_t| underflowed to 0 for a spin 10⁴⁰⁰ times the speed (no friction again)
        norm = math.hypot(math.hypot(ux, uy), uz)
        jx, jy, jz = -limit * (ux / norm), -limit * (uy / norm), -limit * (uz / norm)
    v_out[0], v_out[1], v_out[2] = vx + jn * nx + jx, vy + jn * ny + jy, vz + jn * nz + jz
    arm = 1.0 / (alpha * radius)  # ω' = ω − n × (J_t/m)/(α·R)
    w_out[0] = wx - (ny * jz - nz * jy) * arm
    w_out[1] = wy - (nz * jx - nx * jz) * arm
    w_out[2] = wz - (nx * jy - ny * jx) * arm
    return True


@compiled(from_python=True)
def impacts(velocities, spins, normal, surface, v_out, w_out):
    """:func:`impact` on each of the (K, 3) ``velocities`` and ``spins``, into the (K, 3) ``v_out`` and ``w_out``."""
    for k in range(len(velocities)):
        impact(velocities[k], spins[k], normal, surface, v_out[k], w_out[k])
