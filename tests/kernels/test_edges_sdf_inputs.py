"""Every public function of ``kernels.sdf`` and ``shaders`` refuses a bad argument with a ``ValueError`` that names
it ("<name> must be ..."), or defines the case: never a numpy or Python TypeError, AttributeError or OverflowError,
a silent NaN or inf, or a message naming another argument.

Each family below is one kind of fault an outside review found, tested over the whole family of bad values; the
value it was found with is in the family.
"""

from __future__ import annotations

import dataclasses
import decimal
import math
import re
from decimal import Decimal
from typing import Any

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from kernels import sdf
from shaders.camera import Camera, Shading, camera_rays, check_image_size, screen_rectangle
from shaders.glsl_sandbox import check_field_bounds

P = np.array([[0.0, 0.0, 0.0], [0.3, -0.2, 0.5], [2.0, 1.0, -1.0]])
SPHERE = sdf.Primitive("sphere", (0.0, 0.0, 0.0), (0.5,))
SCENE = sdf.Scene((SPHERE,))

# Not a real number: each must be refused by name wherever a number, a distance or a coordinate is wanted.
NOT_REAL: list[Any] = [None, "1", True, object(), 1 + 2j, 10**400, Decimal(1)]
NOT_FINITE: list[Any] = [math.nan, math.inf, -math.inf]
BAD_NUMBERS = NOT_REAL + NOT_FINITE
# Not an integer: each must be refused where a count is wanted (the last ones are numbers, but not whole).
BAD_INTEGERS = [*BAD_NUMBERS, 1.5, 16.0, np.float64(32.0), np.array([32]), np.timedelta64(32, "s")]
NOT_A_FLAG: list[Any] = [None, "yes", 1, 0, 1.0, math.nan, np.array([True]), object()]
NOT_A_CHOICE: list[Any] = [None, 0, 1.5, object(), np.array(["union"]), np.array(["sphere", "box"]), "UNION"]
NOT_A_SCENE: list[Any] = [None, 0, "scene", object(), SPHERE, (SPHERE,), np.zeros(3)]


def ids(value: object) -> str:
    """A test id the same in every process: an object's repr holds its address, which pytest-xdist's workers must
    agree on, so it is left out."""
    text = re.sub(r" at 0x[0-9a-f]+", "", repr(value))
    return type(value).__name__ + ":" + text[:30]


def vector_family(size: int) -> list[Any]:
    """Bad (size,) vectors: not real numbers, not finite, wrong shapes."""
    good = [0.0] * size
    bad_elements = [[v, *good[1:]] for v in [None, "1", object(), 1 + 2j, 10**400, math.nan, math.inf, -math.inf]]
    return [None, "1", True, object(), 1.0, [True] * size, *bad_elements, good[:-1], [good], [*good, 0.0]]


# ------------------------------------------------------------------------ 1. quaternions: the name and the norm
@pytest.mark.parametrize("bad", [*vector_family(4), (0.0, 0.0, 0.0, 0.0)], ids=ids)
def test_a_bad_quaternion_is_refused_naming_wxyz_or_rotation(bad: Any) -> None:
    # Once: rotation_matrix said "rotation must be ..." for its argument wxyz, "got 1.0" for "1" and "got nan" for
    # None; Primitive(rotation=object() / complex / bigint) raised TypeError or OverflowError.
    with pytest.raises(ValueError, match=r"^wxyz must"):
        sdf.rotation_matrix(bad)
    with pytest.raises(ValueError, match=r"^rotation must"):
        sdf.Primitive("sphere", (0.0, 0.0, 0.0), (0.5,), rotation=bad)


@pytest.mark.parametrize("scale", [1e300, 1.7e308, 1e-300, 5e-324, 1.0])
def test_a_huge_or_tiny_quaternion_is_normalised_not_refused(scale: float) -> None:
    # Once: Primitive(rotation=(1e300, 0, 0, 0)) said "must be a non-zero quaternion": its norm overflowed to inf.
    np.testing.assert_allclose(sdf.rotation_matrix((scale, 0.0, 0.0, 0.0)), np.eye(3), atol=0.0)
    quarter = sdf.rotation_matrix((scale, 0.0, 0.0, scale))  # a quarter turn about z
    np.testing.assert_allclose(quarter, [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]], atol=1e-15)
    prim = sdf.Primitive("box", (0.0, 0.0, 0.0), (0.1, 0.2, 0.3), rotation=(scale, 0.0, 0.0, scale))
    np.testing.assert_allclose(prim.rotation, (math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5)), rtol=1e-15)


# ------------------------------------------------------------------------ 2. distances given to the operators
@pytest.mark.parametrize("bad", [None, "1", True, object(), 1 + 2j, 10**400, math.nan, [0.5, None]], ids=ids)
def test_round_and_onion_refuse_a_distance_that_is_not_real_naming_d(bad: Any) -> None:
    # Once: d=None gave NaN, "1" and True were taken as 1 m, object/complex/bigint raised TypeError/OverflowError.
    with pytest.raises(ValueError, match=r"^d must"):
        sdf.op_round(bad, 0.1)
    with pytest.raises(ValueError, match=r"^d must"):
        sdf.op_onion(bad, 0.1)


@pytest.mark.parametrize("bad", [*BAD_NUMBERS, -0.1, 1e300], ids=ids)
def test_round_and_onion_refuse_a_bad_width_by_name(bad: Any) -> None:
    with pytest.raises(ValueError, match=r"^radius must"):
        sdf.op_round([0.5], bad)
    with pytest.raises(ValueError, match=r"^thickness must"):
        sdf.op_onion([0.5], bad)


def test_round_and_onion_of_an_infinite_distance_are_defined() -> None:
    # Documented: ±inf is a distance (a point too far for float64), never NaN.
    np.testing.assert_array_equal(sdf.op_round([-np.inf, np.inf, 1.0], 0.25), [-np.inf, np.inf, 0.75])
    np.testing.assert_array_equal(sdf.op_onion([-np.inf, np.inf, -1.0], 0.25), [np.inf, np.inf, 0.75])


@pytest.mark.parametrize("k", [0.0, 0.1, 1e6])
@pytest.mark.parametrize("blend", sdf.BLEND_FORMS)
def test_booleans_with_an_infinite_distance_give_the_hard_answer(k: float, blend: sdf.BlendForm) -> None:
    # Reported as NaN: smin_poly / smooth_union / op_union with −inf, smooth_subtract / op_intersect with +inf.
    # Documented: infinite distances are defined (not refused), as min and max define them.
    inf = np.inf
    for a, b in ((-inf, 1.0), (1.0, -inf), (-inf, inf), (-inf, -inf)):
        assert sdf.smooth_union([a], [b], k, blend)[0] == -inf
        assert sdf.op_union(a, b) == -inf
        assert sdf.smin_poly(a, b, k) == -inf
        assert sdf.smin_exp(a, b, max(k, 1e-3)) == -inf
    for a, b in ((inf, 1.0), (1.0, inf), (inf, -inf), (inf, inf)):
        assert sdf.smooth_intersect([a], [b], k, blend)[0] == inf
        assert sdf.op_intersect(a, b) == inf
    # a − b = max(a, −b): +inf minus anything, or anything minus −inf, is +inf; minus +inf leaves a.
    assert sdf.smooth_subtract([inf], [1.0], k, blend)[0] == inf
    assert sdf.smooth_subtract([1.0], [-inf], k, blend)[0] == inf
    assert sdf.smooth_subtract([0.5], [inf], k, blend)[0] == 0.5
    assert sdf.op_subtract(inf, 1.0) == inf and sdf.op_subtract(0.5, inf) == 0.5


# ------------------------------------------------------------------------ 3. huge but finite geometry
HUGE = [1e151, 1e300, 1.7e308, -1e300]


@pytest.mark.parametrize("huge", HUGE)
def test_a_primitive_beyond_max_coordinate_is_refused_naming_the_field(huge: float) -> None:
    # Once: a sphere at (1e300, 0, 0) had the distance [inf] everywhere.
    with pytest.raises(ValueError, match=r"^center must"):
        sdf.Primitive("sphere", (huge, 0.0, 0.0), (0.5,))
    for kind in sdf.primitive_kinds():
        count = sdf.primitive_spec(kind).size_count
        with pytest.raises(ValueError, match=r"^size must"):
            sdf.Primitive(kind, (0.0, 0.0, 0.0), (abs(huge),) * count)  # type: ignore[arg-type]


def test_a_primitive_at_max_coordinate_has_finite_distances() -> None:
    bound = sdf.MAX_COORDINATE
    for kind in sdf.primitive_kinds():
        count = sdf.primitive_spec(kind).size_count
        for center, size in (((bound, -bound, bound), (0.5,) * count), ((0.0, 0.0, 0.0), (bound,) * count)):
            scene = sdf.Scene((sdf.Primitive(kind, center, size, rotation=(1.0, 0.2, 0.3, 0.4)),))  # type: ignore[arg-type]
            with np.errstate(all="raise"):
                d = sdf.scene_distance(scene, [[0.0, 0.0, 0.0], [bound, bound, -bound]])
            assert np.all(np.isfinite(d)), (kind, center, size, d)


@pytest.mark.parametrize("blend", ["poly", "exp"])
@pytest.mark.parametrize("op", ["union", "subtract", "intersect"])
@pytest.mark.parametrize("kind", sdf.BUILT_IN_KINDS)
def test_a_point_beyond_max_coordinate_is_infinitely_far_never_nan(kind: str, op: str, blend: str) -> None:
    # Once: an octahedron's or a cone's distance at (1.7e308, −1.7e308, 1.7e308) was NaN (inf − inf), and its
    # colour NaN. A point that far lies outside every primitive: its distance is +inf (or exact, while finite).
    count = sdf.primitive_spec(kind).size_count
    first = sdf.Primitive(kind, (0.1, 0.2, 0.3), (0.3,) * count, rotation=(0.9, 0.1, 0.3, 0.2))  # type: ignore[arg-type]
    second = sdf.Primitive(kind, (0.2, 0.1, 0.3), (0.4,) * count, op=op)  # type: ignore[arg-type]
    scene = sdf.Scene((first, second), k=0.2, blend=blend)  # type: ignore[arg-type]
    points = [[1e155, 0.0, 0.0], [0.0, 1e160, -1e160], [1e300, 1e300, 0.0], [1.7e308, -1.7e308, 1.7e308]]
    with np.errstate(over="raise", invalid="raise", divide="raise"):  # an exp blend's weights may underflow to 0
        d, colour = sdf.scene_distance(scene, points), sdf.scene_color(scene, points)
    assert np.all((d == np.inf) | ((d > 0.99e155) & np.isfinite(d))), d
    assert np.all(np.isfinite(colour)) and np.all((0.0 <= colour) & (colour <= 1.0)), colour


# (function, keyword arguments that work, the arguments a huge value is tried in)
PRIMITIVE_CALLS: list[tuple[Any, dict[str, Any], list[str]]] = [
    (sdf.sd_sphere, {"radius": 0.5}, ["radius"]),
    (sdf.sd_box, {"half_size": [0.5, 0.4, 0.3]}, ["half_size"]),
    (sdf.sd_torus, {"major_radius": 0.5, "minor_radius": 0.1}, ["major_radius", "minor_radius"]),
    (sdf.sd_capsule, {"a": [0.0, 0.0, 0.0], "b": [0.0, 1.0, 0.0], "radius": 0.2}, ["a", "b", "radius"]),
    (sdf.sd_cylinder, {"half_height": 0.5, "radius": 0.2}, ["half_height", "radius"]),
    (sdf.sd_round_box, {"half_size": [0.5, 0.4, 0.3], "radius": 0.1}, ["half_size"]),
    (sdf.sd_octahedron, {"size": 0.5}, ["size"]),
    (sdf.sd_cone, {"radius": 0.3, "height": 1.0}, ["radius", "height"]),
    (sdf.sd_hex_prism, {"apothem": 0.3, "half_height": 0.5}, ["apothem", "half_height"]),
    (sdf.sd_ellipsoid, {"radii": [0.5, 0.4, 0.3]}, ["radii"]),
    (sdf.sd_ellipsoid_lipschitz, {"radii": [0.5, 0.4, 0.3]}, ["radii"]),
    (sdf.sd_plane, {"normal": [0.0, 0.0, 1.0], "offset": 0.1}, ["offset"]),
]


def _huge_like(value: Any, huge: float) -> Any:
    return [huge] * len(value) if isinstance(value, list) else abs(huge)


@pytest.mark.parametrize("huge", HUGE)
@pytest.mark.parametrize("call", PRIMITIVE_CALLS, ids=lambda c: c[0].__name__)
def test_huge_geometry_and_points_are_refused_by_name_in_every_primitive(call: Any, huge: float) -> None:
    # Once: sd_capsule(P, a=[1e300]*3, ...) was NaN and sd_cone(P, 0.3, 1e300) not finite.
    fn, kwargs, names = call
    for name in names:
        with pytest.raises(ValueError, match=rf"^{name} must"):
            fn(P, **{**kwargs, name: _huge_like(kwargs[name], huge)})
    with pytest.raises(ValueError, match=r"^p must"):
        fn([[huge, 0.0, 0.0]], **kwargs)


@pytest.mark.parametrize("call", PRIMITIVE_CALLS, ids=lambda c: c[0].__name__)
def test_geometry_at_max_coordinate_gives_finite_distances(call: Any) -> None:
    fn, kwargs, names = call
    bound = sdf.MAX_COORDINATE
    far = np.array([[bound, -bound, bound], [0.0, 0.0, 0.0], [-bound, 0.0, 1.0]])
    for name in names:
        args = {**kwargs, name: _huge_like(kwargs[name], bound)}
        if fn is sdf.sd_round_box:
            args["radius"] = 0.1
        with np.errstate(over="raise", invalid="raise"):
            d = fn(far, **args)
        assert np.all(np.isfinite(d)), (fn.__name__, name, d)


@pytest.mark.parametrize("tiny", [1e-150, 1e-300, 5e-324])
@pytest.mark.parametrize("call", PRIMITIVE_CALLS, ids=lambda c: c[0].__name__)
def test_the_smallest_geometry_gives_finite_distances_or_is_refused_by_name(call: Any, tiny: float) -> None:
    # Once: an ellipsoid with a semi-axis under 1e-154 m gave NaN (p/r² overflowed), and a cone with a radius under
    # 1e-292 m warned of an overflow. An ellipsoid's semi-axes are now at least 1e-150 m (MIN_SEMI_AXIS), so that
    # any point allowed over any semi-axis stays finite; every other size may be any positive float.
    fn, kwargs, names = call
    bound = sdf.MAX_COORDINATE
    points = np.array(
        [[bound, -bound, bound], [0.0, 0.0, 0.0], [-bound, 0.0, 1.0], [1.0, 1.0, 1.0], [0.0, 1e-300, 0.0]]
    )
    for name in names:
        if (fn is sdf.sd_capsule and name in ("a", "b")) or fn is sdf.sd_plane or fn is sdf.sd_round_box:
            continue  # a point, not a size; the plane's offset may be 0; the round box's rounding is below its size
        args = {**kwargs, name: [tiny] * len(kwargs[name]) if isinstance(kwargs[name], list) else tiny}
        if fn in (sdf.sd_ellipsoid, sdf.sd_ellipsoid_lipschitz) and tiny < sdf.MIN_SEMI_AXIS:
            with pytest.raises(ValueError, match=r"^radii must each be at least 1e-150 m, got"):
                fn(points, **args)
            continue
        with np.errstate(over="raise", invalid="raise", divide="raise"):
            d = fn(points, **args)
        assert np.all(np.isfinite(d)), (fn.__name__, name, d)
        assert d[0] == pytest.approx(math.sqrt(3.0) * bound, rel=1e-6), (fn.__name__, name, d)  # far from a speck


@given(
    radii=st.tuples(*[st.floats(math.log(1e-150), math.log(1e150)).map(math.exp)] * 3),
    point=st.tuples(*[st.floats(-1.0, 1.0)] * 3),
    log_scale=st.floats(math.log(1e-300), math.log(1e150)),
)
def test_the_ellipsoid_estimate_is_quilezs_formula_at_any_scale(radii, point, log_scale) -> None:
    # k0·(k0 − 1)/k1 with k0 = |p/r|, k1 = |p/r²| (Quilez 2008), worked in 60-digit decimals as the reference.
    p = np.array(point) * math.exp(log_scale)
    if not p.any():
        return
    with decimal.localcontext() as context:
        context.prec = 60
        pd, rd = [Decimal(float(c)) for c in p], [Decimal(r) for r in radii]
        k0 = sum(((a / b) ** 2 for a, b in zip(pd, rd, strict=True)), Decimal(0)).sqrt()
        k1 = sum(((a / b / b) ** 2 for a, b in zip(pd, rd, strict=True)), Decimal(0)).sqrt()
        expected = float(k0 * (k0 - 1) / k1)
    with np.errstate(over="raise", invalid="raise", divide="raise"):
        got = sdf.sd_ellipsoid(p[None], radii)[0]
    # Rounding of k0 near the surface (k0 − 1 cancels) is worth about an ulp of the point's distance.
    assert got == pytest.approx(expected, rel=1e-9, abs=1e-12 * (np.linalg.norm(p) + min(radii)))


def test_a_huge_plane_normal_is_normalised() -> None:
    np.testing.assert_allclose(sdf.sd_plane(P, [0.0, 0.0, 1e300], 0.1), P[:, 2] + 0.1)
    np.testing.assert_allclose(sdf.sd_plane(P, [0.0, 0.0, 1e-320], 0.1), P[:, 2] + 0.1)
    with pytest.raises(ValueError, match=r"^normal must"):
        sdf.sd_plane(P, [0.0, 0.0, 0.0], 0.1)


@pytest.mark.parametrize("huge", HUGE)
def test_huge_operator_arguments_are_refused_by_name(huge: float) -> None:
    with pytest.raises(ValueError, match=r"^half_length must"):
        sdf.op_elongate(P, [abs(huge)] * 3)
    for op in (sdf.op_twist, sdf.op_bend):
        with pytest.raises(ValueError, match=r"^rate must"):
            op(P, huge)
    with pytest.raises(ValueError, match=r"^spacing must"):
        sdf.op_repeat_finite(P, [abs(huge)] * 3, [1.0, 1.0, 1.0])
    with pytest.raises(ValueError, match=r"^limit must"):
        sdf.op_repeat_finite(P, [1.0, 1.0, 1.0], [abs(huge)] * 3)
    point_maps: list[tuple[Any, tuple[Any, ...]]] = [
        (sdf.op_elongate, ([0.1] * 3,)),
        (sdf.op_twist, (1.0,)),
        (sdf.op_bend, (1.0,)),
        (sdf.op_repeat_finite, ([1.0] * 3, [1.0] * 3)),
        (sdf.op_symmetry, ([1.0, 0.0, 1.0],)),
    ]
    for op, args in point_maps:
        with pytest.raises(ValueError, match=r"^p must"):
            op([[huge, 0.0, 0.0]], *args)


def test_operators_at_their_bounds_stay_finite() -> None:
    bound = sdf.MAX_COORDINATE
    far = np.array([[bound, -bound, bound], [0.0, 1.0, 0.0]])
    with np.errstate(over="raise", invalid="raise"):
        assert np.all(np.isfinite(sdf.op_twist(far, sdf.MAX_RATE)))
        assert np.all(np.isfinite(sdf.op_bend(far, -sdf.MAX_RATE)))
        assert np.all(np.isfinite(sdf.op_repeat_finite(far, [bound] * 3, [bound] * 3)))
        assert np.all(np.isfinite(sdf.op_elongate(far, [bound] * 3)[0]))


# ------------------------------------------------------------------------ 4. a scene that is not a Scene
@pytest.mark.parametrize("bad", NOT_A_SCENE, ids=ids)
def test_a_scene_that_is_not_a_scene_is_refused_naming_scene(bad: Any) -> None:
    # Once: AttributeError ('NoneType' object has no attribute 'primitives').
    x = np.zeros(2)
    calls = [
        lambda: sdf.scene_distance(bad, P),
        lambda: sdf.scene_color(bad, P),
        lambda: sdf.scene_bounds(bad),
        lambda: sdf.scene_bounding_spheres(bad),
        lambda: sdf.fold_xyz(bad, x, x, x, False),
        lambda: sdf.mesh(bad, 16),
        lambda: sdf.make_grid(bad, 16),
        lambda: sdf.sphere_trace(bad, [[0.0, 0.0, 5.0]], [[0.0, 0.0, -1.0]]),
        lambda: sdf.sample_full(bad, sdf.make_grid(SCENE, 16)),
        lambda: sdf.sample_near_surface(bad, sdf.make_grid(SCENE, 16)),
    ]
    for call in calls:
        with pytest.raises(ValueError, match=r"^scene must"):
            call()


@pytest.mark.parametrize("bad", [0, None, 1.5, object(), SPHERE, "sphere", (), (SPHERE,) * 5, (SPHERE, "box")], ids=ids)
def test_scene_primitives_that_are_not_primitives_are_refused_by_name(bad: Any) -> None:
    # Once: Scene(primitives=0) raised TypeError ('int' object is not iterable).
    with pytest.raises(ValueError, match=r"^primitives must"):
        sdf.Scene(bad)


# ------------------------------------------------------------------------ 5. integer arguments
@pytest.mark.parametrize("bad", [*BAD_INTEGERS, 0, -1, 10_001, 10**400], ids=ids)
def test_max_steps_must_be_an_integer_in_range(bad: Any) -> None:
    # Once: nan said "cannot convert float NaN to integer", inf raised OverflowError, None TypeError, and "1",
    # Decimal, True and 1.5 were taken.
    with pytest.raises(ValueError, match=r"^max_steps must"):
        sdf.sphere_trace(SCENE, [[0.0, 0.0, 5.0]], [[0.0, 0.0, -1.0]], max_steps=bad)
    with pytest.raises(ValueError, match=r"^max_steps must"):
        Shading(max_steps=bad)


def test_sphere_trace_still_takes_a_numpy_integer() -> None:
    t = sdf.sphere_trace(SCENE, [[0.0, 0.0, 5.0]], [[0.0, 0.0, -1.0]], max_steps=np.int32(64))  # type: ignore[arg-type]
    assert t[0] == pytest.approx(4.5, abs=1e-3)


@pytest.mark.parametrize("bad", [*BAD_INTEGERS, 15, 513, 10**400], ids=ids)
def test_resolution_must_be_an_integer_in_range(bad: Any) -> None:
    with pytest.raises(ValueError, match=r"^resolution must"):
        sdf.make_grid(SCENE, bad)
    with pytest.raises(ValueError, match=r"^resolution must"):
        sdf.mesh(SCENE, bad)


@pytest.mark.parametrize("bad", [*BAD_INTEGERS, 0, 8193, 10**400], ids=ids)
def test_image_sizes_must_be_integers_in_range(bad: Any) -> None:
    camera = Camera((3.0, 0.0, 1.0), (0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match=r"^width must"):
        check_image_size(bad, 8)
    with pytest.raises(ValueError, match=r"^height must"):
        camera_rays(camera, 8, bad)
    with pytest.raises(ValueError, match=r"^width must"):
        screen_rectangle(camera, np.zeros((1, 3)), bad, 8)


# ------------------------------------------------------------------------ 6. bounds, flags and choices
@pytest.mark.parametrize(
    "bad",
    ["1", object(), 1 + 2j, True, [[10**400, 0, 0], [1, 1, 1]], [[0, 0, 0], [1, 1, math.nan]], np.zeros(6), [1, 2]],
    ids=ids,
)
def test_bad_bounds_are_refused_naming_bounds(bad: Any) -> None:
    # Once: an object or a bigint raised TypeError or OverflowError.
    with pytest.raises(ValueError, match=r"^bounds must"):
        sdf.mesh(SCENE, 16, bad)
    with pytest.raises(ValueError, match=r"^bounds must"):
        check_field_bounds(bad)


def test_the_editor_needs_bounds() -> None:
    with pytest.raises(ValueError, match=r"^bounds must"):
        check_field_bounds(None)  # type: ignore[arg-type]


@pytest.mark.parametrize("bad", NOT_A_FLAG, ids=ids)
def test_near_surface_must_be_a_bool(bad: Any) -> None:
    # Once: any value was taken (its truth decided).
    with pytest.raises(ValueError, match=r"^near_surface must"):
        sdf.mesh(SCENE, 16, near_surface=bad)


@pytest.mark.parametrize("bad", [1, "progress", object()], ids=ids)
def test_progress_must_be_callable(bad: Any) -> None:
    with pytest.raises(ValueError, match=r"^progress must"):
        sdf.mesh(SCENE, 16, progress=bad)


@pytest.mark.parametrize("bad", NOT_A_CHOICE, ids=ids)
def test_string_choices_refuse_arrays_and_other_values_by_name(bad: Any) -> None:
    # Once: an array raised numpy's "The truth value of an array ... is ambiguous", naming nothing.
    with pytest.raises(ValueError, match=r"^kind must"):
        sdf.Primitive(bad, (0.0, 0.0, 0.0), (0.5,))
    with pytest.raises(ValueError, match=r"^kind must"):
        sdf.primitive_spec(bad)
    with pytest.raises(ValueError, match=r"^kind must"):
        sdf.unregister_primitive(bad)
    with pytest.raises(ValueError, match=r"^op must"):
        sdf.Primitive("sphere", (0.0, 0.0, 0.0), (0.5,), op=bad)
    with pytest.raises(ValueError, match=r"^blend must"):
        sdf.Scene((SPHERE,), blend=bad)
    for smooth in (sdf.smooth_union, sdf.smooth_subtract, sdf.smooth_intersect):
        for k in (0.0, 0.1):
            with pytest.raises(ValueError, match=r"^blend must"):
                smooth([0.0], [1.0], k, bad)
    with pytest.raises(ValueError, match=r"^op must"):
        sdf.combine_weighted(np.zeros(1), np.ones(1), bad, 0.1, "poly")


# ------------------------------------------------------------------------ 7. the shaders' camera and shading
@pytest.mark.parametrize("huge", [1e19, 1e300, -1.7e308])
def test_a_camera_beyond_the_float32_bound_is_refused_naming_the_field(huge: float) -> None:
    # Once: a camera at (1e300, 0, 0) rendered an empty image with overflow RuntimeWarnings.
    with pytest.raises(ValueError, match=r"^position must"):
        Camera((huge, 0.0, 0.0), (0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match=r"^look_at must"):
        Camera((3.0, 0.0, 0.0), (huge, 0.0, 1.0))


@pytest.mark.parametrize("field", ["position", "look_at", "up"])
@pytest.mark.parametrize("bad", vector_family(3), ids=ids)
def test_bad_camera_vectors_are_refused_by_name(field: str, bad: Any) -> None:
    args = {"position": (3.0, 0.0, 1.0), "look_at": (0.0, 0.0, 0.0), "up": (0.0, 0.0, 1.0), field: bad}
    with pytest.raises(ValueError, match=rf"^{field} must"):
        Camera(**args)


def test_a_huge_up_vector_is_a_direction() -> None:
    camera = Camera((3.0, 0.0, 1.0), (0.0, 0.0, 0.0), up=(0.0, 0.0, 1e300))
    reference = Camera((3.0, 0.0, 1.0), (0.0, 0.0, 0.0))
    for got, want in zip(camera.basis(), reference.basis(), strict=True):
        np.testing.assert_allclose(got, want)


@pytest.mark.parametrize("bad", [*BAD_NUMBERS, 0.0, math.pi, -0.1], ids=ids)
def test_a_bad_field_of_view_is_refused_by_name(bad: Any) -> None:
    with pytest.raises(ValueError, match=r"^fov_y_rad must"):
        Camera((3.0, 0.0, 1.0), (0.0, 0.0, 0.0), fov_y_rad=bad)


SHADING_NUMBERS = [field.name for field in dataclasses.fields(Shading) if field.type in ("float", float)]
"""Every real-number field of Shading, so a new one is tested as soon as it is declared."""


def test_the_shading_numbers_are_its_ten_real_fields() -> None:
    assert len(SHADING_NUMBERS) == 10 and {"ambient", "shininess", "normal_epsilon"} <= set(SHADING_NUMBERS)


@pytest.mark.parametrize("name", SHADING_NUMBERS)
@pytest.mark.parametrize("bad", [*BAD_NUMBERS, -1.0, 1e300], ids=ids)
def test_bad_shading_numbers_are_refused_by_name(name: str, bad: Any) -> None:
    with pytest.raises(ValueError, match=rf"^{name} must"):
        Shading(**{name: bad})


@pytest.mark.parametrize("name", ["shadows", "occlusion"])
@pytest.mark.parametrize("bad", NOT_A_FLAG, ids=ids)
def test_shading_switches_must_be_bools(name: str, bad: Any) -> None:
    with pytest.raises(ValueError, match=rf"^{name} must"):
        Shading(**{name: bad})


@pytest.mark.parametrize("name", ["light_direction", "background"])
@pytest.mark.parametrize("bad", vector_family(3), ids=ids)
def test_bad_shading_vectors_are_refused_by_name(name: str, bad: Any) -> None:
    with pytest.raises(ValueError, match=rf"^{name} must"):
        Shading(**{name: bad})


def test_a_zero_light_direction_and_a_background_outside_the_unit_cube_are_refused() -> None:
    with pytest.raises(ValueError, match=r"^light_direction must"):
        Shading(light_direction=(0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match=r"^background must"):
        Shading(background=(0.5, 0.5, 1.5))


# Kind: a refusal that implies a value would pass. A direction of length 100 was told "of magnitude ≤ 2", and then
# one of length 1.5 "must be unit vectors".
@pytest.mark.parametrize("length", [0.0, 0.5, 1.5, 1.99, 2.5, 100.0, 1e200, 1.7e308])
def test_a_ray_direction_that_is_not_unit_is_refused_as_such(length: float) -> None:
    scene = sdf.Scene((sdf.Primitive("sphere", (0.0, 0.0, 0.0), (0.5,)),))
    with pytest.raises(ValueError, match=r"^directions must be unit vectors, got "):
        sdf.sphere_trace(scene, [[0.0, 0.0, -3.0]], [[0.0, 0.0, length]])
    assert np.isfinite(sdf.sphere_trace(scene, [[0.0, 0.0, -3.0]], [[0.0, 0.0, 1.0]])).all()


# Kind: a real number called "not a real number": a Python int past float64 is refused as not finite.
def test_an_integer_past_float64_is_refused_as_not_finite() -> None:
    with pytest.raises(ValueError, match=r"^p must be finite \(within float64's range\), got "):
        sdf.sd_sphere([[10**400, 0, 0]], 0.5)


@pytest.mark.parametrize(
    ("kind", "size", "message"),
    [
        # An outside tester: "size of a sphere must have 1 values, got ()" for a bare radius, and "got
        # array([1.e+300])" (numpy's repr) for a huge one. A bare number is a one-parameter kind's parameter.
        ("sphere", (0.5, 0.3), "size of a sphere must have one value, got (0.5, 0.3)"),
        ("sphere", (), "size of a sphere must have one value, got ()"),
        ("box", 0.5, "size of a box must have 3 values, got 0.5"),
        ("torus", (1.0,), "size of a torus must have 2 values, got (1.0,)"),
        ("ellipsoid", 0.5, "size of an ellipsoid must have 3 values, got 0.5"),  # a re-tester: "a ellipsoid"
        ("octahedron", (0.5, 0.5), "size of an octahedron must have one value, got (0.5, 0.5)"),
        ("sphere", (1e300,), "size must be of magnitude ≤ 1e+150, got [1e+300]"),
    ],
)
def test_a_primitive_size_of_the_wrong_count_or_magnitude_is_refused_in_plain_values(
    kind: sdf.PrimitiveKind, size: Any, message: str
) -> None:
    with pytest.raises(ValueError) as refused:
        sdf.Primitive(kind, (0.0, 0.0, 0.0), size)
    assert str(refused.value) == message


def test_a_bare_number_is_the_size_of_a_one_parameter_kind() -> None:
    assert sdf.Primitive("sphere", (0.0, 0.0, 0.0), 0.5).size == (0.5,)  # type: ignore[arg-type]
    assert sdf.Primitive("octahedron", (0.0, 0.0, 0.0), 0.25).size == (0.25,)  # type: ignore[arg-type]
