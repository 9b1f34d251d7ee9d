"""The peloton's course mode: ride a real route (a GPX file or the bundled sample) in real air.

:class:`CourseMode` owns the mode's GUI folder and its nodes under ``/peloton/course_mode``: uploads, the power
solver and playback. What it rides and draws comes from :mod:`scenes.peloton.course_model` (no viser).
"""

from __future__ import annotations

import dataclasses
import logging
import math
import re
import threading
import time
import unicodedata
from typing import TYPE_CHECKING

import numpy as np
import viser
import viser.uplot

from kernels import course as course_kernel
from scenes._base import set_if_changed
from scenes._charts import FittedChart, number_scales
from scenes._controls import build_controls, declared, read_controls
from scenes._framing import Lens, View, frame_clear_of_notice
from scenes._instances import park_hidden
from scenes._look import add_ground, mesh_glb
from scenes._numbers import signed
from scenes.peloton.course_model import (
    COURSE_POWER_DECIMALS,
    COURSE_POWER_RANGE_W,
    GROUP_VIEW_DIRECTION,
    LINE_VIEW_DIRECTION,
    MAX_CHART_POINTS,
    MODE_FOLDER,
    MODEL_LABEL,
    MORE_FOLDER,
    POWER_FOLDER,
    SAMPLE_LABEL,
    CourseParams,
    CourseState,
    RoadLayout,
    compute_course,
    course_air,
    course_rider,
    drawn_indices,
    format_duration,
    framed_front,
    framed_words,
    lay_out_road,
    place_powers,
    position_end_km,
    position_km,
    position_m,
    rider_boxes,
    split_every_m,
    time_saved_words,
)
from scenes.peloton.legend import formation_table, legend_html, power_colours, power_range, riders_text
from scenes.peloton.meshes import (
    GRASS_COLOUR,
    ROAD_COLOUR,
    Detail,
    add_riders,
    rider_detail,
    rider_head_m,
    show_position,
)
from scenes.peloton.model import BIKE_LENGTH_M, MAX_GROUP, PelotonParams, Position, group_cda, is_line_view

CHART_TITLE = "Elevation, speed and power"
"""The course chart's title (short: the panel is narrow)."""
ROAD_SHOWN_M = {True: (3.0, 0.0), False: (10.0, 4.0)}
"""Road the camera frames ahead of the leader and behind the last framed rider (m), the road's full width, for a line
seen from its side (True) and a group seen from behind (False): a small group is seen on its road, not from a metre
away (two abreast of 8 stood 37 % of the window tall)."""
MARK_COLOUR = (250, 250, 250)
"""The start and finish lines' paint."""
MARK_LABEL_M = 0.02
"""Height of the "Start" and "Finish" labels over the lines' right end (m): on the road's edge on the riders' right,
the side the chase camera looks from, below the riders rather than over a head, and at the line however close the
camera comes (0.3 m stood 80 px over it for one rider)."""
_UNIT_BAND = (
    np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]]),
    np.array([[0, 1, 3], [0, 3, 2]]),
)
"""A placeholder quad for a line's node until a layout places it."""
BACKDROP_HALF_M = 2000.0
"""Half the side of the flat grass under course mode's road window (m): to the horizon at every camera distance."""
BACKDROP_DROP_M = 1.0
"""How far under the lowest point of the drawn verge the flat grass lies (m)."""
RIDER_HALF_M = (0.5 * BIKE_LENGTH_M, 0.3)
"""Half a rider's box (m): along the bike and across the handlebars."""
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
LINE_INPUTS = ("cda_m2", "mass_kg", "crr", "drivetrain_pct", "drafting", "formation", "n_riders", "gap_m", "model")
"""The line's inputs that change the ride on the course (the paceline options apply there too; so do its preset
menus, which set the CdA and Crr)."""
FLAT_ROAD_ONLY = ("speed_kmh", "rotate", "turn_s")
"""The flat road's inputs that the course does not use, hidden while it is ridden."""
FLAT_ROAD_FOLDERS = ("Course", "Speed at a power")
"""The flat road's folders that the course does not use (grade, altitude, head- and crosswind; the speed at a
power), hidden while it is ridden."""


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
        """Why the last file was not loaded, in the panel (Markdown); empty once one is."""
        self.refusal = ""
        """The same, as plain text, for the notification to the tab that uploaded it."""
        self._ridden: tuple[object, ...] | None = None
        """The route and the inputs the shown ride was ridden with (:data:`RIDE_INPUTS`, :data:`LINE_INPUTS`)."""
        self.solve_note: tuple[tuple[object, ...], str] | None = None
        """What the last 'Find the power' said (a target outside the power input's range, or why no power was found)
        and the ride and target it said it of (:meth:`_solve_key`): shown under the button while they are."""
        self._since_readout = 0.0
        self._drawn_riders: tuple[Position, Detail] | None = None
        """The riding position and mesh detail the riders were last meshed for."""
        self._upload_lock = threading.Lock()
        self._upload_seq = 0
        """Number of the newest upload: parses run in parallel on viser's pool, and only the newest installs."""
        self._chosen_at = 0.0
        """When (``time.monotonic()``) a route was last loaded by :meth:`load` (the sample button): a file picked
        before that and still arriving then is not the user's last choice, and is dropped."""
        self.refusal_notices: list[viser.NotificationHandle] = []
        """The "GPX not loaded" notifications still up: the next route loaded, or refused, takes them down, so
        none is left saying "Still showing" a route that is no longer shown."""
        self._build_gui()
        self._show_air_inputs(self.params)
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
            # Its range is the loaded route's length; playback moves it too.
            place = build_controls(gui, p, ("position_km",))
            place = place.with_range("position_km", 0.0, self._total_km())
            scrub = place["position_km"]
            assert isinstance(scrub, viser.GuiSliderHandle)
            self.scrub = scrub
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
                scales=number_scales("m", "kmh", "W"),
                # Three y axes share a panel-wide chart: each axis is coloured as its series and the units are in
                # the legend's names, so no axis spends width on a unit label (with them the plot was 104 px wide).
                axes=(
                    viser.uplot.Axis(scale="x", label="km", labelSize=16),
                    viser.uplot.Axis(scale="m", side=3, size=28, labelSize=0, stroke="rgb(120,90,60)"),
                    _right_axis("kmh", 28, "rgb(30,110,220)"),
                    _right_axis("W", 28, "rgb(220,40,40)"),
                ),
                legend=viser.uplot.Legend(show=True),
                title=CHART_TITLE,
                aspect=1.4,
                visible=False,  # until the first ride: a profile over flat zeros reads as a rider not pedalling
            )
            power = build_controls(gui, p, ("power_w", "target_min"))
            with power.folders[POWER_FOLDER]:  # between the target and the model
                self.solve = gui.add_button("Find the power for this time")
                self.solve_info = gui.add_markdown("", visible=False)
                """Under the button, where the eye is after a click: why the power found is an input's end."""
            rest = build_controls(
                gui,
                p,
                [name for name in declared(CourseParams) if name not in {*head.fields, *place.fields, *power.fields}],
                collapsed=(MORE_FOLDER,),
                folders_open=power.folders,
            )
            with gui.add_folder("Splits", expand_by_default=False):
                self.splits = gui.add_markdown("")
        self.head = head
        """The "Ride a course" checkbox, read on its own (:meth:`_on_enable`)."""
        self.controls = head | place | power | rest
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
        for menu in self.scene.presets.values():  # a preset writes its field's control without running its callbacks
            menu.on_update(cb(self._on_input))

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
        layout = self.layout()
        name = self.frame.name
        # Grass to the horizon under the whole drawn window (the verge follows the road; beyond it the view showed
        # the sky through the inside of a hairpin): lower than every drawn point, so it never covers the road.
        half = BACKDROP_HALF_M
        self.backdrop = add_ground(
            scene,
            f"{name}/backdrop",
            np.array([[-half, -half, 0.0], [half, -half, 0.0], [half, half, 0.0], [-half, half, 0.0]]),
            np.array([[0, 1, 2], [0, 2, 3]]),
            GRASS_COLOUR,
        )
        self.verge = add_ground(scene, f"{name}/verge", *layout.verge, GRASS_COLOUR)
        self.road = add_ground(scene, f"{name}/route", *layout.road, ROAD_COLOUR)  # the route's road
        self.road_edges = scene.add_line_segments(
            f"{name}/road_edges", layout.edges, colors=(250, 250, 250), thickness=0.06
        )
        self.centre_line = scene.add_line_segments(
            f"{name}/centre_line", layout.dashes, colors=(240, 240, 240), thickness=0.08
        )
        self.course_riders = add_riders(scene, f"{name}/riders", self.scene.params.position, 0.0, MAX_GROUP)
        self._drawn_riders = (self.scene.params.position, "full")
        self.mark_lines = {
            mark: add_ground(scene, f"{name}/{mark.lower()}_line", *_UNIT_BAND, MARK_COLOUR, visible=False)
            for mark in layout.marks
        }
        self.mark_labels = {
            mark: scene.add_label(f"{name}/{mark.lower()}", text=mark, position=(0.0, 0.0, 0.0))
            for mark in layout.marks
        }
        self._draw_layout(layout)

    def formation_xy(self) -> np.ndarray:
        """(n, 2) the group's formation (m ahead of the leader, m to its left), leader first, as the line lays it
        out."""
        return np.asarray(self.scene.state.positions, dtype=np.float64)[: self.scene.params.n_riders]

    def layout(self) -> RoadLayout:
        """The road near the group and the group on it, where the leader is now."""
        return lay_out_road(self.route, self.leader_distance_m(), self.formation_xy(), self.params.exaggeration)

    def view_for(self, lens: Lens) -> View:
        """The camera for ``lens`` that shows the group on its road left of the panel and clear of viser's
        software-WebGL notice, as large as it fits: every framed rider's box, wheels to head, and the road's width
        from a little behind the last framed rider to a little ahead of the leader (:data:`ROAD_SHOWN_M`). A group
        longer than :data:`FRAMED_LENGTH_M` has its front framed (:meth:`framed_riders`)."""
        with self.scene.state_lock:
            points = self.framed_points()
            direction = LINE_VIEW_DIRECTION if is_line_view(self.scene.params) else GROUP_VIEW_DIRECTION
        return frame_clear_of_notice(points, direction, lens)

    def framed_riders(self) -> int:
        """How many riders, from the leader back, the camera frames: those within :data:`FRAMED_LENGTH_M` of it."""
        xy = self.formation_xy()
        return int(np.count_nonzero(framed_front(xy)))

    def framed_points(self) -> np.ndarray:
        """(k, 3) scene points the camera frames: each framed rider's box corners (turned and pitched as drawn) and
        the road's edges where :data:`ROAD_SHOWN_M` says."""
        layout = self.layout()
        n = self.framed_riders()
        positions, wxyz = layout.riders
        boxes = rider_boxes(positions[:n], wxyz[:n], rider_head_m(self.scene.params.position)[1], RIDER_HALF_M)
        xy = self.formation_xy()[:n]
        leader = self.leader_distance_m()
        ahead, behind = ROAD_SHOWN_M[is_line_view(self.scene.params)]
        d_from, d_to = layout.window_m
        vertices = layout.road[0].astype(np.float64)
        k = vertices.shape[0] // 2
        distance = np.linspace(d_from, d_to, k)
        near = (distance >= leader + float(xy[:, 0].min()) - behind) & (distance <= leader + ahead)
        road = np.vstack([vertices[:k][near], vertices[k:][near]])
        return np.vstack([boxes, road])

    # ----------------------------------------------------------------------------------------- inputs
    def read_params(self) -> CourseParams:
        """The course inputs, cleaned: anything non-finite, out of range or unknown keeps the last good value."""
        return read_controls(self.controls, self.params, write_back=self.scene.write_back)

    def _show_flat_road_inputs(self) -> None:
        """Hide the flat road's inputs that the course does not use while the course is ridden (its speed, grade,
        altitude, head- and crosswind, the rotation and the speed at a power: the course rides at a power, on its
        own grades and in its own air), and show them again on the flat road."""
        flat = not self.enabled
        controls = self.scene.controls
        for name in FLAT_ROAD_ONLY:
            set_if_changed(controls[name], "visible", flat)
        for folder in FLAT_ROAD_FOLDERS:
            set_if_changed(controls.folders[folder], "visible", flat)

    def _on_enable(self) -> None:
        was = self.enabled
        self.params = read_controls(self.head, self.params, write_back=self.scene.write_back)
        self._show_flat_road_inputs()
        if self.enabled and self.state is None:
            self.recompute()
        self.redraw()
        if not self.enabled:
            self.scene.redraw()  # the flat road's legend, table and readouts again
        if self.enabled != was:
            self.scene.framing.reframe()  # the course's group on its road, or the line again
        self.scene.wake_loops()

    def _show_air_inputs(self, p: CourseParams) -> None:
        """Show only the air inputs that the chosen air uses: a weather reading's temperature, pressure source and
        humidity, and the pressure itself only when it is read from a barometer (the textbook atmosphere uses
        none of them; the standard atmosphere gives the pressure)."""
        weather = p.air == "weather"
        for name in ("temperature_c", "pressure_from_barometer", "humidity_pct"):
            set_if_changed(self.controls[name], "visible", weather)
        set_if_changed(self.controls["pressure_hpa"], "visible", weather and p.pressure_from_barometer)

    def _on_input(self, solve_note: str = "") -> None:
        """Ride again with every input as it is now; ``solve_note``, what a 'Find the power' says of this ride."""
        self._show_air_inputs(self.read_params())
        if not self.enabled:  # the line's sliders move often: ride the course only while it is shown
            self.state = None
            return
        self.recompute()
        if solve_note:
            self.solve_note = (self._solve_key(), solve_note)
        self.redraw()

    def _solve_key(self) -> tuple[object, ...]:
        """What a 'Find the power' note speaks of: the shown ride's route and inputs, and the target time."""
        return (self._ridden, self.params.target_min)

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
        # The riders stay where they are on the course (the Position slider's place), not at the same time of a
        # ride that is now faster or slower: else the readout and the slider part (5.57 km against 5.5).
        at_m = self.leader_distance_m() if self.state is not None else self._scrub_m()
        self.params, self.state = params, state
        self._ridden = _ride_inputs(self.route, params, line)
        self.message = ""
        self.play_time_s = float(np.interp(at_m, state.ride.distance_m, state.ride.elapsed_s))
        if self.enabled and self.playing:  # a ride that had none to play now has one
            self.scene.wake_loops()

    def _on_sample(self) -> None:
        self.load(course_kernel.SAMPLE_ROUTE.read_bytes(), SAMPLE_LABEL)

    def _on_upload(self, event: object = None) -> None:
        """An upload arrived (viser's thread pool). Parse it off the scene's lock, since gpxpy needs seconds for a
        large file, then install it (or the reason it failed) as a guarded callback. Nothing escapes.

        A refused file is also told to the tab that sent it, in a notification that takes the place of viser's own
        "File uploaded successfully" (:meth:`_tell_not_loaded`)."""
        client = getattr(event, "client", None)
        finished = self.server.finished_upload(event)
        upload_notice = None if finished is None else finished.notice_id
        # The number and the file are taken together: a higher number is a newer file.
        with self._upload_lock:
            picked_before_a_later_choice = finished is not None and finished.started_at < self._chosen_at
            if not picked_before_a_later_choice:
                self._upload_seq += 1
            seq, arrived_at = self._upload_seq, time.monotonic()
            uploaded = self.upload.value
        if picked_before_a_later_choice:
            self.scene.callback(lambda: self._tell_superseded(client, upload_notice, uploaded, "arriving"))(None)
            return
        try:
            name = str(getattr(uploaded, "name", "") or "upload")[:80]
            content = getattr(uploaded, "content", b"")
            route, error = None, None
            if not isinstance(content, bytes):
                error = "the upload carried no file"
            else:
                try:
                    route = course_kernel.load_gpx(content, file_name=name)
                except ValueError as failure:
                    error = str(failure)
        except Exception:  # a file must never take the scene down; say so and keep the course
            logger.exception("peloton: reading an uploaded GPX failed")
            name, route, error = "upload", None, "the file could not be read"

        installed = False

        def install() -> None:
            nonlocal installed
            installed = True
            with self._upload_lock:
                superseded, chosen_since = seq != self._upload_seq, self._chosen_at > arrived_at
            if superseded:  # a later choice of route, or a newer upload, came while this one was read: it wins
                if chosen_since:  # the newer upload says what became of it itself
                    self._tell_superseded(client, upload_notice, uploaded, "being read")
                return
            if not self._install(route, error, name):
                body = self.refusal if len(self.refusal) <= 500 else self.refusal[:499] + "…"
                self._tell_not_loaded(client, upload_notice, body)

        self.scene.callback(install)(None)
        if not installed and self.scene.closed:  # a Reset or a scene switch came while it was read
            self._tell_left(client, upload_notice, name)

    def _tell_left(self, client: object, upload_notice: str | None, name: str) -> None:
        """Tell the tab that file ``name`` was still being read when this scene closed (a Reset or a scene switch),
        in place of viser's "File uploaded successfully": the closed scene cannot show it, so it stands over the
        next one for its 15 s."""
        if not isinstance(client, viser.ClientHandle):
            return
        if upload_notice is not None:
            self.server.remove_upload_notice(upload_notice)
        body = (
            f"{name} was still being read when the scene was reset or switched, so it was not loaded. "
            "Upload it again to ride it."
        )
        client.add_notification("GPX not loaded", body, color="red", auto_close_seconds=15.0)

    def _tell_superseded(self, client: object, upload_notice: str | None, uploaded: object, stage: str) -> None:
        """Tell the tab that file ``uploaded`` was still ``stage`` ("arriving", "being read") when a later choice of
        route was made, which stays."""
        name = str(getattr(uploaded, "name", "") or "The file")[:80]
        body = (
            f"{name} was still {stage} when you chose {self.route.name}, which stays. Upload {name} again to ride it."
        )
        self._tell_not_loaded(client, upload_notice, body)

    def _tell_not_loaded(self, client: object, upload_notice: str | None, body: str) -> None:
        """Tell the tab that uploaded a file why it was not loaded, in place of viser's own "File uploaded
        successfully" (notice ``upload_notice``), which would contradict it."""
        if not isinstance(client, viser.ClientHandle):
            return
        if upload_notice is not None:
            self.server.remove_upload_notice(upload_notice)
        self.refusal_notices.append(self.scene.notify(client, "GPX not loaded", body, color="red"))

    def load(self, data: bytes, label: str) -> bool:
        """Load a GPX file's bytes as the course; on a bad file keep the last good course and show why. An upload
        still being read, or still arriving, is dropped: the user's last choice of route wins (:meth:`_on_upload`)."""
        with self._upload_lock:
            self._upload_seq += 1
            self._chosen_at = time.monotonic()
        try:
            route, error = course_kernel.load_gpx(data, file_name=label), None
        except ValueError as failure:
            route, error = None, str(failure)
        return self._install(route, error, label)

    def _install(self, route: course_kernel.Course | None, error: str | None, label: str) -> bool:
        for notice in self.refusal_notices:  # each said what was shown then; this load changes that
            self.scene.take_down(notice)
        self.refusal_notices.clear()
        state, params, line = None, self.read_params(), self.scene.read_params()
        if route is not None:
            try:
                state = compute_course(route, params, line)
            except ValueError as failure:
                error = str(failure)
        if route is None or state is None:
            # The file is named already: "x.gpx was not loaded: it is not a valid GPX file", not "the file is".
            reason = re.sub(r"^the file(: | )", lambda m: "" if m.group(1) == ": " else "it ", str(error))
            self.refusal = f"{label} was not loaded: {reason}. Still showing {self.route.name}."
            self.message = (
                f"**{_escape(label)}** was not loaded: {_escape(reason)}. Still showing **{_escape(self.route.name)}**."
            )
            self.redraw()
            return False
        self.route, self.route_label, self.state = route, label, state
        self.params, self._ridden = params, _ride_inputs(route, params, line)
        self.message = ""
        self.play_time_s = 0.0
        self.playing = False
        # The gate clamps a browser's scrub to the new course's length, not the first one's.
        self.controls = self.controls.with_range("position_km", 0.0, self._total_km())
        self._put_position(0.0)  # the riders are back at the start
        self.redraw()
        return True

    def _on_solve(self) -> None:
        params = self.read_params()
        line = self.scene.read_params()
        air = course_air(self.route, params)
        rider = course_rider(line, params, group_cda(line))
        target_s, cap = params.target_min * 60.0, params.max_speed_kmh / 3.6
        low, high = COURSE_POWER_RANGE_W
        # The finish shown is the paced ride's when pacing is on: the power is found for that one.
        gain = params.pacing_gain_pct / 100.0 if params.pacing else 0.0

        def finish_at(power_w: float) -> float:
            conditions = (params.wind_ms, params.wind_from_deg, air, cap)
            try:
                if gain:
                    return course_kernel.paced_ride(self.route, power_w, rider, gain, *conditions).paced.time_s
                return course_kernel.ride(self.route, power_w, rider, *conditions).time_s
            except ValueError:  # too little power to cross a wall: never finishes
                return math.inf

        fastest, slowest = finish_at(high), finish_at(low)
        wanted = f"{params.target_min:g} min"
        floor_s = course_kernel.fastest_time_s(self.route, cap)  # the safe speed all the way: no power beats it
        if target_s < fastest:
            power = high
            needs = f"needs more than {high:.0f} W, the most this input takes"
            if target_s <= floor_s:
                needs = (
                    f"is out of reach: held to the {params.max_speed_kmh:.0f} km/h safe speed, no power rides these "
                    f"{floor_s * cap / 1000:.1f} km in under {format_duration(floor_s)}"
                )
            note = f"A {wanted} finish {needs}: set to {high:.0f} W, which finishes in {format_duration(fastest)}."
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
                    gain=gain,
                )
            except ValueError as error:
                reason = f"Could not find the power for {wanted}: {_escape(str(error))}"
                self.solve_note = (self._solve_key(), reason)
                self.redraw()
                return
            note = ""
        if not note:  # as few digits as put the finish within half a second of the target (a readout's second)
            for digits in range(1, COURSE_POWER_DECIMALS + 1):
                rounded = round(power, digits)
                if abs(finish_at(rounded) - target_s) < 0.5:
                    break
            power = rounded
        self.scene.write_back(self.controls["power_w"], power)
        # Shown under the button (it stood at the top of the folder, scrolled out of view by the time the button is
        # reached) while this ride is: its finish time is the one the note gives.
        self._on_input(solve_note=note)

    def _on_play(self) -> None:
        if self.state is None:
            return
        if self.play_time_s >= self.state.ride.time_s:
            self.play_time_s = 0.0
        self.playing = True
        self.scene.wake_loops()

    def _on_pause(self) -> None:
        self.playing = False
        self._show_at_km(round(self._leader_km(), 2))  # where the riders stopped, to the slider's step
        self.redraw(readouts=False)
        self.scene.framing.reframe()  # framed for the road where they stopped

    def _put_position(self, km: float) -> None:
        """Put the Position slider and ``params.position_km`` at ``km`` (playback, a new route, a pause)."""
        self.params = dataclasses.replace(self.params, position_km=km)
        self.scene.write_back(self.scrub, km)

    def _show_at_km(self, km: float) -> None:
        """Put the Position slider and the riders at ``km`` together (the readout then says the same place)."""
        self._put_position(km)
        if self.state is not None:
            ride = self.state.ride
            self.play_time_s = float(np.interp(self._km_to_m(km), ride.distance_m, ride.elapsed_s))

    def _km_to_m(self, km: float) -> float:
        """Where the Position slider at ``km`` puts the leader (m): its end is the finish."""
        return position_m(km, self.route.total_distance_m)

    def _scrub_m(self) -> float:
        """Where the Position slider puts the riders (m)."""
        return self._km_to_m(self.params.position_km)

    def _on_scrub(self) -> None:
        if self.state is None:
            return
        # Only the position is taken here: every other input is applied by its own callback.
        km = self.read_params().position_km
        self.params = dataclasses.replace(self.params, position_km=km)
        ride = self.state.ride
        self.play_time_s = float(np.interp(self._km_to_m(km), ride.distance_m, ride.elapsed_s))
        self.redraw(readouts=False)
        # The group keeps its place in the picture as the road under it bends and steepens.
        self.scene.framing.reframe()

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
            self._put_position(round(self._leader_km(), 2))
            self.redraw(readouts=False, now=True)
        else:
            self.redraw(readouts=False, now=False)
        return True

    # ----------------------------------------------------------------------------------------- drawing
    def _total_km(self) -> float:
        """The Position slider's end, the finish, and the length the summary gives (:func:`position_end_km`)."""
        return position_end_km(self.route.total_distance_m)

    def leader_distance_m(self) -> float:
        if self.state is None:
            return 0.0
        ride = self.state.ride
        return float(np.interp(self.play_time_s, ride.elapsed_s, ride.distance_m))

    def _leader_km(self) -> float:
        """Where the leader is as the Position slider gives it (km, on its 10 m step; its end at the finish)."""
        return position_km(self.leader_distance_m(), self.route.total_distance_m)

    def redraw(self, *, readouts: bool = True, now: bool = True) -> None:
        """Show or hide the mode and push its state: the road and riders always, the readouts when asked."""
        s = self.scene
        with self.server.atomic():
            s.course.visible = not self.enabled
            if self.enabled:
                s.wind_arrow.visible = s.wind_label.visible = False
            self.frame.visible = self.enabled
            riders = (s.params.position, rider_detail(s.params.n_riders))
            if riders != self._drawn_riders:
                show_position(self.course_riders, *riders)
                self._drawn_riders = riders
            if self.enabled:
                self._draw_layout(self.layout())
                if now or readouts:
                    self._show_places(readouts=readouts)
            if now:
                self.now.content = self._now_markdown()
            if readouts:
                self.route_info.content = self._route_markdown()
                self.readout.content = self._readout_markdown()
                note = self._solve_note_markdown()
                set_if_changed(self.solve_info, "content", note)
                set_if_changed(self.solve_info, "visible", bool(note))
                self.splits.content = self._splits_markdown()
                self.chart.data = self._chart_data()
                self.chart.visible = self.state is not None
        self.server.flush()

    def place_watts(self) -> tuple[np.ndarray, np.ndarray]:
        """(n,) each place's power where the leader is now and (n,) its mean over the ride (W), leader first
        (:func:`~scenes.peloton.course_model.place_powers`); zeros before the first ride."""
        n = self.scene.params.n_riders
        if self.state is None or self.state.drag.shape[0] != n:
            return np.zeros(n), np.zeros(n)
        return place_powers(self.state, self.leader_distance_m())

    def _show_places(self, *, readouts: bool) -> None:
        """Colour each rider by its place's power where the group is now, with the key in watts at the top of the
        panel; with ``readouts``, the Results table of the course's places and the words on how the group shares the
        work."""
        s, state = self.scene, self.state
        n = s.params.n_riders
        if state is None or state.drag.shape[0] != n:  # no ride yet, or the last good one is of another group
            return
        here, mean = self.place_watts()
        low, high = power_range(here)
        bodies = np.asarray(self.course_riders["body"].batched_colors).copy()
        bodies[:n] = power_colours(here, low, high)
        set_if_changed(self.course_riders["body"], "batched_colors", bodies)
        drag = state.drag
        summary = (
            f"Power of each place where the group is now ({self._leader_km():.2f} km): {riders_text(n)}, mean drag "
            f"{100 * float(np.mean(drag)):.0f} % of a lone rider's"
        )
        set_if_changed(s.legend, "content", legend_html(here, summary, "Rider colour = power here (W)"))
        set_if_changed(s.legend, "visible", True)
        table = formation_table(
            s.state.positions,
            drag,
            {"Here": here, "Ride mean": mean},
            f"Each place's drag (% of a lone rider's) and power (W) at **{self._leader_km():.2f} km** and over the "
            "whole ride",
        )
        set_if_changed(s.table, "content", table)
        if not readouts:
            return
        shown = framed_words(self.formation_xy())
        s.density.content = (
            f"**On the course.** The group rides at the mean drag of its formation, "
            f"**{100 * float(np.mean(drag)):.0f} %** of a lone rider's (CdA {state.group_cda_m2:.3f} m²): the speed at "
            f"which its places' powers average the course power. Each rider's colour is its place's power; a rider "
            f"who moves through the places over a long ride (a rotating line, or the slow churn of a bunch) averages "
            f"the course power.{shown}"
        )
        s.rotation.content = ""
        s.chart.visible = False  # the flat road's solo curve: the course's own chart is in its folder

    def _draw_layout(self, layout: RoadLayout) -> None:
        """Push a layout to the road's and riders' nodes."""
        for node, (vertices, faces), colour in (
            (self.road, layout.road, ROAD_COLOUR),
            (self.verge, layout.verge, GRASS_COLOUR),
        ):
            node.glb_data = mesh_glb(vertices, faces, color=colour, unlit=True)
        self.backdrop.position = (0.0, 0.0, float(layout.verge[0][:, 2].min()) - BACKDROP_DROP_M)
        self.road_edges.points = layout.edges
        self.centre_line.points = layout.dashes
        for mark, band in layout.marks.items():
            line, label = self.mark_lines[mark], self.mark_labels[mark]
            line.visible = label.visible = band is not None
            if band is not None:
                vertices, faces = band
                line.glb_data = mesh_glb(vertices, faces, color=MARK_COLOUR, unlit=True)
                label.position = vertices[2:].mean(axis=0) + np.array([0.0, 0.0, MARK_LABEL_M])
        positions, wxyz = layout.riders
        n = positions.shape[0]
        all_positions = np.zeros((MAX_GROUP, 3), np.float32)
        all_positions[:n] = positions
        all_wxyz = np.tile(np.array([1.0, 0.0, 0.0, 0.0], np.float32), (MAX_GROUP, 1))
        all_wxyz[:n] = wxyz
        scales = np.zeros((MAX_GROUP, 3), np.float32)
        scales[:n] = 1.0
        all_positions = park_hidden(all_positions, scales)
        for node in self.course_riders.values():
            node.batched_positions = all_positions
            node.batched_wxyzs = all_wxyz
            node.batched_scales = scales

    def _chart_data(self) -> tuple[np.ndarray, ...]:
        route = self.route
        index = drawn_indices(route.n_points, MAX_CHART_POINTS)
        km = route.distance_m[index] / 1000.0
        elevation = route.elevation_m[index]
        if self.state is None:  # before the first ride: the profile, and zeros (never a NaN-only series)
            zeros = np.zeros_like(km)
            return km, elevation, zeros, zeros
        ride = self.state.ride
        # Whole watts: the power axis then ticks whole numbers, and its labels take no room for decimals.
        return km, elevation, 3.6 * ride.speed_ms[index], np.round(ride.power_w[index])

    def _route_markdown(self) -> str:
        r = self.route
        average = 100.0 * (r.elevation_m[-1] - r.elevation_m[0]) / r.total_distance_m
        slope = signed(average, 1)  # a loop's tiny difference read "-0.0 %"
        text = (
            f"**{_escape(r.name)}**: {self._total_km():.2f} km, +{r.climbing_m:.0f} m, "
            f"{r.elevation_m[0]:.0f} → {r.elevation_m[-1]:.0f} m ({slope} % on average), {r.n_points} points"
        )
        if self.route_label == SAMPLE_LABEL:
            text += (
                "  \n*Sample route, built from Alpe d'Huez's published climb profile (13.2 km, 744 → 1815 m, "
                "8.1 %); its plan shape is schematic.*"
            )
        if self.message:
            text += f"  \n⚠️ {self.message}"
        return text

    def _solve_note_markdown(self) -> str:
        """The last 'Find the power' note while the ride and target it speaks of are shown, else ""."""
        note = self.solve_note
        return f"⚠️ {note[1]}" if note is not None and self.state is not None and note[0] == self._solve_key() else ""

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
                f"  \nAverage {ride.average_power_w:.0f} W of the {p.power_w:.0f} W set: the riders ease off or "
                f"coast where {p.power_w:.0f} W would take them over the {p.max_speed_kmh:.0f} km/h safe speed"
            )
        if state.group_cda_m2 != line.cda_m2:
            text += (
                f"  \n{riders_text(line.n_riders)} {FORMATION_WORDS[line.formation]} at the formation's mean drag "
                f"(CdA {state.group_cda_m2:.3f} m²): "
                f"alone the same power takes {format_duration(state.solo.time_s)}"
            )
        if state.pacing is not None:
            text += (
                f"  \nPacing by grade (±{p.pacing_gain_pct:.0f} %): {format_duration(state.constant.time_s)} "
                f"at constant power → {format_duration(ride.time_s)}, "
                f"**{time_saved_words(state.pacing.time_saved_s)}** at the same average power"
            )
        start = f"  \nAir at the start ({state.route.elevation_m[0]:.0f} m): "
        if p.air == "weather":
            source = (
                f"{p.pressure_hpa:g} hPa read" if p.pressure_from_barometer else "the standard atmosphere's pressure"
            )
            text += (
                f"{start}the weather reading, **{state.density_weather:.3f}** kg/m³ ({p.temperature_c:g} °C, "
                f"{source}, {p.humidity_pct:g} % humidity); the textbook atmosphere would give "
                f"{state.density_textbook:.3f} kg/m³"
            )
        else:
            text += f"{start}the textbook atmosphere (exponential), **{state.density_textbook:.3f}** kg/m³"
        if ride.brakes_j > 0.0:
            text += f"  \nBraking to hold {p.max_speed_kmh:.0f} km/h took {ride.brakes_j / 1000:.0f} kJ"
        return text

    def _splits_markdown(self) -> str:
        if self.state is None:
            return ""
        ride = self.state.ride
        every = split_every_m(float(ride.distance_m[-1]))
        marks, times = ride.splits(every)
        if marks.shape[0] >= 2 and marks[-1] - marks[-2] < 0.5:  # a finish within half a metre of a whole split:
            marks, times = np.delete(marks, -2), np.delete(times, -2)  # one row, not "5.0" and "5.000" at 9:52
        rows = ["| km | elapsed | split | km/h |", "|---:|---:|---:|---:|"]
        previous_mark, previous_time = 0.0, 0.0
        shown = np.unique(np.linspace(0, marks.shape[0] - 1, min(marks.shape[0], 20)).round().astype(int))
        for i in range(marks.shape[0]):
            split = times[i] - previous_time
            speed = 3.6 * (marks[i] - previous_mark) / split if split > 0 else 0.0
            if i in shown:
                # The finish reads to the metre, with as few digits as that takes (20.01 after 20.0, not 20.0 twice;
                # 0.13, not 0.1); every other mark is a whole split.
                km, digits = marks[i] / 1000, 1
                while i == marks.shape[0] - 1 and digits < 3 and abs(round(km, digits) - km) >= 0.0005:
                    digits += 1
                rows.append(
                    f"| {km:.{digits}f} | {format_duration(times[i])} | {format_duration(split)} | {speed:.1f} |"
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
            ride.power_w[min(int(np.searchsorted(ride.distance_m, d, side="right")) - 1, ride.power_w.shape[0] - 1)]
        )
        elevation = float(np.interp(d, self.route.distance_m, self.route.elevation_m))
        coasting = ""
        if self.state.pacing is None and power < 0.99 * self.params.power_w:
            # Pedalling less to hold the cap is not coasting: 2000 W up 6.5 % at the 72 km/h cap pedals 1431 W.
            held = "coasting at" if power < 0.5 else "easing off to hold"
            coasting = f" ({held} the {self.params.max_speed_kmh:.0f} km/h safe speed)"
        if self.scene.params.n_riders > 1:  # the group's power; the leader's place needs more (the table's row 1)
            lead = float(self.place_watts()[0][0])
            watts = f"the group's {power:.0f} W{coasting} (the leader's place {lead:.0f} W)"
        else:
            watts = f"{power:.0f} W{coasting}"
        return (
            f"Leader at **{self._leader_km():.2f} km**, {format_duration(self.play_time_s)}: "
            f"{3.6 * speed:.1f} km/h, {watts}, {elevation:.0f} m"
        )


def _right_axis(scale: str, size: float, colour: str) -> viser.uplot.Axis:
    """An axis of the course chart on its right, in its series' colour, without grid lines (the left axis has them)
    and without a unit label (the legend names the unit)."""
    return viser.uplot.Axis(
        scale=scale, side=1, size=size, labelSize=0, grid=viser.uplot.Axis_Grid(show=False), stroke=colour
    )


_MARKDOWN_ESCAPES = str.maketrans({c: f"&#{ord(c)};" for c in "<>[]*_`~|\\:@.!#"} | {"&": "&amp;"})
"""Each character that can start HTML, a link, an image, emphasis, code, a table cell, or a bare address that
GitHub-flavoured markdown makes a link (``http://x``, ``www.x``, ``a@b.c``), as a character reference."""


_WORD_JOINER = "\u2060"
_BARE_ADDRESS = re.compile(r"(?i)(?<=www)(?=\.)|(?<=:)(?=//)|(?=@)")
"""Where GitHub-flavoured markdown's bare-address links start (``www.``, ``://``, ``@``). Its link finder runs on the
text after character references are read, so these get an invisible word joiner (U+2060) instead."""


_BREAK = "\u200b"
BREAK_EVERY = 24
"""Longest run of characters without a place to wrap that :func:`_escape` leaves: a file name or track name with no
spaces (a 240-character one) ran past the panel's right edge, clipped, where the notification wrapped it."""
_ZERO_WIDTH_JOINER = "\u200d"
"""What joins emoji into one picture (👨‍👩‍👧): no break after it."""


def _is_flag_half(c: str) -> bool:
    """Whether ``c`` is a regional indicator: two make a flag."""
    return "\U0001f1e6" <= c <= "\U0001f1ff"


def _breakable(before: str, after: str, flag_halves: int) -> bool:
    """Whether a zero-width space may go between two characters without splitting what is drawn as one: not before
    a combining mark, a format character or an emoji's skin tone, not after a zero-width joiner, not inside a flag
    (``flag_halves`` regional indicators run up to ``before``)."""
    if before == _ZERO_WIDTH_JOINER or unicodedata.category(after) in ("Mn", "Mc", "Me", "Cf"):
        return False
    if "\U0001f3fb" <= after <= "\U0001f3ff":
        return False
    return not (_is_flag_half(after) and flag_halves % 2 == 1)


def _wrappable(text: str) -> str:
    """``text`` with a zero-width space (U+200B, a place to wrap, drawn as nothing) in every run of more than
    :data:`BREAK_EVERY` characters without white space, that far apart, or a little further where a character and
    its marks are drawn as one; never more than twice as far (text made of joiners and marks wraps too)."""
    out: list[str] = []
    run = flag_halves = 0
    for i, c in enumerate(text):
        if c.isspace() or c == _BREAK:
            run = 0
        elif run >= BREAK_EVERY and (run >= 2 * BREAK_EVERY or _breakable(text[i - 1], c, flag_halves)):
            out.append(_BREAK)
            run = 0
        out.append(c)
        run += not c.isspace() and c != _BREAK
        flag_halves = flag_halves + 1 if _is_flag_half(c) else 0
    return "".join(out)


def _escape(text: str) -> str:
    """Text from a file, shown in markdown as the same characters: no HTML, links, images or emphasis, and a place
    to wrap in every long run without white space (:func:`_wrappable`)."""
    return _BARE_ADDRESS.sub(_WORD_JOINER, _wrappable(text)).translate(_MARKDOWN_ESCAPES)


def _ride_inputs(route: course_kernel.Course, params: CourseParams, line: PelotonParams) -> tuple[object, ...]:
    """What a ride on ``route`` depends on, to compare with ``==``: the route itself (compared as the same object:
    its arrays do not compare with ``==``), the course's :data:`RIDE_INPUTS` and the line's :data:`LINE_INPUTS`."""
    return (
        id(route),
        route,
        *(getattr(params, name) for name in RIDE_INPUTS),
        *(getattr(line, name) for name in LINE_INPUTS),
    )
