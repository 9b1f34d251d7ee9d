"""Bursts of browser input coalesce (latest value wins) and still end on the last value, for every viewer; the SDF
gallery's progressive meshing (a cheap preview while a drag's inputs keep arriving) ends on the full-quality mesh
and reference once they stop.

The fault's kind: work queued per message, so a flood either falls behind without bound or, once coalesced, drops
the final value. The unit tests pin the mechanism (:meth:`scenes._base.Scene.callback`) deterministically, for any
sequence of values; the scene tests flood real scenes over the websocket. No timed assertions: waits are for state.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable

import numpy as np
import pytest
import trimesh
import viser
from helpers.properties import examples
from helpers.scenes import StubScene
from helpers.waiting import wait_until
from helpers.wsclient import BrowserClient
from hypothesis import given, settings
from hypothesis import strategies as st

from kernels import sdf
from scenes.arm import ArmScene
from scenes.freekick import FreeKickParams, FreeKickScene
from scenes.freekick.model import compute_kick, resample
from scenes.freekick.props import polyline_segments
from scenes.sdf_gallery import SdfGalleryScene
from scenes.sdf_gallery.params import PREVIEW_RESOLUTION
from server.switcher import SceneSwitcher
from server.turns import Turns
from shaders import gl_service
from shaders.renderer import GLUnavailableError

SPEED = "Launch speed (m/s)"


class Held(StubScene):
    """A scene whose handler blocks on its first call until released, and records the value each call reads."""

    key = "held"

    def __init__(self, server: viser.ViserServer) -> None:
        super().__init__(server)
        self.latest = 0.0
        """Stands for a handle's value: set before each call, as viser sets the handle before it queues one."""
        self.read: list[float] = []
        self.entered = threading.Event()
        self.release = threading.Event()
        self.handler = self.callback(self._on_value)

    def _on_value(self) -> None:
        self.read.append(self.latest)
        self.entered.set()
        self.release.wait()


def flood(held: Held, values: list[float], queued: int = 1) -> list[threading.Thread]:
    """Call the handler once per value from its own thread (viser's pool), the value set first, while the first
    call is still running; return the threads once all but the ``queued`` ones still waiting have returned."""
    threads = []
    for value in values:
        held.latest = value
        thread = threading.Thread(target=held.handler)
        thread.start()
        threads.append(thread)
    wait_until(lambda: sum(t.is_alive() for t in threads) <= queued, "the flood to coalesce")
    return threads


@settings(max_examples=examples(20), deadline=None)
@given(values=st.lists(st.floats(0.0, 10.0, allow_nan=False), min_size=1, max_size=60))
def test_a_flood_coalesces_to_one_call_that_reads_the_last_value(values: list[float]) -> None:
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        held = Held(server)
        first = threading.Thread(target=held.handler)
        first.start()
        held.entered.wait()  # the first call runs (and holds the scene) while the flood arrives
        threads = flood(held, values)
        held.release.set()
        for thread in [first, *threads]:
            thread.join()
        # One call for the whole flood, after it, reading the last value sent: none lost, none repeated.
        assert held.read == [0.0, values[-1]]
    finally:
        server.stop()


def test_200_values_coalesce_to_the_last() -> None:
    """The plain case of the family: 200 values while a call runs; the last (7.3) is the one applied."""
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        held = Held(server)
        first = threading.Thread(target=held.handler)
        first.start()
        held.entered.wait()
        values = [round(0.05 * i, 2) for i in range(199)] + [7.3]
        threads = flood(held, values)
        held.release.set()
        for thread in [first, *threads]:
            thread.join()
        assert held.read == [0.0, 7.3]
    finally:
        server.stop()


@settings(max_examples=examples(10), deadline=None)
@given(values=st.lists(st.floats(0.0, 10.0, allow_nan=False), min_size=1, max_size=40))
def test_two_scenes_take_turns_and_a_burst_that_waits_merges(values: list[float]) -> None:
    """While one tab's callback runs, another tab's scene does not run its own (one turn per process), and the burst
    that waits meanwhile merges into at most two calls, both reading the last value."""
    servers = [viser.ViserServer(host="127.0.0.1", port=0, verbose=False) for _ in range(2)]
    try:
        running, waiting = Held(servers[0]), Held(servers[1])
        waiting.release.set()  # its calls never block: only the turn holds them
        first = threading.Thread(target=running.handler)
        first.start()
        running.entered.wait()
        # One call holds its scene and waits for the turn, one more waits for the scene; the rest merged.
        threads = flood(waiting, values, queued=2)
        assert waiting.read == []
        running.release.set()
        for thread in [first, *threads]:
            thread.join()
        assert 1 <= len(waiting.read) <= 2 and set(waiting.read) == {values[-1]}
    finally:
        for server in servers:
            server.stop()


def test_turns_go_in_the_order_asked_are_reentrant_and_survive_an_exception() -> None:
    turns = Turns()
    order: list[int] = []
    inside = 0
    most_inside = 0
    lock = threading.Lock()

    def take(k: int) -> None:
        nonlocal inside, most_inside
        with turns.turn():
            with lock:
                inside += 1
                most_inside = max(most_inside, inside)
            with turns.turn():  # re-entrant: the holder's own nested turn goes at once
                order.append(k)
            with lock:
                inside -= 1

    with turns.turn():
        threads = []
        for k in range(12):
            thread = threading.Thread(target=take, args=(k,))
            thread.start()
            wait_until(lambda k=k: len(turns._waiting) == k + 1, f"caller {k} to queue")
            threads.append(thread)
    for thread in threads:
        thread.join()
    assert order == list(range(12)) and most_inside == 1
    with pytest.raises(RuntimeError), turns.turn():
        raise RuntimeError("a failing callback")
    done = threading.Event()

    def take_once() -> None:
        with turns.turn():
            done.set()

    threading.Thread(target=take_once).start()
    assert done.wait(5.0), "the turn stayed held after an exception"


class SlowBuild(StubScene):
    """A scene whose control exists, and is moved by a browser, before its 3D node does."""

    key = "slowbuild"

    def __init__(self, server: viser.ViserServer) -> None:
        super().__init__(server)
        self.node: viser.FrameHandle | None = None
        self.seen: list[bool] = []
        handler = self.callback(lambda: self.seen.append(self.node is not None))
        caller = threading.Thread(target=handler)  # a browser's message, on viser's thread pool
        caller.start()
        caller.join(timeout=0.3)  # long enough for an unguarded handler to run on the half-built scene
        self.caller = caller
        self.node = server.scene.add_frame(f"{self.root.name}/node")


def test_a_callback_during_the_build_waits_for_it() -> None:
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        scene = SlowBuild(server)
        scene.caller.join()
        assert scene.seen == [True]  # it ran once, on the whole scene
    finally:
        server.stop()


# ------------------------------------------------------------------------------------------ real scenes
def test_flooding_a_slider_ends_on_the_last_value_for_every_viewer(
    server: viser.ViserServer, switcher: SceneSwitcher
) -> None:
    scene = switcher.show("freekick")
    assert isinstance(scene, FreeKickScene)
    values = [round(20.0 + 0.5 * (i % 24), 1) for i in range(199)] + [27.5]
    with BrowserClient(server.get_port()) as sender, BrowserClient(server.get_port()) as viewer:
        sender.wait_for_gui(SPEED)
        viewer.wait_for_gui(SPEED)
        for value in values:  # no pauses: far faster than the scene can redraw
            sender.set_value(SPEED, value)
        wait_until(lambda: scene.params.speed_ms == 27.5, "the scene on the last speed")
        scene.wait_idle()
        expected = polyline_segments(resample(compute_kick(FreeKickParams(speed_ms=27.5)).flight))
        np.testing.assert_allclose(scene.path.points, expected, rtol=1e-6)
        for client in (sender, viewer):
            client.wait_for(lambda c=client: c.value_of(SPEED) == 27.5, what="the slider at 27.5")
            client.wait_for(
                lambda c=client: np.allclose(
                    c.nodes["/freekick/path"].get("props", {}).get("points", np.zeros(0)).reshape(-1),
                    expected.reshape(-1),
                    rtol=1e-6,
                ),
                what="the 27.5 m/s path drawn",
            )


def test_sdf_preview_while_dragging_ends_on_the_full_mesh_and_reference(
    server: viser.ViserServer, switcher: SceneSwitcher
) -> None:
    try:
        gl_service.run(lambda _renderer: None)
        has_gl = True
    except GLUnavailableError:
        has_gl = False  # the mesh half still runs; the reference half needs GL
    scene = switcher.show("sdf")
    assert isinstance(scene, SdfGalleryScene)
    full = scene.params.resolution
    assert full > PREVIEW_RESOLUTION
    with BrowserClient(server.get_port()) as client:
        client.wait_for_node("/sdf/mesh")
        previews, references = scene.preview_serial, scene.reference_serial
        path = [(0.3 * math.cos(a), 0.3 * math.sin(a), 0.5) for a in np.linspace(0, 2 * math.pi, 61)[1:]]
        client.drag_transform("/sdf/gizmo_2", path)  # no pauses: a burst
        target = tuple(float(v) for v in path[-1])
        wait_until(
            lambda: scene.mesh_scene is not None and np.allclose(scene.mesh_scene.primitives[1].center, target),
            "the full mesh of the last position",
        )
        assert scene.preview_serial > previews  # the drag was shown with cheap previews
        assert scene.shown_resolution == full  # and ended on the full resolution
        vertices, faces, _colors = sdf.mesh(scene.params.scene(), full)
        np.testing.assert_array_equal(scene.mesh_vertices, vertices)
        if has_gl:
            client.send_camera(position=(2.0, -2.4, 1.6), look_at=(0.0, 0.0, 0.3), size=(400, 640))
            client.set_value("View", "Both")
            # The wireframe drawn into the ray-marched frame is the full mesh's, not a preview's.
            edges = trimesh.Trimesh(vertices, faces, process=False).edges_unique
            wait_until(lambda: scene.view_edges == len(edges), "the wireframe of the full mesh")
        client.set_value("View", "Mesh")
        wait_until(lambda: scene.mesh_node.visible, "the mesh back")
        client.wait_for(
            lambda: client.nodes["/sdf/mesh"].get("props", {}).get("glb_data") == scene.mesh_node.glb_data,
            what="the full mesh at the viewer",
        )
        if has_gl:
            wait_until(
                lambda: scene.reference_serial > references and scene.reference_mesh_serial == scene.mesh_serial,
                "the reference against the full mesh after the drag",
            )
            assert scene.reference_rgb is not None
            assert scene.reference_rgb.shape[1] == scene.params.reference_width
            assert scene.agreement.iou is not None and scene.agreement.iou > 0.9


@pytest.mark.parametrize("gizmo", ["/arm/target", "/arm/obstacle_0"])
def test_a_drag_burst_on_an_arm_gizmo_coalesces_and_ends_on_its_last_pose(
    server: viser.ViserServer, switcher: SceneSwitcher, gizmo: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Every gizmo's handler is made once, so a burst of drag messages queued behind a busy scene runs the handler
    a few times, not once a message, and the chain ends on the last pose sent. Before, the arm made a new wrapper
    per message: 40 messages, 40 handler runs, each holding one of viser's callback threads while it waited (the
    kind: a per-message wrapper defeats coalescing)."""
    runs: list[int] = []
    for name in ("_apply_target", "_apply_obstacle"):
        original = getattr(ArmScene, name)

        def counted(self: ArmScene, *args: int, _original: Callable[..., None] = original) -> None:
            runs.append(self.messages_in_call)
            _original(self, *args)

        monkeypatch.setattr(ArmScene, name, counted)
    scene = switcher.show("arm")
    assert isinstance(scene, ArmScene)
    handle = scene.target_gizmo if gizmo == "/arm/target" else scene.obstacle_gizmos[0]
    path = [(0.45 + 0.2 * math.cos(t), 0.0, 0.8 + 0.2 * math.sin(t)) for t in np.linspace(0, 3, 40)]
    with BrowserClient(server.get_port()) as client:
        client.wait_for_node(gizmo)
        runs.clear()
        with scene._lock:  # the scene is busy: every message queues behind the lock
            client.drag_transform(gizmo, path)
            wait_until(
                lambda: np.allclose(np.asarray(handle.position), path[-1]), "the last message to reach the server"
            )
            time.sleep(0.2)  # let viser's pool start the queued calls (each returns or waits on the lock)
        wait_until(lambda: sum(runs) >= len(path), "every message handled")
        with scene._lock:
            shown = scene.target if gizmo == "/arm/target" else scene.obstacle_centres[0]
            np.testing.assert_allclose(shown, path[-1])
            assert len(runs) <= 3, runs
