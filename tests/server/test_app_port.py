"""The app's port: a busy port given with --port is refused before any URL is printed; --help reads plainly."""

from __future__ import annotations

import socket
import subprocess
import sys
from pathlib import Path

import app

ROOT = Path(__file__).resolve().parents[2]


def _listening() -> socket.socket:
    holder = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    holder.bind(("127.0.0.1", 0))
    holder.listen()
    return holder


def test_port_is_free_tells_a_listening_port_from_a_free_one() -> None:
    with _listening() as holder:
        busy = holder.getsockname()[1]
        assert not app.port_is_free("127.0.0.1", busy)
    assert app.port_is_free("127.0.0.1", busy)  # closed again


def test_a_busy_port_given_with_port_is_refused_without_a_url() -> None:
    with _listening() as holder:
        busy = holder.getsockname()[1]
        run = subprocess.run(
            [sys.executable, "app.py", "--port", str(busy)],
            cwd=ROOT,
            capture_output=True,
            text=True,
            timeout=120,
        )
    assert run.returncode == 2
    assert f"Port {busy} is already in use" in run.stderr
    assert "http://" not in run.stdout + run.stderr  # viser's banner would name a port it never serves


def test_help_names_the_port_default_in_words() -> None:
    run = subprocess.run([sys.executable, "app.py", "--help"], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert run.returncode == 0
    text = " ".join(run.stdout.split())
    assert "--port INT" in text and "{None}" not in text
    assert "default: 8080, or the next free port" in text.replace("│ ", "").replace(" │", "")


def test_a_port_outside_the_tcp_range_is_refused_in_words() -> None:
    for port in ("0", "-1", "99999"):
        run = subprocess.run(
            [sys.executable, "app.py", "--port", port], cwd=ROOT, capture_output=True, text=True, timeout=120
        )
        assert run.returncode == 2, port
        assert "--port must be a TCP port from 1 to 65535" in run.stderr and "Traceback" not in run.stderr
        assert "http://" not in run.stdout + run.stderr
