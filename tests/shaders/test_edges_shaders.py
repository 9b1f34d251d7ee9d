"""The blends in the GLSL: shaders/sdf.glsl's blends at tiny widths, evaluated through the probe shader.

Property (the kernel's, tests/kernels/test_edges_sdf_blend.py): for every finite k ≥ 0, subnormals included (the uniform
is float32, so 1e-40 arrives subnormal and 1e-310 as 0), every blend form and boolean gives finite distances within
k/4 of the hard operation, and the colours stay finite. Needs an OpenGL context (``gl`` marker).
"""

from __future__ import annotations

import numpy as np
import pytest
from helpers.paths import GLSL
from helpers.properties import examples
from hypothesis import given, settings
from hypothesis import strategies as st

from kernels import sdf
from shaders import renderer as gl_renderer
from shaders.renderer import Renderer

TINY_WIDTHS = [0.0, 1e-310, 1e-45, 1e-40, 1.1e-38, 1.2e-38, 1e-37, 1e-30, 1e-20, 1e-12, 1e-6, 1e-3]


def probe_points(scene: sdf.Scene) -> np.ndarray:
    """Random points plus ties: the plane halfway between the first two centres and the centres themselves."""
    rng = np.random.default_rng(5)
    random = rng.uniform(-1.5, 1.5, (2000, 3))
    c0, c1 = (np.asarray(p.center) for p in scene.primitives[:2])
    normal = (c1 - c0) / np.linalg.norm(c1 - c0)
    in_plane = rng.uniform(-1.0, 1.0, (1000, 3))
    in_plane -= np.outer(in_plane @ normal, normal)
    tie = 0.5 * (c0 + c1) + in_plane
    centres = np.array([p.center for p in scene.primitives])
    return np.concatenate([random, tie, centres, [0.5 * (c0 + c1)]])


def scene_of(ops: tuple[sdf.BooleanOp, ...], k: float, blend: sdf.BlendForm) -> sdf.Scene:
    """Spheres of radius 0.5 at (±0.5, 0, 0) (the reported pair), then more primitives combined by ``ops``."""
    more = [
        sdf.Primitive("box", (0.0, 0.0, 0.3), (0.4, 0.3, 0.3)),
        sdf.Primitive("torus", (0.0, 0.0, 0.0), (0.5, 0.15)),
    ]
    prims = [
        sdf.Primitive("sphere", (-0.5, 0.0, 0.0), (0.5,)),
        sdf.Primitive("sphere", (0.5, 0.0, 0.0), (0.5,), op=ops[0]),
        *(dataclass_with_op(p, op) for p, op in zip(more, ops[1:], strict=False)),
    ]
    return sdf.Scene(tuple(prims), k=k, blend=blend)


def dataclass_with_op(primitive: sdf.Primitive, op: sdf.BooleanOp) -> sdf.Primitive:
    import dataclasses

    return dataclasses.replace(primitive, op=op)


@pytest.mark.gl
@given(
    k=st.sampled_from(TINY_WIDTHS),
    ops=st.lists(st.sampled_from(sdf.BOOLEAN_OPS), min_size=1, max_size=3).map(tuple),
    blend=st.sampled_from(sdf.BLEND_FORMS),
)
@settings(max_examples=examples(40), deadline=None)
def test_glsl_blends_are_finite_and_near_the_hard_operation_for_every_width(
    gl: Renderer, k: float, ops: tuple[sdf.BooleanOp, ...], blend: sdf.BlendForm
) -> None:
    scene = scene_of(ops, k, blend)
    hard = sdf.Scene(scene.primitives, k=0.0)
    points = probe_points(scene)
    distance, color = gl.probe(scene, points)
    assert np.all(np.isfinite(distance)) and np.all(np.isfinite(color))
    # float32 rounding of the points and the primitives (~1e-7 m) on top of the blend's dip k/4 per blend.
    slack = 3 * k / 4 + 2e-6
    np.testing.assert_allclose(distance, sdf.scene_distance(hard, points), atol=slack, rtol=0)
    np.testing.assert_allclose(distance, sdf.scene_distance(scene, points), atol=2e-6, rtol=0)


@pytest.mark.gl
@pytest.mark.parametrize(("k", "blend"), [(1e-40, "exp"), (1e-310, "poly"), (1e-310, "exp")])
def test_glsl_two_spheres_at_a_tiny_width_match_k_zero(gl: Renderer, k: float, blend: sdf.BlendForm) -> None:
    scene = scene_of(("union",), k, blend)
    distance, _ = gl.probe(scene, [[0.0, 0.0, 0.0], [0.0, 0.3, 0.0], [1.0, 0.0, 0.0]])
    assert np.all(np.isfinite(distance))
    np.testing.assert_allclose(distance, [0.0, np.hypot(0.5, 0.3) - 0.5, 0.0], atol=1e-6)


# ------------------------------------------------------------------------------------------------ the functions alone
BLEND_PROBE = GLSL / "blend_probe.frag"


def glsl_blends(gl: Renderer, inputs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(N, 4) poly and (N, 4) exp outputs of tests/glsl/blend_probe.frag at (N, 4) (a, b, k, sharpness)."""
    import moderngl

    ctx = gl.ctx
    program = ctx.program(
        vertex_shader=(gl_renderer.SHADER_DIR / "fullscreen.vert").read_text(), fragment_shader=BLEND_PROBE.read_text()
    )
    n = len(inputs)
    source = ctx.texture((n, 1), 4, inputs.astype(np.float32).tobytes(), dtype="f4")
    source.filter = (moderngl.NEAREST, moderngl.NEAREST)
    poly, expo = (ctx.texture((n, 1), 4, dtype="f4") for _ in range(2))
    fbo = ctx.framebuffer(color_attachments=[poly, expo])
    try:
        source.use(location=0)
        program["u_inputs"] = 0
        fbo.use()
        ctx.viewport = (0, 0, n, 1)
        ctx.vertex_array(program, []).render(moderngl.TRIANGLES, vertices=3)
        read = [np.frombuffer(t.read(), np.float32).reshape(n, 4).copy() for t in (poly, expo)]
    finally:
        for obj in (fbo, source, poly, expo, program):
            obj.release()
    return read[0], read[1]


@pytest.mark.gl
@given(
    k=st.one_of(st.sampled_from(TINY_WIDTHS), st.floats(0.0, 0.0010000000474974513, width=32)),
    a=st.lists(
        st.one_of(st.sampled_from([0.0, 0.25, -0.25, 1e-30]), st.floats(-2.0, 2.0, width=32)), min_size=8, max_size=8
    ),
)
@settings(max_examples=examples(30), deadline=None)
def test_glsl_blend_functions_are_finite_and_near_the_hard_ones(gl: Renderer, k: float, a: list[float]) -> None:
    a_arr = np.asarray(a, np.float32)
    # b equal to a (the tie), a float32 ulp away, and well apart; sharpness 4 ln 2 / k as float32 (inf when it
    # overflows), as a scene of width k would use.
    b_arr = np.concatenate([a_arr, np.nextafter(a_arr, np.float32(np.inf)), a_arr + np.float32(0.3)])
    a_all = np.tile(a_arr, 3)
    with np.errstate(divide="ignore", over="ignore"):
        sharpness = np.float32(sdf.EXP_SHARPNESS_PER_WIDTH) / np.float32(k)
    inputs = np.stack([a_all, b_arr, np.full_like(a_all, k), np.full_like(a_all, sharpness)], axis=1)
    poly, expo = glsl_blends(gl, inputs)
    assert np.all(np.isfinite(poly)) and np.all(np.isfinite(expo))
    x, y = a_all.astype(np.float64), b_arr.astype(np.float64)
    hard = np.stack([np.minimum(x, y), np.minimum(x, y), np.maximum(x, -y), np.maximum(x, y)], axis=1)
    slack = k / 4 * (1 + 1e-6) + 4e-7 * np.maximum(np.abs(x), np.abs(y))[:, None] + 1e-30
    assert np.all(np.abs(poly - hard) <= slack)
    assert np.all(np.abs(expo - hard) <= slack)


@pytest.mark.gl
@pytest.mark.parametrize("k", [0.0, 1e-310, 1e-40, 1.1e-38, 1.2e-38, 1e-30, 0.25])
@pytest.mark.parametrize("blend", sdf.BLEND_FORMS)
def test_glsl_and_numpy_colour_a_tie_alike_at_every_width(gl: Renderer, k: float, blend: sdf.BlendForm) -> None:
    """Two coincident spheres tie everywhere: the mesh (numpy) and the reference (GLSL) must colour them alike.

    Below MIN_BLEND_WIDTH both take the first primitive's colour, as k = 0 does; above it both mix half and half.
    """
    red = sdf.Primitive("sphere", (0.0, 0.0, 0.5), (0.45,), color=(1.0, 0.0, 0.0))
    blue = sdf.Primitive("sphere", (0.0, 0.0, 0.5), (0.45,), color=(0.0, 0.0, 1.0))
    scene = sdf.Scene((red, blue), k=k, blend=blend)
    points = np.random.default_rng(2).uniform(-1.0, 1.0, (500, 3))
    _, color = gl.probe(scene, points)
    np.testing.assert_allclose(color, sdf.scene_color(scene, points), atol=1e-5)
    expected_blue = 0.0 if k < sdf.MIN_BLEND_WIDTH else 0.5
    np.testing.assert_allclose(color[:, 2], expected_blue, atol=1e-5)


# ------------------------------------------------------------------------ infinite and huge distances, huge widths
# float32 lengths overflow to inf past ~1.8e19 m, and inf − inf or 0·inf in the blends gave NaN.
# The same family as the numpy test: ±inf, ±huge and ordinary distances, widths up to float32's largest.
FLOAT32_MAX = float(np.finfo(np.float32).max)


@pytest.mark.gl
@given(
    k=st.one_of(
        st.sampled_from([0.0, 1e-40, 1.2e-38, 0.1, 1.0, 1e19, 1e30, FLOAT32_MAX]), st.floats(0.0, 1e6, width=32)
    ),
    values=st.lists(
        st.sampled_from([np.inf, -np.inf, FLOAT32_MAX, -FLOAT32_MAX, 1e30, -1e30, 0.0, 0.5, -0.5]),
        min_size=8,
        max_size=8,
    ),
)
@settings(max_examples=examples(30), deadline=None)
def test_glsl_blends_of_infinite_and_huge_distances_are_never_nan(gl: Renderer, k: float, values: list[float]) -> None:
    v = np.asarray(values, np.float32)
    a_all, b_all = np.repeat(v, len(v)), np.tile(v, len(v))  # every pair, ties included
    with np.errstate(divide="ignore", over="ignore", under="ignore"):
        sharpness = np.float32(sdf.EXP_SHARPNESS_PER_WIDTH) / np.float32(k)
    inputs = np.stack([a_all, b_all, np.full_like(a_all, k), np.full_like(a_all, sharpness)], axis=1)
    poly, expo = glsl_blends(gl, inputs)
    assert not np.any(np.isnan(poly)) and not np.any(np.isnan(expo))
    x, y = a_all.astype(np.float64), b_all.astype(np.float64)
    hard = np.stack([np.minimum(x, y), np.minimum(x, y), np.maximum(x, -y), np.maximum(x, y)], axis=1)
    infinite = ~np.isfinite(hard)
    for got in (poly, expo):
        got64 = got.astype(np.float64)
        np.testing.assert_array_equal(got64[infinite], hard[infinite])
        fin = ~infinite & np.isfinite(got64)
        dip = min(k, FLOAT32_MAX) / 4
        # Finite wherever the true blend (within k/4 of the hard answer) fits in float32.
        with np.errstate(over="ignore"):
            fits = np.abs(hard) + dip * (1 + 1e-6) < FLOAT32_MAX * (1 - 1e-6)
        assert np.all(np.isfinite(got64)[~infinite & fits])
        slack = dip * (1 + 1e-5) + 4e-7 * np.abs(hard[fin]) + 1e-30
        assert np.all(np.abs(got64[fin] - hard[fin]) <= slack)


@pytest.mark.gl
@pytest.mark.parametrize("blend", sdf.BLEND_FORMS)
def test_glsl_scene_far_away_is_infinite_not_nan(gl: Renderer, blend: sdf.BlendForm) -> None:
    # A float32 length overflows past ~1.8e19 m: both primitives' distances are inf there.
    scene = sdf.Scene(
        (
            sdf.Primitive("sphere", (0.0, 0.0, 0.0), (0.5,)),
            sdf.Primitive("box", (1.0, 0.0, 0.0), (0.5, 0.5, 0.5), op="union"),
        ),
        k=0.1,
        blend=blend,
    )
    distance, color = gl.probe(scene, [[1e30, 0.0, 0.0], [0.0, 1e25, 1e25], [0.0, 0.0, 0.0]])
    assert not np.any(np.isnan(distance)) and np.all(np.isfinite(color))
    assert distance[0] == np.inf and distance[1] == np.inf
    assert distance[2] == pytest.approx(-0.5, abs=1e-6)
