"""The first start: kernels compile in the background while the same functions run as plain Python.

A cold numba cache makes the first call of each compiled kernel wait for its compile (several seconds per module on
a small machine). :func:`start` compiles every kernel module in child processes (which write numba's disk cache, in
parallel over the machine's cores) and then loads the cache here. Until a module's kernels are loaded, each compiled
entry point (an :class:`Entry`, wrapped around the numba dispatcher that Python code calls) runs its *plain-Python
twin*: the very same function, ``dispatcher.py_func``, with every compiled function it calls swapped for that
function's own twin. No second copy of any algorithm exists; the twin is slower (pure Python loops) but gives the
same numbers, which is good enough for the first frames.

Outside :func:`start` (tests, scripts, library use) nothing changes: an :class:`Entry` calls its dispatcher, which
compiles on first use as numba always does.

    >>> from kernels import warming
    >>> warming.start()            # in the app, before serving pages
    >>> warming.progress()         # Progress(done=('course',), pending=('fabrik', 'ball'), elapsed_s=4.2)
"""

from __future__ import annotations

import atexit
import dataclasses
import importlib
import importlib.util
import logging
import os
import subprocess
import sys
import tempfile
import threading
import time
import types
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, Generic, ParamSpec, TypeVar

from numba.core.dispatcher import Dispatcher

from kernels._jit import CompiledOnly
from kernels._jit_cache import WARM_SUFFIX, cache_dirs

logger = logging.getLogger(__name__)

MODULES: tuple[str, ...] = ("kernels.fabrik", "kernels.ball", "kernels.course")
"""The kernel packages with compiled code, each with a ``warm_up()`` that compiles every core it has."""

PROCESSES: tuple[tuple[str, ...], ...] = (("kernels.fabrik",), ("kernels.course", "kernels.ball"))
"""Which cold packages compile in one child process, in order: the two large ones (about 13 CPU-s each on a 2-core
machine) apart, the small course package (about 1 s) first in the ball's, so that no third child pays Python's,
numba's and LLVM's start (about 0.7 CPU-s, which on two cores the large ones would wait for). A package in none of
them compiles in a child of its own."""

LABELS: dict[str, str] = {
    "kernels.fabrik": "inverse kinematics",
    "kernels.ball": "ball flight",
    "kernels.course": "course ride",
}
"""What each package computes, in the words the status line uses."""

P = ParamSpec("P")
R = TypeVar("R")


@dataclasses.dataclass(frozen=True)
class Progress:
    """Where the background compile stands: packages loaded, packages still compiling, seconds since :func:`start`."""

    done: tuple[str, ...]
    pending: tuple[str, ...]
    elapsed_s: float

    @property
    def finished(self) -> bool:
        return not self.pending


class _State:
    """The process-wide state of the background compile (one per process; :func:`start` is idempotent)."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.started_at: float | None = None
        self.pending: set[str] = set()
        self.done: list[str] = []
        self.listeners: list[Callable[[Progress], None]] = []


_STATE = _State()
_TWINS: dict[Any, Callable[..., Any]] = {}
_TWINS_LOCK = threading.RLock()


def _module_twin(module: types.ModuleType) -> types.SimpleNamespace:
    """A namespace with ``module``'s attributes, its compiled functions swapped for their twins (for code that calls
    ``cycling.wheel_power_terms_compiled(...)`` through the module)."""
    key = ("module", module.__name__)
    if key in _TWINS:
        return _TWINS[key]  # type: ignore[return-value]
    namespace = types.SimpleNamespace()
    _TWINS[key] = namespace  # type: ignore[assignment]
    for name, value in vars(module).items():
        setattr(namespace, name, _make_twin(value) if isinstance(value, Dispatcher) else value)
    return namespace


def python_twin(dispatcher: Any) -> Callable[..., Any]:
    """The plain-Python twin of a numba dispatcher: its ``py_func`` (the same code object) run with globals in
    which every compiled function it calls is that function's twin, recursively. Calling it never compiles.

    Raises:
        TypeError: ``dispatcher`` is not a numba dispatcher.
    """
    if not isinstance(dispatcher, Dispatcher):
        raise TypeError(f"dispatcher must be a numba dispatcher, got {type(dispatcher).__name__}")
    with _TWINS_LOCK:
        return _make_twin(dispatcher)


def _make_twin(dispatcher: Any) -> Callable[..., Any]:
    twin = _TWINS.get(dispatcher)
    if twin is not None:
        return twin
    source = dispatcher.py_func
    namespace: dict[str, Any] = dict(source.__globals__)
    twin = types.FunctionType(source.__code__, namespace, source.__name__, source.__defaults__, source.__closure__)
    twin.__kwdefaults__ = source.__kwdefaults__
    twin.__doc__ = source.__doc__
    _TWINS[dispatcher] = twin  # before the callees: recursion and cycles find it
    for name, value in namespace.items():
        if isinstance(value, Dispatcher):
            namespace[name] = _make_twin(value)
        elif isinstance(value, types.ModuleType) and value.__name__.startswith("kernels."):
            namespace[name] = _module_twin(value)
    return twin


class Entry(Generic[P, R]):
    """A compiled kernel as Python code calls it: the dispatcher, or, while :func:`start`'s compile of its package
    is under way and the dispatcher holds no compiled code yet, the dispatcher's plain-Python twin.

    Wrap only functions that Python calls (compiled code calls the dispatcher itself: ``entry.compiled``).
    """

    def __init__(self, compiled: Callable[P, R]) -> None:
        if not isinstance(compiled, Dispatcher) or isinstance(compiled, CompiledOnly):
            raise TypeError(
                "compiled must be a numba dispatcher Python may call (compiled(from_python=True)), "
                f"got {type(compiled).__name__}"
            )
        self.compiled = compiled
        self.package = _package_of(compiled.py_func.__module__)
        """The package of :data:`MODULES` whose background compile this entry waits for (found once, here)."""
        self.__doc__ = compiled.__doc__
        self.__name__ = compiled.__name__

    def __call__(self, *args: P.args, **kwargs: P.kwargs) -> R:
        if (
            _STATE.pending
            and not self.compiled.signatures
            and self.package in _STATE.pending
            and not getattr(_LOADING, "here", False)
        ):
            try:
                return python_twin(self.compiled)(*args, **kwargs)
            except Exception:  # a twin that cannot run this input: wait for the compiled code instead
                logger.debug("plain-Python %s failed; waiting for its compiled code", self.__name__, exc_info=True)
        return self.compiled(*args, **kwargs)


def _package_of(module: str) -> str:
    """The package of :data:`MODULES` that holds ``module``, else ``module`` itself."""
    return next((package for package in MODULES if module == package or module.startswith(package + ".")), module)


def is_pending(package: str) -> bool:
    """Whether ``package`` (e.g. ``"kernels.ball"``) is still compiling in the background (False without
    :func:`start`)."""
    return package in _STATE.pending


def progress() -> Progress:
    """Where the background compile stands (both tuples empty when :func:`start` was never called)."""
    with _STATE.lock:
        elapsed = 0.0 if _STATE.started_at is None else time.perf_counter() - _STATE.started_at
        return Progress(tuple(_STATE.done), tuple(sorted(_STATE.pending)), elapsed)


def on_progress(listener: Callable[[Progress], None]) -> None:
    """Call ``listener(progress())`` each time a package finishes (from a background thread; it must not raise)."""
    with _STATE.lock:
        _STATE.listeners.append(listener)


def remove_listener(listener: Callable[[Progress], None]) -> None:
    """Stop calling ``listener`` (no error when it was not registered)."""
    with _STATE.lock:
        if listener in _STATE.listeners:
            _STATE.listeners.remove(listener)


def describe(progress: Progress) -> str:
    """The status line for ``progress``: what is compiling, how far it is, and what that means for the scenes."""
    total = len(progress.done) + len(progress.pending)
    pending = ", ".join(LABELS.get(name, name) for name in progress.pending)
    return (
        f"First start: compiling the {pending} kernels ({len(progress.done)} of {total} ready). Until then they "
        "run as plain Python, so a scene may answer slowly."
    )


def start(modules: Sequence[str] = MODULES, *, processes: bool = True) -> threading.Thread | None:
    """Compile ``modules``' kernels in the background; until each is ready its entries run as plain Python.

    With ``processes`` the packages compile in the child processes of :data:`PROCESSES` (numba's compile holds
    this process's GIL for most of its time; children use the other cores and write the disk cache), and each loads
    here from the cache as soon as its child is done with it; without, or where a child fails, it compiles on a
    thread here. Returns the thread that waits for them
    (None when already started).
    """
    cold = tuple(name for name in modules if not has_cache(name))
    with _STATE.lock:
        if _STATE.started_at is not None:
            return None
        _STATE.started_at = time.perf_counter()
        _STATE.pending = set(cold)  # a package with a warm cache just loads (about a second): no twins, no status
        _STATE.done = []
    thread = threading.Thread(
        target=_compile_all, args=(tuple(modules), set(cold), processes), name="kernels-warming", daemon=True
    )
    thread.start()
    return thread


def _compile_all(modules: tuple[str, ...], cold: set[str], processes: bool) -> None:
    """Compile every cold package at once (in the child processes of :data:`PROCESSES`) and load each here as soon
    as its child reports it done; load the warm ones from the cache meanwhile."""
    groups: list[tuple[str, ...]] = []
    if processes:
        ours = [tuple(name for name in group if name in cold) for group in PROCESSES]
        groups = [group for group in ours if group] + [
            (name,) for name in modules if name in cold and not any(name in group for group in PROCESSES)
        ]
    here = [name for name in modules if not any(name in group for group in groups)]
    waiters = [
        threading.Thread(target=_compile_group, args=(group,), name=f"kernels-warming-{group[0]}", daemon=True)
        for group in groups
    ] + [threading.Thread(target=_load, args=(name,), name=f"kernels-warming-{name}", daemon=True) for name in here]
    for waiter in waiters:
        waiter.start()
    for waiter in waiters:
        waiter.join()
    with _STATE.lock:
        started = _STATE.started_at or 0.0
    logger.info("compiled kernels ready in %.1f s", time.perf_counter() - started)


def _compile_group(names: tuple[str, ...]) -> None:
    """Compile ``names`` in one child process, in order, loading each here as soon as the child says it is done;
    whatever the child did not finish (it failed, or could not start) compiles here instead."""
    child = _spawn(names)
    left = list(names)
    if child is not None:
        assert child.stdout is not None
        for line in child.stdout:  # the child prints each package's name once its cache is written
            name = line.decode(errors="replace").strip()
            if name in left and not _EXITING.is_set():
                left.remove(name)
                _load(name)
        child.wait()
        errors = _tail(child)
        if _EXITING.is_set():  # the app is exiting and stopped the child: nothing to load, nothing to say
            return
        if child.returncode != 0:  # it failed: the loads below compile here instead, and the log says why
            logger.warning("the compile process for %s failed: %s", ", ".join(left), errors)
    for name in left:
        _load(name)


def _load(name: str) -> None:
    """Load ``name``'s compiled code from the cache (or compile it here, where the cache lacks it)."""
    _LOADING.here = True  # this thread's entries call their dispatchers while the package is still pending
    try:
        warm(name)
    except Exception:  # the kernel then compiles on first use instead; say why (unless the app is exiting)
        if not _EXITING.is_set():
            logger.exception("compiling %s failed", name)
        return
    finally:
        _LOADING.here = False
    _finish(name)


_LOADING = threading.local()
"""``here`` is True on a thread that is loading (or compiling) a package: its entries run compiled code, not twins."""


_CHILDREN: list[subprocess.Popen[bytes]] = []
"""Compile processes started here; any still running when this process exits is stopped with it."""
_ERRORS: dict[int, Any] = {}
"""Each compile process's stderr file, by its pid."""
_EXITING = threading.Event()
"""Set when this process exits: a compile cut short then is neither loaded nor reported."""


def has_cache(package: str) -> bool:
    """Whether numba's disk cache holds all of ``package``'s compiled code (beside it, or under ``NUMBA_CACHE_DIR``):
    a warm-up finished writing it (:func:`warm`'s marker) and its index is still there. A start stopped while it
    compiled leaves some indexes but no marker: that package compiles in the background again, with its status line,
    rather than inside the first scene that calls it. The cache and its markers are dropped whole when any kernel
    source changes (:mod:`kernels._jit_cache`)."""
    marker = package + WARM_SUFFIX
    for directory in _cache_dirs(package):
        try:
            names = {path.name for path in directory.iterdir()}
        except OSError:
            continue
        if marker in names and any(name.endswith(".nbi") for name in names):
            return True
    return False


def warm(package: str) -> None:
    """Compile ``package``'s kernels (or load them from the cache), then mark its cache whole (:func:`has_cache`)."""
    importlib.import_module(package).warm_up()
    for directory in _cache_dirs(package):
        try:
            if any(path.suffix == ".nbi" for path in directory.iterdir()):
                (directory / (package + WARM_SUFFIX)).touch()
        except OSError:
            continue  # a read-only cache directory: the next start compiles again, as it would without the marker


def _cache_dirs(package: str) -> list[Path]:
    """Where numba reads ``package``'s cache: beside its sources, or only under ``NUMBA_CACHE_DIR`` when set."""
    spec = importlib.util.find_spec(package)
    if spec is None or spec.origin is None:
        return []
    override = os.environ.get("NUMBA_CACHE_DIR")
    return [
        directory
        for directory in cache_dirs(Path(spec.origin).parent)
        if not override or directory.is_relative_to(override)
    ]


_CHILD = (
    "import signal, sys\n"
    "signal.signal(signal.SIGINT, signal.SIG_IGN)\n"  # Ctrl+C stops the app, which stops this (not a traceback)
    "from kernels import warming\n"
    "for name in sys.argv[1:]:\n"
    "    warming.warm(name)\n"
    "    print(name, flush=True)\n"
)
"""What a compile process runs: each package's :func:`warm` (numba's cache, then its marker), its name printed after.
It ignores SIGINT: Ctrl+C in the app's terminal reaches the whole process group, and a child that died of it first
was reported as a failed compile, with numba's traceback, before the app's exit stopped it."""


def _spawn(names: tuple[str, ...]) -> subprocess.Popen[bytes] | None:
    command = [sys.executable, "-c", _CHILD, *names]
    try:  # stderr to a file: a pipe the waiter does not read while it reads stdout could fill and stall the child
        errors = tempfile.TemporaryFile()
        child = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=errors, env=os.environ.copy())
    except OSError:
        logger.warning("could not start a compile process for %s; compiling here", ", ".join(names))
        return None
    _ERRORS[child.pid] = errors
    if not _CHILDREN:
        atexit.register(_stop_children)
    _CHILDREN.append(child)
    return child


def _tail(child: subprocess.Popen[bytes]) -> str:
    """The end of what ``child`` wrote to stderr (where :func:`_spawn` kept it)."""
    errors = _ERRORS.pop(child.pid, None)
    if errors is None:
        return ""
    with errors:
        errors.seek(0)
        return errors.read().decode(errors="replace")[-2000:]


def _stop_children() -> None:
    _EXITING.set()
    for child in _CHILDREN:
        if child.poll() is None:
            child.kill()


def _finish(name: str) -> None:
    with _STATE.lock:
        _STATE.pending.discard(name)
        _STATE.done.append(name)
        listeners = list(_STATE.listeners)
    snapshot = progress()
    for listener in listeners:
        try:
            listener(snapshot)
        except Exception:
            logger.exception("a compile-progress listener failed")


def _reset_for_tests() -> None:
    """Forget :func:`start` (tests only): entries call their dispatchers again."""
    _EXITING.clear()
    with _STATE.lock:
        _STATE.started_at = None
        _STATE.pending = set()
        _STATE.done = []
        _STATE.listeners = []
