"""Software renderer: the golden path from scenes to frames (numpy + stdlib only).

Modules, in pipeline order:

- ``scene``: TOML scenes (camera animation, meshes, textures, encoding groups), SceneError,
  ``load_scene``, ``build_texture_set``.
- ``textures``: procedural wood, marble, checker, stripes.  ``imageio``: PNG in/out (OpenImageIO).
- ``mesh``: primitives.  ``camera``: look-at and perspective.
- ``raster``: clipping, fixed-point edge functions (top-left rule), z-buffer, perspective-correct
  (s, t) with analytic derivatives.
- ``sampling``: the two-phase sampler (``requests`` then ``resolve``), point and trilinear with
  fixed-point weights, wrap/clamp. ``sparse``: the sparse request stream (no zero-weight request, no
  repeat; the same frames). ``fovea``: the foveation LOD bias.
- ``pyramid``: the TextureSource protocol and the uncompressed ReferenceSource.
- ``frame``: ``render_frame`` and request-stream export.  ``metrics``: ``frame_mse``.
- ``bench``: ``run()`` prints frame times and requests per frame.
"""

from .frame import frame_requests, load_requests, plan_frame, render_frame, resolve_frame, save_requests
from .metrics import frame_mse, frame_psnr
from .pyramid import ReferenceSource, TextureSource, build_pyramid
from .raster import Fragments, rasterize
from .sampling import Sampler
from .scene import BUILTIN_SCENES, Scene, SceneError, build_texture_set, load_scene, parse_scene

__all__ = [
    "BUILTIN_SCENES", "Fragments", "ReferenceSource", "Sampler", "Scene", "SceneError", "TextureSource",
    "build_pyramid", "build_texture_set", "frame_mse", "frame_psnr", "frame_requests", "load_requests",
    "load_scene", "parse_scene", "plan_frame", "rasterize", "render_frame", "resolve_frame", "save_requests",
]
