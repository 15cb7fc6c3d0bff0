"""``vqtex bench WHAT [--json]``: benchmarks that print numbers (never timed tests).

encode  -- the codebook designer against scikit-learn's KMeans (needs the ``bench`` extra)
mip     -- extended codewords: the paper's averages against joint training, per level
sim     -- simulation backends: pysim, compiled CXXRTL, Verilator (cycles per second, build times)
render  -- golden render time (uncompressed and VQ) and RTL cycles per frame, both built-in scenes
skip    -- the sparse request stream against the fixed one: requests, RTL cycles and time per frame
codecs  -- VQ against BC1, ASTC, JPEG 2000 and wavelet coders: bits, PSNR, encode, decode, one random texel
           (needs the ``codecs`` extra; the full run's photographs need ``bench``)
stability -- numerical stability and hostile input: the colour matrix on every input, long streams under
           backpressure, mutated .vqt files, adversarial encoder training sets
"""

from __future__ import annotations

import importlib
import inspect

from .common import CliError, add_json

__all__ = ["add_parser"]

BENCHES = {
    "encode": "vqtex.sim.bench.encoder",
    "mip": "vqtex.sim.bench.mipmaps",
    "sim": "vqtex.sim.bench.simulation",
    "render": "vqtex.sim.bench.render",
    "skip": "vqtex.sim.bench.skip",
    "stability": "vqtex.sim.bench.stability",
    "codecs": "vqtex.sim.bench.codecs",
}

#: The extra that installs what a bench needs (default ``bench``).
EXTRAS = {"codecs": "codecs"}


def _needs(what: str, e: ImportError) -> CliError:
    """The one-line error for a missing dependency: a Python package (its extra) or a system library."""
    name = e.name or "a missing module"
    how = "scripts/install-sim-tools" if name.startswith("lib") else f"pip install '.[{EXTRAS.get(what, 'bench')}]'"
    return CliError(f"bench {what} needs {name} ({how})")


def cmd_bench(args) -> int:
    try:
        mod = importlib.import_module(BENCHES[args.what])
    except ImportError as e:
        raise _needs(args.what, e) from None
    kwargs = {}
    if args.quick:
        if "quick" not in inspect.signature(mod.run).parameters:
            raise CliError(f"bench {args.what} has no --quick")
        kwargs["quick"] = True
    try:
        mod.run(json_out=args.json, **kwargs)
    except ImportError as e:
        raise _needs(args.what, e) from None
    return 0


def add_parser(sub) -> None:
    b = sub.add_parser("bench", help="benchmarks that print numbers (speed and quality, not tests)")
    b.add_argument("what", choices=sorted(BENCHES),
                   help="encode: codebook design vs scikit-learn KMeans; mip: extended codewords; "
                        "sim: simulation backends' speed; render: golden render time and RTL cycles per frame; "
                        "skip: sparse against fixed request stream (requests, RTL cycles and time per frame); "
                        "codecs: VQ against BC1, ASTC, JPEG 2000 and wavelet coders")
    b.add_argument("--quick", action="store_true",
                   help="codecs: a small run (two bundled textures, two VQ configurations, 2 repeats) "
                        "instead of the full one (default off)")
    add_json(b)
    b.set_defaults(func=cmd_bench)
