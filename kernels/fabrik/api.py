"""The public chain functions: :func:`solve`, :func:`solve_batch`, :func:`ccd`, :func:`jacobian_dls`, the analytic
:func:`two_bone`, and helpers on poses. Arguments are checked here, once, and the compiled core trusts them.

Shapes: one chain is (n + 1, d) joints and a (d,) target, d = 2 or 3, metres; a batch leads with B. See
:mod:`kernels.fabrik` for the model and its sources.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from kernels import _checks
from kernels._checks import bounded_array, finite_number
from kernels._rows import run_rows
from kernels.fabrik.chain import (
    _BAD_JOINTS,
    _BAD_TARGET,
    _FAR_TARGET,
    _FARTHEST,
    _SOLVER_IDS,
    _SPAN,
    _UNSCALED,
    STATUSES,
    Solver,
    Status,
)
from kernels.fabrik.chain import _solve_one as _compiled_solve_one
from kernels.fabrik.chain import _solve_rows as _compiled_solve_rows
from kernels.fabrik.geometry import _LARGEST, _TINY
from kernels.fabrik.geometry import _perpendicular as _compiled_perpendicular
from kernels.fabrik.limits import _FREE_TABLE, _KIND_CONE, _TABLE_WIDTH, Constraint, _limit_table
from kernels.fabrik.limits import _limit_flags as _compiled_limit_flags
from kernels.fabrik.limits import _usage as _compiled_usage
from kernels.warming import Entry

# The compiled cores Python calls here: plain Python while the app's first start compiles them (kernels.warming).
_solve_one = Entry(_compiled_solve_one)
_solve_rows = Entry(_compiled_solve_rows)
_perpendicular = Entry(_compiled_perpendicular)
_limit_flags = Entry(_compiled_limit_flags)
_usage = Entry(_compiled_usage)

Obstacle = tuple[ArrayLike, float]
"""``(centre (d,) m, radius m)``: a circle in 2D, a sphere in 3D."""

_MAX_ITERATIONS_CAP = 100_000
"""Largest ``max_iterations`` accepted (each chain keeps an error history of that length)."""


def _solve_batch_rows(args: tuple[Any, ...]) -> None:
    """:func:`~kernels.fabrik.chain._solve_rows` over every row of a batch (``args[0]`` the (B, n + 1, 3) joints),
    shared among threads by :func:`kernels._rows.run_rows`: ``_solve_rows`` runs without the GIL, so no
    ``parallel=True`` core has to compile on the first start."""
    run_rows(_solve_rows, len(args[0]), *args)


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
    return _solve_single(
        "fabrik",
        joints,
        target,
        tolerance,
        max_iterations,
        cone_half_angle_rad,
        obstacles,
        root_direction,
        extrapolate,
        constraints,
    )


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
    points = bounded_array("targets", targets, _LARGEST)
    if points.shape != (batch, dim):
        raise ValueError(f"targets must have shape ({batch}, {dim}) to match joints, got {points.shape}")
    if not isinstance(solver, str) or solver not in _SOLVER_IDS:
        raise ValueError(f"solver must be one of 'fabrik', 'ccd', 'jacobian_dls', got {_checks.shown(solver)}")
    setup = _Setup.build(
        dim, tolerance, max_iterations, cone_half_angle_rad, obstacles, root_direction, _SOLVER_IDS[solver], extrapolate
    )
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
    if batch == 0:  # an empty batch is solved at once, as numpy reduces nothing (every argument still checked)
        return BatchSolution(
            joints=chains.copy(),
            iterations=iterations,
            error=error,
            status=np.array(STATUSES)[status],
            error_history=history,
        )
    check_reach_span(chains, points, "targets")
    scale, params, centres, radii = _to_unit_scale(p, goal, setup)
    args = (
        p,
        goal,
        params,
        setup.flags,
        setup.root_direction,
        centres,
        radii,
        out_p,
        history,
        iterations,
        status,
        error,
        setup.table,
    )
    _solve_batch_rows(args)
    if scale != 1.0:
        out_p *= scale
        history *= scale
        error *= scale
    still = iterations == 0  # a start returned as it stands: its own coordinates, not their round trip about the root
    out_p[still, :, :dim] = chains[still]
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
    return _solve_single(
        "ccd",
        joints,
        target,
        tolerance,
        max_iterations,
        cone_half_angle_rad,
        obstacles,
        root_direction,
        False,
        constraints,
    )


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
    return _solve_single(
        "jacobian_dls",
        joints,
        target,
        tolerance,
        max_iterations,
        cone_half_angle_rad,
        obstacles,
        root_direction,
        False,
        constraints,
    )


def limit_usage(
    joints: ArrayLike, constraints: Sequence[Constraint], root_direction: ArrayLike | None = None
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


def two_bone(
    root: ArrayLike, upper_length: float, lower_length: float, target: ArrayLike, bend_direction: ArrayLike
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
            counts; if it has none, a fixed perpendicular is used). For a target on the root, where there is no
            root–target line, the folded chain lies along it with the elbow toward it.

    Returns:
        (3, d) root, elbow and end positions (m).

    Raises:
        ValueError: naming the argument, for non-finite values, wrong shapes or negative lengths.
    """
    p_root = bounded_array("root", root, _LARGEST)
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
    on_root = distance <= _TINY * scale
    axis = offset / distance if not on_root else _toward(bend, dim)
    side = bend - float(bend @ axis) * axis
    side_norm = float(np.linalg.norm(side))
    side = side / side_norm if side_norm > _TINY else _perpendicular_numpy(axis)

    reach = min(max(distance, abs(upper - lower)), upper + lower)
    if upper <= _TINY * scale or reach <= _TINY * scale:
        cos_alpha = 1.0 if reach >= upper else -1.0
    else:
        cos_alpha = (upper**2 + reach**2 - lower**2) / (2.0 * upper * reach)
    cos_alpha = min(1.0, max(-1.0, cos_alpha))
    if on_root and cos_alpha < 0.0:
        # No root–target line: the folded chain lies on the line of bend_direction, its elbow toward it.
        axis = -axis  # the elbow, upper·cos α·axis with cos α = −1, then lies toward bend_direction
    sin_alpha = math.sqrt(max(0.0, 1.0 - cos_alpha**2))
    elbow = upper * (cos_alpha * axis + sin_alpha * side)
    end_offset = reach * axis - elbow
    end_norm = float(np.linalg.norm(end_offset))
    direction = end_offset / end_norm if end_norm > _TINY * scale else axis
    return np.stack([p_root, p_root + unit * elbow, p_root + unit * (elbow + lower * direction)])


def link_lengths(joints: ArrayLike) -> NDArray[np.float64]:
    """Link lengths (m): (n,) for (n + 1, d) joints, (B, n) for (B, n + 1, d).

    Raises:
        ValueError: ``joints`` not finite real numbers of magnitude ≤ 1e150 m, or not of shape (n + 1, d) or
            (B, n + 1, d) with n ≥ 1 and d = 2 or 3; the message names ``joints``.
    """
    points = bounded_array("joints", joints, _LARGEST)
    if points.ndim not in (2, 3) or points.shape[-1] not in (2, 3):
        raise ValueError(f"joints must have shape (n + 1, d) or (B, n + 1, d) with d = 2 or 3, got {points.shape}")
    points = _check_joints("joints", points, batched=points.ndim == 3)  # and n ≥ 1
    segments = np.diff(points, axis=-2)
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
    links = bounded_array("lengths", lengths, _LARGEST)
    if links.ndim != 1 or links.shape[0] < 1 or not bool((links >= 0.0).all()):
        raise ValueError(f"lengths must be a non-empty (n,) array of lengths ≥ 0, got {_checks.shown(lengths)}")
    total = float(links.sum())
    return max(0.0, 2.0 * float(links.max()) - total), total


def _check_joints(name: str, value: ArrayLike, *, batched: bool) -> NDArray[np.float64]:
    array = bounded_array(name, value, _LARGEST)
    want = 3 if batched else 2
    shape = "(B, n + 1, d)" if batched else "(n + 1, d)"
    if array.ndim != want or array.shape[-1] not in (2, 3):
        raise ValueError(f"{name} must have shape {shape} with d = 2 or 3, got {array.shape}")
    if array.shape[-2] < 2:
        raise ValueError(f"{name} must hold at least two joints (n ≥ 1 link), got {array.shape}")
    return array


def _check_vector(name: str, value: ArrayLike, dim: int) -> NDArray[np.float64]:
    array = bounded_array(name, value, _LARGEST)
    if array.shape != (dim,):
        raise ValueError(f"{name} must have shape ({dim},), got {array.shape}")
    return array


def _check_length(name: str, value: float) -> float:
    number = _checks.finite_number(name, value)  # a scalar: "a finite number", not "an array" (True, None, [1.0])
    if not 0.0 <= number <= _LARGEST:
        raise ValueError(f"{name} must be a finite number in [0, {_LARGEST:g}], got {_checks.shown(value)}")
    return number


def _root_direction(value: ArrayLike | None, dim: int) -> NDArray[np.float64]:
    if value is None:
        axis = np.zeros(dim)
        axis[-1] = 1.0
        return axis
    return _checks.direction("root_direction", _check_vector("root_direction", value, dim), dim)


def _status_literal(text: str) -> Status:
    for status in STATUSES:
        if status == text:
            return status
    raise ValueError(f"unknown status {_checks.shown(text)}")


def _perpendicular_numpy(axis: NDArray[np.float64]) -> NDArray[np.float64]:
    """A fixed unit vector perpendicular to the unit ``axis`` (d,)."""
    if axis.shape[0] == 2:
        return np.array([-axis[1], axis[0]])
    x, y, z = _perpendicular(float(axis[0]), float(axis[1]), float(axis[2]), 3)
    return np.array([x, y, z])


def _toward(bend: NDArray[np.float64], dim: int) -> NDArray[np.float64]:
    """``bend`` as a unit axis (or +last axis where it is zero): the line a chain folds on for a target on the root."""
    norm = float(np.linalg.norm(bend))
    if norm <= _TINY:
        axis = np.zeros(dim)
        axis[-1] = 1.0
        return axis
    return bend / norm


_F64 = NDArray[np.float64]
_SingleArgs = tuple[_F64, _F64, float, _F64, NDArray[np.int64], _F64, _F64, _F64, _F64]
"""The arguments of :func:`~kernels.fabrik.chain._solve_one`, in order: see :meth:`_Setup.single_args`."""


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

    def single_args(self, chain: ArrayLike, point: ArrayLike) -> _SingleArgs:
        """The arguments of :func:`~kernels.fabrik.chain._solve_one` for one shape-checked chain (n + 1, d) and
        target (d,): what :func:`_solve_single` calls it with, and what :func:`compiled_single_solve` times."""
        return (
            np.ascontiguousarray(chain),
            np.ascontiguousarray(point),
            _LARGEST,
            self.params,
            self.flags,
            self.root_direction,
            self.centres,
            self.radii,
            self.table,
        )

    def constrained(self, constraints: Sequence[Constraint] | None, n: int, dim: int, cone: float | None) -> _Setup:
        """These options with per-segment ``constraints`` (checked) in place of the uniform cone."""
        if constraints is None:
            return self
        if cone is not None:
            raise ValueError("constraints and cone_half_angle_rad are alternatives: give one of them, not both")
        table = _limit_table(constraints, n, dim, "constraints", segment_offset=0)
        has_limits, holding = _limit_flags(table)
        cones = table[table[:, 0] == _KIND_CONE, 1]
        cos_phi = float(cones.max()) if cones.size else -1.0  # the tightest cone bounds the unbending arc
        params = self.params.copy()
        params[1], params[2] = cos_phi, math.sqrt(max(0.0, 1.0 - cos_phi * cos_phi))
        flags = self.flags.copy()
        flags[4], flags[5] = int(has_limits), int(holding)
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
            options = _options(dim, tolerance, max_iterations, cone_half_angle_rad, solver, extrapolate)
        except TypeError:  # an unhashable argument: check it without the cache (and raise ValueError)
            options = _options.__wrapped__(dim, tolerance, max_iterations, cone_half_angle_rad, solver, extrapolate)
        # an array or an iterator: its items are the obstacles
        if not isinstance(obstacles, (list, tuple)):
            try:
                obstacles = list(obstacles)
            except TypeError as error:
                raise ValueError(
                    f"obstacles must be a sequence of (centre, radius), got {_checks.shown(obstacles)}"
                ) from error
        if root_direction is None and not obstacles:
            return options
        count = len(obstacles)
        centres, radii = np.zeros((count, 3)), np.empty(count)
        for k, obstacle in enumerate(obstacles):
            try:
                centre, radius = obstacle
            except (TypeError, ValueError) as error:
                raise ValueError(f"obstacles[{k}] must be (centre, radius), got {_checks.shown(obstacle)}") from error
            centres[k, :dim] = _check_vector(f"obstacles[{k}] centre", centre, dim)
            radii[k] = finite_number(f"obstacles[{k}] radius", radius)
            if not 0.0 < radii[k] <= _LARGEST:
                raise ValueError(
                    f"obstacles[{k}] radius must be a finite number in (0, {_LARGEST:g}], got {_checks.shown(radius)}"
                )
        rest = options.root_direction
        if root_direction is not None:
            rest = np.zeros(3)
            rest[:dim] = _root_direction(root_direction, dim)
        return dataclasses.replace(options, root_direction=rest, centres=centres, radii=radii)


@functools.lru_cache(maxsize=64, typed=True)
def _options(
    dim: int, tolerance: float, max_iterations: int, cone_half_angle_rad: float | None, solver: int, extrapolate: bool
) -> _Setup:
    """The checked scalar options, without obstacles, on the default root direction; cached, since a dragged
    chain asks for the same ones every frame (the compiled core never writes to them)."""
    tol = finite_number("tolerance", tolerance)
    if tol < 0.0:
        raise ValueError(f"tolerance must be a finite number ≥ 0, got {_checks.shown(tolerance)}")
    if isinstance(max_iterations, bool) or not isinstance(max_iterations, (int, np.integer)):
        raise ValueError(f"max_iterations must be an integer, got {_checks.shown(max_iterations)}")
    if not 1 <= max_iterations <= _MAX_ITERATIONS_CAP:
        raise ValueError(f"max_iterations must be in [1, {_MAX_ITERATIONS_CAP}], got {max_iterations}")
    cos_phi, sin_phi, has_limits = -1.0, 0.0, 0
    if cone_half_angle_rad is not None:
        phi = finite_number("cone_half_angle_rad", cone_half_angle_rad)
        if not 0.0 <= phi <= math.pi:
            raise ValueError(f"cone_half_angle_rad must be in [0, π], got {_checks.shown(cone_half_angle_rad)}")
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
            [int(max_iterations), dim, solver, int(_checks.flag("extrapolate", extrapolate)), has_limits, has_limits],
            dtype=np.int64,
        ),
        root_direction=rest,
        centres=np.zeros((0, 3)),
        radii=np.zeros(0),
    )


def check_reach_span(joints: NDArray[np.float64], targets: NDArray[np.float64], name: str) -> None:
    """``ValueError`` naming ``name`` (and the row, for a batch) when a target lies more than :data:`_FARTHEST` times
    its chain's length from the root, or the chain lies more than that from the origin; or, for a batch, when its
    chains (targets included) differ in size by more than :data:`_SPAN`.

    ``joints`` (B, n + 1, d) and ``targets`` (B, d), finite and checked. Outside these spans the links fall below
    the rounding of the problem's scale and the solve is no longer the algorithm's: FABRIK collapsed a 0.5 m chain to
    its root for a target 1e200 m away; a chain 1e15 m from the origin had its links changed 8 % by the rounding of
    its coordinates; and a batch is solved in units of one power of 2 near its largest chain (see
    :func:`_to_unit_scale`), so a row 1e200 times smaller lost its links (DLS already at 1e60).
    """
    root = joints[:, :1, :]
    size = np.maximum(np.abs(joints - root).max(axis=(1, 2)), np.abs(targets - root[:, 0]).max(axis=1))
    total = _norms(np.diff(joints, axis=1)).sum(axis=1)
    reach = _norms(targets - root[:, 0])
    origin = np.maximum(np.abs(joints).max(axis=(1, 2)), np.abs(targets).max(axis=1))
    single = name == "target"
    for measure, what in ((reach, "target"), (origin, "origin")):
        far = np.flatnonzero((total > 0.0) & (measure / _FARTHEST > total))
        if not far.size:
            continue
        k = int(far[0])
        if what == "target":
            raise ValueError(
                f"{name}{'' if single else f'[{k}]'} is {reach[k]:.3g} m from the root, more than {_FARTHEST:g} "
                f"times the chain's length ({total[k]:.3g} m): too far to solve; a target nearer on the same line "
                f"gives the same pose"
            )
        raise ValueError(
            f"joints{'' if single else f'[{k}]'} and the target lie {origin[k]:.3g} m from the origin, more than "
            f"{_FARTHEST:g} times the chain's length ({total[k]:.3g} m): the rounding of the coordinates alone "
            f"changes its links; solve it with the origin nearer"
        )
    sized = size[size > 0.0]
    if sized.size and sized.max() / _SPAN > sized.min():
        small, large = int(np.flatnonzero(size == sized.min())[0]), int(np.flatnonzero(size == sized.max())[0])
        raise ValueError(
            f"row {small} (joints and target within {size[small]:.3g} m of its root) and row {large} (within "
            f"{size[large]:.3g} m) differ in size by more than {_SPAN:g} times: they cannot share a batch; solve "
            f"them in separate calls"
        )


def _norms(vectors: NDArray[np.float64]) -> NDArray[np.float64]:
    """Euclidean norms over the last axis (2 or 3 components), by ``hypot``: no square overflows or underflows."""
    result = np.hypot(vectors[..., 0], vectors[..., 1])
    return np.hypot(result, vectors[..., 2]) if vectors.shape[-1] == 3 else result


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


def compiled_single_solve(
    joints: NDArray[np.float64], target: NDArray[np.float64]
) -> tuple[Callable[..., object], tuple[object, ...]]:
    """The compiled call one default :func:`solve` makes, and its prepared arguments, for timing the core alone.

    ``joints`` (n + 1, d) and ``target`` (d,) float64 arrays, d = 2 or 3 (m); default options (no limits, no
    obstacles). ``core(*args)`` runs exactly the compiled work of ``solve(joints, target)``, so a benchmark can
    print how much the Python around it costs. Raises ``ValueError`` naming a bad argument, as :func:`solve` does.
    """
    chain = _check_joints("joints", joints, batched=False)
    point = _check_vector("target", target, chain.shape[1])
    setup = _Setup.build(chain.shape[1], 1e-3, 50, None, (), None, _SOLVER_IDS["fabrik"], True)
    return _compiled_solve_one, setup.single_args(chain, point)


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
    """One chain: checked here, solved by the same compiled core as every chain of a batch.

    The common case, float64 arrays of the right shapes, goes straight to one compiled call that also scans the
    numbers (finite, magnitude ≤ 1e300); anything else, or a refused number, goes through the checks of
    :mod:`kernels._checks` first, which name the argument in their error."""
    chain = joints
    if not (
        type(chain) is np.ndarray
        and chain.dtype == np.float64
        and chain.ndim == 2
        and chain.shape[1] in (2, 3)
        and chain.shape[0] >= 2
    ):
        chain = _check_joints("joints", joints, batched=False)
    count, dim = chain.shape
    point = target
    if not (type(point) is np.ndarray and point.dtype == np.float64 and point.shape == (dim,)):
        point = _check_vector("target", target, dim)
    setup = _Setup.build(
        dim, tolerance, max_iterations, cone_half_angle_rad, obstacles, root_direction, _SOLVER_IDS[solver], extrapolate
    )
    setup = setup.constrained(constraints, count - 1, dim, cone_half_angle_rad)
    code, out, history, used, status, error = _solve_one(*setup.single_args(chain, point))
    if code == _BAD_JOINTS:
        _check_joints("joints", joints, batched=False)  # raises, naming it
    if code == _BAD_TARGET:
        _check_vector("target", target, dim)
    if code == _FAR_TARGET:
        check_reach_span(chain[None], point[None], "target")  # raises, naming it
        # The compiled estimate and this check round differently in the last ulps at the limit: solve it as a batch
        # of one, which this check passed (never the empty arrays of a refused call).
        return solve_batch(
            chain[None],
            point[None],
            tolerance=tolerance,
            max_iterations=max_iterations,
            cone_half_angle_rad=cone_half_angle_rad,
            obstacles=obstacles,
            root_direction=root_direction,
            constraints=constraints,
            solver=solver,
            extrapolate=extrapolate,
        )[0]
    # The frozen dataclass's __init__ sets each field through object.__setattr__ (~0.8 µs, a third of the Python
    # around a small chain's core); filling the instance's dict makes the same object in a quarter of that.
    solution = object.__new__(Solution)
    solution.__dict__.update(joints=out, iterations=used, error=error, status=STATUSES[status], error_history=history)
    return solution
