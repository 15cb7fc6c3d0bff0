"""What the tests share (not a test module), by kind:

- :mod:`tests.support.tools`: ``REPO``, ``PVRTEX_DATA``, the external-tool checks (``need``,
  ``need_python``, ``need_synth_tools``), the shared build cache, ``run_cli``, ``assert_one_error``;
- :mod:`tests.support.sets`: texture sets (``image``, ``CONFIGS``, ``texture_set``, ``combined_set``,
  ``texture_sets``, ``builtin_set``, ``levels``, ``random_dt``, ``pvr2_small_sets``);
- :mod:`tests.support.requests`: request streams (``random_requests``, ``adversarial_requests``,
  ``straddle_offsets``, ``back_to_back_requests``);
- :mod:`tests.support.compare`: a backend against golden (``assert_same``, ``compare_with_golden``);
- :mod:`tests.support.hdl`: Amaranth testbench helpers (``stream_put``, ``stream_get``, ``run_lockstep``);
- :mod:`tests.support.scenes`: tiny versions of the paper's scenes for the experiment tests.

Test modules import every name from here, ``from tests.support import ...``, whichever module holds
it. Fixtures shared by tests of more than one folder belong here, not in a test module.
"""

from vqtex.golden.color import JFIF_BT601

from .compare import assert_same, compare_with_golden
from .hdl import run_lockstep, stream_get, stream_put
from .requests import adversarial_requests, back_to_back_requests, random_requests, straddle_offsets
from .sets import (CONFIGS, builtin_set, combined_set, image, levels, pvr2_small_sets, random_dt, texture_set,
                   texture_sets)
from .tools import (PVRTEX_DATA, REPO, assert_one_error, need, need_python, need_synth_tools, run_cli,
                    shared_cache, shared_cache_dir)

__all__ = ["REPO", "PVRTEX_DATA", "need", "need_python", "shared_cache", "need_synth_tools", "builtin_set", "run_cli",
           "assert_one_error", "shared_cache_dir", "image", "CONFIGS", "texture_set", "combined_set", "texture_sets",
           "levels", "random_requests", "random_dt", "adversarial_requests", "back_to_back_requests", "straddle_offsets",
           "assert_same", "compare_with_golden", "stream_put", "stream_get", "run_lockstep", "pvr2_small_sets",
           "JFIF_BT601"]
