"""The paper's Tables 3 and 4, row for row: the encoding configurations and the paper's figures.

Beers, Agrawala and Chaddha, *Rendering from Compressed Textures* (SIGGRAPH 1996):

- **Table 3** is the *town* scene: every texture mipmapped; the RGB textures are encoded as each row
  says, the one-channel textures with a codebook of 256 2x2 codewords, the RGBA textures with one of
  256 2x2 codewords.
- **Table 4** is *topspin*, 50 frames: three textures (wood, marble, the top).

A row is a :class:`Row`: its sampling (point or trilinear mipmapping) and its codebooks. A codebook
is a :class:`Codebook`: the scene texture groups it serves, its size K, block and colour format, and
``separate`` (one codebook of those settings *per texture* of the groups, the paper's "separate").
Each "+" in the paper's row names a codebook of its own: "signs and roads 256 2x2 YUV + other
4096 4x4 YUV" is two codebooks, the first shared by every sign and road texture. Index maps are
ceil(log2 K) bits wide (7 bits for K = 128, 10 for 1024), as the paper stores them.

Scene groups: ``town-paper`` has signs, roads, other (RGB), grey (one-channel), cutouts (RGBA);
``topspin-paper`` has floor (the wood), marble and top.

Our own rows follow the paper's (:data:`TABLE3_OURS`, :data:`TABLE4_OURS`).
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Codebook", "Row", "TABLE3_SCENE", "TABLE4_SCENE", "TABLE3_PAPER", "TABLE4_PAPER",
           "TABLE3_OURS", "TABLE4_OURS", "describe"]

TABLE3_SCENE = "town-paper"
TABLE4_SCENE = "topspin-paper"


@dataclass(frozen=True)
class Codebook:
    """One codebook (or, with ``separate``, one per texture) over the scene groups ``groups``."""

    groups: tuple[str, ...]
    codebook_size: int
    block: str                      # "4x4", "2x2"
    color: str                      # "rgb", "yuv411", "intensity", "rgba"
    separate: bool = False
    index_bits: int | None = None   # None: ceil(log2 K), the paper's


@dataclass(frozen=True)
class Row:
    """One configuration of a table; ``paper`` is (overall rate, frame MSE) as the paper prints them."""

    label: str
    sampling: str                   # "point" | "trilinear"
    codebooks: tuple[Codebook, ...]
    paper: tuple[float, float] | None = None

    @property
    def mipmaps(self) -> bool:
        return self.sampling == "trilinear"


RGB_TOWN = ("signs", "roads", "other")
#: Table 3's fixed part: one-channel textures 256 2x2, RGBA 256 2x2.
_TOWN_REST = (Codebook(("grey",), 256, "2x2", "intensity"), Codebook(("cutouts",), 256, "2x2", "rgba"))

TABLE3_PAPER = (
    Row("all RGB: 4096 4x4 RGB", "trilinear",
        (Codebook(RGB_TOWN, 4096, "4x4", "rgb"),) + _TOWN_REST, (11.8, 12.12)),
    Row("all RGB: 4096 4x4 YUV", "trilinear",
        (Codebook(RGB_TOWN, 4096, "4x4", "yuv411"),) + _TOWN_REST, (15.3, 16.17)),
    Row("signs and roads 256 2x2 YUV + other 4096 4x4 YUV", "trilinear",
        (Codebook(("signs", "roads"), 256, "2x2", "yuv411"), Codebook(("other",), 4096, "4x4", "yuv411"))
        + _TOWN_REST, (12.7, 11.27)),
    Row("signs 256 2x2 YUV + roads and other 256 4x4 YUV", "trilinear",
        (Codebook(("signs",), 256, "2x2", "yuv411"), Codebook(("roads", "other"), 256, "4x4", "yuv411"))
        + _TOWN_REST, (24.5, 16.19)),
)

_ALL_TOWN = RGB_TOWN + ("grey", "cutouts")
#: Our rows for the town: how codebook sharing trades rate for error (K = 256 and 1024, 4x4 RGB for
#: the RGB textures, Table 3's codebooks for the others).
TABLE3_OURS = tuple(
    Row(f"{label}: {k} 4x4 RGB", "trilinear", cbs)
    for k in (256, 1024)
    for label, cbs in (
        ("one codebook per texture", (Codebook(RGB_TOWN, k, "4x4", "rgb", separate=True),) + _TOWN_REST),
        ("signs + roads + other", tuple(Codebook((g,), k, "4x4", "rgb") for g in RGB_TOWN) + _TOWN_REST),
    )
)

_TOP = ("floor", "marble", "top")
TABLE4_PAPER = (
    Row("wood and marble 128 4x4 YUV + top 128 2x2 YUV, point", "point",
        (Codebook(("floor", "marble"), 128, "4x4", "yuv411"), Codebook(("top",), 128, "2x2", "yuv411")),
        (34.7, 34.7)),
    Row("wood and marble 256 4x4 YUV + top 256 2x2 YUV, point", "point",
        (Codebook(("floor", "marble"), 256, "4x4", "yuv411"), Codebook(("top",), 256, "2x2", "yuv411")),
        (28.3, 19.1)),
    Row("all 256 2x2 YUV, point", "point", (Codebook(_TOP, 256, "2x2", "yuv411"),), (11.5, 37.9)),
    Row("separate 256 4x4 RGB, mipmap", "trilinear", (Codebook(_TOP, 256, "4x4", "rgb", separate=True),),
        (17.6, 14.2)),
    Row("separate 1024 4x4 RGB, mipmap", "trilinear", (Codebook(_TOP, 1024, "4x4", "rgb", separate=True),),
        (8.0, 13.3)),
)

#: Our rows for topspin: a codebook per texture, K = 256, block x colour x sampling (the one the
#: paper has, separate 256 4x4 RGB mipmap, is left out).
TABLE4_OURS = tuple(
    Row(f"separate 256 {block} {'YUV' if color == 'yuv411' else 'RGB'}, {'mipmap' if mode == 'trilinear' else 'point'}",
        mode, (Codebook(_TOP, 256, block, color, separate=True),))
    for mode in ("point", "trilinear") for color in ("rgb", "yuv411") for block in ("2x2", "4x4")
    if (mode, color, block) != ("trilinear", "rgb", "4x4")
)


def describe(row: Row) -> str:
    """The row's codebooks in one line: ``signs+roads 256 2x2 yuv411; other 4096 4x4 yuv411; ...``."""
    return "; ".join(f"{'+'.join(c.groups)} {c.codebook_size} {c.block} {c.color}"
                     + (" (one per texture)" if c.separate else "") for c in row.codebooks)
