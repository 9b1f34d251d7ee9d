"""A real browser: Chromium opens the free-kick scene, a mouse click on "Kick" flies the ball in the page."""

from __future__ import annotations

from typing import Any

import pytest
import viser
from browser import open_viser

from scenes.freekick import FreeKickScene, ball_spot
from scenes.switcher import SceneSwitcher

pytestmark = pytest.mark.browser

BALL = "/freekick/ball"
NODE = f"window.__viserMutable.nodeRefFromName[{BALL!r}]"


def test_pressing_kick_flies_the_ball_in_the_page(
    server: viser.ViserServer, browser_page: Any
) -> None:
    switcher = SceneSwitcher(server, "freekick")
    try:
        scene = switcher.scene
        assert isinstance(scene, FreeKickScene)
        page = browser_page
        open_viser(page, server.get_port(), BALL)
        spot_x = float(ball_spot(scene.params)[0])
        page.wait_for_function(
            f"() => Math.abs({NODE}.position.x - ({spot_x})) < 1e-3", timeout=20_000
        )

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
    finally:
        switcher.close()
