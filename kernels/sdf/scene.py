"""Signed distance fields: four primitives, hard and smooth booleans, a scene of up to four, and its mesh.

Points are ``(N, 3)`` float arrays in metres; distances are ``(N,)`` in metres, negative inside. A primitive's
distance is evaluated in its local frame, ``p_local = Rᵀ·(p_world − centre)`` with ``R`` the rotation of its
``wxyz`` quaternion, so every primitive stays an exact distance after a rigid move.

Primitives (exact distances, after Inigo Quilez's list of distance functions):

    sphere   |p| − r
    box      |max(q, 0)| + min(max(q.x, q.y, q.z), 0),   q = |p| − b
    torus    |(|p.xz| − R, p.y)| − r                      (the ring lies in the local xz plane; axis local y)
    capsule  |pa − ba·h| − r,   h = clamp(pa·ba / ba·ba, 0, 1)   (a scene's capsule runs along local y)

Smooth minimum, as the seed writes it:

    smin_poly(a, b, k) = mix(b, a, h) − k·h·(1 − h),   h = clamp(0.5 + 0.5·(b − a)/k, 0, 1)   (k: blend width, m)
    smin_exp(a, b, k)  = −log(exp(−k·a) + exp(−k·b)) / k                                       (k: sharpness, 1/m)

``smin_exp`` is evaluated as ``min(a, b) − log1p(exp(−k·|a − b|))/k``, which is the same number and cannot overflow.
Both are ≤ min(a, b) and tend to it as the blend narrows (poly: k → 0; exp: k → ∞). Their derivatives are convex
weights (``h`` and ``1 − h`` for poly, a logistic for exp), so a blend of 1-Lipschitz fields is 1-Lipschitz: not an
exact distance, but a distance bound, which is what sphere tracing and the coarse-to-fine mesher rely on. The same
weights blend the primitives' colours in :func:`scene_color`.

Booleans: union ``min(a, b)``, subtraction ``max(a, −b)`` (a minus b), intersection ``max(a, b)``; the smooth forms
are ``smin(a, b)``, ``−smin(−a, b)`` and ``−smin(−a, −b)``.

A :class:`Scene` folds its primitives in order: the first starts the shape (its ``op`` is not used) and each later
one combines with the shape so far by its ``op``. One blend width ``k`` (m) serves both forms; the exponential form
uses the sharpness ``4·ln 2 / k``, which makes both forms dip by the same ``k/4`` where two surfaces meet. ``k = 0``
means hard booleans, and so does any k below ``MIN_BLEND_WIDTH`` (float32's smallest normal): every form is then
finite for every finite k ≥ 0 and tends to the hard boolean as k → 0, in float32 and float64 alike.

:func:`mesh` samples the field on a grid and runs scikit-image's marching cubes (Lewiner et al. 2003) on the float
field, which keeps sub-voxel accuracy. It evaluates the field only near the surface: a block of samples whose centre
is farther from the surface than the block's radius plus one voxel diagonal cannot hold a corner of a cell the
surface crosses (the field is 1-Lipschitz), so the block gets the sign of its centre and is not refined. Marching
cubes reads values only at corners of crossed cells, so the output equals the full-grid output exactly; it is also
told to skip cells outside the evaluated region (its ``mask``).

Sources: I. Quilez, "distance functions" and "smooth minimum" (iquilezles.org, 2008–2024); J. C. Hart, "Sphere
tracing", The Visual Computer 12 (1996); T. Lewiner et al., J. Graphics Tools 8(2) (2003).
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
import math
import numbers
from collections.abc import Callable
from typing import Literal

import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray
from skimage.measure import marching_cubes

PrimitiveKind = Literal[
    "sphere",
    "box",
    "torus",
    "capsule",
    "cylinder",
    "round_box",
    "octahedron",
    "cone",
    "hex_prism",
    "ellipsoid",
]
"""Kinds of primitive; see :attr:`Primitive.size` for what each one's sizes mean."""
BooleanOp = Literal["union", "subtract", "intersect"]
"""How a primitive combines with the shape before it."""
BlendForm = Literal["poly", "exp"]
"""Which smooth minimum blends the booleans."""

PRIMITIVE_KINDS: tuple[PrimitiveKind, ...] = (
    "sphere",
    "box",
    "torus",
    "capsule",
    "cylinder",
    "round_box",
    "octahedron",
    "cone",
    "hex_prism",
    "ellipsoid",
)
ROUND_BOX_ROUNDING = 0.25
"""A scene's round box is rounded by this fraction of its smallest half size."""
BOOLEAN_OPS: tuple[BooleanOp, ...] = ("union", "subtract", "intersect")
BLEND_FORMS: tuple[BlendForm, ...] = ("poly", "exp")
MAX_PRIMITIVES = 4
MIN_RESOLUTION = 16
MAX_RESOLUTION = 512

EXP_SHARPNESS_PER_WIDTH = 4.0 * math.log(2.0)
"""A scene's exp blend uses sharpness ``EXP_SHARPNESS_PER_WIDTH / k``: both forms then dip by k/4 where a = b."""
MIN_BLEND_WIDTH = float(np.finfo(np.float32).tiny)
"""Blend widths below this (float32's smallest normal, 1.2e-38 m) are the hard booleans, here and in the GLSL: their
dip k/4 is below any distance's rounding, a float32 uniform cannot hold them reliably (subnormal or 0), and
above it 0.5/k and the exp sharpness 4·ln 2/k stay finite in float32."""
MAX_BLEND_WIDTH = 1e6
"""Widest blend a :class:`Scene` takes (m). A union blended over k reaches k/4 beyond its primitives, so the mesh's
grid spans about k: past ~1e18 m float32 squares of its coordinates overflow and the field is lost (the mesh came out
empty from k ≈ 1e19). 1000 km is far beyond any gallery scene yet keeps every float32 value small."""
MAX_FIELD_COORDINATE = 1e18
"""Largest |coordinate| (m) of a mesh grid: float32 squares of differences of such coordinates stay finite."""

_SIZE_COUNT: dict[str, int] = {
    "sphere": 1,
    "box": 3,
    "torus": 2,
    "capsule": 2,
    "cylinder": 2,
    "round_box": 3,
    "octahedron": 1,
    "cone": 2,
    "hex_prism": 2,
    "ellipsoid": 3,
}

FloatArray = NDArray[np.float64]
AnyFloatArray = NDArray[np.floating]
"""Internal fast paths keep their input's float dtype (float32 for the mesher's grid)."""


# ------------------------------------------------------------------------------------------ input checks
def _points(p: ArrayLike, name: str = "p") -> FloatArray:
    arr = np.asarray(p, dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"{name} must have shape (N, 3), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite")
    return arr


def _real(value: float, name: str) -> float:
    """``value`` as a float when it is a real number (a string, None, a bool or a sequence is refused)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ValueError(f"{name} must be a real number, got {value!r}")
    return float(value)


def _positive(value: float, name: str) -> float:
    number = _real(value, name)
    if not math.isfinite(number) or number <= 0.0:
        raise ValueError(f"{name} must be finite and positive, got {value!r}")
    return number


def _non_negative(value: float, name: str) -> float:
    number = _real(value, name)
    if not math.isfinite(number) or number < 0.0:
        raise ValueError(f"{name} must be finite and non-negative, got {value!r}")
    return number


def _vector3(value: ArrayLike, name: str) -> FloatArray:
    arr = np.asarray(value, dtype=np.float64)
    if arr.shape != (3,):
        raise ValueError(f"{name} must have shape (3,), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite")
    return arr


def _distances(a: ArrayLike, b: ArrayLike) -> tuple[FloatArray, FloatArray]:
    a_arr, b_arr = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    if np.any(np.isnan(a_arr)):
        raise ValueError("a must not be NaN")
    if np.any(np.isnan(b_arr)):
        raise ValueError("b must not be NaN")
    return a_arr, b_arr


# ------------------------------------------------------------------------------------------ primitives
def sd_sphere(p: ArrayLike, radius: float) -> FloatArray:
    """Exact distance to a sphere at the origin.

    Args:
        p: (N, 3) points in the local frame (m).
        radius: radius (m), > 0.

    Returns:
        (N,) signed distances (m).
    """
    pts = _points(p)
    r = _positive(radius, "radius")
    return np.linalg.norm(pts, axis=1) - r


def sd_box(p: ArrayLike, half_size: ArrayLike) -> FloatArray:
    """Exact distance to an axis-aligned box centred at the origin.

    Args:
        p: (N, 3) points in the local frame (m).
        half_size: (3,) half extents along x, y, z (m), each > 0.

    Returns:
        (N,) signed distances (m).
    """
    pts = _points(p)
    b = _vector3(half_size, "half_size")
    if np.any(b <= 0.0):
        raise ValueError(f"half_size must be positive, got {b.tolist()}")
    q = np.abs(pts) - b
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
    pts = _points(p)
    big_r = _positive(major_radius, "major_radius")
    small_r = _positive(minor_radius, "minor_radius")
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
    pts = _points(p)
    a_vec, b_vec = _vector3(a, "a"), _vector3(b, "b")
    r = _positive(radius, "radius")
    pa = pts - a_vec
    ba = b_vec - a_vec
    length_sq = float(ba @ ba)
    h = np.zeros(len(pts)) if length_sq == 0.0 else np.clip(pa @ ba / length_sq, 0.0, 1.0)
    return np.linalg.norm(pa - h[:, None] * ba, axis=1) - r


# ------------------------------------------------------------------------------------------ blends
def _smin_poly_weighted(
    a: AnyFloatArray, b: AnyFloatArray, k: float
) -> tuple[AnyFloatArray, AnyFloatArray]:
    """Polynomial smooth min and the weight of ``b`` in it (``1 − h``), in the inputs' float dtype.

    Finite for every finite k ≥ 0 and finite distances, and never NaN for infinite ones: a width below
    :data:`MIN_BLEND_WIDTH` is the hard minimum; above it (b − a)/k overflows to ±inf at worst, which the clamp maps
    to 0 or 1, and is 0 where a = b (the same infinity included, instead of inf − inf). Where h is 0 or 1 the result
    is b or a outright (not 0·inf), and a width beyond the dtype's largest float is that float. The result lies
    within k/4 of min(a, b).
    """
    if not k >= MIN_BLEND_WIDTH:
        return np.minimum(a, b), (b < a).astype(np.float64)
    dtype = np.result_type(a, b)
    width = dtype.type(min(k, float(np.finfo(dtype).max)))
    with np.errstate(over="ignore", invalid="ignore"):
        gap = np.where(a == b, dtype.type(0.0), b - a)
        h = np.clip(0.5 + 0.5 * (gap / width), 0.0, 1.0)
        blended = h * a + (1.0 - h) * b - width * h * (1.0 - h)
    d = np.where(h == 0.0, b, np.where(h == 1.0, a, blended))
    return d, 1.0 - h


def _smin_exp_weighted(
    a: AnyFloatArray, b: AnyFloatArray, k: float
) -> tuple[AnyFloatArray, AnyFloatArray]:
    """Exponential smooth min (``k`` = sharpness) and the weight of ``b``: exp(−kb)/(exp(−ka) + exp(−kb)).

    Finite for every sharpness in (0, ∞] and finite distances, in the inputs' float dtype, and never NaN for
    infinite ones: a sharpness that overflows it (4·ln 2 / k for a tiny width k) is the hard minimum, with
    exp(−k·|a − b|) taken as 1 where a = b (the same infinity included) instead of exp(−∞·0); a sharpness below the
    dtype's smallest normal (a huge width, or a subnormal sharpness) is that normal, so ln 2 / k stays finite.
    """
    dtype = np.result_type(a, b)
    tiny = np.finfo(dtype).tiny
    with np.errstate(over="ignore", under="ignore"):
        sharpness = max(dtype.type(k), tiny)  # inf when it overflows the dtype
    # Overflow here is a true value beyond the dtype (a gap or a dip past its largest float), kept as ±inf.
    with np.errstate(over="ignore", invalid="ignore"):
        gap = np.where(a == b, dtype.type(0.0), np.abs(a - b))
        e = np.exp(-sharpness * gap)  # in [0, 1]; −∞·0 (NaN) only at gap 0, set below
        e = np.where(gap == 0.0, dtype.type(1.0), e)
        d = (
            np.minimum(a, b) - np.log1p(e) / sharpness
        )  # log1p(e) ≤ ln 2: → 0 as the sharpness grows
    w_b = np.where(a > b, 1.0, e) / (1.0 + e)
    return d, w_b


def smin_poly(a: ArrayLike, b: ArrayLike, k: float) -> FloatArray:
    """The seed's polynomial smooth minimum; ≤ min(a, b), equal to it where |a − b| ≥ k.

    Args:
        a: distances (m), any shape broadcastable with ``b``.
        b: distances (m).
        k: blend width (m), ≥ 0; 0 (or anything below ``MIN_BLEND_WIDTH``) is the hard minimum.

    Returns:
        Blended distances (m), the broadcast shape.
    """
    a_arr, b_arr = _distances(a, b)
    return np.asarray(_smin_poly_weighted(a_arr, b_arr, _non_negative(k, "k"))[0], dtype=np.float64)


def smin_exp(a: ArrayLike, b: ArrayLike, k: float) -> FloatArray:
    """The seed's exponential smooth minimum −log(exp(−ka) + exp(−kb))/k, evaluated without overflow.

    Args:
        a: distances (m), any shape broadcastable with ``b``.
        b: distances (m).
        k: sharpness (1/m), > 0; larger is sharper (→ min(a, b) as k → ∞).

    Returns:
        Blended distances (m), ≤ min(a, b) − 0 and ≥ min(a, b) − ln 2 / k.
    """
    a_arr, b_arr = _distances(a, b)
    return np.asarray(_smin_exp_weighted(a_arr, b_arr, _positive(k, "k"))[0], dtype=np.float64)


def op_union(a: ArrayLike, b: ArrayLike) -> FloatArray:
    """Hard union min(a, b)."""
    a_arr, b_arr = _distances(a, b)
    return np.minimum(a_arr, b_arr)


def op_subtract(a: ArrayLike, b: ArrayLike) -> FloatArray:
    """Hard subtraction: ``a`` with ``b`` cut away, max(a, −b)."""
    a_arr, b_arr = _distances(a, b)
    return np.maximum(a_arr, -b_arr)


def op_intersect(a: ArrayLike, b: ArrayLike) -> FloatArray:
    """Hard intersection max(a, b)."""
    a_arr, b_arr = _distances(a, b)
    return np.maximum(a_arr, b_arr)


def _combine(
    a: AnyFloatArray, b: AnyFloatArray, op: BooleanOp, k: float, blend: BlendForm
) -> tuple[AnyFloatArray, AnyFloatArray]:
    """Distance of ``a op b`` and the weight of ``b`` in it; ``k`` is the blend width (m), 0 for hard."""

    def smin(x: AnyFloatArray, y: AnyFloatArray) -> tuple[AnyFloatArray, AnyFloatArray]:
        if k < MIN_BLEND_WIDTH:  # 0 and tiny widths: the hard boolean, as in the GLSL
            return _smin_poly_weighted(x, y, 0.0)
        match blend:
            case "poly":
                return _smin_poly_weighted(x, y, k)
            case "exp":
                return _smin_exp_weighted(x, y, EXP_SHARPNESS_PER_WIDTH / k)
            case _:
                raise ValueError(f"blend must be one of {BLEND_FORMS}, got {blend!r}")

    if blend not in BLEND_FORMS:  # also for k = 0, which never reaches the match above
        raise ValueError(f"blend must be one of {BLEND_FORMS}, got {blend!r}")
    match op:
        case "union":
            return smin(a, b)
        case "subtract":
            d, w = smin(-a, b)
            return -d, w
        case "intersect":
            d, w = smin(-a, -b)
            return -d, w
        case _:
            raise ValueError(f"op must be one of {BOOLEAN_OPS}, got {op!r}")


def smooth_union(a: ArrayLike, b: ArrayLike, k: float, blend: BlendForm = "poly") -> FloatArray:
    """Smooth union ``smin(a, b)``; ``k`` is the blend width (m), 0 for the hard union."""
    a_arr, b_arr = _distances(a, b)
    return np.asarray(
        _combine(a_arr, b_arr, "union", _non_negative(k, "k"), blend)[0], dtype=np.float64
    )


def smooth_subtract(a: ArrayLike, b: ArrayLike, k: float, blend: BlendForm = "poly") -> FloatArray:
    """Smooth subtraction, ``a`` minus ``b``: −smin(−a, b); ``k`` is the blend width (m)."""
    a_arr, b_arr = _distances(a, b)
    return np.asarray(
        _combine(a_arr, b_arr, "subtract", _non_negative(k, "k"), blend)[0], dtype=np.float64
    )


def smooth_intersect(a: ArrayLike, b: ArrayLike, k: float, blend: BlendForm = "poly") -> FloatArray:
    """Smooth intersection −smin(−a, −b); ``k`` is the blend width (m)."""
    a_arr, b_arr = _distances(a, b)
    return np.asarray(
        _combine(a_arr, b_arr, "intersect", _non_negative(k, "k"), blend)[0], dtype=np.float64
    )


# ------------------------------------------------------------------------------------------ scene
def rotation_matrix(wxyz: ArrayLike) -> FloatArray:
    """(3, 3) rotation of a unit quaternion (w, x, y, z); it is normalised first."""
    q = np.asarray(wxyz, dtype=np.float64)
    if q.shape != (4,) or not np.all(np.isfinite(q)):
        raise ValueError(f"rotation must be 4 finite numbers (w, x, y, z), got {q.tolist()}")
    norm = float(np.linalg.norm(q))
    if norm < 1e-9:
        raise ValueError("rotation must be a non-zero quaternion")
    w, x, y, z = q / norm
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
    """"sphere" | "box" | "torus" | "capsule"."""
    center: tuple[float, float, float]
    """Position of the local origin in the world (m)."""
    size: tuple[float, ...]
    """The kind's parameters (m): sphere (radius,); box (hx, hy, hz); torus (major, minor); capsule (half length,
    radius), the segment running along local y; cylinder (half height, radius) along y; round_box (hx, hy, hz),
    rounded by ROUND_BOX_ROUNDING of the smallest; octahedron (size,); cone (base radius, height) along y;
    hex_prism (apothem, half height) along z; ellipsoid (rx, ry, rz), by :func:`sd_ellipsoid_lipschitz` (a bound
    that keeps the scene 1-Lipschitz, which Quilez's estimate does not for an elongated ellipsoid)."""
    rotation: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)
    """Orientation as a unit quaternion (w, x, y, z), local to world; normalised on construction."""
    color: tuple[float, float, float] = (0.8, 0.8, 0.8)
    """Linear RGB in [0, 1]."""
    op: BooleanOp = "union"
    """How it combines with the shape made by the primitives before it (unused for the first)."""

    def __post_init__(self) -> None:
        if self.kind not in PRIMITIVE_KINDS:
            raise ValueError(f"kind must be one of {PRIMITIVE_KINDS}, got {self.kind!r}")
        if self.op not in BOOLEAN_OPS:
            raise ValueError(f"op must be one of {BOOLEAN_OPS}, got {self.op!r}")
        center = _vector3(self.center, "center")
        size = np.asarray(self.size, dtype=np.float64)
        if size.shape != (_SIZE_COUNT[self.kind],):
            raise ValueError(
                f"size of a {self.kind} must have {_SIZE_COUNT[self.kind]} values, got {size.shape}"
            )
        if not np.all(np.isfinite(size)) or np.any(size <= 0.0):
            raise ValueError(f"size must be finite and positive, got {size.tolist()}")
        rotation = rotation_matrix(self.rotation)  # raises for a bad quaternion
        del rotation
        q = np.asarray(self.rotation, dtype=np.float64)
        color = _vector3(self.color, "color")
        if np.any(color < 0.0) or np.any(color > 1.0):
            raise ValueError(f"color must lie in [0, 1], got {color.tolist()}")
        object.__setattr__(self, "center", tuple(float(v) for v in center))
        object.__setattr__(self, "size", tuple(float(v) for v in size))
        object.__setattr__(self, "rotation", tuple(float(v) for v in q / np.linalg.norm(q)))
        object.__setattr__(self, "color", tuple(float(v) for v in color))

    @property
    def bounding_radius(self) -> float:
        """Radius (m) of a sphere about ``center`` that holds the primitive."""
        s = self.size
        match self.kind:
            case "sphere":
                return s[0]
            case "box":
                return math.sqrt(s[0] ** 2 + s[1] ** 2 + s[2] ** 2)
            case "torus":
                return s[0] + s[1]
            case "capsule":
                return s[0] + s[1]
            case "cylinder":
                return math.hypot(s[0], s[1])
            case "round_box":
                return math.sqrt(s[0] ** 2 + s[1] ** 2 + s[2] ** 2)
            case "octahedron":
                return s[0]
            case "cone":
                return math.hypot(s[0], s[1] / 2)
            case "hex_prism":
                return math.hypot(2 * s[0] / math.sqrt(3.0), s[1])
            case "ellipsoid":
                return max(s)

    def local_distance(self, p_local: FloatArray) -> FloatArray:
        """(N,) distance of (N, 3) points given in this primitive's local frame."""
        s = self.size
        match self.kind:
            case "sphere":
                return sd_sphere(p_local, s[0])
            case "box":
                return sd_box(p_local, s)
            case "torus":
                return sd_torus(p_local, s[0], s[1])
            case "capsule":
                return sd_capsule(p_local, (0.0, -s[0], 0.0), (0.0, s[0], 0.0), s[1])
            case "cylinder":
                return sd_cylinder(p_local, s[0], s[1])
            case "round_box":
                return sd_round_box(p_local, s, ROUND_BOX_ROUNDING * min(s))
            case "octahedron":
                return sd_octahedron(p_local, s[0])
            case "cone":
                return sd_cone(p_local, s[0], s[1])
            case "hex_prism":
                return sd_hex_prism(p_local, s[0], s[1])
            case "ellipsoid":
                return sd_ellipsoid_lipschitz(p_local, s)

    def distance(self, points: FloatArray) -> FloatArray:
        """(N,) distance of (N, 3) world points."""
        return self._distance_xyz(points[:, 0], points[:, 1], points[:, 2]).astype(
            np.float64, copy=False
        )

    @functools.cached_property
    def _turned(self) -> FloatArray | None:
        """The (3, 3) :func:`rotation_matrix` of ``rotation``, or None for none; built once per primitive (a mesh
        evaluates the field a dozen times, and building it took 10 % of a 32³ preview)."""
        r = rotation_matrix(self.rotation)
        return None if np.array_equal(r, np.eye(3)) else r

    def _distance_xyz(
        self, x: NDArray[np.floating], y: NDArray[np.floating], z: NDArray[np.floating]
    ) -> NDArray[np.floating]:
        """Distance of world points given as coordinate arrays (any float dtype, kept): the scene's fast path.

        The same formulas as the ``sd_*`` functions, written per coordinate (no (N, 3) temporaries, no
        re-validation); the tests hold the two equal.
        """
        r = self._turned
        dx, dy, dz = x - self.center[0], y - self.center[1], z - self.center[2]
        if r is None:
            lx, ly, lz = dx, dy, dz
        else:  # p_local = Rᵀ·(p − c)
            lx = dx * r[0, 0] + dy * r[1, 0] + dz * r[2, 0]
            ly = dx * r[0, 1] + dy * r[1, 1] + dz * r[2, 1]
            lz = dx * r[0, 2] + dy * r[1, 2] + dz * r[2, 2]
        s = self.size
        match self.kind:
            case "sphere":
                return np.sqrt(lx * lx + ly * ly + lz * lz) - s[0]
            case "box":
                qx, qy, qz = np.abs(lx) - s[0], np.abs(ly) - s[1], np.abs(lz) - s[2]
                ox, oy, oz = np.maximum(qx, 0.0), np.maximum(qy, 0.0), np.maximum(qz, 0.0)
                inside = np.minimum(np.maximum(np.maximum(qx, qy), qz), 0.0)
                return np.sqrt(ox * ox + oy * oy + oz * oz) + inside
            case "torus":
                qx = np.sqrt(lx * lx + lz * lz) - s[0]
                return np.sqrt(qx * qx + ly * ly) - s[1]
            case "capsule":  # the segment runs from (0, −h, 0) to (0, h, 0)
                off = ly - np.clip(ly, -s[0], s[0])
                return np.sqrt(lx * lx + off * off + lz * lz) - s[1]
            case _:  # the catalogue's kinds: their sd_* function on stacked local points
                local = np.stack([lx, ly, lz], axis=1).astype(np.float64)
                return self.local_distance(local).astype(x.dtype, copy=False)


@dataclasses.dataclass(frozen=True)
class Scene:
    """Up to four primitives folded in order, with one blend width and form."""

    primitives: tuple[Primitive, ...]
    """One to four primitives; the first starts the shape."""
    k: float = 0.25
    """Blend width (m), ≥ 0; 0 gives hard booleans."""
    blend: BlendForm = "poly"
    """"poly" (the seed's polynomial smin) or "exp" (its exponential smin, sharpness 4·ln 2 / k)."""

    def __post_init__(self) -> None:
        prims = tuple(self.primitives)
        if not 1 <= len(prims) <= MAX_PRIMITIVES:
            raise ValueError(f"primitives must hold 1 to {MAX_PRIMITIVES}, got {len(prims)}")
        if not all(isinstance(p, Primitive) for p in prims):
            raise ValueError("primitives must all be Primitive")
        if self.blend not in BLEND_FORMS:
            raise ValueError(f"blend must be one of {BLEND_FORMS}, got {self.blend!r}")
        object.__setattr__(self, "primitives", prims)
        k = _non_negative(self.k, "k")
        if k > MAX_BLEND_WIDTH:
            raise ValueError(
                f"k must be at most MAX_BLEND_WIDTH = {MAX_BLEND_WIDTH:g} m, got {self.k!r}"
            )
        object.__setattr__(self, "k", k)


def _fold(
    scene: Scene, points: FloatArray, with_color: bool
) -> tuple[FloatArray, FloatArray | None]:
    x, y, z = (
        np.ascontiguousarray(points[:, i]) for i in range(3)
    )  # strided columns are several times slower
    d, color = _fold_xyz(scene, x, y, z, with_color)
    return d.astype(np.float64, copy=False), None if color is None else color.astype(
        np.float64, copy=False
    )


def _fold_xyz(
    scene: Scene,
    x: NDArray[np.floating],
    y: NDArray[np.floating],
    z: NDArray[np.floating],
    with_color: bool,
) -> tuple[NDArray[np.floating], NDArray[np.floating] | None]:
    first = scene.primitives[0]
    # A point far enough away (|p| beyond ~1e154 m in float64, ~1e19 m in float32) has an infinite distance; the
    # blends take infinities without NaN, so that is the answer there, not a warning.
    with np.errstate(over="ignore"):
        d = first._distance_xyz(x, y, z)
        color = np.tile(np.asarray(first.color, dtype=d.dtype), (len(d), 1)) if with_color else None
        for prim in scene.primitives[1:]:
            d, w = _combine(d, prim._distance_xyz(x, y, z), prim.op, scene.k, scene.blend)
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
    return _fold(scene, _points(points, "points"), with_color=False)[0]


def scene_color(scene: Scene, points: ArrayLike) -> FloatArray:
    """The primitives' colours blended by the same weights as the distances.

    Args:
        scene: the scene.
        points: (N, 3) world points (m).

    Returns:
        (N, 3) RGB in [0, 1].
    """
    color = _fold(scene, _points(points, "points"), with_color=True)[1]
    assert color is not None
    return color


def scene_bounds(scene: Scene) -> FloatArray:
    """(2, 3) box (min corner, max corner) in metres that holds the scene with room for the blend."""
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
    """
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
        origins: (N, 3) ray origins (m), outside the shape.
        directions: (N, 3) unit directions.
        max_steps: steps before a ray counts as a miss.
        hit_epsilon: hit threshold (m at t ≤ 1, relative beyond).
        max_distance: rays longer than this miss (m).

    Returns:
        (N,) distance along each ray to the hit (m); ``inf`` for a miss.
    """
    o = _points(origins, "origins")
    d = _points(directions, "directions")
    if o.shape != d.shape:
        raise ValueError(f"directions must match origins' shape {o.shape}, got {d.shape}")
    if not 1 <= int(max_steps) <= 10_000:
        raise ValueError(f"max_steps must be in 1..10000, got {max_steps}")
    eps = _positive(hit_epsilon, "hit_epsilon")
    far = _positive(max_distance, "max_distance")
    centers, radii = scene_bounding_spheres(scene)
    t, t_exit = ray_spheres_interval(o, d, centers, radii)
    t_exit = np.minimum(t_exit, far)
    hit = np.zeros(len(o), dtype=bool)
    active = t_exit >= t
    for _ in range(int(max_steps)):
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


# ------------------------------------------------------------------------------------------ meshing
@dataclasses.dataclass(frozen=True)
class Grid:
    """A regular sample grid: ``origin + index·spacing``, ``shape`` samples per axis."""

    origin: tuple[float, float, float]
    """World position of sample (0, 0, 0) (m)."""
    spacing: float
    """Distance between neighbouring samples (m)."""
    shape: tuple[int, int, int]
    """Samples along x, y, z."""


def make_grid(scene: Scene, resolution: int, bounds: ArrayLike | None = None) -> Grid:
    """The grid :func:`mesh` samples: cubic voxels, ``resolution`` samples along the box's longest side.

    Args:
        scene: the scene (its bounds are used when ``bounds`` is None).
        resolution: samples along the longest side, 16..512.
        bounds: optional (2, 3) min and max corners (m).
    """
    if isinstance(resolution, bool) or not isinstance(resolution, (int, np.integer)):
        raise ValueError(f"resolution must be an integer, got {resolution!r}")
    if not MIN_RESOLUTION <= int(resolution) <= MAX_RESOLUTION:
        raise ValueError(
            f"resolution must be in {MIN_RESOLUTION}..{MAX_RESOLUTION}, got {resolution}"
        )
    if bounds is None:
        box = scene_bounds(scene)
    else:
        box = np.asarray(bounds, dtype=np.float64)
        if box.shape != (2, 3) or not np.all(np.isfinite(box)) or np.any(box[1] <= box[0]):
            raise ValueError("bounds must be finite (2, 3) min and max corners with max > min")
    if not np.all(np.abs(box) <= MAX_FIELD_COORDINATE):
        raise ValueError(
            f"bounds (given or the scene's) must lie within ±{MAX_FIELD_COORDINATE:g} m for the float32 field, "
            f"got {box.tolist()}"
        )
    extent = box[1] - box[0]
    spacing = float(extent.max()) / (int(resolution) - 1)
    counts = np.minimum(np.ceil(extent / spacing - 1e-9).astype(int) + 1, int(resolution))
    center = 0.5 * (box[0] + box[1])
    origin = center - 0.5 * (counts - 1) * spacing
    return Grid(
        origin=(float(origin[0]), float(origin[1]), float(origin[2])),
        spacing=spacing,
        shape=(int(counts[0]), int(counts[1]), int(counts[2])),
    )


def sample_full(scene: Scene, grid: Grid) -> NDArray[np.float32]:
    """The field at every grid sample, (nx, ny, nz) float32: the plain baseline the coarse-to-fine pass matches."""
    axes = [grid.origin[i] + grid.spacing * np.arange(grid.shape[i]) for i in range(3)]
    xs, ys, zs = np.meshgrid(*axes, indexing="ij")
    return _field_at(scene, np.stack([xs.ravel(), ys.ravel(), zs.ravel()], axis=1)).reshape(
        grid.shape
    )


def _field_at(scene: Scene, points: NDArray[np.floating]) -> NDArray[np.float32]:
    """The field at (N, 3) sample points, evaluated in float32 (what marching cubes reads) on coordinate arrays.

    Both samplers call this with coordinates computed the same way, so equal points give bit-equal values.
    """
    p32 = points.astype(np.float32)
    d, _ = _fold_xyz(scene, p32[:, 0].copy(), p32[:, 1].copy(), p32[:, 2].copy(), with_color=False)
    return d.astype(np.float32, copy=False)


_LEVELS = (16, 4)
"""Block sizes (samples per side) of the coarse passes; the last level's surviving blocks are sampled in full."""


@dataclasses.dataclass(frozen=True)
class NearSurfaceField:
    """The grid field from the coarse-to-fine pass."""

    field: NDArray[np.float32]
    """(nx, ny, nz) values (m): exact at every corner of a cell the surface crosses, sign-correct elsewhere."""
    mask: NDArray[np.bool_]
    """(nx, ny, nz) True where the value was evaluated exactly; it holds every corner of every crossed cell, so
    marching cubes may skip cells whose far corner is False."""
    evaluated: int
    """Points evaluated, block centres included."""


def sample_near_surface(
    scene: Scene, grid: Grid, progress: Callable[[float], None] | None = None
) -> NearSurfaceField:
    """The field, evaluated exactly where marching cubes reads it and sign-filled elsewhere.

    Args:
        scene: the scene.
        grid: the grid.
        progress: optional callback receiving the fraction done, 0..1.
    """
    h = grid.spacing
    # A corner of a crossed cell lies within one voxel diagonal of the surface.
    margin = math.sqrt(3.0) * h * (1.0 + 1e-3) + 1e-6  # slack for float32 rounding
    top = _LEVELS[0]
    padded = tuple(-(-n // top) * top for n in grid.shape)
    field = np.empty(padded, dtype=np.float32)
    origin = np.asarray(grid.origin)
    evaluated = 0

    def block_centers(corners: NDArray[np.int64], size: int) -> FloatArray:
        return origin + h * (corners + 0.5 * (size - 1)).astype(np.float64)

    def view(size: int) -> NDArray[np.float32]:
        n = [m // size for m in padded]
        return field.reshape(n[0], size, n[1], size, n[2], size)

    # Level 0: every top block, written as a whole-field fill of its centre's value.
    n0 = [m // top for m in padded]
    idx = np.stack(np.meshgrid(*[np.arange(c) for c in n0], indexing="ij"), axis=-1).reshape(-1, 3)
    corners = idx * top
    d = _field_at(scene, block_centers(corners, top))
    evaluated += len(d)
    view(top)[...] = d.astype(np.float32).reshape(n0[0], 1, n0[1], 1, n0[2], 1)
    keep = np.abs(d) <= math.sqrt(3.0) * 0.5 * (top - 1) * h + margin
    corners = corners[keep]
    size = top
    for child in (*_LEVELS[1:], 1):
        if progress is not None:
            progress(0.2 + 0.6 * (1 - child / top))
        ratio = size // child
        offsets = (
            np.stack(np.meshgrid(*[np.arange(ratio)] * 3, indexing="ij"), axis=-1).reshape(-1, 3)
            * child
        )
        corners = (corners[:, None, :] + offsets[None, :, :]).reshape(-1, 3)
        d = _field_at(scene, block_centers(corners, child))
        evaluated += len(d)
        blocks = corners // child
        fill = d.astype(np.float32)[:, None, None, None]
        view(child)[blocks[:, 0], :, blocks[:, 1], :, blocks[:, 2], :] = fill
        if child == 1:
            mask = np.zeros(padded, dtype=bool)
            mask[corners[:, 0], corners[:, 1], corners[:, 2]] = True
            break
        keep = np.abs(d) <= math.sqrt(3.0) * 0.5 * (child - 1) * h + margin
        corners = corners[keep]
        size = child
    nx, ny, nz = grid.shape
    return NearSurfaceField(field[:nx, :ny, :nz], mask[:nx, :ny, :nz], evaluated)


def mesh(
    scene: Scene,
    resolution: int,
    bounds: ArrayLike | None = None,
    *,
    near_surface: bool = True,
    progress: Callable[[float], None] | None = None,
) -> tuple[FloatArray, NDArray[np.int64], FloatArray]:
    """Triangle mesh of the scene's zero level set by marching cubes on the float field.

    Args:
        scene: the scene.
        resolution: samples along the longest side of the bounds, 16..512.
        bounds: optional (2, 3) min and max corners (m); by default found from the primitives with room for the
            blend, so closed shapes give closed meshes.
        near_surface: evaluate only near the surface (coarse to fine; same output); False samples every point.
        progress: optional callback receiving the fraction done, 0..1.

    Returns:
        vertices (V, 3) in metres, faces (F, 3) vertex indices wound outward, vertex colours (V, 3) RGB in [0, 1].
        Samples on (or within 1e-3 voxel of) the zero level are moved 1e-3 voxel off it first: inside where they
        lie on a face along grid lines next to a grid cell whose centre is inside, else outside (see
        ``_polygonise``), so every vertex is distinct, a closed shape gives a watertight mesh even where faces lie on
        grid planes, and a feature one voxel thick between two grid planes keeps its volume. An empty field (no
        surface inside the bounds) gives empty arrays.

    Raises:
        ValueError: a bad resolution, or bounds (given or the scene's) not finite or beyond
            ±:data:`MAX_FIELD_COORDINATE`.
    """
    grid = make_grid(scene, resolution, bounds)
    mask = None
    if near_surface:
        sampled = sample_near_surface(scene, grid, progress)
        field, mask = sampled.field, sampled.mask
    else:
        field = sample_full(scene, grid)
    if progress is not None:
        progress(0.8)
    return _polygonise(scene, grid, field, mask)


ISO_NUDGE_VOXELS = 1e-3
"""Samples within this fraction of a voxel of the zero level move to that distance from it before marching cubes."""


def _polygonise(
    scene: Scene, grid: Grid, field: NDArray[np.float32], mask: NDArray[np.bool_] | None
) -> tuple[FloatArray, NDArray[np.int64], FloatArray]:
    # A sample exactly on the level is a tie that marching cubes breaks differently in neighbouring cells (its
    # classification and its face test disagree), which leaves holes (scikit-image issue 8116), so every sample
    # closer than δ = 1e-3 voxel to the level moves to ±δ. Which side: a sample on the level is a boundary point of
    # the hard solid {d ≤ 0}; when it lies on a face along grid lines (a level neighbour), it goes inside (−δ) if a
    # grid cell it is a corner of has its centre inside (d < 0: the solid has volume in that cell), else outside
    # (+δ, as in Lewiner's reference code). Pushing every such
    # sample outside made a feature one voxel thick with both faces on grid planes vanish (no sample was left
    # inside it); pushing every one inside would turn zero-volume sets (boxes touching in an intersection, A − A)
    # into sheets. A sample a hair inside (d < 0) stays inside. Neighbouring samples differ by at most a voxel (the
    # field is 1-Lipschitz), so each vertex lies at least ~δ/voxel inside its own edge: vertices stay distinct in
    # float32 and the mesh is a plain marching-cubes mesh (no merging), the surface moving by at most δ. Both
    # samplers' fields pass through here and level samples and their cells' corners are evaluated exactly by both
    # (the sign fill comes from blocks far from the surface), so the coarse-to-fine output equals the full grid's.
    delta = np.float32(ISO_NUDGE_VOXELS * grid.spacing)
    near_level = np.abs(field) < delta
    if near_level.any():
        # Only samples with a level neighbour (a face or a feature's edge along grid lines) take that test; a lone
        # one (a blend grazing a sample) stays outside, so a sub-voxel blend keeps the topology it always had.
        # On the grid's outer layer a sample stays outside as well: the solid may go on beyond the bounds, and
        # marching cubes only closes a surface that crosses inside them (a box that fills its bounds).
        lined = near_level & (field >= 0.0) & _beside(near_level)
        lined[[0, -1], :, :] = False
        lined[:, [0, -1], :] = False
        lined[:, :, [0, -1]] = False
        inward = (field < 0.0) | _touches_solid(scene, grid, lined)
        nudged = np.where(inward, -delta, delta)
        # A level sample left outside next to one moved inside: the edge between them runs along a face that only
        # the inside one bounds (a cut flush with another face), so the surface belongs at the inside sample, not
        # halfway between ±δ. The outside one takes half a voxel instead, putting the vertex ~2δ from it.
        beside = _beside(near_level & inward) & near_level & ~inward
        nudged = np.where(beside, np.float32(0.5 * grid.spacing), nudged)
        field = np.where(near_level, nudged, field)
    if not (field.min() < 0.0 < field.max()):
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64), np.zeros((0, 3))
    verts, faces, _normals, _values = marching_cubes(
        np.ascontiguousarray(field, dtype=np.float32),
        level=0.0,
        spacing=(grid.spacing,) * 3,
        mask=None if mask is None else np.ascontiguousarray(mask),
    )
    verts = verts.astype(np.float64) + np.asarray(grid.origin)
    # scikit-image's default winding faces a field that is negative inside outward (tests check the volume's sign).
    return verts, faces.astype(np.int64), scene_color(scene, verts)


def _beside(samples: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """True at grid samples with one of their six axis neighbours in ``samples``."""
    out = np.zeros_like(samples)
    for axis in range(3):
        n = samples.shape[axis]
        lower = [slice(None)] * 3
        upper = [slice(None)] * 3
        lower[axis], upper[axis] = slice(0, n - 1), slice(1, n)
        out[tuple(lower)] |= samples[tuple(upper)]
        out[tuple(upper)] |= samples[tuple(lower)]
    return out


def _touches_solid(scene: Scene, grid: Grid, samples: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """(nx, ny, nz) True at the ``samples`` that are a corner of a grid cell whose centre is inside (d < 0)."""
    out = np.zeros(samples.shape, dtype=bool)
    at = np.argwhere(samples)
    if len(at) == 0:
        return out
    cells_shape = np.asarray(samples.shape) - 1
    offsets = np.array(list(itertools.product((-1, 0), repeat=3)))
    cells = (at[:, None, :] + offsets[None, :, :]).reshape(-1, 3)
    valid = np.all((cells >= 0) & (cells < cells_shape), axis=1)
    unique = np.unique(cells[valid], axis=0)
    centres = np.asarray(grid.origin) + grid.spacing * (unique + 0.5)
    inside_cell = np.zeros(tuple(cells_shape), dtype=bool)
    inside_cell[unique[:, 0], unique[:, 1], unique[:, 2]] = _field_at(scene, centres) < 0.0
    hit = np.zeros(len(cells), dtype=bool)
    good = cells[valid]
    hit[valid] = inside_cell[good[:, 0], good[:, 1], good[:, 2]]
    out[at[:, 0], at[:, 1], at[:, 2]] = hit.reshape(len(at), len(offsets)).any(axis=1)
    return out


def mesh_trimesh(
    vertices: FloatArray, faces: NDArray[np.int64], colors: FloatArray
) -> trimesh.Trimesh:
    """The output of :func:`mesh` as a ``trimesh.Trimesh`` with 8-bit vertex colours (for export)."""
    rgba = np.concatenate([np.clip(colors, 0.0, 1.0), np.ones((len(colors), 1))], axis=1)
    return trimesh.Trimesh(
        vertices=vertices,
        faces=faces,
        vertex_colors=(rgba * 255).round().astype(np.uint8),
        process=False,
    )


def default_scene() -> Scene:
    """The gallery's opening scene: a sphere, a box, a torus lying flat and a capsule, smoothly united."""
    # A quarter turn about x takes local y to world z: the torus lies flat.
    flat = (math.cos(math.pi / 4), math.sin(math.pi / 4), 0.0, 0.0)
    return Scene(
        primitives=(
            Primitive("sphere", (0.0, 0.0, 0.5), (0.45,), color=(0.90, 0.35, 0.30)),
            Primitive("box", (0.6, 0.0, 0.3), (0.3, 0.3, 0.3), color=(0.30, 0.60, 0.90)),
            Primitive(
                "torus", (0.0, 0.0, 0.1), (0.6, 0.12), rotation=flat, color=(0.95, 0.80, 0.30)
            ),
            Primitive("capsule", (-0.5, 0.2, 0.5), (0.35, 0.15), color=(0.40, 0.80, 0.45)),
        ),
        k=0.25,
        blend="poly",
    )


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
    pts = _points(p)
    h, r = _positive(half_height, "half_height"), _positive(radius, "radius")
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
    pts = _points(p)
    b = _vector3(half_size, "half_size")
    if np.any(b <= 0.0):
        raise ValueError(f"half_size must be positive, got {b.tolist()}")
    r = _non_negative(radius, "radius")
    if r > b.min():
        raise ValueError(f"radius must be at most min(half_size) = {b.min()}, got {radius!r}")
    q = np.abs(pts) - b + r
    return np.linalg.norm(np.maximum(q, 0.0), axis=1) + np.minimum(q.max(axis=1), 0.0) - r


def sd_octahedron(p: ArrayLike, size: float) -> FloatArray:
    """Exact distance to the regular octahedron |x| + |y| + |z| = size (Quilez, "Octahedron - exact").

    Args:
        p: (N, 3) points in the local frame (m).
        size: distance from the centre to each vertex (m), > 0.

    Returns:
        (N,) signed distances (m).
    """
    pts = np.abs(_points(p))
    s = _positive(size, "size")
    m = pts.sum(axis=1) - s
    x, y, z = pts[:, 0], pts[:, 1], pts[:, 2]
    # Pick the face region: q is p with its axes cycled so the nearest edge is the one the formula handles.
    use_x, use_y, use_z = 3.0 * x < m, 3.0 * y < m, 3.0 * z < m
    q = np.where(
        use_x[:, None],
        pts,
        np.where(use_y[:, None], pts[:, [1, 2, 0]], pts[:, [2, 0, 1]]),
    )
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
    pts = _points(p)
    r, h = _positive(radius, "radius"), _positive(height, "height")
    # Quilez's frame: apex at the origin, base at y = −h; q is the base rim in the (radial, y) half-plane.
    qx, qy = r, -h
    wx = np.hypot(pts[:, 0], pts[:, 2])
    wy = pts[:, 1] - 0.5 * h
    t = np.clip((wx * qx + wy * qy) / (qx * qx + qy * qy), 0.0, 1.0)
    ax, ay = wx - qx * t, wy - qy * t
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
    pts = np.abs(_points(p))
    a, h = _positive(apothem, "apothem"), _positive(half_height, "half_height")
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
        radii: (3,) semi-axes along x, y, z (m), each > 0.

    Returns:
        (N,) signed distance estimates (m).
    """
    pts = _points(p)
    r = _vector3(radii, "radii")
    if np.any(r <= 0.0):
        raise ValueError(f"radii must be positive, got {r.tolist()}")
    k0 = np.linalg.norm(pts / r, axis=1)
    k1 = np.linalg.norm(pts / (r * r), axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        d = k0 * (k0 - 1.0) / k1
    return np.where(k1 > 0.0, d, -r.min())


def sd_ellipsoid_lipschitz(p: ArrayLike, radii: ArrayLike) -> FloatArray:
    """A 1-Lipschitz distance bound for an axis-aligned ellipsoid: (|p/r| − 1)·min(r) (Quilez, "Ellipsoid SDF",
    iquilezles.org/articles/ellipsoids, 2008: the first, simplest bound).

    |∇|p/r|| ≤ 1/min(r), so the value is 1-Lipschitz; it is zero on the surface, hence never more than the true
    distance: what sphere tracing and the coarse-to-fine mesher need. :func:`sd_ellipsoid` (Quilez's estimate)
    is closer to the distance but can grow faster than 1 per metre (by up to max(r)/min(r)). Equal radii give
    the sphere's distance.

    Args:
        p: (N, 3) points in the local frame (m).
        radii: (3,) semi-axes along x, y, z (m), each > 0.

    Returns:
        (N,) signed distance bounds (m).
    """
    pts = _points(p)
    r = _vector3(radii, "radii")
    if np.any(r <= 0.0):
        raise ValueError(f"radii must be positive, got {r.tolist()}")
    return (np.linalg.norm(pts / r, axis=1) - 1.0) * r.min()


def sd_plane(p: ArrayLike, normal: ArrayLike, offset: float) -> FloatArray:
    """Exact distance to the plane n·p + offset = 0, negative on the side −n points to (Quilez, "Plane").

    Args:
        p: (N, 3) points (m).
        normal: (3,) normal; normalised here (must be non-zero).
        offset: the plane's signed distance from the origin along −n (m).

    Returns:
        (N,) signed distances (m).
    """
    pts = _points(p)
    n = _vector3(normal, "normal")
    length = float(np.linalg.norm(n))
    if length < 1e-12:
        raise ValueError("normal must be non-zero")
    off = float(offset)
    if not math.isfinite(off):
        raise ValueError(f"offset must be finite, got {offset!r}")
    return pts @ (n / length) + off


# ------------------------------------------------------------------------------------------ operators
# Quilez, "distance functions": rounding, onion, and the point transforms (elongation, twist, bend, finite
# repetition, mirror symmetry). A point transform maps the query point; the shape is then any primitive evaluated
# at the mapped point. GLSL has no function arguments, so both sides are written this way, name for name.
def op_round(d: ArrayLike, radius: float) -> FloatArray:
    """d − radius: a shape grown by ``radius`` with rounded edges (Quilez, "Rounding"). Exact if d is, outside.

    Args:
        d: (N,) distances (m).
        radius: rounding radius (m), ≥ 0.
    """
    return np.asarray(d, dtype=np.float64) - _non_negative(radius, "radius")


def op_onion(d: ArrayLike, thickness: float) -> FloatArray:
    """|d| − thickness: a shell of the surface (Quilez, "Onion"). Exact if d is.

    Args:
        d: (N,) distances (m).
        thickness: half the shell's wall thickness (m), ≥ 0.
    """
    return np.abs(np.asarray(d, dtype=np.float64)) - _non_negative(thickness, "thickness")


def op_elongate(p: ArrayLike, half_length: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Stretch a shape by 2·half_length, splitting it at its centre planes (Quilez, "Elongation", exact form).

    ``q = |p| − h``; the shape is ``sd(p − clamp(p, −h, h)) + min(max(q.x, q.y, q.z), 0)``. The first part keeps
    the sign of p (Quilez writes ``max(q, 0)``, which needs a shape symmetric in every axis). Exact if sd is.

    Args:
        p: (N, 3) points (m).
        half_length: (3,) elongation along x, y, z (m), each ≥ 0.

    Returns:
        (N, 3) points to evaluate the shape at, and (N,) the term to add to its distance.
    """
    pts = _points(p)
    h = _vector3(half_length, "half_length")
    if np.any(h < 0.0):
        raise ValueError(f"half_length must be non-negative, got {h.tolist()}")
    q = np.abs(pts) - h
    return pts - np.clip(pts, -h, h), np.minimum(q.max(axis=1), 0.0)


def op_twist(p: ArrayLike, rate: float) -> FloatArray:
    """Twist about local y: rotate (x, z) by the angle rate·y (Quilez, "Twist").

    Not a distance-preserving map: a shape of radius ρ from the axis needs its distance divided by
    sqrt(1 + (rate·ρ)²) to stay a bound.

    Args:
        p: (N, 3) points (m).
        rate: twist (rad/m), finite.

    Returns:
        (N, 3) points: (c·x − s·z, y, s·x + c·z) with c, s = cos, sin(rate·y).
    """
    pts = _points(p)
    k = float(rate)
    if not math.isfinite(k):
        raise ValueError(f"rate must be finite, got {rate!r}")
    c, s = np.cos(k * pts[:, 1]), np.sin(k * pts[:, 1])
    return np.stack(
        [c * pts[:, 0] - s * pts[:, 2], pts[:, 1], s * pts[:, 0] + c * pts[:, 2]], axis=1
    )


def op_bend(p: ArrayLike, rate: float) -> FloatArray:
    """Bend in the xy plane: rotate (x, y) by the angle rate·x (Quilez, "Bend").

    Not distance-preserving either (the same bound correction as :func:`op_twist`).

    Args:
        p: (N, 3) points (m).
        rate: bend (rad/m), finite.

    Returns:
        (N, 3) points: (c·x − s·y, s·x + c·y, z) with c, s = cos, sin(rate·x).
    """
    pts = _points(p)
    k = float(rate)
    if not math.isfinite(k):
        raise ValueError(f"rate must be finite, got {rate!r}")
    c, s = np.cos(k * pts[:, 0]), np.sin(k * pts[:, 0])
    return np.stack(
        [c * pts[:, 0] - s * pts[:, 1], s * pts[:, 0] + c * pts[:, 1], pts[:, 2]], axis=1
    )


def op_repeat_finite(p: ArrayLike, spacing: ArrayLike, limit: ArrayLike) -> FloatArray:
    """Finite repetition: copies every ``spacing`` along each axis, cell indices in [−limit, limit]
    (Quilez, "Finite Repetition").

    ``p − spacing·clamp(round(p/spacing), −limit, limit)``, rounding half up (floor(x + ½), the same in GLSL,
    whose round() leaves halves to the driver). Exact for a shape that fits in its cell and is symmetric.

    Args:
        p: (N, 3) points (m).
        spacing: (3,) cell size along x, y, z (m), each > 0.
        limit: (3,) copies on each side of the middle one, each ≥ 0 (whole numbers).

    Returns:
        (N, 3) points in the nearest copy's frame.
    """
    pts = _points(p)
    c = _vector3(spacing, "spacing")
    if np.any(c <= 0.0):
        raise ValueError(f"spacing must be positive, got {c.tolist()}")
    lim = _vector3(limit, "limit")
    if np.any(lim < 0.0) or np.any(lim != np.round(lim)):
        raise ValueError(f"limit must be whole numbers ≥ 0, got {lim.tolist()}")
    return pts - c * np.clip(np.floor(pts / c + 0.5), -lim, lim)


def op_symmetry(p: ArrayLike, axes: ArrayLike) -> FloatArray:
    """Mirror symmetry: the chosen coordinates replaced by their absolute values (Quilez, "Symmetry").

    Args:
        p: (N, 3) points (m).
        axes: (3,) 1 (mirror across that coordinate's plane) or 0 (leave it), for x, y, z.

    Returns:
        (N, 3) points.
    """
    pts = _points(p)
    mask = _vector3(axes, "axes")
    if not np.all((mask == 0.0) | (mask == 1.0)):
        raise ValueError(f"axes must be 0 or 1 each, got {mask.tolist()}")
    return np.where(mask > 0.0, np.abs(pts), pts)


# ------------------------------------------------------------------------------------------ sampled fields
def mesh_samples(
    grid: Grid, field: NDArray[np.float32], mask: NDArray[np.bool_] | None = None
) -> tuple[FloatArray, NDArray[np.int64]]:
    """Marching cubes of a field sampled elsewhere (the GLSL editor's, sampled on the GPU), by :func:`mesh`'s pass.

    Args:
        grid: where the samples are (:func:`make_grid`).
        field: (nx, ny, nz) float32 distances (m), negative inside, shaped like ``grid.shape``.
        mask: optional (nx, ny, nz) cells marching cubes may visit.

    Returns:
        vertices (V, 3) in metres and faces (F, 3) wound outward; empty when no surface crosses the grid.
    """
    if field.shape != grid.shape:
        raise ValueError(f"field must have the grid's shape {grid.shape}, got {field.shape}")
    if not np.all(np.isfinite(field)):
        raise ValueError("field must be finite")
    # _polygonise colours its vertices from a scene; one small sphere keeps that cost to a few ms.
    verts, faces, _ = _polygonise(_COLOURLESS, grid, field.astype(np.float32, copy=False), mask)
    return verts, faces


_COLOURLESS = Scene((Primitive("sphere", (0.0, 0.0, 0.0), (1.0,)),))
