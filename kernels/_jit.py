"""How every kernel is compiled: ``numba.njit(cache=True, no_cfunc_wrapper=True)``, falling back to no disk cache
where numba finds no writable cache directory.

Compiled code is cached in ``__pycache__`` beside each kernel module, or, where that is read-only (an installed
package), in numba's user-wide cache (``~/.cache/numba``; ``NUMBA_CACHE_DIR`` overrides both; with neither writable,
no disk cache). :mod:`kernels._jit_cache` keeps the cache in step with the sources.

No kernel is called through a C function pointer (numba's first-class functions, ``cfunc``), so none gets numba's C
wrapper: about a twentieth of a cold compile.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

from numba import njit

UNCACHED: list[str] = []
"""Compiled kernels that run without numba's disk cache (none where a cache directory is writable)."""


def compiled(**options: Any) -> Callable[[Callable[..., Any]], Any]:
    """``numba.njit(cache=True, no_cfunc_wrapper=True, **options)``; without the disk cache where numba finds no
    writable directory.

    numba caches beside the module, else in ``~/.cache/numba`` (or ``NUMBA_CACHE_DIR``); where none of those is
    writable it refuses ``cache=True`` outright, which would make the kernel's module fail to import.
    """

    options = {"no_cfunc_wrapper": True, **options}  # (a flag numba's type stubs do not list)

    def decorate(function: Callable[..., Any]) -> Any:
        try:
            return njit(cache=True, **options)(function)
        except RuntimeError as error:
            if "no locator available" not in str(error):
                raise
            if not UNCACHED:
                logging.getLogger(__name__).warning(
                    "no writable numba cache directory: the kernels compile at every start"
                )
            UNCACHED.append(function.__name__)
            return njit(**options)(function)

    return decorate
