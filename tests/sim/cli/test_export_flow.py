"""The exported Verilog in someone else's flow: ``vqtex export`` writes OUT.v and its waiver file
OUT.vlt together; ``verilator --lint-only -Wall OUT.vlt OUT.v`` is clean, and so is
``iverilog -Wall`` (v2005 dialect; the sv dialect with -g2012 prints only Icarus's "sorry" notes
about constant selects in always_* processes)."""

import os
import subprocess

import numpy as np
import pytest

from tests.support import need, texture_sets
from vqtex.golden.render.imageio import write_image
from vqtex.sim.cli import main
from vqtex.sim.cli.export import LINT_WAIVERS


@pytest.fixture(scope="module")
def vqt_files(tmp_path_factory):
    """The tests' mixed set and a small set whose raw memory has one word (a zero-width address)."""
    folder = tmp_path_factory.mktemp("vqt")
    texture_sets()["mixed"].save(folder / "mixed.vqt")
    write_image(folder / "a.png", np.random.default_rng(0).integers(0, 256, (32, 32, 3)).astype(np.uint8))
    assert main(["encode", str(folder / "a.png"), "-o", str(folder / "small.vqt"), "-k", "16", "--index-bits", "12"]) == 0
    return {n: str(folder / f"{n}.vqt") for n in ("mixed", "small")}


@pytest.mark.parametrize("name,dialect,one_port", [("mixed", "sv", False), ("mixed", "v2005", True),
                                                   ("small", "sv", True), ("small", "v2005", False)])
def test_lint_clean_in_the_users_flow(vqt_files, tmp_path, capsys, name, dialect, one_port):
    need("verilator", "iverilog")
    out = tmp_path / "unit.v"
    argv = ["export", vqt_files[name], "-o", str(out), "--dialect", dialect] + (["--one-port"] if one_port else [])
    assert main(argv) == 0
    assert sorted(os.listdir(tmp_path)) == ["unit.v", "unit.vlt"]
    assert (tmp_path / "unit.vlt").read_text() == LINT_WAIVERS
    assert "unit.vlt" in capsys.readouterr().out
    lint = subprocess.run(["verilator", "--lint-only", "-Wall", str(tmp_path / "unit.vlt"), str(out)],
                          capture_output=True, text=True)
    assert lint.returncode == 0 and "%Warning" not in lint.stderr and "%Error" not in lint.stderr, lint.stderr
    bare = subprocess.run(["verilator", "--lint-only", "-Wall", str(out)], capture_output=True, text=True)
    assert bare.returncode != 0                                  # the waivers are needed, and they are shipped
    ica = subprocess.run(["iverilog", "-Wall", *(["-g2012"] if dialect == "sv" else []), "-o", os.devnull, str(out)],
                         capture_output=True, text=True)
    assert ica.returncode == 0, ica.stderr
    notes = [ln for ln in (ica.stdout + ica.stderr).splitlines() if ln.strip()]
    if dialect == "v2005":
        assert notes == []
    else:
        assert all("sorry: constant selects in always_* processes" in ln for ln in notes), notes


def test_export_pair_complete_or_absent(vqt_files, tmp_path, capsys):
    (tmp_path / "unit.vlt").mkdir()                               # the waiver file's place is a folder
    assert main(["export", vqt_files["small"], "-o", str(tmp_path / "unit.v")]) == 2
    assert "is a folder" in capsys.readouterr().err
    assert sorted(os.listdir(tmp_path)) == ["unit.vlt"]
