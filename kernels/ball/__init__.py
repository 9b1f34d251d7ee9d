"""Flight of a spinning football: drag, Magnus lift, gravity and the knuckleball's unsteady side force.

Frame and units: world frame with x from the ball toward the goal, y to the left, z up; SI throughout (m, s, kg,
rad/s). A position is the ball's centre, (3,) or (N, 3); spin ω is the angular-velocity vector in rad/s.

Model (per unit mass, A = π r², v̂ = v/|v|, ω̂ = ω/|ω|, zero when ω = 0)::

    F_drag   = −½·ρ·A·C_D·|v|·v
    F_Magnus = ½·ρ·A·C_L·|v|·(ω̂ × v)
    F_grav   = (0, 0, −m·g)

The Magnus force is sometimes written C_L·ρ·π·r²·|v×ω|/|ω|, which has units of kg/s, not newtons; the form above
keeps its direction (ω × v) and its sin-angle factor and gives the often-quoted "3–5 m sideways over 25 m" (about
4.4 m at C_L = 0.25). Two coefficient models:

* ``"constant"``: C_D and C_L as given (defaults 0.25 and 0.25). The curl radius is then fixed at 2m/(ρ·A·C_L)
  ≈ 73.9 m whatever the spin rate, so spin changes nothing but the direction of the curl.
* ``"measured"``: coefficients from published fits, so the spin rate matters. With S = r·|ω|/max(|v|, 1 m/s) the spin
  parameter and Re = ρ·max(|v|, 1 m/s)·2r/μ (μ = 1.81·10⁻⁵ Pa·s), so that below 1 m/s the coefficients are held at
  their 1 m/s values (a ball at rest has a finite S; the force, ∝ C·|v|², still vanishes with the speed):

      C_L(S) = 0.9·min(S, 0.3)
          A linear law capped at S = 0.3 (0.27 beyond). It lies below the measurements: 0.16 at S = 0.18 and 0.20 at
          S = 0.22, where Asai et al. 2007 (Sports Eng. 10:101, wind tunnel) measured 0.21 and 0.24 (0.29 at
          S = 0.34), and Bray & Kerwin 2003 (J. Sports Sci. 21:75) fitted 0.23–0.29 to real free kicks. A saturating
          C_L = 0.32·(1 − e^(−S/0.17)) follows Asai within 0.015; it is not adopted here, so flights stay as they
          were, and the curl is therefore somewhat understated.
      C_D(Re, S) = C_D0(Re) + min(S/0.05, 1)·(C_Ds(max(S, 0.05)) − C_D0(Re))
      C_D0(Re)   = 0.155 + 0.346 / (1 + exp((Re − 1.815·10⁵) / 1.949·10⁴))
      C_Ds(S)    = 0.4127·S^0.3056
          Goff & Carré 2010 (Eur. J. Phys. 31): the non-spinning fit 0.155 + 0.346/(1 + exp((v − 12.19)/1.309)) to
          the Teamgeist, re-expressed in Re for a 0.22 m ball in air of 1.225 kg/m³, is centred at Re = 1.815·10⁵
          (12.2 m/s); the centre is :attr:`FlightConfig.drag_crisis_re` (other balls cross elsewhere:
          :data:`DRAG_CRISIS_RE_BY_BALL`). The spinning fit (S > 0.05) is theirs too. Between S = 0 and 0.05 the two
          are blended linearly so C_D is continuous.

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
rigid. Without a pitch the flight stops at the first touch of the ground and a ball that touches the wall or the
frame does not rebound; with a :class:`Pitch` (``simulate(..., pitch=...)``) it bounces, rolls and strikes the posts,
bar, wall and keeper (:mod:`kernels.ball.play`). Integrators: ``"euler"`` is the fixed-step method of most web
demos (v += a·dt, then x += v·dt; first order), ``"rk4"`` the classical fourth-order Runge–Kutta. The last sample of a
flight is placed on the ground (or on the ``x_stop`` plane) by cubic Hermite interpolation of the last step, which keeps
RK4's accuracy: the first root of that cubic in the step, bracketed between its turning points (a ball may rise, peak
and land within one long step). Wall and goal crossings are found the same way. Every step is ``dt`` but the last, which
is shortened to end exactly on ``t_max``. Planes are closed on the start side: a ball launched on the ``x_stop``, wall
or goal plane and moving through it crosses at t = 0; one launched on the ground (``z = ground_m``) and not moving up
lands at t = 0; one launched below it is refused. The measured model refuses a launch spin parameter
r·|ω|/max(|v|, 1 m/s) above 10³ (its fits stop at S ≈ 0.3; 10³ is ~2·10⁵ rev/s at 25 m/s) with a ``ValueError`` naming
the spin; :func:`coefficients` refuses the same inputs by the same check (:func:`kernels.ball.config.refuse_fast_spin`).

Implementation: every numeric core (force law, Euler and RK4 steps, the Hermite end of a flight, plane crossings and
the verdict) is written once, on scalars, and compiled by numba (``@njit(cache=True)``). One kick and a batch run the
same compiled flight; a batch runs its kicks in parallel (ranges of kicks on :func:`numba.get_num_threads` threads,
the compiled loop without the GIL). The Python functions around them only validate (``ValueError`` naming the
argument) and package arrays. Compiled code is cached in ``__pycache__`` beside each module, or, where that is
read-only (an installed package), in numba's user-wide cache (``~/.cache/numba``; ``NUMBA_CACHE_DIR`` overrides
both; with neither writable, no disk cache). :func:`warm_up` compiles (or loads) every core.

Step bound for accuracy: ``dt`` is at most :data:`~kernels.ball.config.MAX_DT_S` = 0.1 s (``ValueError`` naming
``dt``, from :class:`FlightConfig`, which every entry builds). Measured over 3,768 kicks across the free-kick scene's
controls (5–40 m/s, −5–50°, 0–15 rev/s about any axis, both models): RK4's landing point lies at most 5 mm from a
0.1 ms reference at 0.1 s (p99 1.3 mm), and first strays past 1 cm at 0.11 s (13 mm; 16 mm at 0.15 s, 63 mm at
0.2 s). RK4 in a vacuum, exact for the parabola, takes any step. A pitch allows at most 0.05 s (its contacts).

Step limit: a kick whose ``dt`` is beyond the method's stability limit for its drag is refused before it flies, with a
``ValueError`` naming ``dt`` and the limit (:func:`kernels.ball.aero.max_stable_step`). Drag alone on a ball at speed
|v| has velocity-Jacobian eigenvalues −k|v| and −2k|v| (k = ½ρA·C_D/m); forward Euler is stable for λ·dt in [−2, 0]
and classical RK4 in [−2.7853, 0] (Hairer & Wanner, Solving ODEs II, §IV.2), so dt ≤ β/(2k|v|), which for Euler is
k|v|·dt ≤ 1: a step never reverses the velocity. The lift and knuckle factors are added to k, and |v| is the fastest
the ball can fly (its launch speed, or the terminal speed, or the speed a fall from its height gives: whichever
bound is least). On a pitch a bounce can turn the spin's energy into speed and spin up a ball launched without
spin, so there |v| adds 2·√(α·R²)·|ω₀| in quadrature and the lift counts whatever the launch spin; the refusal then
names the spin too. A flight whose steps still overshoot, so that |v|² + 2gz grows far past its launch value (or
overflows), also raises ``ValueError`` naming ``dt`` rather than returning an absurd path.

Modules: :mod:`~kernels.ball.config` (constants, :class:`FlightConfig`, input checks), :mod:`~kernels.ball.pitch` (goal
and wall panels), :mod:`~kernels.ball.aero` (the compiled force law), :mod:`~kernels.ball.core` (the compiled flight,
crossings and verdict), :mod:`~kernels.ball.api` (:func:`simulate`, the batch functions and their results),
:mod:`~kernels.ball.contact` (the compiled bounce), :mod:`~kernels.ball.laws` (:func:`coefficients` and
:func:`bounce`), :mod:`kernels._jit` (numba with or without its disk cache). Everything public is importable
from here.

Laws on their own: :func:`coefficients` gives the (C_D, C_L) above at any speed and spin rate, from the same compiled
function the flight's force law calls. :func:`bounce` gives a ball's velocity and spin after it strikes a surface,
by Cross's grip–slip impulse model (Cross 2002, Am. J. Phys. 70:1093; Mencke et al. 2020, Am. J. Phys. 88:934):
normal impulse −(1 + e_n)·m·(v·n); the contact point's tangential velocity u_t reversed to −e_t·u_t while the ball
grips, or a Coulomb friction impulse μ·J_n against it when that would need more; defaults e_n 0.6, μ 0.6, e_t 0.1
and I = ⅔·m·r² (a 2 m drop rebounds 0.72 m, inside FIFA Quality Pro's 0.60–0.85 m for turf). The flight on a
pitch calls the same compiled impact at every contact.

On a pitch (:mod:`kernels.ball.play`, :class:`Pitch`, :class:`Keeper`): the ball bounces on the turf (e_n 0.6,
μ 0.6 dry / 0.25 wet, e_t 0.1), rolls once a bounce leaves it under 0.5 m/s upward (rolling resistance 0.8 m/s² plus
the air's drag: FIFA's ball-roll band, 4–10 m from 3.2 m/s), strikes posts and bar (capsules of radius 0.06 m,
e_n 0.75, μ 0.3: assumed from FIFA's drop onto steel, see :data:`FRAME`), the wall's players (capsules, e_n 0.4,
a guess) and the keeper (saved on touch), and stops in the net. Odds of a real strike with a player's scatter:
:mod:`kernels.ball.odds`.
"""

from __future__ import annotations

from kernels.ball.api import (
    EVENT_KINDS,
    BatchOutcome,
    BatchTrajectory,
    Event,
    KeeperDive,
    KeeperPath,
    Outcome,
    Trajectory,
    keeper_path,
    launch_velocity,
    outcome,
    outcome_batch,
    simulate,
    simulate_batch,
    simulate_outcomes,
    spin_vector,
    warm_up,
)
from kernels.ball.config import (
    AIR_DENSITY,
    AIR_VISCOSITY,
    BALL_MASS_KG,
    BALL_RADIUS_M,
    DRAG_CRISIS_RE,
    DRAG_CRISIS_RE_BY_BALL,
    KNUCKLE_COEFFICIENT,
    KNUCKLE_SPIN_LIMIT,
    KNUCKLE_WAVELENGTH_M,
    FlightConfig,
    G,
    Method,
    Model,
)
from kernels.ball.core import Ending, Result
from kernels.ball.laws import bounce, coefficients
from kernels.ball.odds import Odds, StrikeSpread, odds_map, strike_odds
from kernels.ball.pitch import (
    BODY,
    DRY_TURF,
    FRAME,
    GOAL_HEIGHT_M,
    GOAL_WIDTH_M,
    WALL_DISTANCE_M,
    WET_TURF,
    Keeper,
    Panel,
    Pitch,
    Surface,
    free_kick_panels,
)

__all__ = [
    "AIR_DENSITY",
    "AIR_VISCOSITY",
    "BALL_MASS_KG",
    "BALL_RADIUS_M",
    "BODY",
    "DRAG_CRISIS_RE",
    "DRAG_CRISIS_RE_BY_BALL",
    "DRY_TURF",
    "EVENT_KINDS",
    "FRAME",
    "GOAL_HEIGHT_M",
    "GOAL_WIDTH_M",
    "KNUCKLE_COEFFICIENT",
    "KNUCKLE_SPIN_LIMIT",
    "KNUCKLE_WAVELENGTH_M",
    "WALL_DISTANCE_M",
    "WET_TURF",
    "BatchOutcome",
    "BatchTrajectory",
    "Ending",
    "Event",
    "FlightConfig",
    "G",
    "Keeper",
    "KeeperDive",
    "KeeperPath",
    "Method",
    "Model",
    "Odds",
    "Outcome",
    "Panel",
    "Pitch",
    "Result",
    "StrikeSpread",
    "Surface",
    "Trajectory",
    "bounce",
    "coefficients",
    "free_kick_panels",
    "keeper_path",
    "launch_velocity",
    "odds_map",
    "outcome",
    "outcome_batch",
    "simulate",
    "simulate_batch",
    "simulate_outcomes",
    "spin_vector",
    "strike_odds",
    "warm_up",
]
