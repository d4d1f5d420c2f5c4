"""Lossless depth-range compression of a cropped LDI into one 2D texture (seed 003, slides 13-17).

A texel's layers pair up into depth ranges (S_j, E_j) = (d_2j, d_2j+1), the insides of the
volume along its ray. The texture (RG32UI, `width` texels wide, row-major) holds first the
index segment, one (offset, count) per cropped texel, then the range segment, each range as
the float bits of (S, E). Offset 0 means the texel has no range. A texel with an odd number
of layers (a ray grazing a silhouette) gets E = NIL for its last range, so decompression
still restores every layer exactly.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from .peel import NIL, LayeredDepthImage


@dataclass
class CompressedLDI:
    data: np.ndarray  # uint32 [rows, width, 2]
    depth: int  # layers of the original (for decompression)
    crop: tuple[int, int, int, int]
    size: tuple[int, int]
    ranges: int  # depth ranges stored
    milliseconds: float = 0.0  # time to compress

    @property
    def nbytes(self) -> int:
        """Memory of the packed texture (the seed's M_comp)."""
        return int(self.data.nbytes)


def compress(ldi: LayeredDepthImage, max_width: int = 4096) -> CompressedLDI:
    t0 = time.perf_counter()
    layers = ldi.layers
    d, h, w = layers.shape
    pairs = (d + 1) // 2
    padded = np.full((2 * pairs, h, w), NIL, np.float32)
    padded[:d] = layers
    starts = padded[0::2].transpose(1, 2, 0).reshape(h * w, pairs)  # texel-major, range j within
    ends = padded[1::2].transpose(1, 2, 0).reshape(h * w, pairs)
    present = starts < NIL
    count = present.sum(axis=1).astype(np.uint32)
    first = h * w + np.concatenate([[0], np.cumsum(count)[:-1]]).astype(np.uint32)
    index = np.stack([np.where(count > 0, first, 0).astype(np.uint32), count], -1)
    ranges = np.stack([starts[present], ends[present]], -1).view(np.uint32)
    flat = np.concatenate([index.reshape(-1, 2), ranges.reshape(-1, 2)])
    total = len(flat)
    width = int(min(max_width, max(1, int(np.ceil(np.sqrt(total))))))
    rows = max(1, -(-total // width))
    data = np.zeros((rows * width, 2), np.uint32)
    data[:total] = flat
    return CompressedLDI(
        data.reshape(rows, width, 2), d, ldi.crop, ldi.size, int(count.sum()), (time.perf_counter() - t0) * 1e3
    )


def decompress(comp: CompressedLDI) -> np.ndarray:
    """The layers (float32 [depth, h, w], NIL-filled) back from the packed texture."""
    _, _, w, h = comp.crop
    flat = comp.data.reshape(-1, 2)
    index = flat[: w * h]
    out = np.full((max(comp.depth + 1, 2), h * w), NIL, np.float32)
    count = index[:, 1].astype(np.int64)
    if count.sum():
        texel = np.repeat(np.arange(h * w), count)
        j = np.arange(len(texel)) - np.repeat(np.cumsum(count) - count, count)
        at = np.repeat(index[:, 0].astype(np.int64), count) + j
        values = flat[at].view(np.float32)
        out[2 * j, texel] = values[:, 0]
        out[2 * j + 1, texel] = values[:, 1]
    return out[: comp.depth].reshape(comp.depth, h, w)
