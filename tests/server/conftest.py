"""What every server test shares: the process's refusal log starts and ends each test with nothing logged.

The log writes one line per kind of refused message per 10 s, so a line an earlier test caused would otherwise
silence the one a test expects (or a test's lines would silence the next test's)."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from server.refusals import refusals


@pytest.fixture(autouse=True)
def fresh_refusal_log() -> Iterator[None]:
    refusals.reset()
    yield
    refusals.reset()
