"""Compiled helpers called on their own from a test.

The kernels build a function that only compiled code calls without numba's CPython wrapper (``kernels._jit``), so
Python cannot call it. :func:`from_python` compiles the same source with the same options and the wrapper, without
the disk cache (whose index does not tell the two builds apart).
"""

from __future__ import annotations

import functools
from typing import Any

from numba import njit


@functools.cache
def from_python(helper: Any) -> Any:
    """``helper`` (a compiled-only kernel function) as a dispatcher Python can call: the same ``py_func``, compiled
    with the same target options (calling the same compiled callees), plus numba's CPython wrapper."""
    options = {
        key: value for key, value in helper.targetoptions.items() if key not in ("no_cpython_wrapper", "nopython")
    }
    return njit(**options)(helper.py_func)
