"""Missing capabilities (Chromium, an OpenGL context): skipped locally, a failure under CI=true."""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from collections.abc import Iterator
from typing import TYPE_CHECKING, Any, NoReturn

import pytest

from shaders import gl_service
from shaders.renderer import GLUnavailableError, Renderer

if TYPE_CHECKING:
    from playwright.sync_api import ViewportSize

IN_CI = os.environ.get("CI", "").lower() in ("1", "true", "yes")
"""Whether this run is CI's: then nothing may be skipped for want of a capability."""

CHROMIUM = os.environ.get("CHROMIUM", "/usr/bin/chromium")
"""Debian's Chromium, which the browser tests drive (never a browser a test tool downloads)."""
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--enable-unsafe-swiftshader",
]


@contextlib.contextmanager
def chromium_context(viewport: tuple[int, int] | None = None) -> Iterator[Any]:
    """A playwright browser context of Debian's Chromium (never playwright's own downloaded browser), in a profile
    folder of its own that is removed afterwards; ``viewport`` (CSS px) is its pages' default size."""
    from playwright.sync_api import sync_playwright

    size: ViewportSize | None = None if viewport is None else {"width": viewport[0], "height": viewport[1]}
    with sync_playwright() as playwright:
        profile = tempfile.mkdtemp(prefix="chromium-profile-")
        context = playwright.chromium.launch_persistent_context(
            profile, executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS, viewport=size
        )
        try:
            yield context
        finally:
            context.close()
            shutil.rmtree(profile, ignore_errors=True)


def skip_or_fail(reason: str) -> NoReturn:
    """Skip outside CI; under CI=true a missing capability is a failure, never a silent skip."""
    if IN_CI:
        pytest.fail(f"{reason} (CI=true: this test must run)")
    pytest.skip(reason)


def need_gl() -> None:
    """Make sure the process's shared GL context exists (made here if not yet), or skip or fail."""
    try:
        gl_service.run(lambda _renderer: None)
    except GLUnavailableError as exc:
        skip_or_fail(str(exc))


@contextlib.contextmanager
def fresh_renderer() -> Iterator[Renderer]:
    """A renderer of its own (not the shared one), released afterwards; skip or fail without a GL context."""
    try:
        renderer = Renderer()
    except GLUnavailableError as exc:
        skip_or_fail(str(exc))
    try:
        yield renderer
    finally:
        renderer.release()
