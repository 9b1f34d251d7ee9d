"""The free-kick scene: a spinning ball's 3D flight over a wall, with its forces, a no-spin ghost, a ±10 % spin band
and the knuckleball, drawn from :mod:`scenes.freekick.model` onto viser.

Every redraw writes the same nodes' arrays (line-segment points, one band mesh's vertices) and never re-adds a node.
Three searches run on :class:`~scenes._worker.LatestWorker` threads, never on a callback: the outcome map (a speed
× spin grid through :func:`kernels.ball.simulate_batch`), "aim at a clicked point of the goal mouth" and the goal
chance from every spot (on request). Each worker runs only the latest request; a newer request makes an older
one's result be dropped, and the outcome map waits for the settings to be still for a moment so dragging a slider
redraws at full speed.
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np
import trimesh
import viser
import viser.uplot
from numpy.typing import NDArray

from kernels import ball, warming
from scenes._base import Scene, set_if_changed
from scenes._charts import FittedChart
from scenes._controls import build_controls, declared
from scenes._framing import ClientFraming, Lens, View
from scenes._instances import add_instances
from scenes._look import add_ground
from scenes._numbers import fixed, signed
from scenes._worker import LatestWorker
from scenes.freekick.model import (
    DEFENDER_WIDTH_M,
    DEFENDERS,
    JUMP_M,
    KEEPER,
    LIMB_RADII_M,
    LIMBS,
    MAP_CELL_PX,
    MAP_QUIET_S,
    MAP_SPEEDS_MS,
    MAP_SPINS_REV_S,
    PATH_POINTS,
    PRESETS,
    RESULT_COLOURS,
    VERDICT_WORDS,
    WOBBLE_SCALE,
    FreeKickParams,
    after_contact,
    aim_at,
    ball_spot,
    compute_kick,
    deflection_m,
    free_flight_result,
    goal_line_reached,
    keeper_limbs,
    keeper_show_time,
    keeper_words,
    knuckle_toggled,
    knuckle_wobble_m,
    landing_words,
    map_marker_words,
    margin_words,
    outcome_map,
    outcome_map_image,
    play_words,
    position_at,
    resample,
    sample_rows,
    save_margin_s,
    spin_axis,
    spin_vector,
    spin_words,
    verdict_words,
    wall_axes,
    wall_height_words,
    wobble_path,
    wobble_words,
)
from scenes.freekick.odds import (
    chances_words,
    heat_cells,
    heat_colours,
    odds_map_settings,
    odds_map_words,
    spot_odds_map,
    strike_chances,
)
from scenes.freekick.props import (
    AFTER_COLOUR,
    ARROW_POINTS,
    FORCE_COLOURS,
    GHOST_COLOUR,
    KNUCKLE_COLOUR,
    METRES_PER_NEWTON,
    PATH_COLOUR,
    arrow_segments,
    axis_angle_wxyz,
    dashed,
    defender_mesh,
    goal_frame_mesh,
    net_segments,
    pitch_markings,
    polyline_segments,
    strip_faces,
)
from scenes.freekick.views import frame_view, view_points

GRASS_HALF_M = 2500.0
"""Half the side (m) of the grass square round the goal: past viser's far clipping plane (1000 m along the view
axis, up to 2.2 km at the canvas's corners for the client's 75° field of view) from any camera the views put within
100 m of the goal, so no view shows where it ends."""
GRASS_COLOUR = (115, 190, 104)
"""The pitch's grass (8-bit sRGB, drawn unlit: after viser's tone mapping it shows as the lit grass did)."""
CHART_COLOURS = {**FORCE_COLOURS, "knuckle": KNUCKLE_COLOUR}
"""The force chart's series after time, by the flight's force field: its arrows' colours and the knuckle's."""


BALL_KERNELS = "kernels.ball"
"""The package whose compile the outcome map waits for on a first start (see :mod:`kernels.warming`)."""


KEEPER_COLOURS = np.array(
    [[25, 25, 25], [25, 25, 25], [250, 205, 0], [250, 205, 0], [250, 205, 0], [235, 190, 150]], np.uint8
)
"""The keeper's limbs (:data:`~scenes.freekick.model.LIMBS`): dark shorts and socks, a bright yellow shirt that
stands out from both teams and the grass, and his head."""
REPLAY_MAX_S = 4.0
"""The Kick button's replay stops this long after the kick (s), even if the ball rolls on."""


def _z_to(directions: NDArray[np.float64]) -> NDArray[np.float64]:
    """(N, 4) wxyz quaternions turning +z onto each of (N, 3) unit ``directions`` (half-way
    vector; −z turns about x)."""
    z = np.array([0.0, 0.0, 1.0])
    w = 1.0 + directions @ z
    xyz = np.cross(z, directions)
    q = np.column_stack([w, xyz])
    flipped = w < 1e-9
    q[flipped] = [0.0, 1.0, 0.0, 0.0]
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def heat_legend_image(width: int = 240, height: int = 18) -> NDArray[np.uint8]:
    """The odds map's colour bar: no goals at the left to every strike a goal at the right, ticks every 25 %."""
    bar = np.repeat(heat_colours(np.linspace(0.0, 1.0, width))[None], height, axis=0)
    for share in (0.0, 0.25, 0.5, 0.75, 1.0):
        x = min(round(share * (width - 1)), width - 1)
        bar[height - 5 :, max(x - 1, 0) : x + 1] = 255
    return bar


def _css(rgb: tuple[int, int, int]) -> str:
    return f"rgb({rgb[0]},{rgb[1]},{rgb[2]})"


class FreeKickScene(Scene[FreeKickParams]):
    key = "freekick"
    title = "Free kick: Magnus effect"
    opening_view = View((-31.0, -4.0, 3.6), (-6.0, 0.0, 1.4))
    about = """
**What it shows.** A free kick's flight in 3D over a four-man wall 9.15 m from the ball (1.8 m tall; 2.15 m when it
jumps): the kick as set (thick orange line), the same kick with no spin (dark dashed ghost), a faint band between 10 %
less and 10 % more spin, and force arrows along the path: drag (red), Magnus (blue), gravity (purple). **View** frames
the kick raised over the kicker's shoulder, from behind the ball, side-on, as the goalkeeper sees it or from above.
**Kick** flies the ball, spinning, in real time. Click a point in the goal mouth to have the scene find a kick that
reaches it over the wall. The outcome map colours each launch speed × spin rate by result: goal (green), wall (red),
over (orange), wide (yellow), short (grey); the white cross is the current kick.

**On the pitch.** The same kick played on (pale line): it bounces, rolls, strikes the posts, bar and the wall's
players, and the goalkeeper (yellow shirt) stands on the bisector of the posts' angle, reads the ball 0.25 s after
it passes the wall and dives at 3.9 m/s (Ibrahim et al. 2019) to where he reads it will cross; a touch is a save.
He is drawn as the ball arrives; **Kick** plays his dive. **Goal chance over the pitch** strikes this kick 32 times
from each of 357 spots and colours each spot by its goal chance. *Knuckleball*: the thin orange line draws the
kick's difference from the spinless path ten times larger.

**Equations** (A = πr², ω̂ = ω/|ω|): F_drag = −½ρA·C_D·|v|·v, F_Magnus = ½ρA·C_L·|v|·(ω̂ × v), F_g = −m·g·ẑ;
m = 0.43 kg, r = 0.11 m, ρ = 1.225 kg/m³. The original brief's Magnus formula (C_L·ρπr²·|v×ω|/|ω|) is not a force; this
form keeps its direction and gives its 3–5 m of curl over 25 m.

**Models.** *Constant*: C_D = C_L = 0.25; the curl radius is then 2m/(ρA·C_L) ≈ 74 m whatever the spin rate, so the
spin rate changes nothing but the direction. *Measured*: C_L = 0.9·S (S = r|ω|/|v|, up to S = 0.3; Asai et al.
2007), C_D from Goff & Carré 2010 (drag crisis centred at Re 1.8·10⁵, 12 m/s; 0.4127·S^0.3056 when spinning):
10 % more spin visibly moves the ball. *Knuckleball*: with almost no spin, an unsteady side force zig-zags the ball by
about a diameter per ~15 m (Cohen, Texier, Quéré & Clanet 2012; Texier et al. 2016), drawn from a random draw number
(the same number, the same flight).

**Integrators.** RK4 at 10 ms is within a few micrometres of a DOP853 reference over 30 m; the original brief's Euler at
1 ms is off by 7–17 mm (more with spin), not "within a centimetre".

**Assumptions.** Constant spin between contacts, still air. The orange flight ends at the turf or two metres past
the goal line; the played-on flight and its verdict are the pitch's. A goal needs the whole ball over the line
between the posts and under the bar. The keeper dives on his first read of a ball that comes at his goal and never
reads it again, so a ball that bounces in front of him beats him more often than it would a real keeper.
"""

    def __init__(self, server: viser.ViserServer) -> None:
        super().__init__(server)
        self.params = FreeKickParams()
        self.state = compute_kick(self.params)
        self.kick_time_s: float | None = None
        """How far the kick's replay has got (s), or None when the ball rests on its spot."""
        self._map_version = 0
        self._aim_version = 0
        self.map_results: NDArray[np.str_] | None = None
        self.map_runs = 0
        """How many outcome maps have been computed (a burst of changes computes one)."""
        self.map_params: FreeKickParams | None = None
        """The settings the shown outcome map was computed for."""
        self.chances: ball.Odds | None = None
        """The odds shown for the map's settings: the kick struck many times with a player's scatter."""
        self.last_target: tuple[float, float] | None = None
        self.aim_message = ""
        self._aim_searching = False
        """Whether a goal-mouth click's search is under way (for the kick shown when it was clicked)."""
        self._odds_version = 0
        self.odds_map: NDArray[np.float64] | None = None
        """The goal chance over the pitch's spots (:func:`~scenes.freekick.odds.spot_odds_map`), once asked for."""
        self.odds_map_params: FreeKickParams | None = None
        """The strike (:func:`~scenes.freekick.odds.odds_map_settings`) the shown odds map is for."""
        self.odds_map_asked: FreeKickParams | None = None
        """The strike of the odds map being computed (the latest click's), None once it is done or has failed: what
        the status says follows it, not the worker, whose own job is still running when it shows its result."""
        self._map_worker = LatestWorker("freekick-map")
        self._aim_worker = LatestWorker("freekick-aim")
        self._odds_worker = LatestWorker("freekick-odds-map")
        # The scene's join() waits for a search in flight, as for its animation loop.
        self._threads += [self._map_worker.thread, self._aim_worker.thread, self._odds_worker.thread]
        self._build_gui()
        self._build_world()
        self.redraw()
        self.framing = ClientFraming(self._view_for, opening=self.opening_view.position)
        self.watch_cameras(self.framing.on_camera)
        # On a first start the map (1,271 kicks) waits for the compiled flight; plain Python would take ~10 s.
        warming.on_progress(self._on_kernels_compiled)
        self.request_outcome_map()
        self.start_loop(self._animate, 1.0 / 30.0)

    def _on_kernels_compiled(self, progress: warming.Progress) -> None:
        if BALL_KERNELS in progress.done:
            warming.remove_listener(self._on_kernels_compiled)
            if not self.closed:
                self.request_outcome_map()

    # ----------------------------------------------------------------------------------------- GUI
    def _build_gui(self) -> None:
        gui, p = self.server.gui, self.params
        with self.gui_root:
            self.kick_button = gui.add_button("Kick", color="green")
            self.view_controls = build_controls(gui, p, names=("view",))
            """The View dropdown: a change reframes the kick, which stays as it is."""
            self.result = gui.add_markdown("")
            self.kick_controls = build_controls(
                gui, p, names=[name for name in declared(FreeKickParams) if name != "view"]
            )
            """Every other control, in its folder: a change recomputes the kick."""
            self.controls = self.kick_controls | self.view_controls
            """Every control the user sets, by field name."""
            with gui.add_folder("Presets"):
                self.preset_buttons = [gui.add_button(preset.label) for preset in PRESETS]
            with gui.add_folder("Forces"):
                self.chart = FittedChart(
                    gui,
                    data=self._chart_data(),
                    series=(
                        viser.uplot.Series(label="t (s)"),
                        *(
                            viser.uplot.Series(label=f"{name.title()} (N)", stroke=_css(colour), width=2)
                            for name, colour in CHART_COLOURS.items()
                        ),
                    ),
                    legend=viser.uplot.Legend(show=True),
                    title="Force magnitudes along the flight",
                    aspect=1.6,
                )
            with gui.add_folder("Aim at the goal mouth"):
                self.aim_help = gui.add_markdown(
                    "Click a point in the goal mouth: the scene searches elevation, azimuth and sidespin at this "
                    "launch speed for a kick that reaches it over the wall."
                )
                self.aim_status = gui.add_markdown("")
            with gui.add_folder("Outcome map"):
                self.map_legend = gui.add_markdown(
                    "Launch speed 15–35 m/s left to right, spin 0–15 rev/s bottom to top, other settings as set "
                    "(flown by RK4 at 10 ms whatever the Integrator). "
                    "Green goal, red wall, orange over, yellow wide, grey short; white cross: this kick (an arrow "
                    "on the edge when it lies off the map)."
                )
                self.map_image = gui.add_image(
                    np.full((len(MAP_SPINS_REV_S) * MAP_CELL_PX, len(MAP_SPEEDS_MS) * MAP_CELL_PX, 3), 200, np.uint8),
                    label="Speed × spin",
                    format="png",
                )
                self.map_status = gui.add_markdown("Computing…")
                self.odds_status = gui.add_markdown("")
                """The current kick's odds over many strikes, computed with the map."""
            with gui.add_folder("Goal chance over the pitch"):
                self.heat_button = gui.add_button("Map the goal chance from every spot")
                self.heat_progress = gui.add_progress_bar(0.0, visible=False, animated=True)
                self.heat_status = gui.add_markdown(
                    "This strike from 357 spots, 16–36 m out and 40° either side, 32 strikes each with a player's "
                    "scatter: the goal chance drawn on the grass."
                )
                self.heat_legend = gui.add_image(heat_legend_image(), label="Goal 0 → 100 %", format="png")
                self.heat_legend.visible = False

        self.kick_controls.on_update(self.callback(self.apply_inputs))
        self.kick_button.on_click(self.callback(self._on_kick))
        self.heat_button.on_click(self.callback(self.request_odds_map))
        self.view_controls.on_update(self.callback(self._on_view))
        for preset, button in zip(PRESETS, self.preset_buttons, strict=True):
            button.on_click(self.callback(lambda preset=preset: self.apply(preset.params.shown_as(self.params))))

    # ----------------------------------------------------------------------------------------- world
    def _build_world(self) -> None:
        scene, root = self.server.scene, self.root.name
        grass = trimesh.creation.box(extents=(2.0 * GRASS_HALF_M, 2.0 * GRASS_HALF_M, 0.02))
        grass.apply_translation((0.0, 0.0, -0.011))
        add_ground(scene, f"{root}/grass", grass.vertices, grass.faces, GRASS_COLOUR)
        scene.add_line_segments(f"{root}/markings", pitch_markings(), colors=(245, 245, 245), thickness=0.12)
        frame = goal_frame_mesh()
        scene.add_mesh_simple(f"{root}/goal_frame", frame.vertices, frame.faces, color=(250, 250, 250))
        scene.add_line_segments(f"{root}/net", net_segments(), colors=(225, 225, 225), thickness=0.02)
        half, h = 0.5 * ball.GOAL_WIDTH_M, ball.GOAL_HEIGHT_M
        # A nearly invisible pane across the goal mouth: clicking it aims a kick there.
        self.goal_mouth = scene.add_mesh_simple(
            f"{root}/goal_mouth",
            np.array([[0.0, -half, 0.0], [0.0, half, 0.0], [0.0, half, h], [0.0, -half, h]]),
            np.array([[0, 1, 2], [0, 2, 3]]),
            color=(255, 255, 255),
            opacity=0.08,
            side="double",
            cast_shadow=False,
            receive_shadow=False,
        )
        self.goal_mouth.on_click(self._on_goal_click)
        self.target_marker = scene.add_icosphere(
            f"{root}/target", radius=0.12, color=(255, 60, 200), position=(0.0, 0.0, 1.0), visible=False
        )

        # The goal chance over the pitch: one flat tile per spot, coloured once a map is computed.
        centres, headings, sizes = heat_cells()
        tile = trimesh.creation.box(extents=(1.0, 1.0, 0.004))
        self.heat_nodes = add_instances(
            scene,
            f"{root}/odds_map",
            tile,
            len(centres),
            np.tile(heat_colours(np.zeros(1)), (len(centres), 1)),
            scale=None,
            cast_shadow=False,
            visible=False,
        )
        half = 0.5 * np.hypot(sizes[:, 0], sizes[:, 1])[:, None]
        self._heat_corners = np.vstack([centres + half * [1.0, 1.0, 0.0], centres - half * [1.0, 1.0, 0.0]])
        """Points round every tile of the odds map: what the view from above keeps in frame while it shows."""
        self.heat_nodes.batched_positions = centres.astype(np.float32)
        self.heat_nodes.batched_wxyzs = np.column_stack(
            [np.cos(headings / 2), np.zeros((len(headings), 2)), np.sin(headings / 2)]
        ).astype(np.float32)
        self.heat_nodes.batched_scales = np.column_stack([sizes, np.ones(len(sizes))]).astype(np.float32)

        defender = defender_mesh()
        self.wall_nodes = add_instances(
            scene,
            f"{root}/wall",
            defender,
            DEFENDERS,
            np.tile(np.array([30, 60, 170], np.uint8), (DEFENDERS, 1)),
            scale=None,
        )

        # The keeper: one rod per limb (a unit cylinder stretched and turned), and a head.
        rod = trimesh.creation.cylinder(radius=1.0, height=1.0, sections=10)
        rod.apply_translation((0.0, 0.0, 0.5))
        self.keeper_nodes = add_instances(scene, f"{root}/keeper", rod, len(LIMBS), KEEPER_COLOURS, scale=None)
        self.keeper_head = scene.add_icosphere(
            f"{root}/keeper_head", radius=LIMB_RADII_M[-1], color=(235, 190, 150), subdivisions=2
        )

        self.ball_frame = scene.add_frame(f"{root}/ball", show_axes=False, position=tuple(ball_spot(self.params)))
        sphere = trimesh.creation.icosphere(subdivisions=3, radius=ball.BALL_RADIUS_M)
        scene.add_mesh_simple(f"{self.ball_frame.name}/sphere", sphere.vertices, sphere.faces, color=(250, 250, 250))
        # A dark band round the ball's equator makes its spin visible.
        band = trimesh.creation.torus(
            major_radius=ball.BALL_RADIUS_M, minor_radius=0.018, major_sections=32, minor_sections=6
        )
        band.apply_transform(trimesh.transformations.rotation_matrix(math.pi / 2, [1, 0, 0]))
        scene.add_mesh_simple(f"{self.ball_frame.name}/band", band.vertices, band.faces, color=(20, 20, 20))

        empty_path = np.zeros((PATH_POINTS - 1, 2, 3), np.float32)
        self.path = scene.add_line_segments(f"{root}/path", empty_path, colors=PATH_COLOUR, thickness=0.09)
        self.ghost = scene.add_line_segments(f"{root}/ghost", empty_path, colors=GHOST_COLOUR, thickness=0.04)
        self.after = scene.add_line_segments(f"{root}/after", empty_path, colors=AFTER_COLOUR, thickness=0.06)
        self.wobble = scene.add_line_segments(
            f"{root}/wobble", empty_path, colors=KNUCKLE_COLOUR, thickness=0.05, visible=False
        )
        """The knuckleball's difference from the spinless path, magnified (hidden without a knuckle force)."""
        """The kick played on after its first contact: bounces, rolls, rebounds off the frame or a defender."""
        self.band = scene.add_mesh_simple(
            f"{root}/band",
            np.zeros((2 * PATH_POINTS, 3), np.float32),
            strip_faces(PATH_POINTS),
            color=(255, 200, 90),
            opacity=0.35,
            side="double",
            cast_shadow=False,
            receive_shadow=False,
        )
        empty_arrows = np.zeros((3 * ARROW_POINTS, 2, 3), np.float32)
        self.arrows = {
            name: scene.add_line_segments(f"{root}/force_{name}", empty_arrows, colors=colour, thickness=0.07)
            for name, colour in FORCE_COLOURS.items()
        }

    # ----------------------------------------------------------------------------------------- inputs
    def read_params(self) -> FreeKickParams:
        """The current GUI values, cleaned: anything non-finite or unknown keeps the last good value, a number out of
        range is clamped."""
        return self.read_controls(self.controls)

    def apply_inputs(self) -> None:
        """Read the controls and show the kick they set (what a change of any control but the view runs). Ticking
        Knuckleball sets the spin near zero and unticking it brings the spin back (:func:`knuckle_toggled`); the
        slider shows it."""
        params = knuckle_toggled(self.params, self.read_params())
        handle = self.controls["spin_rev_s"]
        if handle.value != params.spin_rev_s:
            self.write_back(handle, params.spin_rev_s)
        self._set_params(params)

    def _set_params(self, params: FreeKickParams) -> None:
        state = compute_kick(params)  # raises (and keeps the last state) if the kernels refuse the input
        moved = (params.distance_m, params.angle_deg) != (self.params.distance_m, self.params.angle_deg)
        if params.shown_as(self.params) != self.params:  # another kick, not only its arrows or view
            self._drop_aim()
        self.params, self.state = params, state
        self.kick_time_s = None
        self.redraw()
        self.request_outcome_map()
        self._show_odds_map()
        if moved:  # the ball is on another spot: every view moves with it
            self.framing.reframe()
        else:  # a higher or wider flight (or its no-spin path) than the view was framed for: frame it again
            self.framing.keep_in_view(self._framed_points())

    # ----------------------------------------------------------------------------------------- camera
    def _on_view(self) -> None:
        self.params = self.read_controls(self.view_controls)  # the kick itself is unchanged
        self.framing.reframe()

    def _view_for(self, lens: Lens) -> View:
        shown = self.heat_nodes.visible
        return frame_view(self.params, self.state, self.params.view, lens, self._heat_corners if shown else None)

    def _framed_points(self) -> NDArray[np.float64]:
        """(N, 3) what the current view keeps in frame (m): :func:`~scenes.freekick.views.view_points`."""
        shown = self.heat_nodes.visible
        return view_points(self.params, self.state, self.params.view, self._heat_corners if shown else None)

    def apply(self, params: FreeKickParams) -> None:
        """Show ``params``: write every GUI control (without re-running callbacks) and redraw once."""
        with self.server.atomic():
            for name, built in self.controls.fields.items():
                self.write_back(built.handles[0], built.control.to_gui(getattr(params, name)))
        view = self.params.view
        # What no control holds (the spin a Knuckleball tick kept) is ``params``'s, not the kick's before.
        unshown = {
            member.name: getattr(params, member.name)
            for member in dataclasses.fields(params)
            if member.name not in self.controls.fields
        }
        self._set_params(dataclasses.replace(self.read_params(), **unshown))
        if self.params.view != view:
            self.framing.reframe()

    def _on_kick(self) -> None:
        self.kick_time_s = 0.0
        self.wake_loops()

    def _on_goal_click(self, event: viser.SceneNodePointerEvent) -> None:
        origin, direction = event.ray_origin, event.ray_direction
        self.callback(lambda: self.aim_from_ray(origin, direction))(None)

    def aim_from_ray(self, ray_origin: object, ray_direction: object) -> None:
        """Intersect a click ray with the goal mouth and queue the search for a kick reaching that point."""
        try:
            o = np.asarray(ray_origin, dtype=np.float64)
            d = np.asarray(ray_direction, dtype=np.float64)
        except (TypeError, ValueError):
            return  # not a ray: a crafted message
        if o.shape != (3,) or d.shape != (3,) or not (np.all(np.isfinite(o)) and np.all(np.isfinite(d))):
            return
        if abs(d[0]) < 1e-9:
            return
        s = -o[0] / d[0]
        if s <= 0:
            return
        y, z = float(o[1] + s * d[1]), float(o[2] + s * d[2])
        half, h = 0.5 * ball.GOAL_WIDTH_M, ball.GOAL_HEIGHT_M
        if not (-half <= y <= half and 0.0 <= z <= h):
            return
        self.aim_at_point(y, z)

    def aim_at_point(self, y: float, z: float) -> None:
        """Queue a search for a kick reaching (y, z) on the goal line; its result is applied when it finishes."""
        self.last_target = (y, z)
        self._aim_version += 1
        self._aim_searching = True
        version, params = self._aim_version, self.params
        with self.server.atomic():
            self.target_marker.position = (0.0, y, z)
            self.target_marker.visible = True
            self.aim_status.content = f"Searching for a kick to y = {signed(y, 2)} m, z = {fixed(z, 2)} m…"

        def job() -> None:
            found = aim_at(params, (y, z))
            with self._lock:
                if self.closed or version != self._aim_version:
                    return
                self._aim_searching = False
                if found is None:
                    self.aim_message = "No kick at this speed reaches that point over the wall; try another speed."
                    self.aim_status.content = self.aim_message
                    return
                self.apply(found.shown_as(self.params))  # arrows and view as shown now, not when the click came
                self.target_marker.visible = True  # (the kick's change took the last one's down)
                point = self.state.outcome.goal_point
                crossing = "" if point is None else f"y = {signed(point[1], 2)} m, z = {fixed(point[2], 2)} m"
                reached = f" It crosses at {crossing}." if crossing else ""
                self.aim_message = (
                    f"Found: elevation {found.elevation_deg:.1f}°, azimuth {signed(found.azimuth_deg, 1)}°, "
                    f"{spin_words(found)}.{reached}"
                )
                self.aim_status.content = self.aim_message

        self._aim_worker.submit(job)

    def _drop_aim(self) -> None:
        """The kick changed: a search under way was for the kick before, and is dropped (it says so until the next
        click: a drag's later updates leave it up); a result and its marker spoke of the kick before, and are taken
        down."""
        self._aim_version += 1
        if not (self._aim_searching or self.aim_message or self.target_marker.visible):
            return
        stopped = "The kick changed during the search, which was stopped; click the goal again to aim this one."
        self.aim_message = stopped if self._aim_searching or self.aim_message == stopped else ""
        self._aim_searching = False
        with self.server.atomic():
            self.target_marker.visible = False
            self.aim_status.content = self.aim_message

    # ----------------------------------------------------------------------------------------- outcome map
    def request_outcome_map(self) -> None:
        """Queue the outcome map of the current settings; it is computed once they have been still for
        :data:`~scenes.freekick.model.MAP_QUIET_S`, and a newer request drops this one's result."""
        self._map_version += 1
        version, params = self._map_version, self.params

        def job() -> None:
            if warming.is_pending(BALL_KERNELS):  # requested again once they are compiled
                with self._lock:
                    if not self.closed:
                        self.map_status.content = "The outcome map is drawn once the ball-flight kernels have compiled."
                return
            self.map_runs += 1
            results = outcome_map(params)
            chances = strike_chances(params)
            with self._lock:
                if self.closed or version != self._map_version:
                    return
                self.map_results, self.map_params = results, params
                counts = {name: int(np.sum(results == name)) for name in RESULT_COLOURS}
                self.map_image.image = outcome_map_image(results, params)
                words = {
                    "goal": "goals",
                    "wall": "blocked by the wall",
                    "over": "over the bar",
                    "wide": "wide",
                    "short": "short",
                }
                summary = f"Of {results.size} kicks: " + ", ".join(
                    f"{n} {words[name]}" for name, n in counts.items() if n
                )
                if where := map_marker_words(params):
                    summary += f"  \n{where}"
                if params.model == "constant":
                    summary += (
                        "  \nConstant C_L: any spin above zero curls the same, so the rows repeat. Pick the "
                        "measured model to see the spin rate matter."
                    )
                self.map_status.content = summary
                self.chances = chances
                self.odds_status.content = chances_words(chances)

        self._map_worker.submit(job, delay_s=MAP_QUIET_S)

    # ----------------------------------------------------------------------------------------- odds over the pitch
    def request_odds_map(self) -> None:
        """Queue the goal chance of the current strike from every spot of the map (the button); a progress bar
        follows it, and a newer request drops this one's result."""
        self._odds_version += 1
        version, params = self._odds_version, self.params
        self.odds_map_asked = odds_map_settings(params)
        with self.server.atomic():
            self.heat_progress.value = 0.0
            self._show_odds_map()

        def progress(share: float) -> None:
            with self._lock:
                if not self.closed and version == self._odds_version:
                    self.heat_progress.value = round(100.0 * share, 1)

        def job() -> None:
            try:
                chance = spot_odds_map(params, progress)
            except Exception:
                with self._lock:
                    if not self.closed and version == self._odds_version:
                        self.odds_map_asked = None
                        with self.server.atomic():
                            self._show_odds_map()
                            self.heat_status.content = "The goal chance map failed (the log says why): map it again."
                raise  # the worker logs it
            with self._lock:
                if self.closed or version != self._odds_version:
                    return  # a newer click's map is on its way, and its status is shown
                self.odds_map, self.odds_map_params = chance, odds_map_settings(params)
                self.odds_map_asked = None
                self.heat_nodes.batched_colors = heat_colours(chance.ravel())
                self._show_odds_map()
                if not self.heat_nodes.visible:  # the strike changed while it was mapped: the view stays
                    return
                if self.params.view != "above":  # a map of the pitch reads best from above
                    self.apply(dataclasses.replace(self.params, view="above"))
                else:
                    self.framing.reframe()

        self._odds_worker.submit(job)

    def _show_odds_map(self) -> None:
        """Show the odds map if it is for the current strike (from any spot), else hide it and say why; the progress
        bar shows while a map of the current strike is computed. A map asked for a strike that has since changed
        still finishes (it is shown should that strike come back), but says at once that this strike needs its own."""
        strike = odds_map_settings(self.params)
        current = self.odds_map is not None and self.odds_map_params == strike
        striking = self.odds_map_asked == strike
        with self.server.atomic():
            set_if_changed(self.heat_nodes, "visible", current)
            set_if_changed(self.heat_legend, "visible", current)
            set_if_changed(self.heat_progress, "visible", striking)
            if striking:
                self.heat_status.content = "Striking the kick from every spot…"
            elif current and self.odds_map is not None:
                self.heat_status.content = (
                    f"{odds_map_words(self.odds_map, self.params)}  \nEach tile: this strike from there, 32 times "
                    "with a player's scatter, the wall square to the goal. Shown from above (pick another View to "
                    "see the kick)."
                )
            elif self.odds_map is not None or self.odds_map_asked is not None:
                self.heat_status.content = "The strike has changed: map it again to see its goal chance."

    def wait_idle(self, timeout_s: float = 30.0) -> bool:
        """Sleep until no search is queued or running (True), or ``timeout_s`` has passed (False); for tests and
        benchmarks. An aim's result queues a new outcome map, so the aim worker is waited for first, and both again
        should a search have been queued meanwhile."""
        deadline = time.monotonic() + timeout_s
        workers = (self._aim_worker, self._map_worker, self._odds_worker)
        while True:
            for worker in workers:
                if not worker.wait_idle(max(0.0, deadline - time.monotonic())):
                    return False
            if all(worker.idle() or worker.closed for worker in workers):
                return True

    def close(self) -> None:
        """Drop any waiting search and stop the workers, then remove the scene (a search in flight finishes, and
        finds the scene closed)."""
        warming.remove_listener(self._on_kernels_compiled)
        for worker in (self._aim_worker, self._map_worker, self._odds_worker):
            worker.close(timeout_s=0.0)  # the base's close joins their threads
        super().close()

    # ----------------------------------------------------------------------------------------- drawing
    def _chart_data(self) -> tuple[NDArray[np.float64], ...]:
        f = self.state.flight
        return (f.t, *(np.linalg.norm(getattr(f, name), axis=1) for name in CHART_COLOURS))

    def redraw(self) -> None:
        """Push the current state to the path, ghost, band, arrows, wall, ball and readouts, in one atomic update."""
        p, state = self.params, self.state
        path = resample(state.flight)
        less, more = resample(state.less_spin), resample(state.more_spin)
        strip = np.empty((2 * PATH_POINTS, 3))
        strip[0::2], strip[1::2] = less, more
        flight = state.flight
        times = np.linspace(0.0, float(flight.t[-1]), ARROW_POINTS + 2)[1:-1]
        names = list(FORCE_COLOURS)
        at = sample_rows(times, flight.t, np.hstack([flight.position, *(getattr(flight, n) for n in names)]))
        origins, forces = at[:, :3], at[:, 3:].reshape(ARROW_POINTS, len(names), 3)
        # Every force's arrows in one call: (3 parts, force, arrow, 2, 3), each force's (3K, 2, 3) a slice.
        arrows = arrow_segments(
            np.tile(origins, (len(names), 1)), METRES_PER_NEWTON * forces.transpose(1, 0, 2).reshape(-1, 3)
        ).reshape(3, len(names), ARROW_POINTS, 2, 3)
        wall = state.wall
        normal, along = wall_axes(wall)
        offsets = (np.arange(DEFENDERS) - 0.5 * (DEFENDERS - 1)) * DEFENDER_WIDTH_M
        feet = np.array(wall.centre_xy) + offsets[:, None] * along
        lift = JUMP_M if p.wall_jumps else 0.0
        heading = math.atan2(normal[1], normal[0])

        with self.server.atomic():
            self.path.points = polyline_segments(path)
            self.ghost.points = dashed(polyline_segments(resample(state.ghost)))
            after = after_contact(state.played)
            if after is not None:
                self.after.points = polyline_segments(after).astype(np.float32)
            set_if_changed(self.after, "visible", after is not None)
            wobble = wobble_path(state)
            if wobble is not None:
                self.wobble.points = polyline_segments(wobble)
            set_if_changed(self.wobble, "visible", wobble is not None)
            self.band.vertices = strip.astype(np.float32)
            for k, name in enumerate(names):
                self.arrows[name].points = arrows[:, k].reshape(-1, 2, 3).astype(np.float32)
                set_if_changed(self.arrows[name], "visible", p.show_forces)
            # Only what changed: viser casts every write through its type hints first (~0.1 ms each).
            set_if_changed(
                self.wall_nodes,
                "batched_positions",
                np.column_stack([feet, np.full(DEFENDERS, lift)]).astype(np.float32),
            )
            set_if_changed(
                self.wall_nodes,
                "batched_wxyzs",
                np.tile([math.cos(heading / 2), 0.0, 0.0, math.sin(heading / 2)], (DEFENDERS, 1)).astype(np.float32),
            )
            self._draw_keeper(keeper_show_time(state))
            set_if_changed(self.ball_frame, "position", tuple(ball_spot(p)))
            set_if_changed(self.ball_frame, "wxyz", (1.0, 0.0, 0.0, 0.0))
            for name, disabled in (
                ("axis_tilt_deg", p.spin_axis != "custom"),
                ("axis_turn_deg", p.spin_axis != "custom"),
                ("knuckle_seed", not p.knuckle),
            ):
                handle = self.controls[name]
                if handle.disabled != disabled:
                    handle.disabled = disabled
            self.result.content = self.readout_markdown()
            self.chart.data = self._chart_data()
        self.server.flush()

    def readout_markdown(self) -> str:
        state, p = self.state, self.params
        o = state.outcome
        # The verdict is the pitch's (posts, bar, defenders, turf) wherever the kick is played on; the free flight's
        # crossing of the goal plane is said beside it when it differs (a ball 0.1 m wide of the post's inside edge
        # still strikes the post).
        played = state.played
        result = played.result if played is not None and played.result in VERDICT_WORDS else o.result
        reached = goal_line_reached(state)  # then the played ball crossed where the free flight does
        margin = save_margin_s(state)
        if result == "saved" and margin is not None:
            headline = f"Saved: the keeper {margin_words(margin, 'reached it {s} s early', 'just reached it')}"
        else:
            headline = verdict_words(result, o.goal_point if reached else None)
        lines = [f"**{headline}**"]
        free = free_flight_result(state)
        if result != free:
            lines.append(f"In free flight through the goal plane: {verdict_words(free, o.goal_point)}")
        lines += ["", f"Height at the wall: **{wall_height_words(state)}** (wall top {state.wall.height_m:.2f} m)"]
        if reached and o.goal_point is not None and o.goal_time is not None:
            lines.append(
                f"At the goal line: **y = {signed(o.goal_point[1], 2)} m, z = {fixed(o.goal_point[2], 2)} m** after "
                f"**{o.goal_time:.2f} s**"
            )
        elif o.goal_point is None:
            lines.append(landing_words(state))
        deflection = deflection_m(state)
        if deflection is not None:
            lines.append(f"Sideways against the no-spin kick: **{signed(deflection, 2)} m** (+ = left)")
        words = play_words(state.played)
        if words:
            lines.append(f"Played on: **{words}** (pale line)")
        keeper = keeper_words(state)
        if keeper:
            lines.append(f"Keeper (drawn as the ball arrives): **{keeper}**")
        wobble = knuckle_wobble_m(p, state)
        if wobble is not None:
            lines.append(
                f"Knuckle wobble: up to **{wobble:.2f} m** off the spinless path (dashed): "
                f"**{wobble_words(p, state)}**; the thin orange line draws it {WOBBLE_SCALE:g}× larger"
            )
        elif p.knuckle:
            lines.append("Knuckleball: no wobble at this spin (any real spin steadies the wake)")
        if p.knuckle and p.spin_before_knuckle_rev_s is not None:
            lines.append(
                f"Knuckleball: spin set to {p.spin_rev_s:g} rev/s (a knuckleball is struck with almost none; spin "
                f"steadies the wake that makes it wobble). Untick it to get the {p.spin_before_knuckle_rev_s:g} rev/s "
                "back."
            )
        s_param = ball.BALL_RADIUS_M * 2 * math.pi * p.spin_rev_s / max(p.speed_ms, 1e-9)
        lines.append(f"Spin parameter S = r·ω/v = {s_param:.3f}")
        return "  \n".join(lines)

    def _draw_keeper(self, t: float) -> None:
        """Put the keeper figure where the kernel's keeper is ``t`` s after the kick (hidden without one)."""
        state = self.state
        shown = state.keeper_xy is not None and state.played is not None
        set_if_changed(self.keeper_nodes, "visible", shown)
        set_if_changed(self.keeper_head, "visible", shown)
        if state.keeper_xy is None or state.played is None:
            return
        pose = ball.keeper_path(KEEPER, state.keeper_xy, state.played.keeper_dive, np.array([t]))
        facing = ball_spot(self.params)[:2] - np.array(state.keeper_xy)
        limbs = keeper_limbs(pose, facing / max(float(np.linalg.norm(facing)), 1e-9))[0]
        starts, ends = limbs[:, 0], limbs[:, 1]
        lengths = np.linalg.norm(ends - starts, axis=1)
        directions = (ends - starts) / np.maximum(lengths, 1e-9)[:, None]
        self.keeper_nodes.batched_positions = starts.astype(np.float32)
        self.keeper_nodes.batched_wxyzs = _z_to(directions).astype(np.float32)
        scales = np.column_stack([LIMB_RADII_M, LIMB_RADII_M, lengths])
        scales[-1] = 0.0  # the head is its own sphere
        self.keeper_nodes.batched_scales = scales.astype(np.float32)
        self.keeper_head.position = 0.5 * (starts[-1] + ends[-1])

    def replay_flight(self) -> ball.Trajectory:
        """What the Kick button flies: the kick played on (bounces, posts, the keeper), else its free flight."""
        return self.state.played if self.state.played is not None else self.state.flight

    # ----------------------------------------------------------------------------------------- animation
    def _animate(self, dt: float) -> bool:
        """One frame of the kick's replay; False (the loop sleeps) when no kick is playing."""
        if self.kick_time_s is None:
            return False
        flight = self.replay_flight()
        end = min(float(flight.t[-1]), REPLAY_MAX_S)
        self.kick_time_s += min(dt, 0.1)
        t = min(self.kick_time_s, end)
        angle = float(np.linalg.norm(spin_vector(self.params))) * t
        with self.server.atomic():
            self.ball_frame.position = tuple(position_at(flight, t))
            self.ball_frame.wxyz = axis_angle_wxyz(spin_axis(self.params), angle)
            self._draw_keeper(t)
        self.server.flush()
        if self.kick_time_s >= end + 1.5:
            self.kick_time_s = None  # rest a moment where it landed, then go back to the spot
            with self.server.atomic():
                self.ball_frame.position = tuple(ball_spot(self.params))
                self.ball_frame.wxyz = (1.0, 0.0, 0.0, 0.0)
                self._draw_keeper(keeper_show_time(self.state))
        return True
