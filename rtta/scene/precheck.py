"""Checks made on a scene file before trimesh reads it: what it refers to (glTF buffers and
images stay inside the file's folder; no URLs) and how much memory its declared sizes need
(binary STL, PLY and glTF headers), so a bad or huge file fails fast with a clear message.

`precheck(path)` raises RttaError for what cannot be loaded and returns warnings for what
can (a missing or unreadable texture: the object keeps its material colour).
"""

from __future__ import annotations

import json
import os
import re
import struct
from pathlib import Path
from urllib.parse import unquote

from ..errors import RttaError

BYTES_PER_VERTEX = 112     # trimesh float64 positions/normals + our float32 copies + GPU buffer
BYTES_PER_TRIANGLE = 80    # trimesh int64 faces + face normals + our uint32 indices + GPU buffer
DEFAULT_LIMIT_MB = 4096


def memory_limit() -> int:
    """Bytes a scene may need: RTTA_MEMORY_LIMIT_MB (default 4096 MiB)."""
    raw = os.environ.get("RTTA_MEMORY_LIMIT_MB", "")
    try:
        mb = float(raw) if raw else DEFAULT_LIMIT_MB
    except ValueError:
        raise RttaError(f"RTTA_MEMORY_LIMIT_MB must be a number of MiB, got '{raw}'") from None
    return int(mb * 2**20)


def check_size(vertices: int, triangles: int, path: Path, what: str = "") -> None:
    """RttaError when a mesh of this size would need more than the memory limit."""
    need = vertices * BYTES_PER_VERTEX + triangles * BYTES_PER_TRIANGLE
    limit = memory_limit()
    if need > limit:
        raise RttaError(f"{what or 'the scene has'} {vertices:,} vertices and {triangles:,} triangles, about "
                        f"{need / 2**20:,.0f} MiB, over the memory limit of {limit / 2**20:,.0f} MiB "
                        "(RTTA_MEMORY_LIMIT_MB)", path)


def precheck(path: Path) -> list[str]:
    suffix = path.suffix.lower()
    if suffix in (".gltf", ".glb"):
        doc = _gltf_json(path) if suffix == ".gltf" else _glb_json(path)
        return _gltf_references(doc, path)
    if suffix == ".stl":
        _stl(path)
    elif suffix == ".ply":
        _ply(path)
    return []


def _decode(raw: bytes, path: Path, what: str) -> dict:
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise RttaError(f"{what} is not valid UTF-8 (byte {exc.start})", path) from None
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise RttaError(f"{what} is not valid JSON ({exc.msg} at line {exc.lineno}, column {exc.colno})",
                        path) from None
    if not isinstance(doc, dict):
        raise RttaError(f"{what} is not a JSON object", path)
    return doc


def _gltf_json(path: Path) -> dict:
    return _decode(path.read_bytes(), path, "glTF JSON")


def _glb_json(path: Path) -> dict:
    with open(path, "rb") as f:
        head = f.read(20)
        if head[:4] != b"glTF":
            raise RttaError("not a GLB file (no 'glTF' header)", path)
        if len(head) < 20:
            raise RttaError(f"GLB file is truncated ({len(head)} bytes; the header alone is 20)", path)
        _, version, total, length, kind = struct.unpack("<4sIIII", head)
        size = path.stat().st_size
        if version != 2:
            raise RttaError(f"GLB version {version} is not supported (only 2)", path)
        if total > size or 20 + length > size:
            raise RttaError(f"GLB file is truncated (header says {total:,} bytes, file has {size:,})", path)
        if kind != 0x4E4F534A:
            raise RttaError("GLB file's first chunk is not JSON", path)
        return _decode(f.read(length), path, "GLB JSON chunk")


def _local_file(uri: str, path: Path, what: str) -> Path | None:
    """The file a glTF URI names, inside the scene's folder; None for data: URIs."""
    if uri.startswith("data:"):
        return None
    if re.match(r"^[a-zA-Z][a-zA-Z0-9+.-]*:", uri):
        raise RttaError(f"{what} '{uri}' is a URL; only files next to the scene are read", path)
    name = unquote(uri)
    folder = path.resolve().parent
    target = (folder / name).resolve()
    if Path(name).is_absolute() or folder not in target.parents:
        raise RttaError(f"{what} '{uri}' is outside the scene's folder", path)
    return target


def _gltf_references(doc: dict, path: Path) -> list[str]:
    """Errors for buffers that are URLs, outside the folder or missing; warnings for images
    that are missing or unreadable. Also the memory estimate from the accessor counts."""
    warnings = []
    for buf in doc.get("buffers", []) or []:
        uri = buf.get("uri") if isinstance(buf, dict) else None
        if not isinstance(uri, str):
            continue
        target = _local_file(uri, path, "buffer")
        if target is not None and not target.is_file():
            raise RttaError(f"buffer file '{uri}' is missing", path)
    for image in doc.get("images", []) or []:
        uri = image.get("uri") if isinstance(image, dict) else None
        if not isinstance(uri, str):
            continue
        target = _local_file(uri, path, "image")
        if target is not None:
            problem = _image_problem(target)
            if problem:
                warnings.append(f"texture '{uri}' {problem}; objects using it keep their material colour")
    _gltf_size(doc, path)
    return warnings


def _image_problem(target: Path) -> str | None:
    if not target.is_file():
        return "is missing"
    from PIL import Image

    try:
        with Image.open(target) as im:
            im.verify()
    except Exception:
        return "cannot be read as an image"
    return None


def _gltf_size(doc: dict, path: Path) -> None:
    accessors = doc.get("accessors", []) or []

    def count(i) -> int:
        try:
            return int(accessors[i].get("count", 0))
        except (IndexError, TypeError, AttributeError, ValueError):
            return 0
    uses: dict[int, int] = {}
    for node in doc.get("nodes", []) or []:
        if isinstance(node, dict) and isinstance(node.get("mesh"), int):
            uses[node["mesh"]] = uses.get(node["mesh"], 0) + 1
    vertices = triangles = 0
    for mi, mesh in enumerate(doc.get("meshes", []) or []):
        for prim in (mesh.get("primitives", []) if isinstance(mesh, dict) else []) or []:
            if not isinstance(prim, dict):
                continue
            v = count((prim.get("attributes") or {}).get("POSITION", -1))
            idx = prim.get("indices")
            vertices += v * uses.get(mi, 1)
            triangles += (count(idx) if isinstance(idx, int) else v) // 3 * uses.get(mi, 1)
    check_size(vertices, triangles, path, "the file declares")


def _stl(path: Path) -> None:
    size = path.stat().st_size
    with open(path, "rb") as f:
        head = f.read(84)
    if head[:5].lower() == b"solid" and b"\0" not in head:
        return        # ASCII STL: trimesh parses it; its size is checked after loading
    if len(head) < 84:
        raise RttaError(f"not an STL file (no 'solid' line, and {size} bytes is shorter than a "
                        "binary STL header)", path)
    count = struct.unpack_from("<I", head, 80)[0]
    check_size(3 * count, count, path, "the binary STL declares")
    if 84 + 50 * count != size:
        raise RttaError(f"binary STL declares {count:,} triangles ({84 + 50 * count:,} bytes) "
                        f"but the file has {size:,} bytes", path)


def _ply(path: Path) -> None:
    with open(path, "rb") as f:
        head = f.read(65536)
    end = head.find(b"end_header")
    if not head.startswith(b"ply") or end < 0:
        raise RttaError("not a PLY file (no 'ply' ... 'end_header' header)", path)
    counts = dict(re.findall(rb"element\s+(\w+)\s+(\d+)", head[:end]))
    check_size(int(counts.get(b"vertex", 0)), int(counts.get(b"face", 0)), path, "the PLY header declares")
