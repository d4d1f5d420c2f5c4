"""The record set R of one frame (RTTA paper, section 3.1): per object its transform T, clip
rectangle, B_atlas, B_viewport, layer and region scale, as planar arrays and as the GPU's
std430 record buffer (shaders/records.glsl)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .scratch import scratch

RECORD_DTYPE = np.dtype(
    [("transform", "<f4", 4), ("clip", "<f4", 4), ("atlas", "<f4", 4), ("viewport", "<f4", 4), ("info", "<i4", 4)]
)


@dataclass
class Records:
    """The record set R of one frame, Algorithm 1's output: planar arrays indexed by object id.

    A viewport pixel (px, py) of object i lies at atlas texel
    (x + border + scale * (px - x0), y + border + scale * (py - y0)) in its layer, where
    (x, y) = atlas_rect[i, :2] and (x0, y0) = viewport_rect[i, :2].

    Attributes
    ----------
    visible : numpy.ndarray
        bool [n]: packed this frame (not culled, hidden or left out).
    viewport_rect : numpy.ndarray
        int64 [n, 4]: the inner B_viewport x0, y0, x1, y1 in pixels, clipped to the viewport.
    atlas_rect : numpy.ndarray
        int64 [n, 4]: B_atlas x, y, w, h in texels, border included.
    layer : numpy.ndarray
        int64 [n]: the atlas layer of each region.
    scale : numpy.ndarray
        float64 [n]: atlas texels per viewport pixel.
    transform : numpy.ndarray
        float64 [n, 4]: T as (sx, sy, tx, ty) in NDC, viewport to atlas.
    clip_ndc : numpy.ndarray
        float64 [n, 4]: the inner B_viewport in the viewport's NDC.
    viewport : tuple of int
        (W, H) in pixels.
    atlas_size : tuple of int
        (T_w, T_h, T_d): the atlas's used width, height and layers.
    border : int
        Empty texels around each region.
    """

    visible: np.ndarray  # bool [n]
    viewport_rect: np.ndarray  # int64 [n,4] inner B_viewport x0,y0,x1,y1 (pixels, clipped)
    atlas_rect: np.ndarray  # int64 [n,4] B_atlas x,y,w,h (texels, border included)
    layer: np.ndarray  # int64 [n]
    scale: np.ndarray  # float64 [n] atlas texels per viewport pixel
    transform: np.ndarray  # float64 [n,4] T as (sx, sy, tx, ty) in NDC
    clip_ndc: np.ndarray  # float64 [n,4] inner B_viewport in viewport NDC
    viewport: tuple[int, int]
    atlas_size: tuple[int, int, int]  # (T_w, T_h, T_d)
    border: int

    def packed(self, reuse: bool = False) -> np.ndarray:
        """The GPU record buffer contents (std430 layout of shaders/records.glsl), [n] of RECORD_DTYPE,
        from planar rows in one transposing copy; reuse: a scratch array, valid until the next reuse."""
        n = len(self.visible)
        rows = scratch("records.rows", (20, n), np.float32)
        for k, field in enumerate((self.transform, self.clip_ndc, self.atlas_rect, self.viewport_rect)):
            rows[4 * k : 4 * k + 4] = field.T
        ints = rows.view(np.int32)
        ints[16], ints[17], ints[18] = self.layer, self.visible, self.border
        rows[19] = self.scale  # info.w: the scale's float bits
        out = scratch("records.packed", (n, 20), np.float32) if reuse else np.empty((n, 20), np.float32)
        np.copyto(out, rows.T)
        return out.view(RECORD_DTYPE).reshape(n)

    @classmethod
    def from_packed(
        cls, packed: np.ndarray, viewport: tuple[int, int], atlas_size: tuple[int, int, int], border: int
    ) -> Records:
        """Records from the record buffer's contents ([n] of RECORD_DTYPE, as `packed` makes
        them and the GPU writes them: float32 where the buffer holds floats)."""
        info = packed["info"]
        return cls(
            visible=info[:, 1] != 0,
            viewport_rect=packed["viewport"].astype(np.int64),
            atlas_rect=packed["atlas"].astype(np.int64),
            layer=info[:, 0].astype(np.int64),
            scale=np.ascontiguousarray(info[:, 3]).view(np.float32).astype(np.float64),
            transform=packed["transform"].astype(np.float64),
            clip_ndc=packed["clip"].astype(np.float64),
            viewport=viewport,
            atlas_size=atlas_size,
            border=border,
        )

    @property
    def meets_edge(self) -> np.ndarray:
        """bool [n]: the inner B_viewport lies on an edge of the viewport, so the object may
        reach beyond it (its projection was clipped there). Any other region holds its
        object's whole projection (B_world's, snapped outward): the capture need not clip to it."""
        rect, (w, h) = self.viewport_rect, self.viewport
        return (rect[:, 0] <= 0) | (rect[:, 1] <= 0) | (rect[:, 2] >= w) | (rect[:, 3] >= h)

    @property
    def utilization(self) -> float:
        """Sum of region areas over the allocated atlas area (0 when nothing is packed)."""
        tw, th, td = self.atlas_size
        area = tw * th * td
        r = self.atlas_rect[self.visible]
        return float((r[:, 2] * r[:, 3]).sum() / area) if area else 0.0


def _read_back(name: str) -> property:
    """A planar array of GpuRecords: read back with the others on first use."""
    return property(lambda self: getattr(self.read(), name), doc=f"`Records.{name}`, read back on first use.")


class GpuRecords(Records):
    """R of a frame that the GPU wrote into the record buffer (`Settings(parameterize="gpu")`):
    what the CPU knows without waiting for the GPU, and the planar arrays read back on first use.

    The GPU-driven passes (the capture's draw lists, compositing's sort and sprite draws) take
    the record buffer as it is and read none of the arrays; picking, the export, pixel-order
    blending and the dataset read them (`read()`, or any array of `Records`), which waits for
    the GPU once per frame.

    Parameters
    ----------
    count : int
        Objects (entries in the record buffer).
    viewport : tuple of int
        (W, H) in pixels.
    atlas_size : tuple of int
        (T_w, T_h, T_d): the atlas extent the transforms T map to (with sizing "ahead" the
        allocation, not the extent used: that is known on the GPU alone until read).
    border : int
        Empty texels around each region.
    reader : callable
        Returns the frame's `Records` (reads the record buffer back).
    """

    on_gpu = True
    visible = _read_back("visible")  # type: ignore[assignment]
    viewport_rect = _read_back("viewport_rect")  # type: ignore[assignment]
    atlas_rect = _read_back("atlas_rect")  # type: ignore[assignment]
    layer = _read_back("layer")  # type: ignore[assignment]
    scale = _read_back("scale")  # type: ignore[assignment]
    transform = _read_back("transform")  # type: ignore[assignment]
    clip_ndc = _read_back("clip_ndc")  # type: ignore[assignment]

    def __init__(  # no Records.__init__: the arrays are read back on first use
        self, count: int, viewport: tuple[int, int], atlas_size: tuple[int, int, int], border: int, reader
    ) -> None:
        self.count = count
        self.viewport = viewport
        self.atlas_size = atlas_size
        self.border = border
        self._reader = reader
        self._read: Records | None = None

    @property
    def is_read(self) -> bool:
        """Whether the arrays were read back already."""
        return self._read is not None

    def read(self) -> Records:
        """The frame's records as planar arrays (read back once; waits for the GPU)."""
        read = self._read
        if read is None:
            read = self._read = self._reader()
        return read

    def __repr__(self) -> str:
        size, read = self.atlas_size, self.is_read
        return f"GpuRecords(count={self.count}, viewport={self.viewport}, atlas_size={size}, read={read})"


def region_scales(records: Records, wanted: np.ndarray, atlas_max: tuple[int, int], factor: float) -> np.ndarray:
    """The region scales in doubles, as Algorithm 1's shader works them out (the record holds
    float32): min(wanted, the fit into a layer) x the rounds' factor; 0 for objects without a region."""
    inner = np.maximum(records.viewport_rect[:, 2:] - records.viewport_rect[:, :2], 1).astype(np.float64)
    room = np.asarray(atlas_max, np.float64) - 2 * records.border
    fit = np.minimum(room[0] / inner[:, 0], room[1] / inner[:, 1])
    return np.where(records.visible, np.minimum(wanted, fit) * factor, 0.0)
