"""Numbers in a scene's panel never read "-0.00" or "+0.00" (an outside tester: "Sideways … -0.00 m")."""

from __future__ import annotations

import pytest
from helpers.properties import examples
from hypothesis import given, settings
from hypothesis import strategies as st

from scenes._numbers import fixed, signed


@pytest.mark.parametrize(
    ("value", "digits", "as_fixed", "as_signed"),
    [
        (-0.004, 2, "0.00", "0.00"),
        (0.004, 2, "0.00", "0.00"),
        (-0.0, 1, "0.0", "0.0"),
        (-0.006, 2, "-0.01", "-0.01"),
        (1.25, 2, "1.25", "+1.25"),
        (-40.04, 1, "-40.0", "-40.0"),
        (0.05, 0, "0", "0"),
    ],
)
def test_a_value_that_rounds_to_zero_has_no_sign(value: float, digits: int, as_fixed: str, as_signed: str) -> None:
    assert fixed(value, digits) == as_fixed
    assert signed(value, digits) == as_signed


@settings(max_examples=examples(500))
@given(st.floats(allow_nan=False, allow_infinity=False, min_value=-1e6, max_value=1e6), st.integers(0, 4))
def test_the_words_are_the_number_rounded_with_a_sign_only_off_zero(value: float, digits: int) -> None:
    text, with_sign = fixed(value, digits), signed(value, digits)
    assert float(text) == float(with_sign) == float(f"{value:.{digits}f}")
    if float(text) == 0.0:
        assert text == with_sign == f"{0:.{digits}f}"
    else:
        assert text == f"{value:.{digits}f}" and with_sign == f"{value:+.{digits}f}"
