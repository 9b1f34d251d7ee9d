"""Start the viser server with every scene behind one switcher.

python app.py                      # http://127.0.0.1:8080, peloton first
python app.py --scene peloton --port 8090
python app.py --host 0.0.0.0       # exposes the server to the network: read the warning it prints

Ctrl+C stops it with one line. When 8080 is taken the app says so and serves on the next free port; a port given
with --port must be free, or the app refuses to start.
"""

from __future__ import annotations

import contextlib
import io
import ipaddress
import logging
import sys

import tyro
import viser

from scenes import SceneName
from scenes.switcher import SceneSwitcher

logger = logging.getLogger("app")

DEFAULT_PORT = 8080


def is_loopback(host: str) -> bool:
    """True when ``host`` only accepts connections from this machine."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def exposure_warning(host: str, port: int) -> str | None:
    """The warning to print when ``host`` is reachable from other machines, else None."""
    if is_loopback(host):
        return None
    return (
        f"WARNING: binding {host}:{port} exposes this server beyond this machine. Anyone who can reach that "
        "address can open the page, move every slider and drag every gizmo, with no password; the server runs "
        "their inputs on this machine. Use --host 127.0.0.1 (the default) unless that is what you want."
    )


def port_message(asked: int, bound: int, explicit: bool) -> str | None:
    """What to tell the user when viser bound another port than the one asked for (it moves on when one is busy)."""
    if bound == asked:
        return None
    if explicit:
        return (
            f"Port {asked} is already in use (another copy of this app?). Stop that process, or choose a free "
            "port with --port."
        )
    return f"Port {asked} is already in use; serving on port {bound} instead."


APP_LABEL = "Physics scenes"
"""Shown as the title of the control panel."""


def make_server(host: str, port: int, *, verbose: bool = True) -> viser.ViserServer:
    """The viser server as the app serves it: its label on the panel and the wide control panel.

    The browser tests build theirs with this too, so what they look at (and the README screenshots) is the app's.
    """
    server = viser.ViserServer(host=host, port=port, label=APP_LABEL, verbose=verbose)
    server.gui.configure_theme(control_width="large")
    return server


def main(scene: SceneName = "peloton", host: str = "127.0.0.1", port: int | None = None) -> None:
    """Serve the physics scenes in the browser.

    Args:
        scene: which scene opens first.
        host: address to bind; the default accepts connections from this machine only.
        port: TCP port to bind (8080 when not given, or the next free one). A port given here must be free.
    """
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s %(levelname)s %(message)s")
    logging.getLogger("websockets").setLevel(logging.WARNING)  # not a line per start and stop
    asked = DEFAULT_PORT if port is None else port
    warning = exposure_warning(host, asked)
    if warning is not None:
        print(warning, flush=True)
    server = None
    try:
        server = make_server(host, asked)
        message = port_message(asked, server.get_port(), explicit=port is not None)
        if message is not None and port is not None:
            _stop_quietly(server)
            print(message, file=sys.stderr, flush=True)
            raise SystemExit(2)
        if message is not None:
            print(message, flush=True)
        SceneSwitcher(server, scene)
        shown_host = "127.0.0.1" if host in ("0.0.0.0", "::") else host
        print(
            f"Open http://{shown_host}:{server.get_port()} in a browser (Ctrl+C to stop).",
            flush=True,
        )
        server.sleep_forever()
    except KeyboardInterrupt:
        if server is not None:
            _stop_quietly(server)
        print("Stopped.", flush=True)


def _stop_quietly(server: viser.ViserServer) -> None:
    """Stop the server without viser's own farewell line: Ctrl+C answers with exactly one line."""
    with contextlib.redirect_stdout(io.StringIO()):
        server.stop()


def entrypoint() -> None:
    tyro.cli(main)


if __name__ == "__main__":
    entrypoint()
