"""Copies of a register that synthesis keeps: one flip-flop per group of loads, against fan-out.

A register that drives hundreds of loads spread over the chip (a pipeline's enable, a pick's
select, a decision taken in one place and used in many) spends most of its cycle in routing. The
usual cure is copies: several flip-flops loading the same value, each driving a share of the loads,
each placed near its share. Synthesis undoes that on its own: Yosys's ``opt_merge`` merges
flip-flops with the same inputs, clock, enable and reset into one (so does Vivado's "equivalent
register removal"), and Amaranth's ``keep`` attribute lands on the signal's wire, which
``opt_merge`` ignores.

:func:`register_copies` makes the copies as Amaranth signals marked ``keep``. What keeps them apart:

* ``vqtex report area`` (``sim.reports.synth.tools.yosys_script``) gives every flip-flop that drives
  a wire marked ``keep`` the ``keep`` attribute on the cell itself (:data:`KEEP_REGISTERS`, a Yosys
  ``setattr`` before ``synth_ecp5``), which ``opt_merge`` and ``opt_clean`` respect.
* In the exported Verilog the signal is a ``(* keep = 32'd1 *) reg``: Vivado's and Quartus's
  synthesis keep a register declared so (its equivalent-register removal skips it); a Yosys flow
  of the user's own needs the same ``setattr`` line.

Contract: each copy equals the register it copies in every cycle (same next value, same enable,
same reset value): the copies change no cycle and no bit of the design, only its netlist.
"""

from __future__ import annotations

from amaranth.hdl import Module, Shape, Signal, Value

__all__ = ["KEEP", "register_copies"]

#: The attribute that marks a register to keep (Amaranth puts it on the signal's wire).
KEEP = {"keep": 1}


def register_copies(m: Module, value: Value, n: int, *, name: str, enable: Value | None = None,
                    init: int = 0, reset_less: bool = False, domain: str = "sync") -> list:
    """``n`` flip-flops in ``m`` (``name0``, ``name1``, ...; ``value``'s shape), each loading
    ``value`` in ``domain`` when ``enable`` (every cycle without one), resetting to ``init`` (or
    reset-less): copies of one register, marked ``keep`` so synthesis keeps them apart. Returns the
    copies; each drives its own share of the loads. Latency: one cycle, as the register copied."""
    if n < 1:
        raise ValueError(f"at least one copy, not {n}")
    value = Value.cast(value)
    out = []
    for k in range(n):
        q = Signal(Shape.cast(value.shape()), init=init, reset_less=reset_less, name=f"{name}{k}",
                   attrs=KEEP)
        if enable is None:
            m.d[domain] += q.eq(value)
        else:
            with m.If(enable):
                m.d[domain] += q.eq(value)
        out.append(q)
    return out
