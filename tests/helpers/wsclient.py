"""A websocket client that acts as a browser toward a viser 1.1.1 server.

It speaks the wire protocol the real client speaks (see ``shared/notes/viser.md``), keeps a mirror of the GUI and
scene the server has sent, and sends the same messages a browser sends when a person moves a slider, clicks a button
or drags a gizmo. Because it is not a browser it can also send what no honest browser would (NaN, out-of-range
numbers, wrong types, unknown uuids): the scenes must survive those.

    with BrowserClient(port) as client:
        client.set_value("Speed (km/h)", 45.0)
        client.wait_for(lambda: ..., "what the test waits for")

Server → client frames: ``[u64 msgpack length][u64 zstd length] zstd(msgpack {messages, timestampSec,
binaryBufferLengths}) [padding to 8] [raw buffers, each 8-aligned]``; numpy arrays arrive as
``{"__binary_index": i, "dtype": ...}`` placeholders. Client → server: ``msgpack({"type": ClassName, **fields})``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from typing import Any

import msgspec
import numpy as np
import zstandard
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import ClientConnection, connect
from websockets.typing import Subprotocol

from helpers.waiting import wait_until

VISER_SUBPROTOCOL = "viser-v1.1.1"


def decode_frame(frame: bytes) -> list[dict[str, Any]]:
    """Decode one server → client websocket frame into its list of message dicts (arrays as numpy)."""
    inner_size = int.from_bytes(frame[0:8], "little")
    compressed_size = int.from_bytes(frame[8:16], "little")
    inner = zstandard.ZstdDecompressor().decompress(frame[16 : 16 + compressed_size], max_output_size=inner_size)
    payload = msgspec.msgpack.decode(inner)
    buffers: list[bytes] = []
    offset = 16 + compressed_size
    for length in payload.get("binaryBufferLengths", ()):
        offset += (8 - offset % 8) % 8
        buffers.append(frame[offset : offset + length])
        offset += length
    return [_restore_arrays(message, buffers) for message in payload["messages"]]


def _restore_arrays(value: Any, buffers: list[bytes]) -> Any:
    if isinstance(value, dict):
        if "__binary_index" in value and "dtype" in value:
            return np.frombuffer(buffers[value["__binary_index"]], dtype=np.dtype(value["dtype"]))
        return {key: _restore_arrays(item, buffers) for key, item in value.items()}
    if isinstance(value, list):
        return [_restore_arrays(item, buffers) for item in value]
    return value


class BrowserClient:
    """A connected fake browser: a mirror of the GUI and scene, and the messages a person's actions send."""

    def __init__(self, port: int, host: str = "127.0.0.1", *, send_camera: bool = True) -> None:
        self._ws: ClientConnection = connect(
            f"ws://{host}:{port}", subprotocols=[Subprotocol(VISER_SUBPROTOCOL)], max_size=None
        )
        self._lock = threading.RLock()
        self.gui: dict[str, dict[str, Any]] = {}
        """uuid → {"type", "value", "props", "container_uuid"} for every live GUI element."""
        self.nodes: dict[str, dict[str, Any]] = {}
        """node name → its creation message, with later updates applied."""
        self.received: list[tuple[float, dict[str, Any]]] = []
        """Every message received, with the monotonic time it arrived."""
        self.closed_by_server = False
        self._reader = threading.Thread(target=self._read_forever, name="ws-client", daemon=True)
        self._reader.start()
        if send_camera:
            self.send_camera()

    # ------------------------------------------------------------------------------------------ plumbing
    def __enter__(self) -> BrowserClient:
        return self

    def __exit__(self, *_exc: object) -> None:
        self.close()

    def close(self) -> None:
        self._ws.close()
        self._reader.join(timeout=2.0)

    def send(self, type_name: str, **fields: Any) -> None:
        """Send one client → server message, exactly as the browser encodes it."""
        self._ws.send(msgspec.msgpack.encode({"type": type_name, **fields}))

    def send_raw(self, data: bytes) -> None:
        self._ws.send(data)

    def _read_forever(self) -> None:
        try:
            for frame in self._ws:
                if not isinstance(frame, bytes):
                    continue
                messages = decode_frame(frame)
                now = time.monotonic()
                with self._lock:
                    for message in messages:
                        self.received.append((now, message))
                        self._apply(message)
        except ConnectionClosed:
            pass
        finally:
            with self._lock:
                self.closed_by_server = True

    def _apply(self, message: dict[str, Any]) -> None:
        kind = message.get("type", "")
        if kind == "GuiRemoveMessage":
            self.gui.pop(message["uuid"], None)
        elif kind == "GuiUpdateMessage":
            element = self.gui.get(message["uuid"])
            if element is not None:
                for key, value in message["updates"].items():
                    if key == "value":
                        element["value"] = value
                    else:
                        element["props"][key] = value
        elif kind.startswith("Gui") and "uuid" in message and "props" in message:
            self.gui[message["uuid"]] = {
                "type": kind,
                "value": message.get("value"),
                "props": dict(message["props"]),
                "container_uuid": message.get("container_uuid"),
            }
        elif kind == "RemoveSceneNodeMessage":
            self.nodes.pop(message["name"], None)
        elif kind == "SceneNodeUpdateMessage":
            node = self.nodes.get(message["name"])
            if node is not None:
                node.setdefault("props", {}).update(message["updates"])
        elif kind == "SetPositionMessage":
            if message["name"] in self.nodes:
                self.nodes[message["name"]]["position"] = message["position"]
        elif kind == "SetOrientationMessage":
            if message["name"] in self.nodes:
                self.nodes[message["name"]]["wxyz"] = message["wxyz"]
        elif "name" in message and kind.endswith("Message") and "props" in message:
            self.nodes[message["name"]] = dict(message)

    # ------------------------------------------------------------------------------------------ waiting
    def wait_for(self, predicate: Callable[[], object], what: str, timeout_s: float = 10.0) -> None:
        """:func:`helpers.waiting.wait_until` (same arguments), with ``predicate()`` read under the lock the reader
        thread updates this mirror under: it sees each message whole, and may walk ``gui`` or ``nodes``."""

        def holds() -> object:
            with self._lock:
                return predicate()

        wait_until(holds, what, timeout_s)

    def wait_for_gui(self, label: str, timeout_s: float = 10.0) -> str:
        self.wait_for(lambda: self._find(label) is not None, f"GUI element {label!r}", timeout_s)
        uuid = self._find(label)
        assert uuid is not None
        return uuid

    def wait_for_node(self, name: str, timeout_s: float = 10.0) -> dict[str, Any]:
        self.wait_for(lambda: name in self.nodes, f"scene node {name!r}", timeout_s)
        return self.nodes[name]

    # ------------------------------------------------------------------------------------------ GUI
    def _find(self, label: str) -> str | None:
        """The uuid of the element labelled ``label``; a control before a folder of the same name."""
        found = None
        for uuid, element in self.gui.items():
            if element["props"].get("label") == label:
                if element["type"] != "GuiFolderMessage":
                    return uuid
                found = found or uuid
        return found

    def uuid_of(self, label: str) -> str:
        with self._lock:
            uuid = self._find(label)
        if uuid is None:
            raise KeyError(f"no GUI element labelled {label!r}; have {sorted(self.labels())}")
        return uuid

    def take_received(self) -> list[tuple[float, dict[str, Any]]]:
        """Every message received since the last call, oldest first, handed over and forgotten here (the mirrored
        GUI and nodes stay): a long run keeps only what it needs instead of every mesh and image."""
        with self._lock:
            received, self.received = self.received, []
        return received

    def value_at(self, uuid: str) -> Any:
        """The value this browser shows for the GUI element ``uuid``."""
        with self._lock:
            return self.gui[uuid]["value"]

    def pose_of(self, name: str) -> tuple[tuple[float, ...], tuple[float, ...]]:
        """(position, wxyz) this browser shows for the node ``name`` (viser's defaults where never sent)."""
        with self._lock:
            node = self.nodes[name]
            position = node.get("position", (0.0, 0.0, 0.0))
            wxyz = node.get("wxyz", (1.0, 0.0, 0.0, 0.0))
        return tuple(float(v) for v in position), tuple(float(v) for v in wxyz)

    def visible_instances(self, name: str) -> np.ndarray | None:
        """(N, 3) positions of batched mesh ``name``'s visible instances (scale > 0) as this browser last received
        them; None before the node and both arrays arrived."""
        with self._lock:
            node = self.nodes.get(name)
            props = {} if node is None else node.get("props", {})
            positions, scales = props.get("batched_positions"), props.get("batched_scales")
        if positions is None or scales is None:
            return None
        positions = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
        scales = np.asarray(scales, dtype=np.float64).reshape(-1, 3)
        return positions[scales[:, 0] > 0]

    def labels(self) -> Iterable[str]:
        with self._lock:
            return [str(element["props"].get("label")) for element in self.gui.values()]

    def value_of(self, label: str) -> Any:
        with self._lock:
            uuid = self._find(label)
            if uuid is None:
                raise KeyError(label)
            return self.gui[uuid]["value"]

    def element(self, label: str) -> dict[str, Any]:
        with self._lock:
            uuid = self._find(label)
            if uuid is None:
                raise KeyError(label)
            return self.gui[uuid]

    def set_value(self, label: str, value: Any) -> None:
        """What a browser sends when a person moves the slider (or edits the input) labelled ``label``.

        A dropdown takes only one of its options, as in a browser: a label that is not one (the server refuses it
        and keeps its value) raises ``AssertionError`` here, so a test cannot silently test the default instead.
        A crafted value goes through :meth:`send_value`."""
        uuid = self.uuid_of(label)
        with self._lock:
            options = self.gui[uuid]["props"].get("options")
        if options is not None and value not in options:
            raise AssertionError(f"{value!r} is not one of {label!r}'s options {list(options)}")
        self.send_value(label, value)

    def send_value(self, label: str, value: Any) -> None:
        """What a crafted client sends as the value of the control labelled ``label``: anything, unchecked."""
        uuid = self.uuid_of(label)
        with self._lock:  # the browser shows its own edit at once, as the real one does
            self.gui[uuid]["value"] = value
        self.send("GuiUpdateMessage", uuid=uuid, updates={"value": value})

    def notices(self) -> list[dict[str, Any]]:
        """The props (title, body, colour...) of every notification the server has shown this client, in order."""
        return [
            message["props"] for _at, message in list(self.received) if message.get("type") == "NotificationShowMessage"
        ]

    def set_value_answered(self, label: str, value: Any, settle_s: float = 0.15) -> None:
        """Wait for the control labelled ``label``, send ``value`` to it (crafted: anything, as :meth:`send_value`),
        wait for the server's answer, then ``settle_s`` more for the callback (it runs on viser's thread pool) to
        finish."""
        self.wait_for_gui(label)
        stamp = len(self.received)
        self.send_value(label, value)
        self.wait_for(lambda: len(self.received) > stamp, what="the server to answer")
        time.sleep(settle_s)

    def click(self, label: str) -> None:
        """What a browser sends when a person clicks the button labelled ``label``."""
        self.send("GuiUpdateMessage", uuid=self.uuid_of(label), updates={"value": True})

    # ------------------------------------------------------------------------------------------ scene
    def send_camera(
        self,
        position: tuple[float, float, float] = (3.0, -6.0, 3.0),
        look_at: tuple[float, float, float] = (0.0, 0.0, 0.0),
        size: tuple[int, int] = (720, 1280),
    ) -> None:
        """The camera message a browser sends first; only after it does the server run callbacks for us."""
        self.send(
            "ViewerCameraMessage",
            wxyz=(1.0, 0.0, 0.0, 0.0),
            position=position,
            fov=1.0,
            near=0.01,
            far=1000.0,
            image_height=size[0],
            image_width=size[1],
            look_at=look_at,
            up_direction=(0.0, 0.0, 1.0),
        )

    def drag_transform(
        self, name: str, positions: Iterable[Any], wxyz: Any = (1.0, 0.0, 0.0, 0.0), period_s: float = 0.0
    ) -> None:
        """Drag the transform-controls gizmo ``name`` through ``positions`` (parent frame), as a mouse drag does."""
        owner = str(self.wait_for_node(name).get("owner", "") or "")
        self.send("TransformControlsDragStartMessage", name=name, owner=owner)
        for position in positions:
            with self._lock:  # the browser shows the gizmo where the mouse put it, as the real one does
                self.nodes[name]["position"] = position
                self.nodes[name]["wxyz"] = wxyz
            self.send("TransformControlsUpdateMessage", name=name, wxyz=wxyz, position=position, owner=owner)
            if period_s:
                time.sleep(period_s)
        self.send("TransformControlsDragEndMessage", name=name, owner=owner)

    def drag_transform_step(self, name: str, position: Any, owner: str, wxyz: Any = (1.0, 0.0, 0.0, 0.0)) -> None:
        """One move of a drag already started (``TransformControlsDragStartMessage``), as a mouse move sends."""
        with self._lock:
            self.nodes[name]["position"] = position
            self.nodes[name]["wxyz"] = wxyz
        self.send("TransformControlsUpdateMessage", name=name, wxyz=wxyz, position=position, owner=owner)

    def click_scene(self, ray_origin: tuple[float, float, float], ray_direction: tuple[float, float, float]) -> None:
        """A click in the 3D view along the given world ray."""
        self.send(
            "ScenePointerMessage",
            event_type="click",
            ray_origin=ray_origin,
            ray_direction=ray_direction,
            screen_pos=((0.5, 0.5),),
            modifier=None,
        )


def shows_number(shown: object, expected: object) -> bool:
    """Whether a control's value as a browser shows it is the finite number ``expected`` (an int or a float)."""
    assert isinstance(expected, (int, float))
    return isinstance(shown, (int, float)) and math.isfinite(shown) and float(shown) == float(expected)


@dataclasses.dataclass(frozen=True)
class Crafted:
    """A crafted value sent to the control labelled ``label``, the parameter ``field`` it sets, and what that field
    must hold after (the value cleaned)."""

    label: str
    value: object
    field: str
    expected: object

    def __str__(self) -> str:
        return f"{self.label}-{self.value}-{self.field}-{self.expected}"


@contextlib.contextmanager
def crafted_sent(port: int, crafted: Crafted, caplog: Any) -> Iterator[BrowserClient]:
    """A browser on ``port`` that has sent ``crafted``'s value and had the server answer; on leaving, asserts that
    no callback logged an error (``caplog``: pytest's log capture)."""
    with BrowserClient(port) as client:
        client.set_value_answered(crafted.label, crafted.value)
        yield client
    assert not [r for r in caplog.records if r.levelname == "ERROR"], "a callback failed"


def connect_tab(server: Any, sessions: Any) -> tuple[BrowserClient, Any]:
    """A new tab on ``server`` (per-tab mode), and the scene switcher ``sessions`` built for it."""
    known = set(server.get_clients())
    client = BrowserClient(server.get_port())
    client.wait_for(lambda: bool(set(server.get_clients()) - known), what="the client registered")
    (client_id,) = set(server.get_clients()) - known
    client.wait_for(lambda: sessions.switcher(client_id) is not None, what="its session built")
    switcher = sessions.switcher(client_id)
    assert switcher is not None
    # Built on the server is not yet shown in the tab: its controls are still on their way. Wait until the tab has
    # them, as a person cannot pick a scene before the dropdown shows.
    client.wait_for_gui(switcher.dropdown.label)
    client.wait_for_gui(switcher.reset_button.label)
    return client, switcher
