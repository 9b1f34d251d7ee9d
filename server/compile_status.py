"""The status line under the scene picker while the first start compiles the kernels (see :mod:`kernels.warming`)."""

from __future__ import annotations

import logging
import threading

import viser

from kernels import warming
from server.sessions import GuiFacade

logger = logging.getLogger(__name__)


class CompileStatus:
    """A markdown line saying what is compiling and how far it is; it goes once every kernel is compiled.

    Shows nothing when nothing compiles (a warm cache, or the kernels used without :func:`kernels.warming.start`).
    """

    def __init__(self, gui: viser.GuiApi | GuiFacade, *, order: float) -> None:
        self._lock = threading.Lock()
        self._handle: viser.GuiMarkdownHandle | None = None
        warming.on_progress(self._update)  # first, so a finish between here and the check below is not missed
        with self._lock:
            now = warming.progress()
            if now.finished:
                warming.remove_listener(self._update)
                return
            self._handle = gui.add_markdown(warming.describe(now), order=order)

    @property
    def text(self) -> str:
        """What the line says now ("" when it is not shown)."""
        return "" if self._handle is None else self._handle.content

    @property
    def shown(self) -> bool:
        """Whether the line is on the page."""
        return self._handle is not None

    def _update(self, progress: warming.Progress) -> None:
        with self._lock:
            if self._handle is None:
                return
            if progress.finished:
                self._remove()
            else:
                self._handle.content = warming.describe(progress)

    def _remove(self) -> None:
        warming.remove_listener(self._update)
        if self._handle is not None:
            self._handle.remove()
            self._handle = None

    def close(self) -> None:
        """Take the line off the page and stop listening (idempotent)."""
        with self._lock:
            self._remove()
