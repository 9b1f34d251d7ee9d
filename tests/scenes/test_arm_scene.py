"""The arm scene through a real ViserServer: handles read back, a browser-like websocket client, bad input."""

from __future__ import annotations

import dataclasses
import itertools
import math
import re

import numpy as np
import pytest
import viser
from helpers.scenes import scene_fixture
from helpers.wsclient import BrowserClient

from kernels import fabrik
from scenes.arm import MAX_LINKS, TARGET_START, ArmParams, ArmScene, rest_pose, solve_arm, why_short

scene = scene_fixture(ArmScene)


def drawn_joints(scene: ArmScene) -> np.ndarray:
    """World joint positions as the batched joint mesh shows them (visible instances only)."""
    positions = np.asarray(scene.joint_nodes.batched_positions)
    scales = np.asarray(scene.joint_nodes.batched_scales)
    return positions[scales[:, 0] > 0]


def clearance(joints: np.ndarray, centre: np.ndarray) -> float:
    best = math.inf
    for a, b in itertools.pairwise(joints):
        seg = b - a
        t = min(1.0, max(0.0, float((centre - a) @ seg / (seg @ seg))))
        best = min(best, float(np.linalg.norm(a + t * seg - centre)))
    return best


# ------------------------------------------------------------------------------------------------ server side
def test_opening_state_reaches_the_target_around_the_obstacle(scene: ArmScene) -> None:
    p = ArmParams()
    report = scene.report
    assert report is not None
    assert report.result.status == "reached"
    assert np.linalg.norm(scene.pose[-1] - TARGET_START) < p.tolerance_mm / 1000.0
    np.testing.assert_allclose(fabrik.link_lengths(scene.pose), p.link_length_m, rtol=1e-9)
    assert np.all(scene.pose[:, 1] == 0.0)  # planar: the chain stays in the x–z plane
    # The obstacle sits on the straight line to the target: the chain goes round it.
    assert clearance(scene.pose, scene.obstacle_centres[0]) >= p.radii_m[0]
    # What is drawn is what was solved: 7 joints shown, the other instances scaled to zero.
    np.testing.assert_allclose(drawn_joints(scene), scene.pose, atol=1e-6)
    link_scales = np.asarray(scene.link_nodes.batched_scales)
    np.testing.assert_allclose(link_scales[: p.n_links, 2], p.link_length_m, rtol=1e-5)
    assert np.all(link_scales[p.n_links :] == 0.0)
    # The ghost is the exact two-bone answer: its end is on the target.
    assert report.ghost_error_m < 1e-9
    assert "status **reached**" in scene.readout.content
    assert f"{report.result.iterations} iteration" in scene.readout.content
    counts, history = (np.asarray(d) for d in scene.plot.data)
    np.testing.assert_array_equal(counts, np.arange(1, report.result.iterations + 1))
    assert history[-1] == pytest.approx(report.result.error * 1000.0)  # the chart ends on the readout's error
    assert history[-1] < 1.0  # mm, below the tolerance


def test_two_links_ghost_is_the_fabrik_solution(scene: ArmScene) -> None:
    scene.controls["n_obstacles"].value = 0
    scene.controls["tolerance_mm"].value = 0.01
    scene.controls["max_iterations"].value = 500
    scene.controls["n_links"].value = 2
    scene.target_gizmo.position = (0.3, 0.0, 0.2)  # inside the 0.5 m reach
    scene._apply_target()
    report = scene.report
    assert report is not None and report.result.status == "reached"
    assert report.ghost_gap_m < 1e-3  # the analytic elbow is FABRIK's elbow, to within a millimetre
    assert "FABRIK's elbow" in scene.ghost_readout.content


@pytest.mark.parametrize("solver", ["CCD", "Jacobian DLS"])
def test_the_ghost_readout_names_the_solver_it_compares_with(scene: ArmScene, solver: str) -> None:
    # Once: it said "FABRIK's elbow" whichever solver had placed the elbow.
    scene.controls["n_links"].value = 2
    scene.controls["solver"].value = solver
    assert scene.params.solver == solver
    assert f"from {solver}'s elbow." in scene.ghost_readout.content
    assert "FABRIK" not in scene.ghost_readout.content
    scene.controls["n_links"].value = 3
    assert "from the chain's middle joint." in scene.ghost_readout.content


def test_more_links_and_joint_limits(scene: ArmScene) -> None:
    scene.controls["n_links"].value = MAX_LINKS
    scene.controls["half_angle_deg"].value = 30.0
    scene.controls["limits"].value = True
    assert len(drawn_joints(scene)) == MAX_LINKS + 1
    angles = fabrik.joint_angles(scene.pose[:, [0, 2]], [0.0, 1.0])
    assert np.all(angles <= math.radians(30.0) + 1e-6)
    report = scene.report
    assert report is not None and report.result.status == "reached"
    # 3 m of chain curled onto a target 1.08 m away: several joints sit at their limit, drawn red; the free end grey.
    colours = np.asarray(scene.joint_nodes.batched_colors)[: MAX_LINKS + 1]
    at_limit = angles > math.radians(29.9)
    assert at_limit.sum() >= 3
    assert np.all(colours[:-1][at_limit][:, 0] >= 220) and np.all(colours[:-1][at_limit][:, 1] <= 60)
    relaxed = angles < math.radians(5.0)
    assert np.all(colours[:-1][relaxed][:, 1] >= 190)  # green
    np.testing.assert_array_equal(colours[-1], (205, 210, 220))


def test_obstacles_are_avoided_and_ignored_when_avoidance_is_off(scene: ArmScene) -> None:
    scene.controls["avoid"].value = False
    free_pose = scene.pose.copy()
    # Put the obstacle on the middle joint of the unobstructed solution, then let the chain avoid it.
    scene.obstacle_gizmos[0].position = tuple(free_pose[3])
    scene._apply_obstacle(0)
    # Avoidance off: the chain goes straight through the obstacle's centre.
    assert clearance(scene.pose, free_pose[3]) == 0.0
    scene.controls["avoid"].value = True
    report = scene.report
    assert report is not None and report.result.status == "reached"
    assert clearance(scene.pose, free_pose[3]) >= scene.params.radii_m[0]
    scene.controls["n_obstacles"].value = 4
    for k in range(4):
        assert clearance(scene.pose, scene.obstacle_centres[k]) >= scene.params.radii_m[k]
        assert scene.obstacle_discs[k].visible and not scene.obstacle_spheres[k].visible


def test_an_obstacle_over_the_root_is_ignored_and_said_so(scene: ArmScene) -> None:
    scene.obstacle_gizmos[0].position = (0.05, 0.0, 0.05)
    scene._apply_obstacle(0)
    report = scene.report
    assert report is not None and report.result.status == "reached"
    assert "Obstacle 1 covers the root and cannot be avoided" in scene.readout.content
    # An outside tester read "Obstacle 1, 2 covers the root" for two.
    scene.controls["n_obstacles"].value = 2
    scene.obstacle_gizmos[1].position = (0.0, 0.0, 0.0)
    scene._apply_obstacle(1)
    assert "Obstacles 1 and 2 cover the root and cannot be avoided" in scene.readout.content, scene.readout.content


def test_solvers_all_reach_the_target(scene: ArmScene) -> None:
    for label in ("CCD", "Jacobian DLS", "FABRIK"):
        scene.pose = rest_pose(6, 0.25)
        scene.controls["solver"].value = label
        report = scene.report
        assert report is not None
        assert report.result.status == "reached", label
        assert f"**{label}**" in scene.readout.content


def test_three_d_mode_frees_the_target(scene: ArmScene) -> None:
    scene.controls["three_d"].value = True
    assert scene.target_gizmo.active_axes == (True, True, True)
    assert scene.obstacle_spheres[0].visible and not scene.obstacle_discs[0].visible
    assert not scene.grid.visible
    scene.target_gizmo.position = (0.4, 0.5, 0.9)
    scene._apply_target()
    assert np.linalg.norm(scene.pose[-1] - [0.4, 0.5, 0.9]) < 1e-3
    # Back to the plane: everything is flattened onto y = 0 and solved there.
    scene.controls["three_d"].value = False
    assert scene.target[1] == 0.0 and np.all(scene.pose[:, 1] == 0.0)
    assert scene.target_gizmo.active_axes == (True, False, True)


def test_solve_arm_is_pure() -> None:
    report = solve_arm(ArmParams(n_obstacles=0), rest_pose(6, 0.25), TARGET_START, np.zeros((4, 3)))
    assert report.result.status == "reached"
    assert report.result.joints.shape == (7, 3)


# ------------------------------------------------------------------------------------------------ over the websocket
def client_joints(client: BrowserClient) -> np.ndarray | None:
    """Joint positions of the visible instances as the fake browser last received them."""
    return client.visible_instances("/arm/joints")


def test_dragging_the_target_gizmo_moves_the_chain_end_onto_it(server: viser.ViserServer, scene: ArmScene) -> None:
    with BrowserClient(server.get_port()) as client:
        client.wait_for_node("/arm/target")
        path = [(0.9 - 0.05 * i, 0.0, 0.6 + 0.04 * i) for i in range(1, 13)]
        client.drag_transform("/arm/target", path, period_s=0.01)
        goal = np.array(path[-1])
        client.wait_for(lambda: bool(np.linalg.norm(scene.pose[-1] - goal) < 1e-3), what="the chain end on the target")
        assert scene.report is not None and scene.report.result.status == "reached"

        def browser_shows_end_on_target() -> bool:
            joints = client_joints(client)
            return joints is not None and float(np.linalg.norm(joints[-1] - goal)) < 2e-3

        client.wait_for(browser_shows_end_on_target, what="the browser to receive the new pose")


def test_an_off_plane_drag_is_put_back_in_the_plane(server: viser.ViserServer, scene: ArmScene) -> None:
    with BrowserClient(server.get_port()) as client:
        client.wait_for_node("/arm/target")
        client.drag_transform("/arm/target", [(0.7, 0.4, 0.9)])  # y = 0.4: a crafted client, out of the plane
        client.wait_for(lambda: scene.gizmo_events >= 3, what="the drag handled")
        with scene._lock:
            np.testing.assert_array_equal(scene.target, (0.7, 0.0, 0.9))
            # The gizmo is drawn where the chain solves, not where the message put it.
            np.testing.assert_array_equal(np.asarray(scene.target_gizmo.position), (0.7, 0.0, 0.9))


def test_the_target_and_obstacles_a_person_moved_are_parameters_a_control_keeps(
    server: viser.ViserServer, scene: ArmScene
) -> None:
    # Everything a person sets is in the scene's parameters: the gizmos' places too, kept when a control changes.
    with BrowserClient(server.get_port()) as client:
        client.wait_for_node("/arm/obstacle_0")
        client.drag_transform("/arm/target", [(0.7, 0.0, 0.9)])
        client.drag_transform("/arm/obstacle_0", [(-0.4, 0.0, 0.5)])
        client.wait_for(lambda: scene.gizmo_events >= 6, what="both drags handled")
        client.set_value("Links", 7)
        client.wait_for(lambda: scene.params.n_links == 7, what="the new chain")
    with scene.state_lock:
        assert scene.params.target == (0.7, 0.0, 0.9)
        assert scene.params.obstacle_centres[0] == (-0.4, 0.0, 0.5)
        assert scene.params.obstacle_centres[1:] == ArmParams().obstacle_centres[1:]
        assert scene.report is not None
        assert np.linalg.norm(scene.pose[-1] - (0.7, 0.0, 0.9)) <= scene.report.result.error + 1e-12


def test_leaving_3d_puts_every_gizmo_the_browser_moved_back_on_the_plane(
    server: viser.ViserServer, scene: ArmScene
) -> None:
    # Once the target stayed off the plane in the browser, its y axis locked, while the chain solved for its
    # projection and read "reached": the scene flattened its target in place, which was the gizmo's own array, so
    # viser saw no change to send.
    with BrowserClient(server.get_port()) as client:
        client.wait_for_node("/arm/obstacle_0")
        client.set_value("3D (free target, sphere obstacles)", True)
        client.wait_for(lambda: scene.params.three_d, what="3D on")
        client.drag_transform("/arm/target", [(0.7, 0.8, 0.9)])
        client.drag_transform("/arm/obstacle_0", [(-0.4, -0.6, 0.5)])
        client.wait_for(lambda: scene.gizmo_events >= 6, what="both drags handled")
        client.set_value("3D (free target, sphere obstacles)", False)
        client.wait_for(lambda: not scene.params.three_d, what="back to the plane")
        client.wait_for(
            lambda: client.pose_of("/arm/target")[0][1] == 0.0 and client.pose_of("/arm/obstacle_0")[0][1] == 0.0,
            what="both gizmos shown on the plane",
        )
        assert client.pose_of("/arm/target")[0] == (0.7, 0.0, 0.9)
        assert client.pose_of("/arm/obstacle_0")[0] == (-0.4, 0.0, 0.5)
        with scene._lock:
            np.testing.assert_array_equal(scene.target, (0.7, 0.0, 0.9))
            assert scene.report is not None
            assert np.linalg.norm(scene.pose[-1] - scene.target) <= scene.report.result.error + 1e-12


@pytest.mark.parametrize("bad", [(float("nan"), 0.0, 0.5), (float("inf"), 0.0, 0.5), (0.3, float("nan"), 0.5)])
def test_crafted_gizmo_messages_keep_the_last_good_pose(
    server: viser.ViserServer, scene: ArmScene, bad: tuple[float, float, float]
) -> None:
    with BrowserClient(server.get_port()) as client:
        client.wait_for_node("/arm/target")
        good = (0.7, 0.0, 0.9)
        client.drag_transform("/arm/target", [good])
        # A drag is three messages (start, move, end), each running the gizmo's callback once.
        client.wait_for(lambda: scene.gizmo_events >= 3, what="the good drag handled")
        assert np.linalg.norm(scene.pose[-1] - good) < 1e-3
        pose_before = scene.pose.copy()
        solves = scene.solves
        client.drag_transform("/arm/target", [bad])
        client.wait_for(lambda: scene.gizmo_events >= 6, what="the crafted drag handled")
        with scene._lock:
            np.testing.assert_array_equal(scene.pose, pose_before)
            np.testing.assert_array_equal(scene.target, good)
            assert scene.solves == solves
            # What every browser is told is the last good target.
            np.testing.assert_array_equal(np.asarray(scene.target_gizmo.position), good)


@pytest.mark.parametrize(
    ("sent", "kept"),
    [
        ((7.0, 0.0, 0.5), (7.0, 0.0, 0.5)),
        ((1e12, 0.0, 0.5), (8.0, 0.0, 0.5)),
        ((-30.0, 2.0, -9.0), (-8.0, 0.0, -8.0)),
        ((20.0, -1e300, 0.5), (8.0, 0.0, 0.5)),
    ],
)
def test_a_target_beyond_the_longest_reach_is_brought_into_the_world_box_and_solved(
    server: viser.ViserServer, scene: ArmScene, sent: tuple[float, float, float], kept: tuple[float, float, float]
) -> None:
    """Kind: a target the longest chain cannot be shown reaching for. The world box was ±4 m where 12 links of
    0.5 m reach 6 m: a drag past 4 m was dropped without a word (the gizmo stopped at 3.998 m in Chromium), so that
    chain could never show "unreachable" along an axis. The box is now 2 m past the longest reach, and a point
    beyond it is brought to its edge."""
    scene.controls["n_links"].value = 12
    scene.controls["link_length_m"].value = 0.5
    with BrowserClient(server.get_port()) as client:
        client.wait_for_node("/arm/target")
        client.drag_transform("/arm/target", [sent])
        client.wait_for(lambda: scene.gizmo_events >= 3, what="the drag handled")
        with scene._lock:
            np.testing.assert_array_equal(scene.target, kept)
            np.testing.assert_array_equal(np.asarray(scene.target_gizmo.position), kept)
            report = scene.report
            assert report is not None and report.result.status == "unreachable"
            # Stretched straight at the target: every joint on the line from the base toward it.
            toward = np.asarray(kept) / np.linalg.norm(kept)
            np.testing.assert_allclose(scene.pose, np.outer(0.5 * np.arange(13), toward), atol=1e-9)


def test_crafted_obstacle_message_and_slider_values_keep_a_good_state(
    server: viser.ViserServer, scene: ArmScene
) -> None:
    with BrowserClient(server.get_port()) as client:
        client.wait_for_node("/arm/obstacle_0")
        centre = scene.obstacle_centres[0].copy()
        client.drag_transform("/arm/obstacle_0", [(float("nan"), 0.0, 0.0)])
        client.wait_for(lambda: scene.gizmo_events >= 3, what="the crafted obstacle drag handled")
        client.wait_for_gui("Links")
        for label, value in (
            ("Links", float("nan")),  # viser itself drops a NaN for an int slider
            ("Links", 1000),
            ("Tolerance (mm)", -5.0),
            ("Solver", "Newton"),
            ("Cone half-angle (°)", float("inf")),
            ("Joint limits", "yes"),
        ):
            client.send_value(label, value)
        # Every callback re-reads every control, so once this last, honest edit shows, the crafted ones are cleaned.
        client.set_value("Max iterations", 77)
        client.wait_for(lambda: scene.params.max_iterations == 77, what="the sentinel edit applied")
        with scene._lock:
            p = scene.params
            np.testing.assert_array_equal(scene.obstacle_centres[0], centre)
            # 1000 is clamped to the slider's max; NaN kept the last value.
            assert p.n_links == MAX_LINKS
            assert p.tolerance_mm == pytest.approx(0.01)  # clamped to the slider's min
            assert p.solver == "FABRIK"
            assert p.half_angle_deg == 45.0
            assert p.limits is False
            assert np.all(np.isfinite(scene.pose)) and scene.pose.shape == (MAX_LINKS + 1, 3)
            report = scene.report
            assert report is not None and report.result.status == "reached"


def test_clicking_in_the_plane_places_the_target(server: viser.ViserServer, scene: ArmScene) -> None:
    with BrowserClient(server.get_port()) as client:
        client.wait_for_node("/arm/target")
        # A ray from the camera side (−y) through (−0.5, 0, 1.0).
        origin = (-0.5, -4.0, 1.0)
        client.click_scene(origin, (0.0, 1.0, 0.0))
        client.wait_for(
            lambda: bool(np.allclose(scene.target, (-0.5, 0.0, 1.0))), what="the target placed by the click"
        )
        client.wait_for(
            lambda: bool(np.linalg.norm(scene.pose[-1] - (-0.5, 0.0, 1.0)) < 1e-3), what="the chain to follow"
        )
        np.testing.assert_allclose(np.asarray(scene.target_gizmo.position), (-0.5, 0.0, 1.0))


def test_a_target_the_limits_keep_away_reads_limited_not_unreachable(scene: ArmScene) -> None:
    """A target inside the reach that 5° cones cannot bend to is "limited", with the best pose seen."""
    scene.controls["n_obstacles"].value = 0
    scene.controls["limits"].value = True
    scene.controls["half_angle_deg"].value = 5.0
    report = scene.report
    assert report is not None
    assert np.linalg.norm(TARGET_START) < 6 * 0.25  # inside the reach
    assert report.result.status == "limited"
    assert "status **limited**" in scene.readout.content
    # The starting pose (the last frame's) breaks the new limits; of the iterates, the best comes back.
    assert report.result.error <= report.result.error_history[1:].min()
    angles = fabrik.joint_angles(scene.pose[:, [0, 2]], [0.0, 1.0])
    assert np.all(angles <= math.radians(5.0) + 1e-6)


def test_the_view_frames_what_matters_not_the_whole_reach(scene: ArmScene) -> None:
    from scenes.arm import GIZMO_SCALE_M, framed_points

    scene.controls["n_links"].value = 12
    scene.controls["link_length_m"].value = 0.5  # a 6 m reach
    with scene._lock:
        points = framed_points(scene.params, scene.pose, scene.target, scene.obstacle_centres)
        pose, target = scene.pose.copy(), scene.target.copy()
    lo, hi = points.min(axis=0), points.max(axis=0)
    # Every joint, the target and its gizmo arrows are inside; the box is the chain's, not the 12 m wide reach.
    assert np.all(pose >= lo) and np.all(pose <= hi)
    assert np.all(target + GIZMO_SCALE_M * np.array([1.0, 0.0, 1.0]) <= hi + 1e-12)
    reach = 12 * 0.5
    width, height = hi[0] - lo[0], hi[2] - lo[2]
    assert width < reach and height < reach, (width, height)  # the whole reach framed 2 × 6 m by 6 m


def test_moving_the_target_out_of_the_framed_box_frames_again(scene: ArmScene) -> None:
    from scenes._framing import Lens

    calls: list[int] = []
    scene.framing.reframe = lambda: calls.append(1)  # type: ignore[method-assign]
    with scene._lock:
        scene._view_for(Lens(0.9, 1600, 1000))
        scene.target = scene.target + np.array([0.05, 0.0, 0.0])  # a small move stays in the frame
        scene.solve_and_draw()
        scene._reframe_if_outgrown()
        assert calls == []
        scene.target = np.array([-1.4, 0.0, 0.2])  # across to the other side
        scene.solve_and_draw()
        scene._reframe_if_outgrown()
        assert calls == [1]


def test_the_panel_opens_with_the_skeleton_menu_above_about(server: viser.ViserServer, scene: ArmScene) -> None:
    """The preset menu is a declared control like any other, and its folder still comes first in the scene's panel."""
    with BrowserClient(server.get_port()) as client:
        client.wait_for_gui("Preset")
        folders = {
            element["props"].get("label"): element
            for element in list(client.gui.values())
            if element["type"] == "GuiFolderMessage"
        }
        skeleton, about = folders["Skeleton"], folders["About"]
        assert skeleton["container_uuid"] == about["container_uuid"]
        assert skeleton["props"]["order"] < about["props"]["order"]


# ------------------------------------------------------------------------------------------------ short of the target
def best_admissible_by_sampling(
    params: ArmParams, target: np.ndarray, centres: np.ndarray, count: int = 200_000
) -> float:
    """An independent reference: the closest end (m) of ``count`` random planar poses that keep every cone limit and
    clear every obstacle (each link turned by a uniform angle within ±half-angle from the last, the base from up)."""
    rng = np.random.default_rng(7)
    phi = math.radians(params.half_angle_deg)
    angles = np.cumsum(rng.uniform(-phi, phi, (count, params.n_links)), axis=1)
    steps = params.link_length_m * np.stack([np.sin(angles), np.cos(angles)], axis=-1)
    joints = np.concatenate([np.zeros((count, 1, 2)), np.cumsum(steps, axis=1)], axis=1)
    admissible = np.ones(count, dtype=bool)
    for k in range(params.n_obstacles):
        centre = centres[k, [0, 2]]
        a, seg = joints[:, :-1], np.diff(joints, axis=1)
        t = np.clip(((centre - a) * seg).sum(-1) / (seg * seg).sum(-1), 0.0, 1.0)
        admissible &= np.linalg.norm(a + t[..., None] * seg - centre, axis=-1).min(axis=1) >= params.radii_m[k]
    errors = np.linalg.norm(joints[:, -1] - target[[0, 2]], axis=1)
    return float(errors[admissible].min())


def readout_error_mm(text: str) -> float:
    return float(text.split("error **")[1].split(" mm")[0])


def test_joint_limits_switched_on_over_a_reached_target_keep_the_closest_admissible_pose(
    server: viser.ViserServer, scene: ArmScene
) -> None:
    """The chain reaches (0.1, 0.98) round the obstacle; ticking 45° limits once swung it away to end "blocked"
    216 mm short, though random admissible poses come within 13 mm. Now it ends at least as close as they do, and the
    chart ends on the readout's error, never rising (it plots the pose the solver would return: the best so far)."""
    goal = (0.1, 0.0, 0.98)
    with BrowserClient(server.get_port()) as client:
        client.wait_for_node("/arm/target")
        client.drag_transform("/arm/target", [goal])
        client.wait_for(lambda: bool(np.linalg.norm(scene.pose[-1] - goal) < 1e-3), what="the target reached")
        client.wait_for_gui("Joint limits")
        client.set_value("Joint limits", True)
        client.wait_for(lambda: scene.params.limits, what="limits on")
        with scene._lock:
            params, target, centres = scene.params, scene.target.copy(), scene.obstacle_centres.copy()
            report, text = scene.report, scene.readout.content
            counts, chart = (np.asarray(d, dtype=np.float64) for d in scene.plot.data)
        assert report is not None
        reference = best_admissible_by_sampling(params, target, centres)
        assert reference < 0.05  # an admissible pose 13 mm off exists
        error_mm = readout_error_mm(text)
        assert error_mm <= reference * 1000.0 + 1.0, (error_mm, reference, text)
        angles = fabrik.joint_angles(scene.pose[:, [0, 2]], [0.0, 1.0])
        assert np.all(angles <= math.radians(45.0) + 1e-6)
        assert clearance(scene.pose, centres[0]) >= params.radii_m[0] - 1e-9
        assert chart[-1] == pytest.approx(error_mm, abs=5e-4)  # the readout rounds to 0.001 mm
        assert np.all(np.diff(chart) <= 1e-9), chart
        assert np.all(np.diff(counts) > 0)


def test_the_chart_plots_the_best_admissible_pose_not_the_iterates(scene: ArmScene) -> None:
    """20° cones over the reached default pose: the iterates wander (their error ends near 520 mm) while the pose
    returned is the best admissible one; the chart shows that pose's error after each iteration, ending on it."""
    scene.controls["half_angle_deg"].value = 20.0
    scene.controls["limits"].value = True
    report = scene.report
    assert report is not None and report.result.status != "reached"
    counts, chart = (np.asarray(d, dtype=np.float64) for d in scene.plot.data)
    assert chart[-1] == pytest.approx(report.result.error * 1000.0)
    assert readout_error_mm(scene.readout.content) == pytest.approx(chart[-1], abs=5e-4)
    assert np.all(np.diff(chart) <= 1e-9)
    # Each point is what a run capped at that many iterations returns, from the same start.
    from scenes.arm import _run, _solve_kwargs, arc_starts, to_kernel

    starts = {
        "last pose": None,
        **{f"gently bent start {k + 1} of 9": pose for k, pose in enumerate(arc_starts(scene.params, scene.target))},
    }
    start = starts[report.start]
    # Said in words a user has: it read "a worse fixed point ... solved from arc 8 of 9".
    assert "fixed point" not in scene.readout.content and "arc " not in scene.readout.content
    if start is not None:
        assert f"solved again from a {report.start}" in scene.readout.content
        for k, value in zip(counts[:3], chart[:3], strict=True):
            kwargs = _solve_kwargs(scene.params, scene.obstacle_centres) | {"max_iterations": int(k)}
            capped = _run("fabrik", to_kernel(start, False), to_kernel(scene.target, False), **kwargs)
            assert capped.error * 1000.0 == pytest.approx(value)


@pytest.mark.parametrize(
    ("setup", "words"),
    [
        ({"target": (1.6, 0.0, 0.6)}, "beyond the chain's reach of 1.50 m"),
        ({"target": (0.45, 0.0, 0.5)}, "the target is inside obstacle 1"),
        ({"target": (0.0, 0.0, 1.4), "obstacle": (0.0, 0.0, 0.75), "radius": 0.6}, "obstacle 1 is in the way"),
        ({"limits": 5.0, "n_obstacles": 0}, "at the 5° joint limit"),
    ],
)
def test_a_short_pose_says_in_words_why(scene: ArmScene, setup: dict, words: str) -> None:
    if "n_obstacles" in setup:
        scene.controls["n_obstacles"].value = setup["n_obstacles"]
    if "radius" in setup:
        scene.controls.each("radii_m")[0].value = setup["radius"]
    if "obstacle" in setup:
        scene.obstacle_gizmos[0].position = setup["obstacle"]
        scene._apply_obstacle(0)
    if "limits" in setup:
        scene.controls["half_angle_deg"].value = setup["limits"]
        scene.controls["limits"].value = True
    if "target" in setup:
        scene.target_gizmo.position = setup["target"]
        scene._apply_target()
    report = scene.report
    assert report is not None and report.result.status != "reached"
    text = scene.readout.content
    assert f"Short by **{report.result.error * 1000.0:.1f} mm**" in text, text
    assert words in text.lower(), text
    # Reached again: no excuse is left on the readout.
    scene.controls["limits"].value = False
    scene.controls["n_obstacles"].value = 0
    scene.target_gizmo.position = (0.5, 0.0, 0.9)
    scene._apply_target()
    assert scene.report is not None and scene.report.result.status == "reached"
    assert "Short by" not in scene.readout.content


def test_a_limited_chain_with_joints_to_spare_is_not_said_to_be_held_by_its_limits(scene: ArmScene) -> None:
    # An outside tester: 20° cones, target (0.3, 0, 1.2), "Short by 239.7 mm: The base is at the 20° joint limit",
    # while the other joints bent 6–14° and a pose that keeps every cone ends 63.6 mm short. "limited" is a fixed
    # point of the solver, not proof; the words say so where joints are left to spare.
    scene.controls["half_angle_deg"].value = 20.0
    scene.controls["limits"].value = True
    scene.target_gizmo.position = (0.3, 0.0, 1.2)
    scene._apply_target()
    report = scene.report
    assert report is not None and report.result.status == "limited"
    text = scene.readout.content
    assert "the base is at the 20° joint limit (the other joints bend up to" in text.lower(), text
    assert "a closer pose may exist" in text
    # It does: bends of −20, 1.8, 20, 20, 20, 20° (each within the cone) clear obstacle 1 and end 63.6 mm short.
    headings = np.cumsum(np.radians([-20.0, 1.8, 20.0, 20.0, 20.0, 20.0]))
    ends = np.cumsum(0.25 * np.column_stack([np.sin(headings), np.cos(headings)]), axis=0)
    closer = float(np.linalg.norm(ends[-1] - [0.3, 1.2]))
    assert closer == pytest.approx(0.0636, abs=1e-4) and closer < report.result.error - 0.1
    pose = np.vstack([[0.0, 0.0], ends])
    assert clearance(np.column_stack([pose[:, 0], np.zeros(7), pose[:, 1]]), scene.obstacle_centres[0]) > 0.5


def test_a_limited_chain_with_every_joint_at_its_limit_is_not_said_to_be_held_by_them(scene: ArmScene) -> None:
    # An outside tester: 20° cones, target (−1, 0, 0.5): "Short by 186.7 mm: The base, joint 2 … joint 6 are at the
    # 20° joint limit", as if the limits held it there, while a pose within every cone ends 128.8 mm short.
    scene.controls["half_angle_deg"].value = 20.0
    scene.controls["limits"].value = True
    scene.target_gizmo.position = (-1.0, 0.0, 0.5)
    scene._apply_target()
    report = scene.report
    assert report is not None and report.result.status == "limited"
    text = scene.readout.content
    assert "joint 6 are at the 20° joint limit; the solver settled here, and a closer pose may exist" in text, text
    # It does (found by SLSQP from 300 starts): bends of −13.4, then −20° five times; it clears obstacle 1.
    headings = np.cumsum(np.radians([-13.4, -20.0, -20.0, -20.0, -20.0, -20.0]))
    ends = np.cumsum(0.25 * np.column_stack([np.sin(headings), np.cos(headings)]), axis=0)
    closer = float(np.linalg.norm(ends[-1] - [-1.0, 0.5]))
    assert closer == pytest.approx(0.1288, abs=1e-4) and closer < report.result.error - 0.05
    pose = np.vstack([[0.0, 0.0], ends])
    assert clearance(np.column_stack([pose[:, 0], np.zeros(7), pose[:, 1]]), scene.obstacle_centres[0]) > 0.3


def test_a_target_inside_two_obstacles_names_them_in_the_plural(scene: ArmScene) -> None:
    # An outside tester read "The target is inside obstacle 1 and 2".
    scene.controls["n_obstacles"].value = 2
    for k, centre in enumerate([(0.9, 0.0, 0.6), (0.95, 0.0, 0.62)]):
        scene.obstacle_gizmos[k].position = centre
        scene._apply_obstacle(k)
    scene.target_gizmo.position = (0.9, 0.0, 0.6)
    scene._apply_target()
    assert "the target is inside obstacles 1 and 2" in scene.readout.content.lower(), scene.readout.content


def test_a_straight_chain_held_by_0_degree_limits_is_not_said_to_have_a_closer_pose(scene: ArmScene) -> None:
    # At 0° the straight chain is the only pose: "a closer pose may exist" was wrong there.
    scene.controls["half_angle_deg"].value = 0.0
    scene.controls["limits"].value = True
    scene.controls["n_obstacles"].value = 0
    scene.target_gizmo.position = (0.8, 0.0, 0.9)
    scene._apply_target()
    assert scene.report is not None and scene.report.result.status != "reached"
    text = scene.readout.content
    assert "at the 0° joint limit" in text and "closer pose" not in text, text


def test_two_obstacles_in_the_way_are_named_in_the_plural(scene: ArmScene) -> None:
    # An outside tester read "Obstacle 1 and 2 is in the way (the chain rests against it)".
    scene.controls["n_obstacles"].value = 2
    for k, centre in enumerate([(0.3, 0.0, 0.12), (0.94, 0.0, 0.53)]):
        scene.controls.each("radii_m")[k].value = 0.31
        scene.obstacle_gizmos[k].position = centre
        scene._apply_obstacle(k)
    scene.target_gizmo.position = (1.31, 0.0, 0.7)
    scene._apply_target()
    assert scene.report is not None and scene.report.result.status == "blocked"
    text = scene.readout.content.lower()
    assert "obstacles 1 and 2 are in the way (the chain rests against them)" in text, text
    assert " is in the way" not in text


def test_a_solve_from_another_start_is_told_in_a_users_words(scene: ArmScene) -> None:
    # The outside tester's input, on the defaults (limits off, one obstacle avoided): Link length 0.5, then Links 2.
    # The readout blamed "the joint limits", which were off; the obstacle held the arm.
    scene.controls["link_length_m"].value = 0.5
    scene.controls["n_links"].value = 2
    report = scene.report
    assert report is not None and report.start == "gently bent start 8 of 9"
    text = scene.readout.content
    assert (
        "From the last pose obstacle 1 held the arm farther from the target, so this pose was solved again from a "
        "gently bent start 8 of 9" in text
    ), text
    assert "joint limit" not in text
    assert "fixed point" not in text and "arc " not in text


RESTARTS = {
    # setup: (n_links, link_length_m, half_angle_deg, target), and the (limits, n_obstacles, avoid) that restart there
    "limits hold": (
        (6, 0.25, 20.0, (1.08, 0.0, 0.47)),
        # Without limits the kernel's own restart takes this one around the obstacle from the last pose.
        {(True, 0, True), (True, 0, False), (True, 1, True), (True, 1, False)},
    ),
    "the obstacle holds": ((2, 0.5, 45.0, (0.9, 0.0, 0.6)), {(True, 1, True), (False, 1, True)}),
}


@pytest.mark.parametrize("setup", list(RESTARTS))
@pytest.mark.parametrize(
    ("limits", "n_obstacles", "avoid"), list(itertools.product([True, False], [0, 1], [True, False]))
)
def test_a_restart_names_only_what_is_on_and_held_the_arm(
    scene: ArmScene, setup: str, limits: bool, n_obstacles: int, avoid: bool
) -> None:
    """Every combination of limits × obstacles × avoidance, solved from the rest pose where other starts come
    closer: the readout's restart sentence names what held the last pose's solve (a joint at its limit, the obstacle
    it rests against) and never a constraint that is off or absent; with nothing on, no other start is tried."""
    (n_links, length, half_angle, target), restarting = RESTARTS[setup]
    scene.controls["limits"].value = limits
    scene.controls["n_obstacles"].value = n_obstacles
    scene.controls["avoid"].value = avoid
    scene.controls["half_angle_deg"].value = half_angle
    scene.controls["n_links"].value = n_links
    scene.controls["link_length_m"].value = length
    scene.target_gizmo.position = target
    scene._apply_target()
    scene._on_reset_pose()  # solved from the rest pose: what the table above was measured from
    report, text = scene.report, scene.readout.content
    assert report is not None
    restarted = (limits, n_obstacles, avoid) in restarting
    assert (report.start != "last pose") == restarted, (report.start, text)
    if not restarted:
        assert "held the arm" not in text and "solved again" not in text, text
        return
    sentence = text.split("From the last pose")[1].split("held the arm")[0]
    assert ("joint limit" in sentence) <= limits, text
    assert ("obstacle" in sentence) <= (avoid and n_obstacles > 0), text
    first = report.last_pose_solution
    assert first is not None
    # What held the last pose's solve, found here independently of the scene's words.
    angles = fabrik.joint_angles(first.joints[:, [0, 2]], [0.0, 1.0])
    at_limit = limits and bool(np.any(angles >= math.radians(half_angle - 0.5)))
    radius = scene.params.radii_m[0]
    touching = (
        avoid and n_obstacles == 1 and clearance(first.joints, scene.obstacle_centres[0]) <= radius * 1.001 + 1e-4
    )
    causes = [c for c, held in (("the joint limits", at_limit), ("obstacle 1", touching)) if held] or [
        c for c, on in (("the joint limits", limits), ("obstacle 1", avoid and n_obstacles == 1)) if on
    ]
    assert causes  # a restart happens only under a constraint that is on
    said = f"From the last pose {' and '.join(causes)} held the arm farther from the target, so this pose was solved "
    assert said + f"again from a {report.start}" in text, text


def test_iteration_counts_read_in_good_english(scene: ArmScene) -> None:
    # An outside tester read "still closing in after 1 iterations".
    scene.controls["tolerance_mm"].value = 0.01
    scene.controls["max_iterations"].value = 1
    scene.target_gizmo.position = (-0.6, 0.0, 0.9)
    scene._apply_target()
    report = scene.report
    assert report is not None and report.result.iterations == 1 and report.result.status != "reached"
    text = scene.readout.content
    assert re.search(r"\b1 iterations\b", text) is None
    assert "**FABRIK**: 1 iteration," in text and "after 1 iteration (raise Max iterations)" in text


def test_the_iteration_cap_is_not_blamed_where_the_joint_limits_hold_the_end_off(scene: ArmScene) -> None:
    # Kind: advice that cannot help. At Max iterations 1 a chain of 0° cones read "still closing in after 1 iteration
    # (raise Max iterations)"; at 500 the same pose, 984.9 mm short, reads "limited".
    scene.controls["limits"].value = True
    scene.controls["half_angle_deg"].value = 0.0
    scene.controls["max_iterations"].value = 1
    scene.target_gizmo.position = (-0.4, 0.0, 0.6)
    scene._apply_target()
    report = scene.report
    assert report is not None and report.result.status == "max_iterations"
    text = scene.readout.content
    assert "at the 0° joint limit" in text and "it stopped at its cap of 1 iteration" in text
    assert "raise Max iterations" not in text and "closing in" not in text


def test_a_stall_beside_an_obstacle_without_limits_is_said_to_be_beside_it(scene: ArmScene) -> None:
    # An outside tester: the kernel said "limited" with no joint limits, stalled 1.6 mm clear of an obstacle, and the
    # readout's only words were "the iterations stalled there". (The kernel's restart now goes round that case; the
    # words stay for a stall it does not.)
    scene.controls["limits"].value = False
    scene.controls["n_obstacles"].value = 1
    scene.controls["avoid"].value = True
    report = scene.report
    assert report is not None
    stalled = dataclasses.replace(report, result=dataclasses.replace(report.result, status="limited", error=0.0314))
    words = why_short(scene.params, stalled, scene.target, scene.obstacle_centres)
    assert words == (
        "Short by **31.4 mm**: The iterations stalled beside obstacle 1, clear of it, and a closer pose may exist."
    )
    scene.controls["avoid"].value = False  # an obstacle the chain may pass through holds nothing
    words = why_short(scene.params, stalled, scene.target, scene.obstacle_centres)
    assert words == "Short by **31.4 mm**: The iterations stalled there."


@pytest.mark.parametrize("radii", [(0.6, 0.6, 0.6, 0.6), (0.3, 0.4, 0.5, 0.6)])
def test_overlapping_obstacle_discs_never_share_a_face_plane(scene: ArmScene, radii: tuple[float, ...]) -> None:
    # An outside tester: four discs of radius 0.6 overlapped in torn, jagged patches: their faces lay in one plane,
    # which the depth test split between them. Each disc now stands 2 mm nearer the camera than the one before, at
    # a thickness its radius does not change.
    scene.controls["n_obstacles"].value = 4
    for k, radius in enumerate(radii):
        scene.controls.each("radii_m")[k].value = radius
    faces = []
    for k, disc in enumerate(scene.obstacle_discs):
        assert disc.visible
        y = np.asarray(disc.vertices)[:, 1] * np.asarray(disc.scale)[1] + np.asarray(disc.position)[1]
        assert y.min() < 0.0 < y.max()  # it still stands across the chain's plane
        width = np.ptp(np.asarray(disc.vertices)[:, 0]) * np.asarray(disc.scale)[0]
        assert width == pytest.approx(2.0 * radii[k], rel=1e-3)  # drawn at its radius
        faces += [y.min(), y.max()]
    gaps = np.diff(np.sort(faces))
    assert gaps.min() >= 1e-3, np.sort(faces)
