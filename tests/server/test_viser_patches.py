"""The patched property cast (:func:`server.viser_compat.cast_value_recursive`) returns what viser 1.1.1's own does, for
every property hint viser declares and values of every shape the scenes write, and it is the one in use."""

from __future__ import annotations

import dataclasses
from typing import Any, get_type_hints

import numpy as np
import pytest
import viser

# Importing server (the package) applies the patch.
from server.viser_compat import ORIGINAL_CAST, cast_value_recursive, installed_property_cast
from server.viser_compat import messages as _messages


class _Viser:
    """A ``self`` whose recursion goes through viser's own cast (the class attribute is the patched one)."""

    _cast_value_recursive = ORIGINAL_CAST


def _hints() -> list[tuple[str, str, Any]]:
    out = []
    for name in dir(_messages):
        cls = getattr(_messages, name)
        if isinstance(cls, type) and name.endswith("Props") and dataclasses.is_dataclass(cls):
            out += [(name, prop, hint) for prop, hint in get_type_hints(cls).items()]
    return out


HINTS = _hints()
VALUES: list[Any] = [
    np.arange(6.0).reshape(2, 3),
    np.arange(6, dtype=np.int64),
    np.array([0.2, 0.5, 1.0], dtype=np.float32),
    np.array([[10, 300, -4]]),
    [1.0, 2.0, 3.0],
    (1.0, 2.0, 3.0),
    (np.zeros(3), np.ones(3)),
    ((1, 2), (3, 4)),
    "text",
    None,
    1.5,
    True,
]


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return (
            isinstance(a, np.ndarray)
            and isinstance(b, np.ndarray)
            and a.dtype == b.dtype
            and a.shape == b.shape
            and bool(np.array_equal(a, b, equal_nan=a.dtype.kind in "fc"))
        )
    if isinstance(a, tuple) and isinstance(b, tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    return type(a) is type(b) and a == b


def test_there_are_hints_of_every_kind_the_cast_handles() -> None:
    kinds = {repr(hint) for _, _, hint in HINTS}
    assert len(HINTS) > 100
    for dtype in ("float16", "float32", "float64", "uint8"):
        assert any(dtype in kind and "ndarray" in kind for kind in kinds), dtype
    assert any(kind.startswith("typing.Tuple[") and "..." in kind for kind in kinds)


@pytest.mark.parametrize("value", VALUES, ids=lambda v: type(v).__name__ + repr(np.shape(v)))
def test_the_patched_cast_returns_what_viser_returns(value: Any) -> None:
    viser_self = _Viser()
    for cls, prop, hint in HINTS:
        # viser casts uint8 arrays only for names with "color": every uint8 prop's name has it, so try one without.
        for name in (prop, prop + "_color", "points"):
            try:
                expected: Any = ORIGINAL_CAST(viser_self, hint, value, name)
            except Exception as error:  # the same failure, of the same type
                with pytest.raises(type(error)):
                    cast_value_recursive(viser_self, hint, value, name)
                continue
            got = cast_value_recursive(viser_self, hint, value, name)
            assert _same(got, expected), (cls, prop, hint, value, got, expected)


def test_the_patch_is_in_use_and_writes_cast() -> None:
    assert viser.__version__ == "1.1.1"
    assert installed_property_cast() is cast_value_recursive
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        cloud = server.scene.add_point_cloud("/cloud", points=np.zeros((2, 3)), colors=np.zeros((2, 3), dtype=np.uint8))
        cloud.points = np.ones((2, 3), dtype=np.float64)  # type: ignore[assignment]  # cast to the float16 it holds
        cloud.colors = np.array([[0.0, 0.5, 1.0], [1.0, 1.0, 1.0]])  # floats in [0, 1] to uint8
        assert cloud.points.dtype == np.float16 and np.array_equal(cloud.points, np.ones((2, 3)))
        assert cloud.colors.dtype == np.uint8
        assert cloud.colors.tolist() == [[0, 127, 255], [255, 255, 255]]
    finally:
        server.stop()
