"""What the tests share (not a test module): test images and texture sets, request streams, the
golden-vs-RTL comparison, Amaranth stream helpers for testbenches, and the external-tool check.

Test modules import it as ``from tests.support import ...``.
"""

from __future__ import annotations

import contextlib
import functools
import os
import shutil

import numpy as np
import pytest

from vqtex.golden.pvr2 import pvr, pvr_set
from vqtex.golden.color import DREAMCAST_YUV422, JFIF_BT601
from vqtex.golden.encode import encode
from vqtex.golden.fetch import block_address, fetch, lookup_descriptor, random_requests, straddles
from vqtex.golden.format import TextureSet
from vqtex.hw.texel_fetch import LATENCY, REGISTERS
from vqtex.sim.backends import simulate
from vqtex.sim.backends.toolchain import using_cache

__all__ = ["REPO", "need", "need_python", "shared_cache", "need_synth_tools", "builtin_set", "run_cli", "assert_one_error", "shared_cache_dir", "image", "CONFIGS", "texture_set", "combined_set", "texture_sets",
           "levels", "random_requests", "random_dt", "adversarial_requests", "back_to_back_requests", "straddle_offsets",
           "assert_same", "compare_with_golden", "stream_put", "stream_get", "run_lockstep", "JFIF_BT601"]

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def need(*tools):
    """Skip (or, with VQTEX_REQUIRE_TOOLS=1, fail) unless every tool is on the PATH."""
    missing = [t for t in tools if shutil.which(os.environ.get("CXX", t) if t == "g++" else t) is None]
    if missing:
        msg = f"needs {', '.join(missing)} (scripts/install-sim-tools)"
        if os.environ.get("VQTEX_REQUIRE_TOOLS") == "1":
            pytest.fail(msg + " and VQTEX_REQUIRE_TOOLS=1")
        pytest.skip(msg)


def need_python(*modules):
    """Skip (or, with VQTEX_REQUIRE_TOOLS=1, fail) unless the Python modules import (the ``test``
    extra installs them)."""
    import importlib
    missing = []
    for name in modules:
        try:
            importlib.import_module(name)
        except ImportError as e:
            missing.append(f"{name} ({e})")
    if missing:
        msg = f"needs {', '.join(missing)} (pip install '.[test]')"
        if os.environ.get("VQTEX_REQUIRE_TOOLS") == "1":
            pytest.fail(msg + " and VQTEX_REQUIRE_TOOLS=1")
        pytest.skip(msg)


def need_synth_tools():
    """Skip (or, with VQTEX_REQUIRE_TOOLS set, fail) unless Yosys and nextpnr-ecp5 (the ``synth``
    extra) are installed."""
    from vqtex.sim.reports import synth
    missing = [name for name, ok in synth.tools_available().items() if not ok]
    if missing:
        msg = f"{', '.join(missing)} not installed (pip install '.[synth]')"
        if os.environ.get("VQTEX_REQUIRE_TOOLS"):
            pytest.fail(msg)
        pytest.skip(msg)


@functools.lru_cache(maxsize=None)
def builtin_set(name: str) -> TextureSet:
    """The built-in texture set ``name`` of ``vqtex report area --builtin NAME`` (``tiny``, ``four``,
    ...), encoded once per test run: tests take it from here, not from the product's modules."""
    from vqtex.sim.cli.report import BUILTINS
    from vqtex.sim.reports.synth import texture_sets
    return getattr(texture_sets, BUILTINS[name][0])()


@contextlib.contextmanager
def shared_cache():
    """``$VQTEX_CACHE`` set to :func:`shared_cache_dir` inside the block (the builds of every test
    run shared), restored after. Test modules use it as an autouse fixture: ``with shared_cache(): yield``."""
    with using_cache(shared_cache_dir()):
        yield


def run_cli(capsys, *argv):
    """``vqtex ARGV`` in this process: (exit status, stdout, stderr) of that call alone."""
    from vqtex.sim.cli import main
    capsys.readouterr()
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def assert_one_error(capsys, argv, pattern):
    """``vqtex ARGV`` ends with exit status 2, nothing on stdout and one ``vqtex: error:`` line on
    stderr containing ``pattern``."""
    code, out, err = run_cli(capsys, *argv)
    assert code == 2 and out == "", (argv, out)
    assert err.count("\n") == 1 and err.startswith("vqtex: error: ") and pattern in err, (argv, err)


def shared_cache_dir():
    """Builds shared by test runs: $VQTEX_CACHE if set, else the repository's .vqtex-cache/."""
    return os.environ.get("VQTEX_CACHE") or os.path.join(REPO, ".vqtex-cache")


def image(size, seed, channels=4):
    """A noisy gradient (h, w, channels) uint8: every codeword gets used, mip levels differ."""
    w, h = size
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:h, 0:w]
    base = np.stack([xx * 255 // max(1, w - 1), yy * 255 // max(1, h - 1), (xx + yy) * 127 // max(1, w + h - 2),
                     255 - yy * 200 // max(1, h - 1)], axis=2)
    img = np.clip(base + rng.integers(-60, 61, (h, w, 4)), 0, 255).astype(np.uint8)
    return img[..., :channels]


#: name -> encode() keyword arguments. Sizes 32..64, 8..16 codewords (256 for the full 8-bit range).
CONFIGS = {
    "rgb_4x4_b8_mip": dict(size=(64, 64), block=(4, 4), codebook_size=16, color="rgb", index_bits=8,
                           mipmaps=True, raw_below=4),
    "yuv_4x4_b12_mip": dict(size=(64, 64), block=(4, 4), codebook_size=16, color="yuv411", index_bits=12,
                            mipmaps=True, raw_below=4),
    "rgba_2x2_b7_mip_w16": dict(size=(32, 32), block=(2, 2), codebook_size=16, color="rgba", index_bits=7,
                                mipmaps=True, raw_below=4, word_bits=16),
    "i8_4x2_b5_w64": dict(size=(64, 32), block=(4, 2), codebook_size=12, color="intensity", index_bits=5,
                          word_bits=64),
    "yuv_2x4_b12_mip_w64": dict(size=(32, 64), block=(2, 4), codebook_size=10, color="yuv411", index_bits=12,
                                mipmaps=True, raw_below=8, word_bits=64),
    "rgb_4x4_b12_w16": dict(size=(32, 32), block=(4, 4), codebook_size=16, color="rgb", index_bits=12,
                            word_bits=16),
    "rgb_4x4_b8_k256": dict(size=(64, 64), block=(4, 4), codebook_size=256, color="rgb", index_bits=8),
    "rgb_2x2_b16_w16": dict(size=(32, 32), block=(2, 2), codebook_size=8, color="rgb", index_bits=16,
                            word_bits=16),
    "i8_4x4_b1_mip": dict(size=(32, 32), block=(4, 4), codebook_size=2, color="intensity", index_bits=1,
                          mipmaps=True, raw_below=4),
    "rgba_8x8_b9_mip": dict(size=(64, 64), block=(8, 8), codebook_size=8, color="rgba", index_bits=9,
                            mipmaps=True, raw_below=8),
    "yuv_8x2_b6": dict(size=(64, 32), block=(8, 2), codebook_size=8, color="yuv411", index_bits=6),
    "raw_only_8x8_mip": dict(size=(8, 8), block=(4, 4), codebook_size=4, color="rgb", mipmaps=True),
    "yuv_dreamcast_4x4_b12_mip": dict(size=(64, 64), block=(4, 4), codebook_size=16, color="yuv411",
                                      index_bits=12, mipmaps=True, raw_below=4, matrix=DREAMCAST_YUV422),
}


@functools.lru_cache(maxsize=None)
def texture_set(name: str, seed: int = 0, images: int = 1) -> TextureSet:
    kw = dict(CONFIGS[name])
    size = kw.pop("size")
    return encode([image(size, seed + n) for n in range(images)], seed=seed, **kw)


@functools.lru_cache(maxsize=None)
def combined_set() -> TextureSet:
    """Several groups with their own codebooks and formats (and two textures sharing one), 32-bit words."""
    parts = [
        encode([image((64, 64), 10), image((32, 32), 11)], block=(4, 4), codebook_size=16, color="rgb",
               index_bits=8, mipmaps=True, raw_below=4, seed=1),
        encode([image((32, 32), 12)], block=(2, 2), codebook_size=8, color="yuv411", index_bits=12, seed=2),
        encode([image((64, 32), 13)], block=(4, 2), codebook_size=12, color="intensity", index_bits=5,
               mipmaps=True, raw_below=8, seed=3),
        encode([image((32, 64), 14)], block=(2, 4), codebook_size=16, color="rgba", index_bits=7, seed=4),
        encode([image((8, 8), 15)], block=(4, 4), codebook_size=4, color="rgb", mipmaps=True, seed=5),  # all raw
    ]
    return TextureSet.combine(parts)


def levels(ts: TextureSet):
    """Every (texture, level, width, height)."""
    for t in range(ts.n_textures):
        for L, (w, h) in enumerate(ts.level_shapes(t)):
            yield t, L, w, h


def adversarial_requests(ts: TextureSet, seed: int = 0) -> np.ndarray:
    """Every corner of every level; the first and last block's corners; for every compressed level,
    a texel of blocks whose index starts at every bit offset of a word (every straddle position)."""
    rng = np.random.default_rng(seed)
    out = []
    for t, L, w, h in levels(ts):
        for i, j in ((0, 0), (w - 1, 0), (0, h - 1), (w - 1, h - 1)):
            out.append((t, L, i, j))
        d = ts.descriptor(t, L)
        if not d["compressed"]:
            out.append((t, L, int(rng.integers(0, w)), int(rng.integers(0, h))))
            continue
        bw, bh = 1 << d["log2bw"], 1 << d["log2bh"]
        nbx, nby = w // bw, h // bh
        # first and last block: their far corners too
        out += [(t, L, bw - 1, bh - 1), (t, L, w - bw, h - bh)]
        # blocks 0 .. W-1 cover every offset k*b mod W (one per offset class)
        b, W = d["index_bits"], ts.word_bits
        seen = set()
        for k in range(min(nbx * nby, W)):
            off = (k * b) % W
            if off in seen:
                continue
            seen.add(off)
            bx, by = k % nbx, k // nbx
            out.append((t, L, bx * bw + int(rng.integers(0, bw)), by * bh + int(rng.integers(0, bh))))
    req = np.array(out, dtype=np.int64)
    return req[rng.permutation(len(req))]


def straddle_offsets(ts: TextureSet, req: np.ndarray) -> set:
    """Bit offsets (k*b mod W) at which the compressed requests' indices start."""
    d = lookup_descriptor(ts, req[:, 0], req[:, 1])
    comp = d["compressed"].astype(bool)
    k, _, _ = block_address(d[comp], req[comp, 2], req[comp, 3])
    return set(((k * d[comp]["index_bits"].astype(np.int64)) % ts.word_bits).tolist())


def texture_sets():
    """Small texture sets covering the configuration matrix (kept tiny for pysim)."""
    rgb12 = encode([image((64, 64), 0, 3)], codebook_size=16, mipmaps=True, index_bits=12)
    yuv = encode([image((32, 32), 1, 3), image((32, 32), 2, 3)], codebook_size=8, color="yuv411", block=(2, 2), mipmaps=True,
                 index_bits=5)
    rgba = encode([image((32, 32), 3, 4)], codebook_size=16, color="rgba", index_bits=8)
    inten = encode([image((32, 32), 4, 1)], codebook_size=32, color="intensity", block=(2, 2), index_bits=7,
                   encoder="tsvq")
    mixed = TextureSet.combine([rgb12, yuv, rgba, inten])
    w16 = encode([image((32, 32), 5, 3)], codebook_size=32, block=(2, 2), mipmaps=True, index_bits=12, word_bits=16)
    return {"rgb12": rgb12, "mixed": mixed, "w16": w16}


def back_to_back_requests(ts, limit=200):
    """Texels whose index straddles a word boundary (back to back), the corners of every level,
    the same texel repeated, and textures alternating every request."""
    rows = []
    for t, info in enumerate(ts.textures):
        for L in range(info.levels):
            d = ts.descriptors[t, L]
            w, h = 1 << int(d["log2w"]), 1 << int(d["log2h"])
            rows += [[t, L, 0, 0], [t, L, w - 1, h - 1], [t, L, w - 1, 0], [t, L, 0, h - 1]]
            if d["compressed"]:
                jj, ii = np.mgrid[0:h, 0:w]
                req = np.stack([np.full(w * h, t), np.full(w * h, L), ii.ravel(), jj.ravel()], 1)
                dd = lookup_descriptor(ts, req[:, 0], req[:, 1])
                k, _, _ = block_address(dd, req[:, 2], req[:, 3])
                s = req[straddles(dd, k, ts.word_bits)]
                rows += s[:: max(1, len(s) // 12)][:12].tolist()
    rows += [rows[0]] * 5
    alt = random_requests(ts, 20, seed=7)
    rows += alt.tolist()
    return np.array(rows[:limit] if len(rows) > limit else rows, dtype=np.int64)


def assert_same(a, b, what=""):
    """Two SimResults agree on everything they hold (responses, cycles, stalls, straddles, occupancy)."""
    assert np.array_equal(a.responses, b.responses), f"{what}: responses differ"
    assert a.cycles == b.cycles, f"{what}: cycles {a.cycles} != {b.cycles}"
    assert a.requests == b.requests and a.latency == b.latency, what
    assert a.stall_cycles == b.stall_cycles, f"{what}: {a.stall_cycles} != {b.stall_cycles}"
    assert a.straddles == b.straddles, f"{what}: straddles {a.straddles} != {b.straddles}"
    if a.occupancy is not None and b.occupancy is not None:
        assert a.occupancy.keys() == b.occupancy.keys(), what
        for k in a.occupancy:
            assert abs(a.occupancy[k] - b.occupancy[k]) < 1e-12, f"{what}: occupancy {k}"


def compare_with_golden(ts, req, backend, **kw):
    """``backend`` and golden agree on everything a SimResult holds, the responses equal
    golden.fetch's texels, and every cycle is a transfer, a backpressure stall, a one-port bubble or
    one of the first LATENCY; returns the backend's result."""
    r = simulate(ts, req, backend=backend, **kw)
    g = simulate(ts, req, backend="golden", **kw)
    assert np.array_equal(r.responses, fetch(ts, req[:, 0], req[:, 1], req[:, 2], req[:, 3]))
    assert_same(r, g, backend)
    assert r.occupancy.keys() == g.occupancy.keys() == set(REGISTERS)
    assert r.cycles == len(req) + LATENCY + r.stall_cycles["output_backpressure"] + r.stall_cycles["one_port_straddle"]
    return r


# Testbench helpers (Amaranth's async testbenches)

async def stream_put(ctx, stream, payload):
    """Present ``payload`` on ``stream`` (valid high) until it transfers; returns after the transfer
    cycle's clock edge with ``valid`` low again."""
    ctx.set(stream.valid, 1)
    ctx.set(stream.payload, payload)
    await ctx.tick().until(stream.ready)
    ctx.set(stream.valid, 0)


async def stream_get(ctx, stream):
    """Raise ``ready`` until ``stream`` transfers; return the payload (lowers ``ready`` after)."""
    ctx.set(stream.ready, 1)
    payload, = await ctx.tick().sample(stream.payload).until(stream.valid)
    ctx.set(stream.ready, 0)
    return payload


def run_lockstep(dut, inputs: dict, outputs: list, latency: int, *, en: str = "en",
                 en_pattern=None, hold: str | None = None, seed: int = 0) -> dict:
    """Drive a pipelined datapath block (an ``en`` input, no valid/ready) with one input vector per
    enabled cycle and collect its outputs; for stage unit tests.

    ``inputs`` maps port names of ``dut`` to lists of ints (one per item); ``outputs`` names the
    ports to read. The item fed in the e-th cycle with ``en`` high appears on the outputs after
    ``latency`` enabled cycles. ``en_pattern`` (iterable of bools, default all high) drops ``en`` in
    some cycles: the inputs then carry another (random) item's values and the outputs must hold.
    ``hold`` names a combinational output (the one-port index reader's): while it is high in an
    enabled cycle, the block keeps the item it took in the previous enabled cycle in its first
    stage, a bubble goes down the pipeline ahead of that item, and the inputs are not taken (the
    same item is presented again).

    Returns ``{name: [int per item]}``.
    """
    from amaranth.sim import Simulator
    from amaranth.hdl import Value

    def port(name):
        p = getattr(dut, name)
        return p if isinstance(p, Value) else p.as_value()

    in_ports = {name: port(name) for name in inputs}
    out_ports = {name: port(name) for name in outputs}
    n = len(next(iter(inputs.values()))) if inputs else 0
    results = {name: [None] * n for name in outputs}
    rng = np.random.default_rng(seed)
    pattern = iter(en_pattern) if en_pattern is not None else None

    async def bench(ctx):
        item = 0              # next item to feed
        fed = []              # per enabled cycle: the item fed, or None (a bubble or held item)
        last = None           # position of item n-1 in ``fed``
        enabled = 0
        while n:
            if enabled >= latency:
                pos = enabled - latency
                if fed[pos] is not None:
                    for name, p in out_ports.items():
                        results[name][fed[pos]] = ctx.get(p)
                if last is not None and pos >= last:
                    break
            on = True if pattern is None else bool(next(pattern, True))
            src = item if (on and item < n) else int(rng.integers(0, n))
            for name, p in in_ports.items():
                ctx.set(p, int(inputs[name][src]))
            ctx.set(port(en), int(on))
            if on:
                held = hold is not None and ctx.get(port(hold))
                if held:                    # a bubble goes ahead of the item in the first stage
                    fed.insert(len(fed) - 1, None)
                    if last is not None:
                        last += 1
                elif item < n:
                    fed.append(item)
                    if item == n - 1:
                        last = len(fed) - 1
                    item += 1
                else:
                    fed.append(None)
                enabled += 1
            await ctx.tick()

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    return results


def random_dt(width: int, height: int, fmt: int, n: int, seed: int) -> bytes:
    """A Dreamcast VQ ``.dt`` made byte by byte (not by golden.pvr2.pvr_set): a random codebook of ``n``
    entries of pixel format ``fmt``, random index bytes ``256-n .. 255``, not mipmapped."""
    rng = np.random.default_rng(seed)
    body = rng.integers(0, 1 << 16, (n, 4)).astype("<u2").tobytes()
    body += rng.integers(256 - n, 256, width * height // 4).astype(np.uint8).tobytes()
    control = (1 << 30) | (fmt << 27)
    size = 32 + len(body)
    return (b"DcTx" + size.to_bytes(4, "little") + bytes([0, 0, n - 1, 0]) + width.to_bytes(2, "little")
            + height.to_bytes(2, "little") + control.to_bytes(4, "little") + bytes(12) + body)


PVRTEX_DATA = os.path.join(REPO, "tests", "data", "pvrtex")


@functools.lru_cache(maxsize=None)
def pvr2_small_sets() -> dict:
    """Tiny PowerVR2 sets for pysim: rectangles both ways, an 8x8 mip chain down to 1x1 in yuv422
    (whose 1x1 level is rgb565) and argb4444, small codebooks, one 128x128 pvrtex mip chain."""
    parts = [pvr_set.from_dt(pvr.parse_dt(random_dt(*a, seed=n), decode=False))
             for n, a in enumerate([(16, 8, 3, 17), (8, 32, 0, 256), (16, 16, 2, 5)])]
    mip = bytearray(random_dt(8, 8, 3, 200, seed=9))
    extra = np.random.default_rng(9).integers(56, 256, 6).astype(np.uint8).tobytes()   # 1x1, 2x2, 4x4 maps
    mip = bytes(mip[:32]) + bytes(mip[32:32 + 1600]) + extra + bytes(mip[32 + 1600:])
    mip = mip[:4] + len(mip).to_bytes(4, "little") + mip[8:19] + bytes([mip[19] | 0x80]) + mip[20:]
    parts.append(pvr_set.from_dt(pvr.parse_dt(mip, decode=False)))
    crate = os.path.join(PVRTEX_DATA, "generated", "crate_argb4444_c_64_m.dt")
    return {"rectangles_and_mip8": TextureSet.combine(parts), "crate_argb4444_c_64_m": pvr_set.import_dt([crate])}
