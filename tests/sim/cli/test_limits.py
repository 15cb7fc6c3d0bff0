"""Every numeric option of every command at its limits, generated from the parser itself: the test
walks ``vqtex``'s argparse tree, so an option added later is probed without a new test.

Each option's value is probed at NaN, +-inf, 0, -1, 2^31, 2^63, 2^64, an overflowing float, text that
is no number, and the edges of its stated range (each end and the nearest value beyond it). A value
outside the range answers with one ``vqtex: error:`` line naming the option, nothing on stdout and
exit status 2, before any work (so the probes run in process, in well under a second each); a value
inside it parses to itself (its documented result). An option whose text is a number must use a
type of :mod:`vqtex.sim.cli.limits` (or ``int`` with ``choices``), so that it is found here, and
its ``--help`` states the range.
"""

from __future__ import annotations

import argparse
import math

import pytest

from tests.support import run_cli
from vqtex.sim.cli import limits
from vqtex.sim.cli.entry import build_parser

#: The values every numeric option is probed at, besides its range's edges.
PROBES = ("nan", "NaN", "inf", "-inf", "1e400", "0", "-1", "1", str(2**31), str(2**63), str(2**64), str(-2**63),
          "0.5", "x", "", " ", "1_0", "0x10")


def _commands(p=None, path=()):
    """(command words, parser) for every (sub)command with options of its own."""
    p = p or build_parser()
    for a in p._actions:
        if isinstance(a, argparse._SubParsersAction):
            for name, sub in a.choices.items():
                yield path + (name,), sub
                yield from _commands(sub, path + (name,))


def _numeric(p):
    """The actions of ``p`` whose value is a number (or built of numbers) or an address."""
    kinds = (limits.Number, limits.Pair, limits.ListOf, limits.Address)
    return [a for a in p._actions if isinstance(a.type, kinds) or (a.type in (int, float))]


def _base_argv(words, p, tmp):
    """``vqtex WORDS`` with every required argument filled in (a choice, or a path that need not
    exist: the probes fail or are parsed before anything is read)."""
    argv = list(words)
    for a in p._actions:
        if isinstance(a, (argparse._SubParsersAction, argparse._HelpAction)):
            continue
        if not a.option_strings and a.nargs != "?":
            argv.append(str(a.choices[0]) if a.choices else str(tmp / "in.vqt"))
        elif a.option_strings and a.required:
            argv += [a.option_strings[0], str(tmp / "out.png")]
    return argv


def _cases():
    """(id, words, option string, action) for every numeric option of every command."""
    out = []
    for words, p in _commands():
        for a in _numeric(p):
            out.append((f"{' '.join(words)} {a.option_strings[0]}", words, a.option_strings[0], a.dest))
    return out


CASES = _cases()


def _number_ok(n: limits.Number, text: str):
    """The documented result for ``text``: (True, value) inside the range, (False, None) outside.
    Written from the range's ends, independently of ``Number.parse``."""
    s = text.strip()
    try:
        if n.kind is int:
            if not s or not all(c.isdigit() or c in "+-_" for c in s) or s.startswith("_"):
                return False, None
            v = int(s)
        else:
            v = float(s)
    except ValueError:
        return False, None
    if isinstance(v, float) and not math.isfinite(v):
        return False, None
    if n.lo is not None and (v < n.lo or (n.lo_open and v == n.lo)):
        return False, None
    if n.hi is not None and (v > n.hi or (n.hi_open and v == n.hi)):
        return False, None
    if n.powers_of_two and (v < 1 or v & (v - 1)):
        return False, None
    return True, v


def _edges(n: limits.Number) -> list[str]:
    """The ends of ``n``'s range and the nearest values beyond them."""
    vals = []
    for end, away in ((n.lo, -math.inf), (n.hi, math.inf)):
        if end is None:
            continue
        if n.kind is int:
            vals += [end, end + (1 if away > 0 else -1)]
        else:
            vals += [end, math.nextafter(end, away), math.nextafter(end, -away)]
    return [repr(v) if isinstance(v, float) else str(v) for v in vals]


def _probes(t):
    """(text, valid, value) for the type ``t`` of an option."""
    if isinstance(t, limits.Number):
        for text in PROBES + tuple(_edges(t)):
            ok, v = _number_ok(t, text)
            yield text, ok, v
    elif isinstance(t, limits.Pair):
        for text, ok, v in _probes(t.side):
            yield f"{text}x{text}", ok, (v, v) if ok else None
            yield f"1x{text}", ok, (1, v) if ok else None
        yield "4x4x4", False, None
        yield "4", False, None
    elif isinstance(t, limits.ListOf):
        for text, ok, v in _probes(t.item):
            if "," not in text and text.strip():
                yield text, ok, (v,) if ok else None
        yield ",", False, None
        yield ",".join(["16"] * (t.most + 1)), False, None
    elif isinstance(t, limits.Address):
        for text in ("", "x", "not-an-address", "tcp://host", "tcp://host:0", "tcp://host:65536", "host:" + str(2**64),
                     "tcp://host:nan", "ftp://host:8786", "tcp://:8786"):
            yield text, False, None
        for text, value in (("serial", "serial"), ("tcp://127.0.0.1:8786", "tcp://127.0.0.1:8786"),
                            ("host:1", "tcp://host:1"), ("tls://[::1]:65535", "tls://[::1]:65535")):
            yield text, True, value


def test_every_numeric_option_uses_the_validator():
    """A plain ``type=int`` or ``type=float`` would take NaN, infinity or any width: only ``int``
    with ``choices`` (a closed set) is allowed besides the types of ``limits``."""
    plain = [c[0] for c in CASES if _action(c[1], c[3]).type in (int, float) and not _action(c[1], c[3]).choices]
    assert plain == []
    assert len(CASES) >= 25                               # the walk found the options


def _action(words, dest):
    parser = dict(_commands())[tuple(words)]
    return next(a for a in parser._actions if a.dest == dest and a.option_strings)


@pytest.mark.parametrize("name, words, opt, dest", CASES, ids=[c[0] for c in CASES])
def test_option_at_its_limits(name, words, opt, dest, tmp_path, capsys):
    a = _action(words, dest)
    parser = build_parser()
    base = _base_argv(words, dict(_commands(parser))[tuple(words)], tmp_path)
    if a.type in (int, float):                            # int with choices: the choices are the range
        probes = [(t, t.strip().lstrip("-").isdigit() and int(t) in a.choices, None) for t in PROBES]
        probes += [(str(c), True, c) for c in a.choices]
    else:
        assert a.type.range_text in " ".join(a.help.split()), (name, a.help)   # --help states the range
        probes = list(_probes(a.type))
    assert len(probes) >= 10
    for text, ok, value in probes:
        argv = base + [f"{opt}={text}"]
        if ok:
            ns = parser.parse_args(argv)
            if value is not None:
                assert getattr(ns, dest) == value, (argv, getattr(ns, dest))
            continue
        code, out, err = run_cli(capsys, *argv)
        assert code == 2 and out == "", (argv, code, out)
        assert err.count("\n") == 1 and err.startswith("vqtex: error: "), (argv, err)
        assert opt in err or any(o in err for o in a.option_strings), (argv, err)
        if isinstance(a.type, (limits.Number, limits.Pair, limits.ListOf)) and text.strip() not in ("", "x", ","):
            assert a.type.range_text.split(", each ")[-1].split("sides ")[-1] in err, (argv, err)


def test_the_reported_cases():
    """The cases the limits suite was written for, each one line and exit 2 (docs/usage.md)."""
    import contextlib
    import io
    from vqtex.sim.cli import main
    cases = [
        (["cache", "clean", "--keep-mb", "nan"], "--keep-mb"),
        (["cache", "clean", "--keep-mb", "inf"], "--keep-mb"),
        (["need", "topspin", "--frames", "0", "--cache-tile", "9223372036854775808x2"], "--cache-tile"),
        (["bench", "tradeoff", "--quick", "--scheduler", "not-an-address"], "--scheduler"),
        (["bench", "tradeoff", "--quick", "--scheduler", ""], "--scheduler"),
        (["render", "topspin", "--frames", "0", "--stall", "1", "-o", "r.png"], "--stall"),
        (["render", "topspin", "--frames", "0", "--stall=-3", "-o", "r.png"], "--stall"),
        (["render", "topspin", "--frames", "0", "--stall", "nan", "-o", "r.png"], "--stall"),
        (["encode", "--layout", "pvr2", "--block", "4x4", "IMAGE.png", "-o", "o.dt"], "--block does not apply"),
        (["encode", "--layout", "pvr2", "--block", "2x2", "IMAGE.png", "-o", "o.dt"], "--block does not apply"),
    ]
    for argv, pattern in cases:
        err = io.StringIO()
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()) as out:
            code = main(argv)
        assert code == 2 and out.getvalue() == "", argv
        assert err.getvalue().count("\n") == 1 and pattern in err.getvalue(), (argv, err.getvalue())


#: Options that do not apply, given with the value they would default to (refused all the same).
NOT_APPLYING = [
    (["encode", "a.png", "-o", "o.dt", "--layout", "pvr2", "--index-bits", "8"], "--index-bits does not apply"),
    (["encode", "a.png", "-o", "o.dt", "--layout", "pvr2", "--mip-training", "average"], "--mip-training"),
    (["encode", "a.png", "-o", "o.dt", "--layout", "pvr2", "--encoder", "gla"], "--encoder does not apply"),
    (["encode", "a.png", "-o", "o.dt", "--layout", "pvr2", "--word-bits", "32"], "--word-bits does not apply"),
    (["encode", "a.png", "-o", "o.vqt", "--mip-training", "average"], "needs --mipmaps"),
    (["render", "topspin", "--frames", "0", "-o", "r.png", "--lanes", "4"], "needs --filter-in-rtl"),
    (["render", "topspin", "--frames", "0", "-o", "r.png", "--index-banks", "parity"], "needs --filter-in-rtl"),
    (["render", "topspin", "--frames", "0", "-o", "r.png", "--train-on", "levels"], "--encode-needed"),
    (["render", "topspin", "--frames", "0", "-o", "r.png", "--diff-scale", "32"], "needs --diff"),
    (["render", "topspin", "--frames", "0", "-o", "r.png", "--stall", "0.5"], "--stall 0.5 does not apply"),
    (["render", "topspin", "--frames", "0", "-o", "r.png", "--one-port"], "--one-port does not apply"),
    (["render", "topspin", "--frames", "0", "-o", "r.png", "--backend", "pysim", "--stall-seed", "0"], "needs --stall"),
    (["prune", "s.vqt", "--scene", "topspin", "--frames", "0", "-o", "p.vqt", "--train-on", "levels"], "--train-on"),
    (["export", "s.vqt", "-o", "x.v", "--index-banks", "parity"], "needs --filter-lanes"),
    (["export", "s.vqt", "-o", "x.v", "--filter-lanes", "2", "--unit", "specialised"], "--unit"),
    (["report", "area", "--builtin", "tiny", "--index-banks", "parity"], "needs --filter-lanes"),
    (["report", "area", "--builtin", "tiny", "--filter-lanes", "2", "--unit", "specialised"], "--unit"),
    (["report", "area", "--builtin", "tiny", "--no-pnr", "--freq", "150"], "--freq"),
    (["report", "area", "--builtin", "tiny", "--no-pnr", "--placer-seed", "1"], "--placer-seed"),
    (["report", "area", "--builtin", "tiny", "--no-pnr", "--router", "router2"], "--router"),
    (["report", "area", "--builtin", "tiny", "--no-route", "--router", "router2"], "--router"),
    (["report", "area", "--builtin", "tiny", "--no-pnr", "--no-route"], "--no-route"),
    (["report", "area", "--builtin", "tiny", "--no-pnr", "--bram-outreg"], "--bram-outreg"),
    (["experiments", "table3", "--backend", "golden"], "--backend"),
    (["experiments", "table4", "--requests", "fixed"], "--requests"),
    (["experiments", "table5", "--paper-only"], "--paper-only"),
    (["experiments", "table5", "--scheduler", "serial"], "--scheduler"),
    (["experiments", "hardware", "--frame-step", "5", "--scheduler", "serial", "--workers", "2"], "--workers"),
    (["cache", "info", "--keep-mb", "0"], "--keep-mb"),
    (["bench", "mip", "--threads", "0"], "--threads"),
]


@pytest.mark.parametrize("argv, pattern", NOT_APPLYING, ids=[" ".join(a[0][:1] + a[0][-2:]) for a in NOT_APPLYING])
def test_options_that_do_not_apply_are_refused_at_any_value(argv, pattern, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "a.png").write_bytes(b"")                     # refused before the image is read
    code, out, err = run_cli(capsys, *argv)
    assert code == 2 and out == "" and err.count("\n") == 1 and pattern in err, (argv, err)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.png"]


def test_a_scene_beyond_the_rasterizer_limits_is_one_line(tmp_path, capsys):
    """A floor of 1e9 units (the scene reader's largest magnitude) through the view of a camera whose
    near plane is at 1e-6: clipped, beyond raster.CLIP_RANGE times the near plane; the command answers
    with one line (a SceneError), not a traceback and not half a frame."""
    from tests.support import TINY_SCENE
    scene = tmp_path / "huge.toml"
    scene.write_text(TINY_SCENE.replace("size = [6.0, 6.0]", "size = [1e9, 1e9]").replace("fov = 50", "fov = 50\nnear = 1e-6"))
    code, out, err = run_cli(capsys, "render", scene, "--frames", "0", "-o", tmp_path / "f.png")
    assert code == 2 and out == "" and err.count("\n") == 1, err
    assert "frame 0" in err and "needs clipping" in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["huge.toml"]


def test_usage_states_every_range():
    """docs/usage.md's table holds every numeric option with its range (a new option fails here until
    it is documented)."""
    import os
    from tests.support import REPO
    doc = open(os.path.join(REPO, "docs", "usage.md")).read()
    for words, p in _commands():
        for a in _numeric(p):
            rng = a.type.range_text if hasattr(a.type, "range_text") else "one of " + ", ".join(map(str, a.choices))
            assert f"| `{'/'.join(a.option_strings)}` | {rng} |" in doc, (words, a.option_strings)
