"""`--order pixel`: transparency blended per pixel in the order of the objects' own front
surfaces, checked against the blend computed in numpy from the atlas (issue 24)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import trimesh

from rtta.gl.readback import map_back
from rtta.passes import oit
from rtta.passes.composite import BACKGROUND, Style
from rtta.renderer.settings import Settings
from rtta.scene.camera import Camera
from rtta.scene.model import from_meshes

VP = (200, 150)
RASTER = Settings(blend="raster")  # object order as sprites on every GPU, as the CPU branch blends it


@pytest.fixture(params=["fetched", "lists"], autouse=True)
def list_path(request, monkeypatch, gl) -> bool:
    """Every test on both ways of listing the surfaces: the first three per pixel in colour
    attachments read through framebuffer fetch (llvmpipe, Mesa), or every one a node linked
    by an atomic exchange (NVIDIA and drivers without the fetch)."""
    fetched = request.param == "fetched"
    if fetched and not oit.first_fetched(gl):
        pytest.skip("this driver has no framebuffer fetch of colour and stencil")
    monkeypatch.setattr(oit, "first_fetched", lambda ctx: fetched)
    return fetched


def _nested_scene():
    """A sphere inside a sphere (equal bounds centres: the object order is a tie, broken by
    id, that puts the inner one in front) and a shaft through a housing (the shaft's centre
    is nearer the camera, so object order draws it over the housing's front face)."""
    outer = trimesh.creation.icosphere(3, 1.0)
    inner = trimesh.creation.icosphere(3, 0.5)
    housing = trimesh.creation.box(extents=(1.4, 0.8, 0.8))
    shaft = trimesh.creation.cylinder(0.15, 3.0, sections=24)
    parts = [
        ("outer", np.asarray(outer.vertices), np.asarray(outer.faces), None),
        ("inner", np.asarray(inner.vertices), np.asarray(inner.faces), None),
        ("housing", np.asarray(housing.vertices) + (2.6, 0, 0), np.asarray(housing.faces), None),
        ("shaft", np.asarray(shaft.vertices) + (2.6, 0.1, 0.9), np.asarray(shaft.faces), None),
    ]
    colors = [(0.8, 0.2, 0.1, 1), (0.1, 0.3, 0.9, 1), (0.2, 0.7, 0.2, 1), (0.9, 0.8, 0.1, 1)]
    return from_meshes(parts, colors)


def _numpy_blend(r, opacity: float) -> np.ndarray:
    """Each pixel: the objects whose mapped-back region covers it, sorted by their atlas
    depth, blended back to front over the background (float, 0..255)."""
    records = r.last[0]
    tw, th, td = records.atlas_size
    atlas = r.atlas.read((tw, th), td)
    atlas = {"color": atlas["color"], "depth": atlas["depth"]}
    maps = [map_back(atlas, records, o) for o in np.flatnonzero(records.visible)]
    depth = np.stack([m["depth"] for m in maps])  # [k, H, W], 1 where not covered
    color = np.stack([m["color"][..., :3] for m in maps]).astype(np.float64)
    order = np.argsort(-depth, axis=0, kind="stable")  # farthest first
    out = np.broadcast_to(np.array(BACKGROUND[:3]) * 255, depth.shape[1:] + (3,)).copy()
    for k in range(len(maps)):
        idx = order[k]
        d = np.take_along_axis(depth, idx[None], 0)[0]
        c = np.take_along_axis(color, idx[None, ..., None], 0)[0]
        a = np.where(d < 1.0, opacity, 0.0)[..., None]
        out = c * a + out * (1 - a)
    return out


@pytest.mark.parametrize("orbit", [(10, 15, 2.0), (-25, -10, 1.8)])
def test_pixel_order_equals_numpy_blend(make_renderer, orbit, list_path):
    scene = _nested_scene()
    r = make_renderer(scene)
    cam = Camera.orbit(scene.center, scene.radius, *orbit)
    r.capture(cam, VP)
    want = _numpy_blend(r, 0.5)
    got = r.composite("transparent", Style(order="pixel")).read()[0][..., :3].astype(np.float64)
    assert "resolve" in r._composite.passes and r._composite._pixel_order.fetch == list_path
    diff = np.abs(got - want).max(-1)
    assert diff.max() <= 3, f"pixel order differs from numpy by {diff.max()} at {int((diff > 3).sum())} px"
    objects = r.composite("transparent", Style(order="object")).read()[0][..., :3].astype(np.float64)
    wrong = np.abs(objects - want).max(-1) > 8
    assert wrong.sum() > 300, "object order agrees with the per-pixel blend: the scene proves nothing"


def test_pixel_order_overflow_keeps_nearest(make_renderer, monkeypatch):
    """Over the node bound the frame falls back to object order: counted, and said once (a
    warning, and in Renderer.warnings), however many frames fall back."""
    scene = _nested_scene()
    r = make_renderer(scene, RASTER)  # the same blend as the fallback (a compute blend differs by 1/255)
    cam = Camera.orbit(scene.center, scene.radius, 10, 15, 2.0)
    r.capture(cam, VP)
    by_object = r.composite("transparent", Style(order="object")).read()[0].copy()
    assert r.warnings == []
    monkeypatch.setattr(oit, "MAX_NODES", 10)
    with pytest.warns(UserWarning, match="more than 10 surfaces"):
        fallback = r.composite("transparent", Style(order="pixel")).read()[0]
    assert r._composite.fallbacks == 1 and np.array_equal(fallback, by_object)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # said once: no second warning
        r.composite("transparent", Style())
    assert r._composite.fallbacks == 2 and len(r.warnings) == 1 and "object order" in r.warnings[0]
    with pytest.raises(ValueError, match="order"):
        r.composite("transparent", Style(order="depth"))


def test_a_target_too_large_for_the_fetched_surfaces_keeps_the_lists(make_renderer, monkeypatch, list_path):
    """The fetched first surfaces take 33 bytes per target pixel: over FETCH_MAX_BYTES the
    frame keeps the lists (and releases the other way's targets), with the same picture; the
    next frame within the bound fetches again."""
    scene = _nested_scene()
    r = make_renderer(scene)
    r.capture(Camera.orbit(scene.center, scene.radius, 10, 15, 2.0), VP)
    first = r.composite("transparent", Style(order="pixel")).read()[0].copy()
    assert r._composite._pixel_order.fetch == list_path
    monkeypatch.setattr(oit, "FETCH_MAX_BYTES", VP[0] * VP[1] * oit.FETCHED_BYTES_PER_PIXEL - 1)
    large = r.composite("transparent", Style(order="pixel")).read()[0].copy()
    pixel_order = r._composite._pixel_order
    assert not pixel_order.fetch and list(pixel_order._marks) == [False]
    assert np.abs(large.astype(int) - first).max() <= 1
    monkeypatch.undo()
    monkeypatch.setattr(oit, "first_fetched", lambda ctx: list_path)
    again = r.composite("transparent", Style(order="pixel")).read()[0]
    assert pixel_order.fetch == list_path and np.array_equal(again, first)


def test_a_view_too_large_for_the_lists_blends_in_object_order(make_renderer, monkeypatch):
    """The lists' per-pixel targets (12 bytes a pixel) over LISTS_MAX_BYTES: object order,
    counted, and said with the view's size (not as too many surfaces)."""
    scene = _nested_scene()
    r = make_renderer(scene, RASTER)  # the same blend as the fallback (a compute blend differs by 1/255)
    r.capture(Camera.orbit(scene.center, scene.radius, 10, 15, 2.0), VP)
    by_object = r.composite("transparent", Style(order="object")).read()[0].copy()
    monkeypatch.setattr(oit, "FETCH_MAX_BYTES", 0)
    monkeypatch.setattr(oit, "LISTS_MAX_BYTES", VP[0] * VP[1] * oit.LIST_BYTES_PER_PIXEL - 1)
    with pytest.warns(UserWarning, match=f"per-pixel targets for this {VP[0]}x{VP[1]} view"):
        got = r.composite("transparent", Style(order="pixel")).read()[0]
    assert r._composite.fallbacks == 1 and np.array_equal(got, by_object)


def test_more_surfaces_than_kept_merge_behind(make_renderer):
    """12 nested spheres, more than the K = 8 surfaces the resolve sorts: the stated fallback.
    The 8 nearest surfaces are blended in exact depth order, the others merged into one layer
    behind them (opacity-weighted mean colour, opacity 1 - prod(1 - a)), whatever order the
    list holds them in (on a GPU, the order fragments arrived in). The spheres are drawn by
    id (equal bounds centres) and the nearest have the lowest ids, so keeping the 8 drawn
    last (what the list order alone would give on llvmpipe) fails here. The numpy blend of
    the rule matches; the exact blend does not."""
    k_kept, n = 8, 12
    parts = [
        (
            f"s{i}",
            np.asarray(trimesh.creation.icosphere(3, 0.5 + 0.05 * (n - 1 - i)).vertices),
            np.asarray(trimesh.creation.icosphere(3, 1.0).faces),
            None,
        )
        for i in range(n)
    ]
    strong = [(0.9, 0.1, 0.1, 1), (0.1, 0.8, 0.1, 1), (0.1, 0.1, 0.9, 1), (0.9, 0.9, 0.1, 1)]
    scene = from_meshes(parts, [(0.5, 0.5, 0.5, 1)] * k_kept + strong)
    r = make_renderer(scene)
    cam = Camera.orbit(scene.center, scene.radius, 0, 0, 2.5)
    r.capture(cam, VP)
    # faint outer shells (ids 0-7, nearest: kept), strong inner spheres (ids 8-11: merged)
    opacity = {i: 0.08 if i < k_kept else 0.9 for i in range(n)}
    got = r.composite("transparent", Style(order="pixel", opacity=opacity)).read()[0][..., :3].astype(np.float64)
    records = r.last[0]
    tw, th, td = records.atlas_size
    atlas = r.atlas.read((tw, th), td)
    maps = [map_back({"color": atlas["color"], "depth": atlas["depth"]}, records, o) for o in range(n)]
    depth = np.stack([m["depth"] for m in maps])
    color = np.stack([m["color"][..., :3] for m in maps]).astype(np.float64)
    alpha = np.array([opacity[i] for i in range(n)])
    y, x = VP[1] // 2, VP[0] // 2  # the centre: all 12 cover it
    assert (depth[:, y, x] < 1).all()
    kept = np.argsort(depth[:, y, x])[:k_kept]  # the nearest
    assert set(kept) == set(range(k_kept)), "the outer shells are not the nearest: the test proves nothing"
    out, exact = _kept_and_merged(color[:, y, x], depth[:, y, x], alpha, k_kept)
    assert np.abs(got[y, x] - out).max() <= 3, (got[y, x], out, exact)
    assert np.abs(exact - out).max() > 3, "the fallback equals the exact blend here: the test proves nothing"


def _kept_and_merged(color: np.ndarray, depth: np.ndarray, alpha: np.ndarray, k_kept: int):
    """One pixel's surfaces (colour [n, 3] in 0..255, depth [n], opacity [n]) blended over the
    background by the resolve's rule: the k_kept nearest in depth order, the rest merged
    behind them (opacity-weighted mean colour, opacity 1 - prod(1 - a)); and exactly."""
    by_depth = np.argsort(depth, kind="stable")  # nearest first
    kept, rest = by_depth[:k_kept], by_depth[k_kept:]
    out = np.array(BACKGROUND[:3]) * 255
    if len(rest):
        w = alpha[rest]
        tail_a = 1 - np.prod(1 - w)
        out = (w[:, None] * color[rest]).sum(0) / w.sum() * tail_a + out * (1 - tail_a)
    for o in kept[::-1]:  # farthest first
        out = color[o] * alpha[o] + out * (1 - alpha[o])
    exact = np.array(BACKGROUND[:3]) * 255
    for o in by_depth[::-1]:
        exact = color[o] * alpha[o] + exact * (1 - alpha[o])
    return out, exact


def test_a_pixel_with_hundreds_of_surfaces(make_renderer, list_path):
    """150 nested spheres of low opacity over the centre: more surfaces than the fetched
    path's stencil counts (127, saturating) and than the K = 8 kept; the centre follows the
    resolve's rule, which differs from the exact blend there (so the test can fail)."""
    n, k_kept = 150, 8
    sphere = trimesh.creation.icosphere(1, 1.0)
    parts = [
        (f"s{i}", np.asarray(sphere.vertices) * (0.3 + 0.7 * i / n), np.asarray(sphere.faces), None) for i in range(n)
    ]
    rng = np.random.default_rng(7)
    scene = from_meshes(parts, [(*rng.uniform(0.1, 0.9, 3), 1.0) for _ in range(n)])
    r = make_renderer(scene)
    r.capture(Camera.orbit(scene.center, scene.radius, 0, 0, 2.5), VP)
    opacity = {i: 0.06 for i in range(n)}
    got = r.composite("transparent", Style(order="pixel", opacity=opacity)).read()[0][..., :3].astype(np.float64)
    assert r._composite._pixel_order.fetch == list_path
    records = r.last[0]
    tw, th, td = records.atlas_size
    atlas = r.atlas.read((tw, th), td)
    maps = [map_back({"color": atlas["color"], "depth": atlas["depth"]}, records, o) for o in range(n)]
    y, x = VP[1] // 2, VP[0] // 2
    depth = np.array([m["depth"][y, x] for m in maps])
    color = np.array([m["color"][y, x, :3] for m in maps], np.float64)
    assert (depth < 1).all()
    want, exact = _kept_and_merged(color, depth, np.full(n, 0.06), k_kept)
    assert np.abs(got[y, x] - want).max() <= 3, (got[y, x], want, exact)
    assert np.abs(exact - want).max() > 3, "the rule equals the exact blend here: the test proves nothing"


def _numpy_ghosted(r, focus: list[int], style: Style, clip: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """`ghosted` from the atlas in numpy: the focus objects opaque (nearest surface), then
    per pixel the context surfaces in front of them (all, where no focus covers), sorted by
    depth, desaturated, blended back to front with the context opacity. Also the mask of
    pixels within 3 of a focus silhouette (the outline drawn there is left out)."""
    records = r.last[0]
    tw, th, td = records.atlas_size
    atlas = r.atlas.read((tw, th), td)
    atlas = {"color": atlas["color"], "depth": atlas["depth"]}
    visible = np.flatnonzero(records.visible)
    maps = {o: map_back(atlas, records, o) for o in visible}
    out = np.broadcast_to(np.array(BACKGROUND[:3]) * 255, (VP[1], VP[0], 3)).copy()
    front = np.ones((VP[1], VP[0]))
    for o in focus:
        d = maps[o]["depth"]
        near = d < front
        out[near] = maps[o]["color"][..., :3][near]
        front = np.where(near, d, front)
    context = [o for o in visible if o not in focus]
    limit = front if clip else 1.0
    depth = np.stack([np.where(maps[o]["depth"] < limit, maps[o]["depth"], 1.0) for o in context])
    color = np.stack([maps[o]["color"][..., :3] for o in context]).astype(np.float64)
    grey = (color * [0.299, 0.587, 0.114]).sum(-1, keepdims=True)
    color = color + (grey - color) * style.desaturate
    for k in np.argsort(-depth, axis=0, kind="stable"):  # farthest first
        d = np.take_along_axis(depth, k[None], 0)[0]
        c = np.take_along_axis(color, k[None, ..., None], 0)[0]
        a = np.where(d < 1.0, style.context_opacity, 0.0)[..., None]
        out = c * a + out * (1 - a)
    covered = front < 1.0
    edge = np.zeros_like(covered)
    for dy in range(-3, 4):
        for dx in range(-3, 4):
            edge |= np.roll(covered, (dy, dx), (0, 1)) != covered
    return out, edge


@pytest.mark.parametrize("orbit", [(10, 15, 2.0), (-25, -10, 1.8)])
@pytest.mark.parametrize("focus", [1, 3])
def test_ghosted_context_in_pixel_order_equals_numpy(make_renderer, orbit, focus, list_path):
    """The ghosted context blended per pixel. Focus on the inner sphere: inside its context
    shell, with the shaft and housing (context) through each other, where object order is
    shown to differ. Focus on the shaft: the housing's face behind it is hidden (the numpy
    blend without that differs, so a missing clip fails)."""
    scene = _nested_scene()
    r = make_renderer(scene)
    cam = Camera.orbit(scene.center, scene.radius, *orbit)
    r.capture(cam, VP)
    style = Style(focus={focus}, order="pixel", context_opacity=0.7, desaturate=0.2)  # strong enough to tell
    want, edge = _numpy_ghosted(r, [focus], style)
    got = r.composite("ghosted", style).read()[0][..., :3].astype(np.float64)
    assert "resolve" in r._composite.passes and r._composite._pixel_order.fetch == list_path
    diff = np.abs(got - want).max(-1)
    diff[edge] = 0
    assert diff.max() <= 3, f"ghosted pixel order differs from numpy by {diff.max()} at {int((diff > 3).sum())} px"
    if focus == 3:
        unclipped, _ = _numpy_ghosted(r, [focus], style, clip=False)
        assert ((np.abs(unclipped - want).max(-1) > 8) & ~edge).sum() > 30, "nothing lies behind the focus"
        return
    objects = r.composite("ghosted", Style(focus={1}, context_opacity=0.7, desaturate=0.2)).read()[0][..., :3]
    wrong = (np.abs(objects.astype(np.float64) - want).max(-1) > 8) & ~edge
    assert wrong.sum() > 30, "object order agrees with the per-pixel blend: the scene proves nothing"


def test_coplanar_surfaces_blend_alike_in_any_draw_order(make_renderer):
    """Two parts sharing a face (coincident boxes, as adjacent CAD parts often are): their
    surfaces have equal depths, and the per-pixel blend of the pair must not depend on which
    one is drawn (or reaches the list) first. The same scene with its objects in the other
    order gives the same image; object order is shown to depend on it (so the pair's order
    matters to the blend and the test can fail)."""
    box = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    red, blue = (0.9, 0.1, 0.1, 1), (0.1, 0.2, 0.9, 1)
    part = (np.asarray(box.vertices), np.asarray(box.faces), None)
    images = {}
    for name, colors in (("red first", [red, blue]), ("blue first", [blue, red])):
        scene = from_meshes([("a", *part), ("b", *part)], colors)
        r = make_renderer(scene)
        r.capture(Camera.orbit(scene.center, scene.radius, 20, 15, 2.2), VP)
        images[name] = {
            order: r.composite("transparent", Style(default_opacity=0.6, order=order))
            .read()[0][..., :3]
            .astype(np.int64)
            for order in ("pixel", "object")
        }
    covered = (np.abs(images["red first"]["pixel"] - np.array(BACKGROUND[:3]) * 255).max(-1) > 8).sum()
    assert covered > 2000
    by_object = np.abs(images["red first"]["object"] - images["blue first"]["object"]).max(-1)
    assert (by_object > 8).sum() > 1000, "the pair's order does not matter to the blend: the test proves nothing"
    by_pixel = np.abs(images["red first"]["pixel"] - images["blue first"]["pixel"]).max(-1)
    assert by_pixel.max() <= 1, f"pixel order depends on the draw order at {int((by_pixel > 1).sum())} px"


def test_cli_says_the_fallback_in_one_line(tmp_path, capsys, monkeypatch):
    """`rtta snapshot` says a degraded frame as one `rtta: warning: ...` line (no Python
    warning format, no source line) and still writes the image."""
    from rtta.cli.main import main

    monkeypatch.setattr(oit, "MAX_NODES", 10)
    out = tmp_path / "t.png"
    assert main(["snapshot", "--mode", "transparent", "--size", "96x72", "--out", str(out)]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert out.is_file()
    assert len(err) == 1 and err[0].startswith("rtta: warning: per-pixel order would need more than 10"), err


def test_a_reallocated_target_is_drawn_into(make_renderer):
    """The marking pass's framebuffer follows the composite target: released and allocated
    again at the same size, the target gets the same picture, not one drawn into a framebuffer
    kept from before. A driver that hands out a released name again (NVIDIA's does; Mesa's
    does not) gives the new texture the old one's GL name: that is simulated here."""
    scene = _nested_scene()
    r = make_renderer(scene)
    r.capture(Camera.orbit(scene.center, scene.radius, 10, 15, 2.0), VP)
    first = r.composite("transparent", Style(order="pixel")).read()[0].copy()
    for _ in range(2):
        old_name = r.target.color.glo
        r.target.release()
        r.target.ensure(VP)
        r.target.color._glo = old_name  # what the new texture is called on such a driver
        again = r.composite("transparent", Style(order="pixel")).read()[0]
        assert np.array_equal(again, first)


def test_in_place_bound_follows_opacity():
    """How many in-order surfaces keep the 8-bit object-order blend: the rounding each leaves
    is damped by (1 - a) per surface over it, so from opacity 0.4 up any number (up to the
    stencil's 254; at 0.4 the sum nears the budget only from below), and fewer as the
    opacity falls (oit.ROUNDING_BUDGET)."""
    bound = [oit.blended_in_place(a) for a in (1.0, 0.5, 0.3, 0.2, 0.1, 0.0)]
    assert bound == [254, 254, 3, 3, 2, 2] and oit.blended_in_place(0.4) >= 64
    for a in (0.3, 0.2, 0.1, 0.0):
        n = oit.blended_in_place(a)
        assert sum((1 - a) ** k for k in range(n)) <= oit.ROUNDING_BUDGET < sum((1 - a) ** k for k in range(n + 1))
