"""The latest-wins worker: newest job only, quiet-spell delays, no polling, survives failing jobs."""

from __future__ import annotations

import sys
import threading
import time

import pytest

from scenes._worker import LatestWorker


@pytest.fixture
def worker():
    w = LatestWorker("test-worker")
    yield w
    assert w.close(5.0)


def test_a_burst_runs_the_first_and_the_newest_only(worker: LatestWorker) -> None:
    gate = threading.Event()
    ran: list[int] = []
    worker.submit(lambda: (gate.wait(5.0), ran.append(0)))  # holds the thread while the burst arrives
    time.sleep(0.05)
    for i in range(1, 101):
        worker.submit(lambda i=i: ran.append(i))
    gate.set()
    assert worker.wait_idle(5.0)
    assert ran == [0, 100]


def test_delay_waits_for_a_quiet_spell(worker: LatestWorker) -> None:
    ran: list[float] = []
    start = time.monotonic()
    for _ in range(5):
        worker.submit(lambda: ran.append(time.monotonic()), delay_s=0.2)
        time.sleep(0.05)
    assert worker.wait_idle(5.0)
    assert len(ran) == 1
    # the last submission came ~0.2 s after the first; the job ran a full quiet spell after it
    assert ran[0] - start >= 0.2 + 0.2 - 0.02


def test_schedule_keeps_a_waiting_job(worker: LatestWorker) -> None:
    ran: list[str] = []
    worker.submit(lambda: ran.append("submitted"), delay_s=0.1)
    worker.schedule(lambda: ran.append("scheduled"), delay_s=0.0)
    assert worker.wait_idle(5.0)
    assert ran == ["submitted"]
    worker.schedule(lambda: ran.append("scheduled"), delay_s=0.0)
    assert worker.wait_idle(5.0)
    assert ran == ["submitted", "scheduled"]


def test_a_failing_job_is_reported_and_the_worker_goes_on() -> None:
    errors: list[Exception] = []
    w = LatestWorker("test-worker", on_error=errors.append)
    try:
        w.submit(lambda: 1 / 0)
        assert w.wait_idle(5.0)
        done = threading.Event()
        w.submit(done.set)
        assert done.wait(5.0)
        assert len(errors) == 1 and isinstance(errors[0], ZeroDivisionError)
    finally:
        assert w.close(5.0)


def test_close_drops_a_waiting_job_and_stops_the_thread() -> None:
    ran: list[int] = []
    w = LatestWorker("test-worker")
    w.submit(lambda: ran.append(1), delay_s=10.0)
    start = time.monotonic()
    assert w.close(5.0)
    assert time.monotonic() - start < 1.0
    assert not w.thread.is_alive() and ran == []


def test_an_idle_worker_sleeps_without_a_timeout(worker: LatestWorker) -> None:
    """No polling: with nothing to do the thread waits on its condition with no timeout."""
    assert worker.wait_idle(5.0)
    time.sleep(0.05)
    ident = worker.thread.ident
    assert ident is not None
    frame = sys._current_frames().get(ident)
    waits = []
    while frame is not None:
        if frame.f_code.co_name == "wait" and "timeout" in frame.f_locals:
            waits.append(frame.f_locals["timeout"])
        frame = frame.f_back
    assert waits == [None]
