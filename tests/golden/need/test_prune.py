"""Pruned texture sets (golden.need.prune): the frames they were pruned for are identical, everything
else is refused, and the container round-trips them."""

import numpy as np
import pytest

from tests.support import PRUNE_SCENES, small_scene
from vqtex.golden.fetch import RequestError, check_requests, fetch
from vqtex.golden.format import FormatError, TextureSet
from vqtex.golden.need.analysis import analyse, distinct_requests, scene_streams
from vqtex.golden.need.prune import encode_needed, prune, pruned_bytes, touched_levels
from vqtex.golden.render.frame import render_frame
from vqtex.golden.render.pyramid import VQSource
from vqtex.golden.render.scene import build_texture_set


@pytest.fixture(scope="module", params=sorted(PRUNE_SCENES))
def pruned(request):
    name = request.param
    scene = small_scene(name)
    ts = build_texture_set(scene)
    frames = PRUNE_SCENES[name][2]
    need = analyse(ts, scene_streams(scene, ts, frames))
    return name, scene, ts, frames, need, TextureSet.from_bytes(prune(ts, need).to_bytes())


def test_frames_pruned_for_are_identical(pruned):
    name, scene, ts, frames, _, p = pruned
    for f in frames:
        assert np.array_equal(render_frame(scene, f, VQSource(p)), render_frame(scene, f, VQSource(ts))), (name, f)


def test_pruned_set_is_smaller_and_says_what_is_absent(pruned):
    name, scene, ts, frames, need, p = pruned
    before, after = pruned_bytes(ts), pruned_bytes(p)
    assert after["codebook"] + after["index"] + after["raw"] < before["codebook"] + before["index"] + before["raw"]
    lv = need.levels
    for t, info in enumerate(p.textures):
        assert info.absent_levels == [L for L in range(info.levels) if not lv[t, L]]
        assert p.level_shapes(t) == ts.level_shapes(t)                  # level numbers and sizes stay
    assert sorted(cb.size for cb in p.codebooks) == sorted(int(u.sum()) for u in need.codewords if u.any())
    assert all(p.textures[t].index_bits == max(1, int(np.ceil(np.log2(p.codebooks[p.textures[t].codebook].size))))
               for t in range(p.n_textures) if p.textures[t].codebook >= 0)
    if name == "town":                                                  # 12-bit maps get narrower
        assert max(t.index_bits for t in p.textures if t.codebook >= 0) < 12


def test_requests_outside_the_need_are_refused(pruned):
    name, scene, ts, frames, need, p = pruned
    other = next(scene_streams(scene, ts, [PRUNE_SCENES[name][3]]))[1]
    with pytest.raises(RequestError, match="pruned from this texture set"):
        check_requests(p, *other.T)
    # exactly the requests of untouched levels or blocks are refused, one at a time
    rng = np.random.default_rng(1)
    some = other[rng.choice(len(other), 300, replace=False)]
    keep = np.zeros(len(some), bool)
    for n, r in enumerate(some):
        t, L, i, j = (int(x) for x in r)
        if need.levels[t, L]:
            d = ts.descriptor(t, L)
            bx, by = (i >> d["log2bw"], j >> d["log2bh"]) if d["compressed"] else (i, j)
            keep[n] = (not d["compressed"]) or need.touched_blocks(t, L)[by, bx]
        try:
            check_requests(p, *r[:, None])
            accepted = True
        except RequestError:
            accepted = False
        assert accepted == keep[n], (n, r)
    assert np.array_equal(fetch(p, *some[keep].T), fetch(ts, *some[keep].T))


def test_pruning_again_for_the_same_frames_changes_nothing(pruned):
    name, scene, ts, frames, need, p = pruned
    need_p = analyse(p, scene_streams(scene, p, frames))
    again = prune(p, need_p)
    assert again == p
    s = need_p.summary(per_frame=False)                   # the pruned set: everything stored is touched
    for key in ("textures", "levels", "level_groups"):
        assert s[key]["stored"] == s[key]["touched"], key
    assert s["codewords"]["stored"] == s["codewords"]["used"]
    texels = distinct_requests(r for _, r in scene_streams(scene, ts, frames))       # what encode_needed uses
    assert prune(ts, analyse(ts, [texels], per_frame=False)) == p


@pytest.mark.parametrize("train", ["levels", "blocks"])
def test_encode_needed_stores_only_touched_levels(train):
    scene = small_scene("town")
    frames = [0]
    keep = touched_levels(scene, frames)
    p, need = encode_needed(scene, frames, train=train)
    for t, info in enumerate(p.textures):
        stored = [L for L in range(info.levels) if L not in info.absent_levels]
        assert stored == keep[t]
    assert not all(keep)                                                # town: some textures unseen
    for f, reqs in scene_streams(scene, p, frames):
        check_requests(p, *reqs.T)
        assert np.array_equal(fetch(p, *reqs.T), fetch(need.ts, *reqs.T))


def test_combining_block_pruned_sets_is_refused(pruned):
    p = pruned[-1]
    with pytest.raises(FormatError, match="combine, then prune"):
        TextureSet.combine([p, p])


def test_train_texels_trains_on_their_blocks_only():
    from vqtex.golden.encode import encode
    from vqtex.golden.fetch import decode
    rng = np.random.default_rng(5)
    img = rng.integers(0, 256, (64, 64, 3)).astype(np.uint8)
    everything = encode([img], codebook_size=4, block=(4, 4))
    one = encode([img], codebook_size=4, block=(4, 4), train_texels=[np.array([[0, 5, 6]])])   # block (1, 1)
    got = decode(one, 0, 0)[4:8, 4:8, :3].astype(int)
    assert np.abs(got - img[4:8, 4:8]).max() <= 1          # the one block trained on is (nearly) exact
    assert not np.array_equal(one.codebook, everything.codebook)
    assert decode(one, 0, 0).shape == (64, 64, 4)          # every block still has an index
