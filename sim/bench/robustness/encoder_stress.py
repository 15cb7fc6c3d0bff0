"""Encoder arithmetic under adversarial training sets (issue 12): every block's index checked
against the true nearest codeword in exact arithmetic.

Contract
--------
``run_cases() -> dict`` builds every case of :data:`CASES`, encodes it and returns
``{"cases", "blocks_checked", "disagreements", "nan", "threads_compared", "threads_differ",
"seconds", "per_case"}``; the figures are measured, never asserted here (the tests assert them).

The exact check (:func:`exact_nearest`) is independent of the code under test: float64 squared
distances from direct differences (no ``|x|^2 - 2 x.c + |c|^2`` form) with a rigorous relative
error bound of (d + 4) 2^-53 find, per vector, every codeword that could be nearest; a vector
with more than one such candidate is settled in Python integers after scaling every value by
the power of two that makes it integral.  Ties go to the lowest codeword index, the rule
``golden.codebook.nearest`` states and implements (the encoder's stored indices come from it).

What is checked per case: the encoder's stored index of every block of every compressed level
group (encoder "gla"; the paper's TSVQ encodes by tree search and is not full-search nearest by
design) against the exact nearest stored codeword, for the problem the encoder solves: the
block vectors as float32 (sub-level 0, or all sub-levels weighted 2^s each for
``mip_training="joint"``) against the stored codebook rows; the codebook of
``golden.codebook.gla`` on the same vectors: finite, every component within the range of the
data (centroids are weighted means: an overflow or a NaN would leave it), cell sums of
``cells.centroids`` equal to exact integer sums.  ``threads`` cases are encoded with one and with
two BLAS threads and their ``.vqt`` bytes compared (threadpoolctl when installed, else a
subprocess with OMP_NUM_THREADS / OPENBLAS_NUM_THREADS / MKL_NUM_THREADS).
"""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
import time

import numpy as np

from vqtex.golden import codebook as vq
from vqtex.golden.codebook import cells
from vqtex.golden.encode import block_vectors, encode, reference_pyramid
from vqtex.golden.format import unpack_indices

__all__ = ["CASES", "build", "exact_nearest", "check_encoding", "check_design", "encode_bytes",
           "encoded_with_threads", "run_case", "run_cases"]

_U64 = 2.0 ** -53


# --------------------------------------------------------------------------------------------
# the cases
# --------------------------------------------------------------------------------------------
def _rng(seed):
    return np.random.default_rng(seed)


def _large_norm_close(seed):
    """Half black, half near white with texels 250..255 (8x8 RGBA blocks, d = 256): vectors of
    large norm (|x'| ~ 2000 after centring) whose codewords differ by a few units."""
    img = np.zeros((128, 256, 4), np.uint8)
    img[:, 128:] = _rng(seed).integers(250, 256, (128, 128, 4))
    return [img]


def _identical_million(seed):
    """1024x1024 texels of one colour and five outliers, 1x1 blocks: 2^20 identical vectors."""
    img = np.empty((1024, 1024, 3), np.uint8)
    img[:] = (200, 100, 50)
    r = _rng(seed)
    img[r.integers(0, 1024, 5), r.integers(0, 1024, 5)] = r.integers(0, 256, (5, 3))
    return [img]


def _constant(seed):
    return [np.full((64, 64, 3), 77, np.uint8)]


def _two_colour(seed):
    img = np.zeros((64, 64, 3), np.uint8)
    img[(np.arange(64)[:, None] + np.arange(64)[None, :]) % 2 == 1] = (255, 0, 255)
    return [img]


def _noise(seed):
    return [_rng(seed).integers(0, 256, (128, 128, 3)).astype(np.uint8)]


def _extremes(seed):
    """Every component 0 or 255 (saturated noise)."""
    return [(_rng(seed).integers(0, 2, (128, 128, 3)) * 255).astype(np.uint8)]


def _row(seed):
    return [_rng(seed).integers(0, 256, (1, 1024, 3)).astype(np.uint8)]


def _column(seed):
    return [_rng(seed).integers(0, 256, (1024, 1, 3)).astype(np.uint8)]


def _few_colours(seed):
    """16 distinct colours in 2x2 blocks of one colour each: fewer distinct vectors than k."""
    pal = _rng(seed).integers(0, 256, (16, 3)).astype(np.uint8)
    lab = _rng(seed + 1).integers(0, 16, (32, 32))
    return [np.repeat(np.repeat(pal[lab], 2, axis=0), 2, axis=1)]


def _nearest_large_norm(seed):
    """Not an image: integer vectors near 2^20 in every component (|x|^2 ~ 2^44, far beyond
    float32's 24 bits), codewords a few units apart, one codeword at 0 to move the centring
    away, repeated codewords and exactly equidistant ones (ties)."""
    r = _rng(seed)
    base = float(1 << 20)
    c = base + r.integers(-3, 4, (63, 16)).astype(np.float64)
    c = np.concatenate([c, np.zeros((1, 16)), c[:8]])  # rows 64..71 repeat rows 0..7
    x = base + r.integers(-4, 5, (4000, 16)).astype(np.float64)
    mid = (c[3] + c[5]) / 2  # exactly equidistant from codewords 3 and 5 where integral
    x[:50] = np.floor(mid)
    return x, c


def _nearest_fractional_ties(seed):
    """Not an image: float32 vectors in [0, 255] (the form of yuv411's training vectors) exactly
    equidistant from codewords 0 and 1 (x0 + x5 = 1, codeword 1 = e0 + e5), the other components
    spread over 2^-10 .. 2^7.9: the two distances are sums of the same squares in another order,
    which float64 rounds differently for about 1 % of them, either way; the exact answer is
    always codeword 0."""
    r = _rng(seed)
    n, d = 4096, 6
    x = np.empty((n, d), np.float32)
    x[:, 0] = r.random(n, dtype=np.float32)
    x[:, d - 1] = 1 - x[:, 0]  # exact in float32
    x[:, 1:d - 1] = np.exp2(r.uniform(-10, 7.9, (n, d - 2)))
    c = np.zeros((4, d))
    c[1, [0, d - 1]] = 1
    c[2] = 255
    c[3] = c[1]  # a repeat of codeword 1
    return x.astype(np.float64), c


#: name -> (builder, encode options; None: a ``nearest`` case, threads: compare 1 and 2 threads)
CASES = {
    "large_norm_close": (_large_norm_close, dict(block=(8, 8), codebook_size=128, color="rgba"),
                         True),
    "identical_million": (_identical_million, dict(block=(1, 1), codebook_size=4, color="rgb"),
                          False),
    "constant": (_constant, dict(block=(4, 4), codebook_size=256, color="rgb"), False),
    "two_colour": (_two_colour, dict(block=(2, 2), codebook_size=1024, color="yuv411",
                                     mipmaps=True), False),
    "noise": (_noise, dict(block=(2, 2), codebook_size=256, color="rgb"), True),
    "noise_yuv_joint": (_noise, dict(block=(4, 4), codebook_size=128, color="yuv411",
                                     mipmaps=True, mip_training="joint"), False),
    "noise_tsvq": (_noise, dict(block=(4, 4), codebook_size=256, color="rgb", encoder="tsvq"),
                   True),
    "extremes_0_255": (_extremes, dict(block=(4, 4), codebook_size=256, color="yuv411"), False),
    "extremes_intensity": (_extremes, dict(block=(4, 4), codebook_size=64, color="intensity"),
                           False),
    "row_1xN": (_row, dict(block=(4, 1), codebook_size=64, color="rgb"), False),
    "column_Nx1": (_column, dict(block=(1, 4), codebook_size=64, color="rgb"), False),
    "more_codewords_than_vectors": (_few_colours, dict(block=(2, 2), codebook_size=1024,
                                                       color="rgb"), False),
    "nearest_large_norm": (_nearest_large_norm, None, False),
    "nearest_fractional_ties": (_nearest_fractional_ties, None, False),
}


def build(name: str, seed: int = 0):
    """The case's images (list of uint8 arrays), or (vectors, codebook) for a ``nearest`` case."""
    return CASES[name][0](seed)


# --------------------------------------------------------------------------------------------
# the exact checker
# --------------------------------------------------------------------------------------------
_TO_INT = np.frompyfunc(int, 1, 1)  # int() of an integral float64 is exact


def _as_ints(a: np.ndarray) -> np.ndarray:
    """Exact Python integers a * 2^s (object array) for the least s making every value integral."""
    a = np.asarray(a, dtype=np.float64)
    for s in range(0, 1100):
        y = np.ldexp(a, s)
        if np.all(np.floor(y) == y):
            return _TO_INT(y)  # (astype(object) would give Python floats)
    raise ValueError("values are not finite")


def exact_nearest(x: np.ndarray, c: np.ndarray, chunk_bytes: int = 1 << 25):
    """Index of the nearest row of ``c`` for every row of ``x`` (float arrays) in exact
    arithmetic, ties to the lowest index.  Returns (indices (N,) int64, rows settled in
    integers)."""
    x = np.asarray(x, dtype=np.float64)
    c = np.asarray(c, dtype=np.float64)
    n, d = x.shape
    k = c.shape[0]
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(c))):
        raise ValueError("exact_nearest needs finite values")
    out = np.empty(n, dtype=np.int64)
    step = max(1, chunk_bytes // (8 * k * d))
    slack = 1.0 + 4.0 * (d + 4) * _U64
    pr, pc = [], []  # (row, candidate) pairs of rows with several candidates
    for s in range(0, n, step):
        e = min(n, s + step)
        diff = x[s:e, None, :] - c[None, :, :]
        dd = np.einsum("ijk,ijk->ij", diff, diff)
        m = dd.min(axis=1)
        out[s:e] = dd.argmin(axis=1)
        cand = dd <= (m * slack)[:, None]  # a true minimiser always passes (error <= (d+4)u D)
        many = np.flatnonzero(np.count_nonzero(cand, axis=1) > 1)
        r, j = np.nonzero(cand[many])  # row-major: candidates of a row in increasing index
        pr.append(s + many[r])
        pc.append(j)
    r, j = np.concatenate(pr), np.concatenate(pc)
    if r.size == 0:
        return out, 0
    rows, pos = np.unique(r, return_inverse=True)
    ints = _as_ints(np.concatenate([x[rows].ravel(), c.ravel()]))
    xi = ints[: rows.size * d].reshape(rows.size, d)
    ci = ints[rows.size * d:].reshape(k, d)
    dist = ((xi[pos] - ci[j]) ** 2).sum(axis=1)  # Python integers: exact
    start = np.flatnonzero(np.r_[True, r[1:] != r[:-1]])
    best = np.minimum.reduceat(dist, start)
    hit = np.flatnonzero((dist == np.repeat(best, np.diff(np.r_[start, r.size]))).astype(bool))
    first = hit[np.r_[True, r[hit][1:] != r[hit][:-1]]]  # lowest index at the minimum
    out[r[first]] = j[first]
    return out, int(rows.size)


def _unique_rows(v: np.ndarray):
    """Distinct rows and the inverse map (rows compared bit for bit)."""
    v = np.ascontiguousarray(v, dtype=np.float64) + 0.0
    key = v.view(np.dtype((np.void, v.dtype.itemsize * v.shape[1]))).ravel()
    _, first, inv = np.unique(key, return_index=True, return_inverse=True)
    return v[first], inv.reshape(-1)


def _problems(ts, images, opts):
    """(training vectors as the encoder quantises them, codebook rows in the same units,
    stored indices) of every compressed level group, in the encoder's order."""
    color = opts.get("color", "rgb")
    bw, bh = opts.get("block", (4, 4))
    mipmaps = opts.get("mipmaps", False)
    joint = opts.get("mip_training", "average") == "joint"
    info = ts.codebooks[0]
    lay = info.layout
    nsub = lay.nsub
    cb = ts.codebook.astype(np.float64)
    if joint:
        ends = [lay.planes[s][0] for s in range(1, nsub)] + [lay.size]
        scale = np.concatenate([np.full(ends[s] - lay.planes[s][0], float(1 << s))
                                for s in range(nsub)])
        code = cb * scale
    else:
        code = cb[:, : (lay.planes[1][0] if nsub > 1 else lay.size)]
    vecs, idx = [], []
    for t, img in enumerate(images):
        pyr = reference_pyramid(img, color, mipmaps)
        for L in range(len(pyr)):
            row = ts.descriptors[t, L]
            if not row["compressed"] or row["sublevel"] != 0:
                continue
            parts = [block_vectors(pyr[L + s], color, bw >> s, bh >> s) * float(1 << s)
                     for s in range(nsub if joint else 1)]
            v = np.concatenate(parts, axis=1).astype(np.float32)  # as the encoder trains
            h, w = pyr[L].shape[:2]
            n = (h // bh) * (w // bw)
            idx.append(unpack_indices(ts.index_words, int(row["index_bits"]), n, int(row["base"]),
                                      ts.word_bits))
            vecs.append(v)
    return np.concatenate(vecs).astype(np.float64), code, np.concatenate(idx)


def check_encoding(ts, images, opts) -> dict:
    """Compare every stored index with the exact nearest stored codeword: blocks checked,
    disagreements, vectors settled in integers."""
    v, code, idx = _problems(ts, images, opts)
    u, inv = _unique_rows(v)
    ref, settled = exact_nearest(u, code)
    bad = int(np.count_nonzero(ref[inv] != idx))
    return {"blocks": int(idx.size), "disagreements": bad, "settled": settled}


def check_design(v: np.ndarray, k: int, seed: int = 0) -> dict:
    """``golden.codebook.gla`` on ``v``: non-finite values in its outputs, codewords outside the
    data's per-component range, and cells whose float64 sums differ from the exact integer
    sums (integer-valued ``v`` only)."""
    r = vq.gla(v, k, seed=seed)
    nan = int(np.count_nonzero(~np.isfinite(r.codebook)) + (not np.isfinite(r.distortion))
              + np.count_nonzero(~np.isfinite(np.asarray(r.history, dtype=np.float64))))
    lo, hi = v.min(axis=0), v.max(axis=0)
    outside = int(np.count_nonzero((r.codebook < lo) | (r.codebook > hi)))
    wrong_sums = 0
    if np.all(np.floor(v) == v):
        u, wu, _ = vq.unique_weighted(v + 0.0, np.ones(v.shape[0]))
        a = vq.nearest(u, r.codebook)[0]
        cnt, sums = cells.centroids(u, wu, a, k)
        ui, wi = u.astype(np.int64), wu.astype(np.int64)
        exact_cnt = np.zeros(k, dtype=np.int64)
        exact = np.zeros((k, u.shape[1]), dtype=np.int64)
        np.add.at(exact_cnt, a, wi)
        np.add.at(exact, a, wi[:, None] * ui)  # int64: exact (totals stay far below 2^63)
        # object arrays: Python compares a float with an int exactly
        wrong_sums = int(np.count_nonzero(sums.astype(object) != exact.astype(object))
                         + np.count_nonzero(cnt.astype(object) != exact_cnt.astype(object)))
    return {"nan": nan, "outside_range": outside, "wrong_sums": wrong_sums}


# --------------------------------------------------------------------------------------------
# threads
# --------------------------------------------------------------------------------------------
def encode_bytes(name: str, seed: int = 0) -> bytes:
    """The case's texture set as ``.vqt`` bytes."""
    return encode(build(name, seed), seed=seed, **CASES[name][1]).to_bytes()


def encoded_with_threads(name: str, threads: int, seed: int = 0) -> str:
    """sha256 of :func:`encode_bytes` with the BLAS limited to ``threads`` threads."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:
        threadpool_limits = None
    if threadpool_limits is not None:
        with threadpool_limits(limits=threads):
            return hashlib.sha256(encode_bytes(name, seed)).hexdigest()
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        env[var] = str(threads)
    code = ("import hashlib,sys;from vqtex.sim.bench.robustness.encoder_stress import encode_bytes;"
            f"print(hashlib.sha256(encode_bytes({name!r}, {seed})).hexdigest())")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         check=True, timeout=600)
    return out.stdout.strip()


# --------------------------------------------------------------------------------------------
# running
# --------------------------------------------------------------------------------------------
def run_case(name: str, seed: int = 0, threads: bool = True) -> dict:
    """One case's figures: blocks checked, disagreements, non-finite values, thread check."""
    t0 = time.perf_counter()
    builder, opts, cmp_threads = CASES[name]
    out = {"blocks": 0, "disagreements": 0, "settled": 0, "nan": 0, "outside_range": 0,
           "wrong_sums": 0, "threads_compared": 0, "threads_differ": 0}
    if opts is None:
        x, c = builder(seed)
        idx, d2 = vq.nearest(x, c)
        ref, settled = exact_nearest(x, c)
        out.update(blocks=int(x.shape[0]), disagreements=int(np.count_nonzero(idx != ref)),
                   settled=settled, nan=int(np.count_nonzero(~np.isfinite(d2))))
    else:
        images = builder(seed)
        ts = encode(images, seed=seed, **opts)
        if opts.get("encoder", "gla") == "gla":
            out.update(check_encoding(ts, images, opts))
        v, _, _ = _problems(ts, images, opts)
        out.update(check_design(v, opts["codebook_size"], seed))
        if threads and cmp_threads:
            one, two = (encoded_with_threads(name, t, seed) for t in (1, 2))
            out.update(threads_compared=1, threads_differ=int(one != two))
    out["seconds"] = round(time.perf_counter() - t0, 2)
    return out


def run_cases(names=None, seed: int = 0, threads: bool = True) -> dict:
    """Every case (or those named): totals and the per-case figures."""
    t0 = time.perf_counter()
    per = {name: run_case(name, seed, threads) for name in (names or CASES)}
    tot = {key: sum(r[key] for r in per.values())
           for key in ("blocks", "disagreements", "settled", "nan", "outside_range", "wrong_sums",
                       "threads_compared", "threads_differ")}
    return {"cases": len(per), "blocks_checked": tot.pop("blocks"), **tot,
            "seconds": round(time.perf_counter() - t0, 1), "per_case": per}


if __name__ == "__main__":
    print(json.dumps(run_cases(), sort_keys=True, indent=1))
