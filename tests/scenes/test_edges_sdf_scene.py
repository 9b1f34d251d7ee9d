"""Blend widths at their edges through the SDF gallery: a browser may send any blend width the slider accepts, tiny ones
too."""

from __future__ import annotations

import dataclasses
import io

import numpy as np
import pytest
import trimesh
import viser
from helpers.waiting import wait_until
from helpers.wsclient import BrowserClient

from kernels import sdf
from scenes.sdf_gallery import SdfGalleryScene
from server.switcher import SceneSwitcher


# The labels were "Exponential" and "Polynomial", not options: the gate refused them, so every case meshed the
# default polynomial blend, and its write-back could replace the mesh with a preview after the wait (1 in 6 runs).
@pytest.mark.parametrize(
    ("k", "blend", "form"),
    [
        (1e-40, "Smooth (exponential)", "exp"),
        (1e-310, "Smooth (polynomial)", "poly"),
        (1e-310, "Smooth (exponential)", "exp"),
    ],
)
def test_a_tiny_blend_width_from_a_browser_still_shows_the_shape(
    server: viser.ViserServer, switcher: SceneSwitcher, k: float, blend: str, form: str
) -> None:
    scene = switcher.show("sdf")
    assert isinstance(scene, SdfGalleryScene)
    with BrowserClient(server.get_port()) as client:
        client.wait_for_gui("Blend width k (m)")
        # P2 becomes a copy of P1 (a sphere of 0.45 m at (0, 0, 0.5)): the two distances tie at every sample,
        # where a tiny width used to give 0/0 and inf·0.
        client.set_value("P2 kind", "Sphere")
        client.set_value("P2 size a (m)", 0.45)
        client.drag_transform("/sdf/gizmo_2", [(0.0, 0.0, 0.5)])
        client.set_value("Blend", blend)
        client.set_value("Blend width k (m)", k)
        # The gate takes a number nearer zero than 1e-9 of its control's range as 0 (server.clean.NEGLIGIBLE): the
        # kernel's own tiny widths are tested in tests/kernels.
        wait_until(
            lambda: (
                scene.mesh_scene is not None
                and scene.mesh_scene.k == 0.0
                and scene.mesh_scene.blend == form
                and scene.mesh_scene.primitives[1]
                == dataclasses.replace(scene.mesh_scene.primitives[0], color=scene.mesh_scene.primitives[1].color)
            ),
            "the re-mesh of the tied pair at the tiny width",
        )
        assert scene.mesh_scene is not None
        hard = sdf.mesh(sdf.Scene(scene.mesh_scene.primitives, k=0.0), scene.params.resolution)
        assert len(hard[1]) > 1000
        assert abs(len(scene.mesh_faces) - len(hard[1])) <= 0.02 * len(hard[1]) + 16
        shown = trimesh.load(io.BytesIO(scene.mesh_node.glb_data), file_type="glb", force="mesh", process=False)
        assert isinstance(shown, trimesh.Trimesh) and len(shown.faces) == len(scene.mesh_faces)
        assert np.all(np.isfinite(shown.vertices))
