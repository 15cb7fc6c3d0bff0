"""The RTL run against the golden model, and the tools around it.

Layers (each imports only those below it; nothing here is imported by ``golden`` or ``hw``):

- :mod:`.cli`: the ``vqtex`` command line, one module per subcommand;
- :mod:`.bench`: benchmarks and the paper's experiments;
- :mod:`.reports`: cycle reports and plots, synthesis and area;
- :mod:`.backends`: the simulators (golden cycle model, pysim, CXXRTL, Verilator, Icarus) and Verilog export;
- :mod:`.streams`: the ready patterns and stream helpers every backend shares.
"""
