"""How fast the RTL simulates (docs/simulation.md).

:mod:`.simulation` (``vqtex bench sim``: pysim, CXXRTL and Verilator side by side on the default
unit), :mod:`.units` (the specialised unit against the full one on CXXRTL). Nothing is re-exported
here: import the modules.
"""
