"""File uploads as a browser sends them over viser's websocket."""

from __future__ import annotations

import uuid
from typing import Any

from helpers.wsclient import BrowserClient


def upload(client: BrowserClient, label: str, filename: str, data: bytes, part: int = 64_000) -> str:
    """What the browser sends when a person picks a file for the upload button ``label``; returns its transfer id."""
    source = client.uuid_of(label)
    transfer = str(uuid.uuid4())
    parts = [data[i : i + part] for i in range(0, len(data), part)]
    client.send(
        "FileTransferStartUpload",
        source_component_uuid=source,
        transfer_uuid=transfer,
        filename=filename,
        mime_type="application/gpx+xml",
        part_count=len(parts),
        size_bytes=len(data),
    )
    for index, content in enumerate(parts):
        client.send(
            "FileTransferPart",
            source_component_uuid=source,
            transfer_uuid=transfer,
            part_index=index,
            content=content,
        )
    return transfer


def send_part(client: BrowserClient, transfer: str, index: int, content: Any) -> None:
    client.send(
        "FileTransferPart",
        source_component_uuid=client.uuid_of("Upload GPX"),
        transfer_uuid=transfer,
        part_index=index,
        content=content,
    )
