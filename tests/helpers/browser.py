"""Helpers for real-browser tests: open a viser page, wait for state (never for time), and look at what it shows.

"Looking" means what a person sees: screenshots as RGB arrays, points projected through the page's own three.js
camera into CSS pixels, the control panel's rectangle, a chart's plot area, and the page's visible text.
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
import re
import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from typing import Any, TypeVar

import numpy as np
from numpy.typing import NDArray

from helpers.paths import SCREENSHOTS
from helpers.waiting import wait_until

T = TypeVar("T")
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
    """Open the viser client on ``port``, wait until scene node ``node`` exists in its three.js scene, and hold its
    drawing resolution (:func:`hold_resolution`)."""
    page.goto(f"http://127.0.0.1:{port}/", wait_until="domcontentloaded", timeout=timeout_ms)
    page.wait_for_function(
        "name => !!(window.__viserMutable && window.__viserMutable.nodeRefFromName"
        " && window.__viserMutable.nodeRefFromName[name] && window.__viserMutable.camera"
        " && window.__viserMutable.canvas)",
        arg=node,
        timeout=timeout_ms,
    )
    hold_resolution(page)


HOLD_RESOLUTION = """
() => {
  window.__viserTestpoints.devSettings.set({ fixedDpr: window.devicePixelRatio });
  const c = window.__viserMutable.canvas;
  return new Promise(done => { const check = () => Math.abs(c.width - c.clientWidth * window.devicePixelRatio) <= 1
    ? done() : requestAnimationFrame(check); check(); });
}
"""


def hold_resolution(page: Any) -> None:
    """Make the page draw at its full resolution from now on, as on a fast machine.

    viser's client lowers its drawing resolution (0.75–1× the device pixels) while software WebGL draws slowly,
    and raises it again later: two screenshots compared pixel by pixel (an object shown, then hidden) could then
    differ at every edge of the picture (CI: 2075 of 4821 "peloton" pixels outside the riders' box). Framing under
    a changing resolution is checked on its own, in ``test_camera_browser.py``.
    """
    page.evaluate(HOLD_RESOLUTION)


def drawn_width(page: Any) -> int:
    """The width of viser's canvas in device pixels: what its drawing resolution is now."""
    return int(page.evaluate("() => window.__viserMutable.canvas.width"))


SOFTWARE_WEBGL = """
() => {
  const gl = document.createElement("canvas").getContext("webgl2")
    || document.createElement("canvas").getContext("webgl");
  const info = gl && gl.getExtension("WEBGL_debug_renderer_info");
  const renderer = (info ? gl.getParameter(info.UNMASKED_RENDERER_WEBGL) : "").toLowerCase();
  return ["swiftshader", "llvmpipe", "softpipe", "software"].some(name => renderer.includes(name));
}
"""
"""Whether viser's client will show its "Software WebGL rendering detected" notice (its own test, BrowserWarning)."""

TOAST = ".mantine-Notification-root"
"""A notification (toast) of viser's client."""


def close_notifications(page: Any, timeout_ms: int = 90_000) -> list[str]:
    """Close viser's toasts as a person would, and return their titles.

    Without a GPU, viser's client shows "Software WebGL rendering detected" over the top-left corner of the scene
    (296 × 171 CSS px at 14 px from the corner) soon after the page opens, until it is closed. This waits for that
    notice where the page renders in software, then clicks the close button of every toast and waits until each
    has gone (Mantine's exit animation takes seconds while software WebGL keeps the page busy).
    """
    if page.evaluate(SOFTWARE_WEBGL):
        page.locator(TOAST, has_text="Software WebGL rendering detected").wait_for(timeout=timeout_ms)
    toasts = page.locator(TOAST)
    titles = [toasts.nth(i).inner_text().split("\n")[0] for i in range(toasts.count())]
    close = page.locator(f"{TOAST} .mantine-Notification-closeButton")
    for i in reversed(range(close.count())):
        close.nth(i).click(no_wait_after=True, timeout=timeout_ms)
    page.wait_for_function(f"() => !document.querySelector({TOAST!r})", timeout=timeout_ms)
    wait_frames(page, 2)
    return titles


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
    """(N, 3): CSS x, y and NDC depth of ``points`` (in scene node ``frame``'s coordinates) through the page's
    camera."""
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


def line_mask(image: NDArray[np.uint8], rgb: Sequence[int], strength: float = 0.5) -> NDArray[np.bool_]:
    """(H, W) pixels that show a line of colour ``rgb`` drawn over white: the colour itself or, where a thin line
    falls between pixel rows, its blend with the white background holding at least ``strength`` of it (a 1.5 px
    dashed line across two rows is (231, 100, 100) for (220, 30, 30), not the colour itself)."""
    white = np.full(3, 255.0)
    towards = np.asarray(rgb, np.float64) - white
    offset = image.astype(np.float64) - white
    share = offset @ towards / max(float(towards @ towards), 1e-9)
    residual = np.linalg.norm(offset - share[..., None] * towards, axis=-1)
    return (share >= strength) & (residual <= 30.0)


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
    width = drawn_width(page)
    page.evaluate(HIDE, {"names": names, "hide": True})
    wait_frames(page, 3)
    image = screenshot(page)
    page.evaluate(HIDE, {"names": names, "hide": False})
    wait_frames(page, 3)
    assert drawn_width(page) == width, "the drawing resolution changed: open the page with open_viser"
    return image


def with_labels_hidden(page: Any) -> NDArray[np.uint8]:
    """A screenshot without the scene's text labels (viser draws them all on one 2D canvas over the 3D one)."""
    page.evaluate("() => { window.__viserMutable.canvas2d.style.visibility = 'hidden'; }")
    wait_frames(page, 2)
    image = screenshot(page)
    page.evaluate("() => { window.__viserMutable.canvas2d.style.visibility = ''; }")
    wait_frames(page, 2)
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


# --------------------------------------------------------------------------------------------- one scene, one page
@dataclasses.dataclass
class ScenePage:
    """A scene served on its own viser server and shown in one Chromium page of a given size."""

    server: Any
    switcher: Any
    page: Any
    viewport: tuple[int, int]

    @property
    def scene(self) -> Any:
        return self.switcher.scene

    @property
    def client_camera(self) -> Any:
        clients = list(self.server.get_clients().values())
        assert len(clients) == 1, clients
        return clients[0].camera

    def open(self, node: str) -> None:
        """Open the page on this server and wait for scene node ``node`` (:func:`open_viser`)."""
        open_viser(self.page, self.server.get_port(), node)


def chart_and_text_tests(chart: str, colours: dict[str, Sequence[int]]) -> tuple[Any, Any]:
    """Two tests for a module with a ``shown`` fixture (assign them to ``test_…`` names): chart ``chart`` draws every
    series in its ``colours`` (:func:`assert_chart_draws`), and the page shows no error text (:func:`error_text`)."""

    def test_the_chart_draws_every_series(shown: ScenePage) -> None:
        assert_chart_draws(shown.page, chart, colours)

    def test_no_error_text_on_the_page(shown: ScenePage) -> None:
        assert error_text(shown.page) == []

    return test_the_chart_draws_every_series, test_no_error_text_on_the_page


MENU_ROOMS = """
([labels, texts]) => {
  const rooms = {};
  let font = null;
  for (const label of labels) {
    for (const tag of document.querySelectorAll('label')) {
      if (tag.textContent.trim() !== label || tag.offsetParent === null) continue;
      let row = tag;
      while (row && !row.querySelector('input:not([type=hidden])')) row = row.parentElement;
      const input = row && row.querySelector('input:not([type=hidden])');
      if (!input || input.offsetParent === null) continue;
      const style = getComputedStyle(input);
      const room = input.clientWidth - parseFloat(style.paddingLeft) - parseFloat(style.paddingRight);
      rooms[label] = Math.min(rooms[label] ?? Infinity, room);
      font = font ?? `${style.fontWeight} ${style.fontSize} ${style.fontFamily}`;
    }
  }
  if (font === null) return null;
  const pen = document.createElement('canvas').getContext('2d');
  pen.font = font;
  return [rooms, texts.map(text => pen.measureText(text).width)];
}
"""
"""The room for text in each shown menu of ``labels`` (CSS px, by label) and the width each of ``texts`` takes in
their font; null where no menu is shown."""


def menu_test() -> Any:
    """A test for a module with a ``shown`` fixture (assign it to a ``test_…`` name): every option of every dropdown
    the scene holds fits its menu, so the option picked is read whole. A menu not shown (a closed folder, a hidden
    one) is held to the narrowest shown."""

    def test_every_menu_option_fits_its_menu(shown: ScenePage) -> None:
        from helpers.viser_private import dropdowns

        menus = dropdowns(shown.server)
        texts = sorted({option for options in menus.values() for option in options})
        measured = shown.page.evaluate(MENU_ROOMS, [list(menus), texts])
        assert measured is not None, ("no menu shown", list(menus))
        rooms, widths = measured
        width = dict(zip(texts, widths, strict=True))
        narrowest = min(rooms.values())
        assert narrowest > 100.0, rooms
        too_wide = {
            label: {option: round(width[option]) for option in options if width[option] > rooms.get(label, narrowest)}
            for label, options in menus.items()
        }
        assert not any(too_wide.values()), ({label: round(room) for label, room in rooms.items()}, too_wide)

    return test_every_menu_option_fits_its_menu


def scene_page_fixture(key: str, viewports: Sequence[tuple[int, int]] = VIEWPORTS, *, gl: bool = False) -> Any:
    """A module-scoped fixture (assign it to ``shown``): scene ``key`` served and shown in one settled page per
    viewport (:func:`scene_page`), shared by the module's tests at that viewport. ``gl``: the scene needs the
    process's GL context (made first, or the test skipped or failed)."""
    import pytest

    @pytest.fixture(scope="module", params=list(viewports), ids=lambda v: f"{v[0]}x{v[1]}")
    def shown(request: pytest.FixtureRequest, chromium_browser: Any) -> Iterator[ScenePage]:
        if gl:
            from helpers.ci import need_gl

            need_gl()
        with scene_page(chromium_browser, key, request.param) as page:
            yield page

    return shown


@contextlib.contextmanager
def served_scene(
    server: Any, page: Any, key: str, node: str | None = None, viewport: tuple[int, int] | None = None
) -> Iterator[ScenePage]:
    """Scene ``key`` shown on ``server`` by the app's switcher (closed afterwards) for ``page``, whose CSS size is
    ``viewport`` (default: the page's own); the page is opened on scene node ``node`` when given (else call
    :meth:`ScenePage.open` when ready)."""
    from server.switcher import SceneSwitcher

    switcher = SceneSwitcher(server, key)
    try:
        if viewport is None:
            viewport = (page.viewport_size["width"], page.viewport_size["height"])
        shown = ScenePage(server, switcher, page, viewport)
        if node is not None:
            shown.open(node)
        yield shown
    finally:
        switcher.close()


@contextlib.contextmanager
def served_scene_at(server: Any, page: Any, key: str, node: str, viewport: tuple[int, int]) -> Iterator[ScenePage]:
    """:func:`served_scene` on ``page`` set to ``viewport`` (CSS px) first, opened on scene node ``node``."""
    page.set_viewport_size({"width": viewport[0], "height": viewport[1]})
    with served_scene(server, page, key, node, viewport=viewport) as shown:
        yield shown


@contextlib.contextmanager
def notice_left_open(shown: ScenePage) -> Iterator[tuple[float, float] | None]:
    """Wait for viser's software-WebGL notice and leave it open; give its bottom right corner (CSS px), or None where
    the page draws on a GPU and shows none. On leaving, the notice must still be open: what was looked at was
    under it."""
    hold_resolution(shown.page)
    if not shown.page.evaluate(SOFTWARE_WEBGL):
        yield None
        return
    toast = shown.page.locator(TOAST, has_text="Software WebGL rendering detected")
    toast.wait_for(timeout=90_000)
    box = toast.bounding_box()
    assert box is not None
    yield box["x"] + box["width"], box["y"] + box["height"]
    assert shown.page.locator(TOAST).count() == 1  # still open: what was looked at was under it


@contextlib.contextmanager
def scene_page(context: Any, key: str, viewport: tuple[int, int]) -> Iterator[ScenePage]:
    """Serve scene ``key``, open it in a new page of ``viewport`` (CSS px), and wait until it has settled."""
    import app
    from server.switcher import SceneSwitcher

    server = app.make_server("127.0.0.1", 0, verbose=False)
    switcher = SceneSwitcher(server, key)
    page = context.new_page()
    page.set_default_timeout(90_000)  # software WebGL on two busy cores: a screenshot can take many seconds
    try:
        page.set_viewport_size({"width": viewport[0], "height": viewport[1]})
        open_viser(page, server.get_port(), f"/{key}")
        close_notifications(page)
        shown = ScenePage(server, switcher, page, viewport)
        settle(shown)
        yield shown
    finally:
        page.close()
        switcher.close()
        server.stop()


def settle(shown: ScenePage, timeout_s: float = 30.0) -> None:
    """Wait until the scene has framed this page's camera, the page reported the framed view back, the camera holds
    still and the picture is drawn.

    Without the report, a page under load could be looked at while the framing was still on its way, or just
    after viser's client had put it back at its opening view (the scene then frames it again).
    """
    scene = shown.scene
    framing = getattr(scene, "framing", None)
    if framing is not None:
        wait_until(lambda: framing.frames >= 1, "the scene to frame the camera", timeout_s)
    client_ids = list(shown.server.get_clients())
    looks: list[Any] = []  # the camera's pose at each look, one drawn frame apart
    steady: list[bool] = []

    def still_over_three_frames() -> bool:  # the same pose over three drawn frames, not one glance
        now = shown.page.evaluate(
            "() => [...window.__viserMutable.camera.position.toArray(),"
            " ...window.__viserMutable.camera.quaternion.toArray()]"
        )
        framing_pending = framing is not None and any(framing.pending(c) for c in client_ids)
        steady.append(bool(looks) and np.allclose(now, looks[-1], atol=1e-6) and not framing_pending)
        looks.append(now)
        wait_frames(shown.page, 1)
        return len(steady) >= 3 and all(steady[-3:])

    wait_until(still_over_three_frames, "the framed camera to hold still over three drawn frames", timeout_s)
    wait_frames(shown.page, 3)


def assert_in_view(shown: ScenePage, frame: str, points: NDArray[np.float64], what: str) -> NDArray[np.float64]:
    """Assert that ``points`` (in node ``frame``'s coordinates) project inside the page and left of the panel.

    Returns their (N, 2) CSS positions.
    """
    width, height = shown.viewport
    projected = project(shown.page, frame, points)
    xy, depth = projected[:, :2], projected[:, 2]
    left, top, _, bottom = panel_rect(shown.page)
    assert np.all(np.abs(depth) < 1.0), f"{what}: behind the camera or clipped"
    assert xy[:, 0].min() >= 0.0 and xy[:, 1].min() >= 0.0, (what, xy.min(axis=0))
    assert xy[:, 0].max() <= width and xy[:, 1].max() <= height, (what, xy.max(axis=0))
    under_panel = (xy[:, 0] >= left) & (xy[:, 1] >= top) & (xy[:, 1] <= bottom)
    assert not under_panel.any(), f"{what}: {under_panel.sum()} points under the control panel"
    return xy


def assert_in_view_clear_of_notice(
    shown: ScenePage, frame: str, points: NDArray[np.float64], what: str, notice: tuple[float, float] | None
) -> NDArray[np.float64]:
    """``points`` (k, 3) of ``frame`` in view left of the panel (:func:`assert_in_view`) and, where the page shows
    the software-WebGL notice (its bottom-right corner ``notice``, CSS px; see :func:`notice_left_open`), none under
    it; their (k, 2) screen points (CSS px)."""
    seen = assert_in_view(shown, frame, points, what)
    if notice is not None:
        under = (seen[:, 0] < notice[0]) & (seen[:, 1] < notice[1])
        assert not under.any(), f"{what}: {under.sum()} points under the notice, at {seen[under].tolist()}"
    return seen


def node_box_corners(page: Any, name: str) -> NDArray[np.float64]:
    """(8, 3) corners of scene node ``name``'s bounding box in its own frame, from the geometry the page holds."""
    corners = page.evaluate(
        """name => {
          const node = window.__viserMutable.nodeRefFromName[name];
          let lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
          node.updateWorldMatrix(true, true);
          const inverse = node.matrixWorld.clone().invert();
          node.traverse(o => {
            if (!o.geometry || !o.geometry.attributes.position) return;
            const p = o.geometry.attributes.position, v = new node.position.constructor();
            const toNode = inverse.clone().multiply(o.matrixWorld);
            for (let i = 0; i < p.count; i += 7) {
              v.fromBufferAttribute(p, i).applyMatrix4(toNode);
              lo = [Math.min(lo[0], v.x), Math.min(lo[1], v.y), Math.min(lo[2], v.z)];
              hi = [Math.max(hi[0], v.x), Math.max(hi[1], v.y), Math.max(hi[2], v.z)];
            }
          });
          const out = [];
          for (const x of [lo[0], hi[0]])
            for (const y of [lo[1], hi[1]])
              for (const z of [lo[2], hi[2]]) out.push([x, y, z]);
          return out;
        }""",
        name,
    )
    return np.asarray(corners, dtype=np.float64)


def assert_seen(
    shown: ScenePage,
    image: NDArray[np.uint8],
    nodes: Iterable[str],
    xy: NDArray[np.float64],
    what: str,
    max_outside: float = 0.25,
    *,
    without_labels: bool = False,
) -> NDArray[np.bool_]:
    """Assert that hiding ``nodes`` changes the picture inside the box around ``xy``: a person sees them there.

    At most ``max_outside`` of what they change may lie outside that box (their shadows, a gizmo's arrows).
    With ``without_labels``, ``image`` was taken with the text labels hidden (:func:`with_labels_hidden`) and so is
    the comparison: viser hides a label its 3D objects occlude, so hiding those objects shows labels elsewhere.
    Returns the mask of pixels the nodes cover.
    """
    if without_labels:
        shown.page.evaluate("() => { window.__viserMutable.canvas2d.style.visibility = 'hidden'; }")
    try:
        hidden = with_nodes_hidden(shown.page, nodes)
    finally:
        if without_labels:
            shown.page.evaluate("() => { window.__viserMutable.canvas2d.style.visibility = ''; }")
    covered = changed_mask(image, hidden)
    x0, y0 = np.floor(xy.min(axis=0)).astype(int) - 4
    x1, y1 = np.ceil(xy.max(axis=0)).astype(int) + 4
    inside = covered[max(y0, 0) : max(y1, 0), max(x0, 0) : max(x1, 0)].sum()
    area = max((x1 - x0) * (y1 - y0), 1)
    assert inside > 200 and inside > 0.005 * area, f"{what}: only {inside} px of its {area} px box show it"
    outside = covered.sum() - inside
    assert outside <= max_outside * covered.sum(), f"{what}: {outside} of {covered.sum()} px drawn outside its box"
    return covered


def assert_chart_draws(page: Any, title: str, colours: dict[str, Sequence[int]], min_px: int = 25) -> None:
    """Assert that the plot area of chart ``title`` shows every series' colour (at least ``min_px`` pixels)."""
    image = chart_image(page, title)
    counts = {name: int(np.count_nonzero(line_mask(image, rgb))) for name, rgb in colours.items()}
    missing = {name: n for name, n in counts.items() if n < min_px}
    assert not missing, f"chart {title!r}: series not drawn {missing} (all: {counts})"


def save_scene_screenshot(shown: ScenePage, key: str) -> None:
    """At 1600×1000, save the picture of scene ``key`` from this very page to :data:`helpers.paths.SCREENSHOTS`."""
    if shown.viewport != (1600, 1000):
        return
    SCREENSHOTS.mkdir(parents=True, exist_ok=True)
    screenshot(shown.page, path=str(SCREENSHOTS / f"{key}.png"))


# ------------------------------------------------------------------------------------- chart tick labels
TICK_LABEL_BOXES = """
title => {
  const entries = Object.values((window.__viserTestpoints || {}).uplots || {});
  const found = entries.find(({chart}) => {
    const t = chart.root.querySelector('.u-title');
    return t && t.textContent === title;
  });
  if (!found) return null;
  const u = found.chart, ratio = u.pxRatio || window.devicePixelRatio || 1;
  const bb = u.bbox, measure = document.createElement('canvas').getContext('2d');
  const boxes = [];
  u.axes.forEach((axis, i) => {
    if (!axis.show || !axis._values) return;
    const side = axis.side, ori = side % 2, scale = u.scales[axis.scale];
    // uPlot's drawAxesGrid: labels sit tick size + gap beyond the axis line, away from the plot.
    const dir = side === 0 || side === 3 ? -1 : 1;
    const tick = axis.ticks && axis.ticks.show !== false ? axis.ticks.size : 0;
    const base = Math.round(axis._pos * ratio) + Math.round((tick + axis.gap) * ratio) * dir;
    measure.font = axis.font[0];
    measure.textAlign = ori === 0 ? 'center' : side === 3 ? 'right' : 'left';
    measure.textBaseline = ori === 1 ? 'middle' : side === 2 ? 'top' : 'bottom';
    axis._values.forEach((text, k) => {
      if (text == null || text === '') return;
      const at = u.valToPos(axis._splits[k], axis.scale, true);
      const x = ori === 0 ? at : base, y = ori === 0 ? base : at;
      String(text).split('\\n').forEach((line, row) => {
        const m = measure.measureText(line), dy = row * axis.font[1] * (axis.lineGap || 1.5);
        boxes.push({axis: i, text: line, left: x - m.actualBoundingBoxLeft, right: x + m.actualBoundingBoxRight,
                    top: y + dy - m.actualBoundingBoxAscent, bottom: y + dy + m.actualBoundingBoxDescent,
                    rotated: !!axis._rotate});
      });
    });
    if (axis.label != null && axis._lpos != null) {  // the axis title, drawn centred along the axis
      measure.font = axis.labelFont[0];
      const m = measure.measureText(axis.label), lpos = Math.round(axis._lpos * ratio);
      const half = (m.actualBoundingBoxLeft + m.actualBoundingBoxRight) / 2;
      const height = m.actualBoundingBoxAscent + m.actualBoundingBoxDescent;
      if (ori === 1) {  // rotated a quarter turn, its baseline on the lpos line
        const mid = bb.top + bb.height / 2, inner = side === 3 ? [lpos - height, lpos] : [lpos, lpos + height];
        boxes.push({axis: i, text: axis.label, left: inner[0], right: inner[1], top: mid - half, bottom: mid + half,
                    rotated: false});
      } else {
        const mid = bb.left + bb.width / 2, inner = side === 2 ? [lpos, lpos + height] : [lpos - height, lpos];
        boxes.push({axis: i, text: axis.label, left: mid - half, right: mid + half, top: inner[0], bottom: inner[1],
                    rotated: false});
      }
    }
  });
  const stroke = u.axes.filter(a => a.show).map(a => typeof a.stroke === 'function' ? a.stroke(u, 0) : a.stroke);
  return {width: u.ctx.canvas.width, height: u.ctx.canvas.height, ratio, boxes, stroke, uuid: Object.keys(
    window.__viserTestpoints.uplots).find(k => window.__viserTestpoints.uplots[k] === found)};
}
"""
"""Where uPlot drew each tick label and axis title of the chart with a given title: canvas-px boxes, measured with
the axis's own font, placed as uPlot's drawAxesGrid places them (viser's client exposes each chart under
``window.__viserTestpoints.uplots``)."""


def tick_label_boxes(page: Any, title: str) -> dict[str, Any]:
    """Canvas size, device-pixel ratio, axis colours and every tick label's box (canvas px) of chart ``title``."""
    layout = page.evaluate(TICK_LABEL_BOXES, title)
    assert layout is not None, f"no uPlot chart titled {title!r} on the page"
    return layout


def chart_canvas_image(page: Any, title: str) -> NDArray[np.uint8]:
    """(H, W, 3) RGB, canvas px, of what uPlot drew on the canvas of the chart titled ``title``, over white.

    Read from the canvas itself (its legend and the expand button, HTML laid over the canvas's edges, stay out).
    """
    import base64

    from PIL import Image

    wait_frames(page, 2)
    url = page.evaluate(
        """title => {
          const chart = [...document.querySelectorAll('.uplot')].find(
              c => (c.querySelector('.u-title') || {}).textContent === title);
          return chart ? chart.querySelector('canvas').toDataURL('image/png') : null;
        }""",
        title,
    )
    assert url is not None, f"no uPlot chart titled {title!r} on the page"
    rgba = Image.open(io.BytesIO(base64.b64decode(url.split(",", 1)[1]))).convert("RGBA")
    white = Image.new("RGBA", rgba.size, (255, 255, 255, 255))
    return np.asarray(Image.alpha_composite(white, rgba).convert("RGB"))


def _css_rgb(colour: str) -> tuple[int, int, int]:
    match = re.fullmatch(r"\s*#([0-9a-fA-F]{6})\s*", colour)
    if match:
        value = int(match.group(1), 16)
        return (value >> 16) & 255, (value >> 8) & 255, value & 255
    match = re.fullmatch(r"\s*rgba?\(\s*(\d+)\s*,\s*(\d+)\s*,\s*(\d+)[^)]*\)\s*", colour)
    assert match, f"axis colour {colour!r} is not #rrggbb or rgb()"
    return int(match.group(1)), int(match.group(2)), int(match.group(3))


def assert_tick_labels_inside(page: Any, title: str, border_px: int = 2) -> None:
    """Assert that every tick label and axis title of chart ``title`` lies wholly inside the chart's canvas.

    Two looks: uPlot's own layout (each label's box, measured with its font, inside the canvas) and the pixels a
    person sees (no pixel of the axes' text colour in the canvas's outer ``border_px`` rows and columns, where a
    label running off the edge would be cut).
    """
    layout = tick_label_boxes(page, title)
    width, height = layout["width"], layout["height"]
    # The measured box is the glyphs' own; antialiasing reaches about a pixel beyond it.
    inside = border_px - 1
    outside = [
        f"{box['text']!r} (axis {box['axis']}: x {box['left']:.1f}..{box['right']:.1f}, "
        f"y {box['top']:.1f}..{box['bottom']:.1f})"
        for box in layout["boxes"]
        if min(box["left"], box["top"]) < inside or box["right"] > width - inside or box["bottom"] > height - inside
    ]
    assert layout["boxes"], f"chart {title!r}: no tick labels drawn"
    assert not any(box["rotated"] for box in layout["boxes"]), "rotated tick labels: not measured"
    assert not outside, f"chart {title!r} ({width}×{height} canvas px): labels cut at the edge: {outside}"
    image = chart_canvas_image(page, title)
    ring = np.ones(image.shape[:2], dtype=bool)
    ring[border_px:-border_px, border_px:-border_px] = False
    touching = {
        colour: colour_pixels(image[ring], _css_rgb(colour), tolerance=30.0) for colour in set(layout["stroke"])
    }
    assert not any(touching.values()), (
        f"chart {title!r}: axis-text pixels on the canvas's outer {border_px} px: {touching}"
    )


CHART_WINDOW = """
title => {
  const found = Object.values((window.__viserTestpoints || {}).uplots || {}).find(({chart}) => {
    const t = chart.root.querySelector('.u-title');
    return t && t.textContent === title;
  });
  if (!found) return null;
  const u = found.chart;
  return u.series.map(s => {
    const scale = u.scales[s.scale];
    return {scale: s.scale, min: scale.min, max: scale.max, log: scale.distr === 3};
  });
}
"""


def assert_chart_shows_its_data(page: Any, title: str, data: Sequence[Any]) -> None:
    """Assert that chart ``title`` opens on all of ``data`` (the server's arrays): its x window is the data's x
    extent, and every series' scale spans that series' finite values (positive ones on a log scale).

    A chart left zoomed into part of its data by a client's stale state shows tick labels and curves that look
    fine but describe a sliver (the labels' chart once showed y "-4,899.999" for data from -4,900 to 2,100).
    """
    windows = page.evaluate(CHART_WINDOW, title)
    assert windows is not None, f"no uPlot chart titled {title!r} on the page"
    x = np.asarray(data[0], dtype=np.float64)
    x = x[np.isfinite(x)]
    if x.size and x.max() > x.min():
        shown = windows[0]
        tol = 1e-9 * max(1.0, abs(float(x.min())), abs(float(x.max())))
        assert abs(shown["min"] - x.min()) <= tol and abs(shown["max"] - x.max()) <= tol, (
            f"chart {title!r}: x window {shown['min']}..{shown['max']}, data {x.min()}..{x.max()}"
        )
    for k, (window, values) in enumerate(zip(windows[1:], data[1:], strict=True), start=1):
        v = np.asarray(values, dtype=np.float64)
        v = v[np.isfinite(v) & ((v > 0.0) if window["log"] else True)]
        if not v.size:
            continue
        tol = 1e-9 * max(abs(float(v.min())), abs(float(v.max())), 1e-300)
        assert window["min"] <= v.min() + tol and window["max"] >= v.max() - tol, (
            f"chart {title!r}: series {k} (scale {window['scale']!r}) shows "
            f"{window['min']}..{window['max']}, data {v.min()}..{v.max()}"
        )


def wait_chart_data(page: Any, title: str, data: Sequence[Any], timeout_ms: int = 30_000) -> None:
    """Wait until the uPlot chart titled ``title`` holds ``data`` (the server's arrays) and has drawn it."""
    ends = [[float(np.asarray(d)[0]), float(np.asarray(d)[-1]), len(d)] for d in data]
    page.wait_for_function(
        """([title, ends]) => Object.values((window.__viserTestpoints || {}).uplots || {}).some(({chart}) => {
          const t = chart.root.querySelector('.u-title');
          if (!t || t.textContent !== title || !chart.data || chart.data.length !== ends.length) return false;
          const close = (a, b) => Math.abs(a - b) <= 1e-9 * Math.max(1, Math.abs(a), Math.abs(b));
          return chart.data.every((d, i) => d.length === ends[i][2] && close(d[0], ends[i][0])
                                            && close(d[d.length - 1], ends[i][1]));
        })""",
        arg=[title, ends],
        timeout=timeout_ms,
        polling=100,
    )
    wait_frames(page, 3)


def screen_of(page: Any, name: str, local: tuple[float, float, float]) -> tuple[float, float]:
    """CSS position of a point in scene node ``name``'s own frame."""
    x, y, _ = project(page, name, [local])[0]
    return float(x), float(y)


def drag(
    page: Any,
    start: tuple[float, float],
    step: tuple[float, float],
    moves: int,
    *,
    steps: int = 2,
    pause_s: float = 0.02,
) -> None:
    """Press the mouse at ``start`` (CSS px), move it ``moves`` times by ``step`` (each move in ``steps`` mouse
    events, ``pause_s`` apart, as a hand moves) and release it."""
    page.mouse.move(*start)
    page.mouse.down()
    for k in range(1, moves + 1):
        page.mouse.move(start[0] + step[0] * k, start[1] + step[1] * k, steps=steps)
        if pause_s:
            time.sleep(pause_s)
    page.mouse.up()


def wait_moved_and_still(read: Callable[[], T], moved: Callable[[T], bool], timeout_s: float = 15.0) -> T:
    """Poll ``read()`` until its value has ``moved`` and then held still for half a second: every message of a drag
    has been handled. Returns the value then; AssertionError after ``timeout_s``.

    Still for a while, not an event: a mouse drag sends its moves and then nothing that the server answers, so no
    message says that the last move has been handled."""
    last: list[tuple[T, float]] = [(read(), time.monotonic())]  # the value, and since when it has held

    def moved_and_still() -> bool:
        now = read()
        if not np.array_equal(np.asarray(now), np.asarray(last[0][0])):
            last[0] = (now, time.monotonic())
            return False
        return moved(now) and time.monotonic() - last[0][1] > 0.5

    wait_until(moved_and_still, "the value to move, then hold still for 0.5 s", timeout_s)
    return read()


INSTANCE = """
args => {
  let mesh = null;
  window.__viserMutable.nodeRefFromName[args.name].traverse(o => {
    if (o.isInstancedMesh && mesh === null) mesh = o;
  });
  if (mesh === null || mesh.count <= args.i) return null;
  const matrix = new mesh.matrix.constructor();
  mesh.getMatrixAt(args.i, matrix);
  return [matrix.elements[12], matrix.elements[13], matrix.elements[14]];
}
"""
"""Position of instance ``i`` of a batched mesh, as the page's three.js scene holds it."""


def assert_instance_drawn_at(
    page: Any, name: str, i: int, expected: NDArray[np.float64], atol: float = 1e-3, timeout_s: float = 10.0
) -> None:
    """Assert that the page comes to draw instance ``i`` of batched mesh node ``name`` at ``expected`` (the pose the
    server solved), within ``timeout_s``."""

    def drawn_there() -> bool:
        drawn = page.evaluate(INSTANCE, {"name": name, "i": i})
        return drawn is not None and float(np.linalg.norm(np.array(drawn) - expected)) <= atol

    with contextlib.suppress(AssertionError):  # on a timeout, the asserts below say where it is drawn instead
        wait_until(drawn_there, f"instance {i} of {name} drawn at {expected}", timeout_s)
    drawn = page.evaluate(INSTANCE, {"name": name, "i": i})
    assert drawn is not None, f"{name} has no instance {i}"
    np.testing.assert_allclose(drawn, expected, atol=atol)


@dataclasses.dataclass(frozen=True)
class NumberChange:
    """A number control typed into, the parameter field it sets, the value to type and the value to restore."""

    label: str
    field: str
    value: float
    restore: float


def assert_chart_fits_after(
    shown: ScenePage, title: str, changes: Sequence[NumberChange], chart_data: Any, check: Any
) -> None:
    """Assert chart ``title``'s tick labels stay inside its canvas, before and after the ``changes`` are typed in,
    and that the redrawn chart shows all of its new data; then type the old values back.

    ``chart_data(scene)`` reads the chart's arrays (called under the scene's lock); ``check(data)`` asserts the
    changes did stretch the axes as meant.
    """
    scene = shown.scene
    assert_tick_labels_inside(shown.page, title)
    _type_numbers(shown, [(c.label, c.field, c.value) for c in changes], "set")
    with scene._lock:
        data = chart_data(scene)
    check(data)
    wait_chart_data(shown.page, title, data)
    assert_chart_shows_its_data(shown.page, title, data)
    assert_tick_labels_inside(shown.page, title)
    _type_numbers(shown, [(c.label, c.field, c.restore) for c in changes], "back")


def chart_fits_test(
    kind: type, title: str, changes: Sequence[NumberChange], chart_data: Any, check: Callable[[Any], None]
) -> Any:
    """A test for a module with a ``shown`` fixture (assign it to a ``test_…`` name): the page shows a scene of class
    ``kind``, and chart ``title``'s tick labels stay inside its canvas before and after the ``changes``
    (:func:`assert_chart_fits_after`, with its ``chart_data`` and ``check``)."""

    def test_the_chart_tick_labels_stay_inside_its_canvas(shown: ScenePage) -> None:
        assert isinstance(shown.scene, kind)
        assert_chart_fits_after(shown, title, changes, chart_data, check)

    return test_the_chart_tick_labels_stay_inside_its_canvas


def peaks_over(limit: float) -> Callable[[Any], None]:
    """A ``check`` for :func:`assert_chart_fits_after`: some series of the chart's data (after its x values) rises
    over ``limit``."""

    def check(data: Any) -> None:
        assert max(float(np.max(series)) for series in data[1:]) > limit

    return check


def _type_numbers(shown: ScenePage, typed: Sequence[tuple[str, str, float]], what: str) -> None:
    """Type each ``(label, field, value)`` into its number control, then wait until the scene's parameters hold them
    all (``what`` names the wait: "set", "back")."""
    for label, _field, value in typed:
        set_number(shown.page, label, value)
    wait_until(
        lambda: all(getattr(shown.scene.params, field) == value for _label, field, value in typed),
        f"{[field for _label, field, _value in typed]} {what}",
    )
