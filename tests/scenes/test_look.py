"""What the browser is sent to draw cheaply (scenes/_look.py, scenes/_instances.py, the peloton's rider detail): the
lights without shadow maps or environment map, matte and unlit GLBs, hidden instances parked out of view, a light
rider mesh for a group and a crowd mesh for a bunch, grass that is not drawn under the road. The frames per second
these buy are measured by bench/bench_browser_fps.py."""

from __future__ import annotations

import json
import struct

import numpy as np
import pytest
import trimesh
import viser
from helpers.scenes import read_glb, scene_fixture
from helpers.wsclient import BrowserClient
from trimesh.visual.material import PBRMaterial

import app
from scenes._instances import PARKED_AT_M, park_hidden
from scenes._look import mesh_glb
from scenes.peloton.meshes import CROWD_ABOVE, LIGHT_ABOVE, rider_detail, rider_meshes, rod
from scenes.peloton.model import MAX_GROUP, POSITIONS, ROAD_HALF_WIDTH_M
from scenes.peloton.scene import ROAD_X_M, PelotonScene

scene = scene_fixture(PelotonScene)


def glb_json(glb: bytes) -> dict:
    """The JSON chunk of a GLB (glTF 2.0 binary: a 12-byte header, then the JSON chunk's length and type)."""
    magic, version, total = struct.unpack_from("<4sII", glb, 0)
    assert (magic, version, total) == (b"glTF", 2, len(glb))
    length, kind = struct.unpack_from("<I4s", glb, 12)
    assert kind == b"JSON"
    return json.loads(glb[20 : 20 + length])


def test_the_app_lights_without_shadow_maps_or_an_environment_map() -> None:
    """The kind: a default that costs more than it shows. viser's main light casts shadows in three cascades and its
    environment map is sampled by every lit pixel; in software WebGL those took a lit plane from 14 to 3.4 frames/s."""
    server = app.make_server("127.0.0.1", 0, verbose=False)
    try:
        with BrowserClient(server.get_port()) as client:
            client.wait_for_node("/fill_light")
            messages = [m for _, m in client.take_received()]
    finally:
        server.stop()
    lights = [m for m in messages if m["type"] == "EnableLightsMessage"]
    environment = [m for m in messages if m["type"] == "EnvironmentMapMessage"]
    assert lights and lights[-1]["enabled"] and not lights[-1]["cast_shadow"]
    assert environment and environment[-1]["hdri_data"] is None
    fill = [m for m in messages if m["type"] == "HemisphereLightMessage"]
    assert len(fill) == 1 and fill[0]["props"]["intensity"] > 0.0


def test_a_matte_glb_reads_back_as_written() -> None:
    mesh = trimesh.creation.icosphere(subdivisions=2)
    colours = np.random.default_rng(3).random((len(mesh.vertices), 3))
    glb = mesh_glb(mesh.vertices, mesh.faces, normals=mesh.vertex_normals, vertex_colors=colours, color=(255, 128, 0))
    back = read_glb(glb)
    np.testing.assert_allclose(back.vertices, mesh.vertices, atol=1e-6)
    np.testing.assert_array_equal(back.faces, mesh.faces)
    material = getattr(back.visual, "material", None)
    assert isinstance(material, PBRMaterial) and material.metallicFactor == 0.0
    # glTF colours are linear light: 8-bit sRGB 128 is 0.2158 (IEC 61966-2-1), 255 is 1.
    factor = glb_json(glb)["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"]
    np.testing.assert_allclose(factor, [1.0, 0.21586, 0.0, 1.0], atol=1e-4)
    assert "extensionsUsed" not in glb_json(glb)


def test_an_unlit_glb_says_so_and_keeps_its_shape() -> None:
    box = trimesh.creation.box(extents=(4.0, 2.0, 0.02))
    glb = mesh_glb(box.vertices, box.faces, color=(70, 72, 78), unlit=True)
    doc = glb_json(glb)
    assert doc["extensionsUsed"] == ["KHR_materials_unlit"]
    assert doc["materials"][0]["extensions"] == {"KHR_materials_unlit": {}}
    back = read_glb(glb)
    np.testing.assert_allclose(back.bounds, box.bounds, atol=1e-6)


@pytest.mark.parametrize("shape", [(5, 3), (5,)])
def test_park_hidden_moves_only_the_instances_of_zero_scale(shape: tuple[int, ...]) -> None:
    positions = np.arange(15, dtype=np.float64).reshape(5, 3)
    scales = np.ones(shape)
    scales[[1, 3]] = 0.0
    placed = park_hidden(positions, scales)
    assert placed.dtype == np.float32
    np.testing.assert_array_equal(placed[[0, 2, 4]], positions[[0, 2, 4]])
    np.testing.assert_array_equal(placed[[1, 3]], [PARKED_AT_M, PARKED_AT_M])
    np.testing.assert_array_equal(positions, np.arange(15).reshape(5, 3))  # the input is left alone


def test_the_peloton_sends_its_hidden_riders_out_of_every_view(server: viser.ViserServer, scene: PelotonScene) -> None:
    """The kind: an instance scaled to zero at the origin is in view, so the browser still transforms its vertices;
    with 4 riders shown of 121 instances the page drew 7.3 frames/s, 14.7 with the hidden ones parked."""
    with BrowserClient(server.get_port()) as client:
        client.wait_for_gui("Riders")
        client.set_value("Riders", 3)
        name = "/peloton/course/riders_body"

        def sent() -> np.ndarray | None:
            props = client.nodes.get(name, {}).get("props", {})
            positions, scales = props.get("batched_positions"), props.get("batched_scales")
            if positions is None or scales is None:
                return None
            shown = np.asarray(scales, dtype=np.float64).reshape(-1, 3)[:, 0] > 0
            return None if shown.sum() != 3 else np.asarray(positions, dtype=np.float64).reshape(-1, 3)

        client.wait_for(lambda: sent() is not None, what="three riders shown")
        positions = sent()
        assert positions is not None and len(positions) == MAX_GROUP
        np.testing.assert_array_equal(positions[3:], np.tile(PARKED_AT_M, (MAX_GROUP - 3, 1)))
        assert np.all(np.abs(positions[:3, 2]) < 1.0)  # the three shown ride on the road


@pytest.mark.parametrize(("detail", "coarser", "share"), [("light", "full", 1 / 3), ("crowd", "light", 1 / 2)])
def test_a_lighter_rider_is_the_same_figure_in_a_fraction_of_the_triangles(detail: str, coarser: str, share: float):
    for position in POSITIONS:
        fine, light = rider_meshes(position, coarser), rider_meshes(position, detail)
        fine_triangles = sum(len(m.faces) for m in fine.values())
        light_triangles = sum(len(m.faces) for m in light.values())
        assert light_triangles < fine_triangles * share, (position, light_triangles, fine_triangles)
        # Each part spans the same box within 3 cm (a 3-sided rod's flat side lies at half its radius, 2.3 cm in from
        # a 4.5 cm arm): the same size and pose.
        for part in fine:
            np.testing.assert_allclose(light[part].bounds, fine[part].bounds, atol=0.03, err_msg=f"{position} {part}")


@pytest.mark.parametrize("detail", ["full", "light", "crowd"])
def test_every_rider_face_faces_out_and_every_vertex_has_a_normal(detail: str) -> None:
    """The browser shades by vertex normals averaged over faces: a flat ring whose two sides shared vertices would
    average to zero (black), and a face wound inwards is culled from the side it should show."""
    for position in POSITIONS:
        for part, mesh in rider_meshes(position, detail).items():
            normals = mesh.vertex_normals
            np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-6, err_msg=f"{position} {part}")
            if part == "bike":
                continue  # a wheel's flat ring has no inside to face away from (the open rods are tested below)
            for piece in mesh.split(only_watertight=False):  # torso, arms, legs, head: each a convex solid
                outward = piece.triangles_center - piece.vertices.mean(axis=0)
                facing = np.einsum("ij,ij->i", piece.face_normals, outward)
                assert np.all(facing > 0), (position, part, detail)


def test_an_open_rod_is_a_prism_wound_outwards() -> None:
    a, b = np.array([0.1, 0.2, 0.3]), np.array([0.4, -0.1, 0.9])
    prism = rod(a, b, 0.05, 3, caps=False)
    assert len(prism.faces) == 6
    axis = (b - a) / np.linalg.norm(b - a)
    radial = prism.triangles_center - a - np.outer((prism.triangles_center - a) @ axis, axis)
    assert np.all(np.einsum("ij,ij->i", prism.face_normals, radial) > 0)
    capped = rod(a, b, 0.05, 3)
    assert capped.is_watertight and len(capped.faces) > len(prism.faces)


def test_the_grass_lies_beside_the_road_not_under_it(scene: PelotonScene) -> None:
    """Every pixel of road drawn over grass is shaded twice; in software WebGL the ground is a third of a frame."""
    grass = read_glb(scene.grass.glb_data)
    start, end = ROAD_X_M
    centre = grass.triangles_center
    across = np.abs(centre[:, 1]) < ROAD_HALF_WIDTH_M - 1e-6
    along = (centre[:, 0] > start + 1e-6) & (centre[:, 0] < end - 1e-6)
    assert not (across & along).any()
    # It still reaches the horizon either side, and lies beyond the road's ends, where a camera framing the
    # tallest bars looks down past the leader (the page's white showed there).
    assert grass.bounds[0, 1] <= -25.0 and grass.bounds[1, 1] >= 25.0
    assert grass.bounds[0, 0] <= start - 100.0 and grass.bounds[1, 0] >= end + 100.0
    beyond = across & ~along
    assert centre[beyond, 0].min() < start and centre[beyond, 0].max() > end


def test_a_group_rides_light_and_a_line_rides_full(scene: PelotonScene) -> None:
    assert rider_detail(LIGHT_ABOVE) == "full" and rider_detail(LIGHT_ABOVE + 1) == "light"
    assert rider_detail(CROWD_ABOVE) == "light" and rider_detail(CROWD_ABOVE + 1) == "crowd"
    for count, detail in ((MAX_GROUP, "crowd"), (20, "light"), (4, "full")):
        scene.controls["n_riders"].value = count
        meshes = rider_meshes(scene.params.position, detail)
        for part, node in scene.riders_nodes.items():
            assert len(node.faces) == len(meshes[part].faces), (count, part)
