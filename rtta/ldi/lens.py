"""A 3D lens that cuts the context away inside it (seed 003's use of the volumetric test):
a sphere, a box or a closed object of the scene, represented by a layered depth image built
once in the lens's own coordinates. Moving or resizing the lens changes one matrix, not the
LDI; compositing tests each context texel's world position (from its atlas depth) against it.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum
from typing import Literal

import moderngl
import numpy as np

from ..errors import RttaError
from ..gl import glsl
from ..gl.bindings import Texture
from ..scene.model import Scene
from .gpu import LdiTextures
from .peel import Peeler, build, closed_mesh


class LensShape(StrEnum):
    """The shape lenses (besides an object of the scene)."""

    SPHERE = "sphere"  # radius 1 in its frame
    BOX = "box"  # half-size 1 in its frame


LensShapeName = Literal["sphere", "box"]
SHAPES: tuple[str, ...] = tuple(s.value for s in LensShape)
RESOLUTION = 256


@dataclass
class Lens:
    """`key` names the lens geometry; `vertices`/`faces` are in its local frame, where a shape
    lens has unit size (radius 1, or a box of half-size 1) and an object lens its own size
    about its bounds centre. World = center + radius * local."""

    key: str
    vertices: np.ndarray
    faces: np.ndarray
    center: np.ndarray
    radius: float = 1.0
    object_id: int = -1  # the scene object used as the lens: never cut itself

    @classmethod
    def shape(cls, kind: LensShapeName | LensShape, center, radius: float) -> Lens:
        from ..scene.generators import shapes

        try:
            shape = LensShape(kind)
        except ValueError:
            raise RttaError(f"unknown lens shape {kind!r}; shapes: {', '.join(SHAPES)}, or an object name") from None
        if not (np.isfinite(radius) and radius > 0):
            raise RttaError(f"lens radius must be positive, got {radius}")
        mesh = shapes.sphere(1.0, 3) if shape is LensShape.SPHERE else shapes.box(2.0)
        vertices, faces = np.asarray(mesh.vertices), np.asarray(mesh.faces)
        return cls(shape.value, vertices, faces, np.asarray(center, float), float(radius))

    @classmethod
    def of_object(cls, scene: Scene, oid: int) -> Lens:
        """A closed object of the scene as the lens, placed where it is."""
        first, count = scene.index_ranges[oid]
        faces = scene.indices[first : first + count].reshape(-1, 3).astype(np.int64)
        used, faces = np.unique(faces, return_inverse=True)
        local = scene.positions[used].astype(np.float64)
        center = (local.min(axis=0) + local.max(axis=0)) / 2
        v, f = closed_mesh(local - center, faces.reshape(-1, 3), f"lens object {scene.names[oid]!r}")
        return cls(f"object:{oid}", v, f, center + scene.origin, 1.0, oid)

    def to_local(self, origin) -> np.ndarray:
        """World relative to `origin` -> the lens shape's own frame (where its LDI was built)."""
        m = np.eye(4)
        m[:3, :3] /= self.radius
        m[:3, 3] = (np.asarray(origin, float) - self.center) / self.radius
        return m


NO_FOCUS_SHARE = 0.25  # of the scene's bounds diagonal: a lens on the whole scene would cut it all


def default_placement(scene: Scene, focus) -> tuple[np.ndarray, float]:
    """Centre and radius that reveal the focus set: its bounds centre, radius 0.6 x its
    bounds diagonal. With nothing in focus, everything is context and such a lens would cut
    the whole scene away (a blank picture): the scene's centre, radius NO_FOCUS_SHARE x its
    diagonal, a cut into its middle."""
    ids = sorted(focus) or list(range(scene.count))
    share = 0.6 if len(focus) else NO_FOCUS_SHARE
    lo, hi = scene.aabb_min[ids].min(axis=0), scene.aabb_max[ids].max(axis=0)
    return (lo + hi) / 2, max(share * float(np.linalg.norm(hi - lo)), 1e-6 * scene.radius)


class LensPass:
    """The GPU side: an LDI per lens geometry (built on first use, kept), bound for composite.frag."""

    def __init__(self, ctx: moderngl.Context) -> None:
        self.ctx = ctx
        self._ldis: dict[str, LdiTextures] = {}
        self._peeler: Peeler | None = None

    def textures(self, lens: Lens) -> LdiTextures:
        if lens.key not in self._ldis:
            self._peeler = self._peeler or Peeler(self.ctx)
            ldi = build(self.ctx, lens.vertices, lens.faces, RESOLUTION, peeler=self._peeler)
            self._ldis[lens.key] = LdiTextures(self.ctx, ldi)
        return self._ldis[lens.key]

    def bind(self, prog: moderngl.Program, lens: Lens, origin) -> None:
        tex = self.textures(lens)
        # not on PROJECTOR_DEPTH: a projector and a lens are bound for the same draws
        tex.bind(prog, lens.to_local(origin), packed_unit=Texture.LDI_RANGES, prefix="u_lens_")
        if "u_lens_object" in prog:
            glsl.uniform(prog, "u_lens_object").value = lens.object_id

    def release(self) -> None:
        for t in self._ldis.values():
            t.release()
        self._ldis.clear()
        if self._peeler is not None:
            self._peeler.release()
            self._peeler = None
