"""Plain glTF primitives read straight from their accessors, without trimesh (issue 22).

CAD and BIM exports are plain: triangle lists of float positions (and normals), a base
colour per material, no textures. For such a file trimesh's per-primitive objects (a
Trimesh, a visual, a material each) cost more than the geometry itself: at 10^4 parts they
are most of the load time and a large share of the peak memory. `decode` reads every
drawn (mesh, primitive) of a plain file into arrays; any other file (textures, vertex
colours, strips, quantized accessors, compression) returns None and goes through
trimesh as before. The arrays equal what trimesh gives (tests/test_gltf_read.py); the
document has been checked (rtta.scene.readers.gltf_check), so every byte range lies in its buffer.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .gltf_check import FLOAT, TYPE_WIDTH

DTYPES = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
NO_FACTOR = [102 / 255, 102 / 255, 102 / 255, 1.0]  # trimesh's colour for a material without baseColorFactor


@dataclass
class Decoded:
    """One primitive's geometry: vertices float64 [V, 3], faces int32 [F, 3], the file's
    normals (float32 [V, 3]; None when it has none or they are not finite), base colour
    (RGBA in [0, 1], None for the palette; one list per material, shared); uvs (float32
    [V, 2]) and the texture's index where textured (the loader's records of trimesh meshes)."""

    vertices: np.ndarray
    faces: np.ndarray
    normals: np.ndarray | None
    color: list[float] | None
    uv: np.ndarray | None = None
    texture: int = -1


def accessor_array(doc: dict, index: int, buffers: list[bytes]) -> np.ndarray:
    """Accessor `index` as an array [count, width] of its component type (zeros when it has
    no bufferView, as the glTF specification says); strided views are gathered."""
    acc = doc["accessors"][index]
    dtype = np.dtype(DTYPES[acc["componentType"]])
    width, count = TYPE_WIDTH[acc["type"]], acc["count"]
    if "bufferView" not in acc:
        return np.zeros((count, width), dtype)
    view = doc["bufferViews"][acc["bufferView"]]
    start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
    element = dtype.itemsize * width
    stride = view.get("byteStride") or element
    data = buffers[view["buffer"]]
    if stride == element and start % dtype.itemsize == 0:
        return np.frombuffer(data, dtype, count=count * width, offset=start).reshape(count, width)
    raw = np.frombuffer(data, np.uint8, count=(count - 1) * stride + element, offset=start)
    rows = np.lib.stride_tricks.as_strided(raw, (count, element), (stride, 1))
    return np.ascontiguousarray(rows).view(dtype).reshape(count, width)


def densify_sparse(doc: dict, buffers: list[bytes]) -> None:
    """Every sparse accessor made dense (glTF 2.0, 3.6.2.3): its base values (zeros without
    a bufferView) with the substitutions applied, in a buffer of its own appended to
    `buffers` and to the document, so trimesh (which ignores `sparse`) and decode() read
    the values the file means. ValueError names an accessor whose indices are out of range."""
    for i, acc in enumerate(doc.get("accessors", [])):
        sparse = acc.pop("sparse", None)
        if sparse is None:
            continue
        dense = np.array(accessor_array(doc, i, buffers))
        n, indices = sparse["count"], sparse["indices"]
        at = _packed(doc, buffers, indices, indices["componentType"], 1, n).reshape(-1).astype(np.int64)
        if at.max() >= len(dense):
            raise ValueError(f"accessor {i} has sparse indices up to {at.max():,}, but {len(dense):,} values")
        dense[at] = _packed(doc, buffers, sparse["values"], acc["componentType"], dense.shape[1], n)
        acc["bufferView"], acc["byteOffset"] = append_view(doc, buffers, dense.tobytes()), 0


def transform_texcoords(doc: dict, pairs: list[tuple[int, int]], buffers: list[bytes], warnings: list[str]) -> None:
    """The base-colour texture's coordinate set (`texCoord`) made set 0, and its
    KHR_texture_transform (offset, rotation, scale: glTF's T R S) applied to each drawn
    primitive's TEXCOORD_0, into a float accessor of its own, so
    trimesh (which ignores the extension) and the material atlas read the coordinates the
    file means. A transform that is not numbers is left out with a warning."""
    materials, bad = doc.get("materials", []), 0
    for m, p in pairs:
        prim = doc["meshes"][m]["primitives"][p]
        texture = (
            materials[prim["material"]].get("pbrMetallicRoughness", {}).get("baseColorTexture")
            if "material" in prim
            else None
        )
        _use_texcoord_set(doc, prim, texture)
        if "TEXCOORD_0" not in prim["attributes"]:
            continue
        transform = extension(texture, "KHR_texture_transform")
        if transform is None:
            continue
        matrix = _uv_matrix(transform)
        if matrix is None:
            bad += 1
            continue
        uv = _float_texcoords(doc, prim["attributes"]["TEXCOORD_0"], buffers)
        prim["attributes"]["TEXCOORD_0"] = append_accessor(
            doc, buffers, (uv @ matrix[:, :2].T + matrix[:, 2]).astype(np.float32), "VEC2"
        )
    if bad:
        warnings.append(f"{bad} primitive(s) with a KHR_texture_transform that is not numbers: drawn untransformed")


def _use_texcoord_set(doc: dict, prim: dict, texture) -> None:
    """A base-colour texture on coordinate set N > 0 (`texCoord`): that set is read as set 0,
    the only one the readers take, where it is a VEC2 of a texture-coordinate type."""
    n = texture.get("texCoord", 0) if isinstance(texture, dict) else 0
    index = prim["attributes"].get(f"TEXCOORD_{n}") if type(n) is int and n > 0 else None
    acc = doc["accessors"][index] if type(index) is int and 0 <= index < len(doc["accessors"]) else None
    positions = doc["accessors"][prim["attributes"]["POSITION"]]["count"]
    if (
        acc is not None
        and acc.get("type") == "VEC2"
        and acc.get("count") == positions
        and acc.get("componentType") in (5126, 5121, 5123, 5120, 5122)
    ):
        prim["attributes"]["TEXCOORD_0"] = index


def _uv_matrix(t) -> np.ndarray | None:
    """The 2x3 matrix T(offset) R(rotation) S(scale) of a KHR_texture_transform, or None."""
    try:
        ox, oy = (float(v) for v in t.get("offset", (0.0, 0.0)))
        sx, sy = (float(v) for v in t.get("scale", (1.0, 1.0)))
        r = float(t.get("rotation", 0.0))
    except (TypeError, ValueError, AttributeError):
        return None
    if not np.isfinite([ox, oy, sx, sy, r]).all():
        return None
    c, s = np.cos(r), np.sin(r)
    return np.array([[c * sx, s * sy, ox], [-s * sx, c * sy, oy]])


def _float_texcoords(doc: dict, index: int, buffers: list[bytes]) -> np.ndarray:
    """TEXCOORD accessor `index` as float64 [V, 2] (normalized integers mapped to [0, 1] or [-1, 1])."""
    acc = doc["accessors"][index]
    raw = accessor_array(doc, index, buffers)
    if raw.dtype.kind == "f" or not acc.get("normalized"):
        return raw.astype(np.float64)
    return np.maximum(raw / float(np.iinfo(raw.dtype).max), -1.0)


def extension(obj, name: str):
    """obj["extensions"][name] where obj and its extensions are objects (None otherwise: the
    checker does not look inside extensions)."""
    extensions = obj.get("extensions") if isinstance(obj, dict) else None
    return extensions.get(name) if isinstance(extensions, dict) else None


def view_bytes(doc: dict, buffers: list[bytes], v: int) -> bytes:
    """The bytes of bufferView `v` (the document has been checked: they lie in their buffer)."""
    view = doc["bufferViews"][v]
    start = view.get("byteOffset", 0)
    return bytes(buffers[view["buffer"]][start : start + view["byteLength"]])


def append_view(doc: dict, buffers: list[bytes], raw: bytes) -> int:
    """A new buffer and a bufferView over all of it, holding `raw`; the view's index."""
    buffers.append(raw)
    doc.setdefault("buffers", []).append({"byteLength": len(raw)})
    doc.setdefault("bufferViews", []).append({"buffer": len(buffers) - 1, "byteLength": max(len(raw), 1)})
    return len(doc["bufferViews"]) - 1


def append_accessor(doc: dict, buffers: list[bytes], data: np.ndarray, kind: str) -> int:
    """A new buffer, view and accessor holding `data` (float32 or uint32, tightly packed); its index."""
    view = append_view(doc, buffers, np.ascontiguousarray(data).tobytes())
    component = 5125 if data.dtype == np.uint32 else 5126
    doc.setdefault("accessors", []).append(
        {"bufferView": view, "componentType": component, "count": len(data), "type": kind}
    )
    return len(doc["accessors"]) - 1


def _packed(doc: dict, buffers: list[bytes], part: dict, ctype: int, width: int, n: int) -> np.ndarray:
    """n tightly packed elements of `width` components at a sparse part's bufferView and offset."""
    view = doc["bufferViews"][part["bufferView"]]
    start = view.get("byteOffset", 0) + part.get("byteOffset", 0)
    dtype = np.dtype(DTYPES[ctype])
    return np.frombuffer(buffers[view["buffer"]][start : start + n * width * dtype.itemsize], dtype).reshape(n, width)


def plain(doc: dict, pairs: list[tuple[int, int]]) -> bool:
    """Whether every drawn primitive can be decoded here: a triangle list or fan, float
    POSITION (and NORMAL), no COLOR_0, no extension, no sparse accessor left, and a material
    (if any) without a base-colour texture."""
    accessors, materials = doc.get("accessors", []), doc.get("materials", [])
    for m, p in pairs:
        prim = doc["meshes"][m]["primitives"][p]
        attrs = prim["attributes"]
        if prim.get("mode", 4) not in (4, 6) or "extensions" in prim or "COLOR_0" in attrs:
            return False
        used = [
            attrs["POSITION"],
            *[attrs[k] for k in ("NORMAL",) if k in attrs],
            *([prim["indices"]] if "indices" in prim else []),
        ]
        if any("sparse" in accessors[a] for a in used):
            return False
        if any(accessors[attrs[k]]["componentType"] != FLOAT for k in ("POSITION", "NORMAL") if k in attrs):
            return False
        if "material" in prim and "baseColorTexture" in materials[prim["material"]].get("pbrMetallicRoughness", {}):
            return False
    return True


def decode(doc: dict, pairs: list[tuple[int, int]], buffers: list[bytes]) -> dict[tuple[int, int], Decoded] | None:
    """Every drawn (mesh, primitive) of a plain document decoded; None when it is not plain."""
    if not plain(doc, pairs):
        return None
    colors = [_color(mat) for mat in doc.get("materials", [])]
    out = {}
    for m, p in pairs:
        prim = doc["meshes"][m]["primitives"][p]
        attrs = prim["attributes"]
        v = accessor_array(doc, attrs["POSITION"], buffers).astype(np.float64)
        normals = None
        if "NORMAL" in attrs:
            normals = np.array(accessor_array(doc, attrs["NORMAL"], buffers), np.float32)
            normals = normals if np.isfinite(normals).all() else None
        out[(m, p)] = Decoded(
            v, _faces(doc, prim, buffers, len(v)), normals, colors[prim["material"]] if "material" in prim else None
        )
    return out


def _faces(doc: dict, prim: dict, buffers: list[bytes], vertices: int) -> np.ndarray:
    if "_fan" in prim:  # a fan, made a triangle list by gltf._primitives
        fan = prim["_fan"]
        return fan.astype(np.int32).reshape(-1, 3) if len(fan) else np.zeros((1, 3), np.int32)
    if "indices" in prim:
        return accessor_array(doc, prim["indices"], buffers).astype(np.int32).reshape(-1, 3)
    return np.arange(vertices, dtype=np.int32).reshape(-1, 3)


def _color(material: dict) -> list[float]:
    """Base colour factor quantised to 8 bits, as trimesh stores it (NaN and out-of-range
    components were made drawable by gltf._colors)."""
    factor = material.get("pbrMetallicRoughness", {}).get("baseColorFactor")
    if factor is None:
        return list(NO_FACTOR)
    c = np.round(np.clip(np.asarray(factor, np.float64), 0.0, 1.0) * 255.0) / 255.0
    return [float(x) for x in c]
