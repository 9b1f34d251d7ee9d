"""What every benchmark here times and prints with: wall-clock times of repeated calls, their 95th percentile, a
table row of median and p95, and a scene's input handling timed where its callback runs it."""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from scenes.freekick import FreeKickScene
    from scenes.peloton import PelotonScene


def timings(call: Callable[[], object], repeat: int, *, warmup: int = 0, scale: float = 1.0) -> list[float]:
    """Wall-clock time of each of ``repeat`` calls of ``call`` (s, times ``scale``: 1e3 for ms), after ``warmup``
    calls left untimed."""
    for _ in range(warmup):
        call()
    out = []
    for _ in range(repeat):
        start = time.perf_counter()
        call()
        out.append(scale * (time.perf_counter() - start))
    return out


def p95(values: list[float]) -> float:
    """The 95th percentile (numpy's linear interpolation)."""
    return float(np.percentile(values, 95))


def row(name: str, values: list[float], unit: float, unit_name: str, note: str = "", *, width: int = 46) -> None:
    """Print one table row: ``name`` padded to ``width``, then the median and p95 of ``values`` in ``unit``."""
    median, high = statistics.median(values) / unit, p95(values) / unit
    print(f"| {name:<{width}} | {median:>10.3f} | {high:>10.3f} | {unit_name:<4} | {note}")


def time_handling(scene: FreeKickScene | PelotonScene, names: Iterable[str]) -> list[float]:
    """Make the scene's controls ``names`` call its ``apply_inputs`` timed: the list returned gets each call's
    wall-clock time (s), as the scene's callback runs it (serialised, with the process's turn)."""
    handling: list[float] = []
    inner = scene.apply_inputs

    def timed_on_input() -> None:
        start = time.perf_counter()
        inner()
        handling.append(time.perf_counter() - start)

    for name in names:
        handle = scene.controls[name]
        handle.remove_update_callback()
        handle.on_update(scene.callback(timed_on_input))
    return handling
