"""Shared fixtures: a real viser server on a free port, the app's scene switcher, and a real Chromium page.

Under CI=true nothing is skipped: a missing Chromium or GL context fails the run instead.
"""

from __future__ import annotations

import contextlib
import shutil
from collections.abc import Iterator
from pathlib import Path

import pytest
import viser
from helpers.ci import CHROMIUM, chromium_context, fresh_renderer, skip_or_fail
from helpers.properties import EXPLORE_EXAMPLES
from helpers.scenes import MakeScene, S
from hypothesis import settings

from app import serve_scenes
from scenes._base import Scene
from scenes._look import configure_lighting
from server.gate import install_gate
from server.sessions import Sessions
from server.switcher import SceneSwitcher
from shaders.renderer import Renderer

# The README's test command must pass for anyone, every run: hypothesis draws the same examples in and out of CI.
# Explore with fresh ones before calling a change done: pytest --hypothesis-profile=explore --hypothesis-seed=random
settings.register_profile("deterministic", derandomize=True, deadline=None, print_blob=True)
settings.register_profile("explore", derandomize=False, deadline=None, print_blob=True, max_examples=EXPLORE_EXAMPLES)
settings.load_profile("deterministic")  # --hypothesis-profile, read after this file, overrides it


@pytest.fixture
def server() -> Iterator[viser.ViserServer]:
    """A real ViserServer on a free loopback port, lit and behind the app's message gate (as app.py puts it)."""
    srv = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    configure_lighting(srv.scene)
    install_gate(srv)
    try:
        yield srv
    finally:
        srv.stop()


@pytest.fixture
def switcher(server: viser.ViserServer) -> Iterator[SceneSwitcher]:
    """The app's scene switcher on ``server``'s shared session (what every tab sees), showing the first scene."""
    with contextlib.closing(SceneSwitcher(server, "peloton")) as app:
        yield app


@pytest.fixture
def sessions(server: viser.ViserServer) -> Iterator[Sessions]:
    """The app's per-tab sessions on ``server`` (each tab its own scene), opening on the peloton."""
    with contextlib.closing(serve_scenes(server, "peloton", shared=False)) as manager:
        assert isinstance(manager, Sessions)
        yield manager


@pytest.fixture
def show_scene(switcher: SceneSwitcher) -> MakeScene:
    """Shows a scene class on ``switcher`` (closed with it) and returns the scene, checked to be of that class."""

    def show(kind: type[S]) -> S:
        shown = switcher.show(kind.key)
        assert isinstance(shown, kind)
        return shown

    return show


@pytest.fixture
def scene_on(server: viser.ViserServer) -> Iterator[MakeScene]:
    """Builds a scene class directly on ``server`` (no switcher) and closes what is still open afterwards."""
    built: list[Scene] = []

    def build(kind: type[S]) -> S:
        scene = kind(server)
        built.append(scene)
        return scene

    try:
        yield build
    finally:
        for scene in built:
            if not scene.closed:
                scene.close()


@pytest.fixture(scope="module")
def gl() -> Iterator[Renderer]:
    """A renderer of the module's own (an OpenGL context: skipped locally without one, a failure under CI)."""
    with fresh_renderer() as renderer:
        yield renderer


@pytest.fixture(scope="session")
def chromium_browser() -> Iterator[object]:
    """Debian's Chromium driven by playwright (never playwright's own downloaded browser)."""
    if shutil.which(CHROMIUM) is None and not Path(CHROMIUM).exists():
        skip_or_fail(f"Chromium not found at {CHROMIUM}: apt-get install chromium")
    with chromium_context((1280, 800)) as context:
        yield context


@pytest.fixture
def browser_page(chromium_browser: object) -> Iterator[object]:
    """A fresh page in the shared Chromium context."""
    page = chromium_browser.new_page()  # type: ignore[attr-defined]
    try:
        yield page
    finally:
        page.close()
