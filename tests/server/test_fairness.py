"""One tab cannot starve the others: costly inputs are budgeted per tab, uploads in flight across all tabs.

A flooding tab (a crafted client: the real browser sends at most one message per 50 ms) clicks "Reset scene to
defaults" or switches scenes hundreds of times a second. Without a budget every click queued a full scene rebuild on
viser's callback pool, and another tab's first GUI waited behind them (measured here: 15.2 s). With it, a burst of
costly inputs from one tab is coalesced (a burst of Resets is one Reset, the latest pick wins) and the rest of the
server keeps serving.
"""

from __future__ import annotations

import dataclasses
import logging
import threading
import time
from collections.abc import Callable
from typing import Any

import pytest
import viser
from helpers.browser import open_viser
from helpers.gpx import hill_gpx
from helpers.uploads import send_part, start_upload, upload
from helpers.waiting import wait_until
from helpers.wsclient import BrowserClient
from hypothesis import given
from hypothesis import strategies as st

import server.budget as budget_module
from scenes import SCENES
from scenes.peloton import PelotonScene
from server.budget import (
    COSTLY_BURST,
    COSTLY_RATE_HZ,
    MAX_UPLOAD_BYTES_IN_FLIGHT_TOTAL,
    MAX_UPLOADS_IN_FLIGHT_TOTAL,
    CostlyBudget,
)
from server.gate import install_gate
from server.sessions import Sessions
from server.switcher import SceneSwitcher

FIRST_GUI_BOUND_S = 2.0
"""The most another tab may wait for its first GUI while one tab floods (the goal's bound)."""
FLOOD_HZ = 200.0


def own_session(server: viser.ViserServer, sessions: Sessions, known: set[int]) -> int:
    """The client id of the one tab that registered since ``known``, once its session is built."""
    built: list[int] = []

    def session_built() -> bool:
        new = set(server.get_clients()) - known
        if not new:
            return False
        (client_id,) = new  # one tab, not two
        if sessions.switcher(client_id) is None:
            return False
        built.append(client_id)
        return True

    wait_until(session_built, "the tab's session built", 20.0)
    return built[-1]


class Flood:
    """Send ``messages()`` from ``client`` at ``hz`` on a thread until stopped."""

    def __init__(self, send: Callable[[int], None], hz: float) -> None:
        self._send = send
        self._period = 1.0 / hz
        self._stop = threading.Event()
        self.sent = 0
        self.last_sent_at = 0.0
        self._thread = threading.Thread(target=self._run, name="flood", daemon=True)

    def _run(self) -> None:
        next_at = time.monotonic()
        while not self._stop.is_set():
            self._send(self.sent)
            self.sent += 1
            self.last_sent_at = time.monotonic()
            next_at += self._period
            self._stop.wait(max(0.0, next_at - time.monotonic()))

    def __enter__(self) -> Flood:
        self._thread.start()
        return self

    def __exit__(self, *_exc: object) -> None:
        self._stop.set()
        self._thread.join(timeout=5.0)


def wait_flooding(server: viser.ViserServer, client_id: int, flood: Flood) -> None:
    """Until ``flood`` (from tab ``client_id``) has sent half a second's worth and the gate holds its inputs back."""
    gate = install_gate(server)
    wait_until(
        lambda: flood.sent > 0.5 * FLOOD_HZ and gate.costly_held_back(client_id) > 0,
        "the flood under way, beyond the tab's budget",
        30.0,
    )


def first_gui_delay(server: viser.ViserServer, sessions: Sessions) -> float:
    """Seconds from a new tab's connection to the first control of its own session (then checks it is served)."""
    known = set(server.get_clients())
    start = time.monotonic()
    with BrowserClient(server.get_port()) as late:
        late.wait_for_gui("Reset scene to defaults", timeout_s=60.0)
        delay = time.monotonic() - start
        late.wait_for_node("/peloton", timeout_s=30.0)
        switcher = sessions.switcher(own_session(server, sessions, known))
        assert switcher is not None
        late.set_value("Speed (km/h)", 31.0)  # a slider moved there reaches its own scene
        late.wait_for(
            lambda: switcher.scene.params.speed_kmh == 31.0,  # type: ignore[attr-defined]
            what="the late tab's slider",
        )
    return delay


def builds_of(client: BrowserClient, root: str) -> list[float]:
    """When ``client`` was sent each new build of the scene whose root frame is ``root``."""
    return [
        at for at, message in client.received if message.get("type") == "FrameMessage" and message.get("name") == root
    ]


def wait_settled(server: viser.ViserServer, client: BrowserClient, client_id: int) -> None:
    """Until every input ``client`` (tab ``client_id``) has sent reached the gate, which holds back none of them and
    runs none: the last delivered scene switch or Reset has rebuilt (on viser's callback pool) and nothing is left
    that could change the scene."""
    gate = install_gate(server)
    tab = server.get_clients()[client_id]
    marked_at = time.time()
    # A camera message is not held in line: the gate takes it in order after every input sent before it, and viser
    # stamps the tab's camera with it. Once stamped, the gate has taken all of them (held back or delivered).
    client.send_camera()
    wait_until(
        lambda: (
            tab.camera.update_timestamp >= marked_at
            and gate.costly_held_back(client_id) == 0
            and gate.costly_in_flight(client_id) == 0
        ),
        "the tab's inputs taken by the gate, none held back and none still running",
        30.0,
    )


EDITS = {  # an edit per scene that a Reset undoes: (label, value, params field)
    "peloton": ("Speed (km/h)", 33.0, "speed_kmh"),
    "sdf": ("Blend width k (m)", 0.37, "k"),  # the costliest rebuild: a mesh and a GL reference
}


@pytest.mark.parametrize("key", sorted(EDITS))
def test_a_reset_flood_does_not_delay_another_tab_and_ends_in_a_reset_scene(
    server: viser.ViserServer, sessions: Sessions, caplog: pytest.LogCaptureFixture, key: str
) -> None:
    label, value, field = EDITS[key]
    flooder = BrowserClient(server.get_port())
    with flooder, caplog.at_level(logging.WARNING):
        client_id = own_session(server, sessions, set())
        switcher = sessions.switcher(client_id)
        assert switcher is not None
        reset = flooder.wait_for_gui("Reset scene to defaults")
        flooder.set_value("Scene", SCENES[key].title)
        flooder.wait_for(lambda: switcher.scene.key == key, timeout_s=30.0, what=f"the session shows {key}")
        flooder.wait_for_gui(label)
        flooder.set_value(label, value)
        flooder.wait_for(
            lambda: getattr(switcher.scene.params, field) == value,  # type: ignore[attr-defined]
            timeout_s=30.0,
            what="the edit",
        )
        edited = switcher.scene
        built_before = len(builds_of(flooder, f"/{key}"))
        caplog.clear()
        started = time.monotonic()
        with Flood(lambda _i: flooder.send("GuiUpdateMessage", uuid=reset, updates={"value": True}), FLOOD_HZ) as flood:
            wait_flooding(server, client_id, flood)
            delay = first_gui_delay(server, sessions)
        flood_s = flood.last_sent_at - started
        print(f"{key} Reset flood: {flood.sent} clicks in {flood_s:.1f} s; another tab's first GUI in {delay:.2f} s")
        assert flood.sent > 0.5 * FLOOD_HZ
        assert delay <= FIRST_GUI_BOUND_S, f"the second tab's first GUI took {delay:.2f} s"

        wait_settled(server, flooder, client_id)

        def rebuilt_after_the_last_click() -> bool:
            # The last delivered Reset rebuilds on viser's callback pool: wait for that rebuild, not a fixed time
            # (under load, 0.5 s once found the scene it replaces already closed and the new one not yet shown).
            shown = switcher.scene
            builds = builds_of(flooder, f"/{key}")[built_before:]
            return bool(builds) and builds[-1] >= flood.last_sent_at and shown is not edited and not shown.closed

        flooder.wait_for(rebuilt_after_the_last_click, timeout_s=30.0, what="a rebuild after the last Reset")
        builds = builds_of(flooder, f"/{key}")[built_before:]
        print(f"{key} Reset flood: {len(builds)} rebuilds")
        # A burst of Resets is a few rebuilds (the budget), not one per click...
        assert 1 <= len(builds) <= COSTLY_BURST + flood_s * COSTLY_RATE_HZ + 2, (
            f"{len(builds)} rebuilds for {flood.sent} Resets in {flood_s:.1f} s"
        )
        # ...and the last click is not dropped: a rebuild comes after it, and the scene is what a Reset gives.
        assert builds[-1] >= flood.last_sent_at
        scene = switcher.scene
        assert scene is not edited and scene.key == key and not scene.closed
        defaults = type(scene.params)()  # type: ignore[attr-defined]
        assert scene.params == defaults  # type: ignore[attr-defined]
        flooder.wait_for(
            lambda: flooder.value_of(label) == getattr(defaults, field), what="the flooder shows the reset scene"
        )
    kinds = [r.getMessage() for r in caplog.records if "costly input" in r.getMessage()]
    assert 1 <= len(kinds) <= 2  # one rate-limited line, not one per click
    assert "Traceback" not in caplog.text


def test_an_edit_sent_after_resets_beyond_the_budget_is_not_undone(
    server: viser.ViserServer, sessions: Sessions, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Five Resets at once (the budget lets three through, holds back the last), then a speed: the held-back Reset
    goes first and the speed after it, so the tab ends on a reset scene at the speed it sent last."""
    # A token every 5 s: the held-back Reset still waits once the three let through have rebuilt, on any machine.
    monkeypatch.setattr(budget_module, "COSTLY_RATE_HZ", 0.2)
    with BrowserClient(server.get_port()) as client:
        client_id = own_session(server, sessions, set())
        switcher = sessions.switcher(client_id)
        assert switcher is not None
        reset = client.wait_for_gui("Reset scene to defaults")
        client.wait_for_node("/peloton")
        for _ in range(COSTLY_BURST + 2):
            client.send("GuiUpdateMessage", uuid=reset, updates={"value": True})
        gate = install_gate(server)

        def held_with_the_tab_on_a_built_scene() -> bool:
            # Only the held-back Reset is pending, and the tab's Speed is the live control: the case this test
            # is about. (An edit aimed at a control that a Reset still running has removed is refused as unknown;
            # the tab is sent the rebuilt scene: README, Known limits.)
            tab = gate._budgets.get(client_id)  # pyright: ignore[reportPrivateUsage]
            uuid = client._find("Speed (km/h)")  # pyright: ignore[reportPrivateUsage]
            return (
                tab is not None
                and tab.budget.held >= 1
                and tab.in_flight == 0
                and uuid is not None
                and gate._gui_handle(server, client_id, uuid) is not None  # pyright: ignore[reportPrivateUsage]
            )

        client.wait_for(held_with_the_tab_on_a_built_scene, what="a Reset held back")
        client.set_value("Speed (km/h)", 33.0)
        wait_settled(server, client, client_id)
        client.wait_for(
            lambda: (
                not switcher.scene.closed
                and switcher.scene.params.speed_kmh == 33.0  # type: ignore[attr-defined]
                and client.value_of("Speed (km/h)") == 33.0
            ),
            timeout_s=30.0,
            what="the speed sent after the Resets, in the reset scene",
        )
        wait_settled(server, client, client_id)  # nothing is left that could undo it
        scene = switcher.scene
        assert scene.params == dataclasses.replace(type(scene.params)(), speed_kmh=33.0)  # type: ignore[attr-defined]


def test_a_scene_switch_flood_ends_on_the_last_pick_and_does_not_delay_another_tab(
    server: viser.ViserServer, sessions: Sessions
) -> None:
    titles = [cls.title for cls in SCENES.values()]
    flooder = BrowserClient(server.get_port())
    with flooder:
        client_id = own_session(server, sessions, set())
        pick = flooder.wait_for_gui("Scene")
        flooder.wait_for_node("/peloton")
        picked: list[str] = []

        def switch(i: int) -> None:
            picked.append(titles[i % len(titles)])
            flooder.send("GuiUpdateMessage", uuid=pick, updates={"value": picked[-1]})

        with Flood(switch, FLOOD_HZ) as flood:
            wait_flooding(server, client_id, flood)
            delay = first_gui_delay(server, sessions)
        print(f"Switch flood: {flood.sent} picks; another tab's first GUI in {delay:.2f} s")
        assert delay <= FIRST_GUI_BOUND_S, f"the second tab's first GUI took {delay:.2f} s"

        wait_settled(server, flooder, client_id)
        (last_key,) = [key for key, cls in SCENES.items() if cls.title == picked[-1]]
        switcher = sessions.switcher(client_id)
        assert switcher is not None
        flooder.wait_for(
            lambda: switcher.scene.key == last_key and not switcher.scene.closed,
            timeout_s=30.0,
            what=f"the session shows {last_key}",
        )
        flooder.wait_for(
            lambda: (
                f"/{last_key}" in flooder.nodes
                and not any(f"/{key}" in flooder.nodes for key in SCENES if key != last_key)
            ),
            timeout_s=20.0,
            what="the flooder shows only the last pick",
        )
        # The gate sends the flooder the server's value after the pick's rebuild, so just behind the scene's nodes.
        flooder.wait_for(lambda: flooder.value_of("Scene") == picked[-1], "the flooder's menu shows the last pick")


def test_a_slider_at_30_per_second_is_never_held_back(
    server: viser.ViserServer, sessions: Sessions, caplog: pytest.LogCaptureFixture
) -> None:
    with BrowserClient(server.get_port()) as client, caplog.at_level(logging.WARNING):
        client_id = own_session(server, sessions, set())
        client.wait_for_node("/peloton")
        switcher = sessions.switcher(client_id)
        assert switcher is not None
        values = [20.0 + 0.5 * i for i in range(45)]  # 1.5 s at 30 messages/s
        seen: set[float] = set()
        for value in values:
            client.set_value("Speed (km/h)", value)
            time.sleep(1.0 / 30.0)
            seen.add(switcher.scene.params.speed_kmh)  # type: ignore[attr-defined]
        client.wait_for(
            lambda: switcher.scene.params.speed_kmh == values[-1],  # type: ignore[attr-defined]
            what="the last value",
        )
        assert install_gate(server).costly_held_back(client_id) == 0
        assert len(seen & set(values)) >= len(values) // 2  # applied as they came, not coalesced
    assert "costly input" not in caplog.text and "refused" not in caplog.text


# ------------------------------------------------------------------------------------------ the budget alone
def replay(arrivals: list[tuple[float, str, int]], free: str = "") -> list[tuple[float, str, int]]:
    """Offer (gap s, control, value) arrivals to a fresh budget (controls named in ``free`` cost no token), taking
    each held-back one as soon as the budget hands it out; (time, control, value) in delivery order."""
    budget: CostlyBudget[int] = CostlyBudget(COSTLY_BURST, COSTLY_RATE_HZ, now=0.0)
    delivered: list[tuple[float, str, int]] = []
    now = [0.0]

    def release_until(t: float) -> None:
        while (wait := budget.wait_s(now[0])) is not None and now[0] + wait <= t:
            now[0] += wait
            taken = budget.take(now[0])
            assert taken is not None
            delivered.append((now[0], *taken))

    for gap, key, value in arrivals:
        release_until(now[0] + gap)
        now[0] += gap
        goes, _ = budget.offer(key, value, now[0], free=key in free)
        if goes:
            delivered.append((now[0], key, value))
    release_until(float("inf"))
    return delivered


def assert_within_the_budget(times: list[float]) -> None:
    """At most ``burst + rate·t`` of these delivery times in any ``t`` s."""
    for i, start in enumerate(times):
        for j in range(i, len(times)):
            assert j - i + 1 <= COSTLY_BURST + (times[j] - start) * COSTLY_RATE_HZ + 1e-9


def arrivals_of(controls: str) -> st.SearchStrategy[list[tuple[float, str, int]]]:
    """1 to 80 arrivals (gap s, control, value) of the one-letter ``controls``, as ``replay`` takes them."""
    return st.lists(
        st.tuples(st.floats(0.0, 0.6), st.sampled_from(controls), st.integers(0, 9)), min_size=1, max_size=80
    )


@given(arrivals_of("abc"))
def test_the_budget_bounds_work_and_delivers_each_controls_last_value(arrivals: list[tuple[float, str, int]]) -> None:
    """Any arrivals of costly inputs (gap s, control, value): at most ``burst + rate·t`` go in any ``t`` s, and each
    control's last value delivered is the last one sent."""
    delivered = replay(arrivals)
    last_sent = {key: value for _gap, key, value in arrivals}
    last_delivered = {key: value for _t, key, value in delivered}
    assert last_delivered == last_sent
    assert_within_the_budget([t for t, _key, _value in delivered])


@given(arrivals_of("abcxy"))
def test_an_input_after_a_held_back_one_is_applied_after_it(arrivals: list[tuple[float, str, int]]) -> None:
    """Costly controls a, b, c and free ones x, y (cheap sliders, gizmos) arriving in any order: each control ends
    on its last value, free inputs never spend the budget, and an input sent after a costly control's last value is
    delivered after it (an edit after a Reset is not undone by the Reset)."""
    delivered = replay(arrivals, free="xy")
    sent_at = {key: i for i, (_gap, key, _value) in enumerate(arrivals)}
    assert {key: v for _t, key, v in delivered} == {key: v for _g, key, v in arrivals}
    last_delivery = {key: i for i, (_t, key, _v) in enumerate(delivered)}
    for costly in set(sent_at) & set("abc"):
        for other in sent_at:
            if sent_at[other] > sent_at[costly]:
                assert last_delivery[other] > last_delivery[costly], (costly, other, delivered)
    assert_within_the_budget([t for t, key, _v in delivered if key in "abc"])


def test_an_edit_after_a_held_back_reset_waits_for_it() -> None:
    budget: CostlyBudget[str] = CostlyBudget(1, 1.0, now=0.0)
    assert budget.offer("reset", "first reset", 0.0) == (True, False)
    assert budget.offer("reset", "second reset", 0.1) == (False, False)  # beyond the budget: held back
    assert budget.offer("speed", "33 km/h", 0.2, free=True) == (False, False)  # behind it, in line
    assert budget.wait_s(0.2) == pytest.approx(0.8)
    assert budget.take(1.0) == ("reset", "second reset")
    assert budget.wait_s(1.0) == 0.0  # a free input goes as soon as it is first in line
    assert budget.take(1.0) == ("speed", "33 km/h")
    assert budget.offer("speed", "34 km/h", 1.0, free=True) == (True, False)  # nothing held: at once


def test_a_burst_of_resets_is_one_held_back_reset() -> None:
    budget: CostlyBudget[str] = CostlyBudget(3, 1.0, now=0.0)
    assert [budget.offer("reset", f"click {i}", 0.0)[0] for i in range(200)] == [True] * 3 + [False] * 197
    assert budget.held == 1 and budget.wait_s(0.0) == pytest.approx(1.0)
    assert budget.take(0.5) is None
    assert budget.take(1.0) == ("reset", "click 199")
    assert budget.held == 0 and budget.wait_s(1.0) is None


@pytest.mark.parametrize(("burst", "rate_hz"), [(0, 1.0), (1, 0.0), (1, float("nan"))])
def test_a_budget_that_lets_nothing_through_is_refused(burst: int, rate_hz: float) -> None:
    with pytest.raises(ValueError, match="burst"):
        CostlyBudget(burst, rate_hz, now=0.0)


# ------------------------------------------------------------------------------------------ uploads
def start_big_upload(client: BrowserClient, size: int, parts: int) -> str:
    """Start an upload of ``size`` bytes in ``parts`` parts to the course's button; returns its transfer id."""
    return start_upload(client, "Upload GPX", "big.gpx", size, parts)[1]


def open_course_tabs(
    server: viser.ViserServer, sessions: Sessions, count: int
) -> list[tuple[BrowserClient, PelotonScene]]:
    tabs = []
    for _ in range(count):
        known = set(server.get_clients())
        client = BrowserClient(server.get_port())
        switcher = sessions.switcher(own_session(server, sessions, known))
        assert switcher is not None and isinstance(switcher.scene, PelotonScene)
        switcher.scene.course_mode.enable.value = True
        client.wait_for_gui("Upload GPX")
        tabs.append((client, switcher.scene))
    return tabs


def padded_gpx(name: str, size: int) -> bytes:
    """A valid GPX course of exactly ``size`` bytes (an XML comment pads it)."""
    data = hill_gpx(name, 300)
    head, tail = data.split(b"<trk>", 1)
    padding = size - len(data) - len(b"<!--  -->")
    return head + b"<!-- " + b"x" * padding + b" -->" + b"<trk>" + tail


def refusal_notice(client: BrowserClient) -> dict[str, Any]:
    client.wait_for(lambda: bool(client.notices()), what="the refusal notice")
    note = client.notices()[-1]
    assert note["title"] == "Upload refused" and note["color"] == "red"
    return note


def test_uploads_beyond_the_server_wide_count_are_refused_with_a_notice_and_the_others_complete(
    server: viser.ViserServer, sessions: Sessions, caplog: pytest.LogCaptureFixture
) -> None:
    gate = install_gate(server)
    tabs = open_course_tabs(server, sessions, 5)
    try:
        with caplog.at_level(logging.WARNING):
            data = [hill_gpx(f"Tab {i}", 300) for i in range(len(tabs))]
            transfers: list[list[str]] = []
            for i, (client, _scene) in enumerate(tabs):  # 5 tabs × 2 uploads: 10 > the cap of 8
                transfers.append([start_big_upload(client, len(data[i]), 1) for _ in range(2)])
                if i < 4:
                    client.wait_for(lambda i=i: gate.uploads_in_flight()[0] == 2 * (i + 1), what="in flight")
            assert MAX_UPLOADS_IN_FLIGHT_TOTAL == 8
            note = refusal_notice(tabs[4][0])
            assert "other uploads" in note["body"] and "8 files" in note["body"]
            assert gate.uploads_in_flight()[0] == 8
            for i, (client, _scene) in enumerate(tabs):
                for transfer in transfers[i]:
                    send_part(client, transfer, 0, data[i])
            for i, (client, scene) in enumerate(tabs[:4]):
                client.wait_for(lambda s=scene, n=f"Tab {i}": s.course_mode.route.name == n, what=f"tab {i}'s upload")
                assert not client.notices()
            # Each tab sent two uploads; its course changes with the first, and the second may still be landing.
            tabs[0][0].wait_for(lambda: gate.uploads_in_flight() == (0, 0), what="every upload landed")
            assert tabs[4][1].course_mode.route.name != "Tab 4"
            # Once the others are done, the refused tab's upload goes through.
            upload(tabs[4][0], "Upload GPX", "again.gpx", data[4])
            tabs[4][0].wait_for(lambda: tabs[4][1].course_mode.route.name == "Tab 4", what="the retry")
        assert "refused uploads in flight across all tabs" in caplog.text
    finally:
        for client, _scene in tabs:
            client.close()


def test_uploads_beyond_the_server_wide_bytes_are_refused_with_a_notice_and_the_others_complete(
    server: viser.ViserServer, sessions: Sessions
) -> None:
    gate = install_gate(server)
    big = 20 * 1024 * 1024
    assert 3 * big <= MAX_UPLOAD_BYTES_IN_FLIGHT_TOTAL < 4 * big
    tabs = open_course_tabs(server, sessions, 5)
    try:
        transfers = []
        for i, (client, _scene) in enumerate(tabs[:3]):
            transfers.append(start_big_upload(client, big, 1))
            client.wait_for(lambda i=i: gate.uploads_in_flight()[0] == i + 1, what="in flight")
        start_big_upload(tabs[3][0], big, 1)  # 60 + 20 MiB > 64 MiB
        note = refusal_notice(tabs[3][0])
        assert "60.0 MiB in flight" in note["body"] and "64 MiB" in note["body"]
        # A small file still fits beside the three big ones.
        upload(tabs[4][0], "Upload GPX", "small.gpx", hill_gpx("Small", 300))
        tabs[4][0].wait_for(lambda: tabs[4][1].course_mode.route.name == "Small", what="small")
        for i, (client, _scene) in enumerate(tabs[:3]):
            send_part(client, transfers[i], 0, padded_gpx(f"Big {i}", big))
        for i, (client, scene) in enumerate(tabs[:3]):
            client.wait_for(
                lambda s=scene, n=f"Big {i}": s.course_mode.route.name == n,
                timeout_s=30.0,
                what=f"tab {i}'s 20 MiB upload",
            )
            assert not client.notices()
        assert gate.uploads_in_flight() == (0, 0)
        assert tabs[3][1].course_mode.route.name != "Big 3"
    finally:
        for client, _scene in tabs:
            client.close()


def test_a_stalled_upload_stops_holding_the_server_wide_budget(
    server: viser.ViserServer, sessions: Sessions, monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    monkeypatch.setattr("server.budget.UPLOAD_STALL_S", 0.3)  # 30 s in the app
    gate = install_gate(server)
    tabs = open_course_tabs(server, sessions, 2)
    try:
        with caplog.at_level(logging.WARNING):
            (stalled, _), (honest, scene) = tabs
            data = hill_gpx("Stalled", 300)
            transfer = start_big_upload(stalled, len(data), 2)
            stalled.wait_for(lambda: gate.uploads_in_flight()[0] == 1, what="in flight")
            send_part(stalled, transfer, 0, data[:100])
            stalled.wait_for(
                lambda: any(
                    m.get("type") == "FileTransferPartAck" and m.get("transfer_uuid") == transfer
                    for _at, m in stalled.received
                ),
                "the first part taken",
            )
            # Stalled is time gone by, not an event: the gate finds a stalled upload when the next one starts.
            time.sleep(0.5)
            upload(honest, "Upload GPX", "honest.gpx", hill_gpx("Honest", 300))
            honest.wait_for(lambda: scene.course_mode.route.name == "Honest", what="the upload")
            assert gate.uploads_in_flight() == (0, 0)
            send_part(stalled, transfer, 1, data[100:])  # too late: refused, the course stays
            honest.wait_for(lambda: "refused upload part" in caplog.text, what="the late part")
            assert tabs[0][1].course_mode.route.name != "Stalled"
        assert "refused stalled upload" in caplog.text
    finally:
        for client, _scene in tabs:
            client.close()


def pick_file(page: Any, name: str, data: bytes) -> None:
    """What picking a file for the page's upload button does (set in the page: under software WebGL on busy cores,
    playwright's click waits on animation frames that may not come for a minute)."""
    page.wait_for_selector("input[type=file]", state="attached", timeout=120_000)
    page.evaluate(
        """([name, text]) => {
            const input = document.querySelector("input[type=file]");
            const files = new DataTransfer();
            files.items.add(new File([text], name, {type: "application/gpx+xml"}));
            input.files = files.files;
            input.dispatchEvent(new Event("change", {bubbles: true}));
        }""",
        [name, data.decode()],
    )


@pytest.mark.browser
def test_a_person_whose_upload_is_refused_is_told_why_and_can_retry(
    server: viser.ViserServer, browser_page: Any, caplog: pytest.LogCaptureFixture, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Chromium uploads a GPX while crafted tabs hold the server-wide budget: a red notice, then a retry works."""
    # Software WebGL on busy cores can take over 30 s to run the page's script: the hogs must not stall out first.
    monkeypatch.setattr("server.budget.UPLOAD_STALL_S", 600.0)

    switcher = SceneSwitcher(server, "peloton")
    hogs: list[BrowserClient] = []
    caplog.set_level(logging.WARNING)
    try:
        scene = switcher.scene
        assert isinstance(scene, PelotonScene)
        mode = scene.course_mode
        mode.enable.value = True
        gate = install_gate(server)
        page = browser_page
        open_viser(page, server.get_port(), "/peloton/course_mode/route", timeout_ms=120_000)
        page.wait_for_selector("input[type=file]", state="attached", timeout=120_000)
        # 2 tabs × 4 uploads that never send a part: the 8 the server takes at once.
        hogs += [BrowserClient(server.get_port()) for _ in range(2)]
        for hog in hogs:
            hog.wait_for_gui("Upload GPX")
            for _ in range(4):
                start_big_upload(hog, 1000, 1)
        hogs[0].wait_for(lambda: gate.uploads_in_flight()[0] == 8, what="the budget held")
        data = hill_gpx("Browser retry", 300)
        pick_file(page, "retry.gpx", data)
        wait_until(lambda: "refused uploads in flight across all tabs" in caplog.text, "the refusal logged", 60.0)
        page.get_by_text("Upload refused", exact=True).first.wait_for(timeout=60_000)
        page.get_by_text("receiving other uploads", exact=False).first.wait_for(timeout=10_000)
        assert mode.route.name != "Browser retry"

        for hog in hogs:
            hog.close()  # their uploads end with their tabs
        wait_until(lambda: gate.uploads_in_flight() == (0, 0), "the hogs' uploads gone", 20.0)
        pick_file(page, "retry.gpx", data)
        wait_until(lambda: mode.route.name == "Browser retry", "the retried upload's course", 60.0)
    finally:
        for hog in hogs:
            hog.close()
        switcher.close()
