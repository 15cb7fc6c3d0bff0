"""The formal proofs' runner: the properties of :mod:`vqtex.hw.formal` proved with SymbiYosys
(YoWASP's build, with an SMT solver from the package index), for ``vqtex verify`` and the tests.
``runner.py`` writes the RTLIL and the ``.sby`` files, runs them and reads the results; see
docs/verification.md."""
