"""Section planes and capped solids (issue 41): every pixel left lies on the kept side, caps
lie on the plane in the part's darker colour, in STD, in the atlas and in the composite."""

from __future__ import annotations

import numpy as np
import pytest
from checks import assert_depth_close, check_frame

import rtta
from rtta.errors import RttaError
from rtta.gl.readback import map_back
from rtta.renderer.placing import make_staging
from rtta.renderer.snapshot import over_background
from rtta.scene.camera import Camera
from rtta.scene.cutaway import SectionPlane, parse_section
from rtta.scene.generators.shapes import box, sphere
from rtta.scene.model import from_meshes

VP = (200, 150)
TOL = 1e-4  # of the scene radius: what a pixel may lie beyond the plane


@pytest.fixture(scope="module")
def solids():
    """A sphere (radius 1 at the origin) and a box (1.2 wide at x = 2.5): both closed."""
    s, b = sphere(1.0, 4), box(1.2)
    return from_meshes([("sphere", s.vertices, s.faces, None), ("box", b.vertices + [2.5, 0, 0], b.faces, None)])


def world(depth: np.ndarray, view: np.ndarray, proj: np.ndarray) -> np.ndarray:
    """World points [H, W, 3] of window depths [H, W] (row 0 at the bottom), through the
    inverse view-projection (perspective or orthographic alike)."""
    h, w = depth.shape
    x, y = np.meshgrid((np.arange(w) + 0.5) / w * 2 - 1, (np.arange(h) + 0.5) / h * 2 - 1)
    ndc = np.stack([x, y, depth.astype(np.float64) * 2 - 1, np.ones_like(x)], -1)
    p = ndc @ np.linalg.inv(proj @ view).T
    return p[..., :3] / p[..., 3:]


def beyond(points: np.ndarray, plane: SectionPlane) -> np.ndarray:
    return points @ np.asarray(plane.normal) - plane.d


def test_specs_parse_alike():
    assert parse_section("x=0.5") == SectionPlane((1, 0, 0), 0.5)
    assert parse_section("-y=2") == SectionPlane((0, -1, 0), -2)
    assert parse_section("0,0,2,1") == SectionPlane((0, 0, 1), 0.5)
    assert parse_section(" Z = -1 ").removes(np.array([[0, 0, 0], [0, 0, -2]])).tolist() == [True, False]


def test_specs_at_a_fraction_of_the_bounds():
    """`x=P%` lies P% of the way across the scene's box on x, `x` alone halfway; `-x` keeps the
    other side. Placed on a scene (`on`), they are the planes written in world units."""
    bounds = (np.array([-2.0, 0.0, 10.0]), np.array([6.0, 4.0, 30.0]))
    assert parse_section("x") == SectionPlane((1, 0, 0), 0.0, 0.5)
    assert parse_section("x").on(bounds) == SectionPlane((1, 0, 0), 2.0)
    assert parse_section("-x").on(bounds) == SectionPlane((-1, 0, 0), -2.0)
    assert parse_section("y=25%").on(bounds) == parse_section("y=1")
    assert parse_section("-z=10%").on(bounds) == parse_section("-z=12")
    assert parse_section("x=3").on(bounds) == parse_section("x=3")  # in world units already
    with pytest.raises(ValueError, match="on\\(scene.bounds\\)"):
        parse_section("x").relative(np.zeros(3))  # a plane not placed never reaches a shader


def test_a_plane_at_a_fraction_cuts_as_the_plane_in_world_units(gl, solids, tmp_path):
    """snapshot with `x` and `-z=30%` is the snapshot with the same planes in world units (the
    solids' box: x from -1 to 3.1, z from -1 to 1); the CLI takes `-x` as its own word, and a
    saved view keeps the fractions (so one view file cuts any scene alike)."""
    import json

    from rtta.cli.main import main

    lo, hi = solids.bounds
    mid, low = float(lo[0] + 0.5 * (hi[0] - lo[0])), float(lo[2] + 0.3 * (hi[2] - lo[2]))
    for mode in ("std", "ghosted"):
        a = rtta.snapshot(solids, mode, size=VP, sections=["x", "-z=30%"], camera=(35, 25, 2.5))
        b = rtta.snapshot(solids, mode, size=VP, sections=[f"x={mid!r}", f"-z={low!r}"], camera=(35, 25, 2.5))
        assert np.array_equal(a, b), mode
    whole = rtta.snapshot(solids, "std", size=VP, camera=(35, 25, 2.5))
    assert (a != whole).any(axis=-1).mean() > 0.02  # it cuts
    out, view = tmp_path / "a.png", tmp_path / "v.json"
    assert main(["snapshot", "--size", "64x48", "--section", "-x", "--out", str(out), "--save-view", str(view)]) == 0
    assert json.loads(view.read_text())["sections"]["planes"] == ["-x"]


@pytest.mark.parametrize(
    "spec", ["w=1", "x=", "x=nan", "1,2,3", "0,0,0,1", "x=1e400", "a,b,c,d", "--x=1", "w", "x=%", "x=abc%", "x%", ""]
)
def test_malformed_specs_refused(spec):
    with pytest.raises(RttaError, match="--section"):
        parse_section(spec)


def _cap_check(cap, plane: SectionPlane, radius: float) -> tuple[int, int]:
    """(pixels beyond the kept side, pixels of a sphere's cut disc not showing the cap): the
    STD and every object's mapped-back atlas image. The cap region is computed from the
    rays: where the ray meets the plane inside the unit sphere, having entered it on the removed side."""
    wrong_side = 0
    images = [(cap.std_depth, cap.std_id)]
    for oid in np.flatnonzero(cap.visible):
        m = cap.amodal(int(oid))
        images.append((m["depth"], m["id"]))
    for depth, ids in images:
        covered = ids >= 0
        pts = world(depth, cap.view, cap.proj)
        wrong_side += int((beyond(pts[covered], plane) > TOL * radius).sum())
    if "sphere" not in cap.names:
        return wrong_side, 0
    # the expected disc: each pixel's ray (near point q to far point f) meets the plane at P
    h, w = cap.std_depth.shape
    q, f = world(np.zeros((h, w)), cap.view, cap.proj), world(np.ones((h, w)), cap.view, cap.proj)
    n = np.asarray(plane.normal)
    with np.errstate(divide="ignore", invalid="ignore"):  # rays along the plane never meet it
        t = (plane.d - q @ n) / ((f - q) @ n)
        hit = q + t[..., None] * (f - q)
    eye_removed = q @ n > plane.d
    disc = eye_removed & (np.linalg.norm(hit, axis=-1) < 0.97) & (t > 0) & (t < 1)
    sphere_id = cap.names.index("sphere")
    on_plane = np.abs(beyond(world(cap.std_depth, cap.view, cap.proj), plane)) <= TOL * radius
    colors = cap.std_color[..., :3].astype(int)
    shows_cap = on_plane & (cap.std_id == sphere_id)
    if shows_cap.any():  # one flat colour: the sphere's, darker
        ref = np.median(colors[shows_cap], axis=0)
        shows_cap &= np.abs(colors - ref).max(-1) <= 2
        assert (ref < np.asarray(cap.std_color[..., :3]).max()).all()
    return wrong_side, int((disc & ~shows_cap).sum())


# cameras on both sides of each plane: z=0.2 removes z > 0.2 (the eye at azimuth 0 lies there)
@pytest.mark.parametrize("spec", ["z=0.2", "-x=-0.3", "0.3,1,0.5,0.1"])
@pytest.mark.parametrize("orbit", [(0, 20, 2.0), (180, -25, 2.0), (70, 50, 1.6)])
@pytest.mark.parametrize("projection", ["perspective", "ortho"])
def test_kept_side_and_caps(gl, solids, spec, orbit, projection):
    plane = parse_section(spec)
    cap = rtta.capture(solids, camera=orbit, size=VP, sections=[spec], projection=projection)
    wrong_side, missing_cap = _cap_check(cap, plane, solids.radius)
    assert wrong_side == 0
    assert missing_cap == 0


def test_caps_off_fails_the_cap_check(gl, solids):
    """The check can fail: without caps the disc shows the sphere's inside, not the plane."""
    plane = parse_section("z=0.2")
    solid = _cap_check(rtta.capture(solids, camera=(0, 20, 2.0), size=VP, sections=["z=0.2"]), plane, solids.radius)
    off = rtta.capture(solids, camera=(0, 20, 2.0), size=VP, sections=["z=0.2"], caps="off")
    wrong_side, missing_cap = _cap_check(off, plane, solids.radius)
    assert solid[1] == 0 and wrong_side == 0
    assert missing_cap > 500, missing_cap


@pytest.mark.parametrize("caps", ["solid", "hatch"])
@pytest.mark.parametrize("orbit", [(60, 20, 2.0), (230, -30, 1.8), (10, 20, 2.0)])
def test_atlas_std_rtt_agree_with_sections(make_renderer, solids, demo_scene, caps, orbit):
    """The core's equalities (atlas = RTT per object, STD = front-most atlas) hold cut and
    capped, both capture paths, on the solids and on the demo, from both sides of the planes.
    """
    for scene, specs in ((solids, ["z=0.2", "x=2.7"]), (demo_scene, ["x=0.05", "-y=-0.2"])):
        r = make_renderer(scene)
        r.staging = make_staging(specs, caps)
        cam = Camera.orbit(scene.center, scene.radius, *orbit)
        for path in ("vs", "gs"):
            check_frame(r, cam, VP, path)


@pytest.mark.parametrize("orbit", [(60, 20, 2.0), (230, -30, 1.8)])
def test_sprites_match_std_with_sections(make_renderer, solids, demo_scene, orbit):
    """`sprites` reconstructs STD cut and capped as it does whole, on the solids and on the
    demo, whose parts interpenetrate (pistons inside the caliper's solid): a part's cap covers
    what lies inside it in STD as in its own atlas image."""
    for scene, specs in ((solids, ["z=0.2", "x=2.7"]), (demo_scene, ["x=0.05"])):
        r = make_renderer(scene)
        r.staging = make_staging(specs)
        cam = Camera.orbit(scene.center, scene.radius, *orbit)
        r.capture(cam, VP)
        rgba, depth = r.composite("sprites").read()
        std = r.std(cam, VP).read(VP, 1)
        std_rgba, std_depth, std_id = over_background(std["color"][0]), std["depth"][0], std["id"][0]
        close = np.abs(rgba[..., :3].astype(int) - std_rgba[..., :3].astype(int)).max(-1) <= 3
        assert close.mean() >= 0.995, f"only {close.mean():.4f} of pixels within 3/255"
        assert_depth_close(depth, std_depth, std_id >= 0, std_id, "sprites against STD")


def test_demo_kept_side_every_mode(gl, demo_scene):
    """Every pixel of the demo's STD and atlas regions lies on the kept side, from both sides;
    each composite mode differs from the uncut one."""
    plane = parse_section("x=0")
    for orbit in ((90, 10, 2.2), (270, 10, 2.2)):
        cap = rtta.capture(demo_scene, camera=orbit, size=VP, sections=["x=0"])
        wrong_side, _ = _cap_check(cap, plane, demo_scene.radius)
        assert wrong_side == 0
    for mode in ("std", "sprites", "transparent", "ghosted", "ghosted-ao"):
        cut = rtta.snapshot(demo_scene, mode, size=VP, sections=["x=0"], focus=["caliper"])
        whole = rtta.snapshot(demo_scene, mode, size=VP, focus=["caliper"])
        assert (cut != whole).any(axis=-1).mean() > 0.02, mode


def test_context_scope_keeps_the_focus_whole(make_renderer, demo_scene):
    """--section-scope context: the focus parts' atlas images and STD pixels equal the uncut
    ones; the context is cut (with scope all the focus is cut too)."""
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, 35, 25, 2.2)
    caliper = demo_scene.index("caliper")

    def frame(staging):
        r = make_renderer(demo_scene)
        if staging is not None:
            r.staging = staging
        records = r.capture(cam, VP, focus={caliper})
        tw, th, td = records.atlas_size
        atlas = r.atlas.read((tw, th), td, parts=("color", "depth"))
        std = r.std(cam, VP).read(VP, 1)
        return map_back(atlas, records, caliper), std["color"][0], std["id"][0]

    whole, whole_std, whole_id = frame(None)
    kept, kept_std, kept_id = frame(make_staging(["x=0"], section_scope="context"))
    cut, _, cut_id = frame(make_staging(["x=0"]))
    assert np.array_equal(kept["color"], whole["color"])  # the program differs: depth within float rounding
    assert np.array_equal(kept["depth"] < 1, whole["depth"] < 1) and np.abs(kept["depth"] - whole["depth"]).max() < 1e-6
    both = (whole_id == caliper) & (kept_id == caliper)
    assert both.sum() > 500 and np.array_equal(kept_std[both], whole_std[both])
    assert (kept_id == caliper).sum() >= (whole_id == caliper).sum()  # context cut away reveals more of it
    assert not np.array_equal(cut["depth"], whole["depth"])
    assert (kept_id != whole_id).mean() > 0.02


def test_plane_removing_everything_refused(gl, solids):
    with pytest.raises(RttaError, match="remove the whole scene"):
        rtta.snapshot(solids, "std", size=VP, sections=["x=-5"])
    with pytest.raises(RttaError, match="--caps"):
        rtta.snapshot(solids, "std", size=VP, sections=["x=0"], caps="striped")
    with pytest.raises(RttaError, match="at most 6"):
        rtta.snapshot(solids, "std", size=VP, sections=["x=1"] * 7)
    rgba = rtta.snapshot(solids, "std", size=VP, sections=["x=-5"], section_scope="context", focus=["box"])
    assert (rgba[..., :3] != rgba[0, 0, :3]).any()  # the focus stays: not everything is removed


def test_dataset_takes_the_flags(gl, tmp_path, capsys):
    """rtta dataset --section/--caps/--explode: saved in its settings, the images cut; bad ones refused."""
    import json

    from rtta.cli.main import main

    pytest.importorskip("pycocotools")  # the dataset's masks (rtta[dataset]; CI installs it)
    common = ["dataset", "--views", "1", "--size", "96x72", "--no-progress", "--seed", "3"]
    assert main([*common, "--out", str(tmp_path / "whole")]) == 0
    assert (
        main([*common, "--section", "x=0", "--caps", "hatch", "--explode", "0.5", "--out", str(tmp_path / "cut")]) == 0
    )
    settings = json.loads((tmp_path / "cut" / "dataset.json").read_text())["settings"]
    assert (settings["sections"], settings["caps"], settings["explode"]) == (["x=0"], "hatch", 0.5)
    assert "sections" not in json.loads((tmp_path / "whole" / "dataset.json").read_text())["settings"]
    rgb = sorted((tmp_path / "whole").rglob("rgb.png"))[0].relative_to(tmp_path / "whole")
    assert (tmp_path / "whole" / rgb).read_bytes() != (tmp_path / "cut" / rgb).read_bytes()
    capsys.readouterr()
    assert main([*common, "--section", "x=1e400", "--out", str(tmp_path / "bad")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--section expects" in err and not (tmp_path / "bad").exists()


def test_viewer_cutaway_state(make_renderer, demo_scene):
    """The viewer's cutaway panel state: its plane as --section takes it, a new capture key on
    every change, and the renderer it stages cut (viewer.cutaway; the window is not needed)."""
    from rtta.renderer.placing import restage
    from viewer.cutaway import CutawayState
    from viewer.state import ViewerState

    state = ViewerState(names=list(demo_scene.names))
    before = state.capture_key()
    state.cutaway = CutawayState(axis="-x", at=0.5, caps="hatch", explode=0.5)
    assert state.capture_key() != before
    lo, hi = demo_scene.bounds
    assert state.cutaway.spec(demo_scene) == f"-x={(lo[0] + hi[0]) / 2:.9g}"
    r = make_renderer(demo_scene)
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, 35, 25, 3.0)
    whole = r.std(cam, VP).read(VP, 1)["id"][0].copy()
    restage(r, state.cutaway.staging(demo_scene))
    assert r.staging.cutaway.caps == "hatch" and r.staging.explode == 0.5
    cut = r.std(cam, VP).read(VP, 1)["id"][0]
    assert (cut != whole).mean() > 0.05
    restage(r, CutawayState().staging(demo_scene))  # back to whole
    assert np.array_equal(r.std(cam, VP).read(VP, 1)["id"][0], whole)


def test_projector_paints_caps_alike(gl, demo_scene):
    """The projector paints the caps at their points on the plane, in STD as in the composite,
    and what the planes cut away casts no shadow (its shadow map is cut too)."""
    opts = dict(size=VP, projector="default", sections=["z=0.1"], camera=(35, 25, 2.2))
    std, sprites = rtta.snapshot(demo_scene, "std", **opts), rtta.snapshot(demo_scene, "sprites", **opts)
    close = np.abs(std[..., :3].astype(int) - sprites[..., :3].astype(int)).max(-1) <= 3
    assert close.mean() >= 0.99, close.mean()
    plain = rtta.snapshot(demo_scene, "std", size=VP, sections=["z=0.1"], camera=(35, 25, 2.2))
    assert (std != plain).any(axis=-1).mean() > 0.08  # painted


def test_a_plane_below_can_follow_the_flag_as_its_own_word(tmp_path, gl):
    """`--section -y=0` (what the docs write) works as `--section=-y=0`: argparse would take
    the leading dash for an option."""
    from rtta.cli.main import main

    a, b = tmp_path / "a.png", tmp_path / "b.png"
    assert main(["snapshot", "--size", "64x48", "--section", "-y=0", "--out", str(a)]) == 0
    assert main(["snapshot", "--size", "64x48", "--section=-y=0", "--out", str(b)]) == 0
    assert a.read_bytes() == b.read_bytes()
