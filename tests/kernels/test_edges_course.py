"""``kernels.course`` at its edges: every public function refuses bad input with a ``ValueError`` naming the
argument, or applies its documented clamp; no NaN course, no leaked numpy error, no whole array in a message."""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from decimal import Decimal
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from helpers.gpx import gpx_text
from helpers.properties import examples
from hypothesis import given, settings
from hypothesis import strategies as st

from kernels import course, cycling

BAD_NUMBERS: list[Any] = [None, "1", True, object(), 1 + 2j, 10**400, math.nan, math.inf, -math.inf, Decimal("1.5")]
BAD_CHOICES: list[Any] = [None, math.nan, object(), 1, np.array(["textbook", "textbook"]), np.array("textbook")]
X = np.array([0.0, 10.0, 20.0, 30.0, 40.0])
Z = np.array([0.0, 1.0, 0.5, 2.0, 1.0])
FLAT = course.course_from_xy([0.0, 10.0, 20.0], [0.0, 0.0, 0.0], [0.0, 0.5, 0.0])


# Kind: a smoothing window below the distances' resolution gave 0/0, a course of NaN with no error.
@pytest.mark.parametrize("smoothing_m", [1e-300, 1e-100, 1e-20, 1e-10, 1e-3, 0.0099])
def test_a_window_below_the_floor_keeps_the_profile_as_given(smoothing_m: float) -> None:
    sample = course.load_gpx(course.SAMPLE_ROUTE, smoothing_m=smoothing_m)
    raw = course.load_gpx(course.SAMPLE_ROUTE, smoothing_m=0.0)
    np.testing.assert_array_equal(sample.elevation_m, raw.elevation_m)
    np.testing.assert_array_equal(sample.grade, raw.grade)
    xy = course.course_from_xy(X, np.zeros(5), Z, smoothing_m=smoothing_m)
    np.testing.assert_array_equal(xy.elevation_m, Z)
    lat = 45.0 + X / 111_000.0
    points = course.course_from_points(lat, np.full(5, 6.0), Z, smoothing_m=smoothing_m)
    np.testing.assert_array_equal(points.elevation_m, Z)
    assert np.isfinite(course.ride(sample, 250.0).time_s)


@pytest.mark.parametrize("smoothing_m", [course.SMOOTHING_FLOOR_M, 0.05, 1.0, 50.0, 1e300])
def test_a_window_from_the_floor_up_smooths_to_finite_values(smoothing_m: float) -> None:
    xy = course.course_from_xy(X, np.zeros(5), Z, smoothing_m=smoothing_m)
    assert np.all(np.isfinite(xy.elevation_m)) and np.all(np.isfinite(xy.grade))
    # A window of h moves a point by at most h/8 times the change of grade there (here at most 0.25).
    assert np.all(np.abs(xy.elevation_m - Z) <= min(smoothing_m, 40.0) / 8 * 0.25 + 1e-9)
    if smoothing_m >= 1.0:
        assert not np.array_equal(xy.elevation_m, Z)


def test_a_window_of_a_centimetre_smooths_the_sample_by_under_a_millimetre() -> None:
    fine = course.load_gpx(course.SAMPLE_ROUTE, smoothing_m=course.SMOOTHING_FLOOR_M)
    raw = course.load_gpx(course.SAMPLE_ROUTE, smoothing_m=0.0)
    assert np.max(np.abs(fine.elevation_m - raw.elevation_m)) < 1e-3


# Kind: a window cut short at an end of the route, whose mean lies off its point. A steady 45 % climb smoothed over
# 50 m read 22.5 % on its first and last 25 m and 105.6 → 1505.6 m for a file going 100 → 1511 m (the sample route
# read 745 m for its published 744 m start); the speed chart spiked at both ends.
@pytest.mark.parametrize("grade", [0.45, 0.08, -0.12])
def test_a_steady_grade_keeps_its_grade_and_its_heights_to_the_ends(grade: float) -> None:
    s = np.arange(0.0, 3140.0, 10.0)
    metre_deg = 180.0 / (math.pi * course.EARTH_RADIUS_M)
    z = 100.0 + grade * s
    c = course.course_from_points(45.0 + s * metre_deg, np.full_like(s, 6.0), z, smoothing_m=50.0)
    np.testing.assert_allclose(c.grade, grade, rtol=1e-9)
    np.testing.assert_allclose(c.elevation_m, z, atol=1e-9)
    assert course.total_ascent(c.distance_m, c.elevation_raw_m) == pytest.approx(max(grade, 0.0) * s[-1], abs=1e-6)


def test_the_sample_route_starts_and_ends_at_its_published_heights() -> None:
    sample = course.load_gpx(course.SAMPLE_ROUTE)
    assert sample.elevation_m[0] == pytest.approx(744.0, abs=0.1)
    assert sample.elevation_m[-1] == pytest.approx(1815.5, abs=0.1)


@settings(max_examples=examples(200), deadline=None)
@given(
    grade=st.floats(-0.4, 0.4),
    steps=st.lists(st.floats(0.5, 60.0), min_size=2, max_size=300),
    window=st.floats(course.SMOOTHING_FLOOR_M, 5000.0),
    start=st.floats(-500.0, 5000.0),
)
def test_any_straight_profile_is_its_own_smoothing(
    grade: float, steps: list[float], window: float, start: float
) -> None:
    """A line is kept by the moving average (a symmetric window) and by the end's least-squares line alike, at any
    spacing and any window, one shorter or longer than the route."""
    x = np.concatenate(([0.0], np.cumsum(steps)))
    z = start + grade * x
    c = course.course_from_xy(x, np.zeros_like(x), z, smoothing_m=window)
    np.testing.assert_allclose(c.elevation_m, z, rtol=0.0, atol=1e-9 * (1.0 + abs(start) + x[-1]))


def test_noise_at_the_ends_is_smoothed_like_the_rest() -> None:
    """The end's line is fitted to a whole window: a noisy steady climb's end grades scatter no more than 1.1 times
    its middle's (a line fitted to the half window that remains scatters about 2.7 times as much), and about the
    true grade (the cut window's mean read half of it)."""
    s = np.arange(0.0, 2000.1, 5.0)
    ends, middles = [], []
    for seed in range(200):
        z = 300.0 + 0.08 * s + np.random.default_rng(seed).normal(0.0, 2.0, s.size)
        grade = course.course_from_xy(s, np.zeros_like(s), z, smoothing_m=50.0).grade - 0.08
        ends += [grade[0], grade[1], grade[-2], grade[-1]]
        middles += [grade[150], grade[250]]
    end_rms, middle_rms = np.sqrt(np.mean(np.square(ends))), np.sqrt(np.mean(np.square(middles)))
    assert end_rms < 1.1 * middle_rms
    assert abs(np.mean(ends)) < 3.0 * end_rms / math.sqrt(len(ends))


@pytest.mark.parametrize("value", [*BAD_NUMBERS, -1.0, -1e-300])
@pytest.mark.parametrize(
    "build",
    [
        lambda w: course.load_gpx(course.SAMPLE_ROUTE, smoothing_m=w),
        lambda w: course.course_from_xy(X, np.zeros(5), Z, smoothing_m=w),
        lambda w: course.course_from_points(45.0 + X / 1e5, np.full(5, 6.0), Z, smoothing_m=w),
    ],
    ids=["load_gpx", "course_from_xy", "course_from_points"],
)
def test_a_bad_smoothing_is_refused_by_name(build: Callable[[Any], object], value: Any) -> None:
    with pytest.raises(ValueError, match=r"^smoothing_m must"):
        build(value)


def test_total_ascent_with_a_tiny_window_counts_the_raw_climbs() -> None:
    assert course.total_ascent(X, [0.0, 6.0, 0.0, 8.0, 8.0], window_m=1e-300) == 14.0
    with pytest.raises(ValueError, match=r"^elevation_m must"):
        course.total_ascent(X[:4], [0.0, 1e308, -1e308, 8.0])


@pytest.mark.parametrize("name", [None, math.nan, 1, object(), np.array(["a"]), b"route"])
def test_a_name_must_be_a_str(name: Any) -> None:
    with pytest.raises(ValueError, match=r"^name must be a str"):
        course.course_from_xy(X, np.zeros(5), Z, name=name)
    with pytest.raises(ValueError, match=r"^name must be a str"):
        course.course_from_points(45.0 + X / 1e5, np.full(5, 6.0), Z, name=name)
    if name is not None:
        with pytest.raises(ValueError, match=r"^name must be a str"):
            course.load_gpx(course.SAMPLE_ROUTE, name=name)


@pytest.mark.parametrize("coordinate", [1e300, -1e308, 2.1e7])
def test_map_coordinates_past_the_earth_are_refused_by_name(coordinate: float) -> None:
    with pytest.raises(ValueError, match=r"^east_m must be within"):
        course.course_from_xy([0.0, coordinate, coordinate / 2], [0.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    with pytest.raises(ValueError, match=r"^north_m must be within"):
        course.course_from_xy([0.0, 0.0, 0.0], [0.0, coordinate, coordinate / 2], [0.0, 1.0, 0.0])


# Kind: steepest_grade and pacing_factors are public and checked nothing.
@pytest.mark.parametrize("window_m", [*BAD_NUMBERS, 0.0, -1.0, -math.inf])
def test_steepest_grade_refuses_a_bad_window_by_name(window_m: Any) -> None:
    with pytest.raises(ValueError, match=r"^window_m must"):
        course.steepest_grade(X, Z, window_m)


@pytest.mark.parametrize(
    ("distance", "elevation", "name"),
    [
        (5.0, Z, "distance_m"),
        (X, Z[:3], "elevation_m"),
        (X, 1.0, "elevation_m"),
        ([0.0], [1.0], "distance_m"),
        (X[::-1], Z, "distance_m"),
        ([0.0, 0.0, 1.0], [0.0, 0.0, 1.0], "distance_m"),
        ([0.0, 1e-9, 1.0], [0.0, 0.0, 1.0], "distance_m"),
        ([0.0, math.nan], [0.0, 1.0], "distance_m"),
        (X, [0.0, 1.0, math.inf, 2.0, 1.0], "elevation_m"),
        (X, [0.0, 1e308, -1e308, 2.0, 1.0], "elevation_m"),
        (np.stack([X, X]), np.stack([Z, Z]), "distance_m"),
        ("12345", Z, "distance_m"),
        (None, Z, "distance_m"),
    ],
)
def test_steepest_grade_refuses_bad_arrays_by_name(distance: Any, elevation: Any, name: str) -> None:
    with pytest.raises(ValueError, match=f"^{name} must"):
        course.steepest_grade(distance, elevation, 25.0)


@pytest.mark.parametrize("window_m", [1e-300, 1e-9, 1.0, 9.99])
def test_steepest_grade_with_a_window_under_the_spacing_takes_neighbours(window_m: float) -> None:
    # The stretches are from each point to the next: the steepest is 1.5 m over 10 m, from point 2.
    assert course.steepest_grade(X, Z, window_m) == (pytest.approx(0.15), 2)


def test_steepest_grade_with_a_window_past_the_route_takes_the_whole_route() -> None:
    assert course.steepest_grade(X, Z, 1e300) == (pytest.approx(1.0 / 40.0), 0)


@pytest.mark.parametrize("gain", [*BAD_NUMBERS, -5.0, -1e-9, 0.51, 1e300])
def test_pacing_factors_refuse_a_bad_gain_by_name(gain: Any) -> None:
    with pytest.raises(ValueError, match=r"^gain must"):
        course.pacing_factors(0.05, gain)


@pytest.mark.parametrize("grade", [math.nan, math.inf, [0.0, math.nan], None, "0.05", 1 + 2j, [[0.0], [0.0, 1.0]]])
def test_pacing_factors_refuse_a_bad_grade_by_name(grade: Any) -> None:
    with pytest.raises(ValueError, match=r"^grade must"):
        course.pacing_factors(grade, 0.15)


def test_pacing_factors_keep_within_one_plus_or_minus_the_gain() -> None:
    factors = course.pacing_factors([-1e300, -0.05, 0.0, 0.05, 1e300], 0.5)
    np.testing.assert_allclose(factors, [0.5, 1.0 - 0.5 * math.tanh(1.0), 1.0, 1.0 + 0.5 * math.tanh(1.0), 1.5])
    assert course.pacing_factors(0.05, 0.0) == 1.0


# Kind: arrays and odd types in Rider and Air fields, and arrays as a choice.
@pytest.mark.parametrize("value", [*BAD_NUMBERS, [15.0, 16.0, 17.0], np.array([1.0, 2.0])])
@pytest.mark.parametrize("field", ["temperature_c", "pressure_hpa", "relative_humidity", "altitude_m"])
def test_every_air_field_is_one_number(field: str, value: Any) -> None:
    with pytest.raises(ValueError, match=f"^{field} must"):
        course.Air("weather", **{field: value})


@pytest.mark.parametrize("value", [*BAD_NUMBERS, [0.3, 0.3, 0.3], np.array([1.0, 2.0])])
@pytest.mark.parametrize(
    "field",
    ["cda_m2", "mass_kg", "crr", "drivetrain_efficiency", "spoke_drag_m2", "wheel_inertia_kgm2", "wheel_radius_m"],
)
def test_every_rider_field_is_one_number(field: str, value: Any) -> None:
    with pytest.raises(ValueError, match=f"^{field} must"):
        course.Rider(**{field: value})


@pytest.mark.parametrize("value", BAD_CHOICES)
def test_a_model_or_kind_must_be_one_of_its_strings(value: Any) -> None:
    with pytest.raises(ValueError, match=r"^model must be one of 'textbook', 'martin'"):
        course.Rider(model=value)
    with pytest.raises(ValueError, match=r"^kind must be one of 'textbook', 'weather'"):
        course.Air(kind=value)


def test_weather_air_below_the_standard_atmosphere_takes_its_edge() -> None:
    deep = course.course_from_xy([0.0, 10.0, 20.0], [0.0, 0.0, 0.0], [-6000.0, -6000.0, -6000.0])
    air = course.Air("weather", temperature_c=-20.0, pressure_hpa=500.0)
    ride = course.ride(deep, 200.0, air=air)  # refused as "altitude_m must be in [-5000, 20000]", an Air field
    assert np.all(np.isfinite(ride.air_density))
    np.testing.assert_allclose(ride.air_density, air.density(-6000.0))
    # The pressure ratio is the one at −5000 m, the standard atmosphere's lowest; the temperature follows the lapse
    # rate (−20 °C + 6.5 K/km × 6 km = 19 °C).
    pressure = 500.0 * float(cycling.isa_pressure_hpa(-5000.0)) / float(cycling.isa_pressure_hpa(0.0))
    assert pressure < 1100.0  # not held at the reading's top
    expected = float(cycling.air_density_weather(19.0, pressure, 0.0))
    assert float(air.density(-6000.0)) == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("elevation", [math.nan, -1e5, 1e300, [0.0, math.inf]])
def test_air_density_refuses_an_elevation_by_name(elevation: Any) -> None:
    for kind in ("textbook", "weather"):
        with pytest.raises(ValueError, match=r"^elevation_m must"):
            course.Air(kind).density(elevation)  # type: ignore[arg-type]


def test_a_message_never_dumps_a_whole_array() -> None:
    with pytest.raises(ValueError) as refused:
        course.Air().density(np.full(5000, -1e5))
    assert len(str(refused.value)) < 200
    with pytest.raises(ValueError) as refused:
        course.ride(course.load_gpx(course.SAMPLE_ROUTE), np.full(660, 1e6))
    assert len(str(refused.value)) < 200


# Kind: a huge power took seconds (14 s for paced_ride at 1e300 W).
@pytest.mark.parametrize("power_w", [5000.0001, 1e5, 1e300, 10**400])
def test_a_power_beyond_the_maximum_is_refused_by_name_at_once(power_w: Any) -> None:
    sample = course.load_gpx(course.SAMPLE_ROUTE)
    start = time.perf_counter()
    with pytest.raises(ValueError, match=r"^power_w must"):
        course.paced_ride(sample, power_w)
    with pytest.raises(ValueError, match=r"^power_w must"):
        course.ride(sample, power_w)
    assert time.perf_counter() - start < 1.0


# Kind: a refusal that does not quote the value it refused.
@pytest.mark.parametrize(("power_w", "quoted"), [(0, "0"), (-5.0, "-5.0"), (math.nan, "nan"), (-math.inf, "-inf")])
def test_a_power_not_above_zero_is_refused_quoting_it(power_w: float, quoted: str) -> None:
    sample = course.load_gpx(course.SAMPLE_ROUTE)
    for ride in (course.ride, course.paced_ride):
        with pytest.raises(ValueError, match=rf"^power_w must be .*, got {quoted}$"):
            ride(sample, power_w)


def test_the_maximum_power_rides_the_sample() -> None:
    sample = course.load_gpx(course.SAMPLE_ROUTE)
    pacing = course.paced_ride(sample, course.MAX_POWER_W)
    assert np.isfinite(pacing.paced.time_s) and np.isfinite(pacing.constant.time_s)


@pytest.mark.parametrize("every_m", [1e-300, 1e-3, *BAD_NUMBERS])
def test_splits_too_fine_or_not_numbers_are_refused_by_name(every_m: Any) -> None:
    ride = course.ride(FLAT, 200.0)
    with pytest.raises(ValueError, match=r"^every_m must"):
        ride.splits(every_m)


@pytest.mark.parametrize("odd", [0, 1, 2])
def test_the_array_of_the_wrong_length_is_the_one_named(odd: int) -> None:
    # The first array set the shape, so a short east_m was reported as "north_m has shape (200,)".
    arrays = [np.linspace(0.0, 1000.0, 200) for _ in range(3)]
    arrays[odd] = arrays[odd][:2]
    name = ["east_m", "north_m", "elevation_m"][odd]
    with pytest.raises(ValueError, match=rf"^{name} must have as many points as the others"):
        course.course_from_xy(arrays[0], arrays[1], arrays[2])


def test_a_directory_is_refused_as_a_file_it_cannot_read(tmp_path: Path) -> None:
    # A missing file said "cannot read"; a directory raised IsADirectoryError.
    with pytest.raises(ValueError, match=r"^cannot read .*: Is a directory"):
        course.load_gpx(tmp_path)
    with pytest.raises(ValueError, match=r"^cannot read .*: No such file or directory"):
        course.load_gpx(tmp_path / "missing.gpx")


def test_a_weather_reading_below_the_standard_atmospheres_range_is_taken_where_it_was_read() -> None:
    # A course starting 2 km below sea level had its reading refused as altitude_m (the scene reads at the start).
    reading = course.Air("weather", 15.0, 1013.0, 0.5, altitude_m=-2000.0)
    at_reading = cycling.air_density_weather(15.0, 1013.0, 0.5)
    np.testing.assert_allclose(reading.density([-2000.0]), at_reading, rtol=1e-12)
    assert reading.density([0.0])[0] < at_reading  # thinner up the road
    with pytest.raises(ValueError, match=r"^altitude_m must be in \[-10000, 30000\] m"):
        course.Air("weather", 15.0, 1013.0, 0.5, altitude_m=-20000.0)


# Kind: a flag taken as a coordinate (True was latitude 1°), and a refusal that did not quote the value.
@pytest.mark.parametrize("bad", [[0.0, True], [0.0, None], ["0", "1"]], ids=repr)
def test_a_route_refuses_what_is_not_numbers_quoting_it(bad: Any) -> None:
    with pytest.raises(ValueError, match=r"^latitude_deg must be an array of numbers, got \["):
        course.course_from_points(bad, [0.0, 0.01], [0.0, 0.0])
    with pytest.raises(ValueError, match=r"^elevation_m must be an array of numbers, got \["):
        course.course_from_xy([0.0, 100.0], [0.0, 100.0], bad)


@pytest.mark.parametrize(
    ("missing", "words"), [(1, "1 of 5 track points has no elevation"), (2, "2 of 5 track points have")]
)
def test_points_without_elevation_are_counted_in_words(missing: int, words: str) -> None:
    # An outside tester read "1 of 200 track points have no elevation".
    points = [(45.0 + i * 1e-3, 6.0, None if i < missing else 300.0) for i in range(5)]
    with pytest.raises(ValueError, match=words):
        course.load_gpx(gpx_text(points).encode())
