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


def test_processes_report_every_field(capsys):
    """The whole-process mode on 64x64 crops, one round: the four processes ran, the ratios are
    the paired ones, both PSNRs were read from what the processes printed."""
    out = eb.run_processes(True, cases=(1,), images=("astronaut",), repeats=1, warmup=0, size=64)
    printed = json.loads(capsys.readouterr().out)
    assert printed["benchmark"] == "encode-processes" and printed["target"] == eb.PROCESS_TARGET
    (row,) = out["rows"]
    assert (row["case"], row["threads"], row["image"], row["block"], row["k"]) == (1, "default", "astronaut", "2x2", 256)
    for name in ("help", "encode", "kmeans", "kmeans_start"):
        assert row[name]["wall_s"]["median"] > 0 and row[name]["cpu_s"]["median"] >= 0
    h, e, m, s = (row[n]["wall_s"]["median"] for n in ("help", "encode", "kmeans", "kmeans_start"))
    assert row["ratio"] == pytest.approx((m - h) / (e - h))
    assert row["fit_ratio"] == pytest.approx((m - s) / (e - h))
    assert row["net_s"] == pytest.approx({"ours": e - h, "kmeans": m - h, "kmeans_fit": m - s})
    assert math.isfinite(row["psnr_db"]["ours"]) and math.isfinite(row["psnr_db"]["kmeans"])
    assert row["psnr_loss_db"] == round(row["psnr_db"]["kmeans"] - row["psnr_db"]["ours"], 3)
    (case,) = out["cases"]
    assert case["min_ratio"] == row["ratio"] and case["min_fit_ratio"] == row["fit_ratio"]
    assert case["ratio"] == pytest.approx((m - h) / (e - h)) and isinstance(case["met"], bool)


def test_kmeans_process_is_standalone():
    """The KMeans process imports no vqtex module (it stands for a user's own script)."""
    import ast
    tree = ast.parse(open(eb.KMEANS_PROCESS).read())
    names = {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
    names |= {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)}
    assert names == {"sys", "numpy", "OpenImageIO", "sklearn.cluster"}
