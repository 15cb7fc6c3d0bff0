"""Simulation backends: the RTL run against the golden model.

``simulate(ts, requests, backend=...)`` (:mod:`.interface`) runs a request stream on one of

- ``golden``: :func:`vqtex.golden.fetch.fetch` with the exact cycle model (:mod:`.cycle_model`);
- ``pysim``: Amaranth's simulator (:mod:`.pysim`), for small tests;
- ``cxxrtl``: the design compiled to C++ by CXXRTL (:mod:`.cxxrtl`, :mod:`.cxxrtl_inplace`), 2e7 cycles/s;
- ``verilator``: the exported Verilog (:mod:`.verilog`) compiled by Verilator (:mod:`.verilator`).

:mod:`.filter` runs the texture filter on the same backends (``simulate_filter``). :mod:`.design`
holds what the compiled backends and the Icarus cross-check need to know about each elaborated unit
(ports, payload layouts, strobes, memories: one description per unit, the texel-fetch unit's and the
filter's); :mod:`.toolchain` finds the compilers and keeps the build cache; ``drivers/`` holds the C++
batch drivers the backends compile, one per simulator for every unit.
"""

from .interface import BACKENDS, SimResult, simulate

__all__ = ["BACKENDS", "SimResult", "simulate"]
