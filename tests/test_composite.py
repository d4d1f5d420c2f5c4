"""Compositing from the atlas, checked against renders made in the same test and numpy."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from checks import assert_depth_close

from rtta.passes.composite import BACKGROUND, MODES, Style
from rtta.renderer.settings import Settings
from rtta.renderer.snapshot import over_background
from rtta.scene.camera import DEFAULT_ORBIT, Camera
from rtta.scene.generators.generate import random_scene
from rtta.scene.model import from_meshes

VP = (240, 180)


def _std(r, cam):
    std = r.std(cam, VP).read(VP, 1)
    return over_background(std["color"][0]), std["depth"][0], std["id"][0]


def _assert_matches_std(rgba, depth, std_rgba, std_depth, std_id):
    close = np.abs(rgba[..., :3].astype(int) - std_rgba[..., :3].astype(int)).max(-1) <= 3
    assert close.mean() >= 0.995, f"only {close.mean():.4f} of pixels within 3/255"
    cov = std_id >= 0
    if depth is not None:  # the core's tolerance: 1e-5 plus the depth slope over sub-pixel snapping
        assert_depth_close(depth, std_depth, cov, std_id, "sprites against STD")
        assert (depth[~cov] == 1.0).all()


@pytest.mark.parametrize("projection", ["perspective", "ortho"])
@pytest.mark.parametrize("orbit", [DEFAULT_ORBIT, (200, -30, 1.5), (80, 60, 3.0)])
def test_sprites_reconstruct_std_demo(make_renderer, demo_scene, orbit, projection):
    r = make_renderer(demo_scene)
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, *orbit, projection=projection)
    r.capture(cam, VP)
    rgba, depth = r.composite("sprites").read()
    _assert_matches_std(rgba, depth, *_std(r, cam))


@pytest.mark.parametrize("projection", ["perspective", "ortho"])
@pytest.mark.parametrize("n", [1, 40, 500])
def test_sprites_reconstruct_std_generated(make_renderer, n, projection):
    scene = random_scene(n, seed=n, spread=3.0 * np.cbrt(n) + 2)
    r = make_renderer(scene)
    cam = Camera.orbit(scene.center, scene.radius, 30, 20, 1.7, projection=projection)
    r.capture(cam, VP)
    rgba, depth = r.composite("sprites").read()
    _assert_matches_std(rgba, depth, *_std(r, cam))


def _separated_scene(n=12, seed=0):
    """Small boxes on a grid: no two intersect, so back-to-front order is well defined."""
    rng = np.random.default_rng(seed)
    parts = []
    for i in range(n):
        box = trimesh.creation.box(extents=rng.uniform(0.3, 0.8, 3))
        center = np.array([i % 4, (i // 4) % 3, i // 12], float) * 1.6 + rng.uniform(-0.2, 0.2, 3)
        parts.append((f"b{i}", np.asarray(box.vertices) + center, np.asarray(box.faces), None))
    scene = from_meshes(parts)
    lo, hi = scene.aabb_min, scene.aabb_max
    overlap = (lo[:, None] < hi[None]).all(-1) & (lo[None] < hi[:, None]).all(-1)
    assert overlap.sum() == n  # only each box with itself
    return scene


def test_transparent_with_opacity_one_equals_std(make_renderer):
    scene = _separated_scene()
    r = make_renderer(scene)
    cam = Camera.orbit(scene.center, scene.radius, 25, 15, 2.0)
    r.capture(cam, VP)
    rgba, _ = r.composite("transparent", Style(default_opacity=1.0)).read()
    _assert_matches_std(rgba, None, *_std(r, cam))


@pytest.mark.parametrize("alpha", [0.2, 0.65])
def test_one_object_alpha_blend_over_background(make_renderer, alpha):
    box = trimesh.creation.icosphere(subdivisions=2)
    scene = from_meshes([("ball", np.asarray(box.vertices), np.asarray(box.faces), None)])
    r = make_renderer(scene)
    cam = Camera.orbit(scene.center, scene.radius, 10, 10, 2.5)
    r.capture(cam, VP)
    rgba, _ = r.composite("transparent", Style(opacity={0: alpha})).read()
    std = r.std(cam, VP).read(VP, 1)
    cov = std["id"][0] >= 0
    src = std["color"][0][..., :3].astype(np.float64)
    expected = np.where(
        cov[..., None], alpha * src + (1 - alpha) * np.array(BACKGROUND[:3]) * 255, np.array(BACKGROUND[:3]) * 255
    )
    assert np.abs(rgba[..., :3] - expected).max() <= 3.0


def _hidden_pair():
    """A small box entirely behind a large one, seen from +Z."""
    big = trimesh.creation.box(extents=(4, 4, 0.5))
    small = trimesh.creation.box(extents=(1, 1, 1))
    return from_meshes(
        [
            ("wall", np.asarray(big.vertices), np.asarray(big.faces), None),
            ("hidden", np.asarray(small.vertices) + [0, 0, -3], np.asarray(small.faces), None),
        ]
    )


@pytest.mark.parametrize("mode", ["ghosted", "ghosted-ao"])
def test_ghosted_shows_a_hidden_focus_object(make_renderer, mode):
    scene = _hidden_pair()
    r = make_renderer(scene)
    cam = Camera.orbit(scene.center, scene.radius, 0, 0, 2.5)
    assert not (r.std(cam, VP).read(VP, 1)["id"][0] == 1).any()  # hidden in STD
    records = r.capture(cam, VP)
    plain, _ = r.composite(mode, Style()).read()
    plain = plain.copy()
    style = Style(focus={1})
    focused, _ = r.composite(mode, style).read()
    x0, y0, x1, y1 = records.viewport_rect[1]
    region = (slice(y0, y1), slice(x0, x1))
    changed = np.abs(focused[region].astype(int) - plain[region].astype(int)).max(-1) > 10
    assert changed.mean() > 0.5
    outline = np.abs(focused[..., :3].astype(int) - np.array(style.outline_color[:3]) * 255).max(-1) <= 3
    assert outline[region].sum() >= 2 * ((x1 - x0) + (y1 - y0)) * 0.8  # its silhouette is drawn
    assert not outline[~_in_rect(focused.shape, records.viewport_rect[1])].any()


def _in_rect(shape, rect):
    m = np.zeros(shape[:2], bool)
    x0, y0, x1, y1 = rect
    m[y0:y1, x0:x1] = True
    return m


def test_style_changes_recomposite_only(make_renderer, demo_scene):
    r = make_renderer(demo_scene)
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, *DEFAULT_ORBIT)
    r.capture(cam, VP)
    frames = r.capture_pass().frames
    a = r.composite("ghosted", Style(focus={0})).read()[0].copy()
    b = r.composite("ghosted", Style(focus={0, 5}, context_opacity=0.6)).read()[0].copy()
    assert r.capture_pass().frames == frames and not np.array_equal(a, b)


def draws(passes: list[str]) -> list[str]:
    """The draws of a frame by what they do: a GPU-listed draw is issued once per scale class
    (upsample variants, the count on the GPU: rtta.passes.composite_gpu), drawn as one."""
    kinds = ["+".join(t for t in p.split("+") if t not in GPU_VARIANTS) for p in passes]
    return [k for i, k in enumerate(kinds) if i == 0 or k != kinds[i - 1]]


GPU_VARIANTS = {"hull_per_sprite", "upsample", "upsample_dynamic"}


@pytest.mark.parametrize("where", ["cpu", "gpu", "gpu+compute"])
def test_only_needed_passes_run(make_renderer, demo_scene, where):
    parameterize, _, blend = where.partition("+")
    r = make_renderer(demo_scene, Settings(parameterize=parameterize, blend=blend or "raster"))  # type: ignore[arg-type]
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, *DEFAULT_ORBIT)
    r.capture(cam, VP)
    context = "blend_tiles" if blend else "blend"  # the ghosted context in a compute pass (blend_tiles.py)
    expected = {
        "sprites": ["sprite"],
        "transparent": ["blend+collect", "resolve"],
        "ghosted": ["sprite+outline", context],
    }
    for mode, passes in expected.items():
        r.composite(mode, Style(focus={1}))
        highlight = ["outline"] if mode != "ghosted" else []  # sprites/transparent: highlight outlines
        assert draws(r._composite.passes) == passes + highlight and r._post is None
        if highlight:
            r.composite(mode, Style())
            assert draws(r._composite.passes) == passes
    r.composite("ghosted", Style(focus={1}, outline_width=0))  # no outline: no outline pass or variant
    assert draws(r._composite.passes) == ["sprite", context]
    r.composite("ghosted-ao", Style(focus={1}))
    shaded = "blend_tiles+ao" if blend else "blend+with_ao"
    assert draws(r._composite.passes) == ["sprite+outline+with_ao", shaded] and r._post is not None
    assert r._composite.gpu_driven == (parameterize == "gpu")


@pytest.mark.parametrize(
    "mode, order, halo",
    [("ghosted", "object", 0), ("ghosted", "pixel", 0), ("ghosted-ao", "object", 3), ("ghosted", "pixel", 3)],
)
def test_ghosted_outlines_stay_on_top(make_renderer, demo_scene, mode, order, halo):
    """The ghosted focus outlines are drawn in the focus sprites' pass at depth 0: the context
    (blended by object or collected per pixel) and halos composited after never cover them,
    so the outline pixels are exactly the focus objects' silhouette texels, as drawn last."""
    r = make_renderer(demo_scene)
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, *DEFAULT_ORBIT)
    rec = r.capture(cam, VP)
    covered = r.atlas.read(rec.atlas_size[:2], rec.atlas_size[2], ("depth",))["depth"] < 1.0
    focus = {1, 5, demo_scene.count // 2}
    style = Style(focus=focus, order=order, halo=halo)
    rgba, depth = r.composite(mode, style).read()
    assert r._composite.passes[0].startswith("sprite+outline") and "outline" not in r._composite.passes[1:]
    drawn = np.abs(rgba[..., :3].astype(int) - np.array(style.outline_color[:3]) * 255).max(-1) <= 3
    expected = np.zeros(drawn.shape, bool)
    for oid in focus:
        x0, y0, x1, y1 = rec.viewport_rect[oid].astype(int)
        sil = _silhouettes(rec, covered, oid, 1)
        expected[y0:y1, x0:x1] |= sil[1 : 1 + y1 - y0, 1 : 1 + x1 - x0]
    assert expected.sum() > 200
    assert np.array_equal(drawn, expected), f"{(drawn != expected).sum()} pixels differ"
    assert (depth[expected] == 0.0).all()


def test_borders_are_marked_empty(make_renderer, demo_scene):
    from rtta.renderer.renderer import Settings

    r = make_renderer(demo_scene, Settings(border=2))
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, *DEFAULT_ORBIT)
    rec = r.capture(cam, VP)
    atlas = r.atlas.read(rec.atlas_size[:2], rec.atlas_size[2])
    for oid in np.flatnonzero(rec.visible):
        x, y, w, h = rec.atlas_rect[oid]
        ids = atlas["id"][rec.layer[oid], y : y + h, x : x + w]
        alpha = atlas["color"][rec.layer[oid], y : y + h, x : x + w, 3]
        ring = np.ones(ids.shape, bool)
        ring[2:-2, 2:-2] = False
        assert (ids[ring] == -1).all() and (alpha[ring] == 0).all()


def test_stale_atlas_texels_never_show(make_renderer, demo_scene):
    """The atlas is depth-keyed: a frame clears only its depth, so the colour, normal and id
    of texels that are empty now still hold an earlier view. No output may show them: every
    mode, the post-process and the atlas read equal those of a renderer without that history."""
    c, radius = demo_scene.center, demo_scene.radius
    now, before = Camera.orbit(c, radius, 30, 20, 2.2), Camera.orbit(c, radius, 200, -30, 1.3)
    style = Style(focus={0, demo_scene.count // 2})
    r, fresh = make_renderer(demo_scene), make_renderer(demo_scene)
    r.capture(before, VP)
    for mode in MODES:
        r.composite(mode, style)
    allocations = r.atlas.allocations
    r.capture(now, VP)
    fresh.capture(now, VP)
    assert r.atlas.allocations == allocations  # the same textures, history and all
    w, h = r.atlas.size
    raw = np.frombuffer(r.atlas.color.read(), np.uint8).reshape(-1, h, w, 4)
    assert raw[r.atlas.depth.read() >= 1.0].any(), "no stale texel: the test would prove nothing"
    for mode in MODES:
        got, want = r.composite(mode, style).read(), fresh.composite(mode, style).read()
        assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1]), mode
    tw, th, td = r.last[0].atlas_size
    got, want = r.atlas.read((tw, th), td), fresh.atlas.read((tw, th), td)
    for part in got:
        assert np.array_equal(got[part], want[part]), part
    assert (got["id"][got["depth"] >= 1.0] == -1).all() and (got["color"][got["depth"] >= 1.0] == 0).all()


def _silhouettes(records, covered: np.ndarray, oid: int, width: int) -> np.ndarray:
    """The object's texels in its B_atlas with a texel within `width` (square window) that
    is outside B_atlas or empty, and in view: what the outline pass draws, in numpy (at scale 1).
    Texels beyond the viewport (where the view cuts the object) make no silhouette."""
    x, y, w, h = records.atlas_rect[oid]
    own = np.zeros((h + 2 * width, w + 2 * width), bool)  # outside B_atlas: not the object's
    own[width:-width, width:-width] = covered[records.layer[oid], y : y + h, x : x + w]
    # texel (border + i, border + j) of B_atlas shows pixel (x0 + i, y0 + j)
    (x0, y0), (vw, vh) = records.viewport_rect[oid, :2].astype(int) - records.border, records.viewport
    px, py = x0 + np.arange(-width, w + width), y0 + np.arange(-width, h + width)
    own |= ((px < 0) | (px >= vw))[None, :] | ((py < 0) | (py >= vh))[:, None]
    near_other = np.zeros((h, w), bool)
    for dy in range(-width, width + 1):
        for dx in range(-width, width + 1):
            near_other |= ~own[width + dy : width + dy + h, width + dx : width + dx + w]
    return own[width:-width, width:-width] & near_other


@pytest.mark.parametrize("mode", ["sprites", "ghosted"])
@pytest.mark.parametrize(
    "border, width, distance",
    [(0, 1, 2.2), (0, 1, 0.6), (0, 3, 0.6), (1, 3, 2.2), (1, 1, 2.2), (1, 1, 0.6), (2, 1, 0.6)],
)
def test_outlines_match_numpy_silhouettes(make_renderer, demo_scene, border, width, distance, mode):
    """Every object in focus: the outline pixels are exactly the silhouette texels of each
    object's own atlas region mapped back through T^-1. With border 0 the regions touch, so
    a silhouette next to B_atlas's edge is found only if texels beyond it count as empty
    (not the neighbouring object's); close up (distance 0.6) parts cross the viewport's edge,
    so their regions are full up to B_atlas's edge, and the cut there is no silhouette (no
    outline frames the image). A wide outline reaches past a 1-texel border.
    `sprites` draws outlines in a pass of their own, `ghosted` in the focus sprites' pass;
    width 1 with a border takes the quad-derivative silhouette (OUTLINE_QUAD) in both."""
    from rtta.renderer.renderer import Settings

    r = make_renderer(demo_scene, Settings(border=border))
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, 30, 20, distance)
    rec = r.capture(cam, VP)
    covered = r.atlas.read(rec.atlas_size[:2], rec.atlas_size[2], ("depth",))["depth"] < 1.0
    style = Style(focus=set(range(demo_scene.count)), outline_width=width)
    rgba, _ = r.composite(mode, style).read()
    drawn = np.abs(rgba[..., :3].astype(int) - np.array(style.outline_color[:3]) * 255).max(-1) <= 3
    expected = np.zeros(drawn.shape, bool)
    for oid in np.flatnonzero(rec.visible):
        assert rec.scale[oid] == 1.0
        x0, y0, x1, y1 = rec.viewport_rect[oid].astype(int)
        sil = _silhouettes(rec, covered, oid, width)
        # pixel (x0 + i, y0 + j) shows texel (border + i, border + j) of B_atlas at scale 1
        expected[y0:y1, x0:x1] |= sil[border : border + y1 - y0, border : border + x1 - x0]
    assert expected.sum() > 500
    assert np.array_equal(drawn, expected), f"{(drawn != expected).sum()} pixels differ"


def test_back_to_front_is_farthest_first_ties_by_id():
    """The sort takes a plain argsort and falls back to a lexsort only on equal depths: both
    give the order farthest first, equals by id, and only visible objects."""
    from types import SimpleNamespace

    from rtta.passes.composite import back_to_front
    from rtta.passes.outlines import HULL_MIN_AREA, worth_outlines

    rng = np.random.default_rng(5)
    n = 5000
    records = SimpleNamespace(visible=rng.random(n) > 0.2)
    for depth in (rng.random(n), np.round(rng.random(n), 2)):  # no ties; many ties
        ids = rng.permutation(n)[: n // 2]
        got = back_to_front(records, depth, ids)
        vis = np.sort(ids[records.visible[ids]])
        assert np.array_equal(got, vis[np.lexsort((vis, -depth[vis]))])
    lo = rng.integers(0, 400, (n, 2))
    records.viewport_rect = np.hstack([lo, lo + rng.integers(1, 90, (n, 2))])
    r = records.viewport_rect
    area = (r[:, 2] - r[:, 0]) * (r[:, 3] - r[:, 1])
    for ids in (np.arange(10), np.arange(n), rng.permutation(n)[:4000]):  # rows gathered; areas of all
        assert worth_outlines(records, ids) == (area[ids].mean() >= HULL_MIN_AREA)


def test_per_pixel_lists_are_released_when_unused(make_renderer, demo_scene):
    """The per-pixel lists of `transparent` (tens of MB at 1280x720) are not held for a mode
    no longer shown: released after SHRINK_AFTER_FRAMES renders without them, made again
    when needed, with the same picture."""
    from rtta.gl.targets import SHRINK_AFTER_FRAMES

    r = make_renderer(demo_scene)
    r.capture(Camera.orbit(demo_scene.center, demo_scene.radius, *DEFAULT_ORBIT), VP)
    first = r.composite("transparent", Style()).read()[0].copy()
    assert r._composite._pixel_order is not None
    for _ in range(SHRINK_AFTER_FRAMES):
        r.composite("ghosted", Style(focus={1}))
    assert r._composite._pixel_order is not None  # a mode switched back and forth keeps them
    r.composite("ghosted", Style(focus={1}))
    assert r._composite._pixel_order is None
    assert np.array_equal(r.composite("transparent", Style()).read()[0], first)


def test_sprite_draws_apply_their_masks_to_the_framebuffer_bound(make_renderer, demo_scene, monkeypatch):
    """SpritePass._state sets the depth and colour masks on `ctx.fbo` and binds it again only for
    a colour mask (moderngl applies one to a framebuffer of one attachment at its next `use()`).
    At every sprite draw of every mode, in object and pixel order (the surfaces listed, where the
    context is drawn with its colour masked), GL's own binding and masks are the draw's."""
    import ctypes

    from rtta.gl import glraw
    from rtta.passes import oit
    from rtta.passes.sprites import SpritePass

    GL_DRAW_FRAMEBUFFER_BINDING, GL_DEPTH_WRITEMASK, GL_COLOR_WRITEMASK = 0x8CA6, 0x0B72, 0x0C23
    seen, state = [], SpritePass._state

    def checked(self, draw):
        held = state(self, draw)
        gl, bound, depth, colour = glraw._lib(), ctypes.c_int(-1), ctypes.c_ubyte(9), (ctypes.c_ubyte * 4)()
        gl.glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, ctypes.byref(bound))
        gl.glGetBooleanv(GL_DEPTH_WRITEMASK, ctypes.byref(depth))
        gl.glGetBooleani_v(GL_COLOR_WRITEMASK, 0, colour)
        fbo, colours = self.ctx.fbo, tuple(map(bool, colour))
        mask = fbo.color_mask  # per attachment: a tuple of them, or the one's (none: depth only)
        mask = (mask[0] if isinstance(mask[0], tuple) else mask) if mask else colours
        seen.append(((bound.value, bool(depth.value), colours), (fbo.glo, fbo.depth_mask, tuple(mask))))
        return held

    monkeypatch.setattr(SpritePass, "_state", checked)
    monkeypatch.setattr(oit, "first_fetched", lambda ctx: False)  # the lists: the masked context draw
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, *DEFAULT_ORBIT)
    for path in ("cpu", "gpu"):
        r = make_renderer(demo_scene, Settings(parameterize=path))
        r.capture(cam, VP)
        for mode in MODES:
            for order in ("object", "pixel"):
                r.composite(mode, Style(focus={1, 5}, order=order))
    assert any(not want[2][0] for _, want in seen), "no draw masked its colour"
    assert all(got == want for got, want in seen), [s for s in seen if s[0] != s[1]]
