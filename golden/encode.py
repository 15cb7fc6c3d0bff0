"""The encoder: images -> a :class:`golden.format.TextureSet` (blocks, colour, mipmaps, codebooks).

``encode(images, ...)`` compresses one *texture group*: every image in the call shares one codebook
(the paper's texture groups: signs, roads, ...). Several groups with their own codebooks, formats or
block sizes are joined into one set with :meth:`TextureSet.combine`.

Vectors. A block's vector is exactly the byte order of its codeword entry (``golden.format``):
texels row-major with their channels (rgb, rgba, intensity), or for yuv411 the block's Y values, then
its share of U, then of V (U and V averaged over 2x2 texels, so a 4x4 block's vector has 24 values
instead of 48: the vector and the codebook roughly halve).

Mipmaps. A box-filtered pyramid ((a+b+c+d+2)>>2 per channel; for a non-square texture, once one side
is 1, pairs are averaged along the other with (a+b+1)>>1). Levels are taken in groups of
``sub_levels(bw, bh)`` (3 for 4x4 blocks); a group's top level is vector quantised and the levels
below it reuse its index map through *extended codewords* (the 4x4 codeword, then its 2x2 and 1x1
averages). Levels smaller than 32 texels on either side are stored raw.
``mip_training="average"`` is the paper's scheme (the codebook is trained on the top level; the
smaller sub-levels are rounded means of the rounded codeword). ``mip_training="joint"`` goes beyond
the paper: codewords are trained on all sub-levels of the original pyramid at once (each level's
squared error weighted so every level counts per texel equally), so levels 1 and 2 are no longer
limited by level 0's error.

Indices. With ``encoder="gla"`` every block's stored index names the nearest *stored* codeword
(``codebook.nearest``): the one minimising the sum of squared differences between the block's
vector (as float32, the form it is trained in; for "joint", every sub-level's part scaled by 2^s) and
the codeword's stored bytes (scaled likewise), in exact arithmetic, ties to the lowest index. For rgb,
rgba and intensity the vectors are integers and float64 computes that sum exactly; yuv411's vectors
are fractions, and a tie or near tie float64 cannot order is settled in integers. ``encoder="tsvq"``
stores the paper's tree-search indices, which need not be the nearest.
"""

from __future__ import annotations

import numpy as np

from . import codebook as vq
from .color import JFIF_BT601, ColorMatrix, rgb_to_yuv
from .mipmap import box_down, build_pyramid
from .mipmap import to_rgba as _to_rgba
from .format import (COLOR_CODES, COLORS, DESCRIPTOR_DTYPE, PVR2_COLORS, MAX_LEVELS, MAX_SIZE, RAW_BELOW,
                     WORD_BITS_ALLOWED, CodebookInfo, TextureInfo, TextureSet, default_index_bits,
                     entry_layout, is_pow2, log2, pack_indices, sub_levels)

__all__ = ["EncodeError", "encode", "reference_pyramid", "ENCODERS", "MIP_TRAINING"]

ENCODERS = ("gla", "tsvq")
MIP_TRAINING = ("average", "joint")


class EncodeError(ValueError):
    """Bad input to the encoder (unsupported size, block, codebook size, format...)."""


# ---------------------------------------------------------------------------------------------
# Pixels

def _rgba(img: np.ndarray) -> np.ndarray:
    """The image as RGBA uint8; a bad array is an EncodeError."""
    try:
        return _to_rgba(img)
    except ValueError as e:
        raise EncodeError(f"image: {e}") from None


def _for_color(rgba: np.ndarray, color: str) -> np.ndarray:
    """The image as the texture will hold it, in RGBA8888 (the response a perfect codec would give)."""
    out = rgba.copy()
    if color in ("rgb", "yuv411"):
        out[..., 3] = 255
    elif color == "intensity":
        y = np.rint(rgba[..., :3].astype(np.float64) @ np.array([0.299, 0.587, 0.114]))
        out[..., :3] = np.clip(y, 0, 255).astype(np.uint8)[..., None]
        out[..., 3] = 255
    return out


# ---------------------------------------------------------------------------------------------
# Block vectors in entry byte order

def _planes(rgba: np.ndarray, color: str) -> list[np.ndarray]:
    """Full-resolution planes the codebook quantises: list of (H, W, C) arrays (uint8 views for
    rgb, rgba and intensity, float64 Y, U, V for yuv411)."""
    if color == "rgb":
        return [rgba[..., :3]]
    if color == "rgba":
        return [rgba]
    if color == "intensity":
        return [rgba[..., :1]]
    yuv = rgb_to_yuv(rgba[..., :3])
    return [yuv[..., :1], yuv[..., 1:2], yuv[..., 2:3]]


def _blockify(a: np.ndarray, bw: int, bh: int) -> np.ndarray:
    """(H, W, C) -> (H/bh * W/bw, bh, bw, C), blocks in row-major order."""
    h, w, c = a.shape
    return a.reshape(h // bh, bh, w // bw, bw, c).transpose(0, 2, 1, 3, 4).reshape(-1, bh, bw, c)


def _mean_groups(blocks: np.ndarray, oh: int, ow: int) -> np.ndarray:
    """(N, h, w, C) -> (N, oh, ow, C) float mean over equal groups."""
    n, h, w, c = blocks.shape
    return blocks.reshape(n, oh, h // oh, ow, w // ow, c).mean(axis=(2, 4))


def block_vectors(rgba: np.ndarray, color: str, bw: int, bh: int) -> np.ndarray:
    """(nblocks, vector length) float64 vectors of one level, in codeword entry byte order."""
    planes = _planes(rgba, color)
    if color != "yuv411":
        # blocks of bytes first, then float64: one float64 copy instead of two
        return _blockify(planes[0], bw, bh).reshape(-1, bw * bh * planes[0].shape[2]).astype(np.float64)
    cw, ch = max(1, bw >> 1), max(1, bh >> 1)
    y = _blockify(planes[0], bw, bh).reshape(-1, bw * bh)
    u = _mean_groups(_blockify(planes[1], bw, bh), ch, cw).reshape(-1, cw * ch)
    v = _mean_groups(_blockify(planes[2], bw, bh), ch, cw).reshape(-1, cw * ch)
    return np.concatenate([y, u, v], axis=1)


def _split_planes(vec: np.ndarray, color: str, w: int, h: int) -> list[np.ndarray]:
    """Entry bytes of one sub-level -> list of (N, h_p, w_p, C_p) planes."""
    n = len(vec)
    if color != "yuv411":
        c = {"rgb": 3, "rgba": 4, "intensity": 1}[color]
        return [vec.reshape(n, h, w, c)]
    cw, ch = max(1, w >> 1), max(1, h >> 1)
    y = vec[:, : w * h].reshape(n, h, w, 1)
    u = vec[:, w * h: w * h + cw * ch].reshape(n, ch, cw, 1)
    v = vec[:, w * h + cw * ch:].reshape(n, ch, cw, 1)
    return [y, u, v]


def _extend(code0: np.ndarray, layout) -> np.ndarray:
    """The paper's extended codewords: sub-level s+1 = rounded 2x2 mean of sub-level s (per plane;
    a plane already 1 texel wide or high is averaged along the other axis only, or copied)."""
    parts = [code0.astype(np.int64)]
    planes = _split_planes(parts[0], layout.color, layout.bw, layout.bh)
    for s in range(1, layout.nsub):
        planes = [box_down(p.transpose(1, 2, 0, 3)).transpose(2, 0, 1, 3) for p in planes]
        parts.append(np.concatenate([p.reshape(len(p), -1) for p in planes], axis=1))
    return np.concatenate(parts, axis=1)


# ---------------------------------------------------------------------------------------------
# The encoder

def _check(images, block, codebook_size, color, index_bits, encoder, mip_training, word_bits):
    if color not in COLORS or color in PVR2_COLORS:
        paper = [c for c in COLORS if c not in PVR2_COLORS]
        raise EncodeError(f"colour format {color!r} is not one of {', '.join(paper)}"
                          + (" (PowerVR2 formats: golden.pvr2.pvr_encode, vqtex encode --layout pvr2)" if color in PVR2_COLORS else ""))
    bw, bh = block
    if not (is_pow2(bw) and is_pow2(bh) and bw <= 8 and bh <= 8):
        raise EncodeError(f"block {bw}x{bh}: width and height must be powers of two from 1 to 8")
    if not 2 <= codebook_size <= 4096:
        raise EncodeError(f"codebook size {codebook_size} is outside 2..4096")
    need = default_index_bits(codebook_size)
    if index_bits is not None and not need <= index_bits <= 16:
        raise EncodeError(f"index width {index_bits} cannot address {codebook_size} codewords "
                          f"(need {need}..16 bits)")
    if encoder not in ENCODERS:
        raise EncodeError(f"encoder {encoder!r} is not one of {', '.join(ENCODERS)}")
    if mip_training not in MIP_TRAINING:
        raise EncodeError(f"mip training {mip_training!r} is not one of {', '.join(MIP_TRAINING)}")
    if word_bits not in WORD_BITS_ALLOWED:
        raise EncodeError(f"index word width {word_bits} is not one of {WORD_BITS_ALLOWED}")
    if not images:
        raise EncodeError("no images to encode")
    for n, img in enumerate(images):
        h, w = np.asarray(img).shape[:2]
        if not (is_pow2(w) and is_pow2(h) and w <= MAX_SIZE and h <= MAX_SIZE):
            raise EncodeError(f"image {n} is {w}x{h}: sides must be powers of two from 1 to {MAX_SIZE}")


def _trained_blocks(texels, top: int, nsub: int, plan, shape, block):
    """bool (blocks of the group at ``top``,): the blocks ``texels`` ((N, 3) level, i, j) fall in at
    the group's compressed levels; None for ``texels`` None (every block)."""
    if texels is None:
        return None
    h, w = shape[:2]
    bw, bh = block
    nbx = w // bw
    mask = np.zeros(nbx * (h // bh), bool)
    tx = np.asarray(texels, np.int64).reshape(-1, 3)
    for s in range(nsub):
        if top + s >= len(plan) or not plan[top + s]:
            continue
        at = tx[tx[:, 0] == top + s]
        k = (at[:, 2] >> (log2(bh) - s)) * nbx + (at[:, 1] >> (log2(bw) - s))
        mask[k[(k >= 0) & (k < len(mask))]] = True
    return mask


def encode(images, *, block=(4, 4), codebook_size: int = 256, color: str = "rgb",
           index_bits: int | None = None, mipmaps: bool = False, encoder: str = "gla", seed: int = 0,
           mip_training: str = "average", names=None, word_bits: int = 32,
           matrix: ColorMatrix = JFIF_BT601, raw_below: int = RAW_BELOW, max_iter: int = 100,
           tol: float = 1e-3, raw: bool = False, keep_levels=None, train_texels=None) -> TextureSet:
    """Compress ``images`` (list of (H, W[, C]) uint8) into one texture group sharing a codebook.

    Arguments
    ---------
    block : (bw, bh), powers of two 1..8.  codebook_size : K, 2..4096.
    color : "rgb", "rgba", "intensity" or "yuv411".  index_bits : b, default ceil(log2 K).
    mipmaps : build the pyramid and extended codewords.  encoder : "gla" or "tsvq".
    mip_training : "average" (the paper) or "joint" (train on all sub-levels).
    raw_below : mip levels narrower or shorter than this are stored raw.
    raw : store every level uncompressed (the baseline of the paper's Table 5).
    keep_levels : per image, the level numbers to store (None: all levels of every image). The others
        are absent (``TextureInfo.absent_levels``, as in a pruned set): a level group none of whose
        levels is kept is neither trained on nor stored, so the codebook is trained on the blocks of
        the kept level groups only (``golden.need.prune.encode_needed``).
    train_texels : per image, None or an (N, 3) integer array of texels (level, i, j): the codebook
        is trained only on the blocks of compressed levels these texels fall in (every level group's
        blocks for an image given None); indices are still chosen for every block of every stored
        group. ``golden.need.prune.encode_needed(..., train="blocks")``.
    max_iter, tol : GLA's stop rule: stop when the distortion's relative decrease falls to ``tol``
        (``D_{m-1} - D_m <= tol * D_m``) or after ``max_iter`` iterations (``golden.codebook.gla``).

    Raises
    ------
    EncodeError
        On any unsupported parameter or image.
    """
    block = tuple(int(v) for v in block)
    _check(images, block, codebook_size, color, index_bits, encoder, mip_training, word_bits)
    bw, bh = block
    b = index_bits or default_index_bits(codebook_size)
    names = list(names) if names is not None else [f"texture{n}" for n in range(len(images))]
    nsub = sub_levels(bw, bh) if mipmaps else 1
    layout = entry_layout(color, bw, bh, nsub)

    # Pyramids (as the texture holds them) and the plan: which levels are compressed.
    pyrs, plans = [], []
    for img in images:
        rgba = _for_color(_rgba(img), color)
        pyr = build_pyramid(rgba) if mipmaps else [rgba]
        pyrs.append(pyr)
        plan = []
        for L, lv in enumerate(pyr):
            h, w = lv.shape[:2]
            top = pyr[L - L % nsub]
            ok = (w >= raw_below and h >= raw_below) if mipmaps else (w >= bw and h >= bh)
            ok = ok and top.shape[0] % bh == 0 and top.shape[1] % bw == 0 and not raw
            plan.append(ok)
        plans.append(plan)
    if keep_levels is None:
        stored = [[True] * len(pyr) for pyr in pyrs]
    else:
        if len(keep_levels) != len(images):
            raise EncodeError(f"keep_levels lists {len(keep_levels)} images, not {len(images)}")
        stored = [[L in set(int(x) for x in keep) for L in range(len(pyr))] for keep, pyr in zip(keep_levels, pyrs)]
    if train_texels is not None and len(train_texels) != len(images):
        raise EncodeError(f"train_texels lists {len(train_texels)} images, not {len(images)}")

    # Training vectors: the top level of every compressed level group.
    weights_by_sub = [4.0 ** s for s in range(nsub)]
    groups = []                                     # (texture, top level)
    vecs = []
    train = []                                      # per group, the blocks trained on (None: all)
    for t, (pyr, plan) in enumerate(zip(pyrs, plans)):
        for L in range(0, len(pyr), nsub):
            if not plan[L] or not any(stored[t][M] and plan[M] for M in range(L, min(L + nsub, len(pyr)))):
                continue
            groups.append((t, L))
            train.append(_trained_blocks(train_texels[t] if train_texels is not None else None,
                                         L, nsub, plan, pyr[L].shape, (bw, bh)))
            if mip_training == "joint":
                parts = []
                for s in range(nsub):
                    v = block_vectors(pyr[L + s], color, bw >> s, bh >> s)
                    parts.append(v * np.sqrt(weights_by_sub[s]))
                vecs.append(np.concatenate(parts, axis=1))
            else:
                vecs.append(block_vectors(pyr[L], color, bw, bh))

    indices_by_group = []
    cb_rows = np.zeros((codebook_size, layout.size), np.uint8)
    if groups:
        allv = np.concatenate(vecs, dtype=np.float32)  # rounds as astype does, without a float64 copy
        sizes = [len(v) for v in vecs]
        del vecs                                    # (the 4096x4096 encode's peak memory)
        some = None if all(m is None for m in train) else np.concatenate(
            [np.ones(n, bool) if m is None else m for m, n in zip(train, sizes)])
        if some is not None and not some.any():
            some = None                             # nothing touched: train on everything stored
        tv = allv if some is None else allv[some]
        joint = mip_training == "joint"
        if joint:
            ends = [layout.planes[s][0] for s in range(1, nsub)] + [layout.size]
            scale = np.concatenate([np.full(ends[s] - layout.planes[s][0], 1.0 / np.sqrt(weights_by_sub[s]))
                                    for s in range(nsub)])

        def stored_rows(code):
            """The codewords' stored bytes (level 0's, or every sub-level's for "joint")."""
            code = np.asarray(code, dtype=np.float64)
            return np.clip(np.rint(code * scale if joint else code), 0, 255).astype(np.uint8)

        def as_trained(rows):
            """Stored codewords in the training vectors' form: what the indices are nearest to."""
            return rows.astype(np.float32) / scale.astype(np.float32) if joint else rows.astype(np.float32)

        if encoder == "gla":
            # the map is optimal for what is stored: every block's nearest stored codeword
            code, idx = vq.design(tv, codebook_size, method="gla", seed=seed, max_iter=max_iter, tol=tol,
                                  stored=lambda c: as_trained(stored_rows(c)))
            rows = stored_rows(code)
            if some is not None:                    # trained on some blocks: index every block
                idx, _ = vq.nearest(allv, as_trained(rows))
        else:                                       # the paper's TSVQ with tree-search encoding
            tree = vq.tsvq_tree(tv, codebook_size, seed=seed)
            rows, idx = stored_rows(tree.codebook), tree.encode(allv)
        cb_rows = rows if joint else _extend(rows, layout).astype(np.uint8)
        del tv
        idx = np.asarray(idx, dtype=np.int64)
        splits = np.cumsum(sizes)[:-1]
        indices_by_group = np.split(idx, splits)

    # Memory images.
    descriptors = np.zeros((len(images), MAX_LEVELS), DESCRIPTOR_DTYPE)
    index_parts, raw_parts = [], []
    iw = rw = 0
    group_base = {}
    for (t, L), idx in zip(groups, indices_by_group):
        words = pack_indices(idx, b, word_bits)
        group_base[(t, L)] = iw
        index_parts.append(words)
        iw += len(words)
    textures = []
    for t, (pyr, plan) in enumerate(zip(pyrs, plans)):
        for L, lv in enumerate(pyr):
            h, w = lv.shape[:2]
            row = descriptors[t, L]
            row["log2w"], row["log2h"] = log2(w), log2(h)
            if not stored[t][L]:
                continue                                # absent: only its size is kept
            row["valid"] = 1
            if plan[L]:
                s = L % nsub
                row["compressed"] = 1
                row["base"] = group_base[(t, L - s)]
                row["log2bw"], row["log2bh"] = log2(bw) - s, log2(bh) - s
                row["index_bits"] = b
                row["cb_base"] = 0
                row["sublevel"] = s
                row["color"] = COLOR_CODES[color]
                row["texel_off"], row["u_off"], row["v_off"] = layout.planes[s]
            else:
                row["base"] = rw
                raw_parts.append(np.ascontiguousarray(lv).view("<u4").ravel())
                rw += w * h
        textures.append(TextureInfo(
            name=str(names[t]), width=pyr[0].shape[1], height=pyr[0].shape[0], levels=len(pyr),
            color=color, block=block, codebook=0 if any(p and k for p, k in zip(plan, stored[t])) else -1,
            index_bits=b, mipmapped=bool(mipmaps),
            params={"codebook_size": codebook_size, "encoder": encoder, "seed": seed,
                    "mip_training": mip_training, "raw_below": raw_below},
            absent_levels=[L for L in range(len(pyr)) if not stored[t][L]]))
    dt = np.dtype(f"<u{word_bits // 8}")
    index_parts.append(np.zeros(1, dt))
    codebooks = [CodebookInfo(color, block, nsub, codebook_size, 0)] if groups else []
    ts = TextureSet(
        word_bits=word_bits,
        index_words=np.concatenate(index_parts).astype(dt),
        codebook=cb_rows if groups else np.zeros((0, max(1, layout.size)), np.uint8),
        raw_words=(np.concatenate(raw_parts) if raw_parts else np.zeros(0)).astype("<u4"),
        descriptors=descriptors, textures=textures, codebooks=codebooks, matrix=matrix,
    )
    ts.validate()
    return ts


def reference_pyramid(img: np.ndarray, color: str, mipmaps: bool) -> list[np.ndarray]:
    """The uncompressed RGBA pyramid a texture of this colour format stands for (for error metrics)."""
    rgba = _for_color(_rgba(img), color)
    return build_pyramid(rgba) if mipmaps else [rgba]
