"""``vqtex bench WHAT [--json]``: benchmarks that print numbers (never timed tests).

encode  -- the codebook designer against scikit-learn's KMeans (needs the ``bench`` extra)
mip     -- extended codewords: the paper's averages against joint training, per level
sim     -- simulation backends: pysim, compiled CXXRTL, Verilator (cycles per second, build times)
render  -- golden render time (uncompressed and VQ) and RTL cycles per frame, both built-in scenes
skip    -- the sparse request stream against the fixed one: requests, RTL cycles and time per frame
stability -- numerical stability and hostile input: the colour matrix on every input, long streams under
           backpressure, mutated .vqt files, adversarial encoder training sets
"""

from __future__ import annotations

import importlib

from .common import CliError, add_json

__all__ = ["add_parser"]

BENCHES = {
    "encode": "vqtex.sim.bench.encoder",
    "mip": "vqtex.sim.bench.mipmaps",
    "sim": "vqtex.sim.bench.simulation",
    "render": "vqtex.sim.bench.render",
    "skip": "vqtex.sim.bench.skip",
    "stability": "vqtex.sim.bench.stability",
}


def cmd_bench(args) -> int:
    try:
        mod = importlib.import_module(BENCHES[args.what])
    except ImportError as e:
        raise CliError(f"bench {args.what} needs {e.name} (pip install '.[bench]')") from None
    mod.run(json_out=args.json)
    return 0


def add_parser(sub) -> None:
    b = sub.add_parser("bench", help="benchmarks that print numbers (speed and quality, not tests)")
    b.add_argument("what", choices=sorted(BENCHES),
                   help="encode: codebook design vs scikit-learn KMeans; mip: extended codewords; "
                        "sim: simulation backends' speed; render: golden render time and RTL cycles per frame; "
                        "skip: sparse against fixed request stream (requests, RTL cycles and time per frame)")
    add_json(b)
    b.set_defaults(func=cmd_bench)
