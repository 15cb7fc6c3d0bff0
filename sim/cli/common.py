"""What every ``vqtex`` subcommand shares: the user-error exception, the argument parser class,
JSON or text output, the command's output files and loading a texture set with clean errors.

Outputs (:class:`Outputs`) follow one rule for every command:

* **checked before work**: each output is registered (``add`` for a file, ``folder`` for an output
  folder) before the command computes anything. A missing folder, a path that is a folder (or, for an
  output folder, a file), a folder the user cannot write, an extension that does not name what is
  written: one line (``vqtex: error: output folder ... does not exist``) and exit 2.
* **complete or absent**: every file is written into a hidden staging folder (``.vqtex-staging-*``)
  created at registration in the destination's own folder (so the final move is a rename on one file
  system, and creating it is the writability check). Only when the command has finished its work are
  the files renamed into place, together, with the ending signals held back for those few renames; an
  error or an interrupt before that removes the staging folders and nothing of the set appears. A new
  output folder (``vqtex demo -o DIR``) is staged whole and appears with one rename. Only a killed
  process (SIGKILL, power loss) can leave a staging folder behind.
* **ending signals**: SIGINT (Ctrl-C), SIGTERM and SIGHUP end a command the same way
  (:func:`ending_signals`, which ``vqtex``'s ``main`` runs every command in): the signal becomes an
  exception in the main thread (``KeyboardInterrupt``; :class:`Terminated`, a subclass, for SIGTERM
  and SIGHUP), so the staging folders are removed as for any error, and the command exits with
  ``128 + signum`` (130, 143, 129: :func:`exit_status`) after one line on stderr. A signal that
  arrives while the outputs are being renamed into place, or their staging removed, waits for that to
  finish.
* **ordinary permissions**: a written file gets ``0666 & ~umask`` (0644 under umask 022), whatever
  the writer used for its temporary file (``mkstemp`` makes 0600).

The subcommand modules import this module; it imports none of them.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import contextlib
import signal
import sys
import tempfile
import threading

from . import limits
from .limits import number_help

__all__ = ["CliError", "Parser", "number_help", "BACKEND_HELP", "add_json", "add_texture_set", "add_backend",
           "add_hardware_options", "stall_seed", "resolve", "add_unit", "unit_geometry", "add_tag_width", "emit", "warn", "warn_slow", "progress_enabled", "progress_line",
           "Outputs", "check_folder", "IMAGE_SUFFIXES", "write_bytes", "write_json", "load_set", "is_dt", "with_default",
           "file_mode", "ENDING_SIGNALS", "Terminated", "ending_signals", "check_ended", "exit_status", "ending_message", "add_sweep_options", "sweep_options", "PYSIM_CYCLES_PER_SECOND", "SLOW_SECONDS", "STAGING_PREFIX"]

#: Image file extensions an output image may have (all hold RGBA except JPEG and BMP, which drop alpha).
IMAGE_SUFFIXES = (".png", ".tif", ".tiff", ".exr", ".tga", ".bmp", ".jpg", ".jpeg")

STAGING_PREFIX = ".vqtex-staging-"


class CliError(Exception):
    """A user error: printed as one line, exit status 2."""


#: The signals that end a command cleanly (staging removed, exit status 128 + signum).
ENDING_SIGNALS = tuple(getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name))


class Terminated(KeyboardInterrupt):
    """SIGTERM or SIGHUP as an exception (``signum``): it unwinds the command as Ctrl-C's
    ``KeyboardInterrupt`` does (it is one), so every ``finally`` and every ``Outputs`` block cleans up."""

    def __init__(self, signum: int):
        super().__init__(signal.Signals(signum).name)
        self.signum = int(signum)


#: The ending signals received inside :func:`ending_signals` (emptied when it starts). Python can
#: lose the exception a handler raises (raised inside an ``issubclass`` check of an import, it is
#: printed as "ignored" and the program goes on), so the signal is also recorded here, and
#: :func:`check_ended` raises it again where it must not be missed: before outputs are renamed into
#: place and when a command returns.
_ENDED: list = []


def _raise_for(signum, _frame=None):
    if signum == signal.SIGINT:
        raise KeyboardInterrupt
    raise Terminated(signum)


def _on_signal(signum, _frame=None):
    _ENDED.append(int(signum))
    _raise_for(signum)


def check_ended() -> None:
    """Raise the first ending signal received inside :func:`ending_signals` (``KeyboardInterrupt``
    or :class:`Terminated`), even if the exception its handler raised was lost; nothing otherwise."""
    if _ENDED:
        _raise_for(_ENDED[0])


def exit_status(exc: KeyboardInterrupt) -> int:
    """The conventional exit status of a command ended by ``exc``: 128 + the signal's number (130
    for Ctrl-C's plain ``KeyboardInterrupt``)."""
    return 128 + getattr(exc, "signum", int(signal.SIGINT))


def ending_message(exc: KeyboardInterrupt) -> str:
    """The one line printed when a signal ends a command: ``vqtex: interrupted`` (SIGINT) or
    ``vqtex: terminated by SIGTERM`` (SIGHUP likewise)."""
    if isinstance(exc, Terminated):
        return f"vqtex: terminated by {signal.Signals(exc.signum).name}"
    return "vqtex: interrupted"


@contextlib.contextmanager
def ending_signals():
    """Inside the block, SIGTERM and SIGHUP raise :class:`Terminated` and SIGINT ``KeyboardInterrupt``
    in the main thread (elsewhere the block changes nothing: Python delivers signals to the main thread
    only). The previous handlers are restored after."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    _ENDED.clear()
    old = {s: signal.signal(s, _on_signal) for s in ENDING_SIGNALS}
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h)
        _ENDED.clear()


@contextlib.contextmanager
def _signals_held():
    """Inside the block the ending signals are recorded, not acted on; after it, the first one
    recorded is raised (as :func:`ending_signals` would have). Only in the main thread."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    pending = []
    old = {s: signal.signal(s, lambda signum, _f: pending.append(signum)) for s in ENDING_SIGNALS}
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h)
    if pending:
        _on_signal(pending[0])


class Parser(argparse.ArgumentParser):
    """An ``ArgumentParser`` whose errors are one line and exit 2 (argparse would print the usage too).

    The message names the subcommand once: ``vqtex: error: encode: the following arguments ...``.
    """

    def error(self, message):
        sub = self.prog.split(" ", 1)[1] if " " in self.prog else ""
        raise CliError(f"{sub}: {message}" if sub else message)


def with_default(text: str, default) -> str:
    """Help text ending with its default, as every argument's help shows it."""
    return f"{text} (default {default})"


#: What each backend is, for --backend help texts.
BACKEND_HELP = {
    "golden": "golden (numpy fetch and the exact cycle model, no RTL)",
    "pysim": "pysim (Amaranth's simulator, about 2e3 cycles/s: small traces)",
    "cxxrtl": "cxxrtl (the RTL compiled with CXXRTL, about 1e7 cycles/s)",
    "verilator": "verilator (the exported Verilog through Verilator)",
}


def add_json(p) -> None:
    """``--json``: print one JSON object instead of text."""
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout instead of text")


def add_texture_set(p) -> None:
    """The positional ``.vqt`` input."""
    p.add_argument("file", metavar="FILE.vqt", help="a texture set written by vqtex encode or vqtex import, "
                   "or a Dreamcast VQ texture (.dt, as pvrtex writes it: a set of one texture)")


def add_backend(p, choices, default: str) -> None:
    """``--backend`` with each choice explained."""
    p.add_argument("--backend", choices=choices, default=default,
                   help=with_default("what answers the texel requests: "
                                     + "; ".join(BACKEND_HELP[c] for c in choices), default))


def add_hardware_options(p, *, stall: bool = True) -> None:
    """The unit's options shared by the simulating commands: ``--one-port``, and with ``stall`` the
    output backpressure ``--stall`` and its pattern's seed ``--stall-seed`` (old spelling ``--seed``)."""
    p.add_argument("--one-port", action="store_true",
                   help="one-port index memory: one extra cycle per straddling index (the paper's penalty; "
                        "default two banks, no penalty)")
    if stall:
        p.add_argument("--stall", type=limits.STALL, default=0.0,
                       help=number_help("probability that the consumer holds the output's ready low in a cycle",
                                        limits.STALL, 0.0))
        p.add_argument("--stall-seed", "--seed", dest="seed", type=limits.SEED, default=None,
                       help=number_help("seed of the --stall pattern, with --stall above 0 (--seed is the old "
                                        "spelling)", limits.SEED, 0))


def stall_seed(args, stall_applies: bool = True) -> int:
    """``--stall-seed`` checked against what it seeds: refused when the ``--stall`` pattern it seeds
    is all ready (``--stall 0``) or when ``--stall`` itself does not apply (``stall_applies`` False:
    then ``--stall`` above 0 is refused too); the seed, 0 when not given."""
    if args.stall > 0 and not stall_applies:
        raise CliError(f"--stall {args.stall:g} does not apply: nothing runs the unit's cycles here "
                       "(an RTL backend, --compare-fixed or --fovea does)")
    if args.seed is not None and args.stall == 0:
        raise CliError("--stall-seed seeds the --stall pattern: it needs --stall above 0")
    return 0 if args.seed is None else args.seed


#: ``--memory``: every memory on chip (the unit of docs/hardware.md), or the index map and raw levels
#: in external memory behind caches (docs/memory.md).
MEMORIES = ("on-chip", "external")
#: The external memory's options: (attribute, option, limits type, default, help).
_MEMORY_OPTIONS = (
    ("cache_size", "--cache-size", "CACHE_BYTES", 16384, "the index cache's bytes"),
    ("raw_cache_size", "--raw-cache-size", "CACHE_BYTES", 4096, "the raw cache's bytes"),
    ("cache_line", "--cache-line", "CACHE_LINE", 32, "bytes per cache line (both caches; one AXI burst)"),
    ("cache_ways", "--cache-ways", None, 4, "ways per set (both caches), LRU"),
    ("prefetch", "--prefetch", "PREFETCH", 128, "entries of the FIFO of references between tag check and data "
                                               "read; 1 is the blocking cache"),
    ("memory_latency", "--memory-latency", "MEMORY_LATENCY", 100, "fixed memory: cycles from AR to the first beat"),
    ("memory_bandwidth", "--memory-bandwidth", "MEMORY_BANDWIDTH", 16, "fixed memory: bytes per clock"),
    ("bus_bytes", "--bus-bytes", "BUS_BYTES", 16, "AXI data width in bytes"),
    ("dram_clock", "--dram-clock", "DRAM_CLOCK", 200.0, "DRAM: the controller's (and unit's) clock"),
    ("controller_cycles", "--controller-cycles", "CONTROLLER_CYCLES", 0, "DRAM: the controller's own latency "
                                                                        "beyond CL"),
)


def add_memory_options(p) -> None:
    """``--memory on-chip|external`` and the external memory's caches and timing (docs/memory.md)."""
    p.add_argument("--memory", choices=MEMORIES, default="on-chip",
                   help=with_default("where the index map and raw levels live: on chip, or in external memory "
                                     "read over AXI4 behind caches (every backend)", "on-chip"))
    for attr, opt, kind, default, text in _MEMORY_OPTIONS:
        if kind is None:                    # --cache-ways: as vqtex need spells it
            p.add_argument(opt, dest=attr, type=int, choices=[1, 2, 4, 8, 16], default=None,
                           help=with_default(text + " (--memory external)", default))
            continue
        p.add_argument(opt, dest=attr, type=getattr(limits, kind), default=None,
                       help=number_help(text + " (--memory external)", getattr(limits, kind), default))
    p.add_argument("--memory-model", choices=("fixed", "dram"), default=None,
                   help=with_default("the external memory: a fixed latency and bandwidth, or a DRAM part "
                                     "(--dram-part)", "fixed"))
    from vqtex.golden.memory.dram import PARTS
    p.add_argument("--dram-part", choices=sorted(PARTS), default=None,
                   help=with_default("the DRAM part (--memory-model dram)", "MT41K256M16-125"))


def memory_config(args):
    """The :class:`golden.memory.system.MemoryConfig` of ``--memory external`` and its options, or
    None for ``--memory on-chip`` (then every external-memory option is refused); a configuration
    the memory system refuses (a line wider than the cache, a bandwidth that does not divide the bus,
    ...) is a one-line CliError."""
    from vqtex.golden.memory.cache import CacheShape
    from vqtex.golden.memory.system import MemoryConfig
    names = [a for a, *_ in _MEMORY_OPTIONS] + ["memory_model", "dram_part"]
    if args.memory != "external":
        for a in names:
            if getattr(args, a) is not None:
                raise CliError(f"--{a.replace('_', '-')} needs --memory external")
        return None
    v = {a: (getattr(args, a) if getattr(args, a) is not None else d) for a, _, _, d, _ in _MEMORY_OPTIONS}
    kind = args.memory_model or "fixed"
    for a, applies in (("memory_latency", kind == "fixed"), ("memory_bandwidth", kind == "fixed"),
                       ("dram_clock", kind == "dram"), ("controller_cycles", kind == "dram"),
                       ("dram_part", kind == "dram")):
        if getattr(args, a) is not None and not applies:
            raise CliError(f"--{a.replace('_', '-')} does not apply to --memory-model {kind}")
    try:
        return MemoryConfig(
            index_cache=CacheShape(v["cache_size"], v["cache_line"], v["cache_ways"]),
            raw_cache=CacheShape(v["raw_cache_size"], v["cache_line"], v["cache_ways"]),
            prefetch=v["prefetch"], kind=kind, latency=v["memory_latency"], bandwidth=v["memory_bandwidth"],
            bus_bytes=v["bus_bytes"], dram_part=args.dram_part or "MT41K256M16-125", clock_mhz=v["dram_clock"],
            controller_cycles=v["controller_cycles"])
    except ValueError as e:
        raise CliError(f"--memory external: {e}") from None


#: ``--unit`` choices: the texel-fetch unit specialised to the texture set, the full one (both
#: with the set baked into ROMs), or the loadable one (a geometry; the set loaded over its bus port).
UNITS = ("specialised", "full", "loadable")


def add_unit(p, *, both: bool = False) -> None:
    """``--unit``: which texel-fetch unit the RTL is (``hw.features``); with ``both``, also the
    specialised and full units side by side. ``--geometry``: the loadable unit's geometry."""
    p.add_argument("--unit", choices=UNITS + (("both",) if both else ()), default=None,
                   help=with_default("the RTL unit: specialised (the set in ROMs, only what it needs: "
                                     "bit-exact and smaller), full (the set in ROMs, every path) or loadable "
                                     "(memories loaded over a Wishbone port: one unit for every set of its "
                                     "--geometry)" + ("; both: specialised and full side by side" if both else ""),
                                     "specialised"))
    p.add_argument("--geometry", metavar="NAME|FILE.toml", default=None,
                   help=with_default("with --unit loadable: what the unit holds, a preset (paper, dreamcast, "
                                     "max) or a geometry file (docs/hardware.md)", "the texture set's own"))


def unit_geometry(args, ts=None, where: str = ""):
    """The loadable unit's :class:`golden.geometry.Geometry` from ``--unit``/``--geometry`` (None for
    the baked units): the named or written geometry, else the set's own; one-line CliErrors for a
    ``--geometry`` without ``--unit loadable``, a bad geometry, and a set that does not fit it."""
    from vqtex.golden.geometry import Geometry, GeometryError, geometry_from
    if args.unit != "loadable":
        if args.geometry is not None:
            raise CliError(f"--geometry applies to --unit loadable (not --unit {args.unit or 'specialised'})")
        return None
    if args.geometry is None:
        if ts is None:
            raise CliError("--unit loadable needs --geometry NAME|FILE.toml (or a texture set to size it)")
        return Geometry.of(ts)
    try:
        g = geometry_from(args.geometry)
    except GeometryError as e:
        raise CliError(str(e)) from None
    if ts is not None:
        misfit = g.fits(ts)
        if misfit:
            raise CliError(f"{where or 'the texture set'} does not fit geometry {args.geometry}: " + "; ".join(misfit))
    return g


def add_index_banks(p) -> None:
    """``--index-banks``: how the texture filter's lanes hold the index memory."""
    p.add_argument("--index-banks", choices=["parity", "lane"], default=None,
                   help=with_default("the texture filter's index memory: one memory banked by block parity, "
                                     "shared by the lanes, or a copy per lane (docs/filter.md; only with the "
                                     "filter)", "parity"))


def resolve(args, name: str, default, applies: bool, why: str, option: str | None = None):
    """The option ``name`` (an ``args`` attribute whose argparse default is None, so that a given
    option is told from an absent one): a CliError ``--OPTION WHY`` when it was given but does not
    apply, else its value or ``default``. Stored back into ``args``. ``option`` is the option's
    name when it is not ``name`` with dashes."""
    value = getattr(args, name)
    if value is not None and not applies:
        raise CliError(f"{option or '--' + name.replace('_', '-')} {why}")
    value = default if value is None else value
    setattr(args, name, value)
    return value


def add_tag_width(p) -> None:
    p.add_argument("--tag-width", type=limits.TAG_WIDTH, default=8,
                   help=number_help("bits of the request tag carried to the response", limits.TAG_WIDTH, 8))


def add_sweep_options(p) -> None:
    """``--scheduler`` and ``--workers`` for commands that run a sweep of independent jobs
    (:func:`vqtex.sim.bench.sweep.run_jobs`)."""
    p.add_argument("--scheduler", metavar="ADDRESS", type=limits.SCHEDULER, default=None,
                   help=number_help("where the sweep's jobs run: the address of a running dask scheduler "
                                    "(its form checked before any work), 'serial' for this process, or none for "
                                    "a dask LocalCluster of worker processes on this machine", limits.SCHEDULER,
                                    "a LocalCluster"))
    p.add_argument("--workers", type=limits.WORKERS, default=None,
                   help=number_help("worker processes of the LocalCluster (not with --scheduler)", limits.WORKERS,
                                    "the cores this process may use"))


def sweep_options(args) -> dict:
    """``run_jobs`` keyword arguments from :func:`add_sweep_options`' options, checked: ``--workers``
    is at least 1 and only for the LocalCluster (no ``--scheduler``)."""
    if args.workers is not None and args.workers < 1:
        raise CliError(f"--workers must be at least 1, got {args.workers}")
    if args.workers is not None and args.scheduler is not None:
        raise CliError("--workers sizes the LocalCluster: it does not go with --scheduler")
    return {"scheduler": args.scheduler, "workers": args.workers, "progress": progress_enabled()}


def emit(obj: dict, as_json: bool, text: str) -> None:
    """Print ``obj`` as one JSON object (``--json``) or ``text``."""
    if as_json:
        print(json.dumps(obj, sort_keys=True))
    else:
        print(text)


def warn(message: str) -> None:
    """One line on stderr, ``vqtex: warning: ...``: the command goes on (exit 0) but the result is
    probably not what the user meant."""
    print(f"vqtex: warning: {message}", file=sys.stderr)


#: Amaranth's simulator runs the unit at about this many cycles per second (docs/simulation.md);
#: :func:`warn_slow` warns when a run would take longer than :data:`SLOW_SECONDS` at that rate.
PYSIM_CYCLES_PER_SECOND = 2e3
SLOW_SECONDS = 60


def warn_slow(backend: str, requests: int) -> None:
    """Warn (one line) when ``backend`` is pysim and ``requests`` texel requests would take more than
    :data:`SLOW_SECONDS` (about one cycle per request)."""
    seconds = requests / PYSIM_CYCLES_PER_SECOND
    if backend == "pysim" and seconds > SLOW_SECONDS:
        warn(f"pysim simulates about {PYSIM_CYCLES_PER_SECOND:.0f} cycles/s: {requests} requests take about "
             f"{seconds / 60:.0f} minutes (--backend cxxrtl takes seconds)")


def progress_enabled() -> bool:
    """Whether progress lines are shown: ``$VQTEX_PROGRESS`` (1 or 0) when set, else when stderr is a
    terminal (so logs and pipes get only results, warnings and errors)."""
    env = os.environ.get("VQTEX_PROGRESS", "").strip()
    return env == "1" if env in ("0", "1") else sys.stderr.isatty()


def progress_line(message: str) -> None:
    """``vqtex: MESSAGE`` on stderr when progress is shown: the step that starts now may be silent
    for a while."""
    if progress_enabled():
        print(f"vqtex: {message}", file=sys.stderr, flush=True)


def file_mode() -> int:
    """``0666 & ~umask``: the mode of an ordinary new file."""
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask


def _probe_writable(folder: str) -> None:
    """A CliError unless ``folder`` exists, is a folder and a file can be created in it."""
    if not os.path.exists(folder):
        raise CliError(f"output folder {folder} does not exist")
    if not os.path.isdir(folder):
        raise CliError(f"output folder {folder} is not a folder")
    try:
        with _signals_held():                   # a signal between the two calls would leave the probe
            os.rmdir(tempfile.mkdtemp(prefix=STAGING_PREFIX, dir=folder))
    except OSError as e:
        raise CliError(f"output folder {folder} is not writable ({e.strerror})") from None


def check_folder(path: str) -> str:
    """An output folder whose files need not be complete-or-absent (``report area --keep``): its
    parent must exist and be writable; created if missing. Returns it (absolute)."""
    path = os.path.abspath(path)
    if os.path.exists(path) and not os.path.isdir(path):
        raise CliError(f"output folder {path} is a file")
    if not os.path.isdir(path):
        _probe_writable(os.path.dirname(path))
        os.makedirs(path, exist_ok=True)
    _probe_writable(path)
    return path


class Outputs:
    """The files one command writes: checked at registration, staged, renamed into place together.

    Use as a context manager::

        with Outputs() as outs:
            out = outs.add(args.output, (".npy",))      # before any work
            ...                                         # the work
            np.save(outs.path(out), data)               # write the staged file
            outs.commit()                               # all files appear (also done at a clean exit)

    Leaving the block by an exception (including ``KeyboardInterrupt``) removes every staged file.
    """

    def __init__(self):
        self._staging: dict[str, str] = {}     # destination folder -> its staging folder
        self._files: dict[str, str] = {}       # final path -> staged path (files in existing folders)
        self._new_dirs: dict[str, str] = {}    # new output folder -> its staged copy
        self._committed = False

    def __enter__(self) -> "Outputs":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        try:
            if exc_type is None and not self._committed:
                self.commit()
        finally:
            with _signals_held():
                self._discard()

    def _stage_in(self, folder: str) -> str:
        if folder not in self._staging:
            _probe_writable(folder)
            with _signals_held():               # created and recorded (so removed) as one step
                self._staging[folder] = tempfile.mkdtemp(prefix=STAGING_PREFIX, dir=folder)
        return self._staging[folder]

    def folder(self, path: str) -> str:
        """Register an output folder (created if new; its parent must exist). Returns it (absolute)."""
        path = os.path.abspath(path)
        if os.path.exists(path):
            if not os.path.isdir(path):
                raise CliError(f"output folder {path} is a file")
            self._stage_in(path)
        elif path not in self._new_dirs:
            staged = os.path.join(self._stage_in(os.path.dirname(path)), os.path.basename(path))
            os.mkdir(staged)
            self._new_dirs[path] = staged
        return path

    def add(self, path: str, suffixes=None, what: str = "") -> str:
        """Register the output file ``path`` (its extension one of ``suffixes``, case-insensitive,
        when given; ``what`` names the content in that error). Returns it (absolute)."""
        if os.path.isdir(path):
            raise CliError(f"output {os.path.abspath(path)} is a folder")
        if suffixes is not None:
            ext = os.path.splitext(path)[1].lower()
            if ext not in suffixes:
                raise CliError(f"output {path}: the extension must be {' or '.join(suffixes)}"
                               f"{' for ' + what if what else ''} (not {ext or 'none'})")
        path = os.path.abspath(path)
        folder = os.path.dirname(path)
        if folder in self._new_dirs:
            staged = os.path.join(self._new_dirs[folder], os.path.basename(path))
        else:
            staged = os.path.join(self._stage_in(folder), os.path.basename(path))
            self._files[path] = staged
        return path

    def path(self, final: str) -> str:
        """Where to write the registered output ``final`` now (its staged file)."""
        final = os.path.abspath(final)
        if final in self._files:
            return self._files[final]
        folder = os.path.dirname(final)
        if folder in self._new_dirs:
            return os.path.join(self._new_dirs[folder], os.path.basename(final))
        raise KeyError(f"{final} was not registered as an output")

    def commit(self) -> None:
        """Rename every written file (and new folder) into place, the ending signals (SIGINT,
        SIGTERM, SIGHUP) held back meanwhile; a registered output that was not written is skipped."""
        with _signals_held():
            check_ended()                       # a signal whose exception was lost: nothing appears
            mode = file_mode()
            staged = list(self._files.values()) + [
                os.path.join(d, n) for d in self._new_dirs.values() for n in os.listdir(d)]
            for f in staged:
                if os.path.isfile(f):
                    os.chmod(f, mode)
            for final, staged_dir in self._new_dirs.items():
                os.rename(staged_dir, final)
            for final, f in self._files.items():
                if os.path.exists(f):
                    os.replace(f, final)
            self._committed = True

    def _discard(self) -> None:
        for staging in self._staging.values():
            shutil.rmtree(staging, ignore_errors=True)
        self._staging.clear()


def write_bytes(path: str, data: bytes) -> None:
    """Write ``data`` to ``path`` (which need not be registered: a staged path is written directly)."""
    with open(path, "wb") as f:
        f.write(data)


def write_json(path: str, obj) -> None:
    """Write ``obj`` as indented JSON to ``path``."""
    write_bytes(path, json.dumps(obj, indent=2, sort_keys=True).encode())


def is_dt(path: str) -> bool:
    """``path`` names a Dreamcast ``.dt`` texture (by its extension, any case)."""
    return str(path).lower().endswith(".dt")


def load_set(path: str):
    """The ``TextureSet`` in ``path`` (a ``.vqt``, or a ``.dt`` imported as a one-texture set in the
    PowerVR2 layout); ``golden.format.FormatError`` (one line, naming the file) if it is not a valid
    one."""
    from vqtex.golden.format import FormatError, TextureSet
    if is_dt(path):
        from vqtex.golden.pvr2.pvr import PvrError
        from vqtex.golden.pvr2.pvr_set import import_dt
        try:
            return import_dt([path])
        except PvrError as e:
            raise FormatError(str(e).strip().splitlines()[0]) from None
    try:
        return TextureSet.load(path)
    except FormatError as e:
        msg = str(e).strip()
        if str(path) in msg:
            raise
        raise FormatError(f"{path}: {msg}") from None
