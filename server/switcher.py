"""The scene switcher: a dropdown that tears the shown scene down completely and builds the chosen one.

One switcher serves one :class:`~server.sessions.Session`: a browser tab's own (the default; each tab switches and
resets only its own scene) or the server's, shared by every tab (``--shared``).
"""

from __future__ import annotations

import asyncio
import logging
import threading
from collections.abc import Callable, Coroutine
from typing import Any

import viser

from scenes import SCENES, Scene
from server.clean import mark_costly
from server.compile_status import CompileStatus
from server.sessions import Session

logger = logging.getLogger(__name__)


def _in_a_thread(handler: Callable[[object], None]) -> Callable[[object], Coroutine[Any, Any, None]]:
    """``handler`` as a coroutine function that runs it on the event loop's worker threads and returns when done."""

    async def run(event: object) -> None:
        try:
            await asyncio.get_running_loop().run_in_executor(None, handler, event)
        except Exception:  # no exception escapes a callback (nobody awaits the gate's delivery)
            logger.exception("scene switcher: handling %r failed", event)

    return run


class SceneSwitcher:
    """Owns the one live scene of a session and the dropdown that picks it.

    Given a plain ``viser.ViserServer`` it serves the server's shared session.
    """

    def __init__(self, server: viser.ViserServer | Session, initial: str) -> None:
        if initial not in SCENES:
            raise ValueError(f"scene must be one of {sorted(SCENES)}, got {initial!r}")
        session = server if isinstance(server, Session) else Session.shared(server)
        self.server = session
        self._lock = threading.RLock()
        self.closed = False
        """Set by :meth:`close`: a pick or Reset handled after it (its tab closed while the input waited on viser's
        callback pool or the gate's budget) builds nothing, else it would build a scene that nobody closes."""
        titles = {cls.title: key for key, cls in SCENES.items()}
        self._key_from_title = titles
        # Callbacks first, under the lock: a pick made while the first scene builds waits for it, then applies.
        with self._lock:
            # Both rebuild a scene: costly inputs, budgeted per tab at the gate (a burst of Resets is one Reset).
            self.dropdown = mark_costly(
                session.gui.add_dropdown(
                    "Scene", options=tuple(titles), initial_value=SCENES[initial].title, order=-100.0
                )
            )
            self.reset_button = mark_costly(session.gui.add_button("Reset scene to defaults", order=-99.0))
            self.compile_status = CompileStatus(session.gui, order=-98.0)
            # Awaited by viser (coroutines), the builds running on a worker thread: the gate then knows when a
            # pick or Reset has finished, and holds that tab's later inputs until it has (server.gate).
            self.dropdown.on_update(_in_a_thread(self._on_pick))
            self.reset_button.on_click(_in_a_thread(self._on_reset))
            self.scene: Scene = SCENES[initial](session)

    def show(self, key: str, *, rebuild: bool = False) -> Scene:
        """Replace the current scene with ``key``'s; when it is already shown, only ``rebuild`` rebuilds it."""
        if key not in SCENES:
            raise ValueError(f"scene must be one of {sorted(SCENES)}, got {key!r}")
        with self._lock:
            self._build(key, rebuild=rebuild)
            if self.dropdown.value != SCENES[key].title:
                self.dropdown.value = SCENES[key].title
            return self.scene

    def _build(self, key: str, *, rebuild: bool) -> None:
        if self.closed:
            return
        if self.scene.key != key or rebuild:  # (a tab closing meanwhile: its session's writes are lost without a word)
            self.scene.close()
            self.scene = SCENES[key](self.server)

    # A browser's pick or Reset builds without writing the dropdown back: a newer pick that arrived during the
    # build is in the dropdown already, and its own callback (next in line for the lock) builds it.
    def _on_pick(self, _event: object) -> None:
        with self._lock:
            key = self._key_from_title.get(str(self.dropdown.value))
            if key is None:  # not one of ours: a crafted message; show what is really on screen
                self.dropdown.value = self.scene.title
                return
            try:
                self._build(key, rebuild=False)
            except Exception:
                logger.exception("switching to %s failed", key)

    def _on_reset(self, _event: object) -> None:
        with self._lock:
            try:
                self._build(self.scene.key, rebuild=True)
            except Exception:
                logger.exception("resetting %s failed", self.scene.key)

    def close(self) -> None:
        with self._lock:
            self.closed = True
            self.scene.close()
            self.dropdown.remove()
            self.reset_button.remove()
            self.compile_status.close()
