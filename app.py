"""Start the viser server with every scene behind one switcher.

python app.py                      # http://127.0.0.1:8080, peloton first
python app.py --scene peloton --port 8090
python app.py --host 0.0.0.0       # exposes the server to the network: read the warning it prints
python app.py --shared             # one scene for every browser tab (presenting to a room)
"""

from __future__ import annotations

import ipaddress
import logging

import tyro
import viser

from scenes import SceneName
from scenes._gate import install_gate
from scenes._session import Sessions, limit_malloc_arenas
from scenes.switcher import SceneSwitcher

logger = logging.getLogger("app")


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


def serve_scenes(
    server: viser.ViserServer, scene: SceneName, *, shared: bool
) -> SceneSwitcher | Sessions:
    """Put the scenes on ``server``: one switcher for every tab (``shared``), or one per tab, built as it connects."""
    limit_malloc_arenas()
    install_gate(server)
    return SceneSwitcher(server, scene) if shared else Sessions(server, scene)


def main(
    scene: SceneName = "peloton", host: str = "127.0.0.1", port: int = 8080, shared: bool = False
) -> None:
    """Serve the physics scenes in the browser.

    Args:
        scene: which scene opens first.
        host: address to bind; the default accepts connections from this machine only.
        port: TCP port to bind.
        shared: one scene for every browser tab (a switch or Reset in one tab changes it for all); by default each
            tab has its own scene.
    """
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s %(levelname)s %(message)s")
    warning = exposure_warning(host, port)
    if warning is not None:
        print(warning, flush=True)
    server = viser.ViserServer(host=host, port=port, label="Physics scenes")
    server.gui.configure_theme(control_width="large")
    serve_scenes(server, scene, shared=shared)
    shown_host = "127.0.0.1" if host in ("0.0.0.0", "::") else host
    print(
        f"Open http://{shown_host}:{server.get_port()} in a browser (Ctrl+C to stop).", flush=True
    )
    server.sleep_forever()


def entrypoint() -> None:
    tyro.cli(main)


if __name__ == "__main__":
    entrypoint()
