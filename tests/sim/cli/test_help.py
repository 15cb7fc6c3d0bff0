"""Help and consistency of the command line: every argument explained with its default, --version,
old spellings kept as aliases, argparse errors prefixed once, the scene format documented."""

import argparse
import os
import re
import subprocess
import sys

from tests.support import REPO
from vqtex.sim.cli import main
from vqtex.sim.cli.entry import build_parser, version


def _parsers(p, name="vqtex"):
    """(name, parser) for the parser and every subcommand's, recursively."""
    yield name, p
    for a in p._actions:
        if isinstance(a, argparse._SubParsersAction):
            for sub_name, sub in a.choices.items():
                yield from _parsers(sub, f"{name} {sub_name}")


def _shown_default(default):
    if isinstance(default, tuple):
        return "x".join(map(str, default))
    return default


def test_every_argument_has_help_with_its_default():
    checked = 0
    for name, p in _parsers(build_parser()):
        for a in p._actions:
            if isinstance(a, (argparse._HelpAction, argparse._VersionAction)):
                continue
            if isinstance(a, argparse._SubParsersAction):
                for choice in a._choices_actions:
                    assert choice.help, (name, choice.dest)
                continue
            where = (name, a.option_strings or a.dest)
            assert a.help and len(a.help) > 10, where
            assert not re.search(r"\bissue\b", a.help), where                 # no internal wording
            checked += 1
            if not a.option_strings or isinstance(a, argparse._StoreTrueAction) or a.required:
                continue
            m = re.search(r"\(default ([^()]*(?:\([^()]*\))?[^()]*)\)", a.help)
            assert m, where
            if a.default is not None:
                shown = m.group(1)
                want = _shown_default(a.default)
                assert shown == str(want) or (isinstance(want, float) and float(shown) == want), (where, shown, want)
    assert checked > 60


def test_version():
    p = subprocess.run([sys.executable, "-m", "vqtex.sim.cli", "--version"], capture_output=True, text=True,
                       env=dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [os.environ.get("PYTHONPATH"), REPO]))))
    assert p.returncode == 0 and p.stdout == f"vqtex {version()}\n" and p.stderr == ""
    assert re.fullmatch(r"\d+\.\d+\.\d+.*", version())


def test_one_name_per_meaning_old_spellings_kept():
    p = build_parser()
    for argv, dest, value in (
            (["encode", "a.png", "-o", "a.vqt", "--encoder-seed", "3"], "seed", 3),
            (["encode", "a.png", "-o", "a.vqt", "--seed", "3"], "seed", 3),
            (["sim", "a.vqt", "r.npy", "-o", "o.npy", "--stall-seed", "4"], "seed", 4),
            (["sim", "a.vqt", "r.npy", "-o", "o.npy", "--seed", "4"], "seed", 4),
            (["render", "topspin", "-o", "f.png", "--stall-seed", "5"], "seed", 5),
            (["report", "area", "--builtin", "tiny", "--placer-seed", "6"], "seed", 6),
            (["report", "area", "--builtin", "tiny", "--seed", "6"], "seed", 6),
            (["demo", "-o", "d"], "out_dir", "d"),
            (["demo", "--out-dir", "d"], "out_dir", "d")):
        assert getattr(p.parse_args(argv), dest) == value, argv
    helps = {name: sub.format_help() for name, sub in _parsers(p)}
    assert "--encoder-seed" in helps["vqtex encode"] and "--stall-seed" in helps["vqtex sim"]
    assert "--placer-seed" in helps["vqtex report area"]


def test_argparse_errors_prefixed_once(capsys):
    for argv, start in ((["encode"], "vqtex: error: encode: the following arguments are required"),
                        (["report", "area", "--freq", "x"], "vqtex: error: report area: argument --freq"),
                        (["info", "a.vqt", "--bogus"], "vqtex: error: unrecognized arguments: --bogus"),
                        ([], "vqtex: error: the following arguments are required: command"),
                        (["render"], "vqtex: error: render: the following")):
        capsys.readouterr()
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert err.startswith(start) and err.count("vqtex") == 1 and err.count("\n") == 1, (argv, err)


def test_scene_format_documented():
    """docs/rendering.md holds the scene format: its example parses as a scene, and every shape and
    texture generator the loader knows is in its tables."""
    from vqtex.golden.render.scene import SHAPES, parse_scene
    from vqtex.golden.render.textures import GENERATORS
    doc = open(os.path.join(REPO, "docs", "rendering.md")).read()
    section = doc[doc.index("## Scene files"):]
    section = section[:section.index("\n## ", 5)]
    block = re.search(r"```toml\n(.*?)```", section, re.S).group(1)
    scene = parse_scene(block, os.path.join(REPO, "docs", "example.toml"))
    assert scene.name == "demo" and scene.frames == 50
    for name in list(SHAPES) + list(GENERATORS):
        assert f"`{name}`" in section, name
    usage = open(os.path.join(REPO, "docs", "usage.md")).read()
    assert "rendering.md#scene-files" in usage
