"""The first start on an empty compile cache: how soon each scene is built and has computed its first frame, and how
long until every kernel is compiled.

    python bench/bench_first_start.py            # both runs below, each in a fresh process with an empty cache
    python bench/bench_first_start.py --only warming

Two runs, each in a fresh process with its own empty ``NUMBA_CACHE_DIR``:
- *warming*, as the app starts: :func:`kernels.warming.start` compiles in child processes while the scenes' kernels
  run as plain Python; the four scenes are then built one after another on a server, each timed until its first
  frame is computed (its workers idle), and the time until every kernel is compiled and loaded is printed.
- *baseline*, the same scenes with no background compile: each first call compiles where it stands.

Prints a table per run (seconds); the warming run adds the CPU seconds its compile processes used (user + system,
summed over them: on a busy machine the wall time stretches, this much less). The browser's own draw adds a fraction of
a second on top (see docs/performance.md).
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENE_KEYS = ("peloton", "arm", "freekick", "sdf")


def run_child(warming_on: bool) -> None:
    """In a fresh process: build each scene and time it (the parent set an empty ``NUMBA_CACHE_DIR``)."""
    started = time.perf_counter()
    from kernels import warming

    ready: list[float] = []  # when the last package was loaded (the thread ends later: it waits for its children)
    if warming_on:  # as app.py does: the compile processes start before the app's other imports

        def report(progress: warming.Progress) -> None:
            ready.append(time.perf_counter() - started)
            print(f"| {warming.LABELS[progress.done[-1]]} kernels compiled and loaded (from start) | {ready[-1]:.2f} |")

        warming.on_progress(report)
    thread = warming.start() if warming_on else None
    import viser

    from scenes import SCENES
    from server.switcher import SceneSwitcher

    print(f"| {'start + ' if warming_on else ''}imports | {time.perf_counter() - started:.2f} |", flush=True)
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        for key in SCENE_KEYS:
            assert key in SCENES, key
            begin = time.perf_counter()
            switcher = SceneSwitcher(server, key)
            wait_idle = getattr(switcher.scene, "wait_idle", None)
            if wait_idle is not None:
                wait_idle(300.0)
            print(f"| {key} built with its first frame | {time.perf_counter() - begin:.2f} |", flush=True)
            switcher.close()
        if thread is not None:
            thread.join()
            print(f"| every kernel compiled and loaded (from start) | {ready[-1]:.2f} |")
            children = resource.getrusage(resource.RUSAGE_CHILDREN)
            print(f"| CPU time of the compile processes, together | {children.ru_utime + children.ru_stime:.2f} |")
            own = resource.getrusage(resource.RUSAGE_SELF)
            print(f"| CPU time of this process (imports, scenes, cache loads) | {own.ru_utime + own.ru_stime:.2f} |")
    finally:
        server.stop()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--child", choices=("warming", "baseline"), help=argparse.SUPPRESS)
    parser.add_argument("--only", choices=("warming", "baseline"), help="run only this one of the two runs")
    args = parser.parse_args()
    if args.child is not None:
        run_child(args.child == "warming")
        return
    print(f"# First start on an empty numba cache ({os.cpu_count()} cores, {time.strftime('%Y-%m-%d %H:%M')})")
    for mode in (args.only,) if args.only else ("warming", "baseline"):
        with tempfile.TemporaryDirectory(prefix="numba-cold-") as cache:
            print(f"\n## {mode}\n| step | s |\n|---|---:|", flush=True)
            env = dict(os.environ, NUMBA_CACHE_DIR=cache, PYTHONPATH=str(ROOT))
            subprocess.run([sys.executable, __file__, "--child", mode], env=env, cwd=ROOT, check=True)


if __name__ == "__main__":
    main()
