"""The shared scene machinery: untrusted-value cleaning, guarded callbacks, loops that stop, complete removal."""

from __future__ import annotations

import dataclasses
import threading
import time

import pytest
import viser
from helpers.scenes import StubScene
from helpers.viser_private import gui_uuids, node_names
from helpers.waiting import wait_until
from helpers.wsclient import BrowserClient

from scenes._controls import build_controls, slider


@dataclasses.dataclass(frozen=True)
class ProbeParams:
    value: float = dataclasses.field(default=1.0, metadata=slider("Value", 0.0, 10.0, 0.1))


class Probe(StubScene):
    key = "probe"
    about = "A test scene. Assumptions: none. Equation: x = x."

    def __init__(self, server: viser.ViserServer) -> None:
        super().__init__(server)
        self.params = ProbeParams()
        self.value = 1.0
        self.point = (0.0, 0.0, 0.0)
        self.calls = 0
        self.ticks = 0
        self.animating = True
        """What the loop's step reports: False puts the loop to sleep until wake_loops()."""
        self.gizmo_events = 0
        with self.gui_root:
            self.controls = build_controls(self.server.gui, self.params)
            self.slider = self.controls["value"]
            self.choice = server.gui.add_dropdown("Choice", options=("a", "b"), initial_value="a")
            self.boom = server.gui.add_button("Boom")
        self.gizmo = server.scene.add_transform_controls(f"{self.root.name}/gizmo", scale=0.5)
        self.slider.on_update(self.callback(self._on_value))
        self.boom.on_click(self.callback(self._explode))
        self.gizmo.on_update(self.callback(self._on_gizmo))
        self.start_loop(self._tick, 0.01)

    def _on_value(self) -> None:
        self.calls += 1
        self.params = self.read_controls(self.controls)
        self.value = self.params.value

    def _explode(self) -> None:
        raise RuntimeError("a bug in a callback")

    def _on_gizmo(self) -> None:
        self.point = self.read_position(self.gizmo, self.point, (-5.0, -5.0, 0.0), (5.0, 5.0, 5.0))
        self.gizmo_events += self.messages_in_call

    def _tick(self, _dt: float) -> bool:
        self.ticks += 1
        return self.animating


def _wait_ticks(probe: Probe, at_least: int) -> None:
    wait_until(lambda: probe.ticks >= at_least, f"{at_least} steps of the loop", 5.0)


def test_an_idle_loop_sleeps_until_woken_and_a_sleeping_loop_still_stops(server: viser.ViserServer) -> None:
    probe = Probe(server)
    _wait_ticks(probe, 2)
    with probe._lock:
        probe.animating = False
    _wait_ticks(probe, probe.ticks + 1)  # the step that reports "idle"
    asleep = probe.ticks
    time.sleep(0.3)  # 30 periods: an awake loop would have stepped ~30 times (a step not taken sends no event)
    assert probe.ticks == asleep
    probe.wake_loops()  # a wake-up while idle runs one step, which reports idle again
    _wait_ticks(probe, asleep + 1)
    time.sleep(0.1)  # 10 periods: a loop the wake-up left awake would have stepped again
    assert probe.ticks == asleep + 1
    with probe._lock:
        probe.animating = True
    probe.wake_loops()
    _wait_ticks(probe, asleep + 5)  # animating again: it steps every period
    with probe._lock:
        probe.animating = False
    _wait_ticks(probe, probe.ticks + 1)
    probe.close()  # the loop sleeps: close wakes it to end
    assert not any(t.name == "probe-loop" and t.is_alive() for t in threading.enumerate())


def test_numbers_are_cleaned_and_written_back(server: viser.ViserServer) -> None:
    probe = Probe(server)
    probe.slider.value = 4.0
    assert probe.value == 4.0
    probe.slider.value = float("nan")
    assert probe.value == 4.0 and probe.slider.value == 4.0
    probe.slider.value = 99.0
    assert probe.value == 10.0 and probe.slider.value == 10.0
    probe.slider.value = -3.0
    assert probe.value == 0.0
    assert probe.calls == 4  # the write-backs did not re-enter the callback
    assert probe.read_choice(probe.choice, ("a", "b"), "a") == "a"
    probe.choice.value = "zzz"  # type: ignore[assignment]  # what a crafted browser can send
    assert probe.read_choice(probe.choice, ("a", "b"), "b") == "b" and probe.choice.value == "b"
    probe.close()


def test_an_exception_in_a_callback_is_logged_not_raised(
    server: viser.ViserServer, caplog: pytest.LogCaptureFixture
) -> None:
    probe = Probe(server)
    with BrowserClient(server.get_port()) as client:
        client.wait_for_gui("Boom")
        client.click("Boom")
        client.set_value("Value", 6.0)
        client.wait_for(lambda: probe.value == 6.0, what="the scene to keep working after the bug")
    assert any("a bug in a callback" in r.getMessage() or r.exc_info for r in caplog.records)
    probe.close()


def test_gizmo_positions_from_a_browser_are_cleaned(server: viser.ViserServer) -> None:
    probe = Probe(server)
    with BrowserClient(server.get_port()) as client:
        client.wait_for_node("/probe/gizmo")
        client.drag_transform("/probe/gizmo", [(1.0, 2.0, 3.0)])
        client.wait_for(lambda: probe.point == (1.0, 2.0, 3.0), what="a good drag")
        seen = probe.gizmo_events
        client.drag_transform("/probe/gizmo", [(float("nan"), 0.0, 0.0)])
        # start, update and end each run the callback: wait until all three were handled
        client.wait_for(lambda: probe.gizmo_events >= seen + 3, what="the crafted drag to be handled")
        with probe._lock:
            assert probe.point == (1.0, 2.0, 3.0)
            assert tuple(probe.gizmo.position) == (1.0, 2.0, 3.0)
        client.drag_transform("/probe/gizmo", [(1e9, -1e9, 2.0)])
        client.wait_for(lambda: probe.point == (5.0, -5.0, 2.0), what="a clamped drag")
    probe.close()


def test_close_stops_the_loop_and_removes_everything(server: viser.ViserServer) -> None:
    nodes, gui = node_names(server), gui_uuids(server)
    probe = Probe(server)
    _wait_ticks(probe, 3)
    probe.close()
    ticks = probe.ticks
    time.sleep(0.1)  # 10 periods: a loop still running would have stepped again (no event marks a step not taken)
    assert probe.ticks == ticks
    assert not any(t.name == "probe-loop" and t.is_alive() for t in threading.enumerate())
    assert node_names(server) == nodes and gui_uuids(server) == gui
