"""The texture atlas of one frame: every part of the demo unoccluded, in a region of its own.

Each frame, rtta projects every object's bounds, packs the rectangles into the layers of an
atlas (Algorithm 1 of Trapp & Döllner) and draws the whole scene once, each object displaced
into its region. `rtta.capture` gives that atlas as arrays, with each object's region
(`atlas_rect`, texels, border included) and layer. The picture: the direct render, then each
atlas layer with its regions outlined; the pads and pistons hidden in the render are whole
in the atlas.

    python examples/atlas_layers.py [OUT_DIR]    # writes OUT_DIR/atlas_layers.png
"""

import sys
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

import rtta

BACKGROUND = (40, 42, 48)


def main(out: Path) -> Path:
    cap = rtta.capture(None, camera=(35, 25, 2.0), size=(480, 360))  # None: the built-in demo
    layers, th, tw = cap.color.shape[:3]
    used = cap.atlas_rect[cap.visible][:, 2:].prod(axis=1).sum() / (layers * th * tw)
    print(f"{int(cap.visible.sum())} objects in {layers} layer(s) of {tw}x{th} texels, {used:.0%} used")
    panels = [cap.std_color[::-1]]  # the arrays have row 0 at the bottom: flip them for images
    for layer in range(layers):
        rgba = cap.color[layer]
        panel = Image.fromarray(np.where(rgba[..., 3:] > 0, rgba, (*BACKGROUND, 255)).astype(np.uint8)[::-1])
        draw = ImageDraw.Draw(panel)
        for oid in np.flatnonzero(cap.visible & (cap.layer == layer)):
            x, y, w, h = (int(v) for v in cap.atlas_rect[oid])
            draw.rectangle((x, th - y - h, x + w - 1, th - y - 1), outline=(255, 190, 40))  # flipped rows
            if w > 60 and h > 14:  # names where they fit
                draw.text((x + 3, th - y - h + 2), cap.names[oid], fill=(255, 255, 255))
        draw.text((4, th - 14), f"layer {layer}", fill=(120, 200, 255))
        panels.append(np.asarray(panel))
    panels[0] = np.where(cap.std_color[::-1, :, 3:] > 0, panels[0], 235)  # the render's background, light
    h, w = max(p.shape[0] for p in panels) + 4, max(p.shape[1] for p in panels) + 4
    sheet = np.full(((len(panels) + 1) // 2 * h, 2 * w, 3), 255, np.uint8)  # two panels a row
    for k, panel in enumerate(panels):
        y, x = k // 2 * h, k % 2 * w
        sheet[y : y + panel.shape[0], x : x + panel.shape[1]] = panel[..., :3]
    Image.fromarray(sheet).save(out / "atlas_layers.png")
    return out / "atlas_layers.png"


if __name__ == "__main__":
    out = Path(sys.argv[1] if sys.argv[1:] else "out/examples")
    out.mkdir(parents=True, exist_ok=True)
    print("wrote", main(out))
