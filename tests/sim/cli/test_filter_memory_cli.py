"""The texture filter through the memory system from the command line, beside render's
(test_render_filter_memory.py): ``vqtex export --filter-lanes N --memory external`` writes its
SystemVerilog, baked or loadable (with the loadable cached unit's register map), which Verilator lints
clean and Icarus compiles; ``vqtex sim`` and ``vqtex report cycles --filter-lanes N --memory external``
run it on a pixel trace, golden's cycle model and pysim reporting the same figures; the combinations
it does not serve are one line, exit 2."""

import json
import subprocess

import numpy as np
import pytest

from tests.support import assert_one_error, filter_set, need, need_python, run_cli

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


@pytest.fixture(scope="module")
def pixel_file(vqt):
    """30 edge-case pixels (tests.support.edge_pixels) as a seven-column .npy, and the set."""
    from vqtex.golden.format import TextureSet
    from vqtex.hw.filter.footprint import level_table
    from vqtex.sim.backends.filter import FIELDS, default_frac
    from tests.support import edge_pixels
    ts = TextureSet.load(str(vqt))
    px = edge_pixels(level_table(ts), default_frac(ts), 30, 5)
    p = vqt.parent / "px.npy"
    np.save(p, np.stack([np.asarray(px[f], np.int64) for f in FIELDS], 1))
    return p, ts, px


@pytest.mark.parametrize("unit", [[], ["--unit", "loadable"]])
def test_sim_golden_and_pysim_agree(capsys, vqt, pixel_file, tmp_path, unit):
    """vqtex sim --filter-lanes 2 --memory external on a pixel trace, under output backpressure: the
    colours are golden's filter's; golden's cycle model and pysim report the same cycles, stalls,
    bytes and fill waits (loadable: and load cycles)."""
    from vqtex.sim.backends.filter import default_frac, golden_colors
    path, ts, px = pixel_file
    reps = {}
    for backend in ("golden", "pysim"):
        out = tmp_path / f"{backend}.npy"
        code, text, err = run_cli(capsys, "sim", vqt, path, "-o", out, "--filter-lanes", "2", *SMALL,
                                  "--memory-latency", "30", "--stall", "0.3", "--backend", backend, *unit, "--json")
        assert code == 0, err
        reps[backend] = json.loads(text)
        assert (np.load(out) == golden_colors(ts, px, default_frac(ts))).all()
    g, p = reps["golden"], reps["pysim"]
    assert g["pixels"] == p["pixels"] == 30 and g["groups"] == p["groups"]
    assert g["cycles"] == p["cycles"] > g["on_chip_cycles"]
    assert g["stall_cycles"] == p["stall_cycles"] and g["stall_cycles"]["output_backpressure"] > 0
    assert g["stall_cycles"]["memory"] == g["memory"]["fill_waits"] > 0
    for key in ("bursts", "memory_bytes", "bytes_per_pixel", "configuration"):
        assert g["memory"][key] == p["memory"][key]
    assert g["unit"] == p["unit"] == ("loadable" if unit else "specialised")
    if unit:
        assert g["load_cycles"] == p["load_cycles"] > 0


def test_report_cycles_and_plot(capsys, vqt, pixel_file, tmp_path):
    """report cycles --filter-lanes: the same report as sim's, the text and the plot."""
    need_python("matplotlib")
    path, _, _ = pixel_file
    code, text, err = run_cli(capsys, "report", "cycles", vqt, path, "--filter-lanes", "2", *SMALL,
                              "--plot", tmp_path / "p.png")
    assert code == 0, err
    assert "pixels per clock" in text and "fill waits" in text and "hit rate" in text
    assert (tmp_path / "p.png").read_bytes()[:4] == b"\x89PNG"


@pytest.mark.parametrize("argv,pattern", [
    (["--filter-lanes", "2"], "needs --memory external"),
    (["--filter-lanes", "2", *SMALL, "--unit", "full"], "no --unit full"),
    (["--filter-lanes", "2", *SMALL, "--unit", "specialised"], "does not apply to --backend golden"),
    (["--filter-lanes", "2", *SMALL, "--one-port"], "no --one-port"),
    (["--filter-lanes", "2", *SMALL, "FOUR"], "columns"),
    (["--filter-lanes", "2", *SMALL, "BADTEX"], "texture id out of range"),
])
def test_sim_refused(capsys, vqt, pixel_file, tmp_path, argv, pattern):
    path, _, _ = pixel_file
    rows = np.load(path)
    np.save(tmp_path / "four.npy", rows[:, :4])
    bad = rows.copy()
    bad[0, 0] = 99
    np.save(tmp_path / "badtex.npy", bad)
    trace = {"FOUR": tmp_path / "four.npy", "BADTEX": tmp_path / "badtex.npy"}
    given = [a for a in argv if a in trace]
    argv = [a for a in argv if a not in trace]
    assert_one_error(capsys, ["sim", vqt, trace[given[0]] if given else path, "-o", tmp_path / "x.npy", *argv], pattern)
    assert not (tmp_path / "x.npy").exists()
