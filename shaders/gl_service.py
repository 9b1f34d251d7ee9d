"""One OpenGL context per process, on one thread that every caller shares.

An EGL context belongs to the thread that made it, and Mesa does not give back all of a context's memory when it
is released (about 50 MiB each under llvmpipe), so a context per scene build leaked. Here the context, its compiled
programs (a :class:`~shaders.renderer.Renderer`) and the thread that owns them are made once, on first use, and
live until the process ends. Every caller (each SDF gallery, each browser session's gallery, the benchmarks) hands
its GL work to :func:`run`, which queues it on that thread and waits for the answer; jobs run one at a time, in the
order they arrive.

If no context can be made, :func:`run` raises :class:`~shaders.renderer.GLUnavailableError` with the reason, every
time, without trying again.
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Callable
from concurrent.futures import Future
from typing import TypeVar

from shaders.renderer import GLUnavailableError, Renderer

T = TypeVar("T")

_lock = threading.Lock()
_jobs: queue.SimpleQueue[tuple[Callable[[Renderer], object], Future[object]]] = queue.SimpleQueue()
_thread: threading.Thread | None = None
_renderer: Renderer | None = None
_error: str | None = None


def _serve() -> None:
    global _renderer, _error
    while True:
        job, future = _jobs.get()
        if not future.set_running_or_notify_cancel():
            continue
        try:
            if _renderer is None:
                if _error is not None:
                    raise GLUnavailableError(_error)
                try:
                    _renderer = Renderer()
                except GLUnavailableError as exc:
                    _error = str(exc)
                    raise
            future.set_result(job(_renderer))
        except BaseException as exc:  # the caller re-raises it; this thread must keep serving
            future.set_exception(exc)


def submit(job: Callable[[Renderer], T]) -> Future[T]:
    """Queue ``job(renderer)`` on the process's GL thread (started on first use); its future."""
    global _thread
    with _lock:
        if _thread is None:
            _thread = threading.Thread(target=_serve, name="gl-service", daemon=True)
            _thread.start()
    future: Future[object] = Future()
    _jobs.put((job, future))
    return future  # type: ignore[return-value]


def run(job: Callable[[Renderer], T], timeout_s: float | None = None) -> T:
    """Run ``job(renderer)`` on the GL thread and return its result (or raise its exception).

    Args:
        job: work for the shared :class:`~shaders.renderer.Renderer`; it must not keep the renderer.
        timeout_s: give up waiting after this long (``TimeoutError``); the job still runs to its end.

    Raises:
        GLUnavailableError: no OpenGL context can be made on this machine (the reason in the message).
    """
    return submit(job).result(timeout=timeout_s)


def thread() -> threading.Thread | None:
    """The GL thread, once started (tests check that there is only ever one)."""
    return _thread
