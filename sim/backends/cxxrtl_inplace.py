"""One clock cycle of the CXXRTL model with the registers updated in place (no next-state copies).

CXXRTL simulates a clock edge in two steps: ``eval()`` computes every register's next state into
``wire.next`` from the current states ``wire.curr``, then ``commit()`` copies ``next`` into ``curr``
for every register. For this design the copy was a third of the run time (139 registers, four of
them 504 bits wide). This module rewrites the generated ``eval()`` into one member function

    template<class F> void p_top::vq_cycle(F &&sample)

that does the same clock cycle with ``rst`` low:

1. the *combinational* statements of ``eval()`` (every top-level statement that is not a register
   or memory-read-port update), in their order: they read only register states (``curr``), inputs
   and each other, so they give this cycle's outputs;
2. ``sample()``: the driver reads the ports (outputs, strobes, the stages' valid bits);
3. the register updates (the ``if (posedge_p_clk) { ... }`` blocks), writing ``curr`` directly, in
   an order in which every register is written only after every update that reads its current state
   (readers first: for a pipeline, the last stage first). Registers that read each other in a cycle
   read a copy taken before the updates. ``p_rst`` is the constant 0 in this function, so the
   compiler drops the reset multiplexers.

An asynchronous memory read port (the loadable unit's first block RAM ports) is a combinational
statement too (a block of eight lines, :data:`_MEMREAD`): it reads the memory before this cycle's
writes are committed, as in ``eval()``.

Memory write ports (the loadable unit's) are ``if (posedge_p_clk)`` blocks that queue a write
(``memory_x.update(...)``) and write no register: they run before the register updates (so they
read this cycle's register states, as in ``eval()``), every register update then reads the memories
unchanged (the read ports are not transparent: a read in the cycle of a write returns the old
word), and the queued writes are committed last (``memory_x.commit``), as ``commit()`` does.

The result is the same as ``eval(); commit();`` bit for bit (tested against CXXRTL's own stepping and
against golden). It is built only from the generated code's regular shape; anything unexpected (a
combinational loop, a statement of another form) makes :func:`inplace_cycle` return ``None`` and
the driver keeps CXXRTL's own ``eval()``/``commit()``.
"""

from __future__ import annotations

import heapq
import re

__all__ = ["inplace_cycle", "inplace_rewrite", "CLASS_DECL"]

_EVAL = re.compile(r"^bool p_top::eval\(performer \*performer\) \{\n(.*?)^\}\n", re.S | re.M)
#: The member declarations added to ``struct p_top`` (after ``eval``'s).
CLASS_DECL = "\ttemplate<class F> void vq_cycle(F &&sample);\n\tvoid vq_reset_cycle();\n"
_EVAL_DECL = "\tbool eval(performer *performer = nullptr) override;\n"
_SKIP = {"\tbool converged = true;", "\tbool posedge_p_clk = this->posedge_p_clk();", "\treturn converged;"}
_PART = r"\w+\.slice<\d+(?:,\d+)?>\(\)"          # a slice of a wire or local, as an lvalue
#: A combinational statement: a local's declaration, a reference to a register's state, or an
#: assignment to a whole wire or local, to a slice of one (``x.slice<7,0>() = ...``, as CXXRTL
#: writes a signal assigned in parts, the texture filter's wide payloads) or to a concatenation of
#: slices (``x.slice<14>().concat(x.slice<1,0>()) = ...``).
_COMB = re.compile(rf"^\t(?:value<\d+> \w+|const value<\d+> &?\w+ = [\w.]+"
                   rf"|(?:\w+|{_PART}(?:\.concat\({_PART}\))*) = .*);$")
_TARGET = re.compile(r"(\w+)\.slice<")


#: An asynchronous memory read port (the loadable unit's pipeline ports, ``hw.bus_port.attach_memory``
#: with ``own_port``), as CXXRTL writes one: a combinational statement of eight lines that reads the
#: memory's current words (the writes of the cycle are committed after it) into one wire.
_MEMREAD = re.compile(r"\tauto (tmp_\d+) = memory_index\([^;]*\);\n"
                      r"\tCXXRTL_ASSERT\(\1\.valid && \"out of bounds read\"\);\n"
                      r"\tif\(\1\.valid\) \{\n"
                      r"\t\tvalue<(\d+)> (tmp_\d+) = memory_\w+\[\1\.index\];\n"
                      r"\t\t(\w+) = \3;\n"
                      r"\t\} else \{\n"
                      r"\t\t\4 = value<\2> \{\};\n"
                      r"\t\}\Z")


def _targets(line: str) -> set:
    """The wires and locals a combinational assignment writes (all of them, or parts)."""
    read = _MEMREAD.match(line)
    if read:
        return {read.group(4)}
    lhs = line.split(" = ", 1)[0].strip()
    return set(_TARGET.findall(lhs)) or {lhs}
_ALIAS = re.compile(r"^\tconst value<(?P<width>\d+)> &(?P<dst>\w+) = (?P<src>\w+\.curr);$")
_NEXT = re.compile(r"\b(\w+)\.next\b")
_CURR = re.compile(r"\b(\w+)\.curr\b")
_IDENT = re.compile(r"\b[A-Za-z_]\w*\b")
_WRITE = re.compile(r"\b(memory_\w+)\.update\(")


def _items(body: str):
    """Top-level statements of ``eval()``: ("comb", line) or ("reg", inner lines), comments dropped.
    None if a statement has an unexpected form."""
    items = []
    lines = body.split("\n")
    k = 0
    while k < len(lines):
        line = lines[k]
        k += 1
        if not line or line.startswith("\t// ") or line in _SKIP:
            continue
        if line == "\tif (posedge_p_clk) {":
            inner = []
            while k < len(lines) and lines[k] != "\t}":
                if not lines[k].startswith("\t\t"):
                    return None
                inner.append(lines[k])
                k += 1
            if k == len(lines):
                return None
            k += 1
            items.append(("reg", inner))
        elif _COMB.match(line) and ".next" not in line:
            items.append(("comb", line))
        elif line.startswith("\tauto tmp_") and "= memory_index(" in line:
            block = [line]
            while k < len(lines) and lines[k] != "\t}":
                block.append(lines[k])
                k += 1
            block = "\n".join(block + lines[k:k + 1])
            k += 1
            if not _MEMREAD.match(block):
                return None
            items.append(("comb", block))
        else:
            return None
    return items


def _order(reads, writes):
    """Register updates in an order where each wire is written after every *other* update reading
    it (ties: the generated order); returns (order, wires to snapshot). A wire read by an update
    that cannot come before its writer (a cycle) is snapshotted: its reads then no longer
    constrain the order."""
    n = len(reads)
    writer = {w: i for i in range(n) for w in writes[i]}
    snap = set()
    while True:
        succ = [set() for _ in range(n)]         # r -> w: r reads a wire that w writes (r first)
        indeg = [0] * n
        for r in range(n):
            for name in reads[r] - snap:
                w = writer.get(name)
                if w is not None and w != r and w not in succ[r]:
                    succ[r].add(w)
                    indeg[w] += 1
        heap = [i for i in range(n) if indeg[i] == 0]
        heapq.heapify(heap)
        order = []
        while heap:
            i = heapq.heappop(heap)
            order.append(i)
            for j in succ[i]:
                indeg[j] -= 1
                if indeg[j] == 0:
                    heapq.heappush(heap, j)
        if len(order) == n:
            return order, snap
        left = set(range(n)) - set(order)
        snap |= {w for i in left for w in writes[i] if any(w in reads[r] for r in left if r != i)}


def inplace_cycle(src: str) -> str | None:
    """The generated C++ with ``p_top::vq_cycle`` added (see the module docstring), or None."""
    out, _ = inplace_rewrite(src)
    return None if out is src else out


def inplace_rewrite(src: str) -> tuple[str, int]:
    """(the generated C++ with ``p_top::vq_cycle`` added, the number of register and write-port
    update blocks it moved into it), or (``src`` itself, 0) when the code does not have the shape
    the rewrite needs (the pass's report in :func:`sim.backends.cxxrtl.rewrite`)."""
    if _EVAL_DECL not in src:
        return src, 0
    m = _EVAL.search(src)
    if not m or "converged = false" in m.group(1):
        return src, 0
    items = _items(m.group(1))
    if items is None:
        return src, 0
    widths = {name: int(w) for w, name in re.findall(r"^\t(?:/\*\w+\*/ )?wire<(\d+)> (\w+);$", src, re.M)}
    combs = [text for kind, text in items if kind == "comb"]
    aliases = {}                                # local -> the register it is a reference to
    for line in combs:
        a = _ALIAS.match(line)
        if a:
            aliases[a.group("dst")] = a.group("src").removesuffix(".curr")
    bodies, writes, reads = [], [], []
    memory_writes, written_memories = [], []    # write-port blocks, and the memories they write
    for kind, inner in items:
        if kind != "reg":
            continue
        text = "\n".join(inner)
        w = set(_NEXT.findall(text))
        if not w and _WRITE.search(text):       # a memory write port: queued, committed last
            memory_writes.append(text)
            written_memories += [mem for mem in _WRITE.findall(text) if mem not in written_memories]
            continue
        if not w or not w <= widths.keys():
            return src, 0
        bodies.append(text)
        writes.append(w)
        reads.append(set(_CURR.findall(text)) | {aliases[i] for i in _IDENT.findall(text) if i in aliases})
    written = set().union(*writes) if writes else set()
    if any(_targets(line) & written for line in combs):
        return src, 0                           # the combinational part never writes a register
    order, snap = _order(reads, writes)

    # Two functions of one body: vq_cycle (rst low, ``sample`` between the combinational part and
    # the updates) and vq_reset_cycle (rst high: a reset edge that keeps every register's state in
    # ``curr``, where eval()/commit() would commit the stale ``next`` of the registers this
    # function updated in place; the loadable unit resets this way, keeping what was loaded).
    out = ["template<class F> void p_top::vq_cycle(F &&sample) {",
           "\tconst value<1> p_rst{0u};\t// vq_cycle is a cycle with rst low"]
    head = len(out)
    for line in combs:
        a = _ALIAS.match(line)
        if a and aliases[a.group("dst")] in snap:   # a reference would see the update: a copy
            line = f"\tconst value<{a.group('width')}> {a.group('dst')} = {a.group('src')};"
        out.append(line)
    sample_at = len(out)
    out.append("\tsample();")
    for text in memory_writes:                  # queued with this cycle's register states
        out.append("\t{\n" + text + "\n\t}")
    for w in sorted(snap):                      # copies taken before any register changes
        out.append(f"\tconst value<{widths[w]}> vq_old_{w} = {w}.curr;")
    for i in order:
        text = bodies[i]
        for w in snap:
            text = re.sub(rf"\b{w}\.curr\b", f"vq_old_{w}", text)
        out.append("\t{\n" + _NEXT.sub(lambda mm: f"{mm.group(1)}.curr", text) + "\n\t}")
    if written_memories:                        # the writes land after every read of this cycle
        out.append("\tobserver vq_observer;")
        out += [f"\t{mem}.commit(vq_observer);" for mem in written_memories]
    out.append("}\n")
    reset = (["void p_top::vq_reset_cycle() {", "\tconst value<1> p_rst{1u};\t// a clock edge with rst high"]
             + out[head:sample_at] + out[sample_at + 1:])
    out += reset
    # the definition goes right after eval()'s (inside the design's namespace)
    src = src[:m.end()] + "\n" + "\n".join(out) + src[m.end():]
    return src.replace(_EVAL_DECL, _EVAL_DECL + CLASS_DECL, 1), len(bodies) + len(memory_writes)
