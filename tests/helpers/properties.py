"""How many examples a property test draws, in the two hypothesis profiles of ``tests/conftest.py``.

``deterministic`` (the default, in and out of CI) draws each test's own count, the same examples every run.
``explore`` (``pytest --hypothesis-profile=explore``) draws fresh examples, at least :data:`EXPLORE_EXAMPLES` per test,
so one exploring run covers every property family thousands of times over.
"""

from __future__ import annotations

import os

from hypothesis import settings

EXPLORE_EXAMPLES = int(os.environ.get("EXPLORE_EXAMPLES", "2000"))
"""Examples per property test in the explore profile (the environment variable ``EXPLORE_EXAMPLES`` sets another)."""


def examples(count: int) -> int:
    """``count`` in the deterministic profile; at least the loaded profile's own count when it draws fresh ones."""
    current = settings()
    return count if current.derandomize else max(count, current.max_examples)
