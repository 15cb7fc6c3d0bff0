"""Reports on the hardware: where the cycles go (:mod:`.cycles`) and area and timing on an FPGA
(:mod:`.synth`: Yosys synthesis, nextpnr place and route for a Lattice ECP5)."""
