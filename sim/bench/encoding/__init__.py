"""The encoders measured: time, memory and error of the codebook designers (docs/benchmarks.md).

:mod:`.encoder` (``vqtex bench encode``: the codebook designer against scikit-learn's KMeans, in one
process and as whole processes against :mod:`.kmeans_process`),
:mod:`.tradeoff` (``vqtex bench tradeoff``: every encoder's time, bits and error over a grid),
:mod:`.mipmaps` (``vqtex bench mip``: extended codewords, averaged against joint training),
:mod:`.scale` (encode time and peak memory against texture size), :mod:`.pvr2_quality` (our PowerVR2
encoder against pvrtex's). Nothing is re-exported here: import the modules.
"""
