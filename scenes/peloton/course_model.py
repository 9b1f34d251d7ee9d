"""The course mode's model: its parameters, a route ridden for them, and the route mapped into the scene.

:class:`CourseParams` is what the user sets in the mode (each field declares its GUI control, :mod:`scenes._controls`);
:func:`compute_course` rides a route for it and the line's :class:`~scenes.peloton.model.PelotonParams` into a
:class:`CourseState` through :mod:`kernels.course` (Martin et al. 1998). :class:`ChaseFrame`, :func:`road_strip`
and :func:`riders_on_road` lay the road near the group and the group on it at life size, in a frame that rides along
with the group (heights exaggerated on request). No viser handles: all testable alone.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from kernels import course as course_kernel
from kernels import cycling
from scenes._controls import checkbox, dropdown, dropdown_from_labels, number, slider
from scenes.peloton.model import BIKE_LENGTH_M, ROAD_HALF_WIDTH_M, PelotonParams, drag_reductions, group_cda

CourseAirLabel = Literal["Textbook atmosphere", "Weather reading"]
AIR_FROM_LABEL: dict[str, course_kernel.AirKind] = {"Textbook atmosphere": "textbook", "Weather reading": "weather"}
PRESSURE_SOURCES = ("Standard atmosphere", "Barometer")
"""What the "Pressure from" dropdown shows for :attr:`CourseParams.pressure_from_barometer` False and True."""
POWER_MODEL_FROM_LABEL: dict[str, course_kernel.Model] = {
    "Martin et al. 1998 (full)": "martin",
    "Textbook (aero, rolling, climbing)": "textbook",
}
BAROMETER_RANGE_HPA = (250.0, 1100.0)
"""What the barometer input takes (hPa). A course may start as high as 10 000 m
(:data:`kernels.course.MAX_ELEVATION_M`), where the standard atmosphere reads 265 hPa and a deep low some 5 % less;
Everest's summit reads about 337 hPa. The air kernel takes 10 to 1100 hPa. (From 500 hPa, a route above 5 500 m,
which the reader accepts, could not be given its real reading: 480 hPa at 5 800 m.)"""
COURSE_POWER_RANGE_W = (20.0, 2000.0)
"""What the Course power input takes (W); 'Find the power for this time' says when a target needs more or less."""
COURSE_POWER_DECIMALS = 4
"""Digits after the point of a found Course power: as few as put the finish within half a second of the target, at
most these (at 25 W over ten hours, 0.1 W moves the finish by 70 s)."""
MODEL_LABEL = {model: label for label, model in POWER_MODEL_FROM_LABEL.items()}
SAMPLE_LABEL = "Alpe d'Huez (sample, from the published profile)"
VERGE_HALF_WIDTH_M = 16.0
"""Half the width of the grass either side of the road (m)."""
VERGE_DROP_M = 0.5
"""How far under the road the verge lies (m). A strip's quads twist in a bend on a climb (its inner edge climbs faster
than its outer); a verge just under the road rose through it there in stripes."""
ROAD_AHEAD_M = 30.0
"""Road drawn ahead of the leader (m)."""
ROAD_BEHIND_M = 20.0
"""Road drawn behind the last rider (m)."""
ROAD_STEP_M = 1.0
"""Spacing of the drawn road's cross-sections (m): a bend of the route turns smoothly over a few of them."""
LINE_VIEW_DIRECTION = (1.2, 7.5, -1.6)
"""Where the camera looks at a line of riders on the course: from the line's right side, a little behind and above."""
GROUP_VIEW_DIRECTION = (3.0, 2.6, -2.4)
"""Where the camera looks at a group on the course: from behind its right side and above, so every row shows (from
ahead, as on the flat road, the road framed ahead of the leader pushed the group to the far end of the picture)."""
FRAMED_LENGTH_M = 45.0
"""The camera frames at most this much of the group, from its leader back (m): a longer line (121 riders in single
file run over 260 m) framed whole draws its riders a few pixels tall, so the front of it is framed and the panel says
so. The scene's frame turns with the road under that front (:func:`lay_out_road`)."""


def framed_front(xy: np.ndarray) -> np.ndarray:
    """(n,) whether each rider of an (n, 2) formation (m ahead, m left; leader first) is within
    :data:`FRAMED_LENGTH_M` of its front: the riders a camera frames."""
    x = np.asarray(xy, dtype=np.float64)[:, 0]
    return x >= x.max() - FRAMED_LENGTH_M


def framed_words(xy: np.ndarray) -> str:
    """What the panel says of a group longer than :data:`FRAMED_LENGTH_M` (a line break and a sentence: how many of
    its riders are framed, how far it runs back); empty for a group framed whole."""
    framed = int(np.count_nonzero(framed_front(xy)))
    if framed >= len(xy):
        return ""
    x = np.asarray(xy, dtype=np.float64)[:, 0]
    return (
        f"  \nThe camera frames the front {FRAMED_LENGTH_M:.0f} m of the group (its first {framed} riders); it runs "
        f"{float(x.max() - x.min()):.0f} m back: zoom out to see the rest."
    )


MAX_CHART_POINTS = 1000

MODE_FOLDER = "Course mode (GPX route)"
POWER_FOLDER = "Power, model and air"
MORE_FOLDER = "Wind, descents, pacing, view"
"""Opens collapsed."""


POSITION_STEP_M = 10.0
"""The Position (km) slider's step (m)."""


@dataclasses.dataclass(frozen=True)
class CourseParams:
    """Course-mode inputs (the rider, the line and drafting come from :class:`PelotonParams`).

    Each field is also its GUI control, declared once (:mod:`scenes._controls`), in the order and folder shown.
    """

    enabled: bool = field(default=False, metadata=checkbox("Ride a course", folder=MODE_FOLDER))
    """Whether the course mode is shown (and ridden) instead of the line."""
    position_km: float = field(default=0.0, metadata=slider("Position (km)", 0.0, 1.0, POSITION_STEP_M / 1000.0))
    """Where the leader is along the route (km, on the slider's 10 m step; its end is the finish): set by the person
    or by playback. Built in the mode's folder under the Play and Pause buttons; the declared range is a placeholder,
    which the scene sets to the loaded route's length."""
    power_w: float = field(
        default=250.0,
        metadata=number(
            "Course power (W)", *COURSE_POWER_RANGE_W, 5.0, decimals=COURSE_POWER_DECIMALS, folder=POWER_FOLDER
        ),
    )
    """Constant pedal power of each rider (W)."""
    target_min: float = field(default=60.0, metadata=number("Target time (min)", 1.0, 6000.0, 1.0, folder=POWER_FOLDER))
    """Finish time that 'Find the power for this time' aims at (min)."""
    model: course_kernel.Model = field(
        default="martin", metadata=dropdown_from_labels("Power model", POWER_MODEL_FROM_LABEL, folder=POWER_FOLDER)
    )
    """Power model: Martin et al. 1998's full terms or the textbook three."""
    air: course_kernel.AirKind = field(
        default="textbook", metadata=dropdown_from_labels("Air", AIR_FROM_LABEL, folder=POWER_FOLDER)
    )
    """Air along the route: the textbook exponential atmosphere or a weather reading."""
    temperature_c: float = field(default=15.0, metadata=slider("Temp (°C)", -20.0, 45.0, 0.5, folder=POWER_FOLDER))
    """Air temperature at the start (°C), weather air."""
    pressure_from_barometer: bool = field(
        default=False, metadata=dropdown("Pressure from", (False, True), PRESSURE_SOURCES, folder=POWER_FOLDER)
    )
    """Weather air: the barometer's pressure, or the standard atmosphere's at the start's altitude."""
    pressure_hpa: float = field(
        default=1013.25, metadata=number("Pressure at the start (hPa)", *BAROMETER_RANGE_HPA, 0.5, folder=POWER_FOLDER)
    )
    """Station pressure at the start (hPa), when read from a barometer."""
    humidity_pct: float = field(default=50.0, metadata=slider("Humidity (%)", 0.0, 100.0, 1.0, folder=POWER_FOLDER))
    """Relative humidity (%), weather air."""
    wind_ms: float = field(default=0.0, metadata=slider("Wind (m/s)", 0.0, 20.0, 0.5, folder=MORE_FOLDER))
    """Wind speed (m/s)."""
    wind_from_deg: float = field(
        default=0.0, metadata=slider("Wind from (° from north)", 0.0, 359.0, 1.0, folder=MORE_FOLDER)
    )
    """Where the wind blows from, clockwise from north (°)."""
    max_speed_kmh: float = field(
        default=72.0, metadata=slider("Safe descending speed (km/h)", 20.0, 110.0, 1.0, folder=MORE_FOLDER)
    )
    """Safe descending speed (km/h): riders brake to hold it."""
    pacing: bool = field(default=False, metadata=checkbox("Pace by grade", folder=MORE_FOLDER))
    """Vary power with the grade (Swain 1997) at the same average."""
    pacing_gain_pct: float = field(default=15.0, metadata=slider("Pacing gain (%)", 0.0, 50.0, 1.0, folder=MORE_FOLDER))
    """How much more power on steep climbs, and less on descents (%)."""
    exaggeration: float = field(default=1.0, metadata=slider("Steepness drawn (×)", 1.0, 5.0, 0.5, folder=MORE_FOLDER))
    """Vertical exaggeration of the drawn road (the ride itself is on the real grades)."""
    playback: float = field(default=60.0, metadata=slider("Playback speed (×)", 1.0, 600.0, 1.0, folder=MORE_FOLDER))
    """Playback speed (× real time)."""


@dataclasses.dataclass(frozen=True)
class CourseState:
    """What the course mode shows for one route and parameter set."""

    route: course_kernel.Course
    ride: course_kernel.Ride
    """The ride drawn and animated: paced when pacing is on, else constant."""
    constant: course_kernel.Ride
    solo: course_kernel.Ride
    """One rider alone at the same power (no shelter)."""
    pacing: course_kernel.Pacing | None
    group_cda_m2: float
    """CdA the group rides at when riders share the front equally (m²): the rider's CdA times the mean of
    :attr:`drag`."""
    drag: np.ndarray
    """(n,) drag of each place in the formation as a fraction of the same rider alone, leader first."""
    rider_cda_m2: float
    """The rider's CdA alone (m²)."""
    efficiency: float
    """Drivetrain efficiency (0, 1]."""
    density_textbook: float
    """The exponential atmosphere's density at the start (kg/m³)."""
    density_weather: float
    """The weather reading's density at the start (kg/m³)."""


def course_air(route: course_kernel.Course, p: CourseParams) -> course_kernel.Air:
    """The :class:`kernels.course.Air` for the inputs; the reading is taken at the route's start."""
    start = float(route.elevation_m[0])
    pressure = (
        p.pressure_hpa
        if p.pressure_from_barometer
        # The standard atmosphere at the start, within its range and the reading's 10–1100 hPa (a start below
        # about −700 m would read more than 1100 hPa and be refused).
        else float(np.clip(cycling.isa_pressure_hpa(np.clip(start, -1000.0, 20_000.0)), 10.0, 1100.0))
    )
    return course_kernel.Air(p.air, p.temperature_c, pressure, p.humidity_pct / 100.0, altitude_m=start)


def course_rider(line: PelotonParams, p: CourseParams, cda_m2: float) -> course_kernel.Rider:
    """The :class:`kernels.course.Rider` of the line's rider and the mode's power model, at drag area ``cda_m2``."""
    return course_kernel.Rider(
        cda_m2=cda_m2,
        mass_kg=line.mass_kg,
        crr=line.crr,
        drivetrain_efficiency=line.drivetrain_pct / 100.0,
        model=p.model,
    )


def compute_course(route: course_kernel.Course, p: CourseParams, line: PelotonParams) -> CourseState:
    """Ride ``route`` for one parameter set (no viser: testable on its own)."""
    air = course_air(route, p)
    weather = dataclasses.replace(air, kind="weather")
    start = float(route.elevation_m[0])

    def rider(cda: float) -> course_kernel.Rider:
        return course_rider(line, p, cda)

    cda = group_cda(line)
    drag = 1.0 - drag_reductions(line, yaw_rad=0.0) if line.drafting and line.n_riders >= 2 else np.ones(line.n_riders)
    wind, wind_from, cap = p.wind_ms, p.wind_from_deg, p.max_speed_kmh / 3.6

    def ride_at(cda_m2: float) -> course_kernel.Ride:
        return course_kernel.ride(route, p.power_w, rider(cda_m2), wind, wind_from, air, cap)

    pacing = None
    if p.pacing:
        pacing = course_kernel.paced_ride(
            route, p.power_w, rider(cda), p.pacing_gain_pct / 100.0, wind, wind_from, air, cap
        )
        constant, shown = pacing.constant, pacing.paced
    else:
        constant = shown = ride_at(cda)
    solo = constant if cda == line.cda_m2 else ride_at(line.cda_m2)
    return CourseState(
        route=route,
        ride=shown,
        constant=constant,
        solo=solo,
        pacing=pacing,
        group_cda_m2=cda,
        drag=drag,
        rider_cda_m2=line.cda_m2,
        efficiency=line.drivetrain_pct / 100.0,
        density_textbook=float(cycling.air_density(start)),
        density_weather=float(weather.density(start)),
    )


def _per_m2(speed_ms: ArrayLike, headwind_ms: ArrayLike, density: ArrayLike, efficiency: float) -> np.ndarray:
    """Pedal power (W) each m² of drag area costs: ½·ρ·(v + w)·|v + w|·v / η (Martin et al. 1998's aero term; the
    spoke drag F_w is the same for every rider, so it drops out of a difference between riders)."""
    v = np.asarray(speed_ms, np.float64)
    air = v + np.asarray(headwind_ms, np.float64)
    return 0.5 * np.asarray(density, np.float64) * air * np.abs(air) * v / efficiency


def aero_watts_per_m2(ride: course_kernel.Ride, efficiency: float) -> np.ndarray:
    """(N − 1,) pedal power (W) each m² of drag area costs on each segment of ``ride`` (:func:`_per_m2`) at the
    segment's mean speed v (its length over its time), headwind w and air density ρ."""
    seconds = np.diff(ride.elapsed_s)
    metres = np.diff(ride.distance_m)
    v = np.divide(metres, seconds, out=np.zeros_like(metres), where=seconds > 0.0)
    return _per_m2(v, ride.headwind_ms, ride.air_density, efficiency)


def place_powers(state: CourseState, at_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Each place's pedal power in the formation (W), leader first: (n,) where the leader is ``at_m`` (m along the
    route) and (n,) its mean over the ride (by time).

    The group rides at the mean drag of its places, at the group's power P (the ride's), less what its brakes take
    to hold the speed cap, B (:attr:`~kernels.course.Ride.brakes_w`, at the wheel: B/η at the pedals). A place with
    drag area CdA_i needs P − B/η + (CdA_i − CdA_group)·a, with a the aero power per m² (½·ρ·(v + w)·|v + w|·v / η):
    here at the speed v at ``at_m`` (0 at a standing start, where every place needs P), and segment by segment
    over the ride at each one's mean speed (:func:`aero_watts_per_m2`). A place that would need less than nothing (a
    sheltered rider on a descent, or every rider where the group brakes) pedals 0 W: it brakes or sits up. So the
    places average the group's power wherever none of them brakes; riders who share the work in turn each average
    it over the ride.
    """
    ride = state.ride
    eta = state.efficiency
    per_m2 = aero_watts_per_m2(ride, eta)
    extra = state.rider_cda_m2 * np.asarray(state.drag) - state.group_cda_m2  # (n,) m²
    segment = int(np.clip(np.searchsorted(ride.distance_m, at_m, side="right") - 1, 0, per_m2.shape[0] - 1))
    v = np.interp(at_m, ride.distance_m, ride.speed_ms)
    here_per_m2 = float(_per_m2(v, ride.headwind_ms[segment], ride.air_density[segment], eta))
    here = float(ride.power_w[segment] - ride.brakes_w[segment] / eta) + extra * here_per_m2
    group = ride.power_w[:-1] - ride.brakes_w / eta  # (S,) the group's net pedal power on each segment (W)
    seconds = np.diff(ride.elapsed_s)
    mean = np.empty_like(extra)
    rows = max(1, _MEAN_CHUNK // max(group.shape[0], 1))  # places at a time: at most ~1e6 values in flight
    for start in range(0, extra.shape[0], rows):
        needs = group[None, :] + extra[start : start + rows, None] * per_m2[None, :]
        mean[start : start + rows] = np.maximum(needs, 0.0) @ seconds
    mean /= max(float(np.sum(seconds)), 1e-9)
    return np.maximum(here, 0.0), mean


_MEAN_CHUNK = 1_000_000
"""How many (place, segment) needs :func:`place_powers` holds at once (8 MB)."""


def position_end_km(total_m: float) -> float:
    """The Position slider's end, and the route's length as the panel gives it (km): the length to the slider's
    10 m step, nearest. That end is the finish (:func:`position_m`), so the slider reaches it and the two agree (the
    end had been rounded up, 13.16 against a 13.15 km route)."""
    return round(total_m / POSITION_STEP_M) * POSITION_STEP_M / 1000.0


def position_m(km: float, total_m: float) -> float:
    """Where the Position slider at ``km`` puts the leader (m along a route of ``total_m``): its end
    (:func:`position_end_km`) is the finish, and a place short of it is that far along, at most the finish."""
    if km >= position_end_km(total_m):
        return float(total_m)
    return float(np.clip(1000.0 * km, 0.0, total_m))


def position_km(distance_m: float, total_m: float) -> float:
    """The Position slider's value (km, on its 10 m step) for a leader ``distance_m`` along a route of ``total_m``:
    its end at the finish. The readouts give the same, so slider, summary and readout say one number."""
    if distance_m >= total_m:
        return position_end_km(total_m)
    return min(round(distance_m / 10.0) / 100.0, position_end_km(total_m))


def format_duration(seconds: float) -> str:
    """h:mm:ss (or m:ss under an hour)."""
    total = round(seconds)
    hours, rest = divmod(total, 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours:d}:{minutes:02d}:{secs:02d}" if hours else f"{minutes:d}:{secs:02d}"


def time_saved_words(saved_s: float) -> str:
    """A time saved (s; negative: lost) in words, to the second: "12 s saved", "5 s lost", or "no time saved"."""
    seconds = round(saved_s)
    if seconds == 0:
        return "no time saved"
    return f"{abs(seconds)} s {'saved' if seconds > 0 else 'lost'}"


def split_every_m(total_m: float) -> float:
    """Split length for the table: 1 km up to 30 km, 5 km up to 150 km, else 10 km."""
    return 1000.0 if total_m <= 30_000.0 else 5000.0 if total_m <= 150_000.0 else 10_000.0


def drawn_indices(n_points: int, limit: int) -> np.ndarray:
    """Indices of at most ``limit`` points spread along the route, first and last included."""
    return np.unique(np.linspace(0, n_points - 1, min(n_points, limit)).round().astype(np.int64))


def route_points(route: course_kernel.Course, distance_m: np.ndarray) -> np.ndarray:
    """(k, 3) map points (east, north, elevation; m) at distances along the route (m). Before the start and past the
    finish the road runs on straight and level, along the first and last segment (riders wait there)."""
    d = np.asarray(distance_m, dtype=np.float64)
    total = float(route.total_distance_m)
    inside = np.clip(d, 0.0, total)
    east = np.interp(inside, route.distance_m, route.east_m)
    north = np.interp(inside, route.distance_m, route.north_m)
    elevation = np.interp(inside, route.distance_m, route.elevation_m)
    for end, beyond in ((0, np.minimum(d, 0.0)), (-1, np.maximum(d - total, 0.0))):
        a, b = (0, 1) if end == 0 else (-2, -1)
        step = np.array([route.east_m[b] - route.east_m[a], route.north_m[b] - route.north_m[a]])
        step = step / max(float(np.hypot(*step)), 1e-9)
        east = east + beyond * step[0]
        north = north + beyond * step[1]
    return np.stack([east, north, elevation], axis=1)


CORNER_ROUNDING_M = 6.0
"""σ (m) of the Gaussian along the route that rounds its corners where the road is drawn: a GPX track is a
polyline, and at its corners a road several metres wide, and a bunch across it, would fold over itself."""
_ROUNDING_OFFSETS = np.linspace(-2.0, 2.0, 41) * CORNER_ROUNDING_M  # 0.6 m apart: finer than any GPX track
_ROUNDING_WEIGHTS = np.exp(-0.5 * (_ROUNDING_OFFSETS / CORNER_ROUNDING_M) ** 2)
_ROUNDING_WEIGHTS /= _ROUNDING_WEIGHTS.sum()


INSIDE_REACH = 0.8
"""How far a drawn strip (road, verge) reaches into the inside of a bend, as a fraction of the bend's radius."""


def drawn_route_points(route: course_kernel.Course, distance_m: np.ndarray) -> np.ndarray:
    """(k, 3) :func:`route_points` at distances along the route (m), averaged with Gaussian weights over
    ±2·:data:`CORNER_ROUNDING_M` of road: the road as drawn, its corners rounded into bends (and its grade changes
    eased); the road and the riders on it are both laid out on it."""
    d = np.asarray(distance_m, dtype=np.float64).reshape(-1)
    points = route_points(route, (d[:, None] + _ROUNDING_OFFSETS[None, :]).ravel())
    return np.einsum("kmc,m->kc", points.reshape(len(d), len(_ROUNDING_OFFSETS), 3), _ROUNDING_WEIGHTS)


@dataclasses.dataclass(frozen=True)
class ChaseFrame:
    """The scene frame the riders are drawn in, at life size: its origin is the middle of the group on the route,
    its x axis points from the group's last rider to its leader (level), z is up, with heights exaggerated by
    ``exaggeration`` about the origin. The road and riders are laid out in it every frame, so a camera framed on the
    group keeps seeing it as it rides."""

    origin: np.ndarray
    """(3,) map point (east, north, elevation; m) drawn at the scene origin."""
    heading_rad: float
    """Direction of the scene's x axis on the map (rad, counter-clockwise from east)."""
    exaggeration: float

    @staticmethod
    def around(route: course_kernel.Course, leader_m: float, length_m: float, exaggeration: float) -> ChaseFrame:
        """The frame around a group whose leader is at ``leader_m`` and whose last rider is ``length_m`` behind."""
        half = 0.5 * max(length_m, 4.0)
        tail, middle, head = route_points(route, np.array([leader_m - 2 * half, leader_m - half, leader_m]))
        heading = math.atan2(head[1] - tail[1], head[0] - tail[0])
        return ChaseFrame(origin=middle, heading_rad=heading, exaggeration=exaggeration)

    def local(self, points: np.ndarray) -> np.ndarray:
        """(k, 3) scene points of (k, 3) map points."""
        c, s = math.cos(self.heading_rad), math.sin(self.heading_rad)
        d = points - self.origin
        return np.stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1], self.exaggeration * d[:, 2]], axis=1)

    def along(self, route: course_kernel.Course, distance_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(k, 3) scene points of the road's centre at distances along the route and (k, 3) unit tangents there,
        the route's corners rounded (:func:`drawn_route_points`)."""
        d = np.asarray(distance_m, dtype=np.float64)
        centre = self.local(drawn_route_points(route, d))
        tangent = self.local(drawn_route_points(route, d + 0.5)) - self.local(drawn_route_points(route, d - 0.5))
        norm = np.linalg.norm(tangent, axis=1, keepdims=True)
        return centre, tangent / np.where(norm > 1e-12, norm, 1.0)


def road_strip(
    frame: ChaseFrame, route: course_kernel.Course, distance_m: np.ndarray, half_width: float, lift: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """A flat strip ``half_width`` (m) either side of the road's centre at the (k,) distances ``distance_m``,
    ``lift`` (m) above it: (2k, 3) scene vertices (left edge, then right edge) and (2(k−1), 3) faces.

    On the inside of a bend the strip reaches at most :data:`INSIDE_REACH` of the bend's radius: wider, its inner
    edge would pass the bend's centre, fold back over itself and, on a climb, lie over the road further on."""
    d = np.asarray(distance_m, dtype=np.float64)
    return strip_along(d, *frame.along(route, d), half_width, lift)


def strip_along(
    d: np.ndarray, centre: np.ndarray, tangent: np.ndarray, half_width: float, lift: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`road_strip` on a centre line already laid out: (k,) distances (m), (k, 3) centre points and (k, 3) unit
    tangents (:meth:`ChaseFrame.along`), so strips of several widths share one layout of the road."""
    left = np.stack([-tangent[:, 1], tangent[:, 0], np.zeros(len(centre))], axis=1)
    left /= np.maximum(np.linalg.norm(left, axis=1, keepdims=True), 1e-12)
    heading = np.unwrap(np.arctan2(tangent[:, 1], tangent[:, 0]))
    # Curvature dθ/ds (1/m, + turning left), each side's sharpest within a half-width along the road (the inner
    # edge of a strip that narrows into a bend folds over where the bend is sharpest, not only where it is).
    if len(d) > 2 and np.all(np.diff(d) > 0):
        turning = np.gradient(heading, d)
        reach = math.ceil(half_width / float(np.median(np.diff(d))))
        windows = np.lib.stride_tricks.sliding_window_view(np.pad(turning, reach, mode="edge"), 2 * reach + 1)
        left_turn, right_turn = np.maximum(windows.max(axis=1), 0.0), np.maximum(-windows.min(axis=1), 0.0)
    else:
        left_turn = right_turn = np.zeros(len(d))
    left_width = np.minimum(half_width, INSIDE_REACH / np.maximum(left_turn, 1e-9))[:, None]
    right_width = np.minimum(half_width, INSIDE_REACH / np.maximum(right_turn, 1e-9))[:, None]
    lifted = centre + [0.0, 0.0, lift]
    vertices = np.concatenate([lifted + left_width * left, lifted - right_width * left])
    k = centre.shape[0]
    a = np.arange(k - 1)
    faces = np.concatenate([np.stack([a, k + a, k + a + 1], axis=1), np.stack([a, k + a + 1, a + 1], axis=1)])
    return vertices.astype(np.float32), faces.astype(np.uint32)


def riders_on_road(
    frame: ChaseFrame, route: course_kernel.Course, leader_m: float, formation_xy: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Where each rider of a formation rides on the road: (n, 3) scene positions and (n, 4) wxyz orientations.

    ``formation_xy`` is (n, 2): metres ahead of the leader (≤ 0 behind) and to its left, as
    :func:`kernels.cycling.formation` lays them out on a straight road; on the route each rider keeps its distance
    behind the leader along the road and its offset across it, turned to the road's heading and pitched to its
    drawn grade."""
    xy = np.asarray(formation_xy, dtype=np.float64).reshape(-1, 2)
    centre, tangent = frame.along(route, leader_m + xy[:, 0])
    yaw = np.arctan2(tangent[:, 1], tangent[:, 0])
    pitch = np.arctan2(tangent[:, 2], np.hypot(tangent[:, 0], tangent[:, 1]))
    left = np.stack([-np.sin(yaw), np.cos(yaw), np.zeros(len(yaw))], axis=1)
    positions = centre + xy[:, 1:2] * left
    # Yaw about z, then the nose up by the grade (a turn about the rider's left axis, −pitch by the right hand).
    cy, sy = np.cos(yaw / 2), np.sin(yaw / 2)
    cp, sp = np.cos(-pitch / 2), np.sin(-pitch / 2)
    wxyz = np.stack([cy * cp, -sy * sp, cy * sp, sy * cp], axis=1)
    return positions, wxyz


def rider_boxes(positions: np.ndarray, wxyz: np.ndarray, top_m: float, half_m: tuple[float, float]) -> np.ndarray:
    """(8n, 3) corners of each rider's box as drawn: ``half_m`` (m, along the bike and across it) either side of its
    (n, 3) position, from the road to ``top_m`` above it, turned by its (n, 4) wxyz orientation."""
    w, x, y, z = np.asarray(wxyz, np.float64).T
    # The rotation matrix of a unit quaternion (columns: where the rider's x, y and z axes point).
    axes = np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)], axis=1),
            np.stack([2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x)], axis=1),
            np.stack([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)], axis=1),
        ],
        axis=1,
    )  # (n, 3 axes, 3)
    corners = np.array([(sx * half_m[0], sy * half_m[1], h) for sx in (-1, 1) for sy in (-1, 1) for h in (0.0, top_m)])
    pos = np.asarray(positions, np.float64)
    return (pos[:, None, :] + np.einsum("ck,nkd->ncd", corners, axes)).reshape(-1, 3)


def dash_distances(d_from: float, d_to: float, every_m: float = 3.0, count: int | None = None) -> np.ndarray:
    """(m, 2) start and end (m along the route) of the centre line's dashes between ``d_from`` and ``d_to``: 1.5 m
    dashes every ``every_m``, fixed to the road so they pass as the riders move; padded to ``count`` rows with empty
    dashes (the drawn node keeps its size)."""
    first = math.ceil(d_from / every_m) * every_m
    starts = np.arange(first, d_to - 0.5 * every_m, every_m)
    dashes = np.stack([starts, starts + 0.5 * every_m], axis=1)
    if count is not None:
        empty = np.full((max(count - len(dashes), 0), 2), d_from)  # zero-length: drawn as nothing
        dashes = np.concatenate([dashes[:count], empty])
    return dashes


@dataclasses.dataclass(frozen=True)
class RoadLayout:
    """The road near the group and the group on it, in the scene frame of :class:`ChaseFrame` (m)."""

    frame: ChaseFrame
    window_m: tuple[float, float]
    """(from, to): the stretch of the route drawn (m along it; before 0 and past the finish the road runs on)."""
    half_width_m: float
    road: tuple[np.ndarray, np.ndarray]
    """Vertices and faces of the road."""
    verge: tuple[np.ndarray, np.ndarray]
    """Vertices and faces of the grass either side, a little below the road."""
    edges: np.ndarray
    """(2(k−1), 2, 3) segments of the road's two white edge lines."""
    dashes: np.ndarray
    """(m, 2, 3) segments of the centre line's dashes."""
    riders: tuple[np.ndarray, np.ndarray]
    """(n, 3) positions and (n, 4) wxyz of the riders, leader first."""
    marks: dict[str, tuple[np.ndarray, np.ndarray] | None]
    """"Start" and "Finish": the painted line across the road there, (4, 3) vertices (left edge, then right edge)
    and (2, 3) faces of a flat band :data:`MARK_WIDTH_M` wide, or None when it is not in the window."""


MARK_WIDTH_M = 0.3
"""Width along the road of the painted start and finish lines (m)."""


def lay_out_road(
    route: course_kernel.Course, leader_m: float, formation_xy: np.ndarray, exaggeration: float
) -> RoadLayout:
    """Lay the group out on the road at ``leader_m`` along the route, and the road around it (see
    :class:`RoadLayout`). ``formation_xy`` is (n, 2) as :func:`riders_on_road` takes it."""
    xy = np.asarray(formation_xy, dtype=np.float64).reshape(-1, 2)
    length = float(-xy[:, 0].min()) if len(xy) else 0.0
    # The frame follows the road under the group's framed front: the camera looks along it, not along the chord
    # from a long line's leader to its last rider, which a hairpin turns across the road at the front.
    frame = ChaseFrame.around(route, leader_m, min(length, FRAMED_LENGTH_M), exaggeration)
    half_width = max(ROAD_HALF_WIDTH_M, float(np.abs(xy[:, 1]).max(initial=0.0)) + 0.9)
    d_from, d_to = leader_m - length - ROAD_BEHIND_M, leader_m + ROAD_AHEAD_M
    k = round((d_to - d_from) / ROAD_STEP_M) + 1
    distance = np.linspace(d_from, d_to, k)
    line = frame.along(route, distance)  # laid out once for the road, its verge and its edge lines
    road = strip_along(distance, *line, half_width, 0.0)
    verge = strip_along(distance, *line, VERGE_HALF_WIDTH_M, -VERGE_DROP_M)
    inset = strip_along(distance, *line, half_width - 0.15, 0.004)[0]
    edges = np.concatenate([np.stack([side[:-1], side[1:]], axis=1) for side in (inset[:k], inset[k:])])
    dash_m = dash_distances(d_from, d_to, count=int((d_to - d_from) / 3.0) + 1)
    dashes = frame.along(route, dash_m.ravel())[0].reshape(-1, 2, 3) + [0.0, 0.0, 0.004]
    marks: dict[str, tuple[np.ndarray, np.ndarray] | None] = {}
    for name, at in (("Start", 0.0), ("Finish", float(route.total_distance_m))):
        # Where the leader's front wheel is when the ride's clock starts and stops (a rider's distance is the bike's
        # centre): the leader stood across the start line at 0.00 km, his rear wheel on it.
        line_at = at + 0.5 * BIKE_LENGTH_M
        if d_from <= line_at - 0.5 * MARK_WIDTH_M and line_at + 0.5 * MARK_WIDTH_M <= d_to:
            span = np.array([line_at - 0.5 * MARK_WIDTH_M, line_at + 0.5 * MARK_WIDTH_M])
            marks[name] = road_strip(frame, route, span, half_width, 0.006)
        else:
            marks[name] = None
    return RoadLayout(
        frame=frame,
        window_m=(d_from, d_to),
        half_width_m=half_width,
        road=road,
        verge=verge,
        edges=edges.astype(np.float32),
        dashes=dashes.astype(np.float32),
        riders=riders_on_road(frame, route, leader_m, xy),
        marks=marks,
    )
