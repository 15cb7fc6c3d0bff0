"""SIGTERM and SIGHUP end a command as Ctrl-C does: staging removed, nothing partial, one line on
stderr and exit status 128 + signum; one test per long command (render, demo, encode, bench), each a
``vqtex`` process signalled while its outputs are staged."""

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
from vqtex.sim.cli.common import STAGING_PREFIX, Outputs, Terminated, ending_signals, exit_status


_LAST = []


def _staged(folder):
    return [n for n in os.listdir(folder) if n.startswith(STAGING_PREFIX)]


def _signalled(argv, folder, signum, *, before=None):
    """Run ``vqtex ARGV``; once a staging folder exists in ``folder`` (so the command has started its
    work: outputs are registered first), send ``signum``. Returns (exit status, stderr)."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [os.environ.get("PYTHONPATH"), REPO])),
               VQTEX_PROGRESS="0")
    p = subprocess.Popen([sys.executable, "-m", "vqtex.sim.cli", *map(str, argv)], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, env=env)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and p.poll() is None and not _staged(folder):
        time.sleep(0.01)
    assert p.poll() is None, f"the command ended before it was signalled: {p.communicate()}"
    if before is not None:
        before()
    p.send_signal(signum)
    out, err = p.communicate(timeout=120)
    _LAST[:] = [out[-300:], sorted(os.listdir(folder))]
    return p.returncode, err


def _assert_ended(code, err, signum, folder, expected_left):
    name = signal.Signals(signum).name
    assert code == 128 + signum, (code, err, _LAST)
    assert err == f"vqtex: terminated by {name}\n", err
    assert sorted(os.listdir(folder)) == sorted(expected_left)


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGHUP])
def test_render(tmp_path, signum):
    out = tmp_path / "out"
    out.mkdir()
    code, err = _signalled(["render", "topspin", "--frames", "0:40:4", "-o", out / "f.png", "--report",
                            out / "r.json"], out, signum)
    _assert_ended(code, err, signum, out, [])


def test_demo(tmp_path):
    code, err = _signalled(["demo", "--backend", "golden", "--frames", "0:50:5", "-o", tmp_path / "demo"],
                           tmp_path, signal.SIGTERM)
    _assert_ended(code, err, signal.SIGTERM, tmp_path, [])


def test_encode(tmp_path):
    img = tmp_path / "big.png"
    write_image(img, np.random.default_rng(0).integers(0, 256, (512, 512, 3)).astype(np.uint8))
    code, err = _signalled(["encode", img, "-o", tmp_path / "o.vqt", "-k", "4096", "--mipmaps"], tmp_path,
                           signal.SIGHUP)
    _assert_ended(code, err, signal.SIGHUP, tmp_path, ["big.png"])


def test_bench(tmp_path):
    pytest.importorskip("sklearn")
    pytest.importorskip("matplotlib")
    code, err = _signalled(["bench", "tradeoff", "--quick", "--scheduler", "serial", "--plot", tmp_path / "plots"],
                           tmp_path, signal.SIGTERM)
    _assert_ended(code, err, signal.SIGTERM, tmp_path, [])


def test_exit_status_and_handlers_restored(tmp_path, capsys):
    """In process: the handlers are vqtex's only inside ``ending_signals`` (so ``main`` leaves the
    caller's in place); a signal raised inside an Outputs block removes its staging."""
    before = {s: signal.getsignal(s) for s in (signal.SIGTERM, signal.SIGHUP)}
    with pytest.raises(Terminated) as info:
        with ending_signals(), Outputs() as outs:
            outs.add(str(tmp_path / "x.png"))
            assert _staged(tmp_path)
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(5)                           # the handler raises before this ends
    assert exit_status(info.value) == 143 and exit_status(KeyboardInterrupt()) == 130
    assert os.listdir(tmp_path) == []
    assert {s: signal.getsignal(s) for s in before} == before
    assert main(["cache", "info", "--keep-mb", "1"]) == 2
    assert {s: signal.getsignal(s) for s in before} == before


def test_signal_during_commit_waits_for_the_renames(tmp_path):
    """A SIGTERM while the outputs are renamed into place is acted on after: every file appears."""
    with pytest.raises(Terminated):
        with ending_signals(), Outputs() as outs:
            paths = [outs.add(str(tmp_path / f"{n}.txt")) for n in range(3)]
            for p in paths:
                with open(outs.path(p), "w") as f:
                    f.write("x")
            real = os.replace

            def replace_then_signal(a, b):
                real(a, b)
                os.kill(os.getpid(), signal.SIGTERM)
            os.replace = replace_then_signal
            try:
                outs.commit()
            finally:
                os.replace = real
    assert sorted(os.listdir(tmp_path)) == ["0.txt", "1.txt", "2.txt"]


def _swallowed_sigterm():
    """SIGTERM whose exception is lost, as Python loses one raised inside an ``issubclass`` check of
    an import (seen about once in 20 runs of ``test_render``)."""
    try:
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(5)
    except BaseException:
        pass


def test_a_lost_exception_still_ends_the_command(tmp_path, capsys, monkeypatch):
    with pytest.raises(Terminated):
        with ending_signals(), Outputs() as outs:
            path = outs.add(str(tmp_path / "x.txt"))
            with open(outs.path(path), "w") as f:
                f.write("x")
            _swallowed_sigterm()
            outs.commit()                               # refused: the signal was received
    assert os.listdir(tmp_path) == []
    from vqtex.sim.backends import toolchain
    monkeypatch.setenv("VQTEX_CACHE", str(tmp_path))
    real = toolchain.cache_info

    def info():
        _swallowed_sigterm()
        return real()
    monkeypatch.setattr(toolchain, "cache_info", info)
    capsys.readouterr()
    assert main(["cache", "info"]) == 143               # a command without outputs: main checks at its end
    assert capsys.readouterr().err == "vqtex: terminated by SIGTERM\n"
    assert main(["cache", "info", "--keep-mb", "1"]) == 2   # the next call starts afresh


def test_module_run_exit_status_survives_a_caught_nested_interrupt(tmp_path):
    """``python -m vqtex.sim.cli`` keeps the command's exit status after a ``KeyboardInterrupt`` was
    raised and caught inside an ``exec`` of a string (as Ctrl-C during a lazy import's dataclass
    does): without the empty ``exec`` in ``__main__`` CPython ends such a process by SIGINT (-2)."""
    probe = tmp_path / "probe"
    probe.mkdir()
    (probe / "__init__.py").write_text("")
    (probe / "__main__.py").write_text(
        "import contextlib, io, runpy, sys\n"
        "from vqtex.sim.cli.entry import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n    main(['cache', 'info', '--json'])\n"  # every import done
        "try:\n    exec('raise KeyboardInterrupt')\nexcept KeyboardInterrupt:\n    pass\n"
        "sys.argv = ['vqtex', 'cache', 'info', '--json']\n"
        "runpy.run_module('vqtex.sim.cli', run_name='__main__')\n")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(tmp_path), os.environ.get("PYTHONPATH"), REPO])))
    r = subprocess.run([sys.executable, "-m", "probe"], capture_output=True, text=True, env=env, timeout=120)
    assert r.returncode == 0, r.stderr
    # the control: the same probe without vqtex's __main__ dies by SIGINT, so the check above can fail
    (probe / "__main__.py").write_text(
        "import sys\ntry:\n    exec('raise KeyboardInterrupt')\nexcept KeyboardInterrupt:\n    pass\nsys.exit(0)\n")
    r = subprocess.run([sys.executable, "-m", "probe"], capture_output=True, text=True, env=env, timeout=120)
    assert r.returncode == -signal.SIGINT
