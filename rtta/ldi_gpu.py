"""GPU volumetric parity tests: an LDI (plain texture array or compressed 2D texture) on the
GPU, bound for any shader that includes `ldi.glsl`, and `ParityTest` classifying points."""

from __future__ import annotations

import time

import moderngl
import numpy as np

from . import glsl
from .ldi import LayeredDepthImage
from .ldi_pack import CompressedLDI, compress
from .passes import mat_bytes
from .targets import release_all

POINTS_WIDTH = 2048
LOCAL_SIZE = 256      # ldi_classify.comp's local_size_x (injected); divides POINTS_WIDTH


class LdiTextures:
    """The plain layers (R32F array, read as an image) and the compressed ranges (RG32UI)
    of one LDI."""

    def __init__(self, ctx: moderngl.Context, ldi: LayeredDepthImage, packed: CompressedLDI | None = None) -> None:
        self.ldi = ldi
        self.packed = packed or compress(ldi)
        d, h, w = ldi.layers.shape
        self.layers = ctx.texture_array((max(w, 1), max(h, 1), max(d, 1)), 1, dtype="f4")
        if d and w and h:
            self.layers.write(np.ascontiguousarray(ldi.layers).tobytes())
        rows, width, _ = self.packed.data.shape
        self.ranges = ctx.texture((width, rows), 2, self.packed.data.tobytes(), dtype="u4")
        for t in (self.layers, self.ranges):
            t.filter = moderngl.NEAREST, moderngl.NEAREST

    def bind(self, prog: moderngl.Program, to_world: np.ndarray, *, packed_unit: int, prefix: str = "u_") -> None:
        """Bind the layers (image unit 0, ldi.glsl) and the ranges (texture unit `packed_unit`),
        and set <prefix>to_crop (point space -> crop space, for `to_world`: point -> world),
        crop_size and depth, where the program uses them."""
        self.layers.bind_to_image(0, read=True, write=False)
        self.ranges.use(packed_unit)
        if f"{prefix}to_crop" in prog:
            prog[f"{prefix}to_crop"].write(mat_bytes(self.ldi.crop_matrix @ to_world))
        for name, value in (("crop_size", tuple(self.ldi.crop[2:])), ("depth", self.ldi.depth)):
            if prefix + name in prog:
                prog[prefix + name].value = value

    def release(self) -> None:
        self.layers.release()
        self.ranges.release()


class ParityTest:
    """`classify(points, compressed=False)` -> bool [N], one compute invocation per point."""

    def __init__(self, ctx: moderngl.Context, ldi: LayeredDepthImage, packed: CompressedLDI | None = None) -> None:
        self.ctx = ctx
        self.textures = LdiTextures(ctx, ldi, packed)
        self._programs: dict[bool, moderngl.ComputeShader] = {}
        self._rows = 0
        self._parts: list = []
        self._staging = None
        self.last_ms: dict[str, float] = {}

    def _program(self, compressed: bool) -> moderngl.ComputeShader:
        if compressed not in self._programs:
            source = glsl.load("ldi_classify.comp", COMPRESSED=compressed, LOCAL_SIZE=LOCAL_SIZE)
            self._programs[compressed] = self.ctx.compute_shader(source)
        return self._programs[compressed]

    def _targets(self, rows: int) -> None:
        if rows <= self._rows:
            return
        self._release_targets()
        self.points = self.ctx.texture((POINTS_WIDTH, rows), 3, dtype="f4")
        self.inside = self.ctx.texture((POINTS_WIDTH, rows), 1, dtype="u1")
        for t in (self.points, self.inside):
            t.filter = moderngl.NEAREST, moderngl.NEAREST
        self._staging = np.empty((rows * POINTS_WIDTH, 3), np.float32)   # reused: no page faults per call
        self._parts = [self.points, self.inside]
        self._rows = rows

    def classify(self, points: np.ndarray, compressed: bool = False) -> np.ndarray:
        """Inside (bool [N]) for world points [N, 3]. When the LDI lies far from the world
        origin (over 64 box sizes), points are centred on it in float64 before going to float32,
        so they keep their precision; otherwise they go as they are (faster)."""
        points = np.asarray(points).reshape(-1, 3)
        n = len(points)
        if n == 0:
            return np.zeros(0, bool)
        t0 = time.perf_counter()
        ldi = self.textures.ldi
        m = ldi.matrix[:3, :3]
        center = np.linalg.solve(m, 0.5 - ldi.matrix[:3, 3])          # world point at T = 0.5
        if np.abs(center).max() <= 64.0 / np.linalg.norm(m, axis=1).min():
            center = np.zeros(3)
        shift = np.eye(4)
        shift[:3, 3] = center
        rows = -(-n // POINTS_WIDTH)
        self._targets(rows)
        data = self._staging[:rows * POINTS_WIDTH]
        data[:n] = points - center if center.any() else points
        data[n:] = 0.0
        self.points.write(data, viewport=(0, 0, POINTS_WIDTH, rows))
        t1 = time.perf_counter()
        prog = self._program(compressed)
        self.textures.bind(prog, shift, packed_unit=2)
        self.points.use(0)
        self.inside.bind_to_image(1, read=False, write=True)
        prog.run(POINTS_WIDTH // LOCAL_SIZE, rows)
        self.ctx.finish()
        t2 = time.perf_counter()
        raw = self.inside.read()
        out = np.frombuffer(raw, np.uint8)[:n] != 0
        self.last_ms = {"upload": (t1 - t0) * 1e3, "test": (t2 - t1) * 1e3,
                        "read": (time.perf_counter() - t2) * 1e3}
        return out

    def _release_targets(self) -> None:
        release_all(self.ctx, self._parts)
        self._parts, self._rows, self._staging = [], 0, None

    def release(self) -> None:
        self._release_targets()
        for obj in self._programs.values():
            obj.release()
        self._programs.clear()
        self.textures.release()
