"""A real browser looks at the free kick: ball, wall, goal and path in view and clear of the panel, the force chart
drawn, no error text, at 1600×1000 and 1280×720; in the opening view the path stands apart from its no-spin ghost and
10 % more spin moves it on the screen; every camera view keeps the kick in view with the goal a real size, and the
goalkeeper's view looks over his shoulder with no net over the ball. (The click on "Kick" is in
``test_interactions_browser.py``.)"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from helpers.browser import (
    TOAST,
    NumberChange,
    ScenePage,
    assert_in_view,
    assert_in_view_clear_of_notice,
    assert_seen,
    changed_mask,
    chart_and_text_tests,
    chart_fits_test,
    colour_pixels,
    error_text,
    menu_test,
    notice_left_open,
    panel_rect,
    peaks_over,
    project,
    save_scene_screenshot,
    scene_page_fixture,
    screenshot,
    served_scene_at,
    set_number,
    settle,
    visible_text,
    with_nodes_hidden,
)
from helpers.screen_geometry import GOAL_CORNERS, polyline_gap
from helpers.waiting import wait_until

from scenes._framing import NOTICE_PX, Lens, project_points
from scenes.freekick import FreeKickParams, FreeKickScene
from scenes.freekick.model import PRESETS, VIEW_LABELS, ViewName, ball_spot, resample
from scenes.freekick.odds import heat_cells
from scenes.freekick.props import FORCE_COLOURS, KNUCKLE_COLOUR, PATH_COLOUR
from scenes.freekick.views import frame_view, view_points

pytestmark = pytest.mark.browser

BALL = "/freekick/ball"
NODE = f"window.__viserMutable.nodeRefFromName[{BALL!r}]"
MAIN = ["/freekick/wall", "/freekick/goal_frame", "/freekick/path", "/freekick/ball"]
CHART = "Force magnitudes along the flight"
CHART_COLOURS = {**FORCE_COLOURS, "knuckle": KNUCKLE_COLOUR}
OPENING_GOAL_SHARE = 0.21
"""Least share of the free canvas width (left of the panel) the goal's box spans in the opening view at the
defaults (the old opening view: 0.18–0.19; framed clear of the software-WebGL notice: 0.22 at 1280×720)."""
GOAL_SHARE_AGREES = 0.03
"""In every other view the goal's width on the page must match the width the pure projection of the scene's
framing gives (tests/scenes/test_freekick_scene.py bounds it over presets and ball spots) to this relative tolerance. A
fixed floor here tested one state only: side-on it is 0.12–0.15 at the defaults, depending on the spin the
earlier tests left, and 0.06 for a ball 40 m out."""
OPENING_GAP_PX = 25.0
"""Least on-screen distance of the path from its no-spin ghost over the flight's second half, opening view (the old
one drew them 1–10 px apart)."""
SPIN_SHIFT_SHARE = 0.005
"""10 % more spin moves the crossing of the goal line by at least this share of the window width on the screen in
the opening view (the old view: 8.2 px at 1600 and 5.8 px at 1280 wide; framed clear of the software-WebGL notice
the view at 1280×720 is smaller: 6.6 px)."""


shown = scene_page_fixture("freekick")


def _look_at_the_kick(shown: ScenePage) -> None:
    scene = shown.scene
    assert isinstance(scene, FreeKickScene)
    image = screenshot(shown.page)
    with scene._lock:
        points = view_points(scene.params, scene.state, scene.params.view)
    xy = assert_in_view(shown, "/freekick", points, f"the kick ({scene.params.view})")
    assert_seen(shown, image, MAIN, xy, "ball, wall, goal and path")


def _goal_share(shown: ScenePage) -> float:
    xy = project(shown.page, "/freekick", GOAL_CORNERS)[:, :2]
    return float(np.ptp(xy[:, 0])) / panel_rect(shown.page)[0]


def test_the_kick_fills_the_view_clear_of_the_panel(shown: ScenePage) -> None:
    _look_at_the_kick(shown)
    scene = shown.scene
    assert scene.params.view == "broadcast"
    # It fills the screen: the goal-to-ball extent spans most of the free width, not a postage stamp...
    with scene._lock:
        points = view_points(scene.params, scene.state, scene.params.view)
        path, ghost = resample(scene.state.flight, 40), resample(scene.state.ghost, 40)
    xy = project(shown.page, "/freekick", points)[:, :2]
    width = panel_rect(shown.page)[0]
    assert np.ptp(xy[:, 0]) > 0.55 * width, np.ptp(xy[:, 0])  # 0.60 at 1280×720, framed below the WebGL notice
    # ...with the goal a real size...
    assert _goal_share(shown) >= OPENING_GOAL_SHARE, _goal_share(shown)
    # ...and the curl across the screen: the path stands apart from the no-spin ghost over the second half.
    path_xy = project(shown.page, "/freekick", path)[20:, :2]
    ghost_xy = project(shown.page, "/freekick", ghost)[:, :2]
    gap = polyline_gap(path_xy, ghost_xy)
    assert np.mean(gap >= OPENING_GAP_PX) >= 0.9, np.round(gap)
    save_scene_screenshot(shown, "freekick")


test_the_chart_draws_every_series, test_no_error_text_on_the_page = chart_and_text_tests(CHART, CHART_COLOURS)
test_every_menu_option_fits_its_menu = menu_test()


def test_ten_percent_more_spin_moves_the_path_on_the_screen(shown: ScenePage) -> None:
    scene = shown.scene
    with scene._lock:
        before = resample(scene.state.flight, 40)
        spin = scene.params.spin_rev_s
    was = project(shown.page, "/freekick", before)[:, :2]
    set_number(shown.page, "Spin rate (rev/s)", round(1.1 * spin, 1))
    wait_until(lambda: scene.params.spin_rev_s == round(1.1 * spin, 1), "the new spin to reach the scene")
    settle(shown)
    with scene._lock:
        after = resample(scene.state.flight, 40)
    now = project(shown.page, "/freekick", after)[:, :2]
    # Where the ball crosses the goal line moved by several pixels on the screen...
    assert scene.params.view == "broadcast"
    shift = float(np.linalg.norm(now[-1] - was[-1]))
    assert shift > SPIN_SHIFT_SHARE * shown.viewport[0], (was[-1], now[-1])
    # ...and the orange path is drawn there, not where it was.
    image = screenshot(shown.page)
    samples = now[20:-2:2]
    drawn = [
        colour_pixels(image[int(y) - 4 : int(y) + 5, int(x) - 4 : int(x) + 5], PATH_COLOUR, 70) > 0 for x, y in samples
    ]
    assert np.mean(drawn) > 0.7, f"the path shows at only {sum(drawn)} of {len(drawn)} places"  # arrows cross it
    assert error_text(shown.page) == []


def test_every_camera_view_keeps_the_kick_in_view(shown: ScenePage) -> None:
    scene = shown.scene
    views: list[ViewName] = list(VIEW_LABELS)
    order: list[ViewName] = [*views[1:], views[0]]  # the opening view last: choosing it again changes nothing
    for view in order:
        frames = scene.framing.frames
        scene.controls["view"].value = VIEW_LABELS[view]  # type: ignore[index]
        wait_until(
            lambda view=view, frames=frames: scene.params.view == view and scene.framing.frames > frames,
            f"the {view} view",
        )
        settle(shown)
        image = screenshot(shown.page)
        with scene._lock:
            points = view_points(scene.params, scene.state, scene.params.view)
            spot = ball_spot(scene.params)
        xy = assert_in_view(shown, "/freekick", points, f"the kick ({view})")
        assert_seen(shown, image, MAIN, xy, f"ball, wall, goal and path ({view})")
        if view != "goal":
            assert_in_view(shown, "/freekick", GOAL_CORNERS, f"the goal ({view})")
            camera = shown.client_camera
            lens = Lens(float(camera.fov), int(camera.image_width), int(camera.image_height))
            with scene._lock:
                framed = frame_view(scene.params, scene.state, view, lens)
            # The camera reports its canvas in device pixels, which viser's client scales down (to 0.75–1 of the
            # CSS size here) while it draws slowly: the pure projection is in those, the page's in CSS px.
            css_per_px = shown.viewport[0] / lens.width_px
            expected = css_per_px * float(np.ptp(project_points(framed, lens, GOAL_CORNERS)[:, 0]))
            seen = float(np.ptp(project(shown.page, "/freekick", GOAL_CORNERS)[:, 0]))
            assert seen == pytest.approx(expected, rel=GOAL_SHARE_AGREES), view
            continue
        # The goalkeeper's view: the camera stands behind the keeper, above his raised hands (over his shoulder)...
        eye = np.asarray(shown.client_camera.position)
        with scene._lock:
            keeper_xy = scene.state.keeper_xy
        assert keeper_xy is not None
        assert np.hypot(*(eye[:2] - spot[:2])) > np.hypot(*(np.asarray(keeper_xy) - spot[:2])) and eye[2] > 2.3, eye
        # ...the ball is seen, and no net or post is drawn over it. From 20-odd metres the ball is a few pixels
        # across and its own path and force arrows start on it, so both pictures leave those out: the ball's pixels
        # are what hiding it changes, and none of them may change when the goal is hidden too.
        ball_xy = project(shown.page, "/freekick", [spot.tolist()])[0, :2]
        x, y = np.round(ball_xy).astype(int)
        overlays = ["/freekick/path", "/freekick/ghost", "/freekick/band"] + [
            f"/freekick/force_{name}" for name in FORCE_COLOURS
        ]
        plain = with_nodes_hidden(shown.page, overlays)
        ball = changed_mask(plain, with_nodes_hidden(shown.page, [*overlays, BALL]))
        near = np.zeros_like(ball)
        near[max(y - 12, 0) : y + 13, max(x - 12, 0) : x + 13] = True
        ball &= near
        assert ball.sum() >= 5, f"the ball is hidden at {x, y}"
        goal = ["/freekick/net", "/freekick/goal_frame"]
        over_ball = changed_mask(plain, with_nodes_hidden(shown.page, [*overlays, *goal])) & ball
        assert not over_ball.any(), f"the goal is drawn over the ball at {x, y}"
        # ...and the keeper is drawn, left of the panel and clear of the software-WebGL notice (the old view stood
        # inside him or showed none of him).
        keeper = changed_mask(plain, with_nodes_hidden(shown.page, [*overlays, *KEEPER]))
        assert keeper.sum() >= 40, keeper.sum()
        rows, cols = np.nonzero(keeper)
        assert cols.max() < panel_rect(shown.page)[0], cols.max()
        assert not ((cols < NOTICE_PX[0]) & (rows < NOTICE_PX[1])).any(), "the keeper under the notice"


HARDEST_KICK = [
    NumberChange("Launch speed (m/s)", "speed_ms", 40.0, 25.0),
    NumberChange("Spin rate (rev/s)", "spin_rev_s", 15.0, 8.0),
]
"""The hardest, most spun kick: the force axis grows from a few newtons to over ten."""


test_the_force_chart_tick_labels_stay_inside_its_canvas = chart_fits_test(
    FreeKickScene, CHART, HARDEST_KICK, lambda scene: scene.chart.data, peaks_over(10.0)
)


KEEPER = ["/freekick/keeper", "/freekick/keeper_head"]
SHOWN_PRESETS = (
    "Low curler: bounces, saved",
    "Driven, off the post",
    "Top corner past the keeper",
    "Curler round the wall, saved",  # the defaults last: the page is left as it opened
)
"""Presets whose picture is looked at: a bounce and a save, a post, a goal past the keeper, the opening save."""


def _keeper_points(scene: FreeKickScene) -> np.ndarray:
    """(N, 3) both ends of every drawn limb of the keeper (m)."""
    starts = np.asarray(scene.keeper_nodes.batched_positions, dtype=np.float64)
    scales = np.asarray(scene.keeper_nodes.batched_scales, dtype=np.float64)
    w, x, y, z = np.asarray(scene.keeper_nodes.batched_wxyzs, dtype=np.float64).T
    axis = np.column_stack([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)])
    return np.vstack([starts, starts + scales[:, 2:3] * axis, np.asarray(scene.keeper_head.position)[None]])


def test_each_preset_shows_the_keeper_in_view_and_says_what_happened(shown: ScenePage) -> None:
    scene = shown.scene
    assert isinstance(scene, FreeKickScene)
    words = {
        "Low curler: bounces, saved": "Bounces, into the keeper's hands",
        "Driven, off the post": "Hits the right post at 1.2 m",
        "Top corner past the keeper": "the ball beats him by",
        "Curler round the wall, saved": "Saved: the keeper reached it",
    }
    for label in SHOWN_PRESETS:
        preset = next(preset for preset in PRESETS if preset.label == label)
        shown.page.get_by_role("button", name=label, exact=True).click()
        wait_until(lambda preset=preset: scene.params == preset.params.shown_as(scene.params), f"the {label} preset")
        settle(shown)
        assert words[label] in visible_text(shown.page), label
        image = screenshot(shown.page)
        with scene._lock:
            points = _keeper_points(scene)
        xy = assert_in_view(shown, "/freekick", points, f"the keeper ({label})")
        assert_seen(shown, image, KEEPER, xy, f"the keeper ({label})", max_outside=0.4)  # his shadow falls aside
    assert error_text(shown.page) == []


def test_the_goal_chance_map_is_drawn_on_the_grass_from_above(shown: ScenePage) -> None:
    scene = shown.scene
    assert isinstance(scene, FreeKickScene)
    assert not scene.heat_nodes.visible
    shown.page.get_by_role("button", name="Map the goal chance from every spot").click()
    wait_until(lambda: scene.heat_nodes.visible and scene.params.view == "above", "the map", 300.0)
    settle(shown)
    image = screenshot(shown.page)
    centres, _, _ = heat_cells()
    xy = assert_in_view(shown, "/freekick", centres, "the goal-chance map")
    covered = assert_seen(shown, image, ["/freekick/odds_map"], xy, "the goal-chance map", max_outside=0.1)
    # The map is a large picture, not a strip: it covers a tenth of the free canvas or more.
    assert covered.sum() > 0.1 * panel_rect(shown.page)[0] * shown.viewport[1]
    text = visible_text(shown.page)
    assert "Best spot:" in text and "Goal 0 → 100 %" in text
    assert error_text(shown.page) == []


GROWN_KICKS = {
    "40m-40ms-50deg": [
        ("Distance to goal (m)", "distance_m", 40.0),
        ("Launch speed (m/s)", "speed_ms", 40.0),
        ("Elevation (°)", "elevation_deg", 50.0),
    ],
    "35m-30deg-32ms-45deg": [
        ("Distance to goal (m)", "distance_m", 35.0),
        ("Spot angle (°, + = left)", "angle_deg", 30.0),
        ("Launch speed (m/s)", "speed_ms", 32.0),
        ("Elevation (°)", "elevation_deg", 45.0),
    ],
}
"""Numbers typed in a person's order (the spot first) after which a review saw the flight run off the top of the
picture, and side-on and from the goal the dashed no-spin path too: moving the ball reframed the view, the strike
did not."""


@pytest.mark.parametrize("kick", list(GROWN_KICKS))
def test_a_grown_kick_and_its_no_spin_path_stay_in_every_view(shown: ScenePage, kick: str) -> None:
    scene = shown.scene
    assert isinstance(scene, FreeKickScene)
    try:
        for view in VIEW_LABELS:
            scene.apply(FreeKickParams(view=view))  # the opening kick, seen from this view
            settle(shown)
            for label, name, value in GROWN_KICKS[kick]:
                set_number(shown.page, label, value)
                wait_until(lambda name=name, value=value: getattr(scene.params, name) == value, f"{label} = {value}")
            settle(shown)
            with scene._lock:
                flight, ghost = resample(scene.state.flight), resample(scene.state.ghost)
            width = shown.viewport[0]
            screenshot(shown.page, path=f"/tmp/freekick_grown_{kick}_{view}_{width}.png")
            assert_in_view(shown, "/freekick", flight, f"the flight ({kick}, {view}, {width} px)")
            assert_in_view(shown, "/freekick", ghost, f"the no-spin path ({kick}, {view}, {width} px)")
    finally:
        scene.apply(FreeKickParams())  # the page as it opened, for the tests after
        settle(shown)


@pytest.mark.parametrize("viewport", [(1600, 1000), (1280, 720)], ids=lambda v: f"{v[0]}x{v[1]}")
def test_the_goal_frame_and_keeper_show_clear_of_the_notice_and_the_panel(
    server: Any, browser_page: Any, viewport: tuple[int, int]
) -> None:
    # A review at 1280×720 saw only the goal's top left corner, under viser's software-WebGL notice, and no keeper
    # while the readout said "Saved"; with the ball 30 m out at 40° the goal and keeper left the frame. Here the
    # notice stays open, as it does until a person closes it, and the pixels the goal's white frame and the keeper
    # make (the difference when they are hidden) are counted where a person can see them, left of the panel.
    with (
        served_scene_at(server, browser_page, "freekick", "/freekick/goal_frame", viewport) as shown,
        notice_left_open(shown) as corner,
    ):
        page = shown.page
        notice = (0.0, 0.0) if corner is None else corner
        scene = shown.scene
        assert isinstance(scene, FreeKickScene)
        panel_left = panel_rect(page)[0]
        for distance, angle in ((22.0, 0.0), (30.0, 40.0), (40.0, -45.0)):
            scene.controls["distance_m"].value, scene.controls["angle_deg"].value = distance, angle
            settle(shown)
            shown_px = screenshot(page, path=f"/tmp/freekick_notice_{distance:.0f}_{angle:.0f}_{viewport[0]}.png")
            # The goal's corners and the standing keeper's box through the page's own camera: in the page, left of
            # the panel and none behind the notice (the notice hides what is under it, so pixels alone cannot tell).
            with scene._lock:
                keeper = scene.state.keeper_xy
            assert keeper is not None
            standing = [
                [keeper[0] + sx, keeper[1] + sy, z] for sx in (-0.4, 0.4) for sy in (-0.4, 0.4) for z in (0, 2.3)
            ]
            assert_in_view_clear_of_notice(
                shown, "/freekick", np.vstack([GOAL_CORNERS, standing]), f"goal and keeper {distance, angle}", corner
            )
            # Least pixels each draws: the goal's frame covers 133 px at its smallest (40 m out at −45°, 1280×720).
            for names, least in ((["/freekick/goal_frame"], 100), (["/freekick/keeper", "/freekick/keeper_head"], 20)):
                seen = changed_mask(shown_px, with_nodes_hidden(page, names))
                seen[:, int(panel_left) :] = False  # the panel's text can redraw meanwhile; it covers the canvas
                ys, xs = np.nonzero(seen)
                where = (names[0], distance, angle, viewport)
                assert len(xs) >= least, where  # drawn large enough to see
                under = (xs < notice[0]) & (ys < notice[1])
                assert not under.any(), (where, int(under.sum()))  # none of it under the notice
            if corner is not None:
                assert page.locator(TOAST).count() == 1  # still open: what was looked at was under it
            assert error_text(page) == []
        scene.controls["distance_m"].value, scene.controls["angle_deg"].value = 22.0, 0.0
