"""`rtta export`: the documented format, checked with numpy from the files alone."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from rtta.cli.main import main
from rtta.scene.generators.demo import demo_path
from rtta.scene.loader import load_scene

RTTA = str(Path(sys.executable).with_name("rtta"))


@pytest.fixture(scope="module", params=["perspective", "ortho"])
def exported(tmp_path_factory, ctx, request):
    out = tmp_path_factory.mktemp("exp") / "demo"
    args = ["export", "--out", str(out), "--size", "320x240", "--camera", "35,25,2.2", "--border", "2"]
    assert main([*args, "--projection", request.param]) == 0
    assert ctx.error == "GL_NO_ERROR"
    assert json.loads((out / "records.json").read_text())["camera"]["projection"] == request.param
    return out


def test_files_and_shapes(exported):
    rec = json.loads((exported / "records.json").read_text())
    tw, th, layers = rec["atlas"]
    assert rec["viewport"] == [320, 240] and layers >= 1
    depth = np.load(exported / "atlas_depth.npy")
    ids = np.load(exported / "atlas_id.npy")
    assert depth.dtype == np.float32 and depth.shape == (layers, th, tw)
    assert ids.dtype == np.int32 and ids.shape == (layers, th, tw)
    assert ((ids == -1) == (depth == 1.0)).mean() > 0.999
    for k in range(layers):
        assert Image.open(exported / f"atlas_color_{k}.png").size == (tw, th)
    assert np.load(exported / "std_depth.npy").shape == (240, 320)
    assert [o["id"] for o in rec["objects"]] == list(range(len(rec["objects"])))


def test_png_rows_are_top_first(exported):
    std_id = np.load(exported / "std_id.npy")
    alpha = np.asarray(Image.open(exported / "std_color.png"))[..., 3]
    assert np.array_equal(alpha[::-1] > 0, std_id >= 0)


def test_view_and_proj_place_objects_in_their_viewport_rects(exported):
    rec = json.loads((exported / "records.json").read_text())
    scene = load_scene(demo_path())
    view, proj = np.array(rec["view"]), np.array(rec["proj"])
    W, H = rec["viewport"]
    world = scene.positions.astype(np.float64) + scene.origin
    clip = np.c_[world, np.ones(len(world))] @ (proj @ view).T
    ndc = clip[:, :2] / clip[:, 3:4]
    px = (ndc + 1) / 2 * [W, H]
    for obj in rec["objects"]:
        if not obj["visible"]:
            continue
        mine = px[scene.object_ids == obj["id"]]
        x0, y0, x1, y1 = obj["viewport_rect"]
        inside_view = (mine >= 0).all(1) & (mine <= [W, H]).all(1)
        p = mine[inside_view]
        assert (p[:, 0] >= x0 - 1e-3).all() and (p[:, 0] <= x1 + 1e-3).all(), obj["name"]
        assert (p[:, 1] >= y0 - 1e-3).all() and (p[:, 1] <= y1 + 1e-3).all(), obj["name"]


def test_std_is_the_front_most_of_the_exported_atlas(exported):
    """Re-implements the mapping from docs/library.md: atlas = atlas_rect.xy + border + scale*(px - rect.xy)."""
    rec = json.loads((exported / "records.json").read_text())
    depth, ids = np.load(exported / "atlas_depth.npy"), np.load(exported / "atlas_id.npy")
    std_id, std_depth = np.load(exported / "std_id.npy"), np.load(exported / "std_depth.npy")
    b = rec["border"]
    best_d = np.ones_like(std_depth)
    best_id = np.full_like(std_id, -1)
    for obj in rec["objects"]:
        if not obj["visible"]:
            continue
        x0, y0, x1, y1 = obj["viewport_rect"]
        ax, ay = obj["atlas_rect"][:2]
        s = obj["scale"]
        tx = np.floor(ax + b + s * (np.arange(x0, x1) + 0.5 - x0)).astype(int)
        ty = np.floor(ay + b + s * (np.arange(y0, y1) + 0.5 - y0)).astype(int)
        d = depth[obj["layer"]][ty[:, None], tx[None, :]]
        i = ids[obj["layer"]][ty[:, None], tx[None, :]]
        sub_d, sub_i = best_d[y0:y1, x0:x1], best_id[y0:y1, x0:x1]
        closer = (i == obj["id"]) & (d < sub_d)
        sub_d[closer], sub_i[closer] = d[closer], i[closer]
    agree = (best_id == std_id).mean()
    assert agree > 0.995
    both = (best_id == std_id) & (std_id >= 0)
    assert np.median(np.abs(best_d - std_depth)[both]) < 1e-6


def test_existing_output_is_replaced_whole(tmp_path):
    """An earlier export (recognised by its records.json) is replaced whole; a folder rtta did
    not write, or one holding files an export does not write, is refused and left as it was."""
    out = tmp_path / "out"
    assert main(["export", "--out", str(out), "--size", "32x24"]) == 0
    (out / "atlas_color_7.png").write_bytes(b"stale layer of an earlier export")
    assert main(["export", "--out", str(out), "--size", "64x48"]) == 0
    assert not (out / "atlas_color_7.png").exists()
    assert json.loads((out / "records.json").read_text())["viewport"] == [64, 48]
    assert [p.name for p in tmp_path.iterdir()] == ["out"]  # no temporary folders left
    (out / "notes.txt").write_text("mine")
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "old.txt").write_text("old")
    for folder in (out, mine):
        assert main(["export", "--out", str(folder), "--size", "64x48"]) == 2
    assert (out / "notes.txt").read_text() == "mine" and (mine / "old.txt").read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine", "out"]


def _run(args, cwd):
    return subprocess.run([RTTA, *args], cwd=cwd, capture_output=True, text=True, timeout=120)


@pytest.mark.parametrize(
    "args,needle",
    [
        (["export", "missing.glb", "--out", "o"], "missing.glb: no such file"),
        (["export", "bad.glb", "--out", "o"], "bad.glb: GLB file is truncated"),
        (["export", "--out", "o", "--size", "12by4"], "--size expects WxH"),
        (["export", "--out", "o", "--camera", "1,2,3,4"], "--camera expects AZ,EL,DIST"),
        (["export", "--out", "o", "--camera", "1,x"], "--camera '1,x': AZ and EL must be finite"),
        (["export", "--out", "o", "--view", "top", "--camera", "1,2"], "--view top and --camera both"),
        (["export", "--out", "o", "--projection", "fisheye"], "--projection"),
        (["export", "--out", "o", "--border", "-1"], "--border must be"),
        (["export", "--out", "o", "--atlas-max", "0x0"], "--atlas-max"),
    ],
)
def test_bad_input_exits_2_with_one_line(tmp_path, args, needle):
    (tmp_path / "bad.glb").write_bytes(b"glTF garbage")
    (tmp_path / "o").mkdir()  # an earlier export: may be replaced, not on error
    (tmp_path / "o" / "records.json").write_text("{}")
    (tmp_path / "o" / "std_color.png").write_text("mine")
    res = _run(args, tmp_path)
    assert res.returncode == 2, res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and needle in lines[0] and "Traceback" not in res.stderr
    assert (tmp_path / "o" / "std_color.png").read_text() == "mine"


def test_runs_from_another_directory(tmp_path):
    res = _run(["export", "--out", "x", "--size", "96x64"], tmp_path)
    assert res.returncode == 0, res.stderr
    assert (tmp_path / "x" / "atlas_color_0.png").exists()
    res = _run(["info"], tmp_path)
    assert res.returncode == 0 and "rotor" in res.stdout


def test_snapshot_all_modes(tmp_path):
    res = _run(["snapshot", "--all-modes", "shots", "--size", "96x72", "--focus", "pad_inner"], tmp_path)
    assert res.returncode == 0, res.stderr
    names = sorted(p.name for p in (tmp_path / "shots").iterdir())
    assert names == sorted(f"{m}.png" for m in ("std", "sprites", "transparent", "ghosted", "ghosted-ao"))
    assert Image.open(tmp_path / "shots" / "ghosted.png").size == (96, 72)


@pytest.mark.parametrize(
    "args,needle",
    [
        (["snapshot", "--out", "a.png", "--focus", "pad_iner"], "did you mean pad_inner"),
        (["snapshot", "--out", "a.png", "--mode", "xray"], "--mode must be one of"),
        (["snapshot", "--out", "a.png", "--opacity", "rotor=2"], "--opacity expects NAME=A"),
        (["snapshot", "--out", "a.gif"], "--out must name a .png, .jpg"),
        (["snapshot", "--out", "nowhere/a.png"], "parent directory does not exist"),
    ],
)
def test_snapshot_bad_input(tmp_path, args, needle):
    res = _run(args, tmp_path)
    assert res.returncode == 2 and needle in res.stderr and "Traceback" not in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize("suffix, kind", [(".jpg", "JPEG"), (".JPEG", "JPEG"), (".webp", "WEBP"), (".tiff", "TIFF")])
def test_snapshot_writes_the_format_its_suffix_names(tmp_path, gl, suffix, kind):
    """--out a.jpg, .webp, .tif: the format by the suffix (only PNG was taken), the same picture:
    WebP and TIFF losslessly, JPEG within its compression (RGB, no alpha)."""
    png, other = tmp_path / "a.png", tmp_path / f"a{suffix}"
    for out in (png, other):
        assert main(["snapshot", "--size", "96x72", "--mode", "ghosted", "--focus", "hub", "-o", str(out)]) == 0
    with Image.open(other) as im:
        assert im.format == kind and im.size == (96, 72)
        got = np.asarray(im.convert("RGB")).astype(int)
    want = np.asarray(Image.open(png).convert("RGB")).astype(int)
    if kind == "JPEG":
        assert np.abs(got - want).mean() < 3
    else:
        assert np.array_equal(got, want)
