"""viser's own notices, as a person sees them: the "Software WebGL rendering detected" toast over the scene.

Without a GPU, viser's client puts its notice over the top-left corner of the scene (at 1280×720 half the free-kick
goal) until it is closed. The browser tests close it as a person would, by its close button
(:func:`helpers.browser.close_notifications`), never by hiding it; this test looks at it first: it is on the
picture, it says what it is, and one click on its close button takes its words off the picture. The scenes frame
what they show clear of the notice (``scenes/_framing.py``), so below it lies mostly sky.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
import viser
from helpers.browser import (
    SOFTWARE_WEBGL,
    TOAST,
    VIEWPORTS,
    close_notifications,
    screenshot,
    served_scene_at,
    wait_frames,
)

pytestmark = pytest.mark.browser


@pytest.mark.parametrize("viewport", VIEWPORTS, ids=lambda v: f"{v[0]}x{v[1]}")
def test_the_software_webgl_notice_shows_over_the_scene_and_its_close_button_uncovers_it(
    server: viser.ViserServer, browser_page: Any, viewport: tuple[int, int]
) -> None:
    page = browser_page
    with served_scene_at(server, page, "freekick", "/freekick/ball", viewport):
        if not page.evaluate(SOFTWARE_WEBGL):  # a GPU: viser shows no notice, and none covers the scene
            wait_frames(page, 10)
            assert close_notifications(page) == []
            return
        toast = page.locator(TOAST, has_text="Software WebGL rendering detected")
        toast.wait_for(timeout=90_000)
        wait_frames(page, 3)
        box = toast.bounding_box()
        assert box is not None
        left, top, right, bottom = (
            round(v) for v in (box["x"], box["y"], box["x"] + box["width"], box["y"] + box["height"])
        )
        # In the top-left corner of the scene, left of the control panel, as a person sees it.
        assert left < 40 and top < 40 and right < viewport[0] / 2 and bottom < viewport[1] / 2
        with_notice = screenshot(page)[top:bottom, left:right].astype(np.int16)
        # The toast is drawn: its orange bar down the left edge and its dark text on a white card.
        assert _orange_bar(with_notice) > 0.5, "the notice's orange bar is not on the picture"
        grey_text = (with_notice.max(axis=2) < 170) & (np.ptp(with_notice, axis=2) < 30)
        assert grey_text.mean() > 0.01, "the notice's text is not on the picture"
        assert "not on your GPU" in toast.inner_text()

        titles = close_notifications(page)
        assert titles == ["Software WebGL rendering detected"]
        assert page.locator(TOAST).count() == 0
        uncovered = screenshot(page)[top:bottom, left:right].astype(np.int16)
        assert _orange_bar(uncovered) < 0.02, "the notice's bar is still on the picture after its close button"
        # Where the notice's words were, the scene now shows: the scenes frame themselves clear of the notice, so
        # what lies below is mostly sky, and the test looks at the text's pixels rather than at the whole card.
        changed = np.abs(uncovered - with_notice).max(axis=2) > 24
        assert changed[grey_text].mean() > 0.8, "closing the notice left its words on the picture"
        still_text = (uncovered.max(axis=2) < 170) & (np.ptp(uncovered, axis=2) < 30)
        assert still_text.mean() < 0.25 * grey_text.mean(), "closing the notice did not uncover the scene below it"


def _orange_bar(corner: np.ndarray) -> float:
    """Fraction of the notice's left edge (its first 12 px columns, inside its rounded ends) that is Mantine's
    orange (253, 126, 20)."""
    edge = corner[8:-8, :12]
    orange = np.abs(edge - np.array([253, 126, 20])).max(axis=2) < 40
    return float(orange.any(axis=1).mean())
