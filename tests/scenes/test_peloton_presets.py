"""The peloton's preset menus (Position → CdA, Tyres / surface → Crr) always show the preset the current value matches,
or Custom: whether the value changed by typing, by a preset, by a reset, by a browser's message or in course mode.

Driven by the controls' labels, as a person sees them, through a real viser server (and, for a browser's message, the
websocket client)."""

from __future__ import annotations

import dataclasses

import pytest
import viser
from helpers.scenes import scene_fixture
from helpers.viser_private import gui_inputs
from helpers.wsclient import BrowserClient

from scenes.peloton import PelotonScene
from scenes.peloton.course_model import compute_course
from scenes.peloton.model import CRR_PRESETS, POSITIONS
from server.switcher import SceneSwitcher

scene = scene_fixture(PelotonScene)


@dataclasses.dataclass(frozen=True)
class Menu:
    """A preset menu as a person sees it: its label, the control it sets, and the values it names."""

    label: str
    control: str
    """The label of the control whose value the menu names."""
    field: str
    """The parameter that control holds."""
    presets: dict[str, float]
    default: str
    """What the menu shows at the scene's opening state."""
    off_preset: float
    """A value on the control's range that is no preset (the outside tester's)."""

    def __str__(self) -> str:
        return self.label


MENUS = [
    Menu("Position", "CdA (m²)", "cda_m2", {p.label: p.cda_m2 for p in POSITIONS.values()}, "Drops", 0.8),
    Menu("Tyres / surface", "Crr", "crr", CRR_PRESETS, "Race tyre, smooth asphalt (0.0040)", 0.02),
]
CUSTOM = "Custom"
"""What a menu shows for a value that is none of its presets."""
EVERY_PRESET = [(menu, label) for menu in MENUS for label in menu.presets]


def control(server: viser.ViserServer, label: str) -> viser.GuiInputHandle:
    """The one GUI input labelled ``label`` (what a person finds in the panel)."""
    (handle,) = [h for h in gui_inputs(server.gui).values() if getattr(h, "label", None) == label]
    return handle  # type: ignore[return-value]


def shown(server: viser.ViserServer, menu: Menu) -> str:
    return control(server, menu.label).value


def test_every_preset_menu_is_listed() -> None:
    # The family is these two menus: a new preset menu in the scene must be added here (and so tested).
    from scenes.peloton.model import PRESET_MENUS

    assert sorted((m.label, m.field) for m in PRESET_MENUS) == sorted((m.label, m.field) for m in MENUS)


# ------------------------------------------------------------------------------------------------ server side
@pytest.mark.parametrize("menu", MENUS, ids=str)
def test_a_value_that_is_no_preset_shows_custom(server: viser.ViserServer, scene: PelotonScene, menu: Menu) -> None:
    assert shown(server, menu) == menu.default
    control(server, menu.control).value = menu.off_preset
    assert getattr(scene.params, menu.field) == menu.off_preset
    assert shown(server, menu) == CUSTOM


@pytest.mark.parametrize(("menu", "preset"), EVERY_PRESET, ids=lambda x: str(x))
def test_typing_a_presets_value_shows_that_preset_and_choosing_it_sets_its_value(
    server: viser.ViserServer, scene: PelotonScene, menu: Menu, preset: str
) -> None:
    control(server, menu.control).value = menu.off_preset
    control(server, menu.control).value = menu.presets[preset]
    assert shown(server, menu) == preset
    control(server, menu.control).value = menu.off_preset
    control(server, menu.label).value = preset
    assert getattr(scene.params, menu.field) == menu.presets[preset]
    assert control(server, menu.control).value == menu.presets[preset]
    assert shown(server, menu) == preset


@pytest.mark.parametrize("menu", MENUS, ids=str)
def test_choosing_custom_leaves_the_value(server: viser.ViserServer, scene: PelotonScene, menu: Menu) -> None:
    control(server, menu.control).value = menu.off_preset
    control(server, menu.label).value = menu.default  # a preset, then Custom
    control(server, menu.label).value = CUSTOM
    assert getattr(scene.params, menu.field) == menu.presets[menu.default]
    # The value is still the preset's, and the menu says so.
    assert shown(server, menu) == menu.default


@pytest.mark.parametrize("menu", MENUS, ids=str)
def test_a_clamped_value_is_named_as_held(server: viser.ViserServer, scene: PelotonScene, menu: Menu) -> None:
    # Far past the slider's end: the scene holds the clamped value, which is no preset.
    control(server, menu.control).value = 100.0
    assert getattr(scene.params, menu.field) < 100.0
    assert shown(server, menu) == CUSTOM


def test_one_menu_leaves_the_other_as_it_is(server: viser.ViserServer, scene: PelotonScene) -> None:
    position, tyres = MENUS
    control(server, tyres.control).value = tyres.off_preset
    control(server, position.label).value = "Hour record"
    assert shown(server, tyres) == CUSTOM and scene.params.crr == tyres.off_preset
    assert shown(server, position) == "Hour record"


def test_reset_shows_the_defaults_presets(server: viser.ViserServer, switcher: SceneSwitcher) -> None:
    switcher.show("peloton")
    for menu in MENUS:
        control(server, menu.control).value = menu.off_preset
    scene = switcher.show("peloton", rebuild=True)  # what "Reset scene to defaults" does
    assert isinstance(scene, PelotonScene)
    for menu in MENUS:
        assert getattr(scene.params, menu.field) == menu.presets[menu.default]
        assert shown(server, menu) == menu.default


@pytest.mark.parametrize("menu", MENUS, ids=str)
def test_in_course_mode_the_menus_name_the_value_and_set_the_ride(
    server: viser.ViserServer, scene: PelotonScene, menu: Menu
) -> None:
    control(server, "Ride a course").value = True
    mode = scene.course_mode
    control(server, menu.control).value = menu.off_preset
    assert shown(server, menu) == CUSTOM
    preset = next(label for label in menu.presets if label != menu.default)
    control(server, menu.label).value = preset
    assert getattr(scene.params, menu.field) == menu.presets[preset]
    assert shown(server, menu) == preset
    assert mode.state is not None
    ridden = compute_course(mode.route, mode.params, scene.params)
    assert mode.state.ride.elapsed_s[-1] == ridden.ride.elapsed_s[-1]  # the ride is the preset's


# ------------------------------------------------------------------------------------------------ over the websocket
@pytest.mark.parametrize("menu", MENUS, ids=str)
def test_a_browser_sees_custom_and_may_choose_it(server: viser.ViserServer, scene: PelotonScene, menu: Menu) -> None:
    with BrowserClient(server.get_port()) as client:
        client.wait_for_gui(menu.label)
        client.set_value(menu.control, menu.off_preset)
        client.wait_for(lambda: client.value_of(menu.label) == CUSTOM, what=f"{menu.label} to read {CUSTOM}")
        preset = next(iter(menu.presets))
        client.set_value(menu.label, preset)
        client.wait_for(
            lambda: client.value_of(menu.control) == menu.presets[preset], what=f"{menu.control} to take the preset"
        )
        client.set_value(menu.control, menu.off_preset)
        client.wait_for(lambda: client.value_of(menu.label) == CUSTOM, what=f"{menu.label} to read {CUSTOM} again")
        client.set_value(menu.label, CUSTOM)  # an option the gate takes: the value stays
        client.set_value("Mass, rider + bike (kg)", 81.0)  # a later input, answered after the Custom
        client.wait_for(lambda: scene.params.mass_kg == 81.0, what="the later input")
        assert getattr(scene.params, menu.field) == menu.off_preset
        assert client.value_of(menu.label) == CUSTOM
