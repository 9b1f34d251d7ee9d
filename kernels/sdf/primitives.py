"""SDF primitives: exact distances (and two bounds) after Inigo Quilez, and the registry of a scene's kinds.

Points are ``(N, 3)`` float arrays in metres, in the primitive's local frame; distances are ``(N,)`` in metres,
negative inside. Each ``sd_*`` function is mirrored name for name in ``shaders/sdf.glsl`` (float32 there).

    sphere   |p| − r
    box      |max(q, 0)| + min(max(q.x, q.y, q.z), 0),   q = |p| − b
    torus    |(|p.xz| − R, p.y)| − r                      (the ring lies in the local xz plane; axis local y)
    capsule  |pa − ba·h| − r,   h = clamp(pa·ba / ba·ba, 0, 1)   (a scene's capsule runs along local y)

:data:`PRIMITIVES` is the one table of the kinds a :class:`~kernels.sdf.scene.Primitive` may be: per kind its GUI
label, its size parameters (names and units), its numpy distance, its GLSL function and arguments, and the stable
integer code the renderer passes to the GLSL. The kernel's evaluation, the gallery's menus, the renderer's codes and
the GLSL dispatch (``shaders/glsl_library.py``) are all read from it, so adding a kind is one
:class:`PrimitiveSpec` (:func:`register_primitive`) plus its two formulas, numpy and GLSL.

Source: I. Quilez, "distance functions" (iquilezles.org/articles/distfunctions, 2008–2024).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from kernels import _checks

PrimitiveKind = str
"""The name of a kind of primitive in the registry, :data:`PRIMITIVES` (the built-in ten, :data:`BUILT_IN_KINDS`, and
any added by :func:`register_primitive`), which says what each one's sizes mean."""

FloatArray = NDArray[np.float64]
AnyFloatArray = NDArray[np.floating]
"""Internal fast paths keep their input's float dtype (float32 for the mesher's grid)."""

ROUND_BOX_ROUNDING = 0.25
"""A scene's round box is rounded by this fraction of its smallest half size."""
MAX_COORDINATE = 1e150
"""Largest magnitude (m) of a coordinate, position or size a primitive or operator takes: squares and products of
sums of such numbers stay finite in float64 (1e300 at most), so no formula overflows to inf or NaN. Anything larger
is refused by name (a sphere at 1e300 m had the distance inf; a capsule's end at 1e300 m gave NaN)."""
MIN_SEMI_AXIS = 1.0 / MAX_COORDINATE
"""Smallest semi-axis (m) an ellipsoid takes: a point within ±:data:`MAX_COORDINATE` over it stays finite."""


def coordinates(name: str, value: ArrayLike) -> FloatArray:
    """(N, 3) points (m) as float64, each coordinate within ±:data:`MAX_COORDINATE`, else ``ValueError`` naming
    ``name``."""
    pts = _checks.points(name, value)
    if not (np.abs(pts) <= MAX_COORDINATE).all():
        raise ValueError(f"{name} must be of magnitude ≤ {MAX_COORDINATE:g} m, got {_checks.shown(value)}")
    return pts


def position(name: str, value: ArrayLike) -> FloatArray:
    """A (3,) position (m) within ±:data:`MAX_COORDINATE`, else ``ValueError`` naming ``name``."""
    return _checks.vector(name, _checks.bounded_array(name, value, MAX_COORDINATE), 3)


def length(name: str, value: object, *, zero_ok: bool = False) -> float:
    """A length (m) > 0 (≥ 0 with ``zero_ok``) and ≤ :data:`MAX_COORDINATE`, else ``ValueError`` naming it."""
    number = _checks.non_negative(name, value) if zero_ok else _checks.positive(name, value)
    if number > MAX_COORDINATE:
        raise ValueError(f"{name} must be at most {MAX_COORDINATE:g} m, got {_checks.shown(value)}")
    return number


def semi_axes(radii: ArrayLike) -> FloatArray:
    """(3,) an ellipsoid's semi-axes (m), each in [:data:`MIN_SEMI_AXIS`, :data:`MAX_COORDINATE`], else
    ``ValueError`` naming ``radii``."""
    r = lengths("radii", radii, 3)
    if r.min() < MIN_SEMI_AXIS:
        raise ValueError(f"radii must each be at least {MIN_SEMI_AXIS:g} m, got {_checks.shown(r)}")
    return r


def lengths(name: str, value: ArrayLike, size: int) -> FloatArray:
    """(size,) lengths (m), each > 0 and ≤ :data:`MAX_COORDINATE`, else ``ValueError`` naming ``name``."""
    return _checks.positive_vector(name, _checks.bounded_array(name, value, MAX_COORDINATE), size)


def sd_sphere(p: ArrayLike, radius: float) -> FloatArray:
    """Exact distance to a sphere at the origin.

    Args:
        p: (N, 3) points in the local frame (m), within ±:data:`MAX_COORDINATE` (as every length here).
        radius: radius (m), > 0.

    Returns:
        (N,) signed distances (m).
    """
    return _sd_sphere(coordinates("p", p), length("radius", radius))


def _sd_sphere(pts: FloatArray, r: float) -> FloatArray:
    return np.linalg.norm(pts, axis=1) - r


def sd_box(p: ArrayLike, half_size: ArrayLike) -> FloatArray:
    """Exact distance to an axis-aligned box centred at the origin.

    Args:
        p: (N, 3) points in the local frame (m).
        half_size: (3,) half extents along x, y, z (m), each > 0.

    Returns:
        (N,) signed distances (m).
    """
    return _sd_box(coordinates("p", p), lengths("half_size", half_size, 3))


def _sd_box(pts: FloatArray, b: FloatArray | Sizes) -> FloatArray:
    q = np.abs(pts) - np.asarray(b)
    outside = np.linalg.norm(np.maximum(q, 0.0), axis=1)
    inside = np.minimum(q.max(axis=1), 0.0)
    return outside + inside


def sd_torus(p: ArrayLike, major_radius: float, minor_radius: float) -> FloatArray:
    """Exact distance to a torus whose ring lies in the local xz plane (axis along local y).

    Args:
        p: (N, 3) points in the local frame (m).
        major_radius: distance from the centre to the tube's centre line (m), > 0.
        minor_radius: tube radius (m), > 0.

    Returns:
        (N,) signed distances (m).
    """
    return _sd_torus(coordinates("p", p), length("major_radius", major_radius), length("minor_radius", minor_radius))


def _sd_torus(pts: FloatArray, big_r: float, small_r: float) -> FloatArray:
    qx = np.hypot(pts[:, 0], pts[:, 2]) - big_r
    return np.hypot(qx, pts[:, 1]) - small_r


def sd_capsule(p: ArrayLike, a: ArrayLike, b: ArrayLike, radius: float) -> FloatArray:
    """Exact distance to a capsule: the points within ``radius`` of segment ab.

    Args:
        p: (N, 3) points (m).
        a: (3,) one end of the segment (m).
        b: (3,) the other end (m); may equal ``a`` (a sphere).
        radius: radius (m), > 0.

    Returns:
        (N,) signed distances (m).
    """
    return _sd_capsule(coordinates("p", p), position("a", a), position("b", b), length("radius", radius))


def _sd_capsule(pts: FloatArray, a_vec: FloatArray, b_vec: FloatArray, r: float) -> FloatArray:
    pa = pts - a_vec
    ba = b_vec - a_vec
    length_sq = float(ba @ ba)
    h = np.zeros(len(pts)) if length_sq == 0.0 else np.clip(pa @ ba / length_sq, 0.0, 1.0)
    return np.linalg.norm(pa - h[:, None] * ba, axis=1) - r


# ------------------------------------------------------------------------------------------ more primitives
# After I. Quilez, "distance functions" (iquilezles.org/articles/distfunctions, 2008–2024), mirrored name for name
# in shaders/sdf.glsl. Each says whether it is an exact distance or only a bound (≤ the true distance outside and
# 1-Lipschitz, so sphere tracing stays safe).
def sd_cylinder(p: ArrayLike, half_height: float, radius: float) -> FloatArray:
    """Exact distance to a capped cylinder along local y, centred at the origin (Quilez, "Capped Cylinder").

    Args:
        p: (N, 3) points in the local frame (m).
        half_height: half its length along y (m), > 0.
        radius: radius (m), > 0.

    Returns:
        (N,) signed distances (m).
    """
    return _sd_cylinder(coordinates("p", p), length("half_height", half_height), length("radius", radius))


def _sd_cylinder(pts: FloatArray, h: float, r: float) -> FloatArray:
    dx = np.hypot(pts[:, 0], pts[:, 2]) - r
    dy = np.abs(pts[:, 1]) - h
    return np.minimum(np.maximum(dx, dy), 0.0) + np.hypot(np.maximum(dx, 0.0), np.maximum(dy, 0.0))


def sd_round_box(p: ArrayLike, half_size: ArrayLike, radius: float) -> FloatArray:
    """Exact distance to a box with rounded edges (Quilez, "Rounded Box").

    The box's outer half extents are ``half_size``; its edges and corners are rounded with ``radius``.

    Args:
        p: (N, 3) points in the local frame (m).
        half_size: (3,) outer half extents (m), each > 0.
        radius: rounding radius (m), in [0, min(half_size)].

    Returns:
        (N,) signed distances (m).
    """
    pts = coordinates("p", p)
    b = lengths("half_size", half_size, 3)
    r = length("radius", radius, zero_ok=True)
    if r > b.min():
        raise ValueError(f"radius must be at most min(half_size) = {b.min()}, got {_checks.shown(radius)}")
    return _sd_round_box(pts, b, r)


def _sd_round_box(pts: FloatArray, b: FloatArray | Sizes, r: float) -> FloatArray:
    q = np.abs(pts) - np.asarray(b) + r
    return np.linalg.norm(np.maximum(q, 0.0), axis=1) + np.minimum(q.max(axis=1), 0.0) - r


def sd_octahedron(p: ArrayLike, size: float) -> FloatArray:
    """Exact distance to the regular octahedron |x| + |y| + |z| = size (Quilez, "Octahedron - exact").

    Args:
        p: (N, 3) points in the local frame (m).
        size: distance from the centre to each vertex (m), > 0.

    Returns:
        (N,) signed distances (m).
    """
    return _sd_octahedron(coordinates("p", p), length("size", size))


def _sd_octahedron(p: FloatArray, s: float) -> FloatArray:
    pts = np.abs(p)
    m = pts.sum(axis=1) - s
    x, y, z = pts[:, 0], pts[:, 1], pts[:, 2]
    # Pick the face region: q is p with its axes cycled so the nearest edge is the one the formula handles.
    use_x, use_y, use_z = 3.0 * x < m, 3.0 * y < m, 3.0 * z < m
    q = np.where(use_x[:, None], pts, np.where(use_y[:, None], pts[:, [1, 2, 0]], pts[:, [2, 0, 1]]))
    k = np.clip(0.5 * (q[:, 2] - q[:, 1] + s), 0.0, s)
    edge = np.sqrt(q[:, 0] ** 2 + (q[:, 1] - s + k) ** 2 + (q[:, 2] - k) ** 2)
    return np.where(use_x | use_y | use_z, edge, m * (1.0 / math.sqrt(3.0)))


def sd_cone(p: ArrayLike, radius: float, height: float) -> FloatArray:
    """Exact distance to a solid cone along local y (Quilez, "Cone - exact").

    Its base, a disc of ``radius``, lies in the plane y = −height/2 and its apex at y = +height/2, so the origin is
    the middle of its axis.

    Args:
        p: (N, 3) points in the local frame (m).
        radius: base radius (m), > 0.
        height: apex to base (m), > 0.

    Returns:
        (N,) signed distances (m).
    """
    return _sd_cone(coordinates("p", p), length("radius", radius), length("height", height))


def _sd_cone(pts: FloatArray, r: float, h: float) -> FloatArray:
    # Quilez's frame: apex at the origin, base at y = −h; q is the base rim in the (radial, y) half-plane.
    qx, qy = r, -h
    wx = np.hypot(pts[:, 0], pts[:, 2])
    wy = pts[:, 1] - 0.5 * h
    t = np.clip((wx * qx + wy * qy) / (qx * qx + qy * qy), 0.0, 1.0)
    ax, ay = wx - qx * t, wy - qy * t
    with np.errstate(over="ignore"):  # a radius under 1e-292 m: w/q passes the float maximum, clipped to 1
        bx, by = wx - qx * np.clip(wx / qx, 0.0, 1.0), wy - qy
    d = np.minimum(ax * ax + ay * ay, bx * bx + by * by)
    # k = sign(q.y) = −1
    s = np.maximum(-(wx * qy - wy * qx), -(wy - qy))
    return np.sqrt(d) * np.sign(s)


def sd_hex_prism(p: ArrayLike, apothem: float, half_height: float) -> FloatArray:
    """Exact distance to a regular hexagonal prism along local z (Quilez, "Hexagonal Prism - exact").

    Args:
        p: (N, 3) points in the local frame (m).
        apothem: distance from the axis to each flat side (m), > 0; two sides are parallel to the x axis.
        half_height: half its length along z (m), > 0.

    Returns:
        (N,) signed distances (m).
    """
    pts = coordinates("p", p)
    return _sd_hex_prism(pts, length("apothem", apothem), length("half_height", half_height))


def _sd_hex_prism(p: FloatArray, a: float, h: float) -> FloatArray:
    pts = np.abs(p)
    kx, ky, kz = -math.sqrt(3.0) / 2.0, 0.5, 1.0 / math.sqrt(3.0)
    fold = 2.0 * np.minimum(kx * pts[:, 0] + ky * pts[:, 1], 0.0)
    x, y = pts[:, 0] - fold * kx, pts[:, 1] - fold * ky
    dx = np.hypot(x - np.clip(x, -kz * a, kz * a), y - a) * np.sign(y - a)
    dy = pts[:, 2] - h
    return np.minimum(np.maximum(dx, dy), 0.0) + np.hypot(np.maximum(dx, 0.0), np.maximum(dy, 0.0))


def sd_ellipsoid(p: ArrayLike, radii: ArrayLike) -> FloatArray:
    """A distance bound (not exact) for an axis-aligned ellipsoid (Quilez, "Ellipsoid - bound (not exact)", 2008).

    ``k0·(k0 − 1)/k1`` with ``k0 = |p/r|``, ``k1 = |p/r²|``: zero exactly on the surface and of the right sign,
    but only an approximation of the distance away from it (exact for a sphere), and not 1-Lipschitz for an
    elongated ellipsoid (scenes use :func:`sd_ellipsoid_lipschitz`). At the centre, where the formula is 0/0, it is
    −min(radii), the exact value there.

    Args:
        p: (N, 3) points in the local frame (m).
        radii: (3,) semi-axes along x, y, z (m), each in [:data:`MIN_SEMI_AXIS`, :data:`MAX_COORDINATE`].

    Returns:
        (N,) signed distance estimates (m).
    """
    pts = coordinates("p", p)
    r = semi_axes(radii)
    # k0/k1 depends only on p's direction, so it is taken of p scaled by a power of two (exactly) to a largest
    # component in [0.5, 1): then |p/r| ≤ 1e150 and the largest of |p/r²| ≥ 5e-301, with no overflow, and nothing
    # that matters to the norms is a subnormal. Its product with k0 − 1 (k0 ≤ 1e300) is at most |p| (Cauchy–Schwarz).
    # As written above, p/r² overflowed for a semi-axis under 1e-154 m, and a point under 1e-300 m lost digits.
    _, exponent = np.frexp(np.abs(pts).max(axis=1, keepdims=True))
    direction = np.ldexp(pts, -exponent) / r
    with np.errstate(invalid="ignore"):  # 0/0 at the centre only
        ratio = _hypot3(direction) / _hypot3(direction / r)  # k0/k1 (m), in [min(r), max(r)]
    d = ratio * (_hypot3(pts / r) - 1.0)
    return np.where(np.isfinite(ratio), d, -r.min())


def _hypot3(v: AnyFloatArray) -> AnyFloatArray:
    """(N,) lengths of (N, 3) vectors without squaring, so a component up to the float maximum does not overflow."""
    return np.hypot(np.hypot(v[:, 0], v[:, 1]), v[:, 2])


def sd_ellipsoid_lipschitz(p: ArrayLike, radii: ArrayLike) -> FloatArray:
    """A 1-Lipschitz distance bound for an axis-aligned ellipsoid: max((|p/r| − 1)·min(r), |p| − max(r)).

    The first term is Quilez's first, simplest bound ("Ellipsoid SDF", iquilezles.org/articles/ellipsoids, 2008):
    |∇|p/r|| ≤ 1/min(r), so it is 1-Lipschitz, and it is zero on the surface, hence never more than the true
    distance. Away from a flat ellipsoid it is far too small (a tenth of the distance for radii 0.5, 0.05, 0.5 m),
    and a smooth union, which takes k/4 off where two fields are both under k, then grew a flat ellipsoid's blend
    into a disc twice its size. The second term, the distance to the sphere of radius max(r) that holds the
    ellipsoid, is a 1-Lipschitz lower bound too; the larger of two such bounds is one, so the value stays what
    sphere tracing and the coarse-to-fine mesher need, with the surface unchanged. :func:`sd_ellipsoid` (Quilez's
    estimate) is closer to the distance but can grow faster than 1 per metre (by up to max(r)/min(r)). Equal radii
    give the sphere's distance.

    Args:
        p: (N, 3) points in the local frame (m).
        radii: (3,) semi-axes along x, y, z (m), each in [:data:`MIN_SEMI_AXIS`, :data:`MAX_COORDINATE`].

    Returns:
        (N,) signed distance bounds (m).
    """
    return _sd_ellipsoid_lipschitz(coordinates("p", p), semi_axes(radii))


def _sd_ellipsoid_lipschitz(pts: FloatArray, radii: FloatArray | Sizes) -> FloatArray:
    r = np.asarray(radii)
    # hypot's norm: p/r passes 1e154 for a semi-axis under 1e-4 m
    return np.maximum((_hypot3(pts / r) - 1.0) * r.min(), _hypot3(pts) - r.max())


def sd_plane(p: ArrayLike, normal: ArrayLike, offset: float) -> FloatArray:
    """Exact distance to the plane n·p + offset = 0, negative on the side −n points to (Quilez, "Plane").

    Args:
        p: (N, 3) points (m).
        normal: (3,) normal of any finite non-zero length; normalised here (scaled by its largest component first,
            so neither a huge nor a tiny one overflows or underflows).
        offset: the plane's signed distance from the origin along −n (m), within ±:data:`MAX_COORDINATE`.

    Returns:
        (N,) signed distances (m).
    """
    pts = coordinates("p", p)
    n = _checks.direction("normal", normal, 3)
    off = _checks.finite_number("offset", offset)
    if abs(off) > MAX_COORDINATE:
        raise ValueError(f"offset must be of magnitude ≤ {MAX_COORDINATE:g} m, got {_checks.shown(offset)}")
    return pts @ n + off


# ------------------------------------------------------------------------------------------ the registry
Sizes = tuple[float, ...]
LocalDistance = Callable[[FloatArray, Sizes], FloatArray]
"""(N, 3) local points (m) and a kind's sizes (m) → (N,) distances (m)."""
CoordinateDistance = Callable[[AnyFloatArray, AnyFloatArray, AnyFloatArray, Sizes], AnyFloatArray]
"""Local x, y, z coordinate arrays (m, any float dtype) and sizes → distances in that dtype."""


@dataclasses.dataclass(frozen=True)
class PrimitiveSpec:
    """One kind of scene primitive: everything the kernel, the GUI and the GLSL need to know about it."""

    kind: PrimitiveKind
    """Its name in a :class:`~kernels.sdf.scene.Primitive` (``"sphere"``)."""
    label: str
    """The GUI's name for it ("Hexagonal prism")."""
    code: int
    """Stable integer code the renderer writes to ``u_kind`` (the GLSL's ``KIND_<NAME>``)."""
    sizes: tuple[tuple[str, str], ...]
    """Name and unit of each size parameter, in order (1 to 3: the GLSL holds them in a vec3)."""
    distance: LocalDistance
    """The numpy distance of points in the local frame: the unchecked formula of its ``sd_*`` function for the
    built-in kinds (a :class:`~kernels.sdf.scene.Primitive` has checked its sizes, and a scene's local points may
    lie beyond what ``sd_*`` takes as its argument ``p``)."""
    bounding_radius: Callable[[Sizes], float]
    """Radius (m) of a sphere about the local origin that holds the primitive."""
    half_extents: Callable[[Sizes], tuple[float, float, float]]
    """Half extents (m) of a local-frame box about the origin that holds the primitive."""
    glsl_function: str
    """The GLSL function of its distance (the ``sd_*`` of the same name in ``shaders/sdf.glsl``, or of
    ``glsl_file``)."""
    glsl_arguments: str
    """The GLSL call's arguments in terms of the local point ``p`` and the sizes ``vec3 s``."""
    glsl_file: Path | None = None
    """A ``.glsl`` file defining ``glsl_function``; None for the functions of ``shaders/sdf.glsl``."""
    fused: bool = False
    """True for the kinds sdf.glsl's ``primitive_distance`` evaluates by its one shared formula (the first four
    codes); every other kind goes through the generated ``catalogue_distance`` (programs with EXTRA_KINDS)."""
    distance_xyz: CoordinateDistance | None = None
    """Optional fast path on coordinate arrays (no (N, 3) temporaries, dtype kept), equal to ``distance``."""
    meaning: str = ""
    """What its sizes are, named a, b, c in order, for a reader ("a = major radius, b = tube radius (ring in the
    local xz plane)"); empty: :attr:`size_meaning` names them from :attr:`sizes`."""

    @property
    def size_count(self) -> int:
        """How many size parameters it takes."""
        return len(self.sizes)

    @property
    def size_meaning(self) -> str:
        """What its sizes a, b, c are: :attr:`meaning`, or each size's name ("a = half length, b = radius")."""
        named = (f"{axis} = {name.replace('_', ' ')}" for axis, (name, _) in zip("abc", self.sizes, strict=False))
        return self.meaning or ", ".join(named)


def _sphere_xyz(x: AnyFloatArray, y: AnyFloatArray, z: AnyFloatArray, s: Sizes) -> AnyFloatArray:
    return np.sqrt(x * x + y * y + z * z) - s[0]


def _box_xyz(x: AnyFloatArray, y: AnyFloatArray, z: AnyFloatArray, s: Sizes) -> AnyFloatArray:
    qx, qy, qz = np.abs(x) - s[0], np.abs(y) - s[1], np.abs(z) - s[2]
    ox, oy, oz = np.maximum(qx, 0.0), np.maximum(qy, 0.0), np.maximum(qz, 0.0)
    inside = np.minimum(np.maximum(np.maximum(qx, qy), qz), 0.0)
    return np.sqrt(ox * ox + oy * oy + oz * oz) + inside


def _torus_xyz(x: AnyFloatArray, y: AnyFloatArray, z: AnyFloatArray, s: Sizes) -> AnyFloatArray:
    qx = np.sqrt(x * x + z * z) - s[0]
    return np.sqrt(qx * qx + y * y) - s[1]


def _capsule_xyz(x: AnyFloatArray, y: AnyFloatArray, z: AnyFloatArray, s: Sizes) -> AnyFloatArray:
    off = y - np.clip(y, -s[0], s[0])  # the segment runs from (0, −h, 0) to (0, h, 0)
    return np.sqrt(x * x + off * off + z * z) - s[1]


def _norm3(s: Sizes) -> float:
    return math.sqrt(s[0] ** 2 + s[1] ** 2 + s[2] ** 2)


_M = "m"
# fmt: off
_BUILT_IN = (
    PrimitiveSpec(
        "sphere", "Sphere", 0, (("radius", _M),),
        lambda p, s: _sd_sphere(p, s[0]),
        lambda s: s[0],
        lambda s: (s[0], s[0], s[0]),
        "sd_sphere", "p, s.x", fused=True, distance_xyz=_sphere_xyz,
        meaning="a = radius",
    ),
    PrimitiveSpec(
        "box", "Box", 1, (("half_x", _M), ("half_y", _M), ("half_z", _M)),
        lambda p, s: _sd_box(p, s),
        _norm3,
        lambda s: (s[0], s[1], s[2]),
        "sd_box", "p, s", fused=True, distance_xyz=_box_xyz,
        meaning="a, b, c = half sizes along local x, y, z",
    ),
    PrimitiveSpec(
        "torus", "Torus", 2, (("major_radius", _M), ("minor_radius", _M)),
        lambda p, s: _sd_torus(p, s[0], s[1]),
        lambda s: s[0] + s[1],
        lambda s: (s[0] + s[1], s[1], s[0] + s[1]),
        "sd_torus", "p, s.x, s.y", fused=True, distance_xyz=_torus_xyz,
        meaning="a = major radius, b = tube radius (ring in the local xz plane)",
    ),
    PrimitiveSpec(
        "capsule", "Capsule", 3, (("half_length", _M), ("radius", _M)),
        lambda p, s: _sd_capsule(p, np.array([0.0, -s[0], 0.0]), np.array([0.0, s[0], 0.0]), s[1]),
        lambda s: s[0] + s[1],
        lambda s: (s[1], s[0] + s[1], s[1]),
        "sd_capsule", "p, vec3(0.0, -s.x, 0.0), vec3(0.0, s.x, 0.0), s.y",
        fused=True, distance_xyz=_capsule_xyz,
        meaning="a = half length along local y, b = radius",
    ),
    PrimitiveSpec(
        "cylinder", "Cylinder", 4, (("half_height", _M), ("radius", _M)),
        lambda p, s: _sd_cylinder(p, s[0], s[1]),
        lambda s: math.hypot(s[0], s[1]),
        lambda s: (s[1], s[0], s[1]),
        "sd_cylinder", "p, s.x, s.y",
        meaning="a = half height along local y, b = radius",
    ),
    PrimitiveSpec(
        "round_box", "Round box", 5, (("half_x", _M), ("half_y", _M), ("half_z", _M)),
        lambda p, s: _sd_round_box(p, s, ROUND_BOX_ROUNDING * min(s)),
        _norm3,
        lambda s: (s[0], s[1], s[2]),
        "sd_round_box", "p, s, ROUND_BOX_ROUNDING * min(s.x, min(s.y, s.z))",
        meaning="a, b, c = half sizes, edges rounded by a quarter of the smallest",
    ),
    PrimitiveSpec(
        "octahedron", "Octahedron", 6, (("size", _M),),
        lambda p, s: _sd_octahedron(p, s[0]),
        lambda s: s[0],
        lambda s: (s[0], s[0], s[0]),
        "sd_octahedron", "p, s.x",
        meaning="a = centre to vertex",
    ),
    PrimitiveSpec(
        "cone", "Cone", 7, (("radius", _M), ("height", _M)),
        lambda p, s: _sd_cone(p, s[0], s[1]),
        lambda s: math.hypot(s[0], s[1] / 2),
        lambda s: (s[0], s[1] / 2, s[0]),
        "sd_cone", "p, s.x, s.y",
        meaning="a = base radius, b = height, along local y",
    ),
    PrimitiveSpec(
        "hex_prism", "Hexagonal prism", 8, (("apothem", _M), ("half_height", _M)),
        lambda p, s: _sd_hex_prism(p, s[0], s[1]),
        lambda s: math.hypot(2 * s[0] / math.sqrt(3.0), s[1]),
        lambda s: (2 * s[0] / math.sqrt(3.0), s[0], s[1]),
        "sd_hex_prism", "p, s.x, s.y",
        meaning="a = centre to flat side, b = half height along local z",
    ),
    # A scene's ellipsoid uses the 1-Lipschitz bound: Quilez's estimate is not 1-Lipschitz when elongated.
    PrimitiveSpec(
        "ellipsoid", "Ellipsoid (bound)", 9, (("radius_x", _M), ("radius_y", _M), ("radius_z", _M)),
        lambda p, s: _sd_ellipsoid_lipschitz(p, s),
        lambda s: max(s),
        lambda s: (s[0], s[1], s[2]),
        "sd_ellipsoid_lipschitz", "p, s",
        meaning="a, b, c = semi-axes (a distance bound, not exact)",
    ),
)
# fmt: on

PRIMITIVES: dict[str, PrimitiveSpec] = {spec.kind: spec for spec in _BUILT_IN}
"""Every kind a scene primitive may be, by name, in code order: the built-in ten and any registered since."""
BUILT_IN_KINDS: tuple[PrimitiveKind, ...] = tuple(spec.kind for spec in _BUILT_IN)


def primitive_kinds() -> tuple[str, ...]:
    """The names of every registered kind, in code order."""
    return tuple(PRIMITIVES)


def primitive_spec(kind: str) -> PrimitiveSpec:
    """The registry entry of ``kind``, or ``ValueError`` naming the kinds there are."""
    spec = PRIMITIVES.get(kind) if isinstance(kind, str) else None
    if spec is None:
        raise ValueError(f"kind must be one of {primitive_kinds()}, got {_checks.shown(kind)}")
    return spec


def register_primitive(spec: PrimitiveSpec) -> None:
    """Add a kind to :data:`PRIMITIVES`: a new name and the next free code, 1 to 3 sizes, not ``fused``.

    Its GLSL function must be defined in ``spec.glsl_file`` (or already in ``shaders/sdf.glsl``); renderers created
    afterwards dispatch to it.
    """
    _checks.instance("spec", spec, PrimitiveSpec)
    if not isinstance(spec.kind, str) or not spec.kind.isidentifier():
        raise ValueError(f"kind must be a name (a Python identifier), got {_checks.shown(spec.kind)}")
    if spec.kind in PRIMITIVES:
        raise ValueError(f"kind {_checks.shown(spec.kind)} is already registered")
    next_code = max(s.code for s in PRIMITIVES.values()) + 1
    if spec.code != next_code:
        raise ValueError(f"code must be the next free code {next_code}, got {_checks.shown(spec.code)}")
    if not 1 <= spec.size_count <= 3:
        raise ValueError(f"sizes must name 1 to 3 parameters, got {spec.size_count}")
    if spec.fused:
        raise ValueError("fused must be False: only the built-in four share sdf.glsl's one formula")
    if not spec.glsl_function.isidentifier():
        raise ValueError(f"glsl_function must be a GLSL name, got {_checks.shown(spec.glsl_function)}")
    PRIMITIVES[spec.kind] = spec


def unregister_primitive(kind: str) -> None:
    """Remove a kind added by :func:`register_primitive` (the built-in ten stay)."""
    _checks.choice("kind", kind, primitive_kinds())
    if kind in BUILT_IN_KINDS:
        raise ValueError(f"kind {_checks.shown(kind)} is built in")
    primitive_spec(kind)
    del PRIMITIVES[kind]
