"""Reports on the hardware and the compression: where the cycles go (:mod:`.cycles`), area and
timing on an FPGA (:mod:`.synth`: Yosys synthesis, nextpnr place and route for a Lattice ECP5),
the compression error seen as PSNR per level and difference pictures (:mod:`.quality`), the
matplotlib figures (:mod:`.plotting`, the optional ``plot`` extra) and what foveation saves
(:mod:`.foveation`)."""
