"""Shared fixtures: a real viser server on a free port, the app's scene switcher, and a real Chromium page.

Under CI=true nothing is skipped: a missing Chromium or GL context fails the run instead.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest
import viser
from hypothesis import settings

from server.gate import install_gate
from server.switcher import SceneSwitcher

IN_CI = os.environ.get("CI", "").lower() in ("1", "true", "yes")

# CI must not be flaky: under CI=true hypothesis draws the same examples on every run (locally it explores anew).
settings.register_profile("ci", derandomize=True, deadline=None, print_blob=True)
if IN_CI:
    settings.load_profile("ci")
CHROMIUM = os.environ.get("CHROMIUM", "/usr/bin/chromium")
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--enable-unsafe-swiftshader",
]


def skip_or_fail(reason: str) -> None:
    """Skip outside CI; under CI=true a missing capability is a failure, never a silent skip."""
    if IN_CI:
        pytest.fail(f"{reason} (CI=true: this test must run)")
    pytest.skip(reason)


@pytest.fixture
def server() -> Iterator[viser.ViserServer]:
    """A real ViserServer on a free loopback port, behind the app's message gate (as app.py puts it)."""
    srv = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    install_gate(srv)
    try:
        yield srv
    finally:
        srv.stop()


@pytest.fixture
def switcher(server: viser.ViserServer) -> Iterator[SceneSwitcher]:
    """The app's scene switcher on ``server``'s shared session (what every tab sees), showing the first scene."""
    app = SceneSwitcher(server, "peloton")
    try:
        yield app
    finally:
        app.close()


@pytest.fixture(scope="session")
def chromium_browser() -> Iterator[object]:
    """Debian's Chromium driven by playwright (never playwright's own downloaded browser)."""
    if shutil.which(CHROMIUM) is None and not Path(CHROMIUM).exists():
        skip_or_fail(f"Chromium not found at {CHROMIUM}: apt-get install chromium")
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        user_data = tempfile.mkdtemp(prefix="chromium-profile-")
        context = playwright.chromium.launch_persistent_context(
            user_data,
            executable_path=CHROMIUM,
            headless=True,
            args=CHROMIUM_ARGS,
            viewport={"width": 1280, "height": 800},
        )
        try:
            yield context
        finally:
            context.close()
            shutil.rmtree(user_data, ignore_errors=True)


@pytest.fixture
def browser_page(chromium_browser: object) -> Iterator[object]:
    """A fresh page in the shared Chromium context."""
    page = chromium_browser.new_page()  # type: ignore[attr-defined]
    try:
        yield page
    finally:
        page.close()
