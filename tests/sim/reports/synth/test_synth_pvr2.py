"""``vqtex report area`` on a Dreamcast .dt: synthesis of a PowerVR2 unit (Yosys only here; the
placed-and-routed figures of --builtin pvr2 are in docs/pvr2.md)."""

import json

from tests.support import need_synth_tools as _need_tools, random_dt, run_cli as _run


def test_report_area_of_a_dt_no_pnr(tmp_path, capsys):
    """Both units of a one-level .dt: the full unit keeps the PowerVR2 set's descriptor table in LUTs;
    the specialised one has no table at all (every field a constant)."""
    _need_tools()
    path = tmp_path / "small.dt"
    path.write_bytes(random_dt(32, 16, 3, 40, seed=2))                 # yuv422, 40 entries, rectangular
    code, out, err = _run(capsys, "report", "area", str(path), "--no-pnr", "--unit", "both", "--json")
    assert code == 0, err
    units = json.loads(out)["units"]
    for unit, rep in units.items():
        assert rep["textures"] == 1 and rep["memory_images"]["entry_bytes"] == 8, unit
        assert rep["memory_images"]["codebook_entries"] == 40, unit
        u = rep["utilisation"]
        assert u["luts"] > 0 and u["dsps"] > 0, unit     # the Dreamcast colour matrix's products
    assert units["full"]["memories"]["fetch.front.descriptor.table"]["mapped_to"] == "logic"
    assert not any("descriptor" in name for name in units["specialised"]["memories"])
    assert units["specialised"]["features"]["twiddle"] and units["specialised"]["features"]["layouts"] == [1]
