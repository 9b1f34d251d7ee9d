"""Ride a :class:`kernels.course.route.Course`: the speed integrated along it, the power that rides it in a given
time, and power paced with the grade.

Along each segment the rider's kinetic energy changes by the work of the pedals minus the resistances (the power
terms of :mod:`kernels.cycling`, the textbook terms or Martin et al. 1998's), integrated with an implicit midpoint step
on the segment's mean speed so the energy books balance exactly; pacing after Swain (1997, Med. Sci. Sports Exerc.
29:1104). Per-segment arrays are (N − 1,); SI units (m, s, kg, W). The model and its assumptions in full:
:mod:`kernels.course`. The loop is compiled with numba (``@njit(cache=True)``); :func:`warm_up` compiles it.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from kernels import _checks, cycling
from kernels._jit import compiled
from kernels.course.route import Course, course_from_xy
from kernels.warming import Entry

Model = Literal["textbook", "martin"]
AirKind = Literal["textbook", "weather"]
_MODELS: tuple[Model, ...] = ("textbook", "martin")
_AIR_KINDS: tuple[AirKind, ...] = ("textbook", "weather")


# --------------------------------------------------------------------------------------------- rider and air
@dataclasses.dataclass(frozen=True)
class Rider:
    """A rider and bike; the ``"martin"`` model adds spoke drag, wheel bearings and wheel inertia."""

    cda_m2: float = 0.32
    """Drag area (m², > 0)."""
    mass_kg: float = 80.0
    """Rider plus bike (kg, > 0)."""
    crr: float = 0.004
    """Rolling-resistance coefficient (≥ 0)."""
    drivetrain_efficiency: float = 0.976
    """Fraction of pedal power reaching the wheel, [0.001, 1]; Martin et al. 1998's 0.976."""
    model: Model = "martin"
    """``"textbook"``: aero, rolling, climbing; ``"martin"``: Martin et al. 1998's terms."""
    spoke_drag_m2: float = 0.0044
    """Martin's F_w (m², ≥ 0)."""
    wheel_inertia_kgm2: float = 0.14
    """Both wheels' moment of inertia (kg·m², ≥ 0)."""
    wheel_radius_m: float = 0.311
    """Tyre radius (m, > 0)."""

    def __post_init__(self) -> None:
        for key in ("cda_m2", "mass_kg", "wheel_radius_m"):
            _checks.positive(key, getattr(self, key))
        for key in ("crr", "spoke_drag_m2", "wheel_inertia_kgm2"):
            _checks.non_negative(key, getattr(self, key))
        # The forward model's ranges (cycling.MARTIN_DOMAIN): a mass of 1e308 kg overflowed the ride, and a tyre
        # radius of 1e-300 m raised ZeroDivisionError.
        for key in ("cda_m2", "mass_kg", "crr", "spoke_drag_m2", "wheel_inertia_kgm2", "wheel_radius_m"):
            low, high = cycling.MARTIN_DOMAIN[key]
            if not low <= getattr(self, key) <= high:
                raise ValueError(f"{key} must be in [{low:g}, {high:g}], got {_checks.shown(getattr(self, key))}")
        eta = self.drivetrain_efficiency
        if not 1e-3 <= _checks.finite_number("drivetrain_efficiency", eta) <= 1.0:
            raise ValueError(f"drivetrain_efficiency must be in [0.001, 1], got {_checks.shown(eta)}")
        _checks.choice("model", self.model, _MODELS)

    @property
    def effective_mass_kg(self) -> float:
        """m + I/r² under the Martin model (the wheels' spin stores energy too), m under the textbook model."""
        if self.model == "martin":
            return self.mass_kg + self.wheel_inertia_kgm2 / self.wheel_radius_m**2
        return self.mass_kg


@dataclasses.dataclass(frozen=True)
class Air:
    """Air along the route: the textbook exponential atmosphere, or a weather reading taken at one altitude.

    ``"weather"``: the reading (temperature, station pressure, humidity at ``altitude_m``) is carried along the
    route by the standard atmosphere: temperature falls 6.5 K/km, pressure follows the ISA ratio
    p_ISA(h)/p_ISA(h_ref), relative humidity stays. Density by :func:`kernels.cycling.air_density_weather`.
    """

    kind: AirKind = "textbook"
    """``"textbook"`` (the exponential atmosphere) or ``"weather"`` (the reading below)."""
    temperature_c: float = 15.0
    """Air temperature at ``altitude_m`` (°C, −60 to 60)."""
    pressure_hpa: float = 1013.25
    """Station pressure at ``altitude_m`` (hPa, 10 to 1100)."""
    relative_humidity: float = 0.0
    """Relative humidity, a fraction in [0, 1]."""
    altitude_m: float = 0.0
    """Where the reading was taken (m, −10 000 to 30 000, as a course's elevations; the standard atmosphere's pressure
    ratio that carries it is taken within −5000 to 20 000 m, :data:`kernels.cycling.ISA_ALTITUDE_M`)."""

    def __post_init__(self) -> None:
        _checks.choice("kind", self.kind, _AIR_KINDS)
        # One number each (an array broadcast against the route's elevations inside the ride).
        reading = [
            _checks.finite_number(key, getattr(self, key))
            for key in ("temperature_c", "pressure_hpa", "relative_humidity", "altitude_m")
        ]
        cycling.air_density_weather(*reading[:3])
        low, high = cycling.AIR_DENSITY_ALTITUDE_M  # every course's range; the ratio below clamps to the ISA's
        if not low <= reading[3] <= high:
            raise ValueError(f"altitude_m must be in [{low:g}, {high:g}] m, got {_checks.shown(self.altitude_m)}")

    def density(self, elevation_m: ArrayLike) -> NDArray[np.float64]:
        """Air density (kg/m³) at each elevation (m, −10 000 to 30 000, :data:`kernels.cycling.AIR_DENSITY_ALTITUDE_M`,
        which holds every course's; any shape). A weather reading is carried by the standard atmosphere's pressure
        ratio within its range, −5000 to 20 000 m (an elevation beyond takes the ratio at the range's end), and held
        within −60…60 °C and 10…1100 hPa."""
        h = _checks.finite_array("elevation_m", elevation_m)
        low, high = cycling.AIR_DENSITY_ALTITUDE_M
        if np.any((h < low) | (h > high)):
            raise ValueError(f"elevation_m must be in [{low:g}, {high:g}] m, got {_checks.shown(h)}")
        match self.kind:
            case "textbook":
                return cycling.air_density(h)
            case "weather":
                temperature = self.temperature_c - cycling.ISA_LAPSE_RATE_K_PER_M * (h - self.altitude_m)
                isa_h = np.clip(h, *cycling.ISA_ALTITUDE_M)
                pressure = (
                    self.pressure_hpa
                    * cycling.isa_pressure_hpa(isa_h)
                    / cycling.isa_pressure_hpa(np.clip(self.altitude_m, *cycling.ISA_ALTITUDE_M))
                )
                return cycling.air_density_weather(
                    np.clip(temperature, -60.0, 60.0), np.clip(pressure, 10.0, 1100.0), self.relative_humidity
                )


# --------------------------------------------------------------------------------------------- ride
@dataclasses.dataclass(frozen=True)
class Ride:
    """One ride of a course; per-point arrays (N,), per-segment (N − 1,), energies in joules."""

    time_s: float
    """Finish time (s)."""
    distance_m: NDArray[np.float64]
    """(N,) distance along the ground at each point (m): the course's."""
    speed_ms: NDArray[np.float64]
    """(N,) speed at each point (m/s); 0 at the start from rest."""
    power_w: NDArray[np.float64]
    """(N,) pedal power on the segment that starts at each point, time-averaged over it (W); the last point
    repeats the last segment's. Below the asked power where the rider eases off to hold the speed cap."""
    elapsed_s: NDArray[np.float64]
    """(N,) time since the start at each point (s)."""
    headwind_ms: NDArray[np.float64]
    """(N − 1,) headwind component on each segment (m/s, negative for a tailwind)."""
    air_density: NDArray[np.float64]
    """(N − 1,) air density on each segment (kg/m³)."""
    work_j: float
    """Energy the rider put into the pedals (J)."""
    drivetrain_j: float
    """Lost in the drivetrain (J)."""
    aero_j: float
    rolling_j: float
    bearings_j: float
    climbing_j: float
    """Net potential energy gained, m·g·(z_end − z_start) (J)."""
    kinetic_j: float
    """Kinetic energy at the finish, ½·M·v² (J) (the start is from rest unless asked)."""
    brakes_j: float
    """Taken by the brakes to hold the speed cap (J)."""
    brakes_w: NDArray[np.float64]
    """(N − 1,) power the brakes take on each segment to hold the speed cap, time-averaged over it (W at the wheel;
    0 where the rider does not brake). Over the ride it sums to :attr:`brakes_j`."""

    @property
    def average_speed_ms(self) -> float:
        return float(self.distance_m[-1]) / self.time_s

    @property
    def average_power_w(self) -> float:
        """Time-averaged pedal power (W), what a power meter shows for the ride."""
        return self.work_j / self.time_s

    def splits(self, every_m: float = 1000.0) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(marks, elapsed): the elapsed time (s) at every ``every_m`` metres and at the finish."""
        every = _checks.positive("every_m", every_m)
        total = float(self.distance_m[-1])
        if total / every > 10_000:  # before numpy is asked for the marks (10²⁹⁹ of them at 1e-300 m)
            raise ValueError(f"every_m must give at most 10 000 splits, got {_checks.shown(every_m)} over {total:g} m")
        marks = np.arange(every, total, every)
        marks = np.concatenate((marks, [total]))
        return marks, np.interp(marks, self.distance_m, self.elapsed_s)


_E_WORK, _E_AERO, _E_ROLL, _E_BEAR, _E_CLIMB, _E_BRAKE = range(6)
_REFINE_RATIO = 0.1
"""A step that changes the speed by more than this fraction is redone in halves (up to _REFINE_UP_TO)."""
_REFINE_UP_TO = 64
_SETTLE_TOLERANCE = 1e-3
"""Largest error a step's gain may put on its end speed, as a fraction of the speed. Near a steady speed the midpoint
step's gain dv₁/dv₀ is A = (1 − x/2)/(1 + x/2), x = λh for relaxation rate λ (1/m) and step h, where the true gain is
e^(−x): on a step much longer than 1/λ, A falls to −1 and the speed rings about the steady one, never settling. The
step moves the speed by (A − 1)·d for a distance d from the steady speed, so it misses
by |A − e^(−x)|·|v₁ − v₀|/|1 − A|; a step that misses by more is redone in halves."""
_SETTLE_UP_TO = 4096
"""At most this many sub-steps to settle a segment (a 100 km segment, relaxing over about 130 m, takes about 800)."""
_GRADED_BELOW = 0.01
"""A segment entered at a speed whose cube is below this fraction of 3ηP·L/M (the cube of the speed the pedals alone
would reach over it from rest) starts as from rest, on cubically graded sub-steps (uniform ones from 0.5 m/s rode a
flat kilometre 0.24 s slow)."""


@compiled()
def _wheel_power(v, drag, rolling, climbing, wind, b0, b1):  # pragma: no cover - compiled
    """P_wheel(v) (W): the sum of :func:`kernels.cycling.wheel_power_terms`, the one power law, compiled."""
    aero, roll, bearings, climb = cycling.wheel_power_terms_compiled(v, drag, rolling, climbing, wind, b0, b1)
    return aero + roll + bearings + climb


@compiled()
def _slope(x, v0, length, drag, rolling, climbing, wind, mass, b0, b1):  # pragma: no cover - compiled
    """d/dv̄ of the step's equation 2M(v̄ − v0)v̄² + L·(P_wheel(v̄) − P_in) at v̄ = ``x``."""
    air = x + wind
    wheel = drag * (2.0 * abs(air) * x + air * abs(air)) + rolling + climbing + b0 + 2.0 * b1 * x
    return 2.0 * mass * (3.0 * x * x - 2.0 * v0 * x) + length * wheel


@compiled()
def _settle_miss(gain):  # pragma: no cover - compiled
    """|A − e^(−x)|/|1 − A| for a step's gain A = dv₁/dv₀ = (1 − x/2)/(1 + x/2): what the step misses the true
    settling by, per unit of its move |v₁ − v₀| (:data:`_SETTLE_TOLERANCE`); infinite where A ≤ −1."""
    if gain <= -1.0:
        return math.inf
    if gain == 1.0:
        return 0.0
    return abs(gain - math.exp(-2.0 * (1.0 - gain) / (1.0 + gain))) / abs(1.0 - gain)


@compiled()
def _step(v0, length, drag, rolling, climbing, wind, power_in, mass, b0, b1):  # pragma: no cover
    """Mean speed v̄ ≥ v0/2 solving 2M(v̄ − v0)v̄² + L·(P_wheel(v̄) − P_in) = 0; −1 when none exists."""
    lo = 0.5 * v0
    q_lo = 2.0 * mass * (lo - v0) * lo * lo + length * (
        _wheel_power(lo, drag, rolling, climbing, wind, b0, b1) - power_in
    )
    if q_lo > 0.0:
        return -1.0
    if q_lo == 0.0 and lo > 0.0:
        return lo
    # Newton from v̄ = v0 (the answer for a short step), inside a bracket [lo, hi] that bisection falls back on.
    x = v0 if v0 > lo else 1.0
    q_x = 2.0 * mass * (x - v0) * x * x + length * (_wheel_power(x, drag, rolling, climbing, wind, b0, b1) - power_in)
    if q_x > 0.0:
        hi = x
    else:
        lo = x
        hi = 1.25 * x + 0.5
        for _ in range(80):
            q_hi = 2.0 * mass * (hi - v0) * hi * hi + length * (
                _wheel_power(hi, drag, rolling, climbing, wind, b0, b1) - power_in
            )
            if q_hi > 0.0:
                break
            lo = hi
            hi *= 2.0
    for _ in range(100):
        q = 2.0 * mass * (x - v0) * x * x + length * (_wheel_power(x, drag, rolling, climbing, wind, b0, b1) - power_in)
        if q <= 0.0:
            lo = x
        else:
            hi = x
        dq = _slope(x, v0, length, drag, rolling, climbing, wind, mass, b0, b1)
        step_ok = dq > 0.0
        nxt = x - q / dq if step_ok else 0.5 * (lo + hi)
        if not (lo < nxt < hi):
            nxt = 0.5 * (lo + hi)
        if abs(nxt - x) <= 1e-13 * (1.0 + x) or hi - lo <= 1e-13 * (1.0 + hi):
            return nxt
        x = nxt
    return x


@compiled(from_python=True)
def _ride_core(
    length,
    drag,
    rolling,
    climbing,
    wind,
    power_w,
    efficiency,
    mass,
    b0,
    b1,
    v_cap,
    v_start,
    speed,
    elapsed,
    power_out,
    brake_out,
    energy,
):  # pragma: no cover - compiled
    """Integrate every segment; fills speed/elapsed (N,), power_out and brake_out (N − 1,) and energy (6,). Returns 0
    or the 1-based index of a segment that could not be crossed."""
    v0 = v_start
    t = 0.0
    speed[0] = v0
    elapsed[0] = 0.0
    for i in range(length.shape[0]):
        # From rest v grows as s^(1/3) (v³ = 3ηP·s/M): cubically graded sub-steps follow it, and from nearly rest.
        graded = v0 * v0 * v0 < _GRADED_BELOW * 3.0 * efficiency * power_w[i] * length[i] / mass or v0 == 0.0
        n_sub = 64 if graded else 1
        while True:
            ok = True
            v = v0
            dt_total = 0.0
            work = 0.0
            aero = 0.0
            roll = 0.0
            bear = 0.0
            brake = 0.0
            for k in range(n_sub):
                if graded:
                    sub = length[i] * ((k + 1.0) ** 3 - k**3) / n_sub**3
                else:
                    sub = length[i] / n_sub
                p_in = efficiency * power_w[i]
                vb = _step(v, sub, drag[i], rolling[i], climbing[i], wind[i], p_in, mass, b0, b1)
                if vb <= 0.0:
                    ok = False
                    break
                v1 = 2.0 * vb - v
                if not graded and n_sub < _REFINE_UP_TO and abs(v1 - v) > _REFINE_RATIO * max(v, v1):
                    ok = False  # an abrupt change of speed (a wall, a crest): finer steps, for accuracy
                    break
                if n_sub < _SETTLE_UP_TO and abs(v1 - v) > _SETTLE_TOLERANCE * max(v, v1):
                    slope = _slope(vb, v, sub, drag[i], rolling[i], climbing[i], wind[i], mass, b0, b1)
                    if _settle_miss(4.0 * mass * vb * vb / slope - 1.0) * abs(v1 - v) > _SETTLE_TOLERANCE * max(v, v1):
                        ok = False  # a step longer than the speed takes to settle rings about the steady speed
                        break
                reach, reach_in = sub, p_in  # ridden at mean speed vb, the rider's power reach_in
                hold, hold_in = 0.0, 0.0  # then at the cap, the rider's power hold_in
                if v1 > v_cap:
                    # The cap is reached within the step: at full power up to it, then held (the rider eases off, the
                    # brakes take the rest). The reach distance solves the step's own equation with v̄ = (v + cap)/2.
                    # Holding the cap only from the step's end (v̄ over the whole step) let more power ride slower.
                    v1 = v_cap
                    vb = 0.5 * (v + v1)
                    surplus = p_in - _wheel_power(vb, drag[i], rolling[i], climbing[i], wind[i], b0, b1)
                    need = _wheel_power(v_cap, drag[i], rolling[i], climbing[i], wind[i], b0, b1)
                    if surplus > 0.0 and need <= p_in:
                        reach = min(2.0 * mass * (vb - v) * vb * vb / surplus, sub)
                        hold, hold_in = sub - reach, max(need, 0.0)
                        brake += (hold_in - need) * (hold / v_cap)
                    else:
                        # The cap is above what this power can hold: the step's overshoot is the trapezoid's, not the
                        # rider's. The step arrives at the cap, the rider easing to what that takes (at most p_in).
                        need = (2.0 * mass * (vb - v) * vb * vb + sub * (p_in - surplus)) / sub
                        reach_in = min(max(need, 0.0), p_in)
                        brake += (reach_in - need) * sub / vb
                for distance, speed_here, rider_in in ((hold, v_cap, hold_in), (reach, vb, reach_in)):
                    if distance > 0.0:
                        dt = distance / speed_here
                        p_aero, p_roll, p_bear, _ = cycling.wheel_power_terms_compiled(
                            speed_here, drag[i], rolling[i], climbing[i], wind[i], b0, b1
                        )
                        dt_total += dt
                        work += rider_in / efficiency * dt
                        aero += p_aero * dt
                        roll += p_roll * dt
                        bear += p_bear * dt
                v = max(v1, 0.0)
            if ok:
                break
            n_sub *= 2
            if n_sub > 1 << 20:
                return i + 1
        energy[_E_WORK] += work
        energy[_E_AERO] += aero
        energy[_E_ROLL] += roll
        energy[_E_BEAR] += bear
        energy[_E_CLIMB] += climbing[i] * length[i]
        energy[_E_BRAKE] += brake
        t += dt_total
        v0 = v
        speed[i + 1] = v
        elapsed[i + 1] = t
        power_out[i] = work / dt_total
        brake_out[i] = brake / dt_total
    return 0


_MAX_SEARCH_RIDES = 100
"""Most rides :func:`power_for_time` tries; a bisection of log power over 1–5000 W halves its bracket at least
every other ride, to 10⁻¹³ of it in 90."""
MAX_POWER_W = 5000.0
"""Most pedal power a ride takes (W), per segment: twice a track sprinter's peak, and the ceiling
:func:`power_for_time` searches to. (At 10³⁰⁰ W the sub-steps that hold the speed cap took seconds.)"""
_MIN_POWER_W, _MAX_POWER_W = 1.0, MAX_POWER_W
_MAX_SPEED_MS = cycling.MODEL_DOMAIN["speed_ms"][1]
_MIN_CAP_MS = 0.1
"""Slowest safe speed a ride takes (m/s, 0.36 km/h, below walking pace): a cap of 1e-320 m/s rode a course in an
infinite time with NaN energies."""
_MAX_WIND_MS = cycling.MODEL_DOMAIN["headwind_ms"][1]
"""A ride's safe speed and wind stay within the power law's range (:data:`kernels.cycling.MODEL_DOMAIN`)."""


@dataclasses.dataclass(frozen=True)
class _Segments:
    """A course, rider, wind and air reduced to the per-segment coefficients the compiled loop needs."""

    length: NDArray[np.float64]
    drag: NDArray[np.float64]
    rolling: NDArray[np.float64]
    climbing: NDArray[np.float64]
    wind: NDArray[np.float64]
    density: NDArray[np.float64]
    efficiency: float
    mass: float
    b0: float
    b1: float


def _segments(course: Course, rider: Rider, wind_ms: float, wind_from_deg: float, air: Air) -> _Segments:
    _checks.instance("course", course, Course)
    _checks.instance("rider", rider, Rider)
    _checks.instance("air", air, Air, "an Air")
    wind = _checks.finite_number("wind_ms", wind_ms)
    if abs(wind) > _MAX_WIND_MS:
        raise ValueError(
            f"wind_ms must be in [-{_MAX_WIND_MS:g}, {_MAX_WIND_MS:g}] m/s (the model's range), "
            f"got {_checks.shown(wind_ms)}"
        )
    wind_from = math.radians(_checks.finite_number("wind_from_deg", wind_from_deg))
    rolling, climbing = cycling.road_forces(rider.mass_kg, rider.crr, course.grade)
    mid_elevation = 0.5 * (course.elevation_m[1:] + course.elevation_m[:-1])
    density = air.density(mid_elevation)
    drag_area = rider.cda_m2 + (rider.spoke_drag_m2 if rider.model == "martin" else 0.0)
    bearings = cycling.MARTIN_BEARING_W if rider.model == "martin" else (0.0, 0.0)
    return _Segments(
        length=np.ascontiguousarray(course.length_m),
        drag=0.5 * density * drag_area,
        rolling=rolling,
        climbing=climbing,
        wind=wind * np.cos(wind_from - course.heading_rad),
        density=density,
        efficiency=float(rider.drivetrain_efficiency),
        mass=rider.effective_mass_kg,
        b0=float(bearings[0]),
        b1=float(bearings[1]),
    )


def _segment_power(power_w: ArrayLike, n_segments: int) -> NDArray[np.float64]:
    # Special to a ride: one number for the whole course or one per segment, so not a kernels._checks shape.
    # True rode as 1 W, "250" as 250 W, a complex power lost its imaginary part.
    power = _checks.real_array("power_w", power_w, "a number or an array of numbers")
    scalar = power.ndim == 0
    if scalar:
        power = np.full(n_segments, float(power))
    if power.shape != (n_segments,):
        raise ValueError(f"power_w must be a number or shape ({n_segments},), got shape {power.shape}")
    if not np.all(np.isfinite(power)) or np.any(power <= 0.0):
        raise ValueError(f"power_w must be finite and > 0 (W), got {_shown_power(power_w, power, scalar)}")
    if np.any(power > MAX_POWER_W):
        raise ValueError(f"power_w must be at most {MAX_POWER_W:g} W, got {_shown_power(power_w, power, scalar)}")
    return np.ascontiguousarray(power)


def _shown_power(power_w: ArrayLike, power: NDArray[np.float64], scalar: bool) -> str:
    """A refused power as given (one number) or in brief (one per segment)."""
    return repr(power_w) if scalar else _checks.shown(power)


def _ride(course: Course, power: NDArray[np.float64], s: _Segments, max_speed: float, start: float) -> Ride:
    n = course.n_points
    speed, elapsed = np.empty(n), np.empty(n)
    power_out, brake_out, energy = np.empty(n - 1), np.empty(n - 1), np.zeros(6)
    failed = _ride_core_entry(
        s.length,
        s.drag,
        s.rolling,
        s.climbing,
        s.wind,
        power,
        s.efficiency,
        s.mass,
        s.b0,
        s.b1,
        max_speed,
        start,
        speed,
        elapsed,
        power_out,
        brake_out,
        energy,
    )
    if failed:
        raise ValueError(
            f"power_w is too low: at this power the rider cannot cross segment {failed - 1} (its grade and headwind)"
        )
    work = float(energy[_E_WORK])
    return Ride(
        time_s=float(elapsed[-1]),
        distance_m=course.distance_m,
        speed_ms=speed,
        power_w=np.concatenate((power_out, power_out[-1:])),
        elapsed_s=elapsed,
        headwind_ms=s.wind,
        air_density=s.density,
        work_j=work,
        drivetrain_j=work * (1.0 - s.efficiency),
        aero_j=float(energy[_E_AERO]),
        rolling_j=float(energy[_E_ROLL]),
        bearings_j=float(energy[_E_BEAR]),
        climbing_j=float(energy[_E_CLIMB]),
        kinetic_j=0.5 * s.mass * float(speed[-1]) ** 2,
        brakes_j=float(energy[_E_BRAKE]),
        brakes_w=brake_out,
    )


def _speeds(max_speed_ms: float, start_speed_ms: float) -> tuple[float, float]:
    cap = _checks.positive("max_speed_ms", max_speed_ms)
    if not _MIN_CAP_MS <= cap <= _MAX_SPEED_MS:
        raise ValueError(
            f"max_speed_ms must be in [{_MIN_CAP_MS:g}, {_MAX_SPEED_MS:g}] m/s (the model's range), "
            f"got {_checks.shown(max_speed_ms)}"
        )
    start = _checks.finite_number("start_speed_ms", start_speed_ms)
    if start < 0.0 or start > cap:
        raise ValueError(f"start_speed_ms must be in [0, max_speed_ms], got {_checks.shown(start_speed_ms)}")
    return cap, start


def ride(
    course: Course,
    power_w: ArrayLike,
    rider: Rider = Rider(),
    wind_ms: float = 0.0,
    wind_from_deg: float = 0.0,
    air: Air = Air(),
    max_speed_ms: float = 20.0,
    start_speed_ms: float = 0.0,
) -> Ride:
    """Ride ``course`` at ``power_w``, integrating speed with kinetic energy (see the module docstring).

    Args:
        course: the route.
        power_w: pedal power (W, in (0, :data:`MAX_POWER_W`], 5000 W): one number, or (N − 1,) one per segment.
        rider: rider, bike and model.
        wind_ms: wind speed (m/s, at most 1000 either way; negative reverses it).
        wind_from_deg: where the wind blows from, clockwise from north (°): 0 is a north wind.
        air: air density along the route.
        max_speed_ms: safe descending speed (m/s, in [0.1, 10⁸]; 20 m/s = 72 km/h); the rider brakes to hold it.
        start_speed_ms: speed at the start (m/s, 0 = from rest).

    Returns:
        :class:`Ride`.

    Raises:
        ValueError: an argument is invalid (the message names it).
    """
    s = _segments(course, rider, wind_ms, wind_from_deg, air)
    cap, start = _speeds(max_speed_ms, start_speed_ms)
    return _ride(course, _segment_power(power_w, course.n_points - 1), s, cap, start)


def power_for_time(
    course: Course,
    time_s: float,
    rider: Rider = Rider(),
    wind_ms: float = 0.0,
    wind_from_deg: float = 0.0,
    air: Air = Air(),
    max_speed_ms: float = 20.0,
    start_speed_ms: float = 0.0,
    tolerance_s: float = 0.01,
    gain: float = 0.0,
) -> float:
    """The constant pedal power that rides ``course`` in ``time_s``: the inverse of :func:`ride`; with a ``gain``,
    the time-averaged power of the ride paced by grade that does (the inverse of :func:`paced_ride`).

    The finish time falls strictly as power rises, so the root is unique; it is found by a safeguarded secant
    method on log(time) against log(power) (close to a straight line: P ∝ v³ on the flat, ∝ v on a climb),
    between 1 W and 5000 W; typically 4–6 rides (each a few rides when paced).

    Args:
        time_s: target finish time (s, > 0).
        tolerance_s: how close the ride's time must come (s, > 0).
        gain: pacing by grade, as for :func:`paced_ride` (0 to 0.5; 0, the default, rides at constant power).
        Other arguments as for :func:`ride`.

    Returns:
        Power (W).

    Raises:
        ValueError: an argument is invalid, or the time is out of reach (faster than 5000 W rides it, faster than
            the course's distance at ``max_speed_ms`` all the way, or slower than 1 W); the message says which.
    """
    target = _checks.positive("time_s", time_s)
    tol = _checks.positive("tolerance_s", tolerance_s)
    g = _gain(gain)
    s = _segments(course, rider, wind_ms, wind_from_deg, air)
    cap, start = _speeds(max_speed_ms, start_speed_ms)
    n = course.n_points - 1

    def time_at(power: float) -> float:
        if g == 0.0:
            return _ride(course, np.full(n, power), s, cap, start).time_s
        try:
            return _paced(course, power, g, s, cap, start).paced.time_s
        except ValueError as error:  # said of the time asked for, not of a power the search tried
            raise ValueError(f"time_s {target:.6g} s is out of reach paced by grade (gain {g:g}): {error}") from error

    lo_p, hi_p = _MIN_POWER_W, _MAX_POWER_W
    # Secant steps on f(x) = log t(eᵡ) − log target (x = log P), which is close to a straight line of slope
    # −1/3 (flat) to −1 (climb). Start from 250 W and a slope of −1/2; once the root is bracketed every step stays
    # inside the bracket: a secant step, or a bisection when it would leave the bracket or when the same end moved
    # twice running. The safe-speed cap kinks the curve, and plain false position crawled along the kink (on the
    # sample climb at 12 m/s, 60 steps ended 5 s off the target, and that power was returned).
    x_lo, f_lo, x_hi, f_hi = -math.inf, math.inf, math.inf, -math.inf
    x, slope = math.log(250.0), -0.5
    x_prev, f_prev = math.nan, math.nan
    moved = ""
    for _ in range(_MAX_SEARCH_RIDES):
        power = min(max(math.exp(x), lo_p), hi_p)  # exp(log(5000)) is 5000.000000000004, which a ride refuses
        t = time_at(power)
        if abs(t - target) <= tol:
            return power
        f = math.log(t / target)
        end = "lo" if f > 0.0 else "hi"
        again, moved = end == moved, end
        if f > 0.0:
            x_lo, f_lo = x, f
        else:
            x_hi, f_hi = x, f
        if math.isfinite(x_lo) and math.isfinite(x_hi):
            nxt = x_lo - f_lo * (x_hi - x_lo) / (f_hi - f_lo)
            if not (x_lo < nxt < x_hi) or x_hi - x_lo < 1e-12 or again:
                nxt = 0.5 * (x_lo + x_hi)
        else:
            if math.isfinite(x_prev) and x_prev != x and (f - f_prev) / (x - x_prev) < 0.0:
                slope = (f - f_prev) / (x - x_prev)
            nxt = x - f / slope
            if nxt > math.log(hi_p):
                if x >= math.log(hi_p) or time_at(hi_p) > target + tol:
                    raise ValueError(_too_fast(target, course, cap, hi_p))
                nxt = math.log(hi_p)
            elif nxt < math.log(lo_p):
                if x <= math.log(lo_p) or time_at(lo_p) < target - tol:
                    raise ValueError(f"time_s {target:.6g} s is out of reach: even {lo_p:.0f} W rides it faster")
                nxt = math.log(lo_p)
        x_prev, f_prev = x, f
        x = nxt
    raise ValueError(
        f"time_s {target:.6g} s was not reached within tolerance_s = {tol:g} s in {_MAX_SEARCH_RIDES} rides "
        f"(closest: {math.exp(x_lo):.6g} W rides slower, {math.exp(x_hi):.6g} W faster)"
    )


def fastest_time_s(course: Course, max_speed_ms: float) -> float:
    """The bound no power beats: ``course`` ridden at the safe speed all the way, Σ length_m / max_speed_ms (s; the
    length along the slope, which the rider covers, not the map's).

    Raises:
        ValueError: ``max_speed_ms`` not a number in the ride's range (as for :func:`ride`).
    """
    cap, _ = _speeds(max_speed_ms, 0.0)
    return float(np.sum(_checks.instance("course", course, Course).length_m)) / cap


def _too_fast(time_s: float, course: Course, max_speed_ms: float, power_w: float) -> str:
    """Why ``time_s`` is beyond ``power_w``: the safe speed where no power rides the course that fast
    (:func:`fastest_time_s`), else the power."""
    floor_s = fastest_time_s(course, max_speed_ms)
    if time_s <= floor_s:
        ridden_km = floor_s * max_speed_ms / 1000.0
        return (
            f"time_s {time_s:.6g} s is out of reach: held to the safe speed max_speed_ms = {max_speed_ms:g} m/s, "
            f"no power rides the {ridden_km:.4g} km in under {floor_s:.6g} s"
        )
    return f"time_s {time_s:.6g} s is out of reach: it needs more than {power_w:.0f} W"


@dataclasses.dataclass(frozen=True)
class Pacing:
    """A paced ride next to the constant-power ride at the same time-averaged power."""

    constant: Ride
    paced: Ride
    time_saved_s: float
    """constant.time_s − paced.time_s (s); positive when pacing is faster."""


def _gain(gain: object) -> float:
    g = _checks.finite_number("gain", gain)
    if not 0.0 <= g <= 0.5:
        raise ValueError(f"gain must be in [0, 0.5], got {_checks.shown(gain)}")
    return g


def pacing_factors(grade: ArrayLike, gain: float) -> NDArray[np.float64]:
    """Relative power per segment: 1 + gain·tanh(grade / 0.05), more uphill, less downhill (unnormalised).

    Args:
        grade: rise over run of each segment, any shape (finite).
        gain: how strongly power follows the grade (0 to 0.5, as for :func:`paced_ride`).

    Returns:
        Factors in [1 − gain, 1 + gain], the shape of ``grade``.

    Raises:
        ValueError: ``grade`` not finite real numbers, or ``gain`` not a number in [0, 0.5]; the message names it.
    """
    slope = _checks.finite_array("grade", grade)
    return 1.0 + _gain(gain) * np.tanh(slope / 0.05)


def paced_ride(
    course: Course,
    power_w: float,
    rider: Rider = Rider(),
    gain: float = 0.15,
    wind_ms: float = 0.0,
    wind_from_deg: float = 0.0,
    air: Air = Air(),
    max_speed_ms: float = 20.0,
    start_speed_ms: float = 0.0,
) -> Pacing:
    """Vary power with the grade (Swain 1997) at the same time-averaged power as a constant ``power_w``.

    Segment i gets P_i = min(k·(1 + gain·tanh(grade_i / 0.05)), :data:`MAX_POWER_W`): up to ``gain`` more on steep
    climbs and less on descents, and k is set (a few fixed-point rescalings) so that the paced ride's time-averaged
    power
    Σ P_i·t_i / Σ t_i equals the constant ride's (what a power meter would show for both rides; that is
    ``power_w`` unless the constant ride eased off to hold the speed cap).

    Args:
        power_w: the constant ride's power and the paced ride's time-averaged power (W, in (0, 5000]).
        gain: how strongly power follows the grade (0 to 0.5; 0 is constant power).
        Other arguments as for :func:`ride`.

    Returns:
        :class:`Pacing` with both rides and the time saved.

    Raises:
        ValueError: an argument is invalid (the message names it).
    """
    target = _checks.positive("power_w", power_w)
    if target > MAX_POWER_W:
        raise ValueError(f"power_w must be at most {MAX_POWER_W:g} W, got {_checks.shown(power_w)}")
    g = _gain(gain)
    s = _segments(course, rider, wind_ms, wind_from_deg, air)
    cap, start = _speeds(max_speed_ms, start_speed_ms)
    return _paced(course, target, g, s, cap, start)


def _paced(course: Course, target: float, g: float, s: _Segments, cap: float, start: float) -> Pacing:
    """:func:`paced_ride` of checked arguments: ``target`` (W), ``g`` the gain, ``s`` the course's segments."""
    n = course.n_points - 1
    constant = _ride(course, np.full(n, target), s, cap, start)
    shape = pacing_factors(course.grade, g)
    # Match what the constant ride really averaged: where it eases off to hold the speed cap it is below target.
    average = constant.average_power_w

    def paced_at(scale: float) -> Ride:
        return _ride(course, np.minimum(scale * shape, MAX_POWER_W), s, cap, start)

    # Rescale to the constant ride's average; where that does not settle (segments held at MAX_POWER_W, or easing
    # off at the speed cap), bisect between the scales tried that gave less and more.
    scale, tried = target, []
    for _ in range(_PACING_STEPS):
        paced = paced_at(scale)
        if abs(paced.average_power_w / average - 1.0) < _PACING_TOLERANCE:
            return Pacing(constant=constant, paced=paced, time_saved_s=constant.time_s - paced.time_s)
        tried.append((scale, paced.average_power_w))
        scale *= average / paced.average_power_w
    low = max((sc for sc, got in tried if got < average), default=None)
    high = min((sc for sc, got in tried if got > average), default=None)
    for _ in range(_PACING_STEPS):  # widen to a bracket: halve below the least scale tried, double above the most
        if low is not None and high is not None:
            break
        probe = 0.5 * min(sc for sc, _got in tried) if low is None else 2.0 * max(sc for sc, _got in tried)
        try:
            got = paced_at(probe).average_power_w
        except ValueError:  # too little power to cross a segment: below any average
            got = 0.0
        tried.append((probe, got))
        if got < average:
            low = probe if low is None else max(low, probe)
        elif got > average:
            high = probe if high is None else min(high, probe)
    if low is not None and high is not None and low < high:
        for _ in range(_PACING_STEPS):
            scale = 0.5 * (low + high)
            paced = paced_at(scale)
            if abs(paced.average_power_w / average - 1.0) < _PACING_TOLERANCE:
                return Pacing(constant=constant, paced=paced, time_saved_s=constant.time_s - paced.time_s)
            low, high = (scale, high) if paced.average_power_w < average else (low, scale)
    raise ValueError(
        f"power_w = {target:.6g} W cannot be paced with gain {g:g}: held at most {MAX_POWER_W:g} W on "
        f"each segment and eased off at the speed cap, the paced ride does not average the constant ride's "
        f"{average:.1f} W; a lower power or gain paces"
    )


_PACING_STEPS = 60
"""Fixed-point rescalings :func:`paced_ride` tries before it says the power cannot be paced."""
_PACING_TOLERANCE = 1e-9
"""Relative difference of the two rides' time-averaged powers at which :func:`paced_ride` stops."""


# The compiled ride loop as _ride calls it: plain Python while the app's first start compiles it (kernels.warming).
_ride_core_entry = Entry(_ride_core)


def warm_up() -> None:
    """Compile (or load from numba's cache) the ride loop now, so the first real ride is fast."""
    course = course_from_xy([0.0, 10.0, 20.0], [0.0, 0.0, 0.0], [0.0, 0.5, 0.0])
    ride(course, 200.0)
