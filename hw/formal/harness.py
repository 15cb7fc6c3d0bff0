"""What every formal harness shares: the harness itself, its claims, white-box lookups, seeded bugs
and the description of a property that the runner (:mod:`vqtex.sim.formal`) proves.

A **harness** (:class:`Harness`) is an Amaranth elaboratable whose only port is the clock of a
reset-less ``sync`` domain: it instantiates the design under test, drives its inputs from free
values (``AnySeq``: the solver picks them in every cycle), restricts them with ``Assume`` where a
property needs valid inputs, and states the property with ``Assert``. Registers start from their
initial values (the unit's reset state) in the base case; k-induction starts from any state.

A **claim** is an ``Assert`` of what the property says (recorded with its text, so that a failure
names it); a **lemma** is a white-box helper invariant that makes the claim inductive (it names the
unit's internal registers, e.g. "the watched request's tag is in the tag register of its stage").
A lemma is proved as much as a claim is; it is only not the point.

A **seeded bug** (:class:`SeededBug`) is one more assignment in a named sub-module of the elaborated
design, after the design's own (in Amaranth the last assignment to a signal wins): the negative
control of a property is the same harness around the design with the bug, and the proof must fail.
Bugs name signals by their names in the design, so a renamed signal breaks the control loudly
(:class:`LookupError`), never silently.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass
from typing import Callable

from amaranth import *
from amaranth.hdl import Assert, Assume, Cover, Fragment

__all__ = ["Harness", "SeededBug", "Property", "internal", "internals", "popcount", "component"]


def _targets(value):
    """The signals an assignment to ``value`` drives (a signal, a slice or part of one, a
    concatenation of them), through the values' public properties."""
    if isinstance(value, Signal):
        yield value
    elif hasattr(value, "parts"):                   # Cat(...)
        for part in value.parts:
            yield from _targets(part)
    elif hasattr(value, "value"):                   # a slice, a part
        yield from _targets(value.value)


def _driven(statements):
    for stmt in statements:
        if hasattr(stmt, "lhs"):                    # an assignment
            yield from _targets(stmt.lhs)
        elif hasattr(stmt, "cases"):                # m.If, m.Switch: their cases' statements
            for _patterns, stmts, _src_loc in stmt.cases:
                yield from _driven(stmts)


def internals(fragment: Fragment) -> dict:
    """Every signal a fragment's own statements drive, by name (a name used by two signals maps to
    both), found through the statements' public properties (``lhs``, ``cases``)."""
    found = {}
    for stmts in fragment.statements.values():
        for sig in _driven(stmts):
            found.setdefault(sig.name, {})[id(sig)] = sig
    return {name: list(sigs.values()) for name, sigs in found.items()}


def _subfragment(fragment: Fragment, path) -> Fragment:
    for name in path:
        try:
            fragment = fragment.find_subfragment(name)
        except NameError:
            raise LookupError(f"no sub-module {name!r} on the path {'/'.join(path)}") from None
    return fragment


def internal(fragment: Fragment, *path_and_name: str):
    """The signal named ``name`` in the sub-module at ``path`` below ``fragment``
    (``internal(frag, "front", "skid_valid")``): one that the sub-module drives, else its port of that
    name (an input). Reading it from a harness is a white-box look.

    Raises
    ------
    LookupError
        If there is no such sub-module, or no signal or several signals of that name in it.
    """
    *path, name = path_and_name
    frag = _subfragment(fragment, path)
    sigs = internals(frag).get(name, [])
    if not sigs:
        port = getattr(_origin(frag), name, None)
        if isinstance(port, Signal):
            return port
    if len(sigs) != 1:
        where = "/".join(path) or "the top"
        raise LookupError(f"{len(sigs)} signals named {name!r} in {where} (expected one)")
    return sigs[0]


def _origin(frag: Fragment):
    origins = [o for o in (frag.origins or ()) if hasattr(o, "elaborate")]
    return origins[0] if origins else None


def component(fragment: Fragment, *path: str):
    """The elaboratable (the component object) that the sub-module at ``path`` was elaborated from,
    for its ports (``component(frag, "footprint").o``)."""
    origin = _origin(_subfragment(fragment, path))
    if origin is None:
        raise LookupError(f"sub-module {'/'.join(path)} has no elaboratable origin")
    return origin


def popcount(value) -> Value:
    """The number of set bits of ``value``."""
    value = Value.cast(value)
    width = max(1, len(value).bit_length())
    return sum((value[n].as_unsigned() for n in range(len(value))), C(0, width))


@dataclass(frozen=True)
class SeededBug:
    """A seeded bug: ``assign(signals)`` returns the statements that break the design, as
    ``(domain, statement)`` pairs, appended to the sub-module at ``path`` (below the harness's
    design named ``design``). ``signals(name)`` looks a signal of that sub-module up by name, and
    ``signals(name, "sub", "path")`` one of a sub-module below it."""
    name: str
    text: str
    path: tuple
    assign: Callable
    design: str = "dut"

    def apply(self, fragment: Fragment) -> None:
        target = _subfragment(fragment, self.path)

        def signals(name, *below):
            return internal(target, *below, name)

        for domain, stmt in self.assign(signals):
            target.add_statements(domain, stmt)


class Harness(Elaboratable):
    """A formal harness (see the module docstring). Subclasses implement :meth:`build`.

    Arguments
    ---------
    bug : SeededBug, optional
        The negative control's bug, applied to the design added with :meth:`design` under the
        bug's ``design`` name.

    Attributes
    ----------
    claims : dict
        The number of each ``Assert`` (in its source location, ``file#n:line``) ->
        ``("claim" | "lemma", text)``, filled at elaboration.
    """

    def __init__(self, bug: SeededBug | None = None):
        self.bug = bug
        self.domain = ClockDomain("sync", reset_less=True)
        self.claims = {}

    def ports(self) -> list:
        """The harness's ports: its clock only (every other input is a free value inside)."""
        return [self.domain.clk]

    def elaborate(self, platform):
        m = Module()
        m.domains.sync = self.domain
        self.claims = {}
        try:
            self.build(m, platform)
        except Exception:
            # the half-built module is dropped with the error: elaborate it so that Amaranth does
            # not also warn that it was never used
            with contextlib.suppress(Exception):
                Fragment.get(m, platform)
            raise
        return m

    def build(self, m: Module, platform) -> None:
        raise NotImplementedError

    def design(self, m: Module, name: str, dut, platform=None) -> Fragment:
        """Elaborate ``dut``, apply the seeded bug if it is aimed at ``name``, add it as sub-module
        ``name``; returns its fragment (for :func:`internal` and :func:`component` looks)."""
        fragment = Fragment.get(dut, platform)
        if self.bug is not None and self.bug.design == name:
            self.bug.apply(fragment)
        m.submodules[name] = fragment
        return fragment

    def _record(self, m, kind, cond, text):
        prop = Assert(cond, text, src_loc_at=2)
        # The claim's number rides in its source location (``file#n:line``), which the solver's
        # report of a failed assertion quotes: two claims written on one line stay apart.
        n = len(self.claims)
        prop.src_loc = (f"{prop.src_loc[0]}#{n}", prop.src_loc[1])
        self.claims[n] = (kind, text)
        m.d.comb += prop

    def claim(self, m: Module, cond, text: str) -> None:
        """``Assert(cond)``: part of what the property says."""
        self._record(m, "claim", cond, text)

    def lemma(self, m: Module, cond, text: str) -> None:
        """``Assert(cond)``: a helper invariant that makes the claims inductive. Left out of a
        negative control (a harness with a bug), whose bounded check needs no lemma: the bug must
        break a claim, not a lemma about the design without it."""
        if self.bug is None:
            self._record(m, "lemma", cond, text)

    @staticmethod
    def assume(m: Module, cond) -> None:
        m.d.comb += Assume(cond)

    @staticmethod
    def cover(m: Module, cond) -> None:
        m.d.comb += Cover(cond)


@dataclass(frozen=True)
class Property:
    """One property: what it says, how it is proved and its negative control.

    name : str
        ``stage.what[.variant]``, e.g. ``texel_fetch.order.specialised``.
    stage : str
        The ``hw`` module it is about (``hw/formal/<stage>.py`` holds it).
    text : str
        What it says, one sentence.
    harness : callable
        ``harness(bug)`` -> a :class:`Harness` (``bug`` None: the design as it is).
    method : str
        ``induction`` (k-induction: a proof for every cycle) or ``bmc`` (bounded: every trace of
        ``depth`` cycles from reset).
    depth : int
        k for induction (the base case is checked to the same depth), or the BMC depth.
    bug : SeededBug
        The negative control; ``bug_depth`` is the BMC depth at which the proof must fail with it.
    quick : bool
        In the quick subset (the test suite proves it; ``vqtex verify`` proves every property).
    quick_control : bool
        The test suite runs the negative control (all but a few slow ones that repeat another's
        bug on a larger design; ``vqtex verify`` runs every control).
    """
    name: str
    stage: str
    text: str
    harness: Callable
    method: str
    depth: int
    bug: SeededBug
    bug_depth: int
    quick: bool = False
    quick_control: bool = True

    def __post_init__(self):
        if self.method not in ("induction", "bmc"):
            raise ValueError(f"method must be induction or bmc, not {self.method!r}")
