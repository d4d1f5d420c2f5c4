"""Saved views in the viewer: the camera, projection, mode, focus, hidden parts, opacities
and compositing style, written and read as `rtta.renderer.view_file` files (the format
`rtta snapshot --save-view` writes and `--view-file` renders), one file per named view in
a folder per scene: DIR/<scene file's stem>/<name>.json.
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from rtta.errors import RttaError
from rtta.renderer.options import CORE_STYLE
from rtta.renderer.view_file import SavedView, read_view, write_view
from rtta.scene import framing
from rtta.scene.cutaway import Caps, SectionPlane, parse_section
from rtta.scene.select import resolve_names

if TYPE_CHECKING:
    from rtta.scene.model import Scene

    from .orbit import Orbit
    from .state import ViewerState


def default_dir() -> Path:
    """$XDG_DATA_HOME/rtta/views, else ~/.local/share/rtta/views."""
    data = os.environ.get("XDG_DATA_HOME") or str(Path.home() / ".local" / "share")
    return Path(data) / "rtta" / "views"


def clean_name(name: str) -> str:
    """A view's name as a file name: letters, digits, '-', '_' and '.' kept, the rest '_'."""
    return re.sub(r"[^\w.-]", "_", name.strip())[:80].strip(".") or "view"


def capture(scene: Scene, state: ViewerState, orbit: Orbit) -> SavedView:
    """What the viewer shows now, as a SavedView (objects by name)."""
    names = scene.names
    o = framing.Orbit(
        float(orbit.az),
        float(orbit.el),
        float(orbit.dist),
        tuple(float(v) for v in orbit.target),  # type: ignore[arg-type]
        float(orbit.fov_y),
        orbit.projection,
    )
    style = {k: _plain(getattr(state.style, k)) for k in CORE_STYLE}
    c, spec = state.cutaway, state.cutaway.spec(scene)
    return SavedView(
        orbit=o,
        mode=state.mode,
        focus=[names[i] for i in sorted(state.highlighted)],
        hidden=[names[i] for i in sorted(state.hidden)],
        opacity={names[i]: float(a) for i, a in sorted(state.style.opacity.items())},
        style=style,
        sections={"planes": [spec], "caps": str(c.caps), "scope": str(c.scope)} if spec else None,
        explode={"factor": float(c.explode), "scope": str(c.explode_scope)} if c.explode > 0 else None,
    )


def apply(view: SavedView, scene: Scene, state: ViewerState, orbit: Orbit) -> None:
    """Show `view`: its camera, mode, focus, hidden parts, opacities and style replace the
    viewer's (names the scene lacks: an RttaError, nothing changed)."""
    focus = resolve_names(scene, view.focus, "focus")
    hidden = resolve_names(scene, view.hidden, "hidden")
    opacity = {i: a for name, a in view.opacity.items() for i in resolve_names(scene, [name], "opacity")}
    plane = _plane(view, scene)
    state.mode = view.mode
    state.style.focus.clear()
    state.style.focus |= set(focus)
    state.show_all()
    if hidden:
        state.hide(hidden)
    state.style.opacity.clear()
    state.style.opacity.update(opacity)
    for key, value in view.style.items():
        setattr(state.style, key, value)
    _cutaway(view, plane, state)
    state.touched = True  # a view chosen: its mode as it was saved
    if view.orbit is not None:
        o = view.orbit
        orbit.az, orbit.el, orbit.dist = o.az, o.el, o.distance
        orbit.target = np.array(o.target, np.float64)
        orbit.fov_y, orbit.projection = o.fov, o.projection


class Views:
    """The named views of one scene, in `folder` (made when the first view is saved)."""

    def __init__(self, root: Path, scene: Scene) -> None:
        stem = clean_name(Path(scene.source).stem) if scene.source else "scene"
        self.folder = Path(root) / stem
        self.inputs = list(scene.inputs)
        self.name = ""  # the panel's name field

    def names(self) -> list[str]:
        """The saved views' names, sorted."""
        try:
            return sorted(p.stem for p in self.folder.glob("*.json") if p.is_file())
        except OSError:
            return []

    def save(self, name: str, view: SavedView) -> Path:
        """Write `view` as `name` (an existing view of that name is replaced)."""
        self.folder.mkdir(parents=True, exist_ok=True)
        return write_view(view, self.folder / f"{clean_name(name)}.json", self.inputs)

    def load(self, name: str) -> SavedView:
        return read_view(self.folder / f"{clean_name(name)}.json")

    def delete(self, name: str) -> None:
        path = self.folder / f"{clean_name(name)}.json"
        try:
            read_view(path)  # only a view file is removed
            path.unlink()
        except OSError as exc:
            raise RttaError(f"cannot remove the view ({exc.strerror or exc})", path) from None


def stage(scene: Scene, state: ViewerState, section: str | None, caps: Caps, explode: str) -> None:
    """rtta-view's --section, --caps and --explode into the viewer's cutaway state, checked as
    a view file's are (one plane: the viewer shows one; its SPEC as `rtta snapshot` takes it)."""
    from rtta.renderer.placing import make_staging

    staging = make_staging([section] if section else [], caps, "all", explode)  # RttaError for a bad flag
    view = SavedView(
        sections={"planes": [section], "caps": caps, "scope": "all"} if section else None,
        explode={"factor": staging.explode, "scope": "all"} if staging.explode > 0 else None,
    )
    _cutaway(view, _plane(view, scene), state)


def _plane(view: SavedView, scene: Scene) -> tuple[str, float] | tuple[SectionPlane] | None:
    """The view's section as (axis, where over the scene's bounds 0..1), or (SectionPlane,) for a
    plane along a normal (nx,ny,nz,d), None without one; the viewer shows one plane: more are an
    RttaError."""
    if not view.sections or not view.sections.get("planes"):
        return None
    planes = view.sections["planes"]
    m = re.fullmatch(r"\s*(-?[xyz])\s*(?:=\s*([^,\s]+))?\s*", str(planes[0])) if len(planes) == 1 else None
    if m is None and len(planes) == 1 and str(planes[0]).count(",") == 3:
        return (parse_section(str(planes[0])),)
    try:
        plane = parse_section(str(planes[0])) if m else None
    except RttaError:
        plane = None
    if m is None or plane is None:
        one = "one plane along an axis (x=V, -z=V, x=P%, x, ...) or a normal (nx,ny,nz,d)"
        raise RttaError(f"sections {planes}: the viewer shows {one}")
    lo, hi = scene.bounds
    k = "xyz".index(m.group(1)[-1])
    if plane.at is not None:  # x=P% or x alone: the slider's place as it is
        return m.group(1), float(np.clip(plane.at, 0.0, 1.0))
    value = plane.d * plane.normal[k]
    return m.group(1), float(np.clip((value - lo[k]) / max(hi[k] - lo[k], 1e-30), 0.0, 1.0))


def _cutaway(view: SavedView, plane, state: ViewerState) -> None:
    """The view's section plane and explode into the viewer's cutaway state."""
    c = state.cutaway
    c.axis, c.normal, c.enabled, c.picking = "off", None, True, False
    if plane is not None and view.sections:
        if len(plane) == 1:
            c.normal, c.offset = plane[0].normal, plane[0].d
        else:
            c.axis, c.at = plane  # type: ignore[assignment]
        c.caps = view.sections.get("caps", c.caps)  # type: ignore[assignment]
        c.scope = view.sections.get("scope", c.scope)  # type: ignore[assignment]
    c.explode = float(view.explode.get("factor", 0.0)) if view.explode else 0.0
    if view.explode:
        c.explode_scope = view.explode.get("scope", c.explode_scope)  # type: ignore[assignment]


def _plain(value):
    """A style value as JSON holds it (enums as their strings, numpy numbers as floats)."""
    if isinstance(value, str):
        return str(value)
    if isinstance(value, (bool, int)):
        return int(value)
    return float(value)
