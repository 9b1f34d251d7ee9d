"""Every field of every message a browser may send, bent to every wrong type: refused at the gate, one line a kind.

viser only warns about a field of the wrong type and passes the message on; a dict as a node name (unhashable)
then raised deep in its handlers, once per message, as an unretrieved asyncio task exception (a flood of them
flooded the log), and a frame nested thousands of lists deep closed the connection with a RecursionError.
"""

from __future__ import annotations

import dataclasses
import logging
import typing
from typing import Any

import pytest
import viser
from helpers.wsclient import BrowserClient

from scenes.freekick import FreeKickScene
from scenes.peloton import PelotonScene
from server.decode import ALLOWED_MESSAGES, decode_frame, field_hints, fits
from server.refusals import refusals
from server.switcher import SceneSwitcher
from server.viser_compat import messages

WRONG_VALUES: list[Any] = [{"a": 1}, [[1, 2], [3]], None, "text", 1e308, -7, True, b"\x00"]


def honest_fields(cls: type) -> dict[str, Any]:
    """A value of each field's declared type (zeros and empty text), for one message class."""

    def sample(hint: Any) -> Any:
        origin, args = typing.get_origin(hint), typing.get_args(hint)
        if hint is str:
            return "x"
        if hint is bytes:
            return b""
        if hint is int:
            return 1
        if hint is float:
            return 1.0
        if hint is bool:
            return False
        if origin is typing.Union:
            return sample(args[0])
        if origin is typing.Literal:
            return args[0]
        if origin is tuple:
            if len(args) == 2 and args[1] is Ellipsis:
                return []
            return [sample(arg) for arg in args]
        if origin is dict:
            return {"value": 1.0}
        return None

    return {name: sample(hint) for name, hint in field_hints(cls).items()}


def bent_messages() -> list[tuple[str, str, Any]]:
    """(message type, field, wrong value) for every field of every allowed message, where the value is wrong."""
    cases = []
    for cls in ALLOWED_MESSAGES:
        for name, hint in field_hints(cls).items():
            for value in WRONG_VALUES:
                if not fits(value, hint):
                    cases.append((cls.__name__, name, value))
    return cases


@pytest.mark.parametrize("kind", [cls.__name__ for cls in ALLOWED_MESSAGES])
def test_the_honest_sample_of_every_allowed_message_fits(kind: str) -> None:
    import msgspec

    cls = next(c for c in ALLOWED_MESSAGES if c.__name__ == kind)
    message = decode_frame(msgspec.msgpack.encode({"type": kind, **honest_fields(cls)}))
    assert isinstance(message, cls)


def test_every_wrong_typed_field_is_refused_at_decoding(caplog: pytest.LogCaptureFixture) -> None:
    import msgspec

    cases = bent_messages()
    assert len(cases) > 100  # every field of every message type, not a handful
    with caplog.at_level(logging.WARNING):
        for kind, field, value in cases:
            cls = next(c for c in ALLOWED_MESSAGES if c.__name__ == kind)
            fields = honest_fields(cls)
            fields[field] = value
            refusals.reset()
            message = decode_frame(msgspec.msgpack.encode({"type": kind, **fields}))
            # Refused, whatever viser's decoder would have made of it: it turned a camera's image_height True into
            # the int 1 (a 1280×1 camera), so a value is checked as the frame carried it, not as decoded.
            assert message is None, (kind, field, value, message)
    assert "Traceback" not in caplog.text


def test_dict_names_on_drags_and_clicks_are_refused_without_a_traceback(
    server: viser.ViserServer, switcher: SceneSwitcher, caplog: pytest.LogCaptureFixture
) -> None:
    switcher.show("arm")
    with caplog.at_level(logging.WARNING), BrowserClient(server.get_port()) as client:
        client.wait_for_gui("Scene")
        for _ in range(200):
            client.send("TransformControlsDragStartMessage", name={"a": 1}, owner="")
            client.send("TransformControlsDragEndMessage", name={"a": 1}, owner="")
            client.send(
                "SceneNodeClickMessage",
                name={"a": 1},
                instance_index=None,
                ray_origin=(0.0, 0.0, 0.0),
                ray_direction=(1.0, 0.0, 0.0),
                screen_pos=(0.5, 0.5),
                modifier=None,
                owner="",
            )
        # Still serving this browser: an honest value goes through and comes back.
        client.set_value("Scene", PelotonScene.title)
        client.wait_for(lambda: switcher.scene.key == "peloton", what="the honest switch")
    errors = [r for r in caplog.records if r.levelno >= logging.ERROR]
    assert errors == []
    gate_lines = [r for r in caplog.records if r.name == "server.refusals"]
    assert 1 <= len(gate_lines) <= 6  # one line per kind of refusal, not one per message


@pytest.mark.parametrize("depth", [2_000, 100_000])
def test_a_frame_nested_thousands_deep_is_one_refusal_and_the_connection_stays(
    server: viser.ViserServer, switcher: SceneSwitcher, depth: int, caplog: pytest.LogCaptureFixture
) -> None:
    with caplog.at_level(logging.WARNING), BrowserClient(server.get_port()) as client:
        client.wait_for_gui("Scene")
        client.send_raw(b"\x91" * depth + b"\xc0")
        client.set_value("Scene", FreeKickScene.title)
        client.wait_for(lambda: switcher.scene.key == "freekick", what="the connection still up")
    assert "refused malformed frame" in caplog.text
    assert "Traceback" not in caplog.text and "connection handler failed" not in caplog.text


def test_every_allowed_message_is_a_dataclass_the_check_can_read() -> None:
    for cls in ALLOWED_MESSAGES:
        assert dataclasses.is_dataclass(cls) and issubclass(cls, messages.Message)
        assert field_hints(cls), cls
