"""The C++ twin of the golden memory models (``drivers/memory_model.h``), built and called through
ctypes: what the compiled simulators' AXI slave will use, held equal to :mod:`golden.memory.external`
and :mod:`golden.memory.dram` burst for burst (tests/sim/backends/test_memory_model_cxx.py).

``reads(model, t, address, beats) -> (first, queued)``: the model (a ``FixedMemory`` or
``DramMemory`` of golden, whose parameters are passed, not its state) answers the bursts from reset.
"""

from __future__ import annotations

import ctypes
import os

import numpy as np

from vqtex.golden.memory.dram import DramMemory
from vqtex.golden.memory.external import FixedMemory

from .cxxrtl import DRIVER_DIR
from .toolchain import cached_build, digest, find_cxx, run_tool, tool_version

__all__ = ["reads", "library", "model_params"]

CXXFLAGS = ["-std=c++17", "-O2", "-fPIC", "-shared", "-fvisibility=hidden", "-DNDEBUG"]
_TIMINGS = ("CL", "tRCD", "tRP", "tRAS", "tRC", "tRFC", "tREFI", "tRRD", "tFAW", "tRTP")


def library() -> ctypes.CDLL:
    """The built library (cached by the sources, flags and compiler)."""
    cxx = find_cxx()
    sources = {}
    for name in ("memory_model.h", "memory_model.cc"):
        with open(os.path.join(DRIVER_DIR, name), "rb") as f:
            sources[name] = f.read()
    key = digest("memory-model", *sources.values(), CXXFLAGS, tool_version(cxx))

    def build(folder):
        run_tool([cxx, *CXXFLAGS, "-I", DRIVER_DIR, os.path.join(DRIVER_DIR, "memory_model.cc"),
                  "-o", os.path.join(folder, "libmemory.so")], cwd=folder, what="C++ compiler (memory model)",
                 log="build.log")
    path, _, _ = cached_build("memory-model", key, build, "libmemory.so")
    lib = ctypes.CDLL(path)
    p = ctypes.POINTER(ctypes.c_int64)
    lib.vq_memory_reads.argtypes = [ctypes.c_int, p, ctypes.c_int64, p, p, p, p, p]
    lib.vq_memory_reads.restype = ctypes.c_int
    return lib


def model_params(model) -> tuple[int, list]:
    """(kind, parameters) of a golden memory model as memory_model.cc and drivers/axi_slave.h take
    them: 0 and (latency, beat_interval) for FixedMemory, 1 and fourteen integers for DramMemory."""
    if isinstance(model, FixedMemory):
        return 0, [model.latency, model.beat_interval]
    if isinstance(model, DramMemory):
        part = model.part
        return 1, [model.timings[k] for k in _TIMINGS] + [part.banks, part.page_bytes, model.beat_interval,
                                                           model.controller_cycles]
    raise TypeError(f"no C++ twin of {type(model).__name__}")


def reads(model, t, address, beats):
    """(first, queued), int64 arrays: the C++ model of ``model``'s kind and parameters, from reset."""
    kind, params = model_params(model)
    arrays = [np.ascontiguousarray(a, np.int64) for a in (t, address, beats)]
    n = len(arrays[0])
    first, queued = np.zeros(n, np.int64), np.zeros(n, np.int64)
    ptr = ctypes.POINTER(ctypes.c_int64)
    par = np.array(params, np.int64)
    rc = library().vq_memory_reads(kind, par.ctypes.data_as(ptr), n, *(a.ctypes.data_as(ptr) for a in arrays),
                                   first.ctypes.data_as(ptr), queued.ctypes.data_as(ptr))
    if rc:
        raise RuntimeError("vq_memory_reads refused its arguments")
    return first, queued
