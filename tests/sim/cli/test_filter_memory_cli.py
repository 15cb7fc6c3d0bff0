"""The texture filter through the memory system from the command line, beside render's
(test_render_filter_memory.py): ``vqtex export --filter-lanes N --memory external`` writes its
SystemVerilog, baked or loadable (with the loadable cached unit's register map), which Verilator lints
clean and Icarus compiles; the combinations it does not serve are one line, exit 2."""

import json
import subprocess

import pytest

from tests.support import assert_one_error, filter_set, need, run_cli

SMALL = ["--memory", "external", "--cache-size", "256", "--raw-cache-size", "128", "--cache-line", "16",
         "--cache-ways", "2", "--prefetch", "4"]


@pytest.fixture(scope="module")
def vqt(tmp_path_factory):
    p = tmp_path_factory.mktemp("filter_memory_cli") / "set.vqt"
    filter_set().save(str(p))
    return p


@pytest.mark.parametrize("unit", [[], ["--unit", "loadable"]])
def test_export_filter_through_memory(capsys, vqt, tmp_path, unit):
    """Baked: the AXI master and one fill strobe per lane, no bus. Loadable (the set's own geometry):
    the Wishbone port too, and the loadable cached unit's register map (the base registers) and C
    header beside it. Verilator's lint is clean (--lint) and Icarus compiles it."""
    need("verilator", "iverilog")
    from vqtex.golden.geometry import Geometry
    from vqtex.golden.register_map import RegisterMap
    from vqtex.hw.memory.filter import LATENCY
    out = tmp_path / "cf.sv"
    code, text, err = run_cli(capsys, "export", vqt, "--filter-lanes", "2", *SMALL, *unit, "-o", out, "--lint",
                              "--json")
    assert code == 0, err
    rep = json.loads(text)
    assert rep["module"] == "texture_filter" and rep["latency"] == LATENCY and rep["lint"] == "clean"
    assert rep["top"] == "texture filter, 2 lane(s)" and rep["memory"]["prefetch"] == 4
    assert "index_banks" not in rep
    ports = set(rep["ports"])
    assert {"i_payload", "o_payload", "axi_araddr", "axi_rdata", "stall_memory0", "stall_memory1",
            "overflow"} <= ports
    verilog = out.read_text()
    assert "module texture_filter" in verilog and "axi_araddr" in verilog
    res = subprocess.run(["iverilog", "-g2012", "-o", str(tmp_path / "a.out"), str(out)], capture_output=True,
                         text=True)
    assert res.returncode == 0, res.stderr
    if unit:
        from vqtex.golden.format import TextureSet
        g = Geometry.of(TextureSet.load(str(vqt)))
        assert rep["unit"] == "loadable" and "bus_adr" in ports
        assert rep["bus_addr_bits"] == RegisterMap(g, external=True).addr_bits == rep["ports"]["bus_adr"]
        assert "| INDEX_BASE |" in (tmp_path / "cf.regs.md").read_text()
        assert "VQTEX_REG_RAW_BASE" in (tmp_path / "cf.h").read_text()
    else:
        assert not any(p.startswith("bus_") for p in ports)
        assert not (tmp_path / "cf.regs.md").exists()


@pytest.mark.parametrize("extra,pattern", [
    (["--index-banks", "lane"], "a cache per lane"),
    (["--unit", "full"], "--unit applies"),
    (["--one-port"], "no --one-port"),
    (["--memory-latency", "30"], "not part of the exported unit"),
])
def test_export_refused(capsys, vqt, tmp_path, extra, pattern):
    assert_one_error(capsys, ["export", vqt, "--filter-lanes", "2", *SMALL, *extra, "-o", tmp_path / "x.sv"], pattern)
    assert not (tmp_path / "x.sv").exists()
