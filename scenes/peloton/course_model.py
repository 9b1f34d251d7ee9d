"""The course mode's model: its parameters, a route ridden for them, and the route mapped into the scene.

:class:`CourseParams` is what the user sets in the mode (each field declares its GUI control, :mod:`scenes._controls`);
:func:`compute_course` rides a route for it and the line's :class:`~scenes.peloton.model.PelotonParams` into a
:class:`CourseState` through :mod:`kernels.course` (Martin et al. 1998). :class:`CourseDrawing`,
:func:`terrain_strip`, :func:`ground_under` and :func:`grade_colours` map the route into the box the line's camera
already frames: map metres scaled, elevation exaggerated, (N, 3) scene points. No viser handles: all testable alone.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import field
from typing import Literal

import numpy as np
import trimesh

from kernels import course as course_kernel
from kernels import cycling
from scenes._controls import checkbox, dropdown, dropdown_from_labels, number, slider
from scenes.peloton.model import PelotonParams, group_cda

CourseAirLabel = Literal["Exponential atmosphere (textbook)", "Weather (temperature, pressure or altitude, humidity)"]
AIR_FROM_LABEL: dict[str, course_kernel.AirKind] = {
    "Exponential atmosphere (textbook)": "seed",
    "Weather (temperature, pressure or altitude, humidity)": "weather",
}
PRESSURE_SOURCES = ("Standard atmosphere at the route's altitude", "Barometer at the start (hPa)")
"""What the "Pressure from" dropdown shows for :attr:`CourseParams.pressure_from_barometer` False and True."""
POWER_MODEL_FROM_LABEL: dict[str, course_kernel.Model] = {
    "Martin et al. 1998 (full)": "martin",
    "Textbook (aero, rolling, climbing)": "seed",
}
COURSE_POWER_RANGE_W = (20.0, 2000.0)
"""What the Course power input takes (W); 'Find the power for this time' says when a target needs more or less."""
MODEL_LABEL = {model: label for label, model in POWER_MODEL_FROM_LABEL.items()}
SAMPLE_LABEL = "Alpe d'Huez (sample, from the published profile)"
COURSE_BOX_M = 6.0
"""The drawn course fits a square of this size (scene metres) where the line's camera looks."""
COURSE_CENTRE = np.array([-3.2, 0.0])
TERRAIN_HALF_WIDTH_M = 0.15
"""Half width of the drawn terrain strip (scene m)."""
COURSE_MARKER_SCALE = 0.25
"""Riders on the course are drawn at this fraction of life size (a marker, not to the map's scale)."""
MAX_DRAWN_POINTS = 2000
MAX_CHART_POINTS = 1000

MODE_FOLDER = "Course mode (GPX route)"
POWER_FOLDER = "Power, model and air"
MORE_FOLDER = "Wind, descents, pacing, view"
"""Opens collapsed."""


@dataclasses.dataclass(frozen=True)
class CourseParams:
    """Course-mode inputs (the rider, the line and drafting come from :class:`PelotonParams`).

    Each field is also its GUI control, declared once (:mod:`scenes._controls`), in the order and folder shown.
    """

    enabled: bool = field(default=False, metadata=checkbox("Ride a course", folder=MODE_FOLDER))
    """Whether the course mode is shown (and ridden) instead of the line."""
    power_w: float = field(
        default=250.0,
        metadata=number("Course power (W)", *COURSE_POWER_RANGE_W, 5.0, folder=POWER_FOLDER),
    )
    """Constant pedal power of each rider (W)."""
    target_min: float = field(default=60.0, metadata=number("Target time (min)", 1.0, 6000.0, 1.0, folder=POWER_FOLDER))
    """Finish time that 'Find the power for this time' aims at (min)."""
    model: course_kernel.Model = field(
        default="martin",
        metadata=dropdown_from_labels("Power model", POWER_MODEL_FROM_LABEL, folder=POWER_FOLDER),
    )
    """Power model: Martin et al. 1998's full terms or the textbook three."""
    air: course_kernel.AirKind = field(
        default="seed",
        metadata=dropdown_from_labels("Air", AIR_FROM_LABEL, folder=POWER_FOLDER),
    )
    """Air along the route: the textbook exponential atmosphere or a weather reading."""
    temperature_c: float = field(
        default=15.0, metadata=slider("Temperature (°C)", -20.0, 45.0, 0.5, folder=POWER_FOLDER)
    )
    """Air temperature at the start (°C), weather air."""
    pressure_from_barometer: bool = field(
        default=False,
        metadata=dropdown("Pressure from", (False, True), PRESSURE_SOURCES, folder=POWER_FOLDER),
    )
    """Weather air: the barometer's pressure, or the standard atmosphere's at the start's altitude."""
    pressure_hpa: float = field(
        default=1013.25,
        metadata=number("Pressure at the start (hPa)", 500.0, 1100.0, 0.5, folder=POWER_FOLDER),
    )
    """Station pressure at the start (hPa), when read from a barometer."""
    humidity_pct: float = field(default=50.0, metadata=slider("Humidity (%)", 0.0, 100.0, 1.0, folder=POWER_FOLDER))
    """Relative humidity (%), weather air."""
    wind_ms: float = field(default=0.0, metadata=slider("Wind (m/s)", 0.0, 20.0, 0.5, folder=MORE_FOLDER))
    """Wind speed (m/s)."""
    wind_from_deg: float = field(
        default=0.0,
        metadata=slider("Wind from (° from north)", 0.0, 359.0, 1.0, folder=MORE_FOLDER),
    )
    """Where the wind blows from, clockwise from north (°)."""
    max_speed_kmh: float = field(
        default=72.0,
        metadata=slider("Safe descending speed (km/h)", 20.0, 110.0, 1.0, folder=MORE_FOLDER),
    )
    """Safe descending speed (km/h): riders brake to hold it."""
    pacing: bool = field(default=False, metadata=checkbox("Pace by grade", folder=MORE_FOLDER))
    """Vary power with the grade (Swain 1997) at the same average."""
    pacing_gain_pct: float = field(default=15.0, metadata=slider("Pacing gain (%)", 0.0, 50.0, 1.0, folder=MORE_FOLDER))
    """How much more power on steep climbs, and less on descents (%)."""
    exaggeration: float = field(
        default=2.0,
        metadata=slider("Elevation exaggeration (×)", 1.0, 10.0, 0.5, folder=MORE_FOLDER),
    )
    """Vertical exaggeration of the drawn terrain."""
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
    """CdA the group rides at when riders share the front equally (m²)."""
    density_seed: float
    """The exponential atmosphere's density at the start (kg/m³)."""
    density_weather: float
    """The weather reading's density at the start (kg/m³)."""


def course_air(route: course_kernel.Course, p: CourseParams) -> course_kernel.Air:
    """The :class:`kernels.course.Air` for the inputs; the reading is taken at the route's start."""
    start = float(route.elevation_m[0])
    pressure = (
        p.pressure_hpa
        if p.pressure_from_barometer
        else float(cycling.isa_pressure_hpa(np.clip(start, -1000.0, 20_000.0)))
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
        density_seed=float(cycling.air_density(start)),
        density_weather=float(weather.density(start)),
    )


def format_duration(seconds: float) -> str:
    """h:mm:ss (or m:ss under an hour)."""
    total = round(seconds)
    hours, rest = divmod(total, 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours:d}:{minutes:02d}:{secs:02d}" if hours else f"{minutes:d}:{secs:02d}"


def split_every_m(total_m: float) -> float:
    """Split length for the table: 1 km up to 30 km, 5 km up to 150 km, else 10 km."""
    return 1000.0 if total_m <= 30_000.0 else 5000.0 if total_m <= 150_000.0 else 10_000.0


def drawn_indices(n_points: int, limit: int) -> np.ndarray:
    """Indices of at most ``limit`` points spread along the route, first and last included."""
    return np.unique(np.linspace(0, n_points - 1, min(n_points, limit)).round().astype(np.int64))


@dataclasses.dataclass(frozen=True)
class CourseDrawing:
    """The route mapped into the scene: map (east, north) scaled into the framed box, elevation exaggerated."""

    scale: float
    """Scene metres per map metre."""
    offset: np.ndarray
    """(2,) map point drawn at COURSE_CENTRE (m)."""
    base_m: float
    """Elevation drawn at z = 0 (m): the route's lowest point."""

    @staticmethod
    def of(route: course_kernel.Course) -> CourseDrawing:
        east, north = route.east_m, route.north_m
        extent = max(float(np.ptp(east)), float(np.ptp(north)), 1.0)
        centre = np.array([0.5 * (east.min() + east.max()), 0.5 * (north.min() + north.max())])
        return CourseDrawing(scale=COURSE_BOX_M / extent, offset=centre, base_m=float(route.elevation_m.min()))

    def points(self, route: course_kernel.Course, index: np.ndarray, exaggeration: float) -> np.ndarray:
        """(k, 3) scene positions of route points ``index``."""
        xy = (np.stack([route.east_m[index], route.north_m[index]], axis=1) - self.offset) * self.scale
        z = (route.elevation_m[index] - self.base_m) * self.scale * exaggeration + 0.05
        return np.concatenate([xy + COURSE_CENTRE, z[:, None]], axis=1)

    def at_distance(
        self, route: course_kernel.Course, distance_m: np.ndarray, exaggeration: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """(k, 3) scene positions and (k,) yaw angles (rad, from +x) at distances along the route."""
        d = np.clip(distance_m, 0.0, route.total_distance_m)
        east = np.interp(d, route.distance_m, route.east_m)
        north = np.interp(d, route.distance_m, route.north_m)
        z = np.interp(d, route.distance_m, route.elevation_m)
        segment = np.clip(np.searchsorted(route.distance_m, d, side="right") - 1, 0, route.n_points - 2)
        yaw = math.pi / 2 - route.heading_rad[segment]
        xy = (np.stack([east, north], axis=1) - self.offset) * self.scale + COURSE_CENTRE
        zz = (z - self.base_m) * self.scale * exaggeration + 0.05
        return np.concatenate([xy, zz[:, None]], axis=1), yaw


def terrain_strip(points: np.ndarray, half_width: float) -> tuple[np.ndarray, np.ndarray]:
    """A road-side strip along the route and a curtain under it down to z = 0: (4k, 3) vertices and faces.

    The strip is the terrain the road crosses; the curtain shows the height above the valley floor.
    """
    k = points.shape[0]
    direction = np.gradient(points[:, :2], axis=0)
    norm = np.linalg.norm(direction, axis=1, keepdims=True)
    direction = direction / np.where(norm > 1e-12, norm, 1.0)
    side = np.stack([-direction[:, 1], direction[:, 0]], axis=1) * half_width
    top = points[:, 2:3] - 0.03
    left = np.concatenate([points[:, :2] + side, top], axis=1)
    right = np.concatenate([points[:, :2] - side, top], axis=1)
    centre = np.concatenate([points[:, :2], top - 0.01], axis=1)
    foot = centre * [1.0, 1.0, 0.0]
    vertices = np.concatenate([left, right, centre, foot])
    a = np.arange(k - 1)
    b = a + 1
    L, R, C, F = 0, k, 2 * k, 3 * k  # block offsets: left edge, right edge, centre, its foot
    faces = np.concatenate(
        [
            np.stack([L + a, R + a, R + b], axis=1),
            np.stack([L + a, R + b, L + b], axis=1),  # strip
            np.stack([F + a, C + a, C + b], axis=1),
            np.stack([F + a, C + b, F + b], axis=1),  # curtain
        ]
    )
    return vertices.astype(np.float32), faces.astype(np.uint32)


def ground_under(points: np.ndarray, margin: float = 0.6) -> tuple[np.ndarray, np.ndarray]:
    """A thin slab under the route's bounding rectangle plus ``margin`` (scene m): vertices and faces."""
    lo, hi = points[:, :2].min(axis=0) - margin, points[:, :2].max(axis=0) + margin
    slab = trimesh.creation.box(extents=(*(hi - lo), 0.02))
    slab.apply_translation((*((lo + hi) / 2), -0.011))
    return slab.vertices.astype(np.float32), slab.faces.astype(np.uint32)


def grade_colours(grade: np.ndarray) -> np.ndarray:
    """(k, 3) uint8: descents blue, flat white-green, climbs yellow to red at 12 %."""
    g = np.clip(grade / 0.12, -1.0, 1.0)
    up = np.clip(g, 0.0, 1.0)[:, None]
    down = np.clip(-g, 0.0, 1.0)[:, None]
    flat = np.array([90.0, 200.0, 90.0])
    colour = flat + up * (np.array([230.0, 40.0, 30.0]) - flat) + down * (np.array([40.0, 110.0, 230.0]) - flat)
    return colour.astype(np.uint8)
