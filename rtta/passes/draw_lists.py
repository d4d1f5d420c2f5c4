"""The capture's draw lists built on the GPU (issue 43): a frame whose CPU cost does not grow
with the number of objects.

The CPU path (`ScenePass.draw_objects`) builds each frame's lists from R's arrays in numpy
(visible, on the viewport's edge, closed and wholly beyond the near plane) and turns them into
index runs. Where R lives on the GPU alone (`GpuRecords`, Algorithm 1 in compute shaders) a
compute shader (shaders/capture_lists.comp) sorts the objects into four kinds, {culled back
faces, double-sided} x {clipped to their regions, not}, and writes for each kind a list of
DrawElementsIndirect commands, consecutive objects of one kind merged into one command (at
most one command per 64 objects and per change of kind), and its length into a parameter
buffer. The capture then draws each list with one glMultiDrawElementsIndirectCount (GL 4.6,
GL_ARB_indirect_parameters), or without that extension reads the four lengths (16 bytes) and
draws with `render_indirect`. The CPU's calls per frame are constant (nvpro-samples'
gl_occlusion_culling does the same).

The order of the commands within a list depends on the GPU's atomics; the images do not:
every object draws into its own atlas region (the regions of unclipped objects hold their
whole projection, the others are clipped), and each object's triangles keep their order
inside one command.
"""

from __future__ import annotations

import moderngl
import numpy as np

from ..gl import glraw, glsl, sync
from ..gl.bindings import Storage
from ..gl.glsl import mat_bytes
from ..gl.gpu import GpuScene
from ..gl.indirect import COMMAND_BYTES, IndirectCountDraw
from ..gl.targets import LayeredTarget
from ..scene.camera import near_distance

LOCAL_SIZE = 64  # objects per workgroup: a command covers at most this many
MAX_GROUPS = 65535  # workgroups along x that every GL 4.3 driver takes
KINDS = 4  # kind = 2 * clipped + double-sided (shaders/capture_lists.comp)
GL_SHADER_STORAGE_BARRIER_BIT = 0x2000
GL_COMMAND_BARRIER_BIT = 0x40  # indirect commands and the parameter buffer
GL_BUFFER_UPDATE_BARRIER_BIT = 0x200
ZERO_COUNTS = bytes(4 * KINDS)


def kind(cull: bool, clip: bool) -> int:
    """The list of objects drawn with back faces culled or not, clipped or not."""
    return 2 * clip + (not cull)


def draws_from_lists(records, gpu: GpuScene) -> bool:
    """Whether the capture draws from GPU-built lists: R is on the GPU (`GpuRecords`) and no
    section plane cuts an object (sections keep the CPU path: their programs and caps)."""
    placement = gpu.placement
    return bool(getattr(records, "on_gpu", False)) and (placement is None or not placement.sections)


class CaptureLists:
    """The capture's four draw lists, written by a compute shader from the record buffer.

    Per scene the objects' index ranges are uploaded once, and per placement (explode, cut
    away) their flags (closed, removed); per frame `build` costs a 16-byte write, a few
    uniforms and one dispatch.

    Parameters
    ----------
    ctx : moderngl.Context
        An OpenGL 4.3+ context with double precision in shaders (core since 4.0).
    """

    def __init__(self, ctx: moderngl.Context) -> None:
        self.ctx = ctx
        self.program = ctx.compute_shader(glsl.load("capture_lists.comp", LOCAL_SIZE=LOCAL_SIZE))
        self.counts = ctx.buffer(reserve=4 * KINDS)
        self.commands: moderngl.Buffer | None = None
        self.capacity = 0  # commands per list
        self.ranges: moderngl.Buffer | None = None
        self.flags: moderngl.Buffer | None = None
        self._ranges_for: GpuScene | None = None
        self._flags_for: tuple | None = None
        self._lengths: np.ndarray | None = None  # the counts as read (lengths())
        self._count_draw = IndirectCountDraw(ctx.version_code, set(ctx.extensions))
        self.count_draw = self._count_draw.available  # False: the lengths are read back (tests set it)

    def build(
        self, gpu: GpuScene, view: np.ndarray, proj: np.ndarray, viewport: tuple[int, int], clip_all: bool = False
    ) -> None:
        """Write the four lists for one frame from `gpu.records` (R, shaders/records.glsl) and
        `gpu.bounds` (B_world, moved by the placement's offsets: rtta.renderer.placing).

        Parameters
        ----------
        gpu : GpuScene
            The scene, R in its record buffer.
        view, proj : numpy.ndarray
            The frame's 4x4 matrices (the scene origin at 0).
        viewport : tuple of int
            (W, H) in pixels, R's.
        clip_all : bool, default False
            Every object clipped (the geometry-shader path): lists 0 and 1 stay empty.
        """
        self._upload(gpu)
        n = gpu.scene.count
        self.counts.write(ZERO_COUNTS)
        self._lengths = None
        if n == 0:
            return
        gpu.records.bind_to_storage_buffer(Storage.RECORDS)
        gpu.objects.bind_to_storage_buffer(Storage.OBJECTS)
        gpu.bounds.bind_to_storage_buffer(Storage.BOUNDS)
        assert self.flags is not None and self.ranges is not None and self.commands is not None
        self.flags.bind_to_storage_buffer(Storage.DRAW_FLAGS)
        self.ranges.bind_to_storage_buffer(Storage.DRAW_RANGES)
        self.commands.bind_to_storage_buffer(Storage.DRAW_COMMANDS)
        self.counts.bind_to_storage_buffer(Storage.DRAW_COUNTS)
        values = {
            "u_count": n,
            "u_capacity": self.capacity,
            "u_viewport": (float(viewport[0]), float(viewport[1])),
            "u_view_z": tuple(np.asarray(view, np.float64)[2].tolist()),
            "u_near": near_distance(proj),
            "u_cull_closed": bool(gpu.cull_closed),
            "u_clip_all": bool(clip_all),
        }
        glsl.set_uniforms(self.program, values)
        wait = not sync.synchronous(self.ctx)  # (sync.barrier's test, once)
        if wait:
            self.ctx.memory_barrier(GL_SHADER_STORAGE_BARRIER_BIT)  # R written by Algorithm 1's shaders
        blocks = -(-n // LOCAL_SIZE)
        wide = min(blocks, MAX_GROUPS)
        self.program.run(wide, -(-blocks // wide))
        if wait:
            self.ctx.memory_barrier(GL_COMMAND_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT)

    def draw(self, vao: moderngl.VertexArray, program: moderngl.Program, which: int) -> None:
        """Draw list `which` (`kind()`) with `program` and `vao` in one call, its length as
        the GPU wrote it; without the extension the four lengths are read first."""
        assert self.commands is not None, "build() first"
        if self.count_draw:
            self._count_draw.draw(
                program.glo,
                vao.glo,
                self.commands.glo,
                self.counts.glo,
                which * self.capacity,
                4 * which,
                self.capacity,
            )
            return
        count = int(self.lengths()[which])
        if count:
            vao.render_indirect(self.commands, moderngl.TRIANGLES, count=count, first=which * self.capacity)

    def lengths(self) -> np.ndarray:
        """uint32 [4]: the commands in each list (the GPU's counts read once per build: waits for it)."""
        if self._lengths is None:
            self._lengths = np.frombuffer(self.counts.read(), np.uint32).copy()
        return self._lengths

    def commands_of(self, which: int) -> np.ndarray:
        """uint32 [k, 5]: list `which`'s commands (count, 1, first index, 0, 0), as written (tests)."""
        assert self.commands is not None, "build() first"
        k = int(self.lengths()[which])
        if k == 0:
            return np.zeros((0, 5), np.uint32)
        raw = self.commands.read(size=k * COMMAND_BYTES, offset=which * self.capacity * COMMAND_BYTES)
        return np.frombuffer(raw, np.uint32).reshape(k, 5).copy()

    def _upload(self, gpu: GpuScene) -> None:
        """The index ranges and command lists once per scene; the flags once per placement."""
        scene = gpu.scene
        if self._ranges_for is not gpu:
            for buf in (self.ranges, self.commands):
                if buf is not None:
                    buf.release()
            n = max(scene.count, 1)
            ranges = np.zeros((n, 2), np.uint32)
            ranges[: scene.count] = scene.index_ranges
            self.ranges = self.ctx.buffer(ranges.tobytes())
            self.capacity = n  # a list holds at most one command per object
            self.commands = self.ctx.buffer(reserve=KINDS * n * COMMAND_BYTES)
            self._ranges_for, self._flags_for = gpu, None
        placement = gpu.placement
        key = (gpu, None if placement is None else placement.serial)
        if self._flags_for != key:
            flags = np.zeros(max(scene.count, 1), np.uint32)
            flags[: scene.count] = scene.closed
            if placement is not None:
                flags[: scene.count] |= np.asarray(placement.removed, np.uint32) << 1
            if self.flags is not None:
                self.flags.release()
            self.flags = self.ctx.buffer(flags.tobytes())
            self._flags_for = key

    def release(self) -> None:
        for buf in (self.counts, self.commands, self.ranges, self.flags):
            if buf is not None:
                buf.release()
        self.commands = self.ranges = self.flags = None
        self._ranges_for = self._flags_for = None
        self.program.release()


def draw_from_lists(capture, lists: CaptureLists, gpu: GpuScene, view, proj, atlas: LayeredTarget) -> None:
    """Draw the frame's objects into `atlas` from the lists `lists.build` wrote (`capture`: a
    CapturePass, its program and state prepared by `capture.prepare`): per clip variant one
    setup and, culled and double-sided, one indirect-count draw each. The geometry-shader path
    clips every object (one variant)."""
    clip_all = capture.path == "gs"
    matrices = (mat_bytes(view), mat_bytes(proj))  # once for both variants
    try:
        for clip in (True,) if clip_all else (False, True):
            guard = clip and capture.guard > 0  # (rtta.passes.guard)
            vao = capture.prepare(
                gpu, view, proj, atlas, matrices, REGION_CLIP=clip and not clip_all, REGION_GUARD=guard
            )
            glraw.set_clip_distances(4, clip)
            for cull in (True, False):
                capture.cull(cull)
                lists.draw(vao, capture.program, kind(cull, clip))
    finally:
        capture.cull(False)
        glraw.set_clip_distances(4, False)


def capture_from_records(capture, gpu: GpuScene, view, proj, atlas: LayeredTarget, records) -> None:
    """Draw the frame's objects into `atlas` from R's arrays (the CPU path): on the geometry-
    shader path every visible object clipped, in one call; on the vertex-shader path those
    whose region meets the viewport's edge alone, in a second call."""
    if capture.path == "gs":  # the geometry shader clips every triangle
        _draw(capture, gpu, view, proj, atlas, records.visible, clip=True)
        return
    edge = records.visible & records.meets_edge
    _draw(capture, gpu, view, proj, atlas, records.visible & ~edge, clip=False)
    _draw(capture, gpu, view, proj, atlas, edge, clip=True)


def _draw(capture, gpu: GpuScene, view, proj, atlas: LayeredTarget, objects: np.ndarray, *, clip: bool) -> None:
    """Draw the objects in `objects` (bool [n]; culled and hidden ones are never in it),
    clipped to their regions or not, in one call (ScenePass.draw_objects: one per kind)."""
    if not objects.any():
        return
    guard = clip and capture.guard > 0  # an extreme zoom (rtta.passes.guard)
    vao = capture.setup(gpu, view, proj, atlas, REGION_CLIP=clip and capture.path == "vs", REGION_GUARD=guard)
    glraw.set_clip_distances(4, clip)
    try:
        capture.draw_objects(vao, gpu, None if objects.all() else objects)
    finally:
        glraw.set_clip_distances(4, False)
