"""``vqtex render`` and ``vqtex demo``: scenes rendered from compressed textures, golden and RTL.

A frame is rendered in two phases (``golden.render.frame``): its texel requests, then the frame
resolved from the texels that answer them. The golden backend answers with ``golden.fetch``; the RTL
backends (pysim, cxxrtl, verilator) answer by simulating the texel-fetch unit on the same request
stream, so "the RTL frame is identical to the golden frame" is a pixel-for-pixel comparison.
"""

from __future__ import annotations

import os
import sys
import time

import numpy as np

from . import limits
from .common import (IMAGE_SUFFIXES, CliError, Outputs, add_backend, add_hardware_options, add_index_banks, add_json, add_unit,
                     add_memory_options, emit, load_set, memory_config, number_help, progress_enabled, resolve,
                     stall_seed, unit_geometry, warn, warn_slow, with_default, write_json)

__all__ = ["add_parser", "cmd_render", "render_scene", "render_to_files", "encode_scene", "parse_frames", "parse_fovea",
           "Progress"]


class Progress:
    """A one-line progress bar on stderr (when :func:`~vqtex.sim.cli.common.progress_enabled`, or forced)."""

    def __init__(self, total: int, label: str, enabled: bool | None = None):
        self.total, self.label, self.n = max(1, total), label, 0
        self.enabled = progress_enabled() if enabled is None else enabled
        self.t0 = time.perf_counter()
        self._draw()

    def _draw(self):
        if not self.enabled:
            return
        w = 30
        fill = int(w * self.n / self.total)
        sys.stderr.write(f"\r{self.label:<22} [{'#' * fill}{'.' * (w - fill)}] {self.n}/{self.total} "
                         f"{time.perf_counter() - self.t0:6.1f}s")
        sys.stderr.flush()

    def step(self, k: int = 1):
        self.n += k
        self._draw()

    def done(self):
        if self.enabled:
            self.n = self.total
            self._draw()
            sys.stderr.write("\n")


def parse_frames(text: str | None, total: int) -> list[int]:
    """``--frames`` as a list of frame numbers of a ``total``-frame scene: a Python slice ``A:B`` or
    ``A:B:STEP`` (any part may be empty; negative numbers count from the end) or one frame number.

    A slice reaching past the last frame is clamped with a warning; one that selects no frame, a
    step of 0 or a frame number outside the scene is a CliError.
    """
    if text is None:
        return list(range(total))
    try:
        if ":" in text:
            parts = text.split(":")
            if len(parts) > 3:
                raise ValueError
            a, b, step = (int(v) if v.strip() else None for v in parts + [""] * (3 - len(parts)))
            if step == 0:
                raise CliError(f"--frames {text!r}: the step must not be 0")
            frames = list(range(total))[slice(a, b, step)]
            if frames and ((b is not None and b > total) or (a is not None and a >= total)):
                warn(f"--frames {text}: the scene has {total} frames (0..{total - 1}); "
                     f"rendering {len(frames)} of them")
        else:
            frames = [int(text)]
    except ValueError:
        raise CliError(f"--frames {text!r} is not a slice A:B[:STEP] or a frame number") from None
    if not frames or any(not 0 <= f < total for f in frames):
        raise CliError(f"--frames {text!r} selects no frame of the scene's {total}")
    return frames


def _frame_path(pattern: str, frame: int, many: bool) -> str:
    if not many:
        return pattern
    root, ext = os.path.splitext(pattern)
    return f"{root}_{frame:04d}{ext}"


def render_scene(scene, ts, frames, *, mode="trilinear", backend="golden", stall=0.0, seed=0,
                 one_port=False, reference=True, images=None, progress=None, cycle_model=False,
                 stream="sparse", fovea=None, compare_fixed=False, filter_in_rtl=False, lanes=4,
                 index_banks="parity", unit="specialised", geometry=None, memory=None):
    """Render ``frames`` of ``scene`` from TextureSet ``ts``; yields one dict per frame with the frame,
    the golden frame when the backend is RTL (for comparison), cycle results and the reference MSE.
    With the golden backend and ``cycle_model``, the cycles come from the exact cycle model (no RTL).
    ``stream`` is the sampler's request stream (``sparse`` or ``fixed``: the same frames); with a
    ``fovea`` (:class:`~vqtex.golden.render.fovea.Fovea`) the frame is foveated and ``"fovea"`` holds
    :func:`vqtex.sim.reports.foveation.compare_regions` against the unbiased frame. ``compare_fixed``
    also runs the fixed stream through the backend (the cycle model for ``golden``, which then
    reports the sparse stream's cycles too): ``"fixed"`` holds its requests, cycles and whether its
    frame is identical.
    With ``filter_in_rtl`` the backend runs the texture filter (``hw.filter.TextureFilter`` with
    ``lanes`` lanes) on the frame's per-pixel inputs (the fovea's biased level of detail included)
    instead of the texel-fetch unit on its texel requests; the result's ``filter`` is its
    :class:`~vqtex.sim.backends.filter.FilterResult`. It does not go with ``compare_fixed`` (which runs
    request streams through the texel-fetch unit); the fovea's region figures then come from the
    texel-fetch unit's exact cycle model.
    ``unit`` is the RTL texel-fetch unit (``specialised`` or ``full``); with ``geometry`` it is the
    loadable unit of that geometry (or, with ``filter_in_rtl``, the loadable texture filter, with
    ``memory`` the loadable filter through the memory system), ``ts`` loaded over its bus port
    before each frame (``"sim"``, or the filter's result, holds the load's cycles too).
    With ``memory`` (:class:`golden.memory.system.MemoryConfig`) the unit is the cached one, its
    textures in external memory (golden: its cycle model, always run; pysim, cxxrtl, verilator: its RTL); ``"sim"``
    holds its cycles and ``memory`` figures.
    A compiled backend's unit is elaborated and built (or found in the build cache) once, before the
    first frame's simulation: that frame's ``"rtl_setup_seconds"``; every frame's ``"rtl_seconds"`` is
    its own simulation."""
    unit_kw = {"specialise": unit != "full", "geometry": geometry}
    if memory is not None:
        unit_kw = {"memory": memory, "geometry": geometry}      # (geometry: the loadable cached unit)
    if filter_in_rtl and compare_fixed:
        raise ValueError("compare_fixed runs request streams through the texel-fetch unit, not the RTL filter")
    from vqtex.golden.fetch import check_requests, fetch
    from vqtex.golden.render.frame import frame_requests
    from vqtex.golden.render.metrics import frame_mse
    from vqtex.golden.render.pyramid import ReferenceSource
    from vqtex.golden.render.pyramid import VQSource
    src = VQSource(ts)
    pruned = ts.present_blocks is not None or any(t.absent_levels for t in ts.textures)
    ref_src = None
    if reference:
        if images is None:
            images = [img for img, _ in scene.load_textures()]
        ref_src = ReferenceSource(images, levels=[len(ts.level_shapes(t)) for t in range(ts.n_textures)])
    prepared = False
    for f in frames:
        out = {"frame": f}
        t0 = time.perf_counter()
        reqs, sampler = frame_requests(scene, f, src, mode, stream=stream, fovea=fovea)
        if pruned:                                      # a pruned set refuses what it does not hold
            check_requests(ts, reqs[:, 0], reqs[:, 1], reqs[:, 2], reqs[:, 3])
        golden_texels = fetch(ts, reqs[:, 0], reqs[:, 1], reqs[:, 2], reqs[:, 3])
        golden_frame = sampler.resolve(golden_texels)
        out["golden_seconds"] = time.perf_counter() - t0
        out["requests"] = int(len(reqs))
        out["pixels_textured"] = int(len(sampler.fragments))
        out["skipped"] = sampler.skipped
        out["request_stream"] = reqs                    # for the need analysis of --report
        if filter_in_rtl:
            from vqtex.sim.backends.filter import simulate_filter
            pixels = sampler.filter_inputs(sampler.fragments, sampler.frac)
            if f == frames[0]:
                warn_slow(backend, int(len(pixels["mode"]) * 8 // lanes * len(frames)))
            if not prepared:                # elaborate and build once: each frame's rtl_seconds is its simulation
                t0 = time.perf_counter()
                if memory is not None:
                    compiled = backend in ("cxxrtl", "verilator")
                    if compiled:
                        from vqtex.sim.backends.filter_memory import compiled_build
                        compiled_build(ts, memory, lanes=lanes, frac=sampler.frac, backend=backend, geometry=geometry)
                    out["rtl_setup_seconds"] = time.perf_counter() - t0 if compiled else 0.0
                else:
                    from vqtex.sim.backends.filter import prepare_filter
                    out["rtl_setup_seconds"] = prepare_filter(backend, ts, lanes=lanes, frac=sampler.frac,
                                                              index_banks=index_banks, geometry=geometry)
                prepared = True
            t0 = time.perf_counter()
            if memory is not None:          # the filter's lanes through the memory system
                from vqtex.sim.backends.filter_memory import simulate_cached_filter
                res = simulate_cached_filter(ts, pixels, memory, backend=backend, lanes=lanes, frac=sampler.frac,
                                             stall=stall, seed=seed, geometry=geometry)
            else:
                res = simulate_filter(ts, pixels, backend=backend, lanes=lanes, frac=sampler.frac, stall=stall,
                                      seed=seed, index_banks=index_banks, geometry=geometry)
            out["rtl_seconds"] = time.perf_counter() - t0
            out["image"] = sampler.place(res.colors)
            out["identical_to_golden"] = bool(np.array_equal(out["image"], golden_frame))
            out["filter"] = res
        elif backend == "golden":
            out["image"] = golden_frame
            if (cycle_model or compare_fixed or memory is not None) and len(reqs):
                from vqtex.sim.backends import simulate
                out["sim"] = simulate(ts, reqs, backend="golden", stall=stall, seed=seed, one_port=one_port,
                                      memory=memory, geometry=geometry if memory is not None else None)
                out["rtl_seconds"] = 0.0
        else:
            from vqtex.sim.backends import simulate
            if f == frames[0]:
                warn_slow(backend, len(reqs) * len(frames))
            if not prepared and len(reqs):
                from vqtex.sim.backends.interface import prepare
                out["rtl_setup_seconds"] = prepare(ts, backend=backend, one_port=one_port, **unit_kw)
                prepared = True
            t0 = time.perf_counter()
            res = (simulate(ts, reqs, backend=backend, stall=stall, seed=seed, one_port=one_port, **unit_kw)
                   if len(reqs) else None)
            out["rtl_seconds"] = time.perf_counter() - t0
            out["image"] = sampler.resolve(res.responses) if res is not None else golden_frame
            out["identical_to_golden"] = bool(np.array_equal(out["image"], golden_frame))
            out["sim"] = res
        if ref_src is not None:
            ref = sampler.resolve(ref_src.fetch(reqs[:, 0], reqs[:, 1], reqs[:, 2], reqs[:, 3]))
            out["mse"] = frame_mse(out["image"], ref)
            out["reference"] = ref
        if compare_fixed:
            from vqtex.sim.backends import simulate
            freqs, fsampler = frame_requests(scene, f, src, mode, stream="fixed", fovea=fovea)
            fres = (simulate(ts, freqs, backend=backend, stall=stall, seed=seed, one_port=one_port, **unit_kw)
                    if len(freqs) else None)
            fimg = fsampler.resolve(fres.responses) if fres is not None else out["image"]
            out["fixed"] = {"requests": int(len(freqs)), "cycles": int(fres.cycles) if fres is not None else 0,
                            "identical": bool(np.array_equal(fimg, out["image"]))}
        if fovea is not None:
            from vqtex.sim.reports.foveation import compare_regions
            ureqs, usampler = frame_requests(scene, f, src, mode, stream=stream)
            if pruned:
                check_requests(ts, ureqs[:, 0], ureqs[:, 1], ureqs[:, 2], ureqs[:, 3])
            uframe = usampler.resolve(fetch(ts, ureqs[:, 0], ureqs[:, 1], ureqs[:, 2], ureqs[:, 3]))
            out["fovea"] = compare_regions(ts, fovea, (reqs, sampler, golden_frame), (ureqs, usampler, uframe), f,
                                           backend="golden" if filter_in_rtl else backend, stall=stall, seed=seed,
                                           one_port=one_port)
        if progress:
            progress.step()
        yield out


def encode_scene(scene, images):
    """The scene's texture set, encoded with its settings (a progress line while it runs)."""
    from vqtex.golden.render.scene import build_texture_set
    p = Progress(1, "encoding textures")
    ts = build_texture_set(scene, images)
    p.step()
    p.done()
    return ts


def render_to_files(scene, ts, frames, path_of, images, *, backend, outs, on_frame=None, **kw):
    """Render ``frames``; frame ``f`` goes to the registered output ``path_of(f)`` of ``outs`` (an
    :class:`~vqtex.sim.cli.common.Outputs`, so it appears with the rest of the command's files), then
    ``on_frame(r)`` sees the frame's dict from :func:`render_scene` (to write more files).
    Returns (per-frame reports, frames whose RTL image differs from the golden one)."""
    from vqtex.golden.render.imageio import write_image
    prog = Progress(len(frames), f"rendering ({backend})")
    per_frame, mismatches = [], []
    for r in render_scene(scene, ts, frames, backend=backend, images=images, progress=prog, **kw):
        path = path_of(r["frame"])
        write_image(outs.path(path), r["image"])
        rep = _frame_report(r)
        rep["output"] = path
        if on_frame is not None:
            rep.update(on_frame(r) or {})
        per_frame.append(rep)
        if r.get("identical_to_golden") is False:
            mismatches.append(r["frame"])
    prog.done()
    return per_frame, mismatches


def _extra_outputs(args, outs, frames):
    """``--reference`` and ``--diff``: their per-frame paths registered in ``outs``, and the
    ``on_frame`` callback that writes them (None when neither is asked for)."""
    many = len(frames) > 1
    paths = {}
    for opt in ("reference", "diff"):
        pattern = getattr(args, opt)
        if pattern:
            outs.add(pattern, IMAGE_SUFFIXES if opt == "reference" else (".png",), f"--{opt}")
            paths[opt] = {f: outs.add(_frame_path(pattern, f, many)) for f in frames}
    if not paths:
        return None
    if "diff" in paths:
        from vqtex.sim.reports.plotting import require
        require()                                       # matplotlib, before any work

    def write(r):
        from vqtex.golden.render.imageio import write_image
        from vqtex.sim.reports.plotting import save_difference_plot
        from vqtex.sim.reports.quality import difference
        done = {}
        if "reference" in paths:
            done["reference"] = paths["reference"][r["frame"]]
            write_image(outs.path(done["reference"]), r["reference"])
        if "diff" in paths:
            diff = difference(r["image"], r["reference"])
            done["diff"] = paths["diff"][r["frame"]]
            done["diff_max"] = int(diff.max())
            save_difference_plot(diff, outs.path(done["diff"]), vmax=args.diff_scale,
                                 title=f"{args.scene} frame {r['frame']}: compressed vs uncompressed, "
                                       f"MSE {r['mse']:.3f}, largest difference {int(diff.max())}")
        return done
    return write


class _NeedReport:
    """``--report``'s need analysis (``golden.need.analysis``), fed each frame's requests as it is rendered;
    each frame's report gets its figures under ``need``."""

    def __init__(self, ts, then=None):
        from vqtex.golden.need.analysis import NeedCounter
        self.counter, self.then = NeedCounter(ts), then

    def on_frame(self, r):
        done = dict(self.then(r) or {}) if self.then else {}
        done["need"] = self.counter.add(r["frame"], r["request_stream"]).to_dict()
        return done


def _frame_report(r: dict) -> dict:
    d = {"frame": r["frame"], "requests": r["requests"], "golden_seconds": round(r["golden_seconds"], 4)}
    if "pixels_textured" in r:
        d["pixels_textured"] = r["pixels_textured"]
    if "skipped" in r:
        k = r["skipped"]
        d.update(requests_fixed=k.fixed, skipped_zero_weight=k.zero_weight, skipped_repeats=k.repeats)
    if "fovea" in r:
        d["fovea"] = r["fovea"]
    if "fixed" in r:
        d["fixed_stream"] = r["fixed"]
    if "mse" in r:
        d["mse"] = round(float(r["mse"]), 4)
    if "rtl_setup_seconds" in r:            # (the first RTL frame: elaborating and building the unit, once)
        d["rtl_setup_seconds"] = round(r["rtl_setup_seconds"], 4)
    if "filter" in r:
        s = r["filter"]
        d.update(rtl_seconds=round(r["rtl_seconds"], 4), pixels=int(s.pixels), cycles=int(s.cycles),
                 pixels_per_clock=round(s.pixels_per_clock, 4), lanes=int(s.lanes), latency=int(s.latency),
                 texels_fetched=int(s.texels), stall_cycles={k: int(v) for k, v in s.stall_cycles.items()},
                 bank_conflicts=int(s.bank_conflicts), identical_to_golden=r["identical_to_golden"])
        if s.memory is not None:            # (JSON: the AR cycles are for the tests)
            d["memory"] = {k: v for k, v in s.memory.items() if k != "ar"}
        if s.load_cycles is not None:
            d["load_cycles"] = int(s.load_cycles)
    if "sim" in r and r["sim"] is not None:
        s = r["sim"]
        d.update(rtl_seconds=round(r["rtl_seconds"], 4), cycles=int(s.cycles), latency=int(s.latency),
                 straddling_index_reads=int(s.straddles),
                 stall_cycles={k: int(v) for k, v in s.stall_cycles.items()})
        if s.load_cycles is not None:
            d["load_cycles"] = int(s.load_cycles)
        if s.memory is not None:
            d["memory"] = s.memory
        if "identical_to_golden" in r:
            d["identical_to_golden"] = r["identical_to_golden"]
    return d


def cmd_render(args) -> int:
    from vqtex.golden.render.scene import load_scene
    with Outputs() as outs:
        outs.add(args.output, IMAGE_SUFFIXES, "a frame")
        report_path = outs.add(args.report, (".json",), "the report") if args.report else None
        scene = load_scene(args.scene)
        frames = parse_frames(args.frames, scene.frames)
        fovea = parse_fovea(args, scene)
        if args.compare_fixed and args.requests == "fixed":
            raise CliError("--compare-fixed compares the sparse stream with the fixed one: it needs --requests sparse")
        if args.filter_in_rtl and args.one_port:
            raise CliError("--filter-in-rtl: the filter's lanes have two-bank index memories (no --one-port)")
        if args.filter_in_rtl and args.compare_fixed:
            raise CliError("--compare-fixed runs request streams through the texel-fetch unit: it does not go with "
                           "--filter-in-rtl (the filter takes per-pixel inputs, not requests)")
        if args.filter_in_rtl and args.encode_needed:
            raise CliError("--filter-in-rtl fetches every texel of a footprint, zero weights too: it does not go "
                           "with --encode-needed (a pruned texture set)")
        memory = memory_config(args)
        if memory is not None and args.filter_in_rtl:
            bad = [opt for opt, on in (("--fovea", fovea is not None), ("--index-banks", args.index_banks is not None),
                                       (f"--unit {args.unit}", args.unit not in (None, "loadable"))) if on]
            if bad:
                raise CliError(f"--filter-in-rtl --memory external: the filter's lanes read through their own caches, "
                               f"not with {bad[0]}")
        elif memory is not None:
            bad = [opt for opt, on in (("--filter-in-rtl", args.filter_in_rtl), ("--compare-fixed", args.compare_fixed),
                                       ("--fovea", fovea is not None), ("--one-port", args.one_port),
                                       (f"--unit {args.unit}", args.unit not in (None, "loadable"))) if on]
            if bad:
                raise CliError(f"--memory external renders with the cached texel-fetch unit: not with {bad[0]}")
        _options_that_apply(args, fovea, memory is not None)
        frame_paths = {f: _frame_path(args.output, f, len(frames) > 1) for f in frames}
        for path in frame_paths.values():
            outs.add(path)
        on_frame = _extra_outputs(args, outs, frames)
        images = [img for img, _ in scene.load_textures()]
        if args.encode_needed and args.texture_set:
            raise CliError("--encode-needed encodes the scene's textures: it does not go with --texture-set")
        if args.encode_needed and (args.requests != "sparse" or args.compare_fixed or fovea is not None):
            raise CliError("--encode-needed encodes what the sparse, unbiased stream needs: it does not go with "
                           "--requests fixed, --compare-fixed or --fovea")
        if args.encode_needed:
            from vqtex.golden.need.prune import encode_needed
            ts = encode_needed(scene, frames, args.mode, images, train=args.train_on)[0]
        else:
            ts = load_set(args.texture_set) if args.texture_set else encode_scene(scene, images)
        if ts.n_textures != len(scene.textures):
            raise CliError(f"{args.texture_set} holds {ts.n_textures} textures, the scene uses {len(scene.textures)}")
        if args.filter_in_rtl and (ts.present_blocks is not None or any(t.absent_levels for t in ts.textures)):
            raise CliError(f"--filter-in-rtl fetches every texel of a footprint, zero weights too: {args.texture_set} "
                           "is pruned (vqtex prune); use an unpruned set")
        resolve(args, "unit", "specialised", args.backend != "golden" or (memory is not None and args.unit == "loadable"),
                "chooses the RTL unit: it needs an RTL --backend (pysim, cxxrtl, verilator)")
        if args.filter_in_rtl and args.unit == "full":
            raise CliError("--filter-in-rtl: the filter's lanes are specialised or loadable (no --unit full)")
        geometry = unit_geometry(args, ts, args.texture_set or f"{scene.name}'s texture set")
        if geometry is not None and args.filter_in_rtl and args.index_banks != "lane":
            raise CliError("--filter-in-rtl --unit loadable keeps a copy of the memories per lane: --index-banks lane")
        need = _NeedReport(ts, on_frame) if report_path else None
        if need is not None:
            on_frame = need.on_frame
        per_frame, mismatches = render_to_files(
            scene, ts, frames, frame_paths.get, images, outs=outs, on_frame=on_frame,
            mode=args.mode, backend=args.backend, stall=args.stall, seed=args.seed, one_port=args.one_port,
            stream=args.requests, fovea=fovea, compare_fixed=args.compare_fixed,
            filter_in_rtl=args.filter_in_rtl, lanes=args.lanes, index_banks=args.index_banks,
            unit=args.unit, geometry=geometry, memory=memory)
        report = {
            "scene": scene.name, "mode": args.mode, "backend": args.backend, "frames": per_frame,
            "overall_rate": round(ts.rates()["overall"], 4),
            "mean_mse": round(float(np.mean([f["mse"] for f in per_frame])), 4),
            "request_stream": args.requests,
            "requests_per_frame": round(float(np.mean([f["requests"] for f in per_frame])), 1),
            "fixed_requests_per_frame": round(float(np.mean([f["requests_fixed"] for f in per_frame])), 1),
        }
        report["unit"] = args.unit
        if geometry is not None:
            report["geometry"] = geometry.to_dict()
        if args.filter_in_rtl:
            report["filter_in_rtl"] = True
            report["lanes"] = args.lanes
            report["index_banks"] = args.index_banks
        if args.backend != "golden" or args.filter_in_rtl:
            report["identical_to_golden"] = not mismatches
            report["cycles_per_frame"] = round(float(np.mean([f["cycles"] for f in per_frame])), 1)
        if memory is not None:
            report["cycles_per_frame"] = round(float(np.mean([f.get("cycles", 0) for f in per_frame])), 1)
            report["memory"] = (_filter_memory_summary(memory, per_frame) if args.filter_in_rtl
                                else memory_summary(memory, per_frame))
        stream_mismatches = []
        if args.compare_fixed:
            report["cycles_per_frame"] = round(float(np.mean([f.get("cycles", 0) for f in per_frame])), 1)
            report["fixed_cycles_per_frame"] = round(float(np.mean([f["fixed_stream"]["cycles"] for f in per_frame])), 1)
            stream_mismatches = [f["frame"] for f in per_frame if not f["fixed_stream"]["identical"]]
            report["identical_to_fixed_stream"] = not stream_mismatches
        if fovea is not None:
            from vqtex.sim.reports.foveation import summarize
            report["fovea"] = dict(fovea.as_dict(), **summarize([f["fovea"] for f in per_frame]))
        if args.filter_in_rtl:
            pixels, cycles = sum(f["pixels"] for f in per_frame), sum(f["cycles"] for f in per_frame)
            report["pixels_per_clock"] = round(pixels / cycles, 4) if cycles else 0.0
        if report_path:
            report["need"] = need.counter.result().summary(per_frame=False)
            write_json(outs.path(report_path), report)
    text = [f"{scene.name}: {len(frames)} frame(s), {args.mode}, backend {args.backend}, "
            f"overall compression {report['overall_rate']:.2f}:1, mean frame MSE {report['mean_mse']:.3f}"]
    text.append(_requests_line(report))
    if args.filter_in_rtl:
        stalls = {k: sum(f["stall_cycles"][k] for f in per_frame) for k in per_frame[0]["stall_cycles"]}
        text.append(f"texture filter in the RTL ({args.lanes} lane{'s' if args.lanes > 1 else ''}), frames identical "
                    f"to golden: {'yes' if not mismatches else 'NO, frames ' + str(mismatches)}; "
                    f"{report['cycles_per_frame']:.0f} cycles per frame, {report['pixels_per_clock']:.3f} pixels "
                    f"per clock; stall cycles: " + ", ".join(f"{k} {v}" for k, v in stalls.items())
                    + ("; the index map and raw levels in external memory, a cache per lane" if memory is not None else
                       f"; index memory {'banked by block parity' if args.index_banks == 'parity' else 'per lane'}, "
                       f"bank conflicts: {sum(f['bank_conflicts'] for f in per_frame)}"))
    elif args.backend != "golden":
        text.append(f"RTL frames identical to golden: {'yes' if not mismatches else 'NO, frames ' + str(mismatches)}; "
                    f"{report['cycles_per_frame']:.0f} cycles per frame")
    loads = [f["load_cycles"] for f in per_frame if f.get("load_cycles") is not None]
    if loads:
        text.append(f"loadable unit: the set loaded over its bus in {loads[0]:,} cycles before each frame's requests")
    if memory is not None and args.filter_in_rtl:
        m = report["memory"]
        text.append(f"external memory ({m['configuration']}), a cache per lane: {m['bytes_per_pixel']:.4f} bytes read "
                    f"per pixel" + (f", hit rates index {_pct(m['hit_rate']['index'])}, raw {_pct(m['hit_rate']['raw'])}"
                                    if "hit_rate" in m else "")
                    + f"; the on-chip filter: {m['on_chip_pixels_per_clock']:.3f} pixels per clock")
    elif memory is not None:
        text.append(memory_line(report))
    if args.compare_fixed:
        text.append(f"fixed stream: {report['fixed_requests_per_frame']:,.0f} requests and "
                    f"{report['fixed_cycles_per_frame']:,.0f} cycles per frame; sparse: "
                    f"{report['requests_per_frame']:,.0f} and {report['cycles_per_frame']:,.0f} "
                    f"({'cycle model' if args.backend == 'golden' else args.backend}); frames identical: "
                    f"{'yes' if not stream_mismatches else 'NO, frames ' + str(stream_mismatches)}")
    if fovea is not None:
        from vqtex.sim.reports.foveation import summary_lines
        text += summary_lines(report["fovea"])
    emit(report, args.json, "\n".join(text))
    if mismatches:
        raise CliError(f"RTL frames {mismatches} differ from the golden frames")
    if stream_mismatches:
        raise CliError(f"frames {stream_mismatches} of the fixed stream differ from the sparse stream's")
    return 0


def _pct(v) -> str:
    return "-" if v is None else f"{100 * v:.2f}%"


def memory_line(report) -> str:
    """The external memory's line of a render (or demo) summary, from ``report["memory"]``
    (:func:`memory_summary`) and ``report["cycles_per_frame"]``."""
    m = report["memory"]
    return (f"external memory ({m['configuration']}): {report['cycles_per_frame']:,.0f} cycles per frame, "
            f"{m['bytes_per_texel']:.4f} bytes read per texel, {m['bytes_per_pixel']:.4f} per pixel, "
            f"hit rates index {_pct(m['hit_rate']['index'])}, raw {_pct(m['hit_rate']['raw'])}"
            + (f", {m['of_zero_latency']:.3f} of the zero-latency texels per clock" if "of_zero_latency" in m
               else ""))


def memory_summary(memory, per_frame) -> dict:
    """The external memory's figures over the frames: bytes per texel and per textured pixel, hit
    rates (over all references), cycles against zero latency (golden)."""
    frames = [f for f in per_frame if "memory" in f]
    refs = {k: sum(f["memory"]["references"][k] for f in frames) for k in ("index", "raw")}
    misses = {k: sum(f["memory"]["misses"][k] for f in frames) for k in ("index", "raw")}
    nbytes = sum(sum(f["memory"]["memory_bytes"].values()) for f in frames)
    texels = sum(f["requests"] for f in frames)
    pixels = sum(f.get("pixels_textured", 0) for f in frames)
    out = {"configuration": frames[0]["memory"]["configuration"] if frames else memory.describe(),
           "bytes": nbytes, "bytes_per_texel": nbytes / texels if texels else 0.0,
           "bytes_per_pixel": nbytes / pixels if pixels else 0.0,
           "hit_rate": {k: (1 - misses[k] / refs[k]) if refs[k] else None for k in refs}}
    if frames and "zero_latency_cycles" in frames[0]["memory"]:
        zero = sum(f["memory"]["zero_latency_cycles"] for f in frames)
        out["of_zero_latency"] = zero / sum(f["cycles"] for f in frames)
    return out


def _filter_memory_summary(memory, per_frame) -> dict:
    """The filter's external-memory figures over the frames: bytes per pixel, hit rates (golden),
    the on-chip filter's pixels per clock on the same pixels (``groups + hw.filter.LATENCY`` cycles a frame)."""
    from vqtex.hw.filter import LATENCY
    nbytes = sum(sum(f["memory"]["memory_bytes"].values()) for f in per_frame)
    pixels = sum(f["pixels"] for f in per_frame)
    on_chip = sum(f["texels_fetched"] // f["lanes"] + LATENCY for f in per_frame if f["pixels"])
    out = {"configuration": memory.describe(), "bytes": nbytes, "bytes_per_pixel": nbytes / pixels if pixels else 0.0,
           "on_chip_pixels_per_clock": pixels / on_chip if on_chip else 0.0}
    if all("references" in f["memory"] for f in per_frame):
        refs = {k: sum(f["memory"]["references"][k] for f in per_frame) for k in ("index", "raw")}
        hits = {k: sum(round(f["memory"]["hit_rate"][k] * f["memory"]["references"][k])
                       for f in per_frame if f["memory"]["references"][k]) for k in refs}
        out["hit_rate"] = {k: hits[k] / refs[k] if refs[k] else None for k in refs}
    return out


def _options_that_apply(args, fovea, memory: bool = False) -> None:
    """Refuse an option given where it changes nothing, whatever its value (their argparse defaults
    are None), then fill in the defaults: ``--lanes`` and ``--index-banks`` need ``--filter-in-rtl``;
    ``--train-on`` needs ``--encode-needed``; ``--diff-scale`` needs ``--diff``; ``--stall`` above 0,
    ``--stall-seed`` and ``--one-port`` need something that runs the unit's cycles (an RTL backend,
    ``--compare-fixed`` or ``--fovea``; ``--filter-in-rtl`` for ``--stall``)."""
    filt = args.filter_in_rtl
    resolve(args, "lanes", 4, filt, "is the RTL filter's lanes: it needs --filter-in-rtl")
    resolve(args, "index_banks", "lane" if args.unit == "loadable" else "parity", filt,
            "is how the RTL filter's lanes hold the index memory: it needs --filter-in-rtl")
    resolve(args, "train_on", "levels", args.encode_needed, "goes with --encode-needed")
    resolve(args, "diff_scale", 32, bool(args.diff), "is the top of the --diff heat map: it needs --diff")
    cycles = args.backend != "golden" or args.compare_fixed or fovea is not None or memory
    args.seed = stall_seed(args, stall_applies=bool(cycles or filt))
    if args.one_port and not cycles:
        raise CliError("--one-port does not apply: nothing runs the unit's cycles here (an RTL backend, "
                       "--compare-fixed or --fovea does)")


def _requests_line(report: dict) -> str:
    n, fixed = report["requests_per_frame"], report["fixed_requests_per_frame"]
    saved = f", {100 * (1 - n / fixed):.1f}% fewer than the fixed stream's {fixed:,.0f}" if fixed and n != fixed else ""
    return f"{report['request_stream']} request stream: {n:,.0f} requests per frame{saved}"


def parse_fovea(args, scene):
    """``--fovea X,Y`` with ``--fovea-radius`` (default a quarter of the frame's smaller side) and
    ``--fovea-falloff`` as a :class:`~vqtex.golden.render.fovea.Fovea`, or None; a CliError when
    they are malformed, given without ``--fovea`` or with point sampling (no level to bias)."""
    from vqtex.golden.render.fovea import Fovea, parse_gaze
    if args.fovea is None:
        for opt in ("fovea_radius", "fovea_falloff"):
            if getattr(args, opt) is not None:
                raise CliError(f"--{opt.replace('_', '-')} needs --fovea X,Y")
        return None
    if args.mode == "point":
        raise CliError("--fovea biases the level of detail: it needs --mode bilinear or trilinear")
    try:
        x, y = parse_gaze(args.fovea)
        radius = min(scene.width, scene.height) / 4 if args.fovea_radius is None else args.fovea_radius
        falloff = 1.0 if args.fovea_falloff is None else args.fovea_falloff
        return Fovea(x, y, float(radius), float(falloff))
    except ValueError as e:
        raise CliError(f"--fovea: {e}") from None


def add_parser(sub) -> None:
    r = sub.add_parser("render", help="render a scene (TOML file or built-in name) from compressed textures")
    r.add_argument("scene", help="scene file (docs/rendering.md) or built-in scene name (topspin, town)")
    r.add_argument("-o", "--output", required=True,
                   help="image to write (.png, ...); with several frames _NNNN is added before the extension")
    r.add_argument("--frames", help=with_default("frames to render: a Python slice A:B[:STEP] or one frame number",
                                                 "all"))
    r.add_argument("--mode", choices=["point", "bilinear", "trilinear"], default="trilinear",
                   help=with_default("point sampling of level 0, bilinear filtering of the finer mip level, "
                                     "or trilinear mipmapping", "trilinear"))
    add_backend(r, ["golden", "pysim", "cxxrtl", "verilator"], "golden")
    r.add_argument("--requests", choices=["sparse", "fixed"], default="sparse",
                   help=with_default("request stream: sparse leaves out texels of zero filter weight and repeats "
                                     "of a texel in one pixel's footprint; fixed issues every pixel's whole "
                                     "footprint (4 per pixel in bilinear, 8 in trilinear). The frames are identical "
                                     "(docs/skipping.md)", "sparse"))
    r.add_argument("--compare-fixed", action="store_true",
                   help="also run the fixed stream through the backend (the exact cycle model for golden) and "
                        "report its requests and cycles beside the sparse stream's; its frames must be identical "
                        "(default off)")
    r.add_argument("--fovea", metavar="X,Y",
                   help=with_default("foveate: bias the level of detail up with the distance from this gaze "
                                     "point (pixels from the top-left corner; --fovea=-X,Y when X is negative), 0 inside --fovea-radius; the report "
                                     "compares fovea and periphery with the unbiased frame (docs/skipping.md)",
                                     "no foveation"))
    r.add_argument("--fovea-radius", type=limits.FOVEA_RADIUS, metavar="R",
                   help=number_help("radius of the fovea: inside it frames are unchanged", limits.FOVEA_RADIUS,
                                    "a quarter of the frame's smaller side"))
    r.add_argument("--fovea-falloff", type=limits.FOVEA_FALLOFF, metavar="F",
                   help=number_help("levels of bias per radius of distance beyond the fovea's edge",
                                    limits.FOVEA_FALLOFF, 1.0))
    r.add_argument("--texture-set", metavar="FILE.vqt",
                   help=with_default("use this texture set instead of encoding the scene's textures",
                                     "encode them with the scene's settings"))
    r.add_argument("--encode-needed", action="store_true",
                   help="encode only what the rendered frames need (their levels; codebooks trained on those, "
                        "then pruned: golden.need.prune.encode_needed; default: encode everything)")
    r.add_argument("--train-on", choices=["levels", "blocks"], default=None,
                   help=with_default("with --encode-needed: train the codebooks on every block of the touched level "
                                     "groups, or on the touched blocks only", "levels"))
    add_hardware_options(r)
    add_unit(r)
    add_memory_options(r)
    r.add_argument("--filter-in-rtl", action="store_true",
                   help="run the texture filter in the RTL (hw.filter: per-pixel (s, t, lod) in, filtered colour "
                        "out) instead of the texel-fetch unit with the filtering in numpy (default: off)")
    r.add_argument("--lanes", type=int, choices=[1, 2, 4, 8], default=None,
                   help=with_default("texel-fetch lanes of the RTL filter (--filter-in-rtl): texels per clock", 4))
    add_index_banks(r)
    r.add_argument("--report", metavar="REPORT.json", help=with_default("also write the JSON report here", "none"))
    r.add_argument("--reference", metavar="REF.png",
                   help=with_default("also write the frame rendered from the uncompressed textures "
                                     "(_NNNN added like -o)", "none"))
    r.add_argument("--diff", metavar="DIFF.png",
                   help=with_default("also write the difference from the uncompressed frame as a heat map with "
                                     "its colour scale (needs the plot extra; _NNNN added like -o)", "none"))
    r.add_argument("--diff-scale", type=limits.DIFF_SCALE, default=None,
                   help=number_help("with --diff, the heat map's top: differences of this many levels or more "
                                    "saturate", limits.DIFF_SCALE, 32))
    add_json(r)
    r.set_defaults(func=cmd_render)
