"""Inverse kinematics of a chain of rigid links: FABRIK, and the solvers it is compared with.

A chain is ``n + 1`` joint positions ``p_0 … p_n`` in 2D or 3D (``d`` = 2 or 3, metres); ``p_0`` is the fixed root,
``p_n`` the end effector. Link lengths ``L_i = |p_{i+1} − p_i|`` come from the joints given and never change.
Batches lead: a batch of chains is ``(B, n + 1, d)`` and its targets ``(B, d)``.

Model and method:

* FABRIK (Aristidou & Lasenby 2011, "FABRIK: a fast, iterative solver for the Inverse Kinematics problem",
  Graphical Models 73(5)): a forward pass sets ``p_n`` on the target and re-places every joint on the line to the
  joint before it at the link's length; a backward pass sets ``p_0`` back on the root and does the same outwards.
* Reach: a target at distance ``r`` from the root is reachable only if ``max(0, 2·max L − ΣL) ≤ r ≤ ΣL`` (the
  reach annulus, to within 1e-12 of the chain's scale ``max(ΣL, r)``). Outside it FABRIK returns the closest pose at once
  (stretched straight toward the target, or folded back onto the inner boundary), as the paper does for
  unreachable targets, unless joint limits or obstacles forbid that pose.
* Full and inner reach: a target within ``tolerance`` of full reach (``r ≥ ΣL − tolerance``) is first tried with
  the straight pose toward it (error ``ΣL − r``), one within ``tolerance`` of a non-zero inner radius with the
  folded pose (error ``r − inner``); near these singular poses FABRIK itself converges only linearly.
* Joint limits: each segment stays within a cone of half-angle ``φ`` around the previous segment's direction (the
  first segment around ``root_direction``). The forward pass clamps each segment against the one placed just before
  it, the backward pass against its predecessor, so every iterate satisfies every limit (as Aristidou & Lasenby 2011
  apply constraints inside the passes, here with a symmetric cone; in 2D the cone is the angle range ``[−φ, φ]``).
* Joint types per segment (``constraints=[...]``): :class:`Cone` (the cone above, per joint) or :class:`Hinge`
  (caliko's hinge, Lansley 2016: the segment turns only about an axis, fixed in the world or turning with the
  previous segment, within an angle range from a reference direction). The forward pass holds consecutive segments
  by the cone between them, or turns a segment about the next joint's hinge axis until that joint's angle is in
  range, and keeps each hinge's segment in its plane; the backward pass imposes every limit exactly, so every
  iterate keeps every hinge. CCD and DLS keep them through the same backward pass.
* Skeletons (:func:`solve_tree`): Aristidou & Lasenby 2011, §4.2, several end effectors: forward reaching from each
  effector to its sub-base, the sub-base at the centroid of its branches' proposals, then on toward the root, and
  backward reaching from the root along every branch.
* Obstacles: circles (2D) or spheres (3D). Whenever a pass would place a segment through one, the segment is turned
  about its anchor, by the least angle, until it only touches it (tangent, or its far end on the surface).
  Obstacles that contain the root cannot be avoided and are ignored.
* Best pose: a pose is admissible when it keeps every limit and cuts no obstacle. The solvers return the best
  admissible pose seen (the start, the closest-pose or straight candidates, or an iterate), so the returned error is
  never larger than an admissible start's nor than any admissible iterate's (caliko keeps the best pose too). Only
  if no admissible pose was ever seen is the last iterate returned, with status ``"infeasible"``.
* Extrapolation (our addition, not in the paper): near cone limits FABRIK converges linearly and slowly (the
  error shrinks by 0.8–0.95 per iteration). Where the error ratio ``r`` of the last iteration is in [0.5, 1), the
  joints are moved on along their last step by ``r / (1 − r)`` steps (the rest of the geometric series,
  Aitken-style, at most 8) before the next passes, which then re-impose lengths, limits and obstacles; a chain whose
  error grew after an extrapolation is not extrapolated again. Also ours: an extrapolated FABRIK chain under
  limits that stalls short of a reachable target restarts once from the straight pose toward the target, clamped
  into the cones (a stall is a fixed point of one start, not proof that the limits keep the target away; on
  targets an admissible pose reaches, "limited" fell from 22 % to 2 %). Only FABRIK is extrapolated, and only
  FABRIK tries the closest-pose, straight and folded candidates: ``ccd`` and ``jacobian_dls`` run as published.
* Stopping: at the tolerance (``error ≤ tolerance``), at ``max_iterations``, or, where limits or obstacles apply or
  the target is out of reach, at a fixed point: when the error changes by less than 0.1 % of the tolerance in an
  iteration (caliko's "minimum change" rule), or the best admissible error has improved by less than 10 % of the
  tolerance in 10 iterations (the iterates creep toward, or circle, a fixed point). Without constraints the iterations converge and run to the cap.
* Degenerate input never makes NaN: a zero-length link or coincident joints keep the last defined direction, a
  straight chain whose target lies on its own axis is first bent into a gentle arc (a straight chain otherwise never
  bends, a known FABRIK complaint), and a target on the root picks the root direction.
* Scale: every test in the core is relative to the chain's scale ``max(ΣL, |target − root|)`` (no absolute length),
  and the wrappers solve in units of a power of 2 near the problem's extent (exact), so a problem multiplied by
  ``2^k`` is solved as the original times ``2^k``, bit for bit, and squared norms never overflow or underflow.
  Domain: coordinates, lengths and radii of magnitude ≤ 1e300 m.
* ``two_bone`` is the analytic law-of-cosines solution for two links; ``ccd`` (cyclic coordinate descent, Wang &
  Chen 1991) and ``jacobian_dls`` (damped least squares, Wampler 1986; Buss 2004) are the methods the FABRIK paper
  compared with (its Table 1: 10 joints, FABRIK 15.5 iterations, CCD 26.3, DLS 999). They take the same arguments,
  honour the same limits and obstacles by projecting every iterate with the constrained backward pass, and return
  the same result.
* Speed: each solver is one implementation compiled by numba (``@njit(cache=True)``) on the scalars of one chain;
  :func:`solve` calls it for one chain, :func:`solve_batch` for every chain, in parallel over the batch
  (``prange``; ``numba.set_num_threads`` sets the threads). 2D chains run as 3D ones in the plane ``z = 0``. The
  first call compiles (seconds) or loads the machine code from numba's cache (``__pycache__`` beside this file, or
  numba's user-wide cache directory where that is read-only); :func:`warm_up` does it ahead of time.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import threading
from collections.abc import Mapping, Sequence
from typing import Literal

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

Status = Literal["reached", "unreachable", "max_iterations", "blocked", "limited", "infeasible"]
"""Why a solve stopped:

* ``"reached"``: the end effector is within the tolerance of the target (error ≤ tolerance, exactly: no slack);
* ``"unreachable"``: the target lies outside the reach annulus, farther than the tolerance from the closest pose
  (the closest admissible pose seen is returned);
* ``"blocked"``: a reachable target not reached, with the returned pose resting against an obstacle (within 0.1 %
  of its radius) or the target inside one;
* ``"limited"``: a reachable target not reached, the iterates stalled under joint limits (or obstacles, not
  touched) at a fixed point of the method: the error stopped changing, or the best error stopped improving (see
  Stopping). It does not prove the limits keep the chain from the target; another start may reach it;
* ``"max_iterations"``: the iteration cap came first (a reachable target, still converging);
* ``"infeasible"``: no pose the solver saw (neither the start nor any iterate) keeps every limit and clears every
  obstacle; the last iterate is returned, and it is not admissible.
"""
STATUSES: tuple[Status, ...] = (
    "reached", "unreachable", "max_iterations", "blocked", "limited", "infeasible"
)  # fmt: skip
_REACHED, _UNREACHABLE, _MAX_ITERATIONS, _BLOCKED, _LIMITED, _INFEASIBLE = range(6)

Solver = Literal["fabrik", "ccd", "jacobian_dls"]
"""The iterative methods; they share arguments, constraints and result."""
_FABRIK, _CCD, _DLS = range(3)
_SOLVER_IDS: dict[str, int] = {"fabrik": _FABRIK, "ccd": _CCD, "jacobian_dls": _DLS}

Obstacle = tuple[ArrayLike, float]
"""``(centre (d,) m, radius m)``: a circle in 2D, a sphere in 3D."""

_TINY = 1e-12
"""Relative length below which a vector has no direction, and the rounding slack of the reach tests (times the
chain's scale, ``max(ΣL, |target − root|)``; never added to the tolerance)."""
_LARGEST = 1e300
"""Largest magnitude accepted for a coordinate, length or radius (m): sums and differences stay finite."""
_MAX_ITERATIONS_CAP = 100_000
"""Largest ``max_iterations`` accepted (each chain keeps an error history of that length)."""
_CLEARANCE = 1e-6
"""Segments are turned to clear an obstacle by this fraction of its radius, so rounding never leaves them inside."""
_TOUCH = 1e-3
"""A pose within this fraction of an obstacle's radius of it rests against it ("blocked")."""
_STALL = 1e-3
"""A chain whose end-effector error changed by less than this fraction of the tolerance in an iteration is at a
fixed point (caliko's "minimum change" rule)."""
_PATIENCE = 10
"""A constrained chain whose best admissible error has improved by less than :data:`_PROGRESS` of the tolerance in
this many iterations has stopped making progress (it creeps toward, or circles, a fixed point the limits or
obstacles impose)."""
_PROGRESS = 0.1
"""See :data:`_PATIENCE`: 1 % of the tolerance per iteration, a pace at which the cap would come first anyway."""
_EXTRAPOLATION_CAP = 8.0
"""Most last-steps a FABRIK iterate is moved on by: enough for an error ratio of 0.89."""
_EXTRAPOLATION_MIN_RATIO = 0.5
"""Error ratio per iteration below which FABRIK iterates are left as they are."""
_DLS_DAMPING = 0.1
"""Damping of the DLS step, times the mean link length (Buss 2004 suggests λ of the order of the link size)."""
_CONE_SLACK = 1e-12
"""Rounding allowed when checking ``cos(angle) ≥ cos φ``."""


@dataclasses.dataclass(frozen=True)
class Solution:
    """One chain's solve."""

    joints: NDArray[np.float64]
    """(n + 1, d) joint positions of the returned pose (m); ``joints[0]`` is the root."""
    iterations: int
    """Iterations run (0 when the starting pose already met the tolerance and every constraint)."""
    error: float
    """Final distance from the end effector to the target (m)."""
    status: Status
    """Why it stopped; see :data:`Status`."""
    error_history: NDArray[np.float64]
    """(iterations + 1,) end-effector distance before the first iteration and after each one (m): the iterates',
    which may differ from the returned (best admissible) pose's ``error``."""


@dataclasses.dataclass(frozen=True)
class BatchSolution:
    """A batch of solves, one entry per chain."""

    joints: NDArray[np.float64]
    """(B, n + 1, d) joint positions (m)."""
    iterations: NDArray[np.int64]
    """(B,) iterations each chain ran."""
    error: NDArray[np.float64]
    """(B,) final end-effector distance to the target (m)."""
    status: NDArray[np.str_]
    """(B,) status strings, each one of :data:`STATUSES`."""
    error_history: NDArray[np.float64]
    """(B, max_iterations + 1) error before the first and after each iteration; NaN after a chain stopped."""

    def __getitem__(self, index: int) -> Solution:
        """The ``index``-th chain as a :class:`Solution`."""
        count = int(self.iterations[index])
        return Solution(
            joints=self.joints[index],
            iterations=count,
            error=float(self.error[index]),
            status=_status_literal(str(self.status[index])),
            error_history=self.error_history[index, : count + 1],
        )


# ================================================================================================ joint types
@dataclasses.dataclass(frozen=True)
class Cone:
    """A ball joint: the segment stays within ``half_angle_rad`` of the previous segment's direction (the first
    segment of the root direction), as ``cone_half_angle_rad`` does for every joint at once."""

    half_angle_rad: float
    """Half-angle of the cone (rad), in [0, π]; π leaves the joint free."""

    def __post_init__(self) -> None:
        phi = _finite_number("half_angle_rad", self.half_angle_rad)
        if not 0.0 <= phi <= math.pi:
            raise ValueError(f"half_angle_rad must be in [0, π], got {self.half_angle_rad!r}")
        object.__setattr__(self, "half_angle_rad", phi)


HingeFrame = Literal["global", "local"]
"""Where a hinge's axes are given: fixed in the world, or in the frame of the previous segment."""


@dataclasses.dataclass(frozen=True)
class Hinge:
    """A hinge joint: the segment turns only about ``axis``, within an angle range (caliko's hinge, 2016).

    The segment's direction is kept in the plane through its inner joint perpendicular to the axis; its signed angle
    about the axis (right-handed), measured from the reference direction, stays in ``[min_angle_rad,
    max_angle_rad]``. The reference direction is ``reference_axis`` (its part perpendicular to the axis), or, when
    None, the previous segment's direction (the root direction for the first segment) projected onto that plane: the
    angle is then the joint angle a robot's encoder reads, 0 for a straight joint.

    ``frame="global"``: ``axis`` and ``reference_axis`` are fixed in the world (caliko's GLOBAL_HINGE).
    ``frame="local"``: they are given for a chain at rest along the root direction and turn with the previous
    segment, by the shortest rotation taking the root direction onto it (caliko's LOCAL_HINGE builds the previous
    bone's frame from a fixed up vector instead; the two agree about the bone's axis and differ in twist, which
    positions alone do not fix). For the first segment both frames are the world.

    Where ours differs from caliko: a range need not contain 0 (caliko's clockwise/anticlockwise limits do); a
    direction outside the range goes to the nearer end around the circle (caliko clamps to the end on its side);
    the forward pass only keeps each segment in its hinge plane and the backward pass imposes the range, as caliko
    does, so every returned pose keeps every hinge.
    """

    axis: ArrayLike
    """(3,) rotation axis (any length > 0; unit once built). In 2D it must be ±z, the plane's normal."""
    min_angle_rad: float = -math.pi
    """Lower end of the range (rad), in [−π, π]."""
    max_angle_rad: float = math.pi
    """Upper end of the range (rad), in [min_angle_rad, π]."""
    reference_axis: ArrayLike | None = None
    """(3,) direction angle 0 is measured from (its part perpendicular to ``axis``); None: the previous segment."""
    frame: HingeFrame = "global"
    """"global" or "local"; see the class docstring."""

    def __post_init__(self) -> None:
        axis = _finite_array("axis", self.axis)
        if axis.shape != (3,) or not float(np.linalg.norm(axis)) > _TINY:
            raise ValueError(f"axis must be a non-zero (3,) vector, got {self.axis!r}")
        axis = axis / float(np.linalg.norm(axis))
        low = _finite_number("min_angle_rad", self.min_angle_rad)
        high = _finite_number("max_angle_rad", self.max_angle_rad)
        if not -math.pi <= low <= math.pi:
            raise ValueError(f"min_angle_rad must be in [−π, π], got {self.min_angle_rad!r}")
        if not low <= high <= math.pi:
            raise ValueError(
                f"max_angle_rad must be in [min_angle_rad, π] = [{low}, π], got {self.max_angle_rad!r}"
            )
        reference = None
        if self.reference_axis is not None:
            raw = _finite_array("reference_axis", self.reference_axis)
            if raw.shape != (3,):
                raise ValueError(
                    f"reference_axis must be a (3,) vector, got {self.reference_axis!r}"
                )
            off = raw - float(raw @ axis) * axis
            if not float(np.linalg.norm(off)) > 1e-9 * max(float(np.linalg.norm(raw)), _TINY):
                raise ValueError(
                    f"reference_axis must not be parallel to axis, got {self.reference_axis!r}"
                )
            reference = tuple(float(v) for v in off / float(np.linalg.norm(off)))
        match self.frame:
            case "global" | "local":
                pass
            case _:
                raise ValueError(f"frame must be 'global' or 'local', got {self.frame!r}")
        object.__setattr__(self, "axis", tuple(float(v) for v in axis))
        object.__setattr__(self, "min_angle_rad", low)
        object.__setattr__(self, "max_angle_rad", high)
        object.__setattr__(self, "reference_axis", reference)


Constraint = Cone | Hinge | None
"""One segment's joint: a cone, a hinge, or None (free)."""

_TABLE_WIDTH = 13
"""Columns of a limit table row: kind, cos φ, sin φ, axis (3), reference (3), min, max, local, has reference."""
_KIND_FREE, _KIND_CONE, _KIND_HINGE = 0.0, 1.0, 2.0
_FREE_TABLE = np.zeros((1, _TABLE_WIDTH))
_HINGE_SLACK = 1e-9
"""Rounding allowed when checking a hinge: out of its plane by this much (of a unit direction), or past its range
by this many radians."""


def _limit_table(
    constraints: Sequence[Constraint], count: int, dim: int, name: str, *, segment_offset: int
) -> NDArray[np.float64]:
    """(count, 13) rows the compiled core reads, one per segment, from checked constraints.

    ``segment_offset`` rows are left free at the start (the root of a tree has no segment)."""
    if isinstance(constraints, (str, bytes)) or not isinstance(constraints, Sequence):
        raise ValueError(f"{name} must be a sequence of Cone, Hinge or None, got {constraints!r}")
    if len(constraints) != count:
        raise ValueError(
            f"{name} must have one entry per segment ({count}), got {len(constraints)}"
        )
    table = np.zeros((count, _TABLE_WIDTH))
    for i, item in enumerate(constraints):
        if i < segment_offset and item is not None:
            raise ValueError(f"{name}[{i}] must be None (the root has no segment), got {item!r}")
        match item:
            case None:
                pass
            case Cone(half_angle_rad=phi):
                if phi < math.pi:
                    table[i, :3] = _KIND_CONE, math.cos(phi), math.sin(phi)
            case Hinge():
                axis = np.asarray(item.axis)
                if dim == 2 and abs(axis[2]) < 1.0 - 1e-12:
                    raise ValueError(
                        f"{name}[{i}].axis must be ±z for a 2D chain, got {item.axis!r}"
                    )
                table[i, 0] = _KIND_HINGE
                table[i, 3:6] = axis
                if item.reference_axis is not None:
                    table[i, 6:9] = item.reference_axis
                    table[i, 12] = 1.0
                table[i, 9], table[i, 10] = item.min_angle_rad, item.max_angle_rad
                table[i, 11] = 1.0 if item.frame == "local" else 0.0
            case _:
                raise ValueError(f"{name}[{i}] must be a Cone, a Hinge or None, got {item!r}")
    return table


def limit_usage(
    joints: ArrayLike,
    constraints: Sequence[Constraint],
    root_direction: ArrayLike | None = None,
) -> NDArray[np.float64]:
    """How near each segment is to its joint's limit: 0 free or centred, 1 at the limit.

    A cone's share is ``angle / φ``; a hinge's is ``1 − (distance to the nearer end) / (half the range)`` (1 for a
    zero range). Free segments give 0.

    Args:
        joints: (n + 1, d) joint positions (m).
        constraints: n entries as in :func:`solve`.
        root_direction: (d,) as in :func:`solve`.

    Returns:
        (n,) shares in [0, 1].

    Raises:
        ValueError: as :func:`solve`.
    """
    chain = _check_joints("joints", joints, batched=False)
    n, dim = chain.shape[0] - 1, chain.shape[1]
    table = _limit_table(constraints, n, dim, "constraints", segment_offset=0)
    rest = np.zeros(3)
    rest[:dim] = _root_direction(root_direction, dim)
    p = np.zeros((n + 1, 3))
    p[:, :dim] = chain
    scale = max(float(np.linalg.norm(np.diff(chain, axis=0), axis=1).sum()), 1.0)
    return _usage(p, table, rest, _TINY * scale)


# ================================================================================================ public API
def solve(
    joints: ArrayLike,
    target: ArrayLike,
    *,
    tolerance: float = 1e-3,
    max_iterations: int = 50,
    cone_half_angle_rad: float | None = None,
    obstacles: Sequence[Obstacle] = (),
    root_direction: ArrayLike | None = None,
    constraints: Sequence[Constraint] | None = None,
    extrapolate: bool = True,
) -> Solution:
    """Solve one chain with FABRIK.

    Args:
        joints: (n + 1, d) starting joint positions (m), d = 2 or 3, n ≥ 1; ``joints[0]`` is the fixed root.
        target: (d,) target of the end effector (m).
        tolerance: stop when the end effector is this close to the target (m), ≥ 0.
        max_iterations: iteration cap, ≥ 1.
        cone_half_angle_rad: joint limit, in [0, π]: the angle between consecutive segments (and between the
            first segment and ``root_direction``) never exceeds it. None: no limits.
        obstacles: circles (2D) or spheres (3D) as ``(centre (d,), radius)`` no segment may pass through.
        root_direction: (d,) rest direction of the root, the axis of the first segment's cone. Default: +y in 2D
            (the plane's up), +z in 3D.
        extrapolate: move slowly converging iterates on along their last step, and restart a stall under limits
            once (see the module docstring); False gives plain FABRIK as the paper writes it.
        constraints: one :class:`Cone`, :class:`Hinge` or None (free) per segment, segment i being joints i to
            i + 1; replaces ``cone_half_angle_rad`` (give one or the other). None: as ``cone_half_angle_rad``.

    Returns:
        The :class:`Solution`: the best admissible pose seen.

    Raises:
        ValueError: naming the argument, for non-finite values or magnitudes above 1e300, bool or complex arrays,
            wrong shapes, n < 1, a negative tolerance, a half-angle outside [0, π], a non-positive radius,
            obstacles that are not (centre, radius) pairs, max_iterations outside [1, 100 000], or constraints of
            the wrong count or kind (a hinge axis off ±z in 2D).
    """
    return _solve_single("fabrik", joints, target, tolerance, max_iterations,
                         cone_half_angle_rad, obstacles, root_direction, extrapolate,
                         constraints)  # fmt: skip


def solve_batch(
    joints: ArrayLike,
    targets: ArrayLike,
    *,
    tolerance: float = 1e-3,
    max_iterations: int = 50,
    cone_half_angle_rad: float | None = None,
    obstacles: Sequence[Obstacle] = (),
    root_direction: ArrayLike | None = None,
    constraints: Sequence[Constraint] | None = None,
    solver: Solver = "fabrik",
    extrapolate: bool = True,
) -> BatchSolution:
    """Solve B chains at once, in parallel over the batch; each chain stops on its own.

    Args:
        joints: (B, n + 1, d) starting joint positions (m), every chain with the same n and d.
        targets: (B, d) targets (m).
        tolerance: as in :func:`solve`.
        max_iterations: as in :func:`solve`.
        cone_half_angle_rad: as in :func:`solve`, the same for every chain.
        obstacles: as in :func:`solve`, shared by every chain.
        root_direction: as in :func:`solve`, shared by every chain.
        solver: "fabrik", "ccd" or "jacobian_dls".
        extrapolate: as in :func:`solve` (FABRIK only).
        constraints: as in :func:`solve`, the same for every chain.

    Returns:
        The :class:`BatchSolution`; ``result[i]`` is chain i's :class:`Solution`, the same as solving it alone.

    Raises:
        ValueError: as :func:`solve`, and for a batch size mismatch or an unknown solver.
    """
    chains = _check_joints("joints", joints, batched=True)
    batch, count, dim = chains.shape
    points = _finite_array("targets", targets)
    if points.shape != (batch, dim):
        raise ValueError(
            f"targets must have shape ({batch}, {dim}) to match joints, got {points.shape}"
        )
    if not isinstance(solver, str) or solver not in _SOLVER_IDS:
        raise ValueError(f"solver must be one of 'fabrik', 'ccd', 'jacobian_dls', got {solver!r}")
    setup = _Setup.build(dim, tolerance, max_iterations, cone_half_angle_rad, obstacles,
                         root_direction, _SOLVER_IDS[solver], extrapolate)  # fmt: skip
    setup = setup.constrained(constraints, count - 1, dim, cone_half_angle_rad)
    p = np.zeros((batch, count, 3))
    p[:, :, :dim] = chains
    goal = np.zeros((batch, 3))
    goal[:, :dim] = points
    out_p = np.empty_like(p)
    history = np.empty((batch, setup.max_iterations + 1))  # the core fills it, NaN past the end
    iterations = np.empty(batch, dtype=np.int64)
    status = np.empty(batch, dtype=np.int64)
    error = np.empty(batch)
    scale, params, centres, radii = _to_unit_scale(p, goal, setup)
    args = (p, goal, params, setup.flags, setup.root_direction, centres, radii,
            out_p, history, iterations, status, error, setup.table)  # fmt: skip
    if batch == 1:
        _solve_rows(0, 1, *args)
    else:
        # numba's workqueue threading layer (where OpenMP and TBB are missing) is not thread-safe
        with _PARALLEL_LOCK:
            _solve_parallel(min(batch, _CHUNKS), *args)
    if scale != 1.0:
        out_p *= scale
        history *= scale
        error *= scale
    return BatchSolution(
        joints=out_p[:, :, :dim].copy() if dim == 2 else out_p,
        iterations=iterations,
        error=error,
        status=np.array(STATUSES)[status],
        error_history=history,
    )


def ccd(
    joints: ArrayLike,
    target: ArrayLike,
    *,
    tolerance: float = 1e-3,
    max_iterations: int = 50,
    cone_half_angle_rad: float | None = None,
    obstacles: Sequence[Obstacle] = (),
    root_direction: ArrayLike | None = None,
    constraints: Sequence[Constraint] | None = None,
) -> Solution:
    """Cyclic coordinate descent: one iteration turns each joint, end to root, to point the end at the target.

    Arguments, result and errors are those of :func:`solve`.
    """
    return _solve_single("ccd", joints, target, tolerance, max_iterations,
                         cone_half_angle_rad, obstacles, root_direction, False,
                         constraints)  # fmt: skip


def jacobian_dls(
    joints: ArrayLike,
    target: ArrayLike,
    *,
    tolerance: float = 1e-3,
    max_iterations: int = 50,
    cone_half_angle_rad: float | None = None,
    obstacles: Sequence[Obstacle] = (),
    root_direction: ArrayLike | None = None,
    constraints: Sequence[Constraint] | None = None,
) -> Solution:
    """Damped-least-squares Jacobian IK: ``Δθ = Jᵀ(JJᵀ + λ²I)⁻¹e`` with ball joints (3D) or hinges (2D).

    Arguments, result and errors are those of :func:`solve`.
    """
    return _solve_single("jacobian_dls", joints, target, tolerance, max_iterations,
                         cone_half_angle_rad, obstacles, root_direction, False,
                         constraints)  # fmt: skip


def warm_up() -> None:
    """Compile every solver core (or load it from numba's cache) on tiny inputs, so the first real solve waits for
    nothing. Safe to call from a background thread; numba's compiler lock makes a concurrent first solve wait for
    it instead of compiling twice."""
    chain = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.3, 0.0, 1.9]])
    obstacles = [(np.array([1.0, 0.0, 1.0]), 0.2)]
    for solver in ("fabrik", "ccd", "jacobian_dls"):
        for batch in (1, 2):  # the serial driver (one chain) and the parallel one
            solve_batch(
                np.repeat(chain[None], batch, axis=0),
                np.repeat([[0.8, 0.0, 1.2]], batch, axis=0),
                cone_half_angle_rad=1.0,
                obstacles=obstacles,
                max_iterations=3,
                solver=solver,
            )
    hinge = Hinge((0.0, 1.0, 0.0), -1.0, 1.0)
    solve(chain, [0.8, 0.0, 1.2], constraints=[hinge, Cone(1.0)], max_iterations=3)
    solve_tree([-1, 0, 1, 1], np.vstack([chain, [[-0.3, 0.0, 1.9]]]), {2: [0.8, 0.0, 1.2], 3: [-0.8, 0.0, 1.2]},
               constraints=[None, hinge, Cone(1.0), hinge], obstacles=obstacles, max_iterations=3)  # fmt: skip


def two_bone(
    root: ArrayLike,
    upper_length: float,
    lower_length: float,
    target: ArrayLike,
    bend_direction: ArrayLike,
) -> NDArray[np.float64]:
    """The analytic two-link solution by the law of cosines.

    The elbow sits at angle ``α = acos((L1² + r² − L2²) / (2·L1·r))`` from the root–target line, on the side of
    ``bend_direction``. A target out of reach (``r > L1 + L2`` or ``r < |L1 − L2|``) gives the closest pose: the
    chain straight, or folded, along the root–target line.

    Args:
        root: (d,) root position (m), d = 2 or 3.
        upper_length: root-to-elbow length (m), ≥ 0.
        lower_length: elbow-to-end length (m), ≥ 0.
        target: (d,) target (m).
        bend_direction: (d,) the side the elbow bends toward (only its part perpendicular to the root–target line
            counts; if it has none, a fixed perpendicular is used).

    Returns:
        (3, d) root, elbow and end positions (m).

    Raises:
        ValueError: naming the argument, for non-finite values, wrong shapes or negative lengths.
    """
    p_root = _finite_array("root", root)
    if p_root.ndim != 1 or p_root.shape[0] not in (2, 3):
        raise ValueError(f"root must have shape (2,) or (3,), got {p_root.shape}")
    dim = p_root.shape[0]
    p_target = _check_vector("target", target, dim)
    bend = _check_vector("bend_direction", bend_direction, dim)
    upper = _check_length("upper_length", upper_length)
    lower = _check_length("lower_length", lower_length)

    offset = p_target - p_root
    # In units of a power of 2 near the problem's extent (exact), so squares neither overflow nor underflow.
    extent = max(float(np.abs(offset).max()), upper, lower)
    unit = math.ldexp(1.0, math.frexp(extent)[1]) if extent > 0.0 else 1.0
    offset, upper, lower = offset / unit, upper / unit, lower / unit
    largest = float(np.abs(bend).max())
    bend = bend / largest if largest > 0.0 else bend
    distance = float(np.linalg.norm(offset))
    scale = max(upper + lower, distance, 1.0)
    axis = offset / distance if distance > _TINY * scale else _fallback_axis(bend, dim)
    side = bend - float(bend @ axis) * axis
    side_norm = float(np.linalg.norm(side))
    side = side / side_norm if side_norm > _TINY else _perpendicular_numpy(axis)

    reach = min(max(distance, abs(upper - lower)), upper + lower)
    if upper <= _TINY * scale or reach <= _TINY * scale:
        cos_alpha = 1.0 if reach >= upper else -1.0
    else:
        cos_alpha = (upper**2 + reach**2 - lower**2) / (2.0 * upper * reach)
    cos_alpha = min(1.0, max(-1.0, cos_alpha))
    sin_alpha = math.sqrt(max(0.0, 1.0 - cos_alpha**2))
    elbow = upper * (cos_alpha * axis + sin_alpha * side)
    end_offset = reach * axis - elbow
    end_norm = float(np.linalg.norm(end_offset))
    direction = end_offset / end_norm if end_norm > _TINY * scale else axis
    return np.stack([p_root, p_root + unit * elbow, p_root + unit * (elbow + lower * direction)])


def link_lengths(joints: ArrayLike) -> NDArray[np.float64]:
    """Link lengths (m): (n,) for (n + 1, d) joints, (B, n) for (B, n + 1, d)."""
    segments = np.diff(np.asarray(joints, dtype=np.float64), axis=-2)
    # each segment first to max-abs 1, so its squared norm neither overflows (1e300) nor underflows (1e-160)
    largest = np.abs(segments).max(axis=-1, keepdims=True)
    largest = np.where(largest > 0.0, largest, 1.0)
    return np.linalg.norm(segments / largest, axis=-1) * largest[..., 0]


def joint_angles(joints: ArrayLike, root_direction: ArrayLike | None = None) -> NDArray[np.float64]:
    """Angle of each segment to the one before it (the first to ``root_direction``), radians in [0, π].

    Zero-length segments have no direction: they get angle 0 and the next segment is measured against the last
    segment that has one.

    Args:
        joints: (n + 1, d) joint positions (m).
        root_direction: (d,) as in :func:`solve`.

    Returns:
        (n,) angles (rad).
    """
    chain = _check_joints("joints", joints, batched=False)
    dim = chain.shape[1]
    previous = _root_direction(root_direction, dim)
    segments = np.diff(chain, axis=0)
    largest = float(np.abs(segments).max())
    # directions only: first to max-abs 1, so norms neither overflow nor underflow
    if largest > 0.0:
        segments = segments / largest
    scale = float(np.add.reduce(np.linalg.norm(segments, axis=1)))
    angles = np.zeros(segments.shape[0])
    for i, segment in enumerate(segments):
        length = float(np.linalg.norm(segment))
        if length <= _TINY * scale:
            continue
        direction = segment / length
        angles[i] = math.acos(min(1.0, max(-1.0, float(direction @ previous))))
        previous = direction
    return angles


def reach_limits(lengths: ArrayLike) -> tuple[float, float]:
    """``(inner, outer)`` radii (m) of the annulus the end effector can reach: ``max(0, 2·max L − ΣL)`` and ``ΣL``.

    Args:
        lengths: (n,) link lengths (m), n ≥ 1, each ≥ 0.

    Raises:
        ValueError: naming ``lengths``, for a wrong shape, an empty array, or negative or non-finite lengths.
    """
    links = _finite_array("lengths", lengths)
    if links.ndim != 1 or links.shape[0] < 1 or not bool((links >= 0.0).all()):
        raise ValueError(f"lengths must be a non-empty (n,) array of lengths ≥ 0, got {lengths!r}")
    total = float(links.sum())
    return max(0.0, 2.0 * float(links.max()) - total), total


# ================================================================================================ checks
def _finite_array(name: str, value: ArrayLike) -> NDArray[np.float64]:
    """Real numbers (not bool, not complex) of magnitude ≤ 1e300 as float64, else ValueError naming them."""
    try:
        array = np.asarray(value)
        # bool and complex would convert silently (True → 1, the imaginary part dropped); objects (Python ints
        # beyond float64) convert below or overflow
        if array.dtype.kind not in "fiuO":
            raise TypeError(array.dtype)
        array = np.asarray(array, dtype=np.float64)
    except (TypeError, ValueError, OverflowError) as error:
        raise ValueError(f"{name} must be an array of real numbers, got {value!r}") from error
    flat = array.reshape(-1)
    # A compiled scan costs a fraction of numpy's isfinite + all on the few numbers of one chain.
    if flat.flags.writeable:
        finite = _all_within(flat, _LARGEST)
    else:
        finite = bool((np.abs(flat) <= _LARGEST).all())
    if not finite:
        raise ValueError(f"{name} must be finite, of magnitude ≤ {_LARGEST:g}, got {value!r}")
    return array


@numba.njit(cache=True, error_model="numpy")
def _all_within(values: NDArray[np.float64], bound: float) -> bool:
    for value in values:
        if not abs(value) <= bound:  # NaN fails too
            return False
    return True


def _finite_number(name: str, value: object) -> float:
    """A finite real number (Python or numpy scalar; not bool) as a float, else ValueError naming it."""
    if isinstance(value, (float, int, np.floating, np.integer)) and not isinstance(value, bool):
        number = float(value)
        if math.isfinite(number):
            return number
    raise ValueError(f"{name} must be a finite number, got {value!r}")


def _check_joints(name: str, value: ArrayLike, *, batched: bool) -> NDArray[np.float64]:
    array = _finite_array(name, value)
    want = 3 if batched else 2
    shape = "(B, n + 1, d)" if batched else "(n + 1, d)"
    if array.ndim != want or array.shape[-1] not in (2, 3):
        raise ValueError(f"{name} must have shape {shape} with d = 2 or 3, got {array.shape}")
    if array.shape[-2] < 2:
        raise ValueError(f"{name} must hold at least two joints (n ≥ 1 link), got {array.shape}")
    return array


def _check_vector(name: str, value: ArrayLike, dim: int) -> NDArray[np.float64]:
    array = _finite_array(name, value)
    if array.shape != (dim,):
        raise ValueError(f"{name} must have shape ({dim},), got {array.shape}")
    return array


def _check_length(name: str, value: float) -> float:
    number = _finite_array(name, value)
    if number.shape != () or float(number) < 0.0:
        raise ValueError(f"{name} must be a finite number ≥ 0, got {value!r}")
    return float(number)


def _root_direction(value: ArrayLike | None, dim: int) -> NDArray[np.float64]:
    if value is None:
        axis = np.zeros(dim)
        axis[-1] = 1.0
        return axis
    axis = _check_vector("root_direction", value, dim)
    largest = float(np.abs(axis).max())
    if largest == 0.0:
        raise ValueError(f"root_direction must be non-zero, got {value!r}")
    # first to max-abs 1, so neither a huge nor a tiny vector over- or underflows its norm
    axis = axis / largest
    return axis / float(np.linalg.norm(axis))


def _status_literal(text: str) -> Status:
    for status in STATUSES:
        if status == text:
            return status
    raise ValueError(f"unknown status {text!r}")


def _perpendicular_numpy(axis: NDArray[np.float64]) -> NDArray[np.float64]:
    """A fixed unit vector perpendicular to the unit ``axis`` (d,)."""
    if axis.shape[0] == 2:
        return np.array([-axis[1], axis[0]])
    x, y, z = _perpendicular(float(axis[0]), float(axis[1]), float(axis[2]), 3)
    return np.array([x, y, z])


def _fallback_axis(bend: NDArray[np.float64], dim: int) -> NDArray[np.float64]:
    """Any unit axis perpendicular to ``bend`` (or +last axis), for a target on the root."""
    norm = float(np.linalg.norm(bend))
    if norm <= _TINY:
        axis = np.zeros(dim)
        axis[-1] = 1.0
        return axis
    return _perpendicular_numpy(bend / norm)


@dataclasses.dataclass(frozen=True)
class _Setup:
    """Checked options shared by every chain, packed as the compiled core takes them."""

    max_iterations: int
    params: NDArray[np.float64]
    """(3,) tolerance (m), cos φ, sin φ."""
    flags: NDArray[np.int64]
    """(6,) max_iterations, d, solver id, extrapolate, has limits, has limits that can hold a chain at a fixed
    point (a cone, or a hinge with less than the full turn: free hinges only keep a chain in their planes, where
    it moves as freely as without them, so the fixed-point rule waits for the cap)."""
    root_direction: NDArray[np.float64]
    """(3,) unit rest direction of the root (z = 0 in 2D)."""
    centres: NDArray[np.float64]
    """(K, 3) obstacle centres (m)."""
    radii: NDArray[np.float64]
    """(K,) obstacle radii (m)."""
    table: NDArray[np.float64] = dataclasses.field(default_factory=lambda: _FREE_TABLE)
    """(T, 13) joint limits, one row per segment (T = n) or one row for all (T = 1); see :func:`_limit_table`."""

    def constrained(
        self, constraints: Sequence[Constraint] | None, n: int, dim: int, cone: float | None
    ) -> _Setup:
        """These options with per-segment ``constraints`` (checked) in place of the uniform cone."""
        if constraints is None:
            return self
        if cone is not None:
            raise ValueError(
                "constraints and cone_half_angle_rad are alternatives: give one of them, not both"
            )
        table = _limit_table(constraints, n, dim, "constraints", segment_offset=0)
        has_limits = bool(np.any(table[:, 0] != _KIND_FREE))
        cones = table[table[:, 0] == _KIND_CONE, 1]
        cos_phi = (
            float(cones.max()) if cones.size else -1.0
        )  # the tightest cone bounds the unbending arc
        params = self.params.copy()
        params[1], params[2] = cos_phi, math.sqrt(max(0.0, 1.0 - cos_phi * cos_phi))
        flags = self.flags.copy()
        flags[4] = int(has_limits)
        full_turn = (table[:, 0] == _KIND_HINGE) & (table[:, 10] - table[:, 9] >= 2.0 * math.pi)
        flags[5] = int(bool(np.any((table[:, 0] != _KIND_FREE) & ~full_turn)))
        return dataclasses.replace(self, params=params, flags=flags, table=table)

    @staticmethod
    def build(
        dim: int,
        tolerance: float,
        max_iterations: int,
        cone_half_angle_rad: float | None,
        obstacles: Sequence[Obstacle],
        root_direction: ArrayLike | None,
        solver: int,
        extrapolate: bool,
    ) -> _Setup:
        try:
            options = _options(
                dim, tolerance, max_iterations, cone_half_angle_rad, solver, extrapolate
            )
        except (
            TypeError
        ):  # an unhashable argument: check it without the cache (and raise ValueError)
            options = _options.__wrapped__(
                dim, tolerance, max_iterations, cone_half_angle_rad, solver, extrapolate
            )
        # an array or an iterator: its items are the obstacles
        if not isinstance(obstacles, (list, tuple)):
            try:
                obstacles = list(obstacles)
            except TypeError as error:
                raise ValueError(
                    f"obstacles must be a sequence of (centre, radius), got {obstacles!r}"
                ) from error
        if root_direction is None and not obstacles:
            return options
        count = len(obstacles)
        centres, radii = np.zeros((count, 3)), np.empty(count)
        for k, obstacle in enumerate(obstacles):
            try:
                centre, radius = obstacle
            except (TypeError, ValueError) as error:
                raise ValueError(
                    f"obstacles[{k}] must be (centre, radius), got {obstacle!r}"
                ) from error
            centres[k, :dim] = _check_vector(f"obstacles[{k}] centre", centre, dim)
            radii[k] = _finite_number(f"obstacles[{k}] radius", radius)
            if not 0.0 < radii[k] <= _LARGEST:
                raise ValueError(
                    f"obstacles[{k}] radius must be a finite number in (0, {_LARGEST:g}], got {radius!r}"
                )
        rest = options.root_direction
        if root_direction is not None:
            rest = np.zeros(3)
            rest[:dim] = _root_direction(root_direction, dim)
        return dataclasses.replace(options, root_direction=rest, centres=centres, radii=radii)


@functools.lru_cache(maxsize=64, typed=True)
def _options(
    dim: int,
    tolerance: float,
    max_iterations: int,
    cone_half_angle_rad: float | None,
    solver: int,
    extrapolate: bool,
) -> _Setup:
    """The checked scalar options, without obstacles, on the default root direction; cached, since a dragged
    chain asks for the same ones every frame (the compiled core never writes to them)."""
    tol = _finite_number("tolerance", tolerance)
    if tol < 0.0:
        raise ValueError(f"tolerance must be a finite number ≥ 0, got {tolerance!r}")
    if isinstance(max_iterations, bool) or not isinstance(max_iterations, (int, np.integer)):
        raise ValueError(f"max_iterations must be an integer, got {max_iterations!r}")
    if not 1 <= max_iterations <= _MAX_ITERATIONS_CAP:
        raise ValueError(
            f"max_iterations must be in [1, {_MAX_ITERATIONS_CAP}], got {max_iterations}"
        )
    cos_phi, sin_phi, has_limits = -1.0, 0.0, 0
    if cone_half_angle_rad is not None:
        phi = _finite_number("cone_half_angle_rad", cone_half_angle_rad)
        if not 0.0 <= phi <= math.pi:
            raise ValueError(f"cone_half_angle_rad must be in [0, π], got {cone_half_angle_rad!r}")
        if phi < math.pi:
            cos_phi, sin_phi, has_limits = math.cos(phi), math.sin(phi), 1
    rest = np.zeros(3)
    rest[:dim] = _root_direction(None, dim)
    table = np.zeros((1, _TABLE_WIDTH))
    if has_limits:
        table[0, :3] = _KIND_CONE, cos_phi, sin_phi
    return _Setup(
        max_iterations=int(max_iterations),
        table=table,
        params=np.array([tol, cos_phi, sin_phi]),
        flags=np.array(
            [int(max_iterations), dim, solver, int(bool(extrapolate)), has_limits, has_limits],
            dtype=np.int64,
        ),
        root_direction=rest,
        centres=np.zeros((0, 3)),
        radii=np.zeros(0),
    )


_UNSCALED = 2.0**-16, 2.0**16
"""Extents (m) solved as they are; outside, a problem is divided by a power of 2 near its extent first."""


def _to_unit_scale(
    p: NDArray[np.float64], goal: NDArray[np.float64], setup: _Setup
) -> tuple[float, NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Divide the chains ``p`` (B, n + 1, 3) and targets ``goal`` (B, 3), in place, and the tolerance and obstacles,
    by a power of 2 near the batch's extent (the largest coordinate offset from a root); returns that scale and the
    scaled params, centres and radii.

    The core's tests are all relative to the chain's scale, and dividing by a power of 2 is exact, so it gives the
    same bits at any scale; scaling only keeps squared norms (and DLS's 3 × 3 determinant, ~ extent⁶) from
    overflowing or underflowing for huge or tiny chains. Results are multiplied back by the caller.
    """
    root = p[:, :1, :]
    extent = max(float(np.abs(p - root).max()), float(np.abs(goal - root[:, 0]).max()))
    if extent == 0.0 or _UNSCALED[0] <= extent <= _UNSCALED[1]:
        return 1.0, setup.params, setup.centres, setup.radii
    scale = math.ldexp(1.0, math.frexp(extent)[1])  # ≥ extent, exact; division by it is exact
    p /= scale
    goal /= scale
    params = setup.params.copy()
    # the tolerance (inf beyond float range: then every error is within it)
    params[0] = params[0] / scale
    return scale, params, setup.centres / scale, setup.radii / scale


def _solve_single(
    solver: Solver,
    joints: ArrayLike,
    target: ArrayLike,
    tolerance: float,
    max_iterations: int,
    cone_half_angle_rad: float | None,
    obstacles: Sequence[Obstacle],
    root_direction: ArrayLike | None,
    extrapolate: bool,
    constraints: Sequence[Constraint] | None = None,
) -> Solution:
    """One chain: checked here, solved by the same compiled core as every chain of a batch."""
    chain = _check_joints("joints", joints, batched=False)
    count, dim = chain.shape
    point = _check_vector("target", target, dim)
    setup = _Setup.build(dim, tolerance, max_iterations, cone_half_angle_rad, obstacles,
                         root_direction, _SOLVER_IDS[solver], extrapolate)  # fmt: skip
    setup = setup.constrained(constraints, count - 1, dim, cone_half_angle_rad)
    p = np.zeros((1, count, 3))
    p[0, :, :dim] = chain
    goal = np.zeros((1, 3))
    goal[0, :dim] = point
    out_p = np.empty_like(p)
    history = np.empty((1, setup.max_iterations + 1))
    iterations = np.empty(1, dtype=np.int64)
    status = np.empty(1, dtype=np.int64)
    error = np.empty(1)
    scale, params, centres, radii = _to_unit_scale(p, goal, setup)
    _solve_rows(0, 1, p, goal, params, setup.flags, setup.root_direction, centres,
                radii, out_p, history, iterations, status, error, setup.table)  # fmt: skip
    if scale != 1.0:
        out_p *= scale
        history *= scale
        error *= scale
    used = int(iterations[0])
    return Solution(
        joints=out_p[0, :, :dim].copy() if dim == 2 else out_p[0],
        iterations=used,
        error=float(error[0]),
        status=STATUSES[int(status[0])],
        error_history=history[0, : used + 1],
    )


# ================================================================================================ compiled core
# Every solver lives once, below, on the scalars of one chain (3D; a 2D chain has z = 0 and d = 2 where the
# perpendicular and the rotations differ). ``_solve_rows`` runs it over some rows of a batch; ``solve`` calls it for
# one row, ``_solve_parallel`` splits a batch into chunks across threads.
_CHUNKS = 256
"""Most chunks a parallel batch is cut into: enough to balance chains that need 1 and 50 iterations."""
_PARALLEL_LOCK = threading.Lock()


@numba.njit(cache=True, error_model="numpy")
def _unit(
    x: float, y: float, z: float, fx: float, fy: float, fz: float, tiny: float
) -> tuple[float, float, float, float]:
    """``(x, y, z) / |(x, y, z)|`` and the norm; the fallback direction where the norm is ≤ ``tiny``."""
    norm = math.sqrt(x * x + y * y + z * z)
    if norm > tiny:
        inverse = 1.0 / norm
        return x * inverse, y * inverse, z * inverse, norm
    return fx, fy, fz, norm


@numba.njit(cache=True, error_model="numpy")
def _perpendicular(x: float, y: float, z: float, dim: int) -> tuple[float, float, float]:
    """A fixed unit vector perpendicular to the unit vector (x, y, z): in the plane for d = 2."""
    if dim == 2:
        return -y, x, 0.0
    # the cross product with the coordinate axis least aligned with the vector
    ex, ey = (0.0, 1.0) if abs(x) > 0.9 else (1.0, 0.0)
    cx, cy, cz = -z * ey, z * ex, x * ey - y * ex
    norm = math.sqrt(cx * cx + cy * cy + cz * cz)
    return cx / norm, cy / norm, cz / norm


@numba.njit(cache=True, error_model="numpy")
def _clamp_cone(
    vx: float, vy: float, vz: float, ax: float, ay: float, az: float, cos_phi: float,
    sin_phi: float, dim: int,
) -> tuple[float, float, float]:  # fmt: skip
    """The unit direction v turned, by the least angle, into the cone of half-angle φ around the unit ``a``."""
    cos_v = vx * ax + vy * ay + vz * az
    if not cos_v < cos_phi:
        return vx, vy, vz
    sx, sy, sz, side = _unit(vx - cos_v * ax, vy - cos_v * ay, vz - cos_v * az, 0.0, 0.0, 0.0, 1e-9)
    if side <= 1e-9:  # v (anti)parallel to the axis: any side will do
        sx, sy, sz = _perpendicular(ax, ay, az, dim)
    # A nearly (anti)parallel v leaves the side only roughly perpendicular: renormalise so lengths stay exact.
    cx, cy, cz = (
        cos_phi * ax + sin_phi * sx,
        cos_phi * ay + sin_phi * sy,
        cos_phi * az + sin_phi * sz,
    )
    norm = math.sqrt(cx * cx + cy * cy + cz * cz)
    return cx / norm, cy / norm, cz / norm


@numba.njit(cache=True, error_model="numpy")
def _turn_clear(
    ax: float, ay: float, az: float, vx: float, vy: float, vz: float, length: float,
    centre: NDArray[np.float64], radius: float, tiny: float, dim: int,
) -> tuple[float, float, float]:  # fmt: skip
    """The direction nearest v whose segment of ``length`` from anchor ``a`` just clears one obstacle: tangent to
    it if the segment is long enough to reach the tangent point, else with its far end on the surface."""
    clear = radius * (1.0 + _CLEARANCE)
    cx, cy, cz, distance = _unit(
        centre[0] - ax, centre[1] - ay, centre[2] - az, -vx, -vy, -vz, tiny
    )
    if distance <= radius:  # an anchor inside: leave straight away from the centre
        return -cx, -cy, -cz
    if length * length >= distance * distance - clear * clear:
        sin_t = min(max(clear / max(distance, tiny), 0.0), 1.0)
        cos_t = math.sqrt(1.0 - sin_t * sin_t)
    else:
        cos_t = (length * length + distance * distance - clear * clear) / (
            2.0 * max(length, tiny) * max(distance, tiny)
        )
        cos_t = min(max(cos_t, -1.0), 1.0)
        sin_t = math.sqrt(1.0 - cos_t * cos_t)
    along = vx * cx + vy * cy + vz * cz
    sx, sy, sz, side = _unit(vx - along * cx, vy - along * cy, vz - along * cz, 0.0, 0.0, 0.0, 1e-9)
    if side <= 1e-9:  # v through the centre: turn to any side
        sx, sy, sz = _perpendicular(cx, cy, cz, dim)
    tx, ty, tz = cos_t * cx + sin_t * sx, cos_t * cy + sin_t * sy, cos_t * cz + sin_t * sz
    norm = math.sqrt(tx * tx + ty * ty + tz * tz)
    return tx / norm, ty / norm, tz / norm


@numba.njit(cache=True, error_model="numpy")
def _deflect(
    ax: float, ay: float, az: float, vx: float, vy: float, vz: float, length: float,
    centres: NDArray[np.float64], radii: NDArray[np.float64], live: NDArray[np.bool_], tiny: float,
    dim: int,
) -> tuple[float, float, float, bool]:  # fmt: skip
    """Turn the segment ``a + t·v, t ∈ [0, length]`` by the least angle until no live obstacle cuts it; returns
    the new unit direction and whether it was turned."""
    turned = False
    for _ in range(3):  # turning around one obstacle can push into another: a few rounds settle it
        hit = False
        for k in range(radii.shape[0]):
            if not live[k]:
                continue
            rx, ry, rz = centres[k, 0] - ax, centres[k, 1] - ay, centres[k, 2] - az
            rel2 = rx * rx + ry * ry + rz * rz
            reach = length + radii[k]
            if rel2 >= reach * reach:  # too far for the segment to touch: most pairs stop here
                continue
            along = rx * vx + ry * vy + rz * vz
            t = min(max(along, 0.0), length)
            if rel2 - 2.0 * t * along + t * t < radii[k] * radii[k]:
                hit = True
                vx, vy, vz = _turn_clear(ax, ay, az, vx, vy, vz, length, centres[k], radii[k],
                                         tiny, dim)  # fmt: skip
        if not hit:
            return vx, vy, vz, turned
        turned = True
    return vx, vy, vz, turned


@numba.njit(cache=True, error_model="numpy")
def _forward_pass(
    p: NDArray[np.float64], target: NDArray[np.float64], lengths: NDArray[np.float64],
    tiny: float, rest: NDArray[np.float64], limits: tuple[bool, NDArray[np.float64]],
    centres: NDArray[np.float64], radii: NDArray[np.float64], live: NDArray[np.bool_],
    has_zero: bool, dim: int,
) -> None:  # fmt: skip
    """End on the target, each joint back toward its old place at its link's length (the root is left)."""
    has_limits, table = limits
    n = lengths.shape[0]
    p[n, 0], p[n, 1], p[n, 2] = target[0], target[1], target[2]
    qx, qy, qz, _ = _unit(p[0, 0] - p[n, 0], p[0, 1] - p[n, 1], p[0, 2] - p[n, 2],
                          -rest[0], -rest[1], -rest[2], tiny)  # fmt: skip
    x, y, z = p[n, 0], p[n, 1], p[n, 2]  # the anchor, carried in registers from joint to joint
    for i in range(n - 1, 0, -1):
        dx, dy, dz, _ = _unit(p[i, 0] - x, p[i, 1] - y, p[i, 2] - z, qx, qy, qz, tiny)
        if radii.shape[0] > 0:
            dx, dy, dz, _ = _deflect(
                x, y, z, dx, dy, dz, lengths[i], centres, radii, live, tiny, dim
            )
        if has_limits:
            dx, dy, dz = _forward_limits(p, i, n, dx, dy, dz, qx, qy, qz, table, rest, tiny, dim)
        length = lengths[i]
        x, y, z = x + length * dx, y + length * dy, z + length * dz
        p[i, 0], p[i, 1], p[i, 2] = x, y, z
        if not has_zero or length > tiny:
            qx, qy, qz = dx, dy, dz


@numba.njit(cache=True, error_model="numpy")
def _backward_pass(
    p: NDArray[np.float64], lengths: NDArray[np.float64], tiny: float,
    rest: NDArray[np.float64], limits: tuple[bool, NDArray[np.float64]], centres: NDArray[np.float64],
    radii: NDArray[np.float64], live: NDArray[np.bool_], has_zero: bool, dim: int,
) -> None:  # fmt: skip
    """Root back on its place, each joint outward toward its current place; limits and obstacles enforced."""
    has_limits, table = limits
    qx, qy, qz = rest[0], rest[1], rest[2]
    x, y, z = p[0, 0], p[0, 1], p[0, 2]  # the anchor, carried in registers from joint to joint
    for i in range(1, lengths.shape[0] + 1):
        dx, dy, dz, _ = _unit(p[i, 0] - x, p[i, 1] - y, p[i, 2] - z, qx, qy, qz, tiny)
        if has_limits:
            dx, dy, dz = _constrain(dx, dy, dz, qx, qy, qz, table, i - 1, rest, tiny, dim)
        if radii.shape[0] > 0:
            dx, dy, dz, turned = _deflect(x, y, z, dx, dy, dz, lengths[i - 1], centres, radii, live,
                                          tiny, dim)  # fmt: skip
            if turned and has_limits:
                dx, dy, dz = _constrain(dx, dy, dz, qx, qy, qz, table, i - 1, rest, tiny, dim)
        length = lengths[i - 1]
        x, y, z = x + length * dx, y + length * dy, z + length * dz
        p[i, 0], p[i, 1], p[i, 2] = x, y, z
        if not has_zero or length > tiny:
            qx, qy, qz = dx, dy, dz


@numba.njit(cache=True, error_model="numpy")
def _ccd_sweep(
    p: NDArray[np.float64], target: NDArray[np.float64], tiny: float, rest: NDArray[np.float64],
    dim: int,
) -> None:  # fmt: skip
    """One CCD sweep (Wang & Chen 1991): each joint, end to root, turns what lies beyond it about
    ``to_end × to_target`` (Rodrigues' formula) so that the end points at the target."""
    n = p.shape[0] - 1
    for i in range(n - 1, -1, -1):
        ox, oy, oz = p[i, 0], p[i, 1], p[i, 2]
        ex, ey, ez, end_norm = _unit(p[n, 0] - ox, p[n, 1] - oy, p[n, 2] - oz,
                                     rest[0], rest[1], rest[2], tiny)  # fmt: skip
        tx, ty, tz, target_norm = _unit(target[0] - ox, target[1] - oy, target[2] - oz,
                                        ex, ey, ez, tiny)  # fmt: skip
        if not (end_norm > tiny and target_norm > tiny):
            continue
        cos_a = min(max(ex * tx + ey * ty + ez * tz, -1.0), 1.0)
        kx, ky, kz = ey * tz - ez * ty, ez * tx - ex * tz, ex * ty - ey * tx
        sin_a = math.sqrt(kx * kx + ky * ky + kz * kz)
        # (In the plane the axis is ±z; end and target antiparallel turn about z, or in 3D any perpendicular.)
        kx, ky, kz, _ = _unit(kx, ky, kz, 0.0, 0.0, 1.0, 1e-12)
        if sin_a <= 1e-12 and dim == 3:
            kx, ky, kz = _perpendicular(ex, ey, ez, 3)
        for j in range(i + 1, n + 1):
            # Rodrigues: v cos a + (k × v) sin a + k (k·v)(1 − cos a)
            vx, vy, vz = p[j, 0] - ox, p[j, 1] - oy, p[j, 2] - oz
            dot = (kx * vx + ky * vy + kz * vz) * (1.0 - cos_a)
            p[j, 0] = ox + vx * cos_a + (ky * vz - kz * vy) * sin_a + kx * dot
            p[j, 1] = oy + vy * cos_a + (kz * vx - kx * vz) * sin_a + ky * dot
            p[j, 2] = oz + vz * cos_a + (kx * vy - ky * vx) * sin_a + kz * dot


@numba.njit(cache=True, error_model="numpy")
def _dls_step(
    p: NDArray[np.float64], target: NDArray[np.float64], lengths: NDArray[np.float64],
    tiny: float, turns: NDArray[np.float64],
) -> None:  # fmt: skip
    """One damped-least-squares step on joint angles (Wampler 1986; Buss 2004): ``Δθ = Jᵀ(JJᵀ + λ²I)⁻¹e``.

    Ball joints: ``J_i = −[l_i]×`` with ``l_i = p_n − p_i``, so ``JJᵀ = Σ |l_i|²I − l_i l_iᵀ`` and
    ``Δθ_i = l_i × y`` for ``y = (JJᵀ + λ²I)⁻¹e``. In the plane (z = 0) every ``Δθ_i`` is along z and the step is the
    planar one of hinges, ``J_i = perp(l_i)``. The error is clamped to the mean link length and
    ``λ = 0.1 × mean link length`` (Buss 2004). Segment j turns by ``R(Δθ_0) … R(Δθ_j)``, the rotations of the
    joints' rotation vectors (in the plane: by their summed angle). ``turns`` is (n + 1, 3) scratch.
    """
    n = lengths.shape[0]
    endx, endy, endz = p[n, 0], p[n, 1], p[n, 2]
    cap = max(np.sum(lengths) / n, tiny)
    ex, ey, ez = target[0] - endx, target[1] - endy, target[2] - endz
    shrink = min(1.0, cap / max(math.sqrt(ex * ex + ey * ey + ez * ez), tiny))
    ex, ey, ez = ex * shrink, ey * shrink, ez * shrink
    # JJᵀ + λ²I, symmetric: a00 a01 a02 / a11 a12 / a22
    a00 = a11 = a22 = (_DLS_DAMPING * cap) ** 2
    a01 = a02 = a12 = 0.0
    for i in range(n):
        lx, ly, lz = endx - p[i, 0], endy - p[i, 1], endz - p[i, 2]
        l2 = lx * lx + ly * ly + lz * lz
        a00, a11, a22 = a00 + l2 - lx * lx, a11 + l2 - ly * ly, a22 + l2 - lz * lz
        a01, a02, a12 = a01 - lx * ly, a02 - lx * lz, a12 - ly * lz
    # Cramer's rule on the symmetric positive-definite 3 × 3 matrix
    c00, c01, c02 = a11 * a22 - a12 * a12, a02 * a12 - a01 * a22, a01 * a12 - a02 * a11
    c11, c12, c22 = a00 * a22 - a02 * a02, a01 * a02 - a00 * a12, a00 * a11 - a01 * a01
    det = a00 * c00 + a01 * c01 + a02 * c02
    yx = (c00 * ex + c01 * ey + c02 * ez) / det
    yy = (c01 * ex + c11 * ey + c12 * ez) / det
    yz = (c02 * ex + c12 * ey + c22 * ez) / det
    for i in range(n):  # Δθ_i = J_iᵀ y = l_i × y
        lx, ly, lz = endx - p[i, 0], endy - p[i, 1], endz - p[i, 2]
        turns[i, 0], turns[i, 1], turns[i, 2] = (
            ly * yz - lz * yy,
            lz * yx - lx * yz,
            lx * yy - ly * yx,
        )
    # Turn every segment by the joints up to it and re-chain from the root.
    turn, step, product = np.eye(3), np.empty((3, 3)), np.empty((3, 3))
    ox, oy, oz = p[0, 0], p[0, 1], p[0, 2]
    for i in range(n):
        sx, sy, sz = p[i + 1, 0] - ox, p[i + 1, 1] - oy, p[i + 1, 2] - oz
        ox, oy, oz = p[i + 1, 0], p[i + 1, 1], p[i + 1, 2]
        theta = math.sqrt(turns[i, 0] ** 2 + turns[i, 1] ** 2 + turns[i, 2] ** 2)
        if theta > 1e-15:
            kx, ky, kz = turns[i, 0] / theta, turns[i, 1] / theta, turns[i, 2] / theta
            s, c = math.sin(theta), math.cos(theta)
            # Rodrigues: R = cos θ I + sin θ [k]× + (1 − cos θ) k kᵀ
            for r in range(3):
                for q in range(3):
                    step[r, q] = (1.0 - c) * turns[i, r] * turns[i, q] / (theta * theta)
                step[r, r] += c
            step[0, 1], step[0, 2], step[1, 2] = (
                step[0, 1] - s * kz,
                step[0, 2] + s * ky,
                step[1, 2] - s * kx,
            )
            step[1, 0], step[2, 0], step[2, 1] = (
                step[1, 0] + s * kz,
                step[2, 0] - s * ky,
                step[2, 1] + s * kx,
            )
            for r in range(3):
                for q in range(3):
                    product[r, q] = (
                        turn[r, 0] * step[0, q] + turn[r, 1] * step[1, q] + turn[r, 2] * step[2, q]
                    )
            turn[:, :] = product
        p[i + 1, 0] = p[i, 0] + turn[0, 0] * sx + turn[0, 1] * sy + turn[0, 2] * sz
        p[i + 1, 1] = p[i, 1] + turn[1, 0] * sx + turn[1, 1] * sy + turn[1, 2] * sz
        p[i + 1, 2] = p[i, 2] + turn[2, 0] * sx + turn[2, 1] * sy + turn[2, 2] * sz


@numba.njit(cache=True, error_model="numpy")
def _cone_ok(
    p: NDArray[np.float64], tiny: float, rest: NDArray[np.float64], table: NDArray[np.float64]
) -> bool:
    """Whether every segment keeps its joint's cone or hinge (zero-length segments have none and are skipped)."""
    qx, qy, qz = rest[0], rest[1], rest[2]
    for i in range(p.shape[0] - 1):
        dx, dy, dz, norm = _unit(p[i + 1, 0] - p[i, 0], p[i + 1, 1] - p[i, 1],
                                 p[i + 1, 2] - p[i, 2], qx, qy, qz, tiny)  # fmt: skip
        if norm <= tiny:
            continue
        if not _joint_ok(dx, dy, dz, qx, qy, qz, table, i, rest, tiny):
            return False
        qx, qy, qz = dx, dy, dz
    return True


@numba.njit(cache=True, error_model="numpy")
def _colliding(
    p: NDArray[np.float64], centres: NDArray[np.float64], radii: NDArray[np.float64],
    live: NDArray[np.bool_], inflate: float,
) -> bool:  # fmt: skip
    """Whether any segment passes within ``inflate`` × radius of a live obstacle's centre."""
    for i in range(p.shape[0] - 1):
        x, y, z = p[i, 0], p[i, 1], p[i, 2]
        sx, sy, sz = p[i + 1, 0] - x, p[i + 1, 1] - y, p[i + 1, 2] - z
        seg2 = sx * sx + sy * sy + sz * sz
        for k in range(radii.shape[0]):
            if not live[k]:
                continue
            rx, ry, rz = centres[k, 0] - x, centres[k, 1] - y, centres[k, 2] - z
            grown = radii[k] * inflate
            # |c − a| ≥ |s| + r, so no point of the segment is within r: (|s| + r)² ≤ 2(|s|² + r²)
            if rx * rx + ry * ry + rz * rz >= 2.0 * (seg2 + grown * grown):
                continue
            t = min(max((rx * sx + ry * sy + rz * sz) / (seg2 if seg2 > 0.0 else 1.0), 0.0), 1.0)
            gx, gy, gz = rx - t * sx, ry - t * sy, rz - t * sz
            if gx * gx + gy * gy + gz * gz < grown * grown:
                return True
    return False


@numba.njit(cache=True, error_model="numpy")
def _admissible(
    p: NDArray[np.float64], tiny: float, rest: NDArray[np.float64], has_limits: bool,
    table: NDArray[np.float64], centres: NDArray[np.float64], radii: NDArray[np.float64],
    live: NDArray[np.bool_],
) -> bool:  # fmt: skip
    """Whether the pose keeps every joint limit and cuts no live obstacle."""
    if has_limits and not _cone_ok(p, tiny, rest, table):
        return False
    return not _colliding(p, centres, radii, live, 1.0)


@numba.njit(cache=True, error_model="numpy")
def _copy(source: NDArray[np.float64], destination: NDArray[np.float64]) -> None:
    for i in range(source.shape[0]):
        destination[i, 0], destination[i, 1], destination[i, 2] = (
            source[i, 0],
            source[i, 1],
            source[i, 2],
        )


@numba.njit(cache=True, error_model="numpy")
def _end_error(p: NDArray[np.float64], target: NDArray[np.float64]) -> float:
    n = p.shape[0] - 1
    x, y, z = p[n, 0] - target[0], p[n, 1] - target[1], p[n, 2] - target[2]
    return math.sqrt(x * x + y * y + z * z)


@numba.njit(cache=True, error_model="numpy")
def _place_on_line(
    pose: NDArray[np.float64], root: NDArray[np.float64], lengths: NDArray[np.float64],
    ux: float, uy: float, uz: float, fold: bool,
) -> None:  # fmt: skip
    """The chain along the unit direction u from the root: straight, or (``fold``) with its longest link toward u
    and the others folded back, so the end rests on the inner boundary of the reach."""
    longest = np.argmax(lengths)
    reach = 0.0
    pose[0, 0], pose[0, 1], pose[0, 2] = root[0], root[1], root[2]
    for i in range(lengths.shape[0]):
        reach += lengths[i] if not fold or i == longest else -lengths[i]
        pose[i + 1, 0], pose[i + 1, 1], pose[i + 1, 2] = (
            root[0] + reach * ux,
            root[1] + reach * uy,
            root[2] + reach * uz,
        )


@numba.njit(cache=True, error_model="numpy")
def _unbend(
    p: NDArray[np.float64], target: NDArray[np.float64], lengths: NDArray[np.float64],
    tiny: float, rest: NDArray[np.float64], has_limits: bool, cos_phi: float, dim: int,
) -> None:  # fmt: skip
    """Bend a straight chain whose target lies on its own line into a gentle symmetric arc, so the passes can bend
    it (every interior joint leaves the line; an arc starting along it would leave p_1 on it)."""
    n = p.shape[0] - 1
    ax, ay, az = rest[0], rest[1], rest[2]
    for i in range(n):  # the axis: the first segment with a direction
        dx, dy, dz = p[i + 1, 0] - p[i, 0], p[i + 1, 1] - p[i, 1], p[i + 1, 2] - p[i, 2]
        ux, uy, uz, norm = _unit(dx, dy, dz, ax, ay, az, tiny)
        if norm > tiny:
            ax, ay, az = ux, uy, uz
            break
    for i in range(n):
        dx, dy, dz = p[i + 1, 0] - p[i, 0], p[i + 1, 1] - p[i, 1], p[i + 1, 2] - p[i, 2]
        along = dx * ax + dy * ay + dz * az
        ox, oy, oz = dx - along * ax, dy - along * ay, dz - along * az
        if math.sqrt(ox * ox + oy * oy + oz * oz) > 1e-9 * max(lengths[i], tiny):
            return  # not straight
    tx, ty, tz = target[0] - p[0, 0], target[1] - p[0, 1], target[2] - p[0, 2]
    along = tx * ax + ty * ay + tz * az
    ox, oy, oz = tx - along * ax, ty - along * ay, tz - along * az
    distance = math.sqrt(tx * tx + ty * ty + tz * tz)
    if math.sqrt(ox * ox + oy * oy + oz * oz) > 1e-9 * max(distance, tiny):
        return  # the target is off the chain's line: the passes bend it
    step = 0.1 if not has_limits else min(0.1, 0.5 * math.acos(cos_phi))
    if step <= 0.0:
        return
    sx, sy, sz = _perpendicular(ax, ay, az, dim)
    for i in range(n):
        angle = step * (i - 0.5 * (n - 1))
        c, s = math.cos(angle) * lengths[i], math.sin(angle) * lengths[i]
        p[i + 1, 0] = p[i, 0] + c * ax + s * sx
        p[i + 1, 1] = p[i, 1] + c * ay + s * sy
        p[i + 1, 2] = p[i, 2] + c * az + s * sz


@numba.njit(cache=True, error_model="numpy")
def _extrapolate(
    p: NDArray[np.float64], previous: NDArray[np.float64], error: float, previous_error: float,
    allowed: bool,
) -> bool:  # fmt: skip
    """Move the joints on along their last step, in place, by the rest of a geometric series; ``previous`` (the
    pose before the last step) becomes the pose before this move.

    Where the end-effector error shrank by a ratio ``r`` in [0.5, 1) in the last iteration, FABRIK converges
    linearly at about that ratio, and the steps still to come sum to ``r / (1 − r)`` times the last one (Aitken's
    Δ² extrapolation of a linearly converging sequence), capped at 8 steps. Only the next passes' starting guess
    moves: they still place every joint at its link's length, inside its cone and clear of obstacles. Nothing moves
    unless ``allowed``. Returns whether it moved the joints.
    """
    ratio = error / previous_error if previous_error > 0.0 else 0.0  # scale-free: no absolute floor
    slow = allowed and _EXTRAPOLATION_MIN_RATIO <= ratio < 1.0
    if not slow:  # (``previous`` is not yet set on the first call: only copy into it)
        _copy(p, previous)
        return False
    weight = ratio / max(1.0 - ratio, ratio / _EXTRAPOLATION_CAP)
    for i in range(p.shape[0]):
        for c in range(3):
            now = p[i, c]
            p[i, c] = now + weight * (now - previous[i, c])
            previous[i, c] = now
    return True


@numba.njit(cache=True, error_model="numpy")
def _solve_chain(
    p: NDArray[np.float64], target: NDArray[np.float64], params: NDArray[np.float64],
    flags: NDArray[np.int64], rest: NDArray[np.float64], centres: NDArray[np.float64],
    radii: NDArray[np.float64], lengths: NDArray[np.float64], live: NDArray[np.bool_],
    best: NDArray[np.float64], previous: NDArray[np.float64], before: NDArray[np.float64],
    out_p: NDArray[np.float64], history: NDArray[np.float64], table: NDArray[np.float64],
) -> tuple[int, int, float]:  # fmt: skip
    """Solve one chain, starting from ``p`` (n + 1, 3), which it works on in place.

    Writes the returned pose to ``out_p`` and the iterates' errors to ``history`` (max_iterations + 1,), which it
    leaves NaN past the last iteration; ``lengths`` (n,), ``live`` (K,), ``best``, ``previous`` and ``before``
    (n + 1, 3) are scratch. Returns (iterations, status, error of the returned pose).
    """
    tolerance, cos_phi = params[0], params[1]
    max_iterations, dim, solver = flags[0], flags[1], flags[2]
    extrapolate = flags[3] != 0 and solver == _FABRIK
    has_limits = flags[4] != 0
    limits = (has_limits, table)
    n = p.shape[0] - 1
    history[:] = np.nan

    total, has_zero = 0.0, False
    for i in range(n):
        dx, dy, dz = p[i + 1, 0] - p[i, 0], p[i + 1, 1] - p[i, 1], p[i + 1, 2] - p[i, 2]
        lengths[i] = math.sqrt(dx * dx + dy * dy + dz * dz)
        total += lengths[i]
    ox, oy, oz = target[0] - p[0, 0], target[1] - p[0, 1], target[2] - p[0, 2]
    distance = math.sqrt(ox * ox + oy * oy + oz * oz)
    # relative only: the core gives the same bits at any power-of-2 scale
    tiny = _TINY * max(total, distance)
    for i in range(n):
        has_zero = has_zero or lengths[i] <= tiny
    inner = max(0.0, 2.0 * np.max(lengths) - total)
    beyond = distance > total + tiny
    fold = distance < inner - tiny
    out_of_reach = beyond or fold
    # Within tolerance of the inner radius the folded pose is as good a candidate as the straight one at full reach.
    near_inner = inner > 0.0 and distance <= inner + tolerance + tiny
    fold = fold or (near_inner and distance - inner < total - distance)
    any_live = False
    for k in range(radii.shape[0]):
        live[k] = (centres[k, 0] - p[0, 0]) ** 2 + (centres[k, 1] - p[0, 1]) ** 2 + (
            centres[k, 2] - p[0, 2]
        ) ** 2 > radii[k] * radii[k]
        any_live = any_live or live[k]
    constrained = (has_limits and flags[5] != 0) or any_live

    error = _end_error(p, target)
    history[0] = error
    _copy(p, best)
    best_error = np.inf
    if _admissible(p, tiny, rest, has_limits, table, centres, radii, live):
        best_error = error
        if error <= tolerance:
            _copy(p, out_p)
            return 0, _REACHED, error

    if solver == _FABRIK and (out_of_reach or near_inner or distance >= total - tolerance - tiny):
        # The closest pose to a target out of reach; the straight pose toward one within tolerance of full reach.
        ux, uy, uz, _ = _unit(ox, oy, oz, rest[0], rest[1], rest[2], tiny)
        _place_on_line(before, p[0], lengths, ux, uy, uz, fold)
        candidate = _end_error(before, target)
        # "reached" means error ≤ tolerance, with no slack: a candidate short of it by rounding iterates on.
        if _admissible(before, tiny, rest, has_limits, table, centres, radii, live):
            if candidate <= tolerance or out_of_reach:
                _copy(before, out_p)
                history[1] = candidate
                return 1, _REACHED if candidate <= tolerance else _UNREACHABLE, candidate

    _unbend(p, target, lengths, tiny, rest, has_limits, cos_phi, dim)
    # The extrapolation's first call moves by 0 × (p − previous): never 0 × uninitialised memory (NaN).
    _copy(p, previous)
    stall = _STALL * tolerance + tiny
    progress = _PROGRESS * tolerance + tiny
    stall_applies = constrained or out_of_reach
    trusted, moved, reached, stalled = True, False, False, False
    count, mark_iteration, mark_error = 0, 0, best_error
    # Extrapolated FABRIK under limits, within reach, restarts once where it stalls (see below) at ``restart``
    retry, restart = extrapolate and has_limits and not out_of_reach, 0
    for iteration in range(1, max_iterations + 1):
        count = iteration
        last_error = history[iteration - 1]
        if (
            extrapolate and iteration >= restart + 2
        ):  # from the third iteration on, and while trusted
            allowed = iteration >= restart + 3 and trusted
            moved = _extrapolate(p, previous, last_error, history[iteration - 2], allowed)
        if solver == _FABRIK:
            _forward_pass(
                p, target, lengths, tiny, rest, limits, centres, radii, live, has_zero, dim
            )
        elif solver == _CCD:
            _ccd_sweep(p, target, tiny, rest, dim)
        else:
            _dls_step(p, target, lengths, tiny, before)
        _backward_pass(p, lengths, tiny, rest, limits, centres, radii, live, has_zero, dim)
        error = _end_error(p, target)
        history[iteration] = error
        # A chain whose extrapolation made its error grow (a target the limits keep away, r → 1) is left to plain
        # FABRIK from then on, which settles at its fixed point.
        trusted = trusted and not (moved and error > last_error)
        if (error < best_error or error <= tolerance) and (
            not constrained or _admissible(p, tiny, rest, has_limits, table, centres, radii, live)
        ):
            if error < best_error:
                _copy(p, best)
                best_error = error
            reached = error <= tolerance
        if best_error < mark_error - progress:
            mark_iteration, mark_error = iteration, best_error
        stalled = stall_applies and (
            abs(last_error - error) < stall or iteration - mark_iteration >= _PATIENCE
        )
        if stalled and not reached and retry:
            # A stall under limits is a fixed point of this start, not proof that the limits keep the target
            # away: go on once from the straight pose toward the target, clamped into the cones (another basin).
            retry, stalled, restart, trusted, mark_iteration = (
                False,
                False,
                iteration,
                True,
                iteration,
            )
            ux, uy, uz, _ = _unit(ox, oy, oz, rest[0], rest[1], rest[2], tiny)
            _place_on_line(p, best[0], lengths, ux, uy, uz, False)
            _unbend(
                p, target, lengths, tiny, rest, has_limits, cos_phi, dim
            )  # a straight chain never bends
            _backward_pass(p, lengths, tiny, rest, limits, centres, radii, live, has_zero, dim)
            continue
        if reached or stalled:
            break

    if (
        reached or best_error == np.inf
    ):  # reached: this iterate is the best; none admissible: the last
        _copy(p, out_p)
    else:
        _copy(best, out_p)
    final_error = _end_error(out_p, target)
    if reached:
        return count, _REACHED, final_error
    # neither the start nor any iterate kept every limit and cleared every obstacle
    if best_error == np.inf:
        return count, _INFEASIBLE, final_error
    if out_of_reach:
        return count, _UNREACHABLE, final_error
    if any_live:
        for k in range(radii.shape[0]):
            inside = (
                (centres[k, 0] - target[0]) ** 2 + (centres[k, 1] - target[1]) ** 2
                + (centres[k, 2] - target[2]) ** 2 < radii[k] * radii[k]
            )  # fmt: skip
            if live[k] and inside:
                return count, _BLOCKED, final_error
        if _colliding(out_p, centres, radii, live, 1.0 + _TOUCH):
            return count, _BLOCKED, final_error
    return count, _LIMITED if stalled else _MAX_ITERATIONS, final_error


@numba.njit(cache=True, error_model="numpy")
def _solve_rows(
    lo: int, hi: int, p: NDArray[np.float64], target: NDArray[np.float64],
    params: NDArray[np.float64], flags: NDArray[np.int64], rest: NDArray[np.float64],
    centres: NDArray[np.float64], radii: NDArray[np.float64], out_p: NDArray[np.float64],
    history: NDArray[np.float64], iterations: NDArray[np.int64], status: NDArray[np.int64],
    error: NDArray[np.float64], table: NDArray[np.float64],
) -> None:  # fmt: skip
    """Solve rows ``lo`` to ``hi`` of a batch (p (B, n + 1, 3), target (B, 3)) with one set of scratch arrays."""
    count = p.shape[1]
    lengths = np.empty(count - 1)
    live = np.empty(radii.shape[0], dtype=np.bool_)
    best, previous, before = np.empty((count, 3)), np.empty((count, 3)), np.empty((count, 3))
    for b in range(lo, hi):
        iterations[b], status[b], error[b] = _solve_chain(
            p[b], target[b], params, flags, rest, centres, radii, lengths, live, best, previous,
            before, out_p[b], history[b], table,
        )  # fmt: skip


@numba.njit(cache=True, error_model="numpy", parallel=True)
def _solve_parallel(
    chunks: int, p: NDArray[np.float64], target: NDArray[np.float64],
    params: NDArray[np.float64], flags: NDArray[np.int64], rest: NDArray[np.float64],
    centres: NDArray[np.float64], radii: NDArray[np.float64], out_p: NDArray[np.float64],
    history: NDArray[np.float64], iterations: NDArray[np.int64], status: NDArray[np.int64],
    error: NDArray[np.float64], table: NDArray[np.float64],
) -> None:  # fmt: skip
    """:func:`_solve_rows` over a whole batch, in ``chunks`` contiguous chunks spread over numba's threads."""
    batch = p.shape[0]
    for c in numba.prange(chunks):
        _solve_rows(c * batch // chunks, (c + 1) * batch // chunks, p, target, params, flags, rest,
                    centres, radii, out_p, history, iterations, status, error, table)  # fmt: skip


# ================================================================================================ compiled joints
# Per-segment limits, read from a (T, 13) table (see :func:`_limit_table`): row i for segment i, or row 0 for every
# segment when T = 1 (the uniform cone). A tree's table has one row per joint, for the segment from its parent.
@numba.njit(cache=True, error_model="numpy")
def _row(table: NDArray[np.float64], i: int) -> int:
    return i if table.shape[0] > 1 else 0


@numba.njit(cache=True, error_model="numpy")
def _turn_shortest(
    vx: float, vy: float, vz: float, s: NDArray[np.float64], tx: float, ty: float, tz: float
) -> tuple[float, float, float]:
    """v turned by the shortest rotation taking unit s onto unit t (π about a perpendicular where t = −s).

    ``R v = v + c × v + c × (c × v) / (1 + s·t)`` with ``c = s × t`` (Rodrigues' formula without the angle)."""
    cx, cy, cz = s[1] * tz - s[2] * ty, s[2] * tx - s[0] * tz, s[0] * ty - s[1] * tx
    dot = s[0] * tx + s[1] * ty + s[2] * tz
    if dot < -1.0 + 1e-12:
        kx, ky, kz = _perpendicular(s[0], s[1], s[2], 3)
        along = 2.0 * (kx * vx + ky * vy + kz * vz)
        return along * kx - vx, along * ky - vy, along * kz - vz
    wx, wy, wz = cy * vz - cz * vy, cz * vx - cx * vz, cx * vy - cy * vx
    k = 1.0 / (1.0 + dot)
    ux, uy, uz = cy * wz - cz * wy, cz * wx - cx * wz, cx * wy - cy * wx
    return vx + wx + k * ux, vy + wy + k * uy, vz + wz + k * uz


@numba.njit(cache=True, error_model="numpy")
def _hinge_axes(
    table: NDArray[np.float64], row: int, qx: float, qy: float, qz: float,
    rest: NDArray[np.float64],
) -> tuple[float, float, float, float, float, float]:  # fmt: skip
    """The hinge's world axis a and unit reference r ⊥ a, for a previous-segment direction q (unit)."""
    ax, ay, az = table[row, 3], table[row, 4], table[row, 5]
    rx, ry, rz = table[row, 6], table[row, 7], table[row, 8]
    if table[row, 11] != 0.0:  # local: turn with the previous segment
        ax, ay, az = _turn_shortest(ax, ay, az, rest, qx, qy, qz)
        if table[row, 12] != 0.0:
            rx, ry, rz = _turn_shortest(rx, ry, rz, rest, qx, qy, qz)
    if table[row, 12] == 0.0:
        rx, ry, rz = qx, qy, qz
    along = rx * ax + ry * ay + rz * az
    px, py, pz = _perpendicular(ax, ay, az, 3)
    rx, ry, rz, _ = _unit(rx - along * ax, ry - along * ay, rz - along * az, px, py, pz, 1e-9)
    return ax, ay, az, rx, ry, rz


@numba.njit(cache=True, error_model="numpy")
def _rotate(
    vx: float, vy: float, vz: float, ax: float, ay: float, az: float, angle: float
) -> tuple[float, float, float]:
    """v turned by ``angle`` (rad) about the unit axis a (Rodrigues' formula)."""
    c, s = math.cos(angle), math.sin(angle)
    dot = (ax * vx + ay * vy + az * vz) * (1.0 - c)
    return (
        vx * c + (ay * vz - az * vy) * s + ax * dot,
        vy * c + (az * vx - ax * vz) * s + ay * dot,
        vz * c + (ax * vy - ay * vx) * s + az * dot,
    )


@numba.njit(cache=True, error_model="numpy")
def _wrap(angle: float) -> float:
    """``angle`` (rad) brought into [−π, π)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


@numba.njit(cache=True, error_model="numpy")
def _hinge_angle(
    vx: float, vy: float, vz: float, ax: float, ay: float, az: float, rx: float, ry: float,
    rz: float, low: float, high: float,
) -> float:  # fmt: skip
    """Signed angle of v about a from r (rad), as the representative in [low − 2π, high + 2π] nearest the range."""
    bx, by, bz = ay * rz - az * ry, az * rx - ax * rz, ax * ry - ay * rx
    theta = math.atan2(vx * bx + vy * by + vz * bz, vx * rx + vy * ry + vz * rz)
    if theta < low and theta + 2.0 * math.pi <= high + _HINGE_SLACK:
        theta += 2.0 * math.pi
    elif theta > high and theta - 2.0 * math.pi >= low - _HINGE_SLACK:
        theta -= 2.0 * math.pi
    return theta


@numba.njit(cache=True, error_model="numpy")
def _clamp_hinge(
    vx: float, vy: float, vz: float, qx: float, qy: float, qz: float,
    table: NDArray[np.float64], row: int, rest: NDArray[np.float64],
) -> tuple[float, float, float]:  # fmt: skip
    """The unit direction v brought onto the hinge: projected onto its plane (the nearest direction there), then,
    outside the range, onto the nearer end around the circle."""
    ax, ay, az, rx, ry, rz = _hinge_axes(table, row, qx, qy, qz, rest)
    along = vx * ax + vy * ay + vz * az
    ux, uy, uz, _ = _unit(vx - along * ax, vy - along * ay, vz - along * az, rx, ry, rz, 1e-12)
    low, high = table[row, 9], table[row, 10]
    theta = _hinge_angle(ux, uy, uz, ax, ay, az, rx, ry, rz, low, high)
    if low <= theta <= high:
        return ux, uy, uz
    end = low if abs(_wrap(theta - low)) <= abs(_wrap(theta - high)) else high
    bx, by, bz = ay * rz - az * ry, az * rx - ax * rz, ax * ry - ay * rx
    c, s = math.cos(end), math.sin(end)
    return c * rx + s * bx, c * ry + s * by, c * rz + s * bz


@numba.njit(cache=True, error_model="numpy")
def _constrain(
    vx: float, vy: float, vz: float, qx: float, qy: float, qz: float,
    table: NDArray[np.float64], i: int, rest: NDArray[np.float64], tiny: float, dim: int,
) -> tuple[float, float, float]:  # fmt: skip
    """Segment i's unit direction v brought inside its joint's limit, q (unit) the previous segment's direction."""
    row = _row(table, i)
    kind = table[row, 0]
    if kind == _KIND_CONE:
        return _clamp_cone(vx, vy, vz, qx, qy, qz, table[row, 1], table[row, 2], dim)
    if kind == _KIND_HINGE:
        return _clamp_hinge(vx, vy, vz, qx, qy, qz, table, row, rest)
    return vx, vy, vz


@numba.njit(cache=True, error_model="numpy")
def _forward_limits(
    p: NDArray[np.float64], i: int, n: int, dx: float, dy: float, dz: float, qx: float,
    qy: float, qz: float, table: NDArray[np.float64], rest: NDArray[np.float64], tiny: float,
    dim: int,
) -> tuple[float, float, float]:  # fmt: skip
    """The forward pass's limits on segment i, whose reversed unit direction is d (q: segment i + 1's, reversed).

    The cone of the joint between segments i and i + 1 holds them together (it is symmetric); a hinge on segment i
    keeps it in its plane, the plane taken from segment i − 1 as it stands (caliko's forward pass; the range waits
    for the backward pass)."""
    if i < n - 1:
        row = _row(table, i + 1)
        if table[row, 0] == _KIND_CONE:
            dx, dy, dz = _clamp_cone(dx, dy, dz, qx, qy, qz, table[row, 1], table[row, 2], dim)
        elif table[row, 0] == _KIND_HINGE and table[row, 12] == 0.0:
            # A joint angle (measured from segment i): turn segment i about the axis until segment i + 1's
            # angle from it is in range, as the cone does by symmetry.
            ax, ay, az, rx, ry, rz = _hinge_axes(table, row, -dx, -dy, -dz, rest)
            low, high = table[row, 9], table[row, 10]
            theta = _hinge_angle(-qx, -qy, -qz, ax, ay, az, rx, ry, rz, low, high)
            if not low <= theta <= high:
                end = low if abs(_wrap(theta - low)) <= abs(_wrap(theta - high)) else high
                dx, dy, dz = _rotate(dx, dy, dz, ax, ay, az, theta - end)
    row = _row(table, i)
    if table[row, 0] == _KIND_HINGE:
        sx, sy, sz, _ = _unit(p[i, 0] - p[i - 1, 0], p[i, 1] - p[i - 1, 1], p[i, 2] - p[i - 1, 2],
                              rest[0], rest[1], rest[2], tiny)  # fmt: skip
        ax, ay, az, rx, ry, rz = _hinge_axes(table, row, sx, sy, sz, rest)
        along = dx * ax + dy * ay + dz * az
        dx, dy, dz, _ = _unit(
            dx - along * ax, dy - along * ay, dz - along * az, -rx, -ry, -rz, 1e-12
        )
    return dx, dy, dz


@numba.njit(cache=True, error_model="numpy")
def _joint_ok(
    dx: float, dy: float, dz: float, qx: float, qy: float, qz: float,
    table: NDArray[np.float64], i: int, rest: NDArray[np.float64], tiny: float,
) -> bool:  # fmt: skip
    """Whether segment i's unit direction d keeps its joint's limit, q the previous segment's unit direction."""
    row = _row(table, i)
    kind = table[row, 0]
    if kind == _KIND_CONE:
        return dx * qx + dy * qy + dz * qz >= table[row, 1] - _CONE_SLACK
    if kind == _KIND_HINGE:
        ax, ay, az, rx, ry, rz = _hinge_axes(table, row, qx, qy, qz, rest)
        if abs(dx * ax + dy * ay + dz * az) > _HINGE_SLACK:
            return False
        low, high = table[row, 9], table[row, 10]
        theta = _hinge_angle(dx, dy, dz, ax, ay, az, rx, ry, rz, low, high)
        return low - _HINGE_SLACK <= theta <= high + _HINGE_SLACK
    return True


@numba.njit(cache=True, error_model="numpy")
def _usage(
    p: NDArray[np.float64], table: NDArray[np.float64], rest: NDArray[np.float64], tiny: float
) -> NDArray[np.float64]:
    """(n,) share of each segment's limit used (see :func:`limit_usage`)."""
    n = p.shape[0] - 1
    share = np.zeros(n)
    qx, qy, qz = rest[0], rest[1], rest[2]
    for i in range(n):
        dx, dy, dz, norm = _unit(p[i + 1, 0] - p[i, 0], p[i + 1, 1] - p[i, 1],
                                 p[i + 1, 2] - p[i, 2], qx, qy, qz, tiny)  # fmt: skip
        if norm <= tiny:
            continue
        row = _row(table, i)
        kind = table[row, 0]
        if kind == _KIND_CONE:
            phi = math.atan2(table[row, 2], table[row, 1])
            angle = math.acos(min(max(dx * qx + dy * qy + dz * qz, -1.0), 1.0))
            share[i] = 1.0 if phi <= 0.0 else min(angle / phi, 1.0)
        elif kind == _KIND_HINGE:
            ax, ay, az, rx, ry, rz = _hinge_axes(table, row, qx, qy, qz, rest)
            low, high = table[row, 9], table[row, 10]
            theta = _hinge_angle(dx, dy, dz, ax, ay, az, rx, ry, rz, low, high)
            half = 0.5 * (high - low)
            gap = min(theta - low, high - theta)
            share[i] = 1.0 if half <= 0.0 else min(max(1.0 - gap / half, 0.0), 1.0)
        qx, qy, qz = dx, dy, dz
    return share


# ================================================================================================ skeletons
@dataclasses.dataclass(frozen=True)
class TreeSolution:
    """One skeleton's solve (:func:`solve_tree`)."""

    joints: NDArray[np.float64]
    """(J, d) joint positions of the returned pose (m), in the order given."""
    effectors: NDArray[np.int64]
    """(E,) the joints that had targets, ascending; ``error`` and ``status`` follow this order."""
    error: NDArray[np.float64]
    """(E,) distance from each end effector to its target (m)."""
    status: tuple[Status, ...]
    """(E,) why each effector stopped where it did; see :data:`Status`. A tree stops at a fixed point of the
    centroid rule only where limits or live obstacles can hold it ("limited" then also covers an effector held short
    of its target by the others' targets) or where some effector's target is out of its path's reach (an effector
    held short by that compromise is "unreachable": its target cannot be met together with the others'). Never
    "limited" without limits or obstacles; "infeasible" where no iterate kept every limit and cleared every
    obstacle."""
    iterations: int
    """Iterations run (0 when the start already met the tolerance)."""
    error_history: NDArray[np.float64]
    """(iterations + 1, E) every effector's error before the first iteration and after each one (m)."""


def solve_tree(
    parents: ArrayLike,
    joints: ArrayLike,
    targets: Mapping[int, ArrayLike],
    *,
    tolerance: float = 1e-3,
    max_iterations: int = 50,
    constraints: Sequence[Constraint] | None = None,
    obstacles: Sequence[Obstacle] = (),
    root_direction: ArrayLike | None = None,
) -> TreeSolution:
    """Solve a skeleton with several end effectors by FABRIK (Aristidou & Lasenby 2011, §4.2, multiple end
    effectors).

    Forward stage: from each end effector with a target, forward reaching up its branch to the sub-base (the
    nearest joint with several children, or the root); each branch proposes a place for the sub-base and the
    sub-base goes to their centroid, then forward reaching goes on from there toward the root. Backward stage: the
    root back on its place and backward reaching outwards along every branch. Effectors without a target, and the
    branches that only lead to them, take no part in the forward stage and follow in the backward one. Joint limits
    are imposed inside the backward stage (the forward stage only keeps each hinge's segment in its plane), so every
    iterate keeps every limit; obstacles as in :func:`solve`. Stops when every effector is within ``tolerance``, at
    ``max_iterations``, or when no effector's error changes by more than 0.1 % of the tolerance in an iteration
    where limits or obstacles can hold the tree or a target is out of reach (as :func:`solve`); a free tree within
    reach that stalls so goes on once from every segment turned aside (a mirror-symmetric start stays symmetric
    under the centroid rule), then to the cap. "Reached" is error ≤ tolerance on a pose that keeps every limit (a
    start that breaks one is iterated on); the returned pose is the last iterate, or the best admissible one where
    the last is not. Huge or tiny trees are divided by a power of 2 first (as :func:`solve`): a tree scaled by 2^k
    gives the same result scaled.

    A tree that is one chain (no joint with two children) is solved by :func:`solve` itself, so it gives
    ``solve``'s result (with its extrapolation, its best-pose rule and its closest pose for targets out of reach).

    Args:
        parents: (J,) int, the parent of each joint; −1 for the one root. Any order (joints need not follow their
            parents).
        joints: (J, d) starting joint positions (m), d = 2 or 3; the root is fixed and link lengths (joint to
            parent) are kept.
        targets: end-effector joint index (a joint with no children) → (d,) target (m); at least one.
        tolerance: as in :func:`solve` (m), for every effector.
        max_iterations: iteration cap, ≥ 1.
        constraints: one entry per joint for the segment from its parent (None for the root and free joints):
            :class:`Cone` or :class:`Hinge`, "previous segment" being the parent's segment (the root direction for
            the root's children).
        obstacles: as in :func:`solve`.
        root_direction: as in :func:`solve`.

    Returns:
        The :class:`TreeSolution`.

    Raises:
        ValueError: naming the argument, for a ``parents`` that is not one tree over the joints, targets on joints
            that are not end effectors, and everything :func:`solve` refuses.
    """
    points = _check_joints("joints", joints, batched=False)
    count, dim = points.shape
    if not isinstance(targets, Mapping) or not targets:
        raise ValueError(
            f"targets must be a non-empty mapping joint index → target, got {targets!r}"
        )
    # Keys and parents are checked for type and shape before the cache: 2.0 and True hash as 2 and 1, and a
    # flattened (1, J) array as its (J,) row, so the cache would otherwise answer for input it must refuse.
    for key in targets:
        if isinstance(key, bool) or not isinstance(key, (int, np.integer)) or not 0 <= key < count:
            raise ValueError(f"targets keys must be joint indices in [0, {count - 1}], got {key!r}")
    keys = tuple(sorted(int(key) for key in targets))
    try:
        raw = np.asarray(parents)
    except (TypeError, ValueError):
        raw = None
    if raw is not None and raw.dtype.kind in "iu" and raw.shape == (count,):
        topology = _tree_topology(tuple(raw.tolist()), count, keys)
    else:  # refused (ValueError naming parents) without the cache
        topology = _tree_topology.__wrapped__(parents, count, keys)
    order, parent, active, has_goal, effector_ids, is_chain = topology
    goal = np.zeros((count, 3))
    for key in effector_ids.tolist():
        goal[key, :dim] = _check_vector(f"targets[{key}]", targets[key], dim)
    setup = _Setup.build(dim, tolerance, max_iterations, None, obstacles, root_direction,
                         _FABRIK, False)  # fmt: skip
    root = int(order[0])
    table = _tree_table(constraints, count, dim, root)
    tol = float(setup.params[0])

    if is_chain:  # one chain: solve's result
        chain_constraints = None if constraints is None else [constraints[j] for j in order[1:]]
        single = _solve_single("fabrik", points[order], goal[effector_ids[0], :dim], tol,
                               setup.max_iterations, None, obstacles, root_direction, True,
                               chain_constraints)  # fmt: skip
        out = np.empty_like(points)
        out[order] = single.joints
        return TreeSolution(
            joints=out,
            effectors=effector_ids.copy(),
            error=np.array([single.error]),
            status=(single.status,),
            iterations=single.iterations,
            error_history=single.error_history[:, None].copy(),
        )

    p = np.zeros((count, 3))
    p[:, :dim] = points
    history = np.empty((setup.max_iterations + 1, len(effector_ids)))
    codes = np.empty(len(effector_ids), dtype=np.int64)
    final = np.empty(len(effector_ids))
    # As solve: divided by a power of 2 near the extent (exact), so squared norms neither overflow nor underflow
    extent = _tree_extent(p, goal, effector_ids, root)
    scale, centres, radii = 1.0, setup.centres, setup.radii
    if extent != 0.0 and not _UNSCALED[0] <= extent <= _UNSCALED[1]:
        scale = math.ldexp(1.0, math.frexp(extent)[1])
        p /= scale
        goal /= scale
        tol, centres, radii = tol / scale, centres / scale, radii / scale
    iterations = _solve_tree_core(
        p, parent, order, active, goal, has_goal, effector_ids, table, setup.root_direction,
        centres, radii, tol, setup.max_iterations, dim, history, codes, final,
    )  # fmt: skip
    if scale != 1.0:
        p *= scale
        history *= scale
        final *= scale
    return TreeSolution(
        joints=p[:, :dim].copy() if dim == 2 else p,
        effectors=effector_ids.copy(),
        error=final,
        status=tuple(STATUSES[c] for c in codes.tolist()),
        iterations=int(iterations),
        error_history=history[: iterations + 1].copy(),
    )


@functools.lru_cache(maxsize=64)
def _tree_topology(
    parents: object, count: int, keys: tuple[object, ...]
) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.bool_], NDArray[np.bool_],
           NDArray[np.int64], bool]:  # fmt: skip
    """Checked tree structure: breadth-first order, parents, the joints that take part in the forward stage (a
    target beyond them), the targeted joints, the effectors (ascending) and whether the tree is one chain. Cached:
    a dragged skeleton asks for the same every frame (the arrays are never written to)."""
    try:
        raw = np.asarray(parents)
    except (TypeError, ValueError) as error:
        raise ValueError(
            f"parents must be a ({count},) array of integers, got {parents!r}"
        ) from error
    if (
        raw.shape != (count,)
        or raw.dtype.kind not in "iu"
        or np.any(raw < -1)
        or np.any(raw >= count)
    ):
        raise ValueError(
            f"parents must be ({count},) integers in [−1, {count - 1}], got {parents!r}"
        )
    parent = raw.astype(np.int64)
    roots = np.flatnonzero(parent == -1)
    if roots.size != 1:
        raise ValueError(f"parents must have exactly one root (−1), got {roots.size}")
    children: list[list[int]] = [[] for _ in range(count)]
    for j, up in enumerate(parent.tolist()):
        if up >= 0:
            children[up].append(j)
    order = [int(roots[0])]
    for j in order:  # breadth first: every joint after its parent
        order.extend(children[j])
    if len(order) != count:
        raise ValueError(
            "parents must form one tree: some joints are on a cycle, not under the root"
        )
    has_goal = np.zeros(count, dtype=np.bool_)
    for key in keys:
        if isinstance(key, bool) or not isinstance(key, (int, np.integer)) or not 0 <= key < count:
            raise ValueError(f"targets keys must be joint indices in [0, {count - 1}], got {key!r}")
        if children[key]:
            raise ValueError(
                f"targets[{key}] is on a joint with children: targets go on end effectors"
            )
        has_goal[key] = True
    active = has_goal.copy()
    for j in reversed(
        order
    ):  # a joint takes part in the forward stage when a target lies beyond it
        if active[j] and parent[j] >= 0:
            active[parent[j]] = True
    effectors = np.flatnonzero(has_goal).astype(np.int64)
    is_chain = all(len(c) <= 1 for c in children)
    return np.array(order, dtype=np.int64), parent, active, has_goal, effectors, is_chain


def _tree_table(
    constraints: Sequence[Constraint] | None, count: int, dim: int, root: int
) -> NDArray[np.float64]:
    """The checked limit table of a tree (one row per joint), cached on hashable constraints."""
    if constraints is None:
        return np.zeros((count, _TABLE_WIDTH))
    try:
        return _tree_table_cached(tuple(constraints), count, dim, root)
    except TypeError:  # unhashable entries: checked (and refused) without the cache
        return _tree_table_cached.__wrapped__(constraints, count, dim, root)


@functools.lru_cache(maxsize=64)
def _tree_table_cached(
    constraints: Sequence[Constraint], count: int, dim: int, root: int
) -> NDArray[np.float64]:
    if (
        isinstance(constraints, Sequence)
        and len(constraints) == count
        and constraints[root] is not None
    ):
        raise ValueError(f"constraints[{root}] must be None: the root has no segment")
    return _limit_table(constraints, count, dim, "constraints", segment_offset=0)


@numba.njit(cache=True, error_model="numpy")
def _solve_tree_core(
    p: NDArray[np.float64], parents: NDArray[np.int64], order: NDArray[np.int64],
    active: NDArray[np.bool_], goal: NDArray[np.float64], has_goal: NDArray[np.bool_],
    effectors: NDArray[np.int64], table: NDArray[np.float64], rest: NDArray[np.float64],
    centres: NDArray[np.float64], radii: NDArray[np.float64], tolerance: float,
    max_iterations: int, dim: int, history: NDArray[np.float64], codes: NDArray[np.int64],
    final: NDArray[np.float64],
) -> int:  # fmt: skip
    """Multi-end-effector FABRIK on ``p`` (J, 3), in place; ``order`` is breadth first from the root.

    Leaves the returned pose in ``p``: the last iterate where it keeps every limit and clears every live obstacle,
    else the best (smallest largest error) that did, else the last. Fills ``history`` (max_iterations + 1, E) with
    the iterates' errors, NaN past the last iteration, ``final`` (E,) with the returned pose's errors and ``codes``
    (E,) with each effector's status: reached (error ≤ tolerance, on an admissible pose); unreachable (farther from
    the root than its path's length); blocked (target inside a live obstacle, or the pose touching one); limited
    (stopped at a fixed point while limits or obstacles hold the tree); infeasible (no admissible pose seen);
    max_iterations. Returns the iterations run. Every test is relative to the tree's size (no absolute floor), so
    a tree scaled by a power of 2 gives the same bits scaled."""
    count = p.shape[0]
    root = int(order[0])
    history[:, :] = np.nan
    has_limits, holding = False, False
    for j in range(count):
        has_limits = has_limits or table[j, 0] != _KIND_FREE
        # free hinges (a full turn) only keep a segment in its plane: no fixed point of their own (as solve)
        full_turn = table[j, 0] == _KIND_HINGE and table[j, 10] - table[j, 9] >= 2.0 * math.pi
        holding = holding or (table[j, 0] != _KIND_FREE and not full_turn)
    lengths = np.zeros(count)
    total = 0.0
    for j in range(count):
        if parents[j] >= 0:
            up = int(parents[j])
            dx, dy, dz = p[j, 0] - p[up, 0], p[j, 1] - p[up, 1], p[j, 2] - p[up, 2]
            lengths[j] = math.sqrt(dx * dx + dy * dy + dz * dz)
            total += lengths[j]
    distance = 0.0
    for e in range(effectors.shape[0]):
        k = int(effectors[e])
        dx, dy, dz = goal[k, 0] - p[root, 0], goal[k, 1] - p[root, 1], goal[k, 2] - p[root, 2]
        distance = max(distance, math.sqrt(dx * dx + dy * dy + dz * dz))
    # relative only (as solve): the core gives the same bits at any power-of-2 scale
    tiny = _TINY * max(total, distance)
    live = np.empty(radii.shape[0], dtype=np.bool_)
    any_live = False
    for k in range(radii.shape[0]):
        live[k] = (centres[k, 0] - p[root, 0]) ** 2 + (centres[k, 1] - p[root, 1]) ** 2 + (
            centres[k, 2] - p[root, 2]
        ) ** 2 > radii[k] * radii[k]
        any_live = any_live or live[k]
    # As solve, the fixed-point rule stops a tree only where limits or obstacles can hold it, or where some
    # effector's target is out of its path's reach; a free tree within reach iterates on to the cap.
    out_of_reach = False
    for e in range(effectors.shape[0]):
        key = int(effectors[e])
        reach, longest, j = 0.0, 0.0, key
        while parents[j] >= 0:
            reach += lengths[j]
            longest = max(longest, lengths[j])
            j = int(parents[j])
        inner = max(0.0, 2.0 * longest - reach)  # the path's annulus, as solve's
        dx, dy, dz = goal[key, 0] - p[root, 0], goal[key, 1] - p[root, 1], goal[key, 2] - p[root, 2]
        distance = math.sqrt(dx * dx + dy * dy + dz * dz)
        out_of_reach = out_of_reach or distance > reach + tiny or distance < inner - tiny
    stall_applies = holding or any_live or out_of_reach
    best = p.copy()
    best_worst = np.inf
    bx, by, bz = p[root, 0], p[root, 1], p[root, 2]
    directions = np.zeros(
        (count, 3)
    )  # each joint's segment direction (its parent's where it has none)
    directions[root, 0], directions[root, 1], directions[root, 2] = rest[0], rest[1], rest[2]
    for k in range(1, count):
        j = int(order[k])
        up = int(parents[j])
        ux, uy, uz, _ = _unit(p[j, 0] - p[up, 0], p[j, 1] - p[up, 1], p[j, 2] - p[up, 2],
                              directions[up, 0], directions[up, 1], directions[up, 2], tiny)  # fmt: skip
        directions[j, 0], directions[j, 1], directions[j, 2] = ux, uy, uz
    sums = np.zeros((count, 3))
    counts = np.zeros(count, dtype=np.int64)
    only_child = np.full(count, -1, dtype=np.int64)  # the one active child, where a joint has one
    for j in range(count):
        up = int(parents[j])
        if up >= 0 and active[j]:
            only_child[up] = j if counts[up] == 0 else -1
            counts[up] += 1

    worst = _tree_errors(p, goal, effectors, history, 0)
    if _tree_admissible(p, parents, order, table, rest, tiny, has_limits, centres, radii, live):
        best_worst = worst
        if worst <= tolerance:  # the start is returned as reached only where it keeps every limit
            final[:] = history[0]
            _tree_statuses(p, parents, goal, effectors, lengths, centres, radii, live, tolerance,
                           tiny, final, False, False, codes)  # fmt: skip
            return 0
    stall = _STALL * tolerance + tiny
    iterations, stalled, retry = 0, False, True
    for iteration in range(1, max_iterations + 1):
        iterations = iteration
        # forward stage: effectors on their targets, sub-bases at the centroid of their branches' proposals
        sums[:, :] = 0.0
        counts[:] = 0
        for k in range(count - 1, 0, -1):
            j = int(order[k])
            if not active[j]:
                continue
            if has_goal[j]:
                x, y, z = goal[j, 0], goal[j, 1], goal[j, 2]
            else:
                x, y, z = sums[j, 0] / counts[j], sums[j, 1] / counts[j], sums[j, 2] / counts[j]
            p[j, 0], p[j, 1], p[j, 2] = x, y, z
            up = int(parents[j])
            dx, dy, dz, _ = _unit(p[up, 0] - x, p[up, 1] - y, p[up, 2] - z,
                                  -directions[j, 0], -directions[j, 1], -directions[j, 2], tiny)  # fmt: skip
            c = only_child[j]
            if (
                c >= 0 and not has_goal[j]
            ):  # the joint to its one child holds this segment (as in a chain)
                qx, qy, qz, _ = _unit(x - p[c, 0], y - p[c, 1], z - p[c, 2], dx, dy, dz, tiny)
                if table[c, 0] == _KIND_CONE:
                    dx, dy, dz = _clamp_cone(dx, dy, dz, qx, qy, qz, table[c, 1], table[c, 2], dim)
                elif table[c, 0] == _KIND_HINGE and table[c, 12] == 0.0:
                    ax, ay, az, rx, ry, rz = _hinge_axes(table, c, -dx, -dy, -dz, rest)
                    low, high = table[c, 9], table[c, 10]
                    theta = _hinge_angle(-qx, -qy, -qz, ax, ay, az, rx, ry, rz, low, high)
                    if not low <= theta <= high:
                        end = low if abs(_wrap(theta - low)) <= abs(_wrap(theta - high)) else high
                        dx, dy, dz = _rotate(dx, dy, dz, ax, ay, az, theta - end)
            # keep the segment in its hinge's plane (caliko's forward pass)
            if table[j, 0] == _KIND_HINGE:
                ax, ay, az, rx, ry, rz = _hinge_axes(
                    table, j, directions[up, 0], directions[up, 1], directions[up, 2], rest
                )
                along = dx * ax + dy * ay + dz * az
                dx, dy, dz, _ = _unit(dx - along * ax, dy - along * ay, dz - along * az,
                                      -rx, -ry, -rz, 1e-12)  # fmt: skip
            if radii.shape[0] > 0:
                dx, dy, dz, _ = _deflect(x, y, z, dx, dy, dz, lengths[j], centres, radii, live, tiny,
                                         dim)  # fmt: skip
            sums[up, 0] += x + lengths[j] * dx
            sums[up, 1] += y + lengths[j] * dy
            sums[up, 2] += z + lengths[j] * dz
            counts[up] += 1
        # backward stage: the root back on its place, every branch outwards
        p[root, 0], p[root, 1], p[root, 2] = bx, by, bz
        for k in range(1, count):
            j = int(order[k])
            up = int(parents[j])
            qx, qy, qz = directions[up, 0], directions[up, 1], directions[up, 2]
            ax, ay, az = p[up, 0], p[up, 1], p[up, 2]
            dx, dy, dz, _ = _unit(p[j, 0] - ax, p[j, 1] - ay, p[j, 2] - az, qx, qy, qz, tiny)
            if has_limits:
                dx, dy, dz = _constrain(dx, dy, dz, qx, qy, qz, table, j, rest, tiny, dim)
            if radii.shape[0] > 0:
                dx, dy, dz, turned = _deflect(ax, ay, az, dx, dy, dz, lengths[j], centres, radii,
                                              live, tiny, dim)  # fmt: skip
                if turned and has_limits:
                    dx, dy, dz = _constrain(dx, dy, dz, qx, qy, qz, table, j, rest, tiny, dim)
            length = lengths[j]
            p[j, 0], p[j, 1], p[j, 2] = ax + length * dx, ay + length * dy, az + length * dz
            if length > tiny:
                directions[j, 0], directions[j, 1], directions[j, 2] = dx, dy, dz
            else:
                directions[j, 0], directions[j, 1], directions[j, 2] = qx, qy, qz
        worst = _tree_errors(p, goal, effectors, history, iteration)
        # Checked only where it matters, since it costs a pass of its own: a pose within tolerance, or a better one
        # where the last iterate may not be the one returned (live obstacles can leave it cutting one; after a
        # restart the best is returned). The backward stage keeps every limit on every iterate.
        track = any_live or not retry
        admissible = (worst <= tolerance or (track and worst < best_worst)) and _tree_admissible(
            p, parents, order, table, rest, tiny, has_limits, centres, radii, live
        )
        if admissible and worst < best_worst:
            best[:, :] = p
            best_worst = worst
        if admissible and worst <= tolerance:
            break
        change = 0.0
        for e in range(effectors.shape[0]):
            change = max(change, abs(history[iteration, e] - history[iteration - 1, e]))
        if change < stall:
            if stall_applies:
                stalled = True
                break
            if retry and iteration < max_iterations:
                # A free tree within reach at a fixed point of the centroid rule (a mirror-symmetric start keeps
                # it symmetric): go on once from every segment turned aside, another basin; then on to the cap.
                retry = False
                _tree_turn_aside(p, parents, order, lengths, tiny, dim)
    feasible = best_worst < np.inf
    if feasible and (
        not retry  # restarted: never worse than the best before or after
        or not _tree_admissible(
            p, parents, order, table, rest, tiny, has_limits, centres, radii, live
        )
    ):
        p[:, :] = best  # never an inadmissible last iterate where an admissible one was seen
    for e in range(effectors.shape[0]):
        k = int(effectors[e])
        x, y, z = p[k, 0] - goal[k, 0], p[k, 1] - goal[k, 1], p[k, 2] - goal[k, 2]
        final[e] = math.sqrt(x * x + y * y + z * z)
    _tree_statuses(p, parents, goal, effectors, lengths, centres, radii, live, tolerance, tiny,
                   final, stalled, holding or any_live, codes)  # fmt: skip
    if not feasible:
        codes[:] = _INFEASIBLE
    return iterations


@numba.njit(cache=True, error_model="numpy")
def _tree_extent(
    p: NDArray[np.float64], goal: NDArray[np.float64], effectors: NDArray[np.int64], root: int
) -> float:
    """The largest coordinate offset from the root of a joint or a target (m)."""
    extent = 0.0
    for j in range(p.shape[0]):
        for c in range(3):
            extent = max(extent, abs(p[j, c] - p[root, c]))
    for e in range(effectors.shape[0]):
        for c in range(3):
            extent = max(extent, abs(goal[int(effectors[e]), c] - p[root, c]))
    return extent


@numba.njit(cache=True, error_model="numpy")
def _tree_turn_aside(
    p: NDArray[np.float64], parents: NDArray[np.int64], order: NDArray[np.int64],
    lengths: NDArray[np.float64], tiny: float, dim: int,
) -> None:  # fmt: skip
    """Turn every segment of the pose ``p`` (in place, root fixed, lengths kept) by 1 to 2 rad about an axis
    across it, the angles and axes spread by the golden ratio over the breadth-first order (deterministic, and
    different for mirror-image branches)."""
    old = p.copy()
    golden = 0.6180339887498949
    for k in range(1, p.shape[0]):
        j = int(order[k])
        up = int(parents[j])
        dx, dy, dz, _ = _unit(old[j, 0] - old[up, 0], old[j, 1] - old[up, 1], old[j, 2] - old[up, 2],
                              0.0, 0.0, 1.0, tiny)  # fmt: skip
        spread = (k * golden) % 1.0
        angle = 1.0 + spread
        if dim == 2:
            ax, ay, az = 0.0, 0.0, 1.0
            angle = angle if k % 2 else -angle
        else:
            px, py, pz = _perpendicular(dx, dy, dz, 3)
            ax, ay, az = _rotate(
                px, py, pz, dx, dy, dz, 2.0 * math.pi * ((k * golden * golden) % 1.0)
            )
        dx, dy, dz = _rotate(dx, dy, dz, ax, ay, az, angle)
        p[j, 0] = p[up, 0] + lengths[j] * dx
        p[j, 1] = p[up, 1] + lengths[j] * dy
        p[j, 2] = p[up, 2] + lengths[j] * dz


@numba.njit(cache=True, error_model="numpy")
def _tree_admissible(
    p: NDArray[np.float64], parents: NDArray[np.int64], order: NDArray[np.int64],
    table: NDArray[np.float64], rest: NDArray[np.float64], tiny: float, has_limits: bool,
    centres: NDArray[np.float64], radii: NDArray[np.float64], live: NDArray[np.bool_],
) -> bool:  # fmt: skip
    """Whether the tree's pose keeps every joint limit (each segment against its parent's, the root's against
    ``rest``; zero-length segments have none and pass their parent's on) and cuts no live obstacle."""
    if not has_limits and radii.shape[0] == 0:
        return True
    count = p.shape[0]
    directions = np.empty((count, 3))
    root = int(order[0])
    directions[root, 0], directions[root, 1], directions[root, 2] = rest[0], rest[1], rest[2]
    for k in range(1, count):
        j = int(order[k])
        up = int(parents[j])
        qx, qy, qz = directions[up, 0], directions[up, 1], directions[up, 2]
        dx, dy, dz, norm = _unit(p[j, 0] - p[up, 0], p[j, 1] - p[up, 1], p[j, 2] - p[up, 2],
                                 qx, qy, qz, tiny)  # fmt: skip
        if norm <= tiny:
            directions[j, 0], directions[j, 1], directions[j, 2] = qx, qy, qz
            continue
        if has_limits and not _joint_ok(dx, dy, dz, qx, qy, qz, table, j, rest, tiny):
            return False
        directions[j, 0], directions[j, 1], directions[j, 2] = dx, dy, dz
        x, y, z = p[up, 0], p[up, 1], p[up, 2]
        sx, sy, sz = p[j, 0] - x, p[j, 1] - y, p[j, 2] - z
        seg2 = sx * sx + sy * sy + sz * sz
        for o in range(radii.shape[0]):
            if not live[o]:
                continue
            rx, ry, rz = centres[o, 0] - x, centres[o, 1] - y, centres[o, 2] - z
            t = min(max((rx * sx + ry * sy + rz * sz) / seg2, 0.0), 1.0)
            gx, gy, gz = rx - t * sx, ry - t * sy, rz - t * sz
            if gx * gx + gy * gy + gz * gz < radii[o] * radii[o]:
                return False
    return True


@numba.njit(cache=True, error_model="numpy")
def _tree_statuses(
    p: NDArray[np.float64], parents: NDArray[np.int64], goal: NDArray[np.float64],
    effectors: NDArray[np.int64], lengths: NDArray[np.float64], centres: NDArray[np.float64],
    radii: NDArray[np.float64], live: NDArray[np.bool_], tolerance: float, tiny: float,
    error: NDArray[np.float64], stalled: bool, held: bool, codes: NDArray[np.int64],
) -> None:  # fmt: skip
    """Each effector's status code (see :func:`_solve_tree_core`); ``held``: limits or live obstacles can hold the
    tree at a fixed point (else a stall is another effector's target out of reach: "unreachable")."""
    touching = False
    for j in range(p.shape[0]):
        up = int(parents[j])
        if up < 0 or radii.shape[0] == 0:
            continue
        x, y, z = p[up, 0], p[up, 1], p[up, 2]
        sx, sy, sz = p[j, 0] - x, p[j, 1] - y, p[j, 2] - z
        seg2 = sx * sx + sy * sy + sz * sz
        for k in range(radii.shape[0]):
            rx, ry, rz = centres[k, 0] - x, centres[k, 1] - y, centres[k, 2] - z
            t = min(max((rx * sx + ry * sy + rz * sz) / (seg2 if seg2 > 0.0 else 1.0), 0.0), 1.0)
            gx, gy, gz = rx - t * sx, ry - t * sy, rz - t * sz
            grown = radii[k] * (1.0 + _TOUCH)
            touching = touching or (live[k] and gx * gx + gy * gy + gz * gz < grown * grown)
    root = 0
    while parents[root] >= 0:
        root = int(parents[root])
    for e in range(effectors.shape[0]):
        key = int(effectors[e])
        reach, longest, j = 0.0, 0.0, key
        while parents[j] >= 0:
            reach += lengths[j]
            longest = max(longest, lengths[j])
            j = int(parents[j])
        inner = max(0.0, 2.0 * longest - reach)
        dx, dy, dz = goal[key, 0] - p[root, 0], goal[key, 1] - p[root, 1], goal[key, 2] - p[root, 2]
        distance = math.sqrt(dx * dx + dy * dy + dz * dz)
        inside = False
        for k in range(radii.shape[0]):
            ox = centres[k, 0] - goal[key, 0]
            oy = centres[k, 1] - goal[key, 1]
            oz = centres[k, 2] - goal[key, 2]
            inside = inside or (live[k] and ox * ox + oy * oy + oz * oz < radii[k] * radii[k])
        if error[e] <= tolerance:
            codes[e] = _REACHED
        elif distance > reach + tiny or distance < inner - tiny:
            codes[e] = _UNREACHABLE
        elif inside or touching:
            codes[e] = _BLOCKED
        else:
            codes[e] = (_LIMITED if held else _UNREACHABLE) if stalled else _MAX_ITERATIONS


@numba.njit(cache=True, error_model="numpy")
def _tree_errors(
    p: NDArray[np.float64], goal: NDArray[np.float64], effectors: NDArray[np.int64],
    history: NDArray[np.float64], row: int,
) -> float:  # fmt: skip
    """Write each effector's distance to its target into ``history[row]``; return the largest."""
    worst = 0.0
    for e in range(effectors.shape[0]):
        k = int(effectors[e])
        x, y, z = p[k, 0] - goal[k, 0], p[k, 1] - goal[k, 1], p[k, 2] - goal[k, 2]
        history[row, e] = math.sqrt(x * x + y * y + z * z)
        worst = max(worst, history[row, e])
    return worst
