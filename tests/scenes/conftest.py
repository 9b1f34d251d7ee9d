"""What the scene tests share: a test marked ``gl`` gets the process's shared GL context (the one the scenes render
with, :mod:`shaders.gl_service`) before anything else is set up, or is skipped (a failure under CI)."""

from __future__ import annotations

import pytest
from helpers.ci import need_gl
from helpers.scenes import MakeScene

from scenes.freekick import FreeKickScene


@pytest.fixture(autouse=True)
def gl_when_marked(request: pytest.FixtureRequest) -> None:
    if request.node.get_closest_marker("gl") is not None:
        need_gl()


@pytest.fixture
def freekick(show_scene: MakeScene) -> FreeKickScene:
    """The free-kick scene shown on a server, its first kick computed."""
    shown = show_scene(FreeKickScene)
    assert shown.wait_idle()
    return shown
