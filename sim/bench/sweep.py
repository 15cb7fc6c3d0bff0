"""Sweeps: a list of independent jobs, run serially or on a dask.distributed cluster.

    from vqtex.sim.bench.sweep import run_jobs
    results = run_jobs(encode_point, [(image, 256), (image, 1024)])          # LocalCluster
    results = run_jobs(encode_point, jobs, scheduler="tcp://host:8786")     # an existing cluster
    results = run_jobs(encode_point, jobs, scheduler="serial")              # this process

A *job* is a tuple of arguments for one call ``fn(*job)``; ``fn`` is a module-level function (so it
pickles by name) and the jobs are picklable. The contract:

- **Results in job order**, whatever order the workers finish in; ``run_jobs(fn, jobs, ...)`` returns
  exactly ``[fn(*job) for job in jobs]`` (the serial path is that list comprehension), so a
  deterministic ``fn`` gives identical results on any scheduler and any number of workers.
- **Where it runs**: ``scheduler=None`` starts a ``distributed.LocalCluster`` of worker *processes*
  on this machine, ``workers`` of them (default: the cores this process may use), one thread each,
  and closes it afterwards. dask's nanny sets ``OMP_NUM_THREADS``, ``OPENBLAS_NUM_THREADS`` and
  ``MKL_NUM_THREADS`` to 1 in every worker (its ``distributed.nanny.pre-spawn-environ`` default), so
  the workers, not BLAS threads, share the cores: time a job on one worker and you time it on one
  thread. ``scheduler="tcp://..."`` connects to a running cluster (its workers need vqtex installed,
  the same version); ``scheduler="serial"`` (or a single job) runs in this process with no dask.
- **Failures**: the first job (in job order) that raised re-raises its exception here, with the
  job's index in a note; the cluster is closed either way.
- **Progress**: with ``progress=True`` a ``vqtex: sweep: k/N jobs`` line on stderr as jobs finish
  (rewritten in place on a terminal, one line per tenth of the sweep otherwise).

dask.distributed is the ``sweep`` extra: the sweeps of ``vqtex bench`` and ``vqtex experiments`` are
embarrassingly parallel, and the same code runs on one laptop's cores or a cluster's.
"""

from __future__ import annotations

import os
import sys
from typing import Any, Callable, Sequence

__all__ = ["run_jobs", "SERIAL", "default_workers"]

#: ``scheduler=SERIAL`` runs every job in this process, in order.
SERIAL = "serial"
#: Seconds to wait for a scheduler given by address before giving up with an OSError.
CONNECT_TIMEOUT = 10


def default_workers() -> int:
    """The cores this process may run on (its CPU affinity), at least 1."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


class _Progress:
    """``vqtex: sweep: k/N jobs`` on stderr."""

    def __init__(self, total: int, enabled: bool):
        self.total, self.done, self.enabled = total, 0, enabled and total > 0
        self.tty = sys.stderr.isatty()
        self._last_tenth = -1

    def step(self) -> None:
        self.done += 1
        if not self.enabled:
            return
        if self.tty:
            end = "\n" if self.done == self.total else ""
            print(f"\rvqtex: sweep: {self.done}/{self.total} jobs", end=end, file=sys.stderr, flush=True)
        else:
            tenth = 10 * self.done // self.total
            if tenth != self._last_tenth:
                self._last_tenth = tenth
                print(f"vqtex: sweep: {self.done}/{self.total} jobs", file=sys.stderr, flush=True)


def _noted(exc: BaseException, index: int) -> BaseException:
    if hasattr(exc, "add_note"):
        exc.add_note(f"(sweep job {index})")
    return exc


def _run_serial(fn, jobs, progress: _Progress) -> list:
    results = []
    for k, job in enumerate(jobs):
        try:
            results.append(fn(*job))
        except Exception as e:
            raise _noted(e, k)
        progress.step()
    return results


def _run_on(client, fn, jobs, progress: _Progress) -> list:
    from distributed import as_completed
    futures = [client.submit(fn, *job, pure=False, key=f"vqtex-sweep-{k}") for k, job in enumerate(jobs)]
    index = {f.key: k for k, f in enumerate(futures)}
    failed = []
    for future in as_completed(futures):
        if future.status == "error":
            failed.append(index[future.key])
        progress.step()
    if failed:
        first = min(failed)
        try:
            futures[first].result()
        except Exception as e:
            raise _noted(e, first)
    return client.gather(futures)


def run_jobs(fn: Callable[..., Any], jobs: Sequence[tuple], *, scheduler: str | None = None,
             workers: int | None = None, progress: bool = True) -> list:
    """``[fn(*job) for job in jobs]``, computed on ``scheduler`` (see the module's contract).

    Arguments:
        fn: a module-level function (pickled by name for the workers).
        jobs: one tuple of positional arguments per call.
        scheduler: None for a LocalCluster on this machine, ``"serial"`` for this process, or the
            address of a running dask scheduler (``tcp://host:8786``).
        workers: LocalCluster worker processes (default :func:`default_workers`); ignored otherwise.
        progress: print ``vqtex: sweep: k/N jobs`` lines on stderr.
    """
    jobs = [tuple(j) for j in jobs]
    if workers is not None and workers < 1:
        raise ValueError(f"workers must be at least 1, got {workers}")
    bar = _Progress(len(jobs), progress)
    if scheduler == SERIAL or len(jobs) <= 1:
        return _run_serial(fn, jobs, bar)
    from distributed import Client, LocalCluster
    if scheduler is None:
        n = min(workers or default_workers(), len(jobs))
        with LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster, \
                Client(cluster) as client:
            return _run_on(client, fn, jobs, bar)
    with Client(scheduler, timeout=CONNECT_TIMEOUT) as client:
        return _run_on(client, fn, jobs, bar)
