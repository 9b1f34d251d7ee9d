"""Benchmark the SDF gallery: meshing, coarse-to-fine against a full grid, the GLSL reference, and drag-to-mesh.

    python bench/bench_sdf.py [--quick]

Prints one table. Rows and goals (issue 5):

1. Mesh the four-primitive smooth default scene at 128³ samples (coarse-to-fine + marching cubes + merge):
   median and p95, goal ≤ 100 ms.
2. At 161³ ≈ 2²² samples: plain full-grid evaluation + marching cubes against coarse-to-fine + marching cubes, run
   in the same process; goal ≥ 3× faster, with identical vertices and faces.
3. The reference image (ray-march, Phong, soft shadows, AO) at 512×512 on this machine's GL (llvmpipe without a
   GPU): goal ≤ 60 ms; and 1920×1080 (goal ≥ 100 frames/s on a GPU, where one is lent).
4. A gizmo drag through the websocket test client → the new 64³ mesh arriving back at the client: p50, p95,
   goal p95 ≤ 50 ms.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

import viser  # noqa: E402
from wsclient import BrowserClient  # noqa: E402

from kernels import sdf  # noqa: E402
from scenes.sdf_gallery import SdfGalleryScene  # noqa: E402
from shaders.renderer import Camera, GLUnavailableError, Renderer, Shading  # noqa: E402


def times_ms(call: Callable[[], object], repeats: int, warmup: int = 1) -> list[float]:
    for _ in range(warmup):
        call()
    out = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        out.append(1e3 * (time.perf_counter() - start))
    return out


def p95(values: list[float]) -> float:
    return float(np.percentile(values, 95))


def cube_bounds(scene: sdf.Scene) -> np.ndarray:
    """The scene's bounds grown to a cube, so ``resolution`` samples fill every axis (resolution³ in all)."""
    box = sdf.scene_bounds(scene)
    center, half = box.mean(axis=0), 0.5 * float((box[1] - box[0]).max())
    return np.stack([center - half, center + half])


def row(name: str, value: str, goal: str, verdict: str) -> str:
    return f"| {name} | {value} | {goal} | {verdict} |"


def bench_mesh(repeats: int) -> list[str]:
    scene = sdf.default_scene()
    bounds = cube_bounds(scene)
    t = times_ms(lambda: sdf.mesh(scene, 128, bounds), repeats)
    rows = [
        row(
            "Mesh 4-primitive smooth scene, 128³ (coarse-to-fine)",
            f"median {statistics.median(t):.0f} ms, p95 {p95(t):.0f} ms",
            "≤ 100 ms",
            "met" if statistics.median(t) <= 100 else "missed",
        )
    ]
    grid = sdf.make_grid(scene, 161, bounds)
    samples = int(np.prod(grid.shape))
    full = times_ms(
        lambda: sdf.mesh(scene, 161, bounds, near_surface=False), max(2, repeats // 3), warmup=0
    )
    near = times_ms(lambda: sdf.mesh(scene, 161, bounds), repeats)
    same = all(
        np.array_equal(a, b)
        for a, b in zip(
            sdf.mesh(scene, 161, bounds),
            sdf.mesh(scene, 161, bounds, near_surface=False),
            strict=True,
        )
    )
    evaluated = sdf.sample_near_surface(scene, grid).evaluated
    ratio = statistics.median(full) / statistics.median(near)
    rows.append(
        row(
            f"161³ = {samples:,} samples (2²² = 4,194,304): full grid + MC vs coarse-to-fine + MC",
            f"{statistics.median(full):.0f} ms vs {statistics.median(near):.0f} ms: {ratio:.1f}×; "
            f"{100 * evaluated / samples:.1f} % of samples evaluated; identical output: {same}",
            "≥ 3×, identical",
            "met" if ratio >= 3 and same else "missed",
        )
    )
    return rows


def bench_reference(repeats: int) -> list[str]:
    try:
        renderer = Renderer()
    except GLUnavailableError as exc:
        return [row("Reference image", f"not measured: {exc}", "", "n/a")]
    scene = sdf.default_scene()
    camera = Camera(SdfGalleryScene.camera_position, SdfGalleryScene.camera_look_at)
    rows = []
    for label, shading in [
        ("full shading", Shading()),
        ("no shadows, no AO", Shading(shadows=False, occlusion=False)),
    ]:
        cpu_start = time.process_time()
        t = times_ms(
            lambda shading=shading: renderer.render(scene, camera, 512, 512, shading), repeats
        )
        cpu_ms = (
            1e3 * (time.process_time() - cpu_start) / (repeats + 1)
        )  # llvmpipe's threads are ours
        rows.append(
            row(
                f"Reference 512×512, {label} ({renderer.renderer_name})",
                f"median {statistics.median(t):.0f} ms, p95 {p95(t):.0f} ms (CPU {cpu_ms:.0f} ms a frame)",
                "≤ 60 ms" if label == "full shading" else "",
                ("met" if statistics.median(t) <= 60 else "missed")
                if label == "full shading"
                else "",
            )
        )
    t = times_ms(lambda: renderer.render(scene, camera, 1920, 1080), max(2, repeats // 3))
    gpu = "llvmpipe" not in renderer.renderer_name.lower()
    rows.append(
        row(
            f"Reference 1920×1080, full shading ({renderer.renderer_name})",
            f"median {statistics.median(t):.0f} ms = {1e3 / statistics.median(t):.1f} frames/s",
            "≥ 100 frames/s on a GPU",
            ("met" if 1e3 / statistics.median(t) >= 100 else "missed")
            if gpu
            else "no GPU lent: not measurable",
        )
    )
    renderer.release()
    return rows


def bench_drag(drags: int) -> list[str]:
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    scene = SdfGalleryScene(server)
    latencies = []
    server_side = []
    try:
        with BrowserClient(server.get_port()) as client:
            client.wait_for_node("/sdf/gizmo_1")
            client.wait_for_node("/sdf/mesh")
            owner = str(client.nodes["/sdf/gizmo_1"].get("owner", "") or "")
            client.send("TransformControlsDragStartMessage", name="/sdf/gizmo_1", owner=owner)
            for i in range(drags):
                z = 0.5 + 0.3 * np.sin(
                    (i + 1) / 3
                )  # never the opening 0.5: an unchanged mesh sends nothing
                count = len(client.received)
                serial = scene.mesh_serial
                start = time.monotonic()
                client.send(
                    "TransformControlsUpdateMessage",
                    name="/sdf/gizmo_1",
                    wxyz=(1.0, 0.0, 0.0, 0.0),
                    position=(0.0, 0.0, float(z)),
                    owner=owner,
                )

                def arrived(count: int = count) -> bool:
                    return any(
                        m.get("type") == "SceneNodeUpdateMessage"
                        and m.get("name") == "/sdf/mesh"
                        and "glb_data" in m.get("updates", {})
                        for _, m in client.received[count:]
                    )

                client.wait_for(arrived, timeout=10.0, what="new mesh")
                arrival = next(
                    t
                    for t, m in client.received[count:]
                    if m.get("type") == "SceneNodeUpdateMessage" and m.get("name") == "/sdf/mesh"
                )
                latencies.append(1e3 * (arrival - start))
                server_side.append(scene.agreement.mesh_ms)
                assert scene.mesh_serial > serial
                time.sleep(
                    0.15
                )  # let the reference render settle between drags, as a person pauses
            client.send("TransformControlsDragEndMessage", name="/sdf/gizmo_1", owner=owner)
    finally:
        scene.close()
        server.stop()
    return [
        row(
            f"Gizmo drag → new 64³ mesh at the client ({drags} drags)",
            f"p50 {statistics.median(latencies):.0f} ms, p95 {p95(latencies):.0f} ms "
            f"(meshing + GLB alone: p50 {statistics.median(server_side):.0f} ms)",
            "p95 ≤ 50 ms",
            "met" if p95(latencies) <= 50 else "missed",
        )
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description="Benchmark the SDF gallery.")
    parser.add_argument("--quick", action="store_true", help="fewer repeats")
    args = parser.parse_args()
    repeats = 3 if args.quick else 9
    load = os.getloadavg()[0]
    print(
        f"Machine: {os.cpu_count()} cores, load average {load:.1f} at start (other work shares these cores)."
    )
    print("| Measure | Result | Goal | Verdict |")
    print("|---|---|---|---|")
    for line in [
        *bench_mesh(repeats),
        *bench_reference(repeats),
        *bench_drag(10 if args.quick else 30),
    ]:
        print(line, flush=True)


if __name__ == "__main__":
    main()
