"""What every scene in :data:`scenes.SCENES` promises, checked on a real server behind the app's gate.

A scene builds its GUI and its nodes under its root; a declared control moved by a browser changes
``scene.params``; a hostile value (NaN, a string, out of range) is refused or clamped and leaves the last good
parameters; and ``close()`` removes every node and GUI element the scene made.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, NamedTuple

import pytest
import viser
from helpers.scenes import MakeScene
from helpers.viser_private import gui_uuids, node_names
from helpers.wsclient import BrowserClient

from scenes import SCENES
from scenes._base import Scene
from scenes._controls import Control, declared

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


@pytest.fixture
def bare(server: viser.ViserServer) -> Bare:
    """The server's nodes and GUI elements before the test's scene is built."""
    return Bare(node_names(server), gui_uuids(server))


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


def test_close_removes_every_node_and_gui_element_the_scene_made(
    server: viser.ViserServer, scene: Scene, bare: Bare
) -> None:
    assert node_names(server) != bare.nodes and gui_uuids(server) != bare.gui
    scene.close()
    assert scene.join(10.0), "the scene's threads outlived close()"
    assert node_names(server) == bare.nodes
    assert gui_uuids(server) == bare.gui
