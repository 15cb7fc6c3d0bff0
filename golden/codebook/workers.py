"""The encoder's worker threads: the codeword screening, the Elkan half gaps and the exact
distances run their chunks on all the machine's cores (the TSVQ build runs on one: its numpy calls
hold the GIL too much for threads to pay).

Contract: :func:`map_ordered` ``(fn, items)`` returns ``[fn(i) for i in items]`` in order, running
the calls on :func:`threads` worker threads (the calling thread and a shared
``ThreadPoolExecutor``).  The functions given to it work on disjoint slices, so the result never
depends on the number of threads: the encoder's output is the same bytes on 1 and N threads (the
chunk boundaries depend on the problem's size only, never on the thread count).

numpy's matmul, argmax, take and most ufuncs release the GIL, so Python threads over chunks use
several cores.  The encoder's entry points (``gla``, ``nearest``, the TSVQ build; decorator
:func:`one_blas_thread`) hold the BLAS to one thread of its own for their whole run, as
scikit-learn's KMeans does around its OpenMP loop: their parallel parts run on these threads (two
workers each asking OpenBLAS for both cores would oversubscribe them), and OpenBLAS's threads
would only spin between the small GEMMs in between.  That goes through threadpoolctl (a
dependency); without it the BLAS keeps its own setting, which is only slower.

Thread count: :func:`set_threads` (``None``: automatic), else the environment variable
``VQTEX_THREADS``, else the cores this process may run on (``os.sched_getaffinity``).
"""
from __future__ import annotations

import functools
import os
import threading
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager, nullcontext

__all__ = ["MAX_THREADS", "ThreadSettingError", "threads", "set_threads", "map_ordered", "local_buffer", "blas_single",
           "one_blas_thread", "using_threads"]


class ThreadSettingError(ValueError):
    """A bad thread count (``VQTEX_THREADS`` or :func:`set_threads`); one line."""

MAX_THREADS = 1024
_lock = threading.Lock()
_set: int | None = None
_pools: dict[int, ThreadPoolExecutor] = {}
_blas = None  # threadpoolctl controller of the BLAS (False: not available)
_local = threading.local()


def _cores() -> int:
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):  # not Linux
        return max(1, os.cpu_count() or 1)


def threads() -> int:
    """Worker threads of the encoder: :func:`set_threads`, else ``VQTEX_THREADS``, else the cores
    this process may run on."""
    if _set is not None:
        return _set
    env = os.environ.get("VQTEX_THREADS", "").strip()
    if env:
        try:
            n = int(env)
        except ValueError:
            raise ThreadSettingError(f"VQTEX_THREADS must be a positive integer, got {env!r}") from None
        if not 1 <= n <= MAX_THREADS:
            raise ThreadSettingError(f"VQTEX_THREADS must be an integer 1..{MAX_THREADS}, got {env!r}")
        return n
    return _cores()


def set_threads(n: int | None) -> None:
    """Set the encoder's worker threads (``None``: back to automatic).  The output does not
    depend on it."""
    global _set
    if n is not None and (isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= MAX_THREADS):
        raise ThreadSettingError(f"threads must be an integer 1..{MAX_THREADS} or None, got {n!r}")
    _set = n


@contextmanager
def using_threads(n: int | None):
    """Context: :func:`set_threads` ``(n)`` inside, the previous setting restored after."""
    global _set
    before = _set
    set_threads(n)
    try:
        yield
    finally:
        _set = before


def _executor(n: int) -> ThreadPoolExecutor:
    """The shared pool of ``n`` threads (one pool per size, never shut down while the process
    lives: a pool another thread may be submitting to stays valid)."""
    with _lock:
        pool = _pools.get(n)
        if pool is None:
            pool = _pools[n] = ThreadPoolExecutor(max_workers=n, thread_name_prefix="vqtex-encoder")
        return pool


def blas_single():
    """Context holding the BLAS to one thread (threadpoolctl), or nothing without it.  The
    encoder's entry points (``gla``, ``nearest``) hold it for their whole run: their parallel
    parts run on this module's threads, and OpenBLAS's own threads between two small GEMMs only
    spin between calls."""
    global _blas
    if _blas is None:
        try:
            from threadpoolctl import ThreadpoolController
            _blas = ThreadpoolController()
        except ImportError:
            _blas = False
    return _blas.limit(limits=1, user_api="blas") if _blas else nullcontext()


def one_blas_thread(fn):
    """Decorator: run ``fn`` under :func:`blas_single` (the encoder's entry points)."""
    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        with blas_single():
            return fn(*args, **kwargs)
    return wrapper


def map_ordered(fn, items) -> list:
    """``[fn(i) for i in items]`` on :func:`threads` threads (the results in ``items`` order)."""
    items = list(items)
    t = threads()
    n = min(t, len(items))
    if n <= 1 or getattr(_local, "worker", False):
        return [fn(i) for i in items]
    pool = _executor(t - 1)

    def run(part):
        _local.worker = True
        try:
            return [fn(i) for i in part]
        finally:
            _local.worker = False

    # n strided parts: the calling thread takes the first, the pool the others
    parts = [items[p::n] for p in range(n)]
    with blas_single():
        futs = [pool.submit(run, part) for part in parts[1:]]
        first = run(parts[0])
        rest = [f.result() for f in futs]
    out = [None] * len(items)
    for p, res in enumerate([first] + rest):
        out[p::n] = res
    return out


def local_buffer(size: int, dtype):
    """A reusable buffer of this thread of at least ``size`` elements of ``dtype`` (fresh large
    allocations cost page faults on every call)."""
    key = ("buf", dtype)
    buf = getattr(_local, "bufs", None)
    if buf is None:
        buf = _local.bufs = {}
    b = buf.get(key)
    if b is None or b.size < size:
        import numpy as np
        b = buf[key] = np.empty(size, dtype=dtype)
    return b
