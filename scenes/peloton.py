"""Peloton: riders in a line, their power split into aero / rolling / climbing, drafting by gap, live.

Physics comes from :mod:`kernels.cycling`; this module owns the viser handles. The riders are three batched meshes
(bodies in team colours, bikes, heads) with one instance per rider, so a redraw is a handful of array writes. The
scene opens with eight instances and hides the unused ones by scaling them to zero, so changing the rider count
never re-adds a node.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import Literal

import numpy as np
import trimesh
import viser
import viser.uplot

from kernels import cycling
from scenes._base import Scene
from scenes._framing import ClientFraming, Lens, View, frame_points

MAX_RIDERS = 8
BIKE_LENGTH_M = 1.70
"""Wheel-to-wheel length of one bike; the gap is measured from the front wheel to the wheel ahead."""
BAR_METRES_PER_WATT = 1.0 / 400.0
"""Height of the stacked power bars above the riders."""
VIEW_DIRECTION = (-1.2, 7.5, -1.8)
"""The camera looks at the line from its left side, a little ahead of it and above."""
LABEL_STAGGER_M = 0.4
"""Every other rider's label sits this much higher (m), so labels of riders a wheel apart do not overlap."""
LABEL_PX = (190.0, 30.0)
"""Room a rider's label needs right of and above its anchor (px): framing keeps it clear of the panel."""

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
        self._build_gui()
        self._build_world()
        self.redraw()
        self._framed_for = self._framing_key()
        self._framed_points = self.line_points()
        self.framing = ClientFraming(self._view_for)
        self.watch_cameras(self.framing.on_camera)
        self.start_loop(self._animate, 1.0 / 30.0)

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
                    "Gap (m)", min=0.0, max=15.0, step=0.1, initial_value=p.gap_m
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
                self.chart = gui.add_uplot(
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
        grass = trimesh.creation.box(extents=(90.0, 60.0, 0.02))
        grass.apply_translation((-15.0, 0.0, -0.03))
        scene.add_mesh_simple(
            f"{self.course.name}/grass", grass.vertices, grass.faces, color=(120, 165, 95)
        )
        road = trimesh.creation.box(extents=(60.0, 3.0, 0.02))
        road.apply_translation((-15.0, 0.0, -0.01))
        scene.add_mesh_simple(
            f"{self.course.name}/road", road.vertices, road.faces, color=(70, 72, 78)
        )
        dashes = np.array(
            [[[x, 0.0, 0.002], [x + 1.5, 0.0, 0.002]] for x in np.arange(-44.0, 14.0, 3.0)]
        )
        scene.add_line_segments(
            f"{self.course.name}/centre_line", dashes, colors=(240, 240, 240), thickness=0.08
        )
        for side in (-1.5, 1.5):
            edge = np.array([[[-45.0, side, 0.003], [15.0, side, 0.003]]])
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

    # ----------------------------------------------------------------------------------------- camera
    def line_points(self) -> np.ndarray:
        """(N, 3) world points the view must hold: every rider (also swinging off), bar tops and the wind arrow."""
        p = self.params
        n = p.n_riders
        front, back = (
            0.5 * BIKE_LENGTH_M,
            float(slot_offsets(n, p.gap_m)[n - 1]) - 0.5 * BIKE_LENGTH_M,
        )
        top = 1.95 + LABEL_STAGGER_M + float(np.max(self.state.power.total)) * BAR_METRES_PER_WATT
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

    def _view_for(self, lens: Lens) -> View:
        ndc = lens.usable_ndc(right_px=LABEL_PX[0], top_px=LABEL_PX[1])
        return frame_points(
            self._framed_points, VIEW_DIRECTION, fov_rad=lens.fov_rad, aspect=lens.aspect, ndc=ndc
        )

    def _update_framing(self) -> None:
        """Frame every browser again when the line changes length or tilt, or its bars outgrow the view."""
        key = self._framing_key()
        points = self.line_points()
        if key == self._framed_for and points[:, 2].max() <= self._framed_points[:, 2].max() + 0.05:
            return
        self._framed_for, self._framed_points = key, points
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
            self.course.wxyz = (math.cos(-theta / 2), 0.0, math.sin(-theta / 2), 0.0)
            if p.position != self._drawn_position:
                for part, mesh in rider_meshes(p.position).items():
                    self.riders_nodes[part].vertices = mesh.vertices.astype(np.float32)
                    self.riders_nodes[part].faces = mesh.faces.astype(np.uint32)
                self._drawn_position = p.position
            for node in self.riders_nodes.values():
                node.batched_positions = positions.astype(np.float32)
                node.batched_scales = scales.astype(np.float32)

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
                    label.position = (x[i], y[i], 1.95 + base[i] + LABEL_STAGGER_M * (i % 2))

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
        self.wind_arrow.points = np.array(
            [[[tail_x, 0.0, 1.2], tip], [head[0], tip], [head[1], tip]]
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
    def _animate(self, dt: float) -> None:
        if not (self._rotating and self.params.n_riders > 1):
            return
        dt = min(dt, 0.2)
        slots = self.current_slots()
        self._energy_j[: self.params.n_riders] += np.asarray(self.state.power.total)[slots] * dt
        self._ridden_s += dt
        self._rotation_time_s += dt
        self.redraw(readouts=False)

    def rider_average_power(self) -> np.ndarray:
        """(n_riders,) time-averaged power of each rider since the rotation started (W); zeros before."""
        n = self.params.n_riders
        if self._ridden_s <= 0:
            return np.zeros(n)
        return self._energy_j[:n] / self._ridden_s
