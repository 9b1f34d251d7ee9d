"""Camera framing: where to put a browser's camera so a set of points fills the part of the view a person can see.

viser's control panel floats over the right of the canvas (384 px wide and 15 px from the edge at the app's
``control_width="large"``), so "in view" means inside the canvas and left of the panel. Framing is pure geometry
on the client's vertical field of view and image size, so it works for any window; scenes call it from
:meth:`~scenes._base.Scene.watch_cameras` once per client and again when what they show grows or moves.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import threading
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

logger = logging.getLogger(__name__)

PANEL_PX = 410.0
"""Width the control panel covers at the right of the canvas, with a margin (px)."""
MARGIN_PX = 24.0
"""Space kept free at the other edges (px)."""
NEAR_M = 0.05
"""Least distance of a framed point in front of the camera (m), whatever ``min_depth`` says: viser's near clipping
plane is 0.01 m, and a cloud lying along the view direction would otherwise get the camera 1 mm from its nearest
point, which the near plane then cuts away."""
FULL_NDC = (-0.9, 0.9, -0.9, 0.9)
"""The rectangle framing uses when none is given, or when the one given is empty."""


@dataclasses.dataclass(frozen=True)
class View:
    """A camera pose: where it sits and the point it orbits (world frame, m)."""

    position: tuple[float, float, float]
    look_at: tuple[float, float, float]

    @property
    def direction(self) -> tuple[float, float, float]:
        """From the position to the look-at point (m)."""
        (px, py, pz), (lx, ly, lz) = self.position, self.look_at
        return lx - px, ly - py, lz - pz


def _basis(direction: NDArray[np.float64]) -> tuple[NDArray[np.float64], ...]:
    d = direction / np.linalg.norm(direction)
    right = np.cross(d, (0.0, 0.0, 1.0))
    if np.linalg.norm(right) < 1e-9:  # looking straight down or up: pick +x as right
        right = np.array([1.0, 0.0, 0.0])
    right = right / np.linalg.norm(right)
    return d, right, np.cross(right, d)


@dataclasses.dataclass(frozen=True)
class Lens:
    """One browser's camera: vertical field of view and canvas size (CSS px: :data:`server.gate.CSS_CAMERA_JS`)."""

    fov_rad: float
    width_px: int
    height_px: int

    @property
    def aspect(self) -> float:
        return self.width_px / self.height_px

    def usable_ndc(self, *, right_px: float = 0.0, top_px: float = 0.0) -> tuple[float, float, float, float]:
        """(x0, x1, y0, y1) of the canvas left of the panel, in normalised device coordinates.

        ``right_px`` and ``top_px`` keep extra room free for screen-sized things anchored at the points (labels).
        A window narrower than twice the panel gets the whole width (viser then lays the panel out differently).
        """
        width, height = max(self.width_px, 1), max(self.height_px, 1)
        panel = PANEL_PX if width > 2.0 * PANEL_PX else 0.0
        mx, my = 2.0 * MARGIN_PX / width, 2.0 * MARGIN_PX / height
        return (-1.0 + mx, 1.0 - 2.0 * (panel + right_px) / width - mx, -1.0 + my, 1.0 - 2.0 * top_px / height - my)


@dataclasses.dataclass(frozen=True)
class Sight:
    """Points as a camera looking along a direction sees them, about the centre of their bounding box: where
    framing starts, whatever way it then finds the distance and the centring shifts.

    Attributes:
        centre: (3,) centre of the points' bounding box (m).
        basis: (3,) unit vectors (forward, right, up): the view direction, its horizontal right and its up.
        offsets: (N,) arrays (u, v, w), each point's offset from the centre along right, up and forward (m).
        tan_x, tan_y: tangents of half the horizontal and half the vertical field of view.
        depth_extent: largest |w| (m).
        size: largest distance of a point from the centre (m).
    """

    centre: NDArray[np.float64]
    basis: tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]
    offsets: tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]
    tan_x: float
    tan_y: float
    depth_extent: float
    size: float

    @staticmethod
    def of(pts: NDArray[np.float64], direction: tuple[float, float, float], *, fov_rad: float, aspect: float) -> Sight:
        """The sight of (N ≥ 1, 3) points along ``direction``; an unusable ``fov_rad`` is 50°, an ``aspect`` 1.6."""
        if not (math.isfinite(fov_rad) and 0.01 < fov_rad < 3.0):
            fov_rad = math.radians(50.0)
        if not (math.isfinite(aspect) and aspect > 0.05):
            aspect = 1.6
        forward, right, up = _basis(np.asarray(direction, dtype=np.float64))
        centre = 0.5 * (pts.min(axis=0) + pts.max(axis=0))
        rel = pts - centre
        w = rel @ forward
        tan_y = math.tan(0.5 * fov_rad)
        return Sight(
            centre,
            (forward, right, up),
            (rel @ right, rel @ up, w),
            tan_x=aspect * tan_y,
            tan_y=tan_y,
            depth_extent=float(np.max(np.abs(w))),
            size=float(np.max(np.linalg.norm(rel, axis=1))),
        )

    def view(self, distance: float, sx: float, sy: float) -> View:
        """The camera ``distance`` (m) behind the centre shifted by ``sx`` right and ``sy`` up (m), looking along
        the view direction; it orbits the shifted centre."""
        forward, right, up = self.basis
        look_at = self.centre + sx * right + sy * up
        position = look_at - distance * forward
        return View(
            position=(float(position[0]), float(position[1]), float(position[2])),
            look_at=(float(look_at[0]), float(look_at[1]), float(look_at[2])),
        )


def frame_points(
    points: NDArray[np.float64],
    direction: tuple[float, float, float],
    *,
    fov_rad: float,
    aspect: float,
    ndc: tuple[float, float, float, float] = FULL_NDC,
    min_depth: float = 0.0,
) -> View:
    """The camera looking along ``direction`` (z up) that shows every one of ``points`` inside ``ndc``, as close as it
    can.

    Args:
        points: (N, 3) world points that must be seen (m).
        direction: view direction (any length, not vertical).
        fov_rad: vertical field of view (rad), as viser's ``camera.fov``.
        aspect: image width / height.
        ndc: (x0, x1, y0, y1) rectangle of normalised device coordinates the points must project into; an empty
            one (x1 ≤ x0 or y1 ≤ y0) falls back to :data:`FULL_NDC`.
        min_depth: every point stays at least this far in front of the camera (m): "behind the ball", not in it;
            never under :data:`NEAR_M`.

    Returns:
        The camera position and orbit centre. The orbit centre sits on the view axis, so the points appear centred
        in ``ndc`` rather than in the middle of the canvas.
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    x0, x1, y0, y1 = ndc
    sight = Sight.of(pts, direction, fov_rad=fov_rad, aspect=aspect)
    u, v, w = sight.offsets
    tan_x, tan_y, depth_extent, size = sight.tan_x, sight.tan_y, sight.depth_extent, sight.size
    least_depth = max(min_depth, NEAR_M) if math.isfinite(min_depth) else NEAR_M
    # The camera at distance D behind the centre sees point i at depth D + w_i and, shifted by s across the view, at
    # ndc (u_i − s)/((D + w_i)·tan_x) on x (likewise on y). Some s puts every point inside [lo, hi] iff
    # max_i(u_i − hi·k_i) ≤ min_j(u_j − lo·k_j) with k = (D + w)·tan_x, which is linear in D: the least distance is
    # closed-form (_least_distance). The nearest distance is never under the one the depths allow (which keeps every
    # k positive); it is never over `far`, beyond which the rectangle counts as unable to hold the points.
    far = depth_extent + least_depth + 1000.0 * (size + 1.0)
    distance = max(
        least_depth - float(np.min(w)), _least_distance(u, w, tan_x, x0, x1), _least_distance(v, w, tan_y, y0, y1)
    )
    # Also NaN: the rectangle is empty, or too small to hold the points from `far`.
    if not distance <= far:
        if ndc != FULL_NDC:
            return frame_points(pts, direction, fov_rad=fov_rad, aspect=aspect, ndc=FULL_NDC, min_depth=min_depth)
        distance = far
    depth = distance + w
    sx = _centring_shift(u, depth * tan_x, x0, x1)
    sy = _centring_shift(v, depth * tan_y, y0, y1)
    return sight.view(distance, sx, sy)


def _least_distance(coord: NDArray[np.float64], w: NDArray[np.float64], tan: float, lo: float, hi: float) -> float:
    """Least distance D at which some shift s puts every (coord_i − s)/((D + w_i)·tan) inside [lo, hi] (m).

    Feasible iff coord_i − hi·k_i ≤ coord_j − lo·k_j for every pair (i, j), with k = (D + w)·tan; the pairs separate,
    so D = (max_i(coord_i/tan − hi·w_i) + max_j(lo·w_j − coord_j/tan)) / (hi − lo). An empty interval (hi ≤ lo)
    gives +inf; NaN bounds give NaN.
    """
    if not hi > lo:
        return math.nan if math.isnan(hi - lo) else math.inf
    scaled = coord / tan
    return (float(np.max(scaled - hi * w)) + float(np.max(lo * w - scaled))) / (hi - lo)


def _centring_shift(coord: NDArray[np.float64], scale: NDArray[np.float64], lo: float, hi: float) -> float:
    """The shift s with the projections p_i = (coord_i − s)/scale_i (scale > 0) centred in [lo, hi]:
    max p + min p = lo + hi, exactly (to rounding).

    That s is the one keeping every p_i inside [lo + δ, hi − δ] for the largest margin δ: such an s exists iff
    h(δ) = max_i(coord_i − hi·scale_i + δ·scale_i) + max_j(lo·scale_j − coord_j + δ·scale_j) ≤ 0, and h is convex,
    piecewise linear and strictly increasing in δ. Newton's method on it from δ = (hi − lo)/2 (where h ≥ 0) stays
    right of the root and lands on it exactly once it uses the root's linear piece: a few steps, at most one a piece.
    """
    alpha, beta = coord - hi * scale, lo * scale - coord
    delta = 0.5 * (hi - lo)
    active = (-1, -1)
    for _ in range(2 * len(coord) + 2):
        upper, lower = alpha + delta * scale, beta + delta * scale
        i, j = int(np.argmax(upper)), int(np.argmax(lower))
        excess = float(upper[i] + lower[j])
        if not excess > 0.0 or (i, j) == active:
            break
        active = (i, j)
        delta -= excess / float(scale[i] + scale[j])
    else:
        upper, lower = alpha + delta * scale, beta + delta * scale
    # At the root max(coord − (hi − δ)·scale) = min(coord − (lo + δ)·scale) = s; average the two against rounding.
    return 0.5 * (float(np.max(upper)) - float(np.max(lower)))


def project_points(view: View, lens: Lens, points: NDArray[np.float64]) -> NDArray[np.float64]:
    """(N, 3) where ``points`` land on the canvas of a camera at ``view`` with up +z: x, y (px from the top left) and
    depth along the view axis (m), as three.js's perspective camera draws them.

    Args:
        view: camera position and orbit centre (world frame, m).
        lens: the browser's vertical field of view and canvas size.
        points: (N, 3) world points (m).
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    eye = np.asarray(view.position, dtype=np.float64)
    d, right, up = _basis(np.asarray(view.look_at, dtype=np.float64) - eye)
    rel = pts - eye
    depth = rel @ d
    safe = np.where(np.abs(depth) > 1e-9, depth, 1e-9)
    tan_y = math.tan(0.5 * lens.fov_rad)
    ndc_x = (rel @ right) / (safe * tan_y * lens.aspect)
    ndc_y = (rel @ up) / (safe * tan_y)
    return np.stack([0.5 * (ndc_x + 1.0) * lens.width_px, 0.5 * (1.0 - ndc_y) * lens.height_px, depth], axis=1)


def box_corners(lo: NDArray[np.float64] | tuple, hi: NDArray[np.float64] | tuple) -> NDArray[np.float64]:
    """(8, 3) corners of the axis-aligned box [lo, hi]."""
    lo_a, hi_a = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    return np.array(
        [[(lo_a, hi_a)[i][0], (lo_a, hi_a)[j][1], (lo_a, hi_a)[k][2]] for i in (0, 1) for j in (0, 1) for k in (0, 1)]
    )


NOTICE_PX = (318.0, 193.0)
"""Room (px, width and height from the canvas's top left corner) of viser's "Software WebGL rendering detected"
notice: 296 × 171 px, 14 px from the corner, with 8 px to spare. A browser drawing without a GPU shows it over the
scene until a person closes it, so nothing framed goes under it."""


def in_notice(points_px: NDArray[np.float64]) -> NDArray[np.bool_]:
    """(N,) whether each canvas point of (N, ≥2) ``points_px`` (x, y in px from the top left) lies under
    :data:`NOTICE_PX`."""
    px = np.asarray(points_px, dtype=np.float64).reshape(len(points_px), -1)
    return (px[:, 0] < NOTICE_PX[0]) & (px[:, 1] < NOTICE_PX[1])


def beside_notice(
    lens: Lens, ndc: tuple[float, float, float, float], *, room_above_px: float = 0.0
) -> list[tuple[float, float, float, float]]:
    """The two parts of the rectangle ``ndc`` (x0, x1, y0, y1, normalised device coordinates of ``lens``) clear of
    :data:`NOTICE_PX`: below the notice (leaving ``room_above_px`` under it, e.g. for labels drawn above their
    anchors) and right of it."""
    x0, x1, y0, y1 = ndc
    # One pixel past the notice's edges, so a point framed onto a part's edge stays clear of it after rounding.
    below = 1.0 - 2.0 * (NOTICE_PX[1] + 1.0 + room_above_px) / max(lens.height_px, 1)
    right = -1.0 + 2.0 * (NOTICE_PX[0] + 1.0) / max(lens.width_px, 1)
    return [(x0, x1, y0, min(y1, below)), (max(x0, right), x1, y0, y1)]


def shows(
    view: View, lens: Lens, points: NDArray[np.float64], *, slack_px: float = 1.0, clear_of_notice: bool = True
) -> bool:
    """Whether a camera at ``view`` shows every one of (N, 3) ``points`` (m) where framing puts them: in front of it,
    inside the canvas left of the panel (:meth:`Lens.usable_ndc`, give or take ``slack_px``) and, with
    ``clear_of_notice`` (for views framed by :func:`frame_clear_of_notice`), none under :data:`NOTICE_PX`."""
    xy = project_points(view, lens, points)
    width, height = max(lens.width_px, 1), max(lens.height_px, 1)
    x0, x1, y0, y1 = lens.usable_ndc()
    x_ndc, y_ndc = 2.0 * xy[:, 0] / width - 1.0, 1.0 - 2.0 * xy[:, 1] / height
    sx, sy = 2.0 * slack_px / width, 2.0 * slack_px / height
    inside = (x_ndc >= x0 - sx) & (x_ndc <= x1 + sx) & (y_ndc >= y0 - sy) & (y_ndc <= y1 + sy)
    return bool(np.all(inside & (xy[:, 2] >= NEAR_M)) and not (clear_of_notice and in_notice(xy).any()))


def frame_clear_of_notice(
    points: NDArray[np.float64], direction: tuple[float, float, float], lens: Lens, *, min_depth: float = 0.0
) -> View:
    """The camera looking along ``direction`` that shows every one of (N, 3) ``points`` (m) left of the panel, at
    least ``min_depth`` (m) in front of it, and none under viser's software-WebGL notice (:data:`NOTICE_PX`).

    Where the framing of the whole free rectangle puts a point under the notice, the nearer (larger) of the framings
    below it and right of it (:func:`beside_notice`) that keeps every point clear; if neither does, the nearer."""

    def frame(ndc: tuple[float, float, float, float]) -> View:
        return frame_points(points, direction, fov_rad=lens.fov_rad, aspect=lens.aspect, ndc=ndc, min_depth=min_depth)

    def hidden(view: View) -> bool:
        return bool(in_notice(project_points(view, lens, points)).any())

    ndc = lens.usable_ndc()
    framed = frame(ndc)
    if not hidden(framed):
        return framed
    candidates = [frame(part) for part in beside_notice(lens, ndc)]
    clear = [c for c in candidates if not hidden(c)] or candidates
    return min(clear, key=lambda v: math.dist(v.position, v.look_at))


class ClientFraming:
    """Frames each browser's camera once, by its own image size, and all of them again on :meth:`reframe`.

    ``view_for(lens)`` gives the view for one camera. Feed :meth:`on_camera` to
    :meth:`~scenes._base.Scene.watch_cameras`: a camera seen for the first time (a new tab) or with a new canvas size
    (a resized window) is framed; other moves (the person orbiting) are left alone until the scene calls
    :meth:`reframe`, as when what it shows grows.

    ``opening`` is the position (m) viser's client puts a tab back to: the server's ``initial_camera``. A tab that
    reports it is framed again, whenever that happens: viser's client can apply its opening camera after our first
    framing arrived and was reported back (its ``InitialCameraSetter`` effect runs when the server's initial camera
    first reaches the tab, and again whenever the scene root turns), and its "Reset View" button goes there too. A
    person orbiting does not stop at exactly that pose.
    """

    def __init__(self, view_for: Callable[[Lens], View], opening: tuple[float, float, float] | None = None) -> None:
        self._view_for = view_for
        self._opening = None if opening is None else np.asarray(opening, dtype=np.float64)
        self._lock = threading.Lock()
        self._cameras: dict[int, Any] = {}
        self._framed: dict[int, tuple[int, int]] = {}
        """Canvas size each client was last framed for."""
        self._unconfirmed: dict[int, tuple[NDArray[np.float64], int]] = {}
        """Position written to each client whose camera has not reported it back yet, and the re-frames left."""
        self._written: dict[int, NDArray[np.float64]] = {}
        """Position last written to each client."""
        self.frames = 0
        """How many times a camera was framed (tests wait on it)."""

    def on_camera(self, camera: Any) -> None:
        try:
            client_id = int(camera.client.client_id)
        except (AttributeError, TypeError, ValueError):
            return
        try:
            size = (int(camera.image_width), int(camera.image_height))
        except (AttributeError, TypeError, ValueError, AssertionError):
            return
        with self._lock:
            self._cameras[client_id] = camera
            if self._framed.get(client_id) == size:
                unconfirmed = self._unconfirmed.pop(client_id, None)
                if unconfirmed is None:
                    if not self._put_back(camera, client_id):
                        return  # the person orbiting, or our own write coming back: leave the view alone
                    unconfirmed = (self._written[client_id], CONFIRM_TRIES)
                written, tries = unconfirmed
                if _reports(camera, written) or tries <= 0:
                    return  # the tab shows the framed view: from now on every move is the person's
                # Not there yet: on connect viser's client applies the server's initial camera in a React effect
                # that can run after our first write, putting the tab back at the opening view. Frame it again.
                self._unconfirmed[client_id] = (written, tries - 1)
            else:
                self._framed[client_id] = size  # a new tab, or a resized window
                self._unconfirmed.pop(client_id, None)
        self._frame(camera)

    def pending(self, client_id: int) -> bool:
        """Whether a framing was written to client ``client_id`` that its camera has not reported back yet."""
        with self._lock:
            return client_id in self._unconfirmed

    def _put_back(self, camera: Any, client_id: int) -> bool:
        """Whether ``camera`` reports the opening view instead of the one last written to it (call under the lock)."""
        written = self._written.get(client_id)
        if self._opening is None or written is None:
            return False
        return _reports(camera, self._opening, strict=True) and not _reports(camera, written)

    def reframe(self) -> None:
        """Frame every camera seen so far again (for cameras of closed tabs the write is dropped by viser)."""
        with self._lock:
            cameras = list(self._cameras.values())
        for camera in cameras:
            self._frame(camera)

    def keep_in_view(self, points: NDArray[np.float64], *, clear_of_notice: bool = True) -> None:
        """Frame again every camera that no longer shows all of (N, 3) ``points`` (m) where framing would put them
        (:func:`shows`; ``clear_of_notice`` as the scene's framing is): what the scene shows has grown out of the
        view, as when a kick flies higher. A camera that still shows them keeps its pose, a person's own included."""
        with self._lock:
            cameras = list(self._cameras.values())
        for camera in cameras:
            try:
                lens = Lens(float(camera.fov), int(camera.image_width), int(camera.image_height))
                (px, py, pz), (lx, ly, lz) = (float(v) for v in camera.position), (float(v) for v in camera.look_at)
                view = View((px, py, pz), (lx, ly, lz))
            except (AttributeError, TypeError, ValueError, AssertionError):
                continue
            if (
                lens.width_px <= 0
                or lens.height_px <= 0
                or not shows(view, lens, points, clear_of_notice=clear_of_notice)
            ):
                self._frame(camera)

    def _frame(self, camera: Any) -> None:
        try:
            width, height = int(camera.image_width), int(camera.image_height)
            fov = float(camera.fov)
        except (AttributeError, TypeError, ValueError, AssertionError):
            return
        if width <= 0 or height <= 0:  # a crafted camera message: frame for a common window instead
            width, height = 1600, 1000
        view = self._view_for(Lens(fov, width, height))
        try:
            with camera.client.atomic():
                # A tab closed since: the report's write is dropped without a warning; there is nothing to frame.
                camera.up_direction = (0.0, 0.0, 1.0)
                camera.position = view.position
                camera.look_at = view.look_at
        except Exception:
            logger.exception("framing a camera failed; it keeps its view")
            return
        with self._lock:
            client_id = int(camera.client.client_id)  # on_camera read it already: a real handle
            tries = self._unconfirmed.get(client_id, (None, CONFIRM_TRIES))[1]
            position = np.asarray(view.position, dtype=np.float64)
            self._unconfirmed[client_id] = (position, tries)
            self._written[client_id] = position
        self.frames += 1


CONFIRM_TRIES = 5
"""Camera reports a tab may send after a framing without showing it before it is framed no more (stale reports
already on their way count too)."""


def _reports(camera: Any, position: NDArray[np.float64], *, strict: bool = False) -> bool:
    """Whether ``camera`` (a viser camera handle) reports ``position`` (m), to a millimetre per metre of it.

    A camera whose position cannot be read counts as reporting it, so that nothing is framed forever, unless
    ``strict``."""
    try:
        reported = np.asarray(camera.position, dtype=np.float64)
    except (AttributeError, TypeError, ValueError, AssertionError):
        return not strict
    tolerance = 1e-3 * (1.0 + float(np.linalg.norm(position)))
    return reported.shape == (3,) and bool(np.all(np.abs(reported - position) <= tolerance))
