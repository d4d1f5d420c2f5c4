"""Layered depth images of closed meshes (seed 003, Trapp & Döllner 2008) for volumetric tests.

A mesh is depth-peeled with an orthographic camera into layers of linear depth
(`LayeredDepthImage.layers`, float32 [d, h, w], NIL after a texel's last surface). The
depth complexity d is found by peeling until a pass writes no fragment (occlusion query).
The viewing direction is chosen by the seed's viewpoint selection (directions sampled on the
sphere; minimal depth complexity first, then maximal coverage), and the layers are cropped
to the AABB of layer 0. A point is inside when an odd number of layers lie in front of it
(the volumetric parity test; `ldi_pack` compresses, `ldi_gpu` tests on the GPU).

Texture space: s, t in [0, 1) across the padded box seen by the camera, r in [0, 1] the
linear depth (0 nearest). Texel (i, j) holds the surfaces met by the ray through its centre.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import moderngl
import numpy as np

from ..errors import RttaError
from ..gl import glraw, glsl
from ..gl.bindings import Texture
from ..gl.glsl import mat_bytes
from ..gl.targets import release_all

NIL = 4.0  # depth of "no surface" (> every linear depth in [0, 1])
MAX_LAYERS = 256  # a closed mesh needing more is refused, not peeled forever
_NDC = np.array([[2.0, 0, 0, -1], [0, 2.0, 0, -1], [0, 0, 2.0, -1], [0, 0, 0, 1]])


def closed_mesh(vertices, faces, name: str = "mesh") -> tuple[np.ndarray, np.ndarray]:
    """(vertices float64, faces int) of a closed mesh; RttaError for an open one, since the
    parity test has no defined answer where a ray can leave through a hole."""
    import trimesh

    v = np.asarray(vertices, np.float64)
    center = (v.min(axis=0) + v.max(axis=0)) / 2 if len(v) else np.zeros(3)
    extent = float(np.ptp(v, axis=0).max()) if len(v) else 0.0
    extent = extent if extent > 0 and np.isfinite(extent) else 1.0
    # trimesh merges vertices to a fixed number of decimals: judge the topology at unit size,
    # so a closed mesh at 1e-30 or 1e12 units is as closed as at 1
    with np.errstate(all="ignore"):
        mesh = trimesh.Trimesh((v - center) / extent, np.asarray(faces, np.int64), process=True)
        mesh.merge_vertices()
    if len(mesh.faces) == 0:
        raise RttaError("has no triangles", name)
    if not mesh.is_watertight:
        _, uses = np.unique(mesh.edges_sorted, axis=0, return_counts=True)
        raise RttaError(
            f"is not a closed mesh ({int((uses == 1).sum())} open edges, {int((uses > 2).sum())} "
            "shared by more than two triangles); the parity test needs a closed surface",
            name,
        )
    return np.asarray(mesh.vertices) * extent + center, np.asarray(mesh.faces)


def look_rotation(direction) -> np.ndarray:
    """Rows (s, t, r) of an orthonormal frame whose r axis is `direction` (the view direction)."""
    r = np.asarray(direction, np.float64)
    r = r / np.linalg.norm(r)
    helper = np.array([0.0, 1.0, 0.0]) if abs(r[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
    s = np.cross(helper, r)
    s /= np.linalg.norm(s)
    return np.stack([s, np.cross(r, s), r])


def to_texture(rotation: np.ndarray, vertices: np.ndarray, resolution: int) -> np.ndarray:
    """World -> texture space (4x4) for a view along rotation[2]: the rotated AABB padded by one
    texel in s and t (silhouettes are sampled) and 1% in r (no fragment clipped)."""
    local = vertices @ rotation.T
    lo, hi = local.min(axis=0), local.max(axis=0)
    extent = np.maximum(hi - lo, 1e-9 * max(float((hi - lo).max()), 1e-300))  # flat sides: scale-free floor
    pad = np.array([extent[0] / max(resolution - 2, 1), extent[1] / max(resolution - 2, 1), extent[2] * 0.01])
    lo, hi = lo - pad, hi + pad
    m = np.eye(4)
    m[:3, :3] = rotation / (hi - lo)[:, None]
    m[:3, 3] = -lo / (hi - lo)
    return m


@dataclass
class LayeredDepthImage:
    """Cropped LDI: `layers` [d, h, w] of linear depth (NIL where a texel has no more surfaces),
    `crop` (s0, t0, w, h) in texels of the `size` (N, N) image, `matrix` world -> texture space."""

    layers: np.ndarray
    size: tuple[int, int]
    crop: tuple[int, int, int, int]
    matrix: np.ndarray
    direction: np.ndarray
    timings: dict[str, float] = field(default_factory=dict)  # ms: view, peel, crop
    complexity: tuple[int, int] = (0, 0)  # (d_min, d_max) over the viewpoints tried

    @property
    def depth(self) -> int:
        return int(self.layers.shape[0])

    @property
    def crop_matrix(self) -> np.ndarray:
        """World -> crop space: texels of the crop in x and y (the texel is the floor), linear
        depth in z. A point is in the LDI's box when 0 <= x < w, 0 <= y < h, 0 <= z < 1."""
        s = np.diag([float(self.size[0]), float(self.size[1]), 1.0, 1.0])
        s[0, 3], s[1, 3] = -self.crop[0], -self.crop[1]
        return s @ self.matrix

    @property
    def texel_size(self) -> np.ndarray:
        """World size of one texel along s and t (a volumetric test is exact up to this)."""
        return 1.0 / (np.linalg.norm(self.matrix[:2, :3], axis=1) * np.array(self.size))

    @property
    def nbytes(self) -> int:
        """Memory of the cropped float layers (the seed's M_crop)."""
        return int(self.layers.size * 4)


class Peeler:
    """Orthographic depth peeling and depth-complexity counting of the mesh last `load`ed (it
    is uploaded once, however many directions are tried); owns its programs and (reused)
    render targets."""

    def __init__(self, ctx: moderngl.Context) -> None:
        self.ctx = ctx
        vert = glsl.load("ldi.vert")
        self.peel_prog = glsl.program(ctx, vertex_shader=vert, fragment_shader=glsl.load("ldi_peel.frag"))
        self.count_prog = glsl.program(ctx, vertex_shader=vert, fragment_shader=glsl.load("ldi_peel.frag", COUNT=True))
        self.query = glraw.SamplesQuery()
        self.vertices = np.zeros((0, 3))
        self._size = None
        self._parts: list = []
        self._mesh: list = []

    def load(self, vertices, faces) -> None:
        """Upload the mesh every later count() and peel() draws (vertices as float32)."""
        release_all(self.ctx, self._mesh)
        self.vertices = np.asarray(vertices, np.float64)
        vbo = self.ctx.buffer(np.asarray(vertices, np.float32).tobytes())
        ibo = self.ctx.buffer(np.asarray(faces, np.uint32).tobytes())
        self._vaos = {
            prog.glo: self.ctx.vertex_array(prog, [(vbo, "3f", "in_position")], index_buffer=ibo, index_element_size=4)
            for prog in (self.peel_prog, self.count_prog)
        }
        self._mesh = [*self._vaos.values(), vbo, ibo]

    def _targets(self, n: int) -> None:
        if self._size == n:
            return
        self._release_targets()
        self.tex = [self.ctx.texture((n, n), 1, dtype="f4") for _ in range(2)]
        for t in self.tex:
            t.filter = moderngl.NEAREST, moderngl.NEAREST
        self.fbos = [self.ctx.framebuffer([t]) for t in self.tex]
        self._parts = [*self.fbos, *self.tex]
        self._size = n

    def _setup(self, matrix: np.ndarray, n: int, equation: int) -> None:
        if not self._mesh:
            raise RuntimeError("Peeler: load() a mesh first")
        self.ctx.enable_only(moderngl.BLEND)
        self.ctx.blend_func = moderngl.ONE, moderngl.ONE
        self.ctx.blend_equation = equation, equation  # colour and alpha
        for prog in (self.peel_prog, self.count_prog):
            glsl.uniform(prog, "u_matrix").write(mat_bytes(_NDC @ matrix))
        self._targets(n)

    def _done(self) -> None:
        self.ctx.blend_equation = moderngl.FUNC_ADD, moderngl.FUNC_ADD
        self.ctx.enable_only(moderngl.NOTHING)

    def count(self, matrix: np.ndarray, n: int) -> np.ndarray:
        """Surfaces crossed by each texel's ray (float32 [n, n]) in one additive pass."""
        try:
            self._setup(matrix, n, moderngl.FUNC_ADD)
            self.fbos[0].use()
            self.fbos[0].clear(0.0)
            self._vaos[self.count_prog.glo].render(moderngl.TRIANGLES)
            return np.frombuffer(self.tex[0].read(), np.float32).reshape(n, n).copy()
        finally:
            self._done()

    def peel(self, matrix: np.ndarray, n: int) -> np.ndarray:
        """All depth layers (float32 [d, n, n], NIL-filled): pass k keeps, per texel, the
        nearest fragment behind layer k-1 (MIN blending on float, so exact); stops at the first
        pass whose occlusion query counts no fragment."""
        layers = []
        try:
            self._setup(matrix, n, moderngl.MIN)
            vao = self._vaos[self.peel_prog.glo]
            for k in range(MAX_LAYERS + 1):
                out, prev = self.fbos[k % 2], self.tex[(k + 1) % 2]
                out.use()
                out.clear(NIL)
                prev.use(Texture.PEEL_PREVIOUS)
                glsl.uniform(self.peel_prog, "u_pass").value = k
                with self.query:
                    vao.render(moderngl.TRIANGLES)
                if not self.query.any_samples:
                    break
                layers.append(np.frombuffer(self.tex[k % 2].read(), np.float32).reshape(n, n))
            else:
                raise RttaError(f"depth complexity above {MAX_LAYERS}", "mesh")
        finally:
            self._done()
        return np.stack(layers) if layers else np.full((0, n, n), NIL, np.float32)

    def _release_targets(self) -> None:
        release_all(self.ctx, self._parts)
        self._parts, self._size = [], None

    def release(self) -> None:
        self._release_targets()
        release_all(self.ctx, self._mesh)
        self._mesh = []
        for p in (self.peel_prog, self.count_prog, self.query):
            p.release()


def sphere_directions(horizontal: int = 8, vertical: int = 4) -> np.ndarray:
    """The seed's sH x sV orientations on the sphere, as view directions. Orthographic rays
    along d and -d are the same lines, so one hemisphere suffices; its pole is added once."""
    out = [(0.0, 1.0, 0.0)]
    for v in range(vertical):
        el = np.pi / 2 * v / vertical
        for h in range(horizontal):
            az = 2 * np.pi * h / horizontal
            out.append((np.cos(el) * np.sin(az), np.sin(el), np.cos(el) * np.cos(az)))
    return np.array(out)


def select_viewpoint(
    peeler: Peeler, resolution: int = 128, directions: np.ndarray | None = None
) -> tuple[np.ndarray, list[tuple[int, float]]]:
    """For the mesh loaded in `peeler`: the direction of minimal depth complexity, ties broken
    by maximal coverage of the texture (covered texels / all texels); also every direction's
    (d, coverage)."""
    directions = sphere_directions() if directions is None else directions
    scores = []
    for d in directions:
        rot = look_rotation(d)
        counts = peeler.count(to_texture(rot, peeler.vertices, resolution), resolution)
        scores.append((int(round(float(counts.max()))), float((counts > 0).mean())))
    best = min(range(len(directions)), key=lambda i: (scores[i][0], -scores[i][1], i))
    return directions[best], scores


def crop_bounds(layer0: np.ndarray) -> tuple[int, int, int, int]:
    """(s0, t0, w, h) of the texels layer 0 covers (the seed's AABB_LDI); an empty layer gives w = h = 0."""
    covered = layer0 < NIL
    cols, rows = np.flatnonzero(covered.any(axis=0)), np.flatnonzero(covered.any(axis=1))
    if len(cols) == 0:
        return 0, 0, 0, 0
    return int(cols[0]), int(rows[0]), int(cols[-1] - cols[0] + 1), int(rows[-1] - rows[0] + 1)


def build(
    ctx: moderngl.Context,
    vertices,
    faces,
    resolution: int = 512,
    *,
    direction=None,
    peeler: Peeler | None = None,
    select_resolution: int = 128,
) -> LayeredDepthImage:
    """Viewpoint selection (unless `direction` is given), peeling and cropping of a closed mesh."""
    if not 4 <= resolution <= 8192:
        raise RttaError(f"LDI resolution {resolution} outside 4..8192", "--resolution")
    vertices = np.asarray(vertices, np.float64)
    center = (vertices.min(axis=0) + vertices.max(axis=0)) / 2  # peel centred: float32 keeps precision
    vertices = vertices - center
    own = peeler is None
    peeler = peeler or Peeler(ctx)
    try:
        timings = {}
        peeler.load(vertices, faces)
        t0 = time.perf_counter()
        complexity = (0, 0)
        if direction is None:
            direction, scores = select_viewpoint(peeler, select_resolution)
            complexity = (min(s[0] for s in scores), max(s[0] for s in scores))
        timings["view"] = (time.perf_counter() - t0) * 1e3
        rotation = look_rotation(direction)
        matrix = to_texture(rotation, vertices, resolution)
        t0 = time.perf_counter()
        layers = peeler.peel(matrix, resolution)
        timings["peel"] = (time.perf_counter() - t0) * 1e3
        t0 = time.perf_counter()
        s0, t0_, w, h = crop = crop_bounds(layers[0]) if len(layers) else (0, 0, 0, 0)
        cropped = np.ascontiguousarray(layers[:, t0_ : t0_ + h, s0 : s0 + w])
        timings["crop"] = (time.perf_counter() - t0) * 1e3
        if complexity == (0, 0):
            complexity = (len(layers), len(layers))
        shift = np.eye(4)
        shift[:3, 3] = -center
        return LayeredDepthImage(
            cropped, (resolution, resolution), crop, matrix @ shift, np.asarray(direction, float), timings, complexity
        )
    finally:
        if own:
            peeler.release()


def crop_coords(ldi: LayeredDepthImage, points: np.ndarray) -> np.ndarray:
    """Points (world, [N, 3]) in the LDI's crop space (`crop_matrix`), float32 as the GPU
    computes them."""
    p = np.asarray(points, np.float64)
    m = ldi.crop_matrix
    return (p @ m[:3, :3].T + m[:3, 3]).astype(np.float32)


def classify(ldi: LayeredDepthImage, points: np.ndarray) -> np.ndarray:
    """CPU volumetric parity test (bool [N]): the reference the GPU paths are compared with."""
    q = crop_coords(ldi, points)
    w, h = ldi.crop[2:]
    ok = (q >= 0).all(axis=1) & (q[:, 0] < w) & (q[:, 1] < h) & (q[:, 2] < 1)
    texel = np.floor(np.where(ok[:, None], q[:, :2], 0)).astype(np.int64)
    out = np.zeros(len(q), bool)
    idx = np.flatnonzero(ok)
    if len(idx) == 0 or ldi.depth == 0:
        return out
    depths = ldi.layers[:, texel[idx, 1], texel[idx, 0]]  # [d, M]
    in_front = (depths < q[idx, 2][None, :]).sum(axis=0)
    out[idx] = in_front % 2 == 1
    return out
