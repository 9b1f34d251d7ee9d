"""Input checks shared by every kernel: each refuses bad input with a ``ValueError`` that names the argument.

A kernel's public function checks its arguments once, at the boundary, and its compiled core trusts them. The
messages follow one pattern, ``"<name> must be <what>, got <value>"``, so a caller (or a test) can tell which
argument was wrong. Booleans and complex numbers are refused where a real number is wanted: numpy would convert
them silently (``True`` → 1, the imaginary part dropped).

The scalar checks take a fast path for a plain ``float``, the common case, so a single kernel call spends well
under a microsecond per argument here.
"""

from __future__ import annotations

import math
import numbers
import reprlib
from typing import Any, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "bounded_array",
    "choice",
    "direction",
    "finite_array",
    "finite_number",
    "flag",
    "holds_booleans",
    "indices",
    "instance",
    "integer",
    "non_negative",
    "non_negative_array",
    "points",
    "positive",
    "positive_array",
    "positive_vector",
    "real_array",
    "shown",
    "vector",
]

_REAL_SCALARS = (float, int, np.floating, np.integer)
_SHOWN_CHARS = 200
"""The longest a refused value is quoted in a message: a million-point array is not printed whole."""


def shown(value: object) -> str:
    """``repr(value)`` for a message: an array's middle elided (numpy's summary, three items at each end), a long
    list's or tuple's tail (:mod:`reprlib`), and cut to :data:`_SHOWN_CHARS` characters."""
    if isinstance(value, np.ndarray):
        with np.printoptions(threshold=6, edgeitems=3):
            text = repr(value)
    else:
        text = _REPR.repr(value)
    return text if len(text) <= _SHOWN_CHARS else text[: _SHOWN_CHARS - 1] + "…"


def and_more(count: int) -> str:
    """What follows the first of ``count`` refused values in a message: `` (and 2 more)``, or nothing for one."""
    return "" if count <= 1 else f" (and {count - 1} more)"


_REPR = reprlib.Repr()
_REPR.maxlist = _REPR.maxtuple = _REPR.maxdict = _REPR.maxset = 6
_REPR.maxstring, _REPR.maxother = _SHOWN_CHARS, 80
T = TypeVar("T")


def finite_number(name: str, value: object) -> float:
    """``value`` as a float when it is a finite real scalar (Python or numpy; not bool), else ``ValueError``."""
    if type(value) is float and math.isfinite(value):  # the common case, first
        return value
    if isinstance(value, _REAL_SCALARS) and not isinstance(value, (bool, np.bool_, np.timedelta64)):
        try:
            number = float(value)
        except OverflowError:  # an int beyond float64
            number = math.inf
        if math.isfinite(number):
            return number
    raise ValueError(f"{name} must be a finite number, got {shown(value)}")


def choice(name: str, value: object, options: tuple[str, ...]) -> str:
    """``value`` when it is one of the strings ``options``, else ``ValueError`` naming it and the options (an array,
    a number or ``None`` included: compared with ``in``, an array would raise numpy's "truth value is ambiguous")."""
    if isinstance(value, str) and value in options:
        return value
    listed = ", ".join(repr(option) for option in options)
    raise ValueError(f"{name} must be one of {listed}, got {shown(value)}")


def flag(name: str, value: object) -> bool:
    """``value`` when it is a Python or numpy bool, else ``ValueError`` naming it (``"no"`` or NaN is not a flag)."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    raise ValueError(f"{name} must be True or False, got {shown(value)}")


def integer(name: str, value: object, minimum: int | None = None) -> int:
    """``value`` as an int when it is a Python or numpy integer (not bool), ≥ ``minimum`` if given, else
    ``ValueError`` naming it."""
    if (
        isinstance(value, (bool, np.timedelta64))  # numpy's timedelta is an integer type
        or not isinstance(value, (int, np.integer))
        or (minimum is not None and value < minimum)
    ):
        at_least = "" if minimum is None else f" >= {minimum}"
        raise ValueError(f"{name} must be an integer{at_least}, got {shown(value)}")
    return int(value)


def instance(name: str, value: object, kind: type[T], what: str = "") -> T:
    """``value`` when it is a ``kind``, else ``ValueError`` naming it and the type it got.

    ``what`` says what was wanted where "a <kind's name>" does not ("an Air", "a Trajectory from simulate()").
    """
    if not isinstance(value, kind):
        raise ValueError(f"{name} must be {what or 'a ' + kind.__name__}, got {type(value).__name__}")
    return value


def indices(name: str, value: ArrayLike, corners: int, count: int) -> NDArray[np.int64]:
    """(N, ``corners``) integer indices into ``count`` items (a mesh's faces or lines into its vertices) as int64;
    an empty array is (0, ``corners``). Else ``ValueError`` naming it: floats, bools, text, a wrong shape, or an
    index outside [0, count)."""
    wanted = f"{name} must be (N, {corners}) integer indices into the {count} vertices"
    try:
        raw = np.asarray(value)
        if raw.size and raw.dtype.kind not in "iu":
            raise TypeError(raw.dtype)
        array = raw.astype(np.int64)
    except (TypeError, ValueError, OverflowError) as error:
        raise ValueError(f"{wanted}, got {shown(value)}") from error
    if array.size == 0:
        return np.zeros((0, corners), dtype=np.int64)
    if array.ndim != 2 or array.shape[1] != corners or array.min() < 0 or array.max() >= count:
        raise ValueError(f"{wanted}, got {shown(value)}")
    return array


def positive(name: str, value: object) -> float:
    """A finite real scalar > 0 as a float, else ``ValueError`` naming it."""
    number = finite_number(name, value)
    if number <= 0.0:
        raise ValueError(f"{name} must be > 0, got {shown(value)}")
    return number


def non_negative(name: str, value: object) -> float:
    """A finite real scalar ≥ 0 as a float, else ``ValueError`` naming it."""
    number = finite_number(name, value)
    if number < 0.0:
        raise ValueError(f"{name} must be >= 0, got {shown(value)}")
    return number


def holds_booleans(value: object) -> bool:
    """Whether ``value`` is a boolean, a boolean array or a (nested) list or tuple holding one: numpy would turn a
    ``[1.0, True, 2.0]`` into floats, and a flag where a number belongs is a caller's bug."""
    if isinstance(value, np.ndarray):
        return value.dtype == np.bool_
    if isinstance(value, (list, tuple)):
        for item in value:  # a plain loop: this runs on every kick's three vectors
            kind = type(item)
            if kind is bool or kind is np.bool_:
                return True
            if (kind is list or kind is tuple or kind is np.ndarray) and holds_booleans(item):
                return True
        return False
    return isinstance(value, (bool, np.bool_))


def _is_real(item: object) -> bool:
    return isinstance(item, numbers.Real) and not isinstance(item, (bool, np.bool_))


def real_array(name: str, value: ArrayLike, what: str = "an array of real numbers") -> NDArray[np.float64]:
    """Real numbers of any shape as float64, not yet checked finite. Bool (anywhere in a list), complex, text, None,
    other objects and ragged input are refused with ``ValueError`` saying ``name`` must be ``what``: numpy would take
    True as 1 and None as NaN (then called "not finite"), drop an imaginary part, or raise its own error."""
    try:
        if isinstance(value, (list, tuple)) and holds_booleans(value):
            raise TypeError("a boolean")
        array: Any = np.asarray(value)
        if array.dtype.kind not in "fiuO":
            raise TypeError(array.dtype)
        if array.dtype.kind == "O" and not all(_is_real(item) for item in array.flat):
            raise TypeError("not a real number")
        return np.asarray(array, dtype=np.float64)
    except OverflowError as error:  # a Python int past float64 (10**400): a real number, but not a finite float
        raise ValueError(f"{name} must be finite (within float64's range), got {shown(value)}") from error
    except (TypeError, ValueError) as error:
        raise ValueError(f"{name} must be {what}, got {shown(value)}") from error


def finite_array(name: str, value: ArrayLike) -> NDArray[np.float64]:
    """:func:`real_array`, all finite."""
    array = real_array(name, value)
    if not np.isfinite(array).all():
        if array.ndim == 0:
            raise ValueError(f"{name} must be finite, got {shown(value)}")
        where = [int(i) for i in np.argwhere(~np.isfinite(array))[0]]
        raise ValueError(f"{name} must be finite, got {float(array[tuple(where)])!r} at {where} of {shown(value)}")
    return array


def bounded_array(name: str, value: ArrayLike, bound: float) -> NDArray[np.float64]:
    """As :func:`finite_array`, and every magnitude ≤ ``bound``, so sums and differences of them stay finite."""
    array = finite_array(name, value)
    if not (np.abs(array) <= bound).all():
        raise ValueError(f"{name} must be of magnitude ≤ {bound:g}, got {shown(value)}")
    return array


def positive_array(name: str, value: ArrayLike) -> NDArray[np.float64]:
    """:func:`finite_array` with every element > 0, else ``ValueError`` naming it."""
    array = finite_array(name, value)
    if np.any(array <= 0.0):
        raise ValueError(f"{name} must be > 0, got {shown(value)}")
    return array


def non_negative_array(name: str, value: ArrayLike) -> NDArray[np.float64]:
    """:func:`finite_array` with every element ≥ 0, else ``ValueError`` naming it."""
    array = finite_array(name, value)
    if np.any(array < 0.0):
        raise ValueError(f"{name} must be >= 0, got {shown(value)}")
    return array


def vector(name: str, value: ArrayLike, size: int) -> NDArray[np.float64]:
    """A finite float64 vector of shape ``(size,)``, else ``ValueError`` naming it."""
    array = finite_array(name, value)
    if array.shape != (size,):
        raise ValueError(f"{name} must have shape ({size},), got {array.shape}")
    return array


def direction(name: str, value: ArrayLike, size: int, what: str = "") -> NDArray[np.float64]:
    """The unit vector along a finite, non-zero :func:`vector` of any length, else ``ValueError`` naming it (as a
    non-zero ``what`` where given, e.g. "quaternion (w, x, y, z)"). It is scaled by its largest component before its
    norm is taken, so a huge one (1e300) does not overflow the norm and a tiny one (1e-300) does not underflow it."""
    array = vector(name, value, size)
    largest = float(np.abs(array).max())
    if largest == 0.0:
        raise ValueError(f"{name} must be {'a non-zero ' + what if what else 'non-zero'}, got {shown(value)}")
    array = array / largest
    return array / math.sqrt(float(array @ array))


def positive_vector(name: str, value: ArrayLike, size: int) -> NDArray[np.float64]:
    """:func:`vector` with every element > 0 (sizes, semi-axes, spacings), else ``ValueError`` naming it."""
    array = vector(name, value, size)
    if np.any(array <= 0.0):
        raise ValueError(f"{name} must be > 0, got {array.tolist()}")
    return array


def points(name: str, value: ArrayLike, dim: int = 3) -> NDArray[np.float64]:
    """Finite float64 points of shape ``(N, dim)`` (an empty list is ``(0, dim)``), else ``ValueError``."""
    array = finite_array(name, value)
    if array.size == 0 and array.ndim == 1:
        array = array.reshape(0, dim)
    if array.ndim != 2 or array.shape[1] != dim:
        raise ValueError(f"{name} must have shape (N, {dim}), got {array.shape}")
    return array
