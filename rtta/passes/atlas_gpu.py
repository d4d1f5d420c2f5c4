"""Algorithm 1 in compute shaders (`Settings(parameterize="gpu")`), beside the CPU reference
`rtta.atlas.parameterize`: the same culling, near-plane clipping, viewport rectangles, border
and region scales, in doubles, and a parallel shelf packing (shaders/parameterize.comp).

Per object data live on the GPU: B_world's corners (once per scene), the explode offsets and the scale
wanted per object (0: hidden), each uploaded when it changes. Per frame the CPU issues a constant number
of calls, the last ones writing T and the records straight into the record buffer (shaders/records.glsl).
It returns a `GpuRecords`: nothing of R is read back unless a caller asks for its arrays (picking, the
export, the dataset).

Sizing the atlas: "exact" (the default; one-shot renders) reads the 64-byte state after the
rounds and sizes the atlas to the extent used, as the CPU path does; "ahead" (the viewer, the
benchmarks) reads nothing that waits: the layers are chosen from the state of the frame before,
read a frame late (docs/performance/frame.md, "Reading back").

Scale-down: when the regions need more layers than allowed, the layout stage lowers every region's scale
by the CPU loop's rule and the next round packs again; none is dropped.
"""

from __future__ import annotations

import time
from typing import Literal

import moderngl
import numpy as np

from ..atlas.records import RECORD_DTYPE, GpuRecords, Records, region_scales
from ..atlas.thinning import KeepShare
from ..errors import RttaError
from ..gl import glsl, sync
from ..gl.bindings import Storage
from ..gl.gpu import GpuScene
from .thin_gpu import CUT, RANK, GpuThinning

LOCAL_SIZE = 64
CLASSES, CLASS_BYTES, ITEM_BYTES = 128, 48, 80  # height classes (parameterize.comp), their and an item's bytes
ROUNDS = 2  # rounds of projection and layout dispatched before the state is read ("exact")
AHEAD_ROUNDS = 4  # rounds dispatched per frame when nothing is read ("ahead")
MAX_ROUNDS = 64  # as the CPU path's loop
STATE_DTYPE = np.dtype(
    [(name, "<u4") for name in ("done", "layers", "used_w", "used_h", "rounds", "cursor_layer", "cursor_y", "shelves1")]
    + [("wide2", "<u4"), ("cap2", "<u4"), ("demand", "<u4"), ("pad", "<u4"), ("factor", "<f8"), ("area", "<f8")]
)
Sizing = Literal["exact", "ahead"]
PROJECT, LAYOUT, PLACE, LAYOUT_SECOND, PLACE_SECOND, RECORD, FUSED = 1, 2, 3, 4, 5, 6, 9  # the shader's stages
ROUND = (PROJECT, LAYOUT, PLACE, LAYOUT_SECOND)
FUSED_MAX, FUSED_GROUP = 1024, 256  # up to FUSED_MAX objects one work group of FUSED_GROUP runs every stage


class GpuParameterize:
    """Algorithm 1 on the GPU for one scene's objects: records written into `GpuScene.records`.

    Parameters
    ----------
    ctx : moderngl.Context
        An OpenGL 4.3+ context with double precision in shaders (core since 4.0).
    sizing : {"exact", "ahead"}, default "exact"
        How the atlas is sized (the module's docstring): reading the frame's state, or a
        layer count chosen ahead from the state of the frame before.
    """

    def __init__(self, ctx: moderngl.Context, sizing: Sizing = "exact") -> None:
        self.ctx = ctx
        self.sizing: Sizing = sizing
        try:
            sizes = {**dict.fromkeys((*ROUND, PLACE_SECOND, RECORD), LOCAL_SIZE), FUSED: FUSED_GROUP}
            self.programs = {
                stage: ctx.compute_shader(glsl.load("parameterize.comp", STAGE=stage, LOCAL_SIZE=size))
                for stage, size in sizes.items()
            }
        except moderngl.Error as exc:  # e.g. a driver without doubles in compute shaders
            first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
            raise RttaError(f"--parameterize gpu: this driver cannot build its compute shaders ({first})") from None
        self.classes = ctx.buffer(reserve=CLASSES * CLASS_BYTES)
        self.state = ctx.buffer(reserve=STATE_DTYPE.itemsize)
        self.late = ctx.buffer(reserve=STATE_DTYPE.itemsize)  # the state of the frame before ("ahead")
        self.next_round = ctx.buffer(reserve=32)  # indirect dispatch sizes of the rounds after the first
        self.fused_max = 0 if sync.synchronous(ctx) else FUSED_MAX  # llvmpipe: 2-3x slower in one group
        self._start = np.zeros(1, STATE_DTYPE)
        self._start["factor"] = 1.0
        self.corners: moderngl.Buffer | None = None  # and the scales, items and shelves: made for n objects
        self.scales: moderngl.Buffer | None = None
        self.items = self.shelves = self.scales
        self._corners_of: np.ndarray | None = None  # the array uploaded (compared by identity)
        self.offsets = ctx.buffer(reserve=8)
        self._offsets_of: np.ndarray | None = None  # likewise
        self._wanted = np.zeros(0)
        self._wanted_key: object = None
        self._uniforms: dict[str, object] = {}  # as the programs hold them
        self._holders: dict[frozenset, list] = {}  # the programs holding any of some uniforms
        self.layers = 0  # "ahead": the layers allocated (0: none yet, the next frame is exact)
        self._ahead_of: tuple | None = None  # (viewport, atlas_max, max_layers) the allocation is for
        self._late_pending = False  # a state was copied aside and not read yet
        self.last_state = np.zeros(1, STATE_DTYPE)[0]  # the state read back last ("exact")
        self.reads = 0  # reads that waited for the GPU (the state, the records)
        self._thinning: GpuThinning | None = None
        self.cpu_seconds = 0.0  # of the last run, in Python and numpy outside GL calls (rtta bench capture)

    def _upload(self, corners: np.ndarray, wanted: np.ndarray | None, boxes: int) -> None:
        """Corners [k, n, 8, 3] and the scales wanted [n] (None: as uploaded), each when it changed."""
        n = corners.shape[-3]
        if corners is not self._corners_of:
            data = np.ascontiguousarray(corners, np.float64).reshape(boxes, n, 8, 3)
            if self.corners is None or self.corners.size != max(data.nbytes, 8):
                self.corners = _replace(self.ctx, self.corners, max(data.nbytes, 8))
            self.corners.write(data)
            self._corners_of = corners
        if wanted is None:
            return
        if self.scales is None or self.scales.size != max(n, 1) * 8 or not np.array_equal(wanted, self._wanted):
            if self.scales is None or self.scales.size != max(n, 1) * 8:
                self.scales = _replace(self.ctx, self.scales, max(n, 1) * 8)
                self.items = _replace(self.ctx, self.items, max(n, 1) * ITEM_BYTES)
                self.shelves = _replace(self.ctx, self.shelves, (n + 8) * 8)  # at most n + 3 shelves
            self.scales.write(wanted)
            self._wanted = wanted

    @classmethod
    def attempt(cls, ctx: moderngl.Context, sizing: Sizing, where: str, warn) -> GpuParameterize | bool:
        """A GpuParameterize, or False where its shaders do not build and `where` is "auto"
        (`warn` says so once; where it is "gpu" the RttaError goes on)."""
        try:
            return cls(ctx, sizing)
        except RttaError as exc:
            if where == "gpu":
                raise
            warn(f"{exc}: Algorithm 1 runs on the CPU")
            return False

    def knows(self, key: object, n: int) -> bool:
        """Whether the scales wanted uploaded are those of `key` (run's `key`) for n objects."""
        return key is not None and key == self._wanted_key and len(self._wanted) == n

    def _wanted_scales(self, n: int, region_scale, hidden, key) -> np.ndarray | None:
        """The scales wanted [n] (0: hidden), or None when `key` says they are as uploaded."""
        if self.knows(key, n):
            return None
        wanted = np.broadcast_to(np.asarray(1.0 if region_scale is None else region_scale, np.float64), (n,)).copy()
        if not (np.isfinite(wanted).all() and (wanted > 0).all() and (wanted <= 16).all()):
            raise ValueError("region scale must be in (0, 16]")
        if hidden is not None:
            wanted[np.asarray(hidden, bool)] = 0.0
        self._wanted_key = key
        return wanted

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
        region_scale: float | np.ndarray | None = 1.0,
        hidden: np.ndarray | None = None,
        offsets: np.ndarray | None = None,
        key: object = None,
        thin: KeepShare | None = None,
    ) -> GpuRecords:
        """Algorithm 1 as `rtta.atlas.parameterize`, its records written into `gpu.records`.

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
            Atlas texels per viewport pixel, for all or per object [n] (None: 1).
        hidden : numpy.ndarray, optional
            bool [n]: objects given no region.
        offsets : numpy.ndarray, optional
            float64 [n, 3]: each object's B_world moved by its offset (an exploded view:
            uploaded when the array changes, the corners stay).
        key : hashable, optional
            Equal keys promise equal `region_scale` and `hidden` (they are then neither
            checked nor uploaded again: a frame's cost does not grow with n).
        thin : KeepShare, optional
            Fast navigation: the smallest objects on screen left out too (thin_gpu.py).

        Returns
        -------
        GpuRecords
            R on the GPU; its arrays (float32 where the record buffer holds floats) are read
            back on first use.
        """
        t0 = time.perf_counter()
        n = corners.shape[-3]
        boxes = 1 if corners.ndim == 3 else corners.shape[0]
        W, H = int(viewport[0]), int(viewport[1])
        if W < 1 or H < 1:
            raise ValueError(f"viewport must be at least 1x1, got {W}x{H}")
        if atlas_max[0] < 1 + 2 * border or atlas_max[1] < 1 + 2 * border:
            raise ValueError(f"atlas maximum {atlas_max} cannot hold a 1-pixel region with border {border}")
        atlas_max = (int(atlas_max[0]), int(atlas_max[1]))
        gpu.keep_held()  # R held by a caller is read before the GPU writes over it
        wanted = self._wanted_scales(n, region_scale, hidden, key)
        ahead = self._ahead_layers((W, H), atlas_max, int(max_layers))
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
            "u_atlas_max": atlas_max,
            "u_max_layers": ahead or int(max_layers),
            "u_extent": atlas_max if self.sizing == "ahead" else (0, 0),  # the first frame's T as the next ones
            "u_thin": thin is not None,
            "u_keep": 1.0 if thin is None else float(thin.keep),
        }
        thinning = None if thin is None else self.thinning()
        self._bind(gpu, uniforms)
        groups = max(1, -(-n // LOCAL_SIZE))
        if thinning is not None and thin is not None:
            thinning.run(self.programs, thin, n, groups)  # leaves the smallest out of the rounds
        if ahead:
            self._dispatch(groups, AHEAD_ROUNDS)
            self.ctx.copy_buffer(self.late, self.state)
            self._late_pending = True
            size = (*atlas_max, ahead)
        else:
            state = self._exact(groups, n, border, atlas_max, int(max_layers))
            layers = int(state["layers"])
            size = (int(state["used_w"]), int(state["used_h"]), layers) if layers else (0, 0, 0)
            if self.sizing == "ahead":  # the first frame: allocate what it used, and an eighth more
                self.layers = min(int(max_layers), layers + max(1, layers // 8))
                self._ahead_of = ((W, H), atlas_max, int(max_layers))
                size = (*atlas_max, self.layers)
        t1 = time.perf_counter()
        frame, wanted_now = gpu.serial + 1, self._wanted
        records = GpuRecords(
            n, (W, H), size, border, lambda: self._read_records(gpu, frame, (W, H), size, border, wanted_now, atlas_max)
        )
        gpu.hand(records)
        self.cpu_seconds = outside + time.perf_counter() - t1
        return records

    def thinning(self) -> GpuThinning:
        """The thinning stages (thin_gpu.py), built on first use."""
        if self._thinning is None:
            for stage in (RANK, CUT):
                self.programs[stage] = self.ctx.compute_shader(
                    glsl.load("parameterize.comp", STAGE=stage, LOCAL_SIZE=LOCAL_SIZE)
                )
            self._thinning, self._uniforms, self._holders = GpuThinning(self.ctx), {}, {}  # the new programs' set
        return self._thinning

    def _ahead_layers(self, viewport: tuple[int, int], atlas_max: tuple[int, int], max_layers: int) -> int:
        """The layers to pack into without reading ("ahead"), from the state of the frame
        before; 0: this frame is exact (the first, after a resize, or after a frame that did
        not fit in AHEAD_ROUNDS)."""
        if self.sizing != "ahead" or self._ahead_of != (viewport, atlas_max, max_layers) or not self.layers:
            self._late_pending = False
            return 0
        if self._late_pending:
            late = np.frombuffer(self.late.read(), STATE_DTYPE)[0]  # done: the throttle waited for it
            self._late_pending = False
            if not late["done"]:
                return 0
            demand = int(late["demand"])
            if demand > self.layers:
                self.layers = min(max_layers, demand + max(1, demand // 8))
        return self.layers

    def _bind(self, gpu: GpuScene, uniforms: dict) -> None:
        """The uniforms that changed (most stay from frame to frame: the matrix alone moves),
        the state reset and the buffers bound."""
        changed = {name: value for name, value in uniforms.items() if self._uniforms.get(name) != value}
        if changed:
            self._uniforms.update(changed)
            names = frozenset(changed)  # most frames: the matrix alone, which two stages hold
            holders = self._holders.get(names)
            if holders is None:
                holders = self._holders[names] = [p for p in self.programs.values() if names & glsl.members(p)]
            for prog in holders:
                glsl.set_uniforms(prog, changed)
        self.state.write(self._start)
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

    def _exact(self, groups: int, n: int, border: int, atlas_max: tuple[int, int], max_layers: int) -> np.void:
        """Rounds until the regions fit, reading the state after each batch of ROUNDS."""
        state = self._rounds(groups)
        while not state["done"] and state["rounds"] < MAX_ROUNDS:  # rare: scaled down more than twice
            state = self._rounds(groups)
        self.last_state = state
        if not state["done"]:
            raise ValueError(
                f"{n} regions with border {border} do not fit into {max_layers} layer(s) of "
                f"{atlas_max[0]}x{atlas_max[1]} even at the smallest scale"
            )
        return state

    def _dispatch(self, groups: int, rounds: int) -> None:
        """`rounds` rounds of projection and layout, then placing and the records (the records
        of no region unless they fit). The rounds after the first are dispatched indirectly,
        with the sizes the layout stage leaves: 0 groups once the regions fit. Up to `fused_max` objects
        one work group runs every stage in one dispatch (a GPU: 1 call and no gaps instead of 18;
        llvmpipe: 0, the work group's barriers cost it more than the calls)."""
        self.next_round.write(np.array([groups, 1, 1, 0, 1, 1, 1, 0], np.uint32))
        self.next_round.bind_to_storage_buffer(Storage.PARAM_DISPATCH)  # the layout stage writes it
        if groups * LOCAL_SIZE <= self.fused_max:
            glsl.set_uniform(self.programs[FUSED], "u_rounds", rounds)
            self.programs[FUSED].run(1)
            return sync.barrier(self.ctx, moderngl.SHADER_STORAGE_BARRIER_BIT | moderngl.BUFFER_UPDATE_BARRIER_BIT)
        programs, wait = self.programs, not sync.synchronous(self.ctx)  # (sync.barrier's test, once)
        for r in range(rounds):
            for stage in ROUND:
                single = stage in (LAYOUT, LAYOUT_SECOND)
                if r == 0:
                    programs[stage].run(1 if single else groups)
                else:
                    programs[stage].run_indirect(self.next_round, 16 if single else 0)
                if wait:
                    self.ctx.memory_barrier(moderngl.SHADER_STORAGE_BARRIER_BIT | moderngl.COMMAND_BARRIER_BIT)
        for stage in (PLACE_SECOND, RECORD):
            programs[stage].run(groups)
            if wait:
                self.ctx.memory_barrier(moderngl.SHADER_STORAGE_BARRIER_BIT | moderngl.BUFFER_UPDATE_BARRIER_BIT)

    def _rounds(self, groups: int) -> np.void:
        """ROUNDS rounds, placing and the records; the state, a read that waits for the GPU."""
        self._dispatch(groups, ROUNDS)
        self.reads += 1
        return np.frombuffer(self.state.read(), STATE_DTYPE)[0]

    def _read_records(self, gpu, frame: int, viewport, size, border, wanted, atlas_max) -> Records:
        """The records of `frame` read back (GpuRecords.read), waiting for the GPU; held ones are
        read before a later frame writes over R (GpuScene.keep_held), a missed one is an error."""
        if gpu.serial != frame or not self.programs:
            raise RuntimeError(
                "these records belong to an earlier capture, whose R the GPU no longer holds: "
                "read them (records.read()) before capturing again or releasing the renderer"
            )
        n = len(wanted)
        self.reads += 1
        state = np.frombuffer(self.state.read(), STATE_DTYPE)[0]
        records = Records.from_packed(_read_packed(gpu.records, n), viewport, size, border)
        records.scale[:] = region_scales(records, wanted, atlas_max, float(state["factor"]))
        return records

    def release(self) -> None:
        """Free the programs and buffers."""
        for prog in self.programs.values():
            prog.release()
        self.programs.clear()
        buffers = (self.classes, self.state, self.late, self.next_round, self.corners, self.scales, self.items)
        for buf in (*buffers, self.shelves, self.offsets):
            if buf is not None:
                buf.release()
        if self._thinning is not None:
            self._thinning.release()
        self.corners = self.scales = self.items = self.shelves = self._thinning = None
        self._corners_of = self._offsets_of = None


def _replace(ctx: moderngl.Context, old: moderngl.Buffer | None, size: int) -> moderngl.Buffer:
    if old is not None:
        old.release()
    return ctx.buffer(reserve=size)


def _read_packed(buffer: moderngl.Buffer, n: int) -> np.ndarray:
    """The record buffer's first n entries (std430, RECORD_DTYPE)."""
    return np.frombuffer(buffer.read(size=n * RECORD_DTYPE.itemsize), RECORD_DTYPE) if n else np.zeros(0, RECORD_DTYPE)
