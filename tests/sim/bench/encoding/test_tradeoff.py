"""``vqtex bench tradeoff`` on a tiny grid: every documented field in every row, the JSON object,
the plots, the Pareto fronts, and the options' errors (no timing assertions)."""

from __future__ import annotations

import json
import math

import pytest

from vqtex.sim.bench.encoding import tradeoff as t
from vqtex.sim.cli import main


TINY = dict(images=("marble32",), blocks=((2, 2),), sizes=(16,), colors=("rgb", "yuv411"),
            methods=t.METHODS + t.REFERENCES)


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    folder = tmp_path_factory.mktemp("plots")
    return t.run(False, plot=str(folder), grid=TINY, scheduler="serial", progress=False)


def test_every_row_reports_every_field(report):
    rows = report["rows"]
    assert {(r["method"], r["color"]) for r in rows} == {(m, c) for m in TINY["methods"] for c in TINY["colors"]}
    for r in rows:
        assert set(r) == set(t.FIELDS)
        assert r["config"] == f"2x2 k=16 {r['color']}" and r["image"] == "marble32"
        assert r["texels"] == 32 * 32 and r["index_bits"] == 4 and r["threads"] == 1
        for f in ("psnr_db", "frame_psnr_db", "frame_mse", "encode_s", "decode_s", "encode_cpu_s"):
            assert math.isfinite(r[f]) and r[f] >= 0, f
        assert 15 < r["psnr_db"] < 60 and 15 < r["frame_psnr_db"] < 70


def test_bits_per_texel_as_the_paper_counts_them(report):
    for r in report["rows"]:
        entry_bytes = 12 if r["color"] == "rgb" else 6  # 2x2: 4 RGB texels, or 4 Y + U + V
        nblocks = r["texels"] // 4
        assert r["bits_per_texel"] == (nblocks * 4 + 16 * entry_bytes * 8) / r["texels"]


def test_every_method_is_reproducible():
    """Each method is seeded: the same job twice gives the same errors."""
    for m in t.METHODS + t.REFERENCES:
        a = t.run_job(t.Job(m, "marble32", (2, 2), 16, "rgb"))
        b = t.run_job(t.Job(m, "marble32", (2, 2), 16, "rgb"))
        assert a["psnr_db"] == b["psnr_db"] and a["frame_mse"] == b["frame_mse"], m


def test_json_and_pareto(report):
    assert report["benchmark"] == "tradeoff" and report["threads"] == 1
    assert "codebook" in report["bits_per_texel"]
    fronts = report["pareto"]["marble32"]
    assert fronts["time"] and fronts["bits"]
    json.dumps(report)  # JSON-safe (no inf/nan)


def test_pareto_keeps_only_the_undominated():
    rows = [dict(x=1, psnr_db=30), dict(x=2, psnr_db=29), dict(x=3, psnr_db=31), dict(x=3, psnr_db=30)]
    assert t.pareto(rows, "x") == [rows[0], rows[2]]


def test_plots_are_png(report):
    assert [p.rsplit("/", 1)[1] for p in report["plots"]] == ["tradeoff_time.png", "tradeoff_bits.png"]
    for p in report["plots"]:
        with open(p, "rb") as f:
            assert f.read(8) == b"\x89PNG\r\n\x1a\n"


def test_frame_error_is_zero_for_the_original():
    img = t.load_image("marble32")
    from vqtex.golden.mipmap import to_rgba
    mse, psnr = t.frame_error("marble32", to_rgba(img))
    assert mse == 0 and psnr == math.inf


def test_job_list_skips_codebooks_larger_than_a_quarter_of_the_blocks():
    jobs = t.job_list(dict(images=("marble32",), blocks=((2, 2), (4, 4)), sizes=(16, 64, 256),
                           colors=("rgb",), methods=("gla",)))
    assert [(j.block, j.codebook_size) for j in jobs] == [((2, 2), 16), ((2, 2), 64), ((4, 4), 16)]


def test_cli_json_one_object(capsys):
    code = main(["bench", "tradeoff", "--json", "--images", "marble32", "--sizes", "16", "--blocks", "2x2",
                 "--scheduler", "serial", "--quick"])
    out = capsys.readouterr().out
    assert code == 0
    rep = json.loads(out)
    assert len(rep["rows"]) == 2 * 4 and all(set(r) == set(t.FIELDS) for r in rep["rows"])


@pytest.mark.parametrize("argv, msg", [
    (["--images", "nosuch"], "unknown image"),
    (["--sizes", "16,x"], "--sizes"),
    (["--sizes", "1"], "2..4096"),
    (["--blocks", "3x3"], "powers of two"),
    (["--blocks", "abc"], "--blocks"),
    (["--threads", "-1"], "--threads"),
    (["--workers", "0"], "--workers"),
])
def test_cli_bad_options_are_one_line_and_exit_2(capsys, argv, msg):
    code = main(["bench", "tradeoff", *argv])
    err = capsys.readouterr().err
    assert code == 2 and msg in err and len(err.strip().splitlines()) == 1


def test_grid_options_belong_to_tradeoff_only(capsys):
    code = main(["bench", "mip", "--sizes", "16"])
    err = capsys.readouterr().err
    assert code == 2 and "tradeoff" in err


def test_missing_extra_is_one_line_naming_it(capsys, monkeypatch):
    import builtins
    real = builtins.__import__

    def no_sklearn(name, *a, **kw):
        if name.split(".")[0] == "sklearn":
            raise ImportError(f"No module named {name!r}", name=name)
        return real(name, *a, **kw)

    monkeypatch.setattr(builtins, "__import__", no_sklearn)
    code = main(["bench", "tradeoff", "--quick", "--scheduler", "serial"])
    err = capsys.readouterr().err
    assert code == 2 and "pip install '.[bench]'" in err and len(err.strip().splitlines()) == 1


def test_codecs_rows_join_the_table_and_plots(tmp_path):
    """--codecs: the codecs bench's rows on the same image, in the same table, fronts and plots;
    JPEG 2000 and the wavelets at the GLA rows' rates."""
    grid = dict(TINY, colors=("rgb",), methods=("gla",))
    out = t.run(False, grid=grid, include_codecs=True, scheduler="serial", progress=False, plot=str(tmp_path))
    methods = {r["method"] for r in out["rows"]}
    assert {"gla", "bc1", "astc", "jpeg2000", "wavelet"} <= methods
    gla = next(r for r in out["rows"] if r["method"] == "gla")
    for r in out["rows"]:
        assert r["image"] == "marble32"
        for f in ("method", "config", "image", "bits_per_texel", "psnr_db", "encode_s", "decode_s"):
            assert f in r
        if r["method"] in ("jpeg2000", "wavelet"):
            assert r["config"].endswith("@2x2/16 rgb") and r["target_bits_per_texel"] == gla["bits_per_texel"]
    assert len(out["plots"]) == 2
    json.dumps(out)


def test_plots_on_cpu_time(report, tmp_path):
    paths = t.save_plots(report["rows"], str(tmp_path), time_field="encode_cpu_s")
    assert len(paths) == 2 and all((tmp_path / p.rsplit("/", 1)[1]).stat().st_size > 1000 for p in paths)


def test_a_job_restores_the_thread_setting():
    from vqtex.golden.codebook import workers
    before = workers.threads()
    t.run_job(t.Job("gla", "marble32", (2, 2), 16, "rgb", threads=1))
    assert workers.threads() == before
