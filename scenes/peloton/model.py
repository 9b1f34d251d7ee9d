"""The peloton's line model: riding positions, the scene's parameters, and pure functions from them to a state.

:class:`PelotonParams` is everything a user sets (each field also declares its GUI control, :mod:`scenes._controls`);
:func:`compute_line` turns it into a :class:`LineState` of per-rider drag and power, leader first, through
:mod:`kernels.cycling`; :func:`solo_curves` and :func:`solo_speed` give the lone rider's power curve and speed at a
power for the chart and readout. Nothing here touches a viser handle: every function is testable alone. SI units
inside (m, s, W); km/h, % and the like only in the parameters, as the GUI shows them.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import field
from typing import Literal

import numpy as np

from kernels import cycling
from scenes._controls import checkbox, dropdown_from_labels, number, slider

MAX_RIDERS = 8
"""Riders of a single file drawn with their own power bars and labels (more, or another formation, are coloured by
power instead)."""
MAX_GROUP = 121
"""Most riders the scene shows: Blocken et al. 2018's peloton."""
LATERAL_M = 0.6
"""Distance between the centres of riders side by side in a formation (m)."""
BIKE_LENGTH_M = 1.70
"""Wheel-to-wheel length of one bike; the gap is measured from the front wheel to the wheel ahead."""
MAX_GAP_M = 15.0
"""Largest wheel-to-wheel gap the slider offers (m): beyond ~3 m drafting is gone (Blocken et al. 2013)."""
ROAD_HALF_WIDTH_M = 3.0
"""Half the drawn road's width (m): a bunch eight abreast fits on it. A course's road is wider where its formation
is wider."""

Position = Literal["upright", "hoods", "drops", "tt", "hour"]


@dataclasses.dataclass(frozen=True)
class RidingPosition:
    label: str
    cda_m2: float
    """Typical drag area for the position (the original brief's table; hour record from Bigham 2022)."""
    torso_deg: float
    """Torso angle above horizontal, for the drawing."""
    hands: tuple[float, float, float]
    """Where the hands rest, in the bike frame (m)."""


POSITIONS: dict[Position, RidingPosition] = {
    "upright": RidingPosition("Upright (commuting)", 0.55, 62.0, (0.42, 0.20, 1.00)),
    "hoods": RidingPosition("Hoods", 0.42, 42.0, (0.50, 0.19, 0.95)),
    "drops": RidingPosition("Drops", 0.32, 28.0, (0.50, 0.17, 0.84)),
    "tt": RidingPosition("Time-trial tuck", 0.22, 12.0, (0.62, 0.06, 0.98)),
    "hour": RidingPosition("Hour record", 0.16, 6.0, (0.66, 0.05, 0.96)),
}

CRR_PRESETS: dict[str, float] = {
    "Track, wooden velodrome (0.0020)": 0.0020,
    "Race tyre, smooth asphalt (0.0040)": 0.0040,
    "Training tyre (0.0060)": 0.0060,
    "Gravel tyre (0.0080)": 0.0080,
    "Mountain bike, knobbly (0.0120)": 0.0120,
}
FORMATION_FROM_LABEL: dict[str, cycling.FormationShape] = {
    "Single file": "single",
    "Two abreast": "double",
    "Bunch (peloton)": "bunch",
    "Echelon": "echelon",
}
DraftModelLabel = Literal["Textbook formula (exponential fade)", "Measured (by position)"]
MODEL_FROM_LABEL: dict[str, cycling.DraftModel] = {
    "Textbook formula (exponential fade)": "textbook",
    "Measured (by position)": "measured",
}


@dataclasses.dataclass(frozen=True)
class PelotonParams:
    """Everything the scene shows is a function of these; defaults are the opening state.

    Each field is also its GUI control, declared once (:mod:`scenes._controls`), in the order and folder shown.
    """

    speed_kmh: float = field(default=40.0, metadata=slider("Speed (km/h)", 0.0, 80.0, 0.5, folder="Rider"))
    """Ground speed of the line (km/h)."""
    cda_m2: float = field(default=0.32, metadata=slider("CdA (m²)", 0.10, 0.80, 0.005, folder="Rider"))
    """Drag area of one rider riding alone (m²); the "Position" presets above it set it, and the rider is drawn in
    the position it is nearest (:attr:`position`)."""
    mass_kg: float = field(default=80.0, metadata=slider("Mass, rider + bike (kg)", 30.0, 150.0, 0.5, folder="Rider"))
    """Rider plus bike (kg)."""
    crr: float = field(default=0.0040, metadata=slider("Crr", 0.0, 0.02, 0.0005, folder="Rider"))
    """Rolling-resistance coefficient (the "Tyres / surface" presets above it set it)."""
    drivetrain_pct: float = field(
        default=97.6, metadata=slider("Drivetrain efficiency (%)", 80.0, 100.0, 0.1, folder="Rider")
    )
    """Drivetrain efficiency (%), Martin et al. 1998."""
    grade_pct: float = field(default=0.0, metadata=slider("Grade (%)", -15.0, 20.0, 0.5, folder="Course"))
    """Road grade (%), rise over run."""
    altitude_m: float = field(default=0.0, metadata=slider("Altitude (m)", -500.0, 4000.0, 50.0, folder="Course"))
    """Altitude (m): sets air density; from the Dead Sea's shore (−430 m) to the highest passes."""
    headwind_ms: float = field(
        default=0.0, metadata=slider("Headwind (m/s, − = tailwind)", -15.0, 15.0, 0.5, folder="Course")
    )
    """Wind against the riders (m/s); negative is a tailwind."""
    crosswind_ms: float = field(
        default=0.0, metadata=slider("Crosswind (m/s, + from the left)", -15.0, 15.0, 0.5, folder="Course")
    )
    """Wind across the road (m/s, + blowing from the riders' left): it turns the wakes downwind
    (:func:`formation_yaw`), so a line loses its shelter and an echelon forms on the downwind side. The power's air
    speed is the wind along the road (the headwind)."""
    drafting: bool = field(default=True, metadata=checkbox("Drafting", folder="Drafting"))
    """Whether riders behind the leader draft."""
    formation: cycling.FormationShape = field(
        default="single", metadata=dropdown_from_labels("Formation", FORMATION_FROM_LABEL, folder="Drafting")
    )
    """How the riders ride together: single file, two abreast, a bunch or an echelon."""
    n_riders: int = field(default=4, metadata=slider("Riders", 1, MAX_GROUP, 1, folder="Drafting"))
    """Riders in the group."""
    gap_m: float = field(default=0.5, metadata=slider("Gap (m)", 0.0, MAX_GAP_M, 0.1, folder="Drafting"))
    """Wheel-to-wheel gap between riders (m)."""
    model: cycling.DraftModel = field(
        default="measured", metadata=dropdown_from_labels("Draft model", MODEL_FROM_LABEL, folder="Drafting")
    )
    """Drafting model: the textbook formula or the position-dependent fit to measurements."""
    rotate: bool = field(default=False, metadata=checkbox("Rotate the lead", folder="Drafting"))
    """Whether the lead rotates: every turn the leader swings off and drops to the back."""
    turn_s: float = field(default=6.0, metadata=slider("Turn at the front (s)", 2.0, 30.0, 1.0, folder="Drafting"))
    """Seconds each rider leads when the lead rotates."""
    target_power_w: float = field(
        default=250.0, metadata=number("Power (W)", 0.0, 2500.0, 5.0, folder="Speed at a power")
    )
    """Power for the 'speed at this power' readout (W)."""

    @property
    def position(self) -> Position:
        """The riding position drawn: the one whose typical CdA is nearest :attr:`cda_m2` (the first of two as near),
        so the drawing and the "Position" menu never disagree."""
        return min(POSITIONS, key=lambda key: abs(POSITIONS[key].cda_m2 - self.cda_m2))


# --------------------------------------------------------------------------------------------- preset menus
CUSTOM = "Custom"
"""What a preset menu shows when its field's value is none of its presets; choosing it leaves the value as it is."""
PRESET_REL_TOL = 1e-9
"""A value is a preset's when it is within this fraction of it: a slider's steps carry rounding (0.1 + 44 × 0.005
is 0.32000000000000006), far below any difference a person types."""


@dataclasses.dataclass(frozen=True)
class PresetMenu:
    """A dropdown that sets one parameter to a named value, and shows the name of the value the parameter holds now
    (or :data:`CUSTOM`). It is no parameter of its own: it is shown just above its field's control, in its folder."""

    label: str
    field: str
    """The :class:`PelotonParams` field a preset sets."""
    presets: dict[str, float]
    """Each preset's name (as shown) and value."""

    @property
    def options(self) -> tuple[str, ...]:
        """What the dropdown offers: every preset, then :data:`CUSTOM`."""
        return (*self.presets, CUSTOM)

    def shown(self, params: PelotonParams) -> str:
        """What the menu shows for ``params``: :func:`preset_name` of its field's value."""
        return preset_name(self.presets, getattr(params, self.field))


def preset_name(presets: dict[str, float], value: float) -> str:
    """The name of the preset ``value`` is (to :data:`PRESET_REL_TOL`), else :data:`CUSTOM`: the one rule every
    preset menu shows by."""
    for name, preset in presets.items():
        if math.isclose(value, preset, rel_tol=PRESET_REL_TOL):
            return name
    return CUSTOM


PRESET_MENUS = (
    PresetMenu("Position", "cda_m2", {p.label: p.cda_m2 for p in POSITIONS.values()}),
    PresetMenu("Tyres / surface", "crr", CRR_PRESETS),
)
"""Every preset menu of the scene, each shown above its field's control."""


@dataclasses.dataclass(frozen=True)
class LineState:
    """Per-rider results for the current parameters, leader first."""

    reduction: np.ndarray
    cda_m2: np.ndarray
    power: cycling.Power
    solo: cycling.Power
    positions: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((0, 2)))
    """(n, 2) where each rider rides (m): x forward, y to the left, leader first."""

    @functools.cached_property
    def pedal_w(self) -> np.ndarray:
        """(n,) what each rider pedals (W): the power the speed needs, or 0 where it needs less than nothing (down a
        slope the rider coasts and brakes off the rest, :attr:`brake_w`), as in course mode."""
        return np.maximum(np.asarray(self.power.total, np.float64), 0.0)

    @functools.cached_property
    def brake_w(self) -> np.ndarray:
        """(n,) what each rider brakes off to hold the speed (W): the power the speed needs below 0, as positive."""
        return np.maximum(-np.asarray(self.power.total, np.float64), 0.0)

    @property
    def solo_pedal_w(self) -> float:
        """What the same rider alone pedals (W), 0 where it coasts."""
        return max(float(self.solo.total), 0.0)

    @functools.cached_property
    def saving(self) -> np.ndarray:
        """(n,) fraction of the solo rider's pedalling each rider saves; zero when riding alone costs nothing."""
        solo = self.solo_pedal_w
        if solo <= 0.0:
            return np.zeros_like(self.pedal_w)
        return 1.0 - self.pedal_w / solo

    @functools.cached_property
    def pedals_more(self) -> np.ndarray:
        """(n,) bool: the riders who pedal more than alone (to 0.1 % of the solo rider's power), as a rider sheltered
        from a tailwind's push does; their saving is none."""
        return (self.solo_pedal_w > 0.0) & (np.round(100.0 * self.saving, 1) < 0.0)

    @property
    def solo_spent_w(self) -> float:
        """What the solo rider's power is spent on (W): the air where it drags, the tyres, the climb uphill. Down a
        slope or in a tailwind faster than the rider, gravity or the wind pays part of it."""
        solo = self.solo
        return max(float(solo.aero), 0.0) + float(solo.rolling) + max(float(solo.climbing), 0.0)


def compute_line(p: PelotonParams) -> LineState:
    """Run the kernels for one parameter set (no viser: testable on its own)."""
    n = p.n_riders
    common = dict(
        mass_kg=p.mass_kg,
        crr=p.crr,
        grade=p.grade_pct / 100.0,
        altitude_m=p.altitude_m,
        headwind_ms=p.headwind_ms,
        drivetrain_efficiency=p.drivetrain_pct / 100.0,
    )
    speed = p.speed_kmh / 3.6
    positions = formation_positions(p)
    reduction = drag_reductions(p) if p.drafting else np.zeros(n)
    cda = p.cda_m2 * (1.0 - reduction)
    power = cycling.power(np.full(n, speed), cda, **common)
    solo = cycling.power(speed, p.cda_m2, **common)
    return LineState(reduction=reduction, cda_m2=cda, power=power, solo=solo, positions=positions)


MAX_YAW_RAD = math.radians(85.0)
"""Largest apparent-wind yaw the wakes are turned by (rad): a tailwind as fast as the riders has no wake to ride in
that the model knows; past 85° it is held there."""


def formation_yaw(p: PelotonParams) -> float:
    """Yaw of the apparent wind the group rides in (rad, + from the left): :func:`kernels.cycling.apparent_yaw` of the
    speed, headwind and crosswind, held within ±:data:`MAX_YAW_RAD`. Without a crosswind: 0 where the air meets the
    riders head on, and :data:`MAX_YAW_RAD` where a tailwind as fast as they or faster brings it from behind, as the
    least crosswind there does (the wakes, which the model lays out behind the riders, give no shelter)."""
    if p.crosswind_ms == 0.0:
        return 0.0 if p.speed_kmh / 3.6 + p.headwind_ms > 0.0 else MAX_YAW_RAD
    yaw = cycling.apparent_yaw(p.speed_kmh / 3.6, p.headwind_ms, p.crosswind_ms)
    return float(np.clip(yaw, -MAX_YAW_RAD, MAX_YAW_RAD))


def wind_words(p: PelotonParams) -> str:
    """The ground wind in a few words, for the label at the wind arrow ("headwind 5 m/s", "crosswind 8 m/s from the
    left", "wind 9.4 m/s (5 head, 8 from left)"); "" in still air. The arrow alone is foreshortened where the view
    looks across the road, as the side view of a line does."""
    head, cross = p.headwind_ms, p.crosswind_ms
    side = "left" if cross > 0 else "right"
    if cross == 0.0:
        return "" if head == 0.0 else f"{'headwind' if head > 0 else 'tailwind'} {abs(head):.3g} m/s"
    if head == 0.0:
        return f"crosswind {abs(cross):.3g} m/s from the {side}"
    along = f"{abs(head):.3g} {'head' if head > 0 else 'tail'}"
    return f"wind {math.hypot(head, cross):.2g} m/s ({along}, {abs(cross):.3g} from {side})"


def yaw_words(p: PelotonParams) -> str:
    """Where the air meets the riders, for the panel ("the air meets the riders 36° off their line, from the
    left"); "" without a crosswind, where it meets them head on (or from behind, in a tailwind faster than they)."""
    if p.crosswind_ms == 0.0:
        return ""
    yaw = math.degrees(cycling.apparent_yaw(p.speed_kmh / 3.6, p.headwind_ms, p.crosswind_ms))
    return f"the air meets the riders {abs(yaw):.0f}° off their line, from the {'left' if yaw > 0 else 'right'}"


def _formation(p: PelotonParams) -> np.ndarray:
    """The formation as the kernel lays it out; an echelon on the downwind side (it steps to the right behind its
    leader, into a wind from the left; mirrored for a wind from the right)."""
    xy = cycling.formation(p.n_riders, p.formation, gap_m=p.gap_m, lateral_m=LATERAL_M)
    if p.formation == "echelon" and p.crosswind_ms < 0.0:
        xy = xy * np.array([1.0, -1.0])
    return xy


def formation_positions(p: PelotonParams) -> np.ndarray:
    """(n_riders, 2) positions of the riders in the chosen formation on the road (m), leader first: the formation
    moved across the road so that its outermost riders are as far left of the road's axis as right of it (an
    echelon starts at the left edge and steps across to the right one). Moving a whole group changes no rider's
    drag: the wake model sees only the riders' offsets from each other."""
    xy = _formation(p)
    return xy - [0.0, 0.5 * float(xy[:, 1].min() + xy[:, 1].max())]


def drag_reductions(p: PelotonParams, yaw_rad: float | None = None) -> np.ndarray:
    """(n_riders,) drag reduction of each rider, leader first: the line model in single file in still air (as it
    always was), the formation wake model (:func:`kernels.cycling.formation_drag`) otherwise, its wakes turned by
    ``yaw_rad`` (rad; None: the flat road's own, :func:`formation_yaw`)."""
    yaw = formation_yaw(p) if yaw_rad is None else yaw_rad
    if p.formation == "single" and yaw == 0.0:
        return cycling.drag_reduction(p.n_riders, p.gap_m, p.model)
    return 1.0 - cycling.formation_drag(_formation(p), p.model, yaw_rad=yaw)


def is_line_view(p: PelotonParams) -> bool:
    """Whether the scene draws the labelled line (single file of at most :data:`MAX_RIDERS`) rather than a group
    coloured by power."""
    return p.formation == "single" and p.n_riders <= MAX_RIDERS


def group_cda(line: PelotonParams) -> float:
    """CdA of a rider in a group that shares the work evenly: the mean over the formation's positions, in still air
    (course mode's wind is the route's own)."""
    if not line.drafting or line.n_riders < 2:
        return line.cda_m2
    return float(line.cda_m2 * (1.0 - np.mean(drag_reductions(line, yaw_rad=0.0))))


# The solo rider's curve and speed-at-power depend on neither the speed nor the line: moving the speed slider (the
# control people move most) reuses them.
SoloKey = tuple[float, float, float, float, float, float, float]
"""What the solo rider's curve depends on: CdA, mass, Crr, grade (%), altitude, headwind, drivetrain (%)."""


def solo_key(p: PelotonParams) -> SoloKey:
    """The parameters the solo rider's curve and speed at a power depend on (a cache key)."""
    return (p.cda_m2, p.mass_kg, p.crr, p.grade_pct, p.altitude_m, p.headwind_ms, p.drivetrain_pct)


@functools.lru_cache(maxsize=64)
def solo_curves(key: SoloKey) -> tuple[np.ndarray, ...]:
    """(speeds in km/h, aero, rolling, climbing, total) of one rider from 0 to 80 km/h, for the chart."""
    cda, mass, crr, grade_pct, altitude, wind, drivetrain_pct = key
    speeds_kmh = np.linspace(0.0, 80.0, 161)
    solo = cycling.power(speeds_kmh / 3.6, cda, mass, crr, grade_pct / 100.0, altitude, wind, drivetrain_pct / 100.0)
    curves = (speeds_kmh, solo.aero, solo.rolling, solo.climbing, solo.total)
    for curve in curves:
        curve.setflags(write=False)  # shared between calls
    return curves


@functools.lru_cache(maxsize=64)
def solo_speed(key: SoloKey, power_w: float) -> float:
    """Speed (m/s) at which one rider alone holds ``power_w`` (W)."""
    cda, mass, crr, grade_pct, altitude, wind, drivetrain_pct = key
    return float(
        cycling.speed_for_power(power_w, cda, mass, crr, grade_pct / 100.0, altitude, wind, drivetrain_pct / 100.0)
    )
