"""What every scene shares: one root frame, one GUI folder, guarded callbacks and untrusted-input cleaning.

A scene owns every viser handle it creates. It puts its 3D nodes under the frame ``/<key>`` and its GUI under one
folder, so :meth:`Scene.close` removes everything with two calls (viser cascades removal to children) and stops
any thread the scene started.

A scene is built on a :class:`~server.sessions.Session` (one browser tab's scene and GUI, or the server's, shared);
given a plain ``viser.ViserServer`` it builds on the shared session of that server.

Every value a browser sends is untrusted. The gate (:mod:`server.gate`) lets only a control's value, a gizmo's pose
and a camera through, already checked against the control's recorded spec. Scenes still read GUI values only through
:meth:`Scene.read_controls` (the controls declared on the scene's parameter dataclass, :mod:`scenes._controls`) or
:meth:`Scene.read_choice` (a menu that is not a parameter of its own: the peloton's presets), which clean a value with
the gate's own :func:`server.clean.clean_value` against the recorded spec (never a handle's props), fall back to the
last good value for anything unusable and write the cleaned value back. They wrap every callback in
:meth:`Scene.callback`, which serialises callbacks (viser runs plain callbacks on a thread pool) and logs, rather
than raises, anything that goes wrong.
"""

from __future__ import annotations

import abc
import functools
import logging
import threading
import time
from collections.abc import Callable, Sequence
from typing import Any, ClassVar, Generic, Literal, TypeVar

import numpy as np
import viser

from scenes import _controls
from scenes._controls import Controls, P
from scenes._framing import View

# The one bridge from the scenes to server/: a scene module imports what it needs of server/ from here.
from server.clean import ControlSpec as ControlSpec
from server.clean import clean_value, control_spec
from server.clean import mark_costly as mark_costly
from server.clean import record_spec as record_spec
from server.sessions import CameraReport, Session
from server.turns import TURNS as TURNS

logger = logging.getLogger(__name__)

T = TypeVar("T")

BUILD_WAIT_S = 120.0
"""How long a browser's callback waits for its scene to finish building before it gives up (s)."""


class Scene(abc.ABC, Generic[P]):
    """Base class of the four scenes. Subclasses set the class variables and build in ``__init__``.

    ``P`` is the scene's frozen parameter dataclass (``class ArmScene(Scene[ArmParams])``): ``self.params`` has its
    type, and :meth:`read_controls` reads its declared controls (:mod:`scenes._controls`).
    """

    key: ClassVar[str]
    """Registry key and root node name, e.g. ``"peloton"``."""
    title: ClassVar[str]
    """Human title shown in the scene switcher."""
    about: ClassVar[str]
    """Markdown for the About panel: what it shows, equations, assumptions, sources."""
    opening_view: ClassVar[View] = View((6.0, -6.0, 4.0), (0.0, 0.0, 0.5))
    """Where the camera opens and the point it looks at (world frame, m)."""
    params: P
    """What the user set, cleaned: the scene shows a function of it (set by the subclass before it builds)."""

    def __init_subclass__(cls, **kwargs: Any) -> None:
        """Mark the scene built when the most-derived ``__init__`` returns (callbacks wait for it)."""
        super().__init_subclass__(**kwargs)
        init = cls.__dict__.get("__init__")
        if init is None:
            return

        @functools.wraps(init)
        def init_then_mark_built(self: Scene, *args: Any, **kw: Any) -> None:
            init(self, *args, **kw)
            # Only the outermost __init__ marks it (a subclass of a scene may or may not define its own).
            if type(self).__init__ is init_then_mark_built:
                self._built.set()

        cls.__init__ = init_then_mark_built

    def __init__(self, server: viser.ViserServer | Session) -> None:
        self._built = threading.Event()
        """Set when the scene's ``__init__`` has finished: its GUI exists before its 3D nodes, and a browser can
        move a control in between (8 tabs building at once on 2 cores leave a second or more for it)."""
        self._build_thread = threading.get_ident()
        session = server if isinstance(server, Session) else Session.shared(server)
        self.server = session
        """What the scene draws on: ``.scene``, ``.gui``, ``.atomic()``, ``.flush()`` (one tab's or everyone's)."""
        self.root = session.scene.add_frame(f"/{self.key}", show_axes=False)
        self.gui_root = session.gui.add_folder(self.title)
        self._lock = threading.RLock()
        self._pending_lock = threading.Lock()
        """Guards each handler's "a call is queued" flag (:meth:`callback`); held only to read or set it."""
        self._in_callback = False
        self.messages_in_call = 1
        """How many input messages the handler running now stands for (a burst coalesced into one call): a handler
        that counts the messages it handled adds this, not 1. Read it only inside a callback."""
        self._stop = threading.Event()
        self._threads: list[threading.Thread] = []
        self._wakes: list[threading.Event] = []
        self._camera_listeners: list[Callable[[viser.CameraHandle], None]] = []
        self._notices: dict[int, tuple[viser.ClientHandle, viser.NotificationHandle, float]] = {}
        """The notifications :meth:`notify` showed and that may still be up, by id: (tab, handle, closes at)."""
        with self.gui_root, session.gui.add_folder("About", expand_by_default=False):
            session.gui.add_markdown(self.about)
        session.frame_camera(self.opening_view.position, self.opening_view.look_at)

    @property
    def state_lock(self) -> threading.RLock:
        """The lock every callback of the scene holds while it reads or changes the scene's state: a helper that
        reads that state from another thread (a camera framing asked by a new tab) holds it too."""
        return self._lock

    # ----------------------------------------------------------------------------------------- lifecycle
    def close(self) -> None:
        """Stop the scene's threads and remove every node and GUI element it created."""
        self._stop.set()
        self.wake_loops()  # sleeping loops see the scene closed and end
        self._built.set()  # callbacks still waiting for a build that failed go on, see the scene closed, return
        hub = self.server.cameras
        for listener in self._camera_listeners:
            hub.remove(listener)
        for thread in self._threads:
            thread.join(timeout=2.0)
        with self._lock:
            self.root.remove()
            self.gui_root.remove()
            notices = list(self._notices.values())
            self._notices.clear()
        for client, notice, _ in notices:
            self.server.remove_notification(client, notice)

    def notify(
        self,
        client: viser.ClientHandle,
        title: str,
        body: str,
        *,
        color: Literal["red"] | None = None,
        auto_close_seconds: float = 15.0,
    ) -> viser.NotificationHandle:
        """Show tab ``client`` a notification about this scene; it goes when the scene closes (a red "GPX not
        loaded" stood over the free kick for the rest of its 15 s), or earlier by :meth:`take_down`."""
        notice = client.add_notification(title, body, color=color, auto_close_seconds=auto_close_seconds)
        now = time.monotonic()
        with self._lock:
            closed = self.closed
            if not closed:  # kept while it may be up; those past their time are dropped as others come
                self._notices = {key: kept for key, kept in self._notices.items() if kept[2] > now}
                self._notices[id(notice)] = (client, notice, now + auto_close_seconds)
        if closed:
            self.server.remove_notification(client, notice)
        return notice

    def take_down(self, notice: viser.NotificationHandle) -> None:
        """Remove a notification :meth:`notify` showed (once; a second call, or one after the close, does nothing)."""
        with self._lock:
            kept = self._notices.pop(id(notice), None)
        if kept is not None:
            self.server.remove_notification(kept[0], notice)

    def join(self, timeout_s: float) -> bool:
        """After :meth:`close`, wait up to ``timeout_s`` for the scene's threads (a job in flight finishes first);
        True when all have ended."""
        deadline = time.monotonic() + timeout_s
        for thread in self._threads:
            thread.join(timeout=max(0.0, deadline - time.monotonic()))
        return not any(thread.is_alive() for thread in self._threads)

    @property
    def closed(self) -> bool:
        return self._stop.is_set()

    def watch_cameras(self, listener: Callable[[viser.CameraHandle], None]) -> None:
        """Call ``listener`` with every client's camera now and whenever one moves, until :meth:`close`."""
        self.server.cameras.add(listener)
        self._camera_listeners.append(listener)
        for client in self.server.get_clients().values():
            listener(CameraReport(client.camera))  # type: ignore[arg-type]  # reads as the handle does

    def start_loop(self, step: Callable[[float], bool], period_s: float) -> None:
        """Run ``step(dt)`` every ``period_s`` on a daemon thread until :meth:`close`; it sleeps, never spins.

        ``step`` returns whether it is animating. Once it returns False the loop sleeps until :meth:`wake_loops`
        (a kick, a rotation, a ride started), instead of waking 30 times a second for nothing: eight idle tabs'
        loops cost 7 % of the server's busy time in a free-kick soak. Whatever starts an animation sets its state
        first (under the scene lock, as callbacks do) and then wakes the loops; the loop clears its wake-up before
        each step, so a wake-up during a step is not lost.
        """
        wake = threading.Event()
        self._wakes.append(wake)

        def run() -> None:
            last = time.monotonic()
            while not self._stop.wait(period_s):
                now = time.monotonic()
                wake.clear()
                with self._lock:
                    if self._stop.is_set():
                        return
                    try:
                        animating = step(now - last)
                    except Exception:
                        logger.exception("%s: animation step failed; skipping this frame", self.key)
                        animating = True
                last = now
                if not animating:
                    wake.wait()
                    last = time.monotonic()  # the first frame after a wake-up is one period long

        thread = threading.Thread(target=run, name=f"{self.key}-loop", daemon=True)
        self._threads.append(thread)
        thread.start()

    def wake_loops(self) -> None:
        """Wake the scene's sleeping :meth:`start_loop` threads (call after setting what they animate)."""
        for wake in self._wakes:
            wake.set()

    # ----------------------------------------------------------------------------------------- callbacks
    def callback(self, func: Callable[[], None]) -> Callable[[Any], None]:
        """Wrap a no-argument handler for ``handle.on_update``/``on_click``.

        Callbacks are serialised, re-entrant calls (a write-back of a cleaned value runs ``on_update`` again,
        synchronously) are dropped, and no exception escapes: it is logged and the scene keeps its last state.

        Bursts coalesce, latest value wins: viser stores a message's value on the handle before it queues the
        callback, and a handler reads the handle, not the event. So while one call of this handler waits for the
        scene (another callback runs), later calls return at once: the waiting call runs after their values
        arrived and reads the newest. A flood of 30 messages/s from each of 8 tabs therefore costs one update per
        burst instead of a queue that grows without bound (and fills viser's 32 callback threads), and the scene
        still ends on the last value sent. A handler must therefore depend only on the scene's state, not on
        how many times it ran (true of every value, pose and button handler here).

        A call that arrives while the scene is still being built (its controls exist before its nodes) waits for
        the build to finish, then applies the newest value, rather than failing on half a scene or being lost.
        """
        pending = False
        """True while a call of this handler is queued for the scene's lock and has not read any input yet."""
        arrived = 0
        """Messages since the last call read the handles: the burst the next call stands for."""

        @functools.wraps(func)
        def handler(_event: Any = None) -> None:
            nonlocal pending, arrived
            with self._pending_lock:
                arrived += 1
                if pending:
                    return  # the queued call has not read the handles yet: it will see this value
                pending = True
            if threading.get_ident() != self._build_thread and not self._built.wait(BUILD_WAIT_S):
                with self._pending_lock:
                    pending = False
                logger.warning("%s: the scene took over %.0f s to build; input dropped", self.key, BUILD_WAIT_S)
                return
            with self._lock:
                with self._pending_lock:
                    pending = False  # from here on a newer value needs a call of its own
                    burst, arrived = arrived, 0
                if self._in_callback or self.closed:
                    return
                self._in_callback = True
                self.messages_in_call = burst
                try:
                    with TURNS.turn():
                        func()
                except Exception:
                    logger.exception("%s: callback %s failed; keeping the last good state", self.key, _describe(func))
                finally:
                    self._in_callback = False

        return handler

    # ----------------------------------------------------------------------------------------- inputs
    def read_choice(self, handle: Any, options: Sequence[T], last_good: T) -> T:
        """The handle's value if it is one of ``options`` and of the control's recorded options, else ``last_good``
        (written back)."""
        accepted, cleaned, _reason = clean_value(control_spec(handle), handle.value)
        if accepted:
            for option in options:
                if option == cleaned:
                    return option
        self.write_back(handle, last_good)
        return last_good

    def read_controls(self, controls: Controls[P]) -> P:
        """The scene's parameters as its declared controls hold them now, cleaned as the gate cleans them: out of
        range is clamped, unusable keeps ``self.params``'s value, and what differs is written back
        (:func:`scenes._controls.read_controls`)."""
        return _controls.read_controls(controls, self.params, write_back=self.write_back)

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

    def write_back(self, handle: Any, value: Any) -> None:
        """Set GUI ``handle``'s value to ``value`` (a cleaned value, shown to every browser) without running this
        scene's handler of it again (the ``on_update`` the write triggers returns at once)."""
        was = self._in_callback
        self._in_callback = True  # the synchronous on_update this triggers must not re-run the handler
        try:
            handle.value = value
        finally:
            self._in_callback = was


def set_if_changed(handle: Any, name: str, value: Any) -> None:
    """Write a handle's property ``name`` only when ``value`` differs from it.

    viser skips a write of an unchanged value too, but only after casting it through the property's type hints,
    which cost more than the rest of a redraw (measured: ~40 % of a peloton speed change's 2.2 ms)."""
    old = getattr(handle, name)
    if old is not None:
        current = np.asarray(old)
        new = np.asarray(value, dtype=current.dtype)
        if current.shape == new.shape and np.array_equal(current, new):
            return
    setattr(handle, name, value)


def _describe(func: Callable[..., object]) -> str:
    """A callback's name for the log: ``functools.partial`` and other callables have no ``__name__``."""
    while isinstance(func, functools.partial):
        func = func.func
    return str(getattr(func, "__qualname__", None) or getattr(func, "__name__", None) or repr(func))
