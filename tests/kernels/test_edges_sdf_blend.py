"""Every blend form and boolean of kernels/sdf at tiny blend widths, in float32 and float64.

Property: for every finite k ≥ 0, subnormals included, distances are finite and lie within k/4 (plus the rounding
of the mix) of the hard operation, so they approach it as k → 0; a scene's mesh is empty only where the hard
scene's is.
"""

from __future__ import annotations

import dataclasses
import warnings
from typing import Any

import numpy as np
import pytest
from helpers.properties import examples
from hypothesis import given, settings
from hypothesis import strategies as st

from kernels import sdf

# Widths from zero through float64 and float32 subnormals to ordinary ones.
TINY_WIDTHS = [0.0, 5e-324, 1e-320, 1e-310, 2.2e-308, 1e-300, 1e-45, 1e-40, 1.2e-38, 1e-30, 1e-12]
widths = st.one_of(st.sampled_from(TINY_WIDTHS), st.floats(0.0, 1e-3), st.floats(0.0, 1.0))
distances = st.one_of(st.sampled_from([0.0, -0.0, 1e-30, -1e-30, 0.25, -0.25]), st.floats(-3.0, 3.0))

HARD = {"union": np.minimum, "subtract": lambda a, b: np.maximum(a, -b), "intersect": np.maximum}
SMOOTH = {"union": sdf.smooth_union, "subtract": sdf.smooth_subtract, "intersect": sdf.smooth_intersect}


def smooth_in_its_dtype(op: sdf.BooleanOp, x: np.ndarray, y: np.ndarray, k: float, blend: sdf.BlendForm) -> np.ndarray:
    """The smooth ``op`` of ``x`` and ``y`` as the code runs it for their dtype: the float64 functions, or the mesher's
    float32 path, whose result is asserted to stay float32 and whose weights to lie in [0, 1]."""
    if x.dtype == np.float64:
        return SMOOTH[op](x, y, k, blend)
    got, weight = sdf.combine_weighted(x, y, op, k, blend)
    assert got.dtype == np.float32 and np.all(np.isfinite(weight))
    assert np.all((weight >= 0.0) & (weight <= 1.0))
    return got


def assert_near_hard(got: np.ndarray, hard: np.ndarray, k: float, a: np.ndarray, b: np.ndarray) -> None:
    assert np.all(np.isfinite(got)), got
    rounding = 4 * np.finfo(got.dtype).eps * np.maximum(np.abs(a), np.abs(b))
    assert np.all(np.abs(got.astype(np.float64) - hard) <= k / 4 * (1 + 1e-6) + rounding)


@dataclasses.dataclass(frozen=True)
class Blend:
    """One call of a blend: two equal-length float64 arrays, a width, the boolean, the form and the dtype run in."""

    a: np.ndarray
    b: np.ndarray
    k: float
    op: sdf.BooleanOp
    blend: sdf.BlendForm
    dtype: type


@st.composite
def blends(
    draw: st.DrawFn, a: st.SearchStrategy[float], b: st.SearchStrategy[float], k: st.SearchStrategy[float], size: int
) -> Blend:
    """A :class:`Blend` of up to ``size`` values drawn from ``a`` and ``b``, a width from ``k``, and any op, form and
    dtype."""
    a_list = draw(st.lists(a, min_size=1, max_size=size))
    b_list = draw(st.lists(b, min_size=1, max_size=size))
    n = min(len(a_list), len(b_list))
    return Blend(
        np.asarray(a_list[:n], dtype=np.float64),
        np.asarray(b_list[:n], dtype=np.float64),
        draw(k),
        draw(st.sampled_from(sdf.BOOLEAN_OPS)),
        draw(st.sampled_from(sdf.BLEND_FORMS)),
        draw(st.sampled_from([np.float32, np.float64])),
    )


offsets = st.sampled_from([0.0, 1e-40, -1e-40, 1e-7, 0.3])
"""b − a in the test below."""


@given(case=blends(distances, offsets, widths, 20))
@settings(max_examples=examples(400), deadline=None)
def test_every_blend_is_finite_and_near_the_hard_operation_for_every_width(case: Blend) -> None:
    op, k, blend, dtype = case.op, case.k, case.blend, case.dtype
    # b near a (equal, one subnormal apart, a few ulps, far): the ties where 0/0 and inf·0 used to appear.
    a_arr = case.a
    b_arr = a_arr + case.b
    for x, y in ((a_arr, b_arr), (b_arr, a_arr), (a_arr, -b_arr)):
        x_t, y_t = x.astype(dtype), y.astype(dtype)
        with np.errstate(divide="raise"):  # nothing is ever divided by a width or sharpness of 0
            got = smooth_in_its_dtype(op, x_t, y_t, k, blend)
        hard = HARD[op](x_t.astype(np.float64), y_t.astype(np.float64))
        assert_near_hard(np.asarray(got), hard, k, x_t, y_t)


@given(k=st.sampled_from(TINY_WIDTHS[1:]), blend=st.sampled_from(sdf.BLEND_FORMS))
@settings(max_examples=examples(30), deadline=None)
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
        kind = draw(st.sampled_from(("sphere", "box", "torus", "capsule")))
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
@settings(max_examples=examples(25), deadline=None)
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


# ------------------------------------------------------------------------------------------------ public inputs
def two_spheres(k: float, blend: sdf.BlendForm) -> sdf.Scene:
    return sdf.Scene(
        (sdf.Primitive("sphere", (-0.5, 0.0, 0.0), (0.5,)), sdf.Primitive("sphere", (0.5, 0.0, 0.0), (0.5,))),
        k=k,
        blend=blend,
    )


@pytest.mark.parametrize(("k", "blend"), [(1e-40, "exp"), (1e-310, "poly"), (1e-310, "exp")])
def test_two_spheres_with_a_tiny_width_mesh_like_k_zero(k: float, blend: sdf.BlendForm) -> None:
    # Once: 0 faces (k = 0 gives about 4000), and scene_distance NaN at the origin for exp k = 1e-310.
    _, faces_hard, _ = sdf.mesh(two_spheres(0.0, "poly"), 33)
    _, faces, colors = sdf.mesh(two_spheres(k, blend), 33)
    assert 3900 <= len(faces_hard) <= 4100
    assert abs(len(faces) - len(faces_hard)) <= 16
    assert np.all(np.isfinite(colors))
    at_origin = float(sdf.scene_distance(two_spheres(k, blend), [[0.0, 0.0, 0.0]])[0])
    assert np.isfinite(at_origin) and -k / 4 <= at_origin <= 0.0


# ------------------------------------------------------------------------ infinite and huge distances, huge widths
# The kind: inf − inf and 0·inf inside the blends. A far point's distance overflows to inf
# (float64 past ~1e154 m, float32 past ~1e19 m), and a huge width (or a subnormal sharpness) overflowed ln 2 / k.
# Family: ±inf, ±huge and ordinary distances against widths from 0 to the largest float, every op, form and dtype.
HUGE = [np.inf, -np.inf, 1.7e308, -1.7e308, 1e300, -1e300, 3.4e38, -3.4e38, 1e30, -1e30]
extreme_distances = st.one_of(st.sampled_from(HUGE + [0.0, 0.5, -0.5]), st.floats(-3.0, 3.0))
extreme_widths = st.one_of(
    widths, st.sampled_from([1.0, 1e19, 1e30, 3.4e38, 3.5e38, 1e100, 1e300, 1.7976931348623157e308])
)


@given(case=blends(extreme_distances, extreme_distances, extreme_widths, 12))
@settings(max_examples=examples(400), deadline=None)
def test_blends_of_infinite_and_huge_distances_are_never_nan(case: Blend) -> None:
    op, k, blend, dtype = case.op, case.k, case.blend, case.dtype
    with np.errstate(over="ignore"):
        x, y = case.a.astype(dtype), case.b.astype(dtype)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        got = smooth_in_its_dtype(op, x, y, k, blend)
    hard = HARD[op](x.astype(np.float64), y.astype(np.float64))
    got64 = np.asarray(got, dtype=np.float64)
    assert not np.any(np.isnan(got64))
    infinite = ~np.isfinite(hard)
    np.testing.assert_array_equal(got64[infinite], hard[infinite])  # inf blended with anything is the hard answer
    big = float(np.finfo(dtype).max)
    # Finite where the hard answer is, unless the true blend itself (within k/4 of it) lies beyond the dtype.
    with np.errstate(over="ignore", invalid="ignore"):
        ok = np.isfinite(got64) | (np.abs(hard) + min(k, big) / 4 > big)
    assert np.all(ok[~infinite])
    fin = ~infinite & np.isfinite(got64)
    sign = 1.0 if op == "union" else -1.0
    dev = sign * (hard[fin] - got64[fin])  # ≥ 0: a union only dips, the others only rise
    rounding = 4 * np.finfo(dtype).eps * np.abs(hard[fin])
    assert np.all(dev >= -rounding) and np.all(dev <= min(k, big) / 4 * (1 + 1e-6) + rounding)


def test_an_infinite_distance_blends_to_the_other_one() -> None:
    # Once: smooth_union([inf], [1], 0.1) was NaN (the hard union gives 1).
    for blend in sdf.BLEND_FORMS:
        assert float(sdf.smooth_union([np.inf], [1.0], 0.1, blend)[0]) == 1.0
        assert float(sdf.smooth_union([np.inf], [np.inf], 0.1, blend)[0]) == np.inf
        assert float(sdf.smooth_union([np.inf], [-np.inf], 0.1, blend)[0]) == -np.inf
        assert float(sdf.smooth_intersect([np.inf], [1.0], 0.1, blend)[0]) == np.inf
        assert float(sdf.smooth_subtract([1.0], [np.inf], 0.1, blend)[0]) == 1.0


@pytest.mark.parametrize("op", sdf.BOOLEAN_OPS)
@pytest.mark.parametrize("blend", sdf.BLEND_FORMS)
def test_a_far_point_has_an_infinite_distance_and_a_colour(op: sdf.BooleanOp, blend: sdf.BlendForm) -> None:
    # Once: NaN for every op and form at [[1e200, 0, 0]] (both primitives' lengths overflow to inf).
    scene = sdf.Scene(
        (
            sdf.Primitive("sphere", (0.0, 0.0, 0.0), (0.5,), color=(1.0, 0.0, 0.0)),
            sdf.Primitive("box", (1.0, 0.0, 0.0), (0.5, 0.5, 0.5), op=op, color=(0.0, 0.0, 1.0)),
        ),
        k=0.1,
        blend=blend,
    )
    far = [[1e200, 0.0, 0.0], [1e160, 1e160, 0.0], [0.0, 0.0, 1e154]]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        d = sdf.scene_distance(scene, far)
        color = sdf.scene_color(scene, far)
    # The sphere's distance is inf at the first two (and 1e154 − 0.5 at the third); subtracting a box far away
    # leaves the sphere's, so every op gives inf there.
    assert d[0] == np.inf and d[1] == np.inf
    assert d[2] == pytest.approx(1e154, rel=1e-12)
    assert np.all(np.isfinite(color)) and np.all((color >= 0.0) & (color <= 1.0))


def test_smin_exp_with_a_subnormal_sharpness_is_finite_without_warnings() -> None:
    # Once: overflow warnings (ln 2 / 5e-324 overflows); the sharpness floors at the smallest normal.
    a = np.array([0.0, 1.0, -2.0, 0.5])
    b = np.array([0.0, 3.0, -2.0, 0.5 + 1e-16])
    for sharpness in (5e-324, 1e-320, 1e-310):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            got = sdf.smin_exp(a, b, sharpness)
        with np.errstate(over="ignore"):
            low = np.minimum(a, b) - np.log(2.0) / sharpness  # −inf: the bound says nothing at such sharpness
        assert np.all(np.isfinite(got)) and np.all((low <= got) & (got <= np.minimum(a, b)))


# ------------------------------------------------------------------------------------------------ bad arguments
@pytest.mark.parametrize("blend", ["POLY", "quadratic", None, 0])
@pytest.mark.parametrize("k", [0.0, 0.1])
def test_an_unknown_blend_form_is_a_value_error_naming_blend(blend: object, k: float) -> None:
    for fn in SMOOTH.values():
        with pytest.raises(ValueError, match="blend"):
            fn([0.0], [1.0], k, blend)  # type: ignore[arg-type]


@pytest.mark.parametrize("k", [None, [0.1], "0.1", b"0.1", True, 1j, np.array([0.1])])
def test_a_width_that_is_not_a_real_number_is_a_value_error_naming_k(k: object) -> None:
    for fn in SMOOTH.values():
        with pytest.raises(ValueError, match="k"):
            fn([0.0], [1.0], k)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="k"):
        sdf.Scene((sdf.Primitive("sphere", (0.0, 0.0, 0.0), (0.5,)),), k=k)  # type: ignore[arg-type]


# ------------------------------------------------------------------------------------------------ huge widths
def test_a_width_beyond_max_blend_width_is_refused_by_name() -> None:
    # Once: k ≥ ~1e19 gave an empty mesh (the float32 field overflowed); k = 1e30 warned too.
    for k in (np.nextafter(sdf.MAX_BLEND_WIDTH, np.inf), 1e19, 1e30, 1e300):
        with pytest.raises(ValueError, match="k"):
            two_spheres(k, "poly")


@pytest.mark.parametrize("blend", sdf.BLEND_FORMS)
@pytest.mark.parametrize("k", [1.0, 1e3, 1e6])
def test_the_widest_blends_still_mesh_closed(k: float, blend: sdf.BlendForm) -> None:
    import trimesh

    scene = two_spheres(k, blend)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        vertices, faces, colors = sdf.mesh(scene, 33)
    assert len(faces) > 0
    tri = trimesh.Trimesh(vertices, faces, process=False)
    assert tri.is_watertight and tri.euler_number == 2
    assert np.all(np.isfinite(colors))
    # The blend dips by k/4 between the spheres: the blob reaches about k/4 beyond them.
    assert float(np.abs(vertices).max()) == pytest.approx(k / 4, rel=0.5, abs=1.2)


def test_bounds_beyond_float32_reach_are_refused_by_name() -> None:
    scene = two_spheres(0.1, "poly")
    for size in (2e18, 2e19, 1e30):
        with pytest.raises(ValueError, match="bounds"):
            sdf.mesh(scene, 16, [[-size] * 3, [size] * 3])


# The kind: distances that are not real numbers. A complex distance raised float()'s TypeError, or (in an array)
# lost its imaginary part with only numpy's warning; True was blended as 1 m. Family: every public blend and boolean,
# each bad value as a and as b.
BLENDS = {
    "smin_poly": lambda a, b: sdf.smin_poly(a, b, 0.1),
    "smin_exp": lambda a, b: sdf.smin_exp(a, b, 10.0),
    "op_union": sdf.op_union,
    "op_subtract": sdf.op_subtract,
    "op_intersect": sdf.op_intersect,
    "smooth_union": lambda a, b: sdf.smooth_union(a, b, 0.1),
    "smooth_subtract": lambda a, b: sdf.smooth_subtract(a, b, 0.1, "exp"),
    "smooth_intersect": lambda a, b: sdf.smooth_intersect(a, b, 0.1),
}


@pytest.mark.parametrize("name", sorted(BLENDS))
@pytest.mark.parametrize(
    "bad", [1 + 1j, np.array([1 + 1j, 0.5]), True, np.array([True]), "0.5", None, [0.5, "a"]], ids=repr
)
@pytest.mark.parametrize("side", ["a", "b"])
def test_a_distance_that_is_not_a_real_number_is_refused_by_name(name: str, bad: object, side: str) -> None:
    a, b = (bad, 0.5) if side == "a" else (0.5, bad)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError, match=f"^{side} must be real distances"):
            BLENDS[name](a, b)


@pytest.mark.parametrize("name", sorted(BLENDS))
def test_real_distances_of_every_kind_still_blend(name: str) -> None:
    for a in (0.3, np.float32(0.3), np.int64(1), [0.3, -np.inf], np.array([[0.3], [np.inf]], dtype=np.float32)):
        result = BLENDS[name](a, 0.5)
        assert not np.isnan(result).any()


@pytest.mark.parametrize("name", ["smin_poly", "smin_exp", "smooth_union", "smooth_subtract", "smooth_intersect"])
def test_a_timedelta_width_is_refused_by_name(name: str) -> None:
    # numpy's timedelta64 is an integer type: accepted as a number, then float() raised TypeError.
    with pytest.raises(ValueError, match=r"^k must be a finite number"):
        getattr(sdf, name)(0.3, 0.5, np.timedelta64(1, "s"))


# Kind: a flag taken as a distance. numpy made [1.0, True] two distances of 1 m; None in a list a NaN.
@pytest.mark.parametrize("bad", [[1.0, True], [[0.5], [np.True_]], [1.0, None]], ids=repr)
def test_booleans_or_none_in_a_list_of_distances_are_refused_by_name(bad: Any) -> None:
    good = [0.5, 0.5]
    for call, side in [
        (lambda: sdf.smin_poly(bad, good, 0.1), "a"),
        (lambda: sdf.smin_poly(good, bad, 0.1), "b"),
        (lambda: sdf.smin_exp(bad, good, 0.1), "a"),
        (lambda: sdf.op_round(bad, 0.1), "d"),
        (lambda: sdf.op_onion(bad, 0.1), "d"),
    ]:
        with pytest.raises(ValueError, match=rf"^{side} must be real distances \(m\), got "):
            call()


# Kind: a refusal in numpy's words. smin_poly([0, 1], [0, 1, 2], 0.1) raised "operands could not be broadcast
# together", naming neither a nor b (an outside tester).
@pytest.mark.parametrize(
    "blend",
    [
        lambda a, b: sdf.smin_poly(a, b, 0.1),
        lambda a, b: sdf.smin_exp(a, b, 10.0),
        sdf.op_union,
        sdf.op_subtract,
        sdf.op_intersect,
        lambda a, b: sdf.smooth_union(a, b, 0.1, "exp"),
        lambda a, b: sdf.smooth_subtract(a, b, 0.1),
        lambda a, b: sdf.smooth_intersect(a, b, 0.1),
    ],
    ids=["smin_poly", "smin_exp", "op_union", "op_subtract", "op_intersect", "union", "subtract", "intersect"],
)
def test_distances_that_do_not_broadcast_are_refused_by_name(blend: Any) -> None:
    with pytest.raises(ValueError, match=r"a and b must broadcast together, got shapes \(2,\) and \(3,\)"):
        blend([0.0, 1.0], [0.0, 1.0, 2.0])
    assert np.asarray(blend([[0.0], [1.0]], [0.0, 1.0, 2.0])).shape == (2, 3)  # shapes that broadcast still do


def test_smin_exp_takes_the_sharpness_that_the_width_k_gives() -> None:
    # Every other blend's k is a width in metres; smin_exp's is the seed's sharpness (docs/sdf.md says both).
    a, b = np.linspace(-1.0, 1.0, 41), np.linspace(1.0, -1.0, 41)
    for k in (0.05, 0.4, 2.0):
        np.testing.assert_allclose(
            sdf.smin_exp(a, b, 4.0 * np.log(2.0) / k), sdf.smooth_union(a, b, k, "exp"), rtol=1e-12, atol=1e-15
        )
        assert sdf.smooth_union([0.0], [0.0], k, "exp")[0] == pytest.approx(-k / 4.0, rel=1e-12)
