"""glTF JSON checked before trimesh sees it: the type and range of every field the loader
reads (or trimesh reads on its behalf), every index into another array, every byte range
against its buffer, so a malformed file is one RttaError naming the field, never a
traceback from deep inside trimesh.

`check(doc, path, bin_size)` validates the document (rtta.scene.readers.gltf_document reads
it) in place, filling defaults; RttaError for the first field that is wrong.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Literal, overload

from ...errors import RttaError

COMPONENT_BYTES = {5120: 1, 5121: 1, 5122: 2, 5123: 2, 5125: 4, 5126: 4}
TYPE_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
INDEX_TYPES = (5121, 5123, 5125)
FLOAT = 5126
MAX_COUNT = 2**31 - 1  # counts, lengths and offsets: anything larger is no real file
MAX_ARRAY = 10_000_000  # entries of one top-level array
_MISSING = object()
_REAL = {int, float}


class Checker:
    """Type checks that raise RttaError('glTF <where> ...', path)."""

    def __init__(self, doc: dict, path: Path) -> None:
        self.doc, self.path = doc, path

    def fail(self, where: str, problem: str):
        raise RttaError(f"glTF {where} {problem}", self.path)

    def array(self, key: str) -> list[dict]:
        """A top-level array of objects (missing: empty)."""
        value = self.doc.get(key, [])
        if not isinstance(value, list):
            self.fail(f"'{key}'", f"must be an array, not {_kind(value)}")
        if len(value) > MAX_ARRAY:
            self.fail(f"'{key}'", f"has {len(value):,} entries (at most {MAX_ARRAY:,})")
        for i, item in enumerate(value):
            if not isinstance(item, dict):
                self.fail(f"{key}[{i}]", f"must be an object, not {_kind(item)}")
        return value

    @overload  # required, or with a default: an int
    def integer(
        self,
        obj: dict,
        key: str,
        where: str,
        *,
        below: int | None = ...,
        least: int = ...,
        required: Literal[True],
        default: None = ...,
    ) -> int: ...
    @overload
    def integer(
        self,
        obj: dict,
        key: str,
        where: str,
        *,
        below: int | None = ...,
        least: int = ...,
        required: bool = ...,
        default: int,
    ) -> int: ...
    @overload
    def integer(
        self,
        obj: dict,
        key: str,
        where: str,
        *,
        below: int | None = ...,
        least: int = ...,
        required: bool = ...,
        default: None = ...,
    ) -> int | None: ...
    def integer(self, obj: dict, key: str, where: str, *, below=None, least=0, required=False, default=None):
        value = obj.get(key, _MISSING)
        if type(value) is int and least <= value <= MAX_COUNT and (below is None or value < below):
            return value  # the common case, first
        if value is _MISSING:
            if required:
                self.fail(where, f"has no '{key}'")
            return default
        if isinstance(value, float) and value.is_integer() and abs(value) <= MAX_COUNT:
            value = obj[key] = int(value)  # 3.0 is 3 in JSON
        if not isinstance(value, int) or isinstance(value, bool):
            self.fail(f"{where}.{key}", f"must be an integer, not {_kind(value)}")
        if value < least or value > MAX_COUNT:
            self.fail(f"{where}.{key}", f"is {value}, out of range")
        if below is not None and value >= below:
            self.fail(f"{where}.{key}", f"is {value}, but there are only {below}")
        return value

    @overload
    def index(self, obj: dict, key: str, where: str, target: str, *, required: Literal[True]) -> int: ...
    @overload
    def index(self, obj: dict, key: str, where: str, target: str, *, required: bool = ...) -> int | None: ...
    def index(self, obj: dict, key: str, where: str, target: str, *, required: bool = False) -> int | None:
        """An index into top-level array `target`."""
        return self.integer(obj, key, where, below=len(self.doc.get(target, [])), required=required)

    def numbers(self, obj: dict, key: str, where: str, n: int, *, finite: bool = True) -> list[float] | None:
        if key not in obj:
            return None
        value = obj[key]
        if type(value) is list and len(value) == n and {type(v) for v in value} <= _REAL and _finite(sum(value)):
            obj[key] = value = [float(v) for v in value]  # the common case: a finite sum, so all are finite
            return value
        if (
            not isinstance(value, list)
            or len(value) != n
            or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
        ):
            self.fail(f"{where}.{key}", f"must be an array of {n} numbers")
        if finite and not all(_finite(v) for v in value):
            self.fail(f"{where}.{key}", "holds NaN or infinite numbers")
        obj[key] = value = [_float(v) for v in value]  # the loader reads floats only
        return value

    def obj(self, parent: dict, key: str, where: str) -> dict:
        value = parent.get(key, {})
        if not isinstance(value, dict):
            self.fail(f"{where}.{key}", f"must be an object, not {_kind(value)}")
        return value

    def text(self, obj: dict, key: str, where: str, *, uri: bool = False) -> str | None:
        """A string; a URI must not hold a NUL byte (no file name can)."""
        value = obj.get(key)
        if value is None:
            return None
        if not isinstance(value, str):
            self.fail(f"{where}.{key}", f"must be a string, not {_kind(value)}")
        if uri and "\0" in value:
            self.fail(f"{where}.{key}", "contains a NUL byte")
        return value

    def index_list(self, obj: dict, key: str, where: str, target: str) -> list[int]:
        value = obj.get(key, [])
        if not isinstance(value, list):
            self.fail(f"{where}.{key}", f"must be an array, not {_kind(value)}")
        holder = {}
        for i in range(len(value)):
            holder["i"] = value[i]
            value[i] = self.index(holder, "i", f"{where}.{key}[{i}]", target)
        return value


def _finite(v: float) -> bool:
    """math.isfinite, also for an integer too large for a float (JSON allows 1 followed by
    400 zeros), which is not finite here."""
    try:
        return math.isfinite(v)
    except OverflowError:
        return False


def _float(v: float) -> float:
    try:
        return float(v)
    except OverflowError:
        return math.inf if v > 0 else -math.inf


def _kind(value) -> str:
    return {
        dict: "an object",
        list: "an array",
        str: "a string",
        bool: "a boolean",
        int: "an integer",
        float: "a number",
        type(None): "null",
    }.get(type(value), type(value).__name__)


def check(doc: dict, path: Path, bin_size: int | None) -> None:
    """Validate every field the loader reads; RttaError for the first that is wrong."""
    c = Checker(doc, path)
    for key in (
        "buffers",
        "bufferViews",
        "accessors",
        "meshes",
        "nodes",
        "scenes",
        "materials",
        "textures",
        "images",
        "samplers",
        "cameras",
        "skins",
        "animations",
    ):
        c.array(key)
    if "scene" in doc:
        c.index(doc, "scene", "document", "scenes")
    for key in ("extensionsUsed", "extensionsRequired"):
        value = doc.get(key, [])
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            c.fail(f"'{key}'", "must be an array of strings")
    _buffers(c, bin_size)
    _accessors(c)
    _meshes(c)
    _nodes(c)
    _materials(c)


def _buffers(c: Checker, bin_size: int | None) -> None:
    for i, buf in enumerate(c.array("buffers")):
        where = f"buffers[{i}]"
        length = c.integer(buf, "byteLength", where, required=True)
        uri = c.text(buf, "uri", where, uri=True)
        if uri is None and i == 0 and bin_size is not None and length > bin_size:
            c.fail(f"{where}.byteLength", f"is {length:,}, but the GLB binary chunk has {bin_size:,} bytes")
        if uri is None and not (i == 0 and bin_size is not None):
            c.fail(where, "has no 'uri' (only a GLB's first buffer may have none)")
    buffers = c.array("buffers")
    for i, view in enumerate(c.array("bufferViews")):
        where = f"bufferViews[{i}]"
        b = c.index(view, "buffer", where, "buffers", required=True)
        offset = c.integer(view, "byteOffset", where, default=0)
        length = c.integer(view, "byteLength", where, least=1, required=True)
        stride = c.integer(view, "byteStride", where, least=4)
        if stride is not None and (stride > 252 or stride % 4):
            c.fail(f"{where}.byteStride", f"is {stride}; it must be a multiple of 4 from 4 to 252")
        if offset + length > buffers[b]["byteLength"]:
            c.fail(where, f"reaches byte {offset + length:,} of buffer {b}, which has {buffers[b]['byteLength']:,}")


def _accessors(c: Checker) -> None:
    views = c.array("bufferViews")
    for i, acc in enumerate(c.array("accessors")):
        where = f"accessors[{i}]"
        count = c.integer(acc, "count", where, least=1, required=True)
        ctype = c.integer(acc, "componentType", where, required=True)
        if ctype not in COMPONENT_BYTES:
            c.fail(f"{where}.componentType", f"is {ctype}, not a glTF component type")
        kind = c.text(acc, "type", where)
        if kind not in TYPE_WIDTH:
            c.fail(f"{where}.type", f"is {kind!r}, not one of {', '.join(TYPE_WIDTH)}")
        v = c.index(acc, "bufferView", where, "bufferViews")
        offset = c.integer(acc, "byteOffset", where, default=0)
        element = COMPONENT_BYTES[ctype] * TYPE_WIDTH[kind]
        if "sparse" in acc:
            _sparse(c, acc["sparse"], views, f"{where}.sparse", count, element)
        if v is None:
            if offset:
                c.fail(f"{where}.byteOffset", "is set, but the accessor has no bufferView")
            continue
        view = views[v]
        stride = view.get("byteStride") or element
        end = offset + (count - 1) * stride + element
        if end > view["byteLength"]:
            c.fail(
                where,
                f"needs {end:,} bytes of bufferView {v}, which has {view['byteLength']:,} "
                f"({count:,} x {kind} of {COMPONENT_BYTES[ctype]}-byte components)",
            )
        if offset % COMPONENT_BYTES[ctype]:
            c.fail(f"{where}.byteOffset", f"is {offset}, not a multiple of the component size")


def _sparse(c: Checker, sparse, views: list, where: str, count: int, element: int) -> None:
    """A sparse accessor's substitutions: at most `count` of them, indices of an index type
    and values of the accessor's element size, each within its bufferView."""
    if not isinstance(sparse, dict):
        c.fail(where, "must be an object")
    n = c.integer(sparse, "count", where, least=1, required=True)
    if n > count:
        c.fail(f"{where}.count", f"is {n:,}, more than the accessor's {count:,} values")
    for key in ("indices", "values"):
        part = c.obj(sparse, key, where)
        v = c.index(part, "bufferView", f"{where}.{key}", "bufferViews", required=True)
        offset = c.integer(part, "byteOffset", f"{where}.{key}", default=0)
        size = element
        if key == "indices":
            ctype = c.integer(part, "componentType", f"{where}.indices", required=True)
            if ctype not in INDEX_TYPES:
                c.fail(f"{where}.indices.componentType", f"is {ctype}, not an index type")
            size = COMPONENT_BYTES[ctype]
        if offset + n * size > views[v]["byteLength"]:
            c.fail(
                f"{where}.{key}",
                f"needs bytes {offset:,} to {offset + n * size:,} of bufferView {v}, "
                f"which has {views[v]['byteLength']:,}",
            )


def _meshes(c: Checker) -> None:
    accessors = c.array("accessors")
    quantized = "KHR_mesh_quantization" in c.doc.get("extensionsUsed", [])
    for i, mesh in enumerate(c.array("meshes")):
        where = f"meshes[{i}]"
        c.text(mesh, "name", where)
        prims = mesh.get("primitives")
        if not isinstance(prims, list) or not prims:
            c.fail(f"{where}.primitives", "must be a non-empty array")
        for j, prim in enumerate(prims):
            pw = f"{where}.primitives[{j}]"
            if not isinstance(prim, dict):
                c.fail(pw, f"must be an object, not {_kind(prim)}")
            mode = c.integer(prim, "mode", pw, default=4)
            if mode > 6:
                c.fail(f"{pw}.mode", f"is {mode}; glTF modes are 0 to 6")
            c.index(prim, "material", pw, "materials")
            attrs = c.obj(prim, "attributes", pw)
            for name in list(attrs):
                c.index(attrs, name, f"{pw}.attributes", "accessors")
            if mode < 4:
                continue  # points and lines: left out, only their indices matter
            pos = c.index(attrs, "POSITION", f"{pw}.attributes", "accessors", required=True)
            _accessor_is(
                c,
                accessors,
                pos,
                f"{pw}.attributes.POSITION",
                ("VEC3",),
                (FLOAT, 5120, 5121, 5122, 5123) if quantized else (FLOAT,),
            )
            n = accessors[pos]["count"]
            for name, kinds, types in (
                ("NORMAL", ("VEC3",), (FLOAT, 5120, 5122) if quantized else (FLOAT,)),
                ("TEXCOORD_0", ("VEC2",), (FLOAT, 5121, 5123, 5120, 5122)),
                ("COLOR_0", ("VEC3", "VEC4"), (FLOAT, 5121, 5123)),
            ):
                if name in attrs:
                    _accessor_is(c, accessors, attrs[name], f"{pw}.attributes.{name}", kinds, types)
                    if accessors[attrs[name]]["count"] != n:
                        c.fail(
                            f"{pw}.attributes.{name}",
                            f"has {accessors[attrs[name]]['count']:,} values for {n:,} positions",
                        )
            idx = c.index(prim, "indices", pw, "accessors")
            if idx is not None:
                _accessor_is(c, accessors, idx, f"{pw}.indices", ("SCALAR",), INDEX_TYPES)
            count = n if idx is None else accessors[idx]["count"]
            if mode == 4 and count % 3:
                c.fail(
                    pw,
                    f"is a triangle list of {count:,} {'indices' if idx is not None else 'vertices'}, "
                    "not a multiple of 3",
                )


def _accessor_is(c: Checker, accessors: list, i: int, where: str, kinds: tuple, types: tuple) -> None:
    acc = accessors[i]
    if acc["type"] not in kinds or acc["componentType"] not in types:
        c.fail(
            where,
            f"is accessor {i} of {acc['type']} / componentType {acc['componentType']}; "
            f"expected {' or '.join(kinds)} of {' or '.join(map(str, types))}",
        )


def _nodes(c: Checker) -> None:
    for i, node in enumerate(c.array("nodes")):
        where = f"nodes[{i}]"
        c.text(node, "name", where)
        c.index(node, "mesh", where, "meshes")
        c.index(node, "camera", where, "cameras")
        c.index_list(node, "children", where, "nodes")
        if "matrix" in node and any(k in node for k in ("translation", "rotation", "scale")):
            c.fail(where, "has both 'matrix' and translation/rotation/scale")
        c.numbers(node, "matrix", where, 16)
        c.numbers(node, "translation", where, 3)
        c.numbers(node, "rotation", where, 4)
        c.numbers(node, "scale", where, 3)
    for i, scene in enumerate(c.array("scenes")):
        c.text(scene, "name", f"scenes[{i}]")
        c.index_list(scene, "nodes", f"scenes[{i}]", "nodes")


def _materials(c: Checker) -> None:
    for i, mat in enumerate(c.array("materials")):
        where = f"materials[{i}]"
        c.text(mat, "name", where)
        pbr = c.obj(mat, "pbrMetallicRoughness", where)
        c.numbers(pbr, "baseColorFactor", f"{where}.pbrMetallicRoughness", 4, finite=False)
        tex = c.obj(pbr, "baseColorTexture", f"{where}.pbrMetallicRoughness")
        if "baseColorTexture" in pbr:
            c.index(tex, "index", f"{where}.pbrMetallicRoughness.baseColorTexture", "textures", required=True)
    for i, tex in enumerate(c.array("textures")):
        c.index(tex, "source", f"textures[{i}]", "images")
    for i, image in enumerate(c.array("images")):
        where = f"images[{i}]"
        c.text(image, "uri", where, uri=True)
        c.text(image, "mimeType", where)
        c.index(image, "bufferView", where, "bufferViews")
