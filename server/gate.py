"""One gate for every message a browser sends, and every access to viser 1.1.1's private state the app makes.

viser 1.1.1 applies whatever a client's message names: a ``GuiUpdateMessage`` may set any attribute of a GUI handle
(``props``, ``update_cb``, ``removed``), a gizmo update carries arrays of any length, a camera any image size, and a
frame that does not decode ends the sender's connection with a traceback. Only three things may come from a browser:

- a control's **value**: of the control's own kind (a checkbox takes only ``True``/``False``, a slider only a finite
  number, clamped to the range the scene declared, a dropdown only one of its options);
- a gizmo's **pose**: 3 finite numbers for the position and 4 finite numbers for the orientation, normalised; a
  zero or non-finite quaternion, or a wrong length, keeps the last good pose;
- a **camera**: finite numbers, a unit quaternion, positive image sizes; otherwise the client's last good camera.

Everything else is refused, and each kind of refusal is logged once (one line, no traceback) per
:attr:`Gate.log_interval_s`, with a count of the ones left unlogged. After each accepted value the server's value is
sent back to every viewer, so two browsers moving one slider a few milliseconds apart end on the same value.

A control's limits and options are its :class:`ControlSpec`, recorded by :func:`record_spec` when the scene creates
it (before any browser can touch it) and kept beside the handle; they are never read back from the handle's props,
which a browser could once change.

Two budgets keep one tab from starving the others. Costly inputs (a control the scene marked with
:func:`mark_costly`: a scene switch, a Reset, a remesh) go through a per-tab token bucket (:class:`CostlyBudget`):
beyond it only the latest value of each such control is held back and delivered later, never dropped. Uploads in
flight are bounded per tab and across all tabs; a refused upload is told to its tab as a notification.

viser is pinned ``==1.1.1`` because this module reaches into its internals: the websocket server's dispatch, the
per-connection dispatch, the GUI and gizmo registries, and the frame decoder.
"""

from __future__ import annotations

import asyncio
import dataclasses
import functools
import logging
import math
import threading
import time
import typing
import warnings
import weakref
from collections.abc import Callable, Coroutine
from typing import Any, Literal

import msgspec
import viser
from viser import _messages
from viser.infra import _infra

logger = logging.getLogger(__name__)

ControlKind = Literal["number", "choice", "bool", "button", "rgb", "text", "vector", "display"]

MAX_FRAME_BYTES = 32 * 1024 * 1024
"""Larger frames are refused (the largest honest one is a canvas render sent back for ``get_render``)."""
MAX_IMAGE_SIDE = 16384
"""Largest camera image side (pixels) a browser may report."""
MAX_CAMERA_M = 1e6
"""A camera's position, target and up vector stay within this many metres of the origin (every scene is a few
tens of metres across; viser's orbit controls cannot reach 1000 km)."""
MAX_TEXT_CHARS = 10_000
MIB = 1024 * 1024
MAX_UPLOAD_BYTES = 24 * MIB
"""Largest file a browser may upload (a scene may refuse smaller ones with its own message, e.g. GPX over 20 MB)."""
MAX_UPLOADS_IN_FLIGHT = 4
"""Uploads one browser may have started and not finished; viser keeps each one's parts in memory until then."""
MAX_UPLOADS_IN_FLIGHT_TOTAL = 8
"""Uploads every browser together may have in flight on one server."""
MAX_UPLOAD_BYTES_IN_FLIGHT_TOTAL = 64 * MIB
"""Bytes the uploads in flight on one server may announce together (each is held in memory until it completes)."""
MAX_UPLOAD_BYTES_IN_FLIGHT_PER_TAB = MAX_UPLOAD_BYTES
"""Bytes one tab's uploads in flight may announce together: one tab holds at most this share of the server-wide
budget, however slowly it sends."""
MIN_PART_BYTES = 4096
"""Smallest average part an upload may announce (viser's browser sends 512 KiB parts): viser keeps ~100 bytes of
bookkeeping a part, so an upload of 1-byte parts would hold ~100× the bytes the budget counts."""
UPLOAD_DEADLINE_S = 120.0
"""An upload not finished this long after its start is dropped (24 MiB needs 200 KiB/s): a tab trickling one byte
every few seconds would otherwise hold its share of the budget for good."""
UPLOAD_STALL_S = 30.0
"""An upload that has received no part for this long is dropped (its parts freed), so it stops holding the
server-wide budget."""
COSTLY_BURST = 3
"""Costly inputs (a scene rebuild, a long job: see :attr:`ControlSpec.costly`) one tab may send at once."""
COSTLY_RATE_HZ = 1.0
"""Costly inputs per second one tab is given beyond its burst (a token bucket); the rest wait, coalesced."""
MAX_NAME_CHARS = 255

ALLOWED_MESSAGES: tuple[type[_messages.Message], ...] = (
    _messages.GuiUpdateMessage,
    _messages.ViewerCameraMessage,
    _messages.TransformControlsUpdateMessage,
    _messages.TransformControlsDragStartMessage,
    _messages.TransformControlsDragEndMessage,
    _messages.ScenePointerMessage,
    _messages.SceneNodeClickMessage,
    _messages.GetRenderResponseMessage,
    _messages.FileTransferStartUpload,
    _messages.FileTransferPart,
)
"""The only message types a browser may send this app; any other (share-URL requests...) is refused. Uploads are
taken only for an upload button the sender can see, within :data:`MAX_UPLOAD_BYTES`."""
_ALLOWED_BY_NAME = {cls.__name__: cls for cls in ALLOWED_MESSAGES}


@dataclasses.dataclass(frozen=True)
class ControlSpec:
    """What a scene declared for one control, recorded when it was created."""

    kind: ControlKind
    """How a browser's value is checked."""
    lo: float | None = None
    """Smallest value (numbers), or None."""
    hi: float | None = None
    """Largest value (numbers), or None."""
    integer: bool = False
    """Whether the number is an integer (viser casts to the initial value's type)."""
    options: tuple[str, ...] = ()
    """The dropdown's options."""
    length: int = 0
    """Number of components (RGB, vectors)."""
    costly: bool = False
    """Whether a change rebuilds a scene or starts a long job: such inputs share a per-tab budget at the gate, and a
    burst beyond it is coalesced (see :func:`mark_costly`)."""


_SPEC_ATTRIBUTE = "_scenes_control_spec"


def spec_from_handle(handle: object) -> ControlSpec:
    """The spec of ``handle`` as it stands now: call it only when the scene has just created the handle."""
    if isinstance(handle, viser.GuiCheckboxHandle):
        return ControlSpec("bool")
    if isinstance(handle, viser.GuiButtonHandle):
        return ControlSpec("button")
    if isinstance(handle, (viser.GuiSliderHandle, viser.GuiNumberHandle)):
        lo, hi = handle.min, handle.max
        return ControlSpec(
            "number",
            lo=None if lo is None else float(lo),
            hi=None if hi is None else float(hi),
            integer=isinstance(handle.value, int),
        )
    if isinstance(handle, viser.GuiDropdownHandle):
        return ControlSpec("choice", options=tuple(str(option) for option in handle.options))
    if isinstance(handle, viser.GuiRgbHandle):
        return ControlSpec("rgb", lo=0.0, hi=255.0, integer=True, length=3)
    if isinstance(handle, viser.GuiTextHandle):
        return ControlSpec("text")
    if isinstance(handle, (viser.GuiVector2Handle, viser.GuiVector3Handle)):
        return ControlSpec("vector", length=len(handle.value))
    return ControlSpec(
        "display"
    )  # progress bars, uploads, button groups...: nothing a browser may set


def record_spec(handle: object) -> ControlSpec:
    """Record ``handle``'s spec beside it (call right after creating it); returns the spec."""
    spec = spec_from_handle(handle)
    setattr(_state(handle), _SPEC_ATTRIBUTE, spec)
    return spec


H = typing.TypeVar("H")


def mark_costly(handle: H) -> H:
    """Declare ``handle`` (a control just created) costly: each change rebuilds a scene or starts a long job.

    The gate lets a tab send :data:`COSTLY_BURST` costly inputs at once, then :data:`COSTLY_RATE_HZ` a second;
    beyond that it keeps only the latest value of each costly control (a burst of clicks is one click, the last pick
    or resolution wins) and delivers it when the tab's budget allows, so every viewer still ends on the value the
    browser sent last. Returns ``handle``.
    """
    spec = dataclasses.replace(control_spec(handle), costly=True)
    setattr(_state(handle), _SPEC_ATTRIBUTE, spec)
    return handle


def control_spec(handle: object) -> ControlSpec:
    """The spec recorded for ``handle``; a control made without the facade is recorded now, on first use."""
    spec = getattr(_state(handle), _SPEC_ATTRIBUTE, None)
    return spec if isinstance(spec, ControlSpec) else record_spec(handle)


def _state(handle: object) -> Any:
    return handle._impl  # type: ignore[attr-defined]


def gui_uuid(handle: object) -> str:
    """The uuid a browser uses to address ``handle``."""
    return str(_state(handle).uuid)


# ------------------------------------------------------------------------------------------------ logging
class RefusalLog:
    """One log line per kind of refusal per ``interval_s``; the ones in between are counted, not logged."""

    def __init__(self, interval_s: float = 10.0) -> None:
        self.interval_s = interval_s
        self._lock = threading.Lock()
        self._last: dict[str, tuple[float, int]] = {}

    def refuse(self, kind: str, detail: str) -> None:
        now = time.monotonic()
        with self._lock:
            last = self._last.get(kind)
            if last is not None and now - last[0] < self.interval_s:
                self._last[kind] = (last[0], last[1] + 1)
                return
            unlogged = 0 if last is None else last[1]
            self._last[kind] = (now, 0)
        more = f" ({unlogged} more of this kind since the last line)" if unlogged else ""
        logger.warning("refused %s: %s%s", kind, detail[:200], more)

    def reset(self) -> None:
        """Forget what was logged (tests use it between cases)."""
        with self._lock:
            self._last.clear()


refusals = RefusalLog()
"""The process's refusal log (frames are refused before it is known which server they reached)."""


# ------------------------------------------------------------------------------------------------ values
def _finite_number(value: object) -> float | None:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    number = float(value)
    return number if math.isfinite(number) else None


def _finite_vector(value: object, length: int) -> tuple[float, ...] | None:
    if not isinstance(value, (list, tuple)) or len(value) != length:
        return None
    numbers = tuple(_finite_number(item) for item in value)
    if any(number is None for number in numbers):
        return None
    return tuple(float(number) for number in numbers if number is not None)


def unit_quaternion(value: object) -> tuple[float, float, float, float] | None:
    """``value`` as a unit wxyz quaternion, or None when it is not 4 finite numbers with a non-zero norm."""
    q = _finite_vector(value, 4)
    if q is None:
        return None
    norm = math.hypot(*q)  # overflow-safe for components near 1e308
    if not (math.isfinite(norm) and norm > 1e-12):
        return None
    w, x, y, z = (component / norm for component in q)
    return (w, x, y, z)


def clean_value(spec: ControlSpec, value: object) -> tuple[bool, Any, str]:
    """(accepted, cleaned value, reason refused) for a browser's ``value`` of a control with ``spec``."""
    match spec.kind:
        case "bool":
            if type(value) is bool:
                return True, value, ""
            return False, None, "a checkbox value that is not true or false"
        case "button":
            if value is True:
                return True, value, ""
            return False, None, "a button value other than true"
        case "number":
            number = _finite_number(value)
            if number is None:
                return False, None, "a number that is not finite or not a number"
            if spec.integer:
                # truncated, as viser's own cast to the control's int type does, then kept to the integers in range
                lo = None if spec.lo is None else math.ceil(spec.lo)
                hi = None if spec.hi is None else math.floor(spec.hi)
                if lo is not None and hi is not None and lo > hi:
                    return False, None, "a number for a control whose range holds no integer"
                whole = int(number)
                whole = whole if lo is None else max(whole, lo)
                return True, (whole if hi is None else min(whole, hi)), ""
            if spec.lo is not None:
                number = max(number, spec.lo)
            if spec.hi is not None:
                number = min(number, spec.hi)
            return True, number, ""
        case "choice":
            if isinstance(value, str) and value in spec.options:
                return True, value, ""
            return False, None, "an option the dropdown does not have"
        case "rgb":
            rgb = _finite_vector(value, 3)
            if rgb is None or not all(0.0 <= c <= 255.0 for c in rgb):
                return False, None, "a colour that is not three numbers in 0..255"
            return True, tuple(round(c) for c in rgb), ""
        case "text":
            if isinstance(value, str) and len(value) <= MAX_TEXT_CHARS:
                return True, value, ""
            return False, None, "text that is not a string of at most 10 000 characters"
        case "vector":
            vector = _finite_vector(value, spec.length)
            if vector is None:
                return False, None, f"a vector that is not {spec.length} finite numbers"
            return True, vector, ""
        case "display":
            return False, None, "a value for a control a browser may not set"


def _camera_fields(message: _messages.ViewerCameraMessage) -> tuple[dict[str, Any] | None, str]:
    """(the camera's fields, cleaned, or None; the first field that is not a camera a browser can have, or "")."""
    wxyz = unit_quaternion(message.wxyz)
    points = {
        name: _finite_vector(getattr(message, name), 3)
        for name in ("position", "look_at", "up_direction")
    }
    fov, near, far = (_finite_number(v) for v in (message.fov, message.near, message.far))
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
    return {
        "wxyz": wxyz,
        **points,
        "fov": fov,
        "near": near,
        "far": far,
        **sizes,
    }, ""


def _ray(origin: object, direction: object) -> bool:
    d = _finite_vector(direction, 3)
    return _finite_vector(origin, 3) is not None and d is not None and math.hypot(*d) > 0.0


def click_problem(message: _messages.ScenePointerMessage | _messages.SceneNodeClickMessage) -> str:
    """Why a click cannot be used ("" when it can): rays are 3 finite numbers, screen points 2."""
    if isinstance(message, _messages.ScenePointerMessage):
        if message.event_type not in ("click", "rect-select"):
            return "an unknown pointer event"
        if (message.ray_origin is None) != (message.ray_direction is None):
            return "half a ray"
        if message.ray_origin is not None and not _ray(message.ray_origin, message.ray_direction):
            return "a ray that is not finite"
        points = message.screen_pos
        if not isinstance(points, (list, tuple)) or not 1 <= len(points) <= 2:
            return "screen points that are not one or two"
        if any(_finite_vector(point, 2) is None for point in points):
            return "a screen point that is not two finite numbers"
        return ""
    index = message.instance_index
    if index is not None and (type(index) is not int or index < 0):
        return "an instance index that is not a count"
    if not _ray(message.ray_origin, message.ray_direction):
        return "a ray that is not finite"
    if _finite_vector(message.screen_pos, 2) is None:
        return "a screen point that is not two finite numbers"
    return ""


# ------------------------------------------------------------------------------------------------ frames
def decode_frame(raw: object) -> _messages.Message | None:
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
            message = _messages.Message.deserialize(raw)
    except (
        Exception
    ) as error:  # the frame's fields do not fit the message: refused, the connection stays up
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
    for name, hint in _field_hints(kind).items():
        if name in mapping and not _fits(mapping[name], hint):
            return name
    return ""


def _fits(value: object, hint: Any) -> bool:
    """Whether ``value`` has the type ``hint`` that viser declares for a message field (the shapes browsers send)."""
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if hint is typing.Any:
        return True
    if hint is float:
        return isinstance(value, (int, float)) and not isinstance(value, bool)
    if hint in (int, str, bytes, bool):
        return type(value) is hint
    if origin is typing.Union:
        return any(_fits(value, arg) for arg in args)
    if origin is typing.Literal:
        return any(value == arg and type(value) is type(arg) for arg in args)
    if origin is tuple:
        if not isinstance(value, (tuple, list)):
            return False
        if len(args) == 2 and args[1] is Ellipsis:
            return all(_fits(item, args[0]) for item in value)
        return len(value) == len(args) and all(
            _fits(v, a) for v, a in zip(value, args, strict=True)
        )
    if origin is dict:
        return isinstance(value, dict)
    return True  # a kind browsers do not send here; the message's own cleaner checks it


def _misfit_field(message: _messages.Message) -> str:
    """The first field of ``message`` whose value does not have its declared type, or "" (every field fits).

    viser only warns about such fields and passes them on, where a dict as a node name (unhashable) raises deep in
    its handlers: every field of every message is checked here, once, whatever its kind.
    """
    hints = _field_hints(type(message))
    for field in dataclasses.fields(message):  # type: ignore[arg-type]  # viser's messages are dataclasses
        hint = hints.get(field.name)
        if hint is not None and not _fits(getattr(message, field.name), hint):
            return field.name
    return ""


@functools.cache
def _field_hints(cls: type) -> dict[str, Any]:
    hints = typing.get_type_hints(cls)
    return {
        name: hint
        for name, hint in hints.items()
        if typing.get_origin(hint) is not typing.ClassVar and name != "excluded_self_client"
    }


async def _gated_message_consumer(
    websocket: Any, handle_message: Callable[[Any], None], message_class: object
) -> None:
    """viser's receive loop, with frames decoded by :func:`decode_frame` (a bad frame no longer ends the connection)."""
    del message_class  # every frame is decoded as a viser message by decode_frame
    while True:
        message = decode_frame(await websocket.recv())
        if message is not None:
            handle_message(message)


def _install_frame_gate() -> None:
    # A module-level function that viser's connection handler looks up on every new connection: one process-wide
    # swap (idempotent), because the receive loop does not know which server it serves.
    _infra._message_consumer = _gated_message_consumer  # type: ignore[attr-defined]


# ------------------------------------------------------------------------------------------------ the gate
Dispatch = Callable[[Any, Any], Coroutine[Any, Any, None]]


@dataclasses.dataclass
class _Upload:
    """One browser upload in flight, as its start message announced it."""

    part_count: int
    size_bytes: int
    last_part_at: float
    """When it started or last received a part (``time.monotonic()``)."""
    started_at: float = dataclasses.field(default_factory=time.monotonic)
    """When its start message was taken (``time.monotonic()``)."""
    bytes_seen: int = 0
    parts_seen: set[int] = dataclasses.field(default_factory=set)


Item = typing.TypeVar("Item")
_TOKEN_SLACK = 1e-9
"""A token refilled to within this of 1 counts as whole: the timer set by :meth:`CostlyBudget.wait_s` fires then."""


class CostlyBudget(typing.Generic[Item]):
    """One tab's token bucket for costly inputs, holding back the latest value of each control beyond it.

    ``burst`` inputs may go at once, then ``rate_hz`` a second. An input offered while the bucket is empty (or while
    others wait) is held back in place of any earlier one of the same control, last in line; :meth:`take` hands the
    oldest one out when a token is there. So a burst of clicks becomes one click, the latest value of a control is
    always the last of it delivered, and a tab's costly work is bounded by ``burst + rate_hz * t`` in any ``t`` s.
    Pure bookkeeping (times are passed in, e.g. ``time.monotonic()``); the gate runs it on the event loop.
    """

    def __init__(self, burst: int, rate_hz: float, now: float) -> None:
        if burst < 1 or not rate_hz > 0.0:
            raise ValueError(f"burst must be ≥ 1 and rate_hz > 0, got {burst}, {rate_hz}")
        self.burst = burst
        self.rate_hz = rate_hz
        self._tokens = float(burst)
        self._refilled_at = now
        self._held: dict[str, tuple[Item, bool]] = {}
        """By control key, in the order of each one's latest arrival: (item, free)."""

    def _refill(self, now: float) -> None:
        elapsed = max(0.0, now - self._refilled_at)
        self._tokens = min(float(self.burst), self._tokens + elapsed * self.rate_hz)
        self._refilled_at = max(now, self._refilled_at)

    def offer(
        self, key: str, item: Item, now: float, *, free: bool = False, hold: bool = False
    ) -> tuple[bool, bool]:
        """(goes now, replaced one held back) for ``item``, the new value of control ``key``.

        A ``free`` input (a cheap control, a gizmo) costs no token: it goes at once unless inputs are held back,
        and then waits in line behind them, so an edit made after a held-back Reset is applied after the Reset
        rather than undone by it. ``hold`` holds it even then (the caller knows of costly work still running)."""
        self._refill(now)
        if not hold and not self._held and (free or self._tokens >= 1.0 - _TOKEN_SLACK):
            if not free:
                self._tokens = max(0.0, self._tokens - 1.0)
            return True, False
        replaced = self._held.pop(key, None) is not None
        self._held[key] = (item, free)
        return False, replaced

    def take(self, now: float) -> tuple[str, Item] | None:
        """The oldest held-back (key, item) if the budget allows it now (a free one always), else None."""
        if not self._held:
            return None
        key = next(iter(self._held))
        item, free = self._held[key]
        if not free:
            self._refill(now)
            if self._tokens < 1.0 - _TOKEN_SLACK:
                return None
            self._tokens = max(0.0, self._tokens - 1.0)
        del self._held[key]
        return key, item

    def wait_s(self, now: float) -> float | None:
        """Seconds until :meth:`take` can hand out the next held-back input; None when none is held."""
        if not self._held:
            return None
        if self._held[next(iter(self._held))][1]:
            return 0.0
        self._refill(now)
        return max(0.0, (1.0 - self._tokens) / self.rate_hz)

    @property
    def next_is_free(self) -> bool:
        """Whether the next held-back input in line is a free one."""
        return bool(self._held) and self._held[next(iter(self._held))][1]

    @property
    def held(self) -> int:
        """How many inputs are held back (one per control at most)."""
        return len(self._held)


IN_LINE = (
    _messages.GuiUpdateMessage,
    _messages.TransformControlsUpdateMessage,
    _messages.TransformControlsDragStartMessage,
    _messages.TransformControlsDragEndMessage,
    _messages.SceneNodeClickMessage,
    _messages.ScenePointerMessage,
)
"""The inputs a tab's held-back or running scene switch or Reset keeps in line behind it: values, drags, clicks."""
Deferred = tuple[Any, Callable[[], None] | None, tuple[type, str] | None]
"""A held-back input: the cleaned message, what to do after it, and for a cheap GUI edit its control's (handle
type, label), to find the control again when a Reset rebuilt it."""


@dataclasses.dataclass
class _TabBudget:
    budget: CostlyBudget[Deferred]
    timer: asyncio.TimerHandle | None = None
    in_flight: int = 0
    """Costly inputs delivered whose handlers have not finished (a scene switch or Reset still building): the tab's
    later inputs wait in line until they have, or they would reach the scene being replaced."""


class Gate:
    """The one gate in front of one server's message dispatch. Made by :func:`install_gate`.

    Besides cleaning, it shares two budgets out fairly: costly inputs per tab (:func:`mark_costly`), so one tab
    flooding Reset or scene switches cannot fill viser's callback pool and delay every other tab; and uploads in
    flight across all tabs (:data:`MAX_UPLOADS_IN_FLIGHT_TOTAL`, :data:`MAX_UPLOAD_BYTES_IN_FLIGHT_TOTAL`).
    """

    def __init__(self, server: viser.ViserServer) -> None:
        self._server_ref = weakref.ref(server)
        self.log = refusals
        ws = server._websock_server
        self._server_dispatch: Dispatch = ws._handle_incoming_message
        self._client_dispatch: dict[int, Dispatch] = {}
        self._uploads: dict[int, dict[str, _Upload]] = {}
        """Per client, the uploads started and not finished, by transfer id."""
        self._budgets: dict[int, _TabBudget] = {}
        """Per client, its costly-input budget (only touched on the event loop)."""
        self._deliveries: set[asyncio.Future[None]] = set()
        ws._handle_incoming_message = self._dispatch  # type: ignore[method-assign]
        ws.on_client_connect(self._on_connect)
        ws.on_client_disconnect(self._on_disconnect)

    # Every message reaches viser's server-scoped and its connection-scoped handlers (two tasks). The gate takes
    # the connection's dispatch for itself and runs both from one place, after cleaning.
    def _on_connect(self, connection: Any) -> None:
        self._client_dispatch[int(connection.client_id)] = connection._handle_incoming_message
        connection._handle_incoming_message = _ignore
        connection.queue_message(_messages.RunJavascriptMessage(source=CSS_CAMERA_JS))

    def _on_disconnect(self, connection: Any) -> None:
        client_id = int(connection.client_id)
        self._client_dispatch.pop(client_id, None)
        self._uploads.pop(client_id, None)
        tab = self._budgets.pop(client_id, None)
        if tab is not None and tab.timer is not None:
            tab.timer.cancel()

    async def _dispatch(self, client_id: Any, message: Any) -> None:
        server = self._server_ref()
        if server is None:
            return
        try:
            cleaned, after = self._clean(server, int(client_id), message)
            if isinstance(cleaned, IN_LINE) and not self._admit(
                server, int(client_id), cleaned, after
            ):
                return  # held back, coalesced: delivered when the tab's budget allows
        except (
            Exception
        ) as error:  # a gate bug must not take the connection down, nor let the message through
            self.log.refuse(
                f"unreadable {type(message).__name__}", f"{type(error).__name__}: {error}"
            )
            return
        await self._deliver(client_id, cleaned, after)

    async def _deliver(
        self, client_id: Any, cleaned: Any, after: Callable[[], None] | None
    ) -> None:
        if cleaned is not None:
            await self._server_dispatch(client_id, cleaned)
            client_dispatch = self._client_dispatch.get(int(client_id))
            if client_dispatch is not None:
                await client_dispatch(client_id, cleaned)
        if after is not None:
            after()

    # ----------------------------------------------------------------------------------------- costly inputs
    def _admit(
        self,
        server: viser.ViserServer,
        client_id: int,
        message: Any,
        after: Callable[[], None] | None,
    ) -> bool:
        """Whether ``message`` goes through now; a costly input beyond the tab's budget is held back instead, and
        so is any input of that tab behind it (in line, free of the budget): a cheap edit or a drag that follows a
        held-back Reset or scene switch would otherwise be applied first and then undone by it."""
        tab = self._budgets.get(client_id)
        if isinstance(message, _messages.GuiUpdateMessage):
            key = str(message.uuid)
            handle = self._gui_handle(server, client_id, key)
            costly = handle is not None and control_spec(handle).costly
        else:  # a drag, a click: one in line per kind and node, the latest
            key, handle = f"{type(message).__name__} {getattr(message, 'name', '')}", None
            costly = False
        if not costly:
            if tab is None or (tab.budget.held == 0 and tab.in_flight == 0):
                return True
            label = None if handle is None else self._control_path(server, client_id, handle)
            tab.budget.offer(key, (message, after, label), time.monotonic(), free=True, hold=True)
            self._schedule(client_id, tab)
            return False
        now = time.monotonic()
        if tab is None:
            tab = self._budgets[client_id] = _TabBudget(
                CostlyBudget(COSTLY_BURST, COSTLY_RATE_HZ, now)
            )
        goes, replaced = tab.budget.offer(key, (message, after, None), now)
        if goes:
            self._deliver_costly(client_id, tab, message, after)
            return False  # on its way, tracked
        self.log.refuse(
            "costly input beyond the tab's budget (held back; the latest value is applied)",
            f"{str(getattr(handle, 'label', '?'))!r} from client {client_id}"
            f"{', replacing one held back' if replaced else ''} (budget {COSTLY_BURST} at once, "
            f"{COSTLY_RATE_HZ:g}/s)",
        )
        self._schedule(client_id, tab)
        return False

    def _is_costly(self, server: viser.ViserServer, client_id: int, message: Any) -> bool:
        if not isinstance(message, _messages.GuiUpdateMessage):
            return False
        handle = self._gui_handle(server, client_id, str(message.uuid))
        return handle is not None and control_spec(handle).costly

    def _deliver_costly(
        self, client_id: int, tab: _TabBudget, message: Any, after: Callable[[], None] | None
    ) -> None:
        """Deliver a costly input as a task; until its handler has finished, the tab's cheap inputs wait."""
        tab.in_flight += 1

        def finished(_task: object) -> None:
            tab.in_flight -= 1
            if self._budgets.get(client_id) is tab:
                self._schedule(client_id, tab)

        self._start(client_id, message, after).add_done_callback(finished)

    def _start(
        self, client_id: int, message: Any, after: Callable[[], None] | None
    ) -> asyncio.Future[None]:
        task = asyncio.ensure_future(self._deliver(client_id, message, after))
        self._deliveries.add(task)  # asyncio keeps only a weak reference to a running task
        task.add_done_callback(self._deliveries.discard)
        return task

    def _schedule(self, client_id: int, tab: _TabBudget) -> None:
        wait_s = tab.budget.wait_s(time.monotonic())
        if tab.timer is not None or wait_s is None:
            return
        if wait_s == 0.0 and tab.in_flight and tab.budget.next_is_free:
            return  # a cheap input waits for the costly ones in flight: their end schedules it
        tab.timer = asyncio.get_running_loop().call_later(wait_s, self._release, client_id)

    def _release(self, client_id: int) -> None:
        """Deliver the oldest held-back costly input of ``client_id`` (on the event loop, from its timer)."""
        tab = self._budgets.get(client_id)
        if tab is None:
            return
        tab.timer = None
        if tab.in_flight and tab.budget.next_is_free:
            return  # scheduled again when the costly inputs in flight finish
        taken = tab.budget.take(time.monotonic())
        server = self._server_ref()
        try:
            if taken is not None and server is not None:
                key, (message, after, label) = taken
                if (
                    isinstance(message, _messages.GuiUpdateMessage)
                    and self._gui_handle(server, client_id, key) is None
                ):
                    # The control went meanwhile: a Reset or scene switch held back before it rebuilt its scene.
                    # An edit made after it goes to the rebuilt scene's control of the same kind, label and
                    # folders (a person who clicked Reset, then moved Speed, expects Speed to stick); with none,
                    # or more than one, there is nothing to apply.
                    message, after = self._retarget(server, client_id, message, label)
                if message is not None and self._is_costly(server, client_id, message):
                    self._deliver_costly(client_id, tab, message, after)
                elif message is not None:
                    self._start(client_id, message, after)
        except Exception as error:  # a gate bug must not stall the tab's line
            self.log.refuse("held-back input", f"{type(error).__name__}: {error}")
        finally:
            self._schedule(client_id, tab)

    def _control_path(
        self, server: viser.ViserServer, client_id: int, handle: Any
    ) -> tuple[type, str]:
        """(handle type, its label under the labels of the folders it sits in): which control it is to a person,
        the same for a control rebuilt by a Reset and different in another scene (under another scene's folder)."""
        client = self._client(server, client_id)
        containers = [server.gui._container_handle_from_uuid]
        if client is not None:
            containers.append(client.gui._container_handle_from_uuid)
        names = [str(getattr(handle, "label", ""))]
        parent = getattr(_state(handle), "parent_container_id", "root")
        for _ in range(
            32
        ):  # folders nest a few deep; a cycle would be viser's bug, not a hang here
            if parent == "root":
                break
            container = next((c[parent] for c in containers if parent in c), None)
            if container is None:
                break
            names.append(str(getattr(container, "label", type(container).__name__)))
            parent = getattr(getattr(container, "_impl", None), "parent_container_id", "root")
        return type(handle), " / ".join(reversed(names))

    def _retarget(
        self,
        server: viser.ViserServer,
        client_id: int,
        message: _messages.GuiUpdateMessage,
        label: tuple[type, str] | None,
    ) -> tuple[Any, Callable[[], None] | None]:
        """``message`` sent to the one live control of ``label`` (its handle type and label) instead, cleaned
        against that control's own spec; (None, None) when there is no such control or more than one."""
        if label is None:
            return None, None
        client = self._client(server, client_id)
        registries = [server.gui._gui_input_handle_from_uuid]
        if client is not None:
            registries.append(client.gui._gui_input_handle_from_uuid)
        matches = [
            uuid
            for registry in registries
            for uuid, handle in list(registry.items())
            if type(handle) is label[0]
            and not _state(handle).removed
            and self._control_path(server, client_id, handle) == label
        ]
        if len(matches) != 1:
            return None, None
        return self._clean_gui(
            server, client_id, _messages.GuiUpdateMessage(matches[0], message.updates)
        )

    def uploads_in_flight(self) -> tuple[int, int]:
        """(uploads, bytes they announced) started and not finished, across every tab of this server."""
        # Mutated only on the event loop; list() copies each dict in one step under the GIL, so a test thread may
        # read this while uploads come and go.
        everyone = [u for uploads in list(self._uploads.values()) for u in list(uploads.values())]
        return len(everyone), sum(upload.size_bytes for upload in everyone)

    def costly_held_back(self, client_id: int) -> int:
        """How many costly inputs of ``client_id`` wait for its budget (one per control at most)."""
        tab = self._budgets.get(client_id)
        return 0 if tab is None else tab.budget.held

    def _client(self, server: viser.ViserServer, client_id: int) -> viser.ClientHandle | None:
        return server._connected_clients.get(client_id)

    def _clean(
        self, server: viser.ViserServer, client_id: int, message: Any
    ) -> tuple[Any, Callable[[], None] | None]:
        if isinstance(message, _messages.GuiUpdateMessage):
            return self._clean_gui(server, client_id, message)
        if isinstance(message, _messages.TransformControlsUpdateMessage):
            return self._clean_gizmo(server, client_id, message)
        if isinstance(message, _messages.ViewerCameraMessage):
            return self._clean_camera(server, client_id, message), None
        if isinstance(message, _messages.TransformControlsDragEndMessage):
            # A drag ends: every viewer, the dragging one too, is sent the gizmo's pose on the server (during the
            # drag the sender is not, so its own gizmo does not fight the mouse).
            handle = self._gizmo_handle(server, client_id, str(message.name), str(message.owner))
            return message, None if handle is None else functools.partial(_send_pose, handle)
        if isinstance(message, (_messages.ScenePointerMessage, _messages.SceneNodeClickMessage)):
            reason = click_problem(message)
            if reason:
                self.log.refuse(f"click ({reason})", f"{type(message).__name__}")
                return None, None
            return message, None
        if isinstance(message, _messages.FileTransferStartUpload):
            return self._clean_upload_start(server, client_id, message)
        if isinstance(message, _messages.FileTransferPart):
            return self._clean_upload_part(client_id, message), None
        if isinstance(message, ALLOWED_MESSAGES):
            return message, None
        self.log.refuse("message type", f"{type(message).__name__} is not one a browser may send")
        return None, None

    def _gui_handle(self, server: viser.ViserServer, client_id: int, uuid: str) -> Any:
        handle = server.gui._gui_input_handle_from_uuid.get(uuid)
        if handle is None:
            client = self._client(server, client_id)
            if client is not None:
                handle = client.gui._gui_input_handle_from_uuid.get(uuid)
        return None if handle is None or _state(handle).removed else handle

    def _clean_gui(
        self, server: viser.ViserServer, client_id: int, message: _messages.GuiUpdateMessage
    ) -> tuple[Any, Callable[[], None] | None]:
        updates = message.updates
        if not isinstance(updates, dict) or set(updates) != {"value"}:
            fields = (
                sorted(str(key)[:40] for key in updates) if isinstance(updates, dict) else updates
            )
            self.log.refuse("GUI update of a field other than value", f"fields {fields!r}")
            return None, None
        handle = self._gui_handle(server, client_id, str(message.uuid))
        if handle is None:
            self.log.refuse("GUI update for an unknown id", f"uuid {str(message.uuid)[:64]!r}")
            return None, None
        spec = control_spec(handle)
        accepted, value, reason = clean_value(spec, updates["value"])
        # After each change, and after each refusal (the sender shows its own edit), every viewer is sent the
        # server's value: two viewers that moved one slider a few ms apart both end on the server's.
        send_back = functools.partial(_send_value, handle)
        if not accepted:
            label = str(getattr(handle, "label", "?"))
            self.log.refuse(f"GUI value ({reason})", f"{label!r} got {updates['value']!r}"[:200])
            return None, send_back
        return _messages.GuiUpdateMessage(message.uuid, {"value": value}), send_back

    def _clean_upload_start(
        self, server: viser.ViserServer, client_id: int, message: _messages.FileTransferStartUpload
    ) -> tuple[Any, Callable[[], None] | None]:
        handle = self._gui_handle(server, client_id, str(message.source_component_uuid))
        size, parts = message.size_bytes, message.part_count
        if not isinstance(handle, viser.GuiUploadButtonHandle):
            self.log.refuse(
                "upload for an unknown id", f"uuid {str(message.source_component_uuid)[:64]!r}"
            )
            return None, None
        if not all(isinstance(x, int) and not isinstance(x, bool) for x in (size, parts)) or (
            not 0 <= parts <= max(1, -(-size // MIN_PART_BYTES)) or (size > 0) != (parts > 0)
        ):
            self.log.refuse("upload size", f"{size!r} bytes in {parts!r} parts")
            return None, None
        if not 0 <= size <= MAX_UPLOAD_BYTES:
            self.log.refuse("upload size", f"{size!r} bytes (limit {MAX_UPLOAD_BYTES})")
            return None, self._tell(
                server,
                client_id,
                f"The file is {size / MIB:.1f} MiB; this server takes files up to "
                f"{MAX_UPLOAD_BYTES / MIB:.0f} MiB.",
            )
        if not all(
            isinstance(x, str) and len(x) <= MAX_NAME_CHARS
            for x in (message.filename, message.mime_type, message.transfer_uuid)
        ):
            self.log.refuse("upload name", "file name, type or transfer id is not short text")
            return None, None
        self._drop_stalled_uploads(server)
        if any(message.transfer_uuid in uploads for uploads in list(self._uploads.values())):
            # Every tab sees a shared upload button's part acks, with their transfer id: a second start under
            # that id would mix another tab's parts into the first tab's file.
            self.log.refuse("upload transfer id", "already in flight")
            return None, None
        in_flight = self._uploads.setdefault(client_id, {})
        if len(in_flight) >= MAX_UPLOADS_IN_FLIGHT:
            self.log.refuse("uploads in flight", f"more than {MAX_UPLOADS_IN_FLIGHT} at once")
            return None, self._tell(
                server,
                client_id,
                f"This tab already has {MAX_UPLOADS_IN_FLIGHT} uploads under way; wait for one to finish.",
            )
        own_bytes = sum(upload.size_bytes for upload in list(in_flight.values()))
        if own_bytes + size > MAX_UPLOAD_BYTES_IN_FLIGHT_PER_TAB:
            self.log.refuse(
                "upload bytes in flight",
                f"{own_bytes} + {size} bytes from one tab (limit {MAX_UPLOAD_BYTES_IN_FLIGHT_PER_TAB})",
            )
            return None, self._tell(
                server,
                client_id,
                f"This tab's uploads under way already announce {own_bytes / MIB:.1f} MiB; it takes "
                f"{MAX_UPLOAD_BYTES_IN_FLIGHT_PER_TAB / MIB:.0f} MiB at once. Wait for them to finish.",
            )
        count, total_bytes = self.uploads_in_flight()
        if (
            count >= MAX_UPLOADS_IN_FLIGHT_TOTAL
            or total_bytes + size > MAX_UPLOAD_BYTES_IN_FLIGHT_TOTAL
        ):
            self.log.refuse(
                "uploads in flight across all tabs",
                f"{count} uploads of {total_bytes} bytes under way, {size} more asked (limits "
                f"{MAX_UPLOADS_IN_FLIGHT_TOTAL} uploads, {MAX_UPLOAD_BYTES_IN_FLIGHT_TOTAL} bytes)",
            )
            return None, self._tell(
                server,
                client_id,
                f"The server is receiving other uploads ({count} files, "
                f"{total_bytes / MIB:.1f} MiB in flight from all tabs; it takes "
                f"{MAX_UPLOADS_IN_FLIGHT_TOTAL} files or {MAX_UPLOAD_BYTES_IN_FLIGHT_TOTAL / MIB:.0f} MiB at "
                "once). Try again in a moment.",
            )
        if parts > 0:
            in_flight[message.transfer_uuid] = _Upload(parts, size, time.monotonic())
        return message, None

    def _tell(self, server: viser.ViserServer, client_id: int, body: str) -> Callable[[], None]:
        """A notification of a refused upload for the tab that sent it (shown after the refusal)."""

        def notify() -> None:
            client = self._client(server, client_id)
            if client is not None:
                client.add_notification(
                    "Upload refused", body, color="red", auto_close_seconds=15.0
                )

        return notify

    def _drop_stalled_uploads(self, server: viser.ViserServer) -> None:
        """Forget uploads that received no part for :data:`UPLOAD_STALL_S`, and free the parts viser holds."""
        now = time.monotonic()
        for client_id, uploads in list(self._uploads.items()):
            for transfer, upload in list(uploads.items()):
                stalled = now - upload.last_part_at >= UPLOAD_STALL_S
                late = now - upload.started_at >= UPLOAD_DEADLINE_S
                if not (stalled or late):
                    continue
                del uploads[transfer]
                self.log.refuse(
                    "stalled upload",
                    f"no part for {UPLOAD_STALL_S:g} s"
                    if stalled
                    else f"not finished {UPLOAD_DEADLINE_S:g} s after its start",
                )
                client = self._client(server, client_id)
                for api in (server.gui, None if client is None else client.gui):
                    if api is not None:
                        api._current_file_upload_states.pop(transfer, None)

    def _clean_upload_part(self, client_id: int, message: _messages.FileTransferPart) -> Any:
        upload = self._uploads.get(client_id, {}).get(str(message.transfer_uuid))
        index, content = message.part_index, message.content
        if upload is None or not isinstance(index, int) or not 0 <= index < upload.part_count:
            self.log.refuse("upload part", "for no upload in flight, or out of range")
            return None
        if index in upload.parts_seen:
            self.log.refuse("upload part", "sent twice")
            return None
        if not isinstance(content, bytes) or upload.bytes_seen + len(content) > upload.size_bytes:
            self.log.refuse("upload part", "more bytes than the upload announced")
            return None
        upload.bytes_seen += len(content)
        upload.parts_seen.add(index)
        upload.last_part_at = time.monotonic()
        if len(upload.parts_seen) == upload.part_count:
            del self._uploads[client_id][str(message.transfer_uuid)]
        return message

    def _gizmo_handle(
        self, server: viser.ViserServer, client_id: int, name: str, owner: str
    ) -> Any:
        apis = [server.scene]
        client = self._client(server, client_id)
        if client is not None:
            apis.append(client.scene)
        for api in apis:
            if api._owner_id == owner:
                return api._handle_from_transform_controls_name.get(name)
        return None

    def _clean_gizmo(
        self,
        server: viser.ViserServer,
        client_id: int,
        message: _messages.TransformControlsUpdateMessage,
    ) -> tuple[Any, Callable[[], None] | None]:
        handle = self._gizmo_handle(server, client_id, str(message.name), str(message.owner))
        if handle is None:
            self.log.refuse("gizmo update for an unknown gizmo", f"name {str(message.name)[:64]!r}")
            return None, None
        position = _finite_vector(message.position, 3)
        wxyz = unit_quaternion(message.wxyz)
        if position is not None and wxyz is not None:
            return dataclasses.replace(message, position=position, wxyz=wxyz), None
        if position is None:
            self.log.refuse("gizmo position (not 3 finite numbers)", f"{message.position!r}"[:200])
        if wxyz is None:
            self.log.refuse(
                "gizmo orientation (not 4 finite numbers with a non-zero norm)",
                f"{message.wxyz!r}"[:200],
            )
        last_position = tuple(float(v) for v in handle.position)
        last_wxyz = tuple(float(v) for v in handle.wxyz)
        cleaned = dataclasses.replace(
            message,
            position=position if position is not None else last_position,
            wxyz=wxyz if wxyz is not None else last_wxyz,
        )
        return cleaned, functools.partial(_send_pose, handle)

    def _clean_camera(
        self, server: viser.ViserServer, client_id: int, message: _messages.ViewerCameraMessage
    ) -> _messages.ViewerCameraMessage | None:
        fields, wrong = _camera_fields(message)
        if fields is not None:
            return _messages.ViewerCameraMessage(**fields)
        client = self._client(server, client_id)
        self.log.refuse(
            "camera (non-finite, out of bounds, or an image size that is not a positive integer)",
            f"{wrong} = {str(getattr(message, wrong.split('/')[0], ''))[:80]}",
        )
        if client is None:
            return None  # a first camera that is unusable: the client is not registered until a good one comes
        camera = client.camera
        return _messages.ViewerCameraMessage(
            wxyz=tuple(float(v) for v in camera.wxyz),  # type: ignore[arg-type]
            position=tuple(float(v) for v in camera.position),  # type: ignore[arg-type]
            fov=float(camera.fov),
            near=float(camera.near),
            far=float(camera.far),
            image_height=int(camera.image_height),
            image_width=int(camera.image_width),
            look_at=tuple(float(v) for v in camera.look_at),  # type: ignore[arg-type]
            up_direction=tuple(float(v) for v in camera.up_direction),  # type: ignore[arg-type]
        )


async def _ignore(_client_id: Any, _message: Any) -> None:
    """The connection's own dispatch, now run by the gate instead."""


def _send_value(handle: Any) -> None:
    """Send the server's value of ``handle`` to every viewer of it (the sender included)."""
    state = _state(handle)
    if not state.removed and not state.is_button:
        state.gui_api._websock_interface.queue_message(
            _messages.GuiUpdateMessage(state.uuid, {"value": state.value})
        )


def _send_pose(handle: Any) -> None:
    """Send the server's pose of gizmo ``handle`` to every viewer of it (the sender included)."""
    state = handle._impl
    if state.removed:
        return
    api = state.api
    x, y, z = (float(v) for v in state.position)
    w, i, j, k = (float(v) for v in state.wxyz)
    api._queue_scene_message(_messages.SetPositionMessage(state.name, (x, y, z)))
    api._queue_scene_message(_messages.SetOrientationMessage(state.name, (w, i, j, k)))


_gates: weakref.WeakKeyDictionary[viser.ViserServer, Gate] = weakref.WeakKeyDictionary()
_gates_lock = threading.Lock()


def install_gate(server: viser.ViserServer) -> Gate:
    """Put the gate in front of ``server``'s dispatch (once per server; later calls return the same gate).

    Install it before browsers connect: a connection opened earlier keeps viser's own connection-scoped dispatch.
    """
    with _gates_lock:
        gate = _gates.get(server)
        if gate is None:
            _install_frame_gate()
            gate = _gates[server] = Gate(server)
        return gate


CSS_CAMERA_JS = """(() => {
  const viewer = window.__viserMutable;
  if (!viewer || typeof viewer.sendMessage !== "function" || viewer.sendMessage.cssCamera) return;
  const send = viewer.sendMessage;
  const wrapped = (message) => {
    const canvas = viewer.canvas;
    if (message && message.type === "ViewerCameraMessage" && canvas
        && canvas.clientWidth > 0 && canvas.clientHeight > 0) {
      message = Object.assign({}, message,
        { image_width: canvas.clientWidth, image_height: canvas.clientHeight });
    }
    return send(message);
  };
  wrapped.cssCamera = true;
  viewer.sendMessage = wrapped;
  if (typeof viewer.sendCamera === "function") viewer.sendCamera();
})();"""
"""Sent to every tab as it connects: its camera reports then give the canvas size in CSS pixels.

viser 1.1.1's client reports ``canvas.width``, in device pixels: twice the CSS size on a HiDPI screen, and 0.75–1
of it while its adaptive resolution drops on a slow machine. The control panel is a fixed CSS width, so framing in
device pixels put the scene under the panel on HiDPI screens, and each resolution change re-framed the camera
(during a drag, too). The script wraps the client's ``sendMessage`` (reassigned on each connection, so each
connection gets the script again) and sends the camera once at once.
"""


# ------------------------------------------------------------------------------------------------ registries
def node_names(api: viser.SceneApi) -> set[str]:
    """Names of every scene node ``api`` (a server's or a client's scene) holds."""
    return set(api._handle_from_node_name)


def live_controls(api: viser.GuiApi) -> int:
    """How many GUI inputs ``api`` holds."""
    return len(api._gui_input_handle_from_uuid)
