"""How every kernel is compiled: ``numba.njit(cache=True, no_cfunc_wrapper=True)``, and, for a function that only
compiled code calls, without numba's CPython wrapper; falling back to no disk cache where numba finds no writable
cache directory.

Compiled code is cached in ``__pycache__`` beside each kernel module, or, where that is read-only (an installed
package), in numba's user-wide cache (``~/.cache/numba``; ``NUMBA_CACHE_DIR`` overrides both; with neither writable,
no disk cache). :mod:`kernels._jit_cache` keeps the cache in step with the sources.

Two wrappers numba builds around every compiled function by default are left out where nothing uses them:

- the C wrapper, for calls through a C function pointer (numba's first-class functions, ``cfunc``): no kernel is
  called that way. About a twentieth of a cold compile.
- the CPython wrapper, which unboxes Python arguments and boxes the result: only functions that Python calls need it
  (``compiled(from_python=True)``: the entry points, and a few helpers the tests call on their own). The others,
  called only from compiled code, are built without it, about a fifteenth of a cold compile. Calling one of those
  from Python would jump to a wrapper that does not exist; :class:`CompiledOnly` refuses the call instead.

numba internals used here, read from numba 0.68: the dispatcher class of the CPU target
(``numba.core.registry.CPUDispatcher``), which ``njit`` itself builds, and the target flag ``no_cpython_wrapper``,
which numba sets for its own internal functions.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

from numba import njit
from numba.core.registry import CPUDispatcher

UNCACHED: list[str] = []
"""Compiled kernels that run without numba's disk cache (none where a cache directory is writable)."""


class CompiledOnly(CPUDispatcher):
    """A dispatcher built without the CPython wrapper: compiled code calls it; Python may not."""

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        raise TypeError(
            f"{self.py_func.__qualname__} is compiled for compiled callers only; "
            "declare it with compiled(from_python=True) to call it from Python"
        )


def compiled(*, from_python: bool = False, **options: Any) -> Callable[[Callable[..., Any]], Any]:
    """``numba.njit(cache=True, no_cfunc_wrapper=True, **options)``; without the CPython wrapper unless
    ``from_python``; without the disk cache where numba finds no writable directory.

    numba caches beside the module, else in ``~/.cache/numba`` (or ``NUMBA_CACHE_DIR``); where none of those is
    writable it refuses ``cache=True`` outright, which would make the kernel's module fail to import.
    """

    options = {"no_cfunc_wrapper": True, **options}  # (a flag numba's type stubs do not list)

    def decorate(function: Callable[..., Any]) -> Any:
        dispatcher = njit(**options)(function)
        if not from_python:  # the same dispatcher, but for the wrapper and Python's call
            dispatcher = CompiledOnly(
                py_func=function,
                locals=dispatcher.locals,
                targetoptions={**dispatcher.targetoptions, "no_cpython_wrapper": True},
            )
        try:
            dispatcher.enable_caching()
        except RuntimeError as error:
            if "no locator available" not in str(error):
                raise
            if not UNCACHED:
                logging.getLogger(__name__).warning(
                    "no writable numba cache directory: the kernels compile at every start"
                )
            UNCACHED.append(function.__name__)
        return dispatcher

    return decorate
