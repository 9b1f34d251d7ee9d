"""Crafted uploads through the gate: only an upload button the sender sees, within the announced size and parts.

The honest path (a GPX picked in the browser) is tested in ``tests/test_course_scene.py``; here every field of the
two upload messages is bent, one at a time, and the course stays what it was while the server keeps serving.
"""

from __future__ import annotations

import logging
import uuid
from typing import Any

import pytest
import viser
from test_course_scene import hill_gpx, upload
from wsclient import BrowserClient

from scenes._gate import MAX_UPLOAD_BYTES, MAX_UPLOADS_IN_FLIGHT, refusals
from scenes.peloton import CourseMode, PelotonScene
from scenes.switcher import SceneSwitcher


@pytest.fixture(autouse=True)
def fresh_refusal_log() -> None:
    refusals.reset()  # one line per kind per 10 s: each test starts with none logged


@pytest.fixture
def mode(switcher: SceneSwitcher) -> CourseMode:
    scene = switcher.show("peloton")
    assert isinstance(scene, PelotonScene)
    scene.course_mode.enable.value = True
    return scene.course_mode


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


def part(client: BrowserClient, transfer: str, index: int, content: Any) -> None:
    client.send(
        "FileTransferPart",
        source_component_uuid=client.uuid_of("Upload GPX"),
        transfer_uuid=transfer,
        part_index=index,
        content=content,
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
    server: viser.ViserServer,
    mode: CourseMode,
    override: dict[str, Any],
    caplog: pytest.LogCaptureFixture,
) -> None:
    before = mode.route.name
    with BrowserClient(server.get_port()) as client, caplog.at_level(logging.WARNING):
        client.wait_for_gui("Upload GPX")
        transfer = start(client, **override)
        part(client, transfer, 0, b"0123456789")
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
        part(client, transfer, 5, data[:half])  # out of range
        part(client, transfer, 0, data[:half] + b"x" * len(data))  # more bytes than announced
        part(client, str(uuid.uuid4()), 0, data[:half])  # for no upload in flight
        part(client, transfer, 0, data[:half])
        part(client, transfer, 0, data[:half])  # sent twice
        part(client, transfer, 1, data[half:])
        client.wait_for(lambda: mode.route.name == "Announced", what="the honest parts' course")
    assert caplog.text.count("refused upload part") >= 1
    assert "out of range" in caplog.text or "for no upload" in caplog.text


def test_uploads_in_flight_are_bounded_per_browser(
    server: viser.ViserServer, mode: CourseMode, caplog: pytest.LogCaptureFixture
) -> None:
    with BrowserClient(server.get_port()) as client, caplog.at_level(logging.WARNING):
        client.wait_for_gui("Upload GPX")
        for _ in range(MAX_UPLOADS_IN_FLIGHT + 3):
            start(client, part_count=4, size_bytes=10)
        client.wait_for(lambda: "refused uploads in flight" in caplog.text, what="the bound")
        # The person at that tab is told why, once per refused upload.
        client.wait_for(lambda: len(notices(client)) == 3, what="the refusal notices")
        assert all(
            note["title"] == "Upload refused" and f"{MAX_UPLOADS_IN_FLIGHT} uploads" in note["body"]
            for note in notices(client)
        )


def notices(client: BrowserClient) -> list[dict[str, Any]]:
    return [
        message["props"]
        for _at, message in list(client.received)
        if message.get("type") == "NotificationShowMessage"
    ]


def test_a_file_over_the_size_limit_is_refused_with_a_notice(
    server: viser.ViserServer, mode: CourseMode
) -> None:
    with BrowserClient(server.get_port()) as client:
        client.wait_for_gui("Upload GPX")
        start(client, part_count=25, size_bytes=MAX_UPLOAD_BYTES + 1)
        client.wait_for(lambda: bool(notices(client)), what="the refusal notice")
        (note,) = notices(client)
        assert note["title"] == "Upload refused" and "up to 24 MiB" in note["body"]
