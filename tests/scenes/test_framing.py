"""Camera framing: every point lands inside the asked rectangle, as tightly as the view allows, for any cloud."""

from __future__ import annotations

import contextlib
import math
from typing import NamedTuple

import numpy as np
import pytest
from helpers.screen_geometry import pinhole_ndc
from hypothesis import example, given, settings
from hypothesis import strategies as st

from scenes._framing import NEAR_M, ClientFraming, Lens, View, box_corners, frame_points


def _project(points: np.ndarray, position: np.ndarray, look_at: np.ndarray, fov: float, aspect: float) -> np.ndarray:
    """(N, 3) NDC x, y and depth (m) through an independent pinhole camera."""
    return pinhole_ndc(points, position, look_at, fov, aspect)


coordinate = st.floats(-50.0, 50.0, allow_nan=False)


def _direction(azimuth: float, pitch: float) -> tuple[float, float, float]:
    """Unit view direction at ``azimuth`` about z and ``pitch`` above the horizontal (rad)."""
    return (math.cos(azimuth) * math.cos(pitch), math.sin(azimuth) * math.cos(pitch), math.sin(pitch))


def _rectangle(x0: float, width: float, y0: float, height: float) -> tuple[float, float, float, float]:
    """NDC rectangle (x0, x1, y0, y1) from a corner and a size, its far edges kept inside the view."""
    return (x0, min(x0 + width, 0.99), y0, min(y0 + height, 0.99))


def _clouds(min_size: int, max_size: int) -> st.SearchStrategy[np.ndarray]:
    """(N, 3) point clouds (m) of ``min_size`` to ``max_size`` points."""
    return st.lists(st.tuples(coordinate, coordinate, coordinate), min_size=min_size, max_size=max_size).map(np.array)


def _directions(max_pitch: float) -> st.SearchStrategy[tuple[float, float, float]]:
    """Unit view directions at any azimuth, pitched at most ``max_pitch`` (rad) above or below the horizontal."""
    return st.builds(_direction, st.floats(-math.pi, math.pi), st.floats(-max_pitch, max_pitch))


def _rectangles(side: st.SearchStrategy[float]) -> st.SearchStrategy[tuple[float, float, float, float]]:
    """NDC rectangles with a corner anywhere in the view and sides drawn from ``side``."""
    corner = st.floats(-0.99, 0.9)
    return st.builds(_rectangle, corner, side, corner, side)


MIN_DEPTHS = st.sampled_from([0.0, 3.0])
"""No least depth, and one that holds the camera back."""


class Shot(NamedTuple):
    """One call of frame_points: a cloud seen along a direction through a lens into a rectangle."""

    cloud: np.ndarray
    """(N, 3) points to frame (m)."""
    direction: tuple[float, float, float]
    """Unit view direction."""
    fov: float
    """Vertical field of view (rad)."""
    aspect: float
    """Width over height of the window."""
    ndc: tuple[float, float, float, float]
    """Rectangle (x0, x1, y0, y1) the points must land in."""
    min_depth: float
    """Least depth of any point in front of the camera (m)."""

    def view(self) -> View:
        return frame_points(
            self.cloud, self.direction, fov_rad=self.fov, aspect=self.aspect, ndc=self.ndc, min_depth=self.min_depth
        )

    def project(self, view: View) -> np.ndarray:
        """(N, 3) NDC x, y and depth of the cloud through ``view``, by the independent pinhole camera."""
        return _project(self.cloud, np.array(view.position), np.array(view.look_at), self.fov, self.aspect)


def _shots(
    clouds: st.SearchStrategy[np.ndarray],
    max_pitch: float,
    rectangles: st.SearchStrategy[tuple[float, float, float, float]],
    min_depths: st.SearchStrategy[float] = MIN_DEPTHS,
) -> st.SearchStrategy[Shot]:
    """Shots of the given clouds into the given rectangles, any lens of 20–90° and aspect 0.5–3."""
    fovs = st.floats(20.0, 90.0).map(math.radians)
    return st.builds(Shot, clouds, _directions(max_pitch), fovs, st.floats(0.5, 3.0), rectangles, min_depths)


def _assert_inside(projected: np.ndarray, ndc: tuple[float, float, float, float]) -> None:
    """Every projected point's NDC x and y lie inside the rectangle ``ndc``, to rounding."""
    eps = 1e-6
    assert projected[:, 0].min() >= ndc[0] - eps and projected[:, 0].max() <= ndc[1] + eps
    assert projected[:, 1].min() >= ndc[2] - eps and projected[:, 1].max() <= ndc[3] + eps


def _assert_tight_or_held_back(
    projected: np.ndarray, ndc: tuple[float, float, float, float], least_depth: float
) -> None:
    """Tight: some point reaches an edge of the rectangle, unless the least depth holds the camera back (its nearest
    point is as near as allowed: a cloud along the view direction, or one a few centimetres across)."""
    spread = max(np.ptp(projected[:, 0]) / (ndc[1] - ndc[0]), np.ptp(projected[:, 1]) / (ndc[3] - ndc[2]))
    held_back = projected[:, 2].min() <= least_depth * (1.0 + 1e-6) + 1e-6
    assert held_back or spread > 0.97, (spread, projected[:, 2].min())


@given(_shots(_clouds(1, 12), 1.2, st.just((-0.8, 0.4, -0.7, 0.9))))
def test_every_point_projects_inside_the_rectangle(shot: Shot) -> None:
    projected = shot.project(shot.view())
    least_depth = max(shot.min_depth, NEAR_M)
    assert np.all(projected[:, 2] >= least_depth - 1e-6)
    _assert_inside(projected, shot.ndc)
    if np.ptp(shot.cloud, axis=0).max() > 1e-3:
        _assert_tight_or_held_back(projected, shot.ndc, least_depth)


def test_a_cloud_along_the_view_direction_stays_beyond_the_near_plane() -> None:
    # Found by the property above: the camera was put 1 mm in front of the near point (viser clips at 10 mm).
    cloud = np.array([(0.0, 0.0, 0.0), (2.0, 0.0, 3.0)])
    direction = (math.cos(3.0) * math.cos(-1.0), math.sin(3.0) * math.cos(-1.0), math.sin(-1.0))
    view = frame_points(cloud, direction, fov_rad=math.radians(20.0), aspect=1.0, ndc=(-0.8, 0.4, -0.7, 0.9))
    projected = _project(cloud, np.array(view.position), np.array(view.look_at), math.radians(20.0), 1.0)
    assert projected[:, 2].min() == pytest.approx(NEAR_M, rel=1e-3)


def test_a_cloud_deep_behind_its_centre_is_framed_tight_not_held_back_by_its_far_side() -> None:
    # Found by the property above with fresh examples: the camera was kept at least the cloud's largest depth offset
    # (its far side's) behind the centre, so a cloud whose far side lies deeper than its near side filled only 93 % of
    # the rectangle while its nearest point stood 0.23 m away, not at the 0.05 m that holds a camera back.
    cloud = np.array([(0.0, 0.0, 0.0), (0.0, 2.0, 0.0), (1.0, 0.0, 0.0)])
    ndc, fov = (-0.8, 0.4, -0.7, 0.9), math.radians(31.0)
    view = frame_points(cloud, _direction(-1.75, 0.0), fov_rad=fov, aspect=3.0, ndc=ndc)
    projected = _project(cloud, np.array(view.position), np.array(view.look_at), fov, 3.0)
    _assert_inside(projected, ndc)
    assert np.ptp(projected[:, 0]) / (ndc[1] - ndc[0]) == pytest.approx(1.0, abs=1e-9)
    assert projected[:, 2].min() > NEAR_M


def test_a_box_seen_side_on_is_centred_in_the_free_part_of_the_window() -> None:
    # A 10 m × 1 m × 2 m box, seen along +y: its centre lands mid-way across the canvas left of the panel.
    lo, hi = np.array([-5.0, -0.5, 0.0]), np.array([5.0, 0.5, 2.0])
    corners = np.array(
        [[(lo, hi)[i][0], (lo, hi)[j][1], (lo, hi)[k][2]] for i in (0, 1) for j in (0, 1) for k in (0, 1)]
    )
    lens = Lens(math.radians(50.0), 1600, 1000)
    ndc = lens.usable_ndc()
    view = frame_points(corners, (0.0, 1.0, 0.0), fov_rad=lens.fov_rad, aspect=lens.aspect, ndc=ndc)
    projected = _project(corners, np.array(view.position), np.array(view.look_at), lens.fov_rad, lens.aspect)
    centre_x = 0.5 * (projected[:, 0].min() + projected[:, 0].max())
    assert centre_x == pytest.approx(0.5 * (ndc[0] + ndc[1]), abs=1e-6)
    assert ndc[1] < 1.0 - 2 * 384 / 1600  # the free part ends left of the 384 px panel


def test_a_narrow_window_uses_the_whole_width_and_bad_lenses_fall_back() -> None:
    assert Lens(1.0, 600, 800).usable_ndc()[1] > 0.9  # viser moves the panel out of the way there
    view = frame_points(np.zeros((1, 3)), (1.0, 0.0, 0.0), fov_rad=float("nan"), aspect=0.0)
    assert all(math.isfinite(c) for c in (*view.position, *view.look_at))


@given(_shots(_clouds(2, 12), 1.0, _rectangles(st.floats(0.05, 1.0)), min_depths=st.just(0.0)))
def test_a_rectangle_off_the_view_axis_is_filled_too(shot: Shot) -> None:
    # The fault's family: any rectangle, also one that misses the centre of the view (the part of a narrow window
    # left of the panel and the labels' room lies wholly left of it). Every point lands inside, and tightly.
    if np.ptp(shot.cloud, axis=0).max() < 1e-2:
        return
    projected = shot.project(shot.view())
    assert np.all(projected[:, 2] > 0.0)
    _assert_inside(projected, shot.ndc)
    _assert_tight_or_held_back(projected, shot.ndc, NEAR_M)


def test_eight_riders_six_metres_apart_in_a_1150_px_window_are_framed_near() -> None:
    # The failing input: the line's box (8 riders 6 m apart at 55 km/h) in a 1150×720 canvas, where the room left of
    # the panel and the labels ends left of the view axis (x1 = −0.085). The camera went 28 km away (0 px of the
    # riders drawn); the line is 56 m long, so about 40 m is right.
    lo, hi = np.array([-54.75, -1.1, 0.0]), np.array([0.85, 1.1, 4.26])
    corners = box_corners(lo, hi)
    lens = Lens(math.radians(75.0), 1150, 720)
    ndc = lens.usable_ndc(right_px=190.0, top_px=30.0)
    assert ndc[1] < 0.0
    view = frame_points(corners, (-1.2, 7.5, -1.8), fov_rad=lens.fov_rad, aspect=lens.aspect, ndc=ndc)
    distance = float(np.linalg.norm(np.subtract(view.position, view.look_at)))
    assert 20.0 < distance < 80.0, distance
    projected = _project(corners, np.array(view.position), np.array(view.look_at), lens.fov_rad, lens.aspect)
    assert projected[:, 0].min() >= ndc[0] - 1e-6 and projected[:, 0].max() <= ndc[1] + 1e-6


def test_an_empty_rectangle_frames_in_the_whole_view() -> None:
    cloud = box_corners((-5.0, -1.0, 0.0), (5.0, 1.0, 2.0))
    view = frame_points(cloud, (0.0, 1.0, 0.0), fov_rad=1.0, aspect=1.5, ndc=(0.3, 0.1, -0.5, 0.5))
    projected = _project(cloud, np.array(view.position), np.array(view.look_at), 1.0, 1.5)
    assert np.abs(projected[:, :2]).max() <= 0.9 + 1e-6
    assert np.abs(projected[:, 0]).max() > 0.85  # framed tightly, not from far away


class _Tab:
    """A stand-in for one tab's viser camera handle: it reports what the test sets, and records the writes."""

    def __init__(self) -> None:
        self.client = self
        self.client_id = 7
        self.image_width, self.image_height, self.fov = 1280, 720, math.radians(75.0)
        self.position, self.look_at, self.up_direction = ((1.0, -7.5, 2.8), (0.0, 0.0, 1.0), (0.0, 0.0, 1.0))

    def atomic(self) -> contextlib.AbstractContextManager[None]:
        return contextlib.nullcontext()


def test_a_tab_put_back_at_its_opening_view_before_showing_the_framing_is_framed_again() -> None:
    # viser's client applies the server's initial camera in a React effect that can run after the first framing
    # arrived: the tab then reports its opening view and, with an unchanged canvas, was never framed again.
    framed = View(position=(5.0, -32.5, 11.2), look_at=(-0.9, 4.4, 2.4))
    framing = ClientFraming(lambda lens: framed)
    tab = _Tab()
    opening = tab.position
    framing.on_camera(tab)
    assert framing.frames == 1 and tab.position == framed.position
    tab.position = opening  # the client's reset, reported back
    framing.on_camera(tab)
    assert framing.frames == 2 and tab.position == framed.position
    framing.on_camera(tab)  # now the tab reports the framed view
    tab.position = (9.0, -9.0, 3.0)  # and from then on the person orbits: left alone
    framing.on_camera(tab)
    assert framing.frames == 2 and tab.position == (9.0, -9.0, 3.0)


@pytest.mark.parametrize("confirmations", [0, 1, 3, 6])
def test_a_tab_put_back_at_its_opening_view_after_showing_the_framing_is_framed_again(confirmations: int) -> None:
    # The kind: viser's client resets a tab to the server's initial camera at any time after connecting (its
    # InitialCameraSetter effect, the root turning, "Reset View"), also after the tab reported the framed view
    # back, however many times it did. The old rule took every move after a confirmation for the person's.
    framed = View(position=(5.0, -32.5, 11.2), look_at=(-0.9, 4.4, 2.4))
    tab = _Tab()
    opening = tab.position
    framing = ClientFraming(lambda lens: framed, opening=opening)
    framing.on_camera(tab)
    assert framing.pending(tab.client_id)
    for _ in range(confirmations):
        framing.on_camera(tab)  # the framed view reported back (again)
    assert not framing.pending(tab.client_id) or confirmations == 0
    tab.position = opening  # the client's reset, reported back
    framing.on_camera(tab)
    assert framing.frames == 2 and tab.position == framed.position
    framing.on_camera(tab)
    assert not framing.pending(tab.client_id)
    # A person orbiting is left alone, also next to the opening view; only the opening pose itself re-frames.
    near = (opening[0] + 0.05, opening[1], opening[2])
    tab.position = near
    framing.on_camera(tab)
    assert framing.frames == 2 and tab.position == near


def test_without_an_opening_view_a_move_after_the_confirmation_is_the_persons() -> None:
    framed = View(position=(5.0, -32.5, 11.2), look_at=(-0.9, 4.4, 2.4))
    tab = _Tab()
    opening = tab.position
    framing = ClientFraming(lambda lens: framed)
    framing.on_camera(tab)
    framing.on_camera(tab)
    tab.position = opening
    framing.on_camera(tab)
    assert framing.frames == 1 and tab.position == opening


def _reference_view(shot: Shot) -> tuple[np.ndarray, np.ndarray]:
    """(position, look_at) by brute force, as frame_points once searched: bisect the distance between the depth
    extent and 1000× the cloud's size, at each one bisecting each shift across the view until the points' ndc are
    centred in the rectangle and checking they fit; an empty (x1 ≤ x0 or y1 ≤ y0) or unreachable rectangle falls back
    to the whole view."""
    cloud, direction, fov, aspect, ndc, min_depth = shot
    d = np.asarray(direction) / np.linalg.norm(direction)
    right = np.cross(d, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, d)
    centre = 0.5 * (cloud.min(axis=0) + cloud.max(axis=0))
    rel = cloud - centre
    u, v, w = rel @ right, rel @ up, rel @ d
    tan_y = math.tan(fov / 2)
    size = float(np.linalg.norm(rel, axis=1).max())
    least = max(min_depth, NEAR_M)

    def centred(coord: np.ndarray, scale: np.ndarray, lo: float, hi: float) -> float:
        a, b = -1e4 * (size + 1.0), 1e4 * (size + 1.0)
        for _ in range(64):
            s = 0.5 * (a + b)
            p = (coord - s) / scale
            a, b = (s, b) if p.min() + p.max() > lo + hi else (a, s)
        return 0.5 * (a + b)

    def fit(distance: float, rect: tuple[float, float, float, float]) -> tuple[bool, float, float]:
        depth = distance + w
        if depth.min() < least:
            return False, 0.0, 0.0
        kx, ky = depth * tan_y * aspect, depth * tan_y
        sx, sy = centred(u, kx, rect[0], rect[1]), centred(v, ky, rect[2], rect[3])
        px, py = (u - sx) / kx, (v - sy) / ky
        inside = px.min() >= rect[0] and px.max() <= rect[1] and py.min() >= rect[2] and py.max() <= rect[3]
        return bool(inside), sx, sy

    empty = not (ndc[1] > ndc[0] and ndc[3] > ndc[2])  # the docstring's rule (a lone point fits a line by luck)
    for rect in [(-0.9, 0.9, -0.9, 0.9)] if empty else [ndc, (-0.9, 0.9, -0.9, 0.9)]:
        near = float(np.abs(w).max()) + NEAR_M
        far = float(np.abs(w).max()) + least + 1000.0 * (size + 1.0)
        for _ in range(64):
            mid = 0.5 * (near + far)
            near, far = (near, mid) if fit(mid, rect)[0] else (mid, far)
        ok, sx, sy = fit(far, rect)
        if ok or rect == (-0.9, 0.9, -0.9, 0.9):
            look_at = centre + sx * right + sy * up
            return look_at - far * d, look_at
    raise AssertionError("unreachable")


# The peloton's line box in a 1150 px window (rectangle left of the view axis), the same box from further off
# with min_depth 3, and an empty rectangle.
# A rectangle's side is empty (≤ 0) or at least 0.01: a narrower one is below what the brute force resolves (with one
# point it takes a 1e-210 wide rectangle for empty, as the bisection's shift never lands the point inside).
_side = st.one_of(st.floats(-0.3, 0.0), st.floats(0.01, 1.0))
_LINE = box_corners((-54.75, -1.1, 0.0), (0.85, 1.1, 4.26))


@given(_shots(_clouds(1, 16), 1.2, _rectangles(_side)))
@settings(deadline=None)  # the brute force takes ~40 ms an example
@example(
    Shot(_LINE, _direction(1.73, -0.23), math.radians(75.0), 1150 / 720, _rectangle(-0.917, 0.832, -0.867, 1.65), 0.0)
)
@example(Shot(_LINE, _direction(0.4, 0.3), math.radians(50.0), 1.6, _rectangle(-0.8, 1.6, -0.8, 1.6), 3.0))
@example(Shot(_LINE, _direction(0.4, 0.3), math.radians(50.0), 1.6, _rectangle(0.3, -0.2, -0.5, 1.0), 0.0))
def test_frame_points_agrees_with_a_brute_force_search(shot: Shot) -> None:
    # The fault's kind: a closed-form search that differs from the nested bisections it replaced, for any cloud,
    # direction, lens or rectangle (off the view axis, or empty: x1 ≤ x0 or y1 ≤ y0). The nearest distance and the
    # centring shift are both unique, so the views agree to rounding.
    view = shot.view()
    position, look_at = _reference_view(shot)
    cloud = shot.cloud
    scale = 1.0 + float(np.linalg.norm(position - look_at)) + float(np.ptp(cloud, axis=0).max())
    assert np.abs(np.subtract(view.position, position)).max() <= 1e-9 * scale, (view, position)
    assert np.abs(np.subtract(view.look_at, look_at)).max() <= 1e-9 * scale, (view, look_at)
