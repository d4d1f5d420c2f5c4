"""glTF builders and the glTF part of the bad-input corpus (tests/bad_inputs.py): documents
whose fields have the wrong type or range, broken node graphs, and the files that load
with a warning (names, colours, dropped or rewritten primitives, textures)."""

from __future__ import annotations

import copy
import io
import json
import struct
from collections.abc import Callable

import numpy as np

# a unit box: 24 vertices (flat normals), 36 indices, outward winding
_CORNERS = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)], np.float32)
_QUADS = [
    (0, 1, 3, 2, (-1, 0, 0)),
    (4, 6, 7, 5, (1, 0, 0)),
    (0, 4, 5, 1, (0, -1, 0)),
    (2, 3, 7, 6, (0, 1, 0)),
    (0, 2, 6, 4, (0, 0, -1)),
    (1, 5, 7, 3, (0, 0, 1)),
]


def box_arrays() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(positions [24, 3], normals [24, 3], indices [36]) of a unit box, faces outward."""
    pos, nrm, idx = [], [], []
    for a, b, c, d, n in _QUADS:
        base = len(pos)
        pos += [_CORNERS[k] for k in (a, b, c, d)]
        nrm += [n] * 4
        idx += [base, base + 1, base + 2, base, base + 2, base + 3]
    return np.array(pos, np.float32), np.array(nrm, np.float32), np.array(idx, np.uint16)


def box_doc(nodes: list[dict] | None = None, prims: int = 1) -> tuple[dict, bytes]:
    """A glTF document (one mesh of `prims` box primitives) and its binary buffer; `nodes`
    default to one node 'box' with the mesh."""
    pos, nrm, idx = box_arrays()
    binary = pos.tobytes() + nrm.tobytes() + idx.tobytes()
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": nodes if nodes is not None else [{"mesh": 0, "name": "box"}],
        "meshes": [
            {
                "name": "m",
                "primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2} for _ in range(prims)],
            }
        ],
        "buffers": [{"byteLength": len(binary)}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 288},
            {"buffer": 0, "byteOffset": 288, "byteLength": 288},
            {"buffer": 0, "byteOffset": 576, "byteLength": 72},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 24, "type": "VEC3", "min": [-0.5] * 3, "max": [0.5] * 3},
            {"bufferView": 1, "componentType": 5126, "count": 24, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5123, "count": 36, "type": "SCALAR"},
        ],
    }
    if nodes is not None and all("mesh" not in n for n in nodes):
        doc["scenes"] = [{"nodes": [0]}]
    return doc, binary


def glb(doc: dict, binary: bytes = b"") -> bytes:
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    binary = binary + b"\0" * (-len(binary) % 4)
    total = 12 + 8 + len(text) + (8 + len(binary) if binary else 0)
    out = struct.pack("<4sIII", b"glTF", 2, total, len(text)) + b"JSON" + text
    return out + (struct.pack("<I", len(binary)) + b"BIN\0" + binary if binary else b"")


def png(size=(4, 4), color=(200, 30, 30)) -> bytes:
    from PIL import Image

    buf = io.BytesIO()
    Image.new("RGB", size, color).save(buf, format="PNG")
    return buf.getvalue()


def _mutated(change: Callable[[dict], object], nodes=None, prims: int = 1) -> bytes:
    doc, binary = box_doc(nodes, prims)
    change(doc)
    return glb(doc, binary)


def _set(*path_value):
    """A change that sets doc[path...] = value."""
    *path, value = path_value

    def change(doc):
        target = doc
        for key in path[:-1]:
            target = target[key]
        target[path[-1]] = copy.deepcopy(value)

    return change


def _delete(*path):
    def change(doc):
        target = doc
        for key in path[:-1]:
            target = target[key]
        del target[path[-1]]

    return change


def _chain(depth: int) -> list[dict]:
    return [{"children": [i + 1], "name": f"level{i}"} for i in range(depth)] + [{"mesh": 0, "name": "leaf"}]


def _binary_dag(levels: int) -> list[dict]:
    """Node i has node i+1 twice as its child: 2**levels paths to the leaf."""
    return [{"children": [i + 1, i + 1]} for i in range(levels)] + [{"mesh": 0, "name": "leaf"}]


# (name, change, says): every one must be a one-line error containing `says`
GLTF_ERRORS: list[tuple[str, Callable, str]] = [
    ("accessors_is_int", _set("accessors", 5), "'accessors' must be an array"),
    ("accessors_is_dict", _set("accessors", {"0": {}}), "'accessors' must be an array"),
    ("accessor_is_string", _set("accessors", 0, "x"), "accessors[0] must be an object"),
    ("count_1e400", _set("accessors", 0, "count", float("inf")), "accessors[0].count"),
    ("count_string", _set("accessors", 0, "count", "24"), "accessors[0].count"),
    ("count_negative", _set("accessors", 0, "count", -3), "accessors[0].count"),
    ("count_huge", _set("accessors", 0, "count", 10**15), "accessors[0].count"),
    ("count_beyond_view", _set("accessors", 0, "count", 25), "bufferView 0"),
    ("count_missing", _delete("accessors", 0, "count"), "has no 'count'"),
    ("component_type_string", _set("accessors", 0, "componentType", "float"), "componentType"),
    ("component_type_unknown", _set("accessors", 0, "componentType", 5130), "componentType"),
    ("type_unknown", _set("accessors", 0, "type", "VEC7"), "accessors[0].type"),
    ("position_is_vec2", _set("accessors", 0, "type", "VEC2"), "POSITION"),
    ("indices_are_float", _set("accessors", 2, "componentType", 5126), "indices"),
    ("buffer_view_out_of_range", _set("accessors", 0, "bufferView", 9), "bufferView is 9"),
    ("buffer_view_negative", _set("accessors", 0, "bufferView", -1), "bufferView"),
    ("byte_offset_past_view", _set("accessors", 0, "byteOffset", 400), "bufferView 0"),
    ("byte_offset_unaligned", _set("accessors", 0, "byteOffset", 2), "accessors[0]"),
    ("byte_stride_odd", _set("bufferViews", 0, "byteStride", 5), "byteStride"),
    ("view_past_buffer", _set("bufferViews", 2, "byteLength", 10**6), "buffer 0"),
    ("view_length_1e12", _set("bufferViews", 0, "byteLength", 10**12), "byteLength"),
    ("view_buffer_string", _set("bufferViews", 0, "buffer", "0"), "bufferViews[0].buffer"),
    ("buffer_length_string", _set("buffers", 0, "byteLength", "648"), "byteLength"),
    ("buffer_longer_than_bin", _set("buffers", 0, "byteLength", 10**6), "binary chunk"),
    ("buffer_uri_nul", _set("buffers", 0, "uri", "a\0b.bin"), "NUL"),
    ("buffer_uri_int", _set("buffers", 0, "uri", 7), "uri"),
    ("meshes_is_string", _set("meshes", "box"), "'meshes' must be an array"),
    ("primitives_is_int", _set("meshes", 0, "primitives", 3), "primitives"),
    ("primitives_empty", _set("meshes", 0, "primitives", []), "primitives"),
    ("attributes_is_list", _set("meshes", 0, "primitives", 0, "attributes", [0]), "attributes"),
    ("position_missing", _delete("meshes", 0, "primitives", 0, "attributes", "POSITION"), "POSITION"),
    ("position_is_string", _set("meshes", 0, "primitives", 0, "attributes", "POSITION", "0"), "POSITION"),
    ("position_out_of_range", _set("meshes", 0, "primitives", 0, "attributes", "POSITION", 99), "POSITION"),
    ("indices_float", _set("meshes", 0, "primitives", 0, "indices", 2.5), "indices"),
    ("mode_9", _set("meshes", 0, "primitives", 0, "mode", 9), "mode"),
    ("material_out_of_range", _set("meshes", 0, "primitives", 0, "material", 4), "material"),
    ("normal_count_mismatch", _set("accessors", 1, "count", 20), "NORMAL"),
    ("index_count_not_3n", _set("accessors", 2, "count", 35), "multiple of 3"),
    ("nodes_is_dict", _set("nodes", {"a": 1}), "'nodes' must be an array"),
    ("node_mesh_out_of_range", _set("nodes", 0, "mesh", 7), "mesh is 7"),
    ("node_mesh_bool", _set("nodes", 0, "mesh", True), "mesh"),
    ("children_is_int", _set("nodes", 0, "children", 1), "children"),
    ("child_out_of_range", _set("nodes", 0, "children", [5]), "children"),
    ("own_child", _set("nodes", 0, "children", [0]), "cycle"),
    ("matrix_is_string", _set("nodes", 0, "matrix", "identity"), "matrix"),
    ("matrix_15_numbers", _set("nodes", 0, "matrix", [1.0] * 15), "matrix"),
    ("matrix_nan", _set("nodes", 0, "matrix", [float("nan")] * 16), "matrix"),
    ("translation_2", _set("nodes", 0, "translation", [1, 2]), "translation"),
    ("rotation_inf", _set("nodes", 0, "rotation", [0, 0, 0, float("inf")]), "rotation"),
    ("scale_strings", _set("nodes", 0, "scale", ["1", "1", "1"]), "scale"),
    (
        "matrix_and_trs",
        lambda d: d["nodes"][0].update(
            matrix=[1.0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1], translation=[1, 0, 0]
        ),
        "matrix",
    ),
    ("scale_1e300", _set("nodes", 0, "scale", [1e300, 1e300, 1e300]), "coordinates"),
    ("name_is_int", _set("nodes", 0, "name", 42), "name"),
    ("scene_out_of_range", _set("scene", 3), "scene is 3"),
    ("scene_nodes_string", _set("scenes", 0, "nodes", "0"), "nodes"),
    ("scenes_is_int", _set("scenes", 1), "'scenes' must be an array"),
    (
        "material_color_strings",
        _set("materials", [{"pbrMetallicRoughness": {"baseColorFactor": "red"}}]),
        "baseColorFactor",
    ),
    (
        "texture_index_out_of_range",
        _set("materials", [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 3}}}]),
        "index",
    ),
    ("extensions_required_meshopt", _set("extensionsRequired", ["EXT_meshopt_compression"]), "meshopt"),
    ("extensions_required_int", _set("extensionsRequired", [1]), "extensionsRequired"),
]


def gltf_error_files() -> dict[str, tuple[bytes, str]]:
    """{file name: (GLB bytes, text the error must contain)}, the cases above plus graphs."""
    out = {f"gltf_{n}.glb": (_mutated(change), says) for n, change, says in GLTF_ERRORS}
    out["gltf_nodes_each_others_child.glb"] = (
        _mutated(lambda d: None, nodes=[{"mesh": 0, "children": [1], "name": "a"}, {"children": [0], "name": "b"}]),
        "cycle",
    )
    out["gltf_chain_2000_deep.glb"] = (_mutated(lambda d: None, nodes=_chain(2000)), "deeper than")
    out["gltf_chain_10000_deep.glb"] = (_mutated(lambda d: None, nodes=_chain(10000)), "deeper than")
    out["gltf_dag_2_pow_40_paths.glb"] = (_mutated(lambda d: None, nodes=_binary_dag(40)), "node paths")
    out["gltf_json_nested_100000.gltf"] = (b'{"asset": ' + b"[" * 100000 + b"]" * 100000 + b"}", "nested")
    out["gltf_int_5000_digits.gltf"] = (b'{"asset": {"version": "2.0"}, "scene": ' + b"9" * 5000 + b"}", "JSON")
    out["gltf_top_level_array.gltf"] = (b"[1, 2, 3]", "JSON object")
    doc, _ = box_doc()
    doc["accessors"].append({"componentType": 5126, "count": 2**31 - 1, "type": "MAT4"})
    out["gltf_bufferless_accessor_huge.glb"] = (glb(doc, box_doc()[1]), "memory limit")
    return out


def gltf_loading_files() -> dict[str, tuple[bytes, str]]:
    """{file name: (GLB bytes, text a warning must contain, '' for none)}: what loads."""
    doc, binary = box_doc(prims=2)
    out = {"names_two_primitives.glb": (glb(doc, binary), "numbered")}
    doc, binary = box_doc([{"mesh": 0, "name": "part", "translation": [2.0 * i, 0, 0]} for i in range(3)])
    doc["scenes"] = [{"nodes": [0, 1, 2]}]
    out["names_duplicate_nodes.glb"] = (glb(doc, binary), "numbered")
    doc, binary = box_doc([{"mesh": 0}, {"mesh": 0, "translation": [2, 0, 0]}])
    doc["scenes"] = [{"nodes": [0, 1]}]
    out["names_unnamed_nodes.glb"] = (glb(doc, binary), "")
    for label, name in (
        ("esc", "evil\x1b[2Jname"),
        ("bel", "ring\x07"),
        ("newline", "two\nlines"),
        ("rlo", "abc\u202edef"),
        ("nul", "nul\x00byte"),
    ):
        doc, binary = box_doc([{"mesh": 0, "name": name}])
        out[f"names_control_{label}.glb"] = (glb(doc, binary), "")
    doc, binary = box_doc(
        [
            {"children": [2], "name": "left"},
            {"children": [2], "name": "right", "translation": [3, 0, 0]},
            {"mesh": 0, "name": "shared"},
        ]
    )
    doc["scenes"] = [{"nodes": [0, 1]}]
    out["pictures_second_parent.glb"] = (glb(doc, binary), "more than one parent")
    doc, binary = box_doc()
    doc["materials"] = [{"pbrMetallicRoughness": {"baseColorFactor": [float("nan"), 0.5, 0.5, 1.0]}}]
    doc["meshes"][0]["primitives"][0]["material"] = 0
    out["pictures_nan_base_color.glb"] = (glb(doc, binary), "baseColorFactor")
    doc["materials"] = [{"pbrMetallicRoughness": {"baseColorFactor": [2.0, -1.0, 0.5, 1.0]}}]
    out["pictures_base_color_out_of_range.glb"] = (glb(doc, binary), "baseColorFactor")
    out["pictures_fan_beside_triangles.glb"] = (_fan_file(), "")
    doc, binary = box_doc(prims=2)
    doc["meshes"][0]["primitives"][1]["mode"] = 1
    out["pictures_lines_beside_triangles.glb"] = (glb(doc, binary), "lines left out")
    doc, binary = box_doc([{"mesh": 0, "name": "tiny", "scale": [1e-40] * 3}])
    out["pictures_box_at_1e-40.glb"] = (glb(doc, binary), "may be blank; scale the model up")
    doc, binary = box_doc(
        [{"mesh": 0, "name": "far", "matrix": [1e-7, 0, 0, 0, 0, 1e-7, 0, 0, 0, 0, 1e-7, 0, 1e7, 1e7, 1e7, 1]}]
    )
    out["pictures_small_box_at_1e7.glb"] = (glb(doc, binary), "cannot be placed")
    out["pictures_corrupt_embedded_texture.glb"] = (_textured(png()[:40]), "embedded")
    out["pictures_oversized_embedded_texture.glb"] = (_textured(_bomb_png()), "too large")
    out["limits_twelve_2048px_textures.glb"] = (_textured(png((2048, 2048)), copies=12), "memory limit")
    return out


def _fan_file() -> bytes:
    """A box primitive beside a triangle-fan square (4 vertices, indices 0 1 2 3)."""
    doc, binary = box_doc(prims=2)
    square = np.array([[2, -0.5, 0], [3, -0.5, 0], [3, 0.5, 0], [2, 0.5, 0]], np.float32)
    fan = np.array([0, 1, 2, 3], np.uint16)
    start = len(binary)
    binary += square.tobytes() + fan.tobytes()
    doc["buffers"][0]["byteLength"] = len(binary)
    doc["bufferViews"] += [
        {"buffer": 0, "byteOffset": start, "byteLength": 48},
        {"buffer": 0, "byteOffset": start + 48, "byteLength": 8},
    ]
    doc["accessors"] += [
        {"bufferView": 3, "componentType": 5126, "count": 4, "type": "VEC3"},
        {"bufferView": 4, "componentType": 5123, "count": 4, "type": "SCALAR"},
    ]
    doc["meshes"][0]["primitives"][1] = {"attributes": {"POSITION": 3}, "indices": 4, "mode": 6}
    return glb(doc, binary)


def _textured(image: bytes, copies: int = 1) -> bytes:
    """The box with a texture embedded in a bufferView (and texture coordinates); with
    `copies`, that many primitives, each with its own material, texture and image."""
    doc, binary = box_doc(prims=copies)
    uv = np.zeros((24, 2), np.float32)
    start = len(binary)
    binary += uv.tobytes()
    img_start = len(binary)
    binary += image + b"\0" * (-len(image) % 4)
    doc["buffers"][0]["byteLength"] = len(binary)
    doc["bufferViews"] += [
        {"buffer": 0, "byteOffset": start, "byteLength": uv.nbytes},
        {"buffer": 0, "byteOffset": img_start, "byteLength": len(image)},
    ]
    doc["accessors"].append({"bufferView": 3, "componentType": 5126, "count": 24, "type": "VEC2"})
    for k, prim in enumerate(doc["meshes"][0]["primitives"]):
        prim["attributes"]["TEXCOORD_0"] = 3
        prim["material"] = k
    doc["materials"] = [{"pbrMetallicRoughness": {"baseColorTexture": {"index": k}}} for k in range(copies)]
    doc["textures"] = [{"source": k} for k in range(copies)]
    doc["images"] = [{"bufferView": 4, "mimeType": "image/png"} for _ in range(copies)]
    return glb(doc, binary)


def _bomb_png() -> bytes:
    """A PNG that declares 30000 x 30000 pixels in a few hundred bytes (its IHDR only, then a
    tiny compressed row block): the size check must refuse it before anything decodes it."""
    import zlib

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    ihdr = struct.pack(">IIBBBBB", 30000, 30000, 8, 0, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(b"\0" * 30001)) + chunk(b"IEND", b"")
    )
