"""What the built-in scenes need, what pruning saves, and what encoding for the frames costs:
``python -m vqtex.sim.bench.scenes.need [--json] [--repeat N] [--scenes topspin,town]``.

For each scene, over all its frames (topspin 50, town 60), side by side in one run:

* the need analysis (``golden.need.analysis``) of the full encode: textures, levels, level groups, blocks,
  codewords touched against stored, distinct memory words, block-buffer and cache hits, and its time;
* ``golden.need.prune.prune`` of the full set: what is stored before and after, memory and file bytes,
  and that every 10th frame renders identically from the pruned set;
* the full encode (``build_texture_set``) against ``encode_needed`` (the frames' distinct requests
  from rasterising them, encode of the touched levels, need analysis and prune), each best of
  ``--repeat`` runs alternating, with the parts of ``encode_needed`` timed separately;
* ``encode_needed(train="blocks")`` (codebooks trained on the touched blocks only), one run;
* frame MSE against the uncompressed textures (every 10th frame) of the full encode and of the two
  encodes for the frames (their codebooks are trained on fewer blocks, so their frames differ).
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

__all__ = ["run", "scene_bench"]


def _best(fn, repeat):
    best, out = None, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        dt = time.perf_counter() - t0
        best = dt if best is None else min(best, dt)
    return best, out


def scene_bench(name: str, repeat: int = 2, check_step: int = 10) -> dict:
    from vqtex.golden.need.analysis import analyse, scene_level_shapes, scene_streams
    from vqtex.golden.need.prune import encode_needed, prune, prune_report, touched_levels, touched_texels
    from vqtex.golden.render.frame import render_frame
    from vqtex.golden.render.metrics import frame_mse
    from vqtex.golden.render.pyramid import VQSource
    from vqtex.golden.render.scene import build_texture_set, load_scene
    scene = load_scene(name)
    images = [img for img, _ in scene.load_textures()]
    frames = list(range(scene.frames))
    full_s = needed_s = None
    parts = {}
    for _ in range(repeat):                                   # alternate the two encodes
        t0 = time.perf_counter()
        full = build_texture_set(scene, images)
        dt = time.perf_counter() - t0
        full_s = dt if full_s is None else min(full_s, dt)
        t0 = time.perf_counter()                          # encode_needed, step by step
        texels = touched_texels(scene, frames)
        t1 = time.perf_counter()
        partial = build_texture_set(scene, images, keep_levels=touched_levels(scene, texels=texels))
        t2 = time.perf_counter()
        needed = prune(partial, analyse(partial, [texels], per_frame=False))
        t3 = time.perf_counter()
        run_parts = {"rasterise_frames": t1 - t0, "encode": t2 - t1, "analyse_and_prune": t3 - t2}
        if needed_s is None or t3 - t0 < needed_s:
            needed_s, parts = t3 - t0, run_parts
    t0 = time.perf_counter()
    need = analyse(full, scene_streams(scene, full, frames))
    analyse_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    pruned = prune(full, need)
    prune_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    blocks, _ = encode_needed(scene, frames, images=images, train="blocks")
    blocks_s = time.perf_counter() - t0
    ref = scene.reference_source(images)
    check = frames[::check_step]
    identical = all(np.array_equal(render_frame(scene, f, VQSource(pruned)), render_frame(scene, f, VQSource(full)))
                    for f in check)
    mse_full = [frame_mse(render_frame(scene, f, VQSource(full)), render_frame(scene, f, ref)) for f in check]
    mse_needed = [frame_mse(render_frame(scene, f, VQSource(needed)), render_frame(scene, f, ref)) for f in check]
    mse_blocks = [frame_mse(render_frame(scene, f, VQSource(blocks)), render_frame(scene, f, ref)) for f in check]
    summary = need.summary(per_frame=False)
    fr = need.frames
    per_frame = {k: round(float(np.mean([getattr(f, k) for f in fr])), 1)
                 for k in ("requests", "blocks", "index_words", "codebook_entries", "raw_words", "buffer_hits",
                           "cache_hits")}
    assert scene_level_shapes(scene) == [full.level_shapes(t) for t in range(full.n_textures)]
    return {
        "scene": name, "frames": len(frames),
        "need": {k: summary[k] for k in ("textures", "levels", "level_groups", "compressed_blocks", "codewords",
                                         "formats", "memory_stored", "memory_touched", "totals", "cache")},
        "need_per_frame_mean": per_frame, "need_seconds": round(analyse_s, 2),
        "prune": prune_report(full, pruned), "prune_seconds": round(prune_s, 3),
        "pruned_frames_identical": identical, "frames_checked": check,
        "encode_needed": prune_report(full, needed),
        "encode_needed_blocks": prune_report(full, blocks), "encode_needed_blocks_seconds": round(blocks_s, 2),
        "encode_seconds": {"full": round(full_s, 2), "needed": round(needed_s, 2),
                           **{k: round(v, 2) for k, v in parts.items()}},
        "mse": {"full": round(float(np.mean(mse_full)), 4), "needed": round(float(np.mean(mse_needed)), 4),
                "needed_blocks": round(float(np.mean(mse_blocks)), 4)},
    }


def _text(r: dict) -> str:
    n, p, e = r["need"], r["prune"], r["encode_needed"]
    pf = r["need_per_frame_mean"]

    def ch(rep, k):
        return f"{rep['before'][k]} -> {rep['after'][k]}"
    es = r["encode_seconds"]
    return "\n".join([
        f"{r['scene']}: {r['frames']} frames, need analysis {r['need_seconds']} s",
        f"  touched/stored: textures {n['textures']['touched']}/{n['textures']['stored']}, levels "
        f"{n['levels']['touched']}/{n['levels']['stored']}, level groups {n['level_groups']['touched']}/"
        f"{n['level_groups']['stored']}, compressed blocks {n['compressed_blocks']['touched']}/"
        f"{n['compressed_blocks']['stored']}, codewords {n['codewords']['used']}/{n['codewords']['stored']}",
        f"  memory touched/stored: index words {n['memory_touched']['index_words']}/{n['memory_stored']['index_words']}, "
        f"codebook entries {n['memory_touched']['codebook_entries']}/{n['memory_stored']['codebook_entries']}, raw words "
        f"{n['memory_touched']['raw_words']}/{n['memory_stored']['raw_words']}",
        f"  per frame (mean): {pf['requests']:.0f} requests, {pf['blocks']:.0f} blocks, {pf['index_words']:.0f} index words, "
        f"{pf['codebook_entries']:.0f} entries, {pf['raw_words']:.0f} raw words; block buffer hits "
        f"{100 * pf['buffer_hits'] / pf['requests']:.1f}%, cache hits {100 * pf['cache_hits'] / pf['requests']:.1f}%",
        f"  prune: textures {ch(p, 'textures')}, levels {ch(p, 'levels')}, blocks {ch(p, 'compressed_level_blocks')}, "
        f"codewords {ch(p, 'codewords')}, memory bytes {ch(p, 'memory_bytes')}, file bytes "
        f"{p['before']['bytes']['file']} -> {p['after']['bytes']['file']}; frames {r['frames_checked']} identical: "
        f"{r['pruned_frames_identical']}",
        f"  encode for the frames: levels {ch(e, 'levels')}, codewords {ch(e, 'codewords')}, memory bytes "
        f"{ch(e, 'memory_bytes')}; seconds full {es['full']} vs needed {es['needed']} (rasterise the frames "
        f"{es['rasterise_frames']}, encode {es['encode']}, analyse and prune {es['analyse_and_prune']})",
        f"  encode for the frames, trained on the touched blocks only: {r['encode_needed_blocks_seconds']} s (one run), "
        f"codewords {ch(r['encode_needed_blocks'], 'codewords')}, memory bytes {ch(r['encode_needed_blocks'], 'memory_bytes')}",
        f"  frame MSE vs uncompressed (frames {r['frames_checked']}): full encode {r['mse']['full']}, encoded for the "
        f"frames {r['mse']['needed']}, trained on the touched blocks {r['mse']['needed_blocks']}",
    ])


def run(json_out: bool = False, repeat: int = 2, scenes=("topspin", "town")) -> list[dict]:
    rows = [scene_bench(name, repeat) for name in scenes]
    if json_out:
        print(json.dumps({"need": rows}, sort_keys=True))
    else:
        print("\n".join(_text(r) for r in rows))
    return rows


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--repeat", type=int, default=2, help="encode timings: best of this many runs (default 2)")
    p.add_argument("--scenes", default="topspin,town", help="comma-separated built-in scenes (default topspin,town)")
    a = p.parse_args(argv)
    run(a.json, a.repeat, tuple(a.scenes.split(",")))


if __name__ == "__main__":
    main()
