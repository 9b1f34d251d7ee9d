"""Meshing a scene's zero level set: a sample grid, a coarse-to-fine sampler, and marching cubes.

:func:`mesh` samples the field on a grid and runs scikit-image's marching cubes (Lewiner et al. 2003) on the float
field, which keeps sub-voxel accuracy. It evaluates the field only near the surface: a block of samples whose centre
is farther from the surface than the block's radius plus one voxel diagonal cannot hold a corner of a cell the
surface crosses (the field is 1-Lipschitz), so the block gets the sign of its centre and is not refined. Marching
cubes reads values only at corners of crossed cells, so the output equals the full-grid output exactly; it is also
told to skip cells outside the evaluated region (its ``mask``).

Grid samples are in metres; fields are ``(nx, ny, nz)`` float32 distances (m), negative inside; meshes are
vertices ``(V, 3)`` (m), faces ``(F, 3)`` wound outward and vertex colours ``(V, 3)`` RGB in [0, 1].

Source: T. Lewiner, H. Lopes, A. W. Vieira, G. Tavares, "Efficient implementation of marching cubes' cases with
topological guarantees", J. Graphics Tools 8(2) (2003).
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
import math
from collections.abc import Callable

import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray
from skimage.measure import label, marching_cubes

from kernels import _checks
from kernels.sdf.primitives import FloatArray
from kernels.sdf.scene import Scene, fold_xyz, scene_bounds, scene_color

MIN_RESOLUTION = 16
MAX_RESOLUTION = 512
MAX_FIELD_COORDINATE = 1e18
"""Largest |coordinate| (m) of a mesh grid: float32 squares of differences of such coordinates stay finite."""
MIN_SPACING_ULPS = 4096
"""Fewest float64 steps (ulps of the grid's largest |coordinate|) between neighbouring samples. The rounding of the
sample positions there moves the surface by about 40 ulps: at 4096 a sample, the mesh lies within 1/100 of a voxel
of the same shape's at the origin (a 1 m box at 32 samples may lie up to 6.8·10¹⁰ m out)."""


@dataclasses.dataclass(frozen=True)
class Grid:
    """A regular sample grid: ``origin + index·spacing``, ``shape`` samples per axis."""

    origin: tuple[float, float, float]
    """World position of sample (0, 0, 0) (m)."""
    spacing: float
    """Distance between neighbouring samples (m)."""
    shape: tuple[int, int, int]
    """Samples along x, y, z."""


def make_grid(scene: Scene, resolution: int, bounds: ArrayLike | None = None) -> Grid:
    """The grid :func:`mesh` samples: cubic voxels, ``resolution`` samples along the box's longest side.

    Args:
        scene: the scene (its bounds are used when ``bounds`` is None).
        resolution: samples along the longest side, 16..512.
        bounds: optional (2, 3) min and max corners (m).
    """
    _checks.instance("scene", scene, Scene)
    _checks.integer("resolution", resolution)
    if not MIN_RESOLUTION <= int(resolution) <= MAX_RESOLUTION:
        raise ValueError(f"resolution must be in {MIN_RESOLUTION}..{MAX_RESOLUTION}, got {resolution}")
    if bounds is None:
        box = scene_bounds(scene)
    else:
        box = _checks.finite_array("bounds", bounds)
        if box.shape != (2, 3) or np.any(box[1] <= box[0]):
            raise ValueError(
                f"bounds must be finite (2, 3) min and max corners with max > min, got {_checks.shown(bounds)}"
            )
    if not np.all(np.abs(box) <= MAX_FIELD_COORDINATE):
        raise ValueError(
            f"bounds (given or the scene's) must lie within ±{MAX_FIELD_COORDINATE:g} m for the float32 field, "
            f"got {box.tolist()}"
        )
    extent = box[1] - box[0]
    spacing = float(extent.max()) / (int(resolution) - 1)
    reach = float(np.abs(box).max())
    if spacing < MIN_SPACING_ULPS * float(np.spacing(reach)):
        raise ValueError(
            f"bounds (given or the scene's) reach {reach:g} m from the origin with samples {spacing:g} m apart, "
            f"but positions there step by {float(np.spacing(reach)):g} m in float64: mesh the shape nearer the "
            "origin, or at a lower resolution"
        )
    counts = np.minimum(np.ceil(extent / spacing - 1e-9).astype(int) + 1, int(resolution))
    center = 0.5 * (box[0] + box[1])
    origin = center - 0.5 * (counts - 1) * spacing
    return Grid(
        origin=(float(origin[0]), float(origin[1]), float(origin[2])),
        spacing=spacing,
        shape=(int(counts[0]), int(counts[1]), int(counts[2])),
    )


def _grid(value: object) -> Grid:
    """A :class:`Grid` whose fields are what :func:`make_grid` makes (a frozen dataclass takes anything), else
    ``ValueError`` naming ``grid``."""
    grid = _checks.instance("grid", value, Grid)
    origin = _checks.finite_array("grid", grid.origin)
    spacing = _checks.finite_number("grid", grid.spacing)
    shape = np.asarray(grid.shape)
    if (
        origin.shape != (3,)
        or not (np.abs(origin) <= MAX_FIELD_COORDINATE).all()
        or not 0.0 < spacing <= MAX_FIELD_COORDINATE
        or shape.shape != (3,)
        or shape.dtype.kind not in "iu"
        or not ((shape >= 2) & (shape <= MAX_RESOLUTION)).all()
    ):
        raise ValueError(f"grid must be a Grid from make_grid, got {_checks.shown(grid)}")
    return grid


def sample_full(scene: Scene, grid: Grid) -> NDArray[np.float32]:
    """The field at every grid sample, (nx, ny, nz) float32: the plain baseline the coarse-to-fine pass matches."""
    _checks.instance("scene", scene, Scene)
    _grid(grid)
    axes = [grid.origin[i] + grid.spacing * np.arange(grid.shape[i]) for i in range(3)]
    xs, ys, zs = np.meshgrid(*axes, indexing="ij")
    return _field_at(scene, grid, np.stack([xs.ravel(), ys.ravel(), zs.ravel()], axis=1)).reshape(grid.shape)


def _field_at(scene: Scene, grid: Grid, points: NDArray[np.floating]) -> NDArray[np.float32]:
    """The field at (N, 3) sample points of ``grid``, evaluated in float32 (what marching cubes reads) on coordinate
    arrays, in the frame of :func:`_grid_shift` (the scene moved with the points), so that a shape far from the
    world's origin keeps float32's precision across its grid.

    Both samplers call this with coordinates computed the same way, so equal points give bit-equal values.
    """
    shift = _grid_shift(grid)
    if np.any(shift):
        moved = tuple(
            dataclasses.replace(p, center=(p.center[0] - shift[0], p.center[1] - shift[1], p.center[2] - shift[2]))
            for p in scene.primitives
        )
        scene, points = dataclasses.replace(scene, primitives=moved), points - shift
    p32 = points.astype(np.float32)
    d, _ = fold_xyz(scene, p32[:, 0].copy(), p32[:, 1].copy(), p32[:, 2].copy(), with_color=False)
    return d.astype(np.float32, copy=False)


def _grid_shift(grid: Grid) -> FloatArray:
    """(3,) where the field is evaluated from (m): the grid's centre rounded to a multiple of the power of two at or
    above its longest side, so 0 for a grid about the world's origin (the world frame, bit for bit) and within one
    such multiple of the grid elsewhere. (In world float32 coordinates, which step by 8 m at 10⁸ m, a sphere there
    was meshed as its whole box.)"""
    origin = np.asarray(grid.origin, dtype=np.float64)
    extent = grid.spacing * (np.asarray(grid.shape, dtype=np.float64) - 1.0)
    quantum = 2.0 ** math.ceil(math.log2(float(extent.max())))
    return np.round((origin + 0.5 * extent) / quantum) * quantum


_LEVELS = (16, 4)
"""Block sizes (samples per side) of the coarse passes; the last level's surviving blocks are sampled in full."""


@dataclasses.dataclass(frozen=True)
class NearSurfaceField:
    """The grid field from the coarse-to-fine pass."""

    field: NDArray[np.float32]
    """(nx, ny, nz) values (m): exact at every corner of a cell the surface crosses, sign-correct elsewhere."""
    mask: NDArray[np.bool_]
    """(nx, ny, nz) True where the value was evaluated exactly; it holds every corner of every crossed cell, so
    marching cubes may skip cells whose far corner is False."""
    evaluated: int
    """Points evaluated, block centres included."""


def _progress(value: object) -> None:
    if value is not None and not callable(value):
        raise ValueError(f"progress must be a function of the fraction done or None, got {type(value).__name__}")


def sample_near_surface(scene: Scene, grid: Grid, progress: Callable[[float], None] | None = None) -> NearSurfaceField:
    """The field, evaluated exactly where marching cubes reads it and sign-filled elsewhere.

    Args:
        scene: the scene.
        grid: the grid.
        progress: optional callback receiving the fraction done, 0..1.
    """
    _checks.instance("scene", scene, Scene)
    _grid(grid)
    _progress(progress)
    h = grid.spacing
    # A corner of a crossed cell lies within one voxel diagonal of the surface.
    margin = math.sqrt(3.0) * h * (1.0 + 1e-3) + 1e-6  # slack for float32 rounding
    top = _LEVELS[0]
    padded = tuple(-(-n // top) * top for n in grid.shape)
    field = np.empty(padded, dtype=np.float32)
    origin = np.asarray(grid.origin)
    evaluated = 0

    def block_centers(corners: NDArray[np.int64], size: int) -> FloatArray:
        return origin + h * (corners + 0.5 * (size - 1)).astype(np.float64)

    def view(size: int) -> NDArray[np.float32]:
        n = [m // size for m in padded]
        return field.reshape(n[0], size, n[1], size, n[2], size)

    # Level 0: every top block, written as a whole-field fill of its centre's value.
    n0 = [m // top for m in padded]
    idx = np.stack(np.meshgrid(*[np.arange(c) for c in n0], indexing="ij"), axis=-1).reshape(-1, 3)
    corners = idx * top
    d = _field_at(scene, grid, block_centers(corners, top))
    evaluated += len(d)
    view(top)[...] = d.astype(np.float32).reshape(n0[0], 1, n0[1], 1, n0[2], 1)
    keep = np.abs(d) <= math.sqrt(3.0) * 0.5 * (top - 1) * h + margin
    corners = corners[keep]
    size = top
    for child in (*_LEVELS[1:], 1):
        if progress is not None:
            progress(0.2 + 0.6 * (1 - child / top))
        ratio = size // child
        offsets = np.stack(np.meshgrid(*[np.arange(ratio)] * 3, indexing="ij"), axis=-1).reshape(-1, 3) * child
        corners = (corners[:, None, :] + offsets[None, :, :]).reshape(-1, 3)
        d = _field_at(scene, grid, block_centers(corners, child))
        evaluated += len(d)
        blocks = corners // child
        fill = d.astype(np.float32)[:, None, None, None]
        view(child)[blocks[:, 0], :, blocks[:, 1], :, blocks[:, 2], :] = fill
        if child == 1:
            mask = np.zeros(padded, dtype=bool)
            mask[corners[:, 0], corners[:, 1], corners[:, 2]] = True
            break
        keep = np.abs(d) <= math.sqrt(3.0) * 0.5 * (child - 1) * h + margin
        corners = corners[keep]
        size = child
    nx, ny, nz = grid.shape
    return NearSurfaceField(field[:nx, :ny, :nz], mask[:nx, :ny, :nz], evaluated)


def mesh(
    scene: Scene,
    resolution: int,
    bounds: ArrayLike | None = None,
    *,
    near_surface: bool = True,
    progress: Callable[[float], None] | None = None,
) -> tuple[FloatArray, NDArray[np.int64], FloatArray]:
    """Triangle mesh of the scene's zero level set by marching cubes on the float field.

    Args:
        scene: the scene.
        resolution: samples along the longest side of the bounds, 16..512.
        bounds: optional (2, 3) min and max corners (m); by default found from the primitives with room for the
            blend, so closed shapes give closed meshes.
        near_surface: evaluate only near the surface (coarse to fine; same output); False samples every point.
        progress: optional callback receiving the fraction done, 0..1.

    Returns:
        vertices (V, 3) in metres, faces (F, 3) vertex indices wound outward, vertex colours (V, 3) RGB in [0, 1].
        Samples on (or within 1e-3 voxel of) the zero level are moved 1e-3 voxel off it first: inside where they
        lie on a face along grid lines next to a grid cell whose centre is inside, else outside (see
        ``_polygonise``), so every vertex is distinct, a closed shape gives a watertight mesh even where faces lie on
        grid planes, and a feature one voxel thick between two grid planes keeps its volume. An empty field (no
        surface inside the bounds) gives empty arrays.

    Raises:
        ValueError: naming the argument: a scene that is not a :class:`Scene`, a resolution that is not an integer
            in 16..512, bounds (given or the scene's) not finite or beyond ±:data:`MAX_FIELD_COORDINATE`, a
            ``near_surface`` that is not a bool, a ``progress`` that is not callable.
    """
    grid = make_grid(scene, resolution, bounds)
    _progress(progress)
    mask = None
    if _checks.flag("near_surface", near_surface):
        sampled = sample_near_surface(scene, grid, progress)
        field, mask = sampled.field, sampled.mask
    else:
        field = sample_full(scene, grid)
    if progress is not None:
        progress(0.8)
    verts, faces = _polygonise(grid, field, mask, lambda points: _field_at(scene, grid, points))
    return verts, faces, scene_color(scene, verts) if len(verts) else np.zeros((0, 3))


ISO_NUDGE_VOXELS = 1e-3
"""Samples within this fraction of a voxel of the zero level move to that distance from it before marching cubes."""


def _polygonise(
    grid: Grid,
    field: NDArray[np.float32],
    mask: NDArray[np.bool_] | None,
    distance_at: Callable[[FloatArray], NDArray[np.floating]],
) -> tuple[FloatArray, NDArray[np.int64]]:
    # A sample exactly on the level is a tie that marching cubes breaks differently in neighbouring cells (its
    # classification and its face test disagree), which leaves holes (scikit-image issue 8116), so every sample
    # closer than δ = 1e-3 voxel to the level moves to ±δ. Which side: a sample on the level is a boundary point of
    # the hard solid {d ≤ 0}; when it lies on a face along grid lines (a level neighbour), it goes inside (−δ) if a
    # grid cell it is a corner of has its centre inside (d < 0: the solid has volume in that cell), else outside
    # (+δ, as in Lewiner's reference code). Pushing every such
    # sample outside made a feature one voxel thick with both faces on grid planes vanish (no sample was left
    # inside it); pushing every one inside would turn zero-volume sets (boxes touching in an intersection, A − A)
    # into sheets. A sample a hair inside (d < 0) stays inside. Neighbouring samples differ by at most a voxel (the
    # field is 1-Lipschitz), so each vertex lies at least ~δ/voxel inside its own edge: vertices stay distinct in
    # float32 and the mesh is a plain marching-cubes mesh (no merging), the surface moving by at most δ. Both
    # samplers' fields pass through here and level samples and their cells' corners are evaluated exactly by both
    # (the sign fill comes from blocks far from the surface), so the coarse-to-fine output equals the full grid's.
    delta = np.float32(ISO_NUDGE_VOXELS * grid.spacing)
    near_level = np.abs(field) < delta
    if near_level.any():
        # Only samples with a level neighbour (a face or a feature's edge along grid lines) take that test; a lone
        # one (a blend grazing a sample) stays outside, so a sub-voxel blend keeps the topology it always had.
        # On the grid's outer layer a sample stays outside as well: the solid may go on beyond the bounds, and
        # marching cubes only closes a surface that crosses inside them (a box that fills its bounds).
        outer = np.zeros(field.shape, dtype=bool)
        outer[[0, -1], :, :] = outer[:, [0, -1], :] = outer[:, :, [0, -1]] = True
        lined = near_level & (field >= 0.0) & _beside(near_level) & ~outer
        inward = (field < 0.0) | _holds_volume(_touches_solid(distance_at, grid, lined), field < 0.0)
        nudged = np.where(inward, -delta, delta)
        # A level sample left outside next to one moved inside: the edge between them runs along a face that only
        # the inside one bounds (a cut flush with another face), so the surface belongs at the inside sample, not
        # halfway between ±δ. The outside one takes half a voxel instead, putting the vertex ~2δ from it.
        # (Not on the outer layer, left outside for the bounds' sake, not the geometry's: a plane on a grid plane
        # that crosses the bounds kept its vertices there a third of a voxel off it.)
        beside = _beside(near_level & inward) & near_level & ~inward & ~outer
        nudged = np.where(beside, np.float32(0.5 * grid.spacing), nudged)
        field = np.where(near_level, nudged, field)
    if not (field.min() < 0.0 < field.max()):
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
    verts, faces, _normals, _values = marching_cubes(
        np.ascontiguousarray(field, dtype=np.float32),
        level=0.0,
        spacing=(grid.spacing,) * 3,
        mask=None if mask is None else np.ascontiguousarray(mask),
    )
    verts = verts.astype(np.float64) + np.asarray(grid.origin)
    # scikit-image's default winding faces a field that is negative inside outward (tests check the volume's sign).
    return verts, faces.astype(np.int64)


def _holds_volume(level_in: NDArray[np.bool_], inside: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """The ``level_in`` samples (level samples bound for the inside) whose group, 6-connected through them and the
    ``inside`` samples, holds a sample strictly inside or a whole grid cell (all eight corners in it).

    A group that holds neither is a line or a point where the field only touches zero (a smooth blend's crease running
    along a grid line): the solid has no volume there at this grid, and marching cubes would close those samples into
    a separate shell of no thickness, a second component that a finer grid does not have. A feature one voxel thick
    with both faces on grid planes still holds whole cells, and a face of a larger solid touches its inside samples.
    """
    if not level_in.any():
        return level_in
    lo = np.maximum(np.argwhere(level_in).min(axis=0) - 1, 0)
    hi = np.argwhere(level_in).max(axis=0) + 2
    box = tuple(slice(a, b) for a, b in zip(lo, hi, strict=True))
    candidates, solid = level_in[box], inside[box]
    members = candidates | solid
    labels: NDArray[np.intp] = np.asarray(label(members, connectivity=1), dtype=np.intp)
    count = int(labels.max())
    keep = np.zeros(count + 1, dtype=bool)
    keep[labels[solid]] = True
    nx, ny, nz = (n - 1 for n in members.shape)
    whole = np.ones((nx, ny, nz), dtype=bool)
    for dx, dy, dz in itertools.product((0, 1), repeat=3):
        whole &= members[dx : dx + nx, dy : dy + ny, dz : dz + nz]
    keep[labels[:-1, :-1, :-1][whole]] = True
    keep[0] = False
    out = np.zeros_like(level_in)
    out[box] = candidates & keep[labels]
    return out


def _beside(samples: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """True at grid samples with one of their six axis neighbours in ``samples``."""
    out = np.zeros_like(samples)
    for axis in range(3):
        n = samples.shape[axis]
        lower = [slice(None)] * 3
        upper = [slice(None)] * 3
        lower[axis], upper[axis] = slice(0, n - 1), slice(1, n)
        out[tuple(lower)] |= samples[tuple(upper)]
        out[tuple(upper)] |= samples[tuple(lower)]
    return out


def _touches_solid(
    distance_at: Callable[[FloatArray], NDArray[np.floating]], grid: Grid, samples: NDArray[np.bool_]
) -> NDArray[np.bool_]:
    """(nx, ny, nz) True at the ``samples`` that are a corner of a grid cell whose centre is inside (d < 0 by
    ``distance_at``, the field at (N, 3) points)."""
    out = np.zeros(samples.shape, dtype=bool)
    at = np.argwhere(samples)
    if len(at) == 0:
        return out
    cells_shape = np.asarray(samples.shape) - 1
    offsets = np.array(list(itertools.product((-1, 0), repeat=3)))
    cells = (at[:, None, :] + offsets[None, :, :]).reshape(-1, 3)
    valid = np.all((cells >= 0) & (cells < cells_shape), axis=1)
    unique = np.unique(cells[valid], axis=0)
    centres = (np.asarray(grid.origin) + grid.spacing * (unique + 0.5)).astype(np.float64)
    inside_cell = np.zeros(tuple(cells_shape), dtype=bool)
    inside_cell[unique[:, 0], unique[:, 1], unique[:, 2]] = np.asarray(distance_at(centres)) < 0.0
    hit = np.zeros(len(cells), dtype=bool)
    good = cells[valid]
    hit[valid] = inside_cell[good[:, 0], good[:, 1], good[:, 2]]
    out[at[:, 0], at[:, 1], at[:, 2]] = hit.reshape(len(at), len(offsets)).any(axis=1)
    return out


def mesh_trimesh(vertices: FloatArray, faces: NDArray[np.int64], colors: FloatArray) -> trimesh.Trimesh:
    """The output of :func:`mesh` as a ``trimesh.Trimesh`` with 8-bit vertex colours (for export)."""
    vertices = _checks.points("vertices", vertices)
    faces = _checks.indices("faces", faces, 3, len(vertices))
    colors = _checks.finite_array("colors", colors)
    if colors.shape != vertices.shape:
        raise ValueError(f"colors must have the vertices' shape {vertices.shape}, got {colors.shape}")
    rgba = np.concatenate([np.clip(colors, 0.0, 1.0), np.ones((len(colors), 1))], axis=1)
    return trimesh.Trimesh(
        vertices=vertices, faces=faces, vertex_colors=(rgba * 255).round().astype(np.uint8), process=False
    )


# ------------------------------------------------------------------------------------------ sampled fields
def mesh_samples(
    grid: Grid,
    field: NDArray[np.float32],
    mask: NDArray[np.bool_] | None = None,
    distance_at: Callable[[FloatArray], NDArray[np.floating]] | None = None,
) -> tuple[FloatArray, NDArray[np.int64]]:
    """Marching cubes of a field sampled elsewhere (the GLSL editor's, sampled on the GPU), by :func:`mesh`'s pass.

    Args:
        grid: where the samples are (:func:`make_grid`).
        field: (nx, ny, nz) float32 distances (m), negative inside, shaped like ``grid.shape``.
        mask: optional (nx, ny, nz) cells marching cubes may visit.
        distance_at: optional, the field at (N, 3) points (m), for the centres of the cells next to samples on the
            zero level (whether the solid has volume there: see :func:`mesh`); without it, a centre's distance is
            the mean of its cell's eight corners.

    Returns:
        vertices (V, 3) in metres and faces (F, 3) wound outward; empty when no surface crosses the grid.
    """
    _grid(grid)
    # Not through _checks.finite_array: a 512³ field would be copied to float64 (1 GiB).
    if not isinstance(field, np.ndarray) or field.dtype.kind != "f":
        raise ValueError(f"field must be a float array of distances (m), got {type(field).__name__}")
    if field.shape != tuple(grid.shape):
        raise ValueError(f"field must have the grid's shape {grid.shape}, got {field.shape}")
    values = field.astype(np.float32, copy=False)
    if not np.isfinite(values).all():
        raise ValueError("field must be finite float32 distances (m)")
    if mask is not None:
        mask = np.asarray(mask)
        if mask.dtype != np.bool_ or mask.shape != tuple(grid.shape):
            raise ValueError(f"mask must be None or bools of the grid's shape {grid.shape}, got {_checks.shown(mask)}")
    if distance_at is None:
        distance_at = functools.partial(_corner_mean, grid, values)
    elif not callable(distance_at):
        raise ValueError(f"distance_at must be None or a function of (N, 3) points, got {_checks.shown(distance_at)}")
    return _polygonise(grid, values, mask, distance_at)


def _corner_mean(grid: Grid, field: NDArray[np.float32], centres: FloatArray) -> NDArray[np.float32]:
    """The mean of the eight samples of ``field`` around each of the (N, 3) cell ``centres`` (trilinear at the
    centre)."""
    corner = np.rint((centres - np.asarray(grid.origin)) / grid.spacing - 0.5).astype(np.int64)
    total = np.zeros(len(centres), dtype=np.float64)
    for offset in itertools.product((0, 1), repeat=3):
        at = corner + offset
        total += field[at[:, 0], at[:, 1], at[:, 2]]
    return (total / 8.0).astype(np.float32)
