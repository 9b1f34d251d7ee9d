"""Total ascent counts climbs, not GPS noise.

Summing every rise of the smoothed profile read +122 m on a flat 10 km road logged every 5 m with 1.5 m of
elevation noise, and +143 m for one 50 m hill. Synthetic profiles whose true ascent is known in closed form (flat,
one hill, several hills, a long climb), with Gaussian noise up to 2 m and occasional spikes, must read within
max(10 %, 5 m) of it. Hills are raised cosines no steeper than 15 % and at least 20 m high: climbs smaller than the
5 m threshold are, by design, not counted.
"""

from __future__ import annotations

import math
import os
from typing import Literal

import numpy as np
import pytest
from helpers.properties import examples
from hypothesis import given, settings
from hypothesis import strategies as st

from kernels import course

EXAMPLES = int(os.environ.get("EXPLORE_EXAMPLES", 120))
METRE_DEG = 180.0 / (math.pi * course.EARTH_RADIUS_M)
Shape = Literal["flat", "one hill", "several hills", "long climb"]


def profile(shape: Shape, s: np.ndarray, heights: list[float], grade: float) -> tuple[np.ndarray, float]:
    """(elevation above 300 m at distances s, its true total ascent), from closed forms.

    Hills are raised cosines h·(1 + cos(2π(s − c)/w))/2 on their own stretch of road, each rising exactly h once;
    the long climb rises ``grade`` all the way."""
    z = np.zeros_like(s)
    match shape:
        case "flat":
            return 300.0 + z, 0.0
        case "long climb":
            return 300.0 + grade * s, grade * float(s[-1])
        case "one hill" | "several hills":
            hills = heights[:1] if shape == "one hill" else heights
            slot = float(s[-1]) / len(hills)
            for k, h in enumerate(hills):
                w = min(0.9 * slot, max(600.0, math.pi * h / 0.12))  # steepest π·h/w: 12 %, or 15 % where short
                h = min(h, 0.15 * w / math.pi)
                hills[k] = h
                centre = slot * (k + 0.5)
                on = np.abs(s - centre) < w / 2
                z[on] += h * (1.0 + np.cos(2.0 * np.pi * (s[on] - centre) / w)) / 2.0
            return 300.0 + z, float(sum(hills))


def noisy(z: np.ndarray, sigma: float, spike_rate: float, seed: int) -> np.ndarray:
    """z plus N(0, σ²) noise and, at a fraction ``spike_rate`` of points, an isolated spike of 5 to 100 m either way."""
    rng = np.random.default_rng(seed)
    spikes = rng.random(z.shape) < spike_rate
    spikes[1:] &= ~spikes[:-1]  # isolated: a spike's neighbours are not spikes
    size = rng.choice([-1.0, 1.0], z.shape) * rng.uniform(5.0, 100.0, z.shape)
    return z + rng.normal(0.0, sigma, z.shape) + np.where(spikes, size, 0.0)


def along_a_meridian(s: np.ndarray, elevation: np.ndarray, smoothing_m: float = 50.0) -> course.Course:
    """A course due north from 45° N 6° E (what load_gpx builds after parsing)."""
    return course.course_from_points(45.0 + s * METRE_DEG, np.full_like(s, 6.0), elevation, smoothing_m=smoothing_m)


@settings(max_examples=examples(EXAMPLES), deadline=None)
@given(
    shape=st.sampled_from(["flat", "one hill", "several hills", "long climb"]),
    length_m=st.floats(3_000.0, 12_000.0),
    spacing_m=st.floats(1.0, 10.0),
    heights=st.lists(st.floats(20.0, 120.0), min_size=2, max_size=5),
    grade=st.floats(0.02, 0.08),
    sigma_m=st.floats(0.0, 2.0),
    spike_rate=st.sampled_from([0.0, 0.001, 0.005]),
    smoothing_m=st.sampled_from([0.0, 50.0, 200.0]),
    seed=st.integers(0, 2**32 - 1),
)
def test_ascent_of_a_noisy_profile_is_within_ten_percent_or_five_metres(
    shape: Shape,
    length_m: float,
    spacing_m: float,
    heights: list[float],
    grade: float,
    sigma_m: float,
    spike_rate: float,
    smoothing_m: float,
    seed: int,
) -> None:
    """Points 1–10 m apart (a 1 s log), any course smoothing: the readout stays within max(10 %, 5 m)."""
    s = np.arange(0.0, length_m, spacing_m)
    clean, true = profile(shape, s, list(heights), grade)
    c = along_a_meridian(s, noisy(clean, sigma_m, spike_rate, seed), smoothing_m)
    assert abs(c.climbing_m - true) <= max(0.1 * true, 5.0), (c.climbing_m, true)


@settings(max_examples=examples(EXAMPLES), deadline=None)
@given(
    shape=st.sampled_from(["one hill", "several hills", "long climb"]),
    spacing_m=st.floats(1.0, 200.0),
    heights=st.lists(st.floats(20.0, 120.0), min_size=2, max_size=5),
    grade=st.floats(0.02, 0.08),
)
def test_a_clean_profile_reads_its_true_ascent_at_any_spacing(
    shape: Shape, spacing_m: float, heights: list[float], grade: float
) -> None:
    """No noise, points up to 200 m apart (a sparse planned route): never more than the ascent as sampled, and less
    by at most what the 100 m window rounds off, steepest grade × 25 m at each summit and each foot of a climb."""
    s = np.arange(0.0, 10_000.0, spacing_m)
    clean, _ = profile(shape, s, list(heights), grade)
    sampled = float(np.sum(np.maximum(np.diff(clean), 0.0)))  # a sparse hill may miss its top
    climbs = {"one hill": 1, "several hills": len(heights), "long climb": 1}[shape]
    steepest = float(np.max(np.abs(np.diff(clean) / np.diff(s))))
    rounded = climbs * 2 * steepest * course.ASCENT_WINDOW_M / 4
    found = course.total_ascent(s, clean)
    slack = 1e-9 * (1.0 + sampled)
    assert sampled - rounded - slack <= found <= sampled + slack


def gpx(s: np.ndarray, elevation: np.ndarray) -> str:
    rows = "".join(
        f'<trkpt lat="{float(45.0 + d * METRE_DEG)!r}" lon="6.0"><ele>{z:.2f}</ele></trkpt>'
        for d, z in zip(s, elevation, strict=True)
    )
    return f'<?xml version="1.0"?><gpx version="1.1" creator="test"><trk><trkseg>{rows}</trkseg></trk></gpx>'


def test_flat_ten_kilometres_with_gps_noise_climbs_nothing() -> None:
    """The public case: 10 km flat, a point every 5 m, elevation noise N(0, 1.5 m); the true ascent is 0."""
    s = np.arange(0.0, 10_000.0 + 2.5, 5.0)
    elevation = noisy(np.full_like(s, 300.0), 1.5, 0.0, seed=2024)
    c = course.load_gpx(gpx(s, elevation))
    summed = float(np.sum(np.maximum(np.diff(c.elevation_m), 0.0)))
    print(f"flat 10 km, σ 1.5 m: every rise of the smoothed profile {summed:.1f} m, climbing_m {c.climbing_m:.1f} m")
    assert summed > 50.0  # the noise the old sum counted
    assert c.climbing_m <= 5.0


def test_one_fifty_metre_hill_reads_fifty_metres() -> None:
    """The public case: the same road with one 50 m hill (a raised cosine 2 km long, 7.9 % at its steepest)."""
    s = np.arange(0.0, 10_000.0 + 2.5, 5.0)
    clean = 300.0 + np.where(np.abs(s - 5000.0) < 1000.0, 25.0 * (1.0 + np.cos(np.pi * (s - 5000.0) / 1000.0)), 0.0)
    c = course.load_gpx(gpx(s, noisy(clean, 1.5, 0.0, seed=2025)))
    summed = float(np.sum(np.maximum(np.diff(c.elevation_m), 0.0)))
    print(f"one 50 m hill, σ 1.5 m: every rise {summed:.1f} m, climbing_m {c.climbing_m:.1f} m")
    assert c.climbing_m == pytest.approx(50.0, abs=5.0)


def test_the_ride_is_unchanged_by_noise_in_its_net_climbing_work() -> None:
    """The ride's climbing work telescopes: m·g·Σ rise = m·g·(end − start) of the smoothed profile, noise or not,
    so the ride keeps the smoothed profile and only the readout needed a noise-aware count."""
    s = np.arange(0.0, 5_000.0, 5.0)
    c = along_a_meridian(s, noisy(np.full_like(s, 300.0), 2.0, 0.0, seed=7))
    rider = course.Rider(cda_m2=0.32, mass_kg=80.0, crr=0.004, model="textbook")
    r = course.ride(c, 250.0, rider)
    net = rider.mass_kg * 9.81 * float(c.elevation_m[-1] - c.elevation_m[0])
    assert r.climbing_j == pytest.approx(net, rel=1e-3, abs=50.0)


@pytest.mark.parametrize(
    ("arguments", "name"),
    [
        (([0.0, 1.0], [0.0]), "distance_m and elevation_m"),
        (([0.0, float("nan")], [0.0, 1.0]), "distance_m"),
        (([0.0, 1.0], [0.0, float("inf")]), "elevation_m"),
        (([1.0, 0.0], [0.0, 1.0]), "distance_m must be non-decreasing"),
    ],
)
def test_bad_profiles_are_refused_naming_the_argument(arguments: tuple[list[float], list[float]], name: str) -> None:
    with pytest.raises(ValueError, match=name):
        course.total_ascent(*arguments)
    with pytest.raises(ValueError, match="threshold_m"):
        course.total_ascent([0.0, 1.0], [0.0, 1.0], threshold_m=0.0)
    with pytest.raises(ValueError, match="window_m"):
        course.total_ascent([0.0, 1.0], [0.0, 1.0], window_m=-1.0)
