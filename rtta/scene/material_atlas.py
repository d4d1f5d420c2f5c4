"""Material texture atlas (Knecht & Mattausch, section 2.4): every base-colour texture of a
scene packed into one 2D texture array, so the whole scene stays ONE batch.

- Sorted by size, largest first; each texture goes into the smallest free region it fits
  (guillotine free list); a new layer when none fits. Layers are square, as small as
  holds everything, and a multiple of 2**levels (not necessarily a power of two).
- Mip levels 0..`levels` are kept. Every slot's position and size are multiples of
  2**levels texels, so the slot never crosses a 2**levels line and no kept mip level
  mixes two textures.
- Each texture sits `border` = 2**levels texels inside its slot (the seed's border width:
  2^mipmaplevel), and the whole slot around it is filled from the opposite edges (texel
  (x, y) of the slot holds texel ((x - b) mod w, (y - b) mod h)), so bilinear taps across
  a wrap line, and the mip texels built from them, see what REPEAT would.
- Textures are not resampled: a non-power-of-two texture keeps its texels. Its mip levels
  are box filters of the wrapped texture; GL builds a separate non-power-of-two texture's
  levels by resampling instead, so at minification such a texture looks slightly different
  (sizes divisible by 2**levels give identical levels 0..levels).
The shader (shaders/material.glsl) emulates REPEAT inside the rectangle with fract() and
samples with gradients of the unwrapped coordinates, so mip selection has no seams.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

DEFAULT_LEVELS = 5
DEFAULT_MAX_SIZE = 4096  # a multiple of 2**levels


@dataclass
class MaterialAtlas:
    """Level 0 of the atlas layers (uint8 [layers, S, S, 4], row 0 = v 0) and where each
    texture lies: rects[i] = (layer, x, y, w, h) of texture i in texels, border excluded."""

    image: np.ndarray
    rects: np.ndarray  # int64 [T, 5]
    levels: int

    @property
    def size(self) -> int:
        return int(self.image.shape[1])

    @property
    def layers(self) -> int:
        return int(self.image.shape[0])

    @property
    def nbytes(self) -> int:
        """GPU bytes of the atlas with its mip levels 1..levels."""
        return sum(self.layers * (self.size >> k) ** 2 * 4 for k in range(self.levels + 1))


def original_nbytes(textures: list[np.ndarray]) -> int:
    """GPU bytes of the textures as separate RGBA8 textures with full mip chains."""
    total = 0
    for t in textures:
        h, w = t.shape[:2]
        while True:
            total += w * h * 4
            if w == 1 and h == 1:
                break
            w, h = max(1, w // 2), max(1, h // 2)
    return total


def build_atlas(
    textures: list[np.ndarray], levels: int = DEFAULT_LEVELS, max_size: int = DEFAULT_MAX_SIZE
) -> MaterialAtlas:
    """Pack `textures` (uint8 [h, w, 4], row 0 = v 0) into atlas layers of at most max_size."""
    if not 0 <= levels <= 8:
        raise ValueError(f"material atlas mip levels must be 0..8, got {levels}")
    unit = border = 1 << levels
    fitted = [_fit(t, max_size - 2 * border) for t in textures]
    slots = [(_round(t.shape[1] + 2 * border, unit), _round(t.shape[0] + 2 * border, unit)) for t in fitted]
    size = _layer_size(slots, max_size, unit)
    places = pack_slots(slots, size)
    layers = 1 + max((p[0] for p in places), default=0)
    image = np.zeros((layers, size, size, 4), np.uint8)
    rects = np.zeros((len(fitted), 5), np.int64)
    for i, (tex, (sw, sh), (layer, x, y)) in enumerate(zip(fitted, slots, places, strict=True)):
        h, w = tex.shape[:2]
        rows = (np.arange(sh) - border) % h
        cols = (np.arange(sw) - border) % w
        image[layer, y : y + sh, x : x + sw] = tex[rows[:, None], cols[None, :]]
        rects[i] = (layer, x + border, y + border, w, h)
    return MaterialAtlas(image=image, rects=rects, levels=levels)


def pack_slots(slots: list[tuple[int, int]], size: int) -> list[tuple[int, int, int]]:
    """(layer, x, y) per slot: largest first, each into the smallest free rectangle that
    holds it (guillotine split of the rest); a new size x size layer when none does."""
    order = sorted(range(len(slots)), key=lambda i: (-max(slots[i]), -slots[i][0] * slots[i][1], i))
    free: list[tuple[int, int, int, int, int]] = []  # (layer, x, y, w, h)
    places: list[tuple[int, int, int]] = [(0, 0, 0)] * len(slots)
    layers = 0
    for i in order:
        w, h = slots[i]
        fits = [r for r in free if r[3] >= w and r[4] >= h]
        if not fits:
            free.append((layers, 0, 0, size, size))
            layers += 1
            fits = [free[-1]]
        best = min(fits, key=lambda r: (r[3] * r[4], r[0], r[2], r[1]))
        free.remove(best)
        layer, x, y, fw, fh = best
        places[i] = (layer, x, y)
        # split the leftover along the shorter side, so the larger remainder stays whole
        if fw - w > fh - h:
            parts = [(layer, x + w, y, fw - w, fh), (layer, x, y + h, w, fh - h)]
        else:
            parts = [(layer, x, y + h, fw, fh - h), (layer, x + w, y, fw - w, h)]
        free.extend(p for p in parts if p[3] > 0 and p[4] > 0)
    return places


def _round(v: int, unit: int) -> int:
    return -(-v // unit) * unit


def _layer_size(slots: list[tuple[int, int]], max_size: int, unit: int) -> int:
    """The smallest multiple of `unit` (tried in steps of about 1/16) whose square layer
    holds every slot, or max_size when none does (the textures then use several layers).
    Layers need not be powers of two: only the 2**levels lines matter for the mip levels."""
    if not slots:
        return unit
    area = sum(w * h for w, h in slots)
    size = _round(max(max(max(s) for s in slots), int(np.ceil(np.sqrt(area)))), unit)
    while size < max_size and max(p[0] for p in pack_slots(slots, size)) > 0:
        size = _round(size + max(unit, size // 16), unit)
    return min(size, max_size)


def _fit(tex: np.ndarray, limit: int) -> np.ndarray:
    """Halve (2x2 box) a texture until it fits `limit` texels (fitted_shape's rule)."""
    while max(tex.shape[:2]) > limit:
        h, w = (tex.shape[0] // 2) * 2 or 1, (tex.shape[1] // 2) * 2 or 1
        t = tex[:h, :w].astype(np.float32)
        if h > 1:
            t = (t[0::2] + t[1::2]) / 2
        if w > 1:
            t = (t[:, 0::2] + t[:, 1::2]) / 2
        tex = np.round(t).astype(np.uint8)
    return tex


def fitted_shape(shape: tuple[int, int], limit: int) -> tuple[int, int]:
    """(h, w) of a texture of `shape` once _fit has halved it to `limit` texels a side."""
    h, w = shape
    while max(h, w) > limit:
        h, w = max(1, h // 2), max(1, w // 2)
    return h, w


def oversized_note(
    textures: list[np.ndarray], users: list[list[str]], levels: int = DEFAULT_LEVELS, max_size: int = DEFAULT_MAX_SIZE
) -> str | None:
    """One warning line for the textures the atlas will store halved (too large for a layer
    with their borders), naming each texture's size, stored size and first user; None when
    all fit."""
    limit = max_size - 2 * (1 << levels)
    big = []
    for i, tex in enumerate(textures):
        shape = tuple(tex.shape[:2])
        fit = fitted_shape(shape, limit)
        if fit != shape:
            more = f" and {len(users[i]) - 1} more" if len(users[i]) > 1 else ""
            who = users[i][0] + more if users[i] else "unused"
            big.append(f"{shape[1]}x{shape[0]} -> {fit[1]}x{fit[0]} ({who})")
    if not big:
        return None
    return (
        f"{len(big)} texture(s) larger than the material atlas holds ({limit} texels a side) stored "
        "at reduced resolution: " + ", ".join(big[:5]) + (" ..." if len(big) > 5 else "")
    )
