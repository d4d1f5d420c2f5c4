"""`rtta.snapshot` / `rtta.capture`: pixel for pixel what `rtta snapshot` / `rtta export` write,
one context and a flat GL census over many calls, and the CLI's error messages."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import rtta
from rtta.bench.compare import near_edges
from rtta.bench.reliability import gl_census
from rtta.cli.main import main
from rtta.renderer import api
from rtta.renderer.snapshot import SNAPSHOT_MODES, over_background
from rtta.scene.camera import Camera
from rtta.scene.generators.demo import demo_path
from rtta.scene.generators.generate import random_scene

RTTA = str(Path(sys.executable).with_name("rtta"))
ORBIT, SIZE = (60.0, 20.0, 2.0), (160, 120)
FOCUS = ["caliper", "piston_1"]
CLI_VIEW = [
    "--camera",
    "60,20,2",
    "--size",
    "160x120",
    "--focus",
    *FOCUS,
    "--opacity",
    "rotor=0.4",
    "--context-opacity",
    "0.2",
    "--edge-width",
    "2",
    "--ao-radius",
    "4",
]
API_VIEW = {
    "camera": ORBIT,
    "size": SIZE,
    "focus": FOCUS,
    "opacity": {"rotor": 0.4},
    "context_opacity": 0.2,
    "edge_width": 2,
    "ao_radius": 4,
}


@pytest.fixture(autouse=True, scope="module")
def _release_api():
    """The API keeps a renderer between calls: give its GPU resources back after this module."""
    yield
    api.release()


def _png(path) -> np.ndarray:
    return np.asarray(Image.open(path).convert("RGBA"))


@pytest.mark.parametrize("mode", SNAPSHOT_MODES)
def test_snapshot_equals_the_cli_png(gl, tmp_path, mode):
    out = tmp_path / f"{mode}.png"
    assert main(["snapshot", "--mode", mode, *CLI_VIEW, "--out", str(out)]) == 0
    image = rtta.snapshot(None, mode, **API_VIEW)
    assert image.dtype == np.uint8 and image.shape == (SIZE[1], SIZE[0], 4) and image.flags.c_contiguous
    assert np.array_equal(image, _png(out))


def test_snapshot_equals_the_installed_command_for_every_mode(gl, tmp_path):
    """The same through `rtta snapshot --all-modes` in its own process (and its own context)."""
    subprocess.run([RTTA, "snapshot", *CLI_VIEW, "--all-modes", str(tmp_path)], check=True, capture_output=True)
    for mode in SNAPSHOT_MODES:
        assert np.array_equal(rtta.snapshot(mode=mode, **API_VIEW), _png(tmp_path / f"{mode}.png")), mode


def test_row_zero_is_the_top(make_renderer, demo_scene):
    """The Renderer reads GL rows (row 0 at the bottom); snapshot gives them as an image."""
    image = rtta.snapshot(mode="std", camera=ORBIT, size=(96, 64))
    r = make_renderer(demo_scene)
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, *ORBIT)
    bottom_first = over_background(r.std(cam, (96, 64)).read((96, 64), 1)["color"][0])
    assert np.array_equal(image, bottom_first[::-1]) and not np.array_equal(image, bottom_first)


def test_scene_object_path_and_demo_agree(gl, demo_scene):
    kw = {"mode": "ghosted", "camera": ORBIT, "size": (96, 64), "focus": ["hub"]}
    by_default = rtta.snapshot(**kw)
    assert np.array_equal(rtta.snapshot(str(demo_path()), **kw), by_default)
    assert np.array_equal(rtta.snapshot(demo_scene, **kw), by_default)
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, *ORBIT)
    assert np.array_equal(rtta.snapshot(demo_scene, **{**kw, "camera": cam}), by_default)


def test_lens_and_projector_as_the_cli(gl, tmp_path):
    out = tmp_path / "lens.png"
    argv = [
        "--camera",
        "60,20,2",
        "--size",
        "128x96",
        "--focus",
        "piston_1",
        "--lens",
        "sphere",
        "--projector",
        "default,10,30,3",
        "--projector-fov",
        "40",
    ]
    assert main(["snapshot", "--mode", "ghosted", *argv, "--out", str(out)]) == 0
    image = rtta.snapshot(
        mode="ghosted",
        camera=ORBIT,
        size=(128, 96),
        focus="piston_1",
        lens="sphere",
        projector="default,10,30,3",
        projector_fov=40,
    )
    assert np.array_equal(image, _png(out))
    plain = rtta.snapshot(mode="ghosted", camera=ORBIT, size=(128, 96), focus="piston_1")
    assert not np.array_equal(plain, image)  # a later call without them has neither


def test_200_calls_keep_one_context_and_leak_no_gl_objects(gl, monkeypatch):
    other = random_scene(6, seed=3)

    def call(i: int) -> None:
        elsewhere = i % 40 == 20  # switch scenes now and then: the old renderer is freed
        mode = SNAPSHOT_MODES[i % len(SNAPSHOT_MODES)]
        rtta.snapshot(
            other if elsewhere else None,
            mode,
            focus=[] if elsewhere else FOCUS,
            camera=(i * 7.0 % 360, 25, 2.2),
            size=(96, 64),
        )
        if i % 25 == 0:
            rtta.capture(camera=(i, 20, 2.0), size=(96, 64))

    for i in range(160, 200):  # the loop's last stretch first: the passes it leaves made exist now
        call(i)
    assert gl.error == "GL_NO_ERROR"
    before = gl_census(gl)

    def no_new_context(*args, **kwargs):
        raise AssertionError("a second context was created")

    monkeypatch.setattr("moderngl.create_standalone_context", no_new_context)
    monkeypatch.setattr("moderngl.create_context", no_new_context)
    monkeypatch.setattr("rtta.gl.context.create_headless_context", no_new_context)
    for i in range(200):
        call(i)
    assert api.context() is gl and api._session.renderer.ctx is gl
    assert gl_census(gl) == before
    assert len(api._session.scenes) <= api.SCENE_CACHE


@pytest.fixture(scope="module")
def exported(tmp_path_factory, ctx):
    out = tmp_path_factory.mktemp("api") / "demo"
    assert main(["export", "--out", str(out), "--size", "200x150", "--camera", "35,25,2.2", "--border", "2"]) == 0
    return out


def test_capture_equals_the_export(gl, exported):
    cap = rtta.capture(camera=(35, 25, 2.2), size=(200, 150), border=2)
    rec = json.loads((exported / "records.json").read_text())
    tw, th, layers = rec["atlas"]
    assert cap.color.shape == (layers, th, tw, 4) and cap.color.dtype == np.uint8
    assert cap.depth.dtype == np.float32 and cap.id.dtype == np.int32
    assert np.array_equal(cap.depth, np.load(exported / "atlas_depth.npy"))
    assert np.array_equal(cap.id, np.load(exported / "atlas_id.npy"))
    for k in range(layers):
        assert np.array_equal(cap.color[k][::-1], _png(exported / f"atlas_color_{k}.png"))
    assert np.array_equal(cap.std_color[::-1], _png(exported / "std_color.png"))
    assert np.array_equal(cap.std_depth, np.load(exported / "std_depth.npy"))
    assert np.array_equal(cap.std_id, np.load(exported / "std_id.npy"))
    assert list(cap.viewport) == rec["viewport"] and cap.border == rec["border"] == 2
    assert np.array_equal(cap.view, rec["view"]) and np.array_equal(cap.proj, rec["proj"])
    for obj in rec["objects"]:
        oid = obj["id"]
        assert cap.names[oid] == obj["name"] and cap.index(obj["name"]) == oid
        assert bool(cap.visible[oid]) == obj["visible"] and int(cap.layer[oid]) == obj["layer"]
        assert cap.viewport_rect[oid].tolist() == obj["viewport_rect"]
        assert cap.atlas_rect[oid].tolist() == obj["atlas_rect"] and float(cap.scale[oid]) == obj["scale"]


def test_amodal_mask_of_a_hidden_object_is_its_id_region(gl, make_renderer, demo_scene):
    """piston_1 is hidden inside the caliper (absent from STD); mapped back from the atlas it is
    whole, and its mask equals the object rendered alone, except within 1 px of its outline."""
    cap = rtta.capture(camera=(35, 25, 2.2), size=(200, 150))
    oid = cap.index("piston_1")
    assert cap.visible[oid] and not (cap.std_id == oid).any()
    m = cap.amodal("piston_1")
    assert set(np.unique(m["id"]).tolist()) == {-1, oid}
    mask = m["id"] == oid
    assert np.array_equal(mask, m["depth"] < 1.0) and np.array_equal(mask, m["color"][..., 3] == 255)
    region = cap.region(oid)
    assert region["id"].shape == tuple(cap.atlas_rect[oid, [3, 2]])
    assert (region["id"] == oid).sum() == mask.sum()  # scale 1: every texel maps to one pixel
    r = make_renderer(demo_scene)
    alone = []
    r.rtt(cap.camera, cap.viewport, [oid], lambda _, target: alone.append(target.read(cap.viewport, 1)["id"][0]))
    rtt_mask = alone[0] == oid
    assert rtt_mask.sum() > 50 and not (mask != rtt_mask)[~near_edges(rtt_mask)].any()


def test_unknown_names_and_bad_options_say_what_is_wrong(gl):
    with pytest.raises(rtta.RttaError, match="no object named 'calipr'.*did you mean caliper"):
        rtta.snapshot(focus=["calipr"], size=(32, 32))
    with pytest.raises(rtta.RttaError, match="no object named 'rotr'.*did you mean rotor"):
        rtta.snapshot(opacity={"rotr": 0.5}, size=(32, 32))
    with pytest.raises(rtta.RttaError, match="mode must be one of .* got 'ghost'; did you mean ghosted"):
        rtta.snapshot(mode="ghost")
    with pytest.raises(TypeError, match="ao_radus.*did you mean ao_radius"):
        rtta.snapshot(ao_radus=3)
    with pytest.raises(rtta.RttaError, match="context-opacity must be in"):
        rtta.snapshot(context_opacity=2.0, size=(32, 32))
    with pytest.raises(rtta.RttaError, match="size 0x10"):
        rtta.snapshot(size=(0, 10))
    with pytest.raises(rtta.RttaError, match="--camera expects AZ,EL,DIST"):
        rtta.capture(camera=(1, 2, 3, 4), size=(32, 32))
    with pytest.raises(rtta.RttaError, match="no object named 'nope'"):
        rtta.capture(size=(32, 32)).index("nope")
    with pytest.raises(rtta.RttaError):
        rtta.snapshot("/nonexistent/scene.glb")


def test_public_face():
    assert {"snapshot", "capture", "Capture", "Renderer", "Scene", "RttaError"} <= set(rtta.__all__)
    assert all(hasattr(rtta, name) for name in rtta.__all__)
    assert callable(rtta.snapshot) and rtta.Capture is api.Capture
