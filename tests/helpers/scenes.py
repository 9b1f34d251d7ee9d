"""Typing for the scene fixtures of ``tests/conftest.py`` (a callable that makes or shows a scene of a given class),
the ``scene`` and course ``mode`` fixtures a test module declares in one line, readers of the GLB meshes scenes
send, and what a person does in the SDF gallery's GLSL editor."""

from __future__ import annotations

import io
from typing import Any, Protocol, TypeVar

import numpy as np
import pytest
import trimesh

from helpers.wsclient import BrowserClient
from scenes._base import Scene
from scenes.peloton import PelotonScene
from scenes.peloton.course import CourseMode

S = TypeVar("S", bound=Scene)


class MakeScene(Protocol):
    """Builds (or shows) a scene of class ``kind`` and returns it, typed as that class."""

    def __call__(self, kind: type[S]) -> S: ...


class StubScene(Scene):
    """A scene made for a test: a subclass names its ``key``; no person reads its title or its about."""

    title = "Test"
    about = "A test scene."


def scene_fixture(kind: type[Scene]) -> Any:
    """A fixture (assign it to ``scene``): a scene of class ``kind`` shown on the test's switcher, through
    ``tests/conftest.py``'s ``show_scene`` (checked to be of that class, closed with the switcher)."""

    @pytest.fixture
    def scene(show_scene: MakeScene) -> Scene:
        return show_scene(kind)

    return scene


def course_mode_fixture() -> Any:
    """A fixture (assign it to ``mode``): the peloton shown on the test's switcher (``show_scene``, so the same scene
    a ``scene`` fixture of that class gives), its course mode switched on."""

    @pytest.fixture
    def mode(show_scene: MakeScene) -> CourseMode:
        course = show_scene(PelotonScene).course_mode
        course.enable.value = True
        return course

    return mode


def read_glb(glb_data: bytes) -> trimesh.Trimesh:
    """The one mesh of a GLB as a scene sends it, read by trimesh (not by our writer) with its material and vertex
    colours."""
    loaded = trimesh.load(io.BytesIO(glb_data), file_type="glb", process=False)
    assert isinstance(loaded, trimesh.Scene) and len(loaded.geometry) == 1
    (mesh,) = loaded.geometry.values()
    assert isinstance(mesh, trimesh.Trimesh)
    return mesh


def glb_vertices(glb_data: bytes) -> np.ndarray:
    """(V, 3) vertex positions of a one-mesh GLB as a scene sends it (read by trimesh, not by our writer)."""
    loaded = trimesh.load(io.BytesIO(glb_data), file_type="glb", force="mesh", process=False)
    assert isinstance(loaded, trimesh.Trimesh)
    return np.asarray(loaded.vertices)


GLSL_EDITOR = "sdf(p) in GLSL"
"""The label of the SDF gallery's GLSL editor."""


def apply_glsl(client: BrowserClient, source: str) -> None:
    """What a person does in the SDF gallery's GLSL editor: wait for it, type ``source`` and click Apply."""
    client.wait_for_gui(GLSL_EDITOR)
    client.set_value(GLSL_EDITOR, source)
    client.click("Apply")
