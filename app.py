"""Start the viser server with every scene behind one switcher.

python app.py                      # http://127.0.0.1:8080, peloton first
python app.py --scene peloton --port 8090
python app.py --host 0.0.0.0       # exposes the server to the network: read the warning it prints
python app.py --shared             # one scene for every browser tab (presenting to a room)

Ctrl+C stops it with one line. When 8080 is taken the app says so and serves on the next free port; a port given
with --port must be free, or the app refuses to start.
"""

from __future__ import annotations

import signal

_STOP_ASKED: list[int] = []
"""Ctrl+C while the app starts (its imports, reading its command line, starting the compile): held, and obeyed as
soon as the server is about to start (:func:`_obey_ctrl_c`)."""


def _hold_ctrl_c(signum: int, _frame: object) -> None:
    _STOP_ASKED.append(signum)


if __name__ == "__main__":
    # A KeyboardInterrupt in the first seconds (imports; tyro's lazy ones as it reads the command line) printed a
    # traceback, or was swallowed by a library that catches BaseException (trimesh importing scipy, importlib's
    # module-lock cleanup), and the app then served on as if nothing had happened.
    signal.signal(signal.SIGINT, _hold_ctrl_c)

import contextlib
import errno
import io
import ipaddress
import logging
import logging.handlers
import select
import socket
import sys
from typing import Annotated

from kernels import warming

_HELD = logging.handlers.MemoryHandler(capacity=1_000, flushLevel=logging.CRITICAL + 1)
"""Log lines from before the command line is read, held until it is (and dropped if it is refused)."""


def configure_logging(*, hold: bool = False) -> None:
    """The app's log lines on stderr, with time and source; websockets' line per connection left out, and its
    traceback for a connection that closes before its handshake (a port probe) too. ``hold``: keep them until the
    next call (which prints them), so that a refused command line prints only why."""
    root = logging.getLogger()
    root.setLevel(logging.INFO)
    logging.getLogger("websockets").setLevel(logging.WARNING)
    quiet = logging.getLogger("websockets.server")
    if _no_handshake not in quiet.filters:
        quiet.addFilter(_no_handshake)
    if hold:
        if not root.handlers:
            root.addHandler(_HELD)
        return
    if any(handler is not _HELD for handler in root.handlers):
        return  # configured already
    stream = logging.StreamHandler()
    stream.setFormatter(logging.Formatter("%(asctime)s %(name)s %(levelname)s %(message)s"))
    root.addHandler(stream)
    if _HELD in root.handlers:
        root.removeHandler(_HELD)
        _HELD.setTarget(stream)
        _HELD.flush()


def _no_handshake(record: logging.LogRecord) -> bool:
    """False for websockets' "opening handshake failed": a connection closed (or sent no HTTP) before its
    handshake, which a port probe or a health check does; it was an ERROR with three chained tracebacks."""
    return record.getMessage() != "opening handshake failed"


if __name__ == "__main__" and not any(arg in ("-h", "--help") or arg.startswith("--port") for arg in sys.argv[1:]):
    # A first start's compile processes begin before the imports below: about a second in which one of two cores
    # would idle. main() starts them where this did not (the installed command, a --port that may be refused,
    # --help; start() runs once).
    configure_logging(hold=True)  # first: a warm cache's loads are logged within the second, once main() runs
    warming.start()

import tyro
import viser

from scenes import SceneName
from scenes._look import configure_lighting
from scenes.sdf_gallery.editor import COMPILE_LIMIT_S, FRAME_LIMIT_S, set_editing_allowed
from server.gate import install_gate
from server.memory import limit_malloc_arenas
from server.sessions import Sessions
from server.switcher import SceneSwitcher
from shaders.glsl_sandbox import MAX_SOURCE_CHARS

logger = logging.getLogger("app")

DEFAULT_PORT = 8080
APP_LABEL = "Physics scenes"
"""Shown as the title of the control panel."""


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
    bound = f"[{host}]:{port}" if ":" in host else f"{host}:{port}"
    return (
        f"WARNING: binding {bound} exposes this server beyond this machine. Anyone who can reach that "
        "address can open the page, move every slider and drag every gizmo, with no password; the server runs "
        f"their inputs on this machine. Use --host 127.0.0.1 (the default) unless that is what you want. {glsl}"
    )


def serve_scenes(server: viser.ViserServer, scene: SceneName, *, shared: bool) -> SceneSwitcher | Sessions:
    """Put the scenes on ``server``: one switcher for every tab (``shared``), or one per tab, built as it connects."""
    limit_malloc_arenas()
    install_gate(server)
    return SceneSwitcher(server, scene) if shared else Sessions(server, scene)


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


def _bind(host: str, port: int, *, reuse: bool) -> None:
    """Bind a throwaway socket to ``host``:``port`` as viser would (``reuse``: address reuse on); raises
    ``socket.gaierror`` for a name that does not resolve, ``OSError`` for a bind that fails."""
    family, kind, proto, _name, address = socket.getaddrinfo(
        host, port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE
    )[0]
    with socket.socket(family, kind, proto) as probe:
        if reuse:
            probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        if family == socket.AF_INET6:  # as asyncio binds it: IPv6 alone, which takes no IPv4-mapped address
            probe.setsockopt(socket.IPPROTO_IPV6, socket.IPV6_V6ONLY, 1)
        probe.bind(address)


def host_problem(host: str) -> str | None:
    """Why the app cannot listen on ``host`` at all, in words, or None. viser takes every failure to bind for a busy
    port and tries the next one, a thousand times over: a mistyped address hung the app without a word, or was
    refused as a busy port."""
    with contextlib.suppress(ValueError):
        mapped = ipaddress.ip_address(host)
        if isinstance(mapped, ipaddress.IPv6Address) and mapped.ipv4_mapped is not None:
            # viser's server listens on IPv6 alone there, which cannot take it: its bind failed and the app hung
            return f"--host {host} is an IPv4 address written as IPv6; give it as --host {mapped.ipv4_mapped}."
    try:
        _bind(host, 0, reuse=False)  # port 0: any free port, so only the address is tried
    except (socket.gaierror, UnicodeError) as error:
        return f"--host {host!r} is not a name or address this machine can resolve ({error})."
    except OSError as error:
        if error.errno == errno.EADDRNOTAVAIL:
            return (
                f"--host {host} is not an address of this machine, so the app cannot listen on it. Give one of its "
                "own addresses, 127.0.0.1 (the default, this machine only) or 0.0.0.0 (every network it is on)."
            )
        return f"The app cannot listen on --host {host}: {error.strerror or error}."
    return None


def browser_url(host: str, port: int) -> str:
    """The address to open: this machine's for a wildcard bind (IPv6's for ``::``, which serves IPv6 alone), an IPv6
    address in brackets (RFC 3986)."""
    shown = {"0.0.0.0": "127.0.0.1", "::": "::1"}.get(host, host)
    return f"http://[{shown}]:{port}" if ":" in shown else f"http://{shown}:{port}"


def port_is_free(host: str, port: int) -> bool:
    """Whether ``port`` on ``host`` can be bound now, as viser would bind it (address reuse on, so a port whose last
    connections are closing still counts as free; one another process listens on does not). Ask
    :func:`host_problem` about the address first."""
    try:
        _bind(host, port, reuse=True)
    except OSError:
        return False
    return True


def make_server(host: str, port: int, *, verbose: bool = True) -> viser.ViserServer:
    """The viser server as the app serves it: its label on the panel, the wide control panel and the lighting that a
    browser without a GPU can keep up with (:mod:`scenes._look`).

    The browser tests build theirs with this too, so what they look at (and the README screenshots) is the app's.
    """
    server = viser.ViserServer(host=host, port=port, label=APP_LABEL, verbose=verbose)
    server.gui.configure_theme(control_width="large")
    configure_lighting(server.scene)
    return server


def main(
    scene: SceneName = "peloton",
    host: str = "127.0.0.1",
    port: Annotated[
        int | None, tyro.conf.arg(metavar="INT", help_behavior_hint="(default: 8080, or the next free port)")
    ] = None,
    allow_remote_glsl: bool = False,
    shared: bool = False,
) -> None:
    """Serve the physics scenes in the browser.

    Args:
        scene: which scene opens first.
        host: address to bind; the default accepts connections from this machine only.
        port: TCP port to bind. A port given here must be free, or the app refuses to start.
        allow_remote_glsl: with a non-loopback host, still let browsers type GLSL into the SDF gallery's editor.
        shared: one scene for all browser tabs (a switch or Reset in one changes it for all); else each has its own.
    """
    signal.signal(signal.SIGINT, _hold_ctrl_c)  # (the installed command's start: held from here)
    asked = DEFAULT_PORT if port is None else port
    if port is not None and not 1 <= port <= 65535:
        print(f"--port must be a TCP port from 1 to 65535, got {port}.", file=sys.stderr, flush=True)
        raise SystemExit(2)
    problem = host_problem(host)
    if problem is not None:
        print(problem, file=sys.stderr, flush=True)
        raise SystemExit(2)
    set_editing_allowed(is_loopback(host) or allow_remote_glsl)
    warning = exposure_warning(host, asked, allow_remote_glsl=allow_remote_glsl)
    if warning is not None:
        print(warning, flush=True)
    if port is not None and not port_is_free(host, port):  # refuse before viser prints a URL it will not serve
        print(port_message(port, port + 1, explicit=True), file=sys.stderr, flush=True)
        raise SystemExit(2)
    configure_logging()  # the command line is good: log lines held since the start come now
    warming.start()  # every scene draws at once; kernels run as plain Python until compiled
    server = None
    try:
        _obey_ctrl_c()
        with contextlib.redirect_stdout(io.StringIO()) if ":" in host else contextlib.nullcontext():
            server = make_server(host, asked)  # viser's box shows an IPv6 host as http://:::8080, no address
        message = port_message(asked, server.get_port(), explicit=port is not None)
        if message is not None and port is not None:  # taken between the check and the bind
            _stop_quietly(server)
            print(message, file=sys.stderr, flush=True)
            raise SystemExit(2)
        if message is not None:
            print(message, flush=True)
        serve_scenes(server, scene, shared=shared)
        print(f"Open {browser_url(host, server.get_port())} in a browser (Ctrl+C to stop).", flush=True)
        sleep_until_a_signal()
    except KeyboardInterrupt:
        if server is not None:
            _stop_quietly(server)
        print("Stopped.", flush=True)


def _obey_ctrl_c() -> None:
    """Ctrl+C is live from here on, and one held since the start (:data:`_STOP_ASKED`) stops the app now.

    Also where it was ignored: a shell starts a background job (`python app.py &` in a script) with SIGINT ignored,
    and Python leaves it so; Ctrl+C would not stop the app. It is live before the server starts, so a Ctrl+C sent as
    soon as the address shows is not lost.
    """
    signal.signal(signal.SIGINT, signal.default_int_handler)
    if _STOP_ASKED:
        raise KeyboardInterrupt


def sleep_until_a_signal() -> None:
    """Sleep until Ctrl+C, whichever thread the system hands the signal to.

    ``ViserServer.sleep_forever`` sleeps an hour at a time: when the system delivers SIGINT to one of the server's
    threads rather than the main one, the main thread sleeps on and the app does not stop. Here the main thread waits
    on Python's signal wake-up socket, which the interpreter writes to on any signal from any thread; the pending
    ``KeyboardInterrupt`` is then raised here.
    """
    reader, writer = socket.socketpair()
    reader.setblocking(False)
    writer.setblocking(False)
    previous = signal.set_wakeup_fd(writer.fileno())
    try:
        while True:
            select.select([reader], [], [])
            with contextlib.suppress(BlockingIOError):
                reader.recv(64)
    finally:
        signal.set_wakeup_fd(previous)
        reader.close()
        writer.close()


def _stop_quietly(server: viser.ViserServer) -> None:
    """Stop the server without viser's own farewell line: Ctrl+C answers with exactly one line, and a second Ctrl+C
    while it stops (about a second) does not interrupt the stop with a traceback."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    with contextlib.redirect_stdout(io.StringIO()):
        server.stop()


def entrypoint() -> None:
    tyro.cli(main)


if __name__ == "__main__":
    entrypoint()
