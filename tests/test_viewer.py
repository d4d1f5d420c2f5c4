"""The viewer: orbit maths, panel state and layout in numpy; picking against the atlas on
EGL; and the real window under Xvfb driven with synthetic input (tests/viewer_driver.py)."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from rtta.errors import printable
from rtta.gl.readback import front_most
from rtta.passes.picking import objects_at, pick
from rtta.scene.camera import DEFAULT_ORBIT, Camera
from viewer.orbit import MAX_ELEVATION, Orbit
from viewer.state import ViewerState
from viewer.views import Layout, atlas_rects_on_screen, layer_tiles

HERE = Path(__file__).parent
RTTA_VIEW = str(Path(sys.executable).with_name("rtta-view"))  # the installed entry point users run


def project(cam: Camera, p, aspect: float) -> np.ndarray:
    clip = cam.projection(aspect) @ cam.view(np.zeros(3)) @ np.append(p, 1.0)
    return clip[:2] / clip[3]


def test_orbit_never_flips_at_the_poles():
    o = Orbit.default(np.zeros(3), 1.0)
    for _ in range(50):
        o.rotate(0, 100)  # far past the pole
        cam = o.camera()
        assert o.el <= MAX_ELEVATION and np.dot(cam.up, [0, 1, 0]) > 0
    assert np.all(np.isfinite(o.camera().view(np.zeros(3))))


def test_zoom_keeps_the_point_under_the_cursor():
    o = Orbit.default(np.array([1.0, 2.0, 3.0]), 2.0)
    aspect, ndc = 1.5, (0.4, -0.3)
    cam = o.camera()
    right, up = o._axes()
    half = o.dist * np.tan(np.radians(o.fov_y) / 2)
    p = o.target + (ndc[0] * aspect * right + ndc[1] * up) * half
    assert np.allclose(project(cam, p, aspect), ndc)
    o.zoom(3, ndc, aspect)
    assert o.dist < 2.2 * 2.0 * 0.7
    assert np.allclose(project(o.camera(), p, aspect), ndc, atol=1e-9)


def test_pan_moves_the_scene_with_the_cursor():
    o = Orbit.default(np.zeros(3), 1.0)
    height = 600
    before = project(o.camera(), np.zeros(3), 1.0)
    o.pan(30, -60, height)  # right 30 px, up 60 px (y down)
    after = project(o.camera(), np.zeros(3), 1.0)
    assert np.allclose((after - before) * height / 2, [30, 60], atol=1e-6)


def test_frame_and_orbit_around():
    o = Orbit.default(np.zeros(3), 1.0)
    o.zoom(-20)
    o.frame()
    cam = o.camera()
    for axis in np.eye(3):  # the bounding sphere's extreme points are in view
        for p in (axis, -axis):
            assert np.all(np.abs(project(cam, p, 1.0)) <= 1.0)
    eye = cam.eye.copy()
    o.orbit_around([0.5, 0.2, -0.1])
    assert np.allclose(o.camera().eye, eye) and np.allclose(o.target, [0.5, 0.2, -0.1])


def test_state_filter_and_bulk_selection():
    s = ViewerState(["pad_inner", "pad_outer", "disc", "Piston_1"])
    s.filter = "PAD"
    assert s.filtered() == [0, 1]
    s.select("all")
    assert s.highlighted == {0, 1}
    s.toggle(3)
    s.select("invert")
    assert s.highlighted == {3}
    s.filter = ""
    s.select("none")
    assert s.highlighted == set()
    key = s.style_key()
    s.style.opacity[2] = 0.2
    assert s.style_key() != key
    with pytest.raises(ValueError):
        ViewerState([], mode="nope")


def test_layout_and_atlas_tiles():
    lay = Layout.of((1280, 720), True)
    assert lay.panel[2] + lay.composite[2] + lay.atlas[2] == 1280
    assert Layout.of((1280, 720), False).atlas[2] == 0 and Layout.of((0, 0), True).composite[2] == 0
    tiles = layer_tiles((900, 20, 380, 700), (600, 700), 3, -1)
    assert [k for k, _ in tiles] == [0, 1, 2]
    boxes = [(x, y, x + w, y + h) for _, (x, y, w, h) in tiles]
    for i, a in enumerate(boxes):  # inside the view, not overlapping
        assert a[0] >= 900 and a[1] >= 20 and a[2] <= 1280 and a[3] <= 720
        for b in boxes[i + 1 :]:
            assert a[2] <= b[0] or b[2] <= a[0] or a[3] <= b[1] or b[3] <= a[1]
    # a full-extent region covers its whole tile; y flips (atlas rows count from the bottom)
    ((_, rect),) = layer_tiles((0, 0, 100, 100), (50, 100), 1, 0)
    assert np.allclose(atlas_rects_on_screen([[0, 0, 50, 100]], (50, 100), rect), [[25, 0, 75, 100]])
    assert np.allclose(atlas_rects_on_screen([[0, 0, 10, 10]], (50, 100), rect), [[25, 90, 35, 100]])


def test_picking_finds_hidden_objects_and_front_most(make_renderer, demo_scene):
    """objects_at's nearest hit equals the front-most id mapped back from the whole atlas;
    a preferred (highlighted) object behind it is found too; reading only the candidates'
    texels from the target gives the same hits."""
    r = make_renderer(demo_scene)
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, *DEFAULT_ORBIT)
    rec = r.capture(cam, (160, 120))
    atlas = r.atlas.read(rec.atlas_size[:2], rec.atlas_size[2], parts=("id", "depth"))
    front = front_most(atlas, rec)["id"]
    rng = np.random.default_rng(3)
    occluded = 0
    for x, y in zip(rng.integers(0, 160, 300), rng.integers(0, 120, 300), strict=True):
        hits = objects_at(atlas, rec, int(x), int(y))
        assert (hits[0][0] if hits else -1) == front[y, x]
        assert objects_at(r.atlas, rec, int(x), int(y)) == hits  # the candidates' texels read alone
        assert [h[1] for h in hits] == sorted(h[1] for h in hits)
        if len(hits) > 1:
            occluded += 1
            assert pick(hits, {hits[-1][0]}) == hits[-1][0] and pick(hits) == hits[0][0]
    assert occluded > 20
    assert objects_at(atlas, rec, -1, 5) == [] and pick([]) is None


@pytest.fixture(scope="module")
def display():
    """An X display: the one given, or a fresh Xvfb (the test starts it; CI has none). With
    RTTA_TEST_HEADLESS=1, none: the viewer runs in pyglet's headless window through EGL, as
    on a GPU server without X (scripts/bench_device.sh)."""
    if os.environ.get("RTTA_TEST_HEADLESS"):
        yield None
        return
    if os.environ.get("DISPLAY"):
        yield os.environ["DISPLAY"]
        return
    xvfb = shutil.which("Xvfb")
    assert xvfb, "Xvfb is missing: scripts/setup.sh installs it (package xvfb)"
    r, w = os.pipe()
    proc = subprocess.Popen(
        [xvfb, "-displayfd", str(w), "-screen", "0", "1920x1080x24", "-nolisten", "tcp"],
        pass_fds=(w,),
        stderr=subprocess.DEVNULL,
    )
    os.close(w)
    with os.fdopen(r) as f:
        number = f.readline().strip()
    assert number, "Xvfb did not start"
    yield f":{number}"
    proc.terminate()
    proc.wait(10)


def _env(display: str | None, headless: bool = True) -> dict:
    """The environment with `display`; with none, pyglet headless under RTTA_TEST_HEADLESS."""
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY", "PYGLET_HEADLESS")}
    if display:
        env["DISPLAY"] = display
    elif headless and os.environ.get("RTTA_TEST_HEADLESS"):
        env["PYGLET_HEADLESS"] = "true"
    return env


def run_driver(
    display: str | None,
    out: Path,
    script: str,
    *args: str,
    timeout: int = 300,
    cwd: Path | None = None,
    env: dict | None = None,
) -> tuple[dict, dict]:
    """Run a viewer driver script (tests/viewer_*driver.py) into `out` under the Xvfb display, from
    `cwd`, `env` added; its result.json and its screenshots (name -> RGB array)."""
    proc = subprocess.run(
        [sys.executable, str(HERE / script), str(out), *args],
        env={**_env(display), **(env or {})},
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=timeout,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    result = json.loads((out / "result.json").read_text())
    shots = {p.stem: np.asarray(Image.open(p).convert("RGB")) for p in out.glob("*.png")}
    return result, shots


def _region(img: np.ndarray, rect) -> np.ndarray:
    x, y, w, h = rect
    return img[y : y + h, x : x + w, :3].astype(int)


@pytest.fixture(scope="module")
def driven(display, tmp_path_factory):
    return run_driver(display, tmp_path_factory.mktemp("viewer"), "viewer_driver.py")


def test_window_draws_panel_and_both_views(driven):
    result, shots = driven
    lay, img = result["layout"], shots["start"]
    panel, comp, atlas = (_region(img, lay[k]) for k in ("panel", "composite", "atlas"))
    assert panel.std() > 20  # text and widgets on the panel
    bg = np.array([0.93, 0.93, 0.95]) * 255
    assert (np.abs(comp - bg).max(-1) > 10).mean() > 0.1  # the scene over the background
    atlas_bg = np.array([0.16, 0.16, 0.18]) * 255
    assert (np.abs(atlas - atlas_bg).max(-1) > 10).mean() > 0.1  # captured objects in the atlas
    assert result["gl_errors"] == []


def test_dragging_changes_the_view(driven):
    result, shots = driven
    rect = result["layout"]["composite"]
    changed = np.abs(_region(shots["start"], rect) - _region(shots["dragged"], rect)).max(-1) > 10
    assert changed.mean() > 0.05
    assert result["az1"] != result["az0"]


def test_highlight_toggles_change_the_composite(driven):
    result, shots = driven
    rect = result["layout"]["composite"]
    assert result["focus_after_checkbox"] == [result["checkbox_target"]]
    changed = np.abs(_region(shots["dragged"], rect) - _region(shots["highlight"], rect)).max(-1) > 10
    assert changed.sum() > 50
    # the click lands on the highlighted piston seen through the part in front of it
    assert result["front_most_at_piston"] != result["picked"] and result["focus_after_pick"] == []


def test_keys_wheel_files_and_resizes(driven):
    result, _ = driven
    assert all(result["keys_changed"].values()), result["keys_changed"]
    assert result["zoomed"] and result["mode_after_cycle"] == "ghosted-ao"
    assert len(result["screenshots"]) == 4 and len(set(result["screenshots"])) == 4
    assert result["open_bad"] is False and result["scene_kept"] and "broken.glb" in result["message"]
    assert result["after_resize"] == [1280, 720] and result["gl_errors"] == []


def test_files_open_on_a_worker_thread(driven):
    """A dropped 10,000-part file loads while the window keeps drawing frames; a second file
    meanwhile is refused with a line; a broken file opened the same way keeps the scene."""
    later = driven[0]["later"]
    assert later["message_at_start"] == "loading later.glb ..." and later["second_refused"]
    assert later["frames_while_loading"] >= 3, later
    assert later["count"] == 10_000 and not later["error"] and later["message"].startswith("opened later.glb")
    assert later["bad_error"] and "broken.glb" in later["bad_message"] and later["bad_kept"]


def test_projector_toggle_and_move(driven):
    result, shots = driven
    assert result["projector"]["on"] and not result["projector"]["attached"]
    rect = result["layout"]["composite"]
    unpainted, painted, moved = (_region(shots[k], rect) for k in ("unpainted", "painted", "projector_moved"))
    assert (np.abs(painted - unpainted).max(-1) > 10).mean() > 0.05  # the grid lands on the scene
    assert (np.abs(moved - painted).max(-1) > 10).mean() > 0.02  # and moves with the projector


def test_lens_cuts_and_follows_the_mouse(driven):
    result, shots = driven
    rect = result["layout"]["composite"]
    plain, cut, moved = (_region(shots[k], rect) for k in ("no_lens", "lens", "lens_moved"))
    assert (np.abs(cut - plain).max(-1) > 10).mean() > 0.02  # the context is cut away
    assert (np.abs(moved - cut).max(-1) > 10).mean() > 0.02  # where the mouse went
    assert result["lens_center_1"] != result["lens_center_2"]


def test_bad_input_corpus_in_the_viewer(driven):
    """Each corpus file opened in the running viewer: errors shown, the scene kept."""
    result, _ = driven
    cases = result["corpus"]
    assert len(cases) >= 150
    for name, c in cases.items():
        assert "\n" not in c["message"] and "\x1b" not in c["message"], (name, c["message"])
        if c["expect_error"]:
            assert not c["opened"] and c["error"] and c["kept"], name
            assert printable(c["path"]) in c["message"] and c["says"].lower() in c["message"].lower(), (
                name,
                c["message"],
            )
        else:
            assert c["opened"] and not c["error"] and c["says"] in c["message"], (name, c["message"])


def test_degraded_frames_are_said_in_the_panel(driven):
    """A view whose per-pixel order falls back to object order says so in the panel's
    message line (a warning, not an error), once."""
    result, _ = driven
    fb = result["fallback"]
    assert not fb["error"] and fb["message"].startswith("warning: per-pixel order would need more than 10")
    assert len([w for w in fb["warnings"] if "per-pixel order" in w]) == 1


def test_screenshot_that_cannot_be_written_says_so(driven):
    result, _ = driven
    bad = result["screenshot_bad_dir"]
    assert bad["written"] == [] and bad["error"] and "parent directory does not exist" in bad["message"]


def test_no_display_says_so_in_one_line():
    proc = subprocess.run([RTTA_VIEW], env=_env(None, headless=False), capture_output=True, text=True)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "rtta snapshot" in lines[0] and "Traceback" not in proc.stderr


def test_bench_without_a_display_runs_headless():
    """`--bench` needs no screen (a GPU server, CI): pyglet's headless window, through EGL."""
    proc = subprocess.run(
        [RTTA_VIEW, "--bench", "1", "--bench-modes", "ghosted", "--size", "320x200"],
        env=_env(None, headless=False),
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "headless window (EGL) 320x200" in proc.stdout
    (row,) = [ln for ln in proc.stdout.splitlines() if ln.startswith("| ghosted |")]
    assert float(row.split("|")[2]) > 0
    bad = subprocess.run([RTTA_VIEW, "--bench", "-1"], env=_env(None, headless=False), capture_output=True, text=True)
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "--bench" in bad.stderr, bad.stderr  # no NaN table


@pytest.mark.slow  # measured: 23-28 s for the five
@pytest.mark.parametrize("after", [0.8, 1.2, 1.6, 2.5, 8.0])
def test_ctrl_c_closes_the_viewer_quietly(after):
    """SIGINT from the terminal at any moment, from the imports through the scene's load to
    the frame loop (here in a headless window, so no X is needed): exit 130, no traceback.
    trimesh's imports catch BaseException: an interrupt there was swallowed and the viewer
    opened anyway, and one inside a native module's start could crash it (SIGSEGV)."""
    env = {**_env(None, headless=False), "PYGLET_HEADLESS": "true"}
    proc = subprocess.Popen(
        [RTTA_VIEW, "--size", "320x200"], env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    time.sleep(after)
    proc.send_signal(signal.SIGINT)
    try:
        out, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert proc.returncode == 130 and "Traceback" not in err, (proc.returncode, err[-2000:])


def test_bad_scene_on_the_command_line(display, tmp_path):
    bad = tmp_path / "scene.glb"
    bad.write_text("not a model")
    proc = subprocess.run([RTTA_VIEW, str(bad)], env=_env(display), capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and "scene.glb" in proc.stderr and "Traceback" not in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1


def test_bench_prints_every_mode(display):
    proc = subprocess.run(
        [RTTA_VIEW, "--bench", "1", "--size", "640x360"], env=_env(display), capture_output=True, text=True, timeout=300
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    rows = [ln for ln in proc.stdout.splitlines() if ln.startswith("| ") and not ln.startswith("| mode")]
    assert [r.split("|")[1].strip() for r in rows] == ["std", "sprites", "transparent", "ghosted", "ghosted-ao"]
    assert all(float(r.split("|")[2]) > 0 for r in rows)


SCALE_PARTS = 20_000


@pytest.fixture(scope="module")
def driven_large(display, tmp_path_factory):
    result, _ = run_driver(
        display, tmp_path_factory.mktemp("viewer_large"), "viewer_scale_driver.py", str(SCALE_PARTS), timeout=600
    )
    return result


def test_large_assembly_survives_every_interaction(driven_large):
    """20,000 parts: drag, wheel, typing into the filter, all / invert / none, a click pick,
    and a frame whose imgui draw list is far past moderngl-window's fixed buffers."""
    r = driven_large
    assert r["objects"] == SCALE_PARTS and r["visible"] > SCALE_PARTS // 2
    assert r["dragged"] and r["zoomed"]
    # fast navigation: parts left out while the camera moved (never the focus), every part at rest
    assert max(r["drag_left_out"]) > 0 and r["moving_focus_packed"]
    assert r["rest_left_out"] == 0 and r["rest_whole"]
    assert r["filter"] == "part0001" and r["filtered"] == 100  # part000100 .. part000199
    assert r["after_all"] == 100 and r["after_invert"] == 0
    assert r["filter_cleared"] == "" and r["all_everything"] == SCALE_PARTS and r["after_none"] == 0
    assert r["picked"] is not None and r["after_pick"] == [r["picked"]]
    assert r["capacity"][0] == 65536 and r["capacity"][1] > 65536  # the imgui buffers grew
    assert r["gl_errors"] == []
    # UI-only frames (no capture, no compositing) stay cheap at this size
    assert r["frame_ms"]["typing"] < 1000 and r["frame_ms"]["end"] < 1000
