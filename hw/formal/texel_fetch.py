"""Proofs about the whole texel-fetch unit (:class:`hw.texel_fetch.TexelFetch`): its output keeps the
stream rules, and it never loses, duplicates or reorders a response, each response leaving after
exactly ``LATENCY`` cycles in which the output was free (one-port: plus one per bubble it waited
behind, at most ``UPSTREAM_STAGES``).

Both harnesses drive the request stream and the output's ``ready`` with free values in every cycle
and assume nothing of them: the requests need not be valid and the producer need not keep the
stream rules (the claims are about the control, which does not look at the request), and every
pattern of backpressure is allowed.

**No loss, duplicate or reorder** (:class:`OrderHarness`) is a counting and tag-tracking argument:

* the harness counts the responses in flight (accepted minus delivered) and claims that no response
  is delivered while none is in flight (no response invented or duplicated);
* the solver picks any one accepted request to *watch* (a free choice, so the claim is about every
  request); the harness records its tag and the number of responses in flight ahead of it, counts
  down as they leave, and claims that the response delivered when none is left ahead carries the
  watched tag (nothing lost, duplicated or overtaken in between);
* it counts the cycles since the watched request was accepted in which the output was free (not
  ``valid & ~ready``) and claims that the response is delivered exactly when that count reaches
  ``LATENCY`` (never later: nothing lost, whatever the backpressure); with ``one_port``, plus one
  for each cycle the upstream stages held it for a straddling index's second read
  (``stall_one_port``), which happens at most ``UPSTREAM_STAGES`` times.

It is proved by k-induction with lemmas that name the unit's control: the count in flight is the
number of valid bits (the ``valid`` output), ``advance`` is the complement of the skid register's
valid bit, and the watched request sits in the stage the harness expects (valid, with its tag in the
tag register of that stage), with as many valid stages ahead of it as there are responses ahead;
one-port, that the index reader's first stage holds a valid request and that each straddler holds
the upstream stages once (the reader's ``second``).
"""

from __future__ import annotations

from amaranth import *
from amaranth.asserts import AnySeq

from ..pipeline import LATENCY, UPSTREAM_STAGES
from ..texel_fetch import TexelFetch
from .harness import Harness, SeededBug, internal, popcount
from .stream import stream_rules

__all__ = ["StreamHarness", "OrderHarness", "drive_free", "SKID_NEVER_SHOWS", "SKID_SHOWS_TWICE", "HOLD_IGNORED"]


def drive_free(m: Module, unit: TexelFetch) -> None:
    """Drive every input of ``unit`` with a free value in every cycle: the request stream, the
    output's ready and, for a loadable unit, its Wishbone port (the host may hold a cycle, write or
    read any register at any time)."""
    m.d.comb += [
        unit.i.valid.eq(AnySeq(1)),
        unit.i.payload.eq(AnySeq(len(Value.cast(unit.i.payload)))),
        unit.o.ready.eq(AnySeq(1)),
    ]
    if unit.loadable and hasattr(unit, "bus"):
        for name in ("adr", "dat_w", "sel", "cyc", "stb", "we"):
            port = getattr(unit.bus, name)
            m.d.comb += port.eq(AnySeq(len(port)))


class StreamHarness(Harness):
    """The unit's output keeps the stream rules (:func:`hw.formal.stream.stream_rules`).

    Arguments
    ---------
    unit : callable
        Makes the unit under test (``lambda: TexelFetch(ts)``).
    bug : SeededBug, optional
    """

    def __init__(self, unit, bug: SeededBug | None = None):
        super().__init__(bug)
        self._unit = unit

    def build(self, m, platform):
        unit = self._unit()
        self.design(m, "dut", unit, platform)
        drive_free(m, unit)
        stream_rules(self, m, unit.o, "o")
        self.cover(m, unit.o.valid & ~unit.o.ready)


class OrderHarness(Harness):
    """No response lost, duplicated or reordered, each delivered after exactly ``LATENCY`` free
    output cycles, plus its one-port bubbles (see the module docstring).

    Arguments
    ---------
    unit : callable
        Makes the unit under test (``tag_width`` at least 1).
    bug : SeededBug, optional
    """

    def __init__(self, unit, bug: SeededBug | None = None):
        super().__init__(bug)
        self._unit = unit

    def build(self, m, platform):
        unit = self._unit()
        if unit.tag_width < 1:
            raise ValueError("the order proof tracks tags: the unit needs a tag")
        frag = self.design(m, "dut", unit, platform)
        drive_free(m, unit)
        tags = internal(frag, "front", "tag_stages")
        skid_tag = internal(frag, "front", "skid_tag")
        advance = internal(frag, "front", "advance")
        tw = unit.tag_width
        valid = unit.valid                              # bit n: stage n; bit LATENCY: the skid register
        accepted = unit.i.valid & unit.i.ready
        delivered = unit.o.valid & unit.o.ready
        free = ~(unit.o.valid & ~unit.o.ready)          # the output was not stalled this cycle

        # Counting: responses in flight.
        in_flight = Signal(range(LATENCY + 3))
        m.d.sync += in_flight.eq(in_flight + accepted - delivered)
        self.claim(m, ~delivered | (in_flight != 0), "no response without a request in flight")
        self.lemma(m, in_flight == popcount(valid), "in flight = valid stages and skid register")
        self.lemma(m, advance == ~valid[LATENCY], "advance = not skid_valid")

        # Tag tracking: one watched request, chosen by the solver.
        watch = AnySeq(1)
        armed = Signal()                                # a request has been watched
        pending = Signal()                              # ... and its response has not left yet
        tag = Signal(tw)                                # its tag
        ahead = Signal(range(LATENCY + 2))              # responses in flight ahead of it
        stage = Signal(range(LATENCY + 1))              # where it is: stage n, LATENCY: the skid register
        free_cycles = Signal(range(LATENCY + UPSTREAM_STAGES + 2))     # free output cycles since it was accepted
        # One-port bubbles it waited behind: cycles in which the pipeline advanced but the upstream
        # stages it was in held for a straddling index's second read (``stall_one_port``; never
        # with two banks). At most one per request in the upstream stages with it, itself included.
        bubbles = Signal(range(UPSTREAM_STAGES + 2))
        upstream_held = pending & unit.stall_one_port & (stage < UPSTREAM_STAGES)
        with m.If(accepted & watch & ~armed):
            m.d.sync += [armed.eq(1), pending.eq(1), tag.eq(unit.i.p.tag), ahead.eq(in_flight - delivered),
                         stage.eq(0), free_cycles.eq(free), bubbles.eq(0)]
        with m.If(pending):
            with m.If(free):
                m.d.sync += free_cycles.eq(free_cycles + 1)
            with m.If(upstream_held):
                m.d.sync += bubbles.eq(bubbles + 1)
            with m.Elif(advance & (stage < LATENCY)):
                m.d.sync += stage.eq(stage + 1)
            with m.If(delivered):
                with m.If(ahead == 0):
                    self.claim(m, unit.o.p.tag == tag, "the response delivered when none is ahead is the watched one")
                    self.claim(m, free_cycles == LATENCY + bubbles,
                               "delivered after exactly LATENCY free output cycles (+ one per one-port bubble)")
                    m.d.sync += pending.eq(0)
                with m.Else():
                    m.d.sync += ahead.eq(ahead - 1)
            self.claim(m, free_cycles <= LATENCY + bubbles,
                       "a pending response has waited at most LATENCY free output cycles (+ one per one-port bubble)")
            self.claim(m, bubbles <= UPSTREAM_STAGES, "at most UPSTREAM_STAGES one-port bubbles")
            # Lemmas: where the watched request is, and what is ahead of it.
            self.lemma(m, valid.bit_select(stage, 1), "the watched request's stage is valid")
            with m.If(stage < LATENCY):
                self.lemma(m, tags.word_select(stage, tw) == tag, "its tag is in its stage's tag register")
            with m.Else():
                self.lemma(m, skid_tag == tag, "its tag is in the skid register")
            self.lemma(m, ahead == popcount(valid >> (stage + 1)), "ahead = valid registers after its stage")
            self.lemma(m, free_cycles == stage + advance + bubbles, "free cycles = stage + advance + bubbles")
            if unit.one_port:
                # Each straddling index in the index reader's first stage holds the upstream stages
                # once (``second`` is high once it has): the bubbles it waited behind, plus those
                # that the requests ahead of it in the upstream stages and itself can still cause.
                second = internal(frag, "front", "index_reader", "second")
                u = UPSTREAM_STAGES
                with m.If(stage < u):
                    self.lemma(m, bubbles + popcount(valid[:u] >> (stage + 1)) + 1 - second <= u,
                               "bubbles so far and still possible: at most UPSTREAM_STAGES")
        self.lemma(m, ~pending | armed, "pending only once watched")
        if unit.one_port:
            reader_valid = internal(frag, "front", "index_reader", "fields_bit")[-1]
            self.lemma(m, ~reader_valid | valid[UPSTREAM_STAGES - 1], "the index reader's request is a valid one")
            self.lemma(m, ~internal(frag, "front", "index_reader", "second") | valid[UPSTREAM_STAGES - 1],
                       "a second read is of a valid request")
        self.cover(m, pending & delivered & (ahead == 0) & (in_flight > 2) & ((bubbles > 0) if unit.one_port else 1))


#: Negative control of the stream rules (and of no loss): the skid register never shows, so the
#: response that was stalled is replaced by the next one.
SKID_NEVER_SHOWS = SeededBug(
    "skid_never_shows", "the skid register's valid bit stuck at 0: a stalled response is overwritten",
    ("front",), lambda s: [("sync", s("skid_valid").eq(0))])

#: Negative control of no duplicate: after the skid register's response has transferred, it shows
#: it again while the output stays ready.
SKID_SHOWS_TWICE = SeededBug(
    "skid_shows_twice", "the skid register keeps showing its response after it transferred",
    ("front",), lambda s: [("sync", s("skid_valid").eq(s("stall_output") | (s("skid_valid") & s("o_ready"))))])

#: Negative control of the one-port order: the upstream stages do not wait while the index reader
#: holds a straddling index for its second read (the request behind it overwrites it).
HOLD_IGNORED = SeededBug(
    "hold_ignored", "the upstream stages move while a straddling index is held for its second read",
    ("front",), lambda s: [("comb", s("upstream").eq(s("advance")))])
