"""A trial of an editor source in a short-lived child process, stopped at the time limit.

A GLSL compiler can take minutes on a short source (every call is inlined, so a chain of functions that each call
the one before twice doubles at each link), and moderngl holds Python's GIL while the driver compiles: in the
server's own process that froze every viewer. So a new source is first compiled and drawn once here, in a child
process with its own EGL context; the parent waits without holding the GIL and kills the child at the limit. Only a
source that passes is compiled in the server.

Run as ``python -m shaders.trial``: it reads one JSON request on stdin, prints ``ready`` once its context exists
(the clock starts then, so a slow start on a loaded machine is not counted), then one JSON line with the compile
and frame times or the compiler's error.
"""

from __future__ import annotations

import dataclasses
import json
import os
import queue
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from shaders.camera import Camera, Shading
from shaders.glsl_sandbox import ShaderCompileError
from shaders.renderer import GLUnavailableError

START_LIMIT_S = 60.0
"""Longest wait for the child's Python and EGL context to start (s); not part of the source's limits."""
_ROOT = Path(__file__).resolve().parent.parent


@dataclasses.dataclass(frozen=True)
class TrialTimes:
    """What a trial measured in the child (s)."""

    compile_s: float
    frame_s: float


def trial(
    source: str,
    shadings: list[Shading],
    camera: Camera,
    bounds: ArrayLike,
    width: int,
    height: int,
    compile_limit_s: float,
    frame_limit_s: float,
) -> TrialTimes:
    """Compile ``source`` for every shading in ``shadings`` and draw one ``width`` × ``height`` frame with the first,
    in a child process killed once ``compile_limit_s + frame_limit_s`` have passed since its context was ready.

    Raises:
        ShaderCompileError: the compiler refused the source, or compiling or the frame ran past its limit (the
            message says which and the limit).
        GLUnavailableError: the child could not make a GL context.
    """
    request = {
        "source": source,
        "shadings": [dataclasses.asdict(s) for s in shadings],
        "camera": dataclasses.asdict(camera),
        "bounds": np.asarray(bounds, dtype=np.float64).tolist(),
        "width": int(width),
        "height": int(height),
    }
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(_ROOT), *filter(None, [env.get("PYTHONPATH")])])
    proc = subprocess.Popen(
        [sys.executable, "-m", "shaders.trial"],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        env=env,
        cwd=_ROOT,
        text=True,
    )
    lines: queue.SimpleQueue[str] = queue.SimpleQueue()

    def read() -> None:
        assert proc.stdout is not None
        for line in proc.stdout:
            lines.put(line)
        lines.put("")  # the child ended

    threading.Thread(target=read, name="glsl-trial-reader", daemon=True).start()
    try:
        assert proc.stdin is not None
        proc.stdin.write(json.dumps(request))
        proc.stdin.close()
        try:
            first = lines.get(timeout=START_LIMIT_S)
        except queue.Empty:
            raise GLUnavailableError(f"the GLSL trial process did not start within {START_LIMIT_S:.0f} s") from None
        if first.strip() != "ready":
            answer = json.loads(first) if first.strip() else {"error": "the trial process ended"}
            raise GLUnavailableError(str(answer.get("error")))
        try:
            answer = json.loads(lines.get(timeout=compile_limit_s + frame_limit_s) or "{}")
        except queue.Empty:
            raise ShaderCompileError(
                f"compiling and one test frame took longer than {compile_limit_s + frame_limit_s:.0f} s, so "
                "they were stopped; the limits are "
                f"{compile_limit_s:.0f} s to compile and {1e3 * frame_limit_s:.0f} ms a frame",
                None,
            ) from None
    finally:
        if proc.poll() is None:
            proc.kill()
        proc.wait()
    if "compile_error" in answer:
        raise ShaderCompileError(answer["compile_error"], answer.get("line"))
    if "compile_s" not in answer:
        raise ShaderCompileError(
            "the GLSL trial process ended without an answer (the driver may have crashed on this source)", None
        )
    times = TrialTimes(float(answer["compile_s"]), float(answer["frame_s"]))
    if times.compile_s > compile_limit_s:
        raise ShaderCompileError(f"compiling took {times.compile_s:.1f} s; the limit is {compile_limit_s:.0f} s", None)
    if times.frame_s > frame_limit_s:
        raise ShaderCompileError(
            f"one {width}-pixel-wide frame took {1e3 * times.frame_s:.0f} ms; the limit is "
            f"{1e3 * frame_limit_s:.0f} ms",
            None,
        )
    return times


def _tuples(fields: dict[str, Any]) -> dict[str, Any]:
    """JSON's lists back to the dataclasses' tuples."""
    out: dict[str, Any] = {}
    for key, value in fields.items():
        out[key] = tuple(value) if isinstance(value, list) else value
    return out


def _say(line: str) -> None:
    sys.stdout.write(line + "\n")
    sys.stdout.flush()


def _child() -> None:
    from shaders.renderer import Renderer

    request = json.loads(sys.stdin.read())
    try:
        gl = Renderer(builtin=False)
    except GLUnavailableError as exc:
        _say(json.dumps({"error": str(exc)}))
        return
    _say("ready")
    shadings = [Shading(**_tuples(s)) for s in request["shadings"]]
    camera = Camera(**_tuples(request["camera"]))
    try:
        start = time.perf_counter()
        for shading in shadings:
            gl.compile_field(request["source"], shading)
        compile_s = time.perf_counter() - start
        start = time.perf_counter()
        gl.render_field(request["source"], request["bounds"], camera, request["width"], request["height"], shadings[0])
        frame_s = time.perf_counter() - start
    except ShaderCompileError as exc:
        _say(json.dumps({"compile_error": exc.reason, "line": exc.line}))
        return
    _say(json.dumps({"compile_s": compile_s, "frame_s": frame_s}))


if __name__ == "__main__":
    _child()
