"""FABRIK's public helpers and flags refuse bad input by name (the family of kernels/_checks.py's refusals)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from kernels import fabrik

JOINTS = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]]


@pytest.mark.parametrize("value", ["no", None, math.nan, 1, 0, 1 + 2j, object(), [], np.array([True, False])])
@pytest.mark.parametrize("method", ["fabrik", "ccd", "jacobian_dls"])
def test_extrapolate_is_a_bool_or_refused_by_name(value: Any, method: str) -> None:
    # It was int(bool(value)): "no" and NaN meant True, and an array raised numpy's "truth value is ambiguous".
    with pytest.raises(ValueError, match=r"^extrapolate must be True or False, got "):
        fabrik.solve(JOINTS, [1.0, 1.0, 0.0], extrapolate=value)
    with pytest.raises(ValueError, match=r"^extrapolate must be True or False, got "):
        fabrik.solve_batch([JOINTS], [[1.0, 1.0, 0.0]], solver=method, extrapolate=value)  # type: ignore[arg-type]


@pytest.mark.parametrize("value", [True, False, np.bool_(True)])
def test_extrapolate_takes_python_and_numpy_bools(value: Any) -> None:
    assert fabrik.solve(JOINTS, [1.0, 1.0, 0.0], extrapolate=value).status == "reached"


@pytest.mark.parametrize(
    ("joints", "message"),
    [
        (object(), r"^joints must be an array of real numbers"),
        (10**400, r"^joints must be finite \(within float64.s range\)"),
        ("1", r"^joints must be an array of real numbers"),
        (np.array(["a"]), r"^joints must be an array of real numbers"),
        (math.nan, r"^joints must be finite"),
        ([[0.0, 0.0, 0.0], [math.nan, 0.0, 0.0]], r"^joints must be finite, got nan at \[1, 0\]"),  # was [nan]
        ([[0.0, 0.0, 0.0], [1.7e308, 0.0, 0.0]], r"^joints must be of magnitude"),
        (0.0, r"^joints must have shape \(n \+ 1, d\) or \(B, n \+ 1, d\) with d = 2 or 3, got \(\)"),
        ([1.0, 2.0], r"^joints must have shape .* got \(2,\)"),
        ([[0.0, 0.0, 0.0, 0.0]], r"^joints must have shape .* got \(1, 4\)"),
        # Kind: a chain of no links. One joint gave an empty array, where its docstring promises the error.
        ([[0.0, 0.0]], r"^joints must hold at least two joints \(n ≥ 1 link\), got \(1, 2\)"),
        (np.zeros((3, 1, 3)), r"^joints must hold at least two joints \(n ≥ 1 link\), got \(3, 1, 3\)"),
        (np.zeros((0, 3)), r"^joints must hold at least two joints"),
    ],
)
def test_link_lengths_refuses_what_is_not_a_chain_by_name(joints: Any, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        fabrik.link_lengths(joints)


def test_link_lengths_of_a_chain_and_a_batch() -> None:
    np.testing.assert_array_equal(fabrik.link_lengths(JOINTS), [1.0, 1.0])
    np.testing.assert_array_equal(fabrik.link_lengths([[0.0, 0.0], [3.0, 4.0]]), [5.0])
    np.testing.assert_array_equal(fabrik.link_lengths([JOINTS, JOINTS]), [[1.0, 1.0], [1.0, 1.0]])
    # Scaled before the squares: neither 1e149 m nor 1e-160 m is lost.
    np.testing.assert_allclose(fabrik.link_lengths([[0.0, 0.0], [3e149, 4e149]]), [5e149], rtol=1e-15)
    np.testing.assert_allclose(fabrik.link_lengths([[0.0, 0.0], [3e-160, 4e-160]]), [5e-160], rtol=1e-15)


# Kind: a scalar argument told it must be an array ("upper_length must be an array of real numbers, got True").
@pytest.mark.parametrize("bad", [True, None, "1", [1.0], math.nan, -1.0], ids=repr)
def test_a_two_bone_length_is_refused_as_a_number(bad: Any) -> None:
    for name in ("upper_length", "lower_length"):
        lengths = {"upper_length": 1.0, "lower_length": 1.0, name: bad}
        with pytest.raises(ValueError, match=rf"^{name} must be a finite number"):
            fabrik.two_bone(
                [0.0, 0.0, 0.0], lengths["upper_length"], lengths["lower_length"], [1.0, 1.0, 0.0], [0, 0, 1]
            )
