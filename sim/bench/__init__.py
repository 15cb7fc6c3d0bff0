"""Benchmarks that print numbers (``vqtex bench WHAT``) and the paper's experiments (``vqtex experiments``),
grouped by what a reader comes for:

- :mod:`.encoding`: the encoders' time, memory and error (``bench encode``, ``tradeoff``, ``mip``);
- :mod:`.scenes`: frames of the built-in scenes (``bench render``, ``skip``; what the scenes need;
  ``vqtex experiments``: the paper's Tables 3, 4 and 5 and the hardware's trade-off);
- :mod:`.simulators`: how fast the RTL simulates (``bench sim``);
- :mod:`.robustness`: numerical stability and hostile input (``bench stability``);
- :mod:`.codecs`: VQ against BC1, ASTC, JPEG 2000 and a wavelet coder (``bench codecs``);
- :mod:`.sweep`: ``run_jobs``, the independent jobs of a sweep run serially or on dask (used by
  ``tradeoff`` and the experiments).
"""
