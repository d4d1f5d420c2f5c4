"""Layered render targets: colour, normal, id and depth 2D texture arrays in one framebuffer.

The atlas uses `LayeredTarget.ensure` each frame; it grows at once when the packing needs
more, and shrinks only after the need has stayed well below the allocation for a number of
frames (the paper's lazy update), so textures are reused, never reallocated per frame.
"""

from __future__ import annotations

import moderngl
import numpy as np

from ..errors import RttaError
from ..scene.files import memory_limit
from . import glraw

SHRINK_AFTER_FRAMES = 60
MIN_TARGET_BYTES = 512 * 2**20  # render targets may always take this much, whatever the scene limit
MAX_TEXEL_BYTES = 24  # a LayeredTarget texel with normals and a stencil (texel_bytes' largest)


def release_framebuffer(ctx: moderngl.Context, fbo) -> None:
    """Release `fbo` after binding the default framebuffer: moderngl rebinds the framebuffer
    it used last, and binding a deleted one is a GL error."""
    ctx.detect_framebuffer(0).use()
    fbo.release()


def release_all(ctx: moderngl.Context, parts) -> None:
    """Release GL objects, framebuffers the safe way (see release_framebuffer)."""
    for p in parts:
        if isinstance(p, moderngl.Framebuffer):
            release_framebuffer(ctx, p)
        else:
            p.release()


def decode_normals(texels: np.ndarray) -> np.ndarray:
    """RGBA8 normal texels -> float32 view-space normals [..., 3] (as the shaders decode them)."""
    return texels[..., :3].astype(np.float32) / 255.0 * 2.0 - 1.0


def _target_budget() -> int:
    """Bytes the render targets may take: half of RTTA_MEMORY_LIMIT_MB, and always MIN_TARGET_BYTES."""
    return max(memory_limit() // 2, MIN_TARGET_BYTES)


def round_up(v: int, step: int) -> int:
    return max(step, -(-v // step) * step)


class LayeredTarget:
    """Colour RGBA8, normal RGBA8 (view-space n * 0.5 + 0.5), id R32I (-1 = empty) and
    depth 32F, `layers` deep. Post-processing takes a texel's view distance from its depth.

    `normals=False` (STD and RTT targets): no normal image; nothing reads one there, and on
    llvmpipe writing it costs about 15% of an STD frame (BENCHMARKS.md in git history).

    `depth_keyed` (the atlas): a texel is empty exactly where its depth is 1 (the far plane,
    which no drawn fragment passes), so `clear()` clears the depth alone and the other
    attachments of empty texels keep whatever an earlier frame left there; every reader
    tests the depth (the shaders) or gets masked arrays (`read`). On llvmpipe a standalone
    clear of a 3-layer 1024² atlas took 14.8 ms with colour, normal and id, 3.3 ms of the
    depth alone (inside a frame the difference is smaller: BENCHMARKS.md in git history).
    """

    # made by _make (after release(), gone until the next allocation)
    color: moderngl.TextureArray
    normal: moderngl.TextureArray | None  # None without normals
    ids: moderngl.TextureArray
    depth: glraw.DepthArray
    _fbo: moderngl.Framebuffer

    def __init__(
        self,
        ctx: moderngl.Context,
        size: tuple[int, int],
        layers: int = 1,
        depth_keyed: bool = False,
        normals: bool = True,
        stencil: bool = False,
    ) -> None:
        self.ctx = ctx
        self.depth_keyed = depth_keyed
        self.normals = normals
        self.stencil = stencil  # depth 32F + stencil 8 (section caps: rtta.passes.sections)
        self.normals_written = normals  # False after a capture that left the normal image alone
        self.ids_written = True  # False after a capture that left the id image alone
        self.size: tuple[int, int] = (0, 0)
        self.layers = 0
        self.allocations = 0
        self._small_frames = 0
        self._textures: list = []
        self._layers_within: tuple = (None, 0)  # (key, layers): layers_within's last answer
        self._allocate(size, layers)

    @property
    def texel_bytes(self) -> int:
        """Bytes per texel of every image: RGBA8 + RGBA8 (with normals) + R32I + D32F (+ S8)."""
        return 4 + 4 * self.normals + 4 + 4 + 4 * self.stencil

    def layers_within(self, size: tuple[int, int]) -> int:
        """The most layers of `size` (in `ensure`'s 64-texel steps, with normals and a stencil
        whether or not the target has them now) that the memory limit allows: Algorithm 1 scales
        regions down to fit in them rather than fail. It depends on `size` alone (worked out, and
        the limit read, when that changes): a bound that moved with sections or the allocation
        would make the viewer's frames size the atlas anew ("ahead" keys on it), and pictures
        differ by a texel's rounding."""
        if self._layers_within[0] != size:
            w, h = round_up(max(1, size[0]), 64), round_up(max(1, size[1]), 64)
            self._layers_within = size, max(1, _target_budget() // (w * h * MAX_TEXEL_BYTES))
        return self._layers_within[1]

    def _allocate(self, size: tuple[int, int], layers: int) -> None:
        """Textures of `size` x `layers`; an RttaError leaves the ones before (over the memory
        limit), or a 1x1 layer where the driver failed: the target stays usable either way."""
        w, h = max(1, int(size[0])), max(1, int(size[1]))
        n = max(1, int(layers))
        need = w * h * n * self.texel_bytes
        if need > _target_budget():
            raise RttaError(
                f"the render targets would need {w}x{h}x{n} texels ({need / 2**20:,.0f} MiB), over half "
                "the memory limit (RTTA_MEMORY_LIMIT_MB); use a smaller --size or --region-scale"
            )
        self._free()
        try:
            self._make(w, h, n)
        except moderngl.Error as exc:  # the driver could not allocate what it allows in principle
            self._free()
            self._make(1, 1, 1)
            raise RttaError(
                f"the driver cannot allocate {w}x{h}x{n} render targets ({need / 2**20:,.0f} MiB: "
                f"{str(exc).splitlines()[0][:80]}); use a smaller --size or --region-scale"
            ) from None

    def _make(self, w: int, h: int, n: int) -> None:
        ctx = self.ctx
        self.color = ctx.texture_array((w, h, n), 4, dtype="f1")
        self.normal = ctx.texture_array((w, h, n), 4, dtype="f1") if self.normals else None
        self.ids = ctx.texture_array((w, h, n), 1, dtype="i4")
        self._textures = [t for t in (self.color, self.normal, self.ids) if t is not None]
        for tex in self._textures:
            tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
        self.depth = glraw.DepthArray(w, h, n, self.stencil)
        self._fbo = ctx.framebuffer(color_attachments=self._textures)
        self._fbo.depth_mask = True
        self._fbo.use()
        self.depth.attach_to_bound_framebuffer()
        self.size, self.layers = (w, h), n
        self.allocations += 1

    def want_stencil(self, on: bool) -> None:
        """With a stencil (reallocated, contents lost, when that changes), or without."""
        if bool(on) != self.stencil:
            self.stencil = bool(on)
            self._allocate(self.size, self.layers)

    def ensure(self, size: tuple[int, int], layers: int) -> bool:
        """Make room for `size` x `layers`; returns True when textures were reallocated."""
        need_w, need_h, need_l = max(1, size[0]), max(1, size[1]), max(1, layers)
        w, h = self.size
        if need_w > w or need_h > h or need_l > self.layers:
            self._small_frames = 0
            size, n = (max(w, round_up(need_w, 64)), max(h, round_up(need_h, 64))), max(self.layers, need_l)
            if size[0] * size[1] * n * self.texel_bytes > _target_budget():  # grown over the limit: the fit alone
                size, n = (round_up(need_w, 64), round_up(need_h, 64)), need_l
            self._allocate(size, n)
            return True
        if need_w * need_h * need_l * 2 < w * h * self.layers:
            self._small_frames += 1
            if self._small_frames >= SHRINK_AFTER_FRAMES:
                return self.trim((need_w, need_h), need_l)
        else:
            self._small_frames = 0
        return False

    def trim(self, size: tuple[int, int], layers: int) -> bool:
        """Reallocate to just hold `size` x `layers` (64-texel steps) now, instead of after
        SHRINK_AFTER_FRAMES frames; returns True when textures were reallocated (contents lost)."""
        fit = (round_up(max(1, size[0]), 64), round_up(max(1, size[1]), 64)), max(1, layers)
        if fit == (self.size, self.layers):
            return False
        self._small_frames = 0
        self._allocate(*fit)
        return True

    @property
    def nbytes(self) -> int:
        """Texture memory: `texel_bytes` per texel."""
        return self.size[0] * self.size[1] * self.layers * self.texel_bytes

    def write_mask(self, normals: bool = True, ids: bool = True) -> None:
        """Whether draws write the normal and id images (colour masks; colour and depth are
        always written)."""
        masks = [(True,) * 4] + [(bool(normals),) * 4] * self.normals + [(bool(ids),) * 4]
        self._fbo.color_mask = masks  # pyright: ignore[reportAttributeAccessIssue]  (one per attachment: moderngl takes it)

    def color_writes(self, masks: bool | list) -> list:
        """Set the colour masks of every attachment (False: none written; or a list as this
        returns) and return the ones before."""
        before = list(self._fbo.color_mask)
        if isinstance(masks, bool):
            masks = [(masks,) * 4] * len(self._textures)
        self._fbo.color_mask = masks  # pyright: ignore[reportAttributeAccessIssue]  (as above)
        return before

    def bind(self, viewport: tuple[int, int, int, int] | None = None) -> None:
        """Bind for drawing, with the GL viewport set (default: the whole allocation)."""
        self._fbo.viewport = viewport or (0, 0, *self.size)
        self._fbo.use()

    def clear(self) -> None:
        """Clear every layer whole: depth 1 (far), and unless depth-keyed colour/normal 0,
        id -1. Unscissored on purpose: on llvmpipe any scissor makes layered clears ~2x
        slower (BENCHMARKS.md in git history)."""
        self._fbo.viewport = (0, 0, *self.size)
        self._fbo.scissor = None  # pyright: ignore[reportAttributeAccessIssue]  (none: moderngl takes it)
        self._fbo.use()
        if not self.depth_keyed:
            glraw.clear_color_float(0, (0.0, 0.0, 0.0, 0.0))
            if self.normals:
                glraw.clear_color_float(1, (0.0, 0.0, 0.0, 0.0))
            glraw.clear_color_int(len(self._textures) - 1, -1)
        if self.stencil:
            glraw.clear_depth_stencil(1.0, 0)
        else:
            glraw.clear_depth(1.0)

    def read(
        self, size: tuple[int, int] | None = None, layers: int | None = None, parts: tuple[str, ...] | None = None
    ) -> dict[str, np.ndarray]:
        """Layers as numpy [layers, H, W(, C)], cropped to `size`; row 0 is the bottom row;
        normals decoded to float32 xyz. `parts` picks which attachments are read (picking
        needs only id and depth; None: all there are, so no "normal" without normals or after
        a capture that wrote none).
        Empty texels (depth 1) read as colour 0, normal 0, id -1, depth-keyed or not."""
        w, h = self.size
        n = self.layers
        cw, ch = size or (w, h)
        cl = n if layers is None else max(1, layers)
        parts = parts or tuple(
            k
            for k, on in (("color", True), ("normal", self.normals_written), ("id", self.ids_written), ("depth", True))
            if on
        )
        self._check_readable(parts)
        normal = self.normal
        readers = {
            "color": lambda: np.frombuffer(self.color.read(), np.uint8).reshape(n, h, w, 4),
            "id": lambda: np.frombuffer(self.ids.read(), np.int32).reshape(n, h, w),
            "depth": self.depth.read,
        }
        if normal is not None:  # (else _check_readable refused "normal")
            readers["normal"] = lambda: decode_normals(np.frombuffer(normal.read(), np.uint8).reshape(n, h, w, 4))
        out = {k: np.array(readers[k]()[:cl, :ch, :cw]) for k in parts}
        if set(parts) - {"depth"}:
            empty = out["depth"] >= 1.0 if "depth" in out else readers["depth"]()[:cl, :ch, :cw] >= 1.0
            for k in set(parts) - {"depth"}:
                out[k][empty] = -1 if k == "id" else 0
        return out

    def texels(self, points: np.ndarray, ids: bool = True) -> dict[str, np.ndarray]:
        """'depth' (float32) and, with `ids`, 'id' (int32) at `points` [k, 3] (x, y, layer;
        row 0 at the bottom), each inside the target; an empty texel (depth 1) reads id -1,
        as in `read`."""
        self._check_readable(("id", "depth") if ids else ("depth",))
        points = np.asarray(points, np.int64).reshape(-1, 3)
        depth = glraw.read_texels(self.depth.glo, points, depth=True)
        if not ids:
            return {"depth": depth}
        found = glraw.read_texels(self.ids.glo, points, depth=False)
        found[depth >= 1.0] = -1
        return {"id": found, "depth": depth}

    def _check_readable(self, parts) -> None:
        """ValueError for a part this target lacks or the last capture left unwritten."""
        if "normal" in parts and not self.normals:
            raise ValueError("this target has no normal image (normals=False)")
        if "normal" in parts and not self.normals_written:
            raise ValueError("the last capture wrote no normal image (capture with normals=True)")
        if "id" in parts and not self.ids_written:
            raise ValueError("the last capture wrote no id image (capture with ids=True)")

    def _free(self) -> None:
        if hasattr(self, "_fbo"):
            release_framebuffer(self.ctx, self._fbo)
            del self._fbo
        for tex in self._textures:
            tex.release()
        self._textures = []
        if hasattr(self, "depth"):
            self.depth.release()
            del self.depth

    def release(self) -> None:
        self._free()


class CompositeTarget:
    """RGBA8 colour + 32-bit float depth of the composite. `viewport` is the part in use;
    the allocation (`size`) grows in steps of 64 and shrinks only after SHRINK_AFTER_FRAMES
    frames of needing less than half, so resizing a window does not reallocate per frame."""

    # made by ensure() (after release(), gone until the next)
    color: moderngl.Texture
    depth: moderngl.Texture
    fbo: moderngl.Framebuffer

    def __init__(self, ctx: moderngl.Context) -> None:
        self.ctx = ctx
        self.size: tuple[int, int] = (0, 0)
        self.viewport: tuple[int, int] = (0, 0)
        self._parts: list = []
        self._small_frames = 0

    def ensure(self, viewport: tuple[int, int]) -> None:
        vw, vh = max(1, int(viewport[0])), max(1, int(viewport[1]))
        w, h = self.size
        self.viewport = (vw, vh)
        if vw > w or vh > h:
            self._allocate((max(w, round_up(vw, 64)), max(h, round_up(vh, 64))))
        elif 2 * vw * vh < w * h:
            self._small_frames += 1
            if self._small_frames >= SHRINK_AFTER_FRAMES:
                self.trim()
        else:
            self._small_frames = 0
        self.fbo.viewport = (0, 0, vw, vh)

    def trim(self) -> None:
        """Reallocate to just hold the current viewport (64-pixel steps) now (contents lost)."""
        fit = (round_up(self.viewport[0], 64), round_up(self.viewport[1], 64))
        if self._parts and fit != self.size:
            self._allocate(fit)

    def _allocate(self, size: tuple[int, int]) -> None:
        viewport = self.viewport
        self.release()
        self.color = self.ctx.texture(size, 4)
        self.depth = self.ctx.depth_texture(size)
        self.fbo = self.ctx.framebuffer([self.color], self.depth)
        self._parts = [self.color, self.depth]
        self.size, self.viewport, self._small_frames = (int(size[0]), int(size[1])), viewport, 0

    @property
    def nbytes(self) -> int:
        return self.size[0] * self.size[1] * (4 + 4)

    @property
    def extent(self) -> tuple[float, float]:
        """The used part as a fraction of the texture (for drawing `color` to a screen)."""
        return self.viewport[0] / self.size[0], self.viewport[1] / self.size[1]

    def read(self) -> tuple[np.ndarray, np.ndarray]:
        """(rgba uint8 [H, W, 4], depth float32 [H, W]) of the viewport; row 0 is the bottom row.
        The depth is the sprites' (1 where none); in the ghosted modes it is 0 under the focus
        outlines, which are drawn at depth 0 so that nothing composited after covers them."""
        w, h = self.size
        vw, vh = self.viewport
        rgba = np.frombuffer(self.fbo.read(viewport=(0, 0, vw, vh), components=4), np.uint8).reshape(vh, vw, 4)
        depth = np.frombuffer(self.depth.read(), np.float32).reshape(h, w)[:vh, :vw]
        return rgba, np.ascontiguousarray(depth)

    def release(self) -> None:
        if self._parts:
            release_framebuffer(self.ctx, self.fbo)
            del self.fbo
        for obj in self._parts:
            obj.release()
        self._parts = []
        self.size = (0, 0)
