"""Ride a real course: a GPX route, the speed integrated along it, and the power that rides it in a given time.

A course of N points has per-point arrays of shape (N,) (distance, elevation, map position) and per-segment arrays of
shape (N − 1,) (grade, heading, length); segment i runs from point i to point i + 1. SI units throughout (m, s, kg,
W, rad); headings are compass bearings, clockwise from north, in radians.

**Course.** :func:`load_gpx` reads the track and route points of a GPX file with gpxpy. Segment lengths on the map are
great-circle (haversine) distances on a sphere of radius 6 371 008.8 m (the IUGG mean Earth radius); headings are the
initial great-circle bearings. GPS elevation is noisy, so it is smoothed by a moving average over a distance window
(``smoothing_m``, 50 m by default; under :data:`SMOOTHING_FLOOR_M`, 1 cm, none), and within half a window of an
end by the least-squares line over that end's first window (a steady climb keeps its grade and its end heights); grade
is the smoothed rise over the map distance, and the rider travels the slope length run·√(1 + grade²). A GPX file's track
segments and routes are joined in file order, and pieces more than 2 km apart are refused, however they arrive.
:attr:`Course.climbing_m` is the noise-aware total ascent (:func:`total_ascent`: spikes out, a 100 m moving average,
climbs counted past a 5 m hysteresis threshold).

**Ride.** Along each segment the rider's kinetic energy changes by the work of the pedals minus the resistances
(the power terms of :mod:`kernels.cycling`, the textbook terms or Martin et al. 1998's):

    d(½·M·v²)/ds = η·P/v − F(v),    M = m + I/r² (wheel inertia, Martin model),  F·v = P_wheel(v)

integrated per segment with an implicit midpoint step on the segment's mean speed v̄ = (v₀ + v₁)/2:
½·M·(v₁² − v₀²) = L·(η·P − P_wheel(v̄))/v̄, time L/v̄. The step is stable at any length (a rider starting from rest
or entering a 20 % wall at speed needs no tiny steps), and the energy books balance exactly: the work of the pedals
equals the kinetic energy gained plus aero, rolling, bearing and climbing work plus what the brakes take, which the
tests check over a closed loop. A segment that cannot be crossed in one step is split in halves until it can, and
so is one that changes the speed by more than a tenth, or is much longer than the speed takes to settle (there the
midpoint step's gain dv₁/dv₀ = (1 − λh/2)/(1 + λh/2), λ the relaxation rate per metre, falls toward −1 and the speed
would ring about the steady one: a step whose gain misses the true e^(−λh) by more than 0.1 % of the speed is
halved). From rest, or nearly, the sub-steps are cubically graded (v³ grows as 3ηP·s/M).
The rider starts from rest (or ``start_speed_ms``) and brakes to hold ``max_speed_ms`` on descents, easing off the
pedals as needed. The wind blows from ``wind_from_deg`` (meteorological convention); each segment feels its
headwind component w = wind·cos(from − heading); the crosswind is ignored (yaw-free CdA).

**Pacing.** :func:`paced_ride` varies power with the grade, more uphill and less downhill at the same time-averaged
power, as Swain (1997, Med. Sci. Sports Exerc. 29:1104) proposed: time is won where the rider is slow.

The integration loop is compiled with numba (``@njit(cache=True)``); the Python wrappers validate every argument
first (ValueError naming it). :func:`warm_up` compiles it ahead of use.

Modules: :mod:`~kernels.course.route` (:class:`Course` and its geometry), :mod:`~kernels.course.gpx` (reading and
checking GPX files), :mod:`~kernels.course.ride` (:class:`Rider`, :class:`Air`, :class:`Ride`, the compiled ride loop
and the power solvers). Everything public is importable from here.
"""

from __future__ import annotations

from kernels.course.gpx import (
    GRADE_WINDOW_M,
    MAX_FILE_BYTES,
    MAX_GPX_GRADE,
    MAX_SEGMENT_GAP_M,
    MIN_COURSE_M,
    SAMPLE_ROUTE,
    grade_window_m,
    load_gpx,
)
from kernels.course.ride import (
    MAX_POWER_W,
    Air,
    AirKind,
    Model,
    Pacing,
    Ride,
    Rider,
    fastest_time_s,
    paced_ride,
    pacing_factors,
    power_for_time,
    ride,
    warm_up,
)
from kernels.course.route import (
    ASCENT_SPIKE_GRADE,
    ASCENT_THRESHOLD_M,
    ASCENT_WINDOW_M,
    EARTH_RADIUS_M,
    MAX_ELEVATION_M,
    MAX_POINTS,
    MIN_ELEVATION_M,
    NOISE_WINDOW_PER_M,
    SMOOTHING_FLOOR_M,
    Course,
    azimuthal_equidistant,
    course_from_points,
    course_from_xy,
    elevation_noise_m,
    noise_smoothing_m,
    steepest_grade,
    total_ascent,
)

__all__ = [
    "ASCENT_SPIKE_GRADE",
    "ASCENT_THRESHOLD_M",
    "ASCENT_WINDOW_M",
    "EARTH_RADIUS_M",
    "GRADE_WINDOW_M",
    "MAX_ELEVATION_M",
    "MAX_FILE_BYTES",
    "MAX_GPX_GRADE",
    "MAX_POINTS",
    "MAX_POWER_W",
    "MAX_SEGMENT_GAP_M",
    "MIN_COURSE_M",
    "MIN_ELEVATION_M",
    "NOISE_WINDOW_PER_M",
    "SAMPLE_ROUTE",
    "SMOOTHING_FLOOR_M",
    "Air",
    "AirKind",
    "Course",
    "Model",
    "Pacing",
    "Ride",
    "Rider",
    "azimuthal_equidistant",
    "course_from_points",
    "course_from_xy",
    "elevation_noise_m",
    "fastest_time_s",
    "grade_window_m",
    "load_gpx",
    "noise_smoothing_m",
    "paced_ride",
    "pacing_factors",
    "power_for_time",
    "ride",
    "steepest_grade",
    "total_ascent",
    "warm_up",
]
