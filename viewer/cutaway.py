"""The viewer's cutaway and exploded view: one section plane along an axis, its caps and scope,
the explode factor and scope (the flags of `rtta snapshot`: rtta.renderer.placing), as state
the side panel edits (`panel`) and the capture reads (`CutawayState.staging`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal, get_args

from rtta.renderer.placing import Staging, make_staging
from rtta.scene.cutaway import CAPS, SECTION_SCOPES, Caps, SectionScope
from rtta.scene.explode import EXPLODE_MAX, EXPLODE_SCOPES, ExplodeScope

if TYPE_CHECKING:
    from rtta.scene.model import Scene

Axis = Literal["off", "x", "y", "z", "-x", "-y", "-z"]
AXES: tuple[Axis, ...] = get_args(Axis)


@dataclass
class CutawayState:
    """One section plane (`axis`: remove what lies beyond `at` on x/y/z, or below it on -x...;
    `at` runs over the scene's bounds from 0 to 1), its caps and scope; explode and its scope."""

    axis: Axis = "off"
    at: float = 0.5
    caps: Caps = "solid"
    scope: SectionScope = "all"
    explode: float = 0.0
    explode_scope: ExplodeScope = "all"

    def key(self) -> tuple:
        """Changes whenever the capture must run again."""
        return (self.axis, self.at, self.caps, self.scope, self.explode, self.explode_scope)

    def spec(self, scene: Scene) -> str | None:
        """The plane as `--section` takes it (world units), or None without one."""
        if self.axis == "off":
            return None
        lo, hi = scene.bounds
        k = "xyz".index(self.axis[-1])
        return f"{self.axis}={float(lo[k] + self.at * (hi[k] - lo[k])):.9g}"

    def staging(self, scene: Scene) -> Staging:
        spec = self.spec(scene)
        return make_staging([spec] if spec else [], self.caps, self.scope, self.explode, self.explode_scope)


def panel(app) -> None:
    """The side panel's cutaway section (a function of the app, as viewer.panels' sections)."""
    from imgui_bundle import imgui

    c: CutawayState = app.state.cutaway
    if not imgui.collapsing_header("cutaway and explode"):
        return
    changed, i = imgui.combo("section plane", AXES.index(c.axis), list(AXES))
    if changed:
        c.axis = AXES[i]
    if c.axis != "off":
        _, c.at = imgui.slider_float("at (of the bounds)", c.at, 0.0, 1.0)
        changed, i = imgui.combo("caps", CAPS.index(c.caps), list(CAPS))
        if changed:
            c.caps = CAPS[i]
        changed, i = imgui.combo("section scope", SECTION_SCOPES.index(c.scope), list(SECTION_SCOPES))
        if changed:
            c.scope = SECTION_SCOPES[i]
        imgui.text_disabled(c.spec(app.renderer.scene) or "")
    _, c.explode = imgui.slider_float("explode", c.explode, 0.0, EXPLODE_MAX)
    changed, i = imgui.combo("explode scope", EXPLODE_SCOPES.index(c.explode_scope), list(EXPLODE_SCOPES))
    if changed:
        c.explode_scope = EXPLODE_SCOPES[i]
