"""numba's disk cache, kept in step with the source of every kernel.

numba keys a compiled function's cached machine code on its own file's modification time and size only. A compiled
function that calls one in another module (the FABRIK chain core calls the joint rules in ``fabrik/limits.py``; the
course's ride loop calls ``cycling``'s power law) would keep running the old callee after that module changed, until
its own file changed too. So the kernels keep one stamp beside the cache: a hash of every kernel source file. When it
differs from the sources on disk, every cached kernel is dropped and compiles afresh on its next use (once).

Where the cache lives: numba writes it in ``__pycache__`` beside each module, or under ``NUMBA_CACHE_DIR`` when that
is set, or, where the package's own directory is read-only, in numba's user-wide directory (``~/.cache/numba``); the
last two hold one directory per source directory, named by numba from its path. All are kept in step here, except
where the stamp itself cannot be written (a read-only install: then nothing is dropped, see
:func:`drop_stale_cache`).
"""

from __future__ import annotations

import hashlib
import logging
import os
from pathlib import Path

from numba.core.caching import UserProvidedCacheLocator
from numba.misc.appdirs import AppDirs

logger = logging.getLogger(__name__)

STAMP_NAME = "numba-sources.sha256"
"""The stamp's file name, in the kernels' own ``__pycache__``."""

WARM_SUFFIX = ".warm"
"""A package's marker beside its cache: its warm-up finished writing it (:func:`kernels.warming.has_cache`)."""
_CACHE_SUFFIXES = (".nbi", ".nbc", WARM_SUFFIX)


def source_hash(root: Path) -> str:
    """SHA-256 over the relative path and bytes of every ``.py`` file below ``root``, in sorted order."""
    digest = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        if "__pycache__" in path.parts:
            continue
        digest.update(path.relative_to(root).as_posix().encode())
        digest.update(b"\0")
        digest.update(path.read_bytes())
        digest.update(b"\0")
    return digest.hexdigest()


def cache_dirs(root: Path) -> list[Path]:
    """Every directory numba may keep a cache of ``root``'s modules in: each ``__pycache__`` below it and, for each
    source directory below it, numba's directory for it under ``NUMBA_CACHE_DIR`` (when set) and under numba's
    user-wide cache (``~/.cache/numba``). numba names those ``<directory name>_<SHA-1 of its absolute path>``
    (``UserProvidedCacheLocator.get_suitable_cache_subpath``, numba 0.68)."""
    dirs = [path for path in root.rglob("__pycache__") if path.is_dir()]
    sources = sorted({path.parent for path in root.rglob("*.py") if "__pycache__" not in path.parts})
    bases = [Path(user_dir)] if (user_dir := os.environ.get("NUMBA_CACHE_DIR")) else []
    bases.append(Path(AppDirs(appname="numba", appauthor=False).user_cache_dir))
    for base in bases:
        for source in sources:
            path = base / UserProvidedCacheLocator.get_suitable_cache_subpath(str(source / "module.py"))
            if path.is_dir():
                dirs.append(path)
    return dirs


def drop_stale_cache(root: Path) -> bool:
    """Drop numba's cached kernels below ``root`` when any source changed since they were cached; True if it did.

    The stamp is written to ``root/__pycache__``; where that cannot be written nothing is dropped or stamped (numba
    then caches elsewhere or not at all, see the module docstring).
    """
    stamp = root / "__pycache__" / STAMP_NAME
    current = source_hash(root)
    try:
        if stamp.read_text().strip() == current:
            return False
    except OSError:
        pass  # no stamp yet: whatever is cached may predate it
    dropped = 0
    for directory in cache_dirs(root):
        for path in directory.iterdir():
            if path.suffix in _CACHE_SUFFIXES:
                try:
                    path.unlink()
                    dropped += 1
                except OSError:
                    pass  # another process removed it first, or the directory is read-only
    try:
        stamp.parent.mkdir(exist_ok=True)
        stamp.write_text(current + "\n")
    except OSError:
        return False
    if dropped:
        logger.info("kernel sources changed: dropped %d cached numba files; they compile again on first use", dropped)
    return dropped > 0
