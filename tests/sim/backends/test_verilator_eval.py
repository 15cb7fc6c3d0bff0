"""How the Verilator backend's driver evaluates a model each cycle (issue 26 item 1): through the
model's generated ``V<prefix>___024root___eval`` on its root instance when Verilator wrote it and
the model has one thread (``eval.h``, :func:`sim.backends.verilator.eval_header`), else through
``eval()``; and the clang++ options of the model's per-cycle C++, probed
(:func:`sim.backends.verilator.model_tuning_flags`). A Verilator or clang that renames what the fast
path uses turns these tests red instead of silently costing the speed; the responses themselves are
checked against golden by every Verilator test (test_backends.py, test_verilator_halves.py)."""

import os

import pytest

from tests.support import need, random_requests, shared_cache, texture_sets
from vqtex.sim.backends import toolchain, verilator as vl
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

#: The shape Verilator 5.006 gives the harness's scheduler (copied from a real build of the default
#: unit, region bodies elided): what :func:`region_calls` accepts.
H = "vqtex_verilator_harness"


def regions(p):
    return REGIONS.replace("@P@", p).replace("@H@", H) + EVAL_DEF.format(p=p)


REGIONS = """VL_INLINE_OPT void V@P@___024root___ico_sequent__TOP__0(V@P@___024root* vlSelf) {
    if (false && vlSelf) {}  // Prevent unused
    V@P@__Syms* const __restrict vlSymsp VL_ATTR_UNUSED = vlSelf->vlSymsp;
    VL_DEBUG_IF(VL_DBG_MSGF("+    V@P@___024root___ico_sequent__TOP__0\\n"); );
    // Body
    vlSelf->@H@__DOT__clk = ((IData)(vlSelf->tick) ^ (IData)(vlSelf->@H@__DOT__phase));
}

void V@P@___024root___eval_ico(V@P@___024root* vlSelf) {
    if (false && vlSelf) {}  // Prevent unused
    // Body
    if (vlSelf->__VicoTriggered.at(0U)) {
        V@P@___024root___ico_sequent__TOP__0(vlSelf);
    }
}

void V@P@___024root___eval_act(V@P@___024root* vlSelf) {
    if (false && vlSelf) {}  // Prevent unused
    VL_DEBUG_IF(VL_DBG_MSGF("+    V@P@___024root___eval_act\\n"); );
}

VL_INLINE_OPT void V@P@___024root___nba_sequent__TOP__0(V@P@___024root* vlSelf) {
    // Body
    vlSelf->@H@__DOT__phase = vlSelf->tick;
    vlSelf->@H@__DOT__clk = ((IData)(vlSelf->tick) 
                                                 ^ (IData)(vlSelf->@H@__DOT__phase));
}

void V@P@___024root___eval_nba(V@P@___024root* vlSelf) {
    // Body
    if (vlSelf->__VnbaTriggered.at(0U)) {
        V@P@___024root___nba_sequent__TOP__0(vlSelf);
    }
}

void V@P@___024root___eval_triggers__ico(V@P@___024root* vlSelf) {
    // Body
    vlSelf->__VicoTriggered.at(0U) = (0U == vlSelf->__VicoIterCount);
#ifdef VL_DEBUG
    if (VL_UNLIKELY(vlSymsp->_vm_contextp__->debug())) {
        V@P@___024root___dump_triggers__ico(vlSelf);
    }
#endif
}

void V@P@___024root___eval_triggers__act(V@P@___024root* vlSelf) {
    // Body
    vlSelf->__VactTriggered.at(0U) = ((IData)(vlSelf->@H@__DOT__clk) 
                                      & (~ (IData)(vlSelf->__Vtrigrprev__TOP__@H@__DOT__clk)));
    vlSelf->__Vtrigrprev__TOP__@H@__DOT__clk 
        = vlSelf->@H@__DOT__clk;
}

"""


def test_eval_header_paths_and_fallbacks(tmp_path):
    """The scheduler's shape recognised: the regions called on the root; only the generated
    ``___eval`` found: it; neither (another Verilator's layout) or a multi-threaded model:
    ``eval()``. ``eval_path``/``fast_eval`` read back which path a build took."""
    _fake_model(tmp_path, "front", regions("front"))
    _fake_model(tmp_path, "mid", EVAL_DEF.format(p="mid"))
    _fake_model(tmp_path, "back", "void Vback___024root___eval_nba(Vback___024root* vlSelf) {\n}\n")
    text = vl.eval_header(str(tmp_path), ["front", "mid", "back"])
    assert ("#define VQ_EVAL_front(model, root) do { Vfront___024root___ico_sequent__TOP__0(root); "
            "Vfront___024root___nba_sequent__TOP__0(root); } while (0)") in text
    assert "void Vfront___024root___nba_sequent__TOP__0(Vfront___024root* vlSelf);" in text
    assert "#define VQ_EVAL_mid(model, root) Vmid___024root___eval(root)" in text
    assert "void Vmid___024root___eval(Vmid___024root* vlSelf);" in text
    assert "#define VQ_EVAL_back(model, root) (model)->eval()" in text
    with open(tmp_path / "eval.h", "w") as f:
        f.write(text)
    assert vl.eval_path(str(tmp_path / "libvq.so")) == {"front": "regions", "mid": "eval", "back": "eval()"}
    assert vl.fast_eval(str(tmp_path / "libvq.so")) == {"front": True, "mid": True, "back": False}
    threaded = vl.eval_header(str(tmp_path), ["front"], threads=2)
    assert "#define VQ_EVAL_front(model, root) (model)->eval()" in threaded


@pytest.mark.parametrize("change", [
    ("at(0U) = (0U == vlSelf->__VicoIterCount);", "at(0U) = (1U == vlSelf->__VicoIterCount);"),   # input trigger
    ("VL_DEBUG_IF(VL_DBG_MSGF(\"+    V@P@___024root___eval_act\\n\"); );", "V@P@___024root___act_sequent__TOP__0(vlSelf);"),
    ("    vlSelf->__Vtrigrprev__TOP__", "    vlSelf->__VactTriggered.at(1U) = vlSelf->rst;\n    vlSelf->__Vtrigrprev__TOP__"),
    ("        V@P@___024root___nba_sequent__TOP__0(vlSelf);\n    }\n",                            # a second trigger
     "        V@P@___024root___nba_sequent__TOP__0(vlSelf);\n    }\n    if (vlSelf->__VnbaTriggered.at(1U)) {\n"
     "        V@P@___024root___nba_sequent__TOP__1(vlSelf);\n    }\n"),
    ("    vlSelf->@H@__DOT__phase = vlSelf->tick;\n    vlSelf->@H@__DOT__clk", "    vlSelf->@H@__DOT__phase"),
])
def test_region_calls_refuses_another_shape(change):
    """Any difference from the one-trigger shape (an input region that does not run on every
    ``eval()``, an active region with code, a second trigger, clocked code that leaves ``clk``
    high) and the regions path is not taken: the model falls back to its ``___eval``."""
    text = regions("top")
    assert vl.region_calls(text, "Vtop___024root") == ["Vtop___024root___ico_sequent__TOP__0",
                                                       "Vtop___024root___nba_sequent__TOP__0"]
    old, new = (c.replace("@P@", "top").replace("@H@", H) for c in change)
    assert old in text
    assert vl.region_calls(text.replace(old, new), "Vtop___024root") is None


def test_tuning_flags_probed(monkeypatch):
    """clang++ that takes the options: CLANG_TUNING (Verilator) or CLANG_INLINE (CXXRTL); g++:
    none; a clang that refuses them: none."""
    monkeypatch.setattr(toolchain, "_tuning", {})
    monkeypatch.setattr(toolchain, "tool_version", lambda path: "clang version 1" if "clang" in path else "g++ (Debian) 12")
    assert toolchain.model_tuning_flags("/no/such/g++") == []
    assert toolchain.model_tuning_flags("/no/such/clang++") == []          # (cannot run: refused)
    clang = next((p for p in ("/usr/bin/clang++",) if os.path.exists(p)), None)
    if clang:
        assert toolchain.model_tuning_flags(clang) == toolchain.CLANG_TUNING
        assert toolchain.model_tuning_flags(clang, toolchain.CLANG_INLINE) == toolchain.CLANG_INLINE
    assert vl.model_tuning_flags is toolchain.model_tuning_flags


@pytest.fixture(scope="module")
def cache():
    with shared_cache():
        yield


def test_builds_take_the_fast_path(cache):
    """With the installed Verilator, the whole export's model and both halves' are evaluated through
    their input and clocked regions (the regions path; the mixed set's one-port unit, as
    test_verilator_halves.py), and the whole export still equals golden, cycles included."""
    need("verilator")
    ts = texture_sets()["mixed"]
    for halves, prefixes in ((False, {"top"}), (True, {"front", "back"})):
        build = vl.build_verilator(ts, one_port=True, halves=halves)
        assert vl.eval_path(build.library) == {p: "regions" for p in prefixes}
    req = random_requests(ts, 500, seed=3)
    got = simulate(ts, req, backend="verilator", one_port=True)
    want = simulate(ts, req, backend="golden", one_port=True)
    assert (got.responses == want.responses).all() and got.cycles == want.cycles
