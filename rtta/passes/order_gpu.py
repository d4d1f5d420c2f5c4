"""Compositing's draw order on the GPU (issue 43): the objects to draw, back to front, as
`composite.back_to_front` orders them (view depth of each bounds centre, farthest first, ties
by id), sorted in compute shaders (shaders/depth_order.comp) into the draw list that sprite
draws read (`Storage.DRAW_LIST`), with their count in indirect DrawArrays commands. Nothing
of it is read back, and the CPU's work per frame does not grow with the objects.

Two sorts give the same order on every driver (`GpuOrder.method`; "auto", the default, takes
bitonic up to BLOCK objects, one dispatch in shared memory, and radix above):
"radix": a stable LSD radix sort of the keys, 4 bits a pass (8 passes of 2
dispatches, 18 in all at any count), the ids starting in ascending order so ties stay by id;
"bitonic": over (key, id) pairs padded to a power of two (unique pairs: one order), the steps
within a block of BLOCK elements in shared memory (dispatches grow with log² of the count:
38 at 100,000). On llvmpipe (2 shared cores) radix took 1/4 to 1/6 of bitonic's time.
"""

from __future__ import annotations

import moderngl
import numpy as np

from ..gl import glsl, sync
from ..gl.bindings import Storage
from .sprites import UPSAMPLE_BELOW

KEYS, BLOCK_SORT, STEP, BLOCK_MERGE, COMMANDS, COUNT, SCATTER = 1, 2, 3, 4, 5, 6, 8  # the shader's stages
# three DrawArrays commands 5 uints apart, four counts, the focus list's three commands, the radix pass, its groups done
COMMAND_WORDS = 37
# the focus list's commands (20-byte steps): every focus region at scale 1, none upsampled, some
FOCUS_COMMANDS = (4, 5, 6)
DRAWN = 15  # the command buffer's word of the drawn count
BLOCK = 1024  # elements sorted in shared memory by one work group
GROUP = 64  # invocations of that work group (each compares BLOCK / 2 / GROUP pairs a step)
STEP_GROUP = 256  # invocations per work group of the key and global step stages
TILE = 2048  # elements per work group of the radix passes (depth_order.comp's 256 * PER)
RADIX_BITS = 4  # bits of the key a radix pass sorts by (the shader's)


def sort_length(count: int, method: str = "radix") -> int:
    """The sort's length for `count` objects: a multiple of TILE (radix), or a power of two
    of at least BLOCK (bitonic)."""
    if method == "radix":
        return TILE * max(1, -(-count // TILE))
    return max(BLOCK, 1 << max(count - 1, 0).bit_length())


class GpuOrder:
    """Sorts a frame's objects back to front on the GPU into `ids` (the draw list) and counts
    the ones to draw into `command` (indirect DrawArrays commands, one per sprite variant).

    Parameters
    ----------
    ctx : moderngl.Context
        An OpenGL 4.3+ context (compute shaders).
    method : {"auto", "radix", "bitonic"}, default "auto"
        The sort (the module's docstring); all give `back_to_front`'s order. "auto": bitonic
        up to BLOCK objects (one dispatch: on llvmpipe, 26 radix dispatches, as there were, cost a small
        scene's frame 30-40% more), radix above.

    Attributes
    ----------
    ids : moderngl.Buffer
        After `sort`: int32 ids, the objects to draw first (farthest first), then the others.
    command : moderngl.Buffer
        After `sort`: three DrawArrays commands (count, 1, 0, 0) uint32 at 20-byte steps
        (moderngl's `render_indirect(command, moderngl.POINTS, count=1, first=k)`), of which
        one draws the list and the others nothing: k = 0 where no region drawn is upsampled
        (sprites.UPSAMPLE_BELOW), 1 where all are, 2 where some are (sprites.Listed).
    """

    def __init__(self, ctx: moderngl.Context, method: str = "auto") -> None:
        if method not in ("auto", "radix", "bitonic"):
            raise ValueError(f"sort method must be auto, radix or bitonic, got {method!r}")
        self.ctx = ctx
        self.method = method
        self.programs: dict[tuple[int, bool], moderngl.ComputeShader] = {}
        self.keys = ctx.buffer(reserve=4 * BLOCK)
        self.ids = ctx.buffer(reserve=4 * BLOCK)
        self.keys_out = ctx.buffer(reserve=4 * BLOCK)  # the radix passes' other side
        self.ids_out = ctx.buffer(reserve=4 * BLOCK)
        self.counts = ctx.buffer(reserve=4)  # the radix passes' digit counts per tile
        self.command = ctx.buffer(reserve=4 * COMMAND_WORDS)
        self.offsets = ctx.buffer(reserve=12)
        self._offsets_of: np.ndarray | None = None  # the offsets uploaded (compared by identity)
        self.dispatches = 0  # of the last sort
        self._wait = not sync.synchronous(ctx)  # barriers between dispatches (sync.barrier)

    def _program(self, stage: int, offsets: bool = False) -> moderngl.ComputeShader:
        key = (stage, offsets)
        if key not in self.programs:
            self.programs[key] = self.ctx.compute_shader(
                glsl.load("depth_order.comp", STAGE=stage, BLOCK=BLOCK, GROUP=GROUP, OFFSETS=offsets)
            )
        return self.programs[key]

    def method_for(self, count: int) -> str:
        """The sort that orders `count` objects ("auto": bitonic up to BLOCK, radix above)."""
        if self.method != "auto":
            return self.method
        return "bitonic" if count <= BLOCK else "radix"

    def _ensure(self, length: int, method: str) -> None:
        radix = method == "radix"
        for buf in (self.keys, self.ids, self.keys_out, self.ids_out) if radix else (self.keys, self.ids):
            if buf.size < 4 * length:
                buf.orphan(4 * length)
        tiles = (16 * 4) * (length // TILE)
        if radix and self.counts.size < tiles:
            self.counts.orphan(tiles)

    def _upload_offsets(self, offsets: np.ndarray | None) -> bool:
        """Upload per-object offsets [n, 3] when the array object changed; whether there are any."""
        if offsets is None:
            return False
        if offsets is not self._offsets_of:
            data = np.ascontiguousarray(offsets, np.float32)
            if self.offsets.size < data.nbytes:
                self.offsets.orphan(data.nbytes)
            self.offsets.write(data)
            self._offsets_of = offsets
        self.offsets.bind_to_storage_buffer(Storage.SORT_OFFSETS)
        return True

    def sort(
        self,
        *,
        count: int,
        records: moderngl.Buffer,
        bounds: moderngl.Buffer,
        view: np.ndarray,
        styles: moderngl.Buffer | None = None,
        exclude_focus: bool = True,
        offsets: np.ndarray | None = None,
        focus: int = 0,
    ) -> None:
        """Order `count` objects back to front for `view` into `ids`, their count in `command`.

        Parameters
        ----------
        count : int
            Objects (entries of the record, bounds and style buffers).
        records : moderngl.Buffer
            R (shaders/records.glsl): objects whose `info.y` is 0 are not drawn.
        bounds : moderngl.Buffer
            B_world per object as (min, max) vec4 pairs, relative to the scene origin (GpuScene.bounds).
        view : numpy.ndarray
            The 4x4 view matrix (scene origin at 0): view depth is -(view @ centre).z.
        styles : moderngl.Buffer, optional
            Compositing's style parameters (opacity, focus, ao, edges) per object: its focus
            flags name the focus objects (the focus list's commands are counted from them).
            None: no focus; every visible object is drawn.
        exclude_focus : bool, default True
            With `styles`: the objects flagged focus are not drawn (the ghosted context).
        offsets : numpy.ndarray, optional
            [count, 3] added to the bounds centres (uploaded when the array object changes).
        focus : int, default 0
            The length of a list of the focus objects (with `styles`): `command` gets three
            more commands for it (FOCUS_COMMANDS), its length in the first where every visible
            focus region is at one texel per pixel (scale 1: quad outlines), else in the second
            where none is upsampled, else in the third.
        """
        self.dispatches = 0
        length = self._keys(count, records, bounds, view, styles, offsets, exclude_focus)
        if self.method_for(count) == "radix":
            self._radix(length)
        else:
            self._bitonic(length)
        self._commands(0, focus if styles is not None else 0)

    def _radix(self, length: int) -> None:
        """The keys and ids sorted by key, stably, RADIX_BITS a pass (an even number of passes:
        the result ends in `keys` and `ids`)."""
        tiles = length // TILE
        self.counts.bind_to_storage_buffer(Storage.SORT_COUNTS)
        self.keys_out.bind_to_storage_buffer(Storage.SORT_KEYS_OUT)  # both sides bound: the GPU
        self.ids_out.bind_to_storage_buffer(Storage.SORT_IDS_OUT)  # counts the passes and picks
        stages = (self._program(COUNT), self._program(SCATTER))
        for prog in stages:
            glsl.set_uniform(prog, "u_tiles", tiles)
        wait, ctx = self._wait, self.ctx  # _run's work inlined: 16 dispatches, no call each
        for _ in range(32 // RADIX_BITS):
            for prog in stages:
                if wait:
                    ctx.memory_barrier(moderngl.SHADER_STORAGE_BARRIER_BIT)
                prog.run(group_x=tiles)
        self.dispatches += 2 * (32 // RADIX_BITS)

    def _bitonic(self, length: int) -> None:
        """The (key, id) pairs sorted by a bitonic network."""
        self._run(self._program(BLOCK_SORT), length // BLOCK)
        k = 2 * BLOCK
        while k <= length:
            j = k // 2
            while j >= BLOCK:
                step = self._program(STEP)
                glsl.set_uniform(step, "u_k", k)
                glsl.set_uniform(step, "u_j", j)
                glsl.set_uniform(step, "u_length", length)
                self._run(step, length // 2 // STEP_GROUP)
                j //= 2
            merge = self._program(BLOCK_MERGE)
            glsl.set_uniform(merge, "u_k", k)
            self._run(merge, length // BLOCK)
            k *= 2

    def every(
        self,
        *,
        count: int,
        records: moderngl.Buffer,
        bounds: moderngl.Buffer,
        styles: moderngl.Buffer | None = None,
        focus: int = 0,
    ) -> None:
        """Every id in ascending order into `ids` (drawn in that order: the invisible ones draw
        nothing), `command` as `sort` makes it (the draw of `count` points in one variant; with
        `styles` and `focus`, the focus list's commands as `sort` writes them)."""
        self.dispatches = 0
        self._keys(count, records, bounds, np.eye(4), styles, None, exclude_focus=False)
        self._commands(count, focus if styles is not None else 0)

    def _commands(self, total: int, focus: int = 0) -> None:
        prog = self._program(COMMANDS)
        glsl.set_uniforms(prog, {"u_total": total, "u_focus": focus})
        self._run(prog, 1)
        sync.barrier(self.ctx, moderngl.COMMAND_BARRIER_BIT | moderngl.SHADER_STORAGE_BARRIER_BIT)

    def _keys(self, count, records, bounds, view, styles, offsets, exclude_focus: bool = True) -> int:
        """Stage 1: keys, ids and counts; returns the sort's length."""
        method = self.method_for(count)
        length = sort_length(count, method)
        self._ensure(length, method)
        self.command.write(np.zeros(COMMAND_WORDS, np.uint32))
        self.keys.bind_to_storage_buffer(Storage.SORT_KEYS)
        self.ids.bind_to_storage_buffer(Storage.DRAW_LIST)
        self.command.bind_to_storage_buffer(Storage.COMPOSITE_COMMAND)
        records.bind_to_storage_buffer(Storage.RECORDS)
        bounds.bind_to_storage_buffer(Storage.BOUNDS)
        if styles is not None:
            styles.bind_to_storage_buffer(Storage.STYLES)
        moved = self._upload_offsets(offsets)
        prog = self._program(KEYS, moved)
        uniforms = {
            "u_count": count,
            "u_length": length,
            "u_depth_row": tuple(np.asarray(view, np.float64)[2].tolist()),
            "u_focus_flags": styles is not None,
            "u_exclude_focus": styles is not None and exclude_focus,
            "u_upsample_below": UPSAMPLE_BELOW,
        }
        glsl.set_uniforms(prog, uniforms)
        self._run(prog, length // STEP_GROUP)
        return length

    def _run(self, prog: moderngl.ComputeShader, groups: int) -> None:
        if self.dispatches and self._wait:
            self.ctx.memory_barrier(moderngl.SHADER_STORAGE_BARRIER_BIT)
        prog.run(group_x=groups)
        self.dispatches += 1

    def read(self) -> np.ndarray:
        """The ids to draw, in order (reads back and waits: for tests and inspection)."""
        count = int(np.frombuffer(self.command.read(4, offset=4 * DRAWN), np.uint32)[0])
        return np.frombuffer(self.ids.read(4 * count), np.int32).copy() if count else np.zeros(0, np.int32)

    def release(self) -> None:
        bufs = [self.keys, self.ids, self.keys_out, self.ids_out, self.counts, self.command, self.offsets]
        for obj in [*self.programs.values(), *bufs]:
            obj.release()
        self.programs.clear()
