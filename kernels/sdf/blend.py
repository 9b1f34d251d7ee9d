"""Smooth minimum and the booleans of signed distances, hard and smooth.

Distances are arrays of any (broadcastable) shape, in metres, negative inside.

Smooth minimum (I. Quilez, "smooth minimum", iquilezles.org, 2008–2024):

    smin_poly(a, b, k) = mix(b, a, h) − k·h·(1 − h),   h = clamp(0.5 + 0.5·(b − a)/k, 0, 1)   (k: blend width, m)
    smin_exp(a, b, k)  = −log(exp(−k·a) + exp(−k·b)) / k                                       (k: sharpness, 1/m)

``smin_exp`` is evaluated as ``min(a, b) − log1p(exp(−k·|a − b|))/k``, which is the same number and cannot overflow.
Both are ≤ min(a, b) and tend to it as the blend narrows (poly: k → 0; exp: k → ∞). Their derivatives are convex
weights (``h`` and ``1 − h`` for poly, a logistic for exp), so a blend of 1-Lipschitz fields is 1-Lipschitz: not an
exact distance, but a distance bound, which is what sphere tracing (Hart 1996) and the coarse-to-fine mesher rely
on. The same weights blend a scene's colours (:func:`combine_weighted` returns them).

Distances may be ±inf (a point too far for float64 has an infinite distance) but not NaN, nor anything that is not
a real number (:func:`distance_array`): every function here then gives the hard boolean's answer wherever it is
infinite (a union with −inf is −inf, an intersection with +inf is +inf), never NaN.

Booleans: union ``min(a, b)``, subtraction ``max(a, −b)`` (a minus b), intersection ``max(a, b)``; the smooth forms
are ``smin(a, b)``, ``−smin(−a, b)`` and ``−smin(−a, −b)``. One blend width ``k`` (m) serves both forms; the
exponential form uses the sharpness ``4·ln 2 / k``, which makes both forms dip by the same ``k/4`` where two surfaces
meet. ``k = 0`` means hard booleans, and so does any k below ``MIN_BLEND_WIDTH`` (float32's smallest normal).
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from kernels import _checks
from kernels.sdf.primitives import AnyFloatArray, FloatArray

BooleanOp = Literal["union", "subtract", "intersect"]
"""How a primitive combines with the shape before it."""
BlendForm = Literal["poly", "exp"]
"""Which smooth minimum blends the booleans."""
BOOLEAN_OPS: tuple[BooleanOp, ...] = ("union", "subtract", "intersect")
BLEND_FORMS: tuple[BlendForm, ...] = ("poly", "exp")

EXP_SHARPNESS_PER_WIDTH = 4.0 * math.log(2.0)
"""A scene's exp blend uses sharpness ``EXP_SHARPNESS_PER_WIDTH / k``: both forms then dip by k/4 where a = b."""
MIN_BLEND_WIDTH = float(np.finfo(np.float32).tiny)
"""Blend widths below this (float32's smallest normal, 1.2e-38 m) are the hard booleans, here and in the GLSL: their
dip k/4 is below any distance's rounding, a float32 uniform cannot hold them reliably (subnormal or 0), and
above it 0.5/k and the exp sharpness 4·ln 2/k stay finite in float32."""


def _distances(a: ArrayLike, b: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """``a`` and ``b`` as distances (:func:`distance_array`) whose shapes broadcast together."""
    a_arr, b_arr = distance_array("a", a), distance_array("b", b)
    try:
        np.broadcast_shapes(a_arr.shape, b_arr.shape)
    except ValueError:
        raise ValueError(f"a and b must broadcast together, got shapes {a_arr.shape} and {b_arr.shape}") from None
    return a_arr, b_arr


def distance_array(name: str, value: ArrayLike) -> FloatArray:
    """Distances (m) as float64, ±inf allowed; NaN, bool, complex, text, None and objects refused with
    ``ValueError`` naming ``name`` (numpy turned True into 1 m and None into NaN, dropped an imaginary part, or
    raised its own TypeError).

    Every function that takes distances here and in :mod:`kernels.sdf.operators` takes them through this, so an
    infinite distance (a point too far away for float64) is an answer they define, never NaN: the hard and smooth
    booleans give what ``min``/``max`` give (a union with −inf is −inf, an intersection with +inf is +inf, a
    subtraction of −inf leaves +inf), and rounding or an onion of ±inf is ±inf or +inf."""
    array = _checks.real_array(name, value, "real distances (m)")
    if np.any(np.isnan(array)):
        raise ValueError(f"{name} must not be NaN")
    return array


def _smin_poly_weighted(a: AnyFloatArray, b: AnyFloatArray, k: float) -> tuple[AnyFloatArray, AnyFloatArray]:
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


def _smin_exp_weighted(a: AnyFloatArray, b: AnyFloatArray, k: float) -> tuple[AnyFloatArray, AnyFloatArray]:
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
        d = np.minimum(a, b) - np.log1p(e) / sharpness  # log1p(e) ≤ ln 2: → 0 as the sharpness grows
    w_b = np.where(a > b, 1.0, e) / (1.0 + e)
    return d, w_b


def smin_poly(a: ArrayLike, b: ArrayLike, k: float) -> FloatArray:
    """The polynomial smooth minimum (Quilez); ≤ min(a, b), equal to it where |a − b| ≥ k.

    Args:
        a: distances (m), any shape broadcastable with ``b``.
        b: distances (m).
        k: blend width (m), ≥ 0; 0 (or anything below ``MIN_BLEND_WIDTH``) is the hard minimum.

    Returns:
        Blended distances (m), the broadcast shape.
    """
    a_arr, b_arr = _distances(a, b)
    return np.asarray(_smin_poly_weighted(a_arr, b_arr, _checks.non_negative("k", k))[0], dtype=np.float64)


def smin_exp(a: ArrayLike, b: ArrayLike, k: float) -> FloatArray:
    """The exponential smooth minimum (Quilez) −log(exp(−ka) + exp(−kb))/k, evaluated without overflow.

    Args:
        a: distances (m), any shape broadcastable with ``b``.
        b: distances (m).
        k: sharpness (1/m), > 0; larger is sharper (→ min(a, b) as k → ∞). Unlike every other blend here, whose
            k is a width in metres: ``smin_exp(a, b, 4·ln 2 / k)`` is ``smooth_union(a, b, k, "exp")``.

    Returns:
        Blended distances (m), ≤ min(a, b) − 0 and ≥ min(a, b) − ln 2 / k.
    """
    a_arr, b_arr = _distances(a, b)
    return np.asarray(_smin_exp_weighted(a_arr, b_arr, _checks.positive("k", k))[0], dtype=np.float64)


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


def combine_weighted(
    a: AnyFloatArray, b: AnyFloatArray, op: BooleanOp, k: float, blend: BlendForm
) -> tuple[AnyFloatArray, AnyFloatArray]:
    """Distance of ``a op b`` and the weight of ``b`` in it, in the inputs' float dtype (unchecked: the fast path).

    Args:
        a: distances (m) of the shape so far.
        b: distances (m) of the primitive combined with it, the same shape.
        op: the boolean.
        k: blend width (m), ≥ 0; below ``MIN_BLEND_WIDTH`` the hard boolean.
        blend: the smooth minimum's form.

    Returns:
        The distances (m) and the weight of ``b`` (in [0, 1]) that blends the colours.
    """

    def smin(x: AnyFloatArray, y: AnyFloatArray) -> tuple[AnyFloatArray, AnyFloatArray]:
        if k < MIN_BLEND_WIDTH:  # 0 and tiny widths: the hard boolean, as in the GLSL
            return _smin_poly_weighted(x, y, 0.0)
        match blend:
            case "poly":
                return _smin_poly_weighted(x, y, k)
            case "exp":
                return _smin_exp_weighted(x, y, EXP_SHARPNESS_PER_WIDTH / k)
            case _:
                raise ValueError(f"blend must be one of {BLEND_FORMS}, got {_checks.shown(blend)}")

    # Checked here for k = 0 too, which never reaches the match above; choice() also names an array, which `in`
    # and `match` would meet with numpy's "truth value is ambiguous".
    _checks.choice("blend", blend, BLEND_FORMS)
    match _checks.choice("op", op, BOOLEAN_OPS):
        case "union":
            return smin(a, b)
        case "subtract":
            d, w = smin(-a, b)
            return -d, w
        case "intersect":
            d, w = smin(-a, -b)
            return -d, w
        case _:
            raise ValueError(f"op must be one of {BOOLEAN_OPS}, got {_checks.shown(op)}")


def smooth_union(a: ArrayLike, b: ArrayLike, k: float, blend: BlendForm = "poly") -> FloatArray:
    """Smooth union ``smin(a, b)``; ``k`` is the blend width (m), 0 for the hard union."""
    a_arr, b_arr = _distances(a, b)
    return np.asarray(combine_weighted(a_arr, b_arr, "union", _checks.non_negative("k", k), blend)[0], dtype=np.float64)


def smooth_subtract(a: ArrayLike, b: ArrayLike, k: float, blend: BlendForm = "poly") -> FloatArray:
    """Smooth subtraction, ``a`` minus ``b``: −smin(−a, b); ``k`` is the blend width (m)."""
    a_arr, b_arr = _distances(a, b)
    return np.asarray(
        combine_weighted(a_arr, b_arr, "subtract", _checks.non_negative("k", k), blend)[0], dtype=np.float64
    )


def smooth_intersect(a: ArrayLike, b: ArrayLike, k: float, blend: BlendForm = "poly") -> FloatArray:
    """Smooth intersection −smin(−a, −b); ``k`` is the blend width (m)."""
    a_arr, b_arr = _distances(a, b)
    return np.asarray(
        combine_weighted(a_arr, b_arr, "intersect", _checks.non_negative("k", k), blend)[0], dtype=np.float64
    )
