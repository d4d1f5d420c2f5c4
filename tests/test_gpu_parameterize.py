"""Algorithm 1 in compute shaders (rtta.passes.atlas_gpu, Settings(parameterize="gpu")) held
against the CPU reference (rtta.atlas.parameterize): the same objects culled, the same
B_viewport, regions inside the atlas and disjoint, and the same pictures."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from checks import check_frame
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rtta.atlas.parameterize import parameterize
from rtta.gl.gpu import GpuScene
from rtta.passes.atlas_gpu import FUSED_MAX, GpuParameterize
from rtta.passes.style import Style
from rtta.renderer.settings import Settings
from rtta.scene.camera import Camera
from rtta.scene.generators.generate import random_scene

VIEWPORT = (160, 120)
_SCENES: dict[int, object] = {}


def scene_of(n: int):
    """random_scene(n), made once per size (20,000 parts take seconds)."""
    if n not in _SCENES:
        _SCENES[n] = random_scene(n, seed=n)
    return _SCENES[n]


@pytest.fixture(scope="module")
def atlas_gpu(ctx):
    """One GPU parameterizer and one GpuScene per scene size, released after the module."""
    made: dict[int, GpuScene] = {}
    param = GpuParameterize(ctx)
    param.fused_max = FUSED_MAX  # a GPU's choice (llvmpipe's is 0: every renderer in the suite runs that)

    def run(n, corners, vpm, viewport, **kw):
        if n not in made:
            made[n] = GpuScene(ctx, scene_of(n))
        return param.run(made[n], corners, vpm, viewport, **kw)

    yield run
    param.release()
    for gpu in made.values():
        gpu.release()


def camera(scene, az, el, dist, near_frac):
    """An orbit camera; near_frac > 0 puts the near plane at that fraction of the distance to
    the centre (through the scene's objects), dist < 1 puts the eye inside the scene."""
    cam = Camera.orbit(scene.center, scene.radius, az, el, dist)
    if near_frac:
        cam = dataclasses.replace(cam, near=dist * scene.radius * near_frac)
    return cam


def coverage_max(rec) -> int:
    """The most regions covering one atlas texel (1: disjoint), by a 2-D difference array per layer."""
    tw, th, td = rec.atlas_size
    vis = np.flatnonzero(rec.visible)
    if not len(vis):
        return 0
    x, y, w, h = rec.atlas_rect[vis].T
    diff = np.zeros((td, th + 1, tw + 1), np.int32)
    layer = rec.layer[vis]
    for dy, dx, sign in ((y, x, 1), (y, x + w, -1), (y + h, x, -1), (y + h, x + w, 1)):
        np.add.at(diff, (layer, dy, dx), sign)
    return int(diff.cumsum(1).cumsum(2).max())


def assert_valid(rec, ref, atlas_max, max_layers):
    """The GPU's records against the CPU's `ref` for the same view."""
    assert np.array_equal(rec.visible, ref.visible), "a different set of objects culled"
    vis = rec.visible
    off = np.abs(rec.viewport_rect - ref.viewport_rect).max(axis=1)
    assert off.max(initial=0) <= 1, "B_viewport differs by more than rounding"
    assert (off > 0).sum() <= max(1, vis.sum() // 1000), f"B_viewport differs at {(off > 0).sum()} objects"
    tw, th, td = rec.atlas_size
    assert tw <= atlas_max[0] and th <= atlas_max[1] and td <= max_layers
    x, y, w, h = rec.atlas_rect[vis].T
    assert (x >= 0).all() and (y >= 0).all() and (x + w <= tw).all() and (y + h <= th).all()
    assert ((rec.layer[vis] >= 0) & (rec.layer[vis] < td)).all()
    assert (w > 2 * rec.border).all() and (h > 2 * rec.border).all()
    assert coverage_max(rec) <= 1, "regions overlap"
    culled = ~vis
    assert not rec.atlas_rect[culled].any() and not rec.transform[culled].any() and not rec.scale[culled].any()
    same = vis & (np.abs(rec.scale - ref.scale) <= 1e-6 * ref.scale) & (off == 0)
    assert np.array_equal(rec.atlas_rect[same, 2:], ref.atlas_rect[same, 2:]), "region sizes differ at one scale"
    if min(ref.scale[vis].min(initial=1), rec.scale[vis].min(initial=1)) >= 1 and vis.any():
        assert same[vis].mean() > 0.99  # no scale-down on either path: the same regions
    # T maps the inner B_viewport's corner onto the region's inner corner
    ndc = rec.viewport_rect[vis, :2] / np.array(rec.viewport) * 2 - 1
    atlas_ndc = (rec.atlas_rect[vis, :2] + rec.border) / np.maximum([tw, th], 1) * 2 - 1
    t = rec.transform[vis]
    np.testing.assert_allclose(t[:, :2] * ndc + t[:, 2:], atlas_ndc, atol=1e-4)


@pytest.mark.parametrize("n", [1, 10, 1000, 2000])  # up to FUSED_MAX one work group runs every stage
@given(
    az=st.floats(0, 359),
    el=st.floats(-89, 89),
    dist=st.sampled_from([0.05, 0.3, 0.8, 1.5, 3.0]),
    near_frac=st.sampled_from([0.0, 0.5, 0.9, 1.0, 1.3]),
    border=st.integers(0, 3),
    bounds=st.sampled_from(["aabb", "obb"]),
)
@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
def test_gpu_records_match_the_cpu_path(gl, atlas_gpu, n, az, el, dist, near_frac, border, bounds):
    scene = scene_of(n)
    cam = camera(scene, az, el, dist, near_frac)
    vpm = cam.projection(VIEWPORT[0] / VIEWPORT[1]) @ cam.view(scene.origin)
    corners = scene.box_corners(bounds)
    atlas_max, max_layers = (VIEWPORT[0] + 2 * border, VIEWPORT[1] + 2 * border), 64
    kw = {"border": border, "atlas_max": atlas_max, "max_layers": max_layers}
    ref = parameterize(corners, vpm, VIEWPORT, **kw)
    rec = atlas_gpu(n, corners, vpm, VIEWPORT, **kw)
    assert gl.error == "GL_NO_ERROR"  # every example (the fixture checks around the whole test)
    assert_valid(rec, ref, atlas_max, max_layers)


@pytest.mark.parametrize("dist, near_frac", [(2.5, 0.0), (0.2, 0.0), (1.5, 0.9)])
def test_20000_parts(gl, atlas_gpu, dist, near_frac):
    """Outside, inside the scene, and the near plane through it."""
    scene = scene_of(20_000)
    cam = camera(scene, 30, 20, dist, near_frac)
    vpm = cam.projection(VIEWPORT[0] / VIEWPORT[1]) @ cam.view(scene.origin)
    kw = {"border": 1, "atlas_max": (162, 122), "max_layers": 2048}
    ref = parameterize(scene.box_corners(), vpm, VIEWPORT, **kw)
    rec = atlas_gpu(20_000, scene.box_corners(), vpm, VIEWPORT, **kw)
    assert rec.visible.sum() > 100
    assert_valid(rec, ref, (162, 122), 2048)


@pytest.mark.parametrize("n", [FUSED_MAX, 2000])  # one work group, and a dispatch per stage
def test_scaled_down_when_the_layers_run_out(gl, atlas_gpu, n):
    """Too few layers: every visible object keeps a (smaller) region, none dropped."""
    scene = scene_of(n)
    cam = camera(scene, 10, 10, 1.5, 0.0)
    vpm = cam.projection(VIEWPORT[0] / VIEWPORT[1]) @ cam.view(scene.origin)
    kw = {"border": 1, "atlas_max": (162, 122), "max_layers": 1}
    ref = parameterize(scene.box_corners(), vpm, VIEWPORT, **kw)
    rec = atlas_gpu(n, scene.box_corners(), vpm, VIEWPORT, **kw)
    assert rec.atlas_size[2] == 1 and rec.visible.sum() == ref.visible.sum() > 100
    assert (rec.scale[rec.visible] < 1).all()
    assert coverage_max(rec) <= 1


@pytest.mark.parametrize("n", [FUSED_MAX, 2000])
def test_refused_as_the_cpu_path_when_nothing_fits(gl, atlas_gpu, n):
    """1-texel regions of 1,024 or 2,000 parts cannot share one 3x3 layer: both paths say so."""
    scene = scene_of(n)
    cam = camera(scene, 10, 10, 1.5, 0.0)
    vpm = cam.projection(VIEWPORT[0] / VIEWPORT[1]) @ cam.view(scene.origin)
    kw = {"border": 1, "atlas_max": (3, 3), "max_layers": 1}
    for run in (
        lambda: parameterize(scene.box_corners(), vpm, VIEWPORT, **kw),
        lambda: atlas_gpu(n, scene.box_corners(), vpm, VIEWPORT, **kw),
    ):
        with pytest.raises(ValueError, match="do not fit"):
            run()


def test_hidden_and_per_object_scales(gl, atlas_gpu):
    scene = scene_of(10)
    cam = camera(scene, 0, 0, 2.5, 0.0)
    vpm = cam.projection(VIEWPORT[0] / VIEWPORT[1]) @ cam.view(scene.origin)
    hidden = np.zeros(10, bool)
    hidden[[1, 4]] = True
    scales = np.full(10, 0.5)
    scales[0] = 1.0
    kw = {"border": 1, "atlas_max": (162, 122), "max_layers": 64, "hidden": hidden, "region_scale": scales}
    ref = parameterize(scene.box_corners(), vpm, VIEWPORT, **kw)
    rec = atlas_gpu(10, scene.box_corners(), vpm, VIEWPORT, **kw)
    assert not rec.visible[hidden].any() and ref.visible[~hidden].sum() == rec.visible.sum() > 5
    assert np.array_equal(rec.scale, ref.scale)  # in doubles, as the CPU path's (the record holds float32)
    assert_valid(rec, ref, (162, 122), 64)


def test_gpu_capture_equals_rtt_and_std(make_renderer, demo_scene):
    """The atlas-versus-RTT and STD checks of tests/checks.py on the gpu path."""
    renderer = make_renderer(demo_scene, Settings(parameterize="gpu"))
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, 35, 25, 2.2)
    summary = check_frame(renderer, cam, (200, 150), "vs")
    assert summary["visible"] > 0
    assert renderer.gpu.written is renderer.last[0]  # the records the GPU wrote, not uploaded again


@pytest.mark.parametrize("mode", ["ghosted", "ghosted-ao", "transparent"])
def test_gpu_composite_equals_the_cpu_path(make_renderer, demo_scene, mode):
    """Each region holds the same picture at the same scale: the composites are equal (both
    blended by sprites: on a GPU where `blend="auto"` picks the compute blend, the GPU path's
    object-order blend differs by 1/255 in places; tests/test_blend_tiles.py checks that one)."""
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, 60, 20, 2.0)
    style = Style(focus=frozenset({2}))
    images = []
    for where in ("cpu", "gpu"):
        renderer = make_renderer(demo_scene, Settings(parameterize=where, blend="raster"))
        records = renderer.capture(cam, (240, 180), focus=style.focus)
        images.append(renderer.composite(mode, style).read())
        assert records.visible.any()
    (color, depth), (color_gpu, depth_gpu) = images
    differ = np.abs(color.astype(int) - color_gpu).max(axis=-1)
    # depths an ulp apart (below) may order coplanar surfaces the other way (transparent: 19 px of 43,200)
    assert differ.max() <= 8 and (differ > 0).mean() < 0.001, f"{(differ > 0).sum()} px, at most {differ.max()}"
    np.testing.assert_allclose(depth, depth_gpu, atol=1e-6)  # interpolated at other atlas texels: float32 ulps


def test_cli_snapshot_gpu_equals_cpu(gl, tmp_path):
    from PIL import Image

    from rtta.cli.main import main

    out = {}
    for where in ("cpu", "gpu"):
        out[where] = tmp_path / f"{where}.png"
        argv = ["snapshot", "--size", "200x150", "--camera", "35,25,2.2", "--parameterize", where, "--blend", "raster"]
        assert main([*argv, "--out", str(out[where])]) == 0
    assert np.array_equal(np.asarray(Image.open(out["cpu"])), np.asarray(Image.open(out["gpu"])))


def test_cli_refuses_an_unknown_place(gl, tmp_path, capsys):
    from rtta.cli.main import main

    assert main(["snapshot", "--parameterize", "tpu", "--out", str(tmp_path / "x.png")]) == 2
    assert "--parameterize" in capsys.readouterr().err and not (tmp_path / "x.png").exists()


def test_bench_rows(gl, capsys):
    """rtta bench capture's rows for both paths (no timing asserted: a shared machine)."""
    from rtta.bench.param_gpu import param_paths, print_paths

    (row,) = param_paths(gl, [1000], (256, 256), 1)
    assert row["objects"] == 1000 and row["visible"] > 0 and row["same_rects"]
    assert 0 < row["gpu_util"] <= 1 and 0 < row["cpu_util"] <= 1 and row["gpu_layers"] >= 1
    assert all(row[k] > 0 for k in ("cpu_ms", "gpu_ms", "cpu_wall_ms", "gpu_wall_ms"))
    print_paths([row])
    assert "GPU path" in capsys.readouterr().out


def test_a_driver_that_cannot_build_it_says_so_in_one_line(gl, monkeypatch):
    from rtta.errors import RttaError
    from rtta.passes import atlas_gpu

    broken = "#version 430\nlayout(local_size_x = 1) in;\nvoid main() { no_such_function(); }\n"
    monkeypatch.setattr(atlas_gpu.glsl, "load", lambda *args, **kw: broken)
    with pytest.raises(RttaError, match="--parameterize gpu: this driver cannot build") as exc:
        GpuParameterize(gl)
    assert "\n" not in str(exc.value)


def test_exploded_view_on_the_gpu(make_renderer, demo_scene):
    """The GPU adds the explode offsets to the unmoved corners: the same records as the CPU
    path's moved corners; the atlas equals RTT and STD (tests/checks.py)."""
    from rtta.renderer.placing import check_staging, make_staging

    staging = make_staging(explode=1.5)
    framed = check_staging(staging, demo_scene)
    cam = Camera.orbit(framed.center, framed.radius, 35, 25, 2.2)
    renderers = [make_renderer(demo_scene, Settings(parameterize=where)) for where in ("cpu", "gpu")]
    for r in renderers:
        r.staging = make_staging(explode=1.5)
    cpu, gpu = (r.capture(cam, (200, 150)) for r in renderers)
    assert gpu.visible.sum() == demo_scene.count and np.array_equal(cpu.viewport_rect, gpu.viewport_rect)
    check_frame(renderers[1], cam, (200, 150), "vs")
