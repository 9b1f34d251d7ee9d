"""The app's port: a busy port given with --port is refused before any URL is printed; --help reads plainly."""

from __future__ import annotations

import itertools
import re
import socket
import subprocess
import sys
from pathlib import Path

import pytest
from helpers.ci import skip_or_fail
from helpers.processes import AppProcess

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
            [sys.executable, "app.py", "--port", str(busy)], cwd=ROOT, capture_output=True, text=True, timeout=120
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
    # An outside tester read "by default each          │ tab has its own scene": a line break of the docstring came
    # through, ending a line where the next word fitted. Every line of an entry is as full as the wrapping allows.
    box = [line[2:-2] for line in run.stdout.splitlines() if line.startswith("│ ") and line.endswith(" │")]
    for above, below in itertools.pairwise(box):
        column = len(below) - len(below.lstrip())  # where an entry's help text starts
        # ``below`` continues help text that ``above`` holds in that column (not an option too long for its own)
        if column >= 10 and above[column - 2 : column] == "  " and above[column:].strip():
            assert len(above.rstrip()) + 1 + len(below.split()[0]) > len(above), (above, below)


def test_a_port_outside_the_tcp_range_is_refused_in_words() -> None:
    for port in ("0", "-1", "99999"):
        run = subprocess.run(
            [sys.executable, "app.py", "--port", port], cwd=ROOT, capture_output=True, text=True, timeout=120
        )
        assert run.returncode == 2, port
        assert "--port must be a TCP port from 1 to 65535" in run.stderr and "Traceback" not in run.stderr
        assert "http://" not in run.stdout + run.stderr


# Kind: a bind failure read as a busy port. viser tries the next port on any failure to bind, a thousand times: a
# host that is not this machine's (--host 10.255.255.1) hung the app without a word, or, with --port, was refused
# as "Port 8096 is already in use"; a name that does not resolve hung it too.
def test_a_host_that_is_not_this_machines_is_refused_in_words() -> None:
    run = subprocess.run(
        [sys.executable, "app.py", "--host", "192.0.2.1", "--port", "8199"],  # TEST-NET-1 (RFC 5737): no machine's
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 2
    assert "--host 192.0.2.1 is not an address of this machine" in run.stderr
    assert "already in use" not in run.stderr and "http://" not in run.stdout + run.stderr
    assert "WARNING" not in run.stdout  # nothing is exposed: the exposure warning would mislead


# The failing input (an outside re-tester): an IPv4-mapped loopback passed the probe bind, which took it on a dual-stack
# socket, while viser's server listens on IPv6 alone: its bind failed, and the app hung with no address.
@pytest.mark.parametrize(("host", "plain"), [("::ffff:127.0.0.1", "127.0.0.1"), ("::ffff:192.0.2.1", "192.0.2.1")])
def test_an_ipv4_address_written_as_ipv6_is_refused_with_its_plain_form(host: str, plain: str) -> None:
    assert app.host_problem(host) == f"--host {host} is an IPv4 address written as IPv6; give it as --host {plain}."
    run = subprocess.run(
        [sys.executable, "app.py", "--host", host, "--port", "8199"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert run.returncode == 2 and "give it as --host" in run.stderr and "http://" not in run.stdout + run.stderr


def _has_ipv6_loopback() -> bool:
    try:
        with socket.socket(socket.AF_INET6, socket.SOCK_STREAM) as probe:
            probe.bind(("::1", 0))
    except OSError:
        return False
    return True


# Kind: an address no browser opens. For an IPv6 host viser's own box printed http://::1:8197 (and http://:::8197 for
# ::) beside the app's line; the warning read "binding :::8197".
def test_an_ipv6_host_prints_only_addresses_a_browser_opens() -> None:
    if not _has_ipv6_loopback():
        skip_or_fail("this machine has no IPv6 loopback")
    running = AppProcess("--host", "::1")
    running.close()
    port, shown = running.port, "".join(running.lines)
    assert f"Open http://[::1]:{port} in a browser" in shown
    assert re.findall(r"(?:http|ws)://\S+", shown) == [f"http://[::1]:{port}"], shown
    warning = app.exposure_warning("::", port)
    assert warning is not None and f"binding [::]:{port} exposes" in warning


def test_host_problem_names_an_unresolvable_name_and_passes_this_machines(monkeypatch: pytest.MonkeyPatch) -> None:
    assert app.host_problem("127.0.0.1") is None
    assert app.host_problem("localhost") is None

    def unresolvable(*args: object, **kwargs: object) -> object:
        raise socket.gaierror(socket.EAI_NONAME, "Name or service not known")

    monkeypatch.setattr(socket, "getaddrinfo", unresolvable)
    problem = app.host_problem("not-a-host.invalid")
    assert problem is not None and "'not-a-host.invalid' is not a name or address this machine can resolve" in problem


@pytest.mark.parametrize(
    ("host", "url"),
    [
        ("127.0.0.1", "http://127.0.0.1:8080"),
        ("0.0.0.0", "http://127.0.0.1:8080"),
        ("::", "http://[::1]:8080"),  # asyncio binds :: to IPv6 alone: 127.0.0.1 was refused
        ("::1", "http://[::1]:8080"),  # it read http://::1:8080, which no browser opens
        ("localhost", "http://localhost:8080"),
    ],
)
def test_the_url_to_open_is_one_a_browser_opens(host: str, url: str) -> None:
    assert app.browser_url(host, 8080) == url
