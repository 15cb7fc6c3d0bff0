"""The sweep runner (vqtex.sim.bench.sweep): a dask LocalCluster gives the serial results, in job order."""

from __future__ import annotations

import hashlib
import os

import numpy as np
import pytest

from vqtex.golden.encode import encode
from vqtex.golden.fetch import decode
from vqtex.sim.bench.sweep import SERIAL, run_jobs
from vqtex.sim.cli.common import CliError, sweep_options
from tests.support import image


def encode_point(seed: int, codebook_size: int, block: tuple[int, int]) -> tuple[str, float]:
    """One sweep point: the .vqt bytes' hash and the PSNR of a small encode."""
    img = image((32, 32), seed, channels=3)
    ts = encode([img], block=block, codebook_size=codebook_size, color="rgb")
    decoded = decode(ts, 0, 0)[..., :3].astype(np.float64)
    mse = float(np.mean((decoded - img) ** 2))
    return hashlib.sha256(ts.to_bytes()).hexdigest(), 10 * np.log10(255 ** 2 / max(mse, 1e-12))


def pid(_: int) -> int:
    import os
    return os.getpid()


def fails_on_three(k: int) -> int:
    if k == 3:
        raise ValueError("job three is bad")
    return k


JOBS = [(seed, k, block) for seed in (1, 2) for k in (4, 16) for block in ((2, 2), (4, 2))]


def test_local_cluster_equals_serial(capsys):
    serial = run_jobs(encode_point, JOBS, scheduler=SERIAL, progress=False)
    assert serial == [encode_point(*job) for job in JOBS]
    assert len(set(h for h, _ in serial)) == len(JOBS)      # the points differ, so order is checked
    parallel = run_jobs(encode_point, JOBS, workers=2, progress=True)
    assert parallel == serial
    err = capsys.readouterr().err
    pids = set(run_jobs(pid, [(k,) for k in range(8)], workers=2, progress=False))
    assert os.getpid() not in pids and 1 <= len(pids) <= 2     # worker processes, not this one
    assert f"vqtex: sweep: {len(JOBS)}/{len(JOBS)} jobs" in err


def test_first_failing_job_raises_with_its_index():
    for scheduler in (SERIAL, None):
        with pytest.raises(ValueError, match="job three is bad") as info:
            run_jobs(fails_on_three, [(k,) for k in range(6)], scheduler=scheduler, workers=2, progress=False)
        assert "(sweep job 3)" in getattr(info.value, "__notes__", [])


def test_unreachable_scheduler_is_an_os_error(monkeypatch):
    from vqtex.sim.bench import sweep
    monkeypatch.setattr(sweep, "CONNECT_TIMEOUT", 1)
    with pytest.raises(OSError):
        run_jobs(fails_on_three, [(0,), (1,)], scheduler="tcp://127.0.0.1:9", progress=False)


def test_sweep_options_are_checked():
    class Args:
        scheduler, workers = None, 0
    with pytest.raises(CliError, match="--workers"):
        sweep_options(Args)
    Args.workers = 2
    assert sweep_options(Args)["workers"] == 2
    with pytest.raises(ValueError):
        run_jobs(fails_on_three, [(0,), (1,)], workers=0)
