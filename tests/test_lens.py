"""The lens (a volumetric test in compositing) and the `rtta ldi` command.

The lens is checked against numpy geometry: a context box with a focus sphere inside, seen
head-on. Where the box's visible surface (from STD depth, unprojected) lies inside the lens
sphere, the ghosted composite must equal the one without any context; where it lies outside,
the one without a lens."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from rtta.bench.compare import near_edges
from rtta.cli.main import main
from rtta.errors import RttaError
from rtta.ldi.lens import Lens, default_placement
from rtta.passes.composite import Style
from rtta.scene.camera import Camera
from rtta.scene.model import from_meshes

VP = (160, 120)


def _scene():
    box = trimesh.creation.box(extents=(2, 2, 2))
    ball = trimesh.creation.icosphere(subdivisions=3, radius=0.45)
    return from_meshes([("box", box.vertices, box.faces, None), ("ball", ball.vertices, ball.faces, None)])


def _world(r, cam) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """World position (relative to the origin) of the STD surface under each pixel centre,
    whether there is one, and the STD ids."""
    std = r.std(cam, VP).read(VP, 1)
    depth = std["depth"][0].astype(np.float64)
    view, proj = r.matrices(cam, VP)
    x, y = np.meshgrid((np.arange(VP[0]) + 0.5) / VP[0] * 2 - 1, (np.arange(VP[1]) + 0.5) / VP[1] * 2 - 1)
    h = np.stack([x, y, depth * 2 - 1, np.ones_like(x)], -1) @ np.linalg.inv(proj @ view).T
    return h[..., :3] / h[..., 3:], depth < 1.0, std["id"][0]


@pytest.mark.parametrize("mode", ["ghosted", "ghosted-ao"])
def test_lens_cuts_the_context_where_numpy_says(make_renderer, mode):
    scene = _scene()
    r = make_renderer(scene)
    cam = Camera.orbit(scene.center, scene.radius, 20.0, 15.0, 2.6)
    world, covered, ids = _world(r, cam)
    center, radius = np.array([0.0, 0.0, 1.0]), 0.8  # on the box's front face
    style = Style(focus={1}, context_opacity=0.6)
    r.capture(cam, VP)
    images = {}
    for name, lens, opacity in (
        ("lens", Lens.shape("sphere", center, radius), 0.6),
        ("none", None, 0.6),
        ("no-context", None, 0.0),
    ):
        r.lens = lens
        style.context_opacity = opacity
        images[name] = r.composite(mode, style).read()[0][..., :3].astype(int)
    dist = np.linalg.norm(world - (center - scene.origin), axis=-1)
    ball = np.abs(images["no-context"] - images["no-context"][0, 0]).max(-1) > 3  # focus and its outline
    stable = covered & ~near_edges(ids) & ~near_edges(near_edges(ball))
    texel = 2.5 * radius / 256 * 2  # the lens LDI's resolution, with margin
    inside = stable & (dist < radius - texel)
    outside = stable & (dist > radius + texel)
    assert inside.sum() > 500 and outside.sum() > 500
    assert np.abs(images["lens"] - images["no-context"])[inside].max() <= 3
    assert np.abs(images["lens"] - images["none"])[outside].max() <= 3
    assert (np.abs(images["lens"] - images["none"]).max(-1) > 3)[inside].mean() > 0.5  # the cut shows


def test_lens_leaves_other_modes_and_the_lens_object_alone(make_renderer):
    scene = _scene()
    r = make_renderer(scene)
    cam = Camera.orbit(scene.center, scene.radius, 20.0, 15.0, 2.6)
    r.capture(cam, VP)
    plain = r.composite("transparent").read()[0]
    r.lens = Lens.shape("sphere", scene.center, 5.0)  # swallows everything
    assert np.array_equal(r.composite("transparent").read()[0], plain)
    r.lens = Lens.of_object(scene, 0)  # the box as the lens: the box stays
    style = Style(focus={1})
    with_lens = r.composite("ghosted", style).read()[0]
    r.lens = None
    assert np.abs(with_lens.astype(int) - r.composite("ghosted", style).read()[0]).max() <= 3


def test_lens_arguments_fail_cleanly(tmp_path, capsys):
    scene = _scene()
    center, radius = default_placement(scene, {1})
    assert np.allclose(center, 0.0) and radius == pytest.approx(0.6 * np.sqrt(3) * 0.9, rel=0.05)
    whole, whole_radius = default_placement(scene, set())
    diagonal = float(np.linalg.norm(scene.aabb_max.max(axis=0) - scene.aabb_min.min(axis=0)))
    assert whole_radius == pytest.approx(0.25 * diagonal)
    with pytest.raises(RttaError, match="radius must be positive"):
        Lens.shape("sphere", center, 0.0)
    out = tmp_path / "x.png"
    for args, says in (
        (["--lens", "cone"], "cone"),
        (["--lens", "sphere,abc"], "radius must be a number"),
        (["--lens", "sphere", "--lens-at", "1,2"], "--lens-at must be X,Y,Z"),
    ):
        assert main(["snapshot", "--mode", "ghosted", "--size", "64x48", "--out", str(out), *args]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and says in err and not out.exists()


def test_snapshot_with_a_lens_differs_where_the_context_is_cut(tmp_path, gl):
    from PIL import Image

    paths = [tmp_path / "a.png", tmp_path / "b.png"]
    base = ["snapshot", "--mode", "ghosted", "--size", "160x120", "--focus", "piston_1", "pad_inner"]
    assert main([*base, "--out", str(paths[0])]) == 0
    assert main([*base, "--lens", "sphere", "--out", str(paths[1])]) == 0
    a, b = (np.asarray(Image.open(p)).astype(int) for p in paths)
    assert (np.abs(a - b).max(-1) > 3).mean() > 0.01


def test_a_lens_with_nothing_in_focus_cuts_into_the_middle(tmp_path, gl):
    """Everything is context with nothing in focus: the default lens cuts into the scene's
    middle instead of cutting all of it away (a blank picture, as a lens sized to the whole
    scene gave)."""
    from PIL import Image

    paths = [tmp_path / "a.png", tmp_path / "b.png"]
    base = ["snapshot", "--mode", "ghosted", "--size", "160x120"]
    assert main([*base, "--out", str(paths[0])]) == 0
    assert main([*base, "--lens", "sphere", "--out", str(paths[1])]) == 0
    a, b = (np.asarray(Image.open(p))[..., :3].astype(int) for p in paths)
    drawn = [(np.abs(im - im[0, 0]).max(-1) > 3).mean() for im in (a, b)]
    assert drawn[1] > 0.25 * drawn[0], f"the lens cut away most of the scene: {drawn}"
    assert (np.abs(a - b).max(-1) > 3).mean() > 0.01, "the lens cut nothing"


def test_ldi_command_classifies_points_and_prints_the_table(tmp_path, capsys, gl):
    rng = np.random.default_rng(0)
    points = rng.uniform(-1.2, 1.2, (5000, 3))
    np.save(tmp_path / "p.npy", points)
    out = tmp_path / "in.npy"
    assert (
        main(["ldi", "shape:sphere", "--points", str(tmp_path / "p.npy"), "--out", str(out), "--resolution", "256"])
        == 0
    )
    inside = np.load(out)
    truth = np.linalg.norm(points, axis=1) < 1.0
    assert inside.dtype == bool and inside.shape == (5000,)
    assert (inside == truth).mean() > 0.99
    assert (
        main(
            [
                "ldi",
                "shape:sphere",
                "--points",
                str(tmp_path / "p.npy"),
                "--out",
                str(out),
                "--resolution",
                "256",
                "--compressed",
            ]
        )
        == 0
    )
    assert np.array_equal(np.load(out), inside)
    capsys.readouterr()
    assert main(["ldi", "shape:torus", "--stats"]) == 0
    header, row = capsys.readouterr().out.splitlines()
    assert header.split()[:5] == ["mesh", "vertices", "d_min", "d_max", "d"]
    values = row.split()
    assert values[0] == "shape:torus" and int(values[4]) == 2 and 0 < float(values[-1]) < 10
    out.write_bytes(b"keep")
    bad = tmp_path / "bad.npy"
    np.save(bad, np.zeros((3, 2)))
    assert main(["ldi", "shape:sphere", "--points", str(bad), "--out", str(out)]) == 2
    assert "shape [N, 3]" in capsys.readouterr().err and out.read_bytes() == b"keep"


def test_ldi_and_lens_release_every_gl_object(gl):
    """Peelers, parity tests and renderers with a lens leave the GL census as it was."""
    from rtta.bench.reliability import gl_census
    from rtta.ldi.gpu import ParityTest
    from rtta.ldi.peel import build, closed_mesh
    from rtta.renderer.renderer import Renderer

    mesh = trimesh.creation.icosphere(subdivisions=2)
    v, f = closed_mesh(mesh.vertices, mesh.faces)
    scene = _scene()
    cam = Camera.orbit(scene.center, scene.radius, 20.0, 15.0, 2.6)

    def work():
        test = ParityTest(gl, build(gl, v, f, 64))
        test.classify(np.zeros((10, 3)))
        test.classify(np.zeros((5000, 3)), compressed=True)  # grows its targets
        test.release()
        r = Renderer(gl, scene)
        r.lens = Lens.shape("box", scene.center, 0.5)
        r.capture(cam, VP)
        r.composite("ghosted", Style(focus={1}))
        r.release()

    work()  # first use: shader caches filled
    before = gl_census(gl)
    for _ in range(3):
        work()
    assert gl_census(gl) == before
