"""Controls declared once on a parameter dataclass: the builder makes what is declared, the reader cleans what a
browser sends as the gate does, and one more declared field is one more control with no other code."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import field
from typing import Any, Literal

import pytest
import viser
from helpers.viser_private import store_value
from helpers.waiting import wait_until
from helpers.wsclient import BrowserClient

from scenes._controls import (
    Controls,
    build_controls,
    checkbox,
    declared,
    dropdown,
    number,
    read_controls,
    rgb,
    slider,
    text,
)
from server.clean import ControlSpec, control_spec

Mode = Literal["fast", "exact"]


@dataclasses.dataclass(frozen=True)
class Demo:
    """Every kind of declaration, in two folders and outside any."""

    speed_kmh: float = field(default=40.0, metadata=slider("Speed (km/h)", 0, 80, 0.5, folder="A"))
    """A float slider."""
    riders: int = field(default=8, metadata=slider("Riders", 1, 16, 1, folder="A"))
    """An integer slider (the default is an int)."""
    power_w: float = field(default=250.0, metadata=number("Power (W)", 0.0, 2500.0, 5.0))
    """A number box."""
    mode: Mode = field(
        default="exact", metadata=dropdown("Mode", ("fast", "exact"), ("Fast (approximate)", "Exact"), folder="B")
    )
    """A dropdown whose field holds the option and whose GUI shows its label."""
    drafting: bool = field(default=True, metadata=checkbox("Drafting", folder="B"))
    """A checkbox."""
    radii_m: tuple[float, ...] = field(default=(0.1, 0.2, 0.3), metadata=slider("Ball {n} radius (m)", 0.05, 0.5, 0.01))
    """A tuple: one slider per element."""
    colour: tuple[int, int, int] = field(default=(10, 20, 30), metadata=rgb("Colour"))
    """An RGB colour: one control for the tuple."""
    source: str = field(default="sphere", metadata=text("Source", multiline=True))
    """Text."""
    note: str = "not a control"
    """A field without a declaration: no control, and the reader keeps its value."""


def _set_value(handle: Any, value: Any) -> None:
    handle.value = value


def read_logged(
    controls: Controls[Demo], last: Demo, store: Callable[[Any, Any], None] = _set_value
) -> tuple[Demo, list[tuple[str, Any]]]:
    """``read_controls`` with a write-back that records (label, value) for each value it writes back, then has
    ``store`` write it; the parameters read and that log."""
    log: list[tuple[str, Any]] = []

    def write(handle: Any, value: Any) -> None:
        log.append((handle.label, value))
        store(handle, value)

    return read_controls(controls, last, write_back=write), log


@pytest.fixture
def demo(server: viser.ViserServer) -> Controls[Demo]:
    return build_controls(server.gui, Demo())


@pytest.mark.parametrize(
    ("name", "kind", "label", "lo", "hi", "step", "value"),
    [
        ("speed_kmh", viser.GuiSliderHandle, "Speed (km/h)", 0, 80, 0.5, 40.0),
        ("riders", viser.GuiSliderHandle, "Riders", 1, 16, 1, 8),
        ("power_w", viser.GuiNumberHandle, "Power (W)", 0.0, 2500.0, 5.0, 250.0),
    ],
)
def test_the_builder_makes_each_declared_number(
    demo: Controls[Demo],
    name: str,
    kind: type[viser.GuiSliderHandle] | type[viser.GuiNumberHandle],
    label: str,
    lo: float,
    hi: float,
    step: float,
    value: float,
) -> None:
    handle = demo[name]
    assert isinstance(handle, kind)
    assert (handle.label, handle.min, handle.max, handle.step, handle.value) == (label, lo, hi, step, value)
    assert type(handle.value) is type(value)


def test_the_builder_makes_each_declared_control(demo: Controls[Demo]) -> None:
    mode = demo["mode"]
    assert isinstance(mode, viser.GuiDropdownHandle)
    assert tuple(mode.options) == ("Fast (approximate)", "Exact") and mode.value == "Exact"
    drafting = demo["drafting"]
    assert isinstance(drafting, viser.GuiCheckboxHandle) and drafting.value is True
    assert [h.label for h in demo.each("radii_m")] == [f"Ball {n} radius (m)" for n in (1, 2, 3)]
    assert [h.value for h in demo.each("radii_m")] == [0.1, 0.2, 0.3]
    assert isinstance(demo["colour"], viser.GuiRgbHandle) and demo["colour"].value == (10, 20, 30)
    assert isinstance(demo["source"], viser.GuiTextHandle) and demo["source"].value == "sphere"
    # In field order, nothing for the undeclared field, and the declared folders, opened once each.
    assert list(demo.fields) == ["speed_kmh", "riders", "power_w", "mode", "drafting", "radii_m", "colour", "source"]
    assert [h.label for h in demo][:3] == ["Speed (km/h)", "Riders", "Power (W)"]
    assert {label: folder.label for label, folder in demo.folders.items()} == {"A": "A", "B": "B"}


def test_the_gate_gets_each_spec_from_its_declaration(demo: Controls[Demo]) -> None:
    assert control_spec(demo["speed_kmh"]) == ControlSpec("number", lo=0.0, hi=80.0)
    assert control_spec(demo["riders"]) == ControlSpec("number", lo=1.0, hi=16.0, integer=True)
    assert control_spec(demo["mode"]) == ControlSpec("choice", options=("Fast (approximate)", "Exact"))
    assert control_spec(demo["drafting"]) == ControlSpec("bool")
    assert control_spec(demo["colour"]).kind == "rgb"
    assert control_spec(demo["source"]).kind == "text"
    # A handle's props changed later (once a browser could) do not move the recorded range.
    speed = demo["speed_kmh"]
    assert isinstance(speed, viser.GuiSliderHandle)
    speed.max = 1000.0
    assert control_spec(speed).hi == 80.0


def test_the_reader_returns_the_values_shown(demo: Controls[Demo]) -> None:
    demo["speed_kmh"].value = 55.5
    demo["riders"].value = 3
    demo["mode"].value = "Fast (approximate)"
    demo["drafting"].value = False
    demo.each("radii_m")[1].value = 0.45
    demo["colour"].value = (1, 2, 3)
    demo["source"].value = "box"
    params, log = read_logged(demo, Demo(note="kept"))
    assert params == Demo(
        speed_kmh=55.5,
        riders=3,
        mode="fast",
        drafting=False,
        radii_m=(0.1, 0.45, 0.3),
        colour=(1, 2, 3),
        source="box",
        note="kept",
    )
    assert isinstance(params.riders, int) and isinstance(params.speed_kmh, float)
    assert log == []  # nothing to clean, nothing written back


def test_the_reader_clamps_numbers_to_the_declared_range_and_writes_them_back(demo: Controls[Demo]) -> None:
    store_value(demo["speed_kmh"], 1e308)
    store_value(demo["riders"], -40)
    store_value(demo["power_w"], 9999.0)
    store_value(demo.each("radii_m")[2], 0.0)
    params, log = read_logged(demo, Demo())
    assert (params.speed_kmh, params.riders, params.power_w) == (80.0, 1, 2500.0)
    assert params.radii_m == (0.1, 0.2, 0.05)
    assert demo["speed_kmh"].value == 80.0 and demo["riders"].value == 1
    assert demo.each("radii_m")[2].value == 0.05
    assert sorted(log) == sorted(
        [("Speed (km/h)", 80.0), ("Riders", 1), ("Power (W)", 2500.0), ("Ball 3 radius (m)", 0.05)]
    )


@pytest.mark.parametrize(
    ("name", "bad"),
    [
        ("speed_kmh", math.nan),
        ("speed_kmh", math.inf),
        ("speed_kmh", -math.inf),
        ("speed_kmh", "fast"),
        ("speed_kmh", True),
        ("speed_kmh", None),
        ("riders", [3]),
        ("power_w", math.nan),
        ("mode", "Turbo"),
        ("mode", "fast"),  # an option, not a label: the browser only ever sees labels
        ("mode", 1),
        ("drafting", 1),
        ("drafting", "true"),
        ("colour", (300, 0, 0)),
        ("colour", (math.nan, 0, 0)),
        ("colour", (1, 2)),
        ("source", 42),
        ("source", "x" * 20_000),
    ],
)
def test_the_reader_refuses_unusable_values_and_keeps_the_last_good_one(
    demo: Controls[Demo], name: str, bad: object
) -> None:
    last = Demo(speed_kmh=12.5, riders=5, power_w=100.0, mode="fast", drafting=False, colour=(4, 5, 6), source="torus")
    for field_name in ("speed_kmh", "riders", "power_w", "drafting", "colour", "source"):
        demo[field_name].value = getattr(last, field_name)
    demo["mode"].value = "Fast (approximate)"
    store_value(demo[name], bad)
    # viser casts a value set on a handle to the type of the one it holds: a wrong type can only be stored by a
    # browser the gate let through (it does not), so here the write-back goes where the browser's went.
    params, log = read_logged(demo, last, store=store_value)
    assert params == last
    shown = "Fast (approximate)" if name == "mode" else getattr(last, name)
    assert demo[name].value == shown
    assert log == [(demo[name].label, shown)]


def test_the_reader_keeps_the_last_good_element_of_a_tuple(demo: Controls[Demo]) -> None:
    store_value(demo.each("radii_m")[0], math.nan)
    params = read_controls(demo, Demo(radii_m=(0.25, 0.2, 0.3)))
    assert params.radii_m == (0.25, 0.2, 0.3)
    assert demo.each("radii_m")[0].value == 0.25


def test_a_float_slider_may_hold_an_int(demo: Controls[Demo]) -> None:
    """viser keeps a browser's 40 as an int: the same number, nothing written back, a float in the params."""
    store_value(demo["speed_kmh"], 40)
    params, log = read_logged(demo, Demo())
    assert params.speed_kmh == 40.0 and isinstance(params.speed_kmh, float) and log == []


def test_adding_a_control_is_one_declaration(server: viser.ViserServer) -> None:
    @dataclasses.dataclass(frozen=True)
    class More(Demo):
        damping: float = field(default=0.5, metadata=slider("Damping", 0.0, 1.0, 0.05, folder="A"))
        """The one new declaration."""

    before = build_controls(server.gui, Demo())
    after = build_controls(server.gui, More())
    assert list(after.fields) == [*before.fields, "damping"]
    assert len(list(after)) == len(list(before)) + 1
    damping = after["damping"]
    assert isinstance(damping, viser.GuiSliderHandle)
    assert (damping.label, damping.min, damping.max, damping.step, damping.value) == ("Damping", 0.0, 1.0, 0.05, 0.5)
    assert control_spec(damping) == ControlSpec("number", lo=0.0, hi=1.0)
    store_value(damping, 7.0)
    assert read_controls(after, More()).damping == 1.0 and damping.value == 1.0


def test_some_fields_can_be_built_where_the_caller_is(server: viser.ViserServer) -> None:
    with server.gui.add_folder("Mine"):
        some = build_controls(server.gui, Demo(), ("power_w", "source"))
    assert list(some.fields) == ["power_w", "source"] and not some.folders
    store_value(some["power_w"], -5.0)
    params = read_controls(some, Demo(speed_kmh=3.0))
    assert (params.power_w, params.speed_kmh) == (0.0, 3.0)  # fields not built keep their value
    assert list(declared(Demo)) == [*Demo.__dataclass_fields__][:-1]  # every field but the undeclared note
    rest = build_controls(server.gui, Demo(), ("speed_kmh", "riders"))
    both = some | rest
    assert list(both.fields) == ["power_w", "source", "speed_kmh", "riders"]
    store_value(rest["riders"], 99)
    assert read_controls(both, Demo()).riders == 16
    with pytest.raises(AssertionError, match="no declared control"):
        build_controls(server.gui, Demo(), ("note",))


def test_a_later_build_fills_a_folder_an_earlier_one_opened(server: viser.ViserServer) -> None:
    first = build_controls(server.gui, Demo(), ("speed_kmh",))
    with first.folders["A"]:
        between = server.gui.add_button("Between")
    rest = build_controls(server.gui, Demo(), ("riders",), folders_open=first.folders)
    assert rest.folders["A"] is first.folders["A"]  # no second "A" folder
    assert first["speed_kmh"].order < between.order < rest["riders"].order
    assert read_controls(first | rest, Demo()).riders == 8


def test_a_browser_value_is_cleaned_once_by_the_declared_spec(server: viser.ViserServer) -> None:
    """Through the gate: out of range is clamped there, NaN refused there, and the reader agrees with both."""
    demo = build_controls(server.gui, Demo())
    with BrowserClient(server.get_port()) as client:
        client.wait_for_gui("Riders")
        client.set_value("Riders", 99)
        client.set_value("Speed (km/h)", math.nan)
        client.send_value("Mode", "Turbo")
        client.set_value("Power (W)", 3000.0)
        wait_until(
            lambda: demo["riders"].value == 16 and demo["power_w"].value == 2500.0,
            "the gate's clamped values",
            timeout_s=10.0,
        )
    params, log = read_logged(demo, Demo())
    assert (params.riders, params.power_w, params.speed_kmh, params.mode) == (16, 2500.0, 40.0, "exact")
    assert log == []  # the gate already sent what the reader would: nothing left to clean
