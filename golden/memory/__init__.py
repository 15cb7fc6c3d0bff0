"""The external memory system: where textures live when they are not on chip (docs/memory.md).

One definition of the memory's timing, used by the golden cycle model and, later, by every
simulator's AXI slave:

- ``external.py``: the contract of a memory read over AXI4 (a burst of beats answered in order) and
  a memory of fixed latency and bandwidth;
- ``dram.py``: a DDR3 part (Micron MT41K256M16, DDR3-1600) behind an in-order open-page controller:
  banks, open rows, refresh;
- ``cache.py``: set-associative LRU caches of lines, classified over a reference stream;
- ``system.py``: the unit's memory configuration (caches, memory, layout) and the references a
  request stream makes;
- ``timing.py``: the exact cycle count of a request stream through the cached unit;
- ``filter.py``: the exact cycle count of the texture filter's pixels through a cache per lane;
- ``arbiter.py``: the order in which the lanes' bursts share one AXI master.

Callers import the modules by name.
"""
