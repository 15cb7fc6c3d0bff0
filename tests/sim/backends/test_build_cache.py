"""The build cache of the compiled backends, and one-line errors for missing tools and bad input."""

import os
import threading
import time

import numpy as np
import pytest

from tests.support import image, need, random_requests
from vqtex.golden.encode import encode
from vqtex.sim.cli import main
from vqtex.sim.backends.toolchain import ToolchainError, cached_build, find_tool


@pytest.fixture(scope="module")
def small_set():
    return encode([image((32, 32), 0, 3)], codebook_size=8, index_bits=12)


def test_cache_reused_and_invalidated(tmp_path, monkeypatch, small_set):
    need("g++")
    from vqtex.sim.backends.cxxrtl import build_cxxrtl
    monkeypatch.setenv("VQTEX_CACHE", str(tmp_path / "cache"))
    first = build_cxxrtl(small_set)
    assert not first.cached and os.path.isfile(first.library)
    # compiled with clang++'s inlining threshold when the compiler is a clang that takes it (one
    # probe for both compiled backends); the installed clang++ must take it
    from vqtex.sim.backends.toolchain import CLANG_INLINE, find_cxx, model_tuning_flags
    with open(os.path.join(os.path.dirname(first.library), "build.log")) as f:
        command = f.readline()
    tuning = model_tuning_flags(find_cxx(), CLANG_INLINE)
    assert (" ".join(CLANG_INLINE) in command) == bool(tuning)
    assert bool(tuning) == ("clang" in os.path.basename(find_cxx()))
    t = time.perf_counter()
    again = build_cxxrtl(small_set)
    assert again.cached and again.library == first.library and again.seconds == 0.0
    assert time.perf_counter() - t < 2.0          # elaboration only: no Yosys, no compiler
    # A different design (one-port index reader) is a different library (keys only: no compiling)...
    other = build_cxxrtl(small_set, one_port=True, compile=False)
    assert other.library != first.library and not other.cached
    # ...and so is a texture set whose memories have other shapes...
    bigger = encode([image((64, 64), 1, 3)], codebook_size=8, index_bits=12)
    assert build_cxxrtl(bigger, compile=False).library != first.library
    # ...or other compiler flags; a same-shaped set with other texels is the same library.
    assert build_cxxrtl(small_set, cxxflags=["-std=c++17", "-O1", "-fPIC", "-shared", "-fvisibility=hidden"],
                        compile=False).library != first.library
    same_shape = encode([image((32, 32), 2, 3)], codebook_size=8, index_bits=12)
    assert build_cxxrtl(same_shape, compile=False).library == first.library
    # Removing the library invalidates the entry: the next call builds it again.
    os.unlink(first.library)
    rebuilt = build_cxxrtl(small_set)
    assert not rebuilt.cached and os.path.isfile(rebuilt.library)


def test_concurrent_builders_leave_one_complete_entry(tmp_path, monkeypatch):
    monkeypatch.setenv("VQTEX_CACHE", str(tmp_path / "cache"))
    calls, results, errors = [], [], []

    def build(folder):
        calls.append(folder)
        time.sleep(0.2)                       # both builders are inside build() at once
        with open(os.path.join(folder, "lib.so"), "w") as f:
            f.write("complete")

    def worker():
        try:
            results.append(cached_build("demo", "k1", build, "lib.so"))
        except Exception as e:               # pragma: no cover - reported below
            errors.append(e)
    threads = [threading.Thread(target=worker) for _ in range(3)]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    assert not errors
    paths = {r[0] for r in results}
    assert len(paths) == 1 and open(paths.pop()).read() == "complete"
    leftovers = [p for p in os.listdir(tmp_path / "cache" / "demo") if p != "k1"]
    assert leftovers == []                    # no temporary folders left behind
    assert cached_build("demo", "k1", build, "lib.so")[2] is True


def test_missing_compiler_is_one_line(tmp_path, monkeypatch, small_set, capsys):
    monkeypatch.setenv("CXX", str(tmp_path / "no-such-g++"))
    monkeypatch.setenv("VQTEX_CACHE", str(tmp_path / "cache"))
    with pytest.raises(ToolchainError, match="not found: install a C\\+\\+ compiler"):
        find_tool("g++")
    path = tmp_path / "set.vqt"
    small_set.save(path)
    np.save(tmp_path / "r.npy", random_requests(small_set, 5))
    out = tmp_path / "o.npy"
    code = main(["sim", str(path), str(tmp_path / "r.npy"), "-o", str(out), "--backend", "cxxrtl"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "apt-get install g++" in err
    assert not out.exists()


def test_missing_verilator_is_one_line(tmp_path, monkeypatch, small_set, capsys):
    monkeypatch.setenv("PATH", str(tmp_path))            # nothing to find
    path = tmp_path / "set.vqt"
    small_set.save(path)
    np.save(tmp_path / "r.npy", random_requests(small_set, 5))
    code = main(["sim", str(path), str(tmp_path / "r.npy"), "-o", str(tmp_path / "o.npy"),
                 "--backend", "verilator"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "not found" in err and "install" in err


def test_cli_sim_cxxrtl_matches_golden(tmp_path, small_set, capsys):
    need("g++")
    import json
    path = tmp_path / "set.vqt"
    small_set.save(path)
    np.save(tmp_path / "r.npy", random_requests(small_set, 500))
    reports = {}
    for backend in ("golden", "cxxrtl"):
        out = tmp_path / f"{backend}.npy"
        code = main(["sim", str(path), str(tmp_path / "r.npy"), "-o", str(out), "--backend", backend,
                     "--stall", "0.25", "--one-port", "--json"])
        assert code == 0
        reports[backend] = json.loads(capsys.readouterr().out)
    assert np.array_equal(np.load(tmp_path / "golden.npy"), np.load(tmp_path / "cxxrtl.npy"))
    for key in ("cycles", "stall_cycles", "straddling_index_reads", "occupancy"):
        assert reports["golden"][key] == reports["cxxrtl"][key], key


def test_cli_sim_cxxrtl_bad_requests(tmp_path, small_set, capsys):
    path = tmp_path / "set.vqt"
    small_set.save(path)
    np.save(tmp_path / "r.npy", np.array([[0, 0, 999, 0]]))
    code = main(["sim", str(path), str(tmp_path / "r.npy"), "-o", str(tmp_path / "o.npy"), "--backend", "cxxrtl"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "outside" in err
    assert not (tmp_path / "o.npy").exists()


def test_cxx_preference(tmp_path, monkeypatch):
    """The CXXRTL model is built by $CXX when set, else clang++ when installed, else g++."""
    from vqtex.sim.backends.toolchain import find_cxx
    bin_ = tmp_path / "bin"
    bin_.mkdir()
    for name in ("g++", "clang++", "my-c++"):
        (bin_ / name).write_text("#!/bin/sh\n")
        (bin_ / name).chmod(0o755)
    monkeypatch.setenv("PATH", str(bin_))
    monkeypatch.delenv("CXX", raising=False)
    assert find_cxx() == str(bin_ / "clang++")
    (bin_ / "clang++").unlink()
    assert find_cxx() == str(bin_ / "g++")
    monkeypatch.setenv("CXX", "my-c++")
    assert find_cxx() == str(bin_ / "my-c++")
    (bin_ / "g++").unlink()
    monkeypatch.delenv("CXX")
    with pytest.raises(ToolchainError, match="g\\+\\+ not found: install a C\\+\\+ compiler"):
        find_cxx()
