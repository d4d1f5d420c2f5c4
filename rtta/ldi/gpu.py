"""GPU volumetric parity tests: an LDI (plain texture array or compressed 2D texture) on the
GPU, bound for any shader that includes `ldi.glsl`, and `ParityTest` classifying points."""

from __future__ import annotations

import time

import moderngl
import numpy as np

from ..gl import glraw, glsl
from ..gl.bindings import Image, Texture
from ..gl.glsl import mat_bytes
from ..gl.targets import release_all
from .pack import CompressedLDI, compress
from .peel import NIL, LayeredDepthImage

POINTS_WIDTH = 2048
LOCAL_SIZE = 256  # ldi_classify.comp's local_size_x (injected); divides POINTS_WIDTH


def texel_major(layers: np.ndarray, max_width: int) -> tuple[np.ndarray, int]:
    """The layers [d, h, w] as one float32 image in which each crop texel's d layers are
    consecutive (ldi.glsl), and per_row, the crop texels per image row: the crop width when
    w * d fits `max_width`, else as many as fit, each crop row then taking k image rows."""
    d, h, w = layers.shape
    depth = max(d, 1)
    per_row = max(1, min(max(w, 1), max_width // depth))
    k = -(-max(w, 1) // per_row)
    image = np.full((max(h, 1), k * per_row, depth), NIL, np.float32)
    image[:h, :w, :d] = np.moveaxis(layers, 0, -1)
    return image.reshape(max(h, 1) * k, per_row * depth), per_row


class LdiTextures:
    """The plain layers (R32F, texel-major, read as an image) and the compressed ranges
    (RG32UI) of one LDI."""

    def __init__(
        self,
        ctx: moderngl.Context,
        ldi: LayeredDepthImage,
        packed: CompressedLDI | None = None,
        max_width: int | None = None,
    ) -> None:
        """`max_width`: the layers image's width limit (default: the driver's)."""
        self.ldi = ldi
        self.packed = packed or compress(ldi)
        image, self.per_row = texel_major(ldi.layers, max_width or ctx.info["GL_MAX_TEXTURE_SIZE"])
        self.layers = ctx.texture(image.shape[::-1], 1, image.tobytes(), dtype="f4")
        rows, width, _ = self.packed.data.shape
        self.ranges = ctx.texture((width, rows), 2, self.packed.data.tobytes(), dtype="u4")
        for t in (self.layers, self.ranges):
            t.filter = moderngl.NEAREST, moderngl.NEAREST

    def bind(
        self,
        prog: moderngl.Program | moderngl.ComputeShader,
        to_world: np.ndarray,
        *,
        packed_unit: int,
        prefix: str = "u_",
    ) -> None:
        """Bind the layers (Image.LDI_LAYERS, ldi.glsl) and the ranges (texture unit `packed_unit`),
        and set <prefix>to_crop (point space -> crop space, for `to_world`: point -> world),
        crop_size, depth and per_row, where the program uses them."""
        self.layers.bind_to_image(Image.LDI_LAYERS, read=True, write=False)
        self.ranges.use(packed_unit)
        if f"{prefix}to_crop" in prog:
            glsl.uniform(prog, f"{prefix}to_crop").write(mat_bytes(self.ldi.crop_matrix @ to_world))
        for name, value in (
            ("crop_size", tuple(self.ldi.crop[2:])),
            ("depth", self.ldi.depth),
            ("per_row", self.per_row),
        ):
            if prefix + name in prog:
                glsl.uniform(prog, prefix + name).value = value

    def release(self) -> None:
        self.layers.release()
        self.ranges.release()


class ParityTest:
    """`classify(points, compressed=False)` -> bool [N], one compute invocation per point."""

    def __init__(
        self,
        ctx: moderngl.Context,
        ldi: LayeredDepthImage,
        packed: CompressedLDI | None = None,
        max_width: int | None = None,
    ) -> None:
        self.ctx = ctx
        self.textures = LdiTextures(ctx, ldi, packed, max_width)
        self._programs: dict[bool, moderngl.ComputeShader] = {}
        self._rows = 0
        self._parts: list = []
        self.last_ms: dict[str, float] = {}

    def _program(self, compressed: bool) -> moderngl.ComputeShader:
        if compressed not in self._programs:
            source = glsl.load(
                "ldi_classify.comp",
                COMPRESSED=compressed,
                LOCAL_SIZE=LOCAL_SIZE,
                LDI_DEPTH=max(1, self.textures.ldi.depth),
            )
            self._programs[compressed] = self.ctx.compute_shader(source)
        return self._programs[compressed]

    def _targets(self, rows: int) -> None:
        if rows <= self._rows:
            return
        self._release_targets()
        self._points_buffer = self.ctx.buffer(reserve=rows * POINTS_WIDTH * 12)
        self.points = glraw.BufferTexture(self._points_buffer.glo)
        self.inside = self.ctx.texture((POINTS_WIDTH, rows), 1, dtype="u1")
        self.inside.filter = moderngl.NEAREST, moderngl.NEAREST
        self._parts = [self.points, self._points_buffer, self.inside]
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
        center = np.linalg.solve(m, 0.5 - ldi.matrix[:3, 3])  # world point at T = 0.5
        if np.abs(center).max() <= 64.0 / np.linalg.norm(m, axis=1).min():
            center = np.zeros(3)
        shift = np.eye(4)
        shift[:3, 3] = center
        rows = -(-n // POINTS_WIDTH)
        self._targets(rows)
        self.points.write_points(points - center if center.any() else points, rows * POINTS_WIDTH)
        t1 = time.perf_counter()
        prog = self._program(compressed)
        self.textures.bind(prog, shift, packed_unit=Texture.LDI_RANGES)
        self.points.use(Texture.LDI_POINTS)
        self.inside.bind_to_image(Image.LDI_INSIDE, read=False, write=True)
        prog.run(POINTS_WIDTH // LOCAL_SIZE, rows)
        self.ctx.finish()
        t2 = time.perf_counter()
        raw = self.inside.read()
        out = np.frombuffer(raw, np.uint8)[:n] != 0
        self.last_ms = {"upload": (t1 - t0) * 1e3, "test": (t2 - t1) * 1e3, "read": (time.perf_counter() - t2) * 1e3}
        return out

    def _release_targets(self) -> None:
        release_all(self.ctx, self._parts)
        self._parts, self._rows = [], 0

    def release(self) -> None:
        self._release_targets()
        for obj in self._programs.values():
            obj.release()
        self._programs.clear()
        self.textures.release()
