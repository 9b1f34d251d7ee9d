"""A real browser looks at the arm: chain, target and obstacle in view and clear of the panel, the obstacle's gizmo
outside its disc, the error plot drawn with its top label whole, no error text, at 1600×1000 and 1280×720; the 3D
toggle shows the floor grid from an angle. (The mouse drags are in ``test_interactions_browser.py``.)"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pytest
from helpers.browser import (
    NumberChange,
    ScenePage,
    assert_chart_draws,
    assert_in_view,
    assert_seen,
    changed_mask,
    chart_fits_test,
    chart_image,
    control_row,
    error_text,
    line_mask,
    menu_test,
    project,
    save_scene_screenshot,
    scene_page_fixture,
    screenshot,
    settle,
    wait_frames,
    with_nodes_hidden,
)
from helpers.waiting import wait_until
from playwright.sync_api import Error as PlaywrightError

from scenes.arm import ArmScene

pytestmark = pytest.mark.browser

MAIN = ["/arm/links", "/arm/joints", "/arm/target", "/arm/obstacle_0"]
CHART = "Error after each iteration (log scale)"


shown = scene_page_fixture("arm")
test_every_menu_option_fits_its_menu = menu_test()


def _chain_points(scene: ArmScene) -> np.ndarray:
    with scene._lock:
        p = scene.params
        shown_obstacles = scene.obstacle_centres[: p.n_obstacles]
        radii = np.asarray(p.radii_m[: p.n_obstacles])[:, None]
        return np.vstack([scene.pose, scene.target[None, :], shown_obstacles - radii, shown_obstacles + radii])


def test_the_chain_is_in_view_clear_of_the_panel(shown: ScenePage) -> None:
    scene = shown.scene
    assert isinstance(scene, ArmScene)
    image = screenshot(shown.page)
    xy = assert_in_view(shown, "/arm", _chain_points(scene), "chain, target and obstacle")
    assert_seen(shown, image, MAIN, xy, "chain, target and obstacle")
    # The obstacle's gizmo shows outside its disc: its arrows' tips are drawn beyond the disc's rim.
    with scene._lock:
        radius = scene.params.radii_m[0]
    gizmo = changed_mask(image, with_nodes_hidden(shown.page, ["/arm/obstacle_0"]))
    disc = changed_mask(image, with_nodes_hidden(shown.page, ["/arm/obstacle_0/disc"]))
    rim = project(shown.page, "/arm/obstacle_0", [(0, 0, 0), (radius, 0, 0)])
    centre, rim_px = rim[0, :2], float(np.linalg.norm(rim[1, :2] - rim[0, :2]))
    ys, xs = np.nonzero(gizmo & ~disc)
    beyond = np.hypot(xs - centre[0], ys - centre[1]) > rim_px + 3
    assert beyond.sum() > 30, f"gizmo hidden in its obstacle ({beyond.sum()} px outside the rim)"
    save_scene_screenshot(shown, "arm")


def test_the_error_plot_draws_and_its_top_label_fits(shown: ScenePage) -> None:
    assert_chart_draws(shown.page, CHART, {"error": (230, 50, 50)})
    # Every tick label of the y axis lies inside the chart's box (the top one, "1,000", was cut off).
    cut = shown.page.evaluate(
        """title => {
          const chart = [...document.querySelectorAll('.uplot')].find(
              c => c.querySelector('.u-title').textContent === title);
          const box = chart.querySelector('canvas').getBoundingClientRect();
          return chart.querySelector('.u-over').getBoundingClientRect().top - box.top;
        }""",
        CHART,
    )
    assert cut >= 10, f"only {cut} px above the plot area for the top tick label"


def test_no_error_text_on_the_page(shown: ScenePage) -> None:
    assert error_text(shown.page) == []


def test_three_d_shows_the_floor_grid_from_an_angle(shown: ScenePage) -> None:
    scene = shown.scene
    frames = scene.framing.frames
    image = screenshot(shown.page)
    checkbox = control_row(shown.page, "3D (free target, sphere obstacles)").locator("input").first
    checkbox.click()
    wait_until(lambda: scene.params.three_d and scene.framing.frames > frames, "3D mode and its camera")
    settle(shown)
    after = screenshot(shown.page)
    # The camera left the front-on view: it looks across x as well as along y, and from above.
    direction = np.asarray(
        shown.page.evaluate(
            "() => { const v = new window.__viserMutable.camera.position.constructor();"
            " window.__viserMutable.camera.getWorldDirection(v); return v.toArray(); }"
        )
    )
    assert abs(direction[0]) > 0.25 and direction[1] < -0.25, direction  # three.js is y-up: −y is down
    # The floor grid is drawn, and much of the picture changed.
    grid = changed_mask(after, with_nodes_hidden(shown.page, ["/arm/floor"]))
    assert grid.sum() > 5_000, grid.sum()
    assert changed_mask(image, after).mean() > 0.02
    xy = assert_in_view(shown, "/arm", _chain_points(scene), "chain in 3D")
    assert_seen(shown, after, MAIN[:2], xy, "chain in 3D", max_outside=0.6)  # its shadow on the floor
    assert error_text(shown.page) == []
    checkbox.click()
    wait_until(lambda: not scene.params.three_d, "back to the plane")
    settle(shown)


def _reaches_hundredths(data: Any) -> None:
    assert float(np.min(data[1])) < 0.1


# A tighter tolerance: the log axis runs down to hundredths of a millimetre ("0.01", wider than "1").
test_the_error_plot_tick_labels_stay_inside_its_canvas = chart_fits_test(
    ArmScene,
    CHART,
    [NumberChange("Tolerance (mm)", "tolerance_mm", 0.01, 1.0)],
    lambda scene: scene.plot.data,
    _reaches_hundredths,
)


FILL = 0.5
"""The chain's projected extent must cover at least this share of the free view's width or height (the old
framing of the whole reach gave it about a third: 0.32 × 0.33 at 1600×1000)."""


def _assert_chain_fills_the_view(shown: ScenePage, what: str) -> None:
    from helpers.browser import panel_rect

    scene = shown.scene
    assert isinstance(scene, ArmScene)
    with scene._lock:
        joints, target = scene.pose.copy(), scene.target.copy()
    xy = assert_in_view(shown, "/arm", np.vstack([joints, target[None, :]]), what)
    chain = xy[: len(joints)]
    left, _, _, _ = panel_rect(shown.page)
    width, height = np.ptp(chain, axis=0)
    fill = max(width / left, height / shown.viewport[1])
    assert fill >= FILL, f"{what}: the chain spans {width:.0f}×{height:.0f} px, {fill:.2f} of the free view"


def test_the_chain_fills_the_view_in_the_plane_and_in_3d(shown: ScenePage) -> None:
    from helpers.browser import set_number

    scene = shown.scene
    assert isinstance(scene, ArmScene)
    _assert_chain_fills_the_view(shown, "the chain in the plane")
    checkbox = control_row(shown.page, "3D (free target, sphere obstacles)").locator("input").first
    frames = scene.framing.frames
    checkbox.click()
    wait_until(lambda: scene.params.three_d and scene.framing.frames > frames, "3D and its camera")
    settle(shown)
    _assert_chain_fills_the_view(shown, "the chain in 3D")
    checkbox.click()
    wait_until(lambda: not scene.params.three_d, "back to the plane")
    # A longer chain is framed again: it still fills the view, all of it in sight.
    frames = scene.framing.frames
    set_number(shown.page, "Links", 12)
    wait_until(lambda: scene.params.n_links == 12 and scene.framing.frames > frames, "12 links")
    settle(shown)
    _assert_chain_fills_the_view(shown, "12 links in the plane")
    set_number(shown.page, "Links", 6)
    wait_until(lambda: scene.params.n_links == 6, "6 links again")
    settle(shown)


def _sphere_corners(centres: np.ndarray, radius: float) -> np.ndarray:
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=np.float64)
    return (centres[:, None, :] + radius * corners[None]).reshape(-1, 3)


def test_the_3d_view_and_each_preset_show_everything_whole(shown: ScenePage) -> None:
    """In the browser, at both sizes: the 3D toggle, and each preset, show every joint whole (as a sphere), the
    ghost, the obstacle sphere and the gizmo tips inside the page and clear of the panel, and the preset's fingers,
    hands and head as drawn pixels; the same 15 s later, and the chain comes back framed."""
    import time

    from scenes import _skeletons
    from scenes.arm import GIZMO_SCALE_M, JOINT_RADIUS_M

    scene = shown.scene
    assert isinstance(scene, ArmScene)
    checkbox = control_row(shown.page, "3D (free target, sphere obstacles)").locator("input").first
    frames = scene.framing.frames
    checkbox.click()
    wait_until(lambda: scene.params.three_d and scene.framing.frames > frames, "3D and its camera")
    settle(shown)
    for wait_s in (0.0, 15.0):
        time.sleep(wait_s)
        with scene._lock:
            report, p = scene.report, scene.params
            assert report is not None
            points = np.vstack(
                [
                    _sphere_corners(scene.pose, JOINT_RADIUS_M),
                    report.ghost,
                    _sphere_corners(scene.obstacle_centres[:1], p.radii_m[0]),
                    scene.target + GIZMO_SCALE_M * np.eye(3),
                ]
            )
        assert_in_view(shown, "/arm", points, f"3D chain after {wait_s:.0f} s")
    screenshot(shown.page, path=f"/tmp/arm_3d_after_{shown.viewport[0]}.png")
    checkbox.click()
    wait_until(lambda: not scene.params.three_d, "back to the plane")
    settle(shown)
    for label in ("Robot arm", "Hand", "Upper body"):
        frames = scene.framing.frames
        scene.controls["preset"].value = label  # as the menu sends it (the pixels are what this test is about)
        assert scene.skeletons.preset == label and scene.framing.frames > frames  # the callback ran and framed it
        settle(shown)
        image = screenshot(shown.page, path=f"/tmp/arm_{label.replace(' ', '_')}_after_{shown.viewport[0]}.png")
        view = scene.skeletons
        with scene._lock:
            points = np.vstack(
                [
                    _sphere_corners(view.pose, _skeletons.JOINT_RADIUS_M),
                    (view.targets[:, None, :] + view.gizmo_scale * np.eye(3)[None]).reshape(-1, 3),
                ]
            )
        xy = assert_in_view(shown, "/arm", points, label)
        assert_seen(shown, image, ["/arm/skeleton/links", "/arm/skeleton/joints"], xy, label)
    scene.controls["preset"].value = "Chain"
    wait_until(lambda: not scene.skeletons.active, "the chain back")
    settle(shown)
    _assert_chain_fills_the_view(shown, "the chain again")


def test_a_solve_with_no_admissible_pose_charts_without_an_error_and_the_next_draws_its_curve(shown: ScenePage) -> None:
    # An empty series made viser's client throw "object null is not iterable" and leave the chart without its red
    # curve; a solve that saw no admissible pose ("infeasible") sent one. Its chart is now its one final error.
    from scenes.arm import OBSTACLE_STARTS, TARGET_START, ArmParams, rest_pose, solve_arm

    scene = shown.scene
    assert isinstance(scene, ArmScene)
    errors: list[str] = []
    shown.page.on("pageerror", lambda error: errors.append(str(error)))
    params = ArmParams(
        n_links=6, link_length_m=0.5, three_d=True, limits=True, n_obstacles=3, solver="Jacobian DLS",
        tolerance_mm=50.0, max_iterations=3,
    )  # fmt: skip
    bent = np.array([[0.0, 0.0, 0.0], [-0.2089, 0.0, 0.4543], [-0.3073, 0.0, 0.9445], [-0.0450, 0.0, 1.3702],
                     [0.4515, 0.0, 1.3111], [0.9041, 0.0, 1.0987], [0.8502, 0.0, 0.6016]])  # fmt: skip
    report = solve_arm(params, bent, TARGET_START, OBSTACLE_STARTS)
    assert report.result.status == "infeasible"
    red: dict[str, Sequence[int]] = {"error": (230, 50, 50)}

    def red_px() -> int | None:
        """The chart's red pixels, or None while viser's client is replacing the chart's element."""
        try:
            return int(np.count_nonzero(line_mask(chart_image(shown.page, CHART), red["error"])))
        except PlaywrightError:
            return None

    with scene._lock:
        before = scene.params
        scene.params = params
        scene._draw(report)
    try:
        wait_until(lambda: (red_px() or 25) < 25, "the chart showing the one final error", timeout_s=30.0)
        wait_frames(shown.page, 10)
        assert not errors, errors
    finally:
        with scene._lock:  # a solve from the rest pose, which takes several iterations, as the scene opens
            scene.params = before
            scene.pose = rest_pose(before.n_links, before.link_length_m)
            scene.solve_and_draw()
    wait_until(lambda: (red_px() or 0) >= 25, "a solve's curve drawn again", timeout_s=30.0)
    assert not errors, errors
    assert_chart_draws(shown.page, CHART, red)
