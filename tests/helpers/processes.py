"""Running a snippet of Python in a fresh interpreter, as a test that needs a cold process does."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Mapping
from pathlib import Path


def python_stdout(
    script: str, *, timeout_s: float, cwd: Path | None = None, env: Mapping[str, str] | None = None
) -> str:
    """Run ``python -c script`` in a new process with this interpreter and return what it printed.

    Raises ``subprocess.CalledProcessError`` when the script fails, and ``subprocess.TimeoutExpired`` after
    ``timeout_s`` seconds.
    """
    command = [sys.executable, "-c", script]
    return subprocess.run(
        command, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout_s, check=True
    ).stdout
