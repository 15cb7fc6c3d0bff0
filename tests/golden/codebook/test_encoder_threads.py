"""The encoder's worker threads (golden/codebook/workers.py): the same .vqt bytes and the same
nearest codewords on one and two threads, the results in order, and the thread setting's checks."""

import threading

import numpy as np
import pytest

from vqtex.golden import codebook as vq
from vqtex.golden.codebook import screen, workers
from vqtex.golden.encode import encode
from vqtex.golden.render.textures import generate


@pytest.fixture
def restore_threads():
    yield
    workers.set_threads(None)


def _encode(threads, **kw):
    workers.set_threads(threads)
    img = generate("marble", (256, 256), seed=3)
    return encode([img], **kw).to_bytes()


@pytest.mark.parametrize("kw", [dict(block=(2, 2), codebook_size=256),
                                dict(block=(4, 4), codebook_size=256, color="yuv411"),
                                dict(block=(4, 2), codebook_size=64, mipmaps=True)])
def test_one_and_two_threads_give_the_same_vqt_bytes(kw, restore_threads):
    assert _encode(1, **kw) == _encode(2, **kw)


def test_the_screening_really_runs_on_two_threads(restore_threads, monkeypatch):
    """With 2 threads and several chunks, two different threads score chunks (else the test above
    compares the serial path with itself)."""
    seen = set()
    real = screen.Screen._score

    def spy(self, *a):
        seen.add(threading.get_ident())
        return real(self, *a)

    monkeypatch.setattr(screen.Screen, "_score", spy)
    rng = np.random.default_rng(0)
    x = rng.integers(0, 256, (20000, 12)).astype(np.float64)
    c = rng.integers(0, 256, (256, 12)).astype(np.float64)
    workers.set_threads(2)
    two = vq.nearest(x, c)
    assert len(seen) == 2
    workers.set_threads(1)
    one = vq.nearest(x, c)
    np.testing.assert_array_equal(one[0], two[0])
    np.testing.assert_array_equal(one[1], two[1])


def test_map_ordered_keeps_the_order(restore_threads):
    for n in (1, 2, 3):
        workers.set_threads(n)
        assert workers.map_ordered(lambda i: i * i, range(17)) == [i * i for i in range(17)]
        assert workers.map_ordered(lambda i: i, []) == []


def test_map_ordered_passes_exceptions_on(restore_threads):
    workers.set_threads(2)

    def boom(i):
        if i == 3:
            raise ValueError("three")
        return i

    with pytest.raises(ValueError, match="three"):
        workers.map_ordered(boom, range(6))


def test_thread_count_from_the_environment(restore_threads, monkeypatch):
    monkeypatch.setenv("VQTEX_THREADS", "3")
    assert workers.threads() == 3
    workers.set_threads(1)
    assert workers.threads() == 1  # set_threads wins
    workers.set_threads(None)
    monkeypatch.setenv("VQTEX_THREADS", "zero")
    with pytest.raises(ValueError, match="VQTEX_THREADS"):
        workers.threads()
    monkeypatch.setenv("VQTEX_THREADS", "0")
    with pytest.raises(ValueError, match="VQTEX_THREADS"):
        workers.threads()
    monkeypatch.delenv("VQTEX_THREADS")
    assert workers.threads() >= 1
    for bad in (0, -1, True, 2.0, workers.MAX_THREADS + 1):
        with pytest.raises(ValueError):
            workers.set_threads(bad)


def test_map_ordered_from_several_threads_at_once(restore_threads):
    """Callers on several threads share the pool (a pool is never shut down under another
    caller), with lists shorter and longer than the thread count."""
    from concurrent.futures import ThreadPoolExecutor
    workers.set_threads(3)

    def caller(n):
        for _ in range(50):
            assert workers.map_ordered(lambda i: i + n, range(n)) == [i + n for i in range(n)]
        return n

    with ThreadPoolExecutor(4) as ex:
        assert list(ex.map(caller, [1, 2, 5, 9])) == [1, 2, 5, 9]
    workers.set_threads(2)  # another size: a pool of its own
    assert workers.map_ordered(lambda i: -i, range(7)) == [-i for i in range(7)]


def test_using_threads_restores_the_setting(restore_threads, monkeypatch):
    monkeypatch.setenv("VQTEX_THREADS", "3")
    with workers.using_threads(1):
        assert workers.threads() == 1
    assert workers.threads() == 3  # back to automatic (the environment), not frozen at 1
    workers.set_threads(2)
    with pytest.raises(RuntimeError):
        with workers.using_threads(1):
            raise RuntimeError
    assert workers.threads() == 2
