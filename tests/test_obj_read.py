"""Plain OBJ files read without trimesh (rtta.scene.readers.obj_read): the same scene as trimesh's
reading (per object: name, triangles, file normals), and every other file left to trimesh."""

from __future__ import annotations

import numpy as np
import pytest

from rtta.scene.loader import load_scene
from rtta.scene.readers import obj_read
from rtta.scene.readers.obj import obj_objects

BOX_V = [(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 2)]
BOX_QUADS = [(1, 2, 4, 3), (5, 7, 8, 6), (1, 5, 6, 2), (3, 4, 8, 7), (1, 3, 7, 5), (2, 6, 8, 4)]


def _box(k: int, base: int, corner: str = "{v}", quads: bool = True, shift=(0.0, 0.0, 0.0)) -> list[str]:
    """Object k: a box as 8 vertices (and 6 normals), its faces as quads or triangles;
    `corner` formats each face corner from its vertex index v, normal index n, uv index t."""
    lines = [f"o part{k}"] + [f"v {x + 3 * k + shift[0]:g} {y + shift[1]:g} {z + shift[2]:g}" for x, y, z in BOX_V]
    axes = ((0, 0, -1), (0, 0, 1), (0, -1, 0), (0, 1, 0), (-1, 0, 0), (1, 0, 0))
    lines += [f"vn {x:g} {y:g} {z:g}" for x, y, z in axes]
    lines += ["vt 0.5 0.5"]
    for q, quad in enumerate(BOX_QUADS):
        cs = [corner.format(v=base + i, n=6 * k + q + 1, t=k + 1) for i in quad]
        if quads:
            lines.append("f " + " ".join(cs))
        else:
            lines += ["f " + " ".join(cs[:3]), "f " + " ".join([cs[0], cs[2], cs[3]])]
    return lines


def _file(
    tmp_path,
    name: str,
    corner: str = "{v}",
    quads: bool = True,
    extra: list[str] = (),
    objects: int = 3,
    newline: str = "\n",
):
    lines = ["# made by the test", *extra]
    for k in range(objects):
        lines += _box(k, 8 * k, corner, quads=quads if k % 2 == 0 else not quads)
        lines.append("g somegroup")
    path = tmp_path / name
    path.write_bytes(newline.join(lines).encode() + b"\n")
    return path


def _triangles(scene, oid: int) -> tuple[np.ndarray, np.ndarray]:
    """An object's triangles as rows of their corners' (position, normal), rows sorted."""
    first, count = scene.index_ranges[oid]
    corners = scene.indices[first : first + count].astype(np.int64)
    tri = np.round(
        np.concatenate([scene.positions[corners], scene.normals[corners]], axis=1).astype(np.float64), 5
    ).reshape(-1, 3, 6)
    # each triangle from its smallest corner on (a rotation keeps the winding)
    first = np.array([min(range(3), key=lambda i, t=t: tuple(t[i])) for t in tri])
    tri = np.stack([tri[np.arange(len(tri)), (first + i) % 3] for i in range(3)], axis=1)
    rows = tri.reshape(-1, 18)
    return rows[np.lexsort(rows.T[::-1])], np.sort(np.round(scene.positions[corners], 5), axis=0)


def _both(path, monkeypatch, **options):
    direct = load_scene(path, **options, cache=False)  # both readings, never the scene cache
    with monkeypatch.context() as m:
        m.setattr(obj_read, "decode", lambda data, names: None)
        via_trimesh = load_scene(path, **options, cache=False)
    return direct, via_trimesh


@pytest.mark.parametrize(
    "corner,quads", [("{v}", True), ("{v}", False), ("{v}//{n}", True), ("{v}/{t}/{n}", False), ("{v}/{t}", True)]
)
@pytest.mark.parametrize("smooth", [False, True])
def test_plain_files_read_as_trimesh_reads_them(tmp_path, monkeypatch, corner, quads, smooth):
    path = _file(tmp_path, "parts.obj", corner, quads)
    data, names = obj_objects(path)
    assert obj_read.decode(data, names) is not None  # the direct reading is the one tested
    direct, via_trimesh = _both(path, monkeypatch, smooth=smooth)
    assert direct.names == via_trimesh.names == ["part0", "part1", "part2"]
    np.testing.assert_allclose(direct.colors, via_trimesh.colors)
    for oid in range(direct.count):
        a, b = _triangles(direct, oid), _triangles(via_trimesh, oid)
        np.testing.assert_allclose(a[1], b[1], atol=1e-6)  # the same triangles
        np.testing.assert_allclose(a[0], b[0], atol=1e-5)  # with the same normals at their corners
    np.testing.assert_allclose(direct.aabb_min, via_trimesh.aabb_min)


def test_groups_as_objects_and_crlf(tmp_path, monkeypatch):
    """No `o` lines but groups: the groups are the objects (rtta.scene.readers.obj), CRLF line ends."""
    lines = []
    for k in range(3):
        lines += [line.replace(f"o part{k}", f"g piece{k}") for line in _box(k, 8 * k, "{v}//{n}")]
    path = tmp_path / "groups.obj"
    path.write_bytes("\r\n".join(lines).encode())
    direct, via_trimesh = _both(path, monkeypatch)
    assert direct.names == via_trimesh.names == ["piece0", "piece1", "piece2"]
    for oid in range(3):
        np.testing.assert_allclose(_triangles(direct, oid)[0], _triangles(via_trimesh, oid)[0], atol=1e-5)


@pytest.mark.parametrize(
    "change",
    [
        (None, "v 0 0 0 1 0 0"),  # vertex colours
        (None, "l 1 2"),  # a line
        (None, "f -1 -2 -3"),  # relative indices
        (None, "f 1 2 99999"),
        (None, "f 0 1 2"),  # out of range: trimesh's messages
        (None, "v 1 2"),
        (None, "v 1 2 x"),  # damaged rows
        (None, "f 1 2"),  # a face of two corners
        (None, "f 1/1/1 2//2 3/1"),  # mixed corner forms
        (None, "v 1 2 3 \\"),  # a continued line
        (None, "f 1 2 3.5"),
        (None, "f 1 2 99999999999999999999999"),  # indices that are not integers
    ],
)
def test_other_files_go_to_trimesh(tmp_path, change):
    head, tail = change
    path = _file(tmp_path, "other.obj", extra=[head] if head else [])
    if tail:
        path.write_bytes(path.read_bytes() + tail.encode() + b"\n")
    data, names = obj_objects(path)
    assert obj_read.decode(data, names) is None


def test_faces_before_any_object_go_to_trimesh(tmp_path):
    path = tmp_path / "loose.obj"
    path.write_text(
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
        + "\n".join(_box(0, 4)[:1] + _box(0, 4)[1:])
        + "\n"
        + "\n".join(_box(1, 12))
        + "\n"
    )
    data, names = obj_objects(path)
    assert len(names) == 2 and obj_read.decode(data, names) is None


def test_many_objects_each_get_their_own_vertices(tmp_path):
    """1,000 parts: each object's vertices are the 8 of its box, its faces index them."""
    lines = []
    for k in range(1000):
        lines += _box(k, 8 * k, "{v}//{n}")
    path = tmp_path / "many.obj"
    path.write_text("\n".join(lines) + "\n")
    data, names = obj_objects(path)
    decoded = obj_read.decode(data, names)
    assert [names[k] for k, _ in decoded] == [f"part{k}" for k in range(1000)]
    for k in (0, 499, 999):
        geometry = decoded[k][1]
        assert geometry.faces.shape == (12, 3) and geometry.faces.max() == len(geometry.vertices) - 1
        assert len(geometry.vertices) == 24  # corners split by their normals
        np.testing.assert_allclose(geometry.vertices.min(axis=0), (3 * k, 0, 0))
        np.testing.assert_allclose(np.linalg.norm(geometry.normals, axis=1), 1.0)


MTL = "newmtl red\nKd 0.8 0.1 0.1\nnewmtl blue\nKd 0.1 0.2 0.9\nd 0.5\nnewmtl grey\nKa 0.2 0.2 0.2\n"


def _material_file(tmp_path, mtllib: str | None, uses: list[list[str]], corner: str = "{v}") -> object:
    """Objects part0.. each drawn as two triangles, the `usemtl` lines of uses[k] (before
    its first and its second triangle) in effect; `mtllib` names the material file."""
    lines = [f"mtllib {mtllib}"] if mtllib else []
    for k, use in enumerate(uses):
        box = _box(k, 8 * k, corner, quads=False)
        faces = [line for line in box if line.startswith("f ")][:2]
        lines += [line for line in box if not line.startswith("f ")]
        for name, face in zip(use + [None] * (2 - len(use)), faces, strict=True):
            lines += ([f"usemtl {name}"] if name else []) + [face]
    path = tmp_path / "coloured.obj"
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize("case", ["carried", "missing file", "outside", "unknown", "uv", "no usemtl"])
def test_material_colours_are_the_ones_trimesh_gives(tmp_path, monkeypatch, case):
    """Colours from trimesh's reading of the material skeleton: a material in effect carries
    over objects, an object of two materials takes one, a material without Kd, a missing or
    refused material file (the same warning), an unknown name, faces with texture coordinates."""
    (tmp_path / "parts.mtl").write_text(MTL)
    (tmp_path.parent / "elsewhere.mtl").write_text(MTL)
    uses = [["red"], ["blue"], ["red", "blue"], ["grey"], []]
    mtllib, corner = "parts.mtl", "{v}"
    if case == "missing file":
        mtllib = "nothere.mtl"
    elif case == "outside":
        mtllib = "../elsewhere.mtl"
    elif case == "unknown":
        uses[1] = ["green"]
    elif case == "uv":
        corner = "{v}/{t}/{n}"
    elif case == "no usemtl":
        uses = [[] for _ in uses]
    path = _material_file(tmp_path, mtllib, uses, corner)
    data, names = obj_objects(path)
    assert obj_read.decode(data, names) is not None and obj_read.has_materials(data)
    direct, via_trimesh = _both(path, monkeypatch)
    assert direct.names == via_trimesh.names
    np.testing.assert_array_equal(direct.colors, via_trimesh.colors)
    assert direct.warnings == via_trimesh.warnings and direct.inputs == via_trimesh.inputs
    if case == "carried":
        assert direct.colors[4].tolist() == direct.colors[3].tolist()  # grey carried over
        assert not np.array_equal(direct.colors[0], direct.colors[1])
    if case in ("missing file", "outside"):
        assert any("nothere.mtl" in w or "elsewhere.mtl" in w for w in direct.warnings)
    for oid in range(direct.count):
        np.testing.assert_allclose(_triangles(direct, oid)[0], _triangles(via_trimesh, oid)[0], atol=1e-5)


def test_textured_materials_go_to_trimesh(tmp_path, monkeypatch):
    """A material with a texture: the whole file is read by trimesh (texture coordinates)."""
    from PIL import Image

    Image.new("RGB", (4, 4), (200, 30, 30)).save(tmp_path / "wood.png")
    (tmp_path / "parts.mtl").write_text(MTL + "newmtl wood\nKd 1 1 1\nmap_Kd wood.png\n")
    path = _material_file(tmp_path, "parts.mtl", [["wood"], ["red"]], "{v}/{t}/{n}")
    direct, via_trimesh = _both(path, monkeypatch)
    assert direct.textured and via_trimesh.textured
    np.testing.assert_array_equal(direct.colors, via_trimesh.colors)
    np.testing.assert_array_equal(direct.texture_ids, via_trimesh.texture_ids)


@pytest.mark.parametrize("damage", ["vt 0.5x 0.5", "vt 0.33800.245", "texture index past the rows", "texture index 1o"])
def test_damaged_texture_coordinates_go_to_trimesh(tmp_path, monkeypatch, damage):
    """Rows and indices of texture coordinates no material uses are still checked: trimesh
    refuses a damaged row and drops an object's uvs (its colour) for an index past them, so
    such files are left to it (found by a fuzzer comparing both readings on damaged files)."""
    path = _file(tmp_path, "uv.obj", "{v}/{t}/{n}")
    text = path.read_text()
    if damage.startswith("vt"):
        text = text.replace("vt 0.5 0.5", damage, 1)
    else:
        face = next(line for line in text.splitlines() if line.startswith("f "))
        corner = face.split()[1]
        v, _, n = corner.split("/")
        text = text.replace(face, face.replace(corner, f"{v}/{'99' if 'past' in damage else '1o'}/{n}", 1), 1)
    path.write_text(text)
    data, names = obj_objects(path)
    assert obj_read.decode(data, names) is None


def test_objects_of_one_material_share_their_skeleton_object(tmp_path, monkeypatch):
    """1,000 parts over 3 materials, some inheriting the material before them: trimesh reads
    one skeleton object per distinct content, and every part gets the colour it gets from
    trimesh's reading of the whole file."""
    (tmp_path / "parts.mtl").write_text(MTL)
    uses = [[["red"], ["blue"], [], ["grey"]][k % 4] for k in range(1000)]
    path = _material_file(tmp_path, "parts.mtl", uses)
    data, _ = obj_objects(path)
    skeleton, stands_for = obj_read.material_skeleton(data)
    assert len(stands_for) == 1000 and len(set(stands_for.values())) == 3  # [] inherits blue
    assert skeleton.count(b"\no rtta.o.") == 3
    direct, via_trimesh = _both(path, monkeypatch)
    np.testing.assert_array_equal(direct.colors, via_trimesh.colors)
    assert len({tuple(c) for c in direct.colors.tolist()}) == 3
