"""Waiting on state another thread or process publishes: poll it, never sleep a fixed time and hope."""

from __future__ import annotations

import time
from collections.abc import Callable

POLL_S = 0.02
"""How long to sleep between two looks (s): short next to any wait, long enough not to spin."""


def wait_until(predicate: Callable[[], object], what: str, timeout_s: float = 30.0) -> None:
    """Poll ``predicate()`` until it is true.

    Args:
        predicate: Looks at the state; truthy once the wait is over.
        what: What is waited for, named in the failure.
        timeout_s: How long before the wait counts as a hang (s).

    Raises:
        AssertionError: ``predicate()`` stayed false for ``timeout_s``.
    """
    deadline = time.monotonic() + timeout_s
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout_s} s waiting for {what}")
        time.sleep(POLL_S)
