"""golden.memory.cache: the stepped classification against a plain LRU written per reference."""

import numpy as np
import pytest

from vqtex.golden.memory.cache import CacheShape, classify


def lru_reference(lines, n_sets, ways):
    """A textbook LRU, one reference at a time: a list per set, most recent last."""
    sets = [[] for _ in range(n_sets)]          # [line, way, last position]
    free = [list(range(ways)) for _ in range(n_sets)]
    hit, way, victim, fill = [], [], [], []
    brought = {}
    for pos, line in enumerate(lines):
        s = sets[line % n_sets]
        found = [e for e in s if e[0] == line]
        if found:
            e = found[0]
            s.remove(e)
            hit.append(True)
            victim.append(-1)
        else:
            if free[line % n_sets]:
                w = free[line % n_sets].pop(0)
                victim.append(-1)
            else:
                old = s.pop(0)
                w = old[1]
                victim.append(old[2])
            e = [line, w, pos]
            hit.append(False)
            brought[line] = pos
        e[2] = pos
        s.append(e)
        way.append(e[1])
        fill.append(brought[line])
    return np.array(hit), np.array(way), np.array(victim), np.array(fill)


@pytest.mark.parametrize("n_sets,ways", [(1, 1), (1, 4), (4, 1), (4, 2), (8, 4), (2, 8)])
def test_classify_equals_lru_reference(n_sets, ways):
    rng = np.random.default_rng(n_sets * 10 + ways)
    for trial in range(20):
        n = int(rng.integers(0, 400))
        span = int(rng.integers(1, 4 * n_sets * ways + 2))
        # runs of repeats (texture locality) mixed with jumps
        lines = rng.integers(0, span, n)
        rep = rng.random(n) < 0.5
        for i in range(1, n):
            if rep[i]:
                lines[i] = lines[i - 1]
        c = classify(lines, lines % n_sets, n_sets, ways)
        hit, way, victim, fill = lru_reference(lines.tolist(), n_sets, ways)
        if n:
            assert c.hit.tolist() == hit.tolist()
            assert c.way.tolist() == way.tolist()
            assert c.victim_last.tolist() == victim.tolist()
            assert c.fill.tolist() == fill.tolist()


def test_a_cache_of_one_line_per_set_is_direct_mapped():
    lines = np.array([0, 4, 0, 4, 1, 1, 5])
    c = classify(lines, lines % 4, 4, 1)
    assert c.hit.tolist() == [False, False, False, False, False, True, False]
    assert c.victim_last.tolist() == [-1, 0, 1, 2, -1, -1, 5]


@pytest.mark.parametrize("kwargs", [dict(size=1000), dict(line=48), dict(ways=3), dict(size=64, line=32, ways=4),
                                    dict(line=8192, size=1 << 16, ways=1), dict(line=2, size=64, ways=1)])
def test_bad_shapes_are_refused(kwargs):
    with pytest.raises(ValueError):
        CacheShape(**kwargs)


def test_shape_counts():
    c = CacheShape(16384, 32, 4)
    assert (c.sets, c.lines) == (128, 512)
