"""Start the viser server with every scene behind one switcher.

python app.py                      # http://127.0.0.1:8080, peloton first
python app.py --scene peloton --port 8090
python app.py --host 0.0.0.0       # exposes the server to the network: read the warning it prints
"""

from __future__ import annotations

import ipaddress
import logging

import tyro
import viser

from scenes import SceneName
from scenes.sdf_gallery import COMPILE_LIMIT_S, FRAME_LIMIT_S, MAX_SOURCE_CHARS, set_editing_allowed
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


def exposure_warning(host: str, port: int, *, allow_remote_glsl: bool = False) -> str | None:
    """The warning to print when ``host`` is reachable from other machines, else None."""
    if is_loopback(host):
        return None
    glsl = (
        "GLSL editing in the SDF gallery is ON (--allow-remote-glsl): anyone can make this machine compile and "
        f"run their shader code. What is enforced: at most {MAX_SOURCE_CHARS} characters, no loops, no # lines, a "
        "bound on the code once calls are inlined, and a trial compile and frame in a child process killed after "
        f"{COMPILE_LIMIT_S:.0f} s + {FRAME_LIMIT_S:.0f} s; "
        "a source that passes is compiled again in the server (briefly blocking it) and its frames are not "
        "stopped mid-draw."
        if allow_remote_glsl
        else "GLSL editing in the SDF gallery is OFF (its examples still work); --allow-remote-glsl turns it on."
    )
    return (
        f"WARNING: binding {host}:{port} exposes this server beyond this machine. Anyone who can reach that "
        "address can open the page, move every slider and drag every gizmo, with no password; the server runs "
        f"their inputs on this machine. Use --host 127.0.0.1 (the default) unless that is what you want. {glsl}"
    )


def main(
    scene: SceneName = "peloton",
    host: str = "127.0.0.1",
    port: int = 8080,
    allow_remote_glsl: bool = False,
) -> None:
    """Serve the physics scenes in the browser.

    Args:
        scene: which scene opens first.
        host: address to bind; the default accepts connections from this machine only.
        port: TCP port to bind.
        allow_remote_glsl: with a non-loopback host, still let browsers type GLSL into the SDF gallery's editor.
    """
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s %(levelname)s %(message)s")
    set_editing_allowed(is_loopback(host) or allow_remote_glsl)
    warning = exposure_warning(host, port, allow_remote_glsl=allow_remote_glsl)
    if warning is not None:
        print(warning, flush=True)
    server = viser.ViserServer(host=host, port=port, label="Physics scenes")
    server.gui.configure_theme(control_width="large")
    SceneSwitcher(server, scene)
    shown_host = "127.0.0.1" if host in ("0.0.0.0", "::") else host
    print(
        f"Open http://{shown_host}:{server.get_port()} in a browser (Ctrl+C to stop).", flush=True
    )
    server.sleep_forever()


def entrypoint() -> None:
    tyro.cli(main)


if __name__ == "__main__":
    entrypoint()
