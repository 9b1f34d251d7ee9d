"""What every scene in :data:`scenes.SCENES` promises, checked on a real server behind the app's gate.

A scene builds its GUI and its nodes under its root; a declared control moved by a browser changes
``scene.params``; a hostile value (NaN, a string, out of range) is refused or clamped and leaves the last good
parameters; and ``close()`` removes every node and GUI element the scene made, ends every thread it started and
leaves nothing on the server that holds the closed scene alive.
"""

from __future__ import annotations

import dataclasses
import gc
import math
import threading
import weakref
from typing import Any, NamedTuple

import pytest
import viser
from helpers.scenes import MakeScene
from helpers.viser_private import gui_uuids, node_names
from helpers.wsclient import BrowserClient

from scenes import SCENES
from scenes._base import Scene
from scenes._controls import Control, declared
from server.sessions import camera_hub
from shaders import gl_service

KINDS = list(SCENES.values())
IDS = list(SCENES)
APPLIED_LATER = {"editor_half_size"}
"""Fields read when a button applies them (the GLSL editor's bounds go with its text, on Apply), not on change."""


def first_number_field(scene: Scene) -> tuple[str, Control]:
    """The scene's first declared slider or number field that holds one value (not a tuple) and applies on change."""
    for name, control in declared(type(scene.params)).items():
        if (
            control.kind in ("slider", "number")
            and not isinstance(getattr(scene.params, name), tuple)
            and name not in APPLIED_LATER
        ):
            return name, control
    raise AssertionError(f"{type(scene).__name__} declares no slider or number")


def in_range_value(control: Control, current: float) -> float:
    """A value on the control's grid, inside its range, a quarter or three quarters of the way, not ``current``."""
    assert control.lo is not None and control.hi is not None and control.step is not None
    steps = (control.hi - control.lo) / control.step
    for fraction in (0.25, 0.75):
        value = control.lo + control.step * max(1, round(steps * fraction))
        value = int(value) if isinstance(current, int) else value
        if value != current:
            return value
    raise AssertionError(f"no in-range value other than {current} for {control.label!r}")


class Bare(NamedTuple):
    """What the server holds before the scene is built."""

    nodes: set[str]
    """The scene node names."""
    gui: set[str]
    """The GUI elements' ids."""
    threads: set[threading.Thread]
    """The process's threads."""


@pytest.fixture
def bare(server: viser.ViserServer) -> Bare:
    """The server's nodes and GUI elements, and the process's threads, before the test's scene is built."""
    return Bare(node_names(server), gui_uuids(server), set(threading.enumerate()))


def started_since(bare: Bare) -> set[threading.Thread]:
    """The threads alive now that were not when ``bare`` was read, less the process's one GL thread: the first scene
    that renders starts it, and every later one shares it (``test_sdf_scene``'s fifty builds count it)."""
    return {thread for thread in threading.enumerate() if thread not in bare.threads} - {gl_service.thread()}


def wait_idle(scene: Scene) -> None:
    """Until ``scene``'s background jobs (meshing, searches) are done. A scene with a job worker says when through its
    ``wait_idle``; one without (the peloton and the arm compute in their callbacks) has none to wait for."""
    idle = getattr(scene, "wait_idle", None)
    if idle is not None:
        assert idle(), f"{type(scene).__name__}'s background jobs never finished"


@pytest.fixture(params=KINDS, ids=IDS)
def scene(request: pytest.FixtureRequest, scene_on: MakeScene, bare: Bare) -> Scene:
    """Each scene of :data:`scenes.SCENES` in turn, built on the test's server once ``bare`` has been read."""
    return scene_on(request.param)


def test_a_scene_builds_its_controls_and_its_nodes_under_its_root(
    server: viser.ViserServer, scene: Scene, bare: Bare
) -> None:
    made = node_names(server) - bare.nodes
    assert made and all(name.startswith(scene.root.name) for name in made)
    assert len({name for name in made if name.startswith(f"{scene.root.name}/")}) > 10
    assert len(gui_uuids(server) - bare.gui) > len(declared(type(scene.params)))


def test_a_declared_control_moved_in_range_changes_the_params(server: viser.ViserServer, scene: Scene) -> None:
    name, control = first_number_field(scene)
    before = scene.params
    value = in_range_value(control, getattr(before, name))
    with BrowserClient(server.get_port()) as client:
        client.wait_for_gui(control.label)
        client.set_value(control.label, value)
        client.wait_for(lambda: getattr(scene.params, name) == pytest.approx(value), what=f"{name} = {value}")
    assert scene.params == dataclasses.replace(before, **{name: getattr(scene.params, name)})


def test_hostile_values_are_refused_or_clamped_and_the_last_good_params_kept(
    server: viser.ViserServer, scene: Scene
) -> None:
    name, control = first_number_field(scene)
    assert control.lo is not None and control.hi is not None
    good = scene.params
    shown = getattr(good, name)
    span = control.hi - control.lo
    with BrowserClient(server.get_port()) as client:
        client.wait_for_gui(control.label)
        refused: list[Any] = [math.nan, math.inf, "12", None, [1.0]]
        for hostile in refused:
            client.set_value(control.label, hostile)
            # The sender showed its own edit; a refusal sends the server's value back.
            client.wait_for(
                lambda: client.value_of(control.label) == shown, what=f"{hostile!r} refused and {shown} sent back"
            )
            assert scene.params == good
        for hostile, clamped in ((control.hi + 10 * span, control.hi), (control.lo - 10 * span, control.lo)):
            client.set_value(control.label, hostile)
            client.wait_for(
                lambda clamped=clamped: getattr(scene.params, name) == clamped, what=f"{hostile} clamped to {clamped}"
            )
            client.wait_for(
                lambda clamped=clamped: client.value_of(control.label) == clamped,
                what=f"the clamped {clamped} sent back",
            )
            assert scene.params == dataclasses.replace(good, **{name: clamped})


@pytest.mark.parametrize("when", ["at once", "once idle"])
def test_close_removes_every_node_and_gui_element_the_scene_made_and_ends_its_threads(
    server: viser.ViserServer, scene: Scene, bare: Bare, when: str
) -> None:
    """Closed at once (a job may be running: it finishes, then its thread ends) or once idle (nothing is running:
    every thread has ended by the time ``close()`` returns)."""
    assert node_names(server) != bare.nodes and gui_uuids(server) != bare.gui
    if when == "once idle":
        wait_idle(scene)
    started = started_since(bare)
    # Every thread the scene started is one it keeps, so one its close() ends. A scene that starts none (the arm)
    # keeps none: a thread it started and did not keep would show here, and again below.
    assert started == set(scene._threads), "a thread the scene started is not one it keeps"
    scene.close()
    if when == "once idle":
        assert not [thread.name for thread in started if thread.is_alive()], "the idle scene's threads outlived close()"
    assert scene.join(10.0), "the scene's threads outlived close()"
    assert not [thread.name for thread in started if thread.is_alive()], "the scene's threads outlived close()"
    assert node_names(server) == bare.nodes
    assert gui_uuids(server) == bare.gui


@pytest.mark.parametrize("kind", KINDS, ids=IDS)
def test_a_closed_scene_is_released(server: viser.ViserServer, kind: type[Scene]) -> None:
    """Nothing the server keeps (callbacks, camera listeners) may hold a closed scene alive."""
    with BrowserClient(server.get_port()) as client:  # a connected browser, so per-client callbacks exist
        client.wait_for(lambda: len(server.get_clients()) == 1, what="the client to register")
        refs = []
        for _ in range(2):
            scene = kind(server)
            refs.append(weakref.ref(scene))
            scene.close()
            del scene
        gc.collect()
        assert camera_hub(server).listener_count == 0
        assert [ref() for ref in refs] == [None, None]
