"""Atlas packing: rectangles into layers of at most (Tw_max, Th_max).

`pack_shelves` is next-fit-decreasing-height shelf packing, vectorised with numpy:
one sort (O(n log n)) plus one binary search per shelf and per layer, so it runs every
frame for thousands of objects. `rtta bench packing` compares it with rectpack
(MaxRects) and rectangle-packer; docs/performance/capture.md has the evidence for choosing it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .scratch import scratch


@dataclass
class Packing:
    x: np.ndarray  # int64 [n] lower-left corner in texels
    y: np.ndarray
    layer: np.ndarray  # int64 [n]
    width: int  # used atlas width  (T_w)
    height: int  # used atlas height (T_h)
    layers: int  # T_d

    @property
    def size(self) -> tuple[int, int, int]:
        return self.width, self.height, self.layers


def _breaks(cum: np.ndarray, sizes: np.ndarray, limit: int) -> np.ndarray:
    """Start indices of greedy runs of `sizes` (cumsum `cum`) whose sum stays <= limit: the
    end of a run from every index in one vectorised search, then one hop per run."""
    reach = np.subtract(cum, sizes, out=scratch("pack.reach", len(cum), cum.dtype))
    reach += limit
    nxt = cum.searchsorted(reach, side="right")  # where a run from each index ends
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
    16-bit sorts when the sizes allow (numpy sorts those by radix: about 10x faster at 10^5).
    The result is a scratch array (this module's pack_shelves consumes it)."""
    top = max(int(w.max()), int(h.max()))
    if top >= 1 << 16:
        return np.lexsort((-w, -h))
    n = len(w)
    key = scratch("pack.key", n, np.uint16)
    np.subtract(top, w, out=key, casting="unsafe")
    by_w = np.argsort(key, kind="stable")
    np.subtract(top, np.take(h, by_w, out=scratch("pack.h_by_w", n, h.dtype)), out=key, casting="unsafe")
    return np.take(by_w, np.argsort(key, kind="stable"), out=scratch("pack.order", n, np.int64))


def _by_shelf(starts: np.ndarray, n: int) -> np.ndarray:
    """The shelf (or run) of each of n items, runs beginning at `starts` (scratch)."""
    of = scratch("pack.shelf_of", n, np.int64)
    of[:] = 0
    of[starts[1:]] = 1
    return np.cumsum(of, out=of)


def pack_shelves(
    w: np.ndarray, h: np.ndarray, max_w: int, max_h: int, out: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
) -> Packing:
    """Pack w x h rectangles (each <= max_w x max_h) into shelves and layers. `out`: int64
    arrays [n] to write x, y and layer into (fresh ones when None)."""
    w = np.asarray(w, np.int64)
    h = np.asarray(h, np.int64)
    n = len(w)
    if n == 0:
        z = np.zeros(0, np.int64)
        return Packing(z, z, z, 0, 0, 0)
    if (w > max_w).any() or (h > max_h).any() or (w < 1).any() or (h < 1).any():
        raise ValueError("rectangles must be between 1x1 and the atlas size")
    order = _decreasing_order(w, h)  # tallest first, then widest
    ws = np.take(w, order, out=scratch("pack.ws", n, np.int64))
    hs = np.take(h, order, out=scratch("pack.hs", n, np.int64))
    cum = np.cumsum(ws, out=scratch("pack.cum", n, np.int64))
    shelf_start = _breaks(cum, ws, max_w)
    shelf_of = _by_shelf(shelf_start, n)
    xs = np.subtract(cum, ws, out=scratch("pack.xs", n, np.int64))
    gathered = scratch("pack.gathered", n, np.int64)
    xs -= np.take(xs[shelf_start], shelf_of, out=gathered)  # from the shelf's left end
    shelf_h = hs[shelf_start]
    shelf_w = np.add.reduceat(ws, shelf_start)
    cum_h = np.cumsum(shelf_h)
    layer_start = _breaks(cum_h, shelf_h, max_h)
    layer_of_shelf = np.repeat(np.arange(len(layer_start)), np.diff(np.append(layer_start, len(shelf_h))))
    shelf_y = cum_h - shelf_h - (cum_h[layer_start] - shelf_h[layer_start])[layer_of_shelf]
    layer_h = np.add.reduceat(shelf_h, layer_start)
    x, y, layer = out if out is not None else (np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n, np.int64))
    x[order] = xs
    y[order] = np.take(shelf_y, shelf_of, out=gathered)
    layer[order] = np.take(layer_of_shelf, shelf_of, out=gathered)
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
