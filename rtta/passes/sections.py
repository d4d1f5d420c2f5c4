"""Cutaways and exploded views in the scene passes (capture, STD, RTT): shaders/section.glsl.

`Placement` is what a frame draws moved and cut: per object a world offset (explode) and
whether the section planes cut it and cap it. The scene passes (capture.ScenePass) take it
from `GpuScene.placement`, so every pass and mode sees the same cut and the same offsets.

Caps: the cap of a closed part lies where the view ray enters the kept region (the point P on
the plane it crosses last), when P is inside the part. Inside means a winding number not 0:
the part's surfaces beyond P along the ray, counted into the stencil (a back face +1, a front
face -1, removed ones too), add up to the number of times P is inside it (concatenated
boxes overlapping, as the demo's caliper is, count alike). The part's back faces beyond P
then draw the cap where the count is not 0 (each resets it), with P's depth, in the part's
darker colour, lit as a face on the plane. In the atlas every texel belongs to one part, so
all parts are capped at once; STD caps one part after the other, so a part's cap covers the
parts inside its solid as each part's own image does.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import moderngl
import numpy as np

from ..gl import glraw, glsl
from ..gl.bindings import Storage
from ..scene.cutaway import Cutaway

GL_FRONT, GL_BACK, GL_FRONT_AND_BACK = 0x0404, 0x0405, 0x0408
GL_NOTEQUAL, GL_ZERO, GL_INCR_WRAP, GL_DECR_WRAP = 0x0205, 0, 0x8507, 0x8508
CAP_STYLES = {"off": 0, "solid": 1, "hatch": 2}
HATCH_LINES = 60  # hatch lines across the scene's diameter


@dataclass
class Placement:
    """Per object: its world offset and whether it is cut and capped; the planes, relative
    to the scene origin. `buffer` holds (offset, flags) per object for the shaders."""

    offsets: np.ndarray | None  # float64 [n, 3], world units; None: nothing moves
    removed: np.ndarray  # bool [n]: cut away whole, not drawn
    cut: np.ndarray  # bool [n]: crossed by a plane
    capped: np.ndarray  # bool [n]: cut, closed and caps on
    planes: np.ndarray  # float32 [k, 4]: (n, d) with the scene origin at 0
    caps: int  # CAP_STYLES
    hatch: float  # world units between hatch lines
    buffer: moderngl.Buffer
    serial: int = field(default_factory=itertools.count().__next__)  # a new one each time: a cache key

    @classmethod
    def make(cls, ctx: moderngl.Context, scene, cutaway: Cutaway, sides: tuple, offsets: np.ndarray | None):
        """The placement of `scene` cut by `cutaway` and moved by `offsets`; `sides`: the
        objects it removes whole and those it crosses (Cutaway.sides)."""
        removed, cut = sides
        n = scene.count
        caps = CAP_STYLES[cutaway.caps] if cutaway else 0
        capped = cut & scene.closed if caps else np.zeros(n, bool)
        data = np.zeros((max(n, 1), 4), np.float32)
        if offsets is not None:
            data[:n, :3] = offsets
        data[:n, 3] = cut.astype(np.float32) + 2.0 * capped
        bounds = scene.bounds  # planes at a fraction of them (x=P%) placed on this scene
        planes = np.array([p.on(bounds).relative(scene.origin) for p in cutaway.planes], np.float32).reshape(-1, 4)
        hatch = 2.0 * scene.radius / HATCH_LINES
        return cls(offsets, removed, cut, capped, planes, caps, hatch, ctx.buffer(data.tobytes()))

    @property
    def sections(self) -> bool:
        return bool(len(self.planes)) and bool(self.cut.any())

    def variant(self) -> dict[str, bool]:
        """The scene programs' defines for this placement."""
        return {"PLACED": self.offsets is not None, "SECTIONS": self.sections}

    def apply(self, program: moderngl.Program, view_proj: np.ndarray) -> None:
        """Bind the per-object buffer and set the sections' uniforms of `program`."""
        self.buffer.bind_to_storage_buffer(Storage.PLACEMENT)
        if not self.sections or "u_section_count" not in program:
            return
        planes = np.zeros((6, 4), np.float32)
        planes[: len(self.planes)] = self.planes
        glsl.uniform(program, "u_sections").write(planes.tobytes())
        glsl.uniform(program, "u_section_count").value = len(self.planes)
        for name, value in (("u_caps", self.caps), ("u_hatch_spacing", self.hatch)):
            if name in program:
                glsl.uniform(program, name).value = value
        inverse = np.linalg.inv(np.asarray(view_proj, np.float64))
        if "u_section_inverse" in program:
            glsl.uniform(program, "u_section_inverse").write(np.ascontiguousarray(inverse.T, np.float32).tobytes())
        if "u_section_near" in program:
            near = np.zeros((6, 3), np.float32)
            near[: len(self.planes)] = near_coefficients(self.planes, inverse)
            glsl.uniform(program, "u_section_near").write(near.tobytes())

    def release(self) -> None:
        self.buffer.release()


def near_coefficients(planes: np.ndarray, inverse: np.ndarray) -> np.ndarray:
    """Per plane (n, d), n.q - d as a x + b y + c of viewport NDC (x, y), q the near-plane point
    there: q is affine in (x, y) for a perspective and an orthographic projection alike."""
    ndc = np.array([[0.0, 0.0, -1.0, 1.0], [1.0, 0.0, -1.0, 1.0], [0.0, 1.0, -1.0, 1.0]])
    h = ndc @ inverse.T
    q = h[:, :3] / h[:, 3:]
    f = q @ planes[:, :3].astype(np.float64).T - planes[:, 3].astype(np.float64)  # [3 points, planes]
    return np.stack([f[1] - f[0], f[2] - f[0], f[0]], axis=1)


def stencil_count() -> None:
    """Stencil on, depth writes off: every fragment adds 1 for a back face, takes 1 for a
    front face (wrapping), whatever the depth: the winding number of the surfaces drawn."""
    gl = glraw._lib()
    gl.glEnable(glraw.GL_STENCIL_TEST)
    gl.glDepthMask(0)
    gl.glStencilMask(0xFF)
    gl.glStencilFuncSeparate(GL_FRONT_AND_BACK, glraw.GL_ALWAYS, 0, 0xFF)
    gl.glStencilOpSeparate(GL_BACK, glraw.GL_KEEP, GL_INCR_WRAP, GL_INCR_WRAP)
    gl.glStencilOpSeparate(GL_FRONT, glraw.GL_KEEP, GL_DECR_WRAP, GL_DECR_WRAP)


def stencil_cap() -> None:
    """Depth writes on; only where the stencil is not 0, which every fragment resets to 0."""
    gl = glraw._lib()
    gl.glDepthMask(1)
    gl.glStencilFuncSeparate(GL_FRONT_AND_BACK, GL_NOTEQUAL, 0, 0xFF)
    gl.glStencilOpSeparate(GL_FRONT_AND_BACK, GL_ZERO, GL_ZERO, GL_ZERO)


def stencil_off() -> None:
    gl = glraw._lib()
    gl.glDepthMask(1)
    gl.glDisable(glraw.GL_STENCIL_TEST)
