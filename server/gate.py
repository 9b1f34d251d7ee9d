"""One gate for every message a browser sends: it cleans what may come through and refuses the rest.

viser 1.1.1 applies whatever a client's message names: a ``GuiUpdateMessage`` may set any attribute of a GUI handle
(``props``, ``update_cb``, ``removed``), a gizmo update carries arrays of any length, a camera any image size, and a
frame that does not decode ends the sender's connection with a traceback. Only three things may come from a browser:

- a control's **value**: of the control's own kind (a checkbox takes only ``True``/``False``, a slider only a finite
  number, clamped to the range the scene declared, a dropdown only one of its options);
- a gizmo's **pose**: 3 finite numbers for the position and 4 finite numbers for the orientation, normalised; a
  zero or non-finite quaternion, or a wrong length, keeps the last good pose;
- a **camera**: finite numbers, a unit quaternion, positive image sizes; otherwise the client's last good camera.

Everything else is refused, and each kind of refusal is logged once (one line, no traceback) per
:attr:`server.refusals.RefusalLog.interval_s`, with a count of the ones left unlogged. The server's value is sent
back to the sender only where the sender may show another (:meth:`Gate._echo`): after a refusal, after a clean that
changed the value, and when another tab or the scene wrote the control a moment before (so two browsers moving one
slider a few milliseconds apart end on the same value). Not while a person may still be typing: viser's page sends
a box's value at every keystroke, and a value sent back over the box reset what was being typed.

Frames are decoded by :mod:`server.decode`; values are cleaned against each control's recorded spec
(:mod:`server.clean`); the costly-input and upload budgets are :mod:`server.budget`'s. What the gate needs of viser's
internals (its dispatch, registries and frame decoder) it reaches through :mod:`server.viser_compat` only.
"""

from __future__ import annotations

import asyncio
import dataclasses
import functools
import math
import threading
import time
import weakref
from collections.abc import Callable
from typing import Any

import viser

from server import budget, viser_compat
from server.budget import (
    MAX_NAME_CHARS,
    MAX_UPLOAD_BYTES,
    MAX_UPLOAD_BYTES_IN_FLIGHT_PER_TAB,
    MAX_UPLOAD_BYTES_IN_FLIGHT_TOTAL,
    MAX_UPLOADS_IN_FLIGHT,
    MAX_UPLOADS_IN_FLIGHT_TOTAL,
    MIB,
    MIN_PART_BYTES,
    CostlyBudget,
    TabBudget,
    Upload,
)
from server.clean import ControlSpec, clean_value, control_spec, finite_vector, unit_quaternion
from server.decode import ALLOWED_MESSAGES, camera_fields, click_problem, decode_frame
from server.refusals import refusals
from server.viser_compat import Dispatch, messages

IN_LINE = (
    messages.GuiUpdateMessage,
    messages.TransformControlsUpdateMessage,
    messages.TransformControlsDragStartMessage,
    messages.TransformControlsDragEndMessage,
    messages.SceneNodeClickMessage,
    messages.ScenePointerMessage,
)
"""The inputs a tab's held-back or running scene switch or Reset keeps in line behind it: values, drags, clicks."""
UNREGISTERED_MAY_SEND = (messages.ViewerCameraMessage, messages.GetRenderResponseMessage)
"""What a tab may send before viser has registered it (at its first usable camera); any input is refused until then."""
ECHO_AFTER_TYPING_S = 1.5
"""A value clamped up from nearer zero than the control's range (the "7" on the way to "75" in a box of 30..150)
is sent back to its tab only after the tab has sent nothing to that control for this long: more digits may still
bring it into range, and viser's box clamps by itself when it loses focus."""
ECHO_IN_FLIGHT_S = 1.0
"""A value of a control sent to a tab this recently (another tab's edit, the scene's write, a send-back) may reach
it after the tab's own next edit of that control: that edit's value is then sent back too, so the tab ends on it."""


@dataclasses.dataclass(frozen=True)
class FinishedUpload:
    """An upload a tab finished, as the gate took it (:meth:`Gate.finished_upload`)."""

    started_at: float
    """When (``time.monotonic()``) the gate took its start: a scene tells a file picked before its user's later
    choice (which the file, still arriving, would otherwise overrule) from one picked after."""
    transfer_uuid: str

    @property
    def notice_id(self) -> str:
        """The id of viser's own notice of it in its tab ("Uploading…", then "File uploaded successfully"): a scene
        that refuses the file takes it down, so that its refusal is the one message the tab shows about the file."""
        return viser_compat.upload_notice_id(self.transfer_uuid)


class Gate:
    """The one gate in front of one server's message dispatch. Made by :func:`install_gate`.

    Besides cleaning, it shares two budgets out fairly: costly inputs per tab (:func:`~server.clean.mark_costly`), so
    one tab flooding Reset or scene switches cannot fill viser's callback pool and delay every other tab; and uploads in
    flight across all tabs (:data:`MAX_UPLOADS_IN_FLIGHT_TOTAL`, :data:`MAX_UPLOAD_BYTES_IN_FLIGHT_TOTAL`).
    """

    def __init__(self, server: viser.ViserServer) -> None:
        self._server_ref = weakref.ref(server)
        self.log = refusals
        self._client_dispatch: dict[int, Dispatch] = {}
        self._uploads: dict[int, dict[str, Upload]] = {}
        """Per client, the uploads started and not finished, by transfer id."""
        self._seen_at: dict[tuple[int, str], float] = {}
        """Per (tab, control uuid), the control's ``update_timestamp`` after the tab's last edit of it was applied."""
        self._echoes: dict[tuple[int, str], asyncio.TimerHandle] = {}
        """Per (tab, control uuid), a send-back waiting for the tab to stop typing (:data:`ECHO_AFTER_TYPING_S`)."""
        self._echoed_at: dict[tuple[int, str], float] = {}
        """Per (tab, control uuid), when the server's value was last sent back to that tab."""
        self._finished_uploads: dict[tuple[int, str], FinishedUpload] = {}
        """The last upload each (client, upload button) finished (:meth:`finished_upload`)."""
        self._budgets: dict[int, TabBudget] = {}
        """Per client, its costly-input budget (only touched on the event loop)."""
        self._deliveries: set[asyncio.Future[None]] = set()
        self._server_dispatch: Dispatch = viser_compat.install_message_filter(
            server, self._dispatch, self._on_connect, self._on_disconnect
        )

    # Every message reaches viser's server-scoped and its connection-scoped handlers (two tasks). The gate takes
    # the connection's dispatch for itself and runs both from one place, after cleaning.
    def _on_connect(self, connection: Any) -> None:
        self._client_dispatch[int(connection.client_id)] = viser_compat.take_connection_dispatch(connection)
        connection.queue_message(messages.RunJavascriptMessage(source=CSS_CAMERA_JS))

    def _on_disconnect(self, connection: Any) -> None:
        client_id = int(connection.client_id)
        self._client_dispatch.pop(client_id, None)
        self._uploads.pop(client_id, None)
        for key in [key for key in list(self._finished_uploads) if key[0] == client_id]:
            self._finished_uploads.pop(key, None)
        for key in [key for key in list(self._seen_at) if key[0] == client_id]:
            self._seen_at.pop(key, None)
        for key in [key for key in list(self._echoes) if key[0] == client_id]:
            self._echoes.pop(key).cancel()
        for key in [key for key in list(self._echoed_at) if key[0] == client_id]:
            self._echoed_at.pop(key, None)
        tab = self._budgets.pop(client_id, None)
        if tab is not None and tab.timer is not None:
            tab.timer.cancel()

    async def _dispatch(self, client_id: Any, message: Any) -> None:
        server = self._server_ref()
        if server is None:
            return
        try:
            cleaned, after = self._clean(server, int(client_id), message)
            if isinstance(cleaned, IN_LINE) and not self._admit(server, int(client_id), cleaned, after):
                return  # held back, coalesced: delivered when the tab's budget allows
        except Exception as error:  # a gate bug must not take the connection down, nor let the message through
            self.log.refuse(f"unreadable {type(message).__name__}", f"{type(error).__name__}: {error}")
            return
        await self._deliver(client_id, cleaned, after)

    async def _deliver(self, client_id: Any, cleaned: Any, after: Callable[[], None] | None) -> None:
        if cleaned is not None:
            await self._server_dispatch(client_id, cleaned)
            client_dispatch = self._client_dispatch.get(int(client_id))
            if client_dispatch is not None:
                await client_dispatch(client_id, cleaned)
        if after is not None:
            after()

    # ----------------------------------------------------------------------------------------- costly inputs
    def _admit(self, server: viser.ViserServer, client_id: int, message: Any, after: Callable[[], None] | None) -> bool:
        """Whether ``message`` goes through now; a costly input beyond the tab's budget is held back instead, and
        so is any input of that tab behind it (in line, free of the budget): a cheap edit or a drag that follows a
        held-back Reset or scene switch would otherwise be applied first and then undone by it."""
        tab = self._budgets.get(client_id)
        if isinstance(message, messages.GuiUpdateMessage):
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
            tab = self._budgets[client_id] = TabBudget(CostlyBudget(budget.COSTLY_BURST, budget.COSTLY_RATE_HZ, now))
        goes, replaced = tab.budget.offer(key, (message, after, None), now)
        if goes:
            self._deliver_costly(client_id, tab, message, after)
            return False  # on its way, tracked
        self.log.refuse(
            "costly input beyond the tab's budget (held back; the latest value is applied)",
            f"{str(getattr(handle, 'label', '?'))!r} from client {client_id}"
            f"{', replacing one held back' if replaced else ''} (budget {budget.COSTLY_BURST} at once, "
            f"{budget.COSTLY_RATE_HZ:g}/s)",
        )
        self._schedule(client_id, tab)
        return False

    def _is_costly(self, server: viser.ViserServer, client_id: int, message: Any) -> bool:
        if not isinstance(message, messages.GuiUpdateMessage):
            return False
        handle = self._gui_handle(server, client_id, str(message.uuid))
        return handle is not None and control_spec(handle).costly

    def _deliver_costly(self, client_id: int, tab: TabBudget, message: Any, after: Callable[[], None] | None) -> None:
        """Deliver a costly input as a task; until its handler has finished, the tab's cheap inputs wait."""
        tab.in_flight += 1

        def finished(_task: object) -> None:
            tab.in_flight -= 1
            if self._budgets.get(client_id) is tab:
                self._schedule(client_id, tab)

        self._start(client_id, message, after).add_done_callback(finished)

    def _start(self, client_id: int, message: Any, after: Callable[[], None] | None) -> asyncio.Future[None]:
        task = asyncio.ensure_future(self._deliver(client_id, message, after))
        self._deliveries.add(task)  # asyncio keeps only a weak reference to a running task
        task.add_done_callback(self._deliveries.discard)
        return task

    def _schedule(self, client_id: int, tab: TabBudget) -> None:
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
                if isinstance(message, messages.GuiUpdateMessage) and self._gui_handle(server, client_id, key) is None:
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

    def _control_path(self, server: viser.ViserServer, client_id: int, handle: Any) -> tuple[type, str]:
        """(handle type, its label under the labels of the folders it sits in): which control it is to a person,
        the same for a control rebuilt by a Reset and different in another scene (under another scene's folder)."""
        names = [str(getattr(handle, "label", ""))]
        parent = viser_compat.parent_container_id(handle)
        for _ in range(32):  # folders nest a few deep; a cycle would be viser's bug, not a hang here
            if parent == "root":
                break
            container = viser_compat.gui_container_by_uuid(server, client_id, parent)
            if container is None:
                break
            names.append(str(getattr(container, "label", type(container).__name__)))
            parent = viser_compat.parent_container_id(container)
        return type(handle), " / ".join(reversed(names))

    def _retarget(
        self,
        server: viser.ViserServer,
        client_id: int,
        message: messages.GuiUpdateMessage,
        label: tuple[type, str] | None,
    ) -> tuple[Any, Callable[[], None] | None]:
        """``message`` sent to the one live control of ``label`` (its handle type and label) instead, cleaned
        against that control's own spec; (None, None) when there is no such control or more than one."""
        if label is None:
            return None, None
        client = self._client(server, client_id)
        registries = [viser_compat.gui_inputs(server.gui)]
        if client is not None:
            registries.append(viser_compat.gui_inputs(client.gui))
        matches = [
            uuid
            for registry in registries
            for uuid, handle in list(registry.items())
            if type(handle) is label[0]
            and not viser_compat.is_removed(handle)
            and self._control_path(server, client_id, handle) == label
        ]
        if len(matches) != 1:
            return None, None
        return self._clean_gui(server, client_id, messages.GuiUpdateMessage(matches[0], message.updates))

    def finished_upload(self, client_id: int, button: object) -> FinishedUpload | None:
        """The last upload tab ``client_id`` finished on upload button ``button``; None if none has. A scene reads it
        in the button's ``on_upload``."""
        return self._finished_uploads.get((client_id, viser_compat.gui_uuid(button)))

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

    def costly_in_flight(self, client_id: int) -> int:
        """How many costly inputs of ``client_id`` were delivered and their handlers have not finished (a scene
        switch or Reset still rebuilding)."""
        tab = self._budgets.get(client_id)
        return 0 if tab is None else tab.in_flight

    def _client(self, server: viser.ViserServer, client_id: int) -> viser.ClientHandle | None:
        return viser_compat.connected_client(server, client_id)

    def _clean(self, server: viser.ViserServer, client_id: int, message: Any) -> tuple[Any, Callable[[], None] | None]:
        if not isinstance(message, UNREGISTERED_MAY_SEND) and self._client(server, client_id) is None:
            # viser registers a tab at its first camera; before that it still stores and relays a value or a gizmo
            # pose, but runs no callback: every viewer would see a control that no longer describes the picture.
            self.log.refuse("input from a tab that has sent no camera yet", f"{type(message).__name__}")
            return None, None
        if isinstance(message, messages.GuiUpdateMessage):
            return self._clean_gui(server, client_id, message)
        if isinstance(message, messages.TransformControlsUpdateMessage):
            return self._clean_gizmo(server, client_id, message)
        if isinstance(message, messages.ViewerCameraMessage):
            return self._clean_camera(server, client_id, message), None
        if isinstance(message, messages.TransformControlsDragEndMessage):
            # A drag ends: every viewer, the dragging one too, is sent the gizmo's pose on the server (during the
            # drag the sender is not, so its own gizmo does not fight the mouse).
            handle = self._gizmo_handle(server, client_id, str(message.name), str(message.owner))
            return message, None if handle is None else functools.partial(viser_compat.send_gizmo_pose, handle)
        if isinstance(message, (messages.ScenePointerMessage, messages.SceneNodeClickMessage)):
            reason = click_problem(message)
            if reason:
                self.log.refuse(f"click ({reason})", f"{type(message).__name__}")
                return None, None
            return message, None
        if isinstance(message, messages.FileTransferStartUpload):
            return self._clean_upload_start(server, client_id, message)
        if isinstance(message, messages.FileTransferPart):
            return self._clean_upload_part(server, client_id, message)
        if isinstance(message, ALLOWED_MESSAGES):
            return message, None
        self.log.refuse("message type", f"{type(message).__name__} is not one a browser may send")
        return None, None

    def _gui_handle(self, server: viser.ViserServer, client_id: int, uuid: str) -> Any:
        return viser_compat.gui_input_by_uuid(server, client_id, uuid)

    def _clean_gui(
        self, server: viser.ViserServer, client_id: int, message: messages.GuiUpdateMessage
    ) -> tuple[Any, Callable[[], None] | None]:
        updates = message.updates
        if not isinstance(updates, dict) or set(updates) != {"value"}:
            fields = sorted(str(key)[:40] for key in updates) if isinstance(updates, dict) else updates
            self.log.refuse("GUI update of a field other than value", f"fields {fields!r}")
            return None, None
        handle = self._gui_handle(server, client_id, str(message.uuid))
        if handle is None:
            self.log.refuse("GUI update for an unknown id", f"uuid {str(message.uuid)[:64]!r}")
            return None, None
        spec = control_spec(handle)
        accepted, value, reason = clean_value(spec, updates["value"])
        key = (client_id, str(message.uuid))
        waiting = self._echoes.pop(key, None)
        if waiting is not None:  # the tab is still at it: its newer value decides
            waiting.cancel()

        # After a refusal the sender still shows its own edit: every viewer is sent the server's value.
        def send_back() -> None:
            client = self._client(server, client_id)
            if client is None:  # the tab has gone: nobody shows its edit
                return
            self._echoed_at[key] = time.monotonic()
            with viser_compat.dead_writes_allowed(client):  # it may be closing now: no warning for a lost write
                viser_compat.send_gui_value(handle)

        if not accepted:
            label = str(getattr(handle, "label", "?"))
            self.log.refuse(f"GUI value ({reason})", f"{label!r} got {updates['value']!r}"[:200])
            if spec.kind == "text" and isinstance(updates["value"], str):  # a paste too long: say so to its tab
                tell = self._tell(
                    server,
                    client_id,
                    f"That text was {len(updates['value']):,} characters long; “{label}” takes at most "
                    f"{spec.max_chars:,}, so the previous text is back.",
                    title="Text refused",
                )

                def send_back_and_tell() -> None:
                    send_back()
                    tell()

                return None, send_back_and_tell
            return None, send_back
        return messages.GuiUpdateMessage(message.uuid, {"value": value}), self._echo(
            key, handle, spec, updates["value"], value, send_back
        )

    def _echo(
        self,
        key: tuple[int, str],
        handle: Any,
        spec: ControlSpec,
        sent: object,
        value: object,
        send_back: Callable[[], None],
    ) -> Callable[[], None]:
        """What to send tab ``key[0]`` after its value ``sent`` for control ``key[1]`` was accepted as ``value``.

        viser sends an accepted value to every other viewer, but not to its sender, which shows what it sent. So the
        sender is sent the server's value only where it may show another: at once after a value sent to it that may
        arrive after its edit (another tab's or the scene's write, or an earlier send-back, within
        :data:`ECHO_IN_FLIGHT_S`) or after a clean it cannot foresee; once it stops typing where more typing may still
        bring the value into range (:data:`ECHO_AFTER_TYPING_S`); otherwise never, so a box being typed in keeps
        its text. Whatever is sent, the write that this edit makes is then counted as seen by the tab.
        """
        written_at = float(handle.update_timestamp)  # the last write of this control, by anyone (time.time())
        written_to_it = time.time() - written_at < ECHO_IN_FLIGHT_S and written_at > self._seen_at.get(key, 0.0)
        echoed = time.monotonic() - self._echoed_at.get(key, -math.inf) < ECHO_IN_FLIGHT_S

        def seen() -> None:
            self._seen_at[key] = float(handle.update_timestamp)

        def now() -> None:
            seen()
            send_back()

        if written_to_it or echoed:
            return now
        if same_value(sent, value):
            return seen
        if spec.kind == "number" and _may_be_typed_on(sent, spec):

            def later() -> None:
                seen()

                def echo() -> None:
                    self._echoes.pop(key, None)
                    send_back()

                self._echoes[key] = asyncio.get_running_loop().call_later(ECHO_AFTER_TYPING_S, echo)

            return later
        return now

    def _clean_upload_start(
        self, server: viser.ViserServer, client_id: int, message: messages.FileTransferStartUpload
    ) -> tuple[Any, Callable[[], None] | None]:
        handle = self._gui_handle(server, client_id, str(message.source_component_uuid))
        size, parts = message.size_bytes, message.part_count
        if not isinstance(handle, viser.GuiUploadButtonHandle):
            self.log.refuse("upload for an unknown id", f"uuid {str(message.source_component_uuid)[:64]!r}")
            return None, None
        if not all(isinstance(x, int) and not isinstance(x, bool) for x in (size, parts)) or (
            not 0 <= parts <= max(1, -(-size // MIN_PART_BYTES)) or (size > 0) != (parts > 0)
        ):
            self.log.refuse("upload size", f"{size!r} bytes in {parts!r} parts")
            return None, None
        if not 0 <= size <= MAX_UPLOAD_BYTES:
            return self._refused_start(
                server,
                client_id,
                message,
                ("upload size", f"{size!r} bytes (limit {MAX_UPLOAD_BYTES})"),
                f"The file is {size / MIB:.1f} MiB; this server takes files up to {MAX_UPLOAD_BYTES / MIB:.0f} MiB.",
            )
        if not all(
            isinstance(x, str) and len(x) <= MAX_NAME_CHARS
            for x in (message.filename, message.mime_type, message.transfer_uuid)
        ):
            self.log.refuse("upload name", "file name, type or transfer id is not short text")
            return None, None
        self._drop_stalled_uploads(server)
        if any(message.transfer_uuid in uploads for uploads in list(self._uploads.values())):
            # A second start under an id in flight (a crafted tab's: acks go to the sender alone) would mix
            # another tab's parts into the first tab's file.
            self.log.refuse("upload transfer id", "already in flight")
            return None, None
        in_flight = self._uploads.setdefault(client_id, {})
        if len(in_flight) >= MAX_UPLOADS_IN_FLIGHT:
            return self._refused_start(
                server,
                client_id,
                message,
                ("uploads in flight", f"more than {MAX_UPLOADS_IN_FLIGHT} at once"),
                f"This tab already has {MAX_UPLOADS_IN_FLIGHT} uploads under way; wait for one to finish.",
            )
        own_bytes = sum(upload.size_bytes for upload in list(in_flight.values()))
        if own_bytes + size > MAX_UPLOAD_BYTES_IN_FLIGHT_PER_TAB:
            return self._refused_start(
                server,
                client_id,
                message,
                (
                    "upload bytes in flight",
                    f"{own_bytes} + {size} bytes from one tab (limit {MAX_UPLOAD_BYTES_IN_FLIGHT_PER_TAB})",
                ),
                f"This tab's uploads under way already announce {own_bytes / MIB:.1f} MiB; it takes "
                f"{MAX_UPLOAD_BYTES_IN_FLIGHT_PER_TAB / MIB:.0f} MiB at once. Wait for them to finish.",
            )
        count, total_bytes = self.uploads_in_flight()
        if count >= MAX_UPLOADS_IN_FLIGHT_TOTAL or total_bytes + size > MAX_UPLOAD_BYTES_IN_FLIGHT_TOTAL:
            return self._refused_start(
                server,
                client_id,
                message,
                (
                    "uploads in flight across all tabs",
                    f"{count} uploads of {total_bytes} bytes under way, {size} more asked (limits "
                    f"{MAX_UPLOADS_IN_FLIGHT_TOTAL} uploads, {MAX_UPLOAD_BYTES_IN_FLIGHT_TOTAL} bytes)",
                ),
                f"The server is receiving other uploads ({count} files, "
                f"{total_bytes / MIB:.1f} MiB in flight from all tabs; it takes "
                f"{MAX_UPLOADS_IN_FLIGHT_TOTAL} files or {MAX_UPLOAD_BYTES_IN_FLIGHT_TOTAL / MIB:.0f} MiB at "
                "once). Try again in a moment.",
            )
        now, button = time.monotonic(), str(message.source_component_uuid)
        if parts > 0:
            in_flight[message.transfer_uuid] = Upload(
                parts, size, now, now, button_uuid=button, filename=str(message.filename)
            )
        else:  # viser finishes an empty file at its start
            self._finished_uploads[(client_id, button)] = FinishedUpload(now, str(message.transfer_uuid))
        return message, None

    def _tell(
        self, server: viser.ViserServer, client_id: int, body: str, title: str = "Upload refused"
    ) -> Callable[[], None]:
        """A notification of a refused upload or text for the tab that sent it (shown after the refusal)."""

        def notify() -> None:
            client = self._client(server, client_id)
            if client is not None:
                client.add_notification(title, body, color="red", auto_close_seconds=15.0)

        return notify

    def _refused_start(
        self,
        server: viser.ViserServer,
        client_id: int,
        start: messages.FileTransferStartUpload,
        refusal: tuple[str, str],
        body: str,
    ) -> tuple[None, Callable[[], None]]:
        """Refuse upload ``start`` (logged as ``refusal``: its kind and detail) and give what its tab is then sent:
        the upload ended there, so its button works again (:func:`~server.viser_compat.end_refused_upload`), then
        a notice that says why (``body``)."""
        self.log.refuse(*refusal)
        tell = self._tell(server, client_id, body)
        transfer = start.transfer_uuid
        if not (isinstance(transfer, str) and len(transfer) <= MAX_NAME_CHARS):
            return None, tell  # not a transfer viser's client could have started

        def end_then_tell() -> None:
            viser_compat.end_refused_upload(
                server, client_id, str(start.source_component_uuid), transfer, start.size_bytes
            )
            tell()

        return None, end_then_tell

    def _drop_stalled_uploads(self, server: viser.ViserServer) -> None:
        """Forget uploads that received no part for :data:`~server.budget.UPLOAD_STALL_S`, and free the parts viser
        holds."""
        now = time.monotonic()
        for client_id, uploads in list(self._uploads.items()):
            for transfer, upload in list(uploads.items()):
                stalled = now - upload.last_part_at >= budget.UPLOAD_STALL_S
                late = now - upload.started_at >= budget.UPLOAD_DEADLINE_S
                if not (stalled or late):
                    continue
                del uploads[transfer]
                self.log.refuse(
                    "stalled upload",
                    f"no part for {budget.UPLOAD_STALL_S:g} s"
                    if stalled
                    else f"not finished {budget.UPLOAD_DEADLINE_S:g} s after its start",
                )
                viser_compat.drop_upload_parts(server, client_id, transfer)

    def _clean_upload_part(
        self, server: viser.ViserServer, client_id: int, message: messages.FileTransferPart
    ) -> tuple[Any, Callable[[], None] | None]:
        upload = self._uploads.get(client_id, {}).get(str(message.transfer_uuid))
        index, content = message.part_index, message.content
        if upload is None or not isinstance(index, int) or not 0 <= index < upload.part_count:
            self.log.refuse("upload part", "for no upload in flight, or out of range")
            return None, None
        if index in upload.parts_seen:
            self.log.refuse("upload part", "sent twice")
            return None, None
        if not isinstance(content, bytes) or upload.bytes_seen + len(content) > upload.size_bytes:
            self.log.refuse("upload part", "more bytes than the upload announced")
            return None, None
        upload.bytes_seen += len(content)
        upload.parts_seen.add(index)
        upload.last_part_at = time.monotonic()
        if len(upload.parts_seen) < upload.part_count:
            return message, None
        transfer = str(message.transfer_uuid)
        del self._uploads[client_id][transfer]
        self._finished_uploads[(client_id, upload.button_uuid)] = FinishedUpload(upload.started_at, transfer)
        if self._gui_handle(server, client_id, upload.button_uuid) is not None:
            return message, None
        # Its button went while the file arrived (a Reset or a scene switch): viser acks the last part, which its
        # client shows as "File uploaded successfully", and drops the file. Take that notice down and say so.
        name = upload.filename[:80] or "The file"
        tell = self._tell(
            server,
            client_id,
            f"{name} was still arriving when the scene was reset or switched, so it was not loaded. "
            "Upload it again to use it.",
            title="File not loaded",
        )

        def take_down_then_tell() -> None:
            for client in server.get_clients().values():  # a shared button's acks showed it in every tab
                with viser_compat.dead_writes_allowed(client):
                    viser_compat.remove_notice(client, viser_compat.upload_notice_id(transfer))
            tell()

        return message, take_down_then_tell

    def _gizmo_handle(self, server: viser.ViserServer, client_id: int, name: str, owner: str) -> Any:
        return viser_compat.gizmo_by_name(server, client_id, name, owner)

    def _clean_gizmo(
        self, server: viser.ViserServer, client_id: int, message: messages.TransformControlsUpdateMessage
    ) -> tuple[Any, Callable[[], None] | None]:
        handle = self._gizmo_handle(server, client_id, str(message.name), str(message.owner))
        if handle is None:
            self.log.refuse("gizmo update for an unknown gizmo", f"name {str(message.name)[:64]!r}")
            return None, None
        position = finite_vector(message.position, 3)
        wxyz = unit_quaternion(message.wxyz)
        if position is not None and wxyz is not None:
            return dataclasses.replace(message, position=position, wxyz=wxyz), None
        if position is None:
            self.log.refuse("gizmo position (not 3 finite numbers)", f"{message.position!r}"[:200])
        if wxyz is None:
            self.log.refuse("gizmo orientation (not 4 finite numbers, or all zero)", f"{message.wxyz!r}"[:200])
        last_position = tuple(float(v) for v in handle.position)
        last_wxyz = tuple(float(v) for v in handle.wxyz)
        cleaned = dataclasses.replace(
            message,
            position=position if position is not None else last_position,
            wxyz=wxyz if wxyz is not None else last_wxyz,
        )
        return cleaned, functools.partial(viser_compat.send_gizmo_pose, handle)

    def _clean_camera(
        self, server: viser.ViserServer, client_id: int, message: messages.ViewerCameraMessage
    ) -> messages.ViewerCameraMessage | None:
        fields, wrong = camera_fields(message)
        if fields is not None:
            return messages.ViewerCameraMessage(**fields)
        client = self._client(server, client_id)
        self.log.refuse(
            "camera (non-finite, out of bounds, or an image size that is not a positive integer)",
            f"{wrong} = {str(getattr(message, wrong.split('/')[0], ''))[:80]}",
        )
        if client is None:
            return None  # a first camera that is unusable: the client is not registered until a good one comes
        camera = client.camera
        return messages.ViewerCameraMessage(
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


_gates: weakref.WeakKeyDictionary[viser.ViserServer, Gate] = weakref.WeakKeyDictionary()
_gates_lock = threading.Lock()


def install_gate(server: viser.ViserServer) -> Gate:
    """Put the gate in front of ``server``'s dispatch (once per server; later calls return the same gate).

    Install it before browsers connect: a connection opened earlier keeps viser's own connection-scoped dispatch.
    """
    with _gates_lock:
        gate = _gates.get(server)
        if gate is None:
            viser_compat.install_frame_decoder(decode_frame)
            viser_compat.route_upload_acks(server)
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


def same_value(sent: object, value: object) -> bool:
    """Whether a browser that sent (or shows) ``sent`` shows the control's value ``value``: a number as int or float,
    a vector as list or tuple."""
    if isinstance(sent, (list, tuple)) and isinstance(value, (list, tuple)):
        return len(sent) == len(value) and all(same_value(a, b) for a, b in zip(sent, value, strict=True))
    if isinstance(sent, bool) or isinstance(value, bool):
        return sent is value
    if isinstance(sent, (int, float)) and isinstance(value, (int, float)):
        return float(sent) == float(value)
    return type(sent) is type(value) and sent == value


def _may_be_typed_on(sent: object, spec: ControlSpec) -> bool:
    """Whether number ``sent``, outside ``spec``'s range, lies between zero and the range: a box's text on its way to
    a number in range (typing a digit moves a number away from zero, never towards it)."""
    if isinstance(sent, bool) or not isinstance(sent, (int, float)) or not math.isfinite(sent):
        return False
    return (spec.lo is not None and 0.0 <= sent < spec.lo) or (spec.hi is not None and spec.hi < sent <= 0.0)
