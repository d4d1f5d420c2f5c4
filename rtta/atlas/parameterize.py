"""Algorithm 1 of the RTTA paper, vectorised over objects: view-frustum culling,
projection of B_world, clipping to NDC, viewport scaling, border, packing, transform T.

Bounds crossing the near plane are clipped against it in clip space before the
perspective divide (box corners in front plus edge/plane intersections), so objects
that cross the near plane or surround the camera get a conservative, finite B_viewport.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import numpy.typing as npt

from .corners import CornerClip, axis_aligned, clipped_bounds, points_clip
from .packing import Packing, pack_shelves
from .records import Records
from .scratch import result_block, scratch
from .thinning import KeepShare as KeepShare  # fast navigation's Thinning, which the GPU path reads too

# (visible [n] bool, inner B_viewport [n, 4]) -> bool [n] of the objects to leave out, or None
Thinning = Callable[[np.ndarray, np.ndarray], "np.ndarray | None"]

EPS_PX = 1e-3  # slack against CPU/GPU rounding when snapping bounds to pixels
CHUNK = 16_384  # boxes per pass of project_bounds: its rows (128 KB) stay in the CPU's cache and
# below the fixed mmap threshold of rtta.memory.steady_heap (no page faults)


def project_bounds(corners: np.ndarray, vpm: np.ndarray, reuse: bool = False):
    """Projected, near-clipped NDC bounds of boxes: (visible [n], ndc_min [n,2], ndc_max [n,2]).
    One corner at a time over up to CHUNK boxes, into planar [3, n] bounds (numpy runs fastest
    on long contiguous rows; chunks keep them in cache). reuse: the bounds are scratch arrays,
    valid until the next call that reuses (parameterize consumes them at once)."""
    n = corners.shape[0]
    m = np.asarray(vpm, np.float64)
    planar = corners.transpose(2, 1, 0)

    def new(name: str, shape: tuple[int, ...] | int, dtype: npt.DTypeLike = np.float64) -> np.ndarray:
        return scratch(name, shape, dtype) if reuse else np.empty(shape, dtype)

    lo = new("bounds.lo", (3, n))
    hi = new("bounds.hi", (3, n))
    all_front = new("bounds.all_front", n, bool)
    some_front = new("bounds.some_front", n, bool)
    clip = CornerClip(m, min(n, CHUNK), axis_aligned(planar))
    for s in range(0, n, CHUNK):
        e = min(n, s + CHUNK)
        _project_chunk(clip, planar[:, :, s:e], lo[:, s:e], hi[:, s:e], all_front[s:e], some_front[s:e])
    if not all_front.all():
        lo[:, ~all_front] = 0
        hi[:, ~all_front] = 0
        rows = np.flatnonzero(some_front & ~all_front)  # crossing the near plane: clipped
        if rows.size:
            pts = points_clip(np.asarray(corners[rows], np.float64), m)
            a, b = clipped_bounds(pts, pts[..., 2] + pts[..., 3])
            lo[:, rows], hi[:, rows] = a.T, b.T
    in_frustum = some_front & (lo[0] <= 1) & (hi[0] >= -1) & (lo[1] <= 1) & (hi[1] >= -1) & (lo[2] <= 1)
    return in_frustum, lo[:2].T, hi[:2].T


def _project_chunk(clip: CornerClip, planar, lo, hi, all_front, some_front) -> None:
    """project_bounds on one chunk (planar [3, 8, c]) into the chunk's views of its outputs."""
    c = planar.shape[2]
    lo[:] = np.inf
    hi[:] = -np.inf
    all_front[:] = True
    some_front[:] = False
    q, front = clip.q[:c], clip.front[:c]
    rows = clip.start(planar)
    with np.errstate(divide="ignore", invalid="ignore"):
        for k in range(8):
            x, y, z, w = rows(k)
            np.greater_equal(np.add(z, w, out=q), 0, out=front)  # in front of the near plane
            all_front &= front
            some_front |= front
            for j, v in enumerate((x, y, z)):
                np.divide(v, w, out=q)
                np.minimum(lo[j], q, out=lo[j])
                np.maximum(hi[j], q, out=hi[j])


def _intersected(boxes: np.ndarray, vpm: np.ndarray):
    """Several enclosing boxes per object [k, n, 8, 3]: the intersection of their projections."""
    vis, lo, hi = project_bounds(boxes[0], vpm)
    for corners in boxes[1:]:
        v, a, b = project_bounds(corners, vpm)
        vis, lo, hi = vis & v, np.maximum(lo, a), np.minimum(hi, b)
    return vis & (lo <= hi).all(axis=1), lo, hi


def viewport_rects(
    vis: np.ndarray, lo: np.ndarray, hi: np.ndarray, size: tuple[int, int], out: np.ndarray | None = None
):
    """Clip NDC bounds to the viewport and snap outward to whole pixels: [n,4] x0,y0,x1,y1
    (a transposed view of planar [4, n] rows, as numpy is fastest on long contiguous rows;
    `out`: int64 [4, n] to hold them)."""
    wh = np.asarray(size, np.float64)[:, None]
    px = scratch("rects.px", (4, len(vis)))  # [4, n], worked on in place
    px[:2], px[2:] = lo.T, hi.T
    np.minimum(np.maximum(px, -1, out=px), 1, out=px)
    px += 1
    px *= np.tile(0.5 * wh, (2, 1))  # == (c + 1) * 0.5 * wh: halving is exact
    x0y0, x1y1 = px[:2], px[2:]
    x0y0 -= EPS_PX
    np.floor(x0y0, out=x0y0)
    x1y1 += EPS_PX
    np.ceil(x1y1, out=x1y1)
    np.minimum(np.maximum(px, 0, out=px), np.tile(wh, (2, 1)), out=px)
    t = scratch("rects.t", x0y0.shape)
    np.maximum(x1y1, np.minimum(np.add(x0y0, 1, out=t), wh, out=t), out=x1y1)
    np.minimum(x0y0, np.subtract(x1y1, 1, out=t), out=x0y0)
    rect = np.empty(px.shape, np.int64) if out is None else out
    np.copyto(rect, px, casting="unsafe")  # whole numbers: exact
    vis = vis & (rect[2] > rect[0]) & (rect[3] > rect[1])
    rect *= vis
    return vis, rect.T


def parameterize(
    corners: np.ndarray,
    vpm: np.ndarray,
    viewport: tuple[int, int],
    *,
    border: int = 1,
    atlas_max: tuple[int, int] | None = None,
    max_layers: int = 2048,
    region_scale: float | np.ndarray = 1.0,
    hidden: np.ndarray | None = None,
    thin: Thinning | None = None,
) -> Records:
    """Algorithm 1: every object's atlas region for one view, vectorised over objects.

    Culls against the view frustum, projects B_world (clipped against the near plane in clip
    space), clips to the viewport, adds the border, packs the regions into layers (shelf
    packing) and computes each object's transform T. Regions are scaled down, the scale
    recorded, where the atlas would need more layers than allowed.

    Parameters
    ----------
    corners : numpy.ndarray
        B_world corners [n, 8, 3], or several enclosing boxes per object [k, n, 8, 3], whose
        projections are intersected.
    vpm : numpy.ndarray
        The 4x4 view-projection matrix (world to clip).
    viewport : tuple of int
        (W, H) in pixels.
    border : int, default 1
        Empty texels around each region.
    atlas_max : tuple of int, optional
        The largest layer (W, H); default `default_atlas_max`.
    max_layers : int, default 2048
        The most layers.
    region_scale : float or numpy.ndarray, default 1
        Atlas texels per viewport pixel wanted for every region (below 1 saves atlas memory
        and fill, above 1 supersamples), or one per object [n] (focus objects at 1, context
        ones lower); lowered per object only where it must be.
    hidden : numpy.ndarray, optional
        bool [n]: objects the user hid, culled like those outside the view (no region).
    thin : callable, optional
        Chooses more objects to leave out from this frame's projection (fast navigation):
        called with (visible [n] bool, inner B_viewport [n, 4] pixels) after culling, it
        returns bool [n] or None; those are culled too.

    Returns
    -------
    Records
        The record set R, arrays indexed by object id.

    Examples
    --------
    >>> import rtta
    >>> from rtta.scene.generators.demo import demo_path
    >>> scene = rtta.load_scene(str(demo_path()))
    >>> camera = rtta.Camera.orbit(scene.center, scene.radius, 35, 25, 2.2)
    >>> vpm = camera.projection(640 / 480) @ camera.view(scene.origin)
    >>> records = rtta.parameterize(scene.box_corners(), vpm, (640, 480))
    >>> int(records.visible.sum()) <= scene.count
    True
    """
    n = corners.shape[-3]
    W, H = int(viewport[0]), int(viewport[1])
    if W < 1 or H < 1:
        raise ValueError(f"viewport must be at least 1x1, got {W}x{H}")
    region_scale = _checked_scale(region_scale, n)
    max_w, max_h = atlas_max or default_atlas_max((W, H), border, float(region_scale.max(initial=1e-3)))
    if max_w < 1 + 2 * border or max_h < 1 + 2 * border:
        raise ValueError(f"atlas maximum {max_w}x{max_h} cannot hold a 1-pixel region with border {border}")
    vis, lo, hi = project_bounds(corners, vpm, reuse=True) if corners.ndim == 3 else _intersected(corners, vpm)
    if hidden is not None:
        vis = vis & ~np.asarray(hidden, bool)
    keep = _result_arrays(n)  # the records' arrays: no fresh pages
    vis, rect = viewport_rects(vis, lo, hi, (W, H), keep["rect"])
    if thin is not None and (more := thin(vis, rect)) is not None:
        more = np.asarray(more, bool) & vis
        vis = vis & ~more
        rect[more] = 0
    idx = np.flatnonzero(vis)
    every = len(idx) == n  # all visible: views, no gathers
    rt = rect.T  # planar [4, n]
    inner = np.subtract(rt[2:], rt[:2], out=scratch("param.inner", (2, n)))  # [2, n]; row-wise 1-D gathers below
    inner_v = inner if every else scratch("param.inner_v", (2, len(idx)))
    for row in range(0 if every else 2):
        np.take(inner[row], idx, out=inner_v[row])
    fit = np.divide(max_w - 2 * border, inner_v[0], out=scratch("param.fit", len(idx)))
    np.minimum(fit, np.divide(max_h - 2 * border, inner_v[1], out=scratch("param.fit_h", len(idx))), out=fit)
    atlas_rect, layer, scale = keep["atlas"], keep["layer"], keep["scale"]
    out = (
        (atlas_rect[0], atlas_rect[1], layer)
        if every  # packed straight into the records
        else tuple(scratch(f"param.packed_{k}", len(idx), np.int64) for k in "xyl")
    )
    wanted = region_scale if every or region_scale.ndim == 0 else region_scale[idx]
    first = np.minimum(wanted, fit, out=scale if every else scratch("param.first", len(idx)))
    packing, scale_v, sizes = _pack_with_scaling(inner_v, first, border, max_w, max_h, max_layers, out)
    if every:
        atlas_rect[2:] = sizes
        if scale_v is not scale:  # scaled down to fit the layers
            scale[:] = scale_v
    else:
        for a in (atlas_rect, layer, scale):  # culled objects: no region, scale 0
            a[...] = 0
        scale[idx] = scale_v
        layer[idx] = packing.layer
        for row, values in enumerate((packing.x, packing.y, sizes[0], sizes[1])):
            atlas_rect[row][idx] = values
    tw, th = max(packing.width, 1), max(packing.height, 1)
    transform = _transforms(rt[:2], atlas_rect[:2], scale, border, (W, H), (tw, th), keep["transform"])
    clip_ndc = np.divide(rt, np.array([[W], [H], [W], [H]], np.float64), out=keep["clip"])
    clip_ndc *= 2.0
    clip_ndc -= 1.0
    if not every:  # culled: zero T and clip rectangle
        transform *= vis
        clip_ndc *= vis
    atlas_rect, transform, clip_ndc = atlas_rect.T, transform.T, clip_ndc.T  # [n, 4] views
    return Records(
        visible=vis,
        viewport_rect=rect,
        atlas_rect=atlas_rect,
        layer=layer,
        scale=scale,
        transform=transform,
        clip_ndc=clip_ndc,
        viewport=(W, H),
        atlas_size=(packing.width, packing.height, packing.layers),
        border=border,
    )


_RESULT_ROWS = (
    ("rect", 4, np.int64),
    ("atlas", 4, np.int64),
    ("layer", 1, np.int64),
    ("scale", 1, np.float64),
    ("transform", 4, np.float64),
    ("clip", 4, np.float64),
)


def _result_arrays(n: int) -> dict[str, np.ndarray]:
    """Uninitialised arrays for the records, rows of one result block ([rows, n], or [n])."""
    block = result_block("records", 8 * n * sum(rows for _, rows, _ in _RESULT_ROWS))
    out, at = {}, 0
    for name, rows, dtype in _RESULT_ROWS:
        a = block[at : at + 8 * n * rows].view(dtype)
        out[name] = a.reshape(rows, n) if rows > 1 else a
        at += 8 * n * rows
    return out


def _checked_scale(region_scale, n: int) -> np.ndarray:
    """The region scale, one for all (a 0-d array: no per-object array to fill and check
    every frame) or one per object, each in (0, 16]."""
    scale = np.asarray(region_scale, np.float64)
    if scale.ndim != 0 and scale.shape != (n,):
        raise ValueError(f"region scale must be a float or one per object ({n}), got shape {scale.shape}")
    if not (np.isfinite(scale).all() and (scale > 0).all() and (scale <= 16).all()):
        bad = scale[~(np.isfinite(scale) & (scale > 0) & (scale <= 16))][0]
        raise ValueError(f"region scale must be in (0, 16], got {bad}")
    return scale


def default_atlas_max(viewport: tuple[int, int], border: int, region_scale: float = 1.0) -> tuple[int, int]:
    """A layer that holds the whole viewport at the region scale, borders included."""
    return (
        int(np.ceil(viewport[0] * region_scale)) + 2 * border,
        int(np.ceil(viewport[1] * region_scale)) + 2 * border,
    )


def _region_sizes(inner: np.ndarray, scale: np.ndarray, border: int) -> np.ndarray:
    """Atlas region sizes [2, m] (w, h rows, border included) of inner sizes [2, m] at `scale` [m]
    (a scratch array)."""
    t = np.multiply(inner, scale, out=scratch("param.sizes_f", inner.shape))
    t -= 1e-9
    np.ceil(t, out=t)
    np.maximum(t, 1, out=t)
    t += 2 * border
    sizes = scratch("param.sizes", inner.shape, np.int64)
    sizes[...] = t
    return sizes


def _pack_with_scaling(
    inner, scale, border, max_w, max_h, max_layers, out=None
) -> tuple[Packing, np.ndarray, np.ndarray]:
    """Pack the visible regions (inner sizes [2, m] at `scale` [m]); while more layers than
    allowed are needed, scale all regions down (none dropped). Returns (packing, scale, sizes);
    `out`: pack_shelves' x, y, layer arrays."""
    capacity = float(max_w) * max_h * max_layers
    for _ in range(64):
        sizes = _region_sizes(inner, scale, border)
        packing = pack_shelves(sizes[0], sizes[1], max_w, max_h, out)
        if packing.layers <= max_layers:
            return packing, scale, sizes
        if (sizes == 1 + 2 * border).all():
            break
        area = float((sizes[0] * sizes[1]).sum())
        shrink = min(0.9, np.sqrt(capacity / area) * 0.95)
        scale = scale * shrink
    raise ValueError(
        f"{inner.shape[1]} regions with border {border} do not fit into {max_layers} "
        f"layer(s) of {max_w}x{max_h} even at the smallest scale"
    )


def _transforms(x0y0, atlas_xy, scale, border, viewport, atlas, out: np.ndarray) -> np.ndarray:
    """T per object as rows [4, m] into `out`: atlas_px = atlas_xy + border + scale * (viewport_px - x0y0),
    in NDC (x0y0, atlas_xy: [2, m] rows). Worked out in place (one [2, m] temporary)."""
    vp = np.asarray(viewport, np.float64)[:, None]
    at = np.asarray(atlas, np.float64)[:, None]
    sxy, txy = out[:2], out[2:]
    np.multiply(scale, vp, out=sxy)
    sxy /= at  # scale * vp / at
    np.multiply(x0y0, 2.0, out=txy)
    np.subtract(vp, txy, out=txy)
    txy *= scale  # scale * (vp - 2 x0y0)
    origin = np.add(atlas_xy, border, out=scratch("param.origin", txy.shape))
    origin *= 2.0
    txy += origin  # + 2 (atlas_xy + border)
    txy /= at
    txy -= 1.0
    return out
