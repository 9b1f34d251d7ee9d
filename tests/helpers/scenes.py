"""Typing for the scene fixtures of ``tests/conftest.py``: a callable that makes or shows a scene of a given class."""

from __future__ import annotations

from typing import Protocol, TypeVar

from scenes._base import Scene

S = TypeVar("S", bound=Scene)


class MakeScene(Protocol):
    """Builds (or shows) a scene of class ``kind`` and returns it, typed as that class."""

    def __call__(self, kind: type[S]) -> S: ...
