"""glTF's KHR_draco_mesh_compression (rtta.scene.readers.draco): compressed primitives load as the
meshes they encode, by both glTF readers; damaged or inconsistent Draco data gives one
error line naming the file; without DracoPy the error says how to add it."""

from __future__ import annotations

import copy
import json
import struct

import numpy as np
import pytest
import trimesh
from test_gltf_read import _load

from rtta.cli.main import main
from rtta.scene.readers import draco

DracoPy = pytest.importorskip("DracoPy")  # in the `draco` extra, which the test extra installs

SHAPES = {
    "box": trimesh.creation.box(),
    "sphere": trimesh.creation.icosphere(2),
    "cylinder": trimesh.creation.cylinder(0.5, 1.5, sections=24),
}


def _glb(doc: dict, binary: bytes) -> bytes:
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    binary += b"\0" * (-len(binary) % 4)
    return (
        struct.pack("<4sIII", b"glTF", 2, 28 + len(text) + len(binary), len(text))
        + b"JSON"
        + text
        + struct.pack("<I", len(binary))
        + b"BIN\0"
        + binary
    )


def _draco_doc() -> tuple[dict, bytes]:
    """The three SHAPES side by side, each a Draco-compressed primitive with normals."""
    meshes, views, accessors, nodes, binary = [], [], [], [], b""
    for i, (name, shape) in enumerate(SHAPES.items()):
        v = shape.vertices + (2.0 * i, 0.0, 0.0)
        blob = DracoPy.encode(
            v.astype(np.float32),
            shape.faces.astype(np.uint32),
            normals=shape.vertex_normals.astype(np.float64),
            quantization_bits=16,
        )
        ids = {a["attribute_type"]: a["unique_id"] for a in DracoPy.decode(blob).attributes}
        views.append({"buffer": 0, "byteOffset": len(binary), "byteLength": len(blob)})
        binary += blob + b"\0" * (-len(blob) % 4)
        a = len(accessors)
        accessors += [
            {"componentType": 5126, "count": len(v), "type": "VEC3"},
            {"componentType": 5126, "count": len(v), "type": "VEC3"},
            {"componentType": 5125, "count": shape.faces.size, "type": "SCALAR"},
        ]
        ext = {"bufferView": len(views) - 1, "attributes": {"POSITION": ids[0], "NORMAL": ids[1]}}
        meshes.append(
            {
                "primitives": [
                    {
                        "attributes": {"POSITION": a, "NORMAL": a + 1},
                        "indices": a + 2,
                        "extensions": {draco.EXTENSION: ext},
                    }
                ]
            }
        )
        nodes.append({"mesh": i, "name": name})
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": nodes,
        "meshes": meshes,
        "buffers": [{"byteLength": len(binary)}],
        "bufferViews": views,
        "accessors": accessors,
        "extensionsUsed": [draco.EXTENSION],
        "extensionsRequired": [draco.EXTENSION],
    }
    return doc, binary


@pytest.mark.parametrize("direct", [True, False])
def test_draco_primitives_load_as_the_meshes_they_encode(tmp_path, monkeypatch, direct):
    path = tmp_path / "draco.glb"
    path.write_bytes(_glb(*_draco_doc()))
    scene = _load(path, direct, monkeypatch)
    assert not isinstance(scene, str), scene
    assert scene.names == list(SHAPES)
    tris = np.diff(np.r_[scene.index_ranges[:, 0], len(scene.indices)]) // 3
    assert tris.tolist() == [len(s.faces) for s in SHAPES.values()]
    for i, shape in enumerate(SHAPES.values()):
        lo, hi = shape.bounds + (2.0 * i, 0.0, 0.0)
        np.testing.assert_allclose(scene.aabb_min[i], lo, atol=1e-3)
        np.testing.assert_allclose(scene.aabb_max[i], hi, atol=1e-3)
        first, count = scene.index_ranges[i]
        corners = scene.positions[scene.indices[first : first + count]] + scene.origin
        # every loaded corner is a vertex of the shape (to the 16-bit quantization)
        gap = np.abs(corners[:, None, :] - (shape.vertices + (2.0 * i, 0, 0))[None]).max(-1).min(-1)
        assert gap.max() < 1e-3


def test_both_readers_agree(tmp_path, monkeypatch):
    path = tmp_path / "draco.glb"
    path.write_bytes(_glb(*_draco_doc()))
    a, b = _load(path, True, monkeypatch), _load(path, False, monkeypatch)
    np.testing.assert_array_equal(a.positions, b.positions)
    np.testing.assert_array_equal(a.indices, b.indices)
    np.testing.assert_array_equal(a.normals, b.normals)


def test_without_dracopy_the_error_says_how_to_add_it(tmp_path, monkeypatch, capsys):
    path = tmp_path / "draco.glb"
    path.write_bytes(_glb(*_draco_doc()))
    monkeypatch.setattr(draco, "available", lambda: False)
    assert main(["info", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "KHR_draco_mesh_compression" in err[0] and "rtta[draco]" in err[0]


def _damaged(change) -> bytes:
    doc, binary = _draco_doc()
    doc, binary = copy.deepcopy(doc), bytearray(binary)
    change(doc, binary)
    return _glb(doc, bytes(binary))


def _garble(doc, binary):
    view = doc["bufferViews"][1]
    binary[view["byteOffset"] + 8 : view["byteOffset"] + view["byteLength"]] = bytes(view["byteLength"] - 8)


def _ext(doc, i=0):
    return doc["meshes"][i]["primitives"][0]["extensions"][draco.EXTENSION]


@pytest.mark.parametrize(
    "change, says",
    [
        (_garble, "cannot be decoded"),
        (
            lambda d, b: [d["accessors"][k].update(count=3) for k in (0, 1)],
            "decodes POSITION to 8 values of 3, where the file declares 3",
        ),
        (lambda d, b: d["accessors"][2].update(count=6), "decodes to 36 indices, where the file declares 6"),
        (lambda d, b: _ext(d).update(bufferView=99), "needs a 'bufferView' index below 3"),
        (lambda d, b: _ext(d)["attributes"].update(NORMAL=7), "has no attribute 7 (NORMAL)"),
        (lambda d, b: _ext(d)["attributes"].pop("POSITION"), "has no POSITION"),
        (lambda d, b: _ext(d).update(attributes=[]), "must map attribute names to Draco ids"),
    ],
)
def test_damaged_draco_data_gives_one_error(tmp_path, capsys, change, says):
    path = tmp_path / "damaged.glb"
    path.write_bytes(_damaged(change))
    assert main(["info", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"rtta: error: {path}: ") and says in err[0], err
