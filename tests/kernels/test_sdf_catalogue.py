"""Quilez's primitives and operators (kernels/sdf and shaders/sdf.glsl, name for name).

Every function: numpy against GLSL within 1e-5 at random points. Exact primitives: analytic distances at points
whose nearest surface point is known, and the eikonal property (|∇d| = 1, and p − d·∇d lands on the surface) at
random points, which a mere bound fails. Operators: against their definitions (a rounded box is a box grown by r,
an elongated sphere is a capsule, a finite repetition of a sphere is the union of its copies, ...).
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable

import numpy as np
import pytest
from helpers.ci import skip_or_fail
from hypothesis import given
from hypothesis import strategies as st

from kernels import sdf
from shaders import gl_service
from shaders import renderer as gl_renderer
from shaders.renderer import GLUnavailableError

RNG = np.random.default_rng(12)
POINTS = RNG.uniform(-1.5, 1.5, size=(3000, 3)).astype(np.float32).astype(np.float64)

# name, numpy distance at (N, 3) points, the GLSL body of sdf(p)
DISTANCES: list[tuple[str, Callable[[np.ndarray], np.ndarray], str]] = [
    ("sd_cylinder", lambda p: sdf.sd_cylinder(p, 0.6, 0.4), "sd_cylinder(p, 0.6, 0.4)"),
    (
        "sd_round_box",
        lambda p: sdf.sd_round_box(p, (0.7, 0.5, 0.3), 0.12),
        "sd_round_box(p, vec3(0.7, 0.5, 0.3), 0.12)",
    ),
    ("sd_octahedron", lambda p: sdf.sd_octahedron(p, 0.8), "sd_octahedron(p, 0.8)"),
    ("sd_cone", lambda p: sdf.sd_cone(p, 0.5, 1.1), "sd_cone(p, 0.5, 1.1)"),
    ("sd_hex_prism", lambda p: sdf.sd_hex_prism(p, 0.45, 0.7), "sd_hex_prism(p, 0.45, 0.7)"),
    ("sd_ellipsoid", lambda p: sdf.sd_ellipsoid(p, (0.9, 0.5, 0.3)), "sd_ellipsoid(p, vec3(0.9, 0.5, 0.3))"),
    (
        "sd_ellipsoid_lipschitz",
        lambda p: sdf.sd_ellipsoid_lipschitz(p, (0.9, 0.5, 0.3)),
        "sd_ellipsoid_lipschitz(p, vec3(0.9, 0.5, 0.3))",
    ),
    ("sd_plane", lambda p: sdf.sd_plane(p, (0.3, -0.5, 0.8), 0.2), "sd_plane(p, vec3(0.3, -0.5, 0.8), 0.2)"),
    (
        "op_round",
        lambda p: sdf.op_round(sdf.sd_box(p, (0.5, 0.4, 0.3)), 0.1),
        "op_round(sd_box(p, vec3(0.5, 0.4, 0.3)), 0.1)",
    ),
    ("op_onion", lambda p: sdf.op_onion(sdf.sd_sphere(p, 0.8), 0.05), "op_onion(sd_sphere(p, 0.8), 0.05)"),
]

# name, numpy point map (N, 3) -> (N, 3), the GLSL body of color(p) (a vec3, read back unclamped)
POINT_MAPS: list[tuple[str, Callable[[np.ndarray], np.ndarray], str]] = [
    ("op_elongate", lambda p: sdf.op_elongate(p, (0.3, 0.0, 0.2))[0], "op_elongate(p, vec3(0.3, 0.0, 0.2)).xyz"),
    (
        "op_elongate (w)",
        lambda p: np.repeat(sdf.op_elongate(p, (0.3, 0.0, 0.2))[1][:, None], 3, axis=1),
        "vec3(op_elongate(p, vec3(0.3, 0.0, 0.2)).w)",
    ),
    ("op_twist", lambda p: sdf.op_twist(p, 2.3), "op_twist(p, 2.3)"),
    ("op_bend", lambda p: sdf.op_bend(p, -1.7), "op_bend(p, -1.7)"),
    (
        "op_repeat_finite",
        lambda p: sdf.op_repeat_finite(p, (0.5, 0.7, 0.3), (2, 1, 0)),
        "op_repeat_finite(p, vec3(0.5, 0.7, 0.3), vec3(2.0, 1.0, 0.0))",
    ),
    ("op_symmetry", lambda p: sdf.op_symmetry(p, (1, 0, 1)), "op_symmetry(p, vec3(1.0, 0.0, 1.0))"),
]


def probe(sdf_body: str, color_body: str = "vec3(0.0)") -> tuple[np.ndarray, np.ndarray]:
    source = f"float sdf(vec3 p) {{\n    return {sdf_body};\n}}\nvec3 color(vec3 p) {{\n    return {color_body};\n}}\n"
    try:
        d, c = gl_service.run(lambda gl: gl.probe_field(source, POINTS))
    except GLUnavailableError as exc:
        skip_or_fail(str(exc))
        raise
    return d.astype(np.float64), c.astype(np.float64)


# ------------------------------------------------------------------------------------------ name for name
def test_every_new_function_is_in_both_languages_with_its_source_and_exactness() -> None:
    glsl = (gl_renderer.SHADER_DIR / "sdf.glsl").read_text()
    defined = set(re.findall(r"^(?:float|vec2|vec3|vec4) (\w+)\(", glsl, flags=re.MULTILINE))
    names = {name.split(" ")[0] for name, _, _ in DISTANCES + POINT_MAPS}
    assert names <= defined
    for name in names:
        doc = getattr(sdf, name).__doc__
        assert "Quilez" in doc, name
        if name.startswith("sd_"):
            assert ("Exact" in doc) != ("bound" in doc), name


@pytest.mark.gl
@pytest.mark.parametrize(("name", "numpy_fn", "glsl"), DISTANCES, ids=[c[0] for c in DISTANCES])
def test_distance_glsl_matches_numpy(name: str, numpy_fn: Callable[[np.ndarray], np.ndarray], glsl: str) -> None:
    d_gl, _ = probe(glsl)
    np.testing.assert_allclose(d_gl, numpy_fn(POINTS), atol=1e-5, rtol=0, err_msg=name)


@pytest.mark.gl
@pytest.mark.parametrize(("name", "numpy_fn", "glsl"), POINT_MAPS, ids=[c[0] for c in POINT_MAPS])
def test_point_map_glsl_matches_numpy(name: str, numpy_fn: Callable[[np.ndarray], np.ndarray], glsl: str) -> None:
    _, mapped = probe("0.0", glsl)
    np.testing.assert_allclose(mapped, numpy_fn(POINTS), atol=1e-5, rtol=0, err_msg=name)


# ------------------------------------------------------------------------------------------ exact distances
S3 = math.sqrt(3.0)
ANALYTIC: list[tuple[str, Callable[[np.ndarray], np.ndarray], list[tuple[tuple[float, ...], float]]]] = [
    (
        "cylinder h=0.6 r=0.4",
        lambda p: sdf.sd_cylinder(p, 0.6, 0.4),
        [
            ((1.0, 0.0, 0.0), 0.6),  # beside the wall
            ((0.0, 0.9, 0.0), 0.3),  # above the cap
            ((0.7, 1.0, 0.0), 0.5),  # past the rim: |(0.3, 0.4)|
            ((0.1, 0.0, 0.0), -0.3),  # inside, nearest the wall
            ((0.0, 0.5, 0.0), -0.1),  # inside, nearest the cap
        ],
    ),
    (
        "round box b=(0.7,0.5,0.3) r=0.1",
        lambda p: sdf.sd_round_box(p, (0.7, 0.5, 0.3), 0.1),
        [
            ((1.0, 0.0, 0.0), 0.3),
            ((0.0, 0.0, -0.5), 0.2),
            ((0.7, 0.5, 0.3), math.sqrt(3 * 0.1**2) - 0.1),  # the sharp corner is 0.0732 outside
            ((0.0, 0.0, 0.0), -0.3),
        ],
    ),
    (
        "octahedron s=0.8",
        lambda p: sdf.sd_octahedron(p, 0.8),
        [
            ((1.1, 0.0, 0.0), 0.3),  # beyond a vertex
            ((0.5, 0.5, 0.5), (1.5 - 0.8) / S3),  # on a face normal
            ((-0.6, 0.6, 0.0), math.sqrt(2) * 0.6 - 0.8 / math.sqrt(2)),  # beyond an edge's middle
            ((0.0, 0.0, 0.0), -0.8 / S3),
        ],
    ),
    (
        "cone r=0.5 h=1.0",
        lambda p: sdf.sd_cone(p, 0.5, 1.0),
        [
            ((0.0, 0.8, 0.0), 0.3),  # above the apex (0, 0.5, 0)
            ((0.0, -0.9, 0.0), 0.4),  # below the base centre
            ((0.8, -0.9, 0.0), 0.5),  # past the rim (0.5, -0.5): |(0.3, 0.4)|
            # beside the slant: its middle (0.25, 0, 0) plus 0.2 along the outward normal (2, 1)/√5
            ((0.25 + 0.4 / math.sqrt(5), 0.2 / math.sqrt(5), 0.0), 0.2),
            ((0.0, -0.45, 0.0), -0.05),  # just above the base, on the axis
        ],
    ),
    (
        "hex prism a=0.45 h=0.7",
        lambda p: sdf.sd_hex_prism(p, 0.45, 0.7),
        [
            ((0.0, 0.75, 0.0), 0.3),  # off the flat side at y = 0.45
            ((0.0, 0.0, 1.0), 0.3),  # off the cap
            ((0.9 / S3 + 0.2, 0.0, 0.0), 0.2),  # beyond the vertex at (0.9/√3, 0)
            ((0.0, 0.0, 0.0), -0.45),
        ],
    ),
    (
        "plane n=(0,0,2) offset 0.5",
        lambda p: sdf.sd_plane(p, (0.0, 0.0, 2.0), 0.5),
        [((3.0, -1.0, 1.0), 1.5), ((0.0, 0.0, -0.5), 0.0), ((0.0, 0.0, -2.0), -1.5)],
    ),
]


@pytest.mark.parametrize(("name", "fn", "cases"), ANALYTIC, ids=[c[0] for c in ANALYTIC])
def test_exact_primitives_give_analytic_distances(
    name: str, fn: Callable[[np.ndarray], np.ndarray], cases: list
) -> None:
    points = np.array([p for p, _ in cases])
    expected = np.array([d for _, d in cases])
    np.testing.assert_allclose(fn(points), expected, atol=1e-12, err_msg=name)


EXACT: list[tuple[str, Callable[[np.ndarray], np.ndarray]]] = [
    ("sd_cylinder", lambda p: sdf.sd_cylinder(p, 0.6, 0.4)),
    ("sd_round_box", lambda p: sdf.sd_round_box(p, (0.7, 0.5, 0.3), 0.12)),
    ("sd_octahedron", lambda p: sdf.sd_octahedron(p, 0.8)),
    ("sd_cone", lambda p: sdf.sd_cone(p, 0.5, 1.1)),
    ("sd_hex_prism", lambda p: sdf.sd_hex_prism(p, 0.45, 0.7)),
    ("sd_plane", lambda p: sdf.sd_plane(p, (0.3, -0.5, 0.8), 0.2)),
]


def gradient(fn: Callable[[np.ndarray], np.ndarray], p: np.ndarray, h: float = 1e-6) -> np.ndarray:
    return np.stack([(fn(p + h * e) - fn(p - h * e)) / (2 * h) for e in np.eye(3)], axis=1)


@pytest.mark.parametrize(("name", "fn"), EXACT, ids=[c[0] for c in EXACT])
def test_exact_primitives_are_eikonal_and_point_at_their_surface(
    name: str, fn: Callable[[np.ndarray], np.ndarray]
) -> None:
    d = fn(POINTS)
    g = gradient(fn, POINTS)
    norm = np.linalg.norm(g, axis=1)
    # Away from the medial axis and the shape's edges (where the field has a kink) the gradient is a unit vector
    # and one step of −d along it reaches the surface: the property that defines an exact distance.
    smooth = np.abs(gradient(lambda q: np.linalg.norm(gradient(fn, q, 1e-6), axis=1), POINTS, 1e-3)).max(axis=1) < 1e3
    assert smooth.mean() > 0.8, name
    np.testing.assert_allclose(norm[smooth], 1.0, atol=1e-4, err_msg=name)
    foot = POINTS[smooth] - d[smooth, None] * g[smooth] / norm[smooth, None]
    np.testing.assert_allclose(fn(foot), 0.0, atol=1e-6, err_msg=name)


def test_ellipsoid_is_a_bound_zero_on_its_surface_and_exact_for_a_sphere() -> None:
    radii = np.array([0.9, 0.5, 0.3])
    theta, phi = RNG.uniform(0, np.pi, 500), RNG.uniform(0, 2 * np.pi, 500)
    on = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=1) * radii
    np.testing.assert_allclose(sdf.sd_ellipsoid(on, radii), 0.0, atol=1e-12)
    inside = np.einsum("ij,j->ij", POINTS, 1 / radii)
    inside_mask = np.linalg.norm(inside, axis=1) < 1
    assert np.all((sdf.sd_ellipsoid(POINTS, radii) < 0) == inside_mask)
    np.testing.assert_allclose(sdf.sd_ellipsoid(POINTS, (0.7, 0.7, 0.7)), sdf.sd_sphere(POINTS, 0.7), atol=1e-12)
    assert sdf.sd_ellipsoid(np.zeros((1, 3)), radii)[0] == -0.3
    # Not exact: off the axes the estimate differs from the distance to a dense sampling of the surface.
    t, f = np.meshgrid(np.linspace(0, np.pi, 800), np.linspace(0, 2 * np.pi, 1600))
    dense = np.stack([np.sin(t) * np.cos(f), np.sin(t) * np.sin(f), np.cos(t)], axis=-1).reshape(-1, 3)
    query = np.array([[0.8, 0.6, 0.3]])
    true = np.linalg.norm(dense * radii - query, axis=1).min()
    assert abs(sdf.sd_ellipsoid(query, radii)[0] - true) > 1e-2


# ------------------------------------------------------------------------------------------ operators
def test_op_round_of_a_box_is_the_round_box_grown() -> None:
    b, r = np.array([0.5, 0.4, 0.3]), 0.1
    np.testing.assert_allclose(sdf.op_round(sdf.sd_box(POINTS, b), r), sdf.sd_round_box(POINTS, b + r, r), atol=1e-12)


def test_op_onion_is_a_shell() -> None:
    d = sdf.op_onion(sdf.sd_sphere(POINTS, 0.8), 0.05)
    radius = np.linalg.norm(POINTS, axis=1)
    np.testing.assert_allclose(d, np.abs(radius - 0.8) - 0.05, atol=1e-12)


def test_elongated_sphere_is_a_capsule() -> None:
    q, extra = sdf.op_elongate(POINTS, (0.0, 0.4, 0.0))
    elongated = sdf.sd_sphere(q, 0.3) + extra
    capsule = sdf.sd_capsule(POINTS, (0.0, -0.4, 0.0), (0.0, 0.4, 0.0), 0.3)
    np.testing.assert_allclose(elongated, capsule, atol=1e-12)


def test_elongated_box_is_the_longer_box() -> None:
    q, extra = sdf.op_elongate(POINTS, (0.2, 0.0, 0.1))
    np.testing.assert_allclose(sdf.sd_box(q, (0.3, 0.3, 0.3)) + extra, sdf.sd_box(POINTS, (0.5, 0.3, 0.4)), atol=1e-12)


def rotation_about(axis: int, angle: np.ndarray) -> np.ndarray:
    """(N, 3, 3) right-handed rotations about a coordinate axis by the (N,) angles."""
    c, s = np.cos(angle), np.sin(angle)
    out = np.zeros((len(angle), 3, 3))
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    out[:, axis, axis] = 1.0
    out[:, i, i], out[:, i, j], out[:, j, i], out[:, j, j] = c, -s, s, c
    return out


def test_twist_rotates_each_slice_about_y_by_rate_times_height() -> None:
    rate = 2.3
    mapped = sdf.op_twist(POINTS, rate)
    # (c·x − s·z, s·x + c·z): a rotation of (z, x) by −angle about y.
    expected = np.einsum("nij,nj->ni", rotation_about(1, -rate * POINTS[:, 1]), POINTS)
    np.testing.assert_allclose(mapped, expected, atol=1e-12)
    np.testing.assert_allclose(mapped[:, 1], POINTS[:, 1])
    np.testing.assert_allclose(np.hypot(mapped[:, 0], mapped[:, 2]), np.hypot(POINTS[:, 0], POINTS[:, 2]))


def test_bend_rotates_about_z_by_rate_times_x() -> None:
    rate = -1.7
    expected = np.einsum("nij,nj->ni", rotation_about(2, rate * POINTS[:, 0]), POINTS)
    np.testing.assert_allclose(sdf.op_bend(POINTS, rate), expected, atol=1e-12)


def test_finite_repetition_of_a_sphere_is_the_union_of_its_copies() -> None:
    spacing, limit, r = np.array([0.5, 0.7, 0.3]), np.array([2, 1, 0]), 0.12
    repeated = sdf.sd_sphere(sdf.op_repeat_finite(POINTS, spacing, limit), r)
    copies = [spacing * np.array([i, j, k]) for i in range(-2, 3) for j in range(-1, 2) for k in range(0, 1)]
    union = np.min([sdf.sd_sphere(POINTS - c, r) for c in copies], axis=0)
    np.testing.assert_allclose(repeated, union, atol=1e-12)


def test_finite_repetition_rounds_halves_up_like_the_glsl() -> None:
    on_boundary = np.array([[0.25, 0.0, 0.0], [-0.25, 0.0, 0.0]])
    np.testing.assert_allclose(
        sdf.op_repeat_finite(on_boundary, (0.5, 1.0, 1.0), (3, 0, 0)), [[-0.25, 0.0, 0.0], [-0.25, 0.0, 0.0]]
    )


def test_mirror_symmetry_is_the_shape_and_its_reflection() -> None:
    centre, r = np.array([0.6, 0.2, 0.5]), 0.3  # wholly at x > 0 and z > 0
    mirrored = sdf.sd_sphere(sdf.op_symmetry(POINTS, (1, 0, 1)) - centre, r)
    copies = [centre * np.array([sx, 1.0, sz]) for sx in (-1, 1) for sz in (-1, 1)]
    union = np.min([sdf.sd_sphere(POINTS - c, r) for c in copies], axis=0)
    np.testing.assert_allclose(mirrored, union, atol=1e-12)


@given(h=st.floats(0.05, 2.0), r=st.floats(0.05, 2.0), x=st.floats(-3, 3), y=st.floats(-3, 3), z=st.floats(-3, 3))
def test_cylinder_against_its_closed_form_everywhere(h: float, r: float, x: float, y: float, z: float) -> None:
    rho, height = math.hypot(x, z), abs(y)
    if rho <= r and height <= h:
        expected = -min(r - rho, h - height)
    else:
        expected = math.hypot(max(rho - r, 0.0), max(height - h, 0.0))
    assert sdf.sd_cylinder(np.array([[x, y, z]]), h, r)[0] == pytest.approx(expected, abs=1e-12)


@pytest.mark.parametrize(
    ("call", "argument"),
    [
        (lambda: sdf.sd_cylinder(POINTS, 0.0, 1.0), "half_height"),
        (lambda: sdf.sd_round_box(POINTS, (0.2, 0.3, 0.4), 0.25), "radius"),
        (lambda: sdf.sd_octahedron(POINTS, float("nan")), "size"),
        (lambda: sdf.sd_cone(POINTS, -1.0, 1.0), "radius"),
        (lambda: sdf.sd_hex_prism(POINTS, 1.0, float("inf")), "half_height"),
        (lambda: sdf.sd_ellipsoid(POINTS, (1.0, 0.0, 1.0)), "radii"),
        (lambda: sdf.sd_plane(POINTS, (0.0, 0.0, 0.0), 0.0), "normal"),
        (lambda: sdf.op_round(np.zeros(3), -0.1), "radius"),
        (lambda: sdf.op_onion(np.zeros(3), float("nan")), "thickness"),
        (lambda: sdf.op_elongate(POINTS, (0.1, -0.1, 0.0)), "half_length"),
        (lambda: sdf.op_twist(POINTS, float("inf")), "rate"),
        (lambda: sdf.op_bend(POINTS, float("nan")), "rate"),
        (lambda: sdf.op_repeat_finite(POINTS, (0.5, 0.0, 0.5), (1, 1, 1)), "spacing"),
        (lambda: sdf.op_repeat_finite(POINTS, (0.5, 0.5, 0.5), (1, 0.5, 1)), "limit"),
        (lambda: sdf.op_symmetry(POINTS, (1, 2, 0)), "axes"),
    ],
)
def test_bad_arguments_raise_naming_the_argument(call: Callable[[], object], argument: str) -> None:
    with pytest.raises(ValueError, match=argument):
        call()


def test_lipschitz_ellipsoid_bound_never_exceeds_the_distance_and_quilez_estimate_can() -> None:
    radii = np.array([0.5, 0.5, 0.125])  # the flat one hypothesis found grows faster than 1/m under Quilez's
    a, b = POINTS[:1500], POINTS[1500:]
    slope = lambda f: np.abs(f(a) - f(b)) / np.linalg.norm(a - b, axis=1)  # noqa: E731
    assert slope(lambda q: sdf.sd_ellipsoid_lipschitz(q, radii)).max() <= 1.0 + 1e-12
    assert slope(lambda q: sdf.sd_ellipsoid(q, radii)).max() > 1.0
    np.testing.assert_allclose(
        sdf.sd_ellipsoid_lipschitz(POINTS, (0.7, 0.7, 0.7)), sdf.sd_sphere(POINTS, 0.7), atol=1e-12
    )
