"""The first start's plain-Python twins: every compiled core Python calls is an Entry, each twin gives the compiled
numbers, and the background compile reports its progress and then hands every call to the compiled code."""

from __future__ import annotations

import dis
import importlib
import pkgutil
import sys
import types
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
import pytest
from numba.core.dispatcher import Dispatcher

from kernels import ball, course, fabrik, warming
from kernels.ball.core import RESULTS
from kernels.fabrik import Cone, Hinge


@pytest.fixture
def fresh_warming() -> Iterator[None]:
    warming._reset_for_tests()
    yield
    warming._reset_for_tests()


def _code_objects(code: types.CodeType) -> Iterator[types.CodeType]:
    yield code
    for constant in code.co_consts:
        if isinstance(constant, types.CodeType):
            yield from _code_objects(constant)


def _python_functions(module: types.ModuleType) -> Iterator[types.FunctionType]:
    for value in vars(module).values():
        members = vars(value).values() if isinstance(value, type) else (value,)
        for member in members:
            function = getattr(member, "__func__", member)
            if isinstance(function, types.FunctionType) and function.__module__ == module.__name__:
                yield function


def _modules(package: str) -> Iterator[pkgutil.ModuleInfo]:
    return pkgutil.walk_packages(importlib.import_module(package).__path__, f"{package}.")


def _called_names(code: types.CodeType, namespace: dict[str, Any]) -> Iterator[str]:
    """Names of the dispatchers ``code`` reaches: a global that is one, or one read as a module's attribute
    (``play.keeper_path``)."""
    module: types.ModuleType | None = None
    for instruction in dis.get_instructions(code):
        if instruction.opname in ("LOAD_ATTR", "LOAD_METHOD") and module is not None:
            if isinstance(getattr(module, instruction.argval, None), Dispatcher):
                yield f"{module.__name__.rsplit('.', 1)[-1]}.{instruction.argval}"
        module = None
        if instruction.opname == "LOAD_GLOBAL":
            value = namespace.get(instruction.argval)
            if isinstance(value, Dispatcher):
                yield instruction.argval
            elif isinstance(value, types.ModuleType):
                module = value


def test_python_code_in_the_kernels_calls_compiled_cores_only_through_entries() -> None:
    # A bare dispatcher called from Python (the scenes' too) would compile in the serving process during the first start
    # (seconds holding its GIL) instead of running its twin. compiled_single_solve hands the raw core to a benchmark on
    # purpose.
    bare = []
    infos = [info for package in ("kernels", "scenes", "server", "shaders") for info in _modules(package)]
    for info in infos:
        module = importlib.import_module(info.name)
        for function in _python_functions(module):
            for code in _code_objects(function.__code__):
                for name in _called_names(code, function.__globals__):
                    bare.append(f"{module.__name__}.{function.__qualname__} calls {name}")
    assert bare == ["kernels.fabrik.api.compiled_single_solve calls _compiled_solve_one"]


def _chain() -> np.ndarray:
    return np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.3, 0.0, 1.9], [0.6, 0.0, 2.5]])


def _wall_goal() -> tuple[Any, Any]:
    return ball.free_kick_panels((0.0, 0.0), (20.0, 0.0), (1.0, 0.0))


def _kicks() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rows = np.tile((0.0, 0.0, ball.BALL_RADIUS_M), (6, 1))
    velocities = np.tile((25.0, -3.0, 6.0), (6, 1)) + np.linspace(0.0, 2.0, 6)[:, None]
    spins = np.tile((0.0, 5.0, 50.0), (6, 1))
    return rows, velocities, spins


def _outcome_numbers(outcome: Any) -> np.ndarray:
    """An outcome's verdicts (as codes) and its wall and goal crossing points, NaN where it crossed none."""
    codes = np.atleast_1d(np.vectorize(RESULTS.index)(np.asarray(outcome.result)))
    points = [
        np.full(3, np.nan) if point is None else np.asarray(point) for point in (outcome.wall_point, outcome.goal_point)
    ]
    return np.nan_to_num(np.concatenate([codes.astype(float), *(point.ravel() for point in points)]), nan=-1.0)


CASES: dict[str, Callable[[], Any]] = {
    "fabrik.solve with limits and an obstacle": lambda: (
        fabrik.solve(
            _chain(),
            [0.8, 0.3, 1.2],
            constraints=[Hinge((0.0, 1.0, 0.0), -1.0, 1.0), Cone(1.0), Cone(1.0)],
            obstacles=[((1.0, 0.0, 1.0), 0.2)],
        ).joints
    ),
    "fabrik.solve_batch (parallel driver)": lambda: (
        fabrik.solve_batch(
            np.repeat(_chain()[None], 3, axis=0), np.array([[0.8, 0.0, 1.2], [0.5, 0.5, 1.5], [0.0, 0.9, 1.0]])
        ).joints
    ),
    "fabrik.ccd": lambda: fabrik.ccd(_chain(), [0.8, 0.3, 1.2]).joints,
    "fabrik.jacobian_dls": lambda: fabrik.jacobian_dls(_chain(), [0.8, 0.3, 1.2]).joints,
    "fabrik.solve_tree": lambda: (
        fabrik.solve_tree(
            [-1, 0, 1, 1],
            np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.3, 0.0, 1.9], [-0.3, 0.0, 1.9]]),
            {2: [0.8, 0.0, 1.2], 3: [-0.8, 0.0, 1.2]},
        ).joints
    ),
    "ball.simulate RK4, measured model, knuckle": lambda: (
        ball.simulate(
            (0.0, 0.0, 0.11),
            (25.0, -3.0, 6.0),
            (0.0, 0.0, 3.0),
            dt=0.002,
            method="rk4",
            model="measured",
            knuckle_seed=3,
        ).position
    ),
    "ball.outcome": lambda: _outcome_numbers(
        ball.outcome(ball.simulate((0.0, 0.0, 0.11), (25.0, -3.0, 6.0), (0.0, 0.0, 50.0), dt=0.002), *_wall_goal())
    ),
    "ball.simulate_batch": lambda: np.nan_to_num(ball.simulate_batch(*_kicks(), dt=0.002).position, nan=-1.0),
    "ball.simulate_outcomes": lambda: _outcome_numbers(ball.simulate_outcomes(*_kicks(), *_wall_goal(), dt=0.002)),
    "course.ride": lambda: np.array(
        [
            course.ride(
                course.course_from_xy(
                    np.linspace(0.0, 3000.0, 60), np.zeros(60), 40.0 * np.sin(np.linspace(0.0, 3.0, 60))
                ),
                250.0,
            ).time_s
        ]
    ),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_the_plain_python_twin_gives_the_compiled_numbers(case: str, monkeypatch: pytest.MonkeyPatch) -> None:
    compiled = np.asarray(CASES[case](), dtype=float)
    monkeypatch.setattr(warming.Entry, "__call__", lambda self, *a, **k: warming.python_twin(self.compiled)(*a, **k))
    twin = np.asarray(CASES[case](), dtype=float)
    assert twin.shape == compiled.shape
    np.testing.assert_allclose(twin, compiled, rtol=1e-9, atol=1e-12)


def test_a_twin_calls_no_compiled_code() -> None:
    from kernels.fabrik.chain import _solve_chain

    twin = warming.python_twin(_solve_chain)
    assert twin.__code__ is _solve_chain.py_func.__code__  # the same source, not a copy
    compiled_globals = [name for name, value in twin.__globals__.items() if isinstance(value, Dispatcher)]
    assert compiled_globals == []
    with pytest.raises(TypeError, match="dispatcher"):
        warming.python_twin(len)


def test_an_entry_wraps_only_what_python_may_call() -> None:
    from kernels.fabrik.chain import _solve_chain, _solve_one

    assert warming.Entry(_solve_one).compiled is _solve_one
    for not_callable in (_solve_chain, len):  # built without numba's CPython wrapper; not compiled at all
        with pytest.raises(TypeError, match="Python may call"):
            warming.Entry(not_callable)


def test_entries_run_twins_only_while_their_package_is_pending(fresh_warming: None) -> None:
    from kernels.fabrik import api

    ran: list[str] = []
    real_twin = warming.python_twin

    def spy(dispatcher: Any) -> Any:
        ran.append(dispatcher.__name__)
        return real_twin(dispatcher)

    entry = warming.Entry(api._solve_one.compiled)
    warming._STATE.pending = {"kernels.ball"}  # another package compiling: fabrik's entry uses its compiled code
    original = warming.python_twin
    try:
        warming.python_twin = spy  # type: ignore[assignment]
        fabrik.solve(_chain(), [0.8, 0.3, 1.2])
        assert ran == []
        assert entry.package == "kernels.fabrik"
    finally:
        warming.python_twin = original  # type: ignore[assignment]


def test_start_reports_progress_and_then_hands_calls_to_compiled_code(
    fresh_warming: None, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(warming, "has_cache", lambda package: False)  # as on a first start
    twins: list[str] = []
    real_twin = warming.python_twin
    monkeypatch.setattr(
        warming, "python_twin", lambda dispatcher: twins.append(dispatcher.__name__) or real_twin(dispatcher)
    )
    seen: list[warming.Progress] = []
    warming.on_progress(seen.append)
    thread = warming.start(("kernels.course",), processes=False)
    assert thread is not None
    assert warming.start(("kernels.course",)) is None  # once per process
    thread.join(120)
    assert not thread.is_alive()
    assert [progress.done for progress in seen] == [("kernels.course",)]
    assert seen[-1].finished and warming.progress().finished
    assert "course ride" in warming.describe(warming.Progress(done=(), pending=("kernels.course",), elapsed_s=1.0))
    ride_module = sys.modules["kernels.course.ride"]
    assert ride_module._ride_core_entry.compiled.signatures  # compiled (or loaded) by start
    assert twins == []  # the load ran the compiled code (it had run the twins, compiling nothing, while pending)


def test_a_package_is_warm_once_its_warm_up_finished_writing_the_cache(
    tmp_path: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    import os
    import subprocess

    # numba itself writes the course's cache under an empty NUMBA_CACHE_DIR (read when numba is imported: a child)
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    assert not any(warming.has_cache(name) for name in warming.MODULES)
    # A warm-up cut short (Ctrl+C during a first start) leaves indexes but no marker: still cold. (An outside tester:
    # 13 of 18 indexes counted as a warm cache, and the next start compiled the rest inside the free kick's first
    # build, 16-26 s of a blank tab with no status line.)
    warm_up = "import kernels.course as m; m.warm_up()"
    subprocess.run([sys.executable, "-c", warm_up], env=env, check=True, timeout=300)
    assert any(path.suffix == ".nbi" for path in tmp_path.rglob("*"))
    assert not warming.has_cache("kernels.course")
    warm = "from kernels import warming; warming.warm('kernels.course')"
    subprocess.run([sys.executable, "-c", warm], env=env, check=True, timeout=300)
    assert warming.has_cache("kernels.course")
    assert not warming.has_cache("kernels.fabrik") and not warming.has_cache("kernels.ball")
    # Without its index the marker alone is not a cache.
    for index in tmp_path.rglob("*.nbi"):
        index.unlink()
    assert not warming.has_cache("kernels.course")


def test_a_package_with_a_warm_cache_is_never_pending(fresh_warming: None, monkeypatch: pytest.MonkeyPatch) -> None:
    # A later start loads the cache in about a second: no plain-Python twins and no "First start" line for it.
    monkeypatch.setattr(warming, "has_cache", lambda package: package == "kernels.course")
    monkeypatch.setattr(warming, "_spawn", lambda name: None)  # compile the cold one here, not in a child
    seen: list[warming.Progress] = []
    warming.on_progress(seen.append)
    thread = warming.start(("kernels.course", "kernels.ball"))
    assert thread is not None
    assert not warming.is_pending("kernels.course")
    thread.join(300)
    assert sorted(seen[-1].done) == ["kernels.ball", "kernels.course"] and seen[-1].finished


def test_exiting_while_a_package_compiles_stops_its_child_and_says_nothing(
    fresh_warming: None, monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    # Ctrl+C during a first start: the app exits, its compile children are stopped, and the thread that waited on
    # one must neither compile the package here (at interpreter shutdown) nor log a traceback about it.
    import subprocess
    import threading

    loads: list[str] = []
    monkeypatch.setattr(warming, "_CHILDREN", [])
    package = types.ModuleType("slow_kernels")
    package.warm_up = lambda: loads.append("slow_kernels")  # pyright: ignore[reportAttributeAccessIssue]
    monkeypatch.setitem(sys.modules, "slow_kernels", package)

    def slow_child(names: tuple[str, ...]) -> subprocess.Popen[bytes]:
        command = [sys.executable, "-c", "import time; time.sleep(60)"]
        child = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        warming._CHILDREN.append(child)
        return child

    monkeypatch.setattr(warming, "_spawn", slow_child)
    waiter = threading.Thread(target=warming._compile_group, args=(("slow_kernels",),))
    with caplog.at_level("DEBUG", logger="kernels.warming"):
        waiter.start()
        while not warming._CHILDREN:
            waiter.join(0.01)
        warming._stop_children()
        waiter.join(30)
    assert not waiter.is_alive()
    assert warming._CHILDREN[0].returncode is not None  # the child was stopped
    assert loads == []  # nothing compiled or loaded here while exiting
    assert caplog.records == []
    assert "slow_kernels" not in warming.progress().done


def test_a_shared_compile_process_hands_over_each_package_as_soon_as_it_is_done(
    fresh_warming: None, tmp_path: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    # Two packages in one child: the first loads here while the child still compiles the second (which, in the
    # child, waits on a FIFO that the test opens only once it has seen the first done).
    import os
    import threading

    fifo = tmp_path / "go"
    os.mkfifo(fifo)
    (tmp_path / "quick_kernels.py").write_text("def warm_up():\n    pass\n")
    in_the_child = f"os.getpid() != {os.getpid()}"  # not when this process loads it after the child
    child_waits = f"import os\n\ndef warm_up():\n    if {in_the_child}:\n        open({str(fifo)!r}).read()\n"
    (tmp_path / "waiting_kernels.py").write_text(child_waits)
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")]))
    monkeypatch.setattr(warming, "PROCESSES", (("quick_kernels", "waiting_kernels"),))
    monkeypatch.setattr(warming, "has_cache", lambda package: False)
    first_done = threading.Event()
    seen: list[warming.Progress] = []

    def listener(progress: warming.Progress) -> None:
        seen.append(progress)
        first_done.set()

    warming.on_progress(listener)
    thread = warming.start(("quick_kernels", "waiting_kernels"))
    assert thread is not None
    assert first_done.wait(60)
    assert seen[0].done == ("quick_kernels",) and seen[0].pending == ("waiting_kernels",)
    with open(fifo, "w") as go:  # now let the child finish the second package
        go.write("go")
    thread.join(60)
    assert not thread.is_alive()
    assert [progress.done for progress in seen] == [("quick_kernels",), ("quick_kernels", "waiting_kernels")]
    assert len(warming._CHILDREN) >= 1 and warming._CHILDREN[-1].returncode == 0  # both compiled in one child


def test_the_small_course_package_shares_the_ball_s_compile_process() -> None:
    # A third child would cost Python's, numba's and LLVM's start on a machine where two children fill the cores.
    assert warming.PROCESSES == (("kernels.fabrik",), ("kernels.course", "kernels.ball"))
    assert sorted(name for group in warming.PROCESSES for name in group) == sorted(warming.MODULES)


def test_a_compile_process_outlives_ctrl_c_until_the_app_stops_it(
    fresh_warming: None, tmp_path: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    # Ctrl+C reaches the whole process group: a child that died of it first was reported as a failed compile, with
    # numba's KeyboardInterrupt traceback, before the app's exit stopped it.
    import os
    import signal
    import subprocess

    fifo = tmp_path / "go"
    os.mkfifo(fifo)
    (tmp_path / "stalled_kernels.py").write_text(f"def warm_up():\n    open({str(fifo)!r}).read()\n")
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")]))
    monkeypatch.setattr(warming, "_CHILDREN", [])
    child = warming._spawn(("stalled_kernels",))
    assert child is not None
    with open(fifo, "w") as go:  # opens once the child is waiting in warm_up (past its signal set-up)
        child.send_signal(signal.SIGINT)
        with pytest.raises(subprocess.TimeoutExpired):
            child.wait(timeout=1.0)  # still compiling
        go.write("go")
    assert child.wait(timeout=30) == 0
    assert child.stdout is not None and child.stdout.read().decode().split() == ["stalled_kernels"]
    assert warming._tail(child) == ""
