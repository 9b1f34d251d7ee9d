"""Plain reference solvers for the tests, written from the papers and not from :mod:`kernels.fabrik`.

Readable numpy, one joint at a time, no speed tricks, no constraints beyond the cone the kernel's docstring
describes; the tests compare the compiled solvers' iterates against these.

* FABRIK: Aristidou & Lasenby 2011, Algorithm 1 (forward reaching, then backward reaching, with
  ``λ_i = d_i / |p_{i+1} − p_i|``); the unreachable case places each joint toward the target. Optional cone limits
  as the kernel documents them, applied by spherical interpolation from the cone's axis.
* CCD: Wang & Chen 1991: each joint, from the end to the root, turns the rest of the chain so the end points at the
  target.
* DLS: Wampler 1986, Buss 2004: ``Δθ = Jᵀ(JJᵀ + λ²I)⁻¹e`` with the Jacobian built column by column (hinges about
  the normal in 2D, three world axes per ball joint in 3D), the error clamped to the mean link length and
  ``λ = 0.1 × mean link length``; segment j turns by ``R(Δθ_0)…R(Δθ_j)`` (scipy's rotation vectors in 3D).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

Array = NDArray[np.float64]


def limit(v: Array, axis: Array, phi: float | None) -> Array:
    """Unit ``v`` brought into the cone of half-angle ``phi`` about unit ``axis``: slerp from the axis by φ."""
    if phi is None:
        return v
    angle = math.acos(min(1.0, max(-1.0, float(v @ axis))))
    if angle <= phi:
        return v
    return (math.sin(angle - phi) * axis + math.sin(phi) * v) / math.sin(angle)


def fabrik(
    joints: Array, target: Array, iterations: int, phi: float | None = None, root_direction: Array | None = None
) -> list[Array]:
    """Poses after each of ``iterations`` FABRIK iterations (Aristidou & Lasenby 2011, Algorithm 1)."""
    p = np.array(joints, dtype=np.float64)
    t = np.asarray(target, dtype=np.float64)
    n = len(p) - 1
    d = [float(np.linalg.norm(p[i + 1] - p[i])) for i in range(n)]
    rest = np.eye(p.shape[1])[-1] if root_direction is None else root_direction
    if np.linalg.norm(t - p[0]) > sum(d):  # unreachable: stretch toward the target
        for i in range(n):
            lam = d[i] / float(np.linalg.norm(t - p[i]))
            p[i + 1] = (1 - lam) * p[i] + lam * t
        return [p.copy()]
    root = p[0].copy()
    poses = []
    for _ in range(iterations):
        p[n] = t  # forward reaching
        previous = None
        for i in range(n - 1, 0, -1):
            lam = d[i] / float(np.linalg.norm(p[i + 1] - p[i]))
            point = (1 - lam) * p[i + 1] + lam * p[i]
            direction = (point - p[i + 1]) / d[i]
            if previous is not None:
                direction = limit(direction, previous, phi)
            p[i] = p[i + 1] + d[i] * direction
            previous = direction
        p[0] = root  # backward reaching
        previous = rest
        for i in range(n):
            lam = d[i] / float(np.linalg.norm(p[i + 1] - p[i]))
            point = (1 - lam) * p[i] + lam * p[i + 1]
            direction = limit((point - p[i]) / d[i], previous, phi)
            p[i + 1] = p[i] + d[i] * direction
            previous = direction
        poses.append(p.copy())
    return poses


def ccd(joints: Array, target: Array, iterations: int) -> list[Array]:
    """Poses after each CCD sweep (Wang & Chen 1991), end to root."""
    p = np.array(joints, dtype=np.float64)
    t = np.asarray(target, dtype=np.float64)
    n = len(p) - 1
    poses = []
    for _ in range(iterations):
        for i in range(n - 1, -1, -1):
            to_end = p[n] - p[i]
            to_target = t - p[i]
            if p.shape[1] == 2:
                angle = math.atan2(to_target[1], to_target[0]) - math.atan2(to_end[1], to_end[0])
                c, s = math.cos(angle), math.sin(angle)
                turn = np.array([[c, -s], [s, c]])
            else:
                axis = np.cross(to_end, to_target)
                # atan2(|a × b|, a · b): exact to rounding at every angle (acos of the cosine loses half the digits
                # near 0, 2e-8 rad, which is what a converging sweep turns by).
                sine = float(np.linalg.norm(axis))
                if sine == 0.0:  # the end effector already on the ray to the target: nothing to turn
                    continue
                angle = math.atan2(sine, float(to_end @ to_target))
                turn = Rotation.from_rotvec(axis / sine * angle).as_matrix()
            p[i + 1 :] = p[i] + (p[i + 1 :] - p[i]) @ turn.T
        poses.append(p.copy())
    return poses


def dls(joints: Array, target: Array, iterations: int) -> list[Array]:
    """Poses after each damped-least-squares step (Wampler 1986; Buss 2004)."""
    p = np.array(joints, dtype=np.float64)
    t = np.asarray(target, dtype=np.float64)
    n, dim = len(p) - 1, p.shape[1]
    lengths = np.linalg.norm(np.diff(p, axis=0), axis=1)
    cap = lengths.mean()
    poses = []
    for _ in range(iterations):
        e = t - p[n]
        e = e * min(1.0, cap / max(float(np.linalg.norm(e)), 1e-300))
        columns = []
        for i in range(n):
            lever = p[n] - p[i]
            if dim == 2:
                columns.append([-lever[1], lever[0]])
            else:
                columns.extend(np.cross(axis, lever) for axis in np.eye(3))
        jac = np.array(columns).T  # (d, m)
        step = jac.T @ np.linalg.solve(jac @ jac.T + (0.1 * cap) ** 2 * np.eye(dim), e)
        segments = np.diff(p, axis=0)
        if dim == 2:
            angles = np.cumsum(step)
            c, s = np.cos(angles), np.sin(angles)
            segments = np.stack(
                [c * segments[:, 0] - s * segments[:, 1], s * segments[:, 0] + c * segments[:, 1]], axis=1
            )
        else:
            turn = np.eye(3)
            for j in range(n):
                turn = turn @ Rotation.from_rotvec(step[3 * j : 3 * j + 3]).as_matrix()
                segments[j] = turn @ segments[j]
        p[1:] = p[0] + np.cumsum(segments, axis=0)
        poses.append(p.copy())
    return poses


def end_errors(poses: list[Array], target: Array) -> Array:
    """(K,) the end effector's distance to ``target`` in each pose (m)."""
    return np.array([float(np.linalg.norm(pose[-1] - target)) for pose in poses])


def rounding_reach(
    reference: Callable[[Array, Array], list[Array]], joints: Array, target: Array, scale: float
) -> Array:
    """(K,) how far the reference's own end-effector errors move, iteration by iteration, when the target moves by
    10⁻¹⁵·``scale`` (about one rounding) in three fixed random directions: the largest move of each.

    An iteration can amplify rounding (FABRIK with cones, or CCD, on some chains: tenfold and more per
    iteration), and then two correct implementations that round differently part after a few iterations. This
    measures that amplification on the reference itself, so a comparison can allow it and no more.
    """
    base = end_errors(reference(joints, target), target)
    rng = np.random.default_rng(0)
    reach = np.zeros_like(base)
    for _ in range(3):
        direction = rng.normal(size=target.shape)
        moved = target + direction / np.linalg.norm(direction) * 1e-15 * scale
        reach = np.maximum(reach, np.abs(end_errors(reference(joints, moved), moved) - base))
    return reach
