"""How every kernel is compiled: ``numba.njit(no_cfunc_wrapper=True)``; an entry point (a function Python calls)
with numba's disk cache, a helper (a function only compiled code calls) without the cache or the CPython wrapper.

An entry point's compiled code is cached in ``__pycache__`` beside its module, or, where that is read-only (an
installed package), in numba's user-wide cache (``~/.cache/numba``; ``NUMBA_CACHE_DIR`` overrides both; with neither
writable, no disk cache). :mod:`kernels._jit_cache` keeps the cache in step with the sources.

What numba builds by default and nothing here uses is left out (each measured on a cold compile):

- the C wrapper, for calls through a C function pointer (numba's first-class functions, ``cfunc``): no kernel is
  called that way. About a twentieth of a cold compile.
- a helper's CPython wrapper, which unboxes Python arguments and boxes the result: only entry points
  (``compiled(from_python=True)``) need one; about a fifteenth of a cold compile. Calling a helper from Python
  would jump to a wrapper that does not exist; :class:`CompiledOnly` refuses the call instead.
- a helper's disk cache: an entry point's cached code holds every helper it calls (numba links them in), and a
  process that loads entry points from the cache never compiles a helper. About 2 % of a cold compile.

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
    """``numba.njit(no_cfunc_wrapper=True, **options)``: with ``from_python``, an entry point with numba's disk cache
    (without it where numba finds no writable directory); otherwise a :class:`CompiledOnly` helper.

    numba caches beside the module, else in ``~/.cache/numba`` (or ``NUMBA_CACHE_DIR``); where none of those is
    writable it refuses ``cache=True`` outright, which would make the kernel's module fail to import.
    """

    options = {"no_cfunc_wrapper": True, **options}  # (a flag numba's type stubs do not list)

    def decorate(function: Callable[..., Any]) -> Any:
        dispatcher = njit(**options)(function)
        if not from_python:  # the same dispatcher, but for the wrapper, Python's call and the disk cache
            return CompiledOnly(
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
