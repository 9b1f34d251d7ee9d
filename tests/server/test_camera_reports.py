"""Camera messages reach the scenes' listeners as reports of their own values, in the order they came: a write to
the camera by one listener (the framing's) or a later message never changes what another listener reads."""

from __future__ import annotations

import asyncio
import threading
from typing import Any

import numpy as np
import viser
from helpers.waiting import wait_until
from helpers.wsclient import BrowserClient

from server.sessions import camera_hub


def test_a_listener_reads_the_reported_camera_even_after_another_wrote_to_it(server: viser.ViserServer) -> None:
    # The SDF gallery's reference once rendered from the framing's own write instead of the reported view: the
    # framing wrote to the live camera handle before the scene's listener read it.
    seen: list[tuple[float, ...]] = []

    def frames(camera: Any) -> None:
        camera.position = (9.0, 9.0, 9.0)  # as the framing writes its view to the tab

    def records(camera: Any) -> None:
        seen.append(tuple(float(v) for v in camera.position))

    hub = camera_hub(server)
    hub.add(frames)
    hub.add(records)
    with BrowserClient(server.get_port()) as client:
        client.send_camera(position=(1.0, -2.0, 0.5))
        wait_until(lambda: (1.0, -2.0, 0.5) in seen, "the reported camera")
        client.send_camera(position=(0.0, -3.5, 0.4))
        wait_until(lambda: (0.0, -3.5, 0.4) in seen, "the second reported camera")
    assert (9.0, 9.0, 9.0) not in seen


def test_reports_arrive_one_at_a_time_in_order_off_the_event_loop(server: viser.ViserServer) -> None:
    # A tab's burst may be coalesced to its newest report, but what arrives comes in the order it was sent, one
    # report at a time, and never on the server's event loop (a framing there held up every tab during a resize).
    seen: list[float] = []
    inside = threading.Semaphore(1)
    overlaps: list[bool] = []
    on_loop: list[bool] = []

    def records(camera: Any) -> None:
        overlaps.append(not inside.acquire(blocking=False))
        try:
            asyncio.get_running_loop()
            on_loop.append(True)
        except RuntimeError:
            on_loop.append(False)
        try:
            seen.append(float(np.asarray(camera.position)[0]))
        finally:
            inside.release()

    camera_hub(server).add(records)
    sent = [float(i) for i in range(101, 141)]
    with BrowserClient(server.get_port()) as client:
        for x in sent:
            client.send_camera(position=(x, -3.0, 1.0))
        wait_until(lambda: seen[-1:] == [sent[-1]], "the last camera")
    reported = [x for x in seen if x in sent]
    assert reported == sorted(set(reported))  # in order, none twice
    assert not any(overlaps) and not any(on_loop)


def test_a_failing_listener_does_not_keep_the_camera_from_the_others(server: viser.ViserServer) -> None:
    seen: list[float] = []

    def fails(camera: Any) -> None:
        raise RuntimeError("a listener's fault")

    camera_hub(server).add(fails)
    camera_hub(server).add(lambda camera: seen.append(float(np.asarray(camera.position)[0])))
    with BrowserClient(server.get_port()) as client:
        client.send_camera(position=(7.0, -3.0, 1.0))
        wait_until(lambda: 7.0 in seen, "the camera at the second listener")
