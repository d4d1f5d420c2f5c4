"""The `ghosted-ao` atlas post-process (ambient occlusion, edges) against the same quantities
computed in numpy from the atlas read back: every shader variant (edge width 1 through the
quad derivatives, wider edges) and border (down to none, narrower than the edge width) must
give the same answer."""

from __future__ import annotations

import numpy as np
import pytest

from rtta.passes.composite import Style
from rtta.renderer.renderer import Settings
from rtta.scene.camera import DEFAULT_ORBIT, Camera

VP = (240, 180)
SPIRAL = np.array(
    [
        (0.0548, 0.0300),
        (-0.1821, 0.0449),
        (0.1732, -0.2601),
        (0.0672, 0.4323),
        (-0.4391, -0.3515),
        (0.6860, -0.0457),
        (-0.5613, 0.5875),
        (0.0196, -0.9373),
    ],
    np.float32,
)


def _smoothstep(e0: float, e1: float, x: np.ndarray) -> np.ndarray:
    t = np.clip((x - e0) / (e1 - e0), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def _normalize(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-30)


class AtlasFrame:
    """The atlas of one capture in numpy, with each texel's object rectangle."""

    def __init__(self, r, records, proj):
        tw, th, td = records.atlas_size
        a = r.atlas.read((tw, th), td, ("normal", "id", "depth"))
        self.ids, self.depth = a["id"], a["depth"].astype(np.float32)
        p22, p23 = np.float32(proj[2, 2]), np.float32(proj[2, 3])
        distance = p23 / (self.depth * np.float32(2) - np.float32(1) + p22)  # as post.frag's view_distance
        self.normal = np.concatenate([a["normal"], distance[..., None]], -1)  # (normal, view distance)
        self.rec, self.proj = records, proj
        self.shape = self.ids.shape  # (layers, th, tw)
        self.covered = np.argwhere(self.ids >= 0)  # (layer, y, x)
        rect = records.atlas_rect[self.ids[tuple(self.covered.T)]]
        self.lo = rect[:, [1, 0]]  # (y, x) per covered texel
        self.hi = self.lo + rect[:, [3, 2]] - 1

    def inside(self, yx: np.ndarray) -> np.ndarray:
        return ((yx >= self.lo) & (yx <= self.hi)).all(-1)

    def fetch(self, image: np.ndarray, yx: np.ndarray) -> np.ndarray:
        y = np.clip(yx[:, 0], 0, self.shape[1] - 1)
        x = np.clip(yx[:, 1], 0, self.shape[2] - 1)
        return image[self.covered[:, 0], y, x]

    def ndc(self, ids: np.ndarray, yx: np.ndarray) -> np.ndarray:
        """Viewport NDC (x, y) of texel yx's centre, in the region of object `ids` (post.geom's g_map)."""
        rec, vp = self.rec, np.asarray(self.rec.viewport, np.float32)
        scale = rec.scale[ids].astype(np.float32)[:, None]
        origin = (rec.viewport_rect[ids, :2] - (rec.atlas_rect[ids, :2] + rec.border) / scale) / vp * 2 - 1
        return origin + (yx[:, ::-1] + 0.5) * (2.0 / (scale * vp))

    def beyond(self, yx: np.ndarray) -> np.ndarray:
        """Whether texel yx (of each covered texel's object) lies beyond the viewport."""
        return (np.abs(self.ndc(self.ids[tuple(self.covered.T)], yx)) > 1.0).any(-1)

    def edges(self, width: int) -> np.ndarray:
        """Per covered texel: max over the 4 neighbours at `width` of silhouette (outside the
        rectangle or empty), relative depth jump and crease; none towards a neighbour beyond
        the viewport (an object cut by the view's edge)."""
        p = self.fetch(self.normal, self.covered[:, 1:])
        n_p, d_p = _normalize(p[:, :3]), p[:, 3]
        out = np.zeros(len(p), np.float32)
        for o in ((0, width), (0, -width), (width, 0), (-width, 0)):
            yx = self.covered[:, 1:] + o
            q = self.fetch(self.normal, yx)
            jump = np.abs(q[:, 3] - d_p) / d_p
            bend = 1.0 - (n_p * _normalize(q[:, :3])).sum(-1)
            e = np.maximum(_smoothstep(0.01, 0.03, jump), _smoothstep(0.2, 0.5, bend))
            e = np.where(self.inside(yx) & (self.fetch(self.depth, yx) < 1.0), e, 1.0)
            out = np.maximum(out, np.where(self.beyond(yx), 0.0, e))
        return out

    def view_position(self, ids: np.ndarray, yx: np.ndarray, d: np.ndarray) -> np.ndarray:
        P, ndc = self.proj, self.ndc(ids, yx)
        z = -P[2, 3] / (d * 2.0 - 1.0 + P[2, 2])
        return np.stack([-z * ndc[:, 0] / P[0, 0], -z * ndc[:, 1] / P[1, 1], z], -1)

    def ambient_occlusion(self, radius: float, strength: float) -> np.ndarray:
        """Per covered texel: AO from the 8 spiral samples of its 2x2 quad (even-aligned):
        quad texel (i, j) takes samples 2k and 2k + 1 (k = i + 2j) around itself, if it is
        covered and in the object's rectangle; samples count within the rectangle only."""
        ids = self.ids[tuple(self.covered.T)]
        occ = np.zeros(len(ids), np.float32)
        used = np.zeros(len(ids), np.float32)
        R = radius * self.rec.scale[ids].astype(np.float32)
        for j in (0, 1):
            for i in (0, 1):
                lane = self.covered[:, 1:] // 2 * 2 + (j, i)  # (y, x)
                d_lane = self.fetch(self.depth, lane)
                live = self.inside(lane) & (d_lane < 1.0)
                p = self.view_position(ids, lane, d_lane)
                n = _normalize(self.fetch(self.normal, lane)[:, :3])
                k = i + 2 * j
                for o in SPIRAL[2 * k : 2 * k + 2]:
                    s = lane + np.rint(R[:, None] * o[::-1]).astype(int)
                    d = self.fetch(self.depth, s)
                    ok = live & self.inside(s) & (d < 1.0)
                    v = self.view_position(ids, s, d) - p
                    dist = np.linalg.norm(v, axis=-1) + 1e-12
                    with np.errstate(invalid="ignore"):
                        o_occ = np.maximum(0, (v * n).sum(-1) - 0.002 * np.abs(p[:, 2])) / dist
                    occ += np.where(ok, o_occ, 0)
                    used += ok
        return np.where(used > 0, np.clip(1 - strength * occ / np.maximum(used, 1), 0, 1), 1.0)


SENTINEL = 77


CLOSE = (35.0, 25.0, 0.8)  # inside the bounding sphere: objects cut by the viewport's edges


@pytest.mark.parametrize("orbit", [DEFAULT_ORBIT, CLOSE])
@pytest.mark.parametrize("edge_width, border", [(1, 1), (1, 0), (2, 1), (2, 2), (3, 1)])
def test_post_process_matches_numpy(make_renderer, demo_scene, edge_width, border, orbit):
    r = make_renderer(demo_scene, Settings(border=border))
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, *orbit)
    records = r.capture(cam, VP)
    style = Style(edge_width=edge_width, ao_radius=12.0, ao_strength=1.5, ao_objects="all")
    post = r.post_process(style)
    post.texture.write(np.full(post.texture.size[:2] + (post.texture.layers, 4), SENTINEL, np.uint8))
    r._post._shaded_for = None  # run again over the sentinel
    post = r.post_process(style)
    frame = AtlasFrame(r, records, r.last[2])
    tw, th, td = records.atlas_size
    w, h = r.atlas.size
    got = np.frombuffer(post.texture.read(), np.uint8).reshape(-1, h, w, 4)[:td, :th, :tw] / 255.0
    at = tuple(frame.covered.T)
    edge_err = np.abs(got[..., 1][at] - frame.edges(edge_width))
    ao_err = np.abs(got[..., 0][at] - frame.ambient_occlusion(style.ao_radius, style.ao_strength))
    assert len(frame.covered) > 5000
    # the same float arithmetic: beyond the RGBA8 rounding only a handful of texels may differ
    # (float contraction on another CPU); a wrong neighbour or sample shows in tens of texels
    assert (edge_err > 2 / 255).sum() <= 3, f"edges: {(edge_err > 2 / 255).sum()} texels differ"
    assert (ao_err > 3 / 255).sum() <= 10, f"AO: {(ao_err > 3 / 255).sum()} texels differ"
    # empty texels of a visible object's rectangle are neither shaded nor written (the depth
    # test against the atlas culls them; compositing reads only the objects' own texels)
    in_rect = np.zeros(frame.shape, bool)
    for oid in np.flatnonzero(records.visible):
        x, y, rw, rh = records.atlas_rect[oid]
        in_rect[records.layer[oid], y : y + rh, x : x + rw] = True
    empty = in_rect & (frame.ids < 0)
    assert empty.sum() > 1000
    assert (got[empty] == SENTINEL / 255.0).all()
    assert not (got[at] == SENTINEL / 255.0).all(-1).any()  # every covered texel was written
    assert 0.02 < (frame.edges(edge_width) > 0.5).mean() < 0.6  # edges exist, not everywhere
    if orbit == CLOSE:  # where the view cuts an object, its texels next to the cut are no silhouette
        cut = np.zeros(len(frame.covered), bool)
        for o in ((0, edge_width), (0, -edge_width), (edge_width, 0), (-edge_width, 0)):
            cut |= frame.beyond(frame.covered[:, 1:] + o)
        assert cut.sum() > 200
        assert (got[..., 1][at][cut] > 0.5).mean() < 0.5, "the viewport's edge drawn as a silhouette"
    assert (frame.ambient_occlusion(style.ao_radius, style.ao_strength) < 0.9).mean() > 0.01
