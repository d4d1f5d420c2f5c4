"""`AtlasPostPass`: ambient occlusion and edge strength per atlas texel, computed on each
object's own unoccluded images (the `ghosted-ao` mode only).

One draw of one quad per visible object over its atlas rectangle. Texels outside every
rectangle are never shaded (compositing reads only the objects' own texels), and no
fragment reads an id or the record buffer. The quads lie at depth 1 and are tested
against the atlas depth, so the empty texels inside the rectangles are not shaded either
(on the demo at 1024² the rectangles hold 1.8 times the objects' texels): llvmpipe rejects
them before shading, where a branch in the shader would still run them (masked lanes cost
as much as live ones). AO takes 8 samples per 2x2 quad of texels, 2 per texel, summed over
the quad through derivatives; with edge width 1 (EDGE_QUAD) the neighbour in the quad comes
from derivatives too."""

from __future__ import annotations

import dataclasses

import moderngl
import numpy as np

from ..atlas.parameterize import Records
from ..gl import glraw, glsl
from ..gl.bindings import Storage, Texture
from ..gl.gpu import GpuScene
from ..gl.targets import LayeredTarget, release_framebuffer
from .style import Role, Style, choice

EVERY = "every"  # a list of every object (post.geom skips those with no region)
STAGES = {"vertex_shader": "post.vert", "geometry_shader": "post.geom", "fragment_shader": "post.frag"}


class _LayerTarget:
    """One texture array with its framebuffer, which tests against the depth of a target of
    the same shape (the atlas); reallocated only when the shape changes or that target
    reallocated its textures."""

    def __init__(self, ctx: moderngl.Context, components: int, dtype: str) -> None:
        self.ctx = ctx
        self.components, self.dtype = components, dtype
        self.texture: moderngl.TextureArray | None = None
        self.fbo: moderngl.Framebuffer | None = None
        self.shape: tuple[int, int, int] | None = None
        self._key: tuple | None = None

    def ensure(self, shape: tuple[int, int, int], depth_of: LayeredTarget) -> None:
        key = (shape, id(depth_of), depth_of.allocations)
        if key != self._key:
            self.release()
            self.texture = texture = self.ctx.texture_array(shape, self.components, dtype=self.dtype)
            texture.filter = (moderngl.NEAREST, moderngl.NEAREST)
            self.fbo = fbo = self.ctx.framebuffer([texture])
            fbo.use()
            depth_of.depth.attach_to_bound_framebuffer()
            self.shape, self._key = shape, key

    @property
    def nbytes(self) -> int:
        size = self.components * int(self.dtype[1])
        return 0 if self.shape is None else self.shape[0] * self.shape[1] * self.shape[2] * size

    def release(self) -> None:
        if self.fbo is not None:
            release_framebuffer(self.ctx, self.fbo)
        if self.texture is not None:
            self.texture.release()
        self.texture = self.fbo = self.shape = self._key = None


class AtlasPostPass:
    """render(*, atlas, records, gpu, proj, style, full, edges) -> `texture`, an RGBA8
    texture array (ao, edge) shaped like the atlas, written on the texels of the visible
    objects listed: `full` get AO and edges, `edges` edges only (AO 1). Other texels keep
    what they held, so a caller can shade objects a few at a time (a focus change)."""

    def __init__(self, ctx: moderngl.Context) -> None:
        self.ctx = ctx
        self._variants: dict[tuple[str, ...], tuple] = {}  # defines -> (program, vao)
        self._out = _LayerTarget(ctx, 4, "f1")  # (ao, edge)
        self._list = ctx.buffer(reserve=16)  # the ids to shade
        self._every = ctx.buffer(reserve=4)  # ids 0..n-1 (EVERY)
        self._every_n = -1
        self._shaded_for: tuple | None = None  # (capture, AO and edge parameters) of `_done`
        self._style_done: Style | None = None  # the roles (focus, AO, edges) shaded for this capture
        self._n = -1  # objects of the capture shaded
        self._done: np.ndarray | None = None  # per object: 0 nothing, 1 edges, 2 AO + edges (made on a focus change)

    @property
    def texture(self):
        return self._out.texture

    @property
    def nbytes(self) -> int:
        return self._out.nbytes

    def _variant(self, *defines: str) -> tuple:
        """(program, vao) compiled on first use; each stage gets the defines it declares."""
        if defines not in self._variants:
            prog = glsl.program(self.ctx, **glsl.stage_sources(STAGES, **{d: True for d in defines}))
            self._variants[defines] = (prog, self.ctx.vertex_array(prog, []))
        return self._variants[defines]

    def shade(self, *, atlas: LayeredTarget, records, gpu: GpuScene, proj: np.ndarray, style, capture: int) -> bool:
        """AO and edges cached per object: they depend on the capture (`capture` counts them)
        and the AO/edge parameters, not on focus or opacity, so a focus change shades only the
        objects whose role now asks for more (--ao-objects focus). A new capture is shaded from
        the roles alone (every object through a list kept on the GPU, or the focus), with no
        work over the objects on the CPU and no read of R. Whether it rendered."""
        key = (capture, style.ao_radius, style.ao_strength, style.edge_width)
        n = gpu.scene.count
        kw = {"atlas": atlas, "records": records, "gpu": gpu, "proj": proj, "style": style}
        done = self._style_done
        if key != self._shaded_for or self._n != n or done is None:  # a new capture
            self._shaded_for, self._n, self._done = key, n, None
            self._style_done = dataclasses.replace(style, focus=frozenset(style.focus))
            self.render(**kw, **_first_lists(style, n))
            return True
        if _roles(style) == _roles(done) and self.texture is not None:
            return False
        if self._done is None:  # what the capture's first shading did
            self._done = _need(done, n)
        self._style_done = dataclasses.replace(style, focus=frozenset(style.focus))
        need = _need(style, n)
        full = np.flatnonzero((need == 2) & (self._done < 2))
        edge_only = np.flatnonzero((need == 1) & (self._done < 1))
        if not (len(full) or len(edge_only) or self.texture is None):
            return False
        self.render(**kw, full=full, edges=edge_only)
        self._done = np.maximum(self._done, need)
        return True

    def render(
        self, *, atlas: LayeredTarget, records: Records, gpu: GpuScene, proj: np.ndarray, style, full=None, edges=()
    ) -> None:
        """Shade `full` (AO and edges; None: every object) and `edges` (edges only), each an
        array of ids or EVERY. Edges are drawn first, so EVERY's edges and the focus's AO make
        the focus shaded in full."""
        w, h = atlas.size
        self._out.ensure((w, h, atlas.layers), atlas)
        tw, th, td = records.atlas_size
        n = gpu.scene.count
        full = EVERY if full is None else full
        if td == 0 or n == 0:
            return
        gpu.bind_storage()
        glraw.bind_texture_array(Texture.ATLAS_DEPTH, atlas.depth.glo)
        if atlas.normal is None:
            raise ValueError("AO and edges read the atlas normals: an atlas made with normals=False has none")
        atlas.normal.use(Texture.ATLAS_NORMAL)
        quad = ("EDGE_QUAD",) if int(style.edge_width) == 1 else ()
        # post.geom skips the objects with no region: R left on the GPU is not read to list them
        listed = not getattr(records, "on_gpu", False) or getattr(records, "is_read", True)
        for ids, defines in ((edges, (*quad, "EDGES_ONLY")), (full, quad)):
            if isinstance(ids, str):
                self._draw(self._every_list(n), n, defines, records, proj, style)
                continue
            ids = np.asarray(ids, np.int64)
            ids = ids[records.visible[ids]] if len(ids) and listed else ids
            if len(ids):
                self._draw(self._upload(ids), len(ids), defines, records, proj, style)

    def _every_list(self, n: int) -> moderngl.Buffer:
        """Ids 0..n-1 on the GPU, written once per n."""
        if self._every_n != n:
            self._every.orphan(4 * max(n, 1))
            self._every.write(np.arange(n, dtype=np.int32).tobytes())
            self._every_n = n
        return self._every

    def _upload(self, ids: np.ndarray) -> moderngl.Buffer:
        data = ids.astype(np.int32).tobytes()
        if self._list.size < len(data):
            self._list.orphan(max(len(data), 2 * self._list.size))
        self._list.write(data)
        return self._list

    def _draw(self, ids: moderngl.Buffer, count: int, defines: tuple, records: Records, proj, style) -> None:
        tw, th, _ = records.atlas_size
        ids.bind_to_storage_buffer(Storage.DRAW_LIST)
        prog, vao = self._variant(*defines)
        uniforms = {
            "u_proj": (float(proj[0, 0]), float(proj[1, 1]), float(proj[2, 2]), float(proj[2, 3])),
            "u_proj_w": (float(proj[3, 2]), float(proj[3, 3])),
            "u_viewport": tuple(float(v) for v in records.viewport),
            "u_target": (float(tw), float(th)),
            "u_ao_radius": float(style.ao_radius),
            "u_ao_strength": float(style.ao_strength),
            "u_edge_width": int(style.edge_width),
        }
        glsl.set_uniforms(prog, uniforms)  # those the variant holds, and changed since its last draw
        # quads at depth 1 pass only where the capture wrote the object (depth < 1):
        # empty texels of the rectangles are never shaded nor written
        self.ctx.enable_only(moderngl.DEPTH_TEST)
        self.ctx.depth_func = ">"
        fbo = self._out.fbo
        assert fbo is not None, "made by render's ensure()"
        fbo.depth_mask = False
        fbo.viewport = (0, 0, tw, th)
        fbo.use()
        vao.render(moderngl.POINTS, vertices=count)
        self.ctx.depth_func = "<"
        self.ctx.enable_only(moderngl.NOTHING)

    def release(self) -> None:
        self._out.release()
        self._list.release()
        self._every.release()
        for prog, vao in self._variants.values():
            vao.release()
            prog.release()
        self._variants.clear()


def _roles(style: Style) -> tuple:
    """What of `style` decides which objects get AO and edges."""
    return frozenset(style.focus), str(style.ao_objects), str(style.edge_objects)


def _need(style: Style, n: int) -> np.ndarray:
    """Per object what `style` asks of the post-process: 0 nothing, 1 edges, 2 AO and edges."""
    ao, edges = style.shaded(n)
    return np.where(ao, 2, np.where(edges, 1, 0)).astype(np.int8)


def _first_lists(style: Style, n: int) -> dict:
    """`render`'s lists for a capture shaded for the first time: EVERY or the focus ids."""
    ao, edges = (choice(Role, getattr(style, name), name) for name in ("ao_objects", "edge_objects"))
    if ao is Role.ALL:
        return {"full": EVERY, "edges": ()}
    focus = np.array(sorted(o for o in style.focus if 0 <= o < n), np.int64)
    return {"full": focus, "edges": EVERY if edges is Role.ALL else ()}
