"""The physics and geometry kernels: numpy and numba, no GUI. See ``docs/development.md`` for the layout."""

from pathlib import Path

from kernels._jit_cache import drop_stale_cache

drop_stale_cache(Path(__file__).parent)
