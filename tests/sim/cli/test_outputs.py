"""Outputs through the command line: checked before any work (one line, exit 2), complete or absent
(also when interrupted), ordinary permissions, extensions that name the format."""

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from tests.support import REPO
from vqtex.golden.render.imageio import write_image
from vqtex.sim.cli import main
from vqtex.sim.cli import demo as demo_cmd


@pytest.fixture
def work(tmp_path):
    """A folder with an image, a texture set and a request file."""
    img = tmp_path / "a.png"
    write_image(img, np.random.default_rng(0).integers(0, 256, (32, 32, 3)).astype(np.uint8))
    assert main(["encode", str(img), "-o", str(tmp_path / "a.vqt"), "-k", "16"]) == 0
    np.save(tmp_path / "r.npy", np.array([[0, 0, 1, 2], [0, 0, 3, 4]]))
    return tmp_path


def _read_only_folder(tmp_path):
    """A folder no file can be created in: chmod 0555 for a normal user; root ignores modes, so /sys."""
    if os.geteuid() != 0:
        ro = tmp_path / "ro"
        ro.mkdir()
        ro.chmod(0o555)
        return str(ro)
    return "/sys"


def _leftovers(folder):
    return [p for p in os.listdir(folder) if p.startswith(".vqtex") or p.startswith(".tmp")]


def _commands(w, out):
    """Every subcommand that writes, with ``out`` as its (first) output."""
    vqt, req, scene = str(w / "a.vqt"), str(w / "r.npy"), "topspin"
    return {
        "encode": ["encode", str(w / "a.png"), "-o", out],
        "decode": ["decode", vqt, "-o", out],
        "sim": ["sim", vqt, req, "-o", out],
        "sim --plot": ["sim", vqt, req, "-o", str(w / "ok.npy"), "--plot", out],
        "export": ["export", vqt, "-o", out],
        "render": ["render", scene, "--frames", "0", "-o", out],
        "render --report": ["render", scene, "--frames", "0", "-o", str(w / "ok.png"), "--report", out],
        "render --diff": ["render", scene, "--frames", "0", "-o", str(w / "ok.png"), "--diff", out],
        "render --reference": ["render", scene, "--frames", "0", "-o", str(w / "ok.png"), "--reference", out],
        "report cycles --plot": ["report", "cycles", vqt, req, "--plot", out],
    }


@pytest.mark.parametrize("case", ["missing folder", "a folder", "read-only"])
def test_outputs_checked_before_work(work, tmp_path, capsys, case):
    ro = _read_only_folder(tmp_path)
    exts = {"encode": ".vqt", "sim": ".npy", "export": ".v", "render --report": ".json"}
    for name in _commands(work, "X"):
        ext = exts.get(name, ".png")
        out = {"missing folder": str(tmp_path / "nodir" / f"o{ext}"), "a folder": str(tmp_path),
               "read-only": os.path.join(ro, f"o{ext}")}[case]
        argv = _commands(work, out)[name]
        capsys.readouterr()
        t0 = time.perf_counter()
        assert main(argv) == 2, name
        err = capsys.readouterr().err
        want = {"missing folder": "does not exist", "a folder": "is a folder", "read-only": "is not writable"}[case]
        assert err.count("\n") == 1 and err.startswith("vqtex: error: output") and want in err, (name, err)
        assert time.perf_counter() - t0 < 5, name            # no rendering or encoding happened first
        assert not (work / "ok.npy").exists() and not (work / "ok.png").exists(), name
        assert not _leftovers(tmp_path), name


def test_extension_must_match_the_format(work, capsys):
    for name, argv in _commands(work, str(work / "o.csv")).items():
        capsys.readouterr()
        assert main(argv) == 2, name
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "the extension must be" in err, (name, err)
    assert main(["decode", str(work / "a.vqt"), "-o", str(work / "o.tif")]) == 0
    assert not (work / "o.csv").exists() and not _leftovers(work)


@pytest.mark.parametrize("umask", [0o022, 0o077])
def test_output_permissions_follow_umask(work, umask):
    old = os.umask(umask)
    try:
        outs = {"encode": "o.vqt", "decode": "o.png", "sim": "o.npy", "sim --plot": "p.png", "export": "o.v"}
        cmds = _commands(work, "")
        for name, out in outs.items():
            argv = [a if a != "" else str(work / out) for a in cmds[name]]
            assert main(argv) == 0, name
            assert (work / out).stat().st_mode & 0o777 == 0o666 & ~umask, name
        assert (work / "ok.npy").stat().st_mode & 0o777 == 0o666 & ~umask
    finally:
        os.umask(old)
    assert not _leftovers(work)


def test_render_several_frames_and_report_all_or_nothing(tmp_path, capsys, monkeypatch):
    from vqtex.sim.cli import render as render_cmd
    real = render_cmd.render_scene
    seen = []

    def failing(*a, **kw):
        for r in real(*a, **kw):
            seen.append(r["frame"])
            if len(seen) == 2:
                raise KeyboardInterrupt
            yield r
    monkeypatch.setattr(render_cmd, "render_scene", failing)
    out = tmp_path / "f.png"
    code = main(["render", "topspin", "--frames", "0:30:10", "-o", str(out), "--report", str(tmp_path / "r.json")])
    assert code == 130 and seen == [0, 10]
    assert os.listdir(tmp_path) == []
    monkeypatch.setattr(render_cmd, "render_scene", real)
    assert main(["render", "topspin", "--frames", "0:30:10", "-o", str(out), "--report", str(tmp_path / "r.json")]) == 0
    assert sorted(os.listdir(tmp_path)) == ["f_0000.png", "f_0010.png", "f_0020.png", "r.json"]


def test_demo_interrupted_in_process_leaves_nothing(tmp_path, capsys, monkeypatch):
    """Ctrl-C after the texture set and a frame are written: neither a new nor an existing folder changes."""
    real = demo_cmd.render_to_files

    def interrupted(scene, ts, frames, path_of, images, *, outs, **kw):
        real(scene, ts, frames[:1], path_of, images, outs=outs, **kw)
        assert os.path.isfile(outs.path(path_of(frames[0])))
        raise KeyboardInterrupt
    monkeypatch.setattr(demo_cmd, "render_to_files", interrupted)
    assert main(["demo", "--backend", "golden", "--frames", "0:2", "-o", str(tmp_path / "new")]) == 130
    assert "interrupted" in capsys.readouterr().err
    assert os.listdir(tmp_path) == []
    old = tmp_path / "old"
    old.mkdir()
    (old / "report.json").write_text("{}")
    assert main(["demo", "--backend", "golden", "--frames", "0:2", "--out-dir", str(old)]) == 130
    assert os.listdir(old) == ["report.json"] and (old / "report.json").read_text() == "{}"


def test_demo_sigint_as_a_subprocess(tmp_path):
    """SIGINT to a running ``vqtex demo`` once its first output exists (in the staging folder): exit
    130, one line, and neither the output folder nor a staging folder is left."""
    out = tmp_path / "demo"
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [os.environ.get("PYTHONPATH"), REPO])))
    p = subprocess.Popen([sys.executable, "-m", "vqtex.sim.cli", "demo", "--backend", "golden",
                          "--frames", "0:50:5", "-o", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True, env=env)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and p.poll() is None:
        staged = [os.path.join(r, f) for r, _, fs in os.walk(tmp_path) for f in fs]
        if any(f.endswith("topspin.vqt") for f in staged):
            break
        time.sleep(0.02)
    assert p.poll() is None, "the demo ended before its first output appeared"
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=120)
    assert p.returncode == 130, err
    assert err == "vqtex: interrupted\n"
    assert os.listdir(tmp_path) == []


def test_demo_complete_set(tmp_path, capsys):
    out = tmp_path / "d"
    assert main(["demo", "--backend", "golden", "--frames", "0:2", "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert sorted(os.listdir(out)) == ["report.json", "topspin.vqt", "topspin_0000.png", "topspin_0001.png",
                                       "topspin_compare.png"]
    assert "RTL: not run" in text and "cycle model" in text
    # the side-by-side picture, named in the summary: uncompressed | compressed | difference
    assert f"{out}/topspin_compare.png: frame 0 uncompressed | compressed | difference" in text
    from vqtex.golden.render.imageio import read_image
    from vqtex.golden.render.scene import load_scene
    from vqtex.golden.render import render_frame
    from vqtex.sim.reports.quality import difference, heat
    pic, frame = read_image(out / "topspin_compare.png"), read_image(out / "topspin_0000.png")
    h, w = frame.shape[:2]
    scene = load_scene("topspin")
    ref = render_frame(scene, 0, scene.reference_source(), "trilinear")
    assert pic.shape == (h + 16, 3 * w + 16, 3)
    assert np.array_equal(pic[:h, :w], ref[..., :3]) and np.array_equal(pic[:h, w + 8:2 * w + 8], frame[..., :3])
    assert np.array_equal(pic[:h, 2 * w + 16:], heat(difference(frame, ref)))
    assert json.loads((out / "report.json").read_text())["comparison"]["file"] == "topspin_compare.png"
    assert (out.stat().st_mode & 0o777) == 0o777 & ~_umask()
    assert not _leftovers(tmp_path)


def _umask():
    m = os.umask(0)
    os.umask(m)
    return m
