"""Issue 8, item 5: every blend form and boolean of kernels/sdf.py at tiny blend widths, in float32 and float64.

Property: for every finite k ≥ 0, subnormals included, distances are finite and lie within k/4 (plus the rounding
of the mix) of the hard operation, so they approach it as k → 0; a scene's mesh is empty only where the hard
scene's is.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from kernels import sdf

# Widths from zero through float64 and float32 subnormals to ordinary ones.
TINY_WIDTHS = [0.0, 5e-324, 1e-320, 1e-310, 2.2e-308, 1e-300, 1e-45, 1e-40, 1.2e-38, 1e-30, 1e-12]
widths = st.one_of(st.sampled_from(TINY_WIDTHS), st.floats(0.0, 1e-3), st.floats(0.0, 1.0))
distances = st.one_of(
    st.sampled_from([0.0, -0.0, 1e-30, -1e-30, 0.25, -0.25]), st.floats(-3.0, 3.0)
)

HARD = {
    "union": np.minimum,
    "subtract": lambda a, b: np.maximum(a, -b),
    "intersect": np.maximum,
}
SMOOTH = {
    "union": sdf.smooth_union,
    "subtract": sdf.smooth_subtract,
    "intersect": sdf.smooth_intersect,
}


def assert_near_hard(
    got: np.ndarray, hard: np.ndarray, k: float, a: np.ndarray, b: np.ndarray
) -> None:
    assert np.all(np.isfinite(got)), got
    rounding = 4 * np.finfo(got.dtype).eps * np.maximum(np.abs(a), np.abs(b))
    assert np.all(np.abs(got.astype(np.float64) - hard) <= k / 4 * (1 + 1e-6) + rounding)


@given(
    a=st.lists(distances, min_size=1, max_size=20),
    b_offset=st.lists(st.sampled_from([0.0, 1e-40, -1e-40, 1e-7, 0.3]), min_size=1, max_size=20),
    k=widths,
    op=st.sampled_from(sdf.BOOLEAN_OPS),
    blend=st.sampled_from(sdf.BLEND_FORMS),
    dtype=st.sampled_from([np.float32, np.float64]),
)
@settings(max_examples=400, deadline=None)
def test_every_blend_is_finite_and_near_the_hard_operation_for_every_width(
    a: list[float],
    b_offset: list[float],
    k: float,
    op: sdf.BooleanOp,
    blend: sdf.BlendForm,
    dtype: type,
) -> None:
    n = min(len(a), len(b_offset))
    # b near a (equal, one subnormal apart, a few ulps, far): the ties where 0/0 and inf·0 used to appear.
    a_arr = np.asarray(a[:n], dtype=np.float64)
    b_arr = a_arr + np.asarray(b_offset[:n])
    for x, y in ((a_arr, b_arr), (b_arr, a_arr), (a_arr, -b_arr)):
        x_t, y_t = x.astype(dtype), y.astype(dtype)
        with np.errstate(divide="raise"):  # nothing is ever divided by a width or sharpness of 0
            if dtype is np.float64:
                got = SMOOTH[op](x_t, y_t, k, blend)
            else:  # the mesher's float32 path
                got, weight = sdf._combine(x_t, y_t, op, k, blend)
                assert got.dtype == np.float32 and np.all(np.isfinite(weight))
                assert np.all((weight >= 0.0) & (weight <= 1.0))
        hard = HARD[op](x_t.astype(np.float64), y_t.astype(np.float64))
        assert_near_hard(np.asarray(got), hard, k, x_t, y_t)


@given(k=st.sampled_from(TINY_WIDTHS[1:]), blend=st.sampled_from(sdf.BLEND_FORMS))
@settings(max_examples=30, deadline=None)
def test_smin_forms_tend_to_min_at_ties(k: float, blend: sdf.BlendForm) -> None:
    a = np.array([0.0, 1.0, -2.0, 1e-300])
    if blend == "poly":
        got = sdf.smin_poly(a, a, k)
    else:  # smin_exp takes a sharpness; a scene's width k is sharpness 4 ln 2 / k, possibly beyond float64
        got = sdf.smin_exp(a, a, min(sdf.EXP_SHARPNESS_PER_WIDTH / k, 1.7e308))
    assert np.all(np.isfinite(got))
    assert np.all(a - k / 4 * (1 + 1e-9) - 1e-300 <= got) and np.all(got <= a)


def test_exp_blend_with_huge_finite_sharpness_is_the_minimum() -> None:
    with np.errstate(divide="raise"):
        got = sdf.smin_exp([0.0, 1.0, 0.5], [0.0, 2.0, 0.5 + 1e-16], 1.7e308)
    np.testing.assert_allclose(got, [0.0, 1.0, 0.5], atol=1e-300)


# ------------------------------------------------------------------------------------------------ scenes and meshes
@st.composite
def scenes_with_tiny_width(draw: st.DrawFn) -> tuple[sdf.Scene, sdf.Scene]:
    """A random two-to-four-primitive scene with a tiny k, and the same scene hard."""
    prims = []
    for _ in range(draw(st.integers(2, 4))):
        kind = draw(st.sampled_from(sdf.PRIMITIVE_KINDS))
        size = {
            "sphere": (draw(st.floats(0.2, 0.6)),),
            "box": tuple(draw(st.floats(0.2, 0.5)) for _ in range(3)),
            "torus": (draw(st.floats(0.3, 0.6)), draw(st.floats(0.1, 0.25))),
            "capsule": (draw(st.floats(0.1, 0.5)), draw(st.floats(0.1, 0.3))),
        }[kind]
        center = tuple(draw(st.sampled_from([-0.5, -0.25, 0.0, 0.25, 0.5])) for _ in range(3))
        op = draw(st.sampled_from(sdf.BOOLEAN_OPS))
        prims.append(sdf.Primitive(kind, center, size, op=op))  # type: ignore[arg-type]
    k = draw(st.sampled_from(TINY_WIDTHS[1:]))
    blend = draw(st.sampled_from(sdf.BLEND_FORMS))
    return sdf.Scene(tuple(prims), k=k, blend=blend), sdf.Scene(tuple(prims), k=0.0)


@given(pair=scenes_with_tiny_width())
@settings(max_examples=25, deadline=None)
def test_a_tiny_width_meshes_like_the_hard_scene(pair: tuple[sdf.Scene, sdf.Scene]) -> None:
    tiny, hard = pair
    bounds = sdf.scene_bounds(hard)
    points = np.random.default_rng(1).uniform(bounds[0], bounds[1], (4000, 3))
    d_tiny, d_hard = sdf.scene_distance(tiny, points), sdf.scene_distance(hard, points)
    assert np.all(np.isfinite(d_tiny))
    np.testing.assert_allclose(d_tiny, d_hard, atol=1e-12)
    _, faces_tiny, colors = sdf.mesh(tiny, 24, bounds)
    _, faces_hard, _ = sdf.mesh(hard, 24, bounds)
    assert (len(faces_tiny) == 0) == (len(faces_hard) == 0)
    # Only a sample exactly at a tie can flip (−k/4 instead of 0): a few faces at most.
    assert abs(len(faces_tiny) - len(faces_hard)) <= 0.02 * len(faces_hard) + 16
    assert np.all(np.isfinite(colors))


# ------------------------------------------------------------------------------------------------ the inputs
def two_spheres(k: float, blend: sdf.BlendForm) -> sdf.Scene:
    return sdf.Scene(
        (
            sdf.Primitive("sphere", (-0.5, 0.0, 0.0), (0.5,)),
            sdf.Primitive("sphere", (0.5, 0.0, 0.0), (0.5,)),
        ),
        k=k,
        blend=blend,
    )


@pytest.mark.parametrize(("k", "blend"), [(1e-40, "exp"), (1e-310, "poly"), (1e-310, "exp")])
def test_two_spheres_with_a_tiny_width_mesh_like_k_zero(k: float, blend: sdf.BlendForm) -> None:
    # Issue 8: 0 faces (k = 0 gives about 4000), and scene_distance NaN at the origin for exp k = 1e-310.
    _, faces_hard, _ = sdf.mesh(two_spheres(0.0, "poly"), 33)
    _, faces, colors = sdf.mesh(two_spheres(k, blend), 33)
    assert 3900 <= len(faces_hard) <= 4100
    assert abs(len(faces) - len(faces_hard)) <= 16
    assert np.all(np.isfinite(colors))
    at_origin = float(sdf.scene_distance(two_spheres(k, blend), [[0.0, 0.0, 0.0]])[0])
    assert np.isfinite(at_origin) and -k / 4 <= at_origin <= 0.0
