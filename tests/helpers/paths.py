"""Where things are, from the tests' point of view."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
"""The repository root (app.py, pyproject.toml)."""
DOCS = ROOT / "docs"
"""Where the README's screenshots live (``scripts/screenshot.py`` refreshes them)."""
SCREENSHOTS = Path(os.environ.get("SCREENSHOT_DIR") or Path(tempfile.gettempdir()) / "viser-physics-scenes-screenshots")
"""Where the browser tests save each scene's picture at 1600×1000: a temporary folder, so a test run leaves the
clone as it was; ``SCREENSHOT_DIR=docs`` writes the README's screenshots from the run instead."""
GLSL = ROOT / "tests" / "glsl"
"""GLSL written for the tests: probe shaders and a user-registered primitive."""
