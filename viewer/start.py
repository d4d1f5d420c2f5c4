"""The view rtta-view opens with: --focus, --hide, --mode, --camera, --view, --projection,
--section, --caps, --explode or a --view-file saved by `rtta snapshot --save-view`
(rtta.renderer.view_file)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rtta.errors import RttaError
from rtta.scene.camera import Projection
from rtta.scene.cutaway import Caps
from rtta.scene.framing import StandardView


@dataclass
class Start:
    """What the command line asks of the first view (empty: the viewer's default)."""

    focus: list[str] = field(default_factory=list)
    hidden: list[str] = field(default_factory=list)
    camera: str | None = None  # AZ,EL[,DIST] as `rtta snapshot --camera`
    view: StandardView | None = None
    projection: Projection | None = None
    view_file: str | None = None
    section: str | None = None  # one plane, as `rtta snapshot --section` takes it
    caps: Caps = "solid"
    explode: str = "0"


def apply_start(app, start: Start) -> None:
    """Put `start` into the viewer `app` (its state, orbit and mode); names that match no
    object, a bad camera or view file are RttaErrors (one line)."""
    from rtta.renderer.view_file import read_view
    from rtta.scene.framing import parse_camera, scene_orbit
    from rtta.scene.select import resolve_names

    scene = app.renderer.scene
    if start.view_file:
        if start.camera or start.view or start.projection:
            raise RttaError("--view-file gives the camera: leave out --camera, --view and --projection")
        if start.section or start.explode != "0" or start.caps != "solid":
            raise RttaError("--view-file gives the cutaway: leave out --section, --caps and --explode")
        saved = read_view(start.view_file)
        from .saved import apply as apply_view  # the viewer's saved views: style, sections, explode too

        apply_view(saved, scene, app.state, app.orbit)
        if saved.orbit is None:
            app.frame_objects()
        return
    focus = resolve_names(scene, start.focus, "--focus")
    hidden = resolve_names(scene, start.hidden, "--hide")
    from .saved import stage

    stage(scene, app.state, start.section, start.caps, start.explode)
    if hidden:
        app.state.hide(hidden)
    if focus:
        app.state.style.focus |= set(focus)
    orbit = app.orbit
    orbit.projection = start.projection or "perspective"
    dist = None
    if start.camera is not None or start.view is not None:
        o = scene_orbit(scene, start.camera, orbit.fov_y, projection=orbit.projection, view=start.view, hidden=hidden)
        orbit.az, orbit.el = o.az, o.el
        dist = parse_camera(start.camera)[2] if start.camera is not None else None
        if dist is not None:  # AZ,EL,DIST: as the orbit says, about the scene's centre
            orbit.dist, orbit.target = o.distance, np.array(o.target, np.float64)
    if dist is None:
        app.frame_objects()  # the parts shown, from the direction asked, in the composite's aspect
