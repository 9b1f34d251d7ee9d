"""What a scene declared for each control (its :class:`ControlSpec`), and cleaning a browser's value against it.

A control's limits and options are recorded by :func:`record_spec` when the scene creates it (before any browser can
touch it) and kept here, beside viser's objects rather than on them; they are never read back from the handle's
props, which a browser could once change. :func:`clean_value` checks one browser value against its control's spec;
:func:`unit_quaternion`, :func:`finite_number` and :func:`finite_vector` are the checks every pose and camera shares.
"""

from __future__ import annotations

import dataclasses
import math
import threading
import typing
import weakref
from typing import Any, Literal

import viser

ControlKind = Literal["number", "choice", "bool", "button", "rgb", "text", "vector", "display"]

MAX_TEXT_CHARS = 10_000
"""Longest text a text control takes unless it declares its own :attr:`ControlSpec.max_chars`."""


@dataclasses.dataclass(frozen=True)
class ControlSpec:
    """What a scene declared for one control, recorded when it was created."""

    kind: ControlKind
    """How a browser's value is checked."""
    lo: float | None = None
    """Smallest value (numbers), or None."""
    hi: float | None = None
    """Largest value (numbers), or None."""
    integer: bool = False
    """Whether the number is an integer (viser casts to the initial value's type)."""
    options: tuple[str, ...] = ()
    """The dropdown's options."""
    length: int = 0
    """Number of components (RGB, vectors)."""
    max_chars: int = MAX_TEXT_CHARS
    """Longest text (text controls): the gate refuses a longer one, puts the last kept text back and tells the tab
    that sent it the length and this limit."""
    costly: bool = False
    """Whether a change rebuilds a scene or starts a long job: such inputs share a per-tab budget at the gate, and a
    burst beyond it is coalesced (see :func:`mark_costly`)."""


def spec_from_handle(handle: object) -> ControlSpec:
    """The spec of ``handle`` as it stands now: call it only when the scene has just created the handle."""
    if isinstance(handle, viser.GuiCheckboxHandle):
        return ControlSpec("bool")
    if isinstance(handle, viser.GuiButtonHandle):
        return ControlSpec("button")
    if isinstance(handle, (viser.GuiSliderHandle, viser.GuiNumberHandle)):
        lo, hi = handle.min, handle.max
        return ControlSpec(
            "number",
            lo=None if lo is None else float(lo),
            hi=None if hi is None else float(hi),
            integer=isinstance(handle.value, int),
        )
    if isinstance(handle, viser.GuiDropdownHandle):
        return ControlSpec("choice", options=tuple(str(option) for option in handle.options))
    if isinstance(handle, viser.GuiRgbHandle):
        return ControlSpec("rgb", lo=0.0, hi=255.0, integer=True, length=3)
    if isinstance(handle, viser.GuiTextHandle):
        return ControlSpec("text")
    if isinstance(handle, (viser.GuiVector2Handle, viser.GuiVector3Handle)):
        return ControlSpec("vector", length=len(handle.value))
    return ControlSpec("display")  # progress bars, uploads, button groups...: nothing a browser may set


# viser's handles are dataclasses compared by value, so unhashable: no WeakKeyDictionary. The specs are kept by the
# handle's id beside a weak reference to it; the reference's callback forgets the entry when the handle is freed,
# and a lookup checks the reference, so a later object that reuses the id never sees another control's spec.
_specs: dict[int, tuple[weakref.ref[Any], ControlSpec]] = {}
_specs_lock = threading.Lock()


def _forget(key: int, ref: weakref.ref[Any]) -> None:
    with _specs_lock:
        entry = _specs.get(key)
        if entry is not None and entry[0] is ref:
            del _specs[key]


def record_spec(handle: object, spec: ControlSpec | None = None) -> ControlSpec:
    """Record ``spec`` for ``handle`` (call right after creating it); without one, the spec is read from the handle
    as it stands now (:func:`spec_from_handle`). Returns the spec recorded."""
    if spec is None:
        spec = spec_from_handle(handle)
    key = id(handle)
    ref = weakref.ref(handle, lambda dead: _forget(key, dead))
    with _specs_lock:
        _specs[key] = (ref, spec)
    return spec


def control_spec(handle: object) -> ControlSpec:
    """The spec recorded for ``handle``; a control made without the facade is recorded now, on first use."""
    with _specs_lock:
        entry = _specs.get(id(handle))
    if entry is not None and entry[0]() is handle:
        return entry[1]
    return record_spec(handle)


H = typing.TypeVar("H")


def mark_costly(handle: H) -> H:
    """Declare ``handle`` (a control just created) costly: each change rebuilds a scene or starts a long job.

    The gate lets a tab send :data:`server.budget.COSTLY_BURST` costly inputs at once, then
    :data:`server.budget.COSTLY_RATE_HZ` a second; beyond that it keeps only the latest value of each costly control
    (a burst of clicks is one click, the last pick or resolution wins) and delivers it when the tab's budget allows,
    so every viewer still ends on the value the browser sent last. Returns ``handle``.
    """
    record_spec(handle, dataclasses.replace(control_spec(handle), costly=True))
    return handle


# ------------------------------------------------------------------------------------------------ values
NEGLIGIBLE = 1e-9
"""A number nearer zero than this share of its control's range (1 where the range is open; a vector's component:
this) is taken as zero. No control means anything at that resolution, and a tiny one underflowed downstream: a
headwind of 1e-320 m/s has a direction whose norm is 0, so the wind arrow was drawn from NaN."""


def finite_number(value: object) -> float | None:
    """``value`` as a float when it is a finite int or float (not a bool), else None."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    number = float(value)
    return number if math.isfinite(number) else None


def finite_vector(value: object, length: int) -> tuple[float, ...] | None:
    """``value`` as ``length`` floats when it is a list or tuple of that many finite numbers, else None."""
    if not isinstance(value, (list, tuple)) or len(value) != length:
        return None
    numbers = tuple(finite_number(item) for item in value)
    if any(number is None for number in numbers):
        return None
    return tuple(float(number) for number in numbers if number is not None)


def unit_quaternion(value: object) -> tuple[float, float, float, float] | None:
    """``value`` as a unit wxyz quaternion, or None when it is not 4 finite numbers, not all zero."""
    q = finite_vector(value, 4)
    if q is None:
        return None
    largest = max(abs(component) for component in q)
    if largest == 0.0:
        return None
    # Scaled to a largest component of ±1 first: the norm neither overflows (1e308) nor loses its digits in
    # subnormals (a 1e-300 quaternion, which the SDF kernel accepts, was refused as having no norm).
    scaled = [component / largest for component in q]
    norm = math.hypot(*scaled)
    w, x, y, z = (component / norm for component in scaled)
    return (w, x, y, z)


def clean_value(spec: ControlSpec, value: object) -> tuple[bool, Any, str]:
    """(accepted, cleaned value, reason refused) for a browser's ``value`` of a control with ``spec``."""
    match spec.kind:
        case "bool":
            if type(value) is bool:
                return True, value, ""
            return False, None, "a checkbox value that is not true or false"
        case "button":
            if value is True:
                return True, value, ""
            return False, None, "a button value other than true"
        case "number":
            number = finite_number(value)
            if number is None:
                return False, None, "a number that is not finite or not a number"
            if spec.integer:
                # truncated, as viser's own cast to the control's int type does, then kept to the integers in range
                lo = None if spec.lo is None else math.ceil(spec.lo)
                hi = None if spec.hi is None else math.floor(spec.hi)
                if lo is not None and hi is not None and lo > hi:
                    return False, None, "a number for a control whose range holds no integer"
                whole = int(number)
                whole = whole if lo is None else max(whole, lo)
                return True, (whole if hi is None else min(whole, hi)), ""
            span = 1.0 if spec.lo is None or spec.hi is None else spec.hi - spec.lo
            if abs(number) < NEGLIGIBLE * span:
                number = 0.0
            if spec.lo is not None:
                number = max(number, spec.lo)
            if spec.hi is not None:
                number = min(number, spec.hi)
            return True, number, ""
        case "choice":
            if isinstance(value, str) and value in spec.options:
                return True, value, ""
            return False, None, "an option the dropdown does not have"
        case "rgb":
            rgb = finite_vector(value, 3)
            if rgb is None or not all(0.0 <= c <= 255.0 for c in rgb):
                return False, None, "a colour that is not three numbers in 0..255"
            return True, tuple(round(c) for c in rgb), ""
        case "text":
            if isinstance(value, str) and len(value) <= spec.max_chars:
                return True, value, ""
            return False, None, f"text that is not a string of at most {spec.max_chars:,} characters"
        case "vector":
            vector = finite_vector(value, spec.length)
            if vector is None:
                return False, None, f"a vector that is not {spec.length} finite numbers"
            return True, tuple(0.0 if abs(x) < NEGLIGIBLE else x for x in vector), ""
        case "display":
            return False, None, "a value for a control a browser may not set"
