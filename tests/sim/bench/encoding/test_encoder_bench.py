"""``vqtex bench encode`` on a tiny input: both thread settings, every documented field (no timing
assertions)."""

from __future__ import annotations

import json
import math

import pytest

from vqtex.sim.bench.encoding import encoder as eb


def test_tiny_run_reports_every_field(capsys):
    out = eb.run(True, repeats=1, cases=(1,), images=("astronaut", "coffee"), size=64)
    printed = json.loads(capsys.readouterr().out)
    assert printed["cases"][0]["per_image"][0]["image"] == "astronaut"
    assert out["settings"] == ["default", "one"] and set(out["thread_pools"]) == {"default", "one"}
    assert any(p.startswith("vqtex=1") for p in out["thread_pools"]["one"])
    assert [r["threads"] for r in out["cases"]] == ["default", "one"]
    for r in out["cases"]:
        assert r["k"] == 256 and r["dim"] == 12 and [p["image"] for p in r["per_image"]] == ["astronaut", "coffee"]
        for p in r["per_image"]:
            assert p["vectors"] == 32 * 32
            for m in ("ours", "kmeans"):
                assert set(p[m]) == {"time_s", "cpu_s", "psnr_db", "iterations", "converged"}
                assert p[m]["time_s"] > 0 and math.isfinite(p[m]["psnr_db"])
            assert p["psnr_loss_db"] == p["kmeans"]["psnr_db"] - p["ours"]["psnr_db"]
        assert r["psnr_loss_db"] == max(p["psnr_loss_db"] for p in r["per_image"])
        assert r["speedup"] == pytest.approx(r["kmeans_time_s"] / r["ours_time_s"])
        assert {"quality_met", "speed_met", "met", "target"} <= set(r)
    assert isinstance(out["all_met"], bool)


def test_one_thread_setting_is_undone():
    """Restored to the previous setting (automatic), not frozen at the value read before."""
    from vqtex.golden.codebook import workers
    before = workers.threads()
    with eb.thread_setting("one"):
        assert workers.threads() == 1
    assert workers.threads() == before


def test_only_runs_one_method(capsys):
    eb.main(["--only", "gla", "--case", "1", "--image", "astronaut", "--size", "64"])
    assert "gla case 1 astronaut:" in capsys.readouterr().out
    eb.main(["--only", "load", "--case", "1", "--image", "astronaut", "--size", "64"])
    assert "load case 1 astronaut: 1024 vectors" in capsys.readouterr().out
