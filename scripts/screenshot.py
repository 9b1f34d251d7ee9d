"""Save a Chromium screenshot of each scene (or one) to docs/, as a person would see it at 1600×1000.

The browser tests write the same screenshots on every run (tests/browser.py ``save_docs_screenshot``); this script
makes them alone, with the same server settings, window size and waiting.

python scripts/screenshot.py                 # every scene → docs/<key>.png
python scripts/screenshot.py --scenes arm    # just one
"""

from __future__ import annotations

import sys
from pathlib import Path

import tyro

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

from helpers.browser import scene_page, screenshot  # noqa: E402
from helpers.ci import chromium_context  # noqa: E402

from scenes import SCENES  # noqa: E402


def main(scenes: tuple[str, ...] = (), out_dir: Path = ROOT / "docs") -> None:
    """Screenshot scenes.

    Args:
        scenes: scene keys; empty means all.
        out_dir: where the PNGs go.
    """
    keys = list(scenes) or list(SCENES)
    out_dir.mkdir(parents=True, exist_ok=True)
    with chromium_context() as context:
        for key in keys:
            with scene_page(context, key, (1600, 1000)) as shown:
                path = out_dir / f"{key}.png"
                screenshot(shown.page, path=str(path))
                print(f"saved {path}")


if __name__ == "__main__":
    tyro.cli(main)
