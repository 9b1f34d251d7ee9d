"""The peloton's course mode: ride a real route (a GPX file or the bundled sample) in real air.

:class:`CourseMode` owns the mode's GUI folder and its nodes under ``/peloton/course_mode``: uploads, the power
solver and playback. What it rides and draws comes from :mod:`scenes.peloton.course_model` (no viser).
"""

from __future__ import annotations

import logging
import math
import threading
from typing import TYPE_CHECKING

import numpy as np
import viser
import viser.uplot

from kernels import course as course_kernel
from scenes._base import record_spec
from scenes._charts import FittedChart
from scenes._controls import build_controls, declared, read_controls
from scenes.peloton.course_model import (
    COURSE_MARKER_SCALE,
    COURSE_POWER_RANGE_W,
    MAX_CHART_POINTS,
    MAX_DRAWN_POINTS,
    MODE_FOLDER,
    MODEL_LABEL,
    MORE_FOLDER,
    POWER_FOLDER,
    SAMPLE_LABEL,
    TERRAIN_HALF_WIDTH_M,
    CourseDrawing,
    CourseParams,
    CourseState,
    compute_course,
    course_air,
    course_rider,
    drawn_indices,
    format_duration,
    grade_colours,
    ground_under,
    split_every_m,
    terrain_strip,
)
from scenes.peloton.meshes import add_riders, show_position
from scenes.peloton.model import BIKE_LENGTH_M, MAX_RIDERS, Position, group_cda

FORMATION_WORDS = {"single": "in single file", "double": "two abreast", "bunch": "in a bunch", "echelon": "in echelon"}
"""How the course readout names each formation."""

if TYPE_CHECKING:
    from scenes.peloton.scene import PelotonScene

logger = logging.getLogger(__name__)

RIDE_INPUTS = (
    "power_w",
    "model",
    "air",
    "temperature_c",
    "pressure_from_barometer",
    "pressure_hpa",
    "humidity_pct",
    "wind_ms",
    "wind_from_deg",
    "max_speed_kmh",
    "pacing",
    "pacing_gain_pct",
)
"""The course inputs that change the ride (the rest change only the view or the solver's target)."""
LINE_INPUTS = (
    "cda_m2",
    "mass_kg",
    "crr",
    "drivetrain_pct",
    "drafting",
    "formation",
    "n_riders",
    "gap_m",
    "model",
    "position",
)
"""The line's inputs that change the ride on the course (the paceline options apply there too)."""


class CourseMode:
    """The course mode of :class:`PelotonScene`: its GUI folder, its nodes under ``/peloton/course_mode``.

    Every input is cleaned as the gate cleans it (:func:`scenes._controls.read_controls`); a bad file leaves the
    last good course in place with a message saying why.
    """

    def __init__(self, scene: PelotonScene) -> None:
        self.scene = scene
        self.server = scene.server
        self.params = CourseParams()
        self.route = course_kernel.load_gpx(course_kernel.SAMPLE_ROUTE)
        self.route_label = SAMPLE_LABEL
        self.state: CourseState | None = None
        """Computed when the mode is first shown (the compiled ride loop loads then)."""
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
        with self.scene.gui_root:
            head = build_controls(gui, p, ("enabled",))
        with head.folders[MODE_FOLDER]:
            self.route_info = gui.add_markdown(self._route_markdown())
            self.sample = gui.add_button("Load the sample route")
            self.upload = gui.add_upload_button("Upload GPX", mime_type=".gpx,application/gpx+xml")
            self.play = gui.add_button("Play")
            self.pause = gui.add_button("Pause")
            # Hand-built, not a parameter: playback moves it, and its range is the loaded route's length.
            self.scrub = gui.add_slider("Position (km)", min=0.0, max=self._total_km(), step=0.01, initial_value=0.0)
            self.now = gui.add_markdown("")
            self.readout = gui.add_markdown("")
            self.chart = FittedChart(
                gui,
                data=self._chart_data(),
                series=(
                    viser.uplot.Series(label="Distance (km)"),
                    viser.uplot.Series(label="Elevation (m)", stroke="rgb(120,90,60)", width=2, scale="m"),
                    viser.uplot.Series(label="Speed (km/h)", stroke="rgb(30,110,220)", width=1.5, scale="kmh"),
                    viser.uplot.Series(label="Power (W)", stroke="rgb(220,40,40)", width=1.5, scale="W"),
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
                    viser.uplot.Axis(scale="kmh", label="km/h", side=1, grid=viser.uplot.Axis_Grid(show=False)),
                ),
                legend=viser.uplot.Legend(show=True),
                title="Elevation, speed and power along the course",
                aspect=1.4,
                visible=False,  # until the first ride: a profile over flat zeros reads as a rider not pedalling
            )
            power = build_controls(gui, p, ("power_w", "target_min"))
            with power.folders[POWER_FOLDER]:  # between the target and the model
                self.solve = gui.add_button("Find the power for this time")
            rest = build_controls(
                gui,
                p,
                [name for name in declared(CourseParams) if name not in {*head.fields, *power.fields}],
                collapsed=(MORE_FOLDER,),
                folders_open=power.folders,
            )
            with gui.add_folder("Splits", expand_by_default=False):
                self.splits = gui.add_markdown("")
        self.head = head
        """The "Ride a course" checkbox, read on its own (:meth:`_on_enable`)."""
        self.controls = head | power | rest
        """Every declared control of :class:`CourseParams`, by field name."""
        cb = self.scene.callback
        self.enable.on_update(cb(self._on_enable))
        self.sample.on_click(cb(self._on_sample))
        self.upload.on_upload(self._on_upload)  # parses off the lock, then installs through cb
        self.solve.on_click(cb(self._on_solve))
        self.play.on_click(cb(self._on_play))
        self.pause.on_click(cb(self._on_pause))
        self.scrub.on_update(cb(self._on_scrub))
        for name in RIDE_INPUTS:
            self.controls[name].on_update(cb(self._on_input))
        for name in ("exaggeration", "playback", "target_min"):
            self.controls[name].on_update(cb(self._on_view))
        line = self.scene.controls
        for name in LINE_INPUTS:
            line[name].on_update(cb(self._on_input))  # the paceline options apply on the course
        self.scene.crr_preset.on_update(cb(self._on_input))

    @property
    def enable(self) -> viser.GuiInputHandle[bool]:
        """The "Ride a course" checkbox."""
        return self.controls["enabled"]

    @property
    def enabled(self) -> bool:
        """Whether the mode is shown (the cleaned checkbox)."""
        return self.params.enabled

    # ----------------------------------------------------------------------------------------- world
    def _build_world(self) -> None:
        scene = self.server.scene
        self.frame = scene.add_frame(f"{self.scene.root.name}/course_mode", show_axes=False, visible=False)
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
        self.route_line = scene.add_line_segments(f"{self.frame.name}/route", segments, colors=colours, thickness=0.08)
        self.course_riders = add_riders(scene, f"{self.frame.name}/riders", self.scene.params.position, 0.0)
        self._drawn_position = self.scene.params.position
        self.leader_marker = scene.add_icosphere(
            f"{self.frame.name}/leader_marker",
            radius=0.12,
            color=(255, 60, 60),
            position=(0.0, 0.0, 1.0),
        )
        self.start_label = scene.add_label(f"{self.frame.name}/start", text="Start", position=tuple(points[0]))
        self.finish_label = scene.add_label(f"{self.frame.name}/finish", text="Finish", position=tuple(points[-1]))

    def _route_segments(self, index: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        segments = np.stack([points[:-1], points[1:]], axis=1) + [0.0, 0.0, 0.02]
        rise = np.diff(self.route.elevation_m[index])
        run = np.maximum(np.diff(self.route.distance_m[index]), 1e-9)
        colours = grade_colours(rise / run)
        return segments.astype(np.float32), np.repeat(colours[:, None, :], 2, axis=1)

    # ----------------------------------------------------------------------------------------- inputs
    def read_params(self) -> CourseParams:
        """The course inputs, cleaned: anything non-finite, out of range or unknown keeps the last good value."""
        return read_controls(self.controls, self.params, write_back=self.scene.write_back)

    def _on_enable(self) -> None:
        self.params = read_controls(self.head, self.params, write_back=self.scene.write_back)
        if self.enabled and self.state is None:
            self.recompute()
        self.redraw()
        self.scene.wake_loops()

    def _on_input(self) -> None:
        if not self.enabled:  # the line's sliders move often: ride the course only while it is shown
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
                f"**{_escape(label)}** was not loaded: {_escape(reason)}. Still showing **{_escape(self.route.name)}**."
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
        rider = course_rider(line, params, group_cda(line))
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
                    self.route,
                    target_s,
                    rider,
                    params.wind_ms,
                    params.wind_from_deg,
                    air,
                    max_speed_ms=cap,
                    tolerance_s=0.05,
                )
            except ValueError as error:
                self.message = f"Could not find the power for {wanted}: {_escape(str(error))}"
                self.redraw()
                return
            note = ""
        self.scene.write_back(self.controls["power_w"], float(np.clip(round(power, 1), low, high)))
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
        """(n,) distance along the route of each drawn rider, leader first (spaced as drawn): the first
        :data:`MAX_RIDERS` of the group (the course's scale draws a bunch as the line at its head)."""
        n, gap = min(self.scene.params.n_riders, MAX_RIDERS), self.scene.params.gap_m
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
                show_position(self.course_riders, s.params.position)
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
        n = min(self.scene.params.n_riders, MAX_RIDERS)
        positions = np.zeros((MAX_RIDERS, 3))
        wxyz = np.tile([1.0, 0.0, 0.0, 0.0], (MAX_RIDERS, 1))
        where, yaw = self._drawing.at_distance(self.route, self.rider_distances_m(), self.params.exaggeration)
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
        if self.state is None:  # before the first ride: the profile, and zeros (never a NaN-only series)
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
                f"  \n{line.n_riders} riders {FORMATION_WORDS[line.formation]} sharing the work, each at the "
                f"formation's mean drag (CdA {state.group_cda_m2:.3f} m²): "
                f"alone the same power takes {format_duration(state.solo.time_s)}"
            )
        if state.pacing is not None:
            saved = state.pacing.time_saved_s
            text += (
                f"  \nPacing by grade (±{p.pacing_gain_pct:.0f} %): {format_duration(state.constant.time_s)} at constant "
                f"power → {format_duration(ride.time_s)}, **{saved:.0f} s {'saved' if saved >= 0 else 'lost'}** at the same average power"
            )
        which = "the weather's air" if p.air == "weather" else "the exponential atmosphere"
        text += (
            f"  \nAir at the start ({state.route.elevation_m[0]:.0f} m): exponential atmosphere **{state.density_seed:.3f}** kg/m³, "
            f"weather **{state.density_weather:.3f}** kg/m³; riding in {which}"
        )
        if ride.brakes_j > 0.0:
            text += f"  \nBraking to hold {p.max_speed_kmh:.0f} km/h took {ride.brakes_j / 1000:.0f} kJ"
        return text

    def _splits_markdown(self) -> str:
        if self.state is None:
            return ""
        ride = self.state.ride
        every = split_every_m(float(ride.distance_m[-1]))
        marks, times = ride.splits(every)
        rows = ["| km | elapsed | split | km/h |", "|---:|---:|---:|---:|"]
        previous_mark, previous_time = 0.0, 0.0
        shown = np.unique(np.linspace(0, marks.shape[0] - 1, min(marks.shape[0], 20)).round().astype(int))
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
        text.replace("&", "&amp;")
        .replace("<", "&lt;")
        .replace(">", "&gt;")
        .replace("[", "&#91;")
        .replace("]", "&#93;")
        .replace("*", "&#42;")
        .replace("|", "&#124;")
    )
