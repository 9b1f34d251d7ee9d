"""The array checks every function of :mod:`kernels.cycling` shares: finite, positive and non-negative arrays (those
of :mod:`kernels._checks`), shapes that broadcast, the drivetrain efficiency, and a domain's closed ranges.

Every function of the package broadcasts, so its arguments are arrays of any shape.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from kernels import _checks

_finite = _checks.finite_array
_positive = _checks.positive_array
_non_negative = _checks.non_negative_array


def _shape(name: str, value: ArrayLike) -> tuple[int, ...]:
    if type(value) is float or type(value) is int:  # the common case, without numpy's conversion
        return ()
    try:
        return np.shape(value)
    except ValueError as error:  # a ragged list: numpy's "inhomogeneous shape" names nothing
        raise ValueError(f"{name} must be an array of real numbers, got {_checks.shown(value)}") from error


def _broadcast(**values: ArrayLike) -> None:
    """``ValueError`` naming the first of ``values`` whose shape does not broadcast with the ones before it (numpy
    would say "operands could not be broadcast together" and name none)."""
    shapes = [(name, _shape(name, value)) for name, value in values.items()]
    if not any(here for _, here in shapes):  # all scalars, the common case: nothing to broadcast
        return
    shape: tuple[int, ...] = ()
    for name, here in shapes:
        try:
            shape = np.broadcast_shapes(shape, here)
        except ValueError as error:
            raise ValueError(
                f"{name} must broadcast with the shape {shape} of the arguments before it, got {here}"
            ) from error


def _efficiency(value: ArrayLike) -> NDArray[np.float64]:
    array = _finite("drivetrain_efficiency", value)
    if np.any((array < 1e-3) | (array > 1.0)):  # a thousandth: far below any drivetrain, and no overflow
        raise ValueError(f"drivetrain_efficiency must be in [0.001, 1], got {_checks.shown(value)}")
    return array


_POSITIVE = frozenset({"mass_kg", "air_density", "wheel_radius_m", "cda_m2"})
"""Arguments that must be > 0: a domain's range (closed) may start at 0 for them, and 0 itself is refused."""


def _check_domain(function: str, domain: dict[str, tuple[float, float]], **values: ArrayLike) -> None:
    """``ValueError`` naming the first of ``values`` that is not finite, not > 0 where it must be, or outside its
    ``domain`` range."""
    for name, value in values.items():
        low, high = domain[name]
        array = _finite(name, value)
        if name in _POSITIVE and np.any(array <= 0.0):  # else -80 kg was told a range [0, …] that holds 0
            raise ValueError(f"{name} must be > 0, got {_checks.shown(value)}")
        if np.any((array < low) | (array > high)):
            raise ValueError(f"{name} must be in [{low:g}, {high:g}] for {function}, got {_checks.shown(value)}")
