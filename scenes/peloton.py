"""Peloton: riders in a line, their power split into aero / rolling / climbing, drafting by gap, live.

Physics comes from :mod:`kernels.cycling`; this module owns the viser handles. The riders are three batched meshes
(bodies in team colours, bikes, heads) with one instance per rider, so a redraw is a handful of array writes. The
scene opens with eight instances and hides the unused ones by scaling them to zero, so changing the rider count
never re-adds a node.
"""

from __future__ import annotations

import dataclasses
import functools
import logging
import math
import threading
from typing import Literal

import numpy as np
import trimesh
import viser
import viser.uplot

from kernels import course as course_kernel
from kernels import cycling
from scenes._base import Scene, record_spec, set_if_changed
from scenes._charts import FittedChart
from scenes._framing import ClientFraming, Lens, View, frame_points

MAX_RIDERS = 8
BIKE_LENGTH_M = 1.70
MAX_GAP_M = 15.0
"""Largest wheel-to-wheel gap the slider offers (m): beyond ~3 m drafting is gone (Blocken et al. 2013)."""
ROAD_X_M = (-(MAX_RIDERS - 1) * (BIKE_LENGTH_M + MAX_GAP_M) - 15.0, 15.0)
"""(start, end) x of the drawn road (m): the longest line (8 riders, the largest gap) rides on it, with 15 m spare
at each end."""
"""Wheel-to-wheel length of one bike; the gap is measured from the front wheel to the wheel ahead."""
BAR_METRES_PER_WATT = 1.0 / 400.0
"""Height of the stacked power bars above the riders."""
VIEW_DIRECTION = (-1.2, 7.5, -1.8)
"""The camera looks at the line from its left side, a little ahead of it and above."""
LABEL_STAGGER_M = 0.4
"""Every other rider's label sits this much higher (m) until a camera is framed and the labels laid out for it."""
LABEL_PX = (190.0, 30.0)
"""Room a rider's label needs right of and above its anchor (px): framing keeps it clear of the panel."""
BAR_HEADROOM = 1.3
"""Bars that outgrow the framed view are framed again this many times as tall: power goes with the cube of speed, so
a drag from 30 to 50 km/h re-frames about 7 times instead of 20."""

Position = Literal["upright", "hoods", "drops", "tt", "hour"]


@dataclasses.dataclass(frozen=True)
class RidingPosition:
    label: str
    cda_m2: float
    """Typical drag area for the position (seed's table; hour record from Bigham 2022)."""
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
POSITION_FROM_LABEL: dict[str, Position] = {p.label: key for key, p in POSITIONS.items()}

CRR_PRESETS: dict[str, float] = {
    "Track, wooden velodrome (0.0020)": 0.0020,
    "Race tyre, smooth asphalt (0.0040)": 0.0040,
    "Training tyre (0.0060)": 0.0060,
    "Gravel tyre (0.0080)": 0.0080,
    "Mountain bike, knobbly (0.0120)": 0.0120,
}
DraftModelLabel = Literal["Seed formula", "Measured (by position)"]
MODEL_FROM_LABEL: dict[str, cycling.DraftModel] = {
    "Seed formula": "seed",
    "Measured (by position)": "measured",
}

JERSEYS = np.array(
    [
        (220, 40, 40),
        (30, 110, 220),
        (250, 200, 30),
        (40, 170, 90),
        (150, 60, 200),
        (250, 130, 30),
        (30, 190, 200),
        (230, 90, 160),
    ],
    dtype=np.uint8,
)
COMPONENT_COLOURS = {"aero": (60, 130, 240), "rolling": (245, 160, 40), "climbing": (60, 190, 90)}


@dataclasses.dataclass(frozen=True)
class PelotonParams:
    """Everything the scene shows is a function of these; defaults are the opening state."""

    speed_kmh: float = 40.0
    """Ground speed of the line (km/h)."""
    position: Position = "drops"
    """Riding position: sets the drawing and, when chosen, the CdA."""
    cda_m2: float = 0.32
    """Drag area of one rider riding alone (m²)."""
    mass_kg: float = 80.0
    """Rider plus bike (kg)."""
    crr: float = 0.0040
    """Rolling-resistance coefficient."""
    drivetrain_pct: float = 97.6
    """Drivetrain efficiency (%), Martin et al. 1998."""
    grade_pct: float = 0.0
    """Road grade (%), rise over run."""
    altitude_m: float = 0.0
    """Altitude (m): sets air density."""
    headwind_ms: float = 0.0
    """Wind against the riders (m/s); negative is a tailwind."""
    drafting: bool = True
    """Whether riders behind the leader draft."""
    n_riders: int = 4
    """Riders in the line."""
    gap_m: float = 0.5
    """Wheel-to-wheel gap between riders (m)."""
    model: cycling.DraftModel = "measured"
    """Drafting model: the seed's formula or the position-dependent fit to measurements."""
    target_power_w: float = 250.0
    """Power for the 'speed at this power' readout (W)."""


@dataclasses.dataclass(frozen=True)
class LineState:
    """Per-rider results for the current parameters, leader first."""

    reduction: np.ndarray
    cda_m2: np.ndarray
    power: cycling.Power
    solo: cycling.Power

    @property
    def saving(self) -> np.ndarray:
        """(n,) fraction of the solo rider's power each rider saves; zero when riding alone costs nothing."""
        solo = float(self.solo.total)
        if solo <= 0.0:
            return np.zeros_like(self.power.total)
        return 1.0 - self.power.total / solo


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
    reduction = cycling.drag_reduction(n, p.gap_m, p.model) if p.drafting else np.zeros(n)
    cda = p.cda_m2 * (1.0 - reduction)
    power = cycling.power(np.full(n, speed), cda, **common)
    solo = cycling.power(speed, p.cda_m2, **common)
    return LineState(reduction=reduction, cda_m2=cda, power=power, solo=solo)


# The solo rider's curve and speed-at-power depend on neither the speed nor the line: moving the speed slider (the
# control people move most) reuses them.
_SoloKey = tuple[float, float, float, float, float, float, float]


def _solo_key(p: PelotonParams) -> _SoloKey:
    return (p.cda_m2, p.mass_kg, p.crr, p.grade_pct, p.altitude_m, p.headwind_ms, p.drivetrain_pct)


@functools.lru_cache(maxsize=64)
def _solo_curves(key: _SoloKey) -> tuple[np.ndarray, ...]:
    """(speeds in km/h, aero, rolling, climbing, total) of one rider from 0 to 80 km/h, for the chart."""
    cda, mass, crr, grade_pct, altitude, wind, drivetrain_pct = key
    speeds_kmh = np.linspace(0.0, 80.0, 161)
    solo = cycling.power(
        speeds_kmh / 3.6, cda, mass, crr, grade_pct / 100.0, altitude, wind, drivetrain_pct / 100.0
    )
    curves = (speeds_kmh, solo.aero, solo.rolling, solo.climbing, solo.total)
    for curve in curves:
        curve.setflags(write=False)  # shared between calls
    return curves


@functools.lru_cache(maxsize=64)
def _solo_speed(key: _SoloKey, power_w: float) -> float:
    cda, mass, crr, grade_pct, altitude, wind, drivetrain_pct = key
    return float(
        cycling.speed_for_power(
            power_w, cda, mass, crr, grade_pct / 100.0, altitude, wind, drivetrain_pct / 100.0
        )
    )


# --------------------------------------------------------------------------------------------- geometry
def _rod(a: np.ndarray, b: np.ndarray, radius: float) -> trimesh.Trimesh:
    return trimesh.creation.cylinder(radius=radius, segment=np.array([a, b]), sections=8)


def _two_bone_knee(hip: np.ndarray, foot: np.ndarray, thigh: float, shin: float) -> np.ndarray:
    """Knee position in the xz plane by the law of cosines, bending forward (as a rider's knee does)."""
    d_vec = foot - hip
    d = float(np.clip(np.linalg.norm(d_vec), 1e-6, thigh + shin - 1e-6))
    along = (thigh**2 - shin**2 + d**2) / (2 * d)
    height = math.sqrt(max(thigh**2 - along**2, 0.0))
    u = d_vec / np.linalg.norm(d_vec)
    forward = np.array(
        [u[2], 0.0, -u[0]]
    )  # u rotated by −90° about y: in front of the hip–foot line
    if forward[0] < 0:
        forward = -forward
    return hip + along * u + height * forward


def rider_meshes(position: Position) -> dict[str, trimesh.Trimesh]:
    """Low-poly bike, body and head for one rider, in the bike frame (x forward, z up, ground at z = 0)."""
    pose = POSITIONS[position]
    wheel_r = 0.34
    rear, front = np.array([-0.51, 0.0, wheel_r]), np.array([0.51, 0.0, wheel_r])
    bb = np.array([-0.04, 0.0, 0.27])
    seat = np.array([-0.20, 0.0, 0.86])
    head_top = np.array([0.40, 0.0, 0.80])
    bars = np.array([pose.hands[0] - 0.02, 0.0, pose.hands[2] - 0.02])

    bike_parts = []
    for centre in (rear, front):
        wheel = trimesh.creation.torus(
            major_radius=wheel_r - 0.015, minor_radius=0.018, major_sections=24, minor_sections=6
        )
        wheel.apply_transform(trimesh.transformations.rotation_matrix(math.pi / 2, [1, 0, 0]))
        wheel.apply_translation(centre)
        bike_parts.append(wheel)
    for a, b in (
        (rear, bb),
        (rear, seat),
        (bb, seat),
        (bb, head_top),
        (seat, head_top),
        (head_top, front),
    ):
        bike_parts.append(_rod(a, b, 0.016))
    bike_parts.append(_rod(head_top, bars, 0.014))
    bike_parts.append(_rod(bars + [0, -0.2, 0], bars + [0, 0.2, 0], 0.012))
    bike_parts.append(_rod(seat + [-0.08, 0, 0.03], seat + [0.08, 0, 0.03], 0.03))

    theta = math.radians(pose.torso_deg)
    hip = seat + np.array([0.0, 0.0, 0.08])
    shoulder = hip + 0.58 * np.array([math.cos(theta), 0.0, math.sin(theta)])
    body_parts = [_rod(hip, shoulder, 0.13)]
    body_parts[0] = trimesh.creation.capsule(height=0.58, radius=0.12, count=[8, 8])
    body_parts[0].apply_transform(
        trimesh.geometry.align_vectors([0, 0, 1], shoulder - hip)  # capsule axis along the torso
    )
    body_parts[0].apply_translation((hip + shoulder) / 2)
    hands = np.array(pose.hands)
    for side in (-1.0, 1.0):
        s = shoulder + [0.0, side * 0.17, 0.0]
        h = hands * [1.0, side, 1.0]
        if position in ("tt", "hour"):  # elbows on the pads: upper arm down, forearm forward
            elbow = np.array([s[0] + 0.05, side * 0.09, hands[2] - 0.02])
            body_parts += [_rod(s, elbow, 0.045), _rod(elbow, h, 0.04)]
        else:
            body_parts.append(_rod(s, h, 0.045))
        crank = np.array([side * 0.17 * 0.7, 0.0, -side * 0.17 * 0.7])
        foot = bb + crank + [0.0, side * 0.12, 0.0]
        h_side = hip + [0.0, side * 0.1, 0.0]
        knee = _two_bone_knee(h_side, foot, 0.46, 0.46)
        body_parts += [_rod(h_side, knee, 0.065), _rod(knee, foot, 0.05)]
    head_centre = shoulder + 0.17 * np.array(
        [math.cos(theta * 0.5), 0.0, math.sin(theta * 0.5) + 0.6]
    )
    head = trimesh.creation.icosphere(subdivisions=2, radius=0.12)
    head.apply_translation(head_centre)
    bike, body = trimesh.util.concatenate(bike_parts), trimesh.util.concatenate(body_parts)
    assert isinstance(bike, trimesh.Trimesh) and isinstance(body, trimesh.Trimesh)
    return {"bike": bike, "body": body, "head": head}


def slot_offsets(n_riders: int, gap_m: float) -> np.ndarray:
    """(MAX_RIDERS,) x positions of the slots, leader at 0 and each slot one bike plus one gap behind."""
    return -np.arange(MAX_RIDERS) * (BIKE_LENGTH_M + gap_m)


LABEL_PAD_PX = 4.0
"""Clear space kept between two riders' labels (px)."""


def course_to_world(points: np.ndarray, grade_pct: float) -> np.ndarray:
    """(N, 3) points of the course frame (m) in the world: the course frame turns by −atan(grade) about y."""
    theta = math.atan(grade_pct / 100.0)
    c, s = math.cos(theta), math.sin(theta)
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    return np.stack(
        [c * pts[:, 0] - s * pts[:, 2], pts[:, 1], s * pts[:, 0] + c * pts[:, 2]], axis=1
    )


def label_lifts_px(anchors_px: np.ndarray, label_px: tuple[float, float] = LABEL_PX) -> np.ndarray:
    """(N,) how far (px, upward) to lift each label so no two overlap, leader first: each takes the lowest free place.

    Args:
        anchors_px: (N, 2) screen x, y (px, y down) of each label's anchor; its box spans ``label_px`` right of and
            above it.
        label_px: (width, height) of a label's box (px).
    """
    width, height = label_px[0] + LABEL_PAD_PX, label_px[1] + LABEL_PAD_PX
    lifts = np.zeros(len(anchors_px))
    for i, (x, y) in enumerate(np.asarray(anchors_px, dtype=np.float64)):
        # Label j, placed, forbids lifts in (low, high): where the two boxes would share rows.
        blocked = [
            (y - yj + lifts[j] - height, y - yj + lifts[j] + height)
            for j, (xj, yj) in enumerate(anchors_px[:i])
            if abs(x - xj) < width
        ]
        for lift in sorted({0.0, *(high for _, high in blocked)}):
            if lift >= 0.0 and not any(low < lift < high for low, high in blocked):
                lifts[i] = lift
                break
    return lifts


def project_px(points_world: np.ndarray, view: View, lens: Lens) -> np.ndarray:
    """(N, 2) screen x, y (px, y down) of world points (m) seen from ``view`` through ``lens`` (pinhole, z up)."""
    position, look_at = np.asarray(view.position), np.asarray(view.look_at)
    d = (look_at - position) / np.linalg.norm(look_at - position)
    right = np.cross(d, (0.0, 0.0, 1.0))
    right /= np.linalg.norm(right)
    up = np.cross(right, d)
    rel = np.asarray(points_world, dtype=np.float64) - position
    depth = rel @ d
    tan_y = math.tan(0.5 * lens.fov_rad)
    x = (rel @ right) / (depth * tan_y * lens.aspect)
    y = (rel @ up) / (depth * tan_y)
    return np.stack([(x + 1.0) / 2.0 * lens.width_px, (1.0 - y) / 2.0 * lens.height_px], axis=1)


def lift_to_metres(
    anchors_world: np.ndarray,
    lifts_px: np.ndarray,
    up_world: np.ndarray,
    view: View,
    lens: Lens,
) -> np.ndarray:
    """(N,) distances (m) along ``up_world`` that raise each anchor by its lift (px) in ``lens`` from ``view``.

    Exact for the pinhole camera: the screen height of a point moved along a line is a ratio of linear functions
    of the distance, solved for the target height.
    """
    position, look_at = np.asarray(view.position), np.asarray(view.look_at)
    d = (look_at - position) / np.linalg.norm(look_at - position)
    right = np.cross(d, (0.0, 0.0, 1.0))
    right /= np.linalg.norm(right)
    up = np.cross(right, d)
    tan_y = math.tan(0.5 * lens.fov_rad)
    rel = np.asarray(anchors_world, dtype=np.float64) - position
    a, b = rel @ up, float(up_world @ up)
    c, e = (rel @ d) * tan_y, float(up_world @ d) * tan_y
    target = a / c + 2.0 * np.asarray(lifts_px, dtype=np.float64) / max(lens.height_px, 1)
    return np.maximum((target * c - a) / (b - target * e), 0.0)


# --------------------------------------------------------------------------------------------- scene
class PelotonScene(Scene):
    key = "peloton"
    title = "Peloton: cycling power"
    camera_position = (-2.0, -7.5, 2.8)
    camera_look_at = (-3.2, 0.0, 1.0)
    about = """
**What it shows.** Riders in a line at one speed. Each rider's power is split into pushing air (aero), tyre
rolling resistance and climbing; riders behind draft. The bars above the riders stack aero (blue), rolling
(orange) and climbing (green); the label gives watts and the share of the solo rider's power.

**Equations** (SI, θ = atan(grade), w = headwind):
P_aero = ½ρ·CdA·(v+w)|v+w|·v, P_roll = Crr·m·g·cos θ·v, P_climb = m·g·sin θ·v,
P = (P_aero + P_roll + P_climb)/η, ρ = 1.225·exp(−h/8500).

**Drafting.** *Seed formula*: CdA·(1 − 0.27·exp(−gap/3.5)) for every follower (27 % at 0 m, 6.5 % at 5 m; the
seed's prose overstates it). *Measured*: position-dependent, fitted to team-pursuit measurements (Barry et al. 2015;
Fitton et al. 2018; Broker, Kyle & Burke 1999), fading with gap as Swiss Side's CFD does; the leader gains ~3 %
from the rider behind (Blocken et al. 2013).

**Assumptions.** Steady speed, no bearing or wheel-rotation losses, CdA independent of yaw; the exponential
atmosphere is the seed's (ISA gives ρ about 4 % higher at 2000 m).

**Rotate the lead** animates a paceline: every turn the leader swings off and drops to the back, so each rider's
time-averaged power is the mean over positions, far below the leader's.
"""

    def __init__(self, server: viser.ViserServer) -> None:
        super().__init__(server)
        self.params = PelotonParams()
        self.state = compute_line(self.params)
        self._drawn_position: Position | None = None
        self._rotation_time_s = 0.0
        self._rotating = False
        """Whether the lead rotates (the cleaned checkbox: the animation never reads raw browser values)."""
        self._turn_s = 6.0
        """Seconds each rider leads (the cleaned slider)."""
        self._energy_j = np.zeros(MAX_RIDERS)
        self._ridden_s = 0.0
        self._label_lift_m = LABEL_STAGGER_M * (np.arange(MAX_RIDERS) % 2)
        """How far each slot's label sits above its bar (m): laid out for the camera framed last."""
        self._build_gui()
        self._build_world()
        self.redraw()
        self._framed_for = self._framing_key()
        self._framed_points = self.line_points()
        self.framing = ClientFraming(self._view_for, opening=self.camera_position)
        self.watch_cameras(self.framing.on_camera)
        self.start_loop(self._animate, 1.0 / 30.0)
        self.course_mode = CourseMode(self)  # issue 13: ride a GPX course

    # ----------------------------------------------------------------------------------------- GUI
    def _build_gui(self) -> None:
        gui, p = self.server.gui, self.params
        with self.gui_root:
            with gui.add_folder("Rider"):
                self.speed = gui.add_slider(
                    "Speed (km/h)", min=0.0, max=80.0, step=0.5, initial_value=p.speed_kmh
                )
                self.position = gui.add_dropdown(
                    "Position",
                    options=[pos.label for pos in POSITIONS.values()],
                    initial_value=POSITIONS[p.position].label,
                )
                self.cda = gui.add_slider(
                    "CdA (m²)", min=0.10, max=0.80, step=0.005, initial_value=p.cda_m2
                )
                self.mass = gui.add_slider(
                    "Mass, rider + bike (kg)",
                    min=30.0,
                    max=150.0,
                    step=0.5,
                    initial_value=p.mass_kg,
                )
                self.crr_preset = gui.add_dropdown(
                    "Tyres / surface",
                    options=list(CRR_PRESETS),
                    initial_value=next(iter(k for k, v in CRR_PRESETS.items() if v == p.crr)),
                )
                self.crr = gui.add_slider(
                    "Crr", min=0.0, max=0.02, step=0.0005, initial_value=p.crr
                )
                self.drivetrain = gui.add_slider(
                    "Drivetrain efficiency (%)",
                    min=80.0,
                    max=100.0,
                    step=0.1,
                    initial_value=p.drivetrain_pct,
                )
            with gui.add_folder("Course"):
                self.grade = gui.add_slider(
                    "Grade (%)", min=-15.0, max=20.0, step=0.5, initial_value=p.grade_pct
                )
                self.altitude = gui.add_slider(
                    "Altitude (m)", min=0.0, max=4000.0, step=50.0, initial_value=p.altitude_m
                )
                self.wind = gui.add_slider(
                    "Headwind (m/s, − = tailwind)",
                    min=-15.0,
                    max=15.0,
                    step=0.5,
                    initial_value=p.headwind_ms,
                )
            with gui.add_folder("Drafting"):
                self.drafting = gui.add_checkbox("Drafting", initial_value=p.drafting)
                self.riders = gui.add_slider(
                    "Riders", min=1, max=MAX_RIDERS, step=1, initial_value=p.n_riders
                )
                self.gap = gui.add_slider(
                    "Gap (m)", min=0.0, max=MAX_GAP_M, step=0.1, initial_value=p.gap_m
                )
                self.model = gui.add_dropdown(
                    "Draft model",
                    options=list(MODEL_FROM_LABEL),
                    initial_value="Measured (by position)",
                )
                self.rotate = gui.add_checkbox("Rotate the lead", initial_value=False)
                self.turn = gui.add_slider(
                    "Turn at the front (s)", min=2.0, max=30.0, step=1.0, initial_value=6.0
                )
            with gui.add_folder("Results"):
                self.density = gui.add_markdown("")
                self.table = gui.add_markdown("")
                self.rotation = gui.add_markdown("")
                self.chart = FittedChart(
                    gui,
                    data=self._chart_data(),
                    series=(
                        viser.uplot.Series(label="Speed (km/h)"),
                        viser.uplot.Series(label="Aero (W)", stroke="rgb(60,130,240)", width=2),
                        viser.uplot.Series(label="Rolling (W)", stroke="rgb(245,160,40)", width=2),
                        viser.uplot.Series(label="Climbing (W)", stroke="rgb(60,190,90)", width=2),
                        viser.uplot.Series(label="Total (W)", stroke="black", width=2),
                        viser.uplot.Series(
                            label="Solo now (W)",
                            stroke="rgb(220,30,30)",
                            width=1.5,
                            dash=(6.0, 4.0),
                            points=viser.uplot.Series_Points(show=False),
                        ),
                    ),
                    scales={
                        "x": viser.uplot.Scale(time=False, auto=True),
                        "y": viser.uplot.Scale(auto=True),
                    },
                    legend=viser.uplot.Legend(show=True),
                    title="Solo power vs speed (cube law)",
                    aspect=1.4,
                )
            with gui.add_folder("Speed at a power"):
                self.target_power = gui.add_number(
                    "Power (W)", min=0.0, max=2500.0, step=5.0, initial_value=p.target_power_w
                )
                self.speed_out = gui.add_markdown("")

        for handle in (
            self.speed, self.cda, self.mass, self.crr, self.drivetrain, self.grade, self.altitude, self.wind,
            self.drafting, self.riders, self.gap, self.model, self.target_power,
        ):  # fmt: skip
            handle.on_update(self.callback(self._on_input))
        self.position.on_update(self.callback(self._on_position))
        self.crr_preset.on_update(self.callback(self._on_crr_preset))
        self.rotate.on_update(self.callback(self._on_rotate))
        self.turn.on_update(self.callback(self._on_rotate))

    # ----------------------------------------------------------------------------------------- world
    def _build_world(self) -> None:
        scene = self.server.scene
        self.course = scene.add_frame(f"{self.root.name}/course", show_axes=False)
        start, end = ROAD_X_M
        length, middle = end - start, 0.5 * (start + end)
        grass = trimesh.creation.box(extents=(length + 30.0, 60.0, 0.02))
        grass.apply_translation((middle, 0.0, -0.03))
        scene.add_mesh_simple(
            f"{self.course.name}/grass", grass.vertices, grass.faces, color=(120, 165, 95)
        )
        road = trimesh.creation.box(extents=(length, 3.0, 0.02))
        road.apply_translation((middle, 0.0, -0.01))
        self.road = scene.add_mesh_simple(
            f"{self.course.name}/road", road.vertices, road.faces, color=(70, 72, 78)
        )
        dashes = np.array(
            [
                [[x, 0.0, 0.002], [x + 1.5, 0.0, 0.002]]
                for x in np.arange(start + 1.0, end - 1.0, 3.0)
            ]
        )
        scene.add_line_segments(
            f"{self.course.name}/centre_line", dashes, colors=(240, 240, 240), thickness=0.08
        )
        for side in (-1.5, 1.5):
            edge = np.array([[[start, side, 0.003], [end, side, 0.003]]])
            scene.add_line_segments(
                f"{self.course.name}/edge_{side:+.0f}", edge, colors=(250, 250, 250), thickness=0.06
            )

        identity = np.tile([1.0, 0.0, 0.0, 0.0], (MAX_RIDERS, 1))
        zeros = np.zeros((MAX_RIDERS, 3))
        self.riders_nodes: dict[str, viser.BatchedMeshHandle] = {}
        meshes = rider_meshes(self.params.position)
        colours = {
            "bike": np.full((MAX_RIDERS, 3), 45, np.uint8),
            "body": JERSEYS,
            "head": np.full((MAX_RIDERS, 3), 235, np.uint8),
        }
        for part, mesh in meshes.items():
            self.riders_nodes[part] = scene.add_batched_meshes_simple(
                f"{self.course.name}/riders_{part}",
                vertices=mesh.vertices.astype(np.float32),
                faces=mesh.faces.astype(np.uint32),
                batched_wxyzs=identity,
                batched_positions=zeros,
                batched_scales=np.ones((MAX_RIDERS, 3)),
                batched_colors=colours[part],
                lod="off",
            )
        self._drawn_position = self.params.position

        unit_box = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
        unit_box.apply_translation((0.0, 0.0, 0.5))  # grows upward from its base
        self.bars: dict[str, viser.BatchedMeshHandle] = {}
        for component, colour in COMPONENT_COLOURS.items():
            self.bars[component] = scene.add_batched_meshes_simple(
                f"{self.course.name}/bars_{component}",
                vertices=unit_box.vertices.astype(np.float32),
                faces=unit_box.faces.astype(np.uint32),
                batched_wxyzs=identity,
                batched_positions=zeros,
                batched_scales=np.zeros((MAX_RIDERS, 3)),
                batched_colors=np.tile(np.array(colour, np.uint8), (MAX_RIDERS, 1)),
                lod="off",
                cast_shadow=False,
            )
        self.labels = [
            scene.add_label(
                f"{self.course.name}/label_{i}",
                text="",
                position=(0.0, 0.0, 2.0),
                font_screen_scale=0.9,
            )
            for i in range(MAX_RIDERS)
        ]
        self.wind_arrow = scene.add_line_segments(
            f"{self.root.name}/wind", np.zeros((3, 2, 3)), colors=(120, 200, 255), thickness=0.05
        )

    # ----------------------------------------------------------------------------------------- callbacks
    def _on_position(self) -> None:
        label = self.read_choice(
            self.position, list(POSITION_FROM_LABEL), POSITIONS[self.params.position].label
        )
        preset = POSITIONS[POSITION_FROM_LABEL[label]]
        self._write_back(self.cda, preset.cda_m2)
        self._on_input()

    def _on_crr_preset(self) -> None:
        closest = min(CRR_PRESETS, key=lambda label: abs(CRR_PRESETS[label] - self.params.crr))
        label = self.read_choice(self.crr_preset, list(CRR_PRESETS), closest)
        self._write_back(self.crr, CRR_PRESETS[label])
        self._on_input()

    def _on_rotate(self) -> None:
        self._rotating = self.read_bool(self.rotate, self._rotating)
        self._turn_s = self.read_number(self.turn, self._turn_s)
        self._rotation_time_s = 0.0
        self._energy_j[:] = 0.0
        self._ridden_s = 0.0
        self.redraw()
        self.wake_loops()

    def _on_input(self) -> None:
        last_good = (self.params, self.state)
        self.params = self.read_params()
        self.state = compute_line(self.params)
        self._energy_j[:] = 0.0
        self._ridden_s = 0.0
        try:
            self.redraw()
        except Exception:
            self.params, self.state = last_good  # never show one state while holding another
            self.redraw()
            raise
        self._update_framing()
        # An input can start the rotation (Riders raised from 1 while Rotate is on): wake the loop.
        if self._rotating and self.params.n_riders > 1:
            self.wake_loops()

    # ----------------------------------------------------------------------------------------- camera
    def line_points(self, bar_headroom: float = 1.0) -> np.ndarray:
        """(N, 3) world points the view must hold: every rider (also swinging off), bar tops (``bar_headroom`` times
        as tall as now) and the wind arrow."""
        p = self.params
        n = p.n_riders
        front, back = (
            0.5 * BIKE_LENGTH_M,
            float(slot_offsets(n, p.gap_m)[n - 1]) - 0.5 * BIKE_LENGTH_M,
        )
        top = 1.95 + LABEL_STAGGER_M + bar_headroom * float(np.max(self._bar_heights_m()))
        x_hi = front + (3.0 + min(abs(p.headwind_ms), 15.0) * 0.25 if p.headwind_ms != 0 else 0.0)
        lo, hi = np.array([back, -1.1, 0.0]), np.array([x_hi, 1.1, max(top, 2.2)])
        corners = np.array(
            [
                [(lo, hi)[i][0], (lo, hi)[j][1], (lo, hi)[k][2]]
                for i in (0, 1)
                for j in (0, 1)
                for k in (0, 1)
            ]
        )
        theta = math.atan(p.grade_pct / 100.0)  # the course frame turns by −θ about y
        c, s = math.cos(theta), math.sin(theta)
        return np.stack(
            [
                c * corners[:, 0] - s * corners[:, 2],
                corners[:, 1],
                s * corners[:, 0] + c * corners[:, 2],
            ],
            axis=1,
        )

    def _bar_heights_m(self) -> np.ndarray:
        """(n_riders,) height of each slot's stacked bars (m): the positive parts only, as drawn (downhill the
        climbing part is negative and the stack stands taller than the total)."""
        power = self.state.power
        parts = [np.maximum(np.asarray(getattr(power, c)), 0.0) for c in COMPONENT_COLOURS]
        return np.sum(parts, axis=0)[: self.params.n_riders] * BAR_METRES_PER_WATT

    def label_anchors(self) -> np.ndarray:
        """(n_riders, 3) world points where each slot's label sits before it is lifted: just above its bar."""
        p, n = self.params, self.params.n_riders
        x = slot_offsets(n, p.gap_m)[:n]
        local = np.stack([x, np.zeros(n), 1.95 + self._bar_heights_m()], 1)
        return course_to_world(local, p.grade_pct)

    def _view_for(self, lens: Lens) -> View:
        """The view of the line for ``lens``, with room above it for the labels, which it lays out for that lens."""
        with self._lock:
            anchors = self.label_anchors()
            up_world = course_to_world(np.array([[0.0, 0.0, 1.0]]), self.params.grade_pct)[0]
            ndc = lens.usable_ndc(right_px=LABEL_PX[0], top_px=LABEL_PX[1])
            x0, x1 = (ndc[0] + 1.0) / 2.0 * lens.width_px, (ndc[1] + 1.0) / 2.0 * lens.width_px
            y_top, y_bottom = (
                (1.0 - ndc[3]) / 2.0 * lens.height_px,
                (1.0 - ndc[2]) / 2.0 * lens.height_px,
            )
            framed, view, lifts_m = self._framed_points, None, np.zeros(len(anchors))
            # Frame the line with the lifted label anchors, which lean with the road's tilt (a fresh review: up a
            # 20 % grade the last label started left of the window); the box of each label lies right of and
            # above its anchor, in the room the rectangle leaves. Framing the anchors shrinks the line, which may
            # stack the labels differently: repeat until the lifted anchors fit.
            for _ in range(MAX_RIDERS + 2):
                view = frame_points(
                    framed, VIEW_DIRECTION, fov_rad=lens.fov_rad, aspect=lens.aspect, ndc=ndc
                )
                lifts_px = label_lifts_px(project_px(anchors, view, lens))
                lifts_m = lift_to_metres(anchors, lifts_px, up_world, view, lens)
                lifted = anchors + lifts_m[:, None] * up_world
                px = project_px(lifted, view, lens)
                if (
                    px[:, 0].min(initial=x0) >= x0 - 0.5
                    and px[:, 0].max(initial=x1) <= x1 + 0.5
                    and px[:, 1].min(initial=y_top) >= y_top - 0.5
                    and px[:, 1].max(initial=y_bottom) <= y_bottom + 0.5
                ):
                    break
                framed = np.vstack([framed, lifted])
            assert view is not None
            self._label_lift_m = np.zeros(MAX_RIDERS)
            self._label_lift_m[: len(lifts_m)] = lifts_m
            self.redraw(readouts=False)
            return view

    def _update_framing(self) -> None:
        """Frame every browser again when the line changes length or tilt, or its bars outgrow the view.

        Bars that outgrow it are framed with :data:`BAR_HEADROOM`: dragging the speed up then moves the camera
        every few km/h, not at each step (each framing lays out the labels for every tab: ~60 ms a tab)."""
        key = self._framing_key()
        points = self.line_points()
        if key != self._framed_for:
            self._framed_for, self._framed_points = key, points
        elif points[:, 2].max() > self._framed_points[:, 2].max() + 0.05:
            self._framed_points = self.line_points(bar_headroom=BAR_HEADROOM)
        else:
            return
        self.framing.reframe()

    def _framing_key(self) -> tuple[object, ...]:
        p = self.params
        return (p.n_riders, p.gap_m, p.grade_pct, p.headwind_ms != 0.0)

    def read_params(self) -> PelotonParams:
        """The current GUI values, cleaned: anything non-finite, out of range or unknown keeps the last good value."""
        last = self.params
        position_label = self.read_choice(
            self.position, list(POSITION_FROM_LABEL), POSITIONS[last.position].label
        )
        model_label = self.read_choice(
            self.model,
            list(MODEL_FROM_LABEL),
            next(k for k, v in MODEL_FROM_LABEL.items() if v == last.model),
        )
        return PelotonParams(
            speed_kmh=self.read_number(self.speed, last.speed_kmh),
            position=POSITION_FROM_LABEL[position_label],
            cda_m2=self.read_number(self.cda, last.cda_m2),
            mass_kg=self.read_number(self.mass, last.mass_kg),
            crr=self.read_number(self.crr, last.crr),
            drivetrain_pct=self.read_number(self.drivetrain, last.drivetrain_pct),
            grade_pct=self.read_number(self.grade, last.grade_pct),
            altitude_m=self.read_number(self.altitude, last.altitude_m),
            headwind_ms=self.read_number(self.wind, last.headwind_ms),
            drafting=self.read_bool(self.drafting, last.drafting),
            n_riders=int(self.read_number(self.riders, last.n_riders, integer=True)),
            gap_m=self.read_number(self.gap, last.gap_m),
            model=MODEL_FROM_LABEL[model_label],
            target_power_w=self.read_number(self.target_power, last.target_power_w),
        )

    # ----------------------------------------------------------------------------------------- drawing
    def _chart_data(self) -> tuple[np.ndarray, ...]:
        p = self.params
        speeds_kmh, aero, rolling, climbing, total = _solo_curves(_solo_key(p))
        # A level line at the solo power now: it meets the total curve at the current speed. (A single marker needs
        # NaN elsewhere, and one NaN makes uPlot's auto range NaN, so the chart drew nothing at all.)
        now = np.full_like(speeds_kmh, float(self.state.solo.total))
        return speeds_kmh, aero, rolling, climbing, total, now

    def _slot_of_rider(self) -> tuple[np.ndarray, np.ndarray]:
        """(x, y) of each rider now: the plain line, or mid-rotation when the lead rotates."""
        n, p = self.params.n_riders, self.params
        slots = slot_offsets(n, p.gap_m)
        x, y = slots.copy(), np.zeros(MAX_RIDERS)
        if not (self._rotating and n > 1):
            return x, y
        turn = self._turn_s
        k, phase = divmod(self._rotation_time_s / turn, 1.0)
        order = (np.arange(n) - int(k)) % n  # slot each rider holds this turn
        swap = 0.25  # last quarter of a turn: leader swings off and drifts back, others move up
        u = max(0.0, (phase - (1.0 - swap)) / swap)
        ease = 0.5 - 0.5 * math.cos(math.pi * u)
        for rider in range(n):
            slot = int(order[rider])
            if slot == 0:
                x[rider] = slots[0] + ease * (slots[n - 1] - slots[0])
                y[rider] = 0.9 * math.sin(math.pi * ease)
            else:
                x[rider] = slots[slot] + ease * (slots[slot - 1] - slots[slot])
        return x, y

    def current_slots(self) -> np.ndarray:
        """(n_riders,) slot index each rider holds (0 = leader); the identity unless the lead rotates."""
        n = self.params.n_riders
        if not (self._rotating and n > 1):
            return np.arange(n)
        k = int(self._rotation_time_s // self._turn_s)
        return (np.arange(n) - k) % n

    def redraw(self, *, readouts: bool = True) -> None:
        """Push the current state to the riders, bars and labels and, with ``readouts``, to the GUI outputs.

        One atomic update; the animation redraws without readouts, which do not change as riders move.
        """
        p, state = self.params, self.state
        n = p.n_riders
        slots = self.current_slots()
        total = np.asarray(state.power.total)
        x, y = self._slot_of_rider()
        positions = np.stack([x, y, np.zeros(MAX_RIDERS)], axis=1)
        visible = (np.arange(MAX_RIDERS) < n).astype(np.float64)
        scales = np.repeat(visible[:, None], 3, axis=1)

        with self.server.atomic():
            theta = math.atan(p.grade_pct / 100.0)
            set_if_changed(
                self.course, "wxyz", (math.cos(-theta / 2), 0.0, math.sin(-theta / 2), 0.0)
            )
            if p.position != self._drawn_position:
                for part, mesh in rider_meshes(p.position).items():
                    self.riders_nodes[part].vertices = mesh.vertices.astype(np.float32)
                    self.riders_nodes[part].faces = mesh.faces.astype(np.uint32)
                self._drawn_position = p.position
            for node in self.riders_nodes.values():
                set_if_changed(node, "batched_positions", positions.astype(np.float32))
                set_if_changed(node, "batched_scales", scales.astype(np.float32))

            base = np.zeros(MAX_RIDERS)
            for component in ("aero", "rolling", "climbing"):
                watts = np.zeros(MAX_RIDERS)
                watts[:n] = np.maximum(np.asarray(getattr(state.power, component))[slots], 0.0)
                height = watts * BAR_METRES_PER_WATT
                bar_pos = positions + np.stack(
                    [np.zeros(MAX_RIDERS), np.zeros(MAX_RIDERS), 1.75 + base], axis=1
                )
                self.bars[component].batched_positions = bar_pos.astype(np.float32)
                self.bars[component].batched_scales = np.stack(
                    [0.35 * visible, 0.35 * visible, np.maximum(height, 1e-4) * visible], axis=1
                ).astype(np.float32)
                base = base + height
            for i, label in enumerate(self.labels):
                # Only write what changed: every property write is a message to every browser.
                if label.visible != (i < n):
                    label.visible = i < n
                if i < n:
                    watts = float(total[slots[i]])
                    solo = float(state.solo.total)
                    share = (
                        f"{100.0 * watts / solo:.0f} % of solo" if solo > 0 else "solo needs 0 W"
                    )
                    text = f"{watts:.0f} W · {share}"
                    if label.text != text:
                        label.text = text
                    # Neighbours' labels alternate in height so close riders' labels never overlap.
                    # Lifted by the layout for the framed camera, so no two labels overlap.
                    set_if_changed(
                        label,
                        "position",
                        (x[i], y[i], 1.95 + base[i] + self._label_lift_m[slots[i]]),
                    )

            rotation = self._rotation_markdown()
            if self.rotation.content != rotation:
                self.rotation.content = rotation
            if readouts:
                self._draw_wind()
                self.density.content = self._density_markdown()
                self.table.content = self._table_markdown()
                self.chart.data = self._chart_data()
                self.speed_out.content = self._speed_markdown()
        self.server.flush()

    def _draw_wind(self) -> None:
        w = self.params.headwind_ms
        length = min(abs(w), 15.0) * 0.25
        if length < 1e-6:
            self.wind_arrow.visible = False
            return
        self.wind_arrow.visible = True
        tip_x = 3.0 if w > 0 else 3.0 + length
        tail_x = tip_x + length if w > 0 else tip_x - length
        direction = -1.0 if w > 0 else 1.0
        tip = np.array([tip_x, 0.0, 1.2])
        head = [tip - [direction * 0.3, 0.0, -0.2], tip - [direction * 0.3, 0.0, 0.2]]
        set_if_changed(
            self.wind_arrow,
            "points",
            np.array([[[tail_x, 0.0, 1.2], tip], [head[0], tip], [head[1], tip]]),
        )

    def _density_markdown(self) -> str:
        p, solo = self.params, self.state.solo
        rho = float(cycling.air_density(p.altitude_m))
        wheel = float(solo.aero + solo.rolling + solo.climbing)
        aero_share = 100.0 * float(solo.aero) / wheel if wheel > 0 else float("nan")
        thinner = 100 * (1 - rho / cycling.RHO_SEA_LEVEL)
        where = "sea level" if abs(thinner) < 0.05 else f"{thinner:.1f} % thinner than at sea level"
        return (
            f"Air density **{rho:.3f} kg/m³** ({where})  \n"
            f"Solo rider: **{float(solo.total):.0f} W**, aero share of wheel power **{aero_share:.1f} %**"
        )

    def _table_markdown(self) -> str:
        state = self.state
        # Narrow columns run together in the panel ("RollClimb"), so the three parts share one cell with slashes.
        rows = [
            "| Rider | CdA (m²) | Aero / rolling / climbing (W) | Total (W) | Saving |",
            "|---|---|---|---|---|",
        ]
        for i in range(self.params.n_riders):
            rows.append(
                f"| {i + 1} | {state.cda_m2[i]:.3f} | {state.power.aero[i]:.0f} / {state.power.rolling[i]:.0f} / "
                f"{state.power.climbing[i]:.0f} | **{state.power.total[i]:.0f}** | {100 * state.saving[i]:.1f} % |"
            )
        return "\n".join(rows)

    def _rotation_markdown(self) -> str:
        n = self.params.n_riders
        if n < 2:
            return ""
        mean = float(np.mean(self.state.power.total))
        lead = float(self.state.power.total[0])
        if lead > 0:
            text = (
                f"Rotating evenly, each rider averages **{mean:.0f} W** against the leader's {lead:.0f} W "
                f"({100 * (1 - mean / lead):.0f} % less): the reason teams rotate."
            )
        else:
            text = f"Here the leader needs {lead:.0f} W: gravity does the work and nobody needs shelter."
        if self._rotating and self._ridden_s > 0:
            averages = self._energy_j[:n] / self._ridden_s
            text += "  \nTime-averaged so far: " + ", ".join(
                f"R{i + 1} {a:.0f} W" for i, a in enumerate(averages)
            )
        return text

    def _speed_markdown(self) -> str:
        p = self.params
        v = _solo_speed(_solo_key(p), p.target_power_w)
        text = f"Riding alone, {p.target_power_w:.0f} W ({p.target_power_w / p.mass_kg:.2f} W/kg of system mass) holds **{3.6 * v:.1f} km/h** here"
        if v > 0.1:
            minutes, seconds = divmod(round(40_000.0 / v), 60)
            hours, minutes = divmod(minutes, 60)
            text += f": a 40 km time trial in {hours:d}:{minutes:02d}:{seconds:02d}"
        return text + "."

    # ----------------------------------------------------------------------------------------- animation
    def _animate(self, dt: float) -> bool:
        """One frame of the rotating lead; False (the loop sleeps) when the lead does not rotate."""
        if not (self._rotating and self.params.n_riders > 1):
            return False
        dt = min(dt, 0.2)
        slots = self.current_slots()
        self._energy_j[: self.params.n_riders] += np.asarray(self.state.power.total)[slots] * dt
        self._ridden_s += dt
        self._rotation_time_s += dt
        self.redraw(readouts=False)
        return True

    def rider_average_power(self) -> np.ndarray:
        """(n_riders,) time-averaged power of each rider since the rotation started (W); zeros before."""
        n = self.params.n_riders
        if self._ridden_s <= 0:
            return np.zeros(n)
        return self._energy_j[:n] / self._ridden_s


# --------------------------------------------------------------------------------------------- course mode
# Issue 13: ride a real route (a GPX file or the bundled sample) in real air with the full Martin model. The course
# is drawn scaled into the box the camera already frames, riders ride it, and the chart shows the profile.
CourseAirLabel = Literal[
    "Seed (exponential)", "Weather (temperature, pressure or altitude, humidity)"
]
AIR_FROM_LABEL: dict[str, course_kernel.AirKind] = {
    "Seed (exponential)": "seed",
    "Weather (temperature, pressure or altitude, humidity)": "weather",
}
PRESSURE_SOURCES = ("Standard atmosphere at the route's altitude", "Barometer at the start (hPa)")
POWER_MODEL_FROM_LABEL: dict[str, course_kernel.Model] = {
    "Martin et al. 1998 (full)": "martin",
    "Seed (aero, rolling, climbing)": "seed",
}
COURSE_POWER_RANGE_W = (20.0, 2000.0)
"""What the Course power input takes (W); 'Find the power for this time' says when a target needs more or less."""
MODEL_LABEL = {model: label for label, model in POWER_MODEL_FROM_LABEL.items()}
SAMPLE_LABEL = "Alpe d'Huez (sample, from the published profile)"
logger = logging.getLogger(__name__)
COURSE_BOX_M = 6.0
"""The drawn course fits a square of this size (scene metres) where the line's camera looks."""
COURSE_CENTRE = np.array([-3.2, 0.0])
TERRAIN_HALF_WIDTH_M = 0.15
"""Half width of the drawn terrain strip (scene m)."""
COURSE_MARKER_SCALE = 0.25
"""Riders on the course are drawn at this fraction of life size (a marker, not to the map's scale)."""
MAX_DRAWN_POINTS = 2000
MAX_CHART_POINTS = 1000


@dataclasses.dataclass(frozen=True)
class CourseParams:
    """Course-mode inputs (the rider, the line and drafting come from :class:`PelotonParams`)."""

    power_w: float = 250.0
    """Constant pedal power of each rider (W)."""
    target_min: float = 60.0
    """Finish time that 'Find the power for this time' aims at (min)."""
    model: course_kernel.Model = "martin"
    """Power model: Martin et al. 1998's full terms or the seed's three."""
    air: course_kernel.AirKind = "seed"
    """Air along the route: the seed's exponential atmosphere or a weather reading."""
    temperature_c: float = 15.0
    """Air temperature at the start (°C), weather air."""
    pressure_from_barometer: bool = False
    """Weather air: the barometer's pressure, or the standard atmosphere's at the start's altitude."""
    pressure_hpa: float = 1013.25
    """Station pressure at the start (hPa), when read from a barometer."""
    humidity_pct: float = 50.0
    """Relative humidity (%), weather air."""
    wind_ms: float = 0.0
    """Wind speed (m/s)."""
    wind_from_deg: float = 0.0
    """Where the wind blows from, clockwise from north (°)."""
    max_speed_kmh: float = 72.0
    """Safe descending speed (km/h): riders brake to hold it."""
    pacing: bool = False
    """Vary power with the grade (Swain 1997) at the same average."""
    pacing_gain_pct: float = 15.0
    """How much more power on steep climbs, and less on descents (%)."""
    exaggeration: float = 2.0
    """Vertical exaggeration of the drawn terrain."""
    playback: float = 60.0
    """Playback speed (× real time)."""


@dataclasses.dataclass(frozen=True)
class CourseState:
    """What the course mode shows for one route and parameter set."""

    route: course_kernel.Course
    ride: course_kernel.Ride
    """The ride drawn and animated: paced when pacing is on, else constant."""
    constant: course_kernel.Ride
    solo: course_kernel.Ride
    """One rider alone at the same power (no shelter)."""
    pacing: course_kernel.Pacing | None
    group_cda_m2: float
    """CdA the group rides at when riders share the front equally (m²)."""
    density_seed: float
    """The seed's density at the start (kg/m³)."""
    density_weather: float
    """The weather reading's density at the start (kg/m³)."""


def course_air(route: course_kernel.Course, p: CourseParams) -> course_kernel.Air:
    """The :class:`kernels.course.Air` for the inputs; the reading is taken at the route's start."""
    start = float(route.elevation_m[0])
    pressure = (
        p.pressure_hpa
        if p.pressure_from_barometer
        else float(cycling.isa_pressure_hpa(np.clip(start, -1000.0, 20_000.0)))
    )
    return course_kernel.Air(
        p.air, p.temperature_c, pressure, p.humidity_pct / 100.0, altitude_m=start
    )


def group_cda(line: PelotonParams) -> float:
    """CdA of a rider in a line that rotates evenly: the mean over the positions (the riders share the work)."""
    if not line.drafting or line.n_riders < 2:
        return line.cda_m2
    reduction = cycling.drag_reduction(line.n_riders, line.gap_m, line.model)
    return float(line.cda_m2 * (1.0 - np.mean(reduction)))


def compute_course(
    route: course_kernel.Course, p: CourseParams, line: PelotonParams
) -> CourseState:
    """Ride ``route`` for one parameter set (no viser: testable on its own)."""
    air = course_air(route, p)
    weather = dataclasses.replace(air, kind="weather")
    start = float(route.elevation_m[0])

    def rider(cda: float) -> course_kernel.Rider:
        return course_kernel.Rider(
            cda_m2=cda,
            mass_kg=line.mass_kg,
            crr=line.crr,
            drivetrain_efficiency=line.drivetrain_pct / 100.0,
            model=p.model,
        )

    cda = group_cda(line)
    wind, wind_from, cap = p.wind_ms, p.wind_from_deg, p.max_speed_kmh / 3.6

    def ride_at(cda_m2: float) -> course_kernel.Ride:
        return course_kernel.ride(route, p.power_w, rider(cda_m2), wind, wind_from, air, cap)

    pacing = None
    if p.pacing:
        pacing = course_kernel.paced_ride(
            route, p.power_w, rider(cda), p.pacing_gain_pct / 100.0, wind, wind_from, air, cap
        )
        constant, shown = pacing.constant, pacing.paced
    else:
        constant = shown = ride_at(cda)
    solo = constant if cda == line.cda_m2 else ride_at(line.cda_m2)
    return CourseState(
        route=route,
        ride=shown,
        constant=constant,
        solo=solo,
        pacing=pacing,
        group_cda_m2=cda,
        density_seed=float(cycling.air_density(start)),
        density_weather=float(weather.density(start)),
    )


def format_duration(seconds: float) -> str:
    """h:mm:ss (or m:ss under an hour)."""
    total = round(seconds)
    hours, rest = divmod(total, 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours:d}:{minutes:02d}:{secs:02d}" if hours else f"{minutes:d}:{secs:02d}"


def split_every_m(total_m: float) -> float:
    """Split length for the table: 1 km up to 30 km, 5 km up to 150 km, else 10 km."""
    return 1000.0 if total_m <= 30_000.0 else 5000.0 if total_m <= 150_000.0 else 10_000.0


def drawn_indices(n_points: int, limit: int) -> np.ndarray:
    """Indices of at most ``limit`` points spread along the route, first and last included."""
    return np.unique(np.linspace(0, n_points - 1, min(n_points, limit)).round().astype(np.int64))


@dataclasses.dataclass(frozen=True)
class CourseDrawing:
    """The route mapped into the scene: map (east, north) scaled into the framed box, elevation exaggerated."""

    scale: float
    """Scene metres per map metre."""
    offset: np.ndarray
    """(2,) map point drawn at COURSE_CENTRE (m)."""
    base_m: float
    """Elevation drawn at z = 0 (m): the route's lowest point."""

    @staticmethod
    def of(route: course_kernel.Course) -> CourseDrawing:
        east, north = route.east_m, route.north_m
        extent = max(float(np.ptp(east)), float(np.ptp(north)), 1.0)
        centre = np.array([0.5 * (east.min() + east.max()), 0.5 * (north.min() + north.max())])
        return CourseDrawing(
            scale=COURSE_BOX_M / extent, offset=centre, base_m=float(route.elevation_m.min())
        )

    def points(
        self, route: course_kernel.Course, index: np.ndarray, exaggeration: float
    ) -> np.ndarray:
        """(k, 3) scene positions of route points ``index``."""
        xy = (
            np.stack([route.east_m[index], route.north_m[index]], axis=1) - self.offset
        ) * self.scale
        z = (route.elevation_m[index] - self.base_m) * self.scale * exaggeration + 0.05
        return np.concatenate([xy + COURSE_CENTRE, z[:, None]], axis=1)

    def at_distance(
        self, route: course_kernel.Course, distance_m: np.ndarray, exaggeration: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """(k, 3) scene positions and (k,) yaw angles (rad, from +x) at distances along the route."""
        d = np.clip(distance_m, 0.0, route.total_distance_m)
        east = np.interp(d, route.distance_m, route.east_m)
        north = np.interp(d, route.distance_m, route.north_m)
        z = np.interp(d, route.distance_m, route.elevation_m)
        segment = np.clip(
            np.searchsorted(route.distance_m, d, side="right") - 1, 0, route.n_points - 2
        )
        yaw = math.pi / 2 - route.heading_rad[segment]
        xy = (np.stack([east, north], axis=1) - self.offset) * self.scale + COURSE_CENTRE
        zz = (z - self.base_m) * self.scale * exaggeration + 0.05
        return np.concatenate([xy, zz[:, None]], axis=1), yaw


def terrain_strip(points: np.ndarray, half_width: float) -> tuple[np.ndarray, np.ndarray]:
    """A road-side strip along the route and a curtain under it down to z = 0: (4k, 3) vertices and faces.

    The strip is the terrain the road crosses; the curtain shows the height above the valley floor.
    """
    k = points.shape[0]
    direction = np.gradient(points[:, :2], axis=0)
    norm = np.linalg.norm(direction, axis=1, keepdims=True)
    direction = direction / np.where(norm > 1e-12, norm, 1.0)
    side = np.stack([-direction[:, 1], direction[:, 0]], axis=1) * half_width
    top = points[:, 2:3] - 0.03
    left = np.concatenate([points[:, :2] + side, top], axis=1)
    right = np.concatenate([points[:, :2] - side, top], axis=1)
    centre = np.concatenate([points[:, :2], top - 0.01], axis=1)
    foot = centre * [1.0, 1.0, 0.0]
    vertices = np.concatenate([left, right, centre, foot])
    a = np.arange(k - 1)
    b = a + 1
    L, R, C, F = 0, k, 2 * k, 3 * k  # block offsets: left edge, right edge, centre, its foot
    faces = np.concatenate([
        np.stack([L + a, R + a, R + b], axis=1), np.stack([L + a, R + b, L + b], axis=1),  # strip
        np.stack([F + a, C + a, C + b], axis=1), np.stack([F + a, C + b, F + b], axis=1),  # curtain
    ])  # fmt: skip
    return vertices.astype(np.float32), faces.astype(np.uint32)


def ground_under(points: np.ndarray, margin: float = 0.6) -> tuple[np.ndarray, np.ndarray]:
    """A thin slab under the route's bounding rectangle plus ``margin`` (scene m): vertices and faces."""
    lo, hi = points[:, :2].min(axis=0) - margin, points[:, :2].max(axis=0) + margin
    slab = trimesh.creation.box(extents=(*(hi - lo), 0.02))
    slab.apply_translation((*((lo + hi) / 2), -0.011))
    return slab.vertices.astype(np.float32), slab.faces.astype(np.uint32)


def grade_colours(grade: np.ndarray) -> np.ndarray:
    """(k, 3) uint8: descents blue, flat white-green, climbs yellow to red at 12 %."""
    g = np.clip(grade / 0.12, -1.0, 1.0)
    up = np.clip(g, 0.0, 1.0)[:, None]
    down = np.clip(-g, 0.0, 1.0)[:, None]
    flat = np.array([90.0, 200.0, 90.0])
    colour = (
        flat
        + up * (np.array([230.0, 40.0, 30.0]) - flat)
        + down * (np.array([40.0, 110.0, 230.0]) - flat)
    )
    return colour.astype(np.uint8)


class CourseMode:
    """The course mode of :class:`PelotonScene`: its GUI folder, its nodes under ``/peloton/course_mode``.

    Every input is cleaned through the scene's helpers; a bad file leaves the last good course in place with
    a message saying why.
    """

    def __init__(self, scene: PelotonScene) -> None:
        self.scene = scene
        self.server = scene.server
        self.params = CourseParams()
        self.route = course_kernel.load_gpx(course_kernel.SAMPLE_ROUTE)
        self.route_label = SAMPLE_LABEL
        self.state: CourseState | None = None
        """Computed when the mode is first shown (the compiled ride loop loads then)."""
        self.enabled = False
        self.playing = False
        self.play_time_s = 0.0
        self.message = ""
        self._since_readout = 0.0
        self._drawn_position: Position | None = None
        self._drawing = CourseDrawing.of(self.route)
        self._upload_lock = threading.Lock()
        self._upload_seq = 0
        """Number of the newest upload: parses run in parallel on viser's pool, and only the newest installs."""
        self._build_gui()
        self._build_world()
        scene.start_loop(self._animate, 1.0 / 30.0)

    # ----------------------------------------------------------------------------------------- GUI
    def _build_gui(self) -> None:
        gui, p = self.server.gui, self.params
        with self.scene.gui_root, gui.add_folder("Course mode (GPX route)"):
            self.enable = gui.add_checkbox("Ride a course", initial_value=False)
            self.route_info = gui.add_markdown(self._route_markdown())
            self.sample = gui.add_button("Load the sample route")
            self.upload = gui.add_upload_button("Upload GPX", mime_type=".gpx,application/gpx+xml")
            self.play = gui.add_button("Play")
            self.pause = gui.add_button("Pause")
            self.scrub = gui.add_slider(
                "Position (km)", min=0.0, max=self._total_km(), step=0.01, initial_value=0.0
            )
            self.now = gui.add_markdown("")
            self.readout = gui.add_markdown("")
            self.chart = FittedChart(
                gui,
                data=self._chart_data(),
                series=(
                    viser.uplot.Series(label="Distance (km)"),
                    viser.uplot.Series(
                        label="Elevation (m)", stroke="rgb(120,90,60)", width=2, scale="m"
                    ),
                    viser.uplot.Series(
                        label="Speed (km/h)", stroke="rgb(30,110,220)", width=1.5, scale="kmh"
                    ),
                    viser.uplot.Series(
                        label="Power (W)", stroke="rgb(220,40,40)", width=1.5, scale="W"
                    ),
                ),
                scales={
                    "x": viser.uplot.Scale(time=False, auto=True),
                    "m": viser.uplot.Scale(auto=True),
                    "kmh": viser.uplot.Scale(auto=True),
                    "W": viser.uplot.Scale(auto=True),  # no axis of its own: the legend gives watts
                },
                axes=(
                    viser.uplot.Axis(scale="x", label="km"),
                    viser.uplot.Axis(scale="m", label="m", side=3),
                    viser.uplot.Axis(
                        scale="kmh", label="km/h", side=1, grid=viser.uplot.Axis_Grid(show=False)
                    ),
                ),
                legend=viser.uplot.Legend(show=True),
                title="Elevation, speed and power along the course",
                aspect=1.4,
                visible=False,  # until the first ride: a profile over flat zeros reads as a rider not pedalling
            )
            with gui.add_folder("Power, model and air"):
                self.power = gui.add_number(
                    "Course power (W)",
                    min=COURSE_POWER_RANGE_W[0],
                    max=COURSE_POWER_RANGE_W[1],
                    step=5.0,
                    initial_value=p.power_w,
                )
                self.target = gui.add_number(
                    "Target time (min)", min=1.0, max=6000.0, step=1.0, initial_value=p.target_min
                )
                self.solve = gui.add_button("Find the power for this time")
                self.power_model = gui.add_dropdown(
                    "Power model",
                    options=list(POWER_MODEL_FROM_LABEL),
                    initial_value="Martin et al. 1998 (full)",
                )
                self.air = gui.add_dropdown(
                    "Air", options=list(AIR_FROM_LABEL), initial_value="Seed (exponential)"
                )
                self.temperature = gui.add_slider(
                    "Temperature (°C)", min=-20.0, max=45.0, step=0.5, initial_value=p.temperature_c
                )
                self.pressure_source = gui.add_dropdown(
                    "Pressure from",
                    options=list(PRESSURE_SOURCES),
                    initial_value=PRESSURE_SOURCES[0],
                )
                self.pressure = gui.add_number(
                    "Pressure at the start (hPa)",
                    min=500.0,
                    max=1100.0,
                    step=0.5,
                    initial_value=p.pressure_hpa,
                )
                self.humidity = gui.add_slider(
                    "Humidity (%)", min=0.0, max=100.0, step=1.0, initial_value=p.humidity_pct
                )
            with gui.add_folder("Wind, descents, pacing, view", expand_by_default=False):
                self.wind = gui.add_slider(
                    "Wind (m/s)", min=0.0, max=20.0, step=0.5, initial_value=p.wind_ms
                )
                self.wind_from = gui.add_slider(
                    "Wind from (° from north)",
                    min=0.0,
                    max=359.0,
                    step=1.0,
                    initial_value=p.wind_from_deg,
                )
                self.max_speed = gui.add_slider(
                    "Safe descending speed (km/h)",
                    min=20.0,
                    max=110.0,
                    step=1.0,
                    initial_value=p.max_speed_kmh,
                )
                self.pacing = gui.add_checkbox("Pace by grade", initial_value=p.pacing)
                self.pacing_gain = gui.add_slider(
                    "Pacing gain (%)", min=0.0, max=50.0, step=1.0, initial_value=p.pacing_gain_pct
                )
                self.exaggeration = gui.add_slider(
                    "Elevation exaggeration (×)",
                    min=1.0,
                    max=10.0,
                    step=0.5,
                    initial_value=p.exaggeration,
                )
                self.playback = gui.add_slider(
                    "Playback speed (×)", min=1.0, max=600.0, step=1.0, initial_value=p.playback
                )
            with gui.add_folder("Splits", expand_by_default=False):
                self.splits = gui.add_markdown("")
        cb = self.scene.callback
        self.enable.on_update(cb(self._on_enable))
        self.sample.on_click(cb(self._on_sample))
        self.upload.on_upload(self._on_upload)  # parses off the lock, then installs through cb
        self.solve.on_click(cb(self._on_solve))
        self.play.on_click(cb(self._on_play))
        self.pause.on_click(cb(self._on_pause))
        self.scrub.on_update(cb(self._on_scrub))
        for handle in (
            self.power, self.power_model, self.air, self.temperature, self.pressure_source, self.pressure,
            self.humidity, self.wind, self.wind_from, self.max_speed, self.pacing, self.pacing_gain,
        ):  # fmt: skip
            handle.on_update(cb(self._on_input))
        self.exaggeration.on_update(cb(self._on_view))
        self.playback.on_update(cb(self._on_view))
        self.target.on_update(cb(self._on_view))
        line = self.scene
        for handle in (
            line.cda, line.mass, line.crr, line.drivetrain, line.drafting, line.riders, line.gap, line.model,
            line.position, line.crr_preset,
        ):  # fmt: skip
            handle.on_update(cb(self._on_input))  # the paceline options apply on the course

    # ----------------------------------------------------------------------------------------- world
    def _build_world(self) -> None:
        scene = self.server.scene
        self.frame = scene.add_frame(
            f"{self.scene.root.name}/course_mode", show_axes=False, visible=False
        )
        index = drawn_indices(self.route.n_points, MAX_DRAWN_POINTS)
        points = self._drawing.points(self.route, index, self.params.exaggeration)
        vertices, faces = terrain_strip(points, TERRAIN_HALF_WIDTH_M)
        ground_vertices, ground_faces = ground_under(points)
        self.ground = scene.add_mesh_simple(
            f"{self.frame.name}/ground", ground_vertices, ground_faces, color=(205, 210, 195)
        )
        self.terrain = scene.add_mesh_simple(
            f"{self.frame.name}/terrain",
            vertices,
            faces,
            color=(150, 175, 110),
            side="double",
        )
        segments, colours = self._route_segments(index, points)
        self.route_line = scene.add_line_segments(
            f"{self.frame.name}/route", segments, colors=colours, thickness=0.08
        )
        identity = np.tile([1.0, 0.0, 0.0, 0.0], (MAX_RIDERS, 1))
        colours_by_part = {
            "bike": np.full((MAX_RIDERS, 3), 45, np.uint8),
            "body": JERSEYS,
            "head": np.full((MAX_RIDERS, 3), 235, np.uint8),
        }
        self.course_riders: dict[str, viser.BatchedMeshHandle] = {}
        for part, mesh in rider_meshes(self.scene.params.position).items():
            self.course_riders[part] = scene.add_batched_meshes_simple(
                f"{self.frame.name}/riders_{part}",
                vertices=mesh.vertices.astype(np.float32),
                faces=mesh.faces.astype(np.uint32),
                batched_wxyzs=identity,
                batched_positions=np.zeros((MAX_RIDERS, 3)),
                batched_scales=np.zeros((MAX_RIDERS, 3)),
                batched_colors=colours_by_part[part],
                lod="off",
            )
        self._drawn_position = self.scene.params.position
        self.leader_marker = scene.add_icosphere(
            f"{self.frame.name}/leader_marker",
            radius=0.12,
            color=(255, 60, 60),
            position=(0.0, 0.0, 1.0),
        )
        self.start_label = scene.add_label(
            f"{self.frame.name}/start", text="Start", position=tuple(points[0])
        )
        self.finish_label = scene.add_label(
            f"{self.frame.name}/finish", text="Finish", position=tuple(points[-1])
        )

    def _route_segments(
        self, index: np.ndarray, points: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        segments = np.stack([points[:-1], points[1:]], axis=1) + [0.0, 0.0, 0.02]
        rise = np.diff(self.route.elevation_m[index])
        run = np.maximum(np.diff(self.route.distance_m[index]), 1e-9)
        colours = grade_colours(rise / run)
        return segments.astype(np.float32), np.repeat(colours[:, None, :], 2, axis=1)

    # ----------------------------------------------------------------------------------------- inputs
    def read_params(self) -> CourseParams:
        """The course inputs, cleaned: anything non-finite, out of range or unknown keeps the last good value."""
        s, last = self.scene, self.params
        model_label = s.read_choice(
            self.power_model,
            list(POWER_MODEL_FROM_LABEL),
            next(k for k, v in POWER_MODEL_FROM_LABEL.items() if v == last.model),
        )
        air_label = s.read_choice(
            self.air,
            list(AIR_FROM_LABEL),
            next(k for k, v in AIR_FROM_LABEL.items() if v == last.air),
        )
        source = s.read_choice(
            self.pressure_source,
            list(PRESSURE_SOURCES),
            PRESSURE_SOURCES[1 if last.pressure_from_barometer else 0],
        )
        return CourseParams(
            power_w=s.read_number(self.power, last.power_w),
            target_min=s.read_number(self.target, last.target_min),
            model=POWER_MODEL_FROM_LABEL[model_label],
            air=AIR_FROM_LABEL[air_label],
            temperature_c=s.read_number(self.temperature, last.temperature_c),
            pressure_from_barometer=source == PRESSURE_SOURCES[1],
            pressure_hpa=s.read_number(self.pressure, last.pressure_hpa),
            humidity_pct=s.read_number(self.humidity, last.humidity_pct),
            wind_ms=s.read_number(self.wind, last.wind_ms),
            wind_from_deg=s.read_number(self.wind_from, last.wind_from_deg),
            max_speed_kmh=s.read_number(self.max_speed, last.max_speed_kmh),
            pacing=s.read_bool(self.pacing, last.pacing),
            pacing_gain_pct=s.read_number(self.pacing_gain, last.pacing_gain_pct),
            exaggeration=s.read_number(self.exaggeration, last.exaggeration),
            playback=s.read_number(self.playback, last.playback),
        )

    def _on_enable(self) -> None:
        self.enabled = self.scene.read_bool(self.enable, self.enabled)
        if self.enabled and self.state is None:
            self.recompute()
        self.redraw()
        self.scene.wake_loops()

    def _on_input(self) -> None:
        if (
            not self.enabled
        ):  # the line's sliders move often: ride the course only while it is shown
            self.state = None
            return
        self.recompute()
        self.redraw()

    def _on_view(self) -> None:
        self.params = self.read_params()
        self.redraw()

    def recompute(self) -> None:
        """Ride the current route with the current inputs; on failure keep the last good state and say why."""
        params = self.read_params()
        line = self.scene.read_params()
        try:
            state = compute_course(self.route, params, line)
        except ValueError as error:
            self.message = f"Could not ride this course: {error}"
            return
        self.params, self.state = params, state
        self.message = ""
        self.play_time_s = min(self.play_time_s, state.ride.time_s)
        if self.enabled and self.playing:  # a ride that had none to play now has one
            self.scene.wake_loops()

    def _on_sample(self) -> None:
        self.load(course_kernel.SAMPLE_ROUTE.read_bytes(), SAMPLE_LABEL)

    def _on_upload(self, _event: object = None) -> None:
        """An upload arrived (viser's thread pool). Parse it off the scene's lock, since gpxpy needs seconds for a
        large file, then install it (or the reason it failed) as a guarded callback. Nothing escapes."""
        # The number and the file are taken together: a higher number is a newer file.
        with self._upload_lock:
            self._upload_seq += 1
            seq = self._upload_seq
            uploaded = self.upload.value
        try:
            name = str(getattr(uploaded, "name", "") or "upload")[:80]
            content = getattr(uploaded, "content", b"")
            route, error = None, None
            if not isinstance(content, bytes):
                error = "the upload carried no file"
            else:
                try:
                    route = course_kernel.load_gpx(content)
                except ValueError as failure:
                    error = str(failure)
        except Exception:  # a file must never take the scene down; say so and keep the course
            logger.exception("peloton: reading an uploaded GPX failed")
            name, route, error = "upload", None, "the file could not be read"

        def install() -> None:
            if seq != self._upload_seq:  # a newer upload arrived while this one parsed: it wins
                return
            self._install(route, error, name)

        self.scene.callback(install)(None)

    def load(self, data: bytes, label: str) -> bool:
        """Load a GPX file's bytes as the course; on a bad file keep the last good course and show why."""
        try:
            route, error = course_kernel.load_gpx(data), None
        except ValueError as failure:
            route, error = None, str(failure)
        return self._install(route, error, label)

    def _install(self, route: course_kernel.Course | None, error: str | None, label: str) -> bool:
        state = None
        if route is not None:
            try:
                state = compute_course(route, self.read_params(), self.scene.read_params())
            except ValueError as failure:
                error = str(failure)
        if route is None or state is None:
            reason = str(error).removeprefix("the file: ")  # the file is named already
            self.message = (
                f"**{_escape(label)}** was not loaded: {_escape(reason)}. "
                f"Still showing **{_escape(self.route.name)}**."
            )
            self.redraw()
            return False
        self.route, self.route_label, self.state = route, label, state
        self.params = self.read_params()
        self.message = ""
        self.play_time_s = 0.0
        self.playing = False
        self._drawing = CourseDrawing.of(route)
        self.scrub.max = self._total_km()
        # The gate clamps a browser's scrub to the new course's length, not the first one's.
        record_spec(self.scrub)
        self.scene.write_back(self.scrub, 0.0)  # the riders are back at the start
        self.redraw(geometry=True)
        return True

    def _on_solve(self) -> None:
        params = self.read_params()
        line = self.scene.read_params()
        air = course_air(self.route, params)
        rider = course_kernel.Rider(
            cda_m2=group_cda(line), mass_kg=line.mass_kg, crr=line.crr,
            drivetrain_efficiency=line.drivetrain_pct / 100.0, model=params.model,
        )  # fmt: skip
        target_s, cap = params.target_min * 60.0, params.max_speed_kmh / 3.6
        low, high = COURSE_POWER_RANGE_W

        def finish_at(power_w: float) -> float:
            try:
                return course_kernel.ride(
                    self.route, power_w, rider, params.wind_ms, params.wind_from_deg, air, cap
                ).time_s
            except ValueError:  # too little power to cross a wall: never finishes
                return math.inf

        fastest, slowest = finish_at(high), finish_at(low)
        wanted = f"{params.target_min:g} min"
        if target_s < fastest:
            power = high
            note = (
                f"A {wanted} finish needs more than {high:.0f} W, the most this input takes: set to "
                f"{high:.0f} W, which finishes in {format_duration(fastest)}."
            )
        elif target_s > slowest:
            power = low
            note = (
                f"A {wanted} finish needs less than {low:.0f} W, the least this input takes: set to "
                f"{low:.0f} W, which finishes in {format_duration(slowest)}."
            )
        else:
            try:
                power = course_kernel.power_for_time(
                    self.route, target_s, rider, params.wind_ms, params.wind_from_deg, air,
                    max_speed_ms=cap, tolerance_s=0.05,
                )  # fmt: skip
            except ValueError as error:
                self.message = f"Could not find the power for {wanted}: {_escape(str(error))}"
                self.redraw()
                return
            note = ""
        self.scene.write_back(self.power, float(np.clip(round(power, 1), low, high)))
        self._on_input()
        if note and not self.message:
            self.message = note
            self.redraw()

    def _on_play(self) -> None:
        if self.state is None:
            return
        if self.play_time_s >= self.state.ride.time_s:
            self.play_time_s = 0.0
        self.playing = True
        self.scene.wake_loops()

    def _on_pause(self) -> None:
        self.playing = False
        self.scene.write_back(self.scrub, round(self._leader_km(), 2))  # where the riders stopped
        self.redraw(readouts=False)

    def _on_scrub(self) -> None:
        if self.state is None:
            return
        raw = self.scrub.value
        ok = isinstance(raw, (int, float)) and not isinstance(raw, bool) and math.isfinite(raw)
        km = float(np.clip(raw if ok else self._leader_km(), 0.0, self._total_km()))
        if not ok or km != raw:
            self.scene.write_back(self.scrub, km)
        ride = self.state.ride
        self.play_time_s = float(np.interp(km * 1000.0, ride.distance_m, ride.elapsed_s))
        self.redraw(readouts=False)

    # ----------------------------------------------------------------------------------------- animation
    def _animate(self, dt: float) -> bool:
        """One frame of the ride's playback; False (the loop sleeps) when it is not playing."""
        if not (self.enabled and self.playing and self.state is not None):
            return False
        dt = min(dt, 0.2)
        self.play_time_s = min(self.play_time_s + dt * self.params.playback, self.state.ride.time_s)
        if self.play_time_s >= self.state.ride.time_s:
            self.playing = False
        self._since_readout += dt
        if self._since_readout >= 0.2 or not self.playing:  # the slider and readout follow at 5 Hz
            self._since_readout = 0.0
            self.scene.write_back(self.scrub, round(self._leader_km(), 2))
            self.redraw(readouts=False, now=True)
        else:
            self.redraw(readouts=False, now=False)
        return True

    # ----------------------------------------------------------------------------------------- drawing
    def _total_km(self) -> float:
        return math.floor(self.route.total_distance_m / 10.0) / 100.0

    def leader_distance_m(self) -> float:
        if self.state is None:
            return 0.0
        ride = self.state.ride
        return float(np.interp(self.play_time_s, ride.elapsed_s, ride.distance_m))

    def _leader_km(self) -> float:
        return self.leader_distance_m() / 1000.0

    def rider_distances_m(self) -> np.ndarray:
        """(n_riders,) distance along the route of each drawn rider, leader first (spaced as drawn)."""
        n, gap = self.scene.params.n_riders, self.scene.params.gap_m
        spacing_m = (BIKE_LENGTH_M + gap) * COURSE_MARKER_SCALE / self._drawing.scale
        return self.leader_distance_m() - np.arange(n) * spacing_m

    def redraw(self, *, geometry: bool = False, readouts: bool = True, now: bool = True) -> None:
        """Show or hide the mode and push its state: riders always, geometry and readouts when asked."""
        s = self.scene
        with self.server.atomic():
            s.course.visible = not self.enabled
            if self.enabled:
                s.wind_arrow.visible = False
            self.frame.visible = self.enabled
            if geometry or self._drawn_exaggeration != self.params.exaggeration:
                self._draw_geometry()
            if s.params.position != self._drawn_position:
                for part, mesh in rider_meshes(s.params.position).items():
                    self.course_riders[part].vertices = mesh.vertices.astype(np.float32)
                    self.course_riders[part].faces = mesh.faces.astype(np.uint32)
                self._drawn_position = s.params.position
            self._draw_riders()
            if now:
                self.now.content = self._now_markdown()
            if readouts:
                self.route_info.content = self._route_markdown()
                self.readout.content = self._readout_markdown()
                self.splits.content = self._splits_markdown()
                self.chart.data = self._chart_data()
                self.chart.visible = self.state is not None
        self.server.flush()

    _drawn_exaggeration: float = 2.0

    def _draw_geometry(self) -> None:
        index = drawn_indices(self.route.n_points, MAX_DRAWN_POINTS)
        points = self._drawing.points(self.route, index, self.params.exaggeration)
        vertices, faces = terrain_strip(points, TERRAIN_HALF_WIDTH_M)
        self.terrain.vertices = vertices
        self.terrain.faces = faces
        self.ground.vertices, self.ground.faces = ground_under(points)
        segments, colours = self._route_segments(index, points)
        self.route_line.points = segments
        self.route_line.colors = colours
        self.start_label.position = tuple(points[0])
        self.finish_label.position = tuple(points[-1])
        self._drawn_exaggeration = self.params.exaggeration

    def _draw_riders(self) -> None:
        n = self.scene.params.n_riders
        positions = np.zeros((MAX_RIDERS, 3))
        wxyz = np.tile([1.0, 0.0, 0.0, 0.0], (MAX_RIDERS, 1))
        where, yaw = self._drawing.at_distance(
            self.route, self.rider_distances_m(), self.params.exaggeration
        )
        positions[:n] = where
        wxyz[:n] = np.stack([np.cos(yaw / 2), np.zeros(n), np.zeros(n), np.sin(yaw / 2)], axis=1)
        visible = (np.arange(MAX_RIDERS) < n).astype(np.float64)
        # Riders behind the start wait there (hidden until the line has rolled out).
        visible[:n] *= self.rider_distances_m() >= 0.0
        scales = np.repeat(visible[:, None], 3, axis=1) * COURSE_MARKER_SCALE
        for node in self.course_riders.values():
            node.batched_positions = positions.astype(np.float32)
            node.batched_wxyzs = wxyz.astype(np.float32)
            node.batched_scales = scales.astype(np.float32)
        self.leader_marker.position = tuple(where[0] + [0.0, 0.0, 0.5])

    def _chart_data(self) -> tuple[np.ndarray, ...]:
        route = self.route
        index = drawn_indices(route.n_points, MAX_CHART_POINTS)
        km = route.distance_m[index] / 1000.0
        elevation = route.elevation_m[index]
        if (
            self.state is None
        ):  # before the first ride: the profile, and zeros (never a NaN-only series)
            zeros = np.zeros_like(km)
            return km, elevation, zeros, zeros
        ride = self.state.ride
        return km, elevation, 3.6 * ride.speed_ms[index], ride.power_w[index]

    def _route_markdown(self) -> str:
        r = self.route
        average = 100.0 * (r.elevation_m[-1] - r.elevation_m[0]) / r.total_distance_m
        text = (
            f"**{_escape(r.name)}**: {r.total_distance_m / 1000:.2f} km, +{r.climbing_m:.0f} m, "
            f"{r.elevation_m[0]:.0f} → {r.elevation_m[-1]:.0f} m ({average:+.1f} % on average), {r.n_points} points"
        )
        if self.route_label == SAMPLE_LABEL:
            text += (
                "  \n*Sample route, built from Alpe d'Huez's published climb profile (13.2 km, 744 → 1815 m, "
                "8.1 %); its plan shape is schematic.*"
            )
        if self.message:
            text += f"  \n⚠️ {self.message}"
        return text

    def _readout_markdown(self) -> str:
        state = self.state
        if state is None:
            return "Tick **Ride a course** to ride it."
        ride, line = state.ride, self.scene.params
        p = self.params
        text = (
            f"Finish **{format_duration(ride.time_s)}**, average **{3.6 * ride.average_speed_ms:.1f} km/h** "
            f"at **{ride.average_power_w:.0f} W** ({MODEL_LABEL[p.model]})"
        )
        if ride.average_power_w < 0.99 * p.power_w and state.pacing is None:
            text += (
                f"  \nAverage {ride.average_power_w:.0f} W of the {p.power_w:.0f} W set: the riders coast "
                f"where the descent would take them over the {p.max_speed_kmh:.0f} km/h safe speed"
            )
        if state.group_cda_m2 != line.cda_m2:
            text += (
                f"  \n{line.n_riders} riders sharing the front (mean CdA {state.group_cda_m2:.3f} m²): "
                f"alone the same power takes {format_duration(state.solo.time_s)}"
            )
        if state.pacing is not None:
            saved = state.pacing.time_saved_s
            text += (
                f"  \nPacing by grade (±{p.pacing_gain_pct:.0f} %): {format_duration(state.constant.time_s)} at constant "
                f"power → {format_duration(ride.time_s)}, **{saved:.0f} s {'saved' if saved >= 0 else 'lost'}** at the same average power"
            )
        which = "weather" if p.air == "weather" else "seed"
        text += (
            f"  \nAir at the start ({state.route.elevation_m[0]:.0f} m): seed (exponential) **{state.density_seed:.3f}** kg/m³, "
            f"weather **{state.density_weather:.3f}** kg/m³; riding in the {which} air"
        )
        if ride.brakes_j > 0.0:
            text += (
                f"  \nBraking to hold {p.max_speed_kmh:.0f} km/h took {ride.brakes_j / 1000:.0f} kJ"
            )
        return text

    def _splits_markdown(self) -> str:
        if self.state is None:
            return ""
        ride = self.state.ride
        every = split_every_m(float(ride.distance_m[-1]))
        marks, times = ride.splits(every)
        rows = ["| km | elapsed | split | km/h |", "|---:|---:|---:|---:|"]
        previous_mark, previous_time = 0.0, 0.0
        shown = np.unique(
            np.linspace(0, marks.shape[0] - 1, min(marks.shape[0], 20)).round().astype(int)
        )
        for i in range(marks.shape[0]):
            split = times[i] - previous_time
            speed = 3.6 * (marks[i] - previous_mark) / split if split > 0 else 0.0
            if i in shown:
                rows.append(
                    f"| {marks[i] / 1000:.1f} | {format_duration(times[i])} | {format_duration(split)} | {speed:.1f} |"
                )
            previous_mark, previous_time = marks[i], times[i]
        return "\n".join(rows)

    def _now_markdown(self) -> str:
        if self.state is None:
            return ""
        ride = self.state.ride
        d = self.leader_distance_m()
        speed = float(np.interp(d, ride.distance_m, ride.speed_ms))
        power = float(
            ride.power_w[
                min(
                    int(np.searchsorted(ride.distance_m, d, side="right")) - 1,
                    ride.power_w.shape[0] - 1,
                )
            ]
        )
        elevation = float(np.interp(d, self.route.distance_m, self.route.elevation_m))
        coasting = ""
        if self.state.pacing is None and power < 0.99 * self.params.power_w:
            coasting = f" (coasting at the {self.params.max_speed_kmh:.0f} km/h descent cap)"
        return (
            f"Leader at **{d / 1000:.2f} km**, {format_duration(self.play_time_s)}: "
            f"{3.6 * speed:.1f} km/h, {power:.0f} W{coasting}, {elevation:.0f} m"
        )


def _escape(text: str) -> str:
    """Text from a file, shown in markdown: no HTML, no markdown links or images."""
    return (
        text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
        .replace("[", "&#91;").replace("]", "&#93;").replace("*", "&#42;").replace("|", "&#124;")
    )  # fmt: skip
