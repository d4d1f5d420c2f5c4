"""Algorithm 1 in compute shaders (`Settings(parameterize="gpu")`), beside the CPU reference
`rtta.atlas.parameterize`: the same culling, near-plane clipping, viewport rectangles, border
and region scales, in doubles, and a parallel shelf packing (shaders/parameterize.comp).

Per object data live on the GPU: B_world's corners (uploaded when the array changes: once
per scene, every frame of an exploded view) and the scale wanted per object, 0 for the hidden
(uploaded when it changes: the focus, hiding). Per frame the CPU issues a constant number of
calls: a small state write, a round of two dispatches twice, two dispatches that write T and
the records straight into the record buffer the capture, post-processing and compositing read
(shaders/records.glsl), a read of the 32-byte state and, in this first step, a read of the
records back into `Records`, which the draw lists and compositing still take on the CPU.

Scale-down policy: when the regions need more layers than allowed, the layout stage itself
lowers every region's scale by min(0.9, 0.95 sqrt(capacity / area)), the CPU loop's rule
(the area counts each region as tall as its height class), and the next round packs
again; no visible object is dropped. Two rounds run
before the CPU reads the state (placing and the records are no-ops until the regions fit);
more only while it says they do not fit yet.
"""

from __future__ import annotations

import time

import moderngl
import numpy as np

from ..atlas.records import RECORD_DTYPE, Records
from ..errors import RttaError
from ..gl import glsl
from ..gl.bindings import Storage
from ..gl.gpu import GpuScene

LOCAL_SIZE = 64
CLASSES = 128  # height classes (parameterize.comp)
CLASS_BYTES = 48
ITEM_BYTES = 80
ROUNDS = 2  # rounds of projection and layout dispatched before the state is read
MAX_ROUNDS = 64  # as the CPU path's loop
STATE_DTYPE = np.dtype(
    [(name, "<u4") for name in ("done", "layers", "used_w", "used_h", "rounds", "cursor_layer", "cursor_y")]
    + [("shelves1", "<u4"), ("wide2", "<u4"), ("cap2", "<u4"), ("factor", "<f8"), ("area", "<f8")]
)
PROJECT, LAYOUT, PLACE, LAYOUT_SECOND, PLACE_SECOND, RECORD = 1, 2, 3, 4, 5, 6  # the shader's stages
ROUND = (PROJECT, LAYOUT, PLACE, LAYOUT_SECOND)


class GpuParameterize:
    """Algorithm 1 on the GPU for one scene's objects: records written into `GpuScene.records`.

    Parameters
    ----------
    ctx : moderngl.Context
        An OpenGL 4.3+ context with double precision in shaders (core since 4.0).
    """

    def __init__(self, ctx: moderngl.Context) -> None:
        self.ctx = ctx
        try:
            self.programs = {
                stage: ctx.compute_shader(glsl.load("parameterize.comp", STAGE=stage, LOCAL_SIZE=LOCAL_SIZE))
                for stage in (*ROUND, PLACE_SECOND, RECORD)
            }
        except moderngl.Error as exc:  # e.g. a driver without doubles in compute shaders
            first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
            raise RttaError(f"--parameterize gpu: this driver cannot build its compute shaders ({first})") from None
        self.classes = ctx.buffer(reserve=CLASSES * CLASS_BYTES)
        self.state = ctx.buffer(reserve=STATE_DTYPE.itemsize)
        self.corners: moderngl.Buffer | None = None
        self.scales: moderngl.Buffer | None = None
        self.items: moderngl.Buffer | None = None
        self.shelves: moderngl.Buffer | None = None
        self._corners_of: np.ndarray | None = None  # the array uploaded (compared by identity)
        self.offsets = ctx.buffer(reserve=8)
        self._offsets_of: np.ndarray | None = None  # likewise
        self._wanted = np.zeros(0)
        self.last_state = np.zeros(1, STATE_DTYPE)[0]  # the state read back by the last run
        self.cpu_seconds = 0.0  # of the last run, in Python and numpy outside GL calls (rtta bench capture)

    def _upload(self, corners: np.ndarray, wanted: np.ndarray, boxes: int) -> None:
        """Corners [k, n, 8, 3] and the scales wanted [n], each when it changed."""
        n = len(wanted)
        if corners is not self._corners_of:
            data = np.ascontiguousarray(corners, np.float64).reshape(boxes, n, 8, 3)
            if self.corners is None or self.corners.size != max(data.nbytes, 8):
                self.corners = _replace(self.ctx, self.corners, max(data.nbytes, 8))
            self.corners.write(data)
            self._corners_of = corners
        if self.scales is None or self.scales.size != max(n, 1) * 8 or not np.array_equal(wanted, self._wanted):
            if self.scales is None or self.scales.size != max(n, 1) * 8:
                self.scales = _replace(self.ctx, self.scales, max(n, 1) * 8)
                self.items = _replace(self.ctx, self.items, max(n, 1) * ITEM_BYTES)
                self.shelves = _replace(self.ctx, self.shelves, (n + 8) * 8)  # at most n + 3 shelves
            self.scales.write(wanted)
            self._wanted = wanted

    def run(
        self,
        gpu: GpuScene,
        corners: np.ndarray,
        vpm: np.ndarray,
        viewport: tuple[int, int],
        *,
        border: int,
        atlas_max: tuple[int, int],
        max_layers: int,
        region_scale: float | np.ndarray = 1.0,
        hidden: np.ndarray | None = None,
        offsets: np.ndarray | None = None,
    ) -> Records:
        """Algorithm 1 as `rtta.atlas.parameterize` (same arguments but `thin`), its records
        written into `gpu.records` and read back.

        Parameters
        ----------
        gpu : GpuScene
            The scene on the GPU, whose record buffer receives R.
        corners : numpy.ndarray
            B_world corners [n, 8, 3], or [k, n, 8, 3] whose projections are intersected.
        vpm : numpy.ndarray
            The 4x4 view-projection matrix.
        viewport : tuple of int
            (W, H) in pixels.
        border : int
            Empty texels around each region.
        atlas_max : tuple of int
            The largest layer (W, H).
        max_layers : int
            The most layers; regions are scaled down rather than dropped.
        region_scale : float or numpy.ndarray, default 1
            Atlas texels per viewport pixel, for all or per object [n].
        hidden : numpy.ndarray, optional
            bool [n]: objects given no region.
        offsets : numpy.ndarray, optional
            float64 [n, 3]: each object's B_world moved by its offset (an exploded view:
            uploaded when the array changes, the corners stay).

        Returns
        -------
        Records
            R as the GPU wrote it (float32 where the record buffer holds floats).
        """
        t0 = time.perf_counter()
        n = corners.shape[-3]
        boxes = 1 if corners.ndim == 3 else corners.shape[0]
        W, H = int(viewport[0]), int(viewport[1])
        if W < 1 or H < 1:
            raise ValueError(f"viewport must be at least 1x1, got {W}x{H}")
        if atlas_max[0] < 1 + 2 * border or atlas_max[1] < 1 + 2 * border:
            raise ValueError(f"atlas maximum {atlas_max} cannot hold a 1-pixel region with border {border}")
        wanted = np.broadcast_to(np.asarray(region_scale, np.float64), (n,)).copy()
        if not (np.isfinite(wanted).all() and (wanted > 0).all() and (wanted <= 16).all()):
            raise ValueError("region scale must be in (0, 16]")
        if hidden is not None:
            wanted[np.asarray(hidden, bool)] = 0.0
        outside = time.perf_counter() - t0
        self._upload(corners, wanted, boxes)
        if offsets is not None and offsets is not self._offsets_of:
            data = np.ascontiguousarray(offsets, np.float64).reshape(n * 3)
            if self.offsets.size < max(data.nbytes, 8):
                self.offsets = _replace(self.ctx, self.offsets, data.nbytes)
            self.offsets.write(data)
            self._offsets_of = offsets
        uniforms = {
            "u_vpm": np.asarray(vpm, np.float64).T.tobytes(),
            "u_count": n,
            "u_boxes": boxes,
            "u_offsets": offsets is not None,
            "u_viewport": (W, H),
            "u_border": border,
            "u_atlas_max": tuple(int(v) for v in atlas_max),
            "u_max_layers": int(max_layers),
        }
        for prog in self.programs.values():
            for name, value in uniforms.items():
                if name in prog:
                    if isinstance(value, bytes):
                        glsl.uniform(prog, name).write(value)
                    else:
                        glsl.uniform(prog, name).value = value
        start = np.zeros(1, STATE_DTYPE)
        start["factor"] = 1.0
        self.state.write(start)
        self.classes.clear()
        assert self.corners is not None and self.scales is not None and self.items is not None
        assert self.shelves is not None
        for buf, binding in (
            (self.corners, Storage.PARAM_CORNERS),
            (self.scales, Storage.PARAM_SCALES),
            (self.items, Storage.PARAM_ITEMS),
            (self.shelves, Storage.PARAM_SHELVES),
            (self.offsets, Storage.PARAM_OFFSETS),
            (self.classes, Storage.PARAM_CLASSES),
            (self.state, Storage.PARAM_STATE),
            (gpu.records, Storage.RECORDS),
        ):
            buf.bind_to_storage_buffer(binding)
        groups = max(1, -(-n // LOCAL_SIZE))
        state = self._rounds(groups)
        while not state["done"] and state["rounds"] < MAX_ROUNDS:  # rare: scaled down more than twice
            state = self._rounds(groups)
        self.last_state = state
        if not state["done"]:
            raise ValueError(
                f"{n} regions with border {border} do not fit into {max_layers} layer(s) of "
                f"{atlas_max[0]}x{atlas_max[1]} even at the smallest scale"
            )
        packed = _read_packed(gpu.records, n)
        t0 = time.perf_counter()
        records = _records(packed, (W, H), border, state)
        records.scale[:] = _scales(records, wanted, atlas_max, float(state["factor"]))
        gpu.written = records
        self.cpu_seconds = outside + time.perf_counter() - t0
        return records

    def _rounds(self, groups: int) -> np.void:
        """ROUNDS rounds of projection and layout (no-ops once the regions fit), then placing and
        the records (no-ops unless they fit); the state, the one read that waits for the GPU."""
        for _ in range(ROUNDS):
            for stage in ROUND:
                self.programs[stage].run(1 if stage in (LAYOUT, LAYOUT_SECOND) else groups)
                self.ctx.memory_barrier(moderngl.SHADER_STORAGE_BARRIER_BIT)
        for stage in (PLACE_SECOND, RECORD):
            self.programs[stage].run(groups)
            self.ctx.memory_barrier(moderngl.SHADER_STORAGE_BARRIER_BIT | moderngl.BUFFER_UPDATE_BARRIER_BIT)
        return self._read_state()

    def _read_state(self) -> np.void:
        return np.frombuffer(self.state.read(), STATE_DTYPE)[0]

    def release(self) -> None:
        """Free the programs and buffers."""
        for prog in self.programs.values():
            prog.release()
        self.programs.clear()
        for buf in (self.classes, self.state, self.corners, self.scales, self.items, self.shelves, self.offsets):
            if buf is not None:
                buf.release()
        self.corners = self.scales = self.items = self.shelves = None
        self._corners_of = self._offsets_of = None


def _replace(ctx: moderngl.Context, old: moderngl.Buffer | None, size: int) -> moderngl.Buffer:
    if old is not None:
        old.release()
    return ctx.buffer(reserve=size)


def _read_packed(buffer: moderngl.Buffer, n: int) -> np.ndarray:
    """The record buffer's first n entries (std430, RECORD_DTYPE)."""
    return np.frombuffer(buffer.read(size=n * RECORD_DTYPE.itemsize), RECORD_DTYPE) if n else np.zeros(0, RECORD_DTYPE)


def _scales(records: Records, wanted: np.ndarray, atlas_max: tuple[int, int], factor: float) -> np.ndarray:
    """The region scales in doubles, as the shader worked them out (the record holds float32):
    min(wanted, the fit into a layer) x the rounds' factor; 0 for objects without a region."""
    inner = np.maximum(records.viewport_rect[:, 2:] - records.viewport_rect[:, :2], 1).astype(np.float64)
    room = np.asarray(atlas_max, np.float64) - 2 * records.border
    fit = np.minimum(room[0] / inner[:, 0], room[1] / inner[:, 1])
    return np.where(records.visible, np.minimum(wanted, fit) * factor, 0.0)


def _records(packed: np.ndarray, viewport: tuple[int, int], border: int, state: np.void) -> Records:
    """Records from the packed entries read back."""
    info = packed["info"]
    layers = int(state["layers"])
    return Records(
        visible=info[:, 1] != 0,
        viewport_rect=packed["viewport"].astype(np.int64),
        atlas_rect=packed["atlas"].astype(np.int64),
        layer=info[:, 0].astype(np.int64),
        scale=np.ascontiguousarray(info[:, 3]).view(np.float32).astype(np.float64),
        transform=packed["transform"].astype(np.float64),
        clip_ndc=packed["clip"].astype(np.float64),
        viewport=viewport,
        atlas_size=(int(state["used_w"]), int(state["used_h"]), layers) if layers else (0, 0, 0),
        border=border,
    )
