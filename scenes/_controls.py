"""Each GUI control declared once, on its parameter's dataclass field: the declaration builds it and cleans it.

A scene's frozen parameter dataclass carries, in each user-settable field's metadata, what the control is: its kind,
label (with the unit), range, step, options, folder. :func:`build_controls` makes the controls from those
declarations, with the field's value as the initial value, and records each one's :class:`~server.clean.ControlSpec`
for the gate from the declaration (never read back from a handle, which a browser can change).
:func:`read_controls` turns what the controls hold now into a new parameter object, cleaning each value with the
gate's own :func:`~server.clean.clean_value` (one clamp, in one place): a number out of range is clamped, anything
unusable (NaN, ±inf, a wrong type, an unknown option) keeps the last good value, and a cleaned value that differs
from the control's is written back so every browser shows what the scene uses.

Kinds: :func:`slider`, :func:`number`, :func:`dropdown` (the field holds the option, the GUI shows its label;
:func:`dropdown_from_labels` takes them from a label → option table),
:func:`checkbox`, :func:`text` and :func:`rgb`. A number is an integer when the field's default is an ``int``. A
field whose default is a tuple of scalars gets one control per element, its label formatted with ``n`` (1, 2, ...)
and ``axis`` (a, b, ...).
A declaration's ``folder`` puts the control in a folder of that name, opened around consecutive fields that name it
(its handle is in :attr:`Controls.folders`, to add buttons or readouts to it). ``names`` builds only some fields,
where the caller is; ``a | b`` joins two builds so one read covers both. A control whose greyed-out state depends on
another's value is declared with its opening state and its ``handle.disabled`` set by the scene.

Adding a control is one declaration. To let the arm's user set a damping factor, add to ``ArmParams``::

    damping: float = field(default=0.5, metadata=slider("Damping", 0.0, 1.0, 0.05, folder="Solver"))
    \"\"\"How much each iteration's step is damped.\"\"\"

The scene's :func:`build_controls` call now makes a "Damping" slider at the end of the Solver folder, the gate clamps
what a browser sends it to [0, 1], and ``read_controls`` (the scene's ``read_params``) fills ``params.damping``; the
scene only has to use the value.
"""

from __future__ import annotations

import contextlib
import dataclasses
import itertools
from collections.abc import Callable, Collection, Iterator, Mapping, Sequence
from typing import TYPE_CHECKING, Any, Generic, Literal, TypeAlias, TypedDict, TypeVar

import viser

from server.clean import MAX_TEXT_CHARS, ControlSpec, clean_value, record_spec

if TYPE_CHECKING:
    from _typeshed import DataclassInstance
    from typing_extensions import Unpack

    from server.sessions import GuiFacade

    GuiLike: TypeAlias = viser.GuiApi | GuiFacade
    """Where controls are made: a session's recording facade, or viser's own GUI API."""

P = TypeVar("P", bound="DataclassInstance")
"""A scene's frozen parameter dataclass."""

METADATA_KEY = "control"
"""The key of a field's metadata that holds its :class:`Control`."""

Handle = viser.GuiInputHandle[Any]
WriteBack = Callable[[Handle, Any], None]
"""How a cleaned value is put back on a control: ``(handle, value)``."""


@dataclasses.dataclass(frozen=True)
class Control:
    """One control as a scene declares it on a parameter field (made by :func:`slider`, :func:`dropdown`...)."""

    kind: Literal["slider", "number", "dropdown", "checkbox", "text", "rgb"]
    label: str
    """Shown beside the control, with the unit: "Speed (km/h)". A tuple field's label is formatted with ``n``."""
    lo: float | None = None
    """Smallest value (slider, number), as given (an int stays an int, so the GUI shows what it was given)."""
    hi: float | None = None
    """Largest value (slider, number)."""
    step: float | None = None
    """Step (slider, number)."""
    decimals: int | None = None
    """Number only: digits the box shows and takes after the point, where a value the scene sets may be finer than
    the step (viser shows as many as the opening value, the range and the step need, and no more)."""
    options: tuple[Any, ...] = ()
    """The values a dropdown's field may take, in the order shown."""
    labels: tuple[str, ...] = ()
    """What the dropdown shows for each of :attr:`options`."""
    choices: Callable[[], Mapping[str, Any]] | None = None
    """A dropdown whose options are read when it is built, as a label → option table, rather than when its class is
    defined (the SDF gallery's kinds come from a registry a program may add to); :meth:`resolved` fills
    :attr:`options` and :attr:`labels` from it."""
    multiline: bool = False
    """Text only: a multi-line box."""
    max_chars: int = MAX_TEXT_CHARS
    """Text only: the longest text the gate passes on (a longer one is refused there, and its tab told why)."""
    folder: str | None = None
    """The folder the control goes in, or None for wherever the builder is called."""
    costly: bool = False
    """A change rebuilds a scene or starts a long job: the gate rations such inputs per tab
    (:func:`server.clean.mark_costly`)."""
    disabled: bool = False
    """Shown greyed out at first (a scene may set ``handle.disabled`` later)."""
    hint: str | None = None
    """A tooltip."""

    def resolved(self) -> Control:
        """This control with its :attr:`choices` read now (itself when it has none)."""
        if self.choices is None:
            return self
        table = self.choices()
        return dataclasses.replace(self, options=tuple(table.values()), labels=tuple(table), choices=None)

    def spec(self, default: object) -> ControlSpec:
        """The gate's spec for this control on a field (or tuple element) whose default is ``default``."""
        match self.kind:
            case "slider" | "number":
                return ControlSpec(
                    "number",
                    lo=None if self.lo is None else float(self.lo),
                    hi=None if self.hi is None else float(self.hi),
                    integer=isinstance(default, int),
                    costly=self.costly,
                )
            case "dropdown":
                return ControlSpec("choice", options=self.labels, costly=self.costly)
            case "checkbox":
                return ControlSpec("bool", costly=self.costly)
            case "text":
                return ControlSpec("text", max_chars=self.max_chars, costly=self.costly)
            case "rgb":
                return ControlSpec("rgb", lo=0.0, hi=255.0, integer=True, length=3, costly=self.costly)

    @property
    def per_element(self) -> bool:
        """Whether a tuple-valued field gets one control per element (every kind but an RGB colour)."""
        return self.kind != "rgb"

    def to_gui(self, value: Any) -> Any:
        """A field value as the control shows it (a dropdown shows an option's label)."""
        if self.kind == "dropdown":
            return self.labels[self.options.index(value)]
        return value

    def from_gui(self, cleaned: Any, default: object) -> Any:
        """A cleaned control value as the field holds it (a dropdown's label becomes its option)."""
        match self.kind:
            case "dropdown":
                return self.options[self.labels.index(cleaned)]
            case "slider" | "number":
                return int(cleaned) if isinstance(default, int) else float(cleaned)
            case _:
                return cleaned

    def add(self, gui: GuiLike, label: str, value: Any) -> Handle:
        """Make this control on ``gui`` showing ``value`` (a field value)."""
        common: dict[str, Any] = {"disabled": self.disabled, "hint": self.hint}
        match self.kind:
            case "slider":
                assert self.lo is not None and self.hi is not None and self.step is not None
                return gui.add_slider(label, self.lo, self.hi, self.step, value, **common)
            case "number":
                box = gui.add_number(label, value, min=self.lo, max=self.hi, step=self.step, **common)
                if self.decimals is not None:
                    box.precision = self.decimals
                return box
            case "dropdown":
                return gui.add_dropdown(label, self.labels, initial_value=self.to_gui(value), **common)
            case "checkbox":
                return gui.add_checkbox(label, value, **common)
            case "text":
                return gui.add_text(label, value, multiline=self.multiline, **common)
            case "rgb":
                return gui.add_rgb(label, value, **common)


class Placement(TypedDict, total=False):
    """What a control of any kind may also be given: see the fields of the same names on :class:`Control`."""

    folder: str | None
    costly: bool
    disabled: bool
    hint: str | None


def _declare(control: Control) -> dict[str, Control]:
    return {METADATA_KEY: control}


def slider(label: str, lo: float, hi: float, step: float, **placement: Unpack[Placement]) -> dict[str, Control]:
    """A slider over [lo, hi] in steps of ``step``; an integer one when the field's default is an ``int``."""
    return _declare(Control("slider", label, lo, hi, step, **placement))


def number(
    label: str,
    lo: float | None = None,
    hi: float | None = None,
    step: float | None = None,
    *,
    decimals: int | None = None,
    **placement: Unpack[Placement],
) -> dict[str, Control]:
    """A number box, clamped to [lo, hi] where given, showing ``decimals`` digits after the point where given."""
    return _declare(Control("number", label, lo, hi, step, decimals=decimals, **placement))


def dropdown(
    label: str, options: Sequence[Any], labels: Sequence[str] | None = None, **placement: Unpack[Placement]
) -> dict[str, Control]:
    """A dropdown of ``options`` (the field's possible values), shown as ``labels`` (default: the options)."""
    shown = tuple(str(option) for option in options) if labels is None else tuple(labels)
    assert len(shown) == len(options) and len(set(shown)) == len(shown), "one distinct label per option"
    return _declare(Control("dropdown", label, options=tuple(options), labels=shown, **placement))


def dropdown_from_labels(
    label: str, option_from_label: Mapping[str, Any] | Callable[[], Mapping[str, Any]], **placement: Unpack[Placement]
) -> dict[str, Control]:
    """A dropdown of ``option_from_label``'s values, each shown as its key (a scene's ``X_FROM_LABEL`` table); given
    a function returning that table, the table is read each time the dropdown is built (:attr:`Control.choices`)."""
    if callable(option_from_label):
        return _declare(Control("dropdown", label, choices=option_from_label, **placement))
    return dropdown(label, tuple(option_from_label.values()), tuple(option_from_label), **placement)


def checkbox(label: str, **placement: Unpack[Placement]) -> dict[str, Control]:
    """A checkbox for a ``bool`` field."""
    return _declare(Control("checkbox", label, **placement))


def text(
    label: str, *, multiline: bool = False, max_chars: int = MAX_TEXT_CHARS, **placement: Unpack[Placement]
) -> dict[str, Control]:
    """A text box for a ``str`` field; the gate refuses text over ``max_chars`` and tells the tab that sent it, so a
    scene declares the most it keeps."""
    return _declare(Control("text", label, multiline=multiline, max_chars=max_chars, **placement))


def rgb(label: str, **placement: Unpack[Placement]) -> dict[str, Control]:
    """A colour picker for a ``tuple[int, int, int]`` field (0–255 each)."""
    return _declare(Control("rgb", label, **placement))


def declared(params_type: type[Any]) -> dict[str, Control]:
    """The declared controls of a parameter dataclass, by field name, in field order."""
    return {
        field.name: field.metadata[METADATA_KEY]
        for field in dataclasses.fields(params_type)
        if METADATA_KEY in field.metadata
    }


# --------------------------------------------------------------------------------------------- build, read
@dataclasses.dataclass(frozen=True)
class Built:
    """The controls of one field: one handle, or one per element of a tuple field."""

    control: Control
    handles: tuple[Handle, ...]
    specs: tuple[ControlSpec, ...]
    """Each handle's spec, as recorded for the gate."""
    per_element: bool
    """Whether the field is a tuple with one control per element."""


@dataclasses.dataclass(frozen=True)
class Controls(Generic[P]):
    """The controls :func:`build_controls` made for a parameter dataclass, by field name in field order."""

    params_type: type[P]
    fields: Mapping[str, Built]
    folders: Mapping[str, viser.GuiFolderHandle]
    """The folders the builder opened, by label."""

    def __getitem__(self, name: str) -> Handle:
        """The one control of field ``name`` (use :meth:`each` for a tuple field's)."""
        built = self.fields[name]
        assert not built.per_element, f"{name} has one control per element: use each()"
        return built.handles[0]

    def each(self, name: str) -> tuple[Handle, ...]:
        """Every control of field ``name`` (one per element of a tuple field)."""
        return self.fields[name].handles

    def __or__(self, other: Controls[P]) -> Controls[P]:
        """Both sets of controls as one (built by separate calls, e.g. with a button between them), so one
        :func:`read_controls` reads them all."""
        assert self.params_type is other.params_type, "controls of two parameter types"
        assert not self.fields.keys() & other.fields.keys(), "a field built twice"
        return Controls(self.params_type, {**self.fields, **other.fields}, {**self.folders, **other.folders})

    def __iter__(self) -> Iterator[Handle]:
        """Every handle, in field order."""
        for built in self.fields.values():
            yield from built.handles

    def on_update(self, callback: Callable[[Any], None]) -> None:
        """Call ``callback`` when any of the controls changes."""
        for handle in self:
            handle.on_update(callback)

    def with_range(self, name: str, lo: float, hi: float) -> Controls[P]:
        """These controls with field ``name``'s slider or number box over [lo, hi]: the handle shows the range, and
        the gate and :func:`read_controls` clamp to it (a range that depends on what the scene loaded, such as the
        course's Position slider over the route's length). The handle is the same; use the returned controls."""
        built = self.fields[name]
        control = dataclasses.replace(built.control, lo=lo, hi=hi)
        assert control.kind in ("slider", "number") and not built.per_element, f"{name} has no one range"
        handle = built.handles[0]
        assert isinstance(handle, (viser.GuiSliderHandle, viser.GuiNumberHandle))
        handle.min, handle.max = lo, hi
        spec = record_spec(handle, dataclasses.replace(built.specs[0], lo=float(lo), hi=float(hi)))
        fields = {**self.fields, name: dataclasses.replace(built, control=control, specs=(spec,))}
        return Controls(self.params_type, fields, self.folders)


def build_controls(
    gui: GuiLike,
    params: P,
    names: Collection[str] | None = None,
    *,
    collapsed: Collection[str] = (),
    folders_open: Mapping[str, viser.GuiFolderHandle] | None = None,
    label_args: Mapping[str, object] | None = None,
) -> Controls[P]:
    """Make the declared controls of ``params`` (all of them, or the fields in ``names``), in field order.

    Each shows its field's value in ``params`` and gets the spec of its declaration recorded for the gate. Controls
    go where ``gui`` adds them now (inside a ``with folder:`` block of the caller's), or into a folder of the name
    their declaration gives, opened once around consecutive fields that name it; folders in ``collapsed`` open
    closed. A folder in ``folders_open`` (an earlier build's :attr:`Controls.folders`) is filled on instead of
    opened again, so a scene can put a control of its own between two builds of one folder. Where ``label_args`` is
    given, labels and folder names are formatted with it (the SDF gallery builds each primitive slot's controls
    from one declaration, "P{slot} kind" in "Primitive {slot}"); ``collapsed`` names folders as formatted.
    """
    params_type = type(params)
    controls = declared(params_type)
    if names is not None:
        unknown = set(names) - set(controls)
        assert not unknown, f"no declared control for {sorted(unknown)} in {params_type.__name__}"
    chosen = [(name, c) for name, c in controls.items() if names is None or name in names]
    fields: dict[str, Built] = {}
    folders: dict[str, viser.GuiFolderHandle] = dict(folders_open or {})
    for folder, group in itertools.groupby(chosen, key=lambda item: item[1].folder):
        label = folder if folder is None or label_args is None else folder.format(**label_args)
        if label is not None and label not in folders:
            folders[label] = gui.add_folder(label, expand_by_default=label not in collapsed)
        with contextlib.nullcontext() if label is None else folders[label]:
            for name, control in group:
                fields[name] = _build_field(gui, control, getattr(params, name), label_args)
    return Controls(params_type, fields, folders)


def _build_field(gui: GuiLike, control: Control, value: Any, label_args: Mapping[str, object] | None) -> Built:
    control = control.resolved()
    per_element = isinstance(value, tuple) and control.per_element
    values = value if per_element else (value,)
    handles: list[Handle] = []
    specs: list[ControlSpec] = []
    for n, element in enumerate(values, start=1):
        if per_element:  # "Rider {n} power (W)", "P{slot} size {axis} (m)"
            label = control.label.format(n=n, axis=chr(ord("a") + n - 1), **(label_args or {}))
        else:
            label = control.label if label_args is None else control.label.format(**label_args)
        handle = control.add(gui, label, element)
        spec = record_spec(handle, control.spec(element))
        handles.append(handle)
        specs.append(spec)
    return Built(control, tuple(handles), tuple(specs), per_element)


def set_value(handle: Handle, value: Any) -> None:
    """Put ``value`` on ``handle`` (the default write-back; a scene passes one that does not re-enter its
    callbacks)."""
    handle.value = value


def read_controls(controls: Controls[P], last_good: P, *, write_back: WriteBack = set_value) -> P:
    """A new parameter object from what the controls hold now, each value cleaned as the gate cleans it.

    A number outside its declared range is clamped to it; a value the gate would refuse (NaN, ±inf, a wrong type,
    an option the dropdown does not have) keeps its field's value in ``last_good``. Whenever the value used differs
    from the control's, it is written back with ``write_back``. Fields without a control keep ``last_good``'s value.
    """
    assert isinstance(last_good, controls.params_type)
    changes: dict[str, Any] = {}
    for name, built in controls.fields.items():
        old = getattr(last_good, name)
        olds = old if built.per_element else (old,)
        assert len(olds) == len(built.handles), f"{name} has {len(built.handles)} controls"
        values = tuple(
            _read(built.control, spec, handle, good, write_back)
            for handle, spec, good in zip(built.handles, built.specs, olds, strict=True)
        )
        changes[name] = values if built.per_element else values[0]
    return dataclasses.replace(last_good, **changes)


def _read(control: Control, spec: ControlSpec, handle: Handle, last_good: Any, write_back: WriteBack) -> Any:
    raw = handle.value
    accepted, cleaned, _reason = clean_value(spec, raw)
    if not accepted:
        write_back(handle, control.to_gui(last_good))
        return last_good
    if not same_value(raw, cleaned):
        write_back(handle, cleaned)
    return control.from_gui(cleaned, last_good)


def same_value(raw: object, cleaned: object) -> bool:
    """Whether a control showing ``raw`` already shows ``cleaned`` (1 and 1.0 are the same number; True is not 1)."""
    if isinstance(raw, bool) or isinstance(cleaned, bool):
        return type(raw) is type(cleaned) and raw == cleaned
    if isinstance(raw, (int, float)) and isinstance(cleaned, (int, float)):
        return raw == cleaned
    return type(raw) is type(cleaned) and raw == cleaned
