"""numba compilation of the ball kernels: ``njit(cache=True)``, falling back to no disk cache where numba finds
no writable cache directory.

Compiled code is cached in ``__pycache__`` beside each module of :mod:`kernels.ball`, or, where that is read-only (an
installed package), in numba's user-wide cache (``~/.cache/numba``; ``NUMBA_CACHE_DIR`` overrides both; with neither
writable, no disk cache).
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

from numba import njit

UNCACHED: list[str] = []
"""Compiled cores that run without numba's disk cache (none where a cache directory is writable)."""


def compiled(**options: Any) -> Callable[[Callable[..., object]], Any]:
    """``numba.njit(cache=True, **options)``; without the disk cache where numba finds no writable directory.

    numba caches beside the module, else in ``~/.cache/numba`` (or ``NUMBA_CACHE_DIR``); where none of those is
    writable it refuses ``cache=True`` outright, which would make this module fail to import.
    """

    def decorate(function: Callable[..., object]) -> Any:
        try:
            return njit(cache=True, **options)(function)
        except RuntimeError as error:
            if "no locator available" not in str(error):
                raise
            if not UNCACHED:
                logging.getLogger(__name__).warning(
                    "no writable numba cache directory: the ball kernels compile at every start"
                )
            UNCACHED.append(function.__name__)
            return njit(**options)(function)

    return decorate
