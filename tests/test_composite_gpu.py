"""Compositing's GPU-driven draws (issue 43): the back-to-front order sorted on the GPU
(order_gpu.GpuOrder) held against composite.back_to_front, and the GPU-driven composite
(R left on the GPU: a GpuRecords) held against the CPU branch's from the same capture."""

from __future__ import annotations

import types

import numpy as np
import pytest

from rtta.atlas.records import RECORD_DTYPE, GpuRecords
from rtta.gl.targets import CompositeTarget
from rtta.passes import composite as composite_module
from rtta.passes import composite_gpu
from rtta.passes.composite import BACKGROUND, CompositePass, back_to_front
from rtta.passes.composite_gpu import gpu_driven
from rtta.passes.order_gpu import COMMAND_WORDS, FOCUS_COMMANDS, GpuOrder
from rtta.passes.style import Mode, Style, style_params
from rtta.renderer.placing import Staging, restage
from rtta.renderer.settings import Settings
from rtta.scene.camera import Camera, ortho_near, outline_eye
from rtta.scene.generators.assembly import write_assembly
from rtta.scene.loader import load_scene

VP = (200, 150)
TOLERANCE = 2  # /255 per channel, on all pixels but SHARE_OFF
SHARE_OFF = 0.002  # near-ties of bounds centres: float32 on the GPU, float64 on the CPU


@pytest.fixture(params=["radix", "bitonic", "auto"])
def order(gl, request):
    o = GpuOrder(gl, request.param)
    yield o
    o.release()


def sorted_on_gpu(gl, order, z, visible, excluded=None, offsets=None):
    """GpuOrder's ids for bounds centres at depth -z (view = identity), R's visibility and
    the objects flagged focus in a style buffer (excluded)."""
    n = len(z)
    bounds = np.zeros((n, 2, 4), np.float32)
    bounds[:, :, 2] = z[:, None]
    bounds[:, :, 0] = np.arange(n)[:, None] % 7  # x, y do not move view depth
    records = np.zeros(n, RECORD_DTYPE)
    records["info"][:, 1] = visible
    styles = None
    made = [gl.buffer(records.tobytes()), gl.buffer(bounds.tobytes())]
    if excluded is not None:
        params = np.zeros((n, 4), np.float32)
        params[excluded, 1] = 1.0
        styles = gl.buffer(params.tobytes())
        made.append(styles)
    order.sort(count=n, records=made[0], bounds=made[1], view=np.eye(4), styles=styles, offsets=offsets)
    got = order.read()
    for buf in made:
        buf.release()
    return got


@pytest.mark.parametrize("n", [1, 2, 1000, 5000, 70000])
def test_gpu_order_is_back_to_front(gl, order, n):
    rng = np.random.default_rng(n)
    z = rng.integers(-40, 40, n).astype(np.float32)  # many ties: ordered by id
    z[::3] = rng.normal(size=len(z[::3])).astype(np.float32)
    z[: min(n, 4)] = [0.0, -0.0, 0.0, -0.0][: min(n, 4)]  # -0 ties with 0, as numpy's keys do
    if n > 10:  # every bit of the keys sorted by: far apart, tiny, of either sign
        z[4:10] = [1e38, -1e38, 1e-30, -1e-30, 1e-30, -2.5e37]
    visible = rng.random(n) > 0.15
    excluded = rng.choice(n, size=min(n, 17), replace=False)
    records = types.SimpleNamespace(visible=visible)
    depth = -z.astype(np.float64)
    np.testing.assert_array_equal(sorted_on_gpu(gl, order, z, visible), back_to_front(records, depth, np.arange(n)))
    kept = np.ones(n, bool)
    kept[excluded] = False
    want = back_to_front(records, depth, np.arange(n)[kept])
    np.testing.assert_array_equal(sorted_on_gpu(gl, order, z, visible, excluded), want)


def test_gpu_order_adds_offsets(gl, order):
    rng = np.random.default_rng(3)
    n = 3000
    z = rng.normal(size=n).astype(np.float32)
    offsets = np.zeros((n, 3), np.float32)
    offsets[:, 2] = rng.integers(-3, 3, n)
    got = sorted_on_gpu(gl, order, z, np.ones(n, bool), offsets=offsets)
    want = back_to_front(
        types.SimpleNamespace(visible=np.ones(n, bool)), -(z + offsets[:, 2]).astype(np.float64), np.arange(n)
    )
    np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("scales", ["full", "upsampled", "mixed", "none drawn"])
def test_gpu_order_gives_one_variant_the_list(gl, order, scales):
    """Of the three indirect commands, the one of the regions' scale class draws the list."""
    n = 900
    records = np.zeros(n, RECORD_DTYPE)
    records["info"][:, 1] = scales != "none drawn"
    scale = np.full(n, 0.5 if scales == "upsampled" else 1.0, np.float32)
    if scales == "mixed":
        scale[::50] = 0.5
    records["info"][:, 3] = scale.view(np.int32)
    made = [gl.buffer(records.tobytes()), gl.buffer(np.zeros((n, 2, 4), np.float32).tobytes())]
    try:
        for sort in (True, False):
            if sort:
                order.sort(count=n, records=made[0], bounds=made[1], view=np.eye(4))
            else:
                order.every(count=n, records=made[0], bounds=made[1])
            words = np.frombuffer(order.command.read(60), np.uint32).reshape(3, 5)
            want = np.zeros(3, np.uint32)
            if scales != "none drawn":
                want[["full", "upsampled", "mixed"].index(scales)] = n
            np.testing.assert_array_equal(words[:, 0], want)
            np.testing.assert_array_equal(words[:, 1], 1)
            ids = np.frombuffer(order.ids.read(4 * n), np.int32)
            np.testing.assert_array_equal(ids, np.arange(n))  # every key ties (one depth): id order
    finally:
        for buf in made:
            buf.release()


@pytest.mark.parametrize("scales", ["one", "scaled", "upsampled", "hidden upsampled"])
def test_gpu_order_gives_one_focus_variant_the_focus(gl, scales):
    """Of the focus list's three commands, the one of its visible regions' class draws it:
    every one at scale 1 (outlines by quads), none upsampled, some upsampled; a focus object
    not visible does not count. The focus flags count whether or not the focus is drawn."""
    n, focus = 300, np.array([3, 50, 299])
    records = np.zeros(n, RECORD_DTYPE)
    records["info"][:, 1] = 1
    scale = np.ones(n, np.float32)
    scale[focus[1]] = {"one": 1.0, "scaled": 0.9995, "upsampled": 0.5, "hidden upsampled": 0.5}[scales]
    scale[7] = 0.5  # a context object upsampled: not the focus's business
    if scales == "hidden upsampled":
        records["info"][focus[1], 1] = 0
    records["info"][:, 3] = scale.view(np.int32)
    params = np.zeros((n, 4), np.float32)
    params[focus, 1] = 1.0
    bounds = np.zeros((n, 2, 4), np.float32)
    made = [gl.buffer(records.tobytes()), gl.buffer(bounds.tobytes()), gl.buffer(params.tobytes())]
    order = GpuOrder(gl)
    want = np.zeros(3, np.uint32)
    want[{"one": 0, "scaled": 1, "upsampled": 2, "hidden upsampled": 0}[scales]] = len(focus)
    visible = records["info"][:, 1] != 0
    try:
        for how in ("context", "everyone", "every"):
            kw = dict(count=n, records=made[0], bounds=made[1], styles=made[2], focus=len(focus))
            if how == "every":
                order.every(**kw)
            else:
                order.sort(**kw, view=np.eye(4), exclude_focus=how == "context")
            words = np.frombuffer(order.command.read(4 * COMMAND_WORDS), np.uint32)
            np.testing.assert_array_equal(words[[5 * k for k in FOCUS_COMMANDS]], want)
            context = visible & (params[:, 1] == 0)
            listed = n if how == "every" else int((context if how == "context" else visible).sum())
            assert words[2 * 5] == listed  # the list itself: some regions upsampled
    finally:
        order.release()
        for buf in made:
            buf.release()


def test_which_branch():
    """GPU-driven: R on the GPU, a view given, no projector or lens, object order where the mode blends."""
    on_gpu, on_cpu, view = types.SimpleNamespace(on_gpu=True), types.SimpleNamespace(), np.eye(4)
    obj, auto, pixel = Style(order="object"), Style(), Style(order="pixel")
    assert gpu_driven(on_gpu, Mode.GHOSTED, auto, view, None, None)
    assert gpu_driven(on_gpu, Mode.GHOSTED_AO, obj, view, None, None)
    assert gpu_driven(on_gpu, Mode.SPRITES, pixel, view, None, None)
    assert gpu_driven(on_gpu, Mode.TRANSPARENT, obj, view, None, None)
    assert not gpu_driven(on_gpu, Mode.TRANSPARENT, auto, view, None, None)  # auto: pixel order there
    assert not gpu_driven(on_gpu, Mode.GHOSTED, pixel, view, None, None)
    assert not gpu_driven(on_cpu, Mode.GHOSTED, auto, view, None, None)
    assert not gpu_driven(on_gpu, Mode.GHOSTED, auto, None, None, None)
    assert not gpu_driven(on_gpu, Mode.GHOSTED, auto, view, "projection", None)
    assert not gpu_driven(on_gpu, Mode.GHOSTED, auto, view, None, "lens")


def test_pixel_order_reads_r_back(gl, make_renderer, demo_scene):
    """transparent in pixel order (Style's default 'auto') takes the CPU branch: R is read back."""
    r = make_renderer(demo_scene, Settings(parameterize="gpu"))
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, 35, 25, 1.6)
    records = r.capture(cam, VP)
    _, view, proj = r.last
    cp, target = CompositePass(gl), CompositeTarget(gl)
    try:
        cp.render(
            atlas=r.atlas, records=records, gpu=r.gpu, style=Style(), mode="transparent", view=view, target=target
        )
        assert not cp.gpu_driven and records.is_read and "resolve" in cp.passes
    finally:
        cp.release()
        target.release()


@pytest.fixture(scope="module")
def assembly(tmp_path_factory):
    path = write_assembly(tmp_path_factory.mktemp("asm") / "asm.glb", 300, seed=4)
    return load_scene(path)


def composite_both(gl, r, mode, style):
    """The CPU branch's and the GPU-driven branch's composite of `r`'s last capture ((rgba, depth) each),
    R made on the CPU (Settings(parameterize="cpu")) and written into the record buffer for the GPU branch."""
    records, view, proj = r.last
    post = r.post_process(style) if mode == "ghosted-ao" else None
    kw = dict(atlas=r.atlas, gpu=r.gpu, style=style, mode=mode, post=post, view_proj=proj @ view)
    kw.update(eye=outline_eye(view, proj, r.scene.radius), ortho_near=ortho_near(proj))
    out = []
    for on_gpu in (False, True):
        cp, target = CompositePass(gl), CompositeTarget(gl)
        try:
            if on_gpu:
                r.gpu.records.write(records.packed())
                n = len(records.visible)
                gpu_records = GpuRecords(n, records.viewport, records.atlas_size, records.border, lambda: records)
                cp.render(records=gpu_records, view=view, target=target, **kw)
                assert cp.gpu_driven and not gpu_records.is_read
            else:
                cp.render(
                    records=records, view_depth=cp.view_depth(r.gpu, view, r.staging.offsets), target=target, **kw
                )
                assert not cp.gpu_driven
            rgba, depth = target.read()
            out.append((rgba.astype(int), depth.copy()))
        finally:
            cp.release()
            target.release()
    return out


def assert_close(cpu, gpu):
    """Colours within TOLERANCE on all but SHARE_OFF of the pixels, depths equal there too."""
    diff = np.abs(cpu[0] - gpu[0]).max(-1)
    off = (diff > TOLERANCE).mean()
    assert off <= SHARE_OFF, f"{off:.4%} of pixels over {TOLERANCE}/255 (max {diff.max()})"
    depth_off = (cpu[1] != gpu[1]).mean()
    assert depth_off <= SHARE_OFF, f"{depth_off:.4%} of pixels of another depth"


STYLES = {
    "plain": lambda ids: Style(order="object"),
    "focus": lambda ids: Style(order="object", focus=set(ids[:3].tolist())),
    "halo": lambda ids: Style(order="object", focus=set(ids[:2].tolist()), halo=4, outline_width=2),
}


@pytest.mark.parametrize("mode", ["ghosted", "ghosted-ao", "sprites", "transparent"])
@pytest.mark.parametrize("styled", list(STYLES))
@pytest.mark.parametrize("scene_name", ["demo", "assembly"])
def test_gpu_composite_equals_cpu(gl, make_renderer, demo_scene, assembly, scene_name, styled, mode):
    scene = demo_scene if scene_name == "demo" else assembly
    focus = np.arange(scene.count)[:: max(1, scene.count // 5)]
    style = STYLES[styled](focus)
    r = make_renderer(scene, Settings(parameterize="cpu", context_scale=0.5 if styled == "focus" else 1.0))
    cam = Camera.orbit(scene.center, scene.radius, 35, 25, 1.6)
    r.capture(cam, VP, focus=style.focus)
    assert_close(*composite_both(gl, r, mode, style))


@pytest.mark.parametrize("mode", ["ghosted", "ghosted-ao"])
def test_gpu_composite_upsampled_focus(gl, make_renderer, demo_scene, mode):
    """Focus regions upsampled (region_scale 0.5): the CPU branch draws their outlines in a pass
    of their own, the GPU branch with the focus sprites (at depth 0): the same colours, and
    the same depths but under the outlines."""
    r = make_renderer(demo_scene, Settings(parameterize="cpu", region_scale=0.5))
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, 35, 25, 1.6)
    style = Style(order="object", focus={1, 4, 7}, halo=3)
    records = r.capture(cam, VP, focus=style.focus)
    assert (records.scale[[1, 4, 7]] < 1).all()
    (cpu, cpu_depth), (gpu, gpu_depth) = composite_both(gl, r, mode, style)
    outline = np.abs(gpu[..., :3] - np.round(np.array(style.outline_color[:3]) * 255)).max(-1) <= 1
    assert outline.sum() > 100
    assert_close((cpu, np.where(outline, 0.0, cpu_depth)), (gpu, gpu_depth))


def test_gpu_composite_exploded(gl, make_renderer, demo_scene):
    r = make_renderer(demo_scene, Settings(parameterize="cpu"))
    restage(r, Staging(explode=0.6))
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, 200, -20, 1.8)
    style = Style(order="object", focus={1, 4})
    r.capture(cam, VP, focus=style.focus)
    assert r.staging.offsets is not None
    for mode in ("ghosted", "transparent"):
        assert_close(*composite_both(gl, r, mode, style))


@pytest.mark.parametrize("mode", ["ghosted", "sprites", "transparent"])
def test_gpu_composite_from_gpu_parameterize(gl, make_renderer, assembly, mode):
    """R as Algorithm 1 on the GPU leaves it (Settings(parameterize="gpu")): composited from
    the record buffer as it is, as the CPU branch composites it read back."""
    r = make_renderer(assembly, Settings(parameterize="gpu", context_scale=0.5))
    cam = Camera.orbit(assembly.center, assembly.radius, 120, 30, 1.5)
    style = Style(order="object", focus={3, 30, 90}, halo=2)
    records = r.capture(cam, VP, focus=style.focus)
    assert isinstance(records, GpuRecords) and not records.is_read
    _, view, proj = r.last
    kw = dict(atlas=r.atlas, gpu=r.gpu, style=style, mode=mode, view_proj=proj @ view)
    kw["eye"] = outline_eye(view, proj, assembly.radius)
    out = []
    for on_gpu in (True, False):  # the GPU branch first: nothing read before
        cp, target = CompositePass(gl), CompositeTarget(gl)
        try:
            if on_gpu:
                cp.render(records=records, view=view, target=target, **kw)
                assert cp.gpu_driven and not records.is_read
            else:
                depth = cp.view_depth(r.gpu, view)
                cp.render(records=records.read(), view_depth=depth, target=target, **kw)
            rgba, depth = target.read()
            out.append((rgba.astype(int), depth.copy()))
        finally:
            cp.release()
            target.release()
    background = np.round(np.array(BACKGROUND[:3]) * 255)
    assert (np.abs(out[0][0][..., :3] - background).max(-1) > 8).mean() > 0.2  # a picture, not a blank
    assert_close(out[1], out[0])


def test_gpu_branch_does_no_work_over_objects(gl, make_renderer, demo_scene, monkeypatch):
    """Per frame, the GPU branch reads nothing of R and sorts nothing on the CPU; the style
    parameters are built again only when the style changes."""
    r = make_renderer(demo_scene, Settings(parameterize="cpu"))
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, 35, 25, 1.6)
    style = Style(order="object", focus={2}, halo=3)
    records, view, proj = r.capture(cam, VP, focus=style.focus), *r.last[1:]
    r.gpu.records.write(records.packed())

    def unread():
        raise AssertionError("R read back")

    gpu_records = GpuRecords(len(records.visible), records.viewport, records.atlas_size, records.border, unread)
    cp, target = CompositePass(gl), CompositeTarget(gl)
    kw = dict(atlas=r.atlas, records=gpu_records, gpu=r.gpu, view=view, target=target, view_proj=proj @ view)
    kw["eye"] = outline_eye(view, proj, demo_scene.radius)
    built = []
    monkeypatch.setattr(composite_gpu, "style_params", lambda *a, **k: built.append(a[1]) or style_params(*a, **k))
    monkeypatch.setattr(composite_module, "back_to_front", lambda *a: pytest.fail("sorted on the CPU"))
    try:
        for mode in ("ghosted", "transparent", "sprites"):
            for _ in range(3):
                cp.render(style=style, mode=mode, **kw)
                assert cp.gpu_driven
        assert built == ["ghosted", "transparent", "sprites"]  # once per mode: the style did not change
        style.focus = {2, 3}
        cp.render(style=style, mode="sprites", **kw)
        assert len(built) == 4
        assert not gpu_records.is_read
    finally:
        cp.release()
        target.release()
