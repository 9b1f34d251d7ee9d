"""One latest-wins worker thread for a scene's costly work (meshing, ray-marching, outcome maps).

A callback records what it wants and calls :meth:`LatestWorker.submit`; the worker runs the newest job only, on its
own thread, so a burst of inputs (a slider dragged, a gizmo moved) costs one job, not one per input. A job may ask to
wait for a quiet spell (``delay_s``): it starts only once that long has passed with no newer submission, so a drag
redraws its cheap parts at full speed and the costly job runs once, after the drag. :meth:`LatestWorker.schedule`
asks for a job later without pushing back one already waiting (a scene's "render the reference once things rest").

The thread sleeps on a condition until a job is due or :meth:`LatestWorker.close` is called: it never polls.
:meth:`LatestWorker.wait_idle` sleeps the same way until nothing is waiting or running.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable

logger = logging.getLogger(__name__)

__all__ = ["LatestWorker"]


class LatestWorker:
    """Runs submitted jobs on one daemon thread, newest only: a job still waiting is replaced by a newer one.

    Args:
        name: The thread's name (shows in logs and tracebacks).
        on_error: Called with the exception when a job raises; the default logs it. The worker goes on either way:
            one failed job must not stop every later one.
    """

    def __init__(self, name: str, on_error: Callable[[Exception], None] | None = None) -> None:
        self._condition = threading.Condition()
        self._job: Callable[[], object] | None = None
        self._due = 0.0
        self._busy = False
        self._closed = False
        self._on_error = on_error
        self.thread = threading.Thread(target=self._run, name=name, daemon=True)
        self.thread.start()

    def submit(self, job: Callable[[], object], delay_s: float = 0.0) -> None:
        """Replace any waiting job with ``job``, due ``delay_s`` seconds from now (a newer submission restarts it)."""
        with self._condition:
            self._job = job
            self._due = time.monotonic() + max(0.0, delay_s)
            self._condition.notify_all()

    def schedule(self, job: Callable[[], object], delay_s: float) -> None:
        """Ask for ``job`` in ``delay_s`` seconds unless a job is already waiting (that one runs, and is kept)."""
        with self._condition:
            if self._job is None:
                self._job = job
                self._due = time.monotonic() + max(0.0, delay_s)
                self._condition.notify_all()

    def idle(self) -> bool:
        """Whether no job is waiting or running."""
        with self._condition:
            return self._job is None and not self._busy

    def wait_idle(self, timeout_s: float) -> bool:
        """Sleep until no job is waiting or running (True), or ``timeout_s`` has passed (False)."""
        with self._condition:
            return self._condition.wait_for(
                lambda: self._closed or (self._job is None and not self._busy), timeout=timeout_s
            )

    def close(self, timeout_s: float = 60.0) -> bool:
        """Drop any waiting job, stop the thread once its running job ends; True when it stopped in time."""
        with self._condition:
            self._closed = True
            self._job = None
            self._condition.notify_all()
        if threading.current_thread() is self.thread:
            return True
        self.thread.join(timeout_s)
        return not self.thread.is_alive()

    @property
    def closed(self) -> bool:
        return self._closed

    def _next_job(self) -> Callable[[], object] | None:
        """Sleep until a job is due (returned) or the worker is closed (None)."""
        with self._condition:
            while not self._closed:
                if self._job is not None:
                    wait_s = self._due - time.monotonic()
                    if wait_s <= 0.0:
                        job, self._job = self._job, None
                        self._busy = True
                        return job
                    self._condition.wait(wait_s)
                else:
                    self._condition.wait()
            return None

    def _report(self, error: Exception) -> None:
        if self._on_error is not None:
            try:
                self._on_error(error)
                return
            except Exception:
                logger.exception("%s: the error handler failed too", self.thread.name)
        logger.error("%s: a background job failed; the last result stays", self.thread.name, exc_info=error)

    def _run(self) -> None:
        while (job := self._next_job()) is not None:
            try:
                job()
            except Exception as error:  # the worker outlives a failed job
                self._report(error)
            finally:
                with self._condition:
                    self._busy = False
                    self._condition.notify_all()
