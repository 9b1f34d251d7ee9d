"""The peloton scene's course mode through a real server: kernel agreement, uploads over the websocket (good and
bad files), play / pause / scrub, air and model choices, the shared paceline, and crafted values."""

from __future__ import annotations

import html
import math
import re
import threading
import time
import unicodedata
from typing import Any
from unittest.mock import ANY

import numpy as np
import pytest
import viser
from helpers.browser import ERROR_TEXT, VIEWPORTS
from helpers.gpx import BAD_FILES, gpx_text, hill_gpx
from helpers.properties import examples
from helpers.scenes import course_mode_fixture, glb_vertices, scene_fixture
from helpers.screen_geometry import pinhole_ndc
from helpers.uploads import send_part, start_upload, upload
from helpers.wsclient import BrowserClient, Crafted, crafted_sent
from hypothesis import given, settings
from hypothesis import strategies as st

from kernels import course as course_kernel
from kernels import cycling
from scenes._framing import MARGIN_PX, NOTICE_PX, PANEL_PX, Lens
from scenes.peloton import PelotonParams, PelotonScene
from scenes.peloton.course import BREAK_EVERY, LINE_INPUTS, RIDE_INPUTS, CourseMode, _escape
from scenes.peloton.course_model import (
    BAROMETER_RANGE_HPA,
    MARK_WIDTH_M,
    SAMPLE_LABEL,
    CourseParams,
    compute_course,
    course_air,
    format_duration,
    lay_out_road,
    route_points,
    time_saved_words,
)
from scenes.peloton.meshes import rider_head_m
from scenes.peloton.model import BIKE_LENGTH_M, group_cda
from scenes.peloton.model import FORMATION_FROM_LABEL as FORMATION
from server.switcher import SceneSwitcher

scene = scene_fixture(PelotonScene)


mode = course_mode_fixture()


# ------------------------------------------------------------------------------------------------ server side
def test_the_flat_roads_inputs_the_course_does_not_use_hide_while_it_is_ridden(scene: PelotonScene) -> None:
    # A review: Crosswind moved nothing on the course (the picture the same to the pixel) and stayed up; so did the
    # flat road's speed, grade, altitude and headwind. The course rides at a power, on its grades, in its own air.
    c = scene.controls
    flat_only = [c["speed_kmh"], c["rotate"], c["turn_s"], c.folders["Course"], c.folders["Speed at a power"]]
    assert all(handle.visible for handle in flat_only)
    scene.course_mode.enable.value = True
    assert not any(handle.visible for handle in flat_only)
    time_before = scene.course_mode.state.ride.time_s if scene.course_mode.state else None
    c["crosswind_ms"].value = 12.0  # a crafted message to the hidden control changes nothing on the course
    assert scene.course_mode.state is not None and scene.course_mode.state.ride.time_s == time_before
    scene.course_mode.enable.value = False
    assert all(handle.visible for handle in flat_only)


def test_course_mode_opens_off_and_shows_the_sample_when_ticked(scene: PelotonScene) -> None:
    mode = scene.course_mode
    assert not mode.enabled and not mode.frame.visible and scene.course.visible
    assert mode.route_label == SAMPLE_LABEL and mode.state is None
    assert not mode.chart.visible  # no ride yet: no profile over flat zeros
    mode.enable.value = True
    assert mode.enabled and mode.frame.visible and not scene.course.visible
    # Ridden: the chart shows, with the rider's real speed and power along the course.
    assert mode.chart.visible
    _, _, speed_kmh, power_w = (np.asarray(series) for series in mode.chart.data)
    assert np.all(speed_kmh >= 0.0) and speed_kmh.max() > 5.0 and power_w.max() > 100.0
    expected = compute_course(mode.route, CourseParams(), PelotonParams())
    assert mode.state is not None
    assert mode.state.ride.time_s == pytest.approx(expected.ride.time_s, rel=1e-12)
    minutes, seconds = divmod(round(expected.ride.time_s), 60)
    hours, minutes = divmod(minutes, 60)
    assert f"Finish **{hours}:{minutes:02d}:{seconds:02d}**" in mode.readout.content
    assert "published climb profile" in mode.route_info.content
    # The chart: distance, elevation, speed, power, all finite, none NaN-only.
    data = mode.chart.data
    assert len(data) == 4 and all(np.all(np.isfinite(np.asarray(series))) for series in data)
    assert float(np.max(data[0])) == pytest.approx(mode.route.total_distance_m / 1000.0)
    np.testing.assert_allclose(np.asarray(data[3]).max(), 250.0, rtol=1e-6)
    # Splits every km, last one at the finish.
    assert mode.splits.content.count("\n") == 1 + 14
    mode.enable.value = False
    assert scene.course.visible and not mode.frame.visible


def test_the_kernel_rides_with_the_paceline_sharing_the_work(mode: CourseMode) -> None:
    scene = mode.scene
    assert mode.state is not None
    four = mode.state
    line = scene.params
    reduction = cycling.drag_reduction(line.n_riders, line.gap_m, line.model)
    assert four.group_cda_m2 == pytest.approx(line.cda_m2 * (1 - reduction.mean()))
    rider = course_kernel.Rider(cda_m2=four.group_cda_m2, mass_kg=80.0, crr=0.004, drivetrain_efficiency=0.976)
    direct = course_kernel.ride(mode.route, 250.0, rider, max_speed_ms=72.0 / 3.6)
    assert four.ride.time_s == pytest.approx(direct.time_s, rel=1e-12)
    scene.controls["n_riders"].value = 1  # one rider alone: slower
    assert mode.state.ride.time_s > four.ride.time_s
    assert mode.state.group_cda_m2 == line.cda_m2
    scene.controls["n_riders"].value = 6
    assert mode.state.ride.time_s < four.ride.time_s
    assert group_cda(scene.params) < four.group_cda_m2


def test_model_and_air_choices_change_the_ride_and_the_readout_shows_both_densities(mode: CourseMode) -> None:
    assert mode.state is not None
    martin = mode.state.ride.time_s
    mode.controls["model"].value = "Textbook (aero, rolling, climbing)"
    assert mode.params.model == "textbook" and mode.state.ride.time_s < martin  # no bearings, no spokes
    # The textbook atmosphere uses no reading: its inputs are hidden, and the readout names it as the menu does.
    air_inputs = ("temperature_c", "pressure_from_barometer", "pressure_hpa", "humidity_pct")
    assert not any(mode.controls[name].visible for name in air_inputs)
    start = float(mode.route.elevation_m[0])
    textbook = float(cycling.air_density(start))
    assert f"the textbook atmosphere (exponential), **{textbook:.3f}** kg/m³" in mode.readout.content
    mode.controls["air"].value = "Weather reading"
    # A reading's temperature, pressure source and humidity show; the pressure box only for a barometer.
    assert [mode.controls[name].visible for name in air_inputs] == [True, True, False, True]
    mode.controls["temperature_c"].value = 30.0
    mode.controls["humidity_pct"].value = 80.0
    expected = float(cycling.air_density_weather(30.0, cycling.isa_pressure_hpa(start), 0.8))
    assert mode.state.density_weather == pytest.approx(expected, rel=1e-12)
    assert f"the weather reading, **{expected:.3f}** kg/m³ (30 °C, the standard atmosphere's pressure" in (
        mode.readout.content
    )
    assert f"the textbook atmosphere would give {textbook:.3f} kg/m³" in mode.readout.content
    np.testing.assert_allclose(mode.state.ride.air_density[0], expected, rtol=1e-3)
    # A barometer reading replaces the standard atmosphere's pressure.
    mode.controls["pressure_from_barometer"].value = "Barometer"
    assert mode.controls["pressure_hpa"].visible
    mode.controls["pressure_hpa"].value = 1000.0
    assert mode.state.density_weather == pytest.approx(float(cycling.air_density_weather(30.0, 1000.0, 0.8)), rel=1e-12)
    assert "1000 hPa read" in mode.readout.content


def test_find_the_power_for_a_time(mode: CourseMode) -> None:
    mode.controls["target_min"].value = 50.0
    mode.solve.value = True  # what a click does, on the server: runs on_click
    assert mode.state is not None
    assert abs(mode.state.ride.time_s - 50 * 60.0) < 0.5  # the readout's second
    assert mode.controls["power_w"].value == pytest.approx(mode.params.power_w)


@pytest.mark.parametrize("target_min", [90.0, 300.0, 600.0, 700.0])
def test_a_found_power_has_the_digits_its_finish_needs_and_the_box_shows_them(
    mode: CourseMode, target_min: float
) -> None:
    # A power rounded to 0.1 W missed long targets by up to 85 s (700 min at 21.6 W); the box, made with a 5 W step,
    # showed no decimals at all.
    mode.controls["target_min"].value = target_min
    mode.solve.value = True
    assert mode.state is not None
    power, box = mode.params.power_w, mode.controls["power_w"]
    assert abs(mode.state.ride.time_s - target_min * 60.0) < 0.5
    assert isinstance(box, viser.GuiNumberHandle)
    assert round(power, box.precision) == power and box.value == power
    assert round(power, 1) == power or abs(ride_time(mode, round(power, 1)) - target_min * 60.0) >= 0.5  # no finer


@pytest.mark.parametrize("target_min", [45.0, 60.0])
def test_find_the_power_paced_by_grade_finishes_on_the_target(mode: CourseMode, target_min: float) -> None:
    # An outside tester: on 20 km of 60 m rollers, paced by grade at 15 %, "Find the power" for 45 min set 256.6 W
    # and the readout said "Finish 43:39": the power was the constant ride's, the finish shown the paced one's.
    s = np.arange(0.0, 20_000.0 + 5, 10.0)
    rollers = course_kernel.course_from_xy(s, np.zeros_like(s), 60.0 * np.sin(2 * np.pi * s / 4000.0))
    mode.scene.controls["drafting"].value = False
    mode.controls["pacing"].value = True
    assert mode._install(rollers, None, "rollers.gpx")
    mode.controls["target_min"].value = target_min
    mode.solve.value = True
    assert mode.state is not None and mode.state.pacing is not None
    assert abs(mode.state.ride.time_s - target_min * 60.0) < 0.5
    assert f"Finish **{format_duration(target_min * 60.0)}**" in mode.readout.content
    assert mode.state.pacing.time_saved_s > 30.0  # the constant ride at that power is well off the target


def ride_time(mode: CourseMode, power_w: float) -> float:
    mode.controls["power_w"].value = power_w
    assert mode.state is not None
    return mode.state.ride.time_s


def test_pacing_reports_the_time_saved(mode: CourseMode) -> None:
    mode.controls["pacing"].value = True
    assert mode.state is not None and mode.state.pacing is not None
    saved = mode.state.pacing.time_saved_s
    assert saved > 0.5 and f"{round(saved)} s saved" in mode.readout.content
    assert mode.state.ride.average_power_w == pytest.approx(mode.state.constant.average_power_w, rel=1e-6)


# Kind: a signed amount in words. A steady descent paced by grade read "-0 s lost" (an outside tester), and a real
# loss would have read "-5 s lost".
@pytest.mark.parametrize(
    ("saved_s", "words"),
    [(12.4, "12 s saved"), (-5.0, "5 s lost"), (-0.3, "no time saved"), (0.49, "no time saved"), (-0.6, "1 s lost")],
)
def test_a_time_saved_reads_without_a_sign(saved_s: float, words: str) -> None:
    assert time_saved_words(saved_s) == words


def test_pacing_on_a_steady_grade_saves_no_time(mode: CourseMode) -> None:
    points = [(45.0 + i * 1e-4, 6.0, 1000.0 - 0.08 * i * 11.1) for i in range(501)]  # 5.5 km at −8 %
    assert mode.load(gpx_text(points).encode(), "descent.gpx")
    mode.controls["pacing"].value = True
    assert mode.state is not None and mode.state.pacing is not None
    assert abs(mode.state.pacing.time_saved_s) < 0.5  # one grade: pacing by grade changes nothing
    (line,) = [line for line in mode.readout.content.split("\n") if "Pacing by grade" in line]
    assert "**no time saved** at the same average power" in line


def test_exaggeration_stretches_the_drawn_heights(mode: CourseMode) -> None:
    mode.scrub.value = 5.0  # on the climb
    before = glb_vertices(mode.road.glb_data)[:, 2].copy()
    assert np.ptp(before) > 2.0  # the road climbs under the group: ~8 % over ~50 m drawn
    mode.controls["exaggeration"].value = 3.0
    after = glb_vertices(mode.road.glb_data)[:, 2]
    np.testing.assert_allclose(after, 3.0 * before, rtol=1e-4, atol=1e-4)  # heights from the group's middle


def test_play_pause_and_scrub_move_the_riders(mode: CourseMode) -> None:
    scene = mode.scene
    mode.controls["playback"].value = 600.0
    body = mode.course_riders["body"]
    start = np.asarray(body.batched_positions)[0].copy()
    mode._on_play()
    time.sleep(0.6)
    with scene._lock:
        moved = mode.leader_distance_m()
        assert moved > 100.0  # 600× real time for half a second at ~12 km/h
        assert not np.allclose(np.asarray(body.batched_positions)[0], start)
    mode._on_pause()
    with scene._lock:
        held = mode.leader_distance_m()
    time.sleep(0.3)
    assert mode.leader_distance_m() == held
    mode.scrub.value = 10.0
    assert mode.leader_distance_m() == pytest.approx(10_000.0, abs=1.0)
    assert mode.state is not None
    assert "Leader at **10.00 km**" in mode.now.content
    # The riders follow the route: the leader is drawn where the route is at 10 km, in the frame riding with them.
    frame = mode.layout().frame
    where = frame.local(route_points(mode.route, np.array([10_000.0])))
    np.testing.assert_allclose(np.asarray(body.batched_positions)[0], where[0], atol=1e-4)
    # The next rider, as far behind the leader along the road as the line lays it out.
    behind = frame.local(route_points(mode.route, np.array([10_000.0 + scene.state.positions[1, 0]])))
    np.testing.assert_allclose(np.asarray(body.batched_positions)[1], behind[0], atol=1e-4)


def test_every_bad_file_keeps_the_last_good_course(mode: CourseMode) -> None:
    assert mode.load(hill_gpx("Good hill"), "good.gpx")
    good = mode.route
    for kind, (text, message) in BAD_FILES.items():
        assert not mode.load(text.encode(), "bad.gpx"), kind
        assert mode.route is good, kind
        # The panel names the file itself ("bad.gpx was not loaded: ..."), then the kernel's words.
        words = re.sub(r"^\^?the file:? ", "", message).removesuffix("$")
        assert re.search(words, html.unescape(mode.route_info.content)), (kind, mode.route_info.content)
        assert "Still showing **Good hill**" in mode.route_info.content
        # An outside tester: a NaN elevation read "has elevation nan, not a number".
        assert not ERROR_TEXT.search(mode.route_info.content), (kind, mode.route_info.content)
    big = b"<gpx>" + b" " * (course_kernel.MAX_FILE_BYTES + 1)
    assert not mode.load(big, "big.gpx") and "20 MiB" in mode.route_info.content
    many = (
        '<gpx version="1.1"><trk><trkseg>'
        + '<trkpt lat="45" lon="6"><ele>1</ele></trkpt>' * (course_kernel.MAX_POINTS + 1)
        + "</trkseg></trk></gpx>"
    ).encode()
    assert not mode.load(many, "many.gpx") and "200000" in mode.route_info.content
    assert mode.route is good
    # A good file afterwards clears the message.
    mode._on_sample()
    assert mode.route_label == SAMPLE_LABEL and "not loaded" not in mode.route_info.content


def test_file_text_is_escaped_in_the_readouts(mode: CourseMode) -> None:
    name = "&lt;img src=x onerror=alert(1)&gt; [link](http://x) **b**"  # XML-escaped in the file
    assert mode.load(hill_gpx(name), "x.gpx")
    assert mode.route.name.startswith("<img")
    info = mode.route_info.content
    assert "<img" not in info and "](" not in info and "<img src=x onerror=alert(1)>" in html.unescape(info)
    # Bare addresses, which GitHub-flavoured markdown makes links (an outside tester's name "http://x" showed as
    # one), and emphasis, code and strike-through marks: each shown as itself, as a character reference.
    name = "see http://x, www.y.org or a@b.com _it_ `code` ~gone~ \\ #1!"
    assert mode.load(hill_gpx(name), "y.gpx")
    info = mode.route_info.content
    for raw in ("http://", "www.", "@", "_it_", "`", "~", "\\"):
        assert raw not in info, raw
    # The link finder reads the text after character references: there a word joiner (U+2060) breaks each address.
    shown = html.unescape(info)
    for address in ("http://", "www.", "a@"):
        assert address not in shown, address
    assert shown.replace("\u2060", "").count(name) == 1


# ------------------------------------------------------------------------------------------------ over the websocket
def test_upload_a_gpx_from_a_browser(server: viser.ViserServer, mode: CourseMode) -> None:
    with BrowserClient(server.get_port()) as client:
        client.wait_for_gui("Upload GPX")
        upload(client, "Upload GPX", "hill.gpx", hill_gpx("Browser hill", 3000), part=20_000)
        client.wait_for(lambda: mode.route.name == "Browser hill", what="the uploaded course")
        assert mode.route.n_points == 3000
        client.wait_for(
            lambda: any("Browser hill" in str(e["props"].get("_markdown", "")) for e in client.gui.values()),
            what="the client to be shown the new course",
        )
        assert mode.scrub.max == pytest.approx(mode.route.total_distance_m / 1000.0, abs=0.01)


@pytest.mark.parametrize("kind", ["plain text", "one point", "no elevation", "nan latitude", "no track points"])
def test_a_bad_upload_from_a_browser_is_reported(
    server: viser.ViserServer, mode: CourseMode, kind: str, caplog: pytest.LogCaptureFixture
) -> None:
    good = mode.route
    text, message = BAD_FILES[kind]
    with BrowserClient(server.get_port()) as client:
        client.wait_for_gui("Upload GPX")
        transfer = upload(client, "Upload GPX", f"{kind}.gpx", text.encode())
        client.wait_for(
            lambda: any("was not loaded" in str(e["props"].get("_markdown", "")) for e in client.gui.values()),
            what="the message",
        )
        # Told in a notification (once, viser's own "uploaded successfully" was all a person saw there), which takes
        # the place of viser's: the two contradicted each other.
        client.wait_for(lambda: bool(client.notices()), what="the notification")
        kinds = [(m["type"], m.get("uuid")) for _at, m in list(client.received) if "Notification" in m["type"]]
        assert kinds[-2:] == [("RemoveNotificationMessage", f"upload-{transfer}"), ("NotificationShowMessage", ANY)]
        (notice,) = client.notices()
        assert notice["title"] == "GPX not loaded" and notice["color"] == "red"
        assert notice["body"].startswith(f"{kind}.gpx was not loaded: ")
        assert re.search(message, notice["body"]) and notice["body"].endswith(f"Still showing {good.name}.")
    assert mode.route is good
    assert message.split()[0] in mode.route_info.content
    assert not [r for r in caplog.records if r.levelname == "ERROR"]


def test_a_refusal_notice_comes_down_when_the_next_route_is_loaded(server: viser.ViserServer, mode: CourseMode) -> None:
    # An outside tester: after two later good loads, a red "GPX not loaded … Still showing <the old route>" was still
    # up, naming a route no longer shown.
    with BrowserClient(server.get_port()) as client:
        client.wait_for_gui("Upload GPX")
        upload(client, "Upload GPX", "bad.gpx", b"hello, I am not a GPX file")
        client.wait_for(lambda: bool(client.notices()), what="the notice")
        client.wait_for(lambda: len(mode.refusal_notices) == 1, what="the notice kept")
        (shown,) = [m["uuid"] for _at, m in list(client.received) if m["type"] == "NotificationShowMessage"]
        upload(client, "Upload GPX", "good.gpx", hill_gpx("Good hill"))
        client.wait_for(lambda: mode.route.name == "Good hill", what="the good route")
        client.wait_for(
            lambda: any(
                m["type"] == "RemoveNotificationMessage" and m.get("uuid") == shown for _at, m in list(client.received)
            ),
            what="the notice taken down",
        )
        assert not mode.refusal_notices


def test_a_refusal_notice_comes_down_when_the_scene_closes(
    server: viser.ViserServer, mode: CourseMode, switcher: SceneSwitcher
) -> None:
    # An outside tester: a red "GPX not loaded … Still showing Alpe d'Huez" stood over the free kick for the rest of
    # its 15 s after a switch of scene.
    with BrowserClient(server.get_port()) as client:
        client.wait_for_gui("Upload GPX")
        upload(client, "Upload GPX", "bad.gpx", b"hello, I am not a GPX file")
        client.wait_for(lambda: bool(client.notices()), what="the notice")
        (shown,) = [m["uuid"] for _at, m in list(client.received) if m["type"] == "NotificationShowMessage"]
        switcher.show("freekick")
        client.wait_for(
            lambda: any(
                m["type"] == "RemoveNotificationMessage" and m.get("uuid") == shown for _at, m in list(client.received)
            ),
            what="the notice taken down with the scene",
        )


CRAFTED = [
    Crafted("Course power (W)", float("nan"), "power_w", 250.0),
    Crafted("Course power (W)", 1e9, "power_w", 2000.0),
    Crafted("Course power (W)", -5.0, "power_w", 20.0),
    Crafted("Humidity (%)", float("inf"), "humidity_pct", 50.0),
    Crafted("Temp (°C)", 1e6, "temperature_c", 45.0),
    Crafted("Air", "vacuum", "air", "textbook"),
    Crafted("Power model", "<b>x</b>", "model", "martin"),
    Crafted("Pressure from", "guess", "pressure_from_barometer", False),
    Crafted("Safe descending speed (km/h)", 0.0, "max_speed_kmh", 20.0),
    Crafted("Steepness drawn (×)", float("nan"), "exaggeration", 1.0),
]


@pytest.mark.parametrize("crafted", CRAFTED, ids=str)
def test_crafted_course_values_keep_a_good_state(
    server: viser.ViserServer, mode: CourseMode, crafted: Crafted, caplog: pytest.LogCaptureFixture
) -> None:
    with crafted_sent(server.get_port(), crafted, caplog), mode.scene._lock:
        assert getattr(mode.params, crafted.field) == crafted.expected
        assert mode.state is not None and math.isfinite(mode.state.ride.time_s)


@pytest.mark.parametrize("value", [float("nan"), 1e9, -3.0, "far"])
def test_crafted_scrub_positions_are_clamped(server: viser.ViserServer, mode: CourseMode, value: object) -> None:
    with BrowserClient(server.get_port()) as client:
        client.wait_for_gui("Position (km)")
        client.set_value("Position (km)", 4.0)
        client.wait_for(lambda: abs(mode.leader_distance_m() - 4000.0) < 1.0, what="scrub to 4 km")
        client.set_value("Position (km)", value)
        time.sleep(0.2)
        with mode.scene._lock:
            d = mode.leader_distance_m()
            assert 0.0 <= d <= mode.route.total_distance_m
            # The place is a parameter, clamped by the one clean to the loaded route's length.
            if value == 1e9:
                assert d == pytest.approx(mode.route.total_distance_m, rel=1e-12)
                assert mode.params.position_km == mode.scrub.value == mode.scrub.max
            elif value == -3.0:
                assert d == 0.0 and mode.params.position_km == mode.scrub.value == 0.0
            else:
                assert d == pytest.approx(4000.0, abs=1.0) and mode.params.position_km == mode.scrub.value == 4.0


def test_play_from_a_browser(server: viser.ViserServer, mode: CourseMode) -> None:
    with BrowserClient(server.get_port()) as client:
        client.wait_for_gui("Play")
        client.wait_for_gui("Playback speed (×)")
        client.set_value("Playback speed (×)", 600.0)
        client.click("Play")
        client.wait_for(lambda: mode.leader_distance_m() > 200.0, what="the riders to ride")
        client.click("Pause")
        client.wait_for(lambda: not mode.playing, what="pause")
        # The browser's scrub slider follows the leader.
        client.wait_for(
            lambda: isinstance(client.value_of("Position (km)"), float) and client.value_of("Position (km)") > 0.1,
            what="the slider to follow",
        )


# ------------------------------------------------------------------------------------------------ uploads out of order
# Kind: work that finishes out of order. Two uploads close together parse in parallel on viser's pool; the last
# file picked must win even when its parse finishes first.
def _slow_parse_of(monkeypatch: pytest.MonkeyPatch, marker: bytes) -> threading.Event:
    """Make the kernel take a second longer to read a GPX holding ``marker``; the event is set once it has."""
    real = course_kernel.load_gpx
    done = threading.Event()

    def slow(source: bytes, **kwargs: object) -> course_kernel.Course:
        if not isinstance(source, bytes) or marker not in source:  # a new scene loads its sample route by path
            return real(source)
        time.sleep(1.0)
        try:
            return real(source)
        finally:
            done.set()

    monkeypatch.setattr(course_kernel, "load_gpx", slow)
    return done


@pytest.mark.parametrize("then", ["a newer upload", "the sample route"])
def test_the_last_route_chosen_wins_when_an_older_upload_finishes_last(
    server: viser.ViserServer, mode: CourseMode, monkeypatch: pytest.MonkeyPatch, then: str
) -> None:
    # The second failing input (an outside tester): a 12.5 MiB upload, then "Load the sample route" a second later:
    # the sample showed, then the upload replaced it when its parse finished.
    older_done = _slow_parse_of(monkeypatch, b"Older hill")
    with BrowserClient(server.get_port()) as client:
        client.wait_for_gui("Upload GPX")
        assert mode.load(hill_gpx("First hill"), "first.gpx")
        upload(client, "Upload GPX", "older.gpx", hill_gpx("Older hill"))
        time.sleep(0.2)  # the older parse is under way
        if then == "a newer upload":
            upload(client, "Upload GPX", "newer.gpx", hill_gpx("Newer hill"))
            expected = "newer.gpx"
        else:
            client.click("Load the sample route")
            expected = SAMPLE_LABEL
        client.wait_for(lambda: mode.route_label == expected, what="the last route chosen")
        assert older_done.wait(5.0)
        time.sleep(0.3)  # the older parse's install, had it been allowed, has run by now
        # Its tab is told, as for a file still arriving, where the sample route was chosen (an outside tester saw
        # only viser's "File uploaded successfully"); a newer upload says what became of it itself.
        told = [n for n in client.notices() if "older.gpx" in n["body"]]
        if then == "the sample route":
            client.wait_for(lambda: any("older.gpx" in n["body"] for n in client.notices()), what="the tab told")
            (note,) = [n for n in client.notices() if "older.gpx" in n["body"]]
            assert note["title"] == "GPX not loaded"
            assert f"older.gpx was still being read when you chose {SAMPLE_LABEL}, which stays" in note["body"]
            removed = [m.get("uuid") for _at, m in list(client.received) if m["type"] == "RemoveNotificationMessage"]
            assert any(str(u).startswith("upload-") for u in removed)  # viser's "uploaded successfully" went
        else:
            assert told == []
    assert mode.route_label == expected and mode.route.name != "Older hill"


def test_a_file_still_arriving_when_the_sample_route_is_chosen_does_not_replace_it(
    server: viser.ViserServer, mode: CourseMode
) -> None:
    """The kind above, one step earlier: a 17 MiB upload still being sent when "Load the sample route" was pressed
    arrived afterwards and, as the newest file, replaced the sample. A file picked before the user's later choice
    now stays out, and its tab is told."""
    data = hill_gpx("Sent before", 3000)
    half = len(data) // 2
    with BrowserClient(server.get_port()) as client:
        client.wait_for_gui("Upload GPX")
        assert mode.load(hill_gpx("First hill"), "first.gpx")
        _button, transfer = start_upload(client, "Upload GPX", "before.gpx", len(data), 2)
        send_part(client, transfer, 0, data[:half])
        client.wait_for(
            lambda: any(m.get("type") == "FileTransferPartAck" for _at, m in list(client.received)),
            what="the first part taken",
        )
        client.click("Load the sample route")
        client.wait_for(lambda: mode.route_label == SAMPLE_LABEL, what="the sample route")
        send_part(client, transfer, 1, data[half:])
        client.wait_for(lambda: any("before.gpx" in n["body"] for n in client.notices()), what="the tab told")
        time.sleep(0.3)  # an install, had the file been let through, has run by now
        (note,) = [n for n in client.notices() if "before.gpx" in n["body"]]
        assert note["title"] == "GPX not loaded" and "was still arriving when you chose" in note["body"]
        removed = [m.get("uuid") for _at, m in list(client.received) if m["type"] == "RemoveNotificationMessage"]
        assert f"upload-{transfer}" in removed  # viser's "uploaded successfully" is not left beside it
        # A file picked after that choice loads as before.
        upload(client, "Upload GPX", "after.gpx", hill_gpx("Picked after"))
        client.wait_for(lambda: mode.route_label == "after.gpx", what="the later upload")
    assert mode.route.name == "Picked after"


@pytest.mark.parametrize("stage", ["arriving", "being read"])
@pytest.mark.parametrize("then", ["Reset", "a scene switch"])
def test_a_file_the_scene_closed_under_is_told_to_its_tab(
    server: viser.ViserServer,
    switcher: SceneSwitcher,
    mode: CourseMode,
    monkeypatch: pytest.MonkeyPatch,
    stage: str,
    then: str,
) -> None:
    """The kind above, with the scene closed under the file: a Reset or a scene switch while a file arrived or was
    read dropped it, and the tab showed only viser's "File uploaded successfully"."""
    _slow_parse_of(monkeypatch, b"Dropped hill")
    data = hill_gpx("Dropped hill", 3000)
    half = len(data) // 2
    with BrowserClient(server.get_port()) as client, BrowserClient(server.get_port()) as other:
        client.wait_for_gui("Upload GPX")
        other.wait_for_gui("Upload GPX")
        button, transfer = start_upload(client, "Upload GPX", "dropped.gpx", len(data), 2)
        send_part(client, transfer, 0, data[:half])
        if stage == "being read":
            send_part(client, transfer, 1, data[half:])
        client.wait_for(
            lambda: (
                sum(m.get("type") == "FileTransferPartAck" for _at, m in list(client.received))
                == (1 if stage == "arriving" else 2)
            ),
            what="the parts sent so far taken",
        )
        closed = switcher.scene
        if then == "Reset":
            client.click("Reset scene to defaults")
        else:
            client.set_value("Scene", "Arm: FABRIK inverse kinematics")
        client.wait_for(lambda: switcher.scene is not closed, timeout_s=30.0, what="the scene closed")  # a build
        if stage == "arriving":
            client.send(
                "FileTransferPart",
                source_component_uuid=button,
                transfer_uuid=transfer,
                part_index=1,
                content=data[half:],
            )
        client.wait_for(
            lambda: any("dropped.gpx" in n["body"] for n in client.notices()), timeout_s=30.0, what="the tab told"
        )
        (note,) = [n for n in client.notices() if "dropped.gpx" in n["body"]]
        assert note["body"].startswith(f"dropped.gpx was still {stage} when the scene was reset or switched")
        assert note["color"] == "red"
        removed = [m.get("uuid") for _at, m in list(client.received) if m["type"] == "RemoveNotificationMessage"]
        assert f"upload-{transfer}" in removed  # viser's "uploaded successfully" is not left beside it
        # Every tab shares the scene here, and the button's acks showed the upload's progress in the other tab
        # too: its notice goes as well (an outside tester saw "Uploading undefined (6.6M)" stay there for good).
        other.wait_for(
            lambda: any(
                m["type"] == "RemoveNotificationMessage" and m.get("uuid") == f"upload-{transfer}"
                for _at, m in list(other.received)
            ),
            timeout_s=30.0,
            what="the other tab's progress notice taken down",
        )
        assert not any("dropped.gpx" in n["body"] for n in other.notices())  # the refusal is the sender's


def test_an_uploads_acks_reach_only_the_tab_that_sent_it(server: viser.ViserServer, mode: CourseMode) -> None:
    """Every tab shares the scene here, and the upload button's acks were broadcast: viser's client in a tab that
    sent nothing showed "Uploading undefined (6.4M)" with a spinner that never went (an outside tester, with and
    without a Reset)."""
    data = hill_gpx("Shared hill", 3000)
    with BrowserClient(server.get_port()) as sender, BrowserClient(server.get_port()) as other:
        sender.wait_for_gui("Upload GPX")
        other.wait_for_gui("Upload GPX")
        upload(sender, "Upload GPX", "shared.gpx", data, part=len(data) // 3 + 1)
        sender.wait_for(lambda: mode.route_label == "shared.gpx", timeout_s=30.0, what="the file loaded")
        acks = [
            [m for _at, m in list(client.received) if m["type"] == "FileTransferPartAck"] for client in (sender, other)
        ]
        assert len(acks[0]) == 3 and acks[0][-1]["transferred_bytes"] == len(data)
        assert acks[1] == []


# Kind: a place on the route the Position slider cannot reach. Its end was the length rounded down to its 10 m
# step, 1–9 m short of the finish (a 2,127 m route ended at 2.12 km). Its end, the length to the nearest step, is the
# finish.
@pytest.mark.parametrize("n", [10, 17, 300, 1001])
def test_the_position_slider_reaches_the_finish_of_any_route(mode: CourseMode, n: int) -> None:
    assert mode.load(hill_gpx(f"Hill of {n}", n), "hill.gpx")
    total_m = mode.route.total_distance_m
    assert abs(mode.scrub.max - total_m / 1000.0) <= 0.005
    assert mode.scrub.max * 100.0 == pytest.approx(round(mode.scrub.max * 100.0), abs=1e-9)  # on its 0.01 km step
    mode.scrub.value = mode.scrub.max
    assert mode.leader_distance_m() == pytest.approx(total_m, rel=1e-12)
    assert mode.state is not None and mode.play_time_s == pytest.approx(mode.state.ride.time_s, rel=1e-12)


# Kind: state left over from the last course. The Position slider goes back to 0 with a new course.
def test_a_new_course_puts_the_position_slider_back_to_the_start(mode: CourseMode) -> None:
    mode.scrub.value = 1.04
    assert mode.leader_distance_m() == pytest.approx(1040.0, abs=1.0)
    assert mode.load(hill_gpx("Next hill"), "next.gpx")
    assert mode.scrub.value == 0.0 and mode.params.position_km == 0.0
    assert mode.leader_distance_m() == 0.0
    assert "Leader at **0.00 km**" in mode.now.content


# Kind: a found value silently clipped to an input's range. Each target is solved within the input's range or
# the message says plainly, in minutes, that it is out of it (12 min needed > 2000 W; 6000 min < 20 W; 1 min is
# faster than the safe speed allows, whatever the power).
@pytest.mark.parametrize("target_min", [1.0, 12.0, 30.0, 50.0, 90.0, 600.0, 6000.0])
def test_find_the_power_says_when_the_target_is_out_of_the_inputs_range(mode: CourseMode, target_min: float) -> None:
    mode.controls["target_min"].value = target_min
    mode.solve.value = True
    assert mode.state is not None
    ride = mode.state.ride
    content = mode.solve_info.content if mode.solve_info.visible else ""
    assert "time_s" not in content and "max_speed_ms" not in content  # the kernel's words, not the page's
    if mode.controls["power_w"].value == 2000.0 and ride.time_s > target_min * 60.0 + 1.0:
        if target_min == 1.0:  # below 13.20 km at 72 km/h all the way, 659.8 s: beyond any power
            assert (
                "A 1 min finish is out of reach: held to the 72 km/h safe speed, no power rides these 13.2 km in"
                " under 11:00: set to 2000 W" in content
            )
        else:
            assert f"A {target_min:g} min finish needs more than 2000 W, the most this input takes" in content
        assert format_duration(ride.time_s) in content
    elif mode.controls["power_w"].value == 20.0 and ride.time_s < target_min * 60.0 - 1.0:
        assert f"A {target_min:g} min finish needs less than 20 W" in content
    else:
        # The finish the readout shows is the target, to its second (the failing input, an outside tester: 600 min
        # was set to 25.2 W, rounded to 0.1 W, and finished in 9:58:50; 25.151 W takes ten hours).
        assert abs(ride.time_s - target_min * 60.0) < 0.5
        assert format_duration(ride.time_s) == format_duration(target_min * 60.0)
        assert "finish needs" not in content
    assert (target_min == 12.0) == ("more than 2000 W" in content)
    assert (target_min == 1.0) == ("safe speed" in content)
    assert (target_min >= 6000.0) == ("less than 20 W" in content)


# Kind: an out-of-reach note that blames the power where the safe speed bounds the ride. At 20 km/h the sample
# climb's 13.20 km along the slope take at least 39:35 whatever the power; a 30 min target read "needs more than
# 2000 W", and so did 39.5 min while the bound was taken on the map's 13.15 km (39:27).
@pytest.mark.parametrize(
    ("safe_kmh", "target_min", "floor"), [(20.0, 30.0, "39:35"), (20.0, 39.5, "39:35"), (30.0, 20.0, "26:24")]
)
def test_find_the_power_blames_the_safe_speed_where_no_power_is_enough(
    mode: CourseMode, safe_kmh: float, target_min: float, floor: str
) -> None:
    mode.controls["max_speed_kmh"].value = safe_kmh
    mode.controls["target_min"].value = target_min
    mode.solve.value = True
    assert mode.controls["power_w"].value == 2000.0 and mode.state is not None
    assert mode.state.ride.time_s > 13196.41 / (safe_kmh / 3.6)
    content = mode.solve_info.content
    assert f"held to the {safe_kmh:.0f} km/h safe speed, no power rides these 13.2 km in under {floor}" in content
    assert "needs more than" not in content


# The failing input (an outside tester): at a 43 km/h safe speed an 18.5 min target was set to 1894 W, which
# finishes in 18:26, with no word: the search had stalled on the safe speed's kink.
@pytest.mark.parametrize("pacing", [False, True])
def test_find_the_power_hits_a_target_the_safe_speed_nearly_bounds(mode: CourseMode, pacing: bool) -> None:
    mode.controls["max_speed_kmh"].value = 43.0
    mode.controls["pacing"].value = pacing
    mode.controls["target_min"].value = 18.5
    mode.solve.value = True
    assert mode.state is not None
    assert abs(mode.state.ride.time_s - 18.5 * 60.0) < 0.5, mode.controls["power_w"].value
    assert not mode.solve_info.visible


def test_the_out_of_range_note_stays_under_the_button_while_its_target_and_power_are_set(mode: CourseMode) -> None:
    mode.controls["target_min"].value = 1.0
    mode.solve.value = True
    assert mode.controls["power_w"].value == 2000.0
    mode.controls["power_w"].value = 2000.0  # the page's own copy of the power coming back changes nothing
    assert mode.solve_info.visible and "A 1 min finish is out of reach" in mode.solve_info.content
    mode.controls["power_w"].value = 1500.0
    assert not mode.solve_info.visible
    mode.controls["power_w"].value = 2000.0
    mode.controls["target_min"].value = 2.0
    assert not mode.solve_info.visible


def _another_value(handle: Any) -> object:
    """A valid value of GUI input ``handle`` other than its own: the other state, option or a number a step or so
    away."""
    value = handle.value
    if isinstance(value, bool):
        return not value
    options = getattr(handle, "options", None)
    if options is not None:
        return next(option for option in options if option != value)
    low, high, step = (float(getattr(handle, name)) for name in ("min", "max", "step"))
    moved = value + max(step, 0.1 * (high - low))
    return moved if moved <= high else value - max(step, 0.1 * (high - low))


# Kind: a note left up that speaks of an earlier ride. "Set to 2000 W, which finishes in 12:07" stayed under the
# button after Mass was raised to 150 kg (finish 16:39), and after wind and the safe speed changed: the note was kept
# while its target and its power were set, whatever else changed. Every input the ride depends on, and a new route,
# now take it down; the view's inputs and the page's own copy of a value coming back leave it.
@pytest.mark.parametrize("name", [*RIDE_INPUTS, *LINE_INPUTS])
def test_the_out_of_range_note_goes_with_any_input_that_changes_the_ride(
    scene: PelotonScene, mode: CourseMode, name: str
) -> None:
    mode.controls["target_min"].value = 1.0
    mode.solve.value = True
    assert mode.solve_info.visible and "A 1 min finish is out of reach" in mode.solve_info.content
    for view in ("exaggeration", "playback"):
        mode.controls[view].value = _another_value(mode.controls[view])
    assert mode.solve_info.visible
    handle = mode.controls[name] if name in RIDE_INPUTS else scene.controls[name]
    handle.value = handle.value  # the page's copy coming back
    assert mode.solve_info.visible
    handle.value = _another_value(handle)
    assert not mode.solve_info.visible, f"{name} = {handle.value!r}"


def test_the_out_of_range_note_goes_with_a_new_route(mode: CourseMode) -> None:
    mode.controls["target_min"].value = 1.0
    mode.solve.value = True
    assert mode.solve_info.visible
    assert mode.load(hill_gpx("Next hill"), "next.gpx")
    assert not mode.solve_info.visible


# Kind: code names and unexplained numbers in the readout.
def test_the_readout_names_the_model_by_its_label_and_explains_coasting(mode: CourseMode) -> None:
    assert "(Martin et al. 1998 (full))" in mode.readout.content
    assert "martin model" not in mode.readout.content
    mode.controls["model"].value = "Textbook (aero, rolling, climbing)"
    assert "(Textbook (aero, rolling, climbing))" in mode.readout.content
    # 2 km at −20 %: 250 W would go far past the 72 km/h cap, so the riders coast and brake.
    down = [(45.0 + i * 1e-4, 6.0, 1000.0 - 0.2 * 11.1195 * i) for i in range(180)]
    assert mode.load(gpx_text(down).encode(), "down.gpx")
    assert mode.state is not None
    average = mode.state.ride.average_power_w
    assert average < 100.0
    assert (
        f"Average {average:.0f} W of the 250 W set: the riders ease off or coast where 250 W would take them "
        "over the 72 km/h safe speed"
    ) in mode.readout.content
    mode.scrub.value = 1.5
    assert "(coasting at the 72 km/h safe speed)" in mode.now.content


@pytest.mark.parametrize(
    ("length_m", "last_rows"),
    [
        (20_010.5, ["20.0", "20.01"]),
        (20_001.0, ["20.0", "20.001"]),
        (20_400.0, ["20.0", "20.4"]),
        (5_003.0, ["5.0", "5.003"]),
        (5_000.4, ["4.0", "5.0"]),  # within half a metre: one row, not "5.0" and "5.000" at one time
        (5_000.04, ["4.0", "5.0"]),
        (130.2, ["0.13"]),
        (1_000.6, ["1.0", "1.001"]),
    ],
)
def test_the_finish_split_reads_to_the_metre_and_apart_from_the_whole_split_before_it(
    mode: CourseMode, length_m: float, last_rows: list[str]
) -> None:
    # Outside testers: a 20.0105 km route's splits ended "20.0 | 43:38" then "20.0 | 43:39"; then 5000.4 m read
    # "5.0" and "5.000" at the same second, and a 130.2 m route's one row "0.1".
    s = np.linspace(0.0, length_m, 2001)
    assert mode._install(course_kernel.course_from_xy(s, np.zeros_like(s), np.zeros_like(s)), None, "flat.gpx")
    rows = [row.split("|")[1].strip() for row in mode.splits.content.splitlines()[2:]]
    assert rows[-len(last_rows) :] == last_rows and len(set(rows)) == len(rows), rows
    assert abs(float(rows[-1]) * 1000.0 - length_m) <= 0.5 + 1e-9  # the finish, to the metre


@pytest.mark.parametrize(
    ("end_m", "words"), [(-0.004, "(0.0 % on average)"), (0.004, "(0.0 % on average)"), (-30.0, "(-0.6 % on average)")]
)
def test_a_route_ending_where_it_starts_reads_no_signed_zero(mode: CourseMode, end_m: float, words: str) -> None:
    # An outside tester: a 5 km loop that ends at the height it starts read "(-0.0 % on average)".
    s = np.linspace(0.0, 5000.0, 501)
    z = 40.0 * np.sin(2 * np.pi * s / 2500.0) + end_m * s / 5000.0
    assert mode._install(course_kernel.course_from_xy(s, np.zeros_like(s), z), None, "loop.gpx")
    assert words in mode.route_info.content, mode.route_info.content


def test_pedalling_less_to_hold_the_safe_speed_on_a_climb_is_not_called_coasting(mode: CourseMode) -> None:
    # An outside tester: a bunch at 2000 W up 6.5 % read "72.0 km/h, the group's 1431 W (coasting at the 72 km/h
    # safe speed)". The riders pedal 1431 W: they ease off, they do not coast.
    up = [(45.0 + i * 1e-4, 6.0, 1000.0 + 0.03 * 11.1195 * i) for i in range(180)]
    assert mode.load(gpx_text(up).encode(), "up.gpx")
    mode.controls["power_w"].value = 2000.0
    mode.scrub.value = 1.5
    assert mode.state is not None
    assert mode.state.ride.speed_ms.max() == pytest.approx(20.0, rel=1e-6)  # the cap holds it
    content = mode.now.content
    watts = re.search(r"(\d+) W \(easing off to hold the 72 km/h safe speed\)", content)
    assert watts is not None and 100 < int(watts.group(1)) < 2000, content
    assert "coasting" not in content


# Kind: bad files, through the scene: refused in a rider's words, the last good course kept.
REVIEW_FILES = {
    "vertical": (
        '<?xml version="1.0"?><gpx version="1.1" creator="r"><trk><trkseg><trkpt lat="45" lon="6"><ele>100</ele>'
        '</trkpt><trkpt lat="45.0000001" lon="6"><ele>600</ele></trkpt><trkpt lat="45.0000002" lon="6">'
        "<ele>1100</ele></trkpt></trkseg></trk></gpx>",
        "was not loaded: the elevation changes 4 496 602 % of the distance near 0.00 km; no road is steeper",
    ),
    "nan elevation": (
        gpx_text([(45.0, 6.0, 1.0), (45.001, 6.0, float("nan"))]),
        "was not loaded: track point 2's elevation is not a number",
    ),
    "not gpx": ("<html><body>hi</body></html>", "was not loaded: it is not GPX: no <gpx>"),
}


@pytest.mark.parametrize("kind", list(REVIEW_FILES))
def test_bad_files_are_refused_in_a_riders_words(mode: CourseMode, kind: str) -> None:
    good = mode.route
    text, message = REVIEW_FILES[kind]
    assert not mode.load(text.encode(), f"{kind}.gpx")
    assert mode.route is good
    shown = html.unescape(mode.route_info.content)  # the file's words are shown as character references
    assert message in shown
    for word in ("elevation_m", "latitude_deg", "non-finite", "time_s", "GPX is not"):
        assert word not in shown


def test_the_riders_keep_their_place_when_the_ride_changes(mode: CourseMode) -> None:
    """The Position slider and the leader's readout say the same place after a change that makes the ride faster or
    slower, and after the mode is hidden, the formation changed and the mode shown again (a reviewer saw 5.57 km
    beside a slider at 5.5: the riders had kept the time of the old ride, not their place)."""
    scene = mode.scene
    mode.scrub.value = 5.5
    assert mode.leader_distance_m() == pytest.approx(5500.0, abs=1e-6)
    mode.controls["power_w"].value = 400.0  # a faster ride: the same time is further up the road
    assert mode.leader_distance_m() == pytest.approx(5500.0, abs=1e-6)
    assert "Leader at **5.50 km**" in mode.now.content and mode.scrub.value == 5.5
    mode.enable.value = False
    scene.controls["formation"].value = "Bunch (peloton)"
    scene.controls["n_riders"].value = 30
    mode.enable.value = True
    assert mode.leader_distance_m() == pytest.approx(5500.0, abs=1e-6)
    assert "Leader at **5.50 km**" in mode.now.content and mode.scrub.value == 5.5
    # Pause snaps the riders to the slider's step, so the two agree to the last digit shown.
    mode.controls["playback"].value = 600.0
    mode._on_play()
    time.sleep(0.4)
    mode._on_pause()
    assert mode.leader_distance_m() == pytest.approx(1000.0 * float(mode.scrub.value), abs=1e-6)
    assert f"Leader at **{float(mode.scrub.value):.2f} km**" in mode.now.content


def test_the_road_and_riders_lie_where_the_route_runs() -> None:
    """The drawn frame: the leader at the route's point, the road's centre under it, each rider on the road's
    surface, nose along the road and pitched by the drawn grade (a turn of +x by the rider's wxyz)."""
    route = course_kernel.load_gpx(course_kernel.SAMPLE_ROUTE)
    xy = cycling.formation(30, "bunch", gap_m=0.5, lateral_m=0.6)
    layout = lay_out_road(route, 6000.0, xy, 2.0)
    positions, wxyz = layout.riders
    centre, tangent = layout.frame.along(route, 6000.0 + xy[:, 0])
    # Across the road by each rider's lateral offset, level with its centre line.
    offset = positions - centre
    np.testing.assert_allclose(np.abs(offset[:, 2]), 0.0, atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(offset[:, :2], axis=1), np.abs(xy[:, 1]), atol=1e-9)
    # Each rider's nose (+x turned by its quaternion) points along the road, its grade included.
    w, x, y, z = wxyz.T
    nose = np.stack([1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)], axis=1)
    np.testing.assert_allclose(nose, tangent, atol=1e-9)
    assert np.all(tangent[:, 2] > 0.05)  # 8 % up, drawn 2x: 16 %
    # The road runs under the whole group and 30 m ahead of the leader; the window says so.
    d_from, d_to = layout.window_m
    assert d_from <= 6000.0 + xy[:, 0].min() - 10.0 and d_to == pytest.approx(6030.0)
    assert layout.marks == {"Start": None, "Finish": None}
    at_start = lay_out_road(route, 0.0, xy, 1.0)
    assert at_start.marks["Start"] is not None and at_start.marks["Finish"] is None


@pytest.mark.parametrize("mark", ["Start", "Finish"])
def test_the_start_and_finish_lines_are_painted_across_the_road_at_the_leaders_front_wheel(mark: str) -> None:
    # An outside tester: at 0.00 km the start line, a 0.25 m tube, lay under the leader's rear wheel, ran past the
    # road's edge onto the grass, and its label floated 2.2 m over the far edge.
    route = course_kernel.load_gpx(course_kernel.SAMPLE_ROUTE)
    xy = cycling.formation(4, "single", gap_m=0.5, lateral_m=0.6)
    at = 0.0 if mark == "Start" else route.total_distance_m
    layout = lay_out_road(route, at, xy, 1.0)
    band = layout.marks[mark]
    assert band is not None
    vertices, faces = band
    assert vertices.shape == (4, 3) and faces.shape == (2, 3)
    # Flat on the road, a few mm over it, exactly as wide as the road, 0.3 m along it.
    centre, tangent = layout.frame.along(route, np.array([at + 0.5 * BIKE_LENGTH_M]))
    left, right = vertices[:2].mean(axis=0), vertices[2:].mean(axis=0)
    np.testing.assert_allclose(0.5 * (left + right), centre[0] + [0.0, 0.0, 0.006], atol=0.02)
    assert np.linalg.norm(left - right) == pytest.approx(2.0 * layout.half_width_m, rel=1e-6)
    assert np.linalg.norm(vertices[1] - vertices[0]) == pytest.approx(MARK_WIDTH_M, rel=0.05)
    # The leader's front wheel (half a bike ahead of his centre) is on it.
    leader, _ = layout.riders
    front = leader[0] + 0.5 * BIKE_LENGTH_M * tangent[0]
    np.testing.assert_allclose(front[:2], centre[0][:2], atol=0.02)


def _surface_heights(vertices: np.ndarray, faces: np.ndarray, points_xy: np.ndarray) -> np.ndarray:
    """(P,) the highest height of the triangle mesh straight above or below each (P, 2) point; −inf where no
    triangle covers it (barycentric test in plan, either winding)."""
    a, b, c = (vertices[faces[:, k]].astype(np.float64) for k in range(3))
    p = points_xy[:, None, :]
    v0, v1, v2 = (b - a)[None, :, :2], (c - a)[None, :, :2], p - a[None, :, :2]
    d00, d01, d11 = (v0 * v0).sum(-1), (v0 * v1).sum(-1), (v1 * v1).sum(-1)
    d20, d21 = (v2 * v0).sum(-1), (v2 * v1).sum(-1)
    denom = d00 * d11 - d01 * d01
    ok = np.abs(denom) > 1e-12
    safe = np.where(ok, denom, 1.0)
    v, w = (d11 * d20 - d01 * d21) / safe, (d00 * d21 - d01 * d20) / safe
    inside = ok & (v >= -1e-9) & (w >= -1e-9) & (v + w <= 1 + 1e-9)
    z = a[None, :, 2] + v * (b - a)[None, :, 2] + w * (c - a)[None, :, 2]
    return np.where(inside, z, -np.inf).max(axis=1)


@pytest.mark.parametrize("shape", ["bunch", "echelon", "double"])
@pytest.mark.parametrize("exaggeration", [1.0, 5.0])
def test_every_rider_stands_on_the_drawn_road_with_no_grass_over_it(
    shape: cycling.FormationShape, exaggeration: float
) -> None:
    """At every 100 m of the sample climb, 121 riders: the road strip never folds over itself (its faces all face
    up), every rider stands on it (a road face under each, at the rider's height), and no grass lies over the road
    where a rider stands. The route is a polyline: at its corners the road folded and the back rows of a bunch stood
    on the grass beside it; a verge just under the road rose through it in stripes where the road bends and climbs."""
    route = course_kernel.load_gpx(course_kernel.SAMPLE_ROUTE)
    xy = cycling.formation(121, shape, gap_m=0.5, lateral_m=0.6)
    for leader_m in np.arange(200.0, float(route.total_distance_m), 100.0):
        layout = lay_out_road(route, float(leader_m), xy, exaggeration)
        road_v, road_f = layout.road
        a, b, c = (road_v[road_f[:, k]].astype(np.float64) for k in range(3))
        assert np.all(np.cross(b - a, c - a)[:, 2] > 0.0), f"the road folds at {leader_m:.0f} m"
        riders = layout.riders[0]
        on_road = _surface_heights(road_v, road_f, riders[:, :2])
        # A road face under every rider (none: it stood on the grass), at its height to within 0.2 m, less than a
        # wheel's radius (the strip's faces are planar, so on a steeply drawn climb they cut a bend's chord).
        assert np.all(np.abs(on_road - riders[:, 2]) < 0.2), f"a rider off the road at {leader_m:.0f} m"
        grass = _surface_heights(*layout.verge, riders[:, :2])
        assert np.all(grass < on_road), f"grass over the road at {leader_m:.0f} m"


def test_a_bunch_rides_the_course_at_its_formations_mean_drag(mode: CourseMode) -> None:
    scene = mode.scene
    assert mode.state is not None
    line_of_four = mode.state.ride.time_s
    scene.controls["formation"].value = "Bunch (peloton)"
    scene.controls["n_riders"].value = 121
    scene.controls["gap_m"].value = 0.3
    assert mode.state is not None
    positions = cycling.formation(121, "bunch", gap_m=0.3, lateral_m=0.6)
    mean_drag = float(np.mean(cycling.formation_drag(positions)))
    assert 0.10 < mean_drag < 0.25  # most of a 121-rider bunch rides at 5-10 % of a lone rider's drag
    assert mode.state.group_cda_m2 == pytest.approx(scene.params.cda_m2 * mean_drag, rel=1e-12)
    rider = course_kernel.Rider(cda_m2=mode.state.group_cda_m2, mass_kg=80.0, crr=0.004, drivetrain_efficiency=0.976)
    direct = course_kernel.ride(mode.route, 250.0, rider, max_speed_ms=72.0 / 3.6)
    assert mode.state.ride.time_s == pytest.approx(direct.time_s, rel=1e-12)
    assert mode.state.ride.time_s < line_of_four  # sharing a bunch's shelter is faster than a line of four
    assert "121 riders in a bunch" in mode.readout.content
    # One account of how a bunch shares the work, on the flat road and on the course: riders in a bunch do not take
    # turns in order (the flat road says so), so the course does not say they take turns at every place.
    for words in (mode.readout.content, scene.density.content):
        assert "take turns" not in words and "sharing the work" not in words
    assert "the speed at which its places' powers average the course power" in scene.density.content
    # The course draws the whole group as it rides: 121 rider instances at life size, each where its formation
    # puts it (on this straight start, metres behind the leader along the road and across it), on the road.
    scales = np.asarray(mode.course_riders["body"].batched_scales)
    assert np.all(scales[:121] == 1.0) and np.all(scales[121:] == 0.0)
    drawn = np.asarray(mode.course_riders["body"].batched_positions)[:121].astype(np.float64)
    relative = drawn - drawn[0]
    heading = np.arctan2(relative[-1, 1], relative[-1, 0]) - np.arctan2(positions[-1, 1], positions[-1, 0])
    c, s = np.cos(heading), np.sin(heading)
    turned = np.stack([c * positions[:, 0] - s * positions[:, 1], s * positions[:, 0] + c * positions[:, 1]], 1)
    np.testing.assert_allclose(relative[:, :2], turned, atol=0.05)  # the formation, turned to the road
    layout = mode.layout()
    assert layout.half_width_m >= 2.1 + 0.5  # the road holds the bunch's width
    assert len({tuple(np.round(p, 3)) for p in drawn}) == 121


# ------------------------------------------------------------------------------------------------ places' power
def _place_watts_reference(mode: CourseMode, at_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Each place's power where the leader is ``at_m`` and over the ride, written out: the group's power plus the
    aero power ½·ρ·(v + w)·|v + w|·v/η of the place's drag area above (or below) the group's, at the speed at
    ``at_m`` (interpolated between the route's points) and, over the ride, at each segment's mean speed."""
    state, line = mode.state, mode.scene.params
    assert state is not None
    ride = state.ride
    positions = cycling.formation(line.n_riders, line.formation, gap_m=line.gap_m, lateral_m=0.6)
    drag = (
        1.0 - cycling.drag_reduction(line.n_riders, line.gap_m, line.model)
        if line.formation == "single"
        else cycling.formation_drag(positions, line.model)
    )
    cda = line.cda_m2 * drag
    group = float(np.mean(cda))
    eta = line.drivetrain_pct / 100.0
    dt = np.diff(ride.elapsed_s)
    v = np.diff(ride.distance_m) / dt
    air = v + ride.headwind_ms
    per_m2 = 0.5 * ride.air_density * air * np.abs(air) * v / eta
    j = min(int(np.searchsorted(ride.distance_m, at_m, side="right")) - 1, len(ride.headwind_ms) - 1)
    v_here = np.interp(at_m, ride.distance_m, ride.speed_ms)
    air_here = v_here + ride.headwind_ms[j]
    here = ride.power_w[j] + (cda - group) * 0.5 * ride.air_density[j] * air_here * abs(air_here) * v_here / eta
    mean = ride.work_j / ride.time_s + (cda - group) * float(np.sum(per_m2 * dt) / np.sum(dt))
    return here, mean


@pytest.mark.parametrize(("shape", "n"), [("Single file", 4), ("Bunch (peloton)", 40)])
def test_where_the_group_brakes_no_place_pedals_and_each_places_mean_counts_only_its_pedalling(
    mode: CourseMode, shape: str, n: int
) -> None:
    # The failing input (an outside tester): 5.5 km at −30 %, 250 W. At 5 km the group held the 72 km/h cap on its
    # brakes (about 3 kW of them), yet the leader's place read 419 W and the places' ride means 342 W, with the
    # lone rider coasting: the places ignored the braking.
    scene = mode.scene
    scene.controls["formation"].value, scene.controls["n_riders"].value = shape, n
    down = [(45.0 + i * 1e-4, 6.0, 2000.0 - 0.3 * 11.1195 * i) for i in range(495)]
    assert mode.load(gpx_text(down).encode(), "descent.gpx")
    state = mode.state
    assert state is not None
    ride = state.ride
    mode.scrub.value = 5.0
    at = mode.leader_distance_m()
    j = int(np.searchsorted(ride.distance_m, at, side="right")) - 1
    assert ride.brakes_w[j] > 1000.0 and ride.power_w[j] == 0.0
    here, mean = mode.place_watts()
    np.testing.assert_array_equal(here, np.zeros(n))
    # Each place's mean, segment by segment: the group's power less its brakes (at the pedals), plus the place's
    # own aero difference, never below 0, averaged by time.
    eta = scene.params.drivetrain_pct / 100.0
    cda = state.rider_cda_m2 * np.asarray(state.drag)
    dt = np.diff(ride.elapsed_s)
    v = np.diff(ride.distance_m) / dt
    air = v + ride.headwind_ms
    per_m2 = 0.5 * ride.air_density * air * np.abs(air) * v / eta
    reference = [
        sum(
            max(ride.power_w[k] - ride.brakes_w[k] / eta + (cda[i] - state.group_cda_m2) * per_m2[k], 0.0) * dt[k]
            for k in range(len(dt))
        )
        / ride.time_s
        for i in range(n)
    ]
    np.testing.assert_allclose(mean, reference, rtol=1e-9)
    assert float(np.max(mean)) < 2.0 * ride.average_power_w  # not the 342 W the braking hid
    table = scene.table.content.splitlines()
    assert "| Drag (%) | Here | Ride mean |" in scene.table.content
    assert "**0**" in table[4]
    assert "the leader's place 0 W" in mode.now.content


@pytest.mark.parametrize(("shape", "n"), [("Bunch (peloton)", 121), ("Single file", 8), ("Single file", 1)])
def test_the_leader_readout_gives_the_groups_power_and_the_leaders_place(mode: CourseMode, shape: str, n: int) -> None:
    # The failing input (a review): at 13.15 km "Leader at 13.15 km … 250 W" while the table's row 1 said 277 W:
    # the 250 W was the group's.
    scene = mode.scene
    scene.controls["formation"].value, scene.controls["n_riders"].value = shape, n
    mode.scrub.value = 13.15
    assert mode.state is not None
    ride = mode.state.ride
    # 13.15 km is the sample's finish (13 151 m), the Position slider's end: the last segment's power.
    segment = min(
        int(np.searchsorted(ride.distance_m, mode.leader_distance_m(), side="right")) - 1, len(ride.brakes_w) - 1
    )
    group = float(ride.power_w[segment])
    here, _ = _place_watts_reference(mode, mode.leader_distance_m())
    text = mode.now.content
    if n == 1:
        assert f", {group:.0f} W" in text and "place" not in text
    else:
        assert f"the group's {group:.0f} W" in text and f"the leader's place {float(here[0]):.0f} W" in text
        assert f"**{round(float(here[0]))}**" in scene.table.content.splitlines()[4]


def test_at_a_standing_start_every_place_needs_the_groups_power(mode: CourseMode) -> None:
    # The failing input (a review): at 0.00 km and 0.0 km/h a bunch of 121's places read 247–257 W, the aero term of
    # the first segment's mean speed; standing still, no place has any air to push.
    scene = mode.scene
    scene.controls["formation"].value, scene.controls["n_riders"].value = "Bunch (peloton)", 121
    mode.scrub.value = 0.0
    assert mode.state is not None and mode.state.ride.speed_ms[0] == 0.0
    here, _ = mode.place_watts()
    np.testing.assert_allclose(here, float(mode.state.ride.power_w[0]), rtol=1e-12)
    reference, _ = _place_watts_reference(mode, mode.leader_distance_m())
    np.testing.assert_allclose(here, reference, rtol=1e-9)


@pytest.mark.parametrize(("shape", "n"), [("Bunch (peloton)", 40), ("Bunch (peloton)", 121), ("Single file", 8)])
def test_course_mode_colours_each_rider_by_its_places_power_with_a_legend_and_the_courses_table(
    mode: CourseMode, shape: str, n: int
) -> None:
    # The failing look (a review): on the course a bunch kept the flat road's jerseys and Results table, and showed
    # no power legend.
    from scenes.peloton.legend import power_colours, power_range

    scene = mode.scene
    scene.controls["formation"].value, scene.controls["n_riders"].value = shape, n
    mode.scrub.value = 6.0  # on the climb
    here, mean = _place_watts_reference(mode, mode.leader_distance_m())
    assert mode.leader_distance_m() == pytest.approx(6000.0, abs=1.0)
    assert mode.state is not None
    ride_power_here = float(mode.state.ride.power_w[np.searchsorted(mode.state.ride.distance_m, 6000.0) - 1])
    # The places average the group's power (it rides at their mean drag); the leader works hardest.
    assert float(np.mean(here)) == pytest.approx(ride_power_here, rel=1e-9)
    assert float(np.mean(mean)) == pytest.approx(mode.state.ride.average_power_w, rel=1e-9)
    assert int(np.argmax(here)) == 0 and here[0] > ride_power_here + 1.0
    got_here, got_mean = mode.place_watts()
    np.testing.assert_allclose(got_here, here, rtol=1e-9)
    np.testing.assert_allclose(got_mean, mean, rtol=1e-9)
    # Each rider's jersey in its place's colour, on the legend's scale, which says the watts.
    bodies = np.asarray(mode.course_riders["body"].batched_colors)[:n]
    low, high = power_range(here)
    np.testing.assert_array_equal(bodies, power_colours(here, low, high))
    legend = scene.legend.content
    assert scene.legend.visible and "power here (W)" in legend
    assert f"{round(low)} W</div>" in legend and f"{round(high)} W</div>" in legend
    # The Results table is the course's: each place's drag, its power here and over the ride.
    table = scene.table.content
    assert "| Drag (%) | Here | Ride mean |" in table and "CdA (m²)" not in table
    assert f"**{round(float(here[0]))}**" in table.splitlines()[4]
    # The panel says the group rides at its formation's mean drag.
    assert "rides at the mean drag of its formation" in scene.density.content
    assert f"CdA {mode.state.group_cda_m2:.3f} m²" in scene.density.content
    assert not scene.chart.visible
    # Back on the flat road: its own table, legend and chart again.
    mode.enable.value = False
    assert "CdA (m²)" in scene.table.content or "Power (W)" in scene.table.content
    assert not scene.legend.visible or "power here" not in scene.legend.content
    assert scene.chart.visible and scene.legend.visible == (shape != "Single file")


def test_the_places_colours_follow_the_riders_along_the_course(mode: CourseMode) -> None:
    scene = mode.scene
    scene.controls["formation"].value, scene.controls["n_riders"].value = "Bunch (peloton)", 40
    mode.scrub.value = 0.5
    first = np.asarray(mode.course_riders["body"].batched_colors)[:40].copy()
    legend = scene.legend.content
    mode.scrub.value = 12.0
    assert scene.legend.content != legend and "12.00 km" in scene.legend.content
    here, _ = _place_watts_reference(mode, mode.leader_distance_m())
    from scenes.peloton.legend import power_colours, power_range

    np.testing.assert_array_equal(
        np.asarray(mode.course_riders["body"].batched_colors)[:40], power_colours(here, *power_range(here))
    )
    assert first.shape == (40, 3)


# ------------------------------------------------------------------------------------------------ camera
def _course_rider_boxes(mode: CourseMode, n: int) -> np.ndarray:
    """(n, 8, 3) corners of each drawn course rider's box (1.70 m by 0.6 m, road to the top of its head), turned
    by its drawn quaternion, from the rider handles."""
    positions = np.asarray(mode.course_riders["body"].batched_positions, dtype=np.float64)[:n]
    w, x, y, z = np.asarray(mode.course_riders["body"].batched_wxyzs, dtype=np.float64)[:n].T
    top = rider_head_m(mode.scene.params.position)[1]
    local = np.array([(sx * 0.85, sy * 0.3, h) for sx in (-1, 1) for sy in (-1, 1) for h in (0.0, top)])
    # v' = v + 2w(q × v) + 2 q × (q × v), q = (x, y, z): the quaternion's turn written out.
    q = np.stack([x, y, z], axis=1)[:, None, :]
    v = np.broadcast_to(local, (n, 8, 3))
    t = 2.0 * np.cross(q, v)
    return positions[:, None, :] + v + w[:, None, None] * t + np.cross(q, t)


@pytest.mark.parametrize("km", [3.0, 9.0])  # a straight, a hairpin
@pytest.mark.parametrize("viewport", VIEWPORTS)
@pytest.mark.parametrize(
    ("shape", "n"),
    [("Single file", 8), ("Two abreast", 8), ("Bunch (peloton)", 40), ("Bunch (peloton)", 121), ("Single file", 121)],
)
def test_the_course_camera_frames_the_group_left_of_the_panel_and_clear_of_the_notice(
    mode: CourseMode, viewport: tuple[int, int], shape: str, n: int, km: float
) -> None:
    # The failing look (a review): the course's camera put riders under viser's software-WebGL notice, drew a single
    # file of 121 as dots and two abreast of 8 from a metre away.
    scene = mode.scene
    scene.controls["formation"].value, scene.controls["n_riders"].value = shape, n
    mode.scrub.value = km
    lens = Lens(math.radians(75.0), *viewport)
    view = scene._view_for(lens)
    boxes = _course_rider_boxes(mode, n)
    framed = mode.framed_riders()
    behind = -cycling.formation(n, "single" if shape == "Single file" else FORMATION[shape], gap_m=0.5, lateral_m=0.6)
    # Every rider within 45 m of the leader is framed: all of every group here but the single file of 121.
    assert framed == int(np.count_nonzero(behind[:, 0] <= 45.0)) and (framed == n) == (
        n != 121 or shape != "Single file"
    )
    x, y, depth = pinhole_ndc(
        boxes[:framed].reshape(-1, 3), np.array(view.position), np.array(view.look_at), lens.fov_rad, lens.aspect
    ).T
    assert np.all(depth > 0.0)
    px = np.stack([(x + 1) / 2 * lens.width_px, (1 - y) / 2 * lens.height_px], axis=1)
    width, height = viewport
    assert px.min() >= 0.5 * MARGIN_PX and px[:, 1].max() <= height - 0.5 * MARGIN_PX, (px.min(0), px.max(0))
    assert px[:, 0].max() <= width - PANEL_PX, px.max(0)
    under = (px[:, 0] < NOTICE_PX[0]) & (px[:, 1] < NOTICE_PX[1])
    assert not under.any(), f"{shape} of {n}: {under.sum()} rider corners under the notice"
    # Riders a person can make out (before, a single file of 121 drew them 4-6 px tall), and none so close that it
    # stands over 30 % of the window tall (before, two abreast of 8: 34-37 %).
    tall = np.ptp(px.reshape(framed, 8, 2)[:, :, 1], axis=1)
    least = {(1600, 1000): 30.0, (1280, 720): 21.0}[viewport]
    assert np.percentile(tall, 10) >= least and tall.max() <= 0.3 * height, (np.percentile(tall, 10), tall.max())
    if framed < n:
        assert f"front 45 m of the group (its first {framed} riders)" in scene.density.content
    else:
        assert "front 45 m" not in scene.density.content


@pytest.mark.parametrize("start_m", [-430.0, -700.0, -2000.0, -9000.0, 8848.0, 9900.0])
def test_the_weather_reading_is_taken_at_any_start_a_course_may_have(start_m: float) -> None:
    # Below about −700 m the standard atmosphere reads more than 1100 hPa, so the reading at the start was refused
    # (a route's elevations may be ±10 km); the reading is now held to the pressures it takes.
    x = np.linspace(0.0, 5000.0, 100)
    route = course_kernel.course_from_xy(x, 0.0 * x, start_m + 0.01 * x)
    air = course_air(route, CourseParams(air="weather"))
    density = air.density(route.elevation_m)
    assert np.isfinite(density).all() and (density > 0.0).all()
    assert air.pressure_hpa <= 1100.0 and air.altitude_m == route.elevation_m[0]


# ---------------------------------------------------------------------------------------------- outside tester's faults
def north_gpx(name: str, length_m: float, elevation_m: float = 100.0) -> bytes:
    """A straight, level route due north from 45° N 6° E, ``length_m`` along the ground, points about 100 m apart."""
    n = max(2, math.ceil(length_m / 100.0) + 1)
    step_deg = length_m / (n - 1) / (course_kernel.EARTH_RADIUS_M * math.pi / 180.0)
    text = gpx_text([(45.0 + i * step_deg, 6.0, elevation_m) for i in range(n)])
    return text.replace("<name>t</name>", f"<name>{name}</name>").encode()


# Kind: a route too short to ride or draw. Two points 1.1 cm apart rode to "Finish 0:00, average 1.1 km/h", "alone
# the same power takes 0:00", a chart ticked "0 0 0" and Start and Finish labels on top of each other.
@pytest.mark.parametrize("length_m", [0.011, 9.99, 99.9])
def test_a_route_too_short_to_ride_is_refused_in_the_panel(mode: CourseMode, length_m: float) -> None:
    good = mode.route
    assert not mode.load(north_gpx("Short", length_m), "short.gpx")
    assert mode.route is good and mode.route_label == SAMPLE_LABEL
    shown = html.unescape(mode.route_info.content)
    print(shown.splitlines()[-1])
    assert "was not loaded: the track is " in shown and "a course needs 100 m or more" in shown
    assert "Finish **0:00**" not in mode.readout.content
    assert mode.load(north_gpx("Long enough", 100.5), "long.gpx") and mode.route.name == "Long enough"


# Kind: text from a file that cannot wrap. A refused file's 240-character name without spaces ran past the panel's
# right edge and was clipped there (the notification wrapped it). Every file name, track name and refusal shown in
# the panel's markdown gets a place to wrap (a zero-width space) at least every 24 characters.
def _runs(markdown: str) -> list[str]:
    """The stretches of the decoded text with no place to wrap: no white space, no zero-width space."""
    return re.split(r"[\s\u200b]+", html.unescape(markdown))


def test_a_long_unbroken_name_wraps_in_the_panel(mode: CourseMode) -> None:
    name = "L" * 236 + ".gpx"
    assert not mode.load(b"not a gpx file", name)
    shown = html.unescape(mode.route_info.content)
    longest = max(_runs(mode.route_info.content), key=len)
    print(f"longest run without a place to wrap: {len(longest)} characters")
    assert len(longest) <= 26  # 24, and the bold marks or a full stop about it
    assert f"⚠️ **{name}** was not loaded" in shown.replace("\u200b", "")
    # A track name (80 characters at most) and what a refusal quotes from the file wrap the same way.
    assert mode.load(hill_gpx("T" * 80), "t.gpx")
    assert max(map(len, _runs(mode.route_info.content))) <= 26
    assert html.unescape(mode.route_info.content).replace("\u200b", "").startswith(f"**{'T' * 80}**")
    encoding = '<?xml version="1.0" encoding="' + "x" * 150 + '"?><gpx/>'
    assert not mode.load(encoding.encode(), "enc.gpx")
    assert "x" * 150 in html.unescape(mode.route_info.content).replace("\u200b", "")
    assert max(map(len, _runs(mode.route_info.content))) <= 26


def test_wrapping_keeps_combining_marks_emoji_and_flags_whole() -> None:
    for text in ("e\u0301" * 40, "👍🏽" * 40, "👨\u200d👩\u200d👧" * 20, "🇫🇷" * 40, "a\u2060" * 40):
        shown = html.unescape(_escape(text))
        assert shown.replace("\u200b", "") == text
        breaks = [i for i, c in enumerate(shown) if c == "\u200b"]
        assert breaks, repr(text)
        for at in breaks:
            before, after = shown[at - 1], shown[at + 1]
            assert unicodedata.category(after) not in ("Mn", "Mc", "Me", "Cf") and before != "\u200d", repr(text)
            assert not "\U0001f3fb" <= after <= "\U0001f3ff", repr(text)
            flags_before = sum("\U0001f1e6" <= c <= "\U0001f1ff" for c in shown[:at])
            assert flags_before % 2 == 0, repr(text)  # a flag is two regional indicators: never split
        assert max(map(len, shown.split("\u200b"))) <= BREAK_EVERY + 2
    # Text that is all joiners and marks still wraps, at most twice as far apart.
    for text in ("a\u200d" * 60, "e" + "\u0301" * 100):
        shown = html.unescape(_escape(text))
        assert shown.replace("\u200b", "") == text
        assert max(map(len, shown.split("\u200b"))) <= 2 * BREAK_EVERY


@settings(max_examples=examples(200), deadline=None)
@given(text=st.text(st.characters(codec="ascii", exclude_categories=("Cc",)), max_size=300))
def test_escaped_text_reads_as_itself_and_wraps_every_24_characters(text: str) -> None:
    shown = html.unescape(_escape(text))
    assert shown.replace("\u200b", "").replace("\u2060", "") == text
    assert max(len(run.replace("\u2060", "")) for run in re.split(r"[\s\u200b]+", shown)) <= BREAK_EVERY


# Kind: a control whose range misses values the course can need. The barometer input began at 500 hPa, yet the reader
# accepts routes up to 10 000 m: at 5 800 m the real reading is about 480 hPa (Everest's summit about 337 hPa).
def test_a_barometer_reading_at_any_accepted_start_can_be_entered(mode: CourseMode) -> None:
    low, high = BAROMETER_RANGE_HPA
    box = mode.controls["pressure_hpa"]
    assert isinstance(box, viser.GuiNumberHandle) and (box.min, box.max) == (low, high)
    # The standard atmosphere at the highest start the reader accepts, less a deep low's 5 %, is in range, and the
    # air kernel takes the whole range.
    assert low <= 0.95 * float(cycling.isa_pressure_hpa(course_kernel.MAX_ELEVATION_M))
    for pressure in (low, high):
        assert math.isfinite(float(cycling.air_density_weather(0.0, pressure, 0.5)))
    assert mode.load(north_gpx("High pass", 2000.0, elevation_m=5800.0), "high.gpx")
    mode.controls["air"].value = "Weather reading"
    mode.controls["pressure_from_barometer"].value = "Barometer"
    mode.controls["temperature_c"].value = -5.0
    mode.controls["pressure_hpa"].value = 480.0
    print(f"pressure kept: {mode.params.pressure_hpa} hPa, shown {mode.controls['pressure_hpa'].value}")
    assert mode.params.pressure_hpa == 480.0 and mode.controls["pressure_hpa"].value == 480.0
    assert mode.state is not None
    expected = float(cycling.air_density_weather(-5.0, 480.0, 0.5))
    assert mode.state.density_weather == pytest.approx(expected, rel=1e-12)
    assert "480 hPa read" in mode.readout.content
    mode.controls["pressure_hpa"].value = 337.0  # Everest's summit
    assert mode.params.pressure_hpa == 337.0


# Kind: one length shown as two numbers. The Position slider ended at the length rounded up (13.16) while the summary
# rounded it to the nearest (13.15 km): 333.59 against 333.58, 1.11 against 1.10. Both are now the length to the
# nearest 10 m, and the slider's end is the finish, as the leader's readout there says.
@pytest.mark.parametrize("length_m", [100.02, 1104.0, 1146.0, 2000.0, 2127.0, 13_154.0, 13_151.28, 333_584.0])
def test_the_summary_and_the_position_sliders_end_give_one_length(mode: CourseMode, length_m: float) -> None:
    assert mode.load(north_gpx("Straight", length_m), "straight.gpx")
    total_m = mode.route.total_distance_m
    assert total_m == pytest.approx(length_m, abs=0.01)
    end = mode.scrub.max
    shown = re.search(r"\*\*: ([\d.]+) km, ", mode.route_info.content)
    assert shown is not None
    print(f"{length_m:.2f} m: summary {shown.group(1)} km, slider end {end}")
    assert shown.group(1) == f"{end:.2f}" == f"{round(length_m / 10.0) / 100.0:.2f}"
    assert abs(end - total_m / 1000.0) <= 0.005 + 1e-9
    mode.scrub.value = end  # the slider's end is the finish
    assert mode.leader_distance_m() == pytest.approx(total_m, rel=1e-12)
    assert f"Leader at **{end:.2f} km**" in mode.now.content
    mode.scrub.value = round(end - 0.01, 2)  # a step short of it is that far along
    assert mode.leader_distance_m() == pytest.approx(1000.0 * round(end - 0.01, 2), abs=1e-6)
    # Ridden to the end, playback leaves the slider at its end.
    mode._on_play()
    assert mode.state is not None
    mode.play_time_s = mode.state.ride.time_s - 1e-9
    while mode._animate(0.2):
        pass
    assert mode.scrub.value == end and f"Leader at **{end:.2f} km**" in mode.now.content
