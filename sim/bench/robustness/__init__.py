"""Numerical stability and hostile input: ``vqtex bench stability`` (docs/stability.md).

:mod:`.stability` (the command: every figure below in one run), :mod:`.fuzz` (mutated ``.vqt``
files), :mod:`.load` (long request streams through ``vqtex sim``, compiled RTL against golden),
:mod:`.encoder_stress` (adversarial training sets through the encoder), :mod:`.decode_memory` (peak
memory of ``vqtex decode`` on the largest valid level). Nothing is re-exported
here: import the modules.
"""
