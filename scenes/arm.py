"""Arm: drag a target and watch a 2–12 link chain follow it by FABRIK, with joint limits and obstacles.

Inverse kinematics comes from :mod:`kernels.fabrik`; this module owns the viser handles. The chain is two batched
meshes (links as unit cylinders, joints as spheres) with one instance per link or joint; unused instances are
scaled to zero, so changing the link count never re-adds a node. A translucent ghost shows the analytic two-bone
solution for comparison.

Planar by default: the chain moves in the world's x–z plane (kernel coordinates (x, z), d = 2), the target gizmo
slides only in that plane and obstacles are circles, drawn as discs. The 3D toggle frees the target (d = 3) and
makes the obstacles spheres.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time
from dataclasses import field
from typing import Any, Literal

import numpy as np
import trimesh
import viser
import viser.uplot
from numpy.typing import NDArray

from kernels import fabrik
from scenes._base import Scene
from scenes._charts import FittedChart, number_scales
from scenes._controls import build_controls, checkbox, declared, dropdown, slider
from scenes._framing import ClientFraming, Lens, View, frame_points
from scenes._instances import add_instances, park_hidden
from scenes._skeletons import JOINT_RADIUS_M as SKELETON_JOINT_M
from scenes._skeletons import (
    PRESET_LABELS,
    WORLD_LIMIT_M,
    PresetLabel,
    SkeletonView,
    clean_target,
    iterations_words,
    moved_gizmo,
    plain_python_note,
)

MAX_LINKS = 12
MAX_OBSTACLES = 4
LINK_RADIUS_M = 0.018
JOINT_RADIUS_M = 0.03

SolverLabel = Literal["FABRIK", "CCD", "Jacobian DLS"]
SOLVER_FROM_LABEL: dict[SolverLabel, fabrik.Solver] = {"FABRIK": "fabrik", "CCD": "ccd", "Jacobian DLS": "jacobian_dls"}

REST_COLOUR = (205, 210, 220)
GHOST_COLOUR = (120, 190, 255)
OBSTACLE_COLOUR = (235, 120, 60)
TARGET_COLOUR = (230, 40, 60)
PLANE_VIEW = (0.0, 1.0, -0.12)
"""Planar mode looks at the x–z plane from −y, a little from above."""
SPACE_VIEW = (0.55, 1.0, -0.6)
"""3D mode looks from the front left (−x, −y) and above, so depth reads at once without orbiting; the chain bends
away from the camera (toward +x), so the obstacles and the target lie beyond the base, not in front of it."""
LIMIT_RAMP = np.array([(60, 200, 90), (250, 200, 40), (230, 50, 50)], dtype=np.float64)
"""Joint colour at 0 %, 50 % and 100 % of its limit."""


@dataclasses.dataclass(frozen=True)
class ArmParams:
    """Everything the scene's own chain shows is a function of these; defaults open the scene.

    Each field but the gizmos' is also its GUI control, declared once (:mod:`scenes._controls`), in the order and
    folder shown; the target and the obstacle centres are set by dragging their gizmos (or clicking, for the target).
    """

    preset: PresetLabel = field(default="Chain", metadata=dropdown("Preset", PRESET_LABELS, folder="Skeleton"))
    """What is shown: the scene's own chain, or a skeleton preset (:mod:`scenes._skeletons`) in its place."""
    n_links: int = field(default=6, metadata=slider("Links", 2, MAX_LINKS, 1, folder="Chain"))
    """Links in the chain (2–12)."""
    link_length_m: float = field(default=0.25, metadata=slider("Link length (m)", 0.05, 0.5, 0.01, folder="Chain"))
    """Length of every link (m)."""
    three_d: bool = field(default=False, metadata=checkbox("3D (free target, sphere obstacles)", folder="Chain"))
    """False: the chain moves in the vertical x–z plane; True: in 3D."""
    limits: bool = field(default=False, metadata=checkbox("Joint limits", folder="Joint limits"))
    """Whether joint limits (cones) apply."""
    half_angle_deg: float = field(
        default=45.0, metadata=slider("Cone half-angle (°)", 0.0, 180.0, 1.0, folder="Joint limits")
    )
    """Cone half-angle of every joint (degrees)."""
    avoid: bool = field(default=True, metadata=checkbox("Avoid obstacles", folder="Obstacles"))
    """Whether the solver avoids the obstacles (when off they are drawn but ignored)."""
    n_obstacles: int = field(default=1, metadata=slider("Obstacles", 0, MAX_OBSTACLES, 1, folder="Obstacles"))
    """Obstacles shown (0–4)."""
    radii_m: tuple[float, ...] = field(
        default=(0.18, 0.15, 0.12, 0.2), metadata=slider("Obstacle {n} radius (m)", 0.03, 0.6, 0.01, folder="Obstacles")
    )
    """Radius of each obstacle (m): one slider each."""
    solver: SolverLabel = field(
        default="FABRIK", metadata=dropdown("Solver", tuple(SOLVER_FROM_LABEL), folder="Solver")
    )
    """Iterative method."""
    tolerance_mm: float = field(default=1.0, metadata=slider("Tolerance (mm)", 0.01, 50.0, 0.01, folder="Solver"))
    """Stop when the end effector is this close to the target (mm)."""
    max_iterations: int = field(default=50, metadata=slider("Max iterations", 1, 500, 1, folder="Solver"))
    """Iteration cap per solve."""
    target: tuple[float, float, float] = (0.9, 0.0, 0.6)
    """Where the end effector is sent (world, m): the target gizmo's position (y = 0 on the plane)."""
    obstacle_centres: tuple[tuple[float, float, float], ...] = (
        (0.45, 0.0, 0.45),
        (-0.6, 0.0, 0.9),
        (0.3, 0.0, 1.45),
        (-0.4, 0.0, 0.3),
    )
    """Each obstacle's centre (world, m), its gizmo's position: :data:`MAX_OBSTACLES` of them, the first
    ``n_obstacles`` shown."""


OBSTACLE_STARTS = np.array(ArmParams().obstacle_centres)
"""Where the obstacles open (world, m), (MAX_OBSTACLES, 3)."""
TARGET_START = np.array(ArmParams().target)
"""Where the target opens (world, m)."""


@dataclasses.dataclass(frozen=True)
class SolveReport:
    """The last solve, as the readouts show it."""

    result: fabrik.Solution
    micros: float
    """Wall time of the kernel calls that made the pose (µs): the solve, and the other starts where it fell short."""
    ghost: NDArray[np.float64]
    """(3, 3) world root, elbow and end of the analytic two-bone ghost (m)."""
    ghost_error_m: float
    """Distance of the ghost's end from the target (m)."""
    ghost_gap_m: float
    """Distance from the ghost's elbow to the chain's middle joint (m); for two links, the solver's elbow."""
    best_history: tuple[NDArray[np.float64], NDArray[np.float64]] = (np.zeros(1), np.zeros(1))
    """(iterations (K,), error (K,) m): the error of the pose the solver would return after that many iterations,
    the best admissible one it has seen (:func:`admissible_history`); the last is ``result.error``."""
    start: str = "last pose"
    """Where the returned pose's solve started: "last pose", or the gently bent start that came closer."""
    last_pose_solution: fabrik.Solution | None = None
    """The solve from the last pose (world joints) when another start's pose was returned instead; else None."""


def rest_pose(n_links: int, link_length_m: float) -> NDArray[np.float64]:
    """(n + 1, 3) world joints of a gentle arc up from the root, bending toward +x in the x–z plane."""
    angles = 0.12 * np.arange(n_links)
    directions = np.stack([np.sin(angles), np.zeros(n_links), np.cos(angles)], axis=1)
    return np.vstack([np.zeros(3), np.cumsum(link_length_m * directions, axis=0)])


def to_kernel(points: NDArray[np.float64], three_d: bool) -> NDArray[np.float64]:
    """World (…, 3) → kernel coordinates: (…, 3) in 3D, (…, 2) = (x, z) in the plane."""
    return points if three_d else points[..., [0, 2]]


def to_world(points: NDArray[np.float64], three_d: bool) -> NDArray[np.float64]:
    """Kernel coordinates → world (…, 3)."""
    if three_d:
        return points
    return np.stack([points[..., 0], np.zeros(points.shape[:-1]), points[..., 1]], axis=-1)


def segment_pose(start: NDArray[np.float64], end: NDArray[np.float64]) -> tuple[NDArray[np.float64], ...]:
    """wxyz (N, 4) turning +z onto each segment, and lengths (N,), for (N, 3) starts and ends."""
    offset = end - start
    length = np.linalg.norm(offset, axis=1)
    direction = offset / np.where(length > 1e-12, length, 1.0)[:, None]
    direction[length <= 1e-12] = (0.0, 0.0, 1.0)
    # Half-way quaternion from +z to d: (1 + d_z, z × d) normalised; antiparallel: 180° about x.
    wxyz = np.stack([1.0 + direction[:, 2], -direction[:, 1], direction[:, 0], np.zeros(len(length))], axis=1)
    flipped = direction[:, 2] < -1.0 + 1e-9
    wxyz[flipped] = (0.0, 1.0, 0.0, 0.0)
    return wxyz / np.linalg.norm(wxyz, axis=1, keepdims=True), length


def limit_colours(joints: NDArray[np.float64], params: ArmParams) -> NDArray[np.uint8]:
    """(n + 1, 3) joint colours: green far from the limit, yellow at half, red at it; grey without limits."""
    count = joints.shape[0]
    if not params.limits:
        return np.tile(np.array(REST_COLOUR, np.uint8), (count, 1))
    phi = math.radians(params.half_angle_deg)
    angles = fabrik.joint_angles(to_kernel(joints, params.three_d), _root_direction(params.three_d))
    share = np.ones(count - 1) if phi <= 0.0 else np.clip(angles / phi, 0.0, 1.0)
    ramp = np.stack([np.interp(share, (0.0, 0.5, 1.0), LIMIT_RAMP[:, c]) for c in range(3)], axis=1)
    end = np.array([REST_COLOUR], dtype=np.float64)
    return np.vstack([ramp, end]).round().astype(np.uint8)


def _point(xyz: NDArray[np.float64]) -> tuple[float, float, float]:
    """A (3,) point as the parameters hold it."""
    x, y, z = (float(v) for v in xyz)
    return (x, y, z)


def _root_direction(three_d: bool) -> NDArray[np.float64]:
    return np.array([0.0, 0.0, 1.0]) if three_d else np.array([0.0, 1.0])


def _solve_kwargs(params: ArmParams, obstacle_centres: NDArray[np.float64]) -> dict[str, Any]:
    three_d = params.three_d
    obstacles = (
        [(to_kernel(obstacle_centres[k], three_d), params.radii_m[k]) for k in range(params.n_obstacles)]
        if params.avoid
        else []
    )
    return {
        "tolerance": params.tolerance_mm / 1000.0,
        "max_iterations": params.max_iterations,
        "cone_half_angle_rad": math.radians(params.half_angle_deg) if params.limits else None,
        "obstacles": obstacles,
        "root_direction": _root_direction(three_d),
    }


def _run(
    method: fabrik.Solver, start: NDArray[np.float64], goal: NDArray[np.float64], **kwargs: Any
) -> fabrik.Solution:
    match method:
        case "fabrik":
            return fabrik.solve(start, goal, **kwargs)
        case "ccd":
            return fabrik.ccd(start, goal, **kwargs)
        case "jacobian_dls":
            return fabrik.jacobian_dls(start, goal, **kwargs)


ARC_STARTS = 9
"""Other starts tried when a constrained solve falls short: this many arcs, each link turned by the same angle from
the last, from the cone's −half-angle to +half-angle (or ±60° without limits), in the vertical plane of the target."""


def arc_starts(params: ArmParams, target: NDArray[np.float64]) -> list[NDArray[np.float64]]:
    """(ARC_STARTS,) world poses (n + 1, 3) that keep every joint limit: arcs of constant bend up from the root,
    in the vertical plane through the target (the x–z plane when planar)."""
    bend = math.radians(params.half_angle_deg) if params.limits else math.radians(60.0)
    across = np.array([target[0], target[1] if params.three_d else 0.0])
    across = across / np.linalg.norm(across) if np.linalg.norm(across) > 1e-9 else np.array([1.0, 0.0])
    poses = []
    for turn in np.linspace(-bend, bend, ARC_STARTS):
        angles = turn * np.arange(1, params.n_links + 1)
        steps = np.stack([np.sin(angles) * across[0], np.sin(angles) * across[1], np.cos(angles)], axis=1)
        poses.append(np.vstack([np.zeros(3), np.cumsum(params.link_length_m * steps, axis=0)]))
    return poses


def constrained(params: ArmParams) -> bool:
    """Whether some iterate or start may break a joint limit or cut an obstacle (so not every pose is admissible)."""
    return params.limits or (params.avoid and params.n_obstacles > 0)


HISTORY_POINTS = 24
"""Most iteration counts :func:`admissible_history` replays (evenly spread, the last always included)."""


def admissible_history(
    params: ArmParams,
    start: NDArray[np.float64],
    target: NDArray[np.float64],
    obstacle_centres: NDArray[np.float64],
    result: fabrik.Solution,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """What the solver would return after k iterations, for k up to ``result.iterations``: (k (K,), error (K,) m).

    The solvers return the best admissible pose they have seen (every limit kept, every obstacle cleared), not the
    last iterate, and stop from what the iterates did alone, so a run capped at k iterations repeats the first k
    iterations of the full run and returns the best admissible pose among them: its error is the k-th point. Without
    limits or obstacles every iterate is admissible and the points are the running minimum of the error history.
    Counts where no admissible pose had been seen yet (status "infeasible") are left out; where the whole run saw
    none, the one point is the pose it returns, at its last iteration (never an empty chart: uPlot's client throws
    on empty data and draws no curve)."""
    history = result.error_history
    if result.iterations == 0:
        return np.zeros(1), np.array([result.error])
    if not constrained(params):
        counts = np.arange(1, len(history))
        return counts.astype(np.float64), np.minimum.accumulate(history)[1:]
    counts = np.unique(np.round(np.linspace(1, result.iterations, min(result.iterations, HISTORY_POINTS))))
    counts = counts.astype(np.int64)
    kwargs = _solve_kwargs(params, obstacle_centres)
    method = SOLVER_FROM_LABEL[params.solver]
    kept_k, kept_e = [], []
    for k in counts[:-1]:
        kwargs["max_iterations"] = int(k)
        capped = _run(method, to_kernel(start, params.three_d), to_kernel(target, params.three_d), **kwargs)
        if capped.status != "infeasible":
            kept_k.append(float(k))
            kept_e.append(capped.error)
    if result.status != "infeasible" or not kept_k:
        kept_k.append(float(result.iterations))
        kept_e.append(result.error)
    return np.array(kept_k), np.array(kept_e)


CHART_FLOOR_MM = 1e-6
"""Least error the log-scale chart plots (mm): an exact hit (0) has no logarithm."""


def chart_points(report: SolveReport) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The error chart's (iterations (K,), error (K,) mm): :attr:`SolveReport.best_history`, which has at least one
    point (:func:`admissible_history`: uPlot's client throws "object null is not iterable" on empty series), floored
    at :data:`CHART_FLOOR_MM` for the log scale."""
    counts, errors = report.best_history
    return counts.astype(np.float64), np.maximum(errors * 1000.0, CHART_FLOOR_MM)


def solve_arm(
    params: ArmParams,
    joints: NDArray[np.float64],
    target: NDArray[np.float64],
    obstacle_centres: NDArray[np.float64],
    *,
    history: bool = True,
) -> SolveReport:
    """Solve one frame: the chosen solver from ``joints`` toward ``target``, and the two-bone ghost (no viser).

    Where limits or obstacles apply and the solve falls short of the tolerance, it is run again from the rest-like
    arcs of :func:`arc_starts`, and the closest admissible pose of all is kept (the last pose's unless another is
    closer by more than the tolerance): a fixed point reached from one start is not proof that no closer pose exists.
    ``history``: also replay the returned solve for :attr:`SolveReport.best_history`."""
    three_d = params.three_d
    kwargs = _solve_kwargs(params, obstacle_centres)
    goal = to_kernel(target, three_d)
    method = SOLVER_FROM_LABEL[params.solver]
    began = time.perf_counter()
    result = _run(method, to_kernel(joints, three_d), goal, **kwargs)
    start, start_name = joints, "last pose"
    from_last_pose = result
    tolerance = params.tolerance_mm / 1000.0
    if result.status != "reached" and constrained(params):
        for k, pose in enumerate(arc_starts(params, target)):
            other = _run(method, to_kernel(pose, three_d), goal, **kwargs)
            if other.status != "infeasible" and other.error < result.error - tolerance:
                result, start, start_name = other, pose, f"gently bent start {k + 1} of {ARC_STARTS}"
    micros = (time.perf_counter() - began) * 1e6
    best = (
        admissible_history(params, start, target, obstacle_centres, result) if history else (np.zeros(1), np.zeros(1))
    )

    kernel_start = to_kernel(joints, three_d)
    lengths = fabrik.link_lengths(kernel_start)
    upper, lower = (lengths[0], lengths[1]) if len(lengths) == 2 else (lengths.sum() / 2, lengths.sum() / 2)
    middle = result.joints[len(lengths) // 2]
    bend = middle - result.joints[0]
    ghost = fabrik.two_bone(kernel_start[0], float(upper), float(lower), goal, bend)
    return SolveReport(
        result=dataclasses.replace(result, joints=to_world(result.joints, three_d)),
        micros=micros,
        ghost=to_world(ghost, three_d),
        ghost_error_m=float(np.linalg.norm(ghost[2] - goal)),
        ghost_gap_m=float(np.linalg.norm(ghost[1] - middle)),
        best_history=best,
        start=start_name,
        last_pose_solution=(
            None
            if start_name == "last pose"
            else dataclasses.replace(from_last_pose, joints=to_world(from_last_pose.joints, three_d))
        ),
    )


def segment_clearance(joints: NDArray[np.float64], centre: NDArray[np.float64]) -> float:
    """Least distance (m) from ``centre`` (3,) to the chain's segments (joints (n + 1, 3))."""
    a, b = joints[:-1], joints[1:]
    seg = b - a
    t = np.clip(np.einsum("ij,ij->i", centre - a, seg) / np.maximum(np.einsum("ij,ij->i", seg, seg), 1e-300), 0, 1)
    return float(np.min(np.linalg.norm(a + t[:, None] * seg - centre, axis=1)))


def _listed(words: list[str]) -> str:
    return words[0] if len(words) == 1 else ", ".join(words[:-1]) + " and " + words[-1]


def _obstacles(numbers: list[int]) -> str:
    """ "obstacle 2", "obstacles 1 and 2" (numbered from 1)."""
    return f"obstacle{'s' if len(numbers) > 1 else ''} {_listed([str(k) for k in numbers])}"


def avoided_obstacles(params: ArmParams, obstacle_centres: NDArray[np.float64]) -> list[int]:
    """Indices of the obstacles the solver avoids: shown, Avoid on, and not over the root at the origin (ignored)."""
    if not params.avoid:
        return []
    return [k for k in range(params.n_obstacles) if np.linalg.norm(obstacle_centres[k]) > params.radii_m[k]]


def touched_obstacles(
    params: ArmParams, joints: NDArray[np.float64], obstacle_centres: NDArray[np.float64]
) -> list[int]:
    """Numbers (from 1) of the avoided obstacles the chain ``joints`` (n + 1, 3) rests against."""
    return [
        k + 1
        for k in avoided_obstacles(params, obstacle_centres)
        if segment_clearance(joints, obstacle_centres[k]) <= params.radii_m[k] * (1 + 1e-3) + 1e-4
    ]


def joints_at_limit(params: ArmParams, joints: NDArray[np.float64]) -> NDArray[np.intp]:
    """Indices of the joints of ``joints`` (n + 1, 3) bent to within 0.5° of the cone limit (none without limits)."""
    if not params.limits:
        return np.zeros(0, dtype=np.intp)
    angles = fabrik.joint_angles(to_kernel(joints, params.three_d), _root_direction(params.three_d))
    return np.flatnonzero(angles >= math.radians(params.half_angle_deg) - math.radians(0.5))


def why_restarted(params: ArmParams, report: SolveReport, obstacle_centres: NDArray[np.float64]) -> str:
    """In words, why the returned pose was solved from another start ("" when it was solved from the last pose).

    Names only what held the last pose's solve and is on: the joints at their limit, the obstacles it rests against,
    the iteration cap; where none of them shows in that pose, the constraints that apply (joint limits on, obstacles
    shown and avoided)."""
    first = report.last_pose_solution
    if report.start == "last pose" or first is None:
        return ""
    causes: list[str] = []
    if len(joints_at_limit(params, first.joints)):
        causes.append("the joint limits")
    touching = touched_obstacles(params, first.joints, obstacle_centres)
    if touching:
        causes.append(_obstacles(touching))
    if first.status == "max_iterations":
        causes.append(f"the cap of {iterations_words(params.max_iterations)}")
    if not causes:
        avoided = [k + 1 for k in avoided_obstacles(params, obstacle_centres)]
        if params.limits:
            causes.append("the joint limits")
        if avoided:
            causes.append(_obstacles(avoided))
    held = f"{_listed(causes)} held the arm" if causes else "the solve stopped"
    return (
        f"From the last pose {held} farther from the target, so this pose was solved again from a {report.start} "
        f"(other starts are tried when the solve falls short)."
    )


def why_short(
    params: ArmParams, report: SolveReport, target: NDArray[np.float64], obstacle_centres: NDArray[np.float64]
) -> str:
    """In words, why the returned pose's end is not on the target ("" when it is, within the tolerance): the reach,
    the obstacle the chain rests against or the target is in, the joints held at their limit, the iteration cap."""
    r = report.result
    if r.status == "reached":
        return ""
    joints = r.joints
    reach = params.n_links * params.link_length_m
    distance = float(np.linalg.norm(target - joints[0]))
    reasons: list[str] = []
    if distance > reach:
        reasons.append(f"the target is {distance:.2f} m from the base, beyond the chain's reach of {reach:.2f} m")
    avoided = avoided_obstacles(params, obstacle_centres)
    inside = [k + 1 for k in avoided if np.linalg.norm(target - obstacle_centres[k]) < params.radii_m[k]]
    if inside:
        reasons.append(f"the target is inside {_obstacles(inside)}")
    touching = touched_obstacles(params, joints, obstacle_centres)
    if touching and not inside:
        verb, it = ("is", "it") if len(touching) == 1 else ("are", "them")
        reasons.append(f"{_obstacles(touching)} {verb} in the way (the chain rests against {it})")
    if params.limits:
        held = joints_at_limit(params, joints)
        angles = fabrik.joint_angles(to_kernel(joints, params.three_d), _root_direction(params.three_d))
        share = angles / max(math.radians(params.half_angle_deg), 1e-12)
        free = np.delete(share, held)
        if len(held):
            names = ["the base" if j == 0 else f"joint {j + 1}" for j in held]
            verb = "is" if len(held) == 1 else "are"
            words = f"{_listed(names)} {verb} at the {params.half_angle_deg:g}° joint limit"
            if r.status == "limited" and len(free):
                # Not proof that the limits hold the end off: "limited" is a fixed point of the method, and with
                # joints to spare a closer pose can exist (a 20° chain settled 240 mm short of one 64 mm short).
                words += (
                    f" (the other joints bend up to {min(float(free.max()), 1.0):.0%} of it); the solver settled "
                    "here, and a closer pose may exist"
                )
            elif r.status == "limited" and params.half_angle_deg > 0.0:
                # Every joint at its limit proves no more: a 20° chain settled 187 mm short of one 129 mm short,
                # whose base bends 13° of its 20°. (At 0° the straight chain is the only pose.)
                words += "; the solver settled here, and a closer pose may exist"
            reasons.append(words)
        elif r.status == "limited":
            reasons.append(
                f"under the {params.half_angle_deg:g}° joint limits the solver settled here (its joints bend up to "
                f"{min(float(share.max()), 1.0):.0%} of the limit), and a closer pose may exist"
            )
    if r.status == "max_iterations":
        # More iterations help only where nothing else named holds the end off the target (a 0° cone, the reach).
        capped = f"it stopped at its cap of {iterations_words(r.iterations)}"
        reasons.append(
            capped
            if reasons
            else f"it was still closing in after {iterations_words(r.iterations)} (raise Max iterations)"
        )
    if r.status == "infeasible":
        reasons.append("no pose it saw kept every limit and cleared every obstacle")
    if not reasons and r.status == "limited" and avoided:
        it = "it" if len(avoided) == 1 else "them"
        reasons.append(
            f"the iterations stalled beside {_obstacles([k + 1 for k in avoided])}, clear of {it}, and a closer pose "
            "may exist"
        )
    if not reasons:
        reasons.append("the iterations stalled there")
    text = "; ".join(reasons)
    return f"Short by **{r.error * 1000.0:.1f} mm**: {text[0].upper()}{text[1:]}."


# --------------------------------------------------------------------------------------------- geometry
GIZMO_SCALE_M = 0.3
"""Length of the target's and obstacles' gizmo arrows (m): the person must see them to grab them."""
BASE_HALF_M = 0.08
"""Half the width of the base plate the chain stands on (m)."""
FRAME_ROOM = 0.04
"""Share of the free view's width and height kept empty on each side of what is framed: room for the arrowheads,
the joints' and links' thickness and the shading at the edges."""
PLANE_DEPTH, SPACE_DEPTH, SKELETON_DEPTH = 0.5, 0.5, 0.8
"""The nearest framed point stays at least this many times the framed box's largest side in front of the camera
(the chain in the plane, in 3D, a skeleton reaching toward the camera): closer, the wide lens makes what is near (an
obstacle, a target gizmo, a fingertip curled toward the camera) look several times larger than what is far (the base,
the knuckles)."""
FRAME_SLACK = 0.15
"""A framed view is kept until what it must show leaves the framed box grown by this fraction of its size."""


def box_points() -> NDArray[np.float64]:
    """(8, 3) corners of the base plate the chain stands on (m)."""
    return np.array(
        [[x, y, z] for x in (-BASE_HALF_M, BASE_HALF_M) for y in (-BASE_HALF_M, BASE_HALF_M) for z in (-0.06, 0.0)]
    )


def framed_points(
    params: ArmParams, pose: NDArray[np.float64], target: NDArray[np.float64], obstacle_centres: NDArray[np.float64]
) -> NDArray[np.float64]:
    """(N, 3) world points (m) the camera must show: what matters now, not the chain's whole reach.

    The chain's joints and base, the target, each shown obstacle out to its radius, and the gizmo arrows of the
    target and obstacles (along the axes they move on: x and z in the plane, all three in 3D).

    Args:
        params: the scene's parameters (count, radii, mode).
        pose: (n_links + 1, 3) joint positions (m).
        target: (3,) target position (m).
        obstacle_centres: (MAX_OBSTACLES, 3) obstacle centres (m); the first ``params.n_obstacles`` are shown.
    """
    axes = np.eye(3) if params.three_d else np.eye(3)[[0, 2]]
    base = box_points()  # the plate is a box in the plane too: its near face must fit
    shown = obstacle_centres[: params.n_obstacles]
    radii = np.asarray(params.radii_m[: params.n_obstacles], dtype=np.float64)
    rims = (shown[:, None, :] + radii[:, None, None] * np.vstack([axes, -axes])[None]).reshape(-1, 3)
    if params.three_d:  # a sphere seen from the side and above: its bounding cube
        rims = np.vstack([rims, *(padded(shown[k : k + 1], float(radii[k])) for k in range(len(shown)))])
    handles = np.vstack([target[None, :], shown])
    tips = (handles[:, None, :] + GIZMO_SCALE_M * axes[None]).reshape(-1, 3)
    return np.vstack([pose, padded(pose, JOINT_RADIUS_M), base, target[None, :], rims, tips])


def padded(points: NDArray[np.float64], radius: float) -> NDArray[np.float64]:
    """(8·N, 3) the corners of the cube of half-side ``radius`` (m) around each of ``points`` (N, 3): what a sphere
    of that radius about each point needs framed, from any side."""
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=np.float64)
    return (points[:, None, :] + radius * corners[None]).reshape(-1, 3)


def _unit_cylinder() -> trimesh.Trimesh:
    """Radius 1 and length 1 along +z from the origin: scaled per instance to a link."""
    mesh = trimesh.creation.cylinder(radius=1.0, height=1.0, sections=14)
    mesh.apply_translation((0.0, 0.0, 0.5))
    return mesh


DISC_STEP_M = 0.002
"""Obstacle k's disc stands k times this nearer the camera (−y) than the plane, its thickness fixed (scaled in x and
z only): overlapping discs had their faces in one plane, which the depth test split into torn patches."""


def _disc_scale(radius_m: float) -> tuple[float, float, float]:
    return (radius_m, 1.0, radius_m)


def _disc() -> trimesh.Trimesh:
    """Radius 1, 0.04 m thick, facing ±y: a circle obstacle in the x–z plane."""
    mesh = trimesh.creation.cylinder(radius=1.0, height=0.04, sections=48)
    mesh.apply_transform(trimesh.transformations.rotation_matrix(math.pi / 2, (1.0, 0.0, 0.0)))
    return mesh


# --------------------------------------------------------------------------------------------- scene
class ArmScene(Scene[ArmParams]):
    key = "arm"
    title = "Arm: FABRIK inverse kinematics"
    opening_view = View((0.3, -2.9, 1.0), (0.3, 0.0, 0.75))
    about = """
**What it shows.** A chain of 2–12 rigid links whose root is fixed. Drag the red target's gizmo (or click in the
plane) and the chain's end follows it. The readout gives the iterations this frame took, the final error, the
status and the time per solve, and, when the end is short of the target, why (the reach, the obstacle in the way,
the joints held at their limit); the plot shows, after each iteration, the error of the pose the solver would return
then: the best one it has seen that keeps every limit and clears every obstacle (log scale). Joints turn from green
to red as they approach their limit. The translucent blue ghost is the analytic two-bone solution (with two links
the same problem; with more, two bones of the same total reach).

**FABRIK** (Aristidou & Lasenby 2011): the forward pass puts the end on the target and pulls each joint toward
the next, λ = dᵢ/|pᵢ − pᵢ₊₁|, pᵢ ← (1 − λ)·pᵢ₊₁ + λ·pᵢ; the backward pass re-anchors the root and does the same
outwards. Repeat until |pₙ − target| < tolerance. No angles, no matrices.

**Limits.** Each segment stays within a cone of the chosen half-angle around the previous one (the first around
the vertical), clamped inside each pass. **Obstacles** (circles in the plane, spheres in 3D): a segment that would
cut one is turned about its anchor by the least angle until it just clears it. The solver returns the best pose
it saw that keeps every limit and clears every obstacle; when that falls short, the scene also solves from a
few gently bent arcs that keep the limits, and keeps whichever pose comes closest. **Status**: "reached" (within the
tolerance); "unreachable" (the target lies outside the reach annulus max(0, 2·max L − ΣL) ≤ |target − root| ≤ ΣL; the
chain stretches straight toward it at once); "blocked" (within reach, but the chain rests against an obstacle short of
it, or the target is inside one); "limited" (within reach, but the iterates stalled at a fixed point under the joint
limits, or beside an obstacle they do not touch, short of it); "max_iterations" (still converging at the cap);
"infeasible" (no pose seen kept every limit and cleared every obstacle).

**Compared with.** CCD (turn each joint, end to root, to aim the end at the target) and damped-least-squares
Jacobian IK, Δθ = Jᵀ(JJᵀ + λ²I)⁻¹e. The paper's Table 1 (10 joints): FABRIK 15.5 iterations, CCD 26.3, DLS 999.

**Skeletons** (the Preset menu): a planar robot arm of hinges with an industrial arm's ranges, a hand (five
fingers of three hinges on a welded palm) and a humanoid upper body of ball joints, each with a draggable target per
end effector, solved by multi-end-effector FABRIK (Aristidou & Lasenby 2011: each branch proposes a place for its
sub-base, the sub-base goes to their centroid, then the backward pass from the root). Each chain has its own colour;
joints turn red near their limits; the dark bars are the hinge axes. The table gives each effector's error and status.

**Assumptions.** Rigid links, ball joints (hinges in the plane), symmetric cone limits, no dynamics: each frame
is a static pose.
"""

    def __init__(self, server: viser.ViserServer) -> None:
        super().__init__(server)
        self.params = ArmParams()
        self.pose = rest_pose(self.params.n_links, self.params.link_length_m)
        self.report: SolveReport | None = None
        self.solves = 0
        """Solves run so far (tests wait on it)."""
        self.gizmo_events = 0
        """Gizmo updates handled so far, accepted or refused (tests wait on it)."""
        self._build_gui()
        self._build_world()
        self._click = server.scene.on_click()(self._on_scene_click)
        self.skeletons = SkeletonView(self, self.controls.folders["Skeleton"])
        """The robot-arm, hand and upper-body presets, shown in place of the chain when chosen."""
        self.solve_and_draw()
        self._framed_box: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None
        """(lo, hi) world box (m) of what the cameras were last framed to show."""
        self.framing = ClientFraming(self._view_for, opening=self.opening_view.position)
        self.watch_cameras(self.framing.on_camera)

    def close(self) -> None:
        self.server.scene.remove_click_callback(self._click)
        super().close()

    # ----------------------------------------------------------------------------------------- GUI
    def _build_gui(self) -> None:
        gui, p = self.server.gui, self.params
        with self.gui_root:
            skeleton = build_controls(gui, p, names=("preset",))
            skeleton.folders["Skeleton"].order = -1  # above About: the panel opens with the preset menu on top
            self.frame_folder = gui.add_folder("This frame")
            with self.frame_folder:
                self.readout = gui.add_markdown("")
                self.ghost_readout = gui.add_markdown("")
                self.plot = FittedChart(
                    gui,
                    data=(np.zeros(1), np.ones(1)),
                    series=(
                        viser.uplot.Series(label="Iteration"),
                        viser.uplot.Series(label="Best pose's error (mm)", stroke="rgb(230,50,50)", width=2),
                    ),
                    scales=number_scales("y", log=("y",)),
                    legend=viser.uplot.Legend(show=True),
                    title="Error after each iteration (log scale)",
                    aspect=1.6,
                )
            chain = [name for name in declared(ArmParams) if name != "preset"]
            self.controls = skeleton | build_controls(gui, p, names=chain)
            with self.controls.folders["Chain"]:  # after the chain's controls
                self.reset_pose = gui.add_button("Straighten the chain")
        for handle in self.controls:  # a wrapper each, so a burst on one control coalesces
            handle.on_update(self.callback(self._on_input))
        self.reset_pose.on_click(self.callback(self._on_reset_pose))

    # ----------------------------------------------------------------------------------------- world
    def _build_world(self) -> None:
        scene, root = self.server.scene, self.root.name
        base = trimesh.creation.box(extents=(0.16, 0.16, 0.06))
        base.apply_translation((0.0, 0.0, -0.03))
        self.base_node = scene.add_mesh_simple(f"{root}/base", base.vertices, base.faces, color=(90, 95, 105))

        def grid(name: str, plane: Literal["xz", "xy"], visible: bool) -> viser.LineSegmentsHandle:
            """A 4 m square grid of 0.25 m cells, darker every 1 m, as thin lines: viser's own grid shades every pixel
            of its plane, which took a software-WebGL view from 45 to 8 frames/s (docs/performance.md)."""
            ticks = np.linspace(-2.0, 2.0, 17)
            ends = np.stack([np.stack([ticks, np.full(17, -2.0)], 1), np.stack([ticks, np.full(17, 2.0)], 1)], 1)
            uv = np.concatenate([ends, ends[:, :, ::-1]])  # (34, 2, 2): lines along v, then along u
            points = np.zeros((len(uv), 2, 3), np.float32)
            points[..., 0] = uv[..., 0]
            points[..., 2 if plane == "xz" else 1] = uv[..., 1]
            section = np.isclose(np.tile(ticks, 2) % 1.0, 0.0)
            colours = np.where(section[:, None, None], 150, 205).repeat(2, 1).repeat(3, 2).astype(np.uint8)
            return scene.add_line_segments(
                f"{root}/{name}", points, colours, thickness=1.0, thickness_units="screen", visible=visible
            )

        self.grid = grid("plane", "xz", visible=True)
        self.floor = grid("floor", "xy", visible=self.params.three_d)
        cylinder, sphere = _unit_cylinder(), trimesh.creation.icosphere(subdivisions=2, radius=1.0)
        self.link_nodes = add_instances(scene, f"{root}/links", cylinder, MAX_LINKS, (70, 110, 200))
        self.joint_nodes = add_instances(
            scene, f"{root}/joints", sphere, MAX_LINKS + 1, np.tile(np.array(REST_COLOUR, np.uint8), (MAX_LINKS + 1, 1))
        )
        self.ghost_links = add_instances(
            scene, f"{root}/ghost_links", cylinder, 2, GHOST_COLOUR, opacity=0.35, cast_shadow=False
        )
        self.ghost_elbow = scene.add_icosphere(
            f"{root}/ghost_elbow", radius=JOINT_RADIUS_M * 0.9, color=GHOST_COLOUR, opacity=0.45
        )
        box = (-WORLD_LIMIT_M, WORLD_LIMIT_M)
        limits = (box, box, box)
        self.target_gizmo = scene.add_transform_controls(
            f"{root}/target",
            scale=0.3,
            active_axes=(True, False, True),
            disable_rotations=True,
            depth_test=False,
            translation_limits=limits,
            position=self.target,
        )
        scene.add_icosphere(f"{root}/target/marker", radius=0.035, color=TARGET_COLOUR)
        # One wrapper per gizmo, made once, so a burst of drag messages coalesces (Scene.callback).
        self._apply_target_cb = self.callback(self._apply_target)
        self._reframe_cb = self.callback(self._reframe_if_outgrown)
        self._apply_obstacle_cbs = [
            self.callback(functools.partial(self._apply_obstacle, k)) for k in range(MAX_OBSTACLES)
        ]
        self.target_gizmo.on_update(self._on_target_drag)
        self.obstacle_gizmos = []
        self.obstacle_discs = []
        self.obstacle_spheres = []
        disc = _disc()
        for k in range(MAX_OBSTACLES):
            gizmo = scene.add_transform_controls(
                f"{root}/obstacle_{k}",
                scale=0.3,
                active_axes=(True, False, True),
                disable_rotations=True,
                depth_test=False,  # drawn over its own disc or sphere, so it can be seen and grabbed
                translation_limits=limits,
                position=self.obstacle_centres[k],
            )
            self.obstacle_discs.append(
                scene.add_mesh_simple(
                    f"{root}/obstacle_{k}/disc",
                    disc.vertices,
                    disc.faces,
                    color=OBSTACLE_COLOUR,
                    opacity=0.8,
                    scale=_disc_scale(self.params.radii_m[k]),
                    position=(0.0, -DISC_STEP_M * k, 0.0),
                )
            )
            self.obstacle_spheres.append(
                scene.add_icosphere(
                    f"{root}/obstacle_{k}/sphere",
                    radius=1.0,
                    color=OBSTACLE_COLOUR,
                    opacity=0.8,
                    scale=self.params.radii_m[k],
                    visible=False,
                )
            )
            gizmo.on_update(functools.partial(self._on_obstacle_drag, k))
            self.obstacle_gizmos.append(gizmo)

    # ----------------------------------------------------------------------------------------- callbacks
    def _on_target_drag(self, event: object) -> None:
        self._apply_target_cb(None)
        if getattr(event, "phase", None) == "end":  # not mid-drag: the view must not move under the mouse
            self._reframe_cb(None)

    def _apply_target(self) -> None:
        self.gizmo_events += self.messages_in_call
        point = moved_gizmo(self.target_gizmo, self.target, not self.params.three_d, upright=True)
        if point is None or (np.array_equal(point, self.target) and self.report is not None):
            return  # unusable, or a burst of updates: an earlier one already solved for this position
        self.target = point
        self.solve_and_draw()

    def _on_obstacle_drag(self, k: int, event: object) -> None:
        self._apply_obstacle_cbs[k](None)
        if getattr(event, "phase", None) == "end":
            self._reframe_cb(None)

    def _apply_obstacle(self, k: int) -> None:
        self.gizmo_events += self.messages_in_call
        point = moved_gizmo(self.obstacle_gizmos[k], self.obstacle_centres[k], not self.params.three_d)
        if point is None or np.array_equal(point, self.obstacle_centres[k]):
            return
        centres = list(self.params.obstacle_centres)
        centres[k] = _point(point)
        self.params = dataclasses.replace(self.params, obstacle_centres=tuple(centres))
        self.solve_and_draw()

    def _on_scene_click(self, event: viser.SceneClickEvent) -> None:
        self.callback(functools.partial(self._apply_click, event.ray_origin, event.ray_direction))(None)

    def _apply_click(self, origin: object, direction: object) -> None:
        """Place the target where the click's ray meets the chain's plane (y = 0, or the target's y in 3D)."""
        try:
            o = np.asarray(origin, dtype=np.float64)
            d = np.asarray(direction, dtype=np.float64)
        except (TypeError, ValueError):
            return
        if o.shape != (3,) or d.shape != (3,) or not (np.all(np.isfinite(o)) and np.all(np.isfinite(d))):
            return
        if abs(d[1]) < 1e-9:
            return  # a ray parallel to the plane never meets it
        plane_y = self.target[1] if self.params.three_d else 0.0
        t = (plane_y - o[1]) / d[1]
        if t <= 0.0:
            return
        point = clean_target(o + t * d, planar=not self.params.three_d)
        if point is None:
            return
        self.target = point
        self.target_gizmo.position = point
        self.solve_and_draw()
        self._reframe_if_outgrown()

    CHAIN_FOLDERS = ("Chain", "Joint limits", "Obstacles", "Solver")
    """The folders of controls that act on the scene's own chain (hidden while a skeleton preset is shown)."""

    def show_chain_panel(self, visible: bool) -> None:
        """Show or hide the chain's own readouts ("This frame": its status, ghost and error chart) and controls
        (:data:`CHAIN_FOLDERS`): a skeleton preset shows its own readout in the Skeleton folder instead."""
        with self.server.atomic():
            self.frame_folder.visible = visible
            for label in self.CHAIN_FOLDERS:
                self.controls.folders[label].visible = visible

    def _on_reset_pose(self) -> None:
        self.pose = rest_pose(self.params.n_links, self.params.link_length_m)
        self.solve_and_draw()

    def _on_input(self) -> None:
        last = self.params
        self.params = self.read_params()
        p = self.params
        if p.preset != last.preset:
            self.skeletons.show(p.preset)
            return
        if (p.n_links, p.link_length_m) != (last.n_links, last.link_length_m):
            self.pose = rest_pose(p.n_links, p.link_length_m)
        if p.three_d != last.three_d:
            self._set_mode(p.three_d)
        self.solve_and_draw()
        if (p.three_d, p.n_links, p.link_length_m) != (last.three_d, last.n_links, last.link_length_m):
            self.framing.reframe()
        else:
            self._reframe_if_outgrown()

    def _view_for(self, lens: Lens) -> View:
        """Frame the chain, its base, the target, the obstacles and their gizmos (:func:`framed_points`)."""
        p = self.params
        points = self._points_to_frame()
        lo, hi = points.min(axis=0), points.max(axis=0)
        self._framed_box = (lo, hi)
        sk = self.skeletons.skeleton
        planar = not p.three_d if sk is None else True  # a skeleton is seen from the front, as it opens
        deep = p.three_d if sk is None else not sk.planar  # whether what is framed reaches toward the camera
        extent = float(np.max(hi - lo))
        x0, x1, y0, y1 = lens.usable_ndc()
        room_x, room_y = FRAME_ROOM * (x1 - x0), FRAME_ROOM * (y1 - y0)
        return frame_points(
            points,
            PLANE_VIEW if planar else SPACE_VIEW,
            fov_rad=lens.fov_rad,
            aspect=lens.aspect,
            ndc=(x0 + room_x, x1 - room_x, y0 + room_y, y1 - room_y),
            min_depth=(PLANE_DEPTH if not deep else SPACE_DEPTH if sk is None else SKELETON_DEPTH) * extent,
        )

    def _points_to_frame(self) -> NDArray[np.float64]:
        """(N, 3) world points (m) the camera frames: the chain's (:func:`framed_points`), or, while a skeleton
        preset is shown instead, its joints, its targets and their gizmo arrows."""
        view = self.skeletons
        if not view.active:
            points = framed_points(self.params, self.pose, self.target, self.obstacle_centres)
            ghost = self.report.ghost if self.report is not None else np.zeros((0, 3))
            return np.vstack([points, padded(ghost, JOINT_RADIUS_M)])
        arrows = (view.targets[:, None, :] + view.gizmo_scale * np.eye(3)[None, :, :]).reshape(-1, 3)
        return np.vstack([padded(view.pose, SKELETON_JOINT_M), padded(view.targets, SKELETON_JOINT_M), arrows])

    def _reframe_if_outgrown(self) -> None:
        """Frame again when the chain, target or obstacles left the framed box (grown by :data:`FRAME_SLACK`)."""
        box = self._framed_box
        if box is None:
            return
        lo, hi = box
        slack = FRAME_SLACK * float(np.max(hi - lo))
        points = self._points_to_frame()
        if np.any(points < lo - slack) or np.any(points > hi + slack):
            self.framing.reframe()

    def _set_mode(self, three_d: bool) -> None:
        """Planar ↔ 3D: gizmo axes, obstacle shapes, the plane grid; leaving 3D flattens everything onto y = 0."""
        axes = (True, True, True) if three_d else (True, False, True)
        with self.server.atomic():
            self.grid.visible = not three_d
            self.floor.visible = three_d
            self.target_gizmo.active_axes = axes
            for k in range(MAX_OBSTACLES):
                self.obstacle_gizmos[k].active_axes = axes
            if not three_d:
                flat = tuple((x, 0.0, z) for x, _, z in self.params.obstacle_centres)
                self.params = dataclasses.replace(self.params, obstacle_centres=flat)
                self.target = self.target * (1.0, 0.0, 1.0)
                self.pose = rest_pose(self.params.n_links, self.params.link_length_m)
                self.target_gizmo.position = self.target
                for k in range(MAX_OBSTACLES):
                    self.obstacle_gizmos[k].position = self.obstacle_centres[k]

    def read_params(self) -> ArmParams:
        """The current GUI values, cleaned: anything non-finite, out of range or unknown keeps the last good value."""
        return self.read_controls(self.controls)

    @property
    def target(self) -> NDArray[np.float64]:
        """Where the end effector is sent (world, m): ``params.target`` as a new (3,) array."""
        return np.array(self.params.target)

    @target.setter
    def target(self, point: NDArray[np.float64]) -> None:
        self.params = dataclasses.replace(self.params, target=_point(point))

    @property
    def obstacle_centres(self) -> NDArray[np.float64]:
        """Each obstacle's centre (world, m): ``params.obstacle_centres`` as a new (MAX_OBSTACLES, 3) array."""
        return np.array(self.params.obstacle_centres)

    # ----------------------------------------------------------------------------------------- solve + draw
    def solve_and_draw(self) -> None:
        """Solve from the last pose toward the target and push the frame to every browser in one update."""
        report = solve_arm(self.params, self.pose, self.target, self.obstacle_centres)
        self.pose = report.result.joints
        self.report = report
        self.solves += 1
        self._draw(report)
        self.skeletons.after_chain_draw()

    def _draw(self, report: SolveReport) -> None:
        p, joints = self.params, report.result.joints
        n = p.n_links
        wxyz, lengths = segment_pose(joints[:-1], joints[1:])
        link_wxyz = np.tile([1.0, 0.0, 0.0, 0.0], (MAX_LINKS, 1))
        link_wxyz[:n] = wxyz
        link_pos = np.zeros((MAX_LINKS, 3))
        link_pos[:n] = joints[:-1]
        link_scale = np.zeros((MAX_LINKS, 3))
        link_scale[:n] = np.stack([np.full(n, LINK_RADIUS_M), np.full(n, LINK_RADIUS_M), lengths], axis=1)
        joint_pos = np.zeros((MAX_LINKS + 1, 3))
        joint_pos[: n + 1] = joints
        joint_scale = np.zeros((MAX_LINKS + 1, 3))
        joint_scale[: n + 1] = JOINT_RADIUS_M
        joint_colour = np.tile(np.array(REST_COLOUR, np.uint8), (MAX_LINKS + 1, 1))
        joint_colour[: n + 1] = limit_colours(joints, p)
        ghost_wxyz, ghost_lengths = segment_pose(report.ghost[:-1], report.ghost[1:])
        ghost_scale = np.stack([np.full(2, LINK_RADIUS_M * 1.4)] * 2 + [ghost_lengths], axis=1)

        with self.server.atomic():
            self.link_nodes.batched_wxyzs = link_wxyz.astype(np.float32)
            self.link_nodes.batched_positions = park_hidden(link_pos, link_scale)
            self.link_nodes.batched_scales = link_scale.astype(np.float32)
            self.joint_nodes.batched_positions = park_hidden(joint_pos, joint_scale)
            self.joint_nodes.batched_scales = joint_scale.astype(np.float32)
            self.joint_nodes.batched_colors = joint_colour
            self.ghost_links.batched_wxyzs = ghost_wxyz.astype(np.float32)
            self.ghost_links.batched_positions = report.ghost[:-1].astype(np.float32)
            self.ghost_links.batched_scales = ghost_scale.astype(np.float32)
            self.ghost_elbow.position = report.ghost[1]
            for k in range(MAX_OBSTACLES):
                shown = k < p.n_obstacles
                self.obstacle_gizmos[k].visible = shown
                self.obstacle_discs[k].visible = shown and not p.three_d
                self.obstacle_spheres[k].visible = shown and p.three_d
                self.obstacle_discs[k].scale = _disc_scale(p.radii_m[k])
                self.obstacle_spheres[k].scale = p.radii_m[k]
            self.readout.content = self._readout_markdown(report)
            self.ghost_readout.content = self._ghost_markdown(report)
            self.plot.data = chart_points(report)
        self.server.flush()

    def _readout_markdown(self, report: SolveReport) -> str:
        r, p = report.result, self.params
        text = (
            f"**{p.solver}**: {iterations_words(r.iterations)}, "
            f"error **{r.error * 1000.0:.3f} mm**, status **{r.status}**  \n"
            f"Solve time **{report.micros:,.0f} µs**{plain_python_note()}"
        )
        restarted = why_restarted(p, report, self.obstacle_centres)
        if restarted:
            text += f"  \n{restarted}"
        short = why_short(p, report, self.target, self.obstacle_centres)
        if short:
            text += f"  \n{short}"
        covering = [
            k + 1
            for k in range(p.n_obstacles)
            if np.linalg.norm(self.obstacle_centres[k] - self.pose[0]) <= p.radii_m[k]
        ]
        if p.avoid and covering:
            verb = "covers" if len(covering) == 1 else "cover"
            text += f"  \n{_obstacles(covering).capitalize()} {verb} the root and cannot be avoided: ignored."
        return text

    def _ghost_markdown(self, report: SolveReport) -> str:
        r = report.result
        which = f"{self.params.solver}'s elbow" if self.params.n_links == 2 else "the chain's middle joint"
        return (
            f"Two-bone ghost (analytic, one step): end error **{report.ghost_error_m * 1000.0:.3f} mm** "
            f"vs {r.error * 1000.0:.3f} mm; its elbow is **{report.ghost_gap_m * 1000.0:.1f} mm** from {which}."
        )
