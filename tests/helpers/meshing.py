"""Checks shared by the SDF meshing tests."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from kernels import sdf

CUBE_BOUNDS = np.array([[-1.0, -1.0, -1.0], [1.0, 1.0, 1.0]])
"""(2, 3) min and max corners (m) of the cube [−1, 1]³ that the meshing and GLSL-editor tests sample; read-only,
since every test module shares it."""
CUBE_BOUNDS.setflags(write=False)


def assert_near_surface_meshes_like_the_full_grid(
    scene: sdf.Scene, resolution: int, bounds: ArrayLike | None = None
) -> None:
    """Coarse-to-fine sampling (``sdf.mesh``'s default) gives the full grid's mesh exactly: vertices, faces, colours."""
    near = sdf.mesh(scene, resolution, bounds)
    full = sdf.mesh(scene, resolution, bounds, near_surface=False)
    for a, b in zip(near, full, strict=True):
        np.testing.assert_array_equal(a, b)
