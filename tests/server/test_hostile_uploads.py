"""Crafted uploads through the gate: only an upload button the sender sees, within the announced size and parts.

The honest path (a GPX picked in the browser) is tested in ``tests/scenes/test_course_scene.py``; here every field of
the two upload messages is bent, one at a time, and the course stays what it was while the server keeps serving.
"""

from __future__ import annotations

import logging
import time
import uuid
from typing import Any

import pytest
import viser
from helpers.gpx import hill_gpx
from helpers.scenes import course_mode_fixture
from helpers.uploads import send_part, upload
from helpers.wsclient import BrowserClient

import server.budget as budget_module
from scenes.peloton.course import CourseMode
from server.budget import MAX_UPLOAD_BYTES, MAX_UPLOAD_BYTES_IN_FLIGHT_PER_TAB, MAX_UPLOADS_IN_FLIGHT, MIN_PART_BYTES
from server.gate import install_gate

mode = course_mode_fixture()


def start(client: BrowserClient, **override: Any) -> str:
    """Send a FileTransferStartUpload for the course's upload button, with ``override`` replacing fields."""
    fields: dict[str, Any] = {
        "source_component_uuid": client.uuid_of("Upload GPX"),
        "transfer_uuid": str(uuid.uuid4()),
        "filename": "crafted.gpx",
        "mime_type": "application/gpx+xml",
        "part_count": 1,
        "size_bytes": 10,
    }
    fields.update(override)
    client.send("FileTransferStartUpload", **fields)
    return str(fields["transfer_uuid"])


def acked(client: BrowserClient, transfer: str) -> bool:
    """Whether ``client`` has been sent a part ack for ``transfer`` (viser sends every tab each upload's acks)."""
    return any(
        message.get("type") == "FileTransferPartAck" and message.get("transfer_uuid") == transfer
        for _at, message in list(client.received)
    )


CRAFTED_STARTS: list[dict[str, Any]] = [
    {"source_component_uuid": "no-such-control"},
    {"size_bytes": MAX_UPLOAD_BYTES + 1},
    {"size_bytes": -1},
    {"size_bytes": 1.5},
    {"size_bytes": True},
    {"part_count": -1},
    {"part_count": 10**12},
    {"part_count": 0, "size_bytes": 10},
    {"filename": "x" * 10_000},
    {"filename": 3},
    {"mime_type": None},
]


@pytest.mark.parametrize("override", CRAFTED_STARTS, ids=lambda o: ",".join(o))
def test_a_crafted_upload_start_is_refused_and_the_course_stays(
    server: viser.ViserServer, mode: CourseMode, override: dict[str, Any], caplog: pytest.LogCaptureFixture
) -> None:
    before = mode.route.name
    with BrowserClient(server.get_port()) as client, caplog.at_level(logging.WARNING):
        client.wait_for_gui("Upload GPX")
        transfer = start(client, **override)
        send_part(client, transfer, 0, b"0123456789")
        # The server still serves this browser: an honest upload after the crafted one loads.
        upload(client, "Upload GPX", "after.gpx", hill_gpx("After the attack", 300))
        client.wait_for(lambda: mode.route.name == "After the attack", what="the honest upload")
    assert before != "After the attack"
    assert "refused upload" in caplog.text
    assert "Traceback" not in caplog.text


def test_parts_beyond_what_the_start_announced_are_refused(
    server: viser.ViserServer, mode: CourseMode, caplog: pytest.LogCaptureFixture
) -> None:
    data = hill_gpx("Announced", 300)
    with BrowserClient(server.get_port()) as client, caplog.at_level(logging.WARNING):
        client.wait_for_gui("Upload GPX")
        transfer = start(client, part_count=2, size_bytes=len(data))
        half = len(data) // 2
        send_part(client, transfer, 5, data[:half])  # out of range
        send_part(client, transfer, 0, data[:half] + b"x" * len(data))  # more bytes than announced
        send_part(client, str(uuid.uuid4()), 0, data[:half])  # for no upload in flight
        send_part(client, transfer, 0, data[:half])
        send_part(client, transfer, 0, data[:half])  # sent twice
        send_part(client, transfer, 1, data[half:])
        client.wait_for(lambda: mode.route.name == "Announced", what="the honest parts' course")
    assert caplog.text.count("refused upload part") >= 1
    assert "out of range" in caplog.text or "for no upload" in caplog.text


def test_uploads_in_flight_are_bounded_per_browser(
    server: viser.ViserServer, mode: CourseMode, caplog: pytest.LogCaptureFixture
) -> None:
    with BrowserClient(server.get_port()) as client, caplog.at_level(logging.WARNING):
        client.wait_for_gui("Upload GPX")
        for _ in range(MAX_UPLOADS_IN_FLIGHT + 3):
            start(client, part_count=1, size_bytes=10)
        client.wait_for(lambda: "refused uploads in flight" in caplog.text, what="the bound")
        # The person at that tab is told why, once per refused upload.
        client.wait_for(lambda: len(client.notices()) == 3, what="the refusal notices")
        assert all(
            note["title"] == "Upload refused" and f"{MAX_UPLOADS_IN_FLIGHT} uploads" in note["body"]
            for note in client.notices()
        )


def test_a_file_over_the_size_limit_is_refused_with_a_notice(server: viser.ViserServer, mode: CourseMode) -> None:
    with BrowserClient(server.get_port()) as client:
        client.wait_for_gui("Upload GPX")
        start(client, part_count=25, size_bytes=MAX_UPLOAD_BYTES + 1)
        client.wait_for(lambda: bool(client.notices()), what="the refusal notice")
        (note,) = client.notices()
        assert note["title"] == "Upload refused" and "up to 24 MiB" in note["body"]


# ---------------------------------------------------- what one tab's uploads may hold
@pytest.mark.parametrize(
    ("size", "parts"), [(300_000, 300_000), (MAX_UPLOAD_BYTES, MAX_UPLOAD_BYTES), (2 * MIN_PART_BYTES, 3), (1, 2)]
)
def test_an_upload_of_tiny_parts_is_refused(
    server: viser.ViserServer, mode: CourseMode, caplog: pytest.LogCaptureFixture, size: int, parts: int
) -> None:
    """The kind: memory the budget does not count. viser keeps ~100 bytes a part, so 300 000 one-byte parts held
    32 MiB for a 300 kB upload; an upload may announce at most one part per MIN_PART_BYTES (viser's own browser
    sends 512 KiB parts)."""
    with BrowserClient(server.get_port()) as client, caplog.at_level(logging.WARNING):
        client.wait_for_gui("Upload GPX")
        start(client, part_count=parts, size_bytes=size)
        client.wait_for(lambda: "refused upload size" in caplog.text, what="the refusal")
        assert install_gate(server).uploads_in_flight() == (0, 0)


def test_a_transfer_id_in_flight_cannot_be_taken_by_another_tab(
    server: viser.ViserServer, mode: CourseMode, caplog: pytest.LogCaptureFixture
) -> None:
    """A second tab's start under a transfer id in flight is refused, so its parts cannot mix into the first tab's
    file. (Every tab once saw a shared button's acks, with the id; they now reach the sender alone, so here the
    second tab is a crafted one that knows the id.)"""
    data = hill_gpx("Mine", 300)
    half = len(data) // 2
    with BrowserClient(server.get_port()) as a, BrowserClient(server.get_port()) as b, caplog.at_level(logging.WARNING):
        a.wait_for_gui("Upload GPX")
        b.wait_for_gui("Upload GPX")
        transfer = start(a, part_count=2, size_bytes=len(data), filename="mine.gpx")
        send_part(a, transfer, 0, data[:half])
        # Waiting for the ack orders the two sockets: without it, b's start could reach the server first and
        # rightly own the id, refusing a's.
        a.wait_for(lambda: acked(a, transfer), what="the ack of a's first part")
        assert not acked(b, transfer)  # the id is not told to other tabs
        start(b, part_count=2, size_bytes=len(data), filename="theirs.gpx", transfer_uuid=transfer)
        client_b_part = hill_gpx("Theirs", 300)
        send_part(b, transfer, 1, client_b_part[half:])  # refused: b has no upload under that id
        b.wait_for(lambda: "refused upload transfer id" in caplog.text, what="the refusal")
        send_part(a, transfer, 1, data[half:])
        a.wait_for(lambda: mode.route.name == "Mine", what="a's own course, whole")


def test_one_tab_holds_at_most_its_share_of_the_upload_budget(server: viser.ViserServer, mode: CourseMode) -> None:
    big = MAX_UPLOAD_BYTES_IN_FLIGHT_PER_TAB // 2 + 1
    with BrowserClient(server.get_port()) as client:
        client.wait_for_gui("Upload GPX")
        start(client, part_count=1, size_bytes=big)
        start(client, part_count=1, size_bytes=big)  # over the tab's share
        client.wait_for(lambda: bool(client.notices()), what="the refusal notice")
        (note,) = client.notices()
        assert note["title"] == "Upload refused" and "MiB at once" in note["body"]
        assert install_gate(server).uploads_in_flight() == (1, big)


def test_an_upload_trickled_past_its_deadline_is_dropped(
    server: viser.ViserServer, mode: CourseMode, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A part every few seconds is progress, so the stall rule never fires; the deadline does (120 s, here 0.5 s),
    and frees the budget for the next tab's upload."""
    monkeypatch.setattr(budget_module, "UPLOAD_DEADLINE_S", 0.5)
    data = hill_gpx("Late", 300)
    with BrowserClient(server.get_port()) as hog, BrowserClient(server.get_port()) as other:
        hog.wait_for_gui("Upload GPX")
        other.wait_for_gui("Upload GPX")
        transfer = start(hog, part_count=2, size_bytes=len(data))
        send_part(hog, transfer, 0, data[: len(data) // 2])
        gate = install_gate(server)
        hog.wait_for(lambda: gate.uploads_in_flight()[0] == 1, what="the hog's upload in flight")
        time.sleep(0.6)
        upload(other, "Upload GPX", "next.gpx", hill_gpx("Next", 300))
        other.wait_for(lambda: mode.route.name == "Next", what="the next tab's course")
        assert gate.uploads_in_flight() == (0, 0)
        send_part(hog, transfer, 1, data[len(data) // 2 :])  # too late: refused, the course stays
        time.sleep(0.3)
        assert mode.route.name == "Next"
