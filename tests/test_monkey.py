"""The viewer's monkey (issue 42): short seeded runs of tests/viewer_monkey.py on the real
window under Xvfb, one per scene (the demo, an engine assembly, 20,000 generated parts),
and the regressions of what the monkey found. The long runs (scripts/monkey.py) are
recorded in docs/reliability.md."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from test_viewer import HERE, _env, display  # noqa: F401  (the Xvfb fixture)

from rtta.scene.generators.demo import demo_path

TOUR = 25  # the monkey's warm-up tour: every action once (viewer_monkey.Monkey.tour)


def run_monkey(display: str | None, folder: Path, scene: str, seed: int, actions: int) -> dict:  # noqa: F811
    """One monkey run in `folder` (its own current folder and cache); its result.json."""
    env = {**_env(display), "RTTA_CACHE_DIR": str(folder / "cache")}
    args = [str(folder / "run"), "--scene", scene, "--seed", str(seed), "--actions", str(actions), "--warmup", "0.4"]
    proc = subprocess.run(
        [sys.executable, str(HERE / "viewer_monkey.py"), *args],
        env=env,
        cwd=folder,
        capture_output=True,
        text=True,
        errors="replace",
        timeout=600,
    )
    result = json.loads((folder / "run" / "result.json").read_text())
    assert proc.returncode == 0, (result["findings"], proc.stderr[-3000:])
    assert "Traceback" not in proc.stderr, proc.stderr[-3000:]
    return result


@pytest.mark.viewer
@pytest.mark.slow  # measured on 2 busy cores: demo 25 s, engine 30 s, large 55 s
@pytest.mark.parametrize(("scene", "seed", "actions"), [("demo", 1, 160), ("engine", 2, 80), ("large", 3, 45)])
def test_monkey_finds_nothing(display, tmp_path, scene, seed, actions):  # noqa: F811
    """A seeded random stream of user actions: no exception, GL error, camera that is not
    finite or frame over 10 s; GL objects, their storage and RSS after the warm-up within 5%."""
    r = run_monkey(display, tmp_path, scene, seed, actions)
    assert r["findings"] == [] and r["actions"] == actions
    assert set(r["by_action"]) >= {"orbit", "key", "click_panel", "open", "drop", "cutaway", "views", "measure"}
    assert set(r["by_action"]) >= {"cube", "section_surface", "section_handle", "section_panel"}
    assert r["frames"] > actions and r["max_frame_s"] < 10
    assert r["reached"]["scenes"] + r["reached"]["errors_said"] > 0  # a file opened or refused
    assert len(r["settled"]) >= 2 and all(s["gl"]["programs"] > 0 and s["gl_mb"] > 1 for s in r["settled"])
    assert r["objects"] == (20_000 if scene == "large" else r["objects"]) and r["objects"] > 1


@pytest.mark.viewer
@pytest.mark.slow
def test_scene_file_named_in_bytes_that_are_not_utf8(display, tmp_path):  # noqa: F811
    """Found by the monkey: a scene file whose name is not UTF-8 (os.fsdecode's stand-ins)
    raised TypeError from imgui in the panel's title line on every frame."""
    scene = Path(shutil.copy(demo_path(), tmp_path / os.fsdecode(b"caf\xe9 demo.glb")))
    r = run_monkey(display, tmp_path, str(scene), 5, TOUR)
    assert r["findings"] == [] and r["frames"] > TOUR


def test_file_browser_lists_names_that_are_not_utf8(tmp_path):
    """Found by the monkey: the file browser listing a file or folder whose name is not
    UTF-8 raised TypeError from imgui.selectable on every frame it was open."""
    from imgui_bundle import imgui

    from viewer.files import FileBrowser, listing

    (tmp_path / os.fsdecode(b"caf\xe9.glb")).write_bytes(b"")
    (tmp_path / os.fsdecode(b"na\xefve")).mkdir()
    assert [len(found) for found in listing(tmp_path)] == [1, 1]
    ctx = imgui.create_context()
    try:
        io = imgui.get_io()
        io.display_size = imgui.ImVec2(800, 600)
        io.set_ini_filename("")
        io.fonts.build()  # what a renderer backend does
        browser = FileBrowser(lambda path: None)
        browser.open(tmp_path)
        for _ in range(3):
            imgui.new_frame()
            browser.draw()  # raised TypeError before
            imgui.render()
        assert browser.visible
    finally:
        imgui.destroy_context(ctx)


def test_a_plane_placed_on_a_surface_clears_the_miss_before(monkeypatch):
    """Found while checking the monkey's section actions: after a click on the background
    ('section: no surface there'), a plane then placed on a surface left that error shown."""
    from types import SimpleNamespace

    from viewer import cutaway

    app = SimpleNamespace(message="", state=SimpleNamespace(cutaway=cutaway.CutawayState(picking=True)))
    app.say = lambda text, error=False: setattr(app, "message", text)
    found = iter([None, ((0.0, 0.0, 2.0), (0.0, 0.0, 1.0))])
    monkeypatch.setattr(cutaway, "surface_plane", lambda *a: next(found))
    assert not cutaway.place_at(app, 1, 1) and app.message == cutaway.NO_SURFACE
    app.state.cutaway.picking = True
    assert cutaway.place_at(app, 2, 2) and app.message == ""
    assert app.state.cutaway.normal == (0.0, 0.0, 1.0) and app.state.cutaway.offset == 2.0
