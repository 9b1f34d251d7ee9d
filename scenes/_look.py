"""How every scene is lit and what its surfaces are made of, chosen so a browser without a GPU keeps up.

Chromium without a GPU draws WebGL on the CPU (SwiftShader), where the cost of a frame is the cost of shading its
pixels. Measured at 1280×720 on a 2-core machine (a camera orbit, frames timed in the page; figures in
docs/performance.md): viser's default lighting (a main light casting shadows in three cascades, and an HDR
environment map that every lit pixel samples) took a screen-covering plane from 14 to 3.4 frames/s, and a lit
ground from 25 (unlit) to 14. So:

- :func:`configure_lighting`: viser's two directional lights without shadow cascades, no environment map, and a
  hemisphere light (sky above, ground below, z up) for the soft fill the environment map gave.
- Glossy materials need an environment to reflect, so every mesh the project sends as a GLB gets an explicit matte
  material (:func:`mesh_glb`; glTF's default is fully metallic, which without an environment map shades black).
- Flat ground (grass, road) is unlit (:func:`add_ground`): it looks the same from every angle anyway, and an unlit
  pixel costs a fraction of a lit one.
"""

from __future__ import annotations

import json
import struct

import numpy as np
import viser
from numpy.typing import ArrayLike

SKY_COLOUR = (255, 255, 255)
"""The hemisphere light's colour from above."""
GROUND_COLOUR = (170, 165, 155)
"""The hemisphere light's colour from below (a warm grey, as light bounced off the ground)."""
FILL_INTENSITY = 1.2
"""The hemisphere light's intensity (three.js units): faces turned from the main light stay readable."""
MATTE_ROUGHNESS = 0.7
"""Roughness of the matte material (glTF metallic-roughness, no metal)."""


def configure_lighting(scene: viser.SceneApi) -> None:
    """Light the whole server's scene as described in the module docstring (server-wide: call once)."""
    scene.configure_default_lights(enabled=True, cast_shadow=False)
    scene.configure_environment_map(hdri=None)
    scene.add_light_hemisphere(
        "/fill_light",
        sky_color=SKY_COLOUR,
        ground_color=GROUND_COLOUR,
        intensity=FILL_INTENSITY,
        position=(0.0, 0.0, 1.0),  # three.js points a hemisphere light's sky along its position: z up
    )


def srgb_to_linear(rgb: ArrayLike) -> np.ndarray:
    """8-bit sRGB colours (..., 3) as linear light in [0, 1] (the sRGB transfer curve, IEC 61966-2-1:1999), as glTF
    wants its colour factors and vertex colours."""
    c = np.asarray(rgb, dtype=np.float64) / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def mesh_glb(
    vertices: ArrayLike,
    faces: ArrayLike,
    *,
    normals: ArrayLike | None = None,
    vertex_colors: ArrayLike | None = None,
    color: tuple[int, int, int] = (255, 255, 255),
    metallic: float = 0.0,
    unlit: bool = False,
) -> bytes:
    """A one-mesh GLB (glTF 2.0 binary), written directly (trimesh's exporter gives the same file several times
    slower, and a scene may send one on every drag).

    Args:
        vertices: (V, 3) positions (m).
        faces: (F, 3) vertex indices, wound counter-clockwise seen from outside.
        normals: optional (V, 3) unit normals; without them the viewer computes smooth ones.
        vertex_colors: optional (V, 3) colours in [0, 1], sRGB-like as the kernels give them (made linear here).
        color: the material's 8-bit sRGB colour (multiplies the vertex colours).
        metallic: glTF's metallic factor in [0, 1]: 0 scatters all light diffusely (matte); more keeps a colour from
            washing out under the main light (a metal's colour lives in its highlights).
        unlit: no lighting at all (glTF's ``KHR_materials_unlit``): the colour as given, from every side.

    Returns:
        The GLB's bytes, with a lit material (roughness :data:`MATTE_ROUGHNESS`) or an unlit one.
    """
    v = np.ascontiguousarray(vertices, dtype=np.float32).reshape(-1, 3)
    indices = np.ascontiguousarray(faces, dtype=np.uint32).ravel()
    attributes: dict[str, int] = {"POSITION": 1}
    blobs = [indices.tobytes(), v.tobytes()]
    accessors: list[dict[str, object]] = [
        {"bufferView": 0, "componentType": 5125, "count": len(indices), "type": "SCALAR"},
        {
            "bufferView": 1,
            "componentType": 5126,
            "count": len(v),
            "type": "VEC3",
            "min": v.min(axis=0).tolist() if len(v) else [0.0] * 3,
            "max": v.max(axis=0).tolist() if len(v) else [0.0] * 3,
        },
    ]
    if normals is not None:
        attributes["NORMAL"] = len(accessors)
        blobs.append(np.ascontiguousarray(normals, dtype=np.float32).reshape(-1, 3).tobytes())
        accessors.append({"bufferView": len(accessors), "componentType": 5126, "count": len(v), "type": "VEC3"})
    if vertex_colors is not None:
        rgba = np.full((len(v), 4), 255, np.uint8)
        rgba[:, :3] = np.round(255 * srgb_to_linear(255 * np.clip(vertex_colors, 0.0, 1.0)))
        attributes["COLOR_0"] = len(accessors)
        blobs.append(rgba.tobytes())
        accessors.append(
            {"bufferView": len(accessors), "componentType": 5121, "normalized": True, "count": len(v), "type": "VEC4"}
        )
    views, offset = [], 0
    for i, blob in enumerate(blobs):
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(blob), "target": 34963 if i == 0 else 34962})
        offset += len(blob)  # every blob's length is a multiple of 4
    material: dict[str, object] = {
        "pbrMetallicRoughness": {
            "baseColorFactor": [*srgb_to_linear(color).tolist(), 1.0],
            "metallicFactor": float(np.clip(metallic, 0.0, 1.0)),
            "roughnessFactor": MATTE_ROUGHNESS,
        }
    }
    gltf: dict[str, object] = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": attributes, "indices": 0, "mode": 4, "material": 0}]}],
        "materials": [material],
        "buffers": [{"byteLength": offset}],
        "bufferViews": views,
        "accessors": accessors,
    }
    if unlit:
        material["extensions"] = {"KHR_materials_unlit": {}}
        gltf["extensionsUsed"] = ["KHR_materials_unlit"]
    text = json.dumps(gltf, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    body = b"".join(blobs)
    return b"".join(
        [
            struct.pack("<4sII", b"glTF", 2, 12 + 8 + len(text) + 8 + len(body)),
            struct.pack("<I4s", len(text), b"JSON"),
            text,
            struct.pack("<I4s", len(body), b"BIN\x00"),
            body,
        ]
    )


def add_ground(
    scene: viser.SceneApi,
    name: str,
    vertices: ArrayLike,
    faces: ArrayLike,
    color: tuple[int, int, int],
    *,
    visible: bool = True,
) -> viser.GlbHandle:
    """Flat ground (grass, a road) as an unlit mesh of one 8-bit sRGB ``color``; (V, 3) ``vertices`` in metres and
    (F, 3) ``faces``. Its ``glb_data`` can be replaced later with :func:`mesh_glb` (``unlit=True``)."""
    return scene.add_glb(name, mesh_glb(vertices, faces, color=color, unlit=True), visible=visible)
