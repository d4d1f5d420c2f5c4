"""Amodal masks: every part's full silhouette, also where other parts hide it.

`rtta.capture` renders the demo brake once into the atlas, where each part is drawn whole
in a region of its own; `Capture.amodal(name)` maps that region back to the view. The
picture: the plain render (left) and, on the right, the same render dimmed with the amodal
mask of each part inside the caliper drawn over it in its own colour and outlined, though
the plain render shows none of them.

    python examples/amodal_masks.py [OUT_DIR]    # writes OUT_DIR/amodal_masks.png
"""

import sys
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw
from scipy import ndimage

import rtta

PARTS = {
    "pad_outer": (60, 150, 255),
    "pad_inner": (40, 220, 120),
    "piston_1": (255, 170, 30),
    "piston_2": (255, 60, 200),
}


def main(out: Path) -> Path:
    cap = rtta.capture(None, camera=(35, 25, 2.0), size=(480, 360))  # None: the built-in demo
    # the capture's arrays have row 0 at the BOTTOM (GL's convention): flip them for images
    std = cap.std_color[::-1, :, :3].astype(float)
    std[cap.std_color[::-1, :, 3] == 0] = 235  # a light background where nothing was drawn
    overlay = 0.45 * std + 0.55 * 235  # the plain render, faded
    for name, colour in PARTS.items():
        mask = (cap.amodal(name)["id"] >= 0)[::-1]  # the whole part, occluded or not
        seen = int((cap.std_id == cap.index(name)).sum())  # what the plain render shows of it
        print(f"{name}: visible {seen} px, amodal {int(mask.sum())} px")
        overlay[mask] = 0.35 * overlay[mask] + 0.65 * np.array(colour)
        edge = mask & ~ndimage.binary_erosion(mask)
        overlay[edge] = colour
    picture = Image.fromarray(np.concatenate([std, overlay], axis=1).astype(np.uint8))
    for k, (name, colour) in enumerate(PARTS.items()):  # a legend, bottom right
        ImageDraw.Draw(picture).text((490, 290 + 16 * k), f"{name} (amodal)", fill=colour)
    path = out / "amodal_masks.png"
    picture.save(path)
    return path


if __name__ == "__main__":
    out = Path(sys.argv[1] if sys.argv[1:] else "out/examples")
    out.mkdir(parents=True, exist_ok=True)
    print("wrote", main(out))
