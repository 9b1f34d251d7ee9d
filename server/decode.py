"""Decoding one browser frame into a viser message, and the checks on its fields before anything cleans it.

:func:`decode_frame` takes only the message types a browser may send this app (:data:`ALLOWED_MESSAGES`), each field
of the declared type (:func:`fits`, checked on the frame's raw values and on the decoded message), and never lets a
frame that does not decode end the sender's connection. :func:`camera_fields` and :func:`click_problem` check the
fields of a camera and a click, which the gate then uses or refuses.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import typing
import warnings
from typing import Any

import msgspec

from server.clean import finite_number, finite_vector, unit_quaternion
from server.refusals import refusals
from server.viser_compat import messages

MAX_FRAME_BYTES = 32 * 1024 * 1024
"""Larger frames are refused (the largest honest one is a canvas render sent back for ``get_render``)."""
MAX_IMAGE_SIDE = 16384
"""Largest camera image side (pixels) a browser may report."""
MAX_CAMERA_M = 1e6
"""A camera's position, target and up vector stay within this many metres of the origin (every scene is a few
tens of metres across; viser's orbit controls cannot reach 1000 km)."""

ALLOWED_MESSAGES: tuple[type[messages.Message], ...] = (
    messages.GuiUpdateMessage,
    messages.ViewerCameraMessage,
    messages.TransformControlsUpdateMessage,
    messages.TransformControlsDragStartMessage,
    messages.TransformControlsDragEndMessage,
    messages.ScenePointerMessage,
    messages.SceneNodeClickMessage,
    messages.GetRenderResponseMessage,
    messages.FileTransferStartUpload,
    messages.FileTransferPart,
)
"""The only message types a browser may send this app; any other (share-URL requests...) is refused. Uploads are
taken only for an upload button the sender can see, within :data:`MAX_UPLOAD_BYTES`."""
_ALLOWED_BY_NAME = {cls.__name__: cls for cls in ALLOWED_MESSAGES}


def camera_fields(message: messages.ViewerCameraMessage) -> tuple[dict[str, Any] | None, str]:
    """(the camera's fields, cleaned, or None; the first field that is not a camera a browser can have, or "")."""
    wxyz = unit_quaternion(message.wxyz)
    points = {name: finite_vector(getattr(message, name), 3) for name in ("position", "look_at", "up_direction")}
    fov, near, far = (finite_number(v) for v in (message.fov, message.near, message.far))
    sizes = {"image_height": message.image_height, "image_width": message.image_width}
    if wxyz is None:
        return None, "wxyz"
    for name, point in points.items():
        # Finite is not enough: a camera 1e308 m out overflows every distance the scenes take from it.
        if point is None or max(abs(v) for v in point) > MAX_CAMERA_M:
            return None, name
    if fov is None or not (0.0 < fov < math.pi):
        return None, "fov"
    if near is None or far is None or not (0.0 < near < far):
        return None, "near/far"
    for name, side in sizes.items():
        if not (type(side) is int and 1 <= side <= MAX_IMAGE_SIDE):
            return None, name
    up = points["up_direction"]
    assert up is not None
    if math.hypot(*up) == 0.0:
        return None, "up_direction"
    if points["look_at"] == points["position"]:  # no view direction: viser refuses to frame such a camera
        return None, "look_at"
    return {"wxyz": wxyz, **points, "fov": fov, "near": near, "far": far, **sizes}, ""


def _ray(origin: object, direction: object) -> bool:
    d = finite_vector(direction, 3)
    return finite_vector(origin, 3) is not None and d is not None and math.hypot(*d) > 0.0


def click_problem(message: messages.ScenePointerMessage | messages.SceneNodeClickMessage) -> str:
    """Why a click cannot be used ("" when it can): rays are 3 finite numbers, screen points 2."""
    if isinstance(message, messages.ScenePointerMessage):
        if message.event_type not in ("click", "rect-select"):
            return "an unknown pointer event"
        if (message.ray_origin is None) != (message.ray_direction is None):
            return "half a ray"
        if message.ray_origin is not None and not _ray(message.ray_origin, message.ray_direction):
            return "a ray that is not finite"
        points = message.screen_pos
        if not isinstance(points, (list, tuple)) or not 1 <= len(points) <= 2:
            return "screen points that are not one or two"
        if any(finite_vector(point, 2) is None for point in points):
            return "a screen point that is not two finite numbers"
        return ""
    index = message.instance_index
    if index is not None and (type(index) is not int or index < 0):
        return "an instance index that is not a count"
    if not _ray(message.ray_origin, message.ray_direction):
        return "a ray that is not finite"
    if finite_vector(message.screen_pos, 2) is None:
        return "a screen point that is not two finite numbers"
    return ""


# ------------------------------------------------------------------------------------------------ frames
def decode_frame(raw: object) -> messages.Message | None:
    """The message in one browser frame, or None (logged) when it is not one this app accepts."""
    if not isinstance(raw, bytes):
        refusals.refuse("text frame", "browsers send binary frames only")
        return None
    if len(raw) > MAX_FRAME_BYTES:
        refusals.refuse("oversized frame", f"{len(raw)} bytes")
        return None
    try:
        mapping = msgspec.msgpack.decode(raw)
    except Exception as error:  # DecodeError, or RecursionError for a frame nested thousands deep
        refusals.refuse("malformed frame", f"{type(error).__name__}: {str(error)[:120]}")
        return None
    kind = mapping.get("type") if isinstance(mapping, dict) else None
    if not isinstance(kind, str) or kind not in _ALLOWED_BY_NAME:
        refusals.refuse("message type", f"{str(kind)[:80]!r} is not one a browser may send")
        return None
    try:
        with warnings.catch_warnings():
            # viser warns (with the value in the text) when a field has the wrong type; the gate checks every
            # field itself, so these warnings would only repeat what it refuses.
            warnings.simplefilter("ignore")
            message = messages.Message.deserialize(raw)
    except Exception as error:  # the frame's fields do not fit the message: refused, the connection stays up
        refusals.refuse(f"malformed {kind}", f"{type(error).__name__}: {error}")
        return None
    if not isinstance(message, _ALLOWED_BY_NAME[kind]):
        return None
    # Checked on the frame's own values as well as on the decoded message: viser's decoding turns some values
    # into the declared type first (a camera's image_height True arrived as the int 1, a 1280×1 camera).
    wrong = _misfit_raw_field(mapping, type(message)) or _misfit_field(message)
    if wrong:
        refusals.refuse(f"malformed {kind}", f"field {wrong!r} does not have its declared type")
        return None
    return message


def _misfit_raw_field(mapping: dict[str, Any], kind: type) -> str:
    """The first field of a decoded frame ``mapping`` whose raw value does not have the type message class
    ``kind`` declares for it, or "" (fields the frame does not carry are left to the message's own decoding)."""
    for name, hint in field_hints(kind).items():
        if name in mapping and not fits(mapping[name], hint):
            return name
    return ""


def fits(value: object, hint: Any) -> bool:
    """Whether ``value`` has the type ``hint`` that viser declares for a message field (the shapes browsers send)."""
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if hint is typing.Any:
        return True
    if hint is float:
        return isinstance(value, (int, float)) and not isinstance(value, bool)
    if hint in (int, str, bytes, bool):
        return type(value) is hint
    if origin is typing.Union:
        return any(fits(value, arg) for arg in args)
    if origin is typing.Literal:
        return any(value == arg and type(value) is type(arg) for arg in args)
    if origin is tuple:
        if not isinstance(value, (tuple, list)):
            return False
        if len(args) == 2 and args[1] is Ellipsis:
            return all(fits(item, args[0]) for item in value)
        return len(value) == len(args) and all(fits(v, a) for v, a in zip(value, args, strict=True))
    if origin is dict:
        return isinstance(value, dict)
    return True  # a kind browsers do not send here; the message's own cleaner checks it


def _misfit_field(message: messages.Message) -> str:
    """The first field of ``message`` whose value does not have its declared type, or "" (every field fits).

    viser only warns about such fields and passes them on, where a dict as a node name (unhashable) raises deep in
    its handlers: every field of every message is checked here, once, whatever its kind.
    """
    hints = field_hints(type(message))
    for field in dataclasses.fields(message):  # type: ignore[arg-type]  # viser's messages are dataclasses
        hint = hints.get(field.name)
        if hint is not None and not fits(getattr(message, field.name), hint):
            return field.name
    return ""


@functools.cache
def field_hints(cls: type) -> dict[str, Any]:
    hints = typing.get_type_hints(cls)
    return {
        name: hint
        for name, hint in hints.items()
        if typing.get_origin(hint) is not typing.ClassVar and name != "excluded_self_client"
    }
