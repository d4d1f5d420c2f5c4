"""Loading: one object per scene-graph node with geometry, batching, normals, bad input."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from rtta.errors import RttaError
from rtta.scene.loader import load_scene
from rtta.scene.model import unique_names


def test_demo_assembly(demo_scene):
    assert 15 <= demo_scene.count <= 30
    assert len(set(demo_scene.names)) == demo_scene.count
    assert {"rotor", "caliper", "pad_inner", "pad_outer", "piston_1", "bracket"} <= set(demo_scene.names)
    # one batch: ids per vertex cover every object, index ranges tile the index buffer
    assert set(np.unique(demo_scene.object_ids)) == set(range(demo_scene.count))
    first, count = demo_scene.index_ranges.T
    assert first[0] == 0 and (first[1:] == first[:-1] + count[:-1]).all()
    assert first[-1] + count[-1] == len(demo_scene.indices)
    for oid in range(demo_scene.count):
        f, c = demo_scene.index_ranges[oid]
        assert (demo_scene.object_ids[demo_scene.indices[f : f + c]] == oid).all()
    np.testing.assert_allclose(np.linalg.norm(demo_scene.normals, axis=1), 1.0, atol=1e-3)


def test_instances_are_separate_objects(tmp_path):
    box = trimesh.creation.box()
    scene = trimesh.Scene()
    for k in range(3):
        scene.add_geometry(
            box,
            node_name=("bolt_a", "bolt_b", "nut")[k],
            geom_name="box",
            transform=trimesh.transformations.translation_matrix((3.0 * k, 0, 0)),
        )
    path = tmp_path / "inst.glb"
    path.write_bytes(scene.export(file_type="glb"))
    s = load_scene(path)
    assert s.count == 3 and len(set(s.names)) == 3
    centers = sorted(((s.aabb_min + s.aabb_max) / 2)[:, 0].round(6))
    assert centers == [0.0, 3.0, 6.0]


@pytest.mark.parametrize("ext", ["obj", "stl", "ply", "off", "3mf"])
def test_formats(tmp_path, ext):
    mesh = trimesh.creation.icosphere(subdivisions=1)
    path = tmp_path / f"sphere.{ext}"
    mesh.export(path)
    s = load_scene(path)
    assert s.count == 1 and s.vertex_count >= 12
    np.testing.assert_allclose(np.linalg.norm(s.normals, axis=1), 1.0, atol=1e-3)  # computed when missing


def test_far_scene_keeps_precision(tmp_path):
    mesh = trimesh.creation.box(extents=(1e-3, 1e-3, 1e-3))
    scene = trimesh.Scene()
    scene.add_geometry(mesh, node_name="far", transform=trimesh.transformations.translation_matrix((1e6, 2e6, -3e6)))
    path = tmp_path / "far.glb"
    path.write_bytes(scene.export(file_type="glb"))
    s = load_scene(path)
    np.testing.assert_allclose(s.origin, (1e6, 2e6, -3e6), atol=1e-6)
    extent = s.positions.max(axis=0) - s.positions.min(axis=0)
    np.testing.assert_allclose(extent, 1e-3, rtol=1e-4)  # float32 relative to the origin


def _write(path, data: bytes):
    path.write_bytes(data)
    return path


@pytest.mark.parametrize(
    "name,data,message",
    [
        ("empty.glb", b"", "empty"),
        ("text.glb", b"this is not a glb file at all", "not a GLB file"),
        ("trunc.stl", b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0", "no objects"),
        ("trunc.glb", b"glTF\x02\x00\x00\x00\xff\xff\x00\x00JSON", "truncated"),
        ("mesh.xyz", b"1 2 3", "unsupported file type"),
        ("nan.obj", b"v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "NaN or infinite"),
        ("inf.obj", b"v inf 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "NaN or infinite"),
        ("nofaces.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\n", "no objects"),
    ],
)
def test_bad_input_is_one_clear_error(tmp_path, name, data, message):
    path = _write(tmp_path / name, data)
    with pytest.raises(RttaError) as info:
        load_scene(path)
    text = str(info.value)
    assert name in text and message in text and "\n" not in text


def test_missing_file(tmp_path):
    with pytest.raises(RttaError, match="no such file"):
        load_scene(tmp_path / "nope.glb")


def test_unique_names():
    assert unique_names(["a", "a", "b", "a_2", ""]) == ["a", "a_3", "b", "a_2", "object"]


def _obj(tmp_path, text: str):
    path = tmp_path / "parts.obj"
    path.write_text(text)
    return load_scene(path)


TRIANGLES = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nv 3 0 0\nv 2 1 0\nv 4 0 0\nv 5 0 0\nv 4 1 0\n"


def test_obj_groups_are_the_parts_when_there_are_no_objects(tmp_path):
    """Many CAD exporters write each part as a `g` group and no more than one `o` line: the
    groups are the objects then, named and ordered as in the file (repeated names numbered);
    in a file with several `o` lines, groups stay inside their objects."""
    scene = _obj(tmp_path, TRIANGLES + "g bolt\nf 1 2 3\ng nut front\nf 4 5 6\ng bolt\nf 7 8 9\n")
    assert scene.names == ["bolt", "nut front", "bolt_2"]
    assert np.allclose(scene.aabb_min[:, 0], [0, 2, 4])
    scene = _obj(tmp_path, TRIANGLES + "o assembly\ng bolt\nf 1 2 3\ng nut\nf 4 5 6\no washer\nf 7 8 9\n")
    assert scene.names == ["assembly", "washer"]
    assert scene.index_ranges[:, 1].tolist() == [6, 3]
    scene = _obj(tmp_path, TRIANGLES + "o model\ng bolt\nf 1 2 3\ng nut\nf 4 5 6\nf 7 8 9\n")  # one `o`
    assert scene.names == ["bolt", "nut"] and scene.index_ranges[:, 1].tolist() == [3, 6]
    assert _obj(tmp_path, TRIANGLES + "o single\ng only\nf 1 2 3\nf 4 5 6\n").names == ["single"]
    assert _obj(tmp_path, TRIANGLES + "f 1 2 3\nf 4 5 6\n").count == 1
