"""The free kick's camera views follow the kick: a flight that grows out of the picture (a harder, higher strike)
is framed again, in every view and window size, without a browser."""

from __future__ import annotations

import contextlib
import math

import numpy as np
import pytest

from scenes._framing import NOTICE_PX, PANEL_PX, Lens, View, project_points
from scenes.freekick import FreeKickScene
from scenes.freekick.model import VIEW_LABELS, ViewName, ball_spot, resample

LENSES = [Lens(math.radians(75.0), 1600, 1000), Lens(math.radians(75.0), 1280, 720)]
"""viser's opening field of view at the two window sizes the browser tests use."""

GROWN_KICKS = {
    "40 m, 40 m/s at 50°": [("distance_m", 40.0), ("speed_ms", 40.0), ("elevation_deg", 50.0)],
    "35 m at 30°, 32 m/s at 45°": [
        ("distance_m", 35.0),
        ("angle_deg", 30.0),
        ("speed_ms", 32.0),
        ("elevation_deg", 45.0),
    ],
}
"""Slider moves, in a person's order (the spot first), after which a review saw the flight run off the top of the
picture, and side-on and from the goal the dashed no-spin path too: the spot reframed the view, the strike did not."""


class _Tab:
    """A stand-in for one tab's viser camera handle: it reports what the scene last wrote to it."""

    def __init__(self, lens: Lens) -> None:
        self.client = self
        self.client_id = 11
        self.image_width, self.image_height, self.fov = lens.width_px, lens.height_px, lens.fov_rad
        self.position, self.look_at, self.up_direction = (-31.0, -4.0, 3.6), (-6.0, 0.0, 1.4), (0.0, 0.0, 1.0)

    def atomic(self) -> contextlib.AbstractContextManager[None]:
        return contextlib.nullcontext()


def _off_the_picture(freekick: FreeKickScene, tab: _Tab, lens: Lens) -> list[str]:
    """Which of the drawn flight, its no-spin path and the ball have a sample outside the free canvas (left of the
    panel, clear of the software-WebGL notice) of the camera the tab shows."""
    view = View(tab.position, tab.look_at)
    state, off = freekick.state, []
    for name, points in (
        ("flight", resample(state.flight)),
        ("no-spin path", resample(state.ghost)),
        ("ball", ball_spot(freekick.params)[None]),
    ):
        xy = project_points(view, lens, points)
        inside = (
            (xy[:, 2] > 0.0)
            & (xy[:, 0] >= 0.0)
            & (xy[:, 1] >= 0.0)
            & (xy[:, 0] <= lens.width_px - PANEL_PX)
            & (xy[:, 1] <= lens.height_px)
            & ~((xy[:, 0] < NOTICE_PX[0]) & (xy[:, 1] < NOTICE_PX[1]))
        )
        if not inside.all():
            off.append(f"{name} ({int((~inside).sum())} samples, highest at y = {xy[:, 1].min():.0f} px)")
    return off


@pytest.mark.parametrize("lens", LENSES, ids=lambda lens: f"{lens.width_px}x{lens.height_px}")
@pytest.mark.parametrize("view", list(VIEW_LABELS))
@pytest.mark.parametrize("kick", list(GROWN_KICKS))
def test_every_view_keeps_a_grown_flight_and_its_no_spin_path_in_the_picture(
    freekick: FreeKickScene, kick: str, view: ViewName, lens: Lens
) -> None:
    tab = _Tab(lens)
    freekick.framing.on_camera(tab)  # the tab opens and is framed
    freekick.controls["view"].value = VIEW_LABELS[view]
    assert freekick.params.view == view and not _off_the_picture(freekick, tab, lens)
    for name, value in GROWN_KICKS[kick]:
        freekick.controls[name].value = value
        assert getattr(freekick.params, name) == value
        assert not _off_the_picture(freekick, tab, lens), (kick, view, name, value)


def test_a_kick_that_still_fits_leaves_the_persons_view_alone(freekick: FreeKickScene) -> None:
    """Only a flight that leaves the picture moves the camera: a person's orbit survives a small change."""
    lens = LENSES[0]
    tab = _Tab(lens)
    freekick.framing.on_camera(tab)
    freekick.framing.on_camera(tab)  # the framed view reported back: from now on moves are the person's
    eye, centre = np.asarray(tab.position), np.asarray(tab.look_at)
    tab.position = tuple(centre + 1.3 * (eye - centre))  # the person zooms out a little
    orbited, frames = tab.position, freekick.framing.frames
    freekick.controls["spin_rev_s"].value = 8.5
    assert freekick.framing.frames == frames and tab.position == orbited
