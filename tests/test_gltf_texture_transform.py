"""KHR_texture_transform on the base-colour texture: the loaded texture coordinates are the
file's, transformed as glTF says (T R S), compared with the same file loaded without it."""

from __future__ import annotations

import copy
import json
import struct

import numpy as np
from bad_gltf import png

from rtta.scene.loader import load_scene


def _textured_quad(transform: dict | None) -> bytes:
    pos = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], np.float32)
    uv = np.array([[0.1, 0.2], [0.9, 0.25], [0.8, 0.7], [0.15, 0.95]], np.float32)
    idx = np.array([0, 1, 2, 0, 2, 3], np.uint16)
    image = png((8, 8))
    binary = pos.tobytes() + uv.tobytes() + idx.tobytes() + b"\0\0"
    start = len(binary)
    binary += image + b"\0" * (-len(image) % 4)
    texture = {"index": 0}
    if transform is not None:
        texture["extensions"] = {"KHR_texture_transform": transform}
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": "q"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": texture}}],
        "textures": [{"source": 0}],
        "images": [{"bufferView": 3, "mimeType": "image/png"}],
        "buffers": [{"byteLength": len(binary)}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 32},
            {"buffer": 0, "byteOffset": 80, "byteLength": 12},
            {"buffer": 0, "byteOffset": start, "byteLength": len(image)},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"},
        ],
    }
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    return (
        struct.pack("<4sIII", b"glTF", 2, 28 + len(text) + len(binary), len(text))
        + b"JSON"
        + text
        + struct.pack("<I", len(binary))
        + b"BIN\0"
        + binary
    )


def _uvs(tmp_path, transform):
    path = tmp_path / "quad.glb"
    path.write_bytes(_textured_quad(copy.deepcopy(transform)))
    scene = load_scene(path)
    assert scene.textured
    return scene, scene.uvs[np.argsort(scene.positions[:, 0] * 2 + scene.positions[:, 1])]  # by position


def test_texture_transform_is_applied(tmp_path):
    _, plain = _uvs(tmp_path, None)
    t = {"offset": [0.25, -0.5], "rotation": 0.7, "scale": [2.0, 3.0]}
    _, got = _uvs(tmp_path, t)
    # the loader gives v flipped against glTF's (row 0 at the bottom): flip, transform, flip back
    u, v = plain[:, 0], 1.0 - plain[:, 1]
    c, s = np.cos(0.7), np.sin(0.7)
    tu = c * 2.0 * u + s * 3.0 * v + 0.25
    tv = -s * 2.0 * u + c * 3.0 * v - 0.5
    np.testing.assert_allclose(got, np.stack([tu, 1.0 - tv], axis=1), atol=1e-5)
    assert np.abs(got - plain).max() > 0.5


def test_a_transform_that_is_not_numbers_is_left_out_with_a_warning(tmp_path):
    _, plain = _uvs(tmp_path, None)
    scene, got = _uvs(tmp_path, {"rotation": "a lot"})
    np.testing.assert_array_equal(got, plain)
    assert any("KHR_texture_transform" in w for w in scene.warnings)


def test_a_texture_on_the_second_coordinate_set_reads_that_set(tmp_path):
    """`texCoord: 1`: the texture is mapped by TEXCOORD_1 (here the first set shifted by 0.5)."""
    _, plain = _uvs(tmp_path, None)
    data = _textured_quad(None)
    n = struct.unpack_from("<I", data, 12)[0]
    doc = json.loads(data[20 : 20 + n])
    binary = data[28 + n :]
    uv = np.frombuffer(binary[48:80], np.float32).reshape(4, 2) + 0.5
    doc["bufferViews"].append({"buffer": 0, "byteOffset": len(binary), "byteLength": 32})
    doc["accessors"].append({"bufferView": 4, "componentType": 5126, "count": 4, "type": "VEC2"})
    binary += uv.tobytes()
    doc["buffers"][0]["byteLength"] = len(binary)
    prim = doc["meshes"][0]["primitives"][0]
    prim["attributes"]["TEXCOORD_1"] = 3
    doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["texCoord"] = 1
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    path = tmp_path / "second.glb"
    path.write_bytes(
        struct.pack("<4sIII", b"glTF", 2, 28 + len(text) + len(binary), len(text))
        + b"JSON"
        + text
        + struct.pack("<I", len(binary))
        + b"BIN\0"
        + binary
    )
    scene = load_scene(path)
    got = scene.uvs[np.argsort(scene.positions[:, 0] * 2 + scene.positions[:, 1])]
    np.testing.assert_allclose(got, plain + [0.5, -0.5], atol=1e-6)  # v is flipped on loading
