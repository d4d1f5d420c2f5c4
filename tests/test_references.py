"""Snapshots of every mode on the demo against reference PNGs.

Tolerance: at least 99% of pixels within 3/255 per channel (llvmpipe differs slightly
across CPUs). On failure a diff image is written to tests/output/. References are
rewritten only with `pytest --regenerate-references`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from rtta.passes.composite import Style
from rtta.renderer.snapshot import render_modes
from rtta.scene.camera import DEFAULT_ORBIT, Camera

HERE = Path(__file__).parent
REFS = HERE / "references"
OUTPUT = HERE / "output"
MODES = ("std", "sprites", "transparent", "ghosted", "ghosted-ao")
FOCUS = ("pad_inner", "pad_outer", "piston_1", "piston_2")


@pytest.fixture(scope="module")
def snapshots(ctx, demo_scene):
    from rtta.renderer.renderer import Renderer

    r = Renderer(ctx, demo_scene)
    try:
        cam = Camera.orbit(demo_scene.center, demo_scene.radius, *DEFAULT_ORBIT)
        style = Style(focus={demo_scene.index(n) for n in FOCUS})
        images = render_modes(r, cam, (320, 240), MODES, style)
    finally:
        r.release()
    assert ctx.error == "GL_NO_ERROR"
    return {m: np.ascontiguousarray(img[::-1]) for m, img in images.items()}  # top row first


@pytest.mark.parametrize("mode", MODES)
def test_matches_reference(snapshots, mode, request):
    got = snapshots[mode]
    ref_path = REFS / f"demo_{mode}.png"
    if request.config.getoption("--regenerate-references"):
        REFS.mkdir(exist_ok=True)
        Image.fromarray(got).save(ref_path)
        return
    assert ref_path.exists(), f"missing {ref_path}; run pytest --regenerate-references"
    ref = np.asarray(Image.open(ref_path).convert("RGBA"))
    assert ref.shape == got.shape
    diff = np.abs(got.astype(int) - ref.astype(int)).max(-1)
    ok = (diff <= 3).mean()
    if ok < 0.99:
        OUTPUT.mkdir(exist_ok=True)
        Image.fromarray(np.clip(diff * 8, 0, 255).astype(np.uint8)).save(OUTPUT / f"diff_{mode}.png")
        Image.fromarray(got).save(OUTPUT / f"got_{mode}.png")
    assert ok >= 0.99, f"{mode}: only {ok:.4f} of pixels within 3/255; see tests/output/diff_{mode}.png"
