"""The bad-input corpus: writes every case into a folder and says what each must give.

    python tests/bad_inputs.py DIR     writes the corpus into DIR and lists the cases by category

A case expects either an error (exit 2, one line naming the file and containing `says`)
or a load that works (exit 0), possibly with a warning line containing `says`. Categories
(docs/reliability.md counts them): `format` (broken or mislabelled files), `gltf` (glTF JSON of
the wrong types and ranges, broken node graphs), `limits` (what would hang or exhaust
memory: FIFOs, devices, declared sizes, zip bombs, deep or exploding graphs), `references`
(files a scene points to), `names` (repeated, missing and hostile object names), `pictures`
(what loads but must say what it changed). Data loss and messages are checked per command
in tests/test_bad_output.py.
"""

from __future__ import annotations

import io
import json
import os
import struct
import sys
from dataclasses import dataclass
from pathlib import Path

import bad_files as bf
import bad_gltf
import numpy as np
import trimesh

from rtta.scene.files import MAX_OBJECTS

TRI = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"


@dataclass
class Case:
    name: str
    path: Path  # what the CLI is given
    error: bool  # True: exit 2 and one error line; False: exit 0
    says: str  # text the error (or the warning) must contain
    category: str = "format"


def _glb(mesh_names=("a",), positions=None, indices=None) -> bytes:
    """A GLB with one node per name; the first mesh's positions and/or indices can be
    overwritten with one value (e.g. NaN, or an index past the end)."""
    scene = trimesh.Scene()
    for i, name in enumerate(mesh_names):
        box = trimesh.creation.box(extents=(1, 1, 1))
        box.apply_translation((i * 1.5, 0, 0))
        scene.add_geometry(box, node_name=name, geom_name=f"g{i}")
    data = scene.export(file_type="glb")
    if positions is None and indices is None:
        return data
    return _patch_glb(data, positions, indices)


def _renamed_glb(data: bytes, names: list[str]) -> bytes:
    """The GLB with its nodes renamed (trimesh keeps node names unique; files need not)."""
    length = struct.unpack_from("<I", data, 12)[0]
    doc = json.loads(data[20 : 20 + length])
    for node, name in zip([n for n in doc["nodes"] if "mesh" in n], names, strict=True):
        node["name"] = name
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    rest = data[20 + length :]
    head = struct.pack("<4sIIII", b"glTF", 2, 20 + len(text) + len(rest), len(text), 0x4E4F534A)
    return head + text + rest


def _patch_glb(data: bytes, positions, indices) -> bytes:
    """Overwrite the first mesh's position (or index) accessor bytes in place."""
    length = struct.unpack_from("<I", data, 12)[0]
    doc = json.loads(data[20 : 20 + length])
    binary_start = 20 + length + 8
    out = bytearray(data)
    prim = doc["meshes"][0]["primitives"][0]
    for acc_id, values in ((prim["attributes"]["POSITION"], positions), (prim.get("indices"), indices)):
        if values is None or acc_id is None:
            continue
        acc = doc["accessors"][acc_id]
        view = doc["bufferViews"][acc["bufferView"]]
        start = binary_start + view.get("byteOffset", 0) + acc.get("byteOffset", 0)
        dtype = np.float32 if acc["componentType"] == 5126 else {5125: np.uint32, 5123: np.uint16}[acc["componentType"]]
        width = {"VEC3": 3, "SCALAR": 1}[acc["type"]]
        raw = np.full(acc["count"] * width, values, dtype).tobytes()
        out[start : start + len(raw)] = raw
    return bytes(out)


def _gltf(buffer_uri: str, image_uri: str | None = None, name: str = "tri") -> str:
    """A .gltf with one triangle whose buffer (and optional texture) live at the URIs."""
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": name}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2}]}],
        "buffers": [{"uri": buffer_uri, "byteLength": 66}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 24},
            {"buffer": 0, "byteOffset": 60, "byteLength": 6},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5123, "count": 3, "type": "SCALAR"},
        ],
    }
    if image_uri is not None:
        doc["images"] = [{"uri": image_uri}]
        doc["textures"] = [{"source": 0}]
        doc["materials"] = [
            {"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "baseColorFactor": [0.2, 0.6, 0.9, 1.0]}}
        ]
        doc["meshes"][0]["primitives"][0]["material"] = 0
    return json.dumps(doc)


def _gltf_buffer() -> bytes:
    pos = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
    uv = np.array([[0, 0], [1, 0], [0, 1]], np.float32)
    return pos.tobytes() + uv.tobytes() + np.array([0, 1, 2], np.uint16).tobytes()


def _png() -> bytes:
    from PIL import Image

    buf = io.BytesIO()
    Image.new("RGB", (4, 4), (200, 30, 30)).save(buf, format="PNG")
    return buf.getvalue()


def _stl_header(count: int, body_triangles: int) -> bytes:
    body = np.zeros(body_triangles * 50, np.uint8).tobytes()
    return b"\0" * 80 + struct.pack("<I", count) + body


def many_objects_obj(n: int) -> str:
    """An OBJ of `n` one-triangle objects."""
    return "".join(
        f"o p{i}\nv {i} 0 0\nv {i + 1} 0 0\nv {i} 1 0\nf {3 * i + 1} {3 * i + 2} {3 * i + 3}\n" for i in range(n)
    )


def many_nodes_glb(n: int) -> bytes:
    """A GLB of `n` nodes sharing one box mesh, side by side."""
    doc, binary = bad_gltf.box_doc([{"mesh": 0, "translation": [i % 100, i // 100, 0]} for i in range(n)])
    doc["scenes"] = [{"nodes": list(range(n))}]
    return bad_gltf.glb(doc, binary)


def make_corpus(folder: str | Path) -> list[Case]:
    """Write every case into `folder` (which must exist and be empty) and return them."""
    d = Path(folder)
    cases: list[Case] = []
    category = "format"

    def add(name: str, content: bytes | str | None, error: bool, says: str, *, path: str | None = None) -> None:
        p = d / (path or name)
        if content is not None:
            p.parent.mkdir(parents=True, exist_ok=True)
            p.write_bytes(content.encode("latin-1") if isinstance(content, str) else content)
        cases.append(Case(name, p, error, says, category))

    good = _glb(("a", "b"))
    add("empty.glb", b"", True, "empty")
    add("empty.obj", b"", True, "empty")
    add("truncated.glb", good[: len(good) // 2], True, "GLB")
    add("truncated_header.glb", good[:10], True, "GLB")
    add("random_bytes.glb", np.random.default_rng(0).bytes(4096), True, "GLB")
    add("text.glb", "this is not a model\n", True, "GLB")
    add("text.obj", "hello world\nthis is text\n", True, "no objects")
    add("text.stl", "just some words, not an STL\n", True, "STL")
    add("ascii_stl_garbage.stl", "solid x\n facet normal a b c\n outer loop\n vertex 1 2\n", True, "no objects")
    add("wrong_extension.png", _png(), True, "unsupported file type")
    add("no_extension", TRI, True, "unsupported file type")
    add("glb_named.obj", good, True, "no objects")
    add("glb_named.gltf", good, True, "UTF-8")
    add("obj_named.glb", TRI, True, "GLB")
    add("nan_vertices.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", True, "NaN")
    add("inf_vertices.obj", "v 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n", True, "NaN or infinite")
    add("nan_vertices.glb", _glb(("a",), positions=np.nan), True, "NaN")
    add("huge_coordinates.obj", "v 0 0 0\nv 1e300 0 0\nv 0 1 0\nf 1 2 3\n", True, "up to 1e+300, beyond the")
    add("beyond_float32.obj", "v 0 0 0\nv 1e39 0 0\nv 0 1 0\nf 1 2 3\n", True, "up to 1e+39, beyond the")
    add("large_coordinates.obj", "v 0 0 0\nv 1e20 0 0\nv 0 1 0\nf 1 2 3\n", True, "up to 1e+20, beyond the")
    # one vertex far out flattens every triangle relative to the object's size: the range is the reason
    add(
        "far_vertex_flattens.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1e27 0 0\nf 1 2 3\nf 1 2 4\n",
        True,
        "up to 1e+27, beyond the",
    )
    add("zero_faces.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n", True, "no objects")
    add(
        "points.ply",
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n",
        True,
        "no objects",
    )
    add("degenerate.obj", "v 0 0 0\nv 1 1 1\nv 2 2 2\nv 5 5 5\nf 1 2 3\nf 1 1 4\nf 2 3 4\n", True, "degenerate")
    add(
        "obj_cut_inside_a_vertex.obj",
        "o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\no b\nv 0 0 1\nv 1 0 1\nv 0.5",
        True,
        "vertices of 1 coordinate(s)",
    )
    add("face_index_out_of_range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 30\n", True, "index")
    add("index_out_of_range.glb", _glb(("a",), indices=60000), True, "index")
    add("stl_truncated_body.stl", _stl_header(1000, 10), True, "STL")
    add("off_bad_counts.off", "OFF\n8 12 0\n0 0 0\n1 0 0\n", True, "OFF")
    add("off_no_counts.off", "OFF\n", True, "OFF")
    add("garbage.3mf", b"PK\x03\x04" + b"\0" * 64, True, "3MF")
    add("3mf_bad_deflate.3mf", bf.threemf_bad_deflate(), True, "3MF archive (compressed data that is damaged")
    add("3mf_without_model.3mf", bf.threemf("<model/>").replace(b"3D/3dmodel.model", b"3D/elsewhere.xml"), True, "3MF")
    add("invalid_json.gltf", '{"asset": {"version": "2.0"}, "nodes": [', True, "JSON")
    add("non_utf8.gltf", _gltf("secret.bin").replace('"tri"', '"caf\xe9"'), True, "UTF-8")
    add("is_a_directory.glb", None, True, "directory")
    (d / "is_a_directory.glb").mkdir()
    add("does_not_exist.glb", None, True, "no such file")
    add("name_over_255_bytes.glb", None, True, "too long", path="n" * 300 + ".glb")
    add("newline_in_file_name.glb", b"not a model", True, "GLB", path="two\nlines.glb")
    add("non_utf8_file_name.glb", b"not a model", True, "GLB", path=os.fsdecode(b"caf\xe9.glb"))
    add("escape_in_file_name.glb", b"not a model", True, "GLB", path="evil\x1b[2J.glb")
    if os.geteuid() != 0:  # root reads any file: the case cannot fail there
        add("no_permission.glb", good, True, "permission")
        os.chmod(d / "no_permission.glb", 0)

    category = "gltf"
    for name, (data, says) in bad_gltf.gltf_error_files().items():
        add(name, data, True, says)

    category = "limits"
    add("stl_claims_2g_triangles.stl", _stl_header(2**31 - 1, 2), True, "memory limit")
    add(
        "ply_claims_too_many.ply",
        "ply\nformat binary_little_endian 1.0\nelement vertex 900000000\n"
        "property float x\nproperty float y\nproperty float z\nelement face 900000000\n"
        "property list uchar int vertex_indices\nend_header\n",
        True,
        "memory limit",
    )
    add(
        "ply_ascii_claims_too_many.ply",
        "ply\nformat ascii 1.0\nelement vertex 2000000000\nproperty float x\n"
        "property float y\nproperty float z\nend_header\n0 0 0\n",
        True,
        "memory limit",
    )
    add("off_claims_too_many.off", "OFF\n1000000000 1000000000 0\n0 0 0\n", True, "memory limit")
    big = trimesh.creation.icosphere(subdivisions=6)  # 81,920 triangles: over RTTA_MEMORY_LIMIT_MB=1
    add("too_large_for_limit.glb", big.export(file_type="glb"), True, "memory limit")
    add("3mf_zip_bomb_16mb.3mf", bf.threemf_bomb(16), True, "memory limit")
    add("3mf_declares_3gib.3mf", bf.threemf_declares(3), True, "memory limit")
    add("3mf_component_cycle.3mf", bf.threemf_cycle(), True, "cycle")
    add("3mf_2_pow_30_components.3mf", bf.threemf_explosion(30), True, "objects")
    add("3mf_entity_expansion.3mf", bf.threemf_entities(), True, "DTD")
    over = MAX_OBJECTS + 1
    add("obj_10001_objects.obj", many_objects_obj(over), True, f"{over:,} objects")  # small files: 10,000
    add("gltf_10001_nodes.glb", many_nodes_glb(over), True, f"{over:,}")
    if bf.make_fifo(d / "fifo_scene.glb"):
        add("fifo_scene.glb", None, True, "not a regular file")
    if bf.make_link(d / "dev_zero.stl", "/dev/zero"):
        add("dev_zero.stl", None, True, "not a regular file")
    if bf.make_fifo(d / "fifo.bin"):
        add("fifo_buffer.gltf", _gltf("fifo.bin"), True, "not a regular file")
    if bf.make_fifo(d / "fifo.png"):
        add("fifo_texture.gltf", _gltf("secret.bin", "fifo.png"), False, "fifo.png")
    if bf.make_fifo(d / "fifo.mtl"):
        obj, _ = bf.obj_with_material("fifo.mtl")
        add("fifo_mtllib.obj", obj, False, "fifo.mtl")

    category = "references"
    (d / "sub").mkdir()
    (d / "secret.bin").write_bytes(_gltf_buffer())
    add("buffer_outside_folder.gltf", _gltf("../secret.bin"), True, "outside", path="sub/buffer_outside_folder.gltf")
    add("buffer_absolute_path.gltf", _gltf(str((d / "secret.bin").resolve())), True, "outside")
    add("buffer_url.gltf", _gltf("https://example.com/tri.bin"), True, "URL")
    add("buffer_file_url.gltf", _gltf("file:///etc/passwd"), True, "URL")
    add("buffer_missing.gltf", _gltf("missing.bin"), True, "missing.bin")
    add("buffer_is_folder.gltf", _gltf("sub"), True, "directory")
    add("buffer_too_short.gltf", _gltf("short.bin"), True, "byteLength")
    (d / "short.bin").write_bytes(b"\0" * 10)
    add("buffer_bad_base64.gltf", _gltf("data:application/octet-stream;base64,@@@@"), True, "byteLength")
    add("missing_texture.gltf", _gltf("secret.bin", "no_such_texture.png"), False, "no_such_texture.png")
    add("unreadable_texture.gltf", _gltf("secret.bin", "broken.png"), False, "broken.png")
    (d / "broken.png").write_bytes(b"\x89PNG\r\n\x1a\nnot really a png")
    add(
        "texture_outside_folder.gltf",
        _gltf("secret.bin", "../broken.png"),
        False,
        "outside",
        path="sub/texture_outside_folder.gltf",
    )
    (d / "sub" / "secret.bin").write_bytes(_gltf_buffer())
    add("texture_url.gltf", _gltf("secret.bin", "http://example.com/t.png"), False, "URL")
    obj, mtl = bf.obj_with_material("red.mtl", "no_such.png")
    (d / "red.mtl").write_text(mtl)
    add("obj_missing_texture.obj", obj, False, "no_such.png")
    obj, _ = bf.obj_with_material("/etc/passwd")
    add("obj_mtllib_absolute.obj", obj, False, "/etc/passwd")
    obj, _ = bf.obj_with_material("../outside.mtl")
    add("obj_mtllib_outside.obj", obj, False, "outside.mtl", path="sub/obj_mtllib_outside.obj")

    category = "names"
    add("duplicate_names.glb", _renamed_glb(_glb(("a", "b", "c")), ["part"] * 3), False, "numbered")
    add("non_utf8_names.obj", "o caf\xe9\n" + TRI + "o na\xefve\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf 4 5 6\n", False, "")
    add("obj_same_name_twice.obj", "o part\n" + TRI + "o part\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf 4 5 6\n", False, "numbered")
    add("obj_unnamed_object.obj", "o\n" + TRI + "o second\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf 4 5 6\n", False, "")
    add("obj_escape_in_name.obj", "o evil\x1b[31mred\x07\n" + TRI, False, "")
    add("3mf_named.3mf", bf.threemf_good(), False, "")

    category = "pictures"
    for name, (data, says) in bad_gltf.gltf_loading_files().items():
        category = name.split("_")[0]
        add(name, data, False, says)
    return cases


if __name__ == "__main__":
    target = Path(sys.argv[1])
    target.mkdir(parents=True, exist_ok=True)
    for case in make_corpus(target):
        print(f"{case.category:10s} {'error' if case.error else 'loads'}  {case.path!r}  {case.says}")
