"""Formal properties of the hardware, written as Amaranth ``Assert``/``Assume``/``Cover`` in harnesses
around the stages they are about; :mod:`vqtex.sim.formal` proves them with SymbiYosys
(docs/verification.md).

One module per stage, named after the ``hw`` module it proves things of (``address.py`` for
``hw/address.py``, ``index_reader.py``, ``texel_fetch.py``, ``features.py`` for the specialisation,
``texture_filter.py``), beside ``harness.py`` (the harness, claims and lemmas, seeded bugs,
:class:`~vqtex.hw.formal.harness.Property`), ``stream.py`` (the stream rules, for every stream),
``sets.py`` (the small texture sets the proofs use) and ``properties.py`` (the list of them all).
They are a sub-package rather than code inside each stage's module because a harness is not part of
the unit: it adds free inputs, reference formulas, miters and white-box looks into the unit that a
synthesised unit must not contain, and the stage modules' RTLIL stays what it was."""
