"""Codebook design for the VQ texture encoder: full-search nearest codeword, the paper's
tree-structured VQ (TSVQ) and the generalized Lloyd algorithm (GLA).

numpy and the standard library only (``golden`` is the executable specification).

Where things live
-----------------
One algorithm per module, each with its contract at the top; no module is named like a function
the package exports, so every module stays importable.

* :mod:`.inputs`   input checks, deduplication of identical vectors (``unique_weighted``)
* :mod:`.screen`   the float32 GEMM screening (one chunked matmul-and-argmax loop, its chunks
                   on the worker threads) and exact float64 distances
* :mod:`.workers`  the encoder's worker threads (``VQTEX_THREADS``; output independent of them)
* :mod:`.fullsearch` exact full-search nearest codeword (``nearest``)
* :mod:`.split`    splitting TSVQ cells (one, or a padded group at once); :mod:`.tree` the
                   greedy tree (``tsvq``, ``tsvq_tree``, ``TsvqTree``)
* :mod:`.cells`    per-cell sums, their updates and the repair of empty cells
* :mod:`.bounds`   reassignment under Hamerly/Elkan bounds (the Lloyd step's search)
* :mod:`.lloyd`    the generalized Lloyd algorithm (``gla``, ``GlaResult``) and ``design``

Conventions shared by every function here
-----------------------------------------
* ``vectors`` is a float array ``(N, d)`` (any real dtype; it is read as float64), N >= 1, finite.
  Blocks of texels flattened row-major are the usual input (d = 12 for 2x2 RGB, 48 for 4x4 RGB...).
* ``weights`` (optional) is ``(N,)``, finite, >= 0, with a positive sum.  A weight multiplies the
  vector's squared error in every distortion sum; identical vectors are merged internally and their
  weights added (so passing duplicates or their count as weight is the same problem).
  Vectors of weight 0 take no part in training but still get an index.
* Codebooks are ``(k, d)`` float64; indices are int64 ``(N,)``.
* Distances are squared Euclidean distances.  ``nearest`` minimises the true distance of the
  float64 values (the sum of squared differences in exact arithmetic; ties go to the lowest
  index) and reports it rounded to float64.  Inner loops screen candidates with a float32 GEMM
  (||x||^2 - 2 x.c + ||c||^2 form, on mean-centred data, in chunks of about 2 MiB of scores),
  compare them in float64 and settle what float64 cannot order in Python integers.  The Lloyd
  iterations' moves use the float64 distances (a move must lower it strictly).
* Everything is deterministic: the same inputs and seed give the same output bits run to run,
  on any number of worker threads (:mod:`.workers`).  ``nearest`` is moreover independent of the BLAS; the designed codebooks can differ between
  BLAS builds (the float32 screening steers which near-tie a Lloyd iteration resolves first).
* Degenerate inputs: when there are at most k distinct vectors (of positive weight) every design
  function returns all of them, exactly, followed by repeats (``np.resize`` order) up to k rows;
  the distortion is then 0.
"""
from __future__ import annotations

from .lloyd import GlaResult, design, gla
from .inputs import unique_weighted
from .fullsearch import nearest
from .tree import TsvqTree, tsvq, tsvq_tree

__all__ = [
    "nearest",
    "tsvq",
    "tsvq_tree",
    "TsvqTree",
    "gla",
    "GlaResult",
    "design",
    "unique_weighted",
]
