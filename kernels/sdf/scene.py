"""A scene of up to four primitives folded by booleans, its distance bound and colours, and sphere tracing.

Points are ``(N, 3)`` float arrays in metres; distances are ``(N,)`` in metres, negative inside. A primitive's
distance is evaluated in its local frame, ``p_local = Rᵀ·(p_world − centre)`` with ``R`` the rotation of its
``wxyz`` quaternion, so every primitive stays an exact distance after a rigid move.

A :class:`Scene` folds its primitives in order: the first starts the shape (its ``op`` is not used) and each later
one combines with the shape so far by its ``op`` (:func:`kernels.sdf.blend.combine_weighted`), with one blend width
``k`` (m) and form. The same weights blend the primitives' colours in :func:`scene_color`. Every blend keeps the
field 1-Lipschitz, a distance bound, which sphere tracing relies on.

Sources: I. Quilez, "distance functions" and "smooth minimum" (iquilezles.org, 2008–2024); J. C. Hart, "Sphere
tracing", The Visual Computer 12 (1996).
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from kernels import _checks
from kernels.sdf.blend import BLEND_FORMS, BOOLEAN_OPS, BlendForm, BooleanOp, combine_weighted
from kernels.sdf.primitives import (
    MAX_COORDINATE,
    FloatArray,
    PrimitiveKind,
    coordinates,
    lengths,
    position,
    primitive_kinds,
    primitive_spec,
)

MAX_PRIMITIVES = 4
MAX_BLEND_WIDTH = 1e6
"""Widest blend a :class:`Scene` takes (m). A union blended over k reaches k/4 beyond its primitives, so the mesh's
grid spans about k: past ~1e18 m float32 squares of its coordinates overflow and the field is lost (the mesh came out
empty from k ≈ 1e19). 1000 km is far beyond any gallery scene yet keeps every float32 value small."""


def unit_quaternion(name: str, value: ArrayLike) -> FloatArray:
    """(4,) unit quaternion (w, x, y, z) from 4 finite real numbers not all zero, else ``ValueError`` naming
    ``name``. It is scaled by its largest component before its norm is taken, so a huge one (1e300) does not
    overflow the norm to inf and a tiny one (1e-300) does not underflow it to zero."""
    return _checks.direction(name, value, 4, "quaternion (w, x, y, z)")


def rotation_matrix(wxyz: ArrayLike) -> FloatArray:
    """(3, 3) rotation of a quaternion (w, x, y, z) of any finite non-zero length; it is normalised first."""
    w, x, y, z = unit_quaternion("wxyz", wxyz)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


@dataclasses.dataclass(frozen=True)
class Primitive:
    """One primitive of a scene; validated on construction (ValueError naming the field)."""

    kind: PrimitiveKind
    """One of :data:`kernels.sdf.primitives.PRIMITIVES` (the built-in ten or a registered kind)."""
    center: tuple[float, float, float]
    """Position of the local origin in the world (m)."""
    size: tuple[float, ...]
    """The kind's parameters (m): sphere (radius,); box (hx, hy, hz); torus (major, minor); capsule (half length,
    radius), the segment running along local y; cylinder (half height, radius) along y; round_box (hx, hy, hz),
    rounded by ROUND_BOX_ROUNDING of the smallest; octahedron (size,); cone (base radius, height) along y;
    hex_prism (apothem, half height) along z; ellipsoid (rx, ry, rz), by :func:`sd_ellipsoid_lipschitz` (a bound
    that keeps the scene 1-Lipschitz, which Quilez's estimate does not for an elongated ellipsoid). A kind of one
    parameter also takes it as a bare number (``0.5`` for ``(0.5,)``)."""
    rotation: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)
    """Orientation as a unit quaternion (w, x, y, z), local to world; normalised on construction."""
    color: tuple[float, float, float] = (0.8, 0.8, 0.8)
    """Linear RGB in [0, 1]."""
    op: BooleanOp = "union"
    """How it combines with the shape made by the primitives before it (unused for the first)."""

    def __post_init__(self) -> None:
        _checks.choice("kind", self.kind, primitive_kinds())
        _checks.choice("op", self.op, BOOLEAN_OPS)
        center = position("center", self.center)
        count = primitive_spec(self.kind).size_count
        size = _checks.finite_array("size", self.size)
        if size.ndim == 0 and count == 1:  # a bare number: the one parameter (a sphere's radius)
            size = size.reshape(1)
        if size.shape != (count,):
            values = "one value" if count == 1 else f"{count} values"
            article = "an" if self.kind[0] in "aeiou" else "a"
            raise ValueError(f"size of {article} {self.kind} must have {values}, got {_checks.shown(self.size)}")
        size = lengths("size", size.tolist(), count)
        q = unit_quaternion("rotation", self.rotation)
        color = _checks.vector("color", self.color, 3)
        if np.any(color < 0.0) or np.any(color > 1.0):
            raise ValueError(f"color must lie in [0, 1], got {color.tolist()}")
        object.__setattr__(self, "center", tuple(float(v) for v in center))
        object.__setattr__(self, "size", tuple(float(v) for v in size))
        object.__setattr__(self, "rotation", tuple(float(v) for v in q))
        object.__setattr__(self, "color", tuple(float(v) for v in color))

    @property
    def bounding_radius(self) -> float:
        """Radius (m) of a sphere about ``center`` that holds the primitive."""
        return primitive_spec(self.kind).bounding_radius(self.size)

    def local_distance(self, p_local: FloatArray) -> FloatArray:
        """(N,) distance of (N, 3) points given in this primitive's local frame."""
        return primitive_spec(self.kind).distance(p_local, self.size)

    def distance(self, points: FloatArray) -> FloatArray:
        """(N,) distance of (N, 3) world points."""
        return self.distance_xyz(points[:, 0], points[:, 1], points[:, 2]).astype(np.float64, copy=False)

    @functools.cached_property
    def _turned(self) -> FloatArray | None:
        """The (3, 3) :func:`rotation_matrix` of ``rotation``, or None for none; built once per primitive (a mesh
        evaluates the field a dozen times, and building it took 10 % of a 32³ preview)."""
        r = rotation_matrix(self.rotation)
        return None if np.array_equal(r, np.eye(3)) else r

    def distance_xyz(
        self, x: NDArray[np.floating], y: NDArray[np.floating], z: NDArray[np.floating]
    ) -> NDArray[np.floating]:
        """Distance of world points given as coordinate arrays (any float dtype, kept): the scene's fast path.

        The kind's coordinate fast path where it has one (no (N, 3) temporaries, no re-validation), else its
        ``sd_*`` function; the tests hold the two equal.
        """
        r = self._turned
        dx, dy, dz = x - self.center[0], y - self.center[1], z - self.center[2]
        if r is None:
            lx, ly, lz = dx, dy, dz
        else:  # p_local = Rᵀ·(p − c)
            lx = dx * r[0, 0] + dy * r[1, 0] + dz * r[2, 0]
            ly = dx * r[0, 1] + dy * r[1, 1] + dz * r[2, 1]
            lz = dx * r[0, 2] + dy * r[1, 2] + dz * r[2, 2]
        spec = primitive_spec(self.kind)
        if spec.distance_xyz is not None:
            return spec.distance_xyz(lx, ly, lz, self.size)
        # The other kinds: their sd_* function on stacked local points.
        local = np.stack([lx, ly, lz], axis=1).astype(np.float64)
        return spec.distance(local, self.size).astype(x.dtype, copy=False)


@dataclasses.dataclass(frozen=True)
class Scene:
    """Up to four primitives folded in order, with one blend width and form."""

    primitives: tuple[Primitive, ...]
    """One to four primitives; the first starts the shape."""
    k: float = 0.25
    """Blend width (m), ≥ 0; 0 gives hard booleans."""
    blend: BlendForm = "poly"
    """"poly" (the polynomial smooth minimum) or "exp" (the exponential one, sharpness 4·ln 2 / k)."""

    def __post_init__(self) -> None:
        if not isinstance(self.primitives, (tuple, list)):
            raise ValueError(f"primitives must be a tuple of Primitive, got {type(self.primitives).__name__}")
        prims = tuple(self.primitives)
        if not 1 <= len(prims) <= MAX_PRIMITIVES:
            raise ValueError(f"primitives must hold 1 to {MAX_PRIMITIVES}, got {len(prims)}")
        if not all(isinstance(p, Primitive) for p in prims):
            raise ValueError(f"primitives must all be Primitive, got {[type(p).__name__ for p in prims]}")
        _checks.choice("blend", self.blend, BLEND_FORMS)
        object.__setattr__(self, "primitives", prims)
        k = _checks.non_negative("k", self.k)
        if k > MAX_BLEND_WIDTH:
            raise ValueError(f"k must be at most MAX_BLEND_WIDTH = {MAX_BLEND_WIDTH:g} m, got {_checks.shown(self.k)}")
        object.__setattr__(self, "k", k)


def _fold(scene: Scene, points: FloatArray, with_color: bool) -> tuple[FloatArray, FloatArray | None]:
    x, y, z = (np.ascontiguousarray(points[:, i]) for i in range(3))  # strided columns are several times slower
    d, color = fold_xyz(scene, x, y, z, with_color)
    return d.astype(np.float64, copy=False), None if color is None else color.astype(np.float64, copy=False)


def fold_xyz(
    scene: Scene, x: NDArray[np.floating], y: NDArray[np.floating], z: NDArray[np.floating], with_color: bool
) -> tuple[NDArray[np.floating], NDArray[np.floating] | None]:
    """The scene's distances (and colours when ``with_color``) at points given as coordinate arrays.

    Args:
        scene: the scene.
        x: (N,) world x (m), any float dtype; the results keep it (float32 for the mesher's grid).
        y: (N,) world y (m).
        z: (N,) world z (m).
        with_color: also blend the colours.

    Returns:
        (N,) distances (m) and (N, 3) RGB in [0, 1], or None without ``with_color``.
    """
    _checks.instance("scene", scene, Scene)
    _checks.flag("with_color", with_color)
    first = scene.primitives[0]
    # A point far enough away (|p| beyond ~1e154 m in float64, ~1e19 m in float32) has an infinite distance; the
    # blends take infinities without NaN, so that is the answer there, not a warning. Beyond MAX_COORDINATE a
    # primitive's formula may meet inf − inf (the octahedron's and the cone's at 1e308 m): its NaN is that infinity,
    # as such a point lies outside every primitive.
    far = max(float(np.abs(c).max(initial=0.0)) for c in (x, y, z)) > MAX_COORDINATE

    def distance(prim: Primitive) -> NDArray[np.floating]:
        d = prim.distance_xyz(x, y, z)
        return np.where(np.isnan(d), np.inf, d) if far else d

    with np.errstate(over="ignore"), np.errstate(invalid="ignore") if far else contextlib.nullcontext():
        d = distance(first)
        color = np.tile(np.asarray(first.color, dtype=d.dtype), (len(d), 1)) if with_color else None
        for prim in scene.primitives[1:]:
            d, w = combine_weighted(d, distance(prim), prim.op, scene.k, scene.blend)
            if color is not None:
                color += w[:, None] * (np.asarray(prim.color, dtype=d.dtype) - color)
    return d, color


def scene_distance(scene: Scene, points: ArrayLike) -> FloatArray:
    """The scene's distance bound at world points.

    Args:
        scene: the scene.
        points: (N, 3) world points (m).

    Returns:
        (N,) signed distances (m): exact for one primitive or hard unions away from seams, a 1-Lipschitz bound
        otherwise.
    """
    _checks.instance("scene", scene, Scene)
    return _fold(scene, _checks.points("points", points), with_color=False)[0]


def scene_color(scene: Scene, points: ArrayLike) -> FloatArray:
    """The primitives' colours blended by the same weights as the distances.

    Args:
        scene: the scene.
        points: (N, 3) world points (m).

    Returns:
        (N, 3) RGB in [0, 1].
    """
    _checks.instance("scene", scene, Scene)
    color = _fold(scene, _checks.points("points", points), with_color=True)[1]
    assert color is not None
    return color


def scene_bounds(scene: Scene) -> FloatArray:
    """(2, 3) box (min corner, max corner) in metres that holds the scene with room for the blend."""
    _checks.instance("scene", scene, Scene)
    centers = np.array([p.center for p in scene.primitives])
    radii = np.array([p.bounding_radius for p in scene.primitives])
    lo = (centers - radii[:, None]).min(axis=0)
    hi = (centers + radii[:, None]).max(axis=0)
    # A union dips at most k/4 per blend (poly) or k/2 over four (exp); pad by k plus 5 % of the size.
    pad = scene.k + 0.05 * float((hi - lo).max())
    return np.stack([lo - pad, hi + pad])


# ------------------------------------------------------------------------------------------ sphere tracing
def scene_bounding_spheres(scene: Scene) -> tuple[FloatArray, FloatArray]:
    """Spheres whose union holds the scene: (P, 3) centres and (P,) radii in metres.

    Each primitive's bounding sphere grown by the blend width k: a smooth union reaches at most 3k/4 beyond the
    primitives (k/4 per blend), and subtraction and intersection only remove. Rays that miss every sphere miss the
    scene; marching runs from the first entry to the last exit. 1 mm of slack covers float32 in the shader.
    """
    _checks.instance("scene", scene, Scene)
    centers = np.array([p.center for p in scene.primitives], dtype=np.float64)
    radii = np.array([p.bounding_radius for p in scene.primitives]) + scene.k + 1e-3
    return centers, radii


def ray_spheres_interval(
    origins: FloatArray, directions: FloatArray, centers: FloatArray, radii: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Where unit rays first enter and last leave a union of spheres.

    Args:
        origins: (N, 3) ray origins (m).
        directions: (N, 3) unit directions.
        centers: (P, 3) sphere centres (m).
        radii: (P,) radii (m).

    Returns:
        (N,) t_enter ≥ 0 and (N,) t_exit (m); t_exit < t_enter where a ray meets no sphere ahead of it.

    Every coordinate and radius lies within ±:data:`~kernels.sdf.primitives.MAX_COORDINATE` (and the directions'
    components within ±1), so the squares below stay finite.
    """
    origins = coordinates("origins", origins)
    directions = _unit_directions("directions", directions, len(origins))
    centers = coordinates("centers", centers)
    radii = _checks.bounded_array("radii", radii, MAX_COORDINATE)
    if radii.shape != (len(centers),) or np.any(radii < 0.0):
        raise ValueError(f"radii must be ({len(centers)},) lengths ≥ 0, got {_checks.shown(radii)}")
    oc = origins[:, None, :] - centers[None, :, :]
    b = np.einsum("npk,nk->np", oc, directions)
    c = np.einsum("npk,npk->np", oc, oc) - radii[None, :] ** 2
    disc = b * b - c
    root = np.sqrt(np.maximum(disc, 0.0))
    exit_ = -b + root
    ahead = (disc >= 0.0) & (exit_ >= 0.0)
    t_enter = np.where(ahead, np.maximum(-b - root, 0.0), np.inf).min(axis=1)
    t_exit = np.where(ahead, exit_, -1.0).max(axis=1)
    return t_enter, t_exit


def _unit_directions(name: str, value: ArrayLike, count: int) -> FloatArray:
    """(count, 3) unit vectors (length within 1e-6 of 1), else ``ValueError`` naming ``name``."""
    d = _checks.points(name, value)
    if len(d) != count:
        raise ValueError(f"{name} must match origins' shape ({count}, 3), got {d.shape}")
    # Components within ±2 first: a longer vector is not unit, and its squares could overflow.
    if not ((np.abs(d) <= 2.0).all() and (np.abs(np.einsum("ij,ij->i", d, d) - 1.0) <= 2e-6).all()):
        raise ValueError(f"{name} must be unit vectors, got {_checks.shown(value)}")
    return d


def sphere_trace(
    scene: Scene,
    origins: ArrayLike,
    directions: ArrayLike,
    *,
    max_steps: int = 256,
    hit_epsilon: float = 1e-4,
    max_distance: float = 100.0,
) -> FloatArray:
    """March rays by the distance bound until it drops below ``hit_epsilon``·max(1, t) (Hart 1996).

    Marching runs over the part of each ray inside :func:`scene_bounding_spheres`. ``shaders/raymarch.frag`` runs
    the same loop, so the two can be compared ray by ray.

    Args:
        scene: the scene.
        origins: (N, 3) ray origins (m), outside the shape, within ±:data:`~kernels.sdf.primitives.MAX_COORDINATE`.
        directions: (N, 3) unit directions (length within 1e-6 of 1).
        max_steps: steps before a ray counts as a miss, an integer in 1..10000.
        hit_epsilon: hit threshold (m at t ≤ 1, relative beyond).
        max_distance: rays longer than this miss (m).

    Returns:
        (N,) distance along each ray to the hit (m); ``inf`` for a miss.
    """
    _checks.instance("scene", scene, Scene)
    o = coordinates("origins", origins)
    d = _unit_directions("directions", directions, len(o))
    steps = _checks.integer("max_steps", max_steps, 1)
    if steps > 10_000:
        raise ValueError(f"max_steps must be in 1..10000, got {_checks.shown(max_steps)}")
    eps = _checks.positive("hit_epsilon", hit_epsilon)
    far = _checks.positive("max_distance", max_distance)
    centers, radii = scene_bounding_spheres(scene)
    t, t_exit = ray_spheres_interval(o, d, centers, radii)
    t_exit = np.minimum(t_exit, far)
    hit = np.zeros(len(o), dtype=bool)
    active = t_exit >= t
    for _ in range(steps):
        idx = np.flatnonzero(active)
        if idx.size == 0:
            break
        dist = scene_distance(scene, o[idx] + t[idx, None] * d[idx])
        done = dist < eps * np.maximum(1.0, t[idx])
        hit[idx[done]] = True
        t[idx[~done]] += dist[~done]
        escaped = t[idx] > t_exit[idx]
        active[idx[done | escaped]] = False
    return np.where(hit, t, np.inf)


def default_scene() -> Scene:
    """The gallery's opening scene: a sphere, a box, a torus lying flat and a standing capsule, smoothly united;
    from the gallery's opening camera each is in sight, none behind another."""
    # A quarter turn about x takes local y to world z: the torus lies flat and the capsule (along local y) stands.
    flat = (math.cos(math.pi / 4), math.sin(math.pi / 4), 0.0, 0.0)
    return Scene(
        primitives=(
            Primitive("sphere", (0.0, 0.0, 0.5), (0.45,), color=(0.90, 0.35, 0.30)),
            Primitive("box", (0.6, 0.0, 0.3), (0.3, 0.3, 0.3), color=(0.30, 0.60, 0.90)),
            Primitive("torus", (0.0, 0.0, 0.1), (0.6, 0.12), rotation=flat, color=(0.95, 0.80, 0.30)),
            Primitive("capsule", (-0.55, -0.45, 0.35), (0.3, 0.14), rotation=flat, color=(0.40, 0.80, 0.45)),
        ),
        k=0.25,
        blend="poly",
    )
