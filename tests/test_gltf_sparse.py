"""Sparse accessors (glTF 2.0, 3.6.2.3): a file whose positions are a base accessor with
substitutions loads as the same file written densely, through the direct reader and
through trimesh (which ignores `sparse` on its own); broken sparse parts give one error."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from bad_gltf import box_arrays, box_doc, glb
from test_gltf_read import _load

MOVED = np.array([0, 5, 23])  # box vertices the substitutions move
SHIFT = np.array([0.75, 0.0, 0.25], np.float32)


def _sparse_file(index_type: int = 5123, bufferless: bool = False) -> tuple[dict, bytes]:
    """The box with MOVED shifted by SHIFT through a sparse POSITION accessor. bufferless:
    the base is zeros (no bufferView) and every vertex is substituted."""
    doc, binary = box_doc()
    pos = box_arrays()[0]
    at = np.arange(len(pos)) if bufferless else MOVED
    values = pos[at] + (0 if bufferless else SHIFT)
    indices = at.astype({5121: np.uint8, 5123: np.uint16, 5125: np.uint32}[index_type]).tobytes()
    indices += b"\0" * (-len(indices) % 4)
    doc["bufferViews"] += [
        {"buffer": 0, "byteOffset": len(binary), "byteLength": len(indices)},
        {"buffer": 0, "byteOffset": len(binary) + len(indices), "byteLength": values.nbytes},
    ]
    binary += indices + values.astype(np.float32).tobytes()
    doc["buffers"][0]["byteLength"] = len(binary)
    acc = doc["accessors"][0]
    acc["sparse"] = {
        "count": len(at),
        "indices": {"bufferView": 3, "componentType": index_type},
        "values": {"bufferView": 4},
    }
    acc.pop("min"), acc.pop("max")
    if bufferless:
        del acc["bufferView"]
    return doc, binary


def _dense_file() -> bytes:
    doc, _ = box_doc()
    pos, nrm, idx = box_arrays()
    pos = pos.copy()
    pos[MOVED] += SHIFT
    doc["accessors"][0].pop("min"), doc["accessors"][0].pop("max")
    return glb(doc, pos.tobytes() + nrm.tobytes() + idx.tobytes())


@pytest.mark.parametrize("direct", [True, False])
@pytest.mark.parametrize("index_type", [5121, 5123, 5125])
def test_sparse_positions_load_as_the_dense_file(tmp_path, monkeypatch, direct, index_type):
    (tmp_path / "sparse.glb").write_bytes(glb(*_sparse_file(index_type)))
    (tmp_path / "dense.glb").write_bytes(_dense_file())
    got = _load(tmp_path / "sparse.glb", direct, monkeypatch)
    want = _load(tmp_path / "dense.glb", direct, monkeypatch)
    assert not isinstance(got, str), got
    assert got.warnings == want.warnings == []
    np.testing.assert_array_equal(got.origin + got.positions, want.origin + want.positions)
    np.testing.assert_array_equal(got.indices, want.indices)
    np.testing.assert_array_equal(got.normals, want.normals)
    # the substitutions matter: the box's own corners are not what loaded
    assert np.abs(got.origin + got.positions).max() > 0.5 + 0.7


@pytest.mark.parametrize("direct", [True, False])
def test_bufferless_sparse_accessor_is_its_substitutions(tmp_path, monkeypatch, direct):
    doc, binary = box_doc()
    (tmp_path / "box.glb").write_bytes(glb(doc, binary))
    (tmp_path / "sparse.glb").write_bytes(glb(*_sparse_file(bufferless=True)))
    got, want = (_load(tmp_path / n, direct, monkeypatch) for n in ("sparse.glb", "box.glb"))
    np.testing.assert_array_equal(got.origin + got.positions, want.origin + want.positions)


def _broken(change) -> bytes:
    doc, binary = _sparse_file()
    doc = copy.deepcopy(doc)
    change(doc["accessors"][0]["sparse"])
    return glb(doc, binary)


@pytest.mark.parametrize(
    "change, says",
    [
        (lambda s: s["indices"].update(bufferView=4), "sparse indices up to"),  # floats read as indices
        (lambda s: s.update(count=25), "sparse.count is 25, more than the accessor's 24 values"),
        (lambda s: s["values"].update(byteOffset=8), "sparse.values needs bytes 8 to 44 of bufferView 4"),
        (lambda s: s["indices"].update(componentType=5126), "not an index type"),
        (lambda s: s.pop("values"), "sparse.values has no 'bufferView'"),
        (lambda s: s.update(indices=[]), "sparse.indices must be an object"),
    ],
)
def test_broken_sparse_parts_are_refused(tmp_path, monkeypatch, change, says):
    path = tmp_path / "broken.glb"
    path.write_bytes(_broken(change))
    for direct in (True, False):
        got = _load(path, direct, monkeypatch)
        assert isinstance(got, str) and says in got, got
