"""An allocation that fails inside a command (numpy's ``_ArrayMemoryError``, a ``MemoryError``) is
one line on stderr and exit status 2, no traceback, and no output file left behind (issue 26 item 5).
The failure is simulated (monkeypatched); the memory the commands take is measured, not asserted, by
``python -m vqtex.sim.bench.robustness.decode_memory`` (docs/stability.md)."""

import os

import numpy as np
import pytest

from tests.support import assert_one_error, texture_set
from vqtex.golden import fetch as fetch_module


def _numpy_memory_error():
    """The exception numpy raises when an allocation fails (its class moved in numpy 2)."""
    try:
        from numpy._core._exceptions import _ArrayMemoryError
    except ImportError:                                   # numpy 1.x
        from numpy.core._exceptions import _ArrayMemoryError
    return _ArrayMemoryError((16777216, 48), np.dtype(np.int64))


@pytest.fixture
def set_file(tmp_path):
    path = tmp_path / "t.vqt"
    texture_set("rgb_4x4_b8_k256").save(path)
    return str(path)


@pytest.mark.parametrize("error", [_numpy_memory_error, lambda: MemoryError()], ids=["numpy", "bare"])
def test_decode_out_of_memory_is_one_line_and_exit_2(monkeypatch, capsys, tmp_path, set_file, error):
    def bands(*_a, **_k):
        raise error()
    monkeypatch.setattr(fetch_module, "decode_bands", bands)
    out = tmp_path / "out.png"
    assert_one_error(capsys, ["decode", set_file, "-o", out], "out of memory")
    assert not out.exists() and os.listdir(tmp_path) == ["t.vqt"]          # nothing written, no staging


def test_the_message_says_how_much(monkeypatch, capsys, tmp_path, set_file):
    def bands(*_a, **_k):
        raise _numpy_memory_error()
    monkeypatch.setattr(fetch_module, "decode_bands", bands)
    assert_one_error(capsys, ["decode", set_file, "-o", tmp_path / "out.png"],
                     "Unable to allocate 6.00 GiB for an array with shape (16777216, 48) and data type int64")


def test_fetch_out_of_memory_in_sim_is_one_line_and_exit_2(monkeypatch, capsys, tmp_path, set_file):
    from vqtex.golden.fetch import random_requests
    from vqtex.golden.format import TextureSet
    req = tmp_path / "req.npy"
    np.save(req, random_requests(TextureSet.load(set_file), 100))

    def failing(*_a, **_k):
        raise _numpy_memory_error()
    monkeypatch.setattr(fetch_module, "_fetch", failing)
    out = tmp_path / "resp.npy"
    assert_one_error(capsys, ["sim", set_file, req, "-o", out, "--backend", "golden"], "out of memory")
    assert not out.exists()
