"""Skeletons with several end effectors: FABRIK's multiple-end-effector form (Aristidou & Lasenby 2011, §4.2).

A tree is ``parents`` (J,) and joints (J, d), metres. Its passes use the chain's compiled joint rules
(:mod:`kernels.fabrik.limits`) and obstacle rule (:mod:`kernels.fabrik.geometry`), so a rule fixed there is fixed for
both; a tree that is one chain is solved by :func:`kernels.fabrik.solve` itself.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from kernels import _checks
from kernels._jit import compiled
from kernels.fabrik.api import _UNSCALED, Obstacle, _check_joints, _check_vector, _norms, _Setup, _solve_single
from kernels.fabrik.chain import (
    _BLOCKED,
    _FABRIK,
    _FARTHEST,
    _INFEASIBLE,
    _LIMITED,
    _MAX_ITERATIONS,
    _REACHED,
    _STALL,
    _UNREACHABLE,
    STATUSES,
    Status,
    _backward_step,
    _copy,
)
from kernels.fabrik.geometry import (
    _DIM_3D,
    _OFF,
    _ROW_0,
    _TINY,
    _TOUCH,
    Obstacles,
    _deflect,
    _inside_live,
    _mark_live,
    _perpendicular,
    _rotate,
    _segment_cuts,
    _unit,
)
from kernels.fabrik.limits import (
    _TABLE_WIDTH,
    Constraint,
    _hold_by_next,
    _into_hinge_plane,
    _joint_ok,
    _limit_flags,
    _limit_table,
)
from kernels.warming import Entry


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
    under the centroid rule; a tree already on its targets to rounding is not turned), then to the cap. "Reached"
    is error ≤ tolerance on a pose that keeps every limit (a start that breaks one is iterated on). The returned
    pose is the last iterate, or the best admissible one (smallest largest error) where the last is not admissible,
    or where the pose the restart left was better than any after it. Huge or tiny trees are divided by a power of 2
    first (as :func:`solve`): a tree scaled by 2^k gives the same result scaled.

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
        raise ValueError(f"targets must be a non-empty mapping joint index → target, got {_checks.shown(targets)}")
    # Keys and parents are checked for type and shape before the cache: 2.0 and True hash as 2 and 1, and a
    # flattened (1, J) array as its (J,) row, so the cache would otherwise answer for input it must refuse.
    for key in targets:
        if isinstance(key, bool) or not isinstance(key, (int, np.integer)) or not 0 <= key < count:
            raise ValueError(f"targets keys must be joint indices in [0, {count - 1}], got {_checks.shown(key)}")
    keys = tuple(sorted(int(key) for key in targets))
    try:
        raw = np.asarray(parents)
    except (TypeError, ValueError):
        raw = None
    if raw is not None and raw.dtype.kind in "iu" and raw.shape == (count,) and not _checks.holds_booleans(parents):
        topology = _tree_topology(tuple(raw.tolist()), count, keys)
    else:  # refused (ValueError naming parents) without the cache
        topology = _tree_topology.__wrapped__(parents, count, keys)
    order, parent, active, has_goal, effector_ids, is_chain = topology
    goal = np.zeros((count, 3))
    for key in effector_ids.tolist():
        goal[key, :dim] = _check_vector(f"targets[{key}]", targets[key], dim)
    setup = _Setup.build(dim, tolerance, max_iterations, None, obstacles, root_direction, _FABRIK, False)
    root = int(order[0])
    table = _tree_table(constraints, count, dim, root)
    tol = float(setup.params[0])

    if is_chain:  # one chain: solve's result
        chain_constraints = None if constraints is None else [constraints[j] for j in order[1:]]
        single = _solve_single(
            "fabrik",
            points[order],
            goal[effector_ids[0], :dim],
            tol,
            setup.max_iterations,
            None,
            obstacles,
            root_direction,
            True,
            chain_constraints,
        )
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

    # Each target within _FARTHEST times the whole tree's length of the root, as solve's target of its chain.
    children = np.flatnonzero(parent >= 0)
    total = float(_norms(points[children] - points[parent[children]]).sum())
    reach = _norms(goal[effector_ids, :dim] - points[root])
    far = np.flatnonzero(reach / _FARTHEST > total) if total > 0.0 else np.empty(0, dtype=np.int64)
    if far.size:
        key = int(effector_ids[far[0]])
        raise ValueError(
            f"targets[{key}] is {reach[far[0]]:.3g} m from the root, more than {_FARTHEST:g} times the tree's length "
            f"({total:.3g} m): too far to solve"
        )
    origin = max(float(np.abs(points).max()), float(np.abs(goal[effector_ids, :dim]).max()))
    if total > 0.0 and origin / _FARTHEST > total:
        raise ValueError(
            f"joints and targets lie {origin:.3g} m from the origin, more than {_FARTHEST:g} times the tree's length "
            f"({total:.3g} m): the rounding of the coordinates alone changes its links; solve it with the origin nearer"
        )
    p = np.zeros((count, 3))
    p[:, :dim] = points
    history = np.empty((setup.max_iterations + 1, len(effector_ids)))
    codes = np.empty(len(effector_ids), dtype=np.int64)
    final = np.empty(len(effector_ids))
    # As solve: about the root (a coordinate far out rounds to a share of its own size, not the tree's), and divided
    # by a power of 2 near the extent (exact), so squared norms neither overflow nor underflow
    anchor = p[root].copy()
    p -= anchor
    goal = goal - anchor
    scale, centres, radii = 1.0, setup.centres - anchor, setup.radii
    extent = _tree_extent_entry(p, goal, effector_ids, root)
    if extent != 0.0 and not _UNSCALED[0] <= extent <= _UNSCALED[1]:
        scale = math.ldexp(1.0, math.frexp(extent)[1])
        p /= scale
        goal /= scale
        tol, centres, radii = tol / scale, centres / scale, radii / scale
    iterations = _solve_tree_core_entry(
        p,
        parent,
        order,
        active,
        goal,
        has_goal,
        effector_ids,
        table,
        setup.root_direction,
        centres,
        radii,
        tol,
        setup.max_iterations,
        dim,
        history,
        codes,
        final,
    )
    if scale != 1.0:
        p *= scale
        history *= scale
        final *= scale
    p += anchor
    if iterations == 0:  # a start returned as it stands: its own coordinates, not their round trip about the root
        p[:, :dim] = points
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
) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.bool_], NDArray[np.bool_], NDArray[np.int64], bool]:
    """Checked tree structure: breadth-first order, parents, the joints that take part in the forward stage (a
    target beyond them), the targeted joints, the effectors (ascending) and whether the tree is one chain. Cached:
    a dragged skeleton asks for the same every frame (the arrays are never written to)."""
    try:
        raw = np.asarray(parents)
    except (TypeError, ValueError) as error:
        raise ValueError(f"parents must be a ({count},) array of integers, got {_checks.shown(parents)}") from error
    if (
        raw.shape != (count,)
        or raw.dtype.kind not in "iu"
        or _checks.holds_booleans(parents)  # numpy reads [-1, False, True] as integers
        or np.any(raw < -1)
        or np.any(raw >= count)
    ):
        raise ValueError(f"parents must be ({count},) integers in [−1, {count - 1}], got {_checks.shown(parents)}")
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
        raise ValueError("parents must form one tree: some joints are on a cycle, not under the root")
    has_goal = np.zeros(count, dtype=np.bool_)
    for key in keys:
        if isinstance(key, bool) or not isinstance(key, (int, np.integer)) or not 0 <= key < count:
            raise ValueError(f"targets keys must be joint indices in [0, {count - 1}], got {_checks.shown(key)}")
        if children[key]:
            raise ValueError(f"targets[{key}] is on a joint with children: targets go on end effectors")
        has_goal[key] = True
    active = has_goal.copy()
    for j in reversed(order):  # a joint takes part in the forward stage when a target lies beyond it
        if active[j] and parent[j] >= 0:
            active[parent[j]] = True
    effectors = np.flatnonzero(has_goal).astype(np.int64)
    is_chain = all(len(c) <= 1 for c in children)
    return np.array(order, dtype=np.int64), parent, active, has_goal, effectors, is_chain


def _tree_table(constraints: Sequence[Constraint] | None, count: int, dim: int, root: int) -> NDArray[np.float64]:
    """The checked limit table of a tree (one row per joint), cached on hashable constraints."""
    if constraints is None:
        return np.zeros((count, _TABLE_WIDTH))
    try:
        return _tree_table_cached(tuple(constraints), count, dim, root)
    except TypeError:  # unhashable entries: checked (and refused) without the cache
        return _tree_table_cached.__wrapped__(constraints, count, dim, root)


@functools.lru_cache(maxsize=64)
def _tree_table_cached(constraints: Sequence[Constraint], count: int, dim: int, root: int) -> NDArray[np.float64]:
    if isinstance(constraints, Sequence) and len(constraints) == count and constraints[root] is not None:
        raise ValueError(f"constraints[{root}] must be None: the root has no segment")
    return _limit_table(constraints, count, dim, "constraints", segment_offset=0)


@compiled(from_python=True, error_model="numpy")
def _solve_tree_core(
    p: NDArray[np.float64],
    parents: NDArray[np.int64],
    order: NDArray[np.int64],
    active: NDArray[np.bool_],
    goal: NDArray[np.float64],
    has_goal: NDArray[np.bool_],
    effectors: NDArray[np.int64],
    table: NDArray[np.float64],
    rest: NDArray[np.float64],
    centres: NDArray[np.float64],
    radii: NDArray[np.float64],
    tolerance: float,
    max_iterations: int,
    dim: int,
    history: NDArray[np.float64],
    codes: NDArray[np.int64],
    final: NDArray[np.float64],
) -> int:
    """Multi-end-effector FABRIK on ``p`` (J, 3), in place; ``order`` is breadth first from the root.

    Leaves the returned pose in ``p``: the last iterate where it keeps every limit and clears every live obstacle
    (and, after a restart, is not worse than the best pose before or after it), else the best (smallest largest
    error) that did, else the last. Fills ``history`` (max_iterations + 1, E) with the iterates' errors, NaN past
    the last iteration, ``final`` (E,) with the returned pose's errors and ``codes`` (E,) with each effector's
    status: reached (error ≤ tolerance, on an admissible pose); unreachable (farther from the root than its path's
    length); blocked (target inside a live obstacle, or the pose touching one); limited (stopped at a fixed point
    while limits or obstacles hold the tree); infeasible (no admissible pose seen); max_iterations. Returns the
    iterations run. Every test is relative to the tree's size (no absolute floor), so a tree scaled by a power of 2
    gives the same bits scaled."""
    count = p.shape[0]
    root = int(order[0])
    for row in range(history.shape[0]):  # loops, here and below: slice assignments compile overloads of their own
        for e in range(history.shape[1]):
            history[row, e] = np.nan
    has_limits, holding = _limit_flags(table)
    limits = (has_limits, table)
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
    any_live = _mark_live(centres, radii, live, p[root, 0], p[root, 1], p[root, 2])
    obstacles = (centres, radii, live)
    # As solve, the fixed-point rule stops a tree only where limits or obstacles can hold it, or where some
    # effector's target is out of its path's reach; a free tree within reach iterates on to the cap.
    out_of_reach = False
    for e in range(effectors.shape[0]):
        out_of_reach = out_of_reach or _out_of_reach(p, parents, lengths, goal, int(effectors[e]), root, tiny)
    stall_applies = holding or any_live or out_of_reach
    best = np.empty((count, 3))
    _copy(p, best)
    best_worst = np.inf
    bx, by, bz = p[root, 0], p[root, 1], p[root, 2]
    directions = np.zeros((count, 3))  # each joint's segment direction (its parent's where it has none)
    directions[root, 0], directions[root, 1], directions[root, 2] = rest[0], rest[1], rest[2]
    for k in range(1, count):
        j = int(order[k])
        up = int(parents[j])
        ux, uy, uz, _ = _unit(
            p[j, 0] - p[up, 0],
            p[j, 1] - p[up, 1],
            p[j, 2] - p[up, 2],
            directions[up, 0],
            directions[up, 1],
            directions[up, 2],
            tiny,
        )
        directions[j, 0], directions[j, 1], directions[j, 2] = ux, uy, uz
    sums = np.zeros((count, 3))
    counts = np.empty(count, dtype=np.int64)
    only_child = np.empty(count, dtype=np.int64)  # the one active child, where a joint has one (-1: none yet)
    for j in range(count):
        counts[j], only_child[j] = 0, -1
    for j in range(count):
        up = int(parents[j])
        if up >= 0 and active[j]:
            only_child[up] = j if counts[up] == 0 else -1
            counts[up] += 1

    worst = _tree_errors(p, goal, effectors, history, int(_ROW_0))
    if _tree_admissible(p, parents, order, table, rest, tiny, has_limits, obstacles):
        best_worst = worst
        if worst <= tolerance:  # the start is returned as reached only where it keeps every limit
            for e in range(final.shape[0]):
                final[e] = history[0, e]
            no = bool(_OFF)
            _tree_statuses(p, parents, goal, effectors, lengths, obstacles, tolerance, tiny, final, no, no, codes)
            return 0
    stall = _STALL * tolerance + tiny
    iterations, stalled, retry = 0, False, True
    for iteration in range(1, max_iterations + 1):
        iterations = iteration
        # forward stage: effectors on their targets, sub-bases at the centroid of their branches' proposals
        for j in range(count):
            sums[j, 0], sums[j, 1], sums[j, 2], counts[j] = 0.0, 0.0, 0.0, 0
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
            dx, dy, dz, _ = _unit(
                p[up, 0] - x, p[up, 1] - y, p[up, 2] - z, -directions[j, 0], -directions[j, 1], -directions[j, 2], tiny
            )
            c = only_child[j]
            if c >= 0 and not has_goal[j]:  # the joint to its one child holds this segment (as in a chain)
                qx, qy, qz, _ = _unit(x - p[c, 0], y - p[c, 1], z - p[c, 2], dx, dy, dz, tiny)
                dx, dy, dz = _hold_by_next(dx, dy, dz, qx, qy, qz, table, c, rest, dim)
            # keep the segment in its hinge's plane (caliko's forward pass)
            dx, dy, dz = _into_hinge_plane(
                dx, dy, dz, directions[up, 0], directions[up, 1], directions[up, 2], table, j, rest
            )
            if radii.shape[0] > 0:
                dx, dy, dz, _ = _deflect(x, y, z, dx, dy, dz, lengths[j], obstacles, tiny, dim)
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
            length = lengths[j]
            dx, dy, dz = _backward_step(
                ax, ay, az, p[j, 0], p[j, 1], p[j, 2], qx, qy, qz, length, j, rest, limits, obstacles, tiny, dim
            )
            p[j, 0], p[j, 1], p[j, 2] = ax + length * dx, ay + length * dy, az + length * dz
            if length > tiny:
                directions[j, 0], directions[j, 1], directions[j, 2] = dx, dy, dz
            else:
                directions[j, 0], directions[j, 1], directions[j, 2] = qx, qy, qz
        worst = _tree_errors(p, goal, effectors, history, iteration)
        # Checked only where it matters, since it costs a pass of its own: a pose within tolerance, or a better one
        # where the last iterate may not be the one returned (live obstacles can leave it cutting one; after a
        # restart the best is returned), or any while none was admissible (a start that breaks a limit: without
        # it, "infeasible" was said of iterates that kept every one). The backward stage keeps every limit on
        # every iterate.
        track = any_live or not retry or best_worst == np.inf
        admissible = (worst <= tolerance or (track and worst < best_worst)) and _tree_admissible(
            p, parents, order, table, rest, tiny, has_limits, obstacles
        )
        if admissible and worst < best_worst:
            _copy(p, best)  # a loop: an array copy compiles numba's shape checks for seconds
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
            if retry and iteration < max_iterations and worst > tiny:
                # A free tree within reach at a fixed point of the centroid rule (a mirror-symmetric start keeps
                # it symmetric): go on once from every segment turned aside, another basin; then on to the cap.
                # Not a tree already on its targets to rounding (tolerance 0 asks for more than rounding gives):
                # turned aside, it left them by 1.7 m.
                retry = False
                if worst < best_worst and _tree_admissible(p, parents, order, table, rest, tiny, has_limits, obstacles):
                    _copy(p, best)  # the basin it leaves, so that the restart is never worse than where it stood
                    best_worst = worst
                _tree_turn_aside(p, parents, order, lengths, tiny, dim)
    feasible = best_worst < np.inf
    if feasible and (
        (not retry and best_worst < worst - stall)  # restarted: the best before or after it, the last among equals
        or not _tree_admissible(p, parents, order, table, rest, tiny, has_limits, obstacles)
    ):
        _copy(best, p)  # never an inadmissible last iterate where an admissible one was seen
    for e in range(effectors.shape[0]):
        k = int(effectors[e])
        x, y, z = p[k, 0] - goal[k, 0], p[k, 1] - goal[k, 1], p[k, 2] - goal[k, 2]
        final[e] = math.sqrt(x * x + y * y + z * z)
    _tree_statuses(
        p, parents, goal, effectors, lengths, obstacles, tolerance, tiny, final, stalled, holding or any_live, codes
    )
    if not feasible:
        for e in range(codes.shape[0]):
            codes[e] = _INFEASIBLE
    return iterations


@compiled(from_python=True, error_model="numpy")
def _tree_extent(p: NDArray[np.float64], goal: NDArray[np.float64], effectors: NDArray[np.int64], root: int) -> float:
    """The largest coordinate offset from the root of a joint or a target (m)."""
    extent = 0.0
    for j in range(p.shape[0]):
        for c in range(3):
            extent = max(extent, abs(p[j, c] - p[root, c]))
    for e in range(effectors.shape[0]):
        for c in range(3):
            extent = max(extent, abs(goal[int(effectors[e]), c] - p[root, c]))
    return extent


@compiled(error_model="numpy")
def _tree_turn_aside(
    p: NDArray[np.float64],
    parents: NDArray[np.int64],
    order: NDArray[np.int64],
    lengths: NDArray[np.float64],
    tiny: float,
    dim: int,
) -> None:
    """Turn every segment of the pose ``p`` (in place, root fixed, lengths kept) by 1 to 2 rad about an axis
    across it, the angles and axes spread by the golden ratio over the breadth-first order (deterministic, and
    different for mirror-image branches)."""
    old = np.empty((p.shape[0], 3))
    _copy(p, old)
    golden = 0.6180339887498949
    for k in range(1, p.shape[0]):
        j = int(order[k])
        up = int(parents[j])
        dx, dy, dz, _ = _unit(
            old[j, 0] - old[up, 0], old[j, 1] - old[up, 1], old[j, 2] - old[up, 2], 0.0, 0.0, 1.0, tiny
        )
        spread = (k * golden) % 1.0
        angle = 1.0 + spread
        if dim == 2:
            ax, ay, az = 0.0, 0.0, 1.0
            angle = angle if k % 2 else -angle
        else:
            px, py, pz = _perpendicular(dx, dy, dz, int(_DIM_3D))
            ax, ay, az = _rotate(px, py, pz, dx, dy, dz, 2.0 * math.pi * ((k * golden * golden) % 1.0))
        dx, dy, dz = _rotate(dx, dy, dz, ax, ay, az, angle)
        p[j, 0] = p[up, 0] + lengths[j] * dx
        p[j, 1] = p[up, 1] + lengths[j] * dy
        p[j, 2] = p[up, 2] + lengths[j] * dz


@compiled(error_model="numpy")
def _tree_admissible(
    p: NDArray[np.float64],
    parents: NDArray[np.int64],
    order: NDArray[np.int64],
    table: NDArray[np.float64],
    rest: NDArray[np.float64],
    tiny: float,
    has_limits: bool,
    obstacles: Obstacles,
) -> bool:
    """Whether the tree's pose keeps every joint limit (each segment against its parent's, the root's against
    ``rest``; zero-length segments have none and pass their parent's on) and cuts no live obstacle."""
    if not has_limits and obstacles[1].shape[0] == 0:  # no limits and no obstacle at all
        return True
    count = p.shape[0]
    directions = np.empty((count, 3))
    root = int(order[0])
    directions[root, 0], directions[root, 1], directions[root, 2] = rest[0], rest[1], rest[2]
    for k in range(1, count):
        j = int(order[k])
        up = int(parents[j])
        qx, qy, qz = directions[up, 0], directions[up, 1], directions[up, 2]
        dx, dy, dz, norm = _unit(p[j, 0] - p[up, 0], p[j, 1] - p[up, 1], p[j, 2] - p[up, 2], qx, qy, qz, tiny)
        if norm <= tiny:
            directions[j, 0], directions[j, 1], directions[j, 2] = qx, qy, qz
            continue
        if has_limits and not _joint_ok(dx, dy, dz, qx, qy, qz, table, j, rest, tiny):
            return False
        directions[j, 0], directions[j, 1], directions[j, 2] = dx, dy, dz
        if _segment_cuts(p, up, j, obstacles, 1.0):
            return False
    return True


@compiled(error_model="numpy")
def _out_of_reach(
    p: NDArray[np.float64],
    parents: NDArray[np.int64],
    lengths: NDArray[np.float64],
    goal: NDArray[np.float64],
    key: int,
    root: int,
    tiny: float,
) -> bool:
    """Whether effector ``key``'s target lies outside the annulus its path from the root reaches (as solve's: the
    path's length outside, twice its longest link less that length inside)."""
    reach, longest, j = 0.0, 0.0, key
    while parents[j] >= 0:
        reach += lengths[j]
        longest = max(longest, lengths[j])
        j = int(parents[j])
    inner = max(0.0, 2.0 * longest - reach)
    dx, dy, dz = goal[key, 0] - p[root, 0], goal[key, 1] - p[root, 1], goal[key, 2] - p[root, 2]
    distance = math.sqrt(dx * dx + dy * dy + dz * dz)
    return distance > reach + tiny or distance < inner - tiny


@compiled(error_model="numpy")
def _tree_statuses(
    p: NDArray[np.float64],
    parents: NDArray[np.int64],
    goal: NDArray[np.float64],
    effectors: NDArray[np.int64],
    lengths: NDArray[np.float64],
    obstacles: Obstacles,
    tolerance: float,
    tiny: float,
    error: NDArray[np.float64],
    stalled: bool,
    held: bool,
    codes: NDArray[np.int64],
) -> None:
    """Each effector's status code (see :func:`_solve_tree_core`); ``held``: limits or live obstacles can hold the
    tree at a fixed point (else a stall is another effector's target out of reach: "unreachable")."""
    touching = False
    if obstacles[1].shape[0] > 0:  # any obstacle at all
        for j in range(p.shape[0]):
            up = int(parents[j])
            touching = touching or (up >= 0 and _segment_cuts(p, up, j, obstacles, 1.0 + _TOUCH))
    root = 0
    while parents[root] >= 0:
        root = int(parents[root])
    for e in range(effectors.shape[0]):
        key = int(effectors[e])
        inside = _inside_live(obstacles, goal[key, 0], goal[key, 1], goal[key, 2])
        if error[e] <= tolerance:
            codes[e] = _REACHED
        elif _out_of_reach(p, parents, lengths, goal, key, root, tiny):
            codes[e] = _UNREACHABLE
        elif inside or touching:
            codes[e] = _BLOCKED
        else:
            codes[e] = (_LIMITED if held else _UNREACHABLE) if stalled else _MAX_ITERATIONS


@compiled(error_model="numpy")
def _tree_errors(
    p: NDArray[np.float64],
    goal: NDArray[np.float64],
    effectors: NDArray[np.int64],
    history: NDArray[np.float64],
    row: int,
) -> float:
    """Write each effector's distance to its target into ``history[row]``; return the largest."""
    worst = 0.0
    for e in range(effectors.shape[0]):
        k = int(effectors[e])
        x, y, z = p[k, 0] - goal[k, 0], p[k, 1] - goal[k, 1], p[k, 2] - goal[k, 2]
        history[row, e] = math.sqrt(x * x + y * y + z * z)
        worst = max(worst, history[row, e])
    return worst


# The compiled cores solve_tree calls from Python: plain Python while the app's first start compiles them
# (kernels.warming); compiled code calls the dispatchers above directly.
_solve_tree_core_entry = Entry(_solve_tree_core)
_tree_extent_entry = Entry(_tree_extent)
