"""Benchmark the SDF gallery: meshing, coarse-to-fine against a full grid, the GLSL reference, and drag-to-mesh.

    python bench/bench_sdf.py [--quick]

Prints one table. Rows and goals:

1. Mesh the four-primitive smooth default scene at 128³ samples (coarse-to-fine + marching cubes + merge):
   median and p95, goal ≤ 100 ms.
2. At 161³ ≈ 2²² samples: plain full-grid evaluation + marching cubes against coarse-to-fine + marching cubes, run
   in the same process; goal ≥ 3× faster, with identical vertices and faces.
3. The reference image (ray-march, Phong, soft shadows, AO) at 512×512 on this machine's GL (llvmpipe without a
   GPU): goal ≤ 60 ms; and 1920×1080 (goal ≥ 100 frames/s on a GPU, where one is lent).
4. A gizmo drag through the websocket test client → the new 64³ mesh arriving back at the client: p50, p95,
   goal p95 ≤ 50 ms.

The editor and the ray-marched main view:

5. An editor source's field sampled in GLSL at 128³ plus marching cubes (``mesh_glsl``): goal ≤ 150 ms on
   llvmpipe; the kernel's numpy mesher on the default scene at 128³ is the same-process baseline.
6. The ray-marched main view, 640×400 at rest and 320×200 while moving (render, depth to the viewer's format,
   JPEG and depth-PNG encoding): goal median ≤ 60 ms a frame while moving.
7. Edit → new ray-march and 64³ mesh at the websocket client (type a new source, Apply, until both the new mesh
   and a new background frame have arrived): goal ≤ 1 s.
8. Another caller's GL job (another gallery tab's frame) while a costly typed field (a nine-level chain of calls)
   is meshed at 256³: its wait, max and p95, with the field's samples drawn a slab at a time (``mesh_glsl``)
   against the same samples drawn as one GL job, in the same process; goal: the longest wait at most one slab's
   draw, a fraction of the whole.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

import viser  # noqa: E402
from helpers.wsclient import BrowserClient  # noqa: E402

from bench._timing import p95, timings  # noqa: E402
from kernels import sdf  # noqa: E402
from scenes.sdf_gallery import SdfGalleryScene  # noqa: E402
from scenes.sdf_gallery.editor import EXAMPLES  # noqa: E402
from shaders import gl_service  # noqa: E402
from shaders import renderer as gl_renderer  # noqa: E402
from shaders.renderer import Camera, GLUnavailableError, Renderer, Shading  # noqa: E402


def times_ms(call: Callable[[], object], repeats: int, warmup: int = 1) -> list[float]:
    return timings(call, repeats, warmup=warmup, scale=1e3)


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
    full = times_ms(lambda: sdf.mesh(scene, 161, bounds, near_surface=False), max(2, repeats // 3), warmup=0)
    near = times_ms(lambda: sdf.mesh(scene, 161, bounds), repeats)
    same = all(
        np.array_equal(a, b)
        for a, b in zip(sdf.mesh(scene, 161, bounds), sdf.mesh(scene, 161, bounds, near_surface=False), strict=True)
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
        return gl_service.run(lambda renderer: _bench_reference(renderer, repeats))
    except GLUnavailableError as exc:
        return [row("Reference image", f"not measured: {exc}", "", "n/a")]


def _bench_reference(renderer: Renderer, repeats: int) -> list[str]:
    scene = sdf.default_scene()
    camera = Camera(SdfGalleryScene.opening_view.position, SdfGalleryScene.opening_view.look_at)
    rows = []
    for label, shading in [("full shading", Shading()), ("no shadows, no AO", Shading(shadows=False, occlusion=False))]:
        cpu_start = time.process_time()
        t = times_ms(lambda shading=shading: renderer.render(scene, camera, 512, 512, shading), repeats)
        cpu_ms = 1e3 * (time.process_time() - cpu_start) / (repeats + 1)  # llvmpipe's threads are ours
        rows.append(
            row(
                f"Reference 512×512, {label} ({renderer.renderer_name})",
                f"median {statistics.median(t):.0f} ms, p95 {p95(t):.0f} ms (CPU {cpu_ms:.0f} ms a frame)",
                "≤ 60 ms" if label == "full shading" else "",
                ("met" if statistics.median(t) <= 60 else "missed") if label == "full shading" else "",
            )
        )
    t = times_ms(lambda: renderer.render(scene, camera, 1920, 1080), max(2, repeats // 3))
    gpu = "llvmpipe" not in renderer.renderer_name.lower()
    rows.append(
        row(
            f"Reference 1920×1080, full shading ({renderer.renderer_name})",
            f"median {statistics.median(t):.0f} ms = {1e3 / statistics.median(t):.1f} frames/s",
            "≥ 100 frames/s on a GPU",
            ("met" if 1e3 / statistics.median(t) >= 100 else "missed") if gpu else "no GPU lent: not measurable",
        )
    )
    return rows


BLEND_EXAMPLE = next(iter(EXAMPLES.values()))
EDITOR_BOUNDS = np.array([[-1.5, -1.5, -1.5], [1.5, 1.5, 1.5]])


def bench_glsl_mesh(repeats: int) -> list[str]:
    try:
        gl_service.run(lambda gl: gl.compile_field(BLEND_EXAMPLE))
    except GLUnavailableError as exc:
        return [row("GLSL-sampled mesh", f"not measured: {exc}", "", "n/a")]
    t = times_ms(lambda: gl_renderer.mesh_glsl(BLEND_EXAMPLE, 128, EDITOR_BOUNDS), repeats)
    grid = sdf.make_grid(sdf.default_scene(), 128, EDITOR_BOUNDS)
    sample = times_ms(lambda: gl_service.run(lambda gl: gl.sample_field(BLEND_EXAMPLE, grid)), repeats)
    scene = sdf.default_scene()
    bounds = cube_bounds(scene)
    numpy = times_ms(lambda: sdf.mesh(scene, 128, bounds), repeats)
    faces = len(gl_renderer.mesh_glsl(BLEND_EXAMPLE, 128, EDITOR_BOUNDS).faces)
    return [
        row(
            "Editor field sampled in GLSL at 128³ + marching cubes (example 1, mesh_glsl)",
            f"median {statistics.median(t):.0f} ms, p95 {p95(t):.0f} ms ({faces:,} faces; GL sampling alone "
            f"median {statistics.median(sample):.0f} ms); numpy mesher, default scene 128³: median "
            f"{statistics.median(numpy):.0f} ms",
            "≤ 150 ms",
            "met" if statistics.median(t) <= 150 else "missed",
        )
    ]


def costly_field(levels: int) -> str:
    """A typed field whose every sample calls a sphere 2^levels times: f_k(p) = min(f_{k−1}(p), f_{k−1}(1.01·p))."""
    lines = ["float f0(vec3 p) { return length(p) - 0.5; }"]
    lines += [f"float f{k}(vec3 p) {{ return min(f{k - 1}(p), f{k - 1}(p * 1.01)); }}" for k in range(1, levels + 1)]
    return "\n".join([*lines, f"float sdf(vec3 p) {{ return f{levels}(p); }}", ""])


def bench_gl_sharing() -> list[str]:
    """Row 8: how long a small GL job waits while a costly field is sampled whole, and a slab at a time."""
    source, resolution = costly_field(9), 256
    try:
        gl_service.run(lambda gl: gl.compile_field(source))
    except GLUnavailableError as exc:
        return [row("GL thread shared with a costly field", f"not measured: {exc}", "", "n/a")]
    grid = sdf.make_grid(sdf.default_scene(), resolution, EDITOR_BOUNDS)

    def waits_during(work: Callable[[], object]) -> tuple[list[float], float]:
        done, waits = threading.Event(), []

        def other_tab() -> None:
            while not done.is_set():
                asked = time.perf_counter()
                gl_service.run(lambda gl: None)
                waits.append(1e3 * (time.perf_counter() - asked))
                time.sleep(0.02)

        thread = threading.Thread(target=other_tab)
        start = time.perf_counter()
        thread.start()
        work()
        total = 1e3 * (time.perf_counter() - start)
        done.set()
        thread.join()
        return waits, total

    whole, whole_ms = waits_during(lambda: gl_service.run(lambda gl: gl.sample_field(source, grid)))
    slabbed, slabbed_ms = waits_during(lambda: gl_renderer.mesh_glsl(source, resolution, EDITOR_BOUNDS))
    slabs = -(-grid.shape[2] // gl_renderer.slab_planes(grid))
    return [
        row(
            f"Another caller's GL wait while a 9-level typed field is meshed at {resolution}³ ({slabs} slabs)",
            f"a slab at a time (mesh_glsl, {slabbed_ms:.0f} ms in all): max {max(slabbed):.0f} ms, p95 "
            f"{p95(slabbed):.0f} ms over {len(slabbed)} jobs; sampled as one job ({whole_ms:.0f} ms): max "
            f"{max(whole):.0f} ms ({max(whole) / max(max(slabbed), 1e-9):.1f}× the slabbed max)",
            "max ≤ one slab's draw",
            "met" if max(slabbed) <= 1.5 * whole_ms / slabs else "missed",
        )
    ]


def bench_view(repeats: int) -> list[str]:
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    camera = Camera(SdfGalleryScene.opening_view.position, SdfGalleryScene.opening_view.look_at)
    rows = []
    try:
        for label, march in [
            ("default scene", lambda gl, w, h, shading: gl.render(sdf.default_scene(), camera, w, h, shading)),
            (
                "editor example 1",
                lambda gl, w, h, shading: gl.render_field(BLEND_EXAMPLE, EDITOR_BOUNDS, camera, w, h, shading),
            ),
        ]:
            for width, height, moving in [(320, 200, True), (640, 400, False)]:
                # As the gallery draws them: no shadows or AO while moving, full shading at rest.
                shading = Shading(shadows=False, occlusion=False) if moving else Shading()

                def frame(march=march, width=width, height=height, shading=shading) -> None:
                    rgb, depth = gl_service.run(lambda gl: march(gl, width, height, shading))
                    depth = np.where(np.isfinite(depth), depth, 1e3).astype(np.float32)
                    server.scene.set_background_image(rgb, format="jpeg", jpeg_quality=90, depth=depth)

                try:
                    t = times_ms(frame, repeats * 2)
                except GLUnavailableError as exc:
                    return [row("Ray-marched view", f"not measured: {exc}", "", "n/a")]
                rows.append(
                    row(
                        f"Main view {width}×{height} "
                        f"({'moving, no shadows/AO' if moving else 'at rest, full shading'}), {label}: "
                        "ray-march + encode",
                        f"median {statistics.median(t):.0f} ms, p95 {p95(t):.0f} ms",
                        "≤ 60 ms" if moving else "",
                        ("met" if statistics.median(t) <= 60 else "missed") if moving else "",
                    )
                )
    finally:
        server.stop()
    return rows


def bench_edit(edits: int) -> list[str]:
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    scene = SdfGalleryScene(server)
    latencies: list[float] = []
    failures: list[str] = []
    try:
        with BrowserClient(server.get_port()) as client:
            client.send_camera(
                position=SdfGalleryScene.opening_view.position,
                look_at=SdfGalleryScene.opening_view.look_at,
                size=(400, 640),
            )
            client.wait_for_gui("Apply")
            client.set_value("View", "Both")
            for i in range(edits):
                # A new constant each time: a source never seen, so nothing is cached (Mesa's disk cache aside).
                radius = 0.5 + 0.01 * i + 1e-4 * (os.getpid() % 97)
                source = (
                    "float sdf(vec3 p) {\n"
                    f"    return smooth_union(sd_round_box(p, vec3(0.6, 0.4, 0.3), 0.1), "
                    f"sd_sphere(p - vec3(0.0, 0.0, 0.4), {radius:.6f}), 0.2, BLEND_POLY);\n}}\n"
                )
                client.set_value("sdf(p) in GLSL", source)
                client.wait_for(lambda s=source: client.value_of("sdf(p) in GLSL") == s, "the typed source")
                count = len(client.received)
                serial = scene.editor_serial
                start = time.monotonic()
                client.click("Apply")

                def arrivals(count: int = count) -> tuple[float | None, float | None]:
                    mesh = frame = None
                    for t, m in client.received[count:]:
                        kind = m.get("type")
                        if (
                            kind == "SceneNodeUpdateMessage"
                            and m.get("name") == "/sdf/mesh"
                            and "glb_data" in m.get("updates", {})
                        ):
                            mesh = mesh or t
                        if kind == "BackgroundImageMessage" and mesh is not None:
                            frame = frame or t
                    return mesh, frame

                try:
                    client.wait_for(lambda: None not in arrivals(), "the new mesh and frame", timeout_s=20.0)
                except AssertionError:
                    failures.append(str(scene.editor_error))
                    continue
                mesh_t, frame_t = arrivals()
                assert mesh_t is not None and frame_t is not None and scene.editor_serial > serial
                latencies.append(1e3 * (max(mesh_t, frame_t) - start))
                time.sleep(0.3)
    except GLUnavailableError as exc:
        return [row("Edit → ray-march and mesh", f"not measured: {exc}", "", "n/a")]
    finally:
        scene.close()
        server.stop()
    return [
        row(
            f"Edit → new ray-march and 64³ mesh at the websocket client ({edits} new sources)",
            f"p50 {statistics.median(latencies):.0f} ms, p95 {p95(latencies):.0f} ms, "
            f"max {max(latencies):.0f} ms" + (f"; {len(failures)} refused: {failures[0]}" if failures else ""),
            "≤ 1 s",
            "met" if max(latencies) <= 1000 and not failures else "missed",
        )
    ]


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
                z = 0.5 + 0.3 * np.sin((i + 1) / 3)  # never the opening 0.5: an unchanged mesh sends nothing
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

                client.wait_for(arrived, timeout_s=10.0, what="new mesh")
                arrival = next(
                    t
                    for t, m in client.received[count:]
                    if m.get("type") == "SceneNodeUpdateMessage" and m.get("name") == "/sdf/mesh"
                )
                latencies.append(1e3 * (arrival - start))
                server_side.append(scene.agreement.mesh_ms)
                assert scene.mesh_serial > serial
                time.sleep(0.15)  # let the reference render settle between drags, as a person pauses
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
    parser.add_argument("--only-editor-and-view", action="store_true", help="only the editor and main-view rows (5-7)")
    args = parser.parse_args()
    repeats = 3 if args.quick else 9
    load = os.getloadavg()[0]
    print(f"Machine: {os.cpu_count()} cores, load average {load:.1f} at start (other work shares these cores).")
    print("| Measure | Result | Goal | Verdict |")
    print("|---|---|---|---|")
    rows: list[Callable[[], list[str]]] = []
    if not args.only_editor_and_view:
        rows += [
            lambda: bench_mesh(repeats),
            lambda: bench_reference(repeats),
            lambda: bench_drag(10 if args.quick else 30),
        ]
    rows += [
        lambda: bench_glsl_mesh(repeats),
        lambda: bench_view(repeats),
        lambda: bench_edit(5 if args.quick else 15),
        bench_gl_sharing,
    ]
    for make in rows:
        for line in make():
            print(line, flush=True)


if __name__ == "__main__":
    main()
