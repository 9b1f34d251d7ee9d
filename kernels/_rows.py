"""A batch's rows shared among threads, as a ``prange`` loop shares them, without a ``parallel=True`` core.

A kernel's batch core is compiled ``nogil=True`` over a range of rows, ``core(start, stop, *args)``: plain threads
then run chunks of the batch at the same time, and the first start need not compile numba's parallel machinery
(about a second of compile per parallel core, more for a large loop body). :func:`run_rows` cuts the batch into
contiguous chunks that ``numba.get_num_threads()`` threads (the calling one and helpers started for the call) take in
turn, so rows of uneven cost balance. Each row's answer is the core's alone: the same numbers on any thread count.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

import numba

CHUNKS_PER_THREAD = 16
"""Chunks per thread a batch is cut into: enough to balance rows that cost one step and a hundred."""


def run_rows(core: Callable[..., Any], rows: int, *args: Any) -> None:
    """``core(start, stop, *args)`` over rows ``[0, rows)``, in chunks shared by ``numba.get_num_threads()`` threads.

    Threads of the call's own, not a pool: a batch run while the interpreter shuts down (an ``atexit`` hook) still
    runs, on this thread if no other can start. The first exception a chunk raises is raised here, after every
    thread has stopped.
    """
    threads = min(numba.get_num_threads(), rows)
    if threads <= 1:
        core(0, rows, *args)
        return
    chunks = min(rows, threads * CHUNKS_PER_THREAD)
    bounds = [c * rows // chunks for c in range(chunks + 1)]
    order = iter(range(chunks))  # shared: next() on it is one atomic step under the GIL
    errors: list[BaseException] = []

    def take_chunks() -> None:
        try:
            for c in order:
                core(bounds[c], bounds[c + 1], *args)
        except BaseException as exc:  # re-raised in the calling thread below
            errors.append(exc)

    helpers: list[threading.Thread] = []
    for _ in range(threads - 1):
        helper = threading.Thread(target=take_chunks, name="kernel-rows", daemon=True)
        try:
            helper.start()
        except RuntimeError:  # no new threads while the interpreter shuts down: this one takes the rest
            break
        helpers.append(helper)
    take_chunks()
    for helper in helpers:
        helper.join()
    if errors:
        raise errors[0]
