"""Shared helpers of tests/sim/test_backends*.py and test_verilog*.py (not a test module)."""

import os
import shutil

import numpy as np
import pytest

from golden.encode import encode
from golden.fetch import block_address, lookup_descriptor, random_requests, straddles  # noqa: F401 (re-exported to the tests)
from golden.format import TextureSet

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def need(*tools):
    """Skip (or, with VQTEX_REQUIRE_TOOLS=1, fail) unless every tool is on the PATH."""
    missing = [t for t in tools if shutil.which(os.environ.get("CXX", t) if t == "g++" else t) is None]
    if missing:
        msg = f"needs {', '.join(missing)} (scripts/install-sim-tools)"
        if os.environ.get("VQTEX_REQUIRE_TOOLS") == "1":
            pytest.fail(msg + " and VQTEX_REQUIRE_TOOLS=1")
        pytest.skip(msg)


def shared_cache_dir():
    """Builds shared by test runs: $VQTEX_CACHE if set, else the repository's .vqtex-cache/."""
    return os.environ.get("VQTEX_CACHE") or os.path.join(REPO, ".vqtex-cache")


def image(seed, size, channels=3):
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:size, 0:size]
    base = [xx * (256 // size), yy * (256 // size), (xx ^ yy) * (256 // size), (xx + yy) * (128 // size)]
    img = np.stack(base[:channels], -1) + rng.integers(0, 24, (size, size, channels))
    return np.clip(img, 0, 255).astype(np.uint8)


def texture_sets():
    """Small texture sets covering the configuration matrix (kept tiny for pysim)."""
    rgb12 = encode([image(0, 64)], codebook_size=16, mipmaps=True, index_bits=12)
    yuv = encode([image(1, 32), image(2, 32)], codebook_size=8, color="yuv411", block=(2, 2), mipmaps=True,
                 index_bits=5)
    rgba = encode([image(3, 32, 4)], codebook_size=16, color="rgba", index_bits=8)
    inten = encode([image(4, 32, 1)], codebook_size=32, color="intensity", block=(2, 2), index_bits=7,
                   encoder="tsvq")
    mixed = TextureSet.combine([rgb12, yuv, rgba, inten])
    w16 = encode([image(5, 32)], codebook_size=32, block=(2, 2), mipmaps=True, index_bits=12, word_bits=16)
    return {"rgb12": rgb12, "mixed": mixed, "w16": w16}


def adversarial_requests(ts, limit=200):
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
    assert np.array_equal(a.responses, b.responses), f"{what}: responses differ"
    assert a.cycles == b.cycles, f"{what}: cycles {a.cycles} != {b.cycles}"
    assert a.requests == b.requests and a.latency == b.latency, what
    assert a.stall_cycles == b.stall_cycles, f"{what}: {a.stall_cycles} != {b.stall_cycles}"
    assert a.straddles == b.straddles, f"{what}: straddles {a.straddles} != {b.straddles}"
    if a.occupancy is not None and b.occupancy is not None:
        assert a.occupancy.keys() == b.occupancy.keys(), what
        for k in a.occupancy:
            assert abs(a.occupancy[k] - b.occupancy[k]) < 1e-12, f"{what}: occupancy {k}"
