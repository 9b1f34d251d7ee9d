"""Soak test: N browsers (default 8), one process each, driving every scene at 30 messages/s, shared and per tab.

    python bench/bench_soak.py [--clients 8] [--rate 30] [--seconds 60] [--scenes peloton arm freekick sdf]
                               [--modes session shared]

For each mode and scene it starts ``app.py`` in its own process (``--shared`` for the shared mode) and N fake
browsers (``tests/wsclient.py``), each in its own process. Each browser moves its scene's main input at ``rate``
messages per second for ``seconds``: the peloton's speed slider, the arm's target gizmo, the free kick's launch
speed slider, the SDF gallery's second primitive's gizmo. It prints:

- the app's RSS over the run (every 10 s; the last figure is after the browsers closed) and its slope while they
  ran, after the first minute (after the first third on runs shorter than three minutes), in MiB/min;
- p50 and p95 from a message to the next scene update the sender receives (in the shared mode another browser's
  change can bring that update: the figure is a lower bound there);
- errors: browser exceptions, connections the server closed, and ERROR or Traceback lines in the app's log;
- whether every viewer ends on the server's values: per tab, the value (or pose) it shows is the last it sent; shared,
  every viewer shows what a browser that connects after the run is told.

Goals (2 cores, 8 browsers): no errors, RSS slope ≤ 1 MiB/min after the first minute, p95 ≤ 50 ms for the peloton,
arm and free kick, ≤ 150 ms for the SDF gallery.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from wsclient import BrowserClient  # noqa: E402

MIB = 1024 * 1024
GOAL_P95_MS = {"peloton": 50.0, "arm": 50.0, "freekick": 50.0, "sdf": 150.0}
SLIDERS = {"peloton": ("Speed (km/h)", 20.0, 60.0), "freekick": ("Launch speed (m/s)", 20.0, 32.0)}
GIZMOS = {"arm": ("/arm/target", 0.35), "sdf": ("/sdf/gizmo_2", 0.15)}
"""Gizmo name and the radius (m) of the circle each browser drags it round."""


# ------------------------------------------------------------------------------------------------ one browser
def run_client(port: int, scene: str, rate: float, seconds: float, index: int) -> dict[str, Any]:
    """One fake browser's run; returns what the parent reports."""
    result: dict[str, Any] = {"errors": [], "latencies_ms": [], "sent": 0}
    client = BrowserClient(port)
    try:
        period = 1.0 / rate
        sends: list[float] = []
        last: Any = None
        if scene in SLIDERS:
            label, lo, hi = SLIDERS[scene]
            client.wait_for_gui(label, timeout=120)
            client.wait_for_node(f"/{scene}", timeout=120)
        else:
            name, radius = GIZMOS[scene]
            node = client.wait_for_node(name, timeout=120)
            centre = [float(v) for v in node.get("position", (0.0, 0.0, 0.0))]
            if scene == "arm":
                centre = [0.55, 0.0, 0.6]
            owner = str(node.get("owner", "") or "")
            client.send("TransformControlsDragStartMessage", name=name, owner=owner)
        time.sleep(1.0)  # let every browser of the wave connect before the clock starts
        start = time.monotonic()
        k = 0
        while (now := time.monotonic()) - start < seconds:
            phase = (
                2 * math.pi * (k / (rate * 4.0) + index / 8.0)
            )  # a 4 s cycle, each browser out of step
            if scene in SLIDERS:
                label, lo, hi = SLIDERS[scene]
                last = round(lo + (hi - lo) * (0.5 + 0.5 * math.sin(phase)), 1)
                client.set_value(label, last)
            else:
                name, radius = GIZMOS[scene]
                x, y, z = centre
                last = (
                    round(x + radius * math.cos(phase), 4),
                    y,
                    round(z + radius * math.sin(phase), 4),
                )
                client.drag_transform_step(name, last, owner)
            sends.append(time.monotonic())
            k += 1
            if client.closed_by_server:
                result["errors"].append("the server closed the connection")
                break
            time.sleep(max(0.0, period - (time.monotonic() - now)))
        if scene in GIZMOS:
            client.send("TransformControlsDragEndMessage", name=GIZMOS[scene][0], owner=owner)
        time.sleep(3.0)  # quiet: let the last updates arrive
        result["sent"] = len(sends)
        result["latencies_ms"] = latencies_ms(client, scene, sends)
        result["last"] = last
        result["shown"] = (
            client.value_of(SLIDERS[scene][0])
            if scene in SLIDERS
            else client.pose_of(GIZMOS[scene][0])[0]
        )
        if client.closed_by_server:
            result["errors"].append("the server closed the connection")
    except Exception as error:  # reported, not raised: the parent counts it
        result["errors"].append(f"{type(error).__name__}: {error}")
    finally:
        client.close()
    return result


def latencies_ms(client: BrowserClient, scene: str, sends: list[float]) -> list[float]:
    """For each send, ms until the first scene-node message of ``scene`` that arrived after it."""
    prefix = f"/{scene}"
    with client._lock:
        arrivals = [
            t
            for t, message in client.received
            if str(message.get("name", "")).startswith(prefix)
            and not str(message.get("type", "")).startswith("Gui")
        ]
    out, j = [], 0
    for sent in sends:
        while j < len(arrivals) and arrivals[j] <= sent:
            j += 1
        if j < len(arrivals):
            out.append(1e3 * (arrivals[j] - sent))
    return out


# ------------------------------------------------------------------------------------------------ the app
def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def rss_mib(pid: int) -> float:
    with open(f"/proc/{pid}/status") as status:
        match = re.search(r"VmRSS:\s+(\d+) kB", status.read())
    return int(match.group(1)) / 1024 if match else float("nan")


def slope_mib_per_min(samples: list[tuple[float, float]], after_s: float) -> float:
    points = [(t, r) for t, r in samples if t >= after_s]
    if len(points) < 2:
        return float("nan")
    mt = statistics.fmean(t for t, _ in points)
    mr = statistics.fmean(r for _, r in points)
    var = sum((t - mt) ** 2 for t, _ in points)
    return 60.0 * sum((t - mt) * (r - mr) for t, r in points) / var if var else float("nan")


def soak(mode: str, scene: str, clients: int, rate: float, seconds: float) -> dict[str, Any]:
    port = free_port()
    args = [sys.executable, str(ROOT / "app.py"), "--port", str(port), "--scene", scene]
    if mode == "shared":
        args.append("--shared")
    log: list[str] = []
    app = subprocess.Popen(
        args, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True
    )
    assert app.stdout is not None
    for line in app.stdout:
        log.append(line)
        if "Open http" in line:
            break
    reader = threading.Thread(target=lambda: log.extend(app.stdout or ()), daemon=True)
    reader.start()
    samples: list[tuple[float, float]] = []
    try:
        outputs = [tempfile.NamedTemporaryFile("r", suffix=".json") for _ in range(clients)]
        browsers = [  # results go to files: a pipe would fill (64 KiB) and block the browser before it exits
            subprocess.Popen(
                [sys.executable, __file__, "--client", str(port), scene, str(rate), str(seconds)]
                + [str(i), out.name],
                cwd=ROOT,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
            )
            for i, out in enumerate(outputs)
        ]
        start = time.monotonic()
        while any(b.poll() is None for b in browsers):
            samples.append((time.monotonic() - start, rss_mib(app.pid)))
            time.sleep(2.0)
        results = []
        for out in outputs:
            text = out.read().strip()
            results.append(
                json.loads(text)
                if text
                else {"errors": ["no result"], "latencies_ms": [], "sent": 0}
            )
            out.close()
        slope = slope_mib_per_min(samples, min(60.0, seconds / 3.0))  # while the browsers ran
        converged = check_convergence(mode, scene, port, results)
        samples.append((time.monotonic() - start, rss_mib(app.pid)))  # after they closed
    finally:
        app.terminate()
        app.wait(timeout=30)
    reader.join(timeout=5)
    app_errors = [line.strip() for line in log if " ERROR " in line or "Traceback" in line]
    latencies = [v for r in results for v in r["latencies_ms"]]
    errors = [e for r in results for e in r["errors"]] + app_errors
    return {
        "mode": mode,
        "scene": scene,
        "sent": sum(r["sent"] for r in results),
        "p50": statistics.median(latencies) if latencies else float("nan"),
        "p95": statistics.quantiles(latencies, n=20)[18] if len(latencies) >= 20 else float("nan"),
        "errors": errors,
        "converged": converged,
        "samples": samples,
        "slope": slope,
    }


def check_convergence(mode: str, scene: str, port: int, results: list[dict[str, Any]]) -> bool:
    """Whether every viewer shows the server's value of the driven input."""
    if any("shown" not in r for r in results):
        return False
    if mode == "session":  # each tab's session took its last value
        return all(_same(r["shown"], r["last"]) for r in results)
    with BrowserClient(port) as auditor:  # a new tab is told the server's value
        if scene in SLIDERS:
            label = SLIDERS[scene][0]
            auditor.wait_for_gui(label, timeout=60)
            time.sleep(1.0)
            server_value: Any = auditor.value_of(label)
        else:
            name = GIZMOS[scene][0]
            auditor.wait_for_node(name, timeout=60)
            time.sleep(1.0)
            server_value = auditor.pose_of(name)[0]
    return all(_same(r["shown"], server_value) for r in results)


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    return (
        isinstance(a, (int, float))
        and isinstance(b, (int, float))
        and abs(float(a) - float(b)) <= 1e-6
    )


def main() -> None:
    if len(sys.argv) > 1 and sys.argv[1] == "--client":
        port, scene, rate, seconds, index, out_path = sys.argv[2:8]
        result = run_client(int(port), scene, float(rate), float(seconds), int(index))
        Path(out_path).write_text(json.dumps(result))
        return
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--clients", type=int, default=8)
    parser.add_argument("--rate", type=float, default=30.0, help="messages per second per browser")
    parser.add_argument("--seconds", type=float, default=60.0, help="per scene and mode")
    parser.add_argument("--scenes", nargs="+", default=["peloton", "arm", "freekick", "sdf"])
    parser.add_argument(
        "--modes", nargs="+", default=["session", "shared"], choices=["session", "shared"]
    )
    args = parser.parse_args()
    print(
        f"{args.clients} browsers x {args.rate:g} messages/s x {args.seconds:g} s per scene and mode "
        f"(app and each browser in its own process)\n"
    )
    header = (
        f"{'mode':8} {'scene':9} {'sent':>6} {'p50 ms':>7} {'p95 ms':>7} {'goal':>5} {'errors':>6} "
        f"{'RSS start':>9} {'RSS end':>8} {'slope MiB/min':>13} {'viewers = server':>16}"
    )
    print(header)
    print("-" * len(header))
    rows = []
    for mode in args.modes:
        for scene in args.scenes:
            row = soak(mode, scene, args.clients, args.rate, args.seconds)
            rows.append(row)
            print(
                f"{mode:8} {scene:9} {row['sent']:>6} {row['p50']:>7.1f} {row['p95']:>7.1f} "
                f"{GOAL_P95_MS[scene]:>5.0f} {len(row['errors']):>6} {row['samples'][0][1]:>9.0f} "
                f"{row['samples'][-1][1]:>8.0f} {row['slope']:>13.2f} {'yes' if row['converged'] else 'NO':>16}",
                flush=True,
            )
    print("\nRSS (MiB) every 10 s:")
    for row in rows:
        series = [f"{r:.0f}" for t, r in row["samples"] if round(t) % 10 < 2]
        print(f"  {row['mode']:8} {row['scene']:9} " + " ".join(series))
    for row in rows:
        for error in row["errors"][:5]:
            print(f"  error ({row['mode']} {row['scene']}): {error}")


if __name__ == "__main__":
    main()
