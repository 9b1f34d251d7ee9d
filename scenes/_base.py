"""What every scene shares: one root frame, one GUI folder, guarded callbacks and untrusted-input cleaning.

A scene owns every viser handle it creates. It puts its 3D nodes under the frame ``/<key>`` and its GUI under one
folder, so :meth:`Scene.close` removes everything with two calls (viser cascades removal to children) and stops
any thread the scene started.

Every value a browser sends is untrusted: a crafted client can send NaN, a number outside a slider's range, or an
option that is not in a dropdown. Scenes read GUI values only through :meth:`Scene.read_number`,
:meth:`Scene.read_choice` and :meth:`Scene.read_bool`, which clamp or fall back to the last good value and write the
cleaned value back to the GUI, and wrap every callback in :meth:`Scene.callback`, which serialises callbacks (viser
runs plain callbacks on a thread pool) and logs, rather than raises, anything that goes wrong.
"""

from __future__ import annotations

import abc
import functools
import logging
import math
import threading
import time
import weakref
from collections.abc import Callable, Sequence
from typing import Any, ClassVar, TypeVar

import numpy as np
import viser

logger = logging.getLogger(__name__)

T = TypeVar("T")


class _CameraHub:
    """One set of viser camera callbacks per server, forwarding to whichever scenes listen now.

    viser 1.1.1 cannot remove an ``on_client_connect`` or camera callback, so a scene that registered its own would
    stay reachable (and keep being called) after it closed; scenes subscribe here instead.
    """

    def __init__(self, server: viser.ViserServer) -> None:
        self._listeners: list[Callable[[viser.CameraHandle], None]] = []
        self._lock = threading.Lock()
        for client in server.get_clients().values():
            self._attach(client)
        server.on_client_connect(self._attach)

    def _attach(self, client: viser.ClientHandle) -> None:
        client.camera.on_update(self._dispatch)
        self._dispatch(client.camera)

    def _dispatch(self, camera: viser.CameraHandle) -> None:
        with self._lock:
            listeners = list(self._listeners)
        for listener in listeners:
            listener(camera)

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


_camera_hubs: weakref.WeakKeyDictionary[viser.ViserServer, _CameraHub] = weakref.WeakKeyDictionary()
_camera_hubs_lock = threading.Lock()


def camera_hub(server: viser.ViserServer) -> _CameraHub:
    """The server's one camera hub, made on first use."""
    with _camera_hubs_lock:
        hub = _camera_hubs.get(server)
        if hub is None:
            hub = _camera_hubs[server] = _CameraHub(server)
        return hub


class Scene(abc.ABC):
    """Base class of the four scenes. Subclasses set the class variables and build in ``__init__``."""

    key: ClassVar[str]
    """Registry key and root node name, e.g. ``"peloton"``."""
    title: ClassVar[str]
    """Human title shown in the scene switcher."""
    about: ClassVar[str]
    """Markdown for the About panel: what it shows, equations, assumptions, sources."""
    camera_position: ClassVar[tuple[float, float, float]] = (6.0, -6.0, 4.0)
    """Where the camera opens (world frame, m)."""
    camera_look_at: ClassVar[tuple[float, float, float]] = (0.0, 0.0, 0.5)
    """What the camera opens looking at (world frame, m)."""

    def __init__(self, server: viser.ViserServer) -> None:
        self.server = server
        self.root = server.scene.add_frame(f"/{self.key}", show_axes=False)
        self.gui_root = server.gui.add_folder(self.title)
        self._lock = threading.RLock()
        self._in_callback = False
        self._stop = threading.Event()
        self._threads: list[threading.Thread] = []
        self._camera_listeners: list[Callable[[viser.CameraHandle], None]] = []
        with self.gui_root, server.gui.add_folder("About", expand_by_default=False):
            server.gui.add_markdown(self.about)
        self._frame_camera()

    def _frame_camera(self) -> None:
        """Point new clients, and the ones already watching, at this scene."""
        self.server.initial_camera.position = self.camera_position
        self.server.initial_camera.look_at = self.camera_look_at
        for client in self.server.get_clients().values():
            with client.atomic():
                client.camera.position = self.camera_position
                client.camera.look_at = self.camera_look_at

    # ----------------------------------------------------------------------------------------- lifecycle
    def close(self) -> None:
        """Stop the scene's threads and remove every node and GUI element it created."""
        self._stop.set()
        hub = camera_hub(self.server)
        for listener in self._camera_listeners:
            hub.remove(listener)
        for thread in self._threads:
            thread.join(timeout=2.0)
        with self._lock:
            self.root.remove()
            self.gui_root.remove()

    @property
    def closed(self) -> bool:
        return self._stop.is_set()

    def watch_cameras(self, listener: Callable[[viser.CameraHandle], None]) -> None:
        """Call ``listener`` with every client's camera now and whenever one moves, until :meth:`close`."""
        camera_hub(self.server).add(listener)
        self._camera_listeners.append(listener)
        for client in self.server.get_clients().values():
            listener(client.camera)

    def start_loop(self, step: Callable[[float], None], period_s: float) -> None:
        """Run ``step(dt)`` every ``period_s`` on a daemon thread until :meth:`close`; it sleeps, never spins."""

        def run() -> None:
            last = time.monotonic()
            while not self._stop.wait(period_s):
                now = time.monotonic()
                with self._lock:
                    if self._stop.is_set():
                        return
                    try:
                        step(now - last)
                    except Exception:
                        logger.exception("%s: animation step failed; skipping this frame", self.key)
                last = now

        thread = threading.Thread(target=run, name=f"{self.key}-loop", daemon=True)
        self._threads.append(thread)
        thread.start()

    # ----------------------------------------------------------------------------------------- callbacks
    def callback(self, func: Callable[[], None]) -> Callable[[Any], None]:
        """Wrap a no-argument handler for ``handle.on_update``/``on_click``.

        Callbacks are serialised, re-entrant calls (a write-back of a cleaned value runs ``on_update`` again,
        synchronously) are dropped, and no exception escapes: it is logged and the scene keeps its last state.
        """

        @functools.wraps(func)
        def handler(_event: Any = None) -> None:
            with self._lock:
                if self._in_callback or self.closed:
                    return
                self._in_callback = True
                try:
                    func()
                except Exception:
                    logger.exception(
                        "%s: callback %s failed; keeping the last good state",
                        self.key,
                        func.__name__,
                    )
                finally:
                    self._in_callback = False

        return handler

    # ----------------------------------------------------------------------------------------- inputs
    def read_number(self, handle: Any, last_good: float, *, integer: bool = False) -> float:
        """The handle's value as a finite number clamped to its ``min``/``max``; ``last_good`` if it is not a number.

        The cleaned value is written back to the GUI so every browser shows what the scene uses.
        """
        raw = handle.value
        value = _as_finite(raw)
        if value is None:
            value = float(last_good)
        lo, hi = getattr(handle, "min", None), getattr(handle, "max", None)
        if lo is not None:
            value = max(value, float(lo))
        if hi is not None:
            value = min(value, float(hi))
        if integer:
            value = float(round(value))
        if not _same(raw, value):
            self._write_back(handle, int(value) if integer else value)
        return value

    def read_choice(self, handle: Any, options: Sequence[T], last_good: T) -> T:
        """The handle's value if it is one of ``options``, else ``last_good`` (written back)."""
        raw = handle.value
        for option in options:
            if raw == option and type(raw) is type(option):
                return option
        self._write_back(handle, last_good)
        return last_good

    def read_bool(self, handle: Any, last_good: bool) -> bool:
        raw = handle.value
        if isinstance(raw, bool):
            return raw
        self._write_back(handle, last_good)
        return last_good

    def read_position(
        self,
        handle: Any,
        last_good: tuple[float, float, float],
        lo: tuple[float, float, float],
        hi: tuple[float, float, float],
    ) -> tuple[float, float, float]:
        """A gizmo's ``.position`` clamped to the box [lo, hi]; ``last_good`` if any coordinate is not finite.

        Setting a transform control's position from the server does not run its ``on_update``, so the cleaned
        value is written straight back.
        """
        try:
            raw = np.asarray(handle.position, dtype=np.float64).reshape(3)
        except (TypeError, ValueError):
            raw = np.full(3, np.nan)
        if np.all(np.isfinite(raw)):
            cleaned = np.clip(raw, np.asarray(lo, np.float64), np.asarray(hi, np.float64))
        else:
            cleaned = np.asarray(last_good, dtype=np.float64)
        if not np.array_equal(cleaned, raw):
            handle.position = tuple(cleaned)
        return (float(cleaned[0]), float(cleaned[1]), float(cleaned[2]))

    def _write_back(self, handle: Any, value: Any) -> None:
        was = self._in_callback
        self._in_callback = (
            True  # the synchronous on_update this triggers must not re-run the handler
        )
        try:
            handle.value = value
        finally:
            self._in_callback = was


def _as_finite(value: object) -> float | None:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    number = float(value)
    return number if math.isfinite(number) else None


def _same(raw: object, value: float) -> bool:
    return isinstance(raw, (int, float)) and not isinstance(raw, bool) and float(raw) == value
