"""Verilog of the texel-fetch unit holding one texture set's memories (``vqtex export``).

The top module (default name ``texel_fetch``) wraps ``hw.texel_fetch.TexelFetch`` so that every
stream member is a port of its own instead of a packed payload vector::

    clk, rst
    i_valid, i_ready, i_texture, i_level, i_i, i_j, i_tag          request stream
    o_valid, o_ready, o_r, o_g, o_b, o_a, o_tag                     response stream
    straddle, stall_one_port, stall_output, valid                   observability strobes
                                         (valid[k]: register hw.texel_fetch.REGISTERS[k])

``rst`` is synchronous and active high (Amaranth's ``sync`` domain); ``i_ready`` and ``o_valid``
come from flip-flops (no combinational path from ``o_ready``). The memories (descriptor table,
even/odd index banks, codebook, raw texels, each in 512-word banks ``bank0``, ``bank1``, ...) are
initialised the way Amaranth/Yosys write them: one ``initial begin mem[k] = ...; end``
block per memory in the module that owns it. Verilator, Icarus Verilog and FPGA synthesis tools
(Yosys, Vivado, Quartus) all accept this for ROMs, and the file stands alone (no ``$readmemh``
side files whose paths would have to be right at simulation time). The other constructs a
simulator-minded reader might notice are Yosys's: ``reg x = value;`` register initial values, and
(``--dialect v2005`` only) a constant ``$auto$verilog_backend...`` trigger register in some ``always
@*`` blocks (an empty ``if`` that synthesis removes). There are no system tasks, delays or assertions.
"""

from __future__ import annotations

from .design import FILTER_TOP_NAME, TOP_NAME, FilterTop, TexelFetchTop, port_map, response_ports
from .yosys import fragment_rtlil, rtlil_script, run_yosys

#: The Yosys script of the sv dialect: amaranth.back.verilog's own (amaranth 0.5, internal attributes
#: stripped) with the processes turned into multiplexers (``proc`` without ``-nomux``) and each
#: register's enable and synchronous reset folded into its flip-flop (``opt_clean; opt_dff``), written
#: with ``write_verilog -sv -noparallelcase``. So every register is one ``always_ff`` block (``if (rst)
#: q <= 0; else if (en) q <= d;``) and the combinational logic is ``assign`` statements (a multi-way
#: multiplexer is a function with a plain ``case``): no next-state variable computed in an
#: ``always_comb`` block from the enables. Same logic as Amaranth's script (Yosys's own rewrites,
#: bit- and cycle-exact); the shape is what a compiled simulator wants: Verilator evaluates the
#: ``always_comb`` next-state blocks of Amaranth's script again on every input change (every register
#: of a pipeline whose enable depends on ``o_ready``; docs/simulation.md, Verilator section). No
#: ``-norename``: Yosys's internal names become ``_N_`` (Icarus reads a function named
#: ``\$procmux$2`` as an unknown system function).
_ATTRS = "-remove generator -remove top -remove src -remove amaranth.hierarchy -remove amaranth.decoding"
SV_SCRIPT = ("proc -norom", "opt_clean", "opt_dff", "opt_clean", "memory_collect", f"attrmap {_ATTRS}",
             f"attrmap -modattr {_ATTRS}", "write_verilog -sv -noparallelcase")

__all__ = ["export_verilog", "export_half_verilog", "export_filter_verilog", "export_cached_verilog", "icarus_testbench", "run_icarus", "DIALECTS"]

#: Output dialects: "sv" (default) writes combinational logic as ``assign`` statements and registers
#: as ``always_ff`` blocks with their enable and reset (:data:`SV_SCRIPT`); "v2005" is Amaranth's plain
#: Verilog-2005 (``always @*`` processes).
DIALECTS = ("sv", "v2005")


def export_verilog(ts, *, one_port: bool = False, tag_width: int = 8, name: str = TOP_NAME,
                   dialect: str = "sv", ports: dict | None = None, specialise: bool = True,
                   geometry=None) -> str:
    """Verilog text of :class:`TexelFetchTop` for ``ts`` (no source-location attributes, so the text
    depends only on the design and the memories). If ``ports`` is a dict, it receives the top's
    port names and widths.

    Why not Amaranth's plain output by default: in Verilog-2005 Yosys writes combinational processes
    as ``always @*`` blocks made sensitive to a constant "trigger" register initialised to 0, hoping
    the initialisation is an event at time 0. Icarus Verilog 11 does not treat it as one, so a block
    whose inputs never change (e.g. a colour-format mux while every request is rgb) keeps X on its
    output forever, and X reaches responses even after reset. The default dialect has no
    combinational processes at all (continuous ``assign`` statements, evaluated at time 0 by every
    simulator) and writes registers as ``always_ff`` (:data:`SV_SCRIPT`; Icarus needs ``-g2012``).
    """
    from amaranth.back import verilog
    if dialect not in DIALECTS:
        raise ValueError(f"Verilog dialect {dialect!r} is not one of {DIALECTS}")
    if geometry is not None:
        ts = None                           # the loadable unit holds no texture data
    top = TexelFetchTop(ts, one_port=one_port, tag_width=tag_width, specialise=specialise, geometry=geometry)
    if ports is not None:
        ports.update({n: len(getattr(top, n)) for n in top.signature.members})
    if dialect == "v2005":
        text = verilog.convert(top, name=name, emit_src=False, strip_internal_attrs=True)
    else:
        text = _systemverilog(top, name)
    head = (f"// {name}: vqtex texel-fetch unit (Beers, Agrawala, Chaddha 1996), "
            f"{'one-port' if one_port else 'two-bank'} index memory, tag width {tag_width}, "
            f"latency {top.latency}.\n"
            f"// {top.fetch.features.describe()}.\n"
            + (f"// Textures: {ts.n_textures}; memories initialised by initial blocks. " if geometry is None else
               f"// Loadable: {geometry.describe()}; memories and colour matrix loaded over the Wishbone "
               "port bus_* (register map: vqtex export --register-map). ")
            + f"{'SystemVerilog: assign and always_ff (iverilog -g2012)' if dialect == 'sv' else 'Verilog-2005'}. "
            f"Generated by vqtex export.\n")
    return head + text


def _systemverilog(top, name: str) -> str:
    """``top`` as SystemVerilog module ``name`` (:data:`SV_SCRIPT`, no source locations)."""
    from amaranth.back import rtlil
    from amaranth.hdl import Fragment
    il, _ = rtlil.convert_fragment(Fragment.get(top, None), port_map(top), name, emit_src=False)
    return run_yosys(rtlil_script(il, *SV_SCRIPT))


def export_half_verilog(info, half: str) -> str:
    """SystemVerilog of one half (``"front"`` or ``"back"``, :data:`sim.backends.design.HALVES`) of
    the baked texel-fetch unit described by ``info`` (:func:`sim.backends.design.design_info`), as
    :func:`export_verilog` writes the whole unit (:data:`SV_SCRIPT`): the very fragment the export
    instantiates as ``fetch.front``/``fetch.back``, top module ``top`` with the half's own ports
    (the front end: ``i__valid``, ``i__ready``, ``i__payload``, ``o_valid``, ``o_ready``, ``o_tag``,
    ``link``, the strobes and ``valid``; the back end: ``link`` in, ``rgba`` out). Simulation only:
    the Verilator backend runs the two halves as CXXRTL does (docs/simulation.md); ``vqtex export``
    writes the whole unit, one top module."""
    frag, ports = info.halves[half]
    return run_yosys(rtlil_script(fragment_rtlil(frag, ports), *SV_SCRIPT))


def export_filter_verilog(ts, *, lanes: int = 1, tag_width: int = 8, frac: int | None = None,
                          name: str = FILTER_TOP_NAME, index_banks: str = "parity", geometry=None):
    """SystemVerilog of :class:`sim.backends.design.FilterTop` for ``ts`` (ports ``clk``, ``rst``,
    ``i_valid``, ``i_ready``, ``i_payload``, ``o_valid``, ``o_ready``, ``o_payload``,
    ``stall_output``, ``busy``, ``bank_conflict``), written as :func:`export_verilog` writes the
    texel-fetch unit. Returns (the text, the FilterTop)."""
    top = FilterTop(None if geometry is not None else ts, lanes=lanes, tag_width=tag_width, frac=frac,
                    index_banks=index_banks, geometry=geometry)
    text = _systemverilog(top, name)
    f = top.filter
    head = (f"// {name}: vqtex texture filter, {lanes} texel-fetch lane(s), {f.banks} index bank(s) per "
            f"set of lanes, s and t with {f.frac} fractional "
            f"bits, tag width {tag_width}, latency {top.latency}.\n"
            f"// i_payload and o_payload: the layouts of hw.filter.footprint.FilterRequestLayout and "
            f"hw.pipeline.ResponseLayout. Generated by vqtex.\n")
    return head + text, top


# ---------------------------------------------------------------------------------------------
# Icarus Verilog (four-state) cross-check

def icarus_testbench(ts, n: int, *, one_port: bool = False, tag_width: int = 8, stalled: bool = False,
                     max_cycles: int = 1_000_000, name: str = TOP_NAME, specialise: bool = True) -> str:
    """A testbench for the exported ``name`` that resets the unit, presents ``n`` requests from
    ``req.hex`` back to back (packed as ``TexelFetch``'s request payload), drives ``o_ready`` from
    ``ready.hex`` (if ``stalled``, else high), and writes every transferred response (hex r g b a tag)
    and, at the end, ``cycles C xerrors E`` to ``resp.txt``. An X or Z on ``i_ready``/``o_valid``, or
    on any response member while ``o_valid`` is high, counts as an X error (``$isunknown``)."""
    from vqtex.hw.texel_fetch import TexelFetch
    fetch = TexelFetch(ts, one_port=one_port, tag_width=tag_width, specialise=specialise)
    req_fields = {nm: (f.offset, f.width) for nm, f in fetch.i.p.shape() if f.width}
    resp = response_ports(fetch)
    rwidth = fetch.i.p.shape().size
    from amaranth.hdl import Fragment
    Fragment.get(fetch, None)           # (only its ports are used here; silences UnusedElaboratable)
    decl = [f"  reg [{w - 1}:0] i_{nm} = 0;" for nm, (_, w) in req_fields.items()]
    decl += [f"  wire [{w - 1}:0] o_{nm};" for nm, w in resp.items()]
    conns = ["    .clk(clk)", "    .rst(rst)", "    .i_valid(i_valid)", "    .i_ready(i_ready)",
             "    .o_valid(o_valid)", "    .o_ready(o_ready)"]
    conns += [f"    .i_{nm}(i_{nm})" for nm in req_fields] + [f"    .o_{nm}(o_{nm})" for nm in resp]
    unpack = "\n".join(f"        i_{nm} = reqs[sent][{off + w - 1}:{off}];" for nm, (off, w) in req_fields.items())
    members = ", ".join(f"o_{nm}" for nm in resp)
    # One $isunknown per member: Icarus 11 wrongly reports X for $isunknown of values over 32 bits.
    unknown = " || ".join(f"$isunknown(o_{nm})" for nm in resp)
    fmt = " ".join("%h" for _ in resp)
    ready = "ready_pat[cycle]" if stalled else "1'b1"
    return f"""`timescale 1ns/1ps
// Generated by sim/backends/verilog.py: Icarus Verilog check of {name} ({n} requests).
module tb;
  reg clk = 0;
  reg rst = 0;
  reg i_valid = 0;
  reg o_ready = 0;
  wire i_ready, o_valid;
{chr(10).join(decl)}
  reg [{rwidth - 1}:0] reqs [0:{max(n, 1) - 1}];
  reg ready_pat [0:{max_cycles - 1}];
  integer sent = 0, got = 0, cycle = 0, xerrors = 0, fd;
  {name} dut (
{("," + chr(10)).join(conns)}
  );
  initial begin
    $readmemh("req.hex", reqs);
    {'$readmemh("ready.hex", ready_pat);' if stalled else ''}
    fd = $fopen("resp.txt", "w");
    // Reset: rst rises after time 0 (so every combinational block sees an event: Icarus does not
    // run Yosys's always @* blocks at time 0 by itself), one clock edge, rst falls.
    #1 rst = 1; #1 clk = 1; #1 clk = 0; rst = 0;
    while (got < {n} && cycle < {max_cycles}) begin
      i_valid = (sent < {n});
      if (sent < {n}) begin
{unpack}
      end
      o_ready = {ready};
      #1;                                     // combinational logic settles
      if ($isunknown(i_ready) || $isunknown(o_valid)) xerrors = xerrors + 1;
      if (o_valid && ({unknown})) xerrors = xerrors + 1;
      if (o_valid && o_ready) begin
        $fwrite(fd, "{fmt}\\n", {members});
        got = got + 1;
      end
      if (i_valid && i_ready) sent = sent + 1;
      clk = 1; #1 clk = 0;
      cycle = cycle + 1;
    end
    $fwrite(fd, "cycles %0d xerrors %0d\\n", cycle, xerrors);
    $fclose(fd);
    $finish;
  end
endmodule
"""


def run_icarus(ts, requests, *, stall: float = 0.0, seed: int = 0, one_port: bool = False,
               tag_width: int = 8, dialect: str = "sv", workdir: str | None = None,
               specialise: bool = True) -> dict:
    """Export ``ts``, simulate ``requests`` under Icarus Verilog (``iverilog -g2012``, ``vvp``).

    Returns ``{"responses": (N, 4) uint8, "tags": (N,) int, "cycles": int, "xerrors": int}``.
    Raises :class:`sim.backends.toolchain.ToolchainError` if Icarus is missing or fails.
    """
    import os
    import tempfile

    import numpy as np

    from vqtex.sim.backends.cycle_model import run_cycles
    from vqtex.sim.streams import ready_pattern
    from .design import design_info, pack_requests
    from .toolchain import ToolchainError, find_tool, run_tool

    iverilog, vvp = find_tool("iverilog"), find_tool("vvp")
    req = np.asarray(requests, dtype=np.int64).reshape(-1, 4)
    n = len(req)
    info = design_info(ts, one_port=one_port, tag_width=tag_width, specialise=specialise)
    expected = run_cycles(ts, req, stall=stall, seed=seed, one_port=one_port, occupancy=False)["cycles"]
    max_cycles = expected + 64
    with tempfile.TemporaryDirectory(dir=workdir) as tmp:
        with open(os.path.join(tmp, "top.v"), "w") as f:
            f.write(export_verilog(ts, one_port=one_port, tag_width=tag_width, dialect=dialect,
                                   specialise=specialise))
        with open(os.path.join(tmp, "tb.v"), "w") as f:
            f.write(icarus_testbench(ts, n, one_port=one_port, tag_width=tag_width, stalled=stall > 0,
                                     max_cycles=max_cycles, specialise=specialise))
        digits = -(-info.request_width // 4)
        with open(os.path.join(tmp, "req.hex"), "w") as f:
            f.write("".join(f"{int(p):0{digits}x}\n" for p in pack_requests(info, req)))
        if stall > 0:
            with open(os.path.join(tmp, "ready.hex"), "w") as f:
                f.write("\n".join("1" if r else "0" for r in ready_pattern(seed, stall, max_cycles)) + "\n")
        run_tool([iverilog, "-g2012", "-o", "sim.vvp", "-s", "tb", "tb.v", "top.v"], tmp, "iverilog", "build.log")
        run_tool([vvp, "-n", "sim.vvp"], tmp, "vvp", "build.log")
        with open(os.path.join(tmp, "resp.txt")) as f:
            lines = f.read().split("\n")
    tail = [ln for ln in lines if ln.startswith("cycles ")]
    if not tail:
        raise ToolchainError("Icarus testbench did not finish")
    _, cycles, _, xerrors = tail[0].split()
    rows = [ln.split() for ln in lines if ln and not ln.startswith("cycles ")]

    def num(s):
        return int(s, 16) if all(c in "0123456789abcdefABCDEF" for c in s) else -1
    vals = np.array([[num(v) for v in r] for r in rows], dtype=np.int64).reshape(len(rows), -1)
    return {"responses": vals[:, :4].astype(np.uint8) if len(rows) else np.zeros((0, 4), np.uint8),
            "tags": vals[:, 4] if vals.shape[1] > 4 else np.zeros(len(rows), np.int64),
            "unknown": int((vals < 0).sum()), "cycles": int(cycles), "xerrors": int(xerrors)}


def export_cached_verilog(ts, config, *, tag_width: int = 8, name: str = "cached_texel_fetch",
                          ports: dict | None = None, geometry=None):
    """SystemVerilog of :class:`sim.backends.design.CachedTexelFetchTop` (the cached unit, its AXI4
    read master as ``axi_*``), written as :func:`export_verilog` writes the on-chip unit. If
    ``ports`` is a dict, it receives the top's port names and widths. Returns (the text, the
    CachedTexelFetchTop: ``top.unit.latency`` is the latency when every reference hits). With
    ``geometry``: the loadable cached unit (no texture data; its Wishbone port as ``bus_*``)."""
    from .design import CachedTexelFetchTop
    top = CachedTexelFetchTop(None if geometry is not None else ts, config, tag_width=tag_width, geometry=geometry)
    if ports is not None:
        ports.update({n: len(getattr(top, n)) for n in top.signature.members})
    head = (f"// {name}: vqtex texel-fetch unit with its index map and raw levels in external memory behind "
            f"caches ({config.describe()}); latency {top.unit.latency} when every reference hits. "
            f"Generated by vqtex.\n")
    return head + _systemverilog(top, name), top


def export_cached_filter_verilog(ts, config, *, lanes: int = 4, tag_width: int = 16, frac: int | None = None,
                                 name: str = "cached_texture_filter", geometry=None, ports: dict | None = None) -> str:
    """SystemVerilog of :class:`sim.backends.design.CachedFilterTop` (the texture filter through the
    memory system, its AXI4 read master as ``axi_*``), written as :func:`export_verilog` writes the
    on-chip unit. With ``geometry``: the loadable filter (no texture data; its Wishbone port as
    ``bus_*``). If ``ports`` is a dict, it receives the top's port names and widths."""
    from .design import CachedFilterTop
    top = CachedFilterTop(None if geometry is not None else ts, config, lanes=lanes, tag_width=tag_width, frac=frac,
                          geometry=geometry)
    if ports is not None:
        ports.update({n: len(getattr(top, n)) for n in top.signature.members})
    head = (f"// {name}: vqtex texture filter, {lanes} lane(s), each reading through its own caches "
            f"({config.describe()}), one AXI4 read master; latency {top.latency} when every reference hits. "
            f"Generated by vqtex.\n")
    return head + _systemverilog(top, name)
