"""What every simulation backend shares about streams: the output's backpressure pattern.

The backpressure pattern
------------------------
``o.ready`` in cycle ``t`` (cycle 0 is the first cycle the first request is presented) is
``ready_pattern(seed, stall, n)[t]`` = ``numpy.random.default_rng(seed).random(n)[t] >= stall``.
numpy's generator draws its doubles in sequence, so the pattern is one infinite sequence per
``(seed, stall)`` and any two lengths agree on their common prefix: a backend that runs out of
pattern asks for a longer one. ``stall = 0`` is "always ready". Every backend (golden cycle model,
pysim, cxxrtl, verilator) is fed this same array.
"""

from __future__ import annotations

import numpy as np

__all__ = ["ready_pattern", "pattern_length"]


def ready_pattern(seed: int, stall: float, ncycles: int) -> np.ndarray:
    """``o.ready`` for cycles ``0 .. ncycles-1``: bool array, ``rng.random(n) >= stall``.

    Raises
    ------
    ValueError
        If ``stall`` is not in [0, 1) or ``ncycles`` is negative.
    """
    stall = float(stall)
    if not 0.0 <= stall < 1.0:
        raise ValueError(f"stall probability {stall} must be in [0, 1)")
    if ncycles < 0:
        raise ValueError("ncycles must be non-negative")
    if stall == 0.0:
        return np.ones(int(ncycles), dtype=bool)
    return np.random.default_rng(seed).random(int(ncycles)) >= stall


def pattern_length(n_requests: int, stall: float, slack: int) -> int:
    """A first guess at the pattern length that lets ``n_requests`` transfer (a backend doubles it
    while it is too short): the expected cycles with 25% margin plus ``slack``."""
    return int(n_requests / (1.0 - stall) * 1.25) + int(slack) + 64
