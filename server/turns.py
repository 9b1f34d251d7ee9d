"""The process-wide turn a scene's callback takes to run: one at a time, in the order asked (:data:`TURNS`)."""

from __future__ import annotations

import collections
import contextlib
import threading
from collections.abc import Iterator


class Turns:
    """A process-wide turn to run a scene's callback: one at a time, in the order they asked, re-entrant per thread.

    Python runs one thread at a time anyway. Left to interleave, the callbacks of 8 tabs at 30 inputs/s each ran
    about four at once, each about four times slower (a free kick input: 2.8 ms alone, a median of 19 ms in the
    soak), so a tab's next input arrived while its last was still running and latest-wins coalescing
    (:meth:`scenes._base.Scene.callback`) never had a burst to merge. Taking turns, each callback runs at its own speed
    and the inputs that arrive meanwhile wait, to be merged. A turn is handed to the longest waiter (no tab starves).
    """

    def __init__(self) -> None:
        self._mutex = threading.Lock()
        self._owner: int | None = None
        self._depth = 0
        self._waiting: collections.deque[tuple[int, threading.Event]] = collections.deque()

    @contextlib.contextmanager
    def turn(self) -> Iterator[None]:
        """Hold the turn for the ``with`` block (at once when this thread holds it already)."""
        me = threading.get_ident()
        with self._mutex:
            if self._owner == me or (self._owner is None and not self._waiting):
                self._owner, self._depth = me, self._depth + 1
                handed = None
            else:
                handed = threading.Event()
                self._waiting.append((me, handed))
        if handed is not None:
            handed.wait()  # the holder hands the turn over: owner and depth are already ours
        try:
            yield
        finally:
            with self._mutex:
                self._depth -= 1
                if self._depth == 0:
                    if self._waiting:
                        self._owner, event = self._waiting.popleft()
                        self._depth = 1
                        event.set()
                    else:
                        self._owner = None


TURNS = Turns()
"""The one :class:`Turns` of the process: every scene's callbacks take it (a scene's own lock first)."""
