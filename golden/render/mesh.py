"""Triangle meshes with texture coordinates, and the built-in primitives.

A :class:`Mesh` is three arrays: ``positions`` (V, 3) float64 in model space, ``texcoords`` (V, 2)
float64 (s, t) and ``triangles`` (T, 3) int64 vertex indices. (s, t) = (0, 0) is the top-left corner
of the texture image (row 0), s runs along the image's columns, t along its rows; values outside
[0, 1) repeat or clamp according to the texture's addressing.

Primitives (all centred on the origin unless said otherwise):

- ``plane(size=(w, d), tiling=(tu, tv), segments=(nu, nv))``: the XZ plane y = 0, facing +y.
- ``quad(size=(w, h), tiling)``: the XY plane z = 0, facing +z, image upright (t = 0 at the top).
- ``box(size=(w, h, d), tiling)``: six faces; the side faces are upright, its base is at y = 0.
- ``revolve(profile, segments, tiling)``: a surface of revolution about +y; ``profile`` lists
  (radius, y) from top to bottom; s goes round, t follows the profile's arc length.
- ``cylinder``, ``cone``, ``sphere``, ``top`` (a spinning top, point at y = 0): profiles for revolve.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Mesh", "plane", "quad", "box", "revolve", "cylinder", "cone", "sphere", "top", "triangles"]


@dataclass
class Mesh:
    positions: np.ndarray
    texcoords: np.ndarray
    triangles: np.ndarray

    def __post_init__(self):
        self.positions = np.asarray(self.positions, np.float64).reshape(-1, 3)
        self.texcoords = np.asarray(self.texcoords, np.float64).reshape(-1, 2)
        self.triangles = np.asarray(self.triangles, np.int64).reshape(-1, 3)
        if len(self.positions) != len(self.texcoords):
            raise ValueError("a mesh needs one (s, t) per vertex")
        if self.triangles.size and (self.triangles.min() < 0 or self.triangles.max() >= len(self.positions)):
            raise ValueError("triangle vertex index out of range")

    @staticmethod
    def concat(meshes: list["Mesh"]) -> "Mesh":
        pos, tc, tri, base = [], [], [], 0
        for m in meshes:
            pos.append(m.positions)
            tc.append(m.texcoords)
            tri.append(m.triangles + base)
            base += len(m.positions)
        return Mesh(np.concatenate(pos), np.concatenate(tc), np.concatenate(tri))


def _grid_triangles(rows: int, cols: int) -> np.ndarray:
    """Two triangles per cell of a (rows+1) x (cols+1) vertex grid, row-major vertices."""
    r, c = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
    v00 = (r * (cols + 1) + c).ravel()
    v01 = v00 + 1
    v10 = v00 + cols + 1
    v11 = v10 + 1
    return np.concatenate([np.stack([v00, v10, v11], 1), np.stack([v00, v11, v01], 1)])


def _sheet(origin, du, dv, tiling, segments) -> Mesh:
    """A flat parallelogram origin + a*du + b*dv, a, b in [0, 1], with (s, t) = (a*tu, b*tv)."""
    nu, nv = (int(x) for x in segments)
    a = np.linspace(0, 1, nu + 1)
    b = np.linspace(0, 1, nv + 1)
    B, A = np.meshgrid(b, a, indexing="ij")
    pos = np.asarray(origin, float) + A[..., None] * np.asarray(du, float) + B[..., None] * np.asarray(dv, float)
    tc = np.stack([A * tiling[0], B * tiling[1]], -1)
    return Mesh(pos.reshape(-1, 3), tc.reshape(-1, 2), _grid_triangles(nv, nu))


def plane(size=(1.0, 1.0), tiling=(1.0, 1.0), segments=(1, 1)) -> Mesh:
    w, d = size
    return _sheet((-w / 2, 0, -d / 2), (w, 0, 0), (0, 0, d), tiling, segments)


def quad(size=(1.0, 1.0), tiling=(1.0, 1.0), segments=(1, 1)) -> Mesh:
    w, h = size
    return _sheet((-w / 2, h / 2, 0), (w, 0, 0), (0, -h, 0), tiling, segments)


def box(size=(1.0, 1.0, 1.0), tiling=(1.0, 1.0)) -> Mesh:
    w, h, d = size
    x0, x1, y0, y1, z0, z1 = -w / 2, w / 2, 0.0, h, -d / 2, d / 2
    faces = [
        _sheet((x0, y1, z1), (w, 0, 0), (0, -h, 0), tiling, (1, 1)),  # front (+z)
        _sheet((x1, y1, z1), (0, 0, -d), (0, -h, 0), tiling, (1, 1)),  # right (+x)
        _sheet((x1, y1, z0), (-w, 0, 0), (0, -h, 0), tiling, (1, 1)),  # back (-z)
        _sheet((x0, y1, z0), (0, 0, d), (0, -h, 0), tiling, (1, 1)),  # left (-x)
        _sheet((x0, y1, z0), (w, 0, 0), (0, 0, d), tiling, (1, 1)),  # top (+y)
        _sheet((x0, y0, z1), (w, 0, 0), (0, 0, -d), tiling, (1, 1)),  # bottom (-y)
    ]
    return Mesh.concat(faces)


def revolve(profile, segments: int = 32, tiling=(1.0, 1.0)) -> Mesh:
    """Surface of revolution about +y of ``profile`` [(radius, y), ...] (top to bottom)."""
    prof = np.asarray(profile, np.float64)
    if prof.ndim != 2 or prof.shape[1] != 2 or len(prof) < 2:
        raise ValueError("profile must list at least two (radius, y) points")
    segments = int(segments)
    if segments < 3:
        raise ValueError("a surface of revolution needs at least 3 segments")
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(prof, axis=0).T))])
    t = arc / arc[-1] if arc[-1] > 0 else np.linspace(0, 1, len(prof))
    ang = np.linspace(0, 2 * np.pi, segments + 1)
    r = prof[:, 0][:, None]
    x = r * np.sin(ang)[None, :]
    z = r * np.cos(ang)[None, :]
    y = np.broadcast_to(prof[:, 1][:, None], x.shape)
    pos = np.stack([x, y, z], -1).reshape(-1, 3)
    s = np.broadcast_to(ang[None, :] / (2 * np.pi) * tiling[0], x.shape)
    tt = np.broadcast_to(t[:, None] * tiling[1], x.shape)
    tc = np.stack([s, tt], -1).reshape(-1, 2)
    return Mesh(pos, tc, _grid_triangles(len(prof) - 1, segments))


def cylinder(radius=0.5, height=1.0, segments=32, tiling=(1.0, 1.0)) -> Mesh:
    return revolve([(0, height), (radius, height), (radius, 0), (0, 0)], segments, tiling)


def cone(radius=0.5, height=1.0, segments=32, tiling=(1.0, 1.0)) -> Mesh:
    return revolve([(0, height), (radius, 0), (0, 0)], segments, tiling)


def sphere(radius=0.5, segments=32, rings=16, tiling=(1.0, 1.0)) -> Mesh:
    phi = np.linspace(0, np.pi, int(rings) + 1)
    return revolve(np.stack([radius * np.sin(phi), radius * (1 + np.cos(phi))], 1), segments, tiling)


def top(radius=0.5, height=1.0, segments=48, tiling=(1.0, 1.0)) -> Mesh:
    """A spinning top standing on its point at the origin: stem, crown, wide body, tip."""
    prof = np.array([
        (0.00, 1.00), (0.10, 1.00), (0.10, 0.80), (0.30, 0.76), (0.60, 0.70), (0.85, 0.64),
        (1.00, 0.56), (0.98, 0.50), (0.88, 0.42), (0.70, 0.30), (0.45, 0.17), (0.20, 0.06),
        (0.04, 0.005), (0.00, 0.00),
    ])
    return revolve(prof * [radius, height], segments, tiling)


def triangles(vertices, texcoords, indices) -> Mesh:
    """An explicit mesh."""
    return Mesh(vertices, texcoords, indices)
