"""Rendering a frame of a scene: rasterize, request texels, fetch them from a source, resolve.

    frame = render_frame(scene, frame_no, source, mode="trilinear")     # (H, W, 4) uint8

is exactly

    sampler = plan_frame(scene, frame_no, source, mode)   # rasterization + sampler
    reqs = sampler.requests(sampler.fragments)            # (N, 4) int64 (texture, level, i, j)
    texels = source.fetch(reqs[:, 0], reqs[:, 1], reqs[:, 2], reqs[:, 3])
    frame = sampler.resolve(texels)

so a frame's request stream can be exported (``frame_requests`` / ``save_requests``), answered by
any backend (the RTL), and resolved into the identical frame (``resolve_frame``).
"""

from __future__ import annotations

import os
from typing import Sequence

import numpy as np

from ..requests import read_request_file
from .pyramid import TextureSource
from .raster import Fragments, rasterize
from .sampling import Sampler

__all__ = [
    "fragments", "plan_frame", "frame_requests", "resolve_frame", "render_frame", "render_frames",
    "save_requests", "load_requests",
]


def _shapes(scene, source) -> list[list[tuple[int, int]]]:
    """Level shapes per scene texture, from the source; checked against the scene's sizes."""
    if isinstance(source, (list, tuple)):
        shapes = [list(s) for s in source]
    else:
        shapes = [list(source.level_shapes(t.id)) for t in scene.textures]
    if len(shapes) != len(scene.textures):
        raise ValueError(f"source has {len(shapes)} textures, the scene {len(scene.textures)}")
    for t, s in zip(scene.textures, shapes):
        if not s or tuple(s[0]) != tuple(t.size):
            raise ValueError(f"texture {t.id} '{t.name}': source level 0 is "
                             f"{s[0] if s else None}, the scene says {t.size}")
    return shapes


def fragments(scene, frame_no: float) -> Fragments:
    """Visible fragments (rasterization and depth test) of one frame; a SceneError (one line) when the
    frame's geometry is beyond the rasterizer's limits (``raster``'s Limits: non-finite, or a clipped
    triangle beyond ``CLIP_RANGE`` times the near plane)."""
    from .scene import SceneError
    clip, st, tex = scene.triangles_at(frame_no)
    try:
        return rasterize(clip, st, tex, scene.width, scene.height, scene.camera_at(frame_no).near)
    except ValueError as e:
        raise SceneError(f"scene {scene.name}, frame {frame_no}: {e}") from None


def plan_frame(scene, frame_no: float, source: TextureSource | Sequence, mode: str = "trilinear", *,
               stream: str = "sparse", fovea=None) -> Sampler:
    """A Sampler for one frame with its fragments attached as ``sampler.fragments``.

    ``source`` is a TextureSource or directly the list of level shapes per texture; ``stream`` and
    ``fovea`` are the Sampler's (the sparse or fixed request stream, an optional LOD bias).
    """
    sampler = Sampler(_shapes(scene, source), scene.addressing, mode, scene.background, stream=stream, fovea=fovea)
    sampler.fragments = fragments(scene, frame_no)
    return sampler


def frame_requests(scene, frame_no: float, source, mode: str = "trilinear", **options):
    """(requests (N, 4) int64, sampler) of one frame; resolve with ``sampler.resolve(texels)``.
    ``options``: :func:`plan_frame`'s ``stream`` and ``fovea``."""
    sampler = plan_frame(scene, frame_no, source, mode, **options)
    return sampler.requests(sampler.fragments), sampler


def resolve_frame(scene, frame_no: float, source, texels: np.ndarray, mode: str = "trilinear",
                  **options) -> np.ndarray:
    """The frame from externally fetched texels answering ``frame_requests`` (same arguments)."""
    _, sampler = frame_requests(scene, frame_no, source, mode, **options)
    return sampler.resolve(texels)


def render_frame(scene, frame_no: float, source: TextureSource, mode: str = "trilinear", **options) -> np.ndarray:
    """Render frame ``frame_no`` of ``scene`` with texels from ``source``: (H, W, 4) uint8 RGBA.
    ``options``: :func:`plan_frame`'s ``stream`` and ``fovea``."""
    reqs, sampler = frame_requests(scene, frame_no, source, mode, **options)
    texels = source.fetch(reqs[:, 0], reqs[:, 1], reqs[:, 2], reqs[:, 3])
    return sampler.resolve(np.asarray(texels, np.uint8))


def render_frames(scene, source: TextureSource, mode: str = "trilinear", frames=None, **options):
    """Yield (frame_no, frame) for ``frames`` (default: all of the scene's frames)."""
    for f in range(scene.frames) if frames is None else frames:
        yield f, render_frame(scene, f, source, mode, **options)


def save_requests(path: str | os.PathLike, reqs: np.ndarray) -> None:
    """Write a request stream as an .npy int64 array (N, 4), atomically."""
    reqs = np.asarray(reqs)
    if reqs.ndim != 2 or reqs.shape[1] != 4 or not np.issubdtype(reqs.dtype, np.integer):
        raise ValueError(f"requests must be an integer array (N, 4), got {reqs.dtype} {reqs.shape}")
    path = os.fspath(path)
    tmp = f"{path}.tmp-{os.getpid()}.npy"
    try:
        np.save(tmp, reqs.astype(np.int64))
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def load_requests(path: str | os.PathLike) -> np.ndarray:
    """Read a request stream written by :func:`save_requests` (or any request file): (N, 4) int64.
    See :func:`golden.requests.read_request_file`; raises its :class:`~golden.fetch.RequestError`
    (a ``ValueError``) with one line naming the file."""
    return read_request_file(path)
