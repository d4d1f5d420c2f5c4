"""Every compositing mode of the built-in demo, side by side, all from one capture.

The demo is a disc brake; its pads and pistons sit inside the caliper, hidden in a plain
render (`std`). All the other modes are composited from ONE capture of the atlas, in which
every part is complete, so the ghosted modes can show the hidden parts through the rest.

    python examples/demo_modes.py [OUT_DIR]      # writes OUT_DIR/demo_modes.png
"""

import sys
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

import rtta

MODES = ["std", "sprites", "transparent", "ghosted", "ghosted-ao"]
FOCUS = ["pad_outer", "pad_inner", "piston_1", "piston_2"]  # the parts hidden inside the caliper
SIZE = (320, 240)  # each tile, (W, H)
STYLED = {"context_opacity": 0.15, "halo": 4}  # the sixth tile: style keywords of snapshot


def main(out: Path) -> Path:
    tiles = []
    for mode, style in [(m, {}) for m in MODES] + [("ghosted-ao", STYLED)]:
        # scene=None is the built-in demo; camera = (azimuth, elevation, distance in scene radii)
        rgba = rtta.snapshot(None, mode=mode, focus=FOCUS, camera=(35, 25, 1.9), size=SIZE, **style)
        tile = Image.fromarray(rgba).convert("RGB")  # row 0 is the top row, as in images
        label = mode + "".join(f", {k}={v}" for k, v in style.items())
        ImageDraw.Draw(tile).text((8, 6), label, fill=(20, 20, 30))
        tiles.append(np.asarray(tile))
    # a 3 x 2 sheet, row by row
    sheet = np.concatenate([np.concatenate(tiles[:3], axis=1), np.concatenate(tiles[3:], axis=1)], axis=0)
    path = out / "demo_modes.png"
    Image.fromarray(sheet).save(path)
    return path


if __name__ == "__main__":
    out = Path(sys.argv[1] if sys.argv[1:] else "out/examples")
    out.mkdir(parents=True, exist_ok=True)
    print("wrote", main(out))
