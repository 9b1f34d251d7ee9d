"""Inverse kinematics of a chain of rigid links: FABRIK, and the solvers it is compared with.

A chain is ``n + 1`` joint positions ``p_0 … p_n`` in 2D or 3D (``d`` = 2 or 3, metres); ``p_0`` is the fixed root,
``p_n`` the end effector. Link lengths ``L_i = |p_{i+1} − p_i|`` come from the joints given and never change.
Batches lead: a batch of chains is ``(B, n + 1, d)`` and its targets ``(B, d)``. Internally the joints are stored
``(n + 1, d, B)`` so that one joint of every chain is a contiguous block and the passes vectorise over ``B``.

Model and method:

* FABRIK (Aristidou & Lasenby 2011, "FABRIK: a fast, iterative solver for the Inverse Kinematics problem",
  Graphical Models 73(5)): a forward pass sets ``p_n`` on the target and re-places every joint on the line to the
  joint before it at the link's length; a backward pass sets ``p_0`` back on the root and does the same outwards.
  It stops when ``|p_n − target| < tolerance`` or after ``max_iterations``.
* Reach: a target at distance ``r`` from the root is reachable only if ``max(0, 2·max L − ΣL) ≤ r ≤ ΣL``. Outside
  that annulus the closest pose is returned at once (stretched straight toward the target, or folded back onto the
  inner boundary), as the paper does for unreachable targets, unless joint limits or obstacles forbid that pose.
* Joint limits: each segment stays within a cone of half-angle ``φ`` around the previous segment's direction (the
  first segment around ``root_direction``). The forward pass clamps each segment against the one placed just before
  it, the backward pass against its predecessor, so the pose every iteration ends on satisfies every limit
  (as Aristidou & Lasenby 2011 apply constraints inside the passes, here with a symmetric cone; in 2D the cone is
  the angle range ``[−φ, φ]``).
* Obstacles: circles (2D) or spheres (3D). Whenever a pass would place a segment through one, the segment is turned
  about its anchor, by the least angle, until it only touches it (tangent, or its far end on the surface). The solver
  keeps the best collision-free pose it has seen and returns that one; "blocked" says that the chain rests against an
  obstacle without reaching the target. Obstacles that contain the root cannot be avoided and are ignored. If no
  collision-free pose was ever seen (the starting pose already cut an obstacle and no iterate cleared it), the last
  pose is returned, still "blocked".
* Extrapolation (our addition, not in the paper): near cone limits FABRIK converges linearly and slowly (the
  error shrinks by 0.8–0.95 per iteration, tens of iterations). Where the error ratio ``r`` of the last iteration
  is in [0.5, 1), the joints are moved on along their last step by ``r / (1 − r)`` steps (the rest of the
  geometric series, Aitken-style, at most 8) before the next passes, which then re-impose lengths, limits and
  obstacles; a chain whose error grew after an extrapolation is not extrapolated again. A warm-started drag near
  the limits takes 3 iterations at p95 instead of 31. Only FABRIK is extrapolated: ``ccd`` and ``jacobian_dls``
  run as published, so iteration counts compared with the paper's Table 1 are this FABRIK's, not the paper's.
* Stopping: at the tolerance, at ``max_iterations``, or at a fixed point, when the error changes by less than 0.1 %
  of the tolerance in an iteration (caliko's "minimum change" rule); a fixed point short of the target is
  "unreachable" (with joint limits: outside the reach the limits allow) or "blocked".
* Degenerate input never makes NaN: a zero-length link or coincident joints keep the last defined direction, a
  straight chain whose target lies on its own axis is first bent into a gentle arc (a straight chain otherwise never
  bends, a known FABRIK complaint), and a target on the root picks the root direction.
* ``two_bone`` is the analytic law-of-cosines solution for two links; ``ccd`` (cyclic coordinate descent, Wang &
  Chen 1991) and ``jacobian_dls`` (damped least squares, Wampler 1986; Buss 2004) are the methods the FABRIK paper
  compared with (its Table 1: 10 joints, FABRIK 15.5 iterations, CCD 26.3, DLS 999). They take the same arguments,
  honour the same limits and obstacles by projecting every iterate with the constrained backward pass, and return
  the same result.
* Speed: a batch runs each pass as a handful of numpy operations on (d, B) blocks. A single chain (B = 1) runs its
  FABRIK passes on Python floats instead, in the same operation order, so it gives the same bits several times
  faster than numpy calls on arrays of one; :func:`solve` also runs its set-up, collision and cone checks and
  bookkeeping that way (its own driver, same bits, iterations and status as a batch of one), handing only the rare
  cases (a target outside the annulus, a zero-length link, a straight chain aimed along itself) to the batch driver.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

Status = Literal["reached", "unreachable", "max_iterations", "blocked"]
"""Why a solve stopped: target within tolerance; target outside the chain's reach (or outside what the joint limits
allow: the solver reached a fixed point); iteration cap; resting against an obstacle short of the target."""
STATUSES: tuple[Status, ...] = ("reached", "unreachable", "max_iterations", "blocked")
_REACHED, _UNREACHABLE, _MAX_ITERATIONS, _BLOCKED = range(4)

Solver = Literal["fabrik", "ccd", "jacobian_dls"]
"""The iterative methods; they share arguments, constraints and result."""

Obstacle = tuple[ArrayLike, float]
"""``(centre (d,) m, radius m)``: a circle in 2D, a sphere in 3D."""

_TINY = 1e-12
"""Relative length below which a vector has no direction (times the chain's scale)."""
_CLEARANCE = 1e-6
"""Segments are turned to clear an obstacle by this fraction of its radius, so rounding never leaves them inside."""
_STALL = 1e-3
"""A chain whose end-effector error changed by less than this fraction of the tolerance in an iteration is at a
fixed point (caliko's "minimum change" rule)."""
_EXTRAPOLATION_CAP = 8.0
"""Most last-steps a FABRIK iterate is moved on by (see :func:`_extrapolate`): enough for an error ratio of 0.89."""
_EXTRAPOLATION_MIN_RATIO = 0.5
"""Error ratio per iteration below which FABRIK iterates are left as they are (see :func:`_extrapolate`)."""
_DLS_DAMPING = 0.1
"""Damping of the DLS step, times the mean link length (Buss 2004 suggests λ of the order of the link size)."""


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
    """(iterations + 1,) end-effector distance before the first iteration and after each one (m)."""


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
    extrapolate: bool = True,
) -> Solution:
    """Solve one chain with FABRIK.

    Args:
        joints: (n + 1, d) starting joint positions (m), d = 2 or 3, n ≥ 1; ``joints[0]`` is the fixed root.
        target: (d,) target of the end effector (m).
        tolerance: stop when the end effector is closer than this to the target (m), ≥ 0.
        max_iterations: iteration cap, ≥ 1.
        cone_half_angle_rad: joint limit, in [0, π]: the angle between consecutive segments (and between the
            first segment and ``root_direction``) never exceeds it. None: no limits.
        obstacles: circles (2D) or spheres (3D) as ``(centre (d,), radius)`` no segment may pass through.
        root_direction: (d,) rest direction of the root, the axis of the first segment's cone. Default: +y in 2D
            (the plane's up), +z in 3D.
        extrapolate: move slowly converging iterates on along their last step (see :func:`_extrapolate`); False
            gives plain FABRIK as the paper writes it.

    Returns:
        The :class:`Solution`.

    Raises:
        ValueError: naming the argument, for non-finite values, wrong shapes, n < 1, a negative tolerance, a
            half-angle outside [0, π], a non-positive radius or max_iterations < 1.
    """
    chain = _check_joints("joints", joints, batched=False)
    point = _check_vector("target", target, chain.shape[1])
    setup = _Setup.build(
        dim=chain.shape[1],
        tolerance=tolerance,
        max_iterations=max_iterations,
        cone_half_angle_rad=cone_half_angle_rad,
        obstacles=obstacles,
        root_direction=root_direction,
    )
    return _run_one(chain, point, setup, extrapolate=extrapolate)


def solve_batch(
    joints: ArrayLike,
    targets: ArrayLike,
    *,
    tolerance: float = 1e-3,
    max_iterations: int = 50,
    cone_half_angle_rad: float | None = None,
    obstacles: Sequence[Obstacle] = (),
    root_direction: ArrayLike | None = None,
    solver: Solver = "fabrik",
    extrapolate: bool = True,
) -> BatchSolution:
    """Solve B chains at once, vectorised over the batch; each chain stops on its own.

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

    Returns:
        The :class:`BatchSolution`; ``result[i]`` is chain i's :class:`Solution`.

    Raises:
        ValueError: as :func:`solve`, and for a batch size mismatch or an unknown solver.
    """
    chains = _check_joints("joints", joints, batched=True)
    batch, _, dim = chains.shape
    points = np.asarray(_finite_array("targets", targets), dtype=np.float64)
    if points.shape != (batch, dim):
        raise ValueError(
            f"targets must have shape ({batch}, {dim}) to match joints, got {points.shape}"
        )
    setup = _Setup.build(
        dim=dim,
        tolerance=tolerance,
        max_iterations=max_iterations,
        cone_half_angle_rad=cone_half_angle_rad,
        obstacles=obstacles,
        root_direction=root_direction,
    )
    match solver:
        case "fabrik":
            step, shortcut = _fabrik_step, True
        case "ccd":
            step, shortcut = _ccd_step, False
        case "jacobian_dls":
            step, shortcut = _dls_step, False
        case _:
            raise ValueError(
                f"solver must be one of 'fabrik', 'ccd', 'jacobian_dls', got {solver!r}"
            )
    return _run(
        chains, points, setup, step, shortcut=shortcut, extrapolate=shortcut and extrapolate
    )


def _solve_one_by_batch(
    solver: Solver,
    joints: ArrayLike,
    target: ArrayLike,
    tolerance: float,
    max_iterations: int,
    cone_half_angle_rad: float | None,
    obstacles: Sequence[Obstacle],
    root_direction: ArrayLike | None,
) -> Solution:
    """One chain through :func:`solve_batch` (the comparison solvers have no single-chain fast path)."""
    chain = _check_joints("joints", joints, batched=False)
    point = _check_vector("target", target, chain.shape[1])
    return solve_batch(
        chain[None],
        point[None],
        tolerance=tolerance,
        max_iterations=max_iterations,
        cone_half_angle_rad=cone_half_angle_rad,
        obstacles=obstacles,
        root_direction=root_direction,
        solver=solver,
    )[0]


def ccd(
    joints: ArrayLike,
    target: ArrayLike,
    *,
    tolerance: float = 1e-3,
    max_iterations: int = 50,
    cone_half_angle_rad: float | None = None,
    obstacles: Sequence[Obstacle] = (),
    root_direction: ArrayLike | None = None,
) -> Solution:
    """Cyclic coordinate descent: one iteration turns each joint, end to root, to point the end at the target.

    Arguments, result and errors are those of :func:`solve`.
    """
    return _solve_one_by_batch(
        "ccd",
        joints,
        target,
        tolerance,
        max_iterations,
        cone_half_angle_rad,
        obstacles,
        root_direction,
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
) -> Solution:
    """Damped-least-squares Jacobian IK: ``Δθ = Jᵀ(JJᵀ + λ²I)⁻¹e`` with ball joints (3D) or hinges (2D).

    Arguments, result and errors are those of :func:`solve`.
    """
    return _solve_one_by_batch(
        "jacobian_dls",
        joints,
        target,
        tolerance,
        max_iterations,
        cone_half_angle_rad,
        obstacles,
        root_direction,
    )


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
    distance = float(np.linalg.norm(offset))
    scale = max(upper + lower, distance, 1.0)
    axis = offset / distance if distance > _TINY * scale else _fallback_axis(bend, dim)
    side = bend - float(bend @ axis) * axis
    side_norm = float(np.linalg.norm(side))
    side = side / side_norm if side_norm > _TINY else _perpendicular(axis[:, None])[:, 0]

    reach = min(max(distance, abs(upper - lower)), upper + lower)
    if upper <= _TINY * scale or reach <= _TINY * scale:
        cos_alpha = 1.0 if reach >= upper else -1.0
    else:
        cos_alpha = (upper**2 + reach**2 - lower**2) / (2.0 * upper * reach)
    cos_alpha = min(1.0, max(-1.0, cos_alpha))
    sin_alpha = math.sqrt(max(0.0, 1.0 - cos_alpha**2))
    elbow = p_root + upper * (cos_alpha * axis + sin_alpha * side)
    end_offset = p_root + reach * axis - elbow
    end_norm = float(np.linalg.norm(end_offset))
    direction = end_offset / end_norm if end_norm > _TINY * scale else axis
    return np.stack([p_root, elbow, elbow + lower * direction])


def link_lengths(joints: ArrayLike) -> NDArray[np.float64]:
    """Link lengths (m): (n,) for (n + 1, d) joints, (B, n) for (B, n + 1, d)."""
    chain = np.asarray(joints, dtype=np.float64)
    return np.linalg.norm(np.diff(chain, axis=-2), axis=-1)


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
    scale = max(float(np.add.reduce(np.linalg.norm(segments, axis=1))), 1.0)
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
    """``(inner, outer)`` radii (m) of the annulus the end effector can reach: ``max(0, 2·max L − ΣL)`` and ``ΣL``."""
    links = np.asarray(lengths, dtype=np.float64)
    total = float(links.sum())
    return max(0.0, 2.0 * float(links.max()) - total), total


# ================================================================================================ checks
def _finite_array(name: str, value: ArrayLike) -> NDArray[np.float64]:
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise ValueError(f"{name} must be an array of numbers, got {value!r}") from error
    if not np.isfinite(array).all():
        raise ValueError(f"{name} must be finite, got {value!r}")
    return array


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
    norm = float(np.linalg.norm(axis))
    if norm <= _TINY:
        raise ValueError(f"root_direction must be non-zero, got {value!r}")
    return axis / norm


def _status_literal(text: str) -> Status:
    for status in STATUSES:
        if status == text:
            return status
    raise ValueError(f"unknown status {text!r}")


# ================================================================================================ set-up
@dataclasses.dataclass(frozen=True)
class _Setup:
    """Checked options shared by every chain of a batch."""

    dim: int
    tolerance: float
    max_iterations: int
    limits: tuple[float, float] | None
    """(cos φ, sin φ) of the cone half-angle, or None."""
    root_direction: NDArray[np.float64]
    """(d, 1) unit rest direction of the root."""
    centres: NDArray[np.float64]
    """(K, d, 1) obstacle centres (m)."""
    radii: NDArray[np.float64]
    """(K, 1) obstacle radii (m)."""

    @staticmethod
    def build(
        *,
        dim: int,
        tolerance: float,
        max_iterations: int,
        cone_half_angle_rad: float | None,
        obstacles: Sequence[Obstacle],
        root_direction: ArrayLike | None,
    ) -> _Setup:
        tol = _finite_array("tolerance", tolerance)
        if tol.shape != () or float(tol) < 0.0:
            raise ValueError(f"tolerance must be a finite number ≥ 0, got {tolerance!r}")
        if isinstance(max_iterations, bool) or not isinstance(max_iterations, (int, np.integer)):
            raise ValueError(f"max_iterations must be an integer, got {max_iterations!r}")
        if max_iterations < 1:
            raise ValueError(f"max_iterations must be ≥ 1, got {max_iterations}")
        limits = None
        if cone_half_angle_rad is not None:
            phi = _finite_array("cone_half_angle_rad", cone_half_angle_rad)
            if phi.shape != () or not 0.0 <= float(phi) <= math.pi:
                raise ValueError(
                    f"cone_half_angle_rad must be in [0, π], got {cone_half_angle_rad!r}"
                )
            if float(phi) < math.pi:
                limits = (math.cos(float(phi)), math.sin(float(phi)))
        centres, radii = [], []
        for k, obstacle in enumerate(obstacles):
            try:
                centre, radius = obstacle
            except (TypeError, ValueError) as error:
                raise ValueError(
                    f"obstacles[{k}] must be (centre, radius), got {obstacle!r}"
                ) from error
            centres.append(_check_vector(f"obstacles[{k}] centre", centre, dim))
            r = _finite_array(f"obstacles[{k}] radius", radius)
            if r.shape != () or float(r) <= 0.0:
                raise ValueError(
                    f"obstacles[{k}] radius must be a finite number > 0, got {radius!r}"
                )
            radii.append(float(r))
        return _Setup(
            dim=dim,
            tolerance=float(tol),
            max_iterations=int(max_iterations),
            limits=limits,
            root_direction=_root_direction(root_direction, dim)[:, None],
            centres=np.array(centres, dtype=np.float64).reshape(len(centres), dim, 1),
            radii=np.array(radii, dtype=np.float64).reshape(len(radii), 1),
        )


@dataclasses.dataclass
class _Chains:
    """The active chains of a batch, laid out joint-major: one joint of every chain is a contiguous (d, B) block."""

    p: NDArray[np.float64]
    """(n + 1, d, B) joints (m)."""
    target: NDArray[np.float64]
    """(d, B) targets (m)."""
    lengths: NDArray[np.float64]
    """(n, B) link lengths (m)."""
    tiny: NDArray[np.float64]
    """(B,) length below which a vector has no direction (m)."""
    obstacle_live: NDArray[np.bool_]
    """(K, B) obstacles this chain avoids (those that do not contain its root)."""
    has_zero_link: bool

    def take(self, keep: NDArray[np.bool_]) -> _Chains:
        return _Chains(
            p=self.p[:, :, keep],
            target=self.target[:, keep],
            lengths=self.lengths[:, keep],
            tiny=self.tiny[keep],
            obstacle_live=self.obstacle_live[:, keep],
            has_zero_link=self.has_zero_link,
        )


# ================================================================================================ vector helpers
def _dot_d(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """Dot product over the d axis (−2) of broadcastable (…, d, B) arrays: (…, B).

    Written out rather than reduced: numpy's reduction over a middle axis is slow, and this is the order (x + y) + z
    that both the reduction and the one-chain path use, so every path gives the same bits.
    """
    total = a[..., 0, :] * b[..., 0, :] + a[..., 1, :] * b[..., 1, :]
    if a.shape[-2] == 3:
        total = total + a[..., 2, :] * b[..., 2, :]
    return total


def _norm(v: NDArray[np.float64]) -> NDArray[np.float64]:
    """(…, d, B) → (…, B) Euclidean norm over the d axis."""
    return np.sqrt(_dot_d(v, v))


def _unit(
    v: NDArray[np.float64], fallback: NDArray[np.float64], tiny: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(d, B) unit vectors of ``v``, ``fallback`` where ``|v| ≤ tiny``; and the norms (B,)."""
    norm = _norm(v)
    defined = norm > tiny
    if defined.all():
        return v / norm, norm
    return np.where(defined, v / np.where(defined, norm, 1.0), fallback), norm


def _perpendicular(axis: NDArray[np.float64]) -> NDArray[np.float64]:
    """(d, B) a fixed unit vector perpendicular to each unit ``axis`` (d, B)."""
    if axis.shape[0] == 2:
        return np.stack([-axis[1], axis[0]])
    # cross with the coordinate axis least aligned with ``axis``
    use_y = np.abs(axis[0]) > 0.9
    ex = np.where(use_y, 0.0, 1.0)
    ey = np.where(use_y, 1.0, 0.0)
    cross = np.stack([-axis[2] * ey, axis[2] * ex, axis[0] * ey - axis[1] * ex])
    return cross / _norm(cross)


def _fallback_axis(bend: NDArray[np.float64], dim: int) -> NDArray[np.float64]:
    """Any unit axis perpendicular to ``bend`` (or +last axis), for a target on the root."""
    norm = float(np.linalg.norm(bend))
    if norm <= _TINY:
        axis = np.zeros(dim)
        axis[-1] = 1.0
        return axis
    return _perpendicular((bend / norm)[:, None])[:, 0]


def _clamp_cone(
    v: NDArray[np.float64], axis: NDArray[np.float64], limits: tuple[float, float]
) -> NDArray[np.float64]:
    """Unit directions ``v`` (d, B) turned, by the least angle, into the cone of half-angle φ around ``axis``."""
    cos_phi, sin_phi = limits
    cos_v = _dot_d(v, axis)
    outside = cos_v < cos_phi
    if not outside.any():
        return v
    cols = np.flatnonzero(outside)  # work on the chains outside only: in a large batch they are few
    axis = np.broadcast_to(axis, v.shape)[:, cols]
    side = v[:, cols] - cos_v[cols] * axis
    side_norm = _norm(side)
    has_side = side_norm > 1e-9
    side = np.where(has_side, side / np.where(has_side, side_norm, 1.0), _perpendicular(axis))
    clamped = cos_phi * axis + sin_phi * side
    out = v.copy()
    # A nearly (anti)parallel v leaves ``side`` only roughly perpendicular: renormalise so lengths stay exact.
    out[:, cols] = clamped / _norm(clamped)
    return out


def _deflect(
    anchor: NDArray[np.float64],
    v: NDArray[np.float64],
    length: NDArray[np.float64],
    setup: _Setup,
    live: NDArray[np.bool_],
    tiny: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Turn the segments ``anchor + t·v, t ∈ [0, length]`` by the least angle until no live obstacle cuts them.

    Returns the new unit directions (d, B) and (B,) which were turned.
    """
    turned = np.zeros(v.shape[1], dtype=bool)
    for _ in range(3):  # turning around one obstacle can push into another: a few rounds settle it
        rel = setup.centres - anchor  # (K, d, B)
        along = _dot_d(rel, v)  # (K, B)
        t = np.minimum(np.maximum(along, 0.0), length)
        dist2 = _dot_d(rel, rel) - 2.0 * t * along + t * t
        hit = (dist2 < setup.radii * setup.radii) & live
        if not hit.any():
            return v, turned
        turned = turned | hit.any(axis=0)
        v = v.copy()
        for k in np.flatnonzero(hit.any(axis=1)):
            cols = np.flatnonzero(hit[k])  # only the chains this obstacle cuts
            v[:, cols] = _turn_clear(
                anchor[:, cols],
                v[:, cols],
                length[cols],
                setup.centres[k],
                setup.radii[k],
                tiny[cols],
            )
    return v, turned


def _turn_clear(
    anchor: NDArray[np.float64],
    v: NDArray[np.float64],
    length: NDArray[np.float64],
    centre: NDArray[np.float64],
    radius: NDArray[np.float64],
    tiny: NDArray[np.float64],
) -> NDArray[np.float64]:
    """Directions (d, B) nearest ``v`` whose segment of ``length`` from ``anchor`` just clears one obstacle."""
    clear = radius * (1.0 + _CLEARANCE)
    to_centre, distance = _unit(centre - anchor, -v, tiny)
    # Far enough to reach the tangent point: stop at the tangent; otherwise the far end rests on the surface.
    safe_distance = np.maximum(distance, tiny)
    safe_length = np.maximum(length, tiny)
    sin_tangent = np.clip(clear / safe_distance, 0.0, 1.0)
    cos_end = np.clip(
        (length * length + distance * distance - clear * clear)
        / (2.0 * safe_length * safe_distance),
        -1.0,
        1.0,
    )
    tangent = length * length >= distance * distance - clear * clear
    cos_t = np.where(tangent, np.sqrt(1.0 - sin_tangent * sin_tangent), cos_end)
    sin_t = np.where(tangent, sin_tangent, np.sqrt(1.0 - cos_end * cos_end))
    side = v - _dot_d(v, to_centre) * to_centre
    side, _ = _unit(side, _perpendicular(to_centre), np.full_like(tiny, 1e-9))
    turned = cos_t * to_centre + sin_t * side
    turned = turned / _norm(turned)
    inside = distance <= radius  # an anchor inside: leave straight away from the centre
    return np.where(inside, -to_centre, turned)


# ================================================================================================ passes
def _forward_pass(chains: _Chains, setup: _Setup) -> None:
    """End on the target, each joint back toward its old place at its link's length (the root is left)."""
    p, lengths, tiny = chains.p, chains.lengths, chains.tiny
    n = lengths.shape[0]
    p[n] = chains.target
    previous, _ = _unit(p[0] - p[n], -setup.root_direction * np.ones_like(tiny), tiny)
    has_obstacles = setup.radii.shape[0] > 0
    for i in range(n - 1, 0, -1):
        direction, _ = _unit(p[i] - p[i + 1], previous, tiny)
        if has_obstacles:
            direction, _ = _deflect(
                p[i + 1], direction, lengths[i], setup, chains.obstacle_live, tiny
            )
        if setup.limits is not None and i < n - 1:
            direction = _clamp_cone(direction, previous, setup.limits)
        p[i] = p[i + 1] + lengths[i] * direction
        previous = (
            np.where(lengths[i] > tiny, direction, previous) if chains.has_zero_link else direction
        )


def _backward_pass(chains: _Chains, setup: _Setup) -> None:
    """Root back on its place, each joint outward toward its current place; limits and obstacles enforced."""
    p, lengths, tiny = chains.p, chains.lengths, chains.tiny
    n = lengths.shape[0]
    previous = setup.root_direction * np.ones_like(tiny)
    has_obstacles = setup.radii.shape[0] > 0
    for i in range(1, n + 1):
        direction, _ = _unit(p[i] - p[i - 1], previous, tiny)
        if setup.limits is not None:
            direction = _clamp_cone(direction, previous, setup.limits)
        if has_obstacles:
            direction, turned = _deflect(
                p[i - 1], direction, lengths[i - 1], setup, chains.obstacle_live, tiny
            )
            if setup.limits is not None and turned.any():
                # Only the turned ones: clamping an already clamped direction again can move it by a rounding
                # error, and the one-chain path (which the batch must equal) does not.
                clamped = _clamp_cone(direction, previous, setup.limits)
                direction = np.where(turned, clamped, direction)
        p[i] = p[i - 1] + lengths[i - 1] * direction
        previous = (
            np.where(lengths[i - 1] > tiny, direction, previous)
            if chains.has_zero_link
            else direction
        )


def _fabrik_step(chains: _Chains, setup: _Setup) -> None:
    if chains.p.shape[2] == 1:
        _fabrik_step_one(chains, setup)
        return
    _forward_pass(chains, setup)
    _backward_pass(chains, setup)


# ------------------------------------------------------------------------------------------------ one chain
# With B = 1 every numpy call costs about a microsecond whatever its size, so one chain's passes run on Python
# floats instead. They repeat the vectorised passes operation for operation, in the same order, so both paths give
# the same bits (the batch-equals-single tests hold them to it).
Vec = list[float]


def _dot(a: Vec, b: Vec) -> float:
    total = a[0] * b[0] + a[1] * b[1]
    return total + a[2] * b[2] if len(a) == 3 else total


def _length(v: Vec) -> float:
    return math.sqrt(_dot(v, v))


def _unit_one(v: Vec, fallback: Vec, tiny: float) -> tuple[Vec, float]:
    norm = _length(v)
    if norm > tiny:
        return [x / norm for x in v], norm
    return fallback, norm


def _perpendicular_one(a: Vec) -> Vec:
    if len(a) == 2:
        return [-a[1], a[0]]
    use_y = abs(a[0]) > 0.9
    ex, ey = (0.0, 1.0) if use_y else (1.0, 0.0)
    cross = [-a[2] * ey, a[2] * ex, a[0] * ey - a[1] * ex]
    norm = _length(cross)
    return [x / norm for x in cross]


def _clamp_cone_one(v: Vec, axis: Vec, limits: tuple[float, float]) -> Vec:
    cos_phi, sin_phi = limits
    cos_v = _dot(v, axis)
    if not cos_v < cos_phi:
        return v
    side = [x - cos_v * a for x, a in zip(v, axis, strict=True)]
    side_norm = _length(side)
    side = [x / side_norm for x in side] if side_norm > 1e-9 else _perpendicular_one(axis)
    clamped = [cos_phi * a + sin_phi * x for a, x in zip(axis, side, strict=True)]
    norm = _length(clamped)
    return [x / norm for x in clamped]


def _deflect_one(
    anchor: Vec,
    v: Vec,
    length: float,
    obstacles: list[tuple[Vec, float, float]],
    tiny: float,
) -> tuple[Vec, bool]:
    """:func:`_deflect` for one chain; ``obstacles`` are its live ones as (centre, radius, far²).

    ``far²`` is a squared distance from the anchor beyond which no segment of the chain can reach the obstacle
    (with a 1 % margin, so rounding never skips a hit the batch path would see): most pairs stop there.
    """
    turned = False
    three = len(anchor) == 3
    ax, ay = anchor[0], anchor[1]
    az = anchor[2] if three else 0.0
    for _ in range(3):
        # Written out, in the order numpy sums over the d axis, so the bits match the batch path; this test runs
        # for every segment and obstacle of every pass, so it is kept to plain float arithmetic.
        hits = []
        vx, vy = v[0], v[1]
        vz = v[2] if three else 0.0
        for k, (centre, radius, far2) in enumerate(obstacles):
            rx, ry = centre[0] - ax, centre[1] - ay
            if three:
                rz = centre[2] - az
                rel2 = rx * rx + ry * ry + rz * rz
                if rel2 > far2:
                    continue
                along = rx * vx + ry * vy + rz * vz
            else:
                rel2 = rx * rx + ry * ry
                if rel2 > far2:
                    continue
                along = rx * vx + ry * vy
            t = along if along > 0.0 else 0.0
            if t > length:
                t = length
            if rel2 - 2.0 * t * along + t * t < radius * radius:
                hits.append(k)
        if not hits:
            return v, turned
        turned = True
        for k in hits:
            v = _turn_clear_one(anchor, v, length, obstacles[k][0], obstacles[k][1], tiny)
    return v, turned


def _turn_clear_one(
    anchor: Vec, v: Vec, length: float, centre: Vec, radius: float, tiny: float
) -> Vec:
    clear = radius * (1.0 + _CLEARANCE)
    to_centre, distance = _unit_one(
        [c - a for c, a in zip(centre, anchor, strict=True)], [-x for x in v], tiny
    )
    if distance <= radius:
        return [-x for x in to_centre]
    safe_distance = max(distance, tiny)
    safe_length = max(length, tiny)
    if length * length >= distance * distance - clear * clear:
        sin_t = min(max(clear / safe_distance, 0.0), 1.0)
        cos_t = math.sqrt(1.0 - sin_t * sin_t)
    else:
        cos_t = min(
            max(
                (length * length + distance * distance - clear * clear)
                / (2.0 * safe_length * safe_distance),
                -1.0,
            ),
            1.0,
        )
        sin_t = math.sqrt(1.0 - cos_t * cos_t)
    along = _dot(v, to_centre)
    side, _ = _unit_one(
        [x - along * c for x, c in zip(v, to_centre, strict=True)],
        _perpendicular_one(to_centre),
        1e-9,
    )
    turned = [cos_t * c + sin_t * x for c, x in zip(to_centre, side, strict=True)]
    norm = _length(turned)
    return [x / norm for x in turned]


def _live_obstacles_one(
    setup: _Setup, live: list[bool], lengths: Vec
) -> list[tuple[Vec, float, float]]:
    """The live obstacles of one chain as :func:`_deflect_one` takes them: (centre, radius, far²)."""
    longest = max(lengths)
    return [
        (centre, radius, 1.01 * (longest + radius) * (longest + radius))
        for centre, radius, alive in zip(
            setup.centres[:, :, 0].tolist(), setup.radii[:, 0].tolist(), live, strict=True
        )
        if alive
    ]


def _fabrik_step_one(chains: _Chains, setup: _Setup) -> None:
    """:func:`_forward_pass` then :func:`_backward_pass` for a batch of one chain, on Python floats."""
    p: list[Vec] = chains.p[:, :, 0].tolist()
    lengths: Vec = chains.lengths[:, 0].tolist()
    live: list[bool] = chains.obstacle_live[:, 0].tolist()
    _fabrik_passes_one(
        p,
        chains.target[:, 0].tolist(),
        lengths,
        float(chains.tiny[0]),
        _live_obstacles_one(setup, live, lengths),
        setup.root_direction[:, 0].tolist(),
        setup.limits,
        zero_links=chains.has_zero_link,
    )
    chains.p[:, :, 0] = p


def _fabrik_passes_one(
    p: list[Vec],
    target: Vec,
    lengths: Vec,
    tiny: float,
    obstacles: list[tuple[Vec, float, float]],
    root_direction: Vec,
    limits: tuple[float, float] | None,
    *,
    zero_links: bool,
) -> None:
    """The forward then the backward pass of one chain ``p`` (n + 1 joints as lists), in place."""
    has_obstacles = bool(obstacles)
    n = len(lengths)

    p[n] = list(target)
    previous, _ = _unit_one(
        [a - b for a, b in zip(p[0], p[n], strict=True)], [-x for x in root_direction], tiny
    )
    for i in range(n - 1, 0, -1):
        anchor = p[i + 1]
        direction, _ = _unit_one([a - b for a, b in zip(p[i], anchor, strict=True)], previous, tiny)
        if has_obstacles:
            direction, _ = _deflect_one(anchor, direction, lengths[i], obstacles, tiny)
        if limits is not None and i < n - 1:
            direction = _clamp_cone_one(direction, previous, limits)
        p[i] = [a + lengths[i] * x for a, x in zip(anchor, direction, strict=True)]
        if not zero_links or lengths[i] > tiny:
            previous = direction

    previous = root_direction
    for i in range(1, n + 1):
        anchor = p[i - 1]
        direction, _ = _unit_one([a - b for a, b in zip(p[i], anchor, strict=True)], previous, tiny)
        if limits is not None:
            direction = _clamp_cone_one(direction, previous, limits)
        if has_obstacles:
            direction, turned = _deflect_one(anchor, direction, lengths[i - 1], obstacles, tiny)
            if turned and limits is not None:
                direction = _clamp_cone_one(direction, previous, limits)
        p[i] = [a + lengths[i - 1] * x for a, x in zip(anchor, direction, strict=True)]
        if not zero_links or lengths[i - 1] > tiny:
            previous = direction


def _rotate_2d(
    v: NDArray[np.float64], cos_a: NDArray[np.float64], sin_a: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Rotate (…, 2, B) vectors by angles given as cos/sin (B,)."""
    x, y = v[..., 0, :], v[..., 1, :]
    return np.stack([cos_a * x - sin_a * y, sin_a * x + cos_a * y], axis=-2)


def _cross(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """Cross product over the d = 3 axis (-2) of (…, 3, B) arrays."""
    ax, ay, az = a[..., 0, :], a[..., 1, :], a[..., 2, :]
    bx, by, bz = b[..., 0, :], b[..., 1, :], b[..., 2, :]
    return np.stack([ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx], axis=-2)


def _ccd_step(chains: _Chains, setup: _Setup) -> None:
    """One CCD sweep, end to root, then the constrained backward pass as a projection."""
    p, tiny = chains.p, chains.tiny
    n = chains.lengths.shape[0]
    for i in range(n - 1, -1, -1):
        pivot = p[i]
        to_end, end_norm = _unit(p[n] - pivot, setup.root_direction * np.ones_like(tiny), tiny)
        to_target, target_norm = _unit(chains.target - pivot, to_end, tiny)
        cos_a = np.clip(_dot_d(to_end, to_target), -1.0, 1.0)
        move = (end_norm > tiny) & (target_norm > tiny)
        downstream = p[i + 1 :] - pivot
        if setup.dim == 2:
            sin_a = to_end[0] * to_target[1] - to_end[1] * to_target[0]
            rotated = _rotate_2d(downstream, cos_a, sin_a)
        else:
            axis = _cross(to_end, to_target)
            sin_a = _norm(axis)
            axis, _ = _unit(axis, _perpendicular(to_end), np.full_like(tiny, 1e-12))
            # Rodrigues: v cos a + (k × v) sin a + k (k·v)(1 − cos a)
            k_dot_v = np.add.reduce(axis * downstream, axis=-2, keepdims=True)
            rotated = (
                downstream * cos_a + _cross(axis * np.ones_like(downstream), downstream) * sin_a
            )
            rotated = rotated + axis * k_dot_v * (1.0 - cos_a)
        p[i + 1 :] = np.where(move, pivot + rotated, p[i + 1 :])
    _backward_pass(chains, setup)


def _dls_step(chains: _Chains, setup: _Setup) -> None:
    """One damped-least-squares step on joint angles, then the constrained backward pass as a projection."""
    p, lengths = chains.p, chains.lengths
    n = lengths.shape[0]
    batch = p.shape[2]
    end = p[n]
    lever = end - p[:n]  # (n, d, B): end effector relative to each joint
    error = chains.target - end  # (d, B)
    # Clamp the step as Buss 2004 advises, so the linearisation holds.
    step_cap = np.maximum(lengths.mean(axis=0), chains.tiny)
    error_norm = _norm(error)
    error = error * np.minimum(1.0, step_cap / np.maximum(error_norm, chains.tiny))
    damping = _DLS_DAMPING * step_cap
    if setup.dim == 2:
        jac = np.stack(
            [-lever[:, 1], lever[:, 0]], axis=1
        )  # (n, 2, B): ∂end/∂θ_i = perp(end − p_i)
        jac = np.transpose(jac, (2, 1, 0))  # (B, 2, n)
    else:
        basis = np.eye(3)[:, :, None, None] * np.ones((1, 1, n, batch))  # (3 axes, 3, n, B)
        cols = _cross(np.moveaxis(basis, 1, -2), lever[None])  # (3 axes, n, 3, B)
        jac = np.transpose(cols, (3, 2, 1, 0)).reshape(
            batch, 3, 3 * n
        )  # columns ordered joint-major
    jjt = jac @ np.swapaxes(jac, 1, 2)
    jjt = jjt + (damping**2)[:, None, None] * np.eye(setup.dim)
    solved = np.linalg.solve(jjt, error.T[:, :, None])  # (B, d, 1)
    dtheta = (np.swapaxes(jac, 1, 2) @ solved)[:, :, 0]  # (B, m)
    segments = np.diff(p, axis=0)  # (n, d, B)
    if setup.dim == 2:
        total = np.cumsum(dtheta.T, axis=0)  # (n, B): segment j turns by the sum of joints 0..j
        segments = _rotate_2d(segments, np.cos(total), np.sin(total))
    else:
        rotvec = dtheta.reshape(batch, n, 3)  # (B, n, 3)
        rot = _rotation_matrices(rotvec)  # (B, n, 3, 3)
        cumulative = rot[:, 0]
        seg = np.transpose(segments, (2, 0, 1))  # (B, n, 3)
        out = np.empty_like(seg)
        for j in range(n):
            if j > 0:
                cumulative = cumulative @ rot[:, j]
            out[:, j] = (cumulative @ seg[:, j, :, None])[:, :, 0]
        segments = np.transpose(out, (1, 2, 0))
    p[1:] = p[0] + np.cumsum(segments, axis=0)
    _backward_pass(chains, setup)


def _rotation_matrices(rotvec: NDArray[np.float64]) -> NDArray[np.float64]:
    """(…, 3) rotation vectors → (…, 3, 3) matrices (Rodrigues)."""
    angle = np.linalg.norm(rotvec, axis=-1)
    safe = np.where(angle > 1e-15, angle, 1.0)
    k = rotvec / safe[..., None]
    kx, ky, kz = k[..., 0], k[..., 1], k[..., 2]
    zero = np.zeros_like(kx)
    skew = np.stack(
        [
            np.stack([zero, -kz, ky], -1),
            np.stack([kz, zero, -kx], -1),
            np.stack([-ky, kx, zero], -1),
        ],
        -2,
    )
    sin_a, cos_a = np.sin(angle)[..., None, None], np.cos(angle)[..., None, None]
    return np.eye(3) + sin_a * skew + (1.0 - cos_a) * (skew @ skew)


# ================================================================================================ checks on poses
def _cone_ok(chains: _Chains, setup: _Setup) -> NDArray[np.bool_]:
    """(B,) whether every segment of each chain lies within its cone."""
    if setup.limits is None:
        return np.ones(chains.p.shape[2], dtype=bool)
    cos_phi = setup.limits[0]
    if not chains.has_zero_link:  # every segment has a direction: compare them all at once
        directions = np.diff(chains.p, axis=0) / chains.lengths[:, None, :]  # (n, d, B)
        previous_all = np.concatenate(
            [setup.root_direction[None] * np.ones_like(directions[:1]), directions[:-1]]
        )
        return np.all(_dot_d(directions, previous_all) >= cos_phi - 1e-12, axis=0)
    previous = setup.root_direction * np.ones_like(chains.tiny)
    ok = np.ones(chains.p.shape[2], dtype=bool)
    for i in range(chains.lengths.shape[0]):
        direction, norm = _unit(chains.p[i + 1] - chains.p[i], previous, chains.tiny)
        ok &= (_dot_d(direction, previous) >= cos_phi - 1e-12) | (norm <= chains.tiny)
        previous = np.where(norm > chains.tiny, direction, previous)
    return ok


def _colliding(
    p: NDArray[np.float64],
    setup: _Setup,
    live: NDArray[np.bool_],
    radii: NDArray[np.float64] | None = None,
) -> NDArray[np.bool_]:
    """(B,) whether any segment of the (n + 1, d, B) chains passes through a live obstacle.

    ``radii`` (K, 1) replace the obstacles' own radii when given.
    """
    batch = p.shape[2]
    radii = setup.radii if radii is None else radii
    if setup.radii.shape[0] == 0:
        return np.zeros(batch, dtype=bool)
    start = p[:-1, None]  # (n, 1, d, B)
    seg = (p[1:] - p[:-1])[:, None]
    rel = setup.centres[None] - start  # (n, K, d, B)
    seg2 = _dot_d(seg, seg)
    t = np.minimum(np.maximum(_dot_d(rel, seg) / np.where(seg2 > 0.0, seg2, 1.0), 0.0), 1.0)
    gap = rel - t[:, :, None] * seg
    dist2 = _dot_d(gap, gap)  # (n, K, B)
    return np.any((dist2 < radii * radii) & live, axis=(0, 1))


def _touching(p: NDArray[np.float64], setup: _Setup, live: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """(B,) whether a segment rests against (or cuts) a live obstacle, within 0.1 % of its radius."""
    return _colliding(p, setup, live, setup.radii * (1.0 + 1e-3))


# ================================================================================================ driver
def _run(
    joints: NDArray[np.float64],
    targets: NDArray[np.float64],
    setup: _Setup,
    step: Callable[[_Chains, _Setup], None],
    *,
    shortcut: bool,
    extrapolate: bool,
) -> BatchSolution:
    batch, count, _ = joints.shape
    n = count - 1
    p = np.transpose(joints, (1, 2, 0)).copy()  # (n + 1, d, B); a copy: the passes work in place
    target = targets.T.copy()  # (d, B)
    lengths = _norm(np.diff(p, axis=0))  # (n, B)
    total = lengths.sum(axis=0)
    scale = np.maximum(np.maximum(total, _norm(target - p[0])), 1.0)
    tiny = _TINY * scale
    root_to_obstacle = _norm(setup.centres - p[0][None])  # (K, B)
    live = root_to_obstacle > setup.radii
    chains = _Chains(p, target, lengths, tiny, live, bool((lengths <= tiny).any()))
    has_obstacles = setup.radii.shape[0] > 0

    out_p = p.copy()
    iterations = np.zeros(batch, dtype=np.int64)
    status = np.full(batch, _MAX_ITERATIONS, dtype=np.int64)
    history = np.full((batch, setup.max_iterations + 1), np.nan)

    offset = target - p[0]
    distance = _norm(offset)
    inner = np.maximum(0.0, 2.0 * lengths.max(axis=0) - total)
    out_of_reach = (distance > total) | (distance < inner)
    error0 = _norm(p[n] - target)
    history[:, 0] = error0

    # The starting pose is kept if it already meets the tolerance and every constraint.
    valid0 = _cone_ok(chains, setup) & ~_colliding(p, setup, live)
    best_p = p.copy()
    best_error = np.where(valid0, error0, np.inf)
    done = valid0 & (error0 < setup.tolerance)
    status[done] = _REACHED

    if shortcut:
        placed = _unreachable_shortcut(
            chains, setup, offset, distance, total, inner, out_of_reach & ~done, out_p
        )
        history[placed, 1] = _norm(out_p[n] - target)[placed]
        iterations[placed] = 1
        status[placed] = _UNREACHABLE
        done = done | placed

    _unbend_axis_chains(chains, setup, offset, distance, ~done)

    index = np.flatnonzero(~done)
    active = chains.take(~done) if done.any() else chains
    best_p_active = best_p[:, :, index]
    best_error_active = best_error[index]
    stall = _STALL * setup.tolerance + tiny[index]
    # Extrapolation (FABRIK only, see _extrapolate): the pose before the last step, which chains may still be
    # extrapolated (none whose extrapolation once made its error grow), and which were before this step.
    previous_p = active.p
    trusted = np.ones(index.size, dtype=bool)
    moved = np.zeros(index.size, dtype=bool)
    for iteration in range(1, setup.max_iterations + 1):
        if index.size == 0:
            break
        last_error = history[index, iteration - 1]
        if extrapolate and iteration >= 2:
            before = active.p.copy()
            if iteration >= 3:
                moved = _extrapolate(
                    active.p, previous_p, last_error, history[index, iteration - 2], trusted
                )
            previous_p = before
        step(active, setup)
        error = _norm(active.p[n] - active.target)
        history[index, iteration] = error
        if extrapolate:
            trusted &= ~(moved & (error > last_error))
        if has_obstacles:
            # Whether the pose is clear matters only where it would be the best yet or reach the target.
            improved = (error < best_error_active) | (error < setup.tolerance)
            if improved.any():
                clear = ~_colliding(active.p, setup, active.obstacle_live)
            else:
                clear = improved
            better = clear & (error < best_error_active)
            if better.any():
                best_p_active[:, :, better] = active.p[:, :, better]
                best_error_active = np.where(better, error, best_error_active)
            reached = clear & (error < setup.tolerance)
        else:
            reached = error < setup.tolerance
        stalled = np.abs(last_error - error) < stall
        finished = reached | stalled | (iteration == setup.max_iterations)
        if not finished.any():
            continue
        rows = index[finished]
        iterations[rows] = iteration
        status[rows] = np.where(
            reached[finished], _REACHED, np.where(stalled[finished], _UNREACHABLE, _MAX_ITERATIONS)
        )
        if has_obstacles:
            # Return the best collision-free pose seen; only if there was none, the last one (still "blocked").
            use_best = ~reached[finished] & np.isfinite(best_error_active[finished])
            final = np.where(use_best, best_p_active[:, :, finished], active.p[:, :, finished])
            out_p[:, :, rows] = final
            short = ~reached[finished]
            if short.any():
                live_rows = active.obstacle_live[:, finished]
                blocked = short & (
                    _touching(final, setup, live_rows)
                    | _target_inside(active.target[:, finished], setup, live_rows)
                )
                status[rows] = np.where(blocked, _BLOCKED, status[rows])
        else:
            out_p[:, :, rows] = active.p[:, :, finished]
        keep = ~finished
        index = index[keep]
        active = active.take(keep)
        best_p_active = best_p_active[:, :, keep]
        best_error_active = best_error_active[keep]
        stall = stall[keep]
        previous_p = previous_p[:, :, keep]
        trusted, moved = trusted[keep], moved[keep]

    final_error = _norm(out_p[n] - target)
    # A target outside the annulus is unreachable whatever the iterations did (unless an obstacle explains it).
    status = np.where(
        out_of_reach & (status != _BLOCKED) & (status != _REACHED), _UNREACHABLE, status
    )
    return BatchSolution(
        joints=np.ascontiguousarray(np.transpose(out_p, (2, 0, 1))),
        iterations=iterations,
        error=final_error,
        status=np.array(STATUSES)[status],
        error_history=history,
    )


def _run_one(
    joints: NDArray[np.float64], target: NDArray[np.float64], setup: _Setup, *, extrapolate: bool
) -> Solution:
    """:func:`_run` with FABRIK for one chain, on Python floats: the same operations in the same order, so the
    same bits, iterations and status, without numpy's per-call cost on arrays of one.

    The rare cases (a target outside the annulus, a zero-length link, a straight chain pointing at its target) go
    to :func:`_run` itself.
    """
    p: list[Vec] = joints.tolist()
    goal: Vec = target.tolist()
    n = len(p) - 1
    lengths = [
        _length([a - b for a, b in zip(q, r, strict=True)]) for q, r in zip(p[1:], p, strict=False)
    ]
    # Summed by numpy, as _run sums it (pairwise, not left to right), so the reach tests agree to the bit.
    total = float(np.add.reduce(np.array(lengths)[:, None], axis=0)[0])
    offset = [a - b for a, b in zip(goal, p[0], strict=True)]
    distance = _length(offset)
    tiny = _TINY * max(max(total, distance), 1.0)
    inner = max(0.0, 2.0 * max(lengths) - total)
    end = [a - b for a, b in zip(p[n], p[0], strict=True)]
    end2 = _dot(end, end)
    offset2 = distance * distance
    along = _dot(end, offset)
    on_line = (end2 * offset2 - along * along) <= 1e-12 * max(end2 * offset2, tiny * tiny)
    if distance > total or distance < inner or min(lengths) <= tiny or on_line:
        return _run(
            joints[None], target[None], setup, _fabrik_step, shortcut=True, extrapolate=extrapolate
        )[0]

    centres: list[Vec] = setup.centres[:, :, 0].tolist()
    radii: list[float] = setup.radii[:, 0].tolist()
    root = p[0]
    live = [
        _length([c - r for c, r in zip(centre, root, strict=True)]) > radius
        for centre, radius in zip(centres, radii, strict=True)
    ]
    obstacles = _live_obstacles_one(setup, live, lengths)
    has_obstacles = bool(radii)
    root_direction: Vec = setup.root_direction[:, 0].tolist()
    limits, tolerance = setup.limits, setup.tolerance

    error0 = _length([a - b for a, b in zip(p[n], goal, strict=True)])
    history = [error0]
    valid0 = _cone_ok_one(p, lengths, root_direction, limits) and not _colliding_one(
        p, obstacles, 1.0
    )
    if valid0 and error0 < tolerance:
        return _solution_one(p, goal, 0, _REACHED, history)

    best_p, best_error = [list(q) for q in p], error0 if valid0 else math.inf
    stall = _STALL * tolerance + tiny
    previous_p = p
    trusted, moved = True, False
    for iteration in range(1, setup.max_iterations + 1):
        last_error = history[iteration - 1]
        if extrapolate and iteration >= 2:
            before = [list(q) for q in p]
            if iteration >= 3:
                moved = _extrapolate_one(p, previous_p, last_error, history[iteration - 2], trusted)
            previous_p = before
        _fabrik_passes_one(
            p, goal, lengths, tiny, obstacles, root_direction, limits, zero_links=False
        )
        error = _length([a - b for a, b in zip(p[n], goal, strict=True)])
        history.append(error)
        if extrapolate:
            trusted = trusted and not (moved and error > last_error)
        if has_obstacles:
            improved = error < best_error or error < tolerance
            clear = improved and not _colliding_one(p, obstacles, 1.0)
            if clear and error < best_error:
                best_p, best_error = [list(q) for q in p], error
            reached = clear and error < tolerance
        else:
            reached = error < tolerance
        stalled = abs(last_error - error) < stall
        if not (reached or stalled or iteration == setup.max_iterations):
            continue
        status = _REACHED if reached else _UNREACHABLE if stalled else _MAX_ITERATIONS
        final = p
        if has_obstacles and not reached:
            if math.isfinite(best_error):
                final = best_p
            inside = any(
                _length([c - t for c, t in zip(centre, goal, strict=True)]) < radius
                for centre, radius, _ in obstacles
            )
            if inside or _colliding_one(final, obstacles, 1.0 + 1e-3):
                status = _BLOCKED
        return _solution_one(final, goal, iteration, status, history)
    raise AssertionError("unreachable: the last iteration always finishes")  # pragma: no cover


def _solution_one(p: list[Vec], goal: Vec, iterations: int, status: int, history: Vec) -> Solution:
    return Solution(
        joints=np.array(p),
        iterations=iterations,
        error=_length([a - b for a, b in zip(p[-1], goal, strict=True)]),
        status=STATUSES[status],
        error_history=np.array(history),
    )


def _cone_ok_one(
    p: list[Vec], lengths: Vec, root_direction: Vec, limits: tuple[float, float] | None
) -> bool:
    """:func:`_cone_ok` for one chain with no zero-length link."""
    if limits is None:
        return True
    bound = limits[0] - 1e-12
    previous = root_direction
    for i, length in enumerate(lengths):
        direction = [(a - b) / length for a, b in zip(p[i + 1], p[i], strict=True)]
        if not _dot(direction, previous) >= bound:
            return False
        previous = direction
    return True


def _colliding_one(p: list[Vec], obstacles: list[tuple[Vec, float, float]], inflate: float) -> bool:
    """:func:`_colliding` (``inflate`` = 1) or :func:`_touching` (1 + 1e-3) for one chain.

    ``obstacles`` are the chain's live ones as :func:`_deflect_one` takes them; a pair farther apart than ``far²``
    (which has room for the 0.1 % inflation) cannot touch and is skipped. The rest is computed as the batch path
    does, in the same order, so the answer is the same.
    """
    three = len(p[0]) == 3
    for i in range(len(p) - 1):
        x0, y0 = p[i][0], p[i][1]
        sx, sy = p[i + 1][0] - x0, p[i + 1][1] - y0
        z0 = p[i][2] if three else 0.0
        sz = p[i + 1][2] - z0 if three else 0.0
        seg2 = sx * sx + sy * sy + sz * sz if three else sx * sx + sy * sy
        divisor = seg2 if seg2 > 0.0 else 1.0
        for centre, radius, far2 in obstacles:
            rx, ry = centre[0] - x0, centre[1] - y0
            if three:
                rz = centre[2] - z0
                if rx * rx + ry * ry + rz * rz > far2:
                    continue
                t = min(max((rx * sx + ry * sy + rz * sz) / divisor, 0.0), 1.0)
                gx, gy, gz = rx - t * sx, ry - t * sy, rz - t * sz
                dist2 = gx * gx + gy * gy + gz * gz
            else:
                if rx * rx + ry * ry > far2:
                    continue
                t = min(max((rx * sx + ry * sy) / divisor, 0.0), 1.0)
                gx, gy = rx - t * sx, ry - t * sy
                dist2 = gx * gx + gy * gy
            grown = radius * inflate
            if dist2 < grown * grown:
                return True
    return False


def _extrapolate_one(
    p: list[Vec], previous_p: list[Vec], error: float, previous_error: float, trusted: bool
) -> bool:
    """:func:`_extrapolate` for one chain, in place."""
    ratio = error / max(previous_error, _TINY)
    slow = _EXTRAPOLATION_MIN_RATIO <= ratio < 1.0 and trusted
    weight = ratio / max(1.0 - ratio, ratio / _EXTRAPOLATION_CAP) if slow else 0.0
    for joint, before in zip(p, previous_p, strict=True):
        joint[:] = [a + weight * (a - b) for a, b in zip(joint, before, strict=True)]
    return slow


def _extrapolate(
    p: NDArray[np.float64],
    previous_p: NDArray[np.float64],
    error: NDArray[np.float64],
    previous_error: NDArray[np.float64],
    trusted: NDArray[np.bool_],
) -> NDArray[np.bool_]:
    """Move the (n + 1, d, B) joints ``p`` on along their last step, in place, by the rest of a geometric series.

    Where the end-effector error shrank by a ratio ``r < 1`` in the last iteration, FABRIK converges linearly at
    about that ratio (near cone limits ``r`` is 0.8–0.95, so tens of iterations), and the steps still to come sum to
    ``r / (1 − r)`` times the last one. The joints are moved on by that much (at most :data:`_EXTRAPOLATION_CAP`
    steps) before the next iteration, as Aitken's Δ² extrapolation does for a linearly converging sequence. Only
    the starting guess of the next passes moves: the passes still place every joint at its link's length, inside
    its cone and clear of obstacles. Where the error grew, or shrank fast already (``r`` below
    :data:`_EXTRAPOLATION_MIN_RATIO`, plain FABRIK needs only a few more iterations), nothing is moved; nor in
    chains not ``trusted`` (B,): the caller stops extrapolating a chain once an extrapolation made its error grow
    (a target the limits put out of reach, where the error tends to a positive value and ``r`` to 1), so plain
    FABRIK settles it at its fixed point. Returns (B,) which chains were moved.
    """
    ratio = error / np.maximum(previous_error, _TINY)
    cap = _EXTRAPOLATION_CAP
    slow = (ratio >= _EXTRAPOLATION_MIN_RATIO) & (ratio < 1.0) & trusted
    weight = np.where(slow, ratio / np.maximum(1.0 - ratio, ratio / cap), 0.0)
    p += weight * (p - previous_p)
    return slow


def _target_inside(
    target: NDArray[np.float64], setup: _Setup, live: NDArray[np.bool_]
) -> NDArray[np.bool_]:
    dist = _norm(setup.centres - target[None])  # (K, B)
    return np.any((dist < setup.radii) & live, axis=0)


def _unreachable_shortcut(
    chains: _Chains,
    setup: _Setup,
    offset: NDArray[np.float64],
    distance: NDArray[np.float64],
    total: NDArray[np.float64],
    inner: NDArray[np.float64],
    candidates: NDArray[np.bool_],
    out_p: NDArray[np.float64],
) -> NDArray[np.bool_]:
    """Place out-of-reach chains in their closest pose at once, where limits and obstacles allow it.

    Beyond the reach: every link along the root–target direction. Inside the inner hole: the longest link toward the
    target and the others folded back, so the end rests on the inner boundary. Returns (B,) which chains it placed.
    """
    if not candidates.any():
        return candidates
    p, lengths = chains.p, chains.lengths
    n = lengths.shape[0]
    direction, _ = _unit(offset, setup.root_direction * np.ones_like(chains.tiny), chains.tiny)
    beyond = distance > total
    longest = np.argmax(lengths, axis=0)
    sign = np.where(beyond | (np.arange(n)[:, None] == longest[None]), 1.0, -1.0)  # (n, B)
    reach = np.cumsum(sign * lengths, axis=0)  # (n, B)
    pose = p.copy()
    pose[1:] = p[0] + reach[:, None, :] * direction
    ok = candidates.copy()
    if setup.limits is not None:
        # A folded chain turns by π; a straight one only at the root.
        root_cos = _dot_d(direction, setup.root_direction)
        ok &= beyond & (root_cos >= setup.limits[0])
    if setup.radii.shape[0] > 0:
        ok &= ~_colliding(pose, setup, chains.obstacle_live)
    out_p[:, :, ok] = pose[:, :, ok]
    return ok


def _unbend_axis_chains(
    chains: _Chains,
    setup: _Setup,
    offset: NDArray[np.float64],
    distance: NDArray[np.float64],
    todo: NDArray[np.bool_],
) -> None:
    """Bend straight chains whose target lies on their own line into a gentle arc, so the passes can bend them."""
    p, tiny = chains.p, chains.tiny
    # Cheap test first: a straight chain's end lies on the root–target line (or on the root).
    end = p[-1] - p[0]
    end2 = _dot_d(end, end)
    offset2 = distance * distance
    along = _dot_d(end, offset)
    scale2 = np.maximum(end2 * offset2, tiny * tiny)
    if not (todo & ((end2 * offset2 - along * along) <= 1e-12 * scale2)).any():
        return
    segments = np.diff(p, axis=0)  # (n, d, B)
    norms = _norm(segments)
    first = np.argmax(norms > tiny, axis=0)  # first segment with a direction
    axis_raw = np.take_along_axis(segments, first[None, None, :], axis=0)[0]
    axis, _ = _unit(axis_raw, setup.root_direction * np.ones_like(tiny), tiny)
    along = _dot_d(segments, axis)  # (n, B)
    off_axis = _norm(segments - along[:, None, :] * axis)  # (n, B)
    straight = np.all(off_axis <= 1e-9 * np.maximum(norms, tiny), axis=0)
    target_off = _norm(offset - _dot_d(offset, axis) * axis)
    on_axis = target_off <= 1e-9 * np.maximum(distance, 1.0)
    bend = todo & straight & on_axis
    if not bend.any():
        return
    step = 0.1 if setup.limits is None else min(0.1, 0.5 * math.acos(setup.limits[0]))
    if step <= 0.0:
        return
    side = _perpendicular(axis)
    # A symmetric arc: every interior joint leaves the line (an arc starting along it leaves p_1 on it).
    count = segments.shape[0]
    angle = step * (np.arange(count) - 0.5 * (count - 1))[:, None]  # (n, 1)
    directions = np.cos(angle)[:, None, :] * axis + np.sin(angle)[:, None, :] * side  # (n, d, B)
    arc = p[0] + np.cumsum(norms[:, None, :] * directions, axis=0)
    p[1:] = np.where(bend, arc, p[1:])
