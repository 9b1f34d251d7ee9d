"""Ride a real course: a GPX route, the speed integrated along it, and the power that rides it in a given time.

A course of N points has per-point arrays of shape (N,) (distance, elevation, map position) and per-segment arrays of
shape (N − 1,) (grade, heading, length); segment i runs from point i to point i + 1. SI units throughout (m, s, kg,
W, rad); headings are compass bearings, clockwise from north, in radians.

**Course.** :func:`load_gpx` reads the track points of a GPX file with gpxpy. Segment lengths on the map are great-circle
(haversine) distances on a sphere of radius 6 371 008.8 m (the IUGG mean Earth radius); headings are the initial
great-circle bearings. GPS elevation is noisy, so it is smoothed by a moving average over a distance window
(``smoothing_m``, 50 m by default); grade is the smoothed rise over the map distance, and the rider travels the
slope length run·√(1 + grade²).

**Ride.** Along each segment the rider's kinetic energy changes by the work of the pedals minus the resistances
(the power terms of :mod:`kernels.cycling`, the seed's or Martin et al. 1998's):

    d(½·M·v²)/ds = η·P/v − F(v),    M = m + I/r² (wheel inertia, Martin model),  F·v = P_wheel(v)

integrated per segment with an implicit midpoint step on the segment's mean speed v̄ = (v₀ + v₁)/2:
½·M·(v₁² − v₀²) = L·(η·P − P_wheel(v̄))/v̄, time L/v̄. The step is stable at any length (a rider starting from rest
or entering a 20 % wall at speed needs no tiny steps), and the energy books balance exactly: the work of the pedals
equals the kinetic energy gained plus aero, rolling, bearing and climbing work plus what the brakes take, which the
tests check over a closed loop. A segment that cannot be crossed in one step is split in halves until it can.
The rider starts from rest (or ``start_speed_ms``) and brakes to hold ``max_speed_ms`` on descents, easing off the
pedals as needed. The wind blows from ``wind_from_deg`` (meteorological convention); each segment feels its
headwind component w = wind·cos(from − heading); the crosswind is ignored (yaw-free CdA).

**Pacing.** :func:`paced_ride` varies power with the grade, more uphill and less downhill at the same time-averaged
power, as Swain (1997, Med. Sci. Sports Exerc. 29:1104) proposed: time is won where the rider is slow.

The integration loop is compiled with numba (``@njit(cache=True)``); the Python wrappers validate every argument
first (ValueError naming it). :func:`warm_up` compiles it ahead of use.
"""

from __future__ import annotations

import codecs
import dataclasses
import math
import os
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Literal

import gpxpy
import gpxpy.gpx
import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from kernels import _checks, cycling

EARTH_RADIUS_M = 6_371_008.8
"""IUGG mean Earth radius (m), for haversine distances."""
MAX_FILE_BYTES = 20 * 1024 * 1024
"""Largest GPX file :func:`load_gpx` reads (20 MiB)."""
MAX_POINTS = 200_000
"""Most track points :func:`load_gpx` accepts."""
SAMPLE_ROUTE = Path(__file__).with_name("routes") / "alpe_dhuez.gpx"
"""The bundled sample: Alpe d'Huez rebuilt from its published profile (see the file's description)."""

Model = Literal["seed", "martin"]
AirKind = Literal["seed", "weather"]


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


_GPX_ROOT = re.compile(r"<(?:([A-Za-z_][\w.-]*):)?gpx[\s>/]")


def load_gpx(
    source: str | os.PathLike[str] | bytes, *, name: str | None = None, smoothing_m: float = 50.0
) -> Course:
    """Read a GPX file's track points (or, when it has no track, its route points) into a :class:`Course`.

    Args:
        source: a path, the file's bytes, or the file's text (a string that starts with ``<``).
        name: course name; default the track's name, else the file name, else "GPX course".
        smoothing_m: elevation moving-average window (m).

    Returns:
        The course, every track segment joined in file order.

    Raises:
        ValueError: with a message a person can act on: the file is larger than 20 MiB, not GPX (or not text),
            has no track points, one point, points without elevation, non-finite or out-of-range values, more
            than 200 000 points, a stretch steeper than :data:`MAX_GPX_GRADE` (50 %), or track segments more than
            :data:`MAX_SEGMENT_GAP_M` (2 km) apart. Nothing else escapes for a bad file.

    The text is decoded by its byte-order mark, else the XML declaration's encoding (ISO-8859-1, UTF-16...),
    else as UTF-8; a namespace prefix on the GPX elements (``<g:gpx xmlns:g=...>``) is read too.
    """
    label = "the file"
    if isinstance(source, bytes):
        if len(source) > MAX_FILE_BYTES:
            raise ValueError(f"the file is {len(source) / 2**20:.1f} MiB; the limit is 20 MiB")
        data = source
    elif isinstance(source, os.PathLike) or (
        isinstance(source, str) and not source.lstrip("\ufeff \t\r\n").startswith("<")
    ):
        path = Path(source)
        label = path.name
        try:
            size = path.stat().st_size
        except OSError as error:
            raise ValueError(f"cannot read {path}: {error.strerror}") from error
        if size > MAX_FILE_BYTES:
            raise ValueError(f"{label} is {size / 2**20:.1f} MiB; the limit is 20 MiB")
        data = path.read_bytes()
    elif isinstance(source, str):
        if len(source) > MAX_FILE_BYTES or len(source.encode("utf-8")) > MAX_FILE_BYTES:
            raise ValueError("the file is larger than the 20 MiB limit")
        data = source.encode("utf-8")
    else:
        raise ValueError(f"source must be a path, bytes or GPX text, got {type(source).__name__}")
    text = _decode(data, label)
    root = _GPX_ROOT.search(text[:4096])
    if root is None:
        raise ValueError(f"{label} is not GPX: no <gpx> element at its start")
    # Count before parsing (gpxpy would build every point first), whatever the namespace prefix.
    prefix = root.group(1)
    tags = ("<trkpt", "<rtept") + ((f"<{prefix}:trkpt", f"<{prefix}:rtept") if prefix else ())
    tagged = sum(text.count(tag) for tag in tags)
    if tagged > MAX_POINTS:
        raise ValueError(f"{label} has {tagged} points; the limit is {MAX_POINTS}")
    if prefix:  # <g:gpx xmlns:g=...>: gpxpy reads only unprefixed names, so drop the prefix
        text = text.replace(f"<{prefix}:", "<").replace(f"</{prefix}:", "</")
    try:
        gpx = gpxpy.parse(text)
    except gpxpy.gpx.GPXException as error:
        raise ValueError(f"{label} is not a valid GPX file: {str(error)[:200]}") from error
    except (ValueError, TypeError, AttributeError, IndexError) as error:
        raise ValueError(f"{label} is not a valid GPX file: {type(error).__name__}") from error

    segments = [
        segment.points for track in gpx.tracks for segment in track.segments if segment.points
    ]
    kind = "track"
    if not segments:
        segments = [route.points for route in gpx.routes if route.points]
        kind = "route"
    points = [p for segment in segments for p in segment]
    if not points:
        raise ValueError(f"{label} has no track points")
    if len(points) > MAX_POINTS:
        raise ValueError(f"{label} has {len(points)} {kind} points; the limit is {MAX_POINTS}")
    if len(points) < 2:
        raise ValueError(f"{label} has only one {kind} point; a course needs two or more")
    missing = sum(p.elevation is None for p in points)
    if missing:
        raise ValueError(
            f"{label}: {missing} of {len(points)} {kind} points have no elevation (<ele>); "
            "export the file with elevation"
        )
    lat = np.array([p.latitude for p in points], dtype=np.float64)
    lon = np.array([p.longitude for p in points], dtype=np.float64)
    ele = np.array([p.elevation for p in points], dtype=np.float64)
    _check_values(label, kind, lat, lon, ele)
    if kind == "track":
        _check_gaps(label, segments)
    title = name or next((t.name for t in gpx.tracks if t.name), None) or gpx.name
    title = title or (label if label != "the file" else "GPX course")
    title = str(title)[:80]
    try:
        result = course_from_points(lat, lon, ele, name=title, smoothing_m=smoothing_m)
    except ValueError as error:  # the builders name the course; a reader is told about the file
        message = str(error).removeprefix(f"{title}: ")
        raise ValueError(f"{label}: {message}") from error
    _check_grades(label, result)
    return result


MAX_GPX_GRADE = 0.5
"""Steepest grade :func:`load_gpx` accepts (50 %), over any stretch of :data:`GRADE_WINDOW_M` (or the whole route
if shorter), raw and smoothed. The steepest paved streets are about 35–37 % (Baldwin Street, Canton Avenue), so a
steeper stretch is a fault in the file (a GPS elevation jump, points logged in one place), not a road."""
GRADE_WINDOW_M = 25.0
"""Stretch over which :data:`MAX_GPX_GRADE` is checked on the raw elevation (m): long enough that ±2 m GPS noise
between points a metre apart stays under 20 %, short enough that a real cliff cannot hide."""
MAX_SEGMENT_GAP_M = 2000.0
"""Largest jump :func:`load_gpx` accepts between the end of one track segment and the start of the next (m)."""

_XML_ENCODING = re.compile(rb"""^<\?xml[^>]*?encoding\s*=\s*["']([A-Za-z0-9._-]+)["']""")


def _decode(data: bytes, label: str) -> str:
    """The file's text: by its byte-order mark, else its XML declaration's encoding, else UTF-8 (XML 1.0 §4.3.3)."""
    for bom, codec in (
        (codecs.BOM_UTF32_LE, "utf-32"), (codecs.BOM_UTF32_BE, "utf-32"), (codecs.BOM_UTF8, "utf-8-sig"),
        (codecs.BOM_UTF16_LE, "utf-16"), (codecs.BOM_UTF16_BE, "utf-16"),
    ):  # fmt: skip
        if data.startswith(bom):
            encoding = codec
            break
    else:
        declared = _XML_ENCODING.match(data[:200])
        encoding = declared.group(1).decode("ascii") if declared else "utf-8"
        try:
            codecs.lookup(encoding)
        except LookupError as error:
            raise ValueError(f"{label} declares an unknown text encoding {encoding!r}") from error
    try:
        text = data.decode(encoding)
    except (UnicodeDecodeError, ValueError) as error:
        raise ValueError(f"{label} is not GPX: it is not text in {encoding.upper()}") from error
    # The text is decoded now: the declaration's encoding must not be applied a second time by the XML parser.
    return re.sub(
        r"""^(\ufeff?<\?xml[^>]*?)\s+encoding\s*=\s*["'][^"']*["']""", r"\1", text, count=1
    )


def _check_values(
    label: str,
    kind: str,
    lat: NDArray[np.float64],
    lon: NDArray[np.float64],
    ele: NDArray[np.float64],
) -> None:
    """Refuse a point that is not on the map, in words a rider reads (point numbers from 1, as in the file)."""
    for values, what, limit, unit in (
        (lat, "latitude", 90.0, "°"), (lon, "longitude", 180.0, "°"), (ele, "elevation", 10_000.0, " m"),
    ):  # fmt: skip
        bad = ~np.isfinite(values)
        if np.any(bad):
            first = int(np.argmax(bad))
            raise ValueError(
                f"{label}: {kind} point {first + 1} has {what} {values[first]}, not a number; "
                f"{int(bad.sum())} point(s) like it"
            )
        out = np.abs(values) > limit
        if np.any(out):
            first = int(np.argmax(out))
            raise ValueError(
                f"{label}: {kind} point {first + 1} has {what} {values[first]:g}{unit}, outside "
                f"±{_spaced(limit)}{unit}"
            )


def _check_gaps(
    label: str, segments: Sequence[Sequence[gpxpy.gpx.GPXTrackPoint | gpxpy.gpx.GPXRoutePoint]]
) -> None:
    """Refuse tracks or segments that do not follow on: the route would jump across the map."""
    for i in range(1, len(segments)):
        a, b = segments[i - 1][-1], segments[i][0]
        gap = _great_circle_m(a.latitude, a.longitude, b.latitude, b.longitude)
        if gap > MAX_SEGMENT_GAP_M:
            raise ValueError(
                f"{label}: track segment {i + 1} starts {_km(gap)} from where segment {i} ends "
                f"(at most {MAX_SEGMENT_GAP_M / 1000:.0f} km is joined); load the pieces as separate files"
            )


def _great_circle_m(lat1: float, lon1: float, lat2: float, lon2: float) -> float:
    """Haversine distance (m) between two points (°)."""
    p1, p2 = math.radians(lat1), math.radians(lat2)
    a = (
        math.sin((p2 - p1) / 2) ** 2
        + math.cos(p1) * math.cos(p2) * math.sin(math.radians(lon2 - lon1) / 2) ** 2
    )
    return 2.0 * EARTH_RADIUS_M * math.asin(math.sqrt(min(max(a, 0.0), 1.0)))


def _spaced(number: float, digits: int = 0) -> str:
    """12 345.6 style: thousands apart by a space."""
    return f"{number:,.{digits}f}".replace(",", " ")


def _km(metres: float) -> str:
    return f"{_spaced(metres / 1000, 1)} km"


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


def _check_grades(label: str, route: Course) -> None:
    """Refuse a profile steeper than any road (:data:`MAX_GPX_GRADE`), before smoothing can hide it."""
    grade, first = steepest_grade(route.distance_m, route.elevation_raw_m, GRADE_WINDOW_M)
    smoothed = float(np.max(np.abs(route.grade)))
    if max(grade, smoothed) > MAX_GPX_GRADE:
        if smoothed > grade:
            first = int(np.argmax(np.abs(route.grade)))
        at = route.distance_m[first]
        raise ValueError(
            f"{label}: the elevation changes {_spaced(100 * max(grade, smoothed))} % of the distance near "
            f"{at / 1000:.2f} km; no road is steeper than about 40 % (the limit is "
            f"{100 * MAX_GPX_GRADE:.0f} %), so the file's elevation or positions are wrong"
        )


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
    """Fraction of pedal power reaching the wheel, (0, 1]; Martin et al. 1998's 0.976."""
    model: Model = "martin"
    """``"seed"``: aero, rolling, climbing; ``"martin"``: Martin et al. 1998's terms."""
    spoke_drag_m2: float = 0.0044
    """Martin's F_w (m², ≥ 0)."""
    wheel_inertia_kgm2: float = 0.14
    """Both wheels' moment of inertia (kg·m², ≥ 0)."""
    wheel_radius_m: float = 0.311
    """Tyre radius (m, > 0)."""

    def __post_init__(self) -> None:
        for key in ("cda_m2", "mass_kg", "wheel_radius_m"):
            value = getattr(self, key)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0.0):
                raise ValueError(f"{key} must be a finite number > 0, got {value!r}")
        for key in ("crr", "spoke_drag_m2", "wheel_inertia_kgm2"):
            value = getattr(self, key)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0.0):
                raise ValueError(f"{key} must be a finite number >= 0, got {value!r}")
        eta = self.drivetrain_efficiency
        if not (isinstance(eta, (int, float)) and 0.0 < eta <= 1.0):
            raise ValueError(f"drivetrain_efficiency must be in (0, 1], got {eta!r}")
        if self.model not in ("seed", "martin"):
            raise ValueError(f"model must be 'seed' or 'martin', got {self.model!r}")

    @property
    def effective_mass_kg(self) -> float:
        """m + I/r² under the Martin model (the wheels' spin stores energy too), m under the seed's."""
        if self.model == "martin":
            return self.mass_kg + self.wheel_inertia_kgm2 / self.wheel_radius_m**2
        return self.mass_kg


@dataclasses.dataclass(frozen=True)
class Air:
    """Air along the route: the seed's exponential atmosphere, or a weather reading taken at one altitude.

    ``"weather"``: the reading (temperature, station pressure, humidity at ``altitude_m``) is carried along the
    route by the standard atmosphere: temperature falls 6.5 K/km, pressure follows the ISA ratio
    p_ISA(h)/p_ISA(h_ref), relative humidity stays. Density by :func:`kernels.cycling.air_density_weather`.
    """

    kind: AirKind = "seed"
    temperature_c: float = 15.0
    """Air temperature at ``altitude_m`` (°C)."""
    pressure_hpa: float = 1013.25
    """Station pressure at ``altitude_m`` (hPa)."""
    relative_humidity: float = 0.0
    """Relative humidity, a fraction in [0, 1]."""
    altitude_m: float = 0.0
    """Where the reading was taken (m)."""

    def __post_init__(self) -> None:
        if self.kind not in ("seed", "weather"):
            raise ValueError(f"kind must be 'seed' or 'weather', got {self.kind!r}")
        cycling.air_density_weather(self.temperature_c, self.pressure_hpa, self.relative_humidity)
        cycling.isa_pressure_hpa(self.altitude_m)

    def density(self, elevation_m: ArrayLike) -> NDArray[np.float64]:
        """Air density (kg/m³) at each elevation (m, any shape)."""
        h = np.asarray(elevation_m, dtype=np.float64)
        match self.kind:
            case "seed":
                return cycling.air_density(h)
            case "weather":
                temperature = self.temperature_c - cycling.ISA_LAPSE_RATE_K_PER_M * (
                    h - self.altitude_m
                )
                pressure = (
                    self.pressure_hpa
                    * cycling.isa_pressure_hpa(h)
                    / cycling.isa_pressure_hpa(self.altitude_m)
                )
                return cycling.air_density_weather(
                    np.clip(temperature, -60.0, 60.0),
                    np.clip(pressure, 10.0, 1100.0),
                    self.relative_humidity,
                )
            case _:
                raise ValueError(f"kind must be 'seed' or 'weather', got {self.kind!r}")


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

    @property
    def average_speed_ms(self) -> float:
        return float(self.distance_m[-1]) / self.time_s

    @property
    def average_power_w(self) -> float:
        """Time-averaged pedal power (W), what a power meter shows for the ride."""
        return self.work_j / self.time_s

    def splits(self, every_m: float = 1000.0) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(marks, elapsed): the elapsed time (s) at every ``every_m`` metres and at the finish."""
        if not (math.isfinite(every_m) and every_m > 0.0):
            raise ValueError(f"every_m must be finite and > 0, got {every_m!r}")
        total = float(self.distance_m[-1])
        marks = np.arange(every_m, total, every_m)
        if marks.shape[0] > 10_000:
            raise ValueError("every_m gives more than 10 000 splits")
        marks = np.concatenate((marks, [total]))
        return marks, np.interp(marks, self.distance_m, self.elapsed_s)


_E_WORK, _E_AERO, _E_ROLL, _E_BEAR, _E_CLIMB, _E_BRAKE = range(6)
_REFINE_RATIO = 0.5
"""A step that changes the speed by more than this fraction is redone in halves (up to _REFINE_UP_TO)."""
_REFINE_UP_TO = 64


@numba.njit(cache=True)
def _wheel_power(v, drag, rolling, climbing, wind, b0, b1):  # pragma: no cover - compiled
    """P_wheel(v) (W): the sum of :func:`kernels.cycling.wheel_power_terms`, the one power law, compiled."""
    aero, roll, bearings, climb = cycling.wheel_power_terms_compiled(
        v, drag, rolling, climbing, wind, b0, b1
    )
    return aero + roll + bearings + climb


@numba.njit(cache=True)
def _step(v0, length, drag, rolling, climbing, wind, power_in, mass, b0, b1):  # pragma: no cover
    """Mean speed v̄ ≥ v0/2 solving 2M(v̄ − v0)v̄² + L·(P_wheel(v̄) − P_in) = 0; −1 when none exists."""
    force = rolling + climbing
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
    q_x = 2.0 * mass * (x - v0) * x * x + length * (
        _wheel_power(x, drag, rolling, climbing, wind, b0, b1) - power_in
    )
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
        air = x + wind
        q = 2.0 * mass * (x - v0) * x * x + length * (
            _wheel_power(x, drag, rolling, climbing, wind, b0, b1) - power_in
        )
        if q <= 0.0:
            lo = x
        else:
            hi = x
        dq = 2.0 * mass * (3.0 * x * x - 2.0 * v0 * x) + length * (
            drag * (2.0 * abs(air) * x + air * abs(air)) + force + b0 + 2.0 * b1 * x
        )
        step_ok = dq > 0.0
        nxt = x - q / dq if step_ok else 0.5 * (lo + hi)
        if not (lo < nxt < hi):
            nxt = 0.5 * (lo + hi)
        if abs(nxt - x) <= 1e-13 * (1.0 + x) or hi - lo <= 1e-13 * (1.0 + hi):
            return nxt
        x = nxt
    return x


@numba.njit(cache=True)
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
    energy,
):  # pragma: no cover - compiled
    """Integrate every segment; fills speed/elapsed (N,), power_out (N − 1,) and energy (6,). Returns 0 or the
    1-based index of a segment that could not be crossed."""
    v0 = v_start
    t = 0.0
    speed[0] = v0
    elapsed[0] = 0.0
    for i in range(length.shape[0]):
        # From rest v grows as s^(1/3) (v³ = 3ηP·s/M): cubically graded sub-steps follow it.
        graded = v0 == 0.0
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
                if (
                    not graded
                    and n_sub < _REFINE_UP_TO
                    and abs(v1 - v) > _REFINE_RATIO * max(v, v1)
                ):
                    ok = False  # an abrupt change of speed (a wall, a crest): finer steps, for accuracy
                    break
                rider_in = p_in
                if v1 > v_cap:
                    v1 = v_cap
                    vb = 0.5 * (v + v1)
                    need = (
                        2.0 * mass * (vb - v) * vb * vb
                        + sub * _wheel_power(vb, drag[i], rolling[i], climbing[i], wind[i], b0, b1)
                    ) / sub
                    rider_in = min(max(need, 0.0), p_in)
                    brake += (rider_in - need) * sub / vb
                dt = sub / vb
                p_aero, p_roll, p_bear, _ = cycling.wheel_power_terms_compiled(
                    vb, drag[i], rolling[i], climbing[i], wind[i], b0, b1
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
    return 0


_MIN_POWER_W, _MAX_POWER_W = 1.0, 5000.0


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


def _segments(
    course: Course, rider: Rider, wind_ms: float, wind_from_deg: float, air: Air
) -> _Segments:
    if not isinstance(course, Course):
        raise ValueError(f"course must be a Course, got {type(course).__name__}")
    if not isinstance(rider, Rider):
        raise ValueError(f"rider must be a Rider, got {type(rider).__name__}")
    if not isinstance(air, Air):
        raise ValueError(f"air must be an Air, got {type(air).__name__}")
    wind = _checks.finite_number("wind_ms", wind_ms)
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
    try:
        power = np.asarray(power_w, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise ValueError(
            f"power_w must be a number or an array of numbers, got {power_w!r}"
        ) from error
    if power.ndim == 0:
        power = np.full(n_segments, float(power))
    if power.shape != (n_segments,):
        raise ValueError(
            f"power_w must be a number or shape ({n_segments},), got shape {power.shape}"
        )
    if not np.all(np.isfinite(power)) or np.any(power <= 0.0):
        raise ValueError("power_w must be finite and > 0 (W)")
    return np.ascontiguousarray(power)


def _ride(
    course: Course, power: NDArray[np.float64], s: _Segments, max_speed: float, start: float
) -> Ride:
    n = course.n_points
    speed, elapsed = np.empty(n), np.empty(n)
    power_out, energy = np.empty(n - 1), np.zeros(6)
    failed = _ride_core(
        s.length, s.drag, s.rolling, s.climbing, s.wind, power, s.efficiency, s.mass, s.b0, s.b1,
        max_speed, start, speed, elapsed, power_out, energy,
    )  # fmt: skip
    if failed:
        raise ValueError(f"the rider cannot cross segment {failed - 1} at this power")
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
    )


def _speeds(max_speed_ms: float, start_speed_ms: float) -> tuple[float, float]:
    cap = _checks.positive("max_speed_ms", max_speed_ms)
    start = _checks.finite_number("start_speed_ms", start_speed_ms)
    if start < 0.0 or start > cap:
        raise ValueError(f"start_speed_ms must be in [0, max_speed_ms], got {start_speed_ms!r}")
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
        power_w: pedal power (W, > 0): one number, or (N − 1,) one per segment.
        rider: rider, bike and model.
        wind_ms: wind speed (m/s; negative reverses it).
        wind_from_deg: where the wind blows from, clockwise from north (°): 0 is a north wind.
        air: air density along the route.
        max_speed_ms: safe descending speed (m/s, > 0; 20 m/s = 72 km/h); the rider brakes to hold it.
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
) -> float:
    """The constant pedal power that rides ``course`` in ``time_s``: the inverse of :func:`ride`.

    The finish time falls strictly as power rises, so the root is unique; it is found by a safeguarded secant
    method on log(time) against log(power) (close to a straight line: P ∝ v³ on the flat, ∝ v on a climb),
    between 1 W and 5000 W; typically 4–6 rides.

    Args:
        time_s: target finish time (s, > 0).
        tolerance_s: how close the ride's time must come (s, > 0).
        Other arguments as for :func:`ride`.

    Returns:
        Power (W).

    Raises:
        ValueError: an argument is invalid, or the time is out of reach (faster than 5000 W rides it, or slower
            than 1 W); the message says which.
    """
    target = _checks.positive("time_s", time_s)
    tol = _checks.positive("tolerance_s", tolerance_s)
    s = _segments(course, rider, wind_ms, wind_from_deg, air)
    cap, start = _speeds(max_speed_ms, start_speed_ms)
    n = course.n_points - 1

    def time_at(power: float) -> float:
        return _ride(course, np.full(n, power), s, cap, start).time_s

    lo_p, hi_p = _MIN_POWER_W, _MAX_POWER_W
    # Secant steps on f(x) = log t(eᵡ) − log target (x = log P), which is close to a straight line of slope
    # −1/3 (flat) to −1 (climb). Start from 250 W and a slope of −1/2; once the root is bracketed every step stays
    # inside the bracket (bisection when a secant step would leave it).
    x_lo, f_lo, x_hi, f_hi = -math.inf, math.inf, math.inf, -math.inf
    x, slope = math.log(250.0), -0.5
    x_prev, f_prev = math.nan, math.nan
    for _ in range(60):
        t = time_at(math.exp(x))
        if abs(t - target) <= tol:
            return math.exp(x)
        f = math.log(t / target)
        if f > 0.0:
            x_lo, f_lo = x, f
        else:
            x_hi, f_hi = x, f
        if math.isfinite(x_lo) and math.isfinite(x_hi):
            nxt = x_lo - f_lo * (x_hi - x_lo) / (f_hi - f_lo)
            if not (x_lo < nxt < x_hi) or x_hi - x_lo < 1e-12:
                nxt = 0.5 * (x_lo + x_hi)
        else:
            if math.isfinite(x_prev) and x_prev != x and (f - f_prev) / (x - x_prev) < 0.0:
                slope = (f - f_prev) / (x - x_prev)
            nxt = x - f / slope
            if nxt > math.log(hi_p):
                if x >= math.log(hi_p) or time_at(hi_p) > target + tol:
                    raise ValueError(
                        f"time_s {target:.1f} s is out of reach: it needs more than {hi_p:.0f} W"
                    )
                nxt = math.log(hi_p)
            elif nxt < math.log(lo_p):
                if x <= math.log(lo_p) or time_at(lo_p) < target - tol:
                    raise ValueError(
                        f"time_s {target:.1f} s is out of reach: even {lo_p:.0f} W rides it faster"
                    )
                nxt = math.log(lo_p)
        x_prev, f_prev = x, f
        x = nxt
    return math.exp(x)


@dataclasses.dataclass(frozen=True)
class Pacing:
    """A paced ride next to the constant-power ride at the same time-averaged power."""

    constant: Ride
    paced: Ride
    time_saved_s: float
    """constant.time_s − paced.time_s (s); positive when pacing is faster."""


def pacing_factors(grade: ArrayLike, gain: float) -> NDArray[np.float64]:
    """Relative power per segment: 1 + gain·tanh(grade / 0.05), more uphill, less downhill (unnormalised)."""
    return 1.0 + gain * np.tanh(np.asarray(grade, dtype=np.float64) / 0.05)


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

    Segment i gets P_i = k·(1 + gain·tanh(grade_i / 0.05)): up to ``gain`` more on steep climbs and less on
    descents, and k is set (a few fixed-point rescalings) so that the paced ride's time-averaged power
    Σ P_i·t_i / Σ t_i equals the constant ride's (what a power meter would show for both rides; that is
    ``power_w`` unless the constant ride eased off to hold the speed cap).

    Args:
        power_w: the constant ride's power and the paced ride's time-averaged power (W, > 0).
        gain: how strongly power follows the grade (0 to 0.5; 0 is constant power).
        Other arguments as for :func:`ride`.

    Returns:
        :class:`Pacing` with both rides and the time saved.

    Raises:
        ValueError: an argument is invalid (the message names it).
    """
    target = _checks.positive("power_w", power_w)
    g = _checks.finite_number("gain", gain)
    if not 0.0 <= g <= 0.5:
        raise ValueError(f"gain must be in [0, 0.5], got {gain!r}")
    s = _segments(course, rider, wind_ms, wind_from_deg, air)
    cap, start = _speeds(max_speed_ms, start_speed_ms)
    n = course.n_points - 1
    constant = _ride(course, np.full(n, target), s, cap, start)
    shape = pacing_factors(course.grade, g)
    # Match what the constant ride really averaged: where it eases off to hold the speed cap it is below target.
    average = constant.average_power_w
    scale = target
    paced = constant
    for _ in range(30):
        paced = _ride(course, scale * shape, s, cap, start)
        ratio = average / paced.average_power_w
        scale *= ratio
        if abs(ratio - 1.0) < 1e-9:
            break
    return Pacing(constant=constant, paced=paced, time_saved_s=constant.time_s - paced.time_s)


def warm_up() -> None:
    """Compile (or load from numba's cache) the ride loop now, so the first real ride is fast."""
    course = course_from_xy([0.0, 10.0, 20.0], [0.0, 0.0, 0.0], [0.0, 0.5, 0.0])
    ride(course, 200.0)
