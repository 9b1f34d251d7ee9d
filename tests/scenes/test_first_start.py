"""The scenes on a first start, while their kernels compile in the background (kernels.warming): each is built and
answers its controls with the plain-Python kernels, and the free kick's outcome map (1,271 flights) waits for the
compiled flight instead of taking ~10 s of plain Python, then is drawn once it lands."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
import viser

from kernels import warming
from scenes import SCENES
from scenes.freekick import FreeKickScene
from scenes.freekick.model import MAP_SPEEDS_MS, MAP_SPINS_REV_S


@pytest.fixture
def compiling() -> Iterator[None]:
    """Every kernel package pending, as in the first seconds of a cold first start; entries run their twins."""
    warming._reset_for_tests()
    warming._STATE.started_at = 0.0
    warming._STATE.pending = set(warming.MODULES)
    yield
    warming._reset_for_tests()


TWINS_RUN = {"arm": {"_solve_one"}, "freekick": {"simulate_one", "judge"}, "peloton": set(), "sdf": set()}
"""Compiled cores each scene runs as plain Python when it opens (the peloton's model and the SDF gallery's fields are
numpy; the course mode's ride loop runs when it is picked)."""


@pytest.mark.parametrize("key", sorted(SCENES))
def test_every_scene_is_built_and_answers_while_its_kernels_compile(
    key: str, compiling: None, server: viser.ViserServer, monkeypatch: pytest.MonkeyPatch
) -> None:
    twins_run: set[str] = set()

    def as_on_a_cold_start(self: warming.Entry, *args: object, **kwargs: object) -> object:  # type: ignore[type-arg]
        twins_run.add(self.__name__)  # this process's cache may be warm: run the twin as a cold start would
        return warming.python_twin(self.compiled)(*args, **kwargs)

    monkeypatch.setattr(warming.Entry, "__call__", as_on_a_cold_start)
    scene = SCENES[key](server)
    try:
        wait_idle = getattr(scene, "wait_idle", None)
        if wait_idle is not None:
            assert wait_idle(60.0)
        assert TWINS_RUN[key] <= twins_run
        before = scene.params
        # The first slider moved as a browser would: the scene takes it with the plain-Python kernels.
        controls: Any = getattr(scene, "scene_controls" if key == "sdf" else "controls")  # the gallery: per folder
        name, built = next(
            (n, b) for n, b in controls.fields.items() if isinstance(b.handles[0], viser.GuiSliderHandle)
        )
        slider = built.handles[0]
        slider.value = slider.value + 0.5 * (slider.max - slider.value)
        if wait_idle is not None:
            assert wait_idle(60.0)
        moved = getattr(scene.params, name)
        assert moved != getattr(before, name) and moved == pytest.approx(slider.value)
    finally:
        scene.close()


def test_the_outcome_map_waits_for_the_compiled_flight_then_draws(compiling: None, server: viser.ViserServer) -> None:
    scene = FreeKickScene(server)
    try:
        assert scene.wait_idle(30.0)
        assert scene.map_results is None and scene.map_runs == 0
        assert "once the ball-flight kernels have compiled" in scene.map_status.content
        warming._finish("kernels.ball")  # the background compile lands
        assert scene.wait_idle(60.0)
        assert scene.map_runs == 1 and scene.map_results is not None
        assert scene.map_results.shape == (len(MAP_SPINS_REV_S), len(MAP_SPEEDS_MS))
        assert np.isin(scene.map_results, ("goal", "wall", "over", "wide", "short")).all()
        assert scene.map_status.content.startswith("Of 1271 kicks:")
    finally:
        scene.close()


WARMED_SCENES_SCRIPT = """
import numba, sys, viser
from kernels import warming
from scenes import SCENES
from scenes._skeletons import PRESET_LABELS
for name in warming.MODULES:
    __import__(name, fromlist=["warm_up"]).warm_up()
def compiled():
    return {
        (module, name, str(signature))
        for module, value in list(sys.modules.items()) if module.startswith("kernels.")
        for name, dispatcher in vars(value).items() if isinstance(dispatcher, numba.core.dispatcher.Dispatcher)
        for signature in dispatcher.signatures
    }
before = compiled()
server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
for key, kind in SCENES.items():
    scene = kind(server)
    if key == "arm":
        for label in PRESET_LABELS:
            scene.controls["preset"].value = label
    getattr(scene, "wait_idle", lambda timeout_s: True)(120.0)
    scene.close()
server.stop()
print("NEW", sorted(compiled() - before))
"""


def test_once_warmed_up_no_scene_compiles_anything() -> None:
    # What the app's background compile loads must cover every call the scenes make (each scene, each arm preset),
    # or a scene would stall on a compile after the status line has gone. A fresh process: this one's dispatchers
    # already hold whatever earlier tests compiled.
    import subprocess
    import sys

    from helpers.paths import ROOT

    run = subprocess.run(
        [sys.executable, "-c", WARMED_SCENES_SCRIPT], cwd=ROOT, capture_output=True, text=True, timeout=600
    )
    assert run.returncode == 0, run.stderr[-3000:]
    assert run.stdout.strip().splitlines()[-1] == "NEW []"


def test_the_arm_says_a_solve_time_is_plain_python_while_its_kernels_compile(
    compiling: None, server: viser.ViserServer
) -> None:
    from scenes.arm import ArmScene

    scene = ArmScene(server)
    try:
        assert "Solve time" in scene.readout.content
        assert scene.readout.content.endswith("(plain Python: the first start is still compiling)")
        warming._finish("kernels.fabrik")
        scene.controls["n_links"].value = scene.params.n_links + 1  # the next solve is the compiled one's
        assert "Solve time" in scene.readout.content and "plain Python" not in scene.readout.content
    finally:
        scene.close()
