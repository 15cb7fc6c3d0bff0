"""Perspective camera and 4x4 transforms (right-handed, column vectors, OpenGL conventions).

Eye space looks down -z with +y up. ``perspective`` maps eye space to clip space with
``w_clip = -z_eye``; the renderer only needs x, y and w of clip space (no far plane: depth is 1/w).
Screen space: x to the right, y *down*, pixel (x, y) covers [x, x+1) x [y, y+1), centre (x+0.5, y+0.5).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "translate", "scale", "rotate_axis", "rotate_xyz", "look_at", "perspective", "Camera",
]


def translate(t) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = np.asarray(t, np.float64)
    return m


def scale(s) -> np.ndarray:
    s = np.broadcast_to(np.asarray(s, np.float64), (3,))
    return np.diag([s[0], s[1], s[2], 1.0])


def rotate_axis(axis, degrees: float) -> np.ndarray:
    """Rotation by ``degrees`` (right hand) about ``axis``."""
    a = np.asarray(axis, np.float64)
    n = np.linalg.norm(a)
    if n == 0:
        raise ValueError("rotation axis is zero")
    x, y, z = a / n
    th = np.radians(degrees)
    c, s = np.cos(th), np.sin(th)
    C = 1 - c
    m = np.eye(4)
    m[:3, :3] = [
        [c + x * x * C, x * y * C - z * s, x * z * C + y * s],
        [y * x * C + z * s, c + y * y * C, y * z * C - x * s],
        [z * x * C - y * s, z * y * C + x * s, c + z * z * C],
    ]
    return m


def rotate_xyz(degrees) -> np.ndarray:
    """Rotation about x, then y, then z (degrees): R = Rz @ Ry @ Rx."""
    rx, ry, rz = np.asarray(degrees, np.float64)
    return rotate_axis((0, 0, 1), rz) @ rotate_axis((0, 1, 0), ry) @ rotate_axis((1, 0, 0), rx)


def look_at(position, target, up=(0, 1, 0)) -> np.ndarray:
    """World-to-eye matrix of a camera at ``position`` looking at ``target``."""
    eye = np.asarray(position, np.float64)
    f = np.asarray(target, np.float64) - eye
    if np.linalg.norm(f) == 0:
        raise ValueError("camera position equals its target")
    f /= np.linalg.norm(f)
    s = np.cross(f, np.asarray(up, np.float64))
    if np.linalg.norm(s) < 1e-12:
        raise ValueError("camera up vector is parallel to the view direction")
    s /= np.linalg.norm(s)
    u = np.cross(s, f)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = s, u, -f
    m[:3, 3] = -m[:3, :3] @ eye
    return m


def perspective(fov_y_degrees: float, aspect: float) -> np.ndarray:
    """Eye-to-clip matrix (x, y and w rows are what the renderer uses; z is left as -z_eye)."""
    f = 1.0 / np.tan(np.radians(fov_y_degrees) / 2)
    m = np.zeros((4, 4))
    m[0, 0] = f / aspect
    m[1, 1] = f
    m[2, 2] = -1.0  # unused: depth is carried by 1/w
    m[3, 2] = -1.0
    return m


@dataclass(frozen=True)
class Camera:
    """A pinhole camera: look-at placement, vertical field of view (degrees), near plane distance.

    Raises:
        ValueError: if ``fov`` is not in (0, 180) degrees or ``near`` is not positive and finite (a
            field of view of 0 or 180 makes the projection infinite or zero; a near plane at 0 lets
            w = 0 into the perspective divide). Degenerate placements raise in :meth:`view`.
    """

    position: tuple
    target: tuple
    up: tuple = (0.0, 1.0, 0.0)
    fov: float = 45.0
    near: float = 0.1

    def __post_init__(self):
        if not (np.isfinite(self.fov) and 0 < self.fov < 180):
            raise ValueError(f"camera field of view must be in (0, 180) degrees, got {self.fov!r}")
        if not (np.isfinite(self.near) and self.near > 0):
            raise ValueError(f"camera near plane distance must be positive and finite, got {self.near!r}")

    def view(self) -> np.ndarray:
        return look_at(self.position, self.target, self.up)

    def projection(self, width: int, height: int) -> np.ndarray:
        return perspective(self.fov, width / height)

    def view_projection(self, width: int, height: int) -> np.ndarray:
        return self.projection(width, height) @ self.view()
