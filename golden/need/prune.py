"""Pruned texture sets: only what some frames need (``golden.need.analysis``), with texture ids, level numbers
and every answered texel unchanged.

``prune(ts, need)`` returns a new :class:`~vqtex.golden.format.TextureSet` that

* keeps every texture (ids are stable) and every level's number and size, but stores only the levels
  the frames touched: the others are listed in the texture's ``absent_levels`` and their descriptor
  rows are not valid (only their size is kept, so level shapes and a scene's requests do not change);
  a texture with no touched level stores nothing;
* keeps, per codebook, only the codewords the touched blocks use (in their old order), renumbers the
  indices of the maps it keeps and packs them at the narrowest width that names the codewords left,
  ``ceil(log2 K')`` bits (at least 1; never wider than before); a codebook no touched block uses is
  dropped and its textures' compressed levels with it;
* keeps the index map of each level group one of whose levels is touched (the map is indexed by block
  number, so it keeps every block's slot), storing in it the new index of each block touched from any
  of the group's stored levels and 0 for the others; ``present_blocks`` marks, per stored compressed
  level, the blocks that level's requests touched: a request for any other block of the level is
  refused by :func:`~vqtex.golden.fetch.check_requests` instead of being answered from a codeword it no longer has;
* keeps the raw levels that were touched, whole.

So the pruned set answers every request of the frames it was pruned for exactly as ``ts`` does, and
refuses every request those frames did not make at the level and block granularity (a request for an
untouched texel of a touched block of a touched level is still answered, correctly).
"""

from __future__ import annotations

import numpy as np

from ..format import (UNPACK_CHUNK, CodebookInfo, TextureInfo, TextureSet, default_index_bits, pack_indices,
                      unpack_indices)

__all__ = ["prune", "pruned_bytes", "stored_counts", "prune_report", "touched_texels", "touched_levels",
           "encode_needed", "TRAIN_ON"]


def _group_rows(d, t: int, top: int, levels: int, keep: np.ndarray) -> list[int]:
    """The stored compressed levels of the level group that starts at ``top`` and that ``keep``."""
    return [L for L in range(top, min(levels, top + 3))       # a group has at most 3 levels
            if keep[t, L] and d["compressed"][t, L] and L - int(d["sublevel"][t, L]) == top]


def _reindexed(ts: TextureSet, row0, n: int, touched: np.ndarray, remap: np.ndarray, b_new: int) -> np.ndarray:
    """A level group's index map (``n`` blocks from descriptor ``row0``) with each touched block's
    index renumbered by ``remap`` and the others 0, packed at ``b_new`` bits. In chunks of
    :data:`UNPACK_CHUNK` blocks (each packs to whole words), so the memory is the map and a bounded
    working set, not a few int64 copies of it."""
    wb, b = ts.word_bits, int(row0["index_bits"])
    parts = []
    for a in range(0, n, UNPACK_CHUNK):
        m = min(UNPACK_CHUNK, n - a)
        old = unpack_indices(ts.index_words, b, m, int(row0["base"]), wb, first=a)
        parts.append(pack_indices(np.where(touched[a: a + m], remap[old], 0), b_new, wb))
    return np.concatenate(parts) if parts else pack_indices(np.zeros(0, np.int64), b_new, wb)


def prune(ts: TextureSet, need) -> TextureSet:
    """``ts`` pruned to what ``need`` (a :class:`golden.need.analysis.Need` of ``ts``) touched; see the module
    docstring. The result is validated like a loaded file."""
    if need.ts is not ts:
        raise ValueError("the need analysis is of another texture set")
    d = ts.descriptors
    valid = d["valid"].astype(bool)
    comp = d["compressed"].astype(bool) & valid
    keep = need.levels & valid

    # Codebooks: the codewords touched blocks use; old index -> new index.
    cb_keep = [np.asarray(used, bool) for used in need.codewords]
    new_cb, remap, cb_new_id = [], [], []
    base = 0
    for c, cb in enumerate(ts.codebooks):
        used = cb_keep[c]
        m = np.cumsum(used) - 1
        remap.append(np.where(used, m, 0))
        k = int(used.sum())
        if k:
            cb_new_id.append(len(new_cb))
            new_cb.append(CodebookInfo(cb.color, tuple(cb.block), cb.nsub, k, base))
            base += k
        else:
            cb_new_id.append(-1)
    entry_bytes = max([cb.layout.size for cb in new_cb], default=1)
    codebook = np.zeros((base, entry_bytes), np.uint8)
    for c, cb in enumerate(ts.codebooks):
        if cb_new_id[c] >= 0:
            nc = new_cb[cb_new_id[c]]
            rows = ts.codebook[cb.base + np.flatnonzero(cb_keep[c])]
            w = min(rows.shape[1], entry_bytes)
            codebook[nc.base: nc.base + nc.size, :w] = rows[:, :w]

    descriptors = np.zeros_like(d)
    descriptors["log2w"], descriptors["log2h"] = d["log2w"], d["log2h"]
    index_parts, raw_parts, present = [], [], {}
    iw = rw = 0
    textures = []
    wb = ts.word_bits
    for t, info in enumerate(ts.textures):
        c = info.codebook
        nc = cb_new_id[c] if c >= 0 else -1
        b_new = default_index_bits(new_cb[nc].size) if nc >= 0 else info.index_bits
        kept_comp = False
        for L in range(info.levels):
            if not valid[t, L]:
                continue
            top = L - int(d["sublevel"][t, L])
            if comp[t, L] and not comp[t, top:L].any():
                # the first stored level of a group: carry its map if any stored level of it is kept
                rows = _group_rows(d, t, top, info.levels, keep & comp)
                if not rows or nc < 0:
                    continue
                row0 = d[t, L]
                n = int(need.grids[0][t, L] * need.grids[1][t, L])
                touched = np.zeros(n, bool)
                for M in rows:
                    m = need.touched_blocks(t, M).ravel()
                    present[(t, M)] = m
                    touched |= m
                words = _reindexed(ts, row0, n, touched, remap[c], b_new)
                for M in rows:
                    descriptors[t, M] = d[t, M]
                    descriptors["base"][t, M] = iw
                    descriptors["index_bits"][t, M] = b_new
                    descriptors["cb_base"][t, M] = new_cb[nc].base
                kept_comp = True
                index_parts.append(words)
                iw += len(words)
            elif not comp[t, L] and keep[t, L]:
                w, h = 1 << int(d["log2w"][t, L]), 1 << int(d["log2h"][t, L])
                descriptors[t, L] = d[t, L]
                descriptors["base"][t, L] = rw
                raw_parts.append(ts.raw_words[int(d["base"][t, L]): int(d["base"][t, L]) + w * h])
                rw += w * h
        stored = descriptors["valid"][t].astype(bool)
        new_info = TextureInfo.from_dict(info.to_dict())
        new_info.absent_levels = [L for L in range(info.levels) if not stored[L]]
        new_info.codebook = nc if kept_comp else -1
        new_info.index_bits = b_new if kept_comp else info.index_bits
        textures.append(new_info)
    dt = np.dtype(f"<u{wb // 8}")
    index_parts.append(np.zeros(1, dt))
    out = TextureSet(
        word_bits=wb, index_words=np.concatenate(index_parts).astype(dt), codebook=codebook,
        raw_words=(np.concatenate(raw_parts) if raw_parts else np.zeros(0)).astype("<u4"),
        descriptors=descriptors, textures=textures, codebooks=new_cb, matrix=ts.matrix)
    rows, offsets, nblocks = out.present_rows()
    pb = np.zeros(int((offsets + (nblocks + 7) // 8).max(initial=0)), np.uint8)
    for (t, L), m in present.items():
        bits = np.packbits(m, bitorder="little")
        pb[int(offsets[t, L]): int(offsets[t, L]) + len(bits)] = bits
    out.present_blocks = pb
    out.validate()
    out.check_consistency()
    out.check_indices()
    return out


def pruned_bytes(ts: TextureSet) -> dict:
    """The bytes of each memory image and of the ``.vqt`` file (for before/after reports)."""
    return {"index": int(ts.index_words.nbytes), "codebook": int(ts.codebook.nbytes), "raw": int(ts.raw_words.nbytes),
            "descriptors": int(ts.descriptors.nbytes),
            "present_blocks": int(ts.present_blocks.nbytes) if ts.present_blocks is not None else 0,
            "file": len(ts.to_bytes())}


def stored_counts(ts: TextureSet) -> dict:
    """What ``ts`` stores: textures with a stored level, levels, compressed levels, blocks of stored
    compressed levels (present ones in a pruned set), codewords, codebooks, index width per texture
    (None without a codebook)."""
    d = ts.descriptors
    valid = d["valid"].astype(bool)
    comp = valid & d["compressed"].astype(bool)
    rows, _, nblocks = ts.present_rows()
    blocks = int(nblocks[rows].sum()) if ts.present_blocks is None else int(np.unpackbits(ts.present_blocks).sum())
    return {"textures": int(valid.any(axis=1).sum()), "levels": int(valid.sum()),
            "compressed_levels": int(comp.sum()), "compressed_level_blocks": blocks,
            "codewords": int(sum(cb.size for cb in ts.codebooks)), "codebooks": len(ts.codebooks),
            "index_bits": [t.index_bits if t.codebook >= 0 else None for t in ts.textures]}


def prune_report(before: TextureSet, after: TextureSet, **extra) -> dict:
    """Before and after: :func:`stored_counts`, :func:`pruned_bytes` and ``memory_bytes`` (index +
    codebook + raw memories: what the hardware holds), plus ``extra``."""
    out = {}
    for key, ts in (("before", before), ("after", after)):
        b = pruned_bytes(ts)
        out[key] = {**stored_counts(ts), "bytes": b, "memory_bytes": b["index"] + b["codebook"] + b["raw"]}
    return {**out, **extra}


def touched_texels(scene, frames, mode: str = "trilinear", **options) -> np.ndarray:
    """The distinct requests (M, 4) of ``frames`` of ``scene``, found before anything is encoded (the
    requests depend only on the level shapes, :func:`golden.need.analysis.scene_level_shapes`); ``options``
    are the request stream's (``stream``, ``fovea``: :func:`golden.need.analysis.scene_streams`)."""
    from .analysis import distinct_requests, scene_level_shapes, scene_streams
    return distinct_requests(r for _, r in scene_streams(scene, scene_level_shapes(scene), frames, mode, **options))


def touched_levels(scene, frames=None, mode: str = "trilinear", texels=None) -> list[list[int]]:
    """Per scene texture, the levels ``frames`` request (or the distinct requests ``texels`` of
    :func:`touched_texels` hold)."""
    from ..constants import MAX_LEVELS
    if texels is None:
        texels = touched_texels(scene, frames, mode)
    seen = np.zeros((len(scene.textures), MAX_LEVELS), bool)
    seen.ravel()[np.unique(texels[:, 0] * MAX_LEVELS + texels[:, 1])] = True
    return [np.flatnonzero(row).tolist() for row in seen]


#: What ``encode_needed`` trains the codebooks on: every block of the touched level groups, or only
#: the blocks the frames touch.
TRAIN_ON = ("levels", "blocks")


def encode_needed(scene, frames, mode: str = "trilinear", images=None, cache=None, train: str = "levels",
                  **options):
    """Encode only what ``frames`` of ``scene`` need: the levels they touch, the codebooks trained on
    the blocks of the touched level groups (``train="levels"``) or on the touched blocks only
    (``train="blocks"``), then :func:`prune` to the codewords and blocks they touch. ``options``
    choose the request stream (:func:`touched_texels`; default the sparse stream ``vqtex render`` issues). Returns (pruned set, the :class:`golden.need.analysis.Need` of the encoded set over
    the frames' distinct requests: its counts are distinct texels per block, not requests).

    The frames are rasterised once (:func:`touched_texels`). The frames rendered from the result
    differ from those of the full encode wherever the codebooks differ (they were trained on fewer
    blocks: all of them visible in these frames); they are identical to the frames of the encoded
    set before pruning."""
    from .analysis import CacheSpec, analyse
    from ..render.scene import build_texture_set
    if train not in TRAIN_ON:
        raise ValueError(f"train must be one of {TRAIN_ON}, not {train!r}")
    texels = touched_texels(scene, frames, mode, **options)
    per_texture = None
    if train == "blocks":
        per_texture = [texels[texels[:, 0] == t][:, 1:] for t in range(len(scene.textures))]
    ts = build_texture_set(scene, images, keep_levels=touched_levels(scene, texels=texels), train_texels=per_texture)
    need = analyse(ts, [texels], cache=cache or CacheSpec(), per_frame=False)
    return prune(ts, need), need
