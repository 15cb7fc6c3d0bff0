"""Colour matrix: raw samples -> RGBA8888.

Twin of :func:`golden.fetch.convert_color` and :meth:`golden.color.ColorMatrix.apply`. One
parameterised fixed-point 3x3 matrix serves every YUV decode::

    out_c = clamp(((sum_k M[c][k] * (in_k - off_k)) + bias) >> F, 0, 255)

(any signed coefficients, offsets, ``F`` and rounding: full-range BT.601 and the Dreamcast YUV422
decode are two instances). rgb, rgba and intensity samples bypass the matrix:
rgb -> (R, G, B, 255), intensity -> (I, I, I, 255), rgba unchanged.
"""

from __future__ import annotations

from amaranth import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from vqtex.golden.color import ColorMatrix as ColorMatrixSpec
from vqtex.golden.format import COLOR_CODES
from vqtex.golden.register_map import COEFF_BITS, CONTROL, REGIONS

from .bus_port import ANSWER_LATENCY, delayed

from .codebook_rom import SamplesLayout

__all__ = ["ColorMatrix", "LATENCY"]

#: Cycles from samples to RGBA.
LATENCY = 3
#: The loaded matrix's widths: a product of an 8-bit sample and an 18-bit coefficient, and the sum
#: of three products and ``K`` (``ColorMatrix._loaded_sums``).
_LOADED_PRODUCT_BITS = COEFF_BITS + 8
_LOADED_SUM_BITS = COEFF_BITS + 12

_RGB, _RGBA, _I8, _YUV = (COLOR_CODES[c] for c in ("rgb", "rgba", "intensity", "yuv411"))


class ColorMatrix(wiring.Component):
    """The colour matrix with its bypass.

    1. *offset*: ``x_k = in_k - off_k`` (signed 9 bits; an offset of 128 is the top bit inverted,
       0 is nothing), registered.
    2. *multiply*: the nine products ``M[c][k] * x_k`` (``matrix.product_bits`` signed bits each,
       constant multipliers: a MULT18X18D between flip-flops, or shifts and adds), registered.
    3. *sum*: per output ``sum_k p[c][k] + bias`` (``matrix.sum_bits`` signed bits), arithmetic
       shift right by ``F``, clamp to 0..255 (by bit tests); or the bypass expansion; registered.

    Latency 3 (every stage advances when ``en`` is high). Throughput: one texel per cycle.

    The products exist only for non-zero coefficients; a coefficient +-2^n (+-1 included) is a
    shift (and a negation), not a multiplier. Given ``colors`` (the colour codes that can arrive),
    the output multiplexer has only their cases, and without yuv411 there is no offset, product or
    sum at all: the three stages are plain registers of the samples (the latency stays 3).

    Loadable (``load``): the coefficients (18-bit signed), offsets (8 bits), ``F`` (5 bits) and the
    rounding bit are registers the host writes over the bus port (control region, offsets
    ``golden.register_map.CONTROL``), initialised from ``matrix`` and kept through a reset (they
    are contents, not pipeline state); all nine products are 18 x 9-bit multipliers; stage 3 keeps
    8 bits of the sum shifted by ``F``, clamping from a registered mask. Same latency, throughput.

    Arguments
    ---------
    matrix : golden.color.ColorMatrix
        Coefficients, offsets, fractional bits and rounding (a loadable matrix's initial value).
    colors : iterable of int, optional
        Colour codes of the samples that can arrive (default: all four).
    load : data.StructLayout, optional
        The bus port's load command (:func:`hw.bus_port.load_layout`): the matrix is loadable;
        members ``load`` and ``load_data`` (this matrix's read answer).

    Members
    -------
    samples : In(SamplesLayout)
        (Y, U, V, -) for yuv411, else the texel's bytes (see :func:`golden.fetch.read_codeword`).
    color : In(2)
        Colour format code of the samples.
    en : In(1)
        Pipeline advance.
    rgba : Out(SamplesLayout)
        R, G, B, A, registered.

    Raises
    ------
    TypeError
        If ``matrix`` is not a :class:`golden.color.ColorMatrix`.
    """

    def __init__(self, matrix: ColorMatrixSpec, *, colors=None, load=None):
        if not isinstance(matrix, ColorMatrixSpec):
            raise TypeError(f"matrix must be a golden.color.ColorMatrix, not {type(matrix).__name__}")
        self._matrix = matrix
        self._all = colors is None          # the full unit: every format, all nine products
        self._colors = frozenset(range(4)) if colors is None else frozenset(int(c) for c in colors)
        if not self._colors or not self._colors <= set(range(4)):
            raise ValueError(f"colour codes {sorted(self._colors)} must be a non-empty subset of 0..3")
        self._load = load
        super().__init__({
            "samples": In(SamplesLayout),
            "color": In(2),
            "en": In(1),
            "rgba": Out(SamplesLayout),
            **({} if load is None else {"load": In(load), "load_data": Out(32)}),
        })

    @property
    def matrix(self) -> ColorMatrixSpec:
        return self._matrix

    @property
    def latency(self) -> int:
        return LATENCY

    def _registers(self, m) -> dict:
        """The loadable matrix's registers (reset-less, initialised from the matrix), their bus
        writes, and this block's read answer: name -> register (``coeff`` a 3x3 list)."""
        mat = self._matrix
        load = self.load
        regs = {"coeff": [[Signal(signed(COEFF_BITS), name=f"m_{'rgb'[c]}{'yuv'[k]}", init=mat.coeffs[c][k],
                                  reset_less=True) for k in range(3)] for c in range(3)],
                "offset": [Signal(8, name=f"off_{'yuv'[k]}", init=mat.offsets[k], reset_less=True) for k in range(3)],
                "frac": Signal(5, name="frac_bits", init=mat.frac_bits, reset_less=True),
                "rounding": Signal(1, name="rounding", init=int(mat.rounding), reset_less=True)}
        by_offset = {}
        for c in range(3):
            for k in range(3):
                by_offset[CONTROL[f"MATRIX_{'RGB'[c]}{'YUV'[k]}"][0]] = regs["coeff"][c][k]
        for k in range(3):
            by_offset[CONTROL[f"MATRIX_OFFSET_{'YUV'[k]}"][0]] = regs["offset"][k]
        by_offset[CONTROL["MATRIX_FRAC_BITS"][0]] = regs["frac"]
        by_offset[CONTROL["MATRIX_ROUNDING"][0]] = regs["rounding"]
        # The command decoded into registers of this block's own first (a write strobe and a read
        # select per register, and the data): the compare and its fan-out to the registers' enables
        # start from flip-flops (the load command's offset -> compare -> the coefficient registers'
        # clock enables was the topspin geometry's critical path, docs/area.md). A write lands one
        # cycle later than the command (K follows 3 cycles after it; the drain rule keeps every
        # request further behind), a read's answer keeps ANSWER_LATENCY.
        mine = load.region == REGIONS["control"]
        offsets = list(by_offset)
        writes = Signal(len(offsets), name="matrix_write")
        reads = Signal(len(offsets), name="matrix_read")
        wdata = Signal(max(len(r) for r in by_offset.values()), name="matrix_data")
        m.d.sync += [
            writes.eq(Cat(*(load.write & mine & (load.offset == off) for off in offsets))),
            reads.eq(Cat(*(load.read & mine & (load.offset == off) for off in offsets))),
            wdata.eq(load.data[:len(wdata)]),
        ]
        answer = Signal(32, name="matrix_answer")
        m.d.sync += answer.eq(0)
        for n, reg in enumerate(by_offset.values()):
            with m.If(writes[n]):
                m.d.sync += reg.eq(wdata[:len(reg)])
            with m.If(reads[n]):                        # coefficients read back sign-extended
                m.d.sync += answer.eq(reg.as_signed() if reg.shape().signed else reg)
        m.d.comb += self.load_data.eq(delayed(m, answer, ANSWER_LATENCY - 3, name="matrix_answer"))
        return regs

    def _loaded_sums(self, m, regs) -> list:
        """Stages 1 and 2 of the loaded matrix: the three sums, registered (``sum_r``, ``sum_g``,
        ``sum_b``, ``COEFF_BITS + 12`` signed bits, bias included).

        The sum is rearranged so that no stage holds more than one multiplication or one addition
        of four terms (150 MHz on an ECP5 with the shift by a loaded ``F`` in stage 3)::

            sum_k M[c][k] * (in_k - off_k) + bias  ==  sum_k M[c][k] * in_k + K[c],
            K[c] = bias - sum_k M[c][k] * off_k

        an identity of integers, so the result equals the offset-first order bit for bit.

        1. the nine products ``M[c][k] * in_k`` (8-bit unsigned samples, 18-bit signed
           coefficients), registered;
        2. per output, the three products plus ``K[c]``, registered.

        ``K`` depends only on the loaded registers: its own two-stage pipeline (the nine
        ``M * off`` registered, then ``bias - sum`` registered) runs every cycle, so it holds the new
        value 3 cycles after the host's last write of a matrix register. The bus port's drain rule
        (no request is accepted while a transfer is under way) and the 11 stages in front of the
        colour matrix put every request after the load well behind that.
        """
        mat = self._matrix
        coeff, offset, frac, rounding = regs["coeff"], regs["offset"], regs["frac"], regs["rounding"]
        pbits, sbits = _LOADED_PRODUCT_BITS, _LOADED_SUM_BITS
        # K's pipeline, initialised to the initial matrix's K (a unit that is never loaded is right
        # from the first cycle).
        q = [[Signal(signed(pbits), name=f"q_{'rgb'[c]}{'yuv'[k]}", reset_less=True,
                     init=mat.coeffs[c][k] * mat.offsets[k]) for k in range(3)] for c in range(3)]
        bias = Signal(17, name="bias", reset_less=True, init=mat.bias)
        konst = [Signal(signed(sbits), name=f"k_{'rgb'[c]}", reset_less=True,
                        init=mat.bias - sum(mat.coeffs[c][k] * mat.offsets[k] for k in range(3))) for c in range(3)]
        # bias 2^(F-1) when rounding and F > 0
        m.d.sync += bias.eq(Mux(rounding & (frac != 0), C(1, 17) << (frac - 1)[:4], 0))
        for c in range(3):
            for k in range(3):
                m.d.sync += q[c][k].eq(coeff[c][k] * offset[k])
            m.d.sync += konst[c].eq(bias - q[c][0] - q[c][1] - q[c][2])
        prod = [[Signal(signed(pbits), name=f"p_{'rgb'[c]}{'yuv'[k]}") for k in range(3)] for c in range(3)]
        acc = [Signal(signed(sbits), name=f"sum_{'rgb'[c]}") for c in range(3)]
        with m.If(self.en):
            for c in range(3):
                for k in range(3):
                    m.d.sync += prod[c][k].eq(self.samples[k] * coeff[c][k])
                m.d.sync += acc[c].eq(prod[c][0] + prod[c][1] + prod[c][2] + konst[c])
        return acc

    def _loaded_shift(self, m, regs) -> tuple:
        """What stage 3 of the loaded matrix needs of ``F``, as registers that follow the loaded
        ``F`` one cycle (or a few) later, as ``K`` does: a copy of ``F`` per output channel, in a
        chain (``F`` -> red -> green -> blue; copies with one source would be merged back into
        one by Yosys), so that each channel's 8-bit shift select has a driver of its own (the
        loaded ``F`` fanned out to all three barrel shifters was the topspin geometry's critical
        net, docs/area.md); and ``above_mask``, the bits of a sum at or above ``F + 8`` (below
        its sign bit): a sum that is not negative clamps to 255 when any of them is set.
        Returns ``(copies, above_mask)``. All of them settle within 3 cycles of the last write of
        ``F`` (the drain rule keeps every request further behind)."""
        mat = self._matrix
        sbits = _LOADED_SUM_BITS
        frac = regs["frac"]
        copies = []
        source = frac
        for c in range(3):
            copy = Signal(5, name=f"frac_{'rgb'[c]}", init=mat.frac_bits, reset_less=True)
            m.d.sync += copy.eq(source)
            copies.append(copy)
            source = copy
        full = (1 << (sbits - 1)) - 1
        above_mask = Signal(sbits - 1, name="above_mask", reset_less=True,
                            init=(full << (mat.frac_bits + 8)) & full)
        m.d.sync += above_mask.eq((C(full, sbits - 1) << (frac + 8))[:sbits - 1])
        return copies, above_mask

    def elaborate(self, platform):
        m = Module()
        mat = self._matrix
        pbits, sbits, F = mat.product_bits, mat.sum_bits, mat.frac_bits
        colors = self._colors
        matrix = _YUV in colors
        one = len(colors) == 1              # one format: no multiplexer, no format carried
        # Input k is offset iff it feeds a product (some coefficient of its column is non-zero).
        used = [matrix and (self._all or any(mat.coeffs[c][k] for c in range(3))) for k in range(3)]
        regs = None
        if self._load is not None:          # registers: every product, every width at its largest
            regs = self._registers(m)
            used = [False] * 3              # the samples go straight into the multipliers (_loaded_sums)
            sbits = _LOADED_SUM_BITS

        # Stage 1: offsets, registered (the multipliers' operands come straight from flip-flops).
        x = [Signal(signed(9), name=f"x{k}") for k in range(3)]
        # The samples and their format ride beside, one register per stage (one update each).
        carried_r = Signal(len(self.samples.as_value()) + (0 if one else 2), name="carried_r")
        with m.If(self.en):
            for k in range(3):
                if not used[k]:
                    continue
                sample, off = self.samples[k], mat.offsets[k]
                if off == 0:
                    m.d.sync += x[k].eq(sample)
                elif off == 128:        # in - 128: the top bit inverted, read as signed (no adder)
                    m.d.sync += x[k].eq(Cat(sample[:7], ~sample[7]).as_signed())
                else:
                    m.d.sync += x[k].eq(sample - off)
            m.d.sync += carried_r.eq(Cat(self.samples, self.color if not one else C(0, 0)))
        if regs is not None and matrix:
            loaded_sums = self._loaded_sums(m, regs)
            frac_copies, above_mask = self._loaded_shift(m, regs)

        # Stage 2: constant multiplications (the full unit: all nine, the synthesis tool folds the
        # constants; specialised: only the non-zero ones, powers of two as shifts).
        prod = [[Signal(signed(pbits), name=f"p_{'rgb'[c]}{'yuv'[k]}") for k in range(3)] for c in range(3)]
        carried_p = Signal.like(carried_r, name="carried_p")
        with m.If(self.en):
            for c in range(3):
                for k in range(3):
                    coeff = mat.coeffs[c][k]
                    if regs is not None or not matrix or (coeff == 0 and not self._all):
                        continue                # no product (the loaded matrix's are in _loaded_sums)
                    if not self._all and abs(coeff) & (abs(coeff) - 1) == 0:   # +-2^n: a shift
                        power = x[k] << (abs(coeff).bit_length() - 1)
                        m.d.sync += prod[c][k].eq(power if coeff > 0 else -power)
                    else:
                        m.d.sync += prod[c][k].eq(x[k] * C(coeff, signed(19)))
            m.d.sync += carried_p.eq(carried_r)
        samples_p = SamplesLayout(carried_p[:32])
        color_p = carried_p[32:] if not one else C(next(iter(colors)), 2)

        # Stage 3: sum + bias, shift, clamp; or bypass.
        acc = [Signal(signed(sbits), name=f"sum_{'rgb'[c]}") for c in range(3)]
        # The shift's own width (a constant shift keeps sbits - F bits): no extra copies of the sign
        # bit, which an exported netlist would write as a vector assigned from its own top bit (a
        # combinational loop to Verilator, UNOPTFLAT). The clamp below reads the same bits either way.
        # (at least 10 bits: the clamp tests bits 8 and up; a matrix whose sums are that narrow after
        # the shift is rare)
        swidth = max(sbits, 10) if regs is not None else max(sbits - F, 10)
        if regs is not None and matrix:
            acc = loaded_sums
        shifted = [Signal(signed(swidth), name=f"shifted_{'rgb'[c]}") for c in range(3)]
        conv = [Signal(8, name=f"conv_{'rgb'[c]}") for c in range(3)]
        for c in range(3):
            if not matrix:
                break
            negative = Signal(name=f"negative_{'rgb'[c]}")
            above = Signal(name=f"above_{'rgb'[c]}")
            if regs is not None:
                # The registered sum (bias included) shifted by the loaded F, without a barrel
                # shifter of the whole sum: the clamp needs the sign (an arithmetic shift keeps
                # it), whether a bit at or above F + 8 is set (the sum masked by ``above_mask``),
                # and the 8 bits at F (a shift of the sum as unsigned by this channel's copy of F,
                # 8 bits of it kept). Past the sum's top they read 0: only a sum that is not
                # negative uses them.
                total = acc[c].as_unsigned()
                m.d.comb += [
                    negative.eq(acc[c][-1]),
                    above.eq((total[:-1] & above_mask).any()),
                    shifted[c][:8].eq((total >> frac_copies[c])[:8]),
                ]
            else:
                terms = [prod[c][k] for k in range(3) if self._all or mat.coeffs[c][k]]
                total = terms[0] if terms else C(0, 1)
                for term in terms[1:]:
                    total = total + term
                m.d.comb += [
                    acc[c].eq(total + mat.bias),
                    shifted[c].eq(acc[c] >> F),
                ]
                # Clamp by bit tests (no comparator): negative is the sign bit, above 255 is any
                # bit between bit 8 and the sign set.
                m.d.comb += [
                    negative.eq(shifted[c][-1]),
                    above.eq(shifted[c][8:-1] != 0),
                ]
            with m.If(negative):
                m.d.comb += conv[c].eq(0)
            with m.Elif(above):
                m.d.comb += conv[c].eq(255)
            with m.Else():
                m.d.comb += conv[c].eq(shifted[c][:8])

        s = samples_p
        out = Signal(SamplesLayout)
        expand = {_YUV: Cat(conv[0], conv[1], conv[2], C(255, 8)), _I8: Cat(s[0], s[0], s[0], C(255, 8)),
                  _RGB: Cat(s[0], s[1], s[2], C(255, 8)), _RGBA: s.as_value()}
        present = [code for code in (_YUV, _I8, _RGB, _RGBA) if code in colors]
        if one:
            m.d.comb += out.eq(expand[present[0]])
        else:
            # Each format's bytes where its decoded code holds, else 0 (the last format: where no
            # other code holds), ORed: the AND-OR a multi-way multiplexer is in the fabric; a
            # simulator selects each by its own condition where it branched on the format (random
            # per texel: Verilator's model about 3 ns a cycle faster than with a case statement,
            # docs/simulation.md).
            hits = [color_p == code for code in present[:-1]]
            hits.append(~Cat(*hits).any())
            value = 0
            for hit, code in zip(hits, present):
                value = value | Mux(hit, expand[code], 0)
            m.d.comb += out.eq(value)
        with m.If(self.en):
            m.d.sync += self.rgba.eq(out)
        return m
