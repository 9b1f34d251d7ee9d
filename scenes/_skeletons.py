"""Skeleton presets of the arm scene: a planar robot arm of hinges, a hand, a humanoid upper body.

Each preset is a tree of joints (:func:`kernels.fabrik.solve_tree`) with a joint type per segment, draggable targets
on its end effectors, and colours: every chain (finger, limb) its own link colour, every joint from green to red as
its segment nears its limit, and each hinge's axis drawn as a short dark bar at the joint it turns about.

The pure part (presets, :func:`solve_skeleton`, :func:`joint_usage`) has no viser; :class:`SkeletonView` owns the
handles, lives inside :class:`scenes.arm.ArmScene` and hides the scene's own chain while a preset is shown.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Literal

import numpy as np
import trimesh
from numpy.typing import NDArray

from kernels import fabrik, warming
from scenes._instances import add_instances, park_hidden

if TYPE_CHECKING:
    import viser

    from scenes.arm import ArmScene

PresetLabel = Literal["Chain", "Robot arm", "Hand", "Upper body"]
PRESET_LABELS: tuple[PresetLabel, ...] = ("Chain", "Robot arm", "Hand", "Upper body")
MAX_JOINTS = 24
MAX_EFFECTORS = 5
WORLD_LIMIT_M = 8.0
"""Targets and obstacles, the chain's and the skeletons', stay inside this box (±m on each axis): 2 m beyond the
longest chain's reach (12 links of 0.5 m), so every chain can be seen stretched toward a target out of its reach.
A position a browser sends beyond it is brought to its edge."""
LINK_RADIUS_M = 0.016
JOINT_RADIUS_M = 0.026
GIZMO_SCALE_M = 0.12
"""Longest arrows a target gizmo has (m); a skeleton's are shorter where its targets lie close together
(:func:`gizmo_scale`). The camera frames their tips."""
END_RADIUS_M = 0.75 * JOINT_RADIUS_M
"""Radius of the ball at each chain's free end (m)."""
MARKER_RADIUS_M = 0.6 * JOINT_RADIUS_M
"""Radius of the coloured ball at each target (m): smaller than an end's, so an effector on its target shows."""
AXIS_HALF_LENGTH_M = 0.05
CHAIN_COLOURS = np.array(
    [(70, 110, 200), (200, 120, 40), (60, 160, 90), (160, 70, 170), (40, 160, 170), (120, 120, 130)], dtype=np.uint8
)
"""Link colour of chain 0, 1, …; the last is the palm and trunk."""
LIMIT_RAMP = np.array([(60, 200, 90), (250, 200, 40), (230, 50, 50)], dtype=np.float64)
"""Joint colour at 0 %, 50 % and 100 % of its limit (as the chain's)."""
FREE_COLOUR = (205, 210, 220)
TARGET_COLOURS = ((230, 40, 60), (240, 140, 30), (40, 150, 230), (150, 60, 200), (30, 170, 120))


@dataclasses.dataclass(frozen=True)
class Skeleton:
    """A preset: a tree of joints in the world (m, z up), its joint types and its effectors' starting targets."""

    name: PresetLabel
    parents: tuple[int, ...]
    """(J,) parent of each joint, −1 for the root."""
    joints: NDArray[np.float64]
    """(J, 3) rest pose (m)."""
    constraints: tuple[fabrik.Constraint, ...]
    """(J,) joint type of the segment from each joint's parent (None for the root and free joints)."""
    chain_of: tuple[int, ...]
    """(J,) colour index of the segment ending at each joint (see :data:`CHAIN_COLOURS`)."""
    effectors: tuple[int, ...]
    """Joints with targets, ascending."""
    effector_labels: tuple[str, ...]
    targets: NDArray[np.float64]
    """(E, 3) opening targets (m)."""
    planar: bool
    """True: targets slide in the x–z plane only."""
    root_direction: tuple[float, float, float] = (0.0, 0.0, 1.0)
    tolerance_mm: float = 1.0
    """The preset's own solver setting: an effector within this distance of its target is "reached" (mm)."""
    max_iterations: int = 200
    """The preset's own solver setting: iterations per solve at most. Dragged away and back to its opening target,
    a Hand finger ended "max_iterations" up to 43 mm off in 2 of 60 drags at 50 (none at 100 or more); a solve that
    cannot reach stops once it stalls, so the cap costs no time there."""


def _chain(start: NDArray[np.float64], directions: list[NDArray[np.float64]], lengths: list[float]) -> list:
    points, here = [], start
    for direction, length in zip(directions, lengths, strict=True):
        here = here + length * direction / np.linalg.norm(direction)
        points.append(here)
    return points


def _turned(u: NDArray[np.float64], axis: NDArray[np.float64], angle: float) -> NDArray[np.float64]:
    """u turned by ``angle`` (rad) about the unit axis (Rodrigues)."""
    return u * math.cos(angle) + np.cross(axis, u) * math.sin(angle) + axis * float(axis @ u) * (1.0 - math.cos(angle))


def robot_arm() -> Skeleton:
    """Four links in the x–z plane, every joint a hinge about the world's y axis with an industrial arm's range
    (shoulder ±92°, elbow −11°…149°, wrist ±109°, flange ±92°, from the previous link)."""
    y = np.array([0.0, 1.0, 0.0])
    lengths = [0.55, 0.45, 0.25, 0.12]
    ranges = [(-1.6, 1.6), (-0.2, 2.6), (-1.9, 1.9), (-1.6, 1.6)]
    direction, points = np.array([0.0, 0.0, 1.0]), [np.zeros(3)]
    for length in lengths:
        direction = _turned(direction, y, 0.25)
        points.append(points[-1] + length * direction)
    hinges = [fabrik.Hinge(y, lo, hi) for lo, hi in ranges]
    return Skeleton(
        name="Robot arm",
        parents=(-1, 0, 1, 2, 3),
        joints=np.array(points),
        constraints=(None, *hinges),
        chain_of=(5, 0, 0, 0, 0),
        effectors=(4,),
        effector_labels=("Tool",),
        targets=np.array([[0.8, 0.0, 0.5]]),
        planar=True,
    )


HAND_SCALE = 5.0
"""The hand is drawn five times life size, so the default camera sees the fingers."""


def hand(curl_rad: float = 0.15, target_curl_rad: float = 0.6) -> Skeleton:
    """A right hand, palm toward the camera (−y): a wrist root, five metacarpals welded to it (hinges of zero
    range), and five fingers of three hinges each flexing toward the palm (MCP −17°…92°, PIP 0…109°, DIP 0…80°;
    the thumb's links a little shorter, with a smaller range). The hand opens with every finger joint curled by
    ``curl_rad`` and the targets where the fingertips are with every joint curled by ``target_curl_rad``."""
    s = HAND_SCALE
    wrist = np.array([0.0, 0.0, 0.2])
    knuckles = [
        np.array([0.032, -0.012, 0.045]),  # thumb (carpometacarpal)
        np.array([0.030, 0.0, 0.090]),
        np.array([0.010, 0.0, 0.094]),
        np.array([-0.010, 0.0, 0.090]),
        np.array([-0.028, 0.0, 0.082]),
    ]
    finger_lengths = [
        [0.035, 0.030, 0.025],
        [0.040, 0.025, 0.020],
        [0.045, 0.028, 0.022],
        [0.042, 0.026, 0.021],
        [0.034, 0.020, 0.018],
    ]
    ranges = [[(-0.3, 0.9), (0.0, 1.2), (0.0, 1.2)]] + [[(-0.3, 1.6), (0.0, 1.9), (0.0, 1.4)]] * 4
    curls = [np.array([-1.0, -0.8, 0.0]), *[np.array([0.0, -1.0, 0.0])] * 4]

    def build(curl: float) -> tuple[list[int], list, list[fabrik.Constraint], list[int], list[int]]:
        parents, chain_of, effectors = [-1], [5], []
        points: list[NDArray[np.float64]] = [wrist]
        constraints: list[fabrik.Constraint] = [None]
        for f in range(5):
            palm = knuckles[f] * s
            u = np.array([0.6, -0.3, 0.75]) if f == 0 else palm / np.linalg.norm(palm)
            u = u / np.linalg.norm(u)
            bend = curls[f] - float(curls[f] @ u) * u
            axis = np.cross(u, bend / np.linalg.norm(bend))  # turning u about it by +θ curls toward the palm
            metacarpal = palm / np.linalg.norm(palm)
            weld_axis = np.cross(metacarpal, np.array([0.0, -1.0, 0.0]))
            parents.append(0)
            points.append(wrist + palm)
            constraints.append(fabrik.Hinge(weld_axis, 0.0, 0.0, reference_axis=metacarpal))
            chain_of.append(5)
            direction = u
            for k, length in enumerate(finger_lengths[f]):
                direction = _turned(direction, axis, curl)
                parents.append(len(points) - 1)
                points.append(points[-1] + s * length * direction)
                lo, hi = ranges[f][k]
                # The first joint is measured from the finger's own rest direction (not the metacarpal's).
                constraints.append(fabrik.Hinge(axis, lo, hi, reference_axis=u if k == 0 else None))
                chain_of.append(f)
            effectors.append(len(points) - 1)
        return parents, points, constraints, chain_of, effectors

    parents, points, constraints, chain_of, effectors = build(curl_rad)
    joints = np.array(points)
    targets = np.array(build(target_curl_rad)[1])[effectors]  # a pose the hand can take
    return Skeleton(
        name="Hand",
        parents=tuple(parents),
        joints=joints,
        constraints=tuple(constraints),
        chain_of=tuple(chain_of),
        effectors=tuple(effectors),
        effector_labels=("Thumb", "Index", "Middle", "Ring", "Little"),
        targets=targets,
        planar=False,
    )


UPPER_BODY_REST_ARM = ((1.0, 0.0, -0.1), (1.0, 0.0, -0.4), (0.6, -0.2, -1.0), (0.3, -0.1, -1.0))
"""Directions of an arm's clavicle, upper arm, forearm and hand at rest (x toward the arm's side, y to the back)."""
UPPER_BODY_REACH = (
    ((-0.15, -0.1), ((1.0, 0.0, -0.05), (1.0, -0.8, -0.2), (0.3, -1.0, 0.6), (0.2, -1.0, 0.6))),
    ((1.0, 0.0, -0.1), (1.0, -0.3, -0.6), (0.4, -0.8, 0.2), (0.2, -1.0, 0.3)),
)
"""The pose the opening targets come from: ((neck lean x, y), right arm directions), left arm directions; the head
nods forward and to the right, the right hand reaches forward to chest height, the left hand forward to the belly."""


def _upper_body_joints(
    neck: tuple[float, float],
    arms: tuple[tuple[tuple[float, float, float], ...], tuple[tuple[float, float, float], ...]],
) -> NDArray[np.float64]:
    """(14, 3) joints of the upper body: a straight spine up from the pelvis, the neck and head leaning by ``neck``
    (x, y per unit height), and the two arms' segments along ``arms`` (right, left; x mirrored for the left)."""
    pelvis = np.array([0.0, 0.0, 0.2])
    head = np.array([neck[0], neck[1], 1.0])
    points = [pelvis, *_chain(pelvis, [np.array([0.0, 0.0, 1.0])] * 3 + [head] * 2, [0.2, 0.2, 0.2, 0.1, 0.2])]
    chest = points[3]
    for side, directions in zip((-1.0, 1.0), arms, strict=True):
        mirrored = [np.array([side * x, y, z]) for x, y, z in directions]
        points.extend(_chain(chest, mirrored, [0.18, 0.3, 0.28, 0.1]))
    return np.array(points)


def upper_body() -> Skeleton:
    """A humanoid upper body of ball joints: pelvis root, a three-link spine, neck and head, and two arms
    (clavicle, upper arm, forearm, hand) from the chest, the chest a sub-base of three branches. Cones: spine 20°,
    neck 29°, head 34°, clavicle 100° and shoulder 80° from the previous link, elbow 137°, wrist 46°.

    The opening targets are the head's and the hands' places in another pose of the same body that keeps every
    limit (:data:`UPPER_BODY_REACH`): reachable together, so the body opens with every effector on its target."""
    parents = [-1, 0, 1, 2, 3, 4]
    cones = [None, 0.35, 0.35, 0.35, 0.5, 0.6]
    chain_of = [5, 5, 5, 5, 2, 2]
    for colour in (0, 1):
        start = len(parents)
        parents.extend([3, start, start + 1, start + 2])
        cones.extend([1.75, 1.4, 2.4, 0.8])
        chain_of.extend([5, colour, colour, colour])
    joints = _upper_body_joints((0.0, 0.0), (UPPER_BODY_REST_ARM, UPPER_BODY_REST_ARM))
    (neck, right), left = UPPER_BODY_REACH
    effectors = (5, 9, 13)
    targets = _upper_body_joints(neck, (right, left))[list(effectors)]
    return Skeleton(
        name="Upper body",
        parents=tuple(parents),
        joints=joints,
        constraints=tuple(None if c is None else fabrik.Cone(c) for c in cones),
        chain_of=tuple(chain_of),
        effectors=effectors,
        effector_labels=("Head", "Right hand", "Left hand"),
        targets=targets,
        planar=False,
        # Three effectors pulling on one spine converge more slowly than one chain: a target dragged away and back
        # left an effector a few mm off, "max_iterations", in 22 of 60 drags at 100 and 9 at 200 (none at 400).
        max_iterations=400,
    )


def gizmo_scale(skeleton: Skeleton) -> float:
    """Arrow length of the skeleton's target gizmos (m): 40 % of the least distance between two of its opening
    targets, at most :data:`GIZMO_SCALE_M`, so neighbouring gizmos (a hand's fingertips) do not overlap."""
    targets = skeleton.targets
    if len(targets) < 2:
        return GIZMO_SCALE_M
    gaps = np.linalg.norm(targets[:, None, :] - targets[None, :, :], axis=-1)
    least = float(np.min(gaps[np.triu_indices(len(targets), 1)]))
    return float(min(GIZMO_SCALE_M, 0.4 * least))


PRESETS: dict[PresetLabel, Callable[[], Skeleton]] = {"Robot arm": robot_arm, "Hand": hand, "Upper body": upper_body}


@dataclasses.dataclass(frozen=True)
class SkeletonReport:
    """The last skeleton solve, as the readouts show it."""

    result: fabrik.TreeSolution
    micros: float
    """Wall time of the kernel call (µs)."""
    usage: NDArray[np.float64]
    """(J,) share of its limit each joint's segment uses, in [0, 1] (0 for the root and free joints)."""


def plain_python_note() -> str:
    """Said after a solve time while the app's first start still compiles the FABRIK kernels (kernels.warming): the
    solve ran as plain Python, so its time is not the compiled solver's."""
    return " (plain Python: the first start is still compiling)" if warming.is_pending("kernels.fabrik") else ""


def joint_usage(skeleton: Skeleton, joints: NDArray[np.float64]) -> NDArray[np.float64]:
    """(J,) how near each segment (parent → joint) is to its limit: :func:`kernels.fabrik.limit_usage` on the
    segment and its parent's."""
    usage = np.zeros(len(skeleton.parents))
    for j, up in enumerate(skeleton.parents):
        constraint = skeleton.constraints[j]
        if up < 0 or constraint is None:
            continue
        grand = skeleton.parents[up]
        if grand < 0:
            usage[j] = fabrik.limit_usage(joints[[up, j]], [constraint], skeleton.root_direction)[0]
        else:
            usage[j] = fabrik.limit_usage(joints[[grand, up, j]], [None, constraint], skeleton.root_direction)[1]
    return usage


def solve_skeleton(
    skeleton: Skeleton,
    pose: NDArray[np.float64],
    targets: NDArray[np.float64],
    *,
    tolerance_m: float,
    max_iterations: int,
) -> SkeletonReport:
    """One frame: every effector toward its target, from the last pose (no viser); where an effector is stuck
    ("limited" more than 10 tolerances away) also from the rest pose, keeping the closer result."""
    goal = {e: targets[k] for k, e in enumerate(skeleton.effectors)}
    began = time.perf_counter()
    solve = functools.partial(
        fabrik.solve_tree,
        skeleton.parents,
        targets=goal,
        tolerance=tolerance_m,
        max_iterations=max_iterations,
        constraints=skeleton.constraints,
        root_direction=skeleton.root_direction,
    )
    result = solve(pose)
    stuck = any(s == "limited" and e > 10.0 * tolerance_m for s, e in zip(result.status, result.error, strict=True))
    if stuck:
        # A finger curled far past its target can settle at a fixed point of FABRIK's hinge passes (the forward
        # pass flips its curled links); from the rest pose it opens. Keep whichever is closer.
        retry = solve(skeleton.joints)
        if float(retry.error.sum()) < float(result.error.sum()):
            result = retry
    micros = (time.perf_counter() - began) * 1e6
    return SkeletonReport(result=result, micros=micros, usage=joint_usage(skeleton, result.joints))


def hinge_axes(skeleton: Skeleton, joints: NDArray[np.float64]) -> NDArray[np.float64]:
    """(H, 2, 3) a short bar along each hinge's world axis, centred on the joint it turns about (m)."""
    bars = []
    rest = np.asarray(skeleton.root_direction)
    for j, constraint in enumerate(skeleton.constraints):
        if not isinstance(constraint, fabrik.Hinge) or constraint.max_angle_rad == constraint.min_angle_rad:
            continue  # a weld has no axis to show
        up = skeleton.parents[j]
        axis = np.asarray(constraint.axis, dtype=np.float64)
        grand = skeleton.parents[up]
        if constraint.frame == "local" and grand >= 0:
            previous = joints[up] - joints[grand]
            previous = previous / max(float(np.linalg.norm(previous)), 1e-12)
            turn = np.cross(rest, previous)
            sin_a, cos_a = float(np.linalg.norm(turn)), float(rest @ previous)
            if sin_a > 1e-12:
                axis = _turned(axis, turn / sin_a, math.atan2(sin_a, cos_a))
        bars.append([joints[up] - AXIS_HALF_LENGTH_M * axis, joints[up] + AXIS_HALF_LENGTH_M * axis])
    return np.array(bars, dtype=np.float64).reshape(-1, 2, 3)


def usage_colours(usage: NDArray[np.float64], free: NDArray[np.bool_]) -> NDArray[np.uint8]:
    """(J, 3) joint colours: the green–yellow–red ramp by usage, grey where the joint has no limit."""
    ramp = np.stack([np.interp(usage, (0.0, 0.5, 1.0), LIMIT_RAMP[:, c]) for c in range(3)], axis=1)
    ramp[free] = FREE_COLOUR
    return ramp.round().astype(np.uint8)


def iterations_words(count: int) -> str:
    """ "1 iteration", "7 iterations"."""
    return f"{count} iteration{'' if count == 1 else 's'}"


def clean_target(raw: object, planar: bool) -> NDArray[np.float64] | None:
    """A browser-sent position as a world point: three finite numbers, brought into the world box
    (:data:`WORLD_LIMIT_M`) and, in the plane, with y put back to 0 (a crafted client may send any y); else None.
    Always a new array: the handle's own, changed in place later (a target flattened when 3D is turned off), would
    leave viser nothing to send."""
    try:
        point = np.array(raw, dtype=np.float64)
    except (TypeError, ValueError):
        return None
    if point.shape != (3,) or not np.all(np.isfinite(point)):
        return None
    point = np.clip(point, -WORLD_LIMIT_M, WORLD_LIMIT_M)
    if planar:
        point[1] = 0.0
    return point


def moved_gizmo(
    gizmo: viser.TransformControlsHandle, last: NDArray[np.float64], planar: bool, *, upright: bool = False
) -> NDArray[np.float64] | None:
    """Where a dragged gizmo now puts its point, cleaned by :func:`clean_target` and drawn there (a crafted y off
    the plane, or a point beyond the world box, is put back); None for a position that cannot be used, with the
    gizmo put back on ``last`` (and upright when ``upright``): the last good point and pose stay."""
    point = clean_target(gizmo.position, planar)
    if point is None:
        gizmo.position = last
        if upright:
            gizmo.wxyz = (1.0, 0.0, 0.0, 0.0)
        return None
    if not np.array_equal(point, np.asarray(gizmo.position, dtype=np.float64)):
        gizmo.position = point
    return point


# --------------------------------------------------------------------------------------------- view
class SkeletonView:
    """The preset dropdown, the skeleton's meshes, hinge axes, target gizmos and readouts, inside the arm scene."""

    def __init__(self, scene: ArmScene, folder: viser.GuiFolderHandle) -> None:
        """Build inside ``scene``; the readout goes in ``folder``, beneath the scene's declared Preset menu."""
        self.scene = scene
        self.preset: PresetLabel = "Chain"
        self.skeleton: Skeleton | None = None
        self.pose = np.zeros((0, 3))
        self.targets = np.zeros((0, 3))
        self.report: SkeletonReport | None = None
        self.gizmo_scale = GIZMO_SCALE_M
        """Arrow length of the shown skeleton's target gizmos (m; :func:`gizmo_scale`)."""
        self.solves = 0
        """Skeleton solves so far (tests wait on it)."""
        self.gizmo_events = 0
        """Skeleton gizmo updates handled, accepted or refused (tests wait on it)."""
        server, root = scene.server, scene.root.name
        gui = server.gui
        with folder:
            self.readout = gui.add_markdown("")
        cylinder = trimesh.creation.cylinder(radius=1.0, height=1.0, sections=12)
        cylinder.apply_translation((0.0, 0.0, 0.5))
        sphere = trimesh.creation.icosphere(subdivisions=2, radius=1.0)
        self.link_nodes = add_instances(
            server.scene,
            f"{root}/skeleton/links",
            cylinder,
            MAX_JOINTS,
            np.tile(CHAIN_COLOURS[0], (MAX_JOINTS, 1)),
            visible=False,
        )
        self.joint_nodes = add_instances(
            server.scene,
            f"{root}/skeleton/joints",
            sphere,
            MAX_JOINTS,
            np.tile(np.array(FREE_COLOUR, np.uint8), (MAX_JOINTS, 1)),
            visible=False,
        )
        self.axes = server.scene.add_line_segments(
            f"{root}/skeleton/hinge_axes",
            points=np.zeros((1, 2, 3), dtype=np.float32),
            colors=(40, 40, 50),
            thickness=0.01,
            visible=False,
        )
        box = (-WORLD_LIMIT_M, WORLD_LIMIT_M)
        self.gizmos = []
        for k in range(MAX_EFFECTORS):
            gizmo = server.scene.add_transform_controls(
                f"{root}/skeleton/target_{k}",
                scale=GIZMO_SCALE_M,
                disable_rotations=True,
                disable_sliders=True,  # arrows only: five gizmos' plane handles hid the fingers they move
                translation_limits=(box, box, box),
                visible=False,
            )
            server.scene.add_icosphere(
                f"{root}/skeleton/target_{k}/marker", radius=MARKER_RADIUS_M, color=TARGET_COLOURS[k]
            )
            # One wrapper per gizmo, made once, so a burst of drag messages coalesces (Scene.callback).
            gizmo.on_update(self.scene.callback(functools.partial(self._apply_target, k)))
            self.gizmos.append(gizmo)

    @property
    def active(self) -> bool:
        """Whether a skeleton preset (not the scene's own chain) is shown."""
        return self.skeleton is not None

    # ----------------------------------------------------------------------------------------- callbacks
    def show(self, label: PresetLabel) -> None:
        """Switch to a preset (its rest pose and opening targets), or back to the chain; the camera frames it."""
        self.preset = label
        self.skeleton = None if label == "Chain" else PRESETS[label]()
        self.scene.show_chain_panel(self.skeleton is None)
        with self.scene.server.atomic():
            self._show_chain(self.skeleton is None)
            for node in (self.link_nodes, self.joint_nodes, self.axes):
                node.visible = self.skeleton is not None
            if self.skeleton is None:
                for gizmo in self.gizmos:
                    gizmo.visible = False
                self.readout.content = ""
        if self.skeleton is None:
            self.report = None
            self.scene.solve_and_draw()
            self.scene.framing.reframe()
            return
        sk = self.skeleton
        self.pose = sk.joints.copy()
        self.targets = sk.targets.copy()
        self.gizmo_scale = gizmo_scale(sk)
        axes = (True, False, True) if sk.planar else (True, True, True)
        with self.scene.server.atomic():
            for k, gizmo in enumerate(self.gizmos):
                shown = k < len(sk.effectors)
                gizmo.visible = shown
                if shown:
                    gizmo.active_axes = axes
                    gizmo.scale = self.gizmo_scale
                    gizmo.position = self.targets[k]
        self.solve_and_draw()
        self.scene.framing.reframe()

    def _show_chain(self, visible: bool) -> None:
        s = self.scene
        for node in (s.link_nodes, s.joint_nodes, s.ghost_links, s.ghost_elbow, s.target_gizmo, s.base_node):
            node.visible = visible
        for k in range(len(s.obstacle_gizmos)):
            shown = visible and k < s.params.n_obstacles
            s.obstacle_gizmos[k].visible = shown
            s.obstacle_discs[k].visible = shown and not s.params.three_d
            s.obstacle_spheres[k].visible = shown and s.params.three_d

    def after_chain_draw(self) -> None:
        """The chain scene drew itself: keep it hidden while a preset is shown."""
        if self.active:
            with self.scene.server.atomic():
                self._show_chain(False)

    def _apply_target(self, k: int) -> None:
        self.gizmo_events += self.scene.messages_in_call
        sk = self.skeleton
        if sk is None or k >= len(sk.effectors):
            return
        point = moved_gizmo(self.gizmos[k], self.targets[k], sk.planar, upright=True)
        if point is None or np.array_equal(point, self.targets[k]):
            return
        self.targets[k] = point
        self.solve_and_draw()

    # ----------------------------------------------------------------------------------------- solve + draw
    def solve_and_draw(self) -> None:
        sk = self.skeleton
        if sk is None:
            return
        report = solve_skeleton(
            sk, self.pose, self.targets, tolerance_m=sk.tolerance_mm / 1000.0, max_iterations=sk.max_iterations
        )
        self.pose = report.result.joints
        self.report = report
        self.solves += 1
        self._draw(sk, report)

    def _draw(self, sk: Skeleton, report: SkeletonReport) -> None:
        from scenes.arm import segment_pose  # the chain's own segment geometry (imported late: arm imports us)

        joints = report.result.joints
        count = len(sk.parents)
        children = [j for j in range(count) if sk.parents[j] >= 0]
        starts = joints[[sk.parents[j] for j in children]]
        wxyz, lengths = segment_pose(starts, joints[children])
        links = len(children)
        link_wxyz = np.tile([1.0, 0.0, 0.0, 0.0], (MAX_JOINTS, 1))
        link_wxyz[:links] = wxyz
        link_pos = np.zeros((MAX_JOINTS, 3))
        link_pos[:links] = starts
        link_scale = np.zeros((MAX_JOINTS, 3))
        link_scale[:links] = np.stack([np.full(links, LINK_RADIUS_M)] * 2 + [lengths], axis=1)
        link_colour = np.tile(CHAIN_COLOURS[0], (MAX_JOINTS, 1))
        link_colour[:links] = CHAIN_COLOURS[[sk.chain_of[j] for j in children]]
        joint_pos = np.zeros((MAX_JOINTS, 3))
        joint_pos[:count] = joints
        joint_scale = np.zeros((MAX_JOINTS, 3))
        joint_scale[:count] = JOINT_RADIUS_M
        free = np.array([c is None for c in sk.constraints])
        # A joint shows how near its outgoing segments are to their limits (the nearest of them).
        nearness = np.zeros(count)
        limited = np.ones(count, dtype=np.bool_)
        for j in children:
            up = sk.parents[j]
            nearness[up] = max(nearness[up], report.usage[j])
            limited[up] = limited[up] and free[j]
        joint_colour = np.tile(np.array(FREE_COLOUR, np.uint8), (MAX_JOINTS, 1))
        joint_colour[:count] = usage_colours(nearness, limited)
        # An end (fingertip, hand, head) has no limit to show: a smaller ball in its chain's colour, so it reads as
        # the tip of that chain rather than as a white blob over it.
        ends = [j for j in range(count) if j not in sk.parents and sk.parents[j] >= 0]
        joint_scale[ends] = END_RADIUS_M
        joint_colour[ends] = CHAIN_COLOURS[[sk.chain_of[j] for j in ends]]
        bars = hinge_axes(sk, joints)
        with self.scene.server.atomic():
            self.link_nodes.batched_wxyzs = link_wxyz.astype(np.float32)
            self.link_nodes.batched_positions = park_hidden(link_pos, link_scale)
            self.link_nodes.batched_scales = link_scale.astype(np.float32)
            self.link_nodes.batched_colors = link_colour
            self.joint_nodes.batched_positions = park_hidden(joint_pos, joint_scale)
            self.joint_nodes.batched_scales = joint_scale.astype(np.float32)
            self.joint_nodes.batched_colors = joint_colour
            if len(bars):
                self.axes.points = bars.astype(np.float32)
            self.axes.visible = bool(len(bars))
            self.readout.content = self._readout(sk, report)
        self.scene.server.flush()

    def _readout(self, sk: Skeleton, report: SkeletonReport) -> str:
        r = report.result
        rows = "\n".join(
            f"| {label} | {r.error[k] * 1000.0:.2f} | {r.status[k]} |" for k, label in enumerate(sk.effector_labels)
        )
        return (
            f"**{sk.name}**: {iterations_words(r.iterations)}, "
            f"solve **{report.micros:,.0f} µs**{plain_python_note()}  \n"
            f"Multi-end-effector FABRIK, tolerance {sk.tolerance_mm:g} mm, "
            f"at most {iterations_words(sk.max_iterations)}."
            f"\n\n| Effector | Error (mm) | Status |\n|---|---|---|\n{rows}"
        )
