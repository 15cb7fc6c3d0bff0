"""Benchmarks that print numbers (``vqtex bench WHAT``) and the paper's experiments (``vqtex experiments``).

:mod:`.encoder` (the codebook designer against KMeans), :mod:`.mipmaps` (extended codewords),
:mod:`.simulation` (cycles per second of each backend), :mod:`.render` (frames and cycles per scene),
:mod:`.experiments` (the paper's Tables 3, 4 and 5), :mod:`.codecs` (VQ against BC1, ASTC, JPEG 2000 and a
wavelet coder: bits, PSNR, decode time and the cost of one random texel).
"""
