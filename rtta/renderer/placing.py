"""A renderer's cutaway and exploded view: what each frame draws cut and moved.

`Staging` keeps the user's choices (section planes, caps and scope; explode factor and
scope) and, per focus, the Placement the scene passes draw with (rtta.passes.sections): the
objects' offsets, which are cut and capped, and which the planes remove whole (not packed).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import RttaError
from ..gl.targets import LayeredTarget
from ..passes.sections import Placement
from ..scene.cutaway import Caps, Cutaway, SectionPlane, SectionScope, parse_section
from ..scene.explode import ExplodeScope, check_explode, explode_offsets


@dataclass(eq=False)
class Staging:
    """Sections and explode of a Renderer (`renderer.staging`); `place` applies them."""

    cutaway: Cutaway = field(default_factory=Cutaway)
    explode: float = 0.0
    explode_scope: ExplodeScope = "all"
    removed: np.ndarray | None = None  # bool [n]: cut away whole (None: none)
    offsets: np.ndarray | None = None  # float64 [n, 3] world offsets (None: none)
    focus: frozenset = frozenset()  # the focus the placement was made for
    _key: tuple | None = None
    _placement: Placement | None = None
    _framed: tuple | None = None

    def __post_init__(self) -> None:
        self.explode = check_explode(self.explode, self.explode_scope)

    def key(self, focus) -> tuple:
        """What the placement depends on (the focus only where a scope names it)."""
        uses_focus = self.cutaway.scope == "context" or self.explode_scope == "focus"
        return (self.cutaway, self.explode, self.explode_scope, frozenset(focus) if uses_focus else None)

    @property
    def choices(self) -> tuple:
        """The user's choices (equal choices stage alike)."""
        return (self.cutaway, self.explode, self.explode_scope)

    @property
    def active(self) -> bool:
        return bool(self.cutaway) or self.explode > 0

    def place(self, gpu, focus, targets: list[LayeredTarget]) -> bool:
        """Make the placement for `focus` (None: the last one) current on `gpu` (uploading
        offsets and bounds) and give `targets` a stencil when caps are drawn; returns True
        when it changed."""
        self.focus = focus = self.focus if focus is None else frozenset(focus)
        key = self.key(focus)
        if key == self._key:
            return False
        self._key = key
        scene = gpu.scene
        self.release()
        if not self.active:
            gpu.placement, self.removed, self.offsets = None, None, None
            self._write_bounds(gpu, None)
            for t in targets:
                t.want_stencil(False)
            return True
        movable = None
        if self.explode_scope == "focus":
            movable = np.zeros(scene.count, bool)
            movable[[o for o in focus if 0 <= o < scene.count]] = True
        offsets = explode_offsets(scene, self.explode, movable) if self.explode > 0 else None
        removed, crossed = self.cutaway.sides(scene, offsets, self.cutaway.cut(scene.count, focus))
        self._placement = Placement.make(gpu.ctx, scene, self.cutaway, (removed, crossed), offsets)
        gpu.placement, self.offsets = self._placement, offsets
        self.removed = removed if removed.any() else None
        self._write_bounds(gpu, offsets)
        for t in targets:
            t.want_stencil(bool(self._placement.sections and self._placement.capped.any()))
        return True

    def framed(self, scene):
        """The scene the default camera frames (check_staging, made once per scene)."""
        if self._framed is None or self._framed[0] is not scene:
            self._framed = (scene, check_staging(self, scene, self.focus))
        return self._framed[1]

    def staged(self, hidden: np.ndarray | None, corners: np.ndarray) -> tuple[np.ndarray | None, np.ndarray]:
        """The objects not packed (hidden, or cut away whole) and B_world's corners, moved."""
        hidden = self.not_packed(hidden)
        if self.offsets is not None:
            corners = corners + self.offsets[..., None, :]
        return hidden, corners

    def not_packed(self, hidden: np.ndarray | None) -> np.ndarray | None:
        """bool [n]: the objects not packed, `hidden` or cut away whole (None: none)."""
        if self.removed is None:
            return hidden
        return self.removed if hidden is None else hidden | self.removed

    @property
    def shift(self) -> np.ndarray | float:
        """The objects' offsets [n, 3], or 0.0 when none moves."""
        return 0.0 if self.offsets is None else self.offsets

    @staticmethod
    def _write_bounds(gpu, offsets: np.ndarray | None) -> None:
        """B_world per object, moved, for compositing's sprite outlines (GpuScene.bounds)."""
        scene = gpu.scene
        bounds = np.zeros((max(scene.count, 1), 2, 4), np.float32)
        shift = 0.0 if offsets is None else offsets
        bounds[: scene.count, 0, :3] = scene.aabb_min - scene.origin + shift
        bounds[: scene.count, 1, :3] = scene.aabb_max - scene.origin + shift
        gpu.bounds.write(bounds.tobytes())

    def release(self) -> None:
        if self._placement is not None:
            self._placement.release()
            self._placement = None


def restage(renderer, staging: Staging | None) -> None:
    """Give `renderer` these choices (None: none), releasing the old placement when they differ."""
    staging = staging or Staging()
    if renderer.staging.choices != staging.choices:
        renderer.staging.release()
        renderer.staging = staging


def make_staging(
    sections=(),
    caps: Caps = "solid",
    section_scope: SectionScope = "all",
    explode: float | str = 0.0,
    explode_scope: ExplodeScope = "all",
) -> Staging:
    """A checked Staging from the CLI's flags or the one-call API's keywords: `sections` are
    SPEC strings (`x=V`, `-x=V`, `nx,ny,nz,d`; rtta.scene.cutaway.parse_section) or
    SectionPlanes."""
    if isinstance(sections, (str, SectionPlane)):
        sections = [sections]
    planes = tuple(p if isinstance(p, SectionPlane) else parse_section(p) for p in sections or ())
    return Staging(Cutaway(planes, caps, section_scope), check_explode(explode, explode_scope), explode_scope)


def check_staging(staging: Staging, scene, focus=(), hidden=()):
    """RttaError when the planes remove every part shown; else the scene to frame the
    default camera on: `scene` itself, or exploded a copy with its boxes moved (its arrays
    shared)."""
    focus = [o for o in focus if 0 <= o < scene.count]
    movable = None
    if staging.explode_scope == "focus":
        movable = np.zeros(scene.count, bool)
        movable[focus] = True
    offsets = explode_offsets(scene, staging.explode, movable) if staging.explode > 0 else None
    cut = staging.cutaway.cut(scene.count, focus)
    shown = np.ones(scene.count, bool)
    shown[[o for o in hidden if 0 <= o < scene.count]] = False
    if staging.cutaway and not (shown & ~staging.cutaway.sides(scene, offsets, cut)[0]).any():
        raise RttaError("--section: the section planes remove the whole scene (see `rtta info` for its bounds)")
    if offsets is None:
        return scene
    return replace(scene, aabb_min=scene.aabb_min + offsets, aabb_max=scene.aabb_max + offsets, _corners={})
