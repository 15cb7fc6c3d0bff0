"""ASTC (Adaptive Scalable Texture Compression): every block is 128 bits whatever its footprint, so
the block size sets the rate: 8x8 is 2 bits per texel (the rate of VQ's 2x2 blocks with 8-bit
indices), 12x12 0.89 (about that of 4x4/256 with its codebook). Encoded and decoded by Arm's
astcenc through astc-encoder-py, LDR profile, quality preset ``medium`` (60), one thread (the
library's default).

Blocks are stored row-major, ``ceil(W / bw)`` per row (partial blocks at the right and bottom edges
are coded whole). One random texel costs the decode of its block: the blocks of a batch of texels
are gathered into one strip image and decoded in one call, then each texel is picked from its block.
"""

from __future__ import annotations

import numpy as np

from .measure import best_time, copy_floor, gather_floor, psnr
from .schema import row

__all__ = ["Astc", "rows", "BLOCKS", "QUALITY"]

#: Default block sizes (square footprints).
BLOCKS = (8, 12)
#: astcenc's quality (0..100; its presets: fastest 0, fast 10, medium 60, thorough 98, exhaustive 100).
QUALITY = 60.0
_BLOCK_BYTES = 16


class Astc:
    """An astcenc context for one block footprint (creating one is expensive: reuse it)."""

    def __init__(self, block: int, quality: float = QUALITY):
        from astc_encoder import ASTCConfig, ASTCContext, ASTCProfile, ASTCSwizzle
        self.block = int(block)
        self.context = ASTCContext(ASTCConfig(ASTCProfile.LDR, self.block, self.block, 1, quality))
        self.swizzle = ASTCSwizzle.from_str("RGBA")

    def blocks_per_row(self, width: int) -> int:
        return -(-width // self.block)

    def encode(self, image: np.ndarray) -> bytes:
        """(H, W, 3) uint8 -> ASTC blocks."""
        from astc_encoder import ASTCImage, ASTCType
        h, w = image.shape[:2]
        rgba = np.concatenate([image[..., :3], np.full((h, w, 1), 255, np.uint8)], axis=2)
        return self.context.compress(ASTCImage(ASTCType.U8, w, h, 1, rgba.tobytes()), self.swizzle)

    def decode(self, data: bytes, width: int, height: int) -> np.ndarray:
        """ASTC blocks -> (height, width, 4) uint8 RGBA."""
        from astc_encoder import ASTCImage, ASTCType
        out = ASTCImage(ASTCType.U8, width, height, 1)
        self.context.decompress(data, out, self.swizzle)
        return np.frombuffer(out.data, np.uint8).reshape(height, width, 4)

    def texels(self, data: bytes, width: int, y, x) -> np.ndarray:
        """The texels (y, x), (n, 4) uint8: the n blocks that hold them gathered into a strip of n
        blocks, decoded in one call, each texel picked from its block."""
        b = self.block
        y = np.asarray(y, dtype=np.int64)
        x = np.asarray(x, dtype=np.int64)
        blocks = np.frombuffer(data, np.uint8).reshape(-1, _BLOCK_BYTES)
        k = (y // b) * self.blocks_per_row(width) + x // b
        strip = self.decode(blocks[k].tobytes(), b * len(k), b)           # (b, n*b, 4)
        return strip[y % b, np.arange(len(k)) * b + x % b]


def rows(name: str, image: np.ndarray, *, y, x, repeats: int = 3, blocks=BLOCKS,
         quality: float = QUALITY) -> list[dict]:
    """One row per block footprint."""
    from importlib.metadata import version
    h, w = image.shape[:2]
    out = []
    for b in blocks:
        codec = Astc(b, quality)
        data, enc_s = best_time(lambda: codec.encode(image), repeats)
        dec, dec_s = best_time(lambda: codec.decode(data, w, h), repeats)
        _, rnd_s = best_time(lambda: codec.texels(data, w, y, x), repeats)
        rgb = np.ascontiguousarray(dec[..., :3])
        out.append(row(method="astc", config=f"{b}x{b} q{quality:g}", image=name,
                       bits_per_texel=len(data) * 8 / (w * h), psnr_db=psnr(image, dec), encode_s=enc_s,
                       decode_s=dec_s, random_texel_s=rnd_s / len(y), floor_s=copy_floor(rgb, repeats),
                       random_floor_s=gather_floor(rgb, y, x, repeats),
                       random_texel=f"astcenc: the texel's block, {len(y)} blocks gathered and decoded in one call",
                       library=f"astc-encoder-py {version('astc-encoder-py')} (astcenc), LDR, 1 thread",
                       width=w, height=h))
    return out
