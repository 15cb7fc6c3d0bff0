"""``vqtex bench stability [--json]``: the stress figures in one command (docs/stability.md).

- ``color``: every (Y, U, V) through the compiled RTL colour matrix against golden, for each matrix
  the project ships, the widest one the unit takes and one random parameterisation
  (:mod:`vqtex.sim.backends.color_sweep`): inputs checked, mismatches, golden's worst error against
  float64 and its bound, clamped outputs, build and sweep seconds.
- ``container``: 100,000 mutated ``.vqt`` files (checksum recomputed) loaded and used as ``info`` and
  ``decode`` use them (:mod:`.fuzz`): counts by outcome (rejected, accepted, crash, hang, big-alloc).
- ``load``: long random request streams through ``vqtex sim`` on the compiled backend against golden
  (:mod:`.load`): 1e7 requests with 30% backpressure on the default unit, 1e6 one-port requests with
  20% backpressure on a set with 12-bit indices; mismatches, cycles, seconds and peak memory.
- ``encoder``: adversarial training sets through the encoder (:mod:`.encoder_stress`): cases, blocks
  whose stored index was checked against the exact nearest codeword, disagreements, non-finite
  values, codewords outside the data's range, wrong cell sums, one- against two-thread encodes.

The figures are measured, never asserted here; the tests assert the same properties on the same code.
"""

from __future__ import annotations

import json
import time

__all__ = ["run", "SECTIONS"]


def color_figures(seed: int = 1) -> dict:
    from vqtex.golden.color import DREAMCAST_YUV422, JFIF_BT601
    from vqtex.sim.backends.color_sweep import extreme_matrix, random_matrix, sweep
    out = {}
    for name, matrix in (("jfif_bt601", JFIF_BT601), ("dreamcast_yuv422", DREAMCAST_YUV422),
                         ("extreme", extreme_matrix()), (f"random_seed_{seed}", random_matrix(seed))):
        out[name] = sweep(matrix)
    return out


def load_figures(n: int = 10_000_000, n_one_port: int = 1_000_000) -> dict:
    from vqtex.sim.reports.synth.texture_sets import four_texture_set
    from .load import load_check
    return {"backpressure_30pct": load_check(n, stall=0.3, seed=5),
            "one_port_20pct": load_check(n_one_port, stall=0.2, one_port=True, seed=6, ts=four_texture_set())}


def container_figures(n: int = 100_000, seed: int = 0) -> dict:
    from .fuzz import run_mutations
    return run_mutations(n, seed=seed)


def encoder_figures() -> dict:
    from .encoder_stress import run_cases
    return run_cases()


#: Section name -> function returning its figures.
SECTIONS = {"container": container_figures, "color": color_figures, "load": load_figures,
            "encoder": encoder_figures}


def _text(rep: dict) -> str:
    lines = []
    if "container" in rep:
        c = rep["container"]
        lines.append(f"container {c['mutations']} mutated files in {c['seconds']} s: "
                     + ", ".join(f"{k} {v}" for k, v in c["counts"].items()))
    for name, r in rep.get("color", {}).items():
        lines.append(f"color {name:<20} {r['inputs']} inputs, {r['mismatches']} mismatches; golden vs float64 "
                     f"{r['worst_error']} (bound {r['error_bound']}); build {r['build_seconds']} s, sweep {r['sweep_seconds']} s")
    for name, r in rep.get("load", {}).items():
        lines.append(f"load  {name:<20} {r['requests']} requests, {r['cycles']} cycles, {r['mismatches']} mismatches; "
                     f"seconds {r['seconds']}, peak MiB {r['peak_mib']}")
    if "encoder" in rep:
        r = rep["encoder"]
        lines.append(f"encoder {r['cases']} cases, {r['blocks_checked']} blocks checked, "
                     f"{r['disagreements']} disagreements, {r['nan']} NaN/inf, "
                     f"{r['outside_range']} codewords out of range, {r['wrong_sums']} wrong sums, "
                     f"{r['threads_differ']} of {r['threads_compared']} differ on 1/2 threads; "
                     f"{r['seconds']} s")
    lines.append(f"total {rep['seconds']} s")
    return "\n".join(lines)


def run(json_out: bool = False, sections=None) -> dict:
    """Run every section (or those named), print a summary (or one JSON object), return the figures."""
    t0 = time.perf_counter()
    rep = {name: SECTIONS[name]() for name in (sections or SECTIONS)}
    rep["seconds"] = round(time.perf_counter() - t0, 1)
    print(json.dumps(rep, sort_keys=True) if json_out else _text(rep))
    return rep


if __name__ == "__main__":
    import sys
    run(json_out="--json" in sys.argv)
