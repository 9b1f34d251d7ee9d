"""File uploads as a browser sends them over viser's websocket."""

from __future__ import annotations

import uuid
from typing import Any

from helpers.wsclient import BrowserClient


def upload(client: BrowserClient, label: str, filename: str, data: bytes, part: int = 64_000) -> str:
    """What the browser sends when a person picks a file for the upload button ``label``; returns its transfer id."""
    parts = [data[i : i + part] for i in range(0, len(data), part)]
    source, transfer = start_upload(client, label, filename, len(data), len(parts))
    for index, content in enumerate(parts):
        client.send(
            "FileTransferPart", source_component_uuid=source, transfer_uuid=transfer, part_index=index, content=content
        )
    return transfer


def start_upload(client: BrowserClient, label: str, filename: str, size_bytes: int, part_count: int) -> tuple[str, str]:
    """The start of an upload to the button ``label``, as the browser sends it; returns (button id, transfer id)."""
    source, transfer = client.uuid_of(label), str(uuid.uuid4())
    client.send(
        "FileTransferStartUpload",
        source_component_uuid=source,
        transfer_uuid=transfer,
        filename=filename,
        mime_type="application/gpx+xml",
        part_count=part_count,
        size_bytes=size_bytes,
    )
    return source, transfer


def send_part(client: BrowserClient, transfer: str, index: int, content: Any) -> None:
    client.send(
        "FileTransferPart",
        source_component_uuid=client.uuid_of("Upload GPX"),
        transfer_uuid=transfer,
        part_index=index,
        content=content,
    )
