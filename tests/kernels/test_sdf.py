"""kernels/sdf against exact distances, independent constructions and the properties the mesher relies on."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh
from helpers.meshing import assert_near_surface_meshes_like_the_full_grid
from helpers.properties import examples
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import KDTree

from kernels import sdf

SETTINGS = settings(max_examples=examples(40), deadline=None)
finite = st.floats(-3.0, 3.0, allow_nan=False)
point = st.tuples(finite, finite, finite)
positive = st.floats(0.05, 2.0)


def quat_about(axis: tuple[float, float, float], angle_rad: float) -> tuple[float, float, float, float]:
    a = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    s = math.sin(angle_rad / 2)
    return (math.cos(angle_rad / 2), a[0] * s, a[1] * s, a[2] * s)


# ------------------------------------------------------------------------------------------ primitives
@pytest.mark.parametrize(
    ("p", "expected"), [((2, 0, 0), 1.0), ((0, 0, 0), -1.0), ((0, 0.5, 0), -0.5), ((0, 3, 4), 4.0), ((-1, 0, 0), 0.0)]
)
def test_sphere_exact(p: tuple[float, float, float], expected: float) -> None:
    assert sdf.sd_sphere(np.array([p], float), 1.0)[0] == pytest.approx(expected, abs=1e-12)


@pytest.mark.parametrize(
    ("p", "expected"),
    [
        ((2, 0, 0), 1.0),  # face
        ((2, 3, 0), math.sqrt(2)),  # edge
        ((2, 3, 4), math.sqrt(3)),  # corner
        ((0, 0, 0), -1.0),  # centre: nearest face is the x one
        ((0.5, 0, 0), -0.5),
        ((0, 1.5, 2.9), -0.1),  # inside, nearest the z face
    ],
)
def test_box_exact(p: tuple[float, float, float], expected: float) -> None:
    assert sdf.sd_box(np.array([p], float), (1.0, 2.0, 3.0))[0] == pytest.approx(expected, abs=1e-12)


@pytest.mark.parametrize(
    ("p", "expected"),
    [
        ((2, 0, 0), -0.5),  # on the ring's centre line
        ((0, 0, 0), 1.5),  # centre of the hole
        ((0, 0, 3), 0.5),  # ring lies in xz: z is in its plane
        ((0, 1, 2), 0.5),  # above the centre line
        ((0, 3, 0), math.sqrt(13) - 0.5),  # on the axis (local y)
    ],
)
def test_torus_exact(p: tuple[float, float, float], expected: float) -> None:
    assert sdf.sd_torus(np.array([p], float), 2.0, 0.5)[0] == pytest.approx(expected, abs=1e-12)


@pytest.mark.parametrize(
    ("p", "expected"), [((0, 0, -1), 0.5), ((1, 0, 1), 0.5), ((0, 0, 1), -0.5), ((0, 0, 3), 0.5), ((3, 4, 2), 4.5)]
)
def test_capsule_exact(p: tuple[float, float, float], expected: float) -> None:
    got = sdf.sd_capsule(np.array([p], float), (0, 0, 0), (0, 0, 2), 0.5)[0]
    assert got == pytest.approx(expected, abs=1e-12)


@SETTINGS
@given(p=point, b=st.tuples(positive, positive, positive))
def test_box_matches_clamp_construction(p: tuple[float, float, float], b: tuple[float, float, float]) -> None:
    """Outside: distance to the nearest box point (a clamp); inside: minus the distance to the nearest face."""
    q, half = np.array(p), np.array(b)
    nearest = np.clip(q, -half, half)
    outside = float(np.linalg.norm(q - nearest))
    expected = outside if outside > 0 else -float(np.min(half - np.abs(q)))
    assert sdf.sd_box(q[None], half)[0] == pytest.approx(expected, abs=1e-9)


@SETTINGS
@given(p=point, major=st.floats(0.5, 2.0), minor=st.floats(0.05, 0.45))
def test_torus_matches_distance_to_ring(p: tuple[float, float, float], major: float, minor: float) -> None:
    """Distance to the ring circle (sampled finely in the xz plane) minus the tube radius."""
    angles = np.linspace(0, 2 * np.pi, 20001)
    ring = np.stack([major * np.cos(angles), np.zeros_like(angles), major * np.sin(angles)], axis=1)
    expected = float(np.min(np.linalg.norm(ring - np.array(p), axis=1))) - minor
    assert sdf.sd_torus(np.array([p]), major, minor)[0] == pytest.approx(expected, abs=2e-3 * major)


@SETTINGS
@given(p=point, a=point, b=point, r=positive)
def test_capsule_matches_distance_to_segment(p, a, b, r) -> None:
    s = np.linspace(0, 1, 20001)[:, None]
    segment = np.array(a) + s * (np.array(b) - np.array(a))
    expected = float(np.min(np.linalg.norm(segment - np.array(p), axis=1))) - r
    seg_len = float(np.linalg.norm(np.subtract(b, a)))
    assert sdf.sd_capsule(np.array([p]), a, b, r)[0] == pytest.approx(expected, abs=1e-4 * seg_len + 1e-12)


# ------------------------------------------------------------------------------------------ blends
@SETTINGS
@given(a=st.floats(-5, 5), b=st.floats(-5, 5), k=st.floats(0.0, 2.0))
def test_smin_poly_bounds(a: float, b: float, k: float) -> None:
    got = float(sdf.smin_poly(a, b, k))
    assert got <= min(a, b) + 1e-12
    assert got >= min(a, b) - k / 4 - 1e-12  # the deepest dip is k/4, where a = b
    if abs(a - b) >= k:
        assert got == min(a, b)


@SETTINGS
@given(a=st.floats(-5, 5), b=st.floats(-5, 5), k=st.floats(0.1, 100.0))
def test_smin_exp_bounds_and_seed_formula(a: float, b: float, k: float) -> None:
    got = float(sdf.smin_exp(a, b, k))
    assert min(a, b) - math.log(2) / k - 1e-12 <= got <= min(a, b) + 1e-12
    if k * max(abs(a), abs(b)) < 300:  # the seed's literal formula is representable here
        seed = -math.log(math.exp(-k * a) + math.exp(-k * b)) / k
        assert got == pytest.approx(seed, abs=1e-9)


def test_smin_dips_exactly_at_equal_distances() -> None:
    assert float(sdf.smin_poly(1.0, 1.0, 0.4)) == pytest.approx(1.0 - 0.1)
    assert float(sdf.smin_exp(1.0, 1.0, 2.0)) == pytest.approx(1.0 - math.log(2) / 2)


@pytest.mark.parametrize("k", [1e-1, 1e-3, 1e-6])
def test_smin_tends_to_min_as_blend_narrows(k: float) -> None:
    a = np.linspace(-1, 1, 101)
    b = a[::-1].copy()
    assert np.max(np.abs(sdf.smin_poly(a, b, k) - np.minimum(a, b))) <= k / 4 + 1e-15
    sharp = 1.0 / k  # exp's k is a sharpness: the blend narrows as it grows
    assert np.max(np.abs(sdf.smin_exp(a, b, sharp) - np.minimum(a, b))) <= math.log(2) / sharp + 1e-15
    assert sdf.smin_poly(0.3, 0.7, 0.0) == 0.3


def test_smin_exp_does_not_overflow() -> None:
    with np.errstate(over="raise", invalid="raise", divide="raise"):
        got = sdf.smin_exp(np.array([1000.0, -1000.0, 5.0]), np.array([1000.5, 2000.0, 5.0]), 50.0)
    assert np.all(np.isfinite(got))
    assert got[0] == pytest.approx(1000.0 - math.log1p(math.exp(-25.0)) / 50.0)
    assert got[1] == -1000.0


def test_hard_booleans() -> None:
    a, b = np.array([0.3, -0.2, 1.0]), np.array([-0.1, 0.4, 2.0])
    np.testing.assert_array_equal(sdf.op_union(a, b), [-0.1, -0.2, 1.0])
    np.testing.assert_array_equal(sdf.op_subtract(a, b), [0.3, -0.2, 1.0])
    np.testing.assert_array_equal(sdf.op_intersect(a, b), [0.3, 0.4, 2.0])


@SETTINGS
@given(a=st.floats(-3, 3), b=st.floats(-3, 3), k=st.floats(0.01, 1.0), blend=st.sampled_from(sdf.BLEND_FORMS))
def test_smooth_booleans_bound_the_hard_ones(a: float, b: float, k: float, blend: sdf.BlendForm) -> None:
    # Both forms dip by at most k/4 (exp with sharpness 4·ln2/k: ln2/sharpness = k/4).
    dip = k / 4 + 1e-12
    union = float(sdf.smooth_union(a, b, k, blend))
    subtract = float(sdf.smooth_subtract(a, b, k, blend))
    intersect = float(sdf.smooth_intersect(a, b, k, blend))
    assert min(a, b) - dip <= union <= min(a, b) + 1e-12
    assert max(a, -b) - 1e-12 <= subtract <= max(a, -b) + dip
    assert max(a, b) - 1e-12 <= intersect <= max(a, b) + dip
    assert float(sdf.smooth_union(a, b, 0.0, blend)) == min(a, b)
    assert float(sdf.smooth_subtract(a, b, 0.0, blend)) == max(a, -b)


# ------------------------------------------------------------------------------------------ scene
def test_primitive_moves_and_rotates_rigidly() -> None:
    quarter_z = quat_about((0, 0, 1), math.pi / 2)  # local x → world y
    box = sdf.Primitive("box", (1.0, 2.0, 3.0), (1.0, 0.25, 0.5), rotation=quarter_z)
    scene = sdf.Scene((box,))
    # World offset (0, 1.5, 0) is local (1.5, 0, 0): 0.5 outside the x face. World (1.5, 0, 0) is local y: 1.25 out.
    pts = np.array([[1.0, 3.5, 3.0], [2.5, 2.0, 3.0], [1.0, 2.0, 3.0]])
    np.testing.assert_allclose(sdf.scene_distance(scene, pts), [0.5, 1.25, -0.25], atol=1e-12)


def test_capsule_and_torus_axes_are_local_y() -> None:
    capsule = sdf.Scene((sdf.Primitive("capsule", (0, 0, 0), (1.0, 0.25)),))
    torus = sdf.Scene((sdf.Primitive("torus", (0, 0, 0), (1.0, 0.25)),))
    np.testing.assert_allclose(sdf.scene_distance(capsule, [[0, 1.25, 0], [1.25, 0, 0]]), [0.0, 1.0], atol=1e-12)
    np.testing.assert_allclose(sdf.scene_distance(torus, [[0, 0, 1.0], [0, 1.0, 0]]), [-0.25, math.sqrt(2) - 0.25])


def test_scene_folds_ops_in_order() -> None:
    # The first primitive's op is not used.
    big = sdf.Primitive("sphere", (0, 0, 0), (1.0,), op="subtract")
    cut = sdf.Primitive("box", (1.0, 0, 0), (0.5, 2.0, 2.0), op="subtract")
    keep = sdf.Primitive("sphere", (0.5, 0, 0), (0.6,), op="intersect")
    hard = sdf.Scene((big, cut, keep), k=0.0)
    pts = np.array([[0.0, 0, 0], [0.7, 0, 0], [-0.95, 0, 0], [0.2, 0.5, 0]])
    d_big = np.linalg.norm(pts, axis=1) - 1.0
    d_cut = sdf.sd_box(pts - [1.0, 0, 0], (0.5, 2.0, 2.0))
    d_keep = np.linalg.norm(pts - [0.5, 0, 0], axis=1) - 0.6
    expected = np.maximum(np.maximum(d_big, -d_cut), d_keep)
    np.testing.assert_allclose(sdf.scene_distance(hard, pts), expected, atol=1e-12)
    assert sdf.scene_distance(hard, pts)[1] > 0  # x = 0.7 was cut away


def test_scene_color_blends_by_the_distance_weights() -> None:
    red = sdf.Primitive("sphere", (-1, 0, 0), (0.8,), color=(1.0, 0.0, 0.0))
    blue = sdf.Primitive("sphere", (1, 0, 0), (0.8,), color=(0.0, 0.0, 1.0))
    for blend in sdf.BLEND_FORMS:
        scene = sdf.Scene((red, blue), k=0.5, blend=blend)
        colors = sdf.scene_color(scene, [[0.0, 0.0, 0.0], [0.0, 0.7, 0.0], [-1.5, 0.0, 0.0]])
        # Equidistant: half and half.
        np.testing.assert_allclose(colors[:2], [[0.5, 0, 0.5]] * 2, atol=1e-12)
        if blend == "poly":  # outside the blend width the nearer primitive's colour is exact
            np.testing.assert_allclose(colors[2], [1.0, 0.0, 0.0], atol=1e-12)
        else:
            assert colors[2, 0] > 0.99
    hard = sdf.Scene((red, blue), k=0.0)
    np.testing.assert_array_equal(sdf.scene_color(hard, [[0.9, 0, 0]]), [[0.0, 0.0, 1.0]])


@st.composite
def random_scenes(draw: st.DrawFn) -> sdf.Scene:
    """One to four primitives of any kind, pose and op near the origin, with a random blend."""
    prims = []
    for _ in range(draw(st.integers(1, 4))):
        kind = draw(st.sampled_from(sdf.PRIMITIVE_KINDS))
        size = {
            "sphere": (draw(st.floats(0.1, 0.6)),),
            "box": tuple(draw(st.floats(0.1, 0.5)) for _ in range(3)),
            "torus": (draw(st.floats(0.3, 0.6)), draw(st.floats(0.05, 0.25))),
            "capsule": (draw(st.floats(0.05, 0.5)), draw(st.floats(0.05, 0.3))),
            "cylinder": (draw(st.floats(0.05, 0.5)), draw(st.floats(0.05, 0.4))),
            "round_box": tuple(draw(st.floats(0.1, 0.5)) for _ in range(3)),
            "octahedron": (draw(st.floats(0.1, 0.6)),),
            "cone": (draw(st.floats(0.1, 0.5)), draw(st.floats(0.1, 0.8))),
            "hex_prism": (draw(st.floats(0.1, 0.4)), draw(st.floats(0.05, 0.5))),
            "ellipsoid": tuple(draw(st.floats(0.1, 0.6)) for _ in range(3)),
        }[kind]
        center = tuple(draw(st.floats(-0.5, 0.5)) for _ in range(3))
        rotation = (draw(st.floats(0.1, 1)), *(draw(st.floats(-1, 1)) for _ in range(3)))
        op = draw(st.sampled_from(sdf.BOOLEAN_OPS))
        prims.append(sdf.Primitive(kind, center, size, rotation, op=op))  # type: ignore[arg-type]
    return sdf.Scene(tuple(prims), k=draw(st.floats(0.0, 0.5)), blend=draw(st.sampled_from(sdf.BLEND_FORMS)))


@SETTINGS
@given(scene=random_scenes(), seed=st.integers(0, 2**16))
def test_scene_field_is_one_lipschitz(scene: sdf.Scene, seed: int) -> None:
    """The coarse-to-fine mesher and sphere tracing both rely on |d(p) − d(q)| ≤ |p − q|."""
    rng = np.random.default_rng(seed)
    p = rng.uniform(-1.5, 1.5, (500, 3))
    q = p + rng.normal(0, 0.2, (500, 3))
    lhs = np.abs(sdf.scene_distance(scene, p) - sdf.scene_distance(scene, q))
    assert np.all(lhs <= np.linalg.norm(p - q, axis=1) * (1 + 1e-9) + 1e-12)


# ------------------------------------------------------------------------------------------ validation
@pytest.mark.parametrize(
    ("make", "name"),
    [
        (lambda: sdf.sd_sphere([[0, 0, float("nan")]], 1.0), "p"),
        (lambda: sdf.sd_sphere([[0, 0]], 1.0), "p"),
        (lambda: sdf.sd_sphere([[0, 0, 0]], -1.0), "radius"),
        (lambda: sdf.sd_box([[0, 0, 0]], (1, -1, 1)), "half_size"),
        (lambda: sdf.sd_torus([[0, 0, 0]], 1.0, float("inf")), "minor_radius"),
        (lambda: sdf.sd_capsule([[0, 0, 0]], (0, 0, float("nan")), (0, 0, 1), 0.1), "a"),
        (lambda: sdf.smin_poly(1.0, 2.0, -0.1), "k"),
        (lambda: sdf.smin_exp(1.0, 2.0, 0.0), "k"),
        (lambda: sdf.smin_poly(float("nan"), 2.0, 0.1), "a"),
        (lambda: sdf.Primitive("sphere", (0, 0, 0), (-0.5,)), "size"),
        (lambda: sdf.Primitive("box", (0, 0, 0), (0.5,)), "size"),
        (lambda: sdf.Primitive("pyramid", (0, 0, 0), (0.5,)), "kind"),  # type: ignore[arg-type]
        (lambda: sdf.Primitive("sphere", (0, float("nan"), 0), (0.5,)), "center"),
        (lambda: sdf.Primitive("sphere", (0, 0, 0), (0.5,), rotation=(0, 0, 0, 0)), "rotation"),
        (lambda: sdf.Primitive("sphere", (0, 0, 0), (0.5,), color=(2, 0, 0)), "color"),
        (lambda: sdf.Primitive("sphere", (0, 0, 0), (0.5,), op="xor"), "op"),  # type: ignore[arg-type]
        (lambda: sdf.Scene((sdf.Primitive("sphere", (0, 0, 0), (0.5,)),) * 5), "primitives"),
        (lambda: sdf.Scene(()), "primitives"),
        (lambda: sdf.Scene((sdf.Primitive("sphere", (0, 0, 0), (0.5,)),), k=float("nan")), "k"),
        (lambda: sdf.Scene((sdf.Primitive("sphere", (0, 0, 0), (0.5,)),), blend="cubic"), "blend"),  # type: ignore[arg-type]
        (lambda: sdf.mesh(sdf.default_scene(), 15), "resolution"),
        (lambda: sdf.mesh(sdf.default_scene(), 513), "resolution"),
        (lambda: sdf.mesh(sdf.default_scene(), 32.5), "resolution"),  # type: ignore[arg-type]
        (lambda: sdf.mesh(sdf.default_scene(), 32, bounds=[[0, 0, 0], [0, 1, 1]]), "bounds"),
        (lambda: sdf.scene_distance(sdf.default_scene(), [[0, 0, float("inf")]]), "points"),
    ],
)
def test_invalid_input_names_the_argument(make, name: str) -> None:
    with pytest.raises(ValueError, match=name):
        make()


# ------------------------------------------------------------------------------------------ mesh
def test_sphere_mesh_is_accurate_watertight_and_outward() -> None:
    scene = sdf.Scene((sdf.Primitive("sphere", (0.1, -0.2, 0.3), (1.0,)),))
    vertices, faces, colors = sdf.mesh(scene, 64)
    tri = trimesh.Trimesh(vertices, faces, process=False)
    assert tri.is_watertight and tri.is_winding_consistent
    assert tri.volume == pytest.approx(4 / 3 * math.pi, rel=5e-3)  # positive: faces wind outward
    grid = sdf.make_grid(scene, 64)
    radial = np.abs(np.linalg.norm(vertices - [0.1, -0.2, 0.3], axis=1) - 1.0)
    assert radial.max() < 0.02 * grid.spacing  # sub-voxel: interpolation of the float field
    np.testing.assert_allclose(colors, np.full_like(colors, 0.8))


def test_default_scene_mesh_is_watertight_with_blended_colors() -> None:
    scene = sdf.default_scene()
    vertices, faces, colors = sdf.mesh(scene, 64)
    tri = trimesh.Trimesh(vertices, faces, process=False)
    assert tri.is_watertight and tri.volume > 0
    assert len(np.unique(faces, axis=0)) == len(faces)
    assert np.all(faces[:, 0] != faces[:, 1]) and np.all(faces[:, 1] != faces[:, 2])
    assert np.all(faces[:, 0] != faces[:, 2])
    spacing = sdf.make_grid(scene, 64).spacing
    assert np.abs(sdf.scene_distance(scene, vertices)).max() < 0.5 * spacing
    np.testing.assert_allclose(colors, sdf.scene_color(scene, vertices))


def test_samples_exactly_on_the_surface_are_merged() -> None:
    """Box faces on grid planes put samples exactly on the level: nudged off it, vertices distinct, watertight."""
    scene = sdf.Scene(
        (sdf.Primitive("box", (0, 0, 0), (0.5, 0.5, 0.5)), sdf.Primitive("sphere", (0.5, 0.5, 0.5), (0.25,))), k=0.0
    )
    bounds = [[-1, -1, -1], [1, 1, 1]]
    grid = sdf.make_grid(scene, 17, bounds)
    assert grid.spacing == 0.125  # so the faces at ±0.5 fall exactly on samples
    field = sdf.sample_near_surface(scene, grid).field
    assert np.count_nonzero(field == 0.0) > 100
    vertices, faces, _ = sdf.mesh(scene, 17, bounds)
    tri = trimesh.Trimesh(vertices, faces, process=False)
    assert len(np.unique(vertices, axis=0)) == len(vertices)
    assert np.all(faces[:, 0] != faces[:, 1]) and np.all(faces[:, 1] != faces[:, 2])
    assert np.all(faces[:, 0] != faces[:, 2])
    assert tri.is_watertight and tri.volume > 0


@settings(max_examples=examples(12), deadline=None)
@given(scene=random_scenes())
def test_near_surface_sampling_gives_the_full_grid_mesh(scene: sdf.Scene) -> None:
    """Coarse-to-fine output equals plain full-grid evaluation plus marching cubes, exactly."""
    assert_near_surface_meshes_like_the_full_grid(scene, 40)
    grid = sdf.make_grid(scene, 40)
    near_field = sdf.sample_near_surface(scene, grid)
    full_field = sdf.sample_full(scene, grid)
    np.testing.assert_array_equal(np.sign(near_field.field), np.sign(full_field))
    np.testing.assert_array_equal(near_field.field[near_field.mask], full_field[near_field.mask])
    assert near_field.evaluated > 0


def test_near_surface_evaluates_a_small_fraction_at_128() -> None:
    grid = sdf.make_grid(sdf.default_scene(), 128)
    sampled = sdf.sample_near_surface(sdf.default_scene(), grid)
    assert sampled.evaluated < 0.2 * math.prod(grid.shape)
    assert sampled.mask.sum() < 0.2 * math.prod(grid.shape)


def test_mesh_bounds_and_progress() -> None:
    scene = sdf.Scene((sdf.Primitive("box", (0, 0, 0), (0.5, 0.5, 0.5)),))
    seen: list[float] = []
    vertices, _, _ = sdf.mesh(scene, 32, bounds=[[-1, -1, -1], [1, 1, 1]], progress=seen.append)
    assert vertices.min() >= -0.5 - 1e-9 and vertices.max() <= 0.5 + 1e-9
    assert seen == sorted(seen) and seen[-1] <= 1.0 and len(seen) >= 2
    empty = sdf.mesh(scene, 32, bounds=[[2, 2, 2], [3, 3, 3]])
    assert [a.shape[0] for a in empty] == [0, 0, 0]


def test_grid_has_cubic_voxels_and_resolution_on_the_longest_side() -> None:
    grid = sdf.make_grid(sdf.default_scene(), 100, bounds=[[0, 0, 0], [2.0, 1.0, 0.5]])
    assert grid.shape == (100, 51, 26)
    assert grid.spacing == pytest.approx(2.0 / 99)


@SETTINGS
@given(scene=random_scenes(), seed=st.integers(0, 2**16))
def test_bounding_spheres_hold_the_shape(scene: sdf.Scene, seed: int) -> None:
    """Every point inside the blended shape lies in one of the grown spheres the ray-marcher is limited to."""
    points = np.random.default_rng(seed).uniform(-1.6, 1.6, (20000, 3))
    inside = points[sdf.scene_distance(scene, points) < 0]
    centers, radii = sdf.scene_bounding_spheres(scene)
    gap = np.linalg.norm(inside[:, None, :] - centers[None], axis=2) - radii[None]
    assert np.all(gap.min(axis=1) <= 0)


# Kind: a field far below the distance under a smooth blend. The scenes' ellipsoid bound (|p/r| − 1)·min(r) is a
# tenth of the distance away from a flat ellipsoid; a smooth union takes up to k/4 off where both fields are under
# k, so two flat ellipsoids (an explore run drew them) blended into a disc 1.07 m across, past the bounding spheres
# the ray-marcher keeps to: the mesh and the ray-marched picture disagreed. The bound is now also never below the
# distance to the ellipsoid's enclosing sphere.
def test_a_smooth_union_of_flat_ellipsoids_stays_in_its_bounding_spheres() -> None:
    flat = [sdf.Primitive("ellipsoid", (0.0, 0.0, 0.0), (0.5, y, 0.5)) for y in (0.125, 0.109375)]
    scene = sdf.Scene(tuple(flat), k=0.5, blend="poly")
    points = np.random.default_rng(0).uniform(-1.6, 1.6, (200_000, 3))
    inside = points[sdf.scene_distance(scene, points) < 0]
    centers, radii = sdf.scene_bounding_spheres(scene)
    gap = np.linalg.norm(inside[:, None, :] - centers[None], axis=2) - radii[None]
    assert np.all(gap.min(axis=1) <= 0)
    # Still a bound: never more than the distance to the surface, sampled densely (1 mm apart at most).
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 1600), np.linspace(0, np.pi, 800))
    radii_xyz = np.array([0.5, 0.109375, 0.5])
    surface = np.stack([np.cos(u) * np.sin(v), np.sin(u) * np.sin(v), np.cos(v)], axis=-1).reshape(-1, 3) * radii_xyz
    outside = np.random.default_rng(1).uniform(-1.2, 1.2, (300, 3))
    outside = outside[np.linalg.norm(outside / radii_xyz, axis=1) > 1.0]
    true = np.array([np.linalg.norm(surface - q, axis=1).min() for q in outside])
    bound = sdf.sd_ellipsoid_lipschitz(outside, radii_xyz)
    assert np.all(bound <= true + 1e-3)
    assert np.all(bound >= np.linalg.norm(outside, axis=1) - 0.5 - 1e-12)


def test_ray_spheres_interval() -> None:
    centers = np.array([[0.0, 0, 5], [0.0, 0, 10]])
    radii = np.array([1.0, 2.0])
    origins = np.array([[0.0, 0, 0], [5.0, 0, 0], [0.0, 0, 5], [0.0, 0, 20]])
    directions = np.array([[0.0, 0, 1], [0.0, 0, 1], [0.0, 0, 1], [0.0, 0, 1]])
    t_enter, t_exit = sdf.ray_spheres_interval(origins, directions, centers, radii)
    np.testing.assert_allclose(t_enter[[0, 2]], [4.0, 0.0])  # first entry; a ray born inside starts at 0
    np.testing.assert_allclose(t_exit[[0, 2]], [12.0, 7.0])  # last exit
    assert t_exit[1] < t_enter[1] and t_exit[3] < t_enter[3]  # beside them; past them


# ------------------------------------------------------------------------------------------ sphere tracing
def test_sphere_trace_hits_and_misses() -> None:
    scene = sdf.Scene((sdf.Primitive("sphere", (0, 0, 0), (1.0,)),))
    origins = np.array([[0, 0, -5.0], [0, 0.6, -5.0], [0, 2.0, -5.0]])
    directions = np.array([[0, 0, 1.0]] * 3)
    t = sdf.sphere_trace(scene, origins, directions)
    assert t[0] == pytest.approx(4.0, abs=1e-3)
    assert t[1] == pytest.approx(5.0 - math.sqrt(1 - 0.36), abs=1e-3)
    assert t[2] == np.inf


# ------------------------------------------------------------------------------------------------ far from the origin
def _moved(scene: sdf.Scene, offset: np.ndarray) -> sdf.Scene:
    return sdf.Scene(
        tuple(
            sdf.Primitive(p.kind, tuple(np.add(p.center, offset)), p.size, p.rotation, p.color, p.op)
            for p in scene.primitives
        ),
        k=scene.k,
        blend=scene.blend,
    )


def test_a_sphere_1e8_m_out_is_meshed_as_the_same_sphere_at_the_origin() -> None:
    # An outside tester's input: the field was evaluated in world float32 coordinates, which step by 8 m there, and
    # the mesh filled the whole ±0.8 m box with 2,560 vertices, not watertight, of volume 0.
    far = sdf.mesh(sdf.Scene((sdf.Primitive("sphere", (1e8, 0.0, 0.0), (0.5,)),)), 32)
    near = sdf.mesh(sdf.Scene((sdf.Primitive("sphere", (0.0, 0.0, 0.0), (0.5,)),)), 32)
    solid = sdf.mesh_trimesh(*far)
    assert solid.is_watertight
    assert solid.volume == pytest.approx(4.0 / 3.0 * math.pi * 0.5**3, rel=0.01)
    assert far[1].shape == near[1].shape
    np.testing.assert_allclose(far[0] - (1e8, 0.0, 0.0), near[0], atol=1e-6)


@pytest.mark.parametrize("distance", [1e3, 1e5, 1e7, 1e9, 1e10])
@pytest.mark.parametrize("direction", [(1.0, 0.0, 0.0), (-0.48, 0.6, 0.64)])
def test_the_default_scene_anywhere_float64_resolves_its_grid_meshes_as_at_the_origin(
    distance: float, direction: tuple[float, float, float]
) -> None:
    """The whole kind: the blended default scene moved out to 10¹⁰ m in any direction gives the origin's mesh moved,
    each vertex within 1/100 of a voxel of the other mesh's."""
    offset = distance * np.array(direction)
    near = sdf.mesh(sdf.default_scene(), 48)
    far = sdf.mesh(_moved(sdf.default_scene(), offset), 48)
    voxel = sdf.make_grid(sdf.default_scene(), 48).spacing
    assert abs(len(far[0]) - len(near[0])) <= 0.01 * len(near[0])
    # Rounding moves a few samples across the iso level (vertex order and count may differ), never the surface.
    gap = max(KDTree(near[0]).query(far[0] - offset)[0].max(), KDTree(far[0] - offset).query(near[0])[0].max())
    assert gap <= 0.01 * voxel
    assert sdf.mesh_trimesh(*far).volume == pytest.approx(sdf.mesh_trimesh(*near).volume, rel=1e-3)


@pytest.mark.parametrize("distance", [1e12, 1e15, 1e17])
def test_a_grid_finer_than_float64_resolves_where_it_lies_is_refused_naming_bounds(distance: float) -> None:
    scene = sdf.Scene((sdf.Primitive("sphere", (distance, 0.0, 0.0), (0.5,)),))
    with pytest.raises(ValueError, match=r"^bounds .* reach .* float64: mesh the shape nearer the origin"):
        sdf.mesh(scene, 32)
    with pytest.raises(ValueError, match=r"^bounds"):
        sdf.make_grid(scene, 32, bounds=[[distance - 1, -1, -1], [distance + 1, 1, 1]])
