"""rtta-view's first view from the command line (viewer/start.py), without a window: --focus,
--hide, --camera, --view, --projection and --view-file reach the viewer's state and orbit."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rtta.errors import RttaError
from rtta.renderer.view_file import read_view
from viewer import build_parser
from viewer.orbit import Orbit
from viewer.start import Start, apply_start
from viewer.state import ViewerState


class _App:
    """What apply_start reads and writes of the viewer: scene, state, orbit, frame_objects."""

    def __init__(self, scene):
        self.renderer = type("R", (), {"scene": scene})()
        self.state = ViewerState(scene.names, paths=scene.paths)
        self.orbit = Orbit.default(scene.center, scene.radius, up_axis=scene.up_axis)
        self.framed = 0

    def frame_objects(self):
        self.framed += 1


def test_flags_set_focus_hidden_direction_and_projection(demo_scene):
    app = _App(demo_scene)
    apply_start(app, Start(focus=["hub"], hidden=["caliper"], view="top", projection="ortho"))
    assert app.state.style.focus == {demo_scene.index("hub")} and app.state.hidden == {demo_scene.index("caliper")}
    assert (app.orbit.az, app.orbit.el, app.orbit.projection) == (0.0, 90.0, "ortho") and app.framed == 1
    assert app.orbit.camera().kind == "ortho"
    app = _App(demo_scene)
    apply_start(app, Start(camera="10,20,3"))
    assert app.orbit.dist == pytest.approx(3 * demo_scene.radius) and app.framed == 0
    assert np.allclose(app.orbit.target, demo_scene.center)


def test_a_view_file_opens_on_its_camera(demo_scene, tmp_path, gl):
    from rtta.cli.main import main

    path = tmp_path / "v.json"
    args = ["--focus", "hub", "--hide", "rotor", "--opacity", "caliper=0.4", "--projection", "ortho"]
    args += ["--mode", "ghosted"]
    assert main(["snapshot", "--size", "64x48", "--out", str(tmp_path / "a.png"), *args, "--save-view", str(path)]) == 0
    app = _App(demo_scene)
    apply_start(app, Start(view_file=str(path)))
    saved = read_view(path).orbit
    assert (app.orbit.az, app.orbit.el, app.orbit.dist, app.orbit.projection) == (
        saved.az, saved.el, saved.distance, "ortho",
    )  # fmt: skip
    assert app.state.mode == "ghosted" and app.state.style.opacity[demo_scene.index("caliper")] == 0.4
    assert app.state.hidden == {demo_scene.index("rotor")}
    mine, theirs = app.orbit.camera(), saved.camera(demo_scene)
    assert np.allclose(mine.view(np.zeros(3))[:3, :3], theirs.view(np.zeros(3))[:3, :3])
    assert mine.half_height() == pytest.approx(theirs.half_height())
    with pytest.raises(RttaError, match="--view-file gives the camera"):
        apply_start(_App(demo_scene), Start(view_file=str(path), camera="1,2"))
    path.write_text(json.dumps({"rtta_view": 9}))
    with pytest.raises(RttaError, match="newer than this rtta reads"):
        apply_start(_App(demo_scene), Start(view_file=str(path)))


def test_the_viewer_parses_the_flags():
    args = build_parser().parse_args(["--focus", "a", "b", "--view", "iso", "--projection", "ortho", "--hide", "c"])
    assert (args.focus, args.view, args.projection, args.hide) == (["a", "b"], "iso", "ortho", ["c"])


def test_a_view_file_brings_its_style_section_and_explode(demo_scene, tmp_path, gl):
    """rtta-view --view-file shows what `rtta snapshot --view-file` renders: the style, the
    section plane with its caps and scope, and the explode, not only camera and parts."""
    from rtta.cli.main import main

    path = tmp_path / "v.json"
    args = ["--focus", "hub", "--mode", "ghosted", "--context-opacity", "0.3", "--section", "-y=0.01"]
    args += ["--caps", "hatch", "--explode", "0.5"]
    assert main(["snapshot", "--size", "64x48", "--out", str(tmp_path / "a.png"), *args, "--save-view", str(path)]) == 0
    app = _App(demo_scene)
    apply_start(app, Start(view_file=str(path)))
    cut = app.state.cutaway
    assert (cut.axis, cut.caps, cut.explode) == ("-y", "hatch", 0.5)
    assert cut.spec(demo_scene) is not None and app.state.style.context_opacity == pytest.approx(0.3)


def test_section_caps_and_explode_flags_open_the_cutaway(demo_scene):
    """rtta-view --section/--caps/--explode (as `rtta snapshot` takes them; one plane) reach the
    cutaway panel: an axis plane at its place over the bounds, a plane along a normal, the
    explode; bad values and a view file beside them are one-line errors."""
    from rtta.cli.main import section_values  # as viewer.main reads its arguments: `-z=..` its own word

    parsed = build_parser().parse_args(section_values(["--section", "-z=25%", "--caps", "hatch", "--explode", "0.5"]))
    assert (parsed.section, parsed.caps, parsed.explode) == ("-z=25%", "hatch", "0.5")
    app = _App(demo_scene)
    apply_start(app, Start(section="-z=25%", caps="hatch", explode="0.5"))
    cut = app.state.cutaway
    assert (cut.axis, cut.at, cut.caps, cut.explode, cut.normal) == ("-z", 0.25, "hatch", 0.5, None)
    lo, hi = demo_scene.bounds
    app = _App(demo_scene)
    apply_start(app, Start(section=f"y={float(lo[1] + 0.75 * (hi[1] - lo[1]))!r}"))
    assert (app.state.cutaway.axis, app.state.cutaway.explode) == ("y", 0.0)
    assert app.state.cutaway.at == pytest.approx(0.75)
    app = _App(demo_scene)
    apply_start(app, Start(section="0,0,2,0.1"))
    assert app.state.cutaway.normal == pytest.approx((0, 0, 1)) and app.state.cutaway.offset == pytest.approx(0.05)
    for bad, match in ((Start(section="w"), "--section expects"), (Start(explode="9"), "--explode")):
        with pytest.raises(RttaError, match=match):
            apply_start(_App(demo_scene), bad)
    with pytest.raises(RttaError, match="--view-file gives the cutaway"):
        apply_start(_App(demo_scene), Start(view_file="v.json", section="x"))
