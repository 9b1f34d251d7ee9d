"""A scene per browser tab: isolation, ``--shared``, sessions freed when tabs close, and the memory budget.

Budget on this machine (2 cores): 16 sessions open, each extra session ≤ 40 MiB (≤ 60 MiB for the SDF gallery);
after they close, RSS is back within 10 % of where it started; 50 builds and closes of any scene grow RSS ≤ 20 MiB.
The memory checks run the app in its own process (``app.py``), so the fake browsers' mirrors do not count.
"""

from __future__ import annotations

import ctypes
import gc
import math
import os
import re
import threading
import time
import warnings
import weakref
from typing import Any

import numpy as np
import pytest
import viser
from helpers.ci import need_gl
from helpers.processes import AppProcess, rss_bytes
from helpers.viser_private import gizmos, node_names, store_value
from helpers.waiting import wait_until
from helpers.wsclient import BrowserClient, connect_tab

from app import serve_scenes
from scenes import SCENES, Scene, SceneName
from scenes.arm import MAX_LINKS
from scenes.sdf_gallery import SdfGalleryScene
from server.sessions import CameraReport, Session, Sessions
from server.switcher import SceneSwitcher

MIB = 1024 * 1024


def test_each_tab_switches_and_resets_only_its_own_scene(server: viser.ViserServer, sessions: Sessions) -> None:
    a, mine = connect_tab(server, sessions)
    b, theirs = connect_tab(server, sessions)
    with a, b:
        assert mine is not theirs
        b.wait_for_node("/peloton")
        a.wait_for_node("/peloton")
        their_scene = theirs.scene

        a.set_value("Scene", SCENES["arm"].title)
        a.wait_for(lambda: "/arm" in a.nodes and "/peloton" not in a.nodes, what="A shows the arm")
        a.wait_for(lambda: mine.scene.key == "arm", what="A's session holds the arm")
        assert theirs.scene is their_scene and their_scene.key == "peloton"
        assert "/arm" not in b.nodes and "/peloton" in b.nodes
        assert b.value_of("Scene") == SCENES["peloton"].title
        a.wait_for_gui("Links")  # the server built the arm: its controls may still be on their way to the tab
        assert "Links" not in b.labels()

        stale = mine.scene
        a.click("Reset scene to defaults")
        a.wait_for(lambda: mine.scene is not stale, what="A's reset rebuilt A's scene")
        assert theirs.scene is their_scene

        b.wait_for_gui("Speed (km/h)")
        b.set_value("Speed (km/h)", 21.0)
        b.wait_for(lambda: their_scene.params.speed_kmh == 21.0, what="B's own edit")  # type: ignore[attr-defined]
        # Nothing is on the server's shared scene: each tab's nodes are its own.
        assert not [name for name in node_names(server) if name.startswith(("/peloton", "/arm"))]


def test_the_gate_guards_a_tabs_own_controls_and_gizmos(
    server: viser.ViserServer, sessions: Sessions, caplog: pytest.LogCaptureFixture
) -> None:
    """Client-scoped handles go through the same gate: crafted fields, NaN, a bad quaternion, a 2-vector."""
    a, mine = connect_tab(server, sessions)
    with a:
        a.set_value("Scene", SCENES["arm"].title)
        a.wait_for(lambda: mine.scene.key == "arm", what="A shows the arm")
        scene = mine.scene
        target = a.wait_for_node("/arm/target")
        assert target.get("owner"), "a tab's own gizmo carries its owner"
        links = a.wait_for_gui("Links")
        a.send("GuiUpdateMessage", uuid=links, updates={"props": {}})
        a.send("GuiUpdateMessage", uuid=links, updates={"removed": True})
        a.set_value("Links", float("nan"))
        a.set_value("Links", 40)
        a.drag_transform("/arm/target", [(0.1, 0.2)], wxyz=(1.0, 0.0, 0.0))
        a.drag_transform("/arm/target", [(float("nan"), 0.0, 0.5)], wxyz=(0.0, 0.0, 0.0, 0.0))
        a.wait_for_gui("Max iterations")
        a.set_value("Max iterations", 77)
        a.wait_for(lambda: scene.params.max_iterations == 77, what="the honest edit")  # type: ignore[attr-defined]
        a.wait_for(lambda: a.value_of("Links") == MAX_LINKS, what="Links clamped to its declared max")
        assert scene.params.n_links == MAX_LINKS  # type: ignore[attr-defined]
        assert "Links" in a.labels()  # still there: the crafted removal was refused
        handle = gizmos(mine.server.scene)["/arm/target"]
        a.wait_for(
            lambda: a.pose_of("/arm/target")[0] == tuple(float(v) for v in handle.position),
            what="the tab shown its gizmo's last good pose",
        )
        assert all(math.isfinite(v) for v in handle.position)
        kinds = {str(r.args[0]) for r in caplog.records if r.name == "server.refusals" and isinstance(r.args, tuple)}
        assert "GUI update of a field other than value" in kinds
        assert any("gizmo position" in kind for kind in kinds)
        assert any("gizmo orientation" in kind for kind in kinds)


def test_a_closed_tab_frees_its_session(server: viser.ViserServer, sessions: Sessions) -> None:
    refs = []
    for key in ("sdf", "arm"):
        client, switcher = connect_tab(server, sessions)
        with client:
            client.set_value("Scene", SCENES[key].title)
            client.wait_for(lambda switcher=switcher, key=key: switcher.scene.key == key, f"the tab shows {key}", 60.0)
            refs += [weakref.ref(switcher), weakref.ref(switcher.scene), weakref.ref(switcher.server)]
            del switcher
        wait_until(lambda: not (sessions.count or server.get_clients()), "the closed tab's session freed")
        assert sessions.count == 0
    # A callback still running on viser's thread pool when the tab closed holds its scene until it returns.

    def all_freed() -> bool:
        gc.collect()
        return all(ref() is None for ref in refs)

    wait_until(all_freed, "the closed tabs' switchers, scenes and sessions collected", timeout_s=10.0)


@pytest.mark.parametrize("field", ["look_at", "position", "up_direction", "fov"])
def test_a_camera_written_after_its_tab_closed_is_lost_without_a_warning(server: viser.ViserServer, field: str) -> None:
    """Kind: a write to a closed tab. A scene frames a camera from the report its tab sent; the explore profile saw
    a tab close in between, and viser warned "Queued a SetCameraLookAtMessage on a closed connection"."""
    with BrowserClient(server.get_port()):
        wait_until(lambda: len(server.get_clients()) == 1, "the tab registered")
        (handle,) = server.get_clients().values()
        report = CameraReport(handle.camera)
    wait_until(lambda: not server.get_clients(), "the tab gone")
    value = {"look_at": (0.0, 0.0, 1.0), "position": (1.0, 2.0, 3.0), "up_direction": (0.0, 0.0, 1.0), "fov": 0.9}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        setattr(report, field, value[field])


def test_a_tab_closed_while_its_session_builds_is_torn_down_and_sent_nothing(
    server: viser.ViserServer, monkeypatch: pytest.MonkeyPatch, recwarn: pytest.WarningsRecorder
) -> None:
    """The open/close race on viser's thread pool: the tab goes while its scene is being built."""
    entered, release = threading.Event(), threading.Event()
    built: list[Scene] = []
    clients: list[viser.ClientHandle] = []
    peloton = SCENES["peloton"]

    class SlowPeloton(peloton):  # type: ignore[valid-type,misc]
        def __init__(self, session: Session) -> None:
            assert session.client is not None
            clients.append(session.client)
            entered.set()
            release.wait(30.0)  # the tab closes here, mid-build
            super().__init__(session)
            built.append(self)

    monkeypatch.setitem(SCENES, "peloton", SlowPeloton)
    manager = serve_scenes(server, "peloton", shared=False)
    assert isinstance(manager, Sessions)
    try:
        tab = BrowserClient(server.get_port())
        assert entered.wait(30.0), "the session's build began"
        tab.close()
        wait_until(lambda: not server.get_clients(), "viser forgot the tab")
        release.set()
        wait_until(lambda: bool(built) and built[0].closed, "the late session torn down once built")
        assert manager.count == 0
        # A connect callback that runs only after its tab has gone (the pool ran the disconnect first) builds nothing.
        manager._open(clients[0])  # pyright: ignore[reportPrivateUsage]
        assert len(built) == 1 and manager.count == 0
        assert not [w for w in recwarn if "closed connection" in str(w.message)]
    finally:
        release.set()
        manager.close()


@pytest.mark.parametrize("key", ["freekick", "peloton"])
def test_a_tabs_session_writing_between_its_close_and_its_teardown_warns_nothing(
    server: viser.ViserServer, monkeypatch: pytest.MonkeyPatch, key: SceneName
) -> None:
    """Kind: a write to a closed tab before its session is torn down. A click on "Goal chance" as its tab closed
    wrote the progress bar to the dead tab: "Queued a GuiUpdateMessage on a closed connection" (an outside tester,
    five tabs closing mid-work). Here the teardown is held while the scene writes: a callback's redraw, a notice."""
    held, release = threading.Event(), threading.Event()
    close = Sessions._close  # pyright: ignore[reportPrivateUsage]

    def held_close(self: Sessions, client: viser.ClientHandle) -> None:
        held.set()
        release.wait(30.0)
        close(self, client)

    monkeypatch.setattr(Sessions, "_close", held_close)  # before the sessions register it with viser
    manager = serve_scenes(server, key, shared=False)
    assert isinstance(manager, Sessions)
    try:
        with BrowserClient(server.get_port()) as tab:
            tab.wait_for_gui("Reset scene to defaults")
            wait_until(lambda: manager.count == 1, "the tab's session built")
            (client,) = server.get_clients().values()
            (switcher,) = manager._switchers.values()  # pyright: ignore[reportPrivateUsage]
        assert held.wait(30.0), "the disconnect reached the sessions"
        scene: Any = switcher.scene
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            if key == "freekick":
                scene.callback(scene.request_odds_map)()  # the button's handler
            else:
                scene.callback(scene.redraw)()
            scene.notify(client, "Late", "written after the tab closed")
        assert not [str(w.message) for w in caught if "closed connection" in str(w.message)]
    finally:
        release.set()
    wait_until(lambda: manager.count == 0, "the session torn down")
    manager.close()


@pytest.mark.parametrize("action", ["pick", "reset"])
def test_a_pick_or_reset_handled_after_its_tab_closed_builds_nothing(
    server: viser.ViserServer, monkeypatch: pytest.MonkeyPatch, action: str
) -> None:
    """The kind: an input that waited on viser's callback pool (or the gate's budget) while its tab closed. Before,
    the switcher built the picked scene after the session had closed it: nobody closed that scene, and its loop and
    workers ran for good (12 such tabs: 7 → 50 threads). Now a closed switcher builds nothing."""
    built: list[Scene] = []
    arm = SCENES["arm"]

    class CountedArm(arm):  # type: ignore[valid-type,misc]
        def __init__(self, session: Session) -> None:
            super().__init__(session)
            built.append(self)

    monkeypatch.setitem(SCENES, "arm", CountedArm)
    switcher = SceneSwitcher(server, "arm")
    assert len(built) == 1
    threads = threading.active_count()
    picked = switcher.dropdown
    switcher.close()
    assert switcher.scene.closed
    store_value(picked, SCENES["peloton"].title)  # what viser stores before it runs the queued callback
    if action == "pick":
        switcher._on_pick(None)  # pyright: ignore[reportPrivateUsage]
    else:
        switcher._on_reset(None)  # pyright: ignore[reportPrivateUsage]
    assert len(built) == 1 and switcher.scene is built[0] and switcher.scene.closed
    wait_until(lambda: threading.active_count() <= threads, "no scene thread left running")


def test_shared_mode_is_one_scene_for_every_tab(server: viser.ViserServer) -> None:
    switcher = serve_scenes(server, "peloton", shared=True)
    assert isinstance(switcher, SceneSwitcher)
    try:
        with BrowserClient(server.get_port()) as a, BrowserClient(server.get_port()) as b:
            a.wait_for_node("/peloton")
            b.wait_for_node("/peloton")
            a.wait_for_gui("Scene")
            a.set_value("Scene", SCENES["freekick"].title)
            b.wait_for(lambda: "/freekick" in b.nodes, what="B sees A's switch")
            b.wait_for(lambda: b.value_of("Scene") == SCENES["freekick"].title, what="B's dropdown")
            b.wait_for(lambda: switcher.scene.key == "freekick", what="the one scene is the free kick")
    finally:
        switcher.close()


# ------------------------------------------------------------------------------------------------ memory
GL_REQUIRED = os.environ.get("CI", "").lower() in ("1", "true", "yes")
"""Under CI=true Mesa's EGL is there: an SDF tab is up only once its reference is rendered, so the memory budgets
below measure sessions that share the one GL context, never sessions that gave up on GL."""


def reference_shown(tab: BrowserClient) -> bool:
    """Whether the tab shows the SDF gallery's reference note after a render (or, outside CI, the reason there is
    none)."""
    notes = (" px on ",) if GL_REQUIRED else (" px on ", "No reference image")
    return any(
        isinstance(value, str) and any(note in value for note in notes)
        for element in tab.gui.values()
        for value in element["props"].values()
    )


def open_tabs(app: AppProcess, count: int, scene: str) -> list[BrowserClient]:
    """``count`` tabs on ``scene``, each fully up: the SDF gallery's first reference image shown."""
    tabs = []
    for _ in range(count):
        tab = BrowserClient(app.port)
        tab.wait_for_gui("Scene", timeout_s=60)
        if scene != "peloton":
            tab.set_value("Scene", SCENES[scene].title)
        tab.wait_for_node(f"/{scene}", timeout_s=120)
        if scene == "sdf":
            tab.wait_for(lambda tab=tab: reference_shown(tab), timeout_s=120, what="its reference")
        tabs.append(tab)
    return tabs


def thread_count(pid: int) -> int:
    with open(f"/proc/{pid}/status") as status:
        match = re.search(r"Threads:\s+(\d+)", status.read())
    assert match is not None
    return int(match.group(1))


def cpu_seconds(pid: int) -> float:
    with open(f"/proc/{pid}/stat") as stat:
        fields = stat.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def settled_rss(app: AppProcess, timeout_s: float = 120.0) -> int:
    """The app's RSS once it is idle (under 2 % of a core for a second): scene jobs in flight have ended.

    Idle is a quiet second, not an event: the app says when its kernels are loaded, not when a job has ended."""
    window: list[tuple[float, float]] = [(time.monotonic(), cpu_seconds(app.process.pid))]  # since when, CPU s then

    def quiet_for_a_second() -> bool:
        now, busy = time.monotonic(), cpu_seconds(app.process.pid)
        if now - window[0][0] < 1.0:
            return False
        quiet = busy - window[0][1] < 0.02
        window[0] = (now, busy)
        return quiet

    wait_until(quiet_for_a_second, "the app idle (under 2 % of a core for a second)", timeout_s)
    return app.rss


@pytest.mark.parametrize(("scene", "budget_mib"), [("peloton", 40), ("arm", 40), ("freekick", 40), ("sdf", 60)])
def test_sixteen_sessions_fit_the_budget_and_are_given_back(scene: str, budget_mib: int) -> None:
    app = AppProcess()
    try:
        # First use loads what every session shares (kernels, caches, shaders, the SDF gallery's one GL
        # context): the warm tab runs until its scene is fully up, or "start" would leave the context out.
        app.wait_compiled()  # before the warm tab, which then loads the compiled code its scene calls
        warm = open_tabs(app, 1, scene)
        for tab in warm:
            tab.close()
        start = settled_rss(app)
        tabs = open_tabs(app, 16, scene)
        full = settled_rss(app)
        for tab in tabs:
            tab.close()
        after = settled_rss(app)
        per_session_mib = (full - start) / 16 / MIB
        print(
            f"{scene}: start {start / MIB:.0f} MiB, 16 sessions {full / MIB:.0f} MiB "
            f"({per_session_mib:.1f} MiB each), closed {after / MIB:.0f} MiB"
        )
        assert per_session_mib <= budget_mib
        assert after <= 1.10 * start
    finally:
        app.close()


def test_a_tab_that_picks_a_scene_and_closes_at_once_leaves_no_warning() -> None:
    """An outside tester: a tab that picked another scene and closed within 50 ms logged viser's "Queued a … on a
    closed connection" for each kind of message the new scene's build sent its dead tab."""
    app = AppProcess()
    try:
        app.wait_compiled()
        for i in range(30):
            tab = BrowserClient(app.port)
            tab.wait_for_gui("Scene", timeout_s=60)
            options = tab.element("Scene")["props"]["options"]
            tab.set_value("Scene", options[1 + i % 3])
            time.sleep(0.05)  # gone while the scene it picked is being built
            tab.close()
        time.sleep(2.0)  # the last builds finish on viser's pool
        assert "closed connection" not in app.log
        assert "Traceback" not in app.log
    finally:
        app.close()


def test_tab_churn_leaves_rss_flat_and_sends_nothing_to_closed_tabs() -> None:
    """Tabs opened and closed one after another, every third closed while its session is still being built."""

    def churn(count: int) -> None:
        for i in range(count):
            tab = BrowserClient(app.port)
            if i % 3 == 0:
                time.sleep(0.01 * (i % 7))  # gone before (or while) its session is built
            else:
                tab.wait_for_gui("Scene", timeout_s=60)
            tab.close()

    app = AppProcess()
    try:
        # viser's callback pool grows toward its 32 threads as builds overlap, each thread adding its stack pages
        # (~0.4 MiB): measure over a run of tabs in which the pool no longer grew. A leak grows every run; under
        # CI's load one run of a steady pool read 55 KiB a tab where the runs before and after read 14-30, so a
        # run over the limit is measured again, up to four runs.
        app.wait_compiled()
        churn(30)
        measured: list[str] = []
        start = end = threads_before = threads_after = 0
        per_tab_kib = math.inf
        for _ in range(4):
            start, threads_before = settled_rss(app), thread_count(app.process.pid)
            churn(30)
            end, threads_after = settled_rss(app), thread_count(app.process.pid)
            per_tab_kib = (end - start) / 30 / 1024
            measured.append(f"{per_tab_kib:.0f} KiB a tab, threads {threads_before} -> {threads_after}")
            if threads_after <= threads_before and per_tab_kib <= 50.0:
                break
        print(f"tab churn: {start / MIB:.1f} -> {end / MIB:.1f} MiB over 30 tabs; {measured}")
        assert threads_after <= threads_before, f"the thread pool kept growing: {measured}"
        assert per_tab_kib <= 50.0, measured
        assert "closed connection" not in app.log
        assert "Traceback" not in app.log
    finally:
        app.close()


def _trim_heap() -> None:
    """Hand freed heap pages back to the system, so RSS measures what is held, not what malloc keeps cached."""
    gc.collect()
    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):
        pass


@pytest.mark.parametrize("key", ["peloton", "arm", "freekick", "sdf"])
def test_fifty_builds_and_closes_grow_rss_at_most_20_mib(server: viser.ViserServer, key: str) -> None:
    """Each build runs until the scene is fully up (the SDF gallery: its first reference image) before it closes."""

    def build_and_close() -> None:
        scene = SCENES[key](server)
        wait_until(lambda: _fully_up(scene), f"{key} to come up", 60.0)
        scene.close()

    for _ in range(2):  # warm up: imports, compiled kernels and caches every build shares
        build_and_close()
    _trim_heap()
    start = rss_bytes()
    for build in range(50):
        build_and_close()
        if build % 5 == 4:  # a leak of whole megabytes per build shows early: stop before it eats the machine
            grown_mib = (rss_bytes() - start) / MIB
            assert grown_mib <= 100.0, f"{key}: {grown_mib:.0f} MiB after {build + 1} builds"
    _trim_heap()
    grown_mib = (rss_bytes() - start) / MIB
    print(f"{key}: 50 builds and closes grew RSS by {grown_mib:.1f} MiB")
    assert grown_mib <= 20.0


def _fully_up(scene: object) -> bool:
    """Whether a scene has done the work its build starts (the SDF gallery renders a reference image or gives up)."""
    if isinstance(scene, SdfGalleryScene):
        return scene.reference_serial >= 1 or (scene.gl_error is not None and not GL_REQUIRED)
    return True


@pytest.mark.gl
def test_each_tab_s_sdf_reference_is_rendered_from_that_tab_s_camera(server: viser.ViserServer) -> None:
    """Per tab, the SDF gallery renders its reference from its own tab's camera: a landscape tab gets a landscape
    image and a portrait tab a portrait one, and moving one tab's camera re-renders that tab's reference only."""
    need_gl()
    manager = serve_scenes(server, "sdf", shared=False)
    assert isinstance(manager, Sessions)
    try:
        a, mine = connect_tab(server, manager)
        b, theirs = connect_tab(server, manager)
        with a, b:
            a.send_camera(position=(2.3, -2.5, 1.7), look_at=(0.05, 0.0, 0.3), size=(600, 800))
            b.send_camera(position=(-2.0, 2.6, 1.2), look_at=(0.0, 0.0, 0.3), size=(800, 600))
            scene_a, scene_b = mine.scene, theirs.scene
            assert isinstance(scene_a, SdfGalleryScene) and isinstance(scene_b, SdfGalleryScene)

            def shape(scene: SdfGalleryScene) -> tuple[int, ...] | None:
                rgb = scene.reference_rgb
                return None if rgb is None else rgb.shape

            def aspect_is(scene: SdfGalleryScene, height_over_width: float) -> bool:
                s = shape(scene)
                return s is not None and abs(s[0] / s[1] - height_over_width) < 0.02

            a.wait_for(lambda: aspect_is(scene_a, 600 / 800), timeout_s=120, what="A's landscape reference")
            b.wait_for(lambda: aspect_is(scene_b, 800 / 600), timeout_s=120, what="B's portrait reference")
            first_b = scene_b.reference_rgb
            serial_a = scene_a.reference_serial
            serial_b = scene_b.reference_serial
            b.send_camera(position=(0.0, -3.5, 0.4), look_at=(0.0, 0.0, 0.3), size=(800, 600))
            b.wait_for(lambda: scene_b.reference_serial > serial_b, timeout_s=60, what="B re-rendered")
            assert scene_b.reference_rgb is not None and first_b is not None
            assert not np.array_equal(scene_b.reference_rgb, first_b)
            time.sleep(0.5)  # A's camera did not move: nothing re-renders A's reference
            assert scene_a.reference_serial == serial_a
    finally:
        manager.close()
