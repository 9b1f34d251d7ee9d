"""The renderer's pinhole camera and shading parameters, and its rays in numpy.

Camera model: a pinhole at ``position`` looking at ``look_at`` with ``up`` and a vertical field of view. Pixel
``(row, col)`` (row 0 at the top) looks along ``forward + x·tan(fov/2)·aspect·right + y·tan(fov/2)·up`` with
``x = 2(col + ½)/W − 1`` and ``y = 1 − 2(row + ½)/H``; :func:`camera_rays` gives the same rays in numpy. Positions
are in metres in the world frame (Z up); angles in radians.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from numpy.typing import NDArray

from kernels import _checks
from kernels.sdf import MAX_FIELD_COORDINATE

MAX_CAMERA_COORDINATE = MAX_FIELD_COORDINATE
"""Largest |coordinate| (m) of a camera's position and target: the shaders march in float32, where squares of
differences of such coordinates stay finite (a camera at 1e300 m drew an empty image with overflow warnings)."""


@dataclasses.dataclass(frozen=True)
class Camera:
    """A pinhole camera in the world frame (Z up)."""

    position: tuple[float, float, float]
    """Eye position (m)."""
    look_at: tuple[float, float, float]
    """Point the view axis passes through (m)."""
    up: tuple[float, float, float] = (0.0, 0.0, 1.0)
    """Approximate up direction; made orthogonal to the view axis."""
    fov_y_rad: float = math.radians(50.0)
    """Vertical field of view (rad), in (0, π)."""

    def __post_init__(self) -> None:
        eye = _checks.vector("position", self.position, 3)
        target = _checks.vector("look_at", self.look_at, 3)
        for name, v in (("position", eye), ("look_at", target)):
            if not (np.abs(v) <= MAX_CAMERA_COORDINATE).all():
                raise ValueError(f"{name} must be of magnitude ≤ {MAX_CAMERA_COORDINATE:g} m, got {v.tolist()}")
        up = _checks.direction("up", self.up, 3)
        forward = target - eye
        if np.linalg.norm(forward) < 1e-9:
            raise ValueError("look_at must differ from position")
        if np.linalg.norm(np.cross(forward, up)) < 1e-9 * np.linalg.norm(forward) * np.linalg.norm(up):
            raise ValueError("up must not be parallel to the view axis")
        fov = _checks.finite_number("fov_y_rad", self.fov_y_rad)
        if not 0.0 < fov < math.pi:
            raise ValueError(f"fov_y_rad must be in (0, π), got {_checks.shown(self.fov_y_rad)}")
        object.__setattr__(self, "position", tuple(float(v) for v in eye))
        object.__setattr__(self, "look_at", tuple(float(v) for v in target))
        object.__setattr__(self, "up", tuple(float(v) for v in up))
        object.__setattr__(self, "fov_y_rad", fov)

    def basis(self) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """Unit (forward, right, up) vectors of the image."""
        forward = np.subtract(self.look_at, self.position).astype(np.float64)
        forward /= np.linalg.norm(forward)
        right = np.cross(forward, self.up)
        right /= np.linalg.norm(right)
        return forward, right, np.cross(right, forward)

    def view_projection(self, aspect: float, near: float, far: float) -> NDArray[np.float64]:
        """(4, 4) OpenGL clip-from-world matrix for this camera."""
        forward, right, up = self.basis()
        eye = np.asarray(self.position, dtype=np.float64)
        view = np.eye(4)
        view[0, :3], view[1, :3], view[2, :3] = right, up, -forward
        view[:3, 3] = -view[:3, :3] @ eye
        f = 1.0 / math.tan(self.fov_y_rad / 2)
        proj = np.zeros((4, 4))
        proj[0, 0], proj[1, 1] = f / aspect, f
        proj[2, 2], proj[2, 3] = (far + near) / (near - far), 2 * far * near / (near - far)
        proj[3, 2] = -1.0
        return proj @ view


@dataclasses.dataclass(frozen=True)
class Shading:
    """Lighting and marching parameters of the reference image; defaults are the gallery's opening values."""

    ambient: float = 0.2
    """k_a, ambient reflection."""
    diffuse: float = 0.75
    """k_d, diffuse reflection."""
    specular: float = 0.3
    """k_s, specular reflection."""
    shininess: float = 32.0
    """α, Phong exponent."""
    light_direction: tuple[float, float, float] = (0.45, -0.35, 0.82)
    """Direction toward the light (world), normalised on use."""
    shadows: bool = True
    """Soft shadows (Quilez's improved technique)."""
    shadow_sharpness: float = 8.0
    """k of the soft shadow: penumbra width ∝ 1/k."""
    occlusion: bool = True
    """Ambient occlusion along the normal."""
    occlusion_strength: float = 3.0
    """How strongly occluded samples darken the ambient term."""
    occlusion_step: float = 0.04
    """Distance between the five AO samples (m)."""
    background: tuple[float, float, float] = (0.93, 0.94, 0.96)
    """Linear RGB where no surface is hit."""
    max_steps: int = 256
    """Sphere-tracing steps before a ray counts as a miss."""
    hit_epsilon: float = 1e-4
    """Hit threshold (m at t ≤ 1, relative beyond)."""
    max_distance: float = 100.0
    """Rays longer than this miss (m)."""
    normal_epsilon: float = 1e-3
    """Central-difference step for normals (m)."""

    def __post_init__(self) -> None:
        # The shaders read these as float32 uniforms: each must be finite there too.
        big = float(np.finfo(np.float32).max)
        for name in ("ambient", "diffuse", "specular", "occlusion_strength"):
            value = _checks.finite_number(name, getattr(self, name))
            if not 0.0 <= value <= 10.0:
                raise ValueError(f"{name} must be in [0, 10], got {_checks.shown(getattr(self, name))}")
            object.__setattr__(self, name, value)
        for name in (
            "shininess",
            "shadow_sharpness",
            "occlusion_step",
            "hit_epsilon",
            "max_distance",
            "normal_epsilon",
        ):
            value = getattr(self, name)
            number = _checks.positive(name, value)
            if number > big:
                raise ValueError(f"{name} must be at most {big:g} (float32), got {_checks.shown(value)}")
            object.__setattr__(self, name, number)
        light = _checks.direction("light_direction", self.light_direction, 3)
        object.__setattr__(self, "light_direction", tuple(float(v) for v in light))
        for name in ("shadows", "occlusion"):
            object.__setattr__(self, name, _checks.flag(name, getattr(self, name)))
        background = _checks.vector("background", self.background, 3)
        if not ((background >= 0.0) & (background <= 1.0)).all():
            raise ValueError(f"background must lie in [0, 1], got {background.tolist()}")
        object.__setattr__(self, "background", tuple(float(v) for v in background))
        steps = _checks.integer("max_steps", self.max_steps, 1)
        if steps > 4096:
            raise ValueError(f"max_steps must be in 1..4096, got {_checks.shown(self.max_steps)}")
        object.__setattr__(self, "max_steps", steps)


def camera_rays(camera: Camera, width: int, height: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The renderer's rays in numpy: origins and unit directions, (H·W, 3) each, row-major from the top row."""
    _checks.instance("camera", camera, Camera)
    check_image_size(width, height)
    forward, right, up = camera.basis()
    tan_half = math.tan(camera.fov_y_rad / 2)
    x = (2 * (np.arange(width) + 0.5) / width - 1) * tan_half * width / height
    y = (1 - 2 * (np.arange(height) + 0.5) / height) * tan_half
    dirs = forward + x[None, :, None] * right + y[:, None, None] * up
    dirs = dirs.reshape(-1, 3)
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    origins = np.broadcast_to(np.asarray(camera.position, dtype=np.float64), dirs.shape).copy()
    return origins, dirs


def check_image_size(width: int, height: int) -> None:
    """``ValueError`` unless ``width`` and ``height`` are integers in 1..8192 (px)."""
    for name, value in (("width", width), ("height", height)):
        if (
            isinstance(value, (bool, np.timedelta64))
            or not isinstance(value, (int, np.integer))
            or not 1 <= value <= 8192
        ):
            raise ValueError(f"{name} must be an integer in 1..8192, got {_checks.shown(value)}")


def screen_rectangle(
    camera: Camera, corners: NDArray[np.float64], width: int, height: int
) -> tuple[int, int, int, int]:
    """(x, y, w, h) pixel rectangle (GL origin bottom left) holding the screen image of (M, 3) world points (m).

    Conservative: the rectangle bounds the points' projections, widened by a pixel; if any point lies near or
    behind the eye it is the whole image, and if all lie behind it, empty.
    """
    _checks.instance("camera", camera, Camera)
    check_image_size(width, height)
    corners = _checks.points("corners", corners)
    if not (np.abs(corners) <= MAX_CAMERA_COORDINATE).all():
        raise ValueError(f"corners must be of magnitude ≤ {MAX_CAMERA_COORDINATE:g} m, got {_checks.shown(corners)}")
    forward, right, up = camera.basis()
    rel = corners - np.asarray(camera.position)
    z = rel @ forward
    if np.all(z <= 0.0):
        return (0, 0, 0, 0)  # wholly behind the eye: nothing to draw
    if np.any(z < 1e-3):
        return (0, 0, width, height)
    tan_half = math.tan(camera.fov_y_rad / 2)
    x_ndc = (rel @ right) / (z * tan_half * width / height)
    y_ndc = (rel @ up) / (z * tan_half)
    x0 = int(np.clip(math.floor((x_ndc.min() + 1) / 2 * width) - 1, 0, width))
    x1 = int(np.clip(math.ceil((x_ndc.max() + 1) / 2 * width) + 1, 0, width))
    y0 = int(np.clip(math.floor((y_ndc.min() + 1) / 2 * height) - 1, 0, height))
    y1 = int(np.clip(math.ceil((y_ndc.max() + 1) / 2 * height) + 1, 0, height))
    return (x0, y0, max(x1 - x0, 0), max(y1 - y0, 0))
