"""A route as arrays: :class:`Course`, built from geographic points or a flat map, its elevation smoothed and checked.

A course of N points has per-point arrays of shape (N,) (distance, elevation, map position) and per-segment arrays of
shape (N − 1,) (grade, heading, length); segment i runs from point i to point i + 1. SI units (m, rad); headings are
compass bearings, clockwise from north. Map lengths are haversine distances on a sphere of radius 6 371 008.8 m (the
IUGG mean Earth radius) with initial great-circle bearings (Sinnott 1984, Sky & Telescope 68:159); map positions are
the azimuthal equidistant projection about the route's centroid (Snyder 1987, USGS Prof. Paper 1395). Elevation is
smoothed by a moving average over a distance window; grade is the smoothed rise over the map distance.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

EARTH_RADIUS_M = 6_371_008.8
"""IUGG mean Earth radius (m), for haversine distances."""
MAX_POINTS = 200_000
"""Most points a course may have; :func:`kernels.course.gpx.load_gpx` counts a file's points against it first."""


# --------------------------------------------------------------------------------------------- course
@dataclasses.dataclass(frozen=True)
class Course:
    """A route: N points along the road, leader of every per-segment array at the segment's start."""

    name: str
    """Name from the file (or given)."""
    east_m: NDArray[np.float64]
    """(N,) map position east of the first point (m), azimuthal equidistant about the route's centroid (true
    shape at any place on Earth); for drawing."""
    north_m: NDArray[np.float64]
    """(N,) map position north of the first point (m)."""
    distance_m: NDArray[np.float64]
    """(N,) distance along the ground (map distance) from the start (m); starts at 0, strictly increasing."""
    elevation_m: NDArray[np.float64]
    """(N,) smoothed elevation (m)."""
    elevation_raw_m: NDArray[np.float64]
    """(N,) elevation as read (m)."""
    grade: NDArray[np.float64]
    """(N − 1,) rise over run of each segment, from the smoothed elevation."""
    heading_rad: NDArray[np.float64]
    """(N − 1,) direction of travel on each segment, clockwise from north (rad, [0, 2π))."""

    @property
    def n_points(self) -> int:
        return int(self.distance_m.shape[0])

    @property
    def run_m(self) -> NDArray[np.float64]:
        """(N − 1,) map length of each segment (m)."""
        return np.diff(self.distance_m)

    @property
    def length_m(self) -> NDArray[np.float64]:
        """(N − 1,) length along the slope of each segment (m): run·√(1 + grade²)."""
        return self.run_m * np.sqrt(1.0 + self.grade**2)

    @property
    def total_distance_m(self) -> float:
        return float(self.distance_m[-1])

    @property
    def climbing_m(self) -> float:
        """Total ascent of the smoothed profile (m)."""
        return float(np.sum(np.maximum(np.diff(self.elevation_m), 0.0)))


def _smooth(
    distance: NDArray[np.float64], z: NDArray[np.float64], window_m: float
) -> NDArray[np.float64]:
    """Moving average of the piecewise-linear profile z(s) over [s − h, s + h] ∩ route, h = window/2."""
    if window_m <= 0.0 or distance.shape[0] < 3:
        return z.copy()
    integral = np.concatenate(([0.0], np.cumsum(np.diff(distance) * 0.5 * (z[1:] + z[:-1]))))
    half = 0.5 * window_m
    lo = np.maximum(distance - half, distance[0])
    hi = np.minimum(distance + half, distance[-1])
    return (np.interp(hi, distance, integral) - np.interp(lo, distance, integral)) / (hi - lo)


def _checked_points(
    name: str, arrays: dict[str, ArrayLike], n_min: int = 2
) -> dict[str, NDArray[np.float64]]:
    """(N,) arrays of one length, finite, n_min ≤ N ≤ MAX_POINTS; else ValueError.

    Kept here rather than in :mod:`kernels._checks`: a route's messages say how many points are bad and where the
    first is, prefixed with the course name, which :func:`load_gpx` rewrites into words about the file.
    """
    out: dict[str, NDArray[np.float64]] = {}
    shape = None
    for key, value in arrays.items():
        try:
            array = np.asarray(value, dtype=np.float64)
        except (TypeError, ValueError) as error:
            raise ValueError(f"{key} must be an array of numbers") from error
        if array.ndim != 1:
            raise ValueError(f"{key} must be one-dimensional, got shape {array.shape}")
        if shape is not None and array.shape != shape:
            raise ValueError(f"{key} has shape {array.shape}, the other arrays {shape}")
        shape = array.shape
        bad = ~np.isfinite(array)
        if np.any(bad):
            raise ValueError(
                f"{name}: {key} has {int(bad.sum())} non-finite value(s), first at point {int(np.argmax(bad))}"
            )
        out[key] = array
    assert shape is not None
    if shape[0] < n_min:
        raise ValueError(f"{name}: needs at least {n_min} points, got {shape[0]}")
    if shape[0] > MAX_POINTS:
        raise ValueError(f"{name}: {shape[0]} points is more than {MAX_POINTS}")
    return out


def _finish(
    name: str,
    east: NDArray[np.float64],
    north: NDArray[np.float64],
    run: NDArray[np.float64],
    heading: NDArray[np.float64],
    elevation: NDArray[np.float64],
    smoothing_m: float,
) -> Course:
    if not (math.isfinite(smoothing_m) and smoothing_m >= 0.0):
        raise ValueError(f"smoothing_m must be finite and >= 0, got {smoothing_m!r}")
    if np.any(np.abs(elevation) > 10_000.0):
        raise ValueError(f"{name}: elevation outside ±10 000 m")
    # Points at one place (a paused GPS logs many) carry no distance: keep the first of each run.
    keep = np.concatenate(([True], run > 1e-6))
    if int(keep.sum()) < 2:
        raise ValueError(f"{name}: every point is at one place; a course needs two distinct points")
    seg_keep = keep[1:]
    east, north, elevation = east[keep], north[keep], elevation[keep]
    # Lengths of the merged segments: the dropped zero-length ones add nothing.
    run, heading = run[seg_keep], heading[seg_keep]
    distance = np.concatenate(([0.0], np.cumsum(run)))
    smoothed = _smooth(distance, elevation, smoothing_m)
    grade = np.diff(smoothed) / run
    for array in (east, north, distance, smoothed, elevation, grade, heading):
        array.setflags(write=False)
    return Course(
        name=name,
        east_m=east,
        north_m=north,
        distance_m=distance,
        elevation_m=smoothed,
        elevation_raw_m=elevation,
        grade=grade,
        heading_rad=heading,
    )


def course_from_points(
    latitude_deg: ArrayLike,
    longitude_deg: ArrayLike,
    elevation_m: ArrayLike,
    name: str = "course",
    smoothing_m: float = 50.0,
) -> Course:
    """Build a :class:`Course` from geographic points (what :func:`load_gpx` does after parsing).

    Args:
        latitude_deg: (N,) latitude (°, −90 to 90).
        longitude_deg: (N,) longitude (°, −180 to 180).
        elevation_m: (N,) elevation (m).
        name: course name.
        smoothing_m: width of the elevation moving-average window (m, ≥ 0; 0 keeps the raw profile).

    Raises:
        ValueError: fewer than two distinct points, non-finite or out-of-range values; the message says which.
    """
    p = _checked_points(
        name,
        {"latitude_deg": latitude_deg, "longitude_deg": longitude_deg, "elevation_m": elevation_m},
    )
    lat, lon = p["latitude_deg"], p["longitude_deg"]
    if np.any(np.abs(lat) > 90.0):
        raise ValueError(f"{name}: latitude_deg outside [-90, 90]")
    if np.any(np.abs(lon) > 180.0):
        raise ValueError(f"{name}: longitude_deg outside [-180, 180]")
    phi, lam = np.radians(lat), np.radians(lon)
    d_phi, d_lam = np.diff(phi), np.diff(lam)
    d_lam = (d_lam + np.pi) % (2.0 * np.pi) - np.pi  # across the antimeridian
    # Haversine distance and initial bearing (e.g. Sinnott 1984, Sky & Telescope 68:159).
    a = np.sin(d_phi / 2) ** 2 + np.cos(phi[:-1]) * np.cos(phi[1:]) * np.sin(d_lam / 2) ** 2
    run = 2.0 * EARTH_RADIUS_M * np.arcsin(np.sqrt(np.clip(a, 0.0, 1.0)))
    heading = np.arctan2(
        np.sin(d_lam) * np.cos(phi[1:]),
        np.cos(phi[:-1]) * np.sin(phi[1:]) - np.sin(phi[:-1]) * np.cos(phi[1:]) * np.cos(d_lam),
    ) % (2.0 * np.pi)
    east, north = azimuthal_equidistant(lat, lon)
    return _finish(name, east, north, run, heading, p["elevation_m"], smoothing_m)


def azimuthal_equidistant(
    latitude_deg: NDArray[np.float64], longitude_deg: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Map positions (east, north) in m, the first point at the origin, for drawing a route in its true shape.

    The azimuthal equidistant projection (Snyder 1987, USGS Prof. Paper 1395, §25) on the sphere about the route's
    centroid (the normalised mean of the points' unit vectors; the first point where that mean vanishes):
    distances and directions from the centre are exact, and a route a few hundred km across keeps its shape to
    a fraction of a percent, over a pole or the antimeridian as anywhere else. (N,) inputs in degrees.
    """
    phi, lam = np.radians(latitude_deg), np.radians(longitude_deg)
    unit = np.stack([np.cos(phi) * np.cos(lam), np.cos(phi) * np.sin(lam), np.sin(phi)], axis=1)
    mean = unit.mean(axis=0)
    norm = float(np.linalg.norm(mean))
    centre = mean / norm if norm > 1e-9 else unit[0]
    # Local east and north at the centre (at a pole, "north" is along longitude 180°, east along 90°).
    up = np.array([0.0, 0.0, 1.0])
    east_axis = np.cross(up, centre)
    if float(np.linalg.norm(east_axis)) < 1e-12:
        east_axis = np.array([0.0, 1.0, 0.0])
    east_axis /= np.linalg.norm(east_axis)
    north_axis = np.cross(centre, east_axis)
    x, y, z = unit @ east_axis, unit @ north_axis, unit @ centre
    angle = np.arctan2(np.hypot(x, y), z)  # great-circle angle from the centre
    sideways = np.hypot(x, y)
    k = np.where(sideways > 1e-15, angle / np.where(sideways > 1e-15, sideways, 1.0), 1.0)
    east, north = EARTH_RADIUS_M * k * x, EARTH_RADIUS_M * k * y
    return east - east[0], north - north[0]


def course_from_xy(
    east_m: ArrayLike,
    north_m: ArrayLike,
    elevation_m: ArrayLike,
    name: str = "course",
    smoothing_m: float = 0.0,
) -> Course:
    """Build a :class:`Course` on a flat map (synthetic routes, tests, benchmarks).

    Args:
        east_m, north_m: (N,) map position (m).
        elevation_m: (N,) elevation (m).
        name: course name.
        smoothing_m: elevation moving-average window (m, ≥ 0); 0 (the default) keeps the profile as given.

    Raises:
        ValueError: as :func:`course_from_points`.
    """
    p = _checked_points(name, {"east_m": east_m, "north_m": north_m, "elevation_m": elevation_m})
    east, north = p["east_m"], p["north_m"]
    d_east, d_north = np.diff(east), np.diff(north)
    run = np.hypot(d_east, d_north)
    heading = np.arctan2(d_east, d_north) % (2.0 * np.pi)
    return _finish(name, east, north, run, heading, p["elevation_m"], smoothing_m)


def steepest_grade(
    distance_m: ArrayLike, elevation_m: ArrayLike, window_m: float
) -> tuple[float, int]:
    """Largest |rise| / run over the stretches from each point to the first point at least ``window_m`` further on
    (the whole route when it is shorter). A cliff anywhere lies inside one such stretch, so no moving average can
    hide it. Returns the grade and the stretch's first point. (N,) inputs, distance strictly increasing (m)."""
    distance_m = np.asarray(distance_m, dtype=np.float64)
    elevation_m = np.asarray(elevation_m, dtype=np.float64)
    n = distance_m.shape[0]
    end = np.searchsorted(distance_m, distance_m + window_m, side="left")
    full = end < n
    if np.any(full):
        start, end = np.flatnonzero(full), end[full]
    else:
        start, end = np.array([0]), np.array([n - 1])
    grade = np.abs(elevation_m[end] - elevation_m[start]) / (distance_m[end] - distance_m[start])
    k = int(np.argmax(grade))
    return float(grade[k]), int(start[k])
