"""The capture's draw lists built on the GPU (rtta.passes.draw_lists, issue 43): with R on the
GPU (GpuRecords) the capture draws the same atlas as the CPU path does from R's arrays, on
both capture paths, for views that cull, hide, cut with the near plane, clip at the viewport's
edge and explode; the lists hold the objects the CPU would draw, merged as promised; the
frame does no per-object work on the CPU."""

from __future__ import annotations

import numpy as np
import pytest

from rtta.atlas.parameterize import parameterize
from rtta.atlas.records import GpuRecords
from rtta.gl.gpu import GpuScene
from rtta.gl.targets import LayeredTarget
from rtta.passes import capture as capture_module
from rtta.passes.capture import CapturePass
from rtta.passes.draw_lists import LOCAL_SIZE, kind
from rtta.passes.sections import Placement
from rtta.scene.camera import Camera
from rtta.scene.closure import beyond_near
from rtta.scene.explode import explode_offsets

VIEWPORT = (200, 150)
PATHS = ("vs", "gs")
# (az, el, dist): an outside view; close (objects culled and on the viewport's edge); inside
# the scene (the near plane cuts objects, those behind the eye are culled)
VIEWS = {"outside": (30, 25, 2.2), "close": (120, -30, 0.9), "inside": (250, 10, 0.25), "ortho": (200, 35, 0.7)}


@pytest.fixture(scope="module")
def assembly(tmp_path_factory):
    from rtta.scene.generators.assembly import write_assembly
    from rtta.scene.loader import load_scene

    return load_scene(write_assembly(tmp_path_factory.mktemp("lists") / "parts.glb", 300, seed=4))


@pytest.fixture(scope="module")
def rig(ctx, demo_scene, assembly):
    """Per scene its GpuScene, per path a CapturePass, and two atlases (CPU path, GPU lists)."""
    gpus = {"demo": GpuScene(ctx, demo_scene), "assembly": GpuScene(ctx, assembly)}
    passes = {path: CapturePass(ctx, path) for path in PATHS}
    atlases = [LayeredTarget(ctx, (64, 64), 1, depth_keyed=True) for _ in range(2)]
    yield gpus, passes, atlases
    for p in passes.values():
        p.release()
    for t in atlases:
        t.release()
    for g in gpus.values():
        if g.placement is not None:
            g.placement.release()
        g.release()


def place(ctx, gpu: GpuScene, offsets=None, removed=None) -> None:
    """Explode offsets and objects cut away whole, no section plane (as
    rtta.renderer.placing.Staging.place leaves them: B_world in gpu.bounds moved)."""
    scene, n = gpu.scene, gpu.scene.count
    if gpu.placement is not None:
        gpu.placement.release()
        gpu.placement = None
    shift = 0.0 if offsets is None else offsets
    bounds = np.zeros((n, 2, 4), np.float32)
    bounds[:, 0, :3] = scene.aabb_min - scene.origin + shift
    bounds[:, 1, :3] = scene.aabb_max - scene.origin + shift
    gpu.bounds.write(bounds.tobytes())
    if offsets is None and removed is None:
        return
    removed = np.zeros(n, bool) if removed is None else removed
    data = np.zeros((n, 4), np.float32)
    if offsets is not None:
        data[:, :3] = offsets
    none = np.zeros(n, bool)
    planes = np.zeros((0, 4), np.float32)
    placement = Placement(offsets, removed, none, none, planes, 0, 1.0, ctx.buffer(data.tobytes()))
    gpu.placement = placement  # pyright: ignore[reportAttributeAccessIssue]  (GpuScene declares it None)


def frame(gpu: GpuScene, view_name: str, hidden=None, offsets=None, **packing):
    """The view's matrices and R (Algorithm 1 on the CPU, `packing`: its border, region
    scale...), B_world moved by `offsets`."""
    scene = gpu.scene
    projection = "ortho" if view_name == "ortho" else "perspective"
    cam = Camera.orbit(scene.center, scene.radius, *VIEWS[view_name], projection=projection)
    view, proj = cam.view(scene.origin), cam.projection(VIEWPORT[0] / VIEWPORT[1])
    corners = scene.box_corners()
    if offsets is not None:
        corners = corners + offsets[:, None, :]
    return view, proj, parameterize(corners, proj @ view, VIEWPORT, hidden=hidden, **packing)


def on_gpu(gpu: GpuScene, rec) -> GpuRecords:
    """R written into the record buffer and handed to the scene, as Algorithm 1's shaders
    leave it (GpuParameterize.run)."""
    gpu.records.write(rec.packed())
    records = GpuRecords(gpu.scene.count, rec.viewport, rec.atlas_size, rec.border, lambda: rec)
    gpu.hand(records)
    return records


def capture_both(rig, scene_name, path, view_name, hidden=None, offsets=None, removed=None, **packing):
    """The atlas images from the CPU path and from the GPU lists, and R."""
    gpus, passes, (cpu_atlas, gpu_atlas) = rig
    gpu, cap = gpus[scene_name], passes[path]
    place(gpu.ctx, gpu, offsets, removed)
    view, proj, rec = frame(gpu, view_name, hidden, offsets, **packing)
    cap.render(gpu=gpu, records=rec, view=view, proj=proj, atlas=cpu_atlas)
    assert not cap.gpu_lists_used
    expected = cpu_atlas.read()
    records = on_gpu(gpu, rec)
    cap.render(gpu=gpu, records=records, view=view, proj=proj, atlas=gpu_atlas)
    assert cap.gpu_lists_used and not records.is_read, "the GPU path read R back"
    return expected, gpu_atlas.read(), rec, (view, proj)


def assert_same_atlas(expected: dict, got: dict) -> None:
    """Every image texel-equal: each object draws the same triangles in the same order into a
    region of its own, so the order of the lists' commands cannot show."""
    assert expected.keys() == got.keys()
    for name in expected:
        a, b = expected[name], got[name]
        assert a.shape == b.shape, name
        bad = np.argwhere(a != b) if name == "depth" else np.argwhere((a != b).reshape(*a.shape[:3], -1).any(-1))
        assert not len(bad), f"{name}: {len(bad)} texels differ, first at {bad[:3].tolist()}"
    assert (expected["depth"] < 1.0).any(), "nothing was drawn"


def cpu_kinds(gpu: GpuScene, rec, view, proj, clip_all: bool, cull_closed: bool = True) -> np.ndarray:
    """int [n]: each object's list as the CPU path decides (-1: not drawn)."""
    scene, placement = gpu.scene, gpu.placement
    lo, hi = scene.aabb_min - scene.origin, scene.aabb_max - scene.origin
    if placement is not None and placement.offsets is not None:
        lo, hi = lo + placement.offsets, hi + placement.offsets
    cull = scene.closed & beyond_near(lo, hi, view, proj) & cull_closed
    clip = np.ones(scene.count, bool) if clip_all else rec.meets_edge
    kinds = np.where(clip, kind(True, True), kind(True, False)) + ~cull
    drawn = rec.visible & (scene.index_ranges[:, 1] > 0)
    if placement is not None:
        drawn &= ~placement.removed
    return np.where(drawn, kinds, -1)


def promised_runs(scene, kinds: np.ndarray) -> int:
    """The commands the merging promises: a new one at each drawn object whose predecessor
    differs in kind, lies apart in the index buffer, or opens a block of LOCAL_SIZE."""
    first, count = scene.index_ranges[:, 0], scene.index_ranges[:, 1]
    i = np.arange(len(kinds))
    new = (i % LOCAL_SIZE == 0) | np.r_[True, (kinds[1:] != kinds[:-1]) | (first[1:] != first[:-1] + count[:-1])]
    return int((new & (kinds >= 0)).sum())


def objects_of(scene, commands: np.ndarray) -> np.ndarray:
    """The object ids the commands [k, 5] draw (each covers whole objects), sorted."""
    first = scene.index_ranges[:, 0]
    out = []
    for count, instances, start, base_vertex, base_instance in commands.tolist():
        assert (instances, base_vertex, base_instance) == (1, 0, 0)
        a, b = np.searchsorted(first, [start, start + count])
        assert first[a] == start and scene.index_ranges[b - 1].sum() == start + count, "not whole objects"
        out.extend(range(a, b))
    return np.sort(np.array(out, np.int64))


CASES = [
    ("demo", "outside", {}),
    ("demo", "close", {}),
    ("demo", "inside", {}),
    ("assembly", "outside", {}),
    ("assembly", "close", {}),
    ("assembly", "inside", {}),
    ("assembly", "ortho", {}),
    ("assembly", "outside", {"hidden": 3}),
    ("assembly", "close", {"explode": 0.6}),
    ("demo", "outside", {"explode": 1.0}),
    ("assembly", "outside", {"removed": 5}),
    ("assembly", "close", {"double_sided": True}),
    ("demo", "inside", {"double_sided": True, "hidden": 4}),
]


def options(scene, extra: dict) -> dict:
    """hidden / explode offsets / removed objects for a case (every k-th object)."""
    n, out = scene.count, {}
    if "hidden" in extra:
        out["hidden"] = np.arange(n) % extra["hidden"] == 0
    if "explode" in extra:
        out["offsets"] = explode_offsets(scene, extra["explode"])
    if "removed" in extra:
        out["removed"] = np.arange(n) % extra["removed"] == 1
    return out


@pytest.mark.parametrize("path", PATHS)
@pytest.mark.parametrize(("scene_name", "view_name", "extra"), CASES)
def test_gpu_lists_capture_the_cpu_paths_atlas(gl, rig, scene_name, view_name, extra, path):
    gpu = rig[0][scene_name]
    opts = options(gpu.scene, extra)
    gpu.cull_closed = not extra.get("double_sided", False)
    try:
        expected, got, rec, (view, proj) = capture_both(rig, scene_name, path, view_name, **opts)
    finally:
        gpu.cull_closed = True
    assert_same_atlas(expected, got)
    lists = rig[1][path].lists
    kinds = cpu_kinds(gpu, rec, view, proj, clip_all=path == "gs", cull_closed=not extra.get("double_sided"))
    lengths = lists.lengths()
    for k in range(4):
        assert np.array_equal(objects_of(gpu.scene, lists.commands_of(k)), np.flatnonzero(kinds == k)), f"list {k}"
    assert lengths.sum() == promised_runs(gpu.scene, kinds)
    changes = int((np.diff(kinds) != 0).sum())
    assert lengths.sum() <= -(-gpu.scene.count // LOCAL_SIZE) + changes


def test_cases_cover_culling_hiding_near_cuts_edges(gl, rig):
    """The views above do what their names say: objects culled, cut by the near plane, on the
    viewport's edge and not, closed ones culled and double-sided ones drawn."""
    gpu = rig[0]["assembly"]
    place(gpu.ctx, gpu)
    seen = {}
    for name in VIEWS:
        view, proj, rec = frame(gpu, name)
        seen[name] = (rec, cpu_kinds(gpu, rec, view, proj, clip_all=False))
    rec, kinds = seen["close"]
    assert (~rec.visible).any(), "none culled"
    assert (kinds == kind(True, True)).any() and (kinds == kind(True, False)).any(), "not on the edge and off it"
    rec, kinds = seen["inside"]
    assert gpu.scene.closed.all()
    assert (kinds == kind(False, True)).any(), "no closed object cut by the near plane (drawn double-sided)"
    assert (kinds == kind(True, True)).any(), "no closed object beyond the near plane on the edge"


def test_without_indirect_parameters_the_lengths_are_read(gl, rig):
    """The fallback for drivers without GL_ARB_indirect_parameters draws the same atlas."""
    cap = rig[1]["vs"]
    capture_both(rig, "demo", "vs", "close")  # makes the lists
    assert cap.lists is not None
    was, cap.lists.count_draw = cap.lists.count_draw, False
    try:
        expected, got, _, _ = capture_both(rig, "demo", "vs", "close")
    finally:
        cap.lists.count_draw = was
    assert_same_atlas(expected, got)


def test_sections_keep_the_cpu_path(gl, rig):
    """A section plane cutting objects: the CPU path draws (its programs and caps), reading R back."""
    gpus, passes, (atlas, _) = rig
    gpu, cap = gpus["demo"], passes["vs"]
    place(gpu.ctx, gpu)
    view, proj, rec = frame(gpu, "outside")
    n = gpu.scene.count
    cut = np.arange(n) % 2 == 0
    data = np.zeros((n, 4), np.float32)
    data[:, 3] = cut
    plane = np.array([[1.0, 0.0, 0.0, 0.0]], np.float32)
    gpu.placement = Placement(
        None, np.zeros(n, bool), cut, np.zeros(n, bool), plane, 0, 1.0, gpu.ctx.buffer(data.tobytes())
    )
    try:
        records = on_gpu(gpu, rec)
        cap.render(gpu=gpu, records=records, view=view, proj=proj, atlas=atlas)
        assert not cap.gpu_lists_used and records.is_read
    finally:
        place(gpu.ctx, gpu)


def test_gpu_frame_does_no_per_object_work_on_the_cpu(gl, rig, monkeypatch):
    """The lists' frame calls neither index_runs nor beyond_near (the CPU path's numpy over
    n), and reads nothing of R."""
    gpus, passes, (_, atlas) = rig
    calls = {"index_runs": 0, "beyond_near": 0}
    scene_type = type(gpus["assembly"].scene)
    index_runs = scene_type.index_runs

    def counted_runs(self, mask):
        calls["index_runs"] += 1
        return index_runs(self, mask)

    def counted_near(*args):
        calls["beyond_near"] += 1
        return beyond_near(*args)

    monkeypatch.setattr(scene_type, "index_runs", counted_runs)
    monkeypatch.setattr(capture_module, "beyond_near", counted_near)
    for path in PATHS:
        for name in ("assembly", "demo"):
            gpu = gpus[name]
            place(gpu.ctx, gpu)
            view, proj, rec = frame(gpu, "close")
            records = on_gpu(gpu, rec)
            passes[path].render(gpu=gpu, records=records, view=view, proj=proj, atlas=atlas)
            assert passes[path].gpu_lists_used and not records.is_read
    assert calls == {"index_runs": 0, "beyond_near": 0}
    view, proj, rec = frame(gpus["demo"], "close")
    passes["vs"].render(gpu=gpus["demo"], records=rec, view=view, proj=proj, atlas=atlas)  # the CPU path counts
    assert calls["beyond_near"] > 0


@pytest.mark.parametrize("path", PATHS)
def test_the_order_of_commands_does_not_show(gl, rig, monkeypatch, path):
    """The lists' order comes from the GPU's atomics (another on NVIDIA than on llvmpipe): each
    list reversed after it is built, the atlas stays texel-equal to the CPU path's."""
    from rtta.gl.indirect import COMMAND_BYTES
    from rtta.passes.draw_lists import CaptureLists

    build = CaptureLists.build
    reversed_lists = []

    def build_reversed(self, *args, **kw):
        build(self, *args, **kw)
        for k in range(4):
            commands = self.commands_of(k)
            if len(commands) > 1:
                self.commands.write(commands[::-1].copy().tobytes(), offset=k * self.capacity * COMMAND_BYTES)
                reversed_lists.append(k)

    monkeypatch.setattr(CaptureLists, "build", build_reversed)
    for view_name, packing in (
        ("close", {}),
        ("inside", {}),
        ("close", {"border": 0, "region_scale": 0.37}),  # regions touching, edges between texels
        ("outside", {"border": 0, "region_scale": 1.7}),
    ):
        expected, got, _, _ = capture_both(rig, "assembly", path, view_name, **packing)
        assert_same_atlas(expected, got)
    assert reversed_lists, "no list had two commands"


def test_blocks_past_one_row_of_workgroups(gl, rig, monkeypatch):
    """More blocks than a dispatch takes along x (65,535; here 2): a 2-D dispatch, the same atlas."""
    from rtta.passes import draw_lists

    monkeypatch.setattr(draw_lists, "MAX_GROUPS", 2)
    for path in PATHS:
        expected, got, _, _ = capture_both(rig, "assembly", path, "close")
        assert_same_atlas(expected, got)


def python_calls(fn) -> int:
    """The Python and C functions `fn()` calls (sys.setprofile)."""
    import sys

    calls = 0

    def count(frame, event, arg):
        nonlocal calls
        calls += event in ("call", "c_call")

    sys.setprofile(count)
    try:
        fn()
    finally:
        sys.setprofile(None)
    return calls


@pytest.mark.parametrize("path", PATHS)
def test_gpu_frame_makes_as_many_calls_at_any_size(gl, rig, path):
    """A frame from the lists makes the same Python and C calls for 24 objects as for 300:
    nothing in it loops over the objects."""
    gpus, passes, (_, atlas) = rig
    counted = []
    for name in ("demo", "assembly"):
        gpu = gpus[name]
        place(gpu.ctx, gpu)
        view, proj, rec = frame(gpu, "close")
        records = on_gpu(gpu, rec)

        def render(gpu=gpu, records=records, view=view, proj=proj):
            passes[path].render(gpu=gpu, records=records, view=view, proj=proj, atlas=atlas)

        render()  # the lists' buffers for this scene, the atlas's size
        counted.append(python_calls(render))
    assert counted[0] == counted[1] and counted[0] > 50, counted
