"""The colour matrix, exhaustively: all 2^24 (Y, U, V) inputs through the RTL stage, compiled.

``sweep(matrix)`` elaborates ``hw.color_matrix.ColorMatrix(matrix)`` alone, converts it with CXXRTL
(the same ``write_cxxrtl`` as the texel-fetch unit), builds it with :file:`drivers/color_sweep.cc`
(cached like the unit: ``toolchain.cached_build``) and streams every input through it, one per clock
with ``en`` high: about 1.7e7 clocks. The RGB it returns is compared with golden's integer matrix
(:meth:`vqtex.golden.color.ColorMatrix.apply`) on every input; golden itself is compared with its
float64 reference (:meth:`~vqtex.golden.color.ColorMatrix.apply_float`, clamped) against its stated
bound (:meth:`~vqtex.golden.color.ColorMatrix.error_bound`), and the outputs clamped at 0 and at 255
are counted per channel. Used by the tests (tests/sim/backends/test_color_sweep.py) and by
``vqtex bench stability``.
"""

from __future__ import annotations

import ctypes
import os
import time

import numpy as np

from .cxxrtl import DRIVER_DIR, cxxrtl_include_dir, write_cxxrtl
from .design import port_map
from .toolchain import cached_build, digest, find_cxx, run_tool, tool_version

__all__ = ["INPUTS", "all_inputs", "rtl_outputs", "golden_check", "sweep", "random_matrix", "extreme_matrix"]

#: Every 8-bit (Y, U, V): input c is Y = c & 255, U = (c >> 8) & 255, V = c >> 16.
INPUTS = 1 << 24
CXXFLAGS = ["-std=c++17", "-O2", "-fPIC", "-shared", "-fvisibility=hidden", "-DNDEBUG"]
#: Inputs per numpy chunk in the golden comparison (bounded temporaries).
CHUNK = 1 << 20


def all_inputs(start: int = 0, stop: int = INPUTS) -> np.ndarray:
    """Inputs ``start .. stop-1`` as (n, 3) uint8 (Y, U, V), in the sweep's order."""
    c = np.arange(start, stop, dtype=np.uint32)
    return np.stack([c & 255, (c >> 8) & 255, c >> 16], axis=1).astype(np.uint8)


def _library(matrix) -> tuple[str, float]:
    from amaranth.hdl import Fragment
    from vqtex.golden.format import COLOR_CODES
    from vqtex.hw.color_matrix import ColorMatrix
    top = ColorMatrix(matrix)
    src = write_cxxrtl(Fragment.get(top, None), port_map(top))
    cxx = find_cxx()
    with open(os.path.join(DRIVER_DIR, "color_sweep.cc"), "rb") as f:
        driver = f.read()
    key = digest("color-sweep", src, driver, CXXFLAGS, tool_version(cxx), COLOR_CODES["yuv411"])

    def build(folder):
        with open(os.path.join(folder, "design.cc"), "w") as f:
            f.write(src)
        run_tool([cxx, *CXXFLAGS, "-I", cxxrtl_include_dir(), "-I", folder,
                  os.path.join(DRIVER_DIR, "color_sweep.cc"), "-o", os.path.join(folder, "libsweep.so")],
                 cwd=folder, what="C++ compiler (colour sweep)", log="build.log")
    path, secs, _ = cached_build("color-sweep", key, build, "libsweep.so")
    return path, secs


def rtl_outputs(matrix) -> tuple[np.ndarray, dict]:
    """(2^24, 3) uint8 RGB of the compiled RTL stage for every input, and timings."""
    from vqtex.golden.format import COLOR_CODES
    from vqtex.hw.color_matrix import LATENCY
    t0 = time.perf_counter()
    path, build_s = _library(matrix)
    lib = ctypes.CDLL(path)
    lib.vq_color_sweep.restype = ctypes.c_uint64
    lib.vq_color_sweep.argtypes = [ctypes.c_void_p, ctypes.c_uint32, ctypes.c_uint32]
    out = np.zeros((INPUTS, 3), np.uint8)
    t1 = time.perf_counter()
    clocks = lib.vq_color_sweep(out.ctypes.data, COLOR_CODES["yuv411"], LATENCY)
    t2 = time.perf_counter()
    return out, {"clocks": int(clocks), "build_seconds": round(t1 - t0, 2), "compiled": build_s > 0,
                 "sweep_seconds": round(t2 - t1, 2)}


def golden_check(matrix, rtl: np.ndarray | None = None) -> dict:
    """Golden's matrix on every input: mismatches against ``rtl`` (if given), worst error against the
    clamped float64 reference and its bound, clamped outputs per channel."""
    mismatches, first, worst = 0, None, 0.0
    low = np.zeros(3, np.int64)
    high = np.zeros(3, np.int64)
    for s in range(0, INPUTS, CHUNK):
        x = all_inputs(s, s + CHUNK)
        g = matrix.apply(x)
        ref = np.clip(matrix.apply_float(x), 0.0, 255.0)
        worst = max(worst, float(np.abs(g - ref).max()))
        low += (g == 0).sum(axis=0)
        high += (g == 255).sum(axis=0)
        if rtl is not None:
            bad = np.flatnonzero(np.any(rtl[s:s + CHUNK] != g, axis=1))
            if len(bad) and first is None:
                k = int(bad[0])
                first = {"yuv": x[k].tolist(), "rtl": rtl[s + k].tolist(), "golden": g[k].tolist()}
            mismatches += len(bad)
    return {"inputs": INPUTS, "mismatches": mismatches, "first_mismatch": first,
            "worst_error": round(worst, 4), "error_bound": round(matrix.error_bound(), 4),
            "within_bound": worst <= matrix.error_bound() + 1e-9,
            "clamped_at_0": low.tolist(), "clamped_at_255": high.tolist()}


def sweep(matrix) -> dict:
    """The RTL stage against golden on all 2^24 inputs (see the module docstring)."""
    rtl, timing = rtl_outputs(matrix)
    return {**golden_check(matrix, rtl), **timing}


def random_matrix(seed: int):
    """A random valid parameterisation over the whole range the unit takes: 18-bit signed
    coefficients (each of a random bit length 1..17, so from -2^17 to 2^17 - 1), any offsets, ``F`` in
    0..16, round or floor."""
    from vqtex.golden.color import ColorMatrix
    rng = np.random.default_rng(seed)
    frac = int(rng.integers(0, 17))
    bits = rng.integers(1, 18, (3, 3))
    coeffs = rng.integers(-(1 << bits), 1 << bits)
    return ColorMatrix(coeffs=coeffs, offsets=tuple(int(v) for v in rng.integers(0, 256, 3)), frac_bits=frac,
                       rounding=bool(rng.integers(0, 2)))


def extreme_matrix():
    """The widest datapath the unit takes: every non-zero coefficient at an end of the 18-bit range (-2^17 or
    2^17 - 1), offsets 0, 255 and 128 (the largest ``|in - off|`` of each sign, so products reach
    their full ``product_bits``), ``F`` = 16 with rounding; each output clamps at both ends and takes
    127 values between (steps of two: a coefficient of 2^17 is 2 at ``F`` = 16)."""
    from vqtex.golden.color import ColorMatrix
    lo, hi = -(1 << 17), (1 << 17) - 1
    return ColorMatrix(coeffs=((hi, hi, 0), (lo, lo, hi), (lo, 0, lo)), offsets=(0, 255, 128), frac_bits=16)
