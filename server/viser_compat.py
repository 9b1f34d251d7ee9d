"""The one change this project makes to viser's Python side, for speed; applied once, when ``scenes`` is imported.

viser 1.1.1 casts every property write through the property's type hint first
(``AssignablePropsBase._cast_value_recursive``), and the cast compares the hint with four ``npt.NDArray[...]``
aliases that it builds anew on every call. Building them runs typing's substitution (numpy's ``NDArray`` is a
``types.GenericAlias``, which caches nothing): about 50 µs a write, 0.8 ms of a 1.75 ms peloton input on this
machine. :func:`cast_value_recursive` is the same function comparing with aliases built once;
``tests/test_viser_patches.py`` holds it to the original for every property hint viser declares.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt
import viser
from viser import _assignable_props_api as props_api

VISER_VERSION = "1.1.1"
"""The viser the patch was written against (pinned in pyproject.toml); any other is left as it is."""

ORIGINAL_CAST: Any = props_api.AssignablePropsBase._cast_value_recursive
"""viser's own cast, kept for the test that compares the two."""

_FLOAT16, _FLOAT32, _FLOAT64, _UINT8 = (
    npt.NDArray[np.float16],
    npt.NDArray[np.float32],
    npt.NDArray[np.float64],
    npt.NDArray[np.uint8],
)


def cast_value_recursive(self: Any, hint: Any, value: Any, prop_name: str) -> Any:
    """viser 1.1.1's ``_cast_value_recursive``, line for line, with the ``NDArray`` aliases built once."""
    if hint == _FLOAT16:
        return np.asarray(value).astype(np.float16)
    elif hint == _FLOAT32:
        return np.asarray(value).astype(np.float32)
    elif hint == _FLOAT64:
        return np.asarray(value).astype(np.float64)
    elif hint == _UINT8 and "color" in prop_name:
        return props_api.colors_to_uint8(value)
    if isinstance(value, np.ndarray):
        return value
    if (
        isinstance(value, tuple)
        and hasattr(hint, "__origin__")
        and hint.__origin__ is tuple
        and hasattr(hint, "__args__")
        and len(hint.__args__) == 2
        and hint.__args__[1] is ...
    ):
        element_type = hint.__args__[0]
        return tuple(cast_value_recursive(self, element_type, item, prop_name) for item in value)
    return value


def apply() -> bool:
    """Install :func:`cast_value_recursive` on viser's props base class; False (nothing done) on another viser."""
    if viser.__version__ != VISER_VERSION:
        return False
    props_api.AssignablePropsBase._cast_value_recursive = cast_value_recursive  # type: ignore[method-assign]
    return True
