"""Software renderer: the golden path from scenes to frames (numpy + stdlib only).

Modules, in pipeline order:

- ``scene``: TOML scenes (camera animation, meshes, textures, encoding groups), SceneError,
  ``load_scene``, ``build_texture_set``.
- ``textures``: procedural wood, marble, checker, stripes.  ``imageio``: PNG in/out (OpenImageIO).
- ``mesh``: primitives.  ``camera``: look-at and perspective.
- ``raster``: clipping, fixed-point edge functions (top-left rule), z-buffer, perspective-correct
  (s, t) with analytic derivatives.
- ``sampling``: the two-phase sampler (``requests`` then ``resolve``), point, bilinear and trilinear
  with fixed-point weights (golden.filter), wrap/clamp/mirror. ``sparse``: the sparse request stream
  (no zero-weight request, no repeat; the same frames). ``fovea``: the foveation LOD bias.
- ``pyramid``: the TextureSource protocol and the uncompressed ReferenceSource.
- ``frame``: ``render_frame`` and request-stream export.  ``metrics``: ``frame_mse``.
- ``bench``: ``run()`` prints frame times and requests per frame.
"""

import importlib

#: Each name the package exports and the module that defines it. They are imported on first use
#: (PEP 562), so that importing one module of the package (``imageio``, to read an image for
#: ``vqtex encode``) does not import the whole renderer.
_HOMES = {
    "frame_requests": "frame", "load_requests": "frame", "plan_frame": "frame", "render_frame": "frame",
    "resolve_frame": "frame", "save_requests": "frame",
    "frame_mse": "metrics", "frame_psnr": "metrics",
    "ReferenceSource": "pyramid", "TextureSource": "pyramid", "build_pyramid": "pyramid",
    "Fragments": "raster", "rasterize": "raster",
    "Sampler": "sampling",
    "BUILTIN_SCENES": "scene", "Scene": "scene", "SceneError": "scene", "build_texture_set": "scene",
    "load_scene": "scene", "parse_scene": "scene",
}

__all__ = sorted(_HOMES)


def __getattr__(name):
    if name not in _HOMES:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{_HOMES[name]}"), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
