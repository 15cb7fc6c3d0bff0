"""What the tests share (not a test module), by kind:

- :mod:`tests.support.tools`: ``REPO``, ``PVRTEX_DATA``, the external-tool checks (``need``,
  ``need_python``, ``need_synth_tools``), the shared build cache, ``run_cli``, ``assert_one_error``;
- :mod:`tests.support.sets`: texture sets (``image``, ``CONFIGS``, ``texture_set``, ``combined_set``,
  ``texture_sets``, ``builtin_set``, ``levels``, ``random_dt``, ``pvr2_small_sets``, ``get_set``,
  ``scene_set``, ``filter_set``, ``SPECIALISE_CASES``);
- :mod:`tests.support.requests`: request streams (``random_requests``, ``adversarial_requests``,
  ``straddle_offsets``, ``back_to_back_requests``);
- :mod:`tests.support.compare`: a backend against golden (``assert_same``, ``compare_with_golden``;
  the cached unit's traced run: ``assert_cached_run``, ``locality_stream``);
- :mod:`tests.support.hdl`: Amaranth testbench helpers (``stream_put``, ``stream_get``, ``run_lockstep``);
- :mod:`tests.support.scenes`: tiny versions of the paper's scenes for the experiment tests, and the
  scenes several commands' and analyses' tests share (``TINY_SCENE``, ``NEED_SCENE``,
  ``PRUNE_SCENES``, ``small_scene``, ``crates_scene``);
- :mod:`tests.support.pixels`: the sampler's and the texture filter's inputs (``fragments``,
  ``edge_pixels``);
- :mod:`tests.support.hostile`: hostile .vqt files (``HOSTILE_CASES``, ``hostile_files`` and the edits).

Test modules import every name from here, ``from tests.support import ...``, whichever module holds
it. Whatever more than one test module uses belongs here: a test module never imports from another
test module (``tests/test_layout.py`` checks it).
"""

from vqtex.golden.color import JFIF_BT601

from .compare import assert_cached_run, assert_same, compare_with_golden, locality_stream
from .hdl import run_lockstep, stream_get, stream_put
from .hostile import HOSTILE_CASES, edit_descriptor, edit_header, hostile_files, set_key
from .pixels import edge_pixels, fragments
from .requests import adversarial_requests, back_to_back_requests, random_requests, straddle_offsets
from .scenes import CRATE_ARGB, CRATE_YUV_MIP, NEED_SCENE, PRUNE_SCENES, TINY_SCENE, crates_scene, small_scene
from .sets import (CONFIGS, SPECIALISE_CASES, builtin_set, combined_set, filter_set, get_set, image, levels,
                   pvr2_small_sets, random_dt, scene_set, texture_set, texture_sets)
from .tools import (PVRTEX_DATA, REPO, assert_one_error, need, need_python, need_synth_tools, run_cli,
                    shared_cache, shared_cache_dir)

__all__ = ["REPO", "PVRTEX_DATA", "need", "need_python", "shared_cache", "need_synth_tools", "builtin_set", "run_cli",
           "assert_one_error", "shared_cache_dir", "image", "CONFIGS", "texture_set", "combined_set", "texture_sets",
           "levels", "random_requests", "random_dt", "adversarial_requests", "back_to_back_requests", "straddle_offsets",
           "assert_same", "compare_with_golden", "assert_cached_run", "locality_stream", "stream_put", "stream_get", "run_lockstep", "pvr2_small_sets",
           "JFIF_BT601", "get_set", "scene_set", "filter_set", "SPECIALISE_CASES", "TINY_SCENE", "NEED_SCENE",
           "PRUNE_SCENES", "small_scene", "crates_scene", "CRATE_YUV_MIP", "CRATE_ARGB", "fragments", "edge_pixels",
           "HOSTILE_CASES", "hostile_files", "edit_header", "edit_descriptor", "set_key"]
