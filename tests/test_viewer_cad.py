"""The viewer's CAD basics (issue 45): the view cube and standard views, the projection
switch, the first view, the double-click on a focus part seen through the context, the
measure tool, saved views, screenshots in the user's pictures folder, taps on the panel, the
splitter, the wheel and the frame statistics. The real window under Xvfb is driven by
tests/viewer_cad_driver.py; the parts without a window are tested directly."""

from __future__ import annotations

import subprocess

import numpy as np
import pytest
from test_viewer import _env, _region, display, run_driver  # noqa: F401  (the Xvfb fixture)

from viewer import gizmo, pictures, saved
from viewer.files import Stats
from viewer.orbit import Orbit
from viewer.ruler import Measurement, Ruler, describe
from viewer.state import ViewerState
from viewer.views import PANEL_MIN, Layout


@pytest.fixture(scope="module")
def cad(display, tmp_path_factory):  # noqa: F811
    """The driver's result and screenshots; run from an empty folder, pictures in their own."""
    out, cwd, pics = (tmp_path_factory.mktemp(k) for k in ("cad", "cwd", "pictures"))
    result, shots = run_driver(display, out, "viewer_cad_driver.py", cwd=cwd, env={"XDG_PICTURES_DIR": str(pics)})
    result["pictures_dir"], result["cwd"] = str(pics), str(cwd)
    return result, shots


def test_view_cube_top_face_gives_the_top_view(cad):
    """A Z-up box: the cube's TOP face turns the camera to look down the file's up axis."""
    r, _ = cad
    assert r["top_face_shown"]
    assert np.allclose(r["after_top"]["forward"], [0.0, 0.0, -1.0], atol=1e-6), r["after_top"]
    assert r["after_top"]["el"] == 90.0 and r["gl_errors"] == []
    assert r["turn_after_drag"]  # a drag during a turn stops it


def test_measure_between_box_vertices_shows_the_edge_length(cad):
    """Two clicks a few pixels off two corners of a 2 mm box snap to them: 2.000 mm along z;
    the measurement stays while the view orbits."""
    m = cad[0]["measure"]
    assert cad[0]["ruler_on"] and m["count"] == 1
    assert m["distance"] == pytest.approx(2.0, abs=1e-6)
    assert np.allclose(np.abs(m["delta"]), [0, 0, 2], atol=1e-6) and np.allclose(m["a"], m["expect_a"])
    assert "2.000 mm" in m["message"] and "dz" in m["message"]
    assert cad[0]["measure_after_orbit"] == 1
    assert cad[0]["ruler_after_esc"] == [False, 1]


def test_double_click_keeps_a_focus_part_seen_through_the_context_and_fits_it(cad):
    """The piston behind the caliper, highlighted: a double-click on it keeps it (not the
    caliper in front, which the second click picked when it saw the first click's focus)
    and fits it (the orbit turns about its centre and comes closer)."""
    r = cad[0]
    d = r["double"]
    assert r["front_at_piston"] != d["piston"]  # the caliper is in front there
    assert d["focus"] == [d["piston"]] and d["target_error"] < 1e-9 and d["closer"]


def test_saved_and_restored_view_gives_the_same_composite(cad):
    r, shots = cad
    assert r["views_after_save"] == ["my_view"] and r["restored_message"] == "view my_view"
    rect = r["layout"]["composite"]
    saved_, changed, restored = (_region(shots[k], rect) for k in ("view_saved", "view_changed", "view_restored"))
    assert (np.abs(saved_ - changed).max(-1) > 10).mean() > 0.1  # the change showed
    assert np.array_equal(saved_, restored)


def test_screenshots_go_to_the_pictures_folder_never_the_cwd(cad):
    r = cad[0]
    assert r["screenshot_dir"] == str(pictures.Path(r["pictures_dir"]) / "rtta")
    assert r["pictures"] == ["rtta-brake_assembly-001-atlas.png", "rtta-brake_assembly-001-composite.png"]
    assert r["cwd_files"] == [] and r["pictures_dir"] in r["screenshot_message"]


def test_first_view_is_solid_and_a_tap_reaches_the_panel(cad):
    """The demo opens solid (nothing in focus: ghosted-ao would be all grey); a tap (press
    and release before one frame) on a row's checkbox highlights it, and ghosted-ao shows."""
    r, shots = cad
    assert (r["first_mode"], r["first_shown"]) == ("ghosted-ao", "std")
    assert r["focus_after_tap"] == [14] and r["shown_after_tap"] == "ghosted-ao"
    rect = r["layout"]["composite"]
    assert (np.abs(_region(shots["start"], rect) - _region(shots["tapped"], rect)).max(-1) > 10).mean() > 0.05


def test_splitter_wheel_projection_and_stats(cad):
    r = cad[0]
    assert r["panel_widths"] == [360, 460]
    assert r["wheel_ratio"] == pytest.approx(r["zoom_per_step"]) and 0.85 < r["zoom_per_step"] <= 0.9
    assert r["projection"] == "ortho"
    st = r["stats"]
    assert st["moving_frames"] > 0 and st["rest_frames"] > 0
    assert st["stages"] and sum(st["stages"].values()) <= st["rendered_ms"] + 1e-6


def test_view_angles_and_turns():
    assert gizmo.view_angles((0, 1, 0)) == (0.0, 90.0) and gizmo.view_angles((-1, 0, 0)) == (-90.0, 0.0)
    az, el = gizmo.view_angles((1, 1, 1))
    assert az == pytest.approx(45.0) and el == pytest.approx(np.degrees(np.arcsin(1 / np.sqrt(3))))
    o = Orbit.default(np.zeros(3), 1.0, up_axis="z")
    o.az, o.el = 350.0, 10.0
    turn = gizmo.Turn.to(o, 20.0, 90.0)
    turn.t0 = 8607.636727584  # a clock reading where (t0 + TURN_S) - t0 falls an ulp short of TURN_S
    assert not turn.step(o, turn.t0 + gizmo.TURN_S / 2)
    assert o.az > 350.0 or o.az < 20.0  # the short way round, through 0
    assert turn.step(o, turn.t0 + gizmo.TURN_S) and (o.az, o.el) == (20.0, 90.0)
    cam = o.camera()
    assert np.allclose((cam.target - cam.eye) / np.linalg.norm(cam.target - cam.eye), [0, 0, -1])


def test_view_cube_hits_the_face_under_the_cursor():
    rect = (0, 0, 800, 600)
    o = Orbit.default(np.zeros(3), 1.0)
    for _, direction, quad in gizmo.cells(rect, o):
        assert gizmo.hit(rect, o, *quad.mean(axis=0)) == ("cube", direction)
    x0, y0, x1, y1 = gizmo.projection_rect(rect)
    assert gizmo.hit(rect, o, (x0 + x1) / 2, (y0 + y1) / 2) == ("projection", None)
    assert gizmo.hit(rect, o, 10, 10) is None


def test_first_contact_and_stats():
    s = ViewerState(["a", "b"])
    assert s.shown_mode() == "std"
    s.toggle(0)
    assert s.shown_mode() == "ghosted-ao"
    s.toggle(0)
    assert s.shown_mode() == "ghosted-ao"  # touched: the user's choice from now on
    t = ViewerState(["a"], mode="ghosted")
    t.choose_mode("ghosted")
    assert t.shown_mode() == "ghosted"
    st = Stats()
    st.done(True, 200.0, {"capture": 150.0, "ui": 20.0})
    st.tick()
    st.done(False, 5.0, None)
    st.tick()
    assert len(st.moving_ms) == 1 and len(st.rest_ms) == 1 and st.rendered == (200.0, {"capture": 150.0, "ui": 20.0})


def test_layout_takes_the_splitter_width():
    assert Layout.of((1280, 720), True, 500).panel[2] == 500
    assert Layout.of((1280, 720), True, 10).panel[2] == PANEL_MIN
    assert Layout.of((1280, 720), False, 5000).panel[2] == int(0.6 * 1280)


def test_ruler_pairs_and_describes():
    r = Ruler()
    assert r.add(np.zeros(3), "a") is None
    m = r.add(np.array([3.0, 4.0, 0.0]), "b")
    assert isinstance(m, Measurement) and m.distance == 5.0 and m.parts == ("a", "b")
    assert describe(m, "m", 10.0) == ("5.00 m", "dx 3.00  dy 4.00  dz 0.00")
    r.clear()
    assert r.done == [] and r.first is None


def test_saved_view_round_trip(demo_scene, tmp_path):
    state = ViewerState(demo_scene.names, paths=demo_scene.paths)
    state.toggle(demo_scene.index("hub"))
    state.hide([demo_scene.index("rotor")])
    state.style.opacity[demo_scene.index("caliper")] = 0.4
    state.cutaway.axis, state.cutaway.at, state.cutaway.explode = "-y", 0.25, 1.5
    o = Orbit.default(demo_scene.center, demo_scene.radius)
    o.az, o.projection = 123.0, "ortho"
    views = saved.Views(tmp_path, demo_scene)
    path = views.save("a/b c", saved.capture(demo_scene, state, o))
    assert path.name == "a_b_c.json" and views.names() == ["a_b_c"]
    other, o2 = ViewerState(demo_scene.names, paths=demo_scene.paths), Orbit.default(np.zeros(3), 1.0)
    saved.apply(views.load("a_b_c"), demo_scene, other, o2)
    assert other.highlighted == state.highlighted and other.hidden == state.hidden
    assert other.style.opacity == state.style.opacity and (o2.az, o2.projection, o2.dist) == (123.0, "ortho", o.dist)
    assert (other.cutaway.axis, other.cutaway.explode) == ("-y", 1.5)
    assert other.cutaway.at == pytest.approx(0.25) and other.cutaway.spec(demo_scene) == state.cutaway.spec(demo_scene)
    two = saved.capture(demo_scene, state, o)
    two.sections = {"planes": ["x=0", "y=0"], "caps": "solid", "scope": "all"}
    with pytest.raises(saved.RttaError, match="one plane along an axis"):
        saved.apply(two, demo_scene, other, o2)
    assert other.cutaway.axis == "-y" and other.highlighted == state.highlighted  # nothing changed
    (views.folder / "notes.json").write_text("{}")
    with pytest.raises(saved.RttaError):
        views.delete("notes")
    assert (views.folder / "notes.json").exists()


def test_pictures_folder(monkeypatch, tmp_path):
    monkeypatch.setenv("XDG_PICTURES_DIR", str(tmp_path / "pics"))
    assert pictures.default_dir() == tmp_path / "pics" / "rtta"
    monkeypatch.delenv("XDG_PICTURES_DIR")
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path))
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    (tmp_path / "user-dirs.dirs").write_text('XDG_PICTURES_DIR="$HOME/Bilder"\n')
    assert pictures.default_dir() == tmp_path / "home" / "Bilder" / "rtta"


def test_measure_points_snap_to_shown_vertices_only(make_renderer):
    """ruler.point_at on a box: a pixel near a front corner gives that corner exactly; near
    where a back corner projects (behind the box's faces) it gives the surface point, not the
    hidden corner; the background far from any vertex gives None."""
    from rtta.scene.camera import Camera
    from rtta.scene.generators.shapes import box
    from rtta.scene.model import from_meshes
    from viewer.ruler import point_at

    cube = box(2.0)
    scene = from_meshes([("box", np.asarray(cube.vertices), np.asarray(cube.faces), None)])
    r = make_renderer(scene)
    cam = Camera.orbit(scene.center, scene.radius, 30.0, 25.0, 3.0)
    vp = (200, 160)
    view, proj = r.matrices(cam, vp)
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    eye = np.asarray(cam.eye, float) - np.asarray(cam.target, float)
    front, back = corners[np.argmax(corners @ eye)], corners[np.argmin(corners @ eye)]

    def pixel(p):
        clip = proj @ view @ np.append(p - scene.origin, 1.0)
        return ((clip[:2] / clip[3] + 1) / 2 * np.array(vp)).astype(int)

    x, y = pixel(front)
    point, oid, snapped = point_at(r, cam, vp, int(x) + 2, int(y) - 2)
    assert snapped and oid == 0 and np.allclose(point, front)
    x, y = pixel(back)
    point, _, snapped = point_at(r, cam, vp, int(x), int(y))
    assert not snapped and np.linalg.norm(point - back) > 0.5 and np.abs(point).max() == pytest.approx(1.0, abs=0.02)
    assert point_at(r, cam, vp, 1, 1) is None


def test_bench_times_a_ghosted_mode_as_itself():
    """`rtta-view --bench` on the demo (nothing highlighted): the ghosted row composites and
    draws no STD, so the first view's solid shading never stands in for the mode timed."""
    from test_viewer import RTTA_VIEW

    proc = subprocess.run(
        [RTTA_VIEW, "--bench", "2", "--bench-modes", "ghosted", "--size", "320x200"],  # 2: the view moves
        env=_env(None, headless=False),
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    lines = proc.stdout.splitlines()
    header = [c.strip() for c in next(ln for ln in lines if ln.startswith("| mode")).split("|")]
    row = [c.strip() for c in next(ln for ln in lines if ln.startswith("| ghosted |")).split("|")]
    assert float(row[header.index("composite")]) > 0 and float(row[header.index("std")]) == 0
