"""The row every codec reports (one per method, configuration and image), shared with the encoder
trade-off bench.

Fields (:data:`FIELDS`; every row has every one, ``None`` where a field does not apply):

=====================  =================================================================================
``method``             ``vq``, ``bc1``, ``astc``, ``jpeg2000``, ``wavelet``
``config``             the configuration, e.g. ``2x2/256 rgb``, ``etcpak``, ``8x8 medium``,
                       ``untiled @2x2/256 rgb`` (a rate-targeted codec names the VQ row whose rate it hit)
``image``              the image's name
``bits_per_texel``     every stored bit over the texels: VQ counts index bits plus the whole codebook
                       (the paper's count, one codebook per image here); BC1 and ASTC the blocks;
                       JPEG 2000 the whole codestream (headers included); wavelets the entropy model's bits
``psnr_db``            PSNR over R, G, B of the decoded image (uint8) against the image; ``None`` when
                       they are equal (lossless: JSON has no infinity)
``encode_s``           wall seconds to compress the image (best of ``repeats``)
``decode_s``           wall seconds to decode the whole image into an (H, W, 3|4) uint8 array
``random_texel_s``     wall seconds for one random texel, amortised over a batch (``random_texel`` says how)
``floor_s``            the physical floor of ``decode_s``: copying the decoded bytes once
``random_floor_s``     the physical floor of ``random_texel_s``: reading the same random texels from the
                       decoded array (numpy fancy indexing), per texel
``random_texel``       how ``random_texel_s`` was measured (the work one random texel costs)
``library``            what encoded and decoded
``target_bits_per_texel``  the rate a rate-controlled codec aimed at (the VQ row's ``bits_per_texel``)
``index_bits_per_texel``   VQ only: the index map alone (without the codebook)
``width``, ``height``  the image's size
=====================  =================================================================================
"""

from __future__ import annotations

import math

__all__ = ["FIELDS", "row"]

FIELDS = ("method", "config", "image", "bits_per_texel", "psnr_db", "encode_s", "decode_s",
          "random_texel_s", "floor_s", "random_floor_s", "random_texel", "library",
          "target_bits_per_texel", "index_bits_per_texel", "width", "height")


def row(**fields) -> dict:
    """A row with every field of :data:`FIELDS` (missing ones ``None``); unknown fields are an error."""
    extra = set(fields) - set(FIELDS)
    if extra:
        raise ValueError(f"unknown row fields {sorted(extra)}")
    out = {k: fields.get(k) for k in FIELDS}
    for k in ("bits_per_texel", "psnr_db", "encode_s", "decode_s", "random_texel_s", "floor_s",
              "random_floor_s", "target_bits_per_texel", "index_bits_per_texel"):
        if out[k] is not None:
            out[k] = float(out[k])
    if out["psnr_db"] is not None and not math.isfinite(out["psnr_db"]):
        out["psnr_db"] = None
    return out
