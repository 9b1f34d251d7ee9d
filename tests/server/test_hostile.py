"""A hostile browser against every control and gizmo of every scene: the gate lets only values, poses and cameras in.

The fake browser (``wsclient.BrowserClient``) sends, for every control and gizmo of every scene, NaN, ±inf, ±1e308,
wrong types, wrong lengths, unknown options, crafted GUI fields (``props``, ``update_cb``, ``removed``...), malformed
frames and unknown ids. Each must leave every viewer (the sender and an honest second browser) on the server's last
good state, be logged once per kind (one line, no traceback), and keep the server serving.
"""

from __future__ import annotations

import contextlib
import functools
import logging
import math
import time
from collections.abc import Iterator
from typing import Any

import msgspec
import numpy as np
import pytest
import viser
from helpers.scenes import StubScene
from helpers.viser_private import control_state, gizmos, gui_inputs
from helpers.waiting import wait_until
from helpers.wsclient import BrowserClient, connect_tab
from hypothesis import example, given
from hypothesis import strategies as st

from scenes import SCENES, Scene
from scenes.peloton.model import MAX_GROUP
from server.clean import NEGLIGIBLE, ControlSpec, clean_value, control_spec, unit_quaternion
from server.gate import same_value
from server.refusals import refusals
from server.switcher import SceneSwitcher

INPUT_TYPES = {
    "GuiSliderMessage",
    "GuiNumberMessage",
    "GuiDropdownMessage",
    "GuiCheckboxMessage",
    "GuiRgbMessage",
    "GuiTextMessage",
    "GuiVector2Message",
    "GuiVector3Message",
}
NAN, INF = float("nan"), float("inf")
WRONG_TYPES: list[Any] = ["fast", "", [1, 2, 3], [], {"a": 1}, None, b"\x00"]
BAD_NUMBERS: list[Any] = [NAN, INF, -INF, True, False, "1", *WRONG_TYPES]
BAD_BOOLS: list[Any] = ["false", "true", 0, 1, 0.0, NAN, None, [True], "yes"]
BAD_CHOICES: list[Any] = ["not an option", "<img src=x onerror=alert(1)>", "", 0, None, ["a"], NAN]
BAD_RGB: list[Any] = [[0, 0], [0, 0, 0, 0], [NAN, 0, 0], [300, 0, 0], [-1, 0, 0], "red", None, 7]
CRAFTED_FIELDS: list[Any] = [
    {"props": {}},
    {"props": {"min": 0, "max": 1e9}},
    {"update_cb": []},
    {"removed": True},
    {"sync_cb": None},
    {"value": 1.0, "props": {}},
    {"visible": False},
    {"disabled": True},
    {"label": "pwned"},
    {},
]
BAD_POSITIONS: list[Any] = [
    (NAN, 0.0, 0.0),
    (INF, 0.0, 0.0),
    (0.0, -INF, 0.0),
    (0.1, 0.2),
    (0.1, 0.2, 0.3, 0.4),
    (),
    "abc",
    None,
    (True, 0.0, 0.0),
    (("x",), 0.0, 0.0),
]
BAD_WXYZ: list[Any] = [
    (1.0, 0.0, 0.0),
    (0.0, 0.0, 0.0, 0.0),
    (NAN, 0.0, 0.0, 0.0),
    (INF, 0.0, 0.0, 0.0),
    (1.0, 0.0, 0.0, 0.0, 0.0),
    "quat",
    None,
]
SENTINELS = {  # an honest edit per scene, to know the hostile messages before it were all handled
    "peloton": ("Speed (km/h)", 33.0, "speed_kmh"),
    "arm": ("Max iterations", 77, "max_iterations"),
    "freekick": ("Spin rate (rev/s)", 3.0, "spin_rev_s"),
    "sdf": ("Blend width k (m)", 0.37, "k"),
}


def refused_lines(caplog: pytest.LogCaptureFixture) -> list[logging.LogRecord]:
    return [r for r in caplog.records if r.name == "server.refusals"]


def refused_kind(record: logging.LogRecord) -> str:
    return str(record.args[0]) if isinstance(record.args, tuple) else record.getMessage()


def server_values(server: viser.ViserServer) -> dict[str, Any]:
    """Every input's value on the server; an upload button's is the last file, which is never sent to a browser."""
    return {
        uuid: handle.value  # type: ignore[attr-defined]
        for uuid, handle in gui_inputs(server.gui).items()
        if not isinstance(handle, viser.GuiUploadButtonHandle)
    }


def shows_server_values(client: BrowserClient, server: viser.ViserServer) -> bool:
    values = server_values(server)
    with client._lock:
        shown = {uuid: element["value"] for uuid, element in client.gui.items()}
    return all(same_value(shown.get(uuid), value) for uuid, value in values.items() if uuid in shown)


def shows_server_poses(client: BrowserClient, server: viser.ViserServer) -> bool:
    for name, gizmo in gizmos(server.scene).items():
        try:
            position, wxyz = client.pose_of(name)
        except (KeyError, TypeError, ValueError):
            return False
        if not (np.allclose(position, gizmo.position, atol=1e-9) and np.allclose(wxyz, gizmo.wxyz, atol=1e-9)):
            return False
    return True


def bad_values_for(kind: str) -> list[Any]:
    match kind:
        case "GuiSliderMessage" | "GuiNumberMessage":
            return BAD_NUMBERS
        case "GuiCheckboxMessage":
            return BAD_BOOLS
        case "GuiDropdownMessage":
            return BAD_CHOICES
        case "GuiRgbMessage" | "GuiVector2Message" | "GuiVector3Message":
            return BAD_RGB
        case _:
            return [None, 5, [1], {"a": 1}, "x" * 20_000]


MALFORMED_FRAMES: list[bytes | str] = [
    b"",
    b"\x93garbage",
    b"\xff" * 64,
    msgspec.msgpack.encode([1, 2, 3]),
    msgspec.msgpack.encode({"no": "type"}),
    msgspec.msgpack.encode({"type": "NoSuchMessage", "x": 1}),
    msgspec.msgpack.encode({"type": "GuiUpdateMessage"}),
    msgspec.msgpack.encode({"type": "GuiUpdateMessage", "uuid": 5, "updates": [1]}),
    msgspec.msgpack.encode({"type": "ShareUrlRequest"}),
    msgspec.msgpack.encode({"type": "GuiFormSubmitMessage", "uuid": "x"}),
    msgspec.msgpack.encode({"type": "TransformControlsUpdateMessage", "name": "/x"}),
    "a text frame",
]


def bad_cameras() -> list[dict[str, Any]]:
    good: dict[str, Any] = {
        "wxyz": (1.0, 0.0, 0.0, 0.0),
        "position": (3.0, -6.0, 3.0),
        "fov": 1.0,
        "near": 0.01,
        "far": 1000.0,
        "image_height": 720,
        "image_width": 1280,
        "look_at": (0.0, 0.0, 0.0),
        "up_direction": (0.0, 0.0, 1.0),
    }
    changes: list[dict[str, Any]] = [
        {"image_height": 0},
        {"image_width": 0},
        {"image_height": -720},
        {"image_height": 720.5},
        {"image_height": "720"},
        {"image_height": 10**9},
        {"image_height": True},
        {"fov": NAN},
        {"fov": 0.0},
        {"fov": 1e308},
        {"near": 0.0},
        {"far": 0.001},
        {"wxyz": (0.0, 0.0, 0.0, 0.0)},
        {"wxyz": (1.0, 0.0, 0.0)},
        {"position": (NAN, 0.0, 0.0)},
        {"position": (INF, 0.0, 0.0)},
        {"position": (1e308, 1e308, 1e308)},  # finite, but every distance from it overflows
        {"look_at": (1e300, -1e300, 0.0)},
        {"look_at": "origin"},
        {"up_direction": (0.0, 0.0, 0.0)},
    ]
    return [{**good, **change} for change in changes]


def assert_an_honest_edit_lands_after(
    sent: int, attacker: BrowserClient, scene: Scene, label: str, field: str, good: object
) -> None:
    """After a barrage of ``sent`` hostile messages (more than 100), the attacker's honest edit of ``label`` to
    ``good`` reaches the scene's ``field``, and the server keeps serving the attacker too: its connection is still
    up and answered."""
    assert sent > 100
    attacker.set_value(label, good)
    attacker.wait_for(
        lambda: getattr(scene.params, field) == good,  # type: ignore[attr-defined]
        timeout_s=60,
        what=f"the honest {label} edit after {sent} hostile messages",
    )
    assert not attacker.closed_by_server


def hostile_barrage(attacker: BrowserClient, server: viser.ViserServer) -> int:
    """Send every hostile message this suite knows at every control and gizmo; returns how many were sent."""
    sent = 0
    for uuid, element in list(attacker.gui.items()):
        kind = element["type"]
        if kind in INPUT_TYPES:
            for value in bad_values_for(kind):
                with attacker._lock:  # the browser shows its own (crafted) edit, as the real one does
                    attacker.gui[uuid]["value"] = value
                attacker.send("GuiUpdateMessage", uuid=uuid, updates={"value": value})
                sent += 1
        if kind in INPUT_TYPES or kind == "GuiButtonMessage":
            for updates in CRAFTED_FIELDS:
                attacker.send("GuiUpdateMessage", uuid=uuid, updates=updates)
                sent += 1
    for unknown in ("no-such-uuid", "", "x" * 1000):
        attacker.send("GuiUpdateMessage", uuid=unknown, updates={"value": 1.0})
        sent += 1
    for name, gizmo in gizmos(server.scene).items():
        good_wxyz = tuple(float(v) for v in gizmo.wxyz)
        good_position = tuple(float(v) for v in gizmo.position)
        attacker.drag_transform(name, BAD_POSITIONS, wxyz=good_wxyz)
        for wxyz in BAD_WXYZ:
            attacker.drag_transform(name, [good_position], wxyz=wxyz)
        sent += len(BAD_POSITIONS) + len(BAD_WXYZ)
    attacker.send("TransformControlsUpdateMessage", name="/no/such/gizmo", wxyz=(1, 0, 0, 0), position=(0, 0, 0))
    bad_rays: list[Any] = [(NAN, 0.0, 1.0), (0.0, INF, 1.0), (0.0, 0.0), "up", None]
    for ray in bad_rays:
        attacker.send(
            "ScenePointerMessage",
            event_type="click",
            ray_origin=ray,
            ray_direction=(1.0, 0.0, 0.0),
            screen_pos=((0.5, 0.5),),
            modifier=None,
        )
        attacker.send(
            "ScenePointerMessage",
            event_type="click",
            ray_origin=(0.0, 0.0, 1.0),
            ray_direction=ray if ray is not None else (0.0, 0.0, 0.0),
            screen_pos=((NAN, 0.5),),
            modifier=None,
        )
        for name in list(attacker.nodes):
            attacker.send(
                "SceneNodeClickMessage",
                name=name,
                instance_index=-1 if ray is None else None,
                ray_origin=ray,
                ray_direction=(1.0, 0.0, 0.0),
                screen_pos=(0.5, 0.5),
                modifier=None,
            )
        sent += 2 + len(attacker.nodes)
    for camera in bad_cameras():
        attacker.send("ViewerCameraMessage", **camera)
        sent += 1
    for frame in MALFORMED_FRAMES:
        attacker._ws.send(frame)
        sent += 1
    return sent


def scene_poses(server: viser.ViserServer) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    return {name: (np.array(gizmo.position), np.array(gizmo.wxyz)) for name, gizmo in gizmos(server.scene).items()}


def assert_untouched_but(
    sentinel: str,
    server: viser.ViserServer,
    values_before: dict[str, Any],
    poses_before: dict[str, tuple[np.ndarray, np.ndarray]],
) -> None:
    """Every input on ``server`` but ``sentinel`` (the honest edit's) holds its value from before the barrage
    (:func:`server_values`), and every gizmo its pose (:func:`scene_poses`)."""
    values_after = server_values(server)
    for uuid, value in values_before.items():
        if uuid != sentinel:
            assert same_value(values_after[uuid], value), (uuid, value, values_after[uuid])
    for name, (position, wxyz) in scene_poses(server).items():
        np.testing.assert_array_equal(position, poses_before[name][0], err_msg=name)
        np.testing.assert_allclose(wxyz, poses_before[name][1], atol=1e-12, err_msg=name)


def assert_each_refusal_logged_once(caplog: pytest.LogCaptureFixture, capfd: pytest.CaptureFixture[str]) -> list[str]:
    """One refusal line per kind, and no error or traceback logged or printed; returns the kinds logged."""
    kinds = [refused_kind(r) for r in refused_lines(caplog)]
    assert len(kinds) == len(set(kinds)), kinds
    assert not [r for r in caplog.records if r.exc_info or r.levelno >= logging.ERROR]
    out, err = capfd.readouterr()
    assert "Traceback" not in out + err
    return kinds


@pytest.fixture(params=list(SCENES))
def key(request: pytest.FixtureRequest) -> str:
    """Each scene's key in turn (a test may name fewer with its own ``parametrize``)."""
    return request.param


@contextlib.contextmanager
def two_viewers(server: viser.ViserServer, key: str) -> Iterator[tuple[SceneSwitcher, BrowserClient, BrowserClient]]:
    """Scene ``key`` on ``server`` and two browsers showing it, both registered and past the scene's first
    callbacks: the first sends, the second watches. The scene closes after the browsers."""
    switcher = SceneSwitcher(server, key)
    try:
        with BrowserClient(server.get_port()) as first, BrowserClient(server.get_port()) as second:
            label = SENTINELS[key][0]
            first.wait_for_gui(label)
            second.wait_for_gui(label)
            first.wait_for(lambda: len(server.get_clients()) == 2, what="both clients registered")
            time.sleep(0.3)  # the scene's first callbacks settle
            yield switcher, first, second
    finally:
        switcher.close()


def test_every_hostile_message_leaves_every_viewer_on_the_last_good_state(
    server: viser.ViserServer, key: str, caplog: pytest.LogCaptureFixture, capfd: pytest.CaptureFixture[str]
) -> None:
    label, good, field = SENTINELS[key]
    with two_viewers(server, key) as (switcher, attacker, observer):
        scene = switcher.scene
        with scene._lock:
            params_before = scene.params  # type: ignore[attr-defined]
        values_before = server_values(server)
        controls_before = {u: control_state(h) for u, h in gui_inputs(server.gui).items()}
        poses_before = scene_poses(server)
        observer_props = {
            u: dict(e["props"])
            for u, e in observer.gui.items()
            if e["type"] in INPUT_TYPES or e["type"] == "GuiButtonMessage"
        }
        # Every tab's camera, the attacker's too: its crafted cameras (a zero height) must not be applied.
        cameras_before = {cid: (c.camera.image_width, c.camera.image_height) for cid, c in server.get_clients().items()}
        caplog.clear()

        sent = hostile_barrage(attacker, server)
        assert_an_honest_edit_lands_after(sent, attacker, scene, label, field, good)
        # The scene is the one it was, with only the honest edit applied.
        assert switcher.scene is scene
        with scene._lock:
            assert scene.params == dataclass_replace(params_before, field, good)  # type: ignore[attr-defined]
        assert_untouched_but(attacker.uuid_of(label), server, values_before, poses_before)
        assert {u: control_state(h) for u, h in gui_inputs(server.gui).items()} == controls_before
        # Every viewer shows the server's values and poses; the observer saw no crafted props.
        for viewer in (attacker, observer):
            viewer.wait_for(lambda v=viewer: shows_server_values(v, server), what="values converge")
            viewer.wait_for(lambda v=viewer: shows_server_poses(v, server), what="poses converge")
        for uuid, props in observer_props.items():
            assert observer.gui[uuid]["props"] == props, uuid
        assert {
            cid: (c.camera.image_width, c.camera.image_height) for cid, c in server.get_clients().items()
        } == cameras_before

        # One line per kind of refusal, and no tracebacks anywhere.
        kinds = assert_each_refusal_logged_once(caplog, capfd)
        assert len(kinds) >= 10, kinds

        # A new browser connects and drives the scene.
        with BrowserClient(server.get_port()) as late:
            late.wait_for_gui(label)
            late.wait_for(lambda: same_value(late.value_of(label), good), what="the late tab's value")


def test_a_tab_that_sent_no_camera_changes_nothing_until_it_does(
    server: viser.ViserServer, key: str, caplog: pytest.LogCaptureFixture
) -> None:
    # The failing input (an outside tester, --shared): a client that never sent a camera set "Blend width k (m)" to
    # 0.9 and View to Mesh. viser stored and relayed the values but ran no callback (it registers a tab at its first
    # camera): every viewer and late joiner read k = 0.9 over the k = 0.25 mesh.
    label, good, field = SENTINELS[key]
    with (
        two_viewers(server, key) as (switcher, _first, observer),
        BrowserClient(server.get_port(), send_camera=False) as early,
    ):
        scene = switcher.scene
        early.wait_for_gui(label)
        with scene._lock:
            params_before = scene.params  # type: ignore[attr-defined]
        values_before, poses_before = server_values(server), scene_poses(server)
        caplog.clear()
        early.set_value(label, good)
        for name, gizmo in gizmos(server.scene).items():  # a drag too: viser would store and relay its pose
            early.drag_transform(name, [tuple(float(v) + 0.2 for v in gizmo.position)])
        early.send("GuiUpdateMessage", uuid=early.uuid_of(label), updates={"value": good})  # last, to wait for
        wait_until(
            lambda: any(refused_kind(r).startswith("input from a tab") for r in refused_lines(caplog)), "the refusal"
        )
        time.sleep(0.3)  # anything let through would have reached the server and the observer by now
        with scene._lock:
            assert scene.params == params_before  # type: ignore[attr-defined]
        assert_untouched_but("", server, values_before, poses_before)
        observer.wait_for(lambda: shows_server_values(observer, server), what="the observer shows the server's")
        assert not same_value(observer.value_of(label), good)
        # Once it sends a camera it is a tab like any other.
        early.send_camera()
        early.set_value(label, good)
        wait_until(lambda: same_value(getattr(scene.params, field), good), "the edit after its camera")
        observer.wait_for(lambda: same_value(observer.value_of(label), good), what="the observer shows it")


def dataclass_replace(params: Any, field: str, value: Any) -> Any:
    import dataclasses

    return dataclasses.replace(params, **{field: value})


def number_specs(attacker: BrowserClient, handles: Any) -> dict[str, Any]:
    """The recorded spec of every number control (slider or number box) the browser ``attacker`` shows, by uuid."""
    number_kinds = ("GuiSliderMessage", "GuiNumberMessage")
    return {uuid: control_spec(handles[uuid]) for uuid, e in attacker.gui.items() if e["type"] in number_kinds}


def test_huge_numbers_clamp_to_the_range_the_scene_declared(server: viser.ViserServer, key: str) -> None:
    """±1e308 are finite: every number control ends on the bound of its declared range, in every viewer."""
    with two_viewers(server, key) as (switcher, attacker, observer):
        handles = gui_inputs(server.gui)
        numbers = number_specs(attacker, handles)
        for huge in (1e308, -1e308):
            for uuid in numbers:
                attacker.send("GuiUpdateMessage", uuid=uuid, updates={"value": huge})
            for uuid, spec in numbers.items():
                bound = spec.hi if huge > 0 else spec.lo
                handle = handles[uuid]
                if bound is None:
                    continue
                attacker.wait_for(
                    lambda h=handle, b=bound: float(h.value) == b,  # type: ignore[attr-defined]
                    timeout_s=60,
                    what=f"{getattr(handle, 'label', uuid)} clamped to {bound}",
                )
        for viewer in (attacker, observer):
            viewer.wait_for(lambda v=viewer: shows_server_values(v, server), timeout_s=60, what="values converge")
        scene = switcher.scene
        with scene._lock:
            for name in scene.params.__dataclass_fields__:  # type: ignore[attr-defined]
                value = getattr(scene.params, name)  # type: ignore[attr-defined]
                if isinstance(value, float):
                    assert math.isfinite(value), name


# Kind: a finite number so small that a scene's arithmetic underflows on it. A headwind of 1e-320 m/s was in range
# and finite, so it came through; the wind arrow's direction divided by its norm, 0, and viser was sent NaN points.
@pytest.mark.parametrize("tiny", [1e-320, -1e-300, 1e-200, -5e-160])
def test_numbers_nearer_zero_than_their_range_can_tell_are_zero(
    server: viser.ViserServer, key: str, tiny: float, capfd: pytest.CaptureFixture[str]
) -> None:
    with two_viewers(server, key) as (switcher, attacker, _observer):
        handles = gui_inputs(server.gui)
        numbers = number_specs(attacker, handles)
        for uuid in numbers:
            attacker.send("GuiUpdateMessage", uuid=uuid, updates={"value": tiny})
        for uuid, spec in numbers.items():
            expected = min(max(0.0, spec.lo if spec.lo is not None else 0.0), spec.hi if spec.hi is not None else 0.0)
            handle = handles[uuid]
            attacker.wait_for(
                lambda h=handle, e=expected: float(h.value) == e,  # type: ignore[attr-defined]
                timeout_s=60,
                what=f"{getattr(handle, 'label', uuid)} at {expected}",
            )
        time.sleep(0.5)  # the scene's callbacks have drawn
        scene = switcher.scene
        with scene._lock:
            for name in scene.params.__dataclass_fields__:  # type: ignore[attr-defined]
                value = getattr(scene.params, name)  # type: ignore[attr-defined]
                assert not (isinstance(value, float) and 0.0 < abs(value) < 1e-9), (name, value)
    assert "RuntimeWarning" not in capfd.readouterr().err


@pytest.mark.parametrize(
    ("updates", "kind"),
    [
        ({"value": NAN}, "GUI value (a number that is not finite or not a number)"),
        ({"value": "fast"}, "GUI value (a number that is not finite or not a number)"),
        ({"props": {}}, "GUI update of a field other than value"),
        ({"update_cb": []}, "GUI update of a field other than value"),
        ({"removed": True}, "GUI update of a field other than value"),
    ],
)
def test_each_refusal_logs_one_line_and_a_flood_stays_one_line(
    server: viser.ViserServer,
    switcher: SceneSwitcher,
    updates: dict[str, Any],
    kind: str,
    caplog: pytest.LogCaptureFixture,
) -> None:
    with BrowserClient(server.get_port()) as client:
        uuid = client.wait_for_gui("Speed (km/h)")
        caplog.clear()
        client.send("GuiUpdateMessage", uuid=uuid, updates=updates)
        client.wait_for(lambda: len(refused_lines(caplog)) == 1, what="one refusal line")
        for _ in range(200):  # a flood of the same kind
            client.send("GuiUpdateMessage", uuid=uuid, updates=updates)
        client.set_value("Speed (km/h)", 41.0)
        client.wait_for(lambda: switcher.scene.params.speed_kmh == 41.0, what="the honest edit")  # type: ignore[attr-defined]
        lines = refused_lines(caplog)
        assert len(lines) == 1 and refused_kind(lines[0]) == kind
        assert lines[0].exc_info is None
        refusals.interval_s = 0.0  # once the window has passed, the next line counts what it held back
        try:
            client.send("GuiUpdateMessage", uuid=uuid, updates=updates)
            client.wait_for(lambda: len(refused_lines(caplog)) == 2, what="the next window's line")
        finally:
            refusals.interval_s = 10.0
        assert "200 more of this kind" in refused_lines(caplog)[1].getMessage()


def test_crafted_props_cannot_lift_a_slider_limit(server: viser.ViserServer, switcher: SceneSwitcher) -> None:
    """The reported case: ``{"props": {}}`` then "Riders" 40 broke the peloton until Reset."""
    with BrowserClient(server.get_port()) as client:
        uuid = client.wait_for_gui("Riders")
        client.send("GuiUpdateMessage", uuid=uuid, updates={"props": {}})
        top = MAX_GROUP  # the slider's declared max (121 riders: a bunch)
        client.set_value("Riders", 4 * top)
        # The gate clamps the value (the page shows the max at once); the scene's coalesced callback applies it after.
        client.wait_for(
            lambda: client.value_of("Riders") == top and switcher.scene.params.n_riders == top,  # type: ignore[attr-defined]
            what=f"Riders clamped to its max, {top}, on the page and in the scene",
        )


def test_a_string_false_does_not_tick_a_checkbox(server: viser.ViserServer, switcher: SceneSwitcher) -> None:
    with BrowserClient(server.get_port()) as client:
        client.wait_for_gui("Drafting")
        client.set_value("Drafting", False)
        client.wait_for(lambda: switcher.scene.params.drafting is False, what="unticked")  # type: ignore[attr-defined]
        client.set_value("Drafting", "false")  # bool("false") is True: viser alone would tick it
        client.wait_for(lambda: client.value_of("Drafting") is False, what="the server's False echoed")
        assert switcher.scene.params.drafting is False  # type: ignore[attr-defined]


def test_a_zero_height_camera_never_reaches_the_sdf_camera_handler(
    server: viser.ViserServer, switcher: SceneSwitcher, caplog: pytest.LogCaptureFixture
) -> None:
    switcher.show("sdf")
    with BrowserClient(server.get_port()) as client:
        client.wait_for_node("/sdf/mesh")
        client.send_camera(size=(0, 1280))
        client.send_camera(size=(600, 800))
        client.wait_for(
            lambda: any(c.camera.image_height == 600 for c in server.get_clients().values()),
            what="the good camera after the bad one",
        )
        time.sleep(0.2)
    assert not [r for r in caplog.records if r.levelno >= logging.ERROR or r.exc_info]
    assert any("camera" in refused_kind(r) for r in refused_lines(caplog))


def test_two_viewers_moving_one_slider_ms_apart_end_equal(server: viser.ViserServer, switcher: SceneSwitcher) -> None:
    """Two tabs move one slider 2-12 ms apart, 32 times: both end on the server's value every time.

    Without the write-back, a tab that only shows what the server said never hears of its own edit: viser sends
    an update to every tab but its sender, so it keeps the other tab's earlier value.
    """
    with BrowserClient(server.get_port()) as a, BrowserClient(server.get_port()) as b:
        uuid = a.wait_for_gui("Speed (km/h)")
        b.wait_for_gui("Speed (km/h)")
        handle = gui_inputs(server.gui)[uuid]
        differ = []
        for attempt in range(32):
            gap_s = (0.002, 0.005, 0.008, 0.012)[attempt % 4]
            sent = (5.0 + attempt, 40.0 + attempt)
            # Half the tries as a browser that shows its own edit at once, half as one whose shown value is only
            # what the server said (a tab that is slow to paint, or a script).
            send = BrowserClient.set_value if attempt % 8 < 4 else _send_only
            send(a, "Speed (km/h)", sent[0])
            time.sleep(gap_s)
            send(b, "Speed (km/h)", sent[1])
            try:
                for viewer in (a, b):
                    viewer.wait_for(
                        lambda v=viewer, sent=sent: (
                            handle.value in sent  # type: ignore[attr-defined]
                            and v.value_at(uuid) == handle.value  # type: ignore[attr-defined]
                        ),
                        "one of the two values, shown by both viewers",
                        timeout_s=10.0,
                    )
            except AssertionError:
                differ.append((gap_s, a.value_at(uuid), b.value_at(uuid), handle.value))  # type: ignore[attr-defined]
        assert differ == []


def _send_only(client: BrowserClient, label: str, value: Any) -> None:
    client.send("GuiUpdateMessage", uuid=client.uuid_of(label), updates={"value": value})


def test_a_partial_callback_that_raises_is_logged_by_its_function_name(
    server: viser.ViserServer, caplog: pytest.LogCaptureFixture
) -> None:
    """The arm's obstacle gizmos use functools.partial, which has no __name__: the error path itself raised."""

    class Partial(StubScene):
        key = "partial"

    scene = Partial(server)

    def drag(index: int) -> None:
        raise RuntimeError(f"obstacle {index} broke")

    try:
        handler = scene.callback(functools.partial(drag, 2))
        handler(None)  # must not raise
        messages = [r.getMessage() for r in caplog.records]
        assert any("drag" in m and "keeping the last good state" in m for m in messages), messages
    finally:
        scene.close()


# ------------------------------------------------------------------------------------------------ properties
JSONISH = st.recursive(
    st.none()
    | st.booleans()
    | st.integers(min_value=-(2**63), max_value=2**63)
    | st.floats(allow_nan=True, allow_infinity=True)
    | st.text(max_size=8),
    lambda children: st.lists(children, max_size=5) | st.dictionaries(st.text(max_size=4), children, max_size=3),
    max_leaves=8,
)


@given(value=JSONISH, lo=st.floats(-1e6, 0.0), width=st.floats(0.0, 1e6), integer=st.booleans())
@example(value=3.185620910834378e-306, lo=0.0, width=1.0, integer=False)  # the explore profile's: taken as 0
def test_a_number_control_accepts_only_finite_numbers_inside_its_range(
    value: Any, lo: float, width: float, integer: bool
) -> None:
    hi = lo + width
    spec = ControlSpec("number", lo=lo, hi=hi, integer=integer)
    accepted, cleaned, reason = clean_value(spec, value)
    is_number = isinstance(value, (int, float)) and not isinstance(value, bool)
    holds_an_integer = math.ceil(lo) <= math.floor(hi)
    assert accepted == (is_number and math.isfinite(float(value)) and (holds_an_integer or not integer))
    if accepted:
        assert isinstance(cleaned, int if integer else float) and not isinstance(cleaned, bool)
        assert lo <= cleaned <= hi
        if integer:  # viser's truncation, kept to the integers in range
            assert cleaned == min(max(int(value), math.ceil(lo)), math.floor(hi))
        elif lo <= float(value) <= hi:  # as sent, but for a number nearer zero than the range can tell, taken as 0
            assert cleaned == (0.0 if abs(float(value)) < NEGLIGIBLE * width else float(value))
    else:
        assert reason


@given(value=JSONISH)
def test_a_checkbox_accepts_only_real_bools(value: Any) -> None:
    accepted, cleaned, _ = clean_value(ControlSpec("bool"), value)
    assert accepted == (type(value) is bool)
    if accepted:
        assert cleaned is value


@given(value=JSONISH, options=st.lists(st.text(min_size=1, max_size=5), min_size=1, max_size=4))
def test_a_dropdown_accepts_only_its_own_options(value: Any, options: list[str]) -> None:
    accepted, cleaned, _ = clean_value(ControlSpec("choice", options=tuple(options)), value)
    assert accepted == (isinstance(value, str) and value in options)
    if accepted:
        assert cleaned == value


FLOATS = st.floats(allow_nan=True, allow_infinity=True) | st.sampled_from([0.0, -0.0, 5e-324, 1e308, -1e308])


@given(q=st.lists(FLOATS, min_size=0, max_size=6) | JSONISH)
def test_an_orientation_is_four_finite_numbers_normalised_or_refused(q: Any) -> None:
    unit = unit_quaternion(q)
    four_finite = (
        isinstance(q, (list, tuple))
        and len(q) == 4
        and all(isinstance(c, (int, float)) and not isinstance(c, bool) and math.isfinite(c) for c in q)
    )
    if unit is None:
        assert not four_finite or not any(q)
    else:
        assert four_finite
        assert math.isclose(math.hypot(*unit), 1.0, rel_tol=1e-12)
        # the same direction as the input, scaled by a power of 2 first (exact, also from subnormals)
        exponent = max(math.frexp(c)[1] for c in q if c)
        exact = [math.ldexp(c, -exponent) for c in q]
        norm = math.hypot(*exact)
        assert all(math.isclose(u, c / norm, rel_tol=1e-9, abs_tol=1e-12) for u, c in zip(unit, exact, strict=True))


@pytest.mark.parametrize("key", ["arm", "sdf"])  # the scenes with gizmos
def test_a_valid_but_not_unit_orientation_reaches_every_viewer_normalised(server: viser.ViserServer, key: str) -> None:
    """(2, 0, 0, 0) and the like are valid rotations, so they are not refused, but no viewer may be left holding
    them un-normalised: the sender's own copy included, every viewer ends on the server's unit quaternion."""
    with two_viewers(server, key) as (_switcher, sender, observer):
        assert gizmos(server.scene), "a scene with no gizmo has nothing to check here"
        for name, gizmo in gizmos(server.scene).items():
            position = tuple(float(v) for v in gizmo.position)
            for wxyz in ((2.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 3.0), (0.3, 0.0, 0.4, 0.0), (0.0, 1e-300, 0.0, 0.0)):
                sender.drag_transform(name, [position], wxyz=wxyz)
                for viewer in (sender, observer):
                    viewer.wait_for(
                        lambda v=viewer: shows_server_poses(v, server), what=f"{name} {wxyz}: the viewers converge"
                    )
                norm = float(np.linalg.norm(np.asarray(gizmo.wxyz, dtype=np.float64)))
                assert abs(norm - 1.0) < 1e-9, (name, wxyz, gizmo.wxyz)
                _, shown = sender.pose_of(name)
                assert abs(float(np.linalg.norm(shown)) - 1.0) < 1e-9, (name, wxyz, shown)


def test_orientations_on_the_issue_list() -> None:
    assert unit_quaternion((2.0, 0.0, 0.0, 0.0)) == (1.0, 0.0, 0.0, 0.0)
    assert unit_quaternion((0.0, 0.0, 0.0, 0.0)) is None
    assert unit_quaternion((NAN, 0.0, 0.0, 0.0)) is None
    assert unit_quaternion((1.0, 0.0, 0.0)) is None
    assert unit_quaternion((1e308, 1e308, 0.0, 0.0)) == pytest.approx((0.5**0.5, 0.5**0.5, 0.0, 0.0))
    # An outside tester's, refused as "no non-zero norm"; the SDF kernel takes it as the identity.
    assert unit_quaternion((1e-300, 0.0, 0.0, 0.0)) == (1.0, 0.0, 0.0, 0.0)
    assert unit_quaternion((5e-324, 5e-324, 0.0, 0.0)) == pytest.approx((0.5**0.5, 0.5**0.5, 0.0, 0.0), rel=1e-15)


class _TabView:
    """A tab's own GUI and scene APIs, in the shape the helpers above read from a server (``.gui``, ``.scene``)."""

    def __init__(self, switcher: SceneSwitcher) -> None:
        session: Any = switcher.server
        self.gui = session.gui.api
        self.scene = session.scene


def test_every_hostile_message_leaves_each_tab_on_its_last_good_state(
    server: viser.ViserServer, key: str, caplog: pytest.LogCaptureFixture, capfd: pytest.CaptureFixture[str]
) -> None:
    """The default mode, a scene per tab: the same barrage at a tab's own controls and gizmos (looked up through
    the tab's own registries), plus edits aimed at another tab's controls, which must not reach that tab."""
    from app import serve_scenes

    sessions = serve_scenes(server, key, shared=False)  # type: ignore[arg-type]  # a key of SCENES
    try:
        attacker, mine = connect_tab(server, sessions)
        other, theirs = connect_tab(server, sessions)
        with attacker, other:
            label, good, field = SENTINELS[key]
            attacker.wait_for_gui(label)
            other.wait_for_gui(label)
            time.sleep(0.3)  # the scenes' first callbacks settle
            scene, their_scene = mine.scene, theirs.scene
            assert scene is not their_scene
            with scene._lock:
                params_before = scene.params  # type: ignore[attr-defined]
            with their_scene._lock:
                their_params = their_scene.params  # type: ignore[attr-defined]
            view = _TabView(mine)  # the attacker tab's own GUI and scene
            values_before = server_values(view)  # type: ignore[arg-type]
            poses_before = scene_poses(view)  # type: ignore[arg-type]
            caplog.clear()

            if key in ("arm", "sdf"):  # the tab's own gizmos are found, so the barrage reaches them
                assert gizmos(view.scene)
            assert gui_inputs(view.gui)
            sent = hostile_barrage(attacker, view)  # type: ignore[arg-type]
            # Another tab's controls are unknown to this one: edits aimed at them reach nothing.
            for uuid, element in list(other.gui.items()):
                if element["type"] in INPUT_TYPES:
                    attacker.send("GuiUpdateMessage", uuid=uuid, updates={"value": element["value"]})
                    attacker.send("GuiUpdateMessage", uuid=uuid, updates={"value": 1e308})
                    sent += 2
            assert_an_honest_edit_lands_after(sent, attacker, scene, label, field, good)
            assert mine.scene is scene and theirs.scene is their_scene
            with scene._lock:
                assert scene.params == dataclass_replace(params_before, field, good)  # type: ignore[attr-defined]
            with their_scene._lock:
                assert their_scene.params == their_params  # type: ignore[attr-defined]
            assert_untouched_but(attacker.uuid_of(label), view, values_before, poses_before)  # type: ignore[arg-type]
            attacker.wait_for(
                lambda: shows_server_values(attacker, view),  # type: ignore[arg-type]
                what="the attacker's values converge",
            )
            attacker.wait_for(
                lambda: shows_server_poses(attacker, view),  # type: ignore[arg-type]
                what="the attacker's poses converge",
            )
            theirs_view = _TabView(theirs)
            other.wait_for(
                lambda: shows_server_values(other, theirs_view),  # type: ignore[arg-type]
                what="the other tab still shows its own scene's values",
            )
            assert_each_refusal_logged_once(caplog, capfd)
    finally:
        sessions.close()


@pytest.mark.parametrize(
    ("change", "field"),
    [
        ({"wxyz": (0.0, 0.0, 0.0, 0.0)}, "wxyz"),
        ({"position": (1e308, 0.0, 0.0)}, "position"),
        ({"position": (0.0, -1.1e6, 0.0)}, "position"),
        ({"look_at": (1e300, -1e300, 0.0)}, "look_at"),
        ({"up_direction": (0.0, 0.0, 1e7)}, "up_direction"),
        ({"up_direction": (0.0, 0.0, 0.0)}, "up_direction"),
        ({"fov": 0.0}, "fov"),
        ({"near": 0.0}, "near/far"),
        ({"far": 0.001}, "near/far"),
        ({"image_height": 0}, "image_height"),
        ({"image_width": 10**12}, "image_width"),
        # An outside tester: a camera at its own look-at point passed, and each scene's framing of it logged
        # viser's "look_at cannot equal position" with a traceback.
        ({"position": (1.0, 2.0, 3.0), "look_at": (1.0, 2.0, 3.0)}, "look_at"),
        ({"position": (0.0, 0.0, 0.0), "look_at": (-0.0, 0.0, 0.0)}, "look_at"),
    ],
)
def test_a_camera_out_of_bounds_is_refused_naming_its_field(change: dict[str, Any], field: str) -> None:
    """The refusal's log line names the field that was wrong (a fresh user found it quoting the valid image size
    for a camera refused for its position), and a finite camera 1e308 m out is refused: every distance the
    scenes take from it overflowed (numpy's RuntimeWarning in the log)."""
    from server.decode import MAX_CAMERA_M, camera_fields
    from server.viser_compat import messages

    def camera(fields: dict[str, Any]) -> Any:
        return messages.ViewerCameraMessage(**fields)

    good = bad_cameras()[0] | {"image_height": 720}
    fields, wrong = camera_fields(camera(good))
    assert fields is not None and wrong == ""
    assert camera_fields(camera(good | {"position": (MAX_CAMERA_M, 0.0, 1.0)}))[1] == ""
    assert camera_fields(camera(good | change)) == (None, field)
