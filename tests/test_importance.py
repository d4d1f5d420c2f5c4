"""Importance-driven capture and shading (issue 24): per-object region scales in Algorithm 1,
depth-aware upsampling of context regions, AO/edges by role with per-object caching."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from checks import assert_depth_close

from rtta.atlas.parameterize import parameterize
from rtta.passes.composite import BACKGROUND, Style
from rtta.renderer.renderer import Settings
from rtta.scene.camera import Camera
from rtta.scene.model import from_meshes

VP = (240, 180)
COLORS = [
    (0.75, 0.1, 0.1, 1.0),
    (0.1, 0.55, 0.15, 1.0),
    (0.15, 0.2, 0.75, 1.0),
    (0.6, 0.45, 0.05, 1.0),
    (0.5, 0.1, 0.55, 1.0),
    (0.05, 0.45, 0.5, 1.0),
]


def _grid_scene(rows=3, cols=4):
    """Tilted boxes in the XY plane, apart: seen from +Z no two overlap, every object has its
    own saturated colour, far from the light background, and every face one shade (flat
    faces). Every other box is axis-aligned, its front face at z = 0.2: it fills its region
    to the edges, so with border 0 its texels touch the next region's in the atlas, at the
    same depth (the depth-aware weights alone would not keep them apart)."""
    rng = np.random.default_rng(5)
    parts, colors = [], []
    for i in range(rows * cols):
        mesh = trimesh.creation.box(extents=(0.8, 0.7, 0.6) if i % 2 else (1.0, 0.5, 0.4))
        rot = trimesh.transformations.random_rotation_matrix(rng.random(3))[:3, :3] if i % 2 else np.eye(3)
        center = np.array([i % cols * 1.5, i // cols * 1.5, rng.uniform(-0.5, 0.5) if i % 2 else 0.0])
        parts.append((f"o{i}", np.asarray(mesh.vertices) @ rot.T + center, np.asarray(mesh.faces), None))
        colors.append(COLORS[i % len(COLORS)])
    return from_meshes(parts, colors)


def _front(scene, projection="perspective"):
    return Camera.orbit(scene.center, scene.radius, 0.0, 0.0, 2.0, projection=projection)


def test_per_object_scale_sizes_regions():
    """A scale per object: focus regions as at scale 1, context ones about half as wide; a
    scalar and an array of the same value give the same records."""
    scene = _grid_scene()
    cam = _front(scene)
    vpm = cam.projection(VP[0] / VP[1]) @ cam.view(scene.origin)
    corners = scene.box_corners()
    full = parameterize(corners, vpm, VP, region_scale=1.0)
    same = parameterize(corners, vpm, VP, region_scale=np.ones(scene.count))
    assert np.array_equal(full.atlas_rect, same.atlas_rect) and np.array_equal(full.transform, same.transform)
    scale = np.full(scene.count, 0.5)
    scale[[0, 3]] = 1.0
    mixed = parameterize(corners, vpm, VP, region_scale=scale)
    assert np.array_equal(mixed.atlas_rect[[0, 3], 2:], full.atlas_rect[[0, 3], 2:])
    inner = full.atlas_rect[:, 2:] - 2
    half = mixed.atlas_rect[:, 2:] - 2
    ctx = np.setdiff1d(np.arange(scene.count), [0, 3])
    assert (half[ctx] == np.ceil(inner[ctx] * 0.5 - 1e-9)).all()
    with pytest.raises(ValueError, match="region scale"):
        parameterize(corners, vpm, VP, region_scale=np.ones(3))


def test_focus_at_scale_one_is_exact(make_renderer, demo_scene):
    """With every object in focus, a context scale changes nothing: sprites still equal STD
    (the same image as without the context scale)."""
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, 30, 20, 2.2)
    everyone = set(range(demo_scene.count))
    out = []
    for cs in (1.0, 0.5):
        r = make_renderer(demo_scene, Settings(context_scale=cs))
        rec = r.capture(cam, VP, focus=everyone)
        assert (rec.scale[rec.visible] == 1.0).all()
        out.append(r.composite("sprites", Style(focus=everyone)).read())
    assert np.array_equal(out[0][0], out[1][0]) and np.array_equal(out[0][1], out[1][1])
    std = r.std(cam, VP).read(VP, 1)
    cov = std["id"][0] >= 0
    assert_depth_close(out[1][1], std["depth"][0], cov, std["id"][0], "sprites at context scale 0.5")


def _neighbourhood(a: np.ndarray, fn, fill, r: int = 1) -> np.ndarray:
    """fn over each pixel's (2r+1)^2 neighbourhood (edges padded with `fill`)."""
    p = np.pad(a, [(r, r), (r, r)] + [(0, 0)] * (a.ndim - 2), constant_values=fill)
    h, w = a.shape[:2]
    k = 2 * r + 1
    stack = np.stack([p[dy : dy + h, dx : dx + w] for dy in range(k) for dx in range(k)])
    return fn(stack, axis=0)


def _paint_empty(atlas, rgba) -> None:
    """Set the colour of every texel whose depth is 1 (empty) to `rgba`."""
    w, h = atlas.size
    raw = np.frombuffer(atlas.color.read(), np.uint8).reshape(-1, h, w, 4).copy()
    empty = atlas.depth.read().reshape(raw.shape[:3]) >= 1.0
    raw[empty] = np.round(np.asarray(rgba) * 255)
    atlas.color.write(raw.tobytes())


@pytest.mark.parametrize(
    ("border", "scale", "projection"), [(0, 0.5, "perspective"), (1, 0.5, "perspective"), (0, 0.3, "perspective"),
                                        (1, 0.5, "ortho"), (0, 0.3, "ortho")]
)  # fmt: skip
def test_upsampling_never_bleeds(make_renderer, border, scale, projection):
    """At context scale 0.5 every pixel a context object covers lies within one pixel of its
    scale-1 silhouette and has a colour within the range of the scale-1 object pixels within
    one texel (2 pixels) of it (at 0.3, where pixels fall anywhere between texels and a
    missing B_atlas test shows: 2 and 4 pixels): no background and no neighbouring region blended in (the
    objects lie apart on screen, in saturated colours, on a light background); every pixel
    it leaves empty lies within one pixel of the scale-1 background. Border 0 puts regions
    edge to edge in the atlas. Every empty atlas texel (between regions, borders, inside
    them) is painted the background colour before compositing: the atlas is depth-keyed,
    so no output may show them, and reading one greys a pixel."""
    scene = _grid_scene()
    cam = _front(scene, projection)
    images = {}
    for cs in (1.0, scale):
        r = make_renderer(scene, Settings(context_scale=cs, border=border))
        rec = r.capture(cam, VP, focus={0})
        _paint_empty(r.atlas, BACKGROUND)
        images[cs] = r.composite("sprites", Style(focus={0}, outline_width=0)).read()
        assert (rec.scale[1:][rec.visible[1:]] == cs).all()
    rgb1, depth1 = images[1.0][0][..., :3].astype(int), images[1.0][1]
    rgb, depth = images[scale][0][..., :3].astype(int), images[scale][1]
    on1, on = depth1 < 1.0, depth < 1.0
    assert on1.sum() > 3000 and on.sum() > 3000
    reach, texel = int(np.ceil(0.5 / scale)), int(np.ceil(1.0 / scale))  # 1 and 2 pixels at 0.5
    near_object = _neighbourhood(on1, np.any, False, reach)
    near_empty = _neighbourhood(~on1, np.any, True, reach)
    assert not (on & ~near_object).any(), "covered farther than one pixel from the silhouette"
    assert not (~on & ~near_empty).any(), "a hole farther than one pixel inside the silhouette"
    # background blended in greys a pixel (3% of it moves these saturated colours'
    # chromaticity by > 0.05), a neighbouring region changes its hue; shading within the
    # object changes the brightness much more (grazing faces are darker, same hue)
    chroma = rgb / np.maximum(rgb.sum(-1, keepdims=True), 1)
    chroma1 = rgb1 / np.maximum(rgb1.sum(-1, keepdims=True), 1)
    c_lo = _neighbourhood(np.where(on1[..., None], chroma1, 9.0), np.min, 9.0, texel)
    c_hi = _neighbourhood(np.where(on1[..., None], chroma1, -9.0), np.max, -9.0, texel)
    foreign = on & ((chroma < c_lo - 0.03) | (chroma > c_hi + 0.03)).any(-1)
    assert not foreign.any(), f"{int(foreign.sum())} pixels of another hue than the object around them"
    # the scaled image is not simply the scale-1 one (the test sees the upsampling)
    assert (np.abs(rgb - rgb1).max(-1) > 2).sum() > 50


def test_shading_by_role(make_renderer, demo_scene):
    """AO and edges on focus objects only: with nothing in focus, ghosted-ao is ghosted; AO on
    focus only changes only pixels where the context is drawn."""
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, 30, 20, 2.2)
    r = make_renderer(demo_scene)
    r.capture(cam, VP)
    plain = r.composite("ghosted", Style()).read()[0].copy()
    bare = r.composite("ghosted-ao", Style(ao_objects="focus", edge_objects="focus")).read()[0]
    assert np.array_equal(plain, bare)
    shaded = r.composite("ghosted-ao", Style()).read()[0]
    assert (np.abs(shaded.astype(int) - plain).max(-1) > 8).sum() > 200
    with pytest.raises(ValueError, match="ao_objects"):
        r.composite("ghosted-ao", Style(ao_objects="some"))


def test_focus_change_shades_only_what_changed(make_renderer, demo_scene):
    """Post-processing is cached per object: after focus changes the image equals a fresh
    renderer's, and only objects whose role asks for more are shaded again."""
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, 30, 20, 2.2)
    r, fresh = make_renderer(demo_scene), make_renderer(demo_scene)
    r.capture(cam, VP)
    calls = []
    post = r.post_process(Style(ao_objects="focus", focus={1}))
    real = post._upload  # the ids of every draw but those of every object (a list kept on the GPU)
    post._upload = lambda ids: (calls.append(sorted(ids.tolist())), real(ids))[1]
    for focus in ({1, 5}, {5}, {1, 5, 7}):
        style = Style(focus=focus, ao_objects="focus")
        got = r.composite("ghosted-ao", style).read()[0].copy()
        fresh.capture(cam, VP)
        want = fresh.composite("ghosted-ao", style).read()[0]
        assert np.array_equal(got, want)
    visible = set(np.flatnonzero(r.last[0].visible).tolist())
    assert calls == [sorted({5} & visible), sorted({7} & visible)]


def test_context_scale_follows_the_focus(make_renderer, demo_scene):
    """A focus change with a context scale re-captures (the region scales follow the focus)."""
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, 30, 20, 2.2)
    r = make_renderer(demo_scene, Settings(context_scale=0.5))
    rec = r.capture(cam, VP, focus={2})
    assert rec.scale[2] == 1.0 and rec.scale[3] == 0.5
    r.composite("ghosted", Style(focus={3}))
    rec = r.last[0]
    assert rec.scale[3] == 1.0 and rec.scale[2] == 0.5


def test_cli_importance_flags(tmp_path, capsys):
    """--context-scale, --ao-objects, --edge-objects and --order reach the snapshot; a context
    scale out of range is one error line and exit 2."""
    from rtta.cli.main import main

    out = tmp_path / "g.png"
    assert (
        main(
            [
                "snapshot",
                "--mode",
                "ghosted-ao",
                "--size",
                "160x120",
                "--focus",
                "piston_1",
                "--context-scale",
                "0.5",
                "--ao-objects",
                "focus",
                "--edge-objects",
                "all",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    assert out.is_file()
    assert (
        main(
            [
                "snapshot",
                "--mode",
                "transparent",
                "--size",
                "160x120",
                "--order",
                "pixel",
                "--out",
                str(tmp_path / "t.png"),
            ]
        )
        == 0
    )
    capsys.readouterr()
    assert main(["snapshot", "--context-scale", "0.1", "--out", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--context-scale" in err[0] and not (tmp_path / "x.png").exists()


def test_halo_where_context_lies_behind(make_renderer):
    """--halo W in numpy: a pixel outside the focus object's silhouette gets the halo exactly
    where a focus pixel lies within W (Euclidean) and the farthest context surface at the
    pixel lies behind that focus pixel's depth; over the background nothing changes."""
    from rtta.gl.readback import map_back

    plate = trimesh.creation.box(extents=(2.0, 1.2, 0.1))
    cube = trimesh.creation.box(extents=(0.5, 0.5, 0.5))
    parts = [
        ("plate", np.asarray(plate.vertices) + (0.6, 0, -1.0), np.asarray(plate.faces), None),
        ("cube", np.asarray(cube.vertices), np.asarray(cube.faces), None),
    ]
    scene = from_meshes(parts, [(0.7, 0.7, 0.7, 1), (0.2, 0.4, 0.8, 1)])
    r = make_renderer(scene)
    cam = Camera.orbit(scene.center, scene.radius, 0, 0, 2.2)
    rec = r.capture(cam, VP)
    width = 5
    plain = r.composite("ghosted", Style(focus={1}, outline_width=0)).read()[0][..., :3].astype(int)
    halo = r.composite("ghosted", Style(focus={1}, outline_width=0, halo=width)).read()[0][..., :3].astype(int)
    tw, th, td = rec.atlas_size
    atlas = r.atlas.read((tw, th), td)
    atlas = {"depth": atlas["depth"]}
    focus_d = map_back(atlas, rec, 1)["depth"]
    plate_d = map_back(atlas, rec, 0)["depth"]
    context_far = np.where(plate_d < 1, plate_d, 0.0)
    h, w = focus_d.shape
    best = np.full((h, w), np.inf)
    near = np.ones((h, w))
    for dy in range(-width, width + 1):
        for dx in range(-width, width + 1):
            r2 = dx * dx + dy * dy
            shifted = np.ones((h, w))
            ys, xs = slice(max(dy, 0), h + min(dy, 0)), slice(max(dx, 0), w + min(dx, 0))
            yd, xd = slice(max(-dy, 0), h + min(-dy, 0)), slice(max(-dx, 0), w + min(-dx, 0))
            shifted[yd, xd] = focus_d[ys, xs]
            take = (shifted < 1) & (r2 < best)
            best[take], near[take] = r2, shifted[take]
    expect = (focus_d >= 1) & (best <= width * width) & (context_far > near)
    strong = expect & (np.sqrt(best) <= 0.6 * width)
    changed = np.abs(halo - plain).max(-1) > 2
    assert strong.sum() > 200 and (focus_d < 1).sum() > 500
    assert not (changed & ~expect).any(), f"{int((changed & ~expect).sum())} halo pixels where none belongs"
    assert changed[strong].all(), f"{int((strong & ~changed).sum())} pixels lack the halo"
    background = (focus_d >= 1) & (plate_d >= 1) & (best <= width * width)
    assert background.sum() > 50 and not changed[background].any()
