"""The hardware trade-off (``vqtex experiments hardware``): frame error against RTL cycles and memory
bits. On a tiny town (its five groups, 64x64 textures) with small codebooks; the paper scenes and
the real codebook sizes are the long run of docs/experiments.md."""

import json

import numpy as np
import pytest

from tests.support.scenes import TINY_TOWN, tiny_scene
from tests.support import need
from vqtex.hw.texel_fetch import LATENCY
from vqtex.sim.bench.scenes import hardware_tradeoff as ht
from vqtex.sim.cli import main

FIELDS = {"scene", "sampling", "index_bits", "codebook_size", "color", "frames", "stream", "mse", "psnr", "requests_per_frame",
          "cycles_per_frame_two_bank", "cycles_per_frame_one_port", "one_port_extra_pct", "straddles_per_frame",
          "memory_bits", "stored_bits", "overall_rate", "rtl_backend", "encode_seconds", "build_seconds",
          "simulate_seconds"}


@pytest.fixture
def town(tmp_path, monkeypatch):
    """A tiny town, and codebooks of 16 (8-bit) and 32 (12-bit) codewords for its RGB textures."""
    monkeypatch.setattr(ht, "CODEBOOK_SIZE", {8: 16, 12: 32})
    return tiny_scene(tmp_path, "tiny-town", TINY_TOWN)


def test_points_on_the_cycle_model(town):
    rows = {(r["sampling"], r["index_bits"]): r
            for r in ht.sweep(frame_step=2, backend="golden", scenes=(town,), colors=("rgb",))}
    assert len(rows) == 4
    for (sampling, bits), r in rows.items():
        assert set(r) == FIELDS and r["frames"] == 2 and r["codebook_size"] == {8: 16, 12: 32}[bits]
        assert r["cycles_per_frame_two_bank"] == r["requests_per_frame"] + LATENCY      # one texel a clock
        assert r["cycles_per_frame_one_port"] == r["cycles_per_frame_two_bank"] + r["straddles_per_frame"]
        assert r["mse"] > 0 and r["psnr"] == pytest.approx(10 * np.log10(255 ** 2 / r["mse"]), abs=0.01)
        m = r["memory_bits"]
        assert m["total"] == m["index"] + m["codebook"] + m["raw"] and 0 < r["stored_bits"] <= m["total"]
        assert (r["straddles_per_frame"] > 0) == (bits == 12)
    for sampling in ("point", "trilinear"):
        eight, twelve = rows[(sampling, 8)], rows[(sampling, 12)]
        assert twelve["memory_bits"]["index"] > eight["memory_bits"]["index"]
        assert twelve["requests_per_frame"] == eight["requests_per_frame"]
    assert rows[("trilinear", 8)]["requests_per_frame"] == 8 * rows[("point", 8)]["requests_per_frame"]  # fixed


def test_sparse_stream_same_error_fewer_cycles(town):
    fixed, sparse = (ht.point(town, "trilinear", 12, "rgb", 2, "golden", stream) for stream in ("fixed", "sparse"))
    assert (fixed["stream"], sparse["stream"]) == ("fixed", "sparse")
    assert sparse["mse"] == fixed["mse"] and sparse["memory_bits"] == fixed["memory_bits"]
    assert sparse["requests_per_frame"] < fixed["requests_per_frame"]
    assert sparse["cycles_per_frame_two_bank"] == sparse["requests_per_frame"] + LATENCY


def test_compiled_rtl_gives_the_cycle_models_point(town):
    """The same point on the CXXRTL backend: the same frame error (the frame is resolved from the
    RTL's responses), cycles and straddles as the exact cycle model."""
    need("g++")
    golden, = ht.sweep(frame_step=3, backend="golden", scenes=(town,), samplings=("point",), index_bits=(12,),
                       colors=("yuv411",))
    rtl, = ht.sweep(frame_step=3, backend="cxxrtl", scenes=(town,), samplings=("point",), index_bits=(12,),
                    colors=("yuv411",))
    timing = ("rtl_backend", "encode_seconds", "build_seconds", "simulate_seconds")
    assert {k: v for k, v in rtl.items() if k not in timing} == {k: v for k, v in golden.items() if k not in timing}
    assert rtl["rtl_backend"] == "cxxrtl" and rtl["straddles_per_frame"] > 0


def test_command_json_and_plot(town, tmp_path, capsys):
    pytest.importorskip("matplotlib")
    plot = tmp_path / "hw.png"
    assert main(["experiments", "hardware", "--scene", town, "--frame-step", "3", "--backend", "golden",
                 "--scheduler", "serial", "--plot", str(plot), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["table"] == "hardware" and out["plot"] == str(plot) and len(out["rows"]) == 8
    assert out["frame_step"] == 3 and all(r["frames"] == 1 for r in out["rows"])
    assert {(r["sampling"], r["index_bits"], r["color"]) for r in out["rows"]} == {
        (s, b, c) for s in ("point", "trilinear") for b in (8, 12) for c in ("rgb", "yuv411")}
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("argv, message", [
    (["hardware", "--frames", "0:2"], "--frame-step"),
    (["table4", "--plot", "x.png"], "--plot is for the hardware experiment"),
])
def test_command_errors(argv, message, capsys, tmp_path):
    assert main(["experiments", *argv]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1
