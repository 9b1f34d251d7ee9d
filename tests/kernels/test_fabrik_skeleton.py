"""Hinge joints and skeletons with several end effectors: properties over random chains and trees,
iterates against a plain multi-end-effector FABRIK written here from the paper, and bad input."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from helpers.properties import examples
from hypothesis import example, given, settings
from hypothesis import strategies as st
from numpy.typing import NDArray

from kernels import fabrik
from tests.helpers.compiled import from_python

PROPERTY = settings(max_examples=examples(50), deadline=None)
Array = NDArray[np.float64]
SEEDS = st.integers(0, 2**32 - 1)


# ------------------------------------------------------------------------------------------------ plain checkers
def shortest_turn(v: Array, s: Array, t: Array) -> Array:
    """v turned by the rotation of least angle taking unit s onto unit t (Rodrigues, by angle and axis)."""
    axis = np.cross(s, t)
    sin_a, cos_a = float(np.linalg.norm(axis)), float(s @ t)
    if sin_a < 1e-12:
        if cos_a > 0:
            return v
        raise AssertionError("antiparallel: not exercised here")
    k = axis / sin_a
    return v * cos_a + np.cross(k, v) * sin_a + k * float(k @ v) * (1 - cos_a)


def hinge_violation(joints: Array, hinges: list[fabrik.Hinge], rest: Array) -> tuple[float, float]:
    """(largest |segment · axis|, largest angle outside its range in rad) over a 3D chain of hinges, computed from
    the documented semantics with plain numpy."""
    off_plane, off_range = 0.0, 0.0
    previous = rest
    for i, hinge in enumerate(hinges):
        segment = joints[i + 1] - joints[i]
        u = segment / np.linalg.norm(segment)
        axis = np.asarray(hinge.axis)
        reference = None if hinge.reference_axis is None else np.asarray(hinge.reference_axis)
        if hinge.frame == "local":
            axis = shortest_turn(axis, rest, previous)
            if reference is not None:
                reference = shortest_turn(reference, rest, previous)
        if reference is None:
            reference = previous
        reference = reference - (reference @ axis) * axis
        reference /= np.linalg.norm(reference)
        off_plane = max(off_plane, abs(float(u @ axis)))
        angle = math.atan2(float(np.cross(reference, u) @ axis), float(u @ reference))
        outside = min(
            max(hinge.min_angle_rad - a, a - hinge.max_angle_rad, 0.0)
            for a in (angle - 2 * math.pi, angle, angle + 2 * math.pi)
        )
        off_range = max(off_range, outside)
        previous = u
    return off_plane, off_range


def random_hinges(rng: np.random.Generator, n: int, frame: fabrik.HingeFrame) -> list[fabrik.Hinge]:
    """n hinges with random axes, ranges (containing 0) and, for half of them, reference axes."""
    hinges = []
    for _ in range(n):
        axis = rng.normal(size=3)
        low, high = -rng.uniform(0.1, math.pi), rng.uniform(0.1, math.pi)
        reference = rng.normal(size=3) if rng.random() < 0.5 else None
        hinges.append(fabrik.Hinge(axis, low, high, reference_axis=reference, frame=frame))
    return hinges


def random_chain(rng: np.random.Generator, n: int, d: int) -> Array:
    joints = [rng.uniform(-1.0, 1.0, d)]
    direction = np.eye(d)[-1]
    for _ in range(n):
        turn = rng.normal(size=d) * 0.6
        direction = direction + turn - (turn @ direction) * direction
        direction /= np.linalg.norm(direction)
        joints.append(joints[-1] + rng.uniform(0.2, 1.0) * direction)
    return np.array(joints)


# ------------------------------------------------------------------------------------------------ hinges
@PROPERTY
@given(
    st.integers(1, 8),
    SEEDS,
    st.sampled_from(["global", "local"]),
    st.sampled_from(["fabrik", "ccd", "jacobian_dls"]),
    st.floats(0.0, 1.5),
)
def test_a_hinge_is_never_violated_from_any_start(
    n: int, seed: int, frame: fabrik.HingeFrame, solver: fabrik.Solver, where: float
) -> None:
    rng = np.random.default_rng(seed)
    joints = random_chain(rng, n, 3)  # a random start: it breaks the hinges
    hinges = random_hinges(rng, n, frame)
    rest = np.array([0.0, 0.0, 1.0])
    if frame == "local":  # the shortest turn is undefined for antiparallel segments: not a start we draw
        hinges = [fabrik.Hinge(h.axis, h.min_angle_rad, h.max_angle_rad, h.reference_axis, "local") for h in hinges]
    total = float(fabrik.link_lengths(joints).sum())
    target = joints[0] + rng.normal(size=3) / math.sqrt(3) * where * total
    result = fabrik.solve_batch(joints[None], target[None], constraints=hinges, solver=solver, max_iterations=100)[0]
    np.testing.assert_allclose(fabrik.link_lengths(result.joints), fabrik.link_lengths(joints), rtol=1e-9)
    if result.iterations == 0:
        return  # the start already reached and kept every hinge (checked by the kernel)
    try:
        off_plane, off_range = hinge_violation(result.joints, hinges, rest)
    except AssertionError:
        return  # an antiparallel local frame: the kernel's fallback turn, which the checker does not model
    assert off_plane < 1e-8
    assert off_range < 1e-8


@PROPERTY
@given(st.integers(1, 10), SEEDS, st.floats(-2.0, 2.0))
def test_a_planar_chain_of_global_z_hinges_stays_in_its_plane(n: int, seed: int, height: float) -> None:
    rng = np.random.default_rng(seed)
    planar = random_chain(rng, n, 2)
    joints = np.column_stack([planar, np.full(n + 1, height)])  # in the plane z = height
    hinges = [fabrik.Hinge((0, 0, 1), -rng.uniform(0.2, 3.0), rng.uniform(0.2, 3.0)) for _ in range(n)]
    target = rng.uniform(-4.0, 4.0, 3)  # anywhere, also off the plane
    result = fabrik.solve(joints, target, constraints=hinges, root_direction=(1.0, 0.0, 0.0))
    np.testing.assert_allclose(result.joints[:, 2], height, atol=1e-12)


@PROPERTY
@given(st.integers(1, 10), SEEDS, st.floats(0.0, 1.3))
def test_hinge_range_limits_hold_in_the_plane(n: int, seed: int, where: float) -> None:
    rng = np.random.default_rng(seed)
    joints = random_chain(rng, n, 2)
    lows = -rng.uniform(0.0, 1.5, n)
    highs = rng.uniform(0.0, 1.5, n)
    hinges = [fabrik.Hinge((0, 0, 1), lo, hi) for lo, hi in zip(lows, highs, strict=True)]
    total = float(fabrik.link_lengths(joints).sum())
    angle = rng.uniform(0, 2 * math.pi)
    target = joints[0] + where * total * np.array([math.cos(angle), math.sin(angle)])
    result = fabrik.solve(joints, target, constraints=hinges, max_iterations=100)
    if result.iterations == 0:
        return
    # Joint angles by atan2 of consecutive segments (the first from the root direction +y).
    segments = np.diff(result.joints, axis=0)
    headings = np.arctan2(segments[:, 1], segments[:, 0])
    previous = np.concatenate([[math.pi / 2], headings[:-1]])
    turns = (headings - previous + math.pi) % (2 * math.pi) - math.pi
    assert np.all(turns >= lows - 1e-9)
    assert np.all(turns <= highs + 1e-9)
    usage = fabrik.limit_usage(result.joints, hinges)
    assert np.all((usage >= 0.0) & (usage <= 1.0))


@PROPERTY
@given(st.integers(2, 10), SEEDS, st.floats(0.0, 1.0), st.booleans())
def test_free_hinges_reach_every_reachable_target_in_their_plane(n: int, seed: int, where: float, local: bool) -> None:
    rng = np.random.default_rng(seed)
    joints = np.column_stack([random_chain(rng, n, 2), np.zeros(n + 1)])
    inner, outer = fabrik.reach_limits(fabrik.link_lengths(joints))
    radius = inner + (0.05 + 0.9 * where) * (outer - inner)  # clear of the annulus edges (see test_fabrik)
    angle = rng.uniform(0, 2 * math.pi)
    target = joints[0] + radius * np.array([math.cos(angle), math.sin(angle), 0.0])
    hinges = [fabrik.Hinge((0, 0, 1), frame="local" if local else "global")] * n
    tolerance = 1e-3 * outer
    result = fabrik.solve(
        joints, target, constraints=hinges, tolerance=tolerance, max_iterations=3000, root_direction=(0.0, 1.0, 0.0)
    )
    assert result.status == "reached"
    assert np.linalg.norm(result.joints[-1] - target) < tolerance


def test_a_list_of_equal_cones_is_the_shorthand_bit_for_bit() -> None:
    rng = np.random.default_rng(4)
    joints = random_chain(rng, 7, 3)
    target = joints[0] + np.array([1.5, 0.5, 1.0])
    obstacles = [(joints[0] + np.array([0.5, 0.2, 0.8]), 0.2)]
    shorthand = fabrik.solve(joints, target, cone_half_angle_rad=0.5, obstacles=obstacles)
    listed = fabrik.solve(joints, target, constraints=[fabrik.Cone(0.5)] * 7, obstacles=obstacles)
    assert np.array_equal(shorthand.joints, listed.joints)
    assert shorthand.iterations == listed.iterations
    assert shorthand.status == listed.status


def test_batch_with_hinges_gives_each_chain_its_single_solve() -> None:
    rng = np.random.default_rng(9)
    chains = np.stack([random_chain(rng, 5, 3) for _ in range(6)])
    targets = chains[:, 0] + rng.normal(size=(6, 3))
    hinges = random_hinges(rng, 5, "local")
    batch = fabrik.solve_batch(chains, targets, constraints=hinges)
    for b in range(6):
        single = fabrik.solve(chains[b], targets[b], constraints=hinges)
        assert np.array_equal(batch.joints[b], single.joints)
        assert batch[b].status == single.status


def test_a_straight_hinge_range_of_zero_fixes_the_segment() -> None:
    """min = max with a global reference: the segment is welded along the reference (how a palm is built)."""
    joints = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, 2.0]])
    weld = fabrik.Hinge((0, 1, 0), 0.3, 0.3, reference_axis=(0, 0, 1))
    result = fabrik.solve(joints, (2.0, 0.0, 0.5), constraints=[weld, None])
    np.testing.assert_allclose(result.joints[1], (math.sin(0.3), 0.0, math.cos(0.3)), atol=1e-12)


# ------------------------------------------------------------------------------------------------ plain tree reference
def tree_reference(parents: list[int], joints: Array, targets: dict[int, Array], iterations: int) -> list[Array]:
    """Poses after each iteration of multi-end-effector FABRIK (Aristidou & Lasenby 2011, §4.2), plainly.

    Forward: each effector on its target, each joint pulled toward its parent (λ = d / |p_parent − p_j|); a joint
    with several branches goes to the centroid of the positions they give it. Backward: the root back, each joint
    pulled toward its parent's new place. Branches without a target only follow."""
    p = np.array(joints, dtype=np.float64)
    count = len(parents)
    root = parents.index(-1)
    children: list[list[int]] = [[] for _ in range(count)]
    for j, up in enumerate(parents):
        if up >= 0:
            children[up].append(j)
    order = [root]
    for j in order:
        order.extend(children[j])
    d = {j: float(np.linalg.norm(p[j] - p[parents[j]])) for j in range(count) if parents[j] >= 0}

    def leads_to_target(j: int) -> bool:
        return j in targets or any(leads_to_target(c) for c in children[j])

    base = p[root].copy()
    poses = []
    for _ in range(iterations):
        proposals: dict[int, list[Array]] = {j: [] for j in range(count)}
        for j in reversed(order[1:]):
            if not leads_to_target(j):
                continue
            p[j] = targets[j] if j in targets else np.mean(proposals[j], axis=0)
            up = parents[j]
            lam = d[j] / float(np.linalg.norm(p[up] - p[j]))
            proposals[up].append((1 - lam) * p[j] + lam * p[up])
        p[root] = base
        for j in order[1:]:
            up = parents[j]
            lam = d[j] / float(np.linalg.norm(p[j] - p[up]))
            p[j] = (1 - lam) * p[up] + lam * p[j]
        poses.append(p.copy())
    return poses


def random_tree(rng: np.random.Generator, count: int, d: int) -> tuple[list[int], Array]:
    """A random tree of ``count`` joints (joint j's parent among 0…j − 1) with links of 0.3–1 m."""
    parents = [-1] + [int(rng.integers(0, j)) for j in range(1, count)]
    joints = np.zeros((count, d))
    for j in range(1, count):
        joints[j] = joints[parents[j]] + rng.uniform(0.3, 1.0) * (np.eye(d)[-1] + 0.8 * rng.normal(size=d))
    return parents, joints


def leaves(parents: list[int]) -> list[int]:
    return [j for j in range(len(parents)) if j not in parents]


@PROPERTY
@given(st.integers(4, 14), SEEDS, st.sampled_from([2, 3]), st.integers(1, 6))
@example(count=6, seed=74720, d=3, k=6)  # on its target to 4e-16 m at 5: turned aside as a stall, 1.7 m off at 6
def test_tree_iterates_are_the_papers_algorithm(count: int, seed: int, d: int, k: int) -> None:
    rng = np.random.default_rng(seed)
    parents, joints = random_tree(rng, count, d)
    if all(parents.count(j) <= 1 for j in range(count)):
        return  # one chain: solve's own result, tested below
    ends = leaves(parents)
    chosen = [e for e in ends if rng.random() < 0.7] or ends[:1]
    targets = {e: joints[e] + rng.normal(size=d) for e in chosen}
    result = fabrik.solve_tree(parents, joints, targets, tolerance=0.0, max_iterations=k)
    reference = tree_reference(parents, joints, targets, k)
    assert 1 <= result.iterations <= k
    np.testing.assert_allclose(result.joints, reference[result.iterations - 1], atol=1e-9)
    lengths = [np.linalg.norm(joints[j] - joints[parents[j]]) for j in range(1, count)]
    got = [np.linalg.norm(result.joints[j] - result.joints[parents[j]]) for j in range(1, count)]
    np.testing.assert_allclose(got, lengths, rtol=1e-12)


@PROPERTY
@given(st.integers(2, 10), SEEDS, st.sampled_from([2, 3]), st.booleans())
def test_a_tree_that_is_one_chain_gives_solves_result(n: int, seed: int, d: int, hinged: bool) -> None:
    rng = np.random.default_rng(seed)
    chain = random_chain(rng, n, d)
    target = chain[0] + rng.normal(size=d)
    constraints: list[fabrik.Constraint] | None = None
    if hinged:
        axis = (0, 0, 1) if d == 2 else tuple(rng.normal(size=3))
        constraints = [fabrik.Hinge(axis, -1.0, 1.0) for _ in range(n)]
    expected = fabrik.solve(chain, target, constraints=constraints)
    # The same chain with its joints stored in a shuffled order.
    order = rng.permutation(n + 1)
    where = np.argsort(order)  # where[chain index] = stored index
    parents = [-1 if order[s] == 0 else int(where[order[s] - 1]) for s in range(n + 1)]
    stored_constraints = None
    if constraints is not None:
        stored_constraints = [None if order[s] == 0 else constraints[order[s] - 1] for s in range(n + 1)]
    result = fabrik.solve_tree(parents, chain[order], {int(where[n]): target}, constraints=stored_constraints)
    assert np.array_equal(result.joints[where], expected.joints)
    assert result.status == (expected.status,)
    assert result.iterations == expected.iterations
    assert result.error[0] == expected.error


def pose_tree(rng: np.random.Generator, parents: list[int], joints: Array) -> Array:
    """The same tree (same link lengths) in another random pose."""
    posed = joints.copy()
    for j in range(1, len(parents)):
        length = float(np.linalg.norm(joints[j] - joints[parents[j]]))
        direction = np.eye(joints.shape[1])[-1] + 0.8 * rng.normal(size=joints.shape[1])
        posed[j] = posed[parents[j]] + length * direction / np.linalg.norm(direction)
    return posed


@PROPERTY
@given(st.integers(2, 5), st.integers(1, 4), SEEDS, st.sampled_from([2, 3]))
def test_reachable_effectors_on_separate_branches_reach(branches: int, links: int, seed: int, d: int) -> None:
    """Branches that meet only at the root do not conflict: every effector reaches a target its branch can reach."""
    rng = np.random.default_rng(seed)
    parents = [-1]
    for _ in range(branches):
        parents.append(0)
        for _ in range(links - 1):
            parents.append(len(parents) - 1)
    count = len(parents)
    joints = np.zeros((count, d))
    for j in range(1, count):
        joints[j] = joints[parents[j]] + rng.uniform(0.3, 1.0) * np.eye(d)[-1]
    goal_pose = pose_tree(rng, parents, joints)  # the targets: a pose the tree can take
    targets = {e: goal_pose[e] for e in leaves(parents)}
    start = pose_tree(rng, parents, joints)
    result = fabrik.solve_tree(parents, start, targets, tolerance=1e-3, max_iterations=3000)
    if links == 1:
        assert all(s in ("reached", "unreachable", "limited") for s in result.status)
        return  # one link only reaches its own circle
    inner = [
        fabrik.reach_limits(fabrik.link_lengths(start[[0, *range(1 + b * links, 1 + (b + 1) * links)]]))
        for b in range(branches)
    ]
    for e, key in enumerate(result.effectors):
        b = (int(key) - 1) // links
        radius = float(np.linalg.norm(targets[int(key)]))
        lo, hi = inner[b]
        if lo + 0.02 * hi < radius < 0.98 * hi:  # clear of the annulus edges
            assert result.status[e] == "reached"
            assert result.error[e] < 1e-3


def y_tree() -> tuple[list[int], Array]:
    """Root, a trunk of two links to a sub-base, and two arms of two links each, mirror-symmetric in x."""
    parents = [-1, 0, 1, 2, 3, 2, 5]
    joints = np.array([[0.0, 0.0], [0.0, 0.5], [0.0, 1.0], [-0.4, 1.3], [-0.8, 1.6], [0.4, 1.3], [0.8, 1.6]])
    return parents, joints


@pytest.mark.parametrize("spread", [2.0, 3.0, 5.0])
def test_conflicting_targets_settle_at_the_centroid_compromise(spread: float) -> None:
    """Two arms pulled apart beyond their reach: the sub-base stays on the mirror line, at the fixed point of the
    centroid rule (one more iteration of the paper's algorithm leaves it), and no error grows."""
    parents, joints = y_tree()
    targets = {4: np.array([-spread, 1.2]), 6: np.array([spread, 1.2])}
    result = fabrik.solve_tree(parents, joints, targets, tolerance=1e-6, max_iterations=200)
    assert abs(result.joints[2, 0]) < 1e-9
    again = tree_reference(parents, result.joints, targets, 1)[0]
    np.testing.assert_allclose(again, result.joints, atol=1e-5)
    growth = np.diff(result.error_history, axis=0)
    assert growth.max() <= 1e-12
    np.testing.assert_allclose(result.error[0], result.error[1], rtol=1e-12)
    assert result.status == ("unreachable", "unreachable") or spread == 2.0


@PROPERTY
@given(SEEDS, st.floats(0.5, 3.0))
def test_conflicting_targets_settle_at_a_fixed_point_of_the_centroid_rule(seed: int, spread: float) -> None:
    rng = np.random.default_rng(seed)
    parents, joints = y_tree()
    targets = {4: rng.normal(size=2) * spread, 6: rng.normal(size=2) * spread}
    result = fabrik.solve_tree(parents, joints, targets, tolerance=1e-4, max_iterations=500)
    if all(s == "reached" for s in result.status):
        return
    # No limits: never "limited"; the fixed-point rule stops the tree only where a target is out of its reach,
    # otherwise it goes on (restarting once from a turned pose) to the cap.
    assert "limited" not in result.status
    # to the cap (a free tree within reach, creeping or restarted once): the last iterate or a better one
    if result.iterations == 500:
        assert result.error.max() <= result.error_history[-1].max()
        return
    assert "unreachable" in result.status  # stopped at a fixed point: some target is out of reach
    again = tree_reference(parents, result.joints, targets, 1)[0]
    np.testing.assert_allclose(again, result.joints, atol=1e-3)


def test_the_papers_centroid_rule_can_trade_one_effectors_error_for_the_others() -> None:
    """Found by the property above: with asymmetric conflicting targets the summed error of multi-end-effector
    FABRIK grows by up to 5e-5 m in an iteration; the plain reference grows by exactly as much, so this is the
    algorithm's (Aristidou & Lasenby 2011 claim no descent), not the kernel's."""
    rng = np.random.default_rng(170)
    parents, joints = y_tree()
    targets = {4: rng.normal(size=2) * 2.0, 6: rng.normal(size=2) * 2.0}
    result = fabrik.solve_tree(parents, joints, targets, tolerance=1e-4, max_iterations=200)
    reference = tree_reference(parents, joints, targets, result.iterations)
    errors = np.array([[np.linalg.norm(p[k] - targets[k]) for k in (4, 6)] for p in reference])
    np.testing.assert_allclose(result.error_history[1:], errors, atol=1e-9)
    growth = np.diff(result.error_history.sum(axis=1)[1:])
    assert 1e-5 < growth.max() < 1e-4


def test_tree_with_hinges_keeps_them_and_follows_untargeted_branches() -> None:
    parents, joints = y_tree()
    hinges: list[fabrik.Constraint] = [None, *[fabrik.Hinge((0, 0, 1), -0.6, 0.6)] * 6]
    result = fabrik.solve_tree(parents, joints, {4: np.array([-1.2, 1.0])}, constraints=hinges)
    for j in range(1, 7):
        segment = result.joints[j] - result.joints[parents[j]]
        up = parents[j]
        before = np.array([0.0, 1.0]) if up == 0 else result.joints[up] - result.joints[parents[up]]
        turn = math.atan2(before[0] * segment[1] - before[1] * segment[0], before @ segment)
        assert -0.6 - 1e-9 <= turn <= 0.6 + 1e-9
    # The untargeted arm (5, 6) kept its lengths and followed the sub-base.
    np.testing.assert_allclose(np.linalg.norm(result.joints[5] - result.joints[2]), 0.5, rtol=1e-12)
    assert result.effectors.tolist() == [4]


# ------------------------------------------------------------------------------------------------ bad input
CHAIN2 = [[0.0, 0.0], [0.0, 1.0], [0.0, 2.0]]
PARENTS = [-1, 0, 1, 1]
BAD_CONSTRAINT: Any = "hinge"
"""A constraint a caller could send that is not a :data:`fabrik.Constraint`."""
TREE = [[0.0, 0.0], [0.0, 1.0], [-1.0, 2.0], [1.0, 2.0]]


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (lambda: fabrik.Hinge((0, 0, 0)), "axis"),
        (lambda: fabrik.Hinge((0, 0, np.nan)), "axis"),
        (lambda: fabrik.Hinge((0, 0, 1), 1.0, 0.5), "max_angle_rad"),
        (lambda: fabrik.Hinge((0, 0, 1), -4.0), "min_angle_rad"),
        (lambda: fabrik.Hinge((0, 0, 1), reference_axis=(0, 0, 2)), "reference_axis"),
        (lambda: fabrik.Hinge((0, 0, 1), frame="world"), "frame"),  # type: ignore[arg-type]
        (lambda: fabrik.Cone(-0.1), "half_angle_rad"),
        (lambda: fabrik.solve(CHAIN2, [1, 1], constraints=[None]), "constraints"),
        (lambda: fabrik.solve(CHAIN2, [1, 1], constraints=[None, BAD_CONSTRAINT]), r"constraints\[1\]"),
        (lambda: fabrik.solve(CHAIN2, [1, 1], constraints=[fabrik.Hinge((1, 0, 0)), None]), r"constraints\[0\].axis"),
        (
            lambda: fabrik.solve(CHAIN2, [1, 1], cone_half_angle_rad=0.5, constraints=[None, None]),
            "cone_half_angle_rad",
        ),
        (lambda: fabrik.solve_tree([-1, -1, 1, 1], TREE, {2: [0, 0]}), "parents"),
        (lambda: fabrik.solve_tree([-1, 2, 1, 1], TREE, {3: [0, 0]}), "parents"),
        (lambda: fabrik.solve_tree([-1, 0, 1], TREE, {2: [0, 0]}), "parents"),
        (lambda: fabrik.solve_tree([-1.0, 0, 1, 1], TREE, {2: [0, 0]}), "parents"),
        (lambda: fabrik.solve_tree(PARENTS, TREE, {1: [0, 0]}), r"targets\[1\]"),
        (lambda: fabrik.solve_tree(PARENTS, TREE, {}), "targets"),
        (lambda: fabrik.solve_tree(PARENTS, TREE, {9: [0, 0]}), "targets keys"),
        (lambda: fabrik.solve_tree(PARENTS, TREE, {2: [0, np.inf]}), r"targets\[2\]"),
        (lambda: fabrik.solve_tree(PARENTS, TREE, {2: [0, 0]}, constraints=[fabrik.Cone(1)] * 4), r"constraints\[0\]"),
        (lambda: fabrik.solve_tree(PARENTS, TREE, {2: [0, 0]}, max_iterations=0), "max_iterations"),
    ],
)
def test_invalid_input_names_the_argument(call: object, name: str) -> None:
    with pytest.raises(ValueError, match=name):
        call()  # type: ignore[operator]


# ------------------------------------------------------------------------------------------------ review faults
Y3_PARENTS = [-1, 0, 1, 2, 3, 2, 5]
Y3 = np.array(
    [
        [0.0, 0.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, 2.0],
        [-0.5, 0.0, 2.8],
        [-1.0, 0.0, 3.6],
        [0.5, 0.0, 2.8],
        [1.0, 0.0, 3.6],
    ]
)


def tree_hinge_violation(parents: list[int], joints: Array, hinges: dict[int, fabrik.Hinge]) -> tuple[float, float]:
    """(largest |segment · axis|, largest angle outside its range in rad) over a 3D tree's global hinges without a
    reference axis (each measured from its parent's segment, the root's children from +z), in plain numpy."""
    off_plane, off_range = 0.0, 0.0
    for j, hinge in hinges.items():
        up = parents[j]
        previous = np.array([0.0, 0.0, 1.0]) if parents[up] < 0 else joints[up] - joints[parents[up]]
        u = (joints[j] - joints[up]) / np.linalg.norm(joints[j] - joints[up])
        axis = np.asarray(hinge.axis)
        reference = previous - (previous @ axis) * axis
        reference /= np.linalg.norm(reference)
        angle = math.atan2(float(np.cross(reference, u) @ axis), float(u @ reference))
        off_plane = max(off_plane, abs(float(u @ axis)))
        off_range = max(off_range, hinge.min_angle_rad - angle, angle - hinge.max_angle_rad, 0.0)
    return off_plane, off_range


def test_a_start_that_breaks_a_hinge_is_not_returned_as_reached() -> None:
    """Kind: an early return before any limit check. The start sits on its targets but its arms bend −0.56 and
    +0.56 rad at hinges allowing [0.2, 0.5]: it was returned as "reached" after 0 iterations."""
    hinge = fabrik.Hinge((0, 1, 0), 0.2, 0.5)
    constraints: list[fabrik.Constraint] = [None, None, None, hinge, None, hinge, None]
    assert tree_hinge_violation(Y3_PARENTS, Y3, {3: hinge, 5: hinge})[1] > 0.05
    result = fabrik.solve_tree(Y3_PARENTS, Y3, {4: Y3[4], 6: Y3[6]}, constraints=constraints)
    assert result.iterations > 0
    off_plane, off_range = tree_hinge_violation(Y3_PARENTS, result.joints, {3: hinge, 5: hinge})
    assert off_plane < 1e-9 and off_range < 1e-9
    for status, error in zip(result.status, result.error, strict=True):
        assert (status == "reached") == (error <= 1e-3)


@PROPERTY
@given(st.integers(4, 12), SEEDS)
def test_every_returned_pose_keeps_every_hinge_whatever_the_start(count: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    parents, joints = random_tree(rng, count, 3)
    hinges = {
        j: fabrik.Hinge(tuple(rng.normal(size=3)), float(lo), float(lo + rng.uniform(0.1, 2.0)))
        for j in range(1, count)
        if rng.random() < 0.5
        for lo in [rng.uniform(-math.pi, math.pi - 2.0)]
    }
    constraints: list[fabrik.Constraint] = [hinges.get(j) for j in range(count)]
    # the start on its own targets: within tolerance at once, whether or not it keeps the hinges
    targets = {e: joints[e] for e in leaves(parents)}
    result = fabrik.solve_tree(parents, joints, targets, constraints=constraints)
    off_plane, off_range = tree_hinge_violation(parents, result.joints, hinges)
    assert off_plane < 1e-9 and off_range < 1e-9
    if max(tree_hinge_violation(parents, joints, hinges)) > 1e-6:  # a start that breaks one is iterated on
        assert result.iterations > 0
    for status, error in zip(result.status, result.error, strict=True):
        assert status != "reached" or error <= 1e-3


@PROPERTY
@given(st.integers(4, 12), SEEDS, st.sampled_from([2, 3]))
def test_an_error_exactly_at_the_tolerance_is_reached(count: int, seed: int, d: int) -> None:
    """Kind: a strict comparison on a threshold. "Reached" is error ≤ tolerance (as solve), so tolerance 0 is met
    by a start on its targets, and a tolerance equal to the start's largest error is met at once."""
    rng = np.random.default_rng(seed)
    parents, joints = random_tree(rng, count, d)
    targets = {e: joints[e] + rng.normal(size=d) * 0.1 for e in leaves(parents)}
    errors = [math.sqrt(sum(float(x) * float(x) for x in joints[e] - targets[e])) for e in targets]
    result = fabrik.solve_tree(parents, joints, targets, tolerance=max(errors))
    assert result.iterations == 0 and set(result.status) == {"reached"}
    on = fabrik.solve_tree(parents, joints, {e: joints[e] for e in targets}, tolerance=0.0)
    assert on.iterations == 0 and set(on.status) == {"reached"}
    np.testing.assert_array_equal(on.error, 0.0)


def test_tolerance_zero_on_the_targets_is_reached() -> None:
    result = fabrik.solve_tree(Y3_PARENTS, Y3, {4: Y3[4], 6: Y3[6]}, tolerance=0.0)
    assert result.status == ("reached", "reached") and result.iterations == 0


@pytest.mark.parametrize("size", [1e-15, 1e-9, 1e6, 1e200])
def test_huge_and_tiny_trees_solve_as_the_unit_tree(size: float) -> None:
    """Kind: squared norms overflowing (1e200 gave NaN) and an absolute 1 m floor in the slack (1e-9 and 1e-15
    stalled as "limited"). With the tolerance scaled too, every scale gives the unit tree's result scaled."""
    targets = {4: np.array([-1.5, 0.0, 3.0]), 6: np.array([1.5, 0.0, 3.0])}
    unit = fabrik.solve_tree(Y3_PARENTS, Y3, targets, tolerance=1e-3)
    scaled = fabrik.solve_tree(Y3_PARENTS, Y3 * size, {k: v * size for k, v in targets.items()}, tolerance=1e-3 * size)
    assert np.isfinite(scaled.joints).all()
    assert scaled.status == unit.status == ("reached", "reached")
    assert scaled.iterations == unit.iterations
    np.testing.assert_allclose(scaled.joints / size, unit.joints, rtol=1e-9, atol=1e-12)


@PROPERTY
@given(st.integers(4, 10), SEEDS, st.sampled_from([2, 3]), st.integers(-900, 900), st.booleans())
def test_a_tree_scaled_by_a_power_of_two_gives_the_result_scaled(
    count: int, seed: int, d: int, k: int, hinged: bool
) -> None:
    rng = np.random.default_rng(seed)
    parents, joints = random_tree(rng, count, d)
    targets = {e: joints[e] + rng.normal(size=d) for e in leaves(parents)}
    constraints: list[fabrik.Constraint] | None = None
    if hinged:
        axis = (0, 0, 1) if d == 2 else tuple(rng.normal(size=3))
        constraints = [None, *[fabrik.Hinge(axis, -1.0, 1.0)] * (count - 1)]
    obstacles = [(joints[0] + np.eye(d)[0] * 2.0, 0.5)]
    s = math.ldexp(1.0, k)
    base = fabrik.solve_tree(parents, joints, targets, constraints=constraints, obstacles=obstacles)
    scaled = fabrik.solve_tree(
        parents,
        joints * s,
        {e: t * s for e, t in targets.items()},
        tolerance=1e-3 * s,
        constraints=constraints,
        obstacles=[(c * s, r * s) for c, r in obstacles],
    )
    assert scaled.status == base.status
    assert scaled.iterations == base.iterations
    np.testing.assert_array_equal(scaled.joints, base.joints * s)
    np.testing.assert_array_equal(scaled.error, base.error * s)


def test_reachable_targets_of_a_free_tree_are_reached_not_limited() -> None:
    """Kind: the fixed-point rule of limits applied with no limit. Both arms of the mirror-symmetric Y tree sent to
    the root (a pose exists: the arms fold back) stalled at 0.113 m after 22 iterations as "limited"."""
    origin = np.zeros(3)
    result = fabrik.solve_tree(Y3_PARENTS, Y3, {4: origin, 6: origin})
    assert result.status == ("reached", "reached")
    assert result.error.max() <= 1e-3


@PROPERTY
@given(st.integers(4, 12), SEEDS, st.sampled_from([2, 3]), st.floats(0.2, 3.0))
def test_a_free_tree_is_never_limited(count: int, seed: int, d: int, spread: float) -> None:
    rng = np.random.default_rng(seed)
    parents, joints = random_tree(rng, count, d)
    targets = {e: rng.normal(size=d) * spread for e in leaves(parents)}
    result = fabrik.solve_tree(parents, joints, targets, max_iterations=100)
    assert "limited" not in result.status
    assert "infeasible" not in result.status


def test_a_restart_never_leaves_a_tree_worse_than_where_it_stood() -> None:
    """Kind: a restart that loses the pose it left. A free Y tree stalled at 0.026 m (both targets within reach),
    was turned aside, settled in another basin and returned 0.39 m from both targets."""
    joints = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [2.0, 1.0]])
    result = fabrik.solve_tree([-1, 0, 1, 1], joints, {2: [1.5, 1.0], 3: [1.0, 1.5]})
    worst = result.error_history.max(axis=1)
    assert worst[9] > 0.39  # the restart's first iterate, in the other basin
    assert result.error.max() == pytest.approx(worst[8], abs=1e-12)  # the pose it stood in before the restart
    np.testing.assert_allclose(result.error, [0.0261356, 0.0213618], atol=1e-7)


@PROPERTY
@given(st.integers(4, 12), SEEDS, st.sampled_from([2, 3]), st.floats(0.2, 3.0))
@example(count=10, seed=10, d=2, spread=1.375)  # turned aside at 1.51 m, returned 1.71 m
def test_a_restarted_tree_returns_no_worse_than_before_the_restart(
    count: int, seed: int, d: int, spread: float
) -> None:
    rng = np.random.default_rng(seed)
    parents, joints = random_tree(rng, count, d)
    targets = {e: joints[0] + rng.normal(size=d) * spread for e in leaves(parents)}
    result = fabrik.solve_tree(parents, joints, targets, max_iterations=60)
    worst = result.error_history.max(axis=1)
    change = np.abs(np.diff(result.error_history, axis=0)).max(axis=1)
    stalls = np.flatnonzero(change < 1e-6)  # 0.1 % of the tolerance: the stall that turns a free tree aside
    if result.iterations == 60 and stalls.size and stalls[0] + 1 < 60:  # a free tree within reach, turned aside
        assert result.error.max() <= worst[stalls[0] + 1] + 1e-6  # the last iterate where it is as good, to the stall
    assert result.error.max() <= worst[-1] + 1e-12  # never worse than the last iterate


# Kind: "infeasible" said of iterates that keep every limit. A Y tree whose start broke its hinges (±0.01 rad, or
# none at all) was never checked again, since the backward stage keeps every limit, and was reported infeasible.
@pytest.mark.parametrize("half_range", [0.01, 0.0])
def test_a_start_that_breaks_a_limit_is_not_infeasible_once_an_iterate_keeps_them(half_range: float) -> None:
    joints = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.5, 0.0, 1.8], [-0.5, 0.0, 1.8]])
    hinge = fabrik.Hinge((0.0, 1.0, 0.0), -half_range, half_range)
    result = fabrik.solve_tree(
        [-1, 0, 1, 1], joints, {2: [0.8, 0.0, 1.2], 3: [-0.8, 0.0, 1.2]}, constraints=[None, hinge, hinge, hinge]
    )
    assert result.status == ("limited", "limited")
    for branch in ([0, 1, 2], [0, 1, 3]):
        usage = fabrik.limit_usage(result.joints[branch], [hinge, hinge])
        assert np.all(usage <= 1.0 + 1e-9)


@PROPERTY
@given(SEEDS, st.floats(0.0, 0.5), st.floats(0.3, 1.5))
def test_a_hinged_tree_without_obstacles_is_never_infeasible(seed: int, half_range: float, bent: float) -> None:
    """The backward stage keeps every limit on every iterate: whatever the start, the first iterate is admissible."""
    rng = np.random.default_rng(seed)
    joints = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [bent, 0.0, 1.8], [-bent, 0.0, 1.8]])
    hinge = fabrik.Hinge((0.0, 1.0, 0.0), -half_range, half_range)
    targets = {2: rng.normal(size=3), 3: rng.normal(size=3)}
    result = fabrik.solve_tree([-1, 0, 1, 1], joints, targets, constraints=[None, hinge, hinge, hinge])
    assert "infeasible" not in result.status


@pytest.mark.parametrize(
    ("key", "alias", "parents"), [(2, 2.0, [-1, 0, 1]), (1, True, [-1, 0]), (2, np.float64(2.0), [-1, 0, 1])]
)
def test_keys_that_hash_as_a_cached_index_are_still_refused(key: int, alias: Any, parents: list[int]) -> None:
    """Kind: validation behind a cache. 2.0 and True hash as 2 and 1, so after a call with the integer key the
    topology cache accepted them."""
    joints = np.eye(len(parents), 3)
    fabrik.solve_tree(parents, joints, {key: [0.0, 0.0, 0.0]})
    with pytest.raises(ValueError, match="targets keys"):
        fabrik.solve_tree(parents, joints, {alias: [0.0, 0.0, 0.0]})


@pytest.mark.parametrize(
    "parents",
    [[-1, False, True, True], [-1, 0, True, 1], (-1, np.False_, 1, 1), np.array([False, True]), [-1, 0, 1, 1.0]],
)
@pytest.mark.parametrize("cached_first", [False, True])
def test_parents_holding_bools_or_floats_are_refused(parents: Any, cached_first: bool) -> None:
    """Kind: an index that is not an integer. numpy reads [-1, False, True, True] as integers, so the tree was
    solved, where a bool key or a float parent is refused; also after the integer form was cached."""
    joints = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, 2.0], [0.0, 1.0, 2.0]])[: len(parents)]
    targets = {len(parents) - 1: joints[-1]}
    if cached_first:
        fabrik.solve_tree([-1, 0, 1, 1][: len(parents)] if len(parents) == 4 else [-1, 0], joints, targets)
    with pytest.raises(ValueError, match=r"^parents must be"):
        fabrik.solve_tree(parents, joints, targets)


def test_parents_of_the_wrong_shape_are_refused_after_the_right_one() -> None:
    targets = {4: np.array([-1.5, 0.0, 3.0])}
    fabrik.solve_tree(Y3_PARENTS, Y3, targets)
    for bad in (np.array(Y3_PARENTS).reshape(1, 7), np.array(Y3_PARENTS).reshape(7, 1)):
        with pytest.raises(ValueError, match="parents"):
            fabrik.solve_tree(bad, Y3, targets)


# ------------------------------------------------------------------------------------------------ one implementation
@PROPERTY
@given(SEEDS, st.integers(2, 7), st.booleans())
def test_chain_and_one_branch_tree_judge_a_pose_alike(seed: int, n: int, limited: bool) -> None:
    """The chain's and the tree's admissibility (joint limits, and the segment–sphere test, zero-length segments
    included) are one compiled implementation: a chain read as a one-branch tree gets the same verdict."""
    from kernels.fabrik import chain, geometry, tree
    from kernels.fabrik.limits import _limit_table

    rng = np.random.default_rng(seed)
    p = np.zeros((n + 1, 3))
    for i in range(n):
        step = rng.normal(size=3) * (0.0 if rng.random() < 0.3 else 1.0)  # some zero-length links
        p[i + 1] = p[i] + step
    centres = p[rng.integers(0, n + 1, size=3)] + 0.3 * rng.normal(size=(3, 3))
    radii = rng.uniform(0.05, 0.6, size=3)
    live = (np.linalg.norm(centres - p[0], axis=1) > radii).astype(np.bool_)
    constraints = [fabrik.Cone(float(rng.uniform(0.3, 2.5))) if limited else None for _ in range(n)]
    table = _limit_table(constraints, n, 3, "constraints", segment_offset=0)
    rest, tiny = np.array([0.0, 0.0, 1.0]), 1e-12
    parents = np.arange(-1, n, dtype=np.int64)
    order = np.arange(n + 1, dtype=np.int64)
    tree_table = np.vstack([np.zeros((1, table.shape[1])), table])
    as_chain = from_python(chain._admissible)(p, tiny, rest, limited, table, (centres, radii, live))
    as_tree = from_python(tree._tree_admissible)(
        p, parents, order, tree_table, rest, tiny, limited, (centres, radii, live)
    )
    assert as_chain == as_tree
    for i in range(n):  # the one segment test, zero-length segments included, never NaN
        cut = from_python(geometry._segment_cuts)(p, i, i + 1, (centres, radii, live), 1.0)
        length = float(np.linalg.norm(p[i + 1] - p[i]))
        if length == 0.0:
            inside = bool(np.any(live & (np.linalg.norm(centres - p[i], axis=1) < radii)))
            assert cut == inside


def test_a_zero_length_segment_inside_a_sphere_cuts_it_for_chain_and_tree() -> None:
    from kernels.fabrik import chain, geometry, tree

    p = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, 1.0]])
    centres, radii, live = np.array([[0.05, 0.0, 1.0]]), np.array([0.1]), np.array([True])
    assert from_python(geometry._segment_cuts)(p, 1, 2, (centres, radii, live), 1.0)
    assert not from_python(geometry._segment_cuts)(p, 1, 2, (centres + 1.0, radii, live), 1.0)
    table = np.zeros((1, 13))
    rest = np.array([0.0, 0.0, 1.0])
    parents, order = np.array([-1, 0, 1]), np.array([0, 1, 2])
    assert not from_python(chain._admissible)(p, 1e-12, rest, False, table, (centres, radii, live))
    assert not from_python(tree._tree_admissible)(
        p, parents, order, np.zeros((3, 13)), rest, 1e-12, False, (centres, radii, live)
    )


def test_a_tree_far_from_the_origin_is_solved_as_at_the_origin() -> None:
    """The kind of the chain's far-out case (tests/kernels/test_fabrik.py): a 3 cm Y tree 1 km out was solved in
    coordinates that round to 1e-13 m, and its iterates went another way (233 of 300 such trees ended apart from the
    same tree at the origin). Solved about its root, each ends as at the origin."""
    rng = np.random.default_rng(3)
    parents = [-1, 0, 1, 2, 3, 2, 5]  # a sub-base at joint 2, effectors 4 and 6
    constraints = [None] + [fabrik.Cone(1.0)] * 6
    for trial in range(60):
        joints = np.zeros((7, 3))
        for i, parent in enumerate(parents):
            if parent >= 0:
                joints[i] = joints[parent] + rng.normal(size=3) * 0.01
        targets = {4: joints[4] + rng.normal(size=3) * 0.01, 6: joints[6] + rng.normal(size=3) * 0.01}
        shift = rng.normal(size=3)
        shift *= 1e3 / np.linalg.norm(shift)
        kwargs: dict[str, Any] = {"tolerance": 1e-5, "max_iterations": 40, "constraints": constraints}
        near = fabrik.solve_tree(parents, joints, targets, **kwargs)
        far = fabrik.solve_tree(parents, joints + shift, {k: v + shift for k, v in targets.items()}, **kwargs)
        assert far.status == near.status, trial
        np.testing.assert_allclose(far.error, near.error, rtol=1e-6, atol=1e-12, err_msg=str(trial))
        np.testing.assert_array_equal(far.joints[0], joints[0] + shift)
