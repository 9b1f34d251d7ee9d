"""What a scene is built on: one browser tab's scene and GUI (a session), or the server's, shared by every tab.

A scene only uses ``self.server.scene``, ``.gui``, ``.atomic()``, ``.flush()`` and the helpers of
:class:`scenes._base.Scene`. :class:`Session` gives it exactly that API over either viser's per-client handles
(``client.scene``, ``client.gui``: only that tab sees them) or the server's (every tab sees them, ``--shared``).
Its ``gui`` is a :class:`GuiFacade`, which records each control's spec (range, options) the moment the scene
creates it, so the gate and the scene's readers clean a browser's value against what the scene declared.

:class:`Sessions` gives each browser tab its own :class:`~server.switcher.SceneSwitcher` when it connects and closes
it when the tab goes. viser 1.1.1 cannot remove a connect/disconnect or camera callback, so those are registered
once per server (here and in :class:`CameraHub`) and forward to whatever lives now; nothing a closed session owns
stays reachable from viser.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import threading
import weakref
from collections.abc import Callable
from contextlib import AbstractContextManager
from typing import TYPE_CHECKING, ParamSpec, TypeVar

import numpy as np
import viser

from server import viser_compat
from server.clean import record_spec
from server.gate import FinishedUpload, install_gate
from server.memory import give_memory_back
from server.viser_compat import dead_writes_allowed

if TYPE_CHECKING:
    from server.switcher import SceneSwitcher

logger = logging.getLogger(__name__)

P = ParamSpec("P")
H = TypeVar("H")


def _recording(add: Callable[P, H]) -> Callable[P, H]:
    """``add`` (a ``GuiApi.add_*`` method) that also records the new control's spec."""

    def add_and_record(*args: P.args, **kwargs: P.kwargs) -> H:
        handle = add(*args, **kwargs)
        record_spec(handle)
        return handle

    return add_and_record


class GuiFacade:
    """The part of viser's ``GuiApi`` the scenes use; every input control's spec is recorded when it is made."""

    def __init__(self, api: viser.GuiApi) -> None:
        self.api = api
        """The viser GUI API underneath (the server's or one client's)."""
        self.add_slider = _recording(api.add_slider)
        self.add_number = _recording(api.add_number)
        self.add_dropdown = _recording(api.add_dropdown)
        self.add_checkbox = _recording(api.add_checkbox)
        self.add_rgb = _recording(api.add_rgb)
        self.add_text = _recording(api.add_text)
        self.add_vector2 = _recording(api.add_vector2)
        self.add_vector3 = _recording(api.add_vector3)
        self.add_button = _recording(api.add_button)
        self.add_upload_button = _recording(api.add_upload_button)
        self.add_folder = api.add_folder
        self.add_markdown = api.add_markdown
        self.add_html = api.add_html
        self.add_image = api.add_image
        self.add_progress_bar = api.add_progress_bar
        self.add_uplot = api.add_uplot
        self.add_tab_group = api.add_tab_group
        self.configure_theme = api.configure_theme


class CameraReport:
    """One camera message as it came in: the values viser's camera handle held then, read once (any that cannot be
    read are read from the handle on use, and raise there as they would have). Writes (``position``, ``look_at``,
    ``up_direction``, ...) go to the live handle, and so to the tab.

    viser hands a camera callback the live handle on a thread pool, and a later message, or another listener's
    write to the handle (the framing's), may have replaced its values by the time a listener reads them: the SDF
    gallery once rendered its reference from a framing it wrote itself instead of the view the tab reported.
    """

    handle: viser.CameraHandle
    """The live handle (writes go to it)."""
    tab: object
    """Which tab reported it (its client id)."""

    _FIELDS = (
        "wxyz",
        "position",
        "look_at",
        "up_direction",
        "fov",
        "aspect",
        "near",
        "far",
        "image_width",
        "image_height",
    )

    def __init__(self, handle: viser.CameraHandle) -> None:
        values: dict[str, object] = {}
        for name in self._FIELDS:
            try:
                value = getattr(handle, name)
            except Exception:  # a handle with no report yet asserts, a crafted one may hold anything: read on use
                continue
            values[name] = value.copy() if isinstance(value, np.ndarray) else value
        try:
            tab: object = int(handle.client.client_id)
        except Exception:  # a handle without a client: one of its own
            tab = id(handle)
        object.__setattr__(self, "handle", handle)
        object.__setattr__(self, "tab", tab)
        object.__setattr__(self, "_values", values)

    @property
    def client(self) -> viser.ClientHandle:
        return self.handle.client

    def __getattr__(self, name: str) -> object:  # only names not set on the report itself
        values = object.__getattribute__(self, "_values")
        if name in values:
            return values[name]
        return getattr(object.__getattribute__(self, "handle"), name)

    def __setattr__(self, name: str, value: object) -> None:
        """Write through to the live handle. A report is read after its tab spoke, and the tab may have closed since
        (a camera framed for a tab as it goes): that write is lost without viser's "closed connection" warning."""
        try:
            client = self.handle.client
        except Exception:  # a handle without a client: nothing closes under it
            client = None
        with dead_writes_allowed(client) if isinstance(client, viser.ClientHandle) else contextlib.nullcontext():
            setattr(self.handle, name, value)


class CameraHub:
    """One set of viser camera callbacks per server (or per client), forwarding to whichever scenes listen now.

    viser 1.1.1 cannot remove an ``on_client_connect`` or camera callback, so a scene that registered its own would
    stay reachable (and keep being called) after it closed; scenes subscribe here instead. Each message reaches the
    listeners as a :class:`CameraReport` of its own values, in the order they came, one at a time, off the event loop
    (a tab's burst coalesced to its newest report); a listener that raises is logged and the others still hear of it.
    """

    def __init__(self, server: viser.ViserServer | None, client: viser.ClientHandle | None) -> None:
        self._listeners: list[Callable[[viser.CameraHandle], None]] = []
        self._lock = threading.Lock()
        self._pending: dict[object, CameraReport] = {}  # the newest report of each tab not yet heard, oldest first
        self._draining = False
        if client is not None:
            self._attach(client)
        elif server is not None:
            for other in server.get_clients().values():
                self._attach(other)
            server.on_client_connect(self._attach)

    def _attach(self, client: viser.ClientHandle) -> None:
        # A tab's first camera message connects it and then reaches this callback too; a tab already connected is
        # read by each listener as it subscribes (scenes._base.Scene.watch_cameras).
        client.camera.on_update(self._on_message)

    async def _on_message(self, camera: viser.CameraHandle) -> None:
        # A coroutine callback: viser awaits it on its event loop as it takes the message, so the report holds this
        # message's values (a plain callback runs later on viser's thread pool and reads whatever the handle holds
        # by then). The listeners run off the loop, on one thread at a time, in order, each tab's burst coalesced
        # to its newest report: a framing (which may redraw a scene under its lock) never holds up the server.
        report = CameraReport(camera)
        with self._lock:
            self._pending.pop(report.tab, None)
            self._pending[report.tab] = report
            if self._draining:
                return  # the thread draining the reports takes it
            self._draining = True
        asyncio.get_running_loop().run_in_executor(None, self._drain)

    def _drain(self) -> None:
        while True:
            with self._lock:
                if not self._pending:
                    self._draining = False
                    return
                report = self._pending.pop(next(iter(self._pending)))
                listeners = list(self._listeners)
            for listener in listeners:
                try:
                    listener(report)  # type: ignore[arg-type]  # a CameraReport reads as the handle does
                except Exception:
                    logger.exception("a camera listener failed; the others still hear of the camera")

    def add(self, listener: Callable[[viser.CameraHandle], None]) -> None:
        with self._lock:
            self._listeners.append(listener)

    def remove(self, listener: Callable[[viser.CameraHandle], None]) -> None:
        with self._lock:
            self._listeners = [other for other in self._listeners if other is not listener]

    @property
    def listener_count(self) -> int:
        with self._lock:
            return len(self._listeners)


_camera_hubs: weakref.WeakKeyDictionary[viser.ViserServer, CameraHub] = weakref.WeakKeyDictionary()
_camera_hubs_lock = threading.Lock()


def camera_hub(server: viser.ViserServer) -> CameraHub:
    """The server's one camera hub for every client (shared mode), made on first use."""
    with _camera_hubs_lock:
        hub = _camera_hubs.get(server)
        if hub is None:
            hub = _camera_hubs[server] = CameraHub(server, None)
        return hub


class Session:
    """The scene, GUI and cameras one scene draws on: one client's (:meth:`for_client`) or everyone's
    (:meth:`shared`)."""

    def __init__(
        self,
        server: viser.ViserServer,
        client: viser.ClientHandle | None,
        scene: viser.SceneApi,
        gui: viser.GuiApi,
        cameras: CameraHub,
    ) -> None:
        self.viser_server = server
        """The viser server this session is on."""
        self.client = client
        """The one browser tab this session serves, or None when it is shared by every tab."""
        self.scene = scene
        self.gui = GuiFacade(gui)
        self.cameras = cameras
        """Camera updates of the clients this session serves."""
        install_gate(server)
        self._dead_writes = contextlib.ExitStack()
        if client is not None:
            # Whatever this session writes after its tab closed (a callback, a loop step or a worker's result that
            # ran just then; its teardown waits for them) is lost with the tab, which drops the session: not the
            # stale-handle writes viser's one-shot "closed connection" warning is for. A click on "Goal chance"
            # as the tab closed logged "Queued a GuiUpdateMessage on a closed connection".
            self._dead_writes.enter_context(dead_writes_allowed(client))

    @classmethod
    def shared(cls, server: viser.ViserServer) -> Session:
        """The server's scene and GUI, which every browser tab sees."""
        return cls(server, None, server.scene, server.gui, camera_hub(server))

    @classmethod
    def for_client(cls, server: viser.ViserServer, client: viser.ClientHandle) -> Session:
        """One browser tab's own scene and GUI (viser's per-client API)."""
        return cls(server, client, client.scene, client.gui, CameraHub(None, client))

    def atomic(self) -> AbstractContextManager[None]:
        return (self.viser_server if self.client is None else self.client).atomic()

    def flush(self) -> None:
        (self.viser_server if self.client is None else self.client).flush()

    @staticmethod
    def send_download(client: viser.ClientHandle, filename: str, content: bytes) -> str:
        """Send tab ``client`` a download (a link in a notice); returns the notice's id, for :meth:`remove_notice`."""
        return viser_compat.send_download(client, filename, content)

    @staticmethod
    def remove_notification(client: viser.ClientHandle, notification: viser.NotificationHandle) -> None:
        """Take ``notification`` down in tab ``client``, which may have closed."""
        with dead_writes_allowed(client):
            notification.remove()

    @staticmethod
    def remove_notice(client: viser.ClientHandle, notice_id: str) -> None:
        """Take notice ``notice_id`` (e.g. a download's, which frees its file) down in tab ``client``."""
        with dead_writes_allowed(client):  # its tab may have closed
            viser_compat.remove_notice(client, notice_id)

    def remove_upload_notice(self, notice_id: str) -> None:
        """Take an upload's progress notice (``upload-<transfer id>``) down in every tab of this session: a shared
        upload button's acks reach every tab, and each shows the upload's progress; a tab other than the sender's
        kept "Uploading…" with its spinner for good once a Reset took the button away mid-upload."""
        for client in self.get_clients().values():
            self.remove_notice(client, notice_id)

    def finished_upload(self, event: object) -> FinishedUpload | None:
        """The upload an upload button's ``on_upload`` ``event`` reports, as the gate took it; None when unknown
        (:meth:`server.gate.Gate.finished_upload`)."""
        client_id, button = getattr(event, "client_id", None), getattr(event, "target", None)
        if not isinstance(client_id, int) or button is None:
            return None
        return install_gate(self.viser_server).finished_upload(client_id, button)

    def get_clients(self) -> dict[int, viser.ClientHandle]:
        """The clients this session serves, by id."""
        if self.client is None:
            return self.viser_server.get_clients()
        return {self.client.client_id: self.client}

    def frame_camera(self, position: tuple[float, float, float], look_at: tuple[float, float, float]) -> None:
        """Point this session's cameras (and, when shared, the cameras of tabs still to come) at a scene."""
        if self.client is None:
            self.viser_server.initial_camera.position = position
            self.viser_server.initial_camera.look_at = look_at
        for client in self.get_clients().values():
            with client.atomic(), dead_writes_allowed(client):  # a tab may close as it is framed
                client.camera.position = position
                client.camera.look_at = look_at


class Sessions:
    """A :class:`~server.switcher.SceneSwitcher` per browser tab: built when it connects, closed when it goes."""

    def __init__(self, server: viser.ViserServer, initial: str) -> None:
        from scenes import SCENES

        if initial not in SCENES:
            raise ValueError(f"scene must be one of {sorted(SCENES)}, got {initial!r}")
        self.server = server
        self.initial = initial
        self._lock = threading.Lock()
        self._switchers: dict[int, SceneSwitcher] = {}
        install_gate(server)
        server.on_client_connect(self._open)
        server.on_client_disconnect(self._close)

    def switcher(self, client_id: int) -> SceneSwitcher | None:
        """The switcher of the tab ``client_id``, or None (not built yet, or gone)."""
        with self._lock:
            return self._switchers.get(client_id)

    @property
    def count(self) -> int:
        with self._lock:
            return len(self._switchers)

    def _connected(self, client: viser.ClientHandle) -> bool:
        """Whether ``client``'s tab is still open (viser forgets a client before its disconnect callbacks run)."""
        return client.client_id in self.server.get_clients()

    def _open(self, client: viser.ClientHandle) -> None:
        from server.switcher import SceneSwitcher

        # Connect and disconnect callbacks run on viser's thread pool, in any order: a tab that closed before its
        # build began gets none, and one that closes during the build is torn down when the build ends.
        if not self._connected(client):
            return
        try:
            # (What the build queues after the tab went is lost with it, without a warning: see Session.)
            switcher = SceneSwitcher(Session.for_client(self.server, client), self.initial)
        except Exception:
            logger.exception("building the session of client %s failed", client.client_id)
            return
        with self._lock:
            # Checked under the lock that _close takes: either the tab is still known here (and _close, which
            # viser calls after forgetting it, finds this switcher) or it is gone and nobody else will close it.
            gone = not self._connected(client)
            if not gone:
                self._switchers[client.client_id] = switcher
        if gone:
            self._close_switcher(client, switcher)
            del switcher  # the last reference: the collection below frees the session
            give_memory_back()

    def _close(self, client: viser.ClientHandle) -> None:
        with self._lock:
            switcher = self._switchers.pop(client.client_id, None)
        if switcher is not None:
            self._close_switcher(client, switcher)
            del switcher  # the last reference: the collection below frees the session
            give_memory_back()

    def _close_switcher(self, client: viser.ClientHandle, switcher: SceneSwitcher) -> None:
        """Close a tab's session and wait for its scene's threads (a thread-pool callback: off the event loop)."""
        try:
            switcher.close()  # (its session writes to its closed tab without a warning)
            if not switcher.scene.join(timeout_s=120.0):
                logger.warning("session of client %s: a scene thread is still running", client.client_id)
        except Exception:
            logger.exception("closing the session of client %s failed", client.client_id)

    def close(self) -> None:
        """Close every session (the server stays up)."""
        with self._lock:
            switchers = list(self._switchers.values())
            self._switchers.clear()
        for switcher in switchers:  # a tab may be closing now: its session writes to it without a warning
            switcher.close()
