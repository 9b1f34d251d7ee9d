"""Fresh processes: a snippet of Python in a cold interpreter, and ``app.py`` itself as a user starts it."""

from __future__ import annotations

import re
import signal
import socket
import subprocess
import sys
import threading
from collections.abc import Callable, Mapping
from pathlib import Path

from helpers.paths import ROOT
from helpers.waiting import wait_until


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


def rss_bytes(pid: int | str = "self") -> int:
    """Resident memory of process ``pid`` (bytes)."""
    with open(f"/proc/{pid}/status") as status:
        match = re.search(r"VmRSS:\s+(\d+) kB", status.read())
    assert match is not None
    return int(match.group(1)) * 1024


def free_port() -> int:
    """A TCP port free on 127.0.0.1 now."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


class AppProcess:
    """``app.py`` in its own process, on a free port, started and read up to the address it prints (stdout and
    stderr together, as a terminal shows them); ``preexec_fn`` runs in the child first (e.g. a background job's
    ignored SIGINT), ``env`` is its environment (this process's by default)."""

    def __init__(
        self,
        *args: str,
        preexec_fn: Callable[[], object] | None = None,
        env: Mapping[str, str] | None = None,
        timeout_s: float = 120.0,
    ) -> None:
        self.port = free_port()
        self.process = subprocess.Popen(
            [sys.executable, str(ROOT / "app.py"), "--port", str(self.port), *args],
            cwd=ROOT,
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            preexec_fn=preexec_fn,
        )
        self.lines: list[str] = []
        """What the app has printed and logged so far."""
        # Read from the start, so a chatty app never blocks on a full pipe, and a test can look at its log.
        self._reader = threading.Thread(target=self._read_output, daemon=True)
        self._reader.start()
        try:
            wait_until(
                lambda: self._address_line() is not None or self.process.poll() is not None,
                "the app to print its address",
                timeout_s,
            )
            address = self._address_line()
            assert address is not None and self.process.poll() is None, f"the app did not start:\n{self.log}"
        except AssertionError:
            self.close()
            raise
        self.started = address + 1
        """How many lines it printed up to its address."""

    def _address_line(self) -> int | None:
        """The index of the line that gives the app's address, once printed."""
        return next((i for i, line in enumerate(list(self.lines)) if "Open http" in line), None)

    def wait_compiled(self, timeout_s: float = 300.0) -> None:
        """Wait until the app has loaded every compiled kernel (its first start compiles them in the background, and
        loading them grows its memory: measure after that)."""
        wait_until(lambda: "compiled kernels ready" in self.log, "the app's kernels compiled and loaded", timeout_s)

    def _read_output(self) -> None:
        assert self.process.stdout is not None
        for line in self.process.stdout:
            self.lines.append(line)

    @property
    def log(self) -> str:
        return "".join(self.lines)

    @property
    def rss(self) -> int:
        return rss_bytes(self.process.pid)

    def interrupt(self, timeout_s: float = 60.0) -> list[str]:
        """Ctrl+C: SIGINT, then wait for the app to exit; what it printed after its address."""
        self.process.send_signal(signal.SIGINT)
        self.process.wait(timeout=timeout_s)
        self._reader.join(timeout=timeout_s)
        return self.lines[self.started :]

    def close(self) -> None:
        """Stop the app (SIGTERM, then SIGKILL after 20 s) and read the rest of what it printed into ``lines``."""
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout=20)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait(timeout=20)
        self._reader.join(timeout=5.0)
