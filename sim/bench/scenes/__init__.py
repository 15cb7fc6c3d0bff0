"""Frames of the built-in scenes measured: render time, cycles, what the frames need, the paper's tables.

:mod:`.render` (``vqtex bench render``: golden render time and RTL cycles per frame), :mod:`.skip`
(``vqtex bench skip``: the sparse request stream against the fixed one), :mod:`.need` (what the scenes
need, pruning and encoding for the frames), :mod:`.experiments` (``vqtex experiments table3|table4|table5``:
the paper's Tables 3, 4 and 5) with :mod:`.paper_configs` (the paper's rows and figures as data), and
:mod:`.hardware_tradeoff` (``vqtex experiments hardware``: frame error against RTL cycles and memory
bits). Nothing is re-exported here: import the modules.
"""
