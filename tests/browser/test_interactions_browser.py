"""A person's actions in Chromium, each on a server and page of its own: a mouse drag on the arm's target gizmo makes
the chain follow on screen, one on a fingertip target of the hand preset curls the finger, one on the peloton's speed
slider changes the power; a click on "Kick" flies the ball in the page; a GPX uploaded through viser's upload button
plays; the SDF gallery shows its mesh and the GLSL reference image the server made, and a shape typed in its editor is
meshed and ray-marched.

They live apart from the scenes' other browser tests, which share one page per window size for a whole module:
pytest runs a module's tests without that page last, while the page is still open and drawing, and two pages drawing
with software WebGL on two cores slowed each of these several times over.
"""

from __future__ import annotations

import contextlib
import io
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import viser
from helpers.browser import (
    TOAST,
    VIEWPORTS,
    assert_instance_drawn_at,
    canvas_is_not_blank,
    changed_mask,
    close_notifications,
    control_row,
    drag,
    panel_rect,
    screen_of,
    screenshot,
    served_scene,
    served_scene_at,
    settle,
    wait_frames,
    wait_moved_and_still,
)
from helpers.ci import need_gl
from helpers.gpx import hill_gpx
from helpers.waiting import wait_until
from PIL import Image
from scipy import ndimage

from scenes._skeletons import hand
from scenes.arm import ArmScene
from scenes.freekick import FreeKickScene
from scenes.freekick.model import ball_spot
from scenes.peloton import PelotonScene
from scenes.peloton.course import CourseMode
from scenes.sdf_gallery import SdfGalleryScene
from server.budget import MAX_UPLOAD_BYTES, MIB
from server.gate import ECHO_AFTER_TYPING_S

pytestmark = pytest.mark.browser

BALL = "/freekick/ball"
NODE = f"window.__viserMutable.nodeRefFromName[{BALL!r}]"
MESH = "/sdf/mesh"


# ------------------------------------------------------------------------------------------------ the arm
def test_drag_the_target_gizmo_with_the_mouse(server: viser.ViserServer, browser_page: Any) -> None:
    with served_scene(server, browser_page, "arm", "/arm/target") as shown:
        scene, page = shown.scene, shown.page
        assert isinstance(scene, ArmScene)
        close_notifications(page)
        # The drag aims at the gizmo on the screen: the camera must be framed and still first, or it moves under
        # the mouse (CI: the drag missed the gizmo while the framing was still arriving).
        settle(shown)
        target_before = scene.target.copy()
        end_before = scene.pose[-1].copy()
        image_before = screenshot(page)

        # Grab the gizmo's x arrow (local +x, out along the shaft) and pull it to the left on screen.
        start = screen_of(page, "/arm/target", (0.2, 0.0, 0.0))
        origin = screen_of(page, "/arm/target", (0.0, 0.0, 0.0))
        assert start[0] > origin[0] + 5  # the arrow points right on screen from this camera
        # About 0.15 m to the left: clear of the obstacle, so the chain reaches it.
        drag(page, start, (-6.0, 0.0), 10)

        def current_target() -> np.ndarray:
            with scene._lock:
                return scene.target.copy()

        wait_moved_and_still(current_target, lambda now: now[0] < target_before[0] - 0.05)
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
        assert_instance_drawn_at(page, "/arm/joints", scene.params.n_links, end)
        # A person sees the chain's end move: the picture changed around the new end's place on the screen.
        wait_frames(page, 3)
        x, y = screen_of(page, "/arm", tuple(end))
        was_x, _ = screen_of(page, "/arm", tuple(end_before))
        assert was_x - x > 15  # dragged left on the screen
        changed = changed_mask(image_before, screenshot(page))
        assert changed[int(y) - 15 : int(y) + 15, int(x) - 15 : int(x) + 15].sum() > 40


def test_drag_a_fingertip_target_with_the_mouse(server: viser.ViserServer, browser_page: Any) -> None:
    name = "/arm/skeleton/target_1"  # the index finger's
    with served_scene(server, browser_page, "arm") as shown:
        scene, page = shown.scene, shown.page
        assert isinstance(scene, ArmScene)
        view = scene.skeletons
        with scene._lock:
            view.show("Hand")
        shown.open(name)
        # The drag aims at the gizmo on the screen: the camera must be framed and still first, or it moves under
        # the mouse (CI: the drag missed the gizmo and the fingertip never moved).
        settle(shown)
        effector = hand().effectors[1]
        with scene._lock:
            target_before = view.targets[1].copy()
            tip_before = view.pose[effector].copy()
        picture_before = page.screenshot()

        # Grab the gizmo's z arrow (local +z, along the shaft; the arrows are scaled to the gaps between the
        # fingertips) and pull it down on screen.
        with scene._lock:
            arrow = view.gizmo_scale
        start = screen_of(page, name, (0.0, 0.0, 0.6 * arrow))
        origin = screen_of(page, name, (0.0, 0.0, 0.0))
        assert start[1] < origin[1] - 5  # the arrow points up on screen from this camera
        drag(page, start, (0.0, 3.0), 15)

        def current_target() -> np.ndarray:
            with scene._lock:
                return view.targets[1].copy()

        wait_moved_and_still(current_target, lambda now: now[2] < target_before[2] - 0.02)
        with scene._lock:
            target = view.targets[1].copy()
            tip = view.pose[effector].copy()
            report = view.report
        # The target moved down (−z) along the arrow only.
        assert target[2] < target_before[2] - 0.02
        np.testing.assert_allclose(target[:2], target_before[:2], atol=1e-6)
        # The finger followed: its tip moved, and it is nearer the new target than it was.
        assert report is not None
        assert np.linalg.norm(tip - tip_before) > 0.01
        assert np.linalg.norm(tip - target) < 0.5 * np.linalg.norm(tip_before - target)
        # The page draws the new pose: the fingertip's instance in three.js sits where the server solved it.
        assert_instance_drawn_at(page, "/arm/skeleton/joints", effector, tip)
        assert page.screenshot() != picture_before  # the picture changed


# ------------------------------------------------------------------------------------------------ the peloton
def test_drag_speed_slider_with_the_mouse(server: viser.ViserServer, browser_page: Any) -> None:
    with served_scene(server, browser_page, "peloton", "/peloton/course/riders_body") as shown:
        scene, page = shown.scene, shown.page
        assert isinstance(scene, PelotonScene)

        # The canvas shows the scene, not a blank page.
        clients = list(server.get_clients().values())
        assert len(clients) == 1
        render = clients[0].get_render(height=360, width=640, transport_format="png")
        buffer = io.BytesIO()
        Image.fromarray(render).save(buffer, format="PNG")
        assert canvas_is_not_blank(buffer.getvalue())

        before_speed = scene.params.speed_kmh
        before_power = float(scene.state.power.total[0])
        label = page.get_by_text("Speed (km/h)", exact=True).first
        row = label.locator("xpath=ancestor::*[.//*[@role='slider']][1]")
        thumb = row.locator("[role='slider']").first
        box = thumb.bounding_box()
        assert box is not None
        drag(page, (box["x"] + box["width"] / 2, box["y"] + box["height"] / 2), (4.0, 0.0), 10, steps=1, pause_s=0.0)

        def speed() -> float:
            with scene._lock:
                return scene.params.speed_kmh

        wait_moved_and_still(speed, lambda now: now != before_speed)
        with scene._lock:
            final_speed = scene.params.speed_kmh
            final_power = float(scene.state.power.total[0])
        assert final_speed > before_speed
        assert final_power > before_power
        # The page shows the server's new value in the slider's number box.
        page.wait_for_function(
            "v => [...document.querySelectorAll('[role=slider]')]"
            ".some(e => Number(e.getAttribute('aria-valuenow')) === v)",
            arg=final_speed,
            timeout=10_000,
            polling=100,
        )


def render(server: viser.ViserServer) -> np.ndarray:
    clients = list(server.get_clients().values())
    assert len(clients) == 1
    return np.asarray(clients[0].get_render(height=360, width=640, transport_format="png"))


def png(image: np.ndarray) -> bytes:
    buffer = io.BytesIO()
    Image.fromarray(image).save(buffer, format="PNG")
    return buffer.getvalue()


def test_upload_a_gpx_and_play_it(server: viser.ViserServer, browser_page: Any, tmp_path: Path) -> None:
    with served_scene(server, browser_page, "peloton", "/peloton/course_mode/route") as served:
        scene, page = served.scene, served.page
        assert isinstance(scene, PelotonScene)
        mode = scene.course_mode
        page.get_by_text("Ride a course", exact=True).first.click()
        wait_until(lambda: mode.enabled and mode.state is not None, "course mode on", timeout_s=15.0)

        path = tmp_path / "browser_hill.gpx"
        path.write_bytes(hill_gpx("Browser hill", 1500))
        with page.expect_file_chooser() as chooser:
            page.get_by_text("Upload GPX", exact=True).first.click()
        chooser.value.set_files(str(path))
        wait_until(lambda: mode.route.name == "Browser hill", "the uploaded course", timeout_s=20.0)
        page.get_by_text("Browser hill", exact=False).first.wait_for(timeout=15_000)

        time.sleep(1.0)  # let the new geometry reach the canvas
        before = render(server)
        assert canvas_is_not_blank(png(before))
        with scene._lock:
            start = mode.leader_distance_m()
        # Fast forward, set on the server (its on_update and cleaning run).
        mode.controls["playback"].value = 300.0
        page.get_by_role("button", name="Play").first.click()
        wait_until(lambda: mode.leader_distance_m() > start + 500.0, "the riders to ride", timeout_s=20.0)
        page.get_by_role("button", name="Pause").first.click()
        wait_until(lambda: not mode.playing, "pause", timeout_s=10.0)
        time.sleep(0.5)
        after = render(server)
        # The riders moved on screen: part of the picture changed.
        changed = np.any(np.abs(after.astype(int) - before.astype(int)) > 30, axis=2)
        assert changed.mean() > 0.0005, f"only {changed.mean():.5f} of the pixels changed"

        # The profile chart shows the elevation line (brown) and the power line (red) in its canvas.
        chart = page.locator(".uplot", has_text="Elevation, speed and power").first
        chart.scroll_into_view_if_needed(timeout=10_000)
        shot = np.asarray(Image.open(io.BytesIO(chart.screenshot())).convert("RGB")).astype(int)

        def has_colour(rgb: tuple[int, int, int]) -> bool:
            return bool(np.any(np.all(np.abs(shot - np.array(rgb)) < 40, axis=2)))

        assert has_colour((120, 90, 60)) and has_colour((220, 40, 40))
        # The page tells the person where the leader is.
        page.get_by_text("Leader at", exact=False).first.wait_for(timeout=10_000)


@contextlib.contextmanager
def course_mode_page(
    server: viser.ViserServer, browser_page: Any, viewport: tuple[int, int]
) -> Iterator[tuple[Any, CourseMode]]:
    """The peloton in a Chromium page of size ``viewport``, notifications closed, "Ride a course" ticked by a click."""
    with served_scene_at(server, browser_page, "peloton", "/peloton/course_mode/route", viewport) as served:
        scene, page = served.scene, served.page
        assert isinstance(scene, PelotonScene)
        mode = scene.course_mode
        close_notifications(page)
        page.get_by_text("Ride a course", exact=True).first.click()
        wait_until(lambda: mode.enabled and mode.state is not None, "course mode on", timeout_s=15.0)
        yield page, mode


@pytest.mark.parametrize("viewport", VIEWPORTS, ids=lambda v: f"{v[0]}x{v[1]}")
def test_a_file_over_the_upload_limit_is_refused_and_the_button_works_again(
    server: viser.ViserServer, browser_page: Any, tmp_path: Path, viewport: tuple[int, int]
) -> None:
    """A 25 MiB file: the server refused its start, but viser's page kept the "Upload GPX" button disabled and its
    "Uploading … (25.0M)" spinner up until a reload, waiting for acks that never came. Now the page shows only the
    refusal, and the button uploads the next file."""
    with course_mode_page(server, browser_page, viewport) as (page, mode):
        button = page.get_by_role("button", name="Upload GPX")

        big = tmp_path / "too_big.gpx"
        big.write_bytes(b" " * (MAX_UPLOAD_BYTES + MIB))
        with page.expect_file_chooser() as chooser:
            button.click()
        chooser.value.set_files(str(big))
        refusal = page.locator(TOAST, has_text="Upload refused")
        refusal.wait_for(timeout=15_000)
        assert "The file is 25.0 MiB; this server takes files up to 24 MiB." in refusal.inner_text()
        page.wait_for_function(
            "() => ![...document.querySelectorAll('button')]"
            ".some(b => b.textContent.includes('Upload GPX') && b.disabled)",
            timeout=10_000,
        )
        wait_frames(page, 5)
        toasts = [page.locator(TOAST).nth(i).inner_text() for i in range(page.locator(TOAST).count())]
        assert all("Uploading" not in text and "successfully" not in text for text in toasts), toasts
        screenshot(page, str(tmp_path / "refused.png"))

        small = tmp_path / "after.gpx"
        small.write_bytes(hill_gpx("After the refusal", 800))
        with page.expect_file_chooser() as chooser:
            button.click()
        chooser.value.set_files(str(small))
        wait_until(lambda: mode.route.name == "After the refusal", "the next upload", timeout_s=20.0)


@pytest.mark.parametrize("viewport", VIEWPORTS, ids=lambda v: f"{v[0]}x{v[1]}")
def test_a_file_the_course_refuses_shows_one_message_not_uploaded_successfully_beside_it(
    server: viser.ViserServer, browser_page: Any, tmp_path: Path, viewport: tuple[int, int]
) -> None:
    """A KML file named .gpx arrived whole, so viser's page said "File uploaded successfully" next to the course's red
    "GPX not loaded": two toasts that contradict each other. Now the refusal is the one message about the file."""
    with course_mode_page(server, browser_page, viewport) as (page, _mode):
        kml = tmp_path / "route.gpx"
        kml.write_bytes(b'<?xml version="1.0"?><kml xmlns="http://www.opengis.net/kml/2.2"><Document/></kml>')
        with page.expect_file_chooser() as chooser:
            page.get_by_role("button", name="Upload GPX").click()
        chooser.value.set_files(str(kml))
        refusal = page.locator(TOAST, has_text="GPX not loaded")
        refusal.wait_for(timeout=15_000)
        assert "route.gpx was not loaded" in refusal.inner_text()
        wait_frames(page, 10)
        toasts = [page.locator(TOAST).nth(i).inner_text() for i in range(page.locator(TOAST).count())]
        assert len(toasts) == 1 and "successfully" not in toasts[0] and "Uploading" not in toasts[0], toasts
        screenshot(page, str(tmp_path / "one_message.png"))


# ------------------------------------------------------------------------------------------------ typing in a box
# Kind: the server's value sent back over a box a person is still typing in. viser's page sends a box's value at
# every keystroke; the server sent each (clamped) value back, so "75" typed into Mass (30–150 kg) became 30 at the
# "7" and then 150, "300" W became 2000, and "1234" typed fast lost digits.
def _type(page: Any, label: str, text: str, delay_ms: float) -> Any:
    box = control_row(page, label).locator("input").last
    box.click()
    box.press("Control+a")
    box.type(text, delay=delay_ms)
    return box


@pytest.mark.parametrize("viewport", VIEWPORTS, ids=lambda v: f"{v[0]}x{v[1]}")
def test_a_number_typed_into_a_box_keystroke_by_keystroke_is_kept(
    server: viser.ViserServer, browser_page: Any, viewport: tuple[int, int]
) -> None:
    typed = [  # label, text, field, value, keystroke gap (ms)
        ("Mass, rider + bike (kg)", "75", "mass_kg", 75.0, 250),  # "7" is below the range
        ("Mass, rider + bike (kg)", "123", "mass_kg", 123.0, 150),  # "1", "12" are below it
        ("Drivetrain efficiency (%)", "95", "drivetrain_pct", 95.0, 250),
        ("Speed (km/h)", "35.5", "speed_kmh", 35.5, 200),  # a slider's box
        ("Power (W)", "1234", "target_power_w", 1234.0, 0),  # a number box, typed as fast as the page takes keys
    ]
    with served_scene_at(server, browser_page, "peloton", "/peloton", viewport) as served:
        scene, page = served.scene, served.page
        assert isinstance(scene, PelotonScene)
        close_notifications(page)
        for label, text, field, value, delay_ms in typed:
            box = _type(page, label, text, delay_ms)
            wait_until(lambda f=field, v=value: getattr(scene.params, f) == v, f"{label} = {text}", timeout_s=10.0)
            time.sleep(ECHO_AFTER_TYPING_S + 0.5)  # anything the server would send back has arrived
            assert box.input_value() == text, (label, box.input_value())
            assert getattr(scene.params, field) == value

        # Out of range, the box is put right once the person stops typing: below the range after a pause, above it
        # at once (no digit typed after it can bring it back).
        for text, shown in (("7", "30"), ("1500", "150")):
            box = _type(page, "Mass, rider + bike (kg)", text, 100)
            wait_until(lambda b=box, s=shown: b.input_value() == s, f"{text} shown as {shown}", timeout_s=10.0)
            assert scene.params.mass_kg == float(shown)


# ------------------------------------------------------------------------------------------------ the free kick
def test_pressing_kick_flies_the_ball_in_the_page(server: viser.ViserServer, browser_page: Any) -> None:
    with served_scene(server, browser_page, "freekick", BALL) as shown:
        scene, page = shown.scene, shown.page
        assert isinstance(scene, FreeKickScene)
        close_notifications(page)
        spot_x = float(ball_spot(scene.params)[0])
        page.wait_for_function(f"() => Math.abs({NODE}.position.x - ({spot_x})) < 1e-3", timeout=20_000)

        # Record what the page draws, every animation frame, from before the click on.
        page.evaluate(
            f"""() => {{
                window.__kick = {{ maxX: -1e9, minW: 1.0 }};
                const sample = () => {{
                    const node = {NODE};
                    window.__kick.maxX = Math.max(window.__kick.maxX, node.position.x);
                    window.__kick.minW = Math.min(window.__kick.minW, Math.abs(node.quaternion.w));
                    requestAnimationFrame(sample);
                }};
                sample();
            }}"""
        )
        page.get_by_role("button", name="Kick", exact=True).click()

        # The three.js ball left its spot and travelled toward the goal (x = 0), several metres on...
        page.wait_for_function(f"() => window.__kick.maxX > {spot_x + 5.0}", timeout=20_000)
        assert spot_x + 5.0 < float(page.evaluate("() => window.__kick.maxX")) <= 2.0 + 1e-6
        # ...spinning: its orientation left the identity during the flight.
        page.wait_for_function("() => window.__kick.minW < 0.999", timeout=20_000)


# ------------------------------------------------------------------------------------------------ the SDF gallery
READ_IMAGE = """
([w, h]) => {
    const img = [...document.querySelectorAll('img')].find(
        i => i.complete && i.naturalWidth === w && i.naturalHeight === h);
    if (!img) return null;
    const canvas = document.createElement('canvas');
    canvas.width = w; canvas.height = h;
    const ctx = canvas.getContext('2d');
    ctx.drawImage(img, 0, 0);
    return Array.from(ctx.getImageData(0, 0, w, h).data);
}
"""


@pytest.mark.gl
def test_browser_shows_the_mesh_and_the_reference_image(server: viser.ViserServer, browser_page: Any) -> None:
    need_gl()
    with served_scene(server, browser_page, "sdf", MESH) as served:
        scene, page = served.scene, served.page
        assert isinstance(scene, SdfGalleryScene)

        # The 3D view shows the mesh: the sphere's red and the box's blue are on the canvas (once the page has
        # drawn the full mesh: a render taken as the page opens can catch it on its way; CI saw 198 blue px).
        # viser registers the page at its first camera message, which can come after the page has drawn the scene.
        wait_until(lambda: len(server.get_clients()) == 1, "the page registered", 30.0)
        clients = list(server.get_clients().values())
        assert len(clients) == 1
        counts: list[tuple[int, int]] = []  # (red, blue) pixels of each render

        def red_and_blue_drawn() -> bool:
            rgb = np.asarray(clients[0].get_render(height=360, width=480))[..., :3].astype(int)
            reddish = (rgb[..., 0] > rgb[..., 2] + 60) & (rgb[..., 0] > 120)
            bluish = (rgb[..., 2] > rgb[..., 0] + 60) & (rgb[..., 2] > 120)
            counts.append((int(reddish.sum()), int(bluish.sum())))
            return min(counts[-1]) > 200

        with contextlib.suppress(AssertionError):  # on a timeout, the assert below gives the last counts
            wait_until(red_and_blue_drawn, "the sphere's red and the box's blue on the canvas", 60.0)
        assert counts and min(counts[-1]) > 200, counts[-1:]

        # The reference panel shows the ray-marched image, pixel for pixel as the server rendered it.
        wait_until(lambda: scene.reference_rgb is not None, "the reference image", 60.0)
        # The browser may move its camera once more (a re-render); wait until the page and the server agree.
        images: list[np.ndarray] = []  # the reference panel's image, as the page shows it, at each look

        def page_shows_the_reference() -> bool:
            expected = scene.reference_rgb
            if expected is None:
                return False
            height, width = expected.shape[:2]
            handle = page.wait_for_function(f"({READ_IMAGE})([{width}, {height}])", timeout=30_000, polling=200)
            images.append(np.asarray(handle.json_value(), dtype=np.uint8).reshape(height, width, 4)[..., :3])
            return np.array_equal(images[-1], expected)

        with contextlib.suppress(AssertionError):  # on a timeout, the assert below says how the two differ
            wait_until(page_shows_the_reference, "the page to show the server's reference image", 60.0)
        assert images and scene.reference_rgb is not None
        shown = images[-1]
        np.testing.assert_array_equal(shown, scene.reference_rgb)
        height, width = shown.shape[:2]
        object_pixels = (np.abs(shown.astype(int) - shown[0, 0].astype(int)).sum(axis=2) > 30).sum()
        assert object_pixels > 0.02 * width * height  # the object, not just background


OCTAHEDRON = (
    "float sdf(vec3 p) {\n    return sd_octahedron(p - vec3(0.0, 0.0, 0.4), 0.7);\n}\n"
    "vec3 color(vec3 p) {\n    return vec3(0.1, 0.85, 0.2);\n}\n"
)


def green_mask(png: bytes) -> np.ndarray:
    import io

    from PIL import Image

    rgb = np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)
    # Green over red and blue by a ratio, so the shaded underside (dark green) counts too.
    green = rgb[..., 1]
    return (green > 20) & (green - np.maximum(rgb[..., 0], rgb[..., 2]) > 0.3 * green)


def wait_for_green(page: Any, pixels: int = 5000, timeout_s: float = 30.0) -> np.ndarray:
    """Screenshots until the green shape shows (the picture a person sees), its mask; AssertionError after
    ``timeout_s``."""
    masks: list[np.ndarray] = []

    def green_shown() -> bool:
        masks.append(green_mask(page.screenshot()))
        return masks[-1].sum() >= pixels

    wait_until(green_shown, f"{pixels} green pixels on the screen", timeout_s)
    return masks[-1]


@pytest.mark.gl
def test_typed_shape_is_meshed_and_ray_marched_in_the_main_view(server: viser.ViserServer, browser_page: Any) -> None:
    from kernels import sdf

    need_gl()
    browser_page.set_viewport_size({"width": 1600, "height": 1000})
    with served_scene(server, browser_page, "sdf", MESH) as served:
        scene, page = served.scene, served.page
        assert isinstance(scene, SdfGalleryScene)
        # Shape → GLSL editor, as a person picks it: the editor's folder appears, open.
        control_row(page, "Shape").locator("input").first.click()
        page.get_by_role("option", name="GLSL editor").click()
        editor = page.locator("textarea").filter(has_text="sdf(vec3 p)").first
        # The folder shows open, its code box a screenful tall (at least 15 of its lines), not viser's 2–6 lines.
        lines = editor.evaluate("e => e.getBoundingClientRect().height / parseFloat(getComputedStyle(e).lineHeight)")
        assert editor.is_visible() and lines >= 15, lines
        # The panel's full width under its label, every line wrapped inside it (none cut off at the box's edge).
        box = editor.bounding_box()
        panel = page.locator(".mantine-Textarea-root").first.evaluate(
            "e => e.closest('.mantine-Paper-root, [class*=Folder]').getBoundingClientRect().width"
        )
        assert box is not None and box["width"] >= 0.85 * panel, (box, panel)
        assert editor.evaluate("e => e.scrollWidth <= e.clientWidth + 1")
        editor.fill(OCTAHEDRON)
        page.get_by_role("button", name="Apply").click()
        wait_until(lambda: scene.editor_serial != 0, "the typed shape applied", 60.0)
        assert scene.editor_serial == 1 and scene.params.editor.source == OCTAHEDRON.strip("\n") + "\n"
        # Meshed: every vertex on the octahedron the person typed.
        d = sdf.sd_octahedron(scene.mesh_vertices - [0.0, 0.0, 0.4], 0.7)
        assert len(d) > 500 and np.abs(d).max() < 0.02
        assert not any(g.visible for g in scene.gizmos)
        mesh_green = wait_for_green(page)
        assert mesh_green.sum() > 5000  # the green octahedron fills a good part of the view

        # Ray-marched: the same green shape, now from the shader, with the mesh hidden.
        page.locator("input[value='Mesh']").first.click()
        page.get_by_role("option", name="Ray-marched").click()
        page.wait_for_function("() => !window.__viserMutable.nodeRefFromName['/sdf/mesh'].visible", timeout=30_000)
        # The frame at rest: the canvas's width (at least 640 px; a moving frame is 320).
        wait_until(
            lambda: scene.view_rgb is not None and scene.view_rgb.shape[1] >= 640, "a ray-marched frame at rest", 60.0
        )
        assert scene.view_rgb is not None and scene.view_rgb.shape[1] >= 640
        marched_green = wait_for_green(page)
        assert marched_green.sum() > 5000
        overlap = (mesh_green & marched_green).sum() / (mesh_green | marched_green).sum()
        assert overlap > 0.8, f"mesh and ray-march silhouettes overlap {overlap:.2f}"
        marched_rgb = screenshot(page)

        # Both: the mesh's edges as dark lines over the ray-marched shape, and nowhere off it.
        page.locator("input[value='Ray-marched']").first.click()
        page.get_by_role("option", name="Both", exact=True).click()
        wait_until(
            lambda: scene.view_edges > 0 and scene.view_rgb is not None and scene.view_rgb.shape[1] >= 640,
            "a frame at rest with the mesh's edges",
            60.0,
        )
        assert scene.view_edges > 0 and scene.view_rgb is not None and scene.view_rgb.shape[1] >= 640
        wait_frames(page, 3)
        both_rgb = screenshot(page)
        # Line pixels: changed from the ray-marched picture of the same camera, and darker.
        lines = changed_mask(marched_rgb, both_rgb) & (both_rgb.sum(axis=2) < marched_rgb.sum(axis=2))
        shape = np.asarray(ndimage.binary_dilation(marched_green, iterations=4), dtype=bool)
        inside = np.asarray(ndimage.binary_erosion(marched_green, iterations=4), dtype=bool)
        assert 0.03 < lines[inside].mean() < 0.6, lines[inside].mean()  # a wireframe, not a blot or nothing
        # Off the shape (the sky around it, left of the panel) no line is drawn.
        free = np.zeros_like(shape)
        free[:, : int(panel_rect(page)[0]) - 10] = True
        assert lines[free & ~shape].mean() < 0.002
