"""Textures in external memory (docs/memory.md): the AXI4 read master and the texture caches.

- ``axi.py``: the AXI4 read channels' signature (AR and R), from the master's side;
- ``reader.py``: :class:`CachedReader`, the index and raw caches with tags checked ahead of the data
  (a FIFO of references, or blocking), reading lines in INCR bursts; cycle-exact against
  :mod:`golden.memory.timing` with ``address_stages=0``;
- ``unit.py``: :class:`CachedTexelFetch`, the texel-fetch unit behind the reader (``cached_lane``:
  one such lane);
- ``arbiter.py``: :class:`AxiArbiter`, several AXI4 read masters onto one, in a fixed order;
- ``filter.py``: :class:`CachedTextureFilter`, the texture filter with a cached lane per lane
  (cycle-exact against :mod:`golden.memory.filter`).

Callers import the modules by name.
"""
