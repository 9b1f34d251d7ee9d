"""The shared input checks: what they accept, and messages that name the argument and quote the value briefly."""

from __future__ import annotations

import math
from collections.abc import Callable
from fractions import Fraction
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from kernels import _checks
from tests.helpers.properties import examples


@pytest.mark.parametrize("value", [np.array(["rk4", "euler"]), None, 3, "RK4", b"rk4", ["rk4"], math.nan])
def test_a_choice_refuses_what_is_not_one_of_its_strings_naming_it(value: object) -> None:
    # An array compared with `in` raised numpy's "truth value of an array is ambiguous", naming nothing.
    with pytest.raises(ValueError, match=r"^method must be one of 'euler', 'rk4', got "):
        _checks.choice("method", value, ("euler", "rk4"))


def test_a_choice_returns_its_string() -> None:
    assert _checks.choice("method", "rk4", ("euler", "rk4")) == "rk4"


@pytest.mark.parametrize("value", ["no", math.nan, 0, 1, None, np.array([True])])
def test_a_flag_is_a_bool_only(value: object) -> None:
    with pytest.raises(ValueError, match=r"^extrapolate must be True or False, got "):
        _checks.flag("extrapolate", value)


@pytest.mark.parametrize(("value", "expected"), [(True, True), (np.bool_(False), False)])
def test_a_flag_returns_a_python_bool(value: object, expected: bool) -> None:
    assert _checks.flag("extrapolate", value) is expected


@pytest.mark.parametrize(
    ("value", "quoted"),
    [
        (np.full(5000, math.nan), "got nan at [0] of array([nan, nan, nan, ..., nan, nan, nan], shape=(5000,))"),
        ([1.0] * 50 + [math.nan], "got nan at [50] of [1.0, 1.0, 1.0, 1.0, 1.0, 1.0, ...]"),
        ([[1.0, 2.0], [3.0, math.inf]], "got inf at [1, 1] of [[1.0, 2.0], [3.0, inf]]"),
        (math.inf, "got inf"),
    ],
)
def test_a_non_finite_array_is_refused_naming_the_first_bad_element_and_quoting_the_value_briefly(
    value: object, quoted: str
) -> None:
    with pytest.raises(ValueError) as caught:
        _checks.finite_array("elevation_m", value)  # type: ignore[arg-type]
    assert str(caught.value) == f"elevation_m must be finite, {quoted}"


@pytest.mark.parametrize(
    "value", [np.arange(10**6, dtype=float), list(range(10**5)), "x" * 10**6, 10**4000, tuple(range(1000))]
)
def test_a_refused_value_is_quoted_in_at_most_two_hundred_characters(value: object) -> None:
    assert len(_checks.shown(value)) <= 200
    with pytest.raises(ValueError) as caught:
        _checks.positive("gap_m", value)
    assert str(caught.value).startswith("gap_m must be a finite number, got ") and len(str(caught.value)) < 260


# The kind, across the kernels: a refusal that quoted its input with !r printed all of it (600,000 characters for
# 50,000 bounds). Every refusal quotes through shown().
_N = 50_000


def _long_refusals() -> list[tuple[str, Callable[[], object]]]:
    from kernels import ball, course, fabrik, sdf

    chain = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]
    many = [[0.0, 0.0, 0.0]] * _N
    x = np.linspace(0.0, 1000.0, 10)
    return [
        ("make_grid bounds", lambda: sdf.make_grid(sdf.default_scene(), 16, bounds=[[0.0, 0.0]] * _N)),
        ("sd_sphere p", lambda: sdf.sd_sphere([*many, [1e200, 0.0, 0.0]], 1.0)),
        ("smin_poly a", lambda: sdf.smin_poly(["x"] * _N, [0.0] * _N, 0.1)),
        ("op_round d", lambda: sdf.op_round([0.0] * _N + [None], 0.1)),  # type: ignore[arg-type]
        ("odds_map distances", lambda: ball.odds_map([1000.0] * _N, [0.0], 25.0, 0.3, 0.0, (0.0, 0.0, 50.0))),
        ("odds_map angles", lambda: ball.odds_map([20.0], [3.0] * _N, 25.0, 0.3, 0.0, (0.0, 0.0, 50.0))),
        ("solve max_iterations", lambda: fabrik.solve(chain, [1.0, 0.0, 0.0], max_iterations=many)),  # type: ignore[arg-type]
        ("two_bone upper_length", lambda: fabrik.two_bone((0, 0), many, 1.0, (1, 1), (0, 1))),  # type: ignore[arg-type]
        ("course_from_xy east_m", lambda: course.course_from_xy(np.full(_N, np.nan), x, x)),
        ("simulate velocity", lambda: ball.simulate((0.0, 0.0, 1.0), [1.0] * _N, (0.0, 0.0, 0.0))),
    ]


@pytest.mark.parametrize("index", range(10))
def test_no_refusal_prints_its_whole_input(index: int) -> None:
    label, call = _long_refusals()[index]
    with pytest.raises(ValueError) as caught:
        call()
    assert len(str(caught.value)) < 500, (label, len(str(caught.value)))


@pytest.mark.parametrize(
    "value",
    [[[0, 1, 3]], [[0, 1, -1]], [[0.0, 1.0, 2.0]], [[True, False, True]], [["0", "1", "2"]], [0, 1, 2], [[0, 1]], None],
)
def test_indices_into_vertices_are_integers_of_their_shape_within_the_count(value: object) -> None:
    with pytest.raises(ValueError, match=r"^faces must be \(N, 3\) integer indices into the 3 vertices, got "):
        _checks.indices("faces", value, 3, 3)  # type: ignore[arg-type]


def test_indices_come_back_as_int64_rows_and_an_empty_list_as_no_rows() -> None:
    np.testing.assert_array_equal(_checks.indices("faces", [[0, 1, 2]], 3, 3), [[0, 1, 2]])
    assert _checks.indices("faces", np.array([[0, 1, 2]], np.uint8), 3, 3).dtype == np.int64
    assert _checks.indices("edges", [], 2, 0).shape == (0, 2)


@pytest.mark.parametrize(
    ("value", "expected"),
    [
        ((3.0, 0.0, -4.0), (0.6, 0.0, -0.8)),
        ((3e300, 4e300, 0.0), (0.6, 0.8, 0.0)),  # its squares overflow to inf
        ((0.0, 3e-320, -4e-320), (0.0, 0.6, -0.8)),  # its squares underflow to 0
        ((0.0, 0.0, 7.0), (0.0, 0.0, 1.0)),
    ],
)
def test_a_direction_is_its_unit_vector_at_any_finite_length(
    value: tuple[float, ...], expected: tuple[float, ...]
) -> None:
    unit = _checks.direction("axis", value, 3)
    np.testing.assert_allclose(unit, expected, rtol=1e-3, atol=1e-15)  # 3e-320 is subnormal: 3 digits
    assert math.isclose(float(unit @ unit), 1.0, rel_tol=1e-15)


@pytest.mark.parametrize(
    ("value", "what", "message"),
    [
        ((0.0, 0.0, 0.0), "", r"^axis must be non-zero, got \(0\.0, 0\.0, 0\.0\)$"),
        ((0.0, -0.0, 0.0, 0.0), "quaternion (w, x, y, z)", r"^axis must be a non-zero quaternion \(w, x, y, z\), got "),
        ((1.0, math.inf, 0.0), "", r"^axis must be finite"),
        ((1.0, 0.0), "", r"^axis must have shape \(3,\), got \(2,\)$"),
    ],
)
def test_a_direction_refuses_a_zero_or_bad_vector_naming_it(value: tuple[float, ...], what: str, message: str) -> None:
    size = 4 if what else 3
    with pytest.raises(ValueError, match=message):
        _checks.direction("axis", value, size, what)


_ANY_FINITE = st.floats(allow_nan=False, allow_infinity=False)


@settings(max_examples=examples(300), deadline=None)
@given(st.lists(_ANY_FINITE, min_size=3, max_size=3).filter(any))
def test_a_direction_is_a_unit_vector_along_any_finite_non_zero_vector(value: list[float]) -> None:
    # Against exact rational arithmetic: the unit vector's components are in the input's ratios, to rounding.
    unit = _checks.direction("axis", value, 3)
    assert abs(float(unit @ unit) - 1.0) <= 1e-15  # a few ulps of 1
    exact = [Fraction(v) for v in value]
    largest = max(abs(v) for v in exact)
    for got, v in zip(unit.tolist(), exact, strict=True):
        # u_i · |v| / max|v| = v_i / max|v|: compared where the component is not lost below the largest's ulp
        norm = math.sqrt(float(sum((x / largest) ** 2 for x in exact)))
        assert got == pytest.approx(float(v / largest) / norm, rel=1e-15, abs=1e-15)


# Kind: a value that is not a number, called "not finite" (None became NaN in an object array) or taken as one
# (numpy turns [1.0, True] into [1.0, 1.0]).
@pytest.mark.parametrize(
    "value",
    [
        None,
        [1.0, None],
        (None, None),
        np.array([1.0, None], dtype=object),
        [True, 1.0],
        (1.0, [2.0, False]),
        [[1.0, 2.0], [3.0, np.True_]],
        ["1.0"],
        [1.0, 2 + 0j],
    ],
    ids=repr,
)
def test_what_is_not_a_real_number_is_refused_as_such(value: Any) -> None:
    with pytest.raises(ValueError, match=r"^speed_ms must be an array of real numbers, got "):
        _checks.finite_array("speed_ms", value)


@pytest.mark.parametrize(
    ("value", "expected"),
    [([1, 2**80], [1.0, 2.0**80]), ([Fraction(1, 4), 2], [0.25, 2.0]), (np.array([1.0, 2], dtype=object), [1.0, 2.0])],
    ids=repr,
)
def test_real_numbers_of_any_python_kind_are_taken(value: Any, expected: list[float]) -> None:
    np.testing.assert_array_equal(_checks.finite_array("speed_ms", value), expected)
