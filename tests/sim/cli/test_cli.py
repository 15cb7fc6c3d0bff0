"""The vqtex command line: encode, info, decode, sim; one-line errors with exit status 2."""

import json
import subprocess
import sys

import numpy as np
import pytest

from vqtex.golden.fetch import decode
from vqtex.golden.format import TextureSet
from vqtex.golden.render.imageio import read_image, write_image
from vqtex.sim.cli import main
from tests.support import run_cli as _run


@pytest.fixture
def images(tmp_path):
    rng = np.random.default_rng(0)
    paths = []
    for n in range(2):
        yy, xx = np.mgrid[0:64, 0:64]
        img = np.stack([xx * 4, yy * 4, (xx ^ yy) * 4], -1) + rng.integers(0, 8, (64, 64, 3))
        p = tmp_path / f"tex{n}.png"
        write_image(p, np.clip(img, 0, 255).astype(np.uint8))
        paths.append(str(p))
    return paths


def test_encode_info_decode(tmp_path, images, capsys):
    out = str(tmp_path / "set.vqt")
    code, stdout, _ = _run(capsys, "encode", *images, "-o", out, "--block", "2x2", "-k", "32",
                           "--mipmaps", "--color", "yuv411", "--index-bits", "12", "--json")
    assert code == 0
    rep = json.loads(stdout)
    assert [t["name"] for t in rep["textures"]] == ["tex0", "tex1"]
    assert rep["textures"][0]["index_bits"] == 12 and rep["textures"][0]["codebook"] == 0
    code, stdout, _ = _run(capsys, "info", out, "--json")
    info = json.loads(stdout)
    assert info["textures"][1]["levels"] == 7 and info["overall_rate"] > 1
    assert info["textures"][0]["compressed_levels"] == [0, 1]          # 64, 32; then raw below 32
    code, stdout, _ = _run(capsys, "info", out)
    assert code == 0 and "overall compression rate" in stdout
    png = str(tmp_path / "l1.png")
    code, _, _ = _run(capsys, "decode", out, "-o", png, "--texture", "1", "--level", "1")
    assert code == 0
    ts = TextureSet.load(out)
    assert np.array_equal(read_image(png), decode(ts, 1, 1)[..., :3])


def test_sim_golden_npy_and_csv(tmp_path, images, capsys):
    out = str(tmp_path / "set.vqt")
    assert _run(capsys, "encode", images[0], "-o", out, "-k", "16", "--mipmaps")[0] == 0
    req = np.array([[0, 0, 5, 7], [0, 1, 31, 31], [0, 6, 0, 0], [0, 2, 3, 15]])
    np.save(tmp_path / "r.npy", req)
    (tmp_path / "r.csv").write_text("texture,level,i,j\n" + "\n".join(",".join(map(str, r)) for r in req))
    ts = TextureSet.load(out)
    from vqtex.golden.fetch import fetch
    want = fetch(ts, *req.T)
    for src in ("r.npy", "r.csv"):
        resp = str(tmp_path / f"{src}.out.npy")
        code, stdout, err = _run(capsys, "sim", out, str(tmp_path / src), "-o", resp, "--json")
        assert code == 0, err
        assert np.array_equal(np.load(resp), want)
        rep = json.loads(stdout)
        assert rep["requests"] == 4


def _bad_cases(tmp_path, images):
    good = str(tmp_path / "good.vqt")
    main(["encode", images[0], "-o", good, "-k", "8"])
    trunc = tmp_path / "trunc.vqt"
    trunc.write_bytes(open(good, "rb").read()[:100])
    odd = tmp_path / "odd.png"
    write_image(odd, np.zeros((48, 64, 3), np.uint8))
    req = tmp_path / "oob.npy"
    np.save(req, np.array([[0, 0, 64, 0]]))
    badreq = tmp_path / "bad.npy"
    np.save(badreq, np.zeros((3, 3), np.int64))
    txt = tmp_path / "notimage.png"
    txt.write_text("hello")
    return [
        (["info", str(tmp_path / "missing.vqt")], "cannot read"),
        (["info", str(trunc)], "too short|checksum"),
        (["decode", good, "-o", str(tmp_path / "x.png"), "--texture", "3"], "does not exist"),
        (["decode", good, "-o", str(tmp_path / "x.png"), "--level", "9"], "no level"),
        (["encode", str(odd), "-o", str(tmp_path / "x.vqt")], "powers of two"),
        (["encode", str(txt), "-o", str(tmp_path / "x.vqt")], "notimage.png"),
        (["encode", images[0], "-o", str(tmp_path / "x.vqt"), "--block", "3x3"], "powers of two"),
        (["encode", images[0], "-o", str(tmp_path / "x.vqt"), "--block", "four"], "WxH"),
        (["encode", images[0], "-o", str(tmp_path / "x.vqt"), "-k", "9999"], "1..4096"),
        (["sim", good, str(req), "-o", str(tmp_path / "x.npy")], "outside"),
        (["sim", good, str(badreq), "-o", str(tmp_path / "x.npy")], "shape"),
        (["sim", good, str(tmp_path / "none.npy"), "-o", str(tmp_path / "x.npy")], "no such file"),
        (["nosuchcommand"], "invalid choice"),
    ]


def test_bad_input_one_line_exit_2_no_output(tmp_path, images, capsys):
    for argv, msg in _bad_cases(tmp_path, images):
        capsys.readouterr()
        code, out, err = _run(capsys, *argv)
        assert code == 2, argv
        assert err.count("\n") == 1 and err.startswith("vqtex: error:"), (argv, err)
        import re
        assert re.search(msg, err), (argv, err)
        assert not (tmp_path / "x.png").exists() and not (tmp_path / "x.vqt").exists() \
            and not (tmp_path / "x.npy").exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".vqt")]


def test_console_script_no_traceback(tmp_path):
    """The installed entry point (as a subprocess) prints one line and exits 2."""
    p = subprocess.run([sys.executable, "-m", "vqtex.sim.cli", "info", str(tmp_path / "nope.vqt")],
                       capture_output=True, text=True)
    assert p.returncode == 2 and "Traceback" not in p.stderr and p.stderr.count("\n") == 1


def test_sim_plot_shows_where_cycles_went(tmp_path, images, capsys):
    """The plot's bar is split by cause with the report's counts; title, axis and legend name them."""
    from vqtex.sim.reports.plotting import cycle_figure
    out = str(tmp_path / "set.vqt")
    assert _run(capsys, "encode", images[0], "-o", out, "-k", "16", "--index-bits", "12")[0] == 0
    rng = np.random.default_rng(1)
    req = np.column_stack([np.zeros(400, int), np.zeros(400, int), rng.integers(0, 64, 400), rng.integers(0, 64, 400)])
    np.save(tmp_path / "r.npy", req)
    png = tmp_path / "cycles.png"
    code, stdout, _ = _run(capsys, "sim", out, str(tmp_path / "r.npy"), "-o", str(tmp_path / "o.npy"),
                           "--stall", "0.5", "--one-port", "--plot", str(png), "--json")
    assert code == 0
    rep = json.loads(stdout)
    assert rep["stall_cycles"]["one_port_straddle"] == rep["straddling_index_reads"] > 0
    img = read_image(png)
    assert img.shape[1] > 600 and img.shape[0] > 150 and len(np.unique(img.reshape(-1, img.shape[2]), axis=0)) > 4
    fig = cycle_figure(rep)
    ax = fig.axes[0]
    widths = [p.get_width() for p in ax.patches]
    assert widths == [rep["requests"], rep["latency"], rep["stall_cycles"]["output_backpressure"],
                      rep["stall_cycles"]["one_port_straddle"]]
    assert sum(widths) == rep["cycles"]
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "consumer held ready low" in legend[2] and f"{rep['stall_cycles']['output_backpressure']} cycles" in legend[2]
    assert "straddling index" in legend[3] and "one-port" in ax.get_title() and ax.get_xlabel() == "clock cycles"


def test_every_bench_module_imports():
    """``vqtex bench WHAT`` finds its module by name: each name resolves to a module with ``run``."""
    import importlib
    from vqtex.sim.cli.bench import BENCHES
    for what, name in BENCHES.items():
        try:
            mod = importlib.import_module(name)
        except ImportError as e:          # only a missing optional extra is acceptable
            assert e.name and not e.name.startswith(("vqtex", "sim", "golden", "hw")), f"{what}: {e}"
            continue
        assert callable(mod.run), what


def test_hostile_vqt_is_one_line_and_exit_2_within_a_second(tmp_path, capsys):
    """info and decode on a file whose header nests 100000 deep and one whose level 0 claims 2^31
    columns: one line, exit 2, no output file."""
    import time
    from tests.support import HOSTILE_CASES, hostile_files
    for k, name in enumerate(("deeply nested JSON", "1 GiB level 0", "sub-level count 10^9")):
        path = tmp_path / f"bad{k}.vqt"
        path.write_bytes(HOSTILE_CASES[name](hostile_files()[0]))
        for argv in (["info", str(path)], ["decode", str(path), "-o", str(tmp_path / "o.png")]):
            t0 = time.perf_counter()
            code, stdout, stderr = _run(capsys, *argv)
            assert code == 2 and stdout == "" and len(stderr.strip().splitlines()) == 1, (name, stderr)
            assert time.perf_counter() - t0 < 1.0
        assert not (tmp_path / "o.png").exists()
