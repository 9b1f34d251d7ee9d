"""Peloton: riders in a line, their power split into aero / rolling / climbing, drafting by gap, live.

Physics comes from :mod:`kernels.cycling` through :mod:`scenes.peloton.model`; this module owns the viser handles.
The riders are three batched meshes (bodies in team colours, bikes, heads) with one instance per rider
(:mod:`scenes.peloton.meshes`), so a redraw is a handful of array writes. The scene opens with eight instances and
hides the unused ones by scaling them to zero, so changing the rider count never re-adds a node. Its course mode
(:mod:`scenes.peloton.course`) rides a real route with the same riders.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable

import numpy as np
import trimesh
import viser
import viser.uplot

from kernels import cycling
from scenes._base import ControlSpec, Scene, record_spec, set_if_changed
from scenes._charts import FittedChart
from scenes._controls import Controls, build_controls, declared
from scenes._framing import ClientFraming, Lens, View, beside_notice, frame_points
from scenes._instances import add_instances, park_hidden
from scenes._look import add_ground
from scenes.peloton.course import CourseMode
from scenes.peloton.course_model import framed_front, framed_words
from scenes.peloton.legend import coasting_words, formation_table, legend_html, power_colours, power_range, riders_text
from scenes.peloton.legend import watts_text as _watts
from scenes.peloton.meshes import (
    GRASS_COLOUR,
    ROAD_COLOUR,
    Detail,
    add_riders,
    rider_colours,
    rider_detail,
    rider_head_m,
    show_position,
)
from scenes.peloton.model import (
    BIKE_LENGTH_M,
    CUSTOM,
    MAX_GAP_M,
    MAX_GROUP,
    MAX_RIDERS,
    PRESET_MENUS,
    ROAD_HALF_WIDTH_M,
    PelotonParams,
    Position,
    PresetMenu,
    compute_line,
    is_line_view,
    solo_curves,
    solo_key,
    solo_speed,
    wind_words,
    yaw_words,
)
from scenes.peloton.projection import (
    LABEL_PAD_PX,
    LABEL_PX,
    course_to_world,
    label_lifts_px,
    lift_to_metres,
    project_px,
    slot_offsets,
    under_notice,
)

ROAD_X_M = (-(MAX_GROUP - 1) * (BIKE_LENGTH_M + MAX_GAP_M) - 15.0, 15.0)
"""(start, end) x of the drawn road (m): the longest group (121 riders in single file at the largest gap) rides on
it, with 15 m spare at each end."""
GRASS_BEYOND_M = 150.0
"""How far the grass reaches beyond the road's sides and ends (m): the camera that frames the tallest bars (80 km/h
up 20 %) looks down from far enough back that grass ending 15 m from the road showed the page's white beneath it."""
BAR_METRES_PER_WATT = 1.0 / 400.0
"""Height of the stacked power bars above the riders."""
VIEW_DIRECTION = (-1.2, 7.5, -0.6)
"""The camera looks at the line from its left side, a little ahead of it and a little above: looking down steeply,
a wide-angle view leaned the bars at the window's edge by 15° (vertical lines converge); at 4.5° down they stand
within 6° of upright."""


def _looking(azimuth_deg: float, down_deg: float) -> tuple[float, float, float]:
    """A unit view direction ``azimuth_deg`` round from the road's forward axis (x) towards its left (y), looking
    ``down_deg`` below the horizon."""
    a, e = math.radians(azimuth_deg), math.radians(down_deg)
    return (math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), -math.sin(e))


GROUP_VIEW_DIRECTIONS: dict[str, tuple[float, float, float]] = {
    shape: _looking(160.0, 40.0) for shape in ("single", "double", "bunch", "echelon")
}
"""A group (a long line, two abreast, a bunch, echelons) is seen from ahead, on its right, 40° down, so the rows
behind show: of the directions tried round the group (every 20°, 30–60° down, the browser's 75° field of view), this
draws its smallest riders (the tenth percentile) largest once framed clear of the panel and of the software-WebGL
notice: a bunch of 121 at 1280×720 25 px tall (36 px at 1600×1000), 20 riders in echelons 33 px (53 px)."""
GROUP_LABELS = 4
"""Riders of a group labelled in the picture with their power and drag: the leader, the hardest-working rider
behind it, the one who works least and the last."""
GROUP_STEM_M = 0.35
"""A group label's anchor sits this far above the top of its rider's head (m), on a line down to the head."""
TEXT_PX_PER_CHAR = 6.4
"""Width (px) a label's text takes per character (DejaVu Sans at the labels' size: 20 characters measured 115 px),
with room to spare: a label's text must not cross another label's line."""
LABEL_STAGGER_M = 0.4
"""Every other rider's label sits this much higher (m) until a camera is framed and the labels laid out for it."""
BAR_HEADROOM = 1.3
"""Bars that outgrow the framed view are framed again this many times as tall: power goes with the cube of speed, so
a drag from 30 to 50 km/h re-frames about 7 times instead of 20."""
COMPONENT_COLOURS = {"aero": (60, 130, 240), "rolling": (245, 160, 40), "climbing": (60, 190, 90)}
ROTATION_WIDTH = {"single": 1, "double": 2}
"""Riders who lead together in each formation that rotates (the others do not take turns in order)."""
ROTATION = ("rotate", "turn_s")
"""The paceline's rotation controls: they restart the rotation and leave the line's power as it is."""
LAST = ("target_power_w",)
"""The controls built after the Results folder (in their own folder, with the speed-at-a-power readout)."""


# --------------------------------------------------------------------------------------------- scene
@dataclasses.dataclass(frozen=True)
class _Framing:
    """A view framed with its labels laid out: each label's lift and lane lift (m), whether anything framed lies
    under the software-WebGL notice, and the camera's distance from what it orbits (m: nearer draws larger)."""

    view: View
    lifts_m: np.ndarray
    lane_m: np.ndarray
    under_notice: bool
    distance_m: float


MIN_FRAMED_ROAD_M = (10.0, 4.0)
"""Least road (m, along and across) a group's camera frames round the group: a few riders are seen on their road."""


def _arrow_length(p: PelotonParams) -> float:
    """Length of the wind arrow (m): 0.25 m per m/s of ground wind (head and cross), at most 15 m/s's; 0 in still
    air."""
    return min(math.hypot(p.headwind_ms, p.crosswind_ms), 15.0) * 0.25


class PelotonScene(Scene[PelotonParams]):
    key = "peloton"
    title = "Peloton: cycling power"
    opening_view = View((-2.0, -7.5, 2.8), (-3.2, 0.0, 1.0))
    about = """
**What it shows.** Riders at one speed: a line of up to eight with power bars, or a formation of up to 121 (two
abreast, a bunch, an echelon) with each rider coloured by power. Each rider's power is split into pushing air (aero),
tyre rolling resistance and climbing; riders behind draft. The bars above the riders stack aero (blue), rolling
(orange) and climbing (green); the label gives watts and the share of the solo rider's power.

**Equations** (SI, θ = atan(grade), w = headwind):
P_aero = ½ρ·CdA·(v+w)|v+w|·v, P_roll = Crr·m·g·cos θ·v, P_climb = m·g·sin θ·v,
P = (P_aero + P_roll + P_climb)/η, ρ = 1.225·exp(−h/8500).

**Drafting.** *Textbook formula*: CdA·(1 − 0.27·exp(−gap/3.5)) for every follower (27 % at 0 m, 6.5 % at 5 m; the
original brief's prose overstates it). *Measured*: position-dependent, fitted to team-pursuit measurements (Barry et al.
2015; Fitton et al. 2018; Broker, Kyle & Burke 1999), fading with gap as Swiss Side's CFD does; the leader gains ~3 %
from the rider behind (Blocken et al. 2013). *Crosswind*: the wakes trail along the apparent wind, at yaw
ψ = atan(crosswind/(v + w)), so a line loses its shelter and an echelon angled downwind keeps it (checked against a
2022 CFD study of five riders in a crosswind). The echelon keeps its 24° diagonal, so it shelters most at ψ ≈ 20–28°
and little past 45° (real echelons steepen there). The power's air speed is the wind along the road.

**Assumptions.** Steady speed, no bearing or wheel-rotation losses, CdA independent of yaw; the exponential
atmosphere is the textbook one (ISA gives ρ about 4 % higher at 2000 m).

**Rotate the lead** animates a paceline: every turn the leader swings off and drops to the back, so each rider's
time-averaged power is the mean over positions, far below the leader's.
"""

    def __init__(self, server: viser.ViserServer) -> None:
        super().__init__(server)
        self.params = PelotonParams()
        self.state = compute_line(self.params)
        self._drawn_riders: tuple[Position, Detail] | None = None
        """The riding position and mesh detail the riders were last meshed for."""
        self._rotation_time_s = 0.0
        self._energy_j = np.zeros(MAX_GROUP)
        self._ridden_s = 0.0
        self._label_lift_m = LABEL_STAGGER_M * (np.arange(MAX_RIDERS) % 2)
        """How far each slot's label sits above its bar (m): laid out for the camera framed last."""
        self._lane_lift_m = np.full(MAX_RIDERS, 2.0 * LABEL_STAGGER_M)
        """How far above its bar (m), at each slot, the label of a leader dropping back rides: above every other
        label, so it crosses none of them (laid out with the others)."""
        self._build_gui()
        self._build_world()
        self.redraw()
        self._framed_for = self._framing_key()
        self._framed_points = self.line_points()
        self.framing = ClientFraming(self._view_for, opening=self.opening_view.position)
        self.watch_cameras(self.framing.on_camera)
        self.start_loop(self._animate, 1.0 / 30.0)
        self.course_mode = CourseMode(self)

    # ----------------------------------------------------------------------------------------- GUI
    def _build_gui(self) -> None:
        gui, p = self.server.gui, self.params
        with self.gui_root:
            # A group's colour key, at the top of the panel: seen at once, without scrolling, in a small window.
            self.legend = gui.add_html("", visible=False)
            line = self._build_line_controls()
            with gui.add_folder("Results"):
                self.density = gui.add_markdown("")
                self.table = gui.add_markdown("")
                self.rotation = gui.add_markdown("")
                self.chart = FittedChart(
                    gui,
                    data=self._chart_data(),
                    series=(
                        viser.uplot.Series(label="Speed (km/h)"),
                        # The parts at the wheel, their sum at the pedals (÷ η): a "Total" beside them read 2.4 %
                        # more than they add to, with nothing to say why.
                        viser.uplot.Series(label="Aero, wheel (W)", stroke="rgb(60,130,240)", width=2),
                        viser.uplot.Series(label="Rolling, wheel (W)", stroke="rgb(245,160,40)", width=2),
                        viser.uplot.Series(label="Climbing, wheel (W)", stroke="rgb(60,190,90)", width=2),
                        viser.uplot.Series(label="Total at the pedals (W)", stroke="black", width=2),
                        viser.uplot.Series(
                            label="Solo now (W)",
                            stroke="rgb(220,30,30)",
                            width=1.5,
                            dash=(6.0, 4.0),
                            points=viser.uplot.Series_Points(show=False),
                        ),
                    ),
                    legend=viser.uplot.Legend(show=True),
                    title="Solo power vs speed (cube law)",
                    aspect=1.4,
                )
            power = build_controls(gui, p, LAST)
            with power.folders["Speed at a power"]:
                self.speed_out = gui.add_markdown("")
        self.controls: Controls[PelotonParams] = line | power
        """Every declared control of :class:`PelotonParams`, by field name."""
        for name in self.controls.fields:
            handler = self._on_rotate if name in ROTATION else self.apply_inputs
            self.controls[name].on_update(self.callback(handler))
        for menu in PRESET_MENUS:
            self.presets[menu.field].on_update(self.callback(functools.partial(self._on_preset, menu)))

    def _build_line_controls(self) -> Controls[PelotonParams]:
        """Build the declared controls up to the Results folder, each preset menu (:data:`PRESET_MENUS`) just above
        its field's control, in that control's folder; fills :attr:`presets`."""
        gui, p = self.server.gui, self.params
        declarations = declared(PelotonParams)
        names = [name for name in declarations if name not in LAST]
        self.presets: dict[str, viser.GuiDropdownHandle[str]] = {}
        """Each preset menu's dropdown, by the field it sets: it shows :meth:`PresetMenu.shown` of the params."""
        built: Controls[PelotonParams] | None = None
        start = 0
        for menu in sorted(PRESET_MENUS, key=lambda m: names.index(m.field)):
            end = names.index(menu.field)
            part = build_controls(gui, p, names[start:end], folders_open=built.folders if built else None)
            built = part if built is None else built | part
            folder = declarations[menu.field].folder
            assert folder is not None, f"{menu.label}: its field's control has no folder to go in"
            if folder not in built.folders:
                built = dataclasses.replace(built, folders={**built.folders, folder: gui.add_folder(folder)})
            with built.folders[folder]:
                handle = gui.add_dropdown(menu.label, menu.options, initial_value=menu.shown(p))
            record_spec(handle, ControlSpec("choice", options=menu.options))  # from the menu, not the handle
            self.presets[menu.field] = handle
            start = end
        part = build_controls(gui, p, names[start:], folders_open=built.folders if built else None)
        return part if built is None else built | part

    # ----------------------------------------------------------------------------------------- world
    def _build_world(self) -> None:
        scene = self.server.scene
        self.course = scene.add_frame(f"{self.root.name}/course", show_axes=False)
        start, end = ROAD_X_M
        length, middle = end - start, 0.5 * (start + end)
        # Grass either side of the road and beyond its ends, not under it: in software WebGL every pixel drawn twice
        # costs a frame.
        verges = []
        for side in (-1.0, 1.0):
            verge = trimesh.creation.box(
                extents=(length + 2.0 * GRASS_BEYOND_M, GRASS_BEYOND_M - ROAD_HALF_WIDTH_M, 0.02)
            )
            verge.apply_translation((middle, side * 0.5 * (GRASS_BEYOND_M + ROAD_HALF_WIDTH_M), -0.03))
            beyond_end = trimesh.creation.box(extents=(GRASS_BEYOND_M, 2.0 * ROAD_HALF_WIDTH_M, 0.02))
            beyond_end.apply_translation((middle + side * 0.5 * (length + GRASS_BEYOND_M), 0.0, -0.03))
            verges += [verge, beyond_end]
        grass = trimesh.util.concatenate(verges)
        assert isinstance(grass, trimesh.Trimesh)
        self.grass = add_ground(scene, f"{self.course.name}/grass", grass.vertices, grass.faces, GRASS_COLOUR)
        road = trimesh.creation.box(extents=(length, 2.0 * ROAD_HALF_WIDTH_M, 0.02))
        road.apply_translation((middle, 0.0, -0.01))
        self.road = add_ground(scene, f"{self.course.name}/road", road.vertices, road.faces, ROAD_COLOUR)
        dashes = np.array([[[x, 0.0, 0.002], [x + 1.5, 0.0, 0.002]] for x in np.arange(start + 1.0, end - 1.0, 3.0)])
        scene.add_line_segments(f"{self.course.name}/centre_line", dashes, colors=(240, 240, 240), thickness=0.08)
        for side in (-ROAD_HALF_WIDTH_M, ROAD_HALF_WIDTH_M):
            edge = np.array([[[start, side, 0.003], [end, side, 0.003]]])
            scene.add_line_segments(
                f"{self.course.name}/edge_{side:+.0f}", edge, colors=(250, 250, 250), thickness=0.06
            )

        self.riders_nodes = add_riders(scene, f"{self.course.name}/riders", self.params.position, 0.0, MAX_GROUP)
        self._drawn_riders = (self.params.position, "full")

        unit_box = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
        unit_box.apply_translation((0.0, 0.0, 0.5))  # grows upward from its base
        self.bars: dict[str, viser.BatchedMeshHandle] = {}
        for component, colour in COMPONENT_COLOURS.items():
            self.bars[component] = add_instances(
                scene,
                f"{self.course.name}/bars_{component}",
                unit_box,
                MAX_RIDERS,
                np.tile(np.array(colour, np.uint8), (MAX_RIDERS, 1)),
                cast_shadow=False,
            )
        self.labels = [
            scene.add_label(f"{self.course.name}/label_{i}", text="", position=(0.0, 0.0, 2.0), font_screen_scale=0.9)
            for i in range(MAX_RIDERS)
        ]
        # A thin line from each bar's top up to its label: a label lifted clear of its neighbours still shows whose
        # it is.
        self.label_leaders = scene.add_line_segments(
            f"{self.course.name}/label_leaders",
            np.zeros((MAX_RIDERS, 2, 3)),
            colors=(90, 90, 95),
            thickness=1.5,
            thickness_units="screen",
        )
        self.wind_arrow = scene.add_line_segments(
            f"{self.root.name}/wind", np.zeros((3, 2, 3)), colors=(120, 200, 255), thickness=0.05
        )
        self.wind_label = scene.add_label(
            f"{self.root.name}/wind_words", text="", position=(3.0, 0.0, 1.6), font_screen_scale=0.9, visible=False
        )

    # ----------------------------------------------------------------------------------------- callbacks
    def _on_preset(self, menu: PresetMenu) -> None:
        """A preset chosen in ``menu`` sets its field's control to its value (:data:`CUSTOM` leaves it), then every
        input is applied (which shows each menu's name for the values held)."""
        name = self.read_choice(self.presets[menu.field], menu.options, menu.shown(self.params))
        if name != CUSTOM:
            self.write_back(self.controls[menu.field], menu.presets[name])
        self.apply_inputs()

    def _show_presets(self) -> None:
        """Show in each preset menu the name of the value its field holds now, or Custom: after every input, so no
        menu names a preset the value has left."""
        for menu in PRESET_MENUS:
            handle, name = self.presets[menu.field], menu.shown(self.params)
            if handle.value != name:
                self.write_back(handle, name)

    def _on_rotate(self) -> None:
        rotation = self.read_params()  # only the rotation is taken: the line's power stays as computed
        self.params = dataclasses.replace(self.params, rotate=rotation.rotate, turn_s=rotation.turn_s)
        self._rotation_time_s = 0.0
        self._energy_j[:] = 0.0
        self._ridden_s = 0.0
        self.redraw()
        self.wake_loops()

    def apply_inputs(self) -> None:
        """Read every control, compute the line and redraw (what any input's change does)."""
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
        finally:
            self._show_presets()  # the menus name what is held, also when a value was clamped or refused
        self._update_framing()
        # An input can start the rotation (Riders raised from 1 while Rotate is on): wake the loop.
        if self._rotating():
            self.wake_loops()

    # ----------------------------------------------------------------------------------------- camera
    def _rotation_width(self) -> int:
        """Riders who lead together and drop back together: 1 in single file, 2 two abreast, 0 where riders do not
        take turns in order (a bunch, an echelon)."""
        return ROTATION_WIDTH.get(self.params.formation, 0)

    def _rotating(self) -> bool:
        """Whether the lead rotates now: asked for, in a paceline with more riders than lead at once."""
        width = self._rotation_width()
        return self.params.rotate and width > 0 and self.params.n_riders > width

    def line_points(self, bar_headroom: float = 1.0) -> np.ndarray:
        """(N, 3) world points the view must hold: every rider (also swinging off), bar tops (``bar_headroom`` times
        as tall as now) and the wind arrow; for a group, the corners of every rider's box and the wind arrow."""
        p = self.params
        n = p.n_riders
        if not is_line_view(p):
            x, y = self.state.positions.T
            framed = framed_front(self.state.positions)  # a long line's front, at a readable size
            x, y, n = x[framed], y[framed], int(np.count_nonzero(framed))
            top, half = rider_head_m(p.position)[1], 0.5 * BIKE_LENGTH_M
            # Every corner of each rider's box, wheels to head: a close camera (a few riders) sees a box's top
            # corners well outside the points of a cross through it.
            local = np.vstack(
                [
                    np.stack([x + sx * half, y + sy * 0.3, np.full(n, z)], axis=1)
                    for sx in (-1, 1)
                    for sy in (-1, 1)
                    for z in (0.0, top)
                ]
            )
            if _arrow_length(p) > 0:  # the wind arrow, ahead of the leader
                local = np.vstack([local, [[x.max() + half + 3.0 + _arrow_length(p), 0.0, 1.2]]])
            # At least a patch of road round a small group: a lone rider framed by its own box filled half the
            # window, its label far above it.
            length, width = MIN_FRAMED_ROAD_M
            front = x.max() + half
            patch = [[front - length * i, width * (j - 0.5), 0.0] for i in (0, 1) for j in (0, 1)]
            local = np.vstack([local, patch])
            return course_to_world(local, p.grade_pct)
        front, back = (0.5 * BIKE_LENGTH_M, float(slot_offsets(n, p.gap_m)[n - 1]) - 0.5 * BIKE_LENGTH_M)
        top = 1.95 + LABEL_STAGGER_M + bar_headroom * float(np.max(self._bar_heights_m()))
        x_hi = front + (3.0 + _arrow_length(p) if _arrow_length(p) > 0 else 0.0)
        lo, hi = np.array([back, -1.1, 0.0]), np.array([x_hi, 1.1, max(top, 2.2)])
        corners = np.array(
            [[(lo, hi)[i][0], (lo, hi)[j][1], (lo, hi)[k][2]] for i in (0, 1) for j in (0, 1) for k in (0, 1)]
        )
        return course_to_world(corners, p.grade_pct)

    def _bar_heights_m(self) -> np.ndarray:
        """(n_riders,) height of each slot's stacked bars (m): the positive parts only, as drawn (downhill the
        climbing part is negative and the stack stands taller than the total)."""
        power = self.state.power
        parts = [np.maximum(np.asarray(getattr(power, c)), 0.0) for c in COMPONENT_COLOURS]
        return np.sum(parts, axis=0)[: self.params.n_riders] * BAR_METRES_PER_WATT

    def label_anchors(self) -> np.ndarray:
        """(labels, 3) world points where each label sits before it is lifted: just above its bar in a line, above
        its rider's head (:data:`GROUP_STEM_M`) for the riders of a group that are labelled
        (:meth:`marked_slots`)."""
        p, n = self.params, self.params.n_riders
        if not is_line_view(p):
            ahead, top = rider_head_m(p.position)
            xy = self.state.positions[self.marked_slots()] + [ahead, 0.0]
            return course_to_world(np.column_stack([xy, np.full(len(xy), top + GROUP_STEM_M)]), p.grade_pct)
        x = slot_offsets(n, p.gap_m)[:n]
        local = np.stack([x, np.zeros(n), 1.95 + self._bar_heights_m()], 1)
        return course_to_world(local, p.grade_pct)

    def marked_slots(self) -> np.ndarray:
        """Slots of a group labelled in the picture, front first, none twice: the leader, the hardest-working rider
        behind it, the one who works least and the last (:data:`GROUP_LABELS`), of the riders the camera frames (the
        front :data:`FRAMED_LENGTH_M` of a long group)."""
        n, total = self.params.n_riders, self.state.pedal_w
        if n == 1:
            return np.zeros(1, np.int64)
        x = self.state.positions[:, 0]
        framed = np.flatnonzero(framed_front(self.state.positions))
        behind = framed[framed > 0]
        if len(behind) == 0:
            return np.zeros(1, np.int64)
        last = int(framed[-1])  # slots run front to back: the last rider, or the last one framed
        picks = [0, int(behind[np.argmax(total[behind])]), int(framed[np.argmin(total[framed])]), last]
        # One label per reading: riders that would say the same (a pair at the front, the last rider when it is
        # the one who works least) are labelled once.
        said = {self.label_text(slot): slot for slot in reversed(picks)}
        unique = list(dict.fromkeys(slot for slot in picks if said[self.label_text(slot)] == slot))[:GROUP_LABELS]
        return np.asarray(unique, np.int64)[np.argsort(-x[unique], kind="stable")]

    def push_cause(self, slope: str = "the slope") -> tuple[str, bool]:
        """(what, plural): what gives the riders power when they need less than nothing, from the solo rider's own
        terms: ``slope`` (the slope, or gravity) where its climbing term is negative, "the tailwind" where its air term
        is (a tailwind faster than the rider), or both (plural: the verb agrees)."""
        solo = self.state.solo
        causes = [
            what for what, yes in ((slope, float(solo.climbing) < 0.0), ("the tailwind", float(solo.aero) < 0.0)) if yes
        ]
        return " and ".join(causes) or slope, len(causes) > 1

    def label_text(self, slot: int) -> str:
        """What the label of the rider in ``slot`` says: its watts and its share of the solo rider's power in a
        line; its watts and its drag (% of the same rider alone) in a group."""
        state = self.state
        watts = float(state.pedal_w[slot])
        coasting = float(state.brake_w[slot]) >= 0.5
        power = f"{_watts(watts)} W coasting" if coasting else f"{_watts(watts)} W"
        if not is_line_view(self.params):
            return f"{power} · drag {100.0 * (1.0 - float(state.reduction[slot])):.0f} %"
        solo = state.solo_pedal_w
        if coasting:
            return "0 W · coasting"
        if self.params.speed_kmh == 0.0:
            return "0 W · standing still"
        if solo <= 0.0:
            return f"{power} · solo coasts"
        if state.pedals_more[slot]:  # a tailwind's push lost to shelter: what alone would pedal, as Saving says
            return f"{power} · solo {_watts(solo)} W"
        return f"{power} · {100.0 * watts / solo:.0f} % of solo"

    def _view_for(self, lens: Lens) -> View:
        """The view of the line for ``lens``, with room above it for the labels, which it lays out for that lens (or,
        in course mode, the course's view of its group: :meth:`CourseMode.view_for`).

        Nothing goes under viser's software-WebGL notice at the top left (:data:`NOTICE_PX`): where the view of the
        whole rectangle left of the panel would put something there, the larger of the views below the notice and
        right of it is taken."""
        course_mode = getattr(self, "course_mode", None)  # built last
        if course_mode is not None and course_mode.enabled:
            return course_mode.view_for(lens)
        with self._lock:
            ndc = lens.usable_ndc(right_px=LABEL_PX[0], top_px=LABEL_PX[1])
            framing = self._frame_with_labels(lens, ndc)
            if framing.under_notice:
                candidates = [
                    self._frame_with_labels(lens, part) for part in beside_notice(lens, ndc, room_above_px=LABEL_PX[1])
                ]
                clear = [c for c in candidates if not c.under_notice] or candidates
                framing = min(clear, key=lambda c: c.distance_m)
            self._label_lift_m = np.zeros(MAX_RIDERS)
            self._label_lift_m[: len(framing.lifts_m)] = framing.lifts_m
            self._lane_lift_m = np.zeros(MAX_RIDERS)
            self._lane_lift_m[: len(framing.lane_m)] = framing.lane_m
            self.redraw(readouts=False)
            return framing.view

    def _frame_with_labels(self, lens: Lens, ndc: tuple[float, float, float, float]) -> _Framing:
        """Frame what :meth:`line_points` holds inside ``ndc`` with the labels laid out for it (call under the
        lock)."""
        anchors = self.label_anchors()
        up_world = course_to_world(np.array([[0.0, 0.0, 1.0]]), self.params.grade_pct)[0]
        x0, x1 = (ndc[0] + 1.0) / 2.0 * lens.width_px, (ndc[1] + 1.0) / 2.0 * lens.width_px
        y_top, y_bottom = (1.0 - ndc[3]) / 2.0 * lens.height_px, (1.0 - ndc[2]) / 2.0 * lens.height_px
        framed, view = self._framed_points, None
        lifts_m = lane_m = np.zeros(len(anchors))
        lifted = anchors
        # Frame the line with the lifted label anchors, which lean with the road's tilt (a fresh review: up a 20 %
        # grade the last label started left of the window); the box of each label lies right of and above its
        # anchor, in the room the rectangle leaves. Framing the anchors shrinks the line, which may stack the labels
        # differently: repeat until the lifted anchors fit.
        line_view = is_line_view(self.params)
        slots = range(self.params.n_riders) if line_view else self.marked_slots()
        text_px = TEXT_PX_PER_CHAR * max(len(self.label_text(int(slot))) for slot in slots)
        stem_m = 0.2 if line_view else GROUP_STEM_M  # from the bar's top or the head up to the anchor
        direction = VIEW_DIRECTION if line_view else GROUP_VIEW_DIRECTIONS[self.params.formation]
        for _ in range(MAX_RIDERS + 2):
            view = frame_points(framed, direction, fov_rad=lens.fov_rad, aspect=lens.aspect, ndc=ndc)
            anchors_px = project_px(anchors, view, lens)
            stem_px = float(np.max(project_px(anchors - stem_m * up_world, view, lens)[:, 1] - anchors_px[:, 1]))
            lifts_px = label_lifts_px(anchors_px, text_px=text_px, stem_px=stem_px)
            lifts_m = lift_to_metres(anchors, lifts_px, up_world, view, lens)
            lifted = anchors + lifts_m[:, None] * up_world
            # The lane: a label lifted to it sits, wherever along the line, above the top of every label.
            lane_y = np.min(anchors_px[:, 1] - lifts_px, initial=np.inf) - LABEL_PX[1] - LABEL_PAD_PX
            lane_px = np.maximum(anchors_px[:, 1] - lane_y, 0.0)
            lane_m = lift_to_metres(anchors, lane_px, up_world, view, lens)
            if self._rotating():  # the lane a dropping leader's label rides in must be in view too
                lifted = np.vstack([lifted, anchors + lane_m[:, None] * up_world])
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
        hidden = under_notice(project_px(framed, view, lens), project_px(lifted, view, lens))
        distance = math.dist(view.position, view.look_at)
        return _Framing(view, lifts_m, lane_m, under_notice=hidden, distance_m=distance)

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
        return (p.n_riders, p.formation, p.gap_m, p.grade_pct, _arrow_length(p) > 0, p.crosswind_ms < 0.0)

    def read_params(self) -> PelotonParams:
        """The current GUI values, cleaned: anything non-finite, out of range or unknown keeps the last good value."""
        return self.read_controls(self.controls)

    # ----------------------------------------------------------------------------------------- drawing
    def _chart_data(self) -> tuple[np.ndarray, ...]:
        p = self.params
        speeds_kmh, aero, rolling, climbing, total = solo_curves(solo_key(p))
        # A level line at the solo power now: it meets the total curve at the current speed. (A single marker needs
        # NaN elsewhere, and one NaN makes uPlot's auto range NaN, so the chart drew nothing at all.)
        now = np.full_like(speeds_kmh, float(self.state.solo.total))
        return speeds_kmh, aero, rolling, climbing, total, now

    def _slot_of_rider(self) -> tuple[np.ndarray, np.ndarray]:
        """(x, y) of each rider now: the plain line, or mid-rotation when the lead rotates."""
        n, p = self.params.n_riders, self.params
        slots = slot_offsets(n, p.gap_m)
        x, y = slots.copy(), np.zeros(MAX_RIDERS)
        if not self._rotating():
            return x, y
        turn = p.turn_s
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
        if not self._rotating():
            return np.arange(n)
        k = int(self._rotation_time_s // self.params.turn_s)
        return (np.arange(n) - k * self._rotation_width()) % n

    def group_positions(self) -> np.ndarray:
        """(n_riders, 2) where each rider of a group rides now (m): its formation slot or, while the lead rotates,
        between slots: in the last quarter of a turn the front riders swing out and drift to the back while the
        others move up a row."""
        slots_xy = self.state.positions
        if not self._rotating():
            return slots_xy
        n, width = self.params.n_riders, self._rotation_width()
        slots = self.current_slots()
        phase = (self._rotation_time_s / self.params.turn_s) % 1.0
        u = max(0.0, (phase - 0.75) / 0.25)
        ease = 0.5 - 0.5 * math.cos(math.pi * u)
        target = (slots - width) % n
        xy = slots_xy[slots] + ease * (slots_xy[target] - slots_xy[slots])
        leading = slots < width
        outward = np.where(slots_xy[slots, 1] < 0.0, -1.0, 1.0)
        xy[:, 1] += leading * outward * 0.9 * math.sin(math.pi * ease)
        return xy

    def redraw(self, *, readouts: bool = True) -> None:
        """Push the current state to the riders, bars and labels and, with ``readouts``, to the GUI outputs.

        One atomic update; the animation redraws without readouts, which do not change as riders move.
        """
        p, state = self.params, self.state
        course_mode = getattr(self, "course_mode", None)  # built last
        if course_mode is not None and course_mode.enabled:
            return  # the flat road is hidden and the panel's legend and table are the course's (CourseMode.redraw)
        if not is_line_view(p):
            self._redraw_group(readouts=readouts)
            return
        n = p.n_riders
        slots = self.current_slots()
        x, y = self._slot_of_rider()
        positions = np.stack([x, y, np.zeros(MAX_RIDERS)], axis=1)
        visible = (np.arange(MAX_RIDERS) < n).astype(np.float64)
        scales = np.repeat(visible[:, None], 3, axis=1)
        group_positions = np.zeros((MAX_GROUP, 3), np.float32)
        group_positions[:MAX_RIDERS] = positions
        group_scales = np.zeros((MAX_GROUP, 3), np.float32)
        group_scales[:MAX_RIDERS] = scales

        with self.server.atomic():
            self._tilt_and_pose()
            self._show_riders(group_positions, group_scales, rider_colours("body", MAX_GROUP))

            base = np.zeros(MAX_RIDERS)
            for component in ("aero", "rolling", "climbing"):
                watts = np.zeros(MAX_RIDERS)
                watts[:n] = np.maximum(np.asarray(getattr(state.power, component))[slots], 0.0)
                height = watts * BAR_METRES_PER_WATT
                bar_pos = positions + np.stack([np.zeros(MAX_RIDERS), np.zeros(MAX_RIDERS), 1.75 + base], axis=1)
                self.bars[component].batched_positions = bar_pos.astype(np.float32)
                self.bars[component].batched_scales = np.stack(
                    [0.35 * visible, 0.35 * visible, np.maximum(height, 1e-4) * visible], axis=1
                ).astype(np.float32)
                base = base + height
            lifts = self._label_lifts(x, slots)
            leaders = np.zeros((MAX_RIDERS, 2, 3))
            leaders[:n, 0] = np.stack([x[:n], y[:n], 1.75 + base[:n]], axis=1)
            leaders[:n, 1] = np.stack([x[:n], y[:n], 1.95 + base[:n] + lifts], axis=1)
            set_if_changed(self.label_leaders, "points", leaders.astype(np.float32))
            set_if_changed(self.label_leaders, "visible", True)
            for i, label in enumerate(self.labels):
                # Only write what changed: every property write is a message to every browser.
                if label.visible != (i < n):
                    label.visible = i < n
                if i < n:
                    text = self.label_text(int(slots[i]))
                    if label.text != text:
                        label.text = text
                    # Neighbours' labels alternate in height so close riders' labels never overlap.
                    # Lifted by the layout for the framed camera, so no two labels overlap.
                    set_if_changed(label, "position", (x[i], y[i], 1.95 + base[i] + lifts[i]))

            set_if_changed(self.legend, "visible", False)
            self._show_panel(self._table_markdown, readouts=readouts)
        self.server.flush()

    def _tilt_and_pose(self) -> None:
        """Tilt the road to the grade and, when the riding position or the group's mesh detail changed, re-mesh every
        rider for it."""
        p = self.params
        theta = math.atan(p.grade_pct / 100.0)
        set_if_changed(self.course, "wxyz", (math.cos(-theta / 2), 0.0, math.sin(-theta / 2), 0.0))
        riders = (p.position, rider_detail(p.n_riders))
        if riders != self._drawn_riders:
            show_position(self.riders_nodes, *riders)
            self._drawn_riders = riders

    def _show_panel(self, table: Callable[[], str], *, readouts: bool) -> None:
        """Write the lead rotation's words and, with ``readouts``, the wind, the density, ``table()``, the chart and
        the speed: the readouts a line and a group share."""
        rotation = self._rotation_markdown()
        if self.rotation.content != rotation:
            self.rotation.content = rotation
        if readouts:
            self._draw_wind()
            self.density.content = self._density_markdown()
            self.table.content = table()
            self.chart.data = self._chart_data()
            set_if_changed(self.chart, "visible", True)  # hidden in course mode, which has its own chart
            self.speed_out.content = self._speed_markdown()

    def _label_lifts(self, x: np.ndarray, slots: np.ndarray) -> np.ndarray:
        """(n_riders,) how far above its bar each rider's label sits (m): its slot's lift from the layout; a leader
        dropping back steps up into the lane above every label as it swings off and rides there, so its label
        crosses no other (it steps, from one frame to the next, rather than sliding through the others)."""
        n = self.params.n_riders
        lifts = self._label_lift_m[slots].copy()
        if not self._rotating():
            return lifts
        xs = slot_offsets(n, self.params.gap_m)[:n]
        for i in np.flatnonzero(slots == 0):
            drift = (xs[0] - x[i]) / max(xs[0] - xs[n - 1], 1e-9)
            if drift <= 0.0:
                continue
            lifts[i] = max(float(np.interp(x[i], xs[::-1], self._lane_lift_m[:n][::-1])), lifts[i])
        return lifts

    def _show_riders(self, positions: np.ndarray, scales: np.ndarray, bodies: np.ndarray) -> None:
        """Place the (MAX_GROUP,) rider instances and colour their bodies (only what changed goes out)."""
        positions = park_hidden(positions, scales)
        for node in self.riders_nodes.values():
            set_if_changed(node, "batched_positions", positions)
            set_if_changed(node, "batched_scales", scales.astype(np.float32))
        set_if_changed(self.riders_nodes["body"], "batched_colors", bodies)

    def _redraw_group(self, *, readouts: bool) -> None:
        """Draw a group: every rider where the formation puts it, its jersey coloured by its power (the legend in
        the panel says the watts), no bars or labels; the readouts, with ``readouts``."""
        p, state = self.params, self.state
        n = p.n_riders
        positions = np.zeros((MAX_GROUP, 3), np.float32)
        positions[:n, :2] = self.group_positions()
        scales = np.zeros((MAX_GROUP, 3), np.float32)
        scales[:n] = 1.0
        total = state.pedal_w
        low, high = power_range(total)
        bodies = rider_colours("body", MAX_GROUP)
        bodies[:n] = power_colours(total[self.current_slots()], low, high)
        with self.server.atomic():
            self._tilt_and_pose()
            self._show_riders(positions, scales, bodies)
            for bar in self.bars.values():
                set_if_changed(bar, "batched_scales", np.zeros((MAX_RIDERS, 3), np.float32))
            self._label_group(positions)
            drag = 1.0 - state.reduction
            summary = (
                f"{riders_text(n)}: mean drag {100 * float(np.mean(drag)):.0f} % of a lone rider's, mean power "
                f"{_watts(float(np.mean(total)))} W (alone {_watts(state.solo_pedal_w)} W)"
            )
            legend = legend_html(total, summary)
            if self.legend.content != legend:
                self.legend.content = legend
            set_if_changed(self.legend, "visible", True)
            self._show_panel(self._group_table_markdown, readouts=readouts)
        self.server.flush()

    def _label_group(self, positions: np.ndarray) -> None:
        """Label the marked riders of a group (:meth:`marked_slots`) where they ride now (``positions``: (MAX_GROUP,
        3) of every rider, m), each on a line down to its head; hide the other labels."""
        marked = self.marked_slots()
        rider_in = np.argsort(self.current_slots())  # which rider rides in each slot
        ahead, head = rider_head_m(self.params.position)
        leaders = np.zeros((MAX_RIDERS, 2, 3))
        for i, label in enumerate(self.labels):
            shown = i < len(marked)
            if label.visible != shown:
                label.visible = shown
            if not shown:
                continue
            x, y = float(positions[rider_in[marked[i]], 0]) + ahead, float(positions[rider_in[marked[i]], 1])
            top = head + GROUP_STEM_M + float(self._label_lift_m[i])
            leaders[i] = [(x, y, head + 0.05), (x, y, top)]
            text = self.label_text(int(marked[i]))
            if label.text != text:
                label.text = text
            set_if_changed(label, "position", (x, y, top))
        set_if_changed(self.label_leaders, "points", leaders.astype(np.float32))
        set_if_changed(self.label_leaders, "visible", True)

    def _group_table_markdown(self) -> str:
        """Drag and power by row of the formation (riders level with each other share a row), front to back; long
        groups show their first and last rows."""
        state, p = self.state, self.params
        total, drag = state.pedal_w, 1.0 - state.reduction
        summary = (
            f"{riders_text(p.n_riders)} · mean drag **{100 * float(np.mean(drag)):.0f} %** of a lone rider's "
            f"· mean power **{_watts(float(np.mean(total)))} W** (a lone rider {_watts(state.solo_pedal_w)} W)"
        )
        if coasting := coasting_words(state.brake_w, *self.push_cause()):
            summary += "  \n" + coasting
        summary += framed_words(state.positions)
        return formation_table(state.positions, drag, {"Power (W)": total}, summary)

    def _draw_wind(self) -> None:
        """The ground wind as an arrow ahead of the leader, blowing the way it blows (against the riders for a
        headwind, across from the left for a crosswind from the left), 0.25 m per m/s up to 15 m/s."""
        p = self.params
        length = _arrow_length(p)
        speed = math.hypot(p.headwind_ms, p.crosswind_ms)  # no underflow: a tiny wind has a direction too
        if length == 0.0 or not speed > 0.0:
            self.wind_arrow.visible = self.wind_label.visible = False
            return
        self.wind_arrow.visible = self.wind_label.visible = True
        u = np.array([-p.headwind_ms, -p.crosswind_ms, 0.0]) / speed
        centre = np.array([3.0 + 0.5 * length, 0.0, 1.2])
        tail, tip = centre - 0.5 * length * u, centre + 0.5 * length * u
        head = [tip - 0.3 * u + [0.0, 0.0, 0.2], tip - 0.3 * u - [0.0, 0.0, 0.2]]
        set_if_changed(self.wind_arrow, "points", np.array([[tail, tip], [head[0], tip], [head[1], tip]]))
        words = wind_words(p)
        if self.wind_label.text != words:
            self.wind_label.text = words
        # The words start above the arrow's end nearest the leader and read on over it, toward the panel.
        set_if_changed(self.wind_label, "position", (3.0, 0.0, 1.2 + 0.5))

    def _density_markdown(self) -> str:
        p, solo = self.params, self.state.solo
        rho = float(cycling.air_density(p.altitude_m))
        aero, rolling, climbing = float(solo.aero), float(solo.rolling), float(solo.climbing)
        spent = self.state.solo_spent_w
        where = density_words(rho)
        if spent > 0 and aero + rolling + climbing > 0:
            share = f"the air takes **{100.0 * max(aero, 0.0) / spent:.1f} %** of the power spent at the wheel"
        else:  # standing still, or a descent or tailwind that pays for it all: no share of nothing
            share = "no power needed at the wheel"
        total = float(solo.total)
        rider = (
            f"**{_watts(total)} W**" if total > -0.5 else f"coasting (it would brake {-total:.0f} W to hold this speed)"
        )
        text = f"Air density **{rho:.3f} kg/m³** ({where})  \nSolo rider: {rider}, {share}"
        if yaw := yaw_words(p):
            text += f"  \n{wind_words(p).capitalize()}: {yaw}."
        return text

    def _table_markdown(self) -> str:
        state = self.state
        # Narrow columns run together in the panel ("RollClimb"), so the three parts share one cell with slashes.
        # The parts are at the wheel; the rider pedals their sum over the drivetrain's efficiency η.
        rows = [
            "| Rider | CdA (m²) | Aero / rolling / climbing at the wheel (W) | "
            f"Pedals (W, η {self.params.drivetrain_pct:g} %) | Saving |",
            "|---|---|---|---|---|",
        ]
        for i in range(self.params.n_riders):
            rows.append(
                f"| {i + 1} | {state.cda_m2[i]:.3f} | {_watts(state.power.aero[i])} / "
                f"{_watts(state.power.rolling[i])} / {_watts(state.power.climbing[i])} "
                f"| **{_watts(state.pedal_w[i])}** | {self._saving_text(i)} |"
            )
        coasting = coasting_words(state.brake_w, *self.push_cause())
        if coasting:  # the bars stand for what is spent, which the rider's 0 W is not
            payer, both = self.push_cause("gravity")
            solo = state.solo
            parts = [
                what
                for what, yes in (
                    ("the air", float(solo.aero) > 0.0),
                    ("the tyres", True),
                    ("the climb", float(solo.climbing) > 0.0),
                )
                if yes
            ]
            taken = " and ".join([", ".join(parts[:-1]), parts[-1]] if len(parts) > 1 else parts)
            coasting += f" The bars show what {taken} take, which {payer} {'pay' if both else 'pays'}."
        return "\n".join(rows) + (f"\n\n{coasting}" if coasting else "")

    def _saving_text(self, slot: int) -> str:
        """The Saving cell of a rider: its saving against the solo rider (%), or what it pedals more (a rider
        sheltered from a tailwind's push needs more than alone)."""
        state = self.state
        if state.pedals_more[slot]:
            extra = float(state.pedal_w[slot]) - state.solo_pedal_w
            return f"none ({extra:.1f} W more)" if extra < 1.0 else f"none ({extra:.0f} W more)"
        return f"{max(100.0 * float(state.saving[slot]), 0.0):.1f} %"  # never "-0.0 %"

    def _rotation_markdown(self) -> str:
        n = self.params.n_riders
        if n < 2:
            return ""
        mean = float(np.mean(self.state.pedal_w))
        lead = float(self.state.pedal_w[0])
        if self._rotation_width() == 0:
            return (
                f"In {'a bunch' if self.params.formation == 'bunch' else 'an echelon'} riders do not take turns in "
                f"order: the mean over its places is **{_watts(mean)} W** against the leader's {_watts(lead)} W."
            )
        hardest = float(np.max(self.state.pedal_w))
        if self.params.speed_kmh == 0.0:
            text = "Standing still, nobody pedals and nobody needs shelter."
        elif hardest < 0.5:
            payer, both = self.push_cause("gravity")
            text = (
                f"At this speed {payer} {'do' if both else 'does'} the work: nobody needs to pedal, so nobody needs "
                "shelter."
            )
        elif hardest >= lead + 0.5 and float(self.state.solo.aero) < 0.0:  # a tailwind faster than the riders
            leader = "The leader coasts" if lead < 0.5 else f"The leader pedals {lead:.0f} W"
            text = (
                f"{leader}: the tailwind pushes it along. The riders behind it are sheltered from that push too and "
                f"pedal up to {hardest:.0f} W, so the lead is the easy turn here."
            )
        elif self.params.n_riders <= self._rotation_width():
            text = (
                "The two ride side by side at the front: there is nobody to rotate with; "
                f"each pedals about {mean:.0f} W."
            )
        elif not self.params.drafting:
            text = (
                f"Drafting is off: every rider rides in clean air at the leader's {lead:.0f} W, "
                "so rotating saves nothing."
            )
        elif mean >= 0.995 * lead:
            text = (
                f"Nobody gains from shelter here{self._no_shelter_reason()}: every rider works about as hard as the "
                f"leader, {lead:.0f} W, or harder, so rotating saves nothing."
            )
        else:
            less = 100 * (1 - mean / lead)
            why = "the reason teams rotate" if less >= 5.0 else "little to gain from rotating here"
            text = (
                f"Rotating evenly, each rider averages **{mean:.0f} W** against the leader's {lead:.0f} W "
                f"({less:.0f} % less): {why}."
            )
        if self.params.rotate and self._ridden_s > 0:
            averages = self._energy_j[:n] / self._ridden_s
            if n <= MAX_RIDERS:
                text += "  \nTime-averaged so far: " + ", ".join(f"R{i + 1} {a:.0f} W" for i, a in enumerate(averages))
            else:
                text += f"  \nTime-averaged so far: {averages.min():.0f}–{averages.max():.0f} W across the {n} riders"
        return text

    def _no_shelter_reason(self) -> str:
        """Why no rider saves power behind another, in parentheses, the first that holds: no air drag or little of it
        (a tailwind as fast as the riders, a slow climb), a crosswind that takes the wakes aside; "" when none of
        these says it (a pair side by side is told so before it is asked)."""
        aero = float(self.state.solo.aero)
        if aero <= 0.0:
            return " (the tailwind is as fast as the riders or faster: there is no air drag to shelter from)"
        if aero < 0.05 * self.state.solo_spent_w:
            return " (there is little air drag to shelter from at this air speed)"
        if self.params.crosswind_ms != 0.0:
            return " (the crosswind takes the wakes to the side of the group)"
        return ""

    def _speed_markdown(self) -> str:
        p = self.params
        v = solo_speed(solo_key(p), p.target_power_w)
        text = (
            f"Riding alone, {p.target_power_w:.0f} W ({p.target_power_w / p.mass_kg:.2f} W/kg of system mass) "
            f"holds **{3.6 * v:.1f} km/h** here"
        )
        if v > 0.1:
            minutes, seconds = divmod(round(40_000.0 / v), 60)
            hours, minutes = divmod(minutes, 60)
            text += f": a 40 km time trial in {hours:d}:{minutes:02d}:{seconds:02d}"
        return text + "."

    # ----------------------------------------------------------------------------------------- animation
    def _animate(self, dt: float) -> bool:
        """One frame of the rotating lead; False (the loop sleeps) when the lead does not rotate."""
        if not self._rotating():
            return False
        dt = min(dt, 0.2)
        slots = self.current_slots()
        self._energy_j[: self.params.n_riders] += self.state.pedal_w[slots] * dt
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


def density_words(rho: float) -> str:
    """How air of density ``rho`` (kg/m³) compares with the sea level's: "sea level", or so many percent thinner
    (above it) or denser (below it, down to the Dead Sea's shore)."""
    change = 100.0 * (rho / cycling.RHO_SEA_LEVEL - 1.0)
    if abs(change) < 0.05:
        return "sea level"
    return f"{abs(change):.1f} % {'denser' if change > 0 else 'thinner'} than at sea level"
