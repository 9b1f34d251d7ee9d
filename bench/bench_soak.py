"""Soak test: N browsers (default 8), one process each, driving every scene at 30 messages/s, shared and per tab.

    python bench/bench_soak.py [--clients 8] [--rate 30] [--seconds 60] [--scenes peloton arm freekick sdf]
                               [--modes session shared]

For each mode and scene it starts ``app.py`` in its own process (``--shared`` for the shared mode) and N fake
browsers (``tests/helpers/wsclient.py``), each in its own process. Every browser connects and receives its scene first;
then all start together (a barrier file) and each moves its scene's main input at ``rate`` messages per second for
exactly ``seconds``: the peloton's speed slider, the arm's target gizmo, the free kick's launch speed slider, the SDF
gallery's second primitive's gizmo. A browser keeps only the arrival times of the scene updates it receives (kept
whole, a minute of SDF meshes is gigabytes per browser). It prints the date, the machine and the load average, then
one Markdown row per mode and scene (ready to paste into the README, with the load average at its start and end):

- the app's RSS over the run (every 10 s; the last figure is after the browsers closed) and its slope while they
  ran, after the first minute (after the first third on runs shorter than three minutes), in MiB/min;
- p50 and p95 from a message to the next scene update the sender receives (in the shared mode another browser's
  change can bring that update: the figure is a lower bound there). A message that repeats the value before it (at
  the sweep's turning points the rounded value repeats for a few steps) changes nothing, so no update follows it:
  it is sent but not timed (timed, it measured the wait for the next different value: ~70–100 ms);
- errors: browser exceptions, connections the server closed, and ERROR or Traceback lines in the app's log;
- whether every viewer ends on the server's values: per tab, the value (or pose) it shows is the last it sent; shared,
  every viewer shows what a browser that connects after the run is told.

Goals (2 cores, 8 browsers): no errors, RSS slope ≤ 1 MiB/min after the first minute, p95 ≤ 50 ms for the peloton,
arm and free kick, ≤ 150 ms for the SDF gallery.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import platform
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from helpers.processes import AppProcess  # noqa: E402
from helpers.waiting import wait_until  # noqa: E402
from helpers.wsclient import BrowserClient  # noqa: E402

MIB = 1024 * 1024
GOAL_P95_MS = {"peloton": 50.0, "arm": 50.0, "freekick": 50.0, "sdf": 150.0}
SLIDERS = {"peloton": ("Speed (km/h)", 20.0, 60.0), "freekick": ("Launch speed (m/s)", 20.0, 32.0)}
GIZMOS = {"arm": ("/arm/target", 0.35), "sdf": ("/sdf/gizmo_2", 0.15)}
"""Gizmo name and the radius (m) of the circle each browser drags it round."""
CONNECT_TIMEOUT_S = 180.0
"""How long a browser may take to connect and receive its scene (8 sessions building at once, on 2 busy cores)."""
QUIET_S = 3.0
"""After the last message, how long each browser waits for the last updates before it reads what it shows."""


# ------------------------------------------------------------------------------------------------ one browser
def run_client(port: int, scene: str, rate: float, seconds: float, index: int, barrier: Path) -> dict[str, Any]:
    """One fake browser's run; returns what the parent reports.

    It connects, waits for its scene, writes ``barrier.ready<index>``, waits for the parent's ``barrier`` file (the
    clock's start, ``time.time()``, once every browser is ready: all send for the same ``seconds``), then sends.
    """
    result: dict[str, Any] = {"errors": [], "latencies_ms": [], "sent": 0, "late_s": 0.0}
    client = BrowserClient(port)
    arrivals: list[float] = []
    try:
        period = 1.0 / rate
        sends: list[float] = []
        last: Any = None
        owner = ""
        if scene in SLIDERS:
            label, lo, hi = SLIDERS[scene]
            client.wait_for_gui(label, timeout_s=CONNECT_TIMEOUT_S)
            client.wait_for_node(f"/{scene}", timeout_s=CONNECT_TIMEOUT_S)
        else:
            name, radius = GIZMOS[scene]
            node = client.wait_for_node(name, timeout_s=CONNECT_TIMEOUT_S)
            centre = [float(v) for v in node.get("position", (0.0, 0.0, 0.0))]
            if scene == "arm":
                centre = [0.55, 0.0, 0.6]
            owner = str(node.get("owner", "") or "")
            client.send("TransformControlsDragStartMessage", name=name, owner=owner)
        Path(f"{barrier}.ready{index}").write_text("ready")
        wait_until(barrier.exists, "the parent's start", CONNECT_TIMEOUT_S + 60.0)  # it waits for the others first
        start_wall = float(barrier.read_text() or "0")
        time.sleep(max(0.0, start_wall - time.time()))
        result["late_s"] = max(0.0, time.time() - start_wall)
        start = time.monotonic()
        next_prune = start + 1.0
        k = 0
        previous: Any = None
        while (now := time.monotonic()) - start < seconds:
            phase = 2 * math.pi * (k / (rate * 4.0) + index / 8.0)  # a 4 s cycle, each browser out of step
            if scene in SLIDERS:
                label, lo, hi = SLIDERS[scene]
                last = round(lo + (hi - lo) * (0.5 + 0.5 * math.sin(phase)), 1)
                client.set_value(label, last)
            else:
                name, radius = GIZMOS[scene]
                x, y, z = centre
                last = (round(x + radius * math.cos(phase), 4), y, round(z + radius * math.sin(phase), 4))
                client.drag_transform_step(name, last, owner)
            if last != previous:  # a repeated value changes nothing: no update follows it, so it is not timed
                sends.append(time.monotonic())
            previous = last
            k += 1
            if client.closed_by_server:
                result["errors"].append("the server closed the connection")
                break
            if now >= next_prune:
                drain_arrivals(client, scene, arrivals)
                next_prune = now + 1.0
            time.sleep(max(0.0, period - (time.monotonic() - now)))
        if scene in GIZMOS:
            client.send("TransformControlsDragEndMessage", name=GIZMOS[scene][0], owner=owner)
        time.sleep(QUIET_S)  # let the last updates arrive
        drain_arrivals(client, scene, arrivals)
        result["sent"] = k
        result["latencies_ms"] = latencies_ms(arrivals, sends)
        result["last"] = last
        result["shown"] = (
            client.value_of(SLIDERS[scene][0]) if scene in SLIDERS else client.pose_of(GIZMOS[scene][0])[0]
        )
        if client.closed_by_server:
            result["errors"].append("the server closed the connection")
    except Exception as error:  # reported, not raised: the parent counts it
        result["errors"].append(f"{type(error).__name__}: {error}")
    finally:
        client.close()
    return result


def drain_arrivals(client: BrowserClient, scene: str, arrivals: list[float]) -> None:
    """Move the arrival times of ``scene``'s scene-node messages out of ``client.received`` into ``arrivals``.

    The client keeps every message it receives, meshes and images included; over a minute of updates that is
    gigabytes per browser, so the run keeps only the times it needs (the mirrored GUI and nodes stay)."""
    prefix = f"/{scene}"
    received = client.take_received()
    arrivals.extend(
        t
        for t, message in received
        if str(message.get("name", "")).startswith(prefix) and not str(message.get("type", "")).startswith("Gui")
    )


def latencies_ms(arrivals: list[float], sends: list[float]) -> list[float]:
    """For each send, ms until the first scene-node update that arrived after it (both sorted, monotonic s)."""
    out, j = [], 0
    for sent in sends:
        while j < len(arrivals) and arrivals[j] <= sent:
            j += 1
        if j < len(arrivals):
            out.append(1e3 * (arrivals[j] - sent))
    return out


# ------------------------------------------------------------------------------------------------ the app
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
    app = AppProcess("--scene", scene, *(["--shared"] if mode == "shared" else []))
    port = app.port
    samples: list[tuple[float, float]] = []
    """(s since the browsers started sending, app RSS in MiB); negative while they connect."""
    load_start = os.getloadavg()[0]
    with tempfile.TemporaryDirectory(prefix="bench-soak-") as tmp:
        barrier = Path(tmp) / "go"
        outputs = [Path(tmp) / f"result{i}.json" for i in range(clients)]
        try:
            browsers = [  # results go to files: a pipe would fill (64 KiB) and block the browser before it exits
                subprocess.Popen(
                    [sys.executable, __file__, "--client", str(port), scene, str(rate), str(seconds)]
                    + [str(i), str(out), str(barrier)],
                    cwd=ROOT,
                    stdout=subprocess.DEVNULL,
                    stderr=subprocess.DEVNULL,
                )
                for i, out in enumerate(outputs)
            ]

            # Every browser connects and builds its scene first; then all start sending together.
            def every_browser_ready_or_gone() -> bool:
                return all(Path(f"{barrier}.ready{i}").exists() or b.poll() is not None for i, b in enumerate(browsers))

            # A browser still not ready by then starts late, and its result says so (late_s); one gone reports why.
            with contextlib.suppress(AssertionError):
                wait_until(every_browser_ready_or_gone, "every browser ready", CONNECT_TIMEOUT_S + 10.0)
            start_wall = time.time() + 1.0
            barrier.write_text(repr(start_wall))
            start = time.monotonic() + 1.0
            while any(b.poll() is None for b in browsers):
                samples.append((time.monotonic() - start, rss_mib(app.process.pid)))
                time.sleep(1.0)
            load_end = os.getloadavg()[0]
            results = []
            for out in outputs:
                text = out.read_text().strip() if out.exists() else ""
                results.append(json.loads(text) if text else {"errors": ["no result"], "latencies_ms": [], "sent": 0})
            # while the browsers sent: after the first minute (after the first third of a shorter run)
            running = [(t, r) for t, r in samples if 0.0 <= t <= seconds]
            slope = slope_mib_per_min(running, min(60.0, seconds / 3.0))
            converged = check_convergence(mode, scene, port, results)
            samples.append((time.monotonic() - start, rss_mib(app.process.pid)))  # after they closed
        finally:
            app.close()
    latencies = [v for r in results for v in r["latencies_ms"]]
    errors = [e for r in results for e in r["errors"]] + app_errors(app.lines)
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
        "late_s": max((float(r.get("late_s", 0.0)) for r in results), default=0.0),
        "load": (load_start, load_end),
    }


def app_errors(log: list[str]) -> list[str]:
    """ERROR lines and bare tracebacks in the app's log, each with the exception its traceback ended on."""
    errors: list[str] = []
    i = 0
    while i < len(log):
        line = log[i].rstrip()
        i += 1
        if " ERROR " not in line and not line.startswith("Traceback"):
            continue
        if line.startswith("Traceback"):
            i -= 1  # a bare traceback: read it below
            line = "traceback"
        exception = ""
        if i < len(log) and log[i].startswith("Traceback"):
            i += 1
            while i < len(log) and (log[i][:1].isspace() or not log[i].strip()):
                i += 1
            if i < len(log):
                exception = log[i].strip()
                i += 1
        errors.append(f"{line} -> {exception}" if exception else line)
    return errors


def check_convergence(mode: str, scene: str, port: int, results: list[dict[str, Any]]) -> bool:
    """Whether every viewer shows the server's value of the driven input."""
    if any("shown" not in r for r in results):
        return False
    if mode == "session":  # each tab's session took its last value
        return all(_same(r["shown"], r["last"]) for r in results)
    with BrowserClient(port) as auditor:  # a new tab is told the server's value
        if scene in SLIDERS:
            label = SLIDERS[scene][0]
            auditor.wait_for_gui(label, timeout_s=60)
            time.sleep(1.0)
            server_value: Any = auditor.value_of(label)
        else:
            name = GIZMOS[scene][0]
            auditor.wait_for_node(name, timeout_s=60)
            time.sleep(1.0)
            server_value = auditor.pose_of(name)[0]
    return all(_same(r["shown"], server_value) for r in results)


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    return isinstance(a, (int, float)) and isinstance(b, (int, float)) and abs(float(a) - float(b)) <= 1e-6


SCENE_TITLES = {"peloton": "peloton", "arm": "arm", "freekick": "free kick", "sdf": "SDF gallery"}
MODE_TITLES = {"session": "per tab", "shared": "shared"}


def machine() -> str:
    """The CPU model, core count and Python, for the figures' caption."""
    model = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as cpuinfo:
            found = re.search(r"model name\s*:\s*(.+)", cpuinfo.read())
        model = found.group(1).strip() if found else model
    except OSError:
        pass
    return f"{model}, {os.cpu_count()} cores, Linux {platform.release()}, Python {platform.python_version()}"


def markdown_row(row: dict[str, Any]) -> str:
    goal = GOAL_P95_MS[row["scene"]]
    met = "met" if row["p95"] <= goal and not row["errors"] else "missed"
    rss = f"{row['samples'][0][1]:.0f} → {row['samples'][-1][1]:.0f}"
    slope = "–" if math.isnan(row["slope"]) else f"{row['slope']:.1f}".replace("-", "−")
    load = f"{row['load'][0]:.1f} → {row['load'][1]:.1f}"
    return (
        f"| {MODE_TITLES[row['mode']]} | {SCENE_TITLES[row['scene']]} | {row['sent']} | {row['p50']:.1f} | "
        f"{row['p95']:.1f} | ≤ {goal:.0f}: {met} | {len(row['errors'])} | {rss} | {slope} | "
        f"{'yes' if row['converged'] else 'NO'} | {load} |"
    )


def rss_every_10_s(samples: list[tuple[float, float]]) -> list[float]:
    """RSS at 0, 10, 20 … s after the browsers started sending (the sample nearest each mark), then the last."""
    marks: list[float] = []
    t_end = max(t for t, _ in samples)
    mark = 0.0
    while mark <= t_end:
        marks.append(min(samples, key=lambda sample: abs(sample[0] - mark))[1])
        mark += 10.0
    return marks + [samples[-1][1]]


def main() -> None:
    if len(sys.argv) > 1 and sys.argv[1] == "--client":
        port, scene, rate, seconds, index, out_path, barrier = sys.argv[2:9]
        result = run_client(int(port), scene, float(rate), float(seconds), int(index), Path(barrier))
        Path(out_path).write_text(json.dumps(result))
        return
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--clients", type=int, default=8)
    parser.add_argument("--rate", type=float, default=30.0, help="messages per second per browser")
    parser.add_argument("--seconds", type=float, default=60.0, help="per scene and mode")
    parser.add_argument("--scenes", nargs="+", default=["peloton", "arm", "freekick", "sdf"], choices=list(GOAL_P95_MS))
    parser.add_argument("--modes", nargs="+", default=["session", "shared"], choices=["session", "shared"])
    args = parser.parse_args()
    started = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    print(
        f"{started}; {machine()}; load average {' '.join(f'{v:.2f}' for v in os.getloadavg())}\n"
        f"{args.clients} browsers x {args.rate:g} messages/s x {args.seconds:g} s per scene and mode "
        f"(app and each browser in its own process); latency from a message to the next scene update the sender "
        f"receives\n",
        flush=True,
    )
    header = (
        "| mode | scene | messages | p50 ms | p95 ms | goal p95 (ms) | errors | RSS start → end (MiB) "
        "| slope MiB/min | viewers = server | load average 1 min, start → end |"
    )
    print(header)
    print("|" + "---|" * (header.count("|") - 1), flush=True)
    rows = []
    for mode in args.modes:
        for scene in args.scenes:
            row = soak(mode, scene, args.clients, args.rate, args.seconds)
            rows.append(row)
            print(markdown_row(row), flush=True)
    print(
        f"\nslope: while the browsers sent, after the first {min(60.0, args.seconds / 3.0):.0f} s; "
        "RSS end: after they closed."
    )
    print("RSS (MiB) at 0, 10, 20 … s after the browsers started sending, then after they closed:")
    for row in rows:
        series = " ".join(f"{r:.0f}" for r in rss_every_10_s(row["samples"]))
        late = f" (a browser started {row['late_s']:.1f} s late)" if row["late_s"] > 0.5 else ""
        print(f"  {MODE_TITLES[row['mode']]:8} {SCENE_TITLES[row['scene']]:12} {series}{late}")
    for row in rows:
        for error in row["errors"][:5]:
            print(f"  error ({row['mode']} {row['scene']}): {error}")


if __name__ == "__main__":
    main()
