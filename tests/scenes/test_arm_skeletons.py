"""The arm scene's skeleton presets: pure solves, and through a real server and a browser-like client."""

from __future__ import annotations

import numpy as np
import pytest
import viser
from helpers.scenes import scene_fixture
from helpers.wsclient import BrowserClient

from kernels import fabrik
from scenes import _skeletons
from scenes.arm import MAX_LINKS, ArmScene

scene = scene_fixture(ArmScene)


def link_lengths(skeleton: _skeletons.Skeleton, joints: np.ndarray) -> np.ndarray:
    return np.array([np.linalg.norm(joints[j] - joints[up]) for j, up in enumerate(skeleton.parents) if up >= 0])


# ------------------------------------------------------------------------------------------------ pure
@pytest.mark.parametrize("label", ["Robot arm", "Hand", "Upper body"])
def test_presets_open_in_a_pose_that_keeps_their_limits_and_lengths(label: _skeletons.PresetLabel) -> None:
    skeleton = _skeletons.PRESETS[label]()
    report = _skeletons.solve_skeleton(skeleton, skeleton.joints, skeleton.targets, tolerance_m=1e-3, max_iterations=50)
    np.testing.assert_allclose(
        link_lengths(skeleton, report.result.joints), link_lengths(skeleton, skeleton.joints), rtol=1e-9
    )
    assert np.all((report.usage >= 0.0) & (report.usage <= 1.0))
    # Every segment keeps its joint type: checked segment by segment with the kernel's own usage (≤ 1 + rounding)
    # and, for hinges, by the segment staying perpendicular to the world axis (all presets' hinges are global).
    for j, constraint in enumerate(skeleton.constraints):
        if isinstance(constraint, fabrik.Hinge):
            segment = report.result.joints[j] - report.result.joints[skeleton.parents[j]]
            assert abs(float(segment @ np.asarray(constraint.axis))) < 1e-9
    if label in ("Robot arm", "Hand"):  # targets the skeleton can reach without conflict
        assert all(s == "reached" for s in report.result.status)
    if label == "Robot arm":
        assert np.all(report.result.joints[:, 1] == 0.0)  # the hinges about y keep it in the x–z plane


def test_clean_target_refuses_what_is_not_three_finite_numbers_and_brings_the_rest_into_the_box() -> None:
    for bad in ([np.nan, 0, 0], [0, 0], "abc", [0, 0, np.inf], [[0, 0, 0]], None):
        assert _skeletons.clean_target(bad, planar=False) is None
    np.testing.assert_array_equal(_skeletons.clean_target([0.1, 0.5, 0.2], planar=True), [0.1, 0.0, 0.2])
    np.testing.assert_array_equal(_skeletons.clean_target([0, -1e300, 1e9], planar=False), [0.0, -8.0, 8.0])
    assert _skeletons.WORLD_LIMIT_M >= MAX_LINKS * 0.5 + 2.0  # the longest chain, stretched, and room beyond


# ------------------------------------------------------------------------------------------------ websocket
def client_joints(client: BrowserClient) -> np.ndarray | None:
    """Joint positions of the visible instances as the fake browser last received them."""
    return client.visible_instances("/arm/skeleton/joints")


def choose_preset(client: BrowserClient, scene: ArmScene, label: _skeletons.PresetLabel) -> None:
    """Pick skeleton preset ``label`` from the browser and wait until the scene has shown and solved it."""
    view = scene.skeletons
    client.wait_for_gui("Preset")
    client.set_value("Preset", label)
    client.wait_for(lambda: view.preset == label and view.solves >= 1, what=f"{label} shown")


def test_choosing_the_hand_and_dragging_a_fingertip_target_curls_the_finger(
    server: viser.ViserServer, scene: ArmScene
) -> None:
    view = scene.skeletons
    with BrowserClient(server.get_port()) as client:
        choose_preset(client, scene, "Hand")
        assert not scene.link_nodes.visible and not scene.target_gizmo.visible  # the chain is hidden
        index = 1
        start = view.targets[index].copy()
        goal = _skeletons.hand(target_curl_rad=1.0).targets[index]  # the index finger curled further
        points = [start + (goal - start) * t for t in np.linspace(0.1, 1.0, 8)]
        path = [(float(x), float(y), float(z)) for x, y, z in points]
        client.wait_for_node(f"/arm/skeleton/target_{index}")
        client.drag_transform(f"/arm/skeleton/target_{index}", path, period_s=0.01)
        effector = _skeletons.hand().effectors[index]
        client.wait_for(
            lambda: bool(np.linalg.norm(view.pose[effector] - goal) < 1e-3), what="the index fingertip on its target"
        )
        report = view.report
        assert report is not None and report.result.status[index] == "reached"
        assert "| Index |" in view.readout.content and "reached" in view.readout.content

        def browser_shows_fingertip() -> bool:
            joints = client_joints(client)
            return joints is not None and float(np.linalg.norm(joints[effector] - goal)) < 2e-3

        client.wait_for(browser_shows_fingertip, what="the browser to receive the curled finger")
        # Back to the chain: the skeleton hides and the chain shows again.
        client.set_value("Preset", "Chain")
        client.wait_for(
            lambda: not view.active and scene.link_nodes.visible and not view.link_nodes.visible,
            what="the chain back, the skeleton hidden",
        )


@pytest.mark.parametrize("bad", [(float("nan"), 0.0, 0.5), (1e12, float("nan"), 0.5), (0.3, float("-inf"), 0.5)])
def test_crafted_skeleton_gizmo_and_preset_messages_keep_the_last_good_state(
    server: viser.ViserServer, scene: ArmScene, bad: tuple[float, float, float]
) -> None:
    view = scene.skeletons
    with BrowserClient(server.get_port()) as client:
        choose_preset(client, scene, "Upper body")
        pose, targets, solves = view.pose.copy(), view.targets.copy(), view.solves
        client.drag_transform("/arm/skeleton/target_0", [bad])
        client.wait_for(lambda: view.gizmo_events >= 3, what="the crafted drag handled")
        client.send_value("Preset", "Octopus")
        client.set_value("Max iterations", 60)  # an honest sentinel edit after the crafted ones
        client.wait_for(lambda: scene.params.max_iterations == 60, what="the sentinel edit")
        with scene._lock:
            assert view.preset == "Upper body"
            np.testing.assert_array_equal(view.pose, pose)
            np.testing.assert_array_equal(view.targets, targets)
            assert view.solves == solves
            np.testing.assert_array_equal(np.asarray(view.gizmos[0].position), targets[0])


@pytest.mark.parametrize("label", ["Robot arm", "Hand", "Upper body"])
def test_a_skeleton_target_dragged_beyond_the_world_box_is_brought_to_its_edge(
    server: viser.ViserServer, scene: ArmScene, label: _skeletons.PresetLabel
) -> None:
    # Past 4 m a Hand or Robot arm target was dropped without a word; the box is now ±8 m and a point beyond it
    # is brought to its edge, as the chain's target is (in the plane of a planar preset).
    edge = [8.0, 0.0 if _skeletons.PRESETS[label]().planar else 0.2, -8.0]
    with BrowserClient(server.get_port()) as client:
        choose_preset(client, scene, label)
        client.drag_transform("/arm/skeleton/target_0", [(1e12, 0.2, -20.0)])
        client.wait_for(lambda: scene.skeletons.gizmo_events >= 3, what="the drag handled")
        with scene._lock:
            np.testing.assert_array_equal(scene.skeletons.targets[0], edge)
            np.testing.assert_array_equal(np.asarray(scene.skeletons.gizmos[0].position), edge)


@pytest.mark.parametrize("label", [label for label in _skeletons.PRESET_LABELS if label != "Chain"])
@pytest.mark.parametrize("size", [(1600, 1000), (1280, 720)])
def test_the_camera_frames_the_shown_skeleton(
    scene: ArmScene, label: _skeletons.PresetLabel, size: tuple[int, int]
) -> None:
    # The kind: a view framed for what is hidden. With a preset shown the camera framed the hidden chain, 0.9 m
    # off, and the hand's gizmos lay off the window (a mouse drag of a fingertip grabbed nothing).
    import math

    from scenes._framing import MARGIN_PX, PANEL_PX, Lens, project_points

    scene.skeletons.show(label)
    lens = Lens(math.radians(75.0), *size)
    view = scene._view_for(lens)
    points = np.vstack([scene.skeletons.pose, scene.skeletons.targets])
    xy = project_points(view, lens, points)
    assert xy[:, 0].min() >= MARGIN_PX - 0.5 and xy[:, 1].min() >= MARGIN_PX - 0.5, label
    assert xy[:, 0].max() <= size[0] - PANEL_PX - MARGIN_PX + 0.5, label
    assert xy[:, 1].max() <= size[1] - MARGIN_PX + 0.5, label
    # Back on the chain, the chain is framed again.
    scene.skeletons.show("Chain")
    xy = project_points(scene._view_for(lens), lens, scene.pose)
    assert xy[:, 0].max() <= size[0] - PANEL_PX - MARGIN_PX + 0.5


# ------------------------------------------------------------------------------------------------ what the panel shows
def shown_elements(client: BrowserClient) -> list[dict]:
    """The GUI elements this browser draws: visible themselves and inside visible folders all the way up."""
    with client._lock:
        gui = dict(client.gui)

    def shown(uuid: str | None) -> bool:
        while uuid is not None and uuid in gui:
            element = gui[uuid]
            if element["props"].get("visible") is False:
                return False
            uuid = element.get("container_uuid")
        return True

    return [element for uuid, element in gui.items() if shown(uuid)]


def shown_labels(client: BrowserClient) -> set[str]:
    return {str(e["props"].get("label")) for e in shown_elements(client) if e["props"].get("label") is not None}


def shown_texts(client: BrowserClient) -> str:
    """Every markdown text this browser draws, and the titles of the charts it draws."""
    parts = []
    for e in shown_elements(client):
        if e["type"] == "GuiMarkdownMessage":
            parts.append(str(e["props"].get("_markdown", e["props"].get("content", ""))))
        elif e["type"] == "GuiUplotMessage":
            parts.append(f"[chart {e['props'].get('title')}]")
    return "\n".join(parts)


CHAIN_ONLY = {
    "Links",
    "Link length (m)",
    "Joint limits",
    "Cone half-angle (°)",
    "Avoid obstacles",
    "Obstacles",
    "Solver",
    "Tolerance (mm)",
    "Max iterations",
    "Straighten the chain",
    "This frame",
}
"""Labels of the chain's own controls and folders (every one acts on the chain alone)."""


@pytest.mark.parametrize("label", ["Robot arm", "Hand", "Upper body"])
def test_a_preset_shows_its_own_readouts_and_controls_only(
    server: viser.ViserServer, scene: ArmScene, label: _skeletons.PresetLabel
) -> None:
    view = scene.skeletons
    with BrowserClient(server.get_port()) as client:
        client.wait_for_gui("Preset")
        client.wait_for(lambda: "status **reached**" in shown_texts(client), what="the chain's readout")
        assert CHAIN_ONLY <= shown_labels(client)  # the chain's panel, as it opens
        assert "[chart Error after each iteration (log scale)]" in shown_texts(client)
        client.set_value("Preset", label)
        client.wait_for(
            lambda: view.preset == label and f"**{label}**" in shown_texts(client), what=f"{label} and its readout"
        )
        client.wait_for(lambda: not (CHAIN_ONLY & shown_labels(client)), what="the chain's controls hidden")
        texts = shown_texts(client)
        # No word of the hidden chain: no "FABRIK: n iterations, error … status …", no ghost, no chain chart.
        assert "status **" not in texts and "Two-bone ghost" not in texts and "[chart" not in texts, texts
        assert "| Effector | Error (mm) | Status |" in texts
        assert {"Preset", "Skeleton"} <= shown_labels(client)
        client.set_value("Preset", "Chain")
        client.wait_for(lambda: CHAIN_ONLY <= shown_labels(client), what="the chain's controls back")
        client.wait_for(lambda: "status **" in shown_texts(client), what="the chain's readout back")
        assert "| Effector |" not in shown_texts(client)


@pytest.mark.parametrize("label", ["Robot arm", "Hand", "Upper body"])
def test_every_preset_opens_solved_by_its_own_solver_settings(
    server: viser.ViserServer, scene: ArmScene, label: _skeletons.PresetLabel
) -> None:
    """A fresh page, the chain's solver turned to a 1-iteration, 50 mm setting first: the preset opens with every
    effector "reached" within its own tolerance, and says which settings it solved with."""
    view = scene.skeletons
    skeleton = _skeletons.PRESETS[label]()
    with BrowserClient(server.get_port()) as client:
        client.wait_for_gui("Preset")
        client.set_value("Max iterations", 1)
        client.set_value("Tolerance (mm)", 50.0)
        client.wait_for(lambda: scene.params.max_iterations == 1, what="the chain's cap at 1")
        client.set_value("Preset", label)
        client.wait_for(lambda: f"**{label}**" in shown_texts(client), what=f"{label}'s readout")
        texts = shown_texts(client)
        rows = [line.split("|")[1:4] for line in texts.splitlines() if line.startswith("| ") and "Effector" not in line]
        assert [name.strip() for name, _, _ in rows] == list(skeleton.effector_labels)
        for name, error_mm, status in rows:
            assert status.strip() == "reached", texts
            assert float(error_mm) <= skeleton.tolerance_mm, (name, texts)
        assert f"tolerance {skeleton.tolerance_mm:g} mm, at most {skeleton.max_iterations} iterations" in texts
        iterations = int(texts.split(f"**{label}**: ")[1].split(" iteration")[0])
        assert 1 <= iterations < skeleton.max_iterations or (iterations == 0 and label != "Upper body")
        # The opening targets are reachable: the pose on them keeps every limit and every link's length.
        with scene._lock:
            pose = view.pose.copy()
        assert np.all(_skeletons.joint_usage(skeleton, pose) <= 1.0 + 1e-9)
        np.testing.assert_allclose(link_lengths(skeleton, pose), link_lengths(skeleton, skeleton.joints), rtol=1e-9)
        for k, effector in enumerate(skeleton.effectors):
            assert np.linalg.norm(pose[effector] - skeleton.targets[k]) <= skeleton.tolerance_mm / 1000.0


# ------------------------------------------------------------------------------------------------ framing
def _free_rect(size: tuple[int, int]) -> tuple[float, float, float, float]:
    from scenes._framing import MARGIN_PX, PANEL_PX

    return MARGIN_PX, size[0] - PANEL_PX - MARGIN_PX, MARGIN_PX, size[1] - MARGIN_PX


def _sphere_extremes(centres: np.ndarray, radius: float) -> np.ndarray:
    """The 8 cube corners around each sphere: a sphere's silhouette lies inside their projection's box."""
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=np.float64)
    return (centres[:, None, :] + radius * corners[None]).reshape(-1, 3)


@pytest.mark.parametrize("size", [(1600, 1000), (1280, 720)])
@pytest.mark.parametrize("what", ["3D chain", "Robot arm", "Hand", "Upper body"])
def test_each_view_frames_everything_it_shows_with_room_and_no_close_up(
    scene: ArmScene, what: str, size: tuple[int, int]
) -> None:
    """The 3D toggle and each preset frame every joint (as a sphere), the base, the ghost, each obstacle sphere and
    each gizmo's arrow tips inside the free view with room at the edges (the 3D view cut the chain at the left and
    top, Robot arm's top joint and Hand's wrist were cut), from far enough that nothing near the camera looms: the
    nearest framed point is at least 0.4 times as far as the farthest (a sphere's drawn size varies at most
    2.5-fold with its depth; framed as close as it could be, 3.4-fold in 3D, and the obstacle sphere hid the base)."""
    import math

    from scenes import arm
    from scenes._framing import Lens, project_points

    if what == "3D chain":
        scene.controls["three_d"].value = True
        with scene._lock:
            report = scene.report
            assert report is not None
            p = scene.params
            axes = np.eye(3)
            tips = np.vstack(
                [h + arm.GIZMO_SCALE_M * axes for h in [scene.target, *scene.obstacle_centres[: p.n_obstacles]]]
            )
            shown = np.vstack(
                [
                    _sphere_extremes(scene.pose, arm.JOINT_RADIUS_M),
                    _sphere_extremes(report.ghost, arm.JOINT_RADIUS_M),
                    *(_sphere_extremes(scene.obstacle_centres[k : k + 1], p.radii_m[k]) for k in range(p.n_obstacles)),
                    tips,
                    arm.box_points(),
                ]
            )
    else:
        scene.skeletons.show(what)  # type: ignore[arg-type]
        view = scene.skeletons
        arrows = np.vstack([t + view.gizmo_scale * np.eye(3) for t in view.targets])
        shown = np.vstack([_sphere_extremes(view.pose, _skeletons.JOINT_RADIUS_M), arrows])
    lens = Lens(math.radians(75.0), *size)
    xy = project_points(scene._view_for(lens), lens, shown)
    left, right, top, bottom = _free_rect(size)
    room_x, room_y = 0.03 * (right - left), 0.03 * (bottom - top)
    assert xy[:, 0].min() >= left + room_x and xy[:, 0].max() <= right - room_x, (what, xy[:, 0].min(), xy[:, 0].max())
    assert xy[:, 1].min() >= top + room_y and xy[:, 1].max() <= bottom - room_y, (what, xy[:, 1].min(), xy[:, 1].max())
    depth = xy[:, 2]
    assert depth.min() >= 0.4 * depth.max(), (what, depth.min(), depth.max())
    # Still a view of the thing, not of empty space: it spans at least half the free width or height.
    fill = max(np.ptp(xy[:, 0]) / (right - left), np.ptp(xy[:, 1]) / (bottom - top))
    assert fill >= 0.5, (what, fill)


def test_hand_gizmos_are_scaled_to_the_fingers_and_leave_the_fingertips_seen(scene: ArmScene) -> None:
    """Each fingertip's gizmo reaches less than half-way to the next fingertip's (they overlapped at 0.12 m), and a
    target's ball is smaller than the fingertip joint on it, so a reached fingertip shows round its target."""
    scene.skeletons.show("Hand")
    view = scene.skeletons
    targets = view.targets
    gaps = np.linalg.norm(targets[:, None] - targets[None], axis=-1)[np.triu_indices(len(targets), 1)]
    assert view.gizmo_scale < 0.5 * gaps.min()
    assert all(g.scale == pytest.approx(view.gizmo_scale) for g in view.gizmos[: len(targets)])
    # The fingertips are drawn as smaller balls in their finger's colour (they were white blobs as big as a joint),
    # and each target's ball is smaller still, so a reached fingertip shows round its target.
    skeleton = view.skeleton
    assert skeleton is not None
    scales = np.asarray(view.joint_nodes.batched_scales)[:, 0]
    colours = np.asarray(view.joint_nodes.batched_colors)
    for k, tip in enumerate(skeleton.effectors):
        assert scales[tip] == pytest.approx(_skeletons.END_RADIUS_M) and scales[tip] < _skeletons.JOINT_RADIUS_M
        np.testing.assert_array_equal(colours[tip], _skeletons.CHAIN_COLOURS[skeleton.chain_of[tip]])
        assert tuple(colours[tip]) != _skeletons.FREE_COLOUR, k
    assert _skeletons.MARKER_RADIUS_M < _skeletons.END_RADIUS_M
    # The robot arm's single target keeps the full-size arrows.
    scene.skeletons.show("Robot arm")
    assert scene.skeletons.gizmo_scale == _skeletons.GIZMO_SCALE_M


def _drag_away_and_back(
    skeleton: _skeletons.Skeleton, effector: int, offset: np.ndarray, steps: int = 8
) -> fabrik.TreeSolution:
    """Frame by frame, as a drag does: effector ``effector``'s target out by ``offset`` and back to its start."""
    pose, targets = skeleton.joints.copy(), skeleton.targets.copy()
    start = targets[effector].copy()
    result = None
    for f in [k / steps for k in range(1, steps + 1)] + [k / steps for k in range(steps - 1, -1, -1)]:
        targets[effector] = start + f * offset
        report = _skeletons.solve_skeleton(
            skeleton, pose, targets, tolerance_m=skeleton.tolerance_mm / 1000.0, max_iterations=skeleton.max_iterations
        )
        pose, result = report.result.joints, report.result
    assert result is not None
    return result


def test_the_upper_body_dragged_away_and_back_reaches_its_opening_targets_again() -> None:
    # An outside tester: the left hand dragged by (0.6, −0.5, −0.6) in 8 steps and back to its start left the head
    # 5.26 mm off its target, "max_iterations": the spine's three pulls needed more than the 100 iterations allowed.
    back = _drag_away_and_back(_skeletons.upper_body(), 2, np.array([0.6, -0.5, -0.6]))
    assert back.status == ("reached", "reached", "reached"), (back.status, back.error)


@pytest.mark.parametrize("label", ["Robot arm", "Hand", "Upper body"])
def test_every_preset_dragged_away_and_back_reaches_its_opening_targets_again(label: _skeletons.PresetLabel) -> None:
    # The family: any effector, any direction, 0.1–0.8 m out and back, ends reached (15 of 40 upper-body drags
    # did not).
    skeleton = _skeletons.PRESETS[label]()
    rng = np.random.default_rng(20261207)
    for _ in range(12):
        effector = int(rng.integers(len(skeleton.effectors)))
        offset = rng.normal(size=3)
        if skeleton.planar:
            offset[1] = 0.0
        offset *= rng.uniform(0.1, 0.8) / np.linalg.norm(offset)
        back = _drag_away_and_back(skeleton, effector, offset)
        assert all(s == "reached" for s in back.status), (effector, offset, back.status, back.error)
