"""Fast navigation's thinning on the GPU (rtta.passes.thin_gpu, parameterize.comp's stages 7 and
8) held against the CPU's `left_out` on the same frame: a cut by area (every part left out is
smaller on screen than every part kept but the protected), at least the share of triangles
asked kept, never more parts left out than the CPU leaves, the focus never, and R read only
by the test."""

from __future__ import annotations

import numpy as np
import pytest

from rtta.atlas.thinning import KeepShare
from rtta.renderer.settings import Settings
from rtta.scene.camera import Camera
from rtta.scene.generators.assembly import write_assembly
from rtta.scene.loader import load_scene

VP = (640, 480)


@pytest.fixture(scope="module")
def assembly(tmp_path_factory):
    path = tmp_path_factory.mktemp("thin") / "asm.glb"
    write_assembly(path, 1500)
    return load_scene(str(path), cache=False)


def area(records) -> np.ndarray:
    r = records.viewport_rect
    return (r[:, 2] - r[:, 0]) * (r[:, 3] - r[:, 1])


@pytest.mark.parametrize("keep", [0.3, 0.7, 0.95])
def test_gpu_thinning_cuts_by_area_as_the_cpu(make_renderer, assembly, keep):
    n = assembly.count
    triangles = assembly.index_ranges[:, 1] // 3
    protect = np.zeros(n, bool)
    protect[[3, n // 2]] = True
    cam = Camera.orbit(assembly.center, assembly.radius, 30, 25, 1.6)
    whole = make_renderer(assembly, Settings(parameterize="cpu")).capture(cam, VP)
    cpu = make_renderer(assembly, Settings(parameterize="cpu"))
    cpu_share = KeepShare(keep, triangles, protect, key=1)
    cpu_rec = cpu.capture(cam, VP, thin=cpu_share)
    gpu = make_renderer(assembly, Settings(parameterize="gpu"))
    gpu_share = KeepShare(keep, triangles, protect, key=1)
    gpu_rec = gpu.capture(cam, VP, thin=gpu_share)
    assert not gpu_rec.is_read
    visible = whole.visible
    gpu_out, cpu_out = visible & ~gpu_rec.visible, visible & ~cpu_rec.visible
    assert cpu_out.any() and gpu_out.any()
    assert not (gpu_out & ~cpu_out).any()  # what the GPU leaves out, the CPU does too
    assert not (gpu_out & protect).any()
    a = area(whole)
    kept = visible & ~gpu_out & ~protect
    assert a[gpu_out].max() < a[kept].min()  # a cut by area
    budget = keep * triangles[visible].sum()
    assert triangles[visible & ~gpu_out].sum() >= budget
    assert gpu_share.left == 0  # the count comes a frame late
    gpu.capture(cam, VP, thin=gpu_share)
    assert gpu_share.left == int(gpu_out.sum())


def test_without_thinning_nothing_is_left_out(make_renderer, assembly):
    cam = Camera.orbit(assembly.center, assembly.radius, 30, 25, 1.6)
    gpu = make_renderer(assembly, Settings(parameterize="gpu"))
    thin = KeepShare(0.2, assembly.index_ranges[:, 1] // 3, key=2)
    assert (~gpu.capture(cam, VP, thin=thin).visible).sum() > (~gpu.capture(cam, VP).visible).sum()
    whole = make_renderer(assembly, Settings(parameterize="cpu")).capture(cam, VP)
    assert np.array_equal(gpu.capture(cam, VP).visible, whole.visible)  # the cut does not stay
