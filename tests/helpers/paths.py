"""Where things are, from the tests' point of view."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
"""The repository root (app.py, pyproject.toml)."""
DOCS = ROOT / "docs"
"""Where the README's screenshots live: the browser tests write them."""
GLSL = ROOT / "tests" / "glsl"
"""GLSL written for the tests: probe shaders and a user-registered primitive."""
