"""Inverse kinematics of a chain of rigid links: FABRIK, and the solvers it is compared with.

A chain is ``n + 1`` joint positions ``p_0 … p_n`` in 2D or 3D (``d`` = 2 or 3, metres); ``p_0`` is the fixed root,
``p_n`` the end effector. Link lengths ``L_i = |p_{i+1} − p_i|`` come from the joints given and never change.
Batches lead: a batch of chains is ``(B, n + 1, d)`` and its targets ``(B, d)``.

Model and method:

* FABRIK (Aristidou & Lasenby 2011, "FABRIK: a fast, iterative solver for the Inverse Kinematics problem",
  Graphical Models 73(5)): a forward pass sets ``p_n`` on the target and re-places every joint on the line to the
  joint before it at the link's length; a backward pass sets ``p_0`` back on the root and does the same outwards.
* Reach: a target at distance ``r`` from the root is reachable only if ``max(0, 2·max L − ΣL) ≤ r ≤ ΣL`` (the
  reach annulus, to within 1e-12 of the chain's scale ``max(ΣL, r)``). Outside it FABRIK returns the closest pose at
  once (stretched straight toward the target, or folded back onto the inner boundary), as the paper does for
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
  targets an admissible pose reaches, "limited" fell from 22 % to 2 %); the restart pose is a candidate itself. Under
  hinges, a chain that stalls again, or creeps (its best error not halved in 10 iterations), is polished once by
  damped least squares projected through the backward pass, from its best pose and from two mirrored pairs of
  admissible poses spread over the ranges: on planar arms of 2–6 links with one-sided ranges, missed reachable targets
  fell from 32 % to 0.2 %, the same for a chain and its mirror image. The straight chain's unbending arc bends each
  hinge toward the inside of its range (not at all for a zero range), so a near-rigid chain is not turned off its line.
  Both decide from the iterates alone, so more iterations are never worse. Only FABRIK is extrapolated, and only
  FABRIK tries the closest-pose, straight and folded candidates: ``ccd`` and ``jacobian_dls`` run as published.
* Stopping: at the tolerance (``error ≤ tolerance``), at ``max_iterations``, or, where limits or obstacles apply or
  the target is out of reach, at a fixed point: when the error changes by less than 0.1 % of the tolerance in an
  iteration (caliko's "minimum change" rule), or the best admissible error has improved by less than 10 % of the
  tolerance in 10 iterations (the iterates creep toward, or circle, a fixed point). Without constraints the iterations
  converge and run to the cap.
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
  (the core runs without the GIL on a pool of threads; ``numba.set_num_threads`` sets how many). 2D chains run as 3D
  ones in the plane ``z = 0``. The first call compiles (seconds) or loads the machine code from numba's cache
  (``__pycache__`` beside this file, or numba's user-wide cache directory where that is read-only); :func:`warm_up` does
  it ahead of time.

Modules: :mod:`~kernels.fabrik.api` (the chain functions and their checks), :mod:`~kernels.fabrik.limits` (joint
types and their compiled rules), :mod:`~kernels.fabrik.geometry` (compiled vectors and the obstacle rule),
:mod:`~kernels.fabrik.chain` (the compiled chain solvers), :mod:`~kernels.fabrik.tree` (skeletons).
"""

from __future__ import annotations

import numpy as np

from kernels.fabrik.api import (
    BatchSolution,
    Obstacle,
    Solution,
    ccd,
    jacobian_dls,
    joint_angles,
    limit_usage,
    link_lengths,
    reach_limits,
    solve,
    solve_batch,
    two_bone,
)
from kernels.fabrik.chain import STATUSES, Solver, Status
from kernels.fabrik.limits import Cone, Constraint, Hinge, HingeFrame
from kernels.fabrik.tree import TreeSolution, solve_tree

__all__ = [
    "STATUSES",
    "BatchSolution",
    "Cone",
    "Constraint",
    "Hinge",
    "HingeFrame",
    "Obstacle",
    "Solution",
    "Solver",
    "Status",
    "TreeSolution",
    "ccd",
    "jacobian_dls",
    "joint_angles",
    "limit_usage",
    "link_lengths",
    "reach_limits",
    "solve",
    "solve_batch",
    "solve_tree",
    "two_bone",
    "warm_up",
]


def warm_up() -> None:
    """Compile every solver core (or load it from numba's cache) on tiny inputs, so the first real solve waits for
    nothing. Safe to call from a background thread; numba's compiler lock makes a concurrent first solve wait for
    it instead of compiling twice."""
    chain = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.3, 0.0, 1.9]])
    obstacles = [(np.array([1.0, 0.0, 1.0]), 0.2)]
    for solver in ("fabrik", "ccd", "jacobian_dls"):
        solve_batch(
            np.repeat(chain[None], 2, axis=0),
            np.repeat([[0.8, 0.0, 1.2]], 2, axis=0),
            cone_half_angle_rad=1.0,
            obstacles=obstacles,
            max_iterations=3,
            solver=solver,
        )
    hinge = Hinge((0.0, 1.0, 0.0), -1.0, 1.0)
    solve(chain, [0.8, 0.0, 1.2], constraints=[hinge, Cone(1.0)], max_iterations=3)
    solve_tree(
        [-1, 0, 1, 1],
        np.vstack([chain, [[-0.3, 0.0, 1.9]]]),
        {2: [0.8, 0.0, 1.2], 3: [-0.8, 0.0, 1.2]},
        constraints=[None, hinge, Cone(1.0), hinge],
        obstacles=obstacles,
        max_iterations=3,
    )
    limit_usage(chain, [hinge, Cone(1.0)])  # the skeleton presets' readouts
