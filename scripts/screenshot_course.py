"""Save a Chromium screenshot of the peloton scene's course mode to docs/peloton_course.png.

python scripts/screenshot_course.py

The sample route, a bunch of 30 riders sharing the work, weather air, about 40 % of the way up the climb.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import tyro

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

from helpers.browser import close_notifications, open_viser  # noqa: E402
from helpers.ci import chromium_context  # noqa: E402

from app import make_server  # noqa: E402
from scenes.peloton import PelotonScene  # noqa: E402
from server.switcher import SceneSwitcher  # noqa: E402


def main(out: Path = ROOT / "docs" / "peloton_course.png", at_km: float = 5.5, settle_s: float = 5.0) -> None:
    """Screenshot the course mode.

    Args:
        out: where the PNG goes.
        at_km: where the leader is shown (km).
        settle_s: seconds to let the page render.
    """
    from playwright.sync_api import Error as PlaywrightError

    server = make_server("127.0.0.1", 0, verbose=False)  # the app's own panel title and width
    server.gui.configure_theme(control_width="large")  # as app.py serves it
    switcher = SceneSwitcher(server, "peloton")
    scene = switcher.scene
    assert isinstance(scene, PelotonScene)
    mode = scene.course_mode
    scene.controls["formation"].value = "Bunch (peloton)"
    scene.controls["n_riders"].value = 30
    mode.enable.value = True
    mode.controls["air"].value = "Weather reading"
    mode.controls["temperature_c"].value = 24.0
    mode.controls["humidity_pct"].value = 60.0
    mode.scrub.value = at_km
    with chromium_context((1600, 1000)) as context:
        page = context.new_page()
        open_viser(page, server.get_port(), "/peloton/course_mode/route")
        close_notifications(page)
        time.sleep(settle_s)
        # Fold the line's own folders so the course mode's readouts and chart are in view.
        for folder in ("Rider", "Course", "Drafting", "Results", "Speed at a power"):
            try:
                page.get_by_text(folder, exact=True).first.click(timeout=20_000)
            except PlaywrightError:
                print(f"could not fold {folder!r}; the picture shows it open")
        chart = page.locator(".uplot", has_text="Elevation, speed and power")
        chart.first.scroll_into_view_if_needed(timeout=10_000)
        time.sleep(1.0)
        page.screenshot(path=str(out))
        print(f"saved {out}")
    switcher.close()
    server.stop()


if __name__ == "__main__":
    tyro.cli(main)
