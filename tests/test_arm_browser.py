"""A real browser: Chromium opens the arm scene and a mouse drag on the target's gizmo makes the chain follow."""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import pytest
import viser
from browser import open_viser

from scenes.arm import ArmScene
from scenes.switcher import SceneSwitcher

pytestmark = pytest.mark.browser

PROJECT = """
args => {
  const m = window.__viserMutable;
  const node = m.nodeRefFromName[args.name];
  node.updateWorldMatrix(true, false);
  const point = node.localToWorld(new node.position.constructor(args.x, args.y, args.z));
  point.project(m.camera);
  const rect = m.canvas.getBoundingClientRect();
  return [rect.left + (point.x + 1) / 2 * rect.width, rect.top + (1 - point.y) / 2 * rect.height];
}
"""
"""Screen position (CSS px) of a point given in a scene node's own frame, through the page's three.js camera."""


def screen_of(page: Any, name: str, local: tuple[float, float, float]) -> tuple[float, float]:
    x, y = page.evaluate(PROJECT, {"name": name, "x": local[0], "y": local[1], "z": local[2]})
    return float(x), float(y)


def test_drag_the_target_gizmo_with_the_mouse(server: viser.ViserServer, browser_page: Any) -> None:
    switcher = SceneSwitcher(server, "arm")
    scene = switcher.scene
    assert isinstance(scene, ArmScene)
    page = browser_page
    open_viser(page, server.get_port(), "/arm/target")
    page.wait_for_function(
        "() => !!(window.__viserMutable && window.__viserMutable.camera && window.__viserMutable.canvas)",
        timeout=30_000,
    )
    target_before = scene.target.copy()
    end_before = scene.pose[-1].copy()

    # Grab the gizmo's x arrow (local +x, out along the shaft) and pull it to the left on screen.
    start = screen_of(page, "/arm/target", (0.2, 0.0, 0.0))
    origin = screen_of(page, "/arm/target", (0.0, 0.0, 0.0))
    assert start[0] > origin[0] + 5  # the arrow points right on screen from this camera
    page.mouse.move(*start)
    page.mouse.down()
    for step in range(1, 21):
        page.mouse.move(start[0] - 6 * step, start[1], steps=2)
        time.sleep(0.02)
    page.mouse.up()

    # Wait until the drag's messages have all been handled: the target has moved and then held still.
    deadline = time.monotonic() + 15.0
    last, still_since = target_before.copy(), time.monotonic()
    while time.monotonic() < deadline:
        with scene._lock:
            now = scene.target.copy()
        if not np.array_equal(now, last):
            last, still_since = now, time.monotonic()
        elif now[0] < target_before[0] - 0.05 and time.monotonic() - still_since > 0.5:
            break
        time.sleep(0.05)
    with scene._lock:
        target = scene.target.copy()
        end = scene.pose[-1].copy()
        report = scene.report
    # The target moved left (−x) along the arrow only; the plane keeps y = 0 and the drag kept z.
    assert target[0] < target_before[0] - 0.05
    assert target[1] == 0.0
    assert abs(target[2] - target_before[2]) < 1e-6
    # The chain followed: its end is on the new target, far from where it was.
    assert report is not None and report.result.status == "reached"
    assert np.linalg.norm(end - target) < 1e-3
    assert np.linalg.norm(end - end_before) > 0.05
    # The page draws the new pose: the end joint's instance in three.js sits on the new target.
    n = scene.params.n_links

    def drawn_end() -> list[float] | None:
        return page.evaluate(
            """n => {
              let mesh = null;
              window.__viserMutable.nodeRefFromName['/arm/joints'].traverse(o => {
                if (o.isInstancedMesh && mesh === null) mesh = o;
              });
              if (mesh === null || mesh.count <= n) return null;
              const matrix = new mesh.matrix.constructor();
              mesh.getMatrixAt(n, matrix);
              return [matrix.elements[12], matrix.elements[13], matrix.elements[14]];
            }""",
            n,
        )

    deadline = time.monotonic() + 10.0
    shown = drawn_end()
    while time.monotonic() < deadline and (
        shown is None or np.linalg.norm(np.array(shown) - end) > 1e-3
    ):
        time.sleep(0.1)
        shown = drawn_end()
    assert shown is not None
    np.testing.assert_allclose(shown, end, atol=1e-3)
    switcher.close()
