"""The direct glTF reader (rtta.scene.readers.gltf_read) gives the scene trimesh's path gives.

Each file is loaded twice, once as it is and once with the direct reader switched off, and
the two scenes must be equal: names, tree paths, vertices, faces, normals, colours, texture
ids and warnings; or both loads fail with the same message. The files: plain ones that
take the direct path (strided views, every index type, no indices, fans, materials
without a factor, primitives without a material, several primitives, NaN normals,
mirrored and sheared nodes), the loading files of the bad-input corpus, and malformed
documents made by hypothesis.
"""

from __future__ import annotations

import copy

import numpy as np
import pytest
from bad_gltf import box_doc, glb, gltf_loading_files
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_gltf_fuzz import BASE, BINARY, PATHS, VALUES, _apply

from rtta.errors import RttaError
from rtta.scene.generators.assembly import write_assembly
from rtta.scene.loader import load_scene
from rtta.scene.readers import gltf, gltf_graph
from rtta.scene.readers.gltf_read import plain


def _load(path, direct: bool, monkeypatch, smooth: bool = False):
    with monkeypatch.context() as m:
        if not direct:
            m.setattr(gltf.Prepared, "decoded", lambda self: None)
        try:
            return load_scene(path, smooth=smooth, cache=False)  # both readings, never the scene cache
        except RttaError as exc:
            return str(exc)


def _same(path, monkeypatch, smooth: bool = False) -> None:
    a, b = _load(path, True, monkeypatch, smooth), _load(path, False, monkeypatch, smooth)
    if isinstance(a, str) or isinstance(b, str):
        assert a == b
        return
    assert a.names == b.names and a.paths == b.paths and a.warnings == b.warnings
    assert (a.texture_ids is None) == (b.texture_ids is None) and len(a.textures) == len(b.textures)
    np.testing.assert_array_equal(a.origin, b.origin)
    np.testing.assert_array_equal(a.positions, b.positions)
    np.testing.assert_array_equal(a.indices, b.indices)
    np.testing.assert_array_equal(a.index_ranges, b.index_ranges)
    np.testing.assert_array_equal(a.normals, b.normals)
    np.testing.assert_array_equal(a.colors, b.colors)
    np.testing.assert_array_equal(a.object_ids, b.object_ids)


def _direct(path) -> bool:
    prepared = gltf.prepare(path)
    return plain(prepared.doc, prepared.pairs)


def _strided(doc: dict, binary: bytes) -> tuple[dict, bytes]:
    """Positions and normals interleaved in one view with byteStride 24."""
    pos = np.frombuffer(binary[:288], np.float32).reshape(24, 3)
    nrm = np.frombuffer(binary[288:576], np.float32).reshape(24, 3)
    binary = np.hstack([pos, nrm]).tobytes() + binary[576:]
    doc["bufferViews"] = [
        {"buffer": 0, "byteOffset": 0, "byteLength": 576, "byteStride": 24},
        {"buffer": 0, "byteOffset": 576, "byteLength": 72},
    ]
    doc["accessors"][0]["bufferView"] = 0
    doc["accessors"][1].update(bufferView=0, byteOffset=12)
    doc["accessors"][2]["bufferView"] = 1
    return doc, binary


def _plain_files() -> dict[str, bytes]:
    out = {}
    nodes = [
        {"mesh": 0, "name": "a", "children": [1, 2]},
        {"mesh": 0, "name": "mirror", "scale": [-1, 1, 1], "translation": [2, 0, 0]},
        {"mesh": 0, "name": "shear", "matrix": [1, 0, 0, 0, 0.5, 1, 0, 0, 0, 0, 2, 0, 0, 3, 0, 1]},
    ]
    doc, binary = box_doc(nodes, prims=2)
    doc["materials"] = [{"pbrMetallicRoughness": {"baseColorFactor": [0.3, 0.62, 0.11, 0.5]}}, {"name": "no factor"}]
    doc["meshes"][0]["primitives"][0]["material"] = 0
    doc["meshes"][0]["primitives"][1]["material"] = 1
    out["materials_and_mirrors.glb"] = glb(doc, binary)
    del doc["meshes"][0]["primitives"][1]["attributes"]["NORMAL"]  # smoothed, in world space where sheared
    out["one_primitive_smoothed.glb"] = glb(doc, binary)
    doc, binary = _strided(*box_doc())
    out["strided.glb"] = glb(doc, binary)
    doc, binary = box_doc()
    idx = np.frombuffer(binary[576:], np.uint16)
    for ctype, dtype in ((5121, np.uint8), (5125, np.uint32)):
        data = idx.astype(dtype).tobytes()
        doc["bufferViews"][2]["byteLength"] = len(data)
        doc["accessors"][2]["componentType"] = ctype
        doc["buffers"][0]["byteLength"] = 576 + len(data)
        out[f"indices_{ctype}.glb"] = glb(doc, binary[:576] + data)
    doc, binary = box_doc()
    pos = np.frombuffer(binary[:288], np.float32).reshape(24, 3)[idx]
    nrm = np.frombuffer(binary[288:576], np.float32).reshape(24, 3)[idx]
    nrm = nrm.copy()
    nrm[0] = np.nan  # unusable normals: smoothed instead
    binary = pos.tobytes() + nrm.tobytes()
    doc["bufferViews"] = [
        {"buffer": 0, "byteOffset": 0, "byteLength": 432},
        {"buffer": 0, "byteOffset": 432, "byteLength": 432},
    ]
    doc["accessors"] = [
        {"bufferView": 0, "componentType": 5126, "count": 36, "type": "VEC3"},
        {"bufferView": 1, "componentType": 5126, "count": 36, "type": "VEC3"},
    ]
    del doc["meshes"][0]["primitives"][0]["indices"]
    doc["buffers"][0]["byteLength"] = len(binary)
    out["no_indices_nan_normals.glb"] = glb(doc, binary)
    return out


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return tmp_path_factory.mktemp("gltf_read")


@pytest.mark.parametrize("name", sorted(_plain_files()))
def test_plain_files_are_read_directly_and_equal_trimesh(folder, name, monkeypatch):
    path = folder / name
    path.write_bytes(_plain_files()[name])
    assert _direct(path), name
    _same(path, monkeypatch)


@pytest.mark.parametrize(("normals", "smooth"), [(False, False), (True, False), (True, True)])
def test_assembly_is_read_directly_and_equals_trimesh(folder, normals, smooth, monkeypatch):
    """Also with `smooth` (file normals ignored, every part smoothed) on a file that has them."""
    path = write_assembly(folder / f"assembly_{normals}.glb", 300, seed=3, normals=normals)
    assert _direct(path)
    _same(path, monkeypatch, smooth)


@pytest.mark.parametrize("name", sorted(gltf_loading_files()))
def test_corpus_files_load_alike(folder, name, monkeypatch):
    path = folder / name
    path.write_bytes(gltf_loading_files()[name][0])
    _same(path, monkeypatch)


def test_textured_and_coloured_files_go_through_trimesh(folder):
    doc, binary = box_doc()
    doc["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"] = 1
    path = folder / "vertex_colours.glb"
    path.write_bytes(glb(doc, binary))
    assert not _direct(path)
    path = folder / "textured.glb"
    path.write_bytes(gltf_loading_files()["pictures_corrupt_embedded_texture.glb"][0])
    assert not _direct(path)


@settings(
    max_examples=150,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(st.lists(st.tuples(st.sampled_from(PATHS), VALUES), min_size=1, max_size=3))
def test_malformed_files_load_alike(folder, monkeypatch, mutations):
    doc = copy.deepcopy(BASE)
    for path, value in mutations:
        _apply(doc, path, value)
    path = folder / "fuzz.glb"
    path.write_bytes(glb(doc, BINARY))
    _same(path, monkeypatch)


def test_node_transforms_equal_trimesh_transformations():
    """gltf_graph.local_transforms (whole-array TRS) against trimesh.transformations composed node by node."""
    import trimesh.transformations as tf

    rng = np.random.default_rng(5)
    nodes, expect = [], []
    for i in range(40):
        node, m = {}, np.identity(4)
        if i % 4 == 3:
            node["matrix"] = rng.normal(size=16).tolist()
            m = np.array(node["matrix"]).reshape(4, 4).T
        else:
            if i % 2:
                node["translation"] = rng.normal(size=3).tolist()
                m = m @ tf.translation_matrix(node["translation"])
            if i % 3:
                q = rng.normal(size=4) if i % 5 else np.zeros(4)
                node["rotation"] = q.tolist()
                x, y, z, w = q
                m = m @ (tf.quaternion_matrix([w, x, y, z]) if q.any() else np.identity(4))
            if i % 5 != 1:
                node["scale"] = rng.uniform(-2, 2, 3).tolist()
                m = m @ np.diag([*node["scale"], 1.0])
        nodes.append(node)
        expect.append(m)
    np.testing.assert_allclose(gltf_graph.local_transforms(nodes), np.array(expect), rtol=0, atol=1e-12)


def test_automatic_collection_is_paused_only_during_a_load(folder):
    """load_scene pauses the cyclic collector (the document's objects would be traversed
    again and again) and turns it back on, also when the file is refused."""
    import gc

    path = write_assembly(folder / "gc.glb", 20)
    bad = folder / "gc_bad.glb"
    bad.write_bytes(b"glTF" + b"\0" * 30)
    seen = []
    original = gltf.prepare

    def spy(p):
        seen.append(gc.isenabled())
        return original(p)

    with pytest.MonkeyPatch.context() as m:
        m.setattr("rtta.scene.readers.mesh.prepare", spy)
        load_scene(path)
        with pytest.raises(RttaError):
            load_scene(bad)
    assert seen == [False, False] and gc.isenabled()
