"""The interface every simulation backend implements: ``simulate(ts, requests, ...) -> SimResult``.

Backends
--------
``golden``
    Responses from :func:`golden.fetch.fetch`; cycles, stalls, straddles and occupancy from
    :mod:`sim.backends.cycle_model`, the exact cycle model of the RTL.
``pysim``
    Amaranth's simulator running ``hw.texel_fetch.TexelFetch`` (:mod:`sim.backends.pysim`).
other names (``cxxrtl``, ``verilator``, ...)
    The module ``vqtex.sim.backends.<name>`` providing ``run(ts, requests, *, stall, seed, one_port)``
    that returns a :class:`SimResult` (and ``specialise``, the unit's own option: the RTL backends
    build the specialised unit unless ``specialise=False``, the full one; the golden backend's
    answers are the same for both).

Every backend presents the requests back to back from cycle 0 (``i.valid`` high while requests
remain), drives ``o.ready`` from :func:`sim.streams.ready_pattern` ``(seed, stall, ...)`` and counts
cycles from cycle 0 (the first cycle a request is presented) up to and including the cycle the last
response transfers, so ``cycles == N + latency`` without backpressure (plus one cycle per straddling
index read with ``one_port``). All backends return the same responses and the same counts.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass

import numpy as np

from vqtex.golden.fetch import check_requests, fetch
from vqtex.golden.format import TextureSet

__all__ = ["SimResult", "simulate", "prepare", "BACKENDS"]

#: Backend names known here (others are looked up as ``vqtex.sim.backends.<name>``).
BACKENDS = ("golden", "pysim", "cxxrtl", "verilator")
#: Requests the golden backend fetches at a time (golden.fetch's temporaries are ~180 bytes a request).
GOLDEN_CHUNK = 1 << 18


@dataclass
class SimResult:
    """What a simulation run reports.

    Members
    -------
    responses : ndarray uint8 (N, 4)
        RGBA per request, in request order.
    cycles : int
        Cycles from the first cycle a request is presented to the cycle the last response transfers,
        inclusive (0 for no requests).
    requests : int
        N.
    latency : int
        The pipeline's latency (``hw.texel_fetch.LATENCY``).
    stall_cycles : dict
        ``{"output_backpressure": cycles with o.valid & ~o.ready,
        "one_port_straddle": extra index-read cycles (one-port only, else 0)}``.
    straddles : int
        Index reads that straddled a word boundary (counted in both index-reader modes).
    occupancy : dict or None
        Stage name (``hw.texel_fetch.STAGES``) -> fraction of ``cycles`` its valid bit was high.
    load_cycles : int or None
        The loadable unit only: cycles the bus writes that loaded the set took before the requests
        (:func:`golden.register_map.load_cycles`); not part of ``cycles``.
    memory : dict or None
        The cached unit only (textures in external memory, :mod:`sim.backends.memory`): bursts,
        bytes read, hit rates.
    """
    responses: np.ndarray
    cycles: int
    requests: int
    latency: int
    stall_cycles: dict
    straddles: int
    occupancy: dict | None = None
    load_cycles: int | None = None
    memory: dict | None = None


def _as_requests(requests) -> np.ndarray:
    req = np.asarray(requests)
    if req.size == 0:
        return np.zeros((0, 4), np.int64)
    if req.ndim != 2 or req.shape[1] != 4 or not np.issubdtype(req.dtype, np.integer):
        raise ValueError("requests must be an integer array of shape (N, 4): texture, level, i, j")
    return req.astype(np.int64)


def _golden(ts: TextureSet, req: np.ndarray, *, stall: float, seed: int, one_port: bool) -> SimResult:
    from . import cycle_model
    model = cycle_model.run_cycles(ts, req, stall=stall, seed=seed, one_port=one_port)
    responses = np.empty((len(req), 4), np.uint8)
    for s in range(0, len(req), GOLDEN_CHUNK):           # bounded temporaries on long streams
        r = req[s:s + GOLDEN_CHUNK]
        responses[s:s + len(r)] = fetch(ts, r[:, 0], r[:, 1], r[:, 2], r[:, 3])
    return SimResult(responses=responses, cycles=model["cycles"], requests=len(req),
                     latency=cycle_model.LATENCY, stall_cycles=model["stall_cycles"],
                     straddles=model["straddles"], occupancy=model["occupancy"])


def simulate(ts: TextureSet, requests, *, backend: str = "golden", stall: float = 0.0, seed: int = 0,
             one_port: bool = False, specialise: bool = True, geometry=None, memory=None) -> SimResult:
    """Run ``requests`` ((N, 4) int: texture, level, i, j) through ``backend`` (an RTL backend
    simulates ``TexelFetch(ts, specialise=specialise)``: the specialised unit by default). With
    ``geometry`` (:class:`golden.geometry.Geometry`), the loadable unit of that geometry: ``ts`` is
    loaded over its bus port first and ``load_cycles`` reports the load (the golden backend gives
    :func:`golden.register_map.load_cycles`); the requests' cycles are the baked unit's. With
    ``memory`` (:class:`golden.memory.system.MemoryConfig`), the cached unit, its index map and raw
    levels in external memory (:mod:`sim.backends.memory`: every backend); with both, the loadable
    cached unit of ``geometry``, ``ts`` loaded over its bus (``load_cycles``) and its memory image at
    ``Layout.of(ts)``.

    Raises
    ------
    golden.fetch.RequestError
        If a request is outside its texture (checked before any backend runs).
    golden.register_map.LoadError
        If ``ts`` does not fit ``geometry``.
    ValueError
        If ``stall`` is not in [0, 1), the requests are malformed or the backend is unknown.
    """
    stall = float(stall)
    if not 0.0 <= stall < 1.0:
        raise ValueError(f"stall probability {stall} must be in [0, 1)")
    req = _as_requests(requests)
    if len(req):
        check_requests(ts, req[:, 0], req[:, 1], req[:, 2], req[:, 3])
    if memory is not None:
        if one_port or (not specialise and geometry is None):
            raise ValueError("the cached unit is the specialised baked unit or the loadable one: no one-port or "
                             "full unit")
        cached = importlib.import_module("vqtex.sim.backends.memory")     # a backend module, like the others
        return cached.run(ts, req, memory, backend=backend, stall=stall, seed=seed, geometry=geometry)
    load = None
    if geometry is not None:
        from vqtex.golden.register_map import load_cycles, load_writes
        load = load_cycles(len(load_writes(ts, geometry)))      # (refuses a set that does not fit)
    if backend == "golden":
        result = _golden(ts, req, stall=stall, seed=seed, one_port=one_port)
        result.load_cycles = load
        return result
    try:
        module = importlib.import_module(f"vqtex.sim.backends.{backend}")
    except ModuleNotFoundError as e:
        if e.name == f"vqtex.sim.backends.{backend}":
            raise ValueError(f"unknown simulation backend {backend!r}") from None
        raise
    unit = {} if specialise else {"specialise": False}     # (a backend without the option: default)
    if geometry is not None:
        unit["geometry"] = geometry
    return module.run(ts, req, stall=stall, seed=seed, one_port=one_port, **unit)


def prepare(ts: TextureSet, *, backend: str, one_port: bool = False, specialise: bool = True, geometry=None,
            memory=None) -> float:
    """Elaborate the unit that :func:`simulate` with these arguments runs and build its library (or
    find it in the build cache), so that a series of runs then costs the simulations only (a renderer
    calls this once, before its first frame; :func:`sim.backends.filter.prepare_filter` is the
    filter's; with ``memory``, the cached unit's). Returns the seconds it took; nothing to do (0.0) for
    the golden and pysim backends."""
    import time
    if backend not in ("cxxrtl", "verilator"):
        return 0.0
    t0 = time.perf_counter()
    if memory is not None:                  # the cached unit (sim.backends.memory)
        importlib.import_module("vqtex.sim.backends.memory").build_cached(ts, memory, backend, geometry=geometry)
        return time.perf_counter() - t0
    build = getattr(importlib.import_module(f"vqtex.sim.backends.{backend}"), f"build_{backend}")  # (as simulate)
    build(ts, one_port=one_port, specialise=specialise, geometry=geometry)
    return time.perf_counter() - t0
