"""kernels.cycling formations: the wake model against the single-file model, published peloton and pair numbers, and
its two properties (a rider joining behind never raises anyone's drag; the mirror image gives mirrored drags)."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from helpers import riders
from helpers.properties import examples
from hypothesis import given, settings
from hypothesis import strategies as st

from kernels import cycling

BUNCH = cycling.formation(121, "bunch")
BUNCH_DRAG = cycling.formation_drag(BUNCH)
STEP = cycling.BIKE_LENGTH_M + 0.3


def _rows(positions: np.ndarray) -> np.ndarray:
    return np.round(-positions[:, 0] / STEP).astype(int)


def _interior(positions: np.ndarray) -> np.ndarray:
    """Riders with a rider on either side of them in their row (not on the bunch's edge)."""
    rows = _rows(positions)
    mask = np.zeros(len(positions), bool)
    for row in np.unique(rows):
        members = np.flatnonzero(rows == row)
        y = positions[members, 1]
        mask[members] = (y > y.min()) & (y < y.max())
    return mask


# ------------------------------------------------------------------------------------------------ (a) single file
@given(n=st.integers(1, 40), gap=st.floats(0.0, 15.0), model=st.sampled_from(["measured", "textbook"]))
@settings(max_examples=examples(80))
def test_single_file_is_the_line_model(n: int, gap: float, model: cycling.DraftModel) -> None:
    drag = cycling.formation_drag(cycling.formation(n, "single", gap_m=gap), model)
    expected = 1.0 - cycling.drag_reduction(n, gap, model)
    # Identical but for the rounding of the positions (x = −k·(L + gap), so the gap read back differs by an ulp).
    np.testing.assert_allclose(drag, expected, rtol=0.0, atol=1e-12)


def test_single_file_values_are_the_published_line_numbers() -> None:
    drag = cycling.formation_drag(cycling.formation(4, "single", gap_m=0.3))
    # Team pursuit (Barry et al. 2015; Fitton et al. 2018): 2nd saves 42-45 %, 3rd 48-55 %, 4th 47-57 %.
    assert 1 - drag[1] == pytest.approx(0.40 * np.exp(-0.3 / 9.7), rel=1e-12)
    assert 0.42 <= 1 - drag[2] + 0.0 <= 0.55 and 0.45 <= 1 - drag[3] <= 0.57


# ------------------------------------------------------------------------------------------------ (b) pairs
def test_a_pair_in_line_gives_the_leader_blocken_2013_gain_and_the_follower_the_line_value() -> None:
    drag = cycling.formation_drag(np.array([[0.0, 0.0], [-(cycling.BIKE_LENGTH_M + 0.3), 0.0]]))
    assert 0.974 <= drag[0] <= 0.992  # Blocken et al. 2013: the leader saves 0.8-2.6 %
    assert drag[1] == pytest.approx(1 - 0.40 * np.exp(-0.3 / 9.7), rel=1e-12)


def test_a_follower_loses_its_shelter_as_it_moves_out_of_line() -> None:
    # A 2017 wind-tunnel study of drafting offsets (ASME FEDSM 2017): no sideways offset gives the lowest drag; the
    # benefit falls away as the follower moves sideways, and beside the leader (no overlap) it is gone.
    offsets = np.linspace(0.0, 2.0, 21)
    follower = [cycling.formation_drag(np.array([[0.0, 0.0], [-2.0, dy]]))[1] for dy in offsets]
    assert np.all(np.diff(follower) > 0.0)
    assert follower[0] < 0.62 and follower[-1] > 0.99
    side_by_side = cycling.formation_drag(np.array([[0.0, 0.0], [0.0, 0.6]]))
    np.testing.assert_array_equal(side_by_side, [1.0, 1.0])


def test_a_two_abreast_paceline_shelters_at_least_as_well_as_single_file() -> None:
    double = cycling.formation_drag(cycling.formation(8, "double", gap_m=0.3))
    single = cycling.formation_drag(cycling.formation(4, "single", gap_m=0.3))
    # Each file of the double line is a single line, plus the shelter of the other file.
    assert np.all(double[0::2] <= single + 1e-12) and np.all(double[1::2] <= single + 1e-12)
    np.testing.assert_allclose(double[0::2], double[1::2], rtol=0, atol=1e-15)  # the two files mirror each other


# ---------------------------------------------------------------------------------------------- (c) the 121-rider bunch
def test_bunch_matches_blocken_2018_map() -> None:
    rows = _rows(BUNCH)
    interior = _interior(BUNCH)
    # Blocken et al. 2018 (J. Wind Eng. Ind. Aerodyn. 179:319): leader 88 %, the two behind it 63 %, the middle of
    # the third row 38 %, the middle of the bunch 5-10 % and the back as low as 4 % of a lone rider's drag.
    assert BUNCH_DRAG[0] == pytest.approx(0.88, abs=0.01)
    np.testing.assert_allclose(BUNCH_DRAG[rows == 1], 0.63, atol=0.01)
    assert BUNCH_DRAG[(rows == 2) & interior][0] == pytest.approx(0.38, abs=0.01)
    middle = BUNCH_DRAG[(rows >= 8) & (rows <= 14) & interior]
    assert 0.05 <= float(np.mean(middle)) <= 0.10
    assert np.mean((middle >= 0.045) & (middle <= 0.10)) >= 0.7
    back = BUNCH_DRAG[(rows >= rows.max() - 1) & interior]
    assert 0.035 <= back.min() and back.max() <= 0.06
    # The leader bears most; deep riders less than the front rows.
    assert BUNCH_DRAG.argmax() == 0 and np.all(BUNCH_DRAG[rows >= 3] < BUNCH_DRAG[rows == 1].min())


def test_the_bunch_widens_behind_its_leader_to_eight_abreast() -> None:
    rows = _rows(BUNCH)
    counts = np.bincount(rows)
    assert list(counts[:8]) == [1, 2, 3, 4, 5, 6, 7, 8]
    assert set(counts[8:-1]) == {7, 8} and counts.sum() == 121
    np.testing.assert_allclose(BUNCH[0], [0.0, 0.0])
    assert np.all(np.abs(BUNCH[:, 1]) <= 3.5 * 0.6 + 1e-12)


# ------------------------------------------------------------------------------------------------ properties
layouts = st.lists(st.tuples(st.floats(-40.0, 0.0), st.floats(-4.0, 4.0)), min_size=1, max_size=25).map(
    lambda points: np.array(points, dtype=np.float64)
)


@given(
    layout=layouts,
    back=st.floats(0.0, 20.0),
    side=st.floats(-4.0, 4.0),
    model=st.sampled_from(["measured", "textbook"]),
)
@settings(max_examples=examples(150))
def test_a_rider_joining_behind_never_raises_anyones_drag(
    layout: np.ndarray, back: float, side: float, model: cycling.DraftModel
) -> None:
    before = cycling.formation_drag(layout, model)
    joined = np.vstack([layout, [[layout[:, 0].min() - back, side]]])
    after = cycling.formation_drag(joined, model)
    assert np.all(after[:-1] <= before + 1e-12)


@given(layout=layouts, model=st.sampled_from(["measured", "textbook"]))
@settings(max_examples=examples(150))
def test_the_mirror_image_across_the_road_gives_the_same_drags(layout: np.ndarray, model: cycling.DraftModel) -> None:
    mirrored = layout * np.array([1.0, -1.0])
    np.testing.assert_array_equal(cycling.formation_drag(mirrored, model), cycling.formation_drag(layout, model))


# ------------------------------------------------------------------------------------------------ crosswind
def _turned(layout: np.ndarray, yaw: float) -> np.ndarray:
    """``layout`` turned by ``yaw`` about the origin (counter-clockwise seen from above)."""
    c, s = math.cos(yaw), math.sin(yaw)
    return layout @ np.array([[c, s], [-s, c]])


def test_in_a_crosswind_a_line_loses_its_shelter_and_an_echelon_keeps_it() -> None:
    # Five riders at 30 km/h in a 30 km/h wind from 40° left of ahead: the apparent wind comes from 20° left.
    v, w = 30 / 3.6, 30 / 3.6
    yaw = cycling.apparent_yaw(v, w * math.cos(math.radians(40.0)), w * math.sin(math.radians(40.0)))
    assert math.degrees(yaw) == pytest.approx(20.0, abs=1e-9)
    line = cycling.formation(5, "single", gap_m=0.3)
    echelon = cycling.formation(5, "echelon", gap_m=0.3)
    in_line, in_echelon = cycling.formation_drag(line, yaw_rad=yaw), cycling.formation_drag(echelon, yaw_rad=yaw)
    # The straight line's leader gains next to nothing (the 2022 CFD: 0.1 %; here the push of the riders behind).
    assert in_line[0] > 0.97
    # Its followers, off the wake to the side, keep little of the 39-48 % they save in still air.
    assert np.all(in_line[1:] > 0.8) and np.all(cycling.formation_drag(line)[1:] < 0.62)
    # The echelon angled downwind shelters its fourth rider by about half (the 2022 CFD: 53.6 %).
    assert 0.40 <= in_echelon[3] <= 0.52
    assert np.all(in_echelon[1:] < in_line[1:])


@given(layout=layouts, yaw=st.floats(-1.5, 1.5))
@settings(max_examples=examples(100))
def test_a_layout_turned_into_the_wind_is_the_same_layout_in_still_air(layout: np.ndarray, yaw: float) -> None:
    # Wakes trail along the apparent wind: turning the riders with it changes nothing.
    np.testing.assert_allclose(
        cycling.formation_drag(_turned(layout, yaw), yaw_rad=yaw), cycling.formation_drag(layout), atol=1e-9
    )


@given(layout=layouts, yaw=st.floats(-1.5, 1.5), back=st.floats(0.0, 20.0), side=st.floats(-4.0, 4.0))
@settings(max_examples=examples(100))
def test_in_a_crosswind_the_mirror_image_and_a_rider_joining_downwind_behave(
    layout: np.ndarray, yaw: float, back: float, side: float
) -> None:
    drag = cycling.formation_drag(layout, yaw_rad=yaw)
    mirrored = layout * np.array([1.0, -1.0])
    np.testing.assert_array_equal(cycling.formation_drag(mirrored, yaw_rad=-yaw), drag)
    # A rider joining behind everyone in the wind's frame never raises anyone's drag.
    in_wind = _turned(layout, -yaw)
    joiner = _turned(np.array([[in_wind[:, 0].min() - back, side]]), yaw)
    joined = cycling.formation_drag(np.vstack([layout, joiner]), yaw_rad=yaw)
    assert np.all(joined[:-1] <= drag + 1e-12)


@pytest.mark.parametrize("yaw", [math.nan, math.inf, 0.5 * math.pi, -2.0, "20"])
def test_formation_drag_refuses_a_bad_yaw_naming_it(yaw: object) -> None:
    with pytest.raises(ValueError, match="yaw_rad"):
        cycling.formation_drag(BUNCH, yaw_rad=yaw)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"speed_ms": -1.0}, "speed_ms"),
        ({"headwind_ms": math.nan}, "headwind_ms"),
        ({"crosswind_ms": "x"}, "crosswind_ms"),
    ],
)
def test_apparent_yaw_refuses_bad_input_naming_it(kwargs: dict, name: str) -> None:
    arguments = {"speed_ms": 10.0, **kwargs}
    with pytest.raises(ValueError, match=name):
        cycling.apparent_yaw(**arguments)


@given(layout=layouts, seed=st.integers(0, 2**32 - 1))
@settings(max_examples=examples(60))
def test_drags_follow_the_riders_not_their_order(layout: np.ndarray, seed: int) -> None:
    order = np.random.default_rng(seed).permutation(len(layout))
    drag = cycling.formation_drag(layout)
    assert np.all((drag > 0.0) & (drag <= 1.0))
    np.testing.assert_allclose(cycling.formation_drag(layout[order]), drag[order], rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("shape", cycling.FORMATION_SHAPES)
@pytest.mark.parametrize("n", [1, 2, 7, 121, 200])
def test_every_shape_lays_out_n_distinct_riders_leader_first(shape: cycling.FormationShape, n: int) -> None:
    positions = cycling.formation(n, shape)
    assert positions.shape == (n, 2)
    assert positions[0, 0] == 0.0 and abs(positions[0, 1]) <= 0.3  # on the axis (a double line's pair astride it)
    assert np.all(positions[:, 0] <= 0.0)
    assert len({tuple(p) for p in np.round(positions, 9)}) == n


def test_echelon_steps_back_and_to_the_right() -> None:
    positions = cycling.formation(5, "echelon", gap_m=0.2, lateral_m=0.5)
    np.testing.assert_allclose(np.diff(positions, axis=0), np.tile([-(0.85 + 0.2), -0.5], (4, 1)))


def test_a_long_echelon_wraps_into_echelons_one_behind_another_each_across_the_road() -> None:
    # The failing look (a review): an echelon of 121 ran 72 m to the right, off the road and across the grass.
    gap, lateral, width = 0.3, 0.6, cycling.ECHELON_WIDTH
    positions = cycling.formation(121, "echelon", gap_m=gap, lateral_m=lateral)
    k = np.arange(121)
    # Each echelon spans the same width as the bunch's widest row, starting again at the leader's side.
    np.testing.assert_allclose(positions[:, 1], -(k % width) * lateral)
    widest_bunch_row = np.ptp(cycling.formation(121, "bunch", lateral_m=lateral)[:, 1])
    assert np.ptp(positions[:, 1]) == pytest.approx(widest_bunch_row)
    # Along an echelon half a bike plus the gap back; from its last rider to the next echelon's first, one bike
    # plus the gap: every rider rides behind all those before it.
    steps = -np.diff(positions[:, 0])
    starts = k[1:] % width == 0
    np.testing.assert_allclose(steps[~starts], 0.5 * cycling.BIKE_LENGTH_M + gap)
    np.testing.assert_allclose(steps[starts], cycling.BIKE_LENGTH_M + gap)
    assert starts.sum() == 15  # 121 riders: fifteen full echelons of eight and one rider starting the sixteenth


@pytest.mark.parametrize("shape", cycling.FORMATION_SHAPES)
def test_a_formation_of_n_plus_one_is_the_formation_of_n_and_one_rider_behind(shape: cycling.FormationShape) -> None:
    # So the wake model's "a rider joining behind never raises anyone's drag" holds from one count to the next.
    big = cycling.formation(121, shape, gap_m=0.4, lateral_m=0.6)
    for n in range(1, 121):
        np.testing.assert_array_equal(cycling.formation(n, shape, gap_m=0.4, lateral_m=0.6), big[:n])
    if shape == "echelon":
        assert np.all(np.diff(big[:, 0]) < 0.0)
        drags = [cycling.formation_drag(big[:n]) for n in range(1, 122)]
        for before, after in itertools.pairwise(drags):
            assert np.all(after[:-1] <= before + 1e-12)


@given(speed=st.floats(0.0, 20.0), cda=riders.cda_m2, mass=riders.mass_kg, crr=riders.crr)
@settings(max_examples=examples(30))
def test_formation_power_is_the_power_law_at_each_riders_drag(
    speed: float, cda: float, mass: float, crr: float
) -> None:
    positions = cycling.formation(30, "bunch")
    group = cycling.formation_power(positions, speed, cda, mass, crr, drivetrain_efficiency=0.976)
    one = cycling.power(speed, cda * cycling.formation_drag(positions), mass, crr, drivetrain_efficiency=0.976)
    np.testing.assert_array_equal(group.total, one.total)
    assert group.total.shape == (30,)


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        (dict(n_riders=0, shape="bunch"), "n_riders"),
        (dict(n_riders=201, shape="bunch"), "n_riders"),
        (dict(n_riders=2.0, shape="bunch"), "n_riders"),
        (dict(n_riders=True, shape="bunch"), "n_riders"),
        (dict(n_riders=5, shape="blob"), "shape"),
        (dict(n_riders=5, shape="bunch", gap_m=-0.1), "gap_m"),
        (dict(n_riders=5, shape="bunch", gap_m=float("nan")), "gap_m"),
        (dict(n_riders=5, shape="bunch", lateral_m=0.1), "lateral_m"),
        (dict(n_riders=5, shape="bunch", lateral_m=float("inf")), "lateral_m"),
    ],
)
def test_formation_refuses_bad_input_naming_it(kwargs: dict, name: str) -> None:
    with pytest.raises(ValueError, match=name):
        cycling.formation(**kwargs)


@pytest.mark.parametrize(
    "positions",
    [
        np.zeros((0, 2)),
        np.zeros((3,)),
        np.zeros((3, 3)),
        [[0.0, float("nan")]],
        [[1e7, 0.0]],
        "riders",
        np.zeros((2001, 2)),
    ],
)
def test_formation_drag_refuses_bad_positions(positions: object) -> None:
    with pytest.raises(ValueError, match="positions_xy"):
        cycling.formation_drag(positions)  # type: ignore[arg-type]


def test_formation_drag_refuses_an_unknown_model() -> None:
    with pytest.raises(ValueError, match="model"):
        cycling.formation_drag(BUNCH, "guess")  # type: ignore[arg-type]
