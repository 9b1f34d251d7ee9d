"""The one module that reaches into viser's private state: everything else in the project uses public viser only.

Read from viser 1.1.1 (pinned ``==1.1.1`` in pyproject.toml for this module's sake); an upgrade means re-reading
viser's code behind each name below, and nothing else. The private names touched, and why:

- ``viser._messages`` (module): the message classes a browser sends and the server sends back, needed to decode,
  clean and answer frames; re-exported as :data:`messages`.
- ``viser.infra._infra._message_consumer`` (module function): the per-connection receive loop, replaced by one that
  decodes frames through the gate's decoder, so a frame that does not decode no longer ends the connection
  (:func:`install_frame_decoder`).
- ``ViserServer._websock_server`` and its ``_handle_incoming_message``: the server-scoped dispatch of every message,
  replaced by the gate's (:func:`install_message_filter`).
- a websocket connection's ``_handle_incoming_message``: the connection-scoped dispatch, taken over so that the gate
  runs both dispatches after cleaning (:func:`take_connection_dispatch`).
- ``ViserServer._connected_clients``: a client by id, as seen from the event loop (:func:`connected_client`).
- ``GuiApi._gui_input_handle_from_uuid``: the GUI inputs by the uuid a browser names (:func:`gui_input_by_uuid`,
  :func:`gui_inputs`).
- ``GuiApi._container_handle_from_uuid``: the folders a control sits in (:func:`gui_container_by_uuid`).
- ``GuiApi._current_file_upload_states``: the parts viser holds for an upload in flight, freed when the gate drops
  a stalled upload (:func:`drop_upload_parts`), and the tab each upload came from (:func:`route_upload_acks`).
- the server's ``GuiApi._websock_interface.queue_message``: wrapped so that an upload's acks go to the tab that sent
  it alone (:func:`route_upload_acks`).
- ``SceneApi._owner_id`` and ``SceneApi._handle_from_transform_controls_name``: the gizmo a browser names, on the
  server's or its own scene (:func:`gizmo_by_name`); ``SceneApi._queue_scene_message``: send a gizmo's pose back
  (:func:`send_gizmo_pose`).
- a GUI or gizmo handle's ``_impl`` (its state: ``uuid``, ``removed``, ``is_button``, ``value``,
  ``parent_container_id``, ``gui_api``; a gizmo's ``api``, ``name``, ``position``, ``wxyz``) and
  ``GuiApi._websock_interface``: a control's uuid and liveness, and sending the server's value back
  (:func:`gui_uuid`, :func:`is_removed`, :func:`parent_container_id`, :func:`send_gui_value`).
- ``ClientHandle._websock_connection``: the client's message buffer, whose ``sanctioned_dead_writes`` scope keeps a
  closing tab's last writes from warning (:func:`dead_writes_allowed`), and through which a refused upload is ended
  in that tab alone (:func:`end_refused_upload`), a download is sent under a transfer id we choose
  (:func:`send_download`) and a notice is taken down (:func:`remove_notice`).
- viser's client (``UploadButton.tsx``, not Python): an upload button stays disabled until the acks of its upload
  reach the size announced, and its progress notice has the id ``upload-<transfer id>`` (:func:`end_refused_upload`,
  :func:`upload_notice_id`).
- viser's client (``MessageHandler.tsx``): a download's notice, which holds its link, has the id
  ``download-<transfer id>`` (:func:`send_download`); ``ClientHandle.send_file_download`` does not return that id.
- ``viser._assignable_props_api.AssignablePropsBase._cast_value_recursive`` and ``colors_to_uint8``: the property
  cast, replaced for speed by :func:`cast_value_recursive` (:func:`patch_property_cast`).

The property cast: viser 1.1.1 casts every property write through the property's type hint first, and the cast
compares the hint with four ``npt.NDArray[...]`` aliases that it builds anew on every call. Building them runs
typing's substitution (numpy's ``NDArray`` is a ``types.GenericAlias``, which caches nothing): about 50 µs a write,
0.8 ms of a 1.75 ms peloton input on this machine. :func:`cast_value_recursive` is the same function comparing with
aliases built once; ``tests/server/test_viser_patches.py`` holds it to the original for every property hint viser
declares.
"""

from __future__ import annotations

import mimetypes
import uuid
from collections.abc import Callable, Coroutine, Mapping
from contextlib import AbstractContextManager
from typing import Any

import numpy as np
import numpy.typing as npt
import viser
from viser import _assignable_props_api as props_api
from viser import _messages as messages
from viser.infra import _infra

__all__ = [
    "ORIGINAL_CAST",
    "VISER_VERSION",
    "Dispatch",
    "cast_value_recursive",
    "connected_client",
    "dead_writes_allowed",
    "drop_upload_parts",
    "end_refused_upload",
    "gizmo_by_name",
    "gui_container_by_uuid",
    "gui_input_by_uuid",
    "gui_inputs",
    "gui_uuid",
    "install_frame_decoder",
    "install_message_filter",
    "installed_property_cast",
    "is_removed",
    "messages",
    "parent_container_id",
    "patch_property_cast",
    "remove_notice",
    "route_upload_acks",
    "send_download",
    "send_gizmo_pose",
    "send_gui_value",
    "take_connection_dispatch",
    "upload_notice_id",
]

VISER_VERSION = "1.1.1"
"""The viser this module was read from (pinned in pyproject.toml); the property-cast patch leaves any other alone."""

Dispatch = Callable[[Any, Any], Coroutine[Any, Any, None]]
"""viser's message dispatch: ``await dispatch(client_id, message)``."""


# ------------------------------------------------------------------------------------------------ handles
def gui_uuid(handle: object) -> str:
    """The uuid a browser uses to address GUI ``handle``."""
    return str(handle._impl.uuid)  # type: ignore[attr-defined]


def is_removed(handle: object) -> bool:
    """Whether GUI or gizmo ``handle`` has been removed."""
    return bool(handle._impl.removed)  # type: ignore[attr-defined]


def parent_container_id(handle: object) -> str:
    """The uuid of the container (folder, tab) ``handle`` sits in; "root" for the panel itself or an unknown kind."""
    return getattr(getattr(handle, "_impl", None), "parent_container_id", "root")


def connected_client(server: viser.ViserServer, client_id: int) -> viser.ClientHandle | None:
    """The client ``client_id`` of ``server``, or None once it is gone (read on the event loop)."""
    return server._connected_clients.get(client_id)


def gui_inputs(api: viser.GuiApi) -> Mapping[str, Any]:
    """Every GUI input handle of ``api`` (the server's or a client's GUI), by uuid: viser's own map, not a copy."""
    return api._gui_input_handle_from_uuid


def gui_input_by_uuid(server: viser.ViserServer, client_id: int, uuid: str) -> Any:
    """The live GUI input ``uuid`` that client ``client_id`` can address (the server's, else its own), or None."""
    handle = server.gui._gui_input_handle_from_uuid.get(uuid)
    if handle is None:
        client = connected_client(server, client_id)
        if client is not None:
            handle = client.gui._gui_input_handle_from_uuid.get(uuid)
    return None if handle is None or is_removed(handle) else handle


def gui_container_by_uuid(server: viser.ViserServer, client_id: int, uuid: str) -> Any:
    """The GUI container (folder, tab...) ``uuid`` on the server's GUI, else on client ``client_id``'s, or None."""
    client = connected_client(server, client_id)
    containers = [server.gui._container_handle_from_uuid]
    if client is not None:
        containers.append(client.gui._container_handle_from_uuid)
    return next((c[uuid] for c in containers if uuid in c), None)


def gizmo_by_name(server: viser.ViserServer, client_id: int, name: str, owner: str) -> Any:
    """The transform-controls handle ``name`` of the scene whose owner id is ``owner`` (the server's, or client
    ``client_id``'s own), or None."""
    apis = [server.scene]
    client = connected_client(server, client_id)
    if client is not None:
        apis.append(client.scene)
    for api in apis:
        if api._owner_id == owner:
            return api._handle_from_transform_controls_name.get(name)
    return None


def drop_upload_parts(server: viser.ViserServer, client_id: int, transfer_uuid: str) -> None:
    """Free the parts viser holds for upload ``transfer_uuid`` (on the server's GUI and client ``client_id``'s)."""
    client = connected_client(server, client_id)
    for api in (server.gui, None if client is None else client.gui):
        if api is not None:
            api._current_file_upload_states.pop(transfer_uuid, None)


def end_refused_upload(
    server: viser.ViserServer, client_id: int, button_uuid: str, transfer_uuid: str, size_bytes: int
) -> None:
    """End upload ``transfer_uuid`` (of ``size_bytes``, on upload button ``button_uuid``) in tab ``client_id`` after
    the gate refused its start, so the tab can upload again.

    viser's client disables the button until acks for the whole size arrive, and shows an "Uploading …" notice with
    a spinner meanwhile; a refused start gets no ack, so both stayed until the page was reloaded. This sends the tab
    one ack for every byte (the button comes back) and removes that notice, which the ack would otherwise turn into
    "File uploaded successfully". The gate's own notice then says why the file was refused.
    """
    client = connected_client(server, client_id)
    if client is not None:
        ack = messages.FileTransferPartAck(button_uuid, transfer_uuid, size_bytes, size_bytes)
        _send(client, ack, messages.RemoveNotificationMessage(uuid=upload_notice_id(transfer_uuid)))


def route_upload_acks(server: viser.ViserServer) -> None:
    """Send each upload's part acks to the tab that sent it, not to every tab (once per server).

    An upload button shared by every tab (``--shared``) acks through the server, which broadcasts. viser's client
    in a tab that did not start the upload then shows "Uploading undefined" under an id of its own, which the
    upload's end never reaches: its spinner stayed until the page was reloaded.
    """
    api = server.gui
    interface = api._websock_interface  # pyright: ignore[reportPrivateUsage]
    broadcast = interface.queue_message
    if getattr(broadcast, "routes_upload_acks", False):
        return

    def queue_message(message: Any) -> None:
        if isinstance(message, messages.FileTransferPartAck):
            upload = api._current_file_upload_states.get(message.transfer_uuid)  # pyright: ignore[reportPrivateUsage]
            client = None if upload is None else connected_client(server, upload["client_id"])
            if client is not None:
                _send(client, message)
                return
        broadcast(message)

    queue_message.routes_upload_acks = True  # type: ignore[attr-defined]
    interface.queue_message = queue_message  # type: ignore[method-assign]


def upload_notice_id(transfer_uuid: str) -> str:
    """The id of the notice viser's client shows for upload ``transfer_uuid`` ("Uploading…", then "File uploaded
    successfully"), for :func:`remove_notice`."""
    return f"upload-{transfer_uuid}"


def send_download(client: viser.ClientHandle, filename: str, content: bytes, chunk_bytes: int = 1024 * 1024) -> str:
    """Send ``content`` to tab ``client`` as a download named ``filename`` shown as a link in a notice, as
    ``ClientHandle.send_file_download`` does; return that notice's id, for :func:`remove_notice`."""
    transfer = str(uuid.uuid4())
    mime_type = mimetypes.guess_type(filename, strict=False)[0] or "application/octet-stream"
    parts = [content[i : i + chunk_bytes] for i in range(0, len(content), chunk_bytes)]
    _send(client, messages.FileTransferStartDownload(False, transfer, filename, mime_type, len(parts), len(content)))
    for index, part in enumerate(parts):
        _send(client, messages.FileTransferPart(None, transfer, index, part))
        client.flush()
    return f"download-{transfer}"


def remove_notice(client: viser.ClientHandle, notice_id: str) -> None:
    """Take notice ``notice_id`` down in tab ``client`` (a download's link notice frees its file there too)."""
    _send(client, messages.RemoveNotificationMessage(uuid=notice_id))


def _send(client: viser.ClientHandle, *queued: messages.Message) -> None:
    """Queue ``queued`` for tab ``client`` alone, in order."""
    connection = client._websock_connection  # pyright: ignore[reportPrivateUsage]
    for message in queued:
        connection.queue_message(message)


def send_gui_value(handle: Any) -> None:
    """Send the server's value of GUI ``handle`` to every viewer of it (a button, or a removed control: nothing)."""
    state = handle._impl
    if not state.removed and not state.is_button:
        state.gui_api._websock_interface.queue_message(messages.GuiUpdateMessage(state.uuid, {"value": state.value}))


def send_gizmo_pose(handle: Any) -> None:
    """Send the server's pose of gizmo ``handle`` to every viewer of it (a removed gizmo: nothing)."""
    state = handle._impl
    if state.removed:
        return
    api = state.api
    x, y, z = (float(v) for v in state.position)
    w, i, j, k = (float(v) for v in state.wxyz)
    api._queue_scene_message(messages.SetPositionMessage(state.name, (x, y, z)))
    api._queue_scene_message(messages.SetOrientationMessage(state.name, (w, i, j, k)))


def dead_writes_allowed(client: viser.ClientHandle) -> AbstractContextManager[object]:
    """A scope in which messages queued for ``client`` after its tab closed do not warn (viser 1.1.1's own scope).

    viser warns once per closed tab about a write through a stale handle; a session being built or closed when
    its tab goes writes there by construction, and those messages are freed with the client.
    """
    buffer = client._websock_connection.get_message_buffer()  # pyright: ignore[reportPrivateUsage]
    return buffer.sanctioned_dead_writes()


# ------------------------------------------------------------------------------------------------ dispatch
def install_message_filter(
    server: viser.ViserServer,
    dispatch: Dispatch,
    on_connect: Callable[[Any], None],
    on_disconnect: Callable[[Any], None],
) -> Dispatch:
    """Route every message ``server`` receives through ``dispatch`` instead of viser's server-scoped dispatch, and
    call ``on_connect``/``on_disconnect`` with each websocket connection; returns viser's dispatch, for ``dispatch``
    to call with what it lets through."""
    ws = server._websock_server
    original: Dispatch = ws._handle_incoming_message
    ws._handle_incoming_message = dispatch  # type: ignore[method-assign]
    ws.on_client_connect(on_connect)
    ws.on_client_disconnect(on_disconnect)
    return original


async def _ignore(_client_id: Any, _message: Any) -> None:
    """The connection's own dispatch, now run by the gate instead."""


def take_connection_dispatch(connection: Any) -> Dispatch:
    """Take websocket ``connection``'s own (connection-scoped) dispatch: viser no longer runs it; returns it."""
    dispatch: Dispatch = connection._handle_incoming_message
    connection._handle_incoming_message = _ignore
    return dispatch


def install_frame_decoder(decode: Callable[[object], messages.Message | None]) -> None:
    """Decode every frame a browser sends with ``decode`` (None: the frame is dropped, the connection stays up).

    viser's connection handler looks its receive loop up, as a module-level function, on every new connection: one
    process-wide swap (idempotent), because the receive loop does not know which server it serves.
    """

    async def gated_message_consumer(
        websocket: Any, handle_message: Callable[[Any], None], message_class: object
    ) -> None:
        """viser's receive loop, with frames decoded by ``decode`` (a bad frame no longer ends the connection)."""
        del message_class  # every frame is decoded as a viser message by ``decode``
        while True:
            message = decode(await websocket.recv())
            if message is not None:
                handle_message(message)

    _infra._message_consumer = gated_message_consumer  # type: ignore[attr-defined]


# ------------------------------------------------------------------------------------------------ property cast
ORIGINAL_CAST: Any = props_api.AssignablePropsBase._cast_value_recursive
"""viser's own cast, kept for the test that compares the two."""

_FLOAT16, _FLOAT32, _FLOAT64, _UINT8 = (
    npt.NDArray[np.float16],
    npt.NDArray[np.float32],
    npt.NDArray[np.float64],
    npt.NDArray[np.uint8],
)


def cast_value_recursive(self: Any, hint: Any, value: Any, prop_name: str) -> Any:
    """viser 1.1.1's ``_cast_value_recursive``, line for line, with the ``NDArray`` aliases built once."""
    if hint == _FLOAT16:
        return np.asarray(value).astype(np.float16)
    elif hint == _FLOAT32:
        return np.asarray(value).astype(np.float32)
    elif hint == _FLOAT64:
        return np.asarray(value).astype(np.float64)
    elif hint == _UINT8 and "color" in prop_name:
        return props_api.colors_to_uint8(value)
    if isinstance(value, np.ndarray):
        return value
    if (
        isinstance(value, tuple)
        and hasattr(hint, "__origin__")
        and hint.__origin__ is tuple
        and hasattr(hint, "__args__")
        and len(hint.__args__) == 2
        and hint.__args__[1] is ...
    ):
        element_type = hint.__args__[0]
        return tuple(cast_value_recursive(self, element_type, item, prop_name) for item in value)
    return value


def patch_property_cast() -> bool:
    """Install :func:`cast_value_recursive` on viser's props base class; False (nothing done) on another viser."""
    if viser.__version__ != VISER_VERSION:
        return False
    props_api.AssignablePropsBase._cast_value_recursive = cast_value_recursive  # type: ignore[method-assign]
    return True


def installed_property_cast() -> Any:
    """The property cast viser's props base class uses now (the test checks that it is the patched one)."""
    return props_api.AssignablePropsBase._cast_value_recursive
