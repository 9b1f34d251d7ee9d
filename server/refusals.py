"""The log of what the gate refuses: one line per kind of refusal per interval, the ones in between counted."""

from __future__ import annotations

import logging
import threading
import time

logger = logging.getLogger(__name__)


class RefusalLog:
    """One log line per kind of refusal per ``interval_s``; the ones in between are counted, not logged."""

    def __init__(self, interval_s: float = 10.0) -> None:
        self.interval_s = interval_s
        self._lock = threading.Lock()
        self._last: dict[str, tuple[float, int]] = {}

    def refuse(self, kind: str, detail: str) -> None:
        now = time.monotonic()
        with self._lock:
            last = self._last.get(kind)
            if last is not None and now - last[0] < self.interval_s:
                self._last[kind] = (last[0], last[1] + 1)
                return
            unlogged = 0 if last is None else last[1]
            self._last[kind] = (now, 0)
        more = f" ({unlogged} more of this kind since the last line)" if unlogged else ""
        logger.warning("refused %s: %s%s", kind, detail[:200], more)

    def reset(self) -> None:
        """Forget what was logged (tests use it between cases)."""
        with self._lock:
            self._last.clear()


refusals = RefusalLog()
"""The process's refusal log (frames are refused before it is known which server they reached)."""
