"""Save a Chromium screenshot of each scene (or one) to docs/, as a person would see it.

python scripts/screenshot.py                 # every scene → docs/<key>.png
python scripts/screenshot.py --scenes arm    # just one
"""

from __future__ import annotations

import shutil
import sys
import tempfile
import time
from pathlib import Path

import tyro
import viser

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

from browser import open_viser  # noqa: E402
from conftest import CHROMIUM, CHROMIUM_ARGS  # noqa: E402

from scenes import SCENES  # noqa: E402
from scenes.switcher import SceneSwitcher  # noqa: E402


def main(
    scenes: tuple[str, ...] = (), out_dir: Path = ROOT / "docs", settle_s: float = 4.0
) -> None:
    """Screenshot scenes.

    Args:
        scenes: scene keys; empty means all.
        out_dir: where the PNGs go.
        settle_s: seconds to let the scene render after its root node appears.
    """
    from playwright.sync_api import sync_playwright

    keys = list(scenes) or list(SCENES)
    out_dir.mkdir(parents=True, exist_ok=True)
    with sync_playwright() as playwright:
        profile = tempfile.mkdtemp(prefix="chromium-shot-")
        context = playwright.chromium.launch_persistent_context(
            profile,
            executable_path=CHROMIUM,
            headless=True,
            args=CHROMIUM_ARGS,
            viewport={"width": 1440, "height": 900},
        )
        try:
            for key in keys:
                server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
                switcher = SceneSwitcher(server, key)
                page = context.new_page()
                open_viser(page, server.get_port(), f"/{key}")
                time.sleep(settle_s)
                # The software-WebGL notice covers the top left corner; a person would close it.
                close_buttons = page.locator(".mantine-Notification-closeButton")
                for i in range(close_buttons.count()):
                    close_buttons.nth(i).click()
                time.sleep(0.5)
                path = out_dir / f"{key}.png"
                page.screenshot(path=str(path))
                print(f"saved {path}")
                page.close()
                switcher.close()
                server.stop()
        finally:
            context.close()
            shutil.rmtree(profile, ignore_errors=True)


if __name__ == "__main__":
    tyro.cli(main)
