"""The CAD viewer's basics in the library and the CLI (issue 45): orthographic projection,
standard views relative to the file's up axis, cameras fitted to the visible parts, rtta.pick
and `rtta info --tree`."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import trimesh

import rtta
from rtta.cli.info import tree_lines
from rtta.cli.main import main
from rtta.passes.composite import BACKGROUND
from rtta.scene.generators.demo import demo_path
from rtta.scene.loader import load_scene
from rtta.scene.model import from_meshes

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data"


def _boxes(*specs) -> rtta.Scene:
    """One box per (name, extents, centre)."""
    parts = []
    for name, extents, centre in specs:
        box = trimesh.creation.box(extents=extents)
        parts.append((name, np.asarray(box.vertices) + centre, np.asarray(box.faces), None))
    return from_meshes(parts)


def _glb(scene_parts, path: Path) -> Path:
    tm = trimesh.Scene()
    for name, extents, centre in scene_parts:
        box = trimesh.creation.box(extents=extents)
        box.apply_translation(centre)
        tm.add_geometry(box, node_name=name, geom_name=name)
    path.write_bytes(tm.export(file_type="glb"))
    return path


def _export(tmp_path: Path, scene_file: Path, *flags: str) -> dict:
    out = tmp_path / f"exp{len(list(tmp_path.iterdir()))}"
    assert main(["export", str(scene_file), "--out", str(out), "--size", "320x240", *flags]) == 0
    return json.loads((out / "records.json").read_text())


def test_ortho_keeps_equal_boxes_equal_at_different_depths(tmp_path, gl):
    """Two equal boxes, one 6 units further away: their exported B_viewport sizes agree within
    a pixel in ortho and differ in perspective."""
    glb = _glb([("near", (1, 1, 1), (-1.5, 0, 0)), ("far", (1, 1, 1), (1.5, 0, -6))], tmp_path / "two.glb")
    sizes = {}
    for projection in ("perspective", "ortho"):
        rec = _export(tmp_path, glb, "--view", "front", "--projection", projection)
        assert rec["camera"]["projection"] == projection
        rects = {o["name"]: np.array(o["viewport_rect"]) for o in rec["objects"]}
        sizes[projection] = {k: r[2:] - r[:2] for k, r in rects.items()}
    ortho, persp = sizes["ortho"], sizes["perspective"]
    assert np.abs(ortho["near"] - ortho["far"]).max() <= 1, ortho
    assert (persp["near"] - persp["far"]).min() >= 5, persp  # the far box is much smaller


def test_top_view_looks_down_the_files_up_axis(tmp_path, gl):
    """--view top: the exported view matrix's z row (towards the viewer) is the file's up axis,
    +Y for a glTF, +Z for a Z-up scene (CAD, BIM)."""
    glb = _glb([("a", (1, 2, 3), (0, 0, 0)), ("b", (1, 1, 1), (2, 0, 0))], tmp_path / "y_up.glb")
    rec = _export(tmp_path, glb, "--view", "top")
    assert np.allclose(np.array(rec["view"])[2, :3], [0, 1, 0], atol=1e-9)
    z_up = _boxes(("a", (1, 2, 3), (0, 0, 0)), ("b", (1, 1, 1), (2, 0, 0)))
    z_up.up_axis = "z"
    for view, axis in (("top", [0, 0, 1]), ("bottom", [0, 0, -1]), ("front", [0, -1, 0]), ("right", [1, 0, 0])):
        cap = rtta.capture(z_up, view=view, size=(64, 48))
        assert np.allclose(cap.view[2, :3], axis, atol=1e-9), view
    if (SHARED / "box_sides.STEP").exists():  # the workspace's STEP file (Z-up); CI has it
        rec = _export(tmp_path, SHARED / "box_sides.STEP", "--view", "top")
        assert np.allclose(np.array(rec["view"])[2, :3], [0, 0, 1], atol=1e-9)


def _check_framed(rgba: np.ndarray, what: str) -> None:
    background = np.rint(np.array(BACKGROUND[:3]) * 255)
    covered = np.abs(rgba[..., :3].astype(float) - background).max(-1) > 0
    assert covered.any(), what
    rows, cols = np.flatnonzero(covered.any(1)), np.flatnonzero(covered.any(0))
    h, w = covered.shape
    free = min(rows[0], h - 1 - rows[-1]) / h, min(cols[0], w - 1 - cols[-1]) / w
    assert min(free) >= 0.01, f"{what}: touches the border ({free})"
    spans = (rows[-1] - rows[0] + 1) / h, (cols[-1] - cols[0] + 1) / w
    assert max(spans) >= 0.6, f"{what}: spans only {spans} of the height and the width"


SHAPES = {
    "tall thin box": [("tall", (0.2, 5.0, 0.2), (0, 0, 0))],
    "wide flat box": [("wide", (8.0, 0.1, 3.0), (0, 0, 0))],
    "far apart": [("a", (1, 1, 1), (-20, 0, 0)), ("b", (1, 1, 1), (20, 3, 0))],
}


@pytest.mark.parametrize("projection", ["perspective", "ortho"])
@pytest.mark.parametrize("shape", sorted(SHAPES))
def test_default_camera_frames_generated_scenes(gl, shape, projection):
    scene = _boxes(*SHAPES[shape])
    for size in ((320, 240), (160, 320)):
        rgba = rtta.snapshot(scene, "std", size=size, projection=projection)
        _check_framed(rgba, f"{shape} {projection} {size}")
    _check_framed(rtta.snapshot(scene, "std", camera="120,-30", size=(200, 200), projection=projection), shape)


@pytest.mark.parametrize("projection", ["perspective", "ortho"])
def test_default_camera_frames_the_demo_and_hidden_parts_leave_the_frame(gl, demo_scene, projection):
    _check_framed(rtta.snapshot(None, "std", size=(320, 240), projection=projection), "demo")
    for view in ("front", "top", "iso"):
        _check_framed(rtta.snapshot(None, "std", size=(240, 240), view=view, projection=projection), view)
    small = demo_scene.names[int(np.argmin(np.linalg.norm(demo_scene.aabb_max - demo_scene.aabb_min, axis=1)))]
    others = [n for n in demo_scene.names if n != small]
    rgba = rtta.snapshot(None, "std", size=(320, 240), hidden=others, projection=projection)
    _check_framed(rgba, f"{small} alone")  # the one part left is framed, not the whole demo


@pytest.mark.parametrize("name", ["box_sides.STEP", "flight_helmet.glb", "engine_2cyl.glb"])
def test_default_camera_frames_the_workspace_files(gl, name):
    path = SHARED / name
    if not path.exists():
        pytest.skip(f"{path} is not present (it lies next to the checkout; CI has it)")
    _check_framed(rtta.snapshot(str(path), "std", size=(320, 240)), name)


def test_camera_az_el_fits_and_az_el_dist_keeps_its_distance(gl, demo_scene):
    fitted = rtta.capture(None, camera="35,25", size=(64, 48)).camera
    fixed = rtta.capture(None, camera="35,25,6", size=(64, 48)).camera
    assert np.linalg.norm(fixed.eye - demo_scene.center) == pytest.approx(6 * demo_scene.radius)
    default = rtta.capture(None, size=(64, 48)).camera
    assert np.allclose(fitted.eye, default.eye)  # the default direction is 35, 25


@pytest.mark.parametrize("projection", ["perspective", "ortho"])
def test_pick_at_the_centre_lies_on_the_part_shown_there(gl, demo_scene, projection):
    size = (320, 240)
    hit = rtta.pick(None, x=160, y=120, size=size, projection=projection)
    assert hit is not None and hit.name in demo_scene.names
    oid = demo_scene.names.index(hit.name)
    first, count = demo_scene.index_ranges[oid]
    tris = demo_scene.positions[demo_scene.indices[first : first + count].reshape(-1, 3)] + demo_scene.origin
    mesh = trimesh.Trimesh(tris.reshape(-1, 3), np.arange(len(tris) * 3).reshape(-1, 3), process=False)
    _, distance, _ = trimesh.proximity.closest_point(mesh, hit.point[None])
    assert distance[0] <= 1e-4 * demo_scene.radius
    assert np.linalg.norm(hit.normal) == pytest.approx(1.0)
    std = rtta.capture(None, size=size, projection=projection)
    assert std.names[std.std_id[size[1] - 1 - 120, 160]] == hit.name  # the part STD shows there
    corner = rtta.pick(None, x=0, y=0, size=size, projection=projection)
    assert corner is None  # the fitted view leaves background at the corners
    with pytest.raises(rtta.RttaError, match=r"pixel \(320, 0\) lies outside the 320x240 view"):
        rtta.pick(None, x=320, y=0, size=size)


def test_info_tree_prints_each_group_once_when_parts_interleave(capsys):
    scene = _boxes(*[(f"p{i}", (1, 1, 1), (2 * i, 0, 0)) for i in range(6)])
    scene.paths = [("asm", "left"), ("asm", "right"), ("asm", "left"), ("loose",), ("asm",), ("asm", "right")]
    lines = tree_lines(scene)
    assert lines == [
        "asm/  (5 objects, 60 triangles)",
        "  left/  (2 objects, 24 triangles)",
        "    0  p0  (12 triangles)",
        "    2  p2  (12 triangles)",
        "  right/  (2 objects, 24 triangles)",
        "    1  p1  (12 triangles)",
        "    5  p5  (12 triangles)",
        "  4  p4  (12 triangles)",
        "loose/  (1 objects, 12 triangles)",
        "  3  p3  (12 triangles)",
    ]


def test_demo_tree_names_every_group_once(capsys):
    lines = tree_lines(load_scene(demo_path()))
    groups = [line.strip() for line in lines if "/  (" in line]
    assert len(groups) == len(set(groups))


def test_ambient_occlusion_and_edges_shade_alike_in_both_projections(gl):
    """AO and edges reconstruct view positions from the atlas depth (post.frag): in ortho they
    darken the focus about as much as in perspective (a perspective-only reconstruction gives
    an orthographic view garbage positions)."""
    shade = {}
    for projection in ("perspective", "ortho"):
        kw = {"focus": "hub", "size": (240, 180), "projection": projection, "camera": "35,25"}
        ao = rtta.snapshot(None, "ghosted-ao", ao_objects="focus", **kw).astype(float)
        flat = rtta.snapshot(None, "ghosted", **kw).astype(float)
        shade[projection] = float(np.abs(ao[..., :3] - flat[..., :3]).mean())
    assert shade["perspective"] > 0.2 and shade["ortho"] > 0.2, shade
    assert 0.5 < shade["ortho"] / shade["perspective"] < 2.0, shade


def test_bench_composite_and_capture_take_the_projection(gl, capsys):
    from rtta.bench import render as bench

    args = ["--quick", "--size", "96x72", "--scene", "random-12", "--projection", "ortho"]
    assert main(["bench", "composite", *args]) == 0
    assert "; ortho; viewport 96x72" in capsys.readouterr().out
    row = bench.capture_row(gl, _boxes(("a", (1, 1, 1), (0, 0, 0))), (64, 48), 1, rtt=False, projection="ortho")
    assert row["atlas"][2] == 1 and row["std_ms"] > 0


@pytest.mark.parametrize("path", ["vs", "gs"])
def test_ortho_near_plane_through_the_parts(make_renderer, demo_scene, path):
    """An orthographic camera whose near plane cuts through the demo (a Camera made by hand,
    not fitted): Algorithm 1 clips the bounds crossing it, and the atlas still equals the
    objects drawn alone and STD its front-most surfaces (tests/checks.py)."""
    from checks import check_frame

    c, r = demo_scene.center, demo_scene.radius
    eye = c + np.array([0.3, 0.2, 1.0]) * r * 0.2
    cam = rtta.Camera(eye=eye, target=c, up=np.array([0.0, 1.0, 0.0]), near=0.01 * r, far=3 * r, kind="ortho")
    cam.height = 0.8 * r
    records = make_renderer(demo_scene).parameterize(cam, (200, 150))
    assert 0 < records.visible.sum() < demo_scene.count  # some parts lie wholly behind the near plane
    out = check_frame(make_renderer(demo_scene), cam, (200, 150), path)
    assert out["visible"] == records.visible.sum()


def test_capture_leaves_hidden_parts_out(gl, demo_scene):
    cap = rtta.capture(None, size=(96, 72), hidden=["rotor", "caliper"])
    gone = [cap.index("rotor"), cap.index("caliper")]
    assert not cap.visible[gone].any() and cap.visible.sum() == demo_scene.count - 2
    assert not np.isin(cap.std_id, gone).any()


def test_ortho_upsampling_keeps_the_surface_within_two_percent(make_renderer, monkeypatch):
    """Context regions below one texel per pixel are upsampled over the texels within 2% of
    the nearest one's view distance; in ortho window depth is linear in distance (not 1 - depth
    ~ 1 / distance): a steep plate and a ball at the back come closer to the scale-1 picture
    with the orthographic reach than with the perspective one."""
    from rtta.passes import sprites
    from rtta.scene.camera import Camera

    plate = trimesh.creation.box(extents=(3, 3, 0.05))
    plate.apply_transform(trimesh.transformations.rotation_matrix(np.radians(75), (1, 0, 0)))
    ball = trimesh.creation.icosphere(3, radius=0.9)
    parts = [("focus", trimesh.creation.box(extents=(0.2, 0.2, 0.2)), (0, 0, 1.5)), ("plate", plate, (-1, 0, -1))]
    parts.append(("ball", ball, (1.2, 0, -1)))
    scene = from_meshes([(n, np.asarray(m.vertices) + c, np.asarray(m.faces), None) for n, m, c in parts])
    cam = Camera.orbit(scene.center, scene.radius, 0, 0, 2.0, projection="ortho")

    def picture(scale):
        r = make_renderer(scene, rtta.Settings(context_scale=scale))
        r.capture(cam, (240, 180), focus={0})
        return r.composite("sprites", rtta.Style(focus={0}, outline_width=0)).read()[0][..., :3].astype(float)

    full, fixed = picture(1.0), picture(0.5)
    frame = sprites.SpritePass.frame
    monkeypatch.setattr(sprites.SpritePass, "frame", lambda self, **kw: frame(self, **{**kw, "ortho_near": None}))
    perspective_reach = picture(0.5)
    assert np.abs(fixed - full).mean() < np.abs(perspective_reach - full).mean()
