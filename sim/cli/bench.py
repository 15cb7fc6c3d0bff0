"""``vqtex bench WHAT [--json]``: benchmarks that print numbers (never timed tests).

encode  -- the codebook designer against scikit-learn's KMeans (needs the ``bench`` extra)
mip     -- extended codewords: the paper's averages against joint training, per level
sim     -- simulation backends: pysim, compiled CXXRTL, Verilator (cycles per second, build times)
render  -- golden render time (uncompressed and VQ) and RTL cycles per frame, both built-in scenes
codecs  -- VQ against BC1, ASTC, JPEG 2000 and wavelet coders: bits, PSNR, encode, decode, one random texel
           (needs the ``codecs`` extra; the full run's photographs need ``bench``)
tradeoff -- encoders: time against error: GLA and TSVQ against scikit-learn's KMeans and MiniBatchKMeans
            over blocks, codebook sizes and colours; Pareto plots with --plot DIR (needs the ``bench`` extra)
skip    -- the sparse request stream against the fixed one: requests, RTL cycles and time per frame
stability -- numerical stability and hostile input: the colour matrix on every input, long streams under
           backpressure, mutated .vqt files, adversarial encoder training sets
"""

from __future__ import annotations

import importlib
import inspect
import os

from . import limits
from .common import CliError, Outputs, add_json, add_sweep_options, number_help, sweep_options, with_default

__all__ = ["add_parser"]

BENCHES = {
    "encode": "vqtex.sim.bench.encoding.encoder",
    "mip": "vqtex.sim.bench.encoding.mipmaps",
    "sim": "vqtex.sim.bench.simulators.simulation",
    "render": "vqtex.sim.bench.scenes.render",
    "skip": "vqtex.sim.bench.scenes.skip",
    "stability": "vqtex.sim.bench.robustness.stability",
    "codecs": "vqtex.sim.bench.codecs",
    "tradeoff": "vqtex.sim.bench.encoding.tradeoff",
}

#: The files ``bench tradeoff --plot DIR`` writes into DIR.
PLOTS = ("tradeoff_time.png", "tradeoff_bits.png")

#: The extra that installs what a bench needs (default ``bench``).
EXTRAS = {"codecs": "codecs"}


def _needs(what: str, e: ImportError) -> CliError:
    """The one-line error for a missing dependency: a Python package (its extra) or a system library."""
    name = e.name or "a missing module"
    top = name.split(".")[0]
    extra = {"distributed": "sweep", "matplotlib": "plot"}.get(top, EXTRAS.get(what, "bench"))
    how = "scripts/install-sim-tools" if name.startswith("lib") else f"pip install '.[{extra}]'"
    return CliError(f"bench {what} needs {name} ({how})")


def cmd_bench(args) -> int:
    try:
        mod = importlib.import_module(BENCHES[args.what])
        opts = _options(args)
        with Outputs() as outs:
            if opts.get("plot"):                # the plots appear together when the run ends well
                folder = outs.folder(opts["plot"])
                staged = [outs.path(outs.add(os.path.join(folder, n))) for n in PLOTS]
                opts["plot_into"] = os.path.dirname(staged[0])
            mod.run(json_out=args.json, **opts)
    except ImportError as e:
        if (e.name or "").split(".")[0] == "vqtex":
            raise
        raise _needs(args.what, e) from None
    return 0


def _options(args) -> dict:
    """The options of the bench ``args.what`` (its run() keywords): ``--quick`` for the benches
    whose run() takes it; the tradeoff grid's options are an error on any other bench."""
    grid_opts = ("plot", "codecs", "images", "sizes", "blocks", "threads", "scheduler", "workers")
    given = [o for o in grid_opts if getattr(args, o) is not None and getattr(args, o) is not False]
    if args.what != "tradeoff":
        if given:
            raise CliError(f"--{given[0]} is an option of 'vqtex bench tradeoff' only")
        if not args.quick:
            return {}
        if "quick" not in inspect.signature(importlib.import_module(BENCHES[args.what]).run).parameters:
            raise CliError(f"bench {args.what} has no --quick")
        return {"quick": True}
    from vqtex.sim.bench.encoding import tradeoff
    grid = dict(tradeoff.QUICK if args.quick else tradeoff.FULL)
    if args.images:
        names = tuple(args.images.split(","))
        bad = [n for n in names if n not in tradeoff.IMAGES]
        if bad:
            raise CliError(f"--images: unknown image {bad[0]!r} (one of {', '.join(tradeoff.IMAGES)})")
        grid["images"] = names
    if args.sizes:
        grid["sizes"] = args.sizes              # checked by the parser (limits.BENCH_SIZES)
    if args.blocks:
        grid["blocks"] = args.blocks            # checked by the parser (limits.BENCH_BLOCKS)
    if args.codecs:
        try:
            importlib.import_module("vqtex.sim.bench.codecs")
        except ImportError as e:
            if e.name == "vqtex.sim.bench.codecs":
                raise CliError("--codecs: this build has no codecs bench (vqtex.sim.bench.codecs)") from None
            raise
    threads = 1 if args.threads is None else (args.threads or None)
    return {"plot": args.plot, "grid": grid, "include_codecs": args.codecs, "threads": threads,
            **sweep_options(args)}


def add_parser(sub) -> None:
    b = sub.add_parser("bench", help="benchmarks that print numbers (speed and quality, not tests)")
    b.add_argument("what", choices=sorted(BENCHES),
                   help="encode: codebook design vs scikit-learn KMeans; mip: extended codewords; "
                        "sim: simulation backends' speed; render: golden render time and RTL cycles per frame; "
                        "skip: sparse against fixed request stream (requests, RTL cycles and time per frame); "
                        "codecs: VQ against BC1, ASTC, JPEG 2000 and wavelet coders; "
                        "tradeoff: encoders' time, bits and error against scikit-learn's k-means")
    b.add_argument("--quick", action="store_true",
                   help=with_default("a small run: codecs: two bundled textures, two VQ configurations, 2 repeats; "
                                     "tradeoff: one 64x64 texture, 2x2 and 4x4, k 16 and 64", "the full run"))
    add_json(b)
    t = b.add_argument_group("tradeoff options")
    t.add_argument("--plot", metavar="DIR", default=None,
                   help=with_default("write the Pareto plots tradeoff_time.png and tradeoff_bits.png into DIR "
                                     "(needs matplotlib)", "no plots"))
    t.add_argument("--codecs", action="store_true",
                   help=with_default("add the codecs' rows (BC1, JPEG 2000, wavelets) on the same images", "off"))
    t.add_argument("--images", metavar="NAMES", default=None,
                   help=with_default("comma-separated image names (docs/benchmarks.md lists them)", "the grid's"))
    t.add_argument("--sizes", metavar="K,K", type=limits.BENCH_SIZES, default=None,
                   help=number_help("codebook sizes", limits.BENCH_SIZES, "16,64,256,1024,4096"))
    t.add_argument("--blocks", metavar="WxH,WxH", type=limits.BENCH_BLOCKS, default=None,
                   help=number_help("blocks", limits.BENCH_BLOCKS, "2x2,4x4,4x2"))
    t.add_argument("--threads", type=limits.THREADS, default=None,
                   help=number_help("threads every library is held to in a job (0: the libraries' defaults)",
                                    limits.THREADS, 1))
    add_sweep_options(t)
    b.set_defaults(func=cmd_bench)
