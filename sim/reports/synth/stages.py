"""Attributing netlist names to the design: the signal a mapped cell stands for (:func:`signal_of`)
and the pipeline stage that owns it (:func:`stage_of`)."""

from __future__ import annotations

import re

__all__ = ["signal_of", "stage_of"]


_SUFFIX = re.compile(r"(\$CCU2_COMB\d|\$CCU2_FCI_INT)$|_(TRELLIS_FF|LUT4|PFUMX|L6MUX21|CCU2C|MULT18X18D|DP16KD|"
                     r"TRELLIS_DPR16X4|TRELLIS_IO)(_[A-Za-z]+\d*)*(_\d+)?.*$")


def signal_of(cell: str) -> str:
    """The design signal a mapped cell stands for: Yosys names a cell after the signal it drives
    plus the cell type and a port chain (``unit.fetch.front.address.k_TRELLIS_FF_Q_5`` ->
    ``unit.fetch.front.address.k``; a block RAM ``unit.fetch.back.codebook_rom.codebook.0.8`` -> the memory
    ``unit.fetch.back.codebook_rom.codebook``)."""
    n = cell.lstrip("\\")
    n = _SUFFIX.sub("", n)
    m = re.match(r"^(.*)\.\d+\.\d+(_(DO|DI|AD)[AB]\d+)?$", n)      # memory blocks: <memory>.<row>.<col>
    return m.group(1) if m else n


_SUBMODULES = {
    "descriptor": "descriptor table",
    "address": "block address",
    "index_reader": "index reader",
    "codebook_rom": "codebook ROM",
    "color_matrix": "colour matrix",
}
#: The filter through memory's own blocks (beside its lanes).
_FILTER_MEMORY = {
    "footprint": "filter footprint",
    "blend": "filter blend",
    "arbiter": "AXI arbiter (lanes' queues)",
    "bus_port": "bus port",
}
_TOP_FIELDS = [
    # the blocks' output registers, named after the top's wires that carry them
    (r"^row\b", "descriptor table"),
    (r"^(k|x|y|raw_addr)(\$\d+)?(\[|$)", "block address"),
    (r"^index(\$\d+)?(\[|$)", "index reader"),
    (r"^(samples|color_out)(\$\d+)?(\[|$)", "codebook ROM"),
    (r"^(i|o)__(valid|ready)", "pipeline control"),
    (r"^(rgba|o__)", "colour matrix"),
    (r"^(advance|upstream)\b", "pipeline control"),
    (r"^(skid|response)\b", "output skid register"),
    (r"^valid(_|$|\[)", "pipeline control"),
    (r"^tag_", "tag carry"),
    (r"^(i|j)_descriptor", "descriptor (carried i, j)"),
    (r"^row_address", "block address (carried descriptor row)"),
    (r"^side_index", "index reader (side fields)"),
]


def stage_of(name: str) -> str:
    """Which part of the design a netlist name belongs to: ``harness`` (the ports' flip-flops), a
    stage (``index reader``, ``codebook ROM``, ...), ``pipeline control`` or ``?`` for names Yosys
    made up (``$abc$...``)."""
    n = name.lstrip("\\")
    if not n or n.startswith("$"):
        return "?"
    parts = n.split(".")
    if parts[0] != "unit":
        return "harness"
    # unit.fetch.<submodule>.<signal> or unit.fetch.<signal> or unit.<port>
    # the cached unit (hw.memory.unit): unit.unit.<reader|descriptor|address|texel>...; its texel
    # pipeline is named as the on-chip unit's
    if len(parts) >= 3 and parts[1] == "unit":
        # the filter through memory (hw.memory.filter): unit.unit.<laneK|laneK_reader|laneK_descriptor|
        # laneK_address|footprint|blend|arbiter|bus_port>...; each lane's texel pipeline named as the
        # unit's, each lane's reader, descriptor and address as the cached unit's
        lane = re.fullmatch(r"lane\d+(_(\w+))?", parts[2])
        if lane and lane.group(2) is None:
            parts = parts[:2] + ["texel"] + parts[3:]
        elif lane:
            parts = parts[:2] + [lane.group(2)] + parts[3:]
        elif parts[2] in _FILTER_MEMORY:
            return _FILTER_MEMORY[parts[2]]
        if parts[2] == "texel":
            parts = ["unit", "fetch"] + parts[3:]
        elif parts[2] == "reader":
            return "cache (tag check, FIFO, AXI, data read)"
        elif parts[2] in ("descriptor", "address"):
            return f"cached unit's {_SUBMODULES[parts[2]]}"
        else:
            return "cached unit top"
    if len(parts) >= 3 and parts[1] == "fetch" and parts[2] in ("front", "back"):
        parts = parts[:2] + parts[3:]           # the two halves (hw.pipeline): named by their blocks
    if len(parts) >= 3 and parts[1] == "fetch":
        if parts[2] in _SUBMODULES and len(parts) >= 4:
            return _SUBMODULES[parts[2]]
        field = ".".join(parts[2:])
        for pat, stage in _TOP_FIELDS:
            if re.match(pat, field):
                return stage
        return "texel fetch top"
    return "unit ports"
