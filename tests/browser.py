"""Helpers for real-browser tests: open a viser page, wait for state (never for time), and look at what it shows.

"Looking" means what a person sees: screenshots as RGB arrays, points projected through the page's own three.js
camera into CSS pixels, the control panel's rectangle, a chart's plot area, and the page's visible text.
"""

from __future__ import annotations

import io
import re
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

VIEWPORTS: tuple[tuple[int, int], ...] = ((1600, 1000), (1280, 720))
"""The windows every scene is looked at in (CSS px)."""
ERROR_TEXT = re.compile(r"\bNaN\b|\bnan\b|Traceback|Exception|undefined|\binf\b|Infinity|\[object")
"""Text that must never reach a person: numbers gone wrong and errors that leaked."""

PROJECT = """
args => {
  const m = window.__viserMutable;
  const node = m.nodeRefFromName[args.name];
  node.updateWorldMatrix(true, false);
  const rect = m.canvas.getBoundingClientRect();
  return args.points.map(([x, y, z]) => {
    const point = node.localToWorld(new node.position.constructor(x, y, z));
    point.project(m.camera);
    return [rect.left + (point.x + 1) / 2 * rect.width, rect.top + (1 - point.y) / 2 * rect.height, point.z];
  });
}
"""
"""CSS-pixel position (and NDC depth) of points given in a scene node's own frame, through the page's camera."""


def open_viser(page: Any, port: int, node: str, timeout_ms: int = 60_000) -> None:
    """Open the viser client on ``port`` and wait until scene node ``node`` exists in its three.js scene."""
    page.goto(f"http://127.0.0.1:{port}/", wait_until="domcontentloaded", timeout=timeout_ms)
    page.wait_for_function(
        "name => !!(window.__viserMutable && window.__viserMutable.nodeRefFromName"
        " && window.__viserMutable.nodeRefFromName[name] && window.__viserMutable.camera"
        " && window.__viserMutable.canvas)",
        arg=node,
        timeout=timeout_ms,
    )


def close_notifications(page: Any) -> None:
    """Hide the toasts, as a person would close them: the software-WebGL notice covers the top left corner.

    (Clicking each close button waits on Mantine's exit animation, seconds per toast under software rendering.)
    """
    page.add_style_tag(content=".mantine-Notifications-root { display: none !important; }")
    wait_frames(page, 2)


def wait_frames(page: Any, frames: int = 3) -> None:
    """Wait until the page has drawn ``frames`` more animation frames (so a change on the page is on the canvas)."""
    page.evaluate(
        """n => new Promise(done => { const step = k => k <= 0 ? done() : requestAnimationFrame(() => step(k - 1));
        step(n); })""",
        frames,
    )


def screenshot(page: Any, path: str | None = None) -> NDArray[np.uint8]:
    """(H, W, 3) RGB of the whole page as a person sees it; also saved to ``path`` when given."""
    from PIL import Image

    png = page.screenshot(path=path)
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))


def project(page: Any, frame: str, points: Iterable[Sequence[float]]) -> NDArray[np.float64]:
    """(N, 3): CSS x, y and NDC depth of ``points`` (in scene node ``frame``'s coordinates) through the page's camera."""
    pts = [[float(c) for c in p] for p in points]
    return np.asarray(page.evaluate(PROJECT, {"name": frame, "points": pts}), dtype=np.float64)


def panel_rect(page: Any) -> tuple[float, float, float, float]:
    """(left, top, right, bottom) CSS px of viser's control panel."""
    box = page.evaluate(
        """() => {
          const button = [...document.querySelectorAll('button')].find(
              b => b.textContent.trim() === 'Reset scene to defaults');
          let e = button;
          while (e && !(e.className && e.className.toString().includes('mantine-Paper-root'))) e = e.parentElement;
          const r = (e || button).getBoundingClientRect();
          return [r.left, r.top, r.right, r.bottom];
        }"""
    )
    return (float(box[0]), float(box[1]), float(box[2]), float(box[3]))


def visible_text(page: Any) -> str:
    """All text a person can read on the page (inner text of the body)."""
    return str(page.evaluate("() => document.body.innerText"))


def error_text(page: Any) -> list[str]:
    """Lines of visible text that look like a number gone wrong or a leaked error."""
    return [line for line in visible_text(page).splitlines() if ERROR_TEXT.search(line)]


def set_number(page: Any, label: str, value: float) -> None:
    """Type ``value`` into the number box of the control labelled ``label`` and press Enter, as a person would."""
    box = control_row(page, label).locator("input:not([type=checkbox]):not([type=hidden])").last
    box.scroll_into_view_if_needed()
    box.click()
    box.fill(f"{value:g}")
    box.press("Enter")


def control_row(page: Any, label: str) -> Any:
    """The row of the control labelled exactly ``label``."""
    text = page.get_by_text(label, exact=True).first
    return text.locator("xpath=ancestor::*[.//input][1]")


def chart_image(page: Any, title: str) -> NDArray[np.uint8]:
    """(H, W, 3) RGB of the plot area (inside the axes) of the uPlot chart titled ``title``, scrolled into view."""
    from PIL import Image

    chart = page.locator(".uplot", has=page.locator(".u-title", has_text=title)).first
    chart.scroll_into_view_if_needed()
    wait_frames(page, 2)
    plot = chart.locator(".u-over").first
    png = plot.screenshot()
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))


def colour_pixels(image: NDArray[np.uint8], rgb: Sequence[int], tolerance: float = 40.0) -> int:
    """How many pixels of ``image`` lie within ``tolerance`` (Euclidean, 0–255 per channel) of ``rgb``."""
    distance = np.linalg.norm(image.astype(np.float64) - np.asarray(rgb, np.float64), axis=-1)
    return int(np.count_nonzero(distance <= tolerance))


def changed_mask(a: NDArray[np.uint8], b: NDArray[np.uint8], threshold: int = 24) -> NDArray[np.bool_]:
    """(H, W) pixels whose colour differs by more than ``threshold`` in some channel."""
    return np.abs(a.astype(np.int16) - b.astype(np.int16)).max(axis=-1) > threshold


HIDE = """
args => {
  const m = window.__viserMutable;
  args.names.forEach(name => m.nodeRefFromName[name].traverse(o => {
    if (args.hide) { if (o.userData.__layers === undefined) o.userData.__layers = o.layers.mask; o.layers.set(31); }
    else if (o.userData.__layers !== undefined) { o.layers.mask = o.userData.__layers; delete o.userData.__layers; }
  }));
  m.requestRender();
}
"""
"""Take scene nodes out of (or back into) the camera's layer: viser re-applies ``visible`` itself, not layers."""


def with_nodes_hidden(page: Any, names: Iterable[str]) -> NDArray[np.uint8]:
    """A screenshot with the three.js nodes ``names`` hidden (client side only), then shows them again.

    Against a screenshot with them shown, the difference is exactly where a person sees those objects.
    """
    names = list(names)
    page.evaluate(HIDE, {"names": names, "hide": True})
    wait_frames(page, 3)
    image = screenshot(page)
    page.evaluate(HIDE, {"names": names, "hide": False})
    wait_frames(page, 3)
    return image


def bbox(mask: NDArray[np.bool_]) -> tuple[int, int, int, int] | None:
    """(left, top, right, bottom) px of the True pixels of ``mask``, or None when there are none."""
    ys, xs = np.nonzero(mask)
    if len(xs) == 0:
        return None
    return int(xs.min()), int(ys.min()), int(xs.max()) + 1, int(ys.max()) + 1


def canvas_is_not_blank(png: bytes) -> bool:
    """True when a PNG of the canvas has real content: many distinct colours, not one flat fill."""
    from PIL import Image

    image = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))
    colours = np.unique(image.reshape(-1, 3)[::7], axis=0)
    return colours.shape[0] > 50 and float(image.std()) > 5.0
