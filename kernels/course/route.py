"""A route as arrays: :class:`Course`, built from geographic points or a flat map, its elevation smoothed and checked.

A course of N points has per-point arrays of shape (N,) (distance, elevation, map position) and per-segment arrays of
shape (N − 1,) (grade, heading, length); segment i runs from point i to point i + 1. SI units (m, rad); headings are
compass bearings, clockwise from north. Map lengths are haversine distances on a sphere of radius 6 371 008.8 m (the
IUGG mean Earth radius) with initial great-circle bearings (Sinnott 1984, Sky & Telescope 68:159); map positions are
the azimuthal equidistant projection about the route's centroid (Snyder 1987, USGS Prof. Paper 1395). Elevation is
smoothed by a moving average over a distance window; within half a window of an end, by the least-squares line
over that end's first whole window (Savitzky & Golay 1964, order 1, as scipy's ``savgol_filter`` at its edges), so
a steady climb keeps its grade and its first and last heights. Grade is the smoothed rise over the map distance.
:func:`~kernels.course.load_gpx` smooths a noisy file over a window that grows with its noise
(:func:`noise_smoothing_m`).

**Total ascent.** Summing every rise of a GPS profile counts its noise: on a flat 10 km road logged every 5 m with
1.5 m of elevation noise the rises add up to over 100 m. :func:`total_ascent` counts climbs the way OsmAnd
(``ElevationDiffsCalculator``, a 7 m threshold; osmand.net "Calculation of uphill / downhill / slope") and Strava
(support article "Elevation Gain": smoothed data, "a gain must exceed a threshold") describe theirs: it takes out
spikes (a point farther from the median of its five neighbours than a road's steepest grade allows), smooths the
profile over :data:`ASCENT_WINDOW_M`, and counts a climb only once the profile has risen :data:`ASCENT_THRESHOLD_M`
above its last low (hysteresis), from that low to the next high. Climbs smaller than the threshold are not counted.
The ride does not use it: the work of climbing telescopes to m·g·(end − start) on any profile, so noise adds no net
climbing work there.
"""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from kernels import _checks

EARTH_RADIUS_M = 6_371_008.8
"""IUGG mean Earth radius (m), for haversine distances."""
MAX_POINTS = 200_000
"""Most points a course may have; :func:`kernels.course.gpx.load_gpx` counts a file's points against it first."""
ASCENT_THRESHOLD_M = 5.0
"""Rise a climb must make above its last low before :func:`total_ascent` counts it (m). OsmAnd uses 7 m on raw GPS
tracks; after the :data:`ASCENT_WINDOW_M` moving average, 2 m of GPS noise on points up to 10 m apart leaves
swings under 5 m, so 5 m loses fewer real rollers."""
ASCENT_WINDOW_M = 100.0
"""Moving-average window for :func:`total_ascent` (m): at least ten points of a 1 s log at up to 36 km/h, and
under 0.5 % off the height of a hill 2 km long."""
SMOOTHING_FLOOR_M = 0.01
"""Shortest moving-average window that smooths (m); a shorter one (or one under a billionth of the distances' own
magnitude, where their rounding would swamp it) keeps the profile as given. A window h moves a point by at most
h/8 times the change of grade there, under 2 mm for any road below 1 cm, while the average's rounding grows as 1/h:
at 1e-10 m it was metres, and at 1e-300 m every value was 0/0."""
NOISE_WINDOW_PER_M = 32.0
"""Metres of window per metre of a profile's point-to-point elevation noise σ (:func:`elevation_noise_m`), over
which a noisy GPX file's grade is checked and its profile smoothed (:func:`noise_smoothing_m`): the largest of ~10⁵
differences of two noisy samples is about 4.5·√2·σ, and a moving average's grade from one point to the next
spreads by √2·σ / window, so this keeps either under 20 %."""
MIN_ELEVATION_M, MAX_ELEVATION_M = -10_000.0, 10_000.0
"""Elevations a course may have (m): ±10 km, past any road (Everest is 8 849 m, the Dead Sea's shore −430 m)."""
ASCENT_SPIKE_GRADE = 0.5
"""A point farther from its neighbours' median than this grade times their reach is a spike (the steepest roads are
about 37 %), replaced by that median before :func:`total_ascent` smooths; a real road's profile is never touched."""


_MAX_DISTANCE_M = 1e15
"""Largest distance :func:`total_ascent` and :func:`steepest_grade` take (m): far past any route, and their sums and
differences stay finite."""
_MAX_ABS_ELEVATION_M = 1e6
"""Largest elevation magnitude :func:`total_ascent` and :func:`steepest_grade` take (m)."""
_MAX_MAP_M = 2e7
"""Largest map coordinate :func:`course_from_xy` takes (m): half the Earth's circumference."""
_MIN_STEP_M = 1e-6
"""Shortest distance between points that counts as a move (m): a course merges points closer than this."""
_MIN_GRADE_STEP_M = 1e-7
"""Shortest step between the distances :func:`steepest_grade` takes (m): a course's (above :data:`_MIN_STEP_M`,
less rounding) pass, and every grade stays finite."""


def _name(name: object) -> str:
    """A course name as given, when it is a str; else ``ValueError`` naming it (None or NaN is not a name)."""
    if not isinstance(name, str):
        raise ValueError(f"name must be a str, got {type(name).__name__}")
    return name


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

    @functools.cached_property
    def climbing_m(self) -> float:
        """Total ascent (m), noise-aware: :func:`total_ascent` of the elevation as read, whatever ``smoothing_m``
        the course was built with (so a noisy flat road reads 0, not the sum of its GPS jitter)."""
        return total_ascent(self.distance_m, self.elevation_raw_m)


def total_ascent(
    distance_m: ArrayLike,
    elevation_m: ArrayLike,
    *,
    threshold_m: float = ASCENT_THRESHOLD_M,
    window_m: float = ASCENT_WINDOW_M,
) -> float:
    """Total ascent of a profile (m), counting climbs and not GPS noise (see the module docstring).

    Spikes are replaced by the median of the five points about them, the profile is smoothed by a moving average
    over ``window_m``, and a climb counts, from its low to its high, once the smoothed profile has risen
    ``threshold_m`` above the last low; a descent of ``threshold_m`` from the high ends it. A climb still rising at
    the finish counts too. The window's cost: a sharp summit or foot (or one sampled sparsely) is rounded off by at
    most its steepest grade × ``window_m`` / 4, so a clean profile never reads more than its own sum of rises.

    Args:
        distance_m: (N,) distance along the route (m), non-decreasing, of magnitude at most 10¹⁵ m.
        elevation_m: (N,) elevation (m), raw or smoothed, of magnitude at most 10⁶ m.
        threshold_m: smallest climb counted (m, > 0).
        window_m: moving-average window (m, ≥ 0; 0, or less than :data:`SMOOTHING_FLOOR_M`, does not smooth).

    Returns:
        The total ascent (m, ≥ 0).

    Raises:
        ValueError: naming the argument: arrays not one-dimensional, of different lengths, empty or not finite,
            distance decreasing or too large, threshold not positive or window negative.
    """
    d = _checks.bounded_array("distance_m", distance_m, _MAX_DISTANCE_M)
    z = _checks.bounded_array("elevation_m", elevation_m, _MAX_ABS_ELEVATION_M)
    threshold = _checks.positive("threshold_m", threshold_m)
    window = _checks.non_negative("window_m", window_m)
    if d.ndim != 1 or z.ndim != 1 or d.shape != z.shape or d.shape[0] == 0:
        raise ValueError(
            f"distance_m and elevation_m must be (N,) arrays of one length N >= 1, got {d.shape} and {z.shape}"
        )
    if np.any(np.diff(d) < 0.0):
        raise ValueError("distance_m must be non-decreasing")
    if d[-1] == d[0]:
        return 0.0  # every point at one place: no road to climb
    profile = _smooth(d, _despike(d, z), window)
    return _hysteresis_ascent(profile, threshold)


def _despike(distance: NDArray[np.float64], z: NDArray[np.float64], half: int = 2) -> NDArray[np.float64]:
    """z with each spike replaced by the median of the 2·half + 1 points about it (ends mirrored).

    A point is a spike when it is farther from that median than :data:`ASCENT_SPIKE_GRADE` times the distance to
    the farthest point of its window. On a profile no steeper than that grade every point of the window, and so
    the median, lies within that bound, so a real road is left as it is.
    """
    n = z.shape[0]
    if n < 2 * half + 1:
        return z
    windows = np.lib.stride_tricks.sliding_window_view(np.pad(z, half, mode="reflect"), 2 * half + 1)
    reach_ends = np.lib.stride_tricks.sliding_window_view(np.pad(distance, half, mode="edge"), 2 * half + 1)
    median = np.median(windows, axis=1)
    reach = np.maximum(distance - reach_ends[:, 0], reach_ends[:, -1] - distance)
    return np.where(np.abs(z - median) > ASCENT_SPIKE_GRADE * reach, median, z)


def _hysteresis_ascent(z: NDArray[np.float64], threshold: float) -> float:
    """Sum of climbs of at least ``threshold`` in z, each from its low to its high (zig-zag with hysteresis)."""
    # Only the turning points matter: keep the ends and every point where the profile changes direction.
    step = np.diff(z)
    direction = np.sign(step[step != 0.0])
    keep = np.flatnonzero(step != 0.0)
    turns = keep[1:][direction[1:] != direction[:-1]]
    values = z[np.concatenate(([0], turns, [z.shape[0] - 1]))].tolist()
    total, low, high, state = (0.0, values[0], values[0], 0)  # state: +1 climbing, -1 descending, 0 not yet known
    for v in values:
        if state > 0:
            if v > high:
                high = v
            elif high - v >= threshold:
                total += high - low
                state, low = -1, v
        elif state < 0:
            if v < low:
                low = v
            elif v - low >= threshold:
                state, high = 1, v
        else:
            low, high = min(low, v), max(high, v)
            if v - low >= threshold:
                state, high = 1, v
            elif high - v >= threshold:
                state, low = -1, v
    if state > 0:
        total += high - low
    return float(total)


def _smooth(distance: NDArray[np.float64], z: NDArray[np.float64], window_m: float) -> NDArray[np.float64]:
    """Moving average of the piecewise-linear profile z(s) over [s − h, s + h] ∩ route, h = window/2.

    A window below :data:`SMOOTHING_FLOOR_M`, or below a billionth of the distances' magnitude, returns z as it is:
    the average is a difference of running integrals over the window's width, whose rounding grows as the window
    shrinks (0/0 once s ± h rounds to s)."""
    resolution = max(SMOOTHING_FLOOR_M, 1e-9 * max(abs(float(distance[0])), abs(float(distance[-1]))))
    if window_m < resolution or distance.shape[0] < 3:
        return z.copy()
    # Integrate the profile about its first value: the running integral stays as small as the climb, not the
    # altitude, and so does its rounding.
    base = float(z[0])
    smoothed = _smooth_about(distance, z - base, window_m)
    return smoothed + base


def _smooth_about(distance: NDArray[np.float64], z: NDArray[np.float64], window_m: float) -> NDArray[np.float64]:
    integral, slope = _running(distance, z)
    half = 0.5 * window_m
    lo = np.maximum(distance - half, distance[0])
    hi = np.minimum(distance + half, distance[-1])
    within = _integral_at(distance, z, integral, slope, hi) - _integral_at(distance, z, integral, slope, lo)
    smoothed = within / (hi - lo)
    # Within half a window of an end the window is cut short and no longer centred on its point: its mean is the
    # profile's about the window's middle (a steady 45 % climb smoothed over 50 m read 22.5 % on its first and last
    # 25 m). There the least-squares line over the end's first whole window is taken instead, as scipy's
    # Savitzky–Golay filter does at its edges (mode "interp", order 1): a steady grade is kept to the ends, and the
    # end grades are as steady as the rest (a window cut short also fits a line to half as many points).
    near_start = distance - distance[0] < half
    near_end = distance[-1] - distance < half
    smoothed[near_start] = _end_line(distance, z, window_m, distance[near_start])
    mirror = distance[-1] - distance[::-1]
    smoothed[near_end] = _end_line(mirror, z[::-1], window_m, distance[-1] - distance[near_end])
    return smoothed


def _running(distance: NDArray[np.float64], z: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The running integral of the piecewise-linear z(s) from the start at each point, and each segment's slope."""
    run = np.diff(distance)
    integral = np.concatenate(([0.0], np.cumsum(run * 0.5 * (z[1:] + z[:-1]))))
    return integral, np.diff(z) / np.where(run > 0.0, run, 1.0)


def _integral_at(
    distance: NDArray[np.float64],
    z: NDArray[np.float64],
    integral: NDArray[np.float64],
    slope: NDArray[np.float64],
    x: NDArray[np.float64] | float,
) -> NDArray[np.float64]:
    """∫ z from the start to each x, exact: a quadratic within each segment (linear interpolation of the running
    integral would replace a sparse profile's summit by its segments' means)."""
    j = np.clip(np.searchsorted(distance, x, side="right") - 1, 0, distance.shape[0] - 2)
    t = x - distance[j]
    return integral[j] + t * (z[j] + 0.5 * slope[j] * t)


def _end_line(
    distance: NDArray[np.float64], z: NDArray[np.float64], window_m: float, at: NDArray[np.float64]
) -> NDArray[np.float64]:
    """(K,) the least-squares line through the piecewise-linear z(s) over [start, start + window] (the whole route
    where it is shorter), at the distances ``at``: the mean plus the slope ∫ z·(s − c) ds / ∫ (s − c)² ds about the
    window's middle c, times the distance from c. The integrals are exact (z is linear on each segment) and taken
    from the route's start, so they stay as small as the window."""
    width = min(window_m, float(distance[-1] - distance[0]))
    within = min(int(np.searchsorted(distance, distance[0] + width, side="right")) + 1, distance.shape[0])
    e, z = distance[:within] - distance[0], z[:within]  # the window's segments only: a long route costs nothing more
    integral, slope = _running(e, z)
    # ∫ z(s)·(s − s₀) ds over each segment: a cubic in the segment's length.
    run = np.diff(e)
    piece = z[:-1] * e[:-1] * run + (z[:-1] + slope * e[:-1]) * run**2 / 2.0 + slope * run**3 / 3.0
    moment = np.concatenate(([0.0], np.cumsum(piece)))
    j = min(int(np.searchsorted(e, width, side="right")) - 1, e.shape[0] - 2)
    t = width - e[j]
    zeroth = _integral_at(e, z, integral, slope, width)
    first = moment[j] + z[j] * e[j] * t + (z[j] + slope[j] * e[j]) * t**2 / 2.0 + slope[j] * t**3 / 3.0
    middle = 0.5 * width
    tilt = (first - middle * zeroth) / (width**3 / 12.0)
    return zeroth / width + tilt * (at - distance[0] - middle)


def _checked_points(name: str, arrays: dict[str, ArrayLike], n_min: int = 2) -> dict[str, NDArray[np.float64]]:
    """(N,) arrays of one length, finite, n_min ≤ N ≤ MAX_POINTS; else ValueError.

    Kept here rather than in :mod:`kernels._checks`: a route's messages say how many points are bad and where the
    first is, prefixed with the course name, which :func:`load_gpx` rewrites into words about the file.
    """
    out: dict[str, NDArray[np.float64]] = {}
    shape = None
    for key, value in arrays.items():
        array = _checks.real_array(key, value, "an array of numbers")  # True was a metre and "10" ten of them
        if array.ndim != 1:
            raise ValueError(f"{key} must be one-dimensional, got shape {array.shape}")
        if shape is not None and array.shape != shape:
            lengths = {k: np.shape(v) for k, v in arrays.items()}
            odd = next((k for k, v in lengths.items() if list(lengths.values()).count(v) == 1), key)
            raise ValueError(f"{odd} must have as many points as the others: the shapes are {lengths}")
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


def _check_range(name: str, key: str, values: NDArray[np.float64], low: float, high: float) -> None:
    """Refuse values outside [low, high], naming the first such point and its value in full (``repr``: 180.0002,
    not a rounded 180 that reads as the bound)."""
    out = (values < low) | (values > high)
    if np.any(out):
        first = int(np.argmax(out))
        raise ValueError(
            f"{name}: {key} outside [{low:g}, {high:g}]: point {first} is {_checks.shown(float(values[first]))}"
            + _checks.and_more(int(out.sum()))
        )


def _finish(
    name: str,
    east: NDArray[np.float64],
    north: NDArray[np.float64],
    run: NDArray[np.float64],
    heading: NDArray[np.float64],
    elevation: NDArray[np.float64],
    smoothing_m: float,
) -> Course:
    window = _checks.non_negative("smoothing_m", smoothing_m)
    _check_range(name, "elevation_m", elevation, MIN_ELEVATION_M, MAX_ELEVATION_M)
    # Points at one place (a paused GPS logs many) carry no distance: keep the first of each run.
    keep = np.concatenate(([True], run > _MIN_STEP_M))
    if int(keep.sum()) < 2:
        raise ValueError(f"{name}: every point is at one place; a course needs two distinct points")
    seg_keep = keep[1:]
    east, north, elevation = east[keep], north[keep], elevation[keep]
    # Lengths of the merged segments: the dropped zero-length ones add nothing.
    run, heading = run[seg_keep], heading[seg_keep]
    distance = np.concatenate(([0.0], np.cumsum(run)))
    smoothed = _smooth(distance, elevation, window)
    grade = np.diff(smoothed) / run
    if not (np.isfinite(smoothed).all() and np.isfinite(grade).all()):  # a guard: _smooth keeps it finite
        raise ValueError(f"smoothing_m must smooth to finite elevations, got {_checks.shown(smoothing_m)}")
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
        elevation_m: (N,) elevation (m, within ±10 000).
        name: course name (a str).
        smoothing_m: width of the elevation moving-average window (m, ≥ 0; 0 keeps the raw profile, and so does a
            window shorter than :data:`SMOOTHING_FLOOR_M`, 1 cm, which would move no point by 2 mm).

    Raises:
        ValueError: fewer than two distinct points, non-finite or out-of-range values; the message says which.
    """
    name = _name(name)
    p = _checked_points(
        name, {"latitude_deg": latitude_deg, "longitude_deg": longitude_deg, "elevation_m": elevation_m}
    )
    lat, lon = p["latitude_deg"], p["longitude_deg"]
    _check_range(name, "latitude_deg", lat, -90.0, 90.0)
    _check_range(name, "longitude_deg", lon, -180.0, 180.0)
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
    east_m: ArrayLike, north_m: ArrayLike, elevation_m: ArrayLike, name: str = "course", smoothing_m: float = 0.0
) -> Course:
    """Build a :class:`Course` on a flat map (synthetic routes, tests, benchmarks).

    Args:
        east_m, north_m: (N,) map position (m, within ±2·10⁷ m, half the Earth's circumference).
        elevation_m: (N,) elevation (m, within ±10 000).
        name: course name (a str).
        smoothing_m: elevation moving-average window (m, ≥ 0); 0 (the default) keeps the profile as given, and so
            does a window shorter than :data:`SMOOTHING_FLOOR_M` (1 cm).

    Raises:
        ValueError: as :func:`course_from_points`.
    """
    name = _name(name)
    p = _checked_points(name, {"east_m": east_m, "north_m": north_m, "elevation_m": elevation_m})
    east, north = p["east_m"], p["north_m"]
    for key, array in (("east_m", east), ("north_m", north)):
        if np.any(np.abs(array) > _MAX_MAP_M):
            raise ValueError(f"{key} must be within ±{_MAX_MAP_M:g} m, got {_checks.shown(array)}")
    d_east, d_north = np.diff(east), np.diff(north)
    run = np.hypot(d_east, d_north)
    heading = np.arctan2(d_east, d_north) % (2.0 * np.pi)
    return _finish(name, east, north, run, heading, p["elevation_m"], smoothing_m)


def elevation_noise_m(elevation_m: NDArray[np.float64]) -> float:
    """The point-to-point noise σ (m) of a profile of (N,) elevations (m), read from its second differences,
    z[i−1] − 2z[i] + z[i+1], which white noise spreads by √6·σ and a road's own bends in grade barely move; by their
    median absolute deviation (×1.4826, Rousseeuw & Croux 1993), so a few spikes or one step do not count as noise.
    0 for fewer than three points."""
    if elevation_m.shape[0] < 3:
        return 0.0
    bends = np.diff(elevation_m, 2)
    return 1.4826 * float(np.median(np.abs(bends - np.median(bends)))) / math.sqrt(6.0)


def noise_smoothing_m(elevation_m: NDArray[np.float64], smoothing_m: float) -> float:
    """The moving-average window (m) for a profile of (N,) elevations (m) asked to be smoothed over ``smoothing_m``:
    that, or :data:`NOISE_WINDOW_PER_M` times its noise where longer, so the noise is not ridden as grade (σ = 6 m
    every metre, averaged over 50 m, still read 52 % from one point to the next). A window under
    :data:`SMOOTHING_FLOOR_M`, which keeps the profile as read, is kept."""
    if smoothing_m < SMOOTHING_FLOOR_M:
        return smoothing_m
    return max(smoothing_m, NOISE_WINDOW_PER_M * elevation_noise_m(elevation_m))


def steepest_grade(distance_m: ArrayLike, elevation_m: ArrayLike, window_m: float) -> tuple[float, int]:
    """Largest |rise| / run over the stretches from each point to the first point at least ``window_m`` further on
    (the whole route when it is shorter). A cliff anywhere lies inside one such stretch, so no moving average can
    hide it.

    Args:
        distance_m: (N,) distance along the route (m), N ≥ 2, each point at least 10⁻⁷ m past the one before (a
            :class:`Course`'s are 10⁻⁶ m apart), of magnitude at most 10¹⁵ m.
        elevation_m: (N,) elevation (m), of magnitude at most 10⁶ m.
        window_m: the shortest stretch (m, > 0); a window shorter than the spacing of the points measures each
            stretch from a point to the next.

    Returns:
        The grade (rise over run, ≥ 0) and the stretch's first point.

    Raises:
        ValueError: naming the argument: not finite, of the wrong shape, too few points, distance not increasing,
            or the window not a positive number.
    """
    d = _checks.bounded_array("distance_m", distance_m, _MAX_DISTANCE_M)
    z = _checks.bounded_array("elevation_m", elevation_m, _MAX_ABS_ELEVATION_M)
    window = _checks.positive("window_m", window_m)
    if d.ndim != 1 or d.shape[0] < 2:
        raise ValueError(f"distance_m must have shape (N,) with N >= 2, got {d.shape}")
    if z.shape != d.shape:
        raise ValueError(f"elevation_m must have the shape of distance_m, {d.shape}, got {z.shape}")
    if not np.all(np.diff(d) >= _MIN_GRADE_STEP_M):
        raise ValueError(f"distance_m must increase by at least {_MIN_GRADE_STEP_M:g} m from point to point")
    n = d.shape[0]
    start = np.arange(n)
    # The first point at least the window further on, and never the point itself (d + window rounds to d when
    # the window is below the distances' resolution).
    end = np.maximum(np.searchsorted(d, d + window, side="left"), start + 1)
    full = end < n
    if np.any(full):
        start, end = start[full], end[full]
    else:
        start, end = np.array([0]), np.array([n - 1])
    grade = np.abs(z[end] - z[start]) / (d[end] - d[start])
    k = int(np.argmax(grade))
    return float(grade[k]), int(start[k])
