"""How the Verilator backend's driver evaluates a model each cycle (issue 26 item 1): through the
model's generated ``V<prefix>___024root___eval`` on its root instance when Verilator wrote it and
the model has one thread (``eval.h``, :func:`sim.backends.verilator.eval_header`), else through
``eval()``; and the clang++ options of the model's per-cycle C++, probed
(:func:`sim.backends.verilator.model_tuning_flags`). A Verilator or clang that renames what the fast
path uses turns these tests red instead of silently costing the speed; the responses themselves are
checked against golden by every Verilator test (test_backends.py, test_verilator_halves.py)."""

import os
import shutil

import pytest

from tests.support import need, random_requests, shared_cache, texture_sets
from vqtex.sim.backends import cxxrtl as cx, toolchain, verilator as vl
from vqtex.sim.backends.interface import simulate


def _fake_model(folder, prefix, body):
    """``folder/obj_{prefix}`` as Verilator writes it, with one per-cycle source holding ``body``."""
    obj = os.path.join(folder, f"obj_{prefix}")
    os.makedirs(obj)
    with open(os.path.join(obj, f"V{prefix}_classes.mk"), "w") as f:
        f.write(f"VM_CLASSES_FAST += \\\n\tV{prefix}__fast \\\n\nVM_CLASSES_SLOW += \\\n\tV{prefix}__slow \\\n")
    with open(os.path.join(obj, f"V{prefix}__fast.cpp"), "w") as f:
        f.write(body)
    open(os.path.join(obj, f"V{prefix}__slow.cpp"), "w").close()


EVAL_DEF = "void V{p}___024root___eval(V{p}___024root* vlSelf) {{\n    // Body\n}}\n"


def test_eval_header_fast_path_and_fallbacks(tmp_path):
    """The generated function found: called on the root; not found (another Verilator's layout) or
    a multi-threaded model: ``eval()``. ``fast_eval`` reads back which path a build took."""
    _fake_model(tmp_path, "front", EVAL_DEF.format(p="front"))
    _fake_model(tmp_path, "back", "void Vback___024root___eval_nba(Vback___024root* vlSelf) {\n}\n")
    text = vl.eval_header(str(tmp_path), ["front", "back"])
    assert "#define VQ_EVAL_front(model, root) Vfront___024root___eval(root)" in text
    assert "void Vfront___024root___eval(Vfront___024root* vlSelf);" in text
    assert "#define VQ_EVAL_back(model, root) (model)->eval()" in text
    with open(tmp_path / "eval.h", "w") as f:
        f.write(text)
    assert vl.fast_eval(str(tmp_path / "libvq.so")) == {"front": True, "back": False}
    threaded = vl.eval_header(str(tmp_path), ["front"], threads=2)
    assert "#define VQ_EVAL_front(model, root) (model)->eval()" in threaded


def test_tuning_flags_probed(monkeypatch):
    """clang++ that takes the options: CLANG_TUNING (Verilator's model) or CLANG_INLINE (CXXRTL's);
    g++: none; a clang that refuses them: none. One helper for both backends."""
    monkeypatch.setattr(toolchain, "_tuning", {})
    monkeypatch.setattr(toolchain, "tool_version", lambda path: "clang version 1" if "clang" in path else "g++ (Debian) 12")
    assert toolchain.model_tuning_flags("/no/such/g++") == []
    assert toolchain.model_tuning_flags("/no/such/g++", toolchain.CLANG_INLINE) == []
    assert toolchain.model_tuning_flags("/no/such/clang++") == []          # (cannot run: refused)
    assert vl.model_tuning_flags is toolchain.model_tuning_flags
    assert cx.model_tuning_flags is toolchain.model_tuning_flags


def test_tuning_flags_taken_by_the_installed_clang(monkeypatch):
    """The installed clang++ (scripts/install-sim-tools) takes both option sets and refuses an option
    it does not know (so the probe can say no)."""
    need("clang++")
    monkeypatch.setattr(toolchain, "_tuning", {})
    clang = shutil.which("clang++")
    assert toolchain.model_tuning_flags(clang) == toolchain.CLANG_TUNING
    assert toolchain.model_tuning_flags(clang, toolchain.CLANG_INLINE) == toolchain.CLANG_INLINE
    assert toolchain.model_tuning_flags(clang, ["-mllvm", "-no-such-option-vqtex"]) == []


@pytest.fixture(scope="module")
def cache():
    with shared_cache():
        yield


def test_builds_take_the_fast_path(cache):
    """With the installed Verilator, the whole export's model and both halves' are evaluated through
    their generated ``___eval`` (the mixed set's one-port unit, as test_verilator_halves.py), and
    the whole export still equals golden."""
    need("verilator")
    ts = texture_sets()["mixed"]
    for halves, prefixes in ((False, {"top"}), (True, {"front", "back"})):
        build = vl.build_verilator(ts, one_port=True, halves=halves)
        assert vl.fast_eval(build.library) == {p: True for p in prefixes}
    req = random_requests(ts, 500, seed=3)
    got = simulate(ts, req, backend="verilator", one_port=True)
    assert (got.responses == simulate(ts, req, backend="golden", one_port=True).responses).all()
