"""Helpers for real-browser tests: open a viser page and wait for state, never for time."""

from __future__ import annotations

from typing import Any


def open_viser(page: Any, port: int, node: str, timeout_ms: int = 60_000) -> None:
    """Open the viser client on ``port`` and wait until scene node ``node`` exists in its three.js scene."""
    page.goto(f"http://127.0.0.1:{port}/", wait_until="domcontentloaded", timeout=timeout_ms)
    page.wait_for_function(
        "name => !!(window.__viserMutable && window.__viserMutable.nodeRefFromName"
        " && window.__viserMutable.nodeRefFromName[name])",
        arg=node,
        timeout=timeout_ms,
    )


def canvas_is_not_blank(png: bytes) -> bool:
    """True when a PNG of the canvas has real content: many distinct colours, not one flat fill."""
    import io

    import numpy as np
    from PIL import Image

    image = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))
    colours = np.unique(image.reshape(-1, 3)[::7], axis=0)
    return colours.shape[0] > 50 and float(image.std()) > 5.0
