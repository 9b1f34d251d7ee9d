"""Typing for the scene fixtures of ``tests/conftest.py`` (a callable that makes or shows a scene of a given class),
and the ``scene`` fixture a scene's test module declares in one line."""

from __future__ import annotations

from typing import Any, Protocol, TypeVar

import pytest

from scenes._base import Scene

S = TypeVar("S", bound=Scene)


class MakeScene(Protocol):
    """Builds (or shows) a scene of class ``kind`` and returns it, typed as that class."""

    def __call__(self, kind: type[S]) -> S: ...


def scene_fixture(kind: type[Scene]) -> Any:
    """A fixture (assign it to ``scene``): a scene of class ``kind`` shown on the test's switcher, through
    ``tests/conftest.py``'s ``show_scene`` (checked to be of that class, closed with the switcher)."""

    @pytest.fixture
    def scene(show_scene: MakeScene) -> Scene:
        return show_scene(kind)

    return scene
