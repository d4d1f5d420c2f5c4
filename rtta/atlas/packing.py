"""Atlas packing: rectangles into layers of at most (Tw_max, Th_max).

`pack_shelves` is next-fit-decreasing-height shelf packing, vectorised with numpy:
one sort (O(n log n)) plus one binary search per shelf and per layer, so it runs every
frame for thousands of objects. `rtta bench packing` compares it with rectpack
(MaxRects) and rectangle-packer; BENCHMARKS.md has the evidence for choosing it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class Packing:
    x: np.ndarray        # int64 [n] lower-left corner in texels
    y: np.ndarray
    layer: np.ndarray    # int64 [n]
    width: int           # used atlas width  (T_w)
    height: int          # used atlas height (T_h)
    layers: int          # T_d

    @property
    def size(self) -> tuple[int, int, int]:
        return self.width, self.height, self.layers


def _breaks(cum: np.ndarray, sizes: np.ndarray, limit: int) -> np.ndarray:
    """Start indices of greedy runs of `sizes` (cumsum `cum`) whose sum stays <= limit: the
    end of a run from every index in one vectorised search, then one hop per run."""
    nxt = cum.searchsorted(cum - sizes + limit, side="right")   # where a run from each index ends
    starts = []
    n = len(sizes)
    i = 0
    while i < n:
        starts.append(i)
        j = int(nxt[i])
        i = j if j > i else i + 1
    return np.asarray(starts, np.int64)


def _decreasing_order(w: np.ndarray, h: np.ndarray) -> np.ndarray:
    """np.lexsort((-w, -h)) (tallest first, then widest, then by index), as two stable
    16-bit sorts when the sizes allow (numpy sorts those by radix: about 10x faster at 10^5)."""
    top = max(int(w.max()), int(h.max()))
    if top >= 1 << 16:
        return np.lexsort((-w, -h))
    by_w = np.argsort((top - w).astype(np.uint16), kind="stable")
    return by_w[np.argsort((top - h[by_w]).astype(np.uint16), kind="stable")]


def pack_shelves(w: np.ndarray, h: np.ndarray, max_w: int, max_h: int) -> Packing:
    """Pack w x h rectangles (each <= max_w x max_h) into shelves and layers."""
    w = np.asarray(w, np.int64)
    h = np.asarray(h, np.int64)
    n = len(w)
    if n == 0:
        z = np.zeros(0, np.int64)
        return Packing(z, z, z, 0, 0, 0)
    if (w > max_w).any() or (h > max_h).any() or (w < 1).any() or (h < 1).any():
        raise ValueError("rectangles must be between 1x1 and the atlas size")
    order = _decreasing_order(w, h)       # tallest first, then widest
    ws, hs = w[order], h[order]
    cum = np.cumsum(ws)
    shelf_start = _breaks(cum, ws, max_w)
    shelf_of = np.repeat(np.arange(len(shelf_start)), np.diff(np.append(shelf_start, n)))
    xs = cum - ws - (cum[shelf_start] - ws[shelf_start])[shelf_of]
    shelf_h = hs[shelf_start]
    shelf_w = np.add.reduceat(ws, shelf_start)
    cum_h = np.cumsum(shelf_h)
    layer_start = _breaks(cum_h, shelf_h, max_h)
    layer_of_shelf = np.repeat(np.arange(len(layer_start)),
                               np.diff(np.append(layer_start, len(shelf_h))))
    shelf_y = cum_h - shelf_h - (cum_h[layer_start] - shelf_h[layer_start])[layer_of_shelf]
    layer_h = np.add.reduceat(shelf_h, layer_start)
    x = np.empty(n, np.int64)
    y = np.empty(n, np.int64)
    layer = np.empty(n, np.int64)
    x[order] = xs
    y[order] = shelf_y[shelf_of]
    layer[order] = layer_of_shelf[shelf_of]
    return Packing(x, y, layer, int(shelf_w.max()), int(layer_h.max()), len(layer_start))


def overlaps(p: Packing, w: np.ndarray, h: np.ndarray) -> bool:
    """True if any two packed rectangles in the same layer overlap (O(n^2), for tests)."""
    for a in range(len(w)):
        same = (p.layer == p.layer[a]) & (np.arange(len(w)) > a)
        ox = (p.x[a] < p.x + w) & (p.x < p.x[a] + w[a])
        oy = (p.y[a] < p.y + h) & (p.y < p.y[a] + h[a])
        if (same & ox & oy).any():
            return True
    return False
