"""The cocotb testbench that ``vqtex export --testbench DIR`` writes beside the Verilog (docs/verification.md).

``bins`` is the functional-coverage model (numpy: a request's bin, the bins a set can reach);
``tb_texel_fetch`` is the cocotb test module and ``run_tb`` its runner, both copied verbatim into
DIR; ``write`` writes them with the configuration and the texture set.
"""
