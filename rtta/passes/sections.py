"""Cutaways and exploded views in the scene passes (capture, STD, RTT): shaders/section.glsl.

`Placement` is what a frame draws moved and cut: per object a world offset (explode) and
whether the section planes cut it and cap it. The scene passes (capture.ScenePass) take it
from `GpuScene.placement`, so every pass and mode sees the same cut and the same offsets.

Caps, per object and so per atlas region: a closed part's back face that is the nearest
surface left after the cut means the view ray entered the solid through the cut, so the cap
lies where the ray crosses into the kept region (exact for any closed part, convex or not). The
first draw marks each texel's nearest surface in the stencil (1: a capped object's back face,
0: anything else) and shades those back faces as the cap; a second draw of the capped back
faces, where the stencil holds 1, writes the cap's depth (the plane's, not the back face's),
the same for every fragment of the texel (the entry point depends on the ray alone). The
back faces are drawn after the front faces, pushed back by BACK_OFFSET, so that where a
mesh has a front and a back face in one place (boxes concatenated into one part) the front
face is the nearest, in the atlas and in RTT alike.

STD caps by the nearest surface of all parts: where a part lies inside another's solid
(interpenetrating parts), STD shows it through the other's cut, where the atlas (each part
alone) shows the other's cap in front of it.
"""

from __future__ import annotations

from dataclasses import dataclass

import moderngl
import numpy as np

from ..gl import glraw
from ..gl.bindings import Storage
from ..scene.cutaway import Cutaway

GL_FRONT, GL_BACK, GL_FRONT_AND_BACK = 0x0404, 0x0405, 0x0408
GL_EQUAL = 0x0202
CAP_STYLES = {"off": 0, "solid": 1, "hatch": 2}
HATCH_LINES = 60  # hatch lines across the scene's diameter
BACK_OFFSET = (1.0, 8.0)  # glPolygonOffset of capped back faces in the first draw (ties go to the front)


@dataclass
class Placement:
    """Per object: its world offset and whether it is cut and capped; the planes, relative
    to the scene origin. `buffer` holds (offset, flags) per object for the shaders."""

    offsets: np.ndarray | None  # float64 [n, 3], world units; None: nothing moves
    cut: np.ndarray  # bool [n]
    capped: np.ndarray  # bool [n]: cut, closed and caps on
    planes: np.ndarray  # float32 [k, 4]: (n, d) with the scene origin at 0
    caps: int  # CAP_STYLES
    hatch: float  # world units between hatch lines
    buffer: moderngl.Buffer

    @classmethod
    def make(cls, ctx: moderngl.Context, scene, cutaway: Cutaway, cut: np.ndarray, offsets: np.ndarray | None):
        """The placement of `scene` cut by `cutaway` (`cut`: the objects it cuts) and moved by `offsets`."""
        n = scene.count
        caps = CAP_STYLES[cutaway.caps] if cutaway else 0
        capped = cut & scene.closed if caps else np.zeros(n, bool)
        data = np.zeros((max(n, 1), 4), np.float32)
        if offsets is not None:
            data[:n, :3] = offsets
        data[:n, 3] = cut.astype(np.float32) + 2.0 * capped
        planes = np.array([p.relative(scene.origin) for p in cutaway.planes], np.float32).reshape(-1, 4)
        hatch = 2.0 * scene.radius / HATCH_LINES
        return cls(offsets, cut, capped, planes, caps, hatch, ctx.buffer(data.tobytes()))

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
        program["u_sections"].write(planes.tobytes())
        program["u_section_count"].value = len(self.planes)
        for name, value in (("u_caps", self.caps), ("u_hatch_spacing", self.hatch)):
            if name in program:
                program[name].value = value
        if "u_section_inverse" in program:
            inverse = np.linalg.inv(np.asarray(view_proj, np.float64))
            program["u_section_inverse"].write(np.ascontiguousarray(inverse.T, np.float32).tobytes())

    def release(self) -> None:
        self.buffer.release()


def stencil_mark(back: int) -> None:
    """Stencil on: every fragment that passes the depth test writes 0 for a front face and
    `back` for a back face (the nearest surface's kind stays in each texel)."""
    gl = glraw._lib()
    gl.glEnable(glraw.GL_STENCIL_TEST)
    gl.glStencilMask(0xFF)
    gl.glStencilFuncSeparate(GL_FRONT, glraw.GL_ALWAYS, 0, 0xFF)
    gl.glStencilFuncSeparate(GL_BACK, glraw.GL_ALWAYS, back, 0xFF)
    gl.glStencilOp(glraw.GL_KEEP, glraw.GL_KEEP, glraw.GL_REPLACE)


def stencil_equal(value: int) -> None:
    """Stencil on: only where the stencil holds `value`, which stays."""
    gl = glraw._lib()
    gl.glEnable(glraw.GL_STENCIL_TEST)
    gl.glStencilFuncSeparate(GL_FRONT_AND_BACK, GL_EQUAL, value, 0xFF)
    gl.glStencilOp(glraw.GL_KEEP, glraw.GL_KEEP, glraw.GL_KEEP)
