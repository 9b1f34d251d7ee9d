"""Numbers as a person reads them in a scene's panel: never "-0.00" or "+0.00" for a value that rounds to zero."""

from __future__ import annotations


def fixed(value: float, digits: int) -> str:
    """``value`` with ``digits`` decimals; a value that rounds to zero reads "0.00", not "-0.00"."""
    text = f"{value:.{digits}f}"
    return text.removeprefix("-") if float(text) == 0.0 else text


def signed(value: float, digits: int) -> str:
    """``value`` with its sign and ``digits`` decimals ("+1.25", "-0.40"); one that rounds to zero reads "0.00", as
    neither side of it."""
    text = f"{value:+.{digits}f}"
    return text[1:] if float(text) == 0.0 else text
