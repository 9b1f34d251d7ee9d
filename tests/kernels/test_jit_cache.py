"""numba's cache follows every kernel source: a change in any module drops every cached kernel, once."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from kernels import _jit as jit
from kernels import _jit_cache


def _package(root: Path) -> tuple[Path, Path]:
    (root / "pkg" / "__pycache__").mkdir(parents=True)
    (root / "pkg" / "core.py").write_text("def f():\n    return 1\n")
    (root / "pkg" / "rules.py").write_text("def g():\n    return 2\n")
    cached = root / "pkg" / "__pycache__" / "core.f-1.py311.nbi"
    return root / "pkg" / "rules.py", cached


def _cache(cached: Path) -> None:
    cached.write_bytes(b"index")
    cached.with_suffix(".nbc").write_bytes(b"code")
    (cached.parent / f"pkg{_jit_cache.WARM_SUFFIX}").touch()  # its warm-up finished (kernels.warming.has_cache)


def test_a_changed_callee_module_drops_the_callers_cache(tmp_path: Path) -> None:
    rules, cached = _package(tmp_path)
    _jit_cache.drop_stale_cache(tmp_path)  # first stamp
    _cache(cached)
    assert not _jit_cache.drop_stale_cache(tmp_path)  # nothing changed: the cache stays
    assert cached.exists()
    rules.write_text("def g():\n    return 3\n")  # only the callee's module changes
    assert _jit_cache.drop_stale_cache(tmp_path)
    assert not cached.exists() and not cached.with_suffix(".nbc").exists()
    assert not (cached.parent / f"pkg{_jit_cache.WARM_SUFFIX}").exists()  # the marker goes with the cache
    _cache(cached)  # compiled again from the new sources
    assert not _jit_cache.drop_stale_cache(tmp_path)
    assert cached.exists()


def test_without_a_stamp_whatever_is_cached_is_dropped(tmp_path: Path) -> None:
    _, cached = _package(tmp_path)
    _cache(cached)
    assert _jit_cache.drop_stale_cache(tmp_path)
    assert not cached.exists()
    assert (tmp_path / "__pycache__" / _jit_cache.STAMP_NAME).read_text().strip() == _jit_cache.source_hash(tmp_path)


def test_a_cache_numba_writes_under_numba_cache_dir_is_kept_in_step(tmp_path: Path) -> None:
    # numba itself writes the cache (in a child process, as NUMBA_CACHE_DIR is read when numba is imported), so the
    # test holds whatever layout numba uses there, not our idea of it.
    source = tmp_path / "src"
    rules, _ = _package(source)
    (source / "pkg" / "core.py").write_text("import numba\n\n@numba.njit(cache=True)\ndef f():\n    return 1\n")
    user = tmp_path / "user-cache"
    env = {**os.environ, "NUMBA_CACHE_DIR": str(user), "PYTHONPATH": str(source)}
    _jit_cache.drop_stale_cache(source)  # first stamp
    subprocess.run([sys.executable, "-c", "import pkg.core; pkg.core.f()"], env=env, check=True, timeout=120)
    written = sorted(user.rglob("*.nbi"))
    assert written, "numba wrote no cache"
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("NUMBA_CACHE_DIR", str(user))
        assert {path.parent for path in written} <= set(_jit_cache.cache_dirs(source))
        assert not _jit_cache.drop_stale_cache(source)  # unchanged sources: kept
        assert all(path.exists() for path in written)
        rules.write_text("def g():\n    return 4\n")
        assert _jit_cache.drop_stale_cache(source)
    assert not list(user.rglob("*.nbi")) and not list(user.rglob("*.nbc"))


def test_the_real_kernels_are_stamped_with_their_sources() -> None:
    root = Path(_jit_cache.__file__).parent
    stamp = root / "__pycache__" / _jit_cache.STAMP_NAME
    assert stamp.read_text().strip() == _jit_cache.source_hash(root)


def test_without_a_writable_cache_directory_the_kernels_compile_uncached(monkeypatch: pytest.MonkeyPatch) -> None:
    # numba refuses cache=True when neither the package's __pycache__ nor ~/.cache/numba is writable (checked by
    # hand as user nobody with a read-only HOME): the module must still import, just compiling at every start.
    from numba.core.registry import CPUDispatcher

    def refuse(self: CPUDispatcher) -> None:
        raise RuntimeError("cannot cache function 'f': no locator available for file 'chain.py'")

    monkeypatch.setattr(CPUDispatcher, "enable_caching", refuse)
    monkeypatch.setattr(jit, "UNCACHED", [])

    def core() -> int:
        return 7

    def helper() -> int:
        return 6

    entry = jit.compiled(from_python=True, error_model="numpy")(core)
    assert entry() == 7
    assert entry.targetoptions == {
        "nopython": True,
        "boundscheck": None,
        "no_cfunc_wrapper": True,
        "error_model": "numpy",
    }
    assert jit.compiled(error_model="numpy")(helper).targetoptions == {
        **entry.targetoptions,
        "no_cpython_wrapper": True,
    }
    assert jit.UNCACHED == ["core"]  # a helper has no disk cache to miss

    def other(self: CPUDispatcher) -> None:
        raise RuntimeError("other failure")

    monkeypatch.setattr(CPUDispatcher, "enable_caching", other)
    with pytest.raises(RuntimeError, match="other failure"):
        jit.compiled(from_python=True)(core)


def test_a_compiled_only_kernel_refuses_a_call_from_python_and_runs_from_compiled_code() -> None:
    # Built without numba's CPython wrapper, a call from Python would jump to code that does not exist (a crash).
    def twice(x: float) -> float:
        return 2.0 * x

    helper = jit.compiled()(twice)
    with pytest.raises(TypeError, match="twice is compiled for compiled callers only"):
        helper(1.5)

    def caller(x: float) -> float:
        return helper(x) + 1.0

    assert jit.compiled(from_python=True)(caller)(1.5) == 4.0


def test_every_compiled_kernel_is_made_one_way() -> None:
    # One decorator compiles every kernel, so each has the disk cache's fallback and no C wrapper it never uses.
    import importlib
    import pkgutil

    from numba.core.registry import CPUDispatcher

    import kernels

    dispatchers = {}
    for info in pkgutil.walk_packages(kernels.__path__, "kernels."):
        for value in vars(importlib.import_module(info.name)).values():
            if isinstance(value, CPUDispatcher):
                dispatchers[f"{value.py_func.__module__}.{value.py_func.__qualname__}"] = value
    assert len(dispatchers) > 100
    made_otherwise = [name for name, d in dispatchers.items() if not d.targetoptions.get("no_cfunc_wrapper")]
    assert made_otherwise == []
    # Each is callable from Python (with numba's CPython wrapper) or refuses Python's call (built without it).
    wrapperless = {name for name, d in dispatchers.items() if d.targetoptions.get("no_cpython_wrapper")}
    refusing = {name for name, d in dispatchers.items() if isinstance(d, jit.CompiledOnly)}
    assert wrapperless == refusing
    assert len(refusing) > 70
    # Python's entry points keep numba's disk cache; a helper has none (its callers' cached code holds it).
    cached = {name for name, d in dispatchers.items() if type(d._cache).__name__ == "FunctionCache"}
    assert cached == set(dispatchers) - refusing
