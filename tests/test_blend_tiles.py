"""The compute blend (rtta.passes.blend_tiles, Settings.blend="compute") against the sprites it
replaces: the same capture composited both ways gives the same pixels within a rounding of
the 8-bit blend per layer, in every mode that blends in object order, at sizes that are not a
multiple of the tile, in orthographic views, with halos, and where nothing or everything is
in the focus."""

from __future__ import annotations

import numpy as np
import pytest

from rtta.passes.blend_tiles import SPAN
from rtta.passes.style import Style
from rtta.renderer.settings import FEW_ROPS, Settings, blend_on
from rtta.scene.camera import Camera
from rtta.scene.generators.assembly import write_assembly
from rtta.scene.loader import load_scene

TOLERANCE = 3  # /255 on other GPUs: each layer's blend rounds to 8 bits in the GPU's own steps
SHARE_OVER_2 = 0.001  # of the pixels: differences of 3 where several layers round the same way


def composites(make_renderer, scene, mode, style, viewport, camera=None):
    """(raster, compute) RGBA of one capture composited both ways, and the passes of each."""
    r = make_renderer(scene, Settings(blend="raster", parameterize="gpu"))  # the GPU-driven branch blends so
    cam = camera or Camera.orbit(scene.center, scene.radius, 35.0, 25.0, 2.2)
    r.capture(cam, viewport, normals=r.needs_normals(mode), ids=False)
    out, passes = [], []
    for blend in ("raster", "compute"):
        r.settings.blend = blend
        r.composite(mode, style)
        out.append(r.target.read()[0].astype(int))
        passes.append(list(r._composite.passes))
    exact.append("llvmpipe" in r.ctx.info["GL_RENDERER"])
    return out, passes


exact: list[bool] = []  # whether the last composites() ran on llvmpipe, whose blend steps the shader follows


def assert_same(raster, compute):
    if exact[-1]:
        assert np.array_equal(raster, compute), f"{(raster != compute).any(axis=-1).sum()} pixels differ"
    diff = np.abs(raster - compute).max(axis=-1)
    assert diff.max() <= TOLERANCE, f"max {diff.max()} at {np.argwhere(diff == diff.max())[:3].tolist()}"
    assert (diff > 2).mean() <= SHARE_OVER_2
    assert (raster != compute).any(axis=-1).mean() < 0.5  # the same picture, not two blank ones
    assert (raster[..., :3] != raster[0, 0, :3]).any(axis=-1).mean() > 0.05


@pytest.mark.parametrize("mode", ["ghosted", "ghosted-ao", "transparent"])
def test_compute_blend_draws_the_sprites_pixels(make_renderer, demo_scene, mode):
    style = Style(focus={0, demo_scene.count // 2}) if mode != "transparent" else Style(order="object")
    (raster, compute), (raster_passes, compute_passes) = composites(make_renderer, demo_scene, mode, style, (203, 149))
    assert_same(raster, compute)
    assert any(p.startswith("blend+") for p in raster_passes)
    assert not any(p.startswith("blend+") for p in compute_passes)
    assert any(p.startswith("blend_tiles") for p in compute_passes)


def test_many_parts_orthographic_with_halos(make_renderer, tmp_path):
    path = tmp_path / "asm.glb"
    write_assembly(path, 600)
    scene = load_scene(str(path))
    cam = Camera.orbit(scene.center, scene.radius, 20.0, 30.0, 2.0, projection="ortho")
    style = Style(focus={3, 300}, halo=4)
    (raster, compute), (_, passes) = composites(make_renderer, scene, "ghosted", style, (97, 211), cam)
    assert_same(raster, compute)
    assert any(p.startswith("halo") for p in passes)  # drawn after the compute blend, over it


def test_no_context_and_all_context(make_renderer, demo_scene):
    everyone = Style(focus=set(range(demo_scene.count)))
    (raster, compute), (_, passes) = composites(make_renderer, demo_scene, "ghosted", everyone, (64, 48))
    assert np.array_equal(raster, compute)  # nothing to blend: the focus sprites alone
    (raster, compute), _ = composites(make_renderer, demo_scene, "ghosted", Style(), (64, 48))
    assert_same(raster, compute)


def test_auto_is_compute_where_raster_hardware_is_scarce():
    assert blend_on("auto", "NVIDIA H100 80GB HBM3/PCIe/SSE2") == "compute"
    assert blend_on("auto", "NVIDIA A100-SXM4-80GB/PCIe/SSE2") == "compute"
    assert blend_on("auto", "NVIDIA GeForce RTX 4090/PCIe/SSE2") == "raster"
    assert blend_on("auto", "llvmpipe (LLVM 15.0.6, 256 bits)") == "raster"
    assert blend_on("raster", "NVIDIA H100 80GB HBM3/PCIe/SSE2") == "raster"
    assert blend_on("compute", "llvmpipe (LLVM 15.0.6, 256 bits)") == "compute"
    assert "H100" in FEW_ROPS and SPAN >= 1
