"""The gate's budgets: costly inputs per tab (a token bucket that coalesces what it holds back) and uploads in flight.

Two budgets keep one tab from starving the others. Costly inputs (a control the scene marked with
:func:`server.clean.mark_costly`: a scene switch, a Reset, a remesh) go through a per-tab token bucket
(:class:`CostlyBudget`): beyond it only the latest value of each such control is held back and delivered later,
never dropped. Uploads in flight are bounded per tab and across all tabs (:class:`Upload` is one upload's
bookkeeping). Pure bookkeeping: the gate (:mod:`server.gate`) runs it on the event loop.
"""

from __future__ import annotations

import asyncio
import dataclasses
import time
import typing
from collections.abc import Callable
from typing import Any

MIB = 1024 * 1024
MAX_UPLOAD_BYTES = 24 * MIB
"""Largest file a browser may upload (a scene may refuse smaller ones with its own message, e.g. GPX over 20 MB)."""
MAX_UPLOADS_IN_FLIGHT = 4
"""Uploads one browser may have started and not finished; viser keeps each one's parts in memory until then."""
MAX_UPLOADS_IN_FLIGHT_TOTAL = 8
"""Uploads every browser together may have in flight on one server."""
MAX_UPLOAD_BYTES_IN_FLIGHT_TOTAL = 64 * MIB
"""Bytes the uploads in flight on one server may announce together (each is held in memory until it completes)."""
MAX_UPLOAD_BYTES_IN_FLIGHT_PER_TAB = MAX_UPLOAD_BYTES
"""Bytes one tab's uploads in flight may announce together: one tab holds at most this share of the server-wide
budget, however slowly it sends."""
MIN_PART_BYTES = 4096
"""Smallest average part an upload may announce (viser's browser sends 512 KiB parts): viser keeps ~100 bytes of
bookkeeping a part, so an upload of 1-byte parts would hold ~100× the bytes the budget counts."""
UPLOAD_DEADLINE_S = 120.0
"""An upload not finished this long after its start is dropped (24 MiB needs 200 KiB/s): a tab trickling one byte
every few seconds would otherwise hold its share of the budget for good."""
UPLOAD_STALL_S = 30.0
"""An upload that has received no part for this long is dropped (its parts freed), so it stops holding the
server-wide budget."""
COSTLY_BURST = 3
"""Costly inputs (a scene rebuild, a long job: see :attr:`server.clean.ControlSpec.costly`) one tab may send at once."""
COSTLY_RATE_HZ = 1.0
"""Costly inputs per second one tab is given beyond its burst (a token bucket); the rest wait, coalesced."""
MAX_NAME_CHARS = 255


@dataclasses.dataclass
class Upload:
    """One browser upload in flight, as its start message announced it."""

    part_count: int
    size_bytes: int
    last_part_at: float
    """When it started or last received a part (``time.monotonic()``)."""
    started_at: float = dataclasses.field(default_factory=time.monotonic)
    """When its start message was taken (``time.monotonic()``)."""
    bytes_seen: int = 0
    parts_seen: set[int] = dataclasses.field(default_factory=set)
    button_uuid: str = ""
    """The upload button it was started on."""
    filename: str = ""
    """The file's name, as its start message gave it."""


Item = typing.TypeVar("Item")
_TOKEN_SLACK = 1e-9
"""A token refilled to within this of 1 counts as whole: the timer set by :meth:`CostlyBudget.wait_s` fires then."""


class CostlyBudget(typing.Generic[Item]):
    """One tab's token bucket for costly inputs, holding back the latest value of each control beyond it.

    ``burst`` inputs may go at once, then ``rate_hz`` a second. An input offered while the bucket is empty (or while
    others wait) is held back in place of any earlier one of the same control, last in line; :meth:`take` hands the
    oldest one out when a token is there. So a burst of clicks becomes one click, the latest value of a control is
    always the last of it delivered, and a tab's costly work is bounded by ``burst + rate_hz * t`` in any ``t`` s.
    Pure bookkeeping (times are passed in, e.g. ``time.monotonic()``); the gate runs it on the event loop.
    """

    def __init__(self, burst: int, rate_hz: float, now: float) -> None:
        if burst < 1 or not rate_hz > 0.0:
            raise ValueError(f"burst must be ≥ 1 and rate_hz > 0, got {burst}, {rate_hz}")
        self.burst = burst
        self.rate_hz = rate_hz
        self._tokens = float(burst)
        self._refilled_at = now
        self._held: dict[str, tuple[Item, bool]] = {}
        """By control key, in the order of each one's latest arrival: (item, free)."""

    def _refill(self, now: float) -> None:
        elapsed = max(0.0, now - self._refilled_at)
        self._tokens = min(float(self.burst), self._tokens + elapsed * self.rate_hz)
        self._refilled_at = max(now, self._refilled_at)

    def offer(self, key: str, item: Item, now: float, *, free: bool = False, hold: bool = False) -> tuple[bool, bool]:
        """(goes now, replaced one held back) for ``item``, the new value of control ``key``.

        A ``free`` input (a cheap control, a gizmo) costs no token: it goes at once unless inputs are held back,
        and then waits in line behind them, so an edit made after a held-back Reset is applied after the Reset
        rather than undone by it. ``hold`` holds it even then (the caller knows of costly work still running)."""
        self._refill(now)
        if not hold and not self._held and (free or self._tokens >= 1.0 - _TOKEN_SLACK):
            if not free:
                self._tokens = max(0.0, self._tokens - 1.0)
            return True, False
        replaced = self._held.pop(key, None) is not None
        self._held[key] = (item, free)
        return False, replaced

    def take(self, now: float) -> tuple[str, Item] | None:
        """The oldest held-back (key, item) if the budget allows it now (a free one always), else None."""
        if not self._held:
            return None
        key = next(iter(self._held))
        item, free = self._held[key]
        if not free:
            self._refill(now)
            if self._tokens < 1.0 - _TOKEN_SLACK:
                return None
            self._tokens = max(0.0, self._tokens - 1.0)
        del self._held[key]
        return key, item

    def wait_s(self, now: float) -> float | None:
        """Seconds until :meth:`take` can hand out the next held-back input; None when none is held."""
        if not self._held:
            return None
        if self._held[next(iter(self._held))][1]:
            return 0.0
        self._refill(now)
        return max(0.0, (1.0 - self._tokens) / self.rate_hz)

    @property
    def next_is_free(self) -> bool:
        """Whether the next held-back input in line is a free one."""
        return bool(self._held) and self._held[next(iter(self._held))][1]

    @property
    def held(self) -> int:
        """How many inputs are held back (one per control at most)."""
        return len(self._held)


Deferred = tuple[Any, Callable[[], None] | None, tuple[type, str] | None]
"""A held-back input: the cleaned message, what to do after it, and for a cheap GUI edit its control's (handle
type, label), to find the control again when a Reset rebuilt it."""


@dataclasses.dataclass
class TabBudget:
    """One tab's costly-input budget, the timer that releases what it holds back, and its costly work running."""

    budget: CostlyBudget[Deferred]
    timer: asyncio.TimerHandle | None = None
    in_flight: int = 0
    """Costly inputs delivered whose handlers have not finished (a scene switch or Reset still building): the tab's
    later inputs wait in line until they have, or they would reach the scene being replaced."""
